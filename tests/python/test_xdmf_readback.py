"""Read-back check of the sdcrack field files (fields.h5 + fields.xdmf + fields/<case>.xdmf).

The folder is the one written by the Rust test
`output::xdmf::tests::fixture_for_python_and_h5_readback` with SDCRACK_FIELDS_DIR set:

    SDCRACK_FIELDS_DIR=/tmp/fields cargo test --lib xdmf::tests::fixture_for_python
    SDCRACK_FIELDS_DIR=/tmp/fields /usr/bin/python3 -m pytest tests/python/test_xdmf_readback.py

The tests are skipped when SDCRACK_FIELDS_DIR is unset. The expected values are recomputed here
from the fixture's definition (keep in sync with the Rust test):

* mesh "levelK-P1" (n = 2 for K = 1, n = 4 for K = 2): nodes (i/n, j/n), index j(n+1)+i, two
  triangles per square [a, a+1, a+n+2], [a, a+n+2, a+n+1], a = j(n+1)+i;
* u = s(x + 2y), p = s(xy, x - y) (written with z = 0);
* crack: I = n segments on y = 1/2 from x = 1/4 to 3/4; lambda = s*k per node or s*(k + 1/2) per
  segment.

Also needs meshio and h5py (Debian: python3-meshio, python3-h5py; run with /usr/bin/python3).
"""

import os
import pathlib
import xml.etree.ElementTree as ET

import numpy as np
import pytest

meshio = pytest.importorskip("meshio")
h5py = pytest.importorskip("h5py")

STEM = "fields"
ODD = "odd <&>\"' name"
# name -> (mesh key, n, s, has u, has p, lambda centering or None)
CASES = {
    "level1-P1-P0-delta1e-2": ("level1-P1", 2, 1.0, True, True, "Cell"),
    "level2-P1-P1-delta1.5e-2": ("level2-P1", 4, 2.0, True, True, "Node"),
    ODD: ("level1-P1", 2, 3.0, True, False, None),
}


@pytest.fixture
def folder():
    d = os.environ.get("SDCRACK_FIELDS_DIR")
    if not d:
        pytest.skip("SDCRACK_FIELDS_DIR is not set")
    return pathlib.Path(d)


def square_mesh(n):
    pts = np.array(
        [[i / n, j / n, 0.0] for j in range(n + 1) for i in range(n + 1)], dtype=float
    )
    tris = []
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i
            tris.append([a, a + 1, a + n + 2])
            tris.append([a, a + n + 2, a + n + 1])
    return pts, np.array(tris, dtype=np.int64)


def expected(name):
    key, n, s, has_u, has_p, centering = CASES[name]
    pts, tris = square_mesh(n)
    x, y = pts[:, 0], pts[:, 1]
    point_data = {}
    if has_u:
        point_data["u"] = s * (x + 2 * y)
    if has_p:
        point_data["p"] = np.stack([s * x * y, s * (x - y), np.zeros_like(x)], axis=1)
    k = np.arange(n + 1)
    crack = np.stack([0.25 + 0.5 * k / n, np.full(n + 1, 0.5), np.zeros(n + 1)], axis=1)
    segs = np.stack([np.arange(n), np.arange(1, n + 1)], axis=1)
    lam = None
    if centering == "Node":
        lam = s * k.astype(float)
    elif centering == "Cell":
        lam = s * (np.arange(n) + 0.5)
    return dict(
        key=key, pts=pts, tris=tris, point_data=point_data, crack=crack, segs=segs,
        centering=centering, lam=lam,
    )


@pytest.mark.parametrize("name", sorted(CASES))
def test_meshio_reads_case_grid(folder, name):
    e = expected(name)
    m = meshio.read(folder / STEM / f"{name}.xdmf")
    np.testing.assert_allclose(m.points, e["pts"], rtol=0, atol=1e-15)
    assert [c.type for c in m.cells] == ["triangle"]
    np.testing.assert_array_equal(m.cells[0].data, e["tris"])
    assert sorted(m.point_data) == sorted(e["point_data"])
    for k, v in e["point_data"].items():
        np.testing.assert_allclose(m.point_data[k], v, rtol=1e-15, atol=1e-15)
    assert not m.cell_data


@pytest.mark.parametrize("name", sorted(CASES))
def test_meshio_reads_crack_grid(folder, name):
    e = expected(name)
    m = meshio.read(folder / STEM / f"{name}.crack.xdmf")
    np.testing.assert_allclose(m.points, e["crack"], rtol=0, atol=1e-15)
    assert [c.type for c in m.cells] == ["line"]
    np.testing.assert_array_equal(m.cells[0].data, e["segs"])
    if e["centering"] == "Node":
        np.testing.assert_allclose(m.point_data["lambda"], e["lam"], rtol=1e-15)
        assert not m.cell_data
    elif e["centering"] == "Cell":
        assert len(m.cell_data["lambda"]) == 1
        np.testing.assert_allclose(m.cell_data["lambda"][0], e["lam"], rtol=1e-15)
        assert not m.point_data
    else:
        assert not m.point_data and not m.cell_data


def test_main_xdmf_references_h5(folder):
    """Every grid of fields.xdmf exists, and every DataItem names an existing h5 dataset."""
    root = ET.parse(folder / f"{STEM}.xdmf").getroot()
    assert root.tag == "Xdmf" and root.attrib["Version"] == "3.0"
    (domain,) = list(root)
    (coll,) = list(domain)
    assert coll.attrib["GridType"] == "Collection"
    assert coll.attrib["CollectionType"] == "Spatial"
    names = [g.attrib["Name"] for g in coll]
    want = []
    for n in CASES:
        want += [n, f"{n}/crack"]
    assert names == want
    with h5py.File(folder / f"{STEM}.h5", "r") as f:
        for item in root.iter("DataItem"):
            assert item.attrib["Format"] == "HDF"
            fname, path = item.text.strip().split(":")
            assert fname == f"{STEM}.h5"
            dims = tuple(int(d) for d in item.attrib["Dimensions"].split())
            assert f[path].shape == dims, path
        # each mesh once, only the used ones
        assert sorted(f["meshes"]) == ["level1-P1", "level2-P1"]
        for name in CASES:
            e = expected(name)
            g = f["cases"][name]
            np.testing.assert_array_equal(g["mesh/points"][()], e["pts"])
            np.testing.assert_array_equal(g["mesh/triangles"][()], e["tris"])
            for k, v in e["point_data"].items():
                np.testing.assert_allclose(g[k][()], v, rtol=1e-15, atol=1e-15)
            np.testing.assert_allclose(g["crack/points"][()], e["crack"], atol=1e-15)
            np.testing.assert_array_equal(g["crack/segments"][()], e["segs"])
            if e["lam"] is None:
                assert "lambda" not in g["crack"]
            else:
                np.testing.assert_allclose(g["crack/lambda"][()], e["lam"], rtol=1e-15)


def test_main_xdmf_grids_match_per_case_files(folder):
    """The grids of fields.xdmf are those of the per-case files up to the h5 path prefix."""
    root = ET.parse(folder / f"{STEM}.xdmf").getroot()
    grids = {g.attrib["Name"]: g for g in root.iter("Grid") if "GridType" in g.attrib
             and g.attrib["GridType"] == "Uniform"}
    for name in CASES:
        for gname, fname in [(name, f"{name}.xdmf"), (f"{name}/crack", f"{name}.crack.xdmf")]:
            sub = ET.parse(folder / STEM / fname).getroot()
            (dom,) = list(sub)
            (g,) = list(dom)
            assert g.attrib["Name"] == gname
            a = [i.text.strip() for i in grids[gname].iter("DataItem")]
            b = [i.text.strip() for i in g.iter("DataItem")]
            assert b == ["../" + t for t in a]


if __name__ == "__main__":
    import sys

    sys.exit(pytest.main([__file__, "-v"]))
