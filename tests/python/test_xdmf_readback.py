"""Read-back check of the sdcrack field files (fields.h5, the time series
fields/<series>.series.xdmf and the one-state files fields/<case>.xdmf).

The folder is the one written by the Rust test
`output::xdmf::write::tests::fixture_for_python_and_h5_readback` with SDCRACK_FIELDS_DIR set:

    SDCRACK_FIELDS_DIR=/tmp/fields cargo test --lib xdmf::write::tests::fixture_for_python
    SDCRACK_FIELDS_DIR=/tmp/fields /usr/bin/python3 -m pytest tests/python/test_xdmf_readback.py

The tests are skipped when SDCRACK_FIELDS_DIR is unset. The expected values are recomputed here
from the fixture's definition (keep in sync with the Rust test):

* mesh "levelK-P1" (n = 2 for K = 1, n = 4 for K = 2): nodes (i/n, j/n), index j(n+1)+i, two
  triangles per square [a, a+1, a+n+2], [a, a+n+2, a+n+1], a = j(n+1)+i;
* u = s(x + 2y), p = s(xy, x - y) (written with z = 0);
* crack: I = n segments on y = 1/2 from x = 1/4 to 3/4; lambda = s*k per node or s*(k + 1/2) per
  segment, and with lambda jump = s*(n - k) per node (the crack field [u_h] = u+ - u-);
* series (one XDMF temporal collection each, steps in this order): "level1-P1-P0" = the cases
  delta 1e-2 (s = 1) then delta 0 (s = 4); "level2-P1-P1" = delta 1.5e-2 (s = 2); ODD (s = 3, no
  p, no lambda).

Also needs meshio and h5py (Debian: python3-meshio, python3-h5py; run with /usr/bin/python3).
"""

import os
import pathlib
import xml.etree.ElementTree as ET

import numpy as np
import pytest

meshio = pytest.importorskip("meshio")
h5py = pytest.importorskip("h5py")
from meshio.xdmf import TimeSeriesReader  # noqa: E402

STEM = "fields"
ODD = "odd <&>\"' name"
# case name -> (series, delta, mesh key, n, s, has p, lambda centering or None)
CASES = {
    "level1-P1-P0-delta1e-2": ("level1-P1-P0", 1e-2, "level1-P1", 2, 1.0, True, "Cell"),
    "level2-P1-P1-delta1.5e-2": ("level2-P1-P1", 1.5e-2, "level2-P1", 4, 2.0, True, "Node"),
    "level1-P1-P0-delta0": ("level1-P1-P0", 0.0, "level1-P1", 2, 4.0, True, "Cell"),
    ODD: (ODD, 0.0, "level1-P1", 2, 3.0, False, None),
}
SERIES = {}
for _name, _c in CASES.items():
    SERIES.setdefault(_c[0], []).append(_name)


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
    series, delta, key, n, s, has_p, centering = CASES[name]
    pts, tris = square_mesh(n)
    x, y = pts[:, 0], pts[:, 1]
    point_data = {"u": s * (x + 2 * y), "delta": np.full(len(x), delta)}
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
    jump = None if centering is None else s * (n - k).astype(float)
    return dict(
        series=series, delta=delta, level=n - 1, key=key, pts=pts, tris=tris,
        point_data=point_data, crack=crack, segs=segs, centering=centering, lam=lam, jump=jump,
    )


def check_jump(point_data, e):
    """The crack's point field `jump` (per node, always Center="Node"), removed from point_data."""
    if e["jump"] is None:
        assert "jump" not in point_data
    else:
        np.testing.assert_allclose(point_data.pop("jump"), e["jump"], rtol=1e-15)


def test_only_series_and_state_files_no_spatial_collection(folder):
    """No file mixes series: no top-level fields.xdmf; one mesh and one crack file per series
    and per case."""
    assert not (folder / f"{STEM}.xdmf").exists()
    want = sorted([f"{s}{ext}" for s in SERIES for ext in (".series.xdmf", ".crack.series.xdmf")]
                  + [f"{c}{ext}" for c in CASES for ext in (".xdmf", ".crack.xdmf")])
    assert sorted(p.name for p in (folder / STEM).iterdir()) == want


def read_series(path, names, points, cell_type, cells):
    """The steps of the time series `path` as meshio reads them, once its mesh is checked (the
    expected points to 1e-15, one block of `cell_type` cells equal to `cells`, one step per name):
    (the expected case, point_data, cell_data) per case of `names`, in order, step k at time k."""
    with TimeSeriesReader(path) as r:
        got_points, got_cells = r.read_points_cells()
        np.testing.assert_allclose(got_points, points, rtol=0, atol=1e-15)
        assert [c.type for c in got_cells] == [cell_type]
        np.testing.assert_array_equal(got_cells[0].data, cells)
        assert r.num_steps == len(names)
        for k, name in enumerate(names):
            t, point_data, cell_data = r.read_data(k)
            assert t == k, "the time of step k is k: the slider walks the sweep in order"
            yield expected(name), point_data, cell_data


@pytest.mark.parametrize("series", sorted(SERIES))
def test_meshio_time_series_reads_mesh_series(folder, series):
    names = SERIES[series]
    first = expected(names[0])
    for e, point_data, cell_data in read_series(folder / STEM / f"{series}.series.xdmf", names,
                                                first["pts"], "triangle", first["tris"]):
        assert sorted(point_data) == sorted(e["point_data"])
        for key, v in e["point_data"].items():
            np.testing.assert_allclose(point_data[key], v, rtol=1e-15, atol=1e-15)
        assert not cell_data


@pytest.mark.parametrize("series", sorted(SERIES))
def test_meshio_time_series_reads_crack_series(folder, series):
    names = SERIES[series]
    first = expected(names[0])
    for e, point_data, cell_data in read_series(folder / STEM / f"{series}.crack.series.xdmf",
                                                names, first["crack"], "line", first["segs"]):
        # δ as a constant point field on the crack too (ParaView shows no Information)
        np.testing.assert_array_equal(point_data.pop("delta"),
                                      np.full(len(first["crack"]), e["delta"]))
        check_jump(point_data, e)
        if e["centering"] == "Node":
            np.testing.assert_allclose(point_data["lambda"], e["lam"], rtol=1e-15)
            assert not cell_data
        elif e["centering"] == "Cell":
            assert len(cell_data["lambda"]) == 1
            np.testing.assert_allclose(cell_data["lambda"][0], e["lam"], rtol=1e-15)
            assert not point_data
        else:
            assert not point_data and not cell_data


@pytest.mark.parametrize("series", sorted(SERIES))
def test_steps_carry_name_time_and_delta(folder, series):
    """Each step grid is named after its case (δ in the name), has Time k and Information δ."""
    for ext, suffix in ((".series.xdmf", ""), (".crack.series.xdmf", "/crack")):
        root = ET.parse(folder / STEM / f"{series}{ext}").getroot()
        assert root.tag == "Xdmf" and root.attrib["Version"] == "3.0"
        (domain,) = list(root)
        (coll,) = list(domain)
        assert coll.attrib["Name"] == series
        assert (coll.attrib["GridType"], coll.attrib["CollectionType"]) == ("Collection", "Temporal")
        steps = list(coll)
        assert [g.attrib["Name"] for g in steps] == [n + suffix for n in SERIES[series]]
        for k, (g, name) in enumerate(zip(steps, SERIES[series])):
            e = expected(name)
            assert g.find("Time").attrib["Value"] == str(k)
            info = {i.attrib["Name"]: i.attrib["Value"] for i in g.findall("Information")}
            assert float(info["delta"]) == e["delta"]
            assert int(info["level"]) == e["level"]
            assert "0e0" not in info["delta"]


@pytest.mark.parametrize("series", sorted(SERIES))
def test_data_items_name_existing_datasets(folder, series):
    with h5py.File(folder / f"{STEM}.h5", "r") as f:
        files = [f"{series}{ext}" for ext in (".series.xdmf", ".crack.series.xdmf")]
        files += [f"{c}{ext}" for c in SERIES[series] for ext in (".xdmf", ".crack.xdmf")]
        for name in files:
            root = ET.parse(folder / STEM / name).getroot()
            for item in root.iter("DataItem"):
                assert item.attrib["Format"] == "HDF"
                fname, path = item.text.strip().split(":")
                assert fname == f"../{STEM}.h5"
                dims = tuple(int(d) for d in item.attrib["Dimensions"].split())
                assert f[path].shape == dims, path


@pytest.mark.parametrize("case", sorted(CASES))
def test_meshio_read_reads_each_state(folder, case):
    """fields/CASE.xdmf and fields/CASE.crack.xdmf: meshio.read returns the case's fields (and
    does not exit the interpreter, as it does on a temporal collection)."""
    e = expected(case)
    try:
        m = meshio.read(folder / STEM / f"{case}.xdmf")
        c = meshio.read(folder / STEM / f"{case}.crack.xdmf")
    except SystemExit as exc:  # pragma: no cover - the failure this test exists for
        pytest.fail(f"meshio.read exited the interpreter ({exc.code})")
    np.testing.assert_allclose(m.points, e["pts"], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(m.cells_dict["triangle"], e["tris"])
    assert sorted(m.point_data) == sorted(e["point_data"])
    for key, v in e["point_data"].items():
        np.testing.assert_allclose(m.point_data[key], v, rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(c.points, e["crack"], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(c.cells_dict["line"], e["segs"])
    check_jump(dict(c.point_data), e)
    if e["centering"] == "Node":
        np.testing.assert_allclose(c.point_data["lambda"], e["lam"], rtol=1e-15)
    elif e["centering"] == "Cell":
        np.testing.assert_allclose(c.cell_data["lambda"][0], e["lam"], rtol=1e-15)


def test_h5_data_and_attributes(folder):
    with h5py.File(folder / f"{STEM}.h5", "r") as f:
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
            if e["jump"] is None:
                assert "jump" not in g["crack"]
            else:
                np.testing.assert_allclose(g["crack/jump"][()], e["jump"], rtol=1e-15)
            np.testing.assert_array_equal(g["delta"][()], np.full(len(e["pts"]), e["delta"]))
            np.testing.assert_array_equal(g["crack/delta"][()], np.full(len(e["crack"]), e["delta"]))
            fields = [g] + [g[k] for k in ("u", "p", "p_bubble", "crack/lambda", "crack/jump", "delta",
                                                    "crack/delta")
                            if k in g]
            for obj in fields:
                a = obj.attrs
                assert a["delta"] == e["delta"] and a["level"] == e["level"], (name, obj.name)
                assert a["series"] == e["series"]
                assert a["step"] == SERIES[e["series"]].index(name)
                assert a["u_space"] == "P1"


if __name__ == "__main__":
    import sys

    sys.exit(pytest.main([__file__, "-v"]))
