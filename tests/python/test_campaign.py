"""ci/cases lists the campaign, and its commands rerun single cases reproducibly (both p masses).

A rerun command of ci/cases (the case's level, u space and multiplier with its δ sweep, warm-started
δ after δ as in the full run) gives bitwise the same u, p, λ and exactly the same KKT residuals,
active set, unknowns and LCP iterations as the same case inside a full run.
"""

import json
import os
import pathlib
import subprocess

import numpy as np
import pytest
from scene_text import set_key

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXE = pathlib.Path(os.environ.get("SDCRACK_BIN", ROOT / "target" / "release" / "sdcrack"))
h5py = pytest.importorskip("h5py")


def cases_with_targets(*args, cwd=ROOT):
    """(row, target): the row's six columns, and the campaign job folder of its trailing
    `# target: ...` comment."""
    out = subprocess.run([str(ROOT / "ci" / "cases"), *map(str, args)], cwd=cwd, check=True,
                         capture_output=True, text=True).stdout
    rows = []
    for line in out.splitlines():
        line, sep, target = line.partition(" # target: ")
        assert sep, f"no target comment in {line!r}"
        rows.append((line.split(" ", 5), target))
    return rows


def cases(*scenes, cwd=ROOT):
    return [row for row, _ in cases_with_targets(*scenes, cwd=cwd)]


def test_case_list_counts_every_case():
    rows = cases(ROOT / "scenes" / "closed-exact.toml")
    # levels × u spaces × multipliers × p masses × δ (its sweep 1, 1e-2, 1e-4, 1e-6, 0)
    assert len(rows) == 5 * 2 * 3 * 2 * 5
    assert {r[0] for r in rows} == {"closed-exact"}
    outs = [r[5].split("--out ")[1] for r in rows]
    assert len(set(outs)) == len(outs), "one folder per case"
    # absolute binary and scene, from any working directory; a results folder reruns its scene copy
    # and the cases of its plan
    cmd = rows[0][5].split()
    assert cmd[0] == str(ROOT / "target" / "release" / "sdcrack")
    assert cmd[2] == str(ROOT / "scenes" / "closed-exact.toml")


def test_case_list_names_the_campaign_jobs(tmp_path):
    """Each line ends in a shell comment naming the campaign's solver shard that computes the case
    (ci/workflow/Snakefile), under --out (default results/campaign of the checkout); the columns
    and COMMAND are unchanged, so `cut -d' ' -f6- | sh` still runs the command alone."""
    rows = cases_with_targets(ROOT / "scenes" / "mixed.toml")
    assert len(rows) == 5 * 2 * 3 * 2 * 6
    for (scene, level, u, m, _delta, cmd), target in rows:
        pm = "lumped" if "--p-mass lumped" in cmd else "consistent"
        assert target == str(ROOT / "results" / "campaign" / "shards" / scene / "solver"
                             / f"l{level}-{u}-{m}-{pm}")
    assert len({t for _, t in rows}) == 5 * 2 * 3 * 2, "one shard per level, u, m, p mass"
    rows = cases_with_targets("--out", "camp", ROOT / "scenes" / "closed-exact.toml", cwd=tmp_path)
    assert rows[0][1] == str(tmp_path / "camp" / "shards" / "closed-exact" / "solver"
                             / "l0-continuous-M0-consistent")
    # the comment is a shell comment: the command part of the line runs without it
    out = subprocess.run(["bash", "-c", "ci/cases scenes/closed-exact.toml | head -1 | cut -d' ' -f6- "
                          "| sed 's/^[^ ]*/echo/' | sh"], cwd=ROOT, check=True,
                         capture_output=True, text=True).stdout
    assert out.strip().endswith("--out results/rerun/closed-exact-l0-continuous-M0-d1.0")


def test_case_list_of_a_results_folder(tmp_path):
    folder = tmp_path / "out" / "closed-exact"
    folder.mkdir(parents=True)
    # a run of the scene at δ = 0 only
    (folder / "scene.toml").write_text(
        set_key((ROOT / "scenes" / "closed-exact.toml").read_text(), "deltas", "[0.0]"))
    (folder / "summary.json").write_text(json.dumps({"plan": {
        "levels": [2], "u_spaces": ["broken"], "multipliers": ["M0", "M1"], "deltas": [0.0]}}))
    rows = cases("out/closed-exact", cwd=tmp_path)
    assert [r[:5] for r in rows] == [["closed-exact", "2", "broken", m, "0.0"] for m in ("M0", "M1")]
    cmd = rows[0][5].split()
    assert cmd[:3] == [str(ROOT / "target" / "release" / "sdcrack"), "run", str(folder / "scene.toml")]
    assert "--delta" not in cmd  # the scene's only δ: the run's δ sweep


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
    picked = {("2", "broken", "M1star", "0.0"), ("1", "continuous", "M0", "0.01"),
              ("2", "broken", "M1", "0.0001")}
    rows = [r for r in cases(scene, cwd=tmp_path) if tuple(r[1:5]) in picked]
    assert len(rows) == 3
    for r in rows:
        cmd = r[5].split() + ["--quiet"]
        assert cmd[0] == str(ROOT / "target" / "release" / "sdcrack") and cmd[2] == str(scene)
        cmd[0] = str(EXE)  # SDCRACK_BIN may name another build
        subprocess.run(cmd, cwd=tmp_path, check=True, capture_output=True)
        folder = tmp_path / cmd[cmd.index("--out") + 1] / "mixed"
        one = json.loads((folder / "summary.json").read_text())["cases"]
        assert len(one) == 6, "the delta sweep of the case"
        c = next(x for x in one if repr(float(x["delta"])) == r[4])
        f = by_key[key(c)]
        for k in ("unknowns", "multipliers", "kkt", "active_multipliers", "converged", "h",
                  "regularized_pivots", "iterations"):
            assert c[k] == f[k], (r[:5], k)
        with h5py.File(folder / "fields.h5") as a, h5py.File(tmp_path / "full" / "mixed" / "fields.h5") as b:
            g = c["fields_grid"]
            for name in ("u", "p", "crack/lambda"):
                assert np.array_equal(a[f"cases/{g}/{name}"][()], b[f"cases/{g}/{name}"][()]), (r[:5], name)


def test_case_list_of_both_p_masses(tmp_path):
    """A scene with p_mass = ["consistent", "lumped"]: one row per p mass, the same columns; the
    lumped rows' commands add `--p-mass lumped` and write to their own `-lumped` folder, the
    consistent ones are those of a scene without p masses. A results folder's plan decides."""
    text = (ROOT / "scenes" / "closed-exact.toml").read_text()
    scene = tmp_path / "closed-exact.toml"
    scene.write_text(set_key(text, "p_mass", '["consistent", "lumped"]'))
    plain_scene = tmp_path / "consistent" / "closed-exact.toml"
    plain_scene.parent.mkdir()
    plain_scene.write_text(set_key(text, "p_mass", '["consistent"]'))
    plain = cases(plain_scene)
    rows = cases(scene)
    assert len(rows) == 2 * len(plain) == 2 * 5 * 2 * 3 * 5
    lumped = [r for r in rows if "--p-mass" in r[5]]
    consistent = [r for r in rows if "--p-mass" not in r[5]]
    assert [r[:5] for r in lumped] == [r[:5] for r in consistent] == [r[:5] for r in plain]
    assert [r[5].replace(str(scene), "S") for r in consistent] == \
        [r[5].replace(str(plain_scene), "S") for r in plain]
    for r in lumped:
        cmd = r[5].split()
        assert cmd[cmd.index("--p-mass") + 1] == "lumped" and cmd.index("--p-mass") < cmd.index("--out")
        assert cmd[-1] == f"results/rerun/closed-exact-l{r[1]}-{r[2]}-{r[3]}-lumped-d{r[4]}"
    outs = [r[5].split("--out ")[1] for r in rows]
    assert len(set(outs)) == len(outs), "one folder per case"
    # a results folder of a --p-mass lumped run: its plan's p masses
    folder = tmp_path / "out" / "closed-exact"
    folder.mkdir(parents=True)
    (folder / "scene.toml").write_text(set_key(scene.read_text(), "deltas", "[0.0]"))
    (folder / "summary.json").write_text(json.dumps({"plan": {
        "levels": [2], "u_spaces": ["broken"], "multipliers": ["M1"], "p_masses": ["lumped"],
        "deltas": [0.0]}}))
    rows = cases("out/closed-exact", cwd=tmp_path)
    assert len(rows) == 1 and rows[0][:5] == ["closed-exact", "2", "broken", "M1", "0.0"]
    assert "--multiplier M1 --p-mass lumped --out" in rows[0][5]


def test_rerun_of_a_lumped_case_reproduces_the_row(tmp_path):
    if not EXE.is_file():
        pytest.skip("sdcrack binary not built")
    text = (ROOT / "scenes" / "open-exact.toml").read_text()
    for key, value in (("levels", "[1, 2]"), ("multipliers", '["M0", "M1"]'),
                       ("deltas", "[1e-2, 0.0]"), ("references", "[]"),
                       ("p_mass", '["consistent", "lumped"]')):
        text = set_key(text, key, value)
    scene = tmp_path / "open.toml"
    scene.write_text(text)
    subprocess.run([str(EXE), "run", str(scene), "--out", str(tmp_path / "full"), "--quiet"],
                   check=True, capture_output=True)
    full_dir = tmp_path / "full" / "open-exact"
    full = json.loads((full_dir / "summary.json").read_text())
    key = lambda c: (c["level"], c["u_space"], c["multiplier"], c["p_mass"], c["delta"])  # noqa: E731
    by_key = {key(c): c for c in full["cases"]}
    rows = [r for r in cases(full_dir, cwd=tmp_path)
            if tuple(r[1:5]) in {("2", "broken", "M1", "0.0"), ("1", "continuous", "M0", "0.01")}]
    assert len(rows) == 4
    for r in rows:
        cmd = r[5].split() + ["--quiet"]
        pm = "lumped" if "--p-mass" in cmd else "consistent"
        assert cmd[0] == str(ROOT / "target" / "release" / "sdcrack")
        cmd[0] = str(EXE)  # SDCRACK_BIN may name another build
        subprocess.run(cmd, cwd=tmp_path, check=True, capture_output=True)
        folder = tmp_path / cmd[cmd.index("--out") + 1] / "open-exact"
        one = json.loads((folder / "summary.json").read_text())["cases"]
        assert {c["p_mass"] for c in one} == ({"lumped"} if pm == "lumped" else {"consistent", "lumped"})
        c = next(x for x in one if repr(float(x["delta"])) == r[4] and x["p_mass"] == pm)
        f = by_key[key(c)]
        for k in ("unknowns", "multipliers", "kkt", "active_multipliers", "converged", "h",
                  "regularized_pivots", "iterations", "fields_grid", "condition_estimate"):
            assert c[k] == f[k], (r[:5], pm, k)
        # the lumped case's error norms, alone and after the consistent one, once differed by
        # 1 ulp (the fields are bitwise equal)
        for q, v in f["errors"].items():
            assert c["errors"][q] == pytest.approx(v, rel=1e-14, abs=1e-300), (r[:5], pm, q)
        with h5py.File(folder / "fields.h5") as a, h5py.File(full_dir / "fields.h5") as b:
            g = c["fields_grid"]
            assert ("-lumped-delta" in g) == (pm == "lumped")
            for name in ("u", "p", "crack/lambda"):
                assert np.array_equal(a[f"cases/{g}/{name}"][()], b[f"cases/{g}/{name}"][()]), (r[:5], name)


@pytest.mark.parametrize("name", ["inclined", "off-axis", "all-closed", "tip-contact", "stress-active-set"])
def test_new_scenes_pass_check(name):
    if not EXE.is_file():
        pytest.skip("sdcrack binary not built")
    r = subprocess.run([str(EXE), "check", str(ROOT / "scenes" / f"{name}.toml")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert f"valid scene '{name}'" in r.stdout
