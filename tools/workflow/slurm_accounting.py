#!/usr/bin/python3
"""What Slurm measured of a campaign run with --profile slurm, against what each job asked for.

    slurm_accounting.py CAMPAIGN_DIR [--factor F] [--json FILE]

Reads which Slurm job ran which Snakemake job from the plugin's logs
(CAMPAIGN_DIR/.snakemake/slurm_logs/rule_<rule>/<wildcards>/<jobid>.log; the profile keeps them)
and each Slurm job's record from `sacct` (state, ReqMem, MaxRSS of every step). A job's peak is
the sum of its steps' MaxRSS (the batch step runs Snakemake, the srun step Snakemake and the
command; they run at the same time; sacct samples every JobAcctGatherFrequency seconds). Prints
one line per rule and level (jobs, requested MB, peak MB, the largest and smallest ratio), the
number of Slurm jobs per Snakemake job, and a verdict:

  FAIL when a completed job's request is below its peak (an estimate too low: on a cluster that
       enforces memory, an out-of-memory kill) or above F times its peak (default F = 2: a
       request far above the need holds memory that other jobs wait for; with every request
       within 2× of its peak, any estimate halved is caught), or when a job did not complete;
  PASS otherwise.

--json FILE writes every job's record. Exit 0 PASS, 1 FAIL, 2 no such campaign, no Slurm logs,
or sacct unavailable (one line on stderr). Standard library only.
"""

import argparse
import collections
import json
import os
import re
import subprocess
import sys

# sacct's sizes: a number and a unit (K, M, G, T; 22.05 may append n or c: per node, per CPU)
SIZE = re.compile(r"^([0-9.]+)([KMGT]?)[nc]?$")
UNIT_MB = {"": 1 / 2**20, "K": 1 / 1024, "M": 1.0, "G": 1024.0, "T": 1024.0**2}


class Refused(Exception):
    """Input the check cannot judge: one line, exit 2."""


def size_mb(text):
    """sacct's `205748K`, `300M` or `1.50G` in MB; 0 for an empty field (a step never sampled)."""
    if not text:
        return 0.0
    m = SIZE.match(text)
    if not m:
        raise Refused(f"sacct printed a size it does not know: {text!r}")
    return float(m.group(1)) * UNIT_MB[m.group(2)]


def slurm_jobs(campaign):
    """{slurm job id: (rule, wildcards)} from the plugin's log folders."""
    logs = os.path.join(campaign, ".snakemake", "slurm_logs")
    if not os.path.isdir(logs):
        raise Refused(f"{logs}: no Slurm logs (was the campaign run with --profile slurm?)")
    jobs = {}
    for rule_dir in sorted(os.listdir(logs)):
        if not rule_dir.startswith("rule_"):
            continue
        for wildcards in sorted(os.listdir(os.path.join(logs, rule_dir))):
            for log in os.listdir(os.path.join(logs, rule_dir, wildcards)):
                stem = log[:-len(".log")]
                if log.endswith(".log") and stem.isdigit():
                    jobs[stem] = (rule_dir[len("rule_"):], wildcards)
    if not jobs:
        raise Refused(f"{logs}: no job logs")
    return jobs


def sacct_records(ids):
    """{job id: {"state", "requested_mb", "steps": {step: max_rss_mb}}} of `sacct -j ids`."""
    cmd = ["sacct", "--parsable2", "--noheader", "--jobs", ",".join(sorted(ids, key=int)),
           "--format", "JobID,State,ReqMem,MaxRSS"]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError) as exc:
        err = getattr(exc, "stderr", "") or str(exc)
        raise Refused(f"sacct failed: {err.strip().splitlines()[-1] if err.strip() else exc}")
    records = {}
    for line in out.splitlines():
        job_id, state, req, rss = line.split("|")
        job, _, step = job_id.partition(".")
        rec = records.setdefault(job, {"state": "", "requested_mb": 0.0, "steps": {}})
        if not step:
            rec["state"] = state.split()[0] if state else ""
            rec["requested_mb"] = size_mb(req)
        elif step != "extern":
            rec["steps"][step] = size_mb(rss)
    return records


def level_of(rule, wildcards):
    """The level in a job's wildcards (`closed-exact_2_broken_M1_lumped_`), or '-' (report)."""
    m = re.search(r"_(\d+)(_|$)", wildcards)
    return m.group(1) if m and rule != "report" else "-"


def judge(campaign, factor):
    """Every job's record and the verdict's problems."""
    names = slurm_jobs(campaign)
    records = sacct_records(names)
    jobs, problems = [], []
    for job_id, (rule, wildcards) in sorted(names.items(), key=lambda kv: int(kv[0])):
        rec = records.get(job_id)
        if rec is None:
            problems.append(f"Slurm job {job_id} ({rule} {wildcards}) is not in sacct")
            continue
        peak = sum(rec["steps"].values())
        job = {"slurm_job": int(job_id), "rule": rule, "wildcards": wildcards,
               "level": level_of(rule, wildcards), "state": rec["state"],
               "requested_mb": rec["requested_mb"], "peak_mb": round(peak, 1),
               "steps_max_rss_mb": {k: round(v, 1) for k, v in rec["steps"].items()}}
        jobs.append(job)
        what = f"Slurm job {job_id} ({rule} {wildcards})"
        if rec["state"] != "COMPLETED":
            problems.append(f"{what} ended {rec['state'] or 'in no state'}")
        elif peak <= 0:
            problems.append(f"{what}: sacct sampled no memory")
        elif rec["requested_mb"] < peak:
            problems.append(f"{what}: requested {rec['requested_mb']:.0f} MB, below its peak "
                            f"{peak:.0f} MB: the estimate is too low")
        elif rec["requested_mb"] > factor * peak:
            problems.append(f"{what}: requested {rec['requested_mb']:.0f} MB, more than {factor:g}× "
                            f"its peak {peak:.0f} MB")
    return jobs, problems


def table(jobs):
    """Lines: per rule and level, jobs, requested and peak MB ranges, ratio range."""
    groups = collections.defaultdict(list)
    for j in jobs:
        if j["peak_mb"] > 0:
            groups[(j["rule"], j["level"])].append(j)
    lines = ["rule              level  jobs  requested MB   peak MB        requested/peak"]
    for (rule, level), js in sorted(groups.items()):
        req = [j["requested_mb"] for j in js]
        peak = [j["peak_mb"] for j in js]
        ratio = [j["requested_mb"] / j["peak_mb"] for j in js]
        lines.append(f"{rule:17} {level:>5} {len(js):5}  {min(req):5.0f}-{max(req):<6.0f} "
                     f"{min(peak):5.0f}-{max(peak):<6.0f}  {min(ratio):4.2f}-{max(ratio):.2f}")
    return lines


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("campaign")
    p.add_argument("--factor", type=float, default=2.0)
    p.add_argument("--json")
    args = p.parse_args(argv)
    try:
        if not os.path.isdir(args.campaign):
            raise Refused(f"{args.campaign}: no such campaign folder")
        jobs, problems = judge(args.campaign, args.factor)
    except Refused as exc:
        print(f"slurm_accounting: {exc}", file=sys.stderr)
        return 2
    runs = collections.Counter((j["rule"], j["wildcards"]) for j in jobs)
    again = {k: n for k, n in runs.items() if n > 1}
    for line in table(jobs):
        print(line)
    print(f"{len(jobs)} Slurm jobs for {len(runs)} Snakemake jobs"
          + (f"; run more than once: {', '.join(f'{r} {w} ({n}×)' for (r, w), n in sorted(again.items()))}"
             if again else ""))
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"factor": args.factor, "jobs": jobs, "problems": problems}, f, indent=1)
    for line in problems[:20]:
        print(f"  {line}")
    if len(problems) > 20:
        print(f"  … and {len(problems) - 20} more")
    print(f"memory requests: {'FAIL' if problems else 'PASS'} ({len(problems)} problem(s) in "
          f"{len(jobs)} jobs; a request must lie within [peak, {args.factor:g} × peak])")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
