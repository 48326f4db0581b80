"""dolfinx 0.5.2 reference solver for the sdcrack reference problem (docs/design.md).

An export whose scene.json has a "problem" (an elastic scene, docs/elasticity.md) is solved by
references/dolfinx/elasticity.py (run_elastic; its documentation says how); everything below is
the scalar problem, the one solved when scene.json has no "problem".

Usage:  /usr/bin/python3 references/dolfinx/solve.py MESH_EXPORT_DIR --out OUT [--fields] [--overwrite]

`solve.py --check-install` runs the version check below alone (exit 0, or 2 with its one line): what
`sdcrack run` asks before solving anything.

Supported dolfinx: 0.5.x only (SUPPORTED_DOLFINX; the Debian 12 package python3-dolfinx, 0.5.2), whose
API this file uses. Before anything else main() imports the package `dolfinx` alone and reads its
__version__; any other version (or none importable) exits with status 2 and one line on stderr, e.g.
"dolfinx reference: dolfinx 0.6.0 is not supported (supported: 0.5.x, the Debian 12 package
python3-dolfinx)".

Reads a folder written by `sdcrack mesh SCENE --out DIR` (scene.json, level{L}/{mesh.json, vertices.txt,
triangles.txt, crack.txt, cracks.txt, crack_normals.txt, boundary.txt, sides.txt}; the crack files are
read and checked by compare/sdshared/sdexport.py, which documents them: any number of polyline
cracks, each with its two tips; an export without cracks.txt / crack_normals.txt has one crack and the
scene's single normal) and, per level, solves on the CRACKED mesh (crack vertices except the tips
duplicated; dolfinx just sees a mesh with slits):

    continuous P1,  -Δu = f,  u = g strongly on Γ (g interpolated at the boundary vertices),
    u⁺_j − u⁻_j ≥ 0 at every interior crack node pair j (of every crack),

i.e. the convex QP  min ½uᵀKu − Fᵀu.  K, F are assembled by dolfinx (f as a UFL expression of the scene
string, translated by compare/sdshared/sdexpr.py).  Quadrature, shared with the FreeFEM reference so that
both solve the same discrete problem to round-off: F with compare/sdshared/sdquad.py's rule (symmetric
Xiao–Gimbutas, degree 16, 55 interior points: f is never evaluated on the crack) as a UFL custom rule
(load_measure), K with the one-point rule (exact for P1); g enters only through its values at the
boundary vertices.  (With degree 8 here and qf9pT in FreeFEM the two differed by 2.9e-7 on mixed with
cells [4, 4] at level 0; see references/freefem/README.md.)  Change of variables u = T v:
the + copy's unknown becomes the jump w_j = u⁺_j − u⁻_j, K' = TᵀKT, F' = TᵀF (scipy.sparse), bound
w ≥ 0.  Primal–dual active set (c = 1): A = {j : λ_j − w_j > tol}, λ = (K'v − F')_plus, w_A = 0, LU
solve of the rest (scipy SuperLU), until A repeats (tol = 1e-12 · max(1, ‖λ‖∞, ‖w‖∞); ≤ 100 solves).
λ_j are nodal forces ≈ −∫ φ_j ∂u/∂ν on Γc.

Writes OUT/summary.json ({"scene", "tool": "dolfinx", "provenance", "cases": [{"level", "h", "unknowns"
(P1 dofs of the cracked mesh), "iterations" (linear solves), "active" (closed crack nodes), "kkt", "status",
"timings_s": {"assembly", "solve", "forms" (the UFL forms' JIT compilation, cached between
processes: a start-up cost, not part of assembly), "total"}, "errors" (exact scenes only)}]}):
  provenance: {"tool": "dolfinx", "tool_version" (dolfinx.__version__), "python", "numpy", "date_utc",
    "command_line" (sys.argv), "cores",
    "threads" (the BLAS/OpenMP thread variables it ran with, null where unset)} (compare/sdshared/sdresults.py: provenance);
  kkt: relative KKT residuals of the QP in the cracked unknowns (kkt_residuals; the definitions of
    crack_qp.edp, modelled on docs/design.md), with λ_j = (K u − F) at the + copy on the active set,
    0 off it, w = u⁺ − u⁻, B the jump operator (‖B‖∞ = 2):
    "equations": componentwise backward error max_i |K u − F − Bᵀλ|_i / (|K||u| + |Bᵀλ| + |F|)_i over
    the non-Dirichlet rows; "primal": max(0, −min w) / (2‖u‖∞); "dual": max(0, −min λ) / ‖λ‖∞;
    "complementarity": max |λ_j w_j| / (‖λ‖∞ 2‖u‖∞) (a zero scale counts as 1);
  status: "converged" when the active set reached its fixed point and every KKT residual is
    ≤ KKT_TOLERANCE = 1e-10 (the Rust solver's), else "not_converged: <reasons>" (e.g. "not_converged:
    active set did not converge in 100 solves" or "not_converged: complementarity 3.0e-04 > 1e-10");
    the results are still written and the exit status is 3;
  errors: {"u_l2" (‖u_h − u‖_{L²(Ω)}), "p_l2" (‖∇u_h − ∇u‖_{L²(Ω_c)}, ∇u from exact.px/py, else UFL's
    derivative of exact.u; null if UFL cannot differentiate it), "lambda_l2" (‖[u_h] − [u]‖_{L²(Γc)}
    over the segments of every crack, [u] from exact.jump, else, in numpy, exact.u on each face of a
    segment with the signed-zero rule of eval_on_face and the segment's normal)}: UFL forms with
    converged quadrature, graded toward the tips of every crack ("Errors against an exact solution"),
OUT/u_level{L}.txt (u at the cracked vertices in the export's numbering, %.17g, for cross-checks with
the FreeFEM reference) and with --fields OUT/fields.h5 + OUT/fields/level{L}.xdmf (the grid "level{L}"
with u, and u_exact when the scene has one: at a crack copy exact.u on its face, see side_points) +
OUT/fields/level{L}.crack.xdmf (the cracks as polylines, segments within each crack; the crack fields
`jump` = u⁺ − u⁻ and `contact_force` = the nodal multipliers λ_j, 0 off the active set and at the tips,
named as in every solver's files: compare/sdshared/sdfields.py, README's field table).  OUT is written atomically (temporary folder, then rename); an
existing OUT is an error unless --overwrite.  Errors: one line on stderr; exit status 2 for an
unsupported dolfinx and for an invalid scene (scene.json malformed, an expression outside the grammar
of compare/sdshared/sdexpr.py: no scene text is ever evaluated as code), 1 for any other failure.
"""

import argparse
import json
import logging
import math
import sys
import time
from pathlib import Path

import numpy as np

# The references' shared modules: the package sdshared (compare/sdshared/; see its __init__.py)
from sdshared import sdexport  # the crack layout of the export (crack.txt, cracks.txt, crack_normals.txt)
from sdshared import sdexpr
from sdshared import sdfields
from sdshared import sdquad  # the load quadrature shared with the FreeFEM reference
from sdshared import sdresults

# The dolfinx release series whose API this file uses (0.5.x: the Debian 12 package python3-dolfinx).
SUPPORTED_DOLFINX = "0.5"
ACTIVITY_TOL = 1e-12
MAX_ITER = 100
STIFFNESS_DEGREE = 0      # K: the P1 integrand is constant per cell, the one-point rule is exact
KKT_TOLERANCE = sdresults.KKT_TOLERANCE
NORM_DEGREE = 20          # error norms: basix's default rule on cells and crack facets without a tip
TIP_POINTS = 16           # error norms: Gauss points per direction of the tip rules (see tip_cell_rule)
# FFCx clamps table values within 1e-9 of 0 and 1e-6 (relative) of ±1 by default, which would move
# quadrature points lying close to a vertex: keep the tables as tabulated for the error forms and
# the load (whose points are the FreeFEM reference's, to be evaluated where FreeFEM evaluates f).
NORM_FFCX = {"table_rtol": 1e-15, "table_atol": 1e-300}


class SolveError(Exception):
    """A failure reported as one line (exit status 1)."""


class SceneError(SolveError):
    """An invalid scene (scene.json malformed, an expression outside the grammar): exit status 2,
    as `sdcrack` for an invalid scene."""


def dolfinx_version_problem():
    """None when the installed dolfinx is of the SUPPORTED_DOLFINX series, else the one-line reason.
    Imports the package `dolfinx` alone (for its __version__), nothing else from it."""
    supported = f"(supported: {SUPPORTED_DOLFINX}.x, the Debian 12 package python3-dolfinx)"
    try:
        import dolfinx
    except Exception as e:  # noqa: BLE001 — not installed, or a broken installation
        why = f"{type(e).__name__}: {e}".replace("\n", " ")
        return f"dolfinx reference: dolfinx cannot be imported ({why}) {supported}"
    version = str(getattr(dolfinx, "__version__", "(no __version__)"))
    if version == SUPPORTED_DOLFINX or version.startswith(SUPPORTED_DOLFINX + "."):
        return None
    return f"dolfinx reference: dolfinx {version} is not supported {supported}".replace("\n", " ")


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
        raise SceneError(f"{p}: invalid JSON: {e}") from None
    if not isinstance(scene, dict):
        raise SceneError(f"{p}: not a JSON object")
    for key in ("name", "f", "g", "levels"):
        if key not in scene:
            raise SceneError(f"{p}: missing key '{key}'")
    try:
        sdexport.scene_cracks(scene, p)  # "cracks", or the old single "crack"
    except sdexport.ExportError as e:
        raise SceneError(str(e)) from None
    return scene


def read_level(export, level, default_normal=None):
    """One level of the export: {"dir", "meta" (mesh.json), "kind", "xy", "tri", "crack" (crack.txt),
    "layout" (sdexport.CrackLayout: cracks, tips, segments, nodal normals), "bnd", "sides" ((T, 3) per
    corner, or None)}; `default_normal`: the scene's single normal, for an export without
    crack_normals.txt (else mesh.json's "normal", else the normals computed from the nodes)."""
    d = export / f"level{level}"
    if not d.is_dir():
        raise SolveError(f"missing folder {d}")
    try:
        meta = sdexport.read_mesh_json(d)
        kind = sdexport.read_kind(meta, d / "mesh.json")
        xy = _load_txt(d / "vertices.txt", float, 2)
        tri = _load_txt(d / "triangles.txt", np.int64, 3)
        bnd = _load_txt(d / "boundary.txt", np.int64)
        nv = len(xy)
        for name, arr in (("triangles", tri), ("boundary", bnd)):
            if arr.size and (arr.min() < 0 or arr.max() >= nv):
                raise SolveError(f"{d}/{name}.txt: vertex index out of range 0..{nv - 1}")
        if meta.get("n_vertices", nv) != nv or meta.get("n_triangles", len(tri)) != len(tri):
            raise SolveError(f"{d}/mesh.json: counts do not match vertices.txt/triangles.txt")
        normal = default_normal if default_normal is not None else meta.get("normal")
        layout = sdexport.read_layout(d, xy, nv, normal)
        sides = sdexport.read_sides(d / "sides.txt", tri, layout)
    except sdexport.ExportError as e:
        raise SolveError(str(e)) from None
    return {"dir": d, "meta": meta, "kind": kind, "xy": xy, "tri": tri, "crack": layout.pairs,
            "layout": layout, "bnd": bnd, "sides": sides}


def parse_expr(scene, key, src):
    try:
        return sdexpr.parse(src)
    except sdexpr.ExprError as e:
        raise SceneError(f"scene expression {key} = {src!r}: column {e.column}: {e.message}") from None


def side_points(xy, side, normal):
    """Coordinates at which each vertex belongs to face `side` (N,) (+1/-1, 0: no crack copy) of a
    crack, ν = normal (N, 2) at the vertex (its crack node's normal; rows with side 0 are unused).

    A node on the x axis (y = 0) whose ν is along the y axis gets y = ±0.0 with the sign of side·ν_y,
    one on the y axis (x = 0) whose ν is along the x axis x = ±0.0 with the sign of side·ν_x (the
    signed zero is understood by the numpy back-end: sign, atan2); any other node is pushed 1e-13
    along side·ν."""
    pts = xy[:, :2].astype(float)
    normal = np.asarray(normal, dtype=float)
    on = side != 0
    pushed = on.copy()
    for axis in (1, 0):  # y = 0 with ν ∥ y, then x = 0 with ν ∥ x
        zero = on & (pts[:, axis] == 0.0) & (np.abs(normal[:, 1 - axis]) < 1e-14)
        pts[zero, axis] = np.copysign(0.0, side[zero] * normal[zero, axis])
        pushed &= ~zero
    pts[pushed] += 1e-13 * side[pushed, None] * normal[pushed]
    return pts[:, 0], pts[:, 1]


# ---------------------------------------------------------------------------------------------
# One level
# ---------------------------------------------------------------------------------------------

def solve_level(scene, lv, trees, want_fields, quadrature=None):
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    import ufl
    from mpi4py import MPI
    from petsc4py import PETSc
    import dolfinx
    import dolfinx.fem.petsc  # noqa: F401

    t0 = time.perf_counter()
    xy, tri, crack, bnd, layout = lv["xy"], lv["tri"], lv["crack"], lv["bnd"], lv["layout"]
    nv = len(xy)

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
    dx_k = ufl.dx(metadata={"quadrature_degree": STIFFNESS_DEGREE})
    dx_f = load_measure()
    u_, v_ = ufl.TrialFunction(V), ufl.TestFunction(V)
    f_ufl = sdexpr.to_ufl(trees["f"], x)
    # form compilation (FFCx JIT, cached between processes) is timed apart: a start-up cost
    t_forms = time.perf_counter()
    a_form = dolfinx.fem.form(ufl.inner(ufl.grad(u_), ufl.grad(v_)) * dx_k)
    t_forms = time.perf_counter() - t_forms
    A = dolfinx.fem.petsc.assemble_matrix(a_form)
    A.assemble()
    load = f_ufl * v_
    if isinstance(load, ufl.constantvalue.Zero):  # f = 0: UFL simplified the form away
        b = PETSc.Vec().createSeq(nv)
        b.set(0.0)
    else:
        t = time.perf_counter()
        l_form = dolfinx.fem.form(load * dx_f, form_compiler_params=NORM_FFCX)
        t_forms += time.perf_counter() - t
        b = dolfinx.fem.petsc.assemble_vector(l_form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    indptr, indices, data = A.getValuesCSR()
    Kd = sp.csr_matrix((data, indices, indptr), shape=A.getSize())
    Fd = b.getArray().copy()
    # to the export's numbering
    K = Kd[dof_of][:, dof_of].tocsr()
    F = Fd[dof_of]

    # ---- change of variables u = T v: the + copy carries the jump w = u+ - u- -----------------
    interior = layout.interior()  # every crack's rows but its tips (sdexport checked plus != minus)
    pairs = crack[interior]
    plus, minus = pairs[:, 0], pairs[:, 1]
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
    t_asm = time.perf_counter() - t0 - t_forms

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
        if key in seen:  # cycling: stop (u is the solve of `active`) and report
            break
        seen.add(active.tobytes())
        active = new_active
    if converged:
        failure = None
    elif iterations >= MAX_ITER:
        failure = f"active set did not converge in {iterations} solves"
    else:
        failure = f"active set cycled after {iterations} solves"
    t_solve = time.perf_counter() - t1

    # ---- KKT residuals in the cracked unknowns u = T v (relative, as crack_qp.edp) ---------------
    u = T @ vvec
    kkt, lam = kkt_residuals(K, F, u, plus, minus, free_base, active)
    uh = dolfinx.fem.Function(V, name="u")
    uh.x.array[dof_of] = u
    case = {
        "level": int(lv["level"]),
        "h": float(lv["meta"].get("h", np.nan)),
        "unknowns": int(nv),
        "iterations": int(iterations),
        "active": int(active.sum()),
        "kkt": kkt,
        "status": sdresults.case_status(kkt, KKT_TOLERANCE, failure),
    }

    # ---- errors against the exact solution ---------------------------------------------------
    jump = u[crack[:, 0]] - u[crack[:, 1]]
    mult = np.zeros(len(crack))
    mult[interior] = lam
    fields = {"xy": xy, "tri": tri, "crack": crack, "segments": layout.segments(), "u": u, "jump": jump,
              "contact_force": mult}
    if trees.get("exact_u") is not None:
        case["errors"] = exact_errors(mesh, uh, dof_of, inp, xy, layout, jump, trees, quadrature)
        if want_fields:
            side = np.zeros(nv, np.int64)
            side[plus] = 1
            side[minus] = -1
            normal = np.zeros((nv, 2))
            normal[plus] = normal[minus] = layout.normals[interior]
            sx, sy = side_points(xy, side, normal)
            fields["u_exact"] = sdexpr.to_numpy(trees["exact_u"])(sx, sy)
    case["timings_s"] = {"assembly": t_asm, "solve": t_solve, "forms": t_forms,
                         "total": time.perf_counter() - t0}
    return case, u, fields


def load_measure():
    """The cell measure of the load form: sdquad.load_rule() as a custom rule (reference points,
    weights summing to 1/2), the FreeFEM reference's rule; assemble with NORM_FFCX (unclamped tables)."""
    import ufl

    points, weights = sdquad.load_rule()
    # lists, not arrays: UFL signs metadata with str() (see custom_measure)
    return ufl.dx(metadata={"quadrature_rule": "custom", "quadrature_points": points.tolist(),
                            "quadrature_weights": weights.tolist()})


def kkt_residuals(K, F, u, plus, minus, free, active):
    """Relative KKT residuals of the QP in the cracked unknowns (definitions of crack_qp.edp and
    docs/design.md) and the multipliers λ (0 off the active set, (Ku − F) at the + copy on it).

    equations: componentwise (Oettli–Prager) backward error of K u − F − Bᵀλ = 0 on the free
    (non-Dirichlet) rows, max_i |r_i| / (|K||u| + |Bᵀλ| + |F|)_i; primal: max(0, −min w) / (‖B‖∞‖u‖∞)
    with w = u⁺ − u⁻ and ‖B‖∞ = 2; dual: max(0, −min λ) / ‖λ‖∞; complementarity:
    max |λ_j w_j| / (‖λ‖∞ ‖B‖∞ ‖u‖∞); a zero scale is replaced by 1."""
    r = K @ u - F
    lam = np.where(active, r[plus], 0.0)
    bt_lam = np.zeros(len(u))
    np.add.at(bt_lam, plus, lam)
    np.add.at(bt_lam, minus, -lam)
    r = r - bt_lam
    scale = abs(K) @ np.abs(u) + np.abs(bt_lam) + np.abs(F)
    w = u[plus] - u[minus]
    u_scale = 2.0 * np.abs(u).max(initial=0.0) or 1.0
    return sdresults.kkt_measures(r[free], scale[free], w, lam, u_scale), lam


# ---------------------------------------------------------------------------------------------
# Errors against an exact solution
# ---------------------------------------------------------------------------------------------
#
# u_l2 and p_l2 are UFL forms assembled by dolfinx over the cracked mesh; lambda_l2 is a form over
# the facets of the cracks' + faces. Cells and crack facets without a tip get basix's default rule of
# degree NORM_DEGREE. Cells and facets having a crack tip (of any crack) as a vertex are tagged and get a custom
# rule built for the r^(1/2) singularity (tip_cell_rule, tip_facet_rule): the Duffy map collapsing
# the cell onto the tip (r ∝ ρ, Jacobian ∝ ρ), then ρ = σ², so that the integrands, which are
# expansions in powers of r^(1/2) times smooth functions of the angle, become smooth in (σ, t) and
# tensor Gauss rules converge exponentially. This is a different quadrature from the FreeFEM
# script's (geometric grading as in crates/sdcrack-core/src/norms.rs) and converges to the same integrals: raising
# NORM_DEGREE and TIP_POINTS changes the norms by < 1e-9 relative (test_dolfinx_reference.py).

REFERENCE_TRIANGLE = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])


def duffy_sqrt_rule(tri, k, n):
    """Rule on the triangle `tri` (3×2 reference coordinates) for integrands singular like r^(-1) at
    its vertex k: x = A + σ²((1 − t)(B − A) + t(C − A)), weight 2σ³·|det(B − A, C − A)| dσ dt."""
    a, b, c = tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]
    g, w = sdquad.gauss01(n)
    sig, t = (m.ravel() for m in np.meshgrid(g, g, indexing="ij"))
    ws, wt = (m.ravel() for m in np.meshgrid(w, w, indexing="ij"))
    rho = sig ** 2
    pts = a + rho[:, None] * ((1 - t)[:, None] * (b - a) + t[:, None] * (c - a))
    det = abs((b - a)[0] * (c - a)[1] - (b - a)[1] * (c - a)[0])
    return pts, 2 * sig ** 3 * ws * wt * det


def tip_cell_rule(corners, n, degree):
    """Reference points and weights (sum 1/2) for a cell whose local vertices k with corners[k] are
    crack tips. One tip: duffy_sqrt_rule toward it. Two or three (a crack of one segment, or tips of
    different cracks): the four midpoint children, each corner child at a tip with duffy_sqrt_rule,
    the others with basix's rule."""
    import basix

    if sum(map(bool, corners)) == 1:
        return duffy_sqrt_rule(REFERENCE_TRIANGLE, [bool(c) for c in corners].index(True), n)
    a, b, c = REFERENCE_TRIANGLE
    ab, bc, ca = (a + b) / 2, (b + c) / 2, (c + a) / 2
    base_p, base_w = basix.make_quadrature(basix.CellType.triangle, degree)
    pts, wts = [], []
    for k, child in enumerate([np.array([a, ab, ca]), np.array([ab, b, bc]), np.array([ca, bc, c]),
                               np.array([ab, bc, ca])]):
        if k < 3 and corners[k]:
            p, w = duffy_sqrt_rule(child, k, n)
        else:
            e1, e2 = child[1] - child[0], child[2] - child[0]
            p = child[0] + base_p[:, :1] * e1 + base_p[:, 1:] * e2
            w = base_w * abs(e1[0] * e2[1] - e1[1] * e2[0])
        pts.append(p)
        wts.append(w)
    return np.vstack(pts), np.concatenate(wts)


def tip_facet_rule(at_start, at_end, n):
    """Points s ∈ (0, 1) and weights (sum 1) on a crack segment with a tip at s = 0 and/or s = 1:
    s = σ² from the tip (weight 2σ dσ), so [u] ~ s^(1/2) becomes smooth in σ; both: each half."""
    g, w = sdquad.gauss01(n)
    if at_start and at_end:
        s0, w0 = tip_facet_rule(True, False, n)
        return np.concatenate([s0 / 2, 1 - s0 / 2]), np.concatenate([w0 / 2, w0 / 2])
    s, ws = g ** 2, 2 * g * w
    return (s, ws) if at_start else (1 - s, ws)


def custom_measure(measure, tag, points, weights):
    # lists, not arrays: UFL signs metadata with str(), which abbreviates long arrays
    md = {"quadrature_rule": "custom", "quadrature_points": np.asarray(points).tolist(),
          "quadrature_weights": np.asarray(weights).tolist()}
    return measure(int(tag), metadata=md)


def exact_errors(mesh, uh, dof_of, inp, xy, layout, jump_h, trees, quadrature=None):
    """{"u_l2", "p_l2", "lambda_l2"} of uh against the scene's exact solution (see above); layout: the
    level's sdexport.CrackLayout, jump_h the nodal jumps per row of crack.txt.
    quadrature: {"degree": NORM_DEGREE, "tip_points": TIP_POINTS} to override the defaults."""
    import ufl
    import dolfinx

    q = {"degree": NORM_DEGREE, "tip_points": TIP_POINTS, **(quadrature or {})}
    degree, n = int(q["degree"]), int(q["tip_points"])
    tips = layout.tip_vertices()
    cell_vertices = inp[mesh.geometry.dofmap.array.reshape(-1, 3)]  # export vertex per local vertex
    at_tip = np.isin(cell_vertices, tips)
    code = (at_tip[:, 0] * 1 + at_tip[:, 1] * 2 + at_tip[:, 2] * 4).astype(np.int32)
    cells = np.arange(len(code), dtype=np.int32)
    dxm = ufl.Measure("dx", domain=mesh, subdomain_data=dolfinx.mesh.meshtags(mesh, 2, cells, code))
    x = ufl.SpatialCoordinate(mesh)

    def integral(integrand):
        form = integrand * dxm(0, metadata={"quadrature_degree": degree})
        for mask in np.unique(code[code > 0]):
            pts, wts = tip_cell_rule([bool(mask >> k & 1) for k in range(3)], n, degree)
            form = form + integrand * custom_measure(dxm, mask, pts, wts)
        value = dolfinx.fem.assemble_scalar(dolfinx.fem.form(form, form_compiler_params=NORM_FFCX))
        return math.sqrt(max(value, 0.0))

    ue = sdexpr.to_ufl(trees["exact_u"], x)
    e_u = integral((uh - ue) ** 2)
    try:
        if trees.get("exact_px") is not None and trees.get("exact_py") is not None:
            grad_e = ufl.as_vector([sdexpr.to_ufl(trees["exact_px"], x), sdexpr.to_ufl(trees["exact_py"], x)])
        else:
            grad_e = ufl.grad(ue)
        e_p = integral(ufl.inner(ufl.grad(uh) - grad_e, ufl.grad(uh) - grad_e))
    except Exception:  # UFL cannot differentiate some expressions: no p error
        e_p = None
    one_segment = any(n_nodes == 2 for _, n_nodes in layout.ranges)
    if trees.get("exact_jump") is not None and not one_segment:
        e_l = jump_error_ufl(mesh, uh, dof_of, inp, layout, jump_h, trees["exact_jump"], degree, n)
    else:  # no exact.jump, or a crack of one segment (no slit in the mesh there)
        e_l = jump_error_numpy(xy, layout, jump_h, trees, degree, n)
    return {"u_l2": e_u, "p_l2": e_p, "lambda_l2": e_l}


def plus_facets(mesh, inp, layout):
    """The facets of the cracks' + faces: (facet index, segment k (a row of layout.segments()), ends)
    with ends[i] true when the facet's reference vertex i (basix: facet f of a triangle joins local
    vertices (1,2), (0,2), (0,1) for f = 0, 1, 2) is a crack tip."""
    import dolfinx

    tdim = 2
    mesh.topology.create_connectivity(tdim, tdim - 1)
    c2f = mesh.topology.connectivity(tdim, tdim - 1)
    chain = layout.pairs[:, 0]  # the + copies (a tip: its one vertex)
    segments = chain[layout.segments()]
    segment = {frozenset((int(a), int(b))): k for k, (a, b) in enumerate(segments)}
    tips = set(map(int, layout.tip_vertices()))
    cell_vertices = inp[mesh.geometry.dofmap.array.reshape(-1, 3)]
    on_chain = np.isin(cell_vertices, chain).sum(axis=1) >= 2
    found = {}
    for c in np.flatnonzero(on_chain):
        for f, (i, j) in enumerate(((1, 2), (0, 2), (0, 1))):
            a, b = int(cell_vertices[c, i]), int(cell_vertices[c, j])
            k = segment.get(frozenset((a, b)))
            if k is not None:
                found[k] = (int(c2f.links(c)[f]), k, (a in tips, b in tips), {a, b})
    mesh.topology.create_connectivity(tdim - 1, tdim)
    exterior = set(map(int, dolfinx.mesh.exterior_facet_indices(mesh.topology)))
    if len(found) != len(segments) or any(found[k][0] not in exterior for k in found):
        raise SolveError("internal error: the + faces of the cracks are not chains of boundary facets")
    # check the numbering assumed above: topology and geometry list a cell's vertices in the same
    # order, and the cell's facet f joins the vertices other than f
    mesh.topology.create_connectivity(tdim, 0)
    mesh.topology.create_connectivity(tdim - 1, 0)
    c2v = mesh.topology.connectivity(tdim, 0).array.reshape(-1, 3)
    node = np.empty(int(c2v.max()) + 1, dtype=np.int64)
    node[c2v] = mesh.geometry.dofmap.array.reshape(-1, 3)
    f2v = mesh.topology.connectivity(tdim - 1, 0)
    if not np.array_equal(inp[node[c2v]], cell_vertices) or any(
            set(map(int, inp[node[f2v.links(found[k][0])]])) != found[k][3] for k in found):
        raise SolveError("internal error: unexpected local vertex or facet numbering in dolfinx")
    return [found[k][:3] for k in sorted(found)]


def jump_error_ufl(mesh, uh, dof_of, inp, layout, jump_h, jump_tree, degree, n):
    """‖[u_h] − [u]‖_{L²(Γc)} as a form over the + face facets of every crack: [u_h] is the P1
    function J with the nodal jumps at the + copies (0 at the tips and everywhere else), [u] the
    scene's exact.jump."""
    import ufl
    import dolfinx

    facets = plus_facets(mesh, inp, layout)
    tags = np.array([1 + (1 if ends[0] else 0) + (2 if ends[1] else 0) for _, _, ends in facets], np.int32)
    ids = np.array([f for f, _, _ in facets], np.int32)
    order = np.argsort(ids)
    ft = dolfinx.mesh.meshtags(mesh, 1, ids[order], tags[order])
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    J = dolfinx.fem.Function(uh.function_space)
    J.x.array[:] = 0.0
    interior = layout.interior()
    J.x.array[dof_of[layout.pairs[interior, 0]]] = jump_h[interior]
    integrand = (J - sdexpr.to_ufl(jump_tree, ufl.SpatialCoordinate(mesh))) ** 2
    form = integrand * ds(1, metadata={"quadrature_degree": degree})
    for tag in np.unique(tags[tags > 1]):
        s, w = tip_facet_rule(bool((tag - 1) & 1), bool((tag - 1) & 2), n)
        form = form + integrand * custom_measure(ds, tag, s[:, None], w)
    value = dolfinx.fem.assemble_scalar(dolfinx.fem.form(form, form_compiler_params=NORM_FFCX))
    return math.sqrt(max(value, 0.0))


def jump_error_numpy(xy, layout, jump_h, trees, degree, n):
    """‖[u_h] − [u]‖_{L²(Γc)} in numpy over the segments of every crack, with the rules of
    jump_error_ufl (tip_facet_rule at a tip end, Gauss of `degree` elsewhere). Without exact.jump,
    [u] = u⁺ − u⁻ by on_face with the segment's normal (UFL has no signed zero to select a face)."""
    fj = sdexpr.to_numpy(trees["exact_jump"]) if trees.get("exact_jump") is not None else None
    fu = sdexpr.to_numpy(trees["exact_u"])
    g, gw = sdquad.gauss01(degree // 2 + 1)

    def rule(tip_a, tip_b):
        return tip_facet_rule(tip_a, tip_b, n) if tip_a or tip_b else (g, gw)

    return math.sqrt(sdexport.jump_error_sq(layout, xy, jump_h, rule, fj, fu))


# ---------------------------------------------------------------------------------------------
# Driver
# ---------------------------------------------------------------------------------------------

def run(export, out, fields=False, overwrite=False, quadrature=None):
    problem = dolfinx_version_problem()
    if problem is not None:
        raise SolveError(problem)
    import dolfinx

    export, out = Path(export), Path(out)
    scene = read_scene(export)
    if "problem" in scene:  # the elastic problem (docs/elasticity.md); absent: the scalar one
        return run_elastic(export, out, scene, fields, overwrite)
    trees = {"f": parse_expr(scene, "f", scene["f"]), "g": parse_expr(scene, "g", scene["g"])}
    exact = scene.get("exact") or None
    if exact is not None:
        if "u" not in exact:
            raise SceneError("scene.json: exact without 'u'")
        trees["exact_u"] = parse_expr(scene, "exact.u", exact["u"])
        for k in ("jump", "px", "py"):
            if exact.get(k):
                trees[f"exact_{k}"] = parse_expr(scene, f"exact.{k}", exact[k])
    normal = sdexport.scene_normal(scene)
    levels = [read_level(export, L, normal) | {"level": L} for L in scene["levels"]]
    if out.exists() and not overwrite:
        raise SolveError(f"{out} exists; refusing to overwrite earlier results (use --overwrite)")
    with sdresults.staged_folder(out) as tmp:
        cases, field_sets = [], []
        for lv in levels:
            case, u, fs = solve_level(scene, lv, trees, fields, quadrature)
            cases.append(case)
            np.savetxt(tmp / f"u_level{case['level']}.txt", u, fmt="%.17g")
            if fields:
                point = {"u": fs["u"], "p": sdfields.vertex_gradient(fs["xy"], fs["tri"], fs["u"])}
                if "u_exact" in fs:
                    point["u_exact"] = fs["u_exact"]
                field_sets.append((case["level"], {
                    "xy": fs["xy"], "tri": fs["tri"], "crack": fs["crack"], "segments": fs["segments"],
                    "point": point,
                    "h": case["h"] if math.isfinite(case["h"]) else None,
                    "crack_fields": {"jump": fs["jump"], "contact_force": fs["contact_force"]}}))
        if fields:
            sdfields.write_fields(tmp, field_sets, "dolfinx")
        summary = sdresults.write_summary(tmp, scene["name"], "dolfinx", cases, tool_version=dolfinx.__version__)
    return summary


def run_elastic(export, out, scene, fields, overwrite):
    """The elastic problem: references/dolfinx/elasticity.py (loaded from this file's folder, which
    need not be on sys.path), given the pieces of this file it shares with the scalar problem: the
    face rule of the Dirichlet data (side_points), the load rule (load_measure) and the active set's
    and KKT's constants. Its errors become SceneError (an invalid scene: exit 2) or SolveError."""
    import importlib.util
    import types

    import dolfinx

    spec = importlib.util.spec_from_file_location("sdcrack_dolfinx_elasticity",
                                                  Path(__file__).resolve().with_name("elasticity.py"))
    elastic = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(elastic)
    shared = types.SimpleNamespace(
        side_points=side_points, load_measure=load_measure, NORM_FFCX=NORM_FFCX,
        STIFFNESS_DEGREE=STIFFNESS_DEGREE, ACTIVITY_TOL=ACTIVITY_TOL, MAX_ITER=MAX_ITER,
        KKT_TOLERANCE=KKT_TOLERANCE, tool_version=dolfinx.__version__)
    try:
        return elastic.run(export, out, scene, fields, overwrite, shared)
    except elastic.InvalidInput as e:
        raise SceneError(str(e)) from None
    except elastic.Failure as e:
        raise SolveError(str(e)) from None


def main(argv=None):
    problem = dolfinx_version_problem()  # first: the rest of this file needs dolfinx 0.5's API
    if problem is not None:
        print(problem, file=sys.stderr)
        return 2
    if (sys.argv[1:] if argv is None else list(argv)) == ["--check-install"]:
        return 0  # `sdcrack run` asks before solving anything: the version check alone
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("export", help="folder written by `sdcrack mesh SCENE --out DIR`")
    ap.add_argument("--out", required=True, help="result folder (summary.json, u_level{L}.txt)")
    ap.add_argument("--fields", action="store_true", help="also write fields.h5 + fields/level{L}[.crack].xdmf")
    ap.add_argument("--overwrite", action="store_true", help="replace an existing OUT")
    args = ap.parse_args(argv)
    logging.getLogger().setLevel(logging.WARNING)
    try:
        summary = run(args.export, args.out, fields=args.fields, overwrite=args.overwrite)
    except (SolveError, OSError, ValueError, KeyError) as e:
        msg = str(e).replace("\n", " ")
        print(f"error: {msg}", file=sys.stderr)
        return 2 if isinstance(e, SceneError) else 1
    for c in summary["cases"]:
        err = c.get("errors", {})
        extra = "".join(f" {k}={v:.3e}" for k, v in err.items() if v is not None)
        print(f"level {c['level']}: unknowns={c['unknowns']} iterations={c['iterations']} "
              f"active={c['active']}{extra} total={c['timings_s']['total']:.2f}s status={c['status']}")
    return sdresults.exit_status(summary["cases"], "warning: ")


if __name__ == "__main__":
    sys.exit(main())
