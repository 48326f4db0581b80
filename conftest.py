"""What the Python tests of every tree (tests/python, references/tests, compare/tests) share: the
sdcrack binary they run, the environment of the programs they start, the figures the report's plot
functions would save. The one conftest.py of the repository; where the tests import from is said
once, in pyproject.toml's [tool.pytest.ini_options].

Module-level uses (a skip condition, a path computed at import) import the plain functions:
`from conftest import sdcrack_bin, run_env`."""
import json
import os
import pathlib

import pytest

ROOT = os.path.dirname(os.path.abspath(__file__))
# The folder holding the package sdcompare_lib in a checkout (see its __init__.py).
PACKAGE_DIR = os.path.join(ROOT, "compare")


def sdcrack_bin():
    """$SDCRACK_BIN, else this checkout's release build (which may not exist: callers skip)."""
    return os.environ.get("SDCRACK_BIN") or os.path.join(ROOT, "target", "release", "sdcrack")


def run_env(*first):
    """The process environment of a program a test starts: FreeFEM's plugin path (Debian's) and
    matplotlib's headless backend unless already set, and on PYTHONPATH the folders `first` (e.g.
    a fake package's), then compare/, where the reference scripts find the package sdcompare_lib
    (as sdcrack launches them), then the caller's. Under ci/test-pip that folder has no
    sdcompare_lib and the installed one is found."""
    e = dict(os.environ)
    e.setdefault("FF_LOADPATH", "/usr/lib/freefem++")
    e.setdefault("MPLBACKEND", "Agg")
    inherited = [p for p in e.get("PYTHONPATH", "").split(os.pathsep) if p]
    e["PYTHONPATH"] = os.pathsep.join([str(p) for p in first] + [PACKAGE_DIR] + inherited)
    return e


def run_scene(tmp, name, text):
    """`sdcrack run` of the scene text `text` in tmp/name (scene.toml, out/), which must succeed:
    the results folder it wrote."""
    import subprocess

    where = tmp / name
    where.mkdir()
    scene = where / "scene.toml"
    scene.write_text(text)
    p = subprocess.run([sdcrack_bin(), "run", str(scene), "--out", str(where / "out"), "--quiet"],
                       capture_output=True, text=True, env=run_env(), timeout=600)
    assert p.returncode == 0, p.stderr[-2000:]
    (folder,) = [d for d in (where / "out").iterdir() if d.is_dir()]
    return str(folder)


@pytest.fixture
def sdcrack():
    """The sdcrack binary (sdcrack_bin), or the test skips when it is not built."""
    exe = sdcrack_bin()
    if not os.access(exe, os.X_OK):
        pytest.skip(f"no sdcrack binary at {exe} (cargo build --release, or set SDCRACK_BIN)")
    return exe


@pytest.fixture(scope="module")
def run_dir():
    """The results folder of a real `sdcrack run` that ci/test provides ($SDCRACK_RUN_DIR), or the
    test skips."""
    d = os.environ.get("SDCRACK_RUN_DIR")
    if not d:
        pytest.skip("SDCRACK_RUN_DIR is not set")
    return pathlib.Path(d)


@pytest.fixture(scope="module")
def summary(run_dir):
    """run_dir's summary.json, parsed."""
    return json.loads((run_dir / "summary.json").read_text())


@pytest.fixture
def figs(monkeypatch):
    """The figures the report's plot functions would save (sdcompare_lib.plots._save), kept open
    and laid out instead of written as PNG files; closed after the test."""
    from sdcompare_lib import plots

    captured = []

    def save(fig, folder, name):
        captured.append(fig)
        return name
    monkeypatch.setattr(plots, "_save", save)
    yield captured
    for fig in captured:
        plots.plt.close(fig)
