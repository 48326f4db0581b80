"""The elastic verdict's "viewer datasets" check (compare/sdcompare_lib/elastic_fields.py): each
reference's field files hold its own outputs. On the synthetic Williams folders of
elastic_synthetic.py, with the field files written by the references' own writer
(sdshared.sdfields.write_fields) and the stress by Hooke's law written out here: a correct folder
PASSes the check, and each realistic bug of a reference's field files FAILs the verdict — a halved
shear stress (tools/mutants.toml's dolfinx-elastic-shear-stress-halved, which every other check
PASSed), a crack field of the wrong sign, a u off by one ulp, another level's mesh, a grid whose
topology names another dataset; without field files the check does not apply.

Run: /usr/bin/python3 -m pytest compare/tests/test_elastic_viewer.py -q
"""
import re
from pathlib import Path

import numpy as np

import elastic_synthetic as es
from sdcompare_lib import elastic, elastic_read
from sdshared import sdfields

LEVELS = (0, 1, 2)
CRACK_COLUMNS = ("opening", "slip", "contact_force", "active")


def stress(xy, tri, u):
    """(T, 3) (σ_xx, σ_yy, σ_xy) of the P1 u: λ tr ε + 2μ ε, written out (plane strain, E = 1,
    ν = 0.3: λ* = λ)."""
    gx, gy = (sdfields.triangle_gradients(xy, tri, u[:, c]) for c in (0, 1))
    exx, eyy, exy = gx[:, 0], gy[:, 1], (gx[:, 1] + gy[:, 0]) / 2
    return np.column_stack([es.LAMBDA * (exx + eyy) + 2 * es.MU * exx,
                            es.LAMBDA * (exx + eyy) + 2 * es.MU * eyy, 2 * es.MU * exy])


def with_fields(folder, damage=None):
    """Writes each reference's fields.h5 and fields/*.xdmf as the references do (sdfields), from
    its u_level{L}.txt and crack_level{L}.txt; damage(tool, level, field_set) may change a field
    set in place before it is written."""
    folder = Path(folder)
    for tool in ("dolfinx", "freefem"):
        sets = []
        for L in LEVELS:
            lv = elastic_read.read_level(str(folder / "mesh"), L)
            u = np.loadtxt(folder / tool / f"u_level{L}.txt", ndmin=2)
            crack = np.loadtxt(folder / tool / f"crack_level{L}.txt", ndmin=2)
            fs = {"xy": lv.points.copy(), "tri": lv.triangles.copy(), "crack": lv.pairs,
                  "segments": lv.segments(), "point": {"u": u},
                  "cell": {"stress": stress(lv.points, lv.triangles, u)},
                  "crack_fields": {c: crack[:, k].copy() for k, c in enumerate(CRACK_COLUMNS)}}
            if damage is not None:
                damage(tool, L, fs)
            sets.append((L, fs))
        sdfields.write_fields(folder / tool, sets, tool)
    return folder


def viewer(folder):
    a = elastic.analyse(elastic_read.load(str(folder)))
    row = next(c for c in a["checks"] if c[0] == "viewer datasets")
    return a, row[2], row[3]


def test_a_correct_folder_passes_the_check(tmp_path):
    folder = with_fields(es.write_results(tmp_path / "w", levels=LEVELS))
    a, probs, na = viewer(folder)
    assert na is None and probs == [] and a["verdict"] == "PASS", (probs, a["reasons"])


def test_without_field_files_the_check_does_not_apply(tmp_path):
    _, probs, na = viewer(es.write_results(tmp_path / "w", levels=LEVELS))
    assert probs == [] and "no reference wrote field files" in na


def fails(tmp_path, damage, pattern):
    folder = with_fields(es.write_results(tmp_path / "w", levels=LEVELS), damage)
    a, probs, _ = viewer(folder)
    assert a["verdict"] == "FAIL" and probs and all(re.search(pattern, p) for p in probs), probs
    # no other check sees the field files
    assert all(r.startswith("viewer datasets:") for r in a["reasons"]), a["reasons"]
    return probs


def test_a_halved_shear_stress_fails(tmp_path):
    """dolfinx-elastic-shear-stress-halved: σ_xy = μ ε_xy in one reference's stress field."""
    def damage(tool, L, fs):
        if tool == "dolfinx":
            fs["cell"]["stress"][:, 2] *= 0.5

    probs = fails(tmp_path, damage, r"^dolfinx/fields\.h5 level \d: stress is not σ\(u_h\)")
    assert len(probs) == len(LEVELS) and "σ_xy" in probs[0]


def test_a_crack_field_of_the_wrong_sign_fails(tmp_path):
    def damage(tool, L, fs):
        if tool == "freefem" and L == 1:
            fs["crack_fields"]["opening"] = -fs["crack_fields"]["opening"]

    fails(tmp_path, damage, r"^freefem/fields\.h5 level 1: /cases/level1/crack/opening differs "
          "from its source")


def test_a_u_off_by_one_ulp_fails(tmp_path):
    """u is bit for bit its u_level{L}.txt (read back exactly from %.17g)."""
    def damage(tool, L, fs):
        if tool == "dolfinx" and L == 2:
            fs["point"]["u"] = fs["point"]["u"].copy()
            fs["point"]["u"][5, 0] = np.nextafter(fs["point"]["u"][5, 0], np.inf)

    fails(tmp_path, damage, r"^dolfinx/fields\.h5 level 2: /cases/level2/u differs from its "
          "source at 1 value")


def test_another_mesh_fails(tmp_path):
    """The grid a viewer shows is the export's: a vertex moved (a corner, on no crack) fails the
    mesh's points."""
    def damage(tool, L, fs):
        if tool == "freefem" and L == 0:
            fs["xy"][0] = fs["xy"][0] + 1e-3

    fails(tmp_path, damage, r"^freefem/fields\.h5 level 0: /meshes/level0/points differs from "
          r"its source at 2 value\(s\) \(first row 0: ")


def test_a_grid_linking_another_dataset_fails(tmp_path):
    folder = with_fields(es.write_results(tmp_path / "w", levels=LEVELS))
    x = folder / "dolfinx" / "fields" / "level1.xdmf"
    x.write_text(x.read_text().replace("/meshes/level1/triangles", "/meshes/level0/triangles"))
    a, probs, _ = viewer(folder)
    assert a["verdict"] == "FAIL"
    assert probs == ["dolfinx/fields/level1.xdmf: the topology of grid level1 points at "
                     "/meshes/level0/triangles, not /meshes/level1/triangles of its fields.h5"]
