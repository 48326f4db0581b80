"""Every crack output, and every dataset a viewer opens that no other check reads (issue 43).

**crack outputs**
* **the solver's `jump`** (/cases/CASE/crack/jump of fields.h5 and of verification.h5: the
  `jump` attribute of fields/*.crack.xdmf) is u⁺ − u⁻ of the case's stored u at each of its crack
  nodes, u⁺ at the node's + copy (the lower vertex number at its position, the original vertex:
  docs/design.md; the "field files' mesh" check holds every corner of the + face to it, from the
  scene's polylines) and u⁻ at its − copy. At a tip and on the continuous u's mesh the node has
  one vertex, so the jump is 0. Exact, bit for bit: the solver subtracts the same two float64
  values (crates/sdcrack-io/src/output/run.rs), and IEEE 754 rounds a difference correctly, so
  this tool's subtraction gives the same bits.
* **M1's λ_h against the jump, where the crack opens** (broken u). There is NO discrete identity
  λ_h = [u_h]: the second equation of the method tested with q ∈ X_h and integrated by parts on
  each face gives (p_h − ∇_h u_h, q) + ∫_Γc (λ_h − [u_h]) q·ν + ∫_Γ (u_h − g) q·n = 0 for all q,
  with p_h continuous (MINI) and ∇_h u_h piecewise constant, so λ_h and [u_h] agree only up to
  the discretisation error; both tend to the exact [u] (λ = [u] at the continuous level,
  Proposition 4.1 of the paper). The check is the one the two sides of that statement bound from
  any right solver: on the open part of the crack (the edges with M1's nodal multiplier Λ_j > 0
  at both ends, where λ_h > 0 on the whole edge), ‖λ_h − [u_h]‖ < ‖λ_h‖ in L²(open part), i.e.
  [u_h] is nearer to λ_h than zero is. A jump of the wrong sign (−[u_h]) or a u whose faces are
  exchanged gives ‖λ_h + [u_h]‖ ≥ ‖λ_h‖ wherever λ_h, [u_h] ≥ 0 — a relative distance ≥ 1 —
  and a u that does not open (zero jump) exactly 1. Measured on every repository scene
  with an open part (levels 0-2, δ = 0): ≤ 0.47, at stress-active-set's level 0 (0.066, 0.009
  at levels 1, 2); tip-contact 0.34, 0.14 at levels 1, 2; user-mesh and l-shape ≤ 0.33 at level
  0; ≤ 0.17 on the others; falling with h (mixed: 0.134, 1.9e-2, 1.6e-2, 1.0e-2 at levels 0-3,
  0.141 at level 0 with δ = 1). LAMBDA_JUMP_BOUND = 1 is that bound: it holds for every δ (the
  second equation does not contain δ).
* **each reference's `jump`** (<tool>/fields.h5 /cases/levelL/crack/jump) is u⁺ − u⁻ of its own
  stored u at the (plus, minus) rows of the export's crack.txt, bit for bit (the reference
  subtracts the same float64 values); its crack nodes and segments are crack.txt's and
  cracks.txt's; at the tips (plus = minus) the jump and the `contact_force` are exactly 0 (the
  nodal multipliers live on the doubled vertices only).
* **the two references' `jump` and `contact_force` agree** as their u does ("reference
  agreement": both solve the same convex QP on the same mesh, so they differ by their solvers'
  tolerances, at most `reference_agreement` = τ per vertex value). The jump is a difference of
  two vertex values: |Δ[u]| ≤ 2τ. The contact force is the multiplier of the jump row, λ_j =
  (K u − F)_{plus_j} up to each reference's equations residual (their KKT `equations`, an
  Oettli–Prager backward error ≤ κ = kkt_tolerance: |r_i| ≤ κ (|K||u| + |Bᵀλ| + |F|)_i, with
  |F| ≤ |K||u| + |λ| + |r|), so |Δλ_j| ≤ ‖K‖∞ τ + 4κ (‖K‖∞ ‖u‖∞ + ‖λ‖∞), ‖K‖∞ bounded by the
  largest sum over a vertex's triangles of the |entries| of their P1 stiffness matrices (the
  load F is the same rule in both, a shared module: its difference is round-off, far below τ).

**viewer datasets**
* every XDMF attribute NAME of a grid G (the solver's fields/*.xdmf, each reference's
  <tool>/fields/*.xdmf) points at /cases/G/NAME of its folder's fields.h5, which holds it: what
  a viewer labels NAME is the dataset the checks read under that name (the Topology and
  Geometry links are the "field files' mesh" check's).
* fields.h5 and verification.h5, when both are written, hold the same values in every dataset
  of a case that both have (the viewer reads the first, every check the second): bit for bit
  (one writer writes both from the same arrays).
* the solver's constant fields `delta` (/cases/CASE/delta, /cases/CASE/crack/delta, which
  ParaView shows per step) are the case's δ of summary.json at every point, bit for bit.
* each reference's u in its fields.h5 is its u_levelL.txt (written with %.17g: read back
  exactly), and its `p` is the area-weighted mean of the gradients of its P1 u over each vertex's
  triangles (references/*: `vertex_gradient`), recomputed here with this tool's own gradients
  (norms.p1_gradients) to P_ROUNDOFF × (‖∇u_h‖∞ + ‖u‖∞ max_T d_T / |det_T|): the gradient of a
  P1 function from float64 values carries an absolute error of a few ε ‖u‖∞ / height per
  triangle (height ~ |det| / d), the mean a few ε relative; 64 ε covers both computations.
Datasets no check reads are listed with the reason in docs/verification.md.
"""
import os

import numpy as np

from . import meshcheck, norms
from .cases import case_key, case_order
from .render import case_text, fmt_delta
from sdshared.sdfields import crack_field

EPS = float(np.finfo(float).eps)
LAMBDA_JUMP_BOUND = 1.0
P_ROUNDOFF = 64 * EPS
JUMP_AGREEMENT_FACTOR = 2.0  # |Δ(u⁺ − u⁻)| ≤ |Δu⁺| + |Δu⁻|
CONTACT_FORCE_KKT_FACTOR = 4.0


def checks(res, a, st):
    """The check rows (label, requirement, problems, not-applicable reason or None)."""
    a["crackcheck"] = {}
    return [crack_outputs_check(res, a, st), viewer_datasets_check(res, a)]


# ---------------------------------------------------------------- helpers
def _solver_files(res):
    """[(name, read.Fields)] of the solver's HDF5 files, each once."""
    out, seen = [], set()
    for f in (res.get("fields"), res.get("data")):
        if f is not None and id(f) not in seen:
            seen.add(id(f))
            out.append((os.path.basename(f.path), f))
    return out


def copies_at(points, crack_points):
    """(plus, minus) (I,) the lower and the higher vertex number at each crack node's position
    (bit for bit): the + and − copies (equal where the node has one vertex); -1 where none."""
    P = np.asarray(points, dtype=float)[:, :2]
    C = np.asarray(crack_points, dtype=float)[:, :2]
    zp, zc = P[:, 0] + 1j * P[:, 1], C[:, 0] + 1j * C[:, 1]
    order = np.argsort(zp, kind="stable")
    lo = np.searchsorted(zp[order], zc, side="left")
    hi = np.searchsorted(zp[order], zc, side="right")
    plus = np.array([order[a:b].min() if b > a else -1 for a, b in zip(lo, hi)], dtype=np.int64)
    minus = np.array([order[a:b].max() if b > a else -1 for a, b in zip(lo, hi)],
                     dtype=np.int64)
    return plus, minus


def open_part_distance(points, segments, lam, jump):
    """(‖λ − J‖, ‖λ‖) in L² over the crack edges with λ > 0 at both ends (P1 on each edge:
    ∫ f² = ℓ (a² + ab + b²) / 3), or None without such an edge."""
    P = np.asarray(points, dtype=float)[:, :2]
    S = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    S = S[(lam[S[:, 0]] > 0) & (lam[S[:, 1]] > 0)]
    if not len(S):
        return None
    ell = np.hypot(*(P[S[:, 1]] - P[S[:, 0]]).T)

    def l2(f):
        x, y = f[S[:, 0]], f[S[:, 1]]
        return float(np.sqrt(np.sum(ell * (x * x + x * y + y * y)) / 3.0))
    return l2(lam - jump), l2(lam)


def stiffness_inf_bound(points, tris):
    """An upper bound of ‖K‖∞ of the P1 stiffness matrix: the largest sum, over a vertex's
    triangles, of the |entries| of its row of their local matrices |T| ∇φ_i·∇φ_j."""
    P = np.asarray(points, dtype=float)[:, :2]
    T = np.asarray(tris, dtype=np.int64)
    X = P[T]
    det = ((X[:, 1, 0] - X[:, 0, 0]) * (X[:, 2, 1] - X[:, 0, 1])
           - (X[:, 2, 0] - X[:, 0, 0]) * (X[:, 1, 1] - X[:, 0, 1]))
    # ∇φ_i = rot(e_i) / det, e_i the edge opposite vertex i: K_ij = |T| ∇φ_i·∇φ_j = e_i·e_j / (2|det|)
    e = np.stack([X[:, 2] - X[:, 1], X[:, 0] - X[:, 2], X[:, 1] - X[:, 0]], axis=1)
    K = np.abs(np.einsum("tid,tjd->tij", e, e)) / (2.0 * np.abs(det))[:, None, None]
    rows = np.zeros(len(P))
    np.add.at(rows, T.ravel(), K.sum(axis=2).ravel())
    return float(rows.max()) if len(rows) else 0.0


# ---------------------------------------------------------------- crack outputs
def crack_outputs_check(res, a, st):
    label = "crack outputs"
    tol = st["reference_agreement"]
    kkt = st["kkt_tolerance"]
    what = ("the solver's jump is u⁺ − u⁻ of its stored u (bit for bit; 0 at the tips and for "
            "the continuous u); for M1 (broken u) ‖λ_h − [u_h]‖ < "
            f"{LAMBDA_JUMP_BOUND:g} × ‖λ_h‖ on the open part (λ_h > 0 at both ends of an edge); "
            "each reference's jump is u⁺ − u⁻ of its u at crack.txt's rows (bit for bit), its "
            "jump and contact_force 0 at the tips, and the two references' jump agree to "
            f"{JUMP_AGREEMENT_FACTOR:g} × {tol:g}, their contact_force to ‖K‖∞ {tol:g} + "
            f"{CONTACT_FORCE_KKT_FACTOR:g} × {kkt:g} (‖K‖∞‖u‖∞ + ‖λ‖∞)")
    problems = []
    n_jump, worst_ratio, n_ratio = _solver_jumps(res, problems)
    n_ref, agreement = _reference_crack_fields(res, problems, tol, kkt)
    if not n_jump and not n_ref:
        return label, what, [], "no crack field stored (no crack, or no field file)"
    a["crackcheck"]["crack_outputs"] = {"solver_jumps": n_jump, "m1_cases": n_ratio,
                                        "largest_lambda_jump_ratio": worst_ratio,
                                        "reference_levels": n_ref, "agreement": agreement}
    measured = [f"{n_jump} solver jump(s)", f"{n_ref} reference level(s)"]
    if n_ratio:
        measured.append(f"M1 ‖λ_h − [u_h]‖/‖λ_h‖ ≤ {worst_ratio:.2g} on {n_ratio} case(s)")
    if agreement:
        measured.append("references' largest jump difference "
                        f"{max(r['jump'] for r in agreement):.1e}, contact_force "
                        f"{max(r['contact_force'] for r in agreement):.1e} (bound "
                        f"{min(r['contact_force_bound'] for r in agreement):.1e} or more)")
    return label, what + f" ({'; '.join(measured)})", _fold(problems), None


def _fold(problems, keep=20):
    if len(problems) <= keep:
        return problems
    return problems[:keep] + [f"… and {len(problems) - keep} more of the same kinds"]


def _solver_jumps(res, problems):
    """The solver's jump in each of its files against its stored u, and M1's λ against it."""
    n, worst, n_ratio = 0, 0.0, 0
    ratio_seen = set()
    copies = {}
    cases = sorted(res["summary"]["cases"], key=case_order)
    for fname, f in _solver_files(res):
        for c in cases:
            grid = c.get("fields_grid")
            if not f.has_case(grid):
                continue
            g = f.h5[f"cases/{grid}"]
            if "crack/jump" not in g or "crack/points" not in g:
                continue
            # u from this file, else from the recomputation file (fields.h5 without u)
            src = g if "u" in g else (res["data"].h5[f"cases/{grid}"] if res["data"] is not None
                                      and res["data"].has_case(grid) else None)
            if src is None or "u" not in src:
                continue
            u = np.asarray(src["u"][()], dtype=float)
            jump = np.asarray(g["crack/jump"][()], dtype=float)
            cp = np.asarray(g["crack/points"][()], dtype=float)[:, :2]
            key = (_mesh_key(g, grid), cp.tobytes())
            if key not in copies:
                copies[key] = copies_at(_mesh_points(f, g), cp)
            plus, minus = copies[key]
            where = f"{fname} {case_text(case_key(c))}"
            n += 1
            if (plus < 0).any():
                problems.append(f"{where}: {int((plus < 0).sum())} crack node(s) of its jump are no "
                                "vertex of its mesh")
                continue
            want = u[plus] - u[minus]
            if jump.shape != want.shape or not np.array_equal(jump, want):
                bad = (np.flatnonzero(jump != want) if jump.shape == want.shape else [0])
                k = int(bad[0])
                problems.append(
                    f"{where}: its jump is not u⁺ − u⁻ of its stored u at "
                    + (f"{len(bad)} of {len(want)} crack nodes, e.g. at ({cp[k, 0]:.6g}, "
                       f"{cp[k, 1]:.6g}) jump = {jump[k]:.17g}, u⁺ − u⁻ = {want[k]:.17g}"
                       if jump.shape == want.shape else
                       f"every node ({jump.shape[0]} values for {want.shape[0]} crack nodes)"))
                continue
            # M1, broken u: λ_h against the jump on the open part (module docstring), once a case
            if c.get("multiplier") != "M1" or c.get("u_space") != "broken" or grid in ratio_seen:
                continue
            lam = (np.asarray(src["crack/lambda"][()], dtype=float) if "crack/lambda" in src
                   else None)
            if lam is None or lam.shape != jump.shape:
                continue
            ratio_seen.add(grid)
            segs = (np.asarray(g["crack/segments"][()], dtype=np.int64)
                    if "crack/segments" in g else np.column_stack(
                        [np.arange(len(cp) - 1), np.arange(1, len(cp))]))
            dist = open_part_distance(cp, segs, lam, jump)
            if dist is None:
                continue
            n_ratio += 1
            r = dist[0] / dist[1]
            worst = max(worst, r)
            if not r < LAMBDA_JUMP_BOUND:
                problems.append(f"{case_text(case_key(c))}: on the open part of the crack (λ_h > 0) "
                                f"‖λ_h − [u_h]‖ = {dist[0]:.3g} is not below ‖λ_h‖ = "
                                f"{dist[1]:.3g} (ratio {r:.3g} ≥ {LAMBDA_JUMP_BOUND:g}): the "
                                "stored jump does not open the crack where λ_h does")
    return n, worst, n_ratio


def _mesh_key(g, grid):
    """The dataset path of a case group's mesh (the cases of one mesh link to /meshes/KEY)."""
    import h5py

    link = g.get("mesh", getlink=True)
    return link.path if isinstance(link, h5py.SoftLink) else f"/cases/{grid}/mesh"


def _mesh_points(f, g):
    """The points of a case group's mesh in read.Fields `f` (its cache of linked meshes)."""
    key = _mesh_key(g, "")
    if key.startswith("/meshes/") and f.has_mesh(key[len("/meshes/"):]):
        return f.mesh_by_key(key[len("/meshes/"):])[0]
    return np.asarray(g["mesh/points"][()], dtype=float)


def _reference_fields(res, tool):
    """The h5py File of a reference's fields.h5, or None."""
    import h5py

    path = os.path.join(res["folder"], tool, "fields.h5")
    if not os.path.exists(path):
        return None
    try:
        return h5py.File(path, "r")
    except OSError:
        return None


def _reference_levels(res, need):
    """(tool, its summary entry, level, export level, fields.h5 File, "cases/levelL") of every
    reference level whose fields.h5 group has the members `need`, the file open meanwhile."""
    for tool, ref in sorted(res["refs"].items()):
        h5 = _reference_fields(res, tool)
        if h5 is None:
            continue
        with h5:
            for lv, m in sorted((ref.get("mesh") or {}).items()):
                name = f"cases/level{lv}"
                if all(f"{name}/{k}" in h5 for k in need):
                    yield tool, ref, lv, m, h5, name


def _reference_crack_fields(res, problems, tol, kkt):
    """Each reference's crack fields against its own u and the export; the two references'
    against each other."""
    n = 0
    per_tool = {}
    for tool, _, lv, m, h5, name in _reference_levels(res, ("crack", "u")):
        g = h5[f"{name}/crack"]
        where = f"reference {tool} level {lv}"
        try:
            jump = np.asarray(crack_field(g, "jump"), dtype=float)
            force = np.asarray(crack_field(g, "contact_force"), dtype=float)
        except KeyError as exc:
            problems.append(f"{where}: {exc.args[0]}")
            continue
        u = np.asarray(h5[f"{name}/u"][()], dtype=float)
        n += 1
        pairs = m.crack
        got = [x for x in (jump, force) if x.shape != (len(pairs),)]
        if got or len(u) != len(m.points):
            problems.append(f"{where}: its crack fields have {jump.shape} / {force.shape} "
                            f"values for {len(pairs)} crack nodes, or its u "
                            f"{len(u)} for {len(m.points)} vertices")
            continue
        pts = np.asarray(g["points"][()], dtype=float)[:, :2] if "points" in g else None
        segs = np.asarray(g["segments"][()], dtype=np.int64) if "segments" in g else None
        if pts is None or not np.array_equal(pts, m.points[pairs[:, 0], :2]) or (
                segs is not None and not np.array_equal(segs, m.segments())):
            problems.append(f"{where}: its crack polylines are not the export's crack "
                            "nodes (crack.txt) and segments (cracks.txt)")
        want = u[pairs[:, 0]] - u[pairs[:, 1]]
        if not np.array_equal(jump, want):
            k = int(np.flatnonzero(jump != want)[0])
            problems.append(f"{where}: its jump is not u⁺ − u⁻ of its u at crack.txt's "
                            f"rows at {int(np.sum(jump != want))} of {len(want)} nodes, "
                            f"e.g. row {k}: jump = {jump[k]:.17g}, u⁺ − u⁻ = "
                            f"{want[k]:.17g}")
        tips = pairs[:, 0] == pairs[:, 1]
        bad = np.flatnonzero(tips & ((force != 0.0) | (jump != 0.0)))
        if len(bad):
            k = int(bad[0])
            problems.append(f"{where}: {len(bad)} crack tip(s) with a nonzero jump or "
                            f"contact_force, e.g. row {k}: jump {jump[k]:.3g}, "
                            f"contact_force {force[k]:.3g} (both must be 0 at a tip)")
        per_tool.setdefault(tool, {})[lv] = (jump, force, u, m)
    agreement = []
    tools = sorted(per_tool)
    if len(tools) >= 2:
        A, B = per_tool[tools[0]], per_tool[tools[1]]
        for lv in sorted(set(A) & set(B)):
            (ja, fa, ua, m), (jb, fb, ub, _) = A[lv], B[lv]
            dj = float(np.abs(ja - jb).max()) if ja.size else 0.0
            df = float(np.abs(fa - fb).max()) if fa.size else 0.0
            knorm = stiffness_inf_bound(m.points, m.tris)
            umax = max(float(np.abs(ua).max(initial=0.0)), float(np.abs(ub).max(initial=0.0)))
            fmax = max(float(np.abs(fa).max(initial=0.0)), float(np.abs(fb).max(initial=0.0)))
            fbound = knorm * tol + CONTACT_FORCE_KKT_FACTOR * kkt * (knorm * umax + fmax)
            agreement.append({"level": lv, "jump": dj, "contact_force": df,
                              "contact_force_bound": fbound})
            where = f"references {tools[0]} and {tools[1]} level {lv}"
            if not dj <= JUMP_AGREEMENT_FACTOR * tol:
                k = int(np.argmax(np.abs(ja - jb)))
                problems.append(f"{where}: their jumps differ by {dj:.3g} > "
                                f"{JUMP_AGREEMENT_FACTOR:g} × {tol:g} (crack.txt row {k}: "
                                f"{ja[k]:.6g} and {jb[k]:.6g})")
            if not df <= fbound:
                k = int(np.argmax(np.abs(fa - fb)))
                problems.append(f"{where}: their contact_force differ by {df:.3g} > {fbound:.3g} "
                                f"(‖K‖∞ = {knorm:.3g}; crack.txt row {k}: {fa[k]:.6g} and "
                                f"{fb[k]:.6g}, largest force {fmax:.3g})")
    return n, agreement


# ---------------------------------------------------------------- viewer datasets
def viewer_datasets_check(res, a):
    label = "viewer datasets"
    what = ("every attribute NAME of a grid G of the field files (fields/*.xdmf, <tool>/fields/"
            "*.xdmf) is the dataset /cases/G/NAME of its folder's fields.h5; "
            "fields.h5 equals verification.h5 in every dataset both hold; the solver's constant "
            "fields delta are the case's δ; each reference's u in fields.h5 is its u_levelL.txt "
            "and its p the area-weighted vertex mean of its P1 gradient (to "
            f"{P_ROUNDOFF / EPS:g} ε round-off, recomputed here); bit for bit otherwise")
    problems = []
    n_links = _attribute_links(res, problems)
    n_same = _fields_equal_verification(res, problems)
    n_delta = _delta_constants(res, problems)
    n_ref = _reference_point_fields(res, problems)
    if not (n_links or n_same or n_delta or n_ref):
        return label, what, [], "no field file"
    a["crackcheck"]["viewer_datasets"] = {"attribute_links": n_links,
                                          "datasets_against_verification": n_same,
                                          "delta_fields": n_delta, "reference_levels": n_ref}
    return (label, what + f" ({n_links} XDMF attributes, {n_same} datasets against "
            f"verification.h5, {n_delta} δ fields, {n_ref} reference levels)", _fold(problems),
            None)


def _datasets(group, prefix=""):
    """{relative path: h5py Dataset} below an h5py group (not following soft links)."""
    import h5py

    out = {}
    for name in group:
        link = group.get(name, getlink=True)
        if isinstance(link, h5py.SoftLink):
            continue
        obj = group[name]
        if isinstance(obj, h5py.Dataset):
            out[prefix + name] = obj
        else:
            out.update(_datasets(obj, prefix + name + "/"))
    return out


def _xdmf_files(res):
    """(folder of its fields.h5, XDMF path) of every field file: the solver's fields/*.xdmf and
    each reference's <tool>/fields/*.xdmf."""
    out = []
    for sub in [""] + sorted(res["refs"]):
        base = os.path.join(res["folder"], sub)
        d = os.path.join(base, "fields")
        if os.path.isdir(d):
            out.extend((base, os.path.join(d, f)) for f in sorted(os.listdir(d))
                       if f.endswith(".xdmf"))
    return out


def _attribute_links(res, problems):
    """Every XDMF attribute NAME of grid G points at /cases/G/NAME of its folder's fields.h5,
    which holds it: the writers' layout (crates/sdcrack-io/src/output/xdmf.rs, sdfields.py),
    so that what a viewer labels NAME is the dataset the checks read under that name."""
    import h5py

    n, files = 0, {}
    try:
        for base, path in _xdmf_files(res):
            x = meshcheck._Xdmf(path)
            if x.error:
                continue  # field files' mesh reports an unreadable file
            h5path = os.path.normpath(os.path.abspath(os.path.join(base, "fields.h5")))
            rel = os.path.relpath(path, res["folder"])
            for grid, entry in x.grids.items():
                for name, link in entry["links"].items():
                    n += 1
                    want = f"/cases/{grid}/{name}"
                    if link is None or link[0] != h5path or link[1] != want:
                        problems.append(f"{rel}: its attribute {name} of grid {grid} points at "
                                        f"{'no HDF5 dataset' if link is None else link[1]} "
                                        f"({'' if link is None else os.path.basename(link[0])})"
                                        f", not {want} of its fields.h5")
                        continue
                    if h5path not in files:
                        files[h5path] = h5py.File(h5path, "r") if os.path.exists(h5path) else None
                    if files[h5path] is None or want not in files[h5path]:
                        problems.append(f"{rel}: its attribute {name} of grid {grid} points at "
                                        f"{want}, which its fields.h5 does not hold")
    finally:
        for f in files.values():
            if f is not None:
                f.close()
    return n


def _fields_equal_verification(res, problems):
    f, v = res.get("fields"), res.get("data")
    if f is None or v is None or f is v:
        return 0
    n = 0
    for c in sorted(res["summary"]["cases"], key=case_order):
        grid = c.get("fields_grid")
        if not (f.has_case(grid) and v.has_case(grid)):
            continue
        mine, theirs = _datasets(f.h5[f"cases/{grid}"]), _datasets(v.h5[f"cases/{grid}"])
        for rel, ds in sorted(mine.items()):
            if rel not in theirs:
                continue
            n += 1
            x, y = ds[()], theirs[rel][()]
            if x.shape != y.shape or not np.array_equal(x, y):
                problems.append(f"fields.h5 {case_text(case_key(c))}: its {rel} is not verification.h5's "
                                "(what a viewer shows is not what was checked)")
    return n


def _delta_constants(res, problems):
    n = 0
    for fname, f in _solver_files(res):
        for c in sorted(res["summary"]["cases"], key=case_order):
            grid = c.get("fields_grid")
            if not f.has_case(grid):
                continue
            g = f.h5[f"cases/{grid}"]
            for rel in ("delta", "crack/delta"):
                if rel not in g:
                    continue
                n += 1
                x = np.asarray(g[rel][()], dtype=float)
                if not np.all(x == float(c["delta"])):
                    problems.append(f"{fname} {case_text(case_key(c))}: its constant field {rel} is not the "
                                    f"case's δ = {fmt_delta(c['delta'])} everywhere (e.g. "
                                    f"{float(x[np.flatnonzero(x != float(c['delta']))[0]])!r})")
    return n


def _reference_point_fields(res, problems):
    n = 0
    for tool, ref, lv, m, h5, name in _reference_levels(res, ("u",)):
        n += 1
        where = f"reference {tool} level {lv}"
        u = np.asarray(h5[f"{name}/u"][()], dtype=float)
        txt = ref["u"].get(lv)
        if txt is not None and not (u.shape == txt.shape and np.array_equal(u, txt)):
            problems.append(f"{where}: the u of its fields.h5 is not its u_level{lv}.txt")
        if f"{name}/p" in h5 and len(u) == len(m.points):
            p = np.asarray(h5[f"{name}/p"][()], dtype=float)[:, :2]
            bad = _vertex_gradient_problem(m.points, m.tris, u, p)
            if bad:
                problems.append(f"{where}: {bad}")
    return n


def _vertex_gradient_problem(points, tris, u, p):
    """The reference's p against the area-weighted vertex mean of the P1 gradient, or None."""
    P = np.asarray(points, dtype=float)[:, :2]
    T = np.asarray(tris, dtype=np.int64)
    grad = norms.p1_gradients(P, T, u)
    area = norms.triangle_areas(P, T)
    acc, wsum = np.zeros((len(P), 2)), np.zeros(len(P))
    for k in range(3):
        np.add.at(acc, T[:, k], grad * area[:, None])
        np.add.at(wsum, T[:, k], area)
    used = wsum > 0
    want = np.zeros_like(acc)
    want[used] = acc[used] / wsum[used, None]
    d = meshcheck.diameters(P, T)
    scale = float(np.abs(grad).max(initial=0.0)) + float(np.abs(u).max(initial=0.0)) * float(
        (d / (2.0 * area)).max(initial=0.0))
    tol = P_ROUNDOFF * scale
    if p.shape != want.shape:
        return f"its p has {p.shape[0]} rows for {want.shape[0]} vertices"
    err = np.abs(p - want).max(axis=1)
    if not err.max(initial=0.0) <= tol:
        k = int(np.argmax(err))
        return (f"its p is not the area-weighted vertex mean of its P1 gradient at "
                f"{int(np.sum(err > tol))} vertices, e.g. vertex {k}: ({p[k, 0]:.6g}, "
                f"{p[k, 1]:.6g}) against ({want[k, 0]:.6g}, {want[k, 1]:.6g}) (difference "
                f"{err[k]:.2g} > {tol:.2g})")
    return None

