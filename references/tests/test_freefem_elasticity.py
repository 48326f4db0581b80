"""The FreeFEM reference's elastic path (references/freefem/elasticity.py + elastic_qp.edp) on the
stand-in exports of elastic_scenes.py (docs/elasticity.md; issue 45 items 2–3). Skipped without
FreeFem++.

Run: FF_LOADPATH=/usr/lib/freefem++ /usr/bin/python3 -m pytest -q -p no:cacheprovider \
         references/tests/test_freefem_elasticity.py
"""

import json
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import elastic_scenes as S
from conftest import run_env
from output_checks import assert_provenance, load_module
from sdshared import sdexpr

HERE = Path(__file__).resolve().parent
SOLVE = HERE.parent / "freefem" / "solve.py"
ffsolve = load_module("freefem_solve_elastic", SOLVE)

pytestmark = pytest.mark.skipif(shutil.which("FreeFem++") is None,
                                reason="FreeFem++ not installed (apt-get install -y freefem++ libfreefem++)")


def run_solve(export, out, *extra):
    return subprocess.run([sys.executable, str(SOLVE), str(export), "--out", str(out), *extra],
                          capture_output=True, text=True, env=run_env())


def solved(export, out, *extra):
    p = run_solve(export, out, *extra)
    assert p.returncode == 0, p.stderr
    summary = json.loads((Path(out) / "summary.json").read_text())
    assert_provenance(summary, "freefem", script=SOLVE)
    assert summary["problem"] == "elasticity" and summary["scene"] == S.scene(export)["name"]
    for case in summary["cases"]:
        assert set(case) == {"level", "h", "unknowns", "iterations", "active", "kkt", "status", "timings_s"}
        assert case["status"] == "converged", case["status"]
        assert all(0.0 <= v <= 1e-12 for v in case["kkt"].values()), case["kkt"]
    return summary


def rates(values):
    return [math.log2(a / b) for a, b in zip(values, values[1:])]


def ev(src, x, y):
    return np.asarray(sdexpr.to_numpy(sdexpr.parse(src))(np.asarray(x, float), np.asarray(y, float)), float)


def constrained_rows(export, level):
    """Crack rows that carry the constraint: not a tip, no copy on a Dirichlet part (with g every
    part is Dirichlet: the rows with neither copy in boundary.txt; without g, every doubled row)."""
    d = Path(export) / f"level{level}"
    pairs = np.loadtxt(d / "crack.txt", dtype=np.int64, ndmin=2)
    dirichlet = S.scene(export)["g"] is not None
    on_boundary = set(np.loadtxt(d / "boundary.txt", dtype=np.int64, ndmin=1).tolist()) if dirichlet else set()
    return np.array([p != m and p not in on_boundary and m not in on_boundary for p, m in pairs])


def u_errors(export, out, level):
    """(‖u_h − u‖_{L²(Ω)}, ‖∇u_h − ∇u‖_{L²(Ω \\ Γc)}) of a level: the scalar reference's graded
    rules (solve.exact_errors) per component, with fewer points than its defaults (degree 8 near
    the tip, 12 splits: the errors change by ≤ 7.4e-7 relative on closed-slip, levels 0–3, at
    a quarter of the cost)."""
    sc = S.scene(export)
    lv = ffsolve.read_level(export, level, mouths=True)
    u, _ = S.read_results(out, level)
    e = [ffsolve.exact_errors(lv, u[:, c], {"u": sc["exact"][k]}, degree=6, near_degree=8, depth=12)
         for c, k in enumerate(("ux", "uy"))]
    return math.hypot(e[0]["u_l2"], e[1]["u_l2"]), math.hypot(e[0]["p_l2"], e[1]["p_l2"])


# ---- the exact fields, checked before they judge the reference ----------------------------------------

def hooke_by_differences(problem, ux, uy, x, y, step=1e-5):
    """σ of (ux, uy) by central differences (error ~ step² |∂³u|) and λ*, μ."""
    def d(src, var):
        dx, dy = (step, 0.0) if var == "x" else (0.0, step)
        return (ev(src, x + dx, y + dy) - ev(src, x - dx, y - dy)) / (2 * step)
    lam, mu = problem["lambda_in_plane"], problem["mu"]
    exx, eyy, gxy = d(ux, "x"), d(uy, "y"), d(ux, "y") + d(uy, "x")
    return lam * (exx + eyy) + 2 * mu * exx, lam * (exx + eyy) + 2 * mu * eyy, mu * gxy


SAMPLES = np.array([[0.31, 0.47], [-0.62, 0.21], [-0.4, -0.33], [0.7, -0.8], [-0.9, 0.05], [0.2, -0.05]])


@pytest.mark.parametrize("plane", ["strain", "stress"])
def test_patch_field_is_uniform_compression(plane):
    problem = S.material(**S.STEEL, plane=plane)
    exx, eyy = S.patch_strain(problem)
    lam, mu = problem["lambda_in_plane"], problem["mu"]
    assert abs(lam * (exx + eyy) + 2 * mu * exx) < 1e-15 and abs(lam * (exx + eyy) + 2 * mu * eyy + 1) < 1e-15
    E, nu = problem["E"], problem["nu"]
    expected = (nu * (1 + nu) / E, -(1 - nu * nu) / E) if plane == "strain" else (nu / E, -1 / E)
    assert np.allclose((exx, eyy), expected, rtol=1e-14, atol=0)


def test_williams_and_closed_fields_satisfy_hooke_equilibrium_and_the_crack_conditions():
    problem = S.material(**S.STEEL)
    x, y = SAMPLES.T
    # Williams (mode I + II): the stress formulas are Hooke's law of the displacement formulas
    ux, uy = S.williams_u(problem, 1.0, 0.5)
    fd = hooke_by_differences(problem, ux, uy, x, y)
    for got, src in zip(fd, S.williams_stress(1.0, 0.5)):
        assert np.allclose(got, ev(src, x, y), rtol=1e-7, atol=1e-8)
    # its faces (θ = ±π): opening (κ+1)/μ K_I √(r/2π), slip (κ+1)/μ K_II √(r/2π), traction free
    xs = np.array([-0.9, -0.5, -0.1])
    coef = (problem["kolosov"] + 1) / problem["mu"] * np.sqrt(-xs / (2 * np.pi))
    face = {s: sdexpr.on_face(xs, np.zeros(3), (0.0, 1.0), s) for s in (1.0, -1.0)}
    jump = [ev(src, *face[1.0]) - ev(src, *face[-1.0]) for src in (ux, uy)]
    assert np.allclose(jump[1], coef * 1.0, rtol=1e-13) and np.allclose(jump[0], coef * 0.5, rtol=1e-13)
    for s in (1.0, -1.0):
        for src in S.williams_stress(1.0, 0.5)[1:]:
            assert np.allclose(ev(src, *face[s]), 0, atol=1e-13)
    # u_C: the stress formulas are Hooke's law, f = −div σ (differences of the stress), σ_xy = 0 and
    # σ_yy < 0 on y = 0
    (cx, cy), stress, f = S.closed_smooth(problem)
    for got, src in zip(hooke_by_differences(problem, cx, cy, x, y), stress):
        assert np.allclose(got, ev(src, x, y), rtol=1e-8, atol=1e-10)
    h = 1e-5
    dx = lambda src: (ev(src, x + h, y) - ev(src, x - h, y)) / (2 * h)  # noqa: E731
    dy = lambda src: (ev(src, x, y + h) - ev(src, x, y - h)) / (2 * h)  # noqa: E731
    assert np.allclose(ev(f[0], x, y), -(dx(stress[0]) + dy(stress[2])), rtol=1e-8, atol=1e-10)
    assert np.allclose(ev(f[1], x, y), -(dx(stress[2]) + dy(stress[1])), rtol=1e-8, atol=1e-10)
    line = np.linspace(-1, 0, 11)
    assert np.abs(ev(stress[2], line, 0 * line)).max() < 1e-15
    assert ev(stress[1], line, 0 * line).max() < -0.33


def test_diagonal_patch_field_is_unit_pressure_on_the_diagonal():
    problem = S.material(**S.STEEL)
    exx, eyy, exy = S.diagonal_patch_strain(problem)
    lam, mu = problem["lambda_in_plane"], problem["mu"]
    sigma = np.array([[lam * (exx + eyy) + 2 * mu * exx, 2 * mu * exy],
                      [2 * mu * exy, lam * (exx + eyy) + 2 * mu * eyy]])
    nu = np.array([-1.0, 1.0]) / math.sqrt(2)
    assert np.allclose(sigma, -np.outer(nu, nu), rtol=0, atol=1e-15)


# ---- the patch test ------------------------------------------------------------------------------------

@pytest.mark.parametrize("plane,crack,tractions", [
    ("strain", S.INTERIOR_CRACK, False), ("stress", S.INTERIOR_CRACK, False), ("strain", S.EDGE_CRACK, False),
    ("strain", S.EDGE_CRACK, True), ("strain", S.DIAGONAL_CRACK, False)],
    ids=["strain", "stress", "edge-crack", "edge-crack-tractions", "diagonal"])
def test_patch_test_is_exact_with_every_pair_in_contact(tmp_path, plane, crack, tractions):
    """Uniform compression σ_yy = −1 across the crack: P1 holds it exactly, so u = the exact field to
    round-off (≤ 1e-10; measured ≤ 7e-16), every constrained pair active and the nodal pressure
    λ_j/m_j = 1 (measured to 1e-15); along the cells' diagonals too (ν = (−1, 1)/√2: the change of
    variables with both components of ν and τ). The edge crack's mouth is Dirichlet under g and carries no
    constraint; under tractions and fixed points it is a constrained pair like the others (its m_j
    half its one segment)."""
    export = (S.diagonal_patch_export(tmp_path / "export") if crack == S.DIAGONAL_CRACK else
              S.patch_export(tmp_path / "export", plane=plane, crack=crack, tractions=tractions))
    out = tmp_path / "out"
    summary = solved(export, out)
    exact = S.scene(export)["exact"]
    for case in summary["cases"]:
        level = case["level"]
        xy = np.loadtxt(export / f"level{level}" / "vertices.txt")
        u, table = S.read_results(out, level)
        assert case["unknowns"] == u.size == 2 * len(xy)
        assert np.abs(u - np.column_stack([ev(exact["ux"], *xy.T), ev(exact["uy"], *xy.T)])).max() < 1e-10
        rows = constrained_rows(export, level)
        assert rows.sum() >= 3 and case["active"] == rows.sum()
        assert (table[rows, 3] == 1).all() and (table[~rows, 3] == 0).all() and (table[~rows, 2] == 0).all()
        assert np.abs(table[:, :2]).max() < 1e-12
        pressure = table[rows, 2] / S.nodal_lengths(export, level)[rows]
        assert np.abs(pressure - 1).max() < 1e-10, pressure


# ---- Williams' open edge crack, closed with slip ------------------------------------------------------

@pytest.fixture(scope="module")
def williams(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("williams")
    export = S.williams_export(tmp / "export")
    solved(export, tmp / "out")
    return export, tmp / "out"


def test_williams_mode_one_is_open_everywhere_at_rate_one(williams):
    """K_I = 1 on the edge crack of (−1, 1)², uniform levels 0–3 (8·2^L cells a side): no pair active,
    every interior opening > 0, the mouth's opening exact (Dirichlet on both faces), and
    ‖u − u_h‖_{L²} 7.08e-2, 3.90e-2, 2.07e-2, 1.07e-2 (rates 0.86, 0.91, 0.96 → 1), broken H¹
    6.07e-1 … 2.23e-1 (rates 0.47, 0.48, 0.49 → ½), measured. The numpy pilot's P1 on its own
    mesh (N = 8, 32, 128 cells a side, diagonals turned per quadrant): 7.31e-2, 1.87e-2, 4.53e-3."""
    export, out = williams
    problem = S.scene(export)["problem"]
    l2, h1 = [], []
    for level in S.scene(export)["levels"]:
        u, table = S.read_results(out, level)
        rows = constrained_rows(export, level)
        assert (table[:, 3] == 0).all() and (table[:, 2] == 0).all()
        assert (table[rows, 0] > 0).all()
        mouth = (problem["kolosov"] + 1) / problem["mu"] * math.sqrt(1 / (2 * math.pi))
        assert abs(table[0, 0] - mouth) < 1e-13 and abs(table[0, 1]) < 1e-13
        e = u_errors(export, out, level)
        l2.append(e[0])
        h1.append(e[1])
    assert all(r > 0.8 for r in rates(l2)) and rates(l2)[-1] > 0.93 and l2[-1] < 1.1e-2, (l2, rates(l2))
    assert all(0.45 < r < 0.55 for r in rates(h1)), (h1, rates(h1))


def test_closed_with_slip_is_in_contact_everywhere(tmp_path):
    """u_C + K_II mode II (f = −div σ(u_C)), levels 0–3: every constrained pair active with a positive
    contact force, opening 0 to round-off; the nodal slip converges to (κ+1)/μ K_II √(r/2π)
    (measured max error over the constrained rows 0.397, 0.315, 0.234, 0.169 of the slip's 2.9 at the
    mouth: rates 0.33, 0.43, 0.47 → ½, the rows next to the tip dominate) and ‖u − u_h‖_{L²} 9.66e-2, 5.07e-2, 2.61e-2, 1.33e-2 (rates 0.93, 0.96, 0.98)."""
    export = S.closed_slip_export(tmp_path / "export")
    out = tmp_path / "out"
    summary = solved(export, out)
    problem = S.scene(export)["problem"]
    l2, slip_err = [], []
    for case in summary["cases"]:
        level = case["level"]
        _, table = S.read_results(out, level)
        rows = constrained_rows(export, level)
        assert case["active"] == rows.sum() and (table[rows, 3] == 1).all() and (table[rows, 2] > 0).all()
        assert np.abs(table[:, 0]).max() < 1e-12
        d = export / f"level{level}"
        x = np.loadtxt(d / "vertices.txt")[np.loadtxt(d / "crack.txt", dtype=np.int64)[:, 0], 0]
        slip = (problem["kolosov"] + 1) / problem["mu"] * np.sqrt(-x / (2 * np.pi))
        slip_err.append(np.abs(table[rows, 1] - slip[rows]).max())
        l2.append(u_errors(export, out, level)[0])
    assert all(r > 0.9 for r in rates(l2)) and l2[-1] < 1.4e-2, (l2, rates(l2))
    assert all(r > 0.3 for r in rates(slip_err)) and rates(slip_err)[-1] > 0.44 and slip_err[-1] < 0.18, slip_err


# ---- GetFEM's set-up: tractions, fixed points, a contact front ------------------------------------------

def rigid_fit(xy, du):
    """The rigid motion a + b(−y, x) nearest to du (n, 2) and the largest misfit."""
    A = np.zeros((2 * len(xy), 3))
    A[0::2, 0], A[1::2, 1], A[0::2, 2], A[1::2, 2] = 1, 1, -xy[:, 1], xy[:, 0]
    coef, *_ = np.linalg.lstsq(A, du.ravel(), rcond=None)
    return coef, np.abs(A @ coef - du.ravel()).max()


def test_getfem_setup_has_a_contact_front_and_its_fixed_points_only_remove_rigid_modes(tmp_path):
    """All four sides under traction (balanced loads), rigid modes removed by the fixed points: the
    crack opens near its mouth and closes towards its tip (the last open row at x = 0.125, 0.1875,
    0.25 on levels 0–2, measured), and fixing other corners ((0, −½) both, (0, ½) x) changes u by a
    rigid motion only (misfit measured ≤ 2e-14 of ‖u‖∞), with the same active set."""
    a = S.getfem_export(tmp_path / "a")
    b = S.getfem_export(tmp_path / "b", fixed=[{"point": [0.0, -0.5], "components": ["x", "y"]},
                                              {"point": [0.0, 0.5], "components": ["x"]}])
    summary = solved(a, tmp_path / "a-out")
    solved(b, tmp_path / "b-out")
    fronts = []
    for case in summary["cases"]:
        level = case["level"]
        ua, ta = S.read_results(tmp_path / "a-out", level)
        ub, tb = S.read_results(tmp_path / "b-out", level)
        xy = np.loadtxt(a / f"level{level}" / "vertices.txt")
        coef, misfit = rigid_fit(xy, ua - ub)
        assert misfit < 1e-12 * np.abs(ua).max() and np.abs(coef).max() > 1e-3, (coef, misfit)
        assert (ta[:, 3] == tb[:, 3]).all()
        interior = ta[1:-1]  # the mouth (row 0, on a traction part) is constrained as well
        open_rows = np.flatnonzero(ta[:-1, 3] == 0)
        assert 0 < case["active"] < len(interior) + 1
        # one contact front: open rows then closed rows
        assert (np.diff(ta[:-1, 3]) >= 0).all(), ta[:, 3]
        x = np.loadtxt(a / f"level{level}" / "vertices.txt")[np.loadtxt(a / f"level{level}" / "crack.txt",
                                                                          dtype=np.int64)[:, 0], 0]
        fronts.append(x[open_rows[-1]])
        assert (ta[ta[:, 3] == 1, 2] > 0).all() and (ta[ta[:, 3] == 0][:-1, 0] > 0).all()
    assert fronts == [0.125, 0.1875, 0.25], fronts


# ---- field files ---------------------------------------------------------------------------------------

def test_fields_hold_u_the_cell_stress_and_the_crack_quantities(tmp_path):
    import h5py
    import meshio

    export = S.patch_export(tmp_path / "export", crack=S.EDGE_CRACK, levels=(0,))
    out = tmp_path / "out"
    solved(export, out, "--fields")
    u, table = S.read_results(out, 0)
    with h5py.File(out / "fields.h5") as h5:
        assert h5.attrs["tool"] == "freefem"
        uh = h5["/cases/level0/u"][()]
        assert uh.shape == (len(u), 3) and (uh[:, :2] == u).all() and (uh[:, 2] == 0).all()
        stress = h5["/cases/level0/stress"][()]
        assert stress.shape == (len(h5["/meshes/level0/triangles"]), 3)
        assert np.abs(stress - [0.0, -1.0, 0.0]).max() < 1e-10
        crack = h5["/cases/level0/crack"]
        for k, name in enumerate(("opening", "slip", "contact_force", "active")):
            assert (crack[name][()] == table[:, k]).all()
            assert crack[name].attrs["level"] == 0 and crack[name].attrs["tool"] == "freefem"
    grid = meshio.read(out / "fields" / "level0.xdmf")
    assert grid.point_data["u"].shape == (len(u), 3)
    assert np.abs(grid.cell_data["stress"][0] - [0.0, -1.0, 0.0]).max() < 1e-10
    line = meshio.read(out / "fields" / "level0.crack.xdmf")
    assert set(line.point_data) == {"opening", "slip", "contact_force", "active"}


# ---- malformed input ------------------------------------------------------------------------------------

def spoil_mu(sc):
    sc["problem"]["mu"] = 0.0


def spoil_expression(sc):
    sc["f"][1] = "__import__('os')"


def spoil_part(sc):
    sc["tractions"] = {"middle": ["0", "0"]}


def spoil_g(sc):
    sc["g"] = None


def spoil_f(sc):
    sc["f"] = "0"


@pytest.mark.parametrize("spoil,message", [
    (spoil_mu, "mu > 0"), (spoil_expression, "f.y"), (spoil_part, "unknown boundary parts ['middle']"),
    (spoil_g, "g is null"), (spoil_f, "f must be two expressions")],
    ids=["mu-zero", "bad-expression", "unknown-part", "g-missing", "f-scalar"])
def test_a_malformed_elastic_scene_is_refused_in_one_line_and_nothing_is_written(tmp_path, spoil, message):
    export = S.patch_export(tmp_path / "export", levels=(0,))
    sc = S.scene(export)
    spoil(sc)
    (export / "scene.json").write_text(json.dumps(sc))
    out = tmp_path / "out"
    p = run_solve(export, out)
    assert p.returncode == 2, p.stderr
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("solve.py: error: ") and message in lines[0], p.stderr
    assert not out.exists() and [q.name for q in tmp_path.iterdir()] == ["export"]


# ---- sdexport reads mouths ------------------------------------------------------------------------------

def test_sdexport_reads_an_edge_cracks_mouth_and_refuses_a_mouth_without_copies(tmp_path):
    """cracks.txt's tip flags: the mouth (row 0 of the edge crack) is doubled, in interior() and not
    a tip; the last row is the tip; a mouth row with plus == minus and a flag other than 0/1 are
    refused in one line naming the file; a two-column cracks.txt still means two tips."""
    from sdshared import sdexport

    export = S.patch_export(tmp_path / "export", crack=S.EDGE_CRACK, levels=(0,))
    d = export / "level0"
    xy = np.loadtxt(d / "vertices.txt")
    layout = sdexport.read_layout(d, xy, len(xy))
    assert layout.ends == [(False, True)] and layout.tip_rows().tolist() == [len(layout.pairs) - 1]
    assert layout.interior().tolist() == [True] * (len(layout.pairs) - 1) + [False]
    assert layout.tip_vertices().tolist() == [layout.pairs[-1, 0]]
    first, n, _, _ = np.loadtxt(d / "cracks.txt", dtype=np.int64)
    (d / "cracks.txt").write_text(f"{first} {n} 2 1\n")
    with pytest.raises(sdexport.ExportError, match="tip_first tip_last must be 0"):
        sdexport.read_layout(d, xy, len(xy))
    (d / "cracks.txt").write_text(f"{first} {n}\n")   # both ends tips: the mouth's row is not one
    with pytest.raises(sdexport.ExportError, match="its tip at row 0 has plus"):
        sdexport.read_layout(d, xy, len(xy))
    pairs = np.loadtxt(d / "crack.txt", dtype=np.int64)
    pairs[0, 1] = pairs[0, 0]
    np.savetxt(d / "crack.txt", pairs, fmt="%d")
    (d / "cracks.txt").write_text(f"{first} {n} 0 1\n")
    with pytest.raises(sdexport.ExportError, match="its mouth at row 0 has plus == minus"):
        sdexport.read_layout(d, xy, len(xy))
