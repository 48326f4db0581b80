"""tools/campaign_index.py's line per scene on sdcrack's errors against the references' (the
report's `glance`, written by sdcompare_lib/glance.py, whose tests make the line's numbers
false: compare/tests/test_glance.py): the index shows the report's line as written, and says
why when a report has none; from hand-made report.json files."""

import json
import pathlib
import subprocess
import sys

import ci_script
import pytest
from conftest import run_env

ROOT = pathlib.Path(__file__).resolve().parents[2]
ci = ci_script.load("tools/campaign_index.py")
LINE = ("u at level 4 ÷ dolfinx, FreeFEM: converging variants 0.98–2.4× either reference "
        "(rates 0.77–2.20 vs 2.12); declared expected failures 95× either reference; δ → 0: PASS")


def glance_report(line=LINE):
    return {"verdict": "PASS", "series": [], "references": [{"tool": "dolfinx"}],
            "glance": {"level": 4, "against": "exact", "rows": [], "line": line,
                       "delta": {"status": "PASS", "text": "every δ-sweep tends to δ = 0"}}}


def test_the_line_is_the_reports():
    g = ci.glance(glance_report())
    assert g["line"] == LINE
    assert (g["level"], g["against"], g["delta"]["status"]) == (4, "exact", "PASS")
    assert ci.glance(glance_report("another line"))["line"] == "another line"


def test_without_glance_or_references():
    """Old reports (no glance, or a glance without its line) and scenes without references say
    so in a few words."""
    assert ci.glance({"series": []})["line"] == "no references"
    assert ci.glance({"series": [], "references": [{"tool": "dolfinx"}]})["line"] == \
        "no error ratios (a report from before the glance)"
    old = glance_report()
    del old["glance"]["line"]
    assert ci.glance(old)["line"] == "no error ratios (a report from before the glance)"


def test_index_shows_the_line(tmp_path):
    """index.json and index.html carry the line; a scene without a glance reads "no
    references"."""
    for name, rep in (("a", glance_report()), ("b", {"verdict": "PASS", "series": []})):
        (tmp_path / name / "report").mkdir(parents=True)
        (tmp_path / name / "report" / "report.json").write_text(json.dumps(rep))
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "campaign_index.py"), str(tmp_path)],
                       env=run_env(), capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    rows = {s["name"]: s for s in json.loads((tmp_path / "index.json").read_text())["scenes"]}
    assert rows["a"]["glance"]["line"] == LINE and rows["b"]["glance"]["line"] == "no references"
    page = (tmp_path / "index.html").read_text()
    assert ('title="errors against the exact solution; every δ-sweep tends to δ = 0">'
            + LINE.replace("×", "×") + "</td>") in page


def test_the_index_and_the_report_share_one_page():
    """One skeleton and one stylesheet (sdcompare_lib/page.py) for the index and the report, and
    the index finds them without numpy."""
    from sdcompare_lib import page, render

    assert ci.page is page.page is render.page and ci.scroll_table is render.scroll_table
    style = f"<style>{page.CSS}</style>"
    assert style in ci.render_html([], "FAIL", "now") and style in render.html_page("x", [], "/")
    # the index itself, with every module it imports (page, cases, choices, baseline, sdresults)
    probe = "import sys, campaign_index; sys.exit('numpy' in sys.modules)"
    r = subprocess.run([sys.executable, "-c", probe], env=run_env(ROOT / "tools"),
                       capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, "tools/campaign_index.py imports numpy" + r.stderr


def index_of(tmp_path, verdicts):
    """tools/campaign_index.py on hand-made reports with these {scene: verdict}: (exit status,
    stdout, index.json)."""
    for name, verdict in verdicts.items():
        (tmp_path / name / "report").mkdir(parents=True)
        rep = {"verdict": verdict, "series": [],
               "reasons": [] if verdict == "PASS" else [f"{name}: why {verdict}"]}
        (tmp_path / name / "report" / "report.json").write_text(json.dumps(rep))
        (tmp_path / name / "report" / "index.html").write_text("report")
    r = subprocess.run([sys.executable, str(ROOT / "tools" / "campaign_index.py"), str(tmp_path)],
                       env=run_env(), capture_output=True, text=True, timeout=60)
    return r.returncode, r.stdout, json.loads((tmp_path / "index.json").read_text())


def test_an_inconclusive_scene_is_listed_with_its_reason_and_fails_nothing(tmp_path):
    """INCONCLUSIVE (compare/sdcompare's exit 3: "cannot judge yet") is a verdict of its own: the
    index shows it as the report wrote it, in its own neutral class, the scene's line is followed
    by the report's reason, and the campaign exits 0 (its verdict INCONCLUSIVE)."""
    rc, out, index = index_of(tmp_path, {"a": "PASS", "b": "INCONCLUSIVE"})
    assert rc == 0, out
    assert index["verdict"] == "INCONCLUSIVE"
    assert [(s["name"], s["verdict"]) for s in index["scenes"]] == [("a", "PASS"),
                                                                    ("b", "INCONCLUSIVE")]
    assert f"  INCONCLUSIVE  {tmp_path}/b/report/index.html\n      b: why INCONCLUSIVE\n" in out
    assert f"  PASS  {tmp_path}/a/report/index.html\n  INCONCLUSIVE" in out  # no line under PASS
    page = (tmp_path / "index.html").read_text()
    assert '<td class="INCONCLUSIVE">INCONCLUSIVE</td>' in page
    # its row says what the cell holds: not a problem, what cannot be judged yet
    (row,) = [r for r in index["scenes"] if r["name"] == "b"]
    assert row["reason"] == "cannot judge yet", row
    from sdcompare_lib.page import CSS

    assert ".INCONCLUSIVE{color:#555;" in CSS  # grey: neither PASS's green nor FAIL's red


@pytest.mark.parametrize("verdicts, campaign, rc", [
    ({"a": "PASS", "b": "PASS"}, "PASS", 0),
    ({"a": "INCONCLUSIVE", "b": "FAIL"}, "FAIL", 1),
    ({"a": "PASS", "b": "NEWWORD"}, "FAIL", 1),  # a word the index does not know fails
    ({"a": "PASS", "b": "<b>x</b>"}, "FAIL", 1),  # not a verdict word: the scene FAILs
])
def test_the_campaigns_verdict_and_exit_status(tmp_path, verdicts, campaign, rc):
    got_rc, out, index = index_of(tmp_path, verdicts)
    assert (got_rc, index["verdict"]) == (rc, campaign), out
    shown = {s["name"]: s["verdict"] for s in index["scenes"]}
    want = verdicts["b"] if verdicts["b"].isalpha() else "FAIL"
    assert shown["b"] == want and f"  {want}  " in out
