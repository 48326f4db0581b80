"""Sentences of the report and of the campaign index that once were false of their numbers (issue
42), each made false on constructed data here and shown to change with it:

* the regularity's "smooth" of a u whose gradient is unbounded at a crack tip (open-graded: graded
  meshes give it the smooth interpolation rate);
* "ok" of a check that checked nothing (reference status of 0 cases, δ → 0 without a fit, …);
* a plot caption's "every point within 2 %" over lines 6.0–6.8 % apart;
* one mesh at different x for different solvers on the h → 0 plot (each its own unknowns);
* one range of ratios to the references across both p spaces (0.41–1.04×, where the
  broken-tangential p stood at 0.41–0.47×).

Run: /usr/bin/python3 -m pytest compare/tests/test_checked_sentences.py -q
"""
import json
import math
import os
import subprocess
import sys
import tomllib
from types import SimpleNamespace

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SCRIPT = os.path.join(os.path.dirname(HERE), "sdcompare")

import synthetic_results as sr
from sdcompare_lib import checks, exact, glance, plots, sections, theory, yardsticks


def scene(name):
    with open(os.path.join(ROOT, "scenes", f"{name}.toml"), "rb") as fh:
        return tomllib.load(fh)


# ------------------------------------------------------------------ "smooth" of a singular u
def growth_of(name):
    sf = scene(name)
    return yardsticks.gradient_growth(exact.ExactSolution.from_scene(sf), sf)


def test_the_tip_singularity_is_measured_where_it_is_and_not_where_it_is_not():
    """open-graded's u = Im sqrt((z − 1/2)(z + 1/2)): |∇u| ~ r^-1/2 at both tips; closed-exact's
    u is smooth: |∇u| bounded at every crack node and domain corner."""
    g = growth_of("open-graded")
    assert g["exponent"] == pytest.approx(0.5, abs=0.01)
    assert g["point"] in ((-0.5, 0.0), (0.5, 0.0))
    assert growth_of("closed-exact")["exponent"] < 0.01
    assert growth_of("open-smooth")["exponent"] < 0.01


def test_a_singular_u_with_the_smooth_interpolation_rate_is_not_called_smooth():
    singular = growth_of("open-graded")
    s, reason = theory.regularity(1.13, growth=singular, graded=True)
    assert s == theory.SMOOTH_S  # the order: P1's, as the interpolation rate says
    assert reason.startswith("singular exact u (|∇u| grows as r^-0.50 towards (")
    assert "smooth" not in reason
    assert "rate 1.13 ≥ 0.9 per halving of h on these graded meshes: P1's orders apply" in reason
    # the same rate with a bounded gradient: smooth, and said so with what was measured
    s, reason = theory.regularity(1.13, growth=growth_of("closed-exact"))
    assert s == theory.SMOOTH_S and reason.startswith("smooth exact u (|∇u| grows no faster than")
    # a singular u below the rate: s = 1/2, singular; a bounded one below it is not called singular
    assert theory.regularity(0.5, growth=singular)[1].startswith("singular exact u")
    bounded = theory.regularity(0.5, growth=growth_of("closed-exact"))
    assert bounded[0] == theory.SINGULAR_S and bounded[1].startswith("exact u with bounded gradient")
    assert "singular" not in bounded[1]


# ------------------------------------------------------------------ "ok" of nothing checked
@pytest.fixture(scope="module")
def no_references(tmp_path_factory):
    """A synthetic folder without references, one δ > 0 (1e-2) and an expectations file without
    its scene: four checks with nothing to check."""
    tmp = tmp_path_factory.mktemp("notrun")
    folder = sr.write_results(str(tmp), "notrun", p_spaces=("continuous",), u_spaces=("broken",),
                              xfail_continuous=False)
    exps = tmp / "exps.toml"
    exps.write_text("")
    p = subprocess.run([sys.executable, SCRIPT, folder, "--expectations", str(exps), "--quiet"],
                       capture_output=True, text=True)
    assert p.returncode == 0, p.stdout + p.stderr
    with open(os.path.join(folder, "report", "report.json"), encoding="utf-8") as fh:
        return json.load(fh)


def test_a_check_of_nothing_says_not_run_and_why(no_references):
    status = {c["check"]: c["status"] for c in no_references["checks"]}
    assert status["reference status"] == "not run: the scene asks for no reference"
    assert status["reference agreement"].startswith("not run: 0 reference(s) in the results "
                                                    "folder (none; the scene asks for none)")
    assert status["δ → 0"].startswith("not run: no variant has two δ > 0 with a difference above "
                                      "round-off (δ > 0: 1e-2)")
    assert status["expectations"] == "not run: the expectations file has no row for scene 'notrun'"
    # the checks that did check something still say ok
    assert status["solver KKT"] == status["series"] == "ok"
    assert no_references["verdict"] == "PASS"


def test_not_run_turns_to_ok_once_there_is_something_to_check():
    assert checks.not_run(0, "why") == "not run: why"
    assert checks.not_run(3, "why") is None
    assert checks.status_text([], checks.not_run(0, "no case")) == "not run: no case"
    assert checks.status_text([], checks.not_run(1, "no case")) == "ok"
    assert checks.status_text(["a problem"], checks.not_run(0, "no case")) == "FAIL"
    one = [{"points_fitted": 1, "slope": None, "residuals": [None]}]
    two = [{"points_fitted": 2, "slope": 1.0, "residuals": [0.01, -0.01]}]
    assert checks.delta_points_checked(one) == 0 and checks.delta_points_checked(two) == 3
    # the first screen's δ line says "not run" too, not "not applicable"
    a = {"checks": [("δ → 0", "slopes", [], checks.not_run(0, "no slope to fit"))],
         "delta_limit": []}
    assert glance.delta_outcome(a) == {"status": "not run",
                                       "text": "δ → 0 (Theorem 2.1): not run — no slope to fit"}


# ------------------------------------------------------------------ the coinciding-lines caption
def note_of(lines):
    """The rate plot's coincidence note for {label: (variant, [(x, y)])} drawn in panel p (X),
    beside a panel u where every line is apart (so none is one legend entry: the note names
    them)."""
    fig = plots.plt.figure()
    u, px = fig.add_subplot(1, 2, 1), fig.add_subplot(1, 2, 2)
    for k, (label, (_, pts)) in enumerate(lines.items()):
        px.loglog(*zip(*pts), label=label)
        u.loglog(*zip(*[(x, y * 2 ** k) for x, y in pts]), label=label)
    _, note = plots._coincidences({"u": u, "p (X)": px}, {k: v for k, (v, _) in lines.items()})
    plots.plt.close(fig)
    return note


def variant(m, pm):
    return ("broken", m, pm, "continuous")


def series_pts(scale, factor0=1.0):
    """Three levels of a series; its level-0 value times factor0."""
    return [(0.1, scale * factor0), (0.05, scale / 4), (0.025, scale / 16)]


def test_the_caption_states_the_spread_it_covers_and_names_the_consistent_p():
    """open-graded's p (X) at level 0: M0 and M1 1.7 % apart with the consistent p mass, 6.8 %
    with the lumped one. The note said "broken/{M0 = M1 = M1star} … (every point within 2 %)",
    read as covering the lumped lines too."""
    def note(lumped_m0):
        """The caption of broken M0 and M1 with each p mass, the lumped M0 at `lumped_m0`."""
        return note_of({"broken/M0": (variant("M0", "consistent"), series_pts(4.824)),
                        "broken/M1": (variant("M1", "consistent"), series_pts(4.744)),
                        "broken/M0/lumped": (variant("M0", "lumped"), series_pts(lumped_m0)),
                        "broken/M1/lumped": (variant("M1", "lumped"), series_pts(1.213))})

    assert note(1.296) == ("Lines on top of each other in p (X): broken/{M0 = M1}/consistent "
                           "(every point within 1.7 %).")
    # the lumped lines 1.5 % apart: they join, and the caption covers both p masses
    assert note(1.232) == ("Lines on top of each other in p (X): broken/{M0 = M1} with each p "
                           "mass (every point within 1.7 %).")


def test_lines_joined_through_a_third_are_said_as_far_apart_as_they_are():
    """A group joins a line within 2 % of its first one: two members 1.9 % either side of it are
    3.8 % apart, and the caption says so, not "2 %"."""
    note = note_of({"broken/M0": (variant("M0", "consistent"), series_pts(1.0)),
                    "broken/M1": (variant("M1", "consistent"), series_pts(1.0, 1.019)),
                    "broken/M1star": (variant("M1star", "consistent"), series_pts(1.0, 0.981))})
    assert note.endswith("broken/{M0 = M1 = M1star} (every point within 3.8 %).")
    assert plots._within(0.0) == "identical points"
    assert plots._within(0.01234) == "every point within 1.3 %"  # rounded up: it holds


# ------------------------------------------------------------------ one x per mesh
def graded_res_and_analysis():
    """open-graded's levels 0–1 as summary.json and the references have them: sdcrack's
    unknowns 250/251 (continuous, broken-tangential p) and 1082/1094, the references' 84 and 364
    (the vertices of the cracked mesh)."""
    vertices = {0: 84, 1: 364}
    cases = [{"level": lv, "u_space": "broken", "multiplier": "M1", "p_mass": "consistent",
              "p_space": ps, "h": 0.35 / 2 ** lv, "unknowns": n}
             for lv, ps, n in ((0, "continuous", 250), (0, "broken-tangential", 251),
                               (1, "continuous", 1082), (1, "broken-tangential", 1094))]
    ref_cases = [{"level": lv, "h": 0.35 / 2 ** lv, "unknowns": n} for lv, n in vertices.items()]
    mesh = {lv: SimpleNamespace(points=[(0.0, 0.0)] * n) for lv, n in vertices.items()}
    res = {"summary": {"cases": cases}, "data": None,
           "refs": {"dolfinx": {"summary": {"cases": ref_cases}, "mesh": mesh}}}
    series = [{"u_space": "broken", "multiplier": "M1", "p_mass": "consistent", "p_space": ps,
               "quantity": "u_l2", "levels": [0, 1], "errors": [0.05, 0.012],
               "h": [n0 ** -0.5, n1 ** -0.5],
               "rates": [math.log(0.05 / 0.012) / math.log((n1 / n0) ** 0.5)],
               "mesh_parameter": "N^-1/2"}
              for ps, n0, n1 in (("continuous", 250, 1082), ("broken-tangential", 251, 1094))]
    curves = [{"tool": "dolfinx", "quantity": "u_l2", "levels": [0, 1],
               "h": [84 ** -0.5, 364 ** -0.5], "errors": [0.04, 0.0095], "label": "dolfinx"}]
    return res, {"graded": True, "series": series, "reference_curves": curves}


def test_one_mesh_stands_at_one_x_for_every_solver():
    res, a = graded_res_and_analysis()
    # as measured, the same level-0 mesh stands at three x, sdcrack's √3 from the reference's
    assert len({s["h"][0] for s in a["series"]} | {a["reference_curves"][0]["h"][0]}) == 3
    series, curves, note = glance.plot_curves(res, a)
    for lv, n in ((0, 84), (1, 364)):
        assert {s["h"][lv] for s in series} | {curves[0]["h"][lv]} == {n ** -0.5}
    assert {s["mesh_parameter"] for s in series} == {glance.SHARED_PARAMETER}
    assert "unknowns at level 1: sdcrack 1082–1094 (by variant), dolfinx 364" in note
    # the tables' rates (the verdict's, per own unknowns) against the slopes drawn: said, measured
    drawn = math.log(0.05 / 0.012) / math.log((364 / 84) ** 0.5)
    gap = max(abs(drawn - s["rates"][0]) for s in a["series"])
    assert f"differ from the slopes drawn here by at most {gap:.2f}." in note
    # the series handed over keep their own rates (what the verdict judged)
    assert [s["rates"] for s in series] == [s["rates"] for s in a["series"]]


def test_uniform_levels_share_the_cases_h_and_unknown_meshes_say_so():
    res, a = graded_res_and_analysis()
    a["graded"] = False
    series, curves, note = glance.plot_curves(res, a)
    assert note is None and curves[0]["h"] == [0.35, 0.175] and series[0]["h"] == [0.35, 0.175]
    res["refs"] = {}  # graded, and neither a reference's mesh nor stored fields: no shared x
    a["graded"], a["reference_curves"] = True, []
    series, _, note = glance.plot_curves(res, a)
    assert series is a["series"] and note.startswith("x: each solver's own mesh parameter")


# ------------------------------------------------------------------ the index's ratios
def glance_rows():
    """open-graded at level 3: the continuous p at 0.894–1.04× the references' u error, the
    broken-tangential p at 0.41–0.469×."""
    def row(m, pm, ps, ratio, rate):
        return {"variant": f"broken/{m}", "u_space": "broken", "multiplier": m, "p_mass": pm,
                "p_space": ps, "status": "converges", "quantity": "u_l2", "error": ratio,
                "rate": rate, "refs": {t: {"error": 1.0, "rate": 2.12, "ratio": ratio}
                                       for t in ("dolfinx", "freefem")}}
    return [row("M1", "consistent", "continuous", 0.894, 0.59),
            row("M0", "consistent", "continuous", 0.899, 0.58),
            row("M1", "lumped", "continuous", 1.04, 0.56),
            row("M1", "consistent", "broken-tangential", 0.464, 2.19),
            row("M1", "lumped", "broken-tangential", 0.41, 2.21)]


def test_the_index_gives_the_ratios_per_p_space():
    g = {"level": 3, "against": "exact", "rows": glance_rows(),
         "delta": {"status": "PASS", "text": "δ → 0 (Theorem 2.1): PASS"}}
    line = glance.index_line(g)
    assert "0.41–1.04×" not in line  # the one range that mixed both p spaces
    assert line == ("u at level 3 ÷ dolfinx, FreeFEM: converging variants per p mass × p space, "
                    "÷ either reference: consistent/pcontinuous 0.894–0.899× (rates 0.58–0.59), "
                    "consistent/ptangential 0.464× (rates 2.19), lumped/pcontinuous 1.04× (rates "
                    "0.56), lumped/ptangential 0.41× (rates 2.21), the references' rates 2.12; "
                    "δ → 0: PASS")
    assert ("converging variants (5), per p mass × p space, ÷ either reference: "
            "consistent/pcontinuous 0.894–0.899× (rates 0.58–0.59)") in glance.reference_sentence(g)
    # one p mass and one p space: one range, as before
    g["rows"] = [r for r in g["rows"] if r["p_mass"] == "consistent"
                 and r["p_space"] == "continuous"]
    assert glance.index_line(g).startswith("u at level 3 ÷ dolfinx, FreeFEM: converging variants "
                                           "0.894–0.899× either reference (rates 0.58–0.59 vs "
                                           "2.12)")


# ------------------------------------------------------------------ the verdict's sentence
def test_the_verdict_without_a_problem_counts_what_it_says():
    """"Every series converges … and every check below holds" was printed over a smoke run's
    inconclusive series and over checks of 0 cases."""
    sentence = sections.no_problem_sentence
    a = {"series": [{"status": "converges"}] * 3 + [{"status": "expected failure"}],
         "checks": [("a", "", [], None), ("b", "", [], None)]}
    assert sentence(a) == ("No problem: of 4 series, 3 converge, 1 are declared expected "
                           "failures; of 2 checks, 2 hold (the table below).")
    a["series"] = [{"status": "inconclusive"}] * 2 + [{"status": "converges"}]
    a["checks"] += [("c", "", [], checks.not_run(0, "no case")), ("d", "", [], "no [exact]")]
    assert sentence(a) == ("No problem: of 3 series, 2 are inconclusive (a smoke run), 1 "
                           "converge; of 4 checks, 2 hold, 1 do not apply, 1 had nothing to "
                           "check (the table below).")
