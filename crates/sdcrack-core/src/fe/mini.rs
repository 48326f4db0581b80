//! The MINI element for p = ∇u (paper §3: P_B(T) = P1(T) ⊕ R φ_T, vector valued) and the exact
//! static condensation of its bubble.
//!
//! We scale the bubble as b_T = 27 λ_0 λ_1 λ_2 (value 1 at the centroid). With ψ = λ_k e_d and
//! ψ = b_T e_d the element integrals are exact closed forms
//! (∫ λ_0^a λ_1^b λ_2^c = 2|T| a! b! c! / (a+b+c+2)!):
//!
//! ∫ b_T = 9|T|/20,  ∫ λ_k b_T = 3|T|/20,  ∫ b_T² = 81|T|/280,
//! ∫ λ_i ∂_d λ_k = |T|/3 ∂_dλ_k,  ∫ λ_i ∂_d b_T = −∂_dλ_i ∫ b_T (b_T = 0 on ∂T).
//!
//! The bubble vanishes on every edge, hence on Γ and on Γc: its rows of (15) carry no right-hand
//! side and no contact term, and it can be eliminated element by element. Writing the symmetric
//! system as [[G, Bᵀ],[B, −δM]] [P; U] = [G_Γ; −F] (the first equation of (15) times −1), the
//! elimination gives exactly
//!
//! G̃_T = M_T − (7|T|/90)·1 1ᵀ (per component),
//! B̃_T[i, (k,d)] = |T|/3 ∂_dλ_k + 7|T|/30 ∂_dλ_i,
//! u–u block −(δ M_T + 7/10 A_T)  (A_T the P1 stiffness),
//!
//! and the bubble coefficient is recovered as b_d = 14/9 ∂_d u_h − 14/27 Σ_k P_{k,d}.

use super::p1::TriangleGeometry;

/// ∫ b_T / |T|.
pub const BUBBLE_INTEGRAL: f64 = 9.0 / 20.0;
/// ∫ λ_k b_T / |T|.
pub const BUBBLE_HAT_INTEGRAL: f64 = 3.0 / 20.0;
/// ∫ b_T² / |T|.
pub const BUBBLE_MASS: f64 = 81.0 / 280.0;
/// The multiple of the P1 stiffness that condensation adds (with a minus sign) to the u–u block.
pub const CONDENSED_STIFFNESS_FACTOR: f64 = BUBBLE_INTEGRAL * BUBBLE_INTEGRAL / BUBBLE_MASS;

/// Condensed element matrices of one triangle (δ-independent parts).
#[derive(Clone, Copy, Debug)]
pub struct CondensedElement {
    /// G̃_T: the P1 vector-mass block after condensation (same for both components).
    pub g: [[f64; 3]; 3],
    /// B̃_T[i][(k, d)] at index [i][2k + d]: u test function i against p basis (k, d).
    pub b: [[f64; 6]; 3],
    /// The P1 mass matrix M_T (enters the u–u block as −δ M_T).
    pub m: [[f64; 3]; 3],
    /// C_T = 7/10 A_T (enters the u–u block as −C_T).
    pub c: [[f64; 3]; 3],
}

impl CondensedElement {
    /// The same element with G̃_T replaced by its row-sum diagonal (the lumped p mass):
    /// every row of G̃_T sums to |T|/3 − 3·(7|T|/90) = |T|/10 > 0. B̃, M and C are unchanged.
    pub fn lumped(mut self) -> CondensedElement {
        let sums = self.g.map(|row| row.iter().sum::<f64>());
        self.g = [[0.0; 3]; 3];
        for (i, s) in sums.into_iter().enumerate() {
            self.g[i][i] = s;
        }
        self
    }
}

/// The condensed element matrices of triangle `t`.
pub fn condensed_element(t: &TriangleGeometry) -> CondensedElement {
    let area = t.area;
    let shift = BUBBLE_HAT_INTEGRAL * BUBBLE_HAT_INTEGRAL / BUBBLE_MASS * area;
    let mut g = t.mass();
    for row in g.iter_mut() {
        for v in row.iter_mut() {
            *v -= shift;
        }
    }
    let cross = BUBBLE_HAT_INTEGRAL * BUBBLE_INTEGRAL / BUBBLE_MASS * area;
    let mut b = [[0.0; 6]; 3];
    for (i, row) in b.iter_mut().enumerate() {
        for k in 0..3 {
            for d in 0..2 {
                row[2 * k + d] = area / 3.0 * t.grad[k][d] + cross * t.grad[i][d];
            }
        }
    }
    let mut c = t.stiffness();
    for row in c.iter_mut() {
        for v in row.iter_mut() {
            *v *= CONDENSED_STIFFNESS_FACTOR;
        }
    }
    CondensedElement {
        g,
        b,
        m: t.mass(),
        c,
    }
}

/// Bubble coefficients (b_x, b_y) of p on `t` from the vertex values `p` and the local u values.
pub fn bubble_coefficients(t: &TriangleGeometry, p: &[[f64; 2]; 3], u: &[f64; 3]) -> [f64; 2] {
    let grad_u = [0, 1].map(|d| (0..3).map(|i| u[i] * t.grad[i][d]).sum::<f64>());
    let a = BUBBLE_INTEGRAL / BUBBLE_MASS; // 14/9
    let s = BUBBLE_HAT_INTEGRAL / BUBBLE_MASS; // 14/27
    [0, 1].map(|d| a * grad_u[d] - s * (p[0][d] + p[1][d] + p[2][d]))
}

/// Value of the bubble b_T = 27 λ_0 λ_1 λ_2 at barycentric coordinates `l`.
pub fn bubble(l: [f64; 3]) -> f64 {
    27.0 * l[0] * l[1] * l[2]
}

/// Value of the MINI field with vertex values `p` and bubble coefficients `bc` at barycentrics `l`.
pub fn mini_value(p: &[[f64; 2]; 3], bc: [f64; 2], l: [f64; 3]) -> [f64; 2] {
    let b = bubble(l);
    [0, 1].map(|d| l[0] * p[0][d] + l[1] * p[1][d] + l[2] * p[2][d] + bc[d] * b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fe::quadrature::{physical_points, triangle_rule, REFERENCE_TRIANGLE};

    /// Builds the full (uncondensed) element system by quadrature and eliminates the bubbles densely.
    #[test]
    fn condensation_matches_dense_elimination_with_quadrature() {
        let t = TriangleGeometry::new([[0.2, -0.1], [1.1, 0.3], [0.4, 0.9]]);
        let rule = triangle_rule(6); // bubble × bubble is degree 6
                                     // unknown order: p (k,d) -> 2k+d (6), bubbles bx, by (6, 7), u (8..11)
        let n = 11;
        let mut k = vec![vec![0.0; n]; n];
        let dbub = |l: [f64; 3], d: usize| {
            27.0 * (t.grad[0][d] * l[1] * l[2]
                + t.grad[1][d] * l[0] * l[2]
                + t.grad[2][d] * l[0] * l[1])
        };
        for q in physical_points(&rule, t.vertices, REFERENCE_TRIANGLE) {
            let (w, l) = (q.weight, TriangleGeometry::barycentric(q.xi));
            let b = bubble(l);
            // p basis: value (vector) and divergence
            let mut val = [[0.0; 2]; 8];
            let mut div = [0.0; 8];
            for kk in 0..3 {
                for d in 0..2 {
                    val[2 * kk + d][d] = l[kk];
                    div[2 * kk + d] = t.grad[kk][d];
                }
            }
            for d in 0..2 {
                val[6 + d][d] = b;
                div[6 + d] = dbub(l, d);
            }
            for a in 0..8 {
                for c in 0..8 {
                    k[a][c] += w * (val[a][0] * val[c][0] + val[a][1] * val[c][1]);
                }
                for i in 0..3 {
                    let bij = w * l[i] * div[a];
                    k[8 + i][a] += bij;
                    k[a][8 + i] += bij;
                }
            }
        }
        // Schur complement eliminating 6, 7 (the 2x2 bubble block is diagonal)
        let keep: Vec<usize> = (0..6).chain(8..11).collect();
        let ce = condensed_element(&t);
        for (ia, &a) in keep.iter().enumerate() {
            for (ic, &c) in keep.iter().enumerate() {
                let mut s = k[a][c];
                for e in 6..8 {
                    s -= k[a][e] * k[e][c] / k[e][e];
                }
                let expected = if ia < 6 && ic < 6 {
                    if ia % 2 == ic % 2 {
                        ce.g[ia / 2][ic / 2]
                    } else {
                        0.0
                    }
                } else if ia >= 6 && ic < 6 {
                    ce.b[ia - 6][ic]
                } else if ia < 6 {
                    ce.b[ic - 6][ia]
                } else {
                    -ce.c[ia - 6][ic - 6]
                };
                assert!(
                    (s - expected).abs() < 1e-13,
                    "entry ({a},{c}): {s} vs {expected}"
                );
            }
        }
        // bubble recovery: b = -(K_bp P + K_bu U)/K_bb
        let p = [[0.3, -1.0], [0.7, 0.2], [-0.4, 0.5]];
        let u = [0.1, -0.6, 0.9];
        let bc = bubble_coefficients(&t, &p, &u);
        for d in 0..2 {
            let e = 6 + d;
            let mut r = 0.0;
            for kk in 0..3 {
                r += k[e][2 * kk + d] * p[kk][d];
            }
            for i in 0..3 {
                r += k[e][8 + i] * u[i];
            }
            assert!((bc[d] + r / k[e][e]).abs() < 1e-12);
        }
    }

    /// The lumped p mass keeps B̃, M, C and puts |T|/10 (the row sums of G̃_T) on the diagonal.
    #[test]
    fn lumped_element_is_the_row_sum_diagonal() {
        let t = TriangleGeometry::new([[0.1, 0.2], [1.3, -0.1], [0.4, 0.9]]);
        let ce = condensed_element(&t);
        let lumped = ce.lumped();
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { t.area / 10.0 } else { 0.0 };
                assert!((lumped.g[i][j] - want).abs() <= 1e-15, "{i} {j}");
            }
        }
        assert_eq!((lumped.b, lumped.m, lumped.c), (ce.b, ce.m, ce.c));
    }

    #[test]
    fn condensed_stiffness_factor_is_seven_tenths() {
        assert!((CONDENSED_STIFFNESS_FACTOR - 0.7).abs() < 1e-15);
    }
}
