#!/usr/bin/python3
"""Stops a Slurm campaign that no node can serve any more, with a message that says why.

    slurm_watch.py CAMPAIGN_DIR SNAKEMAKE_PID [--every S] [--checks N]

Run by tools/campaign beside Snakemake under a Slurm profile. Every S seconds (default 5) it asks
`squeue` for the campaign's jobs (those whose working directory is CAMPAIGN_DIR) and `sinfo` for
the nodes of their partitions. When jobs are pending, none is running, and no node of their
partitions can take a job (every one drained, draining, down, failed or in maintenance) in N
checks in a row (default 3: a node resumed within seconds is no reason to stop), it writes the
message to CAMPAIGN_DIR/logs/slurm-stopped.txt (tools/campaign ends with it), says on stderr that
it stops the campaign, and interrupts Snakemake (SIGINT),
which cancels the campaign's Slurm jobs and exits; the outputs done so far stay, and the same
command resumes the campaign once a node is back. Snakemake alone would wait for the pending jobs
forever. Exits when Snakemake does. Standard library only.
"""

import argparse
import os
import signal
import subprocess
import sys
import time

# sinfo's base states (%T, without its suffixes * ~ # ! % $ @ ^ -) of a node that takes jobs
USABLE = {"idle", "mixed", "allocated", "completing", "planned"}


def run(cmd):
    """stdout of `cmd`, or None when it fails (a Slurm command may time out under load)."""
    try:
        return subprocess.run(cmd, capture_output=True, text=True, timeout=30,
                              check=True).stdout
    except (OSError, subprocess.SubprocessError):
        return None


def campaign_jobs(campaign):
    """[(job id, state, reason, partition)] of the jobs whose working directory is `campaign`."""
    out = run(["squeue", "--noheader", "--format", "%i|%T|%r|%P|%Z"])
    if out is None:
        return None
    jobs = []
    for line in out.splitlines():
        job, state, reason, partition, workdir = line.split("|", 4)
        if os.path.realpath(workdir) == campaign:
            jobs.append((job, state, reason, partition))
    return jobs


def nodes(partitions):
    """[(node, state, reason)] of `partitions` (comma-separated)."""
    out = run(["sinfo", "--noheader", "--Node", "--partition", partitions, "--format", "%N|%T|%E"])
    if out is None:
        return None
    return [tuple(line.split("|", 2)) for line in out.splitlines()]


def base_state(state):
    return state.rstrip("*~#!%$@^-").lower()


def stranded(campaign):
    """The message when the campaign's pending jobs have no node to run on, else None."""
    jobs = campaign_jobs(campaign)
    if not jobs or any(state == "RUNNING" for _, state, _, _ in jobs):
        return None
    pending = [j for j in jobs if j[1] == "PENDING"]
    if not pending:
        return None
    partitions = sorted({p for _, _, _, part in pending for p in part.split(",")})
    found = nodes(",".join(partitions))
    if not found or any(base_state(state) in USABLE for _, state, _ in found):
        return None
    said = "; ".join(f"{n} {s}" + (f" (reason: {r})" if r and r != "none" else "")
                     for n, s, r in found)
    return (f"campaign: stopped: {len(pending)} job(s) pending and no node of partition "
            f"{', '.join(partitions)} can run them: {said}. Done jobs are kept; run the same "
            f"command again once a node is back (e.g. scontrol update nodename=NODE state=resume)")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("campaign")
    p.add_argument("pid", type=int)
    p.add_argument("--every", type=float, default=5.0)
    p.add_argument("--checks", type=int, default=3)
    args = p.parse_args(argv)
    campaign = os.path.realpath(args.campaign)
    seen = 0
    while True:
        time.sleep(args.every)
        try:
            os.kill(args.pid, 0)
        except OSError:
            return 0
        message = stranded(campaign)
        seen = seen + 1 if message else 0
        if seen >= args.checks:
            os.makedirs(os.path.join(campaign, "logs"), exist_ok=True)
            with open(os.path.join(campaign, "logs", "slurm-stopped.txt"), "w") as f:
                f.write(message + "\n")
            print("campaign: no node can run the pending jobs; stopping (cancelling the "
                  "campaign's Slurm jobs)", file=sys.stderr)
            os.kill(args.pid, signal.SIGINT)
            return 0


if __name__ == "__main__":
    sys.exit(main())
