"""The first screen's sentences (sdcompare_lib/glance.py) come from the data and
come out the other way on data that make them false: a δ check with a problem turns the δ → 0
line to FAIL; a forged error moves the ratio; a variant that stops converging leaves the
"converging variants" group; no references says so."""
import math
import os

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))

from sdcompare_lib import glance, refyard

LEVELS = [2, 3, 4]
H = [0.25, 0.125, 0.0625]


def series(u, m, errors, status="converges"):
    return {"u_space": u, "multiplier": m, "p_mass": "consistent", "p_space": "continuous",
            "quantity": "u_l2", "status": status, "against": "exact", "levels": LEVELS,
            "h": H, "errors": errors}


def analysis(series_list, checks=None, delta_limit=None):
    return {"exact": object(), "graded": False, "series": series_list,
            "checks": checks if checks is not None else [
                ("δ → 0", "slopes 1", [], None), ("δ-constant", "settles", [], None),
                ("Theorem 2.1 (exact)", "floor", [], None)],
            "delta_limit": delta_limit if delta_limit is not None else [
                {"points_fitted": 3, "slope": 0.99}, {"points_fitted": 3, "slope": 1.01}]}


def results(tools=("dolfinx", "freefem")):
    cases = [{"level": lv, "h": h, "unknowns": 100 * 4 ** lv} for lv, h in zip(LEVELS, H)]
    return {"refs": {t: {"summary": {"cases": cases}} for t in tools}}


# the references' own errors: rate 2 in h
REF = {(lv, "u_l2"): 0.01 * h ** 2 / H[0] ** 2 for lv, h in zip(LEVELS, H)}


@pytest.fixture(autouse=True)
def reference_errors(monkeypatch):
    monkeypatch.setattr(refyard, "reference_inputs",
                        lambda res, a, tool: (dict(REF), list(a["series"])))


def good():
    return [series("broken", "M1", [2 * REF[(lv, "u_l2")] for lv in LEVELS]),
            series("broken", "M0", [REF[(lv, "u_l2")] for lv in LEVELS]),
            series("continuous", "M1", [0.5, 0.5, 0.5], "expected failure")]


def test_ratios_and_rates_come_from_the_errors():
    g = glance.summary(results(), analysis(good()))
    assert g["level"] == 4 and g["against"] == "exact"
    by = {r["variant"]: r for r in g["rows"]}
    assert by["broken/M1"]["refs"]["dolfinx"]["ratio"] == pytest.approx(2.0)
    assert by["broken/M1"]["rate"] == pytest.approx(2.0)
    assert by["broken/M1"]["refs"]["freefem"]["rate"] == pytest.approx(2.0)
    text = " ".join(glance.first_screen(g))
    assert "converging variants (2): 1–2× either reference, rates 2.00" in text
    assert "declared expected failures (1)" in text
    assert "**δ → 0 (Theorem 2.1): PASS**" in text and "slopes 0.990–1.010 over 2 fits" in text


def test_a_forged_error_moves_the_ratio_and_the_rate():
    s = good()
    s[0]["errors"][-1] *= 3  # broken/M1 at level 4: 6× the reference's, rate 2 - log2(3)
    g = glance.summary(results(), analysis(s))
    row = next(r for r in g["rows"] if r["variant"] == "broken/M1")
    assert row["refs"]["dolfinx"]["ratio"] == pytest.approx(6.0)
    assert row["rate"] == pytest.approx(2 - math.log2(3))
    assert "1–6× either reference" in glance.reference_sentence(g)
    assert "largest: broken/M1 6×" in glance.extremes_sentence(g)


def test_a_variant_that_stops_converging_leaves_the_converging_group():
    s = good()
    s[0]["status"] = "does not converge"
    text = glance.reference_sentence(glance.summary(results(), analysis(s)))
    assert "converging variants (1)" in text and "other variants (1): 2×" in text


def test_a_delta_check_with_a_problem_turns_the_line_to_fail():
    checks = [("δ → 0", "slopes 1", ["broken/M1 u_l2 level 3: slope 0.5"], None),
              ("δ-constant", "settles", [], None)]
    d = glance.summary(results(), analysis(good(), checks=checks))["delta"]
    assert d["status"] == "FAIL"
    assert d["text"].startswith("δ → 0 (Theorem 2.1): FAIL — 1 problem(s); first, δ → 0: "
                                "broken/M1 u_l2 level 3: slope 0.5")
    assert "PASS" not in " ".join(glance.first_screen(glance.summary(
        results(), analysis(good(), checks=checks))))


def test_delta_not_applicable_says_why():
    checks = [("δ → 0", "slopes", [], "the run has one δ (0): no sweep"),
              ("δ-constant", "settles", [], "the run has one δ: no sweep")]
    d = glance.delta_outcome(analysis(good(), checks=checks))
    assert d == {"status": "not applicable",
                 "text": "δ → 0 (Theorem 2.1): not applicable — the run has one δ (0): no sweep"}


def test_references_that_differ_are_named_apart(monkeypatch):
    ref_b = {k: 2 * v for k, v in REF.items()}

    def inputs(res, a, tool):
        return (dict(REF) if tool == "dolfinx" else dict(ref_b)), list(a["series"])
    monkeypatch.setattr(refyard, "reference_inputs", inputs)
    text = glance.reference_sentence(glance.summary(results(), analysis(good())))
    assert "1–2× / 0.5–1×" in text and "either reference" not in text.split(";")[0]


def test_no_references_says_so():
    g = glance.summary(results(tools=()), analysis(good()))
    assert g["level"] is None and g["rows"] == []
    assert any(p.startswith("**No reference run**") for p in glance.first_screen(g))


def test_reference_curves_carry_the_references_errors():
    curves = glance.reference_series(results(), analysis(good()))
    u = [c for c in curves if c["quantity"] == "u_l2"]
    assert [c["tool"] for c in u] == ["dolfinx", "freefem"]
    assert u[0]["h"] == H and u[0]["errors"] == [REF[(lv, "u_l2")] for lv in LEVELS]
    assert u[0]["label"] == "dolfinx: its error"


def test_index_line_follows_the_data():
    g = glance.summary(results(), analysis(good()))
    assert g["line"] == ("u at level 4 ÷ dolfinx, FreeFEM: converging variants 1–2× either "
                         "reference (rates 2.00 vs 2.00); declared expected failures 800× "
                         "either reference; δ → 0: PASS")
    s = good()
    s[0]["errors"][-1] *= 3
    checks = [("δ → 0", "slopes", ["a slope 0.5"], None)]
    g = glance.summary(results(), analysis(s, checks=checks))
    assert "converging variants 1–6× either reference (rates 0.42–2.00 vs 2.00)" in g["line"]
    assert g["line"].endswith("; δ → 0: FAIL")
    assert glance.summary(results(tools=()), analysis(good()))["line"] == \
        "no references; δ → 0: PASS"


def test_without_an_exact_solution_the_sentences_name_the_finest_level_and_its_bias():
    a = analysis(good())
    a["exact"] = None
    g = glance.summary(results(), a)
    assert g["against"] == "reference finest level"
    assert "distances to each reference's finest level" in glance.reference_sentence(g)
    assert glance.FINEST_CAVEAT in glance.reference_sentence(g)
    assert g["line"].startswith("u at level 4 ÷ dolfinx, FreeFEM (distances to their finest "
                                "level): ")
    exact = glance.summary(results(), analysis(good()))
    assert glance.FINEST_CAVEAT not in glance.reference_sentence(exact)
