"""The expected orders of the elastic references' series (vector P1 on the cracked mesh,
docs/elasticity.md), as multiples of the regularity s of the exact u (theory.regularity: s = 1 for
a smooth u or a tip graded with β < 1/2, measured from the P1 interpolation error's rate; s = 1/2
at an r^{1/2} tip on uniform meshes). Rates are per halving of h (the largest triangle's
diameter) on uniform meshes, of N^{-1/2} (N = 2 × the cracked mesh's vertices, the unknowns before
constraints) on graded ones. Each order comes with its reason, which the report prints.

* u_l2 2s, u_h1 s, sigma_l2 s: P1's orders (theory.P1_ORDER_PER_S; σ(u_h) − σ is a bounded
  linear map of ∇(u_h − u), so it has the order of the broken H¹ seminorm). The contact
  constraint is imposed at the nodes, which P1's interpolant satisfies, so the variational
  inequality's error has the order of the best approximation (Falk's lemma's consistency term
  vanishes for an interpolant that is admissible).
* opening_l2, slip_l2 3s/2: the trace of the error on Γc, by the multiplicative trace inequality
  ‖v‖²_{L²(Γc)} ≤ C ‖v‖_{L²(Ω±)} ‖v‖_{H¹(Ω±)} on each side's Lipschitz part (Ω split along the
  crack and its extension): h^{2s/2 + s/2} = h^{3s/2}, i.e. 3/4 on uniform meshes (the
  interpolant of a √r jump alone reaches h, the tip segment's ∫_0^h r dr), 3/2 on graded ones.
  A proven lower bound, not the measured order: a bug that halves the order fails it.
* sif 2s: the interaction integral is a linear functional of u_h whose weight lives on a ring
  away from the tip; by duality (the dual problem has the same r^{1/2} tip) its error is bounded
  by ‖u − u_h‖_{H¹} · ‖z − z_h‖_{H¹} = h^s · h^s.
* pressure (nodal force / m_j): measured and printed, not judged (no order of a nodal pressure
  in the discrete L²(Γc) is proven for the active-set P1 problem).
"""
from . import theory

ORDER_PER_S = {"u_l2": 2.0, "u_h1": 1.0, "sigma_l2": 1.0, "opening_l2": 1.5, "slip_l2": 1.5,
               "sif": 2.0}

REASON = {
    "u_l2": "P1 on the cracked mesh: interpolation and the duality (Aubin–Nitsche) gain give h^(2s)",
    "u_h1": "P1 on the cracked mesh: the energy error has the best approximation's order h^s",
    "sigma_l2": "σ(u_h) − σ is a bounded linear map of ∇(u_h − u): the order h^s of the broken H¹ "
                "seminorm",
    "opening_l2": "the trace of the error on Γc: ‖e‖_{L²(Γc)}² ≤ C ‖e‖_{L²} ‖e‖_{H¹} on each side "
                  "gives h^(2s/2 + s/2) = h^(3s/2), a proven bound",
    "slip_l2": "the trace of the error on Γc: ‖e‖_{L²(Γc)}² ≤ C ‖e‖_{L²} ‖e‖_{H¹} on each side "
               "gives h^(3s/2), a proven bound",
    "sif": "the interaction integral is a linear functional of u_h on a ring away from the tip: "
           "by duality its error is bounded by h^s · h^s = h^(2s)",
}

QUANTITY_TEXT = {"u_l2": "‖u_h − u‖_L²", "u_h1": "‖∇(u_h − u)‖_L²", "sigma_l2": "‖σ(u_h) − σ‖_L²",
                 "opening_l2": "‖[u_h·ν] − [u·ν]‖_L²(Γc)", "slip_l2": "‖[u_h·τ] − [u·τ]‖_L²(Γc)",
                 "pressure_l2": "nodal pressure error (discrete L²(Γc))"}


def expected_order(quantity, s):
    """(order, reason) of a series of `quantity` ("sif" for every K) at regularity s."""
    base = "sif" if quantity.startswith("K_") else quantity
    order = ORDER_PER_S[base] * s
    return order, f"{REASON[base]}: s = {s:g}, order {order:g}"


def threshold(order):
    return theory.threshold(order)
