"""The cracks of an `sdcrack mesh SCENE --out DIR` export, read and checked alike by both references
and the compare tool: which rows of crack.txt form which crack, the tips, the segments, the nodal
normals, the triangle sides and the kind of mesh (structured grid, or uniform refinement).

Files of DIR/level{L}/ (0-based indices; absent files are those of an export written before polyline cracks,
which has one straight crack on a structured grid):

    crack.txt          plus minus        per crack node: the cracked-mesh vertex on the + face and the one
                                         on the − face. The cracks' nodes are concatenated in scene order,
                                         each crack from its first point to its last; the tips of every
                                         crack (its first and last row, unless that end is a mouth) have
                                         plus == minus, every other node plus != minus. A mouth (an edge
                                         crack's end on ∂Ω, elastic scenes) is doubled like an interior
                                         node: plus != minus, both copies on ∂Ω.
    cracks.txt         first n           per crack: crack c is rows first..first+n−1 of crack.txt, n ≥ 2,
      or first n tip_first tip_last      the cracks in order and together covering every row; a crack
                                         with a mouth has two more columns, 1 where that end is a tip and
                                         0 where it is a mouth (two columns: both ends are tips).
                                         Absent: one crack made of all rows.
    crack_normals.txt  nx ny             per row of crack.txt: the unit normal ν at the node. A segment's
                                         normal is its direction (node k → k+1) turned by +90°; at an
                                         interior node the normalised length-weighted mean
                                         (ℓ_{k−1}ν_{k−1} + ℓ_kν_k)/|…| of its two segments' normals (at a
                                         kink of a polyline: a bisector); at a tip its one segment's normal.
                                         The + face is the side ν points into. Absent: the scene's single
                                         normal at every row (when the caller gives one), else the normals
                                         computed from the nodes by that rule.
    sides.txt          s0 s1 s2          per triangle, one per corner in triangles.txt order: +1 / −1 when
                                         that corner is a doubled crack node (an interior node or a mouth)
                                         and the triangle lies on its + / − face, 0 otherwise. Old format: one integer per triangle,
                                         ±1 for a triangle at an interior crack node, 0 otherwise.
    mesh.json          "kind"            "structured" (a rectangle's grid: `nx`, `ny` cells) or "refined"
                                         (level 0 from gmsh, `coarse_triangles` triangles, refined
                                         uniformly: triangle 4t + c of level L+1 lies in triangle t of
                                         level L, children c = 0, 1, 2 at its corners 0, 1, 2, child 3 the
                                         middle) or "graded" (graded towards the crack tips by
                                         newest-vertex bisection; levels L > 0 have parents.txt:
                                         per triangle, the triangle of level L−1 it lies in).
                                         Absent: "structured".
             "boundary_parts"  [name, …]  the named parts of ∂Ω (elastic scenes): a rectangle's "left",
                                         "right", "bottom", "top"; a polygon's "edge1" … "edgeN"; a mesh
                                         file's "boundary".
    boundary_edges.txt v0 v1 part        elastic scenes: per boundary edge of the cracked mesh,
                                         counter-clockwise along ∂Ω (Ω on its left), its vertices (at a
                                         mouth, the copy of the edge's own face) and the index of its
                                         part in mesh.json's "boundary_parts" (read_boundary_edges).

A crack's segments are the pairs of consecutive rows WITHIN it: no segment joins the last node of a
crack to the first of the next. Errors are ExportError, one line naming the file (and the crack).
Standard library and numpy only.
"""

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import sdexpr

KINDS = ("structured", "refined", "graded")
DEFAULT_KIND = "structured"
NORMAL_TOLERANCE = 1e-9  # crack_normals.txt against the normals computed from the nodes


class ExportError(ValueError):
    """A missing or malformed file of a mesh export (the message is one line naming it)."""


@dataclass
class CrackLayout:
    """The cracks of one level: pairs (I, 2) = crack.txt, ranges [(first, n)] per crack (rows
    first..first+n−1), normals (I, 2) the unit normal ν at each row, ends [(tip_first, tip_last)]
    per crack: whether each end is a tip (False: a mouth on ∂Ω); None: every end is a tip."""

    pairs: np.ndarray
    ranges: list
    normals: np.ndarray
    ends: list = None

    @property
    def n_cracks(self):
        return len(self.ranges)

    def crack_ends(self):
        """[(tip_first, tip_last)] per crack (True: that end is a tip)."""
        return self.ends if self.ends is not None else [(True, True)] * len(self.ranges)

    def tip_rows(self):
        """The rows of the tips, in crack order: each crack's first and last row unless that end is a
        mouth (the tips' order of docs/elasticity.md)."""
        return np.array([r for (first, n), tips in zip(self.ranges, self.crack_ends())
                         for r, tip in zip((first, first + n - 1), tips) if tip], dtype=np.int64)

    def mouth_rows(self):
        """The rows of the mouths (crack ends on ∂Ω, doubled), in crack order."""
        return np.array([r for (first, n), tips in zip(self.ranges, self.crack_ends())
                         for r, tip in zip((first, first + n - 1), tips) if not tip], dtype=np.int64)

    def tip_vertices(self):
        """The cracked-mesh vertices of all tips (a tip's plus == minus)."""
        return self.pairs[self.tip_rows(), 0]

    def interior(self):
        """(I,) bool: rows that are not tips (their nodes have a + and a − copy: the interior crack
        nodes and the mouths)."""
        mask = np.ones(len(self.pairs), dtype=bool)
        mask[self.tip_rows()] = False
        return mask

    def segments(self):
        """(S, 2) row pairs [k, k+1] of the segments, crack by crack (S = I − cracks)."""
        return segments_of(self.ranges)


def segments_of(ranges):
    """(S, 2) the row pairs [k, k+1] within each crack of `ranges` [(first, n)], in crack order."""
    parts = [np.column_stack([np.arange(first, first + n - 1), np.arange(first + 1, first + n)])
             for first, n in ranges]
    return np.concatenate(parts).astype(np.int64) if parts else np.zeros((0, 2), dtype=np.int64)


def segment_normals(points, segments):
    """(S, 2) unit normals of the segments [a, b] (rows of points): (b − a)/|b − a| turned by +90°."""
    d = points[segments[:, 1]] - points[segments[:, 0]]
    length = np.hypot(d[:, 0], d[:, 1])
    return np.column_stack([-d[:, 1], d[:, 0]]) / length[:, None]


def jump_error_sq(layout, xy, jump_h, rule, exact_jump=None, exact_u=None):
    """Σ over the crack segments of ∫ ([u_h] − [u])² ds, the references' crack-jump error squared:
    [u_h] linear between the segment's crack-node values `jump_h`; [u] = exact_jump(X, Y), else
    exact_u on each face of the segment (sdexpr.on_face with the segment's normal); `rule(tip_a,
    tip_b)` gives the segment's points s ∈ [0, 1] and weights (whether each end is a tip)."""
    segments = layout.segments()
    points = xy[layout.pairs[:, 0]]
    normals = segment_normals(points, segments)
    is_tip = ~layout.interior()
    total = 0.0
    for (i, j), normal in zip(segments, normals):
        a, b = points[i], points[j]
        s, w = rule(is_tip[i], is_tip[j])
        X, Y = a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])
        if exact_jump is not None:
            je = exact_jump(X, Y)
        else:
            je = exact_u(*sdexpr.on_face(X, Y, normal, 1.0)) \
                - exact_u(*sdexpr.on_face(X, Y, normal, -1.0))
        jh = (1 - s) * jump_h[i] + s * jump_h[j]
        total += float(np.hypot(*(b - a)) * np.sum(w * (jh - je) ** 2))
    return total


def node_normals(points, ranges):
    """(I, 2) the nodal normals of the module documentation's rule, from the crack nodes' points."""
    segments = segments_of(ranges)
    d = points[segments[:, 1]] - points[segments[:, 0]]
    weighted = np.column_stack([-d[:, 1], d[:, 0]])  # ℓ_k ν_k
    acc = np.zeros((len(points), 2))
    np.add.at(acc, segments[:, 0], weighted)
    np.add.at(acc, segments[:, 1], weighted)
    return acc / np.hypot(acc[:, 0], acc[:, 1])[:, None]


# ---- reading -----------------------------------------------------------------------------------

def load_table(path, dtype, ncols):
    """A whitespace table of `ncols` columns as an (R, ncols) array (R may be 0)."""
    path = Path(path)
    if not path.exists():
        raise ExportError(f"missing file {path}")
    try:
        a = np.loadtxt(path, dtype=dtype, ndmin=2)
    except ValueError as e:
        raise ExportError(f"cannot read {path}: {e}".replace("\n", " ")) from None
    if a.size == 0:
        return a.reshape(0, ncols)
    if a.shape[1] != ncols:
        raise ExportError(f"{path}: expected {ncols} columns, found {a.shape[1]}")
    return a


def read_ranges(path, n_rows):
    """[(first, n)] of cracks.txt at `path` for a crack.txt of `n_rows` rows ([(0, n_rows)] when the
    file is absent): the cracks must follow each other from row 0 and cover every row."""
    return read_crack_table(path, n_rows)[0]


def read_crack_table(path, n_rows):
    """([(first, n)], [(tip_first, tip_last)]) of cracks.txt at `path` for a crack.txt of `n_rows`
    rows: read_ranges's ranges, and per crack whether each end is a tip (rows of four columns; two
    columns: both tips)."""
    path = Path(path)
    if not path.exists():
        if n_rows < 2:
            raise ExportError(f"{path.parent / 'crack.txt'}: {n_rows} row(s), a crack needs at least its 2 tips")
        return [(0, int(n_rows))], [(True, True)]
    table = _int_rows(path, (2, 4))
    if len(table) == 0:
        raise ExportError(f"{path}: no crack listed")
    ranges, ends, expected = [], [], 0
    for c, row in enumerate(table):
        first, n = row[:2]
        if first != expected:
            raise ExportError(f"{path}: crack {c} starts at row {first} of crack.txt, expected {expected} "
                              "(the cracks' rows must follow each other)")
        if n < 2:
            raise ExportError(f"{path}: crack {c} has {n} node(s), at least its 2 ends are needed")
        tips = tuple(row[2:]) or (1, 1)
        if any(t not in (0, 1) for t in tips):
            raise ExportError(f"{path}: crack {c}: tip_first tip_last must be 0 (a mouth) or 1 (a tip), "
                              f"found {tips[0]} {tips[1]}")
        ranges.append((int(first), int(n)))
        ends.append((bool(tips[0]), bool(tips[1])))
        expected = first + n
    if expected != n_rows:
        raise ExportError(f"{path}: the cracks cover rows 0..{expected - 1}, but crack.txt has {n_rows} rows")
    return ranges, ends


def _int_rows(path, widths):
    """The rows of a whitespace table of integers, each of one of the column counts `widths`."""
    rows = []
    try:
        text = Path(path).read_text()
    except (OSError, UnicodeDecodeError) as e:
        raise ExportError(f"cannot read {path}: {e}".replace("\n", " ")) from None
    for k, line in enumerate(text.splitlines()):
        words = line.split()
        if not words:
            continue
        try:
            row = [int(w) for w in words]
        except ValueError:
            raise ExportError(f"{path}: line {k + 1} is not integers: {line.strip()[:60]!r}") from None
        if len(row) not in widths:
            raise ExportError(f"{path}: line {k + 1} has {len(row)} columns, expected "
                              f"{' or '.join(map(str, widths))}")
        rows.append(row)
    return rows


def check_pairs(path, pairs, ranges, n_vertices, copies=True, ends=None):
    """crack.txt's rows against the ranges: indices in range, each crack's tips with plus == minus and,
    with `copies`, its interior nodes and its mouths (`ends` [(tip_first, tip_last)], None: every end
    a tip) with plus != minus (the cracked mesh of a solver; a field on a mesh without copies, where
    every row has plus == minus, is read with copies=False)."""
    if pairs.size and (pairs.min() < 0 or pairs.max() >= n_vertices):
        raise ExportError(f"{path}: vertex index out of range 0..{n_vertices - 1}")
    ends = ends if ends is not None else [(True, True)] * len(ranges)
    for c, ((first, n), tips) in enumerate(zip(ranges, ends)):
        last = first + n - 1
        for row, tip in zip((first, last), tips):
            if tip and pairs[row, 0] != pairs[row, 1]:
                raise ExportError(f"{path}: crack {c} (rows {first}..{last}): its tip at row {row} has "
                                  f"plus {pairs[row, 0]} != minus {pairs[row, 1]}")
            if not tip and copies and pairs[row, 0] == pairs[row, 1]:
                raise ExportError(f"{path}: crack {c} (rows {first}..{last}): its mouth at row {row} has "
                                  "plus == minus (a mouth on ∂Ω needs two copies)")
        if not copies:
            continue
        inner = np.flatnonzero(pairs[first + 1:last, 0] == pairs[first + 1:last, 1])
        if len(inner):
            row = first + 1 + int(inner[0])
            raise ExportError(f"{path}: crack {c} (rows {first}..{last}): interior node at row {row} has "
                              "plus == minus (an interior crack node needs two copies)")


def _crack_of_row(ranges, row):
    """The crack of `ranges` [(first, n)] that holds crack.txt's row `row`."""
    return next(c for c, (first, n) in enumerate(ranges) if first <= row < first + n)


def check_segments(path, nodes, ranges):
    """Every segment of every crack has a positive length (nodes (I, 2): the crack nodes' points)."""
    segments = segments_of(ranges)
    d = nodes[segments[:, 1]] - nodes[segments[:, 0]]
    zero = np.flatnonzero(~(np.hypot(d[:, 0], d[:, 1]) > 0))
    if len(zero):
        k = int(segments[zero[0], 0])
        crack = _crack_of_row(ranges, k)
        raise ExportError(f"{path}: crack {crack}: rows {k} and {k + 1} are at the same point (a segment of "
                          "zero length)")


def read_normals(path, points, ranges, default=None):
    """(I, 2) crack_normals.txt at `path` (I crack nodes at `points`), each row checked against the
    normal computed from the nodes (to NORMAL_TOLERANCE); absent: `default` (2,) at every row, or the
    computed normals when no default is given."""
    path = Path(path)
    computed = node_normals(points, ranges)
    if not path.exists():
        return computed if default is None else np.tile(np.asarray(default, dtype=float), (len(points), 1))
    normals = load_table(path, float, 2)
    if len(normals) != len(points):
        raise ExportError(f"{path}: {len(normals)} rows for {len(points)} rows of crack.txt")
    bad = np.flatnonzero(~(np.abs(normals - computed) <= NORMAL_TOLERANCE).all(axis=1))
    if len(bad):
        row = int(bad[0])
        crack = _crack_of_row(ranges, row)
        raise ExportError(f"{path}: row {row} (crack {crack}) is ({normals[row, 0]:.17g}, {normals[row, 1]:.17g}), "
                          f"not the unit normal ({computed[row, 0]:.17g}, {computed[row, 1]:.17g}) of the "
                          "crack at that node")
    return normals


def read_layout(level_dir, points, n_vertices, default_normal=None, copies=True):
    """The CrackLayout of level_dir (crack.txt, cracks.txt, crack_normals.txt); `points` (N, 2) the
    cracked mesh's vertices, `default_normal` the scene's single normal of an old export (or None),
    `copies`: see check_pairs."""
    d = Path(level_dir)
    pairs = load_table(d / "crack.txt", np.int64, 2)
    ranges, ends = read_crack_table(d / "cracks.txt", len(pairs))
    check_pairs(d / "crack.txt", pairs, ranges, n_vertices, copies, ends)
    nodes = np.asarray(points, dtype=float)[pairs[:, 0], :2]
    check_segments(d / "crack.txt", nodes, ranges)
    normals = read_normals(d / "crack_normals.txt", nodes, ranges, default_normal)
    has_mouth = any(not all(e) for e in ends)
    return CrackLayout(pairs=pairs, ranges=ranges, normals=normals, ends=ends if has_mouth else None)


def read_sides(path, triangles, layout):
    """(T, 3) sides.txt at `path`, with the cracked `triangles` (T, 3). New format: each ±1 corner must
    be the + / − copy of a doubled crack node (layout.interior(): interior nodes and mouths), each 0
    corner none. Old format (one value per
    triangle): ±1 spread to the corners at interior crack copies. Absent: None."""
    path = Path(path)
    if not path.exists():
        return None
    try:
        a = np.loadtxt(path, dtype=np.int64, ndmin=1)
    except ValueError as e:
        raise ExportError(f"cannot read {path}: {e}".replace("\n", " ")) from None
    n = len(triangles)
    if a.shape not in ((n,), (n, 3)) or not np.isin(a, (-1, 0, 1)).all():
        raise ExportError(f"{path}: expected one value (old format) or three (s0 s1 s2) in -1, 0, 1 per "
                          f"triangle for {n} triangles, found shape {a.shape}")
    inner = layout.pairs[layout.interior()]
    copy_side = np.zeros(int(max(triangles.max(initial=0), inner.max(initial=0))) + 1, dtype=np.int64)
    copy_side[inner[:, 0]] = 1
    copy_side[inner[:, 1]] = -1
    at_copy = copy_side[triangles]
    if a.ndim == 1:
        return np.where(at_copy != 0, a[:, None], 0)
    bad = np.argwhere(a != at_copy)
    if len(bad):
        t, k = (int(v) for v in bad[0])
        raise ExportError(f"{path}: triangle {t} corner {k} (vertex {triangles[t, k]}) has side {a[t, k]}, "
                          f"but that vertex is {_copy_name(at_copy[t, k])}")
    return a


def _copy_name(side):
    return {1: "the + copy of a doubled crack node", -1: "the − copy of a doubled crack node",
            0: "no doubled crack node"}[int(side)]


def read_kind(meta, path):
    """The mesh.json kind (DEFAULT_KIND when absent), checked: one of KINDS; a refined level has
    coarse_triangles · 4^level triangles."""
    kind = meta.get("kind", DEFAULT_KIND) if isinstance(meta, dict) else DEFAULT_KIND
    if kind not in KINDS:
        raise ExportError(f"{path}: kind {kind!r} is not one of {', '.join(KINDS)}")
    if kind == "refined":
        level, coarse, n = meta.get("level"), meta.get("coarse_triangles"), meta.get("n_triangles")
        if not all(isinstance(v, int) and not isinstance(v, bool) for v in (level, coarse, n)):
            raise ExportError(f"{path}: a refined level needs integer level, coarse_triangles and n_triangles")
        if n != coarse * 4 ** level:
            raise ExportError(f"{path}: {n} triangles, but a level-{level} refinement of {coarse} coarse "
                              f"triangles has {coarse * 4 ** level}")
    return kind


def read_mesh_json(level_dir):
    """mesh.json of level_dir as a dict ({} when absent)."""
    path = Path(level_dir) / "mesh.json"
    if not path.exists():
        return {}
    try:
        meta = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise ExportError(f"{path}: invalid JSON: {e}") from None
    if not isinstance(meta, dict):
        raise ExportError(f"{path}: not a JSON object")
    return meta


def read_boundary_edges(level_dir, n_vertices=None, layout=None):
    """(edges (E, 2), parts (E,), names) of level_dir's boundary_edges.txt and mesh.json's
    "boundary_parts", checked: names a non-empty list of distinct non-empty strings; every row
    `v0 v1 part` with v0 != v1, vertices in 0..n_vertices−1 (when given), part an index of names,
    every part used, no edge twice; each vertex starts at most one edge and ends at most one (∂Ω
    is one loop, cut open at the mouths); with `layout`, each mouth's two copies end or start
    exactly one edge each (the faces split the boundary at a mouth) and no tip is on an edge."""
    d = Path(level_dir)
    path = d / "boundary_edges.txt"
    meta = read_mesh_json(d)
    names = meta.get("boundary_parts")
    if not (isinstance(names, list) and names and all(isinstance(n, str) and n for n in names)
            and len(set(names)) == len(names)):
        raise ExportError(f"{d / 'mesh.json'}: 'boundary_parts' must be a non-empty list of distinct "
                          "part names")
    table = load_table(path, np.int64, 3)
    if len(table) == 0:
        raise ExportError(f"{path}: no boundary edge listed")
    edges, parts = table[:, :2], table[:, 2]
    if (edges[:, 0] == edges[:, 1]).any():
        row = int(np.flatnonzero(edges[:, 0] == edges[:, 1])[0])
        raise ExportError(f"{path}: row {row} joins vertex {edges[row, 0]} to itself")
    if edges.min() < 0 or (n_vertices is not None and edges.max() >= n_vertices):
        raise ExportError(f"{path}: vertex index out of range 0..{(n_vertices or 1) - 1}")
    if parts.min() < 0 or parts.max() >= len(names):
        raise ExportError(f"{path}: part index out of range 0..{len(names) - 1} ({', '.join(names)})")
    unused = sorted(set(range(len(names))) - set(parts.tolist()))
    if unused:
        raise ExportError(f"{path}: boundary part {names[unused[0]]!r} has no edge")
    if len(np.unique(np.sort(edges, axis=1), axis=0)) != len(edges):
        raise ExportError(f"{path}: an edge is listed twice")
    for column, role in ((0, "starts"), (1, "ends")):
        values, counts = np.unique(edges[:, column], return_counts=True)
        if (counts > 1).any():
            raise ExportError(f"{path}: vertex {values[counts > 1][0]} {role} {counts.max()} boundary edges "
                              "(∂Ω is one loop)")
    if layout is not None:
        _check_boundary_at_cracks(path, edges, layout)
    return edges, parts, names


def _check_boundary_at_cracks(path, edges, layout):
    """At each mouth of `layout`: the + and the − copy each on exactly one boundary edge; no tip on
    one."""
    on = np.bincount(edges.ravel(), minlength=int(layout.pairs.max(initial=0)) + 1)

    def count(v):
        return int(on[v]) if v < len(on) else 0
    for row in layout.mouth_rows():
        plus, minus = (int(v) for v in layout.pairs[row])
        if count(plus) != 1 or count(minus) != 1:
            raise ExportError(f"{path}: the mouth at crack.txt row {row} has its copies {plus} and {minus} on "
                              f"{count(plus)} and {count(minus)} boundary edges (each face's copy needs one)")
    for v in layout.tip_vertices():
        if count(int(v)):
            raise ExportError(f"{path}: tip vertex {int(v)} is on a boundary edge (a crack end on ∂Ω is a mouth)")


# ---- scene.json ----------------------------------------------------------------------------------

def scene_cracks(scene, path="scene.json"):
    """The scene's cracks as a list of (n, 2) polylines: "cracks" [{"points": [[x, y], ...]}, ...], else
    the old single "crack" {"a", "b"}."""
    if "cracks" in scene:
        cracks = scene["cracks"]
        if not isinstance(cracks, list) or not cracks:
            raise ExportError(f"{path}: 'cracks' must be a non-empty list")
        out = []
        for c, crack in enumerate(cracks):
            pts = crack.get("points") if isinstance(crack, dict) else None
            out.append(_polyline(pts, f"{path}: crack {c}"))
        return out
    crack = scene.get("crack")
    if not isinstance(crack, dict) or "a" not in crack or "b" not in crack:
        raise ExportError(f"{path}: neither 'cracks' nor a 'crack' with 'a' and 'b'")
    return [_polyline([crack["a"], crack["b"]], f"{path}: crack")]


def _polyline(points, what):
    try:
        a = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        a = None
    if a is None or a.ndim != 2 or a.shape[1] != 2 or len(a) < 2 or not np.isfinite(a).all():
        raise ExportError(f"{what}: 'points' must be a list of at least 2 finite [x, y] points")
    return a


def scene_normal(scene):
    """The old single crack's normal "crack": {"normal"} as a (2,) array, or None (several cracks,
    a polyline, or none given)."""
    crack = scene.get("crack")
    if isinstance(crack, dict) and crack.get("normal") is not None:
        return np.asarray(crack["normal"], dtype=float)
    return None
