"""Tests of compare/sdcompare_lib/exact.py, the independent error norms.

Run: /usr/bin/python3 -m pytest -q -p no:cacheprovider compare/tests/test_exact.py
The agreement test with the solver runs target/release/sdcrack (skipped when it is not built).
"""
import json
import math
import subprocess
import tomllib
from fractions import Fraction
from math import factorial
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
from sdcompare_lib import exact as E
from sdcompare_lib import norms
from sdshared import sdexpr

from scene_text import set_key

SCENES = ROOT / "scenes"
BINARY = ROOT / "target" / "release" / "sdcrack"


# ---------------------------------------------------------------------------------------------
# meshes like the solver's: SW–NE diagonals, cell (i, j) -> triangles 2(j nx + i), 2(j nx + i) + 1
# ---------------------------------------------------------------------------------------------

def structured(x0, x1, y0, y1, nx, ny):
    xs, ys = np.linspace(x0, x1, nx + 1), np.linspace(y0, y1, ny + 1)
    X, Y = np.meshgrid(xs, ys)
    P = np.column_stack([X.ravel(), Y.ravel()])
    j, i = np.meshgrid(np.arange(ny), np.arange(nx), indexing="ij")
    v00 = (j * (nx + 1) + i).ravel()
    v10, v11, v01 = v00 + 1, v00 + nx + 2, v00 + nx + 1
    tris = np.empty((2 * nx * ny, 3), dtype=np.int64)
    tris[0::2] = np.column_stack([v00, v10, v11])
    tris[1::2] = np.column_stack([v00, v11, v01])
    return P, tris


def cracked(P, tris, a=-0.5, b=0.5):
    """Duplicate the interior vertices of the crack [a, b] × {0}; triangles below use the copies.
    Returns (points, triangles, pairs (plus, minus) from tip a to tip b)."""
    on = np.flatnonzero((P[:, 1] == 0.0) & (P[:, 0] >= a) & (P[:, 0] <= b))
    on = on[np.argsort(P[on, 0])]
    inner = on[1:-1]
    new = np.arange(P.shape[0], P.shape[0] + inner.shape[0])
    P2 = np.vstack([P, P[inner]])
    t2 = tris.copy()
    below = P[tris].mean(axis=1)[:, 1] < 0
    remap = np.arange(P.shape[0])
    remap[inner] = new
    t2[below] = np.where(np.isin(t2[below], inner), remap[t2[below]], t2[below])
    pairs = np.column_stack([on, np.concatenate([[on[0]], new, [on[-1]]])])
    return P2, t2, pairs


def scene_mesh(level, broken, cells=8):
    P, t = structured(-1, 1, -1, 1, cells * 2 ** level, cells * 2 ** level)
    return cracked(P, t) if broken else (P, t, None)


def crack_points(level, cells=8):
    n = cells * 2 ** level // 2  # segments on (-1/2, 1/2): h = 2/(cells 2^level)
    x = np.linspace(-0.5, 0.5, n + 1)
    return np.column_stack([x, np.zeros_like(x)])


def open_exact(jump=True):
    s = E.load_scene(SCENES / "open-exact.toml")
    if not jump:
        del s["exact"]["jump"]
    return E.ExactSolution.from_scene(s)


# ---------------------------------------------------------------------------------------------
# rules
# ---------------------------------------------------------------------------------------------

PHYSICAL = [
    [(Fraction(1, 5), Fraction(-1, 10)), (Fraction(11, 10), Fraction(3, 10)), (Fraction(2, 5), Fraction(9, 10))],
    [(Fraction(-3, 4), Fraction(-1)), (Fraction(-1, 2), Fraction(-3, 4)), (Fraction(-3, 4), Fraction(-3, 4))],
    [(Fraction(3), Fraction(2)), (Fraction(1), Fraction(5)), (Fraction(9, 2), Fraction(6))],
    [(Fraction(0), Fraction(0)), (Fraction(1), Fraction(1, 1000)), (Fraction(1, 2), Fraction(1, 500))],
]


def monomial_integral(v, a, b):
    """∫_T x^a y^b exactly (fractions): x, y as linear forms in the barycentrics, expanded, with
    ∫_T λ0^i λ1^j λ2^k = 2|T| i! j! k! / (i + j + k + 2)!."""
    poly = {(0, 0, 0): Fraction(1)}
    for coord, power in ((0, a), (1, b)):
        for _ in range(power):
            out = {}
            for (i, j, k), c in poly.items():
                for m, e in enumerate(((1, 0, 0), (0, 1, 0), (0, 0, 1))):
                    key = (i + e[0], j + e[1], k + e[2])
                    out[key] = out.get(key, 0) + c * v[m][coord]
            poly = out
    area2 = abs((v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[1][1] - v[0][1]) * (v[2][0] - v[0][0]))
    return sum(c * area2 * factorial(i) * factorial(j) * factorial(k) / factorial(i + j + k + 2)
               for (i, j, k), c in poly.items())


def test_gauss_jacobi_moments():
    for n in range(1, 12):
        s, w = E.gauss_jacobi01(n, 1.0)
        assert np.all((s > 0) & (s < 1))
        for k in range(2 * n):
            assert abs(np.dot(w, s ** k) - 1.0 / ((k + 1) * (k + 2))) < 1e-15, (n, k)


@pytest.mark.parametrize("n", [1, 2, 3, 5, 8])
def test_stroud_rule_area_and_monomials_on_physical_triangles(n):
    L, W = E.stroud_rule(n)
    assert np.all(L > 0) and np.allclose(L.sum(axis=1), 1.0, atol=1e-15)
    deg = 2 * n - 1
    for v in PHYSICAL:
        vf = np.array([[float(c) for c in p] for p in v])
        area = float(monomial_integral(v, 0, 0))
        assert abs(E.integrate_on_triangle(lambda x, y: np.ones_like(x), vf, quad=E.Quadrature(n=n)) - area) \
            <= 1e-14 * area
        xy = L @ vf
        for a in range(deg + 1):
            for b in range(deg + 1 - a):
                exact = float(monomial_integral(v, a, b))
                mono = xy[:, 0] ** a * xy[:, 1] ** b
                q = area * np.dot(W, mono)
                scale = area * np.dot(W, np.abs(mono))
                assert abs(q - exact) <= 1e-13 * scale, (n, v, a, b, q, exact)
    # and it is not exact one degree higher (the test can fail)
    v = PHYSICAL[0]
    vf = np.array([[float(c) for c in p] for p in v])
    xy = L @ vf
    errs = [abs(float(monomial_integral(v, a, deg + 1 - a)) - float(monomial_integral(v, 0, 0))
                * np.dot(W, xy[:, 0] ** a * xy[:, 1] ** (deg + 1 - a))) for a in range(deg + 2)]
    assert max(errs) > 1e-12


@pytest.mark.parametrize("corner", [0, 1, 2])
def test_tip_rule_area_and_monomials(corner):
    m = 10
    L, W = E.tip_rule(m, corner)
    assert np.all(L > 0) and abs(W.sum() - 1) < 1e-15
    for v in PHYSICAL[:3]:
        vf = np.array([[float(c) for c in p] for p in v])
        area = float(monomial_integral(v, 0, 0))
        xy = L @ vf
        for a in range(m - 1):
            for b in range(m - 1 - a):
                exact = float(monomial_integral(v, a, b))
                mono = xy[:, 0] ** a * xy[:, 1] ** b
                assert abs(area * np.dot(W, mono) - exact) <= 1e-13 * area * np.dot(W, np.abs(mono)), (a, b)


# triangles with the tip at vertex `tip` (crack along +x from the tip on the first two)
TIP_TRIANGLES = [
    ([[0.5, 0.0], [0.625, 0.0], [0.625, 0.125]], 0),
    ([[0.5, 0.0], [0.5, 0.125], [0.375, 0.0]], 0),
    ([[0.3, 0.9], [0.2, -0.1], [1.1, 0.3]], 1),
    ([[1.0, 1e-3], [0.0, 0.0], [0.5, 2e-3]], 1),
    ([[-0.25, -0.75], [-0.5, -0.5], [-0.5, -0.75]], 2),
]


def _tip_geometry(v, tip):
    A = np.array(v[tip], dtype=float)
    B, C = np.array(v[(tip + 1) % 3], dtype=float), np.array(v[(tip + 2) % 3], dtype=float)
    e = (C - B) / np.linalg.norm(C - B)
    F = B + np.dot(A - B, e) * e  # foot of the perpendicular from A
    h = np.linalg.norm(A - F)
    nrm = (F - A) / h
    sB, sC = np.dot(B - F, e), np.dot(C - F, e)
    angle = abs(math.atan2(sC, h) - math.atan2(sB, h))
    return A, nrm, h, sB, sC, angle


@pytest.mark.parametrize("v,tip", TIP_TRIANGLES)
def test_tip_rule_singular_integrands_closed_forms(v, tip):
    A, nrm, h, sB, sC, angle = _tip_geometry(v, tip)

    def r(x, y):
        return np.hypot(x - A[0], y - A[1])

    def dn(x, y):  # (x − A)·n > 0 inside the triangle
        return (x - A[0]) * nrm[0] + (y - A[1]) * nrm[1]

    cases = [
        # ∫ 1/r = h |asinh(sC/h) − asinh(sB/h)|  (polar coordinates about the tip)
        (lambda x, y: 1.0 / r(x, y), h * abs(math.asinh(sC / h) - math.asinh(sB / h))),
        # r^(−1/2)-type: (ξ·n)^{3/2}/r² = r^{−1/2} cos^{3/2}: ∫ = (2/3) h^{3/2} · angle
        (lambda x, y: dn(x, y) ** 1.5 / r(x, y) ** 2, 2.0 / 3.0 * h ** 1.5 * angle),
        # r^(−1)-type with angular factor: (ξ·n)/r² = r^{−1} cos: ∫ = h · angle
        (lambda x, y: dn(x, y) / r(x, y) ** 2, h * angle),
        # r^(1/2)-type (the crack-tip displacement): (ξ·n)^{5/2}/r² = r^{1/2} cos^{5/2}: (2/5) h^{5/2} angle
        (lambda x, y: dn(x, y) ** 2.5 / r(x, y) ** 2, 0.4 * h ** 2.5 * angle),
        # |∇(r^{1/2} sin(θ/2))|² = 1/(4r)
        (lambda x, y: 0.25 / r(x, y), 0.25 * h * abs(math.asinh(sC / h) - math.asinh(sB / h))),
    ]
    for k, (fn, exact) in enumerate(cases):
        got = E.integrate_on_triangle(fn, v, tip=tip)
        assert abs(got - exact) <= 1e-10 * abs(exact), (k, got, exact)
        # the plain rule of the same size cannot do it: the test would catch a missing tip treatment
        if k in (0, 1):
            plain = E.integrate_on_triangle(fn, v)
            assert abs(plain - exact) > 1e-6 * abs(exact)


def test_near_tip_pieces_tile_and_are_admissible():
    P, t = structured(-1, 1, -1, 1, 16, 16)
    X = P[t]
    tips = [np.array([-0.5, 0.0]), np.array([0.5, 0.0])]
    cen = X.mean(axis=1)
    ids = np.flatnonzero(np.min([np.linalg.norm(cen - tp, axis=1) for tp in tips], axis=0) < 0.4)
    touching = [i for i in ids if any(np.min(np.linalg.norm(X[i] - tp, axis=1)) == 0 for tp in tips)]
    ids = np.setdiff1d(ids, touching)
    for eta in (1.0, 2.0):
        owner, V = E._near_tip_pieces(X, ids, tips, eta)
        ratio = np.abs(np.linalg.det(V))
        np.testing.assert_allclose(np.bincount(owner, ratio, minlength=t.shape[0])[ids], 1.0, atol=1e-14)
        phys = np.einsum("kvb,kbd->kvd", V, X[owner])
        diam = np.max([np.linalg.norm(phys[:, i] - phys[:, (i + 1) % 3], axis=1) for i in range(3)], axis=0)
        for tp in tips:
            assert np.all(E._distance_to_triangles(tp, phys) >= eta * diam)
        assert owner.shape[0] > ids.shape[0]  # something was split


def test_shared_evaluator_is_bitwise_to_numpy():
    srcs = [s for s in ("sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)",
                        "20*sin(2*pi*x)*sign(y)", "min(x, y)^2 - max(x, -y) + abs(x - 0.25)*sign(y)",
                        "x/y", "2^-y + log(x) + tan(x*y)")]
    trees = [sdexpr.parse(s) for s in srcs]
    trees += [sdexpr.derivative(trees[0], "x"), sdexpr.derivative(trees[0], "y"), sdexpr.derivative(trees[2], "x")]
    rng = np.random.default_rng(5)
    x = np.concatenate([rng.uniform(-1, 1, 3000), rng.uniform(-0.5, 0.5, 100), [0.0, -0.0, 0.3]])
    y = np.concatenate([rng.uniform(-1, 1, 3000), np.zeros(50), -np.zeros(50), [0.0, -0.0, -0.0]])
    got = E.SharedEvaluator(trees)(x, y)
    for tr, g in zip(trees, got):
        ref = sdexpr.to_numpy(tr)(x, y)
        assert np.array_equal(g, ref, equal_nan=True)
        assert np.array_equal(np.signbit(g), np.signbit(ref))


# ---------------------------------------------------------------------------------------------
# closed forms on the scenes' meshes
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("level,broken", [(0, False), (0, True), (2, True)])
def test_zero_field_closed_exact(level, broken):
    ex = E.ExactSolution.from_scene(SCENES / "closed-exact.toml")
    P, t, pairs = scene_mesh(level, broken)
    C = crack_points(level)
    I = C.shape[0] - 1
    r = E.solver_case_errors(P, t, np.zeros(len(P)), np.zeros((len(P), 3)), np.zeros((len(t), 2)), C,
                             np.zeros(I + 1), ex)
    h = 2.0 / (8 * 2 ** level)
    assert r["u_l2"] ** 2 == pytest.approx(7.0 / 3.0, rel=1e-13)
    assert r["p_l2"] ** 2 == pytest.approx(2 * math.pi ** 2 + 4, rel=1e-13)
    # every h_T = h √2 and ∫ f² = 4π⁴ ∫ sin²(πx) cos²(πy) = 4π⁴
    assert r["p_x"] ** 2 == pytest.approx(2 * math.pi ** 2 + 4 + 2 * h * h * 4 * math.pi ** 4, rel=1e-13)
    assert r["lambda_l2"] == 0.0 and r["bubble"] == "stored"
    if broken:
        q = E.p1_field_errors(P, t, np.zeros(len(P)), pairs, ex)
        assert q["u_l2"] ** 2 == pytest.approx(7.0 / 3.0, rel=1e-13)
        assert q["p_l2"] ** 2 == pytest.approx(2 * math.pi ** 2 + 4, rel=1e-13)
        assert q["lambda_l2"] == 0.0


def _boundary_energy_open_exact(n=60):
    """‖∇u‖²_{L²(Ω)} of open-exact = ∮_∂Ω u ∂u/∂n (Green: Δu = 0 and ∂u/∂y = 0 on both faces),
    with ∇u from u = Im w, w' = z/w (no sdexpr), Gauss on 8 half-sides (smooth there)."""
    g, w = E.gauss_legendre01(n)
    total = 0.0
    for (x0, y0), (x1, y1), nrm in [((-1, -1), (1, -1), (0, -1)), ((1, -1), (1, 1), (1, 0)),
                                    ((1, 1), (-1, 1), (0, 1)), ((-1, 1), (-1, -1), (-1, 0))]:
        for a, b in ((0.0, 0.5), (0.5, 1.0)):
            s = a + (b - a) * g
            z = (x0 + s * (x1 - x0)) + 1j * (y0 + s * (y1 - y0))
            wz = np.sqrt(z - 0.5) * np.sqrt(z + 0.5)
            dw = z / wz
            dn = dw.imag * nrm[0] + dw.real * nrm[1]
            total += 2.0 * (b - a) * np.dot(w, wz.imag * dn)
    return total


@pytest.mark.parametrize("level,broken", [(0, True), (1, False), (2, True)])
def test_zero_field_open_exact(level, broken):
    P, t, pairs = scene_mesh(level, broken)
    C = crack_points(level)
    energy = _boundary_energy_open_exact()
    for ex in (open_exact(jump=True), open_exact(jump=False)):
        r = E.solver_case_errors(P, t, np.zeros(len(P)), np.zeros((len(P), 2)), np.zeros((len(t), 2)), C,
                                 np.zeros(C.shape[0] - 1), ex)
        # ∫ (2 sqrt(1/4 − x²))² dx = 2/3, with the scene's jump and with u⁺ − u⁻ from the faces
        assert r["lambda_l2"] ** 2 == pytest.approx(2.0 / 3.0, rel=1e-13)
        assert r["p_l2"] ** 2 == pytest.approx(energy, rel=1e-11)
        assert r["p_x"] == r["p_l2"]  # f = 0 and div p_h = 0
        if broken:
            q = E.p1_field_errors(P, t, np.zeros(len(P)), pairs, ex)
            assert q["lambda_l2"] ** 2 == pytest.approx(2.0 / 3.0, rel=1e-13)
            assert q["p_l2"] ** 2 == pytest.approx(energy, rel=1e-11)
            assert q["u_l2"] == pytest.approx(r["u_l2"], rel=1e-14)


def test_linear_exact_solution_gives_zero_and_p1_differences_are_exact():
    """u = 1 + 2x − 3y is in every discrete space: interpolants have no error; a perturbed u_h has the
    exact P1 mass-matrix error of compare/sdcompare_lib/norms.py (tip and near-tip rules included)."""
    ex = E.ExactSolution("1 + 2*x - 3*y", jump="0", f="0", crack=[[-0.5, 0.0], [0.5, 0.0]])
    P, t, pairs = scene_mesh(1, True)
    C = crack_points(1)
    u = 1 + 2 * P[:, 0] - 3 * P[:, 1]
    p = np.tile([2.0, -3.0], (len(P), 1))
    bub = E.recover_bubble(P, t, u, p)
    assert np.abs(bub).max() < 1e-13
    r = E.solver_case_errors(P, t, u, p, bub, C, np.zeros(C.shape[0]), ex)
    assert max(r["u_l2"], r["p_l2"], r["p_x"], r["lambda_l2"]) < 1e-13
    rng = np.random.default_rng(11)
    du = rng.normal(size=len(P))
    q = E.p1_field_errors(P, t, u + du, pairs, ex)
    assert q["u_l2"] == pytest.approx(norms.p1_l2_norm(P, t, du), rel=1e-12)
    g = norms.p1_gradients(P, t, du)
    assert q["p_l2"] == pytest.approx(math.sqrt((norms.triangle_areas(P, t) * (g * g).sum(axis=1)).sum()), rel=1e-12)
    jump = du[pairs[:, 0]] - du[pairs[:, 1]]
    assert q["lambda_l2"] == pytest.approx(norms.crack_l2_norm(C, jump), rel=1e-12)


def test_bubble_is_included_exactly():
    """p_h = P1 part + c 27 λ0λ1λ2 against ∇u = 0, closed form:
    ‖p_h‖²_T = (P1 mass) + 2 c·Σ_k p_k 3|T|/20 + |c|² 81|T|/280."""
    ex = E.ExactSolution("0", f="0", jump="0", crack=[[-0.5, 0.0], [0.5, 0.0]])
    P, t, _ = scene_mesh(0, False)
    rng = np.random.default_rng(2)
    p = rng.normal(size=(len(P), 2))
    c = rng.normal(size=(len(t), 2))
    r = E.solver_case_errors(P, t, np.zeros(len(P)), p, c, crack_points(0), None, ex)
    area = norms.triangle_areas(P, t)
    pt = p[t]
    mass = (area[:, None] / 12 * ((pt ** 2).sum(axis=1) + pt.sum(axis=1) ** 2)).sum()
    cross = (2 * (c * pt.sum(axis=1)).sum(axis=1) * 3 * area / 20).sum()
    bb = ((c ** 2).sum(axis=1) * 81 * area / 280).sum()
    assert r["p_l2"] ** 2 == pytest.approx(mass + cross + bb, rel=1e-13)
    assert r["lambda_l2"] is None
    assert r["p_x"] > r["p_l2"]


def test_p_mass_decides_the_bubble():
    """The lumped p is P1 without bubble: its errors are those with bubble 0, and a stored
    p_bubble is inconsistent; the consistent p is MINI: without its stored p_bubble its errors cannot
    be recomputed (no silent recovery); p_mass None keeps the stored-else-recovered behaviour."""
    P, t, pairs, u, p, c, jump = _synthetic_fields(0)
    C = P[pairs[:, 0]]
    ex = open_exact()
    lumped = E.solver_case_errors(P, t, u, p, None, C, jump, ex, p_mass="lumped")
    zero = E.solver_case_errors(P, t, u, p, np.zeros((len(t), 2)), C, jump, ex)
    assert lumped["bubble"] == "none (lumped)"
    for k in ("u_l2", "p_l2", "p_x", "lambda_l2"):
        assert lumped[k] == zero[k], k
    with_bubble = E.solver_case_errors(P, t, u, p, c, C, jump, ex, p_mass="consistent")
    assert with_bubble["bubble"] == "stored" and with_bubble["p_l2"] != lumped["p_l2"]
    with pytest.raises(E.ExactError, match="lumped p is P1 without bubble"):
        E.solver_case_errors(P, t, u, p, c, C, jump, ex, p_mass="lumped")
    with pytest.raises(E.ExactError, match="no p_bubble"):
        E.solver_case_errors(P, t, u, p, None, C, jump, ex, p_mass="consistent")
    assert E.solver_case_errors(P, t, u, p, None, C, jump, ex)["bubble"] == "recovered"


# ---------------------------------------------------------------------------------------------
# quadrature convergence on a non-trivial field
# ---------------------------------------------------------------------------------------------

def _synthetic_fields(level):
    """Broken level-`level` mesh of open-exact: u_h the face-aware interpolant of u, p_h the
    area-averaged ∇u_h at the vertices, bubbles random, λ_h = [u_h] per node and per segment."""
    P, t, pairs = scene_mesh(level, True)
    ex = open_exact()
    # face values: crack vertices on y = +0 (plus copies) / y = −0 (minus copies)
    y = P[:, 1].copy()
    y[pairs[1:-1, 1]] = -0.0
    u = ex.u(P[:, 0], y)
    g = norms.p1_gradients(P, t, u)
    area = norms.triangle_areas(P, t)
    p = np.zeros((len(P), 2))
    wsum = np.zeros(len(P))
    for k in range(3):
        np.add.at(p, t[:, k], area[:, None] * g)
        np.add.at(wsum, t[:, k], area)
    p /= wsum[:, None]
    c = np.random.default_rng(level).normal(scale=0.1, size=(len(t), 2))
    jump = u[pairs[:, 0]] - u[pairs[:, 1]]
    return P, t, pairs, u, p, c, jump


@pytest.mark.parametrize("level", [0, 2])
def test_doubling_the_quadrature_changes_open_exact_errors_below_1e10(level):
    P, t, pairs, u, p, c, jump = _synthetic_fields(level)
    C = P[pairs[:, 0]]
    for ex in (open_exact(True), open_exact(False)):
        for lam in (jump, 0.5 * (jump[1:] + jump[:-1])):
            base = E.solver_case_errors(P, t, u, p, c, C, lam, ex)
            fine = E.solver_case_errors(P, t, u, p, c, C, lam, ex, E.Quadrature().doubled())
            for k in ("u_l2", "p_l2", "p_x", "lambda_l2"):
                assert abs(base[k] - fine[k]) <= 1e-10 * fine[k], (k, base[k], fine[k])
        b = E.p1_field_errors(P, t, u, pairs, ex)
        f = E.p1_field_errors(P, t, u, pairs, ex, E.Quadrature().doubled())
        for k in b:
            assert abs(b[k] - f[k]) <= 1e-10 * f[k], (k, b[k], f[k])
    # a coarse quadrature without the tip treatment's resolution does move them (the test can fail)
    ex = open_exact()
    coarse = E.solver_case_errors(P, t, u, p, c, C, jump, ex, E.Quadrature(n=2, tip_m=2, eta=0.1, line_n=1))
    fine = E.solver_case_errors(P, t, u, p, c, C, jump, ex, E.Quadrature().doubled())
    assert max(abs(coarse[k] - fine[k]) / fine[k] for k in fine if k != "bubble") > 1e-6


# ---------------------------------------------------------------------------------------------
# agreement with the solver (target/release/sdcrack): summary.json's errors vs this module
# ---------------------------------------------------------------------------------------------

def _run_solver(workdir, scene, level):
    """`sdcrack run` on a copy of scenes/SCENE.toml with fields u, p, lambda, no references and the
    consistent p mass only (MINI p, its bubble stored)."""
    text = set_key((SCENES / f"{scene}.toml").read_text(), "p_mass", '["consistent"]')
    data = tomllib.loads(text)
    lines, section = [], None
    for line in text.splitlines():
        s = line.strip()
        if s.startswith("["):
            section = s
        if section == "[outputs]" and s.startswith("fields"):
            line = 'fields = ["u", "p", "lambda"]'
        if section == "[outputs]" and s.startswith("references"):
            line = "references = []"
        lines.append(line)
    path = workdir / f"{scene}.toml"
    path.write_text("\n".join(lines) + "\n")
    out = workdir / "out"
    subprocess.run([str(BINARY), "run", str(path), "--level", str(level), "--out", str(out)], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, timeout=600)
    subprocess.run([str(BINARY), "mesh", str(path), "--out", str(workdir / "mesh")], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, timeout=600)
    return out / data["name"], workdir / "mesh", E.ExactSolution.from_scene(data)


needs_binary = pytest.mark.skipif(not BINARY.exists(), reason="target/release/sdcrack not built")
LEVEL = 2


@pytest.fixture(scope="module", params=["open-exact", "closed-exact"])
def solver_run(request, tmp_path_factory):
    folder, mesh, ex = _run_solver(tmp_path_factory.mktemp(request.param), request.param, LEVEL)
    summary = json.loads((folder / "summary.json").read_text())
    return request.param, folder, mesh, ex, summary["cases"]


@needs_binary
def test_agreement_with_solver_summary(solver_run):
    """The solver's summary.json errors (crates/sdcrack-core/src/norms.rs) equal this module's to 1e-8 relative."""
    scene, folder, _, ex, cases = solver_run
    # 2 u spaces x 3 multipliers, each over the scene's δ sweep
    assert len({(c["u_space"], c["multiplier"]) for c in cases}) == 6
    assert len({c["delta"] for c in cases}) >= 2 and len(cases) % 6 == 0
    bad = []
    for c in cases:
        ours = E.solver_case_errors_h5(folder / "fields.h5", c["fields_grid"], ex)
        assert ours["bubble"] == "stored", "fields.h5 lacks /cases/CASE/p_bubble"
        for k in ("u_l2", "p_l2", "p_x", "lambda_l2"):
            a, b = c["errors"][k], ours[k]
            if not (abs(a - b) <= 1e-8 * abs(b) or max(abs(a), abs(b)) <= 1e-13):
                bad.append(f"{c['u_space']}/{c['multiplier']} {k}: solver {a!r} vs exact.py {b!r} "
                           f"(relative {a / b - 1:.1e})")
    assert not bad, f"{scene} level {LEVEL}:\n" + "\n".join(bad)


@needs_binary
def test_solver_fields_quadrature_converged_and_bubble_consistent(solver_run):
    """On the solver's own fields: doubling the quadrature moves no error by 1e-10 relative, and the
    stored bubbles are those of the static condensation (recover_bubble, local to each triangle)."""
    _, folder, _, ex, cases = solver_run
    for c in cases:
        d = E.read_h5_case(folder / "fields.h5", c["fields_grid"])
        base = E.solver_case_errors_h5(folder / "fields.h5", c["fields_grid"], ex)
        fine = E.solver_case_errors_h5(folder / "fields.h5", c["fields_grid"], ex, E.Quadrature().doubled())
        for k in ("u_l2", "p_l2", "p_x", "lambda_l2"):
            assert abs(base[k] - fine[k]) <= 1e-10 * fine[k] or max(base[k], fine[k]) <= 1e-13, (c["fields_grid"], k)
        rec = E.recover_bubble(d["points"], d["triangles"], d["u"], d["p"])
        scale = np.abs(d["p"]).max() + 1.0
        assert np.abs(rec - d["p_bubble"]).max() <= 1e-10 * scale, c["fields_grid"]


@needs_binary
def test_p1_field_errors_on_the_exported_cracked_mesh(solver_run):
    """`sdcrack mesh` export (the references' meshes): the crack pairs are (+ face, − face), and the
    solver's broken u on it has the same u_l2 as from fields.h5 (same P1 field, same mesh)."""
    from sdcompare_lib.read import load_export_meshes

    scene, folder, mesh, ex, cases = solver_run
    m = load_export_meshes(str(mesh), [LEVEL])[LEVEL]
    P, t, pairs = m.points, m.tris, m.crack
    # face-aware interpolant of the exact u: crack copies used by triangles below get y = −0
    below = P[t].mean(axis=1)[:, 1] < 0
    y = P[:, 1].copy()
    y[np.unique(t[below])[P[np.unique(t[below]), 1] == 0.0]] = -0.0
    ui = ex.u(P[:, 0], y)
    r = E.p1_field_errors(P, t, ui, pairs, ex, ranges=m.ranges)
    jump_norm = E.p1_field_errors(P, t, 0 * ui, pairs, ex, ranges=m.ranges)["lambda_l2"]
    if scene == "open-exact":
        assert r["lambda_l2"] < 0.1 * jump_norm  # a swapped pair would give about 2 jump_norm
    else:
        assert r["lambda_l2"] < 1e-13 and jump_norm == 0.0
    c = next(c for c in cases if c["u_space"] == "broken")
    d = E.read_h5_case(folder / "fields.h5", c["fields_grid"])
    assert np.array_equal(d["triangles"], t) and np.abs(d["points"][:, :2] - P).max() == 0.0
    q = E.p1_field_errors(P, t, d["u"], pairs, ex, ranges=m.ranges)
    assert q["u_l2"] == pytest.approx(E.solver_case_errors_h5(folder / "fields.h5", c["fields_grid"], ex)["u_l2"],
                                      rel=1e-13)


def test_cached_mesh_quadrature_gives_the_uncached_errors():
    """The exact solution's values at a mesh's quadrature points are kept for the next case on
    the same mesh (the compare tool's cost). A case computed from the cache equals, to
    the bit, the same case computed with an empty cache; a mesh with other coordinates (same
    shape) and another exact solution are not served from the cache."""
    ex = E.ExactSolution("x*x - y + sin(x*y)", crack=((-0.5, 0.0), (0.5, 0.0)))
    n = 4
    P = np.array([[-1 + 2 * i / n, -1 + 2 * j / n] for j in range(n + 1) for i in range(n + 1)])
    tris = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            tris += [[a, a + 1, a + n + 2], [a, a + n + 2, a + n + 1]]
    tris = np.array(tris)
    crack = np.array([[-0.5, 0.0], [0.0, 0.0], [0.5, 0.0]])

    def errors(points, u_scale, exact=ex):
        u = u_scale * (points[:, 0] - points[:, 1])
        p = np.column_stack([u, -u])
        return E.solver_case_errors(points, tris, u, p, None, crack, np.zeros(3), exact)

    E._MESH_QUADRATURE.items.clear()
    first = [errors(P, s) for s in (1.0, 2.0)]
    assert len(E._MESH_QUADRATURE.items) == 1  # the second case reused the first one's values
    E._MESH_QUADRATURE.items.clear()
    assert errors(P, 2.0) == first[1]
    moved = P * np.array([1.0, 0.75])  # other coordinates, the same array shape
    E._MESH_QUADRATURE.items.clear()
    alone = errors(moved, 1.0)
    assert alone != first[0]
    # with the moved mesh in the cache, the original mesh still gets its own values, and back
    assert errors(P, 1.0) == first[0]
    assert errors(moved, 1.0) == alone
    other = E.ExactSolution("x*x - y", crack=((-0.5, 0.0), (0.5, 0.0)))
    assert errors(P, 1.0, other) != first[0]
    assert norms.digest(np.zeros(4)) != norms.digest(np.zeros((2, 2)))


def test_cached_nesting_gives_the_uncached_prolongation():
    """prolong_to_fine keeps each (coarse, fine) pair's nesting; the prolongation of new values on
    a cached pair equals the uncached one, and a wrong nesting is still an error."""
    cp = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    ct = np.array([[0, 1, 2]])
    fp = np.array([[0.0, 0.0], [0.5, 0.0], [0.0, 0.5], [1.0, 0.0], [0.5, 0.5], [0.0, 1.0]])
    ft = np.array([[0, 1, 2], [1, 3, 4], [2, 4, 5], [1, 4, 2]])
    owner = np.zeros(4, dtype=np.int64)
    norms._NESTED.items.clear()
    a = norms.prolong_to_fine(cp, ct, np.array([1.0, 2.0, 3.0]), fp, ft, "graded", owner)
    b = norms.prolong_to_fine(cp, ct, np.array([4.0, 5.0, 7.0]), fp, ft, "graded", owner)
    norms._NESTED.items.clear()
    assert np.array_equal(b, norms.prolong_to_fine(cp, ct, np.array([4.0, 5.0, 7.0]), fp, ft,
                                                   "graded", owner))
    assert np.allclose(a[0], [1.0, 1.5, 2.0])
    with pytest.raises(norms.NormError):
        norms.prolong_to_fine(cp, ct, np.zeros(3), fp + 2.0, ft, "graded", owner)
