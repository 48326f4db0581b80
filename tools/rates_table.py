#!/usr/bin/python3
"""The docs' tables of observed rates from one results folder's summary.json (docs/design.md).

One Markdown row per variant (u space, multiplier, p mass, p space) at one δ: the observed rates
of e_u, e_p, e_p_x and e_λ between consecutive levels, per halving of h or (`--by unknowns`) of
N^{-1/2} with N the case's unknowns, and the errors at the finest level. Reads what sdcrack
reported; the compare tool recomputes the same errors independently in every campaign.

    tools/rates_table.py RESULTS/<scene> [--by h|unknowns] [--delta D] [--u-space broken]
"""

import argparse
import json
import math
import sys
from pathlib import Path

QUANTITIES = ("u_l2", "p_l2", "p_x", "lambda_l2")


def rates(sizes, errors):
    """log(e0/e1)/log(s0/s1) between consecutive entries (None where an error is not positive)."""
    out = []
    for (s0, e0), (s1, e1) in zip(zip(sizes, errors), zip(sizes[1:], errors[1:])):
        out.append(math.log(e0 / e1) / math.log(s0 / s1) if e0 > 0 and e1 > 0 else None)
    return out


def size(case, by):
    """h, or N^{-1/2} with N the case's unknowns."""
    return case["h"] if by == "h" else case["unknowns"] ** -0.5


def variant(case):
    """(u space, multiplier, p mass, p space), the last two defaulting as the compare tool does."""
    return (case["u_space"], case["multiplier"], case.get("p_mass", "consistent"),
            case.get("p_space", "continuous"))


def table(summary, by="h", delta=None, u_space=None):
    """The Markdown lines of the table."""
    cases = [c for c in summary["cases"] if c.get("errors")]
    if not cases:
        raise ValueError("no case has errors (a scene without [exact]: its distances to the "
                         "references are in the compare tool's report)")
    if delta is None:
        delta = min(c["delta"] for c in cases)
    cases = [c for c in cases if c["delta"] == delta and (u_space is None or c["u_space"] == u_space)]
    per = "h" if by == "h" else "N^{-1/2}"
    lines = [f"| variant | u rates | p rates | p_x rates | λ rates | e_u, e_p, e_λ at level "
             f"{max(c['level'] for c in cases)} |", "|---|---|---|---|---|---|"]
    for key in sorted({variant(c) for c in cases}):
        series = sorted((c for c in cases if variant(c) == key), key=lambda c: c["level"])
        sizes = [size(c, by) for c in series]
        cells = []
        for q in QUANTITIES:
            r = rates(sizes, [c["errors"][q] for c in series])
            cells.append(", ".join("–" if x is None else f"{x:.2f}" for x in r))
        last = series[-1]["errors"]
        lines.append(f"| {'/'.join(key)} | " + " | ".join(cells) +
                     f" | {last['u_l2']:.3g}, {last['p_l2']:.3g}, {last['lambda_l2']:.3g} |")
    lines.append(f"\n(rates per halving of {per}; δ = {delta:g})")
    return lines


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("results", type=Path, help="a results folder holding summary.json")
    ap.add_argument("--by", choices=("h", "unknowns"), default="h")
    ap.add_argument("--delta", type=float, default=None, help="default: the smallest δ")
    ap.add_argument("--u-space", default=None)
    args = ap.parse_args(argv)
    path = args.results / "summary.json"
    try:  # an unreadable or malformed summary.json, or one the table cannot be made of
        lines = table(json.loads(path.read_text(encoding="utf-8")), args.by, args.delta,
                      args.u_space)
    except (OSError, ValueError) as exc:
        print(f"rates_table: {path}: {exc}", file=sys.stderr)
        return 2
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
