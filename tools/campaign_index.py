#!/usr/bin/python3
"""The index of a campaign folder: DIR/index.html and DIR/index.json, one row per scene.

    tools/campaign_index.py DIR [--scene NAME ...] [--baseline BASEDIR [--baseline-label TEXT]
                                                 | --no-baseline REASON]

DIR is a campaign folder of tools/campaign or ci/nightly (DIR/<name>/report/report.json per scene,
the jobs' logs under DIR/logs/<name>/), or a folder of such scene folders put together, e.g. the
GitHub nightly's downloaded artifacts. The scenes are the --scene names, else those of
DIR/inputs/config.json (the last campaign run there), else every DIR/<name>/ holding a report,
summary.json or scene.toml and every DIR/logs/<name>/.

A scene's verdict is its report's (PASS, FAIL, INCONCLUSIVE: "cannot judge yet", or whatever
word report.json's `verdict` holds, read as it is). A scene without a report, or one of whose jobs
failed since (its output missing and its log without a `campaign: ... done` line: a failed or
killed job), or whose report is older than its shards or inputs, is FAIL; the index shows the
failing jobs' logs (their last 40 lines, and a link). Each row also says what converged, and, from
the report's `glance`, the ratios of sdcrack's errors to the references' at the finest level both
have and the δ → 0 outcome. An elastic scene's report (docs/elasticity.md) has no glance: its row
says which of its series (per tool, the references' and the smooth-domain method's, and
quantity) converge and, in the glance's place, the method's errors at its finest level, the
references' errors at the finest level (without exact fields: their SIFs, contact fronts and
distances to the finest level) and how well they agree.

--baseline BASEDIR: a campaign folder of the same layout (e.g. the previous night's merged
artifacts; its scenes found as above, without --scene). Each scene's row then lists what changed
since: its verdict, the scene new (or gone: a line of its own), and per series (matched by
variant and quantity) its status, its finest level, its last rate by more than
BASELINE_RATE_ATOL and its error at the finest common level by more than BASELINE_ERROR_RTOL
relative (sdcompare_lib/baseline.py, the tolerances sdcompare's baseline flags use), or
"no change beyond tolerance". --baseline-label names the baseline in the header (default: the
folder). --no-baseline REASON: the header says "no baseline: REASON" instead (the nightly's
first night). Neither changes the verdict or the exit status.

Prints one verdict line per scene (and for a scene whose report does not PASS, the report's first
reason on the next line), the baseline's line and the index's path. The campaign's verdict is FAIL
when a scene's is neither PASS nor INCONCLUSIVE, else INCONCLUSIVE when one scene's is, else PASS;
exit 0 when it is PASS or INCONCLUSIVE (NOT_FAILING), 1 otherwise, 2 on bad usage (one line).
Standard library and the numpy-free
modules of the packages sdcompare_lib and sdshared (page, cases, choices, baseline, sdresults:
tests/python/test_index_glance.py): tools/campaign and ci/nightly run it with the checkout's
Python, `.venv/bin/python tools/campaign_index.py DIR` (ci/setup installs both packages
there); the GitHub nightly's index job, which has no ci/setup, with its runner's python3 and
PYTHONPATH=compare; a pip install of the checkout (pyproject.toml) makes them importable too.
"""

import argparse
import datetime
import html
import json
import math
import os
import re
import sys

from sdcompare_lib import choices
from sdcompare_lib.baseline import (BASELINE_ERROR_RTOL, BASELINE_RATE_ATOL, error_change,
                                    rate_change)
from sdcompare_lib.page import cell_class, page, scroll_table
from sdcompare_lib.cases import p_mass, p_space, variant_label
from sdshared.sdresults import write_atomic

TAIL = 40
RESERVED = {"inputs", "shards", "checks", "logs", "benchmarks"}
MAX_LISTED = 10  # changes per scene listed in index.html (index.json has them all)
NO_CHANGE = "no change beyond tolerance"
# The verdicts that do not fail a campaign: PASS, and INCONCLUSIVE (compare/sdcompare's exit 3: the
# series cannot be judged yet, e.g. "run levels up to N"). Any other word fails it, FAIL and a word
# this index does not know alike.
NOT_FAILING = ("PASS", "INCONCLUSIVE")
# A report's verdict is shown as it is (it is also the cell's CSS class: page.py colours PASS, FAIL
# and INCONCLUSIVE) when it is one upper-case word; anything else is a malformed report: FAIL.
VERDICT_WORD = re.compile(r"[A-Z][A-Z_]*")


class UsageError(Exception):
    """Bad usage or unreadable inputs: one line, exit 2."""


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
        if any(os.path.exists(os.path.join(d, f))
               for f in ("report", "summary.json", "scene.toml")):
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


def load_report(root, name):
    """The scene's report/report.json as a dict, or None."""
    report = load_json(os.path.join(root, name, "report", "report.json"))
    return report if isinstance(report, dict) else None


def scene_row(root, name, report):
    """The index's row of one scene (report: its load_report)."""
    verdict = report.get("verdict") if report else None
    failed = failed_jobs(root, name)
    row = {"name": name, "verdict": "FAIL", "reason": None, "report": None,
           "report_verdict": verdict, "failed_jobs": failed,
           "problem": ELASTIC if is_elastic(report) else None,
           "converged": (None if not report else elastic_converged_line(report)
                         if is_elastic(report) else converged_line(report)),
           "first_problem": first_problem(report) if report else None,
           "glance": (None if not report else elastic_glance(report) if is_elastic(report)
                      else glance(report))}
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
        if isinstance(verdict, str) and VERDICT_WORD.fullmatch(verdict):
            row["verdict"] = verdict
        row["reason"] = ("cannot judge yet" if verdict == "INCONCLUSIVE"
                         else "the report's verdict")
    return row


def campaign_verdict(rows):
    """FAIL when there is no scene or a scene's verdict is not NOT_FAILING, else INCONCLUSIVE
    when a scene's is, else PASS."""
    verdicts = {r["verdict"] for r in rows}
    if not rows or verdicts - set(NOT_FAILING):
        return "FAIL"
    return "PASS" if verdicts == {"PASS"} else "INCONCLUSIVE"


# one symbol per quantity, as the report's plots write them
SYMBOL = {"u_l2": "u", "p_l2": "p", "p_x": "p_X", "lambda_l2": "λ"}


def variant_key(s):
    """"u space/multiplier[/lumped][/ptangential]" of a report.json series (cases.variant_label:
    the labels of before the p mass and p space axes for the consistent p mass and the
    continuous p); an elastic report's series (no u space: one per reference) its reference,
    "dolfinx"."""
    if "u_space" not in s and "tool" in s:
        return str(s["tool"])
    return variant_label(str(s.get("u_space")), str(s.get("multiplier")), p_mass(s), p_space(s))


def converged_line(report):
    """What converged and at which rates, in one line, from report.json's series: the variants
    (variant_key: u space/multiplier[/lumped][/ptangential]) whose every quantity converges, the
    range of their last rates per quantity (per u space, p mass and p space wherever they have
    more than one: sdcompare_lib/choices.py), and the declared expected failures."""
    variants = {}
    for s in report.get("series") or []:
        variants.setdefault(variant_key(s), []).append(s)
    ok = {k: ss for k, ss in variants.items() if all(s.get("status") == "converges" for s in ss)}
    xfail = sorted(k for k, ss in variants.items()
                   if all(s.get("status") == "expected failure" for s in ss))
    if not variants:
        return "no series measured"
    undecided = [k for k, ss in variants.items() if any(s.get("status") == "inconclusive"
                                                        for s in ss)]
    parts = [f"{len(ok)} of {len(variants)} variants converge"
             + (f" ({', '.join(sorted(ok))})" if ok and len(ok) <= 4 else "")
             + (f", {len(undecided)} cannot be judged yet" if undecided else "")]
    converging = [s for ss in ok.values() for s in ss]
    per_choice = [(label, last_rates(ss)) for label, ss in choices.split(converging)]
    per_choice = [(label, text) for label, text in per_choice if text]
    if per_choice and per_choice[0][0] is None:
        parts.append(f"last rates {per_choice[0][1]}")
    elif per_choice:  # the orders differ in kind between p spaces: never one range across them
        parts.append(f"last rates per {choices.varying_axes(converging)}: "
                     + "; ".join(f"{label} {text}" for label, text in per_choice))
    if xfail:
        parts.append(f"{len(xfail)} declared expected failure(s)")
    return "; ".join(parts)


def last_rates(series, symbols=None):
    """"u 0.58–0.59, p 0.88, λ 1.43–2.02": the range of the series' last rates per quantity ("" when
    none has one), the quantities in the order of `symbols` (default SYMBOL), which names them."""
    symbols = SYMBOL if symbols is None else symbols
    rates = {}
    for s in series:
        last = (s.get("rates") or [None])[-1]
        if isinstance(last, (int, float)) and not isinstance(last, bool):
            rates.setdefault(s["quantity"], []).append(float(last))
    return ", ".join(f"{symbols.get(q, q)} {min(v):.2f}"
                     + (f"–{max(v):.2f}" if f"{max(v):.2f}" != f"{min(v):.2f}" else "")
                     for q, v in sorted(rates.items(), key=lambda kv: list(symbols).index(kv[0])
                                        if kv[0] in symbols else len(symbols)))


def first_problem(report):
    """The report's first reason for its verdict, or None."""
    reasons = report.get("reasons") or []
    return str(reasons[0]) if reasons else None


# --------------------------------------------------------------------------- the references

def number(x):
    """x as a finite float, else None (JSON's null, a string, a bool, NaN)."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return None
    return float(x) if math.isfinite(x) else None


def glance(report):
    """The index's line on the report's `glance` (sdcompare_lib/glance.py writes the line, its
    one home, with tests that make it false): sdcrack's u error over the references' at the
    finest level both have, per status group, and the δ → 0 outcome;
    {"line", "level", "against", "delta"}."""
    g = report.get("glance")
    if not isinstance(g, dict) or not isinstance(g.get("line"), str):
        line = ("no references" if not report.get("references")
                else "no error ratios (a report from before the glance)")
        return {"line": line, "level": None, "against": None, "delta": None}
    delta = g.get("delta") if isinstance(g.get("delta"), dict) else None
    return {"line": g["line"], "level": g.get("level"), "against": g.get("against"),
            "delta": delta}


# --------------------------------------------------------------------------- elastic scenes
#
# An elastic scene (docs/elasticity.md): its report judges the smooth-domain method's cases (issue
# 46; series "sdcrack <multiplier> δ=<δ>" per quantity) and the two references, against the exact
# fields where the scene has [exact] (series per tool and quantity), else against each other and
# their finest level. report.json (compare/sdcompare_lib/elastic_report.py) says "problem":
# "elasticity" and has no glance; its row says what converged and, in the glance's column, the
# method's errors at its finest level, the references' errors (or, without [exact], their SIFs,
# contact fronts and distances to the finest level) at the finest level and how well they agree.

ELASTIC = "elasticity"  # report.json's "problem" of an elastic scene (elastic_read.PROBLEM)
# the elastic report's field quantities, in its order, with the symbols of its tables
ELASTIC_SYMBOL = {"u_l2": "u", "u_h1": "∇u", "sigma_l2": "σ", "opening_l2": "opening",
                  "slip_l2": "slip"}


def is_elastic(report):
    return isinstance(report, dict) and report.get("problem") == ELASTIC


def dict_rows(report, key):
    """report.json's list `key`, its dict entries only (a malformed report shows less, never
    crashes the index)."""
    rows = report.get(key)
    return [r for r in rows if isinstance(r, dict)] if isinstance(rows, list) else []


def elastic_converged_line(report):
    """"14 of 14 series converge (dolfinx, freefem); last rates u 0.96, ∇u 0.49, …": the series
    (one per reference and quantity, the SIF errors per tip too) that converge, the references
    all of whose series do, the range of the converging series' last rates per quantity; without
    series (no [exact]) what the references were judged by instead."""
    series = dict_rows(report, "series")
    if not series:
        return "no series (no exact fields): the references compared with each other"
    ok = [s for s in series if s.get("status") == "converges"]
    undecided = sum(s.get("status") == "inconclusive" for s in series)
    tools = sorted({str(s.get("tool")) for s in series})
    whole = [t for t in tools if all(s.get("status") == "converges"
                                     for s in series if str(s.get("tool")) == t)]
    parts = [f"{len(ok)} of {len(series)} series converge"
             + (f" ({', '.join(whole)})" if whole else "")
             + (f", {undecided} cannot be judged yet" if undecided else "")]
    rates = last_rates(ok, ELASTIC_SYMBOL)
    if rates:
        parts.append(f"last rates {rates}")
    return "; ".join(parts)


def fmt(x):
    return "–" if x is None else f"{x:.2g}"


def is_solver_series(series):
    """Whether an elastic report's series is the smooth-domain method's (its tool "sdcrack
    <multiplier> δ=<δ>", compare/sdcompare_lib/elastic_sdm_verdict.py) rather than a
    reference's."""
    return str(series.get("tool")).startswith("sdcrack")


def finest_errors(series):
    """(finest level, ["σ 0.001", …]) of series: the largest error per quantity at the finest
    level any of them reaches, in ELASTIC_SYMBOL's order then the others' (None, [] without)."""
    finest = {}  # quantity -> [(level, error)]
    for s in series:
        levels, errors = s.get("levels"), s.get("errors")
        if isinstance(levels, list) and isinstance(errors, list) and levels and errors:
            finest.setdefault(str(s.get("quantity")), []).append((levels[-1], number(errors[-1])))
    if not finest:
        return None, []
    level = max(lv for rows in finest.values() for lv, _ in rows)
    parts = []
    for q in list(ELASTIC_SYMBOL) + sorted(q for q in finest if q not in ELASTIC_SYMBOL):
        errors = [e for lv, e in finest.get(q, []) if lv == level and e is not None]
        if errors:
            parts.append(f"{ELASTIC_SYMBOL.get(q, q)} {fmt(max(errors))}")
    return level, parts


def elastic_solver_part(report, series):
    """The glance's words on the smooth-domain method's cases: their errors at the finest level
    (the series' tools named), else how many cases the report judged, else "no solver case"."""
    solver = [s for s in series if is_solver_series(s)]
    level, parts = finest_errors(solver)
    if parts:
        tools = ", ".join(sorted({str(s.get("tool")) for s in solver}))
        return f"the SDM's errors at level {level} ({tools}): " + ", ".join(parts)
    cases = report.get("solver", {}).get("cases") if isinstance(report.get("solver"), dict) \
        else None
    if isinstance(cases, int) and cases > 0:
        return f"the SDM: {cases} cases judged (no exact fields)"
    return "no solver case"


def elastic_glance(report):
    """The glance's column of an elastic row, {"line", "level", "against", "delta"} like glance():
    the smooth-domain method's errors at its finest level (or "no solver case"); the references'
    largest error per quantity at their finest level (the fields' and the SIFs', from the
    series), else their SIFs and contact fronts there and the distances of the level below to it;
    then their largest disagreement in u over the levels."""
    series = dict_rows(report, "series")
    level, parts = finest_errors([s for s in series if not is_solver_series(s)])
    against = None
    if parts:
        against = "exact"
        what = f"the references' errors at level {level} (the larger of theirs)"
    else:
        parts, level = elastic_without_exact(report)
        against = "reference finest level" if level is not None else None
        what = (f"the references at level {level}" if level is not None
                else "the references: nothing measured")
    agree = [number(a.get("u_rel")) for a in dict_rows(report, "agreement")]
    agree = [a for a in agree if a is not None]
    line = (f"{elastic_solver_part(report, series)}; {what}"
            + (": " + ", ".join(parts) if parts else ""))
    if agree:
        line += f"; they agree in u to {fmt(max(agree))} (relative)"
    return {"line": line, "level": level, "against": against, "delta": None}


def elastic_without_exact(report):
    """(parts, finest level) of a report without exact fields: the first reference's SIFs per
    tip and contact fronts at its finest level, and the u distances of the level below to it."""
    sifs = dict_rows(report, "sifs")
    levels = [s.get("level") for s in sifs if isinstance(s.get("level"), int)]
    levels += [f.get("finest") for f in dict_rows(report, "field_distances")
               if isinstance(f.get("finest"), int)]
    if not levels:
        return [], None
    level = max(levels)
    tool = min((str(s.get("tool")) for s in sifs + dict_rows(report, "field_distances")),
               default=None)
    parts = []
    for s in sifs:
        if s.get("level") == level and str(s.get("tool")) == tool and isinstance(s.get("K"), list):
            ks = [k for k in s["K"] if isinstance(k, list) and len(k) == 2]
            parts.append(f"{tool}'s (K_I, K_II) per tip "
                         + ", ".join(f"({fmt(number(a))}, {fmt(number(b))})" for a, b in ks))
    for f in dict_rows(report, "fronts"):
        if f.get("level") == level and str(f.get("tool")) == tool \
                and isinstance(f.get("fronts"), list):
            xs = [fmt(number(p[0])) for p in f["fronts"] if isinstance(p, list) and p]
            parts.append(f"contact fronts at x = {', '.join(xs)}" if xs else "no contact front")
    for d in dict_rows(report, "field_distances"):
        if d.get("level") == level - 1 and str(d.get("tool")) == tool:
            parts.append(f"level {level - 1} to it: u {fmt(number(d.get('u_l2')))} (L²), "
                         f"{fmt(number(d.get('u_h1')))} (H¹)")
    return parts, level


# --------------------------------------------------------------------------- the baseline

def series_map(report):
    """{"variant quantity": series} of a report (variant_key, the same on both sides)."""
    return {f"{variant_key(s)} {s.get('quantity')}": s
            for s in (report or {}).get("series") or [] if isinstance(s, dict)}


def by_level(s, key):
    """{level: value or None} of a series' "errors" (one per level) or "rates" (one per step,
    keyed by the level it ends at)."""
    values = s.get(key) or []
    levels = s.get("levels") or list(range(len(s.get("errors") or values)))
    if key == "rates":
        levels = levels[1:]
    return {lv: number(v) for lv, v in zip(levels, values)}


def change(kind, text, old=None, new=None, **more):
    """One change since the baseline, as index.json lists it."""
    return dict({"kind": kind, "text": text, "old": old, "new": new}, **more)


def value_change(key, what, level, old, new):
    """The change of one error ("error", relative tolerance) or rate ("rate", absolute), or
    None within tolerance (sdcompare_lib/baseline.py)."""
    if old is None or new is None:
        if old is new:
            return None
        return change(what, f"{key}: {what} at level {level} {old} → {new}", old, new,
                      level=level)
    if what == "rate":
        d = rate_change(old, new)
        if d is None:
            return None
        return change("rate", f"{key}: last rate (to level {level}) {old:.4f} → {new:.4f} "
                      f"({new - old:+.2g})", old, new, level=level, abs_change=d)
    rc = error_change(old, new)
    if rc is None:
        return None
    return change("error", f"{key}: error at level {level} {old:.6g} → {new:.6g} "
                  f"({rc:.2g} relative)", old, new, level=level, rel_change=rc)


def series_changes(key, old, new):
    """What changed in one series (same variant and quantity) beyond tolerance: its status, its
    finest level, its error at the finest level both have, its rate of the last step both
    have."""
    out = []
    if old.get("status") != new.get("status"):
        out.append(change("status", f"{key}: {old.get('status')} → {new.get('status')}",
                          old.get("status"), new.get("status")))
    for what, field in (("error", "errors"), ("rate", "rates")):
        o, n = by_level(old, field), by_level(new, field)
        if what == "error" and o and n and max(o) != max(n):
            out.append(change("levels", f"{key}: finest level {max(o)} → {max(n)}",
                              max(o), max(n)))
        common = sorted(set(o) & set(n))
        if common:
            c = value_change(key, what, common[-1], o[common[-1]], n[common[-1]])
            out += [c] if c else []
    for c in out:
        c["series"] = key
    return out


def listed(names):
    """"a, b, c, d (+2 more)"."""
    return ", ".join(names[:4]) + (f" (+{len(names) - 4} more)" if len(names) > 4 else "")


def report_changes(old, new):
    """The changes between two reports of one scene: series new, gone, and changed."""
    o, n = series_map(old), series_map(new)
    out = []
    for kind, names in (("series new", [k for k in n if k not in o]),
                        ("series gone", [k for k in o if k not in n])):
        if names:
            out.append(change(kind, f"{len(names)} {kind} ({listed(names)})", names=names))
    changed = [c for key in n if key in o for c in series_changes(key, o[key], n[key])]
    return out + merge_levels(changed, sum(1 for key in n if key in o))


def merge_levels(changes, compared):
    """The changes with the series' "finest level" changes merged into one per (old, new): a
    scene run at other levels says so once, not once per series."""
    levels = {}
    for c in changes:
        if c["kind"] == "levels":
            levels.setdefault((c["old"], c["new"]), []).append(c["series"])
    merged = [change("levels", f"finest level {old} → {new} ("
                     + (f"all {compared} series" if len(keys) == compared else
                        f"{len(keys)} series: {listed(keys)}") + ")", old, new, series=keys)
              for (old, new), keys in levels.items()]
    return merged + [c for c in changes if c["kind"] != "levels"]


def scene_changes(row, report, base_row, base_report):
    """What changed in one scene since the baseline (its row and report there; None: the
    baseline has no such scene)."""
    if base_row is None:
        return [change("new scene", "new scene (not in the baseline)")]
    out = []
    if row["verdict"] != base_row["verdict"]:
        out.append(change("verdict", f"verdict {base_row['verdict']} → {row['verdict']}",
                          base_row["verdict"], row["verdict"]))
    if report and base_report:
        out += report_changes(base_report, report)
    elif report or base_report:
        where = "the baseline" if report else "tonight's folder"
        out.append(change("report", f"no report in {where}: series not compared"))
    return out


def load_baseline(base, label, names):
    """The baseline's scenes ({name: (row, report)}) and its header facts."""
    scenes = {}
    for name in scenes_of(base, None):
        report = load_report(base, name)
        scenes[name] = (scene_row(base, name, report), report)
    index = load_json(os.path.join(base, "index.json"))
    index = index if isinstance(index, dict) else {}
    head = {"folder": base, "label": label or base, "created": index.get("created"),
            "verdict": index.get("verdict"), "rate_atol": BASELINE_RATE_ATOL,
            "error_rtol": BASELINE_ERROR_RTOL,
            "gone": [n for n in scenes if n not in names]}
    return scenes, head


def apply_baseline(rows, reports, base, label):
    """Adds each row's "changes" (a list) and "changes_line" against the baseline folder;
    returns the index's "baseline" entry."""
    scenes, head = load_baseline(base, label, [r["name"] for r in rows])
    for r in rows:
        base_row, base_report = scenes.get(r["name"], (None, None))
        r["changes"] = scene_changes(r, reports[r["name"]], base_row, base_report)
        r["changes_line"] = "; ".join(c["text"] for c in r["changes"]) or NO_CHANGE
    head["changed"] = [r["name"] for r in rows if r["changes"]]
    return head


def baseline_line(head):
    """The one line naming the baseline and what it shows (or why there is none)."""
    if head is None:
        return None
    if "none" in head:
        return f"no baseline: {head['none']}"
    when = (f"its index of {head['created']}, verdict {head['verdict']}" if head["created"]
            else "no index.json there")
    changed = (f"{len(head['changed'])} scene(s) changed beyond tolerance"
               + (f" ({listed(head['changed'])})" if head["changed"] else ""))
    gone = f"; {len(head['gone'])} gone ({listed(head['gone'])})" if head["gone"] else ""
    return (f"baseline: {head['label']} ({when}): {changed}{gone}; tolerances: last rates "
            f"{head['rate_atol']:g} absolute, errors {head['error_rtol']:g} relative")


AGAINST = {"exact": "errors against the exact solution",
           "reference finest level": "distances to each reference's finest level"}


def changes_cell(r):
    """The "changed since baseline" cell: NO_CHANGE or the list (MAX_LISTED of them)."""
    e = html.escape
    if not r["changes"]:
        return f'<td class="t">{e(NO_CHANGE)}</td>'
    items = "".join(f"<li>{e(c['text'])}</li>" for c in r["changes"][:MAX_LISTED])
    more = len(r["changes"]) - MAX_LISTED
    if more > 0:
        items += f"<li>{more} more: index.json</li>"
    return f'<td class="t"><ul>{items}</ul></td>'


def table_row(r, with_baseline):
    """One scene's <tr>."""
    e = html.escape
    link = (f'<a href="{e(r["report"])}">report</a>' if r["report"] else "none")
    reason = r["reason"] if r["verdict"] != "PASS" else None
    problem = " — ".join(x for x in (reason, r.get("first_problem")) if x) or "none"
    g = r.get("glance") or {}
    note = "; ".join(x for x in (AGAINST.get(g.get("against")),
                                 (g.get("delta") or {}).get("text")) if x)
    title = f' title="{e(note)}"' if note else ""
    return (f'<tr><td class="{cell_class(r["name"])}">{e(r["name"])}</td>'
            f'<td class="{e(r["verdict"])}">{e(r["verdict"])}'
            f'</td><td class="t">{e(r.get("converged") or "–")}</td>'
            f'<td class="t"{title}>{e(g.get("line") or "–")}</td>'
            f'<td class="t">{e(problem)}</td>'
            + (changes_cell(r) if with_baseline else "") + f"<td>{link}</td></tr>")


def failed_jobs_html(rows):
    """The failed jobs' sections: each job's log, its last TAIL lines."""
    e = html.escape
    out = []
    for r in rows:
        if not r["failed_jobs"]:
            continue
        out.append(f'<h2 id="{e(r["name"])}">{e(r["name"])}: failed jobs</h2>')
        for j in r["failed_jobs"]:
            out.append(f'<h3>{e(j["job"])} ({e(j["status"])}): <a href="{e(j["log"])}">'
                       f'{e(j["log"])}</a></h3>')
            out.append(f"<p>last {TAIL} lines of the log:</p><pre>{e(j['tail'])}</pre>")
    return out


def render_html(rows, verdict, created, baseline=None):
    """index.html (sdcompare_lib/page.py's page, the report's): the verdict, the baseline's
    line, one row per scene, the failed jobs."""
    e = html.escape
    with_baseline = baseline is not None and "none" not in baseline
    body = [f"<p>{len(rows)} scene(s), index written {e(created)}.</p>"]
    if baseline is not None:
        body.append(f'<p id="baseline">{e(baseline_line(baseline))}</p>')
    headers = (["scene", "verdict", "what converged, at which rates",
                "sdcrack's errors / the references'", "first problem (or what cannot be judged)"]
               + (["changed since baseline"] if with_baseline else []) + ["report"])
    body += scroll_table([e(h) for h in headers], [table_row(r, with_baseline) for r in rows])
    body += failed_jobs_html(rows)
    return page(f"sdcrack campaign: {verdict}", body,
                f'sdcrack campaign: <span class="{e(verdict)}">{e(verdict)}</span>')


def build(root, names=None, baseline=None, label=None, no_baseline=None):
    """Writes ROOT/index.json and ROOT/index.html; returns (rows, verdict, baseline entry)."""
    names = scenes_of(root, names)
    reports = {n: load_report(root, n) for n in names}
    rows = [scene_row(root, n, reports[n]) for n in names]
    head = None
    if baseline is not None:
        head = apply_baseline(rows, reports, baseline, label)
    elif no_baseline is not None:
        head = {"none": no_baseline}
    verdict = campaign_verdict(rows)
    created = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
    index = {"verdict": verdict, "created": created, "baseline": head, "scenes": rows}
    write_atomic(os.path.join(root, "index.json"), json.dumps(index, indent=1) + "\n")
    write_atomic(os.path.join(root, "index.html"), render_html(rows, verdict, created, head))
    return rows, verdict, head


def parse_args(argv):
    """The command line (argparse: exit 2 on an unknown option)."""
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("dir", help="campaign folder")
    p.add_argument("--scene", action="append", default=[],
                   help="a scene the folder should hold (repeat; default: see above)")
    b = p.add_mutually_exclusive_group()
    b.add_argument("--baseline", metavar="BASEDIR",
                   help="an earlier campaign folder: list per scene what changed since")
    b.add_argument("--no-baseline", metavar="REASON",
                   help="no baseline, and why (the header says 'no baseline: REASON')")
    p.add_argument("--baseline-label", metavar="TEXT",
                   help="what the baseline is, for the header (default: BASEDIR)")
    return p.parse_args(argv)


def check_args(args):
    """Raises UsageError on a missing folder or a label without a baseline."""
    if not os.path.isdir(args.dir):
        raise UsageError(f"{args.dir}: no such folder")
    if args.baseline is not None and not os.path.isdir(args.baseline):
        raise UsageError(f"--baseline {args.baseline}: no such folder")
    if args.baseline_label is not None and args.baseline is None:
        raise UsageError("--baseline-label needs --baseline")


def print_rows(root, rows):
    """One verdict line per scene."""
    for r in rows:
        if r["report"] and r["verdict"] == r["report_verdict"]:
            print(f"  {r['verdict']}  {os.path.join(root, r['report'])}")
            if r["verdict"] != "PASS" and r.get("first_problem"):
                print(f"      {r['first_problem']}")
        else:
            jobs = ", ".join(os.path.join(root, j["log"]) for j in r["failed_jobs"][:3])
            more = len(r["failed_jobs"]) - 3
            print(f"  {r['verdict']}  {r['name']}: {r['reason']}"
                  + (f"; see {jobs}" if jobs else "") + (f" (+{more} more)" if more > 0 else ""))
    if not rows:
        print(f"  FAIL  no scene in {root}")


def main(argv=None):
    args = parse_args(argv)
    root = args.dir
    try:
        check_args(args)
        rows, verdict, head = build(root, args.scene, args.baseline, args.baseline_label,
                                    args.no_baseline)
    except UsageError as e:
        print(f"campaign_index: {e}", file=sys.stderr)
        return 2
    print_rows(root, rows)
    if head is not None:
        print(baseline_line(head))
    print(f"index: {os.path.join(root, 'index.html')}")
    return 0 if verdict in NOT_FAILING else 1


if __name__ == "__main__":
    sys.exit(main())
