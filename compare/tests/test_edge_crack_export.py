"""Edge cracks in the mesh export (docs/elasticity.md): compare/sdshared/sdexport.py reads a crack
end on ∂Ω (a mouth: cracks.txt's `first n tip_first tip_last`, a doubled row of crack.txt) and the
named boundary parts (mesh.json's "boundary_parts", boundary_edges.txt), and refuses malformed ones
with a one-line ExportError.

The export read is compare/tests/data/edge-crack-export: the exporter's own output (Rust test
output::mesh_export::tests::the_committed_edge_crack_export_is_the_exporters keeps it so) for
Ω = (−1, 1)², 4 × 4 cells, one crack y = 0 from the mouth (−1, 0) to the tip (0, 0), levels 0 and 1.
The scalar exports keep the two-column cracks.txt and read as before (test_multi_crack_exports.py).

Run: /usr/bin/python3 -m pytest -q -p no:cacheprovider compare/tests/test_edge_crack_export.py
"""
import shutil
from pathlib import Path

import numpy as np
import pytest

from sdshared import sdexport

EXPORT = Path(__file__).resolve().parent / "data" / "edge-crack-export"


def level(n, root=EXPORT):
    d = root / f"level{n}"
    xy = np.loadtxt(d / "vertices.txt", ndmin=2)
    tri = np.loadtxt(d / "triangles.txt", dtype=np.int64, ndmin=2)
    layout = sdexport.read_layout(d, xy, len(xy))
    return d, xy, tri, layout


@pytest.mark.parametrize("n", [0, 1])
def test_the_mouth_is_doubled_and_only_the_tip_is_a_tip(n):
    d, xy, tri, layout = level(n)
    crack_edges = 2 << n
    assert layout.ranges == [(0, crack_edges + 1)]
    assert layout.ends == [(False, True)]
    assert layout.tip_rows().tolist() == [crack_edges]
    assert layout.mouth_rows().tolist() == [0]
    assert xy[layout.tip_vertices()].tolist() == [[0.0, 0.0]]
    plus, minus = layout.pairs[0]
    assert plus != minus and xy[plus].tolist() == xy[minus].tolist() == [-1.0, 0.0]
    # every row but the tip has two copies: the mouth is interior() like an interior node
    assert layout.interior().tolist() == [True] * crack_edges + [False]
    # sides.txt: the mouth's corners are ±1 by face, checked against the copies
    sides = sdexport.read_sides(d / "sides.txt", tri, layout)
    at_minus = tri == minus
    assert at_minus.any() and (sides[at_minus] == -1).all()
    assert (sides[tri == plus] == 1).all()


@pytest.mark.parametrize("n", [0, 1])
def test_boundary_edges_cover_the_square_by_part_and_split_at_the_mouth(n):
    d, xy, tri, layout = level(n)
    edges, parts, names = sdexport.read_boundary_edges(d, len(xy), layout)
    assert names == ["left", "right", "bottom", "top"]
    cells = 4 << n
    assert np.bincount(parts).tolist() == [cells] * 4
    a, b = xy[edges[:, 0]], xy[edges[:, 1]]
    side = {"left": (0, -1.0), "right": (0, 1.0), "bottom": (1, -1.0), "top": (1, 1.0)}
    for k, name in enumerate(names):
        axis, value = side[name]
        assert (a[parts == k, axis] == value).all() and (b[parts == k, axis] == value).all()
    # counter-clockwise: Ω (the origin) on the left of every edge
    cross = (b[:, 0] - a[:, 0]) * (0 - a[:, 1]) - (b[:, 1] - a[:, 1]) * (0 - a[:, 0])
    assert (cross > 0).all()
    # at the mouth: the edge above ends at the + copy, the one below starts at the − copy
    plus, minus = layout.pairs[0]
    assert (edges[:, 1] == plus).sum() == 1 and (edges[:, 0] == minus).sum() == 1
    assert xy[edges[edges[:, 1] == plus][0, 0], 1] > 0
    assert xy[edges[edges[:, 0] == minus][0, 1], 1] < 0
    # boundary.txt lists both copies
    boundary = np.loadtxt(d / "boundary.txt", dtype=np.int64)
    assert plus in boundary and minus in boundary


def damaged(tmp_path, edit):
    """A copy of the export's level 0 with `edit(level_dir)` applied."""
    root = tmp_path / "export"
    shutil.copytree(EXPORT, root)
    edit(root / "level0")
    return root


def rewrite(path, old, new):
    text = path.read_text()
    assert old in text, (path, old)
    path.write_text(text.replace(old, new, 1))


def refused(tmp_path, edit, words, boundary=False):
    d = damaged(tmp_path, edit) / "level0"
    xy = np.loadtxt(d / "vertices.txt", ndmin=2)
    with pytest.raises(sdexport.ExportError) as e:
        layout = sdexport.read_layout(d, xy, len(xy))
        if boundary:
            sdexport.read_boundary_edges(d, len(xy), layout)
    message = str(e.value)
    assert "\n" not in message
    for w in words:
        assert w in message, message


def test_malformed_crack_tables_are_refused(tmp_path):
    # a mouth row made a tip's (plus == minus): the mouth lost its copy
    refused(tmp_path / "a", lambda d: rewrite(d / "crack.txt", "10 25\n", "10 10\n"),
            ["crack.txt", "mouth at row 0", "two copies"])
    # the mouth's end declared a tip: its plus != minus is refused
    refused(tmp_path / "b", lambda d: rewrite(d / "cracks.txt", "0 3 0 1", "0 3 1 1"),
            ["crack.txt", "its tip at row 0"])
    # a tip declared a mouth (plus == minus there)
    refused(tmp_path / "c", lambda d: rewrite(d / "cracks.txt", "0 3 0 1", "0 3 0 0"),
            ["its mouth at row 2 has plus == minus"])
    refused(tmp_path / "d", lambda d: rewrite(d / "cracks.txt", "0 3 0 1", "0 3 0 2"),
            ["cracks.txt", "0 (a mouth) or 1 (a tip)"])
    refused(tmp_path / "e", lambda d: rewrite(d / "cracks.txt", "0 3 0 1", "0 3 0"),
            ["cracks.txt", "line 1 has 3 columns, expected 2 or 4"])


def test_malformed_boundary_edges_are_refused(tmp_path):
    # the mouth's lower edge given the + copy: both faces' edges on one copy
    refused(tmp_path / "a", lambda d: rewrite(d / "boundary_edges.txt", "25 5 0", "10 5 0"),
            ["boundary_edges.txt", "the mouth at crack.txt row 0", "on 2 and 0 boundary edges"],
            boundary=True)
    # an edge listed twice: a vertex starting two edges
    refused(tmp_path / "a2", lambda d: rewrite(d / "boundary_edges.txt", "1 2 2\n", "0 2 2\n"),
            ["boundary_edges.txt", "vertex 0 starts 2 boundary edges"], boundary=True)
    refused(tmp_path / "b", lambda d: rewrite(d / "boundary_edges.txt", "25 5 0", "25 5 4"),
            ["boundary_edges.txt", "part index out of range 0..3"], boundary=True)
    refused(tmp_path / "c", lambda d: rewrite(d / "boundary_edges.txt", "25 5 0", "25 5"),
            ["boundary_edges.txt"], boundary=True)
    refused(tmp_path / "d", lambda d: rewrite(d / "mesh.json", '"left"', '"right"'),
            ["mesh.json", "distinct part names"], boundary=True)
    refused(tmp_path / "e", lambda d: (d / "boundary_edges.txt").unlink(),
            ["missing file", "boundary_edges.txt"], boundary=True)
    # every edge of `top` relabelled `left`: a part with no edge
    def no_top(d):
        p = d / "boundary_edges.txt"
        rows = [line[:-1] + "0" if line.endswith(" 3") else line for line in p.read_text().splitlines()]
        p.write_text("\n".join(rows) + "\n")
    refused(tmp_path / "f", no_top, ["part 'top' has no edge"], boundary=True)
    # the mouth's − copy left off ∂Ω: its lower edge starts at another vertex
    refused(tmp_path / "g", lambda d: rewrite(d / "boundary_edges.txt", "25 5 0", "26 5 0"),
            ["the mouth at crack.txt row 0", "copies 10 and 25"], boundary=True)


def test_scalar_layouts_read_as_before():
    """A layout without ends (every crack end a tip) behaves as before: tips first and last rows."""
    pairs = np.array([[0, 0], [1, 5], [2, 2], [3, 3], [4, 4]])
    layout = sdexport.CrackLayout(pairs=pairs, ranges=[(0, 3), (3, 2)], normals=np.zeros((5, 2)))
    assert layout.tip_rows().tolist() == [0, 2, 3, 4]
    assert layout.mouth_rows().tolist() == []
    assert layout.interior().tolist() == [False, True, False, False, False]
