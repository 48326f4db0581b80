"""PNG plots (matplotlib, Agg backend). Each function returns the file name written or None.

Sizes: a figure is at most MAX_COLS × PANEL_W = 11.2 inches (1120 px) wide; the page shows it at
that width in a 1280 px window and about 772 px wide in an 800 px one (the page's body less its
padding). Its smallest text, a mathtext sub- or superscript of a MATH_PT text (SCRIPT × 14 =
9.8 pt, 13.6 px), is then 13.6 and 9.4 CSS px; plain text is MIN_PT; tick labels are plain text
(1e-3, as the report writes numbers), never 10 with a small exponent. Each PNG carries its
smallest text in its own pixels (render.MIN_FONT_KEY, a PNG text chunk) for the page that shows
it (render._img)."""
import math
import os
import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.text import Text  # noqa: E402
from matplotlib.ticker import FixedLocator, FuncFormatter, NullFormatter  # noqa: E402

from .cases import (DEFAULT_P_MASS, p_mass, p_space, p_space_tag, variant_label,  # noqa: E402
                    variant_of, variant_order)
from .render import MIN_FONT_KEY, REFERENCE_NAMES, fmt_delta  # noqa: E402

DPI = 100
PANEL_W, PANEL_H = 2.8, 2.35  # one panel with its title and tick labels [inches]
TITLE_H = 0.45  # the figure's title [inches]
MAX_COLS = 4  # panels per row
MIN_PT = 10.5  # plain text: ticks, legend, notes, axis labels without scripts
SCRIPT = 0.7  # mathtext's size of a sub- or superscript, relative to its text
MATH_PT = 14  # a text with sub- or superscripts: its scripts 9.8 pt
RC = {"figure.dpi": DPI, "savefig.dpi": DPI, "font.size": MIN_PT, "xtick.labelsize": MIN_PT,
      "ytick.labelsize": MIN_PT, "legend.fontsize": MIN_PT, "axes.labelsize": MATH_PT,
      "axes.titlesize": MATH_PT, "figure.titlesize": MATH_PT, "legend.handlelength": 2.4,
      "legend.columnspacing": 1.2, "legend.labelspacing": 0.35, "legend.borderpad": 0.2,
      # a minor tick's label as far from the axis as a major one's (3.5 + 3.5 = 2 + 5)
      "xtick.minor.pad": 5.0, "ytick.minor.pad": 5.0}

QLABEL = {"u_l2": "$‖u_h - u‖_{L²}$", "p_l2": "$‖p_h - ∇u‖_{L²}$", "p_x": "$‖p_h - ∇u‖_X$",
          "lambda_l2": "$‖λ_h - [u]‖_{L²(Γc)}$"}
# one spelling per symbol in every plot: λ, never "lambda"
SYMBOL = {"u_l2": "u", "p_l2": "p", "p_x": "p", "lambda_l2": "λ"}
# the parts of a variant, as a note under a figure names them
PARTS = ("u space", "multiplier", "p mass", "p space")
# a panel as a note under the figure names it (a no-break space: never wrapped inside)
PANEL_NAME = {"u_l2": "u", "p_l2": "p\u00a0(L²)", "p_x": "p\u00a0(X)", "lambda_l2": "λ"}
# the mesh parameter of the series (read.py's "h" or "N^-1/2") as the axes write it
MESH_NAME = {"h": "h", "N^-1/2": "$N^{-1/2}$", "N_V^-1/2": "$N_V^{-1/2}$"}
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
# or a colour-blind reader still sees two), and unlike any solver variant's marker and line
# (PM_STYLE: dolfinx's long dashes, not the broken-tangential p's dash-dot).
REF_STYLE = {"dolfinx": {"marker": "*", "linestyle": (0, (10, 3)), "color": "black",
                         "markersize": 9,
                         "label": "reference dolfinx"},
             "freefem": {"marker": "D", "linestyle": ":", "color": "tab:gray", "markersize": 6,
                         "markerfacecolor": "none", "label": "reference FreeFEM"}}
# A reference curve of the h → 0 plot is drawn thicker and over the solver's (up to 18) lines.
REF_LINE = {"linewidth": 2.0, "zorder": 4}
# Two lines whose points all agree to this relative distance (on a log axis) look like one line.
OVERLAP_REL = 0.02
# line style per (p mass, p space): solid consistent, dashed lumped; the broken-tangential p
# dash-dotted (consistent) and dash-dot-dotted (lumped)
PM_STYLE = {("consistent", "continuous"): "-", ("lumped", "continuous"): "--",
            ("consistent", "broken-tangential"): "-.",
            ("lumped", "broken-tangential"): (0, (6, 2, 1, 2, 1, 2))}
# a series that does not converge is drawn pale (its status is in the tables)
PALE = 0.35
# δ values up to this many are each a tick of the δ axis (more: a tick per decade or two)
MAX_DELTA_TICKS = 8
# the legend's columns at most; the figure's margin around the legend and notes [inches]
MAX_LEGEND_COLS = 6
PAD_IN = 0.08
# tight_layout's margin around the panels [font sizes] (matplotlib's 1.08: a line of white space)
TIGHT_PAD = 0.8
# the work–precision plot's one panel [inches]
WORK_SIZE = (7.0, 4.6)
# the part of a panel's height kept below the slope guides for their label
LABEL_ROOM = 0.15


def _variant_style(e):
    """(kwargs of plot(), label) of a series / δ-limit / timing entry: colour per u space, p mass
    and p space, marker per multiplier (hollow for continuous u), line style per p mass and p space
    (PM_STYLE); labels as the tables' (cases.variant_label: broken/M1, broken/M1/lumped,
    broken/M1/ptangential)."""
    u, m, pm, ps = variant_of(e)
    kw = {"linestyle": PM_STYLE.get((pm, ps), ":"), "marker": MARK.get(m, "x"),
          "color": VARIANT_COLOR.get((u, pm, ps), "black")}
    if u != "broken":
        kw["markerfacecolor"] = "none"
    return kw, variant_label(u, m, pm, ps)


def _number(x):
    """A tick value as the report writes numbers: 1e-3, 2e-3, 1 (fmt_delta's shortest form)."""
    return fmt_delta(float(f"{x:.6g}"))


def _minor_label(axis):
    """A formatter of an axis' minor ticks: on an axis spanning under two decades (h of a few
    levels) the 2s and 5s are labelled, under half a decade every one, so the axis never shows a
    single label; on a longer one none."""
    def label(x, _):
        lo, hi = axis.get_view_interval()
        decades = math.log10(hi / lo)
        coeff = round(x / 10 ** math.floor(math.log10(x) + 1e-9))
        return _number(x) if decades < 0.5 or (decades < 2 and coeff in (2, 5)) else ""
    return FuncFormatter(label)


def _log_axes(ax):
    """Both log axes labelled in plain text, 1e-3 (_number), at the decades and the labelled minor
    ticks (_minor_label)."""
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_formatter(FuncFormatter(lambda x, _: _number(x)))
        axis.set_minor_formatter(_minor_label(axis))


def _delta_axis(ax, deltas):
    """δ ticks written as the report writes δ (1e-2, not 10⁻² or 0.01); at most MAX_DELTA_TICKS
    δ values: a tick at each of them, the δ of the data (they fell between them before)."""
    ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _: _number(x)))
    ax.xaxis.set_minor_formatter(NullFormatter())
    if len(deltas) <= MAX_DELTA_TICKS:
        ax.xaxis.set_major_locator(FixedLocator(sorted(deltas)))


def _single_x(ax, xs, note):
    """One abscissa only: a decade either side, the ordinates padded by a factor 3 (matplotlib's
    own limits put a lone point on the frame), and a note saying why there is no line or slope."""
    x = xs[0]
    ax.set_xlim(x / 10, x * 10)
    ys = [y for line in ax.get_lines() for y in line.get_ydata() if y > 0]
    if ys:
        ax.set_ylim(min(ys) / 3, max(ys) * 3)
    ax.text(0.03, 0.03, note, transform=ax.transAxes, va="bottom", ha="left",
            bbox={"facecolor": "white", "alpha": 0.8, "edgecolor": "0.7"})


def _overlap(a, b):
    """True when two point lists (x, y > 0) coincide to plotting accuracy."""
    return len(a) == len(b) and all(abs(xa - xb) <= OVERLAP_REL * max(xa, xb)
                                    and abs(ya - yb) <= OVERLAP_REL * max(ya, yb)
                                    for (xa, ya), (xb, yb) in zip(a, b))


def _data_lines(ax):
    """(label, [(x, y)]) of each labelled line of a panel: the series and references, not the
    guides."""
    return [(ln.get_label(), list(zip(ln.get_xdata(), ln.get_ydata()))) for ln in ax.get_lines()
            if not ln.get_label().startswith("_")]


def _coinciding(ax):
    """The groups (≥ 2 labels, in drawing order) of a panel's lines that coincide to plotting
    accuracy (_overlap with the group's first line): only the last drawn shows."""
    groups = []
    for label, pts in _data_lines(ax):
        for g in groups:
            if _overlap(g[0][1], pts):
                g.append((label, pts))
                break
        else:
            groups.append([(label, pts)])
    return [[label for label, _ in g] for g in groups if len(g) > 1]


def _component(i, x, varying, name_p_mass=False):
    """Part i of a variant's label (u space, multiplier, p mass, p space); the consistent p mass
    and the continuous p space ("pcontinuous", as "ptangential") are named only where they vary
    within a group, the consistent p mass also where `name_p_mass` (a note of a figure with both
    p masses: "broken/{M0 = M1}" was read as covering the lumped lines too)."""
    if i == 2:
        return x if varying or name_p_mass or x != DEFAULT_P_MASS else ""
    if i == 3:
        return (p_space_tag(x) or f"p{x}") if varying else p_space_tag(x)
    return x


def _product(labels, variants):
    """The values of each part (u space, multiplier, p mass, p space) of the variants of `labels`
    where they are every combination of them (broken u with M1 and M1star, each p mass); None
    otherwise, or where a line is not a variant (a reference). `variants`: {label: variant}."""
    vs = list(dict.fromkeys(variants.get(label) for label in labels))
    if None in vs:
        return None
    values = [list(dict.fromkeys(v[i] for v in vs)) for i in range(4)]
    return values if math.prod(len(x) for x in values) == len(vs) else None


def _product_text(values, each=(), name_p_mass=False):
    """The label of a product of variants (_product), the parts that vary in braces:
    "broken/{M1 = M1star}/{consistent = lumped}"; the parts `each` are left out and said after
    it: "broken/{M1 = M1star} with each p mass and p space"; `name_p_mass`: _component's."""
    parts = []
    for i, vals in enumerate(values):
        words = [_component(i, x, len(vals) > 1, name_p_mass and i not in each) for x in vals]
        if i in each:
            continue
        if len(words) > 1:
            parts.append("{" + " = ".join(words) + "}")
        elif words[0]:
            parts.append(words[0])
    return "/".join(parts) + (f" with each {' and '.join(PARTS[i] for i in each)}" if each else "")


def _group_text(labels, variants, names=None, name_p_mass=False):
    """The label of lines that coincide: _product_text of a product of variants, otherwise its
    lines joined by " = ", a reference by its tool (`names`: {label: short name}):
    "broken/M1 = dolfinx"."""
    values = _product(labels, variants)
    if values:
        return _product_text(values, name_p_mass=name_p_mass)
    return " = ".join((names or {}).get(label, label) for label in labels)


def _panel_texts(groups, variants, names, name_p_mass=False):
    """The texts of a panel's groups of coinciding lines. Groups alike but for parts that are one
    value in each (broken/{M1 = M1star} of each p mass and p space, four groups) are one text
    when together they are every combination of those parts; the references' groups last;
    `name_p_mass`: _component's."""
    alike, others = {}, []
    for g in groups:
        values = _product(g, variants)
        if values is None:
            others.append(_group_text(g, variants, names, name_p_mass))
            continue
        varying = tuple((i, tuple(v)) for i, v in enumerate(values) if len(v) > 1)
        alike.setdefault(varying, []).append(values)
    texts = []
    for varying, members in alike.items():
        union = [list(dict.fromkeys(x for m in members for x in m[i])) for i in range(4)]
        each = [i for i, v in enumerate(union) if len(v) > 1 and i not in dict(varying)]
        if len(members) > 1 and math.prod(len(union[i]) for i in each) == len(members):
            texts.append(_product_text(union, each, name_p_mass))
        else:
            texts += [_product_text(m, name_p_mass=name_p_mass) for m in members]
    return texts + others


def _merged(panels, groups, variants):
    """The solver lines that coincide in every panel where one of them is drawn, as groups of
    labels in drawing order: one legend entry each."""
    drawn = {name: [label for label, _ in _data_lines(ax)] for name, ax in panels.items()}

    def together(a, b):
        return all((a in ls) == (b in ls)
                   and (a not in ls or any(a in g and b in g for g in groups[name]))
                   for name, ls in drawn.items())
    merged = []
    for label in dict.fromkeys(x for ls in drawn.values() for x in ls if x in variants):
        for g in merged:
            if all(together(label, x) for x in g):
                g.append(label)
                break
        else:
            merged.append([label])
    return [g for g in merged if len(g) > 1]


def _spread(groups, drawn):
    """The largest relative distance |a − b| / max(a, b) between the x or the y of the same point
    of any two lines of one of `groups` (lists of labels) in any panel where both are drawn
    (`drawn`: {panel: {label: points}}): what a caption saying those lines coincide may claim
    (a group joins a line within OVERLAP_REL of its first one, so two members may be farther
    apart)."""
    worst = 0.0
    for pts in drawn.values():
        for g in groups:
            lines = [pts[label] for label in g if label in pts]
            for i, a in enumerate(lines):
                for b in lines[i + 1:]:
                    worst = max([worst] + [abs(u - v) / max(u, v) for pa, pb in zip(a, b)
                                           for u, v in zip(pa, pb)])
    return worst


def _within(spread):
    """A caption's tolerance: "identical points", or "every point within 1.8 %", the measured
    spread (_spread) rounded up to two significant digits (so it holds for every line)."""
    if spread == 0:
        return "identical points"
    pct = 100 * spread
    digits = 1 - math.floor(math.log10(pct))
    bound = math.ceil(pct * 10 ** digits - 1e-9) / 10 ** digits
    return f"every point within {bound:g} %"


def _coincidences(panels, variants, names=None):
    """(legend groups [(label, [line labels])], note) of the lines that lie on top of each other
    (only the last drawn shows): those that coincide in every panel are one legend entry
    (_merged, _group_text); those that coincide in some panels are named in a note, per panel
    (panels alike together). Each sentence states the largest distance between the lines it
    covers (_spread), and a figure with both p masses names the consistent one in the note.
    `panels`: {name: axes}; `variants`, `names`: as _group_text's."""
    groups = {name: _coinciding(ax) for name, ax in panels.items()}
    drawn = {name: dict(_data_lines(ax)) for name, ax in panels.items()}
    merged = _merged(panels, groups, variants)
    known = [set(g) for g in merged]
    both_masses = len({v[2] for v in variants.values()}) > 1
    panels_of = {}
    for panel, gs in groups.items():
        rest = [g for g in gs if set(g) not in known]
        texts = tuple(_panel_texts(rest, variants, names, both_masses))
        if texts:
            panels_of.setdefault(texts, []).append((panel, rest))
    out = ([f"“=” in the legend: lines on top of each other ({_within(_spread(merged, drawn))})"]
           if merged else [])
    if panels_of:
        out.append(("Also" if merged else "Lines on top of each other") + " in " + "; in ".join(
            f"{', '.join(p for p, _ in where)}: {', '.join(texts)} ("
            + _within(max(_spread(rest, {p: drawn[p]}) for p, rest in where)) + ")"
            for texts, where in panels_of.items()))
    return [(_group_text(g, variants), g) for g in merged], (". ".join(out) + ".") if out else None


def _panels(n):
    """A figure of n panels, at most MAX_COLS per row (as few rows as that allows, filled
    evenly), and its axes in reading order. Three panels a row or more take the whole width of
    MAX_COLS panels: a legend of up to 20 entries needs its three columns."""
    rows = -(-n // MAX_COLS)
    cols = -(-n // rows)
    width = PANEL_W * (MAX_COLS if cols >= 3 else cols)
    fig, axes = plt.subplots(rows, cols, figsize=(width, PANEL_H * rows + TITLE_H), squeeze=False)
    axes = list(axes.flat)
    for ax in axes[n:]:
        fig.delaxes(ax)
    return fig, axes[:n]


def _legend_entries(axes, merged=()):
    """{label: handle}: each label once (the panels share their variants and references); the
    lines of a merged group (label, labels) one entry under the group's label, their handles
    drawn over each other as in the panels."""
    seen = {}
    for ax in axes:
        for h, label in zip(*ax.get_legend_handles_labels()):
            if not label.startswith("_"):
                seen.setdefault(label, h)
    group_of = {x: (text, g) for text, g in merged for x in g}
    entries = {}
    for label, h in seen.items():
        text, g = group_of.get(label, (label, None))
        if text not in entries:
            entries[text] = tuple(seen[x] for x in g) if g else h
    return entries


def _fitting_legend(fig, entries, y, renderer):
    """The figure's legend with its lower edge y inches above the figure's bottom, in as many
    columns (at most MAX_LEGEND_COLS) as fit the figure's width: it was clipped on both sides."""
    width = fig.bbox.width - 2 * PAD_IN * fig.dpi
    for ncol in range(min(len(entries), MAX_LEGEND_COLS), 0, -1):
        legend = fig.legend(list(entries.values()), list(entries), loc="lower center", ncol=ncol,
                            frameon=False, borderaxespad=0, bbox_transform=fig.dpi_scale_trans,
                            bbox_to_anchor=(fig.get_size_inches()[0] / 2, y))
        if ncol == 1 or legend.get_window_extent(renderer).width <= width:
            return legend
        legend.remove()


def _wrapped(fig, text, renderer):
    """`text` broken into lines that fit the figure's width (at the width of its average
    character, with a margin)."""
    probe = fig.text(0, 0, text)
    width = probe.get_window_extent(renderer).width
    probe.remove()
    chars = int(len(text) * 0.95 * (fig.bbox.width - 2 * PAD_IN * fig.dpi) / max(width, 1.0))
    return textwrap.fill(text, max(chars, 20))


def _finish(fig, axes, notes=(), merged=()):
    """The figure's layout: under the panels one legend for the whole figure, off the data, then
    the notes (what pale lines mean, which lines coincide, …) as one paragraph wrapped to the
    width; `merged`: the groups of lines that are one legend entry (_coincidences). The figure
    grows by their height, so the panels keep their size and nothing is clipped."""
    renderer = fig.canvas.get_renderer()
    w, h = fig.get_size_inches()
    y = PAD_IN
    note = " ".join(n for n in notes if n)
    if note:
        t = fig.text(w / 2, y, _wrapped(fig, note, renderer), ha="center", va="bottom",
                     color="0.3", transform=fig.dpi_scale_trans)
        y += t.get_window_extent(renderer).height / fig.dpi + PAD_IN
    entries = _legend_entries(axes, merged)
    if entries:
        legend = _fitting_legend(fig, entries, y + PAD_IN, renderer)
        y += legend.get_window_extent(renderer).height / fig.dpi + 2 * PAD_IN
    band = y if y > PAD_IN else 0.0
    fig.set_size_inches(w, h + band)
    fig.tight_layout(pad=TIGHT_PAD, rect=(0, band / (h + band), 1, 1))


def _shown_pt(t):
    """The size a text is drawn at: its font size, SCRIPT of it where mathtext writes a sub- or
    superscript (the smallest part of the text)."""
    s = t.get_text()
    math_part = s.count("$") >= 2 and any(c in s for c in "^_")
    return t.get_fontsize() * (SCRIPT if math_part else 1.0)


def min_font_px(fig):
    """The smallest text of a figure (each drawn text's _shown_pt), in the PNG's pixels."""
    return min(_shown_pt(t) for t in fig.findobj(Text)
               if t.get_visible() and t.get_text().strip()) * fig.dpi / 72


def _save(fig, folder, name):
    """Writes the laid-out figure (_finish) with its smallest text in the MIN_FONT_KEY chunk."""
    path = os.path.join(folder, name)
    fig.canvas.draw()
    fig.savefig(path, dpi=fig.dpi, metadata={MIN_FONT_KEY: f"{min_font_px(fig):.2f}"})
    plt.close(fig)
    return name


def _positive(e):
    return e is not None and e > 0


def _points(xs, ys):
    """The (x, y) of a series that a log plot can show (y > 0)."""
    return [(x, y) for x, y in zip(xs, ys) if _positive(x) and _positive(y)]


def _reference_line(ax, r):
    """A reference's curve in its panel: REF_STYLE (black stars dash-dotted, grey hollow diamonds
    dotted), thicker and over the solver's lines, labelled by the caller (its error, or its
    distance to its finest level). Returns whether there was a point to draw."""
    pts = _points(r["h"], r["errors"])
    if pts:
        style = dict(REF_STYLE.get(r["tool"], {"marker": "x", "linestyle": "-.",
                                               "color": "black"}), **REF_LINE)
        style["label"] = r["label"]
        ax.loglog(*zip(*pts), **style)
    return bool(pts)


@matplotlib.rc_context(RC)
def rate_plot(folder, scene, rate_entries, ref_series=None, axis_note=None):
    """Errors against h per quantity (u = the exact or the reference solution, per the series'
    `against`); a series that does not converge is pale. `ref_series` (dicts of tool, quantity,
    h, errors, label): the references' own curves, drawn over the series of their quantity. A
    note names the lines that lie on top of each other; `axis_note` says what x is (the x of
    the series' mesh_parameter, MESH_NAME)."""
    ents = [r for r in rate_entries if any(_positive(e) for e in r["errors"])]
    if not ents:
        return None
    qs = [q for q in QLABEL if any(r["quantity"] == q for r in ents)]
    fig, axes = _panels(len(qs))
    params = [r.get("mesh_parameter") for r in ents if r.get("mesh_parameter") in MESH_NAME]
    hname = MESH_NAME[params[0] if params else "h"]
    pale, variants, names = False, {}, {}
    for ax, q in zip(axes, qs):
        for r in (r for r in ents if r["quantity"] == q):
            pts = _points(r["h"], r["errors"])
            if not pts:
                continue
            kw, label = _variant_style(r)
            variants[label] = variant_of(r)
            if r["status"] != "converges":
                kw["alpha"], pale = PALE, True
            ax.loglog(*zip(*pts), **kw, label=label)
        for r in (r for r in ref_series or [] if r["quantity"] == q):
            if _reference_line(ax, r):
                names[r["label"]] = REFERENCE_NAMES.get(r["tool"], r["tool"])
        _slope_guides(ax)
        _log_axes(ax)
        ax.set_xlabel(hname)
        ax.set_title(QLABEL[q])
        ax.grid(True, which="both", alpha=0.3)
    merged, note = _coincidences({PANEL_NAME[q]: ax for ax, q in zip(axes, qs)}, variants, names)
    against = sorted({r["against"] for r in ents if r["against"]})
    fig.suptitle(f"{scene}: errors against {hname}"
                 + (f" (u = {' / '.join(against)})" if against else ""))
    _finish(fig, axes, [axis_note, "Pale: a series that does not converge (see the tables)."
                        if pale else None, note], merged)
    return _save(fig, folder, f"rates-{scene}.png")


def _slope_guides(ax):
    """Dotted slopes 1/2, 1 and 2 over the last two halvings of the mesh parameter of the panel's
    finest series (the smallest plotted one and the one two levels coarser), ending below the
    panel's smallest value, labelled at their low end (below every data point, never on one)."""
    lines = [pts for _, pts in _data_lines(ax)]
    if not lines:
        return
    finest = min(lines, key=lambda pts: min(x for x, _ in pts))
    xs = sorted({x for x, _ in finest})
    if len(xs) < 2:
        return
    h1, h0 = xs[0], xs[min(2, len(xs) - 1)]
    e1 = min(y for pts in lines for _, y in pts) / 3
    for p in (0.5, 1.0, 2.0):
        ax.loglog([h1, h0], [e1, e1 * (h0 / h1) ** p], color="0.4", ls=":", lw=1.0)
    ax.annotate("slopes ½, 1, 2", (h1, e1), xytext=(0, -3), textcoords="offset points",
                color="0.3", ha="left", va="top")
    lo, hi = ax.get_ylim()
    ax.set_ylim(min(lo, e1 / (hi / e1) ** LABEL_ROOM), hi)


@matplotlib.rc_context(RC)
def delta_plot(folder, scene, delta_entries):
    """Distance to the δ = 0 solution against δ at the finest level, per quantity; a tick at each
    δ of the data, and a note naming the lines that lie on top of each other."""
    if not delta_entries:
        return None
    lvl = max(d["level"] for d in delta_entries)
    qs = [q for q in ("u_l2", "p_l2", "lambda_l2")
          if any(d["quantity"] == q for d in delta_entries)]
    fig, axes = _panels(len(qs))
    variants = {}
    for ax, q in zip(axes, qs):
        xs = set()
        for d in delta_entries:
            if d["quantity"] != q or d["level"] != lvl:
                continue
            pts = _points(d["deltas"], d["diffs"])
            if pts:
                xs.update(x for x, _ in pts)
                kw, label = _variant_style(d)
                variants[label] = variant_of(d)
                ax.loglog(*zip(*pts), **kw, markersize=6, label=label)
        if len(xs) == 1:
            _single_x(ax, sorted(xs), f"one δ > 0 (δ = {fmt_delta(min(xs))}): no slope")
        elif not xs:
            ax.text(0.5, 0.5, "no difference above zero", transform=ax.transAxes, ha="center")
        _log_axes(ax)
        if xs:
            _delta_axis(ax, xs)
        ax.set_xlabel("δ")
        ax.set_title(f"$‖{SYMBOL[q]}_δ - {SYMBOL[q]}_0‖$")
        ax.grid(True, which="both", alpha=0.3)
    merged, note = _coincidences({SYMBOL[q]: ax for ax, q in zip(axes, qs)}, variants)
    fig.suptitle(f"{scene}, level {lvl}: distance to the δ = 0 solution (slopes in the table)")
    _finish(fig, axes, [note], merged)
    return _save(fig, folder, f"delta-{scene}.png")


@matplotlib.rc_context(RC)
def work_precision_plot(folder, scene, timing_rows, ref_rows):
    """Error against the time spent on each level: the solver's sum of timings_s, a reference's
    total without its start-up (dolfinx's form compilation, cached between runs, which would
    draw a zigzag of cache hits and misses); the start-up range is written under the plot."""
    pts = [t for t in timing_rows if t["u_l2"] is not None and t["u_l2"] > 0 and t["total_s"] > 0]
    rpts = [r for r in ref_rows if (r.get("errors") or {}).get("u_l2") and r.get("total_s")]
    if not pts and not rpts:
        return None
    fig, ax = plt.subplots(figsize=WORK_SIZE)
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
    _log_axes(ax)
    ax.set_xlabel("time per level [s] (solver: sum of timings_s;\nreferences: without start-up)",
                  fontsize=MIN_PT)
    ax.set_ylabel(QLABEL["u_l2"])
    ax.set_title(f"{scene}: work–precision")
    ax.grid(True, which="both", alpha=0.3)
    _finish(fig, [ax], [note or None])
    return _save(fig, folder, f"work-precision-{scene}.png")


@matplotlib.rc_context(RC)
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
    fig, axes = _panels(len(spaces))
    for ax, v in zip(axes, spaces):
        sel = [a for a in rows if a["reference"] == tool and variant_of(a) == v]
        deltas = sorted({a["delta"] for a in sel if a["delta"] > 0})
        if not deltas:
            continue
        for lvl in sorted({a["level"] for a in sel}):
            pts = sorted((a["delta"], a["e_u"]) for a in sel
                         if a["level"] == lvl and a["delta"] > 0)
            floor = [a["e_u"] for a in sel if a["level"] == lvl and a["delta"] == 0]
            line = ax.loglog(*zip(*pts), marker="o", label=f"level {lvl}")[0] if pts else None
            if floor and line is not None:
                ax.axhline(floor[0], color=line.get_color(), ls=":", lw=0.8)
        if len(deltas) == 1:
            _single_x(ax, deltas, f"one δ > 0 (δ = {fmt_delta(deltas[0])}): one point per level")
        _log_axes(ax)
        _delta_axis(ax, deltas)
        ax.set_xlabel("δ (dotted: δ = 0, the floor)", fontsize=MIN_PT)
        ax.set_title(variant_label(*v), fontsize=MIN_PT)
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(f"{scene}: $‖u_{{δh}} - u_\\mathrm{{{tool}}}‖_{{L²}}$ at each level")
    _finish(fig, axes)
    return _save(fig, folder, f"delta-reference-{scene}.png")
