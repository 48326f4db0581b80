"""Read back a real `sdcrack run` results folder with meshio and h5py (Debian packages).

The folder comes from SDCRACK_RUN_DIR (ci/test runs the `mixed` scene at level 1 into a temporary
folder); the tests skip when it is unset. Checks: every case of summary.json with a `fields_grid`
is a step of its series file (`fields/SERIES.series.xdmf`, one XDMF temporal collection per level,
u space, multiplier and p mass, δ decreasing), which meshio's TimeSeriesReader reads, and has its
own one-state file (`fields/CASE.xdmf`), which meshio.read reads without exiting the interpreter, with u and p at every point of the (cracked)
mesh and λ on the crack polyline (per segment for M0, per node otherwise); the values meshio
returns are the ones stored in fields.h5, whose datasets carry level, h, u space, multiplier and δ.
"""

import json
import os
import pathlib

import numpy as np
import pytest

meshio = pytest.importorskip("meshio")
h5py = pytest.importorskip("h5py")
from meshio.xdmf import TimeSeriesReader  # noqa: E402


@pytest.fixture(scope="module")
def run_dir():
    d = os.environ.get("SDCRACK_RUN_DIR")
    if not d:
        pytest.skip("SDCRACK_RUN_DIR is not set")
    return pathlib.Path(d)


@pytest.fixture(scope="module")
def summary(run_dir):
    return json.loads((run_dir / "summary.json").read_text())


def series_steps(run_dir, summary):
    """{series file: [cases in step order]} from summary.json (cases are listed in sweep order)."""
    out = {}
    for case in summary["cases"]:
        out.setdefault(case["fields_series"], []).append(case)
    return out


def read_series(path):
    """(points, cells, [(t, point_data, cell_data)]) of a time-series XDMF file, by meshio."""
    with TimeSeriesReader(path) as r:
        points, cells = r.read_points_cells()
        steps = [r.read_data(k) for k in range(r.num_steps)]
    return points, cells, steps


def finite(point_data, cell_data):
    return all(np.all(np.isfinite(v))
               for v in list(point_data.values()) + [a for v in cell_data.values() for a in v])


def read_state(path):
    """meshio.read of a one-state file; a SystemExit (meshio's answer to a file it cannot read:
    it prints "Unknown section 'Grid'" and exits) fails the test instead of ending the run."""
    try:
        return meshio.read(path)
    except SystemExit as e:  # pragma: no cover - the failure this test exists for
        pytest.fail(f"meshio.read({path}) exited the interpreter ({e.code})")


def test_every_xdmf_file_opens_with_the_meshio_reader_its_name_says(run_dir, summary):
    """Every .xdmf under the results folder (solver and references): NAME.series.xdmf is one
    temporal collection that TimeSeriesReader reads, any other NAME.xdmf one state that
    meshio.read reads; summary.json names every solver file; no top-level spatial collection."""
    files = sorted(run_dir.rglob("*.xdmf"))
    assert files
    solver_files = [f for f in files if f.parent == run_dir / "fields"]
    assert not (run_dir / "fields.xdmf").exists()
    series = {run_dir / s for s in series_steps(run_dir, summary)}
    states = {run_dir / c["fields_state"] for c in summary["cases"]}
    crack = {f.with_name(f.name.replace(".series.xdmf", ".crack.series.xdmf")) for f in series}
    crack |= {f.with_name(f.name.replace(".xdmf", ".crack.xdmf")) for f in states}
    assert set(solver_files) == series | states | crack
    for f in files:
        if f.name.endswith(".series.xdmf"):
            points, cells, steps = read_series(f)
            assert len(points) > 0 and len(cells) == 1 and steps
            assert all(finite(pd, cd) for _, pd, cd in steps), f
        else:
            m = read_state(f)
            assert len(m.points) > 0 and len(m.cells) == 1 and finite(m.point_data, m.cell_data), f


def test_each_state_file_holds_its_case(run_dir, summary):
    """meshio.read of fields/CASE.xdmf gives the case's u and p from fields.h5, on the same points
    as its step in the series; the crack file its λ."""
    with h5py.File(run_dir / "fields.h5", "r") as h5:
        for case in summary["cases"]:
            grid, state = case["fields_grid"], run_dir / case["fields_state"]
            m = read_state(state)
            np.testing.assert_array_equal(m.point_data["u"], h5[f"cases/{grid}/u"][...])
            np.testing.assert_array_equal(m.point_data["p"], h5[f"cases/{grid}/p"][...])
            np.testing.assert_array_equal(m.point_data["delta"], np.full(len(m.points), case["delta"]))
            c = read_state(state.with_name(state.name.replace(".xdmf", ".crack.xdmf")))
            lam = (c.cell_data["lambda"][0] if case["multiplier"] == "M0"
                   else c.point_data["lambda"])
            np.testing.assert_array_equal(lam, h5[f"cases/{grid}/crack/lambda"][...])


def test_every_case_is_a_step_of_its_series(run_dir, summary):
    cases = summary["cases"]
    assert cases, "summary lists cases"
    with h5py.File(run_dir / "fields.h5", "r") as h5:
        for series, steps in series_steps(run_dir, summary).items():
            points, cells, data = read_series(run_dir / series)
            assert len(data) == len(steps)
            deltas = [c["delta"] for c in steps]
            assert deltas == sorted(deltas, reverse=True), "the slider walks δ → 0"
            n = len(points)
            tri = dict((c.type, c.data) for c in cells)["triangle"]
            assert tri.max() < n and tri.min() >= 0
            for k, (case, (t, point_data, _)) in enumerate(zip(steps, data)):
                grid = case["fields_grid"]
                assert t == k and "0e0" not in grid
                u, p = point_data["u"], point_data["p"]
                # δ of the step as a constant point field: what ParaView shows of it
                np.testing.assert_array_equal(point_data["delta"], np.full(n, case["delta"]))
                assert u.shape == (n,) and p.shape == (n, 3)
                assert np.allclose(p[:, 2], 0.0)
                np.testing.assert_array_equal(u, h5[f"cases/{grid}/u"][...])
                attrs = h5[f"cases/{grid}/u"].attrs
                assert attrs["delta"] == case["delta"] and attrs["level"] == case["level"]
                assert attrs["h"] == case["h"] and attrs["multiplier"] == case["multiplier"]
                assert attrs["u_space"] == case["u_space"]
                # unknowns = 2 p values per vertex + u dofs + multipliers; points are the u dofs
                vertices = len(np.unique(points[:, :2], axis=0))
                assert case["unknowns"] == 2 * vertices + n + case["multipliers"]
                if case["u_space"] == "continuous":
                    assert n == vertices
                else:
                    assert n > vertices  # duplicated crack vertices (cracked mesh)


def test_lambda_lives_on_the_crack(run_dir, summary):
    for series, steps in series_steps(run_dir, summary).items():
        points, cells, data = read_series(run_dir / series.replace(".series.xdmf",
                                                                   ".crack.series.xdmf"))
        for case, (_, point_data, cell_data) in zip(steps, data):
            if case["multiplier"] == "M0":
                lam = cell_data["lambda"][0]
                assert len(lam) == case["multipliers"] == len(points) - 1
                assert np.all(lam >= 0.0)
            else:
                lam = point_data["lambda"]
                assert len(lam) == case["multipliers"] == len(points)
                if case["multiplier"] == "M1":
                    assert np.all(lam >= 0.0)
        # the crack of the mixed scene is y = 0, -0.5 <= x <= 0.5
        assert np.allclose(points[:, 1], 0.0)
        assert np.isclose(points[:, 0].min(), -0.5) and np.isclose(points[:, 0].max(), 0.5)
