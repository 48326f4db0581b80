"""`pip install .` uses what is installed and leaves the checkout clean.

In a venv made with --system-site-packages from Debian's /usr/bin/python3, whose h5py pip does not
see (Debian names its distribution h5py._debian_h5py_serial), installing a copy of this checkout
installs sdcrack-tools alone: no second h5py from the index (the run is offline: --no-index, so
any missing requirement would fail it), and the copy holds the same files afterwards, apart from
target/ (where tools/pybuild/sdcrack_build.py builds)."""
import importlib.util
import os
import pathlib
import shutil
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
DEBIAN_PYTHON = "/usr/bin/python3"


def backend():
    spec = importlib.util.spec_from_file_location(
        "sdcrack_build_check", ROOT / "tools" / "pybuild" / "sdcrack_build.py")
    mod = importlib.util.module_from_spec(spec)
    # importing it writes target/pip-build/requirements.txt of this checkout: harmless (ignored)
    spec.loader.exec_module(mod)
    return mod


def test_h5py_is_required_only_when_none_is_importable():
    b = backend()
    assert "h5py>=3.7" not in b.dependencies(True) and "h5py>=3.7" in b.dependencies(False)
    assert b.dependencies(True) == b.DEPENDENCIES
    if os.access(DEBIAN_PYTHON, os.X_OK):
        debian = subprocess.run([DEBIAN_PYTHON, "-c", "import h5py"], capture_output=True)
        assert b.h5py_importable(DEBIAN_PYTHON) == (debian.returncode == 0)


def files(tree):
    return sorted(str(p.relative_to(tree)) for p in tree.rglob("*")
                  if p.is_file() and p.relative_to(tree).parts[0] != "target")


def test_pip_install_into_a_debian_venv_adds_no_h5py_and_leaves_the_tree_clean(tmp_path):
    if not os.access(DEBIAN_PYTHON, os.X_OK):
        pytest.skip("no Debian python")
    if not (ROOT / ".git").exists() or not (ROOT / "compare" / "sdcompare_lib").is_dir():
        pytest.skip("not a git checkout with the package sources (ci/test-pip's copy of the tree)")
    probe = subprocess.run([DEBIAN_PYTHON, "-c", "import h5py, numpy, matplotlib, meshio, "
                            "setuptools, pip"], capture_output=True)
    if probe.returncode != 0:
        pytest.skip("Debian's python3-h5py, -numpy, -matplotlib, -meshio, -setuptools, -pip needed")
    listed = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                            cwd=ROOT, capture_output=True, check=True).stdout.split(b"\0")
    tree = tmp_path / "tree"
    for f in (x.decode() for x in listed if x):
        src = ROOT / f
        if src.is_file():
            (tree / f).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, tree / f)
    before = files(tree)
    venv = tmp_path / "venv"
    subprocess.run([DEBIAN_PYTHON, "-m", "venv", "--system-site-packages", str(venv)], check=True)
    p = subprocess.run([str(venv / "bin" / "pip"), "install", "--disable-pip-version-check",
                        "--no-build-isolation", "--no-index", str(tree)],
                       capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    installed = os.listdir(next((venv / "lib").glob("python3*")) / "site-packages")
    assert not [d for d in installed if d.lower().startswith("h5py")], installed
    assert any(d.startswith("sdcrack_tools-") for d in installed), installed
    # the installed sdcompare imports Debian's h5py
    out = subprocess.run([str(venv / "bin" / "python"), "-c",
                          "import h5py, sdcompare_lib.read; print(h5py.__file__)"],
                         capture_output=True, text=True, cwd=tmp_path, check=True).stdout
    assert out.startswith("/usr/lib/python3/dist-packages/h5py"), out
    assert files(tree) == before, sorted(set(files(tree)) ^ set(before))
