"""A no-op `cargo build --release` does not rebuild the crate.

build.rs once watched .git/packed-refs, which a checkout may lack; cargo reruns a build script whose
watched path is missing, so every build recompiled sdcrack (~40 s) and a no-op tools/campaign took
33-54 s instead of 2 s. Runs where this file is in a git checkout with a release build (ci/test);
skipped elsewhere (ci/test-pip's copy has no .git, and a first build would take minutes)."""
import glob
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
    # the workspace's three crates, each found fresh
    for crate in ("sdcrack-core", "sdcrack-io", "sdcrack"):
        assert f"Fresh {crate} v" in second.stderr, second.stderr[-2000:]


def _build_script():
    """The newest compiled build script of the crate (target/release/build/sdcrack-*/; of the
    workspace's crates only the root package sdcrack has one)."""
    found = [os.path.join(d, "build-script-build")
             for d in glob.glob(os.path.join(ROOT, "target", "release", "build", "sdcrack-*"))
             if os.path.isfile(os.path.join(d, "build-script-build"))]
    return max(found, key=os.path.getmtime) if found else None


@pytest.mark.skipif(not (os.path.isdir(os.path.join(ROOT, ".git")) and _build_script()
                         and shutil.which("git")),
                    reason="needs the git checkout with its release build and git")
def test_the_build_script_leaves_a_fresh_clones_index_alone(tmp_path):
    """The build script's `git status` rewrote .git/index of a fresh clone (whose files'
    stat data is racy), a path it watches, so the clone's second build recompiled the crate (74 s).
    Run in a fresh clone, the build script reports the clone clean and leaves its index as it
    was."""
    clone = tmp_path / "clone"
    subprocess.run(["git", "clone", "-q", ROOT, str(clone)], check=True, timeout=300)
    index = clone / ".git" / "index"
    before = index.stat().st_mtime_ns
    out = subprocess.run([_build_script()], cwd=clone, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert "cargo:rustc-env=SDCRACK_GIT_DIRTY=false" in out.stdout, out.stdout
    assert index.stat().st_mtime_ns == before, "the build script rewrote the clone's .git/index"
