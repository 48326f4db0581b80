"""Observed orders, the convergence rule, least-squares slopes and the GCI."""
import math

import numpy as np

from . import theory

# Convergence rule (stated in every report; theory.py says where each series' expected order p*
# comes from, docs/verification.md "When a series can be judged" derives it):
#   The observed rate of a step, r = log(e_(l-1)/e_l)/log(h_(l-1)/h_l), estimates p* only in the
#   asymptotic range: with e(h) = C h^p* (1 + D h^q + ...), q > 0, the deficit p* − r shrinks by
#   about 2^-q per halving of h, from either side and not always monotonically (a P1 multiplier's
#   rate dips below its order before it settles). A series is judged on its last RULE_LEVELS (3)
#   levels and its last two rates r_(k-1), r_k against t = p* − margin (theory.RATE_MARGIN, and the
#   scene's min_rate when it declares one):
#   * "converges": the errors decrease strictly, r_k ≥ t, and r_(k-1) ≥ t or r_(k-1) is within
#     half the bug gap of p* (≥ p* − BUG_GAP/2) and rising into t;
#   * "does not converge", at any number of levels: the errors grow; or r_k < t and the rate is
#     falling away from p* (two falls in a row, or a fall to below p* − BUG_GAP/2, nearer the order
#     of a bug BUG_GAP lower than to its own); or r_k < t and rising so slowly that, with its
#     deficit shrinking at the pace of its last step, it would need more than EXTRA_LEVELS more
#     levels to reach t (a series of order p* − BUG_GAP stays ≈ BUG_GAP below p*: its deficit does
#     not shrink); or r_k ≤ r_(k-1) < t (stalled);
#   * "inconclusive" (cannot judge yet), with the levels to run: fewer than 3 levels; a rate that
#     fell below t right after reaching p* but stays within BUG_GAP/2 of it (a dip or the start of
#     a fall: one more level tells); a rate rising toward t fast enough to reach it within
#     EXTRA_LEVELS more levels; a last rate at t after one far below it (one more level confirms).
#   A series slowing toward a non-zero floor (the X-norm of p for continuous u on the open crack,
#   levels 1-5: rates 0.42, 0.35, 0.27) fails on its two falls; a series converging at a wrong
#   order (a load evaluated at one vertex: u rate 2.0 -> 1.06 on the closed crack) fails against
#   p* = 2 at any length. A series whose errors are all <= ZERO_FLOOR is exact ("converges", rates
#   null): e.g. e_lambda on a closed crack, where lambda_h = [u] = 0 exactly.
RULE_LEVELS = theory.RULE_LEVELS
ZERO_FLOOR = 1e-13
BUG_GAP = theory.BUG_GAP
EXTRA_LEVELS = theory.EXTRA_LEVELS
# Two rates closer than this are equal: a rate's round-off is ~eps·|log e|/log 2 ≈ 1e-14, and a
# series converging at a steady lower order must read as stalled, not as rising or falling.
RATE_TIE = 1e-9


def rule_text(margin, min_rate=None, source="the regularity of the solution and Theorem 4.3"):
    """The rule in words; `source`: where the expected orders come from (the scalar problem's
    default; the elastic report names its own, elastic_theory.py)."""
    return (f"a series is judged on its last {RULE_LEVELS} levels and its last two observed rates "
            f"log(e_(l−1)/e_l)/log(h_(l−1)/h_l) against t = its expected order p* − {margin:g} "
            f"(the expected order of each series, from {source}, is shown beside it with its reason"
            + (f"; the scene's floor min_rate = {min_rate:g} raises t" if min_rate else "")
            + "). It converges when its errors decrease and its last rate is ≥ t, the one before "
            f"too or rising into t from within {BUG_GAP / 2:g} of p*. It does not converge when "
            "its error grows, its rate is below t and falling away from p* (two falls in a row, or "
            f"a fall to below p* − {BUG_GAP / 2:g}, nearer a bug's order p* − {BUG_GAP:g} than "
            f"to p*), stalled, or rising too slowly to reach t within {EXTRA_LEVELS} more levels "
            "at its last step's pace. Otherwise it is inconclusive (cannot judge yet) and says "
            f"which levels to run: fewer than {RULE_LEVELS} levels, a dip below t right after "
            f"reaching p*, or a rate rising toward t. Errors all ≤ {ZERO_FLOOR:g} are exact "
            "(converges).")


def rate(h0, e0, h1, e1):
    if not (e0 > 0 and e1 > 0 and h0 > 0 and h1 > 0 and h0 != h1):
        return None
    return math.log(e0 / e1) / math.log(h0 / h1)


def successive_rates(h, e):
    return [rate(h[i - 1], e[i - 1], h[i], e[i]) for i in range(1, len(h))]


def levels_to_reach(target_deficit, deficit_before, deficit_now):
    """How many more levels a rate rising toward its order needs for its deficit (p* − r) to
    fall from deficit_now to target_deficit, if it keeps shrinking by deficit_now/deficit_before
    per level (the geometric pace of the asymptotic expansion's correction term); None when it
    does not shrink."""
    if not (0 < deficit_now < deficit_before):
        return None
    if deficit_now <= target_deficit:
        return 0
    pace = deficit_now / deficit_before
    return math.ceil(math.log(target_deficit / deficit_now) / math.log(pace) - 1e-12)


def series_status(h, e, levels, min_rate):
    """(status, reason) of one error series by the rule above (series_judgement without the
    levels to run)."""
    return series_judgement(h, e, levels, min_rate)[:2]


def series_judgement(h, e, levels, min_rate):
    """(status, reason, run_up_to) of one error series by the rule above; status is "converges",
    "does not converge" or "inconclusive" (cannot judge yet: run_up_to is the finest level to run
    for a verdict, which the reason says too; None otherwise). h, e, levels: coarse to fine,
    errors finite; min_rate: the threshold t = p* − margin (or the scene's higher floor); p* is
    taken as t + margin."""
    if len(e) < RULE_LEVELS:
        first = levels[0] if levels else 0
        up_to = first + RULE_LEVELS - 1
        return "inconclusive", (f"{len(e)} level(s); {RULE_LEVELS} are needed to measure two "
                                f"rates: run levels up to {up_to}"), up_to
    if all(abs(x) <= ZERO_FLOOR for x in e):
        return "converges", f"exact: every error ≤ {ZERO_FLOOR:g}", None
    tail = list(zip(h, e, levels))[-RULE_LEVELS:]
    steps = []
    for (h0, e0, l0), (h1, e1, l1) in zip(tail, tail[1:]):
        # 0 → 0 is two exact levels (a field the discretisation represents, its round-off taken
        # as 0 by the caller), not growth: e.g. a patch's SIF, quadrature error 4e-10 at level 0
        # and exact from level 1 on
        if not (e1 < e0 or e1 == e0 == 0.0):
            return "does not converge", (f"the error grows from level {l0} to {l1} "
                                         f"({e0:.3e} → {e1:.3e})"), None
        steps.append(rate(h0, e0, h1, e1))
    if any(r is None for r in steps):  # an exact level among the last three: nothing to fit
        return "converges", ("rates " + ", ".join("exact" if r is None else f"{r:.2f}"
                                                  for r in steps) + " on the last two steps"), None
    earlier = successive_rates(h, e)
    before = earlier[-3] if len(earlier) >= 3 else None
    status, reason, extra = _judge_rates(steps[0], steps[1], before, min_rate,
                                         [t[2] for t in tail])
    return status, reason, (levels[-1] + extra if extra else None)


def _judge_rates(r0, r1, before, t, lv):
    """(status, reason, more levels to run or None) of the rule on the last two rates r0
    (levels lv[0] → lv[1]) and r1 (lv[1] → lv[2]), `before` the rate before them (None with
    three levels), t the threshold."""
    target = t + theory.RATE_MARGIN  # p*
    band = target - BUG_GAP / 2
    step0 = f"{r0:.2f} from level {lv[0]} to {lv[1]}"
    step1 = f"{r1:.2f} from level {lv[1]} to {lv[2]}"
    if r1 >= t and r0 >= t:
        return "converges", f"rates {r0:.2f}, {r1:.2f} ≥ {t:g} on the last two steps", None
    if r1 >= t and r0 >= band:
        return "converges", (f"rates {r0:.2f}, {r1:.2f}: rising into ≥ {t:g} from within "
                             f"{BUG_GAP / 2:g} of its order {target:g}"), None
    if r1 >= t:
        return "inconclusive", (f"rate {step1} ≥ {t:g} right after {step0}, below {band:g}: "
                                f"one more level confirms; run levels up to {lv[2] + 1}"), 1
    # r1 < t from here on; a change of rate within RATE_TIE is round-off, not a fall or a rise
    if r1 < r0 - RATE_TIE:
        fell_twice = before is not None and r0 < before - RATE_TIE
        if r1 < band:
            return "does not converge", (f"rate {r1:.2f} < {t:g} from level {lv[1]} to {lv[2]}, "
                                         f"falling from {r0:.2f} to below {band:g}: nearer the "
                                         f"order of a bug {BUG_GAP:g} lower than its own "
                                         f"{target:g}"), None
        if fell_twice:
            return "does not converge", (f"rate {r1:.2f} < {t:g} from level {lv[1]} to {lv[2]}, "
                                         f"falling for two steps ({before:.2f}, {r0:.2f}, "
                                         f"{r1:.2f}): falling away from its order "
                                         f"{target:g}"), None
        return "inconclusive", (f"rate {step1} < {t:g}, down from {r0:.2f} but within "
                                f"{BUG_GAP / 2:g} of its order {target:g}: a dip or the start "
                                f"of a fall; run levels up to {lv[2] + 1}"), 1
    need = (levels_to_reach(target - t, target - r0, target - r1) if r1 > r0 + RATE_TIE
            else None)
    if need is None:
        return "does not converge", (f"rate {r1:.2f} < {t:g} from level {lv[1]} to {lv[2]}, "
                                     f"stalled ({r0:.2f}, {r1:.2f})"), None
    if need > EXTRA_LEVELS:
        return "does not converge", (f"rate {r1:.2f} < {t:g} from level {lv[1]} to {lv[2]}, "
                                     f"rising from {r0:.2f} too slowly: at this pace it reaches "
                                     f"{t:g} only after {need} more levels "
                                     f"(> {EXTRA_LEVELS})"), None
    return "inconclusive", (f"rate {step1} < {t:g}, rising from {r0:.2f} toward its order "
                            f"{target:g} (deficit ×{(target - r1) / (target - r0):.2f} per level):"
                            f" run levels up to {lv[2] + need}"), need


def fit_line(x, y):
    """Least-squares line log y = a + b log x over the points with x > 0 and y > 0: (b, a,
    residuals), residuals[i] = log y_i − (a + b log x_i) (None where the point is not fitted);
    None with fewer than two distinct x."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    m = (x > 0) & (y > 0) & np.isfinite(x) & np.isfinite(y)
    if m.sum() < 2 or np.unique(x[m]).size < 2:
        return None
    b, a = np.polyfit(np.log(x[m]), np.log(y[m]), 1)
    res = [float(np.log(yi) - (a + b * np.log(xi))) if mi else None
           for xi, yi, mi in zip(x, y, m)]
    return float(b), float(a), res


def fit_slope(x, y):
    """Least-squares slope of log y against log x over the points with x > 0 and y > 0."""
    line = fit_line(x, y)
    return None if line is None else line[0]


def gci(h, f):
    """Roache's Grid Convergence Index (ASME V&V 20-2009) from the three finest levels.

    h, f: sequences ordered coarse -> fine (at least 3); the last three are used:
    f3 (coarse), f2, f1 (fine), r21 = h2/h1, r32 = h3/h2. With constant r (nested levels):
      p = ln|ε32/ε21| / ln r,  ε21 = f2 − f1,  ε32 = f3 − f2,
      e_a = |(f1 − f2)/f1| (relative), GCI_fine = 1.25 e_a / (r^p − 1),
      f_ext = (r^p f1 − f2)/(r^p − 1) (Richardson).
    Non-constant r uses the fixed-point iteration of Celik et al. (2008).
    """
    if len(h) < 3:
        return None
    h3, h2, h1 = h[-3:]
    f3, f2, f1 = f[-3:]
    e21, e32 = f2 - f1, f3 - f2
    out = {"h": [h3, h2, h1], "f": [f3, f2, f1], "r": h2 / h1}
    if e21 == 0 or e32 == 0:
        out.update(p=None, gci_fine=0.0 if e21 == 0 else None, f_ext=f1, oscillatory=False,
                   note="zero difference between levels")
        return out
    r21, r32 = h2 / h1, h3 / h2
    ratio = e32 / e21
    oscillatory = ratio < 0
    if abs(r21 - r32) < 1e-9 * r21:
        p = math.log(abs(ratio)) / math.log(r21)
    else:
        s = 1.0 if ratio > 0 else -1.0
        p = 1.0
        for _ in range(200):
            q = math.log((r21 ** p - s) / (r32 ** p - s))
            p_new = abs(math.log(abs(ratio)) + q) / math.log(r21)
            if abs(p_new - p) < 1e-12:
                break
            p = p_new
    rp = r21 ** p
    out["p"] = p
    if rp - 1.0 <= 0 or f1 == 0:
        out.update(gci_fine=None, f_ext=None, oscillatory=oscillatory, note="p <= 0 or f1 = 0")
        return out
    ea = abs((f1 - f2) / f1)
    out.update(gci_fine=1.25 * ea / (rp - 1.0), f_ext=(rp * f1 - f2) / (rp - 1.0),
               oscillatory=oscillatory, note="oscillatory convergence" if oscillatory else "")
    return out
