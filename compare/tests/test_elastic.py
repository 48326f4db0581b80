"""The compare tool on elastic results folders (docs/elasticity.md, issue 45), on the synthetic
folders of elastic_synthetic.py (no sdcrack, no references: each reference's u is the P1
interpolant of Williams' exact field on the stand-in export): the norms against closed forms, a
correct folder PASSes, and each verdict FAILs on the damage it is there for — a perturbed field
(series), mismatched active sets (agreement, active set), a forged crack column (crack outputs), a
reference that did not converge (status), references that disagree (agreement) —, a short series
cannot be judged yet, bad input is exit 2, and the scalar pipeline is not taken for elastic
folders (nor the elastic one for scalar folders).

Run: /usr/bin/python3 -m pytest compare/tests/test_elastic.py -q
"""
import contextlib
import importlib.machinery
import importlib.util
import io
import json
import re
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import elastic_synthetic as es
from sdcompare_lib import elastic, elastic_exact, elastic_read, exact

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SCRIPT = os.path.join(os.path.dirname(HERE), "sdcompare")
LEVELS = (0, 1, 2, 3)


def analyse(folder):
    return elastic.analyse(elastic_read.load(str(folder)))


def problems(a, label):
    return next(p for lab, _, p, _ in a["checks"] if lab == label)


def _load_script():
    """compare/sdcompare as a module (the script has no .py suffix), so the command-line tests run
    its main() in this process: the same code path without an interpreter's start-up each."""
    loader = importlib.machinery.SourceFileLoader("sdcompare_script", SCRIPT)
    spec = importlib.util.spec_from_loader(loader.name, loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


SDCOMPARE = _load_script()


def run_cli(folder, *extra):
    """(exit code, stdout, stderr) of `compare/sdcompare FOLDER EXTRA…`."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = SDCOMPARE.main([str(folder), *extra])
    return code, out.getvalue(), err.getvalue()


# ------------------------------------------------------------------------- the norms

def test_williams_stresses_are_hookes_law_of_its_displacement():
    """The synthetic exact table is an elastic field: its closed-form σ equals Hooke's law of the
    symbolic ∇u (elastic_exact.hooke), off the crack."""
    ex = elastic_exact.ElasticExact(es.williams(1.3, -0.7), es.PROBLEM)
    rng = np.random.default_rng(1)
    x, y = rng.uniform(-1, 1, 50), rng.uniform(-1, 1, 50)
    v = ex.evaluate(x, y, elastic_exact.DOMAIN_NAMES)
    grad = np.stack([np.stack([v["duxdx"], v["duxdy"]], -1),
                     np.stack([v["duydx"], v["duydy"]], -1)], -2)
    sig = elastic_exact.hooke(grad, es.PROBLEM)
    given = np.stack([v["sxx"], v["syy"], v["sxy"]], -1)
    assert np.abs(sig - given).max() < 1e-12 * np.abs(given).max()
    # and a wrong Lamé constant is seen
    wrong = dict(es.PROBLEM, lambda_in_plane=es.PROBLEM["lambda_in_plane"] * 1.01)
    assert np.abs(elastic_exact.hooke(grad, wrong) - given).max() > 1e-4


def test_opening_of_williams_mode_one_is_the_documented_one():
    """docs/elasticity.md: [u·e₂] = (κ + 1)/μ · K_I √(r/(2π)) behind the tip (from the faces)."""
    ex = elastic_exact.ElasticExact(es.williams(1.0, 0.0), es.PROBLEM)
    x = np.array([-0.7, -0.3, -0.01])
    v = ex.crack_values(np.column_stack([x, np.zeros(3)]), np.tile([0.0, 1.0], (3, 1)))
    want = (es.KAPPA + 1) / es.MU * np.sqrt(-x / (2 * math.pi))
    assert np.abs(v["opening"] - want).max() < 1e-13
    assert np.abs(v["slip"]).max() < 1e-13 and np.abs(v["pressure"]).max() < 1e-12


def test_norms_of_a_linear_field_are_exact(tmp_path):
    """u = A x + b exact, u_h = u + c: ‖u_h − u‖ = |c| √|Ω| = 2|c|, ∇ and σ errors 0; with u_h's
    gradient off by G: ‖∇ error‖ = 2|G|_F and ‖σ error‖ = 2|σ(G)| (Frobenius, σ_xy twice)."""
    grad = np.array([[0.3, -0.2], [0.5, 0.7]])
    lin = es.linear_exact(grad.tolist(), shift=(0.1, 0.0))
    es.write_export(tmp_path, "lin", lin, (1,), 4)
    level = elastic_read.read_level(str(tmp_path), 1)
    ex = elastic_exact.ElasticExact(lin, es.PROBLEM)
    P = level.points
    u = P @ grad.T + np.array([0.1, 0.0])
    c = np.array([0.03, -0.04])
    G = np.array([[0.01, 0.0], [0.0, -0.02]])
    fields = {"shifted": elastic_exact.p1_field(level, u + c),
              "sheared": elastic_exact.p1_field(level, u + P @ G.T)}
    errs = elastic_exact.domain_errors(level, ex, fields, es.PROBLEM)
    e = errs["shifted"]
    assert abs(e["u_l2"] - 2 * 0.05) < 1e-14 and e["u_h1"] < 1e-13 and e["sigma_l2"] < 1e-13
    e = errs["sheared"]
    sg = elastic_exact.hooke(G, es.PROBLEM)
    assert abs(e["u_h1"] - 2 * np.linalg.norm(G)) < 1e-13
    assert abs(e["sigma_l2"] - 2 * math.sqrt(sg[0] ** 2 + sg[1] ** 2 + 2 * sg[2] ** 2)) < 1e-13


def test_crack_errors_of_a_known_opening(tmp_path):
    """opening_h = exact + 0.1 at every row → ‖error‖_{L²(Γc)} = 0.1 × √1 (the crack's length)."""
    es.write_export(tmp_path, "w", es.williams(1.0, 0.0), (1,), 4)
    level = elastic_read.read_level(str(tmp_path), 1)
    ce = elastic_exact.CrackExact(level, elastic_exact.ElasticExact(es.williams(1.0, 0.0),
                                                                    es.PROBLEM))
    c = level.nodes()
    exact_open = (es.KAPPA + 1) / es.MU * np.sqrt(np.maximum(-c[:, 0], 0) / (2 * math.pi))
    # the nodal interpolant of √r is not √r: compare with the tip-graded rule's own value of a
    # constant shift instead, through the difference of two errors
    e0 = ce.jump_errors(exact_open, np.zeros(len(c)))["opening_l2"]
    e1 = ce.jump_errors(exact_open + 0.1, np.zeros(len(c)))["slip_l2"]
    assert e1 == 0.0
    shifted = ce.jump_errors(np.zeros(len(c)) + 0.1, np.zeros(len(c)) + 0.1)
    assert abs(shifted["slip_l2"] - 0.1) < 1e-14
    assert 0 < e0 < 0.2  # the interpolation error of the √r opening at level 1


# ------------------------------------------------------------------------- the verdict

def test_a_correct_folder_passes_and_reports(tmp_path):
    folder = es.write_results(tmp_path / "w", levels=LEVELS)
    code, out, err = run_cli(folder)
    assert code == 0, out + err
    assert out.strip().endswith("williams: PASS")
    rep = json.loads((folder / "report" / "report.json").read_text())
    assert rep["verdict"] == "PASS" and rep["problem"] == "elasticity"
    by = {(s["tool"], s["quantity"]): s for s in rep["series"]}
    # uniform meshes, r^{1/2} tip: s = 1/2, the interpolant's rates
    assert rep["regularity"]["s"] == 0.5
    assert by[("dolfinx", "u_h1")]["expected"] == 0.5 and by[("dolfinx", "u_l2")]["expected"] == 1
    assert by[("freefem", "opening_l2")]["expected"] == 0.75
    assert all(s["status"] == "converges" for s in rep["series"])
    # the SIFs on every level (q_h = 1 on the tip's triangles, whatever the ring), K_I → 1 and
    # K_II → 0 at the finest
    assert by[("freefem", "K_I tip 1")]["levels"] == [0, 1, 2, 3]
    assert by[("freefem", "K_I tip 1")]["errors"][-1] < 1e-5
    assert by[("freefem", "K_II tip 1")]["errors"][-1] < 1e-5
    assert rep["sif_skipped"] == []
    md = (folder / "report" / "report.md").read_text()
    assert "## Contact set and fronts" in md and "## Errors against the exact fields" in md
    assert (folder / "report" / "errors-williams.png").exists()
    assert "Theorem 4.3" not in md  # the scalar problem's source of orders is not named
    # every sentence is formatted: no Python placeholder left in the text (a missing f prefix)
    assert not re.search(r"\{[A-Za-z_][A-Za-z_.]*[(}]", md), re.search(r"\{[A-Za-z_][A-Za-z_.]*[(}].{0,60}", md)


def test_distances_to_the_finest_level_obey_the_triangle_inequality(tmp_path):
    """‖u_L − u_f‖ (prolonged exactly onto the finest mesh) lies within e_f of e_L = ‖u_L − u‖, in
    L² and in the broken H¹ seminorm: the prolongation takes each face's values."""
    a = analyse(es.write_results(tmp_path / "w", levels=LEVELS))
    assert len(a["field_distances"]) == 2 * (len(LEVELS) - 1)
    for r in a["field_distances"]:
        for q in ("u_l2", "u_h1"):
            e_l, e_f = a["errors"][(r["tool"], r["level"])][q], a["errors"][(r["tool"], 3)][q]
            assert abs(r[q] - e_l) <= e_f * (1 + 1e-12), (r, q)
            assert r[q] > 0.5 * e_l


def test_a_perturbed_field_fails_the_series(tmp_path):
    """Both references (so they agree) off by a smooth field of size 0.02 at every level: the u
    and σ errors stall at the perturbation's size."""
    folder = es.write_results(tmp_path / "w", levels=LEVELS, perturb=lambda xy: 0.02 * np.column_stack(
        [np.sin(math.pi * xy[:, 0]), np.cos(math.pi * xy[:, 1])]))
    a = analyse(folder)
    assert a["verdict"] == "FAIL"
    bad = problems(a, "series")
    assert any("dolfinx u_l2" in p for p in bad) and any("freefem sigma_l2" in p for p in bad)
    assert not problems(a, "reference agreement") and not problems(a, "crack outputs")


def test_mismatched_active_sets_fail(tmp_path):
    """FreeFEM flags three open rows (far from any front: Williams' crack is open everywhere)
    active with zero opening and zero force at level 2: the agreement and the active-set checks
    fail, and the crack outputs (an active row whose stored opening is not its u's)."""
    def damage(tool, level, u, crack):
        if tool == "freefem" and level == 2:
            crack[2:5, 3] = 1.0

    a = analyse(es.write_results(tmp_path / "w", levels=LEVELS, damage=damage))
    assert a["verdict"] == "FAIL"
    assert any("differ in 3 active flag(s)" in p for p in problems(a, "reference agreement"))
    assert any(p.startswith("freefem level 2: 3 row(s) flagged active")
               for p in problems(a, "active set"))
    assert any("active but open" in p for p in problems(a, "crack outputs"))
    rows = {(r["tool"], r["level"]): r for r in a["active_set"]}
    assert rows[("freefem", 2)]["mismatch_rows"] == 3
    assert rows[("freefem", 2)]["mismatch_length"] == pytest.approx(3 * 2 / 16)
    assert rows[("dolfinx", 2)]["mismatch_length"] == 0.0


def test_a_short_series_cannot_be_judged(tmp_path):
    folder = es.write_results(tmp_path / "w", levels=(0, 1))
    # the script as a user runs it (the other tests call its main() in this process)
    p = subprocess.run([sys.executable, SCRIPT, str(folder), "--quiet"], capture_output=True,
                       text=True)
    code, out = p.returncode, p.stdout
    assert code == 3 and out.startswith("williams: INCONCLUSIVE"), out + p.stderr
    assert "INCONCLUSIVE (cannot judge yet" in out and "run levels up to 2" in out
    rep = json.loads((folder / "report" / "report.json").read_text())
    # every series (the fields' and the SIFs', computed from level 0 on) needs level 2
    assert rep["verdict"] == "INCONCLUSIVE" and rep["run_levels_up_to"] == 2
    by = {(s["tool"], s["quantity"]): s for s in rep["series"]}
    assert by[("dolfinx", "u_l2")]["reason"].endswith("run levels up to 2")
    assert by[("dolfinx", "K_I tip 1")]["levels"] == [0, 1]
    assert all(s["status"] == "inconclusive" for s in rep["series"])
    code, _, err = run_cli(folder, "--quiet")  # the report is there: refused without --replace
    assert code == 2 and "report exists" in err


def test_a_forged_crack_column_fails(tmp_path):
    def damage(tool, level, u, crack):
        if tool == "dolfinx" and level == 1:
            crack[:, 0] *= -1.0  # the opening's sign

    a = analyse(es.write_results(tmp_path / "w", levels=LEVELS, damage=damage))
    assert any(p.startswith("dolfinx level 1: row") and "opening" in p
               for p in problems(a, "crack outputs"))


def test_a_reference_that_did_not_converge_fails(tmp_path):
    folder = es.write_results(tmp_path / "w", levels=LEVELS)
    path = folder / "dolfinx" / "summary.json"
    s = json.loads(path.read_text())
    s["cases"][1]["status"] = "max_iterations"
    s["cases"][2]["kkt"]["dual"] = 3e-9
    path.write_text(json.dumps(s))
    bad = problems(analyse(folder), "reference status")
    assert "dolfinx level 1: status 'max_iterations', not 'converged'" in bad
    assert any(p.startswith("dolfinx level 2: KKT dual 3.000e-09") for p in bad)


def test_references_that_disagree_fail(tmp_path):
    """FreeFEM's u off by 1e-8 of ‖u‖∞ (above the 1e-9 target) at level 3: the errors barely
    move, the agreement check fails."""
    def damage(tool, level, u, crack):
        if tool == "freefem" and level == 3:
            u += 1e-8 * np.abs(u).max()

    a = analyse(es.write_results(tmp_path / "w", levels=LEVELS, damage=damage))
    bad = problems(a, "reference agreement")
    assert len(bad) == 1 and bad[0].startswith("level 3: dolfinx and freefem differ in u by 1.00e-08")
    assert not problems(a, "series")


def test_sifs_that_differ_fail_the_agreement(tmp_path):
    """The agreement check on the SIFs: 2e-8 of the tip's largest K apart fails, 5e-9 passes."""
    res = elastic_read.load(str(es.write_results(tmp_path / "w", levels=(1,))))
    for gap, fails in ((2e-8, True), (5e-9, False)):
        sifs = {("dolfinx", 1): [(1.0, 0.25)], ("freefem", 1): [(1.0 + gap, 0.25)]}
        rows, bad = elastic.agreement(res, sifs)
        assert rows[0]["sif_rel"] == pytest.approx(gap, rel=1e-6)
        assert bool(bad) == fails, bad


def test_a_finest_level_without_sifs_fails(tmp_path, monkeypatch):
    """sif.sif_p1 refuses a ring the mesh cannot carry (a ValueError naming why: a disc meeting
    the boundary, a tip that is no vertex): no SIF at the finest level is a problem of the SIF
    check, naming the reason."""
    from sdcompare_lib import sif

    def refuse(*args, **kwargs):
        raise ValueError("sif_p1: the tip [0.0, 0.0] is not a vertex of the mesh")

    monkeypatch.setattr(sif, "sif_p1", refuse)
    a = analyse(es.write_results(tmp_path / "w", levels=(0,)))
    bad = problems(a, "SIF")
    assert len(bad) == 2 and all("is not a vertex of the mesh" in p for p in bad)


def test_a_missing_reference_level_fails_completeness(tmp_path):
    folder = es.write_results(tmp_path / "w", levels=LEVELS)
    path = folder / "freefem" / "summary.json"
    s = json.loads(path.read_text())
    s["cases"] = s["cases"][:-1]
    path.write_text(json.dumps(s))
    assert problems(analyse(folder), "completeness") == ["freefem has no case at level(s) 3"]


def test_without_exact_the_references_are_compared(tmp_path):
    """No exact table: the series and the active-set check do not apply, the fronts are printed;
    a partly closed crack (rows x ≤ −0.5 flagged active in both) has its front at x = −0.5 ± a
    half cell at every level."""
    def closed(level, xy, pairs):
        return xy[pairs[:, 0], 0] <= -0.5 + 1e-12

    folder = es.write_results(tmp_path / "w", levels=(0, 1, 2), closed=closed, n0=4)
    scene = json.loads((folder / "mesh" / "scene.json").read_text())
    scene["exact"] = None
    (folder / "mesh" / "scene.json").write_text(json.dumps(scene))
    a = analyse(folder)
    assert a["series"] == [] and not problems(a, "series")
    na = {lab: n for lab, _, _, n in a["checks"]}
    assert na["series"].startswith("no [exact]") and na["active set"].startswith("no [exact]")
    for f in a["fronts"]:
        if f["level"] == 0:  # one row besides the mouth and the tip: no front to place
            assert f["fronts"] == []
            continue
        (x, y), = f["fronts"]
        cell = 2 / (4 * 2 ** f["level"])
        assert abs(x - (-0.5 + cell / 2)) < 1e-12 and y == 0.0
    dist = {(r["tool"], r["level"]): r["front_distance"] for r in a["finest"]}
    assert dist[("dolfinx", 1)] == pytest.approx(0.125 - 0.0625) and dist[("dolfinx", 2)] == 0.0


def patch_folder(tmp_path, damage=None):
    """The patch test: uniform strain (0.1, −0.3) across an interior crack y = 0, |x| ≤ 1/2, every
    pair closed (σ_yy < 0), exact for P1; levels 2–4 of 4 × 4 cells (the ring of the tips, 0.2 to
    0.4, needs the tip's triangles within 0.2)."""
    grad = np.array([[0.1, 0.0], [0.0, -0.3]])
    s = elastic_exact.hooke(grad, es.PROBLEM)
    ex = {"ux": "0.1*x", "uy": "-0.3*y", "sxx": repr(float(s[0])), "syy": repr(float(s[1])), "sxy": repr(float(s[2])),
          "opening": None, "slip": None, "pressure": None, "sif": [[0.0, 0.0], [0.0, 0.0]]}
    return es.write_results(tmp_path / "patch", exact=ex, levels=(2, 3, 4), name="patch",
                            crack=((-0.5, 0.0), (0.5, 0.0)), damage=damage,
                            closed=lambda L, xy, pairs: np.ones(len(pairs), dtype=bool))


def test_the_patch_test_is_exact(tmp_path):
    """Every error at round-off, the pressure λ_j/m_j = −σ_yy at every row, every pair closed as
    the exact field, K = 0 at both tips (the crack-face term cancels the pressure's K_I)."""
    a = analyse(patch_folder(tmp_path))
    assert a["verdict"] == "PASS", a["reasons"]
    for e in a["errors"].values():
        assert max(e.values()) < 1e-14, e
    assert all(r["mismatch_rows"] == 0 and r["exact_closed_rows"] == r["reference_active_rows"] > 0
               for r in a["active_set"])
    level = elastic_read.load(str(tmp_path / "patch"))["levels"][4]
    (t1, e1), (t2, e2) = level.tip_frames()  # first-point end first, e₁ ahead of each tip
    assert t1.tolist() == [-0.5, 0.0] and e1.tolist() == [-1.0, 0.0] and e2.tolist() == [1.0, 0.0]
    for ks in a["sif_by_key"].values():
        assert np.abs(ks).max() < 1e-12
    assert all(r["u_l2"] < 1e-14 and r["u_h1"] < 1e-13 for r in a["field_distances"])


def test_the_sifs_crack_face_term_left_out_fails(tmp_path, monkeypatch):
    """A compare-side bug: the crack-face term without the pressure (as if the lips were free).
    The fields stay exact, the SIFs of the pressed crack do not: K_I ≈ −0.17 at every level, which
    FAILs the SIF series of both tips."""
    monkeypatch.setattr(elastic, "_exact_pressure", lambda ex, e1: lambda x, y: 0.0 * x)
    a = analyse(patch_folder(tmp_path))
    assert a["verdict"] == "FAIL"
    assert {p.split(":")[0] for p in problems(a, "series")} >= {"dolfinx K_I tip 1",
                                                                "freefem K_I tip 2"}
    assert all(max(e[k] for k in elastic.QUANTITIES) < 1e-14 for e in a["errors"].values())


def test_with_exact_data_the_face_term_takes_the_exact_pressure(tmp_path):
    """The references' forces left out (rows active, force 0): the SIFs, which take the exact
    pressure with [exact], stay 0; the pressure error shows the missing force (−σ_yy ≈ 0.35)."""
    def damage(tool, level, u, crack):
        crack[:, 2] = 0.0

    a = analyse(patch_folder(tmp_path, damage))
    assert a["verdict"] == "PASS" and a["sif_pressure"] == "exact"
    assert all(e["pressure_l2"] > 0.1 for e in a["errors"].values())


def test_a_shear_stress_of_engineering_strain_fails(tmp_path, monkeypatch):
    """A compare-tool bug (σ_xy = μ ε_xy, the engineering shear's law with the tensor strain) makes
    σ(u_h)'s error stall at the size of σ_xy: the σ series fails, the others pass."""
    right = elastic_exact.hooke

    def wrong(grad, material):
        s = right(grad, material)
        s[..., 2] *= 0.5
        return s

    folder = es.write_results(tmp_path / "w", levels=LEVELS)
    monkeypatch.setattr(elastic_exact, "hooke", wrong)
    a = analyse(folder)
    bad = problems(a, "series")
    assert bad and all(p.split(":")[0].endswith("sigma_l2") for p in bad)


# ------------------------------------------------------------------------- bad input, dispatch

def test_bad_input_is_one_line_and_exit_2(tmp_path):
    folder = es.write_results(tmp_path / "w", levels=(0, 1, 2))
    (folder / "freefem" / "crack_level1.txt").write_text("0 0 0\n")
    code, out, err = run_cli(folder)
    assert code == 2 and err.count("\n") == 1 and "crack_level1.txt" in err
    assert not (folder / "report").exists()
    os.remove(folder / "mesh" / "scene.json")
    code, _, err = run_cli(folder)
    assert code == 2 and "scene.json" in err


def test_graded_levels_are_measured_in_unknowns(tmp_path):
    """A graded export (mesh.json kind "graded"): rates per halving of N^-1/2, N = 2 × the cracked
    mesh's vertices, not of the largest triangle."""
    folder = es.write_results(tmp_path / "w", levels=(1,))
    level = elastic_read.read_level(str(folder / "mesh"), 1)
    assert elastic.mesh_parameter(level, True) == (2.0 * len(level.points)) ** -0.5
    assert elastic.mesh_parameter(level, False) == pytest.approx(2 * math.sqrt(2) / 8, rel=1e-15)


def test_scalar_only_options_are_refused(tmp_path):
    folder = es.write_results(tmp_path / "w", levels=(0,))
    code, _, err = run_cli(folder, "--baseline", str(folder))
    assert code == 2 and "--baseline is not available for an elastic scene" in err


def test_an_expectations_row_naming_the_elastic_scene_is_refused(tmp_path):
    """The elastic verdict reads no expectations (scenes/expectations.toml bounds the scalar
    solver's series): an [[expectation]] or [[ratio]] row naming the elastic scene would be
    ignored, so it is one line, exit 2, no report; rows of other scenes (and the repository's
    file) are fine, a missing --expectations file is refused as for a scalar scene."""
    folder = es.write_results(tmp_path / "w", levels=(0,))
    other = tmp_path / "other.toml"
    other.write_text('[[expectation]]\nscene = "closed-exact"\nu_space = "*"\nmultiplier = "*"\n'
                     'quantity = "u_l2"\nlevel = 4\nmax_error = 1.0\n')
    for table in ("expectation", "ratio"):
        mine = tmp_path / f"{table}.toml"
        mine.write_text(other.read_text() + f'[[{table}]]\nscene = "williams"\nlevel = 0\n')
        code, _, err = run_cli(folder, "--expectations", str(mine))
        assert code == 2 and err.count("\n") == 1, err
        assert f"[[{table}]] {1 if table == 'expectation' else 0} names the elastic scene " \
            "'williams'" in err, err
        assert not (folder / "report").exists()
    code, _, err = run_cli(folder, "--expectations", str(tmp_path / "missing.toml"))
    assert code == 2 and "missing expectations file" in err
    for args in (["--expectations", str(other)], ["--replace"],
                 ["--expectations", os.path.join(ROOT, "scenes", "expectations.toml"),
                  "--replace"]):
        code, _, err = run_cli(folder, "--quiet", *args)
        assert code == 3 and (folder / "report" / "report.json").is_file(), err  # one level


def test_dispatch_reads_the_problem_key(tmp_path):
    (tmp_path / "summary.json").write_text(json.dumps({"scene": "x", "cases": []}))
    assert not elastic_read.is_elastic(str(tmp_path))
    (tmp_path / "summary.json").write_text(json.dumps({"scene": "x", "problem": "elasticity"}))
    assert elastic_read.is_elastic(str(tmp_path))
    (tmp_path / "summary.json").write_text("{not json")
    assert not elastic_read.is_elastic(str(tmp_path))
