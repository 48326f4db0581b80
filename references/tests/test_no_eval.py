"""Scene text is parsed by the grammar of compare/sdshared/sdexpr.py, never evaluated as code.

Hostile expressions (attribute access, dunder names, calls outside the grammar, string literals,
Python-only syntax, FreeFEM statements) fed to every Python entry point that takes an expression
string: sdexpr.parse / to_numpy / to_freefem / to_ufl / evaluate / derivative, the wrappers of the two
reference solvers, and compare/sdcompare_lib/exact.py (ExactSolution, ExactSolution.from_scene,
SharedEvaluator). Each must raise the module's error (sdexpr.ExprError, or the solver's SceneError)
with a one-line message, and leave no side effect (a file the expression would create). Then each
reference solver runs end to end once on a scene with a hostile expression: exit status 2, one line
on stderr, no result folder, nothing run.
"""

import builtins
import json
from contextlib import contextmanager
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

np = pytest.importorskip("numpy")

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
from sdcompare_lib import exact as sdexact
from sdshared import sdexpr
from output_checks import load_module
from conftest import run_env
from fake_export import write_fake_export

PWNED = "PWNED"  # replaced by a path under the test's tmp_path

# The list is shared with the Rust test tests/no_eval.rs.
HOSTILE = json.loads((HERE / "hostile_expressions.json").read_text())["hostile"]


def hostile(src, tmp_path):
    return src.replace(PWNED, str(tmp_path / "pwned"))



ffsolve = load_module("freefem_solve_no_eval", HERE.parent / "freefem" / "solve.py")
dxsolve = load_module("dolfinx_solve_no_eval", HERE.parent / "dolfinx" / "solve.py")


def ufl_coordinate():
    """x of an abstract UFL triangle mesh (no dolfinx needed); None without UFL."""
    try:
        import ufl
    except ImportError:
        return None
    return ufl.SpatialCoordinate(ufl.Mesh(ufl.VectorElement("Lagrange", ufl.triangle, 1)))


UFL_X = ufl_coordinate()


def entry_points():
    """(name, callable of one expression string, accepted error types)."""
    expr_error = (sdexpr.ExprError,)
    compare_error = (sdexpr.ExprError, sdexact.ExactError)
    scene_error = (ffsolve.SceneError, dxsolve.SceneError)
    return [
        ("sdexpr.parse", sdexpr.parse, expr_error),
        ("sdexpr.to_numpy", lambda s: sdexpr.to_numpy(s)(0.25, -0.5), expr_error),
        ("sdexpr.to_freefem", sdexpr.to_freefem, expr_error),
        ("sdexpr.to_ufl", lambda s: sdexpr.to_ufl(s, UFL_X), expr_error),
        ("sdexpr.evaluate", lambda s: sdexpr.evaluate(s, 0.25, -0.5), expr_error),
        ("sdexpr.derivative x", lambda s: sdexpr.derivative(s, "x"), expr_error),
        ("sdexpr.derivative y", lambda s: sdexpr.derivative(s, "y"), expr_error),
        ("freefem solve.parse", lambda s: ffsolve.parse("f", s), scene_error),
        ("freefem solve.to_freefem", lambda s: ffsolve.to_freefem("g", s), scene_error),
        ("freefem solve.to_numpy", lambda s: ffsolve.to_numpy("exact.u", s), scene_error),
        ("dolfinx solve.parse_expr", lambda s: dxsolve.parse_expr({}, "f", s), scene_error),
        ("exact.ExactSolution u", lambda s: sdexact.ExactSolution(s).u(0.25, -0.5), compare_error),
        ("exact.ExactSolution px", lambda s: sdexact.ExactSolution("x", px=s, py="0"), compare_error),
        ("exact.ExactSolution py", lambda s: sdexact.ExactSolution("x", px="1", py=s), compare_error),
        ("exact.ExactSolution jump", lambda s: sdexact.ExactSolution("x", jump=s), compare_error),
        ("exact.ExactSolution f", lambda s: sdexact.ExactSolution("x", f=s).f(0.25, -0.5), compare_error),
        ("exact.ExactSolution.from_scene", lambda s: sdexact.ExactSolution.from_scene(
            {"exact": {"u": s}, "data": {"f": "0"}}), compare_error),
        ("exact.ExactSolution.from_scene f", lambda s: sdexact.ExactSolution.from_scene(
            {"exact": {"u": "x"}, "data": {"f": s}}), compare_error),
        ("exact.SharedEvaluator", lambda s: sdexact.SharedEvaluator(["x", s])(0.25, -0.5), compare_error),
    ]


ENTRY_NAMES = [name for name, _, _ in entry_points()]


@contextmanager
def no_code_evaluation(attempts):
    """Within the block builtins.eval, exec and compile record their first argument in `attempts`
    and raise instead of running (restored on exit, before any assertion: pytest compiles too)."""
    names = ("eval", "exec", "compile")
    saved = {name: getattr(builtins, name) for name in names}

    def forbidden(*args, **kwargs):
        attempts.append(args[:1])
        raise RuntimeError("code evaluation attempted")

    try:
        for name in names:
            setattr(builtins, name, forbidden)
        yield
    finally:
        for name, fn in saved.items():
            setattr(builtins, name, fn)


def call(fn, src):
    """fn(src) with eval/exec/compile unavailable: (the exception raised or None, attempts)."""
    attempts = []
    with no_code_evaluation(attempts):
        try:
            fn(src)
        except Exception as e:  # noqa: BLE001 — judged by the caller
            return e, attempts
    return None, attempts


@pytest.mark.parametrize("entry", ENTRY_NAMES)
def test_hostile_expressions_are_rejected(entry, tmp_path):
    if entry == "sdexpr.to_ufl" and UFL_X is None:
        pytest.skip("needs ufl")
    _, fn, errors = next(e for e in entry_points() if e[0] == entry)
    for template in HOSTILE:
        src = hostile(template, tmp_path)
        error, attempts = call(fn, src)
        assert attempts == [], (entry, src, attempts)
        assert isinstance(error, errors), (entry, src, repr(error))
        message = str(error)
        assert message and "\n" not in message and len(message.splitlines()) == 1, (entry, src, message)
        if isinstance(error, sdexpr.ExprError):
            assert error.column >= 1 and error.message in message
    assert not (tmp_path / "pwned").exists()
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("entry", ENTRY_NAMES)
def test_grammar_expressions_need_no_code_evaluation(entry):
    """The positive control: expressions of the grammar go through every entry point with eval,
    exec and compile unavailable."""
    if entry == "sdexpr.to_ufl" and UFL_X is None:
        pytest.skip("needs ufl")
    _, fn, _ = next(e for e in entry_points() if e[0] == entry)
    for src in ("sin(pi*x)*cos(pi*y) - y", "atan2(y, x-0.5) + max(x, -y)^2 / sqrt(abs(x) + 1)",
                "-x^2 + sign(y)*exp(log(2))"):
        error, attempts = call(fn, src)
        assert error is None and attempts == [], (entry, src, repr(error), attempts)


def test_no_eval_in_references_or_compare():
    """No eval/exec/compile call in the Python of references/ and compare/ (this file and the test
    loaders aside), so nothing could evaluate scene text as code."""
    import re

    pattern = re.compile(r"(?<![\w.])(eval|exec|compile|__import__)\s*\(")
    hits = []
    files = [p for d in ("references", "compare") for p in (ROOT / d).rglob("*.py")]
    files.append(ROOT / "compare" / "sdcompare")
    for path in files:
        if path.resolve() == Path(__file__).resolve():
            continue
        for n, line in enumerate(path.read_text().splitlines(), 1):
            code = line.split("#", 1)[0]
            if pattern.search(code) and not re.search(r"['\"].*(eval|exec|compile|__import__)\s*\(.*['\"]", code):
                hits.append(f"{path.relative_to(ROOT)}:{n}: {line.strip()}")
    assert hits == []


HOSTILE_F = "__import__('os').system('touch PWNED')"
HOSTILE_G = "exec(\"touch PWNED\")"


def dolfinx_supported():
    try:
        import dolfinx
    except Exception:  # noqa: BLE001
        return False
    return dxsolve.dolfinx_version_problem() is None and bool(dolfinx.__version__)


def test_dolfinx_solver_rejects_hostile_scene(tmp_path):
    if not dolfinx_supported():
        pytest.skip("needs dolfinx 0.5.x")
    export = write_fake_export(tmp_path / "e", "hostile", hostile(HOSTILE_F, tmp_path), "0", levels=(0,))
    r = subprocess.run([sys.executable, str(HERE.parent / "dolfinx" / "solve.py"), str(export),
                        "--out", str(tmp_path / "o")], capture_output=True, text=True, env=run_env())
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert len(r.stderr.splitlines()) == 1 and "scene expression f" in r.stderr, r.stderr
    assert not (tmp_path / "o").exists() and not (tmp_path / "pwned").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["e"]


def test_freefem_solver_rejects_hostile_scene(tmp_path):
    """The scene is rejected before FreeFEM runs: the 'FreeFem++' given is a script that would leave
    a marker file (so this test needs no FreeFEM)."""
    fake = tmp_path / "fake-freefem"
    fake.write_text(f"#!/bin/sh\ntouch {tmp_path / 'freefem-ran'}\n")
    fake.chmod(0o755)
    export = write_fake_export(tmp_path / "e", "hostile", "0", hostile(HOSTILE_G, tmp_path), levels=(0,))
    env = run_env()
    r = subprocess.run([sys.executable, str(HERE.parent / "freefem" / "solve.py"), str(export),
                        "--out", str(tmp_path / "o"), "--freefem", str(fake)], capture_output=True, text=True, env=env)
    assert r.returncode == 2, (r.returncode, r.stderr)
    assert len(r.stderr.splitlines()) == 1 and "scene expression g" in r.stderr, r.stderr
    assert not (tmp_path / "freefem-ran").exists() and not (tmp_path / "pwned").exists()
    assert not (tmp_path / "o").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["e", "fake-freefem"]
    if shutil.which("FreeFem++"):  # and with the real FreeFem++, the same
        r = subprocess.run([sys.executable, str(HERE.parent / "freefem" / "solve.py"), str(export),
                            "--out", str(tmp_path / "o")], capture_output=True, text=True, env=env)
        assert r.returncode == 2 and len(r.stderr.splitlines()) == 1, r.stderr
        assert not (tmp_path / "o").exists() and not (tmp_path / "pwned").exists()
