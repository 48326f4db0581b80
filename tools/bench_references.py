#!/usr/bin/python3
"""Work-precision benchmark: sdcrack against the dolfinx and FreeFEM references.

For one scene with an `[exact]` solution and each level, runs (one process per tool and level,
timed from outside with a wall clock):

* sdcrack: `sdcrack run` of one case (broken u, M1, δ = 0; no fields, no reference run), once per
  p mass of `--p-masses` and p space of `--p-spaces` (`--p-mass PM --p-space PS`), under the row
  keys
    `sdcrack`                    consistent p mass (the paper's), continuous p (the paper's),
    `sdcrack-lumped`             lumped p mass, continuous p,
    `sdcrack-ptangential`        consistent p mass, broken-tangential p (p's tangential component
                                 may jump across the crack; broken u only),
    `sdcrack-lumped-ptangential` lumped p mass, broken-tangential p
  (labels `sdcrack`, `sdcrack (lumped p)`, `sdcrack (broken-tangential p)`, `sdcrack (lumped,
  broken-tangential p)`);
* dolfinx / FreeFEM: `sdcrack mesh` (not timed: it is shared input), then the reference script.

Each tool reports its own ‖u_h − u‖_{L²} against the exact solution, each with a tip-graded
quadrature (sdcrack: collapsed Gauss rules graded toward the tips; dolfinx: UFL forms with rules
collapsed at the tips; FreeFEM's script: numpy rules graded toward the tips on the cracked mesh). Two times are tabulated: the process wall time (start-up, imports, assembly, solve and
error evaluation), and the solve time by each tool's own timer without start-up and without the
error evaluation (sdcrack: its phases but `norms`; dolfinx: assembly + solve; FreeFEM: the
FreeFem++ run). The speed-up at equal error interpolates each reference's (error, time) curve
log-log at each sdcrack variant's errors and divides by that variant's time of the same kind; the
lumped variant of each p space is also compared with the consistent one the same way
(consistent's time at lumped's error / lumped's time), and the broken-tangential variant of each p
mass with the continuous one (continuous's time at broken-tangential's error / its time).

Load control: before each measurement (one tool at one level) the script waits until the machine
is idle (1-min load average < 1.0 and other processes < 0.1 core over 2 s; it gives up after
`--idle-timeout` s, measures anyway and marks it IDLE-TIMEOUT). During the measurement it takes
foreign cores = (busy time of /proc/stat's `cpu` line − CPU time of this process and its children,
from os.times()) / wall; at ≥ 0.2 core the measurement is rejected and repeated, at most
`--max-tries` times (the last try is kept, marked REJECTED-KEPT). `--no-idle-wait` disables both.
One line per try goes to OUT/work_precision.load.txt.

Writes OUT/work_precision.{json,md,png} and prints the Markdown table. The JSON has
`scene`, `p_masses`, `p_spaces`, `levels` (one object per level: `level` and, per tool present at
that level, an object with wall_s, solver_s, u_l2, unknowns, kkt, the load check `load` {status,
tries, foreign_cores} and, for sdcrack, norms_s; tool keys the four sdcrack row keys above,
`dolfinx`, `freefem`), `speedup_solver_time` and `speedup_wall_time` (dicts keyed by sdcrack
variant row key, each a list of {level, u_l2, dolfinx, freefem}, the ratios or null outside the
reference's range), `lumped_vs_consistent` (continuous p) and `lumped_vs_consistent_ptangential`
(broken-tangential p), each a list of {level, u_l2, solve, wall}: consistent's time at lumped's
error / lumped's time, null outside consistent's range, [] unless both p masses ran, and
`ptangential_vs_continuous` (a dict keyed by the broken-tangential row key, `sdcrack-ptangential`,
`sdcrack-lumped-ptangential` and, with a graded scene, the same with `@graded`; each a list of
{level, u_l2, solve, wall}: the continuous variant's time, same p mass and meshes, at its error /
its time; {} unless both p spaces ran).

With `--graded-scene` (the same problem on meshes graded towards the crack tips, e.g.
scenes/open-graded.toml) every tool also runs on that scene's levels, under row keys with the
suffix `@graded` (`sdcrack@graded`, `sdcrack-ptangential@graded`, `dolfinx@graded`, …). Each
graded sdcrack variant is then compared by wall time, at its own errors, with both references on
the uniform meshes, both on the graded meshes and itself on the uniform meshes (JSON
`speedup_graded_wall_time`, keyed by the graded row key, entries {level, u_l2, dolfinx, freefem,
dolfinx@graded, freefem@graded, and the variant's own uniform row key}), and held to two goals,
each printed as one line per variant with MET or MISSED:

* issue 24 (every variant): ≥ 100× faster than the faster uniform reference at the finest error
  that reference reaches (JSON `graded_goal`, a list of {variant, reference, reference_level,
  u_l2, reference_wall_s, graded_wall_s, ratio, met});
* issue 32 (the broken-tangential variants): "graded sdcrack reaches every graded reference error
  faster than dolfinx and FreeFEM by wall time, ≥ 10× at every matched error". At each level of
  dolfinx@graded and freefem@graded whose error lies within the variant's own graded errors, the
  reference's wall time / the variant's wall time interpolated log-log at that error must be
  ≥ 10. A reference error outside the variant's range is not matched: listed as such, never
  counted as met; with none matched the goal is MISSED. The line gives the worst (smallest)
  factor, the reference and level where it occurs, and how many reference errors were matched.
  JSON `graded_goal_issue32`, a list of {variant, goal, points (one per reference level:
  {reference, level, u_l2, reference_wall_s, wall_s, ratio, matched}; wall_s and ratio null when
  not matched), errors ([smallest, largest] of the variant's graded errors), n_references,
  n_matched, n_below_goal, worst (the point of the smallest ratio, or null), ratio (its ratio),
  met}.

The plot draws uniform meshes dashed with open markers and graded meshes solid with filled ones,
one colour per tool and p mass, sdcrack's p space by the marker (continuous: circle for the
consistent, diamond for the lumped p mass; broken-tangential: plus, cross).
"""

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SDCRACK = ROOT / "target" / "release" / "sdcrack"
TOOLS = ("dolfinx", "freefem")
# sdcrack's p masses and p spaces (`--p-mass`, `--p-space`); a variant is one of each
P_MASSES = ("consistent", "lumped")
P_SPACES = ("continuous", "broken-tangential")
# (p mass, p space) → row key: `sdcrack`, `sdcrack-lumped` (continuous p, the keys from before the
# p spaces), `sdcrack-ptangential`, `sdcrack-lumped-ptangential`
VARIANTS = {(m, s): "sdcrack" + ("-lumped" if m == "lumped" else "")
            + ("-ptangential" if s == "broken-tangential" else "")
            for s in P_SPACES for m in P_MASSES}
LABELS = {"sdcrack": "sdcrack", "sdcrack-lumped": "sdcrack (lumped p)",
          "sdcrack-ptangential": "sdcrack (broken-tangential p)",
          "sdcrack-lumped-ptangential": "sdcrack (lumped, broken-tangential p)"}
# a row key on the graded scene's meshes: the tool's key with this suffix
GRADED = "@graded"
# the goal of issue 24: graded sdcrack this many times faster by wall time than the faster
# uniform reference at the finest error that reference reaches
GRADED_GOAL = 100.0
# the goal of issue 32: graded sdcrack with the broken-tangential p this many times faster by wall
# time than each graded reference at every error of that reference its own errors reach
GRADED_GOAL_ISSUE32 = 10.0
IDLE_LOAD = 1.0  # 1-min load average below which the machine counts as idle
IDLE_FOREIGN = 0.1  # cores used by other processes below which the machine counts as idle
REJECT_FOREIGN = 0.2  # cores used by other processes during a measurement that reject it
LOAD_HEADER = """\
# Load during each measurement (tools/bench_references.py). One line per try:
#   time tool level try n: wall (s of the try) own cpu (s of CPU used by this script and its
#   children) foreign (cores used by other processes: /proc/stat busy time minus own cpu, over
#   wall) steal (cores stolen by the hypervisor) load (1-min load average before->after) verdict
# Verdicts: OK; REJECTED (foreign >= 0.2 core, repeated); REJECTED-KEPT (the last try, kept);
# UNCHECKED (foreign >= 0.2 core under --no-idle-wait); IDLE-TIMEOUT appended when the wait for
# an idle machine (load < 1.0, foreign < 0.1 core over 2 s) gave up.
"""


def run_timed(cmd, env=None):
    """Runs `cmd`, returns wall seconds; raises with the tool's stderr on failure."""
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} failed ({p.returncode}): {p.stderr.strip()}")
    return wall


def sdcrack_only_scene(scene_text):
    """The scene with no reference run and no field output (what sdcrack is timed on)."""
    text = re.sub(r"(?m)^references\s*=.*$", "references = []", scene_text)
    return re.sub(r"(?m)^fields\s*=.*$", "fields = []", text)


def parse_loadavg(text):
    """The 1-min load average from the text of /proc/loadavg."""
    return float(text.split()[0])


def parse_proc_stat(text, hz):
    """(busy s, steal s) of all CPUs together from the text of /proc/stat's `cpu` line.

    Busy: user + nice + system + irq + softirq (guest time is already in user and nice); idle,
    iowait and steal are not busy."""
    line = next(x for x in text.splitlines() if x.split()[0] == "cpu")
    v = [int(x) for x in line.split()[1:]] + [0] * 10
    user, nice, system, _idle, _iowait, irq, softirq, steal = v[:8]
    return (user + nice + system + irq + softirq) / hz, steal / hz


def snapshot():
    """Monotonic time, busy and steal CPU s of the machine, own CPU s and the 1-min load."""
    busy, steal = parse_proc_stat(Path("/proc/stat").read_text(), os.sysconf("SC_CLK_TCK"))
    t = os.times()
    return {"t": time.monotonic(), "busy_s": busy, "steal_s": steal,
            "own_s": t.user + t.system + t.children_user + t.children_system,
            "load": parse_loadavg(Path("/proc/loadavg").read_text())}


def foreign_cores(s0, s1):
    """Cores used by other processes between two snapshots: (busy − own CPU time) / wall."""
    return ((s1["busy_s"] - s0["busy_s"]) - (s1["own_s"] - s0["own_s"])) / (s1["t"] - s0["t"])


def idle_sample(seconds=2.0):
    """(1-min load average, foreign cores over the next `seconds`)."""
    s0 = snapshot()
    time.sleep(seconds)
    return s0["load"], foreign_cores(s0, snapshot())


def wait_idle(timeout, sample=idle_sample, clock=time.monotonic):
    """Waits until the machine is idle; False if it still is not after `timeout` s."""
    start = clock()
    while True:
        load, foreign = sample()
        if load < IDLE_LOAD and foreign < IDLE_FOREIGN:
            return True
        if clock() - start >= timeout:
            return False


def verdict(foreign, tries, max_tries, check):
    """OK, REJECTED (to repeat), REJECTED-KEPT (the last try) or UNCHECKED (no check)."""
    if foreign < REJECT_FOREIGN:
        return "OK"
    if not check:
        return "UNCHECKED"
    return "REJECTED" if tries < max_tries else "REJECTED-KEPT"


def measure(label, fn, log, check=True, idle_timeout=300.0, max_tries=3):
    """Runs `fn()` (one tool at one level) under load control, logs each try to `log` (an open
    file; `label` like 'sdcrack L0'), returns fn's dict with the load check under `load`."""
    max_tries = max(1, max_tries)
    for tries in range(1, max_tries + 1):
        idle = wait_idle(idle_timeout) if check else True
        s0 = snapshot()
        result = fn()
        s1 = snapshot()
        wall = s1["t"] - s0["t"]
        foreign = foreign_cores(s0, s1)
        status = verdict(foreign, tries, max_tries, check)
        log.write(f"{time.strftime('%H:%M:%S')} {label} try {tries}: wall {wall:.2f} s own cpu "
                  f"{s1['own_s'] - s0['own_s']:.2f} foreign {foreign:.2f} steal "
                  f"{(s1['steal_s'] - s0['steal_s']) / wall:.2f} load {s0['load']:.2f}->"
                  f"{s1['load']:.2f} {status}{'' if idle else ' IDLE-TIMEOUT'}\n")
        log.flush()
        if status != "REJECTED":
            break
    result["load"] = {"status": status + ("" if idle else " IDLE-TIMEOUT"), "tries": tries,
                      "foreign_cores": foreign}
    return result


def graded(key):
    """The row key of `key` (a tool or sdcrack variant) on the graded scene's meshes."""
    return key + GRADED


def variant_key(p_mass="consistent", p_space="continuous"):
    """The row key of the sdcrack variant with this p mass and p space."""
    return VARIANTS[(p_mass, p_space)]


def variant_of(key):
    """(p mass, p space) of an sdcrack variant's row key (with or without the graded suffix)."""
    base = key.removesuffix(GRADED)
    return next(v for v, k in VARIANTS.items() if k == base)


def variant_name(key):
    """The variant column of the speed-up tables: 'consistent', 'lumped', 'consistent,
    broken-tangential p', 'lumped, broken-tangential p'."""
    mass, space = variant_of(key)
    return mass if space == "continuous" else f"{mass}, {space} p"


def label(key):
    """'sdcrack (lumped p), graded' for 'sdcrack-lumped@graded'."""
    base = key.removesuffix(GRADED)
    return LABELS.get(base, base) + (", graded" if key.endswith(GRADED) else "")


def sdcrack_command(scene_file, level, out, p_mass="consistent", p_space="continuous"):
    """The `sdcrack run` of one case: broken u, M1, δ = 0, this p mass and p space."""
    return [SDCRACK, "run", scene_file, "--level", str(level), "--u-space", "broken",
            "--multiplier", "M1", "--p-mass", p_mass, "--p-space", p_space, "--delta", "0",
            "--out", out, "--quiet"]


def run_sdcrack(scene_file, level, work, p_mass="consistent", tag="", p_space="continuous"):
    """One sdcrack case; `tag` keeps the graded scene's folders apart from the uniform one's."""
    out = work / f"sd{tag}{level}-{p_mass}-{p_space}"
    shutil.rmtree(out, ignore_errors=True)  # a repeated try writes afresh
    wall = run_timed(sdcrack_command(scene_file, level, out, p_mass, p_space))
    (summary,) = out.glob("*/summary.json")
    case = json.loads(summary.read_text())["cases"][0]
    return {
        "wall_s": wall,
        # every phase but the error norms and field arrays (measurement, not solution)
        "solver_s": sum(v for k, v in case["timings_s"].items() if k not in ("norms", "fields")),
        "norms_s": case["timings_s"]["norms"],
        "u_l2": case["errors"]["u_l2"],
        "unknowns": case["unknowns"],
        "kkt": max(case["kkt"].values()),
    }


def run_reference(tool, scene_file, level, work, tag=""):
    mesh = work / f"mesh{tag}{level}"
    if not mesh.exists():
        run_timed([SDCRACK, "mesh", scene_file, "--level", str(level), "--out", mesh])
    out = work / f"{tool}{tag}{level}"
    shutil.rmtree(out, ignore_errors=True)  # a repeated try writes afresh
    env = dict(os.environ, FF_LOADPATH=os.environ.get("FF_LOADPATH", "/usr/lib/freefem++"))
    wall = run_timed(["/usr/bin/python3", ROOT / "references" / tool / "solve.py", mesh,
                      "--out", out], env=env)
    case = json.loads((out / "summary.json").read_text())["cases"][0]
    t = case["timings_s"]
    # assembly and solve, without the error evaluation (dolfinx: its two phases; FreeFEM: the
    # FreeFem++ process, which assembles and solves; errors are computed afterwards in numpy)
    solver = t["assembly"] + t["solve"] if tool == "dolfinx" else t["freefem"]
    return {
        "wall_s": wall,
        "solver_s": solver,
        "u_l2": case["errors"]["u_l2"],
        "unknowns": case["unknowns"],
        "kkt": max(v for v in case["kkt"].values() if v is not None),
    }


def time_at_error(curve, error):
    """Log-log interpolation of a (error, time) curve at `error`; None outside its range."""
    pts = sorted(curve, key=lambda p: -p[0])  # decreasing error
    for (e0, t0), (e1, t1) in zip(pts, pts[1:]):
        if e1 <= error <= e0 and e0 > e1:
            s = (math.log(error) - math.log(e0)) / (math.log(e1) - math.log(e0))
            return math.exp(math.log(t0) + s * (math.log(t1) - math.log(t0)))
    return None


def ratio_at_error(rows, tool, key, e, t):
    """`tool`'s time (`key`) interpolated at error `e`, divided by `t`; None outside its range."""
    tr = time_at_error([(x[tool]["u_l2"], x[tool][key]) for x in rows if tool in x], e)
    return None if tr is None else tr / t


def speedups(rows, key, variant="sdcrack", against=TOOLS):
    """For each row of sdcrack `variant` (a row key): time of each curve of `against` (row keys,
    by default the references on the same meshes) at the variant's error / the variant's time."""
    out = []
    for r in (r for r in rows if variant in r):
        e, t = r[variant]["u_l2"], r[variant][key]
        out.append({"level": r["level"], "u_l2": e,
                    **{other: ratio_at_error(rows, other, key, e, t) for other in against}})
    return out


def graded_against(variant):
    """What a graded sdcrack variant is compared with: both references on uniform meshes, both on
    the graded meshes, and the same variant on uniform meshes."""
    return (*TOOLS, *map(graded, TOOLS), variant)


def finest_uniform_reference(rows):
    """(tool, level, u_l2, wall_s) of the faster uniform reference at the finest level both
    reached (the references solve the same problem on the same mesh: equal errors)."""
    common = [r for r in rows if all(t in r for t in TOOLS)] or [r for r in rows
                                                                 if any(t in r for t in TOOLS)]
    if not common:
        return None
    r = max(common, key=lambda r: r["level"])
    tool = min((t for t in TOOLS if t in r), key=lambda t: r[t]["wall_s"])
    return tool, r["level"], r[tool]["u_l2"], r[tool]["wall_s"]


def graded_goal(rows, variants):
    """Issue 24's goal for each graded sdcrack variant (row keys without the suffix): the faster
    uniform reference's wall time at its finest level / the graded variant's wall time
    interpolated log-log at that error. Ratio None when the graded variant's errors do not
    bracket that error; then the goal is MISSED, said in words."""
    ref = finest_uniform_reference(rows)
    if ref is None:
        return []
    tool, level, e, t = ref
    out = []
    for v in variants:
        curve = [(r[graded(v)]["u_l2"], r[graded(v)]["wall_s"]) for r in rows if graded(v) in r]
        if not curve:
            continue
        tg = time_at_error(curve, e)
        ratio = None if tg is None else t / tg
        out.append({"variant": v, "reference": tool, "reference_level": level, "u_l2": e,
                    "reference_wall_s": t, "graded_wall_s": tg, "ratio": ratio,
                    "met": ratio is not None and ratio >= GRADED_GOAL})
    return out


def goal_line(g):
    """One printed line per graded variant: MET or MISSED with the figures."""
    head = (f"goal: {label(graded(g['variant']))} >= {GRADED_GOAL:.0f}x faster by wall time than "
            f"{g['reference']} on uniform meshes at its finest error ({g['u_l2']:.3e}, level "
            f"{g['reference_level']}, {g['reference_wall_s']:.2f} s): ")
    if g["ratio"] is None:
        return head + "MISSED (the graded errors do not reach it)"
    return head + (f"{'MET' if g['met'] else 'MISSED'} ({g['ratio']:.1f}x, "
                   f"{g['graded_wall_s']:.2f} s)")


def graded_goal_issue32(rows, variants):
    """Issue 32's goal for each graded sdcrack variant with the broken-tangential p among
    `variants` (row keys without the suffix; the others are skipped): at every error of each
    graded reference (every level of dolfinx@graded and freefem@graded) that the graded variant's
    own errors bracket, the reference's wall time / the variant's wall time interpolated log-log
    at that error must be ≥ GRADED_GOAL_ISSUE32. An error outside the variant's range is not
    matched (ratio None) and never counts as met; with no error matched the goal is MISSED. [] when
    no graded reference ran."""
    refs = [graded(t) for t in TOOLS]
    points_ref = [(tool, r["level"], r[tool]["u_l2"], r[tool]["wall_s"])
                  for tool in refs for r in rows if tool in r]
    if not points_ref:
        return []
    out = []
    for v in variants:
        if variant_of(v)[1] != "broken-tangential":
            continue
        curve = [(r[graded(v)]["u_l2"], r[graded(v)]["wall_s"]) for r in rows if graded(v) in r]
        if not curve:
            continue
        points = []
        for tool, level, e, t in points_ref:
            tv = time_at_error(curve, e)
            points.append({"reference": tool, "level": level, "u_l2": e, "reference_wall_s": t,
                           "wall_s": tv, "ratio": None if tv is None else t / tv,
                           "matched": tv is not None})
        matched = [x for x in points if x["matched"]]
        worst = min(matched, key=lambda x: x["ratio"], default=None)
        out.append({"variant": v, "goal": GRADED_GOAL_ISSUE32, "points": points,
                    "errors": [min(e for e, _ in curve), max(e for e, _ in curve)],
                    "n_references": len(points), "n_matched": len(matched),
                    "n_below_goal": sum(x["ratio"] < GRADED_GOAL_ISSUE32 for x in matched),
                    "worst": worst, "ratio": None if worst is None else worst["ratio"],
                    "met": worst is not None and worst["ratio"] >= GRADED_GOAL_ISSUE32})
    return out


def goal_line_issue32(g):
    """One printed line per graded broken-tangential variant: MET or MISSED, the worst factor and
    where it occurs, and how many reference errors were matched (the others listed)."""
    head = (f"goal (issue 32): {label(graded(g['variant']))} >= {g['goal']:.0f}x faster by wall "
            "time than dolfinx and FreeFEM on graded meshes at every graded reference error it "
            "reaches: ")
    lo, hi = g["errors"]
    missed = [x for x in g["points"] if not x["matched"]]
    tail = ""
    if missed:
        tail = (f"; not matched, outside its errors {lo:.3e}..{hi:.3e}: "
                + ", ".join(f"{label(x['reference'])} L{x['level']} ({x['u_l2']:.3e})"
                            for x in missed))
    if g["worst"] is None:
        return head + (f"MISSED (none of the {g['n_references']} graded reference errors "
                       f"matched{tail})")
    w = g["worst"]
    return head + (f"{'MET' if g['met'] else 'MISSED'} (worst {w['ratio']:.1f}x against "
                   f"{label(w['reference'])} at level {w['level']}, error {w['u_l2']:.3e}: "
                   f"{w['reference_wall_s']:.2f} s vs {w['wall_s']:.3f} s; {g['n_matched']} of "
                   f"{g['n_references']} graded reference errors matched, {g['n_below_goal']} "
                   f"below {g['goal']:.0f}x{tail})")


def versus(rows, variant, baseline):
    """For each row of sdcrack `variant` (a row key): `baseline`'s time (another variant's row
    key) interpolated log-log at the variant's error / the variant's time, by both timers (None
    outside the baseline's range)."""
    return [{"level": r["level"], "u_l2": r[variant]["u_l2"],
             **{name: ratio_at_error(rows, baseline, key, r[variant]["u_l2"], r[variant][key])
                for name, key in (("solve", "solver_s"), ("wall", "wall_s"))}}
            for r in rows if variant in r]


def lumped_vs_consistent(rows, p_space="continuous"):
    """For each lumped row of this p space: consistent's time at lumped's error / lumped's time
    (both timers)."""
    return versus(rows, variant_key("lumped", p_space), variant_key("consistent", p_space))


def ptangential_vs_continuous(rows, p_mass="consistent", suffix=""):
    """For each row of the broken-tangential variant of this p mass (on the graded meshes with
    `suffix` GRADED): the continuous-p variant's time (same p mass, same meshes) at its error / its
    time (both timers)."""
    return versus(rows, variant_key(p_mass, "broken-tangential") + suffix,
                  variant_key(p_mass) + suffix)


def fmt_x(v):
    """A ratio as '12.3×', '–' for None."""
    return "–" if v is None else f"{v:.1f}×"


def level_line(level, tool, x):
    """One row of the level table; the norms columns for sdcrack only."""
    norms = "–" if "norms_s" not in x else f"{x['norms_s']:.2f}"
    ratio = ("–" if "norms_s" not in x or x["solver_s"] <= 0
             else f"{x['norms_s'] / x['solver_s']:.1f}")
    return (f"| {level} | {label(tool)} | {x['unknowns']} | {x['u_l2']:.3e} | "
            f"{x['wall_s']:.2f} | {x['solver_s']:.2f} | {norms} | {ratio} |")


def versus_table(intro, first, entries, with_variant=False):
    """A table of versus() entries ({level, u_l2, solve, wall}); `first`: the error column's
    title; `with_variant`: entries are (row key, entry) pairs and get a variant column."""
    head = "| level | variant " if with_variant else "| level "
    lines = ["", intro, "", f"{head}| {first} | solve | wall |",
             "|---|---|---|---|" + ("---|" if with_variant else "")]
    for item in entries:
        key, x = item if with_variant else (None, item)
        mid = f"| {label(key)} " if with_variant else ""
        lines.append(f"| {x['level']} {mid}| {x['u_l2']:.3e} | {fmt_x(x['solve'])} | "
                     f"{fmt_x(x['wall'])} |")
    return lines


def markdown(scene, rows, fast_internal, fast_wall, lumped_fast=(), graded_fast=None, goals=(),
             graded_scene=None, ptangential_fast=None, goals32=()):
    """The report; `fast_internal` / `fast_wall`: speedups() per sdcrack variant (row key);
    `lumped_fast`: lumped_vs_consistent(), a list (continuous p) or a dict keyed by p space;
    `graded_fast`: wall-time speedups() of each graded variant (row key) against
    graded_against(); `goals`: graded_goal(); `ptangential_fast`: ptangential_vs_continuous()
    keyed by the broken-tangential variant's row key (uniform or graded); `goals32`:
    graded_goal_issue32()."""
    lines = [f"# Work-precision: scene `{scene}` (broken u, M1, δ = 0 for sdcrack)", "",
             "Times in seconds, one process per tool and level on this machine. `wall`: the whole "
             "process (start-up, imports, solve and error evaluation); `solve`: the tool's own "
             "timer without start-up and without error evaluation (sdcrack: its phases but the "
             "error norms; dolfinx: assembly + solve; FreeFEM: the FreeFem++ run); `norms`: "
             "sdcrack's error-norm evaluation. `sdcrack`: consistent p mass (the paper's); "
             "`sdcrack (lumped p)`: lumped p mass; both with the continuous p (the paper's). "
             "`sdcrack (broken-tangential p)`, `sdcrack (lumped, broken-tangential p)`: the same "
             "p masses with `--p-space broken-tangential` (p's tangential component may jump "
             "across the crack).", "",
             "| level | tool | unknowns | ‖u_h − u‖_L² | wall s | solve s | norms s "
             "| norms / solve |", "|---|---|---|---|---|---|---|---|"]
    keys = (*VARIANTS.values(), *TOOLS)
    for r in rows:
        lines += [level_line(r["level"], tool, r[tool])
                  for tool in (*keys, *map(graded, keys)) if tool in r]
    lines += ["", "Speed-up of sdcrack at equal error (reference time interpolated log-log at "
              "sdcrack's error, divided by sdcrack's time of the same kind; – where sdcrack's error is "
              "outside the reference's range):", "",
              "| level | variant | sdcrack ‖u_h − u‖ | vs dolfinx (solve) "
              "| vs FreeFEM (solve) | vs dolfinx (wall) | vs FreeFEM (wall) |",
              "|---|---|---|---|---|---|---|"]
    order = list(VARIANTS.values())
    entries = sorted(((a["level"], key, a, b) for key in order
                      for a, b in zip(fast_internal.get(key, []), fast_wall.get(key, []))),
                     key=lambda x: (x[0], order.index(x[1])))
    for level, key, a, b in entries:
        lines.append(f"| {level} | {variant_name(key)} | {a['u_l2']:.3e} | {fmt_x(a['dolfinx'])} | "
                     f"{fmt_x(a['freefem'])} | {fmt_x(b['dolfinx'])} | {fmt_x(b['freefem'])} |")
    if not isinstance(lumped_fast, dict):
        lumped_fast = {"continuous": lumped_fast}
    for space in P_SPACES:
        if not lumped_fast.get(space):
            continue
        which = "" if space == "continuous" else f", both with the {space} p"
        lines += versus_table(
            f"Lumped against consistent p mass at equal error{which} (consistent's time "
            "interpolated log-log at lumped's error, divided by lumped's time; – outside "
            "consistent's range):", "lumped ‖u_h − u‖", lumped_fast[space])
    if ptangential_fast:
        lines += versus_table(
            "Broken-tangential against continuous p at equal error (the continuous-p variant's "
            "time, same p mass and meshes, interpolated log-log at the broken-tangential "
            "variant's error, divided by its time; – outside the continuous variant's range):",
            "‖u_h − u‖", [(k, x) for k, xs in ptangential_fast.items() for x in xs],
            with_variant=True)
    if graded_fast:
        lines += ["", f"sdcrack on the graded meshes of `{graded_scene}` at equal error, by wall "
                  "time (the other curve's wall time interpolated log-log at the graded variant's "
                  "error, divided by its wall time; – outside that curve's range):", "",
                  "| level | variant | ‖u_h − u‖ | vs dolfinx, uniform | vs FreeFEM, uniform "
                  "| vs dolfinx, graded | vs FreeFEM, graded | vs itself, uniform |",
                  "|---|---|---|---|---|---|---|---|"]
        for key, entries in graded_fast.items():
            base = key.removesuffix(GRADED)
            lines += [f"| {a['level']} | {variant_name(base)} | {a['u_l2']:.3e} | "
                      + " | ".join(fmt_x(a[o]) for o in graded_against(base)) + " |"
                      for a in entries]
    if goals or goals32:
        lines += [""] + [goal_line(g) for g in goals] + [goal_line_issue32(g) for g in goals32]
    return "\n".join(lines) + "\n"


# colour per tool and p mass, marker per tool and p space (sdcrack's continuous p: round/diamond,
# broken-tangential p: filled plus/cross); uniform meshes: dashed, open markers; graded: solid,
# filled
PLOT_STYLE = {"sdcrack": ("o", "C0"), "sdcrack-lumped": ("D", "C1"),
              "sdcrack-ptangential": ("P", "C0"), "sdcrack-lumped-ptangential": ("X", "C1"),
              "dolfinx": ("s", "C2"), "freefem": ("^", "C3")}


def plot(rows, path, scene):
    """Error against wall time and solve time against unknowns, one line per tool, variant and
    mesh kind; one legend beside the panels, off the data."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    keys = [k + suffix for suffix in ("", GRADED) for k in PLOT_STYLE
            if any(k + suffix in r for r in rows)]
    # the broken-tangential p's labels are longer, and there are up to 12 of them
    wide = any("ptangential" in k for k in keys)
    fig, axes = plt.subplots(1, 2, figsize=(14.5 if wide else 12.5, 4.4 if len(keys) <= 8 else 5.0))
    for key in keys:
        pts = [(r[key]["wall_s"], r[key]["u_l2"], r[key].get("solver_s"), r[key]["unknowns"])
               for r in rows if key in r]
        marker, colour = PLOT_STYLE[key.removesuffix(GRADED)]
        kw = dict(marker=marker, color=colour, label=label(key))
        kw.update(linestyle="-") if key.endswith(GRADED) else kw.update(linestyle="--",
                                                                       markerfacecolor="none")
        axes[0].loglog([p[0] for p in pts], [p[1] for p in pts], **kw)
        axes[1].loglog([p[3] for p in pts], [p[2] for p in pts], **kw)
    axes[0].set_xlabel("wall time per process [s] (start-up included)")
    axes[0].set_ylabel("‖u_h − u‖_L²")
    axes[0].set_title(f"work–precision, {scene}")
    axes[1].set_xlabel("unknowns")
    axes[1].set_ylabel("solve time [s] (no start-up)")
    axes[1].set_title("solve time per level")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="center right", fontsize="small")
    fig.tight_layout(rect=(0, 0, 0.75 if wide else 0.8, 1))
    fig.savefig(path, dpi=110)
    return fig


def parse_levels(text):
    """'0-4' or '2,3,4' → a list of levels."""
    if "-" in text:
        lo, hi = map(int, text.split("-"))
        return list(range(lo, hi + 1))
    return [int(x) for x in text.split(",")]


def parse_names(text, allowed, what):
    """'a,b' → ['a', 'b'] (in the order given, repeats dropped), each among `allowed`; raises
    argparse.ArgumentTypeError naming the bad ones."""
    names = list(dict.fromkeys(x.strip() for x in text.split(",") if x.strip()))
    bad = [x for x in names if x not in allowed]
    if bad or not names:
        raise argparse.ArgumentTypeError(
            f"{what} must be among {', '.join(allowed)}: {text!r}"
            + (f" ({', '.join(map(repr, bad))} unknown)" if bad else " (none given)"))
    return names


def parse_p_masses(text):
    """'consistent,lumped' → a list of p masses (of P_MASSES)."""
    return parse_names(text, P_MASSES, "p masses")


def parse_p_spaces(text):
    """'continuous,broken-tangential' → a list of p spaces (of P_SPACES)."""
    return parse_names(text, P_SPACES, "p spaces")


def run_level(level, measured, log, **control):
    """One row: `measured` is a list of (row key, function running it), each measured under load
    control (`control`: measure()'s check, idle_timeout and max_tries)."""
    row = {"level": level}
    for key, fn in measured:
        row[key] = measure(f"{key} L{level}", fn, log, **control)
    msg = " ".join(f"{k} {row[k]['u_l2']:.3e}/{row[k]['wall_s']:.2f}s/{row[k]['solver_s']:.2f}s"
                   for k, _ in measured)
    print(f"level {level}: {msg}", file=sys.stderr, flush=True)
    log.write(f"level {level}: {msg}\n")
    return row


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", default=str(ROOT / "scenes" / "open-exact.toml"))
    ap.add_argument("--levels", default="0-4", help="sdcrack's levels, e.g. 0-4 or 2,3,4")
    ap.add_argument("--ref-levels", default=None,
                    help="the references' levels (default: sdcrack's and three more, so that their "
                         "errors reach sdcrack's)")
    ap.add_argument("--graded-scene", default=None,
                    help="a second scene, the first on graded meshes (e.g. "
                         "scenes/open-graded.toml): every tool on it as well, and graded sdcrack "
                         "against everything at equal error")
    ap.add_argument("--graded-levels", default=None,
                    help="sdcrack's levels on the graded scene (default: --levels)")
    ap.add_argument("--graded-ref-levels", default=None,
                    help="the references' levels on the graded scene (default: --graded-levels)")
    ap.add_argument("--tools", default="dolfinx,freefem",
                    help="references to time ('' for sdcrack alone)")
    ap.add_argument("--p-masses", default="consistent,lumped",
                    help="sdcrack's p masses to time, e.g. consistent,lumped or lumped")
    ap.add_argument("--p-spaces", default="continuous,broken-tangential",
                    help="sdcrack's p spaces to time, each with every p mass, e.g. "
                         "continuous,broken-tangential or broken-tangential")
    ap.add_argument("--idle-timeout", type=float, default=300.0,
                    help="seconds to wait for an idle machine before each measurement, then "
                         "measure anyway (marked IDLE-TIMEOUT)")
    ap.add_argument("--max-tries", type=int, default=3,
                    help="tries of a measurement rejected for other processes' load (the last "
                         "one is kept, marked REJECTED-KEPT)")
    ap.add_argument("--no-idle-wait", action="store_true",
                    help="neither wait for an idle machine nor reject loaded measurements")
    ap.add_argument("--out", required=True,
                    help="folder for work_precision.{json,md,png} and work_precision.load.txt")
    a = ap.parse_args(argv)
    try:
        a.p_masses = parse_p_masses(a.p_masses)
        a.p_spaces = parse_p_spaces(a.p_spaces)
    except argparse.ArgumentTypeError as e:  # one line, no usage
        print(f"bench-references: {e}", file=sys.stderr)
        sys.exit(2)
    variants = [(m, sp) for sp in a.p_spaces for m in a.p_masses]
    levels = parse_levels(a.levels)
    ref_levels = (parse_levels(a.ref_levels) if a.ref_levels
                  else list(range(min(levels), max(levels) + 4)))
    tools = [t for t in a.tools.split(",") if t]
    if not tools:
        ref_levels = []
    if not SDCRACK.exists():
        sys.exit(f"bench-references: {SDCRACK} not built (run `cargo build --release`)")
    scene_path = Path(a.scene)
    graded_path = Path(a.graded_scene) if a.graded_scene else None
    for path in (scene_path, graded_path):
        if path is not None and not path.is_file():
            sys.exit(f"bench-references: scene file {path} not found")
    g_levels = parse_levels(a.graded_levels) if a.graded_levels else levels
    g_ref_levels = (parse_levels(a.graded_ref_levels) if a.graded_ref_levels else g_levels)
    if graded_path is None:
        g_levels = g_ref_levels = []
    if not tools:
        g_ref_levels = []
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    text = scene_path.read_text()
    name = re.search(r'(?m)^name\s*=\s*"([^"]+)"', text).group(1)
    rows = []
    with tempfile.TemporaryDirectory(prefix="sdcrack-wp-") as tmp, \
            open(out / "work_precision.load.txt", "w") as log:
        log.write(LOAD_HEADER)
        work = Path(tmp)
        solo = work / "scene.toml"
        solo.write_text(sdcrack_only_scene(text))
        g_solo = work / "graded.toml"
        if graded_path is not None:
            g_solo.write_text(sdcrack_only_scene(graded_path.read_text()))
        for level in sorted(set(levels) | set(ref_levels) | set(g_levels) | set(g_ref_levels)):
            measured = [(VARIANTS[v], lambda v=v: run_sdcrack(solo, level, work, v[0],
                                                              p_space=v[1]))
                        for v in variants if level in levels]
            measured += [(t, lambda t=t: run_reference(t, scene_path, level, work))
                         for t in tools if level in ref_levels]
            measured += [(graded(VARIANTS[v]),
                          lambda v=v: run_sdcrack(g_solo, level, work, v[0], tag="graded",
                                                  p_space=v[1]))
                         for v in variants if level in g_levels]
            measured += [(graded(t),
                          lambda t=t: run_reference(t, graded_path, level, work, tag="graded"))
                         for t in tools if level in g_ref_levels]
            rows.append(run_level(level, measured, log, check=not a.no_idle_wait,
                                  idle_timeout=a.idle_timeout, max_tries=a.max_tries))
    keys = [VARIANTS[v] for v in variants]
    fast_internal = {k: speedups(rows, "solver_s", k) for k in keys}
    fast_wall = {k: speedups(rows, "wall_s", k) for k in keys}
    both_masses = len(a.p_masses) == 2
    lumped_fast = {sp: lumped_vs_consistent(rows, sp) if both_masses else [] for sp in P_SPACES}
    ptangential_fast = {}
    if len(a.p_spaces) == 2:
        for suffix in ("", GRADED) if g_levels else ("",):
            ptangential_fast.update({variant_key(m, "broken-tangential") + suffix:
                                     ptangential_vs_continuous(rows, m, suffix)
                                     for m in a.p_masses})
    graded_fast = {graded(k): speedups(rows, "wall_s", graded(k), graded_against(k))
                   for k in keys if g_levels}
    goals = graded_goal(rows, keys) if g_levels else []
    goals32 = graded_goal_issue32(rows, keys) if g_levels else []
    graded_name = (re.search(r'(?m)^name\s*=\s*"([^"]+)"', graded_path.read_text()).group(1)
                   if graded_path else None)
    md = markdown(name, rows, fast_internal, fast_wall, lumped_fast, graded_fast, goals,
                  graded_name, ptangential_fast, goals32)
    (out / "work_precision.md").write_text(md)
    (out / "work_precision.json").write_text(json.dumps(
        {"scene": name, "p_masses": a.p_masses, "p_spaces": a.p_spaces, "levels": rows,
         "speedup_solver_time": fast_internal, "speedup_wall_time": fast_wall,
         "lumped_vs_consistent": lumped_fast["continuous"],
         "lumped_vs_consistent_ptangential": lumped_fast["broken-tangential"],
         "ptangential_vs_continuous": ptangential_fast, "graded_scene": graded_name,
         "speedup_graded_wall_time": graded_fast, "graded_goal": goals,
         "graded_goal_issue32": goals32}, indent=2))
    plot(rows, out / "work_precision.png", name if not graded_name else f"{name} and {graded_name}")
    print(md)


if __name__ == "__main__":
    main()
