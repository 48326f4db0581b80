"""The elastic references' field files — what a viewer opens — against the outputs every other
check of the elastic verdict reads (docs/elasticity.md): the check "viewer datasets".

The other checks read u_level{L}.txt and crack_level{L}.txt and recompute σ(u_h) themselves, so
without this check a reference could write any stress, any crack field or another mesh into
fields.h5 and the verdict would still PASS (tools/mutants.toml's
dolfinx-elastic-shear-stress-halved did). Per reference that wrote fields.h5 (`[outputs] fields =
["u"]`) and per level it has a case of:

* the grids a viewer opens: every attribute NAME of a grid G of <tool>/fields/*.xdmf points at
  /cases/G/NAME of its fields.h5, which holds it (crackcheck._attribute_links, the scalar check's),
  and the grid level{L} of fields/level{L}.xdmf has its topology at /meshes/level{L}/triangles and
  its geometry at /meshes/level{L}/points, the grid level{L}/crack of fields/level{L}.crack.xdmf at
  /cases/level{L}/crack/segments and /points;
* the mesh: /meshes/level{L}/points are the export's vertices with z = 0 and /triangles its
  triangles; /cases/level{L}/crack/points the crack rows' + copies, /segments the row pairs within
  each crack (bit for bit: the reference copies them);
* u: /cases/level{L}/u is u_level{L}.txt with u_z = 0, bit for bit (the text is written with
  %.17g, which reads back exactly);
* the crack fields: /cases/level{L}/crack/opening, slip, contact_force, active are the columns of
  crack_level{L}.txt, bit for bit (the reference writes one array to both);
* the stress: /cases/level{L}/stress (T, 3) is σ(u_h) = λ* tr ε I + 2μ ε of the P1 gradient of
  that u per triangle, (σ_xx, σ_yy, σ_xy), recomputed here (elastic_exact.hooke of
  elastic_exact.p1_gradients) to STRESS_ROUNDOFF × (2|λ*| + 2μ) × (‖∇u_h‖∞ +
  ‖u‖∞ max_T d_T/|det_T|): a P1 gradient from float64 values carries an absolute error of a few
  ε ‖u‖∞ / height per triangle (height ~ |det_T| / d_T) and a few ε of itself, and each stress
  component sums at most (2|λ*| + 2μ) times a gradient entry; 64 ε covers both codes' orders of
  operations (the same allowance as the scalar check's p). A wrong factor of a component
  (σ_xy = μ ε_xy) is O(‖σ‖). Measured on 2026-11-28 on every repository elastic scene (levels
  0–4, both references): the largest difference is 0.006 of the tolerance (GetFEM's; ≤ 0.0024 on
  the others), ≤ 5.6e-15 of max |σ(u_h)|.
"""
import os

import numpy as np

from . import crackcheck, elastic_exact, meshcheck

EPS = float(np.finfo(float).eps)
STRESS_ROUNDOFF = 64 * EPS
CRACK_COLUMNS = ("opening", "slip", "contact_force", "active")  # crack_level{L}.txt's columns


def viewer_datasets(res):
    """(requirement, problems, not-applicable reason or None) of the check."""
    what = ("each reference's field files (fields.h5, fields/*.xdmf) hold its own outputs: the "
            "grids link the datasets they name, the mesh is the export's, u and the crack fields "
            "are each level's u_level*.txt and crack_level*.txt bit for bit, the stress is σ(u_h) of that u "
            f"(recomputed here, to {STRESS_ROUNDOFF / EPS:g} ε round-off)")
    tools = [t for t in sorted(res["refs"])
             if os.path.exists(os.path.join(res["folder"], t, "fields.h5"))]
    if not tools:
        return what, [], "no reference wrote field files ([outputs] fields = [])"
    problems = []
    crackcheck._attribute_links(res, problems)
    n = 0
    for tool in tools:
        n += _reference_files(res, tool, problems)
    return what + f" ({len(tools)} reference(s), {n} level(s))", problems, None


def _reference_files(res, tool, problems):
    """Appends the problems of one reference's fields.h5 and XDMF grids; the levels checked."""
    import h5py

    folder = os.path.join(res["folder"], tool)
    material = res["mesh_scene"]["problem"]
    by_level = res["refs"][tool][1]
    n = 0
    try:
        h5 = h5py.File(os.path.join(folder, "fields.h5"), "r")
    except OSError as exc:
        problems.append(f"{tool}/fields.h5: cannot read it ({exc})")
        return 0
    with h5:
        for L, ref in sorted(by_level.items()):
            n += 1
            where = f"{tool}/fields.h5 level {L}"
            level = res["levels"][L]
            _grid_links(folder, tool, L, problems)
            got = {}
            for path in (f"meshes/level{L}/points", f"meshes/level{L}/triangles",
                         f"cases/level{L}/u", f"cases/level{L}/stress",
                         f"cases/level{L}/crack/points", f"cases/level{L}/crack/segments",
                         *(f"cases/level{L}/crack/{c}" for c in CRACK_COLUMNS)):
                if path not in h5:
                    problems.append(f"{where}: no dataset /{path}")
                    continue
                got[path] = np.asarray(h5[path][()])
            expected = {
                f"meshes/level{L}/points": _with_z(level.points),
                f"meshes/level{L}/triangles": level.triangles,
                f"cases/level{L}/u": _with_z(ref.u),
                f"cases/level{L}/crack/points": _with_z(level.nodes()),
                f"cases/level{L}/crack/segments": level.segments(),
                **{f"cases/level{L}/crack/{c}": ref.crack[:, k]
                   for k, c in enumerate(CRACK_COLUMNS)}}
            for path, want in expected.items():
                if path in got:
                    _same(where, path, got[path], want, problems)
            if f"cases/level{L}/stress" in got:
                _stress(where, got[f"cases/level{L}/stress"], level, ref.u, material, problems)
    return n


def _with_z(a):
    return np.column_stack([a, np.zeros(len(a))])


def _same(where, path, got, want, problems):
    """Bit for bit (shape and every value; NaN never equals)."""
    if got.shape != want.shape:
        problems.append(f"{where}: /{path} has shape {got.shape}, its source {want.shape}")
        return
    differ = got != want
    if differ.any():
        k = np.flatnonzero(differ.reshape(len(want), -1).any(axis=1))[0]
        problems.append(f"{where}: /{path} differs from its source at {int(differ.sum())} "
                        f"value(s) (first row {k}: {got[k]} ≠ {want[k]})")


def stress_tolerance(level, u, grad, material):
    """STRESS_ROUNDOFF × (2|λ*| + 2μ) × (‖∇u_h‖∞ + ‖u‖∞ max_T d_T/|det_T|) (module text)."""
    X = level.points[level.triangles]
    e1, e2 = X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]
    det = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    d = np.max([np.hypot(*(X[:, i] - X[:, (i + 1) % 3]).T) for i in range(3)], axis=0)
    ratio = float((d / det).max(initial=0.0))
    stiff = 2 * abs(material["lambda_in_plane"]) + 2 * material["mu"]
    return STRESS_ROUNDOFF * stiff * (float(np.abs(grad).max(initial=0.0))
                                      + float(np.abs(u).max(initial=0.0)) * ratio)


def _stress(where, got, level, u, material, problems):
    grad = elastic_exact.p1_gradients(level.points, level.triangles, u)
    want = elastic_exact.hooke(grad, material)
    if got.shape != want.shape:
        problems.append(f"{where}: /stress has shape {got.shape}, σ(u_h) {want.shape} (one "
                        "(σ_xx, σ_yy, σ_xy) per triangle)")
        return
    tol = stress_tolerance(level, u, grad, material)
    diff = np.abs(got - want)
    bad = ~(diff <= tol)  # a NaN is bad
    if bad.any():
        t, c = (int(v) for v in np.argwhere(bad)[0])
        problems.append(f"{where}: stress is not σ(u_h) of its u at {int(bad.any(axis=1).sum())} "
                        f"triangle(s) (first triangle {t}: {('σ_xx', 'σ_yy', 'σ_xy')[c]} "
                        f"{got[t, c]:.6g}, σ(u_h) {want[t, c]:.6g}; tolerance {tol:.2e})")


def _grid_links(folder, tool, L, problems):
    """The topology and geometry of both grids of level L point at the datasets the module text
    names, in the reference's fields.h5 (the attributes are crackcheck._attribute_links')."""
    h5 = os.path.normpath(os.path.abspath(os.path.join(folder, "fields.h5")))
    for fname, grid, topo, geo in (
            (f"level{L}.xdmf", f"level{L}", f"/meshes/level{L}/triangles",
             f"/meshes/level{L}/points"),
            (f"level{L}.crack.xdmf", f"level{L}/crack", f"/cases/level{L}/crack/segments",
             f"/cases/level{L}/crack/points")):
        path = os.path.join(folder, "fields", fname)
        rel = f"{tool}/fields/{fname}"
        if not os.path.exists(path):
            problems.append(f"{rel}: missing (the field files hold one per level)")
            continue
        x = meshcheck._Xdmf(path)
        if x.error:
            problems.append(f"{rel}: {x.error}")
            continue
        entry = x.grids.get(grid)
        if entry is None:
            problems.append(f"{rel}: no grid {grid}")
            continue
        for tag, want in (("topology", topo), ("geometry", geo)):
            link = entry[tag][0]
            if link is None or link[0] != h5 or link[1] != want:
                problems.append(f"{rel}: the {tag} of grid {grid} points at "
                                f"{'no HDF5 dataset' if link is None else link[1]}, not {want} "
                                "of its fields.h5")
