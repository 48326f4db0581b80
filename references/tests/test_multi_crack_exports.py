"""The polyline-crack export format (several polyline cracks, uniformly refined meshes) in both references.

Fake exports (tests/fake_export.py): a kinked crack on a structured grid (grid line, then a cell
diagonal), two cracks (that kink and a straight one), two parallel cracks one cell apart, and a
"refined" mesh (a perturbed coarse triangulation refined uniformly, triangle 4t + c in t). On each:
compare/sdshared/sdexport.py reads and checks the crack files (one-line errors naming the file and
the crack); both references solve with partial contact and agree to <= 1e-8 at every vertex; a smooth
exact u whose ∂u/∂ν < 0 on every segment (so that every crack node closes and u is also the limit of
the discrete contact problem) converges at the P1 rates (u: >= 1.8, ∇u: >= 0.9; measured 1.97, 0.99);
the jump norm runs over the segments within each crack only; the crack field files have one line cell
per such segment.

Run: /usr/bin/python3 -m pytest references/tests/test_multi_crack_exports.py -q
"""

import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
import fake_export as fe
from sdshared import sdexport
from sdshared import sdexpr
from output_checks import assert_fields_readable, load_module



dxsolve = load_module("dolfinx_solve_multi", HERE.parent / "dolfinx" / "solve.py")
ffsolve = load_module("freefem_solve_multi", HERE.parent / "freefem" / "solve.py")

# closed: u smooth, −Δu = f, ∂u/∂ν < −1 on every segment of every crack below (the linear part gives
# ≤ −2.75, the sine part at most π/2; test_exact_u_pushes_every_crack_closed), so [u] = 0 and
# λ = −∂u/∂ν > 0 everywhere
CLOSED_U = "0.5*sin(pi*x)*cos(pi*y) + x - 3*y"
CLOSED_F = "pi^2*sin(pi*x)*cos(pi*y)"
MIXED_F = "20*sin(2*pi*x)"  # with g = 0: the cracks open in part and close in part
PARALLEL = ([(-0.5, 0.0), (0.5, 0.0)], [(-0.5, 0.25), (0.5, 0.25)])  # one cell apart at n0 = 8

EXPORTS = {
    "kinked": lambda out, f, g, exact, levels: fe.kinked_export(out, "kinked", f, g, exact, levels),
    "two-cracks": lambda out, f, g, exact, levels: fe.two_cracks_export(out, "two-cracks", f, g, exact, levels),
    "parallel": lambda out, f, g, exact, levels: fe.kinked_export(out, "parallel", f, g, exact, levels,
                                                                  polylines=PARALLEL),
    "refined": lambda out, f, g, exact, levels: fe.refined_export(out, "refined", f, g, exact, levels),
}


def have_dolfinx():
    try:
        import dolfinx  # noqa: F401
    except ImportError:
        return False
    return dxsolve.dolfinx_version_problem() is None


needs_both = pytest.mark.skipif(shutil.which("FreeFem++") is None or not have_dolfinx(),
                                reason="needs FreeFem++ and dolfinx 0.5")


def solve_both(export, out, fields=False):
    """{tool: summary} of both references on `export` (results under out/<tool>)."""
    return {"dolfinx": dxsolve.run(export, out / "dolfinx", fields=fields),
            "freefem": ffsolve.solve(export, out / "freefem", fields=fields)}


def interior_nodes(export, level):
    crack = np.loadtxt(Path(export) / f"level{level}" / "crack.txt", dtype=np.int64, ndmin=2)
    return int(np.sum(crack[:, 0] != crack[:, 1]))


def rates(cases, key):
    e = [c["errors"][key] for c in cases]
    h = [c["h"] for c in cases]
    return [math.log(e[i] / e[i + 1]) / math.log(h[i] / h[i + 1]) for i in range(len(e) - 1)]


def level_layout(export, level):
    d = Path(export) / f"level{level}"
    xy = np.loadtxt(d / "vertices.txt", ndmin=2)
    return d, xy, sdexport.read_layout(d, xy, len(xy))


# ---- the format and its reader ---------------------------------------------------------------------

@pytest.mark.parametrize("name", sorted(EXPORTS))
def test_sdexport_reads_the_new_format(tmp_path, name):
    export = EXPORTS[name](tmp_path / "e", "0", "0", None, (0, 1, 2))
    scene = json.loads((export / "scene.json").read_text())
    polylines = sdexport.scene_cracks(scene)
    assert ("crack" in scene) == (len(polylines) == 1 and len(polylines[0]) == 2)
    previous = None
    for level in (0, 1, 2):
        d, xy, layout = level_layout(export, level)
        meta = sdexport.read_mesh_json(d)
        assert sdexport.read_kind(meta, d / "mesh.json") == ("refined" if name == "refined" else "structured")
        assert layout.n_cracks == len(polylines) == meta["n_cracks"]
        for (first, n), polyline in zip(layout.ranges, polylines):
            nodes = xy[layout.pairs[first:first + n, 0]]
            np.testing.assert_array_equal(nodes[[0, -1]], np.asarray(polyline)[[0, -1]])  # tips, in order
        if previous is not None:  # each level halves every crack edge
            assert [n for _, n in layout.ranges] == [2 * n - 1 for _, n in previous.ranges]
        previous = layout
        assert len(layout.segments()) == len(layout.pairs) - layout.n_cracks
        tri = np.loadtxt(d / "triangles.txt", dtype=np.int64)
        sides = sdexport.read_sides(d / "sides.txt", tri, layout)
        assert sides.shape == tri.shape and set(np.unique(sides)) == {-1, 0, 1}
        # the kink's normal bisects the two segments' normals (length-weighted: equal lengths here)
        if name == "kinked":
            kink = int(np.flatnonzero(np.all(xy[layout.pairs[:, 0]] == [0.0, -0.25], axis=1))[0])
            nu = layout.normals[kink]
            assert nu[0] < 0 < nu[1] and abs(np.hypot(*nu) - 1) < 1e-15


def test_refined_export_nests_4t_plus_c(tmp_path):
    """Children c = 0, 1, 2 of triangle t share its corner c; every child lies inside its parent."""
    export = fe.refined_export(tmp_path / "e", "r", "0", "0", levels=(0, 1, 2))
    for level in (1, 2):
        xc = np.loadtxt(export / f"level{level - 1}" / "vertices_uncut.txt")
        tc = np.loadtxt(export / f"level{level - 1}" / "triangles_uncut.txt", dtype=np.int64)
        xf = np.loadtxt(export / f"level{level}" / "vertices_uncut.txt")
        tf = np.loadtxt(export / f"level{level}" / "triangles_uncut.txt", dtype=np.int64)
        assert len(tf) == 4 * len(tc)
        for c in range(3):
            np.testing.assert_array_equal(xf[tf[c::4, c]], xc[tc[:, c]])
        np.testing.assert_allclose(xf[tf[3::4]].mean(axis=1), xc[tc].mean(axis=1), atol=1e-15)
        assert sdexport.read_kind(json.loads((export / f"level{level}" / "mesh.json").read_text()),
                                  "mesh.json") == "refined"


def test_old_export_reads_as_one_crack_with_the_scene_normal(tmp_path):
    export = fe.write_fake_export(tmp_path / "e", "old", "0", "0", levels=(0,))
    d, xy, _ = level_layout(export, 0)
    layout = sdexport.read_layout(d, xy, len(xy), default_normal=[0.0, 1.0])
    assert layout.ranges == [(0, len(layout.pairs))] and (layout.normals == [0.0, 1.0]).all()
    tri = np.loadtxt(d / "triangles.txt", dtype=np.int64)
    sides = sdexport.read_sides(d / "sides.txt", tri, layout)  # one value per triangle, spread to corners
    assert sides.shape == tri.shape and sdexport.read_kind({}, d / "mesh.json") == "structured"


def _rewrite(path, transform):
    path.write_text(transform(path.read_text()))


def _damages():
    """name: (file to damage under level0, edit of its text, words the one-line error must contain)."""
    def swap_tip(text):  # the second crack's last row: plus != minus
        rows = text.splitlines()
        p, _ = rows[7].split()
        rows[7] = f"{p} 0"
        return "\n".join(rows) + "\n"
    return {
        "cracks.txt short": ("cracks.txt", lambda t: t.splitlines()[0] + "\n", ["cracks.txt", "cover"]),
        "cracks.txt gap": ("cracks.txt", lambda t: t.replace("4 4", "5 3"), ["cracks.txt", "crack 1", "starts"]),
        "crack of one node": ("cracks.txt", lambda t: "0 4\n4 1\n5 3\n", ["cracks.txt", "crack 1", "node"]),
        "tip with two copies": ("crack.txt", swap_tip, ["crack.txt", "crack 1", "tip"]),
        "flipped normal": ("crack_normals.txt", lambda t: "\n".join(
            " ".join(str(-float(v)) for v in r.split()) for r in t.splitlines()) + "\n",
            ["crack_normals.txt", "crack 0", "normal"]),
        "normals missing a row": ("crack_normals.txt", lambda t: "\n".join(t.splitlines()[1:]) + "\n",
                                  ["crack_normals.txt", "rows"]),
        "sides of the wrong face": ("sides.txt", lambda t: t.replace("-1", "X").replace("1", "-1").replace("X", "1"),
                                    ["sides.txt", "triangle"]),
        "unknown kind": ("mesh.json", lambda t: t.replace('"structured"', '"gmsh"'), ["mesh.json", "kind"]),
    }


@pytest.mark.parametrize("damage", sorted(_damages()))
def test_malformed_crack_files_are_one_line_errors(tmp_path, damage):
    name, edit, words = _damages()[damage]
    export = fe.two_cracks_export(tmp_path / "e", "two", "0", "0", levels=(0,))
    d = export / "level0"
    _rewrite(d / name, edit)
    with pytest.raises(sdexport.ExportError) as err:
        xy = np.loadtxt(d / "vertices.txt")
        layout = sdexport.read_layout(d, xy, len(xy))
        sdexport.read_sides(d / "sides.txt", np.loadtxt(d / "triangles.txt", dtype=np.int64), layout)
        sdexport.read_kind(sdexport.read_mesh_json(d), d / "mesh.json")
    msg = str(err.value)
    assert "\n" not in msg and all(w in msg for w in words), msg


def test_refined_level_with_the_wrong_triangle_count_is_an_error(tmp_path):
    export = fe.refined_export(tmp_path / "e", "r", "0", "0", levels=(0, 1))
    meta = json.loads((export / "level1" / "mesh.json").read_text())
    meta["coarse_triangles"] += 1
    with pytest.raises(sdexport.ExportError, match="refinement of 33 coarse triangles"):
        sdexport.read_kind(meta, "level1/mesh.json")


def test_solvers_report_a_malformed_export_in_one_line(tmp_path):
    """Both references' readers fail alike, naming the file and the crack (their command lines turn
    a SolveError into exit status 1 and one line on stderr)."""
    export = fe.two_cracks_export(tmp_path / "e", "two", "0", "0", levels=(0,))
    _rewrite(export / "level0" / "crack.txt", _damages()["tip with two copies"][1])
    for module in (ffsolve, dxsolve):
        with pytest.raises(module.SolveError) as err:
            module.read_level(export, 0)
        msg = str(err.value)
        assert "crack.txt" in msg and "crack 1" in msg and "\n" not in msg, (module.__name__, msg)


def test_side_points_on_each_face():
    """u_exact at crack copies (dolfinx --fields): signed zero on a coordinate axis when ν is along
    the other axis, a push of 1e-13 along ±ν elsewhere."""
    xy = np.array([[0.3, 0.0], [0.3, 0.0], [0.0, 0.4], [0.0, 0.4], [0.2, 0.2], [0.5, 0.5]])
    side = np.array([1, -1, 1, -1, -1, 0])
    s = 0.5 ** 0.5
    normal = np.array([[0.0, 1.0], [0.0, 1.0], [-1.0, 0.0], [-1.0, 0.0], [-s, s], [0.0, 0.0]])
    x, y = dxsolve.side_points(xy, side, normal)
    assert math.copysign(1, y[0]) == 1 and math.copysign(1, y[1]) == -1 and x[0] == x[1] == 0.3
    assert math.copysign(1, x[2]) == -1 and math.copysign(1, x[3]) == 1 and y[2] == y[3] == 0.4
    assert abs(x[4] - 0.2 - 1e-13 * s) < 1e-16 and abs(y[4] - 0.2 + 1e-13 * s) < 1e-16
    assert (x[5], y[5]) == (0.5, 0.5)


def test_freefem_regions_of_close_cracks(tmp_path):
    """Triangles between two parallel cracks one cell apart use the − copy of one crack's nodes and
    the + copy of the other's: a third FreeFEM region, whose map agrees with its triangles."""
    export = EXPORTS["parallel"](tmp_path / "e", "0", "0", None, (0,))
    lv = ffsolve.read_level(export, 0)
    region, maps = ffsolve.regions_and_maps(lv)
    assert maps.shape[0] == 3 and set(np.unique(region)) == {1, 2, 3}
    for t, r in enumerate(region):
        np.testing.assert_array_equal(maps[r - 1][lv["tri_uncut"][t]], lv["tri"][t])
    one = ffsolve.regions_and_maps(ffsolve.read_level(EXPORTS["two-cracks"](tmp_path / "t", "0", "0", None, (0,)), 0))
    assert one[1].shape[0] == 2  # separated cracks: the usual two regions


def test_exact_u_pushes_every_crack_closed(tmp_path):
    """∂u/∂ν < 0 at 20 points of every segment of every crack of every fake (ν the segment's
    normal): the contact problem's solution is the smooth u, every crack closed."""
    px = sdexpr.to_numpy(sdexpr.derivative(CLOSED_U, "x"))
    py = sdexpr.to_numpy(sdexpr.derivative(CLOSED_U, "y"))
    s = np.linspace(0, 1, 20)
    for name, make in EXPORTS.items():
        export = make(tmp_path / name, "0", "0", None, (0,))
        for polyline in sdexport.scene_cracks(json.loads((export / "scene.json").read_text())):
            for a, b in zip(polyline[:-1], polyline[1:]):
                nu = sdexport.segment_normals(np.array([a, b]), np.array([[0, 1]]))[0]
                x, y = a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])
                assert (px(x, y) * nu[0] + py(x, y) * nu[1] < -1.0).all(), (name, a, b)


# ---- both references ---------------------------------------------------------------------------------

@needs_both
@pytest.mark.parametrize("name", sorted(EXPORTS))
def test_references_agree_on_new_exports(tmp_path, name):
    """Partly open, partly closed cracks: converged KKT in both, vertex values within 1e-8."""
    export = EXPORTS[name](tmp_path / "e", MIXED_F, "0", None, (0, 1, 2))
    s = solve_both(export, tmp_path)
    partial = 0
    for d, f in zip(s["dolfinx"]["cases"], s["freefem"]["cases"]):
        assert d["status"] == f["status"] == "converged", (d["status"], f["status"])
        assert d["active"] == f["active"]
        partial += 0 < d["active"] < interior_nodes(export, d["level"])
        ud = np.loadtxt(tmp_path / "dolfinx" / f"u_level{d['level']}.txt")
        uf = np.loadtxt(tmp_path / "freefem" / f"u_level{d['level']}.txt")
        assert ud.shape == uf.shape and np.abs(ud - uf).max() <= 1e-8 * np.abs(uf).max(), (name, d["level"])
    assert partial >= 2, "the contact should be partial on most levels"


@needs_both
def test_closed_exact_solution_converges_on_the_refined_export(tmp_path):
    """Levels 0-3 of the refined fake: every crack node closes, [u_h] = 0, and the errors fall at the
    P1 rates on the last two levels (measured: u 1.97, ∇u 0.99), the same in both references."""
    export = EXPORTS["refined"](tmp_path / "e", CLOSED_F, CLOSED_U, {"u": CLOSED_U}, (0, 1, 2, 3))
    s = solve_both(export, tmp_path)
    for tool, summary in s.items():
        cases = summary["cases"]
        for c in cases:
            assert c["status"] == "converged" and c["active"] == interior_nodes(export, c["level"]), (tool, c)
            assert c["errors"]["lambda_l2"] < 1e-12
        assert rates(cases, "u_l2")[-1] >= 1.8, (tool, rates(cases, "u_l2"))
        assert rates(cases, "p_l2")[-1] >= 0.9, (tool, rates(cases, "p_l2"))
        assert all(a > b for a, b in zip([c["errors"]["u_l2"] for c in cases], [c["errors"]["u_l2"] for c in cases[1:]]))
    for d, f in zip(s["dolfinx"]["cases"], s["freefem"]["cases"]):
        for key in ("u_l2", "p_l2"):
            assert abs(d["errors"][key] - f["errors"][key]) <= 1e-6 * f["errors"][key], (d["level"], key)


@needs_both
def test_jump_norm_runs_over_the_segments_within_each_crack(tmp_path):
    """A closed crack ([u_h] = 0) against a given jump 1 + x + 2y: lambda_l2 is that function's L²
    norm over the two cracks' own segments (dolfinx: UFL facets of the + faces, FreeFEM: numpy),
    not with a segment from the first crack's last tip to the second's first."""
    exact = {"u": CLOSED_U, "jump": "1 + x + 2*y"}
    export = EXPORTS["two-cracks"](tmp_path / "e", CLOSED_F, CLOSED_U, exact, (0, 1))
    expected = math.sqrt(sum(fe.polyline_l2_sq(p, 1, 1, 2) for p in (fe.KINK, fe.STRAIGHT)))
    joined = math.sqrt(fe.polyline_l2_sq(fe.KINK + fe.STRAIGHT, 1, 1, 2))
    assert abs(joined - expected) > 0.1
    s = solve_both(export, tmp_path)
    for tool, summary in s.items():
        for c in summary["cases"]:
            assert c["errors"]["lambda_l2"] == pytest.approx(expected, rel=1e-12), tool


@needs_both
def test_fields_of_several_cracks(tmp_path):
    """--fields on two cracks: the crack grid's lines are the segments within each crack; dolfinx's
    u_exact at the crack copies is u on each face."""
    export = EXPORTS["two-cracks"](tmp_path / "e", CLOSED_F, CLOSED_U, {"u": CLOSED_U}, (0, 1))
    s = solve_both(export, tmp_path, fields=True)
    for tool, summary in s.items():
        assert_fields_readable(tmp_path / tool, export, summary, tool)
