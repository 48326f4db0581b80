"""The p-space axis: p "continuous" (the paper's MINI p) or "broken-tangential" (p's
tangential component one value per crack face at the interior vertices of a straight crack; broken
u only). On synthetic results folders (synthetic_results.py, no sdcrack binary) and synthetic
series: both p spaces are read as distinct series and reruns, the plan is the product minus
(continuous u, broken-tangential p), the broken-tangential p is held to P1's orders on the cracked
mesh whatever the crack does, and the absolute yardsticks apply to it on an open crack while they
stay not applicable to the continuous p there.

Run: /usr/bin/python3 -m pytest compare/tests/test_p_space.py -q
"""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))

import synthetic_results as sr
from sdcompare_lib import (cases, checks, exact, norms, plots, precomputed, read, render,
                           settings, theory, verdict, yardsticks)

SCRIPT = os.path.join(os.path.dirname(HERE), "sdcompare")
TANGENTIAL = "broken-tangential"


def judge(folder, tmp_path):
    """compare/sdcompare on `folder` (no expectations): (exit code, report.json, report.md)."""
    exps = tmp_path / "exps.toml"
    exps.write_text("")
    p = subprocess.run([sys.executable, SCRIPT, str(folder), "--expectations", str(exps),
                        "--quiet", "--replace"], capture_output=True, text=True)
    report = os.path.join(folder, "report")
    if not os.path.isdir(report):
        return p.returncode, None, p.stdout + p.stderr
    with open(os.path.join(report, "report.json"), encoding="utf-8") as fh:
        r = json.load(fh)
    with open(os.path.join(report, "report.md"), encoding="utf-8") as fh:
        return p.returncode, r, fh.read()


def check_of(r, name):
    return next(c for c in r["checks"] if c["check"] == name)


@pytest.fixture(scope="module")
def both(tmp_path_factory):
    """levels 0-2 × {continuous, broken} u × M1 × {consistent, lumped} × p spaces × δ {1e-2, 0}
    on the smooth open crack: 2 × 3 variants, 36 cases."""
    return sr.write_results(str(tmp_path_factory.mktemp("both")), "both",
                            p_masses=("consistent", "lumped"))


# ------------------------------------------------------------------ (a) read as distinct series
def test_both_p_spaces_are_distinct_series_complete_and_rerun_with_p_space(both, tmp_path):
    rc, r, md = judge(both, tmp_path)
    assert rc == 0 and r["verdict"] == "PASS", r and r["reasons"]
    keys = [(s["u_space"], s["multiplier"], s["p_mass"], s["p_space"], s["quantity"])
            for s in r["series"]]
    assert len(set(keys)) == len(keys) == 6 * 4  # 2 p masses × (2 broken + 1 continuous u)
    assert {k[2:4] for k in keys if k[0] == "broken"} == {
        (pm, ps) for pm in ("consistent", "lumped") for ps in ("continuous", TANGENTIAL)}
    assert not any(k[3] == TANGENTIAL for k in keys if k[0] == "continuous")
    assert check_of(r, "completeness")["status"] == "ok"
    # every solver error recomputed, the broken-tangential p per face from its own copies
    solver = [x for x in r["independent_errors"] if x["source"] == "sdcrack"]
    assert len(solver) == 36 and all(x["worst"] <= 1e-8 for x in solver)
    assert sum(x["p_space"] == TANGENTIAL for x in solver) == 12
    # one rerun command per level × variant: --p-space for the broken-tangential ones only
    reruns = {(k["level"], k["u_space"], k["p_mass"], k["p_space"]): k["rerun"] for k in r["kkt"]}
    assert len(set(reruns.values())) == 3 * 6
    for (lv, u, pm, ps), cmd in reruns.items():
        assert ("--p-space broken-tangential" in cmd) == (ps == TANGENTIAL), cmd
        assert cmd.endswith(f"both-l{lv}-{u}-M1" + ("-lumped" if pm == "lumped" else "")
                            + ("-ptangential" if ps == TANGENTIAL else "")), cmd
    # δ-limit fits, GCI, timings: one per variant, told apart by the p space
    for rows in (r["delta_limit"], r["gci"], r["timings"]):
        assert {x["p_space"] for x in rows} == {"continuous", TANGENTIAL}
    # the report shows the axis: a p space column, /ptangential labels, the rerun sentence
    assert "| u space | mult. | p mass | p space | status |" in md
    assert "broken/M1/ptangential (last rates" in md and "broken/M1/lumped/ptangential" in md
    assert "(u space × multiplier × p mass × p space × quantity)" in md
    assert "`--p-space broken-tangential`" in md


def test_a_continuous_p_folder_reads_as_before_the_axis(tmp_path):
    """A folder without any p_space key (an sdcrack older than the axis) and one whose keys all
    say "continuous" give the same report: no p space column or label, no p_space in report.json
    (byte-for-byte the report of before the axis; checked against the previous sdcompare by hand
    on these folders)."""
    reports = []
    for keys in (False, True):
        folder = sr.write_results(str(tmp_path / f"k{keys}"), "same", p_spaces=("continuous",),
                                  p_space_keys=keys)
        rc, r, md = judge(folder, tmp_path)
        assert rc == 0 and check_of(r, "completeness")["status"] == "ok", r["reasons"]
        assert "p space" not in md and "ptangential" not in md and "--p-space" not in md
        assert "p_space" not in json.dumps(r)
        # the discrete certificate's cost varies from run to run
        cost = ("seconds", "cpu_seconds")
        r["discrete_certificate"] = {k: v for k, v in r["discrete_certificate"].items()
                                     if k not in cost}
        reports.append(json.dumps({k: v for k, v in r.items() if k != "results_dir"})
                       .replace(str(tmp_path / f"k{keys}"), "OUT"))
    assert reports[0] == reports[1]


def test_the_plots_tell_the_p_spaces_apart():
    """Colour and line style differ between the p spaces of one u space, multiplier and p mass,
    and the label names the broken-tangential one."""
    base = {"u_space": "broken", "multiplier": "M1", "p_mass": "consistent"}
    (kc, lc), (kt, lt) = (plots._variant_style(dict(base, p_space=ps))
                          for ps in ("continuous", TANGENTIAL))
    assert kc["color"] != kt["color"] and kc["linestyle"] != kt["linestyle"]
    assert (lc, lt) == ("broken/M1", "broken/M1/ptangential")
    kl, ll = plots._variant_style(dict(base, p_mass="lumped", p_space=TANGENTIAL))
    assert ll == "broken/M1/lumped/ptangential" and kl["linestyle"] not in (kc["linestyle"],
                                                                             kt["linestyle"])


def test_rerun_command_of_a_broken_tangential_case():
    scene = {"discretization": {"deltas": [0.0]}}
    summary = {"scene": "s", "plan": {"deltas": [0.0]}, "provenance": {"executable": "/x/sdcrack"}}
    k = {"level": 2, "u_space": "broken", "multiplier": "M1", "delta": 0.0}
    assert render.rerun_command("/r/s", summary, scene, dict(k, p_space="continuous")) == \
        render.rerun_command("/r/s", summary, scene, k)
    assert render.rerun_command("/r/s", summary, scene, dict(k, p_mass="lumped",
                                                             p_space=TANGENTIAL)) == \
        ("env OMP_NUM_THREADS=1 GOTO_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 "
         "VECLIB_MAXIMUM_THREADS=1 NUMEXPR_NUM_THREADS=1 "
         "/x/sdcrack run /r/s/scene.toml --level 2 --u-space broken --multiplier M1 --p-mass "
         "lumped --p-space broken-tangential --out sdcrack-rerun/s-l2-broken-M1-lumped-ptangential")


def test_case_keys_labels_and_defaults():
    c = {"level": 1, "u_space": "broken", "multiplier": "M0", "delta": 0.0}
    assert cases.case_key(c) == cases.CaseKey(level=1, u_space="broken", multiplier="M0",
                                            p_mass="consistent", p_space="continuous", delta=0.0)
    assert cases.case_key(dict(c, p_space=TANGENTIAL)).p_space == TANGENTIAL
    assert cases.case_key(dict(c, p_mass="lumped", p_space=TANGENTIAL)).case_name() \
        == "level1-broken-M0-lumped-ptangential-delta0"
    assert cases.case_key(dict(c, delta=1e-2)).case_name() == "level1-broken-M0-delta1e-2"
    assert cases.case_key(dict(c, delta=1.0)).case_name() == "level1-broken-M0-delta1e0"
    assert cases.variant_label("broken", "M1") == "broken/M1"
    assert cases.variant_label("broken", "M1", "consistent", TANGENTIAL) == "broken/M1/ptangential"
    assert cases.variant_suffix("lumped", TANGENTIAL) == " lumped ptangential"
    assert cases.plan_p_spaces({"levels": []}) == ["continuous"]
    assert settings.scene_p_spaces({}) == ["continuous"]
    assert not cases.runs_together("continuous", TANGENTIAL)
    assert read.without_default_p_space({"a": [{"p_space": "continuous", "x": 1},
                                               {"p_space": TANGENTIAL}]}) == \
        {"a": [{"x": 1}, {"p_space": TANGENTIAL}]}


def test_cases_sort_in_the_reports_order_not_the_fields_order():
    """The reports list cases by level, u, multiplier, δ, then the p axes (CaseKey.order), though
    the key's fields are in the solver's order (p mass, p space before δ)."""
    c = {"level": 1, "u_space": "broken", "multiplier": "M0"}
    lumped_big = dict(c, delta=1.0, p_mass="lumped")
    consistent_small = dict(c, delta=1e-2, p_mass="consistent")
    want = [consistent_small, lumped_big]  # δ first: 1e-2 < 1
    assert sorted([lumped_big, consistent_small], key=cases.case_order) == want
    assert sorted([cases.case_key(x) for x in (lumped_big, consistent_small)]) \
        == [cases.case_key(x) for x in want]
    # positions would sort the other way (consistent < lumped decides first): a key compared
    # as a plain tuple of its fields fails the order above
    assert tuple(cases.case_key(lumped_big)) > tuple(cases.case_key(consistent_small))


# ------------------------------------------------------------------ (b) completeness
def completeness(folder):
    res = read.load_results(folder)
    try:
        return checks.completeness(res, res["scene_file"])
    finally:
        read.close_results(res)


@pytest.fixture
def small(tmp_path):
    """levels 0-2 × {continuous, broken} u × M1 × consistent × both p spaces × δ = 0."""
    return sr.write_results(str(tmp_path), "small", deltas=(0.0,))


def test_the_plan_is_the_product_minus_continuous_u_with_broken_tangential_p(small):
    s = sr.load_summary(small)
    assert len(s["cases"]) == 3 * 3  # 3 levels × (continuous/continuous, broken × 2 p spaces)
    assert completeness(small) == []


def test_a_missing_broken_tangential_case_is_incomplete(small):
    s = sr.load_summary(small)
    s["cases"] = [c for c in s["cases"] if not (c["level"] == 2 and c["p_space"] == TANGENTIAL)]
    sr.save_summary(small, s)
    problems = completeness(small)
    assert len(problems) == 1 and "1 case(s) asked for are missing" in problems[0]
    assert "level 2 broken M1 ptangential δ=0" in problems[0]


def test_a_continuous_u_with_the_broken_tangential_p_is_flagged(small):
    s = sr.load_summary(small)
    c = next(c for c in s["cases"] if c["u_space"] == "continuous" and c["level"] == 1)
    s["cases"].append(dict(c, p_space=TANGENTIAL))
    sr.save_summary(small, s)
    problems = completeness(small)
    assert any("pair the continuous u space with the broken-tangential p space, which sdcrack "
               "never runs" in p and "level 1 continuous M1 ptangential" in p for p in problems), \
        problems


def test_a_plan_whose_p_spaces_the_scene_lacks_is_flagged(small):
    """The scene copy asks for the continuous p alone, the plan (and the cases) has both."""
    path = os.path.join(small, "scene.toml")
    text = open(path, encoding="utf-8").read()
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(text.replace('p_spaces = ["continuous", "broken-tangential"]',
                              'p_spaces = ["continuous"]'))
    problems = completeness(small)
    assert any("the run's p_spaces ['broken-tangential'] are not in the scene file" in p
               for p in problems), problems


def test_a_case_without_its_p_space_reads_as_a_second_continuous_case(small):
    """A broken-tangential case that lost its `p_space` is a continuous one: listed twice, and its
    broken-tangential twin missing."""
    s = sr.load_summary(small)
    del next(c for c in s["cases"] if c["p_space"] == TANGENTIAL)["p_space"]
    sr.save_summary(small, s)
    problems = completeness(small)
    assert any("missing" in p and "ptangential" in p for p in problems)
    assert "summary.json lists a case twice" in problems


def test_a_p_space_that_differs_from_fields_h5_fails_the_independent_errors(small):
    import h5py

    s = sr.load_summary(small)
    c = next(c for c in s["cases"] if c["p_space"] == TANGENTIAL)
    with h5py.File(os.path.join(small, "fields.h5"), "r+") as f:
        f[f"cases/{c['fields_grid']}"].attrs["p_space"] = "continuous"
    res = read.load_results(small)
    try:
        _, problems = checks.independent_errors(res, res["scene_file"])
    finally:
        read.close_results(res)
    assert problems == [f"sdcrack's case level {c['level']} broken M1 ptangential δ=0 is of p "
                        f"space broken-tangential in summary.json but continuous in fields.h5 "
                        f"(/cases/{c['fields_grid']})"]


def test_the_precomputed_key_includes_the_p_space(small, monkeypatch):
    """The same arrays of another p space are another entry: the report never reads one p
    space's errors for the other."""
    import h5py

    c = next(c for c in sr.load_summary(small)["cases"] if c["p_space"] == TANGENTIAL)
    _, scene_file = read.load_scene_copy(small)
    ex = exact.ExactSolution.from_scene(scene_file)
    monkeypatch.setattr(precomputed, "STORE", precomputed.Store())
    with h5py.File(os.path.join(small, "fields.h5"), "r") as f:
        for ps in ("continuous", TANGENTIAL, TANGENTIAL):
            precomputed.solver_case_errors_h5(f, c["fields_grid"], ex, scene_file, "consistent", ps)
    assert (precomputed.STORE.computed, precomputed.STORE.hits) == (2, 1)


def test_a_broken_p_is_integrated_on_each_face_with_its_own_copy():
    """exact.py reads p per triangle through the cracked mesh's dofs: against a zero exact u
    (∇u = 0) its p_l2 is the exact P1 norm of the broken field (norms.p1_l2_norm, per triangle),
    which differs from the norm of the field with its copies merged."""
    meshes, crack, side = sr.level_meshes(0)
    pts, tris = meshes["broken"]
    p = np.random.default_rng(3).normal(size=(len(pts), 2))  # the copies differ, as p⁺ and p⁻
    zero = exact.ExactSolution("0", crack=sr.CRACK)
    got = exact.solver_case_errors(pts, tris, None, p, None, crack, None, zero, p_mass="lumped")
    assert got["p_l2"] == pytest.approx(norms.p1_l2_norm(pts, tris, p), rel=1e-12)
    merged = p.copy()
    rows = np.column_stack([np.flatnonzero(side > 0), np.flatnonzero(side < 0)])
    merged[rows[:, 1]] = merged[rows[:, 0]]
    assert abs(norms.p1_l2_norm(pts, tris, merged) - got["p_l2"]) > 1e-3 * got["p_l2"]


def test_expectations_name_the_p_space(tmp_path):
    scene_file = {"name": "s", "discretization": {"levels": [1, 2], "u_spaces": ["broken"],
                                                  "multipliers": ["M1"],
                                                  "p_spaces": ["continuous", TANGENTIAL]}}
    base = {"scene": "s", "u_space": "broken", "multiplier": "M1", "quantity": "u_l2", "level": 2,
            "max_error": 0.3}
    exps = verdict.validate_expectations([base, dict(base, p_space=TANGENTIAL),
                                          dict(base, p_space="*")], str(tmp_path / "e.toml"), "s",
                                         scene_file)
    series = [{"u_space": "broken", "multiplier": "M1", "p_mass": "consistent", "p_space": ps,
               "quantity": "u_l2", "levels": [1, 2], "h": [0.2, 0.1], "errors": [0.4, e]}
              for ps, e in (("continuous", 0.2), (TANGENTIAL, 0.35))]
    got = [(e["index"], e["variant"], e["status"])
           for e in verdict.check_expectations(series, exps)]
    assert got == [(0, "broken/M1", "ok"), (1, "broken/M1/ptangential", "violated"),
                   (2, "broken/M1", "ok"), (2, "broken/M1/ptangential", "violated")]
    with pytest.raises(ValueError, match="p_space 'broken' is none of"):
        verdict.validate_expectations([dict(base, p_space="broken")], str(tmp_path / "e.toml"),
                                      "s", scene_file)


# ------------------------------------------------------------------ (c) expected orders
LEVELS = [0, 1, 2, 3, 4]


def series_cases(rate, quantity, p_space, multiplier="M1", s=1.0):
    """Broken-u cases at δ = 0 whose `quantity` falls at `rate` per halving, the others at the
    broken-tangential p's orders for regularity s (so only `quantity` is judged)."""
    out = []
    for lv in LEVELS:
        errs = {"u_l2": 0.1 * 2.0 ** (-2 * s * lv), "p_l2": 0.1 * 2.0 ** (-s * lv),
                "p_x": 0.1 * 2.0 ** (-s * lv), "lambda_l2": 0.1 * 2.0 ** (-2 * s * lv)}
        errs[quantity] = 0.1 * 2.0 ** (-rate * lv)
        out.append({"level": lv, "h": 0.25 / 2 ** lv, "u_space": "broken",
                    "multiplier": multiplier, "delta": 0.0, "p_mass": "consistent",
                    "p_space": p_space, "errors": errs, "kkt": {}})
    return out


def judged(cases, s=1.0, closed=False, **verification):
    st = settings.verification({"discretization": {
        "levels": LEVELS, "u_spaces": ["broken"], "multipliers": ["M0", "M1", "M1star"],
        "deltas": [0.0]}, "verification": verification}, "scene.toml")
    return {(x["quantity"], x["p_space"]): x for x in verdict.compute_series(
        "t", cases, [], True, st, s, "test", crack_closed=closed)}


@pytest.mark.parametrize("s", [1.0, 0.5])
@pytest.mark.parametrize("closed", [True, False])
def test_broken_tangential_orders_are_p1s_whatever_the_crack_does(s, closed):
    """u 2s, p s (p_l2 and p_x), λ 2s for M1 and M1star, 1 (smooth) or 1/2 (tip) for M0, closed or open; the
    continuous p keeps its own orders (1/2 where the crack opens)."""
    for pm in ("consistent", "lumped"):
        got = {q: theory.expected_rate(q, "M1", pm, s, closed, TANGENTIAL)[0]
               for q in ("u_l2", "p_l2", "p_x", "lambda_l2")}
        assert got == {"u_l2": 2 * s, "p_l2": s, "p_x": s, "lambda_l2": 2 * s}
    assert theory.expected_rate("lambda_l2", "M1star", "consistent", s, closed, TANGENTIAL)[0] \
        == 2 * s
    assert theory.expected_rate("lambda_l2", "M0", "consistent", s, closed, TANGENTIAL)[0] \
        == (1.0 if s == 1.0 else 0.5)
    reason = theory.expected_rate("p_l2", "M1", "consistent", s, closed, TANGENTIAL)[1]
    assert "tangential jump of ∇u" in reason and "P1 on the cracked mesh" in reason
    assert theory.expected_rate("p_l2", "M1", "consistent", s, closed) == \
        theory.expected_rate("p_l2", "M1", "consistent", s, closed, "continuous")
    if not closed:
        assert theory.expected_rate("p_l2", "M1", "consistent", s, closed)[0] == 0.5


@pytest.mark.parametrize("quantity", ["u_l2", "p_l2", "p_x", "lambda_l2"])
def test_a_broken_tangential_series_at_one_half_fails_on_an_open_crack(quantity):
    """The same rate 0.5 on a smooth open crack: a continuous-p series passes (its order is 1/2
    there), a broken-tangential one fails (P1's order: u 2, p 1, λ 2)."""
    cont = judged(series_cases(0.5, quantity, "continuous"))[(quantity, "continuous")]
    tang = judged(series_cases(0.5, quantity, TANGENTIAL))[(quantity, TANGENTIAL)]
    assert cont["status"] == "converges", cont["reason"]
    assert tang["status"] == "does not converge" and verdict.series_fails(
        tang, {"smoke": False}), tang["reason"]
    assert tang["expected_rate"] == {"u_l2": 2.0, "lambda_l2": 2.0}.get(quantity, 1.0)
    good = judged(series_cases(tang["expected_rate"] - 0.05, quantity, TANGENTIAL))
    assert good[(quantity, TANGENTIAL)]["status"] == "converges"


def test_m0_lambda_of_the_broken_tangential_p_is_held_to_order_one():
    bad = judged(series_cases(0.8, "lambda_l2", TANGENTIAL, "M0"))[("lambda_l2", TANGENTIAL)]
    good = judged(series_cases(0.95, "lambda_l2", TANGENTIAL, "M0"))[("lambda_l2", TANGENTIAL)]
    assert bad["expected_rate"] == 1.0 and bad["status"] == "does not converge"
    assert good["status"] == "converges"


def test_a_scene_declares_an_order_for_one_p_space():
    decl = [{"u_space": "broken", "p_space": TANGENTIAL, "quantity": "p_l2", "rate": 0.5,
             "reason": "a kinked crack keeps p shared"}]
    got = judged(series_cases(0.5, "p_l2", TANGENTIAL), expected_rate=decl)[("p_l2", TANGENTIAL)]
    assert got["expected_rate"] == 0.5 and got["status"] == "converges"
    assert "declared in the scene" in got["expected_rate_reason"]
    # not for the other p space
    assert theory.declared_rate(settings.verification({"discretization": {
        "u_spaces": ["broken"]}, "verification": {"expected_rate": decl}}, "s")["expected_rates"],
        "broken", "M1", "consistent", "p_l2", "continuous") is None
    with pytest.raises(read.InputError, match="p_space = 'tangential' is none of"):
        settings.verification({"verification": {"expected_rate": [
            dict(decl[0], p_space="tangential", u_space="*")]}}, "s")


# ------------------------------------------------------------------ (d) yardsticks on an open crack
INTERP = {lv: {"h": 0.25 / 2 ** lv, "u_l2": 1e-3 / 4 ** lv, "grad_l2": 1e-2 / 2 ** lv,
               "grad_x": 2e-2 / 2 ** lv} for lv in range(3)}
REF = {"u_l2": 1e-3, "p_l2": 1e-2}  # the reference's own errors at level 0 (smooth: u h², p h)


def yard_series(p_space, factor):
    """Series of a smooth open crack against the exact solution: the continuous p's of order 1/2,
    or the broken-tangential p's of P1's order, `factor` × the interpolation (and reference)
    error."""
    out = []
    for q, key in (("u_l2", "u_l2"), ("p_l2", "grad_l2"), ("p_x", "grad_x")):
        expected = theory.expected_rate(q, "M1", "consistent", 1.0, False, p_space)[0]
        out.append({"u_space": "broken", "multiplier": "M1", "p_mass": "consistent",
                    "p_space": p_space, "quantity": q, "against": "exact", "status": "converges",
                    "expected_rate": expected, "levels": [0, 1, 2],
                    "errors": [factor * INTERP[lv][key] for lv in range(3)]})
    return out


def yardstick_checks(series, references=False, graded=False):
    """yardsticks.checks on a smooth (s = 1) open crack, on `graded` meshes or not; with
    `references`, dolfinx's own errors u 1e-3 h², p 1e-2 h recomputed (the independent rows)."""
    refs = {"dolfinx": {}} if references else {}
    res = {"refs": refs, "scene_file": {}, "summary": {"cases": []}, "plan": {"deltas": [0.0]}}
    independent = [{"source": "dolfinx", "level": lv, **{q: (None, v / (4 if q == "u_l2" else 2)
                                                            ** lv) for q, v in REF.items()}}
                   for lv in range(3)]
    a = {"exact": object(), "interpolation": INTERP, "regularity": 1.0, "crack_closed": False,
         "regularity_reason": "smooth", "series": series, "independent": independent,
         "agreement": [], "delta_limit": [], "graded": graded}
    out = yardsticks.checks(res, a, {"not_applicable": {}})
    return {label: (problems, na) for label, _, problems, na in out}, a["yardsticks"]


def test_the_yardsticks_apply_to_the_broken_tangential_p_on_an_open_crack():
    got, rows = yardstick_checks(yard_series(TANGENTIAL, 1.5), references=True)
    assert got["interpolation yardstick"] == ([], None)
    assert got["reference yardstick"] == ([], None)
    assert {r["p_space"] for r in rows["interpolation"] + rows["reference"]} == {TANGENTIAL}
    assert len(rows["interpolation"]) == 3 * 3 and len(rows["reference"]) == 2 * 3


def test_the_yardsticks_fail_a_broken_tangential_p_too_large_by_a_constant():
    """Rates kept (u 2, p 1), errors 10 × the interpolation error: both yardsticks fail it."""
    got, _ = yardstick_checks(yard_series(TANGENTIAL, 10.0), references=True)
    problems, na = got["interpolation yardstick"]
    assert na is None and {p.split(" at ")[0] for p in problems} == {
        f"broken/M1/ptangential {q}" for q in ("u_l2", "p_l2", "p_x")}
    problems, na = got["reference yardstick"]
    assert na is None and {p.split(" at ")[0] for p in problems} == {
        "broken/M1/ptangential u_l2", "broken/M1/ptangential p_l2"}


def test_the_yardsticks_stay_not_applicable_to_the_continuous_p_on_an_open_crack():
    """Continuous p alone: every expected order (1/2) is below P1's, and the check says so with the
    orders it compared; both p spaces: only the broken-tangential series are held to it."""
    got, rows = yardstick_checks(yard_series("continuous", 10.0), references=True)
    for label, p1 in (("interpolation yardstick", "P1 interpolation order"),
                      ("reference yardstick", "references'")):
        problems, na = got[label]
        assert problems == [] and na.startswith(f"every series' expected order is below the {p1}")
        assert "u_l2 0.5 < 2, p_l2 0.5 < 1" in na
    got, rows = yardstick_checks(yard_series("continuous", 10.0) + yard_series(TANGENTIAL, 1.5),
                                 references=True)
    assert got["interpolation yardstick"] == ([], None)
    assert {r["p_space"] for r in rows["interpolation"]} == {TANGENTIAL}


def test_on_graded_meshes_the_interpolation_yardstick_holds_p_l2_alone():
    """Graded meshes classify a tip-singular u as smooth, but only the energy-norm bound carries
    over (the references' own u error is 4-9 × the interpolation error on open-graded): u_l2 and
    p_x 10 × too large pass it there, p_l2 fails it; the reference yardstick keeps u and p."""
    got, rows = yardstick_checks(yard_series(TANGENTIAL, 10.0), references=True, graded=True)
    problems, na = got["interpolation yardstick"]
    assert na is None and [p.split(" at ")[0] for p in problems] == ["broken/M1/ptangential p_l2"]
    assert {r["quantity"] for r in rows["interpolation"]} == {"p_l2"}
    assert {p.split(" at ")[0] for p in got["reference yardstick"][0]} == {
        "broken/M1/ptangential u_l2", "broken/M1/ptangential p_l2"}
    got, _ = yardstick_checks(yard_series("continuous", 10.0), graded=True)
    problems, na = got["interpolation yardstick"]
    assert problems == [] and "(p_l2 0.5 < 1)" in na


def test_a_too_large_broken_tangential_p_fails_the_report(tmp_path):
    """End to end on the smooth open crack: the broken-tangential p off by a bubble c·h_T (its
    rates kept, its error ×~10 the interpolation error; the summary's errors recomputed from the
    fields, so only the yardstick can see it) FAILs the interpolation yardstick, and only it."""
    import h5py

    folder = sr.write_results(str(tmp_path), "slip", p_spaces=("continuous", TANGENTIAL),
                              deltas=(0.0,))
    s = sr.load_summary(folder)
    _, scene_file = read.load_scene_copy(folder)
    ex = exact.ExactSolution.from_scene(scene_file)
    with h5py.File(os.path.join(folder, "fields.h5"), "r+") as f:
        for c in s["cases"]:
            if c["p_space"] != TANGENTIAL:
                continue
            g = f[f"cases/{c['fields_grid']}"]
            del g["p_bubble"]
            g["p_bubble"] = np.full((len(g["mesh/triangles"]), 2), 0.5 * c["h"])
            c["errors"] = {k: v for k, v in exact.solver_case_errors_h5(
                f, c["fields_grid"], ex, p_mass="consistent").items() if k != "bubble"}
    sr.save_summary(folder, s)
    rc, r, _ = judge(folder, tmp_path)
    assert rc == 1 and r["verdict"] == "FAIL"
    assert {reason.split(":")[0] for reason in r["reasons"]} == {"interpolation yardstick"}, \
        r["reasons"]
    assert all("broken/M1/ptangential p_" in reason for reason in r["reasons"])
