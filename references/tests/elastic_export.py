"""A stand-in for `sdcrack mesh SCENE --out DIR` on an ELASTIC scene (docs/elasticity.md), for the
reference and compare tests only: structured grids of a rectangle (n×n cells split by SW–NE
diagonals, n = n0·2^level) cut along one or more polyline cracks, which may be edge cracks (an end
on ∂Ω: a mouth, its vertex doubled, both copies on ∂Ω).

    problem = material(E=1.0, nu=0.3)                    # or material(lam=1.0, mu=1.0, plane="stress")
    elastic_export(out, name, problem, f=["0", "0"], g=[gx, gy],
                   tractions={"right": [tx, ty]}, fixed=[{"point": [1, -0.5], "components": ["x"]}],
                   exact={"ux", "uy", "sxx", "syy", "sxy", ["opening", "slip", "pressure", "sif"]},
                   levels=(0, 1, 2), n0=8, domain=((-1, -1), (1, 1)), crack=((-1.0, 0.0), (0.0, 0.0)))

`crack` is one polyline (a list of points) or a list of polylines; every segment must follow grid
lines or SW–NE cell diagonals, and every point must be a grid vertex on every level. Writes:

    scene.json     "name", "problem" (material()'s dict), "f" [fx, fy], "g" [gx, gy] or null,
                   "tractions" {part: [tx, ty]}, "fixed" [...], "exact" (ux, uy, sxx, syy, sxy given;
                   opening, slip, pressure, sif null unless given) or null, "domain" {"min", "max"},
                   "cracks" [{"points"}] (and the legacy "crack" {"a", "b", "normal"} for one crack of
                   one segment), "cells" [n0, n0], "mesh_size" null, "levels".
    level{L}/      vertices_uncut.txt, triangles_uncut.txt, vertices.txt, triangles.txt (the cracked
                   mesh: the − copy of every doubled node numbered after the uncut vertices, in
                   crack.txt's row order, taken by the triangles on its − side), crack.txt (plus minus;
                   a tip plus == minus, an interior node or a mouth plus != minus), cracks.txt
                   (first n tip_first tip_last), crack_normals.txt (sdexport's nodal rule; a mouth or
                   a tip: its one segment's normal), sides.txt (per corner ±1 at a doubled node, i.e.
                   an interior crack node or a mouth, 0 elsewhere), boundary.txt (every cracked-mesh
                   vertex on ∂Ω, both copies of a mouth included, ascending), boundary_edges.txt
                   (v0 v1 part per edge of ∂Ω in cracked-mesh vertices, counter-clockwise around Ω:
                   the edges at a mouth on their own face; crack faces are not listed; part indexes
                   mesh.json's "boundary_parts" = ["left", "right", "bottom", "top"]), mesh.json
                   ("level", "kind": "structured", "coarse_triangles", "nx", "ny", "h" (the longest
                   edge), the counts, "n_cracks", "boundary_parts", and "normal" for one crack of one
                   segment).

A mouth must not be a corner of Ω (its face sectors are the half-planes of the crack's line).
Standard library and numpy only.
"""

import json
from pathlib import Path

import numpy as np

from fake_export import _on_plus_side, chain_on_polyline, polyline_normals

RECTANGLE_PARTS = ["left", "right", "bottom", "top"]
ON_BOUNDARY = 1e-12  # a point is on a side of the rectangle when that close (grid points are exact)


def material(E=None, nu=None, lam=None, mu=None, plane="strain"):
    """scene.json's "problem" dict (docs/elasticity.md) of (E, ν) or (λ, μ): the 3-D constants and the
    in-plane ones of crates/sdcrack-core/src/elasticity.rs (Material), written out independently."""
    if (E is None) == (lam is None) or (E is None) != (nu is None) or (lam is None) != (mu is None):
        raise ValueError("give exactly one of (E, nu) and (lam, mu)")
    if E is not None:
        lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    nu = lam / (2 * (lam + mu))
    E = 2 * mu * (1 + nu)
    if plane == "strain":
        lam_in, kolosov, e_prime = lam, 3 - 4 * nu, E / (1 - nu * nu)
    elif plane == "stress":
        lam_in, kolosov, e_prime = 2 * lam * mu / (lam + 2 * mu), (3 - nu) / (1 + nu), E
    else:
        raise ValueError(f"plane must be 'strain' or 'stress', not {plane!r}")
    return {"kind": "elasticity", "plane": plane, "E": E, "nu": nu, "lambda": lam, "mu": mu,
            "lambda_in_plane": lam_in, "kolosov": kolosov, "e_prime": e_prime}


def rectangle_grid(domain, n):
    """(xy, tri) of the n×n grid of the rectangle domain = ((x0, y0), (x1, y1)), vertex j(n+1) + i,
    each cell split by its SW–NE diagonal into two counter-clockwise triangles."""
    (x0, y0), (x1, y1) = domain
    X, Y = np.meshgrid(np.linspace(x0, x1, n + 1), np.linspace(y0, y1, n + 1), indexing="xy")
    xy = np.column_stack([X.ravel(), Y.ravel()])
    j, i = (a.ravel() for a in np.meshgrid(np.arange(n), np.arange(n), indexing="ij"))
    v00 = j * (n + 1) + i
    v10, v01, v11 = v00 + 1, v00 + n + 1, v00 + n + 2
    tri = np.stack([np.column_stack([v00, v10, v11]), np.column_stack([v00, v11, v01])], axis=1)
    return xy, tri.reshape(-1, 3).astype(np.int64)


def boundary_part(p, domain):
    """The index in RECTANGLE_PARTS of the side holding point p (an edge's midpoint), else None."""
    (x0, y0), (x1, y1) = domain
    for k, (c, v) in enumerate(((0, x0), (0, x1), (1, y0), (1, y1))):
        if abs(p[c] - v) <= ON_BOUNDARY:
            return k
    return None


def cut_elastic(xy_u, tri_u, chains, domain):
    """The cracked mesh along the vertex chains: every crack node but the tips doubled (a mouth, an
    end on ∂Ω, included). Returns xy, tri, crack rows (plus, minus), ranges [(first, n, tip_first,
    tip_last)], normals (I, 2), sides (T, 3)."""
    nu = len(xy_u)
    rows, ranges, normals, copy_of = [], [], [], {}
    sides = np.zeros(tri_u.shape, dtype=np.int64)
    centroids = xy_u[tri_u].mean(axis=1)
    for chain in chains:
        last = len(chain) - 1
        is_tip = [boundary_part(xy_u[chain[k]], domain) is None for k in (0, last)]
        ranges.append((len(rows), len(chain), int(is_tip[0]), int(is_tip[1])))
        normals.append(polyline_normals(xy_u[chain]))
        for k, v in enumerate(chain):
            if (k == 0 and is_tip[0]) or (k == last and is_tip[1]):
                rows.append((v, v))
                continue
            if v in copy_of:
                raise ValueError(f"crack node {xy_u[v]} is on two cracks")
            copy_of[v] = nu + len(copy_of)
            rows.append((v, copy_of[v]))
            p = xy_u[v]
            # a mouth's missing neighbour: the crack's line continued out of Ω
            prev = xy_u[chain[k - 1]] if k > 0 else 2 * p - xy_u[chain[1]]
            nxt = xy_u[chain[k + 1]] if k < last else 2 * p - xy_u[chain[last - 1]]
            for t, corner in zip(*np.nonzero(tri_u == v)):
                sides[t, corner] = 1 if _on_plus_side(p, prev, nxt, centroids[t]) else -1
    tri = np.where(sides == -1, np.vectorize(lambda v: copy_of.get(int(v), int(v)))(tri_u), tri_u)
    xy = np.vstack([xy_u, xy_u[list(copy_of)]]) if copy_of else xy_u.copy()
    return xy, tri.astype(np.int64), np.array(rows, dtype=np.int64), ranges, np.vstack(normals), sides


def boundary_edges(xy, tri, domain):
    """(E, 3) rows v0 v1 part: the edges of the cracked mesh on ∂Ω, each in its one triangle's
    counter-clockwise order (so Ω lies to the left), sorted by part then position."""
    local = tri[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    rows = []
    for a, b in local:
        part = boundary_part((xy[a] + xy[b]) / 2, domain)
        if part is not None:
            rows.append((int(a), int(b), part))
    rows.sort(key=lambda r: (r[2], *np.round((xy[r[0]] + xy[r[1]]) / 2, 12)))
    return np.array(rows, dtype=np.int64)


def write_elastic_level(d, xy_u, tri_u, polylines, domain, meta):
    """Writes level folder d; `meta`: mesh.json's keys other than the counts. Returns mesh.json."""
    chains = [chain_on_polyline(xy_u, tri_u, p) for p in polylines]
    xy, tri, crack, ranges, normals, sides = cut_elastic(xy_u, tri_u, chains, domain)
    edges = boundary_edges(xy, tri, domain)
    bnd = np.unique(edges[:, :2])
    d.mkdir(parents=True, exist_ok=True)
    for name, data, fmt in (("vertices_uncut", xy_u, "%.17g"), ("triangles_uncut", tri_u, "%d"),
                            ("vertices", xy, "%.17g"), ("triangles", tri, "%d"), ("crack", crack, "%d"),
                            ("cracks", np.array(ranges), "%d"), ("crack_normals", normals, "%.17g"),
                            ("boundary", bnd, "%d"), ("boundary_edges", edges, "%d"), ("sides", sides, "%d")):
        np.savetxt(d / f"{name}.txt", data, fmt=fmt)
    e = xy_u[tri_u] - xy_u[tri_u[:, [1, 2, 0]]]
    meta = dict(meta, h=float(np.hypot(e[..., 0], e[..., 1]).max()), n_vertices=len(xy),
                n_uncut_vertices=len(xy_u), n_triangles=len(tri), n_cracks=len(polylines),
                boundary_parts=list(RECTANGLE_PARTS))
    if len(polylines) == 1 and len(polylines[0]) == 2:
        meta["normal"] = normals[0].tolist()
    (d / "mesh.json").write_text(json.dumps(meta))
    return meta


def _polylines(crack):
    """`crack` as a list of polylines (it may be one polyline: a list of points)."""
    crack = [list(c) for c in crack]
    if np.ndim(crack[0]) == 1:  # one polyline of points
        crack = [crack]
    return [[tuple(map(float, p)) for p in c] for c in crack]


def exact_block(exact):
    """scene.json's "exact": ux, uy, sxx, syy, sxy required (the stand-in has no symbolic Hooke's
    law: the caller writes the stress out), opening, slip, pressure, sif null unless given."""
    if exact is None:
        return None
    missing = [k for k in ("ux", "uy", "sxx", "syy", "sxy") if k not in exact]
    if missing:
        raise ValueError(f"exact needs {', '.join(missing)}")
    unknown = set(exact) - {"ux", "uy", "sxx", "syy", "sxy", "opening", "slip", "pressure", "sif"}
    if unknown:
        raise ValueError(f"unknown exact keys {sorted(unknown)}")
    return {k: exact.get(k) for k in ("ux", "uy", "sxx", "syy", "sxy", "opening", "slip", "pressure", "sif")}


def elastic_export(out, name, problem, f, g=None, tractions=None, fixed=None, exact=None, levels=(0, 1, 2),
                   n0=8, domain=((-1.0, -1.0), (1.0, 1.0)), crack=((-1.0, 0.0), (0.0, 0.0))):
    """The export folder `out` of an elastic scene (module documentation); returns Path(out)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    domain = tuple(tuple(map(float, p)) for p in domain)
    polylines = _polylines(crack)
    tractions = dict(tractions or {})
    bad = set(tractions) - set(RECTANGLE_PARTS)
    if bad:
        raise ValueError(f"unknown boundary parts {sorted(bad)}")
    for level in levels:
        n = n0 * 2 ** level
        xy_u, tri_u = rectangle_grid(domain, n)
        meta = {"level": level, "kind": "structured", "coarse_triangles": 2 * n0 * n0, "nx": n, "ny": n}
        write_elastic_level(out / f"level{level}", xy_u, tri_u, polylines, domain, meta)
    scene = {"name": name, "problem": dict(problem), "f": list(f), "g": None if g is None else list(g),
             "tractions": {k: list(v) for k, v in tractions.items()}, "fixed": list(fixed or []),
             "exact": exact_block(exact),
             "domain": {"min": list(domain[0]), "max": list(domain[1])},
             "cracks": [{"points": [list(p) for p in c]} for c in polylines],
             "cells": [n0, n0], "mesh_size": None, "levels": list(levels)}
    if len(polylines) == 1 and len(polylines[0]) == 2:
        a, b = (np.asarray(p, float) for p in polylines[0])
        scene["crack"] = {"a": a.tolist(), "b": b.tolist(), "normal": polyline_normals([a, b])[0].tolist()}
    (out / "scene.json").write_text(json.dumps(scene, indent=2))
    return out
