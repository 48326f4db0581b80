#!/usr/bin/python3
"""The index of a campaign folder: DIR/index.html and DIR/index.json, one row per scene.

    ci/campaign_index.py DIR [--scene NAME ...]

DIR is a campaign folder of ci/campaign or ci/nightly (DIR/<name>/report/report.json per scene,
the jobs' logs under DIR/logs/<name>/), or a folder of such scene folders put together, e.g. the
GitHub nightly's downloaded artifacts. The scenes are the --scene names, else those of
DIR/inputs/config.json (the last campaign run there), else every DIR/<name>/ holding a report,
summary.json or scene.toml and every DIR/logs/<name>/.

A scene's verdict is its report's (PASS or FAIL). A scene without a report, or one of whose jobs
failed since (its output missing and its log without a `campaign: ... done` line: a failed or
killed job), or whose report is older than its shards or inputs, is FAIL; the index shows the
failing jobs' logs (their last 40 lines, and a link). Prints one verdict line per scene and the
index's path; exit 0 when every scene PASSes, 1 otherwise, 2 on bad usage. Standard library only.
"""

import argparse
import datetime
import html
import json
import os
import re
import sys

TAIL = 40
RESERVED = {"inputs", "shards", "checks", "logs", "benchmarks"}


def load_json(path):
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except (OSError, ValueError):
        return None


def mtime(path):
    try:
        return os.stat(path).st_mtime
    except OSError:
        return None


def scenes_of(root, names):
    if names:
        return list(dict.fromkeys(names))
    config = load_json(os.path.join(root, "inputs", "config.json"))
    if isinstance(config, dict) and isinstance(config.get("scenes"), list):
        return config["scenes"]
    found = set()
    for entry in os.listdir(root):
        d = os.path.join(root, entry)
        if entry.startswith(".") or entry in RESERVED or not os.path.isdir(d):
            continue
        if any(os.path.exists(os.path.join(d, f)) for f in ("report", "summary.json", "scene.toml")):
            found.add(entry)
    logs = os.path.join(root, "logs")
    if os.path.isdir(logs):
        found.update(e for e in os.listdir(logs) if os.path.isdir(os.path.join(logs, e)))
    return sorted(found)


def job_output(root, name, job):
    """The output a job's log belongs to (None: not a log of the workflow)."""
    if job == "report":
        return os.path.join(root, name, "report", "report.json")
    if job.startswith("check-"):
        return os.path.join(root, "checks", name, job[len("check-"):] + ".json")
    m = re.fullmatch(r"([A-Za-z0-9]+)-(l\d+(?:-.+)?)", job)
    if not m:
        return None
    return os.path.join(root, "shards", name, m.group(1), m.group(2))


def log_status(text):
    """`done`, `failed` or None (no status line: the job was killed or is still running)."""
    status = None
    for line in text.splitlines():
        m = re.match(r"campaign: .* (done|failed) \(exit -?\d+\)$", line)
        if m:
            status = m.group(1)
    return status


def failed_jobs(root, name):
    logs = os.path.join(root, "logs", name)
    out = []
    if not os.path.isdir(logs):
        return out
    for entry in sorted(os.listdir(logs)):
        if not entry.endswith(".log"):
            continue
        job = entry[:-4]
        output = job_output(root, name, job)
        if output is None or os.path.exists(output):
            continue
        path = os.path.join(logs, entry)
        try:
            with open(path, encoding="utf-8", errors="replace") as fh:
                text = fh.read()
        except OSError:
            continue
        status = log_status(text)
        if status == "done":
            continue  # ran to the end; its output was removed since (a later job reruns it)
        lines = text.splitlines()
        out.append({
            "job": job,
            "log": os.path.relpath(path, root),
            "status": status or "did not finish (killed, or still running)",
            "tail": "\n".join(lines[-TAIL:]),
        })
    return out


def stale(root, name):
    """True when the report is older than a shard or input it was made from (a campaign that did
    not get as far as the report since)."""
    report = mtime(os.path.join(root, name, ".snakemake_timestamp")) or \
        mtime(os.path.join(root, name, "report", "report.json"))
    if report is None:
        return False
    newest = [mtime(os.path.join(root, "inputs", f)) for f in (f"{name}.toml", "sdcrack.sha256")]
    shards = os.path.join(root, "shards", name)
    if os.path.isdir(shards):
        for kind in os.listdir(shards):
            k = os.path.join(shards, kind)
            if os.path.isdir(k):
                newest += [mtime(os.path.join(k, s, ".snakemake_timestamp")) for s in os.listdir(k)]
    return any(t is not None and t > report for t in newest)


def scene_row(root, name):
    report = load_json(os.path.join(root, name, "report", "report.json"))
    verdict = report.get("verdict") if isinstance(report, dict) else None
    failed = failed_jobs(root, name)
    row = {"name": name, "verdict": "FAIL", "reason": None, "report": None,
           "report_verdict": verdict, "failed_jobs": failed,
           "converged": converged_line(report) if isinstance(report, dict) else None,
           "first_problem": first_problem(report) if isinstance(report, dict) else None}
    if os.path.isfile(os.path.join(root, name, "report", "index.html")):
        row["report"] = f"{name}/report/index.html"
    if verdict is None:
        row["reason"] = "no report" + (f": {len(failed)} job(s) failed" if failed else
                                       " (and no failed job's log here)")
    elif failed:
        row["reason"] = f"report out of date: {len(failed)} job(s) failed since"
    elif stale(root, name):
        row["reason"] = "report older than its shards or inputs: rerun the campaign"
    elif verdict == "PASS":
        row["verdict"] = "PASS"
    else:
        row["reason"] = "the report's verdict"
    return row


# one symbol per quantity, as the report's plots write them
SYMBOL = {"u_l2": "u", "p_l2": "p", "p_x": "p_X", "lambda_l2": "λ"}
# the p space's tag in a variant's label, as in the report's labels and the solver's field names
# (broken/M1/lumped/ptangential); none for the paper's continuous p (a series without `p_space`)
P_SPACE_TAG = {"continuous": "", "broken-tangential": "ptangential"}


def variant_key(s):
    """"u space/multiplier[/lumped][/ptangential]" of a report.json series: the labels of before
    the p mass and p space axes for the consistent p mass and the continuous p."""
    pm, ps = s.get("p_mass"), s.get("p_space")
    tags = ["" if pm in (None, "consistent") else str(pm),
            "" if ps is None else P_SPACE_TAG.get(ps, str(ps))]
    return "/".join([f"{s.get('u_space')}/{s.get('multiplier')}"] + [t for t in tags if t])


def converged_line(report):
    """What converged and at which rates, in one line, from report.json's series: the variants
    (variant_key: u space/multiplier[/lumped][/ptangential]) whose every quantity converges, the
    range of their last rates per quantity, and the declared expected failures."""
    variants = {}
    for s in report.get("series") or []:
        variants.setdefault(variant_key(s), []).append(s)
    ok = {k: ss for k, ss in variants.items() if all(s.get("status") == "converges" for s in ss)}
    xfail = sorted(k for k, ss in variants.items()
                   if all(s.get("status") == "expected failure" for s in ss))
    if not variants:
        return "no series measured"
    rates = {}
    for ss in ok.values():
        for s in ss:
            last = (s.get("rates") or [None])[-1]
            if isinstance(last, (int, float)):
                rates.setdefault(s["quantity"], []).append(float(last))
    parts = [f"{len(ok)} of {len(variants)} variants converge"
             + (f" ({', '.join(sorted(ok))})" if ok and len(ok) <= 4 else "")]
    if rates:
        parts.append("last rates " + ", ".join(
            f"{SYMBOL.get(q, q)} {min(v):.2f}" + (f"–{max(v):.2f}" if max(v) > min(v) + 5e-3 else "")
            for q, v in sorted(rates.items(), key=lambda kv: list(SYMBOL).index(kv[0])
                               if kv[0] in SYMBOL else 9)))
    if xfail:
        parts.append(f"{len(xfail)} declared expected failure(s)")
    return "; ".join(parts)


def first_problem(report):
    """The report's first reason for its verdict, or None."""
    reasons = report.get("reasons") or []
    return str(reasons[0]) if reasons else None


def write_atomic(path, text):
    tmp = f"{path}.tmp-{os.getpid()}"
    with open(tmp, "w", encoding="utf-8") as fh:
        fh.write(text)
    os.replace(tmp, path)


def render_html(rows, verdict, created):
    e = html.escape
    out = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
           "<title>sdcrack campaign: " + e(verdict) + "</title>",
           '<meta name="viewport" content="width=device-width, initial-scale=1">',
           "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}"
           "div.scroll{overflow-x:auto;max-width:100%}td.t{min-width:14em}"
           "td,th{border:1px solid #ccc;padding:.3em .6em;text-align:left;vertical-align:top}"
           ".PASS{color:#060;font-weight:bold}.FAIL{color:#b00;font-weight:bold}"
           "pre{background:#f6f6f6;padding:.5em;overflow-x:auto;max-width:100em}</style>",
           "</head><body>",
           f'<h1>sdcrack campaign: <span class="{e(verdict)}">{e(verdict)}</span></h1>',
           f"<p>{len(rows)} scene(s), index written {e(created)}.</p>",
           "<div class='scroll'><table><tr><th>scene</th><th>verdict</th>"
           "<th>what converged, at which rates</th><th>first problem</th><th>report</th></tr>"]
    for r in rows:
        link = (f'<a href="{e(r["report"])}">report</a>' if r["report"] else "none")
        problem = " — ".join(x for x in (r["reason"] if r["verdict"] != "PASS" else None,
                                          r.get("first_problem")) if x) or "none"
        out.append(f'<tr><td>{e(r["name"])}</td><td class="{e(r["verdict"])}">{e(r["verdict"])}'
                   f'</td><td class="t">{e(r.get("converged") or "–")}</td>'
                   f'<td class="t">{e(problem)}</td><td>{link}</td></tr>')
    out.append("</table></div>")
    for r in rows:
        if not r["failed_jobs"]:
            continue
        out.append(f'<h2 id="{e(r["name"])}">{e(r["name"])}: failed jobs</h2>')
        for j in r["failed_jobs"]:
            out.append(f'<h3>{e(j["job"])} ({e(j["status"])}): <a href="{e(j["log"])}">'
                       f'{e(j["log"])}</a></h3>')
            out.append(f"<p>last {TAIL} lines of the log:</p><pre>{e(j['tail'])}</pre>")
    out.append("</body></html>")
    return "\n".join(out) + "\n"


def build(root, names=None):
    rows = [scene_row(root, n) for n in scenes_of(root, names)]
    verdict = "PASS" if rows and all(r["verdict"] == "PASS" for r in rows) else "FAIL"
    created = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    write_atomic(os.path.join(root, "index.json"),
                 json.dumps({"verdict": verdict, "created": created, "scenes": rows}, indent=1)
                 + "\n")
    write_atomic(os.path.join(root, "index.html"), render_html(rows, verdict, created))
    return rows, verdict


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("dir", help="campaign folder")
    p.add_argument("--scene", action="append", default=[],
                   help="a scene the folder should hold (repeat; default: see above)")
    args = p.parse_args()
    root = args.dir
    if not os.path.isdir(root):
        print(f"campaign_index: {root}: no such folder", file=sys.stderr)
        return 2
    rows, verdict = build(root, args.scene)
    for r in rows:
        if r["report"] and r["verdict"] == r["report_verdict"]:
            print(f"  {r['verdict']}  {os.path.join(root, r['report'])}")
        else:
            jobs = ", ".join(os.path.join(root, j["log"]) for j in r["failed_jobs"][:3])
            more = len(r["failed_jobs"]) - 3
            print(f"  {r['verdict']}  {r['name']}: {r['reason']}"
                  + (f"; see {jobs}" if jobs else "") + (f" (+{more} more)" if more > 0 else ""))
    if not rows:
        print(f"  FAIL  no scene in {root}")
    print(f"index: {os.path.join(root, 'index.html')}")
    return 0 if verdict == "PASS" else 1


if __name__ == "__main__":
    sys.exit(main())
