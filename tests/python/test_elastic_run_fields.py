"""Read back an elastic `sdcrack run` (the smooth-domain method for elasticity) with meshio and h5py.

The run: the binary of SDCRACK_BIN, else target/release/sdcrack, on scenes/elastic-patch.toml with
`multipliers = ["M1star"]` and `deltas = [1e-2, 0.0]` and no references, at levels 0-1 (a second
or so). Checks (docs/elasticity.md, "The run"): every file summary.json names is read by meshio
(`meshio.read` of each one-state file and its crack file, `TimeSeriesReader` of each series, δ
decreasing), with the shapes the docs give (the broken mesh: 3 points per triangle; the crack: 2
points per crack edge); the values meshio returns are fields.h5's; and the patch test's fields are
its exact ones: σ = diag(0, -1) (raw and symmetrised), u* = (0.39 x, -0.91 y) at δ = 0, pressure
1, opening and slip 0, every crack edge end closed.
"""
import json
import os
import pathlib
import subprocess

import numpy as np
import pytest

from conftest import ROOT, sdcrack_bin

meshio = pytest.importorskip("meshio")
h5py = pytest.importorskip("h5py")
from meshio.xdmf import TimeSeriesReader  # noqa: E402

# The patch test is exact for the method: its fields to round-off. 1e-10 is the bound on
# σ, the opening and the pressure (measured: 1e-11 at level 1); a sign or component slip in the
# writer (σ_xy for σ_yy, u_y for u_x, a crack end swapped) is off by O(1).
EXACT = 1e-10
# δ > 0 perturbs the solution (−div σ + δu = f: σ moves by O(δ|u|), 4e-3 at δ = 1e-2): the exact
# fields are compared at δ = 0 only.
DELTAS = [1e-2, 0.0]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    exe = sdcrack_bin()
    if not os.access(exe, os.X_OK):
        pytest.skip(f"no sdcrack binary at {exe} (cargo build --release, or set SDCRACK_BIN)")
    text = pathlib.Path(ROOT, "scenes", "elastic-patch.toml").read_text(encoding="utf-8")
    # the scene's own solver cases out, this test's in
    text = "\n".join(line for line in text.splitlines()
                     if not line.startswith(("multipliers = ", "deltas = "))) + "\n"
    axes = 'levels = [0, 1, 2, 3, 4]'
    assert axes in text and "references = [" in text
    text = text.replace(axes, 'levels = [0, 1]\nmultipliers = ["M1star"]\ndeltas = [1e-2, 0.0]', 1)
    text = "\n".join("references = []" if line.startswith("references = ") else line
                     for line in text.splitlines()) + "\n"
    tmp = tmp_path_factory.mktemp("elastic")
    scene = tmp / "elastic-patch.toml"
    scene.write_text(text, encoding="utf-8")
    out = tmp / "out"
    subprocess.run([exe, "run", str(scene), "--out", str(out), "--quiet"], check=True,
                   capture_output=True)
    folder = out / "elastic-patch"
    return folder, json.loads((folder / "summary.json").read_text(encoding="utf-8"))


def read_state(path):
    """meshio.read of a one-state file (a SystemExit, meshio's answer to a file it cannot read,
    fails the test)."""
    try:
        return meshio.read(path)
    except SystemExit as e:  # pragma: no cover
        pytest.fail(f"meshio.read({path}) exited the interpreter ({e.code})")


def test_the_summary_lists_the_elastic_cases(run):
    _, s = run
    assert s["problem"] == "elasticity" and s["plan"]["problems"] == ["elasticity"]
    keys = [(c["level"], c["multiplier"], c["delta"]) for c in s["cases"]]
    assert keys == [(lv, "M1star", d) for lv in (0, 1) for d in DELTAS]
    for c in s["cases"]:
        assert c["problem"] == "elasticity"
        assert not {"u_space", "p_mass", "p_space"} & set(c), c
        assert c["converged"] and c["status"] == "converged"
        assert c["closed_ends"] == 2 * c["crack_edges"] > 0
        errors = c["errors"]
        if c["delta"] == 0.0:
            assert errors["stress_sym_l2"] <= EXACT and errors["pressure_l2"] <= EXACT, errors
            assert errors["opening_l2"] <= EXACT, errors
        else:
            assert errors["stress_sym_l2"] > EXACT, "δ > 0 must move σ (or δ is not applied)"


def test_every_field_file_opens_in_meshio_with_the_patch_fields(run):
    folder, s = run
    h5 = h5py.File(folder / "fields.h5", "r")
    for c in s["cases"]:
        mesh = read_state(folder / c["fields_state"])
        (cells,) = mesh.cells
        n = len(cells.data)
        assert cells.type == "triangle" and len(mesh.points) == 3 * n
        assert np.array_equal(cells.data.ravel(), np.arange(3 * n))
        group = h5["cases"][c["fields_grid"]]
        for name, shape in (("sigma", (3 * n, 9)), ("sigma_raw", (3 * n, 9)),
                            ("u_star", (3 * n, 3))):
            assert mesh.point_data[name].shape == shape, name
            assert np.array_equal(mesh.point_data[name], group[name][()]), name
        assert mesh.cell_data["u_h"][0].shape == (n, 3)
        assert mesh.cell_data["gamma_h"][0].shape == (n,)
        assert np.array_equal(mesh.cell_data["u_h"][0], group["u_h"][()])
        crack = read_state(folder / c["fields_state"].replace(".xdmf", ".crack.xdmf"))
        (lines,) = crack.cells
        edges = c["crack_edges"]
        assert lines.type == "line" and len(lines.data) == edges and len(crack.points) == 2 * edges
        assert np.allclose(crack.points[:, 1], 0.0) and np.all(np.abs(crack.points[:, 0]) <= 0.5)
        pd = crack.point_data
        assert np.array_equal(pd["delta"], np.full(2 * edges, c["delta"]))
        assert np.array_equal(pd["closed"], np.ones(2 * edges))
        if c["delta"] == 0.0:
            assert_patch_fields(mesh, pd)


def assert_patch_fields(mesh, crack):
    """The patch test's exact fields: σ = diag(0, −1) (raw and symmetrised, z row and column 0),
    u* = (0.39 x, −0.91 y), pressure 1, opening and slip 0."""
    want = np.zeros(9)
    want[4] = -1.0
    for name in ("sigma", "sigma_raw"):
        assert np.abs(mesh.point_data[name] - want).max() <= EXACT, name
    x, y = mesh.points[:, 0], mesh.points[:, 1]
    u = np.column_stack([0.39 * x, -0.91 * y, 0 * x])
    assert np.abs(mesh.point_data["u_star"] - u).max() <= EXACT
    assert np.abs(crack["pressure"] - 1.0).max() <= EXACT
    assert np.abs(crack["opening"]).max() <= EXACT and np.abs(crack["slip"]).max() <= EXACT


def test_each_series_walks_delta_down(run):
    folder, s = run
    series = {}
    for c in s["cases"]:
        series.setdefault(c["fields_series"], []).append(c)
    assert len(series) == 2
    for path, cases in series.items():
        with TimeSeriesReader(folder / path) as r:
            points, cells = r.read_points_cells()
            steps = [r.read_data(k) for k in range(r.num_steps)]
        assert [d["delta"][0] for _, d, _ in steps] == [c["delta"] for c in cases] == DELTAS
        assert len(points) == 3 * len(cells[0].data)
        for _, d, cd in steps:
            assert set(d) == {"sigma", "sigma_raw", "u_star", "delta"}
            assert set(cd) == {"u_h", "gamma_h"}
