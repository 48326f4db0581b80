"""Reading the results folder of an elastic scene (docs/elasticity.md): OUT/<scene>/ with
summary.json ("problem": "elasticity"), the scene copy scene.toml, the mesh export mesh/ and the
references' outputs <tool>/ (summary.json, u_level{L}.txt, crack_level{L}.txt).

Every malformed or missing file is read.InputError (exit 2), one line naming the file. The mesh
export's crack files (crack.txt, cracks.txt with its tip flags, crack_normals.txt) are read and
checked by compare/sdshared/sdexport.py, as both references read them.
"""
import json
import os
from dataclasses import dataclass

import numpy as np

from sdshared import sdexport

from . import elastic_sdm
from .read import REFERENCE_TOOLS, InputError, load_json, load_scene_copy

PROBLEM = "elasticity"
REFERENCE_CRACK_COLUMNS = ("opening", "slip", "contact_force", "active")


def is_elastic(folder):
    """True when folder/summary.json names the elastic problem (a scalar summary has no
    "problem" key, or "scalar"); False for anything else, including a folder this cannot read
    (the scalar pipeline then reports it)."""
    try:
        with open(os.path.join(folder, "summary.json"), encoding="utf-8") as fh:
            doc = json.load(fh)
    except (OSError, ValueError):
        return False
    return isinstance(doc, dict) and doc.get("problem") == PROBLEM


@dataclass
class Level:
    """One level of the mesh export: the cracked mesh (points (N, 2), triangles (T, 3)), the crack
    rows (pairs (I, 2) = crack.txt's plus, minus), the cracks (ranges [(first, n)]), which crack
    ends are tips (tip_ends [(first is tip, last is tip)]), the nodal normals (I, 2) and the kind
    of mesh (mesh.json)."""

    level: int
    points: np.ndarray
    triangles: np.ndarray
    pairs: np.ndarray
    ranges: list
    tip_ends: list
    normals: np.ndarray
    kind: str

    def layout(self):
        """The crack rows as sdexport's CrackLayout (tips, mouths, doubled rows)."""
        return sdexport.CrackLayout(pairs=self.pairs, ranges=self.ranges, normals=self.normals,
                                    ends=self.tip_ends)

    def tip_rows(self):
        """The rows of crack.txt that are tips, in docs/elasticity.md's order: per crack its
        first-point end, then its last-point end, mouths skipped."""
        return self.layout().tip_rows()

    def mouth_rows(self):
        return self.layout().mouth_rows()

    def pair_rows(self):
        """(I,) bool: the rows whose node has two copies (every row that is not a tip)."""
        return self.layout().interior()

    def segments(self):
        """(S, 2) the row pairs [k, k+1] within each crack."""
        parts = [np.column_stack([np.arange(f, f + n - 1), np.arange(f + 1, f + n)])
                 for f, n in self.ranges]
        return np.concatenate(parts).astype(np.int64)

    def nodes(self):
        return self.points[self.pairs[:, 0]]

    def nodal_measure(self):
        """(I,) m_j: half the sum of the lengths of the crack segments at row j."""
        seg = self.segments()
        c = self.nodes()
        ell = np.hypot(*(c[seg[:, 1]] - c[seg[:, 0]]).T)
        m = np.zeros(len(self.pairs))
        np.add.at(m, seg[:, 0], 0.5 * ell)
        np.add.at(m, seg[:, 1], 0.5 * ell)
        return m

    def tip_frames(self):
        """[(tip point (2,), e1 (2,))] per tip in tip order: e1 along the crack's last segment at
        the tip, pointing ahead of it (docs/elasticity.md, Tips and mouths)."""
        c = self.nodes()
        out = []
        for (first, n), (tf, tl) in zip(self.ranges, self.tip_ends):
            for is_tip, row, prev in ((tf, first, first + 1), (tl, first + n - 1, first + n - 2)):
                if is_tip:
                    d = c[row] - c[prev]
                    out.append((c[row], d / np.hypot(*d)))
        return out


def _table(path, dtype, ncols_allowed):
    if not os.path.exists(path):
        raise InputError(f"missing file: {path}")
    try:
        a = np.loadtxt(path, dtype=dtype, ndmin=2)
    except ValueError as exc:
        raise InputError(f"cannot read {path}: {exc}".replace("\n", " "))
    if a.size and a.shape[1] not in ncols_allowed:
        raise InputError(f"{path}: expected {' or '.join(map(str, ncols_allowed))} columns, found "
                         f"{a.shape[1]}")
    return a


def read_level(export, level):
    """The Level of export/level{L}/, checked: indices in range, the crack layout by sdexport
    (tips with plus == minus, every other row with plus != minus, unit normals), each row's two
    copies at the same point."""
    d = os.path.join(export, f"level{level}")
    pts = _table(os.path.join(d, "vertices.txt"), float, (2, 3))[:, :2]
    tris = _table(os.path.join(d, "triangles.txt"), np.int64, (3,))
    n = len(pts)
    for name, a in (("triangles.txt", tris),):
        if a.size and (a.min() < 0 or a.max() >= n):
            raise InputError(f"{os.path.join(d, name)}: vertex index out of range 0..{n - 1}")
    try:
        layout = sdexport.read_layout(d, pts, n)
    except sdexport.ExportError as exc:
        raise InputError(str(exc)) from None
    meta_path = os.path.join(d, "mesh.json")
    meta = load_json(meta_path) if os.path.exists(meta_path) else {}
    lv = Level(level, pts, tris, layout.pairs, layout.ranges, layout.crack_ends(), layout.normals,
               meta.get("kind", "structured"))
    pairs = layout.pairs
    if np.abs(pts[pairs[:, 0]] - pts[pairs[:, 1]]).max(initial=0) > 0:
        raise InputError(f"{d}/crack.txt: the + and − copies of a row lie at different points")
    return lv


@dataclass
class ReferenceLevel:
    """A reference's outputs at one level: its summary case, u (N, 2), crack (I, 4)."""

    case: dict
    u: np.ndarray
    crack: np.ndarray


def read_reference(folder, tool, mesh_levels):
    """(its summary, {level: ReferenceLevel}) of folder/<tool>/ for the levels it has."""
    sub = os.path.join(folder, tool)
    summary = load_json(os.path.join(sub, "summary.json"))
    if not isinstance(summary, dict) or not isinstance(summary.get("cases"), list):
        raise InputError(f"{sub}/summary.json has no 'cases' list")
    if summary.get("problem") != PROBLEM:
        raise InputError(f"{sub}/summary.json: problem {summary.get('problem')!r}, expected "
                         f"{PROBLEM!r}")
    out = {}
    for i, c in enumerate(summary["cases"]):
        if not isinstance(c, dict) or not isinstance(c.get("level"), int):
            raise InputError(f"{sub}/summary.json: case {i} has no integer 'level'")
        L = c["level"]
        if L not in mesh_levels:
            raise InputError(f"{sub}/summary.json: case {i} is level {L}, which the mesh export "
                             "has not")
        mesh = mesh_levels[L]
        u = _table(os.path.join(sub, f"u_level{L}.txt"), float, (2,))
        crack = _table(os.path.join(sub, f"crack_level{L}.txt"), float, (4,))
        if u.shape != (len(mesh.points), 2):
            raise InputError(f"{sub}/u_level{L}.txt: {u.shape[0]} rows for "
                             f"{len(mesh.points)} vertices")
        if crack.shape != (len(mesh.pairs), 4):
            raise InputError(f"{sub}/crack_level{L}.txt: {crack.shape[0]} rows for "
                             f"{len(mesh.pairs)} crack rows")
        out[L] = ReferenceLevel(c, u, crack)
    return summary, out


def load(folder):
    """The elastic results folder as a dict: folder, summary, scene (name), scene_file (the
    scene copy, parsed), mesh_scene (mesh/scene.json), levels {L: Level}, refs {tool: (summary,
    {L: ReferenceLevel})}."""
    summary = load_json(os.path.join(folder, "summary.json"))
    _, scene_file = load_scene_copy(folder)
    export = os.path.join(folder, "mesh")
    mesh_scene = load_json(os.path.join(export, "scene.json"))
    problem = mesh_scene.get("problem") if isinstance(mesh_scene, dict) else None
    if not isinstance(problem, dict) or problem.get("kind") != PROBLEM:
        raise InputError(f"{export}/scene.json: no elastic 'problem' table")
    for key in ("lambda_in_plane", "mu", "kolosov", "e_prime"):
        if not isinstance(problem.get(key), (int, float)):
            raise InputError(f"{export}/scene.json: problem.{key} is not a number")
    levels = (scene_file.get("discretization") or {}).get("levels")
    if not (isinstance(levels, list) and levels and all(isinstance(v, int) for v in levels)):
        raise InputError(f"{folder}/scene.toml: [discretization] levels is not a list of integers")
    mesh = {L: read_level(export, L) for L in levels}
    name = summary.get("scene", scene_file.get("name"))
    refs = {}
    for tool in REFERENCE_TOOLS:
        if os.path.exists(os.path.join(folder, tool, "summary.json")):
            refs[tool] = read_reference(folder, tool, mesh)
    sdm = elastic_sdm.read_cases(folder, summary)
    for c in sdm:
        if c.level not in mesh:
            raise InputError(f"{folder}/summary.json: solver case {c.grid} is level {c.level}, "
                             "which scene.toml's levels do not list")
    return {"folder": folder, "summary": summary, "scene": name, "scene_file": scene_file,
            "mesh_scene": mesh_scene, "levels": mesh, "refs": refs, "sdm": sdm}
