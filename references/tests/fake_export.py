"""A tiny stand-in for `sdcrack mesh SCENE --out DIR` (for the reference and compare tests only).

write_fake_export: the export format before polyline cracks (no cracks.txt, crack_normals.txt; one side
per triangle): structured mesh of [-1,1]² with n×n cells split by SW–NE diagonals, crack on y = 0 for
-0.5 ≤ x ≤ 0.5 (normal (0, 1)), n = n0·2^level (n0 divisible by 4).

kinked_export, two_cracks_export, refined_export: the polyline-crack format (polyline cracks, several
cracks, uniformly refined meshes; see the section below and compare/sdshared/sdexport.py).
polyline_l2_sq: the exact crack L² norm of a linear function on such a polyline.
Standard library and numpy only.
"""

import json
import math
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


# The scenes' exact solutions both references' tests solve on a fake export (scene-grammar
# strings): the open straight crack y = 0, |x| < 1/2 (u = Im sqrt((z - 1/2)(z + 1/2)), harmonic,
# its jump OPEN_JUMP), and the smooth closed one (f = CLOSED_F = -Δ CLOSED_U).
OPEN_U = "sqrt(sqrt(((x-0.5)^2+y^2)*((x+0.5)^2+y^2)))*sin((atan2(y,x-0.5)+atan2(y,x+0.5))/2)"
OPEN_JUMP = "2*sqrt(0.25 - x^2)"
CLOSED_U = "sin(pi*x)*cos(pi*y) - y"
CLOSED_F = "2*pi^2*sin(pi*x)*cos(pi*y)"


# ---------------------------------------------------------------------------------------------
# The multi-crack export format: several polyline cracks, structured or uniformly refined meshes
# ---------------------------------------------------------------------------------------------
#
# write_export writes scene.json with "domain", "cracks" (and the legacy "crack" only for one crack
# of two points), and per level mesh.json with "kind", "coarse_triangles", "n_cracks",
# crack.txt / cracks.txt / crack_normals.txt for the cracks in scene order, and sides.txt with one
# value per triangle corner (compare/sdshared/sdexport.py documents the formats). The scenarios:
# kinked_export (a kink on a structured grid), two_cracks_export (that kink and a straight crack),
# refined_export (a perturbed coarse triangulation refined uniformly with the 4t + c numbering).

KINK = [(-0.5, -0.25), (0.0, -0.25), (0.25, 0.0)]           # along a grid line, then a SW–NE diagonal
STRAIGHT = [(-0.25, 0.5), (0.5, 0.5)]
REFINED_CRACK = [(-0.5, 0.0), (0.0, 0.1), (0.5, 0.0)]       # a kink at a moved grid vertex


def refine_uniformly(xy, tri):
    """One uniform refinement by edge midpoints: the vertices are kept (numbers unchanged), the edge
    midpoints follow; triangle 4t + c of the result lies in triangle t: c = 0, 1, 2 the child at corner
    0, 1, 2, c = 3 the middle child (all counter-clockwise when t is)."""
    edges = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    uniq, inv = np.unique(edges, axis=0, return_inverse=True)
    mid = len(xy) + inv.reshape(3, -1).T  # (T, 3): midpoints of edges 01, 12, 20
    xy2 = np.vstack([xy, (xy[uniq[:, 0]] + xy[uniq[:, 1]]) / 2])
    v0, v1, v2 = tri.T
    m01, m12, m20 = mid.T
    kids = np.stack([np.stack(k, axis=1) for k in ((v0, m01, m20), (m01, v1, m12), (m20, m12, v2),
                                                   (m01, m12, m20))], axis=1)  # (T, 4, 3)
    return xy2, kids.reshape(-1, 3)


def perturbed_coarse_mesh(n=4, fixed=REFINED_CRACK, seed=7):
    """A small unstructured triangulation of [-1, 1]²: an n×n grid whose interior vertices are moved at
    random (up to 0.15 h) and whose cells take a random diagonal; the vertices nearest the points of
    `fixed` are moved onto them exactly (the crack's polyline then follows grid edges)."""
    xy, _ = structured_level(n)
    rng = np.random.default_rng(seed)
    h = 2.0 / n
    interior = (np.abs(xy) < 1 - 1e-12).all(axis=1)
    xy[interior] += rng.uniform(-0.15 * h, 0.15 * h, size=(int(interior.sum()), 2))
    for p in fixed:
        xy[np.argmin(np.linalg.norm(xy - np.asarray(p), axis=1))] = p
    tris = []
    for j in range(n):
        for i in range(n):
            v00, v10 = j * (n + 1) + i, j * (n + 1) + i + 1
            v01, v11 = v00 + n + 1, v10 + n + 1
            if rng.random() < 0.5:
                tris += [(v00, v10, v11), (v00, v11, v01)]
            else:
                tris += [(v00, v10, v01), (v10, v11, v01)]
    return xy, np.array(tris, dtype=np.int64)


def chain_on_polyline(xy, tri, polyline):
    """The mesh vertices along a polyline, first point to last; consecutive ones must be mesh edges."""
    chain = []
    for a, b in zip(polyline[:-1], polyline[1:]):
        a, b = np.asarray(a, float), np.asarray(b, float)
        d = b - a
        s = (xy - a) @ d / (d @ d)
        off = np.abs((xy - a) @ np.array([-d[1], d[0]])) / np.linalg.norm(d)
        on = np.flatnonzero((off < 1e-12) & (s > -1e-12) & (s < 1 + 1e-12))
        on = on[np.argsort(s[on])]
        chain += list(on if not chain else on[1:])
    edges = {frozenset(e) for t in tri for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
    missing = [(p, q) for p, q in zip(chain[:-1], chain[1:]) if frozenset((p, q)) not in edges]
    assert len(chain) >= 2 and not missing, f"polyline {polyline} does not follow mesh edges: {missing}"
    return [int(v) for v in chain]


def polyline_normals(points):
    """Unit normal per node of one crack (sdexport's rule, written out here independently): segment
    normals are the directions turned by +90°, interior nodes the normalised length-weighted mean."""
    points = np.asarray(points, float)
    out = []
    for k in range(len(points)):
        acc = np.zeros(2)
        for a, b in ((k - 1, k), (k, k + 1)):
            if 0 <= a and b < len(points):
                dx, dy = points[b] - points[a]
                acc += (-dy, dx)  # ℓ ν of the segment
        out.append(acc / np.linalg.norm(acc))
    return np.array(out)


def _on_plus_side(p, prev, nxt, c):
    """True when point c lies in the + sector at crack node p (left of prev → p → next): the sector
    swept counter-clockwise from the direction of next to the direction of prev."""
    def angle(q):
        return np.arctan2(q[1] - p[1], q[0] - p[0])
    two_pi = 2 * np.pi
    start = angle(nxt)
    return 0 < (angle(c) - start) % two_pi < (angle(prev) - start) % two_pi


def cut_mesh(xy_u, tri_u, chains):
    """The cracked mesh of the uncut (xy_u, tri_u) along the vertex chains (one per crack): a − copy of
    every interior crack node, numbered after the uncut vertices in crack.txt's row order, taken by the
    triangles on its − side. Returns xy, tri, crack rows (plus, minus), ranges [(first, n)], normals,
    sides (T, 3)."""
    nu = len(xy_u)
    rows, ranges, normals, copy_of = [], [], [], {}
    sides = np.zeros(tri_u.shape, dtype=np.int64)
    centroids = xy_u[tri_u].mean(axis=1)
    for chain in chains:
        ranges.append((len(rows), len(chain)))
        normals.append(polyline_normals(xy_u[chain]))
        for k, v in enumerate(chain):
            if k in (0, len(chain) - 1):
                rows.append((v, v))
                continue
            copy_of[v] = nu + len(copy_of)
            rows.append((v, copy_of[v]))
            for t, corner in zip(*np.nonzero(tri_u == v)):
                plus = _on_plus_side(xy_u[v], xy_u[chain[k - 1]], xy_u[chain[k + 1]], centroids[t])
                sides[t, corner] = 1 if plus else -1
    tri = np.where(sides == -1, np.vectorize(lambda v: copy_of.get(int(v), int(v)))(tri_u), tri_u)
    xy = np.vstack([xy_u, xy_u[list(copy_of)]]) if copy_of else xy_u.copy()
    return xy, tri.astype(np.int64), np.array(rows, dtype=np.int64), ranges, np.vstack(normals), sides


def write_new_level(d, xy_u, tri_u, polylines, meta):
    """Writes one level of the new format into d (the cracks cut along `polylines`); `meta`: the
    mesh.json keys other than the counts. Returns the mesh.json dict."""
    chains = [chain_on_polyline(xy_u, tri_u, p) for p in polylines]
    xy, tri, crack, ranges, normals, sides = cut_mesh(xy_u, tri_u, chains)
    bnd = np.flatnonzero((np.abs(np.abs(xy_u) - 1) < 1e-14).any(axis=1))
    d.mkdir(parents=True, exist_ok=True)
    for name, data, fmt in (("vertices_uncut", xy_u, "%.17g"), ("triangles_uncut", tri_u, "%d"),
                            ("vertices", xy, "%.17g"), ("triangles", tri, "%d"), ("crack", crack, "%d"),
                            ("cracks", np.array(ranges), "%d"), ("crack_normals", normals, "%.17g"),
                            ("boundary", bnd, "%d"), ("sides", sides, "%d")):
        np.savetxt(d / f"{name}.txt", data, fmt=fmt)
    edges = xy_u[tri_u] - xy_u[tri_u[:, [1, 2, 0]]]
    meta = dict(meta, h=float(np.hypot(edges[..., 0], edges[..., 1]).max()), n_vertices=len(xy),
                n_uncut_vertices=len(xy_u), n_triangles=len(tri), n_cracks=len(polylines))
    if len(polylines) == 1 and len(polylines[0]) == 2:
        meta["normal"] = normals[0].tolist()
    (d / "mesh.json").write_text(json.dumps(meta))
    return meta


def write_export(out, name, f, g, exact, polylines, level_meshes, kind, levels, cells=None, mesh_size=None):
    """A new-format export of [-1, 1]² with the cracks `polylines` (lists of points, scene order);
    level_meshes(L) -> (xy_uncut, tri_uncut) of level L; kind "structured" with cells [n0, n0] (the
    grid of level L has n0·2^L cells a side) or "refined" with mesh_size."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    coarse = len(level_meshes(0)[1])
    for level in levels:
        xy_u, tri_u = level_meshes(level)
        n = None if kind == "refined" else cells[0] * 2 ** level
        meta = {"level": level, "kind": kind, "coarse_triangles": coarse, "nx": n, "ny": n}
        write_new_level(out / f"level{level}", xy_u, tri_u, polylines, meta)
    scene = {"name": name, "f": f, "g": g, "exact": exact, "domain": {"min": [-1.0, -1.0], "max": [1.0, 1.0]},
             "cracks": [{"points": [list(map(float, p)) for p in c]} for c in polylines],
             "cells": cells, "mesh_size": mesh_size, "levels": list(levels)}
    if len(polylines) == 1 and len(polylines[0]) == 2:
        a, b = (np.asarray(p, float) for p in polylines[0])
        scene["crack"] = {"a": a.tolist(), "b": b.tolist(), "normal": polyline_normals([a, b])[0].tolist()}
    (out / "scene.json").write_text(json.dumps(scene, indent=2))
    return out


def kinked_export(out, name, f, g, exact=None, levels=(0, 1, 2), n0=8, polylines=(KINK,)):
    """Structured n×n grids (n = n0·2^level, n0 divisible by 8) of [-1, 1]² with SW–NE diagonals and the
    kinked crack KINK (grid line, then a cell diagonal), or the cracks `polylines`."""
    return write_export(out, name, f, g, exact, [list(p) for p in polylines],
                        lambda L: structured_level(n0 * 2 ** L), "structured", levels, cells=[n0, n0])


def two_cracks_export(out, name, f, g, exact=None, levels=(0, 1, 2), n0=8):
    """kinked_export with two cracks: KINK, then the straight STRAIGHT."""
    return kinked_export(out, name, f, g, exact, levels, n0, polylines=(KINK, STRAIGHT))


def refined_levels(coarse, levels):
    """{L: (xy, tri)} of the uniform refinements of `coarse` (xy, tri) for L = 0..max(levels)."""
    meshes = {0: coarse}
    for L in range(1, max(levels) + 1):
        meshes[L] = refine_uniformly(*meshes[L - 1])
    return meshes


def refined_export(out, name, f, g, exact=None, levels=(0, 1, 2), n=4, seed=7):
    """The kind "refined": perturbed_coarse_mesh (n×n cells) with the kinked crack REFINED_CRACK,
    refined uniformly with the 4t + c numbering at every level."""
    meshes = refined_levels(perturbed_coarse_mesh(n, REFINED_CRACK, seed), levels)
    return write_export(out, name, f, g, exact, [REFINED_CRACK], meshes.__getitem__, "refined", levels,
                        mesh_size=2.0 / n)


def polyline_l2_sq(polyline, a0, ax, ay):
    """∫ (a0 + ax x + ay y)² over a polyline, a list of (x, y) vertices (exact: the integrand is
    quadratic along each segment); what the tests expect of the crack norms."""
    total = 0.0
    for p, q in zip(polyline[:-1], polyline[1:]):
        ga, gb = (a0 + ax * v[0] + ay * v[1] for v in (p, q))
        total += math.dist(p, q) * (ga * ga + ga * gb + gb * gb) / 3
    return total
