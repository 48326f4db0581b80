"""PNG plots (matplotlib, Agg backend). Each function returns the file name written or None."""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import FuncFormatter, NullFormatter  # noqa: E402

from .read import p_mass, p_space, variant_label, variant_of, variant_order  # noqa: E402
from .render import fmt_delta  # noqa: E402

QLABEL = {"u_l2": "‖u_h−u‖_L²", "p_l2": "‖p_h−∇u‖_L²", "p_x": "‖p_h−∇u‖_X", "lambda_l2": "‖λ_h−[u]‖_L²(Γc)"}
# one spelling per symbol in every plot: λ, never "lambda"
SYMBOL = {"u_l2": "u", "p_l2": "p", "p_x": "p", "lambda_l2": "λ"}
STYLE = {"broken": "-", "continuous": "--"}
MARK = {"M0": "o", "M1": "s", "M1star": "^"}
# colour per (u space, p mass, p space): each combination its own hue, so consistent and lumped,
# continuous and broken-tangential p differ by more than dashing; the line style repeats the p mass
# and p space (PM_STYLE) for grey-scale prints, the marker is the multiplier, hollow for the
# continuous u space (which never runs the broken-tangential p)
VARIANT_COLOR = {("broken", "consistent", "continuous"): "tab:blue",
                 ("broken", "lumped", "continuous"): "tab:orange",
                 ("continuous", "consistent", "continuous"): "tab:green",
                 ("continuous", "lumped", "continuous"): "tab:purple",
                 ("broken", "consistent", "broken-tangential"): "tab:red",
                 ("broken", "lumped", "broken-tangential"): "tab:brown"}
# The references: told apart by marker, line style and label as well as colour (a grey-scale print
# or a colour-blind reader still sees two), and unlike any solver variant's marker and line.
REF_STYLE = {"dolfinx": {"marker": "*", "linestyle": "-.", "color": "black", "markersize": 9,
                         "label": "reference dolfinx"},
             "freefem": {"marker": "D", "linestyle": ":", "color": "tab:gray", "markersize": 6,
                         "markerfacecolor": "none", "label": "reference FreeFEM"}}
# Two lines whose points all agree to this relative distance (on a log axis) look like one line.
OVERLAP_REL = 0.02
# line style per (p mass, p space): solid consistent, dashed lumped; the broken-tangential p
# dash-dotted (consistent) and dash-dot-dotted (lumped)
PM_STYLE = {("consistent", "continuous"): "-", ("lumped", "continuous"): "--",
            ("consistent", "broken-tangential"): "-.",
            ("lumped", "broken-tangential"): (0, (6, 2, 1, 2, 1, 2))}
# a series that does not converge is drawn pale (its status is in the tables)
PALE = 0.35


def _variant_style(e):
    """(kwargs of plot(), label) of a series / δ-limit / timing entry: colour per u space, p mass
    and p space, marker per multiplier (hollow for continuous u), line style per p mass and p space
    (PM_STYLE); labels as the tables' (read.variant_label: broken/M1, broken/M1/lumped,
    broken/M1/ptangential)."""
    u, m, pm, ps = variant_of(e)
    kw = {"linestyle": PM_STYLE.get((pm, ps), ":"), "marker": MARK.get(m, "x"),
          "color": VARIANT_COLOR.get((u, pm, ps), "black")}
    if u != "broken":
        kw["markerfacecolor"] = "none"
    return kw, variant_label(u, m, pm, ps)


def _delta_axis(ax):
    """δ ticks written as the report writes δ (1e-2, not 10⁻² or 0.01)."""
    ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _: fmt_delta(float(f"{x:.6g}"))))
    ax.xaxis.set_minor_formatter(NullFormatter())


def _single_x(ax, xs, note):
    """One abscissa only: a decade either side, the ordinates padded by a factor 3 (matplotlib's
    own limits put a lone point on the frame), and a note saying why there is no line or slope."""
    x = xs[0]
    ax.set_xlim(x / 10, x * 10)
    ys = [y for line in ax.get_lines() for y in line.get_ydata() if y > 0]
    if ys:
        ax.set_ylim(min(ys) / 3, max(ys) * 3)
    ax.text(0.03, 0.03, note, transform=ax.transAxes, fontsize=7, va="bottom", ha="left",
            bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "0.7"})


def _overlap(a, b):
    """True when two point lists (x, y > 0) coincide to plotting accuracy."""
    return len(a) == len(b) and all(abs(xa - xb) <= OVERLAP_REL * max(xa, xb)
                                    and abs(ya - yb) <= OVERLAP_REL * max(ya, yb)
                                    for (xa, ya), (xb, yb) in zip(a, b))


def _figure_legend(fig, axes, note=None):
    """One legend for the whole figure, below the panels and off the data: each label once (the
    panels share their variants), in columns; `note` (e.g. what pale lines mean) under it."""
    seen = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if not lab.startswith("_"):
                seen.setdefault(lab, h)
    if not seen:
        return
    ncol = min(len(seen), 6)
    rows = -(-len(seen) // ncol)
    height = fig.get_size_inches()[1]
    note_band = 0.2 / height if note else 0.0  # a line of small text, in figure fractions
    fig.legend(list(seen.values()), list(seen), loc="lower center", ncol=ncol, fontsize=8,
               frameon=False, bbox_to_anchor=(0.5, note_band))
    if note:
        fig.text(0.5, 0.01, note, ha="center", va="bottom", fontsize=7, color="0.3")
    fig._legend_band = min(0.45, note_band + (0.22 * rows + 0.1) / height)  # read by _save


def _save(fig, folder, name):
    path = os.path.join(folder, name)
    fig.tight_layout(rect=(0, getattr(fig, "_legend_band", 0.0), 1, 1))
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return name


def _positive(e):
    return e is not None and e > 0


def rate_plot(folder, scene, rate_entries):
    """Errors against h per quantity (u = the exact or the reference solution, per the series'
    `against`); a series that does not converge is marked in its label by its status."""
    ents = [r for r in rate_entries if any(_positive(e) for e in r["errors"])]
    if not ents:
        return None
    qs = [q for q in QLABEL if any(r["quantity"] == q for r in ents)]
    fig, axes = plt.subplots(1, len(qs), figsize=(4.2 * len(qs), 4.6), squeeze=False)
    graded = any(r.get("mesh_parameter") == "N^-1/2" for r in ents)
    hname = "N^-1/2" if graded else "h"
    pale = False
    for ax, q in zip(axes[0], qs):
        for r in (r for r in ents if r["quantity"] == q):
            pts = [(h, e) for h, e in zip(r["h"], r["errors"]) if _positive(e)]
            if not pts:
                continue
            kw, label = _variant_style(r)
            if r["status"] != "converges":
                kw["alpha"], pale = PALE, True
            ax.loglog(*zip(*pts), **kw, label=label)
        _slope_guides(ax, [x for r in ents for x in r["h"] if _positive(x)],
                      [e for r in ents if r["quantity"] == q for e in r["errors"] if _positive(e)],
                      hname)
        ax.set_xlabel(hname)
        ax.set_title(QLABEL[q], fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    against = sorted({r["against"] for r in ents if r["against"]})
    fig.suptitle(f"{scene}: errors against {hname}"
                 + (f" (u = {' / '.join(against)})" if against else ""), fontsize=11)
    _figure_legend(fig, axes[0], "pale: a series that does not converge (see the tables)"
                   if pale else None)
    return _save(fig, folder, f"rates-{scene}.png")


def _slope_guides(ax, h, errors, hname):
    """Dotted slopes 1/2, 1 and 2 over the last two halvings of h, ending below the smallest
    error, labelled at their low end (below every data point, never on one)."""
    if len(set(h)) < 2 or not errors:
        return
    hs = sorted(set(h))
    h1, h0 = hs[0], hs[min(2, len(hs) - 1)]
    e1 = min(errors) / 3
    for p in (0.5, 1.0, 2.0):
        ax.loglog([h1, h0], [e1, e1 * (h0 / h1) ** p], color="0.4", ls=":", lw=0.8)
    ax.annotate(f"{hname}^½, ^1, ^2", (h1, e1), xytext=(0, -10), textcoords="offset points",
                fontsize=7, color="0.3", ha="left", va="top")
    lo, hi = ax.get_ylim()
    ax.set_ylim(min(lo, e1 / 4), hi)


def delta_plot(folder, scene, delta_entries):
    if not delta_entries:
        return None
    levels = sorted({d["level"] for d in delta_entries})
    lvl = levels[-1]
    qs = [q for q in ("u_l2", "p_l2", "lambda_l2") if any(d["quantity"] == q for d in delta_entries)]
    fig, axes = plt.subplots(1, len(qs), figsize=(4.2 * len(qs), 4.6), squeeze=False)
    for ax, q in zip(axes[0], qs):
        xs = set()
        for d in delta_entries:
            if d["quantity"] != q or d["level"] != lvl:
                continue
            pts = [(x, y) for x, y in zip(d["deltas"], d["diffs"]) if x > 0 and y > 0]
            if pts:
                s = d["slope"]
                xs.update(x for x, _ in pts)
                kw, label = _variant_style(d)
                ax.loglog(*zip(*pts), **kw, markersize=6, label=label)
        if len(xs) == 1:
            _single_x(ax, sorted(xs), f"one δ > 0 (δ = {fmt_delta(min(xs))}): no slope")
        elif not xs:
            ax.text(0.5, 0.5, "no difference above zero", transform=ax.transAxes, ha="center",
                    fontsize=8)
        if xs:
            _delta_axis(ax)
        ax.set_xlabel("δ")
        ax.set_title(f"‖{SYMBOL[q]}_δ − {SYMBOL[q]}_0‖", fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"{scene}, level {lvl}: distance to the δ = 0 solution (slopes in the table)",
                 fontsize=11)
    _figure_legend(fig, axes[0])
    return _save(fig, folder, f"delta-{scene}.png")


def work_precision_plot(folder, scene, timing_rows, ref_rows):
    """Error against the time spent on each level: the solver's sum of timings_s, a reference's
    total without its start-up (dolfinx's form compilation, cached between runs, which would
    draw a zigzag of cache hits and misses); the start-up range is written under the plot."""
    pts = [t for t in timing_rows if t["u_l2"] is not None and t["u_l2"] > 0 and t["total_s"] > 0]
    rpts = [r for r in ref_rows if (r.get("errors") or {}).get("u_l2") and r.get("total_s")]
    if not pts and not rpts:
        return None
    fig, ax = plt.subplots(figsize=(6.4, 5.2))
    for v in sorted({variant_of(t) for t in pts}):
        sel = sorted((t for t in pts if variant_of(t) == v
                      and t["delta"] == min(x["delta"] for x in pts)), key=lambda t: t["level"])
        if sel:
            kw, label = _variant_style(sel[0])
            ax.loglog([t["total_s"] for t in sel], [t["u_l2"] for t in sel], **kw, label=label)

    def work(r):
        return max(r["total_s"] - (r.get("startup_s") or 0.0), 1e-6)
    ref_pts = {tool: [(work(r), r["errors"]["u_l2"]) for r in sorted(
        (r for r in rpts if r["tool"] == tool), key=lambda r: r["level"])]
        for tool in sorted({r["tool"] for r in rpts})}
    overlapping = len(ref_pts) == 2 and _overlap(*ref_pts.values())
    for tool, xy in ref_pts.items():
        style = dict(REF_STYLE.get(tool, {"marker": "x", "linestyle": "-.", "color": "black",
                                          "label": f"reference {tool}"}))
        if overlapping:
            style["label"] += " (overlapping)"
        ax.loglog(*zip(*xy), **style)
    startup = {tool: [r.get("startup_s") or 0.0 for r in rpts if r["tool"] == tool]
               for tool in ref_pts}
    note = "; ".join(f"{tool} start-up {min(s):.2g}–{max(s):.2g} s per level, not plotted"
                     for tool, s in startup.items() if s and max(s) > 0)
    ax.set_xlabel("time per level [s] (solver: sum of timings_s; references: without start-up)")
    ax.set_ylabel("‖u_h − u‖_L²")
    ax.set_title(f"{scene}: work–precision", fontsize=11)
    ax.grid(True, which="both", alpha=0.3)
    _figure_legend(fig, [ax], note or None)
    return _save(fig, folder, f"work-precision-{scene}.png")


def delta_reference_plot(folder, scene, agreement):
    """Distance to the reference of the same level as δ decreases: it falls with δ until it reaches
    the discretisation floor of the level (the δ = 0 value, dotted), and the floor falls with h."""
    rows = [a for a in agreement if a["kind"] == "solver_vs_reference" and a.get("e_u") is not None]
    if not rows:
        return None
    tool = sorted({a["reference"] for a in rows})[0]
    mult = sorted({a["multiplier"] for a in rows})[-1]
    spaces = sorted({(a["u_space"], mult, p_mass(a), p_space(a)) for a in rows if a["delta"] > 0},
                    key=variant_order)
    if not spaces:  # δ = 0 only: the reference tables say it all
        return None
    fig, axes = plt.subplots(1, len(spaces), figsize=(4.6 * len(spaces), 4.6), squeeze=False)
    for ax, v in zip(axes[0], spaces):
        sel = [a for a in rows if a["reference"] == tool and variant_of(a) == v]
        deltas = sorted({a["delta"] for a in sel if a["delta"] > 0})
        if not deltas:
            continue
        for lvl in sorted({a["level"] for a in sel}):
            pts = sorted((a["delta"], a["e_u"]) for a in sel if a["level"] == lvl and a["delta"] > 0)
            floor = [a["e_u"] for a in sel if a["level"] == lvl and a["delta"] == 0]
            line = ax.loglog(*zip(*pts), marker="o", label=f"level {lvl}")[0] if pts else None
            if floor and line is not None:
                ax.axhline(floor[0], color=line.get_color(), ls=":", lw=0.8)
        if len(deltas) == 1:
            _single_x(ax, deltas, f"one δ > 0 (δ = {fmt_delta(deltas[0])}): one point per level")
        _delta_axis(ax)
        ax.set_xlabel("δ (dotted: δ = 0, the floor of the level)")
        ax.set_title(variant_label(*v), fontsize=10)
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"{scene}: ‖u_δh − u_{tool}‖_L² at each level", fontsize=11)
    _figure_legend(fig, axes[0])
    return _save(fig, folder, f"delta-reference-{scene}.png")
