"""Checks of a results folder that are not convergence rates: is everything the scene asked for
there, are the values trustworthy (KKT residuals, reference statuses and agreement, δ-limit
slopes), and do the errors the solvers report equal an independent computation from their fields.

Each check returns rows (for the report) and problems (one line each); any problem fails the run.
"""
import math

from . import exact
from .read import DEFAULT_P_MASS, InputError, case_key, finite_number, p_mass, plan_p_masses, pm_suffix
from .render import fmt_delta
from .settings import QUANTITIES, scene_lists, scene_p_masses

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
    p_masses = plan_p_masses(plan)
    for key, mine, scene in (("u_spaces", plan["u_spaces"], u_spaces),
                             ("multipliers", plan["multipliers"], multipliers),
                             ("p_masses", p_masses, scene_p_masses(scene_file)),
                             ("deltas", plan["deltas"], deltas)):
        extra = [v for v in mine if v not in scene]
        if extra:
            problems.append(f"the run's {key} {extra} are not in the scene file")
    want = {(int(lv), u, m, float(d), pm) for lv in plan["levels"] for u in plan["u_spaces"]
            for m in plan["multipliers"] for d in plan["deltas"] for pm in p_masses}
    have = [case_key(c) for c in s["cases"]]
    missing = sorted(want - set(have))
    if missing:
        k = missing[0]
        problems.append(f"{len(missing)} case(s) asked for are missing from summary.json, e.g. "
                        f"level {k[0]} {k[1]} {k[2]}{pm_suffix(k[4])} δ={fmt_delta(k[3])}")
    extra = sorted(set(have) - want)
    if extra:
        k = extra[0]
        problems.append(f"{len(extra)} case(s) in summary.json were not asked for, e.g. "
                        f"level {k[0]} {k[1]} {k[2]}{pm_suffix(k[4])} δ={fmt_delta(k[3])}")
    if len(set(have)) != len(have):
        problems.append("summary.json lists a case twice")
    if "exact" in scene_file:
        bad = [c for c in s["cases"] if not isinstance(c.get("errors"), dict)
               or not all(finite_number(c["errors"].get(q)) for q in QUANTITIES)]
        if bad:
            k = case_key(bad[0])
            problems.append(f"{len(bad)} case(s) of an exact scene lack a finite error "
                            f"({', '.join(QUANTITIES)}), e.g. level {k[0]} {k[1]} {k[2]}"
                            f"{pm_suffix(k[4])}")
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
            f"{pm_suffix(k.get('p_mass', DEFAULT_P_MASS))} δ={fmt_delta(k['delta'])} (status "
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


def delta_slopes(delta_limit, tol):
    """Problems: δ-limit slopes (fitted above round-off) farther than `tol` from 1."""
    return [f"δ → 0 slope {e['slope']:.3f} of level {e['level']} {e['u_space']} "
            f"{e['multiplier']}{pm_suffix(e.get('p_mass', DEFAULT_P_MASS))} {e['quantity']} is not "
            f"1 ± {tol:g}"
            for e in delta_limit if e["points_fitted"] >= 2 and e["slope"] is not None
            and not abs(e["slope"] - 1.0) <= tol]


def independent_errors(res, scene_file):
    """Recomputes every reported error against the exact solution from the stored fields with the
    compare tool's own quadrature (exact.py): the solver's cases with fields (the consistent p_h
    with its stored bubble, which must be there; the lumped p_h, P1 without bubble, with bubble 0)
    and each reference's P1 field on the exported cracked mesh. Returns (rows, problems);
    rows: dict(source, level, u_space, multiplier, p_mass, delta, quantity → (reported, ours),
    worst)."""
    if "exact" not in scene_file:
        return [], []
    try:
        ex = exact.ExactSolution.from_scene(scene_file)
    except exact.ExactError as exc:  # the scene copy's cracks (expressions raise sdexpr.ExprError)
        raise InputError(f"{res['folder']}/scene.toml: {exc}")
    rows, problems = [], []
    fields = res["fields"]
    for c in sorted(res["summary"]["cases"], key=case_key):
        if fields is None or not fields.has_case(c.get("fields_grid")) \
                or not isinstance(c.get("errors"), dict):
            continue
        pm = p_mass(c)
        what = (f"level {c['level']} {c['u_space']} {c['multiplier']}{pm_suffix(pm)} "
                f"δ={fmt_delta(c['delta'])}")
        stored = fields.h5[f"cases/{c['fields_grid']}"].attrs.get("p_mass")
        if isinstance(stored, bytes):
            stored = stored.decode()
        if stored is not None and str(stored) != pm:
            problems.append(f"sdcrack's case {what} is of p mass {pm} in summary.json but "
                            f"{stored} in fields.h5 (/cases/{c['fields_grid']})")
        try:
            ours = exact.solver_case_errors_h5(fields.h5, c["fields_grid"], ex, p_mass=pm)
        except exact.ExactError as exc:
            ours = {"bubble": None}
            problems.append(f"sdcrack's errors of {what} cannot be recomputed: {exc}")
        row = _error_row("sdcrack", c, c["errors"], ours)
        row["bubble"] = ours.get("bubble")
        rows.append(row)
        if "u_l2" in ours and not row["worst"] <= SOLVER_ERRORS_RTOL:
            problems.append(f"sdcrack's reported errors of {what} differ from the "
                            f"independent computation by {_num(row['worst'])} relative "
                            f"(> {SOLVER_ERRORS_RTOL:g})")
    reported = {}
    for tool, ref in sorted(res["refs"].items()):
        meshes = ref.get("mesh") or {}
        for c in ref["summary"].get("cases", []):
            lv = int(c["level"])
            if lv not in meshes or lv not in ref["u"] or not isinstance(c.get("errors"), dict):
                continue
            m = meshes[lv]
            ours = exact.p1_field_errors(m.points, m.tris, ref["u"][lv], m.crack, ex, ranges=m.ranges)
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


def _error_row(source, c, reported, ours, quantities=QUANTITIES):
    row = {"source": source, "level": int(c["level"]), "u_space": c.get("u_space"),
           "multiplier": c.get("multiplier"), "delta": c.get("delta")}
    if source == "sdcrack":
        row["p_mass"] = p_mass(c)
    worst = 0.0
    for q in quantities:
        a, b = reported.get(q), ours.get(q)
        row[q] = (a, b)
        worst = max(worst, _rel(a, b))
    row["worst"] = worst
    return row

