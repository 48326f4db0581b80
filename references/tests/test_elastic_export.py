"""The elastic export stand-in (elastic_export.py) against docs/elasticity.md's export: a mouth's two
copies on ∂Ω with each boundary edge on its own face, tips and mouths flagged in cracks.txt, the
cracked mesh a valid triangulation whose slit opens exactly along the crack."""

import json

import numpy as np
import pytest

from elastic_export import RECTANGLE_PARTS, elastic_export, material
from sdshared import sdexport

GETFEM_DOMAIN = ((0.0, -0.5), (1.0, 0.5))


def level(out, L=0):
    d = out / f"level{L}"
    load = lambda n, t=float: np.loadtxt(d / f"{n}.txt", dtype=t, ndmin=2)  # noqa: E731
    return {"xy": load("vertices"), "tri": load("triangles", int), "crack": load("crack", int),
            "cracks": load("cracks", int), "normals": load("crack_normals"), "edges": load("boundary_edges", int),
            "sides": load("sides", int), "bnd": np.loadtxt(d / "boundary.txt", dtype=int),
            "meta": json.loads((d / "mesh.json").read_text())}


def edge_count(tri):
    """{sorted edge: number of triangles holding it}."""
    count = {}
    for t in tri:
        for a, b in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0])):
            key = (min(a, b), max(a, b))
            count[key] = count.get(key, 0) + 1
    return count


@pytest.mark.parametrize("case", ["edge", "interior", "getfem"])
def test_export_is_a_cracked_triangulation(tmp_path, case):
    crack, domain = {"edge": (((-1.0, 0.0), (0.0, 0.0)), ((-1, -1), (1, 1))),
                     "interior": (((-0.5, -0.25), (0.0, -0.25), (0.25, 0.0)), ((-1, -1), (1, 1))),
                     "getfem": (((0.0, 0.0), (0.5, 0.0)), GETFEM_DOMAIN)}[case]
    out = elastic_export(tmp_path / case, case, material(lam=1.0, mu=1.0), ["0", "0"], g=["0", "0"],
                         levels=(0, 1), n0=8, domain=domain, crack=crack)
    for L in (0, 1):
        lv = level(out, L)
        xy, tri, crack_rows = lv["xy"], lv["tri"], lv["crack"]
        (x0, y0), (x1, y1) = domain
        cross = np.cross(xy[tri[:, 1]] - xy[tri[:, 0]], xy[tri[:, 2]] - xy[tri[:, 0]])
        assert cross.min() > 0 and np.isclose(cross.sum() / 2, (x1 - x0) * (y1 - y0))
        # cracks.txt: first n tip_first tip_last; a tip has plus == minus, any other row plus != minus
        first, n, tip_a, tip_b = lv["cracks"][0]
        mouth = case in ("edge", "getfem")
        assert (first, n, tip_a, tip_b) == (0, len(crack_rows), 0 if mouth else 1, 1)
        same = crack_rows[:, 0] == crack_rows[:, 1]
        assert same.tolist() == [not mouth] + [False] * (n - 2) + [True]
        # normals: sdexport's nodal rule
        assert np.abs(lv["normals"] - sdexport.node_normals(xy[crack_rows[:, 0]], [(0, n)])).max() < 1e-15
        # the slit: every crack segment is a boundary edge on each face, nothing else is open
        # inside Ω; the boundary edges of the cracked mesh are those of ∂Ω and the crack faces
        count = edge_count(tri)
        open_edges = {e for e, c in count.items() if c == 1}
        listed = {(min(a, b), max(a, b)) for a, b, _ in lv["edges"]}
        faces = set()
        for k in range(n - 1):
            for side in (0, 1):
                a, b = crack_rows[k, side], crack_rows[k + 1, side]
                faces.add((min(a, b), max(a, b)))
        assert len(faces) == 2 * (n - 1) and open_edges == listed | faces and not listed & faces
        # boundary_edges.txt: Ω on the left, the part's side, the perimeter covered once
        a, b, part = lv["edges"].T
        mid, d = (xy[a] + xy[b]) / 2, xy[b] - xy[a]
        outward = np.column_stack([d[:, 1], -d[:, 0]])
        centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
        assert (np.einsum("ij,ij->i", outward, mid - centre) > 0).all()
        sides_at = {0: (0, x0), 1: (0, x1), 2: (1, y0), 3: (1, y1)}
        assert all(abs(mid[i, sides_at[p][0]] - sides_at[p][1]) < 1e-14 for i, p in enumerate(part))
        assert np.isclose(np.hypot(*d.T).sum(), 2 * ((x1 - x0) + (y1 - y0)))
        assert lv["meta"]["boundary_parts"] == RECTANGLE_PARTS and lv["meta"]["kind"] == "structured"
        assert lv["bnd"].tolist() == sorted(set(a) | set(b))
        if mouth:  # both copies on ∂Ω, each on the edge of its own face
            plus, minus = crack_rows[0]
            assert plus in lv["bnd"] and minus in lv["bnd"]
            for copy, sign in ((plus, 1), (minus, -1)):
                at = (a == copy) | (b == copy)
                other = np.where(a[at] == copy, b[at], a[at])
                assert len(other) == 1 and np.sign(xy[other[0], 1] - xy[copy, 1]) == sign
        # sides.txt: ±1 exactly at the corners that are + / − copies of a doubled node
        doubled = crack_rows[~same]
        expect = np.zeros_like(tri)
        expect[np.isin(tri, doubled[:, 0])] = 1
        expect[np.isin(tri, doubled[:, 1])] = -1
        assert np.array_equal(lv["sides"], expect) and (expect != 0).any()
    scene = json.loads((out / "scene.json").read_text())
    assert scene["problem"]["kind"] == "elasticity" and scene["g"] == ["0", "0"] and scene["exact"] is None


def test_material_constants():
    m = material(E=1.0, nu=0.3)
    assert abs(m["nu"] - 0.3) < 1e-15 and abs(m["kolosov"] - 1.8) < 1e-15 and m["lambda_in_plane"] == m["lambda"]
    s = material(E=1.0, nu=0.3, plane="stress")
    assert abs(s["lambda_in_plane"] - 0.3 / 0.91) < 1e-14 and abs(s["e_prime"] - 1.0) < 1e-15
    with pytest.raises(ValueError):
        material(E=1.0, nu=0.3, lam=1.0, mu=1.0)
