"""Checks of a results folder that are not convergence rates: is everything the scene asked for
there, are the values trustworthy (KKT residuals, reference statuses and agreement, δ-limit
slopes), and do the errors the solvers report equal an independent computation from their fields.

Each check returns rows (for the report) and problems (one line each); any problem fails the run.
"""
import math

import numpy as np

from . import exact, norms, precomputed
from .read import InputError, finite_number
from .cases import (CaseKey, case_key, case_order, p_mass, p_space, plan_p_masses, plan_p_spaces,
                    runs_together, variant_suffix)
from .render import case_text, fmt_delta
from .settings import QUANTITIES, scene_lists, scene_p_masses, scene_p_spaces

# The solver's errors against the compare tool's own (exact.py: another rule family, Duffy rules
# at the tips): two correct fixed-degree quadratures of a non-polynomial integrand differ
# by their quadrature errors, which no fixed tolerance bounds (up to 1e-4 relative where the exact
# solution's kinks cross the triangles). Each side estimates its own: the solver's
# summary.json gives, per error, |e(rule) - e(higher rule)| (`errors_quadrature`, crates/sdcrack-core/src/norms.rs,
# 4/3 the points per direction), this tool the same with its own rules (exact.py, 3/2 the points).
# A reported error r and this tool's o must then satisfy
#     |r - o| <= SAFETY (est_sdcrack + est_ours) + ROUNDOFF_RTOL max(|r|, |o|) + ERRORS_ATOL.
# SAFETY: a rule's error falls as n^-k (k >= 1 where the integrand is not smooth on a triangle, a
# bounded integrand; geometrically where it is smooth), so the difference of the two rules,
# e_n (1 - (n/n')^k), is at least e_n (1 - 3/4) for the solver's n'/n = 4/3 and e_n/3 for this
# tool's 3/2: 4 times the estimate bounds each rule's error.
SAFETY = 4.0
# Round-off: each error² is a sum of nonnegative terms, which float64 gives to (n - 1) eps relative
# summed in sequence; the solver sums chunks of 4096 triangles in sequence (crates/sdcrack-core/src/norms.rs), 4096 x
# 2.2e-16 = 9e-13, this tool pairwise (numpy). Measured where both estimates are round-off (smooth
# scenes, levels 2-4): <= 5e-13 relative.
ROUNDOFF_RTOL = 1e-12
# An estimate above this fraction of the error itself means that rule resolves fewer than three
# digits of it (a rule whose two degrees disagree that much is broken, or the integrand is not
# resolved on the mesh): the check FAILs naming whose quadrature, instead of widening its tolerance
# to 2 SAFETY ESTIMATE_CAP = 0.8 %, the widest it may be and still tell a 1 % slip (below the
# expectations' 10 % and the yardsticks' factors 2-3). Measured: <= 2.3e-4 relative (this tool's
# p_x on tests/data/scenes/open-smooth-inclined.toml, levels 0-4, kinks across the triangles;
# <= 8.6e-10 on the repository's exact scenes).
ESTIMATE_CAP = 1e-3
# A summary.json without errors_quadrature (an sdcrack older than its quadrature estimates): the former bare
# tolerance, 1e-8 relative (both quadratures were measured converged to < 1e-10 relative on the
# repository's scenes of that time: a factor 100).
SOLVER_ERRORS_RTOL = 1e-8
# The references' reported errors against each other and against exact.py (1e-6).
REFERENCE_ERRORS_RTOL = 1e-6
# Below this an error is zero to round-off (λ of a closed crack): compared absolutely.
ERRORS_ATOL = 1e-13


def _num(v, spec=".1e"):
    """A number in a problem line: formatted when finite, else what it is (never None/nan/inf)."""
    if finite_number(v):
        return format(v, spec)
    return "missing" if v is None else "missing or not finite" if isinstance(v, (int, float)) \
        else repr(v)


def _residuals(kkt):
    if not isinstance(kkt, dict):
        return "missing"
    return ", ".join(f"{k} {_num(v)}" for k, v in kkt.items()) or "none"


def _estimate_text(e, scale):
    """A quadrature estimate in a problem line: "round-off" below ROUNDOFF_RTOL of the error it
    estimates (its digits there are those of one numpy build's summation order, not of the rule:
    the pip-installed and the Debian tool printed 0.0e+00 and 2.8e-17 for the same case)."""
    if finite_number(e) and finite_number(scale) and abs(e) <= ROUNDOFF_RTOL * abs(scale):
        return "round-off"
    return _num(e)


def _rel(a, b):
    if not (finite_number(a) and finite_number(b)):
        return math.inf
    if max(abs(a), abs(b)) <= ERRORS_ATOL:
        return 0.0
    return abs(a - b) / max(abs(a), abs(b))


def _fields_asked(scene_file):
    out = scene_file.get("outputs")
    return ["u", "p", "lambda"] if out is None else list(out.get("fields", []))


# A check that had nothing to check says so: "not run: why", never "ok" (an "ok" over 0 cases is
# a sentence that cannot come out false). The check's fourth element (its not-applicable reason)
# carries it, so it fails nothing by itself: where the scene asked for what is missing,
# completeness (or the check itself) has the problem.
NOT_RUN = "not run: "


def not_run(count, why):
    """The not-applicable reason of a check over `count` items: "not run: why" when there were
    none, else None (the check ran)."""
    return None if count else NOT_RUN + why


def status_text(problems, not_applicable):
    """"ok", "FAIL", "not run: why" or "not applicable: why" of one check (report.json's
    `status`)."""
    if problems:
        return "FAIL"
    if not_applicable is None:
        return "ok"
    return not_applicable if not_applicable.startswith(NOT_RUN) else \
        f"not applicable: {not_applicable}"


def delta_points_checked(delta_limit):
    """How many slopes and points the δ → 0 check (delta_slopes) could hold to its rule: the
    fitted slopes and the points with a residual from their fit."""
    return sum((e["points_fitted"] >= 2 and e["slope"] is not None)
               + sum(r is not None for r in e.get("residuals") or []) for e in delta_limit)


def _references_asked(scene_file):
    return list((scene_file.get("outputs") or {}).get("references", []))


def completeness(res, scene_file):
    """Problems: a case, error, field or reference the scene asked for that is missing, or parts
    of the folder that belong to another scene."""
    problems = []
    s = res["summary"]
    name = scene_file.get("name")
    if s.get("scene") != name:
        problems.append(f"summary.json is of scene {s.get('scene')!r} but scene.toml of {name!r}")
    for tool, ref in sorted(res["refs"].items()):
        if ref["summary"].get("scene") != name:
            problems.append(f"{tool}/summary.json is of scene {ref['summary'].get('scene')!r}, "
                            f"not {name!r}")
    levels, u_spaces, multipliers, deltas = scene_lists(scene_file)
    plan = res["plan"]
    if sorted(plan["levels"]) != levels and len(plan["levels"]) != 1:
        problems.append(f"the run's levels {plan['levels']} are neither the scene's {levels} "
                        "nor one level (--level)")
    p_masses, p_spaces = plan_p_masses(plan), plan_p_spaces(plan)
    for key, mine, scene in (("u_spaces", plan["u_spaces"], u_spaces),
                             ("multipliers", plan["multipliers"], multipliers),
                             ("p_masses", p_masses, scene_p_masses(scene_file)),
                             ("p_spaces", p_spaces, scene_p_spaces(scene_file)),
                             ("deltas", plan["deltas"], deltas)):
        extra = [v for v in mine if v not in scene]
        if extra:
            problems.append(f"the run's {key} {extra} are not in the scene file")
    want = {CaseKey(level=int(lv), u_space=u, multiplier=m, p_mass=pm, p_space=ps, delta=float(d))
            for lv in plan["levels"] for u in plan["u_spaces"]
            for m in plan["multipliers"] for d in plan["deltas"] for pm in p_masses
            for ps in p_spaces if runs_together(u, ps)}
    have = [case_key(c) for c in s["cases"]]
    missing = sorted(want - set(have))
    if missing:
        problems.append(f"{len(missing)} case(s) asked for are missing from summary.json, e.g. "
                        f"{case_text(missing[0])}")
    never = [k for k in have if not runs_together(k.u_space, k.p_space)]
    if never:
        problems.append(f"{len(never)} case(s) in summary.json pair the {never[0].u_space} u space "
                        f"with the {never[0].p_space} p space, which sdcrack never runs (a p whose "
                        f"tangential part jumps needs a broken u), e.g. {case_text(never[0])}")
    extra = sorted(set(have) - want - set(never))
    if extra:
        problems.append(f"{len(extra)} case(s) in summary.json were not asked for, e.g. "
                        f"{case_text(extra[0])}")
    if len(set(have)) != len(have):
        problems.append("summary.json lists a case twice")
    if "exact" in scene_file:
        bad = [c for c in s["cases"] if not isinstance(c.get("errors"), dict)
               or not all(finite_number(c["errors"].get(q)) for q in QUANTITIES)]
        if bad:
            k = case_key(bad[0])
            problems.append(f"{len(bad)} case(s) of an exact scene lack a finite error "
                            f"({', '.join(QUANTITIES)}), e.g. level {k.level} {k.u_space} "
                            f"{k.multiplier}{variant_suffix(k.p_mass, k.p_space)}")
    if _fields_asked(scene_file):
        if res["fields"] is None:
            problems.append("the scene asks for fields but fields.h5 is missing")
        else:
            bad = [c for c in s["cases"] if not res["fields"].has_case(c.get("fields_grid"))]
            if bad:
                problems.append(f"{len(bad)} case(s) have no fields in fields.h5")
    for tool in _references_asked(scene_file):
        ref = res["refs"].get(tool)
        if ref is None:
            problems.append(f"the scene asks for reference {tool} but {tool}/summary.json is "
                            "missing")
            continue
        got = {int(c.get("level", -1)) for c in ref["summary"].get("cases", [])}
        lack = [lv for lv in plan["levels"] if lv not in got or lv not in ref["u"]]
        if lack:
            problems.append(f"reference {tool} lacks level(s) {lack}")
    # Without the mesh export of a level, the references' fields of that level are compared with
    # nothing (no independent errors, no solver-vs-reference rows), silently.
    no_mesh = sorted({lv for ref in res["refs"].values() for lv in ref["u"]
                      if lv in plan["levels"] and lv not in (ref.get("mesh") or {})})
    if no_mesh:
        problems.append(f"the mesh export mesh/ the references solved on lacks level(s) {no_mesh}: "
                        "their fields cannot be compared there")
    exported = res.get("mesh_scene")
    if exported is not None and exported.get("name") != name:
        problems.append(f"the mesh export mesh/ is of scene {exported.get('name')!r}, not {name!r}")
    return problems


def worst_residual(kkt):
    """The largest KKT residual of a case; absent residuals, or one that is not a finite number
    (null, NaN), count as infinite (max() over a NaN keeps whichever comes first, so a NaN after a
    small residual would otherwise vanish)."""
    if not isinstance(kkt, dict) or not kkt:
        return math.inf
    return max(float(v) if finite_number(v) else math.inf for v in kkt.values())


def solver_values(kkt_rows, tol):
    """Problems: solver cases not converged or with a KKT residual above `tol` (NaN included)."""
    bad = []
    for k in kkt_rows:
        if not k["converged"] or not worst_residual(k["kkt"]) <= tol:
            bad.append(k)
    if not bad:
        return []
    k = bad[0]
    return [f"{len(bad)} solver case(s) not converged or with KKT residual > {tol:g}, e.g. level "
            f"{k['level']} {k['u_space']} {k['multiplier']}"
            f"{variant_suffix(p_mass(k), p_space(k))} δ={fmt_delta(k['delta'])} (status "
            f"{k['status'] or 'missing'}, converged {k['converged']}, residuals "
            f"{_residuals(k['kkt'])})"]


def reference_values(refs, tol):
    """Problems: reference cases whose status is not "converged" (or absent) or whose KKT
    residuals are above `tol` or absent."""
    problems = []
    for tool, ref in sorted(refs.items()):
        for c in ref["summary"].get("cases", []):
            status = c.get("status")
            worst = worst_residual(c.get("kkt"))
            if status != "converged" or not worst <= tol:
                problems.append(f"reference {tool} level {c.get('level')}: "
                                + (f"status {status!r}" if status is not None else "no status")
                                + f", largest KKT residual {_num(worst)} (must be 'converged' "
                                f"and ≤ {tol:g})")
    return problems


def reference_agreement(agreement, tol):
    rows = [a for a in agreement if a["kind"] == "reference_vs_reference"]
    return [(f"references {a['a']} and {a['b']} differ by {a['max_vertex_diff']} > {tol:g} at "
             f"level {a['level']}" if a["max_vertex_diff"] is not None else
             f"references {a['a']} and {a['b']} could not be compared at level {a['level']}"
             + (f" ({a['note']})" if a.get("note") else "")) for a in rows
            if a["max_vertex_diff"] is None or not a["max_vertex_diff"] <= tol]


# Theorem 2.1 at the discrete level: x_δ − x_0 = −δ (K_0 + δM)⁻¹ M x_0 while the active set
# holds, so ‖x_δ − x_0‖/δ is the same number for every small δ and falls only by 1/(1 + δ‖K_0⁻¹M‖)
# at large δ (measured on the repository's scenes: within 8 % at δ = 1, 4 digits below 1e-2).
# Every point of a sweep must lie within this factor of the fitted line: a single stale or wrong
# δ (a field of another δ, 100× off; a forged one, 93× off) fails, whatever the fitted slope.
DELTA_POINT_FACTOR = 1.5


def delta_slopes(delta_limit, tol):
    """Problems: δ-limit slopes (fitted above round-off) farther than `tol` from 1, and points
    farther than DELTA_POINT_FACTOR from the fitted line."""
    out = []
    for e in delta_limit:
        what = (f"level {e['level']} {e['u_space']} {e['multiplier']}"
                f"{variant_suffix(p_mass(e), p_space(e))} {e['quantity']}")
        if e["points_fitted"] >= 2 and e["slope"] is not None and not abs(e["slope"] - 1.0) <= tol:
            out.append(f"δ → 0 slope {e['slope']:.3f} of {what} is not 1 ± {tol:g}")
        for d, r in zip(e["deltas"], e.get("residuals") or []):
            if r is not None and not abs(r) <= math.log(DELTA_POINT_FACTOR):
                out.append(f"δ → 0 point δ={fmt_delta(d)} of {what} lies a factor "
                           f"{math.exp(abs(r)):.3g} off the fitted line (> {DELTA_POINT_FACTOR:g}): "
                           "a stale or wrong field at that δ")
    return out


def independent_errors(res, scene_file):
    """Recomputes every reported error against the exact solution from the stored fields with the
    compare tool's own quadrature (exact.py): the solver's cases with fields (the consistent p_h
    with its stored bubble, which must be there; the lumped p_h, P1 without bubble, with bubble 0;
    p_h per triangle from the triangle's own dofs, so a broken-tangential p is integrated on each
    face with its own copy) and each reference's P1 field on the exported cracked mesh; the p mass
    and p space of fields.h5's attributes must be the summary's. A solver's error is held to the
    tolerance of its quadrature estimates (SAFETY above; the bare SOLVER_ERRORS_RTOL for a summary
    without them), and this tool's quadrature to its self-check on each mesh. Returns (rows,
    problems); rows: dict(source, level, u_space, multiplier, p_mass, p_space, delta, quantity →
    (reported, ours), worst (largest relative difference); for sdcrack also tolerance, estimates
    (quantity → (sdcrack's, ours)), higher (this tool's higher-rule values), ratio (largest
    difference over its tolerance), tolerance_kind, self_check)."""
    if "exact" not in scene_file:
        return [], []
    try:
        ex = exact.ExactSolution.from_scene(scene_file)
    except exact.ExactError as exc:  # the scene copy's cracks (expressions raise sdexpr.ExprError)
        raise InputError(f"{res['folder']}/scene.toml: {exc}")
    rows, problems = [], []
    fields = res["data"]
    unrecomputed = []
    self_checked = set()  # the meshes whose self-check was reported
    for c in sorted(res["summary"]["cases"], key=case_order):
        if not isinstance(c.get("errors"), dict):
            continue  # completeness reports the missing errors
        pm, ps = p_mass(c), p_space(c)
        what = case_text(case_key(c))
        if fields is None or not fields.has_case(c.get("fields_grid")):
            unrecomputed.append(what)
            continue
        problems += _stored_axes(fields, c, what)
        try:
            ours = precomputed.solver_case_errors_h5(fields.h5, c["fields_grid"], ex,
                                                     scene_file, pm, ps)
            mesh_key, self_check = _self_check(fields.h5, c["fields_grid"], ex)
        except exact.ExactError as exc:
            ours, mesh_key, self_check = {"bubble": None}, None, None
            problems.append(f"sdcrack's errors of {what} cannot be recomputed: {exc}")
        row = _error_row("sdcrack", c, c["errors"], ours)
        row["bubble"] = ours.get("bubble")
        rows.append(row)
        lacking = [q for q in QUANTITIES if "u_l2" in ours and ours.get(q) is None]
        if lacking:
            problems.append(f"sdcrack's {', '.join(lacking)} of {what} cannot be recomputed: "
                            "the stored fields lack them")
        if "u_l2" in ours:
            row["self_check"] = self_check
            if mesh_key not in self_checked:
                self_checked.add(mesh_key)
                problems += _self_check_problems(self_check, what)
            problems += _tolerance(row, c, ours, self_check, what)
    if unrecomputed:
        problems.append(f"sdcrack's errors of {len(unrecomputed)} case(s) cannot be recomputed "
                        f"independently, e.g. {unrecomputed[0]}: no stored fields (fields.h5 or "
                        "verification.h5) for them")
    reported = {}
    for tool, ref in sorted(res["refs"].items()):
        meshes = ref.get("mesh") or {}
        for c in ref["summary"].get("cases", []):
            lv = int(c["level"])
            if lv not in meshes or lv not in ref["u"] or not isinstance(c.get("errors"), dict):
                continue
            m = meshes[lv]
            ours = precomputed.p1_field_errors(m, ref["u"][lv], ex, scene_file)
            row = _error_row(tool, c, c["errors"], ours, quantities=("u_l2", "p_l2", "lambda_l2"))
            # the reference's own yardstick (refcheck.py): right after its errors, the exact
            # solution's values at the same quadrature points are still at hand (exact.py)
            row["interpolation"] = precomputed.p1_interpolation_errors(m, ex, scene_file)
            rows.append(row)
            reported.setdefault(lv, {})[tool] = c["errors"]
            if not row["worst"] <= REFERENCE_ERRORS_RTOL:
                problems.append(f"{tool}'s reported errors of level {lv} differ from the "
                                f"independent computation by {_num(row['worst'])} relative "
                                f"(> {REFERENCE_ERRORS_RTOL:g})")
    for lv, by_tool in sorted(reported.items()):
        if len(by_tool) == 2:
            (ta, ea), (tb, eb) = sorted(by_tool.items())
            worst = max(_rel(ea.get(q), eb.get(q)) for q in ("u_l2", "p_l2", "lambda_l2"))
            if not worst <= REFERENCE_ERRORS_RTOL:
                problems.append(f"the references' reported errors of level {lv} differ by "
                                f"{_num(worst)} relative ({ta} vs {tb}; > {REFERENCE_ERRORS_RTOL:g})")
    return rows, problems


# The self-check of this tool's quadrature per mesh (exact.quadrature_self_check), by the digest of
# the mesh's triangles as coordinates (T, 3, 2) and its tips: every δ, multiplier and p mass of a
# level shares one, and so do the continuous and the broken u of a level, whose meshes are the same
# triangles numbered apart (the crack's − copies). The quadrature's pieces, points and weights
# depend on the triangles' coordinates and the tips only (exact._point_batches), so the second
# numbering would integrate the same points with the same weights; only the exact moments'
# boundary edges differ (the broken mesh's two crack faces, whose contributions cancel).
_SELF_CHECKS = {}


def _self_check(h5, case, ex):
    """(mesh key, exact.quadrature_self_check) on the mesh of fields.h5's case CASE with its
    crack tips (the rules and pieces of the errors), computed once per mesh and quadrature;
    (None, None) for a case without a mesh."""
    d = exact.read_h5_case(h5, case)
    if d["points"] is None or d["triangles"] is None:
        return None, None
    _, _, tips = exact._crack_geometry(d["crack_points"], d["crack_segments"], ex)
    tips = np.asarray(tips, dtype=float).reshape(-1, 2)
    corners = np.asarray(d["points"], dtype=float)[:, :2][np.asarray(d["triangles"], dtype=np.int64)]
    key = (norms.digest(corners, tips), repr(exact.Quadrature()))
    if key not in _SELF_CHECKS:
        _SELF_CHECKS[key] = exact.quadrature_self_check(d["points"], d["triangles"], list(tips))
    return key, _SELF_CHECKS[key]


def _self_check_failed(self_check):
    return bool(self_check) and not all(r["ok"] for r in self_check)


def _self_check_problems(self_check, what):
    """One problem per failing rule of the self-check on the case's mesh, reported with the first
    case of that mesh only."""
    out = []
    for r in self_check or []:
        if r["ok"]:
            continue
        a, b = r["monomial"]
        out.append(f"the compare tool's quadrature is suspect: on the mesh of {what} its "
                   f"{r['rule']} ({r['quadrature']}) integrates ξ^{a} η^{b} (scaled coordinates, "
                   f"degree ≤ {r['degree']}, which it must integrate exactly) {_num(r['worst'])} "
                   f"of the mesh's area off the exact moment from the boundary edges (Green's "
                   f"theorem; > {exact.SELF_CHECK_TOLERANCE:g})")
    return out


def _estimate(v):
    """A quadrature estimate: a finite number >= 0, else None."""
    return float(v) if finite_number(v) and v >= 0 else None


def _tolerance(row, c, ours, self_check, what):
    """Fills the row's tolerances (row["tolerance"], ["estimates"], ["higher"], ["ratio"],
    ["tolerance_kind"]) and returns the problems: a reported error farther from this tool's than
    its tolerance (saying which computation is suspect), an estimate too large to verify with
    (ESTIMATE_CAP), a malformed estimate in summary.json."""
    problems = []
    theirs = c.get("errors_quadrature")
    has_estimates = theirs is not None
    if has_estimates and not isinstance(theirs, dict):
        theirs = {}
    higher, mine = ours.get("higher") or {}, ours.get("quadrature") or {}
    row["tolerance_kind"] = ("quadrature estimates" if has_estimates else
                             f"bare {SOLVER_ERRORS_RTOL:g} relative (summary.json has no "
                             "errors_quadrature)")
    row["tolerance"], row["estimates"], row["higher"] = {}, {}, {}
    failing = []
    ratio = 0.0
    for q in QUANTITIES:
        r, o = row[q]
        row["tolerance"][q] = None
        if o is None:
            continue  # not recomputed: reported by the caller
        if not (finite_number(r) and finite_number(o)):
            ratio = math.inf
            failing.append((q, math.inf, None))
            continue
        scale = max(abs(r), abs(o))
        floor = ROUNDOFF_RTOL * scale + ERRORS_ATOL
        e_ours, h = _estimate(mine.get(q)), higher.get(q)
        e_theirs = _estimate(theirs.get(q)) if has_estimates else None
        row["estimates"][q] = (e_theirs, e_ours)
        row["higher"][q] = h
        if has_estimates and e_theirs is None:
            problems.append(f"summary.json's errors_quadrature of {what} has {q} = "
                            f"{theirs.get(q)!r}, not a number ≥ 0")
        for who, e in (("sdcrack's", e_theirs), ("the compare tool's", e_ours)):
            if e is not None and e > ESTIMATE_CAP * scale + ERRORS_ATOL:
                problems.append(f"{who} quadrature is suspect: its estimate of the quadrature "
                                f"error of {q} of {what} is {_num(e / scale)} of the error "
                                f"(> {ESTIMATE_CAP:g}: its rule and its higher rule disagree, "
                                "the integrand is not resolved, and a tolerance built on it could "
                                "not tell a 1 % slip)")
        if e_theirs is not None and e_ours is not None:
            tol = SAFETY * (e_theirs + e_ours) + floor
        elif has_estimates and e_theirs is None:
            tol = None  # a malformed estimate: reported above
        else:  # no estimate in summary.json (or none of this tool's): the former bare tolerance
            tol = SOLVER_ERRORS_RTOL * scale if scale > ERRORS_ATOL else ERRORS_ATOL
        row["tolerance"][q] = tol
        if tol is None:
            continue
        q_ratio = abs(r - o) / tol
        ratio = max(ratio, q_ratio)
        if q_ratio > 1.0:
            failing.append((q, _rel(r, o), tol))
    row["ratio"] = ratio
    if failing:
        q, rel, tol = max(failing, key=lambda f: f[1])
        r, o = row[q]
        detail = (f"{q}: |Δ| = {_num(abs(r - o)) if finite_number(r) else 'not finite'}"
                  + (f" > tolerance {_num(tol)}" if tol is not None else ""))
        e_t, e_o = row["estimates"].get(q, (None, None))
        if tol is not None and e_t is not None and e_o is not None:
            detail += (f" = {SAFETY:g}·(sdcrack's quadrature estimate "
                       f"{_estimate_text(e_t, o)} + this tool's {_estimate_text(e_o, o)}) "
                       "+ round-off")
        elif tol is not None and not has_estimates:
            detail += (f", the bare {SOLVER_ERRORS_RTOL:g} relative: summary.json has no "
                       "errors_quadrature (written by an sdcrack that did not record it yet)")
        problems.append(f"sdcrack's reported errors of {what} differ from the independent "
                        f"computation by {_num(rel)} relative ({detail}): "
                        f"{_suspect(row, q, self_check)}")
    return problems


def _suspect(row, q, self_check):
    """Which computation of the quantity q is suspect, with this tool's higher-order value as
    arbiter: the one farther from it than its own estimate allows (the compare tool's rule, when
    it fails its self-check on the mesh)."""
    if _self_check_failed(self_check):
        return "the compare tool's quadrature is suspect (it fails its self-check on this mesh)"
    r, o = row[q]
    h = row["higher"].get(q)
    e_t, e_o = row["estimates"].get(q, (None, None))
    if not (finite_number(r) and finite_number(o) and finite_number(h)):
        return "sdcrack's value is suspect (it is not a finite number)" if not finite_number(r) \
            else "no higher-order value to tell which computation is suspect"
    floor = ROUNDOFF_RTOL * max(abs(r), abs(o), abs(h)) + ERRORS_ATOL
    # this tool's higher rule is off by at most SAFETY e_o itself (its error is below its rule's)
    own = SAFETY * (e_o or 0.0) + floor
    if e_t is None:  # no estimate from the solver: the bare tolerance, against the higher value
        theirs_off = abs(r - h) > SOLVER_ERRORS_RTOL * abs(h) + own
    else:
        theirs_off = abs(r - h) > SAFETY * e_t + own
    ours_off = abs(o - h) > own
    far = f"from the compare tool's higher-order value {h:.10g}"
    if theirs_off and not ours_off:
        return (f"sdcrack's value is suspect: it lies {_num(abs(r - h))} {far}, beyond its own "
                f"quadrature estimate, where the compare tool's lies within its own")
    if ours_off and not theirs_off:
        return (f"the compare tool's value is suspect: it lies {_num(abs(o - h))} {far}, beyond "
                "its own quadrature estimate, where sdcrack's lies within its own")
    if theirs_off and ours_off:
        return f"both are suspect: each lies beyond its own quadrature estimate {far}"
    return (f"neither lies beyond its own quadrature estimate {far}: the estimates do not add up "
            "to the difference")


def independent_text(rows, has_exact):
    """The "independent errors" row's text: what was compared, to which tolerance, and the
    largest difference (as a fraction of its tolerance), estimates and self-check deviation."""
    if not has_exact:
        return "no exact solution: nothing to recompute"
    if not rows:
        return "no fields stored: the reported errors could not be recomputed"
    solver = [r for r in rows if r["source"] == "sdcrack"]
    refs = [r["worst"] for r in rows if r["source"] != "sdcrack"]
    out = []
    if solver:
        with_est = [r for r in solver if r.get("tolerance_kind") == "quadrature estimates"]
        bare = [r for r in solver if r.get("tolerance_kind") != "quadrature estimates"]
        worst = _largest([r["worst"] for r in solver])
        if with_est:
            est = [e / max(abs(r[q][0]), abs(r[q][1]))
                   for r in with_est for q, pair in r.get("estimates", {}).items()
                   for e in pair if e is not None and finite_number(r[q][0])
                   and max(abs(r[q][0]), abs(r[q][1])) > ERRORS_ATOL]
            out.append(f"sdcrack's errors of {len(with_est)} cases equal the compare tool's own "
                       f"computation within {SAFETY:g}·(sdcrack's quadrature estimate + this "
                       f"tool's) + {ROUNDOFF_RTOL:g} relative (largest difference {worst} "
                       f"relative, {_largest([r.get('ratio', math.inf) for r in with_est])} of "
                       f"its tolerance; estimates up to {_largest(est or [0.0])} relative)")
        if bare:
            out.append(f"sdcrack's errors of {len(bare)} cases to ≤ {SOLVER_ERRORS_RTOL:g} "
                       f"relative (largest {_largest([r['worst'] for r in bare])}): their "
                       "summary.json has no quadrature estimate (errors_quadrature, an sdcrack "
                       "that did not record it yet), so the former bare tolerance applies")
        checked = [r["self_check"] for r in solver if r.get("self_check")]
        if checked:
            dev = max(x["worst"] for sc in checked for x in sc)
            degrees = sorted({x["degree"] for sc in checked for x in sc})
            out.append(f"the compare tool's quadrature (its rule and its higher rule) integrates "
                       f"every monomial of degree ≤ {'/'.join(map(str, degrees))} over the "
                       f"meshes to ≤ {dev:.1e} of their area from the exact moments (self-check, "
                       f"≤ {exact.SELF_CHECK_TOLERANCE:g})")
    if refs:
        out.append(f"the references' errors of {len(refs)} cases to ≤ "
                   f"{REFERENCE_ERRORS_RTOL:g} (largest {_largest(refs)})")
    return "; ".join(out)


def _largest(values):
    m = max(values)
    return f"{m:.1e}" if math.isfinite(m) else "not finite: a reported error is missing or NaN"


def _stored_axes(fields, c, what):
    """Problems: the case's group in fields.h5 carries a p_mass or p_space attribute other than
    the case's in summary.json (an absent attribute: a file older than the axis)."""
    attrs = fields.h5[f"cases/{c['fields_grid']}"].attrs
    out = []
    for key, word, mine in (("p_mass", "p mass", p_mass(c)), ("p_space", "p space", p_space(c))):
        stored = attrs.get(key)
        if isinstance(stored, bytes):
            stored = stored.decode()
        if stored is not None and str(stored) != mine:
            out.append(f"sdcrack's case {what} is of {word} {mine} in summary.json but {stored} "
                       f"in fields.h5 (/cases/{c['fields_grid']})")
    return out


def _error_row(source, c, reported, ours, quantities=QUANTITIES):
    row = {"source": source, "level": int(c["level"]), "u_space": c.get("u_space"),
           "multiplier": c.get("multiplier"), "delta": c.get("delta")}
    if source == "sdcrack":
        row["p_mass"], row["p_space"] = p_mass(c), p_space(c)
    worst = 0.0
    for q in quantities:
        a, b = reported.get(q), ours.get(q)
        row[q] = (a, b)
        worst = max(worst, _rel(a, b))
    row["worst"] = worst
    return row



# Theorem 2.1 against the exact solution: |‖u_δ − u‖ − ‖u_0 − u‖| ≤ ‖u_δ − u_0‖ (the triangle
# inequality) ties the errors the solver reports at each δ to the fields stored at each δ: a
# forged or stale error at one δ breaks it. Relative slack for the two computations' round-off.
THEOREM21_RTOL = 1e-6


THEOREM21_QUANTITIES = ("u_l2", "lambda_l2")  # exact field differences (p's bubble is left out)


def theorem21_rows(cases, delta_limit):
    """Per (level, variant, quantity) and δ > 0: the reported error e(δ) against the exact solution,
    the floor e(0) (the smallest δ) and ‖x_δ − x_0‖ from the fields (delta_limit)."""
    rep = {case_key(c): c.get("errors") for c in cases if isinstance(c.get("errors"), dict)}
    rows = []
    for d in delta_limit:
        if d["quantity"] not in THEOREM21_QUANTITIES:
            continue
        base = rep.get(case_key(dict(d, delta=d["delta_ref"])))
        if base is None or not finite_number(base.get(d["quantity"])):
            continue
        e0 = float(base[d["quantity"]])
        for delta, diff in zip(d["deltas"], d["diffs"]):
            e = (rep.get(case_key(dict(d, delta=delta))) or {}).get(d["quantity"])
            ok = finite_number(e) and abs(e - e0) <= diff * (1 + THEOREM21_RTOL) + ERRORS_ATOL * 10 \
                + THEOREM21_RTOL * e0
            rows.append({"level": d["level"], "u_space": d["u_space"], "multiplier": d["multiplier"],
                         "p_mass": d["p_mass"], "p_space": p_space(d), "quantity": d["quantity"],
                         "delta": delta,
                         "error": e, "floor": e0, "diff": diff, "ok": bool(ok)})
    return rows


def theorem21(rows):
    bad = [r for r in rows if not r["ok"]]
    if not bad:
        return []
    r = bad[0]
    return [f"{len(bad)} reported error(s) at δ > 0 disagree with the stored fields, e.g. level "
            f"{r['level']} {r['u_space']} {r['multiplier']}"
            f"{variant_suffix(r['p_mass'], p_space(r))} "
            f"{r['quantity']} δ={fmt_delta(r['delta'])}: |e(δ) − e(0)| = "
            f"{_num(abs(r['error'] - r['floor']) if finite_number(r['error']) else None, '.3e')} > "
            f"‖x_δ − x_0‖ = {r['diff']:.3e}"]


def exact_solution(res, scene_file):
    """The scene's exact solution (exact.ExactSolution), None without [exact]; a malformed one is
    an InputError (exit 2)."""
    if "exact" not in scene_file:
        return None
    try:
        return exact.ExactSolution.from_scene(scene_file)
    except exact.ExactError as exc:
        raise InputError(f"{res['folder']}/scene.toml: {exc}")


# The quantities each stored field carries.
FIELD_QUANTITIES = {"u": ("u_l2",), "p": ("p_l2", "p_x"), "lambda": ("lambda_l2",)}


def unstored_quantities(res, scene_file):
    """Quantities whose fields are neither in the recomputation file (verification.h5 keeps all)
    nor asked for in fields.h5: a folder written before verification.h5 existed."""
    if res["data"] is not None and res["data"] is not res["fields"]:
        return set()
    asked = _fields_asked(scene_file)
    return {q for f, qs in FIELD_QUANTITIES.items() if f not in asked for q in qs}


def delta_check(res, delta_limit, st):
    """(problems, not-applicable reason) of the δ → 0 check: slopes and points (delta_slopes);
    a scene with one δ does not apply; a sweep without stored fields to measure it fails."""
    deltas = res["plan"].get("deltas", [])
    if len(deltas) < 2:
        return [], f"the run has one δ ({fmt_delta(deltas[0]) if deltas else 'none'}): no sweep"
    declared = st.get("not_applicable", {}).get("δ → 0")
    if declared:
        return [], f"declared in the scene: {declared}"
    if not delta_limit:
        return [f"the run sweeps {len(deltas)} δ but no δ-limit could be measured (no stored "
                "fields for them)"], None
    positive = sorted({d for e in delta_limit for d in e["deltas"] if d > 0}, reverse=True)
    return delta_slopes(delta_limit, st["delta_slope_tolerance"]), not_run(
        delta_points_checked(delta_limit),
        "no variant has two δ > 0 with a difference above round-off (δ > 0: "
        + ", ".join(fmt_delta(d) for d in positive) + "): no slope to fit, no point to check "
        "against one")
