#!/usr/bin/python3
"""Prints the jobs of a `snakemake --dry-run` output (tools/campaign --dry-run), one line each:

    RULE  OUTPUT  (REASON)

sorted by rule (solver, reference, check, report; the rules check_solver and check_references
are both listed as check, elastic_solver as solver) and output, then one summary line:

    campaign: dry run: N of TOTAL jobs would run (solver S, reference R, check C, report P)

Usage: joblist.py DRY_RUN_OUTPUT_FILE TOTAL_JOBS. Standard library only.
"""

import re
import sys

ORDER = {"solver": 0, "reference": 1, "check": 2, "report": 3}
# the workflow's rule names, as listed
LISTED = {"check_solver": "check", "check_references": "check", "elastic_solver": "solver"}


def parse(text):
    jobs, job = [], None
    for line in text.splitlines():
        m = re.match(r"^(?:local)?rule (\w+):$", line)
        if m:
            job = {"rule": LISTED.get(m.group(1), m.group(1)), "output": "", "reason": ""}
            jobs.append(job)
            continue
        m = re.match(r"^\s+(output|reason): (.*)$", line)
        if m and job is not None:
            job[m.group(1)] = m.group(2)
    return [j for j in jobs if j["rule"] in ORDER]


def main():
    with open(sys.argv[1], encoding="utf-8", errors="replace") as fh:
        jobs = parse(fh.read())
    total = sys.argv[2]
    jobs.sort(key=lambda j: (ORDER[j["rule"]], j["output"]))
    width = max((len(j["output"]) for j in jobs), default=0)
    for j in jobs:
        reason = j["reason"].split(":")[0]
        print(f"  {j['rule']:<9}  {j['output']:<{width}}  ({reason})")
    counts = ", ".join(f"{r} {sum(j['rule'] == r for j in jobs)}" for r in ORDER)
    if jobs:
        print(f"campaign: dry run: {len(jobs)} of {total} jobs would run ({counts})")
    else:
        print(f"campaign: dry run: nothing to rerun, all {total} jobs up to date")


if __name__ == "__main__":
    main()
