"""Checks of a results folder that are not convergence rates: is everything the scene asked for
there, are the values trustworthy (KKT residuals, reference statuses and agreement, δ-limit
slopes), and do the errors the solvers report equal an independent computation from their fields.

Each check returns rows (for the report) and problems (one line each); any problem fails the run.
"""
import math

from . import exact, precomputed
from .read import (InputError, case_key, finite_number, p_mass, p_space, plan_p_masses,
                   plan_p_spaces, runs_together, variant_suffix)
from .render import fmt_delta
from .settings import QUANTITIES, scene_lists, scene_p_masses, scene_p_spaces

# The solver's errors against the compare tool's own (exact.py: another rule family, Duffy rules
# at the tips). Both quadratures are converged to < 1e-10 relative (tests/convergence.rs,
# compare/tests/test_exact.py) on the same stored float64 fields; measured agreement <= 8.4e-11.
SOLVER_ERRORS_RTOL = 1e-8
# The references' reported errors against each other and against exact.py (issue 12: 1e-6).
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


def _rel(a, b):
    if not (finite_number(a) and finite_number(b)):
        return math.inf
    if max(abs(a), abs(b)) <= ERRORS_ATOL:
        return 0.0
    return abs(a - b) / max(abs(a), abs(b))


def _fields_asked(scene_file):
    out = scene_file.get("outputs")
    return ["u", "p", "lambda"] if out is None else list(out.get("fields", []))


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
    want = {(int(lv), u, m, float(d), pm, ps) for lv in plan["levels"] for u in plan["u_spaces"]
            for m in plan["multipliers"] for d in plan["deltas"] for pm in p_masses
            for ps in p_spaces if runs_together(u, ps)}
    have = [case_key(c) for c in s["cases"]]
    missing = sorted(want - set(have))
    if missing:
        problems.append(f"{len(missing)} case(s) asked for are missing from summary.json, e.g. "
                        f"{_case_text(missing[0])}")
    never = [k for k in have if not runs_together(k[1], k[5])]
    if never:
        problems.append(f"{len(never)} case(s) in summary.json pair the {never[0][1]} u space with "
                        f"the {never[0][5]} p space, which sdcrack never runs (a p whose "
                        f"tangential part jumps needs a broken u), e.g. {_case_text(never[0])}")
    extra = sorted(set(have) - want - set(never))
    if extra:
        problems.append(f"{len(extra)} case(s) in summary.json were not asked for, e.g. "
                        f"{_case_text(extra[0])}")
    if len(set(have)) != len(have):
        problems.append("summary.json lists a case twice")
    if "exact" in scene_file:
        bad = [c for c in s["cases"] if not isinstance(c.get("errors"), dict)
               or not all(finite_number(c["errors"].get(q)) for q in QUANTITIES)]
        if bad:
            k = case_key(bad[0])
            problems.append(f"{len(bad)} case(s) of an exact scene lack a finite error "
                            f"({', '.join(QUANTITIES)}), e.g. level {k[0]} {k[1]} {k[2]}"
                            f"{variant_suffix(k[4], k[5])}")
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


def _case_text(k):
    """"level L u m[ lumped][ ptangential] δ=D" of a case key (read.case_key)."""
    return f"level {k[0]} {k[1]} {k[2]}{variant_suffix(k[4], k[5])} δ={fmt_delta(k[3])}"


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
    and p space of fields.h5's attributes must be the summary's. Returns (rows, problems); rows:
    dict(source, level, u_space, multiplier, p_mass, p_space, delta, quantity → (reported, ours),
    worst)."""
    if "exact" not in scene_file:
        return [], []
    try:
        ex = exact.ExactSolution.from_scene(scene_file)
    except exact.ExactError as exc:  # the scene copy's cracks (expressions raise sdexpr.ExprError)
        raise InputError(f"{res['folder']}/scene.toml: {exc}")
    rows, problems = [], []
    fields = res["data"]
    unrecomputed = []
    for c in sorted(res["summary"]["cases"], key=case_key):
        if not isinstance(c.get("errors"), dict):
            continue  # completeness reports the missing errors
        pm, ps = p_mass(c), p_space(c)
        what = _case_text(case_key(c))
        if fields is None or not fields.has_case(c.get("fields_grid")):
            unrecomputed.append(what)
            continue
        problems += _stored_axes(fields, c, what)
        try:
            ours = precomputed.solver_case_errors_h5(fields.h5, c["fields_grid"], ex,
                                                     scene_file, pm, ps)
        except exact.ExactError as exc:
            ours = {"bubble": None}
            problems.append(f"sdcrack's errors of {what} cannot be recomputed: {exc}")
        row = _error_row("sdcrack", c, c["errors"], ours)
        row["bubble"] = ours.get("bubble")
        rows.append(row)
        lacking = [q for q in QUANTITIES if "u_l2" in ours and ours.get(q) is None]
        if lacking:
            problems.append(f"sdcrack's {', '.join(lacking)} of {what} cannot be recomputed: "
                            "the stored fields lack them")
        if "u_l2" in ours and not row["worst"] <= SOLVER_ERRORS_RTOL:
            problems.append(f"sdcrack's reported errors of {what} differ from the "
                            f"independent computation by {_num(row['worst'])} relative "
                            f"(> {SOLVER_ERRORS_RTOL:g})")
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
    return delta_slopes(delta_limit, st["delta_slope_tolerance"]), None
