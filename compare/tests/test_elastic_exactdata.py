"""The compare tool's own check of an elastic scene's exact data (compare/sdcompare_lib/
elastic_exactdata.py, docs/elasticity.md *The exact data are checked*): every repository elastic
scene passes (its scene.json as `sdcrack mesh` writes it); one realistic mistake per check fails
with the key it is about; and on a results folder whose scene has a wrong datum the verdict is FAIL
with the scene as its cause, not the references.

Run: /usr/bin/python3 -m pytest -q -p no:cacheprovider compare/tests/test_elastic_exactdata.py
"""
import copy
import json
import math
import os
import subprocess
from pathlib import Path

import pytest

import elastic_synthetic as es
from conftest import run_env, sdcrack_bin
from sdcompare_lib import elastic, elastic_exactdata as ed, elastic_read
from test_elastic import run_cli

ROOT = Path(__file__).resolve().parents[2]
SCENES = sorted(p.stem for p in (ROOT / "scenes").glob("elastic-*.toml"))
WITH_EXACT = ("elastic-patch", "elastic-williams-open", "elastic-closed-slip", "elastic-griffith")


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    """{name: scene.json} of every scenes/elastic-*.toml, by `sdcrack mesh --level 0`."""
    exe = sdcrack_bin()
    if not os.access(exe, os.X_OK):
        pytest.skip("no sdcrack binary (cargo build --release, or SDCRACK_BIN)")
    tmp = tmp_path_factory.mktemp("xdata")
    out = {}
    for name in SCENES:
        subprocess.run([exe, "mesh", str(ROOT / "scenes" / f"{name}.toml"), "--out",
                        str(tmp / name), "--level", "0"], check=True, env=run_env(),
                       capture_output=True, timeout=120)
        out[name] = json.loads((tmp / name / "scene.json").read_text())
    return out


def keys(scene):
    """{key: its first problem's sentence} of the scene's problems."""
    out = {}
    for p in ed.check_scene(scene)[0]:
        out.setdefault(p.key, p.sentence)
    return out


def fails(scene, key, *words):
    """The sentence of a problem about `key` that says all of `words`: it must name the key first
    and say by how much."""
    found = [p.sentence for p in ed.check_scene(scene)[0] if p.key == key]
    assert found, keys(scene)
    match = [t for t in found if all(w in t for w in words)]
    assert match, (words, found)
    sentence = match[0]
    assert sentence.startswith(key.split("[")[0]), sentence
    assert any(w in sentence for w in ("off by", "below 0 by", "above 0 by")), sentence
    return sentence


def test_every_repository_elastic_scene_passes(exported):
    assert set(WITH_EXACT) <= set(exported)
    for name, scene in exported.items():
        problems, checked = ed.check_scene(scene)
        assert problems == [], (name, [str(p) for p in problems])
        assert (checked is None) == (scene["exact"] is None), name


def test_the_sif_limits_are_the_scenes_and_tight(exported):
    """The near-tip limits give the scenes' K far inside their tolerance, and the tolerance is
    below 1e-6 of K where the field has no T-stress-like term (Williams, Griffith)."""
    for name in WITH_EXACT:
        scene = exported[name]
        fld = ed._Field(scene)
        polygon, _ = ed.polygon_and_parts(scene)
        for (tip, e1, R), want in zip(ed.tips(polygon, ed._cracks(scene)), scene["exact"]["sif"]):
            for (K, tol), k in zip(ed.sif_limits(fld, tip, e1, R), want):
                assert abs(K - k) <= 0.1 * tol or abs(K - k) < 1e-13, (name, K, k, tol)
                if name in ("elastic-williams-open", "elastic-griffith") and k:
                    assert tol < 1e-6 * abs(k), (name, tol)


def test_a_flipped_mode_sign_fails_hookes_law(exported):
    s = copy.deepcopy(exported["elastic-williams-open"])
    sxx = s["exact"]["sxx"]
    s["exact"]["sxx"] = sxx.replace(" + 0.5*(-sin", " - 0.5*(-sin")
    assert s["exact"]["sxx"] != sxx
    fails(s, "exact.sxx", "Hooke's law")
    # mode II's u_y of the wrong sign, the stress derived from it: not a Navier field
    s = copy.deepcopy(exported["elastic-williams-open"])
    s["exact"]["uy"] = s["exact"]["uy"].replace(" + 0.5*cos", " - 0.5*cos")
    assert s["exact"]["uy"] != exported["elastic-williams-open"]["exact"]["uy"]
    assert "exact.sxy" in keys(s)


def test_a_wrong_lame_constant_fails_hookes_law(exported):
    """The patch's σ_xx = 0 holds for plane strain's λ* only: plane stress's λ* breaks it."""
    s = copy.deepcopy(exported["elastic-patch"])
    lam, mu = s["problem"]["lambda"], s["problem"]["mu"]
    s["problem"]["lambda_in_plane"] = 2 * lam * mu / (lam + 2 * mu)
    fails(s, "exact.sxx", "Hooke's law", "λ* = 0.32967")


def test_a_wrong_body_force_fails_equilibrium(exported):
    s = copy.deepcopy(exported["elastic-closed-slip"])
    s["f"][1] = s["f"][1].replace("4*(1/2.6)", "2*(1/2.6)")
    assert s["f"][1] != exported["elastic-closed-slip"]["f"][1]
    fails(s, "data.fy", "−(div σ)_y")


def test_g_off_u_fails(exported):
    s = copy.deepcopy(exported["elastic-patch"])
    s["g"][1] = "0.91*y"
    fails(s, "data.gy", "on bottom")


def test_a_traction_with_the_wrong_normal_fails(exported):
    """The patch's top as a traction part: σn = (0, −1) with n = (0, 1); written with the bottom's
    normal, (0, 1)."""
    s = copy.deepcopy(exported["elastic-patch"])
    s["tractions"]["top"] = ["0", "-1"]
    assert keys(s) == {}
    s["tractions"]["top"] = ["0", "1"]
    fails(s, "data.traction.top", "n = (0, 1)")
    s["tractions"] = {"front": ["0", "0"]}
    assert "names no part" in keys(s)["data.traction.front"]


def test_a_fixed_point_where_u_moves_fails(exported):
    s = copy.deepcopy(exported["elastic-patch"])
    s["fixed"] = [{"point": [0.0, 1.0], "components": ["x"]}, {"point": [1.0, 1.0],
                                                               "components": ["y"]}]
    found = keys(s)
    assert set(found) == {"data.fixed[1]"}, found
    assert found["data.fixed[1]"].startswith("data.fixed[1] holds uy = 0 at (1, 1)")


def test_an_opening_that_penetrates_fails(exported):
    # the given opening of the wrong sign: not u's, and interpenetrating
    s = copy.deepcopy(exported["elastic-williams-open"])
    s["exact"]["opening"] = "-" + s["exact"]["opening"]
    fails(s, "exact.opening", "is not [u·ν]")
    fails(s, "exact.opening", "interpenetrate")
    # a mode I of the wrong sign (K_I = −1, consistent everywhere else): the faces overlap
    ex = es.williams(-1.0, 0.0)
    scene = {"domain": {"min": [-1.0, -1.0], "max": [1.0, 1.0]},
             "cracks": [{"points": [[-1.0, 0.0], [0.0, 0.0]]}], "problem": es.PROBLEM,
             "f": ["0", "0"], "g": [ex["ux"], ex["uy"]], "tractions": {}, "fixed": [],
             "exact": ex}
    assert set(keys(scene)) == {"exact.ux"}
    fails(scene, "exact.ux", "[u·ν] ≥ 0", "interpenetrate")


def test_a_given_slip_or_pressure_off_the_field_fails(exported):
    s = copy.deepcopy(exported["elastic-williams-open"])
    s["exact"]["slip"] = s["exact"]["slip"].replace("0.5", "-0.5")
    fails(s, "exact.slip", "[u·τ]")
    s = copy.deepcopy(exported["elastic-closed-slip"])
    s["exact"]["pressure"] = "-" + s["exact"]["pressure"]
    fails(s, "exact.pressure", "−σ_νν")


def test_a_shear_on_a_closed_crack_fails(exported):
    """The closed crack with slip plus the simple shear (0.05 y, 0) (σ_xy + 0.05 μ, g with it): a
    friction the problem does not have."""
    s = copy.deepcopy(exported["elastic-closed-slip"])
    mu = s["problem"]["mu"]
    s["exact"]["ux"] += " + 0.05*y"
    s["g"][0] += " + 0.05*y"
    s["exact"]["sxy"] += f" + 0.05*{mu!r}"
    found = keys(s)
    assert set(found) == {"exact.ux"}, found
    fails(s, "exact.ux", "σ_ντ = 0", "frictionless")


def test_a_crack_in_tension_and_an_open_pressed_crack_fail(exported):
    # the patch pulled: σ_yy = +1 with the crack shut
    s = copy.deepcopy(exported["elastic-patch"])
    s["exact"].update(uy="0.91*y", syy="1", pressure=None)
    s["exact"]["sxx"] = "0"
    s["g"][1] = "0.91*y"
    s["exact"]["ux"] = s["g"][0] = "-0.39*x"
    fails(s, "exact.ux", "σ_νν ≤ 0")
    # the patch with its faces 0.02 apart, still pressed
    s = copy.deepcopy(exported["elastic-patch"])
    s["exact"].update(uy="-0.91*y + 0.01*sign(y)", opening=None, pressure=None)
    s["cracks"] = [{"points": [[-1.0, 0.0], [1.0, 0.0]]}]
    s["g"][1] = s["exact"]["uy"]
    s["exact"]["sif"] = None
    fails(s, "exact.ux", "σ_νν·[u·ν] = 0")


def test_a_traction_jump_across_the_crack_fails(exported):
    s = copy.deepcopy(exported["elastic-patch"])
    m = s["problem"]
    lam, mu = m["lambda_in_plane"], m["mu"]
    # u_y = −0.2y − 0.1|y|: shut, pressed on both faces, more on the + face
    s["exact"].update(ux="0", uy="-0.2*y - 0.1*abs(y)", opening=None, pressure=None, slip=None,
                      sif=None)
    s["exact"]["sxx"] = f"{lam!r}*(-0.2 - 0.1*sign(y))"
    s["exact"]["syy"] = f"{lam + 2 * mu!r}*(-0.2 - 0.1*sign(y))"
    s["g"] = [s["exact"]["ux"], s["exact"]["uy"]]
    s["tractions"] = {}
    fails(s, "exact.ux", "[σν] = 0")


def test_a_wrong_sif_fails(exported):
    """Griffith's K_I = σ∞√(πa) written with the crack's length 2a for a; Williams' K_I and K_II
    swapped; one entry for two tips."""
    s = copy.deepcopy(exported["elastic-griffith"])
    s["exact"]["sif"][1][0] = math.sqrt(math.pi)
    found = keys(s)
    assert set(found) == {"exact.sif[1]"}, found
    fails(s, "exact.sif[1]", "K_I = 1.77245", "tip (0.5, 0)", "1.25331")
    s = copy.deepcopy(exported["elastic-williams-open"])
    s["exact"]["sif"] = [[0.5, 1.0]]
    found = [p.sentence for p in ed.check_scene(s)[0]]
    assert len(found) == 2 and all(p.startswith("exact.sif[0]") for p in found), found
    assert "K_I = 0.5" in found[0] and "K_II = 1" in found[1], found
    s = copy.deepcopy(exported["elastic-griffith"])
    s["exact"]["sif"] = s["exact"]["sif"][:1]
    assert "2 tip(s)" in keys(s)["exact.sif"]


def test_the_closed_cracks_k_i_is_not_a_pressure_artefact(exported):
    """K_I = 0 of the closed crack with slip holds to its tolerance; the K_I a face pressure of the
    field's size would give if read as a singularity (0.1) does not."""
    s = copy.deepcopy(exported["elastic-closed-slip"])
    s["exact"]["sif"] = [[0.1, 1.0]]
    fails(s, "exact.sif[0]", "K_I = 0.1")


# ------------------------------------------------------------------------- the verdict

def test_a_results_folder_with_a_wrong_scene_blames_the_scene(tmp_path):
    """The synthetic Williams folder (every reference the interpolant: a PASS) with the scene's
    K_I written as 2: FAIL, cause the scene, the series not judged, the key in the report."""
    exact = es.williams(1.0, 0.0)
    exact["sif"] = [[2.0, 0.0]]
    folder = es.write_results(tmp_path / "w", exact=exact, levels=(0, 1, 2, 3))
    a = elastic.analyse(elastic_read.load(str(folder)))
    assert a["verdict"] == "FAIL" and a["verdict_cause"] == "scene", a["reasons"]
    assert [p.key for p in a["exact_data"]] == ["exact.sif[0]"]
    rows = {label: (p, na) for label, _, p, na in a["checks"]}
    assert rows["series"][0] == [] and rows["series"][1].startswith("not judged")
    assert all(r.startswith("exact data: exact.sif[0]") for r in a["reasons"]), a["reasons"]
    code, out, err = run_cli(folder)
    assert code == 1, out + err
    assert "FAIL (cause: the scene" in out.strip().splitlines()[-1]
    rep = json.loads((folder / "report" / "report.json").read_text())
    assert rep["verdict"] == "FAIL" and rep["verdict_cause"] == "scene"
    assert rep["exact_data"][0]["key"] == "exact.sif[0]"
    assert "off by 1" in rep["exact_data"][0]["problem"]
    md = (folder / "report" / "report.md").read_text()
    assert "exact.sif[0] gives K_I = 2" in md


def test_a_correct_folder_has_no_cause_and_a_damaged_one_blames_the_results(tmp_path):
    folder = es.write_results(tmp_path / "ok", levels=(0, 1, 2, 3))
    a = elastic.analyse(elastic_read.load(str(folder)))
    assert a["verdict"] == "PASS" and a["verdict_cause"] is None and a["exact_data"] == []
    rows = {label: p for label, _, p, _ in a["checks"]}
    assert rows["exact data"] == []

    bad = es.write_results(tmp_path / "bad", levels=(0, 1, 2, 3),
                           perturb=lambda xy: 0.01 * (xy ** 2))
    a = elastic.analyse(elastic_read.load(str(bad)))
    assert a["verdict"] == "FAIL" and a["verdict_cause"] == "results"


def test_a_malformed_scene_json_is_bad_input(tmp_path):
    folder = es.write_results(tmp_path / "w", levels=(0, 1, 2))
    path = folder / "mesh" / "scene.json"
    scene = json.loads(path.read_text())
    scene["exact"]["sxx"] = "1 +"
    path.write_text(json.dumps(scene))
    code, out, err = run_cli(folder)
    assert code == 2 and err.count("\n") == 1 and "exact.sxx" in err, out + err
    assert not (folder / "report").exists()


def test_malformed_entries_are_scene_errors(exported):
    for change in (lambda s: s["exact"].update(sif=[[1.0]]),
                   lambda s: s["exact"].update(sif="1"),
                   lambda s: s.update(fixed=[{"point": [1.0], "components": ["x"]}]),
                   lambda s: s.update(f=["0"]),
                   lambda s: s.update(domain={"circle": 1})):
        s = copy.deepcopy(exported["elastic-williams-open"])
        change(s)
        with pytest.raises(ed.SceneError, match="^scene.json: "):
            ed.check_scene(s)
