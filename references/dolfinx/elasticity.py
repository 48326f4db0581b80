"""The dolfinx reference's elastic problem (docs/elasticity.md, issue 45): solve.py hands an export
whose scene.json has a "problem" to run() here; the scalar problem never comes here.

Per level, on the CRACKED mesh (every crack node doubled but the tips; a mouth, a crack end on ∂Ω,
doubled too, both copies on ∂Ω):

    vector P1,  K = ∫ σ(u):ε(v), σ = λ* tr ε I + 2μ ε (λ* = lambda_in_plane, μ: scene.json's
    "problem"), assembled by dolfinx with the one-point rule (exact: the integrand is constant per
    cell); F = ∫ f·v with sdquad.load_rule() (solve.py's load_measure, the scalar load's rule) +
    Σ over the traction parts ∫ t·v ds with sdquad.edge_rule() as a UFL custom facet rule (its
    Gauss–Legendre points are symmetric about the edge's midpoint, so the orientation dolfinx gives
    a facet does not move them); u = g at the vertices of the Dirichlet parts (the parts without a
    traction; a vertex shared with a traction part is Dirichlet; a mouth's copies take g on their
    own face: solve.py's side_points, the signed-zero rule of sdexpr); the fixed points' listed
    components 0.

The constraint w_j = (u⁺_j − u⁻_j)·ν_j ≥ 0 at every doubled pair j (a crack.txt row that is not a
tip) with neither copy Dirichlet. Change of variables u = T v: the + copy's two unknowns become the
jump's components (w_ν, w_τ) in (ν_j, τ_j), τ = ν turned by −90° (u⁺ = u⁻ + w_ν ν + w_τ τ), K′ =
TᵀKT, F′ = TᵀF. Primal–dual active set (c = 1) on the w_ν rows, started with every pair open:
A = {j : λ_j − w_j > tol}, λ_j = (K′v − F′) at the w_ν row, w_A = 0, SuperLU solve of the rest,
until A repeats (tol = ACTIVITY_TOL · max(1, ‖λ‖∞, ‖w‖∞), ≤ MAX_ITER solves: solve.py's). λ_j ≥ 0 is
the nodal contact force: (K u − F) at the + copy is λ_j ν_j, at the − copy −λ_j ν_j.

KKT residuals (kkt_residuals: the scalar script's definitions, B the jump operator w = B u of the
constrained pairs, ‖B‖∞ = max_j 2(|ν_x| + |ν_y|)_j): "equations" max_i |K u − F − Bᵀλ|_i /
(|K||u| + |Bᵀλ| + |F|)_i over the rows that are not Dirichlet or fixed; "primal" max(0, −min w) /
(‖B‖∞ ‖u‖∞); "dual" max(0, −min λ) / ‖λ‖∞; "complementarity" max |λ_j w_j| / (‖λ‖∞ ‖B‖∞ ‖u‖∞);
a zero scale counts as 1.

Outputs (docs/elasticity.md): summary.json ("problem": "elasticity"), u_level{L}.txt (ux uy per
cracked vertex), crack_level{L}.txt (opening slip contact_force active per crack.txt row; tips
0 0 0 0), with fields: fields.h5 + fields/level{L}.xdmf (point field u, cell field stress =
σ(u_h) as (σ_xx, σ_yy, σ_xy)) + fields/level{L}.crack.xdmf (opening, slip, contact_force, active).

Errors: InvalidInput (the scene: one line, solve.py exits 2) and Failure (the export files or the
solve: exit 1, as the scalar script's SolveError).
"""

import math
import time
from pathlib import Path

import numpy as np

from sdshared import sdexport, sdexpr, sdfields, sdquad, sdresults

COMPONENTS = {"x": 0, "y": 1}


class InvalidInput(Exception):
    """An invalid elastic scene.json (solve.py: exit status 2)."""


class Failure(Exception):
    """A malformed export or a failed solve (solve.py: exit status 1)."""


# ---------------------------------------------------------------------------------------------
# scene.json
# ---------------------------------------------------------------------------------------------

def _number(problem, key, where):
    v = problem.get(key)
    if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
        raise InvalidInput(f"{where}: problem.{key} must be a finite number, got {v!r}")
    return float(v)


def _expr(src, key, where):
    try:
        return sdexpr.parse(src)
    except sdexpr.ExprError as e:
        raise InvalidInput(f"{where}: scene expression {key} = {src!r}: column {e.column}: {e.message}") from None


def _pair(value, key, where, allow_none=False):
    """Two expressions [a, b] of scene.json's `key` as trees (None when allowed and null)."""
    if value is None and allow_none:
        return None
    if not isinstance(value, list) or len(value) != 2:
        raise InvalidInput(f"{where}: '{key}' must be a list of two expressions, got {value!r}")
    return [_expr(s, f"{key}[{k}]", where) for k, s in enumerate(value)]


def read_problem(scene, where):
    """The elastic scene's data: {"lambda_in_plane", "mu", "f", "g" (trees or None), "tractions"
    {part: trees}, "fixed" [(point, [components])]}; InvalidInput names the bad key."""
    problem = scene.get("problem")
    if not isinstance(problem, dict) or problem.get("kind") != "elasticity":
        raise InvalidInput(f"{where}: 'problem' must be an object with kind \"elasticity\", got {problem!r}")
    lam, mu = _number(problem, "lambda_in_plane", where), _number(problem, "mu", where)
    if not (mu > 0 and lam + mu > 0):
        raise InvalidInput(f"{where}: the material needs mu > 0 and lambda_in_plane + mu > 0 "
                           f"(lambda_in_plane = {lam!r}, mu = {mu!r})")
    tractions = scene.get("tractions") or {}
    if not isinstance(tractions, dict):
        raise InvalidInput(f"{where}: 'tractions' must be an object {{part: [tx, ty]}}")
    fixed = []
    for k, item in enumerate(scene.get("fixed") or []):
        point = item.get("point") if isinstance(item, dict) else None
        comps = item.get("components") if isinstance(item, dict) else None
        ok = (isinstance(point, list) and len(point) == 2 and all(isinstance(c, (int, float)) for c in point)
              and isinstance(comps, list) and comps and all(c in COMPONENTS for c in comps))
        if not ok:
            raise InvalidInput(f"{where}: fixed[{k}] must be {{\"point\": [x, y], \"components\": [\"x\", \"y\"]}}, "
                               f"got {item!r}")
        fixed.append((np.array(point, dtype=float), sorted(COMPONENTS[c] for c in set(comps))))
    return {"lambda_in_plane": lam, "mu": mu,
            "f": _pair(scene.get("f"), "f", where),
            "g": _pair(scene.get("g"), "g", where, allow_none=True),
            "tractions": {str(p): _pair(t, f"tractions.{p}", where) for p, t in tractions.items()},
            "fixed": fixed}


# ---------------------------------------------------------------------------------------------
# One level of the export
# ---------------------------------------------------------------------------------------------

def _table(path, dtype, ncols):
    try:
        return sdexport.load_table(path, dtype, ncols)
    except sdexport.ExportError as e:
        raise Failure(str(e)) from None


def read_level(export, level):
    """{"dir", "meta", "xy", "tri", "pairs" (crack.txt), "ranges" [(first, n)], "doubled" (I,) bool
    (rows with two copies: not a tip), "normals" (I, 2), "edges" (E, 3) boundary_edges.txt,
    "parts" (mesh.json's boundary_parts)}: the files read and checked by compare/sdshared/sdexport.py
    (the crack layout with its tips and mouths, the boundary edges with their parts)."""
    d = Path(export) / f"level{level}"
    if not d.is_dir():
        raise Failure(f"missing folder {d}")
    try:
        meta = sdexport.read_mesh_json(d)
        sdexport.read_kind(meta, d / "mesh.json")
        xy = sdexport.load_table(d / "vertices.txt", float, 2)
        tri = sdexport.load_table(d / "triangles.txt", np.int64, 3)
        nv = len(xy)
        if tri.size and (tri.min() < 0 or tri.max() >= nv):
            raise sdexport.ExportError(f"{d}/triangles.txt: vertex index out of range 0..{nv - 1}")
        if meta.get("n_vertices", nv) != nv or meta.get("n_triangles", len(tri)) != len(tri):
            raise sdexport.ExportError(f"{d}/mesh.json: counts do not match vertices.txt/triangles.txt")
        layout = sdexport.read_layout(d, xy, nv)
        edges, part, parts = sdexport.read_boundary_edges(d, nv, layout)
    except sdexport.ExportError as e:
        raise Failure(str(e)) from None
    return {"dir": d, "meta": meta, "xy": xy, "tri": tri, "pairs": layout.pairs,
            "ranges": layout.ranges, "doubled": layout.interior(), "normals": layout.normals,
            "edges": np.column_stack([edges, part]), "parts": list(parts)}


# ---------------------------------------------------------------------------------------------
# Boundary conditions of one level
# ---------------------------------------------------------------------------------------------

def dirichlet_parts(data, parts, where):
    """(is_dirichlet per part index, traction part indices {index: trees}); InvalidInput for a
    traction on an unknown part, or g given / missing against the parts without a traction."""
    unknown = sorted(set(data["tractions"]) - set(parts))
    if unknown:
        raise InvalidInput(f"{where}: traction on unknown boundary part {unknown[0]!r} "
                           f"(the parts: {', '.join(parts)})")
    is_dir = np.array([p not in data["tractions"] for p in parts])
    if data["g"] is None and is_dir.any():
        raise InvalidInput(f"{where}: g is missing, but the parts {', '.join(np.array(parts)[is_dir])} "
                           "have no traction")
    if data["g"] is not None and not is_dir.any():
        raise InvalidInput(f"{where}: g is given, but every boundary part has a traction")
    if data["fixed"] and is_dir.any():
        raise InvalidInput(f"{where}: fixed points are only allowed with an all-traction boundary")
    return is_dir, {parts.index(p): t for p, t in data["tractions"].items()}


def face_of_vertices(lv):
    """(side (N,), normal (N, 2)): +1 / −1 at the + / − copy of a doubled row, with its row's
    normal; 0 elsewhere (what solve.py's side_points takes)."""
    nv = len(lv["xy"])
    side, normal = np.zeros(nv, dtype=np.int64), np.zeros((nv, 2))
    rows = np.flatnonzero(lv["doubled"])
    plus, minus = lv["pairs"][rows, 0], lv["pairs"][rows, 1]
    side[plus], side[minus] = 1, -1
    normal[plus] = normal[minus] = lv["normals"][rows]
    return side, normal


def prescribed_values(lv, data, is_dir, side_points, where):
    """(dofs (D,), values (D,)): u = g at the vertices of the Dirichlet parts (each copy on its own
    face), the fixed points' listed components 0. Dofs are 2·vertex + component."""
    edges, xy = lv["edges"], lv["xy"]
    dofs, values = [], []
    if data["g"] is not None:
        verts = np.unique(edges[is_dir[edges[:, 2]], :2])
        side, normal = face_of_vertices(lv)
        sx, sy = side_points(xy[verts], side[verts], normal[verts])
        for c in (0, 1):
            g = np.broadcast_to(np.asarray(sdexpr.to_numpy(data["g"][c])(sx, sy), dtype=float), sx.shape)
            if not np.isfinite(g).all():
                raise InvalidInput(f"{where}: g is not finite at some boundary vertex of level {lv['dir'].name}")
            dofs.append(2 * verts + c)
            values.append(g)
    for point, comps in data["fixed"]:
        hit = np.flatnonzero((xy == point).all(axis=1))
        if len(hit) != 1:
            raise InvalidInput(f"{where}: fixed point ({point[0]:.17g}, {point[1]:.17g}) is not one vertex of "
                               f"level {lv['dir'].name}")
        for c in comps:
            dofs.append(np.array([2 * hit[0] + c]))
            values.append(np.zeros(1))
    if data["fixed"]:
        check_rigid_modes(xy, dofs, where)
    dofs, values = np.concatenate(dofs), np.concatenate(values)
    return dofs, values


def check_rigid_modes(xy, dofs, where):
    """The fixed components must remove the three rigid modes (1, 0), (0, 1), (−y, x): the rows of
    the held dofs applied to them have rank 3."""
    held = np.concatenate(dofs)
    vertex, comp = held // 2, held % 2
    modes = np.zeros((len(held), 3))
    modes[:, 0] = comp == 0
    modes[:, 1] = comp == 1
    modes[:, 2] = np.where(comp == 0, -xy[vertex, 1], xy[vertex, 0])
    if np.linalg.matrix_rank(modes) < 3:
        raise InvalidInput(f"{where}: the fixed points do not remove the rigid modes (rank "
                           f"{np.linalg.matrix_rank(modes)} < 3)")


# ---------------------------------------------------------------------------------------------
# Assembly (dolfinx)
# ---------------------------------------------------------------------------------------------

def build_space(lv):
    """(mesh, V, dof_of, inp): the vector P1 space on the cracked mesh and the export vertex →
    dolfinx node map (create_mesh renumbers: through input_global_indices, as solve.py)."""
    import ufl
    from mpi4py import MPI
    import dolfinx

    xy, tri = lv["xy"], lv["tri"]
    nv = len(xy)
    mesh = dolfinx.mesh.create_mesh(MPI.COMM_SELF, tri, xy, ufl.Mesh(ufl.VectorElement("Lagrange", ufl.triangle, 1)))
    V = dolfinx.fem.VectorFunctionSpace(mesh, ("Lagrange", 1))
    if V.dofmap.index_map.size_local != nv or V.dofmap.bs != 2:
        raise Failure(f"{lv['dir']}: dolfinx sees {V.dofmap.index_map.size_local} vertices, the export has "
                      f"{nv} (unused vertices?)")
    geom = mesh.geometry.dofmap.array.reshape(-1, 3)
    nodes = V.dofmap.list.array.reshape(-1, 3)
    inp = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
    dof_of = np.full(nv, -1, dtype=np.int64)
    dof_of[inp[geom.ravel()]] = nodes.ravel()
    if (dof_of < 0).any() or len(np.unique(dof_of)) != nv:
        raise Failure(f"{lv['dir']}: could not map vertices to dofs")
    coords = V.tabulate_dof_coordinates()
    if not np.allclose(coords[dof_of, :2], xy, atol=1e-12):
        raise Failure("internal error: dof coordinates do not match the export")
    return mesh, V, dof_of, inp


def facet_tags(mesh, inp, lv, traction_parts):
    """MeshTags on the facets of ∂Ω of the traction parts: tag = part index + 1."""
    import dolfinx

    mesh.topology.create_connectivity(1, 0)
    mesh.topology.create_connectivity(2, 0)
    c2v = mesh.topology.connectivity(2, 0).array.reshape(-1, 3)
    export_of_topo = np.empty(int(c2v.max()) + 1, dtype=np.int64)
    export_of_topo[c2v] = inp[mesh.geometry.dofmap.array.reshape(-1, 3)]
    f2v = mesh.topology.connectivity(1, 0).array.reshape(-1, 2)
    facet_of = {frozenset(map(int, export_of_topo[v])): f for f, v in enumerate(f2v)}
    ids, tags = [], []
    for a, b, part in lv["edges"]:
        if int(part) in traction_parts:
            f = facet_of.get(frozenset((int(a), int(b))))
            if f is None:
                raise Failure(f"{lv['dir']}/boundary_edges.txt: edge {a} {b} is not a mesh edge")
            ids.append(f)
            tags.append(int(part) + 1)
    ids, tags = np.array(ids, dtype=np.int32), np.array(tags, dtype=np.int32)
    order = np.argsort(ids)
    return dolfinx.mesh.meshtags(mesh, 1, ids[order], tags[order])


def edge_measure(ds, tag):
    """ds(tag) with sdquad.edge_rule() as a custom rule on the reference facet [0, 1]."""
    s, w = sdquad.edge_rule()
    # lists, not arrays: UFL signs metadata with str(), which abbreviates long arrays
    return ds(int(tag), metadata={"quadrature_rule": "custom", "quadrature_points": s[:, None].tolist(),
                                  "quadrature_weights": w.tolist()})


def assemble(lv, data, traction_parts, shared):
    """(K, F) in the export's dofs 2·vertex + component (scipy CSR, numpy), the timings of the
    forms' compilation, and the space's pieces."""
    import scipy.sparse as sp
    import ufl
    from petsc4py import PETSc
    import dolfinx
    import dolfinx.fem.petsc  # noqa: F401

    mesh, V, dof_of, inp = build_space(lv)
    x = ufl.SpatialCoordinate(mesh)
    lam = dolfinx.fem.Constant(mesh, PETSc.ScalarType(data["lambda_in_plane"]))
    mu = dolfinx.fem.Constant(mesh, PETSc.ScalarType(data["mu"]))
    u_, v_ = ufl.TrialFunction(V), ufl.TestFunction(V)

    def eps(w):
        return ufl.sym(ufl.grad(w))

    def sigma(w):
        return lam * ufl.tr(eps(w)) * ufl.Identity(2) + 2 * mu * eps(w)

    t_forms = time.perf_counter()
    a_form = dolfinx.fem.form(ufl.inner(sigma(u_), eps(v_))
                              * ufl.dx(metadata={"quadrature_degree": shared.STIFFNESS_DEGREE}))
    load = 0
    f = ufl.as_vector([sdexpr.to_ufl(t, x) for t in data["f"]])
    if not isinstance(ufl.inner(f, v_), ufl.constantvalue.Zero):  # f = 0: UFL drops the term
        load = ufl.inner(f, v_) * shared.load_measure()
    if traction_parts:
        ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags(mesh, inp, lv, traction_parts))
        for part, trees in sorted(traction_parts.items()):
            t = ufl.as_vector([sdexpr.to_ufl(tr, x) for tr in trees])
            if not isinstance(ufl.inner(t, v_), ufl.constantvalue.Zero):
                load = load + ufl.inner(t, v_) * edge_measure(ds, part + 1)
    l_form = None if isinstance(load, int) else dolfinx.fem.form(load, form_compiler_params=shared.NORM_FFCX)
    t_forms = time.perf_counter() - t_forms
    A = dolfinx.fem.petsc.assemble_matrix(a_form)
    A.assemble()
    indptr, indices, values = A.getValuesCSR()
    nd = 2 * len(lv["xy"])
    order = (2 * dof_of[:, None] + np.arange(2)).ravel()  # export dof 2e + c -> dolfinx dof
    K = sp.csr_matrix((values, indices, indptr), shape=(nd, nd))[order][:, order].tocsr()
    if l_form is None:
        F = np.zeros(nd)
    else:
        b = dolfinx.fem.petsc.assemble_vector(l_form)
        b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
        F = b.getArray().copy()[order]
    return K, F, t_forms


# ---------------------------------------------------------------------------------------------
# The contact problem
# ---------------------------------------------------------------------------------------------

def tangent(normal):
    """τ = ν turned by −90°: (ν_y, −ν_x) per row."""
    return np.column_stack([normal[:, 1], -normal[:, 0]])


def jump_basis(nd, plus, minus, normal):
    """T of u = T v: identity but at each constrained pair's + copy, u⁺ = u⁻ + w_ν ν + w_τ τ with
    (w_ν, w_τ) the + copy's slots of v."""
    import scipy.sparse as sp

    tau = tangent(normal)
    keep = np.ones(nd, dtype=bool)
    keep[2 * plus] = keep[2 * plus + 1] = False
    rows = [np.flatnonzero(keep)]
    cols = [np.flatnonzero(keep)]
    vals = [np.ones(int(keep.sum()))]
    for c in (0, 1):
        r = 2 * plus + c
        rows += [r, r, r]
        cols += [2 * minus + c, 2 * plus, 2 * plus + 1]
        vals += [np.ones(len(plus)), normal[:, c], tau[:, c]]
    return sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(nd, nd))


def active_set(Kp, Fp, fixed_dofs, fixed_values, normal_rows, shared):
    """Primal–dual active set on v[normal_rows] ≥ 0 (solve.py's iteration): (v, active, iterations,
    failure or None)."""
    import scipy.sparse.linalg as spla

    nd = len(Fp)
    v = np.zeros(nd)
    v[fixed_dofs] = fixed_values
    free_base = np.ones(nd, dtype=bool)
    free_base[fixed_dofs] = False
    rhs_base = Fp - Kp[:, fixed_dofs] @ fixed_values
    active = np.zeros(len(normal_rows), dtype=bool)
    seen, iterations, converged = set(), 0, False
    while iterations < shared.MAX_ITER:
        iterations += 1
        free = free_base.copy()
        free[normal_rows[active]] = False
        v[normal_rows[active]] = 0.0
        idx = np.flatnonzero(free)
        v[idx] = spla.splu(Kp[idx][:, idx].tocsc()).solve(rhs_base[idx])
        lam = (Kp @ v - Fp)[normal_rows]
        w = v[normal_rows]
        scale = max(1.0, np.abs(lam).max(initial=0.0), np.abs(w).max(initial=0.0))
        new_active = (lam - w) > shared.ACTIVITY_TOL * scale
        if np.array_equal(new_active, active):
            converged = True
            break
        if new_active.tobytes() in seen:  # cycling: stop (v is the solve of `active`) and report
            break
        seen.add(active.tobytes())
        active = new_active
    if converged:
        failure = None
    elif iterations >= shared.MAX_ITER:
        failure = f"active set did not converge in {iterations} solves"
    else:
        failure = f"active set cycled after {iterations} solves"
    return v, active, iterations, failure


def kkt_residuals(K, F, u, plus, minus, normal, free, active):
    """The relative KKT residuals (module documentation) and λ (0 off the active set, ν·(K u − F)
    at the + copy on it)."""
    r = K @ u - F
    lam = np.where(active, normal[:, 0] * r[2 * plus] + normal[:, 1] * r[2 * plus + 1], 0.0)
    bt_lam = np.zeros(len(u))
    for c in (0, 1):
        np.add.at(bt_lam, 2 * plus + c, lam * normal[:, c])
        np.add.at(bt_lam, 2 * minus + c, -lam * normal[:, c])
    r = r - bt_lam
    scale = abs(K) @ np.abs(u) + np.abs(bt_lam) + np.abs(F)
    w = (u[2 * plus] - u[2 * minus]) * normal[:, 0] + (u[2 * plus + 1] - u[2 * minus + 1]) * normal[:, 1]
    b_norm = 2.0 * np.abs(normal).sum(axis=1).max(initial=0.0)
    u_scale = b_norm * np.abs(u).max(initial=0.0) or 1.0
    return sdresults.kkt_measures(r[free], scale[free], w, lam, u_scale), lam


def cell_stress(xy, tri, u, lam, mu):
    """(T, 3) σ(u_h) = (σ_xx, σ_yy, σ_xy) per triangle of the P1 field u (N, 2)."""
    grads = [sdfields.triangle_gradients(xy, tri, u[:, c]) for c in (0, 1)]  # ∇u_x, ∇u_y
    exx, eyy = grads[0][:, 0], grads[1][:, 1]
    exy = (grads[0][:, 1] + grads[1][:, 0]) / 2
    tr = exx + eyy
    return np.column_stack([lam * tr + 2 * mu * exx, lam * tr + 2 * mu * eyy, 2 * mu * exy])


def node_weights(lv):
    """m_j per crack.txt row: half the summed lengths of its crack segments."""
    m = np.zeros(len(lv["pairs"]))
    seg = sdexport.segments_of(lv["ranges"])
    pts = lv["xy"][lv["pairs"][:, 0]]
    length = np.hypot(*(pts[seg[:, 1]] - pts[seg[:, 0]]).T)
    np.add.at(m, seg[:, 0], length / 2)
    np.add.at(m, seg[:, 1], length / 2)
    return m


def solve_level(lv, data, where, shared):
    """One level: (case, u (N, 2), crack table (I, 4), field set)."""
    t0 = time.perf_counter()
    is_dir, traction_parts = dirichlet_parts(data, lv["parts"], where)
    K, F, t_forms = assemble(lv, data, traction_parts, shared)
    nv, nd = len(lv["xy"]), 2 * len(lv["xy"])
    fixed_dofs, fixed_values = prescribed_values(lv, data, is_dir, shared.side_points, where)
    prescribed = np.zeros(nd, dtype=bool)
    prescribed[fixed_dofs] = True
    # the constrained pairs: doubled rows with neither copy prescribed (a Dirichlet mouth is not)
    held = prescribed.reshape(-1, 2).any(axis=1)
    pairs = lv["pairs"]
    rows = np.flatnonzero(lv["doubled"] & ~held[pairs[:, 0]] & ~held[pairs[:, 1]])
    plus, minus, normal = pairs[rows, 0], pairs[rows, 1], lv["normals"][rows]
    T = jump_basis(nd, plus, minus, normal)
    Kp, Fp = (T.T @ K @ T).tocsr(), T.T @ F
    t_asm = time.perf_counter() - t0 - t_forms

    t1 = time.perf_counter()
    v, active, iterations, failure = active_set(Kp, Fp, fixed_dofs, fixed_values, 2 * plus, shared)
    t_solve = time.perf_counter() - t1
    u = T @ v
    kkt, lam = kkt_residuals(K, F, u, plus, minus, normal, ~prescribed, active)
    case = {"level": int(lv["level"]), "h": float(lv["meta"].get("h", np.nan)), "unknowns": int(nd),
            "iterations": int(iterations), "active": int(active.sum()), "kkt": kkt,
            "status": sdresults.case_status(kkt, shared.KKT_TOLERANCE, failure)}

    U = u.reshape(nv, 2)
    jump = U[pairs[:, 0]] - U[pairs[:, 1]]
    crack = np.zeros((len(pairs), 4))
    crack[:, 0] = (jump * lv["normals"]).sum(axis=1)
    crack[:, 1] = (jump * tangent(lv["normals"])).sum(axis=1)
    crack[rows, 2] = lam
    crack[rows, 3] = active
    crack[~lv["doubled"]] = 0.0  # the tips: one vertex, no pair
    fields = {"xy": lv["xy"], "tri": lv["tri"], "crack": pairs, "segments": sdexport.segments_of(lv["ranges"]),
              "point": {"u": U},
              "cell": {"stress": cell_stress(lv["xy"], lv["tri"], U, data["lambda_in_plane"], data["mu"])},
              "h": case["h"] if math.isfinite(case["h"]) else None,
              "crack_fields": {"opening": crack[:, 0], "slip": crack[:, 1], "contact_force": crack[:, 2],
                               "active": crack[:, 3]}}
    case["timings_s"] = {"assembly": t_asm, "solve": t_solve, "forms": t_forms, "total": time.perf_counter() - t0}
    return case, U, crack, fields


def run(export, out, scene, fields, overwrite, shared):
    """Solves every level of an elastic export into `out` (atomically); returns the summary dict.
    `scene`: scene.json's dict; `shared`: solve.py's pieces (side_points, load_measure, NORM_FFCX,
    STIFFNESS_DEGREE, ACTIVITY_TOL, MAX_ITER, KKT_TOLERANCE, tool_version)."""
    export, out = Path(export), Path(out)
    where = str(export / "scene.json")
    data = read_problem(scene, where)
    levels = scene.get("levels")
    if not isinstance(levels, list) or not all(isinstance(L, int) and not isinstance(L, bool) for L in levels):
        raise InvalidInput(f"{where}: 'levels' must be a list of integers")
    lvs = [read_level(export, L) | {"level": L} for L in levels]
    for lv in lvs:  # the scene against every level's parts and vertices before writing anything
        is_dir, _ = dirichlet_parts(data, lv["parts"], where)
        prescribed_values(lv, data, is_dir, shared.side_points, where)
    if out.exists() and not overwrite:
        raise Failure(f"{out} exists; refusing to overwrite earlier results (use --overwrite)")
    with sdresults.staged_folder(out) as tmp:
        cases, field_sets = [], []
        for lv in lvs:
            case, U, crack, fs = solve_level(lv, data, where, shared)
            cases.append(case)
            np.savetxt(tmp / f"u_level{case['level']}.txt", U, fmt="%.17g")
            np.savetxt(tmp / f"crack_level{case['level']}.txt", crack, fmt="%.17g")
            field_sets.append((case["level"], fs))
        if fields:
            sdfields.write_fields(tmp, field_sets, "dolfinx")
        summary = sdresults.write_summary(tmp, scene.get("name"), "dolfinx", cases,
                                          tool_version=shared.tool_version, problem="elasticity")
    return summary

