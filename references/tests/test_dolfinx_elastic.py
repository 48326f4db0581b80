"""The dolfinx reference on elastic scenes (references/dolfinx/elasticity.py, docs/elasticity.md), on
the exports of elastic_export.py: the patch test (a uniform compression across the crack, reproduced
to round-off, every pair closed with the exact pressure), Williams' mode I on the edge crack (every
pair open, u converging at order 1), a closed crack that slides (every pair closed, the slip
converging), GetFEM's traction / fixed-point scene, the output files, and refused input.

Skipped when dolfinx is not installed."""

import json
import math
import subprocess
import sys

import pytest

dolfinx = pytest.importorskip("dolfinx")
pytest.importorskip("scipy")
np = pytest.importorskip("numpy")

import elastic_fields as ef  # noqa: E402
from conftest import run_env  # noqa: E402
from elastic_export import elastic_export, material  # noqa: E402
from output_checks import assert_provenance, load_module  # noqa: E402
from pathlib import Path  # noqa: E402
from sdshared import sdexpr, sdquad  # noqa: E402

HERE = Path(__file__).resolve().parent
SOLVE = HERE.parent / "dolfinx" / "solve.py"
solve = load_module("dolfinx_solve_elastic", SOLVE)
MATERIAL = material(E=1.0, nu=0.3)  # plane strain: κ = 1.8, as the pilot's
ROUND_OFF = 1e-10  # the patch test: P1 holds the linear field exactly, only the solves' round-off remains


def read_case(out, level):
    """(u (N, 2), crack table (I, 4): opening slip contact_force active) of one level."""
    return (np.loadtxt(out / f"u_level{level}.txt", ndmin=2), np.loadtxt(out / f"crack_level{level}.txt", ndmin=2))


def read_export(exp, level):
    d = exp / f"level{level}"
    cracks = np.loadtxt(d / "cracks.txt", dtype=int, ndmin=2)
    return {"xy": np.loadtxt(d / "vertices.txt"), "tri": np.loadtxt(d / "triangles.txt", dtype=int),
            "crack": np.loadtxt(d / "crack.txt", dtype=int, ndmin=2), "cracks": cracks}


def tip_rows(cracks):
    """The rows of crack.txt that are tips (cracks.txt's flags)."""
    rows = []
    for first, n, tip_a, tip_b in cracks:
        rows += [first] if tip_a else []
        rows += [first + n - 1] if tip_b else []
    return rows


def l2_error(xy, tri, u, ux, uy):
    """‖u_h − u‖_{L²(Ω)} with the degree-16 rule per triangle (its points are interior: the exact
    field is evaluated on each triangle's own face)."""
    p, w = sdquad.load_rule()
    bary = np.column_stack([1 - p.sum(axis=1), p])
    corners = xy[tri]
    det = np.abs(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]))
    X = np.einsum("qk,tkd->tqd", bary, corners)
    total = 0.0
    for c, s in enumerate((ux, uy)):
        uh = np.einsum("qk,tk->tq", bary, u[tri, c])
        ue = np.broadcast_to(sdexpr.to_numpy(sdexpr.parse(s))(X[..., 0], X[..., 1]), uh.shape)
        total += float(np.sum(det[:, None] * w[None, :] * (uh - ue) ** 2))
    return math.sqrt(total)


def rates(errors, hs):
    return [math.log(errors[i] / errors[i + 1]) / math.log(hs[i] / hs[i + 1]) for i in range(len(errors) - 1)]


def assert_kkt(case):
    assert case["status"] == "converged", case["status"]
    assert all(v <= 1e-10 for v in case["kkt"].values()), case["kkt"]


# ---- the exact fields are what they claim (Hooke's law, equilibrium, the crack conditions) ----

SAMPLES = np.array([[0.3, 0.2], [-0.4, 0.5], [-0.7, -0.3], [0.6, -0.8], [0.1, -0.05]])


@pytest.mark.parametrize("name", ["patch", "williams", "closed_slip"])
def test_exact_fields_satisfy_hooke_and_equilibrium(name):
    if name == "patch":
        exact, f = ef.patch(MATERIAL), ["0", "0"]
    elif name == "williams":
        exact, f = ef.williams(MATERIAL, 1.0, 0.5), ["0", "0"]
    else:
        exact, f = ef.closed_slip(MATERIAL)
    x, y = SAMPLES.T
    sigma = ef.stress_of(MATERIAL, exact["ux"], exact["uy"])(x, y)
    for k, key in enumerate(("sxx", "syy", "sxy")):
        given = sdexpr.to_numpy(sdexpr.parse(exact[key]))(x, y)
        assert np.abs(sigma[k] - given).max() < 1e-12, key
    div = ef.divergence_of(exact["sxx"], exact["syy"], exact["sxy"])(x, y)
    for c in (0, 1):
        fc = sdexpr.to_numpy(sdexpr.parse(f[c]))(x, y)
        assert np.abs(div[c] + fc).max() < 1e-12
    if name != "patch":  # on the faces y = ±0 of x < 0: σ_xy = 0, the jumps as given
        xs = np.array([-0.9, -0.5, -0.1])
        val = {k: {s: sdexpr.to_numpy(sdexpr.parse(exact[k]))(xs, np.copysign(np.zeros(3), s)) for s in (1, -1)}
               for k in ("ux", "uy", "sxy", "syy")}
        assert np.abs(val["sxy"][1]).max() < 1e-12 and np.abs(val["sxy"][-1]).max() < 1e-12
        opening = sdexpr.to_numpy(sdexpr.parse(exact["opening"]))(xs, 0.0 * xs)
        slip = sdexpr.to_numpy(sdexpr.parse(exact["slip"]))(xs, 0.0 * xs)
        assert np.abs(val["uy"][1] - val["uy"][-1] - opening).max() < 1e-12
        assert np.abs(val["ux"][1] - val["ux"][-1] - slip).max() < 1e-12
        if name == "closed_slip":  # closed: no opening, a compressive normal stress
            assert np.abs(opening).max() == 0 and val["syy"][1].max() < -0.3


# ---- the runs ---------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def patch_runs(tmp_path_factory):
    d = tmp_path_factory.mktemp("patch")
    exact = ef.patch(MATERIAL)
    runs = {}
    # cracks along y = 0, where σν = (0, −1) is normal: a frictionless crack transmits it exactly
    for kind, crack in (("edge", ((-1.0, 0.0), (0.0, 0.0))), ("interior", ((-0.5, 0.0), (0.5, 0.0)))):
        exp = elastic_export(d / kind, "patch", MATERIAL, ["0", "0"], g=[exact["ux"], exact["uy"]], exact=exact,
                             levels=(0, 1), crack=crack)
        runs[kind] = (exp, solve.run(exp, d / f"{kind}-out", fields=True), d / f"{kind}-out")
    return exact, runs


@pytest.mark.parametrize("kind", ["edge", "interior"])
def test_patch_test_is_exact_and_fully_closed(patch_runs, kind):
    exact, runs = patch_runs
    exp, summary, out = runs[kind]
    assert summary["problem"] == "elasticity" and summary["tool"] == "dolfinx"
    for case in summary["cases"]:
        assert_kkt(case)
        lv = read_export(exp, case["level"])
        u, crack = read_case(out, case["level"])
        xy = lv["xy"]
        ue = np.column_stack([sdexpr.to_numpy(sdexpr.parse(exact[k]))(xy[:, 0], xy[:, 1]) * np.ones(len(xy))
                              for k in ("ux", "uy")])
        assert np.abs(u - ue).max() <= ROUND_OFF
        tips = tip_rows(lv["cracks"])
        pairs = [j for j in range(len(crack)) if j not in tips and not (kind == "edge" and j == 0)]
        assert case["active"] == len(pairs) and crack[pairs, 3].tolist() == [1.0] * len(pairs)
        # the nodal pressure λ_j / m_j = −σ_νν = 1 (ν = (0, 1), σ_yy = −1)
        pts = xy[lv["crack"][:, 0]]
        seg = np.hypot(*np.diff(pts, axis=0).T)
        m = np.zeros(len(pts))
        m[:-1] += seg / 2
        m[1:] += seg / 2
        assert np.abs(crack[pairs, 2] / m[pairs] - 1.0).max() <= ROUND_OFF
        assert np.abs(crack[pairs, :2]).max() <= ROUND_OFF and (crack[tips] == 0).all()


def test_traction_patch_test_is_exact(tmp_path):
    """The uniform stress σ = (½, −1, 0) by tractions on all four sides (t = σn) and fixed points
    (u = 0 at (−1, −1), u_y = 0 at (1, −1)): u = (ε_xx (x + 1), ε_yy (y + 1)) exactly, the edge
    crack closed along its whole length, its mouth on the traction side a constrained pair too."""
    exact = ef.patch(MATERIAL, sxx=0.5, shift=(1.0, 1.0))
    tractions = {"left": ["-0.5", "0"], "right": ["0.5", "0"], "bottom": ["0", "1"], "top": ["0", "-1"]}
    fixed = [{"point": [-1.0, -1.0], "components": ["x", "y"]}, {"point": [1.0, -1.0], "components": ["y"]}]
    exp = elastic_export(tmp_path / "export", "traction-patch", MATERIAL, ["0", "0"], tractions=tractions,
                         fixed=fixed, exact=exact, levels=(0, 1))
    summary = solve.run(exp, tmp_path / "out")
    for case in summary["cases"]:
        assert_kkt(case)
        lv = read_export(exp, case["level"])
        u, crack = read_case(tmp_path / "out", case["level"])
        xy = lv["xy"]
        ue = np.column_stack([sdexpr.to_numpy(sdexpr.parse(exact[k]))(xy[:, 0], xy[:, 1]) for k in ("ux", "uy")])
        assert np.abs(u - ue).max() <= ROUND_OFF
        pairs = list(range(len(crack) - 1))  # every row but the tip, the mouth (row 0) included
        assert case["active"] == len(pairs) and (crack[pairs, 3] == 1).all()
        h = 2.0 / (8 * 2 ** case["level"])
        m = np.full(len(pairs), h)
        m[0] = h / 2  # the mouth has one segment
        assert np.abs(crack[pairs, 2] / m - 1.0).max() <= ROUND_OFF


def test_patch_fields_files(patch_runs):
    h5py = pytest.importorskip("h5py")
    meshio = pytest.importorskip("meshio")
    _, runs = patch_runs
    exp, summary, out = runs["interior"]
    assert_provenance(json.loads((out / "summary.json").read_text()), "dolfinx")
    assert list(json.loads((out / "summary.json").read_text()))[:3] == ["scene", "tool", "problem"]
    u, crack = read_case(out, 1)
    with h5py.File(out / "fields.h5", "r") as h5:
        assert np.array_equal(h5["cases/level1/u"][()], np.column_stack([u, np.zeros(len(u))]))
        stress = h5["cases/level1/stress"][()]
        for k, name in enumerate(("opening", "slip", "contact_force", "active")):
            assert np.array_equal(h5[f"cases/level1/crack/{name}"][()], crack[:, k])
    assert np.abs(stress - [0.0, -1.0, 0.0]).max() <= ROUND_OFF  # the uniform stress of every cell
    mesh = meshio.read(out / "fields" / "level1.xdmf")
    assert mesh.point_data["u"].shape == (len(u), 3) and mesh.cell_data["stress"][0].shape == (len(stress), 3)
    assert sorted(meshio.read(out / "fields" / "level1.crack.xdmf").point_data) == [
        "active", "contact_force", "opening", "slip"]


@pytest.fixture(scope="module")
def williams_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("williams")
    exact = ef.williams(MATERIAL, 1.0, 0.0)
    exp = elastic_export(d / "export", "williams", MATERIAL, ["0", "0"], g=[exact["ux"], exact["uy"]],
                         exact=dict(exact, sif=[[1.0, 0.0]]))
    return exact, exp, solve.run(exp, d / "out"), d / "out"


def test_williams_mode_one_opens_and_converges(williams_run):
    exact, exp, summary, out = williams_run
    errors, hs = [], []
    for case in summary["cases"]:
        assert_kkt(case)
        assert case["active"] == 0 and case["iterations"] == 1
        lv = read_export(exp, case["level"])
        u, crack = read_case(out, case["level"])
        rows = [j for j in range(len(crack)) if j not in tip_rows(lv["cracks"])]
        assert (crack[rows, 0] > 0).all() and (crack[:, 2:] == 0).all()  # open, no force
        errors.append(l2_error(lv["xy"], lv["tri"], u, exact["ux"], exact["uy"]))
        hs.append(case["h"])
    # measured (N = 8, 16, 32, and 64 once): 7.08e-2, 3.90e-2, 2.07e-2 (1.07e-2); rates 0.86, 0.91
    # (0.955). The asymptotic rate is 1 (u ~ r^(1/2): h^(1/2) in energy, h in L²), approached from
    # below on this mesh; the pilot's P1 on its own N×N meshes (other diagonals): 7.31e-2 at N = 8,
    # 1.87e-2 at N = 32. A wrong g at a mouth copy or a crack closed by mistake stalls the rate.
    r = rates(errors, hs)
    assert 0.83 <= r[0] < r[1] <= 1.05, (errors, r)
    assert 0.06 < errors[0] < 0.08, errors


@pytest.fixture(scope="module")
def closed_run(tmp_path_factory):
    d = tmp_path_factory.mktemp("closed")
    exact, f = ef.closed_slip(MATERIAL)
    exp = elastic_export(d / "export", "closed-slip", MATERIAL, f, g=[exact["ux"], exact["uy"]], exact=exact)
    return exact, exp, solve.run(exp, d / "out", fields=True), d / "out"


def test_closed_slip_stays_closed_and_slides(closed_run):
    exact, exp, summary, out = closed_run
    slip_errors, u_errors, hs = [], [], []
    slip = sdexpr.to_numpy(sdexpr.parse(exact["slip"]))
    for case in summary["cases"]:
        assert_kkt(case)
        lv = read_export(exp, case["level"])
        u, crack = read_case(out, case["level"])
        rows = [j for j in range(len(crack)) if j not in tip_rows(lv["cracks"]) and j != 0]  # 0: the mouth
        assert case["active"] == len(rows) and (crack[rows, 3] == 1).all() and (crack[rows, 2] > 0).all()
        assert np.abs(crack[rows, 0]).max() <= ROUND_OFF
        # the nodal slip's error in the crack's lumped L² norm (Σ_j m_j e_j²)^(1/2), m_j = half the
        # lengths of the node's segments
        x = lv["xy"][lv["crack"][:, 0], 0]
        m = np.zeros(len(x))
        m[:-1] += np.diff(x) / 2
        m[1:] += np.diff(x) / 2
        e = crack[:, 1] - slip(x, 0 * x)  # 0 at the tip
        slip_errors.append(math.sqrt(float(np.sum(m * e * e))))
        u_errors.append(l2_error(lv["xy"], lv["tri"], u, exact["ux"], exact["uy"]))
        hs.append(case["h"])
    # measured (N = 8, 16, 32): u 9.66e-2, 5.07e-2, 2.61e-2, rates 0.93, 0.96 (the pilot's P1 on its
    # own meshes: 1.02e-1 at N = 8, 2.58e-2 at N = 32); the nodal slip 2.36e-1, 1.55e-1, 9.24e-2,
    # rates 0.61, 0.75, rising towards 1 (the pilot's P1 nodal slip: 2.86e-1 at N = 8, 9.98e-2 at
    # N = 32)
    r = rates(u_errors, hs)
    assert 0.9 <= r[0] < r[1] <= 1.05, (u_errors, r)
    r = rates(slip_errors, hs)
    assert 0.55 <= r[0] < r[1] <= 1.05 and 0.2 < slip_errors[0] < 0.3, (slip_errors, r)


def test_stress_field_is_hookes_law_of_u(closed_run):
    """fields.h5's cell stress against the in-plane law of u_h's gradients, computed here from the
    corners of each triangle (a field with shear: σ_xy ≠ 0)."""
    h5py = pytest.importorskip("h5py")
    _, exp, summary, out = closed_run
    lam, mu = MATERIAL["lambda_in_plane"], MATERIAL["mu"]
    for case in summary["cases"]:
        lv = read_export(exp, case["level"])
        u, _ = read_case(out, case["level"])
        corners, values = lv["xy"][lv["tri"]], u[lv["tri"]]  # (T, 3, 2)
        # ∇u on each triangle: solve [p1 − p0; p2 − p0] G = [u1 − u0; u2 − u0]
        G = np.linalg.solve(corners[:, 1:] - corners[:, :1], values[:, 1:] - values[:, :1])  # G[d, c] = ∂_d u_c
        exx, eyy, exy = G[:, 0, 0], G[:, 1, 1], (G[:, 0, 1] + G[:, 1, 0]) / 2
        expect = np.column_stack([lam * (exx + eyy) + 2 * mu * exx, lam * (exx + eyy) + 2 * mu * eyy, 2 * mu * exy])
        with h5py.File(out / "fields.h5", "r") as h5:
            stress = h5[f"cases/level{case['level']}/stress"][()]
        assert np.abs(expect[:, 2]).max() > 0.1  # the check sees the shear
        assert np.abs(stress - expect).max() <= 1e-12 * np.abs(expect).max()


def test_getfem_traction_scene_converges(tmp_path):
    scene = ef.getfem_scene()
    m = material(lam=1.0, mu=1.0)
    exp = elastic_export(tmp_path / "export", "getfem", m, levels=(0, 1, 2), n0=8, **scene)
    summary = solve.run(exp, tmp_path / "out")
    u = {}
    for case in summary["cases"]:
        assert_kkt(case)
        u[case["level"]], crack = read_case(tmp_path / "out", case["level"])
        lv = read_export(exp, case["level"])
        xy = lv["xy"]
        # the fixed components hold exactly
        at = {tuple(p): np.flatnonzero((xy == p).all(axis=1))[0] for p in ([1.0, -0.5], [1.0, 0.5])}
        assert u[case["level"]][at[(1.0, -0.5)]].tolist() == [0.0, 0.0] and u[case["level"]][at[(1.0, 0.5)], 0] == 0.0
        # the mouth (row 0) is on a traction part: a constrained pair like the others. A real contact
        # front: open from the mouth, closed towards the tip, the first closed node near x = 0.27
        # (measured: 0.25, 0.25, 0.28 on levels 0, 1, 2; 0.27 on level 3)
        assert (crack[:, 0] >= -ROUND_OFF).all() and (crack[:, 2] >= 0).all()
        closed = np.flatnonzero(crack[:, 3] == 1)
        assert len(closed) and crack[0, 3] == 0 and (np.diff(closed) == 1).all()
        assert 0.2 <= xy[lv["crack"][closed[0], 0], 0] <= 0.3
    # the levels converge: the change at the coarse grid's vertices (the uncut vertices come first,
    # row by row, on every level) shrinks; measured 9.1e-3, 7.0e-3 (then 3.6e-3 on level 3: the
    # front moves on the coarse levels)
    def grid(L):
        n = 8 * 2 ** L + 1
        return u[L][:n * n].reshape(n, n, 2)

    d1 = np.abs(grid(1)[::2, ::2] - grid(0)).max()
    d2 = np.abs(grid(2)[::4, ::4] - grid(1)[::2, ::2]).max()
    assert d2 < 0.8 * d1, (d1, d2)


# ---- refused input ----------------------------------------------------------------------------

def run_cli(exp, out):
    return subprocess.run([sys.executable, str(SOLVE), str(exp), "--out", str(out)], capture_output=True,
                          text=True, env=run_env(), timeout=300)


@pytest.mark.parametrize("bad", ["unknown part", "g missing", "rigid modes", "mu"])
def test_malformed_scene_is_refused_in_one_line(tmp_path, bad):
    exact = ef.patch(MATERIAL)
    kwargs = {"g": [exact["ux"], exact["uy"]]}
    problem = dict(MATERIAL)
    if bad == "unknown part":
        kwargs["tractions"] = {"left": ["0", "0"]}
    elif bad == "g missing":
        kwargs = {"tractions": {"left": ["0", "0"]}}
    elif bad == "rigid modes":
        kwargs = {"tractions": {p: ["0", "0"] for p in ("left", "right", "bottom", "top")},
                  "fixed": [{"point": [1.0, -1.0], "components": ["x", "y"]}]}
    else:
        problem["mu"] = -1.0
    exp = elastic_export(tmp_path / "export", "bad", problem, ["0", "0"], levels=(0,), **kwargs)
    if bad == "unknown part":  # the scene names a part the mesh does not have
        scene = json.loads((exp / "scene.json").read_text())
        scene["tractions"] = {"middle": ["0", "0"]}
        (exp / "scene.json").write_text(json.dumps(scene))
    out = tmp_path / "out"
    r = run_cli(exp, out)
    assert r.returncode == 2 and r.stdout == "" and len(r.stderr.strip().splitlines()) == 1, (r.returncode, r.stderr)
    assert {"unknown part": "middle", "g missing": "g is missing", "rigid modes": "rigid modes",
            "mu": "mu > 0"}[bad] in r.stderr
    assert not out.exists()


@pytest.mark.parametrize("bad", ["mouth not doubled", "tip flag"])
def test_malformed_export_is_refused(tmp_path, bad):
    """A malformed export (as for the scalar script: exit status 1, SolveError, one line), nothing
    written."""
    exact = ef.patch(MATERIAL)
    exp = elastic_export(tmp_path / "export", "bad", MATERIAL, ["0", "0"], g=[exact["ux"], exact["uy"]], levels=(0,))
    d = exp / "level0"
    if bad == "mouth not doubled":
        crack = np.loadtxt(d / "crack.txt", dtype=int)
        crack[0, 1] = crack[0, 0]
        np.savetxt(d / "crack.txt", crack, fmt="%d")
        expect = "its mouth at row 0 has plus == minus"
    else:
        (d / "cracks.txt").write_text("0 9 2 1\n")
        expect = "tip_first tip_last must be 0"
    with pytest.raises(solve.SolveError, match=expect) as info:
        solve.run(exp, tmp_path / "out")
    assert "\n" not in str(info.value) and not (tmp_path / "out").exists()
