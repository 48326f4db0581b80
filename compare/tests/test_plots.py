"""The report's plots on synthetic entries: slope guides over the panel's own
data, legends and notes inside the image, coinciding lines said, a δ tick at each δ of the data,
the references' curves on the h → 0 plot, and the smallest text carried to the page."""
import os
import re

import pytest

COMPARE = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

from sdcompare_lib import plots, render
from sdcompare_lib.cases import BROKEN_TANGENTIAL

QUANTITIES = ("u_l2", "p_l2", "p_x", "lambda_l2")
# the width (CSS px) a plot is shown at in an 800 px window, and the smallest text it may show
NARROW_PX, MIN_CSS_PX = 772, 9


def variants():
    """The 18 variants of a scene with both p masses and both p spaces."""
    for u in ("broken", "continuous"):
        for m in ("M0", "M1", "M1star"):
            for pm in ("consistent", "lumped"):
                for ps in ("continuous", BROKEN_TANGENTIAL):
                    if u == "broken" or ps == "continuous":
                        yield u, m, pm, ps


def rate_entries(levels=3, graded=True):
    """Errors of every variant and quantity: M1 and M1star alike everywhere, M0 apart; on a
    graded scene the N^-1/2 of each u space, p mass and p space differs a little (its own mesh),
    as in open-graded."""
    out = []
    spaces = sorted({(u, pm, ps) for u, _, pm, ps in variants()})
    for u, m, pm, ps in variants():
        h0 = 0.06 * (1 + 0.004 * spaces.index((u, pm, ps))) if graded else 0.25
        hs = [h0 / 2 ** k for k in range(levels)]
        order = {"M0": 1.0, "M1": 1.5, "M1star": 1.5}[m] if u == "broken" else 0.02
        scale = (2.0 if pm == "lumped" else 1.0) * (1.5 if ps == BROKEN_TANGENTIAL else 1.0)
        for q in QUANTITIES:
            out.append({"u_space": u, "multiplier": m, "p_mass": pm, "p_space": ps,
                        "quantity": q, "h": hs, "errors": [scale * h ** order for h in hs],
                        "mesh_parameter": "N^-1/2" if graded else "h", "against": "exact",
                        "status": "converges" if u == "broken" else "expected failure"})
    return out


def ref_series(levels=3):
    return [{"tool": tool, "quantity": q, "h": [0.06 / 2 ** k for k in range(levels)],
             "errors": [f * 0.06 / 2 ** k for k in range(levels)], "label": f"{name}: its error"}
            for tool, name, f in (("dolfinx", "dolfinx", 0.3), ("freefem", "FreeFEM", 0.5))
            for q in ("u_l2", "p_l2", "lambda_l2")]


def delta_entries(deltas=(1.0, 1e-2, 1e-4, 1e-6)):
    """δ-limit entries: every broken variant alike; the continuous ones alike in u and p, their p
    masses apart in λ."""
    out = []
    for u, m, pm, ps in variants():
        for q in ("u_l2", "p_l2", "lambda_l2"):
            c = 1.0 if u == "broken" else 0.3 if q == "lambda_l2" and pm == "lumped" else 0.1
            out.append({"level": 2, "u_space": u, "multiplier": m, "p_mass": pm, "p_space": ps,
                        "quantity": q, "deltas": list(deltas), "diffs": [c * d for d in deltas],
                        "slope": 1.0})
    return out


def texts(fig):
    return [t.get_text() for t in fig.findobj(plots.Text) if t.get_visible() and t.get_text()]


def guides(ax):
    """The slope guides of a panel: its unlabelled lines."""
    return [ln for ln in ax.get_lines() if ln.get_label().startswith("_")]


def test_slope_guides_span_the_panels_data_and_read_plainly(figs):
    """Graded meshes: each variant's N^-1/2 is its own, so the union of all h held values a
    hair apart and the guides collapsed to a dot labelled "N^-1/2^½, ^1, ^2"."""
    assert plots.rate_plot("/nonexistent", "s", rate_entries())
    (fig,) = figs
    for ax in fig.axes:
        xs = [x for ln in ax.get_lines() if not ln.get_label().startswith("_")
              for x in ln.get_xdata()]
        lines = guides(ax)
        assert len(lines) == 3
        for ln in lines:  # three levels: the last two halvings are the whole data range
            assert list(ln.get_xdata()) == pytest.approx([min(xs), 4 * min(xs)])
        (label,) = [t.get_text() for t in ax.texts]
        assert label == "slopes ½, 1, 2"
        assert ax.get_xlabel() == "$N^{-1/2}$"
    assert not [t for t in texts(fig) if "N^-1/2" in t or "^½" in t]


def test_slope_guides_cover_the_last_two_halvings_of_a_longer_series(figs):
    assert plots.rate_plot("/nonexistent", "s", rate_entries(levels=5, graded=False))
    for ax in figs[0].axes:
        for ln in guides(ax):
            assert list(ln.get_xdata()) == pytest.approx([0.25 / 16, 0.25 / 4])


def assert_inside(fig):
    """Every legend and every text of the figure lies inside the image."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    box = fig.bbox
    assert fig.legends
    for legend in fig.legends:
        ext = legend.get_window_extent(renderer)
        assert box.x0 <= ext.x0 and ext.x1 <= box.x1 and box.y0 <= ext.y0 and ext.y1 <= box.y1
    for t in fig.texts + [ax.title for ax in fig.axes]:
        if t is not None and t.get_text():
            ext = t.get_window_extent(renderer)
            assert box.x0 <= ext.x0 and ext.x1 <= box.x1 and box.y0 <= ext.y0, t.get_text()


def test_legends_and_notes_lie_inside_the_image(figs):
    """The work–precision legend of 18 variants and two references was clipped on both sides
    (6 columns on a 6.4-inch figure): the columns now fit the figure, which grows to hold them."""
    timings = [{"level": lv, "u_space": u, "multiplier": m, "p_mass": pm, "p_space": ps,
                "delta": 0.0, "total_s": 0.1 * 4 ** lv, "u_l2": 0.1 / 2 ** lv}
               for u, m, pm, ps in variants() for lv in range(3)]
    refs = [{"tool": t, "level": lv, "total_s": c * 4 ** lv, "errors": {"u_l2": 0.05 / 2 ** lv}}
            for t, c in (("dolfinx", 0.3), ("freefem", 3.0)) for lv in range(3)]
    assert plots.work_precision_plot("/nonexistent", "s", timings, refs)
    assert plots.rate_plot("/nonexistent", "s", rate_entries(), ref_series())
    assert plots.delta_plot("/nonexistent", "s", delta_entries())
    for fig in figs:
        assert_inside(fig)
    labels = {t.get_text() for t in figs[0].legends[0].get_texts()}
    assert {"broken/M1/lumped/ptangential", "reference dolfinx", "reference FreeFEM"} <= labels


def test_coinciding_lines_are_one_legend_entry_or_named_in_a_note(figs):
    """Lines on top of each other were 12 legend entries of which 2 showed: those that coincide
    in every panel are one entry, "broken/{M1 = M1star}"; those that coincide in some panels are
    named in the note under the figure."""
    assert plots.rate_plot("/nonexistent", "s", rate_entries())
    assert plots.delta_plot("/nonexistent", "s", delta_entries())
    rates, delta = figs
    labels = [t.get_text() for t in rates.legends[0].get_texts()]
    assert "broken/{M1 = M1star}/lumped/ptangential" in labels and "broken/M0" in labels
    assert not [x for x in labels if x.startswith("broken/M1/")], labels
    assert {"continuous/{M0 = M1 = M1star}", "continuous/{M0 = M1 = M1star}/lumped"} <= set(labels)
    # every line keeps its own label in its panel (the tables' names)
    assert "broken/M1star/lumped" in [ln.get_label() for ln in rates.axes[0].get_lines()]
    labels = [t.get_text() for t in delta.legends[0].get_texts()]
    assert labels == ["broken/{M0 = M1 = M1star}/{consistent = lumped}/{pcontinuous = ptangential}",
                      "continuous/{M0 = M1 = M1star}", "continuous/{M0 = M1 = M1star}/lumped"]
    (note,) = [t.get_text().replace("\n", " ") for t in delta.texts if t is not delta._suptitle]
    assert note.startswith("“=” in the legend: lines on top of each other")
    assert note.startswith("“=” in the legend: lines on top of each other (identical points)")
    assert ("Also in u, p: continuous/{M0 = M1 = M1star}/{consistent = lumped} (identical "
            "points).") in note


def test_a_reference_among_coinciding_lines_is_named_by_its_tool():
    panel = plots.plt.figure().add_subplot()
    for label in ("broken/M1", "dolfinx: its error", "FreeFEM: its error"):
        panel.loglog([0.1, 0.05], [1e-2, 2.5e-3], label=label)
    groups = plots._coinciding(panel)
    assert groups == [["broken/M1", "dolfinx: its error", "FreeFEM: its error"]]
    text = plots._group_text(groups[0], {"broken/M1": ("broken", "M1", "consistent", "continuous")},
                             {"dolfinx: its error": "dolfinx", "FreeFEM: its error": "FreeFEM"})
    assert text == "broken/M1 = dolfinx = FreeFEM"
    plots.plt.close(panel.figure)


@pytest.mark.parametrize("deltas", [(1.0, 1e-2, 1e-4, 1e-6), (1e-2,)])
def test_delta_ticks_are_the_deltas_of_the_data(figs, deltas):
    """The ticks fell at 1e-7, 1e-5, … between the data's δ = 1e-6, 1e-4, …"""
    assert plots.delta_plot("/nonexistent", "s", delta_entries(deltas))
    fig = figs[0]
    fig.canvas.draw()
    for ax in fig.axes:
        assert list(ax.get_xticks()) == sorted(deltas)
        shown = [t.get_text() for t in ax.get_xticklabels()]
        assert shown == [render.fmt_delta(d) for d in sorted(deltas)]


def test_many_deltas_keep_matplotlibs_ticks(figs):
    deltas = [10.0 ** -k for k in range(10)]
    assert plots.delta_plot("/nonexistent", "s", delta_entries(deltas))
    for ax in figs[0].axes:
        assert not isinstance(ax.xaxis.get_major_locator(), plots.FixedLocator)


def test_reference_curves_are_drawn_over_the_solver_lines(figs):
    """ref_series: each reference in the panels of its quantities (none in p_x), in REF_STYLE,
    thicker and above the solver's lines, one legend entry per label."""
    assert plots.rate_plot("/nonexistent", "s", rate_entries(), ref_series())
    fig = figs[0]
    by_title = {ax.get_title(): ax for ax in fig.axes}
    for q, ax in ((q, by_title[plots.QLABEL[q]]) for q in QUANTITIES):
        lines = {ln.get_label(): ln for ln in ax.get_lines()}
        refs = [lines.get("dolfinx: its error"), lines.get("FreeFEM: its error")]
        if q == "p_x":
            assert refs == [None, None]
            continue
        solver_top = max(ln.get_zorder() for ln in ax.get_lines() if ln not in refs)
        for ln, tool in zip(refs, ("dolfinx", "freefem")):
            style = plots.REF_STYLE[tool]
            assert (ln.get_marker(), ln.get_color()) == (style["marker"], style["color"])
            assert ln.get_zorder() > solver_top and ln.get_linewidth() >= 2
            assert list(ln.get_xdata()) == pytest.approx([0.06, 0.03, 0.015])
    labels = [t.get_text() for t in fig.legends[0].get_texts()]
    assert labels.count("dolfinx: its error") == 1 and labels.count("FreeFEM: its error") == 1


def test_the_png_carries_its_smallest_text_to_the_page(tmp_path):
    """The widest plot (four panels) written to a file: its smallest text (a mathtext subscript
    counts at 70 %), in its own pixels, is in the PNG and on the page's <img>, which links to
    the file; shown 772 px wide (an 800 px window) it is at least 9 CSS px."""
    name = plots.rate_plot(str(tmp_path), "s", rate_entries(), ref_series())
    data = (tmp_path / name).read_bytes()
    font = float(render._png_texts(data)[render.MIN_FONT_KEY])
    width = int.from_bytes(data[16:20], "big")  # IHDR
    assert font == pytest.approx(plots.MATH_PT * plots.SCRIPT * plots.DPI / 72, abs=0.01)
    assert font * min(width, NARROW_PX) / width >= MIN_CSS_PX
    page = render._img(str(tmp_path), name)
    assert re.match(rf"<p class='plot'><a href='{name}'[^>]*><img id='rates-s' "
                    rf"alt='{name}' data-min-font-px='{font:.2f}' src='data:image/png;base64,",
                    page), page[:300]
