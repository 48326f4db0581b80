"""The report's sections (report.md and index.html, rendered by render.py): build_sections lists
them in the report's order, one function per section, each a dict {"title", "paras", "tables",
…} of the analysis `a` (compare/sdcompare's analyse) and the results folder `res`."""
from collections import defaultdict

from . import certificate, checks, glance, rates, refcheck, render, sentences, theory, verdict
from .baseline import BASELINE_ERROR_RTOL, BASELINE_RATE_ATOL
from .cases import (DEFAULT_P_MASS, DEFAULT_P_SPACE, p_mass, p_space, variant_label, variant_of,
                    variant_order, variant_suffix)
from .render import fmt, fmt_delta, fmt_rate


def headline(a):
    """The verdict as the report's first words: the scene named first when it is the cause."""
    if a["verdict_cause"] == "scene":
        return (f"{a['verdict']} (cause: the scene: its [exact] data are not those of an exact "
                f"solution; the solver is not judged against them)")
    return a["verdict"]


def rule_text(a):
    st = a["settings"]
    return (rates.rule_text(theory.RATE_MARGIN, st["min_rate"] if st["min_rate_declared"] else None)
            + f" Regularity of the solution: s = {a['regularity']:g} ({a['regularity_reason']})."
            + (" Graded meshes: rates are per halving of N^-1/2 (N: the case's unknowns), not of "
               "the largest triangle's h." if a.get("graded") else ""))


def check_status(problems, not_applicable, markdown=False, undecided=()):
    """"ok", "N problem(s)", "cannot judge yet: N …", "not judged: why", "not run: why" (nothing
    to check) or "not applicable: why" of one check (checks.status_text)."""
    if problems and markdown:
        return f"**{len(problems)} problem(s)**"
    if not problems and undecided:
        return (f"cannot judge yet: {len(undecided)} series need more levels" if markdown else
                "INCONCLUSIVE")
    if not problems and not_applicable is not None and not_applicable.startswith("not judged"):
        return not_applicable
    return checks.status_text(problems, not_applicable)


def check_statuses(a, markdown=False):
    """{check label: its status} (check_status with what the check cannot judge yet)."""
    return {label: check_status(p, na, markdown, a["undecided"].get(label, ()))
            for label, _, p, na in a["checks"]}


# Problems quoted in the report's first paragraph (all of them follow the tables).
FIRST_PROBLEMS = 5


def label_of(x):
    """broken/M1, broken/M1/lumped, broken/M1/ptangential of a series, GCI or table row."""
    return variant_label(*variant_of(x))


def with_p_columns(a, headers, rows, entries):
    """The table with a "p mass" column after "mult." when the run has the lumped p mass, and a
    "p space" column after it when the run has the broken-tangential p (else unchanged: a run of
    the consistent p mass and the continuous p alone is reported as before either axis);
    `entries`: the rows' variants (dicts with p_mass and p_space, absent meaning the defaults)."""
    i = headers.index("mult.") + 1
    for show, name, value in ((a["show_p_space"], "p space", p_space),
                              (a["show_p_mass"], "p mass", p_mass)):
        if show:
            headers = headers[:i] + [name] + headers[i:]
            rows = [r[:i] + [value(e)] + r[i:] for r, e in zip(rows, entries)]
    return headers, rows


# What the lumped p is (docs/scenes.md, [discretization] p_mass), said once in a run that has it.
LUMPED_P_TEXT = (
    "The lumped p mass replaces the p–p block by its row-sum diagonal D, which eliminates p: "
    "p_h = D⁻¹(G_Γ − B̃ᵀU − contact term) is a recovered P1 gradient without bubble (away from "
    "the crack the area-weighted average of ∇u_h over the vertex patch), so its errors (solver "
    "and this tool's recomputation) take the bubble as 0, while the consistent p is the paper's "
    "MINI field with its bubble.")


# What the broken-tangential p is (docs/scenes.md [discretization] p_spaces), said once
# in a run that has it.
TANGENTIAL_P_TEXT = (
    "The broken-tangential p space gives p_h's tangential component one value per crack face at "
    "every interior vertex where the crack is straight, while p·ν stays shared (kinks and tips "
    "keep p shared); it runs with broken u only. Its p_h can follow the tangential jump of ∇u "
    "where the crack opens, so its expected orders are P1's on the cracked mesh (the references') "
    "whatever the crack does (the series table gives each series' order and its reason).")


def slope_range(delta_limit):
    s = [e["slope"] for e in delta_limit if e["points_fitted"] >= 2 and e["slope"] is not None]
    return f" ({len(s)} fits, slopes {min(s):.3f} to {max(s):.3f})" if s else " (no δ sweep)"


STATUS_SHOWN = {"converges": "converges", "does not converge": "**DOES NOT CONVERGE**",
                "expected failure": "EXPECTED FAILURE", "unexpected pass": "**UNEXPECTED PASS**",
                "inconclusive": "cannot judge yet", "incomplete": "**INCOMPLETE**",
                "not judged": "not judged"}


def series_table(a):
    headers = ["u space", "mult.", "quantity", "against", "status", "last rate", "expected rate",
               "paper rate", "finest error", "reason", "expected rate from"]
    rows = []
    for s in a["series"]:
        last = s["rates"][-1] if s["rates"] else None
        against = s["against"] if s["against"] != "reference" else f"reference ({s['reference']})"
        status = STATUS_SHOWN[s["status"]]
        if s["status"] == "inconclusive" and a["settings"]["smoke"]:
            status = "inconclusive (smoke run)"
        fin = "–" if not s["levels"] else f"{fmt(s['finest_error'])} (level {s['levels'][-1]})"
        rows.append([s["u_space"], s["multiplier"], s["quantity"], against or "–", status,
                     fmt_rate(last), f"{s['expected_rate']:g} (≥ {s['rate_threshold']:g})",
                     fmt_rate(s["paper_rate"]), fin, s["reason"], s["expected_rate_reason"]])
    return with_p_columns(a, headers, rows, a["series"])


def variant_table(a):
    """One row per variant (u space × multiplier × p mass × p space): its status and, per quantity,
    the last observed rate with the threshold it is held to; the long series table is in the h → 0
    section."""
    qs = [q for q in ("u_l2", "p_l2", "p_x", "lambda_l2") if any(s["quantity"] == q
                                                                  for s in a["series"])]
    by_variant = defaultdict(dict)
    for s in a["series"]:
        by_variant[variant_of(s)][s["quantity"]] = s
    headers = ["u space", "mult.", "status"] + [f"{q} rate (≥)" for q in qs]
    g = a["glance"]
    ratio_of = {variant_of(r): r for r in g["rows"]}
    tools = glance.tools_of(g)
    if tools:  # sdcrack's u error at the comparison level and its ratio to each reference's
        headers += [f"u error L{g['level']}"] + [f"÷ {glance.REFERENCE_NAMES[t]}" for t in tools]
    rows, variants = [], []
    for (u, m, pm, ps), ss in by_variant.items():
        st = {s["status"] for s in ss.values()}
        if st == {"converges"}:
            status = "converges"
        elif st == {"expected failure"}:
            status = STATUS_SHOWN["expected failure"]
        else:
            status = "; ".join(f"{q}: {STATUS_SHOWN[s['status']]}" for q, s in ss.items()
                               if s["status"] != "converges")
        cells = []
        for q in qs:
            s = ss.get(q)
            last = s["rates"][-1] if s and s["rates"] else None
            cells.append("–" if s is None else f"{fmt_rate(last)} (≥ {s['rate_threshold']:g})")
        if tools:
            r = ratio_of.get((u, m, pm, ps)) or {"error": None, "refs": {}}
            cells += [fmt(r["error"])] + [glance.ratio_text((r["refs"].get(t) or {}).get("ratio"))
                                          for t in tools]
        rows.append([u, m, status] + cells)
        variants.append({"p_mass": pm, "p_space": ps})
    headers, rows = with_p_columns(a, headers, rows, variants)
    return headers, rows, ("each variant's last observed rates (per halving of the mesh parameter)"
                           + (f"; its u error at level {g['level']} ({g['against']}) and that "
                              "error ÷ each reference's" if tools else ""))


def rate_table(a):
    headers = ["u space", "mult.", "quantity", "δ"]
    levels = sorted({lv for r in a["series"] for lv in r["levels"]})
    headers += [f"e (L{lv})" for lv in levels] + [f"rate L{lv}" for lv in levels[1:]]
    headers += ["expected rate", "paper rate", "status"]
    rows = []
    for r in a["series"]:
        e = dict(zip(r["levels"], r["errors"]))
        rt = dict(zip(r["levels"][1:], r["rates"]))
        rows.append([r["u_space"], r["multiplier"], r["quantity"], fmt_delta(r["delta"])]
                    + [fmt(e.get(lv)) for lv in levels] + [fmt_rate(rt.get(lv)) for lv in levels[1:]]
                    + [f"{r['expected_rate']:g}", fmt_rate(r["paper_rate"]), STATUS_SHOWN[r["status"]]])
    headers, rows = with_p_columns(a, headers, rows, a["series"])
    return headers, rows, "errors and observed rates per level of every series"


def delta_reference_sentences(a):
    """What the δ-reference plot shows, measured: per u space (the plot's multiplier), on which
    levels the distance to the reference falls at every step from the largest δ to δ = 0 (and
    where it rises), and whether the δ = 0 floor falls with h (sdcompare_lib/sentences.py)."""
    rows = [r for r in a["agreement"] if r["kind"] == "solver_vs_reference"
            and r.get("e_u") is not None]
    if not rows:
        return []
    tool = sorted({r["reference"] for r in rows})[0]
    mult = sorted({r["multiplier"] for r in rows})[-1]
    out = [f"Distance ‖u_δh − u_{tool}‖ to the reference of the same level as δ → 0 "
           f"(plot: multiplier {mult}; dotted: δ = 0, the floor of the level)."]
    for v in sorted({(r["u_space"], mult, p_mass(r), p_space(r)) for r in rows},
                    key=variant_order):
        sel = [r for r in rows if r["reference"] == tool and variant_of(r) == v]
        levels = sorted({r["level"] for r in sel})
        floors = [next((r["e_u"] for r in sel if r["level"] == lv and r["delta"] == 0), None)
                  for lv in levels]
        by_level = {lv: [(r["delta"], r["e_u"]) for r in sel if r["level"] == lv]
                    for lv in levels}
        text = (f"{variant_label(*v)}: {sentences.delta_trend(by_level)}; "
                f"{sentences.floor_trend(floors)}.")
        out.append(text)
    return out


def variant_sentences(a):
    """Which variants converge and which do not, from the series statuses."""
    by_variant = defaultdict(list)
    for s in a["series"]:
        by_variant[variant_of(s)].append(s)
    conv, xfail, fail, other = [], [], [], []
    for v, ss in sorted(by_variant.items(), key=lambda kv: variant_order(kv[0])):
        st = {s["status"] for s in ss}
        name = variant_label(*v)
        if st == {"converges"}:
            rts = ", ".join(f"{s['quantity']} {fmt_rate(s['rates'][-1] if s['rates'] else None)}"
                            for s in ss)
            conv.append(f"{name} (last rates {rts})")
        elif st == {"expected failure"}:
            xfail.append(name)
        elif st & {"does not converge", "unexpected pass"}:
            fail.append(name + " (" + ", ".join(f"{s['quantity']} {s['status']}" for s in ss
                                                if s["status"] != "converges") + ")")
        else:
            other.append(name + " (" + ", ".join(sorted(st)) + ")")
    against = sorted({s["against"] for s in a["series"] if s["against"]})
    out = [f"Measured against the {' and the '.join(against) or 'nothing (no exact solution, no reference)'}"
           " solution, on levels " + ", ".join(str(lv) for lv in sorted({lv for s in a["series"]
                                                                           for lv in s["levels"]}))
           + "."]
    if conv:
        out.append("**Converges**: " + "; ".join(conv) + ".")
    if xfail:
        reasons = sorted({s["expected_failure"] for s in a["series"] if s["status"] == "expected failure"})
        out.append("**Does not converge, as declared in the scene** (expected failure): "
                   + ", ".join(xfail) + ". Reason given: " + "; ".join(reasons) + ".")
    if fail:
        out.append("**Fails**: " + "; ".join(fail) + ".")
    if other:
        out.append("Not judged: " + "; ".join(other) + ".")
    if a["show_p_mass"]:
        out.append("P masses: " + " and ".join(a["p_masses"]) + " (a variant without a p mass is "
                   "consistent; lumped variants are labelled /lumped). " + LUMPED_P_TEXT)
    if a["show_p_space"]:
        out.append("P spaces: " + " and ".join(a["p_spaces"]) + " (a variant without a p space is "
                   "continuous; broken-tangential variants are labelled /ptangential). "
                   + TANGENTIAL_P_TEXT)
    return out


def reference_own_table(own):
    """(headers, rows, caption) of each reference's own checks: per reference and quantity its
    last two rates, the order held and the status, and its largest error / interpolation error."""
    worst = {}
    for r in own.get("yardstick", []):
        k = (r["reference"], r["quantity"])
        if k not in worst or r["ratio"] > worst[k]["ratio"]:
            worst[k] = r
    rows = []
    keys = [(r["reference"], r["quantity"]) for r in own.get("orders", [])]
    keys += [k for k in worst if k not in keys]
    orders = {(r["reference"], r["quantity"]): r for r in own.get("orders", [])}
    for k in keys:
        o, w = orders.get(k), worst.get(k)
        rows.append([k[0], k[1],
                     ", ".join(fmt_rate(x) for x in o["rates"][-2:]) if o else "–",
                     f"{o['expected_rate']:g}" if o else "–", o["status"] if o else "–",
                     f"{fmt(w['ratio'], '.3g')} (level {w['level']}) ≤ {w['factor']:g}"
                     if w else "not held"])
    return (["reference", "quantity", "last rates", "order", "status",
             "largest error / interpolation error"], rows,
            "each reference's own orders and interpolation yardstick")


def yardstick_section(a):
    """Absolute yardsticks and Theorem 2.1 against the exact solution: what each bounds, its rows."""
    sec = {"title": "Absolute yardsticks and Theorem 2.1 against the exact solution",
           "paras": [], "tables": []}
    status = check_statuses(a, markdown=True)
    interp = a["interpolation"]
    if interp:
        sec["paras"].append(
            "P1 interpolation error of the exact u on each level's mesh (computed by this tool from "
            "the scene's expression alone): it measures the regularity of u (rate of "
            f"‖∇(u − I_h u)‖; s = {a['regularity']:g}: {a['regularity_reason']}) and, for a smooth "
            "u, bounds the errors: " + status["interpolation yardstick"] + ".")
        sec["tables"].append((["level", "h", "‖u − I_h u‖", "‖∇(u − I_h u)‖",
                               "‖∇u − ∇I_h u‖_X"],
                              [[lv, fmt(v["h"], ".4g"), fmt(v["u_l2"]), fmt(v["grad_l2"]),
                                fmt(v["grad_x"])] for lv, v in sorted(interp.items())],
                              "interpolation errors of the exact u"))
    for kind, title in (("interpolation", "interpolation error"), ("reference", "reference's error")):
        rows = a["yardsticks"][kind]
        if not rows:
            continue
        worst = {}
        for r in rows:
            k = variant_of(r) + (r["quantity"],)
            if k not in worst or (r["ratio"] or 0) > (worst[k]["ratio"] or 0):
                worst[k] = r
        sec["tables"].append(with_p_columns(
            a, ["u space", "mult.", "quantity", "worst level", "error", title, "ratio", "bound"],
            [[r["u_space"], r["multiplier"], r["quantity"], r["level"], fmt(r["error"]),
              fmt(r["yardstick"]), fmt(r["ratio"], ".3g"), f"{r['factor']:g}"]
             for r in worst.values()], list(worst.values()))
            + (f"error / {title} at the worst level of each series ({rows[0]['against']})",))
    if "reference yardstick" in status:
        sec["paras"].append("Against the references: " + status["reference yardstick"] + ".")
    own = a.get("reference_own") or {}
    if own.get("orders") or own.get("yardstick"):
        sec["paras"].append(
            "Each reference on its own (refcheck.py): its orders "
            + status.get(refcheck.ORDERS_LABEL, "–") + "; its error against its own P1 "
            "interpolant of the exact u " + status.get(refcheck.YARDSTICK_LABEL, "–") + ".")
        sec["tables"].append(reference_own_table(own))
    t21 = a["theorem21"]
    sec["paras"].append("Theorem 2.1 against the exact solution: "
                        + status.get("Theorem 2.1 (exact)", "–") + ".")
    if t21:
        sel = [r for r in t21 if r["quantity"] == "u_l2" and variant_of(r) == (
            "broken", "M1", DEFAULT_P_MASS, DEFAULT_P_SPACE)] or \
            [r for r in t21 if r["quantity"] == "u_l2"]
        deltas = sorted({r["delta"] for r in sel}, reverse=True)
        levels = sorted({r["level"] for r in sel})
        cell = {(r["level"], r["delta"]): r for r in sel}
        floor = {r["level"]: r["floor"] for r in sel}
        var = label_of(sel[0])
        held = not any(probs for label, _, probs, _ in a["checks"]
                       if label == "Theorem 2.1 (exact)")
        sec["paras"].append(
            f"‖u_δh − u‖ against δ per level ({var}), the triangle inequality |e_δ − e_0| ≤ "
            "‖u_δ − u_0‖ checked for every variant, u and λ: "
            + ("it holds, so each error approaches the δ = 0 floor of its level as δ → 0, within "
               "the O(δ) distance ‖u_δ − u_0‖." if held else
               "**it fails** (problems above): an error strays from the δ = 0 floor of its level "
               "by more than ‖u_δ − u_0‖."))
        sec["tables"].append((["level"] + [f"δ={fmt_delta(d)}" for d in deltas] + ["δ=0 (floor)"],
                              [[lv] + [fmt((cell.get((lv, d)) or {}).get("error")) for d in deltas]
                               + [fmt(floor[lv])] for lv in levels],
                              "error against the exact solution per level and δ"))
    return sec


def undecided_sentence(a):
    """The verdict's sentence when it is INCONCLUSIVE: how many series cannot be judged yet, the
    levels to run, and each distinct reason once with the series it holds for (the first few)."""
    groups = defaultdict(list)
    for line in a["undecided"]["series"]:
        label, _, reason = line.partition(": inconclusive: ")
        groups[reason].append(label)
    up_to = a["run_levels_up_to"]
    parts = []
    for reason, labels in sorted(groups.items(), key=lambda kv: -len(kv[1]))[:FIRST_PROBLEMS]:
        shown = ", ".join(labels[:3]) + (f" and {len(labels) - 3} more" if len(labels) > 3 else "")
        parts.append(f"{len(labels)} series ({shown}): {reason}")
    parts += [f"{label}: {item}" for label, items in a["undecided"].items() if label != "series"
              for item in items]
    more = len(parts) - FIRST_PROBLEMS
    parts = parts[:FIRST_PROBLEMS]
    return (f"Cannot judge yet: no check found a problem, but {len(a['reasons'])} series cannot "
            "carry a verdict at these levels" + (f"; run levels up to {up_to}" if up_to is not None
                                                 else "") + ". " + " · ".join(parts)
            + (f" · … and {more} more reason(s), listed below the tables." if more > 0 else ""))


def no_problem_sentence(a):
    """The verdict's sentence without a problem, counted from the series and the checks: how many
    series have each status and how many checks hold, do not apply or had nothing to check (a
    fixed "every series converges … every check holds" was printed over smoke runs' inconclusive
    series and checks of 0 cases)."""
    statuses = defaultdict(int)
    for s in a["series"]:
        statuses[s["status"]] += 1
    kinds = defaultdict(int)
    for _, _, probs, na in a["checks"]:
        kinds["ok" if na is None else "not run" if na.startswith(checks.NOT_RUN)
              else "not applicable"] += 1
    said = {"converges": "converge", "expected failure": "are declared expected failures",
            "inconclusive": "are inconclusive (a smoke run)"}
    series = ", ".join(f"{n} {said.get(st, st)}"
                       for st, n in sorted(statuses.items(), key=lambda kv: -kv[1]))
    return (f"No problem: of {len(a['series'])} series, {series or 'none'}; of "
            f"{len(a['checks'])} checks, " + ", ".join(
                f"{kinds[k]} {w}" for k, w in (("ok", "hold"), ("not applicable", "do not apply"),
                                               ("not run", "had nothing to check"))
                if kinds[k]) + " (the table below).")


def rerun_threads_text(res):
    """The Rerun commands' sentences on threads and references: each command pins the BLAS/OpenMP
    threads the campaign's jobs run with; with references, it reruns the sdcrack case alone and
    says how to rerun the references too, and warns when a reference's provenance says it ran
    unpinned (its rerun may then differ in the last digits)."""
    from sdshared.sdresults import PINNED_THREADS, threads_pinned

    pins = " ".join(f"{n}={v}" for n, v in PINNED_THREADS)
    text = (f" Each command starts with `env {pins}`: the BLAS/OpenMP threads the campaign's jobs "
            "run with (a reference's numbers depend on them in the last digits).")
    tools = render.scene_references(res["scene_file"])
    if not tools:
        return text
    names = ", ".join(f"`{t}/`" for t in tools)
    text += (f" It ends in `{render.SOLVER_ONLY}`: it reruns the sdcrack case alone, not the "
             f"references, and the rerun reuses this folder's {names} (`sdcompare-rerun` says so); "
             f"drop `{render.SOLVER_ONLY}` to rerun the case's level's references too, whose fields "
             "`sdcompare-rerun ... --references` then compares bit for bit.")
    unpinned = [t for t in sorted(res["refs"])
                if threads_pinned((res["refs"][t]["summary"].get("provenance") or {})
                                  .get("threads")) is False]
    if unpinned:
        text += (f" This folder's {', '.join(unpinned)} ran with its BLAS/OpenMP threads not "
                 "pinned (Provenance): their rerun may differ from them in the last digits.")
    return text


def certificate_section(a):
    """The discrete certificate's section: what it checks, its tolerances and cost, and the worst
    residuals per level × variant (certificate.py)."""
    cert = a["certificate"]
    ran = [t for show, t in ((a["show_p_mass"], "or the lumped p mass condensed numerically and "
                             "row-summed"),
                            (a["show_p_space"], "the continuous and the broken-tangential p"))
           if show]
    text = (f"This tool assembles the method's discrete system itself (compare/sdcompare_lib/"
            f"certificate.py: the weak form (15) with the MINI p and its bubbles b_T = 27λ0λ1λ2 "
            f"uncondensed{''.join(', ' + t for t in ran)}; the continuous and the broken u; M0, "
            f"M1, M1star; δ) and evaluates it at the stored u, p, bubbles and λ of every case with "
            f"≤ {certificate.UNKNOWNS_LIMIT} unknowns. A row passes when its residual is ≤ "
            f"{certificate.ROUNDOFF_FACTOR:g}ε times its componentwise scale (|K||x| + |b|) plus "
            f"{certificate.QUADRATURE_FACTOR:g} × the estimate of the load's and boundary term's "
            f"quadrature error; the multiplier's sign, the constraint on p and their product are "
            f"held to {certificate.COMPLEMENTARITY_FACTOR:g}·κ·ε (κ the case's condition "
            f"estimate). Backward error: the largest |r_i|/(|K||x| + |b|)_i. "
            f"{len(cert['rows'])} case(s) certified, {cert['skipped']} larger one(s) not; cost "
            f"{cert['seconds']:.2f} s.")
    if cert["not_applicable"]:
        text += f" Not applicable: {cert['not_applicable']}."
    headers, rows, entries = certificate.table(cert)
    return {"title": "Discrete certificate", "paras": [text],
            "tables": [with_p_columns(a, headers, rows, entries)
                       + ("worst residuals per level × variant over its δ values",)] if rows else []}


def build_sections(res, a, exps_path, baseline_dir, images):
    """The report's sections in their order; the condition section only when the run recorded
    condition estimates, the baseline section only with --baseline."""
    secs = [summary_section(res, a, images), provenance_section(a), h_section(a),
            delta_section(a, images), yardstick_section(a), gci_section(a),
            reference_section(res, a, images), kkt_section(res, a)]
    condition = condition_section(a)
    if condition is not None:
        secs.append(condition)
    secs += [rerun_section(res, a), certificate_section(a), work_section(a, images),
             expectations_section(a, exps_path)]
    if baseline_dir is not None:
        secs.append(baseline_section(a, baseline_dir))
    return secs


def summary_section(res, a, images):
    """The verdict, its problems, the first screen, the two plots and the short tables."""
    s = res["summary"]
    summary = {"title": f"Summary: {headline(a)}", "paras": [
        f"Scene `{a['scene']}` — {s.get('description', '')}. Results folder: `{res['folder']}`.",
        f"**Verdict: {headline(a)}**. " + (
            undecided_sentence(a) if a["verdict"] == "INCONCLUSIVE" else
            f"{len(a['reasons'])} problem(s): " + " · ".join(a["reasons"][:FIRST_PROBLEMS])
            + (f" · … and {len(a['reasons']) - FIRST_PROBLEMS} more, listed below the tables."
               if len(a["reasons"]) > FIRST_PROBLEMS else "")
            if a["reasons"] else no_problem_sentence(a))] + glance.first_screen(a["glance"]),
        # what a reader needs first: the verdict, the two plots, then the short tables
        "lead_images": [i for i in (images.get("rates"), images.get("delta")) if i],
        "tables": [variant_table(a)], "fold": False}
    summary["tables"].append((["check", "what is required", "result"],
                              [[label, what, check_statuses(a, markdown=True)[label]]
                               for label, what, probs, na in a["checks"]]))
    summary["paras_after"] = variant_sentences(a)
    if a["reasons"]:
        summary["paras_after"].append("Problems: " + " · ".join(a["reasons"]))
    summary["paras_after"] = summary["paras_after"] + [
        "Verdict rule: PASS iff every check of the table holds. A series (u space × multiplier × "
        + ("p mass × " if a["show_p_mass"] else "") + ("p space × " if a["show_p_space"] else "")
        + "quantity) is measured against the exact solution when the scene has one, otherwise "
        "against the reference solution of the same level; " + rule_text(a)
        + " Every series is expected to converge unless the scene file declares it an expected "
        "failure ([[verification.expected_failure]], with its reason); a declared failure that "
        "converges is an unexpected pass and fails. Inconclusive series fail unless the scene "
        "is a smoke run (verification.smoke). In every table, – marks a value that does not "
        "apply, was not recorded, or is not a finite number; long tables are folded (click to "
        "open)."]
    return summary


def provenance_section(a):
    """Where the results come from: binaries, versions, command lines, shards (folded)."""
    return {"title": "Provenance", "paras": [], "fold": "always", "tables": [
        (a["provenance_headers"], a["provenance_rows"],
         "where the results come from: binaries, versions, command lines, shards")]}


def h_section(a):
    """h → 0 (Theorem 4.3): the errors by level and their rates."""
    sec = {"title": "h → 0 (Theorem 4.3): errors by level", "paras": [], "tables": [],
           "images": []}
    if a["series"]:
        if a["has_exact"]:
            sec["paras"].append(
                "Errors from `summary.json` (`errors`: L² norms of u − u_ex, of p − ∇u_ex on Ω_c, "
                "of λ − [u_ex] on Γc, and `p_x`, the paper's mesh-dependent X-norm of p − ∇u_ex, "
                "Σ_T ‖·‖²_T + h_T²‖div ·‖²_T; computed by the solver with the MINI bubble of p "
                "included, and recomputed independently by this tool from fields.h5 when fields "
                "are stored: see the check table).")
        else:
            sec["paras"].append(
                "No exact solution: the errors are the distances to the reference solution of the "
                "same level (cracked mesh, see “Reference comparisons”): ‖u_h − u_ref‖, "
                "‖p_h − ∇u_ref‖ (p_h with its bubble) and ‖λ_h − [u_ref]‖, exact on shared "
                "triangles.")
        sec["paras"].append(
            f"δ = {fmt_delta(a['series'][0]['delta'])}; rates are "
            + ("log(e_(l−1)/e_l)/log(x_(l−1)/x_l) with x = N^(−1/2), N the case's unknowns "
               "(graded meshes)" if a.get("graded") else "log(e_(l−1)/e_l)/log(h_(l−1)/h_l)")
            + ". The paper's rates (Theorem 4.3: M0 1/2, M1 1/2, "
            "M1star 3/4) bound u in L², p in the X-norm and λ together and assume u, p piecewise "
            "H² on each side; they are shown beside u_l2, p_x and lambda_l2. For M1star the paper "
            "measures λ in H^½(Γc), which is not computed: its λ row is the L² norm.")
        if a["show_p_mass"]:
            sec["paras"].append("Lumped variants (p mass column): p_h is P1 without bubble "
                                "(bubble 0 in its norms); the paper's rates are proven for the "
                                "consistent MINI p and are shown beside the lumped series for "
                                "comparison only.")
        if a["show_p_space"]:
            sec["paras"].append("Broken-tangential variants (p space column): p_h is stored at the "
                                "u dofs of the cracked mesh, each copy of a crack vertex with its "
                                "face's value, and its errors are integrated per triangle from its "
                                "own dofs; the paper's rates are proven for the continuous p and "
                                "are shown beside these series for comparison only.")
        sec["paras"].append("The plot is at the top of the report." + (
            f" Its {a['plot_axis_note']}" if a.get("plot_axis_note") else ""))
        sec["tables"].append(series_table(a))
        sec["tables"].append(rate_table(a))
    return sec


def delta_section(a, images):
    """δ → 0 (Theorem 2.1): the distance to the δ = 0 solution at fixed h."""
    sec = {"title": "δ → 0 (Theorem 2.1): distance to the δ = 0 solution at fixed h",
           "paras": [], "tables": [], "images": []}
    if a["delta_limit"]:
        sec["paras"].append(
            "Exact L² norms on the shared triangles (both fields are P1 on the same mesh: exact "
            "P1 mass matrix per triangle; λ: exact P0/P1 segment formulas). **p is compared by its "
            "P1 (vertex) part only** (its bubble coefficients are in fields.h5 but left out of "
            "this difference). Slope: least-squares log–log fit over δ > 0, excluding differences "
            f"below {verdict.ROUNDOFF_REL:g}×‖field_0‖ (round-off); required: 1 ± "
            f"{a['settings']['delta_slope_tolerance']:g}" + slope_range(a["delta_limit"]) + ".")
        deltas = sorted({d for e in a["delta_limit"] for d in e["deltas"]}, reverse=True)
        headers = ["level", "u space", "mult.", "quantity"] + [f"δ={fmt_delta(d)}" for d in deltas] + \
            ["slope"]
        rows = []
        for e in a["delta_limit"]:
            dd = dict(zip(e["deltas"], e["diffs"]))
            rows.append([e["level"], e["u_space"], e["multiplier"], e["quantity"]]
                        + [fmt(dd.get(d)) for d in deltas] + [fmt_rate(e["slope"])])
        headers, rows = with_p_columns(a, headers, rows, a["delta_limit"])
        sec["tables"].append((headers, rows, "‖x_δ − x_0‖ per level, variant and quantity, "
                              "with the fitted slope"))
        if images.get("delta"):
            sec["paras"].append("The plot is at the top of the report.")
    else:
        sec["paras"].append("No fields.h5 or fewer than two δ per case: no δ-limit study.")
    return sec


def gci_section(a):
    """The grid convergence index of the scalar outputs."""
    sec = {"title": "Grid convergence index (Roache, ASME V&V 20)", "paras": [], "tables": []}
    if a["gci"]:
        sec["paras"].append(
            "From the three finest levels of a scalar output computed exactly from fields.h5 "
            "(‖u_h‖_L² and ∫_Γc λ_h ds) at the smallest δ: p = ln|ε32/ε21|/ln r, "
            "GCI_fine = 1.25 |(f1 − f2)/f1| / (r^p − 1) (relative), f_ext Richardson extrapolation. "
            "Self-convergence never shows convergence to the right solution: the GCI is an error "
            "estimate only for a variant whose u series converges to the exact or reference "
            "solution (summary table); for the others it is labelled self-convergence only.")
        rows = [[g["u_space"], g["multiplier"], g["output"], g["kind"],
                 " / ".join(f"{f:.6g}" for f in g["f"]), fmt_rate(g["p"]), fmt(g["gci_fine"]),
                 fmt(g["f_ext"], ".6g"), g["note"]] for g in a["gci"]]
        sec["tables"].append(with_p_columns(a, ["u space", "mult.", "output", "what it is",
                                                "f3 / f2 / f1", "p", "GCI_fine", "f_ext", "note"],
                                            rows, a["gci"])
                             + ("GCI per variant and output",))
    else:
        sec["paras"].append("Not available (needs fields.h5 with at least 3 levels).")
    return sec


def reference_section(res, a, images):
    """The references: their agreement with each other and with sdcrack, their own runs."""
    sec = {"title": "Reference comparisons", "paras": [], "tables": []}
    if not res["refs"]:
        sec["paras"].append("no reference run (no `dolfinx/` or `freefem/` subfolder).")
    else:
        sec["paras"].append(
            "References present: " + ", ".join(sorted(res["refs"])) + ". Against the reference "
            "of the same level: e_u = ‖u_δh − u_ref‖_L², e_p = ‖p_δh − ∇u_ref‖_L²(Ω_c) (p with "
            "its bubble), e_λ = ‖λ_δh − [u_ref]‖_L²(Γc), exact on the "
            "shared triangles (broken: same vertices; continuous: triangle k's corners mapped by "
            "position). Against the reference's finest level: e_u and e_p with the solver field "
            "evaluated exactly at the corners of the nested finer triangles (each fine triangle "
            "inside one coarse triangle, located by the grid cell on structured meshes and as "
            "t // 4^k on uniformly refined ones, so fields broken across a crack keep their side; "
            "P1 part of p). "
            "Only the δ = 0 rows are listed; report.json has every δ.")
        rr = [r for r in a["agreement"] if r["kind"] == "reference_vs_reference"]
        if rr:
            sec["tables"].append((["level", "a", "b", "max |u_a − u_b| (vertices)", "note"],
                                  [[r["level"], r["a"], r["b"], fmt(r["max_vertex_diff"]),
                                    r["note"]] for r in rr], "dolfinx against FreeFEM per level"))
        sr = [r for r in a["agreement"] if r["kind"] == "solver_vs_reference"]
        if sr:
            d0 = min((r["delta"] for r in sr if r.get("delta") is not None), default=None)
            shown = [r for r in sr if r.get("delta") in (d0, None)]
            sec["tables"].append(with_p_columns(
                a, ["reference", "level", "u space", "mult.", "δ", "e_u", "e_p", "e_λ",
                    "e_u (finest ref)", "e_p (finest ref)", "note"],
                [[r["reference"], r.get("level"), r.get("u_space"), r.get("multiplier"),
                  fmt_delta(r.get("delta")), fmt(r.get("e_u")), fmt(r.get("e_p")),
                  fmt(r.get("e_lambda")), fmt(r.get("e_u_finest")), fmt(r.get("e_p_finest")),
                  r.get("note", "")] for r in shown], shown)
                + ("sdcrack against the references, per level and variant",))
        if a["references"]:
            sec["tables"].append((["tool", "level", "unknowns", "iterations", "total s", "e_u",
                                   "e_p", "e_λ"],
                                  [[r["tool"], r["level"], r["unknowns"], r["iterations"],
                                    fmt(r["total_s"], ".3g"),
                                    fmt((r["errors"] or {}).get("u_l2")),
                                    fmt((r["errors"] or {}).get("p_l2")),
                                    fmt((r["errors"] or {}).get("lambda_l2"))]
                                   for r in a["references"]],
                                  "the references' own runs and their errors"))
        if images.get("delta_reference"):
            sec["paras"] += delta_reference_sentences(a)
            sec.setdefault("images", []).append(images["delta_reference"])
    return sec


def kkt_section(res, a):
    """KKT residuals, iterations and active sets per case, the non-converged first."""
    s = res["summary"]
    bad = [k for k in a["kkt"] if not k["converged"]]
    sec = {"title": "KKT residuals and iterations (non-converged first)", "paras": [
        f"{len(bad)} of {len(a['kkt'])} cases not converged. Residuals are relative (docs/design.md)"
        f"; solver tolerance {s.get('kkt_tolerance', '–')}."], "tables": []}
    sec["tables"].append(with_p_columns(a, ["level", "u space", "mult.", "δ", "converged", "status",
                                            "iter.", "equations", "primal", "dual", "compl.",
                                            "active/total", "reg. piv."],
                          [[k["level"], k["u_space"], k["multiplier"], fmt_delta(k["delta"]),
                            fmt(k["converged"]), k["status"], k["iterations"],
                            fmt(k["kkt"].get("equations"), ".1e"), fmt(k["kkt"].get("primal"), ".1e"),
                            fmt(k["kkt"].get("dual"), ".1e"),
                            fmt(k["kkt"].get("complementarity"), ".1e"),
                            f"{fmt(k['active_multipliers'])}/{fmt(k['multipliers'])}",
                            k["regularized_pivots"]]
                           for k in a["kkt"]], a["kkt"])
                         + ("KKT residuals, iterations and active sets per case",))
    return sec


def rerun_section(res, a):
    """One rerun command per level × u space × multiplier (× p mass × p space)."""
    s = res["summary"]
    reruns = {}
    for k in sorted(a["kkt"], key=lambda k: (k["level"], variant_order(variant_of(k)))):
        reruns.setdefault(k["rerun"], ([k["level"], k["u_space"], k["multiplier"]], k))
    return {"title": "Rerun commands", "paras": [
        "Each command reruns one level × u space × multiplier of this folder, with the run's "
        "δ sweep (each δ warm-started from the previous one, as in the run, so the numbers of "
        "summary.json come back exactly: compare/tests/test_sdcompare.py, "
        "tests/python/test_campaign.py), from the copy of the scene in this folder and the binary "
        "that wrote it (absolute paths: run them from any directory). Each writes into "
        f"`{render.RERUN_FOLDER}/<name>/` under the directory it is run from, never into this "
        "results folder; `tools/cases --rerun-dir DIR` with this folder prints the same commands "
        f"writing into DIR. Then `{render.rerun_compare_command(res['folder'])}` "
        "(sdcrack checkout) compares the rerun with this folder, every field dataset bit for bit "
        "and each case's numbers of summary.json: \"identical\" and exit 0, or exit 1 naming "
        "the first difference (tests/python/test_reruns.py)."
        + (" A lumped case's command adds `--p-mass lumped` (it gives back the case's fields, KKT "
           "residuals and iterations bit for bit; its error norms were seen 1 ulp off when the "
           "lumped case runs alone); a consistent "
           "case's command reruns both p masses." if a["show_p_mass"] else "")
        + (" A broken-tangential case's command adds `--p-space broken-tangential` and writes "
           "to its own `-ptangential` folder (a continuous-p command reruns every p space of its "
           "u space)." if a["show_p_space"] else "")
        + ("" if isinstance((s.get("provenance") or {}).get("executable"), str) else
           " The binary was not recorded (summary.json without provenance): `sdcrack` is taken "
           "from PATH.")
        + rerun_threads_text(res)], "tables": [
        with_p_columns(a, ["level", "u space", "mult.", "command"],
                       [row + [f"`{cmd}`"] for cmd, (row, _) in reruns.items()],
                       [k for _, k in reruns.values()])
        + ("rerun commands, one per level × u space × multiplier"
           + (" × p mass" if a["show_p_mass"] else "")
           + (" × p space" if a["show_p_space"] else ""),)]}


def condition_section(a):
    """The worst five condition estimates of the factored systems, or None when the run recorded
    none."""
    conds = [k for k in a["kkt"] if isinstance(k.get("condition_estimate"), (int, float))]
    if not conds:
        return None
    per_matrix = {}
    for k in conds:  # the multipliers of one (level, u space, p mass, p space, δ) share K(δ)
        key = (k["level"], k["u_space"], k["p_mass"], k["p_space"], k["delta"])
        if key not in per_matrix or k["kkt_max"] > per_matrix[key]["kkt_max"]:
            per_matrix[key] = k
    worst = sorted(per_matrix.values(), key=lambda k: -k["condition_estimate"])[:5]
    return {"title": "Condition of the factored systems (worst five)", "paras": [
        "Condition estimates of the factored systems K(δ) (κ₁ = ‖K‖₁‖K⁻¹‖₁ by the "
        "Hager–Higham estimator, a lower bound usually within a factor 3; one per level, u space "
        "and δ, shared by the multipliers), with the largest KKT residual of their cases: "
        "refinement against the unfactored matrix keeps those at round-off even where κ₁ is "
        "large. ‖K⁻¹‖₁ is estimated afresh at a δ unless an earlier δ' of the sweep is close "
        "enough that a perturbation bound puts the two within a factor 1.1 (column δ')."],
        "tables": [(["level", "u space", "δ", "κ₁ estimate", "‖K⁻¹‖₁ from δ'",
                     "max KKT residual"],
                    [[k["level"], k["u_space"] + variant_suffix(k["p_mass"], k["p_space"]),
                      fmt_delta(k["delta"]), fmt(k["condition_estimate"], ".2e"),
                      fmt_delta(k["condition_estimate_delta"]), fmt(k["kkt_max"], ".1e")]
                     for k in worst])]}


def work_section(a, images):
    """Work–precision: unknowns, time and error per case."""
    sec = {"title": "Work–precision and timings", "paras": [
        "Total per case = sum of `timings_s` (the phases listed in `shared_timings` are shared by "
        "the multipliers of one factorisation and are counted in each of them)."],
        "tables": [], "images": [i for i in [images.get("work")] if i]}
    sec["tables"].append(with_p_columns(a, ["level", "u space", "mult.", "δ", "unknowns",
                                            "total s", "e_u"],
                                        [[t["level"], t["u_space"], t["multiplier"],
                                          fmt_delta(t["delta"]), t["unknowns"],
                                          fmt(t["total_s"], ".3g"), fmt(t["u_l2"])]
                                         for t in a["timings"]], a["timings"])
                         + ("unknowns, time and error per case",))
    return sec


def expectations_section(a, exps_path):
    """The expectations file's rows for this scene, measured."""
    sec = {"title": "Expectations", "paras": [], "tables": []}
    if not a["expectations"]:
        sec["paras"].append(f"`{exps_path}` has no expectation for scene `{a['scene']}`.")
    else:
        sec["paras"].append(f"From `{exps_path}`; rate = observed rate between the last two "
                            "levels; error = error at the finest level.")
        sec["tables"].append((["variant", "quantity", "expected conv.", "min rate", "max error",
                               "measured conv.", "rate", "error", "status", "reason"],
                              [[e.get("variant"), e["quantity"], fmt(e.get("converges")),
                                fmt(e.get("min_rate"), "g"), fmt(e.get("max_error"), ".2e"),
                                fmt(e.get("measured_converges")), fmt_rate(e.get("measured_rate")),
                                fmt(e.get("measured_error")),
                                "**VIOLATED**" if e["status"] == "violated" else e["status"],
                                e.get("reason", "")] for e in a["expectations"]]))
    return sec


def baseline_section(a, baseline_dir):
    """Flags against an earlier results folder of the same scene (informational)."""
    sec = {"title": "Baseline comparison", "paras": [
        f"Against `{baseline_dir}`. Flags: error norms changed by more than "
        f"{BASELINE_ERROR_RTOL:g} relative; rates by more than "
        f"{BASELINE_RATE_ATOL:g} absolute; `converges` changed; total time per case "
        f"grown by more than {verdict.BASELINE_TIME_GROWTH:.0%} (cases with old total < "
        f"{verdict.BASELINE_TIME_MIN_S:g} s ignored as timer noise). Informational: the "
        f"verdict does not use them. {len(a['baseline'])} flag(s)."], "tables": []}
    if a["baseline"]:
        sec["tables"].append((["kind", "what", "quantity", "old", "new", "change"],
                              [[f["kind"], f.get("variant") or f.get("case"),
                                f.get("quantity", "total_s"), f["old"], f["new"],
                                fmt(f.get("rel_change", f.get("abs_change")), ".2e")]
                               for f in a["baseline"]]))
    return sec
