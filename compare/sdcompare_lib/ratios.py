"""Yardsticks from measurement: the ratio of sdcrack's error to the references'.

The reference yardstick (yardsticks.py) bounds sdcrack's error by a fixed 3 × the references' own
error on the same mesh. A load-vector scatter bug made sdcrack's distance to the references
1.7–1.8 × larger, kept its rates, and passed inside that 3 ×. Where sdcrack and the references
converge at the same order the ratio of their errors is a measured property of the method, and
two checks hold it:

* **The ratio settles** ("reference ratio settles"). For a series whose expected order (theory.py)
  is the references' own (theory.p1_order: u 2s, p s; λ has none, the references' jump
  superconverges), ρ_l = e_sdcrack(l) / e_ref(l) per level. If both errors behave as
  C h^r (1 + O(h^σ)), ρ tends to the ratio of the constants and log ρ changes by O(h^σ) per level.
  Exactly, for any errors,

      log ρ_L − log ρ_{L−1} = (r_ref,L − r_sdcrack,L) · ln(h_{L−1}/h_L),

  r_·,L the observed rates from level L − 1 to L: a ratio that grows is sdcrack's rate lagging the
  references' on the same meshes. The series rule accepts an observed rate down to the expected
  order − theory.RATE_MARGIN (0.1); held to the references' observed rate instead of the theory's
  order with the same margin, the bound is

      log ρ_L − log ρ_{L−1} ≤ RATE_MARGIN · ln(h_{L−1}/h_L)   (a factor 2^0.1 = 1.072 per halving),

  on each of the last two steps (as the series rule). Measured on the repository's exact scenes
  (levels 2–4 of tools/campaign, 4–5 of ci/nightly) the largest growth is open-exact's lumped p_l2,
  log change 0.0505 from level 2 to 3 (a rate lag of 0.073), against the bound 0.0693. It is
  one-sided: a falling ρ is sdcrack converging faster than P1 on the same mesh — the lumped p, a
  recovered gradient, superconverges on uniform meshes (p rate 1.74 on closed-exact, ρ 0.12 →
  0.07 over levels 3–4) — which no rate rule forbids either. It applies to the series measured against the exact solution: without one,
  ρ is measured against the reference's finest level F, whose own error biases it by a factor
  that depends on l (≈ 1/(1 − 2^{−r(F−l)}) where the two errors align; measured on mixed, p_l2:
  0.69, 0.80, 1.25 over levels 1–3 against level 4, 0.68, 0.75, 1.02, 1.59 over levels 1–4
  against level 5), so no bound from the rates holds there.

* **Against a recorded ratio** ("recorded reference ratio"). scenes/expectations.toml's [[ratio]]
  rows record ρ at one level of a reviewed run; a ratio outside [ρ / RATIO_BAND, ρ × RATIO_BAND]
  fails. A row holds its scene, a series pattern (u space, multiplier, p mass, p space; "*"
  matches every value), quantity, reference, level, the mesh size h of that level (the largest
  triangle diameter, which tells the mesh recorded from one with other cells), the ratio, and
  without an exact solution the reference level it was measured against (reference_level). A row
  is compared only where the run has that level on that mesh (and, without an exact solution,
  against that reference level); otherwise it is skipped, with the reason. A scene with
  references and no row says "not applicable: no recorded ratio".

The band (RATIO_BAND = 1.25): run to run the ratio at one level is bit-identical (levels 0–4 of
the exact scenes, tools/campaign against ci/nightly: relative difference 0), so the band is set by
what it must catch and what it must let through, not by noise. It must fail the realistic bug,
1.7 × (the load-vector scatter: 1.7–1.8 ×). It must let through what a change of the meshes'
resolution by about one level does to a ratio, measured as the change of ρ from one level to the
next on the repository's exact scenes (tools/campaign levels 2–4, ci/nightly 4–5), leaving out the
lumped p_l2 of the uniform smooth meshes (closed-exact, open-smooth), which superconverges and
falls by 40 % a level: at most a factor 1.12 (open-graded, the lumped broken-tangential p_l2,
0.875 → 0.780 over levels 4–5; 0.972 → 0.875 over 3–4), 1.052 on a rising ratio (open-exact, the
lumped p_l2, 1.359 → 1.429 over levels 2–3). 1.25 leaves a factor ≈ 2 in log on both sides:
ln 1.25 = 1.95 × ln 1.12, ln 1.7 = 2.38 × ln 1.25. (The superconvergent ratios are recorded too:
only the recorded level is compared, where a run reproduces them bit for bit.)

The record command, `compare/sdcompare RESULTS --record-expectations FILE`, writes the scene's
[[ratio]] rows from a run whose every other check holds (record()).
"""
import math
import os
import re
import tomllib

from . import theory
from sdshared.sdresults import write_atomic
from .read import InputError, finite_number
from .cases import (DEFAULT_P_MASS, DEFAULT_P_SPACE, p_mass, p_space, variant_label, variant_of,
                    variant_order)
from .refyard import ABS_FLOOR, reference_inputs

# ρ may differ from the recorded ratio by this factor either way (module docstring).
RATIO_BAND = 1.25
# log ρ may grow by RATE_MARGIN × ln(h_{L−1}/h_L) per step (module docstring).
SETTLE_MARGIN = theory.RATE_MARGIN
# A row's h and the run's h of the same level agree to round-off when the mesh is the same.
H_RTOL = 1e-9
# The record command merges series (u spaces, multipliers) into one "*" row when their ratios
# agree to this relative tolerance: 1 % of the band's log width, so a merged row's value stands
# for each of its series to within 0.2 %.
MERGE_RTOL = 2e-3
# Significant digits of a recorded ratio (a relative rounding of ≤ 5e-5).
DIGITS = 4

SETTLE_LABEL = "reference ratio settles"
RECORDED_LABEL = "recorded reference ratio"
# A scene's [[verification.not_applicable]] of the reference yardstick applies to both checks:
# they measure the same errors against the same references.
DECLARED_AS = "reference yardstick"

RATIO_KEYS = {"scene", "u_space", "multiplier", "p_mass", "p_space", "quantity", "reference",
              "level", "reference_level", "h", "ratio", "note"}
REQUIRED_KEYS = ("scene", "u_space", "multiplier", "quantity", "reference", "level", "h", "ratio")
RATIO_DEFAULTS = {"p_mass": DEFAULT_P_MASS, "p_space": DEFAULT_P_SPACE}
# The quantities the references give an own error for and whose order P1 has (theory.p1_order).
RATIO_QUANTITIES = ("u_l2", "p_l2")
REFERENCES = ("dolfinx", "freefem")
PATTERN_KEYS = ("u_space", "multiplier", "p_mass", "p_space")


# ---------------------------------------------------------------- the rows of the file
def load_rows(path):
    """The [[ratio]] rows of an expectations file, each with its `index`, keys and types checked
    (ValueError naming the row)."""
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    rows = data.get("ratio", [])
    if not isinstance(rows, list):
        raise ValueError("'ratio' must be [[ratio]] tables")
    out = []
    for i, r in enumerate(rows):
        name = f"ratio {i}"
        bad = set(r) - RATIO_KEYS
        if bad:
            raise ValueError(f"{name}: unknown keys {sorted(bad)}; allowed {sorted(RATIO_KEYS)}")
        for k in REQUIRED_KEYS:
            if k not in r:
                raise ValueError(f"{name}: missing '{k}'")
        for k in ("scene",) + PATTERN_KEYS + ("reference", "note"):
            if k in r and (not isinstance(r[k], str) or not r[k]):
                raise ValueError(f"{name}: {k} must be a non-empty string, not {r[k]!r}")
        if r["quantity"] not in RATIO_QUANTITIES:
            raise ValueError(f"{name}: quantity {r['quantity']!r} is none of "
                             f"{', '.join(RATIO_QUANTITIES)} (the quantities the references have "
                             "an own error and P1's order for)")
        if r["reference"] not in REFERENCES:
            raise ValueError(f"{name}: reference {r['reference']!r} is none of "
                             f"{', '.join(REFERENCES)}")
        for k in ("level", "reference_level"):
            if k in r and (not isinstance(r[k], int) or isinstance(r[k], bool) or r[k] < 0):
                raise ValueError(f"{name}: {k} must be a level (an integer ≥ 0), not {r[k]!r}")
        if "reference_level" in r and r["reference_level"] <= r["level"]:
            raise ValueError(f"{name}: reference_level {r['reference_level']} must be finer than "
                             f"level {r['level']}")
        for k in ("h", "ratio"):
            if not finite_number(r[k]) or r[k] <= 0:
                raise ValueError(f"{name}: {k} must be a positive number, not {r[k]!r}")
        out.append({**r, "index": i})
    for a_ in out:
        for b in out:
            if b["index"] > a_["index"] and _overlap(a_, b):
                raise ValueError(f"ratio {a_['index']} and ratio {b['index']} both hold "
                                 f"{a_['scene']} {a_['quantity']} at level {a_['level']} for the "
                                 "same series: one row per series and level")
    return out


def _overlap(a, b):
    """Whether two rows can match the same series at the same level."""
    if (a["scene"], a["quantity"], a["level"]) != (b["scene"], b["quantity"], b["level"]):
        return False
    return all("*" in (a.get(k, RATIO_DEFAULTS.get(k)), b.get(k, RATIO_DEFAULTS.get(k)))
               or a.get(k, RATIO_DEFAULTS.get(k)) == b.get(k, RATIO_DEFAULTS.get(k))
               for k in PATTERN_KEYS)


def _scene_files_beside(path):
    """{scene name: its scene file (parsed)} of the *.toml files beside `path`."""
    import glob

    out = {}
    for f in glob.glob(os.path.join(os.path.dirname(os.path.abspath(path)), "*.toml")):
        try:
            with open(f, "rb") as fh:
                data = tomllib.load(fh)
        except (OSError, ValueError):
            continue
        if isinstance(data.get("name"), str):
            out[data["name"]] = data
    return out


def validate_rows(rows, path, scene, scene_file):
    """The rows that apply to `scene` (ValueError for a row naming a scene, u space, multiplier,
    p mass or p space that does not exist, or a reference_level given where the scene has an exact
    solution or missing where it has none). A row's series must be values of the judged scene's
    file or of the scene file of that name beside `path`: a run of fewer variants (a copy with the
    consistent p mass only) is judged by the rows of the repository's scene. Its level may be any
    level (load_rows: an integer ≥ 0): a run that has not got it (tools/campaign --levels 0-1, the
    nightly's 0–5) skips the row, and the report says so (recorded_rows)."""
    from .settings import scene_lists, scene_p_masses, scene_p_spaces

    beside = _scene_files_beside(path)
    known = set(beside) | {scene}
    mine = []
    for r in rows:
        name = f"ratio {r['index']}"
        if r["scene"] not in known:
            raise ValueError(f"{name} names scene {r['scene']!r}, which is neither this results "
                             f"folder's scene nor a scene file beside {path}")
        if r["scene"] != scene:
            continue
        _, u_spaces, multipliers, _ = scene_lists(scene_file)
        files = [scene_file] + ([beside[scene]] if scene in beside else [])
        for key, values in (("u_space", u_spaces), ("multiplier", multipliers),
                            ("p_mass", scene_p_masses(scene_file)),
                            ("p_space", scene_p_spaces(scene_file))):
            v = r.get(key, RATIO_DEFAULTS.get(key))
            if v != "*" and v not in set(values).union(*(_lists(f)[key] for f in files)):
                raise ValueError(f"{name}: {key} {v!r} is not run by scene {scene!r} (its scene "
                                 f"file lists {values})")
        has_exact = "exact" in scene_file
        if has_exact and "reference_level" in r:
            raise ValueError(f"{name}: scene {scene!r} has an exact solution: its ratio is "
                             "measured against it, not against a reference_level")
        if not has_exact and "reference_level" not in r:
            raise ValueError(f"{name}: scene {scene!r} has no exact solution: give the "
                             "reference_level its ratio was measured against")
        mine.append(r)
    return mine


def _lists(scene_file):
    """{u_space, multiplier, p_mass, p_space: the values the scene file runs}."""
    from .settings import scene_lists, scene_p_masses, scene_p_spaces

    _, u_spaces, multipliers, _ = scene_lists(scene_file)
    return {"u_space": u_spaces, "multiplier": multipliers,
            "p_mass": scene_p_masses(scene_file), "p_space": scene_p_spaces(scene_file)}


def rows_for_scene(path, scene, scene_file):
    """{"path", "rows"}: the [[ratio]] rows of `path` that apply to `scene`, validated."""
    return {"path": path, "rows": validate_rows(load_rows(path), path, scene, scene_file)}


# ---------------------------------------------------------------- the ratios of a run
def equal_order(s, regularity):
    """Whether the series converges at the references' order (theory.p1_order; none for λ) in a
    quantity the references have an own error for (RATIO_QUANTITIES: not p_x, the mixed method's
    X-norm)."""
    if s["quantity"] not in RATIO_QUANTITIES:
        return False
    ref = theory.p1_order(s["quantity"], regularity)
    e = s.get("expected_rate")
    return ref is not None and e is not None and abs(e - ref) <= 1e-12


def level_h(cases):
    """{level: h} of the run's cases (the largest triangle diameter; every case of a level has the
    same triangles)."""
    out = {}
    for c in cases:
        if finite_number(c.get("h")):
            out.setdefault(int(c["level"]), float(c["h"]))
    return out


def reference_finest(ref):
    """The finest level of a reference with a mesh (the level reference_errors_finest measures
    against), or None."""
    meshes = ref.get("mesh") or {}
    levels = [lv for lv in ref.get("u", {}) if lv in meshes]
    return max(levels) if levels else None


def ratio_entries(res, a, tool):
    """(reference level or None, entries): one entry per series of the run that converges at the
    references' order (equal_order) and is not a declared expected failure, with ρ per level
    against `tool` (None where an error is missing or zero to round-off)."""
    yard, series = reference_inputs(res, a, tool)
    ref_level = None if a["exact"] is not None else reference_finest(res["refs"][tool])
    hs = level_h(res["summary"]["cases"])
    out = []
    for s in series:
        if s["status"] == "expected failure" or not equal_order(s, a["regularity"]):
            continue
        q = s["quantity"]
        entry = {"u_space": s["u_space"], "multiplier": s["multiplier"], "p_mass": p_mass(s),
                 "p_space": p_space(s), "quantity": q, "expected_rate": s["expected_rate"],
                 "levels": list(s["levels"]),
                 # the mesh parameter of the rates (N^{-1/2} on graded meshes), else the case's h
                 "mesh_parameter": list(s.get("h") or [hs.get(lv) for lv in s["levels"]]),
                 "h": [hs.get(lv) for lv in s["levels"]], "errors": list(s["errors"]),
                 "yardstick": [yard.get((lv, q)) for lv in s["levels"]]}
        entry["ratios"] = [e / y if finite_number(e) and finite_number(y) and e > ABS_FLOOR
                           and y > ABS_FLOOR else None
                           for e, y in zip(entry["errors"], entry["yardstick"])]
        out.append(entry)
    out.sort(key=lambda e: (variant_order(variant_of(e)), e["quantity"]))
    return ref_level, out


def settling_rows(entries):
    """One row per series and each of its last two steps (consecutive levels with a ratio):
    log ρ_L − log ρ_{L−1} against SETTLE_MARGIN · ln(h_{L−1}/h_L)."""
    rows = []
    for e in entries:
        pts = [(lv, h, r) for lv, h, r in zip(e["levels"], e["mesh_parameter"], e["ratios"])
               if r is not None and finite_number(h) and h > 0]
        steps = [(a, b) for a, b in zip(pts, pts[1:]) if b[0] == a[0] + 1][-2:]
        for (l0, h0, r0), (l1, h1, r1) in steps:
            change, bound = math.log(r1 / r0), SETTLE_MARGIN * math.log(h0 / h1)
            rows.append({"u_space": e["u_space"], "multiplier": e["multiplier"],
                         "p_mass": e["p_mass"], "p_space": e["p_space"],
                         "quantity": e["quantity"], "from_level": l0, "level": l1,
                         "ratio_from": r0, "ratio": r1, "log_change": change, "bound": bound,
                         "rate_lag": change / math.log(h0 / h1) if h0 != h1 else None,
                         "ok": change <= bound + 1e-12})
    return rows


def settling_problems(rows):
    return [_settling_problem(r) for r in rows if not r["ok"]]


def _settling_problem(r):
    return (f"{variant_label(*variant_of(r))} {r['quantity']}: ρ grows from "
            f"{r['ratio_from']:.4g} (level {r['from_level']}) to {r['ratio']:.4g} (level "
            f"{r['level']}), log change {r['log_change']:.3g} > {r['bound']:.3g} = "
            f"{SETTLE_MARGIN:g} × ln(h_{r['from_level']}/h_{r['level']}): sdcrack's rate "
            f"lags the references' by {r['rate_lag']:.3g} > {SETTLE_MARGIN:g}")


def _matches(row, entry):
    return (row["quantity"] == entry["quantity"]
            and all(row.get(k, RATIO_DEFAULTS.get(k)) in ("*", entry[k]) for k in PATTERN_KEYS))


def recorded_rows(rows, res, a):
    """Each applicable [[ratio]] row against the run: status "ok", "violated", "skipped" (the run
    has not got the row's level on the row's mesh, or its reference level; with the reason) or
    "not evaluated" (no series of the run matches it, or a ratio is missing: fails)."""
    out = []
    entries_of = {}
    for row in rows:
        base = {"index": row["index"], "quantity": row["quantity"], "level": row["level"],
                "reference": row["reference"], "recorded": row["ratio"],
                "pattern": _pattern_label(row)}
        tool = row["reference"]
        if tool not in res["refs"]:
            out.append({**base, "status": "skipped",
                        "reason": f"the run has no {tool} reference"})
            continue
        if tool not in entries_of:
            entries_of[tool] = ratio_entries(res, a, tool)
        ref_level, entries = entries_of[tool]
        hs = level_h([c for c in res["summary"]["cases"]])
        if row["level"] not in hs:
            have = sorted(hs)
            out.append({**base, "status": "skipped", "reason": (
                f"the run has no level {row['level']} (its levels: "
                f"{', '.join(map(str, have)) or 'none'})")})
            continue
        if abs(hs[row["level"]] - row["h"]) > H_RTOL * row["h"]:
            out.append({**base, "status": "skipped", "reason": (
                f"the run's level {row['level']} is another mesh (h = {hs[row['level']]:.6g}; "
                f"recorded on h = {row['h']:.6g})")})
            continue
        if "reference_level" in row and ref_level != row["reference_level"]:
            out.append({**base, "status": "skipped", "reason": (
                f"the run's {tool} ends at level {ref_level}, the row was measured against "
                f"level {row['reference_level']}")})
            continue
        lacking = _not_run(row, res["plan"])
        if lacking:
            out.append({**base, "status": "skipped", "reason": f"the run has no {lacking}"})
            continue
        matched = [e for e in entries if _matches(row, e)]
        if not matched:
            out.append({**base, "status": "not evaluated", "reason": (
                "no series of this run that converges at the references' order matches it")})
            continue
        for e in matched:
            r = dict(zip(e["levels"], e["ratios"])).get(row["level"])
            res_row = {**base, "variant": variant_label(*variant_of(e)), "u_space": e["u_space"],
                       "multiplier": e["multiplier"], "p_mass": e["p_mass"],
                       "p_space": e["p_space"], "measured": r, "band": RATIO_BAND}
            if r is None:
                res_row.update(status="not evaluated", reason=(
                    f"no ratio at level {row['level']} (an error is missing or zero)"))
            else:
                ok = row["ratio"] / RATIO_BAND <= r <= row["ratio"] * RATIO_BAND
                res_row.update(factor=r / row["ratio"], status="ok" if ok else "violated",
                               reason="" if ok else (
                                   f"ρ = {r:.4g} at level {row['level']} is {r / row['ratio']:.3g}"
                                   f" × the recorded {row['ratio']:.4g}, outside the band "
                                   f"1/{RATIO_BAND:g}–{RATIO_BAND:g} ×"))
            out.append(res_row)
    return out


def _not_run(row, plan):
    """"p_mass lumped" when the row names a value the run's plan does not run, else None."""
    from .cases import plan_p_masses, plan_p_spaces

    runs = {"u_space": plan.get("u_spaces", []), "multiplier": plan.get("multipliers", []),
            "p_mass": plan_p_masses(plan), "p_space": plan_p_spaces(plan)}
    for k in PATTERN_KEYS:
        v = row.get(k, RATIO_DEFAULTS.get(k))
        if v != "*" and v not in runs[k]:
            return f"{k} {v}"
    return None


def _pattern_label(row):
    return "/".join(row.get(k, RATIO_DEFAULTS.get(k)) for k in PATTERN_KEYS)


# ---------------------------------------------------------------- the check rows
def checks(res, a, declared):
    """The two check rows (label, requirement, problems, not-applicable reason); their rows go to
    a["yardsticks"]["ratio_settling"] and a["yardsticks"]["ratio_recorded"]."""
    from .checks import _references_asked

    a["yardsticks"]["ratio_settling"] = []
    a["yardsticks"]["ratio_recorded"] = []
    recorded = res.get("recorded_ratios") or {"path": None, "rows": []}
    settle_what = (f"over the last two steps, ρ = e / e_ref of each series converging at the "
                   f"references' order grows by ≤ {SETTLE_MARGIN:g} × ln(h_(L−1)/h_L) in log (a "
                   f"factor {2 ** SETTLE_MARGIN:.3f} per halving: sdcrack's rate within "
                   f"{SETTLE_MARGIN:g} of the references' own on the same meshes)")
    source = os.path.basename(recorded["path"]) if recorded["path"] else "the expectations file"
    rec_what = (f"ρ at each recorded level within a factor {RATIO_BAND:g} of the [[ratio]] rows "
                f"of {source}")
    tools = [t for t in REFERENCES if t in res["refs"]]
    na = None
    if DECLARED_AS in declared:
        na = f"declared in the scene for the {DECLARED_AS}: {declared[DECLARED_AS]}"
    elif not tools and not _references_asked(res["scene_file"]):
        na = "the scene runs no reference"
    if na is not None:
        return [(SETTLE_LABEL, settle_what, [], na), (RECORDED_LABEL, rec_what, [], na)]
    if not tools:
        missing = ["could not run: the references the scene asks for are missing"]
        return [(SETTLE_LABEL, settle_what, missing, None), (RECORDED_LABEL, rec_what, missing,
                                                              None)]
    tool = tools[0]
    _, entries = ratio_entries(res, a, tool)
    return [_settling_row(a, tool, entries, settle_what),
            _recorded_row(res, a, recorded, entries, rec_what)]


def _settling_row(a, tool, entries, what):
    if a["exact"] is None:
        return SETTLE_LABEL, what, [], (
            "the scene has no [exact]: ρ is measured against the reference's finest level, whose "
            "own error biases it by a factor that depends on the level (≈ 1/(1 − 2^(−r(F−l))) "
            "where the errors align), so no bound from the rates holds; the recorded ratio holds "
            "it at one level")
    if not entries:
        return SETTLE_LABEL, what, [], (
            "no series converges at the references' order (" + _orders(a) + ")")
    rows = settling_rows(entries)
    a["yardsticks"]["ratio_settling"] = rows
    if not rows:
        if len({lv for e in entries for lv in e["levels"]}) < 2:
            return SETTLE_LABEL, what, [], "the run has one level: no step"
        return SETTLE_LABEL, what, [f"could not run: no two consecutive levels with both "
                                    f"sdcrack's and {tool}'s error"], None
    return (SETTLE_LABEL, what + f" ({tool}; {len(entries)} series, {len(rows)} steps"
            + _ratio_range(entries) + ")", settling_problems(rows), None)


def _ratio_range(entries):
    finest = [e["ratios"][-1] for e in entries if e["ratios"] and e["ratios"][-1] is not None]
    return f"; ρ at the finest level {min(finest):.3g}–{max(finest):.3g}" if finest else ""


def _orders(a):
    """"u_l2 0.5 ≠ 1, p_l2 …": the expected orders of the series against the references'."""
    seen = {}
    for s in a["series"]:
        ref = theory.p1_order(s["quantity"], a["regularity"])
        if ref is None or s.get("expected_rate") is None:
            continue
        seen.setdefault(s["quantity"], (set(), ref))[0].add(f"{s['expected_rate']:g}")
    return ", ".join(f"{q} {'/'.join(sorted(es))} ≠ {ref:g}" for q, (es, ref) in seen.items()) \
        or "no series with an expected order the references have"


def _recorded_row(res, a, recorded, entries, what):
    rows = recorded["rows"]
    if not rows:
        where = recorded["path"] or "the expectations file"
        return RECORDED_LABEL, what, [], (
            f"no recorded ratio for scene {res.get('scene')!r} in {where} (record one from a "
            "reviewed run: compare/sdcompare RESULTS --record-expectations FILE)")
    checked = recorded_rows(rows, res, a)
    a["yardsticks"]["ratio_recorded"] = checked
    problems = [f"ratio {r['index']} ({r.get('variant') or r['pattern']} {r['quantity']}, level "
                f"{r['level']}): {r['status']}: {r['reason']}"
                for r in checked if r["status"] in ("violated", "not evaluated")]
    judged = [r for r in checked if r["status"] in ("ok", "violated", "not evaluated")]
    if not judged:
        reasons = sorted({r["reason"] for r in checked})
        return RECORDED_LABEL, what, [], ("no recorded row applies to this run: "
                                          + "; ".join(reasons))
    skipped = len(checked) - len(judged)
    return (RECORDED_LABEL, what + f" ({len(judged)} series × row comparison(s)" + (
        f"; {skipped} row(s) skipped" if skipped else "") + ")", problems, None)


# ---------------------------------------------------------------- recording
BEGIN = "# --- [[ratio]] rows of {scene} (begin)"
END = "# --- [[ratio]] rows of {scene} (end)"


def measured_rows(res, a, levels=None):
    """The [[ratio]] rows of the run: for the reference the yardstick uses, each series converging
    at the references' order at its finest level with a ratio (among `levels`, when given: those
    of the repository's scene file, so that a nightly run of levels 0-5 records the level 4 the
    campaign runs too), series of one (p mass, p space, quantity) merged into "*" rows where their
    ratios agree to MERGE_RTOL."""
    tools = [t for t in REFERENCES if t in res["refs"]]
    if not tools:
        return None, []
    tool = tools[0]
    ref_level, entries = ratio_entries(res, a, tool)
    hs = level_h(res["summary"]["cases"])
    at = []
    for e in entries:
        pts = [(lv, r) for lv, r in zip(e["levels"], e["ratios"])
               if r is not None and (levels is None or lv in levels)]
        if pts:
            at.append((e, pts[-1][0], pts[-1][1]))
    groups = {}
    for e, lv, r in at:
        groups.setdefault((e["p_mass"], e["p_space"], e["quantity"], lv), []).append((e, r))
    rows = []
    for (pm, ps, q, lv), members in groups.items():
        for (u, m), rs in _merge(members):
            row = {"scene": res["scene"], "u_space": u, "multiplier": m, "p_mass": pm,
                   "p_space": ps, "quantity": q, "reference": tool, "level": lv}
            if ref_level is not None and a["exact"] is None:
                row["reference_level"] = ref_level
            row["h"] = hs[lv]
            row["ratio"] = float(f"{_geomean(rs):.{DIGITS}g}")
            rows.append(row)
    rows.sort(key=lambda r: (variant_order((r["u_space"] if r["u_space"] != "*" else "",
                                            r["multiplier"] if r["multiplier"] != "*" else "",
                                            r["p_mass"], r["p_space"])), r["quantity"]))
    return tool, rows


def _geomean(rs):
    return math.exp(sum(math.log(r) for r in rs) / len(rs))


def _close(rs):
    g = _geomean(rs)
    return all(abs(r / g - 1) <= MERGE_RTOL for r in rs)


def _merge(members):
    """[((u space or "*", multiplier or "*"), [ratios])]: every series as one "*" row where their
    ratios agree, else per u space, else one row per series."""
    def name(ms, key):  # the value the merged series share, else "*"
        values = {e[key] for e, _ in ms}
        return values.pop() if len(values) == 1 else "*"

    if _close([r for _, r in members]):
        return [((name(members, "u_space"), name(members, "multiplier")),
                 [r for _, r in members])]
    out = []
    by_u = {}
    for e, r in members:
        by_u.setdefault(e["u_space"], []).append((e, r))
    for u, ms in by_u.items():
        if _close([r for _, r in ms]):
            out.append(((u, name(ms, "multiplier")), [r for _, r in ms]))
        else:
            out += [((u, e["multiplier"]), [r]) for e, r in ms]
    return out


def _row_text(row):
    lines = ["[[ratio]]"]
    for k in ("scene", "u_space", "multiplier", "p_mass", "p_space", "quantity", "reference",
              "level", "reference_level", "h", "ratio"):
        if k not in row:
            continue
        v = row[k]
        lines.append(f"{k} = " + (f'"{v}"' if isinstance(v, str) else repr(v)))
    return "\n".join(lines)


def block_text(scene, rows, source, tool):
    """The file's block of [[ratio]] rows of `scene`, between its begin and end lines."""
    import textwrap

    level = ", ".join(map(str, sorted({r["level"] for r in rows})))
    against = sorted({r["reference_level"] for r in rows if "reference_level" in r})
    text = (f"ρ = e_sdcrack / e_{tool} at level {level}"
            + (f" (against {tool}'s level {', '.join(map(str, against))}: no [exact])"
               if against else " (against the exact solution)")
            + f", recorded from {source} by `compare/sdcompare RESULTS --record-expectations "
            "FILE`, which rewrites this block (and only it).")
    head = [BEGIN.format(scene=scene)] + ["# " + line for line in textwrap.wrap(
        text, 97, break_on_hyphens=False)]
    return "\n".join(head + ["\n\n".join(_row_text(r) for r in rows), END.format(scene=scene)])


def _key(r):
    return tuple(r.get(k, RATIO_DEFAULTS.get(k)) for k in PATTERN_KEYS) + (r["quantity"],
                                                                           r["level"])


def _describe(r):
    return (f"{'/'.join(str(x) for x in _key(r)[:4])} {r['quantity']} level {r['level']}"
            + (f" (against reference level {r['reference_level']})" if "reference_level" in r
               else ""))


def record(a, res, path, out=print):
    """--record-expectations FILE: writes the scene's [[ratio]] rows into FILE (its block between
    the scene's begin and end lines, replaced, or appended at the end; everything else of the file
    kept byte for byte), prints what changed and returns 0. Refuses (InputError, exit 2) a run
    that fails a check other than the recorded ratio's, a file that does not load, rows of the
    scene outside its block, and a result that would not read back."""
    scene = res["scene"]
    failing = [f"{label}: {p}" for label, _, probs, _ in a["checks"] if label != RECORDED_LABEL
               for p in probs]
    if failing:
        raise InputError(f"not recorded: the run FAILs ({len(failing)} problem(s); first: "
                         f"{failing[0]}): record from a reviewed run that passes")
    if not os.path.isfile(path):
        raise InputError(f"--record-expectations: no such file {path}")
    with open(path, encoding="utf-8") as fh:
        text = fh.read()
    try:
        from .verdict import load_expectations

        load_expectations(path)
        old_all = load_rows(path)
    except (ValueError, OSError) as exc:
        raise InputError(f"bad expectations file {path}: {exc}")
    from .settings import scene_lists

    beside = _scene_files_beside(path)
    tool, rows = measured_rows(res, a, scene_lists(beside[scene])[0] if scene in beside else None)
    if not rows:
        raise InputError(f"not recorded: scene {scene!r} has no series converging at the "
                         "references' order with a ratio (or no reference)")
    begin, end = BEGIN.format(scene=scene), END.format(scene=scene)
    pat = re.compile(r"(?ms)^" + re.escape(begin) + r"$.*?^" + re.escape(end) + r"$")
    found = pat.findall(text)
    if len(found) > 1:
        raise InputError(f"{path}: the rows of {scene} are in {len(found)} blocks; keep one")
    old = [r for r in old_all if r["scene"] == scene]
    inside = load_rows_text(found[0]) if found else []
    if len(inside) != len(old):
        raise InputError(f"{path}: {len(old) - len(inside)} [[ratio]] row(s) of {scene} outside "
                         f"its block ('{begin}' … '{end}'): move or remove them first")
    block = block_text(scene, rows, _source(res), tool)
    if found:
        new_text = pat.sub(lambda _: block, text, count=1)
    else:
        new_text = text.rstrip("\n") + "\n\n" + block + "\n"
    # what changed, then the file written atomically and read back
    changes = _changes(old, rows)
    try:
        mode = os.stat(path).st_mode & 0o7777
    except OSError:
        mode = None

    def reads_back(tmp):
        """The new file loads, holds `rows` for the scene and the other scenes' rows unchanged."""
        try:
            load_expectations(tmp)
            back = [r for r in load_rows(tmp) if r["scene"] == scene]
            others = [r for r in load_rows(tmp) if r["scene"] != scene]
        except (ValueError, OSError) as exc:
            raise InputError(f"not recorded: the new {path} would not load: {exc}")
        strip = [{k: v for k, v in r.items() if k != "index"} for r in back]
        same_others = [{k: v for k, v in r.items() if k != "index"} for r in others] == \
            [{k: v for k, v in r.items() if k != "index"} for r in old_all if r["scene"] != scene]
        if strip != rows or not same_others:
            raise InputError(f"not recorded: {path} would not read back as written")
    write_atomic(path, new_text, mode, reads_back)
    for line in changes:
        out(line)
    out(f"{scene}: {len(rows)} [[ratio]] row(s) recorded in {path} against {tool}, from "
        f"{_source(res)}")
    return 0


def _source(res):
    """The run recorded from: its folder (relative to the working directory when under it) and
    the sdcrack commit and date of its provenance."""
    folder = os.path.abspath(res["folder"])
    rel = os.path.relpath(folder)
    where = rel if not rel.startswith("..") else folder
    prov = res["summary"].get("provenance") or {}
    commit = prov.get("git_commit")
    what = []
    if isinstance(commit, str):
        what.append(f"sdcrack {commit[:7]}" + (" dirty" if prov.get("git_dirty") else ""))
    if isinstance(prov.get("date_utc"), str):
        what.append(prov["date_utc"][:10])
    return where + (f" ({', '.join(what)})" if what else "")


def load_rows_text(text):
    """The [[ratio]] rows of a block of text (its own TOML document)."""
    return tomllib.loads(text).get("ratio", [])


def _changes(old, new):
    """Lines saying what the recording changes: rows added, removed, changed, unchanged."""
    before = {_key(r): r for r in old}
    after = {_key(r): r for r in new}
    lines, same = [], 0
    for k, r in after.items():
        o = before.get(k)
        if o is None:
            lines.append(f"added: {_describe(r)}: ratio {r['ratio']:.4g} (h = {r['h']:.6g})")
        elif (o["ratio"], o["h"], o.get("reference_level"), o["reference"]) != (
                r["ratio"], r["h"], r.get("reference_level"), r["reference"]):
            lines.append(f"changed: {_describe(r)}: ratio {o['ratio']:.4g} → {r['ratio']:.4g}"
                         + (f", h {o['h']:.6g} → {r['h']:.6g}" if o["h"] != r["h"] else "")
                         + (f", reference {o['reference']} → {r['reference']}"
                            if o["reference"] != r["reference"] else ""))
        else:
            same += 1
    for k, o in before.items():
        if k not in after:
            lines.append(f"removed: {_describe(o)}: ratio {o['ratio']:.4g}")
    if same:
        lines.append(f"unchanged: {same} row(s)")
    return lines
