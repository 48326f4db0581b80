#!/usr/bin/python3
"""Work-precision benchmark: sdcrack against the dolfinx and FreeFEM references.

For one scene with an `[exact]` solution and each level, runs (one process per tool and level,
timed from outside with a wall clock):

* sdcrack: `sdcrack run` of one case (broken u, M1, δ = 0; no fields, no reference run), once per
  p mass of `--p-masses`: row key `sdcrack` (`--p-mass consistent`, the paper's) and row key
  `sdcrack-lumped` (`--p-mass lumped`);
* dolfinx / FreeFEM: `sdcrack mesh` (not timed: it is shared input), then the reference script.

Each tool reports its own ‖u_h − u‖_{L²} against the exact solution, each with a tip-graded
quadrature (sdcrack: collapsed Gauss rules graded toward the tips; dolfinx: UFL forms with rules
collapsed at the tips; FreeFEM's script: numpy rules graded toward the tips on the cracked mesh). Two times are tabulated: the process wall time (start-up, imports, assembly, solve and
error evaluation), and the solve time by each tool's own timer without start-up and without the
error evaluation (sdcrack: its phases but `norms`; dolfinx: assembly + solve; FreeFEM: the
FreeFem++ run). The speed-up at equal error interpolates each reference's (error, time) curve
log-log at each sdcrack variant's errors and divides by that variant's time of the same kind; the
lumped variant is also compared with the consistent one the same way (consistent's time at
lumped's error / lumped's time).

Load control: before each measurement (one tool at one level) the script waits until the machine
is idle (1-min load average < 1.0 and other processes < 0.1 core over 2 s; it gives up after
`--idle-timeout` s, measures anyway and marks it IDLE-TIMEOUT). During the measurement it takes
foreign cores = (busy time of /proc/stat's `cpu` line − CPU time of this process and its children,
from os.times()) / wall; at ≥ 0.2 core the measurement is rejected and repeated, at most
`--max-tries` times (the last try is kept, marked REJECTED-KEPT). `--no-idle-wait` disables both.
One line per try goes to OUT/work_precision.load.txt.

Writes OUT/work_precision.{json,md,png} and prints the Markdown table. The JSON has
`scene`, `p_masses`, `levels` (one object per level: `level` and, per tool present at that level,
an object with wall_s, solver_s, u_l2, unknowns, kkt, the load check `load` {status, tries,
foreign_cores} and, for sdcrack, norms_s; tool keys `sdcrack`, `sdcrack-lumped`, `dolfinx`,
`freefem`), `speedup_solver_time` and `speedup_wall_time` (dicts keyed by sdcrack variant,
`sdcrack` / `sdcrack-lumped`, each a list of {level, u_l2, dolfinx, freefem}, the ratios or null
outside the reference's range) and `lumped_vs_consistent` (a list of {level, u_l2, solve, wall}:
consistent's time at lumped's error / lumped's time, null outside consistent's range).

With `--graded-scene` (the same problem on meshes graded towards the crack tips, e.g.
scenes/open-graded.toml) every tool also runs on that scene's levels, under row keys with the
suffix `@graded` (`sdcrack@graded`, `dolfinx@graded`, …). Each graded sdcrack variant is then
compared by wall time, at its own errors, with both references on the uniform meshes, both on the
graded meshes and itself on the uniform meshes (JSON `speedup_graded_wall_time`, keyed by the
graded row key, entries {level, u_l2, dolfinx, freefem, dolfinx@graded, freefem@graded, sdcrack
or sdcrack-lumped}), and held to issue 24's goal: ≥ 100× faster than the faster uniform
reference at the finest error that reference reaches (JSON `graded_goal`, one line per variant
printed with MET or MISSED). The plot draws uniform meshes dashed with open markers and graded
meshes solid with filled ones, one colour per tool and p mass.
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
# sdcrack's p masses → row key and label
VARIANTS = {"consistent": "sdcrack", "lumped": "sdcrack-lumped"}
LABELS = {"sdcrack": "sdcrack", "sdcrack-lumped": "sdcrack (lumped p)"}
# a row key on the graded scene's meshes: the tool's key with this suffix
GRADED = "@graded"
# the goal of issue 24: graded sdcrack this many times faster by wall time than the faster
# uniform reference at the finest error that reference reaches
GRADED_GOAL = 100.0
IDLE_LOAD = 1.0  # 1-min load average below which the machine counts as idle
IDLE_FOREIGN = 0.1  # cores used by other processes below which the machine counts as idle
REJECT_FOREIGN = 0.2  # cores used by other processes during a measurement that reject it
LOAD_HEADER = """\
# Load during each measurement (ci/bench_references.py). One line per try:
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


def label(key):
    """'sdcrack (lumped p), graded' for 'sdcrack-lumped@graded'."""
    base = key.removesuffix(GRADED)
    return LABELS.get(base, base) + (", graded" if key.endswith(GRADED) else "")


def run_sdcrack(scene_file, level, work, p_mass="consistent", tag=""):
    """One sdcrack case; `tag` keeps the graded scene's folders apart from the uniform one's."""
    out = work / f"sd{tag}{level}-{p_mass}"
    shutil.rmtree(out, ignore_errors=True)  # a repeated try writes afresh
    wall = run_timed([SDCRACK, "run", scene_file, "--level", str(level), "--u-space", "broken",
                      "--multiplier", "M1", "--p-mass", p_mass, "--delta", "0", "--out", out,
                      "--quiet"])
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


def lumped_vs_consistent(rows):
    """For each lumped row: consistent's time at lumped's error / lumped's time (both timers)."""
    lumped = VARIANTS["lumped"]
    return [{"level": r["level"], "u_l2": r[lumped]["u_l2"],
             **{name: ratio_at_error(rows, "sdcrack", key, r[lumped]["u_l2"], r[lumped][key])
                for name, key in (("solve", "solver_s"), ("wall", "wall_s"))}}
            for r in rows if lumped in r]


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


def markdown(scene, rows, fast_internal, fast_wall, lumped_fast=(), graded_fast=None, goals=(),
             graded_scene=None):
    """The report; `fast_internal` / `fast_wall`: speedups() per sdcrack variant (row key);
    `graded_fast`: wall-time speedups() of each graded variant (row key) against
    graded_against(); `goals`: graded_goal()."""
    lines = [f"# Work-precision: scene `{scene}` (broken u, M1, δ = 0 for sdcrack)", "",
             "Times in seconds, one process per tool and level on this machine. `wall`: the whole "
             "process (start-up, imports, solve and error evaluation); `solve`: the tool's own "
             "timer without start-up and without error evaluation (sdcrack: its phases but the "
             "error norms; dolfinx: assembly + solve; FreeFEM: the FreeFem++ run); `norms`: "
             "sdcrack's error-norm evaluation. `sdcrack`: consistent p mass (the paper's); "
             "`sdcrack (lumped p)`: lumped p mass.", "",
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
    entries = sorted(((a["level"], mass, a, b) for mass, key in VARIANTS.items()
                      for a, b in zip(fast_internal.get(key, []), fast_wall.get(key, []))),
                     key=lambda x: (x[0], list(VARIANTS).index(x[1])))
    for level, mass, a, b in entries:
        lines.append(f"| {level} | {mass} | {a['u_l2']:.3e} | {fmt_x(a['dolfinx'])} | "
                     f"{fmt_x(a['freefem'])} | {fmt_x(b['dolfinx'])} | {fmt_x(b['freefem'])} |")
    if lumped_fast:
        lines += ["", "Lumped against consistent p mass at equal error (consistent's time "
                  "interpolated log-log at lumped's error, divided by lumped's time; – outside "
                  "consistent's range):", "",
                  "| level | lumped ‖u_h − u‖ | solve | wall |", "|---|---|---|---|"]
        lines += [f"| {x['level']} | {x['u_l2']:.3e} | {fmt_x(x['solve'])} | {fmt_x(x['wall'])} |"
                  for x in lumped_fast]
    if graded_fast:
        lines += ["", f"sdcrack on the graded meshes of `{graded_scene}` at equal error, by wall "
                  "time (the other curve's wall time interpolated log-log at the graded variant's "
                  "error, divided by its wall time; – outside that curve's range):", "",
                  "| level | variant | ‖u_h − u‖ | vs dolfinx, uniform | vs FreeFEM, uniform "
                  "| vs dolfinx, graded | vs FreeFEM, graded | vs itself, uniform |",
                  "|---|---|---|---|---|---|---|---|"]
        for key, entries in graded_fast.items():
            base = key.removesuffix(GRADED)
            mass = next(m for m, k in VARIANTS.items() if k == base)
            lines += [f"| {a['level']} | {mass} | {a['u_l2']:.3e} | "
                      + " | ".join(fmt_x(a[o]) for o in graded_against(base)) + " |"
                      for a in entries]
    if goals:
        lines += [""] + [goal_line(g) for g in goals]
    return "\n".join(lines) + "\n"


# marker and colour per tool and p mass; uniform meshes: dashed, open markers; graded: solid, filled
PLOT_STYLE = {"sdcrack": ("o", "C0"), "sdcrack-lumped": ("D", "C1"), "dolfinx": ("s", "C2"),
              "freefem": ("^", "C3")}


def plot(rows, path, scene):
    """Error against wall time and solve time against unknowns, one line per tool, variant and
    mesh kind; one legend beside the panels, off the data."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(12.5, 4.4))
    for key in (k + suffix for suffix in ("", GRADED) for k in PLOT_STYLE):
        pts = [(r[key]["wall_s"], r[key]["u_l2"], r[key].get("solver_s"), r[key]["unknowns"])
               for r in rows if key in r]
        if not pts:
            continue
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
    fig.tight_layout(rect=(0, 0, 0.8, 1))
    fig.savefig(path, dpi=110)
    return fig


def parse_levels(text):
    """'0-4' or '2,3,4' → a list of levels."""
    if "-" in text:
        lo, hi = map(int, text.split("-"))
        return list(range(lo, hi + 1))
    return [int(x) for x in text.split(",")]


def parse_p_masses(text):
    """'consistent,lumped' → a list of p masses (keys of VARIANTS)."""
    masses = [m for m in text.split(",") if m]
    bad = [m for m in masses if m not in VARIANTS]
    if bad or not masses:
        raise argparse.ArgumentTypeError(f"p masses must be among {', '.join(VARIANTS)}: {text!r}")
    return masses


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
    ap.add_argument("--p-masses", type=parse_p_masses, default="consistent,lumped",
                    help="sdcrack's p masses to time, e.g. consistent,lumped or lumped")
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
            measured = [(VARIANTS[m], lambda m=m: run_sdcrack(solo, level, work, m))
                        for m in a.p_masses if level in levels]
            measured += [(t, lambda t=t: run_reference(t, scene_path, level, work))
                         for t in tools if level in ref_levels]
            measured += [(graded(VARIANTS[m]),
                          lambda m=m: run_sdcrack(g_solo, level, work, m, tag="graded"))
                         for m in a.p_masses if level in g_levels]
            measured += [(graded(t),
                          lambda t=t: run_reference(t, graded_path, level, work, tag="graded"))
                         for t in tools if level in g_ref_levels]
            rows.append(run_level(level, measured, log, check=not a.no_idle_wait,
                                  idle_timeout=a.idle_timeout, max_tries=a.max_tries))
    keys = [VARIANTS[m] for m in a.p_masses]
    fast_internal = {k: speedups(rows, "solver_s", k) for k in keys}
    fast_wall = {k: speedups(rows, "wall_s", k) for k in keys}
    lumped_fast = lumped_vs_consistent(rows) if len(keys) == 2 else []
    graded_fast = {graded(k): speedups(rows, "wall_s", graded(k), graded_against(k))
                   for k in keys if g_levels}
    goals = graded_goal(rows, keys) if g_levels else []
    graded_name = (re.search(r'(?m)^name\s*=\s*"([^"]+)"', graded_path.read_text()).group(1)
                   if graded_path else None)
    md = markdown(name, rows, fast_internal, fast_wall, lumped_fast, graded_fast, goals,
                  graded_name)
    (out / "work_precision.md").write_text(md)
    (out / "work_precision.json").write_text(json.dumps(
        {"scene": name, "p_masses": a.p_masses, "levels": rows,
         "speedup_solver_time": fast_internal, "speedup_wall_time": fast_wall,
         "lumped_vs_consistent": lumped_fast, "graded_scene": graded_name,
         "speedup_graded_wall_time": graded_fast, "graded_goal": goals}, indent=2))
    plot(rows, out / "work_precision.png", name if not graded_name else f"{name} and {graded_name}")
    print(md)


if __name__ == "__main__":
    main()
