"""Read back a real `sdcrack run` results folder with meshio and h5py (Debian packages).

The folder comes from SDCRACK_RUN_DIR (ci/test runs the `mixed` scene at level 1 into a temporary
folder); the tests skip when it is unset. Checks: every case of summary.json with a `fields_grid`
is a step of its series file (`fields/SERIES.series.xdmf`, one XDMF temporal collection per level,
u space, multiplier and p mass, δ decreasing), which meshio's TimeSeriesReader reads, and has its
own one-state file (`fields/CASE.xdmf`), which meshio.read reads without exiting the interpreter, with u and p at every point of the (cracked)
mesh and λ on the crack polyline (per segment for M0, per node otherwise); the values meshio
returns are the ones stored in fields.h5, whose datasets carry level, h, u space, multiplier and δ.

The crack field names (README's field table, one name per quantity in every solver's files): a
run of its own (`names_run`: the binary of SDCRACK_BIN, else target/release/sdcrack, on a small
scene of a straight and a reversed kinked crack, with both references when they are installed) and
the SDCRACK_RUN_DIR folder when set: sdcrack's `jump` is u⁺ − u⁻ of its own u, recomputed here from
the u file alone (zero for the continuous u), has the references' sign where the crack opens, and
the references' crack files hold `jump` and `contact_force` (no `multiplier`).
"""

import json
import os
import pathlib
import shutil
import subprocess

import numpy as np
import pytest

meshio = pytest.importorskip("meshio")
h5py = pytest.importorskip("h5py")
from meshio.xdmf import TimeSeriesReader  # noqa: E402


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


ROOT = pathlib.Path(__file__).resolve().parents[2]
EXE = pathlib.Path(os.environ.get("SDCRACK_BIN", ROOT / "target" / "release" / "sdcrack"))

# A straight crack on y = 0 opened by the load where sin(2πx) > 0 (as the mixed scene), and a
# kinked one run right to left (ν = −y on its first segment) then down the diagonal.
NAMES_SCENE = """
name = "names"
[geometry]
domain = {{ rectangle = [[-1.0, -1.0], [1.0, 1.0]] }}
cracks = [
  {{ polyline = [[-0.5, 0.0], [0.5, 0.0]] }},
  {{ polyline = [[0.75, 0.75], [0.25, 0.75], [0.0, 0.5]] }},
]
[data]
f = "20*sin(2*pi*x)*sign(y)"
g = "0"
[discretization]
cells = [8, 8]
levels = [1]
u_spaces = ["continuous", "broken"]
multipliers = ["M0", "M1"]
p_mass = ["consistent"]
deltas = [1e-2, 0.0]
[outputs]
fields = {fields}
references = {references}
"""


def references_installed():
    """FreeFem++ on PATH and dolfinx under /usr/bin/python3 (what sdcrack runs the references with)."""
    if shutil.which("FreeFem++") is None or not os.path.exists("/usr/bin/python3"):
        return False
    return subprocess.run(["/usr/bin/python3", "-c", "import dolfinx, h5py"], capture_output=True).returncode == 0


def run_names(tmp, fields, references):
    if not EXE.exists():
        pytest.skip(f"no sdcrack binary at {EXE} (cargo build --release, or set SDCRACK_BIN)")
    scene = tmp / "names.toml"
    scene.write_text(NAMES_SCENE.format(fields=json.dumps(fields), references=json.dumps(references)))
    env = dict(os.environ, FF_LOADPATH=os.environ.get("FF_LOADPATH", "/usr/lib/freefem++"))
    p = subprocess.run([str(EXE), "run", str(scene), "--out", str(tmp / "out"), "--quiet"],
                       capture_output=True, text=True, env=env, timeout=120)
    assert p.returncode == 0, p.stderr
    return tmp / "out" / "names"


@pytest.fixture(scope="module")
def names_run(tmp_path_factory):
    refs = ["dolfinx", "freefem"] if references_installed() else []
    return run_names(tmp_path_factory.mktemp("names"), ["u", "p", "lambda"], refs)


def runs(names_run):
    """The folders to check: this module's run and, when set, SDCRACK_RUN_DIR's."""
    d = os.environ.get("SDCRACK_RUN_DIR")
    return [names_run] + ([pathlib.Path(d)] if d else [])


def faces_jump(grid, crack):
    """u⁺ − u⁻ at every crack node, from the u grid (meshio) and the crack grid's points and
    segments alone: the copies of a node are the grid points at its coordinates; a copy is on the +
    face (the one ν, the segment direction turned by +90°, points into) when a triangle holding it
    and a copy of the node before it on its crack lies left of that crack edge (sdcrack itself
    looks at the edge after it)."""
    pts, tris, u = grid.points[:, :2], grid.cells_dict["triangle"], grid.point_data["u"]
    cp = crack.points[:, :2]
    index = {tuple(x): k for k, x in enumerate(cp)}
    node = np.array([index.get(tuple(x), -1) for x in pts])
    copies = [np.flatnonzero(node == k) for k in range(len(cp))]
    prev = {int(b): int(a) for a, b in crack.cells_dict["line"]}
    plus = {}
    for t in tris:
        c = pts[t].mean(axis=0)
        for a in t:
            k = node[a]
            if k < 0 or k not in prev or not (node[t] == prev[k]).any():
                continue
            x0, d = cp[prev[k]], cp[k] - cp[prev[k]]
            plus.setdefault(a, set()).add(bool(d[0] * (c[1] - x0[1]) - d[1] * (c[0] - x0[0]) > 0))
    jump = np.zeros(len(cp))
    for k, dofs in enumerate(copies):
        assert len(dofs) in (1, 2), (k, dofs)
        if len(dofs) == 2:  # one copy a face (a single copy, the continuous u's, sees both)
            a, b = dofs
            assert {frozenset(plus[a]), frozenset(plus[b])} == {frozenset([True]), frozenset([False])}
            jump[k] = u[a] - u[b] if True in plus[a] else u[b] - u[a]
    return jump


def test_jump_is_u_plus_minus_u_minus_of_the_u_file(names_run):
    """Every case's `jump` (one-state crack file, series, fields.h5) is u⁺ − u⁻ of its own u file,
    recomputed here: identically 0 for the continuous u (its u cannot open), nonzero for the
    broken u, 0 at the tips; every .xdmf written opens with its meshio reader."""
    for run in runs(names_run):
        s = json.loads((run / "summary.json").read_text())
        with h5py.File(run / "fields.h5", "r") as h5:
            for case in s["cases"]:
                state = run / case["fields_state"]
                grid, crack = read_state(state), read_state(state.with_name(
                    state.name.replace(".xdmf", ".crack.xdmf")))
                jump = crack.point_data["jump"]
                assert jump.shape == (len(crack.points),)
                np.testing.assert_array_equal(jump, faces_jump(grid, crack), err_msg=case["fields_grid"])
                np.testing.assert_array_equal(jump, h5[f"cases/{case['fields_grid']}/crack/jump"][...])
                tips = np.setdiff1d(np.arange(len(jump)), crack.cells_dict["line"][:, 1]).tolist()
                tips += np.setdiff1d(np.arange(len(jump)), crack.cells_dict["line"][:, 0]).tolist()
                assert (jump[tips] == 0).all()
                if case["u_space"] == "continuous":
                    assert (jump == 0).all()
                else:
                    assert np.abs(jump).max() > 0.1
        for series, steps in series_steps(run, summary=s).items():
            _, _, data = read_series(run / series.replace(".series.xdmf", ".crack.series.xdmf"))
            for case, (_, point_data, _) in zip(steps, data):
                np.testing.assert_array_equal(
                    point_data["jump"], read_state(run / case["fields_state"].replace(
                        ".xdmf", ".crack.xdmf")).point_data["jump"])


def test_jump_has_the_references_sign_where_the_crack_opens(names_run):
    """On the crack opened by the load, sdcrack's broken-u jump at δ = 0 has the sign of the
    references' `jump` (positive: the + face moved up from the − face) wherever theirs is at least a
    quarter of its largest, and is within half of it there; the references' crack files hold
    `jump` and `contact_force` (0 where the crack opens), not `multiplier`."""
    checked = 0
    for run in runs(names_run):
        s = json.loads((run / "summary.json").read_text())
        for tool in ("dolfinx", "freefem"):
            if not (run / tool / "fields").is_dir():
                continue
            for case in s["cases"]:
                if case["u_space"] != "broken" or case["delta"] != 0.0:
                    continue
                state = run / case["fields_state"]
                ours = read_state(state.with_name(state.name.replace(".xdmf", ".crack.xdmf")))
                ref = read_state(run / tool / "fields" / f"level{case['level']}.crack.xdmf")
                assert {"jump", "contact_force"} <= set(ref.point_data), (tool, sorted(ref.point_data))
                assert "multiplier" not in ref.point_data
                np.testing.assert_array_equal(ours.points, ref.points)
                theirs, jump = ref.point_data["jump"], ours.point_data["jump"]
                open_ = theirs >= 0.25 * theirs.max()
                assert open_.sum() >= 2 and theirs.max() > 0.1, theirs
                assert (jump[open_] > 0).all(), (tool, case["fields_grid"], jump, theirs)
                assert np.all(np.abs(jump[open_] - theirs[open_]) <= 0.5 * theirs[open_])
                assert (ref.point_data["contact_force"][open_] == 0).all()
                checked += 1
    if not checked:
        pytest.skip("no reference fields (dolfinx and FreeFEM not installed)")


def test_jump_is_in_every_crack_file_whatever_the_fields_listed(tmp_path):
    """`fields = ["lambda"]`: the crack files still hold `jump` (with λ), the mesh files no u;
    verification.h5 has it too."""
    run = run_names(tmp_path, ["lambda"], [])
    s = json.loads((run / "summary.json").read_text())
    with h5py.File(run / "verification.h5", "r") as h5:
        for case in s["cases"]:
            state = run / case["fields_state"]
            assert "u" not in read_state(state).point_data
            crack = read_state(state.with_name(state.name.replace(".xdmf", ".crack.xdmf")))
            np.testing.assert_array_equal(crack.point_data["jump"],
                                          h5[f"cases/{case['fields_grid']}/crack/jump"][...])
