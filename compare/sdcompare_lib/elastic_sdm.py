"""The smooth-domain method's cases of an elastic scene (issue 46; docs/elasticity.md, "The
smooth-domain method's cases"): summary.json's elastic cases and their fields in fields.h5, read,
and every error of the summary recomputed here, independently of sdcrack's own norms
(crates/sdcrack-core/src/afw/norms.rs), from the stored fields with the compare tool's own
quadrature (exact._point_batches: Stroud away from the tips, Duffy collapsed with s = σ² at every
tip, near-tip triangles split) and the exact fields of elastic_exact.ElasticExact.

A case's fields (fields.h5, /cases/<fields_grid>/, on the broken mesh /meshes/level{L}-elasticity:
three points per triangle, triangle t's corners 3t, 3t + 1, 3t + 2 in its own order):

* sigma_raw, sigma (3T, 9): σ_h and sym σ_h at each corner, row-major 3 × 3 (xx, xy, ·, yx, yy, …);
  σ_h is P1 on each triangle (BDM1 rows), so the corner values are the whole field
* u_h (T, 3), gamma_h (T,): the P0 displacement and rotation
* u_star (3T, 3): the element-wise P1 reconstruction u*
* crack/points (2E, 3), crack/segments (E, 2), crack/opening, slip, pressure (2E,): per crack edge
  the values at its two ends, linear along it; crack/closed (2E,) 1 where the end's constraint is
  active (optional: the contact fronts are printed from it)

The errors (the names of summary.json's "errors"):

* stress_l2 = ‖σ − σ_h‖ (all four components), stress_sym_l2 = ‖σ − sym σ_h‖, stress_energy =
  (A(σ − σ_h) : (σ − σ_h))^{1/2}, A τ = (τ − c tr τ I)/(2μ), c = λ*/(2(μ + λ*)), on the raw σ_h
* u_l2 = ‖u − u_h‖, projected_u_l2 = ‖P0u − u_h‖ (P0u: the cell means of u by this rule),
  u_star_l2 = ‖u − u*‖, rotation_l2 = ‖γ − γ_h‖ (γ = ½(∂_y u_x − ∂_x u_y)), asymmetry_l2 =
  ‖σ_h,xy − σ_h,yx‖ (no exact field)
* opening_l2, slip_l2, pressure_l2 on Σ: Gauss–Legendre per crack edge, graded s = σ² from an end
  that is a tip (elastic_exact.crack_line_rule's rule), against the scene's opening, slip,
  pressure or the faces' limits (ElasticExact.crack_values); the edge's normal ν is the mesh
  export's crack normal at its nodes (crack_normals.txt, the normal into the + face), so the slip's
  sign (t = ν turned by −90°) is the scene's.
"""
import math
import os
from dataclasses import dataclass

import numpy as np

from . import exact as scalar_exact
from .read import InputError

ERROR_NAMES = ("stress_l2", "stress_sym_l2", "stress_energy", "u_l2", "projected_u_l2",
               "u_star_l2", "rotation_l2", "asymmetry_l2", "opening_l2", "slip_l2", "pressure_l2")
DOMAIN = ("stress_l2", "stress_sym_l2", "stress_energy", "u_l2", "projected_u_l2", "u_star_l2",
          "rotation_l2", "asymmetry_l2")
CRACK = ("opening_l2", "slip_l2", "pressure_l2")
# The norm each error is measured against for the round-off floor and the relative tolerance: the
# exact field's own norm of the same kind (stress: ‖σ‖; u: ‖u‖; rotation: ‖γ‖; crack: the larger
# of ‖opening‖, ‖slip‖, ‖pressure‖ on Σ and ‖u‖). asymmetry has no exact field: ‖σ‖; rotation:
# ‖∇u‖ (γ is one of its parts, and is 0 for a pure strain such as the patch test's).
SCALE_OF = {"stress_l2": "sigma", "stress_sym_l2": "sigma", "stress_energy": "sigma_a",
            "u_l2": "u", "projected_u_l2": "u", "u_star_l2": "u", "rotation_l2": "grad",
            "asymmetry_l2": "sigma", "opening_l2": "crack", "slip_l2": "crack",
            "pressure_l2": "crack"}


@dataclass
class SdmCase:
    """One solver case: its summary entry, level, multiplier, δ and fields (module documentation).
    points (3T, 2), triangles (T, 3), sigma_raw, sigma (3T, 2, 2), u_h (T, 2), gamma_h (T,),
    u_star (3T, 2), crack points (2E, 2), segments (E, 2), opening, slip, pressure (2E,)."""

    entry: dict
    level: int
    multiplier: str
    delta: float
    grid: str
    points: np.ndarray
    triangles: np.ndarray
    sigma_raw: np.ndarray
    sigma: np.ndarray
    u_h: np.ndarray
    gamma_h: np.ndarray
    u_star: np.ndarray
    crack_points: np.ndarray
    crack_segments: np.ndarray
    opening: np.ndarray
    slip: np.ndarray
    pressure: np.ndarray
    closed: np.ndarray = None  # (2E,) bool, crack/closed where written

    def label(self):
        return f"{self.multiplier} δ = {self.delta:g}"


def solver_entries(summary, folder):
    """The elastic solver cases of summary.json, checked for the keys this module reads ("errors"
    is there only for a scene with [exact])."""
    out = []
    for i, c in enumerate(summary.get("cases") or []):
        if not isinstance(c, dict):
            raise InputError(f"{folder}/summary.json: case {i} is not a table")
        for key, kind in (("level", int), ("multiplier", str), ("fields_grid", str)):
            if not isinstance(c.get(key), kind):
                raise InputError(f"{folder}/summary.json: case {i} has no {kind.__name__} "
                                 f"{key!r}")
        # errors: only where the scene has [exact]
        if not isinstance(c.get("errors", {}), dict):
            raise InputError(f"{folder}/summary.json: case {i}'s 'errors' is not a table")
        if not isinstance(c.get("delta"), (int, float)):
            raise InputError(f"{folder}/summary.json: case {i} has no number 'delta'")
        out.append(c)
    return out


def _dataset(group, name, shape, where):
    if name not in group:
        raise InputError(f"{where}: no dataset {name!r}")
    a = np.asarray(group[name][()])
    if a.ndim != len(shape) or any(s is not None and a.shape[k] != s for k, s in enumerate(shape)):
        raise InputError(f"{where}/{name}: shape {a.shape}, expected "
                         f"({', '.join('·' if s is None else str(s) for s in shape)})")
    if a.dtype.kind == "f" and not np.all(np.isfinite(a)):
        raise InputError(f"{where}/{name}: a value is not finite")
    return a


def read_cases(folder, summary):
    """[SdmCase] of the folder's elastic solver cases (fields.h5); [] when summary.json has none.
    A missing or malformed dataset is InputError (one line, exit 2)."""
    entries = solver_entries(summary, folder)
    if not entries:
        return []
    import h5py

    path = os.path.join(folder, "fields.h5")
    if not os.path.exists(path):
        raise InputError(f"missing file: {path} (the solver cases' fields)")
    try:
        h5 = h5py.File(path, "r")
    except OSError as exc:
        raise InputError(f"cannot read {path}: {exc}")
    with h5:
        return read_cases_from(h5, entries, path)


def read_cases_from(h5, entries, path):
    """[SdmCase] of the summary entries from the open fields.h5 `h5` (named `path` in errors)."""
    out = []
    for c in entries:
        L, grid = c["level"], c["fields_grid"]
        mesh_name = f"meshes/level{L}-elasticity"
        where = f"{path}:/{mesh_name}"
        if mesh_name not in h5:
            raise InputError(f"{path}: no group /{mesh_name} (the solver mesh of level {L})")
        m = h5[mesh_name]
        tri = _dataset(m, "triangles", (None, 3), where).astype(np.int64)
        T = len(tri)
        pts = _dataset(m, "points", (3 * T, None), where)[:, :2].astype(float)
        if tri.size and (tri.min() < 0 or tri.max() >= len(pts)):
            raise InputError(f"{where}/triangles: a vertex index out of range")
        g = f"cases/{grid}"
        if g not in h5:
            raise InputError(f"{path}: no group /{g} (case {grid} of summary.json)")
        where = f"{path}:/{g}"
        grp = h5[g]
        # corner values per triangle, in the triangle's own vertex order
        corner = lambda a: a[tri]  # noqa: E731
        sig_raw = corner(_dataset(grp, "sigma_raw", (3 * T, 9), where)
                         ).reshape(T, 3, 3, 3)[..., :2, :2]
        sig = corner(_dataset(grp, "sigma", (3 * T, 9), where)).reshape(T, 3, 3, 3)[..., :2, :2]
        u_h = _dataset(grp, "u_h", (T, 3), where)[:, :2]
        gamma_h = _dataset(grp, "gamma_h", (T,), where)
        u_star = corner(_dataset(grp, "u_star", (3 * T, 3), where))[..., :2]
        cw = f"{where}/crack"
        if "crack" in grp:
            cg = grp["crack"]
            seg = _dataset(cg, "segments", (None, 2), cw).astype(np.int64)
            cp = _dataset(cg, "points", (None, 3), cw)[:, :2]
            n = len(cp)
            if seg.size and (seg.min() < 0 or seg.max() >= n):
                raise InputError(f"{cw}/segments: a point index out of range")
            cols = [_dataset(cg, k, (n,), cw) for k in ("opening", "slip", "pressure")]
            closed = _dataset(cg, "closed", (n,), cw) != 0 if "closed" in cg else None
        else:
            seg, cp = np.zeros((0, 2), dtype=np.int64), np.zeros((0, 2))
            cols, closed = [np.zeros(0)] * 3, None
        out.append(SdmCase(c, L, c["multiplier"], float(c["delta"]), grid, pts, tri, sig_raw,
                           sig, u_h, gamma_h, u_star, cp, seg, *cols, closed))
    return out


# ------------------------------------------------------------------------------ the errors

def _compliance_energy(d, material):
    """A d : d per point of the 2 × 2 tensors d (…, 2, 2): (|d|² − c (tr d)²)/(2μ),
    c = λ*/(2(μ + λ*)) (the compliance of docs/design.md, on a tensor that need not be
    symmetric: A d : d = (d − c tr d I) : d / (2μ))."""
    lam, mu = material["lambda_in_plane"], material["mu"]
    c = lam / (2.0 * (mu + lam))
    tr = d[..., 0, 0] + d[..., 1, 1]
    return (np.einsum("...ij,...ij->...", d, d) - c * tr * tr) / (2.0 * mu)


DOMAIN_NAMES = ("ux", "uy", "duxdx", "duxdy", "duydx", "duydy", "sxx", "syy", "sxy")


def domain_errors(case, tips, ex, material, quad):
    """{name: error} of the domain errors (module documentation) and {scale: norm} of the exact
    fields (the zero field's errors), by the compare tool's rule `quad` on the case's triangles."""
    P, t = case.points, case.triangles
    _, area, _, _ = scalar_exact._geometry(P, t)
    acc = dict.fromkeys(DOMAIN, 0.0)
    size = {"sigma": 0.0, "sigma_a": 0.0, "u": 0.0, "grad": 0.0}
    u_int = np.zeros((len(t), 2))  # ∫_T u, for P0u
    for ids, L, W in scalar_exact._point_batches(P, t, tips, quad):
        xy = L @ P[t][ids]
        v = ex.evaluate(xy[..., 0], xy[..., 1], DOMAIN_NAMES)
        w = W * area[ids][:, None]
        shape = xy.shape[:2]
        S = np.empty(shape + (2, 2))
        S[..., 0, 0], S[..., 1, 1] = v["sxx"], v["syy"]
        S[..., 0, 1] = S[..., 1, 0] = v["sxy"]
        raw = np.einsum("kqv,kvij->kqij", np.broadcast_to(L, shape + (3,)), case.sigma_raw[ids])
        sym = np.einsum("kqv,kvij->kqij", np.broadcast_to(L, shape + (3,)), case.sigma[ids])
        d_raw, d_sym = raw - S, sym - S
        ux, uy = np.broadcast_to(v["ux"], shape), np.broadcast_to(v["uy"], shape)
        uh = case.u_h[ids][:, None, :]
        us = np.einsum("kqv,kvi->kqi", np.broadcast_to(L, shape + (3,)), case.u_star[ids])
        gam = 0.5 * (np.broadcast_to(v["duxdy"], shape) - np.broadcast_to(v["duydx"], shape))
        acc["stress_l2"] += float(np.sum(w * np.einsum("kqij,kqij->kq", d_raw, d_raw)))
        acc["stress_sym_l2"] += float(np.sum(w * np.einsum("kqij,kqij->kq", d_sym, d_sym)))
        acc["stress_energy"] += float(np.sum(w * _compliance_energy(d_raw, material)))
        acc["u_l2"] += float(np.sum(w * ((uh[..., 0] - ux) ** 2 + (uh[..., 1] - uy) ** 2)))
        acc["u_star_l2"] += float(np.sum(w * ((us[..., 0] - ux) ** 2 + (us[..., 1] - uy) ** 2)))
        acc["rotation_l2"] += float(np.sum(w * (case.gamma_h[ids][:, None] - gam) ** 2))
        acc["asymmetry_l2"] += float(np.sum(w * (raw[..., 0, 1] - raw[..., 1, 0]) ** 2))
        size["sigma"] += float(np.sum(w * np.einsum("kqij,kqij->kq", S, S)))
        size["sigma_a"] += float(np.sum(w * _compliance_energy(S, material)))
        size["u"] += float(np.sum(w * (ux * ux + uy * uy)))
        size["grad"] += float(np.sum(w * sum(np.broadcast_to(v[k], shape) ** 2 for k in
                                             ("duxdx", "duxdy", "duydx", "duydy"))))
        np.add.at(u_int, ids, np.stack([np.sum(w * ux, axis=1), np.sum(w * uy, axis=1)], axis=1))
    p0u = u_int / area[:, None]
    acc["projected_u_l2"] = float(area @ np.sum((p0u - case.u_h) ** 2, axis=1))
    return ({k: math.sqrt(max(v, 0.0)) for k, v in acc.items()},
            {k: math.sqrt(max(v, 0.0)) for k, v in size.items()})


def crack_normals(case, level):
    """(E, 2) the unit normal ν of each crack edge of the case: the edge's perpendicular, signed as
    the mesh export's crack normal at the export row nearest to the edge's midpoint (the normal
    into the + face)."""
    cp, seg = case.crack_points, case.crack_segments
    a, b = cp[seg[:, 0]], cp[seg[:, 1]]
    d = b - a
    ell = np.hypot(*d.T)
    if np.any(ell == 0):
        raise InputError(f"fields.h5 case {case.grid}: a crack edge of zero length")
    n = np.column_stack([-d[:, 1], d[:, 0]]) / ell[:, None]
    rows = level.nodes()
    mid = 0.5 * (a + b)
    near = np.argmin(((mid[:, None, :] - rows[None, :, :]) ** 2).sum(axis=2), axis=1)
    sign = np.sign(np.sum(n * level.normals[near], axis=1))
    if np.any(sign == 0):
        raise InputError(f"fields.h5 case {case.grid}: a crack edge perpendicular to the export's "
                         "crack normal")
    return n * sign[:, None]


def crack_errors(case, level, tips, ex, quad):
    """{opening_l2, slip_l2, pressure_l2} of the case and {"crack": the larger exact norm on Σ}."""
    out = {k: 0.0 for k in CRACK}
    if len(case.crack_segments) == 0:
        return out, {"crack": 0.0}
    cp, seg = case.crack_points, case.crack_segments
    g, wg = scalar_exact.gauss_legendre01(quad.line_n)
    scale = max(1.0, float(np.abs(cp).max(initial=0.0)))
    is_tip = np.zeros(len(cp), dtype=bool)
    for tp in tips:
        is_tip |= np.hypot(*(cp - tp).T) <= 1e-10 * scale
    normals = crack_normals(case, level)
    ks, ss, ws = [], [], []
    ell = np.hypot(*(cp[seg[:, 1]] - cp[seg[:, 0]]).T)
    for k, (a, b) in enumerate(seg):
        # graded s = σ² from a tip end (the integrands have √r and 1/√r… at a tip: the opening
        # √r, the pressure of a singular σ_h − σ): the rule of elastic_exact.crack_line_rule
        if is_tip[a] and is_tip[b]:
            pieces = [(0.0, 0.5), (1.0, 0.5)]
        elif is_tip[a] or is_tip[b]:
            pieces = [(0.0 if is_tip[a] else 1.0, 1.0)]
        else:
            ks.append(np.full(len(g), k)), ss.append(g), ws.append(wg * ell[k])
            continue
        for end, length in pieces:
            dist = length * g * g
            ks.append(np.full(len(g), k)), ss.append(dist if end == 0.0 else 1.0 - dist)
            ws.append(2.0 * g * wg * length * ell[k])
    k, s, w = np.concatenate(ks), np.concatenate(ss), np.concatenate(ws)
    a, b = seg[k, 0], seg[k, 1]
    xy = cp[a] + s[:, None] * (cp[b] - cp[a])
    exact = ex.crack_values(xy, normals[k])
    size = 0.0
    for name in ("opening", "slip", "pressure"):
        nodal = getattr(case, name)
        e = (1 - s) * nodal[a] + s * nodal[b] - exact[name]
        out[f"{name}_l2"] = math.sqrt(float(np.dot(w, e * e)))
        size = max(size, math.sqrt(float(np.dot(w, exact[name] ** 2))))
    return out, {"crack": size}


def recompute(case, level, ex, material, quad=None):
    """(errors {name: value}, scales {name: the exact field's norm of its kind}) of one case."""
    quad = quad or scalar_exact.Quadrature()
    tips = [level.nodes()[r] for r in level.tip_rows()]
    dom, size = domain_errors(case, tips, ex, material, quad)
    crk, csize = crack_errors(case, level, tips, ex, quad)
    size["crack"] = max(csize["crack"], size["u"])
    return dict(dom, **crk), {name: size[SCALE_OF[name]] for name in ERROR_NAMES}
