"""The triangle quadrature rule that both references use for the load vector F_i = ∫ f φ_i.

The dolfinx and FreeFEM references solve the same discrete problem only if they assemble the same
load: with different rules (formerly UFL's degree 8 and FreeFEM's qf9pT) their vertex values differed
by up to 2.9e-7 on a coarse mesh (scenes/mixed.toml with cells = [4, 4], level 0). Both now take this
rule: the same points and weights, so the two loads differ by round-off only, whatever the data.

The rule is the fully symmetric Xiao–Gimbutas rule of degree LOAD_DEGREE = 16 on the triangle
(55 points, all strictly inside, positive weights), as tabulated by basix 0.5.1
(`basix.make_quadrature(CellType.triangle, 16)`, the rule FFCx would use for quadrature_degree 16),
written here by orbits so that FreeFEM needs no basix. Full S3 symmetry makes the physical points
independent of how a tool numbers the vertices of a cell (dolfinx and FreeFEM need not agree on it).
Interior points keep data such as sign(y) off the crack and the mesh edges.

Degree 16 integrates the load of every repository scene's level 0 (and of mixed with cells [4, 4])
to round-off, ≤ 4e-15 relative (degree 8: 7e-7, 12: 1e-11, 14: 2e-14 on mixed [4, 4]), so the shared
discrete problem is also the one with the exact load integrals. The data must be smooth on each
triangle for that (the scenes' sign(·) and max(·) kinks lie on mesh lines).

Standard library and numpy only (the FreeFEM reference runs without dolfinx/basix).
"""

import itertools

import numpy as np

LOAD_DEGREE = 16

# Orbits of the degree-16 rule: ("S3", weight) the centroid; ("S21", a, weight) the 3 points with
# barycentric coordinates (a, a, 1 − 2a); ("S111", a, b, weight) the 6 permutations of
# (a, b, 1 − a − b). Weights are per point on the reference triangle (0,0), (1,0), (0,1): they sum
# to its area 1/2 (basix's convention).
_ORBITS_16 = [
    ("S3", 0.023113955157095672),
    ("S21", 0.06667447224023837, 0.006212712797780504),
    ("S21", 0.24132168070137838, 0.020592020534896276),
    ("S21", 0.41279809595522365, 0.020492609893407683),
    ("S21", 0.15006373658703515, 0.014391748351374455),
    ("S21", 0.46954803099668496, 0.013546834733855226),
    ("S21", 0.017041629405718517, 0.001894567619132111),
    ("S111", 0.009664954403660254, 0.41376948582708517, 0.004091105276611069),
    ("S111", 0.030305943355186365, 0.30417944822947973, 0.006991803562326784),
    ("S111", 0.010812972776103751, 0.08960908902270585, 0.0028759349852485795),
    ("S111", 0.10665316053614844, 0.29661537240038294, 0.015823030840991622),
    ("S111", 0.051354315344013114, 0.16976335515028973, 0.008826540523551642),
    ("S111", 0.0036969427073556124, 0.21404877992584728, 0.0023073453198645673),
]


def load_rule():
    """(points, weights) of the load rule on the reference triangle (0,0), (1,0), (0,1): points (55, 2)
    are the reference coordinates (λ1, λ2) of the barycentric triples, weights (55,) sum to 1/2."""
    pts, wts = [], []
    for orbit in _ORBITS_16:
        kind, weight = orbit[0], orbit[-1]
        if kind == "S3":
            triple = (1.0 / 3.0,) * 3
        elif kind == "S21":
            a = orbit[1]
            triple = (a, a, 1.0 - 2.0 * a)
        else:
            a, b = orbit[1], orbit[2]
            triple = (a, b, 1.0 - a - b)
        seen = []
        for perm in itertools.permutations(triple):
            if perm not in seen:
                seen.append(perm)
                pts.append(perm[1:])
                wts.append(weight)
    return np.array(pts), np.array(wts)


def gauss01(n):
    """n-point Gauss–Legendre rule on [0, 1] (weights sum 1): the 1-D building block of both
    references' error quadratures."""
    g, w = np.polynomial.legendre.leggauss(n)
    return (g + 1) / 2, w / 2


# The edge rule of the elastic references' traction load ∫_e t·φ_i ds (docs/elasticity.md): 10-point
# Gauss–Legendre, exact to degree 19 on each boundary edge, all points interior to the edge (a kink
# of t at a corner of Ω is never evaluated).
EDGE_POINTS = 10


def edge_rule():
    """(points, weights) of the traction rule on [0, 1]: EDGE_POINTS Gauss–Legendre points, weights
    summing to 1 (multiply by the edge's length)."""
    return gauss01(EDGE_POINTS)
