"""The discrete certificate: do the stored u, p, bubbles and λ solve the method's discrete system?

This module assembles the smooth-domain method's discrete equations itself — in numpy, from the
scene's f and g (sdexpr) and the stored mesh of each case (fields.h5 / verification.h5), with its
own quadrature — and evaluates their residuals at the stored fields. It is written from the
equations of docs/design.md (*Discrete system*, *The p spaces*, *The lumped p mass*, *Multipliers
and the LCP*) and docs/scenes.md, not from the solver's code, so that a bug in one is not a bug in
both.

**The equations** (weak form (15), docs/design.md), on the stored mesh of the case (the cracked mesh
for the broken u), for every test function:

* u rows (first equation), v = φ_i a P1 hat of the u space (both copies of a crack vertex for the
  broken u):  δ(u, v) − (v, div p) = (f, v);
* p rows (second equation), q a vertex function of X_h:
  (p, q) + (u, div q) + ∫_Γc λ q·ν ds = ∫_Γ g q·n ds, div taken triangle by triangle;
* bubble rows, q = b_T e_x, b_T e_y with b_T = 27 λ0 λ1 λ2 (zero on every edge: no boundary or
  crack term): (p, b_T e) + (u, div(b_T e)) = 0.

p on a triangle is Σ_k p_k λ_k + c_T b_T, p_k the stored `p` at the corner's u dof and c_T the
stored `p_bubble` (the coefficient of b_T = 27 λ0λ1λ2: the scaling of docs/design.md; the files
confirm it — with c_T read as the coefficient of λ0λ1λ2 instead, the bubble rows of every case fail
by a factor 27). The vertex functions of X_h are λ_v e_x, λ_v e_y on the patch of v; with the
broken-tangential p, at a doubled vertex (an interior crack node where the crack is straight, two u
copies) they are λ_v ν on the whole patch and λ_v τ on the triangles of each copy (τ = ν turned by
−90°): those rows are the (x, y) element contributions dotted with ν, resp. with τ and summed over
one copy's triangles only; their crack term is ∫ λ λ_v τ·ν = 0. The stored p must lie in the space:
equal at the copies of a vertex, except p·τ at a doubled vertex of the broken-tangential p.

The crack term, per multiplier (the stored `lambda`, docs/design.md and the README's field table):
M0 stores Λ_k per crack segment t_k, the term is Σ_k Λ_k ∫_{t_k} q·ν_k; M1 stores the nodal λ_h,
the term is ∫ λ_h q·ν with each segment's own ν (so two normals at a kink); M1star stores the
nodal λ_h = M_c⁻¹ Λ̃, the term is Σ_j Λ̃_j q(x_j)·ν̄_j with Λ̃ = M_c λ_h (M_c the P1 mass of the
crack, block diagonal over the cracks) and ν̄_j the normal of the node's row: ν at a straight node
and at a tip, at a kink (ℓ_{k−1}ν_{k−1} + ℓ_kν_k)/(ℓ_{k−1} + ℓ_k) — M1's row ∫ φ_j p·ν for a
constant p divided by the length ℓ_{k−1}/2 + ℓ_k/2 that the moment Λ̃_j = ∫ λ_h φ_j assumes, the
row issue 43 derived (`KINK_NORMAL`). ν of a segment is its direction (first crack point to last)
turned by +90°.

The lumped p mass (docs/design.md, *The lumped p mass*) is defined on the condensed system: per
triangle this module eliminates the bubble numerically from its own uncondensed element matrix
(Schur complement), and replaces the condensed p–p block G̃_T by its row-sum diagonal; B̃, C and δM
stay. The lumped p has no bubble.

The complementarity conditions, per multiplier: the multiplier μ (M0 Λ_k, M1 Λ_j, M1star Λ̃_j) is
≥ 0, the constraint on p is ≤ 0 (M0 ∫_{t_k} p·ν_k, M1 ∫ φ_j p·ν with each segment's ν, M1star
p(x_j)·ν̄_j) and their product vanishes.

**Tolerances.** Equations: each row i passes when
    |r_i| ≤ ROUNDOFF_FACTOR·ε·s_i + QUADRATURE_FACTOR·q_i,
s_i = (|K||x| + |b|)_i the componentwise (Oettli–Prager) scale of the row in this module's
uncondensed matrix K (for the lumped p the condensed one), x the stored values, b the load, the
boundary term and the crack term, plus the terms the bubble elimination moves into the p and u
rows, |K_cb K_bb⁻¹||K_bc||x_c| (condensation_weights): the solver solves the condensed system and
refines its solution to a componentwise backward error ≤ 1e-15 (~4.5ε) there (docs/design.md),
and the uncondensed u rows alone see the condensed stiffness (7/10)A|U| only through the small
bubble, c_T ~ ∇u_h − p: without those terms the clean backward error grows like h⁻² (7.6e-16 to
3.9e-14 over levels 0–3 of all-closed), with them it is ~2ε at every level. The two codes' entries
differ by their round-off (products of coordinates, 1/det, the reference integrals, the order of
summation): on the repository scenes the rows without a quadrature share reach ≤ 3.6ε, and
ROUNDOFF_FACTOR = 64 leaves a factor ≥ 15 (docs/verification.md, *The discrete certificate*).
Quadrature: q_i is the estimate of this module's quadrature error of the row's load ∫ f φ_i and
boundary term ∫_Γ g λ_v n ds, the sum over the row's triangles (edges) of the absolute difference
of two rules: on triangles the 55-point symmetric rule of degree 16 (sdquad; the value used) and a
5 × 5 conical product rule of degree 8, on edges Gauss–Legendre with 12 and 5 points (degree 9).
The low rules have the degrees of the solver's, measured: its loads and boundary terms agree
with them to round-off and with no rule of higher degree (docs/design.md), so QUADRATURE_FACTOR
= 4 bounds the solver's quadrature error by four times that of a rule of its degree (the factor
of docs/verification.md's *Quadrature tolerances*: the difference of two rules is at least 1/4 of
the lower rule's error); a solver whose rules were of a lower degree would fail. On smooth data
per triangle q is at round-off; where f jumps inside a triangle (a sign line that continues past
a crack's tip off the mesh lines) neither rule is accurate and the rows of those triangles are
held to the estimate only.
Complementarity: where the crack is open, the constraint on p vanishes only to the forward error
of the solve, ≤ κ·(backward error)·‖x‖ with κ the case's `condition_estimate` (a lower bound of
κ₁ "usually within 3×", docs/design.md): the constraint, the multiplier's sign and their product,
scaled as the solver's KKT residuals (by ‖S‖∞‖P‖∞ and ‖μ‖∞), pass when ≤ COMPLEMENTARITY_FACTOR·κ·ε
+ ROUNDOFF_FACTOR·ε; a case without a condition estimate is held to κ = 1e12.

**Cost.** It runs on the cases whose summary `unknowns` ≤ UNKNOWNS_LIMIT = 2·10⁴: an assembly bug
is a wrong coefficient in every element it touches, so it shows at every level, and the coarse
levels of every series are enough (issue 43). Vectorised numpy, no loop over triangles; the loads
and element matrices are computed once per mesh and shared by that mesh's cases.
"""
import math
import time

import numpy as np

from sdshared import sdexpr, sdquad
from .read import finite_number
from .cases import case_key, case_order
from .render import case_text

EPS = float(np.finfo(float).eps)
LABEL = "discrete certificate"
# Cases with more unknowns are not certified (module docstring: an assembly bug shows at every level).
UNKNOWNS_LIMIT = 20_000
# |r_i| ≤ ROUNDOFF_FACTOR·ε·(|K||x| + |b|)_i + QUADRATURE_FACTOR·q_i (module docstring).
ROUNDOFF_FACTOR = 64.0
QUADRATURE_FACTOR = 4.0
# Complementarity and the multiplier's sign: ≤ COMPLEMENTARITY_FACTOR·κ·ε (module docstring).
COMPLEMENTARITY_FACTOR = 64.0
KAPPA_WITHOUT_ESTIMATE = 1e12
# The stored p must be in X_h: copies of one vertex agree to MEMBERSHIP_FACTOR·ε·‖p‖∞ (the frame
# transform p = (p·ν)ν + (p·τ)τ of the broken-tangential p rounds each component once or twice).
MEMBERSHIP_FACTOR = 16.0
# Two crack segments meeting at a node are collinear (a straight node, doubled in the
# broken-tangential p) when the sine of their angle is below this: far above the round-off of
# float64 coordinates, far below any real kink.
COLLINEAR_SIN = 1e-12
# Rules: the conical product rule's points per direction (exact to degree 2n − 2) and the
# boundary edges' Gauss–Legendre points; the element matrices need degree 6 (bubble × bubble).
LOAD_CONICAL_N = 5
ELEMENT_CONICAL_N = 5
LINE_N = (5, 12)

EQUATIONS = {
    "u": "first equation of (15), δ(u,v) − (v, div p) = (f,v), tested with the P1 hats of u",
    "p": "second equation of (15), (p,q) + (u, div q) + ∫_Γc λ q·ν = ∫_Γ g q·n, tested with the "
         "vertex functions of X_h",
    "bubble": "second equation of (15) tested with the bubbles b_T e (b_T = 27λ0λ1λ2)",
    "sign": "the multiplier's sign",
    "constraint": "the constraint on p",
    "complementarity": "complementarity (multiplier × constraint = 0)",
    "space": "p in X_h (equal at the copies of a vertex; p·ν shared at a doubled vertex)",
}


# ------------------------------------------------------------------------------------- rules
def gauss01(n):
    """n-point Gauss–Legendre rule on [0, 1] (weights sum to 1)."""
    x, w = np.polynomial.legendre.leggauss(int(n))
    return (x + 1.0) / 2.0, w / 2.0


def conical_rule(n):
    """Conical product rule on a triangle: barycentric points L (n², 3), weights W (n²,) with
    Σ W = 1 (∫_T g ≈ |T| Σ W g). The square [0,1]² maps to the triangle by λ1 = s,
    λ2 = t(1 − s) (Jacobian 1 − s, the reference area 1/2): a polynomial of degree d becomes one
    of degree ≤ d + 1 in s and ≤ d in t, so n Gauss points each way are exact for d ≤ 2n − 2."""
    s, ws = gauss01(n)
    t, wt = gauss01(n)
    S, Tt = np.meshgrid(s, t, indexing="ij")
    l1 = S.ravel()
    l2 = (Tt * (1.0 - S)).ravel()
    W = (2.0 * np.outer(ws, wt) * (1.0 - S)).ravel()
    return np.column_stack([1.0 - l1 - l2, l1, l2]), W


def symmetric_rule():
    """The 55-point symmetric rule of degree 16 (sdquad: the references' load rule) as
    barycentric points and weights summing to 1."""
    pts, wts = sdquad.load_rule()
    return np.column_stack([1.0 - pts[:, 0] - pts[:, 1], pts[:, 0], pts[:, 1]]), 2.0 * wts


def reference_integrals(n=ELEMENT_CONICAL_N):
    """The element integrals divided by |T|, by quadrature (degree 2n − 2 ≥ 6): m (3,3) = ∫λaλb,
    one (3,) = ∫λa, lb (3,) = ∫λa b, bb = ∫b², b1 = ∫b, with b = 27λ0λ1λ2 (closed forms: |T|/12
    (1 + δ_ab), |T|/3, 3|T|/20, 81|T|/280, 9|T|/20; compare/tests/test_certificate.py)."""
    L, W = conical_rule(n)
    b = 27.0 * L[:, 0] * L[:, 1] * L[:, 2]
    return {"m": np.einsum("q,qa,qb->ab", W, L, L), "one": W @ L, "lb": np.einsum("q,qa,q->a", W, L, b),
            "bb": float(W @ (b * b)), "b1": float(W @ b)}


# ----------------------------------------------------------------------------------- geometry
def triangle_geometry(X):
    """(area (T,), grad (T,3,2)): the triangles' areas and the gradients of their barycentric
    coordinates, from the corner coordinates X (T,3,2) (either orientation)."""
    d1, d2 = X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    g1 = np.column_stack([d2[:, 1], -d2[:, 0]]) / det[:, None]
    g2 = np.column_stack([-d1[:, 1], d1[:, 0]]) / det[:, None]
    return np.abs(det) / 2.0, np.stack([-g1 - g2, g1, g2], axis=1)


def element_matrices(area, grad, delta, ref):
    """The uncondensed element matrices E (T, 11, 11) of the symmetric form, unknowns ordered
    [p_(k,e) at index 2k + e (6), c_e bubble (2), u_i (3)]: rows p_(k,e) (q = λ_k e):
    (p, q) + (u, div q); bubble rows (q = b e): (p, b e) + (u, div(b e)) = (p, b e) − (∂_e u, b);
    u rows (v = φ_i, the first equation times −1): (v, div p) − δ(u, v)."""
    T = len(area)
    E = np.zeros((T, 11, 11))
    A = area[:, None, None]
    I2 = np.eye(2)
    # p–p: ∫ λk λl e·e'
    E[:, :6, :6] = A * np.kron(ref["m"], I2)[None]
    # p–bubble and bubble–p: ∫ λk b
    pb = np.kron(ref["lb"][:, None], I2)  # (6, 2)
    E[:, :6, 6:8] = A * pb[None]
    E[:, 6:8, :6] = A * pb.T[None]
    E[:, 6:8, 6:8] = A * ref["bb"] * I2[None]
    # p rows, u columns: ∫ φ_i div(λk e) = ∂_e λk ∫ φ_i
    pu = area[:, None, None] * grad.reshape(T, 6)[:, :, None] * ref["one"][None, None, :]
    E[:, :6, 8:] = pu
    E[:, 8:, :6] = np.transpose(pu, (0, 2, 1))
    # bubble rows, u columns: ∫ φ_i ∂_e b = −∂_e φ_i ∫ b
    bu = -area[:, None, None] * ref["b1"] * np.transpose(grad, (0, 2, 1))  # (T, 2, 3)
    E[:, 6:8, 8:] = bu
    E[:, 8:, 6:8] = np.transpose(bu, (0, 2, 1))
    E[:, 8:, 8:] = -delta * A * ref["m"][None]
    return E


def inverse2(A):
    """Inverses of a batch of 2 × 2 matrices (T, 2, 2) in closed form (LAPACK's batched calls cost
    seconds on 10⁴ tiny matrices)."""
    det = A[:, 0, 0] * A[:, 1, 1] - A[:, 0, 1] * A[:, 1, 0]
    out = np.empty_like(A)
    out[:, 0, 0], out[:, 1, 1] = A[:, 1, 1] / det, A[:, 0, 0] / det
    out[:, 0, 1], out[:, 1, 0] = -A[:, 0, 1] / det, -A[:, 1, 0] / det
    return out


def lumped_element_matrices(E):
    """The lumped p mass's element matrices (T, 9, 9), unknowns [p (6), u (3)]: the bubble
    eliminated from E numerically (Schur complement, per element), then the condensed p–p block
    replaced by its row-sum diagonal (docs/design.md, *The lumped p mass*)."""
    keep = np.r_[0:6, 8:11]
    Ecc = E[:, keep][:, :, keep]
    Ecb = E[:, keep][:, :, 6:8]
    Ebc = E[:, 6:8][:, :, keep]
    Ebb = E[:, 6:8, 6:8]
    S = Ecc - Ecb @ (inverse2(Ebb) @ Ebc)
    rows = S[:, :6, :6].sum(axis=2)
    S[:, :6, :6] = 0.0
    S[:, np.arange(6), np.arange(6)] = rows
    return S


# ------------------------------------------------------------------------------------ loads
def load_on_triangles(f, X, area, rule):
    """(T, 3) ∫_T f λ_i by the rule (L, W) on every triangle."""
    L, W = rule
    pts = np.einsum("qa,tad->tqd", L, X)
    vals = f(pts[..., 0], pts[..., 1])
    return area[:, None] * np.einsum("tq,q,qa->ta", vals, W, L)


def boundary_edges(gtris, gxy):
    """(a, b, outward normal (E,2), length (E,)) of the edges of the uncracked topology (triangles
    gtris on the vertex groups gxy, the copies of a crack vertex one group) that lie in one
    triangle only: ∂Ω (a crack edge lies in two)."""
    e = np.concatenate([gtris[:, [0, 1]], gtris[:, [1, 2]], gtris[:, [2, 0]]])
    opp = np.concatenate([gtris[:, 2], gtris[:, 0], gtris[:, 1]])
    _, inv, cnt = np.unique(np.sort(e, axis=1), axis=0, return_inverse=True, return_counts=True)
    one = cnt[inv.ravel()] == 1
    a, b, c = e[one, 0], e[one, 1], opp[one]
    d = gxy[b] - gxy[a]
    length = np.hypot(d[:, 0], d[:, 1])
    n = np.column_stack([d[:, 1], -d[:, 0]]) / length[:, None]
    n[np.einsum("ed,ed->e", gxy[c] - gxy[a], n) > 0] *= -1.0
    return a, b, n, length


def boundary_term(g, gxy, edges, n_points):
    """Per boundary edge (a, b): ∫_edge g λ_a ds and ∫_edge g λ_b ds (Gauss–Legendre, n_points)."""
    a, b, n, length = edges
    s, w = gauss01(n_points)
    pts = gxy[a][:, None, :] + s[None, :, None] * (gxy[b] - gxy[a])[:, None, :]
    vals = g(pts[..., 0], pts[..., 1])
    return length * (vals @ (w * (1.0 - s))), length * (vals @ (w * s))


def scatter_edges(edges, va, vb, nv, absolute=False):
    """(nv, 2) Σ over boundary edges of va n at a and vb n at b (|va| |n| with absolute)."""
    a, b, n, _ = edges
    n = np.abs(n) if absolute else n
    out = np.zeros((nv, 2))
    np.add.at(out, a, va[:, None] * n)
    np.add.at(out, b, vb[:, None] * n)
    return out


# ------------------------------------------------------------------------------- the mesh
class MeshData:
    """What the certificate needs of one stored mesh, shared by its cases: vertex groups (the
    copies of a crack vertex share a group), geometry, element matrices at δ = 0, loads."""

    def __init__(self, points, tris, f, g, ref):
        xy = np.asarray(points, dtype=float)[:, :2]
        self.xy, self.tris = xy, np.asarray(tris, dtype=np.int64)
        uniq, gid = np.unique(xy, axis=0, return_inverse=True)
        self.gid, self.gxy, self.nv = gid.ravel(), uniq, len(uniq)
        X = xy[self.tris]
        self.area, self.grad = triangle_geometry(X)
        self.E0 = element_matrices(self.area, self.grad, 0.0, ref)
        self.Mu = self.area[:, None, None] * ref["m"][None]  # P1 mass per element (for δ)
        hi = load_on_triangles(f, X, self.area, symmetric_rule())
        lo = load_on_triangles(f, X, self.area, conical_rule(LOAD_CONICAL_N))
        self.F_tri, self.F_err_tri = hi, np.abs(hi - lo)
        self.F = np.bincount(self.tris.ravel(), hi.ravel(), minlength=len(xy))
        self.F_abs = np.bincount(self.tris.ravel(), np.abs(hi).ravel(), minlength=len(xy))
        self.F_err = np.bincount(self.tris.ravel(), self.F_err_tri.ravel(), minlength=len(xy))
        edges = boundary_edges(self.gid[self.tris], uniq)
        hi_a, hi_b = boundary_term(g, uniq, edges, LINE_N[1])
        lo_a, lo_b = boundary_term(g, uniq, edges, LINE_N[0])
        self.G = scatter_edges(edges, hi_a, hi_b, self.nv)
        self.G_abs = scatter_edges(edges, np.abs(hi_a), np.abs(hi_b), self.nv, absolute=True)
        self.G_err = scatter_edges(edges, np.abs(hi_a - lo_a), np.abs(hi_b - lo_b), self.nv,
                                   absolute=True)
        self._sorted_gid = np.argsort(self.gid, kind="stable")
        self._lookup = None
        self._lumped, self._abs = None, {}

    def groups_of(self, pts):
        """The vertex group of each point (exact coordinates), -1 where no vertex is there."""
        if self._lookup is None:
            self._lookup = {(float(x), float(y)): i for i, (x, y) in enumerate(self.gxy)}
        return np.array([self._lookup.get((float(x), float(y)), -1) for x, y in pts], dtype=np.int64)

    def copies(self, groups):
        """(count (I,), first (I,), second (I,)): the u dofs of each group (second = first where
        the group has one copy)."""
        s = self.gid[self._sorted_gid]
        lo = np.searchsorted(s, groups, "left")
        hi = np.searchsorted(s, groups, "right")
        first = self._sorted_gid[np.minimum(lo, len(s) - 1)]
        second = self._sorted_gid[np.minimum(np.maximum(hi - 1, lo), len(s) - 1)]
        return hi - lo, first, second

    def lumped(self):
        if self._lumped is None:
            self._lumped = lumped_element_matrices(self.E0)
        return self._lumped

    def absolute(self, lumped):
        """The scale's matrices: |E| of the element matrices at δ = 0 plus, for the consistent p
        mass, W Z of condensation_weights (the rows' scale |E||x| + W Z |x| is this matrix times
        |x|); the lumped p mass's |S| of its condensed matrices."""
        if lumped not in self._abs:
            if lumped:
                self._abs[True] = np.abs(self.lumped())
            else:
                W, Z = condensation_weights(self.E0)
                self._abs[False] = np.abs(self.E0) + W @ Z
        return self._abs[lumped]





# ------------------------------------------------------------------------------ the crack
def crack_geometry(C, segs):
    """Per segment: length ℓ (S,), normal ν (S,2) (direction turned by +90°); per node: the
    segment in and out (-1 at a tip), `straight` (interior, collinear segments), the M1star row
    normal ν̄ (I,2) (KINK_NORMAL)."""
    d = C[segs[:, 1]] - C[segs[:, 0]]
    length = np.hypot(d[:, 0], d[:, 1])
    nu = np.column_stack([-d[:, 1], d[:, 0]]) / length[:, None]
    n = len(C)
    seg_in, seg_out = np.full(n, -1), np.full(n, -1)
    seg_in[segs[:, 1]] = np.arange(len(segs))
    seg_out[segs[:, 0]] = np.arange(len(segs))
    interior = (seg_in >= 0) & (seg_out >= 0)
    si, so = np.maximum(seg_in, 0), np.maximum(seg_out, 0)
    sin = np.abs(d[si, 0] * d[so, 1] - d[si, 1] * d[so, 0]) / (length[si] * length[so])
    straight = interior & (sin < COLLINEAR_SIN)
    return {"length": length, "nu": nu, "seg_in": seg_in, "seg_out": seg_out,
            "interior": interior, "straight": straight,
            "row_normal": KINK_NORMAL(length, nu, seg_in, seg_out)}


def length_weighted_normal(length, nu, seg_in, seg_out):
    """M1star's row normal ν̄_j: (ℓ_in ν_in + ℓ_out ν_out)/(ℓ_in + ℓ_out) (ν at a straight node,
    the segment's ν at a tip): M1's row ∫ φ_j p·ν for a constant p over ∫ φ_j = (ℓ_in + ℓ_out)/2,
    the weight of the moment Λ̃_j = ∫ λ_h φ_j (issue 43's kink row)."""
    w_in = np.where(seg_in >= 0, length[np.maximum(seg_in, 0)], 0.0)
    w_out = np.where(seg_out >= 0, length[np.maximum(seg_out, 0)], 0.0)
    v = (w_in[:, None] * nu[np.maximum(seg_in, 0)] + w_out[:, None] * nu[np.maximum(seg_out, 0)])
    return v / (w_in + w_out)[:, None]


KINK_NORMAL = length_weighted_normal


def crack_mass_apply(length, segs, lam):
    """M_c λ: the crack's P1 mass (block diagonal over the cracks) applied to nodal values."""
    out = np.zeros(int(segs.max()) + 1 if len(segs) else 0)
    a, b = segs[:, 0], segs[:, 1]
    np.add.at(out, a, length / 6.0 * (2.0 * lam[a] + lam[b]))
    np.add.at(out, b, length / 6.0 * (lam[a] + 2.0 * lam[b]))
    return out


def contact(multiplier, lam, geo, segs, cg, nv):
    """The crack term of the p rows per vertex group, (nv, 2), its absolute scale (nv, 2), and
    the multiplier μ the complementarity conditions are about (module docstring)."""
    length, nu = geo["length"], geo["nu"]
    a, b = segs[:, 0], segs[:, 1]
    out, scale = np.zeros((nv, 2)), np.zeros((nv, 2))

    def add(nodes, val, vabs, normal):
        np.add.at(out, cg[nodes], val[:, None] * normal)
        np.add.at(scale, cg[nodes], vabs[:, None] * np.abs(normal))

    if multiplier == "M0":
        w = lam * length / 2.0
        add(a, w, np.abs(w), nu)
        add(b, w, np.abs(w), nu)
        return out, scale, lam
    if multiplier == "M1":
        la, lb = lam[a], lam[b]
        add(a, length / 6.0 * (2 * la + lb), length / 6.0 * (2 * np.abs(la) + np.abs(lb)), nu)
        add(b, length / 6.0 * (la + 2 * lb), length / 6.0 * (np.abs(la) + 2 * np.abs(lb)), nu)
        return out, scale, lam
    moment = crack_mass_apply(length, segs, lam)  # M1star: Λ̃ = M_c λ_h
    mabs = crack_mass_apply(length, segs, np.abs(lam))
    nodes = np.arange(len(moment))
    add(nodes, moment, mabs, geo["row_normal"])
    return out, scale, moment


def constraint(multiplier, p_node, geo, segs):
    """(g, ‖S‖∞): the constraint on p that must be ≤ 0 and the norm of its row weights (M0:
    ∫_{t_k} p·ν_k, ‖S‖ = max ℓ; M1: ∫ φ_j p·ν, ‖S‖ = max (ℓ_in + ℓ_out)/2; M1star: p(x_j)·ν̄_j)."""
    length, nu = geo["length"], geo["nu"]
    a, b = segs[:, 0], segs[:, 1]
    pa = np.einsum("sd,sd->s", p_node[a], nu)
    pb = np.einsum("sd,sd->s", p_node[b], nu)
    if multiplier == "M0":
        return length / 2.0 * (pa + pb), float(length.max())
    if multiplier == "M1":
        g = np.zeros(len(p_node))
        np.add.at(g, a, length / 6.0 * (2 * pa + pb))
        np.add.at(g, b, length / 6.0 * (pa + 2 * pb))
        return g, float(crack_mass_apply(length, segs, np.ones(len(p_node))).max())
    return np.einsum("id,id->i", p_node, geo["row_normal"]), 1.0


# ------------------------------------------------------------------------------- one case
def condensation_weights(E):
    """(W (T, 11, 2), Z (T, 2, 11)) = (|E_cb E_bb⁻¹|, |E_bc|), zero in the bubble rows and
    columns: W Z |x| are the magnitudes the bubble elimination moves into the p and u rows. The
    solver's system is the condensed one (docs/design.md), whose rows read Σ (E_cc −
    E_cb E_bb⁻¹ E_bc) x_c; its componentwise backward error is relative to those terms (for the u
    rows the (7/10)A|U| of the condensed stiffness, which the uncondensed row sees only through the
    small bubble), so they belong to the rows' scale."""
    keep = np.r_[0:6, 8:11]
    W = np.zeros((len(E), 11, 2))
    W[:, keep] = np.abs(E[:, keep, 6:8] @ inverse2(E[:, 6:8, 6:8]))
    Z = np.abs(E[:, 6:8]).copy()
    Z[:, :, 6:8] = 0.0
    return W, Z


def scatter2(index, values, n):
    """(n, 2) Σ of the 2-vectors `values` (..., 2) at `index` (...) (np.bincount per component)."""
    i = np.ravel(index)
    v = np.reshape(values, (-1, 2))
    return np.column_stack([np.bincount(i, v[:, 0], minlength=n), np.bincount(i, v[:, 1], minlength=n)])


def _rows(r, s, q):
    """(backward error max |r|/s, worst ratio |r|/tolerance, index of the worst row) of rows."""
    r, s, q = np.abs(np.ravel(r)), np.ravel(s), np.ravel(q)
    if r.size == 0:
        return 0.0, 0.0, -1
    tol = ROUNDOFF_FACTOR * EPS * s + QUADRATURE_FACTOR * q
    with np.errstate(divide="ignore", invalid="ignore"):
        back = np.where(s > 0, r / s, np.where(r > 0, np.inf, 0.0))
        ratio = np.where(tol > 0, r / tol, np.where(r > 0, np.inf, 0.0))
    i = int(np.argmax(ratio))
    return float(back.max()), float(ratio[i]), i


def certify_case(md, fields, multiplier, p_mass, p_space, delta, kappa):
    """The residuals of one case's stored fields in the discrete system this module assembles on
    the mesh md (MeshData): a dict of measured values and `problems` (one line each, naming the
    equation)."""
    tris, T = md.tris, len(md.tris)
    u = np.asarray(fields["u"], dtype=float)
    p = np.asarray(fields["p"], dtype=float)[:, :2]
    lumped = p_mass == "lumped"
    bub = None if lumped else fields.get("p_bubble")
    problems, out = [], {}
    if u.shape != (len(md.xy),) or p.shape != (len(md.xy), 2):
        return {"problems": [f"u {u.shape} and p {p.shape} do not match the mesh's "
                             f"{len(md.xy)} vertices"]}
    if not lumped and (bub is None or np.shape(bub) != (T, 2)):
        return {"problems": [f"{EQUATIONS['bubble']}: no p_bubble of shape ({T}, 2) for the "
                             "consistent p mass"]}
    # -------- the crack
    C = np.asarray(fields["crack_points"], dtype=float)[:, :2]
    segs = fields.get("crack_segments")
    segs = (np.column_stack([np.arange(len(C) - 1), np.arange(1, len(C))])
            if segs is None else np.asarray(segs, dtype=np.int64))
    geo = crack_geometry(C, segs)
    cg = md.groups_of(C)
    if (cg < 0).any():
        j = int(np.flatnonzero(cg < 0)[0])
        return {"problems": [f"crack node {j} at ({C[j, 0]:.6g}, {C[j, 1]:.6g}) is no vertex of "
                             "the stored mesh"]}
    ncopy, c1, c2 = md.copies(cg)
    lam = np.asarray(fields["lam"], dtype=float)
    if lam.shape != ((len(segs),) if multiplier == "M0" else (len(C),)):
        return {"problems": [f"λ of shape {lam.shape} for {multiplier} with {len(C)} crack nodes "
                             f"and {len(segs)} segments"]}
    doubled = (geo["straight"] & (ncopy == 2)) if p_space == "broken-tangential" else \
        np.zeros(len(C), bool)
    # -------- p in X_h (the copies of a crack vertex)
    pnorm = max(float(np.abs(p).max(initial=0.0)), np.finfo(float).tiny)
    two = ncopy == 2
    diff = p[c1] - p[c2]
    nu_node = geo["row_normal"]
    gap = np.where(doubled, np.abs(np.einsum("id,id->i", diff, nu_node)),
                   np.abs(diff).max(axis=1)) * two
    out["space"] = float(gap.max(initial=0.0)) / pnorm
    if out["space"] > MEMBERSHIP_FACTOR * EPS:
        j = int(np.argmax(gap))
        problems.append(f"{EQUATIONS['space']}: the copies of crack node ({C[j, 0]:.6g}, "
                        f"{C[j, 1]:.6g}) differ by {out['space']:.1e}·‖p‖∞ "
                        f"(> {MEMBERSHIP_FACTOR:g}ε)")
    # -------- element residuals
    Pc = p[tris].reshape(T, 6)
    uc = u[tris]
    if lumped:
        E = md.lumped()
        x = np.concatenate([Pc, uc], axis=1)
        iu = slice(6, 9)
    else:
        E = md.E0
        x = np.concatenate([Pc, np.asarray(bub, dtype=float), uc], axis=1)
        iu = slice(8, 11)
    r = (E @ x[:, :, None])[:, :, 0]
    s = (md.absolute(lumped) @ np.abs(x)[:, :, None])[:, :, 0]
    if delta:
        r[:, iu] -= delta * (md.Mu @ uc[:, :, None])[:, :, 0]
        s[:, iu] += delta * (md.Mu @ np.abs(uc)[:, :, None])[:, :, 0]
    # u rows: Ex − b with b = −F
    n = len(md.xy)
    ru = np.bincount(tris.ravel(), r[:, iu].ravel(), minlength=n) + md.F
    su = np.bincount(tris.ravel(), s[:, iu].ravel(), minlength=n) + md.F_abs
    rows = {"u": (ru, su, md.F_err)}
    where = {"u": md.xy, "bubble": np.repeat(md.xy[tris].mean(axis=1), 2, axis=0)}
    if not lumped:
        rows["bubble"] = (r[:, 6:8], s[:, 6:8], np.zeros((T, 2)))
    # p rows: Ex − b with b = G_Γ − crack term, per vertex group; frames at doubled vertices
    cvec, cabs, mu = contact(multiplier, lam, geo, segs, cg, md.nv)
    rq, sq = r[:, :6].reshape(T, 3, 2), s[:, :6].reshape(T, 3, 2)
    g3 = md.gid[tris]
    Rg = scatter2(g3, rq, md.nv) + cvec - md.G
    Sg = scatter2(g3, sq, md.nv) + cabs + md.G_abs
    Qg = md.G_err.copy()
    framed = np.zeros(md.nv, bool)
    framed[cg[doubled]] = True
    p_r, p_s, p_q = [Rg[~framed]], [Sg[~framed]], [Qg[~framed]]
    p_at = [np.repeat(md.gxy[~framed], 2, axis=0)]
    if doubled.any():
        nu_d = nu_node[doubled]
        tau_d = np.column_stack([nu_d[:, 1], -nu_d[:, 0]])  # ν turned by −90°
        gd = cg[doubled]
        p_r.append(np.einsum("id,id->i", Rg[gd], nu_d))
        p_at += [md.gxy[gd]] * 3
        p_s.append(np.einsum("id,id->i", Sg[gd], np.abs(nu_d)))
        p_q.append(np.einsum("id,id->i", Qg[gd], np.abs(nu_d)))
        Rc, Sc = scatter2(tris, rq, n), scatter2(tris, sq, n)
        for copy in (c1[doubled], c2[doubled]):  # p⁺·τ, p⁻·τ: one copy's triangles each
            p_r.append(np.einsum("id,id->i", Rc[copy], tau_d))
            p_s.append(np.einsum("id,id->i", Sc[copy], np.abs(tau_d)))
            p_q.append(np.zeros(len(copy)))
    rows["p"] = tuple(np.concatenate([np.ravel(a) for a in v]) for v in (p_r, p_s, p_q))
    where["p"] = np.concatenate(p_at)
    for name, (rr, ss, qq) in rows.items():
        back, ratio, i = _rows(rr, ss, qq)
        at = f" at ({where[name][i, 0]:.6g}, {where[name][i, 1]:.6g})" if i >= 0 else ""
        out[f"{name}_backward_error"] = back
        out[f"{name}_ratio"] = ratio
        if not ratio <= 1.0:
            problems.append(f"{EQUATIONS[name]}: residual {ratio:.3g} × its tolerance{at} "
                            f"(componentwise backward error {back:.1e}; tolerance "
                            f"{ROUNDOFF_FACTOR:g}ε·(|K||x| + |b|) + {QUADRATURE_FACTOR:g}·quadrature)")
    # -------- complementarity
    p_node = 0.5 * (p[c1] + p[c2])
    gval, snorm = constraint(multiplier, p_node, geo, segs)
    mnorm = float(np.abs(mu).max(initial=0.0))
    kap = kappa if kappa is not None and math.isfinite(kappa) else KAPPA_WITHOUT_ESTIMATE
    tol = COMPLEMENTARITY_FACTOR * kap * EPS + ROUNDOFF_FACTOR * EPS
    out["complementarity_tolerance"] = tol
    out["primal"] = max(0.0, float(gval.max(initial=0.0))) / (snorm * pnorm)
    out["dual"] = max(0.0, -float(mu.min(initial=0.0))) / mnorm if mnorm > 0 else 0.0
    out["complementarity"] = (float(np.abs(mu * gval).max(initial=0.0)) / (mnorm * snorm * pnorm)
                              if mnorm > 0 else 0.0)
    for key, name, what in (("dual", "sign", "μ ≥ 0: min μ"), ("primal", "constraint",
                            "≤ 0: max"), ("complementarity", "complementarity", "max |μ g|")):
        if not out[key] <= tol:
            problems.append(f"{EQUATIONS[name]} of {multiplier} ({what}) {out[key]:.1e} relative "
                            f"(> {COMPLEMENTARITY_FACTOR:g}·κ·ε = {tol:.1e}, κ = {kap:.2g})")
    out["problems"] = problems
    return out


# ------------------------------------------------------------------------------ a results folder
def _expression(sf, key):
    """f or g of the scene copy as a numpy function (None when absent or unparsable: the
    completeness and exact-data checks report the scene)."""
    text = ((sf or {}).get("data") or {}).get(key)
    if not isinstance(text, str):
        return None
    try:
        return sdexpr.to_numpy(sdexpr.parse(text))
    except sdexpr.ExprError:
        return None


def certify(res, sf):
    """{"rows": one per certified case, "problems": [...], "skipped": cases above
    UNKNOWNS_LIMIT, "seconds": the check's cost, "not_applicable": why nothing was certified or
    None} for the results folder res (read.load_results) with scene copy sf."""
    t0, c0 = time.perf_counter(), time.process_time()
    data = res.get("data")
    f, g = _expression(sf, "f"), _expression(sf, "g")
    out = {"rows": [], "problems": [], "skipped": 0, "seconds": 0.0, "not_applicable": None,
           "unknowns_limit": UNKNOWNS_LIMIT}
    if data is None:
        out["not_applicable"] = "no stored fields (fields.h5 or verification.h5)"
        return out
    if f is None or g is None:
        out["not_applicable"] = "the scene copy has no parsable [data] f and g"
        return out
    ref = reference_integrals()
    meshes = {}
    cases = sorted(res["summary"]["cases"], key=case_order)
    for c in cases:
        grid = c.get("fields_grid")
        unknowns = c.get("unknowns")
        if not (isinstance(unknowns, int) and unknowns <= UNKNOWNS_LIMIT):
            out["skipped"] += 1
            continue
        k = case_key(c)
        what = case_text(k)
        if not data.has_case(grid):
            continue  # completeness names a missing field
        fields = data.case(grid)
        if fields["u"] is None or fields["p"] is None or fields["lam"] is None \
                or fields["crack_points"] is None:
            out["problems"].append(f"{what}: cannot be certified: u, p, λ or the crack are not "
                                   "stored")
            continue
        key = id(fields["points"])
        if key not in meshes:
            meshes[key] = (fields["points"], MeshData(fields["points"], fields["tris"], f, g, ref))
        kappa = c.get("condition_estimate")
        try:
            with np.errstate(all="ignore"):  # a NaN residual fails its row (not ≤ tolerance)
                row = certify_case(meshes[key][1], fields, k.multiplier, k.p_mass, k.p_space, k.delta,
                                   float(kappa) if finite_number(kappa) else None)
        except (ValueError, IndexError) as exc:  # stored arrays of inconsistent shapes
            row = {"problems": [f"cannot be certified: its stored arrays do not fit together "
                                f"({exc})"]}
        row.update({"level": k.level, "u_space": k.u_space, "multiplier": k.multiplier,
                    "delta": k.delta, "p_mass": k.p_mass, "p_space": k.p_space,
                    "unknowns": unknowns})
        row["ok"] = not row["problems"]
        out["problems"] += [f"{what}: {p}" for p in row["problems"]]
        out["rows"].append(row)
    out["seconds"] = time.perf_counter() - t0
    out["cpu_seconds"] = time.process_time() - c0
    if not out["rows"] and not out["problems"]:
        out["not_applicable"] = (f"no case with ≤ {UNKNOWNS_LIMIT} unknowns and stored fields"
                                 if out["skipped"] else "no solver case with stored fields")
    return out


RATIO_KEYS = ("u_ratio", "p_ratio", "bubble_ratio")
BACKWARD_KEYS = ("u_backward_error", "p_backward_error", "bubble_backward_error")


def summary_numbers(cert):
    """The largest measured values over the certified cases: backward errors, ratios to the
    tolerance, complementarity values."""
    rows = cert["rows"]
    pick = lambda key: max((r[key] for r in rows if isinstance(r.get(key), float)), default=None)
    return {k: pick(k) for k in RATIO_KEYS + BACKWARD_KEYS
            + ("primal", "dual", "complementarity", "space")}


def requirement(cert):
    """The check's sentence with the measured worst values (not the cost, which varies from run
    to run: it is in the report's section and report.json)."""
    n = len(cert["rows"])
    worst = summary_numbers(cert)
    ratio = max((v for k, v in worst.items() if k in RATIO_KEYS and v is not None), default=None)
    back = max((v for k, v in worst.items() if k in BACKWARD_KEYS and v is not None), default=None)
    text = (f"the stored u, p, bubbles and λ solve the discrete system of (15) assembled here "
            f"(|r_i| ≤ {ROUNDOFF_FACTOR:g}ε·(|K||x| + |b|)_i + {QUADRATURE_FACTOR:g}·quadrature "
            f"estimate) and its complementarity conditions (≤ {COMPLEMENTARITY_FACTOR:g}·κ·ε) "
            f"on every case with ≤ {UNKNOWNS_LIMIT} unknowns")
    if n:
        text += (f" ({n} cases, {cert['skipped']} larger ones not certified; largest backward "
                 f"error {back:.1e}, largest residual {ratio:.2g} × tolerance)")
    return text


ROW_KEYS = ("level", "u_space", "multiplier", "p_mass", "p_space", "delta", "unknowns", "ok")
MEASURED_KEYS = BACKWARD_KEYS + RATIO_KEYS + ("primal", "dual", "complementarity",
                                              "complementarity_tolerance", "space")


def report_json(cert):
    """report.json's `discrete_certificate`: the tolerances, the cost, and per certified case its
    measured residuals."""
    return {"unknowns_limit": UNKNOWNS_LIMIT, "roundoff_factor": ROUNDOFF_FACTOR,
            "quadrature_factor": QUADRATURE_FACTOR,
            "complementarity_factor": COMPLEMENTARITY_FACTOR, "seconds": cert["seconds"],
            "cpu_seconds": cert.get("cpu_seconds"), "certified": len(cert["rows"]),
            "skipped": cert["skipped"], "worst": summary_numbers(cert),
            "cases": [{k: r.get(k) for k in ROW_KEYS + MEASURED_KEYS} for r in cert["rows"]]}


def table(cert):
    """(headers, rows, entries): one row per level × variant, the worst over its δ values."""
    worst = {}
    for r in cert["rows"]:
        key = (r["level"], r["u_space"], r["multiplier"], r["p_mass"], r["p_space"])
        w = worst.setdefault(key, dict(r, deltas=0))
        w["deltas"] += 1
        w["ok"] = w["ok"] and r["ok"]
        for k in MEASURED_KEYS:
            if isinstance(r.get(k), float):
                w[k] = max(w.get(k) or 0.0, r[k])
    fmt = lambda v: "–" if not isinstance(v, float) or not math.isfinite(v) else f"{v:.1e}"
    entries = [worst[k] for k in sorted(worst)]
    rows = [[w["level"], w["u_space"], w["multiplier"], w["deltas"],
             fmt(max(w.get(k) or 0.0 for k in BACKWARD_KEYS)),
             fmt(max(w.get(k) or 0.0 for k in RATIO_KEYS)),
             fmt(max(w.get(k) or 0.0 for k in ("primal", "dual", "complementarity"))),
             fmt(w.get("complementarity_tolerance")), "ok" if w["ok"] else "**FAIL**"]
            for w in entries]
    return (["level", "u space", "mult.", "δ values", "backward error", "residual ÷ tolerance",
             "KKT (primal, dual, compl.)", "its tolerance", "status"], rows, entries)
