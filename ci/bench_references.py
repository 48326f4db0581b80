#!/usr/bin/python3
"""Work-precision benchmark: sdcrack against the dolfinx and FreeFEM references.

For one scene with an `[exact]` solution and each level, runs (one process per tool and level,
timed from outside with a wall clock):

* sdcrack: `sdcrack run` of one case (broken u, M1, δ = 0; no fields, no reference run);
* dolfinx / FreeFEM: `sdcrack mesh` (not timed: it is shared input), then the reference script.

Each tool reports its own ‖u_h − u‖_{L²} against the exact solution, each with a tip-graded
quadrature (sdcrack: collapsed Gauss rules graded toward the tips; dolfinx: UFL forms with rules
collapsed at the tips; FreeFEM's script: numpy rules graded toward the tips on the cracked mesh). Two times are tabulated: the process wall time (start-up, imports, assembly, solve and
error evaluation), and the solve time by each tool's own timer without start-up and without the
error evaluation (sdcrack: its phases but `norms`; dolfinx: assembly + solve; FreeFEM: the
FreeFem++ run). The speed-up at equal error interpolates each reference's (error, time) curve
log-log at sdcrack's errors and divides by sdcrack's time of the same kind.

Writes OUT/work_precision.{json,md,png} and prints the Markdown table.
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SDCRACK = ROOT / "target" / "release" / "sdcrack"
TOOLS = ("dolfinx", "freefem")


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


def run_sdcrack(scene_file, level, work):
    out = work / f"sd{level}"
    wall = run_timed([SDCRACK, "run", scene_file, "--level", str(level), "--u-space", "broken",
                      "--multiplier", "M1", "--delta", "0", "--out", out, "--quiet"])
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


def run_reference(tool, scene_file, level, work):
    mesh = work / f"mesh{level}"
    if not mesh.exists():
        run_timed([SDCRACK, "mesh", scene_file, "--level", str(level), "--out", mesh])
    out = work / f"{tool}{level}"
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


def speedups(rows, key):
    """For each sdcrack row: time of each reference at sdcrack's error / sdcrack's time."""
    out = []
    for r in (r for r in rows if "sdcrack" in r):
        e, t = r["sdcrack"]["u_l2"], r["sdcrack"][key]
        entry = {"level": r["level"], "u_l2": e}
        for tool in TOOLS:
            curve = [(x[tool]["u_l2"], x[tool][key]) for x in rows if tool in x]
            tr = time_at_error(curve, e)
            entry[tool] = None if tr is None else tr / t
        out.append(entry)
    return out


def markdown(scene, rows, fast_internal, fast_wall):
    lines = [f"# Work-precision: scene `{scene}` (broken u, M1, δ = 0 for sdcrack)", "",
             "Times in seconds, one process per tool and level on this machine. `wall`: the whole "
             "process (start-up, imports, solve and error evaluation); `solve`: the tool's own "
             "timer without start-up and without error evaluation (sdcrack: its phases but the "
             "error norms; dolfinx: assembly + solve; FreeFEM: the FreeFem++ run).", "",
             "| level | tool | unknowns | ‖u_h − u‖_L² | wall s | solve s |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        for tool in ("sdcrack",) + TOOLS:
            if tool in r:
                x = r[tool]
                lines.append(f"| {r['level']} | {tool} | {x['unknowns']} | {x['u_l2']:.3e} | "
                             f"{x['wall_s']:.2f} | {x['solver_s']:.2f} |")
    lines += ["", "Speed-up of sdcrack at equal error (reference time interpolated log-log at "
              "sdcrack's error, divided by sdcrack's time of the same kind; – where sdcrack's error is "
              "outside the reference's range):", "",
              "| level | sdcrack ‖u_h − u‖ | vs dolfinx (solve) | vs FreeFEM (solve) "
              "| vs dolfinx (wall) | vs FreeFEM (wall) |", "|---|---|---|---|---|---|"]
    fmt = lambda v: "–" if v is None else f"{v:.1f}×"  # noqa: E731
    for a, b in zip(fast_internal, fast_wall):
        lines.append(f"| {a['level']} | {a['u_l2']:.3e} | {fmt(a['dolfinx'])} | "
                     f"{fmt(a['freefem'])} | {fmt(b['dolfinx'])} | {fmt(b['freefem'])} |")
    return "\n".join(lines) + "\n"


def plot(rows, path, scene):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    for tool, style in (("sdcrack", "o-"), ("dolfinx", "s--"), ("freefem", "^-.")):
        pts = [(r[tool]["wall_s"], r[tool]["u_l2"], r[tool].get("solver_s"), r[tool]["unknowns"])
               for r in rows if tool in r]
        if not pts:
            continue
        axes[0].loglog([p[0] for p in pts], [p[1] for p in pts], style, label=f"{tool} (wall)")
        axes[1].loglog([p[3] for p in pts], [p[2] for p in pts], style, label=tool)
    axes[0].set_xlabel("wall time [s]")
    axes[0].set_ylabel("‖u_h − u‖_L²")
    axes[0].set_title(f"work-precision, {scene}")
    axes[1].set_xlabel("unknowns")
    axes[1].set_ylabel("solve time [s]")
    axes[1].set_title("time per level")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def parse_levels(text):
    """'0-4' or '2,3,4' → a list of levels."""
    if "-" in text:
        lo, hi = map(int, text.split("-"))
        return list(range(lo, hi + 1))
    return [int(x) for x in text.split(",")]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scene", default=str(ROOT / "scenes" / "open-exact.toml"))
    ap.add_argument("--levels", default="0-4", help="sdcrack's levels, e.g. 0-4 or 2,3,4")
    ap.add_argument("--ref-levels", default=None,
                    help="the references' levels (default: sdcrack's and three more, so that their "
                         "errors reach sdcrack's)")
    ap.add_argument("--tools", default="dolfinx,freefem", help="references to time")
    ap.add_argument("--out", required=True, help="folder for work_precision.{json,md,png}")
    a = ap.parse_args(argv)
    levels = parse_levels(a.levels)
    ref_levels = (parse_levels(a.ref_levels) if a.ref_levels
                  else list(range(min(levels), max(levels) + 4)))
    tools = [t for t in a.tools.split(",") if t]
    if not SDCRACK.exists():
        sys.exit(f"bench-references: {SDCRACK} not built (run `cargo build --release`)")
    scene_path = Path(a.scene)
    if not scene_path.is_file():
        sys.exit(f"bench-references: scene file {scene_path} not found")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    text = scene_path.read_text()
    name = re.search(r'(?m)^name\s*=\s*"([^"]+)"', text).group(1)
    rows = []
    with tempfile.TemporaryDirectory(prefix="sdcrack-wp-") as tmp:
        work = Path(tmp)
        solo = work / "scene.toml"
        solo.write_text(sdcrack_only_scene(text))
        for level in sorted(set(levels) | set(ref_levels)):
            row = {"level": level}
            if level in levels:
                row["sdcrack"] = run_sdcrack(solo, level, work)
            for tool in tools if level in ref_levels else []:
                row[tool] = run_reference(tool, scene_path, level, work)
            rows.append(row)
            msg = " ".join(f"{t} {row[t]['u_l2']:.2e}/{row[t]['wall_s']:.2f}s"
                           for t in ("sdcrack", *tools) if t in row)
            print(f"level {level}: {msg}", file=sys.stderr, flush=True)
    fast_internal = speedups(rows, "solver_s")
    fast_wall = speedups(rows, "wall_s")
    md = markdown(name, rows, fast_internal, fast_wall)
    (out / "work_precision.md").write_text(md)
    (out / "work_precision.json").write_text(json.dumps(
        {"scene": name, "levels": rows, "speedup_solver_time": fast_internal,
         "speedup_wall_time": fast_wall}, indent=2))
    plot(rows, out / "work_precision.png", name)
    print(md)


if __name__ == "__main__":
    main()
