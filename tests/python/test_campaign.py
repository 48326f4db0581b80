"""ci/cases lists the campaign, and its commands rerun single cases reproducibly.

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

ROOT = pathlib.Path(__file__).resolve().parents[2]
EXE = pathlib.Path(os.environ.get("SDCRACK_BIN", ROOT / "target" / "release" / "sdcrack"))
h5py = pytest.importorskip("h5py")


def cases(*scenes, cwd=ROOT):
    out = subprocess.run([str(ROOT / "ci" / "cases"), *map(str, scenes)], cwd=cwd, check=True,
                         capture_output=True, text=True).stdout
    return [line.split(" ", 5) for line in out.splitlines()]


def test_case_list_counts_every_case():
    rows = cases(ROOT / "scenes" / "closed-exact.toml")
    assert len(rows) == 5 * 2 * 3 * 1
    assert {r[0] for r in rows} == {"closed-exact"}
    outs = [r[5].split("--out ")[1] for r in rows]
    assert len(set(outs)) == len(outs), "one folder per case"
    # absolute binary and scene, from any working directory; a results folder reruns its scene copy
    # and the cases of its plan
    cmd = rows[0][5].split()
    assert cmd[0] == str(ROOT / "target" / "release" / "sdcrack")
    assert cmd[2] == str(ROOT / "scenes" / "closed-exact.toml")


def test_case_list_of_a_results_folder(tmp_path):
    folder = tmp_path / "out" / "closed-exact"
    folder.mkdir(parents=True)
    (folder / "scene.toml").write_text((ROOT / "scenes" / "closed-exact.toml").read_text())
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
    text = text.replace("levels = [0, 1, 2, 3, 4]", "levels = [1, 2]")
    text = text.replace('references = ["dolfinx", "freefem"]', "references = []")
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


@pytest.mark.parametrize("name", ["inclined", "off-axis", "all-closed", "tip-contact", "stress-active-set"])
def test_new_scenes_pass_check(name):
    if not EXE.is_file():
        pytest.skip("sdcrack binary not built")
    r = subprocess.run([str(EXE), "check", str(ROOT / "scenes" / f"{name}.toml")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert f"valid scene '{name}'" in r.stdout
