#!/usr/bin/python3
"""Scaling benchmark: `sdcrack bench --json` at several mesh sizes, one after the other.

Fits time ≈ C · n^α (least squares in log-log) for the yardstick (faer's sparse Cholesky of the P1
Laplacian), one sdcrack case, its numeric factorisation and the 18-case sweep, against the number
of mesh vertices n, and writes OUT/scaling.{json,md,png}. A size whose `bench-<n>.json` already
exists in OUT is not rerun (delete it to measure again); each run is a separate process, so the
peak memory of one size does not leak into the next.
"""

import argparse
import json
import math
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SDCRACK = ROOT / "target" / "release" / "sdcrack"

SERIES = [  # (key in the report, label)
    ("bare_cholesky_s", "yardstick: Cholesky of the P1 Laplacian"),
    ("case_s", "one sdcrack case (broken, M1, δ = 0)"),
    ("numeric_factor_s", "its numeric LDLᵀ"),
    ("sweep_s", "sweep: 6 δ × 3 multipliers"),
]


def fit(ns, ts):
    """Least-squares slope and constant of log t = log C + α log n."""
    xs, ys = [math.log(n) for n in ns], [math.log(t) for t in ts]
    mx, my = sum(xs) / len(xs), sum(ys) / len(ys)
    sxx = sum((x - mx) ** 2 for x in xs)
    alpha = sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sxx if sxx > 0 else float("nan")
    return alpha, math.exp(my - alpha * mx)


def run_size(n, out):
    path = out / f"bench-{n}.json"
    if not path.exists():
        print(f"bench-scaling: {n} vertices …", file=sys.stderr, flush=True)
        p = subprocess.run([SDCRACK, "bench", "--vertices", str(n), "--json"],
                           capture_output=True, text=True)
        if p.returncode != 0:
            raise SystemExit(f"bench-scaling: sdcrack bench --vertices {n} failed: {p.stderr.strip()}")
        path.write_text(p.stdout)
    return json.loads(path.read_text())


def markdown(reports, fits):
    lines = ["| vertices | yardstick s | case s | case / yardstick | numeric LDLᵀ s | sweep s "
             "| sweep / 6 LDLᵀ of the sweep | sweep / (6 × case LDLᵀ) | peak MB yardstick | peak MB case "
             "| memory ratio | worst KKT |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in reports:
        lines.append(
            f"| {r['vertices']} | {r['bare_cholesky_s']:.2f} | {r['case_s']:.2f} | "
            f"{r['case_s'] / r['bare_cholesky_s']:.1f} | {r['numeric_factor_s']:.2f} | "
            f"{r['sweep_s']:.1f} | {r['sweep_s'] / r['sweep_factorization_s']:.2f} | "
            f"{r['sweep_s'] / (6 * r['numeric_factor_s']):.2f} | {r['yardstick_peak_rss_mb']:.0f} | "
            f"{r['case_peak_rss_mb']:.0f} | {r['case_peak_rss_mb'] / r['yardstick_peak_rss_mb']:.1f} | "
            f"{r['worst_kkt']:.1e} |")
    lines += ["", "Fitted exponents, time ≈ C · n^α over these sizes (n = vertices):", "",
              "| series | α | C |", "|---|---|---|"]
    for (key, label), (alpha, c) in zip(SERIES, fits):
        lines.append(f"| {label} | {alpha:.2f} | {c:.2e} |")
    return "\n".join(lines) + "\n"


def plot(reports, fits, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    ns = [r["vertices"] for r in reports]
    fig, ax = plt.subplots(figsize=(7, 4.8))
    for (key, label), (alpha, c), style in zip(SERIES, fits, ("k^-", "o-", "s--", "d:")):
        ts = [r[key] for r in reports]
        ax.loglog(ns, ts, style, label=f"{label}: α = {alpha:.2f}")
    ax.set_xlabel("mesh vertices n")
    ax.set_ylabel("seconds")
    ax.set_title("sdcrack bench (2 cores): time vs mesh size")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--vertices", default="25000,50000,100000,250000,500000,1000000")
    ap.add_argument("--out", required=True)
    a = ap.parse_args(argv)
    if not SDCRACK.exists():
        sys.exit(f"bench-scaling: {SDCRACK} not built (run `cargo build --release`)")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    sizes = [int(float(v)) for v in a.vertices.split(",") if v]
    reports = sorted((run_size(n, out) for n in sizes), key=lambda r: r["vertices"])
    ns = [r["vertices"] for r in reports]
    fits = [fit(ns, [r[key] for r in reports]) for key, _ in SERIES]
    md = markdown(reports, fits)
    (out / "scaling.md").write_text(md)
    (out / "scaling.json").write_text(json.dumps(
        {"reports": reports, "fits": {k: {"alpha": a_, "C": c} for (k, _), (a_, c) in
                                      zip(SERIES, fits)}}, indent=2))
    if len(reports) >= 2:
        plot(reports, fits, out / "scaling.png")
    print(md)


if __name__ == "__main__":
    main()
