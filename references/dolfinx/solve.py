"""dolfinx 0.5.2 reference solver for the sdcrack reference problem (BRIEF §3).

Usage:  /usr/bin/python3 references/dolfinx/solve.py MESH_EXPORT_DIR --out OUT [--fields] [--overwrite]

Reads a folder written by `sdcrack mesh SCENE --out DIR` (scene.json, level{L}/{mesh.json, vertices.txt,
triangles.txt, crack.txt, boundary.txt, sides.txt}) and, per level, solves on the CRACKED mesh
(crack vertices except the tips duplicated; dolfinx just sees a mesh with a slit):

    continuous P1,  -Δu = f,  u = g strongly on Γ (g interpolated at the boundary vertices),
    u⁺_j − u⁻_j ≥ 0 at every interior crack node pair j,

i.e. the convex QP  min ½uᵀKu − Fᵀu.  K, F are assembled by dolfinx (f as a UFL expression of the scene
string, translated by references/common/sdexpr.py, quadrature degree 8).  Change of variables u = T v:
the + copy's unknown becomes the jump w_j = u⁺_j − u⁻_j, K' = TᵀKT, F' = TᵀF (scipy.sparse), bound
w ≥ 0.  Primal–dual active set (c = 1): A = {j : λ_j − w_j > tol}, λ = (K'v − F')_plus, w_A = 0, LU
solve of the rest (scipy SuperLU), until A repeats (tol = 1e-12 · max(1, ‖λ‖∞, ‖w‖∞); ≤ 100 solves).
λ_j are nodal forces ≈ −∫ φ_j ∂u/∂ν on Γc.

Writes OUT/summary.json ({"scene", "tool": "dolfinx", "cases": [{"level", "h", "unknowns" (P1 dofs of
the cracked mesh), "iterations" (linear solves), "active" (closed crack nodes), "kkt": {"equations"
(max |K'v − F'| on free non-constraint rows), "primal" (max(0, −min w)), "dual" (max(0, −min λ)),
"complementarity" (max |λ_j w_j|)}, "timings_s": {"assembly", "solve", "total"}, "errors" (exact scenes
only): {"u_l2", "p_l2" (‖∇u_h − ∇u‖, null if UFL cannot differentiate exact.u and no exact.px/py),
"lambda_l2" (‖[u_h] − [u]‖_{L²(Γc)}, [u] from exact.jump or from exact.u at y = ±0.0)}}]}),
OUT/u_level{L}.txt (u at the cracked vertices in the export's numbering, %.17g, for cross-checks with
the FreeFEM reference) and with --fields OUT/fields.xdmf + fields.h5 (one grid "level{L}" per level with
u, and u_exact when the scene has one).  OUT is written atomically (temporary folder, then rename); an
existing OUT is an error unless --overwrite.  Errors: one line on stderr, exit status 1.
"""

import argparse
import json
import logging
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "common"))
import sdexpr  # noqa: E402
import sdfields  # noqa: E402
import sdresults  # noqa: E402

ACTIVITY_TOL = 1e-12
MAX_ITER = 100
QUAD_DEGREE = 8


class SolveError(Exception):
    pass


# ---------------------------------------------------------------------------------------------
# Input
# ---------------------------------------------------------------------------------------------

def _load_txt(path, dtype, ncols=None):
    if not path.exists():
        raise SolveError(f"missing file {path}")
    try:
        a = np.loadtxt(path, dtype=dtype, ndmin=2 if ncols else 1)
    except ValueError as e:
        raise SolveError(f"cannot read {path}: {e}") from None
    if ncols and a.size == 0:
        a = a.reshape(0, ncols)
    if ncols and a.shape[1] != ncols:
        raise SolveError(f"{path}: expected {ncols} columns, found {a.shape[1]}")
    return a


def read_scene(export):
    p = export / "scene.json"
    if not p.exists():
        raise SolveError(f"{export} is not a mesh export (no scene.json)")
    try:
        scene = json.loads(p.read_text())
    except json.JSONDecodeError as e:
        raise SolveError(f"{p}: invalid JSON: {e}") from None
    for key in ("name", "f", "g", "crack", "levels"):
        if key not in scene:
            raise SolveError(f"{p}: missing key '{key}'")
    return scene


def read_level(export, level):
    d = export / f"level{level}"
    if not d.is_dir():
        raise SolveError(f"missing folder {d}")
    meta = json.loads((d / "mesh.json").read_text()) if (d / "mesh.json").exists() else {}
    xy = _load_txt(d / "vertices.txt", float, 2)
    tri = _load_txt(d / "triangles.txt", np.int64, 3)
    crack = _load_txt(d / "crack.txt", np.int64, 2)
    bnd = _load_txt(d / "boundary.txt", np.int64)
    sides = _load_txt(d / "sides.txt", np.int64) if (d / "sides.txt").exists() else None
    nv = len(xy)
    for name, arr in (("triangles", tri), ("crack", crack), ("boundary", bnd)):
        if arr.size and (arr.min() < 0 or arr.max() >= nv):
            raise SolveError(f"{d}/{name}.txt: vertex index out of range 0..{nv - 1}")
    if meta.get("n_vertices", nv) != nv or meta.get("n_triangles", len(tri)) != len(tri):
        raise SolveError(f"{d}/mesh.json: counts do not match vertices.txt/triangles.txt")
    if len(crack) < 2:
        raise SolveError(f"{d}/crack.txt: a crack needs at least its two tips")
    if crack[0, 0] != crack[0, 1] or crack[-1, 0] != crack[-1, 1]:
        raise SolveError(f"{d}/crack.txt: the tips (first and last rows) must have plus == minus")
    return {"dir": d, "meta": meta, "xy": xy, "tri": tri, "crack": crack, "bnd": bnd, "sides": sides}


def parse_expr(scene, key, src):
    try:
        return sdexpr.parse(src)
    except sdexpr.ExprError as e:
        raise SolveError(f"scene expression {key} = {src!r}: column {e.column}: {e.message}") from None


def side_points(xy, side, normal):
    """Coordinates at which a vertex belongs to face `side` (+1/-1/0) of the crack.

    On a crack lying on y = 0 the side is selected by the sign of zero (y = ±0.0, understood by the
    numpy back-end: sign, atan2); elsewhere the point is pushed 1e-13 along ±normal."""
    x = xy[:, 0].copy()
    y = xy[:, 1].copy()
    on = side != 0
    zero = on & (y == 0.0) & (abs(normal[0]) < 1e-14)
    sgn = side * (1.0 if normal[1] >= 0 else -1.0)
    y[zero] = np.copysign(0.0, sgn[zero])
    other = on & ~zero
    x[other] += 1e-13 * side[other] * normal[0]
    y[other] += 1e-13 * side[other] * normal[1]
    return x, y


# ---------------------------------------------------------------------------------------------
# One level
# ---------------------------------------------------------------------------------------------

def solve_level(scene, lv, trees, want_fields):
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    import ufl
    from mpi4py import MPI
    from petsc4py import PETSc
    import dolfinx
    import dolfinx.fem.petsc  # noqa: F401

    t0 = time.perf_counter()
    xy, tri, crack, bnd = lv["xy"], lv["tri"], lv["crack"], lv["bnd"]
    nv = len(xy)
    normal = np.asarray(scene["crack"].get("normal", lv["meta"].get("normal", [0.0, 1.0])), float)

    # ---- mesh and dof map (create_mesh renumbers: go through input_global_indices) ----------
    domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.triangle, 1))
    mesh = dolfinx.mesh.create_mesh(MPI.COMM_SELF, tri, xy, domain)
    V = dolfinx.fem.FunctionSpace(mesh, ("Lagrange", 1))
    if V.dofmap.index_map.size_local != nv:
        raise SolveError(f"{lv['dir']}: dolfinx sees {V.dofmap.index_map.size_local} vertices, "
                         f"the export has {nv} (unused vertices?)")
    geom = mesh.geometry.dofmap.array.reshape(-1, 3)
    cdofs = V.dofmap.list.array.reshape(-1, 3)
    inp = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
    dof_of = np.full(nv, -1, dtype=np.int64)  # export vertex -> dolfinx dof
    dof_of[inp[geom.ravel()]] = cdofs.ravel()
    if (dof_of < 0).any() or len(np.unique(dof_of)) != nv:
        raise SolveError(f"{lv['dir']}: could not map vertices to dofs")
    if not np.allclose(V.tabulate_dof_coordinates()[dof_of, :2], xy, atol=1e-12):
        raise SolveError("internal error: dof coordinates do not match the export")

    # ---- assembly ----------------------------------------------------------------------------
    x = ufl.SpatialCoordinate(mesh)
    dx = ufl.dx(metadata={"quadrature_degree": QUAD_DEGREE})
    u_, v_ = ufl.TrialFunction(V), ufl.TestFunction(V)
    f_ufl = sdexpr.to_ufl(trees["f"], x)
    A = dolfinx.fem.petsc.assemble_matrix(dolfinx.fem.form(ufl.inner(ufl.grad(u_), ufl.grad(v_)) * dx))
    A.assemble()
    load = f_ufl * v_
    if isinstance(load, ufl.constantvalue.Zero):  # f = 0: UFL simplified the form away
        b = PETSc.Vec().createSeq(nv)
        b.set(0.0)
    else:
        b = dolfinx.fem.petsc.assemble_vector(dolfinx.fem.form(load * dx))
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    indptr, indices, data = A.getValuesCSR()
    Kd = sp.csr_matrix((data, indices, indptr), shape=A.getSize())
    Fd = b.getArray().copy()
    # to the export's numbering
    K = Kd[dof_of][:, dof_of].tocsr()
    F = Fd[dof_of]

    # ---- change of variables u = T v: the + copy carries the jump w = u+ - u- -----------------
    pairs = crack[1:-1]
    plus, minus = pairs[:, 0], pairs[:, 1]
    if (plus == minus).any():
        raise SolveError(f"{lv['dir']}/crack.txt: interior crack nodes must have two copies")
    T = (sp.identity(nv, format="csr")
         + sp.csr_matrix((np.ones(len(plus)), (plus, minus)), shape=(nv, nv))).tocsr()
    Kp = (T.T @ K @ T).tocsr()
    Fp = T.T @ F

    # ---- Dirichlet data ----------------------------------------------------------------------
    g = sdexpr.to_numpy(trees["g"])
    is_bnd = np.zeros(nv, bool)
    is_bnd[bnd] = True
    if is_bnd[plus].any() or is_bnd[minus].any():
        raise SolveError(f"{lv['dir']}: crack nodes on the boundary Γ")
    vvec = np.zeros(nv)
    vvec[bnd] = g(xy[bnd, 0], xy[bnd, 1])  # boundary vertices are not crack copies: no side issue
    if not np.isfinite(vvec).all():
        raise SolveError("g is not finite at some boundary vertex")
    t_asm = time.perf_counter() - t0

    # ---- primal-dual active set on w = v[plus] >= 0 ------------------------------------------
    t1 = time.perf_counter()
    free_base = ~is_bnd
    active = np.zeros(len(plus), bool)
    seen = set()
    iterations = 0
    converged = False
    rhs_base = Fp - Kp[:, bnd] @ vvec[bnd]
    while iterations < MAX_ITER:
        iterations += 1
        free = free_base.copy()
        free[plus[active]] = False
        vvec[plus[active]] = 0.0
        idx = np.flatnonzero(free)
        Kff = Kp[idx][:, idx].tocsc()
        vvec[idx] = spla.splu(Kff).solve(rhs_base[idx])
        lam = (Kp @ vvec - Fp)[plus]
        w = vvec[plus]
        scale = max(1.0, np.abs(lam).max(initial=0.0), np.abs(w).max(initial=0.0))
        new_active = (lam - w) > ACTIVITY_TOL * scale
        key = new_active.tobytes()
        if np.array_equal(new_active, active):
            converged = True
            break
        if key in seen:  # cycling: stop and report
            active = new_active
            break
        seen.add(active.tobytes())
        active = new_active
    if not converged:
        raise SolveError(f"{lv['dir']}: active set did not converge in {iterations} iterations")
    t_solve = time.perf_counter() - t1

    u = T @ vvec
    res = Kp @ vvec - Fp
    rows = free_base.copy()
    rows[plus] = False
    lam = res[plus]
    w = vvec[plus]
    kkt = {
        "equations": float(np.abs(res[rows]).max(initial=0.0)),
        "primal": float(max(0.0, -w.min(initial=0.0))),
        "dual": float(max(0.0, -lam.min(initial=0.0))),
        "complementarity": float(np.abs(lam * w).max(initial=0.0)),
    }

    uh = dolfinx.fem.Function(V, name="u")
    uh.x.array[dof_of] = u
    case = {
        "level": int(lv["level"]),
        "h": float(lv["meta"].get("h", np.nan)),
        "unknowns": int(nv),
        "iterations": int(iterations),
        "active": int(active.sum()),
        "kkt": kkt,
    }

    # ---- errors against the exact solution ---------------------------------------------------
    jump = u[crack[:, 0]] - u[crack[:, 1]]
    mult = np.zeros(len(crack))
    mult[1:-1] = lam
    fields = {"xy": xy, "tri": tri, "crack": crack, "u": u, "jump": jump, "multiplier": mult}
    if trees.get("exact_u") is not None:
        ue = sdexpr.to_ufl(trees["exact_u"], x)
        e_u = math.sqrt(abs(dolfinx.fem.assemble_scalar(dolfinx.fem.form((uh - ue) ** 2 * dx))))
        if trees.get("exact_px") is not None and trees.get("exact_py") is not None:
            grad_e = ufl.as_vector([sdexpr.to_ufl(trees["exact_px"], x), sdexpr.to_ufl(trees["exact_py"], x)])
        else:
            grad_e = ufl.grad(ue)
        try:
            e_p = math.sqrt(abs(dolfinx.fem.assemble_scalar(dolfinx.fem.form(
                ufl.inner(ufl.grad(uh) - grad_e, ufl.grad(uh) - grad_e) * dx))))
        except Exception:  # UFL cannot differentiate some expressions (min/max): no p error
            e_p = None
        e_l = jump_error(xy, crack, u, trees, normal)
        case["errors"] = {"u_l2": e_u, "p_l2": e_p, "lambda_l2": e_l}
        if want_fields:
            side = np.zeros(nv, np.int64)
            side[plus] = 1
            side[minus] = -1
            sx, sy = side_points(xy, side, normal)
            fields["u_exact"] = sdexpr.to_numpy(trees["exact_u"])(sx, sy)
    case["timings_s"] = {"assembly": t_asm, "solve": t_solve, "total": time.perf_counter() - t0}
    return case, u, fields


def jump_error(xy, crack, u, trees, normal):
    """‖[u_h] − [u]‖_{L²(Γc)}: [u_h] piecewise linear from the nodal jumps (0 at the tips)."""
    jh = u[crack[:, 0]] - u[crack[:, 1]]
    gx, gw = np.polynomial.legendre.leggauss(10)
    s = (gx + 1) / 2
    gw = gw / 2
    pa, pb = xy[crack[:-1, 0]], xy[crack[1:, 0]]
    L = np.linalg.norm(pb - pa, axis=1)
    P = pa[:, None, :] + s[None, :, None] * (pb - pa)[:, None, :]  # (segments, q, 2)
    jq = jh[:-1, None] * (1 - s)[None, :] + jh[1:, None] * s[None, :]
    X, Y = P[..., 0].ravel(), P[..., 1].ravel()
    if trees.get("exact_jump") is not None:
        je = sdexpr.to_numpy(trees["exact_jump"])(X, Y)
    else:
        fu = sdexpr.to_numpy(trees["exact_u"])
        one = np.ones_like(X)
        xp, yp = side_points(np.column_stack([X, Y]), one.astype(np.int64), normal)
        xm, ym = side_points(np.column_stack([X, Y]), -one.astype(np.int64), normal)
        je = fu(xp, yp) - fu(xm, ym)
    err2 = ((jq - je.reshape(jq.shape)) ** 2 * gw[None, :]).sum(axis=1) @ L
    return float(math.sqrt(err2))


# ---------------------------------------------------------------------------------------------
# Driver
# ---------------------------------------------------------------------------------------------

def run(export, out, fields=False, overwrite=False):
    export, out = Path(export), Path(out)
    scene = read_scene(export)
    trees = {"f": parse_expr(scene, "f", scene["f"]), "g": parse_expr(scene, "g", scene["g"])}
    exact = scene.get("exact") or None
    if exact is not None:
        if "u" not in exact:
            raise SolveError("scene.json: exact without 'u'")
        trees["exact_u"] = parse_expr(scene, "exact.u", exact["u"])
        for k in ("jump", "px", "py"):
            if exact.get(k):
                trees[f"exact_{k}"] = parse_expr(scene, f"exact.{k}", exact[k])
    levels = [read_level(export, L) | {"level": L} for L in scene["levels"]]
    if out.exists() and not overwrite:
        raise SolveError(f"{out} exists; refusing to overwrite earlier results (use --overwrite)")
    with sdresults.staged_folder(out) as tmp:
        cases, field_sets = [], []
        for lv in levels:
            case, u, fs = solve_level(scene, lv, trees, fields)
            cases.append(case)
            np.savetxt(tmp / f"u_level{case['level']}.txt", u, fmt="%.17g")
            if fields:
                point = {"u": fs["u"]}
                if "u_exact" in fs:
                    point["u_exact"] = fs["u_exact"]
                field_sets.append((case["level"], {
                    "xy": fs["xy"], "tri": fs["tri"], "crack": fs["crack"], "point": point,
                    "crack_fields": {"jump": fs["jump"], "multiplier": fs["multiplier"]}}))
        if fields:
            sdfields.write_fields(tmp, field_sets)
        summary = sdresults.write_summary(tmp, scene["name"], "dolfinx", cases)
    return summary


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("export", help="folder written by `sdcrack mesh SCENE --out DIR`")
    ap.add_argument("--out", required=True, help="result folder (summary.json, u_level{L}.txt)")
    ap.add_argument("--fields", action="store_true", help="also write fields.xdmf + fields.h5")
    ap.add_argument("--overwrite", action="store_true", help="replace an existing OUT")
    args = ap.parse_args(argv)
    logging.getLogger().setLevel(logging.WARNING)
    try:
        summary = run(args.export, args.out, fields=args.fields, overwrite=args.overwrite)
    except (SolveError, OSError, ValueError, KeyError) as e:
        msg = str(e).replace("\n", " ")
        print(f"error: {msg}", file=sys.stderr)
        return 1
    for c in summary["cases"]:
        err = c.get("errors", {})
        extra = "".join(f" {k}={v:.3e}" for k, v in err.items() if v is not None)
        print(f"level {c['level']}: unknowns={c['unknowns']} iterations={c['iterations']} "
              f"active={c['active']}{extra} total={c['timings_s']['total']:.2f}s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
