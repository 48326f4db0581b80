"""The elastic reference tests' scenes (docs/elasticity.md, issue 45 item 3) as exports of the stand-in
`elastic_export` (references/tests/elastic_export.py), and what the tests compute on the references'
outputs: their exact fields as scene-grammar strings, checked numerically in
test_freefem_elasticity.py before any reference is judged by them.

    patch_export        uniform compression σ_yy = −1 across an interior or an edge crack, by Dirichlet
                        data or by tractions and fixed points
    diagonal_patch_export  unit pressure across a crack along the cells' diagonals (ν = (−1, 1)/√2)
    williams_export     Williams' edge crack y = 0, x ≤ 0 of (−1, 1)², mode I (K_I > 0, open) and/or mode II
    closed_slip_export  u_C + K_II mode II with f = −div σ(u_C): closed everywhere, slip ~ √r
    getfem_export       GetFEM's xfem_stab_unilat_contact set-up: traction and fixed points only

Standard library and numpy only.
"""

import json
import math
from pathlib import Path

import numpy as np

from elastic_export import elastic_export, material

STEEL = {"E": 1.0, "nu": 0.3}      # the pilot's material (κ = 1.8 in plane strain)
INTERIOR_CRACK = ((-0.5, 0.0), (0.5, 0.0))
EDGE_CRACK = ((-1.0, 0.0), (0.0, 0.0))  # a mouth at (−1, 0), the tip at the origin


def r(v):
    """A float as scene text that reads back bit for bit."""
    return repr(float(v))


# ---- patch test ------------------------------------------------------------------------------------

def patch_strain(problem):
    """(ε_xx, ε_yy) of σ = (σ_xx, σ_yy, σ_xy) = (0, −1, 0) in the in-plane law σ = λ* tr ε I + 2μ ε:
    ε_yy = −(λ* + 2μ)/(4μ(λ* + μ)), ε_xx = λ*/(4μ(λ* + μ)) (σ_xx = 0 ⇔ (λ* + 2μ) ε_xx = −λ* ε_yy).
    Plane strain: ε_xx = ν(1 + ν)/E, ε_yy = −(1 − ν²)/E; plane stress: ν/E, −1/E."""
    lam, mu = problem["lambda_in_plane"], problem["mu"]
    d = 4 * mu * (lam + mu)
    return lam / d, -(lam + 2 * mu) / d


# the patch under tractions: t = σn = (0, ±1) on the bottom and top, 0 on the sides; the rigid modes
# held at the corners (1, −1) (both components) and (1, 1) (x), where the exact field vanishes
PATCH_TRACTIONS = {"left": ["0", "0"], "right": ["0", "0"], "bottom": ["0", "1"], "top": ["0", "-1"]}
PATCH_FIXED = [{"point": [1.0, -1.0], "components": ["x", "y"]}, {"point": [1.0, 1.0], "components": ["x"]}]


def patch_export(out, plane="strain", crack=INTERIOR_CRACK, levels=(0, 1), tractions=False):
    """u = (ε_xx x, ε_yy y) with u = g on ∂Ω, or with `tractions` u = (ε_xx (x − 1), ε_yy (y + 1))
    under PATCH_TRACTIONS and PATCH_FIXED (an edge crack's mouth is then a constrained pair)."""
    problem = material(**STEEL, plane=plane)
    exx, eyy = patch_strain(problem)
    if tractions:
        u = [f"{r(exx)}*(x - 1)", f"{r(eyy)}*(y + 1)"]
        loads = {"g": None, "tractions": PATCH_TRACTIONS, "fixed": PATCH_FIXED}
    else:
        u = [f"{r(exx)}*x", f"{r(eyy)}*y"]
        loads = {"g": u}
    exact = {"ux": u[0], "uy": u[1], "sxx": "0", "syy": "-1", "sxy": "0", "opening": "0", "pressure": "1"}
    return elastic_export(out, f"patch-{plane}", problem, ["0", "0"], exact=exact, levels=levels,
                          crack=crack, **loads)


DIAGONAL_CRACK = ((-0.5, -0.5), (0.5, 0.5))  # along the cells' SW–NE diagonals: ν = (−1, 1)/√2


def diagonal_patch_strain(problem):
    """(ε_xx, ε_yy, ε_xy) of σ = −ν⊗ν, ν = (−1, 1)/√2 (σ_xx = σ_yy = −½, σ_xy = ½: unit pressure on
    the diagonal crack): ε = (σ − λ*/(2(λ* + μ)) tr σ I)/(2μ), tr σ = −1."""
    lam, mu = problem["lambda_in_plane"], problem["mu"]
    e = (-0.5 + lam / (2 * (lam + mu))) / (2 * mu)
    return e, e, 0.5 / (2 * mu)


def diagonal_patch_export(out, levels=(0, 1)):
    """u = ε x (ε symmetric: no rotation) with u = g on ∂Ω across the diagonal crack."""
    problem = material(**STEEL)
    exx, eyy, exy = diagonal_patch_strain(problem)
    u = [f"{r(exx)}*x + {r(exy)}*y", f"{r(exy)}*x + {r(eyy)}*y"]
    exact = {"ux": u[0], "uy": u[1], "sxx": "-0.5", "syy": "-0.5", "sxy": "0.5", "opening": "0",
             "pressure": "1"}
    return elastic_export(out, "patch-diagonal", problem, ["0", "0"], g=u, exact=exact, levels=levels,
                          crack=DIAGONAL_CRACK)


# ---- Williams' edge crack ------------------------------------------------------------------------

def williams_u(problem, k1, k2):
    """(u_x, u_y) of K_I mode I + K_II mode II at the tip (0, 0) of the crack along the negative x-axis
    (θ = atan2(y, x) = ±π on its faces; e₁ = (1, 0)):
        u_x = √(r/2π)/(2μ) [K_I cos(θ/2)(κ − cos θ) + K_II sin(θ/2)(κ + 2 + cos θ)],
        u_y = √(r/2π)/(2μ) [K_I sin(θ/2)(κ − cos θ) − K_II cos(θ/2)(κ − 2 + cos θ)]."""
    mu, kappa = problem["mu"], problem["kolosov"]
    c = f"(sqrt(sqrt(x^2 + y^2)/(2*pi))/(2*{r(mu)}))"
    t = "atan2(y, x)"
    ux = (f"{c}*({r(k1)}*cos({t}/2)*({r(kappa)} - cos({t})) "
          f"+ {r(k2)}*sin({t}/2)*({r(kappa)} + 2 + cos({t})))")
    uy = (f"{c}*({r(k1)}*sin({t}/2)*({r(kappa)} - cos({t})) "
          f"- {r(k2)}*cos({t}/2)*({r(kappa)} - 2 + cos({t})))")
    return ux, uy


def williams_stress(k1, k2):
    """(σ_xx, σ_yy, σ_xy) of the same fields (Williams' leading terms, independent of the material):
        σ_xx = [K_I cos(θ/2)(1 − s s3) − K_II sin(θ/2)(2 + c c3)]/√(2πr),
        σ_yy = [K_I cos(θ/2)(1 + s s3) + K_II sin(θ/2) c c3]/√(2πr),
        σ_xy = [K_I cos(θ/2) s c3 + K_II cos(θ/2)(1 − s s3)]/√(2πr),
    s = sin(θ/2), c = cos(θ/2), s3 = sin(3θ/2), c3 = cos(3θ/2)."""
    t = "atan2(y, x)"
    q = "sqrt(2*pi*sqrt(x^2 + y^2))"
    s, c, s3, c3 = f"sin({t}/2)", f"cos({t}/2)", f"sin(3*{t}/2)", f"cos(3*{t}/2)"
    sxx = f"({r(k1)}*{c}*(1 - {s}*{s3}) - {r(k2)}*{s}*(2 + {c}*{c3}))/{q}"
    syy = f"({r(k1)}*{c}*(1 + {s}*{s3}) + {r(k2)}*{s}*{c}*{c3})/{q}"
    sxy = f"({r(k1)}*{c}*{s}*{c3} + {r(k2)}*{c}*(1 - {s}*{s3}))/{q}"
    return sxx, syy, sxy


def williams_export(out, k1=1.0, k2=0.0, levels=(0, 1, 2, 3)):
    problem = material(**STEEL)
    ux, uy = williams_u(problem, k1, k2)
    sxx, syy, sxy = williams_stress(k1, k2)
    exact = {"ux": ux, "uy": uy, "sxx": sxx, "syy": syy, "sxy": sxy, "sif": [[k1, k2]]}
    return elastic_export(out, "williams", problem, ["0", "0"], g=[ux, uy], exact=exact, levels=levels,
                          crack=EDGE_CRACK)


# ---- closed with frictionless slip -----------------------------------------------------------------

CLOSED_C = 0.1


def closed_smooth(problem, c=CLOSED_C):
    """u_C = c(0.3 sin x cos y, −sin y (2 + cos x)) (u_x even, u_y odd in y), its stress and
    f = −div σ(u_C), by hand: ε_xx = 0.3c cos x cos y, ε_yy = −c cos y (2 + cos x),
    ε_xy = 0.35c sin x sin y, tr ε = −c cos y (2 + 0.7 cos x);
        f_x = −c sin x cos y (0.7λ* + 0.1μ),  f_y = −c sin y (2λ* + 4μ + (0.7λ* + 2.7μ) cos x).
    On y = 0: σ_xy = 0 and σ_yy = −c(2 + 0.7 cos x)λ* − 2μc(2 + cos x) < 0 (contact)."""
    lam, mu = problem["lambda_in_plane"], problem["mu"]
    u = (f"{r(c)}*0.3*sin(x)*cos(y)", f"-{r(c)}*sin(y)*(2 + cos(x))")
    tr = f"(-{r(c)}*cos(y)*(2 + 0.7*cos(x)))"
    stress = (f"{r(lam)}*{tr} + 2*{r(mu)}*{r(c)}*0.3*cos(x)*cos(y)",
              f"{r(lam)}*{tr} - 2*{r(mu)}*{r(c)}*cos(y)*(2 + cos(x))",
              f"2*{r(mu)}*{r(c)}*0.35*sin(x)*sin(y)")
    f = (f"-{r(c)}*sin(x)*cos(y)*{r(0.7 * lam + 0.1 * mu)}",
         f"-{r(c)}*sin(y)*({r(2 * lam + 4 * mu)} + {r(0.7 * lam + 2.7 * mu)}*cos(x))")
    return u, stress, f


def closed_slip_export(out, k2=1.0, levels=(0, 1, 2, 3)):
    problem = material(**STEEL)
    (uc_x, uc_y), sc, f = closed_smooth(problem)
    wx, wy = williams_u(problem, 0.0, k2)
    ws = williams_stress(0.0, k2)
    ux, uy = f"{uc_x} + {wx}", f"{uc_y} + {wy}"
    exact = {"ux": ux, "uy": uy, "sxx": f"{sc[0]} + {ws[0]}", "syy": f"{sc[1]} + {ws[1]}",
             "sxy": f"{sc[2]} + {ws[2]}", "opening": "0", "sif": [[0.0, k2]]}
    return elastic_export(out, "closed-slip", problem, list(f), g=[ux, uy], exact=exact, levels=levels,
                          crack=EDGE_CRACK)


# ---- GetFEM's set-up -----------------------------------------------------------------------------

GETFEM_DOMAIN = ((0.0, -0.5), (1.0, 0.5))
GETFEM_CRACK = ((0.0, 0.0), (0.5, 0.0))  # a mouth at (0, 0), the tip at (1/2, 0)
GETFEM_FIXED = [{"point": [1.0, -0.5], "components": ["x", "y"]}, {"point": [1.0, 0.5], "components": ["x"]}]


def getfem_export(out, fixed=GETFEM_FIXED, levels=(0, 1, 2)):
    """GetFEM's contrib/xfem_stab_unilat_contact (issue 45 item 3): [0, 1] × [−½, ½], the crack y = 0
    for x ≤ ½, λ = μ = 1, t = 0.4 sin(2πy) n on x = 0 and x = 1 (n = ∓e_x), free top and bottom,
    f = (0, 3.5 cos(2πx) y x(1 − x)), u(1, −½) = 0, u_x(1, ½) = 0: no Dirichlet part."""
    problem = material(lam=1.0, mu=1.0)
    tractions = {"left": ["-0.4*sin(2*pi*y)", "0"], "right": ["0.4*sin(2*pi*y)", "0"],
                 "bottom": ["0", "0"], "top": ["0", "0"]}
    f = ["0", "3.5*cos(2*pi*x)*y*x*(1 - x)"]
    return elastic_export(out, "getfem", problem, f, g=None, tractions=tractions, fixed=fixed,
                          levels=levels, domain=GETFEM_DOMAIN, crack=GETFEM_CRACK)


# ---- reading a reference's results ---------------------------------------------------------------

def read_results(out, level):
    """(u (n, 2), crack table (I, 4): opening slip contact_force active) of a reference's level."""
    out = Path(out)
    return (np.loadtxt(out / f"u_level{level}.txt", ndmin=2),
            np.loadtxt(out / f"crack_level{level}.txt", ndmin=2))


def scene(export):
    return json.loads((Path(export) / "scene.json").read_text())


def nodal_lengths(export, level):
    """m_j = half the sum of the lengths of crack row j's segments (docs/elasticity.md), per row."""
    d = Path(export) / f"level{level}"
    xy = np.loadtxt(d / "vertices.txt", ndmin=2)
    pairs = np.loadtxt(d / "crack.txt", dtype=np.int64, ndmin=2)
    cracks = np.loadtxt(d / "cracks.txt", dtype=np.int64, ndmin=2)
    m = np.zeros(len(pairs))
    for first, n, *_ in cracks:
        for k in range(first, first + n - 1):
            half = 0.5 * math.dist(xy[pairs[k, 0]], xy[pairs[k + 1, 0]])
            m[k] += half
            m[k + 1] += half
    return m
