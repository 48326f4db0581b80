"""Exact L² norms of piecewise-linear differences on shared triangles.

Both fields are P1 on the same triangles, so ‖a − b‖²_{L²(T)} = dᵀ M_T d with the exact P1 mass
matrix M_T = |T|/12 (1 + δ_ij), i.e. |T|/12 (Σ d_i² + (Σ d_i)²). No interpolation, no quadrature.
On the cracks (1D): P0 per segment gives Σ ℓ_k d_k², P1 per node gives
Σ ℓ_k/3 (d_a² + d_a d_b + d_b²), summed over the segments [a, b] WITHIN each crack: `segments`
(S, 2), fields.h5's crack/segments, node indices into the crack points (all cracks' nodes
concatenated); None (a file written before several cracks) joins consecutive points (one crack).
A λ with one value per segment is P0 (in the order of `segments`), one per point P1.

Nested meshes (prolong_to_fine): a fine triangle is located in the coarse triangle that contains it
by the meshes' kind (the export's mesh.json "kind"): "structured", the SW–NE grid, by its centroid's
grid cell (locate_structured); "refined", uniform refinements with the numbering 4t + c (child c of
triangle t), by t_coarse = t_fine // 4^(refinements) (locate_refined).
"""
import hashlib
from collections import OrderedDict

import numpy as np


class NormError(ValueError):
    pass


def triangle_areas(points, tris):
    p = np.asarray(points, dtype=float)[:, :2]
    t = np.asarray(tris, dtype=np.int64)
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    return 0.5 * np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))


def _local_sq(area, d):
    """d: (T,3) or (T,3,C) vertex differences -> Σ_T |T|/12 (Σ d_i² + (Σ d_i)²)."""
    if d.ndim == 2:
        d = d[:, :, None]
    # numpy's reductions over the short middle axis were most of a report's time: the corner sum
    # as two additions and the squares by einsum are 3–5 × faster (same terms, summed in another
    # order: the last bits may differ)
    total = d[:, 0] + d[:, 1] + d[:, 2]  # (T, C)
    s = np.einsum("tic,tic->t", d, d) + np.einsum("tc,tc->t", total, total)
    return float(area @ s / 12.0)


def p1_l2_norm(points, tris, values):
    """‖v‖_{L²} of a P1 field (scalar (N,) or vector (N,C)) on one mesh."""
    v = np.asarray(values, dtype=float)
    t = np.asarray(tris, dtype=np.int64)
    return np.sqrt(_local_sq(_areas_of(points, tris), v[t]))


def p1_l2_diff(points, tris, a, b):
    """‖a − b‖_{L²} for two P1 fields on the same mesh."""
    return p1_l2_norm(points, tris, np.asarray(a, dtype=float) - np.asarray(b, dtype=float))


def corner_map(points_a, tris_a, points_b, tris_b, tol=1e-9):
    """For two meshes with the same triangle order (triangle k is the same triangle) return perm
    (T,3) such that vertex tris_b[k, perm[k, i]] is at the position of tris_a[k, i].
    Raises NormError if some triangle's corners do not coincide. Remembered for the last mesh
    pairs (by the digests of their arrays): every case of a level matches the same pair."""
    key = tuple(_digest_of(a) for a in (points_a, tris_a, points_b, tris_b)) + (tol,)
    return _CORNERS.get(key, lambda: _corner_map(points_a, tris_a, points_b, tris_b, tol))


def _corner_map(points_a, tris_a, points_b, tris_b, tol):
    pa = np.asarray(points_a, dtype=float)[:, :2][np.asarray(tris_a, dtype=np.int64)]  # (T,3,2)
    pb = np.asarray(points_b, dtype=float)[:, :2][np.asarray(tris_b, dtype=np.int64)]
    if pa.shape != pb.shape:
        raise NormError(f"triangle counts differ: {pa.shape[0]} vs {pb.shape[0]}")
    dist = np.linalg.norm(pa[:, :, None, :] - pb[:, None, :, :], axis=3)  # (T,3,3)
    perm = dist.argmin(axis=2)
    ok = np.take_along_axis(dist, perm[:, :, None], axis=2)[:, :, 0]
    scale = max(1.0, float(np.abs(pa).max()))
    if (ok > tol * scale).any() or (np.sort(perm, axis=1) != np.arange(3)).any():
        raise NormError("meshes do not share their triangles (corner positions differ)")
    return perm


def p1_l2_diff_two_meshes(points_a, tris_a, a, points_b, tris_b, b):
    """‖a − b‖_{L²} where a is P1 on mesh A, b is P1 on mesh B, and both meshes list the same
    triangles in the same order (e.g. the uncut and the cracked mesh: crack vertices duplicated).
    Vertex values are matched per triangle corner by position, so each triangle uses the copy of
    a duplicated vertex that belongs to it."""
    ta = np.asarray(tris_a, dtype=np.int64)
    tb = np.asarray(tris_b, dtype=np.int64)
    perm = corner_map(points_a, ta, points_b, tb)
    tb_aligned = np.take_along_axis(tb, perm, axis=1)
    va = np.asarray(a, dtype=float)[ta]
    vb = np.asarray(b, dtype=float)[tb_aligned]
    return np.sqrt(_local_sq(_areas_of(points_a, tris_a), va - vb))


def crack_segments(crack_points, segments=None):
    """(S, 2) the segments of the crack points: `segments` checked (node indices in range), or for
    None the consecutive pairs [k, k+1] (one crack)."""
    n = np.asarray(crack_points).shape[0]
    if segments is None:
        k = np.arange(max(n - 1, 0))
        return np.column_stack([k, k + 1]).astype(np.int64)
    s = np.asarray(segments)
    if s.ndim != 2 or s.shape[1] != 2 or not np.issubdtype(s.dtype, np.integer):
        raise NormError(f"crack segments of shape {s.shape} and type {s.dtype}: expected (S, 2) node indices")
    if s.size and (s.min() < 0 or s.max() >= n):
        raise NormError(f"a crack segment refers to node {int(s.max())}, of {n} crack points")
    return s.astype(np.int64)


def segment_lengths(crack_points, segments=None):
    """(S,) the lengths of the crack segments (see crack_segments)."""
    c = np.asarray(crack_points, dtype=float)[:, :2]
    s = crack_segments(c, segments)
    return np.linalg.norm(c[s[:, 1]] - c[s[:, 0]], axis=1)


def _segment_values(crack_points, lam, segments):
    """(ℓ (S,), λ) with λ (S,) for P0 or the end values (a, b) per segment for P1."""
    s = crack_segments(crack_points, segments)
    ell = segment_lengths(crack_points, s)
    lam = np.asarray(lam, dtype=float)
    if lam.shape[0] == s.shape[0]:
        return ell, lam
    if lam.shape[0] == np.asarray(crack_points).shape[0]:
        return ell, (lam[s[:, 0]], lam[s[:, 1]])
    raise NormError(f"lambda has {lam.shape[0]} values for {s.shape[0]} segments and "
                    f"{np.asarray(crack_points).shape[0]} nodes")


def crack_l2_norm(crack_points, lam, segments=None):
    """‖λ‖_{L²(Γc)}: P0 per segment if len(λ) = #segments, P1 per node if len(λ) = #nodes."""
    ell, v = _segment_values(crack_points, lam, segments)
    if not isinstance(v, tuple):
        return float(np.sqrt((ell * v ** 2).sum()))
    a, b = v
    return float(np.sqrt((ell / 3.0 * (a * a + a * b + b * b)).sum()))


def crack_l2_diff(crack_points, lam_a, lam_b, segments=None):
    la, lb = np.asarray(lam_a, dtype=float), np.asarray(lam_b, dtype=float)
    if la.shape != lb.shape:
        raise NormError("lambda fields of different kinds (P0 vs P1)")
    return crack_l2_norm(crack_points, la - lb, segments)


def crack_integral(crack_points, lam, segments=None):
    """∫_Γc λ ds (P0 or P1, exact)."""
    ell, v = _segment_values(crack_points, lam, segments)
    if not isinstance(v, tuple):
        return float((ell * v).sum())
    return float((ell * 0.5 * (v[0] + v[1])).sum())


def p1_vs_piecewise_constant_l2(points, tris, values, const):
    """‖v − c‖_{L²} for v P1 (vertex values (N,) or (N,C)) and c constant per triangle ((T,) or
    (T,C)), exact: d_i = v_i − c_T in the P1 mass formula."""
    t = np.asarray(tris, dtype=np.int64)
    v = np.asarray(values, dtype=float)[t]
    c = np.asarray(const, dtype=float)
    d = v - (c[:, None] if c.ndim == 1 else c[:, None, :])
    return float(np.sqrt(_local_sq(_areas_of(points, tris), d)))


def mini_vs_piecewise_constant_l2(points, tris, values, bubble, const):
    """‖v + b_T c_b − c‖_{L²} for the MINI field v (P1 vertex values (N,C)) plus bubble
    coefficients c_b (T,C) of b_T = 27 λ0 λ1 λ2, against c constant per triangle (T,C), exact:
    ∫ b_T λ_i = 3|T|/20 and ∫ b_T² = 81|T|/280 added to the P1 mass formula of d_i = v_i − c_T."""
    t = np.asarray(tris, dtype=np.int64)
    area = _areas_of(points, tris)
    d = np.asarray(values, dtype=float)[t] - np.asarray(const, dtype=float)[:, None, :]
    cb = np.asarray(bubble, dtype=float)
    if cb.shape != (t.shape[0], d.shape[2]):
        raise NormError(f"bubble coefficients of shape {cb.shape} for {t.shape[0]} triangles")
    cross = (2.0 * 3.0 / 20.0) * (area[:, None] * cb * d.sum(axis=1)).sum()
    square = (81.0 / 280.0) * (area[:, None] * cb * cb).sum()
    return float(np.sqrt(_local_sq(area, d) + cross + square))


def p1_gradients(points, tris, values):
    """∇ of a P1 field, constant per triangle: (T,2)."""
    t = np.asarray(tris, dtype=np.int64)
    return corner_gradients(points, t, np.asarray(values, dtype=float)[t])


def corner_gradients(points, tris, corner_values):
    """(T,2) gradient on each triangle of the linear function with the given (T,3) corner values
    (a field broken across a crack, or a coarse field prolonged onto finer triangles)."""
    p = np.asarray(points, dtype=float)[:, :2]
    t = np.asarray(tris, dtype=np.int64)
    u = np.asarray(corner_values, dtype=float)
    a, b, c = p[t[:, 0]], p[t[:, 1]], p[t[:, 2]]
    e1, e2 = b - a, c - a
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    d1, d2 = u[:, 1] - u[:, 0], u[:, 2] - u[:, 0]
    return np.column_stack([(d1 * e2[:, 1] - d2 * e1[:, 1]) / det, (-d1 * e2[:, 0] + d2 * e1[:, 0]) / det])


def crack_diff_vs_p1(crack_points, lam, nodal, segments=None):
    """‖λ − g‖_{L²(Γc)} with g P1 on the crack nodes and λ P0 per segment or P1 per node (exact:
    ∫_0^1 (c − a(1−s) − b s)² = c² − c(a+b) + (a² + ab + b²)/3 per unit length)."""
    s = crack_segments(crack_points, segments)
    ell = segment_lengths(crack_points, s)
    lam = np.asarray(lam, dtype=float)
    g = np.asarray(nodal, dtype=float)
    if g.shape[0] != np.asarray(crack_points).shape[0]:
        raise NormError(f"{g.shape[0]} nodal values for {np.asarray(crack_points).shape[0]} crack nodes")
    a, b = g[s[:, 0]], g[s[:, 1]]
    if lam.shape[0] == ell.shape[0]:
        c = lam
        return float(np.sqrt(np.maximum((ell * (c * c - c * (a + b) + (a * a + a * b + b * b) / 3)).sum(), 0.0)))
    return crack_l2_diff(crack_points, lam, g, s)


def _grid_lines(v):
    """The distinct grid-line coordinates among v, values closer than 1e-9 × the extent merged
    (a grid point computed two ways, e.g. x0 + i h and x1 − (n − i) h, differs in its last bits)."""
    v = np.sort(v)
    tol = 1e-9 * max(float(v[-1] - v[0]), 1e-300)
    return v[np.concatenate([[True], np.diff(v) > tol])]


def locate_structured(points, tris, xy):
    """Index of the triangle of a structured SW–NE mesh (the solver's meshes: cell (i, j) holds
    triangles 2(j nx + i) (below the diagonal) and 2(j nx + i) + 1) containing each point of xy,
    taken at interior points (e.g. centroids of a finer nested mesh)."""
    p = np.asarray(points, dtype=float)[:, :2]
    xs, ys = _grid_lines(p[:, 0]), _grid_lines(p[:, 1])
    nx, ny = len(xs) - 1, len(ys) - 1
    if 2 * nx * ny != len(tris):
        raise NormError("mesh is not the structured SW-NE triangulation")
    hx, hy = (xs[-1] - xs[0]) / nx, (ys[-1] - ys[0]) / ny
    sx, sy = (xy[:, 0] - xs[0]) / hx, (xy[:, 1] - ys[0]) / hy
    i = np.clip(np.floor(sx).astype(np.int64), 0, nx - 1)
    j = np.clip(np.floor(sy).astype(np.int64), 0, ny - 1)
    upper = (sy - j) > (sx - i)
    return 2 * (j * nx + i) + upper.astype(np.int64)


MESH_KINDS = ("structured", "refined", "graded")
NESTING_TOLERANCE = 1e-9  # barycentric coordinates of a fine corner in its coarse ancestor


def locate_refined(n_coarse, n_fine, refinements):
    """Index of the coarse triangle holding each fine triangle of `refinements` uniform refinements
    numbered 4t + c: t_fine // 4^refinements (the counts must match)."""
    k = int(refinements)
    if k < 0 or n_fine != n_coarse * 4 ** k:
        raise NormError(f"{n_fine} fine triangles are not {k} uniform refinement(s) of {n_coarse} "
                        "coarse triangles")
    return np.arange(n_fine, dtype=np.int64) // 4 ** k


def nesting(meshes, coarse, fine):
    """(kind, nesting) of prolong_to_fine from export level `coarse` to level `fine` of `meshes`
    ({level: ExportLevel}): "structured" (located by coordinates; nesting None), "refined" (4t + c
    numbering: fine − coarse refinements), "graded" (each level's parents.txt: per fine triangle
    its ancestor in the coarse level, composed level by level); levels of different kinds, or a
    graded level without its parents, are a NormError."""
    kind = meshes[fine].kind
    if coarse in meshes and meshes[coarse].kind != kind:
        raise NormError(f"mesh export levels {coarse} and {fine} are of kinds "
                        f"{meshes[coarse].kind} and {kind}")
    if kind == "structured":
        return kind, None
    if kind == "refined":
        return kind, fine - coarse
    owner = np.arange(len(meshes[fine].tris), dtype=np.int64)
    for lv in range(fine, coarse, -1):
        parents = getattr(meshes.get(lv), "parents", None)
        if parents is None:
            raise NormError(f"graded level {lv} of the mesh export has no parents.txt")
        owner = np.asarray(parents, dtype=np.int64)[owner]
    return kind, owner


def digest(*arrays):
    """A key for the contents of numpy arrays (shape, type and bytes): what a cache of results
    computed from them may be keyed by."""
    h = hashlib.blake2b(digest_size=16)
    for a in arrays:
        a = np.ascontiguousarray(a)
        h.update(repr((a.shape, a.dtype.str)).encode())
        h.update(a.tobytes())
    return h.hexdigest()


class _PerArray:
    """f(array) remembered for the last `size` array objects seen, by identity: the reference's
    finest mesh is passed, as the same objects, with every case compared to it. Each remembered
    array is kept alive, so its id cannot be taken by another array; the arrays must not be
    modified in place (the compare tool reads them and never writes them)."""

    def __init__(self, f, size=16):
        self.f, self.size, self.items = f, size, OrderedDict()

    def __call__(self, a):
        hit = self.items.get(id(a))
        if hit is not None and hit[0] is a:
            self.items.move_to_end(id(a))
            return hit[1]
        value = self.f(a)
        self.items[id(a)] = (a, value)
        while len(self.items) > self.size:
            self.items.popitem(last=False)
        return value


_digest_of = _PerArray(lambda a: digest(a))


def _areas_of(points, tris):
    """triangle_areas of a mesh, remembered for the last meshes' arrays (by identity)."""
    key = (_digest_of(points), _digest_of(tris))
    return _AREAS.get(key, lambda: triangle_areas(points, tris))



class LastResults:
    """The `size` results last computed, by key: meshes shared by many cases (every δ, multiplier
    and p mass of a level) are prepared once. Results are returned as stored: callers must not
    modify them."""

    def __init__(self, size):
        self.size, self.items = size, OrderedDict()

    def get(self, key, compute):
        if key in self.items:
            self.items.move_to_end(key)
            return self.items[key]
        value = compute()
        self.items[key] = value
        while len(self.items) > self.size:
            self.items.popitem(last=False)
        return value


# the nesting of a (coarse, fine) mesh pair: every case of a level is compared with the finest
# reference on the same pair
_NESTED = LastResults(8)
# meshes' triangle areas, by the digests of their arrays
_AREAS = LastResults(8)
# corner maps of mesh pairs (corner_map)
_CORNERS = LastResults(8)


def _barycentrics(cp, ct, owner, corners):
    """(T,3,3) barycentric coordinates of the fine corners (T,3,2) in their coarse owners."""
    a, b, c = cp[ct[owner, 0]], cp[ct[owner, 1]], cp[ct[owner, 2]]
    e1, e2 = b - a, c - a
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    r = corners - a[:, None, :]
    l1 = (r[..., 0] * e2[:, None, 1] - r[..., 1] * e2[:, None, 0]) / det[:, None]
    l2 = (e1[:, None, 0] * r[..., 1] - e1[:, None, 1] * r[..., 0]) / det[:, None]
    return np.stack([1 - l1 - l2, l1, l2], axis=2)


def prolong_to_fine(coarse_points, coarse_tris, coarse_values, fine_points, fine_tris,
                    kind="structured", refinements=None):
    """Values (T_f,3[,C]) of a coarse P1 field at the corners of every triangle of a nested finer
    mesh: each fine triangle lies in one coarse triangle, whose own corner values are used, so a
    field broken across a crack is evaluated on the right side. kind: "structured" (the coarse
    triangle found from the fine centroid by locate_structured), "refined" (`refinements` uniform
    refinements from the coarse to the fine mesh: locate_refined) or "graded" (`refinements` is
    then each fine triangle's ancestor in the coarse mesh: nesting); a fine corner outside its
    coarse triangle (e.g. triangles not in the 4t + c order) is a NormError."""
    cp = np.asarray(coarse_points, dtype=float)[:, :2]
    ct = np.asarray(coarse_tris, dtype=np.int64)
    fp = np.asarray(fine_points, dtype=float)[:, :2]
    ft = np.asarray(fine_tris, dtype=np.int64)
    key = (kind, tuple(_digest_of(a) for a in (coarse_points, coarse_tris, fine_points, fine_tris)),
           digest(np.asarray(refinements if refinements is not None else [], dtype=np.int64)))
    owner, lam = _NESTED.get(key, lambda: _nesting(cp, ct, fp, ft, kind, refinements))
    v = np.asarray(coarse_values, dtype=float)[ct[owner]]  # (T,3[,C])
    # batched 3×3 products (matmul: several times faster than einsum's generic loops here)
    if v.ndim == 2:
        return (lam @ v[:, :, None])[..., 0]
    return lam @ v


def _nesting(cp, ct, fp, ft, kind, refinements):
    """(owner (T_f,), barycentrics (T_f,3,3)): each fine triangle's coarse triangle and its corners'
    barycentric coordinates there (prolong_to_fine); NormError when a corner lies outside."""
    corners = fp[ft]  # (T,3,2)
    if kind == "structured":
        owner = locate_structured(cp, ct, corners.mean(axis=1))
    elif kind == "refined":
        if refinements is None:
            raise NormError("refined meshes: the number of refinements from the coarse level is needed")
        owner = locate_refined(len(ct), len(ft), refinements)
    elif kind == "graded":
        owner = np.asarray(refinements if refinements is not None else [], dtype=np.int64)
        if owner.shape != (len(ft),) or (len(owner) and (owner.min() < 0 or owner.max() >= len(ct))):
            raise NormError("graded meshes: per fine triangle its ancestor in the coarse level is "
                            "needed (norms.nesting)")
    else:
        raise NormError(f"unknown mesh kind {kind!r} (expected one of {', '.join(MESH_KINDS)})")
    lam = _barycentrics(cp, ct, owner, corners)
    outside = np.flatnonzero((lam < -NESTING_TOLERANCE).any(axis=(1, 2)))
    if len(outside):
        t = int(outside[0])
        raise NormError(f"fine triangle {t} does not lie in coarse triangle {int(owner[t])} ({kind} "
                        f"nesting; {len(outside)} such triangles)")
    return owner, lam


def prolonged_l2_diff(coarse_points, coarse_tris, coarse_values, fine_points, fine_tris, fine_values,
                      kind="structured", refinements=None):
    """‖u_coarse − u_fine‖_{L²} exactly on the fine triangles (nested meshes, both P1; kind and
    refinements: see prolong_to_fine)."""
    vc = prolong_to_fine(coarse_points, coarse_tris, coarse_values, fine_points, fine_tris, kind,
                         refinements)
    vf = np.asarray(fine_values, dtype=float)[np.asarray(fine_tris, dtype=np.int64)]
    return float(np.sqrt(_local_sq(_areas_of(fine_points, fine_tris), vc - vf)))
