"""The report of an elastic scene (elastic.py's analysis): report.md, index.html, report.json and
the error plot, written with render.py's machinery (sections, atomic publication) and plots.py's
styles; `run` is what compare/sdcompare calls for a folder whose summary.json says
"problem": "elasticity"."""
import os

import matplotlib

from . import elastic, elastic_read, elastic_theory, rates, render, theory, verdict
from .render import fmt, fmt_rate
from .sections import check_status

TOOL_NAME = render.REFERENCE_NAMES
RULE_SOURCE = ("the regularity s of the exact u and P1's orders on the cracked mesh, "
               "compare/sdcompare_lib/elastic_theory.py")


def _status(a, label, problems, na):
    return check_status(problems, na, undecided=a["undecided"].get(label, ()))


def headline(a):
    """The verdict as the report's first words: the scene named first when it is the cause."""
    if a.get("verdict_cause") == "scene":
        return (f"{a['verdict']} (cause: the scene: its [exact] data are not those of an exact "
                f"solution; the references are not judged against them)")
    return a["verdict"]


def verdict_line(a):
    n = len(a["reasons"])
    if a["verdict"] == "INCONCLUSIVE":
        up = a["run_levels_up_to"]
        return (f"{a['scene']}: INCONCLUSIVE (cannot judge yet: {n} series"
                + (f"; run levels up to {up}" if up is not None else "")
                + f"; first: {a['reasons'][0]})")
    return f"{a['scene']}: {headline(a)}" + (f" ({n} problem(s); first: {a['reasons'][0]})"
                                             if n else "")


# ------------------------------------------------------------------------------ sections

def summary_section(a, images):
    paras = [f"**{verdict_line(a)}**",
             f"Elastic scene, references {', '.join(TOOL_NAME.get(t, t) for t in a['tools']) or 'none'}, "
             f"levels {', '.join(map(str, a['levels']))}"
             + (", graded meshes: rates per halving of N^-1/2 (N = 2 × the cracked mesh's "
                "vertices)." if a["graded"] else ", rates per halving of h.")]
    if a["has_exact"]:
        paras.append(f"Regularity of the exact u: s = {a['s']:g} ({a['s_reason']}).")
    checks = [[label, what or "–", _status(a, label, p, na)] for label, what, p, na in a["checks"]]
    series = [[TOOL_NAME.get(s["tool"], s["tool"]), s["quantity"], f"{s['expected']:g}",
               ", ".join(fmt_rate(r) for r in s["rates"]) or "–", s["status"]]
              for s in a["series"]]
    after = [f"Problem: {r}" for r in a["reasons"]]
    return {"title": "Verdict", "paras": paras, "lead_images": [i for i in images if i],
            "tables": [(["check", "requires", "status"], checks),
                       (["reference or solver", "series", "expected order", "rates", "status"], series)],
            "paras_after": after, "fold": False}


def series_section(a):
    if not a["has_exact"]:
        return {"title": "Errors against the exact fields",
                "paras": ["Not applicable: the scene has no [exact]."]}
    rows = []
    for s in a["series"]:
        rs = [None] + list(s["rates"])
        for L, h, e, r in zip(s["levels"], s["h"], s["errors"], rs):
            rows.append([TOOL_NAME.get(s["tool"], s["tool"]), s["quantity"], L, fmt(h), fmt(e),
                         fmt_rate(r), f"{s['expected']:g}"])
    pressure = [[TOOL_NAME.get(t, t), L, fmt(e["pressure_l2"])]
                for (t, L), e in sorted(a["errors"].items())]
    interp = [[L, fmt(v["u_l2"]), fmt(v["u_h1"]), fmt(v["sigma_l2"])]
              for L, v in sorted(a["interpolation"].items())]
    yard = [[TOOL_NAME.get(r["tool"], r["tool"]), r["level"], fmt(r["error"]),
             fmt(r["interpolation"]), "—" if r["ratio"] is None else f"{r['ratio']:.6f}"]
            for r in a.get("yardstick", [])]
    reasons = sorted({f"{s['quantity']}: {s['order_reason']}" for s in a["series"]})
    return {"title": "Errors against the exact fields",
            "paras": [f"Recomputed here from each reference's u and crack file (compare/sdcompare_lib/"
                      f"elastic_exact.py); an error within {elastic.ROUNDOFF_REL:g} of the exact "
                      f"field's own norm is round-off and shown as 0. Rule: {rates.rule_text(theory.RATE_MARGIN, source=RULE_SOURCE)}"],
            "tables": [(["reference or solver", "quantity", "level", "h", "error", "rate", "expected"], rows,
                        "errors and rates per reference, quantity and level"),
                       (["reference", "level", "pressure error"], pressure,
                        "the nodal pressure λ_j/m_j against the exact pressure (measured, not "
                        "judged)"),
                       (["level", "‖u − I_h u‖", "‖∇(u − I_h u)‖", "‖σ(I_h u) − σ‖"], interp,
                        "the P1 interpolant of the exact u"),
                       (["reference", "level", "‖u − u_h‖_a", "‖u − I_h u‖_a", "ratio"], yard,
                        "the interpolation yardstick: energy norms (∫ σ(w):ε(w))^{1/2} "
                        "(Falk's lemma: "
                        "ratio ≤ 1 where it applies; — where I_h u is exact)")],
            "paras_after": [f"Expected orders: {r}." for r in reasons]}


def solver_section(res, a):
    """The smooth-domain method's cases: the sentences against the references, the ratios on the
    same mesh, the independent recomputation and δ → 0 (elastic_sdm_verdict.py)."""
    from . import elastic_sdm_verdict as sv

    sdm = a.get("sdm") or {}
    if not sdm.get("cases"):
        return {"title": "The smooth-domain method",
                "paras": ["summary.json has no elastic solver case: the references alone are judged."]}
    paras = [f"{sdm['cases']} solver case(s). Their errors and rates are the series \"sdcrack …\" "
             "of *Errors against the exact fields*, recomputed here from fields.h5 "
             "(compare/sdcompare_lib/elastic_sdm.py)." if a["has_exact"] else
             f"{sdm['cases']} solver case(s); no [exact]: their errors are not recomputed."]
    paras += sdm.get("sentences", [])
    ratios = [[r["multiplier"], fmt(r["delta"]), r["level"], TOOL_NAME.get(r["tool"], r["tool"]),
               r["quantity"], fmt(r["sdm"]), fmt(r["reference"]),
               "—" if r["ratio"] is None else f"{r['ratio']:.4f}"] for r in sdm.get("ratios", [])]
    worst = {}
    for r in sdm.get("independent", []):
        key = (r["level"], r["multiplier"], r["delta"])
        d = abs(r["summary"] - r["recomputed"]) if isinstance(r["summary"], (int, float)) else None
        q = None if d is None else d / r["tolerance"] if r["tolerance"] > 0 else float("inf")
        if key not in worst or q is None or (worst[key][1] is not None and q > worst[key][1]):
            worst[key] = (r["error"], q)
    indep = [[L, m, fmt(d), e, "—" if q is None else f"{q:.3g}"]
             for (L, m, d), (e, q) in sorted(worst.items())]
    delta = [[r["multiplier"], r["level"], fmt(r["delta"]), fmt(r["diff"]["σ"]), fmt(r["diff"]["u"]),
              fmt(r["diff"]["γ"]), fmt((r.get("constant") or {}).get("σ")),
              fmt((r.get("constant") or {}).get("u"))] for r in sdm.get("delta", [])]
    fr = [[r["multiplier"], r["level"],
           "; ".join(f"({x:.10g}, {y:.10g})" for x, y in r["fronts"]) or "none",
           TOOL_NAME.get(r["tool"], r["tool"]), fmt(r["same_level"]), fmt(r["finest"]),
           fmt(r["edge"])] for r in sdm.get("fronts", [])]
    return {"title": "The smooth-domain method", "paras": paras,
            "tables": [(["multiplier", "level", "contact fronts (closed flags change)",
                         "reference", "distance to its front (same level)",
                         "distance to its finest level's", "longest crack edge"], fr,
                        "the SDM's contact fronts (δ = 0; printed, not judged)"),(["multiplier", "δ", "level", "reference", "quantity", "SDM error",
                         "reference error", "ratio"], ratios,
                        "the SDM's error over the reference's on the same mesh and level (printed, "
                        "not judged: no theorem orders them)"),
                       (["level", "multiplier", "δ", "worst error", "(summary − recomputed) / tolerance, largest"],
                        indep, "independent errors: the summary's against the recomputed ones "
                        f"(tolerance {sv.INDEPENDENT_REL:g} relative + 4 × quadrature estimate + "
                        f"{sv.ROUNDOFF_REL:g} × the field's norm)"),
                       (["multiplier", "level", "δ", "‖σ_δ − σ_0‖", "‖u_δ − u_0‖", "‖γ_δ − γ_0‖",
                         "σ constant", "u constant"], delta, "δ → 0")]}


def crack_section(a):
    act = [[TOOL_NAME.get(r["tool"], r["tool"]), r["level"], r["exact_closed_rows"],
            r["reference_active_rows"], r["mismatch_rows"], fmt(r["mismatch_length"]),
            r["far_rows"]] for r in a["active_set"]]
    fr = [[TOOL_NAME.get(f["tool"], f["tool"]), f["level"],
           "; ".join(f"({x:.10g}, {y:.10g})" for x, y in f["fronts"]) or "none (no flag changes)"]
          for f in a["fronts"]]
    paras = ([f"A row's exact status is closed when the exact opening is ≤ "
              f"{elastic.elastic_exact.CONTACT_TOL:g} × the largest |u| on Γc; the mismatch length "
              "is Σ m_j over the rows (not tips, not mouths) whose reference flag differs."]
             if a["has_exact"] else ["No [exact]: the references' contact fronts per level."])
    return {"title": "Contact set and fronts", "paras": paras,
            "tables": [(["reference", "level", "exact closed rows", "active rows",
                         "rows differing", "mismatch length", "beyond the front's reach"], act),
                       (["reference", "level", "contact fronts (where the active flags change)"],
                        fr)]}


def sif_section(a, exact_sif):
    if a["sif_missing"]:
        return {"title": "Stress intensity factors",
                "paras": [f"Not computed: {a['sif_missing']}."]}
    rows = []
    for (t, L), ks in sorted(a["sif_by_key"].items()):
        for k, kk in enumerate(ks):
            ke = exact_sif[k] if exact_sif and k < len(exact_sif) else None
            rows.append([TOOL_NAME.get(t, t), L, k + 1, f"{kk[0]:.10g}", f"{kk[1]:.10g}",
                         fmt(abs(kk[0] - ke[0]) if ke else None),
                         fmt(abs(kk[1] - ke[1]) if ke else None)])
    dist = [[TOOL_NAME.get(r["tool"], r["tool"]), r["level"], r["finest"], fmt(r["sif_distance"]),
             fmt(r["front_distance"])] for r in a["finest"]]
    skipped = [f"Not computed at {TOOL_NAME.get(t, t)} level {L}: {why}."
               for (t, L), why in sorted(a["sif_skipped"].items())]
    return {"title": "Stress intensity factors",
            "paras": ["K_I, K_II per tip by the interaction integral (compare/sdcompare_lib/sif.py) "
                      f"on the ring from {elastic.RING[0]:g} R to {elastic.RING[1]:g} R, R the tip's "
                      "distance to the outer boundary or another crack, with the scene's body force "
                      f"and, in the crack-face term, the {a['sif_pressure']} pressure (with [exact] "
                      "the exact one: the references' nodal pressure has an h^-1/2 layer at the tip "
                      "whose weighted integral does not vanish, compare/sdcompare_lib/elastic.py)."]
            + skipped,
            "tables": [(["reference", "level", "tip", "K_I", "K_II", "K_I error", "K_II error"], rows),
                       (["reference", "level", "finest level", "largest K difference to the finest level's",
                         "largest front distance to the finest level's"], dist,
                        "distances to each reference's finest level")]}


def finest_section(a):
    rows = []
    by_tool = {}
    for r in a["field_distances"]:
        by_tool.setdefault(r["tool"], []).append(r)
    for tool, rs in by_tool.items():
        for i, r in enumerate(rs):
            prev = rs[i - 1] if i else None
            rate_u = (rates.rate(a["h"][prev["level"]], prev["u_l2"], a["h"][r["level"]], r["u_l2"])
                      if prev and prev["u_l2"] and r["u_l2"] else None)
            rate_g = (rates.rate(a["h"][prev["level"]], prev["u_h1"], a["h"][r["level"]], r["u_h1"])
                      if prev and prev["u_h1"] and r["u_h1"] else None)
            rows.append([TOOL_NAME.get(tool, tool), r["level"], r["finest"], fmt(r["u_l2"]),
                         fmt_rate(rate_u), fmt(r["u_h1"]), fmt_rate(rate_g), r["note"] or "–"])
    return {"title": "Distances to the finest level",
            "paras": ["Each reference's u at every level against its own finest level, evaluated "
                      "exactly on the finest triangles (a self-convergence measure, biased by the "
                      "finest level's own error: printed, not judged)."],
            "tables": [(["reference", "level", "finest level", "‖u_L − u_finest‖", "rate",
                         "‖∇(u_L − u_finest)‖", "rate", "note"], rows)]}


def references_section(res, a):
    kkt = []
    for tool, (_, by_level) in sorted(res["refs"].items()):
        for L, r in sorted(by_level.items()):
            k = r.case.get("kkt") if isinstance(r.case.get("kkt"), dict) else {}
            kkt.append([TOOL_NAME.get(tool, tool), L, r.case.get("status"),
                        r.case.get("iterations"), r.case.get("active")]
                       + [fmt(k.get(n)) for n in ("equations", "primal", "dual",
                                                   "complementarity")])
    agree = [[g["level"], fmt(g["u_rel"]), g["flags_differ"], fmt(g["sif_rel"])]
             for g in a["agreement"]]
    return {"title": "References",
            "tables": [(["reference", "level", "status", "iterations", "active", "KKT equations",
                         "primal", "dual", "complementarity"], kkt),
                       (["level", "‖u_a − u_b‖∞ / ‖u‖∞", "active flags differing",
                         "largest K difference / the tip's largest K"], agree, "dolfinx against FreeFEM")]}


def provenance_section(res):
    prov, headers, rows = render.provenance(
        res["summary"], {t: {"summary": s} for t, (s, _) in res["refs"].items()})
    return prov, {"title": "Provenance", "tables": [(headers, rows)], "fold": "always"}


# ------------------------------------------------------------------------------ the plot

def error_plot(folder, a):
    """Errors against h per quantity, one line per reference (plots.py's reference styles)."""
    if not a["series"]:
        return None
    from . import plots

    with matplotlib.rc_context(plots.RC):
        qs = list(dict.fromkeys(s["quantity"] for s in a["series"]))
        fig, axes = plots._panels(len(qs))
        for ax, q in zip(axes, qs):
            for s in (s for s in a["series"] if s["quantity"] == q):
                plots._reference_line(ax, {"tool": s["tool"], "h": s["h"], "errors": s["errors"],
                                           "label": TOOL_NAME.get(s["tool"], s["tool"])})
            plots._slope_guides(ax)
            plots._log_axes(ax)
            ax.set_xlabel("N^-1/2" if a["graded"] else "h")
            ax.set_title(elastic_theory.QUANTITY_TEXT.get(q, f"|{q} − exact|"))
            ax.grid(True, which="both", alpha=0.3)
        fig.suptitle(f"{a['scene']}: errors against the exact fields")
        plots._finish(fig, axes)
        return plots._save(fig, folder, f"errors-{a['scene']}.png")


# ------------------------------------------------------------------------------ the run

def report_json(res, a, prov, images):
    return verdict.clean({
        "verdict": a["verdict"], "verdict_cause": a["verdict_cause"], "reasons": a["reasons"],
        "scene": a["scene"],
        "exact_data": [{"key": p.key, "problem": p.sentence} for p in a["exact_data"]],
        "problem": elastic_read.PROBLEM, "results_dir": res["folder"], "provenance": prov,
        "convergence_rule": rates.rule_text(theory.RATE_MARGIN, source=RULE_SOURCE),
        "regularity": {"s": a.get("s"), "reason": a.get("s_reason")},
        "checks": [{"check": label, "requires": what, "problems": p,
                    "status": _status(a, label, p, na), "not_applicable": na,
                    "cannot_judge_yet": a["undecided"].get(label, [])}
                   for label, what, p, na in a["checks"]],
        "run_levels_up_to": a["run_levels_up_to"],
        "series": [{k: s[k] for k in ("tool", "quantity", "levels", "h", "errors", "rates",
                                      "expected", "threshold", "order_reason", "status", "reason")}
                   for s in a["series"]],
        "errors": [dict(tool=t, level=L, **e) for (t, L), e in sorted(a["errors"].items())],
        "interpolation": {str(L): v for L, v in sorted(a.get("interpolation", {}).items())},
        "yardstick": a.get("yardstick", []),
        "agreement": a["agreement"], "active_set": a["active_set"], "fronts": a["fronts"],
        "sifs": [{"tool": t, "level": L, "K": ks} for (t, L), ks in sorted(a["sif_by_key"].items())],
        "sif_missing": a["sif_missing"], "finest": a["finest"],
        "field_distances": a["field_distances"],
        "sif_skipped": [{"tool": t, "level": L, "why": w} for (t, L), w in sorted(a["sif_skipped"].items())],
        "solver": {k: (a.get("sdm") or {}).get(k) for k in
                   ("cases", "independent", "ratios", "delta", "fronts", "sentences")},
        "images": [i for i in images if i]})


def check_no_expectations(path, scene):
    """The elastic verdict reads no expectations: its series (the references' and the solver's)
    are judged by elastic_theory.py's orders, and no ratio to the references is recorded yet. A row of the expectations file `path` (--expectations,
    else the default file) naming the elastic `scene` would be silently ignored, so it is refused
    (InputError); rows of other scenes, and "*" rows (patterns of the scalar series), are the
    scalar verdict's. A missing default file is no error here."""
    import tomllib

    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except (OSError, ValueError) as exc:  # tomllib.TOMLDecodeError is a ValueError
        raise elastic_read.InputError(f"bad expectations file {path}: {exc}")
    for table in ("expectation", "ratio"):
        rows = data.get(table)
        for i, row in enumerate(rows if isinstance(rows, list) else []):
            if isinstance(row, dict) and row.get("scene") == scene:
                raise elastic_read.InputError(
                    f"{path}: [[{table}]] {i} names the elastic scene {scene!r}, whose verdict "
                    "reads no expectations (docs/elasticity.md): remove the row")


def run(args, results_dir):
    """The elastic report of RESULTS_DIR (the options --replace, --quiet and --expectations, whose
    file may not name the scene: check_no_expectations; the scalar-only options are refused)."""
    for opt in ("baseline", "record_expectations"):
        if getattr(args, opt, None):
            raise elastic_read.InputError(f"--{opt.replace('_', '-')} is not available for an "
                                          "elastic scene")
    if os.path.lexists(os.path.join(results_dir, "report")) and not args.replace:
        raise elastic_read.InputError(f"{results_dir}/report exists (use --replace to replace it)")
    res = elastic_read.load(results_dir)
    expectations = getattr(args, "expectations", None)
    if expectations is not None and not os.path.exists(expectations):
        raise elastic_read.InputError(f"missing expectations file: {expectations}")
    expectations = expectations or verdict.default_expectations(
        os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    if expectations is not None and os.path.exists(expectations):
        check_no_expectations(expectations, res["scene"])
    a = elastic.analyse(res)
    tmp = render.new_tmp_folder(results_dir)
    try:
        images = [error_plot(tmp, a)]
        prov, prov_sec = provenance_section(res)
        secs = [summary_section(a, images), series_section(a), solver_section(res, a),
                crack_section(a), sif_section(a, (res["mesh_scene"].get("exact") or {}).get("sif")),
                finest_section(a), references_section(res, a), prov_sec]
        title = f"sdcompare report — {a['scene']} (elasticity)"
        render.write_text(tmp, "report.md", render.markdown(title, secs))
        render.write_text(tmp, "index.html", render.html_page(title, secs, tmp))
        render.write_json(tmp, "report.json", report_json(res, a, prov, images))
    except BaseException:
        render.shutil.rmtree(tmp, ignore_errors=True)
        raise
    final = render.publish(tmp, results_dir, replace=args.replace)
    if not args.quiet:
        for r in a["reasons"]:
            print(f"problem: {r}")
        print(f"report: {final}")
    print(verdict_line(a))
    return verdict.VERDICTS[a["verdict"]]
