"""tools/campaign_index.py --baseline: what changed per scene since an earlier campaign folder
(verdicts, scenes new or gone, series' last rates and finest errors beyond the tolerances of
sdcompare_lib/baseline.py, which sdcompare's baseline flags use too), on small hand-made campaign folders; and the GitHub nightly that
hands it the last successful night (.github/workflows/nightly.yml)."""

import json
import pathlib
import subprocess
import sys

import pytest
import yaml  # python3-yaml, installed by ci/setup

import ci_script
from conftest import run_env
from sdcompare_lib.baseline import BASELINE_ERROR_RTOL as ERROR_RTOL
from sdcompare_lib.baseline import BASELINE_RATE_ATOL as RATE_ATOL

ROOT = pathlib.Path(__file__).resolve().parents[2]
INDEX = ROOT / "tools" / "campaign_index.py"
ci = ci_script.load("tools/campaign_index.py")


def series(u="broken", m="M1", q="u_l2", status="converges", errors=(4e-2, 1e-2, 2.5e-3),
           rates=(2.0, 2.0), p_mass="consistent", p_space="continuous"):
    """One report.json series entry, as sdcompare writes it."""
    return {"u_space": u, "multiplier": m, "p_mass": p_mass, "p_space": p_space, "quantity": q,
            "status": status, "levels": list(range(len(errors))), "errors": list(errors),
            "rates": list(rates), "finest_error": errors[-1], "against": "exact"}


def report(verdict="PASS", **edits):
    """A report with three series; edits: {"<variant> <quantity>": {field: value}}."""
    rows = [series(), series(q="p_l2", errors=(0.2, 0.1, 0.05), rates=(1.0, 1.0)),
            series(u="continuous", status="expected failure", errors=(0.3, 0.29, 0.28),
                   rates=(0.05, 0.05))]
    for s in rows:
        s.update(edits.get(f"{ci.variant_key(s)} {s['quantity']}", {}))
    return {"verdict": verdict, "reasons": [] if verdict == "PASS" else ["a problem"],
            "series": rows}


def campaign(root, scenes, created="2026-11-26T02:00:00Z"):
    """A campaign folder: ROOT/<name>/report/report.json per scene (None: no report, only a
    log), and ROOT/index.json with its date."""
    for name, rep in scenes.items():
        if rep is None:
            (root / "logs" / name).mkdir(parents=True)
            continue
        (root / name / "report").mkdir(parents=True)
        (root / name / "report" / "report.json").write_text(json.dumps(rep))
    (root / "index.json").write_text(json.dumps({"verdict": "PASS", "created": created,
                                                 "scenes": []}))
    return root


def index(tmp_path, tonight, before, *extra):
    """Runs the index of tonight's folder against the baseline folder: (exit, stdout, index.json,
    {scene: its row})."""
    now = campaign(tmp_path / "now", tonight)
    base = campaign(tmp_path / "base", before)
    r = subprocess.run([sys.executable, str(INDEX), str(now), "--baseline", str(base), *extra],
                       env=run_env(), capture_output=True, text=True, timeout=60)
    assert r.returncode in (0, 1), r.stderr
    got = json.loads((now / "index.json").read_text())
    return r, got, {s["name"]: s for s in got["scenes"]}


def kinds(row):
    return [c["kind"] for c in row["changes"]]


def test_the_index_and_sdcompare_share_the_baseline_rule():
    """The index's changes and sdcompare's baseline flags come from one numpy-free module."""
    from sdcompare_lib import baseline, verdict

    assert ci.error_change is baseline.error_change is verdict.error_change
    assert ci.rate_change is baseline.rate_change is verdict.rate_change


def test_changes_within_tolerance_are_not_listed(tmp_path):
    """Rates moved by half the tolerance, errors by half theirs: "no change beyond tolerance"."""
    e = 2.5e-3 * (1 + ERROR_RTOL / 2)
    near = report(**{"broken/M1 u_l2": {"rates": [2.0, 2.0 + RATE_ATOL / 2],
                                        "errors": [4e-2, 1e-2, e]}})
    r, got, rows = index(tmp_path, {"a": near}, {"a": report()})
    assert rows["a"]["changes"] == [] and rows["a"]["changes_line"] == ci.NO_CHANGE
    assert got["baseline"]["changed"] == [] and got["baseline"]["gone"] == []
    assert f"<td class=\"t\">{ci.NO_CHANGE}</td>" in (tmp_path / "now" / "index.html").read_text()
    assert "baseline: " in r.stdout and "0 scene(s) changed beyond tolerance" in r.stdout


def test_forged_rate_beyond_tolerance_is_listed(tmp_path):
    """The same baseline with one last rate moved by twice the tolerance: the sentence "no change"
    is gone and the series is named, with both rates."""
    forged = report(**{"broken/M1 u_l2": {"rates": [2.0, 2.0 + 2 * RATE_ATOL]}})
    r, got, rows = index(tmp_path, {"a": report()}, {"a": forged})
    (c,) = rows["a"]["changes"]
    assert c["kind"] == "rate" and c["series"] == "broken/M1 u_l2" and c["level"] == 2
    assert c["text"] == "broken/M1 u_l2: last rate (to level 2) 2.0002 → 2.0000 (-0.0002)"
    page = (tmp_path / "now" / "index.html").read_text()
    assert ci.NO_CHANGE not in page and c["text"] in page
    assert got["baseline"]["changed"] == ["a"] and "1 scene(s) changed" in r.stdout


def test_error_beyond_tolerance_is_listed(tmp_path):
    e = 0.05 * (1 + 3 * ERROR_RTOL)
    r, got, rows = index(tmp_path, {"a": report(**{"broken/M1 p_l2": {"errors": [0.2, 0.1, e]}})},
                         {"a": report()})
    (c,) = rows["a"]["changes"]
    assert (c["kind"], c["series"], c["level"], c["old"], c["new"]) == \
        ("error", "broken/M1 p_l2", 2, 0.05, e)
    assert c["rel_change"] == pytest.approx(3 * ERROR_RTOL, rel=1e-3)


def test_changed_verdict_and_status_are_listed(tmp_path):
    failing = report("FAIL", **{"broken/M1 p_l2": {"status": "does not converge"}})
    r, got, rows = index(tmp_path, {"a": failing}, {"a": report()})
    assert r.returncode == 1
    texts = [c["text"] for c in rows["a"]["changes"]]
    assert texts[:2] == ["verdict PASS → FAIL", "broken/M1 p_l2: converges → does not converge"]


def test_scene_new_gone_and_without_report(tmp_path):
    """A scene the baseline lacks is new; one only the baseline has is gone (the header's line);
    a scene whose report is missing on one side is compared by verdict only."""
    r, got, rows = index(tmp_path, {"a": report(), "new": report(), "broke": None},
                         {"a": report(), "old": report(), "broke": report()})
    assert rows["new"]["changes_line"] == "new scene (not in the baseline)"
    assert kinds(rows["a"]) == []
    assert rows["broke"]["changes_line"] == ("verdict PASS → FAIL; no report in tonight's "
                                             "folder: series not compared")
    assert got["baseline"]["gone"] == ["old"]
    assert "1 gone (old)" in r.stdout


def test_series_new_gone_and_other_levels(tmp_path):
    """Series are matched by variant and quantity; a night at other levels says so once and
    compares the finest level both have."""
    before = report()
    before["series"] = before["series"][1:] + [series(m="M0")]
    tonight = report()
    for s in tonight["series"]:
        s["levels"].append(3)
        s["errors"].append(s["errors"][-1] / 4)
        s["rates"].append(2.0)
    r, got, rows = index(tmp_path, {"a": tonight}, {"a": before})
    assert rows["a"]["changes_line"] == ("1 series new (broken/M1 u_l2); 1 series gone "
                                         "(broken/M0 u_l2); finest level 2 → 3 (all 2 series)")


def test_header_names_the_baseline(tmp_path):
    r, got, _ = index(tmp_path, {"a": report()}, {"a": report()}, "--baseline-label", "run 7")
    head = got["baseline"]
    assert (head["label"], head["created"]) == ("run 7", "2026-11-26T02:00:00Z")
    assert (head["rate_atol"], head["error_rtol"]) == (RATE_ATOL, ERROR_RTOL)
    line = "baseline: run 7 (its index of 2026-11-26T02:00:00Z, verdict PASS)"
    assert line in (tmp_path / "now" / "index.html").read_text() and line in r.stdout


def test_missing_baseline_folder_is_one_line_exit_2(tmp_path):
    now = campaign(tmp_path / "now", {"a": report()})
    r = subprocess.run([sys.executable, str(INDEX), str(now), "--baseline",
                        str(tmp_path / "nowhere")], env=run_env(), capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 2 and r.stdout == ""
    assert r.stderr == f"campaign_index: --baseline {tmp_path / 'nowhere'}: no such folder\n"


def test_no_baseline_says_why(tmp_path):
    now = campaign(tmp_path / "now", {"a": report()})
    r = subprocess.run([sys.executable, str(INDEX), str(now), "--no-baseline", "first night"],
                       env=run_env(), capture_output=True, text=True, timeout=60)
    assert r.returncode == 0, r.stderr
    assert "no baseline: first night" in r.stdout.splitlines()
    assert json.loads((now / "index.json").read_text())["baseline"] == {"none": "first night"}
    page = (now / "index.html").read_text()
    assert "no baseline: first night" in page and "changed since baseline" not in page


def nightly_jobs():
    return yaml.safe_load((ROOT / ".github" / "workflows" / "nightly.yml").read_text())["jobs"]


def test_nightly_finds_the_last_successful_run():
    """The baseline job lists the last successful nightly of the default branch with the run's
    token (actions: read), and a first night is an output, not a failure."""
    wf = yaml.safe_load((ROOT / ".github" / "workflows" / "nightly.yml").read_text())
    assert wf["permissions"]["actions"] == "read"
    (step,) = nightly_jobs()["baseline"]["steps"]
    assert step["env"]["GH_TOKEN"] == "${{ github.token }}"
    run = step["run"]
    for words in ("gh run list", "--workflow nightly.yml", '--branch "$branch"',
                  "--status success", "--limit 1", "first night"):
        assert words in run, words
    assert "exit 1" not in run


def test_nightly_index_and_scenes_get_the_baseline():
    """The index job downloads the baseline run's nightly-* artifacts and passes --baseline (or
    --no-baseline with the reason); each scene job hands its scene's folder to ci/nightly."""
    jobs = nightly_jobs()
    steps = jobs["index"]["steps"]
    downloads = [s for s in steps if s.get("uses", "").startswith("actions/download-artifact")]
    base = [s for s in downloads if s.get("with", {}).get("run-id")]
    assert base and base[0]["with"]["pattern"] == "nightly-*"
    assert base[0]["with"]["run-id"] == "${{ needs.baseline.outputs.run_id }}"
    assert base[0]["with"]["path"] == "results/baseline" and base[0]["continue-on-error"]
    run = next(s["run"] for s in steps if s.get("name") == "index")
    assert "--baseline results/baseline" in run and '--no-baseline "${NONE:-first night}"' in run
    assert "baseline" in jobs["index"]["needs"] and jobs["index"]["if"] == "always()"
    assert "needs.scenes.result == 'success'" in jobs["scene"]["if"]  # baseline job or not
    scene = jobs["scene"]["steps"]
    (dl,) = [s for s in scene if s.get("uses", "").startswith("actions/download-artifact")]
    assert dl["with"]["name"] == "nightly-${{ matrix.scene }}" and dl["continue-on-error"]
    assert any("ci/nightly" in s.get("run", "") and "--baseline results/baseline" in s["run"]
               for s in scene)
