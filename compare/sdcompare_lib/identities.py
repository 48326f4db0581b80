"""Identities between variants: where the method gives the same discrete solution two ways, the
stored fields of the two cases must agree to round-off.

The three multiplier spaces differ only in the contact rows of the LCP (paper (12)–(14)):
* **Crack entirely closed** (no multiplier active, Λ = 0: the contact term vanishes). Every
  variant then solves the same linear system, that of the problem without contact rows, so M0,
  M1 and M1star give the same u, p and a zero λ.
* **Crack entirely open** (every multiplier active: each constraint holds as an equality). On a
  crack without kinks p·ν is linear on each crack edge (the bubble vanishes there), so M1's rows
  ∫ φ_j p·ν = (M_c N P)_j and M1star's rows (N P)_j = p(x_j)·ν span the same equations
  (M_c is invertible), and the multipliers are the same function (Λ̃ = M_c Λ). At a kink M1star
  uses one averaged normal where M1's row integrates each edge's own (crates/sdcrack-core/src/multiplier.rs), so the
  identity holds only for cracks without kinks; M0 (one mean per segment) is weaker and differs.

Threshold: the two solves are backward stable on systems that differ only by an invertible row
transformation (or not at all), so their solutions differ by at most a small multiple of κ·ε in
relative terms, κ the condition estimate sdcrack reports (the larger of the two cases), ε the
float64 unit round-off. IDENTITY_FACTOR = 10 is that small multiple. Measured on the repository
scenes (levels 0–5): closed cracks bit for bit equal, open cracks ≤ 5e-5·κ·ε (2.9e-12 at κ = 1e10
on open-graded).
"""
import math
from collections import defaultdict

import numpy as np

from .read import finite_number
from .cases import case_key, variant_suffix
from .render import fmt_delta

EPS = np.finfo(float).eps
IDENTITY_FACTOR = 10.0
# Two crack edges are collinear when the sine of their angle is below this (the scene's
# coordinates are float64: 1e-12 is well above their round-off and far below any real kink).
COLLINEAR_SIN = 1e-12
# The arrays compared: u and p at the u dofs, p's bubbles (consistent p mass), λ on the crack.
ARRAYS = (("u", "u"), ("p", "p"), ("p_bubble", "p bubble"), ("lam", "λ"))


def crack_state(c):
    """"closed" (no multiplier active), "open" (every multiplier active) or None (mixed or not
    reported) of one case."""
    a, n = c.get("active_multipliers"), c.get("multipliers")
    if not (isinstance(a, int) and isinstance(n, int)) or n <= 0:
        return None
    return "closed" if a == 0 else "open" if a == n else None


def has_kink(crack_points, crack_segments):
    """True when two crack segments meet at a node at an angle (a node of degree 2 whose edges
    are not collinear)."""
    if crack_points is None:
        return False
    pts = np.asarray(crack_points, dtype=float)[:, :2]
    segs = (np.column_stack([np.arange(len(pts) - 1), np.arange(1, len(pts))])
            if crack_segments is None else np.asarray(crack_segments, dtype=np.int64))
    at = defaultdict(list)
    for a, b in segs:
        d = pts[b] - pts[a]
        d = d / max(np.linalg.norm(d), 1e-300)
        at[int(a)].append(d)
        at[int(b)].append(d)
    return any(len(ds) == 2 and abs(ds[0][0] * ds[1][1] - ds[0][1] * ds[1][0]) > COLLINEAR_SIN
               for ds in at.values())


def _pairs(state, kinked):
    """The multiplier pairs the identity holds for in this crack state."""
    if state == "closed":
        return (("M0", "M1"), ("M0", "M1star"), ("M1", "M1star"))
    if state == "open" and not kinked:
        return (("M1", "M1star"),)
    return ()


def _rel_max(a, b):
    """‖a − b‖_∞ / max(‖a‖_∞, ‖b‖_∞) (0 for two zero arrays; inf for different shapes)."""
    if a.shape != b.shape:
        return math.inf
    scale = max(float(np.abs(a).max(initial=0.0)), float(np.abs(b).max(initial=0.0)))
    if scale == 0.0:
        return 0.0
    return float(np.abs(a - b).max()) / scale


def _difference(fa, fb, name):
    """Relative difference of one stored array of two cases; None when neither has it. λ of
    different kinds (M0's P0 against a P1 λ, closed crack only) must both vanish: their larger
    value relative to u's."""
    a, b = fa.get(name), fb.get(name)
    if a is None and b is None:
        return None
    if a is None or b is None:
        return math.inf
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if name == "lam" and a.shape != b.shape:
        u_scale = max(float(np.abs(np.asarray(fa["u"])).max(initial=0.0)), 1e-300)
        return max(float(np.abs(a).max(initial=0.0)), float(np.abs(b).max(initial=0.0))) / u_scale
    return _rel_max(a, b)


def multiplier_identities(cases, fields):
    """Rows (one per compared pair of cases) and problems: pairs of cases of one (level, u space,
    p mass, p space, δ) whose multipliers give the same discrete solution in their common crack
    state (module doc) and whose stored fields differ by more than IDENTITY_FACTOR·κ·ε."""
    if fields is None:
        return [], []
    groups = defaultdict(dict)
    for c in cases:
        if fields.has_case(c.get("fields_grid")):
            k = case_key(c)
            groups[(k.level, k.u_space, k.p_mass, k.p_space, k.delta)][k.multiplier] = c
    rows, problems = [], []
    for (lvl, u, pm, ps, delta), by_m in sorted(groups.items()):
        states = {m: crack_state(c) for m, c in by_m.items()}
        loaded = {}
        for a, b in (("M0", "M1"), ("M0", "M1star"), ("M1", "M1star")):
            if a not in by_m or b not in by_m or states[a] is None or states[a] != states[b]:
                continue
            for m in (a, b):
                if m not in loaded:
                    loaded[m] = fields.case(by_m[m]["fields_grid"])
            fa, fb = loaded[a], loaded[b]
            kinked = has_kink(fa["crack_points"], fa["crack_segments"])
            if (a, b) not in _pairs(states[a], kinked):
                continue
            kappas = [by_m[m].get("condition_estimate") for m in (a, b)]
            kappa = max((float(k) for k in kappas if finite_number(k)), default=math.nan)
            tol = IDENTITY_FACTOR * kappa * EPS
            diffs = {label: _difference(fa, fb, name) for name, label in ARRAYS}
            diffs = {k: v for k, v in diffs.items() if v is not None}
            worst = max(diffs.values(), default=0.0)
            ok = math.isfinite(tol) and worst <= tol
            rows.append({"level": lvl, "u_space": u, "p_mass": pm, "p_space": ps, "delta": delta,
                         "state": states[a], "a": a, "b": b, "kappa": kappa, "tolerance": tol,
                         "differences": diffs, "worst": worst, "ok": bool(ok)})
            if ok:
                continue
            what = (f"level {lvl} {u}{variant_suffix(pm, ps)} δ={fmt_delta(delta)}: {a} and {b}, "
                    f"crack entirely {states[a]}")
            if not math.isfinite(tol):
                problems.append(f"{what}: no condition estimate in summary.json to bound their "
                                "difference")
                continue
            name, d = max(diffs.items(), key=lambda kv: kv[1])
            problems.append(f"{what}, must give the same solution: their {name} differ by "
                            f"{d:.1e} relative (> {IDENTITY_FACTOR:g}·κ·ε = {tol:.1e}, "
                            f"κ = {kappa:.2g})")
    return rows, problems


def requirement(rows):
    """The check's sentence, from the rows it compared."""
    if not rows:
        return "no two multipliers share an entirely closed or open crack here"
    by_state = defaultdict(int)
    for r in rows:
        by_state[r["state"]] += 1
    worst = max(r["worst"] for r in rows)
    parts = ", ".join(f"{n} pair(s) on an entirely {s} crack" for s, n in sorted(by_state.items()))
    return (f"multipliers that must give the same solution agree to ≤ {IDENTITY_FACTOR:g}·κ·ε "
            f"({parts}; largest difference {worst:.1e} relative)")


def not_applicable(rows, fields):
    """Why the check does not apply (None when it compared something)."""
    if rows:
        return None
    if fields is None:
        return "no stored fields"
    return ("no level has two multipliers with the crack entirely closed (no multiplier active) "
            "or, without kinks, entirely open (all active): the contact sets differ")
