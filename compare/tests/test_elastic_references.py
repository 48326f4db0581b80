"""The compare tool on the elastic references' real outputs (dolfinx and FreeFEM, docs/elasticity.md)
on a stand-in mesh export (references/tests/elastic_export.py): Williams' mixed-mode edge crack
(K_I = 1, K_II = 1/2, open everywhere) at levels 0–2 of 8 × 8 cells PASSes, the references agree
to round-off, the rates are P1's singular ones and the SIFs approach the exact ones; the same
folder with one reference's u damaged FAILs. Skipped where a reference's elastic path, dolfinx or
FreeFem++ is missing.

Run: /usr/bin/python3 -m pytest compare/tests/test_elastic_references.py -q
"""
import importlib.util
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import elastic_synthetic as es
from sdcompare_lib import elastic, elastic_read

ROOT = Path(__file__).resolve().parents[2]
SOLVERS = {tool: ROOT / "references" / tool / "solve.py" for tool in ("dolfinx", "freefem")}

pytestmark = [
    pytest.mark.skipif(shutil.which("FreeFem++") is None, reason="FreeFem++ not installed"),
    pytest.mark.skipif(importlib.util.find_spec("dolfinx") is None, reason="dolfinx not installed"),
    pytest.mark.skipif(not all((ROOT / "references" / t / "elasticity.py").exists()
                               for t in SOLVERS),
                       reason="this checkout's references have no elastic path"),
]


def results_folder(tmp_path):
    out = tmp_path / "williams"
    name = "williams-mixed"
    exact = es.williams(1.0, 0.5)
    es.write_export(out / "mesh", name, exact, (0, 1, 2), 8)
    (out / "summary.json").write_text(json.dumps({"scene": name, "problem": "elasticity"}))
    (out / "scene.toml").write_text(f'name = "{name}"\n[discretization]\nlevels = [0, 1, 2]\n'
                                    '[outputs]\nreferences = ["dolfinx", "freefem"]\n')
    env = dict(os.environ, FF_LOADPATH=os.environ.get("FF_LOADPATH", "/usr/lib/freefem++"),
               MPLBACKEND="Agg", PYTHONPATH=os.pathsep.join(
                   [str(ROOT / "compare")] + [p for p in os.environ.get("PYTHONPATH", "").split(
                       os.pathsep) if p]))
    for tool, script in SOLVERS.items():
        p = subprocess.run([sys.executable, str(script), str(out / "mesh"), "--out",
                            str(out / tool)], capture_output=True, text=True, env=env)
        assert p.returncode == 0, (tool, p.stderr)
    return out


def test_the_references_on_williams_pass_and_a_damaged_one_fails(tmp_path):
    folder = results_folder(tmp_path)
    a = elastic.analyse(elastic_read.load(str(folder)))
    assert a["verdict"] == "PASS", a["reasons"]
    assert all(g["u_rel"] < 1e-12 and g["flags_differ"] == 0 and g["sif_rel"] < 1e-12
               for g in a["agreement"])
    by = {(s["tool"], s["quantity"]): s for s in a["series"]}
    # measured (levels 0–2): u 0.94, 0.96; H¹ 0.48, 0.49; K_I 1.02, 1.01; u agreement 1.8e-14
    assert 0.9 < by[("dolfinx", "u_l2")]["rates"][-1] < 1.1
    assert 0.4 < by[("freefem", "u_h1")]["rates"][-1] < 0.6
    k1, k2 = a["sif_by_key"][("dolfinx", 2)][0]
    assert abs(k1 - 1.0) < 0.03 and abs(k2 - 0.5) < 0.01
    # FreeFEM's u at level 2 scaled by 1 + 1e-6: the references no longer agree
    path = folder / "freefem" / "u_level2.txt"
    np.savetxt(path, np.loadtxt(path) * (1 + 1e-6), fmt="%.17g")
    a = elastic.analyse(elastic_read.load(str(folder)))
    assert a["verdict"] == "FAIL"
    assert any(p.startswith("level 2: dolfinx and freefem differ in u by 1.00e-06")
               for p in next(p for lab, _, p, _ in a["checks"] if lab == "reference agreement"))
