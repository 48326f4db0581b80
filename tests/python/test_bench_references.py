"""tools/bench_references.py: equal-error speed-ups of both p masses and both p spaces, the report,
the graded and broken-tangential goals, load control.

The arithmetic is checked on hand-made rows whose expected ratios are worked out by hand below;
two end-to-end runs time the real binary on levels 0–1 of scenes/open-exact.toml and
scenes/open-graded.toml (sdcrack alone).
"""

import argparse
import json
import math
import pathlib
import subprocess
import sys

import pytest

import ci_script

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "tools" / "bench_references.py"
EXE = ROOT / "target" / "release" / "sdcrack"


br = ci_script.load("tools/bench_references.py")


def entry(u_l2, solver_s, wall_s, norms_s=None):
    x = {"u_l2": u_l2, "solver_s": solver_s, "wall_s": wall_s, "unknowns": 100, "kkt": 1e-15}
    if norms_s is not None:
        x["norms_s"] = norms_s
    return x


def hand_rows():
    """References on an exact power law t ∝ e⁻² (error halves, time ×4 per level):
    dolfinx solve 0.1·(0.08/e)², wall 1·(0.08/e)²;
    FreeFEM solve 0.2·(0.08/e)², wall 0.5·(0.08/e)².
    sdcrack consistent: e 0.05 → 0.0125, solve 0.01 → 0.04, wall 0.1 → 0.4 (t ∝ 1/e).
    sdcrack lumped: e 0.025 (inside every range) and 0.005 (outside every range)."""
    return [
        {"level": 0, "sdcrack": entry(0.05, 0.01, 0.1, 0.02),
         "sdcrack-lumped": entry(0.025, 0.01, 0.4, 0.03),
         "dolfinx": entry(0.08, 0.1, 1.0), "freefem": entry(0.08, 0.2, 0.5)},
        {"level": 1, "sdcrack": entry(0.0125, 0.04, 0.4, 0.05),
         "sdcrack-lumped": entry(0.005, 0.04, 0.4, 0.05),
         "dolfinx": entry(0.04, 0.4, 4.0), "freefem": entry(0.04, 0.8, 2.0)},
        {"level": 2, "dolfinx": entry(0.02, 1.6, 16.0), "freefem": entry(0.02, 3.2, 8.0)},
    ]


def test_time_at_error_is_exact_on_a_power_law():
    curve = [(1e-1, 1.0), (1e-2, 100.0)]  # t = 0.01 e⁻²
    assert br.time_at_error(curve, 0.02) == pytest.approx(0.01 / 0.02 ** 2, rel=1e-12)  # 25
    assert br.time_at_error(list(reversed(curve)), 0.05) == pytest.approx(4.0, rel=1e-12)
    assert br.time_at_error(curve, 0.2) is None
    assert br.time_at_error(curve, 0.005) is None
    assert br.time_at_error([], 0.05) is None


def test_speedups_of_the_consistent_variant():
    rows = hand_rows()
    solve = br.speedups(rows, "solver_s", "sdcrack")
    wall = br.speedups(rows, "wall_s", "sdcrack")
    assert [s["level"] for s in solve] == [0, 1]
    # e = 0.05: (0.08/0.05)² = 2.56; dolfinx solve 0.256 / 0.01, FreeFEM 0.512 / 0.01
    assert solve[0]["u_l2"] == 0.05
    assert solve[0]["dolfinx"] == pytest.approx(25.6, rel=1e-12)
    assert solve[0]["freefem"] == pytest.approx(51.2, rel=1e-12)
    # walls 2.56 / 0.1 and 1.28 / 0.1
    assert wall[0]["dolfinx"] == pytest.approx(25.6, rel=1e-12)
    assert wall[0]["freefem"] == pytest.approx(12.8, rel=1e-12)
    # e = 0.0125 is below the references' smallest error 0.02
    assert solve[1]["dolfinx"] is None and solve[1]["freefem"] is None
    assert wall[1]["dolfinx"] is None and wall[1]["freefem"] is None
    # the default variant is the consistent one
    assert br.speedups(rows, "solver_s") == solve


def test_speedups_of_the_lumped_variant():
    rows = hand_rows()
    solve = br.speedups(rows, "solver_s", "sdcrack-lumped")
    wall = br.speedups(rows, "wall_s", "sdcrack-lumped")
    # e = 0.025: (0.08/0.025)² = 10.24; solve 1.024 / 0.01 and 2.048 / 0.01; wall 10.24 / 0.4
    # and 5.12 / 0.4
    assert solve[0]["dolfinx"] == pytest.approx(102.4, rel=1e-12)
    assert solve[0]["freefem"] == pytest.approx(204.8, rel=1e-12)
    assert wall[0]["dolfinx"] == pytest.approx(25.6, rel=1e-12)
    assert wall[0]["freefem"] == pytest.approx(12.8, rel=1e-12)
    assert solve[1]["dolfinx"] is None and wall[1]["freefem"] is None


def test_lumped_vs_consistent_at_equal_error():
    lvc = br.lumped_vs_consistent(hand_rows())
    assert [x["level"] for x in lvc] == [0, 1]
    # consistent at e = 0.025 (t ∝ 1/e): solve 0.02, wall 0.2; lumped: solve 0.01, wall 0.4
    assert lvc[0]["u_l2"] == 0.025
    assert lvc[0]["solve"] == pytest.approx(2.0, rel=1e-12)
    assert lvc[0]["wall"] == pytest.approx(0.5, rel=1e-12)
    # e = 0.005 is below consistent's smallest error 0.0125
    assert lvc[1]["solve"] is None and lvc[1]["wall"] is None


def test_a_slower_lumped_row_gives_a_ratio_below_one():
    rows = hand_rows()
    rows[0]["sdcrack-lumped"]["solver_s"] = 0.05  # damaged: 2.5 × consistent's 0.02 at its error
    lvc = br.lumped_vs_consistent(rows)
    assert lvc[0]["solve"] == pytest.approx(0.4, rel=1e-12)
    assert lvc[0]["solve"] < 1


def test_markdown_lists_both_variants_and_the_norms_columns():
    rows = hand_rows()
    keys = ("sdcrack", "sdcrack-lumped")
    fast = {k: br.speedups(rows, "solver_s", k) for k in keys}
    fast_wall = {k: br.speedups(rows, "wall_s", k) for k in keys}
    md = br.markdown("hand", rows, fast, fast_wall, br.lumped_vs_consistent(rows))
    lines = md.splitlines()
    assert ("| level | tool | unknowns | ‖u_h − u‖_L² | wall s | solve s | norms s "
            "| norms / solve |") in lines
    # norms 0.02 s over solve 0.01 s; norms 0.03 over 0.01
    assert "| 0 | sdcrack | 100 | 5.000e-02 | 0.10 | 0.01 | 0.02 | 2.0 |" in lines
    assert "| 0 | sdcrack (lumped p) | 100 | 2.500e-02 | 0.40 | 0.01 | 0.03 | 3.0 |" in lines
    assert "| 2 | dolfinx | 100 | 2.000e-02 | 16.00 | 1.60 | – | – |" in lines
    assert "| 0 | freefem | 100 | 8.000e-02 | 0.50 | 0.20 | – | – |" in lines
    # the speed-up table, one line per level and variant
    assert "| 0 | consistent | 5.000e-02 | 25.6× | 51.2× | 25.6× | 12.8× |" in lines
    assert "| 0 | lumped | 2.500e-02 | 102.4× | 204.8× | 25.6× | 12.8× |" in lines
    assert "| 1 | consistent | 1.250e-02 | – | – | – | – |" in lines
    # lumped vs consistent
    assert "| level | lumped ‖u_h − u‖ | solve | wall |" in lines
    assert "| 0 | 2.500e-02 | 2.0× | 0.5× |" in lines
    assert "| 1 | 5.000e-03 | – | – |" in lines


def test_plot_draws_both_variants_in_both_panels(tmp_path):
    fig = br.plot(hand_rows(), tmp_path / "wp.png", "hand")
    wall, solve = ([(x.get_label(), x.get_marker(), x.get_linestyle(), x.get_color())
                    for x in ax.get_lines()] for ax in fig.axes)
    # one colour per tool and p mass (consistent and lumped differ by more than dashing)
    assert wall[:2] == [("sdcrack", "o", "--", "C0"), ("sdcrack (lumped p)", "D", "--", "C1")]
    assert solve == wall
    assert [x[0] for x in solve[2:]] == ["dolfinx", "freefem"]
    assert len({x[3] for x in wall}) == 4
    # one legend beside the panels, none over the data
    assert all(ax.get_legend() is None for ax in fig.axes) and len(fig.legends) == 1
    assert (tmp_path / "wp.png").stat().st_size > 0


def test_plot_draws_graded_curves_solid_and_filled(tmp_path):
    fig = br.plot(graded_rows(), tmp_path / "wp.png", "hand")
    lines = {x.get_label(): x for x in fig.axes[0].get_lines()}
    assert set(lines) == {"sdcrack", "sdcrack (lumped p)", "dolfinx", "freefem", "sdcrack, graded",
                          "sdcrack (lumped p), graded", "dolfinx, graded", "freefem, graded"}
    g, u = lines["sdcrack, graded"], lines["sdcrack"]
    assert g.get_color() == u.get_color() and g.get_linestyle() == "-" and u.get_linestyle() == "--"
    assert u.get_markerfacecolor() == "none" and g.get_markerfacecolor() != "none"


def test_proc_parsers_on_fake_text():
    stat = ("cpu  100 20 30 1000 50 5 6 7 3 0\n"
            "cpu0 50 10 15 500 25 2 3 3 1 0\n"
            "intr 12345\n")
    busy, steal = br.parse_proc_stat(stat, 100)
    assert busy == pytest.approx((100 + 20 + 30 + 5 + 6) / 100)  # guest is inside user
    assert steal == pytest.approx(0.07)
    # an old kernel's shorter line: no steal
    assert br.parse_proc_stat("cpu 1 2 3 4\n", 10) == (pytest.approx(0.6), 0.0)
    assert br.parse_loadavg("0.98 0.50 0.30 1/100 1234\n") == 0.98


def test_foreign_cores_and_verdicts():
    s0 = {"t": 10.0, "busy_s": 100.0, "own_s": 1.0}
    s1 = {"t": 12.0, "busy_s": 103.0, "own_s": 2.5}
    # (3 s busy − 1.5 s ours) / 2 s
    assert br.foreign_cores(s0, s1) == pytest.approx(0.75)
    assert br.verdict(0.19, 1, 3, True) == "OK"
    assert br.verdict(0.2, 1, 3, True) == "REJECTED"
    assert br.verdict(0.5, 3, 3, True) == "REJECTED-KEPT"
    assert br.verdict(0.5, 1, 3, False) == "UNCHECKED"


def test_wait_idle_gives_up_after_its_timeout():
    clock = iter(range(100)).__next__
    assert br.wait_idle(5, sample=lambda: (0.5, 0.05), clock=clock)
    busy = [(1.5, 0.0)] * 3 + [(0.5, 0.3)] * 2  # loaded, then other processes busy
    samples = iter(busy)
    assert not br.wait_idle(5, sample=lambda: next(samples), clock=iter(range(100)).__next__)
    assert next(samples, "used up") == "used up"  # it sampled once a second until the timeout


def test_measure_repeats_a_loaded_measurement(monkeypatch, tmp_path):
    # each try: 1 s wall, 0.5 s busy, 0.1 s ours → 0.4 foreign cores, rejected
    clock = iter(range(0, 100, 1))

    def snapshot():
        t = float(next(clock))
        return {"t": t, "busy_s": 0.5 * t, "own_s": 0.1 * t, "steal_s": 0.0, "load": 0.5}

    monkeypatch.setattr(br, "snapshot", snapshot)
    monkeypatch.setattr(br, "wait_idle", lambda timeout: timeout > 1)
    calls = []
    with open(tmp_path / "load.txt", "w") as log:
        res = br.measure("sdcrack L0", lambda: calls.append(1) or {"wall_s": 1.0}, log,
                         idle_timeout=300, max_tries=3)
        quiet = br.measure("x L1", lambda: {"wall_s": 1.0}, log, check=False, idle_timeout=0)
    assert len(calls) == 3
    assert res["load"]["status"] == "REJECTED-KEPT" and res["load"]["tries"] == 3
    assert res["load"]["foreign_cores"] == pytest.approx(0.4)
    assert quiet["load"] == {"status": "UNCHECKED", "tries": 1, "foreign_cores": pytest.approx(0.4)}
    lines = (tmp_path / "load.txt").read_text().splitlines()
    assert len(lines) == 4
    assert lines[0].endswith("sdcrack L0 try 1: wall 1.00 s own cpu 0.10 foreign 0.40 steal 0.00 "
                             "load 0.50->0.50 REJECTED")
    assert lines[2].endswith("try 3: wall 1.00 s own cpu 0.10 foreign 0.40 steal 0.00 "
                             "load 0.50->0.50 REJECTED-KEPT")
    assert lines[3].endswith("x L1 try 1: wall 1.00 s own cpu 0.10 foreign 0.40 steal 0.00 "
                             "load 0.50->0.50 UNCHECKED")


def test_measure_marks_an_idle_timeout(monkeypatch, tmp_path):
    snaps = iter([{"t": 0.0, "busy_s": 0.0, "own_s": 0.0, "steal_s": 0.0, "load": 2.0},
                  {"t": 1.0, "busy_s": 1.0, "own_s": 0.95, "steal_s": 0.0, "load": 2.0}])
    monkeypatch.setattr(br, "snapshot", lambda: next(snaps))
    monkeypatch.setattr(br, "wait_idle", lambda timeout: False)
    with open(tmp_path / "load.txt", "w") as log:
        res = br.measure("dolfinx L3", lambda: {}, log, idle_timeout=0, max_tries=3)
    assert res["load"]["status"] == "OK IDLE-TIMEOUT" and res["load"]["tries"] == 1
    assert (tmp_path / "load.txt").read_text().rstrip().endswith("OK IDLE-TIMEOUT")


FOUR = ("sdcrack", "sdcrack-lumped", "sdcrack-ptangential", "sdcrack-lumped-ptangential")


@pytest.mark.skipif(not EXE.exists(), reason="target/release/sdcrack not built")
def test_end_to_end_both_p_masses_and_p_spaces(tmp_path):
    scene = ROOT / "scenes" / "open-exact.toml"
    subprocess.run([sys.executable, str(SCRIPT), "--scene", str(scene), "--levels", "0-1",
                    "--tools", "", "--no-idle-wait", "--out", str(tmp_path)],
                   check=True, capture_output=True, text=True)
    wp = json.loads((tmp_path / "work_precision.json").read_text())
    assert wp["scene"] == "open-exact"
    assert wp["p_masses"] == ["consistent", "lumped"]
    assert wp["p_spaces"] == ["continuous", "broken-tangential"]
    assert [r["level"] for r in wp["levels"]] == [0, 1]
    for row in wp["levels"]:
        assert set(row) == {"level", *FOUR}
        for key in FOUR:
            x = row[key]
            assert x["wall_s"] > 0 and x["solver_s"] > 0 and x["norms_s"] > 0
            assert x["kkt"] < 1e-10 and x["load"]["tries"] == 1
        assert row["sdcrack"]["unknowns"] == row["sdcrack-lumped"]["unknowns"]
        # p·τ gets one value per crack face: more unknowns than the continuous p
        assert row["sdcrack-ptangential"]["unknowns"] > row["sdcrack"]["unknowns"]
    # docs/performance.md: sdcrack's level-0 error on open-exact (consistent p mass)
    assert f"{wp['levels'][0]['sdcrack']['u_l2']:.3e}" == "4.430e-02"
    level0 = wp["levels"][0]
    assert not math.isclose(level0["sdcrack-lumped"]["u_l2"], level0["sdcrack"]["u_l2"],
                            rel_tol=1e-6)
    assert not math.isclose(level0["sdcrack-ptangential"]["u_l2"], level0["sdcrack"]["u_l2"],
                            rel_tol=1e-6)
    assert set(wp["speedup_solver_time"]) == set(wp["speedup_wall_time"]) == set(FOUR)
    assert [x["level"] for x in wp["lumped_vs_consistent"]] == [0, 1]
    assert [x["level"] for x in wp["lumped_vs_consistent_ptangential"]] == [0, 1]
    assert set(wp["ptangential_vs_continuous"]) == {"sdcrack-ptangential",
                                                   "sdcrack-lumped-ptangential"}
    assert wp["graded_goal"] == wp["graded_goal_issue32"] == []
    md = (tmp_path / "work_precision.md").read_text()
    assert "| 0 | sdcrack (lumped p) |" in md and "| 1 | sdcrack |" in md
    assert "| 0 | sdcrack (broken-tangential p) |" in md
    assert "| 1 | sdcrack (lumped, broken-tangential p) |" in md
    assert (tmp_path / "work_precision.png").stat().st_size > 0
    load = (tmp_path / "work_precision.load.txt").read_text().splitlines()
    assert sum(" try 1: " in x for x in load) == 8


@pytest.mark.skipif(not EXE.exists(), reason="target/release/sdcrack not built")
def test_end_to_end_graded_broken_tangential_only(tmp_path):
    scenes = ROOT / "scenes"
    subprocess.run([sys.executable, str(SCRIPT), "--scene", str(scenes / "open-exact.toml"),
                    "--graded-scene", str(scenes / "open-graded.toml"), "--levels", "0",
                    "--graded-levels", "0-1", "--tools", "", "--p-masses", "lumped",
                    "--p-spaces", "broken-tangential", "--no-idle-wait", "--out", str(tmp_path)],
                   check=True, capture_output=True, text=True)
    wp = json.loads((tmp_path / "work_precision.json").read_text())
    assert wp["p_masses"] == ["lumped"] and wp["p_spaces"] == ["broken-tangential"]
    assert [set(r) for r in wp["levels"]] == [
        {"level", "sdcrack-lumped-ptangential", "sdcrack-lumped-ptangential@graded"},
        {"level", "sdcrack-lumped-ptangential@graded"}]
    assert set(wp["speedup_graded_wall_time"]) == {"sdcrack-lumped-ptangential@graded"}
    # one p mass, one p space: nothing to compare them with; no graded reference: no issue-32 goal
    assert wp["lumped_vs_consistent"] == wp["lumped_vs_consistent_ptangential"] == []
    assert wp["ptangential_vs_continuous"] == {} and wp["graded_goal_issue32"] == []


def graded_rows():
    """hand_rows() plus graded curves. Graded sdcrack consistent: e 0.02 → 0.01 at wall 0.01 →
    0.04 (t ∝ e⁻²); lumped: e 0.03 → 0.025 (never reaching the uniform references' finest 0.02).
    Graded references: e 0.04 → 0.01 at wall 0.1 → 0.2."""
    rows = hand_rows()
    rows[0].update({"sdcrack@graded": entry(0.02, 0.005, 0.01),
                    "sdcrack-lumped@graded": entry(0.03, 0.005, 0.01),
                    "dolfinx@graded": entry(0.04, 0.05, 0.1), "freefem@graded": entry(0.04, 0.05, 0.2)})
    rows[1].update({"sdcrack@graded": entry(0.01, 0.02, 0.04),
                    "sdcrack-lumped@graded": entry(0.025, 0.02, 0.04),
                    "dolfinx@graded": entry(0.01, 0.1, 0.2), "freefem@graded": entry(0.01, 0.1, 0.4)})
    return rows


def test_graded_speedups_against_every_curve():
    rows = graded_rows()
    fast = br.speedups(rows, "wall_s", "sdcrack@graded", br.graded_against("sdcrack"))
    assert [x["level"] for x in fast] == [0, 1]
    # e = 0.02: uniform dolfinx wall 1·(0.08/0.02)² = 16, FreeFEM 8, over 0.01
    assert fast[0]["dolfinx"] == pytest.approx(1600, rel=1e-12)
    assert fast[0]["freefem"] == pytest.approx(800, rel=1e-12)
    # graded dolfinx between (0.04, 0.1) and (0.01, 0.2): t = 0.1·2^{log(2)/log(4)} = 0.1·√2
    assert fast[0]["dolfinx@graded"] == pytest.approx(10 * 2 ** 0.5, rel=1e-12)
    assert fast[0]["freefem@graded"] == pytest.approx(20 * 2 ** 0.5, rel=1e-12)
    # uniform sdcrack's range is 0.05 → 0.0125 with t ∝ 1/e: 0.1·0.05/0.02 = 0.25 over 0.01
    assert fast[0]["sdcrack"] == pytest.approx(25, rel=1e-12)
    # e = 0.01 is below the uniform curves' ranges; graded dolfinx's finest point is at 0.01
    assert fast[1]["dolfinx"] is None and fast[1]["sdcrack"] is None
    assert fast[1]["dolfinx@graded"] == pytest.approx(5, rel=1e-12)


def test_graded_goal_met_missed_and_unreached():
    goals = {g["variant"]: g for g in br.graded_goal(graded_rows(), ["sdcrack", "sdcrack-lumped"])}
    # the uniform references' finest level is 2 (e 0.02): FreeFEM is faster there (8 s vs 16 s)
    g = goals["sdcrack"]
    assert (g["reference"], g["reference_level"], g["u_l2"]) == ("freefem", 2, 0.02)
    # graded consistent reaches e 0.02 at its level 0 (0.01 s): 800×, met
    assert g["graded_wall_s"] == pytest.approx(0.01) and g["ratio"] == pytest.approx(800)
    assert g["met"] and "MET (800.0x" in br.goal_line(g)
    # lumped never gets below 0.025: missed, in words
    g = goals["sdcrack-lumped"]
    assert g["ratio"] is None and not g["met"]
    assert br.goal_line(g).endswith("MISSED (the graded errors do not reach it)")
    # a slower graded variant (damaged: 100× the wall time) misses the goal
    rows = graded_rows()
    for r in rows[:2]:
        r["sdcrack@graded"]["wall_s"] *= 100
    slow = br.graded_goal(rows, ["sdcrack"])[0]
    assert slow["ratio"] == pytest.approx(8) and not slow["met"]
    assert "MISSED (8.0x" in br.goal_line(slow)


def test_markdown_has_the_graded_table_and_goal_lines():
    rows = graded_rows()
    keys = ("sdcrack", "sdcrack-lumped")
    fast = {k: br.speedups(rows, "solver_s", k) for k in keys}
    wall = {k: br.speedups(rows, "wall_s", k) for k in keys}
    gf = {br.graded(k): br.speedups(rows, "wall_s", br.graded(k), br.graded_against(k))
          for k in keys}
    md = br.markdown("hand", rows, fast, wall, (), gf, br.graded_goal(rows, keys), "hand-graded")
    lines = md.splitlines()
    assert "| 0 | sdcrack, graded | 100 | 2.000e-02 | 0.01 | 0.01 | – | – |" in lines
    assert "| 1 | dolfinx, graded | 100 | 1.000e-02 | 0.20 | 0.10 | – | – |" in lines
    assert "| 0 | consistent | 2.000e-02 | 1600.0× | 800.0× | 14.1× | 28.3× | 25.0× |" in lines
    assert sum(x.startswith("goal: ") for x in lines) == 2


def test_variant_row_keys_labels_and_commands():
    # continuous p keeps the keys from before the p spaces; the broken-tangential p adds two
    assert br.VARIANTS == {("consistent", "continuous"): "sdcrack",
                           ("lumped", "continuous"): "sdcrack-lumped",
                           ("consistent", "broken-tangential"): "sdcrack-ptangential",
                           ("lumped", "broken-tangential"): "sdcrack-lumped-ptangential"}
    assert [br.label(k) for k in FOUR] == [
        "sdcrack", "sdcrack (lumped p)", "sdcrack (broken-tangential p)",
        "sdcrack (lumped, broken-tangential p)"]
    assert br.label("sdcrack-lumped-ptangential@graded") \
        == "sdcrack (lumped, broken-tangential p), graded"
    assert [br.variant_name(k) for k in FOUR] == [
        "consistent", "lumped", "consistent, broken-tangential p", "lumped, broken-tangential p"]
    assert br.variant_of("sdcrack-ptangential@graded") == ("consistent", "broken-tangential")
    cmd = [str(x) for x in br.sdcrack_command("s.toml", 3, "out", "lumped", "broken-tangential")]
    assert cmd[1:] == ["run", "s.toml", "--level", "3", "--u-space", "broken", "--multiplier",
                       "M1", "--p-mass", "lumped", "--p-space", "broken-tangential", "--delta",
                       "0", "--out", "out", "--quiet"]
    # the default p space is the paper's, named on the command line all the same
    assert "continuous" in [str(x) for x in br.sdcrack_command("s.toml", 0, "out")]


def test_parse_p_spaces():
    assert br.parse_p_spaces("continuous,broken-tangential") == ["continuous", "broken-tangential"]
    assert br.parse_p_spaces("broken-tangential") == ["broken-tangential"]
    assert br.parse_p_spaces("broken-tangential,continuous,broken-tangential,") \
        == ["broken-tangential", "continuous"]
    for bad in ("", ",", "broken", "continuous,tangential"):
        with pytest.raises(argparse.ArgumentTypeError):
            br.parse_p_spaces(bad)


@pytest.mark.parametrize("args, bad", [(["--p-spaces", "continuous,broken"], "'broken' unknown"),
                                       (["--p-spaces", ""], "(none given)"),
                                       (["--p-masses", "heavy"], "'heavy' unknown")])
def test_a_bad_p_space_exits_2_with_one_line(tmp_path, args, bad):
    out = tmp_path / "out"
    p = subprocess.run([sys.executable, str(SCRIPT), *args, "--out", str(out)],
                       capture_output=True, text=True)
    assert p.returncode == 2 and p.stdout == ""
    lines = p.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("bench-references: p ") and bad in lines[0]
    assert not out.exists()  # nothing ran, nothing written


def issue32_rows(speed=20.0):
    """Graded references at errors 0.08, 0.02, 0.005, 0.00125 (levels 0–3): dolfinx walls
    1, 4, 18, 64 s, FreeFEM 2, 9, 36, 128 s. Graded sdcrack, broken-tangential p, at errors
    0.04, 0.01, 0.0025 (levels 0–2) on the power law t = 0.08 / (speed·e), so that at the
    references' errors inside its range, 0.02 and 0.005, its wall times are 4/speed and
    16/speed: `speed`× faster than dolfinx at 0.02, 18/16·speed× at 0.005, 2.25·speed× than
    FreeFEM at both. 0.08 and 0.00125 are outside its range. The same p mass with the continuous
    p (never held to issue 32's goal) is as fast; the lumped broken-tangential variant at errors
    0.03, 0.025 reaches no reference error."""
    ref = [(0.08, 1.0, 2.0), (0.02, 4.0, 9.0), (0.005, 18.0, 36.0), (0.00125, 64.0, 128.0)]
    rows = [{"level": k, "dolfinx@graded": entry(e, td / 2, td),
             "freefem@graded": entry(e, tf / 2, tf)} for k, (e, td, tf) in enumerate(ref)]
    for k, e in enumerate((0.04, 0.01, 0.0025)):
        t = 0.08 / (speed * e)
        rows[k]["sdcrack-ptangential@graded"] = entry(e, t / 2, t)
        rows[k]["sdcrack@graded"] = entry(e, t / 2, t)
    for k, e in enumerate((0.03, 0.025)):
        rows[k]["sdcrack-lumped-ptangential@graded"] = entry(e, 0.01, 0.02)
    return rows


def test_issue32_goal_met_when_20x_faster():
    goals = br.graded_goal_issue32(issue32_rows(20.0), list(FOUR))
    # only the broken-tangential variants are held to it
    assert [g["variant"] for g in goals] == ["sdcrack-ptangential", "sdcrack-lumped-ptangential"]
    g = goals[0]
    assert g["goal"] == 10 and g["met"]
    assert g["n_references"] == 8 and g["n_matched"] == 4 and g["n_below_goal"] == 0
    assert g["errors"] == [0.0025, 0.04]
    ratios = {(x["reference"], x["level"]): x["ratio"] for x in g["points"]}
    assert ratios[("dolfinx@graded", 1)] == pytest.approx(20, rel=1e-12)  # 4 / 0.2
    assert ratios[("dolfinx@graded", 2)] == pytest.approx(22.5, rel=1e-12)  # 18 / 0.8
    assert ratios[("freefem@graded", 1)] == pytest.approx(45, rel=1e-12)  # 9 / 0.2
    assert ratios[("freefem@graded", 2)] == pytest.approx(45, rel=1e-12)  # 36 / 0.8
    # the worst factor and where it occurs
    w = g["worst"]
    assert (w["reference"], w["level"], w["u_l2"]) == ("dolfinx@graded", 1, 0.02)
    assert w["wall_s"] == pytest.approx(0.2, rel=1e-12) and g["ratio"] == pytest.approx(20)
    line = br.goal_line_issue32(g)
    assert line.startswith("goal (issue 32): sdcrack (broken-tangential p), graded >= 10x faster "
                           "by wall time than dolfinx and FreeFEM")
    assert (": MET (worst 20.0x against dolfinx, graded at level 1, error 2.000e-02: 4.00 s vs "
            "0.200 s; 4 of 8 graded reference errors matched, 0 below 10x; not matched") in line
    assert json.loads(json.dumps(goals)) == goals  # JSON as it is


def test_issue32_goal_missed_when_5x_faster():
    goals = br.graded_goal_issue32(issue32_rows(5.0), ["sdcrack-ptangential"])
    (g,) = goals
    assert not g["met"] and g["n_matched"] == 4
    # 5× and 5.625× against dolfinx, 11.25× against FreeFEM: two of four below the goal
    assert g["ratio"] == pytest.approx(5, rel=1e-12) and g["n_below_goal"] == 2
    assert (g["worst"]["reference"], g["worst"]["level"]) == ("dolfinx@graded", 1)
    line = br.goal_line_issue32(g)
    assert ": MISSED (worst 5.0x against dolfinx, graded at level 1" in line
    assert "4 of 8 graded reference errors matched, 2 below 10x" in line


def test_issue32_goal_reports_unmatched_errors_and_never_counts_them():
    goals = {g["variant"]: g for g in br.graded_goal_issue32(issue32_rows(20.0), list(FOUR))}
    g = goals["sdcrack-ptangential"]
    unmatched = [(x["reference"], x["level"]) for x in g["points"] if not x["matched"]]
    assert unmatched == [("dolfinx@graded", 0), ("dolfinx@graded", 3), ("freefem@graded", 0),
                         ("freefem@graded", 3)]
    assert all(x["ratio"] is None and x["wall_s"] is None for x in g["points"]
               if not x["matched"])
    assert br.goal_line_issue32(g).endswith(
        "; not matched, outside its errors 2.500e-03..4.000e-02: dolfinx, graded L0 (8.000e-02), "
        "dolfinx, graded L3 (1.250e-03), freefem, graded L0 (8.000e-02), freefem, graded L3 "
        "(1.250e-03))")
    # a variant whose errors reach no reference error: MISSED, not met by default
    g = goals["sdcrack-lumped-ptangential"]
    assert g["n_matched"] == 0 and g["worst"] is None and g["ratio"] is None and not g["met"]
    line = br.goal_line_issue32(g)
    assert ": MISSED (none of the 8 graded reference errors matched; not matched" in line
    # an unmatched error far slower for the reference does not rescue a missed goal either way
    rows = issue32_rows(5.0)
    rows[0]["dolfinx@graded"]["wall_s"] = 1e6
    assert not br.graded_goal_issue32(rows, ["sdcrack-ptangential"])[0]["met"]
    # no graded reference ran: no goal to hold
    bare = [{k: v for k, v in r.items() if "@graded" not in k or k.startswith("sdcrack")}
            for r in issue32_rows()]
    assert br.graded_goal_issue32(bare, list(FOUR)) == []


def four_variant_rows():
    """graded_rows() plus the broken-tangential variants.
    Uniform, consistent: e 0.025 → 0.00625, solve 0.01 → 0.04, wall 0.1 → 0.4 (t ∝ 1/e);
    lumped: e 0.0125 → 0.0025, solve 0.01 → 0.04, wall 0.4.
    Graded, consistent: e 0.01 → 0.001 at wall 0.01 → 0.04; lumped: e 0.02 → 0.004."""
    rows = graded_rows()
    rows[0].update({"sdcrack-ptangential": entry(0.025, 0.01, 0.1, 0.02),
                    "sdcrack-lumped-ptangential": entry(0.0125, 0.01, 0.4, 0.03),
                    "sdcrack-ptangential@graded": entry(0.01, 0.005, 0.01),
                    "sdcrack-lumped-ptangential@graded": entry(0.02, 0.005, 0.01)})
    rows[1].update({"sdcrack-ptangential": entry(0.00625, 0.04, 0.4, 0.05),
                    "sdcrack-lumped-ptangential": entry(0.0025, 0.04, 0.4, 0.05),
                    "sdcrack-ptangential@graded": entry(0.001, 0.02, 0.04),
                    "sdcrack-lumped-ptangential@graded": entry(0.004, 0.02, 0.04)})
    return rows


def test_p_space_comparisons_by_hand():
    rows = four_variant_rows()
    # broken-tangential at e 0.025: the continuous consistent curve (t ∝ 1/e through
    # 0.05 → 0.0125) takes solve 0.02, wall 0.2 there; the broken-tangential one 0.01 and 0.1
    pt = br.ptangential_vs_continuous(rows, "consistent")
    assert pt[0]["solve"] == pytest.approx(2.0, rel=1e-12)
    assert pt[0]["wall"] == pytest.approx(2.0, rel=1e-12)
    assert pt[1]["solve"] is None  # 0.00625 is below the continuous curve's 0.0125
    # graded: the continuous curve (t ∝ e⁻², 0.02 → 0.01) at 0.01: wall 0.04, solve 0.02
    g = br.ptangential_vs_continuous(rows, "consistent", br.GRADED)
    assert g[0]["wall"] == pytest.approx(4.0, rel=1e-12)
    assert g[0]["solve"] == pytest.approx(4.0, rel=1e-12)
    # lumped against consistent, both broken-tangential: as for the continuous p
    lvc = br.lumped_vs_consistent(rows, "broken-tangential")
    assert lvc[0]["solve"] == pytest.approx(2.0, rel=1e-12)
    assert lvc[0]["wall"] == pytest.approx(0.5, rel=1e-12)
    assert lvc[1]["solve"] is None
    assert br.lumped_vs_consistent(rows) == br.lumped_vs_consistent(hand_rows())
    # the speed-ups of a broken-tangential variant against the references
    s = br.speedups(rows, "solver_s", "sdcrack-ptangential")
    w = br.speedups(rows, "wall_s", "sdcrack-ptangential")
    assert s[0]["dolfinx"] == pytest.approx(102.4) and w[0]["freefem"] == pytest.approx(51.2)
    # the graded broken-tangential variant against itself on uniform meshes
    f = br.speedups(rows, "wall_s", "sdcrack-ptangential@graded",
                    br.graded_against("sdcrack-ptangential"))
    assert set(f[0]) == {"level", "u_l2", "dolfinx", "freefem", "dolfinx@graded",
                         "freefem@graded", "sdcrack-ptangential"}
    # e 0.01 on the uniform curve t ∝ 1/e through (0.025, 0.1): 0.25, over 0.01
    assert f[0]["sdcrack-ptangential"] == pytest.approx(25, rel=1e-12)


def test_markdown_covers_every_variant_and_both_goals():
    rows = four_variant_rows()
    fast = {k: br.speedups(rows, "solver_s", k) for k in FOUR}
    wall = {k: br.speedups(rows, "wall_s", k) for k in FOUR}
    lumped = {sp: br.lumped_vs_consistent(rows, sp) for sp in br.P_SPACES}
    gf = {br.graded(k): br.speedups(rows, "wall_s", br.graded(k), br.graded_against(k))
          for k in FOUR}
    pt = {br.variant_key(m, "broken-tangential") + suffix:
          br.ptangential_vs_continuous(rows, m, suffix)
          for suffix in ("", br.GRADED) for m in br.P_MASSES}
    md = br.markdown("hand", rows, fast, wall, lumped, gf, br.graded_goal(rows, list(FOUR)),
                     "hand-graded", pt, br.graded_goal_issue32(rows, list(FOUR)))
    lines = md.splitlines()
    # the level table: every variant, uniform and graded
    assert "| 0 | sdcrack (broken-tangential p) | 100 | 2.500e-02 | 0.10 | 0.01 | 0.02 | 2.0 |" \
        in lines
    assert "| 1 | sdcrack (lumped, broken-tangential p), graded | 100 | 4.000e-03 | 0.04 | 0.02 " \
           "| – | – |" in lines
    # the speed-up table, in the order of the variants at each level
    speed = [x for x in lines if x.startswith("| 0 | ") and x.count("|") == 8
             and "e-0" in x.split("|")[3]][:4]
    assert [x.split(" | ")[1] for x in speed] == [
        "consistent", "lumped", "consistent, broken-tangential p", "lumped, broken-tangential p"]
    assert ("| 0 | consistent, broken-tangential p | 2.500e-02 | 102.4× | 204.8× | 102.4× "
            "| 51.2× |") in lines
    # lumped against consistent: one table per p space, the same columns
    assert lines.count("| level | lumped ‖u_h − u‖ | solve | wall |") == 2
    assert any("both with the broken-tangential p" in x for x in lines)
    # broken-tangential against continuous p, uniform and graded
    assert "| level | variant | ‖u_h − u‖ | solve | wall |" in lines
    assert "| 0 | sdcrack (broken-tangential p) | 2.500e-02 | 2.0× | 2.0× |" in lines
    assert "| 0 | sdcrack (broken-tangential p), graded | 1.000e-02 | 4.0× | 4.0× |" in lines
    assert "| 1 | sdcrack (broken-tangential p) | 6.250e-03 | – | – |" in lines
    # the graded table: a line per graded variant and level
    assert sum(x.startswith("| 0 | lumped, broken-tangential p | 2.000e-02 |") for x in lines) == 1
    # issue 24's line for every variant, issue 32's for the broken-tangential ones
    assert sum(x.startswith("goal: ") for x in lines) == 4
    g32 = [x for x in lines if x.startswith("goal (issue 32): ")]
    assert len(g32) == 2
    # graded consistent broken-tangential: at 0.01 (its level 0, 0.01 s) dolfinx graded takes
    # 0.2 s, FreeFEM 0.4 s; the references' 0.04 is above its errors
    assert g32[0].startswith("goal (issue 32): sdcrack (broken-tangential p), graded")
    assert ": MET (worst 20.0x against dolfinx, graded at level 1" in g32[0]
    assert "2 of 4 graded reference errors matched" in g32[0]


def test_plot_tells_the_p_spaces_apart(tmp_path):
    fig = br.plot(four_variant_rows(), tmp_path / "wp.png", "hand")
    lines = {x.get_label(): x for x in fig.axes[0].get_lines()}
    # four sdcrack variants and two references, on uniform and graded meshes
    assert len(lines) == 12 and len(fig.axes[1].get_lines()) == 12
    for mass, cont, tang in (("sdcrack", "sdcrack", "sdcrack (broken-tangential p)"),
                             ("lumped", "sdcrack (lumped p)",
                              "sdcrack (lumped, broken-tangential p)")):
        for suffix in ("", ", graded"):
            c, t = lines[cont + suffix], lines[tang + suffix]
            # same colour (tool and p mass), same dashing (mesh kind), another marker (p space)
            assert c.get_color() == t.get_color() and c.get_linestyle() == t.get_linestyle()
            assert c.get_marker() != t.get_marker()
    assert lines["sdcrack (broken-tangential p)"].get_markerfacecolor() == "none"
    assert lines["sdcrack (broken-tangential p), graded"].get_linestyle() == "-"
    # every (colour, marker, dashing) is a different curve
    assert len({(x.get_color(), x.get_marker(), x.get_linestyle()) for x in lines.values()}) == 12
    assert len(fig.legends) == 1 and len(fig.legends[0].get_texts()) == 12
    assert (tmp_path / "wp.png").stat().st_size > 0
