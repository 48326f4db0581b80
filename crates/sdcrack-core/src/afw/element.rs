//! The lowest-order Arnold–Falk–Winther element on one triangle (docs/design.md, "Element"):
//! the BDM1 vector basis λ_a w of each (edge, end) pair, its values and its constant divergence,
//! and the element's local matrices for the tensor basis Ψ = d ⊗ φ (each row of Ψ is d_i φ):
//! the compliance mass (AΨ_p, Ψ_q), the divergence block (div Ψ_p, v) against u ∈ P0² and the
//! weak-symmetry block (as Ψ_p, η) against γ ∈ P0.
//!
//! Local numbering: edge i of the triangle is the one opposite its vertex i; its two ends are
//! given in the global edge's order ("end slots" 0 and 1), and the local basis function of
//! (edge i, end slot s, direction k) is number 4i + 2s + k.

use crate::elasticity::Material;
use crate::fe::p1::{dot, TriangleGeometry};

/// Number of tensor basis functions of one triangle: 3 edges × 2 ends × 2 directions.
pub const SIGMA_LOCAL: usize = 12;

/// The BDM1 vector basis of one triangle.
#[derive(Clone, Copy, Debug)]
pub struct Bdm1 {
    /// The triangle's geometry (counter-clockwise vertices, ∇λ).
    pub geo: TriangleGeometry,
    /// The local vertex at end slot s of edge i: `ends[i][s]`.
    pub ends: [[usize; 2]; 3],
    /// The constant vector w of (edge i, end slot s): w·n_i = 1, w·n_{e'} = 0 with e' the other
    /// edge of the triangle at that end.
    pub w: [[[f64; 2]; 2]; 3],
}

impl Bdm1 {
    /// The basis of the triangle `vertices` (counter-clockwise) whose edge i (opposite vertex i)
    /// has the global unit normal `normals[i]` and the ends `ends[i]` (local vertices, in the
    /// global edge's order).
    ///
    /// # Panics
    /// If `ends[i]` are not the two vertices other than i (caller bug).
    pub fn new(vertices: [[f64; 2]; 3], normals: [[f64; 2]; 3], ends: [[usize; 2]; 3]) -> Bdm1 {
        let geo = TriangleGeometry::new(vertices);
        let mut w = [[[0.0; 2]; 2]; 3];
        for i in 0..3 {
            for s in 0..2 {
                let a = ends[i][s];
                assert!(
                    a != i && ends[i][1 - s] != i,
                    "edge {i}'s ends {:?}",
                    ends[i]
                );
                // edge i joins a and b; the other edge at a joins a and i: the one opposite b
                let b = ends[i][1 - s];
                w[i][s] = solve2(normals[i], normals[b], [1.0, 0.0]);
            }
        }
        Bdm1 { geo, ends, w }
    }

    /// φ_{i,s} at the point with barycentric coordinates `lambda`.
    pub fn value(&self, i: usize, s: usize, lambda: [f64; 3]) -> [f64; 2] {
        let l = lambda[self.ends[i][s]];
        let w = self.w[i][s];
        [l * w[0], l * w[1]]
    }

    /// div φ_{i,s} = ∇λ_a · w (constant).
    pub fn divergence(&self, i: usize, s: usize) -> f64 {
        dot(self.geo.grad[self.ends[i][s]], self.w[i][s])
    }
}

/// w with n·w = r[0], m·w = r[1].
fn solve2(n: [f64; 2], m: [f64; 2], r: [f64; 2]) -> [f64; 2] {
    let det = n[0] * m[1] - n[1] * m[0];
    [
        (r[0] * m[1] - n[1] * r[1]) / det,
        (n[0] * r[1] - r[0] * m[0]) / det,
    ]
}

/// The local matrices of one triangle for the tensor basis Ψ_p = d_p ⊗ φ_p, p = 4i + 2s + k.
#[derive(Clone, Copy, Debug)]
pub struct LocalMatrices {
    /// (AΨ_p, Ψ_q), symmetric positive definite.
    pub a: [[f64; SIGMA_LOCAL]; SIGMA_LOCAL],
    /// (div Ψ_p, e_r) for r = x, y: `b[r][p]`.
    pub b: [[f64; SIGMA_LOCAL]; 2],
    /// (as Ψ_p, 1).
    pub c: [f64; SIGMA_LOCAL],
}

/// The compliance A as a pair of coefficients: Aσ = (σ − `trace` tr σ I) / (2μ), with
/// `trace` = λ*/(2(μ + λ*)) and λ* the in-plane λ ([`Material::lambda_in_plane`]).
#[derive(Clone, Copy, Debug)]
pub struct Compliance {
    /// 1/(2μ).
    pub inv_two_mu: f64,
    /// λ*/(2(μ + λ*)).
    pub trace: f64,
}

impl Compliance {
    /// The compliance of `m`.
    pub fn of(m: &Material) -> Compliance {
        let lam = m.lambda_in_plane();
        Compliance {
            inv_two_mu: 0.5 / m.mu,
            trace: lam / (2.0 * (m.mu + lam)),
        }
    }

    /// Aσ of a 2 × 2 tensor given row-major [σ_xx, σ_xy, σ_yx, σ_yy].
    pub fn apply(&self, s: [f64; 4]) -> [f64; 4] {
        let tr = self.trace * (s[0] + s[3]);
        [
            (s[0] - tr) * self.inv_two_mu,
            s[1] * self.inv_two_mu,
            s[2] * self.inv_two_mu,
            (s[3] - tr) * self.inv_two_mu,
        ]
    }
}

/// The local matrices of `bdm` with the two directions `directions[i]` of each edge i.
///
/// With Ψ_p = d_p φ_pᵀ, Ψ_p : Ψ_q = (d_p·d_q)(φ_p·φ_q) and tr Ψ_p = d_p·φ_p, so
/// (AΨ_p, Ψ_q) = [(d_p·d_q)(w_p·w_q) − c (d_p·w_p)(d_q·w_q)] ∫ λ_a λ_b / (2μ) with
/// ∫_T λ_a λ_b = |T|(1 + δ_ab)/12 (P1·P1: exact); div Ψ_p = d_p (∇λ_a·w_p) is constant;
/// as Ψ_p = (d_p)_x (φ_p)_y − (d_p)_y (φ_p)_x = ((d_p)_x w_y − (d_p)_y w_x) λ_a, ∫ λ_a = |T|/3.
pub fn local_matrices(
    bdm: &Bdm1,
    directions: &[[[f64; 2]; 2]; 3],
    compliance: Compliance,
) -> LocalMatrices {
    let area = bdm.geo.area;
    let basis: [(usize, [f64; 2], [f64; 2]); SIGMA_LOCAL] = std::array::from_fn(|p| {
        let (i, s, k) = (p / 4, (p / 2) % 2, p % 2);
        (bdm.ends[i][s], directions[i][k], bdm.w[i][s])
    });
    let mut a = [[0.0; SIGMA_LOCAL]; SIGMA_LOCAL];
    let mut b = [[0.0; SIGMA_LOCAL]; 2];
    let mut c = [0.0; SIGMA_LOCAL];
    for (p, &(vp, dp, wp)) in basis.iter().enumerate() {
        for (q, &(vq, dq, wq)) in basis.iter().enumerate() {
            let mass = if vp == vq { area / 6.0 } else { area / 12.0 };
            let inner = dot(dp, dq) * dot(wp, wq) - compliance.trace * dot(dp, wp) * dot(dq, wq);
            a[p][q] = compliance.inv_two_mu * inner * mass;
        }
        let div = dot(bdm.geo.grad[vp], wp);
        b[0][p] = area * dp[0] * div;
        b[1][p] = area * dp[1] * div;
        c[p] = area / 3.0 * (dp[0] * wp[1] - dp[1] * wp[0]);
    }
    LocalMatrices { a, b, c }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::elasticity::PlaneModel;
    use crate::fe::quadrature::triangle_rule;

    /// A skewed triangle (no right angle, no two sides alike) whose edges have normals of both
    /// orientations (edge 0 outward, edges 1 and 2 inward), ends given in a shuffled order.
    fn skewed() -> Bdm1 {
        let v = [[0.1, -0.2], [1.3, 0.15], [0.45, 0.9]];
        let outward = |a: [f64; 2], b: [f64; 2]| {
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let l = dx.hypot(dy);
            [dy / l, -dx / l]
        };
        let n0 = outward(v[1], v[2]);
        let n1 = outward(v[2], v[0]).map(|c| -c);
        let n2 = outward(v[0], v[1]).map(|c| -c);
        Bdm1::new(v, [n0, n1, n2], [[2, 1], [0, 2], [0, 1]])
    }

    fn normals(bdm: &Bdm1) -> [[f64; 2]; 3] {
        // recover n_i from w: n_i·w_{i,s} = 1 and n_i ⟂ the edge
        let v = bdm.geo.vertices;
        std::array::from_fn(|i| {
            let [a, b] = bdm.ends[i].map(|k| v[k]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let l = dx.hypot(dy);
            let n = [dy / l, -dx / l];
            if dot(n, bdm.w[i][0]) > 0.0 {
                n
            } else {
                n.map(|c| -c)
            }
        })
    }

    fn bary_on_edge(bdm: &Bdm1, i: usize, t: f64) -> [f64; 3] {
        // point (1 − t) end0 + t end1 of edge i
        let mut l = [0.0; 3];
        l[bdm.ends[i][0]] = 1.0 - t;
        l[bdm.ends[i][1]] = t;
        l
    }

    #[test]
    fn normal_traces_are_the_hats_of_their_edge_and_zero_elsewhere() {
        let bdm = skewed();
        let n = normals(&bdm);
        for i in 0..3 {
            for s in 0..2 {
                for j in 0..3 {
                    for t in [0.0, 0.3, 1.0] {
                        let trace = dot(bdm.value(i, s, bary_on_edge(&bdm, j, t)), n[j]);
                        let want = if j == i {
                            if s == 0 {
                                1.0 - t
                            } else {
                                t
                            }
                        } else {
                            0.0
                        };
                        assert!(
                            (trace - want).abs() < 1e-13,
                            "φ_({i},{s}) on edge {j} at {t}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_basis_reproduces_linear_vector_fields_from_their_dofs() {
        let bdm = skewed();
        let n = normals(&bdm);
        let field = |x: [f64; 2]| {
            [
                0.3 + 1.7 * x[0] - 0.4 * x[1],
                -1.1 + 0.6 * x[0] + 2.2 * x[1],
            ]
        };
        let v = bdm.geo.vertices;
        let at = |l: [f64; 3]| [0, 1].map(|d| (0..3).map(|k| l[k] * v[k][d]).sum::<f64>());
        for l in [[0.2, 0.5, 0.3], [1.0, 0.0, 0.0], [0.05, 0.05, 0.9]] {
            let mut sum = [0.0; 2];
            for i in 0..3 {
                for s in 0..2 {
                    let dof = dot(field(v[bdm.ends[i][s]]), n[i]);
                    let phi = bdm.value(i, s, l);
                    sum[0] += dof * phi[0];
                    sum[1] += dof * phi[1];
                }
            }
            let want = field(at(l));
            assert!((sum[0] - want[0]).abs() < 1e-13 && (sum[1] - want[1]).abs() < 1e-13);
        }
    }

    /// ∫_T div φ = ∮ φ·n_out: only edge i carries a normal trace, the hat, whose integral is ℓ/2.
    #[test]
    fn the_divergence_satisfies_the_divergence_theorem() {
        let bdm = skewed();
        let n = normals(&bdm);
        let v = bdm.geo.vertices;
        for i in 0..3 {
            let [a, b] = bdm.ends[i].map(|k| v[k]);
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            // outward normal: away from the opposite vertex i
            let mid = [0.5 * (a[0] + b[0]) - v[i][0], 0.5 * (a[1] + b[1]) - v[i][1]];
            let orientation = dot(n[i], mid).signum();
            for s in 0..2 {
                let lhs = bdm.geo.area * bdm.divergence(i, s);
                let rhs = 0.5 * len * orientation;
                assert!((lhs - rhs).abs() < 1e-13, "({i},{s}): {lhs} vs {rhs}");
            }
        }
    }

    /// The local matrices against a degree-2 Gauss rule of the tensors themselves: AΨ_p : Ψ_q
    /// pointwise with [`Compliance::apply`], div Ψ_p from the rows' divergences, as Ψ_p pointwise.
    #[test]
    fn local_matrices_match_a_quadrature_of_the_tensor_basis() {
        let bdm = skewed();
        let rot = |t: f64| [[t.cos(), t.sin()], [-t.sin(), t.cos()]];
        let directions = [rot(0.3), [[1.0, 0.0], [0.0, 1.0]], rot(-1.2)];
        let m = Material::from_young_poisson(2.0, 0.3, PlaneModel::Stress);
        let comp = Compliance::of(&m);
        let lm = local_matrices(&bdm, &directions, comp);
        let rule = triangle_rule(2);
        let tensor = |p: usize, l: [f64; 3]| {
            let (i, s, k) = (p / 4, (p / 2) % 2, p % 2);
            let d = directions[i][k];
            let phi = bdm.value(i, s, l);
            [d[0] * phi[0], d[0] * phi[1], d[1] * phi[0], d[1] * phi[1]]
        };
        let scale = lm.a.iter().flatten().fold(0.0f64, |s, v| s.max(v.abs()));
        for p in 0..SIGMA_LOCAL {
            for q in 0..SIGMA_LOCAL {
                let mut sum = 0.0;
                for (xi, w) in rule.points.iter().zip(&rule.weights) {
                    let l = TriangleGeometry::barycentric(*xi);
                    let ap = comp.apply(tensor(p, l));
                    let tq = tensor(q, l);
                    sum += 2.0 * bdm.geo.area * w * (0..4).map(|r| ap[r] * tq[r]).sum::<f64>();
                }
                assert!((sum - lm.a[p][q]).abs() < 1e-13 * scale, "A[{p}][{q}]");
            }
            let (i, s, k) = (p / 4, (p / 2) % 2, p % 2);
            let d = directions[i][k];
            let div = bdm.divergence(i, s);
            let mut as_sum = 0.0;
            for (xi, w) in rule.points.iter().zip(&rule.weights) {
                let t = tensor(p, TriangleGeometry::barycentric(*xi));
                as_sum += 2.0 * bdm.geo.area * w * (t[1] - t[2]);
            }
            assert!((as_sum - lm.c[p]).abs() < 1e-13);
            for r in 0..2 {
                assert!((bdm.geo.area * d[r] * div - lm.b[r][p]).abs() < 1e-13);
            }
        }
        // symmetric positive definite
        for p in 0..SIGMA_LOCAL {
            assert!(lm.a[p][p] > 0.0);
            for q in 0..p {
                assert!((lm.a[p][q] - lm.a[q][p]).abs() < 1e-15 * scale);
            }
        }
    }
}
