#!/usr/bin/env python3
"""FreeFEM reference solver for the crack problem of BRIEF §3.

Usage: solve.py MESH_EXPORT_DIR --out OUT [--fields] [--freefem FreeFem++] [--keep-work] [--overwrite]

Reads a mesh export of `sdcrack mesh SCENE --out DIR`, runs FreeFem++ on crack_qp.edp once per level
(P1 on the cracked mesh, u = g on Γ, nodal jump constraints u⁺ − u⁻ ≥ 0, primal–dual active set),
and writes OUT/summary.json and OUT/u_level{L}.txt (u at the cracked vertices, %.17g). With an exact
solution in the scene it also computes, on the cracked mesh with numpy,
    u_l2 = ‖u_h − u‖_{L²(Ω_c)},  p_l2 = ‖∇u_h − ∇u‖_{L²(Ω_c)},  lambda_l2 = ‖[u_h] − [u]‖_{L²(Γc)}.
OUT is written atomically (a temporary folder, then one rename); an existing OUT is an error unless
--overwrite is given. Every failure is one line on stderr and a non-zero exit status.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
EDP_BODY = HERE / "crack_qp.edp"
FF_LOADPATH_DEFAULT = "/usr/lib/freefem++"
APT_HINT = "apt-get install -y freefem++ libfreefem++"

sys.path.insert(0, str(HERE.parent / "common"))
try:
    import sdexpr  # the shared translator: parse(src), to_freefem(tree), to_numpy(tree)
except ImportError:
    sdexpr = None
import sdresults  # noqa: E402  (standard library only)


class SolveError(Exception):
    """A failure reported as one line."""


# ---- expressions ---------------------------------------------------------------------------------

def _fallback_freefem(src):
    """Until references/common/sdexpr.py exists: the string is taken as already-translated FreeFEM."""
    return src


_NUMPY_NAMES = {
    "sin": np.sin, "cos": np.cos, "tan": np.tan, "exp": np.exp, "log": np.log, "sqrt": np.sqrt,
    "abs": np.abs, "sign": np.sign, "atan2": np.arctan2, "min": np.minimum, "max": np.maximum,
    "pi": np.pi,
}


def _fallback_numpy(src):
    """Until sdexpr exists: an already-translated string evaluated by numpy ('^' read as power)."""
    code = compile(src.replace("^", "**"), "<expression>", "eval")

    def fn(x, y):
        with np.errstate(all="ignore"):
            v = eval(code, {"__builtins__": {}}, dict(_NUMPY_NAMES, x=x, y=y))
        return np.broadcast_to(np.asarray(v, dtype=float), np.shape(x)).copy()
    return fn


def to_freefem(src):
    if sdexpr is None:
        return _fallback_freefem(src)
    return sdexpr.to_freefem(sdexpr.parse(src))


def to_numpy(src):
    """A callable fn(x, y) -> ndarray for the expression `src`."""
    if sdexpr is None:
        return _fallback_numpy(src)
    out = sdexpr.to_numpy(sdexpr.parse(src))
    if callable(out):
        def fn(x, y):
            with np.errstate(all="ignore"):
                v = out(x, y)
            return np.broadcast_to(np.asarray(v, dtype=float), np.shape(x)).copy()
        return fn
    return _fallback_numpy_code(out)


def _fallback_numpy_code(code_str):
    """sdexpr.to_numpy returned source text in terms of np, x, y."""
    code = compile(code_str, "<expression>", "eval")

    def fn(x, y):
        with np.errstate(all="ignore"):
            v = eval(code, {"__builtins__": {}}, {"np": np, "numpy": np, "x": x, "y": y, "pi": np.pi})
        return np.broadcast_to(np.asarray(v, dtype=float), np.shape(x)).copy()
    return fn


# ---- reading the export --------------------------------------------------------------------------

def _load(path, dtype, cols):
    try:
        a = np.loadtxt(path, dtype=dtype, ndmin=2)
    except OSError:
        raise SolveError(f"missing file {path}")
    except ValueError as e:
        raise SolveError(f"cannot read {path}: {e}")
    if a.size == 0:
        a = a.reshape(0, cols)
    if a.shape[1] != cols:
        raise SolveError(f"{path}: expected {cols} columns, found {a.shape[1]}")
    return a


def read_level(export, level):
    d = Path(export) / f"level{level}"
    if not d.is_dir():
        raise SolveError(f"missing level folder {d}")
    lv = {
        "meta": json.loads((d / "mesh.json").read_text()) if (d / "mesh.json").exists() else None,
        "xy_uncut": _load(d / "vertices_uncut.txt", float, 2),
        "tri_uncut": _load(d / "triangles_uncut.txt", np.int64, 3),
        "xy": _load(d / "vertices.txt", float, 2),
        "tri": _load(d / "triangles.txt", np.int64, 3),
        "crack": _load(d / "crack.txt", np.int64, 2),
        "boundary": _load(d / "boundary.txt", np.int64, 1)[:, 0],
    }
    if lv["meta"] is None:
        raise SolveError(f"missing file {d / 'mesh.json'}")
    nu, n = len(lv["xy_uncut"]), len(lv["xy"])
    if lv["tri"].shape != lv["tri_uncut"].shape:
        raise SolveError(f"{d}: cracked and uncut meshes have different triangle counts")
    if not np.array_equal(lv["xy"][:nu], lv["xy_uncut"]):
        raise SolveError(f"{d}: the first n_uncut cracked vertices differ from the uncut vertices")
    if lv["tri"].min() < 0 or lv["tri"].max() >= n or lv["tri_uncut"].max() >= nu:
        raise SolveError(f"{d}: triangle vertex index out of range")
    if len(lv["boundary"]) and lv["boundary"].max() >= nu:
        raise SolveError(f"{d}: boundary vertex is a crack copy")
    return lv


# ---- FreeFEM input -------------------------------------------------------------------------------

def minus_map_and_regions(lv):
    """Region 1/2 per triangle (2: uses a − copy) and the uncut → − copy vertex map."""
    tri, tri_u = lv["tri"], lv["tri_uncut"]
    nu = len(lv["xy_uncut"])
    differs = tri != tri_u
    region = np.where(differs.any(axis=1), 2, 1)
    mmap = np.arange(nu)
    src, dst = tri_u[region == 2].ravel(), tri[region == 2].ravel()
    mmap[src] = dst
    if not np.array_equal(mmap[src], dst):
        raise SolveError("inconsistent − copies between triangles")
    for p, m in lv["crack"]:
        if p != m and not (0 <= p < nu <= m < len(lv["xy"])):
            raise SolveError(f"bad crack pair {p} {m}")
    return region, mmap


def boundary_edges(tri):
    e = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    uniq, count = np.unique(e, axis=0, return_counts=True)
    return uniq[count == 1]


def write_msh(path, xy, tri, region):
    be = boundary_edges(tri)
    on_b = np.zeros(len(xy), dtype=int)
    on_b[be.ravel()] = 1
    with open(path, "w") as f:
        f.write(f"{len(xy)} {len(tri)} {len(be)}\n")
        for (x, y), lab in zip(xy, on_b):
            f.write(f"{x:.17g} {y:.17g} {lab}\n")
        for (a, b, c), r in zip(tri + 1, region):
            f.write(f"{a} {b} {c} {r}\n")
        for a, b in be + 1:
            f.write(f"{a} {b} 1\n")


def freefem_binary(name):
    exe = shutil.which(name)
    if exe is None:
        raise SolveError(f"FreeFem++ not found ('{name}'); install it with: {APT_HINT}")
    return exe


def run_level(exe, lv, f_ff, g_ff, work):
    xy_u, tri_u = lv["xy_uncut"], lv["tri_uncut"]
    n = len(lv["xy"])
    region, mmap = minus_map_and_regions(lv)
    write_msh(work / "uncut.msh", xy_u, tri_u, region)
    np.savetxt(work / "minus_map.txt", mmap, fmt="%d")
    pairs = lv["crack"][lv["crack"][:, 0] != lv["crack"][:, 1]]
    with open(work / "pairs.txt", "w") as fp:
        fp.write(f"{len(pairs)}\n")
        for p, m in pairs:
            fp.write(f"{p} {m}\n")
    bnd = np.unique(lv["boundary"])
    with open(work / "dirichlet.txt", "w") as fb:
        fb.write(f"{len(bnd)}\n" + "".join(f"{i}\n" for i in bnd))
    if '"' in work.as_posix() or "\\" in work.as_posix():
        raise SolveError(f"unsupported characters in the output path {work}")
    header = (f"// generated by solve.py\nstring dir = \"{work.as_posix()}/\";\nint nCracked = {n};\n"
              f"func f = {f_ff};\nfunc g = {g_ff};\n")
    (work / "run.edp").write_text(header + EDP_BODY.read_text())
    env = dict(os.environ)
    env.setdefault("FF_LOADPATH", FF_LOADPATH_DEFAULT)
    t0 = time.perf_counter()
    proc = subprocess.run([exe, "-nw", "-ns", "-v", "0", str(work / "run.edp")], cwd=work, env=env,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    t_ff = time.perf_counter() - t0
    (work / "freefem.log").write_text(proc.stdout)
    if proc.returncode != 0 or not (work / "info.txt").exists():
        last = [l for l in proc.stdout.strip().splitlines() if l.strip()][-1:] or ["no output"]
        raise SolveError(f"FreeFem++ failed (exit {proc.returncode}): {last[0].strip()}")
    if "Error um" in proc.stdout:
        raise SolveError("FreeFem++: UMFPACK reported a singular or failed factorisation")
    check = np.loadtxt(work / "vertices_check.txt", ndmin=2)
    if check.shape != xy_u.shape or np.abs(check - xy_u).max() > 1e-12 * max(1.0, np.abs(xy_u).max()):
        raise SolveError("FreeFEM changed the vertex order of the uncut mesh")
    info = dict(l.split() for l in (work / "info.txt").read_text().splitlines() if l.strip())
    if info.get("converged") != "1":
        raise SolveError(f"active-set method did not converge in {info.get('iterations')} iterations")
    u = np.loadtxt(work / "u.txt", ndmin=1)
    if u.shape != (n,) or not np.all(np.isfinite(u)):
        raise SolveError("FreeFem++ returned a malformed or non-finite u")
    lam = np.loadtxt(work / "lambda.txt", ndmin=1) if len(pairs) else np.zeros(0)
    return u, lam, info, t_ff


# ---- errors against an exact solution ------------------------------------------------------------

def triangle_rule(n=5):
    """Collapsed (Duffy) Gauss rule on the reference triangle, exact for degree 2n − 2 (8 for n = 5);
    all points interior. Returns barycentric-free (xi, eta) points and weights (sum 1/2)."""
    g, w = np.polynomial.legendre.leggauss(n)
    g, w = (g + 1) / 2, w / 2
    a, b = np.meshgrid(g, g, indexing="ij")
    wa, wb = np.meshgrid(w, w, indexing="ij")
    xi = a.ravel()
    eta = (b * (1 - a)).ravel()
    wt = (wa * wb * (1 - a)).ravel()
    return xi, eta, wt


def exact_errors(lv, u_h, exact, normal):
    xy, tri = lv["xy"], lv["tri"]
    u_ex = to_numpy(exact["u"])
    xi, eta, wt = triangle_rule(5)
    p0, p1, p2 = xy[tri[:, 0]], xy[tri[:, 1]], xy[tri[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    X = p0[:, 0, None] + e1[:, 0, None] * xi + e2[:, 0, None] * eta
    Y = p0[:, 1, None] + e1[:, 1, None] * xi + e2[:, 1, None] * eta
    ut = u_h[tri]
    uh_q = ut[:, 0, None] * (1 - xi - eta) + ut[:, 1, None] * xi + ut[:, 2, None] * eta
    W = np.abs(det)[:, None] * wt
    u_l2 = float(np.sqrt(np.sum(W * (uh_q - u_ex(X, Y)) ** 2)))
    # ∇u_h per triangle: [e1; e2] ∇u = [u1 − u0; u2 − u0]
    d1, d2 = ut[:, 1] - ut[:, 0], ut[:, 2] - ut[:, 0]
    gx = (d1 * e2[:, 1] - d2 * e1[:, 1]) / det
    gy = (-d1 * e2[:, 0] + d2 * e1[:, 0]) / det
    if exact.get("px") and exact.get("py"):
        ex_x, ex_y = to_numpy(exact["px"])(X, Y), to_numpy(exact["py"])(X, Y)
    else:  # central differences inside the triangle (points are interior; step ≪ distance to edges)
        s = 1e-6 * np.sqrt(np.abs(det))[:, None]
        ex_x = (u_ex(X + s, Y) - u_ex(X - s, Y)) / (2 * s)
        ex_y = (u_ex(X, Y + s) - u_ex(X, Y - s)) / (2 * s)
    p_l2 = float(np.sqrt(np.sum(W * ((gx[:, None] - ex_x) ** 2 + (gy[:, None] - ex_y) ** 2))))
    # jump along the crack polyline (crack.txt: tip a → tip b)
    cr = lv["crack"]
    jump_h = u_h[cr[:, 0]] - u_h[cr[:, 1]]
    pts = xy[cr[:, 0]]
    gl, glw = np.polynomial.legendre.leggauss(8)
    t, tw = (gl + 1) / 2, glw / 2
    a, b = pts[:-1], pts[1:]
    L = np.linalg.norm(b - a, axis=1)
    QX = a[:, 0, None] + (b - a)[:, 0, None] * t
    QY = a[:, 1, None] + (b - a)[:, 1, None] * t
    jh = jump_h[:-1, None] * (1 - t) + jump_h[1:, None] * t
    if exact.get("jump"):
        jx = to_numpy(exact["jump"])(QX, QY)
    else:  # exact one-sided traces: steps ±eps ν, Richardson-extrapolated (error O(eps²))
        eps = 1e-7 * max(1.0, float(np.abs(xy).max()))
        nx, ny = normal

        def jump_at(e):
            return u_ex(QX + e * nx, QY + e * ny) - u_ex(QX - e * nx, QY - e * ny)
        jx = 2 * jump_at(eps) - jump_at(2 * eps)
    lam_l2 = float(np.sqrt(np.sum(L[:, None] * tw * (jh - jx) ** 2)))
    return {"u_l2": u_l2, "p_l2": p_l2, "lambda_l2": lam_l2}


# ---- fields (--fields): fields.h5 + fields.xdmf, the shapes of src/output/xdmf.rs ----------------

def vertex_gradient(xy, tri, u):
    """∇u_h at the cracked vertices: area-weighted mean of the constant triangle gradients."""
    p0, p1, p2 = xy[tri[:, 0]], xy[tri[:, 1]], xy[tri[:, 2]]
    e1, e2 = p1 - p0, p2 - p0
    det = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]
    d1, d2 = u[tri[:, 1]] - u[tri[:, 0]], u[tri[:, 2]] - u[tri[:, 0]]
    g = np.column_stack([(d1 * e2[:, 1] - d2 * e1[:, 1]) / det, (-d1 * e2[:, 0] + d2 * e1[:, 0]) / det])
    area = np.abs(det) / 2
    acc, wsum = np.zeros((len(xy), 2)), np.zeros(len(xy))
    for k in range(3):
        np.add.at(acc, tri[:, k], g * area[:, None])
        np.add.at(wsum, tri[:, k], area)
    return acc / np.maximum(wsum, 1e-300)[:, None]


# ---- driver --------------------------------------------------------------------------------------

def solve(export, out, freefem="FreeFem++", keep_work=False, overwrite=False, fields=False):
    export, out = Path(export), Path(out)
    exe = freefem_binary(freefem)
    scene_path = export / "scene.json"
    if not scene_path.exists():
        raise SolveError(f"missing {scene_path} (expected an `sdcrack mesh SCENE --out DIR` export)")
    try:
        scene = json.loads(scene_path.read_text())
        name, f_src, g_src = scene["name"], scene["f"], scene["g"]
        levels, exact = scene["levels"], scene.get("exact")
        normal = scene["crack"]["normal"]
    except (ValueError, KeyError, TypeError) as e:
        raise SolveError(f"{scene_path}: malformed scene ({e})")
    if out.exists() and not overwrite:
        raise SolveError(f"{out} exists; refusing to overwrite earlier results (use --overwrite)")
    f_ff, g_ff = to_freefem(f_src), to_freefem(g_src)
    with sdresults.staged_folder(out) as tmp:
        cases, fields_data = [], []
        for level in levels:
            t0 = time.perf_counter()
            lv = read_level(export, level)
            work = tmp / f"work_level{level}"
            work.mkdir()
            u, lam, info, t_ff = run_level(exe, lv, f_ff, g_ff, work)
            case = {
                "level": level,
                "h": lv["meta"]["h"],
                "unknowns": int(len(u)),
                "iterations": int(info["iterations"]),
                "active": int(info["active"]),
                "kkt": {k: float(info[k]) + 0.0 for k in ("equations", "primal", "dual", "complementarity")},
            }
            with open(tmp / f"u_level{level}.txt", "w") as fu:
                fu.write("".join(f"{v:.17g}\n" for v in u))
            if exact:
                case["errors"] = exact_errors(lv, u, exact, normal)
            case["timings_s"] = {"freefem": t_ff, "total": time.perf_counter() - t0}
            cases.append(case)
            if fields:  # multipliers at the crack nodes (tip a → tip b; 0 at the tips)
                crack = lv["crack"]
                lam_nodes = np.zeros(len(crack))
                lam_nodes[crack[:, 0] != crack[:, 1]] = lam
                fields_data.append((level, {
                    "xy": lv["xy"], "tri": lv["tri"], "crack": crack,
                    "point": {"u": u, "p": vertex_gradient(lv["xy"], lv["tri"], u)},
                    "crack_fields": {"jump": u[crack[:, 0]] - u[crack[:, 1]], "multiplier": lam_nodes}}))
            if not keep_work:
                shutil.rmtree(work)
        if fields:
            try:
                import sdfields
            except ImportError as e:
                raise SolveError(f"--fields needs h5py: apt-get install -y python3-h5py ({e})")
            sdfields.write_fields(tmp, fields_data)
        summary = sdresults.write_summary(tmp, name, "freefem", cases)
    return summary


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("export", help="folder written by `sdcrack mesh SCENE --out DIR`")
    ap.add_argument("--out", required=True, help="result folder (summary.json, u_level{L}.txt)")
    ap.add_argument("--freefem", default="FreeFem++", help="FreeFem++ executable")
    ap.add_argument("--keep-work", action="store_true", help="keep FreeFEM inputs/logs in OUT")
    ap.add_argument("--overwrite", action="store_true", help="replace an existing OUT")
    ap.add_argument("--fields", action="store_true", help="also write fields.h5 + fields.xdmf")
    a = ap.parse_args(argv)
    try:
        # absolute paths: FreeFEM runs with its work folder as the current directory
        s = solve(Path(a.export).resolve(), Path(a.out).resolve(), a.freefem, a.keep_work, a.overwrite, a.fields)
    except SolveError as e:
        print(f"solve.py: error: {e}", file=sys.stderr)
        return 1
    except Exception as e:  # noqa: BLE001 — one line at the edge
        print(f"solve.py: error: {type(e).__name__}: {e}", file=sys.stderr)
        return 1
    for c in s["cases"]:
        err = c.get("errors", {})
        print(f"level {c['level']}: h={c['h']:.4g} unknowns={c['unknowns']} iterations={c['iterations']} "
              + " ".join(f"{k}={v:.3e}" for k, v in err.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
