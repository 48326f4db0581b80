"""Sentences of the report that describe measured data: each is computed from the numbers it
describes and says the opposite where they do (a fixed "the distance falls as δ decreases on
every level" was printed over a table where it rose)."""
from .render import fmt_delta


def delta_trend(points_by_level):
    """The δ → 0 trend of a distance, per level: {level: [(δ, distance), ...]} → one sentence.
    The distance falls on a level when it never rises from one δ to the next smaller one; a level
    where it rises is named with its first rise (the δ-pair and both values)."""
    falls, rises = [], []
    for lv in sorted(points_by_level):
        pts = sorted(points_by_level[lv], key=lambda p: -p[0])  # largest δ first
        rise = next(((a, b) for a, b in zip(pts, pts[1:]) if b[1] > a[1]), None)
        if rise is None:
            falls.append(lv)
        else:
            rises.append((lv, rise))
    if not rises:
        return "the distance falls as δ decreases on every level"
    parts = [f"on level {lv} it rises from {a[1]:.4g} at δ = {fmt_delta(a[0])} to {b[1]:.4g} at "
             f"δ = {fmt_delta(b[0])}" for lv, (a, b) in rises]
    head = ("the distance falls as δ decreases on level" + ("s " if len(falls) > 1 else " ")
            + ", ".join(map(str, falls)) + " only; " if falls
            else "the distance does not fall as δ decreases on any level: ")
    return head + "; ".join(parts)


def floor_trend(floors):
    """The δ = 0 floors of the levels, coarsest first (None: a level without δ = 0) → one
    sentence."""
    if any(f is None for f in floors) or len(floors) < 2:
        return "no δ = 0 floor on every level"
    values = " → ".join(f"{f:.3g}" for f in floors)
    if all(b < a for a, b in zip(floors, floors[1:])):
        return f"the floor decreases with h ({values})"
    return f"**the floor does not decrease with h** ({values})"
