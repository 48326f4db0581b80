"""Theorem 2.1 quantitatively: the δ-constant must converge as h → 0.

Theorem 2.1 bounds ‖x_δ − x_0‖ ≤ C δ with C independent of h, and the discrete δ-limit of the
smooth-domain method commutes with h → 0: (x_δ − x_0)/δ tends, as h → 0, to a fixed function.
The "δ → 0" check only asks that ‖x_δ − x_0‖ be linear in δ on each level; a δ that enters the
matrix with a mesh-dependent scale (δ·h^k) is still exactly linear in δ on each level, and passes
it. Here the constant

    K_l(δ) = ‖x_δ − x_0‖ / (δ ‖x_0‖)        (level l, every δ > 0 of the sweep)

must settle from level to level: on the last step of the run, |log K_L − log K_{L'}| / (L − L')
≤ log(2)/4. A δ scaled by h^k changes K by a factor 2^k per level, so every k ≥ 1/4 FAILs; the
bound is that detection power, not a fit to our output. Dividing by ‖x_0‖ keeps quantities whose
own size tends to 0 with h (a continuous u's λ is O(h)) comparable.

Judged: u and p (fields on all of Ω, whose δ-derivative is one global function). λ is left out:
its constant converges only once the contact set has settled, which on tip-contact happens after
level 4 (its λ constant still changes by 0.79 at level 3 and 0.18 at level 4). The last step is
judged when the finest level is ≥ MIN_LEVEL = 3: on the repository scenes |Δ log K| of u and p
is at most 0.40 per level up to level 2 (stress-active-set, whose contact set settles at level 3),
0.090 at level 3, 0.056 at level 4 and 0.017 at level 5 (nightly, levels 0–5), against the bound
log(2)/4 = 0.173.
"""
import math
from collections import defaultdict

from .cases import p_mass, p_space, variant_suffix
from .render import fmt_delta
from .verdict import ROUNDOFF_REL  # below it (relative) a δ-difference is round-off: not judged

MAX_LOG_CHANGE = math.log(2.0) / 4
MIN_LEVEL = 3
QUANTITIES = ("u_l2", "p_l2")


def constants(delta_limit):
    """{(u space, multiplier, p mass, p space, quantity, δ): {level: K}} from the δ-limit
    entries (verdict.compute_delta_limit); a level whose difference is round-off is left out."""
    out = defaultdict(dict)
    for e in delta_limit:
        if e["quantity"] not in QUANTITIES or not e["norm_ref"] > 0:
            continue
        for d, diff in zip(e["deltas"], e["diffs"]):
            if d > 0 and diff > ROUNDOFF_REL * e["norm_ref"]:
                key = (e["u_space"], e["multiplier"], p_mass(e), p_space(e), e["quantity"], d)
                out[key][int(e["level"])] = diff / (d * e["norm_ref"])
    return out


def rows(delta_limit):
    """One row per (variant, quantity, δ) with at least two levels: the constants per level and
    the per-level change of the last step; `judged` when the finest level is ≥ MIN_LEVEL."""
    out = []
    for (u, m, pm, ps, q, d), by_level in sorted(constants(delta_limit).items()):
        levels = sorted(by_level)
        if len(levels) < 2:
            continue
        lo, hi = levels[-2], levels[-1]
        change = abs(math.log(by_level[hi] / by_level[lo])) / (hi - lo)
        judged = hi >= MIN_LEVEL
        out.append({"u_space": u, "multiplier": m, "p_mass": pm, "p_space": ps, "quantity": q,
                    "delta": d, "levels": levels, "constants": [by_level[lv] for lv in levels],
                    "last_change": change, "judged": judged,
                    "ok": (not judged) or change <= MAX_LOG_CHANGE})
    return out


def problems(rs):
    return [_problem(r) for r in rs if not r["ok"]]


def _problem(r):
    lo, hi = r["levels"][-2], r["levels"][-1]
    k = dict(zip(r["levels"], r["constants"]))
    return (f"{r['u_space']} {r['multiplier']}{variant_suffix(r['p_mass'], r['p_space'])} "
            f"{r['quantity']} δ={fmt_delta(r['delta'])}: the δ-constant "
            f"‖x_δ − x_0‖/(δ‖x_0‖) goes {k[lo]:.3g} → {k[hi]:.3g} from level {lo} to "
            f"{hi}, a factor {math.exp(r['last_change']):.3g} per level (> "
            f"{math.exp(MAX_LOG_CHANGE):.3g}): it does not converge as h → 0 "
            "(Theorem 2.1), as if δ were scaled with the mesh")


def requirement(rs):
    judged = [r for r in rs if r["judged"]]
    text = (f"the δ-constant ‖x_δ − x_0‖/(δ‖x_0‖) of u and p changes by ≤ "
            f"{math.exp(MAX_LOG_CHANGE):.3g}× per level on the last step (Theorem 2.1: it "
            "converges as h → 0)")
    if judged:
        worst = max(judged, key=lambda r: r["last_change"])
        text += (f"; largest {math.exp(worst['last_change']):.3f}× ({len(judged)} constants, "
                 f"{worst['u_space']} {worst['multiplier']}"
                 f"{variant_suffix(worst['p_mass'], worst['p_space'])} {worst['quantity']} "
                 f"δ={fmt_delta(worst['delta'])})")
    return text


def not_applicable(rs, deltas, delta_limit):
    """Why the check does not apply (None where it judged something)."""
    if any(r["judged"] for r in rs):
        return None
    if len(deltas) < 2:
        return "the run has one δ: no sweep"
    if not delta_limit:
        return "no δ-limit measured (the δ → 0 check says why)"
    levels = sorted({int(e["level"]) for e in delta_limit})
    if not rs:
        return "the δ-differences of u and p are round-off or measured on one level only"
    return (f"finest level {levels[-1]} < {MIN_LEVEL}: the constant is judged from level "
            f"{MIN_LEVEL} on (coarser levels are pre-asymptotic)")
