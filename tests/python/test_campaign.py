"""tools/cases lists the campaign, and its commands rerun single cases reproducibly (both p masses).

A rerun command of tools/cases (the case's level, u space and multiplier with its δ sweep, warm-started
δ after δ as in the full run) gives bitwise the same u, p, λ and exactly the same KKT residuals,
active set, unknowns and LCP iterations as the same case inside a full run.
"""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest
from scene_text import add_key, set_key

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXE = pathlib.Path(os.environ.get("SDCRACK_BIN", ROOT / "target" / "release" / "sdcrack"))
h5py = pytest.importorskip("h5py")
# tools/cases is a checkout tool (it writes δ with the compare tool's fmt_delta); ci/test-pip's copy
# of the tree has no compare/sdcompare_lib, and ci/test runs these tests on the checkout
pytestmark = pytest.mark.skipif(not (ROOT / "compare" / "sdcompare_lib").is_dir(),
                                reason="no compare/sdcompare_lib (ci/test-pip's copy of the tree)")


def cases_with_targets(*args, cwd=ROOT):
    """(row, target): the row's seven columns (scene, level, u space, multiplier, p mass, δ sweep,
    command), and the campaign job folder of its trailing `# target: ...` comment (None without
    one)."""
    out = subprocess.run([str(ROOT / "tools" / "cases"), *map(str, args)], cwd=cwd, check=True,
                         capture_output=True, text=True).stdout
    rows = []
    for line in out.splitlines():
        line, sep, target = line.partition(" # target: ")
        rows.append((line.split(" ", 6), target if sep else None))
    return rows


def cases(*scenes, cwd=ROOT):
    return [row for row, _ in cases_with_targets(*scenes, cwd=cwd)]


def command_words(cmd):
    """The words of a rerun command after its prefix `env OMP_NUM_THREADS=1 ...` (the campaign's
    BLAS/OpenMP threads, sdresults.PINNED_THREADS), which it must start with."""
    from sdshared.sdresults import pinned_env_args

    words, pin = cmd.split(), pinned_env_args()
    assert words[:len(pin)] == pin, cmd
    return words[len(pin):]


def out_of(cmd):
    args = cmd.split()
    return args[args.index("--out") + 1]


def test_case_list_has_one_line_per_rerunnable_unit(tmp_path):
    """One line per level × u space × multiplier × p mass, not per δ: each command reruns the
    whole δ sweep, which the DELTAS column lists (as the reports write δ)."""
    rows = cases(ROOT / "scenes" / "closed-exact.toml", cwd=tmp_path)
    assert len(rows) == 5 * 2 * 3 * 2
    assert {r[0] for r in rows} == {"closed-exact"}
    assert {r[5] for r in rows} == {"1,1e-2,1e-4,1e-6,0"}
    assert all("--delta" not in r[6] for r in rows)
    outs = [out_of(r[6]) for r in rows]
    assert len(set(outs)) == len(outs), "one folder per unit"
    # absolute binary and scene: the same command from any working directory, writing into
    # sdcrack-rerun/ under it (relative), or into --rerun-dir (absolute)
    cmd = command_words(rows[0][6])
    assert cmd[0] == str(ROOT / "target" / "release" / "sdcrack")
    assert cmd[2] == str(ROOT / "scenes" / "closed-exact.toml")
    # the scene has references: the unit alone, not its level's references
    assert all(command_words(r[6])[3] == "--solver-only" for r in rows)
    assert outs[0] == "sdcrack-rerun/closed-exact-l0-continuous-M0"
    rows = cases("--rerun-dir", "mine", ROOT / "scenes" / "closed-exact.toml", cwd=tmp_path)
    assert out_of(rows[0][6]) == str(tmp_path / "mine" / "closed-exact-l0-continuous-M0")


def test_case_list_names_the_campaign_jobs(tmp_path):
    """Each line of a scene file ends in a shell comment naming the campaign's solver shard that
    computes the unit (tools/workflow/Snakefile), under --out (default results/campaign of the
    checkout); `cut -d' ' -f7- | sh` runs the command alone."""
    rows = cases_with_targets(ROOT / "scenes" / "mixed.toml")
    assert len(rows) == 5 * 2 * 3 * 2
    for (scene, level, u, m, pm, _deltas, cmd), target in rows:
        assert ("--p-mass lumped" in cmd) == (pm == "lumped")
        assert target == str(ROOT / "results" / "campaign" / "shards" / scene / "solver"
                             / f"l{level}-{u}-{m}-{pm}")
    rows = cases_with_targets("--out", "camp", ROOT / "scenes" / "closed-exact.toml", cwd=tmp_path)
    assert rows[0][1] == str(tmp_path / "camp" / "shards" / "closed-exact" / "solver"
                             / "l0-continuous-M0-consistent")
    # the comment is a shell comment: the command part of the line runs without it
    out = subprocess.run(["bash", "-c", "tools/cases scenes/closed-exact.toml | head -1 | cut -d' ' -f7- "
                          "| sed 's/^[^ ]*/echo/' | sh"], cwd=ROOT, check=True,
                         capture_output=True, text=True).stdout
    assert out.strip().endswith("--out sdcrack-rerun/closed-exact-l0-continuous-M0")


def test_case_list_of_a_results_folder(tmp_path):
    """A results folder reruns its own scene copy and plan (with the binary that wrote it, as its
    report: `sdcrack` from PATH when summary.json does not record it); a folder that no
    campaign wrote has no target comment (no job computes it), one inside a campaign folder
    (OUT/shards/ exists) names that campaign's job, not the checkout's."""
    folder = tmp_path / "out" / "closed-exact"
    folder.mkdir(parents=True)
    # a run of the scene at δ = 0 only
    (folder / "scene.toml").write_text(
        set_key((ROOT / "scenes" / "closed-exact.toml").read_text(), "deltas", "[0.0]"))
    (folder / "summary.json").write_text(json.dumps({"plan": {
        "levels": [2], "u_spaces": ["broken"], "multipliers": ["M0", "M1"], "deltas": [0.0]}}))
    rows = cases_with_targets("out/closed-exact", cwd=tmp_path)
    assert [r[:6] for r, _ in rows] == [["closed-exact", "2", "broken", m, "consistent", "0"]
                                        for m in ("M0", "M1")]
    assert [t for _, t in rows] == [None, None]
    cmd = command_words(rows[0][0][6])
    assert cmd[:3] == ["sdcrack", "run", str(folder / "scene.toml")]  # no provenance recorded
    assert "--delta" not in cmd  # the scene's only δ: the run's δ sweep
    assert out_of(rows[0][0][6]) == "sdcrack-rerun/closed-exact-l2-broken-M0"
    (tmp_path / "out" / "shards").mkdir()
    rows = cases_with_targets(folder, cwd=ROOT)
    assert rows[1][1] == str(tmp_path / "out" / "shards" / "closed-exact" / "solver"
                             / "l2-broken-M1-consistent")


def test_case_list_of_a_results_folder_is_the_reports_rerun_list(tmp_path):
    """For a results folder, tools/cases prints exactly the commands the folder's report lists
    (compare's render.rerun_command), a run restricted to one δ and a lumped p mass included, with
    the folder's recorded binary (a campaign's pinned copy, not this checkout's), `sdcrack` from
    PATH when none is recorded, and --rerun-dir (tests/python/test_reruns.py compares with a real
    report's table)."""
    import tomllib

    from sdcompare_lib import render

    folder = tmp_path / "runs" / "closed-exact"
    folder.mkdir(parents=True)
    text = set_key((ROOT / "scenes" / "closed-exact.toml").read_text(), "p_mass",
                   '["consistent", "lumped"]')
    (folder / "scene.toml").write_text(text)
    pinned = str(tmp_path / "campaign" / "inputs" / "sdcrack")
    for deltas, prov in (([1.0, 0.01, 0.0001, 1e-06, 0.0], {"executable": pinned}),
                         ([0.01], {"executable": pinned}), ([0.01], None)):
        plan = {"levels": [1, 2], "u_spaces": ["broken"], "multipliers": ["M1"],
                "p_masses": ["consistent", "lumped"], "deltas": deltas}
        summary = {"scene": "closed-exact", "plan": plan, "provenance": prov}
        (folder / "summary.json").write_text(json.dumps(summary))
        scene = tomllib.loads(text)
        units = [{"level": lv, "u_space": "broken", "multiplier": "M1", "p_mass": pm,
                  "delta": deltas[0]} for lv in (1, 2) for pm in ("consistent", "lumped")]
        want = [render.rerun_command(str(folder), summary, scene, k) for k in units]
        got = [r[6] for r in cases(folder, cwd=tmp_path)]
        assert got == want
        assert {command_words(c)[0] for c in got} == {pinned if prov else "sdcrack"}
        mine = tmp_path / "mine"
        want = [render.rerun_command(str(folder), summary, scene, k, rerun_dir=str(mine))
                for k in units]
        assert [r[6] for r in cases("--rerun-dir", mine, folder, cwd=ROOT)] == want


def test_rerun_reproduces_the_row(tmp_path):
    if not EXE.is_file():
        pytest.skip("sdcrack binary not built")
    text = (ROOT / "scenes" / "mixed.toml").read_text()
    for key, value in (("p_mass", '["consistent"]'), ("levels", "[1, 2]"), ("references", "[]")):
        text = set_key(text, key, value)
    scene = tmp_path / "mixed.toml"
    scene.write_text(text)
    subprocess.run([str(EXE), "run", str(scene), "--out", str(tmp_path / "full"), "--quiet"],
                   check=True, capture_output=True)
    full = json.loads((tmp_path / "full" / "mixed" / "summary.json").read_text())
    key = lambda c: (c["level"], c["u_space"], c["multiplier"], c["delta"])  # noqa: E731
    by_key = {key(c): c for c in full["cases"]}
    picked = {("2", "broken", "M1star"), ("1", "continuous", "M0")}
    rows = [r for r in cases(scene, cwd=tmp_path) if tuple(r[1:4]) in picked]
    assert len(rows) == 2
    for r in rows:
        cmd = command_words(r[6]) + ["--quiet"]
        assert cmd[0] == str(ROOT / "target" / "release" / "sdcrack") and cmd[2] == str(scene)
        cmd[0] = str(EXE)  # SDCRACK_BIN may name another build
        elsewhere = tmp_path / "elsewhere"  # any directory: the rerun lands under it
        elsewhere.mkdir(exist_ok=True)
        subprocess.run(cmd, cwd=elsewhere, check=True, capture_output=True)
        folder = elsewhere / out_of(r[6]) / "mixed"
        one = json.loads((folder / "summary.json").read_text())["cases"]
        assert len(one) == 6 == len(r[5].split(",")), "the delta sweep of the unit"
        for c in one:
            f = by_key[key(c)]
            for k in ("unknowns", "multipliers", "kkt", "active_multipliers", "converged", "h",
                      "regularized_pivots", "iterations"):
                assert c[k] == f[k], (r[:5], c["delta"], k)
            with h5py.File(folder / "fields.h5") as a, h5py.File(tmp_path / "full" / "mixed" / "fields.h5") as b:
                g = c["fields_grid"]
                for name in ("u", "p", "crack/lambda"):
                    assert np.array_equal(a[f"cases/{g}/{name}"][()], b[f"cases/{g}/{name}"][()]), (r[:5], name)


def test_case_list_of_both_p_masses(tmp_path):
    """A scene with p_mass = ["consistent", "lumped"]: one row per p mass; the lumped rows'
    commands add `--p-mass lumped` and write to their own `-lumped` folder, the consistent ones
    are those of a scene without p masses. A results folder's plan decides."""
    text = (ROOT / "scenes" / "closed-exact.toml").read_text()
    scene = tmp_path / "closed-exact.toml"
    scene.write_text(set_key(text, "p_mass", '["consistent", "lumped"]'))
    plain_scene = tmp_path / "consistent" / "closed-exact.toml"
    plain_scene.parent.mkdir()
    plain_scene.write_text(set_key(text, "p_mass", '["consistent"]'))
    plain = cases(plain_scene, cwd=tmp_path)
    rows = cases(scene, cwd=tmp_path)
    assert len(rows) == 2 * len(plain) == 2 * 5 * 2 * 3
    lumped = [r for r in rows if r[4] == "lumped"]
    consistent = [r for r in rows if r[4] == "consistent"]
    assert [r[:4] + r[5:6] for r in lumped] == [r[:4] + r[5:6] for r in consistent] \
        == [r[:4] + r[5:6] for r in plain]
    assert [r[6].replace(str(scene), "S") for r in consistent] == \
        [r[6].replace(str(plain_scene), "S") for r in plain]
    for r in lumped:
        cmd = r[6].split()
        assert cmd[cmd.index("--p-mass") + 1] == "lumped" and cmd.index("--p-mass") < cmd.index("--out")
        assert cmd[-1] == f"sdcrack-rerun/closed-exact-l{r[1]}-{r[2]}-{r[3]}-lumped"
    assert all("--p-mass" not in r[6] for r in consistent)
    outs = [out_of(r[6]) for r in rows]
    assert len(set(outs)) == len(outs), "one folder per unit"
    # a results folder of a --p-mass lumped run: its plan's p masses
    folder = tmp_path / "out" / "closed-exact"
    folder.mkdir(parents=True)
    (folder / "scene.toml").write_text(set_key(scene.read_text(), "deltas", "[0.0]"))
    (folder / "summary.json").write_text(json.dumps({"plan": {
        "levels": [2], "u_spaces": ["broken"], "multipliers": ["M1"], "p_masses": ["lumped"],
        "deltas": [0.0]}}))
    rows = cases("out/closed-exact", cwd=tmp_path)
    assert len(rows) == 1 and rows[0][:6] == ["closed-exact", "2", "broken", "M1", "lumped", "0"]
    assert "--multiplier M1 --p-mass lumped --out" in rows[0][6]



BOTH_P_SPACES = '["continuous", "broken-tangential"]'


def served_units(levels, multipliers=("M0", "M1", "M1star"), u_spaces=("continuous", "broken"),
                 p_masses=("consistent", "lumped"), p_spaces=("continuous", "broken-tangential")):
    """(level, u, m, p mass, p space) of the units a plan serves, counted here: sdcrack runs the
    broken-tangential p with the broken u only."""
    return [(lv, u, m, pm, ps) for lv in levels for u in u_spaces for m in multipliers
            for pm in p_masses for ps in p_spaces
            if not (u == "continuous" and ps == "broken-tangential")]


def test_case_list_of_both_p_spaces(tmp_path):
    """A scene with p_spaces = ["continuous", "broken-tangential"] and both u spaces: one row per
    served unit (none for the continuous u with the broken-tangential p). The broken-tangential
    rows' fifth column is the p mass with `-ptangential`, their commands add `--p-space
    broken-tangential` and write to their own `-ptangential` folder, and their targets are the
    workflow's -ptangential shards; the continuous-p rows are those of the scene without p
    spaces."""
    text = (ROOT / "scenes" / "closed-exact.toml").read_text()
    scene = tmp_path / "closed-exact.toml"
    scene.write_text(add_key(text, "p_mass", "p_spaces", BOTH_P_SPACES))
    plain_scene = tmp_path / "plain" / "closed-exact.toml"
    plain_scene.parent.mkdir()
    plain_scene.write_text(text)
    plain = cases(plain_scene, cwd=tmp_path)
    rows_targets = cases_with_targets("--out", "camp", scene, cwd=tmp_path)
    rows = [r for r, _ in rows_targets]
    want = served_units(range(5))
    assert len(rows) == len(want) == 5 * (3 * 2 + 3 * 2 * 2) == 90
    assert not [r for r in rows if r[2] == "continuous" and r[4].endswith("-ptangential")]
    tangential = [r for r in rows if r[4].endswith("-ptangential")]
    continuous = [r for r in rows if not r[4].endswith("-ptangential")]
    assert len(tangential) == 5 * 3 * 2 and {r[2] for r in tangential} == {"broken"}
    assert sorted((int(r[1]), r[2], r[3], r[4].removesuffix("-ptangential"),
                   "broken-tangential" if r[4].endswith("-ptangential") else "continuous")
                  for r in rows) == sorted(want)
    assert [r[:6] for r in continuous] == [r[:6] for r in plain]
    assert [r[6].replace(str(scene), "S") for r in continuous] == \
        [r[6].replace(str(plain_scene), "S") for r in plain]
    for r in tangential:
        cmd = r[6].split()
        assert cmd[cmd.index("--p-space") + 1] == "broken-tangential"
        assert cmd.index("--p-space") < cmd.index("--out")
        assert ("--p-mass lumped" in r[6]) == (r[4] == "lumped-ptangential")
        lumped = "-lumped" if r[4] == "lumped-ptangential" else ""
        assert cmd[-1] == f"sdcrack-rerun/closed-exact-l{r[1]}-{r[2]}-{r[3]}{lumped}-ptangential"
    assert all("--p-space" not in r[6] for r in continuous)
    outs = [out_of(r[6]) for r in rows]
    assert len(set(outs)) == len(outs), "one folder per unit"
    # the targets: the campaign's solver shards, l<L>-<u>-<m>-<column 5>
    for r, target in rows_targets:
        assert target == str(tmp_path / "camp" / "shards" / "closed-exact" / "solver"
                             / f"l{r[1]}-{r[2]}-{r[3]}-{r[4]}")
    if EXE.is_file():  # and they are exactly the workflow's solver jobs of the scene's plan
        import ci_script

        prepare = ci_script.load("tools/workflow/prepare.py")
        plan = json.loads(subprocess.run([str(EXE), "check", str(scene), "--json"], check=True,
                                         capture_output=True, text=True).stdout)
        solver = prepare.jobs_of(dict(plan, exact=True))[0]
        assert [str(tmp_path / "camp" / s) for s in solver] == [t for _, t in rows_targets]


def test_case_list_of_a_p_spaces_results_folder_is_the_reports_rerun_list(tmp_path):
    """For a results folder with both p spaces in its plan, tools/cases prints exactly the commands
    the folder's report lists (render.rerun_command with the case's p_space), for the served
    units only; a folder of a `--p-space broken-tangential` run lists its own units."""
    import tomllib

    from sdcompare_lib import render

    folder = tmp_path / "runs" / "closed-exact"
    folder.mkdir(parents=True)
    text = add_key((ROOT / "scenes" / "closed-exact.toml").read_text(), "p_mass", "p_spaces",
                   BOTH_P_SPACES)
    (folder / "scene.toml").write_text(text)
    exe = str(ROOT / "target" / "release" / "sdcrack")
    deltas = [1.0, 0.01, 0.0001, 1e-06, 0.0]
    plan = {"levels": [1, 2], "u_spaces": ["continuous", "broken"], "multipliers": ["M1"],
            "p_masses": ["consistent", "lumped"], "p_spaces": ["continuous", "broken-tangential"],
            "deltas": deltas}
    summary = {"scene": "closed-exact", "plan": plan, "provenance": {"executable": exe}}
    (folder / "summary.json").write_text(json.dumps(summary))
    scene = tomllib.loads(text)
    units = served_units((1, 2), multipliers=("M1",))
    want = [render.rerun_command(str(folder), summary, scene,
                                 {"level": lv, "u_space": u, "multiplier": m, "p_mass": pm,
                                  "p_space": ps, "delta": deltas[0]})
            for lv, u, m, pm, ps in units]
    rows = cases(folder, cwd=tmp_path)
    assert [r[6] for r in rows] == want
    assert sum("--p-space broken-tangential" in c for c in want) == 2 * 2
    assert [r[:5] for r in rows] == [
        ["closed-exact", str(lv), u, m, pm + ("-ptangential" if ps == "broken-tangential" else "")]
        for lv, u, m, pm, ps in units]
    # a run restricted to the broken-tangential p (and one δ)
    (folder / "summary.json").write_text(json.dumps({"plan": {
        "levels": [2], "u_spaces": ["broken"], "multipliers": ["M1"], "p_masses": ["consistent"],
        "p_spaces": ["broken-tangential"], "deltas": [0.0]}}))
    rows = cases(folder, cwd=tmp_path)
    assert len(rows) == 1 and rows[0][:6] == ["closed-exact", "2", "broken", "M1",
                                              "consistent-ptangential", "0"]
    assert "--multiplier M1 --p-space broken-tangential --delta 0 --out" in rows[0][6]
    assert out_of(rows[0][6]).endswith("/closed-exact-l2-broken-M1-ptangential-d0")


def test_an_elastic_scene_has_no_unit(tmp_path):
    """An elastic scene has no solver case until issue 46: tools/cases lists nothing for its scene
    file or its results folder (it stopped with a KeyError on u_spaces), the other scenes as
    without it, and the default list (every scene file) runs."""
    closed = ROOT / "scenes" / "closed-exact.toml"
    assert cases(ROOT / "scenes" / "elastic-patch.toml", closed, cwd=tmp_path) == \
        cases(closed, cwd=tmp_path)
    folder = tmp_path / "out" / "elastic-patch"
    folder.mkdir(parents=True)
    (folder / "scene.toml").write_text((ROOT / "scenes" / "elastic-patch.toml").read_text())
    (folder / "summary.json").write_text(json.dumps({"problem": "elasticity", "plan": {
        "levels": [0], "u_spaces": [], "multipliers": [], "p_masses": [], "p_spaces": [],
        "deltas": []}, "cases": []}))
    assert cases(folder, cwd=tmp_path) == []
    rows = cases(cwd=tmp_path)
    assert rows and not [r for r in rows if r[0].startswith("elastic-")]
    assert {"closed-exact", "mixed"} <= {r[0] for r in rows}


@pytest.mark.parametrize("arg, says", [
    ("nope.toml", "tools/cases: nope.toml: no such file or directory: give a scene file or a results "
                  "folder OUT/<scene>/"),
    ("folder", "tools/cases: folder: a results folder without scene.toml: give a scene file or a "
               "results folder OUT/<scene>/"),
    ("bad.toml", "tools/cases: bad.toml: not a scene file: "),
])
def test_a_bad_argument_is_one_line_and_exit_2(tmp_path, arg, says):
    """tools/cases exited 1 with Python's errno text; now one line and exit 2, as every
    other tool of the repository on bad input."""
    (tmp_path / "folder").mkdir()
    (tmp_path / "bad.toml").write_text("name = \n")
    p = subprocess.run([str(ROOT / "tools" / "cases"), arg], cwd=tmp_path, capture_output=True,
                       text=True)
    assert p.returncode == 2 and p.stdout == "", p
    assert p.stderr.startswith(says) and p.stderr.count("\n") == 1, p.stderr
