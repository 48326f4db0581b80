"""Tests of compare/sdcompare_lib/sif.py, the stress intensity factors by the interaction integral.

Run: /usr/bin/python3 -m pytest -q -p no:cacheprovider compare/tests/test_sif.py

Exact fields (sif_exact): Williams' modes I, II and mixed, Westergaard's Griffith crack, the closed
crack with frictionless slip (whose K_I = 0 needs the crack-face term), on rotated and translated
tips, in plane strain and plane stress, for several rings. The P1 front end (sif_p1) on the nodal
interpolants of exact fields on structured cracked meshes, uniform and graded: K converges at order
2 in h (docs/elasticity.md, "Stress intensity factors": on an interpolant the functional's error is
that of a smooth field on the ring).
"""
import math

import numpy as np
import pytest

from sdcompare_lib import sif

STRAIN = sif.material_from_young(1.0, 0.3, "strain")
STRESS = sif.material_from_young(1.0, 0.3, "stress")
# sif_exact integrates Williams' and Westergaard's fields to round-off (sums of ~10⁴ terms of size
# ≤ 10: ~1e-13); 1e-10 leaves room for the platform's libm.
EXACT_TOL = 1e-10


# ---------------------------------------------------------------------------------------------
# exact fields as callables of global (x, y): grad_u → [[ux_x, ux_y], [uy_x, uy_y]], stress → (sxx,
# syy, sxy)
# ---------------------------------------------------------------------------------------------

def rotation(alpha):
    c, s = math.cos(alpha), math.sin(alpha)
    return np.array([[c, -s], [s, c]])


def placed(grad_local, material, tip=(0.0, 0.0), alpha=0.0):
    """grad_u, stress of a field given in a frame with its tip at the origin (grad_local(x, y) →
    (…, 2, 2)), moved to `tip` and turned by `alpha`: u(x) = Q u_loc(Qᵀ(x − tip))."""
    q = rotation(alpha)

    def grad(x, y):
        lx = q[0, 0] * (x - tip[0]) + q[1, 0] * (y - tip[1])
        ly = q[0, 1] * (x - tip[0]) + q[1, 1] * (y - tip[1])
        return np.moveaxis(q @ grad_local(lx, ly) @ q.T, (-2, -1), (0, 1))

    def stress(x, y):
        s = sif.hooke(np.moveaxis(grad(x, y), (0, 1), (-2, -1)), material["lambda_in_plane"],
                      material["mu"])
        return s[..., 0, 0], s[..., 1, 1], s[..., 0, 1]

    return grad, stress, q[:, 0]


def williams(k1, k2, material):
    def grad(x, y):
        r, t = np.hypot(x, y), np.arctan2(y, x)
        return (k1 * sif.williams_gradient(1, r, t, material)
                + k2 * sif.williams_gradient(2, r, t, material))
    return grad


def westergaard(sigma, a, material):
    """Griffith's crack [−a, a] × {0} under remote biaxial tension σ∞ (Westergaard,
    Z = σ∞ z/√(z² − a²), cut on the crack): 2μ u_x = (κ − 1)/2 Re Z̄ − y Im Z,
    2μ u_y = (κ + 1)/2 Im Z̄ − y Re Z, Z̄ = σ∞ √(z² − a²)."""
    mu, kappa = material["mu"], material["kolosov"]

    def grad(x, y):
        z = x + 1j * y
        w = np.sqrt(z - a) * np.sqrt(z + a)
        zz, dz = sigma * z / w, -sigma * a * a / w ** 3
        # ∂x Re F = Re F′, ∂y Re F = −Im F′, ∂x Im F = Im F′, ∂y Im F = Re F′
        g = np.array([
            [(kappa - 1) / 2 * zz.real - y * dz.imag, -(kappa - 1) / 2 * zz.imag - zz.imag - y * dz.real],
            [(kappa + 1) / 2 * zz.imag - y * dz.real, (kappa + 1) / 2 * zz.real - zz.real + y * dz.imag],
        ]) / (2 * mu)
        return np.moveaxis(g, (0, 1), (-2, -1))
    return grad


C_SLIP, K2_SLIP = 0.1, 1.0


def closed_slip(material):
    """u_C = c(0.3 sin x cos y, −sin y (2 + cos x)) + K_II × Williams mode II, tip at the origin,
    crack along −x; with f = −div σ(u_C) and the pressure −σ_yy(u_C) on y = 0 (mode II is free
    there)."""
    lam, mu, c = material["lambda_in_plane"], material["mu"], C_SLIP
    w2 = williams(0.0, K2_SLIP, material)

    def grad(x, y):
        gc = np.array([[0.3 * c * np.cos(x) * np.cos(y), -0.3 * c * np.sin(x) * np.sin(y)],
                       [c * np.sin(x) * np.sin(y), -c * np.cos(y) * (2 + np.cos(x))]])
        return np.moveaxis(gc, (0, 1), (-2, -1)) + w2(x, y)

    def force(x, y):
        return (-c * (0.7 * lam + 0.1 * mu) * np.sin(x) * np.cos(y),
                -c * ((2 * lam + 4 * mu) + (0.7 * lam + 2.7 * mu) * np.cos(x)) * np.sin(y))

    def pressure(x, y):
        return c * ((2 * lam + 4 * mu) + (0.7 * lam + 2 * mu) * np.cos(x)) + 0 * y

    return grad, force, pressure


# ---------------------------------------------------------------------------------------------
# Williams' auxiliary fields themselves
# ---------------------------------------------------------------------------------------------

def textbook_stress(mode, r, t):
    """Williams' stresses with K = 1 (Anderson, Fracture Mechanics, table 2.1/2.2)."""
    a = 1 / np.sqrt(2 * np.pi * r)
    c, s, c3, s3 = np.cos(t / 2), np.sin(t / 2), np.cos(3 * t / 2), np.sin(3 * t / 2)
    if mode == 1:
        return a * c * (1 - s * s3), a * c * (1 + s * s3), a * c * s * c3
    return -a * s * (2 + c * c3), a * s * c * c3, a * c * (1 - s * s3)


@pytest.mark.parametrize("material", [STRAIN, STRESS], ids=["strain", "stress"])
@pytest.mark.parametrize("mode", [1, 2])
def test_williams_fields_are_the_textbook_ones(mode, material):
    rng = np.random.default_rng(mode)
    r, t = rng.uniform(0.01, 2.0, 50), rng.uniform(-math.pi, math.pi, 50)
    g = sif.williams_gradient(mode, r, t, material)
    s = sif.hooke(g, material["lambda_in_plane"], material["mu"])
    for got, want in zip((s[:, 0, 0], s[:, 1, 1], s[:, 0, 1]), textbook_stress(mode, r, t)):
        assert np.max(np.abs(got - want)) < 1e-13
    # ∇u against central differences of u (polar → Cartesian), equilibrium by differences of σ
    h = 1e-6
    x, y = r * np.cos(t), r * np.sin(t)

    def u(x, y):
        return sif.williams_displacement(mode, np.hypot(x, y), np.arctan2(y, x), material)

    fd = np.stack([(u(x + h, y) - u(x - h, y)) / (2 * h), (u(x, y + h) - u(x, y - h)) / (2 * h)], -1)
    assert np.max(np.abs(fd - g)) < 1e-7

    def sig(x, y):
        return sif.hooke(sif.williams_gradient(mode, np.hypot(x, y), np.arctan2(y, x), material),
                         material["lambda_in_plane"], material["mu"])

    div = ((sig(x + h, y) - sig(x - h, y))[:, :, 0] + (sig(x, y + h) - sig(x, y - h))[:, :, 1]) / (2 * h)
    assert np.max(np.abs(div)) < 1e-5


@pytest.mark.parametrize("material", [STRAIN, STRESS], ids=["strain", "stress"])
def test_williams_faces_are_free_and_open_as_the_contract_says(material):
    r = np.array([1e-4, 0.1, 0.7])
    kappa, mu = material["kolosov"], material["mu"]
    for mode in (1, 2):
        for t in (math.pi, -math.pi):
            s = sif.hooke(sif.williams_gradient(mode, r, np.full(3, t), material),
                          material["lambda_in_plane"], material["mu"])
            assert np.max(np.abs(s[:, 1, :])) < 1e-12  # σ₂₂ = σ₁₂ = 0: free faces
        jump = (sif.williams_displacement(mode, r, np.full(3, math.pi), material)
                - sif.williams_displacement(mode, r, np.full(3, -math.pi), material))
        want = (kappa + 1) / mu * np.sqrt(r / (2 * math.pi))
        # mode I opens ([u₂] = (κ + 1)/μ √(r/2π)), mode II slips ([u₁] the same), neither both
        assert np.allclose(jump[:, 2 - mode], want, rtol=1e-14, atol=0)
        assert np.max(np.abs(jump[:, mode - 1])) < 1e-15
    # κ, E′ of docs/elasticity.md
    nu = 0.3
    if material["plane"] == "strain":
        assert abs(kappa - (3 - 4 * nu)) < 1e-14 and abs(material["e_prime"] - 1 / (1 - nu ** 2)) < 1e-14
    else:
        assert abs(kappa - (3 - nu) / (1 + nu)) < 1e-14 and abs(material["e_prime"] - 1.0) < 1e-14


# ---------------------------------------------------------------------------------------------
# sif_exact
# ---------------------------------------------------------------------------------------------

@pytest.mark.parametrize("k1, k2", [(1.0, 0.0), (0.0, 1.0), (1.0, 0.5), (-0.3, 2.0)])
@pytest.mark.parametrize("tip, alpha", [((0.0, 0.0), 0.0), ((0.3, -0.2), 2.1)])
def test_williams_sifs(k1, k2, tip, alpha):
    grad, stress, e1 = placed(williams(k1, k2, STRAIN), STRAIN, tip, alpha)
    got = sif.sif_exact(grad, stress, STRAIN, tip, e1, 0.1, 0.4)
    assert abs(got[0] - k1) < EXACT_TOL and abs(got[1] - k2) < EXACT_TOL


def test_plane_stress_needs_its_own_constants():
    """A plane-stress Williams field gives its K with the plane-stress material; with plane
    strain's (another κ in u^a, another E′) K_I is off by 2.5 %."""
    grad, stress, e1 = placed(williams(1.0, 0.5, STRESS), STRESS)
    got = sif.sif_exact(grad, stress, STRESS, (0, 0), e1, 0.1, 0.4)
    assert abs(got[0] - 1.0) < EXACT_TOL and abs(got[1] - 0.5) < EXACT_TOL
    wrong = sif.sif_exact(grad, stress, STRAIN, (0, 0), e1, 0.1, 0.4)
    assert abs(wrong[0] - 1.0) > 0.02


@pytest.mark.parametrize("r_in, r_out", [(0.05, 0.2), (0.1, 0.4), (0.2, 0.9), (0.5, 0.8)])
def test_griffith_both_tips_and_any_ring(r_in, r_out):
    """K_I = σ∞ √(πa), K_II = 0 at both tips of Westergaard's crack, on rings up to 0.9 of the
    way to the other tip (2a = 1 away; at 0.95 the other tip's r^(-1/2) costs the Gauss rule 1e-9),
    turned and moved with the crack."""
    a, sigma = 0.5, 1.3
    want = sigma * math.sqrt(math.pi * a)
    for alpha in (0.0, 0.7):
        grad, stress, e1 = placed(westergaard(sigma, a, STRAIN), STRAIN, (0.1, 0.2), alpha)
        q = rotation(alpha)
        for end in (1.0, -1.0):
            tip = np.array([0.1, 0.2]) + q @ [end * a, 0.0]
            got = sif.sif_exact(grad, stress, STRAIN, tip, end * e1, r_in, r_out)
            assert abs(got[0] - want) < EXACT_TOL and abs(got[1]) < EXACT_TOL


@pytest.mark.parametrize("material", [STRAIN, STRESS], ids=["strain", "stress"])
def test_closed_crack_needs_the_face_term(material):
    """Closed with frictionless slip: K_I = 0 and K_II given only with the face pressure and the
    body force; without the face term K_I is −0.3 (a compressed crack read as a negative mode I),
    without f K_I is off by 8e-3."""
    grad_l, force, pressure = closed_slip(material)
    grad, stress, e1 = placed(grad_l, material)
    for r_in, r_out in ((0.1, 0.4), (0.2, 0.9)):
        got = sif.sif_exact(grad, stress, material, (0, 0), e1, r_in, r_out,
                            face_pressure=pressure, body_force=force)
        assert abs(got[0]) < EXACT_TOL and abs(got[1] - K2_SLIP) < EXACT_TOL
    no_face = sif.sif_exact(grad, stress, material, (0, 0), e1, 0.1, 0.4, body_force=force)
    assert no_face[0] < -0.1
    no_force = sif.sif_exact(grad, stress, material, (0, 0), e1, 0.1, 0.4, face_pressure=pressure)
    assert abs(no_force[0]) > 1e-3


def test_a_pressurised_crack_has_a_positive_k1():
    """Griffith's crack with the remote tension removed (Westergaard minus the uniform biaxial
    σ∞): its faces carry the pressure σ∞ (positive: pushing them apart from inside) and K_I is
    still σ∞ √(πa) (superposition), found only with the face term."""
    a, sigma = 0.5, 1.0
    grad_w = westergaard(sigma, a, STRAIN)
    lam, mu = STRAIN["lambda_in_plane"], STRAIN["mu"]
    eps0 = sigma / (2 * (lam + mu))  # the uniform strain of σ = σ∞ I

    def grad_l(x, y):
        return grad_w(x, y) - eps0 * np.eye(2)

    grad, stress, e1 = placed(grad_l, STRAIN)
    got = sif.sif_exact(grad, stress, STRAIN, (a, 0.0), e1, 0.1, 0.4,
                        face_pressure=lambda x, y: np.full_like(x, sigma))
    assert abs(got[0] - sigma * math.sqrt(math.pi * a)) < EXACT_TOL and abs(got[1]) < EXACT_TOL
    free = sif.sif_exact(grad, stress, STRAIN, (a, 0.0), e1, 0.1, 0.4)
    assert abs(free[0] - sigma * math.sqrt(math.pi * a)) > 0.1


def test_bad_rings_are_refused():
    grad, stress, e1 = placed(williams(1.0, 0.0, STRAIN), STRAIN)
    for r_in, r_out in ((0.0, 0.4), (0.4, 0.4), (0.5, 0.4)):
        with pytest.raises(ValueError, match="ring"):
            sif.sif_exact(grad, stress, STRAIN, (0, 0), e1, r_in, r_out)
    with pytest.raises(ValueError, match="e1"):
        sif.sif_exact(grad, stress, STRAIN, (0, 0), (0, 0), 0.1, 0.4)


# ---------------------------------------------------------------------------------------------
# sif_p1 on interpolants
# ---------------------------------------------------------------------------------------------

def cracked_square(n, beta=None):
    """(xy, tri, face) of (−1, 1)² in n × n cells (n even; diagonals towards the centre's
    quadrants), the edge crack y = 0, x ≤ 0 cut open: its vertices but the tip doubled, the
    triangles below using the copies. face: +1 on the + face's vertices (the originals), −1 on
    the copies, 0 elsewhere. beta: the square-ring grading p ↦ p ‖p‖∞^(1/β − 1) towards the tip
    (it keeps y = 0 and ∂Ω; h_T ≈ h r^(1 − β))."""
    s = np.linspace(-1.0, 1.0, n + 1)
    gx, gy = np.meshgrid(s, s, indexing="ij")
    xy = np.column_stack([gx.ravel(), gy.ravel()])
    if beta is not None:
        xy = xy * (np.max(np.abs(xy), axis=1) ** (1.0 / beta - 1.0))[:, None]
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    i, j = i.ravel(), j.ravel()
    a, b = i * (n + 1) + j, (i + 1) * (n + 1) + j
    c, d = b + 1, a + 1
    same = (i < n // 2) == (j < n // 2)
    tri = np.concatenate([np.where(same[:, None], np.column_stack([a, b, c]), np.column_stack([a, b, d])),
                          np.where(same[:, None], np.column_stack([a, c, d]), np.column_stack([b, c, d]))])
    crack = np.arange(n // 2) * (n + 1) + n // 2
    copy = np.full(len(xy), -1)
    copy[crack] = len(xy) + np.arange(len(crack))
    below = xy[tri].mean(axis=1)[:, 1] < 0.0
    sub = tri[below]
    tri[below] = np.where(copy[sub] >= 0, copy[sub], sub)
    face = np.zeros(len(xy) + len(crack), dtype=int)
    face[crack], face[len(xy):] = 1, -1
    return np.vstack([xy, xy[crack]]), tri, face


def face_angle(xy, face):
    """θ per vertex, ±π on the crack's copies."""
    t = np.arctan2(xy[:, 1], xy[:, 0])
    return np.where(face == 1, math.pi, np.where(face == -1, -math.pi, t))


def williams_interpolant(xy, face, k1, k2, material=STRAIN):
    r, t = np.hypot(xy[:, 0], xy[:, 1]), face_angle(xy, face)
    return (k1 * sif.williams_displacement(1, r, t, material)
            + k2 * sif.williams_displacement(2, r, t, material))


def closed_slip_interpolant(xy, face):
    x, y = xy[:, 0], xy[:, 1]
    uc = C_SLIP * np.column_stack([0.3 * np.sin(x) * np.cos(y), -np.sin(y) * (2 + np.cos(x))])
    return uc + williams_interpolant(xy, face, 0.0, K2_SLIP)


def errors(n, beta, field, want, **kw):
    xy, tri, face = cracked_square(n, beta)
    got = sif.sif_p1(xy, tri, field(xy, face), STRAIN, (0.0, 0.0), (1.0, 0.0), 0.2, 0.6, **kw)
    return np.abs(np.array(got) - want)


@pytest.mark.parametrize("beta", [None, 0.4], ids=["uniform", "graded"])
def test_p1_interpolant_of_williams_converges_at_order_2(beta):
    """The interpolant of K_I = 1, K_II = 0.5: at n = 64 K within 3e-4 (measured 1.3e-4 uniform,
    2.5e-4 graded; the bound is the derivation's C h² with the measured C and a factor ~1.2), and
    the error falls at order 2 (measured 2.01, 2.05 uniform; 2.00, 2.00 graded, n = 32 → 64)."""
    def field(xy, face):
        return williams_interpolant(xy, face, 1.0, 0.5)

    coarse, fine = errors(32, beta, field, [1.0, 0.5]), errors(64, beta, field, [1.0, 0.5])
    assert np.all(fine < 3e-4), fine
    assert np.all(np.log2(coarse / fine) > 1.8), np.log2(coarse / fine)


def test_p1_closed_slip_with_nodal_pressure():
    """The closed crack's interpolant with the pressure from nodal values on the crack (as the
    references' λ_j/m_j give it, docs/elasticity.md) and the exact f: K_I → 0 and K_II → 1 at order
    2; without the face term K_I stays near −0.3."""
    _, force, pressure = closed_slip(STRAIN)

    def nodal(n):
        xy, _, face = cracked_square(n)
        on = (face == 1) & (xy[:, 0] < 0.0)
        return sif.pressure_along_crack(xy[on], pressure(xy[on, 0], xy[on, 1]), (0, 0), (1, 0))

    want = [0.0, K2_SLIP]
    coarse = errors(32, None, closed_slip_interpolant, want, face_pressure=nodal(32), body_force=force)
    fine = errors(64, None, closed_slip_interpolant, want, face_pressure=nodal(64), body_force=force)
    assert np.all(fine < 3e-4), fine
    assert np.all(np.log2(coarse / fine) > 1.8), np.log2(coarse / fine)
    no_face = errors(64, None, closed_slip_interpolant, want, body_force=force)
    assert no_face[0] > 0.1


def test_pressure_along_crack_interpolates_in_the_distance_behind_the_tip():
    p = sif.pressure_along_crack([[-0.5, 0.0], [-0.1, 0.0], [-0.3, 0.0]], [5.0, 1.0, 3.0],
                                 (0.0, 0.0), (1.0, 0.0))
    x = np.array([-0.6, -0.5, -0.4, -0.2, -0.05, 0.0])
    assert np.allclose(p(x, 0 * x), [5.0, 5.0, 4.0, 2.0, 1.0, 1.0], rtol=0, atol=1e-14)
    with pytest.raises(ValueError):
        sif.pressure_along_crack([[0.0, 0.0]], [1.0, 2.0], (0, 0), (1, 0))


def test_p1_refuses_rings_it_cannot_integrate():
    xy, tri, face = cracked_square(16)
    u = williams_interpolant(xy, face, 1.0, 0.0)
    with pytest.raises(ValueError, match="boundary or crack edge"):
        sif.sif_p1(xy, tri, u, STRAIN, (0, 0), (1, 0), 0.2, 1.2)  # reaches ∂Ω
    with pytest.raises(ValueError, match="r_in is smaller"):
        sif.sif_p1(xy, tri, u, STRAIN, (0, 0), (1, 0), 0.1, 0.5)  # h = 1/8: the tip's triangles
    with pytest.raises(ValueError, match="not a vertex"):
        sif.sif_p1(xy, tri, u, STRAIN, (0.01, 0), (1, 0), 0.3, 0.5)
    # a "tip" whose crack line is not the mesh's crack: the faces are off its line
    with pytest.raises(ValueError, match="boundary or crack edge"):
        sif.sif_p1(xy, tri, u, STRAIN, (0, 0), (0, 1), 0.2, 0.6)
