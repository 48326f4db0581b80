"""Errors precomputed per shard (sdcompare --precompute, the campaign's check jobs) and read back by
the report (--precomputed): the report is the same with and without them, a file of another
scene is not used, and a damaged value under a right key makes the verdict FAIL (it is checked
against the solver's reported errors like a recomputed one), never PASS."""
import json
import os
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
SDCOMPARE = os.path.join(ROOT, "compare", "sdcompare")

from scene_text import set_key
from conftest import sdcrack_bin


def sdcompare(*args):
    env = dict(os.environ, MPLBACKEND="Agg")
    return subprocess.run([sys.executable, SDCOMPARE, *map(str, args)], capture_output=True,
                          text=True, env=env, timeout=600)


def solve(tmp, name, text):
    scene = tmp / f"{name}.toml"
    scene.write_text(text)
    r = subprocess.run([sdcrack_bin(), "run", str(scene), "--out", str(tmp / "out"), "--quiet"],
                       capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr
    return tmp / "out" / name


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """open-exact and closed-exact, levels 0-1, two δ, no references, every field (renamed:
    scenes/expectations.toml holds the repository scenes to their own levels)."""
    if not os.access(sdcrack_bin(), os.X_OK):
        pytest.skip("no sdcrack binary (cargo build --release, or SDCRACK_BIN)")
    tmp = tmp_path_factory.mktemp("precomputed")
    out = {}
    for name in ("open-exact", "closed-exact"):
        with open(os.path.join(ROOT, "scenes", f"{name}.toml"), encoding="utf-8") as fh:
            text = fh.read()
        for key, value in (("name", f'"{name}-pre"'), ("levels", "[0, 1]"),
                           ("deltas", "[1e-2, 0.0]"), ("references", "[]")):
            text = set_key(text, key, value)
        out[name] = solve(tmp, f"{name}-pre", text)
    return tmp, out


def report_json(folder):
    with open(folder / "report" / "report.json", encoding="utf-8") as fh:
        return json.load(fh)


def independent_check(report):
    """The report's "independent errors" check (two levels are too few for the series checks, so
    the verdict itself is FAIL here whatever the errors)."""
    return next(c for c in report["checks"] if c["check"] == "independent errors")


def test_precomputed_errors_give_the_same_report(runs):
    tmp, out = runs
    folder = out["open-exact"]
    r = sdcompare(folder, "--replace", "--quiet")
    assert r.returncode in (0, 1, 3), r.stdout + r.stderr
    plain = report_json(folder)
    assert independent_check(plain)["status"] == "ok", independent_check(plain)
    assert plain["independent_precomputed"] == {"used": 0, "computed": len(
        plain["independent_errors"])}
    store = tmp / "open.json"
    r = sdcompare("--precompute", folder, "--out", store)
    assert r.returncode == 0, r.stderr
    assert f"1 shard(s): {len(plain['independent_errors'])} case(s) precomputed" in r.stdout
    r = sdcompare(folder, "--replace", "--quiet", "--precomputed", store)
    assert r.returncode in (0, 1, 3), r.stdout + r.stderr
    again = report_json(folder)
    assert again["independent_precomputed"] == {"used": len(plain["independent_errors"]),
                                                "computed": 0}
    assert again["independent_errors"] == plain["independent_errors"]
    assert again["checks"] == plain["checks"] and again["verdict"] == plain["verdict"]


def test_another_scenes_file_is_not_used(runs):
    tmp, out = runs
    store = tmp / "closed.json"
    assert sdcompare("--precompute", out["closed-exact"], "--out", store).returncode == 0
    r = sdcompare(out["open-exact"], "--replace", "--quiet", "--precomputed", store)
    assert r.returncode in (0, 1, 3), r.stdout + r.stderr
    report = report_json(out["open-exact"])
    assert report["independent_precomputed"]["used"] == 0
    assert independent_check(report)["status"] == "ok"


def test_a_damaged_value_fails_the_verdict(runs):
    tmp, out = runs
    store = tmp / "damaged.json"
    assert sdcompare("--precompute", out["open-exact"], "--out", store).returncode == 0
    data = json.loads(store.read_text())
    key = sorted(data["entries"])[0]
    data["entries"][key]["u_l2"] *= 1.001
    store.write_text(json.dumps(data))
    r = sdcompare(out["open-exact"], "--replace", "--quiet", "--precomputed", store)
    assert r.returncode == 1, r.stdout + r.stderr
    check = independent_check(report_json(out["open-exact"]))
    assert check["status"] == "FAIL" and len(check["problems"]) == 1, check
    assert "differ from the independent computation by 1.0" in check["problems"][0]


def test_bad_files_and_arguments_are_one_line_errors(runs, tmp_path):
    _, out = runs
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "something else"}')
    for args in ([out["open-exact"], "--precomputed", bad],
                 [out["open-exact"], "--precomputed", tmp_path / "missing.json"],
                 ["--precompute", out["open-exact"]],
                 ["--precompute", tmp_path / "nothing", "--out", tmp_path / "x.json"],
                 ["--precompute", out["open-exact"], "--out", tmp_path / "no" / "x.json"],
                 []):
        r = sdcompare(*args)
        assert r.returncode == 2, (args, r.stdout, r.stderr)
        assert len(r.stderr.strip().splitlines()) == 1 and "sdcompare: error:" in r.stderr


def test_an_elastic_shard_is_refused_in_one_line(tmp_path):
    """--precompute reads the scalar problem's shards: an elastic scene's shard (its scene copy
    says `kind = "elasticity"`; the elastic report recomputes its own errors, and the campaign runs
    no check job for it) is one line, exit 2, nothing written, not a traceback."""
    shard = tmp_path / "elastic-patch"
    shard.mkdir()
    with open(os.path.join(ROOT, "scenes", "elastic-patch.toml"), encoding="utf-8") as fh:
        (shard / "scene.toml").write_text(fh.read())
    r = sdcompare("--precompute", shard, "--out", tmp_path / "x.json")
    assert r.returncode == 2, r.stdout + r.stderr
    assert r.stderr.count("\n") == 1 and "a shard of an elastic scene" in r.stderr, r.stderr
    assert not (tmp_path / "x.json").exists()


def test_several_shards_into_one_file(runs):
    """One check job covers several shards (the campaign: a level's solver shards of one u space):
    the file holds the errors of both folders, and each report uses its own."""
    tmp, out = runs
    store = tmp / "both.json"
    r = sdcompare("--precompute", out["open-exact"], out["closed-exact"], "--out", store)
    assert r.returncode == 0, r.stderr
    assert "2 shard(s)" in r.stdout
    for name in ("open-exact", "closed-exact"):
        r = sdcompare(out[name], "--replace", "--quiet", "--precomputed", store)
        assert r.returncode in (0, 1, 3), r.stdout + r.stderr
        report = report_json(out[name])
        assert report["independent_precomputed"] == {
            "used": len(report["independent_errors"]), "computed": 0}
