"""The discrete certificate (compare/sdcompare_lib/certificate.py): its own assembly against closed
forms, the undamaged solver results PASS, and damaged fields FAIL with the reason naming the
equation.

The real results are one `sdcrack run --solver-only` of a small partly open crack (cells [4, 4],
levels 0 and 1, both u spaces, the three multipliers, both p masses and p spaces, δ ∈ {1e-2, 0}),
written once per module; the damages are applied to the arrays as read (no copy of the folder),
and the certificate is called in-process, so the file costs a few seconds.
"""
import math
import os
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "compare"))
from conftest import run_env, sdcrack_bin
from scene_text import square_scene
from sdcompare_lib import certificate as C
from sdcompare_lib import cases, read

EPS = np.finfo(float).eps
# A triangle in general position (no axis-aligned edge), counter-clockwise, and its mirror image.
TRI = np.array([[0.1, -0.2], [1.3, 0.4], [0.35, 1.1]])


def one_triangle(X=TRI, delta=0.0):
    area, grad = C.triangle_geometry(X[None])
    return area[0], grad[0], C.element_matrices(area, grad, delta, C.reference_integrals())[0]


# ------------------------------------------------------------------ the assembly, closed forms
def test_reference_integrals_are_the_closed_forms():
    ref = C.reference_integrals()
    assert np.allclose(ref["m"], (np.ones((3, 3)) + np.eye(3)) / 12, rtol=0, atol=4 * EPS)
    assert np.allclose(ref["one"], 1 / 3, rtol=0, atol=4 * EPS)
    assert np.allclose(ref["lb"], 3 / 20, rtol=0, atol=4 * EPS)  # ∫ λ_k b = 3|T|/20
    assert abs(ref["bb"] - 81 / 280) <= 4 * EPS  # ∫ b² = 81|T|/280
    assert abs(ref["b1"] - 9 / 20) <= 4 * EPS  # ∫ b = 9|T|/20


def test_conical_rule_is_exact_to_its_degree_and_not_beyond():
    """∫_T λ1^a λ2^b = 2|T| a! b!/(a + b + 2)!: exact for a + b ≤ 2n − 2, not at 2n."""
    n = 4
    L, W = C.conical_rule(n)
    exact = lambda a, b: 2 * math.factorial(a) * math.factorial(b) / math.factorial(a + b + 2)
    for a in range(2 * n - 1):
        for b in range(2 * n - 1 - a):
            assert abs(W @ (L[:, 1] ** a * L[:, 2] ** b) - exact(a, b)) <= 1e-15
    assert abs(W @ L[:, 1] ** (2 * n) - exact(2 * n, 0)) > 1e-10
    Ls, Ws = C.symmetric_rule()
    assert abs(Ws.sum() - 1) <= 1e-14 and abs(Ws @ (Ls[:, 1] ** 8 * Ls[:, 2] ** 8) - exact(8, 8)) <= 1e-15


def test_element_matrices_against_closed_forms():
    area, grad, E = one_triangle()
    assert abs(area - 0.5 * abs(np.cross(TRI[1] - TRI[0], TRI[2] - TRI[0]))) <= 4 * EPS
    # the p–p block: the vector P1 mass, summing to 2|T| (|T| per component)
    assert abs(E[:6, :6].sum() - 2 * area) <= 16 * EPS
    # u linear: (u, div(λ_k e)) = ∂_e λ_k |T| u(centroid), the bubble rows −∂_e u · 9|T|/20
    a, b, c = 0.7, -1.9, 0.3
    u = a * TRI[:, 0] + b * TRI[:, 1] + c
    assert np.allclose(E[:6, 8:] @ u, grad.ravel() * area * u.mean(), rtol=1e-14, atol=1e-15)
    assert np.allclose(E[6:8, 8:] @ u, -np.array([a, b]) * 9 * area / 20, rtol=1e-14, atol=1e-15)
    # p constant: (v, div p) = 0 for every v (the u rows), the bubble rows 3|T|/20 × 3 p
    p = np.tile([0.4, -1.1], 3)
    assert np.allclose(E[8:, :6] @ p, 0, atol=1e-14)
    assert np.allclose(E[6:8, :6] @ p, 9 / 20 * area * np.array([0.4, -1.1]), rtol=1e-14)
    # the symmetric form of (15): the u rows are the transpose of the (u, div q) columns
    assert np.allclose(E, np.transpose(E), atol=1e-15)


def test_condensation_gives_the_designs_blocks():
    """docs/design.md: condensed p–p block G̃_T = M_T − (7|T|/90) 1 1ᵀ per component (row sums
    |T|/10: the lumped diagonal), u–u block −(δM + 7/10 A), A the P1 stiffness."""
    delta = 0.37
    area, grad, E = one_triangle(delta=delta)
    keep = np.r_[0:6, 8:11]
    S = E[np.ix_(keep, keep)] - E[np.ix_(keep, [6, 7])] @ np.linalg.solve(E[6:8, 6:8], E[np.ix_([6, 7], keep)])
    M = area * (np.ones((3, 3)) + np.eye(3)) / 12
    assert np.allclose(S[:6, :6], np.kron(M - 7 * area / 90 * np.ones((3, 3)), np.eye(2)), atol=1e-15)
    A = area * grad @ grad.T
    assert np.allclose(S[6:, 6:], -(delta * M + 0.7 * A), rtol=1e-13, atol=1e-14)
    L = C.lumped_element_matrices(E[None])[0]
    assert np.allclose(np.diag(L[:6, :6]), area / 10, rtol=1e-14)
    assert np.count_nonzero(L[:6, :6] - np.diag(np.diag(L[:6, :6]))) == 0


def test_loads_boundary_and_crack_operators():
    area, grad = C.triangle_geometry(TRI[None])
    one = lambda x, y: np.ones_like(x)
    assert np.allclose(C.load_on_triangles(one, TRI[None], area, C.symmetric_rule()), area / 3,
                       rtol=1e-14)
    # the unit square's boundary term ∫_Γ g λ_v n ds with g = x, at the corner (1, 1)
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    tris = np.array([[0, 1, 2], [0, 2, 3]])
    edges = C.boundary_edges(tris, xy)
    ga, gb = C.boundary_term(lambda x, y: x, xy, edges, 5)
    G = C.scatter_edges(edges, ga, gb, 4)
    # at (1, 1): edge x = 1 (n = e_x): ∫ 1·λ ds = 1/2; edge y = 1 (n = e_y): ∫ x λ ds = 1/3
    assert np.allclose(G[2], [0.5, 1 / 3], rtol=1e-14)
    # the crack's P1 mass and M1star's kink row: a right-angle kink with legs 1 and 2
    Cp = np.array([[-1.0, 0.0], [0.0, 0.0], [0.0, 2.0]])
    segs = np.array([[0, 1], [1, 2]])
    geo = C.crack_geometry(Cp, segs)
    assert np.allclose(C.crack_mass_apply(geo["length"], segs, np.ones(3)), [0.5, 1.5, 1.0])
    # ν of (−1,0)→(0,0) is (0, 1), of (0,0)→(0,2) is (−1, 0): ν̄ = (1·(0,1) + 2·(−1,0))/3
    assert np.allclose(geo["row_normal"][1], [-2 / 3, 1 / 3], rtol=1e-15)
    assert not geo["straight"][1] and np.allclose(geo["row_normal"][[0, 2]], [[0, 1], [-1, 0]])


# ------------------------------------------------------------------ real results
SCENE = square_scene(
    "cert", "partly open crack for the certificate's tests",
    data={"f": '"20*sin(2*pi*x)*sign(y)"', "g": '"0.1*x"'},
    discretization={"levels": "[0, 1]", "u_spaces": '["continuous", "broken"]',
                    "multipliers": '["M0", "M1", "M1star"]', "p_mass": '["consistent", "lumped"]',
                    "p_spaces": '["continuous", "broken-tangential"]', "deltas": "[1e-2, 0.0]"})


@pytest.fixture(scope="module")
def results(tmp_path_factory):
    exe = sdcrack_bin()
    if not os.path.isfile(exe):
        pytest.skip(f"no sdcrack binary at {exe} (cargo build --release, or set SDCRACK_BIN)")
    d = tmp_path_factory.mktemp("cert")
    (d / "cert.toml").write_text(SCENE)
    subprocess.run([exe, "run", str(d / "cert.toml"), "--quiet", "--out", str(d / "out")],
                   check=True, env=run_env(), capture_output=True, timeout=300)
    res = read.load_results(str(d / "out" / "cert"))
    yield res
    read.close_results(res)


class Damaged:
    """res["data"] with `edit(case dict, fields dict)` applied to the arrays of the cases it
    selects (`which(case)`); every other case is read as stored."""

    def __init__(self, data, cases, which, edit):
        self.data, self.edit = data, edit
        self.grids = {c["fields_grid"]: c for c in cases if which(c)}

    def has_case(self, grid):
        return self.data.has_case(grid)

    def case(self, grid):
        f = self.data.case(grid)
        if grid in self.grids:
            f = {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in f.items()}
            self.edit(self.grids[grid], f)
        return f


def certify(res, which=None, edit=None):
    """The certificate of the results (only the cases `which` selects, damaged by `edit`)."""
    if edit is not None:
        cases = [c for c in res["summary"]["cases"] if which(c)]
        assert cases, "no case selected"
        res = dict(res, summary=dict(res["summary"], cases=cases),
                   data=Damaged(res["data"], cases, which, edit))
    return C.certify(res, res["scene_file"])


def is_case(level, u, m, delta=0.0, pm="consistent", ps="continuous"):
    return lambda c: (c["level"], c["u_space"], c["multiplier"], c["delta"], cases.p_mass(c),
                      cases.p_space(c)) == (level, u, m, delta, pm, ps)


def test_undamaged_results_pass_with_margin(results):
    cert = certify(results)
    assert cert["problems"] == [], cert["problems"]
    assert len(cert["rows"]) == len(results["summary"]["cases"]) and cert["skipped"] == 0
    worst = C.summary_numbers(cert)
    # far inside the tolerances (measured: ratios ≤ 0.25, the quadrature rows at exactly 1/4)
    assert max(worst[k] for k in C.RATIO_KEYS) <= 0.5, worst
    assert worst["bubble_backward_error"] <= 8 * EPS and worst["p_backward_error"] <= 8 * EPS
    # the crack opens somewhere (λ > 0): the crack terms are exercised
    assert any(r["multiplier"] == "M1" and r["complementarity_tolerance"] > 0 for r in cert["rows"])


def one_problem(cert, *needles):
    assert cert["problems"], "the damage passed the certificate"
    assert any(all(n in p for n in needles) for p in cert["problems"]), cert["problems"]


def test_u_perturbed_by_1e_6_at_one_dof_fails(results):
    def edit(c, f):
        f["u"][len(f["u"]) // 2] += 1e-6
    one_problem(certify(results, is_case(1, "broken", "M1"), edit), "level 1 broken M1 δ=0",
                "second equation of (15)")


def test_lambda_scaled_by_1_2_fails_for_each_multiplier(results):
    for m in ("M0", "M1", "M1star"):
        def edit(c, f):
            f["lam"] *= 1.2
        cert = certify(results, is_case(1, "broken", m), edit)
        assert np.abs(results["data"].case(next(
            c for c in results["summary"]["cases"] if is_case(1, "broken", m)(c))["fields_grid"])["lam"]).max() > 0
        one_problem(cert, f"broken {m} δ=0", "second equation of (15)", "∫_Γc λ q·ν")


def test_bubble_zeroed_or_scaled_by_27_fails(results):
    for factor in (0.0, 27.0):  # 27: the bubble read as the coefficient of λ0λ1λ2
        def edit(c, f):
            f["p_bubble"] *= factor
        one_problem(certify(results, is_case(0, "broken", "M1"), edit),
                    "tested with the bubbles b_T e")


def test_sign_violating_multiplier_fails(results):
    def edit(c, f):
        f["lam"][int(np.argmax(f["lam"]))] *= -1.0
    cert = certify(results, is_case(1, "broken", "M1"), edit)
    one_problem(cert, "the multiplier's sign of M1")


def test_p_violating_its_constraint_fails(results):
    """p·ν > 0 at a crack node (the faces interpenetrate): the constraint on p."""
    def edit(c, f):
        on_crack = np.flatnonzero(np.isclose(f["points"][:, 1], 0) & (np.abs(f["points"][:, 0]) < 0.5))
        f["p"][on_crack, 1] = np.abs(f["p"][:, :2]).max()
    one_problem(certify(results, is_case(1, "broken", "M1star"), edit), "the constraint on p of M1star")


def test_tangential_p_out_of_its_space_and_lumped_rows(results):
    def edit(c, f):  # p·ν differs between the two copies of a doubled vertex
        i = int(np.flatnonzero((f["points"][:, 1] == 0) & (f["points"][:, 0] == 0))[0])
        f["p"][i, 1] += 1e-3
    one_problem(certify(results, is_case(1, "broken", "M1", ps="broken-tangential"), edit),
                "p in X_h")

    def edit_u(c, f):  # the lumped p mass's u rows
        f["u"] *= 1.0 + 1e-6
    one_problem(certify(results, is_case(1, "broken", "M0", delta=1e-2, pm="lumped"), edit_u),
                "lumped", "equation of (15)")


def test_only_cases_up_to_the_unknowns_limit_are_certified(results, monkeypatch):
    monkeypatch.setattr(C, "UNKNOWNS_LIMIT", 150)
    cert = certify(results)
    assert cert["skipped"] > 0 and cert["rows"]
    assert all(r["unknowns"] <= 150 for r in cert["rows"])


def test_continuous_p_fields_do_not_solve_the_broken_tangential_system(results):
    """The tangential unknowns never doubled (a frame bug of the solver): the fields of the
    continuous p judged in the broken-tangential space fail its τ rows (second equation)."""
    c = next(c for c in results["summary"]["cases"] if is_case(1, "broken", "M1")(c))
    fields = results["data"].case(c["fields_grid"])
    sf = results["scene_file"]
    md = C.MeshData(fields["points"], fields["tris"], C._expression(sf, "f"),
                    C._expression(sf, "g"), C.reference_integrals())
    right = C.certify_case(md, fields, "M1", "consistent", "continuous", 0.0,
                           c["condition_estimate"])
    wrong = C.certify_case(md, fields, "M1", "consistent", "broken-tangential", 0.0,
                           c["condition_estimate"])
    assert right["problems"] == [] and right["p_ratio"] <= 1
    assert wrong["p_ratio"] > 1e6 and any("second equation of (15)" in p for p in wrong["problems"])


def test_sdcompare_fails_the_verdict_by_the_certificate(results, tmp_path):
    """End to end: one case's bubbles zeroed in fields.h5, compare/sdcompare exits 1 and names
    the check and the equation; report.json and report.md carry the residuals and the cost."""
    import json
    import shutil

    import h5py

    folder = tmp_path / "cert"
    shutil.copytree(results["folder"], folder)
    c = next(c for c in results["summary"]["cases"] if is_case(1, "broken", "M1")(c))
    with h5py.File(folder / "fields.h5", "r+") as h5:
        h5[f"cases/{c['fields_grid']}/p_bubble"][...] = 0.0
    p = subprocess.run([sys.executable, os.path.join(ROOT, "compare", "sdcompare"), str(folder),
                        "--quiet"], capture_output=True, text=True, env=run_env(), timeout=300)
    rep = json.loads((folder / "report" / "report.json").read_text(encoding="utf-8"))
    assert p.returncode == 1 and rep["verdict"] == "FAIL", p.stdout + p.stderr
    mine = [r for r in rep["reasons"] if r.startswith(f"{C.LABEL}: level 1 broken M1 δ=0: ")]
    # the bubble enters all three equations: one problem line each
    assert len(mine) == 3 and any("tested with the bubbles b_T e" in r for r in mine), mine
    row = next(x for x in rep["checks"] if x["check"] == C.LABEL)
    assert row["status"] != "ok" and len(row["problems"]) == 3
    cert = rep["discrete_certificate"]
    assert cert["certified"] == len(results["summary"]["cases"]) and cert["seconds"] > 0
    bad = [x for x in cert["cases"] if not x["ok"]]
    assert len(bad) == 1 and bad[0]["bubble_ratio"] > 1e6
    assert "## Discrete certificate" in (folder / "report" / "report.md").read_text(encoding="utf-8")
