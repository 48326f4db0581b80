"""The "independent errors" check's tolerance from estimated quadrature errors.

Two correct fixed-degree quadratures of a non-polynomial integrand differ by their quadrature
errors, beyond the former bare 1e-8 relative where the exact solution has kinks across the
triangles. The solver's summary.json now gives, per error, |e(rule) − e(higher rule)|
(`errors_quadrature`), this tool the same with its own rules, and a reported error r must be
within SAFETY·(est_sdcrack + est_ours) + round-off of this tool's o (checks.py). Here:

(a) a correct computation with a smooth non-polynomial exact solution whose kinks cross the
    triangles, where the two quadratures differ by more than 1e-8 relative at the coarsest level
    (asserted, so that the test keeps its point), PASSes the check: on a synthetic results folder
    (synthetic_results.py) whose "solver" is another correct rule with its own estimate, and on a
    real sdcrack run of tests/data/scenes/open-smooth-inclined.toml, levels 0-1 (skipped without
    the binary); without errors_quadrature (an older summary) the bare 1e-8 applies, the row says
    so, and the same correct run fails;
(b) the same folder with one reported error forged by a relative 1e-6 FAILs, blaming sdcrack;
(c) a bug in this tool's quadrature (its heaviest weight 1e-3 off, or every weight 1e-6 off)
    FAILs, and the problem lines blame the compare tool, never sdcrack (the former check said
    "sdcrack's reported errors differ"); a value of this tool damaged after the fact is named as
    this tool's by the arbiter, its higher-rule value;
and the self-check itself: monomials against the exact moments of the mesh's polygon (Green's
theorem on its boundary edges).

Run: /usr/bin/python3 -m pytest -q -p no:cacheprovider compare/tests/test_quadrature_tolerance.py
"""
import json
import os
import subprocess

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))

import synthetic_results as sr
from sdcompare_lib import checks, exact, norms, precomputed, read
from conftest import sdcrack_bin
from scene_text import square_scene

ROOT = os.path.dirname(os.path.dirname(HERE))
QUANTITIES = ("u_l2", "p_l2", "p_x", "lambda_l2")

# u = sign(y) W³ cos y, W = max(0.3 − x², 0): C² off the crack, kinked (in W³'s third derivative)
# at x = ±√0.3, which no grid line of the synthetic meshes (cells of 1/4, 1/8) holds, so the
# kinks cross the triangles; f = −Δu as for open-smooth.
KINKED = {"u": "sign(y)*max(0.3-x^2,0)^3*cos(y)", "jump": "2*max(0.3-x^2,0)^3",
          "f": "sign(y)*cos(y)*(max(0.3-x^2,0)^3 + 6*max(0.3-x^2,0)^2 - 24*x^2*max(0.3-x^2,0))"}
# smooth and closed everywhere (closed-exact's solution)
CLOSED = sr.CLOSED
# The "solver" of the synthetic folders: another correct rule (Stroud 6 × 6, tip 12, crack 8
# points) with its own higher rule for its estimate, as crates/sdcrack-core/src/norms.rs does with its own rules.
SOLVER_RULE = exact.Quadrature(n=6, tip_m=12, eta=1.0, line_n=8)


def fresh_caches(monkeypatch):
    """Empty caches of this tool's quadrature results (keyed by the quadrature's parameters, not
    by its code: a monkeypatched rule must not read results of the real one)."""
    monkeypatch.setattr(exact, "_MESH_QUADRATURE", norms.LastResults(2))
    monkeypatch.setattr(precomputed, "STORE", precomputed.Store())
    monkeypatch.setattr(checks, "_SELF_CHECKS", {})


def synthetic(tmp, name, solution):
    """A synthetic folder (broken u, M1, both p masses, levels 0-1, δ = 0) whose reported errors
    and errors_quadrature are SOLVER_RULE's on its fields: a correct solver with another rule.
    Returns (folder, {fields_grid: this tool's errors})."""
    folder = sr.write_results(str(tmp), name, solution=solution, levels=(0, 1),
                              u_spaces=("broken",), multipliers=("M1",),
                              p_masses=("consistent", "lumped"), p_spaces=("continuous",),
                              deltas=(0.0,), xfail_continuous=False)
    s = sr.load_summary(folder)
    ex = exact.ExactSolution(solution["u"], jump=solution["jump"], f=solution["f"], crack=sr.CRACK)
    ours = {}
    for c in s["cases"]:
        h5 = os.path.join(folder, "fields.h5")
        theirs = exact.solver_case_errors_h5(h5, c["fields_grid"], ex, SOLVER_RULE,
                                             p_mass=c["p_mass"])
        high = exact.solver_case_errors_h5(h5, c["fields_grid"], ex, SOLVER_RULE.higher(),
                                           p_mass=c["p_mass"])
        c["errors"] = {q: theirs[q] for q in QUANTITIES}
        c["errors_quadrature"] = {q: abs(theirs[q] - high[q]) for q in QUANTITIES}
        ours[c["fields_grid"]] = exact.solver_case_errors_h5(h5, c["fields_grid"], ex,
                                                             p_mass=c["p_mass"])
    sr.save_summary(folder, s)
    return folder, ours


def independent(folder):
    """(rows, problems, row text) of the "independent errors" check on `folder`."""
    res = read.load_results(folder)
    try:
        rows, problems = checks.independent_errors(res, res["scene_file"])
    finally:
        read.close_results(res)
    return rows, problems, checks.independent_text(rows, True)


def relative(a, b):
    scale = max(abs(a), abs(b))
    return abs(a - b) / scale if scale > 1e-13 else 0.0  # λ of the closed crack: 0


def worst_level0_difference(folder, ours):
    """The largest relative difference, at level 0, between the reported errors and this tool's."""
    s = sr.load_summary(folder)
    return max(relative(c["errors"][q], ours[c["fields_grid"]][q]) for c in s["cases"]
               if c["level"] == 0 for q in QUANTITIES)


def forge(folder, level, quantity, factor):
    """Multiplies one reported error (the first case of `level`) by `factor`; returns its case."""
    s = sr.load_summary(folder)
    c = next(c for c in s["cases"] if c["level"] == level)
    c["errors"][quantity] *= factor
    sr.save_summary(folder, s)
    return c


def drop_estimates(folder):
    s = sr.load_summary(folder)
    for c in s["cases"]:
        del c["errors_quadrature"]
    sr.save_summary(folder, s)


# ------------------------------------------------------------------ (a) correct runs pass
@pytest.fixture
def kinked(tmp_path, monkeypatch):
    fresh_caches(monkeypatch)
    return synthetic(tmp_path, "kinked", KINKED)


def test_a_correct_rule_on_kinks_across_triangles_passes(kinked):
    folder, ours = kinked
    # the point of the test: two correct quadratures differ by more than the former bare 1e-8
    assert worst_level0_difference(folder, ours) > 1e-7
    rows, problems, text = independent(folder)
    assert problems == []
    solver = [r for r in rows if r["source"] == "sdcrack"]
    assert len(solver) == 4 and all(r["tolerance_kind"] == "quadrature estimates" for r in solver)
    assert all(0.0 <= r["ratio"] <= 1.0 for r in solver)
    assert max(r["worst"] for r in solver) > 1e-7  # and the check saw that difference
    assert "within 4·(sdcrack's quadrature estimate + this tool's) + 1e-12 relative" in text
    assert "self-check" in text


def test_without_errors_quadrature_the_bare_1e8_applies_and_says_so(kinked):
    """An older summary.json (no errors_quadrature) is still read: the former bare 1e-8, named in
    the row, under which this correct computation fails (why the estimates exist)."""
    folder, _ = kinked
    drop_estimates(folder)
    rows, problems, text = independent(folder)
    assert "summary.json has no quadrature estimate (errors_quadrature" in text
    assert "the former bare tolerance applies" in text
    assert all(r["tolerance_kind"].startswith("bare 1e-08") for r in rows)
    assert problems and all("the bare 1e-08 relative: summary.json has no errors_quadrature" in p
                            for p in problems), problems


def test_an_old_summary_of_a_smooth_solution_passes_with_the_bare_tolerance(tmp_path, monkeypatch):
    fresh_caches(monkeypatch)
    folder, ours = synthetic(tmp_path, "closed", CLOSED)
    assert worst_level0_difference(folder, ours) < 1e-8
    drop_estimates(folder)
    _, problems, text = independent(folder)
    assert problems == [] and "former bare tolerance applies" in text


# ------------------------------------------------------------------ (b) a forged error fails
def test_an_error_forged_by_1e6_fails_and_blames_sdcrack(kinked):
    folder, _ = kinked
    # λ's integrand is smooth on the crack's segments (the kinks are off the crack): its tolerance
    # is round-off; u, p and p_x on the kinked triangles allow their estimated quadrature error,
    # ~1e-5 relative at level 0, above a forged 1e-6 (the check's resolution there).
    c = forge(folder, 0, "lambda_l2", 1 + 1e-6)
    rows, problems, _ = independent(folder)
    assert len(problems) == 1, problems
    p = problems[0]
    assert p.startswith(f"sdcrack's reported errors of level 0 broken M1 δ=0 differ from the "
                        f"independent computation by 1.0e-06 relative (lambda_l2:"), p
    assert "sdcrack's value is suspect" in p and "compare tool's value is suspect" not in p, p
    row = next(r for r in rows if r["source"] == "sdcrack" and r["level"] == 0
               and r["p_mass"] == c["p_mass"])
    assert row["ratio"] > 1.0


def test_a_forged_estimate_cannot_hide_a_forged_error(kinked):
    """A summary that inflates its own estimate to cover a forged error fails on the estimate."""
    folder, _ = kinked
    s = sr.load_summary(folder)
    c = s["cases"][0]
    c["errors"]["u_l2"] *= 1.01
    c["errors_quadrature"]["u_l2"] = 0.01 * c["errors"]["u_l2"]
    sr.save_summary(folder, s)
    _, problems, _ = independent(folder)
    assert any(p.startswith("sdcrack's quadrature is suspect: its estimate of the quadrature "
                            "error of u_l2 of level 0 broken M1") for p in problems), problems


# ------------------------------------------------------------------ (c) a bug of this tool
def compare_tool_bug(tmp_path, monkeypatch, bug):
    """The problems of the check on a correct synthetic folder of the smooth closed solution once
    this tool's Stroud rule is replaced by bug(rule) (for every n: its rule and its higher rule)."""
    fresh_caches(monkeypatch)
    folder, _ = synthetic(tmp_path, "closed", CLOSED)
    _, problems, _ = independent(folder)
    assert problems == []
    stroud = exact.stroud_rule
    fresh_caches(monkeypatch)
    monkeypatch.setattr(exact, "stroud_rule", lambda n: bug(*stroud(n)))
    _, problems, _ = independent(folder)
    assert problems, "the bug went unnoticed"
    for p in problems:
        assert "the compare tool's quadrature is suspect" in p, p
        assert "sdcrack's value is suspect" not in p, p
        assert "sdcrack's quadrature is suspect" not in p, p
    return problems


def test_a_weight_bug_in_the_compare_tools_rule_blames_the_compare_tool(tmp_path, monkeypatch):
    """The heaviest weight of this tool's Stroud rule 1e-3 too large: its rule and its higher
    rule then disagree (by 2e-5 of the area), which widens its own estimate over the bug, so the
    self-check is what catches it, on every mesh, blaming the compare tool."""
    def bug(L, W):
        W = W.copy()
        W[np.argmax(W)] *= 1 + 1e-3
        return L, W

    problems = compare_tool_bug(tmp_path, monkeypatch, bug)
    self_check = [p for p in problems if "integrates ξ^0 η^0" in p]
    assert len(self_check) == 4, problems  # 2 meshes (levels 0, 1) × (rule, higher rule)


def test_a_normalisation_bug_in_the_compare_tools_rule_blames_the_compare_tool(tmp_path,
                                                                              monkeypatch):
    """Every weight of this tool's Stroud rule 1e-6 too large (a normalisation slip): its rule
    and its higher rule move together, its errors leave the solver's beyond the tolerance (the
    former check said "sdcrack's reported errors differ"), and the lines blame the compare tool
    because its self-check fails."""
    problems = compare_tool_bug(tmp_path, monkeypatch, lambda L, W: (L, W * (1 + 1e-6)))
    differ = [p for p in problems if "differ from the independent computation" in p]
    assert differ, problems
    assert all(p.endswith("the compare tool's quadrature is suspect (it fails its self-check on "
                          "this mesh)") for p in differ), differ
    assert len([p for p in problems if "integrates ξ^0 η^0" in p]) == 4, problems


def test_a_precomputed_value_off_its_own_higher_value_blames_the_compare_tool(kinked,
                                                                             monkeypatch):
    """A stored value of this tool damaged (its higher-order value and estimate intact): the
    arbiter finds it, not sdcrack's, beyond its estimate from the higher-order value."""
    folder, _ = kinked
    independent(folder)  # fills the store
    key = next(iter(precomputed.STORE.entries))
    precomputed.STORE.entries[key]["lambda_l2"] *= 1 + 1e-6
    _, problems, _ = independent(folder)
    assert len(problems) == 1, problems
    assert "the compare tool's value is suspect" in problems[0], problems


# ------------------------------------------------------------------ the self-check
def test_polygon_moments_are_the_closed_forms_of_a_rectangle_with_a_cut():
    """Green's theorem on the boundary edges: the moments of [−1, 1]² (ξ = x) are
    ∫ x^a y^b = (1 − (−1)^{a+1})/(a + 1) · (1 − (−1)^{b+1})/(b + 1), on the cut mesh too (the two
    faces of the crack cancel)."""
    for u_space in ("continuous", "broken"):
        meshes, _, _ = sr.level_meshes(1)
        P, t = meshes[u_space]
        M = exact.polygon_moments(P, exact.boundary_edges(t, P), 10, (0.0, 0.0), 1.0)
        for a in range(11):
            for b in range(11 - a):
                want = ((1 - (-1) ** (a + 1)) / (a + 1)) * ((1 - (-1) ** (b + 1)) / (b + 1))
                assert abs(M[a, b] - want) <= 1e-14, (u_space, a, b, M[a, b], want)


def test_the_self_check_passes_the_rule_and_fails_a_moved_point(monkeypatch):
    meshes, crack, _ = sr.level_meshes(1)
    P, t = meshes["broken"]
    tips = [crack[0], crack[-1]]
    for r in exact.quadrature_self_check(P, t, tips):
        assert r["ok"] and r["worst"] <= 1e-14, r
    assert [r["degree"] for r in exact.quadrature_self_check(P, t, tips)] == [14, 22]
    tip_rule = exact.tip_rule

    def bad_tip(m, corner=0):
        L, W = tip_rule(m, corner)
        L = L.copy()
        k = int(np.argmax(W))  # the heaviest point, moved inside the triangle
        L[k] = L[k] + np.array([1e-6, -1e-6, 0.0])
        return L, W

    monkeypatch.setattr(exact, "tip_rule", bad_tip)
    bad = exact.quadrature_self_check(P, t, tips)
    assert not any(r["ok"] for r in bad), bad


def test_the_higher_rules_have_half_again_the_points():
    q = exact.Quadrature().higher()
    assert (q.n, q.tip_m, q.eta, q.line_n) == (12, 24, 1.0, 18)
    assert exact.Quadrature().degree() == 14 and q.degree() == 22


# ------------------------------------------------------------------ the real solver
@pytest.fixture(scope="module")
def inclined(tmp_path_factory):
    """sdcrack on tests/data/scenes/open-smooth-inclined.toml, levels 0-1, no references: its
    kinks run across the triangles (the nightly FAILed it under the bare 1e-8)."""
    if not os.access(sdcrack_bin(), os.X_OK):
        pytest.skip("no sdcrack binary (cargo build --release, or SDCRACK_BIN)")
    from scene_text import set_key

    tmp = tmp_path_factory.mktemp("inclined")
    with open(os.path.join(ROOT, "tests", "data", "scenes", "open-smooth-inclined.toml"),
              encoding="utf-8") as fh:
        text = fh.read()
    for key, value in (("levels", "[0, 1]"), ("references", "[]")):
        text = set_key(text, key, value)
    scene = tmp / "inclined.toml"
    scene.write_text(text)
    r = subprocess.run([sdcrack_bin(), "run", str(scene), "--out", str(tmp / "out"), "--quiet"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return tmp / "out" / "open-smooth-inclined"


def copy_of(folder, tmp_path):
    import shutil

    dst = tmp_path / folder.name
    shutil.copytree(folder, dst)
    return str(dst)


def test_sdcrack_on_kinks_across_triangles_passes(inclined, tmp_path, monkeypatch):
    fresh_caches(monkeypatch)
    folder = copy_of(inclined, tmp_path)
    s = sr.load_summary(folder)
    assert all(set(c["errors_quadrature"]) == set(QUANTITIES) for c in s["cases"])
    rows, problems, _ = independent(folder)
    assert problems == []
    solver = [r for r in rows if r["source"] == "sdcrack"]
    assert len(solver) == len(s["cases"]) == 36
    # the point: the solver's and this tool's quadratures differ by more than 1e-8 at level 0
    assert max(r["worst"] for r in solver if r["level"] == 0) > 1e-6
    assert max(r["ratio"] for r in solver) <= 1.0
    drop_estimates(folder)
    _, problems, _ = independent(folder)
    assert problems, "the bare 1e-8 passes it: the test lost its point"


def test_sdcrack_with_an_error_forged_by_1e6_fails(inclined, tmp_path, monkeypatch):
    fresh_caches(monkeypatch)
    folder = copy_of(inclined, tmp_path)
    forge(folder, 0, "lambda_l2", 1 - 1e-6)
    _, problems, _ = independent(folder)
    assert len(problems) == 1 and "sdcrack's value is suspect" in problems[0], problems


def test_summary_json_estimates_are_the_solvers_rule_against_a_higher_one(inclined):
    """summary.json's estimates are those of a rule and a higher one: on the kinked triangles of
    level 0 they are well above round-off, and below the cap (ESTIMATE_CAP) the check allows."""
    s = json.loads((inclined / "summary.json").read_text())
    level0 = [c for c in s["cases"] if c["level"] == 0]
    for q in ("u_l2", "p_l2", "p_x"):
        rel = [c["errors_quadrature"][q] / c["errors"][q] for c in level0]
        assert min(rel) > 1e-8 and max(rel) < 1e-3, (q, rel)


# A smooth, non-polynomial exact solution without kinks: closed-exact's with three times the
# frequency, u = sin(3πx)cos(3πy) − y (closed crack: ∂u/∂y = −1 on y = 0), on 4 × 4 cells at
# levels 1-3, where the integrands are resolved but not integrated exactly: at the coarsest level
# the solver's and this tool's quadratures differ by ~1.7e-7 relative (measured), far above the
# former bare 1e-8, and the estimates (~1.7e-7 of u's error) leave a tolerance below a forged
# 1e-6.
WAVY = square_scene(
    "wavy-closed", "closed crack, smooth non-polynomial u = sin(3 pi x) cos(3 pi y) - y",
    data={"f": '"18*pi^2*sin(3*pi*x)*cos(3*pi*y)"', "g": '"sin(3*pi*x)*cos(3*pi*y) - y"'},
    exact={"u": '"sin(3*pi*x)*cos(3*pi*y) - y"', "jump": '"0"'},
    discretization={"levels": "[1, 2, 3]", "u_spaces": '["continuous", "broken"]',
                    "multipliers": '["M1"]', "deltas": "[0.0]"})


@pytest.fixture(scope="module")
def wavy(tmp_path_factory):
    if not os.access(sdcrack_bin(), os.X_OK):
        pytest.skip("no sdcrack binary (cargo build --release, or SDCRACK_BIN)")
    tmp = tmp_path_factory.mktemp("wavy")
    (tmp / "wavy.toml").write_text(WAVY)
    r = subprocess.run([sdcrack_bin(), "run", str(tmp / "wavy.toml"), "--out", str(tmp / "out"),
                        "--quiet"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return tmp / "out" / "wavy-closed"


def test_sdcrack_on_a_smooth_non_polynomial_solution_passes_and_a_1e6_forgery_of_u_fails(
        wavy, tmp_path, monkeypatch):
    """The quadrature estimates' acceptance: a correct solver whose two correct quadratures of a smooth
    non-polynomial solution differ by more than 1e-8 relative at the coarsest level passes the
    check, and the same folder with u's error forged by a relative 1e-6 fails it, blaming sdcrack."""
    fresh_caches(monkeypatch)
    folder = copy_of(wavy, tmp_path)
    rows, problems, _ = independent(folder)
    assert problems == []
    solver = [r for r in rows if r["source"] == "sdcrack"]
    assert len(solver) == 6
    # the point: the two correct quadratures differ by more than the former bare 1e-8
    assert max(r["worst"] for r in solver if r["level"] == 1) > 1e-8
    forge(folder, 1, "u_l2", 1 + 1e-6)
    _, problems, _ = independent(folder)
    assert len(problems) == 1 and "sdcrack's value is suspect" in problems[0], problems
    assert "level 1" in problems[0], problems
