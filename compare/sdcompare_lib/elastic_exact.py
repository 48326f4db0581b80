"""The exact fields of an elastic scene and the errors of a reference's P1 displacement against
them, computed here from the stored fields (u_level{L}.txt, crack_level{L}.txt), independently of
the references' own numbers (docs/elasticity.md).

Exact data: mesh/scene.json's "exact" (ux, uy, sxx, syy, sxy always; opening, slip, pressure
optional, else from u and σ on the faces: opening = (u⁺ − u⁻)·ν, slip = (u⁺ − u⁻)·τ with τ = ν
turned by −90°, pressure = −ν·σν), ∇u the symbolic derivatives of ux, uy (sdexpr.derivative).
A face value takes the signed-zero rule of exact.ExactSolution.on_face (sdexpr.on_face).

Errors of a P1 field u_h (one vector per cracked-mesh vertex), with the domain quadrature of the
scalar errors (exact._point_batches: Stroud's rule away from the tips, Duffy rules collapsed at
every crack tip with s = σ², near-tip triangles split; the same rules, so the same self-check of
exact.quadrature_self_check applies); the tips are the crack ends that are not mouths (a mouth,
on ∂Ω, carries no singularity of its own):

* u_l2     = ‖u_h − u‖_{L²(Ω)}
* u_h1     = ‖∇u_h − ∇u‖_{L²(Ω \\ Γc)}         (the broken H¹ seminorm; ∇u_h constant per triangle)
* sigma_l2 = ‖σ(u_h) − σ‖_{L²(Ω)}, Frobenius (σ_xx² + σ_yy² + 2σ_xy²), σ(u_h) = λ* tr ε(u_h) I +
  2μ ε(u_h) per triangle
* u_a      = ‖u_h − u‖_a = a(w, w)^{1/2}, w = u_h − u: the energy norm (∫ σ(w):ε(w))^{1/2} with the
  material's λ*, μ, of the same gradients (the interpolation yardstick's norm, elastic.py)

On the crack (Gauss–Legendre per segment, graded s = σ² from a tip end as exact._crack_error):

* opening_l2, slip_l2 = ‖w_h − w‖_{L²(Γc)}, w_h linear between the rows' nodal values
  (u[plus] − u[minus])·ν_j and ·τ_j (ν_j from crack_normals.txt)
* pressure_l2 = (Σ_j m_j (λ_j/m_j − p(x_j))²)^{1/2} over the rows with two copies that are not
  mouths (a discrete L²(Γc): the nodal force λ_j over m_j, half its segments' lengths, is the
  references' nodal pressure)
"""
import math

import numpy as np

from sdshared import sdexpr

from . import exact as scalar_exact

# The exact opening at a crack node counts as closed (in contact) when it is at most this
# fraction of the largest |u| at the crack nodes: an opening that is zero as an expression
# evaluates to round-off of its terms (~1e-16 of u), an opening a P1 mesh resolves is far above.
CONTACT_TOL = 1e-9


class ElasticExact:
    """u, ∇u, σ, opening, slip, pressure of mesh/scene.json's "exact" table."""

    def __init__(self, exact, material):
        self.material = material
        self.trees = {}
        for k in ("ux", "uy", "sxx", "syy", "sxy"):
            if not isinstance(exact.get(k), str):
                raise scalar_exact.ExactError(f"exact.{k} is not an expression")
            self.trees[k] = sdexpr.parse(exact[k])
        for comp in ("x", "y"):
            for var in ("x", "y"):
                self.trees[f"du{comp}d{var}"] = sdexpr.derivative(self.trees[f"u{comp}"], var)
        for k in ("opening", "slip", "pressure"):
            if isinstance(exact.get(k), str):
                self.trees[k] = sdexpr.parse(exact[k])
        self.sif = exact.get("sif")
        self._ev = {}

    def evaluate(self, x, y, names):
        """{name: values} at (x, y), the names evaluated in one pass (SharedEvaluator)."""
        names = tuple(names)
        ev = self._ev.get(names)
        if ev is None:
            ev = self._ev[names] = scalar_exact.SharedEvaluator([self.trees[n] for n in names])
        return dict(zip(names, ev(x, y)))

    def on_face(self, xy, normal, side, names):
        """The names at crack points xy (K, 2) seen from face `side` of the normals (K, 2)."""
        q = np.array(xy, dtype=float)[:, :2]
        nu = np.broadcast_to(np.asarray(normal, dtype=float), q.shape)
        for d in range(2):
            z = (q[:, d] == 0.0) & (nu[:, d] != 0.0)
            q[z, d] = np.copysign(0.0, side * nu[z, d])
        return self.evaluate(q[:, 0], q[:, 1], names)

    def crack_values(self, xy, normal):
        """{"opening", "slip", "pressure", "u_scale"} at crack points xy (K, 2) with normals (K, 2):
        the given expressions, else from the faces; u_scale the largest |u| on either face."""
        nu = np.broadcast_to(np.asarray(normal, dtype=float), np.shape(xy))
        tau = np.column_stack([nu[:, 1], -nu[:, 0]])
        plus = self.on_face(xy, nu, 1.0, ("ux", "uy", "sxx", "syy", "sxy"))
        minus = self.on_face(xy, nu, -1.0, ("ux", "uy"))
        jx, jy = plus["ux"] - minus["ux"], plus["uy"] - minus["uy"]
        out = {"opening": jx * nu[:, 0] + jy * nu[:, 1], "slip": jx * tau[:, 0] + jy * tau[:, 1]}
        sn = (plus["sxx"] * nu[:, 0] ** 2 + 2 * plus["sxy"] * nu[:, 0] * nu[:, 1]
              + plus["syy"] * nu[:, 1] ** 2)
        out["pressure"] = -sn
        given = [k for k in ("opening", "slip", "pressure") if k in self.trees]
        if given:
            out.update(self.evaluate(np.asarray(xy)[:, 0], np.asarray(xy)[:, 1], given))
        out["u_scale"] = float(max(np.abs(np.concatenate([plus["ux"], plus["uy"], minus["ux"],
                                                          minus["uy"]])).max(initial=0.0), 0.0))
        return out


def hooke(grad, material):
    """σ (…, 3) = (σ_xx, σ_yy, σ_xy) of displacement gradients grad (…, 2, 2), grad[i, d] =
    ∂u_i/∂x_d: λ* tr ε I + 2μ ε."""
    lam, mu = material["lambda_in_plane"], material["mu"]
    exx, eyy = grad[..., 0, 0], grad[..., 1, 1]
    exy = 0.5 * (grad[..., 0, 1] + grad[..., 1, 0])
    tr = exx + eyy
    return np.stack([lam * tr + 2 * mu * exx, lam * tr + 2 * mu * eyy, 2 * mu * exy], axis=-1)


def p1_gradients(points, triangles, u):
    """(T, 2, 2) the constant gradient of the P1 vector field u (N, 2) on each triangle."""
    _, _, G, _ = scalar_exact._geometry(np.asarray(points, dtype=float), triangles)
    return np.einsum("tvi,tvd->tid", np.asarray(u, dtype=float)[triangles], G)


def tip_points(level):
    return [level.nodes()[r] for r in level.tip_rows()]


DOMAIN_NAMES = ("ux", "uy", "duxdx", "duxdy", "duydx", "duydy", "sxx", "syy", "sxy")


def p1_field(level, u):
    """(corner values (T, 3, 2), gradients (T, 2, 2)) of the P1 field u (N, 2) on the level's
    cracked mesh."""
    u = np.asarray(u, dtype=float)
    return u[level.triangles], p1_gradients(level.points, level.triangles, u)


def vertex_interpolant(level, ex):
    """(N, 2) I_h u, the exact u at every vertex of the level's cracked mesh, a crack row's + and −
    copies each on its own face (ElasticExact.on_face: the face rule the references' g and the
    exact-data check take): one value per vertex, a field of the references' P1 space."""
    xy = np.asarray(level.points, dtype=float)[:, :2]
    v = ex.evaluate(xy[:, 0], xy[:, 1], ("ux", "uy"))
    u = np.column_stack([np.asarray(v["ux"], dtype=float) * np.ones(len(xy)),
                         np.asarray(v["uy"], dtype=float) * np.ones(len(xy))])
    rows = level.pair_rows()
    for side, col in ((1.0, 0), (-1.0, 1)):
        k = level.pairs[rows, col]
        f = ex.on_face(xy[k], level.normals[rows], side, ("ux", "uy"))
        u[k, 0], u[k, 1] = f["ux"], f["uy"]
    bad = np.flatnonzero(~np.all(np.isfinite(u), axis=1))
    if len(bad):
        u[bad] = tip_limit(level, ex, bad)
    if not np.all(np.isfinite(u)):
        raise scalar_exact.ExactError("the exact u is not finite at a vertex of the cracked mesh")
    return u


# A closed form may not evaluate at a crack tip itself (Westergaard's √(z² − a²) in a denominator:
# 0 · ∞) though u is continuous there. Its value is the limit along a ray into one of the vertex's
# triangles: u(r) = u₀ + c √r + O(r) on the ray, so u₀ = 2 u(δ) − u(4δ) + O(δ), δ = TIP_LIMIT_STEP
# × the distance to the centroid (an error ~1e-8 of the field's size, below the yardstick's
# tolerance; the √r difference keeps ~8 digits).
TIP_LIMIT_STEP = 1e-8


def tip_limit(level, ex, vertices):
    """(K, 2) the limit of the exact u at the vertices along a ray towards the centroid of a
    triangle of each (TIP_LIMIT_STEP)."""
    P, t = np.asarray(level.points, dtype=float)[:, :2], level.triangles
    tri = np.array([np.flatnonzero((t == v).any(axis=1))[0] for v in vertices])
    X = P[vertices]
    d = P[t[tri]].mean(axis=1) - X
    near, far = X + TIP_LIMIT_STEP * d, X + 4 * TIP_LIMIT_STEP * d
    a = ex.evaluate(near[:, 0], near[:, 1], ("ux", "uy"))
    b = ex.evaluate(far[:, 0], far[:, 1], ("ux", "uy"))
    return np.column_stack([2 * a["ux"] - b["ux"], 2 * a["uy"] - b["uy"]])


def interpolant_field(level, ex):
    """(corners, gradients) of the P1 interpolant I_h u of the exact u on the level's cracked mesh
    (vertex_interpolant)."""
    return p1_field(level, vertex_interpolant(level, ex))


def domain_errors(level, ex, fields, material, quad=None):
    """{name: {"u_l2", "u_h1", "sigma_l2"}} of the P1 fields {name: (corners (T, 3, 2), gradients
    (T, 2, 2))} on the level's cracked mesh, with the error quadrature (module documentation); the
    exact u, ∇u, σ are evaluated once per batch of points for all fields (memory bounded by a
    batch, whatever the level)."""
    quad = quad or scalar_exact.Quadrature()
    P, t = level.points, level.triangles
    _, area, _, _ = scalar_exact._geometry(P, t)
    sig = {k: hooke(g, material) for k, (_, g) in fields.items()}
    acc = {k: [0.0, 0.0, 0.0, 0.0] for k in fields}
    for ids, L, W in scalar_exact._point_batches(P, t, tip_points(level), quad):
        xy = L @ P[t][ids]
        v = ex.evaluate(xy[..., 0], xy[..., 1], DOMAIN_NAMES)
        w = W * area[ids][:, None]
        for k, (corners, grads) in fields.items():
            uh = L @ corners[ids]  # (K, q, 2)
            dx, dy = uh[..., 0] - v["ux"], uh[..., 1] - v["uy"]
            g = grads[ids][:, None]  # (K, 1, 2, 2)
            d = [g[..., 0, 0] - v["duxdx"], g[..., 0, 1] - v["duxdy"],
                 g[..., 1, 0] - v["duydx"], g[..., 1, 1] - v["duydy"]]
            sk = sig[k][ids][:, None]
            a, b, c = sk[..., 0] - v["sxx"], sk[..., 1] - v["syy"], sk[..., 2] - v["sxy"]
            acc[k][0] += float(np.sum(w * (dx * dx + dy * dy)))
            acc[k][1] += float(np.sum(w * sum(e * e for e in d)))
            acc[k][2] += float(np.sum(w * (a * a + b * b + 2 * c * c)))
            acc[k][3] += float(np.sum(w * energy_density(d, material)))
    return {k: {"u_l2": math.sqrt(su), "u_h1": math.sqrt(sg), "sigma_l2": math.sqrt(ss),
                "u_a": math.sqrt(sa)} for k, (su, sg, ss, sa) in acc.items()}


def energy_density(d, material):
    """σ(w):ε(w) = λ* (tr ε)² + 2μ ε:ε of the gradient d = (∂₁w₁, ∂₂w₁, ∂₁w₂, ∂₂w₂) of w
    (ε:ε = ε₁₁² + ε₂₂² + 2ε₁₂², ε₁₂ = (∂₂w₁ + ∂₁w₂)/2): the integrand of the energy norm
    ‖w‖_a² = a(w, w) of the problem's material (λ* = lambda_in_plane, μ = mu)."""
    exx, eyy, exy = d[0], d[3], 0.5 * (d[1] + d[2])
    return (material["lambda_in_plane"] * (exx + eyy) ** 2
            + 2 * material["mu"] * (exx * exx + eyy * eyy + 2 * exy * exy))


def crack_line_rule(level, quad=None):
    """(seg (K,), s (K,), w (K,)): points of Γc on the segments (S, 2) of level.segments(), local
    coordinate s from the segment's first row, weights in length units; Gauss–Legendre, graded as
    s = σ² from an end that is a tip (a segment with two tip ends: each half from its tip)."""
    quad = quad or scalar_exact.Quadrature()
    g, wg = scalar_exact.gauss_legendre01(quad.line_n)
    seg_rows = level.segments()
    c = level.nodes()
    ell = np.hypot(*(c[seg_rows[:, 1]] - c[seg_rows[:, 0]]).T)
    tip = np.zeros(len(level.pairs), dtype=bool)
    tip[level.tip_rows()] = True
    seg, s, w = [], [], []
    for k, (a, b) in enumerate(seg_rows):
        if tip[a] and tip[b]:
            pieces = [(0.0, 0.5), (1.0, 0.5)]
        elif tip[a] or tip[b]:
            pieces = [(0.0 if tip[a] else 1.0, 1.0)]
        else:
            seg.append(np.full(len(g), k)), s.append(g), w.append(wg * ell[k])
            continue
        for end, length in pieces:
            dist = length * g * g
            seg.append(np.full(len(g), k)), s.append(dist if end == 0.0 else 1.0 - dist)
            w.append(2.0 * g * wg * length * ell[k])
    return np.concatenate(seg), np.concatenate(s), np.concatenate(w)


class CrackExact:
    """The exact opening and slip at the crack quadrature points of a level, and the exact
    opening, pressure and contact status at its rows (shared by the references)."""

    def __init__(self, level, ex, quad=None):
        self.level = level
        seg_rows = level.segments()
        self.seg, self.s, self.w = crack_line_rule(level, quad)
        c = level.nodes()
        a, b = c[seg_rows[self.seg, 0]], c[seg_rows[self.seg, 1]]
        xy = a + self.s[:, None] * (b - a)
        d = b - a
        normals = np.column_stack([-d[:, 1], d[:, 0]]) / np.hypot(*d.T)[:, None]
        self.at_points = ex.crack_values(xy, normals)
        rows = np.flatnonzero(level.pair_rows())
        self.rows = rows
        self.at_rows = ex.crack_values(c[rows], level.normals[rows])
        scale = max(self.at_rows["u_scale"], self.at_points["u_scale"])
        self.contact_tol = CONTACT_TOL * scale
        self.closed = self.at_rows["opening"] <= self.contact_tol  # per row of self.rows

    def nodal_jumps(self, u):
        """(opening (I,), slip (I,)) of u (N, 2) at every row: (u[plus] − u[minus])·ν_j, ·τ_j."""
        lv = self.level
        j = u[lv.pairs[:, 0]] - u[lv.pairs[:, 1]]
        nu = lv.normals
        return (j[:, 0] * nu[:, 0] + j[:, 1] * nu[:, 1], j[:, 0] * nu[:, 1] - j[:, 1] * nu[:, 0])

    def jump_errors(self, opening, slip):
        """{"opening_l2", "slip_l2"} of the nodal values (I,) linear along each segment."""
        seg_rows = self.level.segments()
        out = {}
        for name, nodal in (("opening", opening), ("slip", slip)):
            a, b = nodal[seg_rows[self.seg, 0]], nodal[seg_rows[self.seg, 1]]
            d = (1 - self.s) * a + self.s * b - self.at_points[name]
            out[f"{name}_l2"] = math.sqrt(float(np.dot(self.w, d * d)))
        return out

    def judged_rows(self):
        """(I,) bool over self.rows: the rows with two copies that are not mouths (their
        constraint is the references' on every non-Dirichlet pair; a mouth may be Dirichlet)."""
        keep = np.ones(len(self.rows), dtype=bool)
        keep[np.isin(self.rows, self.level.mouth_rows())] = False
        return keep

    def pressure_error(self, force):
        """The discrete L²(Γc) error of the nodal pressure force_j / m_j (module documentation)."""
        m = self.level.nodal_measure()[self.rows]
        keep = self.judged_rows()
        d = force[self.rows] / m - self.at_rows["pressure"]
        return math.sqrt(float(np.sum((m * d * d)[keep])))
