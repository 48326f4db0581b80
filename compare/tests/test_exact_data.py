"""The scene's exact data are checked before any series is judged against them (issue 42,
sdcompare_lib/exactdata.py): px, py against ∂u/∂x, ∂u/∂y; f against −Δu; g against u on ∂Ω;
jump against u⁺ − u⁻; the contact conditions. Every scene of the repository and of the tests
passes; the four bad scenes of tests/data/scenes/bad-exact/ (the same ones `sdcrack check`
refuses, tests/bad_input.rs) each fail naming the field and a point; and on a results folder
whose scene.toml carries such data the report names the scene as the cause, first, and does not
blame the solver's series.

Run: /usr/bin/python3 -m pytest compare/tests/test_exact_data.py -q
"""
import glob
import json
import os
import re
import subprocess
import sys
import tomllib

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

import synthetic_results as sr
from sdcompare_lib import exactdata
from sdshared import sdexpr

SCRIPT = os.path.join(os.path.dirname(HERE), "sdcompare")
BAD = {  # file: (the field named, the words of the problem)
    "px-sign.toml": ("px", "is not ∂u/∂x"),
    "f-term.toml": ("f", "is not −Δu"),
    "jump-sign.toml": ("jump", "is not u⁺ − u⁻"),
    "g-side.toml": ("g", "is not its [exact] u on ∂Ω"),
}
POINT = re.compile(r"at \(-?[0-9.e+-]+, -?[0-9.e+-]+\)")


def load(path):
    with open(path, "rb") as fh:
        return tomllib.load(fh)


def all_good_scenes():
    """Every scene file of the repository and of the tests that has [exact], and the synthetic
    fixtures' solutions."""
    files = [f for f in sorted(glob.glob(os.path.join(ROOT, "scenes", "*.toml"))
                               + glob.glob(os.path.join(ROOT, "tests", "data", "scenes", "*.toml")))
             if os.path.basename(f) not in ("expectations.toml", "orders.toml")]
    scenes = [(os.path.relpath(f, ROOT), load(f)) for f in files]
    for name, sol in (("synthetic OPEN", sr.OPEN), ("synthetic CLOSED", sr.CLOSED)):
        text = sr.scene_text("s", sol, [0, 1], ["broken"], ["M1"], ["consistent"], None, [0.0],
                             False)
        scenes.append((name, tomllib.loads(text)))
    return scenes


@pytest.mark.parametrize("name,scene", all_good_scenes(), ids=lambda v: v if isinstance(v, str) else "")
def test_every_scene_of_the_repository_and_the_tests_passes(name, scene):
    problems, _ = exactdata.check_scene(scene)
    assert problems == [], f"{name}: {problems}"


def test_the_good_scenes_include_every_exact_scene():
    names = [n for n, s in all_good_scenes() if "exact" in s]
    for n in ("scenes/open-exact.toml", "scenes/open-graded.toml", "scenes/closed-exact.toml",
              "scenes/kinked-exact.toml", "scenes/two-cracks-exact.toml", "scenes/open-smooth.toml",
              "tests/data/scenes/open-smooth-inclined.toml"):
        assert n in names


@pytest.mark.parametrize("file", sorted(BAD))
def test_each_bad_scene_fails_naming_its_field_and_a_point(file):
    problems, _ = exactdata.check_scene(load(os.path.join(ROOT, "tests", "data", "scenes",
                                                          "bad-exact", file)))
    field, words = BAD[file]
    assert problems, file
    first = problems[0]
    assert first.startswith("the scene's"), first
    assert f" {field} " in first and words in first, first
    assert POINT.search(first), first


def test_each_bad_scene_differs_from_its_good_scene_in_one_field_only():
    good = {"closed": load(os.path.join(ROOT, "scenes", "closed-exact.toml")),
            "open": load(os.path.join(ROOT, "scenes", "open-smooth.toml"))}
    for file in BAD:
        bad = load(os.path.join(ROOT, "tests", "data", "scenes", "bad-exact", file))
        base = good["closed" if file == "g-side.toml" else "open"]
        diff = [(t, k) for t in ("data", "exact") for k in set(bad[t]) | set(base[t])
                if bad[t].get(k) != base[t].get(k)]
        assert len(diff) == 1, (file, diff)


def test_the_contact_conditions_fail_on_an_exact_solution_that_breaks_them():
    """u = −sign(y)·(…) has [u] < 0 with a consistent jump; u = y (closed, no jump) has
    ∂u/∂ν = 1 > 0; u = sign(y)·W − y is open and loaded (∂u/∂y = −1 on both faces); u = −y − |y|/2
    (a kink across the closed crack, ∂u/∂y = −3/2 and −1/2) breaks [∂u/∂ν] = 0."""
    def scene(u, jump=None, f="0"):
        s = {"geometry": {"domain": {"rectangle": [[-1, -1], [1, 1]]},
                          "crack": {"segment": [[-0.5, 0.0], [0.5, 0.0]]}},
             "data": {"f": f, "g": u}, "exact": {"u": u}}
        if jump is not None:
            s["exact"]["jump"] = jump
        return s

    w = "max(0.25 - x^2, 0)^3"
    cases = [
        (scene(f"-sign(y)*{w}", f"-2*{w}", f"sign(y)*(-6*max(0.25 - x^2, 0)^2 + 24*x^2*max(0.25 - x^2, 0))"),
         "breaks [u] ≥ 0"),
        (scene("y"), "breaks ∂u/∂ν ≤ 0"),
        (scene(f"sign(y)*{w} - y", f"2*{w}",
               "-sign(y)*(-6*max(0.25 - x^2, 0)^2 + 24*x^2*max(0.25 - x^2, 0))"),
         "breaks [u]·∂u/∂ν = 0"),
        (scene("-y - abs(y)/2", "0"), "breaks [∂u/∂ν] = 0"),
    ]
    for s, words in cases:
        problems, _ = exactdata.check_scene(s)
        assert problems and all(words in p for p in problems), (s["exact"], problems)
        # and each problem is the one intended: no other field is blamed
        assert not any("is not" in p for p in problems), problems


def test_the_round_off_bound_covers_the_error_and_is_not_loose():
    """The running bound of −Δu of open-exact's u (harmonic: the exact value is 0, so the computed
    one is pure round-off) bounds it at every sampled point, and is within 10⁴ of it."""
    sc = load(os.path.join(ROOT, "scenes", "open-exact.toml"))
    u = sdexpr.parse(sc["exact"]["u"])
    pts = exactdata.interior_points(exactdata.scene_polygon(sc), [np.array([[-0.5, 0], [0.5, 0]])])
    uxx, exx = exactdata.bounded(sdexpr.derivative(sdexpr.derivative(u, "x"), "x"), *pts.T)
    uyy, eyy = exactdata.bounded(sdexpr.derivative(sdexpr.derivative(u, "y"), "y"), *pts.T)
    err, bound = np.abs(uxx + uyy), exx + eyy
    assert np.all(err <= bound)
    assert np.median(bound) < 1e4 * max(np.median(err), 1e-300)


def judge(folder, tmp_path):
    exps = tmp_path / "exps.toml"
    exps.write_text("")
    p = subprocess.run([sys.executable, SCRIPT, str(folder), "--expectations", str(exps),
                        "--replace"], capture_output=True, text=True)
    with open(os.path.join(folder, "report", "report.json"), encoding="utf-8") as fh:
        r = json.load(fh)
    with open(os.path.join(folder, "report", "report.md"), encoding="utf-8") as fh:
        return p.returncode, r, fh.read(), p.stdout


# The four bad data on the synthetic open crack's scene.toml (the solver's fields are those of the
# good exact solution): each swaps one field of the scene file the results folder keeps.
SYNTHETIC_BAD = {
    "px": lambda t: t.replace('jump = "', 'px = "6*x*sign(y)*max(0.25-x^2,0)^2*cos(y)"\njump = "', 1),
    "f": lambda t: t.replace("- 24*x^2*max(0.25-x^2,0)", "- 12*x^2*max(0.25-x^2,0)", 1),
    "jump": lambda t: t.replace('jump = "2*', 'jump = "-2*', 1),
    "g": lambda t: t.replace('g = "sign(y)', 'g = "max(x - 0.999, 0) + sign(y)', 1),
}


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    return sr.write_results(str(tmp_path_factory.mktemp("exactdata")), "exactdata",
                            p_spaces=("continuous",))


def test_a_good_scene_has_its_exact_data_checked_and_no_cause_of_failure(synthetic, tmp_path):
    rc, r, md, _ = judge(synthetic, tmp_path)
    row = r["checks"][0]
    assert row["check"] == "exact data" and row["status"] == "ok", row
    assert r["verdict"] == "PASS" and r["verdict_cause"] is None, r["reasons"]
    # every check the exact data can leave not judged is a check of the report (names that drift
    # would silently judge the solver against wrong data)
    assert set(exactdata.JUDGED_AGAINST_EXACT) <= {c["check"] for c in r["checks"]}


@pytest.mark.parametrize("field", sorted(SYNTHETIC_BAD))
def test_bad_exact_data_fail_with_the_scene_as_the_cause_before_any_series(synthetic, tmp_path, field):
    scene = os.path.join(synthetic, "scene.toml")
    with open(scene, encoding="utf-8") as fh:
        good = fh.read()
    bad = SYNTHETIC_BAD[field](good)
    assert bad != good
    try:
        with open(scene, "w", encoding="utf-8") as fh:
            fh.write(bad)
        rc, r, md, out = judge(synthetic, tmp_path)
    finally:
        with open(scene, "w", encoding="utf-8") as fh:
            fh.write(good)
    assert rc == 1 and r["verdict"] == "FAIL" and r["verdict_cause"] == "scene"
    assert r["reasons"][0].startswith(f"exact data: the scene's [") and f" {field} " in r["reasons"][0]
    assert POINT.search(r["reasons"][0])
    # no check judged against the exact solution blames the solver (the swapped scene.toml also
    # makes sdcrack's reported errors differ from the recomputation with the new data: the
    # independent errors check stands, after the exact data)
    assert not [x for x in r["reasons"]
                if x.split(":")[0] in exactdata.JUDGED_AGAINST_EXACT], r["reasons"]
    assert r["checks"][0]["check"] == "exact data" and r["checks"][0]["status"] == "FAIL"
    series = next(c for c in r["checks"] if c["check"] == "series")
    assert series["status"].startswith("not judged: the scene's exact data are inconsistent")
    # the headline names the scene first, in the report and on the terminal
    summary = md[md.index("**Verdict:"):]
    assert summary.startswith("**Verdict: FAIL (cause: the scene:"), summary[:200]
    assert "FAIL (cause: the scene:" in out.splitlines()[-1]
    assert md.index("exact data") < md.index("| series |")
