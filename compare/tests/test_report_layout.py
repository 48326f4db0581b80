"""What a reader sees first, measured in headless Chromium: the report
opens with the verdict, then the h → 0 plot, then the δ → 0 plot, then the short variant table;
at 1280 and 800 px the page never scrolls sideways (wide tables scroll in their own box) and no
text cell is squeezed to a word per line; provenance is folded. Every plot's text is legible at
both widths and the plot links to its PNG; at 1280 px the whole h → 0 plot, its legend included,
is on the first screen. The campaign index says, one line per scene, what
converged at which rates and the first problem.

Chromium (Debian: chromium) runs the page with a script appended that measures the layout and
writes it into the DOM, which `--dump-dom` prints; the tests skip without Chromium."""
import json
import os
import re
import shutil
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

from conftest import run_env
from scene_text import set_key

MEASURE = """<script>
function posY(e) { return e ? e.getBoundingClientRect().top + window.scrollY : null; }
function bottomY(e) { return e ? e.getBoundingClientRect().bottom + window.scrollY : null; }
window.addEventListener('load', function () {
  var out = {
    width: window.innerWidth,
    scroll_width: document.documentElement.scrollWidth,
    verdict: posY(Array.from(document.querySelectorAll('p')).find(function (p) {
      return p.textContent.indexOf('Verdict:') === 0; })),
    rates: posY(document.querySelector('img[id^="rates-"]')),
    // the first screen's δ → 0 line and reference sentence: their bottoms
    delta_line: bottomY(Array.from(document.querySelectorAll('p')).find(function (p) {
      return p.textContent.indexOf('δ → 0 (Theorem 2.1)') === 0; })),
    reference_line: bottomY(Array.from(document.querySelectorAll('p')).find(function (p) {
      return p.textContent.indexOf('sdcrack against ') === 0; })),
    delta: posY(document.querySelector('img[id^="delta-"]:not([id^="delta-reference"])')),
    first_table: posY(document.querySelector('table')),
    provenance_open: Array.from(document.querySelectorAll('h2')).filter(function (h) {
      return h.textContent === 'Provenance'; }).map(function (h) {
      var d = h.nextElementSibling; return d && d.tagName === 'DETAILS' ? d.open : true; }),
    text_cells: Array.from(document.querySelectorAll('td.t')).filter(function (td) {
      return td.offsetParent !== null; }).map(function (td) {
      return td.getBoundingClientRect().width; }),
    images: Array.from(document.querySelectorAll('img')).filter(function (i) {
      return i.offsetParent !== null; }).map(function (i) {
      var r = i.getBoundingClientRect(), a = i.closest('a');
      return {id: i.id, width: r.width, natural: i.naturalWidth, bottom: r.bottom + window.scrollY,
              min_font_px: parseFloat(i.getAttribute('data-min-font-px')),
              href: a ? a.getAttribute('href') : null}; })
  };
  var pre = document.createElement('pre'); pre.id = 'layout';
  pre.textContent = JSON.stringify(out); document.body.appendChild(pre);
});
</script>"""


def chromium():
    return shutil.which("chromium") or shutil.which("chromium-browser")


def layout(page, width, tmp_path):
    """The measurements of `page` (an HTML file) in a window `width` px wide."""
    probe = tmp_path / f"probe-{width}.html"
    probe.write_text(page.read_text().replace("</body>", MEASURE + "</body>"))
    p = subprocess.run([chromium(), "--headless", "--no-sandbox", "--disable-gpu",
                        f"--window-size={width},900", "--virtual-time-budget=10000",
                        "--dump-dom", probe.as_uri()], capture_output=True, text=True, timeout=120)
    m = re.search(r'<pre id="layout">(.*?)</pre>', p.stdout, re.S)
    assert m, p.stderr[-2000:]
    return json.loads(m.group(1).replace("&quot;", '"').replace("&amp;", "&"))


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    """The default scene (mixed) at levels 0-2 with both references, judged: its report."""
    if not chromium():
        pytest.skip("Chromium not installed (apt-get install chromium)")
    exe = os.environ.get("SDCRACK_BIN") or os.path.join(ROOT, "target", "release", "sdcrack")
    if not os.access(exe, os.X_OK):
        pytest.skip("no sdcrack binary (cargo build --release, or SDCRACK_BIN)")
    tmp = tmp_path_factory.mktemp("layout")
    with open(os.path.join(ROOT, "scenes", "mixed.toml"), encoding="utf-8") as fh:
        text = set_key(fh.read(), "levels", "[0, 1, 2]")
    (tmp / "mixed.toml").write_text(text)
    env = dict(os.environ, MPLBACKEND="Agg")
    env.setdefault("FF_LOADPATH", "/usr/lib/freefem++")
    subprocess.run([exe, "run", str(tmp / "mixed.toml"), "--out", str(tmp), "--quiet"],
                   check=True, capture_output=True, env=env, timeout=900)
    p = subprocess.run([sys.executable, os.path.join(ROOT, "compare", "sdcompare"),
                        str(tmp / "mixed")], capture_output=True, text=True, env=env, timeout=900)
    assert p.returncode == 0, p.stdout[-2000:] + p.stderr[-2000:]
    return tmp / "mixed" / "report" / "index.html"


@pytest.fixture(scope="module")
def layouts(report, tmp_path_factory):
    """The report's measurements at 1280 and 800 px, each measured once for all the tests."""
    tmp = tmp_path_factory.mktemp("probe")
    return {width: layout(report, width, tmp) for width in (1280, 800)}


@pytest.mark.parametrize("width", [1280, 800])
def test_report_opens_with_verdict_plots_then_table(layouts, width):
    got = layouts[width]
    assert got["width"] == width
    assert got["verdict"] < got["rates"] < got["delta"] < got["first_table"], got
    # the h → 0 plot starts within the first screen (it was at y ≈ 2860 px below a 36-row
    # table before): the title, the scene line and the verdict come before it
    assert got["rates"] < 450, got
    assert got["provenance_open"] == [False]


@pytest.mark.parametrize("width", [1280, 800])
def test_report_never_scrolls_sideways(layouts, width):
    got = layouts[width]
    assert got["scroll_width"] <= width, got
    # a reason or note cell keeps a readable width (it was one word per line at 800 px)
    assert got["text_cells"] and min(got["text_cells"]) >= 120, sorted(got["text_cells"])[:5]


# The smallest text of a plot as shown, in CSS px (6 px at 800 px before this bound).
MIN_TEXT_CSS_PX = 9
# The first screen at 1280 px: the verdict and the whole h → 0 plot, its legend included.
FIRST_SCREEN_PX = 900


@pytest.mark.parametrize("width", [1280, 800])
def test_plots_are_legible_and_link_to_their_full_size_file(report, layouts, width):
    """Every plot's smallest text (data-min-font-px of its PNG, scaled by the width it is shown
    at) is at least MIN_TEXT_CSS_PX; every plot links to its PNG in the report folder; at 1280 px
    the h → 0 plot with its legend ends within the first screen."""
    images = layouts[width]["images"]
    assert any(i["id"].startswith("rates-") for i in images), images
    shown = {i["id"]: round((i["min_font_px"] or 0) * i["width"] / i["natural"], 2)
             for i in images}
    assert min(shown.values()) >= MIN_TEXT_CSS_PX, (shown, images)
    for i in images:
        assert i["href"] == i["id"] + ".png" and (report.parent / i["href"]).is_file(), i
    if width == 1280:
        rates = next(i for i in images if i["id"].startswith("rates-"))
        assert rates["bottom"] <= FIRST_SCREEN_PX, rates


INDEX_MEASURE = MEASURE.replace(
    "verdict: posY(", "rows: Array.from(document.querySelectorAll('tr')).slice(1).map("
    "function (tr) { return tr.textContent; }), verdict: posY(")


@pytest.mark.parametrize("width", [1280, 800])
def test_campaign_index_says_per_scene_what_converged(report, width, tmp_path):
    """tools/campaign_index.py on the report's results root: one row per scene with what converged,
    the last rates and the first problem (none here), and no sideways scrolling."""
    root = report.parent.parent.parent
    subprocess.run([sys.executable, os.path.join(ROOT, "tools", "campaign_index.py"), str(root)],
                   env=run_env(), check=True, capture_output=True, timeout=120)
    page = root / "index.html"
    probe = tmp_path / "index.html"
    probe.write_text(page.read_text().replace("</body>", INDEX_MEASURE + "</body>"))
    p = subprocess.run([chromium(), "--headless", "--no-sandbox", "--disable-gpu",
                        f"--window-size={width},900", "--virtual-time-budget=10000",
                        "--dump-dom", probe.as_uri()], capture_output=True, text=True, timeout=120)
    got = json.loads(re.search(r'<pre id="layout">(.*?)</pre>', p.stdout, re.S).group(1)
                     .replace("&quot;", '"').replace("&amp;", "&"))
    (row,) = got["rows"]
    # mixed runs both p masses: the last rates per p mass (sdcompare_lib/choices.py)
    assert row.startswith("mixedPASS6 of 12 variants converge; last rates per p mass: "
                          "consistent u "), row
    assert "6 declared expected failure(s)" in row and row.endswith("nonereport")
    assert got["scroll_width"] <= width, got


def test_first_screen_holds_the_verdict_the_delta_result_and_the_references(layouts):
    """At 1280 px the first screen shows the verdict, the δ → 0 line, the sentence on sdcrack
    against dolfinx and FreeFEM, then the h → 0 plot (which draws the references' curves,
    test_plots.py) whole."""
    got = layouts[1280]
    assert got["verdict"] < got["delta_line"] < got["reference_line"] < got["rates"], got
    rates = next(i for i in got["images"] if i["id"].startswith("rates-"))
    assert rates["bottom"] <= FIRST_SCREEN_PX, got
