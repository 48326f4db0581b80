"""Independent errors recomputed per shard of a workflow campaign, kept beside it, read back by
the scene's report.

In a campaign (tools/workflow/Snakefile) a `check` job runs ``sdcompare --precompute SHARD --out
FILE`` on every solver and reference shard as soon as the shard is written, in parallel with the
other jobs; the scene's report job then runs ``sdcompare RESULTS --precomputed FILE ...``. An
entry is this tool's own recomputation (exact.py) of one case's errors against the exact
solution, stored under a sha256 of everything it depends on:

* the arrays it is computed from (mesh, u, p, bubble, crack points and segments, λ; for a
  reference its cracked mesh, crack pairs and ranges), dtype, shape and bytes;
* the scene's exact solution: its ``[exact]``, ``[data] f`` and ``[geometry]`` tables;
* the quadrature (``exact.Quadrature``'s repr, and that of its higher rule, whose values and
  estimate |e(rule) − e(higher rule)| a solver entry carries), the p mass and the p space;
* the source of the code that computes it (exact.py, norms.py and the expression parser).

The report reads the same arrays from the merged folder (``sdcrack merge`` copies them bit for bit)
and uses an entry only when its key matches; anything else is recomputed. A stale or foreign file
can slow a report down, never change what it reports: the report states how many errors came from
precomputed entries (report.json ``independent_precomputed``; the references' interpolation
yardsticks, refcheck.py, are entries too, one per mesh).
"""
import hashlib
import json
import os

import numpy as np

from . import cases, exact
from sdshared.sdresults import write_atomic

FORMAT = "sdcompare-precomputed-1"
# the scene's [problem] kind whose shards this module does not read (elastic_read.PROBLEM)
ELASTIC = "elasticity"


class Store:
    """The entries read from --precomputed files and those computed in this process, by key."""

    def __init__(self):
        self.entries = {}
        self.hits = 0
        self.computed = 0

    def load(self, path):
        """Adds the entries of one file written by ``write``; a file of another format is an
        error (OSError or ValueError, reported by the caller as an input error)."""
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
        if not isinstance(data, dict) or data.get("format") != FORMAT or \
                not isinstance(data.get("entries"), dict):
            raise ValueError(f"{path} is not a file of sdcompare --precompute ({FORMAT})")
        self.entries.update(data["entries"])

    def write(self, path):
        """Writes every entry (sdresults.write_atomic: a temporary name, then renamed)."""
        write_atomic(path, json.dumps({"format": FORMAT, "entries": self.entries}, indent=0,
                                      sort_keys=True))

    def lookup(self, key, compute):
        """The entry under `key`, else compute() stored under it."""
        if key in self.entries:
            self.hits += 1
            return dict(self.entries[key])
        value = compute()
        self.entries[key] = value
        self.computed += 1
        return dict(value)


STORE = Store()


def _code_digest():
    h = hashlib.sha256()
    sdexpr = exact.sdexpr.__file__
    for path in (exact.__file__, os.path.join(os.path.dirname(exact.__file__), "norms.py"), sdexpr):
        with open(path, "rb") as fh:
            h.update(fh.read())
    return h.hexdigest()


_CODE = None


def _exact_tables(scene_file):
    """What ExactSolution.from_scene reads of a scene: [exact], [geometry] and [data] f."""
    return {"exact": scene_file.get("exact"), "geometry": scene_file.get("geometry"),
            "f": (scene_file.get("data") or {}).get("f")}


def _key(kind, arrays, scene_file, extra):
    """sha256 of the arrays (name, dtype, shape, bytes; None as such), the scene's exact solution,
    the quadrature, `extra` and the code."""
    global _CODE
    if _CODE is None:
        _CODE = _code_digest()
    h = hashlib.sha256()
    h.update(json.dumps({"kind": kind, "code": _CODE, "quadrature": repr(exact.Quadrature()),
                         "higher_quadrature": repr(exact.Quadrature().higher()),
                         "exact": _exact_tables(scene_file), "extra": extra},
                        sort_keys=True, default=str).encode())
    for name in sorted(arrays):
        a = arrays[name]
        h.update(name.encode())
        if a is None:
            h.update(b"None")
            continue
        a = np.ascontiguousarray(a)
        h.update(f"{a.dtype.str}{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def solver_case_errors_h5(h5, case, ex, scene_file, p_mass, p_space):
    """``exact.solver_case_errors_estimated`` of a case of fields.h5 through the store: the errors,
    "higher" (the higher rule's) and "quadrature" (their difference, the estimate); the p space is
    part of the key: the same arrays of another p space are another case."""
    d = exact.read_h5_case(h5, case)
    key = _key("solver", d, scene_file, {"p_mass": p_mass, "p_space": p_space})
    return STORE.lookup(key, lambda: exact.solver_case_errors_estimated(
        d["points"], d["triangles"], d["u"], d["p"], d["p_bubble"], d["crack_points"], d["lam"],
        ex, p_mass=p_mass, crack_segments=d["crack_segments"]))


def p1_field_errors(mesh, u, ex, scene_file):
    """``exact.p1_field_errors`` of a reference's field `u` on the export level `mesh` (an
    ExportLevel) through the store."""
    arrays = {"points": mesh.points, "triangles": mesh.tris, "u": u, "crack": mesh.crack,
              "ranges": np.asarray(mesh.ranges, dtype=np.int64)}
    key = _key("p1", arrays, scene_file, {})
    return STORE.lookup(key, lambda: exact.p1_field_errors(
        mesh.points, mesh.tris, u, mesh.crack, ex, ranges=mesh.ranges))


# The interpolation yardsticks this process has looked up, by key: both references solve on one
# mesh export, and the second asks for the first's (not a precomputed entry used: STORE's counts
# stay those of the files read and of what was computed).
_INTERPOLANTS = {}


def p1_interpolation_errors(mesh, ex, scene_file):
    """``exact.p1_interpolation_errors`` on the export level `mesh` (an ExportLevel) through the
    store: the references' own interpolation yardstick (refcheck.py), one per mesh whichever
    reference asks."""
    arrays = {"points": mesh.points, "triangles": mesh.tris, "crack": mesh.crack,
              "ranges": np.asarray(mesh.ranges, dtype=np.int64)}
    key = _key("p1 interpolant", arrays, scene_file, {})
    if key not in _INTERPOLANTS:
        _INTERPOLANTS[key] = STORE.lookup(key, lambda: exact.p1_interpolation_errors(
            mesh.points, mesh.tris, mesh.crack, ex, ranges=mesh.ranges))
    return dict(_INTERPOLANTS[key])


def precompute(folder):
    """Computes into STORE the independent errors of one shard folder (SHARD/<name>/ of a solver
    shard: summary.json with fields.h5 or verification.h5; or of a reference shard: <tool>/ and
    mesh/), the cases ``checks.independent_errors`` recomputes. A case it cannot recompute is
    left out: the report recomputes it and reports why. Returns the number of entries."""
    from . import read

    _, scene_file = read.load_scene_copy(folder)
    problem = scene_file.get("problem")
    if isinstance(problem, dict) and problem.get("kind") == ELASTIC:  # docs/elasticity.md: the elastic report recomputes its own errors
        raise read.InputError(f"{folder}: a shard of an elastic scene: --precompute recomputes the "
                              "scalar problem's errors only (the elastic report computes its own; "
                              "a campaign runs no check job for an elastic scene)")
    if "exact" not in scene_file:
        return 0
    try:
        ex = _exact_of(scene_file)
    except exact.ExactError as exc:
        raise read.InputError(f"{folder}/scene.toml: {exc}")
    n = 0
    summary_path = os.path.join(folder, "summary.json")
    if os.path.exists(summary_path):
        n += _precompute_solver(folder, read, ex, scene_file)
    for tool in read.REFERENCE_TOOLS:
        sub = os.path.join(folder, tool)
        if not os.path.exists(os.path.join(sub, "summary.json")):
            continue
        ref = read.load_reference(sub)
        meshes = ref.get("mesh") or {}
        for c in ref["summary"].get("cases", []):
            lv = int(c["level"])
            if lv in meshes and lv in ref["u"] and isinstance(c.get("errors"), dict):
                p1_field_errors(meshes[lv], ref["u"][lv], ex, scene_file)
                p1_interpolation_errors(meshes[lv], ex, scene_file)
                n += 1
    return n


_EXACT = {}


def _exact_of(scene_file):
    """One ExactSolution per exact solution (the shards of a check share it, and with it the
    quadrature with exact values that exact.py keeps per mesh and ExactSolution)."""
    key = json.dumps(_exact_tables(scene_file), sort_keys=True, default=str)
    if key not in _EXACT:
        _EXACT[key] = exact.ExactSolution.from_scene(scene_file)
    return _EXACT[key]


def _precompute_solver(folder, read, ex, scene_file):
    summary = read.load_json(os.path.join(folder, "summary.json"))
    path = next((os.path.join(folder, f) for f in (read.VERIFICATION_FILE, "fields.h5")
                 if os.path.exists(os.path.join(folder, f))), None)
    if path is None:
        return 0
    data = read.Fields(path)
    n = 0
    try:
        for c in summary.get("cases", []):
            if not isinstance(c.get("errors"), dict) or not data.has_case(c.get("fields_grid")):
                continue
            try:
                solver_case_errors_h5(data.h5, c["fields_grid"], ex, scene_file, cases.p_mass(c),
                                      cases.p_space(c))
                n += 1
            except exact.ExactError:
                continue
    finally:
        data.close()
    return n
