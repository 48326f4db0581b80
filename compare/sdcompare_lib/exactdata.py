"""The scene's exact data checked against what the scene implies, before any series is judged
against them (issue 42; the same check as ``sdcrack check``, crates/sdcrack-core/src/scene/exact_data.rs,
with the same sample points and tolerances):

- ``[exact] px``, ``py`` against ∂u/∂x, ∂u/∂y of ``[exact] u`` (sdexpr's symbolic derivative);
- ``[data] f`` against −Δu (the problem is −Δu = f in Ω \\ Γc, docs/scenes.md) on both sides of
  every crack;
- ``[data] g`` against u on ∂Ω (u = g on ∂Ω);
- ``[exact] jump`` (else u⁺ − u⁻ by the face rule, ``sdexpr.on_face``) against the one-sided limits
  of u on Γc (ν: the segment's direction turned by +90°; the + face is the side ν points into);
- the contact conditions of the exact solution: [∂u/∂ν] = 0, [u] ≥ 0, ∂u/∂ν ≤ 0 and
  [u]·∂u/∂ν = 0 on Γc (the scene format has no open/closed declaration to hold them to: the
  exact data decide where the crack is open).

The expression language has no simplifier that could prove two expressions equal, so the
comparisons are at sampled points, each with the tolerance of its own evaluation:

- two values that should be equal must differ by more than ROUNDOFF_SAFETY × the sum of their
  running round-off bounds (``bounded``: Wilkinson's first-order running error analysis, Higham,
  Accuracy and Stability of Numerical Algorithms, §3.3; the margin 4 covers the neglected
  second-order terms) to be a violation: a correct scene's two sides agree to round-off, a wrong
  one (a flipped sign, a wrong term) is off by the size of the term;
- a value on a face of Γc is the one-sided limit of the value at c ± εν, extrapolated from
  ε = LIMIT_STEP·|segment| and ε/2 (L = 2a(ε/2) − a(ε)), with the truncation estimate
  |a(ε) − a(ε/2)| (≥ the remainder of a smooth a(ε)) times TRUNCATION_SAFETY added to its
  tolerance.

A point where a value or its bound is not finite (a singular derivative) is skipped. Tips and
kinks are never sampled (u may be singular there).
"""

import math

import numpy as np

from sdshared import sdexpr

GRID = 20  # grid points per direction over Ω's bounding box
GRID_OFFSET = 0.381966011250105  # 2 − φ: irrational, so that no point falls on a crack line
CRACK_SAMPLES = 8  # points k/8 of every crack segment, 0 < k < 8 (no tip, no kink)
NEAR_CRACK = 1e-3  # distance of the near-crack points, relative to the segment's length
BOUNDARY_SAMPLES = 12  # points per edge of ∂Ω, at (k + GRID_OFFSET)/12
LIMIT_STEP = 1e-4  # the larger ε of the one-sided limits, relative to the segment's length
ROUNDOFF_SAFETY = 4.0
TRUNCATION_SAFETY = 4.0
U = 2.0 ** -53  # unit round-off of float64

LABEL = "exact data"
REQUIREMENT = ("the scene's [exact] data are those of an exact solution: px, py = ∂u/∂x, ∂u/∂y; "
               "f = −Δu on both sides of Γc; g = u on ∂Ω; jump = u⁺ − u⁻; [∂u/∂ν] = 0, [u] ≥ 0, "
               "∂u/∂ν ≤ 0, [u]·∂u/∂ν = 0 on Γc (at sampled points, to their round-off bounds)")
NOT_JUDGED = ("not judged: the scene's exact data are inconsistent (see the check \"exact data\"); "
              "{n} problem(s) measured against them are not counted")
# The checks whose verdict compares the results with the scene's exact solution: with
# inconsistent exact data their problems say nothing of the solver (sdcompare marks them not
# judged). Every other check (KKT, references, completeness, meshes, …) stands.
# ("independent errors" stands: it checks that sdcrack computed its errors against the scene's
# data as this tool does, which holds or not whatever the data are.)
JUDGED_AGAINST_EXACT = ("series", "expectations", "interpolation yardstick", "reference yardstick",
                        "reference ratio settles", "recorded reference ratio",
                        "Theorem 2.1 (exact)", "reference orders",
                        "reference interpolation yardstick")


# ---------------------------------------------------------------------------------------------
# Evaluation with a running round-off bound (numpy, elementwise)
# ---------------------------------------------------------------------------------------------

def _scaled(coefficient, error):
    """|coefficient|·error with 0·∞ = 0 (an operand without error contributes none)."""
    with np.errstate(all="ignore"):
        return np.where(error == 0.0, 0.0, np.abs(coefficient) * error)


def bounded(tree, x, y):
    """(value, first-order round-off bound) of the expression at the points (x, y), the
    coordinates taken as exact: every operation adds its rounding (U·|v| for + − × ÷ √, 2U·|v| for
    the libm functions) to its operands' errors propagated through its derivative; a decision the
    errors could flip (sign near 0, atan2 on its cut) adds the largest change it can make."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)

    def ev(n):
        k = n[0]
        if k == "num":  # an integer literal is exact; others (0.1, pi) are rounded
            v = np.full(x.shape, n[1])
            return v, (0.0 if float(n[1]).is_integer() else U) * np.abs(v)
        if k == "x":
            return x.copy(), np.zeros(x.shape)
        if k == "y":
            return y.copy(), np.zeros(x.shape)
        if k == "neg":
            a, ea = ev(n[1])
            return -a, ea
        if k == "f1":
            return _f1(n[1], *ev(n[2]))
        if k == "f2":
            return _f2(n[1], *ev(n[2]), *ev(n[3]))
        (a, ea), (b, eb) = ev(n[1]), ev(n[2])
        if k == "+":
            v = a + b
            return v, ea + eb + U * np.abs(v)
        if k == "-":
            v = a - b
            return v, ea + eb + U * np.abs(v)
        if k == "*":
            v = a * b
            return v, _scaled(b, ea) + _scaled(a, eb) + U * np.abs(v)
        if k == "/":
            v = a / b
            return v, _scaled(1.0 / b, ea) + _scaled(v / b, eb) + U * np.abs(v)
        if k == "^":
            v = np.power(a, b)
            da = b * np.power(a, b - 1.0)
            db = np.where(v == 0.0, 0.0, v * np.log(np.abs(a)))  # 0^b: flat in b > 0
            return v, _scaled(da, ea) + _scaled(db, eb) + 2 * U * np.abs(v)
        raise ValueError(f"bad node {n!r}")

    with np.errstate(all="ignore"):
        return ev(sdexpr.parse(tree) if isinstance(tree, str) else tree)


def _f1(name, a, ea):
    v = sdexpr.to_numpy(("f1", name, ("x",)))(a, 0.0)
    libm = 2 * U * np.abs(v)
    if name == "sin":
        return v, _scaled(np.cos(a), ea) + libm
    if name == "cos":
        return v, _scaled(np.sin(a), ea) + libm
    if name == "tan":
        return v, _scaled(1.0 / np.cos(a) ** 2, ea) + libm
    if name == "exp":
        return v, _scaled(v, ea) + libm
    if name == "log":
        return v, _scaled(1.0 / a, ea) + libm
    if name == "sqrt":
        return v, _scaled(0.5 / v, ea) + U * np.abs(v)
    if name == "abs":
        return v, ea
    if name == "sign":  # either sign when a is within its error of 0: a change of 2 at most
        return v, np.where((ea > 0) & (np.abs(a) <= ea), 2.0, 0.0)
    raise ValueError(f"bad function {name!r}")


def _f2(name, a, ea, b, eb):
    if name == "atan2":
        v = np.arctan2(a, b)
        r2 = a * a + b * b
        e = _scaled(b / r2, ea) + _scaled(a / r2, eb) + 2 * U * np.abs(v)
        # on the branch cut (b < 0, a within its error of 0) the angle may jump by 2π
        return v, e + np.where((b < 0) & (ea > 0) & (np.abs(a) <= ea), 2 * math.pi, 0.0)
    # min, max: 1-Lipschitz in each operand. (A derivative's selection between branches is
    # written with sign() by sdexpr.derivative, whose bound covers a flip.)
    fn = np.fmin if name == "min" else np.fmax
    return fn(a, b), np.maximum(ea, eb)


# ---------------------------------------------------------------------------------------------
# Sample points
# ---------------------------------------------------------------------------------------------

def _segments(cracks):
    """(a, b, ν, length) of every crack segment, ν = (b − a)/|b − a| turned by +90°."""
    for c in cracks:
        c = np.asarray(c, dtype=float)
        for a, b in zip(c[:-1], c[1:]):
            length = math.hypot(b[0] - a[0], b[1] - a[1])
            yield a, b, np.array([-(b[1] - a[1]) / length, (b[0] - a[0]) / length]), length


def crack_points(cracks):
    """(points (K, 2), normals (K, 2), segment lengths (K,)) at k/CRACK_SAMPLES of every segment."""
    pts, normals, lengths = [], [], []
    for a, b, nu, length in _segments(cracks):
        for i in range(1, CRACK_SAMPLES):
            t = i / CRACK_SAMPLES
            pts.append([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])])
            normals.append(nu)
            lengths.append(length)
    return (np.array(pts, dtype=float).reshape(-1, 2), np.array(normals, dtype=float).reshape(-1, 2),
            np.array(lengths, dtype=float))


def _inside(p, polygon):
    """Strictly inside the polygon (winding number ≠ 0; a point on an edge is not inside)."""
    wn = 0
    n = len(polygon)
    for k in range(n):
        a, b = polygon[k], polygon[(k + 1) % n]
        cross = (b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])
        if cross == 0.0 and min(a[0], b[0]) <= p[0] <= max(a[0], b[0]) \
                and min(a[1], b[1]) <= p[1] <= max(a[1], b[1]):
            return False
        if a[1] <= p[1] < b[1] and cross > 0:
            wn += 1
        elif b[1] <= p[1] < a[1] and cross < 0:
            wn -= 1
    return wn != 0


def interior_points(polygon, cracks):
    """The GRID² grid points inside Ω, then points at NEAR_CRACK·|segment| on both sides of every
    crack sample point."""
    poly = np.asarray(polygon, dtype=float)
    lo, hi = poly.min(axis=0), poly.max(axis=0)
    out = []
    for i in range(GRID):
        for j in range(GRID):
            p = (lo[0] + (i + GRID_OFFSET) / GRID * (hi[0] - lo[0]),
                 lo[1] + (j + GRID_OFFSET) / GRID * (hi[1] - lo[1]))
            if _inside(p, poly):
                out.append(p)
    c, nu, length = crack_points(cracks)
    for side in (1.0, -1.0):
        out += list(c + (side * NEAR_CRACK * length)[:, None] * nu)
    return np.array(out, dtype=float).reshape(-1, 2)


def boundary_points(polygon):
    poly = np.asarray(polygon, dtype=float)
    t = (np.arange(BOUNDARY_SAMPLES) + GRID_OFFSET) / BOUNDARY_SAMPLES
    return np.concatenate([a + t[:, None] * (b - a) for a, b in zip(poly, np.roll(poly, -1, axis=0))])


def scene_polygon(scene):
    """∂Ω of a scene dict as its vertex list, None for a mesh-file scene (no [geometry])."""
    domain = (scene.get("geometry") or {}).get("domain") or {}
    if "rectangle" in domain:
        (x0, y0), (x1, y1) = domain["rectangle"]
        return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)]
    if "polygon" in domain:
        return [tuple(v) for v in domain["polygon"]]
    return None


# ---------------------------------------------------------------------------------------------
# The check
# ---------------------------------------------------------------------------------------------

def _fmt(v):
    return f"{v + 0.0:.6g}"  # + 0.0: no "-0"


def _at(p):
    return f"({_fmt(p[0])}, {_fmt(p[1])})"


def _differs(a, ta, b, tb):
    """Certainly different: both finite with finite tolerances, apart by more than both."""
    with np.errstate(invalid="ignore"):
        ok = np.isfinite(a) & np.isfinite(b) & np.isfinite(ta) & np.isfinite(tb)
        return ok & (np.abs(a - b) > ta + tb)


def _first(mask):
    idx = np.flatnonzero(mask)
    return int(idx[0]) if idx.size else None


def _one_sided(tree_or_fn, c, nu, length, side):
    """(limit, tolerance) of an expression (or a function giving (value, bound)) at the crack
    points from the face ``side``, extrapolated from ε and ε/2."""
    fn = tree_or_fn if callable(tree_or_fn) else (lambda x, y: bounded(tree_or_fn, x, y))
    eps = LIMIT_STEP * length
    q1 = c + (side * eps)[:, None] * nu
    q2 = c + (side * eps / 2)[:, None] * nu
    (a1, e1), (a2, e2) = fn(q1[:, 0], q1[:, 1]), fn(q2[:, 0], q2[:, 1])
    return 2 * a2 - a1, ROUNDOFF_SAFETY * (2 * e2 + e1) + TRUNCATION_SAFETY * np.abs(a1 - a2)


def check_scene(scene):
    """The problems of a scene dict's exact data, [] when it has none or they hold; each a
    sentence naming the field, both values and the point. Returns (problems, what was checked)."""
    ex = scene.get("exact")
    if not isinstance(ex, dict) or "u" not in ex:
        return [], None
    from .exact import scene_cracks

    data = scene.get("data") or {}
    u = sdexpr.parse(ex["u"])
    px = sdexpr.parse(ex["px"]) if "px" in ex else sdexpr.derivative(u, "x")
    py = sdexpr.parse(ex["py"]) if "py" in ex else sdexpr.derivative(u, "y")
    cracks = scene_cracks(scene)
    polygon = scene_polygon(scene)
    problems = []
    notes = []
    if polygon is not None:
        pts = interior_points(polygon, cracks)
        problems += _gradient(u, px, py, ex, pts)
        problems += _source(u, sdexpr.parse(data.get("f", "0")), pts)
        problems += _boundary(u, sdexpr.parse(data.get("g", "0")), boundary_points(polygon))
        notes.append(f"{len(pts)} points in Ω, {BOUNDARY_SAMPLES} per edge of ∂Ω")
    else:
        notes.append("px, py, f and g not checked: the domain is the mesh file's (no [geometry])")
    c, nu, length = crack_points(cracks)
    if len(c):
        problems += _crack(u, px, py, ex, c, nu, length)
        notes.append(f"{len(c)} points on Γc")
    return problems, "; ".join(notes)


def _gradient(u, px, py, ex, pts):
    out = []
    for key, given, var in (("px", px, "x"), ("py", py, "y")):
        a, ea = bounded(given, pts[:, 0], pts[:, 1])
        b, eb = bounded(sdexpr.derivative(u, var), pts[:, 0], pts[:, 1])
        out += _mismatch(pts, a, ea, b, eb, lambda x, y: f"the scene's [exact] {key} is not "
                         f"∂u/∂{var}: {key} = {x}, ∂u/∂{var} = {y}")
    return out


def _mismatch(pts, a, ea, b, eb, say):
    """[] when the values a and b at the points agree within ROUNDOFF_SAFETY × their round-off
    bounds ea, eb, else the problem `say(a_i, b_i)` (formatted) at the first point i where not."""
    i = _first(_differs(a, ROUNDOFF_SAFETY * ea, b, ROUNDOFF_SAFETY * eb))
    return [] if i is None else [f"{say(_fmt(a[i]), _fmt(b[i]))} at {_at(pts[i])}"]


def _source(u, f, pts):
    uxx, exx = bounded(sdexpr.derivative(sdexpr.derivative(u, "x"), "x"), pts[:, 0], pts[:, 1])
    uyy, eyy = bounded(sdexpr.derivative(sdexpr.derivative(u, "y"), "y"), pts[:, 0], pts[:, 1])
    lap = -(uxx + uyy)
    elap = exx + eyy + U * np.abs(lap)
    fv, ef = bounded(f, pts[:, 0], pts[:, 1])
    return _mismatch(pts, fv, ef, lap, elap, lambda fi, li: "the scene's [data] f is not −Δu of "
                     f"its [exact] u (−Δu = f in Ω \\ Γc): f = {fi}, −Δu = {li}")


def _boundary(u, g, pts):
    gv, eg = bounded(g, pts[:, 0], pts[:, 1])
    uv, eu = bounded(u, pts[:, 0], pts[:, 1])
    return _mismatch(pts, gv, eg, uv, eu, lambda gi, ui: "the scene's [data] g is not its "
                     f"[exact] u on ∂Ω (u = g on ∂Ω): g = {gi}, u = {ui}")


def _scene_jump(u, ex, c, nu):
    """The scene's [u] and its tolerance: [exact] jump, else u⁺ − u⁻ by the face rule."""
    if "jump" in ex:
        j, e = bounded(ex["jump"], c[:, 0], c[:, 1])
        return j, ROUNDOFF_SAFETY * e
    (up, ep), (um, em) = (bounded(u, *face_points(c, nu, s).T) for s in (1.0, -1.0))
    return up - um, ROUNDOFF_SAFETY * (ep + em + U * np.abs(up - um))


def face_points(c, nu, side):
    """The crack points c (K, 2) as seen from the face ``side``, ν one per point (the rule of
    eval_on_face, crates/sdcrack-core/src/problem.rs, and of ExactSolution.on_face): a coordinate
    that is exactly zero where ν has a component gets the sign of side·ν (IEEE signed zero)."""
    q = np.array(c, dtype=float)
    for d in range(2):
        z = (q[:, d] == 0.0) & (nu[:, d] != 0.0)
        q[z, d] = np.copysign(0.0, side * nu[z, d])
    return q


def _crack(u, px, py, ex, c, nu, length):
    out = []
    where = lambda i: f"at {_at(c[i])} (ν = {_at(nu[i])})"  # noqa: E731
    jump, tj = _scene_jump(u, ex, c, nu)
    name = "jump" if "jump" in ex else "u⁺ − u⁻ (by the face rule)"
    (lp, tp), (lm, tm) = (_one_sided(u, c, nu, length, s) for s in (1.0, -1.0))
    i = _first(_differs(jump, tj, lp - lm, tp + tm))
    if i is not None:
        out.append(f"the scene's [exact] {name} is not u⁺ − u⁻ on Γc (+ face: the side ν points "
                   f"into): {name} = {_fmt(jump[i])}, u⁺ − u⁻ = {_fmt(lp[i] - lm[i])} (the limits "
                   f"of u from the faces) {where(i)}")

    def flux(x, y):
        (a, ea), (b, eb) = bounded(px, x, y), bounded(py, x, y)
        v = a * nu[:, 0] + b * nu[:, 1]
        return v, ea * np.abs(nu[:, 0]) + eb * np.abs(nu[:, 1]) + 4 * U * np.abs(v)

    (qp, tqp), (qm, tqm) = (_one_sided(flux, c, nu, length, s) for s in (1.0, -1.0))
    i = _first(_differs(qp, tqp, qm, tqm))
    if i is not None:
        out.append(f"the scene's [exact] u breaks [∂u/∂ν] = 0 on Γc: ∂u/∂ν = {_fmt(qp[i])} on "
                   f"the + face, {_fmt(qm[i])} on the − face {where(i)}")
    with np.errstate(invalid="ignore"):
        fin = np.isfinite(jump) & np.isfinite(tj)
        i = _first(fin & (jump < -tj))
        if i is not None:
            out.append(f"the scene's [exact] {name} breaks [u] ≥ 0 on Γc: [u] = {_fmt(jump[i])} "
                       f"{where(i)}")
        open_ = fin & (jump > tj)
        for side, q, t in (("+", qp, tqp), ("−", qm, tqm)):
            ok = np.isfinite(q) & np.isfinite(t)
            i = _first(ok & (q > t))
            if i is not None:
                out.append(f"the scene's [exact] u breaks ∂u/∂ν ≤ 0 on Γc: ∂u/∂ν = {_fmt(q[i])} "
                           f"on the {side} face {where(i)}")
            i = _first(ok & open_ & (q < -t))
            if i is not None:
                out.append(f"the scene's [exact] u breaks [u]·∂u/∂ν = 0 on Γc: the crack is open "
                           f"([u] = {_fmt(jump[i])}) and its {side} face is loaded (∂u/∂ν = "
                           f"{_fmt(q[i])}) {where(i)}")
    return out


def not_judged(checks, problems):
    """The check rows (label, requirement, problems, not-applicable reason) with the rows judged
    against the exact solution marked not judged when the exact data have problems: their
    measurements stay in the tables, their problems do not make the verdict (the scene is the
    cause). Unchanged when the exact data hold."""
    if not problems:
        return checks
    out = []
    for label, what, probs, na in checks:
        if label in JUDGED_AGAINST_EXACT:
            out.append((label, what, [], NOT_JUDGED.format(n=len(probs))))
        else:
            out.append((label, what, probs, na))
    return out
