"""references/dolfinx/solve.py runs only under the dolfinx release series it is written for
(SUPPORTED_DOLFINX, 0.5.x): under any other it exits with status 2 and one line on stderr, before
it imports anything else from dolfinx. Needs no real dolfinx: a fake package comes first on
PYTHONPATH."""

import importlib.util
import os
import subprocess
import sys
import types
from pathlib import Path

import pytest

from conftest import run_env

HERE = Path(__file__).resolve().parent
SOLVE = HERE.parent / "dolfinx" / "solve.py"

_spec = importlib.util.spec_from_file_location("dolfinx_solve_version", SOLVE)
solve = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(solve)


def fake_dolfinx(root, version):
    """A package `dolfinx` with only __version__; importing any submodule of it (what the solver
    uses: fem, mesh, ...) leaves a marker file."""
    pkg = root / "dolfinx"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text(f"__version__ = {version!r}\n")
    marker = root / "submodule-imported"
    for sub in ("fem", "mesh", "cpp", "io", "la", "geometry", "plot", "common"):
        (pkg / sub).mkdir()
        (pkg / sub / "__init__.py").write_text(f"open({str(marker)!r}, 'w').close()\n")
    return marker


def test_supported_range_is_one_constant():
    assert solve.SUPPORTED_DOLFINX == "0.5"
    assert "0.5.x" in solve.__doc__ and "python3-dolfinx" in solve.__doc__


@pytest.mark.parametrize("version,ok", [("0.5.2", True), ("0.5.0", True), ("0.5", True), ("0.5.3.dev0", True),
                                        ("0.6.0", False), ("0.7.0", False), ("0.50.1", False), ("0.4.1", False),
                                        ("1.0.0", False)])
def test_version_rule(monkeypatch, version, ok):
    monkeypatch.setitem(sys.modules, "dolfinx", types.SimpleNamespace(__version__=version))
    problem = solve.dolfinx_version_problem()
    if ok:
        assert problem is None
    else:
        assert problem == (f"dolfinx reference: dolfinx {version} is not supported "
                           "(supported: 0.5.x, the Debian 12 package python3-dolfinx)")


@pytest.mark.parametrize("version", ["0.7.0", "0.6.0"])
def test_unsupported_dolfinx_exits_2_with_one_line(tmp_path, version):
    marker = fake_dolfinx(tmp_path / "site", version)
    env = run_env(tmp_path / "site")
    r = subprocess.run([sys.executable, str(SOLVE), str(tmp_path / "no-export"), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, env=env)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert r.stderr == (f"dolfinx reference: dolfinx {version} is not supported "
                        "(supported: 0.5.x, the Debian 12 package python3-dolfinx)\n")
    assert r.stdout == ""
    assert not marker.exists(), "the solver imported a dolfinx submodule before checking the version"
    assert not (tmp_path / "o").exists()


def test_missing_dolfinx_exits_2_with_one_line(tmp_path):
    """A `dolfinx` that cannot be imported (here: its __init__ raises) is reported the same way."""
    pkg = tmp_path / "site" / "dolfinx"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("raise ImportError('libdolfinx.so: cannot open shared object file\\nsecond line')\n")
    env = run_env(tmp_path / "site")
    r = subprocess.run([sys.executable, str(SOLVE), str(tmp_path / "no-export"), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, env=env)
    assert r.returncode == 2, r.stderr
    assert len(r.stderr.splitlines()) == 1 and r.stderr.startswith("dolfinx reference: dolfinx cannot be imported")
    assert "(supported: 0.5.x, the Debian 12 package python3-dolfinx)" in r.stderr
