"""The FreeFEM reference's elastic path (docs/elasticity.md): solve.py calls `solve` for an export whose
scene.json has a "problem" of kind "elasticity".

Per level, FreeFem++ runs elastic_qp.edp (its header documents the discrete problem: vector P1 on the
cracked mesh, the stiffness ∫ σ(u):ε(v) with λ* = problem.lambda_in_plane and μ = problem.mu, the
load with sdquad's degree-16 rule, the traction load with sdquad's edge rule, the change of variables
to the jumps' normal and tangential components at every constrained pair and the primal–dual active
set on the normal ones). This module prepares its input and writes the outputs of docs/elasticity.md:

    summary.json          {"scene", "tool": "freefem", "problem": "elasticity", "provenance", "cases":
                          [{"level", "h", "unknowns" (2 × cracked vertices), "iterations", "active",
                          "kkt", "status", "timings_s": {"freefem", "total"}}]}
    u_level{L}.txt        `ux uy` per cracked vertex (%.17g)
    crack_level{L}.txt    per row of crack.txt `opening slip contact_force active` (%.17g; tips 0 0 0 0)
    --fields              fields.h5, fields/level{L}.xdmf (point field u with u_z = 0, cell field
                          stress = (σ_xx, σ_yy, σ_xy) of u_h), fields/level{L}.crack.xdmf (opening,
                          slip, contact_force, active)

The data FreeFEM needs besides the mesh, prepared here:
- u = g at the vertices of the Dirichlet parts (boundary_edges.txt's parts without a traction), with g
  evaluated by sdexpr.to_numpy; a crack copy on ∂Ω (a mouth's + and − copy) takes g on its own face
  by the signed-zero rule (sdexpr.on_face with its node's normal): FreeFEM has no signed zeros, so
  it could not tell the faces of e.g. Williams' atan2(y, x) at the mouth. Fixed components: 0.
- The constrained pairs: every crack row that is not a tip and none of whose four unknowns is
  prescribed (a mouth on a Dirichlet part has none), with its normal from crack_normals.txt.
- The traction edges: boundary_edges.txt's edges of the traction parts (cracked vertices, so a
  mouth's two boundary edges load its own copies), t as FreeFEM expressions per part.
"""

import json
import shutil
import subprocess
import time
from pathlib import Path

import numpy as np

from sdshared import sdexport
from sdshared import sdexpr
from sdshared import sdfields
from sdshared import sdquad
from sdshared import sdresults

HERE = Path(__file__).resolve().parent
EDP_BODY = HERE / "elastic_qp.edp"
COMPONENTS = ("x", "y")
POINT_TOLERANCE = 1e-12  # a fixed point against the mesh's vertices, relative to the domain's size


# ---- the scene's elastic data ---------------------------------------------------------------------

def _number(base, value, what, scene_path):
    if not isinstance(value, (int, float)) or isinstance(value, bool) or not np.isfinite(value):
        raise base.SceneError(f"{scene_path}: problem.{what} must be a finite number, not {value!r}")
    return float(value)


def _pair(base, value, what, scene_path):
    """Two expression strings [x, y], parsed (an invalid one is a SceneError naming it)."""
    if not (isinstance(value, list) and len(value) == 2 and all(isinstance(s, str) for s in value)):
        raise base.SceneError(f"{scene_path}: {what} must be two expressions [x, y], not {value!r}")
    for c, src in zip(COMPONENTS, value):
        base.parse(f"{what}.{c}", src)
    return value


def scene_data(base, scene, scene_path):
    """The elastic keys of scene.json, checked: {"lambda_star", "mu", "f", "g" (or None),
    "tractions" {part: [tx, ty]}, "fixed" [(point (2,), [component index, …])]}."""
    problem = scene["problem"]
    if not isinstance(problem, dict) or problem.get("kind") != "elasticity":
        raise base.SceneError(f"{scene_path}: problem must be {{\"kind\": \"elasticity\", …}}, not {problem!r}")
    lam = _number(base, problem.get("lambda_in_plane"), "lambda_in_plane", scene_path)
    mu = _number(base, problem.get("mu"), "mu", scene_path)
    if not mu > 0 or not lam + mu > 0:
        raise base.SceneError(f"{scene_path}: problem needs mu > 0 and lambda_in_plane + mu > 0 "
                              f"(lambda_in_plane = {lam!r}, mu = {mu!r})")
    data = {"lambda_star": lam, "mu": mu, "f": _pair(base, scene["f"], "f", scene_path)}
    data["g"] = None if scene.get("g") is None else _pair(base, scene["g"], "g", scene_path)
    tractions = scene.get("tractions") or {}
    if not isinstance(tractions, dict):
        raise base.SceneError(f"{scene_path}: tractions must be an object {{part: [tx, ty]}}")
    data["tractions"] = {str(p): _pair(base, t, f"tractions.{p}", scene_path) for p, t in tractions.items()}
    fixed = []
    for k, fp in enumerate(scene.get("fixed") or []):
        try:
            point = np.asarray(fp["point"], dtype=float)
            comps = [COMPONENTS.index(c) for c in fp["components"]]
        except (KeyError, TypeError, ValueError):
            raise base.SceneError(f"{scene_path}: fixed[{k}] must be {{\"point\": [x, y], \"components\": "
                                  f"[\"x\", \"y\"]}}, not {fp!r}") from None
        if point.shape != (2,) or not comps:
            raise base.SceneError(f"{scene_path}: fixed[{k}] must name a point [x, y] and components, not {fp!r}")
        fixed.append((point, comps))
    data["fixed"] = fixed
    return data


# ---- one level's input --------------------------------------------------------------------------

def face_of_vertices(layout, n):
    """(n,) +1 / −1 at the + / − copy of every doubled crack row, 0 elsewhere, and (n, 2) the node's
    normal there: the face a copy's data are evaluated on (sdexpr.on_face)."""
    face, normal = np.zeros(n), np.zeros((n, 2))
    inner = layout.interior()
    for side, col in ((1.0, 0), (-1.0, 1)):
        v = layout.pairs[inner, col]
        face[v] = side
        normal[v] = layout.normals[inner]
    return face, normal


def evaluate_on_faces(fn, xy, face, normal):
    """fn at the points xy, each crack copy (face ≠ 0) on its own face (the signed-zero rule)."""
    values = np.asarray(fn(xy[:, 0], xy[:, 1]), dtype=float) * np.ones(len(xy))
    for k in np.flatnonzero(face):
        x, y = sdexpr.on_face(xy[k:k + 1, 0], xy[k:k + 1, 1], normal[k], face[k])
        values[k] = float(np.asarray(fn(x, y)).ravel()[0])
    return values


def prescribed(base, lv, data, edges, parts):
    """{dof 2v + c: value}: u = g at the vertices of the Dirichlet parts' edges, 0 at the fixed
    components."""
    xy = lv["xy"]
    dirichlet_parts = [k for k, p in enumerate(parts) if p not in data["tractions"]]
    on_dirichlet = np.unique(edges[np.isin(edges[:, 2], dirichlet_parts), :2])
    values = {}
    if len(on_dirichlet):
        if data["g"] is None:
            raise base.SceneError(f"g is null but the boundary parts {[parts[k] for k in dirichlet_parts]} "
                                  "have no traction")
        face, normal = face_of_vertices(lv["layout"], len(xy))
        for c, src in enumerate(data["g"]):
            g = sdexpr.to_numpy(sdexpr.parse(src))
            gv = evaluate_on_faces(g, xy[on_dirichlet], face[on_dirichlet], normal[on_dirichlet])
            values.update({2 * int(v) + c: float(val) for v, val in zip(on_dirichlet, gv)})
    size = max(1.0, float(np.abs(xy).max()))
    for point, comps in data["fixed"]:
        dist = np.hypot(*(lv["xy_uncut"] - point).T)
        v = int(np.argmin(dist))
        if dist[v] > POINT_TOLERANCE * size:
            raise base.SceneError(f"fixed point {point.tolist()} is not a vertex of level {lv['meta'].get('level')}")
        values.update({2 * v + c: 0.0 for c in comps})
    return values


def constrained_pairs(layout, values):
    """Rows of crack.txt that carry the constraint: not a tip, none of the four unknowns prescribed."""
    rows = np.flatnonzero(layout.interior())
    keep = [r for r in rows if not any(2 * int(v) + c in values for v in layout.pairs[r] for c in (0, 1))]
    return np.array(keep, dtype=np.int64)


def traction_funcs(data):
    """FreeFEM `func real tractionX(int k)` / `tractionY`: the k-th traction part's t at x, y."""
    out = []
    for c, name in enumerate(("tractionX", "tractionY")):
        body = "".join(f" if (k == {k}) r = {sdexpr.to_freefem(sdexpr.parse(t[c]))};"
                       for k, t in enumerate(data["tractions"].values()))
        out.append(f"func real {name}(int k) {{ real r = 0.;{body} return r; }}\n")
    return "".join(out)


def edge_rule_edp():
    """The traction rule (sdquad.edge_rule) as rows [weight, s] on [0, 1], weights summing to 1."""
    s, w = sdquad.edge_rule()
    rows = ",\n    ".join(f"[{wk:.17g}, {sk:.17g}]" for wk, sk in zip(w, s))
    return f"real[int,int] edgeRuleTable = [\n    {rows}];\n"


def write_input(base, lv, data, parts, work):
    """The work folder's files for elastic_qp.edp; returns (constrained rows, values)."""
    xy = lv["xy"]
    n = len(xy)
    region, maps = base.regions_and_maps(lv)
    base.write_msh(work / "uncut.msh", lv["xy_uncut"], lv["tri_uncut"], region)
    (work / "region_maps.txt").write_text(f"{len(maps)}\n" + "".join(f"{v}\n" for v in maps.ravel()))
    edges = lv["edges"]
    values = prescribed(base, lv, data, edges, parts)
    (work / "constrained.txt").write_text(
        f"{len(values)}\n" + "".join(f"{d} {v:.17g}\n" for d, v in sorted(values.items())))
    rows = constrained_pairs(lv["layout"], values)
    pairs, normals = lv["layout"].pairs[rows], lv["layout"].normals[rows]
    (work / "pairs.txt").write_text(f"{len(rows)}\n" + "".join(
        f"{p} {m} {nx:.17g} {ny:.17g}\n" for (p, m), (nx, ny) in zip(pairs, normals)))
    index = {p: k for k, p in enumerate(data["tractions"])}
    loaded = [(a, b, index[parts[k]]) for a, b, k in edges if parts[k] in index]
    (work / "traction_edges.txt").write_text(f"{len(loaded)}\n" + "".join(
        f"{a} {b} {k} {xy[a, 0]:.17g} {xy[a, 1]:.17g} {xy[b, 0]:.17g} {xy[b, 1]:.17g}\n" for a, b, k in loaded))
    f_ff = [sdexpr.to_freefem(sdexpr.parse(s)) for s in data["f"]]
    header = (f"// generated by elasticity.py\nstring dir = \"{work.as_posix()}/\";\nint nCracked = {n};\n"
              f"int maxIterations = {int(base.MAX_ITERATIONS)};\n"
              f"real lambdaStar = {data['lambda_star']:.17g};\nreal mu = {data['mu']:.17g};\n"
              f"func fx = {f_ff[0]};\nfunc fy = {f_ff[1]};\n" + traction_funcs(data)
              + base.load_rule_edp() + edge_rule_edp())
    (work / "run.edp").write_text(header + EDP_BODY.read_text())
    return rows


def run_level(base, exe, lv, data, parts, work):
    """FreeFem++ on one level: (u (n, 2), rows, λ per row of `rows`, active per row, info, seconds)."""
    if '"' in work.as_posix() or "\\" in work.as_posix():
        raise base.SolveError(f"unsupported characters in the output path {work}")
    rows = write_input(base, lv, data, parts, work)
    t0 = time.perf_counter()
    proc = subprocess.run([exe, "-nw", "-ns", "-v", "0", str(work / "run.edp")], cwd=work,
                          env=base.freefem_env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    t_ff = time.perf_counter() - t0
    (work / "freefem.log").write_text(proc.stdout)
    if proc.returncode != 0 or not (work / "info.txt").exists():
        last = [l for l in proc.stdout.strip().splitlines() if l.strip()][-1:] or ["no output"]
        raise base.SolveError(f"FreeFem++ failed (exit {proc.returncode}): {last[0].strip()}")
    if "Error um" in proc.stdout:
        raise base.SolveError("FreeFem++: UMFPACK reported a singular or failed factorisation")
    xy_u = lv["xy_uncut"]
    check = np.loadtxt(work / "vertices_check.txt", ndmin=2)
    if check.shape != xy_u.shape or np.abs(check - xy_u).max() > 1e-12 * max(1.0, np.abs(xy_u).max()):
        raise base.SolveError("FreeFEM changed the vertex order of the uncut mesh")
    info = dict(l.split() for l in (work / "info.txt").read_text().splitlines() if l.strip())
    missing = [k for k in ("converged", "iterations", "active", *sdresults.KKT_KEYS) if k not in info]
    if missing:
        raise base.SolveError(f"FreeFem++ info.txt lacks {', '.join(missing)}")
    u = np.loadtxt(work / "u.txt", ndmin=2)
    if u.shape != (len(lv["xy"]), 2) or not np.all(np.isfinite(u)):
        raise base.SolveError("FreeFem++ returned a malformed or non-finite u")
    lam_active = np.loadtxt(work / "lambda.txt", ndmin=2) if len(rows) else np.zeros((0, 2))
    if lam_active.shape != (len(rows), 2):
        raise base.SolveError("FreeFem++ returned a malformed lambda.txt")
    return u, rows, lam_active[:, 0], lam_active[:, 1].astype(np.int64), info, t_ff


# ---- outputs ------------------------------------------------------------------------------------

def crack_table(layout, u, rows, lam, active):
    """(I, 4) per row of crack.txt: opening (u⁺ − u⁻)·ν, slip (u⁺ − u⁻)·τ (τ = ν turned by −90°),
    the nodal contact force λ_j, 1 where j is active; tips 0 0 0 0."""
    table = np.zeros((len(layout.pairs), 4))
    inner = layout.interior()
    jump = u[layout.pairs[:, 0]] - u[layout.pairs[:, 1]]
    nu = layout.normals
    table[inner, 0] = (jump[:, 0] * nu[:, 0] + jump[:, 1] * nu[:, 1])[inner]
    table[inner, 1] = (jump[:, 0] * nu[:, 1] - jump[:, 1] * nu[:, 0])[inner]
    table[rows, 2] = lam
    table[rows, 3] = active
    return table


def cell_stress(xy, tri, u, lam, mu):
    """(T, 3) σ(u_h) = (σ_xx, σ_yy, σ_xy) per triangle of the P1 field u (n, 2), σ = λ* tr ε I + 2μ ε."""
    (ux_x, ux_y), (uy_x, uy_y) = (sdfields.triangle_gradients(xy, tri, u[:, c]).T for c in (0, 1))
    trace = lam * (ux_x + uy_y)
    return np.column_stack([trace + 2 * mu * ux_x, trace + 2 * mu * uy_y, mu * (ux_y + uy_x)])


def write_text(path, table):
    with open(path, "w") as f:
        f.write("".join(" ".join(f"{v:.17g}" for v in row) + "\n" for row in table))


# ---- driver -------------------------------------------------------------------------------------

def read_level(base, export, level, parts_of_scene):
    """solve.read_level plus boundary_edges.txt ("edges": `v0 v1 part` rows) and mesh.json's
    boundary_parts ("parts"), read and checked by sdexport.read_boundary_edges."""
    lv = base.read_level(export, level, mouths=True)
    d = Path(export) / f"level{level}"
    try:
        edges, part, parts = sdexport.read_boundary_edges(d, len(lv["xy"]), lv["layout"])
    except sdexport.ExportError as e:
        raise base.SolveError(str(e)) from None
    unknown = sorted(set(parts_of_scene) - set(parts))
    if unknown:
        raise base.SceneError(f"tractions on unknown boundary parts {unknown} (level {level} has {parts})")
    lv["edges"] = np.column_stack([edges, part])
    lv["parts"] = parts
    return lv


def solve(base, export, out, scene, scene_path, exe, keep_work=False, overwrite=False, fields=False):
    """The elastic problem of every level of `export` into `out` (base: the solve.py module)."""
    try:
        name, levels = scene["name"], scene["levels"]
        data = scene_data(base, scene, scene_path)
        sdexport.scene_cracks(scene, scene_path)
    except sdexport.ExportError as e:
        raise base.SceneError(str(e)) from None
    except (ValueError, KeyError, TypeError) as e:
        raise base.SceneError(f"{scene_path}: malformed elastic scene ({e})") from None
    if out.exists() and not overwrite:
        raise base.SolveError(f"{out} exists; refusing to overwrite earlier results (use --overwrite)")
    version = base.freefem_version(exe)
    with sdresults.staged_folder(out) as tmp:
        cases, field_sets = [], []
        for level in levels:
            t0 = time.perf_counter()
            lv = read_level(base, export, level, data["tractions"])
            work = tmp / f"work_level{level}"
            work.mkdir()
            u, rows, lam, active, info, t_ff = run_level(base, exe, lv, data, lv["parts"], work)
            case = {
                "level": level,
                "h": lv["meta"]["h"],
                "unknowns": int(u.size),
                "iterations": int(info["iterations"]),
                "active": int(info["active"]),
                "kkt": {k: float(info[k]) + 0.0 for k in sdresults.KKT_KEYS},
            }
            failure = (None if info["converged"] == "1" else
                       f"active set did not converge in {int(info['iterations'])} solves")
            case["status"] = sdresults.case_status(case["kkt"], base.KKT_TOLERANCE, failure)
            crack = crack_table(lv["layout"], u, rows, lam, active)
            write_text(tmp / f"u_level{level}.txt", u)
            write_text(tmp / f"crack_level{level}.txt", crack)
            case["timings_s"] = {"freefem": t_ff, "total": time.perf_counter() - t0}
            cases.append(case)
            if fields:
                field_sets.append((level, {
                    "xy": lv["xy"], "tri": lv["tri"], "crack": lv["crack"],
                    "segments": lv["layout"].segments(), "h": lv["meta"]["h"], "point": {"u": u},
                    "cell": {"stress": cell_stress(lv["xy"], lv["tri"], u, data["lambda_star"], data["mu"])},
                    "crack_fields": dict(zip(("opening", "slip", "contact_force", "active"), crack.T))}))
            if not keep_work:
                shutil.rmtree(work)
        if fields:
            try:
                import h5py  # noqa: F401  (sdfields.write_fields writes with it)
            except ImportError as e:
                raise base.SolveError(f"--fields needs h5py: apt-get install -y python3-h5py ({e})")
            sdfields.write_fields(tmp, field_sets, "freefem")
        summary = sdresults.write_summary(tmp, name, "freefem", cases, tool_version=version,
                                          problem="elasticity")
    return summary
