"""The cut of a mesh along the crack, computed from the scene's polylines alone (issue 43): which
mesh vertices are crack nodes, in which order, which are tips, and on which face each triangle
corner at an interior crack node lies. No stored crack polyline, no export's crack.txt and no
solver code is read: the scene copy ([geometry] crack / cracks) and the mesh's coordinates and
triangles are the whole input, so a mesh whose faces are exchanged (at a kink, or everywhere)
is told from a right one with or without references.

The convention checked (docs/design.md "broken u"): on a mesh of the broken u (and the mesh
export the references solve on) every interior crack node has two vertices at its position, the
**+ copy** with the original vertex number and the **− copy** numbered after all vertices, the
− copies of the interior nodes of every crack, crack by crack in the scene's order and along each
polyline from its first point, being the last I vertices N − I … N − 1. Each triangle corner at
an interior crack node x uses the + copy when the triangle lies on the + face, the side the
normal ν points into (ν: the segment direction turned by +90°, so the + face is LEFT of the
polyline walked from its first point): the corner's direction c − x (c the triangle's centroid)
lies in the wedge left of the path, counter-clockwise from the outgoing segment's direction
`out` to the incoming segment's reversed direction `back`. On a continuous u's mesh every crack
node has one vertex; a tip always has one.

ON_CRACK_RTOL: a mesh vertex is a crack node when its distance to a segment of the scene's
polyline is ≤ ON_CRACK_RTOL × the segment's length (and its projection falls on the segment). The
crack vertices of refined and graded levels are midpoints of crack edges computed in float64
(crates/sdcrack-core/src/mesh/refine.rs, bisect.rs), a few units of round-off (~1e-16 relative
per level) off the exact line, and gmsh's level 0 gets the scene's points back exactly
(docs/design.md); every other vertex is a triangle's height away from the crack, 1e-3 of the
segment's length or more on every mesh this tool judges (levels ≤ 8 of cells ≥ 2). 1e-10 lies
six orders above the first and seven below the second.
"""
import numpy as np

from . import exact as exact_mod

ON_CRACK_RTOL = 1e-10


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def plus_face(out, back, d):
    """(n,) bool: direction d (n, 2) from a crack node lies on the + face, the wedge left of the
    path that leaves along `out` and arrives from `back` (both pointing away from the node).
    Written from the geometry, not from the solver's `left_of_path`: on a straight node (back =
    −out, their cross product exactly 0 as the scene's segment direction negated) the left half
    plane of out; at a kink whose left wedge is convex (out × back > 0) the directions left of
    out AND right of back; at a reflex one (out × back < 0) left of out OR right of back (the
    complement of the convex right wedge)."""
    left_of_out = _cross(out, d) > 0.0
    right_of_back = _cross(back, d) < 0.0
    turn = _cross(out, back)
    return np.where(turn == 0.0, left_of_out,
                    np.where(turn > 0.0, left_of_out & right_of_back, left_of_out | right_of_back))


class SceneCrack:
    """The crack nodes of one mesh from the scene's polylines: `xy` (I, 2) their positions (mesh
    coordinates, bit for bit) crack by crack and along each polyline, `segments` (S, 2) the node
    pairs within each crack, `tip` (I,) bool, `out` / `back` (I, 2) the scene's segment directions
    leaving / arriving at each node (pointing away from it; zero at a tip's missing side), `crack`
    (I,) the crack each node belongs to. `problems`: why the mesh cannot carry the scene's cracks
    (a polyline point that is no mesh vertex)."""

    def __init__(self, polylines, points):
        P = np.asarray(points, dtype=float)[:, :2]
        uniq = np.unique(P, axis=0)
        self.problems = []
        xy, seg, tip, out, back, crack = [], [], [], [], [], []
        for c, Q in enumerate(polylines):
            Q = np.asarray(Q, dtype=float)
            nodes = []  # (segment index, t, position)
            for i in range(len(Q) - 1):
                a, d = Q[i], Q[i + 1] - Q[i]
                L2 = float(d @ d)
                rel = uniq - a
                t = rel @ d / L2
                dist = np.abs(_cross(d, rel)) / np.sqrt(L2)
                on = np.flatnonzero((dist <= ON_CRACK_RTOL * np.sqrt(L2))
                                    & (t >= -ON_CRACK_RTOL) & (t <= 1.0 + ON_CRACK_RTOL))
                for k in on[np.argsort(t[on], kind="stable")]:
                    nodes.append((i, float(t[k]), uniq[k]))
            # a polyline point is the end of one segment and the start of the next: once
            ordered, first = [], len(xy)
            for i, t, x in nodes:
                if ordered and np.array_equal(ordered[-1][2], x):
                    continue
                ordered.append((i, t, x))
            for j, q in enumerate(Q):
                if not any(np.array_equal(x, q) for _, _, x in ordered):
                    self.problems.append(f"the point ({q[0]:.6g}, {q[1]:.6g}) of crack {c} of the "
                                         "scene is no mesh vertex")
            dirs = [Q[i + 1] - Q[i] for i in range(len(Q) - 1)]
            for n, (i, t, x) in enumerate(ordered):
                at_point = [j for j, q in enumerate(Q) if np.array_equal(q, x)]
                j = at_point[0] if at_point else None
                # the scene's segment leaving the node and the one arriving at it
                o = dirs[j] if j is not None and j < len(dirs) else (dirs[i] if j is None else None)
                b = (-dirs[j - 1] if j is not None and j > 0 else (-dirs[i] if j is None else None))
                xy.append(x)
                tip.append(o is None or b is None)
                out.append(o if o is not None else np.zeros(2))
                back.append(b if b is not None else np.zeros(2))
                crack.append(c)
                if n:
                    seg.append((first + n - 1, first + n))
        self.xy = np.array(xy, dtype=float).reshape(-1, 2)
        self.segments = np.array(seg, dtype=np.int64).reshape(-1, 2)
        self.tip = np.array(tip, dtype=bool)
        self.out = np.array(out, dtype=float).reshape(-1, 2)
        self.back = np.array(back, dtype=float).reshape(-1, 2)
        self.crack = np.array(crack, dtype=np.int64)

    @classmethod
    def of_scene(cls, scene_file, points, stored=None):
        """From the parsed scene copy; ExactError when it names no readable crack. A scene on a
        mesh file of its own (`mesh = { gmsh = … }`, no [geometry]) has its cracks in that file,
        which the results folder does not keep: `stored` (crack points (I, 2), segments (S, 2)),
        the crack the solver or the export wrote, stands in for its polylines (every node then a
        polyline point; the faces and the copies' numbers are checked all the same, the node
        set is the stored one)."""
        polylines = exact_mod.scene_cracks(scene_file)
        return cls(polylines if polylines or stored is None else chains(*stored), points)

    def vertices_at(self, points):
        """{node: sorted vertex numbers at its position (bit for bit)}."""
        P = np.asarray(points, dtype=float)[:, :2]
        zp = P[:, 0] + 1j * P[:, 1]
        zc = self.xy[:, 0] + 1j * self.xy[:, 1]
        node_of = {complex(z): k for k, z in enumerate(zc)}
        at = {k: [] for k in range(len(zc))}
        for v in np.flatnonzero(np.isin(zp, zc)):
            at[node_of[complex(zp[v])]].append(int(v))
        return at

    def copies(self, points):
        """(plus, minus) (I,) the lower and the higher vertex number at each node (equal where it
        has one vertex), with the list of vertices at each node."""
        at = self.vertices_at(points)
        plus = np.array([min(at[k]) if at[k] else -1 for k in range(len(self.xy))], dtype=np.int64)
        minus = np.array([max(at[k]) if at[k] else -1 for k in range(len(self.xy))],
                         dtype=np.int64)
        return plus, minus, at


def chains(points, segments):
    """The polylines (list of (n, 2) arrays) of crack nodes `points` joined by `segments` (each
    crack's node pairs [k, k + 1] in order)."""
    P = np.asarray(points, dtype=float)[:, :2]
    S = np.asarray(segments, dtype=np.int64).reshape(-1, 2)
    out, cur = [], []
    for a, b in S:
        if cur and cur[-1] == a:
            cur.append(int(b))
        else:
            if cur:
                out.append(P[cur])
            cur = [int(a), int(b)]
    if cur:
        out.append(P[cur])
    return out


def _where(x):
    return f"({x[0]:.6g}, {x[1]:.6g})"


def cut_problems(scene_crack, points, tris, broken, pairs=None):
    """Problems of one mesh's cut against the scene's cracks (module docstring): the copies at
    each node, the − copies' numbers, the face of every corner at an interior node; `pairs`
    (I, 2) the (plus, minus) rows of an export's crack.txt, which must be the (+, −) copies."""
    sc = scene_crack
    if sc.problems:
        return list(sc.problems)
    P = np.asarray(points, dtype=float)[:, :2]
    T = np.asarray(tris, dtype=np.int64)
    plus, minus, at = sc.copies(P)
    out = []
    missing = [k for k in range(len(sc.xy)) if not at[k]]
    if missing:
        return [f"{len(missing)} crack node(s) of the scene's polylines have no mesh vertex, e.g. "
                f"{_where(sc.xy[missing[0]])}"]
    want = np.where(sc.tip | (not broken), 1, 2)
    count = np.array([len(at[k]) for k in range(len(sc.xy))])
    wrong = np.flatnonzero(count != want)
    if len(wrong):
        k = wrong[0]
        what = ("a tip" if sc.tip[k] else "an interior node of the broken u" if broken
                else "a node of the continuous u")
        out.append(f"{len(wrong)} crack node(s) have another number of vertices than the cut "
                   f"needs, e.g. {what} at {_where(sc.xy[k])} has {count[k]} (vertices {at[k]}), "
                   f"{want[k]} expected")
        return out
    if broken:
        inner = np.flatnonzero(~sc.tip)
        n = len(P)
        numbered = np.arange(n - len(inner), n)
        if not np.array_equal(minus[inner], numbered):
            i = int(np.flatnonzero(minus[inner] != numbered)[0])
            k = inner[i]
            out.append(f"the − copies are not the last {len(inner)} vertices in crack order "
                       f"(docs/design.md): the interior node {_where(sc.xy[k])} (crack "
                       f"{sc.crack[k]}) has copies {plus[k]} and {minus[k]}, the − copy must be "
                       f"vertex {numbered[i]}")
        out.extend(_face_problems(sc, P, T, plus, minus))
    if pairs is not None:
        pairs = np.asarray(pairs, dtype=np.int64)
        if pairs.shape != (len(sc.xy), 2) or not (np.array_equal(pairs[:, 0], plus)
                                                   and np.array_equal(pairs[:, 1], minus)):
            out.append("the mesh export's crack.txt is not the (+ copy, − copy) list of the "
                       "scene's crack nodes in crack order"
                       + (f" ({len(pairs)} rows for {len(sc.xy)} nodes)"
                          if len(pairs) != len(sc.xy) else ""))
    return out


def _face_problems(sc, P, T, plus, minus):
    """Corners at interior crack nodes using the other face's copy."""
    node_of = np.full(len(P), -1)
    inner = np.flatnonzero(~sc.tip)
    node_of[plus[inner]] = inner
    node_of[minus[inner]] = inner
    tri, j = np.nonzero(node_of[T] >= 0)
    node = node_of[T[tri, j]]
    x = sc.xy[node]
    cen = P[T[tri]].sum(axis=1) / 3.0
    on_plus = plus_face(sc.out[node], sc.back[node], cen - x)
    used = T[tri, j]
    wrong = np.flatnonzero(used != np.where(on_plus, plus[node], minus[node]))
    if not len(wrong):
        return []
    i = wrong[0]
    k = node[i]
    nodes = np.unique(node[wrong])
    kinks = int(np.sum(_cross(sc.out[nodes], sc.back[nodes]) != 0.0))
    face = "+" if on_plus[i] else "−"
    return [f"{len(wrong)} triangle corner(s) at {len(nodes)} interior crack node(s) ({kinks} of "
            f"them kinks) use the other face's copy, e.g. at {_where(sc.xy[k])} (crack "
            f"{sc.crack[k]}) triangle {tri[i]} lies on the {face} face (its centroid "
            f"{_where(cen[i])}, from the scene's polyline) but uses vertex {used[i]}, the "
            f"{'−' if on_plus[i] else '+'} copy ({face} copy: "
            f"{plus[k] if on_plus[i] else minus[k]})"]
