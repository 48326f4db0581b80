"""The verdict on an elastic scene's results folder (docs/elasticity.md): the references judged
against the exact fields (recomputed here from their stored u and crack files), against each other,
and, without [exact], against their finest level. compare/sdcompare dispatches here when
summary.json says "problem": "elasticity"; the report's sections are elastic_report.py's.

Checks (each a list of problems; a check that does not apply says why):

* exact data (with [exact], run first): the scene's exact data are those of an exact solution
  (elastic_exactdata.py: Hooke's law, equilibrium, g, t, the fixed points, the crack's conditions
  and given opening, slip, pressure, the SIFs against the exact stress's near-tip limits). When
  they are not, the verdict is FAIL with the scene as its cause (verdict_cause "scene"), and the
  checks measured against them (series, active set) are not judged: their problems say nothing of
  the references.
* completeness: every level of the scene copy's [discretization] levels has a case of every
  reference its [outputs] references ask for (default both), and every summary names the scene.
* reference status: each case's status is "converged" and its KKT residuals are numbers
  ≤ KKT_TOLERANCE (the scalar references' tolerance).
* crack outputs: each reference's crack file against its own u: opening and slip equal
  (u⁺ − u⁻)·ν_j and ·τ_j to CRACK_ROUNDOFF × ‖u‖∞ (one subtraction and one dot product in either
  code: a few ulps), the tips' rows 0, the active rows closed (|opening| within the same
  round-off) with a force ≥ −tol, the other rows with force 0 and opening ≥ −tol, tol =
  KKT_TOLERANCE · max(1, ‖λ‖∞, ‖w‖∞) (the active-set method's own stopping scale).
* viewer datasets: each reference's field files (fields.h5, fields/*.xdmf) hold its own u, crack
  fields and mesh bit for bit and the stress σ(u_h) of its u to round-off (elastic_fields.py).
* reference agreement (two references): per level max |u_a − u_b| ≤ U_AGREEMENT · ‖u‖∞, the
  same active flags at every row, the same SIFs to SIF_AGREEMENT · max |K| of the tip.
* series (with [exact]): each reference's errors per level and their rates against
  elastic_theory's orders, by rates.series_judgement (the scalar tool's rule: judged on the last
  two steps; fewer than three levels, or a rate still rising, cannot be judged yet).
* active set (with [exact]): a row whose reference flag differs from the exact contact status
  (closed: exact opening ≤ elastic_exact.CONTACT_TOL × max |u| on Γc) lies within FRONT_REACH rows
  of a row where the exact status changes along the crack (the discrete front may sit one cell
  off); anywhere else it is a problem. The mismatch length Σ m_j over the differing rows is printed.
* interpolation yardstick (with [exact]): each reference's energy error ‖u − u_h‖_a at every level
  is at most (1 + YARDSTICK_TOL) × the interpolant's ‖u − I_h u‖_a (Falk's lemma, constant 1:
  interpolation_yardstick); it does not apply where the exact contact status changes inside the
  crack. A bug that multiplies the error by a constant keeps every rate; this bound does not.
* SIF: every reference's K_I, K_II computed at its finest level (sif.sif_p1 on a fixed ring;
  their errors against the scene's exact SIFs are series above, their differences part of the
  agreement).

Printed, not judged: the nodal pressure error (it does not converge at a tip under slip: the
references' λ_j/m_j has a layer of amplitude ~h^{-1/2} at the node next to the tip, 0.0567 …
0.0547 over levels 0–3 of the closed crack with slip), the contact fronts, and each reference's
distance to its own finest level (the only measure of convergence without [exact]).
"""
import math
import os

import numpy as np

from . import (elastic_exact, elastic_exactdata, elastic_fields, elastic_read, elastic_sdm_verdict,
               elastic_theory, rates, render, theory, verdict)
from .exact import ExactError, Quadrature

KKT_TOLERANCE = 1e-10
# The two references solve the same discrete problem by the same active-set method to a stopping
# tolerance 1e-12 of the problem's scale: the agreement target (1e-9 relative in u,
# identical active sets, SIFs to 1e-8).
U_AGREEMENT = 1e-9
SIF_AGREEMENT = 1e-8
# A SIF's scale where K itself is 0 (a closed patch): the K a stress of the field's size gives on the
# ring, max |σ(u_h)| √(2π r_out). The interaction integral sums up to ~1e5 terms of that size, so its
# round-off is up to ~1e5 ε of it: SIF errors below SIF_ROUNDOFF × the scale count as exact (0), and
# the agreement is measured relative to max(|K|, the scale).
SIF_ROUNDOFF = 1e-11
# 64 ε: the references compute the opening by one subtraction and one dot product; 64 ulps of
# ‖u‖∞ cover both codes' orders of operations with room, and a wrong copy or sign is O(‖u‖).
CRACK_ROUNDOFF = 64 * np.finfo(float).eps
# Rows on either side of an exact contact front where a reference's flag may differ from the
# exact status: the exact opening grows as d^{3/2} and the pressure as d^{1/2} away from the
# front, below the discretisation error within one cell of it.
FRONT_REACH = 1
QUANTITIES = ("u_l2", "u_h1", "sigma_l2", "opening_l2", "slip_l2")
CHECKS = ("exact data", "completeness", "reference status", "crack outputs", "viewer datasets",
          "reference agreement", "series", "active set", "interpolation yardstick", "SIF",
          "solver cases", "independent errors", "solver series", "solver SIF", "patch test",
          "δ → 0")
YARDSTICK_LABEL = "interpolation yardstick"
# ‖u − u_h‖_a ≤ (1 + YARDSTICK_TOL) ‖u − I_h u‖_a (Falk's lemma with v_h = I_h u: constant 1,
# interpolation_yardstick). What the bound leaves out, each far below 1e-6 relative: the error
# quadrature of both norms (the doubled rule moves them by ≤ 7e-13 relative, measured on
# williams-open, griffith, closed-slip-graded at levels 0 and 3), the tip limit of I_h u
# (elastic_exact.TIP_LIMIT_STEP: ≤ 4e-11), the references' load quadrature (ℓ_h − ℓ)(I_h u − u_h)
# (f by a degree-16 rule, tractions by a degree-19 one: ~h¹⁷ of a smooth load's derivatives; 0
# where f = 0 and g is given on all of ∂Ω) and their stopping tolerance and round-off (KKT residuals
# ≤ 1e-10; the two references' ratios differ by ≤ 2.2e-16). The measured ratios are 0.75–0.83 on
# every repository scene with [exact] (docs/elasticity.md): a constant-factor bug (a Lamé constant,
# a load scaled, an error × 1.5 that keeps every rate) is O(1) above the bound.
YARDSTICK_TOL = 1e-6


def mesh_parameter(level, graded):
    """h (the largest triangle diameter) of a level, or N^{-1/2} on graded meshes (N = 2 × the
    cracked mesh's vertices)."""
    if graded:
        return (2.0 * len(level.points)) ** -0.5
    X = level.points[level.triangles]
    return float(max(np.hypot(*(X[:, i] - X[:, (i + 1) % 3]).T).max() for i in range(3)))


# ------------------------------------------------------------------------------ the checks

def completeness(res):
    probs = []
    sf = res["scene_file"]
    asked = (sf.get("outputs") or {}).get("references", list(elastic_read.REFERENCE_TOOLS))
    levels = sorted(res["levels"])
    for tool in asked:
        if tool not in res["refs"]:
            probs.append(f"the scene asks for {tool}, but the folder has no {tool}/summary.json")
            continue
        summary, by_level = res["refs"][tool]
        missing = [L for L in levels if L not in by_level]
        if missing:
            probs.append(f"{tool} has no case at level(s) {', '.join(map(str, missing))}")
        if summary.get("scene") != res["scene"]:
            probs.append(f"{tool}/summary.json names scene {summary.get('scene')!r}, the folder "
                         f"{res['scene']!r}")
    if sf.get("name") != res["scene"]:
        probs.append(f"scene.toml names {sf.get('name')!r}, summary.json {res['scene']!r}")
    return probs


def reference_status(res):
    probs = []
    for tool, (_, by_level) in sorted(res["refs"].items()):
        for L, r in sorted(by_level.items()):
            c = r.case
            if c.get("status") != "converged":
                probs.append(f"{tool} level {L}: status {c.get('status')!r}, not 'converged'")
            kkt = c.get("kkt")
            for k in ("equations", "primal", "dual", "complementarity"):
                v = kkt.get(k) if isinstance(kkt, dict) else None
                if not (isinstance(v, (int, float)) and math.isfinite(v) and v <= KKT_TOLERANCE):
                    probs.append(f"{tool} level {L}: KKT {k} {render.fmt(v)} not a number "
                                 f"≤ {KKT_TOLERANCE:g}")
    return probs


def crack_output_problems(tool, L, level, ref):
    """The crack file of one reference level against its own u (module documentation)."""
    u, crack = ref.u, ref.crack
    j = u[level.pairs[:, 0]] - u[level.pairs[:, 1]]
    nu = level.normals
    opening = j[:, 0] * nu[:, 0] + j[:, 1] * nu[:, 1]
    slip = j[:, 0] * nu[:, 1] - j[:, 1] * nu[:, 0]
    roundoff = CRACK_ROUNDOFF * max(float(np.abs(u).max(initial=0.0)), np.finfo(float).tiny)
    probs = []
    for name, mine, col in (("opening", opening, 0), ("slip", slip, 1)):
        d = np.abs(crack[:, col] - mine)
        if d.max(initial=0.0) > roundoff:
            k = int(d.argmax())
            probs.append(f"{tool} level {L}: row {k}'s {name} {crack[k, col]:.17g} differs from "
                         f"(u⁺ − u⁻)·{'ν' if col == 0 else 'τ'} = {mine[k]:.17g} of its u (by "
                         f"{d[k]:.2e} > {roundoff:.2e})")
    tips = level.tip_rows()
    if np.abs(crack[tips]).max(initial=0.0) != 0.0:
        probs.append(f"{tool} level {L}: a tip's row is not 0 0 0 0")
    force, active = crack[:, 2], crack[:, 3]
    if not np.isin(active, (0.0, 1.0)).all():
        probs.append(f"{tool} level {L}: an active flag is neither 0 nor 1")
        return probs
    tol = KKT_TOLERANCE * max(1.0, float(np.abs(force).max(initial=0.0)),
                              float(np.abs(crack[:, 0]).max(initial=0.0)))
    on, off = active == 1.0, active == 0.0
    for what, bad in (
            ("active but open", on & (np.abs(crack[:, 0]) > roundoff)),
            ("active with a negative contact force", on & (force < -tol)),
            ("inactive with a contact force", off & (np.abs(force) > tol)),
            ("inactive and interpenetrating", off & (crack[:, 0] < -tol))):
        if bad.any():
            k = int(np.flatnonzero(bad)[0])
            probs.append(f"{tool} level {L}: {int(bad.sum())} row(s) {what} (first row {k}: "
                         f"opening {crack[k, 0]:.3e}, force {force[k]:.3e}, tolerance "
                         f"{tol:.1e})")
    return probs


def crack_outputs(res):
    return [p for tool, (_, by_level) in sorted(res["refs"].items())
            for L, r in sorted(by_level.items())
            for p in crack_output_problems(tool, L, res["levels"][L], r)]


def agreement(res, sifs, scales=None):
    """(rows, problems) of the two references per level; `scales` {(tool, L): SIF scale}
    (SIF_ROUNDOFF's comment)."""
    scales = scales or {}
    tools = sorted(res["refs"])
    if len(tools) < 2:
        return [], []
    a, b = tools[:2]
    rows, probs = [], []
    for L in sorted(res["levels"]):
        ra, rb = res["refs"][a][1].get(L), res["refs"][b][1].get(L)
        if ra is None or rb is None:
            continue
        scale = max(float(np.abs(ra.u).max(initial=0.0)), float(np.abs(rb.u).max(initial=0.0)))
        du = float(np.abs(ra.u - rb.u).max(initial=0.0))
        rel = du / scale if scale > 0 else du
        flags = int(np.sum(ra.crack[:, 3] != rb.crack[:, 3]))
        sif_rel = None
        ka, kb = sifs.get((a, L)), sifs.get((b, L))
        if ka is not None and kb is not None:
            floor = max(scales.get((a, L), 0.0), scales.get((b, L), 0.0), np.finfo(float).tiny)
            sif_rel = max((max(abs(x[0] - y[0]), abs(x[1] - y[1]))
                           / max(abs(x[0]), abs(x[1]), abs(y[0]), abs(y[1]), floor))
                          for x, y in zip(ka, kb)) if ka else 0.0
        rows.append({"level": L, "u_rel": rel, "flags_differ": flags, "sif_rel": sif_rel})
        if rel > U_AGREEMENT:
            probs.append(f"level {L}: {a} and {b} differ in u by {rel:.2e} of ‖u‖∞ "
                         f"(> {U_AGREEMENT:g})")
        if flags:
            probs.append(f"level {L}: {a} and {b} differ in {flags} active flag(s)")
        if sif_rel is not None and sif_rel > SIF_AGREEMENT:
            probs.append(f"level {L}: {a} and {b} differ in a SIF by {sif_rel:.2e} of the tip's "
                         f"largest |K| (> {SIF_AGREEMENT:g})")
    return rows, probs


# ------------------------------------------------------------------------------ exact errors

# An error at most this fraction of the exact field's own norm (the same quantity's; for the
# opening and slip, the larger of theirs and ‖u‖_{L²}) is round-off, taken as 0: a field P1
# represents exactly (the patch test) leaves the solver's round-off, ~κ(K) ε ‖u‖ with κ(K) ~ h^-2
# ≤ 1e6 at the nightly's levels (≤ 1e-10), which grows from level to level and would read as a
# growing error; a discretisation error of 1e-10 relative is far below any level run.
ROUNDOFF_REL = 1e-10


def exact_errors(res, ex, graded):
    """{(tool, L): errors}, {L: interpolation errors}, {L: CrackExact}, per-level h, and
    {L: the exact field's norms} (the zero field's errors)."""
    material = res["mesh_scene"]["problem"]
    errors, interp, crack_exact, h, size = {}, {}, {}, {}, {}
    quad = Quadrature()
    for L, level in sorted(res["levels"].items()):
        h[L] = mesh_parameter(level, graded)
        zero = np.zeros((len(level.points), 2))
        refs = {tool: by_level[L] for tool, (_, by_level) in res["refs"].items() if L in by_level}
        fields = {("ref", tool): elastic_exact.p1_field(level, r.u) for tool, r in refs.items()}
        fields["interpolant"] = elastic_exact.interpolant_field(level, ex)
        fields["zero"] = elastic_exact.p1_field(level, zero)
        dom = elastic_exact.domain_errors(level, ex, fields, material, quad)
        interp[L] = dom["interpolant"]
        ce = crack_exact[L] = elastic_exact.CrackExact(level, ex, quad)
        size[L] = dict(dom["zero"], **ce.jump_errors(*ce.nodal_jumps(zero)))
        for tool, r in refs.items():
            e = dict(dom[("ref", tool)], **ce.jump_errors(*ce.nodal_jumps(r.u)))
            e["pressure_l2"] = ce.pressure_error(r.crack[:, 2])
            errors[(tool, L)] = e
    return errors, interp, crack_exact, h, size


def exact_front_levels(res, crack_exact):
    """The levels whose exact contact status changes along a crack between two rows that both have
    two copies and are not mouths (a contact front inside the crack)."""
    out = []
    for L, ce in sorted(crack_exact.items()):
        keep = ce.judged_rows()
        status = dict(zip(ce.rows[keep].tolist(), ce.closed[keep].tolist()))
        for first, n in res["levels"][L].ranges:
            flags = [status[r] for r in range(first, first + n) if r in status]
            if len(set(flags)) > 1:
                out.append(L)
                break
    return out


def interpolation_yardstick(res, a, crack_exact, size):
    """The interpolation yardstick's check row: every reference's energy error ‖u − u_h‖_a at every
    level is at most (1 + YARDSTICK_TOL) ‖u − I_h u‖_a, I_h u the exact u at the cracked mesh's
    vertices (elastic_exact.vertex_interpolant), both in the energy norm a(w, w) = ∫ σ(w):ε(w).

    Falk's lemma (docs/elasticity.md *The interpolation yardstick*): u minimises ½a − ℓ over K
    ([v·ν] ≥ 0 on Γc), u_h over K_h (P1, v = I_h g on Γ_D, nodal [v·ν] ≥ 0). For v_h = I_h u,
    which shares u_h's Dirichlet values, with e = u − u_h and w = v_h − u_h (w = 0 on Γ_D):
        a(e, e) = a(e, u − v_h) + a(u, w) − a(u_h, w) ≤ a(e, u − v_h) + a(u, w) − ℓ(w)
    (the discrete inequality a(u_h, w) ≥ ℓ(w)), and Green's formula gives a(u, w) − ℓ(w) =
    ∫_Γc p [w·ν] ds, p = −σ_νν(u) ≥ 0, p [u·ν] = 0. [u_h·ν] ≥ 0 on the whole of each straight
    segment (linear between nonnegative nodal values), so
        ‖e‖_a² ≤ a(e, u − v_h) + ∫_Γc p ([v_h·ν] − [u·ν]) ≤ ½‖e‖_a² + ½‖u − v_h‖_a² + ∫ p [I_h u·ν].
    The contact term vanishes where the exact crack is open (p = 0) and where it is closed along
    whole segments ([u·ν] = 0 at the nodes, so [I_h u·ν] = 0): then ‖e‖_a ≤ ‖u − I_h u‖_a with
    constant 1, whatever the regularity or the mesh. With a contact front inside the crack the term
    is positive on the front's segment and the check does not apply. An error within the round-off
    floor (the patch test: u_h = u = I_h u) counts as 0."""
    what = (f"every reference's energy error ‖u − u_h‖_a ≤ (1 + {YARDSTICK_TOL:g}) × "
            "‖u − I_h u‖_a on the same mesh (Falk's lemma: constant 1)")
    front = exact_front_levels(res, crack_exact)
    a["yardstick"] = []
    if front:
        return (YARDSTICK_LABEL, what, [], f"the exact contact status changes inside the crack at "
                f"level(s) {', '.join(map(str, front))}: Falk's contact term ∫ p [I_h u·ν] is "
                "positive on the front's segment, so the interpolation error bounds nothing")
    probs = []
    for (tool, L), e in sorted(a["errors"].items()):
        y = a["interpolation"][L]["u_a"]
        floor = ROUNDOFF_REL * size[L]["u_a"]
        ok = e["u_a"] <= (1 + YARDSTICK_TOL) * y + floor
        ratio = e["u_a"] / y if y > floor else None
        a["yardstick"].append({"tool": tool, "level": L, "error": e["u_a"], "interpolation": y,
                               "ratio": ratio, "ok": bool(ok)})
        if not ok:
            probs.append(f"{tool} level {L}: ‖u − u_h‖_a = {e['u_a']:.6e} > (1 + "
                         f"{YARDSTICK_TOL:g}) × ‖u − I_h u‖_a = {y:.6e} (ratio "
                         + (f"{ratio:.6f})" if ratio is not None else "— : I_h u exact)"))
    if not a["yardstick"]:
        probs.append("could not run: no reference level with stored fields")
    return YARDSTICK_LABEL, what + f" ({len(a['yardstick'])} level × reference rows)", probs, None


def roundoff_floor(size, q):
    """ROUNDOFF_REL × the exact field's norm of quantity q at one level (size: its zero-field
    errors)."""
    ref = size[q] if q in ("u_l2", "u_h1", "sigma_l2") else max(size[q], size["u_l2"])
    return ROUNDOFF_REL * ref


def regularity(interp, h, graded, size):
    lv = sorted(interp)
    if lv and all(interp[L]["u_h1"] <= roundoff_floor(size[L], "u_h1") for L in lv):
        return theory.SMOOTH_S, ("the exact u is P1 on every triangle: its interpolation error is "
                                 "round-off; P1's orders apply (s = 1)")
    rate = (rates.rate(h[lv[-2]], interp[lv[-2]]["u_h1"], h[lv[-1]], interp[lv[-1]]["u_h1"])
            if len(lv) >= 2 else None)
    return theory.regularity(rate, True, None, graded)


def series(res, errors, sif_errors, h, s, size):
    """One series per reference and judged quantity (the SIF errors per tip and factor too); a
    field error within roundoff_floor is taken as 0."""
    out = []
    for tool in sorted(res["refs"]):
        names = list(QUANTITIES) + sorted({q for (t, _, q) in sif_errors if t == tool})
        for q in names:
            pts = []
            for L in sorted(res["levels"]):
                if q in QUANTITIES and (tool, L) in errors:
                    e = errors[(tool, L)][q]
                    pts.append((L, h[L], 0.0 if e <= roundoff_floor(size[L], q) else e))
                elif (tool, L, q) in sif_errors:
                    pts.append((L, h[L], sif_errors[(tool, L, q)]))
            levels, hs, es = [p[0] for p in pts], [p[1] for p in pts], [p[2] for p in pts]
            order, reason = elastic_theory.expected_order(q, s)
            t = elastic_theory.threshold(order)
            status, why, up_to = rates.series_judgement(hs, es, levels, t)
            out.append({"tool": tool, "quantity": q, "levels": levels, "h": hs, "errors": es,
                        "rates": rates.successive_rates(hs, es), "expected": order,
                        "threshold": t, "order_reason": reason, "status": status,
                        "reason": why, "run_levels_up_to": up_to})
    return out


def exact_fronts(level, ce):
    """Rows (of crack.txt) beside which the exact contact status changes, per crack."""
    closed = dict(zip(ce.rows.tolist(), ce.closed.tolist()))
    near = set()
    for first, n in level.ranges:
        rows = [r for r in range(first, first + n) if r in closed]
        for r0, r1 in zip(rows, rows[1:]):
            if closed[r0] != closed[r1]:
                near |= set(range(r0 - FRONT_REACH, r1 + FRONT_REACH + 1))
    return near


def discrete_fronts(level, flags):
    """The points on the crack where a reference's active flags change (midpoints of the
    segments whose ends differ), crack by crack."""
    c = level.nodes()
    keep = level.pair_rows()
    keep[level.mouth_rows()] = False
    out = []
    for first, n in level.ranges:
        rows = [r for r in range(first, first + n) if keep[r]]
        for r0, r1 in zip(rows, rows[1:]):
            if flags[r0] != flags[r1]:
                out.append(tuple(float(v) for v in 0.5 * (c[r0] + c[r1])))
    return out


def active_set(res, crack_exact):
    """(rows, problems): per reference and level the mismatch length and the rows outside the
    exact front's reach."""
    rows, probs = [], []
    for tool, (_, by_level) in sorted(res["refs"].items()):
        for L, r in sorted(by_level.items()):
            level, ce = res["levels"][L], crack_exact[L]
            keep = ce.judged_rows()
            flags = r.crack[ce.rows, 3] == 1.0
            differ = (flags != ce.closed) & keep
            m = level.nodal_measure()[ce.rows]
            near = exact_fronts(level, ce)
            far = [int(row) for row in ce.rows[differ] if int(row) not in near]
            rows.append({"tool": tool, "level": L, "mismatch_rows": int(differ.sum()),
                         "mismatch_length": float(m[differ].sum()), "far_rows": len(far),
                         "exact_closed_rows": int((ce.closed & keep).sum()),
                         "reference_active_rows": int((flags & keep).sum())})
            if far:
                probs.append(f"{tool} level {L}: {len(far)} row(s) flagged "
                             f"{'active' if flags[list(ce.rows).index(far[0])] else 'open'} "
                             f"against the exact contact status, farther than {FRONT_REACH} "
                             f"row(s) from any exact front (first row {far[0]})")
    return rows, probs


def fronts(res):
    """Per reference and level the discrete contact fronts."""
    return [{"tool": tool, "level": L,
             "fronts": discrete_fronts(res["levels"][L], r.crack[:, 3] == 1.0)}
            for tool, (_, by_level) in sorted(res["refs"].items())
            for L, r in sorted(by_level.items())]


# ------------------------------------------------------------------------------ SIFs

# The interaction integral's ring, as fractions of the distance R from the tip to the nearest point
# of the outer boundary or another crack: the same ring at every level (the geometry's), so the SIF
# series measures the discretisation alone. sif.sif_p1 sets q_h = 1 on the tip's triangles, so the
# ring suits every level; a level whose mesh cannot carry it (sif_p1's ValueError: the tip no
# vertex, the disc meeting ∂Ω or another crack) has no SIF, and the report says why.
RING = (0.4, 0.8)


def sif_ring(level):
    """(r_in, r_out) per tip: RING × R (above)."""
    from .exact import _point_segment_distance, boundary_edges

    P = level.points
    edges = boundary_edges(level.triangles, P)
    on_crack = np.zeros(len(P), dtype=bool)
    on_crack[level.pairs.ravel()] = True
    outer = edges[~(on_crack[edges[:, 0]] & on_crack[edges[:, 1]])]
    nodes = level.nodes()
    out = []
    for k, (tip, _) in enumerate(level.tip_frames()):
        R = float(_point_segment_distance(tip, P[outer[:, 0]], P[outer[:, 1]]).min())
        first, n = level.ranges[_crack_of_tip(level, k)]
        rest = np.delete(nodes, np.arange(first, first + n), axis=0)
        if len(rest):
            R = min(R, float(np.hypot(*(rest - tip).T).min()))
        out.append((RING[0] * R, RING[1] * R))
    return out


def _crack_of_tip(level, k):
    """The crack (index into level.ranges) of the k-th tip."""
    i = 0
    for c, (tf, tl) in enumerate(level.tip_ends):
        for is_tip in (tf, tl):
            if is_tip:
                if i == k:
                    return c
                i += 1
    raise IndexError(k)


def _body_force(mesh_scene):
    """f as a callable of (x, y) -> (2, …) for sif.sif_p1, or None where f = 0."""
    from sdshared import sdexpr

    f = mesh_scene.get("f") or ["0", "0"]
    trees = [sdexpr.parse(c) for c in f]
    if all(t[0] == "num" and t[1] == 0.0 for t in trees):
        return None
    fns = [sdexpr.to_numpy(t) for t in trees]
    return lambda x, y: np.stack([fn(x, y) for fn in fns])


def _exact_pressure(ex, e1):
    """The exact contact pressure p(x, y) on the crack line behind a tip (crack_values with the
    tip frame's e₂ as normal: −ν·σν does not depend on ν's sign)."""
    e2 = np.array([-e1[1], e1[0]], dtype=float)

    def p(x, y):
        x, y = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        xy = np.column_stack([x.ravel(), y.ravel()])
        return ex.crack_values(xy, np.tile(e2, (len(xy), 1)))["pressure"].reshape(x.shape)

    return p


def compute_sifs(res, ex=None):
    """({(tool, L): [(K_I, K_II) per tip]}, {(tool, L): why not computed}, why none at all or
    None): sif.sif_p1 on each reference's u with the scene's body force and, in the crack-face
    term, the exact pressure where the scene has [exact] (`ex`), else the reference's own nodal
    pressure λ_j/m_j. Why the exact one: the references' nodal pressure has a layer at the tip of
    amplitude ~h^{-1/2} over a few nodes (closed crack with slip, levels 2, 3: λ_j/m_j − p = −0.21,
    −0.30 at the node next to the tip), whose r^{-1/2}-weighted integral in the face term stays
    constant (K_I −0.118, −0.115, −0.114 instead of 0 on levels 1–3; with the exact pressure
    −1.4e-3, −2.4e-4, −5.3e-5), so K with it would not converge."""
    try:
        from . import sif
    except ImportError:
        return {}, {}, "compare/sdcompare_lib/sif.py (the interaction integral) is not in this checkout"
    ms = res["mesh_scene"]
    material, force = ms["problem"], _body_force(ms)
    out, skipped, scales = {}, {}, res.setdefault("sif_scales", {})
    for L, level in sorted(res["levels"].items()):
        rings, frames, m = sif_ring(level), level.tip_frames(), level.nodal_measure()
        nodes, tips = level.nodes(), set(level.tip_rows().tolist())
        for tool, (_, by_level) in res["refs"].items():
            r = by_level.get(L)
            if r is None:
                continue
            ks = []
            for k, ((tip, e1), (r_in, r_out)) in enumerate(zip(frames, rings)):
                first, n = level.ranges[_crack_of_tip(level, k)]
                rows = [j for j in range(first, first + n) if j not in tips]
                face = (_exact_pressure(ex, e1) if ex is not None else
                        sif.pressure_along_crack(nodes[rows], r.crack[rows, 2] / m[rows], tip, e1))
                try:
                    ks.append(tuple(float(v) for v in sif.sif_p1(
                        level.points, level.triangles, r.u, material, tip, e1, r_in, r_out,
                        face_pressure=face, body_force=force)))
                except ValueError as exc:
                    skipped[(tool, L)] = f"tip {k + 1}: {exc}"
                    break
            else:
                out[(tool, L)] = ks
                sig = elastic_exact.hooke(elastic_exact.p1_gradients(
                    level.points, level.triangles, r.u), material)
                scales[(tool, L)] = float(np.abs(sig).max(initial=0.0)) * math.sqrt(
                    2 * math.pi * max((ring[1] for ring in rings), default=0.0))
    return out, skipped, None


def sif_errors(sifs, exact_sif, scales=None):
    """{(tool, L, "K_I tip k" / "K_II tip k"): |K_h − K|} against the scene's exact SIFs; an error
    below SIF_ROUNDOFF × the level's SIF scale is round-off, taken as 0."""
    out = {}
    if not exact_sif:
        return out
    scales = scales or {}
    for (tool, L), ks in sifs.items():
        floor = SIF_ROUNDOFF * scales.get((tool, L), 0.0)
        for k, (kh, ke) in enumerate(zip(ks, exact_sif)):
            for name, i in (("K_I", 0), ("K_II", 1)):
                e = abs(kh[i] - ke[i])
                out[(tool, L, f"{name} tip {k + 1}")] = 0.0 if e <= floor else e
    return out


# ------------------------------------------------------------------------------ analysis

def analyse(res):
    """The analysis dict the report and the verdict read."""
    ms = res["mesh_scene"]
    has_exact = isinstance(ms.get("exact"), dict)
    graded = any(lv.kind == "graded" for lv in res["levels"].values())
    a = {"scene": res["scene"], "has_exact": has_exact, "graded": graded,
         "levels": sorted(res["levels"]), "tools": sorted(res["refs"])}
    checks = [exact_data_check(a, ms)]
    checks.append(("completeness", "every level of the scene has a case of every reference it "
                   "asks for, and every summary names the scene", completeness(res), None))
    checks.append(("reference status", f"every reference case converged with KKT residuals "
                   f"≤ {KKT_TOLERANCE:g}", reference_status(res),
                   None if res["refs"] else "no reference in the folder"))
    checks.append(("crack outputs", "each reference's opening and slip are those of its own u to "
                   f"{CRACK_ROUNDOFF:.1e} ‖u‖∞, tips 0, active rows closed with a force ≥ 0, the "
                   "others free of force", crack_outputs(res),
                   None if res["refs"] else "no reference in the folder"))
    checks.append(("viewer datasets", *elastic_fields.viewer_datasets(res)))
    ex = None
    if has_exact:
        try:
            ex = elastic_exact.ElasticExact(ms["exact"], ms["problem"])
        except ExactError as exc:
            raise elastic_read.InputError(f"{res['folder']}/mesh/scene.json: {exc}")
    a["sif_pressure"] = "exact" if ex is not None else "references' own λ_j/m_j"
    sifs, a["sif_skipped"], a["sif_missing"] = compute_sifs(res, ex)
    a["sifs"] = {f"{t} {L}": v for (t, L), v in sifs.items()}
    a["sif_by_key"] = sifs
    a["agreement"], agree_probs = agreement(res, sifs, res.get("sif_scales"))
    checks.append(("reference agreement", f"the two references' u within {U_AGREEMENT:g} of ‖u‖∞, "
                   f"the same active flags and SIFs within {SIF_AGREEMENT:g} at every level",
                   agree_probs, None if len(res["refs"]) >= 2 else
                   f"{len(res['refs'])} reference(s) in the folder: nothing to compare"))
    a["fronts"] = fronts(res)
    a["undecided"] = {}
    if has_exact:
        a["errors"], a["interpolation"], crack_exact, a["h"], size = exact_errors(res, ex, graded)
        a["s"], a["s_reason"] = regularity(a["interpolation"], a["h"], graded, size)
        a["sif_errors"] = sif_errors(sifs, ms["exact"].get("sif"), res.get("sif_scales"))
        a["series"] = series(res, a["errors"], a["sif_errors"], a["h"], a["s"], size)
        bad = [f"{s['tool']} {s['quantity']}: {s['reason']}" for s in a["series"]
               if s["status"] == "does not converge"]
        pending = [f"{s['tool']} {s['quantity']}: {s['reason']}" for s in a["series"]
                   if s["status"] == "inconclusive"]
        a["undecided"]["series"] = pending
        checks.append(("series", "every reference's series converges at the order "
                       "elastic_theory gives for its regularity (the scalar tool's rule)",
                       bad, None))
        a["active_set"], active_probs = active_set(res, crack_exact)
        checks.append(("active set", "every reference's active flag equals the exact contact "
                       f"status except within {FRONT_REACH} row(s) of an exact front",
                       active_probs, None))
        checks.append(interpolation_yardstick(res, a, crack_exact, size))
    else:
        a["errors"], a["series"], a["active_set"], a["h"] = {}, [], [], {
            L: mesh_parameter(lv, graded) for L, lv in res["levels"].items()}
        why = "no [exact] in the scene: the references are compared with each other and with their finest level"
        checks.append(("series", "", [], why))
        checks.append(("active set", "", [], why))
        checks.append((YARDSTICK_LABEL, "", [], "no [exact] in the scene: no interpolant to "
                       "measure the references' energy error against"))
    checks.append(sif_check(res, a, sifs))
    checks.extend(solver_checks(res, a, ex, size if has_exact else None))
    a["finest"] = finest_distances(res, a, sifs)
    a["field_distances"] = field_distances(res)
    checks = a["checks"] = elastic_exactdata.not_judged(checks, a["exact_data"])
    a["verdict"], a["reasons"] = verdict.decide(
        [(label, p) for label, _, p, _ in checks],
        [(k, v) for k, v in a["undecided"].items() if v])
    ups = [s["run_levels_up_to"] for s in a["series"] if s["status"] == "inconclusive"
           and s["run_levels_up_to"] is not None]
    a["run_levels_up_to"] = max(ups) if ups and a["verdict"] == "INCONCLUSIVE" else None
    a["verdict_cause"] = verdict_cause(a)
    return a


def solver_checks(res, a, ex, size):
    """The rows of the smooth-domain method's checks (elastic_sdm_verdict.py); a["sdm"] keeps
    their numbers (recomputed errors, series, ratios) for the report."""
    sv = elastic_sdm_verdict
    rows = [sv.solver_cases(res)]
    sdm = a["sdm"] = {"cases": len(res.get("sdm") or []), "series": [], "independent": [],
                      "ratios": [], "delta": [], "fronts": [], "sentences": []}
    if not res.get("sdm"):
        why = "summary.json has no elastic solver case"
        return rows + [(label, "", [], why) for label in
                       ("independent errors", "solver series", "solver SIF", "patch test", "δ → 0")]
    rows.append(sv.delta_limit(res, a))
    sdm["fronts"] = sv.fronts(res, a["fronts"])
    sdm["sentences"] = sv.front_sentences(sdm["fronts"])
    if ex is None:
        why = "no [exact] in the scene: nothing to recompute the solver's errors against"
        return rows + [(label, "", [], why) for label in
                       ("independent errors", "solver series", "solver SIF", "patch test")]
    rec = sdm["recomputed"] = sv.recompute_all(res, ex)
    row, sdm["independent"] = sv.independent_errors(res, rec)
    rows.append(row)
    rings = {L: sif_ring(lv) for L, lv in res["levels"].items() if lv.tip_rows().size}
    sifs, sdm["sif_skipped"] = sv.sdm_sifs(res, rings, _body_force(res["mesh_scene"]),
                                           lambda e1: _exact_pressure(ex, e1))
    sdm["sifs"] = [{"level": res["sdm"][i].level, "multiplier": res["sdm"][i].multiplier,
                    "K": ks} for i, ks in sorted(sifs.items())]
    sdm["series"] = sv.series(res, rec, a["h"], a["s"],
                              sv.sif_errors(sifs, res["mesh_scene"]["exact"].get("sif")))
    judged = [s for s in sdm["series"] if not s["quantity"].startswith("K_")]
    bad = [f"{s['tool']} {s['quantity']}: {s['reason']}" for s in judged
           if s["status"] == "does not converge"]
    a["undecided"]["solver series"] = [f"{s['tool']} {s['quantity']}: {s['reason']}"
                                       for s in judged if s["status"] == "inconclusive"]
    for s in sdm["series"]:
        if s["quantity"].startswith("K_"):
            s["status"] = f"printed ({s['status']}; the solver SIF check judges the finest level)"
    rows.append(("solver series", "every solver series (recomputed errors) converges at the "
                 "order elastic_theory gives the smooth-domain method for the regularity s",
                 bad, None if sdm["series"] else "no solver case at a level of the mesh export"))
    rows.append(sv.sif_check(res, sifs, sdm["sif_skipped"], res["mesh_scene"]["exact"].get("sif"),
                             rings, SIF_ROUNDOFF))
    exact_p1 = all(v["u_h1"] <= roundoff_floor(size[L], "u_h1")
                   for L, v in a["interpolation"].items())
    rows.append(sv.patch_test(res, rec, exact_p1))
    sdm["ratios"] = sv.ratios(res, rec, a["errors"])
    a["series"].extend(sdm["series"])
    sdm["sentences"] = sv.sentences(res, a) + sdm["sentences"]
    return rows


def exact_data_check(a, mesh_scene):
    """The exact-data check's row (run first): the scene.json's exact data checked by
    elastic_exactdata; a["exact_data"] keeps its problems (key and sentence each). A scene.json
    whose entries cannot be read is bad input (exit 2)."""
    try:
        found, checked = elastic_exactdata.check_scene(mesh_scene)
    except elastic_exactdata.SceneError as exc:
        raise elastic_read.InputError(f"mesh/{exc}")
    a["exact_data"] = found
    return (elastic_exactdata.LABEL, elastic_exactdata.REQUIREMENT
            + (f" ({checked})" if checked else ""), [p.sentence for p in found],
            None if a["has_exact"] else "the scene has no [exact]")


def verdict_cause(a):
    """What a verdict is attributed to (the scalar tool's rule): "scene" when the scene's exact
    data are inconsistent, "results" for any other FAIL, "levels" for INCONCLUSIVE, None on PASS."""
    if a["verdict"] == "PASS":
        return None
    if a["verdict"] == "INCONCLUSIVE":
        return "levels"
    return "scene" if a["exact_data"] else "results"


def sif_check(res, a, sifs):
    """The SIF check's row: every reference's SIFs computed at its finest level (a coarser level
    whose tip triangles reach beyond the ring's inner radius is left out, and the report says so);
    judged against the scene's exact SIFs as series (above) and between the references
    (agreement)."""
    n_tips = sum(len(lv.tip_rows()) for lv in res["levels"].values())
    what = ("every reference's K_I, K_II computed at its finest level by the interaction integral "
            "(sif.py); their errors are series above where the scene gives exact SIFs")
    if a["sif_missing"]:
        return ("SIF", what, [f"not computed: {a['sif_missing']}"], None)
    if n_tips == 0:
        return ("SIF", what, [], "the cracks have no tip (every end is a mouth)")
    probs = []
    for tool, (_, by_level) in sorted(res["refs"].items()):
        if by_level and (tool, max(by_level)) not in sifs:
            probs.append(f"{tool} level {max(by_level)}: "
                         f"{a['sif_skipped'].get((tool, max(by_level)), 'not computed')}")
    return ("SIF", what, probs, None if res["refs"] else "no reference in the folder")


def _owners(res, coarse, fine):
    """`refinements` of norms.prolong_to_fine from level `coarse` to `fine`: None (structured,
    located by coordinates), the number of refinements (refined), or each fine triangle's
    ancestor (graded: parents.txt of every level between, composed)."""
    kind = res["levels"][fine].kind
    if kind == "refined":
        return kind, fine - coarse
    if kind == "graded":
        owner = np.arange(len(res["levels"][fine].triangles), dtype=np.int64)
        for lv in range(fine, coarse, -1):
            path = os.path.join(res["folder"], "mesh", f"level{lv}", "parents.txt")
            if not os.path.exists(path):
                raise elastic_read.InputError(f"missing file: {path} (a graded level's parents)")
            owner = np.loadtxt(path, dtype=np.int64, ndmin=1)[owner]
        return kind, owner
    return kind, None


def field_distances(res):
    """Per reference and level below its finest: ‖u_finest − u_L‖_{L²} and the broken H¹ seminorm
    of the difference, u_L evaluated exactly at the finest triangles' corners (norms.prolong_to_fine:
    each fine triangle in its coarse triangle, so a field broken across the crack is taken on the
    right face), both P1 on the finest mesh: exact, no quadrature."""
    from . import norms

    rows = []
    for tool, (_, by_level) in sorted(res["refs"].items()):
        if len(by_level) < 2:
            continue
        top = max(by_level)
        fine, uf = res["levels"][top], by_level[top].u
        area = norms.triangle_areas(fine.points, fine.triangles)
        grad_f = elastic_exact.p1_gradients(fine.points, fine.triangles, uf)
        _, _, G, _ = scalar_exact_geometry(fine)
        for L in sorted(by_level):
            if L == top:
                continue
            coarse = res["levels"][L]
            kind, how = _owners(res, L, top)
            try:
                corners = norms.prolong_to_fine(coarse.points, coarse.triangles, by_level[L].u,
                                                fine.points, fine.triangles, kind, how)
            except norms.NormError as exc:
                rows.append({"tool": tool, "level": L, "finest": top, "u_l2": None,
                             "u_h1": None, "note": str(exc)})
                continue
            d = uf[fine.triangles] - corners
            dg = grad_f - np.einsum("tvi,tvd->tid", corners, G)
            rows.append({"tool": tool, "level": L, "finest": top,
                         "u_l2": math.sqrt(norms._local_sq(area, d)),
                         "u_h1": math.sqrt(float(area @ np.einsum("tij,tij->t", dg, dg))),
                         "note": None})
    return rows


def scalar_exact_geometry(level):
    from .exact import _geometry

    return _geometry(level.points, level.triangles)


def finest_distances(res, a, sifs):
    """Per reference and level: the distance of its SIFs and contact fronts to its finest level's
    (printed for every scene; the only measure of convergence without [exact])."""
    rows = []
    fr = {(f["tool"], f["level"]): f["fronts"] for f in a["fronts"]}
    for tool, (_, by_level) in sorted(res["refs"].items()):
        if not by_level:
            continue
        top = max(by_level)
        for L in sorted(by_level):
            ks, kf = sifs.get((tool, L)), sifs.get((tool, top))
            dk = (max(max(abs(x[0] - y[0]), abs(x[1] - y[1])) for x, y in zip(ks, kf))
                  if ks and kf else None)
            f0, f1 = fr.get((tool, L), []), fr.get((tool, top), [])
            df = (max(math.hypot(p[0] - q[0], p[1] - q[1]) for p, q in zip(f0, f1))
                  if f0 and f1 and len(f0) == len(f1) else None)
            rows.append({"tool": tool, "level": L, "finest": top, "sif_distance": dk,
                         "front_distance": df, "fronts": len(f0)})
    return rows
