"""A no-op `cargo build --release` does not rebuild the crate (issue 25, item 10).

build.rs once watched .git/packed-refs, which a checkout may lack; cargo reruns a build script whose
watched path is missing, so every build recompiled sdcrack (~40 s) and a no-op ci/campaign took
33-54 s instead of 2 s. Runs where this file is in a git checkout with a release build (ci/test);
skipped elsewhere (ci/test-pip's copy has no .git, and a first build would take minutes)."""
import os
import shutil
import subprocess

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
CARGO = shutil.which("cargo") or os.path.expanduser("~/.cargo/bin/cargo")


@pytest.mark.skipif(not (os.path.isdir(os.path.join(ROOT, ".git"))
                         and os.path.isdir(os.path.join(ROOT, "target", "release"))
                         and os.path.exists(CARGO)),
                    reason="needs the git checkout with its release build and cargo")
def test_a_second_build_finds_the_crate_fresh():
    build = [CARGO, "build", "--release", "-v"]
    first = subprocess.run(build, cwd=ROOT, capture_output=True, text=True, timeout=1800)
    assert first.returncode == 0, first.stderr[-2000:]
    second = subprocess.run(build, cwd=ROOT, capture_output=True, text=True, timeout=600)
    assert second.returncode == 0, second.stderr[-2000:]
    assert "Fresh sdcrack" in second.stderr, second.stderr[-2000:]
