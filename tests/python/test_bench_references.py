"""ci/bench_references.py: equal-error speed-ups of both p masses, the report, load control.

The arithmetic is checked on hand-made rows whose expected ratios are worked out by hand below;
one end-to-end run times the real binary on levels 0–1 of scenes/open-exact.toml (sdcrack alone).
"""

import json
import math
import pathlib
import subprocess
import sys

import pytest

import ci_script

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "ci" / "bench_references.py"
EXE = ROOT / "target" / "release" / "sdcrack"


br = ci_script.load("ci/bench_references.py")


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
    # one colour per tool and p mass (issue 25: consistent and lumped differ by more than dashing)
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


@pytest.mark.skipif(not EXE.exists(), reason="target/release/sdcrack not built")
def test_end_to_end_both_p_masses(tmp_path):
    scene = ROOT / "scenes" / "open-exact.toml"
    subprocess.run([sys.executable, str(SCRIPT), "--scene", str(scene), "--levels", "0-1",
                    "--tools", "", "--no-idle-wait", "--out", str(tmp_path)],
                   check=True, capture_output=True, text=True)
    wp = json.loads((tmp_path / "work_precision.json").read_text())
    assert wp["scene"] == "open-exact"
    assert wp["p_masses"] == ["consistent", "lumped"]
    assert [r["level"] for r in wp["levels"]] == [0, 1]
    for row in wp["levels"]:
        assert set(row) == {"level", "sdcrack", "sdcrack-lumped"}
        for key in ("sdcrack", "sdcrack-lumped"):
            x = row[key]
            assert x["wall_s"] > 0 and x["solver_s"] > 0 and x["norms_s"] > 0
            assert x["kkt"] < 1e-10 and x["load"]["tries"] == 1
        assert row["sdcrack"]["unknowns"] == row["sdcrack-lumped"]["unknowns"]
    # docs/performance.md: sdcrack's level-0 error on open-exact (consistent p mass)
    assert f"{wp['levels'][0]['sdcrack']['u_l2']:.3e}" == "4.430e-02"
    assert not math.isclose(wp["levels"][0]["sdcrack-lumped"]["u_l2"],
                            wp["levels"][0]["sdcrack"]["u_l2"], rel_tol=1e-6)
    assert set(wp["speedup_solver_time"]) == set(wp["speedup_wall_time"]) \
        == {"sdcrack", "sdcrack-lumped"}
    assert [x["level"] for x in wp["lumped_vs_consistent"]] == [0, 1]
    md = (tmp_path / "work_precision.md").read_text()
    assert "| 0 | sdcrack (lumped p) |" in md and "| 1 | sdcrack |" in md
    assert (tmp_path / "work_precision.png").stat().st_size > 0
    load = (tmp_path / "work_precision.load.txt").read_text().splitlines()
    assert sum(" try 1: " in x for x in load) == 4


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
