"""Reading an sdcrack results folder (OUT/<scene>/) and its optional reference subfolders."""
import decimal
import json
import math
import os
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from sdshared import sdexport  # the reader of the mesh export's cracks, shared with the references

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


# The p masses of `sdcrack run` (summary.json: each case's `p_mass`, the plan's `p_masses`); a case
# without the key (an sdcrack older than the lumped p mass) is consistent.
P_MASSES = ("consistent", "lumped")
DEFAULT_P_MASS = "consistent"
# The spaces of p (summary.json: each case's `p_space`, the plan's `p_spaces`): the
# paper's continuous MINI p, or "broken-tangential", whose tangential component has one value per
# crack face at the interior vertices of a straight crack (p·ν shared; kinks and tips shared). A
# case without the key (an sdcrack older than the axis) is continuous. The broken-tangential p runs
# with broken u only: the plan is the product of its lists minus (continuous u, broken-tangential p).
DEFAULT_P_SPACE = "continuous"
BROKEN_TANGENTIAL = "broken-tangential"
P_SPACES = (DEFAULT_P_SPACE, BROKEN_TANGENTIAL)
# The p space's tag in labels (broken/M1/ptangential), as in the solver's field names
# (level3-broken-M1-lumped-ptangential-delta0); none for the continuous p.
P_SPACE_TAG = {DEFAULT_P_SPACE: "", BROKEN_TANGENTIAL: "ptangential"}


def p_mass(c):
    """The case's (or row's) p mass: its `p_mass` ("consistent" when absent)."""
    v = c.get("p_mass")
    return DEFAULT_P_MASS if v is None else str(v)


def p_space(c):
    """The case's (or row's) p space: its `p_space` ("continuous" when absent)."""
    v = c.get("p_space")
    return DEFAULT_P_SPACE if v is None else str(v)


def runs_together(u_space, ps):
    """Whether sdcrack runs this u space with this p space: a p whose tangential part jumps needs
    a u that may jump (never continuous u with the broken-tangential p)."""
    return not (u_space == "continuous" and ps == BROKEN_TANGENTIAL)


def p_space_tag(ps):
    """"ptangential" of the broken-tangential p space, "" of the continuous one."""
    return P_SPACE_TAG.get(ps, ps)


def variant_label(u_space, multiplier, pm=DEFAULT_P_MASS, ps=DEFAULT_P_SPACE):
    """"broken/M1" (consistent p mass, continuous p: as before either axis existed),
    "broken/M1/lumped", "broken/M1/ptangential", "broken/M1/lumped/ptangential"."""
    return "/".join([f"{u_space}/{multiplier}"] + [t for t in ("" if pm == DEFAULT_P_MASS else pm,
                                                              p_space_tag(ps)) if t])


def variant_suffix(pm=DEFAULT_P_MASS, ps=DEFAULT_P_SPACE):
    """" lumped", " ptangential", " lumped ptangential" after a case's "level L u m" in a problem
    line; nothing for the consistent p mass and the continuous p."""
    return "".join(f" {t}" for t in ("" if pm == DEFAULT_P_MASS else pm, p_space_tag(ps)) if t)


def variant_of(x):
    """(u space, multiplier, p mass, p space) of a case or of a series, table or plot row."""
    return str(x["u_space"]), str(x["multiplier"]), p_mass(x), p_space(x)


def variant_order(v):
    """Sort key of a variant (u, m, p mass, p space): the consistent p mass and the continuous p
    first, as a run without them lists its variants."""
    u, m, pm, ps = v
    return u, m, pm != DEFAULT_P_MASS, pm, ps != DEFAULT_P_SPACE, ps


def shortest_exponent_form(d):
    """(mantissa, exponent) of a positive finite float in the shortest digits that parse back to
    it: 0.01 → ("1", -2), 2.5e-3 → ("2.5", -3), 1.0 → ("1", 0)."""
    _, digits, exp = decimal.Decimal(repr(d)).normalize().as_tuple()
    m = "".join(map(str, digits))
    return m[0] + ("." + m[1:] if len(m) > 1 else ""), exp + len(digits) - 1


class CaseKey(NamedTuple):
    """A case's identity: the solver's case axes in the solver's order (its CaseKey, `sdcrack
    schema`'s "case_key": tests/python/test_schema.py ties the two). Read by field name, never by
    position. Cases are ordered by `order()`, the order the reports have always listed them in."""
    level: int
    u_space: str
    multiplier: str
    p_mass: str
    p_space: str
    delta: float

    @classmethod
    def of(cls, c):
        """The key of a case (or row) of summary.json: its absent p axes are the defaults."""
        return cls(level=int(c["level"]), u_space=str(c["u_space"]),
                   multiplier=str(c["multiplier"]), p_mass=p_mass(c), p_space=p_space(c),
                   delta=float(c["delta"]))

    def series_name(self):
        """The solver's name of the case's δ sweep in the field files (its series_name):
        "level3-broken-M1", then "-lumped" for the lumped p mass, "-ptangential" for the
        broken-tangential p."""
        tags = "".join(f"-{t}" for t in ("" if self.p_mass == DEFAULT_P_MASS else self.p_mass,
                                         p_space_tag(self.p_space)) if t)
        return f"level{self.level}-{self.u_space}-{self.multiplier}{tags}"

    def case_name(self):
        """The solver's name of the case in the field files (its case_name, summary.json's
        fields_grid): the series name, then "-delta" and δ as Rust's `{:e}` writes it ("1e-2",
        "1e0"; "0" for zero), e.g. "level3-broken-M1-lumped-ptangential-delta0"."""
        if self.delta == 0:
            return f"{self.series_name()}-delta0"
        mant, e = shortest_exponent_form(abs(self.delta))
        return f"{self.series_name()}-delta{'-' if self.delta < 0 else ''}{mant}e{e}"

    def order(self):
        """The reports' case order: level, u space, multiplier, δ, then the p axes (which came
        last, so a run without them lists its cases as before them)."""
        return (self.level, self.u_space, self.multiplier, self.delta, self.p_mass, self.p_space)

    # Sorting keys (sorted(set of keys)) follows `order()`, not the tuple's field order.
    def __lt__(self, other):
        return self.order() < other.order()

    def __le__(self, other):
        return self.order() <= other.order()

    def __gt__(self, other):
        return self.order() > other.order()

    def __ge__(self, other):
        return self.order() >= other.order()


def case_key(c):
    """The CaseKey of a case (or row) of summary.json."""
    return CaseKey.of(c)


def case_order(c):
    """Sort key of cases (or rows) of summary.json: the reports' order (CaseKey.order)."""
    return CaseKey.of(c).order()


def plan_p_masses(plan):
    """The plan's p masses (["consistent"] for a plan written before the lumped p mass)."""
    v = plan.get("p_masses") if isinstance(plan, dict) else None
    return list(v) if isinstance(v, list) else [DEFAULT_P_MASS]


def plan_p_spaces(plan):
    """The plan's p spaces (["continuous"] for a plan written before the p space axis)."""
    v = plan.get("p_spaces") if isinstance(plan, dict) else None
    return list(v) if isinstance(v, list) else [DEFAULT_P_SPACE]


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
