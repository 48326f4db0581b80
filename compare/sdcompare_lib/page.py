"""The one HTML page of sdcrack's pages: skeleton and stylesheet of the verification report
(render.py, RESULTS_DIR/report/index.html) and of the campaign index (tools/campaign_index.py,
DIR/index.html).

Standard library only (no numpy): the campaign index imports it from a plain /usr/bin/python3.
Conventions both pages follow: a table scrolls sideways inside its own box (`scroll_table`), the
page never does; a cell of at most SHORT_CELL characters has class "s" (does not wrap, aligned
right: numbers), a longer one class "t" (wraps, aligned left, keeps a readable width); a verdict
has class "PASS", "FAIL" or "INCONCLUSIVE" (green, red or a neutral grey, bold). Page sizes are
in CSS px.
"""
import html

# Cells up to this many characters do not wrap; longer ones (reasons, notes, commands) wrap and are
# left-aligned.
SHORT_CELL = 28

# The pages' style: at most 1200 px wide, never wider than the window (tables scroll in their
# own box, long text cells wrap but keep a readable width, images shrink; plots.py sizes its
# text so that it stays readable at the width of an 800 px window). Lists in cells and logs
# (<pre>) are the index's.
CSS = ("body{font-family:sans-serif;max-width:1200px;margin:auto;padding:1em}"
       "table{border-collapse:collapse;margin:0.5em 0;font-size:13px}"
       "div.scroll{overflow-x:auto;max-width:100%}"
       "td,th{border:1px solid #bbb;padding:2px 6px;text-align:right}"
       "th{background:#eee;text-align:center}"
       ".PASS{color:#070;font-weight:bold}.FAIL{color:#b00;font-weight:bold}"
       ".INCONCLUSIVE{color:#555;font-weight:bold}"
       "img{max-width:100%;height:auto}p.plot{margin:0.5em 0}p.plot img{display:block}"
       "code{font-size:11px;text-align:left;overflow-wrap:anywhere}"
       "td.s{white-space:nowrap}td.t{text-align:left;min-width:14em}"
       "td ul{margin:0;padding-left:1.2em}"
       "pre{background:#f6f6f6;padding:.5em;overflow-x:auto;max-width:100em}"
       "details{margin:0.4em 0}summary{cursor:pointer;color:#035;font-size:14px}"
       "p{overflow-wrap:anywhere}p.caption{margin:0.6em 0 0;font-style:italic}"
       "@media (max-width:900px){body{padding:0.4em}td.t{min-width:11em}}")


def cell_class(text):
    """"s" for a short cell (at most SHORT_CELL characters of text), "t" for a longer one."""
    return "s" if len(text) <= SHORT_CELL else "t"


def scroll_table(header_cells, row_lines):
    """The lines of a table that scrolls in its own box: a header row of `header_cells` (HTML of
    each <th>'s content) and `row_lines` (each a whole <tr>…</tr>)."""
    head = "".join(f"<th>{h}</th>" for h in header_cells)
    return [f"<div class='scroll'><table><tr>{head}</tr>", *row_lines, "</table></div>"]


def page(title, body_lines, heading=None):
    """A whole page: the <head> (UTF-8, the viewport of a phone, `title` as plain text, CSS),
    an <h1> (`heading`: its HTML; default: the title) and `body_lines` (HTML), one per line."""
    heading = html.escape(title) if heading is None else heading
    return "\n".join(["<!DOCTYPE html>", "<html lang='en'><head><meta charset='utf-8'>",
                      "<meta name='viewport' content='width=device-width, initial-scale=1'>",
                      f"<title>{html.escape(title)}</title><style>{CSS}</style></head><body>",
                      f"<h1>{heading}</h1>", *body_lines, "</body></html>"]) + "\n"
