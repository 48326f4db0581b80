"""The load rule shared by the two references (compare/sdshared/sdquad.py) and its use by each.

The rule: exact to degree 16, fully symmetric (so the physical points do not depend on how a tool
orders a cell's vertices), interior points with positive weights, basix's Xiao–Gimbutas rule.
FreeFEM reads the table solve.py writes bit for bit; both tools integrate a non-polynomial load on
triangles given in several vertex orders to the numpy value of the same rule (round-off).

Run: /usr/bin/python3 -m pytest references/tests/test_load_quadrature.py -q
"""

import itertools
import math
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
REFS = HERE.parent
from sdshared import sdexpr
from sdshared import sdquad
from output_checks import load_module



# Two counter-clockwise triangles, each listed in its three rotations (FreeFEM rejects clockwise
# triangles) and, for dolfinx, clockwise too, and a load far from polynomial on them.
TRIANGLES = [np.array([[-0.3, 0.1], [0.9, 0.25], [0.2, 1.1]]), np.array([[0.0, -1.0], [1.0, -1.0], [0.0, 0.0]])]
ROTATIONS = [(0, 1, 2), (1, 2, 0), (2, 0, 1)]
ORDERS = ROTATIONS + [(0, 2, 1)]
F_SRC = "exp(2*x)*sin(5*y) + sign(y)"


def numpy_load(tri, f):
    """∫_T f φ_k for the P1 basis functions of the vertices of `tri` (3×2), with sdquad's rule."""
    p, w = sdquad.load_rule()
    lam = np.column_stack([1 - p.sum(axis=1), p])
    X = lam @ tri
    e1, e2 = tri[1] - tri[0], tri[2] - tri[0]
    det = abs(e1[0] * e2[1] - e1[1] * e2[0])
    return det * (w * f(X[:, 0], X[:, 1])) @ lam


def test_rule_is_exact_symmetric_and_interior():
    p, w = sdquad.load_rule()
    assert sdquad.LOAD_DEGREE == 16 and p.shape == (55, 2) and w.shape == (55,)
    lam = np.column_stack([1 - p.sum(axis=1), p])
    assert w.min() > 0 and abs(w.sum() - 0.5) < 1e-15
    assert lam.min() > 3e-3                      # strictly inside: data never evaluated on an edge
    for a in range(17):                          # exact for x^a y^b, a + b <= 16
        for b in range(17 - a):
            exact = math.factorial(a) * math.factorial(b) / math.factorial(a + b + 2)
            assert abs(np.sum(w * p[:, 0] ** a * p[:, 1] ** b) - exact) < 1e-15, (a, b)
    for perm in itertools.permutations(range(3)):  # S3-invariant: same points, same weights
        q = lam[:, perm]
        d = np.abs(q[:, None, :] - lam[None, :, :]).max(axis=2)
        j = d.argmin(axis=1)
        assert d.min(axis=1).max() < 1e-15 and np.array_equal(w[j], w) and len(set(j)) == len(j)


def test_rule_is_basix_xiao_gimbutas():
    """The table is basix 0.5.1's degree-16 rule (what FFCx uses for quadrature_degree 16)."""
    basix = pytest.importorskip("basix")
    bp, bw = basix.make_quadrature(basix.CellType.triangle, 16)
    p, w = sdquad.load_rule()
    d = np.abs(p[:, None, :] - bp[None, :, :]).max(axis=2)
    j = d.argmin(axis=1)
    assert len(set(j)) == len(bw) == len(w) and d.min(axis=1).max() < 1e-15
    assert np.abs(bw[j] - w).max() < 1e-17


@pytest.mark.skipif(shutil.which("FreeFem++") is None, reason="FreeFem++ not installed")
def test_freefem_uses_the_rule(tmp_path):
    """FreeFEM reads solve.py's table bit for bit, and its load over the two triangles, whichever
    vertex comes first, is the numpy value of the rule."""
    ff = load_module("freefem_solve_q", REFS / "freefem" / "solve.py")
    f_ff = sdexpr.to_freefem(sdexpr.parse(F_SRC))
    lines = ['load "qf11to25"', ff.load_rule_edp(), "QF2 qfLoad(loadRuleDegree, loadRuleTable);",
             f"func f = {f_ff};", "cout.precision(17);",
             "for (int i = 0; i < loadRuleTable.n; i++) cout << \"Q \" << loadRuleTable(i, 0) << \" \""
             " << loadRuleTable(i, 1) << \" \" << loadRuleTable(i, 2) << endl;"]
    expected = []
    for t, tri in enumerate(TRIANGLES):
        for k, order in enumerate(ROTATIONS):
            v = tri[list(order)]
            msh = tmp_path / f"t{t}_{k}.msh"
            msh.write_text("3 1 3\n" + "".join(f"{x:.17g} {y:.17g} 1\n" for x, y in v)
                           + "1 2 3 0\n1 2 1\n2 3 1\n3 1 1\n")
            lines += [f'{{ mesh Th = readmesh("{msh}"); fespace Vh(Th, P1);',
                      "  varf l(u, w) = int2d(Th, qft = qfLoad)(f * w); real[int] F = l(0, Vh);",
                      '  cout << "F"; for (int i = 0; i < 3; i++) cout << " " << F[i]; cout << endl; }']
            expected.append(numpy_load(v, sdexpr.to_numpy(sdexpr.parse(F_SRC))))
    (tmp_path / "q.edp").write_text("\n".join(lines) + "\n")
    env = dict(os.environ)
    env.setdefault("FF_LOADPATH", "/usr/lib/freefem++")
    out = subprocess.run(["FreeFem++", "-nw", "-ns", "-v", "0", str(tmp_path / "q.edp")], env=env,
                         capture_output=True, text=True, check=True).stdout.splitlines()
    table = np.array([[float(t) for t in l.split()[1:]] for l in out if l.startswith("Q ")])
    p, w = sdquad.load_rule()
    assert np.array_equal(table, np.column_stack([2 * w, p]))
    loads = [np.array([float(t) for t in l.split()[1:]]) for l in out if l.startswith("F ")]
    assert len(loads) == len(expected)
    for got, want in zip(loads, expected):
        assert np.abs(got - want).max() <= 1e-14 * np.abs(want).max(), (got, want)


def test_dolfinx_uses_the_rule():
    """dolfinx's load form (load_measure) over the two triangles, in every vertex order, is the
    numpy value of the rule."""
    pytest.importorskip("dolfinx")
    import dolfinx
    import dolfinx.fem.petsc  # noqa: F401
    import ufl
    from mpi4py import MPI

    dsolve = load_module("dolfinx_solve_q", REFS / "dolfinx" / "solve.py")
    for tri in TRIANGLES:
        for order in ORDERS:
            v = tri[list(order)]
            domain = ufl.Mesh(ufl.VectorElement("Lagrange", ufl.triangle, 1))
            mesh = dolfinx.mesh.create_mesh(MPI.COMM_SELF, np.array([[0, 1, 2]], dtype=np.int64), v, domain)
            V = dolfinx.fem.FunctionSpace(mesh, ("Lagrange", 1))
            f = sdexpr.to_ufl(sdexpr.parse(F_SRC), ufl.SpatialCoordinate(mesh))
            form = dolfinx.fem.form(f * ufl.TestFunction(V) * dsolve.load_measure(),
                                    form_compiler_params=dsolve.NORM_FFCX)
            b = dolfinx.fem.petsc.assemble_vector(form).getArray()
            xyz = V.tabulate_dof_coordinates()[:, :2]
            dof = [int(np.argmin(np.abs(xyz - x).sum(axis=1))) for x in v]
            want = numpy_load(v, sdexpr.to_numpy(sdexpr.parse(F_SRC)))
            assert np.abs(b[dof] - want).max() <= 1e-14 * np.abs(want).max(), (b[dof], want)
