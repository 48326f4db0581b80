"""All computed checks (rates, δ-limit, references, GCI, KKT, timings), expectations, baseline,
and the verdict."""
import math
import tomllib
from collections import defaultdict

import numpy as np

from . import norms, rates
from .read import case_key, total_time

# p_x is the paper's mesh-dependent X-norm of the p error (summary.json, when computed).
QUANTITIES = ("u_l2", "p_l2", "p_x", "lambda_l2")
# Theorem 4.3 bounds ‖u−u_h‖ + ‖p−p_h‖_X + ‖λ−λ_h‖ together: its rate applies to each of them.
PAPER_NORMS = ("u_l2", "p_x", "lambda_l2")
PAPER_RATE = {"M0": 0.5, "M1": 0.5, "M1star": 0.75}
BASELINE_ERROR_RTOL = 1e-6
BASELINE_RATE_ATOL = 1e-4
BASELINE_TIME_GROWTH = 0.30
BASELINE_TIME_MIN_S = 0.01
ROUNDOFF_REL = 1e-12


def _variants(cases):
    return sorted({(c["u_space"], c["multiplier"]) for c in cases})


def ref_delta(cases):
    """δ used for the h -> 0 study: 0 if present, else the smallest."""
    ds = {float(c["delta"]) for c in cases}
    return 0.0 if 0.0 in ds else min(ds)


def series_by_variant(cases, delta):
    out = {}
    for u, m in _variants(cases):
        cs = sorted((c for c in cases if c["u_space"] == u and c["multiplier"] == m
                     and float(c["delta"]) == delta), key=lambda c: int(c["level"]))
        if cs:
            out[(u, m)] = cs
    return out


# ---------------------------------------------------------------- h -> 0 (Theorem 4.3)
def compute_rates(scene, cases):
    out = []
    if not cases:
        return out
    delta = ref_delta(cases)
    for (u, m), cs in series_by_variant(cases, delta).items():
        for q in QUANTITIES:
            pts = [(float(c["h"]), float(c["errors"][q]), int(c["level"])) for c in cs
                   if isinstance(c.get("errors"), dict) and c["errors"].get(q) is not None]
            if not pts:
                continue
            h = [p[0] for p in pts]
            e = [p[1] for p in pts]
            out.append({"scene": scene, "u_space": u, "multiplier": m, "quantity": q,
                        "delta": delta, "levels": [p[2] for p in pts], "h": h, "errors": e,
                        "rates": rates.successive_rates(h, e), "converges": rates.converges(h, e),
                        "paper_rate": PAPER_RATE.get(m) if q in PAPER_NORMS else None})
    return out


# ---------------------------------------------------------------- δ -> 0 (Theorem 2.1)
def compute_delta_limit(scene, cases, fields):
    out = []
    if fields is None:
        return out
    groups = defaultdict(list)
    for c in cases:
        if fields.has_case(c.get("fields_grid")):
            groups[(int(c["level"]), c["u_space"], c["multiplier"])].append(c)
    for (lvl, u, m), cs in sorted(groups.items()):
        if len(cs) < 2:
            continue
        cs.sort(key=lambda c: float(c["delta"]))
        base = fields.case(cs[0]["fields_grid"])
        d0 = float(cs[0]["delta"])
        others = [(float(c["delta"]), fields.case(c["fields_grid"])) for c in cs[1:]]
        specs = [
            ("u_l2", "u", lambda f, g: norms.p1_l2_diff(f["points"], f["tris"], f["u"], g["u"]),
             lambda f: norms.p1_l2_norm(f["points"], f["tris"], f["u"])),
            ("p_l2", "p", lambda f, g: norms.p1_l2_diff(f["points"], f["tris"], f["p"], g["p"]),
             lambda f: norms.p1_l2_norm(f["points"], f["tris"], f["p"])),
            ("lambda_l2", "lam",
             lambda f, g: norms.crack_l2_diff(f["crack_points"], f["lam"], g["lam"]),
             lambda f: norms.crack_l2_norm(f["crack_points"], f["lam"])),
        ]
        for q, name, diff, nrm in specs:
            if base[name] is None or any(g[name] is None for _, g in others):
                continue
            ds = [d for d, _ in others]
            diffs = [diff(g, base) for _, g in others]
            scale = nrm(base)
            floor = ROUNDOFF_REL * max(scale, 1e-300)
            fit_d = [d for d, e in zip(ds, diffs) if e > floor]
            fit_e = [e for e in diffs if e > floor]
            out.append({"scene": scene, "u_space": u, "multiplier": m, "level": lvl,
                        "quantity": q, "delta_ref": d0, "deltas": ds, "diffs": diffs,
                        "norm_ref": scale, "slope": rates.fit_slope(fit_d, fit_e),
                        "points_fitted": len(fit_d)})
    return out


# ---------------------------------------------------------------- references
def compute_agreement(scene, cases, fields, refs):
    out = []
    if not refs:
        return out
    tools = sorted(refs)
    # reference vs reference: max vertex difference per level
    if len(tools) >= 2:
        a, b = refs[tools[0]], refs[tools[1]]
        for lvl in sorted(set(a["u"]) & set(b["u"])):
            ua, ub = a["u"][lvl], b["u"][lvl]
            row = {"scene": scene, "kind": "reference_vs_reference", "a": tools[0],
                   "b": tools[1], "level": lvl}
            if ua.shape != ub.shape:
                row.update(max_vertex_diff=None, note=f"sizes differ {ua.shape} vs {ub.shape}")
            else:
                row.update(max_vertex_diff=float(np.abs(ua - ub).max()) if ua.size else 0.0,
                           note="")
            out.append(row)
    if fields is None:
        for tool in tools:
            out.append({"scene": scene, "kind": "solver_vs_reference", "reference": tool,
                        "e_u": None, "note": "no fields.h5: solver fields not written"})
        return out
    for tool in tools:
        out.extend(_solver_vs_reference(scene, cases, fields, refs[tool], tool))
    return out


def _solver_vs_reference(scene, cases, fields, ref, tool):
    """e_u, e_p (P1 part of p), e_λ of every solver case against the reference of the same level
    and against the reference's finest level (nested meshes: the coarse field is evaluated exactly
    at the fine triangles' corners), all exact on shared (sub)triangles."""
    out = []
    meshes = ref.get("mesh") or {}
    if not meshes:
        return [{"scene": scene, "kind": "solver_vs_reference", "reference": tool, "e_u": None,
                 "note": "mesh export not found next to the reference results"}]
    finest = max(meshes)
    fpts, ftris, fcrack = meshes[finest]
    uf = ref["u"][finest]
    grad_f = norms.p1_gradients(fpts, ftris, uf)
    for c in sorted((c for c in cases if fields.has_case(c.get("fields_grid"))), key=case_key):
        lvl = int(c["level"])
        f = fields.case(c["fields_grid"])
        if f["u"] is None or lvl not in meshes or lvl not in ref["u"]:
            continue
        pts, tris, crack = meshes[lvl]
        uref = ref["u"][lvl]
        row = {"scene": scene, "kind": "solver_vs_reference", "reference": tool, "level": lvl,
               "u_space": c["u_space"], "multiplier": c["multiplier"], "delta": float(c["delta"]),
               "finest_level": finest, "note": ""}
        try:
            if c["u_space"] == "broken" and f["points"].shape[0] == pts.shape[0]:
                row["e_u"] = norms.p1_l2_diff(pts, tris, f["u"], uref)
            else:
                row["e_u"] = norms.p1_l2_diff_two_meshes(f["points"], f["tris"], f["u"], pts, tris, uref)
            p = None if f.get("p") is None else np.asarray(f["p"])[:, :2]
            grad = norms.p1_gradients(pts, tris, uref)
            row["e_p"] = None if p is None else norms.p1_vs_piecewise_constant_l2(f["points"], f["tris"], p, grad)
            jump = uref[crack[:, 0]] - uref[crack[:, 1]]
            row["e_lambda"] = (None if f.get("lam") is None
                               else norms.crack_diff_vs_p1(pts[crack[:, 0]], f["lam"], jump))
            row["e_u_finest"] = norms.prolonged_l2_diff(f["points"], f["tris"], f["u"], fpts, ftris, uf)
            if p is not None:
                pf = norms.prolong_to_fine(f["points"], f["tris"], p, fpts, ftris)
                area = norms.triangle_areas(fpts, ftris)
                row["e_p_finest"] = float(np.sqrt(norms._local_sq(area, pf - grad_f[:, None, :])))
        except norms.NormError as exc:
            row.setdefault("e_u", None)
            row["note"] = str(exc)
        out.append(row)
    return out


def reference_rows(scene, refs):
    rows = []
    for tool, r in sorted(refs.items()):
        for c in r["summary"].get("cases", []):
            rows.append({"scene": scene, "tool": tool, "level": int(c["level"]),
                         "h": c.get("h"), "unknowns": c.get("unknowns"),
                         "iterations": c.get("iterations"), "kkt": c.get("kkt"),
                         "total_s": (c.get("timings_s") or {}).get("total"),
                         "errors": c.get("errors")})
    return rows


# ---------------------------------------------------------------- GCI
def compute_gci(scene, cases, fields, has_exact):
    out = []
    if fields is None or not cases:
        return out
    delta = ref_delta(cases)
    for (u, m), cs in series_by_variant(cases, delta).items():
        cs = [c for c in cs if fields.has_case(c.get("fields_grid"))]
        if len(cs) < 3:
            continue
        h, unorm, lint = [], [], []
        for c in cs:
            f = fields.case(c["fields_grid"])
            h.append(float(c["h"]))
            unorm.append(norms.p1_l2_norm(f["points"], f["tris"], f["u"]) if f["u"] is not None
                         else None)
            lint.append(norms.crack_integral(f["crack_points"], f["lam"])
                        if f["lam"] is not None and f["crack_points"] is not None else None)
        for name, vals in (("u_h_l2_norm", unorm), ("lambda_h_integral", lint)):
            if any(v is None for v in vals):
                continue
            g = rates.gci(h, vals)
            if g is None:
                continue
            g.update(scene=scene, u_space=u, multiplier=m, delta=delta, output=name,
                     levels=[int(c["level"]) for c in cs][-3:], scene_has_exact=has_exact)
            out.append(g)
    return out


# ---------------------------------------------------------------- KKT, timings
def kkt_rows(scene, cases):
    rows = []
    for c in cases:
        k = c.get("kkt") or {}
        rows.append({"scene": scene, "level": int(c["level"]), "u_space": c["u_space"],
                     "multiplier": c["multiplier"], "delta": float(c["delta"]),
                     "converged": bool(c.get("converged", False)), "status": c.get("status"),
                     "iterations": c.get("iterations"), "kkt": k,
                     "kkt_max": max([float(v) for v in k.values() if v is not None], default=None),
                     "active_multipliers": c.get("active_multipliers"),
                     "multipliers": c.get("multipliers"),
                     "regularized_pivots": c.get("regularized_pivots"),
                     "condition_estimate": c.get("condition_estimate")})
    rows.sort(key=lambda r: (r["converged"], r["level"], r["u_space"], r["multiplier"],
                             -r["delta"]))
    return rows


def timing_rows(scene, cases):
    rows = []
    for c in sorted(cases, key=case_key):
        e = c.get("errors") if isinstance(c.get("errors"), dict) else {}
        rows.append({"scene": scene, "level": int(c["level"]), "u_space": c["u_space"],
                     "multiplier": c["multiplier"], "delta": float(c["delta"]),
                     "unknowns": c.get("unknowns"), "total_s": total_time(c),
                     "timings_s": c.get("timings_s"), "u_l2": e.get("u_l2")})
    return rows


# ---------------------------------------------------------------- expectations
def load_expectations(path):
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    exps = data.get("expectation", [])
    if not isinstance(exps, list):
        raise ValueError("'expectation' must be an array of tables ([[expectation]])")
    allowed = {"scene", "u_space", "multiplier", "quantity", "converges", "min_rate",
               "max_error", "finest_level", "note"}
    for i, e in enumerate(exps):
        bad = set(e) - allowed
        if bad:
            raise ValueError(f"expectation {i}: unknown keys {sorted(bad)}; allowed {sorted(allowed)}")
        for k in ("scene", "u_space", "quantity"):
            if k not in e:
                raise ValueError(f"expectation {i}: missing '{k}'")
    return exps


def _match(pattern, value):
    return pattern in (None, "*") or pattern == value


def _check_agreement(e, agreement):
    """quantity = "reference_agreement": every level's max |u_dolfinx − u_freefem| <= max_error."""
    rows = [a for a in agreement if a["kind"] == "reference_vs_reference"]
    if not rows:
        return {**e, "variant": None, "status": "not_evaluated", "reason": "no two references in this run"}
    worst = max(rows, key=lambda a: -1.0 if a["max_vertex_diff"] is None else a["max_vertex_diff"])
    bad = [a for a in rows if a["max_vertex_diff"] is None or a["max_vertex_diff"] > e["max_error"]]
    reason = "; ".join(f"level {a['level']}: {a['max_vertex_diff']} > {e['max_error']:.1e}" for a in bad)
    return {**e, "variant": f"{worst['a']} vs {worst['b']}", "measured_error": worst["max_vertex_diff"],
            "status": "violated" if bad else "ok", "reason": reason}


def check_expectations(scene, rate_entries, exps, agreement=()):
    results = []
    for e in exps:
        if e["scene"] not in (scene, "*"):
            continue
        if e["quantity"] == "reference_agreement":
            results.append(_check_agreement(e, agreement))
            continue
        matched = [r for r in rate_entries if _match(e.get("u_space"), r["u_space"])
                   and _match(e.get("multiplier"), r["multiplier"])
                   and _match(e.get("quantity"), r["quantity"])]
        if not matched:
            results.append({**e, "variant": None, "status": "not_evaluated",
                            "reason": "no matching variant/quantity in this run"})
            continue
        for r in matched:
            res = {**e, "multiplier": r["multiplier"], "u_space": r["u_space"],
                   "quantity": r["quantity"], "variant": f"{r['u_space']}/{r['multiplier']}"}
            finest = r["levels"][-1]
            if "finest_level" in e and (finest != e["finest_level"] or len(r["levels"]) < 3):
                res.update(status="not_evaluated",
                           reason=f"run has levels {r['levels']}, expectation needs finest level "
                                  f"{e['finest_level']} and >= 3 levels")
                results.append(res)
                continue
            problems = []
            last_rate = r["rates"][-1] if r["rates"] else None
            if "converges" in e and r["converges"] is not None and \
                    bool(r["converges"]) != bool(e["converges"]):
                problems.append(f"converges = {r['converges']}, expected {e['converges']}")
            if "min_rate" in e and last_rate is not None and last_rate < e["min_rate"]:
                problems.append(f"rate {last_rate:.3f} < {e['min_rate']}")
            if "max_error" in e and r["errors"][-1] > e["max_error"]:
                problems.append(f"error {r['errors'][-1]:.3e} > {e['max_error']:.3e}")
            res.update(measured_converges=r["converges"], measured_rate=last_rate,
                       measured_error=r["errors"][-1],
                       status="violated" if problems else "ok", reason="; ".join(problems))
            results.append(res)
    return results


# ---------------------------------------------------------------- baseline
def _rel(a, b):
    if a == b:
        return 0.0
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def compare_baseline(scene, cases, rate_entries, base_cases, base_rates):
    flags = []
    old = {case_key(c): c for c in base_cases}
    for c in cases:
        k = case_key(c)
        o = old.get(k)
        if o is None:
            continue
        ce = c.get("errors") or {}
        oe = o.get("errors") or {}
        for q in QUANTITIES:
            if ce.get(q) is None or oe.get(q) is None:
                continue
            rd = _rel(float(ce[q]), float(oe[q]))
            if rd > BASELINE_ERROR_RTOL:
                flags.append({"scene": scene, "kind": "error", "case": list(k), "quantity": q,
                              "old": oe[q], "new": ce[q], "rel_change": rd})
        tn, to = total_time(c), total_time(o)
        if to >= BASELINE_TIME_MIN_S and tn > (1 + BASELINE_TIME_GROWTH) * to:
            flags.append({"scene": scene, "kind": "timing", "case": list(k), "old": to,
                          "new": tn, "rel_change": tn / to - 1})
    oldr = {(r["u_space"], r["multiplier"], r["quantity"]): r for r in base_rates}
    for r in rate_entries:
        o = oldr.get((r["u_space"], r["multiplier"], r["quantity"]))
        if o is None:
            continue
        for lv, rn, ro in zip(r["levels"][1:], r["rates"], o["rates"]):
            if rn is None or ro is None:
                continue
            if abs(rn - ro) > BASELINE_RATE_ATOL:
                flags.append({"scene": scene, "kind": "rate", "variant": f"{r['u_space']}/"
                              f"{r['multiplier']}", "quantity": r["quantity"], "level": lv,
                              "old": ro, "new": rn, "abs_change": abs(rn - ro)})
        if o["converges"] != r["converges"]:
            flags.append({"scene": scene, "kind": "converges", "variant": f"{r['u_space']}/"
                          f"{r['multiplier']}", "quantity": r["quantity"],
                          "old": o["converges"], "new": r["converges"]})
    return flags


def decide(kkt, expectation_results):
    reasons = []
    bad = [r for r in kkt if not r["converged"]]
    if bad:
        reasons.append(f"{len(bad)} case(s) did not converge (KKT)")
    viol = [e for e in expectation_results if e["status"] == "violated"]
    if viol:
        reasons.append(f"{len(viol)} expectation(s) violated")
    return ("FAIL" if reasons else "PASS"), reasons


def clean(obj):
    """JSON-safe: NaN/inf -> None, numpy -> python."""
    if isinstance(obj, dict):
        return {str(k): clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [clean(v) for v in obj]
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj
