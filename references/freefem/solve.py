#!/usr/bin/env python3
"""FreeFEM reference solver for the reference problem of docs/design.md.

Usage: solve.py MESH_EXPORT_DIR --out OUT [--fields] [--freefem FreeFem++] [--keep-work] [--overwrite]

Reads a mesh export of `sdcrack mesh SCENE --out DIR` (its crack files crack.txt, cracks.txt,
crack_normals.txt, sides.txt and mesh.json's kind read and checked by compare/sdshared/sdexport.py,
which documents them: any number of polyline cracks; an export without cracks.txt has one crack),
runs FreeFem++ on crack_qp.edp once per level (P1 on the cracked mesh, u = g on Γ, nodal jump
constraints u⁺ − u⁻ ≥ 0 at the interior nodes of every crack, primal–dual active set), and writes
OUT/summary.json and OUT/u_level{L}.txt (u at the cracked vertices, %.17g).

Quadrature, shared with the dolfinx reference so that both solve the same discrete problem to round-off:
the load ∫ f φ_i with compare/sdshared/sdquad.py's rule (symmetric Xiao–Gimbutas, degree 16, 55 interior
points; written into run.edp as loadRuleTable and declared there as a QF2 of the qf11to25 plugin), the
stiffness with qf1pT (exact for P1); u = g by the P1 interpolant at the boundary vertices (no integral of
g). With qf9pT for the load (and dolfinx's degree 8) the two references differed by 2.9e-7 on mixed with
cells [4, 4] at level 0; now by round-off (references/freefem/README.md).

summary.json: {"scene", "tool": "freefem", "provenance", "cases": [{"level", "h", "unknowns", "iterations",
"active", "kkt", "status", "errors" (exact scenes only), "timings_s": {"freefem", "total"}}]}:
  provenance: {"tool": "freefem", "tool_version" (from FreeFem++'s banner, freefem_version; "unknown"
    with a warning if unreadable), "python", "numpy", "date_utc", "command_line" (sys.argv), "cores",
    "threads" (the BLAS/OpenMP thread variables it ran with, null where unset)}
    (compare/sdshared/sdresults.py: provenance);
  kkt: {"equations", "primal", "dual", "complementarity"}, relative, computed by crack_qp.edp:
    the componentwise backward error max_i |K u − F − Bᵀλ|_i / (|K||u| + |Bᵀλ| + |F|)_i over the free
    rows, max(0, −min w) / (2‖u‖∞), max(0, −min λ) / ‖λ‖∞, max |λ_j w_j| / (‖λ‖∞ 2‖u‖∞) (w = u⁺ − u⁻);
  status: "converged" when the active set reached its fixed point and every KKT residual is
    ≤ KKT_TOLERANCE = 1e-10 (the Rust solver's), else "not_converged: <reasons>" (e.g. "not_converged:
    active set did not converge in 100 solves", "not_converged: complementarity 3.0e-04 > 1e-10");
    the results are still written and the exit status is 3;
  errors: with an exact solution in the scene, computed on the cracked mesh with numpy (exact_errors:
    collapsed Gauss rules, geometric grading toward the tips of every crack, converged to < 1e-9
    relative) u_l2 = ‖u_h − u‖_{L²(Ω_c)},  p_l2 = ‖∇u_h − ∇u‖_{L²(Ω_c)},  lambda_l2 = ‖[u_h] − [u]‖_{L²(Γc)}
    (over the segments within each crack), ∇u from exact.px/py, else sdexpr's symbolic derivative of
    exact.u; [u] from exact.jump, else u on each face of a segment by the signed-zero rule of
    eval_on_face (crates/sdcrack-core/src/problem.rs) with the segment's normal.
An export whose scene.json has a "problem" (kind "elasticity", docs/elasticity.md) is solved by the
elastic path instead, elasticity.py + elastic_qp.edp (elasticity_module), with the outputs of
docs/elasticity.md; a scene without one takes this scalar path, unchanged.
With --fields also OUT/fields.h5 and, per level, OUT/fields/level{L}.xdmf (u, p) + level{L}.crack.xdmf
(`jump` = u⁺ − u⁻ and `contact_force` = the nodal multipliers λ_j, 0 off the active set and at the
tips; compare/sdshared/sdfields.py, README's field table).
OUT is written atomically (a temporary folder, then one rename); an existing OUT is an error unless
--overwrite is given. Every failure is one line on stderr: exit status 2 for an invalid scene
(scene.json malformed, an expression outside the grammar of compare/sdshared/sdexpr.py: no scene
text is ever evaluated as code), 1 for any other failure.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
EDP_BODY = HERE / "crack_qp.edp"
FF_LOADPATH_DEFAULT = "/usr/lib/freefem++"
APT_HINT = "apt-get install -y freefem++ libfreefem++"

# The references' shared modules: the package sdshared (compare/sdshared/; see its __init__.py)
from sdshared import sdexport  # the crack layout of the export (crack.txt, cracks.txt, crack_normals.txt)
from sdshared import sdexpr  # the shared translator: parse, to_freefem, to_numpy, derivative
from sdshared import sdquad  # the load quadrature shared with the dolfinx reference
from sdshared import sdresults  # (standard library only)
from sdshared import sdfields  # the field files (fields.h5, XDMF) and p = ∇u_h at the vertices

MAX_ITERATIONS = 100      # linear solves of the active-set method (crack_qp.edp)
KKT_TOLERANCE = sdresults.KKT_TOLERANCE
NORM_DEGREE = 10          # collapsed Gauss rule on triangles away from the crack tips (as crates/sdcrack-core/src/norms.rs)
NORM_NEAR_DEGREE = 20     # ... within NORM_NEAR_RADIUS diameters of a tip, on graded pieces and segments
NORM_NEAR_RADIUS = 4.0
NORM_TIP_DEPTH = 32       # splits toward each crack tip (triangles with a tip vertex, tip segments)


class SolveError(Exception):
    """A failure reported as one line (exit status 1)."""


class SceneError(SolveError):
    """An invalid scene (scene.json unreadable or malformed, an expression outside the grammar):
    exit status 2, as `sdcrack` for an invalid scene."""


# ---- expressions ---------------------------------------------------------------------------------

def parse(key, src):
    try:
        return sdexpr.parse(src)
    except sdexpr.ExprError as e:
        raise SceneError(f"scene expression {key} = {src!r}: column {e.column}: {e.message}") from None


def to_freefem(key, src):
    return sdexpr.to_freefem(parse(key, src))


def to_numpy(key, src_or_tree):
    """A callable fn(x, y) -> ndarray for an expression (source text or sdexpr tree)."""
    tree = parse(key, src_or_tree) if isinstance(src_or_tree, str) else src_or_tree
    return sdexpr.to_numpy(tree)


# ---- reading the export --------------------------------------------------------------------------

def _load(path, dtype, cols):
    try:
        a = np.loadtxt(path, dtype=dtype, ndmin=2)
    except OSError:
        raise SolveError(f"missing file {path}")
    except ValueError as e:
        raise SolveError(f"cannot read {path}: {e}")
    if a.size == 0:
        a = a.reshape(0, cols)
    if a.shape[1] != cols:
        raise SolveError(f"{path}: expected {cols} columns, found {a.shape[1]}")
    return a


def read_level(export, level, default_normal=None, mouths=False):
    """One level of the export: {"meta" (mesh.json), "kind", "xy_uncut", "tri_uncut", "xy", "tri",
    "crack" (crack.txt), "layout" (sdexport.CrackLayout: cracks, tips, segments, nodal normals),
    "boundary"}; `default_normal`: the scene's single normal, for an export without
    crack_normals.txt (else mesh.json's "normal", else the normals computed from the nodes);
    `mouths`: an elastic export, whose boundary.txt holds both copies of a mouth."""
    d = Path(export) / f"level{level}"
    if not d.is_dir():
        raise SolveError(f"missing level folder {d}")
    if not (d / "mesh.json").exists():
        raise SolveError(f"missing file {d / 'mesh.json'}")
    try:
        meta = sdexport.read_mesh_json(d)
        lv = {
            "meta": meta,
            "kind": sdexport.read_kind(meta, d / "mesh.json"),
            "xy_uncut": _load(d / "vertices_uncut.txt", float, 2),
            "tri_uncut": _load(d / "triangles_uncut.txt", np.int64, 3),
            "xy": _load(d / "vertices.txt", float, 2),
            "tri": _load(d / "triangles.txt", np.int64, 3),
            "boundary": _load(d / "boundary.txt", np.int64, 1)[:, 0],
        }
        normal = default_normal if default_normal is not None else meta.get("normal")
        lv["layout"] = sdexport.read_layout(d, lv["xy"], len(lv["xy"]), normal)
        sdexport.read_sides(d / "sides.txt", lv["tri"], lv["layout"])  # checked, not needed
    except sdexport.ExportError as e:
        raise SolveError(str(e)) from None
    lv["crack"] = lv["layout"].pairs
    nu, n = len(lv["xy_uncut"]), len(lv["xy"])
    if lv["tri"].shape != lv["tri_uncut"].shape:
        raise SolveError(f"{d}: cracked and uncut meshes have different triangle counts")
    if not np.array_equal(lv["xy"][:nu], lv["xy_uncut"]):
        raise SolveError(f"{d}: the first n_uncut cracked vertices differ from the uncut vertices")
    if lv["tri"].min() < 0 or lv["tri"].max() >= n or lv["tri_uncut"].max() >= nu:
        raise SolveError(f"{d}: triangle vertex index out of range")
    if len(lv["boundary"]) and lv["boundary"].max() >= (n if mouths else nu):
        raise SolveError(f"{d}: boundary vertex is a crack copy")
    return lv


# ---- FreeFEM input -------------------------------------------------------------------------------

def regions_and_maps(lv):
    """The FreeFEM regions of the uncut triangles and their vertex maps: (region (T,) in 1..R,
    maps (R, n_uncut)), maps[r − 1][i] the cracked vertex that stands for uncut vertex i in the
    triangles of region r (i itself where they do not use it). Region 1: the triangles that use no − copy (map:
    the identity). The others go, in triangle order, to the first region ≥ 2 whose map agrees with
    theirs at their three corners: one region 2 unless a triangle uses the − copy of one crack node
    and the + copy of another that has a − copy (two cracks one element apart)."""
    tri, tri_u = lv["tri"], lv["tri_uncut"]
    nu = len(lv["xy_uncut"])
    for p, m in lv["crack"]:
        if p != m and not (0 <= p < nu <= m < len(lv["xy"])):
            raise SolveError(f"bad crack pair {p} {m}")
    region = np.ones(len(tri), dtype=np.int64)
    maps = [np.arange(nu)]
    assigned = []  # per region ≥ 2: {uncut vertex: cracked vertex} of its triangles
    for t in np.flatnonzero((tri != tri_u).any(axis=1)):
        corners = list(zip(tri_u[t].tolist(), tri[t].tolist()))
        r = next((k for k, m in enumerate(assigned) if all(m.get(i, j) == j for i, j in corners)), None)
        if r is None:
            r = len(assigned)
            assigned.append({})
        assigned[r].update(corners)
        region[t] = r + 2
    for m in assigned:
        vmap = np.arange(nu)
        vmap[list(m)] = list(m.values())
        maps.append(vmap)
    return region, np.array(maps)


def boundary_edges(tri):
    e = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    uniq, count = np.unique(e, axis=0, return_counts=True)
    return uniq[count == 1]


def write_msh(path, xy, tri, region):
    be = boundary_edges(tri)
    on_b = np.zeros(len(xy), dtype=int)
    on_b[be.ravel()] = 1
    with open(path, "w") as f:
        f.write(f"{len(xy)} {len(tri)} {len(be)}\n")
        for (x, y), lab in zip(xy, on_b):
            f.write(f"{x:.17g} {y:.17g} {lab}\n")
        for (a, b, c), r in zip(tri + 1, region):
            f.write(f"{a} {b} {c} {r}\n")
        for a, b in be + 1:
            f.write(f"{a} {b} 1\n")


def load_rule_edp():
    """FreeFEM declarations of the shared load rule (sdquad.load_rule): its degree and the QF2 table,
    rows [weight, x̂, ŷ] with the weights doubled to sum 1 (FreeFEM's convention; exact in binary),
    %.17g (FreeFEM reads them back bit for bit)."""
    pts, wts = sdquad.load_rule()
    rows = ",\n    ".join(f"[{2.0 * w:.17g}, {x:.17g}, {y:.17g}]" for w, (x, y) in zip(wts, pts))
    return (f"int loadRuleDegree = {int(sdquad.LOAD_DEGREE)};\n"
            f"real[int,int] loadRuleTable = [\n    {rows}];\n")


def freefem_binary(name):
    exe = shutil.which(name)
    if exe is None:
        raise SolveError(f"FreeFem++ not found ('{name}'); install it with: {APT_HINT}")
    return exe


def freefem_env():
    env = dict(os.environ)
    env.setdefault("FF_LOADPATH", FF_LOADPATH_DEFAULT)
    return env


def freefem_version(exe):
    """The version in FreeFem++'s banner: run without arguments it prints
    "FreeFem++ - version 4.9 ( - git no git) 64bits" and its usage (exit status 1) -> "4.9".
    (Scripts see only the number `version`, a real: 4.10 would read 4.1.) "unknown", with a
    warning on stderr, when the banner cannot be read."""
    import re

    try:
        proc = subprocess.run([exe], stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, text=True, errors="replace", env=freefem_env(),
                              timeout=60)
        m = re.search(r"FreeFem\+\+\s+-?\s*v(?:ersion)?\s*([0-9][0-9A-Za-z.+~-]*)", proc.stdout)
    except (OSError, subprocess.SubprocessError) as e:
        m, why = None, f"{type(e).__name__}: {e}"
    else:
        why = f"no version in its banner {proc.stdout.strip().splitlines()[:1]}"
    if m is None:
        print(f"solve.py: warning: cannot read the FreeFem++ version of {exe} ({why}); "
              "provenance.tool_version = \"unknown\"", file=sys.stderr)
        return "unknown"
    return m.group(1).rstrip(".")


def run_level(exe, lv, f_ff, g_ff, work):
    xy_u, tri_u = lv["xy_uncut"], lv["tri_uncut"]
    n = len(lv["xy"])
    region, maps = regions_and_maps(lv)
    write_msh(work / "uncut.msh", xy_u, tri_u, region)
    with open(work / "region_maps.txt", "w") as fm:
        fm.write(f"{len(maps)}\n" + "".join(f"{v}\n" for v in maps.ravel()))
    pairs = lv["crack"][lv["layout"].interior()]
    with open(work / "pairs.txt", "w") as fp:
        fp.write(f"{len(pairs)}\n")
        for p, m in pairs:
            fp.write(f"{p} {m}\n")
    bnd = np.unique(lv["boundary"])
    with open(work / "dirichlet.txt", "w") as fb:
        fb.write(f"{len(bnd)}\n" + "".join(f"{i}\n" for i in bnd))
    if '"' in work.as_posix() or "\\" in work.as_posix():
        raise SolveError(f"unsupported characters in the output path {work}")
    header = (f"// generated by solve.py\nstring dir = \"{work.as_posix()}/\";\nint nCracked = {n};\n"
              f"int maxIterations = {int(MAX_ITERATIONS)};\nfunc f = {f_ff};\nfunc g = {g_ff};\n"
              + load_rule_edp())
    (work / "run.edp").write_text(header + EDP_BODY.read_text())
    t0 = time.perf_counter()
    proc = subprocess.run([exe, "-nw", "-ns", "-v", "0", str(work / "run.edp")], cwd=work, env=freefem_env(),
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    t_ff = time.perf_counter() - t0
    (work / "freefem.log").write_text(proc.stdout)
    if proc.returncode != 0 or not (work / "info.txt").exists():
        last = [l for l in proc.stdout.strip().splitlines() if l.strip()][-1:] or ["no output"]
        raise SolveError(f"FreeFem++ failed (exit {proc.returncode}): {last[0].strip()}")
    if "Error um" in proc.stdout:
        raise SolveError("FreeFem++: UMFPACK reported a singular or failed factorisation")
    check = np.loadtxt(work / "vertices_check.txt", ndmin=2)
    if check.shape != xy_u.shape or np.abs(check - xy_u).max() > 1e-12 * max(1.0, np.abs(xy_u).max()):
        raise SolveError("FreeFEM changed the vertex order of the uncut mesh")
    info = dict(l.split() for l in (work / "info.txt").read_text().splitlines() if l.strip())
    missing = [k for k in ("converged", "iterations", "active", *sdresults.KKT_KEYS) if k not in info]
    if missing:
        raise SolveError(f"FreeFem++ info.txt lacks {', '.join(missing)}")
    u = np.loadtxt(work / "u.txt", ndmin=1)
    if u.shape != (n,) or not np.all(np.isfinite(u)):
        raise SolveError("FreeFem++ returned a malformed or non-finite u")
    lam = np.loadtxt(work / "lambda.txt", ndmin=1) if len(pairs) else np.zeros(0)
    return u, lam, info, t_ff


# ---- errors against an exact solution ------------------------------------------------------------
#
# As crates/sdcrack-core/src/norms.rs, with more points: every triangle gets a collapsed (Duffy) Gauss rule, of degree
# NORM_NEAR_DEGREE where its centroid lies within NORM_NEAR_RADIUS of its diameters of a crack tip (there
# ∇u ~ r^(-1/2) is far from polynomial), of degree NORM_DEGREE elsewhere; a triangle having a tip as a
# vertex is split toward the tip NORM_TIP_DEPTH times (each split cuts it into its four midpoint
# children and splits the tip's corner child again: geometric grading, every piece with the near rule);
# crack segments ending at a tip are halved toward it as often, with Gauss–Legendre of the near degree
# on every piece. All points are interior: data are never evaluated on Γc. The defaults are converged:
# raising the degrees and the depth changes the norms by < 1e-9 relative
# (references/tests/test_freefem_reference.py), where degree 10 and depth 16 everywhere leave ~1e-7
# relative in the p error of an open crack.

REFERENCE_TRIANGLE = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])


def collapsed_rule(degree):
    """Collapsed Gauss rule on the reference triangle, exact for polynomials of `degree` (n² points,
    n = degree/2 + 1; all interior; weights sum 1/2): the rule of crates/sdcrack-core/src/fe/quadrature.rs."""
    g, w = sdquad.gauss01(degree // 2 + 1)
    a, b = np.meshgrid(g, g, indexing="ij")
    wa, wb = np.meshgrid(w, w, indexing="ij")
    return np.column_stack([a.ravel(), (b * (1 - a)).ravel()]), (wa * wb * (1 - a)).ravel()


def graded_pieces(corners, depth, tri=REFERENCE_TRIANGLE):
    """Sub-triangles of `tri` graded toward its vertices k with corners[k] true: split into the four
    midpoint children; a corner child at a graded vertex is split again, `depth` times in all
    (3·depth + 1 pieces for one graded corner, as graded_pieces in crates/sdcrack-core/src/norms.rs)."""
    if depth == 0 or not any(corners):
        return [tri]
    a, b, c = tri
    ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
    out = [np.array([ab, bc, ca])]
    for child, k in ((np.array([a, ab, ca]), 0), (np.array([ab, b, bc]), 1), (np.array([ca, bc, c]), 2)):
        mask = [False, False, False]
        mask[k] = bool(corners[k])
        out += graded_pieces(mask, depth - 1 if corners[k] else 0, child)
    return out


def graded_rule(corners, degree, depth):
    """Points (reference coordinates) and weights (sum 1/2) of the graded rule of one triangle."""
    xi, wt = collapsed_rule(degree)
    pts, wts = [], []
    for a, b, c in graded_pieces(corners, depth):
        e1, e2 = b - a, c - a
        pts.append(a + xi[:, :1] * e1 + xi[:, 1:] * e2)
        wts.append(wt * abs(e1[0] * e2[1] - e1[1] * e2[0]))
    return np.vstack(pts), np.concatenate(wts)


def graded_segment_rule(at_start, at_end, degree, depth):
    """Points s ∈ (0, 1) and weights (sum 1) on a segment, halved `depth` times toward a tip end."""
    cuts = {0.0, 1.0}
    if at_start:
        cuts |= {0.5 ** i for i in range(1, depth + 1)}
    if at_end:
        cuts |= {1.0 - 0.5 ** i for i in range(1, depth + 1)}
    cuts = np.array(sorted(cuts))
    g, w = sdquad.gauss01(degree // 2 + 1)
    s0, s1 = cuts[:-1, None], cuts[1:, None]
    return (s0 + g * (s1 - s0)).ravel(), (w * (s1 - s0)).ravel()


def exact_gradient(exact):
    """(∂u/∂x, ∂u/∂y) as numpy callables: the scene's px/py, else sdexpr's symbolic derivatives."""
    if exact.get("px") and exact.get("py"):
        return to_numpy("exact.px", exact["px"]), to_numpy("exact.py", exact["py"])
    tree = parse("exact.u", exact["u"])
    return (to_numpy("exact.u", sdexpr.derivative(tree, "x")),
            to_numpy("exact.u", sdexpr.derivative(tree, "y")))


def exact_errors(lv, u_h, exact, degree=NORM_DEGREE, near_degree=NORM_NEAR_DEGREE,
                 depth=NORM_TIP_DEPTH, near_radius=NORM_NEAR_RADIUS, chunk=1 << 20):
    """{"u_l2", "p_l2", "lambda_l2"} of the P1 field u_h (cracked-mesh vertices) against `exact`
    (the scene's dict of expressions): `degree` away from the tips, `near_degree` near them, on the
    graded pieces (`depth` splits) and on the cracks; `chunk` bounds the points evaluated at once."""
    xy, tri, layout = lv["xy"], lv["tri"], lv["layout"]
    u_ex = to_numpy("exact.u", exact["u"])
    px, py = exact_gradient(exact)
    tips = layout.tip_vertices()
    # rule of each triangle: 1..7 graded toward the tip vertices (bit k: local vertex k), 0 near, 8 far
    at_tip = np.isin(tri, tips)
    code = at_tip[:, 0] * 1 + at_tip[:, 1] * 2 + at_tip[:, 2] * 4
    corners = xy[tri]
    diam = np.max([np.linalg.norm(corners[:, k] - corners[:, (k + 1) % 3], axis=1) for k in range(3)], axis=0)
    dist = np.min([np.linalg.norm(corners.mean(axis=1) - xy[t], axis=1) for t in tips], axis=0)
    code[(code == 0) & (dist > near_radius * diam)] = 8
    su = sp = 0.0
    for group in np.unique(code):
        if group == 8:
            xi, wt = collapsed_rule(degree)
        else:
            xi, wt = graded_rule([bool(group >> k & 1) for k in range(3)], near_degree, depth)
        ids = np.flatnonzero(code == group)
        step = max(1, chunk // len(wt))
        for lo in range(0, len(ids), step):
            t = tri[ids[lo:lo + step]]
            p0, p1, p2 = xy[t[:, 0]], xy[t[:, 1]], xy[t[:, 2]]
            e1, e2 = p1 - p0, p2 - p0
            det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
            X = p0[:, 0, None] + e1[:, 0, None] * xi[:, 0] + e2[:, 0, None] * xi[:, 1]
            Y = p0[:, 1, None] + e1[:, 1, None] * xi[:, 0] + e2[:, 1, None] * xi[:, 1]
            ut = u_h[t]
            uq = ut[:, 0, None] * (1 - xi[:, 0] - xi[:, 1]) + ut[:, 1, None] * xi[:, 0] + ut[:, 2, None] * xi[:, 1]
            W = np.abs(det)[:, None] * wt
            su += float(np.sum(W * (uq - u_ex(X, Y)) ** 2))
            # ∇u_h per triangle: [e1; e2] ∇u = [u1 − u0; u2 − u0]
            d1, d2 = ut[:, 1] - ut[:, 0], ut[:, 2] - ut[:, 0]
            gx = (d1 * e2[:, 1] - d2 * e1[:, 1]) / det
            gy = (-d1 * e2[:, 0] + d2 * e1[:, 0]) / det
            sp += float(np.sum(W * ((gx[:, None] - px(X, Y)) ** 2 + (gy[:, None] - py(X, Y)) ** 2)))
    sl = jump_error_sq(xy, layout, u_h, u_ex, exact, near_degree, depth)
    return {"u_l2": float(np.sqrt(su)), "p_l2": float(np.sqrt(sp)), "lambda_l2": float(np.sqrt(sl))}


def jump_error_sq(xy, layout, u_h, u_ex, exact, degree, depth):
    """‖[u_h] − [u]‖²_{L²(Γc)} over the segments within each crack (sdexport.CrackLayout; [u_h] = 0 at
    the tips): Gauss–Legendre of `degree` on pieces halved `depth` times toward a tip end. [u] is
    exact.jump, else u on each face of the segment (sdexpr.on_face with the segment's normal)."""
    cr = layout.pairs
    jump_h = u_h[cr[:, 0]] - u_h[cr[:, 1]]
    u_jump = to_numpy("exact.jump", exact["jump"]) if exact.get("jump") else None
    return sdexport.jump_error_sq(
        layout, xy, jump_h, lambda tip_a, tip_b: graded_segment_rule(tip_a, tip_b, degree, depth),
        u_jump, u_ex)


# ---- driver --------------------------------------------------------------------------------------

def elasticity_module():
    """elasticity.py beside this file, the elastic path (imported by its path: solve.py runs as a
    script, and the tests load it by path under names of their own)."""
    import importlib.util

    name = "freefem_elasticity"
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, HERE / "elasticity.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        sys.modules[name] = module
    return sys.modules[name]


def solve(export, out, freefem="FreeFem++", keep_work=False, overwrite=False, fields=False):
    export, out = Path(export), Path(out)
    exe = freefem_binary(freefem)
    scene_path = export / "scene.json"
    if not scene_path.exists():
        raise SolveError(f"missing {scene_path} (expected an `sdcrack mesh SCENE --out DIR` export)")
    try:
        scene = json.loads(scene_path.read_text())
    except (ValueError, TypeError) as e:
        raise SceneError(f"{scene_path}: malformed scene ({e})")
    if isinstance(scene, dict) and scene.get("problem") is not None:  # docs/elasticity.md
        return elasticity_module().solve(sys.modules[__name__], export, out, scene, scene_path, exe, keep_work,
                                overwrite, fields)
    try:
        name, f_src, g_src = scene["name"], scene["f"], scene["g"]
        levels, exact = scene["levels"], scene.get("exact")
        sdexport.scene_cracks(scene, scene_path)  # "cracks", or the old single "crack"
        normal = sdexport.scene_normal(scene)
    except sdexport.ExportError as e:
        raise SceneError(str(e))
    except (ValueError, KeyError, TypeError) as e:
        raise SceneError(f"{scene_path}: malformed scene ({e})")
    if out.exists() and not overwrite:
        raise SolveError(f"{out} exists; refusing to overwrite earlier results (use --overwrite)")
    f_ff, g_ff = to_freefem("f", f_src), to_freefem("g", g_src)
    if exact:
        if not isinstance(exact, dict) or not exact.get("u"):
            raise SceneError(f"{scene_path}: exact without 'u'")
        for key in ("u", "px", "py", "jump"):  # report a bad expression before any solve
            if exact.get(key):
                parse(f"exact.{key}", exact[key])
    version = freefem_version(exe)
    with sdresults.staged_folder(out) as tmp:
        cases, fields_data = [], []
        for level in levels:
            t0 = time.perf_counter()
            lv = read_level(export, level, normal)
            work = tmp / f"work_level{level}"
            work.mkdir()
            u, lam, info, t_ff = run_level(exe, lv, f_ff, g_ff, work)
            case = {
                "level": level,
                "h": lv["meta"]["h"],
                "unknowns": int(len(u)),
                "iterations": int(info["iterations"]),
                "active": int(info["active"]),
                "kkt": {k: float(info[k]) + 0.0 for k in sdresults.KKT_KEYS},
            }
            failure = (None if info["converged"] == "1" else
                       f"active set did not converge in {int(info['iterations'])} solves")
            case["status"] = sdresults.case_status(case["kkt"], KKT_TOLERANCE, failure)
            with open(tmp / f"u_level{level}.txt", "w") as fu:
                fu.write("".join(f"{v:.17g}\n" for v in u))
            if exact:
                case["errors"] = exact_errors(lv, u, exact)
            case["timings_s"] = {"freefem": t_ff, "total": time.perf_counter() - t0}
            cases.append(case)
            if fields:  # contact forces (the multipliers) at the crack nodes (crack.txt's rows; 0 at the tips)
                crack = lv["crack"]
                lam_nodes = np.zeros(len(crack))
                lam_nodes[lv["layout"].interior()] = lam
                fields_data.append((level, {
                    "xy": lv["xy"], "tri": lv["tri"], "crack": crack, "segments": lv["layout"].segments(),
                    "h": lv["meta"]["h"],
                    "point": {"u": u, "p": sdfields.vertex_gradient(lv["xy"], lv["tri"], u)},
                    "crack_fields": {"jump": u[crack[:, 0]] - u[crack[:, 1]], "contact_force": lam_nodes}}))
            if not keep_work:
                shutil.rmtree(work)
        if fields:
            try:
                import h5py  # noqa: F401  (sdfields.write_fields writes with it)
            except ImportError as e:
                raise SolveError(f"--fields needs h5py: apt-get install -y python3-h5py ({e})")
            sdfields.write_fields(tmp, fields_data, "freefem")
        summary = sdresults.write_summary(tmp, name, "freefem", cases, tool_version=version)
    return summary


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("export", help="folder written by `sdcrack mesh SCENE --out DIR`")
    ap.add_argument("--out", required=True, help="result folder (summary.json, u_level{L}.txt)")
    ap.add_argument("--freefem", default="FreeFem++", help="FreeFem++ executable")
    ap.add_argument("--keep-work", action="store_true", help="keep FreeFEM inputs/logs in OUT")
    ap.add_argument("--overwrite", action="store_true", help="replace an existing OUT")
    ap.add_argument("--fields", action="store_true", help="also write fields.h5 + fields/level{L}[.crack].xdmf")
    a = ap.parse_args(argv)
    try:
        # absolute paths: FreeFEM runs with its work folder as the current directory
        s = solve(Path(a.export).resolve(), Path(a.out).resolve(), a.freefem, a.keep_work, a.overwrite, a.fields)
    except SolveError as e:
        msg = str(e).replace("\n", " ")
        print(f"solve.py: error: {msg}", file=sys.stderr)
        return 2 if isinstance(e, SceneError) else 1
    except Exception as e:  # noqa: BLE001 — one line at the edge
        msg = str(e).replace("\n", " ")
        print(f"solve.py: error: {type(e).__name__}: {msg}", file=sys.stderr)
        return 1
    for c in s["cases"]:
        err = c.get("errors", {})
        print(f"level {c['level']}: h={c['h']:.4g} unknowns={c['unknowns']} iterations={c['iterations']} "
              + " ".join(f"{k}={v:.3e}" for k, v in err.items()) + f" status={c['status']}")
    return sdresults.exit_status(s["cases"], "solve.py: ")


if __name__ == "__main__":
    sys.exit(main())
