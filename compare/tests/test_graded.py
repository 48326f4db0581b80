"""Graded meshes (issue 24) in the compare tool: the export's "graded" levels nest through
parents.txt, and a coarse P1 field prolongs exactly onto a finer graded level; a wrong parent is a
NormError, not a silently wrong norm."""
import os
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "compare"))
sys.path.insert(0, os.path.join(ROOT, "references", "common"))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))

from scene_text import set_key  # noqa: E402
from sdcompare_lib import norms, read  # noqa: E402


def sdcrack_bin():
    return os.environ.get("SDCRACK_BIN") or os.path.join(ROOT, "target", "release", "sdcrack")


@pytest.fixture(scope="module")
def export(tmp_path_factory):
    if not os.access(sdcrack_bin(), os.X_OK):
        pytest.skip("no sdcrack binary (cargo build --release, or SDCRACK_BIN)")
    tmp = tmp_path_factory.mktemp("graded")
    with open(os.path.join(ROOT, "scenes", "open-exact.toml"), encoding="utf-8") as fh:
        text = fh.read()
    text = set_key(text, "cells", "[8, 8]\ngrading = { beta = 0.4, radius = 0.5 }")
    text = set_key(text, "levels", "[0, 1, 2]")
    scene = tmp / "graded.toml"
    scene.write_text(text)
    subprocess.run([sdcrack_bin(), "mesh", str(scene), "--out", str(tmp / "mesh")], check=True,
                   capture_output=True, timeout=300)
    return str(tmp / "mesh")


def test_graded_levels_nest_and_prolong_p1_fields_exactly(export):
    meshes = read.load_export_meshes(export, [0, 1, 2])
    assert [meshes[lv].kind for lv in (0, 1, 2)] == ["graded"] * 3
    assert meshes[0].parents is None and len(meshes[2].parents) == len(meshes[2].tris)
    n = [len(meshes[lv].tris) for lv in (0, 1, 2)]
    # ~4x per level: 4 asymptotically (the graded zone holds ~πR²/(βh²) elements); measured 5.7
    # from level 0 to 1 (the closure of the grading, relatively larger on coarse levels), 4.7 next
    assert 3.5 < n[2] / n[1] < 5.0 and n[1] / n[0] < 6.0, n
    kind, owner = norms.nesting(meshes, 0, 2)
    assert kind == "graded" and owner.shape == (n[2],)
    c, f = meshes[0], meshes[2]
    linear = lambda p: 1.0 + p[..., 0] - 2.0 * p[..., 1]  # noqa: E731
    v = norms.prolong_to_fine(c.points, c.tris, linear(c.points[:, :2]), f.points, f.tris,
                              kind, owner)
    assert np.allclose(v, linear(f.points[:, :2])[f.tris], rtol=0, atol=1e-13)
    # the crack's two faces: the − copies carry their own values, and a fine triangle takes the
    # values of its own face (its coarse ancestor is on the same side)
    jump = np.zeros(len(c.points))
    jump[c.crack[:, 1]] = 1.0  # − copies only (tips: plus = minus, both set)
    jump[c.crack[:, 0]] = 0.0
    pj = norms.prolong_to_fine(c.points, c.tris, jump, f.points, f.tris, kind, owner)
    assert pj.min() >= -1e-13 and pj.max() <= 1 + 1e-13


def test_a_wrong_parent_is_a_norm_error(export):
    meshes = read.load_export_meshes(export, [0, 1, 2])
    meshes[2].parents = np.roll(meshes[2].parents, 7)
    kind, owner = norms.nesting(meshes, 1, 2)
    c, f = meshes[1], meshes[2]
    with pytest.raises(norms.NormError, match="does not lie in coarse triangle"):
        norms.prolong_to_fine(c.points, c.tris, np.zeros(len(c.points)), f.points, f.tris, kind,
                              owner)
    meshes[2].parents = None
    with pytest.raises(norms.NormError, match="has no parents.txt"):
        norms.nesting(meshes, 1, 2)


def test_graded_rates_are_measured_in_unknowns():
    """On graded meshes the rate is per halving of N^{-1/2}: errors falling 2× per level while N
    grows 5.7×, 4.7× are rates 0.80, 0.90 — not 1 (h still halves)."""
    from sdcompare_lib import settings, verdict

    st = settings.verification({"discretization": {"levels": [0, 1, 2], "u_spaces": ["broken"],
                                                   "multipliers": ["M1"], "deltas": [0.0]},
                                "verification": {}}, "scene.toml")
    cases = [{"level": lv, "h": 0.35 / 2 ** lv, "unknowns": n, "u_space": "broken",
              "multiplier": "M1", "delta": 0.0, "p_mass": "consistent", "kkt": {},
              "errors": {"u_l2": 0.1 / 2 ** lv, "p_l2": 0.1 / 2 ** lv, "p_x": 0.1 / 2 ** lv,
                         "lambda_l2": 0.1 / 2 ** lv}}
             for lv, n in enumerate([256, 1464, 6912])]
    uniform = {s["quantity"]: s for s in verdict.compute_series("t", cases, [], True, st, 1.0)}
    graded = {s["quantity"]: s for s in verdict.compute_series("t", cases, [], True, st, 1.0,
                                                                graded=True)}
    assert uniform["u_l2"]["rates"] == pytest.approx([1.0, 1.0])
    assert graded["u_l2"]["rates"] == pytest.approx([2 / np.log2(1464 / 256), 2 / np.log2(6912 / 1464)])
    assert graded["u_l2"]["mesh_parameter"] == "N^-1/2" and uniform["u_l2"]["mesh_parameter"] == "h"


def test_graded_l_shape_with_two_cracks_passes_against_the_references(tmp_path):
    """Issue 24's acceptance scene (scenes/l-shape-graded.toml: an L-shaped polygon, two cracks,
    four graded tips), levels 0-2 with both references: PASS, the reference yardstick and the
    references' agreement among its checks."""
    if not os.access(sdcrack_bin(), os.X_OK):
        pytest.skip("no sdcrack binary (cargo build --release, or SDCRACK_BIN)")
    with open(os.path.join(ROOT, "scenes", "l-shape-graded.toml"), encoding="utf-8") as fh:
        text = set_key(fh.read(), "levels", "[0, 1, 2]")
    scene = tmp_path / "l-shape-graded.toml"
    scene.write_text(text)
    env = dict(os.environ, MPLBACKEND="Agg")
    env.setdefault("FF_LOADPATH", "/usr/lib/freefem++")
    p = subprocess.run([sdcrack_bin(), "run", str(scene), "--out", str(tmp_path / "out"),
                        "--quiet"], capture_output=True, text=True, env=env, timeout=900)
    assert p.returncode == 0, p.stderr[-2000:]
    folder = tmp_path / "out" / "l-shape-graded"
    assert (folder / "mesh" / "level2" / "parents.txt").is_file()
    p = subprocess.run([sys.executable, os.path.join(ROOT, "compare", "sdcompare"),
                        str(folder)], capture_output=True, text=True, env=env, timeout=900)
    assert p.returncode == 0 and p.stdout.strip().endswith("l-shape-graded: PASS"), \
        p.stdout[-2000:] + p.stderr[-2000:]
    import json

    report = json.loads((folder / "report" / "report.json").read_text())
    status = {c["check"]: c["status"] for c in report["checks"]}
    assert status["reference yardstick"] == "ok" and status["reference agreement"] == "ok"
