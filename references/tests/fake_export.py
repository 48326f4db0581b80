"""A tiny stand-in for `sdcrack mesh SCENE --out DIR` (for the reference tests only).

Structured mesh of [-1,1]² with n×n cells split by SW–NE diagonals, crack on y = 0 for
-0.5 ≤ x ≤ 0.5 (normal (0, 1)), n = n0·2^level (n0 divisible by 4).
"""

import json
from pathlib import Path

import numpy as np


def structured_level(n):
    s = np.linspace(-1.0, 1.0, n + 1)
    X, Y = np.meshgrid(s, s, indexing="xy")  # vertex k = j*(n+1) + i
    xy = np.column_stack([X.ravel(), Y.ravel()])
    tris = []
    for j in range(n):
        for i in range(n):
            v00, v10 = j * (n + 1) + i, j * (n + 1) + i + 1
            v01, v11 = v00 + n + 1, v10 + n + 1
            tris += [(v00, v10, v11), (v00, v11, v01)]
    return xy, np.array(tris, dtype=np.int64)


def write_level(d, n):
    xy_u, tri_u = structured_level(n)
    nu = len(xy_u)
    on_crack = (np.abs(xy_u[:, 1]) < 1e-14) & (xy_u[:, 0] > -0.5 - 1e-14) & (xy_u[:, 0] < 0.5 + 1e-14)
    crack_nodes = np.flatnonzero(on_crack)
    crack_nodes = crack_nodes[np.argsort(xy_u[crack_nodes, 0])]  # tip a (-0.5) → tip b (0.5)
    interior = crack_nodes[1:-1]
    copy = {int(v): nu + k for k, v in enumerate(interior)}
    xy = np.vstack([xy_u, xy_u[interior]])
    tri = tri_u.copy()
    sides = np.zeros(len(tri), dtype=int)
    cy = xy_u[tri_u].mean(axis=1)[:, 1]
    for t in range(len(tri)):
        touches = [v for v in tri_u[t] if int(v) in copy]
        if touches:
            sides[t] = 1 if cy[t] > 0 else -1
            if cy[t] < 0:
                tri[t] = [copy.get(int(v), int(v)) for v in tri_u[t]]
    crack = [(int(v), copy.get(int(v), int(v))) for v in crack_nodes]
    bnd = np.flatnonzero((np.abs(np.abs(xy_u[:, 0]) - 1) < 1e-14) | (np.abs(np.abs(xy_u[:, 1]) - 1) < 1e-14))
    d.mkdir(parents=True, exist_ok=True)
    np.savetxt(d / "vertices_uncut.txt", xy_u, fmt="%.17g")
    np.savetxt(d / "triangles_uncut.txt", tri_u, fmt="%d")
    np.savetxt(d / "vertices.txt", xy, fmt="%.17g")
    np.savetxt(d / "triangles.txt", tri, fmt="%d")
    np.savetxt(d / "crack.txt", np.array(crack), fmt="%d")
    np.savetxt(d / "boundary.txt", bnd, fmt="%d")
    np.savetxt(d / "sides.txt", sides, fmt="%d")
    meta = {"level": None, "h": 2.0 / n, "n_vertices": len(xy), "n_uncut_vertices": nu,
            "n_triangles": len(tri), "normal": [0.0, 1.0]}
    return meta


def write_fake_export(out, name, f, g, exact=None, levels=(0, 1, 2), n0=8):
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for level in levels:
        d = out / f"level{level}"
        meta = write_level(d, n0 * 2 ** level)
        meta["level"] = level
        (d / "mesh.json").write_text(json.dumps(meta))
    scene = {"name": name, "f": f, "g": g, "exact": exact,
             "crack": {"a": [-0.5, 0.0], "b": [0.5, 0.0], "normal": [0.0, 1.0]}, "levels": list(levels)}
    (out / "scene.json").write_text(json.dumps(scene, indent=2))
    return out
