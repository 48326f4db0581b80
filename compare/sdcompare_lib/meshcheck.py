"""The meshes are what the scene says: three checks of the meshes themselves,
which every other check takes on trust.

* **mesh size h** — each case's `h` in summary.json is the largest triangle diameter (the longest
  edge of a triangle: crates/sdcrack-core/src/mesh.rs `Mesh::h`, `diameter`) of the case's stored mesh, the arrays of
  fields.h5 / verification.h5 the errors are recomputed from; each reference's `h` is that of the
  mesh export it solved on (mesh/levelL). Same float64 coordinates, the same hypot and max: they
  can differ by the order of the max only, ~1e-16 relative; H_RTOL = 1e-12 leaves four orders
  and is eleven below a factor-2 slip (h written as 2h: the uniform rates are taken per halving
  of h, and a rate computed from the wrong h is wrong by the slip).
* **graded mesh law** — on a scene with `[discretization] grading = { beta = β, radius = R }`
  the triangles of every level follow the law of the mesher (crates/sdcrack-core/src/mesh/bisect.rs,
  crates/sdcrack-core/src/problem.rs `Grading::target`): with h_ℓ = h₀/2^ℓ (h₀ the largest diameter of the ungraded
  level 0), r_T the smallest distance of T's corners to a crack tip (the ends of every polyline of
  the scene copy) and the target
      t(h, r) = h · (min(max(r, r₀)/R, 1))^{1−β} for r < R, h beyond; r₀ = R (h/R)^{1/β},
  **upper bound**: every triangle has d_T ≤ t(h_ℓ, r_T) (1 + GRADED_UPPER_RTOL) — the mesher's
  own stopping rule (bisect.rs `grade`: it bisects, with closure, until no triangle has
  d_T > t (1 + 1e-12)); GRADED_UPPER_RTOL = 1e-9 adds the round-off of recomputing r and the
  powers here (the tolerance of the Rust unit test of the same property).
  **lower bound** (levels built from the structured grid of square cells, `cells` on a
  rectangle): the smallest triangle has d_min ≥ t(h_ℓ, 0)/√2 — the floor t(h_ℓ, 0) =
  h_ℓ (h_ℓ/R)^{(1−β)/β} (the tip elements' target, the smallest target anywhere) divided by one
  bisection. Derivation from the construction: the grid's triangles are right isosceles with their
  hypotenuse as refinement edge, shared by the two triangles of a cell (a compatible labelling),
  so every newest-vertex bisection halves the area and divides the diameter by exactly √2, and a
  triangle of generation g has d = h₀ 2^{−g/2}. A triangle is bisected (i) because it exceeds its
  target, which is ≥ the floor, so its children are > floor/√2; (ii) by the closure of such a
  bisection, which on compatibly labelled meshes bisects only triangles of a generation ≤ the
  marked one's, so its children are no finer than the marked one's; (iii) by the two uniform
  bisections that start a level, which halve every diameter while the floor falls by
  2^{1/β} ≥ 2 (β ≤ 1), so a level-(ℓ − 1) mesh within the bound gives a level-ℓ one within it
  before grading; level 0's ungraded triangles have d = h₀ ≥ the floor. On an unstructured
  level 0 (gmsh, a mesh file) the diameters of bisected triangles depend on their shapes
  (newest-vertex bisection keeps up to four shape classes per coarse triangle, and gmsh's own
  sizes vary), so no lower factor follows from the code alone: the upper bound is held there.
  A mesh graded with a larger β (β + 0.2, or 1 − β for β < 1/2) is coarser near the tips and
  fails the upper bound; one graded with a smaller β has smaller tip elements and fails the lower
  bound.
* **field files' mesh** — the field files a viewer opens (fields/*.xdmf, the state and series
  file of every case in summary.json) point at a triangle grid (Topology, Geometry) that is the
  case's stored mesh, array for array (exactly: the same float64 and int64 data); every stored
  mesh and every level of the mesh export is cut along the crack as the SCENE's polylines say
  (crackcut.py, from the scene copy's [geometry] and the mesh's coordinates alone, kinks and
  several cracks included): for the broken u (and the export) every interior crack node has the +
  copy, its original vertex number, and the − copy, one of the last I vertices in crack order
  (docs/design.md), and every triangle corner at it uses the copy of the face its triangle lies
  on (+ when left of the polyline walked from its first point: the wedge at a kink); the
  export's crack.txt lists the (+, −) copies, and with the mesh equal to the export's
  vertices.txt / triangles.txt (the cracked mesh the references solved on, written by another
  writer); for the continuous u one vertex per crack node; a tip has one vertex. The case's
  stored crack nodes and segments are the scene's; the crack polylines (fields/*.crack.xdmf)
  point at them, and each reference's fields/levelL.xdmf at the export's cracked mesh. A scene
  on a gmsh file of its own has its cracks in that file, which the folder does not keep: the
  stored crack (the export's for the export) stands in for the polylines there.
"""
import math
import os
import xml.etree.ElementTree as ET

import numpy as np

from . import exact as exact_mod
from . import crackcut, rates, theory
from .read import finite_number
from .cases import case_key, case_order
from .render import case_text

# summary.json's h and the stored mesh's largest diameter (module docstring).
H_RTOL = 1e-12
# d_T ≤ t(h_ℓ, r_T)(1 + GRADED_UPPER_RTOL): the mesher's 1e-12 and this tool's round-off.
GRADED_UPPER_RTOL = 1e-9
# d_min ≥ floor / GRADED_LOWER_FACTOR on the structured grid of square cells: one bisection.
GRADED_LOWER_FACTOR = math.sqrt(2.0)
# Square cells: the two sides of a cell agree to round-off.
SQUARE_RTOL = 1e-12


def checks(res, a):
    """The check rows (label, requirement, problems, not-applicable reason or None) of the three
    mesh checks (the references' own rates on graded meshes, once here, are refcheck.py's, with
    their rates on uniform meshes); measured values go to a["meshcheck"] (report.json's checks carry them in their
    requirement text)."""
    a["meshcheck"] = {}
    meshes = _MeshCache(res)
    return [h_check(res, a, meshes), graded_check(res, a, meshes),
            field_files_check(res, a, meshes)]


# ---------------------------------------------------------------- geometry
def diameters(points, tris):
    """(T,) the largest edge length of each triangle, as crates/sdcrack-core/src/mesh.rs `diameter`: hypot of each
    edge, the max of |p0 p1|, |p1 p2| and |p0 p2|."""
    X = np.asarray(points, dtype=float)[:, :2][np.asarray(tris, dtype=np.int64)]
    e01 = np.hypot(X[:, 0, 0] - X[:, 1, 0], X[:, 0, 1] - X[:, 1, 1])
    e12 = np.hypot(X[:, 1, 0] - X[:, 2, 0], X[:, 1, 1] - X[:, 2, 1])
    e02 = np.hypot(X[:, 0, 0] - X[:, 2, 0], X[:, 0, 1] - X[:, 2, 1])
    return np.maximum(np.maximum(e01, e12), e02)


def largest_diameter(points, tris):
    return float(diameters(points, tris).max()) if len(tris) else 0.0


def grading_target(h, r, beta, radius):
    """crates/sdcrack-core/src/problem.rs `Grading::target`, vectorised over r."""
    r = np.asarray(r, dtype=float)
    if beta >= 1.0:
        return np.full_like(r, h)
    r0 = radius * (h / radius) ** (1.0 / beta)
    t = h * np.minimum(np.maximum(r, r0) / radius, 1.0) ** (1.0 - beta)
    return np.where(r >= radius, h, t)


def tip_distances(points, tris, tips):
    """(T,) the smallest distance of a triangle's corners to a tip (bisect.rs `grade`)."""
    X = np.asarray(points, dtype=float)[:, :2][np.asarray(tris, dtype=np.int64)]
    r = np.full(len(X), np.inf)
    for tip in tips:
        d = np.hypot(X[..., 0] - tip[0], X[..., 1] - tip[1]).min(axis=1)
        r = np.minimum(r, d)
    return r


# ---------------------------------------------------------------- the stored meshes
class _MeshCache:
    """The stored mesh of each case (fields.h5 / verification.h5: res["data"], the arrays the
    errors are recomputed from), read once per mesh: its key (the dataset path, /meshes/KEY of
    sdcrack's layout) → (points, tris)."""

    def __init__(self, res):
        self.data = res["data"]
        self.by_key = {}
        self.key_of = {}

    def of_case(self, c):
        """(key, points, tris) of the case's stored mesh, or None without one."""
        grid = c.get("fields_grid")
        if self.data is None or not self.data.has_case(grid):
            return None
        if grid not in self.key_of:
            import h5py

            g = self.data.h5[f"cases/{grid}"]
            link = g.get("mesh", getlink=True)
            if isinstance(link, h5py.SoftLink) and link.path.startswith("/meshes/") \
                    and self.data.has_mesh(link.path[len("/meshes/"):]):
                key = link.path
                if key not in self.by_key:
                    self.by_key[key] = self.data.mesh_by_key(link.path[len("/meshes/"):])
            else:
                key = f"/cases/{grid}/mesh"
                if key not in self.by_key:
                    self.by_key[key] = (np.asarray(g["mesh/points"][()], dtype=float),
                                        np.asarray(g["mesh/triangles"][()], dtype=np.int64))
            self.key_of[grid] = key
        key = self.key_of[grid]
        return (key,) + self.by_key[key]

    def crack_of_case(self, c):
        """(crack points (I,2), segments (S,2)) stored with the case, or (None, None)."""
        grid = c.get("fields_grid")
        if self.data is None or not self.data.has_case(grid):
            return None, None
        g = self.data.h5[f"cases/{grid}"]
        if "crack/points" not in g:
            return None, None
        pts = np.asarray(g["crack/points"][()], dtype=float)[:, :2]
        segs = (np.asarray(g["crack/segments"][()], dtype=np.int64) if "crack/segments" in g
                else exact_mod.consecutive_segments(len(pts)))
        return pts, segs


def _export_levels(res):
    """{level: read.ExportLevel} of the mesh export (the references' meshes), any reference."""
    out = {}
    for ref in res["refs"].values():
        for lv, m in (ref.get("mesh") or {}).items():
            out.setdefault(int(lv), m)
    return out


def _rel(a, b):
    return abs(a - b) / max(abs(a), abs(b)) if max(abs(a), abs(b)) > 0 else 0.0


# ---------------------------------------------------------------- 1. h
def h_check(res, a, meshes):
    label = "mesh size h"
    what = (f"each case's h in summary.json is the largest triangle diameter (longest edge, "
            f"crates/sdcrack-core/src/mesh.rs) of its stored mesh, each reference's h that of the mesh it solved on, "
            f"to ≤ {H_RTOL:g} relative")
    largest = {}
    problems, worst, n, unmeasured = [], 0.0, 0, []
    bad = {}
    for c in sorted(res["summary"]["cases"], key=case_order):
        m = meshes.of_case(c)
        if m is None:
            unmeasured.append(c)
            continue
        key, pts, tris = m
        if key not in largest:
            largest[key] = largest_diameter(pts, tris)
        H = largest[key]
        h = c.get("h")
        n += 1
        if not finite_number(h):
            bad.setdefault((int(c["level"]), key), []).append((c, h, H, math.inf))
            continue
        rel = _rel(float(h), H)
        worst = max(worst, rel)
        if not rel <= H_RTOL:
            bad.setdefault((int(c["level"]), key), []).append((c, h, H, rel))
    for (lv, key), rows in sorted(bad.items()):
        c, h, H, rel = rows[0]
        problems.append(f"{case_text(case_key(c))}: summary.json's h = {h!r} but its stored mesh "
                        f"({key}) has largest triangle diameter {H:.17g} (relative difference "
                        f"{rel:.1e} > {H_RTOL:g}; {len(rows)} case(s) of this mesh)")
    nref = 0
    for tool, ref in sorted(res["refs"].items()):
        for c in ref["summary"].get("cases", []):
            lv = int(c.get("level", -1))
            m = (ref.get("mesh") or {}).get(lv)
            if m is None:
                continue  # completeness reports a level the export lacks
            ekey = ("export", lv)
            if ekey not in largest:
                largest[ekey] = largest_diameter(m.points, m.tris)
            H, h = largest[ekey], c.get("h")
            nref += 1
            rel = _rel(float(h), H) if finite_number(h) else math.inf
            worst = max(worst, rel)
            if not rel <= H_RTOL:
                problems.append(f"reference {tool} level {lv}: its h = {h!r} but the mesh it "
                                f"solved on (mesh/level{lv}) has largest triangle diameter "
                                f"{H:.17g} (relative difference {rel:.1e} > {H_RTOL:g})")
    if n == 0 and nref == 0:
        return label, what, [], ("no stored mesh (fields.h5 / verification.h5) and no mesh "
                                 "export to measure h on")
    if unmeasured and n:
        problems.append(f"{len(unmeasured)} case(s) have no stored mesh to measure h on, e.g. "
                        f"{case_text(case_key(unmeasured[0]))}")
    a["meshcheck"]["h"] = {"cases": n, "reference_cases": nref,
                           "largest_relative_difference": worst}
    return (label, what + f" ({n} cases, {nref} reference cases; largest difference {worst:.1e})",
            problems, None)


# ---------------------------------------------------------------- 2. graded levels
def grading(scene_file):
    """(β, R) of the scene's [discretization] grading, or None."""
    d = scene_file.get("discretization")
    g = d.get("grading") if isinstance(d, dict) else None
    if not isinstance(g, dict):
        return None
    try:
        return float(g["beta"]), float(g["radius"])
    except (KeyError, TypeError, ValueError):
        return None


def _structured_square_h0(scene_file):
    """h₀ of the structured grid (`cells` on a rectangle): the diagonal of a cell, and whether the
    cells are square; None for an unstructured level 0."""
    d = scene_file.get("discretization") or {}
    dom = (scene_file.get("geometry") or {}).get("domain") or {}
    cells, rect = d.get("cells"), dom.get("rectangle") if isinstance(dom, dict) else None
    if cells is None or rect is None:
        return None
    try:
        (x0, y0), (x1, y1) = rect
        nx, ny = cells
        dx, dy = (float(x1) - float(x0)) / int(nx), (float(y1) - float(y0)) / int(ny)
    except (TypeError, ValueError):
        return None
    return math.hypot(dx, dy), abs(dx - dy) <= SQUARE_RTOL * max(abs(dx), abs(dy))


def graded_check(res, a, meshes):
    label = "graded mesh law"
    sf = res["scene_file"]
    law = grading(sf)
    what = ("every triangle of every level within the grading law of the mesher: d_T ≤ "
            "h_ℓ (r_T/R)^(1−β) (floored at r₀ = R (h_ℓ/R)^(1/β), h_ℓ beyond R; crates/sdcrack-core/src/mesh/bisect.rs) "
            f"× (1 + {GRADED_UPPER_RTOL:g})")
    if law is None:
        return label, what, [], "the scene has no [discretization] grading (uniform levels)"
    beta, radius = law
    if beta >= 1.0:
        return label, what, [], "β = 1: the mesher's levels are uniform (no grading)"
    try:
        tips = [p for c in exact_mod.scene_cracks(sf) for p in (c[0], c[-1])]
    except exact_mod.ExactError:
        tips = []
    if not tips:
        return label, what, ["the scene copy has no crack tips to grade towards"], None
    per_level = {}
    for c in sorted(res["summary"]["cases"], key=lambda c: (int(c["level"]),
                                                            c.get("u_space") != "broken")):
        lv = int(c["level"])
        if lv in per_level:
            continue
        m = meshes.of_case(c)
        if m is not None:
            per_level[lv] = m
    if not per_level:
        exported = _export_levels(res)
        per_level = {lv: (f"mesh/level{lv}", m.points, m.tris) for lv, m in exported.items()}
    if not per_level:
        return label, what, ["could not run: no stored mesh of any level"], None
    largest = {lv: largest_diameter(p, t) for lv, (_, p, t) in per_level.items()}
    structured = _structured_square_h0(sf)
    if structured is not None:
        h0, square = structured
        h0_from = "the diagonal of a level-0 cell"
    else:
        # the largest diameter of level ℓ is h₀/2^ℓ where a triangle of the coarse mesh's largest
        # diameter keeps it (level 0 is the coarse mesh whenever h₀ ≥ R: the target is h₀ there)
        h0, square = max(2.0 ** lv * H for lv, H in largest.items()), False
        h0_from = "max over levels of 2^ℓ × the largest diameter"
    problems, rows = [], []
    for lv, (key, pts, tris) in sorted(per_level.items()):
        h = h0 / 2.0 ** lv
        d = diameters(pts, tris)
        r = tip_distances(pts, tris, tips)
        t = grading_target(h, r, beta, radius)
        q = d / t
        floor = float(grading_target(h, np.array([0.0]), beta, radius)[0])
        row = {"level": lv, "triangles": int(len(tris)), "h": h, "floor": floor,
               "max_ratio": float(q.max()), "min_ratio": float(q.min()),
               "smallest_over_floor": float(d.min() / floor)}
        rows.append(row)
        over = np.flatnonzero(q > 1.0 + GRADED_UPPER_RTOL)
        if len(over):
            k = over[np.argmax(q[over])]
            problems.append(f"level {lv}: {len(over)} of {len(tris)} triangles exceed the "
                            f"grading target, e.g. diameter {d[k]:.4g} at distance {r[k]:.4g} from "
                            f"a tip where the law (β = {beta:g}, R = {radius:g}, h = {h:.4g}) "
                            f"allows {t[k]:.4g} (ratio {q[k]:.3g} > 1): coarser than the scene's "
                            "grading")
        if square and not d.min() >= floor / GRADED_LOWER_FACTOR * (1.0 - GRADED_UPPER_RTOL):
            k = int(np.argmin(d))
            problems.append(f"level {lv}: the smallest triangle has diameter {d[k]:.4g} < the "
                            f"floor {floor:.4g} / √2 = {floor / GRADED_LOWER_FACTOR:.4g} of the "
                            "law "
                            f"(β = {beta:g}, R = {radius:g}, h = {h:.4g}; at distance {r[k]:.3g} "
                            "from a tip): finer than the scene's grading")
    a["meshcheck"]["graded"] = {"beta": beta, "radius": radius, "h0": h0, "levels": rows,
                                "lower_bound": bool(square)}
    ratio = (f"; measured d_T / target {min(r['min_ratio'] for r in rows):.3g} to "
             f"{max(r['max_ratio'] for r in rows):.6g}")
    lower = (f"; and the smallest triangle ≥ the tip floor h_ℓ (h_ℓ/R)^((1−β)/β) / √2 (one "
             f"bisection of the structured grid's right isosceles triangles; measured "
             f"{min(r['smallest_over_floor'] for r in rows):.3g} × the floor)" if square else
             "; no lower bound on an unstructured or non-square level 0 (the bisected triangles' "
             "diameters depend on their shapes)")
    return (label, what + f" (β = {beta:g}, R = {radius:g}, h₀ = {h0:.6g} from {h0_from}, "
            f"{len(rows)} level(s){ratio}{lower})", problems, None)


# ---------------------------------------------------------------- 4. field files
class _Xdmf:
    """The uniform grids of an XDMF file: name → {"topology": (h5 file, dataset, dims, n),
    "geometry": (...), "attributes": {name: dims}, "links": {name: (h5 file, dataset, dims) or
    None}}; a file that cannot be read: error text."""

    def __init__(self, path):
        self.path = path
        self.grids = {}
        self.error = None
        try:
            root = ET.parse(path).getroot()
        except (OSError, ET.ParseError) as exc:
            self.error = f"cannot read {os.path.basename(path)}: {exc}"
            return
        for g in root.iter("Grid"):
            if g.get("GridType", "Uniform") != "Uniform":
                continue
            entry = {"attributes": {}, "links": {}}
            for tag in ("Topology", "Geometry"):
                el = g.find(tag)
                item = el.find("DataItem") if el is not None else None
                entry[tag.lower()] = (self._ref(item), el.get("NumberOfElements")
                                      if el is not None else None)
            for at in g.findall("Attribute"):
                item = at.find("DataItem")
                entry["attributes"][at.get("Name")] = (item.get("Dimensions") if item is not None
                                                       else None)
                entry["links"][at.get("Name")] = self._ref(item)
            self.grids[g.get("Name")] = entry

    def _ref(self, item):
        """(absolute h5 path, dataset path, Dimensions) of an HDF DataItem, or None."""
        text = item.text if item is not None else None
        if item is None or (item.get("Format") or "").upper() != "HDF" or ":" not in (text or ""):
            return None
        file_part, ds = item.text.strip().rsplit(":", 1)
        return (os.path.normpath(os.path.abspath(os.path.join(os.path.dirname(self.path),
                                                              file_part))), ds,
                item.get("Dimensions"))


class _H5Arrays:
    """Datasets of the HDF5 files XDMF files name, read once."""

    def __init__(self):
        self.files, self.arrays = {}, {}

    def get(self, h5path, ds):
        key = (h5path, ds)
        if key not in self.arrays:
            import h5py

            try:
                if h5path not in self.files:
                    self.files[h5path] = h5py.File(h5path, "r")
                self.arrays[key] = np.asarray(self.files[h5path][ds][()])
            except (OSError, KeyError) as exc:
                self.arrays[key] = exc
        return self.arrays[key]

    def known(self, h5path, key, points, tris):
        """The arrays of datasets KEY/points and KEY/triangles of `h5path`, already read."""
        h5path = os.path.normpath(os.path.abspath(h5path))
        self.arrays.setdefault((h5path, f"{key}/points"), points)
        self.arrays.setdefault((h5path, f"{key}/triangles"), tris)

    def close(self):
        for f in self.files.values():
            f.close()


def _dims(text):
    try:
        return tuple(int(x) for x in (text or "").split())
    except ValueError:
        return None


def field_files_check(res, a, meshes):
    label = "field files' mesh"
    what = ("the triangle grid of every case's field files (fields/*.xdmf) is its stored mesh, "
            "array for array; every stored mesh and every exported level is cut along the scene's "
            "polylines as its u space says (broken u: each interior crack node's + copy, the "
            "original vertex, on the + face left of the polyline, its − copy, one of the last "
            "vertices in crack order, on the − face, as the mesh export's crack.txt lists them; "
            "continuous u: one vertex)")
    folder = res["folder"]
    cases = sorted(res["summary"]["cases"], key=case_order)
    exported = _export_levels(res)
    problems = []
    files = {}
    arrays = _H5Arrays()
    compared = {}
    cut_checked = {}
    n_files = n_meshes = 0

    def xdmf(rel):
        path = os.path.normpath(os.path.join(folder, rel))
        if path not in files:
            files[path] = _Xdmf(path) if os.path.exists(path) else None
        return files[path]

    def scene_crack(pts, stored):
        """The scene's crack nodes on this mesh (crackcut; `stored` the crack that stands in for
        the polylines of a scene on a mesh file), or the problem text."""
        try:
            return crackcut.SceneCrack.of_scene(res["scene_file"], pts, stored)
        except exact_mod.ExactError as exc:
            return str(exc)

    def check_cut(key, pts, tris, c, where):
        """The cut of one mesh against the scene's polylines (once per mesh), and the case's
        stored crack nodes against the scene's: problems prefixed with `where`."""
        if key in cut_checked:
            return
        cp, segs = meshes.crack_of_case(c)
        sc = scene_crack(pts, None if cp is None else (cp, segs))
        if isinstance(sc, str):
            cut_checked[key] = [sc]
            problems.append(f"{where}: {sc}")
            return
        if not len(sc.xy):
            cut_checked[key] = []
            return
        lv = int(c["level"])
        broken = c.get("u_space") == "broken"
        m = exported.get(lv)
        pairs = (m.crack if broken and m is not None and m.points.shape[0] == len(pts)
                 and np.array_equal(m.points[:, :2], pts[:, :2]) else None)
        found = crackcut.cut_problems(sc, pts, tris, broken, pairs)
        if cp is not None and not (np.array_equal(cp[:, :2], sc.xy)
                                   and np.array_equal(segs, sc.segments)):
            found.append("the case's crack polylines (crack/points, crack/segments) are not the "
                         f"scene's crack nodes in crack order ({len(cp)} stored, {len(sc.xy)} "
                         "from the scene's polylines on this mesh)")
        cut_checked[key] = found
        problems.extend(f"{where}: {p}" for p in found)

    try:
        for c in cases:
            m = meshes.of_case(c)
            lv, u = int(c["level"]), c.get("u_space")
            if m is not None:
                key, pts, tris = m
                if key.startswith("/meshes/"):
                    # a field file pointing at this very dataset reads these arrays
                    arrays.known(res["data"].path, key, pts, tris)
                # the stored mesh against the mesh export (another writer), once per mesh
                em = exported.get(lv)
                if u == "broken" and em is not None and ("export", key) not in compared:
                    same = (em.points.shape[0] == len(pts)
                            and np.array_equal(em.points[:, :2], pts[:, :2])
                            and np.array_equal(em.tris, tris))
                    compared[("export", key)] = same
                    n_meshes += 1
                    if not same:
                        problems.append(f"level {lv} broken: the stored mesh ({key}) is not the "
                                        f"mesh export's mesh/level{lv} (vertices.txt, "
                                        "triangles.txt) the references solved on")
                check_cut(key, pts, tris, c, f"level {lv} {u} ({key})")
            for field in ("fields_state", "fields_series"):
                rel = c.get(field)
                if not isinstance(rel, str):
                    continue
                x = xdmf(rel)
                what_case = f"{rel} ({case_text(case_key(c))})"
                if x is None:
                    problems.append(f"{what_case}: the field file named in summary.json is missing")
                    continue
                if x.error:
                    problems.append(f"{what_case}: {x.error}")
                    continue
                g = x.grids.get(c.get("fields_grid"))
                if g is None:
                    problems.append(f"{what_case}: no grid {c.get('fields_grid')!r} in it")
                    continue
                n_files += 1
                problems.extend(f"{what_case}: {p}" for p in
                                _grid_problems(g, m, arrays, compared, res, c))
                if field == "fields_state":
                    crack_rel = (rel[:-len(".xdmf")] + ".crack.xdmf" if rel.endswith(".xdmf")
                                 else None)
                    cx = xdmf(crack_rel) if crack_rel else None
                    if cx is not None and not cx.error:
                        cg = cx.grids.get(f"{c.get('fields_grid')}/crack")
                        if cg is not None:
                            problems.extend(f"{crack_rel}: {p}" for p in
                                            _crack_grid_problems(cg, meshes, arrays, c))
        for lv, em in sorted(exported.items()):
            # the mesh export the references solve on: cut as the scene says, whatever u the
            # solver ran (a scene of continuous u only has no stored broken mesh)
            sc = scene_crack(em.points, (em.points[em.crack[:, 0]], em.segments()))
            found = ([sc] if isinstance(sc, str) else
                     crackcut.cut_problems(sc, em.points, em.tris, True, em.crack)
                     if len(sc.xy) else [])
            cut_checked[("export", lv)] = found
            problems.extend(f"mesh/level{lv} (the mesh export): {p}" for p in found)
        for tool, ref in sorted(res["refs"].items()):
            for lv, em in sorted((ref.get("mesh") or {}).items()):
                rel = os.path.join(tool, "fields", f"level{lv}.xdmf")
                x = xdmf(rel)
                if x is None or x.error:
                    continue
                g = x.grids.get(f"level{lv}")
                if g is None:
                    continue
                n_files += 1
                got = _grid_arrays(g, arrays)
                if isinstance(got, str):
                    problems.append(f"{rel}: {got}")
                elif not (got[0].shape[0] == len(em.points)
                          and np.array_equal(got[0][:, :2], em.points[:, :2])
                          and np.array_equal(got[1], em.tris)):
                    problems.append(f"{rel}: its triangle grid is not the mesh export's "
                                    f"mesh/level{lv} the reference solved on")
    finally:
        arrays.close()
    if not cut_checked and not n_files and not n_meshes:
        return label, what, [], "no stored mesh and no field files"
    a["meshcheck"]["field_files"] = {"grids": n_files, "meshes_cut_checked": len(cut_checked),
                                     "meshes_against_export": n_meshes}
    # one line per kind of problem (a bug repeats in every case of a mesh): the first, with a count
    return (label, what + f" ({n_files} field-file grids, {len(cut_checked)} stored meshes, "
            f"{n_meshes} against the export)", _fold(problems), None)


def _fold(problems, keep=20):
    """At most `keep` problem lines, then one line with the number left out."""
    if len(problems) <= keep:
        return problems
    return problems[:keep] + [f"… and {len(problems) - keep} more of the same kinds"]


def _grid_arrays(g, arrays):
    """(points, triangles) the grid's Topology and Geometry point at, or a problem text."""
    topo, geo = g.get("topology"), g.get("geometry")
    if topo is None or topo[0] is None or geo is None or geo[0] is None:
        return "its Topology or Geometry is not an HDF DataItem"
    T = arrays.get(*topo[0][:2])
    P = arrays.get(*geo[0][:2])
    for arr, ref in ((T, topo[0]), (P, geo[0])):
        if isinstance(arr, Exception):
            return f"cannot read {os.path.basename(ref[0])}:{ref[1]} ({arr})"
    if T.ndim != 2 or T.shape[1] != 3 or P.ndim != 2 or P.shape[1] < 2:
        return f"its topology {T.shape} or geometry {P.shape} is not a triangle grid"
    for arr, ref in ((T, topo[0]), (P, geo[0])):
        if _dims(ref[2]) != arr.shape:
            return (f"its DataItem Dimensions {ref[2]!r} are not the shape {arr.shape} of "
                    f"{ref[1]}")
    if topo[1] is not None and _dims(topo[1]) != (T.shape[0],):
        return f"NumberOfElements {topo[1]} ≠ {T.shape[0]} triangles"
    if len(T) and (T.min() < 0 or T.max() >= len(P)):
        return "its triangles name vertices outside the geometry"
    return P, T


def _grid_problems(g, stored, arrays, compared, res, c):
    """Problems of one case's grid in a field file against the case's stored mesh."""
    got = _grid_arrays(g, arrays)
    if isinstance(got, str):
        return [got]
    P, T = got
    out = []
    n = len(P)
    for name, dims in g["attributes"].items():
        d = _dims(dims)
        if d is not None and d[:1] != (n,):
            out.append(f"its attribute {name} has {d[0] if d else 0} values for {n} vertices")
    if stored is None:
        return out + ["the case has no stored mesh (fields.h5 / verification.h5) to compare "
                      "its grid with"]
    key, pts, tris = stored
    ck = (g["topology"][0][:2], g["geometry"][0][:2], key)
    if ck not in compared:
        data = res["data"]
        same_ds = (data is not None
                   and os.path.normpath(os.path.abspath(data.path)) == g["topology"][0][0]
                   and g["geometry"][0][0] == g["topology"][0][0]
                   and g["topology"][0][1] == f"{key}/triangles"
                   and g["geometry"][0][1] == f"{key}/points")
        if same_ds:
            compared[ck] = []
        else:
            bad = []
            if P.shape != pts.shape or not np.array_equal(P, pts):
                bad.append(f"its geometry ({g['geometry'][0][1]}, {P.shape[0]} vertices) is not "
                           f"the case's stored vertices ({key}, {pts.shape[0]})")
            if T.shape != tris.shape or not np.array_equal(T, tris):
                rows = (int(np.sum(np.any(T != tris, axis=1))) if T.shape == tris.shape
                        else None)
                bad.append(f"its triangles ({g['topology'][0][1]}) are not the case's stored "
                           f"triangles ({key}"
                           + (f"; {rows} of {len(tris)} rows differ" if rows is not None else
                              f"; {len(T)} against {len(tris)} triangles") + ")")
            compared[ck] = bad
    return out + compared[ck]


def _crack_grid_problems(g, meshes, arrays, c):
    """The crack polylines of a case's field file against its stored crack nodes and segments."""
    topo, geo = g.get("topology"), g.get("geometry")
    if topo is None or topo[0] is None or geo is None or geo[0] is None:
        return ["its crack Topology or Geometry is not an HDF DataItem"]
    S, P = arrays.get(*topo[0][:2]), arrays.get(*geo[0][:2])
    if isinstance(S, Exception) or isinstance(P, Exception):
        return ["cannot read its crack datasets"]
    cp, segs = meshes.crack_of_case(c)
    if cp is None:
        return []
    if P.ndim != 2 or P.shape[0] != len(cp) or not np.array_equal(P[:, :2], cp) \
            or S.shape != segs.shape or not np.array_equal(S, segs):
        return ["its crack polylines are not the case's stored crack nodes and segments"]
    return []
