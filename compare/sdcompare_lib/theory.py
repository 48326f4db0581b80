"""What the theory predicts for each series: its expected order of convergence, and why.

A series (u space × multiplier × p mass × p space × quantity) is judged by its observed rates
against an expected order p*: it converges iff its errors decrease and each of its last two
observed rates is ≥ p* − RATE_MARGIN (the order-of-accuracy rule of MOOSE's and deal.II's
convergence tests). p* comes from the regularity of the solution and the p space, never from the
output judged. The numbers (the margin, the orders, the classification threshold) are those of
scenes/orders.toml, with their sources, the one table the Rust tests read too; this module says
which order applies to which series, and why:

* **Regularity index s** (u ∈ H^{1+s} on each side of the crack, s ≤ 1). With an exact solution,
  s is read from the exact solution alone: the compare tool interpolates the exact u in P1 on the
  run's meshes and measures the rate r_I of ‖∇(u − I_h u)‖ over the last step (interpolation
  theory: r_I = s). r_I ≥ SMOOTH_INTERPOLATION_RATE → s = 1 (P1's orders); otherwise s = 1/2, the
  crack tip's r^{1/2} singularity, the worst a crack or a polygon corner produces (a corner of angle
  ω < 2π gives π/ω > 1/2). Without an exact solution s = 1/2 (the series are distances to a
  reference solution; a crack open at a tip has the r^{1/2} singularity). Whether the reason calls
  u "smooth" or "singular" is measured apart (yardsticks.gradient_growth: the growth of |∇u|
  towards each crack node and domain corner, SINGULAR_GROWTH): on graded meshes a tip-singular u
  reaches r_I ≥ SMOOTH_INTERPOLATION_RATE, and "smooth" would be false of it.
* **Orders** (docs/design.md, docs/verification.md) of the paper's continuous p (p space
  "continuous"):

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
* **Orders of the broken-tangential p** (p space "broken-tangential", run with broken u only). Its tangential component has one value per crack face at every interior vertex where the
  crack is straight, while p·ν stays shared (the flux ∂u/∂ν is one value on both faces of Γc), so
  p_h can follow the tangential jump of ∇u where the crack opens, and the continuous p's O(1)
  strip error is gone. The method is then as accurate as P1 on the cracked mesh whatever the crack
  does, and its orders are the references' (P1 Galerkin on the cracked mesh, `p1_order`):

  | quantity | order | why |
  |---|---|---|
  | u_l2 | 2s (2 smooth, 1 at an r^{1/2} tip) | P1 on the cracked mesh with the duality gain, as the references: u is bounded by p and λ, which now converge at their P1 orders |
  | p_l2, p_x | s (1 smooth, 1/2 at a tip) | the MINI (or lumped, recovered) p with its broken tangential part approximates the piecewise-smooth ∇u on each face; a kink or a tip keeps p shared, an O(1) error on patches of area O(h²), O(h) in L², within the order |
  | lambda_l2, M1 and M1star | 2s | λ = [u] is approximated by the jump of the broken P1 u at the crack nodes: the order of u in L² |
  | lambda_l2, M0 | 1 smooth, Theorem 4.3's 1/2 at a tip | a P0 multiplier approximates the smooth jump [u] to order h at best; at an r^{1/2} tip its λ_h (the multiplier of ∫_{t_k} p·ν ≤ 0, not the L² projection of [u]) is measured at 0.83 → 0.68 over levels 0–5 of open-exact, falling, with either p: the paper's h^{1/2} is the order held |

  On graded meshes the interpolation rate (per halving of N^{-1/2}) classifies a tip-singular u as
  smooth already: s = 1 there. (Measured when the broken-tangential p came, last rates of levels 1–4:
  smooth open crack u 2.01, p 1.02, λ 2.02, M0's λ 1.00; open-graded u 2.17, p 1.16, λ 2.18;
  open-exact, s = 1/2: u 1.03, p 0.50, λ 0.93, but M0's λ 0.73 < 1 − RATE_MARGIN, an open
  question: compare/README.md.)

A scene may declare its own expected order for some series with a reason
(`[[verification.expected_rate]]`, docs/scenes.md); the report shows every expected order with the
reason it comes from.
"""

import importlib.util
import os
import tomllib

from .cases import BROKEN_TANGENTIAL, DEFAULT_P_SPACE

# The table of expected orders, in the repository's scenes/.
ORDERS_NAME = "orders.toml"
# The repository's scenes/ folder as pip installs it (pyproject.toml: package-dir and package-data).
PACKAGED_SCENES = "sdcompare_scenes"


def packaged_scenes_file(name):
    """The path of file `name` of the scenes/ folder installed with the package (pip:
    `sdcompare_scenes`, the repository's scenes/ with their expectations and orders), or None."""
    try:
        spec = importlib.util.find_spec(PACKAGED_SCENES)
    except (ImportError, ValueError):
        spec = None
    for folder in (spec.submodule_search_locations or []) if spec else []:
        path = os.path.join(folder, name)
        if os.path.isfile(path):
            return os.path.normpath(path)
    return None


def orders_file():
    """The orders table this module judges with: scenes/orders.toml of the checkout it belongs to
    (beside compare/, this package's folder), else the copy installed with the package;
    FileNotFoundError when neither exists."""
    package = os.path.dirname(os.path.abspath(__file__))
    here = os.path.join(package, "..", "..", "scenes", ORDERS_NAME)
    if os.path.isfile(here):
        return os.path.normpath(here)
    packaged = packaged_scenes_file(ORDERS_NAME)
    if packaged is not None:
        return packaged
    raise FileNotFoundError(f"no {ORDERS_NAME}: neither scenes/{ORDERS_NAME} of a checkout nor "
                            f"the installed package {PACKAGED_SCENES}")


# The (section, key) of every number theory.py reads from the table; `lambda.paper` is a table of
# multiplier → order.
ORDER_KEYS = (("rule", "margin"), ("rule", "levels"), ("rule", "bug_gap"), ("rule", "extra_levels"), ("regularity", "smooth_s"), ("regularity", "singular_s"),
              ("regularity", "smooth_interpolation_rate"), ("p1", "u_l2"), ("p1", "p_l2"),
              ("p1", "p_x"), ("open_crack", "order"), ("lambda", "p0_jump"))
MULTIPLIERS = ("M0", "M1", "M1star")


def load_orders(path):
    """The orders table at `path` (a dict of sections, tomllib), every number theory.py reads
    checked to be one (ValueError names the missing or bad key)."""
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    wanted = list(ORDER_KEYS) + [("lambda.paper", m) for m in MULTIPLIERS]
    for section, key in wanted:
        table = data
        for part in section.split("."):
            table = table.get(part, {}) if isinstance(table, dict) else {}
        value = table.get(key) if isinstance(table, dict) else None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{path}: [{section}] {key} must be a number, got {value!r}")
    return data


ORDERS = load_orders(orders_file())
# The observed rate may fall short of the expected order by this much on each of the last two
# steps (an observed rate is an estimate from two levels).
RATE_MARGIN = float(ORDERS["rule"]["margin"])
# The smallest defect of order the verdict must tell from a correct solver, and how many more
# levels a series rising toward its order may ask for before it is held to fail (rates.py).
BUG_GAP = float(ORDERS["rule"]["bug_gap"])
# A series is judged on its last RULE_LEVELS levels: two observed rates.
RULE_LEVELS = int(ORDERS["rule"]["levels"])
EXTRA_LEVELS = int(ORDERS["rule"]["extra_levels"])
# s of a smooth u, and at a crack tip's r^{1/2} singularity (the worst case, and the s assumed
# without an exact solution).
SMOOTH_S = float(ORDERS["regularity"]["smooth_s"])
SINGULAR_S = float(ORDERS["regularity"]["singular_s"])
# ‖∇(u − I_h u)‖ has rate s: at or above this rate the exact u is classified smooth.
SMOOTH_INTERPOLATION_RATE = float(ORDERS["regularity"]["smooth_interpolation_rate"])
# |∇u| growing towards a point faster than r^-(1 − SMOOTH_INTERPOLATION_RATE) is a singularity
# u ~ r^s with s below the rate at which u is classified smooth: the growth of |∇u|
# (yardsticks.gradient_growth) and the interpolation rate share one threshold.
SINGULAR_GROWTH = 1.0 - SMOOTH_INTERPOLATION_RATE
# P1's orders on the cracked mesh as multiples of s (p1_order).
P1_ORDER_PER_S = {q: float(ORDERS["p1"][q]) for q in ("u_l2", "p_l2", "p_x")}
# Theorem 4.3's order of λ_h per multiplier.
PAPER_LAMBDA_RATE = {m: float(ORDERS["lambda"]["paper"][m]) for m in MULTIPLIERS}
# The continuous p_h where the crack opens (an O(1) error in a strip of width h along Γc), and u
# with it.
OPEN_CRACK_RATE = float(ORDERS["open_crack"]["order"])
# A P0 multiplier (M0) on a smooth jump [u]; at an r^{1/2} tip its λ_h is held to Theorem 4.3's
# h^{1/2} (measured 0.83 → 0.68 over levels 0–5 of open-exact, falling).
P0_JUMP_RATE = float(ORDERS["lambda"]["p0_jump"])


def regularity(interpolation_rate, has_exact=True, growth=None, graded=False):
    """(s, reason) from the observed rate of ‖∇(u − I_h u)‖ over the last step (None: no exact
    solution, or too few levels or no stored mesh to measure it). s comes from that rate alone;
    the reason's words "smooth" and "singular" from `growth` (yardsticks.gradient_growth: how fast
    |∇u| grows towards a crack node or domain corner; None: not measured): on `graded` meshes a
    singular u's interpolation rate reaches the smooth one, and "smooth" would be false."""
    if interpolation_rate is None:
        why = ("no exact solution to measure the regularity" if not has_exact else
               "the exact u's interpolation error could not be measured (fewer than two levels "
               "with stored fields)")
        return SINGULAR_S, f"{why}: s = 1/2, the crack tip's r^{{1/2}} singularity (the worst case)"
    meshes = "these graded meshes" if graded else "these meshes"
    smooth_rate = interpolation_rate >= SMOOTH_INTERPOLATION_RATE
    measured = (f"its P1 interpolation error ‖∇(u − I_h u)‖ has rate {interpolation_rate:.2f} "
                f"{'≥' if smooth_rate else '<'} {SMOOTH_INTERPOLATION_RATE:g} per halving of h on "
                f"{meshes}")
    singular = growth is not None and growth["exponent"] > SINGULAR_GROWTH
    where = ("" if growth is None else f"|∇u| grows as r^-{growth['exponent']:.2f} towards "
             f"({growth['point'][0]:g}, {growth['point'][1]:g})" if singular else
             f"|∇u| grows no faster than r^-{max(growth['exponent'], 0.0):.2f} towards any crack "
             "node or domain corner")
    if smooth_rate:
        verdict = f"{measured}: P1's orders apply (s = 1)"
        if singular:
            return SMOOTH_S, f"singular exact u ({where}), resolved: {verdict}"
        return SMOOTH_S, ("smooth exact u" + (f" ({where})" if where else "") + f": {verdict}"
                          if growth is not None else verdict[0].upper() + verdict[1:])
    verdict = f"{measured}: s = 1/2"
    if singular:
        return SINGULAR_S, f"singular exact u ({where}): {verdict}, as at a crack tip's r^{{1/2}}"
    return SINGULAR_S, ((f"exact u with bounded gradient ({where}), but " if where else "")
                        + f"{verdict}, the worst case")


def expected_rate(quantity, multiplier, p_mass, s, crack_closed=False, p_space=DEFAULT_P_SPACE):
    """(expected order, reason) of one series of the smooth-domain method for regularity s; with
    `crack_closed` (the exact [u] vanishes on all of Γc) the contact term is inactive and u keeps
    the duality gain of the mixed Laplacian. The broken-tangential `p_space` (broken u only) has
    the orders of P1 on the cracked mesh whatever the crack does (tangential_rate): p_h follows
    the tangential jump of ∇u."""
    if p_space == BROKEN_TANGENTIAL:
        return tangential_rate(quantity, multiplier, p_mass, s)
    smooth = s >= SMOOTH_S
    paper = PAPER_LAMBDA_RATE[multiplier]
    if quantity == "u_l2":
        if crack_closed:
            order = p1_order(quantity, s)
            return order, (f"crack closed ([u] = 0: the contact term vanishes): P1 "
                           f"interpolation and the duality gain give h^{order:g}")
        return OPEN_CRACK_RATE, (
            "crack open somewhere (or no exact solution): the mixed method's ‖u − u_h‖ is bounded "
            f"by ‖p − p_h‖ + ‖λ − λ_h‖, no duality gain, and p_h converges as "
            f"h^{OPEN_CRACK_RATE:g} there: h^{OPEN_CRACK_RATE:g} (measured: 1.35 → 0.66 over "
            "levels 3–7 of open-exact, → 1 on a smooth open crack, 0.56–0.78 on graded meshes; "
            "docs/design.md)")
    if quantity in ("p_l2", "p_x"):
        what = _p_name(p_mass)
        if not crack_closed:
            return OPEN_CRACK_RATE, (
                f"crack open somewhere: {what} is continuous across Γc while ∇u jumps there, an O(1) "
                f"error in a strip of width h along the crack: h^{OPEN_CRACK_RATE:g} (measured on "
                "a smooth open crack and on graded meshes: rates → 0.54, docs/design.md)")
        if smooth:
            return p1_order(quantity, SMOOTH_S), (f"s = 1 (the regularity above): {what} "
                                                  "approximates ∇u to order h")
        return p1_order(quantity, s), f"singular u: ∇u ~ r^(s−1) near a tip limits {what} to h^s"
    if quantity == "lambda_l2":
        return paper, f"Theorem 4.3: λ_h of {multiplier} converges as h^{paper:g}"
    raise ValueError(f"unknown quantity {quantity!r}")


def _p_name(p_mass, tangential=False):
    """What p_h is, in a reason: the MINI p or the lumped (recovered) one, its tangential part
    broken across Γc or not."""
    what = "the lumped (recovered) p" if p_mass == "lumped" else "the MINI p"
    return what + (" with its tangential component broken across Γc" if tangential else "")


def tangential_rate(quantity, multiplier, p_mass, s):
    """(expected order, reason) of a series of the broken-tangential p space (with broken u): P1's
    order on the cracked mesh (p1_order) for u and p, 2s for λ of M1 and M1star (the jump of the
    broken P1 u), for M0's piecewise-constant λ 1 on a smooth u and the paper's 1/2 at a tip;
    closed or open crack alike."""
    why = (f"{_p_name(p_mass, True)} follows the tangential jump of ∇u where the crack opens (no "
           "strip error), so the method has the orders of P1 on the cracked mesh (the "
           "references'), whatever the crack does")
    if quantity in ("u_l2", "p_l2", "p_x"):
        order = p1_order(quantity, s)
        return order, f"{why}: h^{order:g} ({'2s' if quantity == 'u_l2' else 's'}, s = {s:g})"
    if quantity == "lambda_l2":
        if multiplier == "M0" and s >= SMOOTH_S:
            return P0_JUMP_RATE, (f"{why}; a P0 multiplier (M0) approximates the smooth jump [u] "
                                  f"to order h at best: h^{P0_JUMP_RATE:g}")
        if multiplier == "M0":
            paper = PAPER_LAMBDA_RATE["M0"]
            return paper, (f"{why}; at an r^{{1/2}} tip (s = {s:g}) M0's λ_h, the multiplier of "
                           "∫ p·ν ≤ 0 per segment and not the L² projection of [u], is held to "
                           f"Theorem 4.3's h^{paper:g} (measured 0.83 → 0.68 over levels 0–5 of "
                           "open-exact, falling, with either p)")
        order = p1_order("u_l2", s)
        return order, (f"{why}: λ = [u] is approximated by the jump of the broken P1 u, of the "
                       f"order of u in L²: h^{order:g} (2s, s = {s:g})")
    raise ValueError(f"unknown quantity {quantity!r}")


def p1_order(quantity, s):
    """The order of P1 on the cracked mesh for regularity s, of the references' error (P1
    Galerkin, conforming) and of the P1 interpolation error alike: u 2s (duality), p s; None for λ
    (the references' jump [u_h] superconverges on smooth solutions)."""
    factor = P1_ORDER_PER_S.get(quantity)
    return None if factor is None else factor * s


def reaches_p1_order(quantity, expected, s):
    """Whether a constant factor can bound the solver's error by a P1 error on the same mesh (the
    references' own, or the interpolation error): the solver's expected order is at least P1's
    (else the ratio grows as h → 0)."""
    ref = p1_order(quantity, s)
    return ref is None or (expected is not None and expected >= ref - 1e-12)


def declared_rate(declarations, u_space, multiplier, p_mass, quantity, p_space=DEFAULT_P_SPACE):
    """The scene's own (rate, reason) for this series ([[verification.expected_rate]]), or None;
    the first matching declaration wins (a declaration without p_space matches every p space)."""
    for d in declarations:
        if all(d.get(k, "*") in ("*", v) for k, v in (
                ("u_space", u_space), ("multiplier", multiplier), ("p_mass", p_mass),
                ("p_space", p_space), ("quantity", quantity))):
            return d["rate"], f"declared in the scene: {d['reason']}"
    return None


def threshold(expected, min_rate=None):
    """The smallest observed rate accepted for expected order `expected` (and the scene's
    optional floor min_rate)."""
    t = expected - RATE_MARGIN
    return t if min_rate is None else max(t, min_rate)
