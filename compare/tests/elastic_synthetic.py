"""Synthetic results folders of elastic scenes (docs/elasticity.md) for the compare tool's tests,
without sdcrack or the references: the mesh export of references/tests/elastic_export.py (the
dolfinx helper's stand-in for `sdcrack mesh`; by default the edge crack y = 0, −1 ≤ x ≤ 0 on
(−1, 1)², mouth at (−1, 0), tip at the origin), and per reference the outputs a correct reference
would write if its solution were the P1 interpolant of the exact u (u_level{L}.txt from the exact
field, the crack file from it: opening and slip of the copies, the contact force m_j · p(x_j) on
the rows it flags closed).

williams(K_I, K_II): Williams' edge-crack field (plane strain, E = 1, ν = 0.3), stresses in closed
form (the tests check them against Hooke's law of the symbolic derivatives of u).
"""
import json
import math
from pathlib import Path

import numpy as np
from elastic_export import elastic_export, material  # references/tests (pyproject's pytest pythonpath)
from sdcompare_lib import elastic_read
from sdshared import sdexpr

E, NU = 1.0, 0.3
MU = E / (2 * (1 + NU))
LAMBDA = E * NU / ((1 + NU) * (1 - 2 * NU))
KAPPA = 3 - 4 * NU
PROBLEM = material(E=E, nu=NU)


def williams(k1, k2):
    """The exact table of Williams' field K_I k1 + K_II k2 at the tip (0, 0), crack behind it."""
    r, th = "sqrt(x^2 + y^2)", "atan2(y, x)"
    c, s = f"cos({th}/2)", f"sin({th}/2)"
    c3, s3 = f"cos(3*{th}/2)", f"sin(3*{th}/2)"
    a = f"(sqrt({r}/(2*pi))/(2*{MU!r}))"
    b = f"(1/sqrt(2*pi*{r}))"
    k = repr(KAPPA)
    ux = (f"{k1!r}*{a}*{c}*({k} - 1 + 2*{s}^2) + {k2!r}*{a}*{s}*({k} + 1 + 2*{c}^2)")
    uy = (f"{k1!r}*{a}*{s}*({k} + 1 - 2*{c}^2) - {k2!r}*{a}*{c}*({k} - 1 - 2*{s}^2)")
    sxx = f"{k1!r}*{b}*{c}*(1 - {s}*{s3}) - {k2!r}*{b}*{s}*(2 + {c}*{c3})"
    syy = f"{k1!r}*{b}*{c}*(1 + {s}*{s3}) + {k2!r}*{b}*{s}*{c}*{c3}"
    sxy = f"{k1!r}*{b}*{s}*{c}*{c3} + {k2!r}*{b}*{c}*(1 - {s}*{s3})"
    return {"ux": ux, "uy": uy, "sxx": sxx, "syy": syy, "sxy": sxy, "opening": None,
            "slip": None, "pressure": None, "sif": [[k1, k2]]}


def linear_exact(grad, shift=(0.0, 0.0)):
    """The exact table of the linear field u = grad·(x, y) + shift (no SIFs): its stress is the
    constant Hooke's law of grad, written as Python floats."""
    from sdcompare_lib import elastic_exact

    (a, b), (c, d) = grad
    s = elastic_exact.hooke(np.asarray(grad, dtype=float), PROBLEM)
    return {"ux": f"{a!r}*x + {b!r}*y + {shift[0]!r}", "uy": f"{c!r}*x + {d!r}*y + {shift[1]!r}",
            "sxx": repr(float(s[0])), "syy": repr(float(s[1])), "sxy": repr(float(s[2])), "sif": None}


def write_export(out, name, exact, levels, n0, crack=((-1.0, 0.0), (0.0, 0.0))):
    """The mesh export (references/tests/elastic_export.py, the dolfinx helper's stand-in for
    `sdcrack mesh`) of the scene with this exact table, g = the exact u on ∂Ω."""
    g = None if exact is None else [exact["ux"], exact["uy"]]
    return elastic_export(out, name, PROBLEM, f=["0", "0"], g=g, exact=exact, levels=levels, n0=n0,
                          crack=crack)


def interpolant(exact, level):
    """u (N, 2) of the P1 interpolant on the cracked mesh of a Level: the exact u at every vertex,
    a crack row's + and − copies by sdexpr.on_face (the face rule's signed zeros)."""
    xy = level.points
    x, y = xy[:, 0].copy(), xy[:, 1].copy()
    rows = level.pair_rows()
    for side, col in ((1.0, 0), (-1.0, 1)):
        v = level.pairs[rows, col]
        for k, nu in zip(v, level.normals[rows]):
            x[k], y[k] = (float(c[0]) for c in sdexpr.on_face(x[k:k + 1], y[k:k + 1], nu, side))
    return np.column_stack([sdexpr.to_numpy(exact[c])(x, y) for c in ("ux", "uy")])


def reference_outputs(exact, level, closed):
    """(u, crack (I, 4)) of a reference whose solution is the interpolant on the Level `level`
    (sdcompare_lib.elastic_read); `closed` (I,) bool the rows it reports active, their force
    m_j · p(x_j), p = −ν·σν of the exact field on the + face."""
    xy, pairs, nu = level.points, level.pairs, level.normals
    u = interpolant(exact, level)
    crack = np.zeros((len(pairs), 4))
    crack[:, 0], crack[:, 1] = jumps(u, pairs, nu)
    c = xy[pairs[:, 0]] + 1e-12 * nu
    sxx, syy, sxy = (sdexpr.to_numpy(exact[k])(c[:, 0], c[:, 1]) for k in ("sxx", "syy", "sxy"))
    p = -(sxx * nu[:, 0] ** 2 + 2 * sxy * nu[:, 0] * nu[:, 1] + syy * nu[:, 1] ** 2)
    crack[:, 2] = np.where(closed, level.nodal_measure() * p, 0.0)
    crack[:, 3] = closed.astype(float)
    crack[level.tip_rows()] = 0.0
    return u, crack


def jumps(u, pairs, nu):
    """(opening, slip) per row: (u⁺ − u⁻)·ν and ·τ, τ = ν turned by −90°."""
    j = u[pairs[:, 0]] - u[pairs[:, 1]]
    return j[:, 0] * nu[:, 0] + j[:, 1] * nu[:, 1], j[:, 0] * nu[:, 1] - j[:, 1] * nu[:, 0]


def write_results(out, exact=None, levels=(0, 1, 2), n0=4, tools=("dolfinx", "freefem"),
                  name="williams", perturb=None, closed=None, damage=None,
                  crack=((-1.0, 0.0), (0.0, 0.0))):
    """A results folder OUT/ of the Williams edge crack (or `exact` on `crack`), every reference
    solving to the interpolant. perturb(xy) -> (N, 2) is added to every reference's u;
    closed(level, xy, pairs) -> (I,) bool the active flags (default none); damage(tool, level, u,
    crack) may change a reference's arrays in place."""
    out = Path(out)
    exact = exact or williams(1.0, 0.0)
    out.mkdir(parents=True, exist_ok=True)
    write_export(out / "mesh", name, exact, levels, n0, crack)
    (out / "summary.json").write_text(json.dumps({"scene": name, "problem": "elasticity"}))
    toml = [f'name = "{name}"', "[problem]", 'kind = "elasticity"', "E = 1.0", "nu = 0.3",
            "[discretization]", f"cells = [{n0}, {n0}]", f"levels = {list(levels)}",
            "[outputs]", f"references = {json.dumps(list(tools))}"]
    (out / "scene.toml").write_text("\n".join(toml) + "\n")
    for tool in tools:
        d = out / tool
        d.mkdir(exist_ok=True)
        cases = []
        for level in levels:
            lv = elastic_read.read_level(str(out / "mesh"), level)
            xy, pairs = lv.points, lv.pairs
            flags = (closed(level, xy, pairs) if closed else np.zeros(len(pairs), dtype=bool))
            u, crack_out = reference_outputs(exact, lv, flags)
            if perturb is not None:
                u = u + perturb(xy)
                crack_out[:, 0], crack_out[:, 1] = jumps(u, pairs, lv.normals)
                crack_out[lv.tip_rows()] = 0.0
            if damage is not None:
                damage(tool, level, u, crack_out)
            np.savetxt(d / f"u_level{level}.txt", u, fmt="%.17g")
            np.savetxt(d / f"crack_level{level}.txt", crack_out, fmt="%.17g")
            n = n0 * 2 ** level
            cases.append({"level": level, "h": 2 * math.sqrt(2) / n, "unknowns": 2 * len(xy),
                          "iterations": 1, "active": int(flags.sum()),
                          "kkt": {"equations": 1e-15, "primal": 0.0, "dual": 0.0,
                                  "complementarity": 0.0},
                          "status": "converged", "timings_s": {"solve": 0.01}})
        (d / "summary.json").write_text(json.dumps({"scene": name, "tool": tool,
                                                    "problem": "elasticity",
                                                    "provenance": {"tool": tool},
                                                    "cases": cases}))
    return out


# ------------------------------------------------------------------ the smooth-domain method's cases

def sdm_fields(exact, level, nudge=1e-13):
    """The fields (elastic_sdm.SdmCase's arrays) of a solver case equal to the exact field on the
    Level's triangles (broken: three corners per triangle): σ_h = sym σ_h = σ at the corners, u* = u
    at the corners, u_h, γ_h their centroid values, the crack's opening, slip, pressure the exact
    ones at each segment's ends. Corners are evaluated `nudge` of the way to the centroid (each
    triangle's own face of the crack); σ at a corner at a tip takes the centroid's value."""
    from sdcompare_lib import elastic_exact

    ex = elastic_exact.ElasticExact(exact, PROBLEM)
    tri = level.triangles
    X = level.points[tri]  # (T, 3, 2)
    cen = X.mean(axis=1)
    tips = np.array([level.nodes()[r] for r in level.tip_rows()]).reshape(-1, 2)
    at_tip = np.zeros(X.shape[:2], dtype=bool)
    for tp in tips:
        at_tip |= np.hypot(*(X - tp).transpose(2, 0, 1)) == 0.0
    Q = X + nudge * (cen[:, None, :] - X)
    v = ex.evaluate(Q[..., 0].ravel(), Q[..., 1].ravel(), ("ux", "uy"))
    # σ at a corner at a tip: the centroid's (the exact σ may be infinite there)
    Q = X + np.where(at_tip, 1.0, nudge)[..., None] * (cen[:, None, :] - X)
    v.update(ex.evaluate(Q[..., 0].ravel(), Q[..., 1].ravel(), ("sxx", "syy", "sxy")))
    T = len(tri)
    sig = np.zeros((3 * T, 9))
    sig[:, 0], sig[:, 1], sig[:, 3], sig[:, 4] = v["sxx"], v["sxy"], v["sxy"], v["syy"]
    u_star = np.zeros((3 * T, 3))
    u_star[:, 0], u_star[:, 1] = v["ux"] * np.ones(3 * T), v["uy"] * np.ones(3 * T)
    c = ex.evaluate(cen[:, 0], cen[:, 1], ("ux", "uy", "duxdy", "duydx"))
    u_h = np.zeros((T, 3))
    u_h[:, 0], u_h[:, 1] = c["ux"] * np.ones(T), c["uy"] * np.ones(T)
    gamma = 0.5 * (c["duxdy"] - c["duydx"]) * np.ones(T)
    seg = level.segments()
    nodes = level.nodes()
    cp = nodes[seg.ravel()]
    normals = np.repeat(np.column_stack([-(nodes[seg[:, 1]] - nodes[seg[:, 0]])[:, 1],
                                         (nodes[seg[:, 1]] - nodes[seg[:, 0]])[:, 0]]), 2, axis=0)
    normals /= np.hypot(*normals.T)[:, None]
    normals *= np.sign(np.sum(normals * level.normals[seg.ravel()], axis=1))[:, None]
    cv = ex.crack_values(cp, normals)
    crack = {k: np.nan_to_num(np.asarray(cv[k], dtype=float) * np.ones(len(cp)))
             for k in ("opening", "slip", "pressure")}
    points = np.zeros((3 * T, 3))
    points[:, :2] = X.reshape(-1, 2)
    cpoints = np.zeros((len(cp), 3))
    cpoints[:, :2] = cp
    return {"points": points, "triangles": np.arange(3 * T).reshape(T, 3), "sigma": sig,
            "sigma_raw": sig.copy(), "u_h": u_h, "gamma_h": gamma, "u_star": u_star,
            "crack/points": cpoints, "crack/segments": np.arange(len(cp)).reshape(-1, 2),
            **{f"crack/{k}": a for k, a in crack.items()}}


def write_sdm_cases(folder, exact, variants=(("M1star", 0.0),), damage=None, forge=None,
                    status=None, closed=None):
    """Add solver cases to a results folder of write_results: per level of its scene copy and per
    (multiplier, δ) the fields of sdm_fields in fields.h5 and a summary.json case whose errors are
    recomputed by elastic_sdm (damage(level, multiplier, δ, fields) may change the fields first;
    forge(level, multiplier, δ, errors) the errors written after; status(level, multiplier, δ)
    the case's status, default "converged"; closed(level, crack points (2E, 2)) the crack/closed
    flags written, default none written)."""
    import h5py
    import tomllib

    from sdcompare_lib import elastic_exact, elastic_sdm

    folder = Path(folder)
    scene = tomllib.loads((folder / "scene.toml").read_text())
    levels = scene["discretization"]["levels"]
    summary = json.loads((folder / "summary.json").read_text())
    ex = elastic_exact.ElasticExact(exact, PROBLEM)
    cases = []
    with h5py.File(folder / "fields.h5", "w") as h5:
        for L in levels:
            lv = elastic_read.read_level(str(folder / "mesh"), L)
            base = sdm_fields(exact, lv)
            h5[f"meshes/level{L}-elasticity/points"] = base["points"]
            h5[f"meshes/level{L}-elasticity/triangles"] = base["triangles"]
            for m, d in variants:
                f = {k: np.array(v) for k, v in base.items()}
                if damage is not None:
                    damage(L, m, d, f)
                grid = f"level{L}-elasticity-{m}-delta{d:g}"
                for k in ("sigma", "sigma_raw", "u_h", "gamma_h", "u_star", "crack/points",
                          "crack/segments", "crack/opening", "crack/slip", "crack/pressure"):
                    h5[f"cases/{grid}/{k}"] = f[k]
                if closed is not None:
                    h5[f"cases/{grid}/crack/closed"] = closed(L, f["crack/points"][:, :2]).astype(
                        float)
                X = lv.points[lv.triangles]
                h = float(max(np.hypot(*(X[:, i] - X[:, (i + 1) % 3]).T).max() for i in range(3)))
                entry = {"level": L, "h": h, "multiplier": m, "delta": d, "problem": "elasticity",
                         "fields_grid": grid, "status": "converged", "converged": True,
                         "kkt": {"equations": 0.0, "primal": 0.0, "dual": 0.0,
                                 "complementarity": 0.0}}
                if status is not None:
                    entry["status"] = status(L, m, d)
                case = elastic_sdm.read_cases_from(h5, [dict(entry, errors={})], str(folder))[0]
                errors, _ = elastic_sdm.recompute(case, lv, ex, PROBLEM)
                if forge is not None:
                    forge(L, m, d, errors)
                entry["errors"] = errors
                cases.append(entry)
    summary["cases"] = cases
    (folder / "summary.json").write_text(json.dumps(summary))
    return folder
