"""An elastic scene's exact data checked against what the scene implies, before the references are
judged against them (issue 45; docs/elasticity.md, *The exact data are checked*): the compare
tool's own check of mesh/scene.json, written independently of ``sdcrack check``'s
(crates/sdcrack-core/src/scene/elastic_exact_data.rs) with sdexpr's evaluator and symbolic
derivatives, on the same sample points and with the same tolerances as the scalar check
(exactdata.py, whose machinery it uses):

- ``exact.sxx``, ``syy``, ``sxy`` against Hooke's law σ = λ* tr ε(u) I + 2μ ε(u) of the symbolic
  derivatives of ``exact.ux``, ``uy`` (λ*, μ: scene.json's ``problem.lambda_in_plane``, ``mu``);
- ``data.fx``, ``fy`` against −div σ (the symbolic derivatives of the stress) on the grid over Ω
  and beside both faces of every crack;
- ``data.gx``, ``gy`` against u on every edge of a part without a traction;
  ``data.traction.P`` against σn on the part P's edges (n the outward normal); ``data.fixed[i]``:
  its held components of u are 0 at its point;
- on Γc, from the one-sided limits of u and σ (ν the segment's normal, τ = ν turned by −90°):
  ``exact.opening``, ``slip`` (else u⁺·ν − u⁻·ν, u⁺·τ − u⁻·τ by the face rule) against [u·ν],
  [u·τ]; ``exact.pressure`` against −σ_νν on each face; [σν] = 0 and σ_ντ = 0 on both faces,
  [u·ν] ≥ 0, σ_νν ≤ 0, σ_νν·[u·ν] = 0;
- beyond ``sdcrack check``: ``exact.sif`` (one [K_I, K_II] per tip, docs/elasticity.md's tip
  order) against the exact stress's near-tip asymptotics in the tip frame, σ₂₂ √(2πr) → K_I,
  σ₁₂ √(2πr) → K_II as r → 0 ahead of the tip (the definition of K in docs/elasticity.md). A
  wrong K in the scene blames the scene, not the references' SIF series.

Tolerances (each comparison with the tolerance of its own evaluation, as exactdata.py):

- two values that should be equal differ when they are apart by more than ROUNDOFF_SAFETY × the
  sum of their running round-off bounds (exactdata.bounded); a combination Σ cᵢ vᵢ of bounded
  values (σn, u·ν, σ_νν, −div σ, Hooke's law) carries Σ |cᵢ| eᵢ plus its own rounding
  n·2U·Σ |cᵢ vᵢ| (n products and n − 1 sums, each rounding by at most U of a partial result
  bounded by Σ |cᵢ vᵢ|; 2U for the coefficients' own rounding);
- a face value is exactdata's Richardson limit from c ± εν, its truncation estimate times
  TRUNCATION_SAFETY added;
- a sign condition fails only where the value is certainly of the wrong sign (beyond its
  tolerance), the complementarity only where the crack is certainly open and the face certainly
  pressed, a zero (σ_ντ, u at a fixed point) only where the value is certainly not 0;
- K: g(r) = √(2πr) σ′(tip + r e₁) (σ′ the tip-frame component) is K + a s + b s² + … in s = √r
  (Williams' expansion: the stress's terms are r^(n/2 − 1)), so 2 g(s/2) − g(s) = K + O(s²); a
  single term c sⁿ (n ≥ 2) leaves c sⁿ (1 − 2^(1−n)) there, below the estimate |g(s) − g(s/2)| =
  c sⁿ (1 − 2^(−n)), which TRUNCATION_SAFETY multiplies. r = TIP_STEP · R (R the tip's distance to
  ∂Ω, other cracks and its own segment's other end): 1e-8 R keeps the estimate ~1e-4 of a
  T-stress-like term (a scene's K off by a realistic mistake is off by O(K)), and far above the
  round-off of σ ~ K/√(2πr) there. The point tip + r e₁ is rounded: its true distance and angle
  are used (θ ≠ 0 changes g by at most |θ|(|K_I| + |K_II|)/2 to first order: Williams' angular
  functions have derivatives ½ at θ = 0; the tolerance adds |θ|(|g_I| + |g_II|)).

A point where a value or its bound is not finite is skipped; no crack end (tip or mouth) and no
kink is sampled.
"""
import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from sdshared import sdexpr

from .exactdata import (BOUNDARY_SAMPLES, CRACK_SAMPLES, LIMIT_STEP, ROUNDOFF_SAFETY,
                        TRUNCATION_SAFETY, U, _at, _differs, _first, _fmt, boundary_points,
                        bounded, crack_points, face_points, interior_points)

LABEL = "exact data"
REQUIREMENT = ("the scene's [exact] data are those of an exact solution of the elastic problem: "
               "σ = Hooke's law of ∂u; f = −div σ on both sides of Γc; g = u on the Dirichlet "
               "parts, σn = t on the traction parts, u = 0 at the fixed components; opening, slip "
               "= [u·ν], [u·τ], pressure = −σ_νν; [σν] = 0, σ_ντ = 0, [u·ν] ≥ 0, σ_νν ≤ 0, "
               "σ_νν·[u·ν] = 0 on Γc; sif = the near-tip limits of σ₂₂, σ₁₂ √(2πr) (at sampled "
               "points, to their round-off and truncation bounds)")
NOT_JUDGED = ("not judged: the scene's exact data are inconsistent (see the check \"exact data\"); "
              "{n} problem(s) measured against them are not counted")
# The checks whose verdict compares the references with the scene's exact data: with inconsistent
# data their problems say nothing of the references (elastic.analyse marks them not judged). The
# others (completeness, status, crack outputs, agreement, SIF computed) stand.
JUDGED_AGAINST_EXACT = ("series", "active set", "solver series", "patch test")
TIP_STEP = 1e-8
RECTANGLE_PARTS = ("bottom", "right", "top", "left")  # the edges of {min, max} in CCW order
WHOLE_BOUNDARY = "boundary"  # a part every edge belongs to (a mesh-file scene's one part)
STRESS = ("sxx", "syy", "sxy")


@dataclass(frozen=True)
class Problem:
    """One wrong datum: the key (``exact.sxx``, ``data.traction.left``, ``exact.sif[0]``) and one
    sentence naming it first, both values, their difference and the point."""

    key: str
    sentence: str

    def __str__(self):
        return self.sentence


class SceneError(ValueError):
    """scene.json cannot be checked (a missing or malformed entry): one line."""


# ---------------------------------------------------------------------------------------------
# Bounded values: (value, tolerance) with the tolerance = ROUNDOFF_SAFETY × round-off bound
# ---------------------------------------------------------------------------------------------

def _known(tree, x, y):
    v, e = bounded(tree, x, y)
    return v, ROUNDOFF_SAFETY * e


def _combination(terms):
    """Σ cᵢ vᵢ of (cᵢ, (vᵢ, tᵢ)) with the tolerance Σ |cᵢ| tᵢ + ROUNDOFF_SAFETY·n·2U·Σ |cᵢ vᵢ|
    (module documentation); cᵢ scalars or arrays."""
    with np.errstate(all="ignore"):
        value = sum(c * v for c, (v, _) in terms)
        spread = sum(np.where(t == 0.0, 0.0, np.abs(c) * t) for c, (_, t) in terms)
        size = sum(np.abs(c * v) for c, (v, _) in terms)
    return value, spread + ROUNDOFF_SAFETY * len(terms) * 2 * U * size


def _problem(key, pts, a, b, say):
    """The Problem `say(a_i, b_i, |a_i − b_i|, point)` at the first point where the known values a,
    b certainly differ, else None."""
    i = _first(_differs(a[0], a[1], b[0], b[1]))
    if i is None:
        return None
    return Problem(key, say(_fmt(a[0][i]), _fmt(b[0][i]), _fmt(abs(a[0][i] - b[0][i])),
                            _at(pts[i])))


# ---------------------------------------------------------------------------------------------
# The scene.json entries
# ---------------------------------------------------------------------------------------------

def _expr(text, key):
    if not isinstance(text, str):
        raise SceneError(f"scene.json: {key} is not an expression")
    try:
        return sdexpr.parse(text)
    except ValueError as exc:
        raise SceneError(f"scene.json: {key}: {exc}")


def _numbers(value, n):
    """A list of n finite numbers."""
    return (isinstance(value, list) and len(value) == n
            and all(isinstance(v, (int, float)) and math.isfinite(v) for v in value))


def _pair(value, key):
    if not (isinstance(value, list) and len(value) == 2):
        raise SceneError(f"scene.json: {key} is not a pair of expressions")
    return [_expr(v, f"{key}[{k}]") for k, v in enumerate(value)]


def polygon_and_parts(scene):
    """(∂Ω's vertices counter-clockwise, the part of each edge k → k + 1) of scene.json's domain:
    a rectangle {min, max} (bottom, right, top, left), a polygon (edge1 … edgeN of the polygon as
    stored, counter-clockwise: a clockwise one keeps vertex 1 and reverses the others)."""
    d = scene.get("domain")
    if isinstance(d, dict) and "min" in d and "max" in d:
        (x0, y0), (x1, y1) = d["min"], d["max"]
        return [(x0, y0), (x1, y0), (x1, y1), (x0, y1)], list(RECTANGLE_PARTS)
    if isinstance(d, dict) and isinstance(d.get("polygon"), list):
        p = [tuple(map(float, v)) for v in d["polygon"]]
        area2 = sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(p, p[1:] + p[:1]))
        if area2 < 0:
            p = p[:1] + p[:0:-1]
        return p, [f"edge{k + 1}" for k in range(len(p))]
    raise SceneError("scene.json: 'domain' is neither {min, max} nor {polygon}")


def _on_segment(p, a, b):
    """p on the closed segment [a, b], exactly (rationals)."""
    p, a, b = ([Fraction(c) for c in v] for v in (p, a, b))
    cross = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
    return (cross == 0 and min(a[0], b[0]) <= p[0] <= max(a[0], b[0])
            and min(a[1], b[1]) <= p[1] <= max(a[1], b[1]))


def _distance(p, a, b):
    d = b - a
    t = np.clip(np.dot(p - a, d) / np.dot(d, d), 0.0, 1.0)
    return float(np.hypot(*(p - a - t * d)))


def tips(polygon, cracks):
    """[(tip, e₁, R)] in docs/elasticity.md's order: per crack its first point, then its last, each
    unless it lies on ∂Ω (a mouth, by exact predicates); e₁ along the end segment out of the crack;
    R the tip's distance to ∂Ω, to the other cracks and to its segment's other end."""
    poly = [np.asarray(v, dtype=float) for v in polygon]
    edges = list(zip(poly, poly[1:] + poly[:1]))
    out = []
    for c, crack in enumerate(cracks):
        for end, prev in ((crack[0], crack[1]), (crack[-1], crack[-2])):
            if any(_on_segment(end, a, b) for a, b in edges):
                continue
            e1 = (end - prev) / math.hypot(*(end - prev))
            others = [(a, b) for o, other in enumerate(cracks) if o != c
                      for a, b in zip(other[:-1], other[1:])]
            R = min([math.hypot(*(end - prev))]
                    + [_distance(end, a, b) for a, b in edges + others])
            out.append((end, e1, R))
    return out


def _cracks(scene):
    cracks = scene.get("cracks")
    if not isinstance(cracks, list) or not cracks:
        raise SceneError("scene.json: no 'cracks' list")
    return [np.asarray(c["points"], dtype=float) for c in cracks]


# ---------------------------------------------------------------------------------------------
# The check
# ---------------------------------------------------------------------------------------------

class _Field:
    """The exact u, σ and the scene's data of scene.json as sdexpr trees."""

    def __init__(self, scene):
        ex, p = scene["exact"], scene.get("problem") or {}
        try:
            self.lam, self.mu = float(p["lambda_in_plane"]), float(p["mu"])
        except (KeyError, TypeError, ValueError):
            raise SceneError("scene.json: problem.lambda_in_plane, problem.mu are not numbers")
        self.u = [_expr(ex.get("ux"), "exact.ux"), _expr(ex.get("uy"), "exact.uy")]
        self.sigma = [_expr(ex.get(k), f"exact.{k}") for k in STRESS]
        self.given = {k: _expr(ex[k], f"exact.{k}") for k in ("opening", "slip", "pressure")
                      if ex.get(k) is not None}
        self.f = _pair(scene.get("f"), "f")
        self.g = None if scene.get("g") is None else _pair(scene["g"], "g")
        t = scene.get("tractions") or {}
        if not isinstance(t, dict):
            raise SceneError("scene.json: 'tractions' is not a mapping")
        self.tractions = {part: _pair(v, f"tractions.{part}") for part, v in t.items()}
        self.fixed = scene.get("fixed") or []
        for i, f in enumerate(self.fixed):
            if not (isinstance(f, dict) and _numbers(f.get("point"), 2)
                    and isinstance(f.get("components"), list)
                    and set(f["components"]) <= {"x", "y"}):
                raise SceneError(f"scene.json: fixed[{i}] is not {{point: [x, y], components}}")
        self.sif = ex.get("sif")
        if self.sif is not None and not (isinstance(self.sif, list)
                                         and all(_numbers(k, 2) for k in self.sif)):
            raise SceneError("scene.json: exact.sif is not a list of [K_I, K_II] numbers")

    def u_along(self, x, y, d):
        """u·d with its tolerance; d (2,) or (K, 2)."""
        d = np.asarray(d, dtype=float)
        return _combination([(d[..., 0], _known(self.u[0], x, y)),
                             (d[..., 1], _known(self.u[1], x, y))])

    def stress_form(self, x, y, a, b):
        """a·σb (σ symmetric) with its tolerance; a, b (2,) or (K, 2)."""
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        s = [_known(t, x, y) for t in self.sigma]
        return _combination([(a[..., 0] * b[..., 0], s[0]), (a[..., 1] * b[..., 1], s[1]),
                             (a[..., 0] * b[..., 1] + a[..., 1] * b[..., 0], s[2])])


def check_scene(scene):
    """(problems, what was checked) of scene.json's exact data ([Problem], one per key and check
    that fails, at its first failing point); ([], None) without [exact]. SceneError when an entry
    the check reads is missing or malformed."""
    if not isinstance(scene.get("exact"), dict):
        return [], None
    fld = _Field(scene)
    polygon, parts = polygon_and_parts(scene)
    cracks = _cracks(scene)
    pts = interior_points(polygon, cracks)
    found = (_hooke(fld, pts) + _equilibrium(fld, pts) + _dirichlet(fld, polygon, parts)
             + _tractions(fld, polygon, parts) + _fixed(fld) + _crack(fld, cracks)
             + _sifs(fld, tips(polygon, cracks)))
    c, _, _ = crack_points(cracks)
    checked = (f"{len(pts)} points in Ω, {BOUNDARY_SAMPLES} per edge of ∂Ω, {len(c)} on Γc "
               f"(k/{CRACK_SAMPLES} of each segment), {len(tips(polygon, cracks))} tip(s)")
    return [p for p in found if p is not None], checked


def _hooke(fld, pts):
    x, y = pts[:, 0], pts[:, 1]
    d = {(c, v): _known(sdexpr.derivative(fld.u[c], v), x, y) for c in (0, 1) for v in "xy"}
    lam, mu = fld.lam, fld.mu
    law = [_combination([(lam + 2 * mu, d[0, "x"]), (lam, d[1, "y"])]),
           _combination([(lam, d[0, "x"]), (lam + 2 * mu, d[1, "y"])]),
           _combination([(mu, d[0, "y"]), (mu, d[1, "x"])])]
    out = []
    for k, name in enumerate(STRESS):
        out.append(_problem(
            f"exact.{name}", pts, _known(fld.sigma[k], x, y), law[k],
            lambda a, b, diff, at, name=name: (
                f"exact.{name} is not Hooke's law of exact.ux, exact.uy (σ = λ* tr ε(u) I + "
                f"2μ ε(u), λ* = {_fmt(lam)}, μ = {_fmt(mu)}): {name} = {a}, σ(u) gives {b} "
                f"(off by {diff}) at {at}")))
    return out


def _equilibrium(fld, pts):
    x, y = pts[:, 0], pts[:, 1]
    sxx, syy, sxy = fld.sigma
    div = [[(sxx, "x"), (sxy, "y")], [(sxy, "x"), (syy, "y")]]
    out = []
    for k, comp in enumerate("xy"):
        minus_div = _combination([(-1.0, _known(sdexpr.derivative(s, v), x, y))
                                  for s, v in div[k]])
        out.append(_problem(
            f"data.f{comp}", pts, _known(fld.f[k], x, y), minus_div,
            lambda a, b, diff, at, comp=comp: (
                f"data.f{comp} is not −(div σ)_{comp} of the exact stress (−div σ = f in "
                f"Ω \\ Γc): f{comp} = {a}, −(div σ)_{comp} = {b} (off by {diff}) at {at}")))
    return out


def _edges(polygon, parts):
    """(a, b, part, outward normal) per edge of ∂Ω (counter-clockwise: n = (dy, −dx)/|d|)."""
    for k, part in enumerate(parts):
        a, b = np.asarray(polygon[k], float), np.asarray(polygon[(k + 1) % len(polygon)], float)
        d = b - a
        yield a, b, part, np.array([d[1], -d[0]]) / math.hypot(*d)


def _edge_points(a, b):
    return boundary_points([tuple(a), tuple(b)])[:BOUNDARY_SAMPLES]


def _has_traction(fld, part):
    return part in fld.tractions or WHOLE_BOUNDARY in fld.tractions


def _dirichlet(fld, polygon, parts):
    if fld.g is None:
        return []
    for a, b, part, _ in _edges(polygon, parts):
        if _has_traction(fld, part):
            continue
        pts = _edge_points(a, b)
        for k, c in enumerate("xy"):
            p = _problem(f"data.g{c}", pts, _known(fld.g[k], pts[:, 0], pts[:, 1]),
                         _known(fld.u[k], pts[:, 0], pts[:, 1]),
                         lambda g, u, diff, at, c=c, part=part: (
                             f"data.g{c} is not exact.u{c} on {part} (u = g on the Dirichlet "
                             f"parts of ∂Ω): g{c} = {g}, u{c} = {u} (off by {diff}) at {at}"))
            if p is not None:
                return [p]
    return []


def _tractions(fld, polygon, parts):
    out = []
    for name, t in sorted(fld.tractions.items()):
        key = f"data.traction.{name}"
        mine = [e for e in _edges(polygon, parts) if name in (e[2], WHOLE_BOUNDARY)]
        if not mine:
            out.append(Problem(key, f"{key} names no part of ∂Ω (the parts: {', '.join(parts)})"))
            continue
        for a, b, part, n in mine:
            pts = _edge_points(a, b)
            x, y = pts[:, 0], pts[:, 1]
            sn = [fld.stress_form(x, y, e, n) for e in ((1.0, 0.0), (0.0, 1.0))]
            given = [_known(t[k], x, y) for k in (0, 1)]
            bad = _differs(*given[0], *sn[0]) | _differs(*given[1], *sn[1])
            i = _first(bad)
            if i is not None:
                off = math.hypot(given[0][0][i] - sn[0][0][i], given[1][0][i] - sn[1][0][i])
                out.append(Problem(key, (
                    f"{key} is not σn of the exact stress on {part} (σn = t, n = {_at(n)} the "
                    f"outward normal): t = {_at((given[0][0][i], given[1][0][i]))}, σn = "
                    f"{_at((sn[0][0][i], sn[1][0][i]))} (off by {_fmt(off)}) at {_at(pts[i])}")))
                break
    return out


def _fixed(fld):
    out = []
    for i, f in enumerate(fld.fixed):
        x, y = (np.array([float(c)]) for c in f["point"])
        for comp in f["components"]:
            k = "xy".index(comp)
            v, t = _known(fld.u[k], x, y)
            if np.isfinite(v[0]) and np.isfinite(t[0]) and abs(v[0]) > t[0]:
                out.append(Problem(f"data.fixed[{i}]", (
                    f"data.fixed[{i}] holds u{comp} = 0 at {_at((x[0], y[0]))}, but exact.u{comp} "
                    f"= {_fmt(v[0])} there (off by {_fmt(abs(v[0]))})")))
                break
    return out


# ---------------------------------------------------------------------------------------------
# The crack
# ---------------------------------------------------------------------------------------------

def _limit(fn, c, nu, length, side):
    """The one-sided limit of fn(x, y) -> (value, tolerance) at the crack points from face
    `side`: exactdata's Richardson step, with tolerances already scaled."""
    eps = LIMIT_STEP * length
    q1 = c + (side * eps)[:, None] * nu
    q2 = c + (side * eps / 2)[:, None] * nu
    (a1, t1), (a2, t2) = fn(q1[:, 0], q1[:, 1]), fn(q2[:, 0], q2[:, 1])
    return 2 * a2 - a1, 2 * t2 + t1 + TRUNCATION_SAFETY * np.abs(a1 - a2)


def _scene_jump(fld, name, c, nu, d):
    """The scene's jump of u·d: exact.<name>, else u⁺·d − u⁻·d by the face rule."""
    if name in fld.given:
        return _known(fld.given[name], c[:, 0], c[:, 1])
    (up, tp), (um, tm) = (fld.u_along(*face_points(c, nu, s).T, d) for s in (1.0, -1.0))
    return _combination([(1.0, (up, tp)), (-1.0, (um, tm))])


def _crack(fld, cracks):
    c, nu, length = crack_points(cracks)
    if not len(c):
        return []
    tau = np.column_stack([nu[:, 1], -nu[:, 0]])
    where = lambda i: f"at {_at(c[i])} (ν = {_at(nu[i])})"  # noqa: E731
    out = []
    jumps = {}
    for name, d, v in (("opening", nu, "ν"), ("slip", tau, "τ")):
        given = _scene_jump(fld, name, c, nu, d)
        jumps[name] = given
        (lp, tp), (lm, tm) = (_limit(lambda x, y: fld.u_along(x, y, d), c, nu, length, s)
                              for s in (1.0, -1.0))
        faces = (lp - lm, tp + tm)
        i = _first(_differs(*given, *faces))
        if i is None:
            continue
        if name in fld.given:
            key, what = f"exact.{name}", f"exact.{name} = {_fmt(given[0][i])}"
        else:
            key, what = "exact.ux", (f"exact.ux, exact.uy: u⁺·{v} − u⁻·{v} by the face rule = "
                                     f"{_fmt(given[0][i])}")
        out.append(Problem(key, (
            f"{what} is not [u·{v}] on Γc (the {name}; + face: the side ν points into): the "
            f"limits of u from the faces give {_fmt(faces[0][i])} (off by "
            f"{_fmt(abs(given[0][i] - faces[0][i]))}) {where(i)}")))
    out += _face_tractions(fld, c, nu, tau, length, where)
    out += _contact(fld, c, nu, length, jumps["opening"], where)
    return out


def _face_tractions(fld, c, nu, tau, length, where):
    out = []
    ex, ey = np.array([1.0, 0.0]), np.array([0.0, 1.0])
    sn = {(s, k): _limit(lambda x, y, e=e: fld.stress_form(x, y, e, nu), c, nu, length, s)
          for s in (1.0, -1.0) for k, e in enumerate((ex, ey))}
    bad = _differs(*sn[1.0, 0], *sn[-1.0, 0]) | _differs(*sn[1.0, 1], *sn[-1.0, 1])
    i = _first(bad)
    if i is not None:
        plus, minus = ((sn[s, 0][0][i], sn[s, 1][0][i]) for s in (1.0, -1.0))
        off = math.hypot(plus[0] - minus[0], plus[1] - minus[1])
        out.append(Problem("exact.ux", (
            f"exact.ux, exact.uy break [σν] = 0 on Γc: σν = {_at(plus)} on the + face, "
            f"{_at(minus)} on the − face (off by {_fmt(off)}) {where(i)}")))
    for side, face in ((1.0, "+"), (-1.0, "−")):
        s, t = _limit(lambda x, y: fld.stress_form(x, y, tau, nu), c, nu, length, side)
        with np.errstate(invalid="ignore"):
            i = _first(np.isfinite(s) & np.isfinite(t) & (np.abs(s) > t))
        if i is not None:
            out.append(Problem("exact.ux", (
                f"exact.ux, exact.uy break σ_ντ = 0 on Γc (frictionless): σ_ντ = {_fmt(s[i])} "
                f"on the {face} face (off by {_fmt(abs(s[i]))}) {where(i)}")))
            break
    if "pressure" in fld.given:
        given = _known(fld.given["pressure"], c[:, 0], c[:, 1])
        for side, face in ((1.0, "+"), (-1.0, "−")):
            s, t = _limit(lambda x, y: fld.stress_form(x, y, nu, nu), c, nu, length, side)
            i = _first(_differs(*given, -s, t))
            if i is not None:
                out.append(Problem("exact.pressure", (
                    f"exact.pressure is not −σ_νν on Γc: pressure = {_fmt(given[0][i])}, −σ_νν = "
                    f"{_fmt(-s[i])} on the {face} face (off by {_fmt(abs(given[0][i] + s[i]))}) "
                    f"{where(i)}")))
                break
    return out


def _contact(fld, c, nu, length, opening, where):
    out = []
    w, tw = opening
    key, subject = (("exact.opening", "exact.opening breaks") if "opening" in fld.given else
                    ("exact.ux", "exact.ux, exact.uy break"))
    with np.errstate(invalid="ignore"):
        fin = np.isfinite(w) & np.isfinite(tw)
        i = _first(fin & (w < -tw))
        if i is not None:
            out.append(Problem(key, (
                f"{subject} [u·ν] ≥ 0 on Γc (the faces interpenetrate): [u·ν] = {_fmt(w[i])} "
                f"(below 0 by {_fmt(-w[i])}) {where(i)}")))
        open_ = fin & (w > tw)
        pulled = pressed = None
        for side, face in ((1.0, "+"), (-1.0, "−")):
            s, t = _limit(lambda x, y: fld.stress_form(x, y, nu, nu), c, nu, length, side)
            ok = np.isfinite(s) & np.isfinite(t)
            i = _first(ok & (s > t))
            if i is not None and pulled is None:
                pulled = Problem("exact.ux", (
                    f"exact.ux, exact.uy break σ_νν ≤ 0 on Γc (the faces pull on each other): "
                    f"σ_νν = {_fmt(s[i])} on the {face} face (above 0 by {_fmt(s[i])}) "
                    f"{where(i)}"))
            i = _first(ok & open_ & (s < -t))
            if i is not None and pressed is None:
                pressed = Problem("exact.ux", (
                    f"exact.ux, exact.uy break σ_νν·[u·ν] = 0 on Γc: the crack is open ([u·ν] = "
                    f"{_fmt(w[i])}) and its {face} face is pressed (σ_νν = {_fmt(s[i])}; "
                    f"σ_νν·[u·ν] = {_fmt(s[i] * w[i])}, off by {_fmt(abs(s[i] * w[i]))} from 0) "
                    f"{where(i)}"))
    return out + [p for p in (pulled, pressed) if p is not None]


# ---------------------------------------------------------------------------------------------
# Stress intensity factors
# ---------------------------------------------------------------------------------------------

def _near_tip(fld, tip, e1, r):
    """(g_I, g_II) = √(2πr′) (σ′₂₂, σ′₁₂) at the rounded point tip + r e₁, each (value,
    tolerance), and |θ′|, (r′, θ′) the point's true polar coordinates in the tip frame."""
    e2 = np.array([-e1[1], e1[0]])
    p = tip + r * e1
    d = p - tip
    r_true = math.hypot(*d)
    theta = abs(math.atan2(float(np.dot(d, e2)), float(np.dot(d, e1))))
    x, y = np.array([p[0]]), np.array([p[1]])
    scale = math.sqrt(2 * math.pi * r_true)
    out = []
    for a, b in ((e2, e2), (e1, e2)):
        v, t = fld.stress_form(x, y, a, b)
        g = v[0] * scale
        out.append((g, t[0] * scale + ROUNDOFF_SAFETY * 4 * U * abs(g)))
    return out, theta


def sif_limits(fld, tip, e1, R):
    """[(K, tolerance)] for K_I, K_II at the tip from the exact stress (module documentation)."""
    r1 = TIP_STEP * R
    (g1, th1), (g2, th2) = _near_tip(fld, tip, e1, r1), _near_tip(fld, tip, e1, r1 / 4)
    location = th1 * (abs(g1[0][0]) + abs(g1[1][0])) + th2 * (abs(g2[0][0]) + abs(g2[1][0]))
    out = []
    for m in (0, 1):
        (a1, t1), (a2, t2) = g1[m], g2[m]
        out.append((2 * a2 - a1, 2 * t2 + t1 + TRUNCATION_SAFETY * abs(a1 - a2) + 3 * location))
    return out


def _sifs(fld, tip_list):
    if fld.sif is None:
        return []
    if len(fld.sif) != len(tip_list):
        n = len(fld.sif)
        return [Problem("exact.sif", f"exact.sif has {n} entries, the cracks have "
                                     f"{len(tip_list)} tip(s) (one [K_I, K_II] per tip)")]
    out = []
    for k, ((tip, e1, R), given) in enumerate(zip(tip_list, fld.sif)):
        for m, name in enumerate(("K_I", "K_II")):
            K, tol = sif_limits(fld, tip, e1, R)[m]
            want = float(given[m])
            if (math.isfinite(K) and math.isfinite(tol)
                    and abs(want - K) > tol + ROUNDOFF_SAFETY * U * abs(want)):
                comp = "σ₂₂" if m == 0 else "σ₁₂"
                out.append(Problem(f"exact.sif[{k}]", (
                    f"exact.sif[{k}] gives {name} = {_fmt(want)} at the tip {_at(tip)}, but the "
                    f"exact stress's {comp}·√(2πr) ahead of it (e₁ = {_at(e1)}) tends to "
                    f"{_fmt(K)} (off by {_fmt(abs(want - K))})")))
    return out


def not_judged(checks, problems):
    """The check rows with those judged against the exact data marked not judged when the exact
    data have problems (exactdata.not_judged's rule for the elastic checks)."""
    if not problems:
        return checks
    return [(label, what, [], NOT_JUDGED.format(n=len(probs))) if label in JUDGED_AGAINST_EXACT
            else (label, what, probs, na) for label, what, probs, na in checks]
