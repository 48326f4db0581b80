#!/usr/bin/python3
"""The cost of the error norms against the case they measure.

One case per level (broken u, M1, consistent p mass, δ = 0, no fields) of each scene with an
exact solution, by `sdcrack run --solver-only`, `--repeat` times in separate processes. From the
summary's `timings_s`: `norms` (the quadrature against the exact solution) and the case's solve
phases (every other timer: assembly, symbolic, factorization, crack reduction, condition,
contact), each the fastest of the repeats. The goal: norms ≤ 0.25 × the solve phases at every
level. Prints a table and one goal line (MET/MISSED), writes OUT/norms.{json,md}; exit 1 when the
goal is missed. `--sdcrack BIN` measures another build (an older rule, for instance).
"""

import argparse
import json
import math
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
# The norms cost at most this × the case they measure, at every level.
BOUND = 0.25


def ratio_goal(rows, bound=BOUND):
    """(met, worst ratio): met when every row's norms / solve ratio is a finite number ≤ bound
    (no rows, or a row without a finite ratio, is not met)."""
    ratios = [r.get("ratio") for r in rows]
    finite = [x for x in ratios if isinstance(x, float) and math.isfinite(x)]
    worst = max(finite) if finite else float("nan")
    return bool(rows) and len(finite) == len(ratios) and worst <= bound, worst


def one_case(text, level):
    """`text` restricted to one level, the consistent p mass, δ = 0 and no fields or references."""
    for key, value in [("levels", f"[{level}]"), ("p_mass", '["consistent"]'),
                       ("fields", "[]"), ("references", "[]")]:
        text = re.sub(rf"(?m)^{key} = .*$", f"{key} = {value}", text)
    return text


def measure(sdcrack, scene_path, level, repeat, tmp):
    """Fastest norms and fastest solve phases of `repeat` runs, with the case's unknowns."""
    text = one_case(Path(scene_path).read_text(), level)
    scene = tmp / f"{Path(scene_path).stem}-{level}.toml"
    scene.write_text(text)
    norms, solve, unknowns, name = [], [], None, None
    for k in range(repeat):
        out = tmp / f"run-{scene.stem}-{k}"
        subprocess.run([str(sdcrack), "run", str(scene), "--out", str(out), "--quiet",
                        "--solver-only", "--level", str(level), "--u-space", "broken",
                        "--multiplier", "M1", "--delta", "0"], check=True, capture_output=True)
        summary_path = next(out.glob("*/summary.json"))
        summary = json.loads(summary_path.read_text())
        case = summary["cases"][0]
        t = case["timings_s"]
        norms.append(t["norms"])
        solve.append(sum(v for k, v in t.items() if k not in ("norms", "fields")))
        unknowns, name = case["unknowns"], summary_path.parent.name
    return {"scene": name, "level": level, "unknowns": unknowns, "norms_s": min(norms),
            "solve_s": min(solve), "ratio": min(norms) / min(solve)}


def table(rows):
    lines = ["| scene | level | unknowns | norms s | solve phases s | norms / solve |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['level']} | {r['unknowns']} | {r['norms_s']:.4f} | "
                     f"{r['solve_s']:.4f} | {r['ratio']:.3f} |")
    return "\n".join(lines)


def goal_line(rows):
    met, worst = ratio_goal(rows)
    return (f"goal: norms ≤ {BOUND} × the solve phases at every level: "
            f"{'MET' if met else 'MISSED'} (worst {worst:.3f})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="*",
                    default=[str(ROOT / "scenes" / "open-exact.toml"),
                             str(ROOT / "scenes" / "open-graded.toml")])
    ap.add_argument("--levels", default="0-5", help="A-B or a comma-separated list")
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--sdcrack", default=str(ROOT / "target" / "release" / "sdcrack"))
    ap.add_argument("--out", default="bench/norms")
    args = ap.parse_args()
    if "-" in args.levels:
        a, b = map(int, args.levels.split("-"))
        levels = list(range(a, b + 1))
    else:
        levels = [int(x) for x in args.levels.split(",")]
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as t:
        for scene in args.scenes:
            for level in levels:
                rows.append(measure(args.sdcrack, scene, level, args.repeat, Path(t)))
                print(f"  {rows[-1]['scene']} level {level}: norms {rows[-1]['norms_s']:.4f} s, "
                      f"solve {rows[-1]['solve_s']:.4f} s", file=sys.stderr)
    text = table(rows) + "\n\n" + goal_line(rows)
    print(text)
    (out / "norms.md").write_text(text + "\n")
    (out / "norms.json").write_text(json.dumps({"bound": BOUND, "sdcrack": args.sdcrack,
                                                "repeat": args.repeat, "rows": rows}, indent=1))
    return 0 if ratio_goal(rows)[0] else 1


if __name__ == "__main__":
    sys.exit(main())
