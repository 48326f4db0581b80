"""Observed orders, the convergence rule, least-squares slopes and the GCI."""
import math

import numpy as np

# Convergence rule (stated in every report; theory.py says where each series' expected order p*
# comes from):
#   a series (errors against the exact or the reference solution, one per level, h halving) with
#   fewer than RULE_LEVELS levels is "inconclusive"; otherwise it "converges" iff over its last
#   RULE_LEVELS levels the errors decrease strictly AND each of the last two observed rates
#   log(e_(l-1)/e_l)/log(h_(l-1)/h_l) is >= p* − 0.1 (theory.RATE_MARGIN; and >= the scene's
#   min_rate when it declares one); else it "does not converge". Two rates, not one, and no
#   extrapolation: a series slowing toward a non-zero floor (the X-norm of p for continuous u on the
#   open crack, levels 1-3: 2.582, 1.944, 1.526, rates 0.41, 0.35) fails on its last rate, whatever
#   the number of levels; a series converging at a wrong order (a load evaluated at one vertex:
#   u rate 2.0 -> 1.06 on the closed crack) fails against p* = 2. A series whose errors are all
#   <= ZERO_FLOOR is exact ("converges", rates null): e.g. e_lambda on a closed crack, where
#   lambda_h = [u] = 0 exactly.
RULE_LEVELS = 3
ZERO_FLOOR = 1e-13


def rule_text(margin, min_rate=None):
    return (f"a series converges iff its errors decrease strictly over the last {RULE_LEVELS} "
            f"levels and each of the last two observed rates log(e_(l−1)/e_l)/log(h_(l−1)/h_l) is "
            f"≥ its expected order − {margin:g} (the expected order of each series, from the "
            "regularity of the solution and Theorem 4.3, is shown beside it with its reason"
            + (f"; the scene's floor min_rate = {min_rate:g} applies too" if min_rate else "")
            + f"); with fewer than {RULE_LEVELS} levels it is inconclusive; errors all ≤ "
            f"{ZERO_FLOOR:g} are exact (converges).")


def rate(h0, e0, h1, e1):
    if not (e0 > 0 and e1 > 0 and h0 > 0 and h1 > 0 and h0 != h1):
        return None
    return math.log(e0 / e1) / math.log(h0 / h1)


def successive_rates(h, e):
    return [rate(h[i - 1], e[i - 1], h[i], e[i]) for i in range(1, len(h))]


def series_status(h, e, levels, min_rate):
    """(status, reason) of one error series by the rule above; status is "converges",
    "does not converge" or "inconclusive". h, e, levels: coarse to fine, errors finite."""
    if len(e) < RULE_LEVELS:
        return "inconclusive", (f"{len(e)} level(s); {RULE_LEVELS} are needed to measure two rates")
    if all(abs(x) <= ZERO_FLOOR for x in e):
        return "converges", f"exact: every error ≤ {ZERO_FLOOR:g}"
    tail = list(zip(h, e, levels))[-RULE_LEVELS:]
    steps = []
    for (h0, e0, l0), (h1, e1, l1) in zip(tail, tail[1:]):
        if not e1 < e0:
            return "does not converge", (f"the error grows from level {l0} to {l1} "
                                         f"({e0:.3e} → {e1:.3e})")
        r = rate(h0, e0, h1, e1)
        if r is not None and r < min_rate:
            return "does not converge", (f"rate {r:.2f} < {min_rate:g} from level {l0} to {l1} "
                                         f"({e0:.3e} → {e1:.3e})")
        steps.append("exact" if r is None else f"{r:.2f}")
    return "converges", f"rates {', '.join(steps)} ≥ {min_rate:g} on the last two steps"


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
