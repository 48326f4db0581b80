"""What the theory predicts for each series: its expected order of convergence, and why.

A series (u space × multiplier × p mass × quantity) is judged by its observed rates against an
expected order p*: it converges iff its errors decrease and each of its last two observed rates is
≥ p* − RATE_MARGIN (the order-of-accuracy rule of MOOSE's and deal.II's convergence tests). p*
comes from the regularity of the solution, never from the output judged:

* **Regularity index s** (u ∈ H^{1+s} on each side of the crack, s ≤ 1). With an exact solution,
  s is read from the exact solution alone: the compare tool interpolates the exact u in P1 on the
  run's meshes and measures the rate r_I of ‖∇(u − I_h u)‖ over the last step (interpolation
  theory: r_I = s). r_I ≥ SMOOTH_INTERPOLATION_RATE → s = 1 ("smooth"); otherwise s = 1/2, the
  crack tip's r^{1/2} singularity, the worst a crack or a polygon corner produces (a corner of angle
  ω < 2π gives π/ω > 1/2). Without an exact solution s = 1/2 (the series are distances to a
  reference solution; a crack open at a tip has the r^{1/2} singularity).
* **Orders** (docs/design.md, docs/verification.md):

  | quantity | smooth (s = 1) | r^{1/2} tip (s = 1/2) |
  |---|---|---|
  | u_l2, crack closed ([u] = 0) | 2: P1 interpolation and the duality (Aubin–Nitsche) gain | 2s = 1 |
  | u_l2, crack open somewhere | 1/2: the mixed method's u is controlled by ‖p − p_h‖ + ‖λ − λ_h‖, and p_h is of order 1/2 there (below); the duality gain is lost (measured: → 1 on a smooth open crack, 0.56–0.78 on graded meshes) | 1/2 (measured: rate 1.35 → 0.66 over levels 3–7, docs/design.md) |
  | p_l2, p_x, crack closed | 1: MINI / P1 approximation of ∇u (the lumped p, a recovered gradient, at least 1) | s = 1/2 |
  | p_l2, p_x, crack open somewhere | 1/2: p_h is one continuous field on Ω while ∇u jumps across the open crack, an O(1) error in a strip of width h along Γc (measured: p → 0.54 on graded meshes and on a smooth open crack, docs/design.md) | 1/2 |
  | lambda_l2 | λ = [u] = 0 (closed crack): exact; otherwise Theorem 4.3's rate, M0 1/2, M1 1/2, M1star 3/4 | Theorem 4.3's rate |

  Theorem 4.3 (paper) proves h^{1/2} (M0, M1) and h^{3/4} (M1star) for u in L², p in the X-norm and
  λ together; the table takes the larger, optimal, order for u and p on smooth solutions, where the
  interpolation estimates give it, and the paper's order for λ, which it bounds on its own. Whether
  the crack is closed is read from the exact solution too (‖[u]‖_{L²(Γc)} = 0); without one it is
  taken as open.

A scene may declare its own expected order for some series with a reason
(`[[verification.expected_rate]]`, docs/scenes.md); the report shows every expected order with the
reason it comes from.
"""

# The observed rate may fall short of the expected order by this much on each of the last two
# steps (an observed rate is an estimate from two levels): MOOSE's order-of-accuracy tests.
RATE_MARGIN = 0.1
# ‖∇(u − I_h u)‖ of a smooth u has rate 1; of an r^{1/2} singular u, 1/2. The classification
# threshold lies between them, nearer 1 (a pre-asymptotic smooth u shows rates ≥ 0.95 from level 1
# on the repository's meshes; an r^{1/2} one 0.5–0.6).
SMOOTH_INTERPOLATION_RATE = 0.9
SINGULAR_S = 0.5
PAPER_LAMBDA_RATE = {"M0": 0.5, "M1": 0.5, "M1star": 0.75}
# p_h is continuous on Ω (the smooth-domain method): where the crack opens, ∇u jumps across Γc and
# p_h's error in a strip of width h is O(1), so ‖p − p_h‖ = O(h^{1/2}) whatever the regularity; u,
# bounded by p and λ without a duality gain, is held to the same order.
OPEN_CRACK_RATE = 0.5


def regularity(interpolation_rate, has_exact=True):
    """(s, reason) from the observed rate of ‖∇(u − I_h u)‖ over the last step (None: no exact
    solution, or too few levels or no stored mesh to measure it)."""
    if interpolation_rate is None:
        why = ("no exact solution to measure the regularity" if not has_exact else
               "the exact u's interpolation error could not be measured (fewer than two levels "
               "with stored fields)")
        return SINGULAR_S, f"{why}: s = 1/2, the crack tip's r^{{1/2}} singularity (the worst case)"
    if interpolation_rate >= SMOOTH_INTERPOLATION_RATE:
        return 1.0, (f"smooth exact u: its P1 interpolation error ‖∇(u − I_h u)‖ has rate "
                     f"{interpolation_rate:.2f} ≥ {SMOOTH_INTERPOLATION_RATE:g}")
    return SINGULAR_S, (f"singular exact u: its P1 interpolation error ‖∇(u − I_h u)‖ has rate "
                        f"{interpolation_rate:.2f} < {SMOOTH_INTERPOLATION_RATE:g} (r^{{1/2}} at a "
                        "crack tip: s = 1/2)")


def expected_rate(quantity, multiplier, p_mass, s, crack_closed=False):
    """(expected order, reason) of one series of the smooth-domain method for regularity s; with
    `crack_closed` (the exact [u] vanishes on all of Γc) the contact term is inactive and u keeps
    the duality gain of the mixed Laplacian."""
    smooth = s >= 1.0
    paper = PAPER_LAMBDA_RATE[multiplier]
    if quantity == "u_l2":
        if crack_closed:
            return 2.0 * s, (f"crack closed ([u] = 0: the contact term vanishes): P1 "
                             f"interpolation and the duality gain give h^{2.0 * s:g}")
        return OPEN_CRACK_RATE, (
            "crack open somewhere (or no exact solution): the mixed method's ‖u − u_h‖ is bounded "
            "by ‖p − p_h‖ + ‖λ − λ_h‖, no duality gain, and p_h converges as h^0.5 there: h^0.5 "
            "(measured: 1.35 → 0.66 over levels 3–7 of open-exact, → 1 on a smooth open crack, "
            "0.56–0.78 on graded meshes; docs/design.md)")
    if quantity in ("p_l2", "p_x"):
        what = "the lumped (recovered) p" if p_mass == "lumped" else "the MINI p"
        if not crack_closed:
            return OPEN_CRACK_RATE, (
                f"crack open somewhere: {what} is continuous across Γc while ∇u jumps there, an O(1) "
                "error in a strip of width h along the crack: h^0.5 (measured on a smooth open "
                "crack and on graded meshes: rates → 0.54, docs/design.md)")
        if smooth:
            return 1.0, f"smooth u: {what} approximates ∇u to order h"
        return s, f"singular u: ∇u ~ r^(s−1) near a tip limits {what} to h^s"
    if quantity == "lambda_l2":
        return paper, f"Theorem 4.3: λ_h of {multiplier} converges as h^{paper:g}"
    raise ValueError(f"unknown quantity {quantity!r}")


def reference_order(quantity, s):
    """The order of the references' error (P1 Galerkin on the cracked mesh, conforming): u 2s
    (duality), p s; None for λ (their jump [u_h] superconverges on smooth solutions)."""
    return {"u_l2": 2.0 * s, "p_l2": s, "p_x": s}.get(quantity)


def comparable_to_references(quantity, expected, s):
    """Whether a constant factor can bound the solver's error by the references' on the same
    mesh: the solver's expected order is at least theirs (else the ratio grows as h → 0)."""
    ref = reference_order(quantity, s)
    return ref is None or (expected is not None and expected >= ref - 1e-12)


def declared_rate(declarations, u_space, multiplier, p_mass, quantity):
    """The scene's own (rate, reason) for this series ([[verification.expected_rate]]), or None;
    the first matching declaration wins."""
    for d in declarations:
        if all(d[k] in ("*", v) for k, v in (("u_space", u_space), ("multiplier", multiplier),
                                              ("p_mass", p_mass), ("quantity", quantity))):
            return d["rate"], f"declared in the scene: {d['reason']}"
    return None


def threshold(expected, min_rate=None):
    """The smallest observed rate accepted for expected order `expected` (and the scene's
    optional floor min_rate)."""
    t = expected - RATE_MARGIN
    return t if min_rate is None else max(t, min_rate)
