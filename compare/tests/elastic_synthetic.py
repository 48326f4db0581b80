"""Synthetic results folders of elastic scenes (docs/elasticity.md) for the compare tool's tests,
without sdcrack or the references: an edge crack y = 0, −1 ≤ x ≤ 0 on (−1, 1)² (mouth at
(−1, 0), tip at the origin) on the structured SW–NE grid of references/tests/fake_export.py, the
mesh export's files, and per reference the outputs a correct reference would write if its
solution were the P1 interpolant of the exact u (u_level{L}.txt from the exact field, the crack
file from it: opening and slip of the copies, the contact force m_j · p(x_j) on closed rows).

williams(K_I, K_II): Williams' edge-crack field (plane strain, E = 1, ν = 0.3), stresses in closed
form (the tests check them against Hooke's law of the symbolic derivatives of u).
"""
import json
import math
from pathlib import Path

import numpy as np
from fake_export import structured_level  # references/tests (pyproject's pytest pythonpath)
from sdshared import sdexpr

E, NU = 1.0, 0.3
MU = E / (2 * (1 + NU))
LAMBDA = E * NU / ((1 + NU) * (1 - 2 * NU))
KAPPA = 3 - 4 * NU
PROBLEM = {"kind": "elasticity", "plane": "strain", "E": E, "nu": NU, "lambda": LAMBDA, "mu": MU,
           "lambda_in_plane": LAMBDA, "kolosov": KAPPA, "e_prime": E / (1 - NU ** 2)}


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


def cracked_level(n):
    """(points, triangles, pairs) of the n × n grid cut along y = 0, x ≤ 0: every crack node but
    the tip doubled (the mouth at (−1, 0) too), the − copies appended, triangles below the crack
    on them."""
    xy_u, tri_u = structured_level(n)
    on = (np.abs(xy_u[:, 1]) < 1e-14) & (xy_u[:, 0] < 1e-14)
    nodes = np.flatnonzero(on)
    nodes = nodes[np.argsort(xy_u[nodes, 0])]  # mouth (−1, 0) → tip (0, 0)
    doubled = nodes[:-1]
    copy = {int(v): len(xy_u) + k for k, v in enumerate(doubled)}
    xy = np.vstack([xy_u, xy_u[doubled]])
    tri = tri_u.copy()
    below = xy_u[tri_u].mean(axis=1)[:, 1] < 0
    for t in np.flatnonzero(below):
        tri[t] = [copy.get(int(v), int(v)) for v in tri_u[t]]
    pairs = np.array([(int(v), copy.get(int(v), int(v))) for v in nodes], dtype=np.int64)
    return xy, tri, pairs


def write_export(out, name, exact, levels, n0):
    out = Path(out)
    for level in levels:
        n = n0 * 2 ** level
        xy, tri, pairs = cracked_level(n)
        d = out / f"level{level}"
        d.mkdir(parents=True, exist_ok=True)
        np.savetxt(d / "vertices.txt", xy, fmt="%.17g")
        np.savetxt(d / "triangles.txt", tri, fmt="%d")
        np.savetxt(d / "crack.txt", pairs, fmt="%d")
        np.savetxt(d / "cracks.txt", [[0, len(pairs), 0, 1]], fmt="%d")
        np.savetxt(d / "crack_normals.txt", np.tile([0.0, 1.0], (len(pairs), 1)), fmt="%.17g")
        (d / "mesh.json").write_text(json.dumps({"kind": "structured", "nx": n, "ny": n,
                                                 "level": level, "h": 2 * math.sqrt(2) / n}))
    scene = {"name": name, "problem": PROBLEM, "f": ["0", "0"], "g": [exact["ux"], exact["uy"]],
             "tractions": {}, "fixed": [], "exact": exact,
             "cracks": [{"points": [[-1.0, 0.0], [0.0, 0.0]]}], "levels": list(levels)}
    (out / "scene.json").write_text(json.dumps(scene, indent=1))


def interpolant(exact, xy, tri):
    """u (N, 2) of the P1 interpolant on the cracked mesh: each vertex valued from a triangle that
    uses it (a − copy from below the crack)."""
    side = np.zeros(len(xy))
    cy = xy[tri].mean(axis=1)[:, 1]
    for k in range(3):
        side[tri[:, k]] = np.sign(cy)
    x, y = xy[:, 0].copy(), xy[:, 1].copy()
    y[(y == 0.0) & (side < 0)] = -0.0
    return np.column_stack([sdexpr.to_numpy(exact[c])(x, y) for c in ("ux", "uy")])


def nodal_measure(xy, pairs):
    c = xy[pairs[:, 0]]
    ell = np.hypot(*(c[1:] - c[:-1]).T)
    m = np.zeros(len(pairs))
    m[:-1] += 0.5 * ell
    m[1:] += 0.5 * ell
    return m


def reference_outputs(exact, xy, tri, pairs, closed):
    """(u, crack (I, 4)) of a reference whose solution is the interpolant; `closed` (I,) bool the
    rows it reports active (their force m_j · p(x_j), p = −σ_yy of the exact field)."""
    u = interpolant(exact, xy, tri)
    j = u[pairs[:, 0]] - u[pairs[:, 1]]
    crack = np.zeros((len(pairs), 4))
    crack[:, 0], crack[:, 1] = j[:, 1], j[:, 0]  # ν = (0, 1), τ = ν turned by −90° = (1, 0)
    c = xy[pairs[:, 0]]
    p = -sdexpr.to_numpy(exact["syy"])(c[:, 0], np.full(len(c), 0.0))
    crack[:, 2] = np.where(closed, nodal_measure(xy, pairs) * p, 0.0)
    crack[:, 3] = closed.astype(float)
    crack[-1] = 0.0  # the tip
    return u, crack


def write_results(out, exact=None, levels=(0, 1, 2), n0=4, tools=("dolfinx", "freefem"),
                  name="williams", perturb=None, closed=None, damage=None):
    """A results folder OUT/ of the Williams edge crack (or `exact`), every reference solving to
    the interpolant. perturb(xy) -> (N, 2) is added to every reference's u; closed(level, xy, pairs)
    -> (I,) bool the active flags (default none); damage(tool, level, u, crack) may change a
    reference's arrays in place."""
    out = Path(out)
    exact = exact or williams(1.0, 0.0)
    out.mkdir(parents=True, exist_ok=True)
    write_export(out / "mesh", name, exact, levels, n0)
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
            n = n0 * 2 ** level
            xy, tri, pairs = cracked_level(n)
            flags = (closed(level, xy, pairs) if closed else np.zeros(len(pairs), dtype=bool))
            u, crack = reference_outputs(exact, xy, tri, pairs, flags)
            if perturb is not None:
                u = u + perturb(xy)
                j = u[pairs[:, 0]] - u[pairs[:, 1]]
                crack[:, 0], crack[:, 1] = j[:, 1], j[:, 0]
                crack[-1] = 0.0
            if damage is not None:
                damage(tool, level, u, crack)
            np.savetxt(d / f"u_level{level}.txt", u, fmt="%.17g")
            np.savetxt(d / f"crack_level{level}.txt", crack, fmt="%.17g")
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
