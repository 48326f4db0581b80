"""Exact L² norms of piecewise-linear differences on shared triangles.

Both fields are P1 on the same triangles, so ‖a − b‖²_{L²(T)} = dᵀ M_T d with the exact P1 mass
matrix M_T = |T|/12 (1 + δ_ij), i.e. |T|/12 (Σ d_i² + (Σ d_i)²). No interpolation, no quadrature.
On a crack polyline (1D): P0 per segment gives Σ ℓ_k d_k², P1 per node gives
Σ ℓ_k/3 (d_a² + d_a d_b + d_b²).
"""
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
    s = (d * d).sum(axis=1) + d.sum(axis=1) ** 2  # (T, C)
    return float((area[:, None] * s).sum() / 12.0)


def p1_l2_norm(points, tris, values):
    """‖v‖_{L²} of a P1 field (scalar (N,) or vector (N,C)) on one mesh."""
    v = np.asarray(values, dtype=float)
    t = np.asarray(tris, dtype=np.int64)
    return np.sqrt(_local_sq(triangle_areas(points, t), v[t]))


def p1_l2_diff(points, tris, a, b):
    """‖a − b‖_{L²} for two P1 fields on the same mesh."""
    return p1_l2_norm(points, tris, np.asarray(a, dtype=float) - np.asarray(b, dtype=float))


def corner_map(points_a, tris_a, points_b, tris_b, tol=1e-9):
    """For two meshes with the same triangle order (triangle k is the same triangle) return perm
    (T,3) such that vertex tris_b[k, perm[k, i]] is at the position of tris_a[k, i].
    Raises NormError if some triangle's corners do not coincide."""
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
    return np.sqrt(_local_sq(triangle_areas(points_a, ta), va - vb))


def segment_lengths(crack_points):
    c = np.asarray(crack_points, dtype=float)[:, :2]
    return np.linalg.norm(np.diff(c, axis=0), axis=1)


def crack_l2_norm(crack_points, lam):
    """‖λ‖_{L²(Γc)}: P0 per segment if len(λ) = #segments, P1 per node if len(λ) = #nodes."""
    ell = segment_lengths(crack_points)
    lam = np.asarray(lam, dtype=float)
    if lam.shape[0] == ell.shape[0]:
        return float(np.sqrt((ell * lam ** 2).sum()))
    if lam.shape[0] == ell.shape[0] + 1:
        a, b = lam[:-1], lam[1:]
        return float(np.sqrt((ell / 3.0 * (a * a + a * b + b * b)).sum()))
    raise NormError(f"lambda has {lam.shape[0]} values for {ell.shape[0]} segments")


def crack_l2_diff(crack_points, lam_a, lam_b):
    la, lb = np.asarray(lam_a, dtype=float), np.asarray(lam_b, dtype=float)
    if la.shape != lb.shape:
        raise NormError("lambda fields of different kinds (P0 vs P1)")
    return crack_l2_norm(crack_points, la - lb)


def crack_integral(crack_points, lam):
    """∫_Γc λ ds (P0 or P1, exact)."""
    ell = segment_lengths(crack_points)
    lam = np.asarray(lam, dtype=float)
    if lam.shape[0] == ell.shape[0]:
        return float((ell * lam).sum())
    if lam.shape[0] == ell.shape[0] + 1:
        return float((ell * 0.5 * (lam[:-1] + lam[1:])).sum())
    raise NormError(f"lambda has {lam.shape[0]} values for {ell.shape[0]} segments")
