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
                 "pressure_l2": "nodal pressure error (discrete L²(Γc))",
                 # the smooth-domain method's (summary.json's names)
                 "stress_l2": "‖σ − σ_h‖_L² (SDM, raw σ_h)", "stress_sym_l2": "‖σ − sym σ_h‖_L² (SDM)",
                 "stress_energy": "‖σ − σ_h‖_A (SDM)", "projected_u_l2": "‖P0u − u_h‖_L² (SDM)",
                 "u_star_l2": "‖u − u*‖_L² (SDM)", "rotation_l2": "‖γ − γ_h‖_L² (SDM)",
                 "asymmetry_l2": "‖as σ_h‖_L² (SDM)"}


def expected_order(quantity, s):
    """(order, reason) of a series of `quantity` ("sif" for every K) at regularity s."""
    base = "sif" if quantity.startswith("K_") else quantity
    order = ORDER_PER_S[base] * s
    return order, f"{REASON[base]}: s = {s:g}, order {order:g}"


def threshold(order):
    return theory.threshold(order)


# ------------------------------------------------------------------ the smooth-domain method's
# The AFW element (σ rows in BDM1, u ∈ P0², γ ∈ P0) on the uncracked mesh, the crack's normal
# traces constrained (docs/design.md). Orders in s as above (s = 1/2 at a √r tip on uniform
# meshes, 1 graded with β < 1/2 or smooth), docs/elasticity.md "Expected orders of the SDM":
#
# * stress_l2, stress_sym_l2, stress_energy, rotation_l2: s. AFW's quasi-optimality
#   ‖σ − σ_h‖ + ‖γ − γ_h‖ ≤ C inf (‖σ − τ_h‖ + ‖γ − η_h‖) (Arnold–Falk–Winther 2007, with the
#   crack's normal-trace constraint a closed convex cone of the same space: Falk's lemma for the
#   mixed variational inequality, whose consistency term vanishes because the canonical BDM1
#   interpolant keeps σ_νν ≤ 0 and σ_tν = 0 edge by edge: its normal-trace dofs are the moments of
#   σν against P1(e)), and BDM1/P0 approximate σ ∈ H^s, γ ∈ H^s to h^s. sym σ_h − σ is the
#   symmetric part of σ_h − σ (no larger); ‖as σ_h‖ = ‖as(σ_h − σ)‖ ≤ √2 ‖σ_h − σ‖: s too.
# * u_l2 (P0): min(1, 2s). ‖u − u_h‖ ≤ ‖u − P0u‖ + ‖P0u − u_h‖ = O(h |u|₁) + O(h^{2s}).
# * projected_u_l2: 2s, by duality: ‖P0u − u_h‖ ≤ C h^s (‖σ − σ_h‖ + ‖γ − γ_h‖) (the dual
#   problem with data P0u − u_h has the same r^{1/2} tip: its σ, γ are approximated to h^s).
# * u_star_l2: min(2s, 1 + s) = 2s for s ≤ 1. u − u* = (u − P0u − ∇̄u (x − x_T)) + (P0u − u_h)
#   + (∇̄u − mean_T(Aσ_h) − γ_h J)(x − x_T): the first is the element-wise P1 error in L²,
#   h^{1+s}; the second h^{2s}; the third ≤ h (‖σ − σ_h‖ + ‖γ − γ_h‖) = h^{1+s}.
# * opening_l2, slip_l2: 2s − 1/2. Subtract the continuous equation from the discrete one tested
#   with a crack edge's normal (tangential) basis function Ψ_{e,a} (support: e's two triangles ω_e):
#   ⟨λ_h − λ, hat_a⟩_e = −(A(σ_h − σ), Ψ) − (u_h − P0u, div Ψ) − (γ_h − γ, as Ψ) (div Ψ ∈ P0 lets
#   P0u replace u). With |Ψ| ~ 1, ‖Ψ‖ ~ h, ‖div Ψ‖ ~ 1, and the P1(e) norm equivalence
#   ‖w‖_{L²(e)} ~ h^{-1/2} max_a |⟨w, hat_a⟩| (an inverse estimate), per edge
#   ‖Π_e λ − λ_h‖_{L²(e)} ≤ C h^{-1/2} (h ‖σ − σ_h‖_{ω_e} + ‖P0u − u_h‖_{ω_e} + h ‖γ − γ_h‖_{ω_e});
#   squared and summed: h^{-1/2} (h^{1+s} + h^{2s}) = h^{2s − 1/2}, and ‖λ − Π λ‖ (P1 on each
#   edge of a √r opening) is h^{min(1, …)}, no lower. That is ½ on uniform meshes and 3/2 graded
#   (quasi-uniform meshes; on graded ones h_e near the tip is smaller, and the argument holds with
#   the local h_e in place of h where the local errors scale with h_e, which is what the grading
#   makes them do — not a complete proof there). An independent numpy pilot of the method measured
#   1.0 uniform and ~1.8 graded: the bound is below both.
# * pressure_l2 = ‖p_h − p‖_{L²(Σ)}: the trace of σ_h − σ on Σ by the same inverse estimate is
#   h^{s − 1/2}: 0 on uniform meshes. Printed, not judged.
SDM_ORDER = {
    "stress_l2": lambda s: s, "stress_sym_l2": lambda s: s, "stress_energy": lambda s: s,
    "rotation_l2": lambda s: s, "asymmetry_l2": lambda s: s,
    "u_l2": lambda s: min(1.0, 2 * s), "projected_u_l2": lambda s: 2 * s,
    "u_star_l2": lambda s: min(2 * s, 1 + s),
    "opening_l2": lambda s: 2 * s - 0.5, "slip_l2": lambda s: 2 * s - 0.5,
    "sif": lambda s: 2 * s,
}

SDM_REASON = {
    "stress_l2": "AFW's quasi-optimality (the crack's cone kept by the BDM1 interpolant) and "
                 "BDM1's approximation of σ ∈ H^s: h^s",
    "stress_sym_l2": "sym σ_h − σ is the symmetric part of σ_h − σ: h^s",
    "stress_energy": "the compliance norm is equivalent to L²: h^s",
    "rotation_l2": "AFW's quasi-optimality, P0's approximation of γ ∈ H^s: h^s",
    "asymmetry_l2": "‖as σ_h‖ = ‖as(σ_h − σ)‖ ≤ √2 ‖σ_h − σ‖: h^s",
    "u_l2": "‖u − P0u‖ + ‖P0u − u_h‖ = h + h^(2s): h^min(1, 2s)",
    "projected_u_l2": "duality: ‖P0u − u_h‖ ≤ C h^s (‖σ − σ_h‖ + ‖γ − γ_h‖) = h^(2s)",
    "u_star_l2": "the element-wise P1 error h^(1+s), ‖P0u − u_h‖ h^(2s) and h (‖σ − σ_h‖ + "
                 "‖γ − γ_h‖): h^min(2s, 1+s)",
    "opening_l2": "the multiplier's error equation on a crack edge's two triangles and P1(e)'s "
                  "inverse estimate: h^(-1/2) (h^(1+s) + h^(2s)) = h^(2s − 1/2)",
    "slip_l2": "the tangential dofs' error equation, as the opening: h^(2s − 1/2)",
    "sif": "the interaction integral is a linear functional of σ_h, ∇_h u on a ring away from "
           "the tip: by duality its error is bounded by h^s · h^s = h^(2s)",
}

SDM_JUDGED = ("stress_l2", "stress_sym_l2", "stress_energy", "u_l2", "projected_u_l2", "u_star_l2",
              "rotation_l2", "asymmetry_l2", "opening_l2", "slip_l2")


def sdm_expected_order(quantity, s):
    """(order, reason) of an SDM series of `quantity` (summary.json's error names; "K_…" for a
    SIF) at regularity s."""
    base = "sif" if quantity.startswith("K_") else quantity
    order = SDM_ORDER[base](s)
    return order, f"{SDM_REASON[base]}: s = {s:g}, order {order:g}"
