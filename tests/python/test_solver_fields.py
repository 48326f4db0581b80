"""Read back a real `sdcrack run` results folder with meshio and h5py (Debian packages).

The folder comes from SDCRACK_RUN_DIR (ci/test runs the `mixed` scene at level 1 into a temporary
folder); the tests skip when it is unset. Checks: every case of summary.json with a `fields_grid`
has a per-case XDMF file that meshio reads, with u and p at every point of the (cracked) mesh and
λ on the crack polyline (per segment for M0, per node otherwise); the values meshio returns are the
ones stored in fields.h5; the + and − copies of a crack vertex sit at the same point.
"""

import json
import os
import pathlib

import numpy as np
import pytest

meshio = pytest.importorskip("meshio")
h5py = pytest.importorskip("h5py")


@pytest.fixture(scope="module")
def run_dir():
    d = os.environ.get("SDCRACK_RUN_DIR")
    if not d:
        pytest.skip("SDCRACK_RUN_DIR is not set")
    return pathlib.Path(d)


@pytest.fixture(scope="module")
def summary(run_dir):
    return json.loads((run_dir / "summary.json").read_text())


def test_every_case_has_a_readable_grid(run_dir, summary):
    cases = summary["cases"]
    assert cases, "summary lists cases"
    with h5py.File(run_dir / "fields.h5", "r") as h5:
        for case in cases:
            grid = case["fields_grid"]
            mesh = meshio.read(run_dir / "fields" / f"{grid}.xdmf")
            n = len(mesh.points)
            u = mesh.point_data["u"]
            p = mesh.point_data["p"]
            assert u.shape == (n,) and p.shape == (n, 3)
            assert np.all(np.isfinite(u)) and np.all(np.isfinite(p))
            assert np.allclose(p[:, 2], 0.0)
            np.testing.assert_array_equal(u, h5[f"cases/{grid}/u"][...])
            tri = mesh.cells_dict["triangle"]
            assert tri.max() < n and tri.min() >= 0
            # unknowns = 2 p values per vertex + u dofs + multipliers; the points are the u dofs
            vertices = len(np.unique(mesh.points[:, :2], axis=0))
            assert case["unknowns"] == 2 * vertices + n + case["multipliers"]
            if case["u_space"] == "continuous":
                assert n == vertices
            else:
                assert n > vertices  # duplicated crack vertices (cracked mesh)


def test_lambda_lives_on_the_crack(run_dir, summary):
    for case in summary["cases"]:
        crack = meshio.read(run_dir / "fields" / f"{case['fields_grid']}.crack.xdmf")
        if case["multiplier"] == "M0":
            lam = crack.cell_data["lambda"][0]
            assert len(lam) == case["multipliers"] == len(crack.points) - 1
            assert np.all(lam >= 0.0)
        else:
            lam = crack.point_data["lambda"]
            assert len(lam) == case["multipliers"] == len(crack.points)
            if case["multiplier"] == "M1":
                assert np.all(lam >= 0.0)
        # the crack of the mixed scene is y = 0, -0.5 <= x <= 0.5
        assert np.allclose(crack.points[:, 1], 0.0)
        assert np.isclose(crack.points[:, 0].min(), -0.5) and np.isclose(crack.points[:, 0].max(), 0.5)
