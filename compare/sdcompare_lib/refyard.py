"""The reference yardstick's inputs: the references' own errors (against the exact solution, or
their distance to their finest level) and the solver's series they bound. Shared by the reference
yardstick (yardsticks.py), the measured ratio to the references (ratios.py) and the glance
(glance.py), below all three."""
import numpy as np

from . import norms
from .cases import variant_of
from .verdict import ref_delta

# Against the references (P1 on the cracked mesh, the same triangles): the smooth-domain method's
# u, p and λ approximate the same functions in spaces at least as rich (P1 u on the same cracked
# mesh, MINI p ⊃ ∇P1, λ_h P0/P1 on the crack edges); a factor 3 allows for the mixed method's
# constants and for M0's piecewise-constant λ. Only quantities whose expected order reaches the
# references' are bounded (theory.reaches_p1_order): where the crack opens the continuous p's u and
# p are of order 1/2, and no constant bounds the ratio as h → 0; the broken-tangential p's reach
# it, closed or open.
REFERENCE_FACTOR = {"u_l2": 3.0, "p_l2": 3.0, "lambda_l2": 3.0}
# Errors at or below this are zero to round-off (λ on a closed crack): never a violation.
ABS_FLOOR = 1e-12


def reference_errors_exact(independent_rows, tool):
    """{(level, q): the reference's error against the exact solution as recomputed by this tool}."""
    out = {}
    for r in independent_rows:
        if r["source"] != tool:
            continue
        for q in REFERENCE_FACTOR:
            ours = r.get(q)
            if isinstance(ours, tuple) and ours[1] is not None:
                out[(r["level"], q)] = ours[1]
    return out


def reference_errors_finest(ref):
    """{(level, q): ‖u_ref,L − u_ref,finest‖ (q = u_l2) and ‖∇u_ref,L − ∇u_ref,finest‖ (p_l2)} for
    every level below the reference's finest, the coarse field evaluated exactly at the corners of
    the finest triangles (norms.prolong_to_fine, as for the solver's rows): on each fine triangle
    the coarse field is linear, so its gradient there is the coarse triangle's."""
    meshes = ref.get("mesh") or {}
    levels = sorted(lv for lv in ref["u"] if lv in meshes)
    if len(levels) < 2:
        return {}
    finest = levels[-1]
    fm = meshes[finest]
    uf = ref["u"][finest]
    grad_f = norms.p1_gradients(fm.points, fm.tris, uf)
    area = norms.triangle_areas(fm.points, fm.tris)
    out = {}
    for lv in levels[:-1]:
        m = meshes[lv]
        if m.kind != fm.kind:
            continue
        try:
            vc = norms.prolong_to_fine(m.points, m.tris, ref["u"][lv], fm.points, fm.tris,
                                       *norms.nesting(meshes, lv, finest))
        except norms.NormError:
            continue  # no row: the check reports it could not run
        vf = np.asarray(uf, dtype=float)[fm.tris]
        out[(lv, "u_l2")] = float(np.sqrt(norms._local_sq(area, vc - vf)))
        d = norms.corner_gradients(fm.points, fm.tris, vc) - grad_f
        out[(lv, "p_l2")] = float(np.sqrt(np.sum(area * np.sum(d * d, axis=1))))
    return out


def solver_vs_finest(series, agreement, tool, delta):
    """Series-like entries of the solver's distance to the reference's finest level
    (agreement rows e_u_finest → u_l2, e_p_finest → p_l2) at δ = delta, levels below the finest,
    with the status and expected order of the variant's own series (expected failures are skipped
    by the check)."""
    own = {variant_of(s) + (s["quantity"],): s for s in series}
    out = {}
    for r in agreement:
        if r["kind"] != "solver_vs_reference" or r.get("reference") != tool \
                or r.get("delta") != delta or "level" not in r or r["level"] >= r["finest_level"]:
            continue
        for q, key in (("u_l2", "e_u_finest"), ("p_l2", "e_p_finest")):
            k = variant_of(r) + (q,)
            e = out.setdefault(k, {"u_space": k[0], "multiplier": k[1], "p_mass": k[2],
                                   "p_space": k[3], "quantity": q,
                                   "status": own[k]["status"] if k in own else "converges",
                                   "expected_rate": own[k]["expected_rate"] if k in own else None,
                                   "levels": [], "errors": []})
            e["levels"].append(r["level"])
            e["errors"].append(r.get(key))
    return list(out.values())


def reference_inputs(res, a, tool):
    """(yardstick, series) of the reference yardstick for `tool`: with an exact solution the
    reference's own errors against it (recomputed here) and the series against it; without one
    the reference's distances to its finest level and the solver's (solver_vs_finest)."""
    if a["exact"] is not None:
        return (reference_errors_exact(a["independent"], tool),
                [s for s in a["series"] if s["against"] == "exact"])
    return (reference_errors_finest(res["refs"][tool]),
            solver_vs_finest(a["series"], a["agreement"], tool, ref_delta(
                res["summary"]["cases"])))
