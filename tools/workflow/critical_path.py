#!/usr/bin/python3
"""The campaign's wall time on a cluster with one node per job, from measured job durations.

    tools/workflow/critical_path.py OUT [--json]

Reads Snakemake's measurement of every job of the campaign folder OUT (the `benchmark:` files
OUT/benchmarks/<scene>/<job>.tsv of tools/workflow/Snakefile: column `s`, wall seconds). In the
workflow a `check` job waits for its shards (one level's solver shards of one u space, or its
reference shards), a scene's `report` job for all its shards and checks and nothing else, and
scenes are independent, so with one node per job (and no queueing) the campaign takes

    critical path = max over scenes (max over the scene's shard and check jobs of the chain
                                     ending in it + the scene's report job),

a check job's chain being its longest shard plus itself,

and the scene and jobs on that path are printed. Also printed: the sum of all job durations (the
campaign's wall time on one core, without the engine's overhead), the totals per rule, and the two
goals with MET or MISSED: the compare tool's jobs (report and check) take at most
15 % of the job-seconds, and the critical path is at most 1.2 × the longest solver or reference
job.
Standard library only. Exit 2 (one line) when OUT has no measurements.
"""

import argparse
import json
import os
import sys


def read_seconds(path):
    """Wall seconds of a Snakemake benchmark file (header line, then one row per repeat: the
    first column `s`); None when unreadable."""
    try:
        with open(path, encoding="utf-8") as fh:
            header = fh.readline().split("\t")
            row = fh.readline().split("\t")
        return float(row[header.index("s")])
    except (OSError, ValueError, IndexError):
        return None


def rule_of(job):
    """The rule of a job file stem: report, check (check-<shard job>), solver-l…, else the
    reference tool (dolfinx-l…)."""
    if job == "report" or job.startswith("check-"):
        return job.split("-")[0]
    return job.split("-l")[0] if "-l" in job else job


def checked_by(check, shard):
    """Whether the check job `check` reads the shard job `shard`'s output: check-solver-l<L>-<u>
    the solver shards solver-l<L>-<u>-…, check-references-l<L> the reference shards <tool>-l<L>;
    check-<shard> (one shard) that shard."""
    what = check[len("check-"):]
    if shard == what or shard.startswith(what + "-") and what.startswith("solver-"):
        return True
    if what.startswith("references-l"):
        return not shard.startswith("solver-") and shard.endswith("-" + what[len("references-"):])
    return False


def measure(out):
    """{scene: {job: seconds}} of the campaign folder `out`."""
    root = os.path.join(out, "benchmarks")
    scenes = {}
    for scene in sorted(os.listdir(root)) if os.path.isdir(root) else []:
        jobs = {}
        for f in sorted(os.listdir(os.path.join(root, scene))):
            if f.endswith(".tsv"):
                s = read_seconds(os.path.join(root, scene, f))
                if s is not None:
                    jobs[f[:-4]] = s
        if jobs:
            scenes[scene] = jobs
    return scenes


def critical_path(scenes):
    """{"critical_s", "scene", "shard", "shard_s", "report_s", "sum_s", "per_rule_s", "jobs",
    "per_scene"} of `scenes` (see the module documentation); a scene without a measured report
    counts its report as 0 s."""
    per_scene = {}
    per_rule = {}
    for scene, jobs in scenes.items():
        shards = {j: s for j, s in jobs.items() if rule_of(j) not in ("report", "check")}
        # a check job starts when the last of its shards ends; the report waits for all
        chain = {j: (s, None, 0.0) for j, s in shards.items()}
        for j, s in jobs.items():
            if rule_of(j) == "check":
                mine = {k: v for k, v in shards.items() if checked_by(j, k)}
                first = max(mine, key=mine.get) if mine else None
                chain[j] = (mine.get(first, 0.0), first, s)
        longest = max(chain, key=lambda j: chain[j][0] + chain[j][2]) if chain else None
        shard_s, shard, check_s = chain[longest] if longest else (0.0, None, 0.0)
        if longest in shards:
            shard = longest
        report = jobs.get("report", 0.0)
        per_scene[scene] = {"path_s": shard_s + check_s + report, "shard": shard,
                            "check": longest if check_s else None, "shard_s": shard_s,
                            "check_s": check_s, "report_s": report,
                            "longest_shard_s": max(shards.values(), default=0.0)}
        for j, s in jobs.items():
            per_rule[rule_of(j)] = per_rule.get(rule_of(j), 0.0) + s
    scene = max(per_scene, key=lambda k: per_scene[k]["path_s"])
    return {"critical_s": per_scene[scene]["path_s"], "scene": scene,
            "shard": per_scene[scene]["shard"], "shard_s": per_scene[scene]["shard_s"],
            "check": per_scene[scene]["check"], "check_s": per_scene[scene]["check_s"],
            "report_s": per_scene[scene]["report_s"],
            "sum_s": sum(s for jobs in scenes.values() for s in jobs.values()),
            "per_rule_s": dict(sorted(per_rule.items())),
            "jobs": sum(len(j) for j in scenes.values()), "per_scene": per_scene}


REPORT_SHARE_GOAL = 0.15  # report jobs' share of all job-seconds, at most
CRITICAL_PATH_GOAL = 1.2  # critical path over the longest solver or reference job, at most


def goals(cp):
    """[(text, met)] of the two goals (module documentation) for critical_path()'s result. The
    compare tool's share counts its report and check jobs together: moving its work from the
    report into per-shard checks does not make it cheaper."""
    compare = cp["per_rule_s"].get("report", 0.0) + cp["per_rule_s"].get("check", 0.0)
    share = compare / cp["sum_s"] if cp["sum_s"] > 0 else 0.0
    longest = max((p["longest_shard_s"] for p in cp["per_scene"].values()), default=0.0)
    ratio = cp["critical_s"] / longest if longest > 0 else float("inf")
    return [(f"compare tool (report and check jobs) {100 * share:.1f} % of the job-seconds "
             f"(goal ≤ {100 * REPORT_SHARE_GOAL:.0f} %)", share <= REPORT_SHARE_GOAL),
            (f"critical path {cp['critical_s']:.1f} s = {ratio:.2f} × the longest solver or "
             f"reference job ({longest:.1f} s; goal ≤ {CRITICAL_PATH_GOAL:g} ×)",
             ratio <= CRITICAL_PATH_GOAL)]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", help="campaign folder (tools/campaign --out)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    args = ap.parse_args(argv)
    scenes = measure(args.out)
    if not scenes:
        print(f"critical_path: no job measurements under {args.out}/benchmarks/", file=sys.stderr)
        return 2
    cp = critical_path(scenes)
    cp["goals"] = [{"goal": text, "met": met} for text, met in goals(cp)]
    if args.json:
        print(json.dumps(cp, indent=2))
        return 0
    print(f"{'scene':20} {'shard on the path':34} {'shard s':>8} {'check on the path':26} "
          f"{'check s':>8} {'report s':>9} {'path s':>8}")
    for scene, p in sorted(cp["per_scene"].items(), key=lambda kv: -kv[1]["path_s"]):
        print(f"{scene:20} {str(p['shard']):34} {p['shard_s']:8.1f} {str(p['check'] or '–'):26} "
              f"{p['check_s']:8.1f} {p['report_s']:9.1f} {p['path_s']:8.1f}")
    check = f" + {cp['check']} {cp['check_s']:.1f} s" if cp["check"] else ""
    print(f"\ncritical path (one node per job): {cp['critical_s']:.1f} s "
          f"({cp['scene']}: {cp['shard']} {cp['shard_s']:.1f} s{check}"
          f" + report {cp['report_s']:.1f} s)")
    print(f"sum of all {cp['jobs']} jobs: {cp['sum_s']:.1f} s ("
          + ", ".join(f"{r} {s:.1f}" for r, s in cp["per_rule_s"].items()) + ")")
    for g in cp["goals"]:
        print(f"goal: {g['goal']}: {'MET' if g['met'] else 'MISSED'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
