//! Quadrature rules: Gauss–Legendre on [0, 1] and collapsed (Duffy/conical-product) Gauss rules on
//! the reference triangle {ξ, η ≥ 0, ξ + η ≤ 1}.
//!
//! The collapsed rule with n × n points, ξ = s, η = t(1 − s), weight w_s w_t (1 − s), integrates every
//! polynomial of total degree ≤ 2n − 2 exactly; all its points are strictly inside the triangle, so
//! data are never evaluated on an edge (in particular never on the crack).

/// A 1D rule on [0, 1]: points and weights (weights sum to 1).
#[derive(Clone, Debug)]
pub struct LineRule {
    /// Points in (0, 1).
    pub points: Vec<f64>,
    /// Weights, summing to 1.
    pub weights: Vec<f64>,
}

/// A rule on the reference triangle: barycentric-free (ξ, η) points and weights summing to 1/2.
#[derive(Clone, Debug)]
pub struct TriangleRule {
    /// Points (ξ, η) strictly inside the reference triangle.
    pub points: Vec<[f64; 2]>,
    /// Weights, summing to the reference area 1/2.
    pub weights: Vec<f64>,
    /// Highest total degree integrated exactly.
    pub degree: usize,
}

/// Gauss–Legendre rule with `n` points on [0, 1] (exact to degree 2n − 1).
pub fn gauss_legendre(n: usize) -> LineRule {
    assert!(n >= 1, "a Gauss rule needs at least one point");
    let mut points = vec![0.0; n];
    let mut weights = vec![0.0; n];
    for i in 0..n {
        // Newton on P_n from the Chebyshev-like initial guess.
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (p, dp) = legendre(n, x);
            let dx = p / dp;
            x -= dx;
            if dx.abs() < 1e-16 {
                break;
            }
        }
        let (_, dp) = legendre(n, x);
        points[n - 1 - i] = 0.5 * (1.0 + x);
        weights[n - 1 - i] = 1.0 / ((1.0 - x * x) * dp * dp);
    }
    LineRule { points, weights }
}

/// P_n(x) and P_n'(x) by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    if n == 0 {
        return (1.0, 0.0);
    }
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    let dp = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, dp)
}

/// Collapsed Gauss rule on the reference triangle, exact for total degree ≤ `degree`.
pub fn triangle_rule(degree: usize) -> TriangleRule {
    let n = degree / 2 + 1;
    let g = gauss_legendre(n);
    let mut points = Vec::with_capacity(n * n);
    let mut weights = Vec::with_capacity(n * n);
    for (&s, &ws) in g.points.iter().zip(&g.weights) {
        for (&t, &wt) in g.points.iter().zip(&g.weights) {
            points.push([s, t * (1.0 - s)]);
            weights.push(ws * wt * (1.0 - s));
        }
    }
    TriangleRule {
        points,
        weights,
        degree: 2 * n - 2,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn factorial(n: u32) -> f64 {
        (1..=n).map(f64::from).product()
    }

    #[test]
    fn gauss_exact_on_monomials() {
        for n in 1..=8 {
            let g = gauss_legendre(n);
            for k in 0..(2 * n) as i32 {
                let q: f64 = g
                    .points
                    .iter()
                    .zip(&g.weights)
                    .map(|(x, w)| w * x.powi(k))
                    .sum();
                assert!((q - 1.0 / f64::from(k + 1)).abs() < 1e-14, "n={n} k={k}");
            }
        }
    }

    #[test]
    fn triangle_rule_exact_on_monomials_up_to_degree() {
        for degree in [0, 2, 4, 6, 8, 10, 12] {
            let r = triangle_rule(degree);
            assert!(r.degree >= degree);
            assert!(r
                .points
                .iter()
                .all(|p| p[0] > 0.0 && p[1] > 0.0 && p[0] + p[1] < 1.0));
            for a in 0..=r.degree as u32 {
                for b in 0..=(r.degree as u32 - a) {
                    // ∫ ξ^a η^b over the reference triangle = a! b! / (a + b + 2)!
                    let exact = factorial(a) * factorial(b) / factorial(a + b + 2);
                    let q: f64 = r
                        .points
                        .iter()
                        .zip(&r.weights)
                        .map(|(p, w)| w * p[0].powi(a as i32) * p[1].powi(b as i32))
                        .sum();
                    assert!((q - exact).abs() < 1e-15, "degree {degree}: x^{a} y^{b}");
                }
            }
        }
    }
}
