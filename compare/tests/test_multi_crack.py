"""The compare tool on the polyline-crack export format: several polyline cracks and uniformly refined meshes.

Meshes come from references/tests/fake_export.py (a kinked crack and a straight one on a structured
grid; a perturbed coarse triangulation refined uniformly, triangle 4t + c inside t). Checked here:
prolongation from a coarse level locates the fine triangles by t // 4^k on refined meshes and is exact
for nested P1 fields (and refuses a shuffled triangle order); crack norms and exact-error integrals run
over the segments within each crack only and grade toward the tips of every crack (a triangle with
two tips included); the scene's cracks are read in the old and the new TOML syntax; the mesh export's
kind reaches the prolongation through load_export_meshes and the solver-vs-reference rows.

Run: /usr/bin/python3 -m pytest compare/tests/test_multi_crack.py -q
"""
import math
import os

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

import fake_export as fe
from sdcompare_lib import exact as E
from sdcompare_lib import checks, norms, read, verdict


def linear(p):
    return 1.0 + 2.0 * p[:, 0] - 3.0 * p[:, 1]


def export_level(export, level):
    """(points, triangles) of the cracked mesh of an export level."""
    d = export / f"level{level}"
    return np.loadtxt(d / "vertices.txt"), np.loadtxt(d / "triangles.txt", dtype=np.int64)


@pytest.fixture(scope="module")
def refined(tmp_path_factory):
    return fe.refined_export(tmp_path_factory.mktemp("refined") / "mesh", "refined", "0", "0", levels=(0, 1, 2))


@pytest.fixture(scope="module")
def two_cracks(tmp_path_factory):
    return fe.two_cracks_export(tmp_path_factory.mktemp("two") / "mesh", "two", "0", "0", levels=(0, 1))


# ---- prolongation on refined meshes ---------------------------------------------------------------

def brute_force_owner(cp, ct, q):
    """The coarse triangle containing each point q (by barycentrics, no numbering assumed)."""
    a, b, c = cp[ct[:, 0]], cp[ct[:, 1]], cp[ct[:, 2]]
    det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    r = q[:, None, :] - a[None]
    l1 = (r[..., 0] * (c[:, 1] - a[:, 1]) - r[..., 1] * (c[:, 0] - a[:, 0])) / det
    l2 = ((b[:, 0] - a[:, 0]) * r[..., 1] - (b[:, 1] - a[:, 1]) * r[..., 0]) / det
    inside = (l1 > 0) & (l2 > 0) & (l1 + l2 < 1)
    assert (inside.sum(axis=1) == 1).all()
    return inside.argmax(axis=1)


def test_refined_prolongation_is_exact(refined):
    """A coarse P1 field evaluated at the fine corners (kind "refined", t_coarse = t_fine // 16 two
    levels down) is the field itself: a linear field to ≤ 1e-14 at every fine vertex, a field broken
    across the crack (random vertex values, + and − copies apart) as located by brute force."""
    cp, ct = export_level(refined, 0)
    fp, ft = export_level(refined, 2)
    vals = norms.prolong_to_fine(cp, ct, linear(cp), fp, ft, kind="refined", refinements=2)
    assert np.abs(vals - linear(fp)[ft]).max() <= 1e-14
    assert norms.prolonged_l2_diff(cp, ct, linear(cp), fp, ft, linear(fp), "refined", 2) <= 1e-14
    broken = np.random.default_rng(1).normal(size=len(cp))
    got = norms.prolong_to_fine(cp, ct, broken, fp, ft, kind="refined", refinements=2)
    owner = brute_force_owner(cp, ct, fp[ft].mean(axis=1))
    np.testing.assert_array_equal(owner, np.arange(len(ft)) // 16)
    vc = broken[ct[owner]]  # (T, 3): the owner's own corner values, so each side keeps its copy
    lam = norms._barycentrics(cp, ct, owner, fp[ft])
    np.testing.assert_allclose(got, np.einsum("tkm,tm->tk", lam, vc), atol=1e-14)
    # vector fields (p) too
    vec = np.stack([linear(cp), -linear(cp)], axis=1)
    got = norms.prolong_to_fine(cp, ct, vec, fp, ft, kind="refined", refinements=2)
    assert np.abs(got[..., 0] - linear(fp)[ft]).max() <= 1e-14 and np.abs(got[..., 1] + linear(fp)[ft]).max() <= 1e-14


def test_refined_prolongation_refuses_a_shuffled_order(refined):
    """Fine triangles not in the 4t + c order, a wrong number of refinements, or the structured
    locator on an unstructured mesh: each a NormError, never silently wrong values."""
    cp, ct = export_level(refined, 0)
    fp, ft = export_level(refined, 2)
    shuffled = ft[np.random.default_rng(0).permutation(len(ft))]
    with pytest.raises(norms.NormError, match="does not lie in coarse triangle"):
        norms.prolong_to_fine(cp, ct, linear(cp), fp, shuffled, kind="refined", refinements=2)
    with pytest.raises(norms.NormError, match="uniform refinement"):
        norms.prolong_to_fine(cp, ct, linear(cp), fp, ft, kind="refined", refinements=1)
    with pytest.raises(norms.NormError, match="structured"):
        norms.prolong_to_fine(cp, ct, linear(cp), fp, ft, kind="structured")
    with pytest.raises(norms.NormError, match="unknown mesh kind"):
        norms.prolong_to_fine(cp, ct, linear(cp), fp, ft, kind="gmsh")


# ---- crack norms over several cracks --------------------------------------------------------------

TWO = np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0], [3.0, 2.0]])  # crack 1: nodes 0-2, crack 2: 2 more
TWO_SEGMENTS = np.array([[0, 1], [1, 2], [3, 4]])


def test_crack_norms_use_only_segments_within_each_crack():
    """Crack 0: (0,0)-(1,0)-(3,0); crack 1: (3,2)-(3,5). Consecutive points would add a segment
    (3,0)-(3,2) of length 2 between the cracks."""
    pts = np.vstack([TWO, [[3.0, 5.0]]])
    lam_p0 = np.array([1.0, 2.0, 3.0])
    assert norms.crack_l2_norm(pts, lam_p0, TWO_SEGMENTS) == pytest.approx(math.sqrt(1 + 2 * 4 + 3 * 9))
    assert norms.crack_integral(pts, lam_p0, TWO_SEGMENTS) == pytest.approx(1 + 4 + 9)
    lam_p1 = pts[:, 0] + pts[:, 1]  # x + y: ∫ λ² on crack 0 = ∫_0^3 x² dx = 9, on crack 1 ∫_2^5 (3 + y)² dy = 129
    assert norms.crack_l2_norm(pts, lam_p1, TWO_SEGMENTS) == pytest.approx(math.sqrt(9 + 129), rel=1e-14)
    # joined (no segments: consecutive points) adds ∫_0^2 (3 + y)² dy = 98/3 on the gap
    assert norms.crack_l2_norm(pts, lam_p1) == pytest.approx(math.sqrt(9 + 129 + 98 / 3), rel=1e-14)
    assert norms.crack_integral(pts, lam_p1, TWO_SEGMENTS) == pytest.approx(4.5 + 19.5, rel=1e-14)
    assert norms.segment_lengths(pts, TWO_SEGMENTS).tolist() == [1.0, 2.0, 3.0]
    # P0 λ against P1 nodal values: exact per segment, only within the cracks
    nodal = np.zeros(len(pts))
    assert norms.crack_diff_vs_p1(pts, lam_p0, nodal, TWO_SEGMENTS) == pytest.approx(math.sqrt(1 + 8 + 27))
    assert norms.crack_l2_diff(pts, lam_p1, lam_p1 + 1, TWO_SEGMENTS) == pytest.approx(math.sqrt(6))
    with pytest.raises(norms.NormError):
        norms.crack_l2_norm(pts, np.ones(4), TWO_SEGMENTS)  # neither per segment (3) nor per node (5)


def test_p1_field_errors_integrate_each_crack(two_cracks):
    """A zero field on the two-crack mesh against [u] = 1 + x + 2y: lambda_l2 is its L² norm over
    the two cracks (cracks.txt's ranges); read as one crack (no ranges) it is not."""
    pts, tris = export_level(two_cracks, 1)
    m = read.load_export_meshes(str(two_cracks), [1])[1]
    ex = E.ExactSolution("0", jump="1 + x + 2*y", f="0")
    expected = math.sqrt(sum(fe.polyline_l2_sq(p, 1, 1, 2) for p in (fe.KINK, fe.STRAIGHT)))
    got = E.p1_field_errors(pts, tris, np.zeros(len(pts)), m.crack, ex, ranges=m.ranges)
    assert got["u_l2"] == 0 and got["lambda_l2"] == pytest.approx(expected, rel=1e-13)
    joined = E.p1_field_errors(pts, tris, np.zeros(len(pts)), m.crack, ex)
    assert abs(joined["lambda_l2"] - expected) > 0.1


def test_solver_case_errors_with_crack_segments(two_cracks):
    """λ_h per segment (P0, in the order of crack/segments) or per node against the jump 1 + x + 2y:
    the segments decide which pieces of Γc are integrated (the two cracks', tips graded)."""
    pts, tris = export_level(two_cracks, 1)
    m = read.load_export_meshes(str(two_cracks), [1])[1]
    cp = pts[m.crack[:, 0]]
    seg = m.segments()
    ex = E.ExactSolution("0", jump="1 + x + 2*y", f="0")
    g = 1 + cp[:, 0] + 2 * cp[:, 1]
    node = E.solver_case_errors(pts, tris, None, None, None, cp, g, ex, crack_segments=seg)
    assert node["lambda_l2"] < 1e-13  # P1 λ = the linear jump exactly
    mid = g[seg].mean(axis=1)
    p0 = E.solver_case_errors(pts, tris, None, None, None, cp, mid, ex, crack_segments=seg)
    ell = np.linalg.norm(cp[seg[:, 1]] - cp[seg[:, 0]], axis=1)
    dg = g[seg[:, 1]] - g[seg[:, 0]]
    assert p0["lambda_l2"] == pytest.approx(math.sqrt(np.sum(ell * dg ** 2 / 12)), rel=1e-12)
    with pytest.raises(E.ExactError, match="values for"):
        E.solver_case_errors(pts, tris, None, None, None, cp, g[:-1], ex, crack_segments=seg)
    with pytest.raises(E.ExactError, match="polylines"):
        E.solver_case_errors(pts, tris, None, None, None, cp, g, ex, crack_segments=seg[1:])


# ---- tips of every crack --------------------------------------------------------------------------

def test_triangles_with_two_tips_are_graded_toward_both():
    """A crack of one edge (both tips in the same triangles), r^(1/2) and r^(-1/2) at its two tips:
    the batches tile the mesh and the integral is converged (doubling the rule changes < 1e-10)."""
    xy, tri = fe.structured_level(4)
    tips = [np.array([-0.5, 0.0]), np.array([0.0, 0.0])]

    def integrate(quad):
        area_sum = value = 0.0
        X = xy[tri]
        e1, e2 = X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]
        area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
        for ids, L, W in E._point_batches(xy, tri, tips, quad):
            w = np.broadcast_to(W, L.shape[:-1]) * area[ids][:, None]
            p = L @ X[ids]
            r1, r2 = (np.hypot(p[..., 0] - t[0], p[..., 1] - t[1]) for t in tips)
            area_sum += w.sum()
            value += (w * (np.sqrt(r1) + 1 / np.sqrt(r2))).sum()
        return area_sum, value

    area, v1 = integrate(E.Quadrature())
    _, v2 = integrate(E.Quadrature().doubled())
    assert area == pytest.approx(4.0, rel=1e-14) and abs(v1 - v2) < 1e-10 * v2


def test_tips_of_every_crack_from_the_scene():
    """Scenes in the new syntax (cracks = [{polyline}, {segment}]) and the old (crack = {segment}):
    the tips (used without crack data) are the ends of each polyline."""
    new = {"exact": {"u": "x"}, "geometry": {"cracks": [{"polyline": fe.KINK}, {"segment": fe.STRAIGHT}]}}
    ex = E.ExactSolution.from_scene(new)
    assert [c.shape for c in ex.cracks] == [(3, 2), (2, 2)]
    old = E.ExactSolution.from_scene({"exact": {"u": "x"}, "geometry": {"crack": {"segment": [[-0.5, 0], [0.5, 0]]}}})
    assert len(old.cracks) == 1 and old.cracks[0].tolist() == [[-0.5, 0.0], [0.5, 0.0]]
    _, _, tips = E._crack_geometry(None, None, ex)
    assert np.array(tips).tolist() == [list(fe.KINK[0]), list(fe.KINK[-1]), list(fe.STRAIGHT[0]), list(fe.STRAIGHT[-1])]
    bad = {"exact": {"u": "x"}, "geometry": {"cracks": [{"polyline": fe.KINK}, {"segment": [[0, 0]]}]}}
    with pytest.raises(E.ExactError, match="crack 1"):
        E.scene_cracks(bad)
    with pytest.raises(read.InputError, match=r"^R/scene.toml: \[geometry\] crack 1 is not"):  # exit 2
        checks.independent_errors({"folder": "R"}, bad)


def test_jump_from_the_faces_uses_each_segment_normal():
    """Without exact.jump, [u] = u⁺ − u⁻ with the signed-zero rule and the normal of the segment the
    point lies on: u = sign(y) jumps by 2 across y = 0 seen from +y; sign(x) by −2 across x = 0 for
    a segment going up (ν = (−1, 0))."""
    ex = E.ExactSolution("sign(y) + sign(x)", f="0")
    pts = np.array([[-0.5, 0.0], [0.0, 0.0], [0.0, 0.5]])  # along y = 0, then up x = 0
    segs = np.array([[0, 1], [1, 2]])
    err = E.solver_case_errors(pts, np.array([[0, 1, 2]]), None, None, None, pts, np.array([2.0, -2.0]), ex,
                               crack_segments=segs)
    assert err["lambda_l2"] == pytest.approx(0.0, abs=1e-14)


# ---- the export's kind through load_export_meshes and the reference rows --------------------------

def test_load_export_meshes_reads_kind_and_cracks(refined, two_cracks, tmp_path):
    m = read.load_export_meshes(str(refined), [0, 2])
    assert sorted(m) == [0, 2] and m[2].kind == "refined" and m[2].ranges == [(0, 9)]
    t = read.load_export_meshes(str(two_cracks), [1])[1]
    assert t.kind == "structured" and [n for _, n in t.ranges] == [7, 7] and len(t.segments()) == 12
    bad = tmp_path / "bad"
    fe.two_cracks_export(bad, "two", "0", "0", levels=(0,))
    (bad / "level0" / "cracks.txt").write_text("0 4\n4 3\n")
    with pytest.raises(read.InputError, match="cracks.txt.*cover"):
        read.load_export_meshes(str(bad), [0])


def write_fields(path, export, levels):
    """A fields.h5 with one broken case per level of the export: u the linear field at the cracked
    vertices, λ = 0 per node, crack/points and crack/segments as the solver writes them."""
    import h5py

    cases = []
    with h5py.File(path, "w") as h5:
        for lv in levels:
            pts, tris = export_level(export, lv)
            m = read.load_export_meshes(str(export), [lv])[lv]
            key, grid = f"level{lv}-broken", f"level{lv}-broken-M1-delta0"
            h5[f"meshes/{key}/points"] = np.column_stack([pts, np.zeros(len(pts))])
            h5[f"meshes/{key}/triangles"] = tris
            g = h5.create_group(f"cases/{grid}")
            g["mesh"] = h5py.SoftLink(f"/meshes/{key}")
            g["u"] = linear(pts)
            g["crack/points"] = np.column_stack([pts[m.crack[:, 0]], np.zeros(len(m.crack))])
            g["crack/segments"] = m.segments()
            g["crack/lambda"] = np.zeros(len(m.crack))
            cases.append({"level": lv, "u_space": "broken", "multiplier": "M1", "delta": 0.0,
                          "fields_grid": grid})
    return cases


def test_reference_rows_prolong_by_the_export_kind(refined, tmp_path):
    """_solver_vs_reference on the refined export: the same-level distances and the distance to the
    finest level (located by 4t + c, read from mesh.json) vanish for the nested linear field; with
    the finest level's triangles shuffled the row says why instead."""
    cases = write_fields(tmp_path / "fields.h5", refined, [0, 1, 2])
    ref = {"u": {lv: linear(export_level(refined, lv)[0]) for lv in (0, 1, 2)},
           "mesh": read.load_export_meshes(str(refined), [0, 1, 2])}
    import h5py

    def rows_of(cases, ref):
        fields = read.Fields(str(tmp_path / "fields.h5"))
        try:
            return verdict._solver_vs_reference("refined", cases, fields, ref, "dolfinx")
        finally:
            fields.close()

    rows = rows_of(cases, ref)
    assert [r["level"] for r in rows] == [0, 1, 2] and all(r["note"] == "" for r in rows), rows
    for r in rows:
        assert r["e_u"] <= 1e-14 and r["e_u_finest"] <= 1e-14 and r["e_lambda"] == 0.0
    fine = ref["mesh"][2]
    perm = np.random.default_rng(2).permutation(len(fine.tris))
    shuffled = dict(ref, mesh=dict(ref["mesh"]))
    shuffled["mesh"][2] = read.ExportLevel(2, fine.points, fine.tris[perm], fine.crack, fine.ranges, fine.kind)
    (row,) = rows_of(cases[:1], shuffled)
    assert "does not lie in coarse triangle" in row["note"] and "e_u_finest" not in row
    with h5py.File(tmp_path / "fields.h5", "r+") as h5:
        h5[f"cases/{cases[0]['fields_grid']}/crack/segments"][0] = [1, 0]
    (row,) = rows_of(cases[:1], ref)
    assert "crack segments are not the mesh export's" in row["note"]
