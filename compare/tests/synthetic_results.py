"""A synthetic sdcrack results folder (OUT/<scene>/: scene.toml, summary.json, fields.h5) that the
compare tool judges like a real one, without the sdcrack binary: the tests of the p-space axis
and the byte-for-byte check that a continuous-p folder is reported as before.

The fields are built from the scene's exact solution on the structured SW–NE meshes of [-1, 1]²
cut along the crack (-1/2, 1/2) × {0} (references/tests/fake_export.py), as a discretisation of
that quality would give them:
* u: the P1 interpolant of the exact u, each copy of a crack vertex taking its own face's value
  (broken u on the cracked mesh; continuous u on the uncut mesh takes the mean of the faces);
* p at the u dofs: the exact ∇u at the vertex, from each copy's own face for the broken-tangential
  p space (the two copies differ in their tangential component), the mean of the faces for the
  continuous p (one value on both copies), bubble 0;
* λ: the exact jump [u] at the crack nodes (P1);
* where the crack opens, a continuous u (which cannot open it) has u, p and λ off by STALL
  everywhere: its errors stall, as the scene's declared expected failure says;
* at δ > 0: u + δ cos(y), p (1 + δ), λ (1 + 3δ) (so ‖x_δ − x_0‖ = O(δ)).
Every reported error is the compare tool's own recomputation from these fields (exact.py), so the
independent-errors check holds and the rates are those of the fields: where the crack opens, a
continuous p is O(1) off in a strip of width h (order 1/2), a broken-tangential one is not.
"""
import json
import math
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

import fake_export as fe
from sdcompare_lib import exact, read
from sdcompare_lib.cases import CaseKey

CRACK = [(-0.5, 0.0), (0.5, 0.0)]
# smooth on each face, open on the crack ([u] = 2 m³ > 0), tangential ∂u/∂x jumps, ∂u/∂y = 0 on
# both faces (tools/untuned-scenes/smooth-open.toml on [-1, 1]²)
OPEN = {"u": "sign(y)*max(0.25-x^2,0)^3*cos(y)", "jump": "2*max(0.25-x^2,0)^3",
        "f": "sign(y)*cos(y)*(max(0.25-x^2,0)^3 + 6*max(0.25-x^2,0)^2 - 24*x^2*max(0.25-x^2,0))"}
# smooth and closed everywhere (scenes/closed-exact.toml)
CLOSED = {"u": "sin(pi*x)*cos(pi*y) - y", "jump": "0", "f": "2*pi^2*sin(pi*x)*cos(pi*y)"}
EXECUTABLE = "/opt/sdcrack/bin/sdcrack"
# The fields are interpolants of the exact solution, not a solution of the method's discrete
# system, which the discrete certificate (sdcompare_lib/certificate.py) would rightly FAIL: the
# cases claim UNKNOWNS_SCALE × 3 unknowns per u dof, above its limit (≥ 3 × 100 × 81 > 2·10⁴ from
# level 0 on), so that its check reads "not applicable" here and the folders judge the other
# checks. The scale keeps the unknowns' ratios between levels (rates per N). The certificate's
# own tests are compare/tests/test_certificate.py, on real sdcrack results.
UNKNOWNS_SCALE = 100
# a continuous u cannot open the crack: its fields (u, p and λ) are this far off everywhere, so its
# errors stall (the declared expected failure of an open crack)
STALL = 1e-2


def scene_text(name, solution, levels, u_spaces, multipliers, p_masses, p_spaces, deltas,
               xfail_continuous):
    """The scene file the folder's summary says was run (p_spaces None: no such line)."""
    def toml_list(v):
        return "[" + ", ".join(json.dumps(x) if isinstance(x, str) else repr(float(x))
                               if not isinstance(x, int) else str(x) for x in v) + "]"
    lines = [f'name = "{name}"', 'description = "synthetic results folder (compare/tests)"', "",
             "[geometry]", "domain = { rectangle = [[-1.0, -1.0], [1.0, 1.0]] }",
             "crack = { segment = [[-0.5, 0.0], [0.5, 0.0]] }", "", "[data]",
             f'f = "{solution["f"]}"', f'g = "{solution["u"]}"', "", "[exact]",
             f'u = "{solution["u"]}"', f'jump = "{solution["jump"]}"', "", "[discretization]",
             "cells = [8, 8]", f"levels = {toml_list(levels)}", f"u_spaces = {toml_list(u_spaces)}",
             f"multipliers = {toml_list(multipliers)}", f"p_mass = {toml_list(p_masses)}"]
    if p_spaces is not None:
        lines.append(f"p_spaces = {toml_list(p_spaces)}")
    lines += [f"deltas = {toml_list(deltas)}", "", "[outputs]", 'fields = ["u", "p", "lambda"]',
              "references = []"]
    if xfail_continuous:
        lines += ["", "[[verification.expected_failure]]", 'u_space = "continuous"',
                  'reason = "continuous P1 u cannot carry the jump [u] > 0 where the crack opens"']
    return "\n".join(lines) + "\n"


def level_meshes(level, n0=8):
    """{"continuous": (points, tris), "broken": (points, tris)}, the crack nodes (I, 2), the
    (plus, minus) rows and the side of each vertex of the cracked mesh (+1 the original of a
    crack vertex, −1 its copy, 0 elsewhere)."""
    xy_u, tri_u = fe.structured_level(n0 * 2 ** level)
    chain = fe.chain_on_polyline(xy_u, tri_u, CRACK)
    xy, tri, rows, _, _, _ = fe.cut_mesh(xy_u, tri_u, [chain])
    side = np.zeros(len(xy))
    interior = rows[rows[:, 0] != rows[:, 1]]
    side[interior[:, 0]], side[interior[:, 1]] = 1.0, -1.0
    return {"continuous": (xy_u, tri_u), "broken": (xy, tri)}, xy_u[chain], side


def face_values(ex, xy, side):
    """(u, ∂u/∂x, ∂u/∂y) at the vertices, a crack copy on its own face (signed zero: on_face)."""
    y = np.where(side < 0, -0.0, np.where(side > 0, 0.0, xy[:, 1]))
    return ex.u_grad(xy[:, 0], y)


def fields_of(ex, u_space, p_space, mesh, side, stall):
    """(u (N,), p (N, 2)) of one case at δ = 0 (module docstring); a continuous u `stall` off."""
    xy = mesh[0]
    if u_space == "continuous":  # the uncut mesh: a crack vertex takes the mean of its faces
        crack = (np.abs(xy[:, 1]) == 0.0) & (np.abs(xy[:, 0]) < 0.5)
        plus, minus = face_values(ex, xy, 1.0 * crack), face_values(ex, xy, -1.0 * crack)
        mean = [np.where(crack, 0.5 * (a + b), a) + stall for a, b in zip(plus, minus)]
        return mean[0], np.column_stack(mean[1:])
    u, px, py = face_values(ex, xy, side)
    if p_space == "continuous":  # one p on both copies: the mean of the faces
        twin = {}
        for s in (1.0, -1.0):
            twin[s] = face_values(ex, xy, np.where(side != 0, s, side))
        px = np.where(side != 0, 0.5 * (twin[1.0][1] + twin[-1.0][1]), px)
        py = np.where(side != 0, 0.5 * (twin[1.0][2] + twin[-1.0][2]), py)
    return u, np.column_stack([px, py])


def plan_cases(levels, u_spaces, multipliers, p_masses, p_spaces, deltas):
    """The product of the plan minus (continuous u, broken-tangential p), in the solver's order."""
    return [(lv, u, m, pm, ps, d) for lv in levels for u in u_spaces for m in multipliers
            for pm in p_masses for ps in p_spaces for d in deltas
            if not (u == "continuous" and ps == "broken-tangential")]


def write_results(out, name="pspace", solution=OPEN, levels=(0, 1, 2),
                  u_spaces=("continuous", "broken"), multipliers=("M1",),
                  p_masses=("consistent",), p_spaces=("continuous", "broken-tangential"),
                  deltas=(1e-2, 0.0), p_space_keys=True, xfail_continuous=None):
    """Writes OUT/<name>/ and returns its path. p_space_keys=False writes a folder of an sdcrack
    older than the p space (no plan p_spaces, case p_space, attribute or scene line; continuous p
    only)."""
    import h5py

    folder = os.path.join(out, name)
    os.makedirs(folder)
    xfail = solution is OPEN if xfail_continuous is None else xfail_continuous
    stall = STALL if solution is OPEN else 0.0
    with open(os.path.join(folder, "scene.toml"), "w", encoding="utf-8") as fh:
        fh.write(scene_text(name, solution, levels, u_spaces, multipliers, p_masses,
                            list(p_spaces) if p_space_keys else None, deltas, xfail))
    ex = exact.ExactSolution(solution["u"], jump=solution["jump"], f=solution["f"], crack=CRACK)
    cases = []
    with h5py.File(os.path.join(folder, "fields.h5"), "w") as f5:
        for lv in levels:
            meshes, crack_points, side = level_meshes(lv)
            h = 2.0 * math.sqrt(2.0) / (8 * 2 ** lv)
            for u_space, (pts, tris) in meshes.items():
                f5[f"meshes/level{lv}-{u_space}/points"] = np.column_stack([pts, 0 * pts[:, 0]])
                f5[f"meshes/level{lv}-{u_space}/triangles"] = tris
            lam0 = ex.jump(crack_points, np.array([0.0, 1.0]))
            for (lv_, u_space, m, pm, ps, delta) in plan_cases([lv], u_spaces, multipliers,
                                                                p_masses, p_spaces, deltas):
                pts, tris = meshes[u_space]
                u0, p0 = fields_of(ex, u_space, ps, meshes[u_space], side, stall)
                u, p = u0 + delta * np.cos(pts[:, 1]), p0 * (1 + delta)
                lam = (lam0 + (stall if u_space == "continuous" else 0.0)) * (1 + 3 * delta)
                bubble = None if pm == "lumped" else np.zeros((len(tris), 2))
                grid = CaseKey(level=lv, u_space=u_space, multiplier=m, p_mass=pm, p_space=ps,
                               delta=float(delta)).case_name()
                g = f5.create_group(f"cases/{grid}")
                g["mesh"] = h5py.SoftLink(f"/meshes/level{lv}-{u_space}")
                g["u"], g["p"] = u, np.column_stack([p, 0 * u])
                if bubble is not None:
                    g["p_bubble"] = bubble
                g["crack/points"] = np.column_stack([crack_points, 0 * crack_points[:, 0]])
                g["crack/segments"] = np.column_stack([np.arange(len(crack_points) - 1),
                                                       np.arange(1, len(crack_points))])
                g["crack/lambda"] = lam
                attrs = {"level": lv, "h": h, "u_space": u_space, "multiplier": m, "p_mass": pm,
                         "delta": delta}
                if p_space_keys:
                    attrs["p_space"] = ps
                g.attrs.update(attrs)
                errors = exact.solver_case_errors(pts, tris, u, p, bubble, crack_points, lam, ex,
                                                  p_mass=pm, crack_segments=g["crack/segments"][()])
                errors.pop("bubble")
                case = {"level": lv, "h": h, "u_space": u_space, "multiplier": m, "p_mass": pm,
                        "delta": delta, "unknowns": UNKNOWNS_SCALE * 3 * len(pts), "multipliers": len(crack_points),
                        "iterations": 2, "status": "converged", "converged": True,
                        "kkt": {"equations": 1e-15, "primal": 0.0, "dual": 0.0,
                                "complementarity": 1e-16},
                        "active_multipliers": len(crack_points) - 2, "regularized_pivots": 0,
                        "timings_s": {"assembly": 0.01 * (lv + 1), "factorization": 0.02},
                        "errors": errors, "fields_grid": grid}
                if p_space_keys:
                    case["p_space"] = ps
                cases.append(case)
    plan = {"levels": list(levels), "u_spaces": list(u_spaces), "multipliers": list(multipliers),
            "p_masses": list(p_masses), "deltas": list(deltas)}
    if p_space_keys:
        plan["p_spaces"] = list(p_spaces)
    summary = {"scene": name, "description": "synthetic", "kkt_tolerance": 1e-10,
               "all_converged": True, "plan": plan,
               "provenance": {"executable": EXECUTABLE, "sdcrack_version": "0.0.0-test",
                              "command_line": [EXECUTABLE, "run", "scene.toml"]},
               "recomputation_file": "fields.h5", "cases": cases}
    save_summary(folder, summary)
    return folder


def load_summary(folder):
    """folder/summary.json, read as the compare tool reads it."""
    return read.load_json(os.path.join(folder, "summary.json"))


def save_summary(folder, summary):
    with open(os.path.join(folder, "summary.json"), "w", encoding="utf-8") as fh:
        json.dump(summary, fh, indent=1)
