//! The P1 element on a triangle: barycentric coordinates λ_i, their constant gradients, and the
//! local mass and stiffness matrices. Vertex order is counter-clockwise; area > 0.

/// Geometry of one triangle needed by P1/MINI: vertices, area and ∇λ_i.
#[derive(Clone, Copy, Debug)]
pub struct TriangleGeometry {
    /// The three vertices.
    pub vertices: [[f64; 2]; 3],
    /// Area |T| (> 0 for counter-clockwise vertices).
    pub area: f64,
    /// ∇λ_i, i = 0, 1, 2 (constant on T).
    pub grad: [[f64; 2]; 3],
}

impl TriangleGeometry {
    /// Geometry of the triangle with vertices `v` (counter-clockwise).
    pub fn new(v: [[f64; 2]; 3]) -> TriangleGeometry {
        let [a, b, c] = v;
        let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
        // ∇λ_0 = (y_1 − y_2, x_2 − x_1)/det, cyclically.
        let g = |p: [f64; 2], q: [f64; 2]| [(p[1] - q[1]) / det, (q[0] - p[0]) / det];
        TriangleGeometry {
            vertices: v,
            area: 0.5 * det,
            grad: [g(b, c), g(c, a), g(a, b)],
        }
    }

    /// Physical point of reference coordinates (ξ, η): x = v0 + ξ(v1 − v0) + η(v2 − v0).
    pub fn map(&self, xi: [f64; 2]) -> [f64; 2] {
        let [a, b, c] = self.vertices;
        [
            a[0] + xi[0] * (b[0] - a[0]) + xi[1] * (c[0] - a[0]),
            a[1] + xi[0] * (b[1] - a[1]) + xi[1] * (c[1] - a[1]),
        ]
    }

    /// Barycentric coordinates (λ_0, λ_1, λ_2) of reference point (ξ, η).
    pub fn barycentric(xi: [f64; 2]) -> [f64; 3] {
        [1.0 - xi[0] - xi[1], xi[0], xi[1]]
    }

    /// Local P1 mass matrix ∫ λ_i λ_j = |T|/12 (1 + δ_ij).
    pub fn mass(&self) -> [[f64; 3]; 3] {
        let mut m = [[self.area / 12.0; 3]; 3];
        for (i, row) in m.iter_mut().enumerate() {
            row[i] = self.area / 6.0;
        }
        m
    }

    /// Local P1 stiffness matrix ∫ ∇λ_i · ∇λ_j.
    pub fn stiffness(&self) -> [[f64; 3]; 3] {
        let mut k = [[0.0; 3]; 3];
        for (i, row) in k.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = self.area * dot(self.grad[i], self.grad[j]);
            }
        }
        k
    }
}

/// Euclidean inner product in R².
pub fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> TriangleGeometry {
        TriangleGeometry::new([[0.1, 0.2], [1.3, 0.4], [0.5, 1.7]])
    }

    #[test]
    fn nodality_and_partition_of_unity() {
        let t = tri();
        // λ_i(v_j) = δ_ij through the gradient: λ_i(v_j) = λ_i(v_i) + ∇λ_i·(v_j − v_i)
        for i in 0..3 {
            for j in 0..3 {
                let d = [
                    t.vertices[j][0] - t.vertices[i][0],
                    t.vertices[j][1] - t.vertices[i][1],
                ];
                let val = 1.0 + dot(t.grad[i], d);
                assert!((val - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
        let s = [0, 1].map(|d| t.grad.iter().map(|g| g[d]).sum::<f64>());
        assert!(s[0].abs() < 1e-14 && s[1].abs() < 1e-14, "Σ∇λ_i = 0");
    }

    #[test]
    fn gradients_match_finite_differences() {
        let t = tri();
        let lam = |p: [f64; 2]| -> [f64; 3] {
            // solve for barycentrics of p
            let [a, b, c] = t.vertices;
            let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
            let l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (p[1] - a[1])) / det;
            let l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (p[0] - a[0]) * (b[1] - a[1])) / det;
            [1.0 - l1 - l2, l1, l2]
        };
        let p = t.map([0.3, 0.3]);
        let h = 1e-6;
        for i in 0..3 {
            let dx = (lam([p[0] + h, p[1]])[i] - lam([p[0] - h, p[1]])[i]) / (2.0 * h);
            let dy = (lam([p[0], p[1] + h])[i] - lam([p[0], p[1] - h])[i]) / (2.0 * h);
            assert!((dx - t.grad[i][0]).abs() < 1e-8 && (dy - t.grad[i][1]).abs() < 1e-8);
        }
    }

    #[test]
    fn mass_and_stiffness_identities() {
        let t = tri();
        let m: f64 = t.mass().iter().flatten().sum();
        assert!((m - t.area).abs() < 1e-14, "Σ M_ij = |T|");
        for row in t.stiffness() {
            assert!(
                row.iter().sum::<f64>().abs() < 1e-13,
                "constants in the kernel"
            );
        }
    }
}
