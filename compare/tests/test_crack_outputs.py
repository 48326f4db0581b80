"""Every crack output checked, and the cut checked from the scene (issue 43): the checks "crack
outputs", "viewer datasets" (compare/sdcompare_lib/crackcheck.py) and the cut of "field files'
mesh" (compare/sdcompare_lib/crackcut.py) PASS on real results folders and FAIL, each with its
own problem line, on damaged copies of them.

The folders are written once per module by `sdcrack run` (SDCRACK_BIN, else
target/release/sdcrack):
* kink: tests/data/scenes/kinked-no-references.toml as it is (gmsh levels 0-3, a kinked closed
  crack, broken u, M1, no reference: nothing but the scene tells the + copy from the − one), ~3 s;
* mixed: scenes/mixed.toml on [4, 4] cells, levels 0-1, M1, δ = 0, fields = ["u", "lambda"] (so
  that verification.h5 is written beside fields.h5), both references: an open part and a closed
  part of the crack, ~8 s.
The checks are called as compare/sdcompare calls them, on the loaded folder (no report drawn).
Run: FF_LOADPATH=/usr/lib/freefem++ /usr/bin/python3 -m pytest -q compare/tests/test_crack_outputs.py
"""
import os
import shutil

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

from scene_text import scene_with
from sdcompare_lib import crackcheck, crackcut, meshcheck, read, settings
from conftest import run_scene, sdcrack_bin

KINK = os.path.join(ROOT, "tests", "data", "scenes", "kinked-no-references.toml")
NEW_CHECKS = ("field files' mesh", "crack outputs", "viewer datasets")


def mixed_scene():
    return scene_with("mixed", ("cells", "[4, 4]"), ("levels", "[0, 1]"),
                      ("multipliers", '["M1"]'), ("p_mass", '["consistent"]'),
                      ("deltas", "[0.0]"), ("fields", '["u", "lambda"]'),
                      ("name", '"mixed-crack-outputs"'))


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    if not os.access(sdcrack_bin(), os.X_OK):
        pytest.skip("no sdcrack binary (cargo build --release, or SDCRACK_BIN)")
    tmp = tmp_path_factory.mktemp("crack")
    with open(KINK, encoding="utf-8") as fh:
        kink = fh.read()
    return {"kink": run_scene(tmp, "kink", kink), "mixed": run_scene(tmp, "mixed", mixed_scene())}


def judge(folder, tmp_path, damage=None):
    """{check: problems} of the three checks on a copy of `folder` damaged by damage(copy)."""
    copy = tmp_path / os.path.basename(folder)
    shutil.copytree(folder, copy)
    if damage is not None:
        damage(str(copy))
    res = read.load_results(str(copy))
    try:
        st = settings.verification(res["scene_file"], str(copy / read.SCENE_COPY))
        a = {}
        rows = meshcheck.checks(res, a) + crackcheck.checks(res, a, st)
    finally:
        read.close_results(res)
    return {r[0]: r[2] for r in rows if r[0] in NEW_CHECKS}


def edit_h5(path, fn):
    import h5py

    with h5py.File(path, "r+") as f:
        fn(f)


def set_ds(f, name, values):
    f[name][...] = values


def kink_node_copies(folder, mesh):
    """(plus, minus) vertex numbers of the kink node (0, −0.2) in the stored mesh `mesh`."""
    import h5py

    with h5py.File(os.path.join(folder, "fields.h5"), "r") as f:
        P = f[f"meshes/{mesh}/points"][()][:, :2]
    at = np.flatnonzero((P[:, 0] == 0.0) & (P[:, 1] == -0.2))
    assert len(at) == 2
    return int(at.min()), int(at.max())


def joined(problems):
    return " | ".join(problems)


# ------------------------------------------------------------------ undamaged
@pytest.mark.parametrize("base", ["kink", "mixed"])
def test_undamaged_folders_pass(folders, tmp_path, base):
    checks = judge(folders[base], tmp_path)
    assert set(checks) == set(NEW_CHECKS)
    assert all(p == [] for p in checks.values()), checks


# ------------------------------------------------------------------ the cut, from the scene
def test_faces_swapped_at_the_kink_fail_without_references(folders, tmp_path):
    """The + and − copies of the kink node exchanged in every triangle at it (what a wrong
    left_of_path at a kink gives): the cut is still a cut (one copy per face), and no export
    tells which copy belongs to which face; the scene's polyline does."""
    mesh = "level2-broken"

    def damage(folder):
        a, b = kink_node_copies(folder, mesh)

        def swap(f):
            t = f[f"meshes/{mesh}/triangles"][()]
            t2 = np.where(t == a, b, np.where(t == b, a, t))
            f[f"meshes/{mesh}/triangles"][...] = t2
        edit_h5(os.path.join(folder, "fields.h5"), swap)

    probs = judge(folders["kink"], tmp_path, damage)["field files' mesh"]
    assert len(probs) == 1, probs
    assert probs[0].startswith("level 2 broken (/meshes/level2-broken): ") and \
        "triangle corner(s) at 1 interior crack node(s) (1 of them kinks) use the other face's " \
        "copy, e.g. at (0, -0.2)" in probs[0], probs


def test_faces_swapped_everywhere_fail(folders, tmp_path):
    mesh = "level1-broken"

    def damage(folder):
        def swap(f):
            P = f[f"meshes/{mesh}/points"][()][:, :2]
            t = f[f"meshes/{mesh}/triangles"][()]
            z = P[:, 0] + 1j * P[:, 1]
            other = np.arange(len(P))
            for v in range(len(P)):
                twin = np.flatnonzero(z == z[v])
                if len(twin) == 2:
                    other[v] = twin[twin != v][0]
            f[f"meshes/{mesh}/triangles"][...] = other[t]
        edit_h5(os.path.join(folder, "fields.h5"), swap)

    (line,) = judge(folders["kink"], tmp_path, damage)["field files' mesh"]
    assert "use the other face's copy" in line and "(1 of them kinks)" in line, line


def test_minus_copies_out_of_crack_order_fail(folders, tmp_path):
    """The − copies numbered in reverse crack order (points and triangles renumbered together:
    the same cut mesh, another numbering than docs/design.md's)."""
    mesh = "level1-broken"

    def damage(folder):
        def renumber(f):
            P = f[f"meshes/{mesh}/points"][()]
            t = f[f"meshes/{mesh}/triangles"][()]
            n = len(P)
            z = P[:, 0] + 1j * P[:, 1]
            minus = sorted(v for v in range(n) if np.sum(z == z[v]) == 2 and
                           v == np.flatnonzero(z == z[v]).max())
            perm = np.arange(n)
            perm[minus] = minus[::-1]  # new number of each old vertex
            newP = np.empty_like(P)
            newP[perm] = P
            f[f"meshes/{mesh}/points"][...] = newP
            f[f"meshes/{mesh}/triangles"][...] = perm[t]
        edit_h5(os.path.join(folder, "fields.h5"), renumber)

    probs = judge(folders["kink"], tmp_path, damage)["field files' mesh"]
    assert any("the − copies are not the last" in p and "in crack order" in p for p in probs), probs


def test_plus_face_is_the_left_wedge():
    """plus_face at a straight node, a convex and a reflex kink (unit directions)."""
    def side(out, back, d):
        return bool(crackcut.plus_face(np.array([out], float), np.array([back], float),
                                       np.array([d], float))[0])
    # straight along +x: + is y > 0
    assert side((1, 0), (-1, 0), (0.3, 0.1)) and not side((1, 0), (-1, 0), (0.3, -0.1))
    # the path arrives from −x and turns up (+y): the left wedge is the quadrant x < 0, y > 0
    assert side((0, 1), (-1, 0), (-1, 1)) and not side((0, 1), (-1, 0), (1, 1))
    assert not side((0, 1), (-1, 0), (1, -1)) and not side((0, 1), (-1, 0), (-1, -1))
    # the path arrives from −x and turns down (−y): the left wedge is the other three quadrants
    assert side((0, -1), (-1, 0), (1, 1)) and side((0, -1), (-1, 0), (-1, 1))
    assert side((0, -1), (-1, 0), (1, -1)) and not side((0, -1), (-1, 0), (-1, -1))


def test_scene_crack_nodes_along_a_kinked_polyline():
    """The crack nodes of a mesh from a polyline: those on its segments, in order, the kink once."""
    pts = np.array([[0, 0], [0.5, 0], [1, 0], [1, 0.5], [1, 1], [0.5, 0.5], [2, 0]], float)
    sc = crackcut.SceneCrack([np.array([[0, 0], [1, 0], [1, 1]], float)], pts)
    assert sc.problems == []
    assert sc.xy.tolist() == [[0, 0], [0.5, 0], [1, 0], [1, 0.5], [1, 1]]
    assert sc.tip.tolist() == [True, False, False, False, True]
    assert sc.segments.tolist() == [[0, 1], [1, 2], [2, 3], [3, 4]]
    assert sc.out[2].tolist() == [0, 1] and sc.back[2].tolist() == [-1, 0]
    missing = crackcut.SceneCrack([np.array([[0, 0], [1, 0], [1, 1.5]], float)], pts)
    assert missing.problems == ["the point (1, 1.5) of crack 0 of the scene is no mesh vertex"]


# ------------------------------------------------------------------ the solver's crack outputs
def _negate(name):
    def damage(folder):
        def fn(f):
            for g in f["cases"].values():
                if name in g:
                    g[name][...] = -g[name][()]
        for fname in ("fields.h5", "verification.h5"):
            if os.path.exists(os.path.join(folder, fname)):
                edit_h5(os.path.join(folder, fname), fn)
    return damage


@pytest.mark.parametrize("base", ["kink", "mixed"])
def test_the_solvers_jump_negated_fails(folders, tmp_path, base):
    probs = judge(folders[base], tmp_path, _negate("crack/jump"))["crack outputs"]
    assert probs and all("its jump is not u⁺ − u⁻ of its stored u at" in p for p in probs), probs
    if base == "mixed":  # both files: fields.h5 (the viewer's) and verification.h5
        assert any(p.startswith("fields.h5 level 1 broken M1") for p in probs), probs
        assert any(p.startswith("verification.h5 level 1 broken M1") for p in probs), probs


def test_u_with_its_faces_exchanged_fails_lambda_against_the_jump(folders, tmp_path):
    """u⁺ and u⁻ exchanged at every crack node and the jump written from that u (consistent):
    the jump closes where M1's λ_h opens the crack."""
    def damage(folder):
        def fn(f):
            for name, g in f["cases"].items():
                if "broken" not in name or "u" not in g:
                    continue
                P = f[g["mesh"].name + "/points"][()][:, :2] if "mesh" in g else None
                cp = g["crack/points"][()][:, :2]
                plus, minus = crackcheck.copies_at(P, cp)
                u = g["u"][()]
                u[plus], u[minus] = u[minus].copy(), u[plus].copy()
                g["u"][...] = u
                g["crack/jump"][...] = u[plus] - u[minus]
        for fname in ("fields.h5", "verification.h5"):
            edit_h5(os.path.join(folder, fname), fn)

    # level 0 (3 crack nodes) has no edge with λ_h > 0 at both ends: nothing to compare there
    (line,) = judge(folders["mixed"], tmp_path, damage)["crack outputs"]
    assert line.startswith("level 1 broken M1 δ=0: on the open part of the crack (λ_h > 0) "
                           "‖λ_h − [u_h]‖ = ") and "is not below ‖λ_h‖" in line, line


# ------------------------------------------------------------------ the references' crack outputs
def _ref(folder, tool):
    return os.path.join(folder, tool, "fields.h5")


def test_freefem_contact_force_shifted_by_one_node_fails(folders, tmp_path):
    def damage(folder):
        edit_h5(_ref(folder, "freefem"), lambda f: [
            set_ds(f, f"cases/level{lv}/crack/contact_force",
                   np.roll(f[f"cases/level{lv}/crack/contact_force"][()], 1)) for lv in (0, 1)])

    # level 0's one interior node is open (force 0): the shift moves zeros there
    (line,) = judge(folders["mixed"], tmp_path, damage)["crack outputs"]
    # ‖K‖∞ of the structured grid's P1 stiffness: 4 on the diagonal, 4 × |−1| off it
    assert line.startswith("references dolfinx and freefem level 1: their contact_force differ "
                           "by ") and "(‖K‖∞ = 8; " in line, line


def test_a_contact_force_at_a_tip_fails(folders, tmp_path):
    """Both references with the same nonzero force at the first tip (they agree, and a tip has
    no multiplier)."""
    def damage(folder):
        for tool in ("dolfinx", "freefem"):
            def fn(f):
                x = f["cases/level1/crack/contact_force"][()]
                x[0] = 0.25
                f["cases/level1/crack/contact_force"][...] = x
            edit_h5(_ref(folder, tool), fn)

    probs = judge(folders["mixed"], tmp_path, damage)["crack outputs"]
    assert probs == [f"reference {tool} level 1: 1 crack tip(s) with a nonzero jump or "
                     "contact_force, e.g. row 0: jump 0, contact_force 0.25 (both must be 0 at a "
                     "tip)" for tool in ("dolfinx", "freefem")], probs


def test_dolfinx_jump_negated_fails(folders, tmp_path):
    def damage(folder):
        edit_h5(_ref(folder, "dolfinx"), lambda f: set_ds(
            f, "cases/level1/crack/jump", -f["cases/level1/crack/jump"][()]))

    probs = judge(folders["mixed"], tmp_path, damage)["crack outputs"]
    text = joined(probs)
    assert "reference dolfinx level 1: its jump is not u⁺ − u⁻ of its u at crack.txt's rows" \
        in text, probs
    assert "references dolfinx and freefem level 1: their jumps differ by" in text, probs


def test_dolfinx_contact_force_scaled_fails(folders, tmp_path):
    """A contact force 1 % off (another scaling of the multiplier): only the agreement sees it."""
    def damage(folder):
        edit_h5(_ref(folder, "dolfinx"), lambda f: set_ds(
            f, "cases/level1/crack/contact_force",
            1.01 * f["cases/level1/crack/contact_force"][()]))

    (line,) = judge(folders["mixed"], tmp_path, damage)["crack outputs"]
    assert line.startswith("references dolfinx and freefem level 1: their contact_force differ "
                           "by "), line


# ------------------------------------------------------------------ the viewer's datasets
def test_a_viewers_u_other_than_the_checked_one_fails(folders, tmp_path):
    """fields.h5's u (what ParaView shows) differs from verification.h5's (what every check
    reads) at one vertex."""
    def damage(folder):
        def fn(f):
            g = f["cases/level1-broken-M1-delta0"]
            u = g["u"][()]
            u[0] += 1e-3
            g["u"][...] = u
        edit_h5(os.path.join(folder, "fields.h5"), fn)

    probs = judge(folders["mixed"], tmp_path, damage)["viewer datasets"]
    assert probs == ["fields.h5 level 1 broken M1 δ=0: its u is not verification.h5's (what a "
                     "viewer shows is not what was checked)"], probs


def test_a_wrong_delta_constant_fails(folders, tmp_path):
    def damage(folder):
        edit_h5(os.path.join(folder, "fields.h5"), lambda f: set_ds(
            f, "cases/level2-broken-M1-delta0/crack/delta", 1e-2))

    probs = judge(folders["kink"], tmp_path, damage)["viewer datasets"]
    assert probs == ["fields.h5 level 2 broken M1 δ=0: its constant field crack/delta is not the "
                     "case's δ = 0 everywhere (e.g. 0.01)"], probs


def test_a_references_viewer_u_fails(folders, tmp_path):
    def damage(folder):
        def fn(f):
            u = f["cases/level0/u"][()]
            u[3] += 1e-9
            f["cases/level0/u"][...] = u
        edit_h5(_ref(folder, "freefem"), fn)

    probs = judge(folders["mixed"], tmp_path, damage)["viewer datasets"]
    # its p, the gradient of the stored u, no longer matches that u either
    assert probs[0] == "reference freefem level 0: the u of its fields.h5 is not its u_level0.txt"
    assert len(probs) == 2 and probs[1].startswith("reference freefem level 0: its p is not"), probs


def test_a_references_viewer_p_fails(folders, tmp_path):
    def damage(folder):
        def fn(f):
            p = f["cases/level1/p"][()]
            p[5, 0] += 1e-9
            f["cases/level1/p"][...] = p
        edit_h5(_ref(folder, "freefem"), fn)

    (line,) = judge(folders["mixed"], tmp_path, damage)["viewer datasets"]
    assert line.startswith("reference freefem level 1: its p is not the area-weighted vertex "
                           "mean of its P1 gradient at 1 vertices, e.g. vertex 5"), line


def test_an_attribute_pointing_at_another_dataset_fails(folders, tmp_path):
    """The crack file's `jump` attribute points at λ (a viewer labels λ as the jump)."""
    rel = "fields/level1-broken-M1-delta0.crack.xdmf"

    def damage(folder):
        path = os.path.join(folder, rel)
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
        old = "/cases/level1-broken-M1-delta0/crack/jump<"
        assert text.count(old) == 1
        with open(path, "w", encoding="utf-8") as fh:
            fh.write(text.replace(old, "/cases/level1-broken-M1-delta0/crack/lambda<"))

    probs = judge(folders["kink"], tmp_path, damage)["viewer datasets"]
    assert probs == [f"{rel}: its attribute jump of grid level1-broken-M1-delta0/crack points at "
                     "/cases/level1-broken-M1-delta0/crack/lambda (fields.h5), not "
                     "/cases/level1-broken-M1-delta0/crack/jump of its fields.h5"], probs
