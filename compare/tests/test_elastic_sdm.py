"""The compare tool's checks of the smooth-domain method's elastic cases (issue 46; docs/elasticity.md,
"The smooth-domain method's cases"), on synthetic folders: elastic_synthetic.write_results's
references and export, and solver cases (write_sdm_cases) whose fields are the exact field sampled
on each triangle. The norms against closed forms; a correct folder passes every solver check; each
check FAILs on the damage it is there for: a forged summary error (independent errors), a stalled σ
(solver series), a σ off by 1e-8 on the patch test (patch test), a case that did not converge or is
missing (solver cases), a δ-difference that breaks the triangle inequality or grows with the level
(δ → 0); bad fields.h5 is one line, exit 2; and the real solver's fields.h5 (SDCRACK_BIN) gives back its own
summary's errors.

Run: /usr/bin/python3 -m pytest compare/tests/test_elastic_sdm.py -q
"""
import json
import math
import os
import subprocess
import tomllib

import h5py
import numpy as np
import pytest

import elastic_synthetic as es
from sdcompare_lib import elastic, elastic_exact, elastic_read, elastic_sdm
from test_elastic import run_cli

LEVELS = (0, 1, 2)


def analyse(folder):
    return elastic.analyse(elastic_read.load(str(folder)))


def check(a, label):
    """(problems, why not applicable) of the check row `label`."""
    return next((p, na) for lab, _, p, na in a["checks"] if lab == label)


def patch_exact():
    """Uniform strain (0.1, −0.3) across the interior crack y = 0, |x| ≤ 1/2: σ_yy < 0, closed."""
    grad = np.array([[0.1, 0.0], [0.0, -0.3]])
    s = elastic_exact.hooke(grad, es.PROBLEM)
    return {"ux": "0.1*x", "uy": "-0.3*y", "sxx": repr(float(s[0])), "syy": repr(float(s[1])),
            "sxy": repr(float(s[2])), "opening": None, "slip": None, "pressure": None,
            "sif": [[0.0, 0.0], [0.0, 0.0]]}


def patch_folder(tmp_path, levels=(1, 2, 3), **kw):
    ex = patch_exact()
    folder = es.write_results(tmp_path / "patch", exact=ex, levels=levels, name="patch",
                              crack=((-0.5, 0.0), (0.5, 0.0)),
                              closed=lambda L, xy, pairs: np.ones(len(pairs), dtype=bool))
    return es.write_sdm_cases(folder, ex, **kw)


def williams_folder(tmp_path, **kw):
    ex = es.williams(1.0, 0.5)
    folder = es.write_results(tmp_path / "w", exact=ex, levels=LEVELS)
    return es.write_sdm_cases(folder, ex, **kw)


# ------------------------------------------------------------------------- the norms

def test_errors_of_known_offsets_are_their_closed_forms(tmp_path):
    """On the patch field (P1: the sampled fields are exact), constant offsets of every field give
    the closed forms: ‖C‖_F √|Ω| for σ (|Ω| = 4), |d| √|Ω| for u*, ‖P0u − u_h‖, |g| √|Ω| for γ, the
    compliance energy (|C|² − c tr² C)/(2μ) |Ω|, the offset × √|Σ| on the crack (|Σ| = 1)."""
    C = np.array([[0.3, 0.1], [-0.2, 0.4]])
    d, g, o = np.array([0.05, -0.02]), 0.07, 0.01

    def damage(L, m, delta, f):
        f["sigma_raw"][:, [0, 1, 3, 4]] += C.ravel()
        f["u_star"][:, :2] += d
        f["u_h"][:, :2] += d
        f["gamma_h"] += g
        for k in ("opening", "slip", "pressure"):
            f[f"crack/{k}"] += o

    folder = patch_folder(tmp_path, levels=(1,), damage=damage)
    res = elastic_read.load(str(folder))
    ex = elastic_exact.ElasticExact(res["mesh_scene"]["exact"], es.PROBLEM)
    e, _ = elastic_sdm.recompute(res["sdm"][0], res["levels"][1], ex, es.PROBLEM)
    lam, mu = es.PROBLEM["lambda_in_plane"], es.PROBLEM["mu"]
    c = lam / (2 * (mu + lam))
    close = lambda x, y: abs(x - y) <= 1e-12 * max(1.0, abs(y))  # noqa: E731
    assert close(e["stress_l2"], np.linalg.norm(C) * 2)
    assert e["stress_sym_l2"] < 1e-14
    assert close(e["stress_energy"], math.sqrt((np.sum(C * C) - c * np.trace(C) ** 2) / (2 * mu) * 4))
    assert close(e["asymmetry_l2"], abs(C[0, 1] - C[1, 0]) * 2)
    assert close(e["u_star_l2"], np.linalg.norm(d) * 2)
    assert close(e["projected_u_l2"], np.linalg.norm(d) * 2)
    assert close(e["rotation_l2"], g * 2)
    for k in ("opening_l2", "slip_l2", "pressure_l2"):
        assert close(e[k], o), (k, e[k])
    # u_h (centroid values + d) against the linear u: |d|² + the centroid's variance of ∇u·(x − x_T)
    assert e["u_l2"] > np.linalg.norm(d) * 2


# ------------------------------------------------------------------------- the verdict

def test_a_correct_solver_folder_passes_every_solver_check(tmp_path):
    a = analyse(williams_folder(tmp_path))
    for label in ("solver cases", "independent errors", "solver series"):
        probs, na = check(a, label)
        assert probs == [] and na is None, (label, probs, na)
    assert check(a, "patch test")[1] == "the exact u is not P1 on every triangle"
    assert check(a, "δ → 0")[1] is not None
    sdm = [s for s in a["series"] if s["tool"].startswith("sdcrack")]
    assert {s["quantity"] for s in sdm} == set(elastic.elastic_theory.SDM_JUDGED) | {
        "K_I tip 1", "K_II tip 1"}
    assert check(a, "solver SIF") == ([], None)
    # the SIFs of σ_h, Aσ_h + γ_h J (the exact fields sampled) tend to K_I = 1, K_II = 1/2
    by = {s["quantity"]: s for s in sdm}
    assert by["K_I tip 1"]["errors"][-1] < 1e-4 and by["K_II tip 1"]["errors"][-1] < 1e-4
    assert by["stress_sym_l2"]["expected"] == 0.5 and by["u_star_l2"]["expected"] == 1.0
    assert by["opening_l2"]["expected"] == 0.5 and by["u_l2"]["expected"] == 1.0
    assert len(a["sdm"]["ratios"]) == 2 * len(LEVELS) * 5


def test_a_forged_summary_error_fails(tmp_path):
    """stress_sym_l2 at level 1 written 1 + 1e-6 times the recomputed one: FAIL, nothing else."""
    def forge(L, m, d, errors):
        if L == 1:
            errors["stress_sym_l2"] *= 1 + 1e-6

    a = analyse(williams_folder(tmp_path, forge=forge))
    probs, _ = check(a, "independent errors")
    assert len(probs) == 1 and "level 1" in probs[0] and "stress_sym_l2" in probs[0], probs
    assert a["verdict"] == "FAIL"


def test_a_stalled_stress_fails_the_solver_series(tmp_path):
    """σ_h off by a constant 0.3 I at every level: its errors stall, the series FAILs."""
    def damage(L, m, d, f):
        f["sigma"][:, [0, 4]] += 0.3
        f["sigma_raw"][:, [0, 4]] += 0.3

    a = analyse(williams_folder(tmp_path, damage=damage))
    probs, _ = check(a, "solver series")
    assert any("stress_sym_l2" in p for p in probs) and any("stress_l2" in p for p in probs), probs
    assert not any("u_star_l2" in p or "opening_l2" in p for p in probs)
    assert check(a, "independent errors")[0] == []


def test_a_rotation_off_by_a_linear_field_fails_the_sif_check(tmp_path):
    """γ_h + 0.2 x: ∇_h u's rotation enters the interaction integral (σ^a_ij u_i,1; a constant
    rotation, a rigid motion, would not), so K moves by far more than 0.5 % at the finest level;
    σ's errors do not change."""
    def damage(L, m, d, f):
        f["gamma_h"] += 0.2 * f["points"][:, 0].reshape(-1, 3).mean(axis=1)

    a = analyse(williams_folder(tmp_path, damage=damage))
    probs, _ = check(a, "solver SIF")
    assert probs and all("level 2 tip 1" in p for p in probs), probs
    assert not any("stress" in p for p in check(a, "solver series")[0])


def test_the_patch_test_is_exact_and_fails_off_by_1e_8(tmp_path):
    a = analyse(patch_folder(tmp_path / "ok"))
    assert check(a, "patch test") == ([], None)
    assert a["verdict"] == "PASS", a["reasons"]

    def damage(L, m, d, f):
        if L == 3:
            f["sigma"][:, 4] += 1e-8
            f["sigma_raw"][:, 4] += 1e-8

    probs, _ = check(analyse(patch_folder(tmp_path / "bad", damage=damage)), "patch test")
    assert probs and all("level 3" in p for p in probs), probs
    assert any("stress_sym_l2" in p for p in probs)


def test_a_case_not_converged_or_missing_fails(tmp_path):
    folder = williams_folder(tmp_path, status=lambda L, m, d: "converged" if L else "not converged")
    probs, _ = check(analyse(folder), "solver cases")
    assert len(probs) == 1 and "level 0" in probs[0], probs
    summary = json.loads((folder / "summary.json").read_text())
    summary["cases"][0]["status"] = "converged"
    summary["cases"][1]["kkt"]["primal"] = 3e-7  # "converged" with a residual above 1e-10
    (folder / "summary.json").write_text(json.dumps(summary))
    probs, _ = check(analyse(folder), "solver cases")
    assert len(probs) == 1 and "level 1" in probs[0] and "KKT primal" in probs[0], probs
    summary = json.loads((folder / "summary.json").read_text())
    summary["cases"][1]["kkt"]["primal"] = 0.0
    summary["cases"][2]["h"] *= 2  # an h written wrong: every rate per halving of h would move
    (folder / "summary.json").write_text(json.dumps(summary))
    probs, _ = check(analyse(folder), "solver cases")
    assert len(probs) == 1 and "level 2" in probs[0] and "largest triangle diameter" in probs[0]
    summary["cases"][2]["h"] /= 2
    summary["cases"] = [c for c in summary["cases"] if c["level"] != 2]
    (folder / "summary.json").write_text(json.dumps(summary))
    probs, _ = check(analyse(folder), "solver cases")
    assert any("level 2 has no solver case M1star δ=0" in p for p in probs), probs


def _delta_damage(scale):
    """δ = 1e-3's σ_h and u_h off by δ × scale(L) × a fixed field (x_δ − x_0 = O(δ))."""
    def damage(L, m, d, f):
        if d > 0:
            f["sigma_raw"][:, 0] += d * scale(L) * f["points"][:, 0]
            f["u_h"][:, 0] += d * scale(L)
    return damage


def test_delta_to_zero(tmp_path):
    variants = (("M1star", 0.0), ("M1star", 1e-3))
    a = analyse(patch_folder(tmp_path / "ok", levels=(0, 1, 2, 3), variants=variants,
                             damage=_delta_damage(lambda L: 1.0)))
    assert check(a, "δ → 0") == ([], None)
    assert len(a["sdm"]["delta"]) == 4
    # the constant doubling per level (δ scaled by h⁻¹): FAIL
    a = analyse(patch_folder(tmp_path / "grow", levels=(0, 1, 2, 3), variants=variants,
                             damage=_delta_damage(lambda L: 2.0 ** L)))
    probs, _ = check(a, "δ → 0")
    assert any("δ-constant" in p and " σ " in p for p in probs), probs

    # a δ > 0 error not tied to its field: |e(δ) − e(0)| > ‖x_δ − x_0‖
    def forge(L, m, d, errors):
        if d > 0 and L == 2:
            errors["u_l2"] += 1e-2

    a = analyse(patch_folder(tmp_path / "forged", levels=(0, 1, 2, 3), variants=variants,
                             damage=_delta_damage(lambda L: 1.0), forge=forge))
    probs, _ = check(a, "δ → 0")
    assert any("level 2" in p and "u_l2" in p and "triangle inequality" in p for p in probs), probs


def test_bad_fields_are_one_line_and_exit_2(tmp_path):
    folder = patch_folder(tmp_path, levels=(1,))
    with h5py.File(folder / "fields.h5", "a") as h5:
        del h5["cases/level1-elasticity-M1star-delta0/gamma_h"]
    code, out, err = run_cli(folder)
    assert code == 2 and "gamma_h" in err and len(err.strip().splitlines()) == 1, (out, err)
    assert not (folder / "report").exists()
    (folder / "fields.h5").unlink()
    code, out, err = run_cli(folder)
    assert code == 2 and "fields.h5" in err, (out, err)


def test_the_sentences_follow_the_numbers(tmp_path):
    """The report's sentences are computed: the sampled σ_h (0.49 × P1's σ error) is 'smaller at
    every level'; σ_h off by 0.3 I is 'not smaller' at the levels where it is not; the P0 u_h
    (rate ~1 against P1's ~1.5 here) is 'of lower order'."""
    a = analyse(williams_folder(tmp_path / "ok"))
    said = a["sdm"]["sentences"]
    assert any(t.startswith("On the same mesh the SDM's σ error") and "smaller than dolfinx's at "
               "every level" in t for t in said), said
    assert any("raw u_h (P0)" in t and "of lower order" in t for t in said), said

    def damage(L, m, d, f):
        f["sigma"][:, [0, 4]] += 0.3

    said = analyse(williams_folder(tmp_path / "bad", damage=damage))["sdm"]["sentences"]
    assert any("σ error" in t and "is not smaller than dolfinx's at level(s) 0, 1, 2" in t
               for t in said), said
    assert not any("σ error" in t and "at every level" in t for t in said)


# ------------------------------------------------------------------------- the real solver

def test_the_solvers_own_fields_give_back_its_summary(tmp_path):
    """`sdcrack run` on the graded Williams scene at levels 0–1 (M1star, δ = 0, no references) and
    `sdcrack mesh` for the export: the fields.h5 layout read here is the solver's, and every error
    of its summary.json is recomputed within the independent-errors tolerance."""
    from sdcompare_lib import elastic_sdm_verdict as sv
    from sdcompare_lib.exact import Quadrature

    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    exe = os.environ.get("SDCRACK_BIN") or os.path.join(root, "target", "release", "sdcrack")
    if not os.path.exists(exe):
        pytest.skip(f"no sdcrack binary at {exe} (cargo build --release, or set SDCRACK_BIN)")
    text = open(os.path.join(root, "scenes", "elastic-williams-open-graded.toml")).read()
    scene = tomllib.loads(text)
    lines = [ln for ln in text.splitlines() if not ln.startswith(("levels", "references",
                                                                  "multipliers", "deltas"))]
    scene_file = tmp_path / "w.toml"
    scene_file.write_text("\n".join(lines).replace(
        "[discretization]", '[discretization]\nlevels = [0, 1]\nmultipliers = ["M1star"]\n'
        "deltas = [0.0]").replace("[outputs]", "[outputs]\nreferences = []") + "\n")
    run = subprocess.run([exe, "run", str(scene_file), "--out", str(tmp_path / "out"), "--quiet"],
                         capture_output=True, text=True)
    assert run.returncode in (0, 1), run.stderr
    subprocess.run([exe, "mesh", str(scene_file), "--out", str(tmp_path / "mesh")], check=True,
                   capture_output=True)
    folder = tmp_path / "out" / scene["name"]
    summary = json.loads((folder / "summary.json").read_text())
    cases = elastic_sdm.read_cases(str(folder), summary)
    assert [c.level for c in cases] == [0, 1]
    ms = json.loads((tmp_path / "mesh" / "scene.json").read_text())
    ex = elastic_exact.ElasticExact(ms["exact"], ms["problem"])
    for c in cases:
        lv = elastic_read.read_level(str(tmp_path / "mesh"), c.level)
        e, scale = elastic_sdm.recompute(c, lv, ex, ms["problem"])
        eh, _ = elastic_sdm.recompute(c, lv, ex, ms["problem"], Quadrature().higher())
        for k in elastic_sdm.ERROR_NAMES:
            tol = sv.INDEPENDENT_REL * e[k] + 4 * abs(eh[k] - e[k]) + sv.ROUNDOFF_REL * scale[k]
            assert abs(c.entry["errors"][k] - e[k]) <= tol, (c.level, k, c.entry["errors"][k], e[k])
        assert e["opening_l2"] > 0 and e["stress_sym_l2"] > 0


def test_without_exact_only_the_solver_cases_and_delta_are_judged(tmp_path):
    """No exact table and no "errors" in the cases (sdcrack writes none then): the solver cases
    and δ → 0 are judged, the rest does not apply; the δ-constant doubling per level still FAILs."""
    variants = (("M1star", 0.0), ("M1star", 1e-3))
    for name, scale, ok in (("ok", lambda L: 1.0, True), ("grow", lambda L: 2.0 ** L, False)):
        folder = patch_folder(tmp_path / name, levels=(0, 1, 2, 3), variants=variants,
                              damage=_delta_damage(scale))
        scene = json.loads((folder / "mesh" / "scene.json").read_text())
        scene["exact"] = None
        (folder / "mesh" / "scene.json").write_text(json.dumps(scene))
        summary = json.loads((folder / "summary.json").read_text())
        for c in summary["cases"]:
            del c["errors"]
        (folder / "summary.json").write_text(json.dumps(summary))
        a = analyse(folder)
        assert check(a, "solver cases") == ([], None)
        for label in ("independent errors", "solver series", "solver SIF", "patch test"):
            assert check(a, label)[1].startswith("no [exact]"), label
        probs, na = check(a, "δ → 0")
        assert na is None and (probs == []) == ok, probs


def test_the_front_sentence_follows_the_fronts(tmp_path):
    """The references flag the rows x ≤ −0.5 closed; an SDM closing the same ends has its front
    within one crack edge of theirs at every level; one closing the whole crack has no front, and
    the sentence says so."""
    ex = es.williams(1.0, 0.0)
    for name, sdm_closed, ok in (("same", lambda L, xy: xy[:, 0] <= -0.5 + 1e-12, True),
                                 ("all", lambda L, xy: np.ones(len(xy), dtype=bool), False)):
        folder = es.write_results(tmp_path / name, exact=ex, levels=LEVELS,
                                  closed=lambda L, xy, pairs: xy[pairs[:, 0], 0] <= -0.5 + 1e-12)
        a = analyse(es.write_sdm_cases(folder, ex, closed=sdm_closed))
        said = [t for t in a["sdm"]["sentences"] if "contact front" in t]
        assert len(said) == 1 and ("lies within one crack edge" in said[0]) == ok, said
        if ok:
            assert all(r["same_level"] <= r["edge"] for r in a["sdm"]["fronts"])


def test_delta_to_zero_that_judged_nothing_is_not_applicable(tmp_path):
    """No errors (no [exact]) and levels 0–2 only: neither the triangle inequality nor the
    δ-constant (judged from level 3) was judged, so the check says so instead of "ok"."""
    folder = patch_folder(tmp_path, levels=(0, 1, 2), variants=(("M1star", 0.0), ("M1star", 1e-3)),
                          damage=_delta_damage(lambda L: 1.0))
    summary = json.loads((folder / "summary.json").read_text())
    for c in summary["cases"]:
        del c["errors"]
    (folder / "summary.json").write_text(json.dumps(summary))
    probs, na = check(analyse(folder), "δ → 0")
    assert probs == [] and na.startswith("nothing to judge"), na
