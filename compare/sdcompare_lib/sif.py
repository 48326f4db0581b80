"""Stress intensity factors K_I, K_II at a crack tip by the interaction integral (issue 45).

Conventions (docs/elasticity.md, "Tips and mouths"): the tip frame (e₁, e₂) has e₁ along the crack's
last segment pointing ahead of the tip and e₂ = e₁ turned by +90°; (r, θ) are polar coordinates in
that frame, θ = +π on the face e₂ points into and θ = −π on the other. The crack is straight along
−e₁ within r_out of the tip. K_I, K_II are Williams' factors: σ₂₂(r, 0) ≈ K_I/√(2πr),
σ₁₂(r, 0) ≈ K_II/√(2πr). A face pressure p is the contact pressure −σ_νν ≥ 0 on the crack (the
same on both faces, [σν] = 0; no shear, the contact is frictionless): positive presses the faces
together.

The formula. With the actual field (u, σ = C ε(u), body force f) and Williams' field of mode m
with K_m = 1 (u^a, σ^a: docs/elasticity.md's asymptotics, exact for all r), the interaction
integral of the J-integral J = ∫_Γ (W n₁ − σ_ij n_j u_i,1) ds (Γ → the tip) in domain form is

    I_m = ∫_A (σ_ij u^a_i,1 + σ^a_ij u_i,1 − σ_ik ε^a_ik δ_1j) q_,j dA            (1)
          − ∫_A f_i u^a_i,1 q dA                                                   (2)
          − ∫_0^{r_out} p(r) q(r) [u^a_2,1](r) dr                                  (3)

in the tip frame (indices 1, 2 along e₁, e₂), with q a weight equal to 1 on r ≤ r_in and 0 on
r ≥ r_out, A the disc r < r_out minus the crack, and [u^a_2,1] = u^a_2,1(θ = π) − u^a_2,1(θ = −π)
on the faces at distance r behind the tip. Then (Irwin: J = (K_I² + K_II²)/E′)

    K_m = E′ I_m / 2.                                                               (4)

Derivation: the divergence theorem on A (outward normal m; q = 1 at the tip's small circle, 0 at
r_out) turns the contour integral into (1), plus ∫_A q (σ_ij u^a_i,1 + σ^a_ij u_i,1 −
W^int δ_1j)_,j dA, which equals (2) because σ^a is divergence-free and both fields obey the same
Hooke law (σ_ij ε^a_ij,1 + σ_ij,1 ε^a_ij = (σ_ij ε^a_ij),1), plus the faces' term
−∫ q (t_i u^a_i,1 + t^a_i u_i,1) ds with t = σm: Williams' faces are free (t^a = 0) and a pressure
gives t = −p m, m = −e₂ on the θ = π face and +e₂ on the θ = −π face, hence (3). For mode I,
[u^a_2,1] = −(κ + 1)/(2μ √(2πr)) (from the opening (κ + 1)/μ √(r/(2π))), so a positive pressure
adds to I_I; for mode II, [u^a_2,1] = 0: a frictionless contact changes K_II only through (1)
and (2). Without (3) a closed crack (faces pressed, p > 0) gets a spurious K_I < 0.

Plane strain and plane stress differ only in λ* (docs/elasticity.md): κ = (λ* + 3μ)/(λ* + μ)
(3 − 4ν, resp. (3 − ν)/(1 + ν)) and E′ = 4μ(λ* + μ)/(λ* + 2μ) (E/(1 − ν²), resp. E).

Two front ends: `sif_exact` integrates (1)–(3) for fields given as callables (Gauss–Legendre in
polar coordinates, the r^(−1/2) of (2) and (3) removed by r = s²); `sif_p1` for a vector P1 field
on a cracked triangulation, with q_h the P1 interpolant of the plateau weight (the identity holds
for any Lipschitz q equal to 1 near the tip, so q_h costs no accuracy), σ_h = C ε(u_h) per
triangle, and the faces' q_h and pressure piecewise linear between the crack's vertices.

numpy only.
"""
import math

import numpy as np

from sdshared import sdquad

# Gauss–Legendre points of the exact front end: in r over the ring, θ over (−π, π), and s = √r over
# each of [0, √r_in] and [√r_in, √r_out] for (2) and (3). Williams' fields are trigonometric in θ/2
# (degree ≤ 3 in sin, cos of θ/2 per factor, products of two of them: degree 6) and polynomial in
# √r times r^(-1/2) in r: 48 × 64 points integrate the test fields to round-off (test_sif.py
# checks K to 1e-10 against the closed forms).
EXACT_RADIAL_POINTS = 48
EXACT_ANGULAR_POINTS = 64
# Points per crack segment of the P1 front end's face term (3): the integrand in s = √r is a
# polynomial of degree ≤ 4 in s on each segment for a P1 pressure and weight, exact with 3.
FACE_POINTS_PER_SEGMENT = 6
# A vertex is on the crack's line behind the tip when its distance to the line is below this times
# r_out (mesh coordinates are written with %.17g, so crack vertices lie on it to round-off).
ON_LINE_TOL = 1e-10


def elastic_constants(lambda_in_plane, mu):
    """(κ, E′) of the in-plane law σ = λ* tr ε I + 2μ ε: κ = (λ* + 3μ)/(λ* + μ),
    E′ = 4μ(λ* + μ)/(λ* + 2μ)."""
    lam = float(lambda_in_plane)
    mu = float(mu)
    if not mu > 0.0 or not lam + mu > 0.0:
        raise ValueError(f"material: need mu > 0 and lambda + mu > 0, got lambda = {lam}, "
                         f"mu = {mu}")
    return (lam + 3.0 * mu) / (lam + mu), 4.0 * mu * (lam + mu) / (lam + 2.0 * mu)


def material_from_young(e, nu, plane="strain"):
    """The material mapping the SIF functions take, in scene.json's `problem` form
    (docs/elasticity.md): {"plane", "E", "nu", "lambda", "mu", "lambda_in_plane", "kolosov",
    "e_prime"} from Young's modulus and Poisson's ratio."""
    if plane not in ("strain", "stress"):
        raise ValueError(f"plane must be 'strain' or 'stress', got {plane!r}")
    lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
    mu = e / (2.0 * (1.0 + nu))
    lam_in = lam if plane == "strain" else 2.0 * lam * mu / (lam + 2.0 * mu)
    kappa, e_prime = elastic_constants(lam_in, mu)
    return {"plane": plane, "E": e, "nu": nu, "lambda": lam, "mu": mu,
            "lambda_in_plane": lam_in, "kolosov": kappa, "e_prime": e_prime}


def _lame(material):
    """(λ*, μ, κ, E′) of a material mapping (keys lambda_in_plane, mu)."""
    lam, mu = float(material["lambda_in_plane"]), float(material["mu"])
    kappa, e_prime = elastic_constants(lam, mu)
    return lam, mu, kappa, e_prime


def tip_frame(e1):
    """The rotation R with rows e₁, e₂ (e₂ = e₁ turned by +90°): tip-frame components a′ = R a,
    tensors T′ = R T Rᵀ. e1 need not be normalised."""
    e1 = np.asarray(e1, dtype=float)
    n = math.hypot(e1[0], e1[1])
    if not n > 0.0:
        raise ValueError(f"e1 must be a nonzero vector, got {e1.tolist()}")
    c, s = e1[0] / n, e1[1] / n
    return np.array([[c, s], [-s, c]])


def hooke(grad, lam, mu):
    """σ (…, 2, 2) of the in-plane law from ∇u (…, 2, 2), [i, j] = ∂u_i/∂x_j."""
    eps = 0.5 * (grad + np.swapaxes(grad, -1, -2))
    tr = eps[..., 0, 0] + eps[..., 1, 1]
    sig = 2.0 * mu * eps
    sig[..., 0, 0] += lam * tr
    sig[..., 1, 1] += lam * tr
    return sig


def _williams_angular(mode, theta, kappa, mu):
    """Williams' u = √r (F₁(θ), F₂(θ)) with K = 1: F and dF/dθ, each (2, …)."""
    c = 1.0 / (2.0 * mu * math.sqrt(2.0 * math.pi))
    h = 0.5 * theta
    ch, sh, ct, st = np.cos(h), np.sin(h), np.cos(theta), np.sin(theta)
    if mode == 1:
        # u₁ = c √r cos(θ/2)(κ − cos θ), u₂ = c √r sin(θ/2)(κ − cos θ)
        f = [c * ch * (kappa - ct), c * sh * (kappa - ct)]
        df = [c * (-0.5 * sh * (kappa - ct) + ch * st), c * (0.5 * ch * (kappa - ct) + sh * st)]
    elif mode == 2:
        # u₁ = c √r sin(θ/2)(κ + 2 + cos θ), u₂ = −c √r cos(θ/2)(κ − 2 + cos θ)
        f = [c * sh * (kappa + 2.0 + ct), -c * ch * (kappa - 2.0 + ct)]
        df = [c * (0.5 * ch * (kappa + 2.0 + ct) - sh * st),
              c * (0.5 * sh * (kappa - 2.0 + ct) + ch * st)]
    else:
        raise ValueError(f"Williams mode must be 1 or 2, got {mode!r}")
    return np.array(f), np.array(df)


def williams_displacement(mode, r, theta, material):
    """Williams' displacement of mode 1 or 2 with K = 1 in the tip frame, (…, 2): u = √r F(θ)."""
    _, mu, kappa, _ = _lame(material)
    f, _ = _williams_angular(mode, np.asarray(theta, dtype=float), kappa, mu)
    return np.moveaxis(np.sqrt(r) * f, 0, -1)


def williams_gradient(mode, r, theta, material):
    """∇u (…, 2, 2), [i, j] = ∂u_i/∂x_j, of Williams' mode 1 or 2 with K = 1 in the tip frame:
    ∂₁u = (cos θ F/2 − sin θ F′)/√r, ∂₂u = (sin θ F/2 + cos θ F′)/√r."""
    _, mu, kappa, _ = _lame(material)
    theta = np.asarray(theta, dtype=float)
    f, df = _williams_angular(mode, theta, kappa, mu)
    rs = np.sqrt(r)
    d1 = (np.cos(theta) * f / 2.0 - np.sin(theta) * df) / rs
    d2 = (np.sin(theta) * f / 2.0 + np.cos(theta) * df) / rs
    return np.moveaxis(np.array([[d1[0], d2[0]], [d1[1], d2[1]]]), (0, 1), (-2, -1))


def plateau(r, r_in, r_out):
    """The weight q(r): 1 on r ≤ r_in, (r_out − r)/(r_out − r_in) between, 0 on r ≥ r_out."""
    return np.clip((r_out - np.asarray(r, dtype=float)) / (r_out - r_in), 0.0, 1.0)


def _check_ring(r_in, r_out):
    if not (0.0 < r_in < r_out and math.isfinite(r_out)):
        raise ValueError(f"ring: need 0 < r_in < r_out, got r_in = {r_in}, r_out = {r_out}")


def _domain_integrand(grad, sig, grad_a, sig_a, dq):
    """The integrand of (1) in the tip frame: grad, sig, grad_a, sig_a (…, 2, 2), dq (…, 2)."""
    eps_a = 0.5 * (grad_a + np.swapaxes(grad_a, -1, -2))
    t1 = np.einsum("...ij,...i,...j->...", sig, grad_a[..., :, 0], dq)
    t2 = np.einsum("...ij,...i,...j->...", sig_a, grad[..., :, 0], dq)
    w = np.einsum("...ik,...ik->...", sig, eps_a)
    return t1 + t2 - w * dq[..., 0]


def _face_jump_d1u2(mode, r, material):
    """[u^a_2,1] = u^a_2,1(θ = π) − u^a_2,1(θ = −π) at distance r behind the tip."""
    up = williams_gradient(mode, r, np.full_like(r, math.pi), material)[..., 1, 0]
    dn = williams_gradient(mode, r, np.full_like(r, -math.pi), material)[..., 1, 0]
    return up - dn


def _to_global(tip, rot, x1, x2):
    """Global coordinates of tip-frame points (x1, x2)."""
    return tip[0] + rot[0, 0] * x1 + rot[1, 0] * x2, tip[1] + rot[0, 1] * x1 + rot[1, 1] * x2


def _gauss(a, b, n):
    g, w = np.polynomial.legendre.leggauss(n)
    return 0.5 * (b - a) * g + 0.5 * (a + b), 0.5 * (b - a) * w


def _sqrt_rule(a, b, n):
    """Points r and weights on [a, b] of ∫ g(r) dr by r = s² (Gauss in s on [√a, √b]): exact for
    g = polynomial(√r)/√r."""
    s, w = _gauss(math.sqrt(a), math.sqrt(b), n)
    return s * s, 2.0 * s * w


def _stress_tensor(s):
    """(σ_xx, σ_yy, σ_xy) → (…, 2, 2)."""
    sxx, syy, sxy = (np.asarray(c, dtype=float) for c in s)
    return np.stack([np.stack([sxx, sxy], -1), np.stack([sxy, syy], -1)], -2)


def _k_from_integrals(integrals, e_prime):
    return tuple(0.5 * e_prime * i for i in integrals)


def sif_exact(grad_u, stress, material, tip, e1, r_in, r_out, face_pressure=None,
              body_force=None):
    """(K_I, K_II) at `tip` of a field given by callables of global (x, y) arrays:
    grad_u(x, y) → [[∂u_x/∂x, ∂u_x/∂y], [∂u_y/∂x, ∂u_y/∂y]], stress(x, y) → (σ_xx, σ_yy, σ_xy),
    face_pressure(x, y) → p = −σ_νν on the crack behind the tip (None: free faces),
    body_force(x, y) → (f_x, f_y) (None: f = 0). e1 is the tip frame's e₁; the disc r < r_out must
    lie in the body and meet no other crack, the crack straight along −e₁ within it."""
    _check_ring(r_in, r_out)
    lam, mu, _, e_prime = _lame(material)
    tip = np.asarray(tip, dtype=float)
    rot = tip_frame(e1)
    # (1) on the ring, q′ = −1/(r_out − r_in) radially.
    r, wr = _gauss(r_in, r_out, EXACT_RADIAL_POINTS)
    th, wt = _gauss(-math.pi, math.pi, EXACT_ANGULAR_POINTS)
    rr, tt = np.meshgrid(r, th, indexing="ij")
    ww = np.outer(wr * r, wt)
    x, y = _to_global(tip, rot, rr * np.cos(tt), rr * np.sin(tt))
    grad = rot @ np.moveaxis(np.asarray(grad_u(x, y), dtype=float), (0, 1), (-2, -1)) @ rot.T
    sig = rot @ _stress_tensor(stress(x, y)) @ rot.T
    dq = -np.stack([np.cos(tt), np.sin(tt)], -1) / (r_out - r_in)
    integrals = []
    for mode in (1, 2):
        ga = williams_gradient(mode, rr, tt, material)
        sa = hooke(ga, lam, mu)
        integrals.append(np.sum(ww * _domain_integrand(grad, sig, ga, sa, dq)))
    # (2) and (3) over 0 < r < r_out, split at the plateau's kink.
    rd = np.concatenate([_sqrt_rule(0.0, r_in, EXACT_RADIAL_POINTS)[0],
                         _sqrt_rule(r_in, r_out, EXACT_RADIAL_POINTS)[0]])
    wd = np.concatenate([_sqrt_rule(0.0, r_in, EXACT_RADIAL_POINTS)[1],
                         _sqrt_rule(r_in, r_out, EXACT_RADIAL_POINTS)[1]])
    qd = plateau(rd, r_in, r_out)
    if body_force is not None:
        rr, tt = np.meshgrid(rd, th, indexing="ij")
        ww = np.outer(wd * rd * qd, wt)
        x, y = _to_global(tip, rot, rr * np.cos(tt), rr * np.sin(tt))
        f = np.moveaxis(np.asarray(body_force(x, y), dtype=float), 0, -1) @ rot.T
        for m, mode in enumerate((1, 2)):
            ga = williams_gradient(mode, rr, tt, material)
            integrals[m] -= np.sum(ww * np.einsum("...i,...i->...", f, ga[..., :, 0]))
    if face_pressure is not None:
        x, y = _to_global(tip, rot, -rd, np.zeros_like(rd))
        p = np.asarray(face_pressure(x, y), dtype=float)
        for m, mode in enumerate((1, 2)):
            integrals[m] -= np.sum(wd * qd * p * _face_jump_d1u2(mode, rd, material))
    return _k_from_integrals(integrals, e_prime)


# ---------------------------------------------------------------------------------------------
# P1 front end
# ---------------------------------------------------------------------------------------------

def pressure_along_crack(points, pressure, tip, e1):
    """A face pressure callable from nodal values on the crack behind the tip (e.g. the references'
    contact force λ_j over m_j, docs/elasticity.md): piecewise linear in the distance behind the
    tip, constant beyond the nodes at both ends (the tip's own row carries no value). points (n, 2),
    pressure (n,)."""
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    pressure = np.asarray(pressure, dtype=float).reshape(-1)
    if len(points) == 0 or len(points) != len(pressure):
        raise ValueError(f"pressure_along_crack: {len(points)} points, {len(pressure)} values")
    rot = tip_frame(e1)
    behind = -(points - np.asarray(tip, dtype=float)) @ rot[0]
    order = np.argsort(behind)
    s, v = behind[order], pressure[order]

    def p(x, y):
        d = -((np.asarray(x) - tip[0]) * rot[0, 0] + (np.asarray(y) - tip[1]) * rot[0, 1])
        return np.interp(d, s, v)

    return p


def _boundary_edges(tri):
    """The edges (k, 2) that belong to one triangle only (∂Ω and the crack's faces)."""
    e = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    uniq, count = np.unique(e, axis=0, return_counts=True)
    return uniq[count == 1]


def _weight_p1(loc, tri, r_in, r_out, tip):
    """q at the vertices: the plateau, and 1 on every vertex of the triangles at the tip (so that
    ∇q_h = 0 where Williams' fields are singular, whatever r_in is to the mesh: the identity holds
    for any such q). The tip must be a vertex."""
    dist = np.hypot(loc[:, 0], loc[:, 1])
    at_tip = dist <= ON_LINE_TOL * r_out
    if not at_tip.any():
        raise ValueError(f"sif_p1: the tip {list(tip)} is not a vertex of the mesh")
    q = plateau(dist, r_in, r_out)
    q[tri[at_tip[tri].any(axis=1)].ravel()] = 1.0
    return q


def _check_p1_ring(loc, tri, q, r_out, tip):
    """The ring's assumptions on the mesh: every boundary edge that q_h touches lies on the crack's
    line behind the tip, and every vertex of that line where q_h > 0 is on the crack's faces (a
    boundary edge): the disc does not reach past the crack's other end. Returns the faces'
    vertices (a mask)."""
    on_line = (np.abs(loc[:, 1]) <= ON_LINE_TOL * r_out) & (loc[:, 0] <= ON_LINE_TOL * r_out)
    edges = _boundary_edges(tri)
    bad = (q[edges] > 0.0).any(axis=1) & ~on_line[edges].all(axis=1)
    if bad.any():
        v = edges[bad][0]
        raise ValueError(f"sif_p1: the disc r < r_out = {r_out} around the tip {list(tip)} meets a "
                         f"boundary or crack edge off the tip's crack line (vertices {v.tolist()})")
    on_face = np.zeros(len(loc), dtype=bool)
    on_face[edges[on_line[edges].all(axis=1)].ravel()] = True
    past = on_line & ~on_face & (q > 0.0)
    if past.any():
        raise ValueError(f"sif_p1: the disc r < r_out = {r_out} around the tip {list(tip)} reaches "
                         f"past the crack's other end (vertex {int(np.argmax(past))})")
    return on_face


def _face_term_p1(loc, on_line, q, face_pressure, tip, rot, material):
    """(3) with q_h and p piecewise linear between the crack's vertices behind the tip."""
    dist = -loc[on_line, 0]
    qs = q[on_line]
    br, idx = np.unique(dist, return_index=True)
    qb = qs[idx]
    # up to the first crack vertex where q_h = 0 (beyond it q_h vanishes on the faces)
    last = np.argmax(qb == 0.0) if (qb == 0.0).any() else len(br) - 1
    br, qb = br[:last + 1], qb[:last + 1]
    out = [0.0, 0.0]
    for a, b, qa, qb_ in zip(br[:-1], br[1:], qb[:-1], qb[1:]):
        r, w = _sqrt_rule(a, b, FACE_POINTS_PER_SEGMENT)
        qr = qa + (qb_ - qa) * (r - a) / (b - a)
        x, y = _to_global(tip, rot, -r, np.zeros_like(r))
        p = np.asarray(face_pressure(x, y), dtype=float)
        for m, mode in enumerate((1, 2)):
            out[m] -= np.sum(w * qr * p * _face_jump_d1u2(mode, r, material))
    return out


def sif_p1(xy, tri, u, material, tip, e1, r_in, r_out, face_pressure=None, body_force=None):
    """(K_I, K_II) at `tip` of a vector P1 field u (n, 2) on the cracked triangulation (xy (n, 2),
    tri (m, 3); the tip a vertex, the crack's faces boundary edges of the mesh). q_h is the P1
    interpolant of the plateau weight, set to 1 on the triangles at the tip (whatever r_in);
    face_pressure and body_force as for `sif_exact` (see `pressure_along_crack` for a pressure from
    nodal values). The disc r < r_out (and the triangles at the tip) must meet the mesh's boundary
    only along the tip's crack line (checked: ValueError)."""
    u = np.asarray(u, dtype=float)

    def fields(idx, t, dlam, rot, bary):
        ul = u[t] @ rot.T  # tip-frame components, (m, 3, 2)
        grad = np.einsum("tki,tkj->tij", ul, dlam)
        lam, mu, _, _ = _lame(material)
        return grad[:, None], hooke(grad, lam, mu)[:, None]

    return _sif_on_mesh(xy, tri, fields, material, tip, e1, r_in, r_out, face_pressure,
                        body_force)


def sif_fields(xy, tri, grad, stress, material, tip, e1, r_in, r_out, face_pressure=None,
               body_force=None):
    """(K_I, K_II) at `tip` of fields given per triangle as P1 corner values in the global frame:
    grad (m, 3, 2, 2) the displacement gradient (grad[..., i, d] = ∂u_i/∂x_d) and stress
    (m, 3, 2, 2), both linear on each triangle of the cracked triangulation (xy, tri) (a mixed
    method's ∇_h u = A σ_h + γ_h J and σ_h). The rest as `sif_p1`: the same q_h, ring checks, face
    term and body force; the interaction integral's identity needs only that σ and ∇u obey the
    same Hooke law on its symmetric part, which a stress σ_h with ε_h = A σ_h does."""
    grad = np.asarray(grad, dtype=float)
    stress = np.asarray(stress, dtype=float)

    def fields(idx, t, dlam, rot, bary):
        g = np.einsum("qk,tkij->tqij", bary, grad[idx])
        sg = np.einsum("qk,tkij->tqij", bary, stress[idx])
        return rot @ g @ rot.T, rot @ sg @ rot.T

    return _sif_on_mesh(xy, tri, fields, material, tip, e1, r_in, r_out, face_pressure,
                        body_force)


def _sif_on_mesh(xy, tri, fields, material, tip, e1, r_in, r_out, face_pressure, body_force):
    """The interaction integral (1)–(3) on the triangles where q_h ≠ 0; fields(t, dlam, rot, bary)
    gives the tip-frame gradient and stress (m, 1 or nq, 2, 2) of the active triangles t (rows idx
    of tri)."""
    _check_ring(r_in, r_out)
    lam, mu, _, e_prime = _lame(material)
    xy = np.asarray(xy, dtype=float)
    tri = np.asarray(tri, dtype=np.int64)
    tip = np.asarray(tip, dtype=float)
    rot = tip_frame(e1)
    loc = (xy - tip) @ rot.T
    q = _weight_p1(loc, tri, r_in, r_out, tip)
    on_line = _check_p1_ring(loc, tri, q, r_out, tip)
    active = (q[tri] > 0.0).any(axis=1)
    t, qt = tri[active], q[tri[active]]
    p0, p1, p2 = loc[t[:, 0]], loc[t[:, 1]], loc[t[:, 2]]
    jac = np.stack([p1 - p0, p2 - p0], -1)  # columns: edges, tip frame
    det = jac[:, 0, 0] * jac[:, 1, 1] - jac[:, 0, 1] * jac[:, 1, 0]
    inv = np.stack([np.stack([jac[:, 1, 1], -jac[:, 0, 1]], -1),
                    np.stack([-jac[:, 1, 0], jac[:, 0, 0]], -1)], -2) / det[:, None, None]
    # ∇ of the barycentric λ1, λ2 are the rows of inv; λ0 = 1 − λ1 − λ2.
    dlam = np.stack([-inv[:, 0] - inv[:, 1], inv[:, 0], inv[:, 1]], 1)  # (m, 3, 2)
    dq = np.einsum("tk,tkj->tj", qt, dlam)
    ref, wref = sdquad.load_rule()
    bary = np.column_stack([1.0 - ref[:, 0] - ref[:, 1], ref[:, 0], ref[:, 1]])  # (nq, 3)
    grad, sig = fields(np.flatnonzero(active), t, dlam, rot, bary)
    pts = np.einsum("qk,tkj->tqj", bary, np.stack([p0, p1, p2], 1))
    w = np.abs(det)[:, None] * wref[None, :]
    r = np.hypot(pts[..., 0], pts[..., 1])
    theta = np.arctan2(pts[..., 1], pts[..., 0])
    # a triangle behind the tip lies on one face: its θ takes that face's sign (±π, never ∓π)
    cen = (p0 + p1 + p2) / 3.0
    behind = cen[:, 0] < 0.0
    side = np.where(cen[:, 1] > 0.0, 1.0, -1.0)[:, None]
    theta = np.where(behind[:, None], side * np.abs(theta), theta)
    has_dq = np.any(dq != 0.0, axis=1)
    qq = bary @ qt.T  # (nq, m)
    if body_force is not None:
        gx, gy = _to_global(tip, rot, pts[..., 0], pts[..., 1])
        f = np.moveaxis(np.asarray(body_force(gx, gy), dtype=float), 0, -1) @ rot.T
    integrals = []
    for mode in (1, 2):
        ga = williams_gradient(mode, r, theta, material)
        sa = hooke(ga, lam, mu)
        dom = _domain_integrand(grad, sig, ga, sa, dq[:, None])
        total = np.sum((w * dom)[has_dq])
        if body_force is not None:
            total -= np.sum(w * qq.T * np.einsum("tqi,tqi->tq", f, ga[..., :, 0]))
        integrals.append(total)
    if face_pressure is not None:
        face = _face_term_p1(loc, on_line, q, face_pressure, tip, rot, material)
        integrals = [a + b for a, b in zip(integrals, face)]
    return _k_from_integrals(integrals, e_prime)
