//! Quadrature rules: Gauss–Legendre on [0, 1] and collapsed (Duffy/conical-product) Gauss rules on
//! the reference triangle {ξ, η ≥ 0, ξ + η ≤ 1}, and [`physical_points`], the one place where a
//! reference rule becomes a rule on a physical triangle (weights summing to its area).
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

/// Duffy rule collapsed at the reference vertex (0, 0), for integrands with an r^{k/2} singularity
/// there (a crack tip): ξ = s(1 − t), η = s t (Jacobian s), then s = σ², so dξ dη = 2σ³ dσ dt, with
/// `n` Gauss–Legendre points in σ and in t. Every term r^{k/2} φ(θ) of a tip expansion, times the
/// Jacobian, is then a polynomial in σ and smooth in t, so Gauss converges exponentially
/// (r^{−1}, the density of |∇u|² at the tip, included). Exact for total degree ≤ n − 2
/// (ξ^a η^b becomes σ^{2(a+b)+3} times a polynomial of degree a + b in t).
pub fn collapsed_tip_rule(n: usize) -> TriangleRule {
    let g = gauss_legendre(n);
    let mut points = Vec::with_capacity(n * n);
    let mut weights = Vec::with_capacity(n * n);
    for (&sigma, &ws) in g.points.iter().zip(&g.weights) {
        let s = sigma * sigma;
        for (&t, &wt) in g.points.iter().zip(&g.weights) {
            points.push([s * (1.0 - t), s * t]);
            weights.push(2.0 * sigma.powi(3) * ws * wt);
        }
    }
    TriangleRule {
        points,
        weights,
        degree: n.saturating_sub(2),
    }
}

/// The reference triangle, as a piece of itself: (0, 0), (1, 0), (0, 1).
pub const REFERENCE_TRIANGLE: [[f64; 2]; 3] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];

/// A quadrature point on a physical triangle.
#[derive(Clone, Copy, Debug)]
pub struct PhysicalPoint {
    /// Reference coordinates (ξ, η) of the point in its (parent) triangle.
    pub xi: [f64; 2],
    /// The physical point x = v0 + ξ(v1 − v0) + η(v2 − v0).
    pub x: [f64; 2],
    /// Physical weight: the weights of a piece sum to the piece's area (units of length²).
    pub weight: f64,
}

/// The points of `rule` on the sub-triangle `piece` of the physical triangle `vertices`, `piece`
/// given in the reference coordinates of `vertices` ([`REFERENCE_TRIANGLE`] for the whole
/// triangle). Each weight is the reference weight times |det(piece)| (the piece's share of the
/// reference triangle, ×2) times the physical Jacobian |det(v1 − v0, v2 − v0)| = 2|T|: the weights
/// of `rule` sum to 1/2, so those returned sum to the physical area of the piece.
pub fn physical_points(
    rule: &TriangleRule,
    vertices: [[f64; 2]; 3],
    piece: [[f64; 2]; 3],
) -> Vec<PhysicalPoint> {
    let mut points = Vec::with_capacity(rule.points.len());
    extend_physical_points(rule, vertices, piece, &mut points);
    points
}

/// [`physical_points`] appended to `out` (the same points, without allocating where `out` has
/// room: the error norms' passes reuse one buffer for every triangle).
pub fn extend_physical_points(
    rule: &TriangleRule,
    vertices: [[f64; 2]; 3],
    piece: [[f64; 2]; 3],
    out: &mut Vec<PhysicalPoint>,
) {
    let det = |[a, b, c]: [[f64; 2]; 3]| {
        ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs()
    };
    let affine = |[a, b, c]: [[f64; 2]; 3], s: [f64; 2]| {
        [
            a[0] + s[0] * (b[0] - a[0]) + s[1] * (c[0] - a[0]),
            a[1] + s[0] * (b[1] - a[1]) + s[1] * (c[1] - a[1]),
        ]
    };
    let scale = det(piece) * det(vertices);
    out.extend(rule.points.iter().zip(&rule.weights).map(|(s, w)| {
        let xi = affine(piece, *s);
        PhysicalPoint {
            xi,
            x: affine(vertices, xi),
            weight: w * scale,
        }
    }));
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

    /// Asserts that `r` has all its points strictly inside the reference triangle and integrates
    /// every monomial ξ^a η^b of total degree ≤ r.degree exactly: a! b! / (a + b + 2)!.
    fn assert_exact_on_monomials(r: &TriangleRule, label: &str) {
        assert!(r
            .points
            .iter()
            .all(|p| p[0] > 0.0 && p[1] > 0.0 && p[0] + p[1] < 1.0));
        for a in 0..=r.degree as u32 {
            for b in 0..=(r.degree as u32 - a) {
                let exact = factorial(a) * factorial(b) / factorial(a + b + 2);
                let q: f64 = r
                    .points
                    .iter()
                    .zip(&r.weights)
                    .map(|(p, w)| w * p[0].powi(a as i32) * p[1].powi(b as i32))
                    .sum();
                assert!((q - exact).abs() < 1e-15, "{label}: x^{a} y^{b}");
            }
        }
    }

    #[test]
    fn triangle_rule_exact_on_monomials_up_to_degree() {
        for degree in [0, 2, 4, 6, 8, 10, 12] {
            let r = triangle_rule(degree);
            assert!(r.degree >= degree);
            assert_exact_on_monomials(&r, &format!("degree {degree}"));
        }
    }

    #[test]
    fn collapsed_tip_rule_exact_on_monomials_up_to_its_degree() {
        for n in [2, 6, 12, 16] {
            let r = collapsed_tip_rule(n);
            assert_eq!(r.degree, n - 2);
            assert_exact_on_monomials(&r, &format!("n {n}"));
        }
    }

    /// The tip singularities in closed form on the reference triangle, collapsed at (0, 0):
    /// in polar coordinates r runs to R(θ) = 1/(cos θ + sin θ), so ∫ r^{-1} = ∫_0^{π/2} R dθ =
    /// √2 artanh(1/√2), and ∫ r^{-1/2} = ∫_0^{π/2} R^{3/2} / (3/2) dθ, a smooth integral in θ
    /// taken with 64-point Gauss. A rule that is not collapsed at the singular vertex, or forgets σ = √s,
    /// misses them by far more than 1e-12 (16 points leave 1.4e-13 of ∫ r^{-1}: the angular
    /// factor 1/|d(t)| is analytic but not a polynomial).
    #[test]
    fn collapsed_tip_rule_integrates_the_tip_singularities() {
        let r = collapsed_tip_rule(16);
        let quad = |f: &dyn Fn(f64) -> f64| -> f64 {
            r.points
                .iter()
                .zip(&r.weights)
                .map(|(p, w)| w * f(p[0].hypot(p[1])))
                .sum()
        };
        let inv_r = 2f64.sqrt() * (1.0 / 2f64.sqrt()).atanh();
        assert!((quad(&|r| 1.0 / r) - inv_r).abs() < 1e-12 * inv_r);
        let g = gauss_legendre(64);
        let polar: f64 = g
            .points
            .iter()
            .zip(&g.weights)
            .map(|(t, w)| {
                let th = t * std::f64::consts::FRAC_PI_2;
                w * std::f64::consts::FRAC_PI_2 * (th.cos() + th.sin()).powf(-1.5) / 1.5
            })
            .sum();
        assert!((quad(&|r| r.powf(-0.5)) - polar).abs() < 1e-12 * polar);
    }

    /// ∫_T x^a y^b dA by Green's theorem, ∮_∂T x^(a+1) y^b / (a + 1) dy, each edge with a 1-D
    /// Gauss rule exact for its degree a + b + 1: a path independent of the triangle rules.
    fn monomial_by_green(v: [[f64; 2]; 3], a: i32, b: i32) -> f64 {
        let g = gauss_legendre(((a + b + 2) / 2 + 1) as usize);
        let signed =
            (v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[2][0] - v[0][0]) * (v[1][1] - v[0][1]);
        let mut total = 0.0;
        for k in 0..3 {
            let (p, q) = (v[k], v[(k + 1) % 3]);
            for (t, w) in g.points.iter().zip(&g.weights) {
                let x = p[0] + t * (q[0] - p[0]);
                let y = p[1] + t * (q[1] - p[1]);
                total += w * x.powi(a + 1) * y.powi(b) / f64::from(a + 1) * (q[1] - p[1]);
            }
        }
        total * signed.signum()
    }

    /// Physical triangles of both orientations, far from the reference one, and a sliver.
    const PHYSICAL: [[[f64; 2]; 3]; 4] = [
        [[0.2, -0.1], [1.1, 0.3], [0.4, 0.9]],
        [[-0.75, -1.0], [-0.5, -0.75], [-0.75, -0.75]],
        [[3.0, 2.0], [1.0, 5.0], [4.5, 6.0]],
        [[0.0, 0.0], [1.0, 1e-3], [0.5, 2e-3]],
    ];

    #[test]
    fn every_rule_integrates_one_to_the_area_of_physical_triangles() {
        for degree in [0, 2, 4, 6, 8, 10, 12] {
            let rule = triangle_rule(degree);
            for v in PHYSICAL {
                let area = monomial_by_green(v, 0, 0).abs();
                let q: f64 = physical_points(&rule, v, REFERENCE_TRIANGLE)
                    .iter()
                    .map(|p| p.weight)
                    .sum();
                assert!(
                    (q - area).abs() <= 1e-14 * area,
                    "degree {degree}, triangle {v:?}: Σ w = {q}, area {area}"
                );
            }
        }
    }

    #[test]
    fn every_rule_is_exact_on_monomials_of_physical_triangles() {
        for degree in [0, 2, 4, 6, 8, 10, 12] {
            let rule = triangle_rule(degree);
            for v in PHYSICAL {
                let points = physical_points(&rule, v, REFERENCE_TRIANGLE);
                for a in 0..=degree as i32 {
                    for b in 0..=(degree as i32 - a) {
                        let exact = monomial_by_green(v, a, b);
                        let q: f64 = points
                            .iter()
                            .map(|p| p.weight * p.x[0].powi(a) * p.x[1].powi(b))
                            .sum();
                        let scale = points
                            .iter()
                            .map(|p| p.weight * (p.x[0].powi(a) * p.x[1].powi(b)).abs())
                            .sum::<f64>();
                        assert!(
                            (q - exact).abs() <= 1e-13 * scale,
                            "degree {degree}, {v:?}: x^{a} y^{b}: {q} vs {exact}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn pieces_tile_their_parent_with_physical_weights() {
        // four congruent children of the reference triangle integrate like the parent
        let rule = triangle_rule(6);
        let v = PHYSICAL[2];
        let children = [
            [[0.0, 0.0], [0.5, 0.0], [0.0, 0.5]],
            [[0.5, 0.0], [1.0, 0.0], [0.5, 0.5]],
            [[0.0, 0.5], [0.5, 0.5], [0.0, 1.0]],
            [[0.5, 0.5], [0.0, 0.5], [0.5, 0.0]],
        ];
        let f = |x: [f64; 2]| x[0].powi(3) * x[1].powi(2) - 2.0 * x[1];
        let whole: f64 = physical_points(&rule, v, REFERENCE_TRIANGLE)
            .iter()
            .map(|p| p.weight * f(p.x))
            .sum();
        let split: f64 = children
            .iter()
            .flat_map(|c| physical_points(&rule, v, *c))
            .map(|p| p.weight * f(p.x))
            .sum();
        let exact = monomial_by_green(v, 3, 2) - 2.0 * monomial_by_green(v, 0, 1);
        assert!((whole - exact).abs() <= 1e-12 * exact.abs());
        assert!((split - exact).abs() <= 1e-12 * exact.abs());
    }
}
