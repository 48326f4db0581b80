"""All computed checks (rates, δ-limit, references, GCI, KKT, timings), expectations, baseline,
and the verdict."""
import math
import os
import tomllib
from collections import defaultdict

import numpy as np

from . import norms, rates, theory
from .baseline import error_change, rate_change
from .read import finite_number, total_time
from .cases import (DEFAULT_P_MASS, DEFAULT_P_SPACE, P_MASSES, P_SPACES, case_key, case_order,
                    p_mass, p_space, variant_label, variant_of, variant_order)
from .settings import QUANTITIES, expected_failure  # p_x: the paper's mesh-dependent X-norm

# Theorem 4.3 bounds ‖u−u_h‖ + ‖p−p_h‖_X + ‖λ−λ_h‖ together: its rate applies to each of them.
PAPER_NORMS = ("u_l2", "p_x", "lambda_l2")
PAPER_RATE = {"M0": 0.5, "M1": 0.5, "M1star": 0.75}
BASELINE_TIME_GROWTH = 0.30
BASELINE_TIME_MIN_S = 0.01
ROUNDOFF_REL = 1e-12


def _variants(cases):
    """(u space, multiplier, p mass, p space) of the cases."""
    return sorted({variant_of(c) for c in cases}, key=variant_order)


def ref_delta(cases):
    """δ used for the h -> 0 study: 0 if present, else the smallest."""
    ds = {float(c["delta"]) for c in cases}
    return 0.0 if 0.0 in ds else min(ds)


def series_by_variant(cases, delta):
    """{(u space, multiplier, p mass, p space): the cases of δ = delta, coarse to fine}."""
    out = {}
    for v in _variants(cases):
        cs = sorted((c for c in cases if variant_of(c) == v and float(c["delta"]) == delta),
                    key=lambda c: int(c["level"]))
        if cs:
            out[v] = cs
    return out


# ---------------------------------------------------------------- h -> 0 (Theorem 4.3)
# Against the reference the quantities are the same norms with the reference in place of the exact
# solution: ‖u_h − u_ref‖, ‖p_h − ∇u_ref‖ (p_h with its bubble), ‖λ_h − [u_ref]‖ (compute_agreement).
REFERENCE_QUANTITIES = {"u_l2": "e_u", "p_l2": "e_p", "lambda_l2": "e_lambda"}
PREFERRED_REFERENCE = ("dolfinx", "freefem")
# Series statuses that fail the run; "inconclusive" (cannot judge yet) makes the verdict
# INCONCLUSIVE instead, unless the scene is a smoke run, which only checks that everything runs.
FAILING = ("does not converge", "unexpected pass", "incomplete")
UNDECIDED = "inconclusive"
# The three verdicts, and compare/sdcompare's exit code for each (2: the input could not be read).
VERDICTS = {"PASS": 0, "FAIL": 1, "INCONCLUSIVE": 3}


def mesh_parameter(case, graded=False):
    """The mesh parameter rates are measured in: the case's h (largest triangle diameter), or on
    graded meshes N^{-1/2}, N its unknowns (a graded level's largest triangle says nothing of its
    refinement near the tips; ~4× unknowns per level is a halving of N^{-1/2})."""
    if graded and finite_number(case.get("unknowns")) and case["unknowns"] > 0:
        return float(case["unknowns"]) ** -0.5
    return float(case["h"])


def _measured_series(cases, agreement, has_exact, graded=False):
    """{(u, m, p mass, p space, q): (against, reference, [(level, h, error or None)])} at
    δ = ref_delta; h is mesh_parameter's."""
    delta = ref_delta(cases)
    out = {}
    if has_exact:
        for v, cs in series_by_variant(cases, delta).items():
            for q in QUANTITIES:
                out[v + (q,)] = ("exact", None, [
                    (int(c["level"]), mesh_parameter(c, graded),
                     (c.get("errors") or {}).get(q) if isinstance(c.get("errors"), dict) else None)
                    for c in cs])
        return delta, out
    rows = [r for r in agreement if r["kind"] == "solver_vs_reference" and "level" in r]
    tools = [t for t in PREFERRED_REFERENCE if any(r["reference"] == t for r in rows)]
    for v, cs in series_by_variant(cases, delta).items():
        h_of = {int(c["level"]): mesh_parameter(c, graded) for c in cs}
        for q, key in REFERENCE_QUANTITIES.items():
            if not tools:
                out[v + (q,)] = (None, None, [(int(c["level"]), h_of[int(c["level"])], None)
                                              for c in cs])
                continue
            tool = tools[0]
            by_level = {r["level"]: r.get(key) for r in rows if r["reference"] == tool
                        and variant_of(r) == v and r["delta"] == delta}
            out[v + (q,)] = ("reference", tool, [(int(c["level"]), h_of[int(c["level"])],
                                                  by_level.get(int(c["level"]))) for c in cs])
    return delta, out


def expected_order(settings, u, m, pm, q, s, closed=False, ps=DEFAULT_P_SPACE):
    """(expected order, its reason) of one series: the scene's declaration, else theory.py's."""
    declared = theory.declared_rate(settings.get("expected_rates", []), u, m, pm, q, ps)
    return declared if declared is not None else theory.expected_rate(q, m, pm, s, closed, ps)


def compute_series(scene, cases, agreement, has_exact, settings, s=theory.SINGULAR_S,
                   s_reason="", unstored=(), crack_closed=False, graded=False):
    """One entry per (u space, multiplier, p mass, p space, quantity): the errors against the exact
    solution (scenes with [exact]) or against the reference of the same level, their rates, the
    expected order (theory.py, for the regularity index s of the solution and the p space), the
    measured status (rates.series_status against expected − theory.RATE_MARGIN) and the status
    after the scene's expected failures (which apply to every p mass and p space). Rates are per
    halving of h, or of N^{-1/2} on `graded` meshes (mesh_parameter). A quantity in `unstored` (its field neither
    asked for nor kept for verification: a folder written before verification.h5) whose errors
    are missing is "not judged", not incomplete."""
    out = []
    if not cases:
        return out
    delta, measured = _measured_series(cases, agreement, has_exact, graded)
    order = {q: i for i, q in enumerate(QUANTITIES)}
    for (u, m, pm, ps, q), (against, tool, pts) in sorted(
            measured.items(), key=lambda kv: (variant_order(kv[0][:4]), order[kv[0][4]])):
        levels = [p[0] for p in pts]
        h = [p[1] for p in pts]
        e = [p[2] for p in pts]
        bad = [lv for lv, v in zip(levels, e) if not finite_number(v)]
        if against is None:
            status, reason = "inconclusive", ("no exact solution and no reference with solver "
                                              "fields to measure against")
        elif bad and q in unstored:
            status, reason = "not judged", ("not requested: the scene's [outputs] fields do not "
                                            "store it, and the folder has no verification.h5")
        elif bad:
            status, reason = "incomplete", (f"error against the {against} missing, null or NaN at "
                                            f"level(s) {bad}")
        expected, why = expected_order(settings, u, m, pm, q, s, crack_closed, ps)
        floor = theory.threshold(expected, settings["min_rate"] if settings.get(
            "min_rate_declared") else None)
        run_up_to = None
        if against is not None and not bad:
            status, reason, run_up_to = rates.series_judgement(h, e, levels, floor)
        measured_status = status
        xfail = expected_failure(settings, u, m, q)
        if xfail is not None and status == "converges":
            status, reason = "unexpected pass", (f"declared an expected failure ({xfail}) but it "
                                                 f"converges: {reason}")
        elif xfail is not None and status == "does not converge":
            status, reason = "expected failure", f"declared in the scene; measured: {reason}"
        elif xfail is not None and status == UNDECIDED and against is not None:
            # a declared failure is checked for an unexpected pass; a series that cannot be
            # judged yet has not passed
            status, reason = "expected failure", (f"declared in the scene; measured: cannot "
                                                  f"judge yet ({reason})")
        ok_e = [v if finite_number(v) else None for v in e]
        out.append({"scene": scene, "u_space": u, "multiplier": m, "p_mass": pm, "p_space": ps,
                    "quantity": q, "against": against, "reference": tool, "delta": delta,
                    "levels": levels,
                    "h": h, "errors": ok_e,
                    "rates": rates.successive_rates(h, ok_e) if not bad else [None] * (len(e) - 1),
                    "measured_status": measured_status, "status": status, "reason": reason,
                    "expected_failure": xfail,
                    "finest_error": ok_e[-1] if ok_e else None,
                    "paper_rate": PAPER_RATE.get(m) if q in PAPER_NORMS else None,
                    "expected_rate": expected, "expected_rate_reason": why,
                    "rate_threshold": floor, "regularity": s, "regularity_reason": s_reason,
                    "run_levels_up_to": run_up_to if status == UNDECIDED else None,
                    "mesh_parameter": "N^-1/2" if graded else "h"})
    return out


def series_fails(s, settings):
    return s["status"] in FAILING


def series_undecided(s, settings):
    """A series that cannot be judged yet (too few levels, a rate still approaching its order, no
    exact solution and no reference): the verdict cannot be PASS, and is not FAIL for it."""
    return s["status"] == UNDECIDED and not settings["smoke"]


# ---------------------------------------------------------------- δ -> 0 (Theorem 2.1)
def compute_delta_limit(scene, cases, fields):
    out = []
    if fields is None:
        return out
    groups = defaultdict(list)
    for c in cases:
        if fields.has_case(c.get("fields_grid")):
            groups[(int(c["level"]),) + variant_of(c)].append(c)
    for (lvl, u, m, pm, ps), cs in sorted(groups.items(),
                                          key=lambda kv: (kv[0][0], variant_order(kv[0][1:]))):
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
             lambda f, g: norms.crack_l2_diff(f["crack_points"], f["lam"], g["lam"], f["crack_segments"]),
             lambda f: norms.crack_l2_norm(f["crack_points"], f["lam"], f["crack_segments"])),
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
            line = rates.fit_line(fit_d, fit_e)
            resid = dict(zip(fit_d, line[2])) if line else {}
            out.append({"scene": scene, "u_space": u, "multiplier": m, "p_mass": pm, "p_space": ps,
                        "level": lvl, "quantity": q, "delta_ref": d0, "deltas": ds, "diffs": diffs,
                        "norm_ref": scale, "slope": line[0] if line else None,
                        "points_fitted": len(fit_d),
                        "residuals": [resid.get(d) for d in ds],
                        "max_residual": max((abs(r) for r in resid.values() if r is not None),
                                            default=None)})
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


def _check_same_cracks(f, nodes, segments):
    """NormError unless the solver case's crack points are the export's crack nodes (crack.txt's
    order) and its crack segments, when stored, the export's: λ_h is indexed by them."""
    cp = f.get("crack_points")
    if cp is None or cp.shape[0] != nodes.shape[0] or \
            np.abs(cp[:, :2] - nodes).max() > 1e-9 * max(1.0, float(np.abs(nodes).max())):
        raise norms.NormError("the solver's crack points are not the mesh export's crack nodes")
    if f.get("crack_segments") is not None and not np.array_equal(f["crack_segments"], segments):
        raise norms.NormError("the solver's crack segments are not the mesh export's (cracks.txt)")


def _solver_vs_reference(scene, cases, fields, ref, tool):
    """e_u, e_p (p with its bubble; the lumped p has none), e_λ of every solver case against the
    reference of the same level, and e_u, e_p (P1 part of p) against the reference's finest level (nested meshes: the
    coarse field is evaluated exactly at the fine triangles' corners, the fine triangles located in
    the coarse ones by the export's mesh kind), all exact on shared (sub)triangles. The distances
    to the finest level, the costliest (each on the finest mesh), are computed for the cases of
    δ = ref_delta only: the series, the yardsticks and the report's table read them there and
    nowhere else (they were once computed for every δ)."""
    out = []
    meshes = ref.get("mesh") or {}
    if not meshes:
        return [{"scene": scene, "kind": "solver_vs_reference", "reference": tool, "e_u": None,
                 "note": "mesh export not found next to the reference results"}]
    finest = max(meshes)
    fpts, ftris = meshes[finest].points, meshes[finest].tris
    uf = ref["u"][finest]
    grad_f = norms.p1_gradients(fpts, ftris, uf)
    area_f = norms.triangle_areas(fpts, ftris)
    delta_finest = ref_delta(cases)
    for c in sorted((c for c in cases if fields.has_case(c.get("fields_grid"))), key=case_order):
        lvl = int(c["level"])
        f = fields.case(c["fields_grid"])
        if f["u"] is None or lvl not in meshes or lvl not in ref["u"]:
            continue
        m = meshes[lvl]
        pts, tris, crack = m.points, m.tris, m.crack
        uref = ref["u"][lvl]
        row = {"scene": scene, "kind": "solver_vs_reference", "reference": tool, "level": lvl,
               "u_space": c["u_space"], "multiplier": c["multiplier"], "p_mass": p_mass(c),
               "p_space": p_space(c), "delta": float(c["delta"]), "finest_level": finest,
               "note": ""}
        try:
            if c["u_space"] == "broken" and f["points"].shape[0] == pts.shape[0]:
                row["e_u"] = norms.p1_l2_diff(pts, tris, f["u"], uref)
            else:
                row["e_u"] = norms.p1_l2_diff_two_meshes(f["points"], f["tris"], f["u"], pts, tris, uref)
            p = None if f.get("p") is None else np.asarray(f["p"])[:, :2]
            grad = norms.p1_gradients(pts, tris, uref)
            if p is None:
                row["e_p"] = None
            elif row["p_mass"] == "lumped":  # P1 without bubble
                row["e_p"] = norms.p1_vs_piecewise_constant_l2(f["points"], f["tris"], p, grad)
            elif f.get("p_bubble") is not None:
                row["e_p"] = norms.mini_vs_piecewise_constant_l2(f["points"], f["tris"], p,
                                                                 f["p_bubble"], grad)
            else:
                row["e_p"] = None
                row["note"] = "no p_bubble in fields.h5: e_p (MINI p) not computed"
            jump = uref[crack[:, 0]] - uref[crack[:, 1]]
            if f.get("lam") is None:
                row["e_lambda"] = None
            else:
                _check_same_cracks(f, pts[crack[:, 0]], m.segments())
                row["e_lambda"] = norms.crack_diff_vs_p1(pts[crack[:, 0]], f["lam"], jump, m.segments())
            if float(c["delta"]) == delta_finest:
                nesting = norms.nesting(meshes, lvl, finest)
                row["e_u_finest"] = norms.prolonged_l2_diff(f["points"], f["tris"], f["u"], fpts,
                                                            ftris, uf, *nesting)
                if p is not None:
                    pf = norms.prolong_to_fine(f["points"], f["tris"], p, fpts, ftris, *nesting)
                    row["e_p_finest"] = float(np.sqrt(norms._local_sq(area_f,
                                                                      pf - grad_f[:, None, :])))
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
                         "startup_s": startup_time(c.get("timings_s") or {}),
                         "errors": c.get("errors")})
    return rows


def startup_time(timings):
    """Seconds of a reference's level that are start-up, not work on the level: dolfinx's form
    compilation (`forms`: FFCx JIT, cached between processes, so it comes and goes from one run
    to the next); 0 for a tool that reports none."""
    v = timings.get("forms")
    return float(v) if isinstance(v, (int, float)) and v >= 0 else 0.0


# ---------------------------------------------------------------- GCI
def compute_gci(scene, cases, fields, has_exact):
    out = []
    if fields is None or not cases:
        return out
    delta = ref_delta(cases)
    for (u, m, pm, ps), cs in series_by_variant(cases, delta).items():
        cs = [c for c in cs if fields.has_case(c.get("fields_grid"))]
        hs = [float(c["h"]) for c in cs]
        if len(cs) < 3 or any(not b < a for a, b in zip(hs, hs[1:])):
            continue  # (a level listed twice, e.g. a case without its p mass: completeness fails)
        h, unorm, lint = [], [], []
        for c in cs:
            f = fields.case(c["fields_grid"])
            h.append(float(c["h"]))
            unorm.append(norms.p1_l2_norm(f["points"], f["tris"], f["u"]) if f["u"] is not None
                         else None)
            lint.append(norms.crack_integral(f["crack_points"], f["lam"], f["crack_segments"])
                        if f["lam"] is not None and f["crack_points"] is not None else None)
        for name, vals in (("u_h_l2_norm", unorm), ("lambda_h_integral", lint)):
            if any(v is None for v in vals):
                continue
            g = rates.gci(h, vals)
            if g is None:
                continue
            g.update(scene=scene, u_space=u, multiplier=m, p_mass=pm, p_space=ps, delta=delta,
                     output=name,
                     levels=[int(c["level"]) for c in cs][-3:], scene_has_exact=has_exact)
            out.append(g)
    return out


# ---------------------------------------------------------------- KKT, timings
def kkt_rows(scene, cases):
    rows = []
    for c in cases:
        k = c.get("kkt") or {}
        rows.append({"scene": scene, "level": int(c["level"]), "u_space": c["u_space"],
                     "multiplier": c["multiplier"], "p_mass": p_mass(c), "p_space": p_space(c),
                     "delta": float(c["delta"]), "converged": c.get("converged") is True,
                     "status": c.get("status"),
                     "iterations": c.get("iterations"), "kkt": k,
                     "kkt_max": max([float(v) for v in k.values() if v is not None], default=None),
                     "active_multipliers": c.get("active_multipliers"),
                     "multipliers": c.get("multipliers"),
                     "regularized_pivots": c.get("regularized_pivots"),
                     "condition_estimate": c.get("condition_estimate"),
                     # the δ' whose ‖K⁻¹‖₁ estimate κ₁ uses (δ itself in older summaries)
                     "condition_estimate_delta": c.get("condition_estimate_delta", c["delta"])})
    rows.sort(key=lambda r: (r["converged"], r["level"], variant_order(variant_of(r)),
                             -r["delta"]))
    return rows


def timing_rows(scene, cases):
    rows = []
    for c in sorted(cases, key=case_order):
        e = c.get("errors") if isinstance(c.get("errors"), dict) else {}
        rows.append({"scene": scene, "level": int(c["level"]), "u_space": c["u_space"],
                     "multiplier": c["multiplier"], "p_mass": p_mass(c), "p_space": p_space(c),
                     "delta": float(c["delta"]), "unknowns": c.get("unknowns"),
                     "total_s": total_time(c),
                     "timings_s": c.get("timings_s"), "u_l2": e.get("u_l2")})
    return rows


# ---------------------------------------------------------------- expectations
# An expectation of scenes/expectations.toml bounds one series at one level of one scene:
# max_error (the error at `level`) and min_rate (the rate from level − 1 to `level`). Every name in
# it must exist: the scene among the scene files beside the expectations file (or the judged
# scene), the u space, multiplier, p mass, p space and level among those the judged scene's file
# lists, the quantity among QUANTITIES; otherwise exit 2. `p_mass` and `p_space` are optional:
# without them the expectation bounds the consistent p mass and the continuous p ("*": all). Known
# failures are declared in the scene file ([[verification.expected_failure]]), not here.
EXPECTATION_KEYS = {"scene", "u_space", "multiplier", "p_mass", "p_space", "quantity", "level",
                    "min_rate", "max_error", "note"}
# The value of an optional key of an expectation that does not give it.
EXPECTATION_DEFAULTS = {"p_mass": DEFAULT_P_MASS, "p_space": DEFAULT_P_SPACE}
MOVED_KEYS = {
    "converges": "declare a known failure in the scene file's [[verification.expected_failure]] "
                 "(every series is expected to converge)",
    "finest_level": "use `level = L`: the bounds apply to the error at level L and the rate from "
                    "L − 1 to L",
}


def _scene_names_beside(path):
    import glob

    names = set()
    for f in glob.glob(os.path.join(os.path.dirname(os.path.abspath(path)), "*.toml")):
        try:
            with open(f, "rb") as fh:
                name = tomllib.load(fh).get("name")
        except (OSError, ValueError):
            continue
        if isinstance(name, str):
            names.add(name)
    return names


EXPECTATIONS_NAME = "expectations.toml"


def default_expectations(script_dir):
    """The expectations file sdcompare judges with when none is given: scenes/expectations.toml of
    the checkout the script `script_dir` belongs to, else the copy installed with the package (pip:
    `sdcompare_scenes`, the repository's scenes/ with their expectations); None when neither
    exists (the caller refuses to judge: an sdcompare without its expectations judges less)."""
    here = os.path.join(script_dir, "..", "scenes", EXPECTATIONS_NAME)
    if os.path.isfile(here):
        return os.path.normpath(here)
    return theory.packaged_scenes_file(EXPECTATIONS_NAME)


def load_expectations(path):
    """The [[expectation]] tables of `path`, keys checked (ValueError names the bad one)."""
    with open(path, "rb") as fh:
        data = tomllib.load(fh)
    exps = data.get("expectation", [])
    if not isinstance(exps, list) or set(data) - {"expectation", "ratio"}:
        raise ValueError("only [[expectation]] and [[ratio]] tables are allowed (ratios.py reads "
                         "the [[ratio]] rows)")
    for i, e in enumerate(exps):
        for k in set(e) & set(MOVED_KEYS):
            raise ValueError(f"expectation {i}: key '{k}' is no longer used: {MOVED_KEYS[k]}")
        bad = set(e) - EXPECTATION_KEYS
        if bad:
            raise ValueError(f"expectation {i}: unknown keys {sorted(bad)}; allowed "
                             f"{sorted(EXPECTATION_KEYS)}")
        for k in ("scene", "u_space", "multiplier", "quantity", "level"):
            if k not in e:
                raise ValueError(f"expectation {i}: missing '{k}'")
        if not ("min_rate" in e or "max_error" in e):
            raise ValueError(f"expectation {i}: it bounds nothing (give min_rate and/or max_error)")
        if e["quantity"] not in QUANTITIES + ("*",):
            raise ValueError(f"expectation {i}: quantity {e['quantity']!r} is none of "
                             f"{', '.join(QUANTITIES)} or '*'")
    return exps


# The names an expectation may give per axis (the scene format's vocabularies): one the scene
# does not run is skipped, any other is a mistake.
EXPECTATION_NAMES = {"u_space": ("continuous", "broken"), "multiplier": theory.MULTIPLIERS,
                     "p_mass": P_MASSES, "p_space": P_SPACES}


def validate_expectations(exps, path, scene, scene_file, run_levels=None):
    """The expectations that apply to `scene`; a name that matches nothing, or a level that is no
    level at all (not an integer ≥ 0), is a ValueError. One whose level (or, for min_rate, the
    level before it) this run has not got (`run_levels`, the plan's; default: the scene file's)
    applies but is skipped: it carries `skipped`, the reason, and check_expectations reports it so
    (a campaign at --levels 0-1 is judged by the bounds of its levels, and says which it left)."""
    from .settings import scene_lists, scene_p_masses, scene_p_spaces

    known_scenes = _scene_names_beside(path) | {scene}
    levels, u_spaces, multipliers, _ = scene_lists(scene_file)
    run = sorted(int(lv) for lv in (levels if run_levels is None else run_levels))
    mine = []
    for i, e in enumerate(exps):
        if e["scene"] != "*" and e["scene"] not in known_scenes:
            raise ValueError(f"expectation {i} names scene {e['scene']!r}, which is neither this "
                             f"results folder's scene nor a scene file beside {path}")
        if e["scene"] not in ("*", scene):
            continue
        not_run = None
        for key, values in (("u_space", u_spaces), ("multiplier", multipliers),
                            ("p_mass", scene_p_masses(scene_file)),
                            ("p_space", scene_p_spaces(scene_file))):
            if key in EXPECTATION_DEFAULTS and key not in e:
                continue  # the default, also in a scene that does not run it: no match
            if e[key] != "*" and e[key] not in values:
                if e[key] not in EXPECTATION_NAMES[key]:
                    raise ValueError(f"expectation {i}: {key} {e[key]!r} is none of "
                                     f"{list(EXPECTATION_NAMES[key])}")
                # a variant this scene copy does not run (a campaign of a scene cut down to some
                # variants): skipped and said, as a level it has not got
                not_run = not_run or (f"this run has no {key} {e[key]} (its scene file lists "
                                      f"{', '.join(map(str, values))})")
        level = e["level"]
        if not isinstance(level, int) or isinstance(level, bool) or level < 0:
            raise ValueError(f"expectation {i}: level must be a level (an integer ≥ 0), not "
                             f"{level!r}")
        skipped = {"skipped": not_run} if not_run else _skipped_level(e, run)
        mine.append({**e, "index": i, **skipped})
    return mine


def _skipped_level(e, run):
    """{"skipped": why} when the run has not got the level(s) the expectation `e` bounds (its
    level; for min_rate also the level before it), else {}."""
    need = [e["level"]] + ([e["level"] - 1] if "min_rate" in e else [])
    missing = [lv for lv in need if lv not in run]
    if not missing:
        return {}
    missing = sorted(missing)
    what = (f"level {missing[0]}" if len(missing) == 1
            else f"levels {missing[0]} and {missing[1]}")
    return {"skipped": f"this run has no {what} (its levels: {', '.join(map(str, run)) or 'none'})"
            + (f": min_rate at level {e['level']} is the rate from level {e['level'] - 1}"
               if e["level"] in run else "")}


def check_expectations(series, exps):
    """Evaluates each applicable expectation on every series it matches: status "ok", "violated"
    or "not evaluated" (the level is missing from this run's results); the last two fail. One
    that validate_expectations marked `skipped` (a level this run has not got) is one row of
    status "skipped" with its reason, and fails nothing."""
    results = []
    for e in exps:
        if e.get("skipped"):  # its variant: the expectation's pattern ("*" every value)
            pattern = "/".join([e["u_space"], e["multiplier"]]
                               + [e[k] for k in ("p_mass", "p_space") if k in e])
            results.append({**e, "variant": pattern, "status": "skipped", "reason": e["skipped"]})
            continue
        matched = [s for s in series if _match(e["u_space"], s["u_space"])
                   and _match(e["multiplier"], s["multiplier"]) and _match(e["quantity"], s["quantity"])
                   and _match(e.get("p_mass", DEFAULT_P_MASS), p_mass(s))
                   and _match(e.get("p_space", DEFAULT_P_SPACE), p_space(s))]
        if not matched:
            results.append({**e, "variant": None, "status": "not evaluated",
                            "reason": "no series of this run matches it"})
        for s in matched:
            res = {**e, "u_space": s["u_space"], "multiplier": s["multiplier"], "p_mass": p_mass(s),
                   "p_space": p_space(s), "quantity": s["quantity"],
                   "variant": variant_label(*variant_of(s))}
            at = dict(zip(s["levels"], s["errors"]))
            err, prev = at.get(e["level"]), at.get(e["level"] - 1)
            problems, missing = [], []
            if err is None:
                missing.append(f"no error at level {e['level']}")
            elif "max_error" in e and not err <= e["max_error"]:
                problems.append(f"error {err:.3e} > {e['max_error']:.3e} at level {e['level']}")
            r = None
            if "min_rate" in e:
                if err is None or prev is None:
                    missing.append(f"no errors at levels {e['level'] - 1} and {e['level']}")
                else:
                    i = s["levels"].index(e["level"])
                    r = rates.rate(s["h"][i - 1], prev, s["h"][i], err)
                    if r is None or r < e["min_rate"]:
                        problems.append(f"rate {'not computable' if r is None else round(r, 3)} "
                                        f"< {e['min_rate']} "
                                        f"from level {e['level'] - 1} to {e['level']}")
            status = "not evaluated" if missing else ("violated" if problems else "ok")
            res.update(measured_error=err, measured_rate=r, status=status,
                       reason="; ".join(missing + problems))
            results.append(res)
    return results


def expectations_check(results):
    """The report's check row of the expectations: (label, requirement, problems, why it does not
    apply or None). A violated or not evaluated row is a problem; skipped rows (levels this run
    has not got) are counted and their reasons said; with nothing but skipped rows the check does
    not apply, and says why."""
    judged = [e for e in results if e["status"] != "skipped"]
    skipped = [e for e in results if e["status"] == "skipped"]
    problems = [f"{e['variant']} {e['quantity']} (expectation {e['index']}): {e['status']}: "
                f"{e['reason']}" for e in judged if e["status"] != "ok"]
    why = "; ".join(sorted({e["reason"] for e in skipped}))
    what = f"{len(judged)} expectation row(s) evaluated"
    if skipped:
        what += (f"; {len(skipped)} skipped (expectation"
                 f" {', '.join(str(e['index']) for e in skipped)}: {why})")
    na = None
    if skipped and not judged:
        na = f"every expectation of this scene is at a level this run has not got: {why}"
    return "expectations", what, problems, na


def _match(pattern, value):
    return pattern in (None, "*") or pattern == value


# ---------------------------------------------------------------- baseline
def _case_list(k):
    """A case key as written in a baseline flag: [level, u, m, δ], then the p mass when it or the p
    space is not the default, then the p space when it is not continuous."""
    order = list(k.order())  # [level, u, m, δ, p mass, p space]
    if k.p_space != DEFAULT_P_SPACE:
        return order
    return order[:4] if k.p_mass == DEFAULT_P_MASS else order[:5]


def compare_baseline(scene, cases, rate_entries, base_cases, base_rates):
    """Flags of a rerun against an earlier results folder of the same scene: error norms, rates
    and statuses of the series against the exact solution, and grown timings."""
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
            rd = error_change(float(oe[q]), float(ce[q]))
            if rd is not None:
                flags.append({"scene": scene, "kind": "error", "case": _case_list(k), "quantity": q,
                              "old": oe[q], "new": ce[q], "rel_change": rd})
        tn, to = total_time(c), total_time(o)
        if to >= BASELINE_TIME_MIN_S and tn > (1 + BASELINE_TIME_GROWTH) * to:
            flags.append({"scene": scene, "kind": "timing", "case": _case_list(k), "old": to,
                          "new": tn, "rel_change": tn / to - 1})
    def skey(r):
        return variant_of(r) + (r["quantity"],)

    oldr = {skey(r): r for r in base_rates}
    for r in rate_entries:
        o = oldr.get(skey(r))
        if o is None:
            continue
        label = variant_label(*variant_of(r))
        for lv, rn, ro in zip(r["levels"][1:], r["rates"], o["rates"]):
            if rn is None or ro is None:
                continue
            d = rate_change(ro, rn)
            if d is not None:
                flags.append({"scene": scene, "kind": "rate", "variant": label,
                              "quantity": r["quantity"], "level": lv,
                              "old": ro, "new": rn, "abs_change": d})
        # The baseline's series are computed without its reference comparisons (against None:
        # inconclusive), so only series measured against the exact solution compare statuses.
        if o["against"] == "exact" and o["status"] != r["status"]:
            flags.append({"scene": scene, "kind": "status", "variant": label,
                          "quantity": r["quantity"],
                          "old": o["status"], "new": r["status"]})
    return flags


def decide(groups, undecided=()):
    """FAIL iff some check has a problem; else INCONCLUSIVE iff some check cannot judge yet
    (undecided: [(label, [what cannot be judged, ...])]); else PASS. groups: [(label,
    [problem, ...])]; returns the verdict and the reasons, one line per problem (or, for
    INCONCLUSIVE, per undecided item) prefixed by its check's label."""
    reasons = [f"{label}: {p}" for label, problems in groups for p in problems]
    if reasons:
        return "FAIL", reasons
    pending = [f"{label}: {p}" for label, items in undecided for p in items]
    return ("INCONCLUSIVE" if pending else "PASS"), pending


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
