"""Errors against a scene's exact solution, computed independently of the solver (crates/sdcrack-core/src/norms.rs).

What is computed (the quantities of summary.json's ``errors``)
-----------------------------------------------------------
* ``u_l2``      = ‖u_h − u‖_{L²(Ω)}
* ``p_l2``      = ‖p_h − ∇u‖_{L²(Ω_c)}           (p_h MINI: P1 vertex part + bubble 27 λ0 λ1 λ2;
                                                   the lumped p mass's p_h is P1 without bubble)
* ``p_x``       = sqrt(p_l2² + Σ_T h_T² ‖div p_h + f‖²_T),  h_T the longest edge of T
* ``lambda_l2`` = ‖λ_h − [u]‖_{L²(Γc)}            (λ_h P0 per segment or P1 per node)

Γc is any number of polyline cracks: the crack nodes of all cracks (fields.h5's crack/points, the
rows of crack.txt) with the segments [k, k+1] WITHIN each crack (crack/segments, cracks.txt; without
them the nodes form one crack, consecutive nodes joined). A crack's tips are its end nodes (a node in
one segment only); every tip of every crack gets the tip rules below. On a segment, u on a face is
evaluated with that segment's normal.

``solver_case_errors`` takes one solver case (fields.h5 layout, see ``read_h5_case``);
``p1_field_errors`` takes a reference solver's P1 field on the cracked mesh (there
p_h = ∇u_h, constant per triangle, and λ_h = [u_h], piecewise linear along each crack).
Exact data come from the scene's ``[exact]`` (u, optional px, py, jump) and ``[data] f``, parsed
with compare/sdshared/sdexpr.py; missing px / py are the symbolic derivatives of u
(``sdexpr.derivative``), a missing jump is u on the + face minus u on the − face with the
signed-zero convention of ``eval_on_face`` (crates/sdcrack-core/src/problem.rs).

Quadrature (deliberately not the solver's: crates/sdcrack-core/src/norms.rs uses collapsed Gauss–Legendre rules of
degree 10 and 20, no splitting of the tips' neighbours, and its own Duffy rule at the tips)
----------------------------------------------------------------------------------------------
All rules are tensor rules on [0, 1]² mapped to the triangle; every point is strictly inside the
triangle, so data are never evaluated on the crack or on an edge.

* Regular triangles: Stroud's conical product rule, Gauss–Jacobi (weight 1 − s, n points) ×
  Gauss–Legendre (n points), λ1 = s, λ2 = (1 − s) t: n² points, exact for total degree 2n − 1
  (default n = 8: degree 15).
* Triangles with one crack tip as a vertex (where u ~ r^{1/2}, ∇u ~ r^{−1/2}): a Duffy transform
  collapsed at the tip, x = tip + s ((1 − t)(B − tip) + t (C − tip)), followed by s = σ²:
  dA = 2|T| s ds dt = 4|T| σ³ dσ dt, Gauss–Legendre in σ and t (m points each, default m = 16).
  With r = s |d(t)| every term of the singular expansion Σ r^{k/2} φ_k(θ) becomes analytic
  in (σ, t): r^{1/2} = σ |d(t)|^{1/2}, and |∇u|² ~ r^{−1} times the Jacobian 4σ³ is ~ σ.
  The integrands are therefore analytic on the closed square and Gauss converges exponentially
  (r^{−1} and r^{−1/2}-type integrands to round-off, compare/tests/test_exact.py); polynomials of total
  degree ≤ m − 2 are integrated exactly.
* Triangles with two or three tips as vertices (a crack of one segment, tips of two cracks): the
  four midpoint children, each corner child at a tip with the Duffy rule there (weights / 4), the
  other children treated as the near-tip triangles below.
* Triangles near a tip but not touching it: split recursively into 4 midpoint children until each
  piece P satisfies dist(tip, P) ≥ η · diam(P) (default η = 1) for every tip, then the Stroud rule
  on each piece. The singularity then lies at least one piece diameter away from every piece, where
  the n-point rules converge geometrically in n.
* Crack segments: Gauss–Legendre with n_line points (default 12); a segment ending at a tip in
  σ with s = σ² measured from the tip ([u] ~ s^{1/2} becomes analytic; a segment that is a whole
  crack: each half from its tip).

``Quadrature().doubled()`` doubles n, m, n_line and η; compare/tests/test_exact.py checks that the errors
of open-exact change by < 1e-10 relative under it.

Quadrature-error estimate and self-check
---------------------------------------------------
``solver_case_errors_estimated`` computes every error with the rule above and with
``Quadrature().higher()`` (⌈3n/2⌉ points per direction for each n: Stroud 8 → 12, tip 16 → 24,
crack 12 → 18, the same η) and returns, beside the errors, the higher rule's values (``higher``)
and |e(rule) − e(higher rule)| (``quadrature``), the estimate of each error's quadrature error the
"independent errors" check builds its tolerance from (checks.py). ``quadrature_self_check``
checks the rules themselves, without the solver: over a mesh, with the same pieces and rules as
the errors (tip rules, near-tip splits), it integrates every monomial of the mesh's scaled
coordinates up to the rule's degree and compares with the exact moments of the mesh's polygon,
computed without any quadrature from its boundary edges (Green's theorem, ``polygon_moments``).
"""
import math
import sys

import numpy as np

from sdshared import sdexpr  # the scene's expressions, shared with the references

from .norms import LastResults, digest

__all__ = ["ExactSolution", "Quadrature", "load_scene", "solver_case_errors", "solver_case_errors_h5",
           "solver_case_errors_estimated", "quadrature_self_check", "polygon_moments",
           "boundary_edges", "read_h5_case", "p1_field_errors", "recover_bubble", "stroud_rule", "tip_rule",
           "integrate_on_triangle", "SharedEvaluator", "ExactError", "scene_cracks", "crack_tips"]

CHUNK_POINTS = 1 << 16  # expression evaluation in chunks that stay in cache


class ExactError(ValueError):
    """Inconsistent input (shapes, missing data, a tip not on the mesh, ...)."""


# ---------------------------------------------------------------------------------------------
# 1D and triangle rules
# ---------------------------------------------------------------------------------------------

def gauss_legendre01(n):
    """n-point Gauss–Legendre rule on [0, 1] (weights sum to 1, exact to degree 2n − 1)."""
    x, w = np.polynomial.legendre.leggauss(int(n))
    return 0.5 * (x + 1.0), 0.5 * w


def gauss_jacobi01(n, alpha):
    """n-point Gauss rule on [0, 1] for the weight (1 − s)^alpha (Golub–Welsch on the Jacobi
    recurrence, β = 0): Σ w g(s_i) = ∫_0^1 (1 − s)^alpha g(s) ds exactly for deg g ≤ 2n − 1."""
    n = int(n)
    a, b = float(alpha), 0.0
    k = np.arange(n, dtype=float)
    s = 2 * k + a + b
    diag = (b * b - a * a) / (s * (s + 2))
    kk = np.arange(1, n, dtype=float)
    s1 = 2 * kk + a + b
    off = np.sqrt(4 * kk * (kk + a) * (kk + b) * (kk + a + b) / (s1 * s1 * (s1 + 1) * (s1 - 1)))
    J = np.diag(diag) + np.diag(off, 1) + np.diag(off, -1)
    x, V = np.linalg.eigh(J)
    mu0 = 2 ** (a + b + 1) * math.gamma(a + 1) * math.gamma(b + 1) / math.gamma(a + b + 2)
    w = mu0 * V[0] ** 2
    # x in [-1, 1] with weight (1 - x)^a  ->  s = (1 + x)/2, (1 - x)^a = 2^a (1 - s)^a, dx = 2 ds
    return 0.5 * (x + 1.0), w / 2 ** (a + 1)


def stroud_rule(n):
    """Stroud's conical product rule on a triangle: barycentric points L (n², 3) and weights W
    (n²,) with Σ W = 1, so ∫_T g ≈ |T| Σ W g(Σ_i L_i v_i); exact for total degree ≤ 2n − 1."""
    s, ws = gauss_jacobi01(n, 1.0)
    t, wt = gauss_legendre01(n)
    S, Tt = np.meshgrid(s, t, indexing="ij")
    l1 = S.ravel()
    l2 = ((1 - S) * Tt).ravel()
    L = np.column_stack([(1 - S).ravel() * (1 - Tt).ravel(), l1, l2])
    W = 2.0 * np.outer(ws, wt).ravel()
    return L, W


def tip_rule(m, corner=0):
    """Duffy rule collapsed at local vertex ``corner`` with s = σ²: barycentrics L (m², 3), weights W
    (Σ W = 1). λ_corner = 1 − s, the next two (cyclically) s (1 − t) and s t; W = 4 σ³ w_σ w_t."""
    g, w = gauss_legendre01(m)
    sig, tt = np.meshgrid(g, g, indexing="ij")
    ww = np.outer(w, w)
    s = sig * sig
    L = np.empty((m * m, 3))
    c = int(corner)
    L[:, c] = (1 - s).ravel()
    L[:, (c + 1) % 3] = (s * (1 - tt)).ravel()
    L[:, (c + 2) % 3] = (s * tt).ravel()
    return L, (4.0 * sig ** 3 * ww).ravel()


# Points per direction of the estimate's rule against the errors' rule (Quadrature.higher): for
# an integrand that is not smooth on a triangle the rule's error falls as n^{-k}, k >= 1, and the
# difference of the two rules, e_n (1 - (2/3)^k), is then at least a third of e_n (checks.py's
# SAFETY 4 covers it, and the solver's 4/3, crates/sdcrack-core/src/norms.rs).
HIGHER_RULE_RATIO = (3, 2)


class Quadrature:
    """Resolution of the error quadrature (see the module documentation)."""

    def __init__(self, n=8, tip_m=16, eta=1.0, line_n=12):
        self.n, self.tip_m, self.eta, self.line_n = int(n), int(tip_m), float(eta), int(line_n)

    def doubled(self):
        return Quadrature(2 * self.n, 2 * self.tip_m, 2 * self.eta, 2 * self.line_n)

    def higher(self):
        """The rule of the quadrature-error estimate: ⌈3n/2⌉ points per direction for each n
        (HIGHER_RULE_RATIO), the same η (at a fixed η the near-tip pieces converge geometrically in
        n, so more points are what makes them more accurate)."""
        num, den = HIGHER_RULE_RATIO
        more = lambda k: -(-k * num // den)  # noqa: E731  ⌈k·num/den⌉
        return Quadrature(more(self.n), more(self.tip_m), self.eta, more(self.line_n))

    def degree(self):
        """The total degree every piece's rule integrates exactly: Stroud 2n − 1, the tip rule
        m − 2 (ξ^a η^b becomes σ^{2(a+b)+3} times a polynomial of degree a + b in t)."""
        return min(2 * self.n - 1, self.tip_m - 2)

    def __repr__(self):
        return f"Quadrature(n={self.n}, tip_m={self.tip_m}, eta={self.eta}, line_n={self.line_n})"


# ---------------------------------------------------------------------------------------------
# Exact solution
# ---------------------------------------------------------------------------------------------

def load_scene(path):
    """The scene TOML as a dict (tomllib)."""
    import tomllib

    with open(path, "rb") as fh:
        return tomllib.load(fh)


class SharedEvaluator:
    """Evaluates several sdexpr trees at once on numpy arrays, each distinct subtree once (common
    subexpression elimination: the symbolic gradient of open-exact's u repeats its subtrees, 350
    nodes for 55 distinct ones). Node semantics are those of ``sdexpr.to_numpy`` (same numpy
    functions in the same order, so the values are bit for bit the same; compare/tests/test_exact.py
    checks it), evaluated in chunks of CHUNK_POINTS points."""

    _BIN = {"+": np.add, "-": np.subtract, "*": np.multiply, "/": np.divide, "^": np.power}
    _F1 = {"sin": np.sin, "cos": np.cos, "tan": np.tan, "exp": np.exp, "log": np.log, "sqrt": np.sqrt,
           "abs": np.abs, "sign": lambda v: np.where(np.isnan(v), np.nan, np.copysign(1.0, v))}
    _F2 = {"atan2": np.arctan2, "min": np.fmin, "max": np.fmax}

    def __init__(self, trees):
        self.nodes = []  # (op, payload, child ids)
        self._ids = {}
        old = sys.getrecursionlimit()
        sys.setrecursionlimit(max(old, 40 * sdexpr.MAX_DEPTH))
        try:
            self.roots = [self._add(sdexpr.parse(t) if isinstance(t, str) else t) for t in trees]
        finally:
            sys.setrecursionlimit(old)
        last = [-1] * len(self.nodes)
        for i, (_, _, kids) in enumerate(self.nodes):
            for c in kids:
                last[c] = i
        for r in self.roots:
            last[r] = len(self.nodes)
        self._free_after = [[] for _ in self.nodes]
        for c, i in enumerate(last):
            if 0 <= i < len(self.nodes):
                self._free_after[i].append(c)

    def _add(self, t):
        k = t[0]
        if k == "num":
            key, kids, payload = ("num", repr(float(t[1]))), (), float(t[1])
        elif k in ("x", "y"):
            key, kids, payload = (k,), (), None
        elif k == "neg":
            kids = (self._add(t[1]),)
            key, payload = ("neg",) + kids, None
        elif k in self._BIN:
            kids = (self._add(t[1]), self._add(t[2]))
            key, payload = (k,) + kids, None
        elif k == "f1":
            kids = (self._add(t[2]),)
            key, payload = ("f1", t[1]) + kids, t[1]
        elif k == "f2":
            kids = (self._add(t[2]), self._add(t[3]))
            key, payload = ("f2", t[1]) + kids, t[1]
        else:
            raise ValueError(f"bad node {t!r}")
        i = self._ids.get(key)
        if i is None:
            i = self._ids[key] = len(self.nodes)
            self.nodes.append((k, payload, kids))
        return i

    def _run(self, x, y):
        v = [None] * len(self.nodes)
        for i, (k, payload, kids) in enumerate(self.nodes):
            if k == "num":
                r = payload
            elif k == "x":
                r = x
            elif k == "y":
                r = y
            elif k == "neg":
                r = np.negative(v[kids[0]])
            elif k == "f1":
                r = self._F1[payload](v[kids[0]])
            elif k == "f2":
                r = self._F2[payload](v[kids[0]], v[kids[1]])
            else:
                r = self._BIN[k](v[kids[0]], v[kids[1]])
            v[i] = r
            for c in self._free_after[i]:
                v[c] = None
        return [v[r] for r in self.roots]

    def __call__(self, x, y):
        """List of arrays, one per tree, of the broadcast shape of x and y."""
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        shape = x.shape
        xf, yf = x.ravel(), y.ravel()
        out = [np.empty(xf.shape[0]) for _ in self.roots]
        with np.errstate(all="ignore"):
            for a in range(0, xf.shape[0], CHUNK_POINTS):
                for o, r in zip(out, self._run(xf[a:a + CHUNK_POINTS], yf[a:a + CHUNK_POINTS])):
                    o[a:a + CHUNK_POINTS] = r
        return [o.reshape(shape) for o in out]


class ExactSolution:
    """Exact u, ∇u, [u] and f of a scene.

    ``u``, ``px``, ``py``, ``jump``, ``f``: expression strings (or sdexpr trees); px / py default to
    the symbolic derivatives of u, jump to u⁺ − u⁻ on the faces, f to 0. ``cracks``: the scene's
    cracks, a list of polylines [(x, y), ...] (``crack``: one of them, e.g. the old single segment
    ((ax, ay), (bx, by))), optional: used for the tips when the data have no crack nodes."""

    def __init__(self, u, px=None, py=None, jump=None, f="0", crack=None, cracks=None):
        self.u_tree = sdexpr.parse(u) if isinstance(u, str) else u
        self.px_tree = (sdexpr.parse(px) if isinstance(px, str) else px) if px is not None \
            else sdexpr.derivative(self.u_tree, "x")
        self.py_tree = (sdexpr.parse(py) if isinstance(py, str) else py) if py is not None \
            else sdexpr.derivative(self.u_tree, "y")
        self.jump_tree = (sdexpr.parse(jump) if isinstance(jump, str) else jump) if jump is not None else None
        self.f_tree = sdexpr.parse(f) if isinstance(f, str) else f
        self._evaluators = {}
        self._jump = SharedEvaluator([self.jump_tree]) if self.jump_tree is not None else None
        if crack is not None:
            cracks = [crack] + list(cracks or [])
        self.cracks = [np.asarray(c, dtype=float)[:, :2] for c in cracks or []]

    @classmethod
    def from_scene(cls, scene):
        """From a scene file path or its parsed dict; raises ExactError without [exact]."""
        if not isinstance(scene, dict):
            scene = load_scene(scene)
        ex = scene.get("exact")
        if ex is None:
            raise ExactError("the scene has no [exact] table")
        return cls(ex["u"], ex.get("px"), ex.get("py"), ex.get("jump"),
                   scene.get("data", {}).get("f", "0"), cracks=scene_cracks(scene))

    def evaluate(self, x, y, u=True, grad=True, f=False):
        """dict with "u", "px", "py", "f" (those asked for) at the points (x, y), all evaluated in one
        pass that shares common subexpressions."""
        names = tuple(n for n, want in (("u", u), ("px", grad), ("py", grad), ("f", f)) if want)
        if not names:
            return {}
        ev = self._evaluators.get(names)
        if ev is None:
            trees = {"u": self.u_tree, "px": self.px_tree, "py": self.py_tree, "f": self.f_tree}
            ev = self._evaluators[names] = SharedEvaluator([trees[n] for n in names])
        return dict(zip(names, ev(x, y)))

    def u(self, x, y):
        return self.evaluate(x, y, grad=False)["u"]

    def grad(self, x, y):
        """(∂u/∂x, ∂u/∂y): the scene's px, py, else the symbolic derivatives of u."""
        v = self.evaluate(x, y, u=False)
        return v["px"], v["py"]

    def u_grad(self, x, y):
        """(u, ∂u/∂x, ∂u/∂y), sharing common subexpressions."""
        v = self.evaluate(x, y)
        return v["u"], v["px"], v["py"]

    def f(self, x, y):
        return self.evaluate(x, y, u=False, grad=False, f=True)["f"]

    def on_face(self, xy, normal, side):
        """u on the face ``side`` (+1 / −1) at crack points xy (K, 2), ν = normal (2,) or one per
        point (K, 2): a coordinate that is exactly zero while ν has a component in that direction
        gets the sign of side·ν there (signed zero selects the branch of sign / atan2), as
        eval_on_face in crates/sdcrack-core/src/problem.rs."""
        q = np.array(xy, dtype=float)[:, :2]
        nu = np.broadcast_to(np.asarray(normal, dtype=float), q.shape)
        for d in range(2):
            z = (q[:, d] == 0.0) & (nu[:, d] != 0.0)
            q[z, d] = np.copysign(0.0, side * nu[z, d])
        return self.u(q[:, 0], q[:, 1])

    def jump(self, xy, normal):
        """[u] = u⁺ − u⁻ at crack points xy (K, 2) (normal: (2,) or (K, 2), see on_face): the
        scene's jump, else from the faces."""
        xy = np.asarray(xy, dtype=float)
        if self._jump is not None:
            return self._jump(xy[:, 0], xy[:, 1])[0]
        return self.on_face(xy, normal, 1.0) - self.on_face(xy, normal, -1.0)


def scene_cracks(scene):
    """The cracks of a scene TOML (dict) as a list of polylines: ``[geometry] cracks = [{polyline =
    [...]}, {segment = [a, b]}, ...]`` or the single ``crack = {segment = [a, b]}`` (or
    ``{polyline = [...]}``); [] when the scene gives none."""
    geometry = scene.get("geometry") or {}
    items = geometry.get("cracks")
    if items is None:
        items = [geometry["crack"]] if isinstance(geometry.get("crack"), dict) else []
    if not isinstance(items, list):
        raise ExactError("[geometry] cracks must be a list of {polyline = [...]} or {segment = [...]}")
    out = []
    for c, item in enumerate(items):
        pts = (item.get("polyline", item.get("segment")) if isinstance(item, dict) else None)
        try:
            pts = np.asarray(pts, dtype=float)
        except (TypeError, ValueError):
            pts = None
        if pts is None or pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 2:
            raise ExactError(f"[geometry] crack {c} is not a polyline or segment of at least 2 [x, y] points")
        out.append(pts)
    return out


def consecutive_segments(n_points):
    """(n − 1, 2) the segments [k, k+1] of one crack of n nodes (fields without crack/segments)."""
    k = np.arange(max(int(n_points) - 1, 0))
    return np.column_stack([k, k + 1]).astype(np.int64)


def crack_tips(segments, n_points):
    """Indices of the crack nodes that are tips: in exactly one segment (the ends of each crack)."""
    degree = np.bincount(np.asarray(segments, dtype=np.int64).ravel(), minlength=int(n_points))
    return np.flatnonzero(degree == 1)


def check_segments(segments, n_points):
    """(S, 2) int segments, checked: indices among the n_points crack nodes, each node in one or two
    segments (polylines, none closed, none shared)."""
    s = np.asarray(segments)
    if s.ndim != 2 or s.shape[1] != 2 or not np.issubdtype(s.dtype, np.integer):
        raise ExactError(f"crack segments of shape {s.shape} and type {s.dtype}: expected (S, 2) node indices")
    s = s.astype(np.int64)
    if s.size and (s.min() < 0 or s.max() >= n_points):
        raise ExactError(f"a crack segment refers to node {int(s.max())}, of {n_points} crack nodes")
    degree = np.bincount(s.ravel(), minlength=int(n_points))
    if (degree > 2).any() or (degree == 0).any():
        raise ExactError("crack segments do not form polylines (a node in no segment or in more than two)")
    return s


# ---------------------------------------------------------------------------------------------
# Geometry
# ---------------------------------------------------------------------------------------------

def _geometry(P, tris):
    """Vertices (T,3,2), areas (T,), barycentric gradients (T,3,2), longest edges (T,)."""
    X = P[tris]
    e1, e2 = X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    if np.any(det == 0):
        raise ExactError(f"triangle {int(np.flatnonzero(det == 0)[0])} of a stored mesh is "
                         "degenerate (zero area)")
    g1 = np.column_stack([e2[:, 1], -e2[:, 0]]) / det[:, None]
    g2 = np.column_stack([-e1[:, 1], e1[:, 0]]) / det[:, None]
    G = np.stack([-g1 - g2, g1, g2], axis=1)
    edges = np.stack([np.linalg.norm(X[:, 1] - X[:, 0], axis=1), np.linalg.norm(X[:, 2] - X[:, 1], axis=1),
                      np.linalg.norm(X[:, 0] - X[:, 2], axis=1)], axis=1)
    return X, 0.5 * np.abs(det), G, edges.max(axis=1)


def _point_segment_distance(q, a, b):
    """Distance of point q (2,) to segments a-b (K,2)."""
    d = b - a
    t = np.clip(((q - a) * d).sum(axis=1) / np.maximum((d * d).sum(axis=1), 1e-300), 0.0, 1.0)
    return np.linalg.norm(a + t[:, None] * d - q, axis=1)


def _distance_to_triangles(q, X):
    """Distance of q (2,) to triangles X (K,3,2) (0 if inside)."""
    dist = np.min(np.stack([_point_segment_distance(q, X[:, i], X[:, (i + 1) % 3]) for i in range(3)]), axis=0)
    # inside test (signed areas)
    s = [(X[:, (i + 1) % 3, 0] - X[:, i, 0]) * (q[1] - X[:, i, 1])
         - (X[:, (i + 1) % 3, 1] - X[:, i, 1]) * (q[0] - X[:, i, 0]) for i in range(3)]
    inside = ((s[0] >= 0) & (s[1] >= 0) & (s[2] >= 0)) | ((s[0] <= 0) & (s[1] <= 0) & (s[2] <= 0))
    return np.where(inside, 0.0, dist)


_MID = np.array([[0.5, 0.5, 0.0], [0.0, 0.5, 0.5], [0.5, 0.0, 0.5]])


def _children(V):
    """The 4 midpoint children of pieces V (K,3,3) (rows: vertices in parent barycentrics)."""
    m01, m12, m02 = 0.5 * (V[:, 0] + V[:, 1]), 0.5 * (V[:, 1] + V[:, 2]), 0.5 * (V[:, 0] + V[:, 2])
    kids = [np.stack(c, axis=1) for c in ((V[:, 0], m01, m02), (m01, V[:, 1], m12), (m02, m12, V[:, 2]),
                                          (m01, m12, m02))]
    return np.stack(kids, axis=1).reshape(-1, 3, 3)


def _near_tip_pieces(X, tri_ids, tips, eta, max_depth=40, V=None):
    """Split triangles tri_ids (their vertices X[tri_ids]) — or the pieces V (K,3,3) of them, rows their
    vertices in parent barycentrics — until every piece P has dist(tip, P) ≥ eta·diam(P) for every tip.
    Returns (owner (K,), V (K,3,3) in parent barycentrics)."""
    owner = np.asarray(tri_ids, dtype=np.int64)
    V = np.broadcast_to(np.eye(3), (owner.shape[0], 3, 3)).copy() if V is None else np.asarray(V, dtype=float)
    done_o, done_V = [], []
    for _ in range(max_depth):
        if owner.shape[0] == 0:
            break
        phys = np.einsum("kvb,kbd->kvd", V, X[owner])
        diam = np.max(np.stack([np.linalg.norm(phys[:, i] - phys[:, (i + 1) % 3], axis=1) for i in range(3)]),
                      axis=0)
        ok = np.ones(owner.shape[0], dtype=bool)
        for tp in tips:
            ok &= _distance_to_triangles(tp, phys) >= eta * diam
        done_o.append(owner[ok])
        done_V.append(V[ok])
        owner, V = np.repeat(owner[~ok], 4), _children(V[~ok])
    else:
        raise ExactError("a tip lies inside a triangle that does not have it as a vertex")
    if owner.shape[0]:
        raise ExactError("near-tip subdivision did not terminate")
    return np.concatenate(done_o), np.concatenate(done_V)


def _tip_corners(P, tris, tips, scale):
    """(T,3) bool: local vertices of each triangle that are crack tips (of any crack)."""
    X = P[tris]
    tol = 1e-10 * scale
    at_tip = np.zeros(tris.shape, dtype=bool)
    for tp in tips:
        at_tip |= np.linalg.norm(X - tp[None, None, :], axis=2) <= tol
    return at_tip


# ---------------------------------------------------------------------------------------------
# Domain integrals
# ---------------------------------------------------------------------------------------------

def _point_batches(P, tris, tips, quad, chunk_tris=1024):
    """Yields (ids (K,), L, W): triangle (or piece owner) ids, barycentric points L (K,q,3) — or
    (q,3) shared by all K — in triangle ids[k], weights W (K,q) — or (q,) — as fractions of
    |T_ids[k]|; together they cover the whole mesh."""
    T = tris.shape[0]
    X = P[tris]
    scale = max(1.0, float(np.abs(P).max()))
    at_tip = _tip_corners(P, tris, tips, scale) if len(tips) else np.zeros((T, 3), dtype=bool)
    n_tips = at_tip.sum(axis=1)
    corner = np.where(n_tips == 1, at_tip.argmax(axis=1), -1)
    touching = n_tips > 0
    # near-tip non-touching triangles: a cheap conservative test first (the exact test splits)
    near = np.zeros(T, dtype=bool)
    if len(tips):
        cen = X.mean(axis=1)
        rad = np.max(np.linalg.norm(X - cen[:, None, :], axis=2), axis=1)
        diam = np.max(np.stack([np.linalg.norm(X[:, i] - X[:, (i + 1) % 3], axis=1) for i in range(3)]), axis=0)
        for tp in tips:
            near |= np.linalg.norm(cen - tp, axis=1) - rad < quad.eta * diam
        near &= ~touching
    regular = np.flatnonzero(~touching & ~near)
    Ls, Ws = stroud_rule(quad.n)
    for a in range(0, regular.shape[0], chunk_tris):
        yield regular[a:a + chunk_tris], Ls, Ws
    rules = [tip_rule(quad.tip_m, c) for c in range(3)]
    tip_ids = np.flatnonzero(n_tips == 1)
    if tip_ids.shape[0]:
        yield (tip_ids, np.stack([rules[corner[i]][0] for i in tip_ids]),
               np.stack([rules[corner[i]][1] for i in tip_ids]))
    # two or three tips: the corner children at a tip get the tip rule, the other children are near
    multi = np.flatnonzero(n_tips > 1)
    kids = _children(np.broadcast_to(np.eye(3), (multi.shape[0], 3, 3))).reshape(-1, 4, 3, 3)
    near_V = [kids[:, 3]]
    near_owner = [multi]
    for c in range(3):
        hit = at_tip[multi, c]
        if hit.any():  # child c has the parent's corner c as its local vertex c
            L, W = rules[c]
            yield (multi[hit], np.einsum("qv,kvb->kqb", L, kids[hit, c]),
                   np.broadcast_to(0.25 * W, (int(hit.sum()), W.shape[0])))
        near_V.append(kids[~hit, c])
        near_owner.append(multi[~hit])
    near_ids = np.flatnonzero(near)
    near_V.append(np.broadcast_to(np.eye(3), (near_ids.shape[0], 3, 3)))
    near_owner.append(near_ids)
    near_owner = np.concatenate(near_owner)
    if near_owner.shape[0]:
        owner, V = _near_tip_pieces(X, near_owner, tips, quad.eta, V=np.concatenate(near_V))
        ratio = np.abs(np.linalg.det(V))  # area(piece) / area(parent)
        yield owner, np.einsum("qv,kvb->kqb", Ls, V), ratio[:, None] * Ws[None, :]


# The quadrature of a mesh with the exact solution's values at its points, kept for the next
# cases: every δ, multiplier and p mass of a level share the mesh (the evaluation of the exact
# solution is most of the cost of an independent error).
_MESH_QUADRATURE = LastResults(2)


def _quadrature_with_exact(P, tris, exact, tips, quad, names):
    """[(ids, L, w, vals)]: the batches of _point_batches with weights w (K,q) in area units and
    the exact solution's `names` (of "u", "px", "py", "f") at their points."""
    def compute():
        X, area, _, _ = _geometry(P, tris)
        out = []
        for ids, L, W in _point_batches(P, tris, tips, quad):
            xy = L @ X[ids]  # (K,q,2); matmul broadcasts a shared (q,3) L
            vals = exact.evaluate(xy[..., 0], xy[..., 1], u="u" in names,
                                  grad="px" in names, f="f" in names)
            out.append((ids, L, W * area[ids][:, None], vals))
        return out
    key = (digest(P, tris, np.asarray(tips, dtype=float).reshape(-1, 2)), repr(quad), id(exact),
           names)
    # the entry keeps `exact` alive, so its id cannot be reused by another solution meanwhile
    return _MESH_QUADRATURE.get(key, lambda: (exact, compute()))[1]


def _domain_errors(P, tris, exact, tips, quad, u_tri=None, p_tri=None, bubble=None, want_div=True):
    """Σ_T ∫_T (u_h − u)², (p_h − ∇u)², h_T² (div p_h + f)² with
    u_tri (T,3) vertex values of u_h per triangle, p_tri (T,3,2) vertex values of the P1 part of
    p_h per triangle, bubble (T,2) bubble coefficients of b_T = 27 λ0 λ1 λ2 (or None)."""
    _, _, G, hT = _geometry(P, tris)
    f_zero = exact.f_tree[0] == "num" and exact.f_tree[1] == 0.0
    want_div = want_div and p_tri is not None
    div_lin = np.einsum("tvd,tvd->t", p_tri, G) if p_tri is not None else None
    names = tuple(n for n, want in (("u", u_tri is not None), ("px", p_tri is not None),
                                    ("py", p_tri is not None), ("f", want_div and not f_zero))
                  if want)
    su = sp = sd = 0.0
    for ids, L, w, vals in _quadrature_with_exact(P, tris, exact, tips, quad, names):
        if u_tri is not None:
            d = (L @ u_tri[ids][:, :, None])[..., 0] - vals["u"]
            su += float(np.sum(w * d * d))
        if p_tri is not None:
            ph = L @ p_tri[ids]
            if bubble is not None:
                b = 27.0 * L[..., 0] * L[..., 1] * L[..., 2]
                ph = ph + b[..., None] * bubble[ids][:, None, :]
            dx = ph[..., 0] - vals["px"]
            dy = ph[..., 1] - vals["py"]
            sp += float(np.sum(w * (dx * dx + dy * dy)))
            if want_div:
                div = div_lin[ids][:, None]
                if bubble is not None:
                    # ∇b = 27 (∇λ0 λ1λ2 + ∇λ1 λ0λ2 + ∇λ2 λ0λ1)
                    prods = np.stack([L[..., 1] * L[..., 2], L[..., 0] * L[..., 2], L[..., 0] * L[..., 1]], axis=-1)
                    gb = 27.0 * (prods @ G[ids])  # (K,q,2)
                    div = div + (gb @ bubble[ids][:, :, None])[..., 0]
                r = div if f_zero else div + vals["f"]
                sd += float(np.sum(w * hT[ids][:, None] ** 2 * r * r))
    return su, sp, sd


def bubble_projection(P, tris, exact, tips, quad, p_tri):
    """(T,2) coefficients c_T of the L²(T) projection of ∇u − q_h onto the cubic bubble
    b_T = 27 λ0 λ1 λ2, q_h the P1 field of vertex values p_tri (T,3,2): c_T = ∫_T b_T (∇u − q_h) /
    ∫_T b_T², with ∫_T b_T² = 729 · 2|T| · 2!2!2!/8! = (81/280)|T| (exact, below).
    With q_h = ∇I_h u this is the MINI interpolant of ∇u (P1 part and bubble), the yardstick of
    the consistent p in the X-norm (yardsticks.interpolation_errors)."""
    _, area, _, _ = _geometry(P, tris)
    num = np.zeros((tris.shape[0], 2))
    for ids, L, w, vals in _quadrature_with_exact(P, tris, exact, tips, quad, ("px", "py")):
        b = 27.0 * L[..., 0] * L[..., 1] * L[..., 2]
        q = L @ p_tri[ids]
        r = np.stack([vals["px"], vals["py"]], axis=-1) - q
        np.add.at(num, ids, np.sum((w * b)[..., None] * r, axis=1))
    # ∫_T λ0²λ1²λ2² = 2|T| 2!2!2!/(2+2+2+2)! = 16|T|/40320
    bb = 729.0 * 16.0 / 40320.0 * area
    return num / bb[:, None]


# ---------------------------------------------------------------------------------------------
# Crack integrals
# ---------------------------------------------------------------------------------------------

def _crack_error(C, segments, lam_fn, exact, quad):
    """∫_Γc (λ_h − [u])², Γc the segments (S, 2) [a, b] of the crack nodes C (I, 2), tips the nodes
    in one segment only. lam_fn(k, s) gives λ_h on segment k at local coordinate s ∈ [0, 1] (0 at
    C[segments[k, 0]]); [u] is evaluated with the segment's normal."""
    g, wg = gauss_legendre01(quad.line_n)
    a_all, b_all = C[segments[:, 0]], C[segments[:, 1]]
    ell = np.linalg.norm(b_all - a_all, axis=1)
    tip = np.zeros(C.shape[0], dtype=bool)
    tip[crack_tips(segments, C.shape[0])] = True
    at_a, at_b = tip[segments[:, 0]], tip[segments[:, 1]]
    seg, s, w = [], [], []
    # segments without a tip end: plain Gauss
    for k in np.flatnonzero(~at_a & ~at_b):
        seg.append(np.full(g.shape[0], k)), s.append(g), w.append(wg * ell[k])
    # tip ends: s = σ² measured from the tip (from both ends on a lone segment, split at its middle)
    pieces = []
    for k in np.flatnonzero(at_a | at_b):
        if at_a[k] and at_b[k]:
            pieces += [(k, 0.0, 0.5), (k, 1.0, 0.5)]
        else:
            pieces.append((k, 0.0 if at_a[k] else 1.0, 1.0))
    for k, tip_end, length in pieces:
        dist = length * g * g  # distance from the tip end, in segment-local units
        seg.append(np.full(g.shape[0], k))
        s.append(dist if tip_end == 0.0 else 1.0 - dist)
        w.append(2.0 * g * wg * length * ell[k])
    if not seg:
        return 0.0
    seg, s, w = np.concatenate(seg), np.concatenate(s), np.concatenate(w)
    a, b = a_all[seg], b_all[seg]
    xy = a + s[:, None] * (b - a)
    normals = np.column_stack([a[:, 1] - b[:, 1], b[:, 0] - a[:, 0]]) / ell[seg][:, None]
    d = lam_fn(seg, s) - exact.jump(xy, normals)
    return float(np.dot(w, d * d))


def _lambda_fn(lam, segments, n_points):
    """λ_h(k, s) on segment k: P0 (one value per segment, in the order of `segments`) or P1 (one per
    crack node)."""
    lam = np.asarray(lam, dtype=float)
    if lam.shape[0] == segments.shape[0]:
        return lambda k, s: lam[k]
    if lam.shape[0] == n_points:
        return lambda k, s: (1.0 - s) * lam[segments[k, 0]] + s * lam[segments[k, 1]]
    raise ExactError(f"lambda has {lam.shape[0]} values for {segments.shape[0]} crack segments and "
                     f"{n_points} crack nodes")


# ---------------------------------------------------------------------------------------------
# Public API
# ---------------------------------------------------------------------------------------------

def recover_bubble(points, triangles, u, p):
    """Bubble coefficients (T,2) of p_h from u_h and the vertex values of p: the bubble rows of
    ∫ p·ψ + ∫ u div ψ = (boundary terms, which vanish for ψ = b_T e_d) give, with ∫b = 9|T|/20,
    ∫λ_k b = 3|T|/20, ∫b² = 81|T|/280 (b = 27 λ0λ1λ2): c_d = 14/9 ∂_d u_h − 14/27 Σ_k p_{k,d}.
    (Local to T, independent of δ and of the contact terms, which the bubble does not see.)"""
    P = np.asarray(points, dtype=float)[:, :2]
    t = np.asarray(triangles, dtype=np.int64)
    _, _, G, _ = _geometry(P, t)
    gu = np.einsum("tv,tvd->td", np.asarray(u, dtype=float)[t], G)
    return 14.0 / 9.0 * gu - 14.0 / 27.0 * np.asarray(p, dtype=float)[:, :2][t].sum(axis=1)


def _crack_geometry(crack_points, crack_segments, exact):
    """(C (I, 2) crack nodes or None, segments (S, 2) or None, tips [(2,)...]): the nodes and segments
    of the data (no segments: one crack of consecutive nodes), else the tips of exact.cracks."""
    if crack_points is not None and len(crack_points) >= 2:
        C = np.asarray(crack_points, dtype=float)[:, :2]
        segments = (consecutive_segments(C.shape[0]) if crack_segments is None
                    else check_segments(crack_segments, C.shape[0]))
        return C, segments, list(C[crack_tips(segments, C.shape[0])])
    if exact.cracks:
        return None, None, [p for c in exact.cracks for p in (c[0], c[-1])]
    raise ExactError("no crack geometry: give crack_points or an ExactSolution with cracks")


def solver_case_errors(points, triangles, u, p, p_bubble, crack_points, lam, exact, quad=None,
                       p_mass=None, crack_segments=None):
    """Errors of one solver case against ``exact`` (an ExactSolution).

    points (N,2|3), triangles (T,3) of the case mesh (the cracked mesh for the broken u space, the
    plain mesh for the continuous one; u is P1 per triangle on it), u (N,), p (N,2|3) the values of
    p_h's P1 part at the same vertices (a broken-tangential p has different values on
    the two copies of a crack vertex: each triangle reads its own copy through `triangles`, so p_h
    is integrated on each face with that face's value, never merged), p_bubble (T,2) its bubble
    coefficients (b_T = 27 λ0λ1λ2, triangle order of the mesh;
    None: recovered from u and p by ``recover_bubble``), crack_points (I,2|3) the nodes of every crack,
    crack_segments (S,2) the segments within each crack (None: one crack, consecutive nodes), lam (S,)
    per segment or (I,) per node. Any of u, p, lam may be None (its errors are None).
    p_mass: "consistent" (p_bubble required: ExactError without it), "lumped" (p_h is P1 without
    bubble: bubble 0, and a stored p_bubble is an ExactError) or None (as stored, else recovered).

    Returns {"u_l2", "p_l2", "p_x", "lambda_l2"} (floats or None) and "bubble": "stored",
    "recovered", "none (lumped)" or None."""
    quad = quad or Quadrature()
    P = np.asarray(points, dtype=float)[:, :2]
    t = np.asarray(triangles, dtype=np.int64)
    C, segments, tips = _crack_geometry(crack_points, crack_segments, exact)
    u_tri = None if u is None else np.asarray(u, dtype=float)[t]
    p_tri, bub, bsrc = None, None, None
    if p_mass not in (None, "consistent", "lumped"):
        raise ExactError(f"unknown p mass {p_mass!r}")
    if p is not None:
        p_tri = np.asarray(p, dtype=float)[:, :2][t]
        if p_mass == "lumped":
            if p_bubble is not None:
                raise ExactError("the case has a p_bubble dataset, but the lumped p is P1 without "
                                 "bubble")
            bub, bsrc = np.zeros((t.shape[0], 2)), "none (lumped)"
        elif p_mass == "consistent" and p_bubble is None:
            raise ExactError("no p_bubble in fields.h5: the consistent p is MINI, its bubble "
                             "coefficients must be stored with it")
        elif p_bubble is not None:
            bub, bsrc = np.asarray(p_bubble, dtype=float)[:, :2], "stored"
            if bub.shape[0] != t.shape[0]:
                raise ExactError(f"p_bubble has {bub.shape[0]} rows for {t.shape[0]} triangles")
        elif u is not None:
            bub, bsrc = recover_bubble(P, t, u, p), "recovered"
        else:
            raise ExactError("p without p_bubble and without u: the bubble is unknown")
    su, sp, sd = _domain_errors(P, t, exact, tips, quad, u_tri, p_tri, bub)
    out = {"u_l2": None if u is None else math.sqrt(su),
           "p_l2": None if p is None else math.sqrt(sp),
           "p_x": None if p is None else math.sqrt(sp + sd),
           "lambda_l2": None, "bubble": bsrc}
    if lam is not None:
        if C is None:
            raise ExactError("lambda without crack points")
        out["lambda_l2"] = math.sqrt(_crack_error(C, segments, _lambda_fn(lam, segments, C.shape[0]), exact,
                                                  quad))
    return out


ESTIMATED_QUANTITIES = ("u_l2", "p_l2", "p_x", "lambda_l2")


def solver_case_errors_estimated(*args, quad=None, **kwargs):
    """``solver_case_errors`` with the rule ``quad`` (default Quadrature()), plus "higher": the
    errors with ``quad.higher()``, and "quadrature": |e(quad) − e(quad.higher())| per quantity
    (None where the error is None), the estimate of each error's quadrature error."""
    quad = quad or Quadrature()
    base = solver_case_errors(*args, quad=quad, **kwargs)
    high = solver_case_errors(*args, quad=quad.higher(), **kwargs)
    base["higher"] = {q: high[q] for q in ESTIMATED_QUANTITIES}
    base["quadrature"] = {q: None if base[q] is None or high[q] is None else abs(base[q] - high[q])
                          for q in ESTIMATED_QUANTITIES}
    return base


# ---------------------------------------------------------------------------------------------
# Self-check of the quadrature: monomials against Green's theorem
# ---------------------------------------------------------------------------------------------

def boundary_edges(triangles, points):
    """(E, 2) vertex indices of the edges of one triangle only, each oriented counterclockwise
    in its triangle: the boundary of the mesh's polygon (the two faces of a cut crack included,
    with opposite orientations, so their contributions cancel)."""
    P = np.asarray(points, dtype=float)[:, :2]
    t = np.asarray(triangles, dtype=np.int64)
    X = P[t]
    det = ((X[:, 1, 0] - X[:, 0, 0]) * (X[:, 2, 1] - X[:, 0, 1])
           - (X[:, 1, 1] - X[:, 0, 1]) * (X[:, 2, 0] - X[:, 0, 0]))
    ccw = np.where((det > 0)[:, None], t, t[:, [0, 2, 1]])
    edges = np.concatenate([ccw[:, [0, 1]], ccw[:, [1, 2]], ccw[:, [2, 0]]])
    key = np.sort(edges, axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    return edges[counts[inverse.ravel()] == 1]


def _powers(v, degree):
    """(degree + 1, N): v**0, v**1, ... by repeated products."""
    out = np.empty((degree + 1, v.shape[0]))
    out[0] = 1.0
    for k in range(1, degree + 1):
        np.multiply(out[k - 1], v, out=out[k])
    return out


def polygon_moments(points, edges, degree, center, scale):
    """M[a, b] = ∫_Ω ξ^a η^b dA for a + b ≤ degree, ξ = (x − cx)/scale, η = (y − cy)/scale, Ω
    the polygon(s) bounded by the counterclockwise `edges` (E, 2) of `points`: Green's theorem,
    a sum over the edges (v_i, v_j) of the moments of the signed triangles (0, v_i, v_j),
    ∫ ξ^a η^b = a! b! / (a + b + 2)! (ξ_i η_j − ξ_j η_i) Σ_k Σ_l C(k + l, l) C(a + b − k − l, b − l)
    ξ_i^k ξ_j^(a−k) η_i^l η_j^(b−l) (C. Steger, On the calculation of arbitrary moments of
    polygons, 1996). In area units (dA = scale² dξ dη)."""
    P = (np.asarray(points, dtype=float)[:, :2] - np.asarray(center, dtype=float)) / scale
    xi, yi = P[edges[:, 0], 0], P[edges[:, 0], 1]
    xj, yj = P[edges[:, 1], 0], P[edges[:, 1], 1]
    cross = xi * yj - xj * yi
    Xi, Xj, Yi, Yj = (_powers(v, degree) for v in (xi, xj, yi, yj))
    M = np.zeros((degree + 1, degree + 1))
    for a in range(degree + 1):
        for b in range(degree + 1 - a):
            acc = np.zeros_like(cross)
            for k in range(a + 1):
                for l in range(b + 1):
                    acc += (math.comb(k + l, l) * math.comb(a + b - k - l, b - l)
                            * Xi[k] * Xj[a - k] * Yi[l] * Yj[b - l])
            M[a, b] = (math.factorial(a) * math.factorial(b) / math.factorial(a + b + 2)
                       * float(np.dot(cross, acc)))
    return M * scale * scale


def quadrature_moments(points, triangles, tips, quad, degree, center, scale):
    """M[a, b] ≈ ∫_Ω ξ^a η^b dA (as polygon_moments) by the error quadrature: the pieces and rules
    of the errors (``_point_batches``: Stroud, tip rules, near-tip splits) with ``quad``."""
    P = np.asarray(points, dtype=float)[:, :2]
    t = np.asarray(triangles, dtype=np.int64)
    X, area, _, _ = _geometry(P, t)
    M = np.zeros((degree + 1, degree + 1))
    for ids, L, W in _point_batches(P, t, tips, quad):
        xy = (L @ X[ids] - np.asarray(center, dtype=float)) / scale  # (K,q,2)
        w = np.broadcast_to(W * area[ids][:, None], xy.shape[:2]).ravel()
        xs, ys = xy[..., 0].ravel(), xy[..., 1].ravel()
        M += (_powers(xs, degree) * w) @ _powers(ys, degree).T
    mask = np.add.outer(np.arange(degree + 1), np.arange(degree + 1)) <= degree
    return np.where(mask, M, 0.0)


# Agreement asked of the quadrature's moments with the exact ones, relative to the mesh's area
# (every scaled monomial is at most 1 in absolute value, so |moment| <= area): the rules' weights
# are accurate to ~1e-15 (Golub-Welsch eigenvectors, Gauss-Legendre) and the sums over <= 1e7
# points in float64 to ~1e-13 of the area (blocked matrix products; measured <= 3e-15 on the
# repository's meshes, levels 0-4), while a weight or point off by 1e-9 of one point's share moves
# a moment by more than this.
SELF_CHECK_TOLERANCE = 1e-12


def quadrature_self_check(points, triangles, tips, quad=None):
    """The error quadrature ``quad`` (default Quadrature()) and its higher rule, checked on one
    mesh: the largest |quadrature moment − exact moment| / area over the monomials ξ^a η^b of the
    mesh's scaled coordinates (centred on its bounding box, |ξ|, |η| ≤ 1) with a + b up to each
    rule's degree. Returns [{"rule", "degree", "worst", "monomial", "ok"}] for the rule and the
    higher one."""
    quad = quad or Quadrature()
    P = np.asarray(points, dtype=float)[:, :2]
    t = np.asarray(triangles, dtype=np.int64)
    lo, hi = P.min(axis=0), P.max(axis=0)
    center, scale = 0.5 * (lo + hi), max(0.5 * float(np.max(hi - lo)), 1e-300)
    edges = boundary_edges(t, P)
    tips = [np.asarray(tp, dtype=float)[:2] for tp in tips]
    area = float(_geometry(P, t)[1].sum())
    out = []
    for name, q in (("rule", quad), ("higher rule", quad.higher())):
        d = q.degree()
        exact_m = polygon_moments(P, edges, d, center, scale)
        got = quadrature_moments(P, t, tips, q, d, center, scale)
        dev = np.abs(got - exact_m) / area
        a, b = np.unravel_index(int(np.argmax(dev)), dev.shape)
        worst = float(dev[a, b])
        out.append({"rule": name, "quadrature": repr(q), "degree": d, "worst": worst,
                    "monomial": [int(a), int(b)], "ok": bool(worst <= SELF_CHECK_TOLERANCE)})
    return out


def read_h5_case(h5, case):
    """Datasets of /cases/CASE in fields.h5 (an open h5py File or a path): dict(points, triangles,
    u, p, p_bubble, crack_points, crack_segments, lam), missing ones None."""
    import h5py

    own = not isinstance(h5, h5py.File)
    f = h5py.File(h5, "r") if own else h5
    try:
        g = f[f"cases/{case}"]

        def get(name, dtype=float):
            return np.asarray(g[name][()], dtype=dtype) if name in g else None

        return {"points": get("mesh/points"), "triangles": get("mesh/triangles", np.int64), "u": get("u"),
                "p": get("p"), "p_bubble": get("p_bubble"), "crack_points": get("crack/points"),
                "crack_segments": get("crack/segments", np.int64), "lam": get("crack/lambda")}
    finally:
        if own:
            f.close()


def solver_case_errors_h5(h5, case, exact, quad=None, p_mass=None):
    """``solver_case_errors`` of the case CASE of fields.h5 (open h5py File or path)."""
    d = read_h5_case(h5, case)
    return solver_case_errors(d["points"], d["triangles"], d["u"], d["p"], d["p_bubble"], d["crack_points"],
                              d["lam"], exact, quad, p_mass=p_mass, crack_segments=d["crack_segments"])


def p1_field_errors(points, triangles, u, crack_pairs, exact, quad=None, ranges=None):
    """Errors of a P1 field u (N,) on a cracked mesh (a reference solver's solution):
    crack_pairs (I,2) the (plus, minus) vertex pairs of crack.txt (a tip: the same index twice),
    ranges [(first, n)] its cracks (cracks.txt; None: one crack of all rows). p_h = ∇u_h (constant
    per triangle), λ_h = [u_h] = u[plus] − u[minus] linear along each crack.
    Returns {"u_l2", "p_l2", "lambda_l2"}."""
    quad = quad or Quadrature()
    P = np.asarray(points, dtype=float)[:, :2]
    t = np.asarray(triangles, dtype=np.int64)
    pairs = np.asarray(crack_pairs, dtype=np.int64)
    uu = np.asarray(u, dtype=float)
    C = P[pairs[:, 0]]
    if np.abs(P[pairs[:, 1]] - C).max() > 1e-12 * max(1.0, float(np.abs(P).max())):
        raise ExactError("crack pairs are not at the same positions")
    segments = consecutive_segments(len(pairs)) if ranges is None else np.concatenate(
        [consecutive_segments(n) + first for first, n in ranges])
    tips = list(C[crack_tips(segments, C.shape[0])])
    _, _, G, _ = _geometry(P, t)
    grad = np.einsum("tv,tvd->td", uu[t], G)
    p_tri = np.repeat(grad[:, None, :], 3, axis=1)
    su, sp, _ = _domain_errors(P, t, exact, tips, quad, uu[t], p_tri, None, want_div=False)
    jump_h = uu[pairs[:, 0]] - uu[pairs[:, 1]]
    sl = _crack_error(C, segments, _lambda_fn(jump_h, segments, C.shape[0]), exact, quad)
    return {"u_l2": math.sqrt(su), "p_l2": math.sqrt(sp), "lambda_l2": math.sqrt(sl)}


# Corners of a triangle are evaluated this fraction of the way towards its centroid, so that a
# value on the crack is taken from the triangle's own side (sign(y), atan2's branch cut): the P1
# interpolant on a cracked mesh has one value per face at every crack node.
INSIDE = 1e-12


def interpolant_corners(exact, P, tris):
    """(T,3) the P1 interpolant I_h u of the exact u at the corners of each triangle, each corner
    taken from its own triangle's side of the crack (INSIDE)."""
    X = np.asarray(P, dtype=float)[:, :2][np.asarray(tris, dtype=np.int64)]  # (T,3,2)
    c = X.mean(axis=1, keepdims=True)
    inner = X + INSIDE * (c - X)
    return np.asarray(exact.u(inner[..., 0], inner[..., 1]), dtype=float) * np.ones(X.shape[:2])


def p1_interpolation_errors(points, triangles, crack_pairs, exact, quad=None, ranges=None):
    """‖u − I_h u‖ and ‖∇(u − I_h u)‖ of the P1 interpolant of the exact u on a cracked mesh (a
    reference solver's: crack_pairs, ranges as p1_field_errors, for the tips the quadrature
    refines towards), with the quadrature of p1_field_errors (the same points: its evaluation of
    the exact solution is shared). Returns {"u_l2", "p_l2"}."""
    quad = quad or Quadrature()
    P = np.asarray(points, dtype=float)[:, :2]
    t = np.asarray(triangles, dtype=np.int64)
    pairs = np.asarray(crack_pairs, dtype=np.int64)
    C = P[pairs[:, 0]]
    segments = consecutive_segments(len(pairs)) if ranges is None else np.concatenate(
        [consecutive_segments(n) + first for first, n in ranges])
    tips = list(C[crack_tips(segments, C.shape[0])])
    u_tri = interpolant_corners(exact, P, t)
    _, _, G, _ = _geometry(P, t)
    grad = np.einsum("tv,tvd->td", u_tri, G)
    p_tri = np.repeat(grad[:, None, :], 3, axis=1)
    su, sp, _ = _domain_errors(P, t, exact, tips, quad, u_tri, p_tri, None, want_div=False)
    return {"u_l2": math.sqrt(su), "p_l2": math.sqrt(sp)}


def integrate_on_triangle(fn, vertices, tip=None, quad=None):
    """∫_T fn(x, y) over one triangle: the tip rule collapsed at vertex ``tip`` (0, 1 or 2), or
    for tip=None the plain Stroud rule (no near-tip splitting). For tests."""
    quad = quad or Quadrature()
    X = np.asarray(vertices, dtype=float)[:, :2]
    area = 0.5 * abs((X[1, 0] - X[0, 0]) * (X[2, 1] - X[0, 1]) - (X[1, 1] - X[0, 1]) * (X[2, 0] - X[0, 0]))
    L, W = tip_rule(quad.tip_m, tip) if tip is not None else stroud_rule(quad.n)
    xy = L @ X
    return area * float(np.dot(W, fn(xy[:, 0], xy[:, 1])))
