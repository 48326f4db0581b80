"""Reading an sdcrack results folder (OUT/<scene>/) and its optional reference subfolders."""
import json
import math
import os
from dataclasses import dataclass

import numpy as np

from sdshared import sdexport  # the reader of the mesh export's cracks, shared with the references
from .cases import DEFAULT_P_SPACE

REFERENCE_TOOLS = ("dolfinx", "freefem")


class InputError(Exception):
    """Missing or malformed input (exit code 2)."""


def load_json(path):
    """The JSON document of the file `path` (UTF-8); InputError (exit 2) naming the file when it
    is missing, unreadable or not JSON. One home for the compare tools' JSON input."""
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except FileNotFoundError:
        raise InputError(f"missing file: {path}")
    except OSError as exc:
        raise InputError(f"unreadable file: {path} ({exc.strerror})")
    except ValueError as exc:  # json.JSONDecodeError and UnicodeDecodeError are ValueErrors
        raise InputError(f"malformed JSON in {path}: {exc}")


def finite_number(v):
    """True for an int or float (not a bool) that is finite: a usable error or residual."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def without_default_p_space(obj):
    """`obj` (report.json's content) without the `p_space` keys whose value is the continuous p
    or "*": what a run without the broken-tangential p space writes, so that its report.json is
    byte for byte the one of before the axis."""
    if isinstance(obj, dict):
        return {k: without_default_p_space(v) for k, v in obj.items()
                if not (k == "p_space" and v in (DEFAULT_P_SPACE, "*"))}
    if isinstance(obj, list):
        return [without_default_p_space(v) for v in obj]
    return obj


def total_time(c):
    return float(sum(float(v) for v in (c.get("timings_s") or {}).values() if v is not None))


class Fields:
    """Lazy access to fields.h5 (or verification.h5: the same layout)."""

    def __init__(self, path):
        import h5py

        self.path = path
        try:
            self.h5 = h5py.File(path, "r")
        except OSError as exc:
            raise InputError(f"cannot read {path}: {exc}")
        self._mesh_cache = {}

    def close(self):
        self.h5.close()

    def has_case(self, grid):
        return grid is not None and f"cases/{grid}" in self.h5

    def mesh_by_key(self, key):
        if key not in self._mesh_cache:
            g = self.h5[f"meshes/{key}"]
            self._mesh_cache[key] = self._valid_mesh(
                f"/meshes/{key}", np.asarray(g["points"][()], dtype=float),
                np.asarray(g["triangles"][()], dtype=np.int64))
        return self._mesh_cache[key]

    def _valid_mesh(self, where, pts, tris):
        """(pts, tris), or InputError naming the first triangle that refers to no stored point or
        has zero area: no norm can be taken on such a mesh."""
        if pts.ndim != 2 or pts.shape[1] < 2 or tris.ndim != 2 or tris.shape[1] != 3:
            raise InputError(f"{self.path}: {where}: points {pts.shape}, triangles {tris.shape}: "
                             "expected (N, 2 or 3) and (T, 3)")
        if tris.size and (tris.min() < 0 or tris.max() >= pts.shape[0]):
            bad = int(np.flatnonzero((tris < 0).any(axis=1) | (tris >= pts.shape[0]).any(axis=1))[0])
            raise InputError(f"{self.path}: {where}: triangle {bad} refers to a point that is not "
                             f"stored ({pts.shape[0]} points)")
        X = pts[tris][:, :, :2]
        det = ((X[:, 1, 0] - X[:, 0, 0]) * (X[:, 2, 1] - X[:, 0, 1])
               - (X[:, 1, 1] - X[:, 0, 1]) * (X[:, 2, 0] - X[:, 0, 0]))
        if np.any(det == 0):
            raise InputError(f"{self.path}: {where}: triangle {int(np.flatnonzero(det == 0)[0])} "
                             "is degenerate (zero area)")
        return pts, tris

    def has_mesh(self, key):
        return f"meshes/{key}" in self.h5

    def case(self, grid):
        """dict(points, tris, u, p, p_bubble, crack_points, crack_segments, lam); missing datasets are
        None; the mesh arrays are shared by the cases of one mesh and must not be modified (crack_segments: the segments within each crack, absent in files written before several
        cracks, whose crack points form one crack)."""
        import h5py

        g = self.h5[f"cases/{grid}"]
        link = g.get("mesh", getlink=True)
        if isinstance(link, h5py.SoftLink) and link.path.startswith("/meshes/") \
                and self.has_mesh(link.path[len("/meshes/"):]):
            # the cases of a mesh link to it (sdcrack's layout): one pair of arrays for all of
            # them, which the norms' caches then recognise by identity
            pts, tris = self.mesh_by_key(link.path[len("/meshes/"):])
        else:
            mesh = g["mesh"]
            pts, tris = self._valid_mesh(f"/cases/{grid}/mesh",
                                         np.asarray(mesh["points"][()], dtype=float),
                                         np.asarray(mesh["triangles"][()], dtype=np.int64))

        def get(name):
            return np.asarray(g[name][()], dtype=float) if name in g else None

        return {"points": pts, "tris": tris, "u": get("u"), "p": get("p"),
                "p_bubble": get("p_bubble"), "crack_points": get("crack/points"),
                "crack_segments": (np.asarray(g["crack/segments"][()], dtype=np.int64)
                                   if "crack/segments" in g else None),
                "lam": get("crack/lambda")}


def load_reference(folder):
    s = load_json(os.path.join(folder, "summary.json"))
    u = {}
    for c in s.get("cases", []):
        lvl = int(c["level"])
        path = os.path.join(folder, f"u_level{lvl}.txt")
        if os.path.exists(path):
            try:
                u[lvl] = np.loadtxt(path, dtype=float, ndmin=1)
            except ValueError as exc:
                raise InputError(f"malformed {path}: {exc}")
    return {"summary": s, "u": u, "tool": s.get("tool", os.path.basename(folder)),
            "mesh": load_export_meshes(os.path.join(os.path.dirname(folder), "mesh"), sorted(u))}


@dataclass
class ExportLevel:
    """One level of the mesh export the references solved on: the cracked mesh (points (N,2),
    tris (T,3)), crack (I,2) the (plus, minus) rows of crack.txt, ranges [(first, n)] its cracks
    (cracks.txt), kind "structured" | "refined" | "graded" (mesh.json;
    compare/sdshared/sdexport.py), parents (graded levels: parents.txt)."""

    level: int
    points: np.ndarray
    tris: np.ndarray
    crack: np.ndarray
    ranges: list
    kind: str = sdexport.DEFAULT_KIND
    # "graded" levels above the first: per triangle, its parent in the previous level (parents.txt)
    parents: object = None

    @classmethod
    def one_crack(cls, level, points, tris, crack):
        """A level of an export written before polyline cracks: the rows of crack.txt form one crack on a
        structured grid."""
        return cls(int(level), points, tris, np.asarray(crack, dtype=np.int64), [(0, len(crack))])

    def segments(self):
        """(S, 2) the crack.txt row pairs [k, k+1] within each crack."""
        return sdexport.segments_of(self.ranges)


def load_export_meshes(export, levels):
    """The cracked meshes of the `sdcrack mesh` export the references solved on (written by
    `sdcrack run` into RESULTS/<scene>/mesh): {level: ExportLevel}. A level whose vertices.txt,
    triangles.txt or crack.txt is missing or unreadable is left out (completeness reports it); a
    malformed crack layout (cracks.txt, crack_normals.txt, tips) or mesh.json kind is an InputError."""
    meshes = {}
    for lvl in levels:
        d = os.path.join(export, f"level{lvl}")
        try:
            pts = np.loadtxt(os.path.join(d, "vertices.txt"), dtype=float, ndmin=2)
            tris = np.loadtxt(os.path.join(d, "triangles.txt"), dtype=np.int64, ndmin=2)
            np.loadtxt(os.path.join(d, "crack.txt"), dtype=np.int64, ndmin=2)
        except (OSError, ValueError):
            continue
        try:
            kind = sdexport.read_kind(sdexport.read_mesh_json(d), os.path.join(d, "mesh.json"))
            # copies=False: a field on a mesh without crack copies (plus == minus everywhere) is read too
            layout = sdexport.read_layout(d, pts[:, :2], len(pts), copies=False)
        except sdexport.ExportError as exc:
            raise InputError(str(exc))
        parents = None
        if kind == "graded" and os.path.exists(os.path.join(d, "parents.txt")):
            try:
                parents = np.loadtxt(os.path.join(d, "parents.txt"), dtype=np.int64, ndmin=1)
            except ValueError as exc:
                raise InputError(f"{d}/parents.txt: {exc}")
            if parents.shape != (len(tris),):
                raise InputError(f"{d}/parents.txt: {parents.shape[0]} rows for {len(tris)} triangles")
        meshes[lvl] = ExportLevel(int(lvl), pts, tris, layout.pairs, layout.ranges, kind, parents)
    return meshes


def _not_a_results_folder(folder):
    """The one-line reason `folder` is not one scene's results folder, with a hint where the
    folder is a campaign's (one results folder per scene below it)."""
    if not os.path.exists(folder):
        return f"no such folder: {folder}"
    if not os.path.isdir(folder):
        return f"not a results folder (a file): {folder}"
    scenes = sorted(d for d in os.listdir(folder)
                    if os.path.isfile(os.path.join(folder, d, "summary.json")))
    if scenes:
        return (f"{folder} holds the results folders of {len(scenes)} scene(s) (a campaign): give "
                f"one of them, e.g. {os.path.join(folder, scenes[0])}")
    return f"not a results folder (no summary.json): {folder}"


def load_results(folder):
    if not os.path.isfile(os.path.join(folder, "summary.json")):
        raise InputError(_not_a_results_folder(folder))
    summary = load_json(os.path.join(folder, "summary.json"))
    if "cases" not in summary or not isinstance(summary["cases"], list):
        raise InputError(f"{folder}/summary.json has no 'cases' list")
    for i, c in enumerate(summary["cases"]):
        for k in ("level", "h", "u_space", "multiplier", "delta", "kkt"):
            if k not in c:
                raise InputError(f"{folder}/summary.json: case {i} lacks '{k}'")
    scene_text, scene_file = load_scene_copy(folder)
    plan = summary.get("plan")
    if not (isinstance(plan, dict) and all(isinstance(plan.get(k), list) for k in PLAN_KEYS)):
        raise InputError(f"{folder}/summary.json has no 'plan' ({', '.join(PLAN_KEYS)}): it was "
                         "written by an sdcrack older than the scene copy; rerun the scene")
    for key in ("p_masses", "p_spaces"):
        if key in plan and not isinstance(plan[key], list):
            raise InputError(f"{folder}/summary.json: plan.{key} is not a list")
    mesh_scene = os.path.join(folder, "mesh", "scene.json")
    fpath = os.path.join(folder, "fields.h5")
    fields = Fields(fpath) if os.path.exists(fpath) else None
    vpath = os.path.join(folder, VERIFICATION_FILE)
    # What the independent recomputation reads: verification.h5, which sdcrack keeps with every
    # quantity whenever the scene's [outputs] fields does not list u, p and lambda, else fields.h5.
    data = Fields(vpath) if os.path.exists(vpath) else fields
    refs = {}
    for tool in REFERENCE_TOOLS:
        sub = os.path.join(folder, tool)
        if os.path.exists(os.path.join(sub, "summary.json")):
            refs[tool] = load_reference(sub)
    return {"folder": folder, "summary": summary, "scene": summary.get("scene", os.path.basename(
        os.path.normpath(folder))), "fields": fields, "data": data, "refs": refs, "plan": plan,
        "scene_text": scene_text, "scene_file": scene_file,
        "mesh_scene": load_json(mesh_scene) if os.path.exists(mesh_scene) else None}


def close_results(res):
    """Closes the HDF5 files of a load_results() dict (None: nothing)."""
    if res is None:
        return
    for f in {id(f): f for f in (res.get("fields"), res.get("data")) if f is not None}.values():
        f.close()


PLAN_KEYS = ("levels", "u_spaces", "multipliers", "deltas")
# The solver's compact copy of every field for this tool, written whenever fields.h5 lacks some.
VERIFICATION_FILE = "verification.h5"
SCENE_COPY = "scene.toml"


def load_scene_copy(folder):
    """(text, parsed TOML) of the scene copy sdcrack keeps in the results folder."""
    import tomllib

    path = os.path.join(folder, SCENE_COPY)
    try:
        with open(path, encoding="utf-8") as fh:
            text = fh.read()
    except FileNotFoundError:
        raise InputError(f"missing file: {path} (the copy of the scene that sdcrack writes with its "
                         "results; without it the verdict cannot know what was asked for)")
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"cannot read {path}: {exc}")
    try:
        return text, tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"malformed TOML in {path}: {exc}")
