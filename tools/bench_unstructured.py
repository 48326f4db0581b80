#!/usr/bin/python3
"""Structured vs unstructured levels: one case of the same problem on the structured
grid and on gmsh's mesh refined uniformly, at matched vertex counts.

The problem is scenes/closed-exact.toml (Ω = [−1, 1]², crack (−0.5, 0)–(0.5, 0)), solved as one
case (broken u, M1, consistent p mass, δ = 0, no fields, no norms' quadrature beyond the scene's
exact solution) by `sdcrack run --solver-only`:

* structured: `cells = [8, 8]` at level L (n = (8·2^L + 1)² vertices);
* unstructured: the same scene with `mesh_size = h0` at level L − 3, where h0 is searched so that
  the level's vertex count is within 2 % of n (gmsh's level 0 is made once per run; its seconds
  are reported separately, from the summary's `coarse_mesh.gmsh_seconds`).

Each case runs `--repeat` times in separate processes; the table reports the fastest run's
wall-clock seconds of the solve (`solve s` = the summary's `wall_s`: refinement to the level,
assembly, ordering + symbolic analysis, factorisation, crack reduction, LCP, recovery, norms; gmsh
runs once per process, when `sdcrack run` checks the scene before solving, and its seconds are
the summary's `coarse_mesh.gmsh_seconds`), its phases, gmsh's seconds, and the ratio of the
solve seconds unstructured / structured (the issue's bound: 1.5). Writes
OUT/unstructured.{json,md}.
"""

import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SDCRACK = ROOT / "target" / "release" / "sdcrack"
BASE = (ROOT / "scenes" / "closed-exact.toml").read_text()
PHASES = ["assembly", "symbolic", "factorization", "crack_reduction", "contact", "norms"]
# A level of an unstructured scene costs no more than this × a structured scene with the
# same number of vertices.
BOUND = 1.5


def within_bound(rows, bound=BOUND):
    """Whether every row's ratio unstructured / structured solve seconds is at most `bound`
    (False for a row without a finite ratio: nothing measured is not a pass)."""
    return bool(rows) and all(isinstance(r.get("ratio"), float) and r["ratio"] <= bound
                              for r in rows)


def scene_text(discretization, levels):
    """closed-exact with another mesh line and levels, one case's lists, no outputs."""
    text = re.sub(r"(?m)^cells = .*$", discretization, BASE)
    text = re.sub(r"(?m)^levels = .*$", f"levels = [{levels}]", text)
    text = re.sub(r"(?m)^p_mass = .*$", 'p_mass = ["consistent"]', text)
    text = re.sub(r"(?m)^fields = .*$", "fields = []", text)
    text = re.sub(r"(?m)^references = .*$", "references = []", text)
    return text


def vertices_at(tmp, mesh_size, level):
    """Uncut vertices of level `level` of gmsh's mesh with `mesh_size` (from `sdcrack mesh`)."""
    scene = tmp / "probe.toml"
    scene.write_text(scene_text(f"mesh_size = {mesh_size!r}", level))
    out = tmp / f"probe-{mesh_size}-{level}"
    subprocess.run([str(SDCRACK), "mesh", str(scene), "--out", str(out), "--level", str(level)],
                   check=True, capture_output=True)
    meta = json.loads((out / f"level{level}" / "mesh.json").read_text())
    return meta["n_uncut_vertices"]


def match_mesh_size(tmp, target, level):
    """h0 whose level `level` has within 2 % of `target` vertices (bisection on log h0)."""
    lo, hi = 0.02, 1.0  # vertex count decreases with h0
    for _ in range(30):
        mid = (lo * hi) ** 0.5
        n = vertices_at(tmp, mid, level)
        if abs(n - target) <= 0.02 * target:
            return mid, n
        lo, hi = (mid, hi) if n > target else (lo, mid)
    raise SystemExit(f"no mesh_size gives {target} vertices at level {level}")


def run_case(tmp, text, level, repeat):
    """The fastest of `repeat` runs: (wall_s, phases, unknowns, gmsh seconds)."""
    scene = tmp / "case.toml"
    scene.write_text(text)
    best = None
    for k in range(repeat):
        out = tmp / f"run-{k}-{abs(hash(text))}"
        subprocess.run([str(SDCRACK), "run", str(scene), "--out", str(out), "--quiet", "--solver-only",
                        "--level", str(level), "--u-space", "broken", "--multiplier", "M1",
                        "--delta", "0"], check=True, capture_output=True)
        summary = json.loads((out / "closed-exact" / "summary.json").read_text())
        case = summary["cases"][0]
        gmsh = (summary.get("coarse_mesh") or {}).get("gmsh_seconds")
        row = (summary["wall_s"], case["timings_s"], case["unknowns"], gmsh)
        if best is None or row[0] < best[0]:
            best = row
    return best


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", default="5,6", help="structured levels (8x8 cells), comma-separated")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--out", default="bench/unstructured")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    with tempfile.TemporaryDirectory() as t:
        tmp = Path(t)
        for level in map(int, args.levels.split(",")):
            n = (8 * 2 ** level + 1) ** 2
            s = run_case(tmp, scene_text("cells = [8, 8]", level), level, args.repeat)
            ul = level - 3
            h0, nu = match_mesh_size(tmp, n, ul)
            u = run_case(tmp, scene_text(f"mesh_size = {h0!r}", ul), ul, args.repeat)
            rows.append({"structured": {"level": level, "vertices": n, "unknowns": s[2],
                                        "solve_s": s[0], "timings_s": s[1]},
                         "unstructured": {"level": ul, "mesh_size": h0, "vertices": nu,
                                          "unknowns": u[2], "solve_s": u[0], "timings_s": u[1],
                                          "gmsh_s": u[3]},
                         "ratio": u[0] / s[0]})
            print(f"n ≈ {n}: structured {s[0]:.3f} s, unstructured {u[0]:.3f} s "
                  f"(ratio {u[0] / s[0]:.2f}), gmsh {u[3]:.3f} s", file=sys.stderr)
    (out / "unstructured.json").write_text(json.dumps(rows, indent=2) + "\n")
    lines = ["| mesh | level | vertices | unknowns | solve s | " + " | ".join(PHASES) + " | gmsh s |",
             "|---|---|---|---|---|" + "---|" * len(PHASES) + "---|"]
    for r in rows:
        for kind in ("structured", "unstructured"):
            c = r[kind]
            gmsh = f"{c['gmsh_s']:.3f}" if c.get("gmsh_s") is not None else "–"
            lines.append(f"| {kind} | {c['level']} | {c['vertices']} | {c['unknowns']} | "
                         f"{c['solve_s']:.3f} | "
                         + " | ".join(f"{c['timings_s'][p]:.3f}" for p in PHASES) + f" | {gmsh} |")
        lines.append(f"| ratio | | | | **{r['ratio']:.2f}** |" + " |" * len(PHASES) + " |")
    table = "\n".join(lines) + "\n"
    (out / "unstructured.md").write_text(table)
    print(table)
    if not within_bound(rows):
        print(f"bench-unstructured: an unstructured level costs more than {BOUND} × the "
              "structured one", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
