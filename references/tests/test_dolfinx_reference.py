"""Tests of references/dolfinx/solve.py on fake mesh exports (tests/fake_export.py).

Run: /usr/bin/python3 -m pytest references/tests/test_dolfinx_reference.py
Skipped when dolfinx is not installed.
"""

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

dolfinx = pytest.importorskip("dolfinx")
pytest.importorskip("scipy")
np = pytest.importorskip("numpy")

from conftest import run_env
from fake_export import CLOSED_F, CLOSED_U, OPEN_JUMP, OPEN_U, write_fake_export
from output_checks import assert_fields_readable, assert_provenance, load_module

HERE = Path(__file__).resolve().parent
SOLVE = HERE.parent / "dolfinx" / "solve.py"
solve = load_module("dolfinx_solve", SOLVE)


def rates(cases, key):
    e = [c["errors"][key] for c in cases]
    h = [c["h"] for c in cases]
    return [math.log(e[i] / e[i + 1]) / math.log(h[i] / h[i + 1]) for i in range(len(e) - 1)]


def assert_kkt(case, tol=1e-10):
    k = case["kkt"]
    assert set(k) == {"equations", "primal", "dual", "complementarity"}, k
    assert k["equations"] < tol and k["primal"] < tol and k["dual"] < tol and k["complementarity"] < tol, k
    assert case["status"] == "converged", case["status"]


@pytest.fixture(scope="module")
def open_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("open")
    exp = write_fake_export(d / "export", "open", "0", OPEN_U, exact={"u": OPEN_U, "jump": OPEN_JUMP})
    return exp, solve.run(exp, d / "out", fields=True), d / "out"


@pytest.fixture(scope="module")
def closed_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("closed")
    exp = write_fake_export(d / "export", "closed", CLOSED_F, CLOSED_U, exact={"u": CLOSED_U})
    return exp, solve.run(exp, d / "out"), d / "out"


def test_open_crack_converges(open_run):
    _, s, out = open_run
    cases = s["cases"]
    assert s["tool"] == "dolfinx" and s["scene"] == "open" and [c["level"] for c in cases] == [0, 1, 2]
    prov = assert_provenance(json.loads((out / "summary.json").read_text()), "dolfinx")
    assert prov["tool_version"] == dolfinx.__version__ and solve.dolfinx_version_problem() is None
    for c in cases:
        assert c["active"] == 0  # the exact jump is positive everywhere: the crack is open
        assert_kkt(c)
        assert set(c["timings_s"]) == {"assembly", "solve", "forms", "total"}
        assert c["timings_s"]["forms"] >= 0 and c["timings_s"]["assembly"] >= 0
    # measured (n0 = 8, levels 0..2): u 0.98, 0.99; p 0.49, 0.50; jump 0.92, 0.91
    assert min(rates(cases, "u_l2")) >= 0.9
    assert min(rates(cases, "p_l2")) >= 0.45
    assert min(rates(cases, "lambda_l2")) >= 0.85


def test_closed_crack_converges(closed_run):
    exp, s, _ = closed_run
    cases = s["cases"]
    for c in cases:
        n_crack = len(np.loadtxt(exp / f"level{c['level']}" / "crack.txt"))
        assert c["active"] == n_crack - 2  # every interior crack node closed
        assert c["errors"]["lambda_l2"] < 1e-12
        assert_kkt(c)
    # measured: u 1.89, 1.97; p 0.96, 0.99
    assert min(rates(cases, "u_l2")) >= 1.8
    assert min(rates(cases, "p_l2")) >= 0.9


def test_jump_from_signed_zero_matches_given_jump(tmp_path, open_run):
    """Without exact.jump, [u] is taken from u at y = +0.0 / -0.0 (numpy back-end)."""
    _, s, _ = open_run
    exp = write_fake_export(tmp_path / "e", "open", "0", OPEN_U, exact={"u": OPEN_U}, levels=(0, 1))
    s2 = solve.run(exp, tmp_path / "o")
    for a, b in zip(s["cases"], s2["cases"]):
        assert b["errors"]["lambda_l2"] == pytest.approx(a["errors"]["lambda_l2"], rel=1e-9)


@pytest.mark.filterwarnings("ignore:Number of integration points")
def test_error_quadrature_is_converged(open_run, closed_run, tmp_path):
    """Raising the basix degree off the tips (20 -> 30) and the tip rules' points (16 -> 24 per
    direction) changes no error by more than 1e-9 relative (measured: <= 6e-13 on levels 0-3 of the
    repository scenes), so the reported errors are the integrals, not artefacts of the rules."""
    for name, (exp, s, _) in {"open": open_run, "closed": closed_run}.items():
        hi = solve.run(exp, tmp_path / name, quadrature={"degree": 30, "tip_points": 24})
        for a, b in zip(s["cases"], hi["cases"]):
            for key, v in a["errors"].items():
                w = b["errors"][key]
                assert abs(v - w) <= 1e-9 * max(abs(v), abs(w)), (name, a["level"], key, v, w)


def test_tip_rules_integrate_the_singularity():
    """The tip rules integrate what they are built for: the Duffy-σ² cell rule r^(-1) at the tip
    vertex, the facet rule s^(±1/2) at the tip end; positive weights, interior points."""
    for corners in ([1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0]):
        p, w = solve.tip_cell_rule(corners, 16, 20)
        assert (w > 0).all() and abs(w.sum() - 0.5) < 1e-14
        assert ((p > 0).all(axis=1) & (p.sum(axis=1) < 1)).all()  # interior points only
        if sum(corners) == 1:
            tip = solve.REFERENCE_TRIANGLE[corners.index(1)]
            r = np.hypot(*(p - tip).T)
            # ∫ r^(-1) over the reference triangle from vertex 0: ∫_0^{π/2} dθ / (cos θ + sin θ) = √2 asinh(1).
            # After the map the σ integrand is polynomial; the t integrand 1/|(1 − t, t)| is analytic
            # with poles at t = (1 ± i)/2, so 16 Gauss points leave ~1e-13 (1e-12 allowed).
            if corners[0]:
                exact = math.sqrt(2) * math.asinh(1)
                assert abs(np.sum(w / r) - exact) < 1e-12 * exact
    s, w = solve.tip_facet_rule(True, False, 16)
    assert abs(np.sum(w * np.sqrt(s)) - 2 / 3) < 1e-15 and abs(np.sum(w / np.sqrt(s)) - 2) < 1e-14


def test_status_reports_non_convergence(tmp_path, monkeypatch, capsys):
    """An active set stopped before its fixed point is reported in the case's status and by exit
    status 3, with the results still written."""
    exp = write_fake_export(tmp_path / "e", "mixed", "20*sin(2*pi*x)*sign(y)", "0", levels=(1,))
    monkeypatch.setattr(solve, "MAX_ITER", 1)
    assert solve.main([str(exp), "--out", str(tmp_path / "o")]) == 3
    (case,) = json.loads((tmp_path / "o" / "summary.json").read_text())["cases"]
    assert case["status"].startswith("not_converged: active set did not converge in 1 solves"), case
    assert "not_converged" in capsys.readouterr().err


def test_mixed_crack_kkt(tmp_path):
    """Partly open, partly closed: the active set has both kinds and the KKT system holds."""
    exp = write_fake_export(tmp_path / "e", "mixed", "20*sin(2*pi*x)*sign(y)", "0", levels=(0, 1, 2))
    s = solve.run(exp, tmp_path / "o")
    for c in s["cases"]:
        n_int = len(np.loadtxt(exp / f"level{c['level']}" / "crack.txt")) - 2
        assert 0 < c["active"] < n_int
        assert "errors" not in c
        assert_kkt(c, 1e-9)
        assert c["iterations"] >= 2


def test_vertex_renumbering_is_handled(tmp_path, closed_run):
    """Permute the export's vertex numbering: the solution must follow the permutation."""
    exp, _, out = closed_run
    new = tmp_path / "perm"
    new.mkdir()
    (new / "scene.json").write_text((exp / "scene.json").read_text())
    rng = np.random.default_rng(3)
    perms = {}
    for L in (0, 1, 2):
        src, dst = exp / f"level{L}", new / f"level{L}"
        dst.mkdir()
        xy = np.loadtxt(src / "vertices.txt")
        perm = rng.permutation(len(xy))  # new index of old vertex i is inv[i]
        inv = np.empty_like(perm)
        inv[perm] = np.arange(len(perm))
        np.savetxt(dst / "vertices.txt", xy[perm], fmt="%.17g")
        for name in ("triangles", "crack", "boundary"):
            a = np.loadtxt(src / f"{name}.txt", dtype=np.int64)
            np.savetxt(dst / f"{name}.txt", inv[a], fmt="%d")
        (dst / "sides.txt").write_text((src / "sides.txt").read_text())
        (dst / "mesh.json").write_text((src / "mesh.json").read_text())
        perms[L] = perm
    s = solve.run(new, tmp_path / "o")
    for L, perm in perms.items():
        u_old = np.loadtxt(out / f"u_level{L}.txt")
        u_new = np.loadtxt(tmp_path / "o" / f"u_level{L}.txt")
        np.testing.assert_allclose(u_new, u_old[perm], atol=1e-12)
    assert [c["active"] for c in s["cases"]] == [3, 7, 15]


def test_fields_readable_by_meshio(open_run):
    meshio = pytest.importorskip("meshio")
    exp, s, out = open_run
    assert (out / "fields.h5").exists() and not (out / "fields.xdmf").exists()
    assert_fields_readable(out, exp, s, "dolfinx")  # every *.xdmf under out, by meshio.read
    for c in s["cases"]:
        L = c["level"]
        m = meshio.read(out / "fields" / f"level{L}.xdmf")
        u = np.loadtxt(out / f"u_level{L}.txt")
        np.testing.assert_array_equal(m.point_data["u"], u)
        assert len(m.points) == c["unknowns"]
        # interpolated exact solution: + copies positive, - copies negative on the crack
        cr = meshio.read(out / "fields" / f"level{L}.crack.xdmf")
        jump = cr.point_data["jump"]
        assert jump[0] == 0 and jump[-1] == 0 and (jump[1:-1] > 0).all()
        ue = m.point_data["u_exact"]
        crack = np.loadtxt(out.parent / "export" / f"level{L}" / "crack.txt", dtype=np.int64)
        assert (ue[crack[1:-1, 0]] > 0).all() and (ue[crack[1:-1, 1]] < 0).all()


def test_cli_errors_and_atomicity(tmp_path, closed_run):
    exp, _, out = closed_run
    py = sys.executable
    r = subprocess.run([py, str(SOLVE), str(exp), "--out", str(out)], capture_output=True, text=True, env=run_env())
    assert r.returncode != 0
    assert r.stderr.strip().count("\n") == 0 and "exists" in r.stderr
    r = subprocess.run([py, str(SOLVE), str(tmp_path / "nope"), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, env=run_env())
    assert r.returncode != 0 and r.stderr.strip().count("\n") == 0 and not (tmp_path / "o").exists()
    bad = write_fake_export(tmp_path / "bad", "bad", "sin(x", "0", levels=(0,))
    r = subprocess.run([py, str(SOLVE), str(bad), "--out", str(tmp_path / "o")], capture_output=True, text=True, env=run_env())
    assert r.returncode != 0 and "column 4" in r.stderr and r.stderr.strip().count("\n") == 0
    r = subprocess.run([py, str(SOLVE), str(exp), "--out", str(tmp_path / "ok"), "--fields"],
                       capture_output=True, text=True, env=run_env())
    assert r.returncode == 0, r.stderr
    s = json.loads((tmp_path / "ok" / "summary.json").read_text())
    assert s["tool"] == "dolfinx"
    prov = assert_provenance(s, "dolfinx", script=SOLVE)
    assert prov["command_line"][1:] == [str(exp), "--out", str(tmp_path / "ok"), "--fields"]
    assert_fields_readable(tmp_path / "ok", exp, s, "dolfinx")
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []  # no temporaries left
