use super::*;

/// The structured mesh of (−1, 1)² without a crack: `cells` at level 0, refined `level` times.
fn uncracked_square(cells: [usize; 2], level: u32) -> Mesh {
    crate::mesh::structured::structured(crate::problem::UNIT_SQUARE, cells, &[], level).unwrap()
}

/// The exact solution `u` with its gradient (`px`, `py`, written out rather than derived) and
/// no crack jump, parsed.
fn exact_without_jump(u: &str, px: &str, py: &str) -> Exact {
    let parse = |s: &str| crate::expr::Expr::parse(s).unwrap();
    Exact {
        u: parse(u),
        px: parse(px),
        py: parse(py),
        jump: None,
    }
}

/// A discrete field the tests own: u at the u dofs, p at the u dofs, the bubble coefficients
/// of p per triangle and λ_h; [`Field::solution`] lends it to the norms.
struct Field {
    u: Vec<f64>,
    p: Vec<[f64; 2]>,
    bubbles: Vec<[f64; 2]>,
    lambda: CrackField,
}

impl Field {
    /// u = 0, p = 0 and zero bubbles on `mesh` with the u dofs of `topo`, and λ_h = `lambda`.
    fn zero(mesh: &Mesh, topo: &UTopology, lambda: CrackField) -> Self {
        Field {
            u: vec![0.0; topo.n_dofs],
            p: vec![[0.0; 2]; topo.n_dofs],
            bubbles: vec![[0.0; 2]; mesh.triangles.len()],
            lambda,
        }
    }

    /// The field as the norms take it, with the source f of the X-norm's divergence term.
    fn solution<'a>(&'a self, source: &'a crate::expr::Expr) -> DiscreteSolution<'a> {
        DiscreteSolution {
            u: &self.u,
            p: &self.p,
            bubbles: &self.bubbles,
            lambda: &self.lambda,
            source,
        }
    }
}

#[test]
fn graded_pieces_tile_the_triangle() {
    for corner in [None, Some(0), Some(1), Some(2)] {
        let pieces = graded_pieces(corner, 7);
        let area: f64 = pieces
            .iter()
            .map(|[a, b, c]| {
                0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1])).abs()
            })
            .sum();
        assert!((area - 0.5).abs() < 1e-15);
        if let Some(c) = corner {
            let v = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]][c];
            let smallest = pieces.last().unwrap();
            assert_eq!(smallest[0], v, "last piece sits at the corner");
        }
    }
}

use crate::problem::USpace;
use crate::scene::{testing, Scene};
use std::f64::consts::PI;

/// The error norms of the zero discrete solution of a repository scene at `level`.
fn zero_field_norms(scene: Scene, level: u32) -> (ErrorNorms, Mesh) {
    let mesh = scene.mesh_source().unwrap().level(level).unwrap();
    let topo = mesh.u_topology(USpace::Broken);
    let exact = scene.scalar().unwrap().exact.as_ref().expect("exact scene");
    let lambda = CrackField::PerNode(vec![0.0; mesh.cracks[0].nodes.len()]);
    let field = Field::zero(&mesh, &topo, lambda);
    let sol = field.solution(&scene.scalar().unwrap().f);
    let norms = error_norms(&mesh, &topo, exact, &sol, NormQuadrature::default());
    (norms, mesh)
}

/// The error of the zero field is the norm of the exact solution, here in closed form:
/// u = sin(πx)cos(πy) − y on (−1, 1)² has ‖u‖² = 1 + 4/3, ‖∇u‖² = 2π² + 4, and
/// f = −Δu = 2π² sin(πx)cos(πy) has ‖f‖² = 4π⁴ (the X-norm adds h_T²‖f‖²_T with h_T the
/// diagonal of a cell). A quadrature weight off by a constant factor fails this test.
#[test]
fn zero_field_error_is_the_closed_form_norm_of_the_exact_solution() {
    let (n, mesh) = zero_field_norms(testing::closed_exact(), 1);
    let h_t = std::f64::consts::SQRT_2 * 2.0 / 16.0;
    let close = |a: f64, b: f64, what: &str| {
        assert!((a - b).abs() <= 1e-12 * b, "{what}: {a} vs closed form {b}");
    };
    close(n.u_l2, (7.0f64 / 3.0).sqrt(), "‖u‖");
    close(n.p_l2, (2.0 * PI * PI + 4.0).sqrt(), "‖∇u‖");
    close(
        n.p_x,
        (2.0 * PI * PI + 4.0 + h_t * h_t * 4.0 * PI.powi(4)).sqrt(),
        "‖∇u‖_X",
    );
    assert_eq!(n.lambda_l2, 0.0, "[u] = 0 on the closed crack");
    assert_eq!(mesh.triangles.len(), 2 * 16 * 16);
}

/// On the open crack [u] = 2 sqrt(1/4 − x²) on (−1/2, 1/2): ‖[u]‖² = 4 (1/4 − 1/12) = 2/3,
/// integrated through the r^{1/2} tips by the graded segments.
#[test]
fn zero_multiplier_error_is_the_closed_form_norm_of_the_jump() {
    let (n, _) = zero_field_norms(testing::open_exact(), 0);
    let exact = (2.0f64 / 3.0).sqrt();
    assert!(
        (n.lambda_l2 - exact).abs() <= 1e-9 * exact,
        "‖[u]‖ = {} vs {exact}",
        n.lambda_l2
    );
}

/// The norms of a known discrete field against u = x² + xy + 3y on (−1, 1)² (∇u = (2x + y,
/// x + 3), f = −Δu = −2), on an 8 × 8 grid (cells of side s, h_T = s√2): u_h = 0, and p_h the
/// P1 interpolant of ∇u + (βx, 0) (linear: exact) plus the same bubble c·b_T on every
/// triangle. With ∫_T b = 9|T|/20, ∫_T x b = 9|T|/20 x̄_T, ∫_T b² = 81|T|/280, ∫_T c·∇b = 0,
/// ∫_T (c·∇b)² = 81|T|/20 Σ_i (c·∇λ_i)² and Σ_i (c·∇λ_i)² = Q/s² on both triangles of a
/// cell, Q = c_x² + (c_x − c_y)² + c_y², the closed forms are
/// ‖u_h − u‖² = ∫ (x² + xy + 3y)² = 4/5 + 4/9 + 12,
/// ‖p_h − ∇u‖² = β² ∫ x² + 2β c_x Σ_T ∫_T x b + |c|² Σ_T ∫_T b² = 4β²/3 + 0 + 81|c|²/70,
/// and the X-norm's divergence term (div p_h + f = β + c·∇b_T)
/// Σ_T h_T² ‖β + c·∇b_T‖²_T = 2s² (4β²) + Σ_T 2s² (81|T|/20) Q/s² = 8s²β² + 32.4 Q.
/// A halved weight, a factor √2, a wrong sign of f, a lost or wrong term of div p_h (its P1
/// part or the bubble's gradient) fails this.
#[test]
fn norms_of_a_known_discrete_field_against_a_polynomial_are_the_closed_forms() {
    let mesh = uncracked_square([4, 4], 1);
    assert_eq!(mesh.triangles.len(), 2 * 8 * 8);
    let topo = mesh.u_topology(USpace::Continuous);
    let exact = exact_without_jump("x^2 + x*y + 3*y", "2*x + y", "x + 3");
    let (beta, c, s) = (0.6, [0.3, -0.2], 0.25);
    let field = Field {
        u: vec![0.0; topo.n_dofs],
        p: mesh
            .vertices
            .iter()
            .map(|&[x, y]| [2.0 * x + y + beta * x, x + 3.0])
            .collect(),
        bubbles: vec![c; mesh.triangles.len()],
        lambda: CrackField::PerNode(vec![]),
    };
    let source = crate::expr::Expr::parse("-2").unwrap();
    let sol = field.solution(&source);
    let n = error_norms(&mesh, &topo, &exact, &sol, NormQuadrature::default());
    let close = |a: f64, b: f64, what: &str| {
        assert!((a - b).abs() <= 1e-12 * b, "{what}: {a} vs closed form {b}");
    };
    close(n.u_l2, (4.0f64 / 5.0 + 4.0 / 9.0 + 12.0).sqrt(), "‖u‖");
    let p2 = 4.0 * beta * beta / 3.0 + (c[0] * c[0] + c[1] * c[1]) * 81.0 / 70.0;
    close(n.p_l2, p2.sqrt(), "‖p_h − ∇u‖");
    let q = c[0] * c[0] + (c[0] - c[1]).powi(2) + c[1] * c[1];
    let divergence = 8.0 * s * s * beta * beta + 32.4 * q;
    close(n.p_x, (p2 + divergence).sqrt(), "‖p_h − ∇u‖_X");
    assert_eq!(n.lambda_l2, 0.0, "no crack");
    // Every integrand is a polynomial of degree ≤ 6 (the bubble squared), which both the rule
    // and the higher one integrate exactly: the estimate of the quadrature error is round-off.
    let (e, estimate) =
        error_norms_estimated(&mesh, &topo, &exact, &sol, NormQuadrature::default());
    for (a, b, q, what) in [
        (e.u_l2, n.u_l2, estimate.u_l2, "u_l2"),
        (e.p_l2, n.p_l2, estimate.p_l2, "p_l2"),
        (e.p_x, n.p_x, estimate.p_x, "p_x"),
    ] {
        assert_eq!(
            a.to_bits(),
            b.to_bits(),
            "{what}: the reported error is error_norms'"
        );
        assert!(
            q <= 1e-14 * b,
            "{what}: estimate {q:e} of an exact integral {b}"
        );
    }
    assert_eq!(estimate.lambda_l2, 0.0);
}

/// Bits of norms, to compare them exactly.
fn bits(n: ErrorNorms) -> [u64; 4] {
    [n.u_l2, n.p_l2, n.p_x, n.lambda_l2].map(f64::to_bits)
}

/// Norms with their estimates, as bits.
fn all_bits(norms: &[(ErrorNorms, ErrorNorms)]) -> Vec<[u64; 4]> {
    norms
        .iter()
        .flat_map(|&(e, q)| [bits(e), bits(q)])
        .collect()
}

/// A non-trivial discrete solution of the open crack's level 0 (both u spaces) with both
/// multiplier layouts, and the norms of `check` on it.
fn with_open_crack_solutions(check: impl Fn(&Mesh, &Exact, &[(UTopology, Vec<DiscreteSolution>)])) {
    let scene = testing::open_exact();
    let mesh = scene.mesh_source().unwrap().level(0).unwrap();
    let exact = scene.scalar().unwrap().exact.as_ref().unwrap();
    let topos = [USpace::Broken, USpace::Continuous].map(|s| mesh.u_topology(s));
    let n = topos[0].n_dofs;
    let u: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin()).collect();
    let p: Vec<[f64; 2]> = (0..n).map(|i| [(0.11 * i as f64).cos(), 0.2]).collect();
    let bubbles: Vec<[f64; 2]> = (0..mesh.triangles.len())
        .map(|t| [0.01 * t as f64, -0.3])
        .collect();
    let nodes = mesh.cracks[0].nodes.len();
    let per_node = CrackField::PerNode((0..nodes).map(|k| 0.1 * k as f64).collect());
    let per_segment = CrackField::PerSegment((1..nodes).map(|k| 0.2 * k as f64).collect());
    let sols = |topo: &UTopology| {
        [&per_node, &per_segment]
            .map(|lambda| DiscreteSolution {
                u: &u[..topo.n_dofs],
                p: &p[..topo.n_dofs],
                bubbles: &bubbles,
                lambda,
                source: &scene.scalar().unwrap().f,
            })
            .to_vec()
    };
    let cases: Vec<(UTopology, Vec<DiscreteSolution>)> = topos
        .into_iter()
        .map(|topo| {
            let s = sols(&topo);
            (topo, s)
        })
        .collect();
    check(&mesh, exact, &cases);
}

/// The cached exact data give the norms of the uncached passes bit for bit, for every rule
/// (collapsed and graded tips, the crack's jumps), in the first pass (which builds the cache)
/// and the later ones, and for two u topologies reading one cache (as the u spaces of a level
/// do in a study).
#[test]
fn cached_and_uncached_norms_are_the_same_bit_for_bit() {
    with_open_crack_solutions(|mesh, exact, cases| {
        let graded = NormQuadrature {
            tip: TipRule::Graded { depth: 6 },
            ..NormQuadrature::default()
        };
        for quad in [NormQuadrature::default(), graded] {
            let source = cases[0].1[0].source;
            let cache = NormCache::new(mesh, exact, source, quad, NORM_CACHE_BUDGET);
            assert!(cache.cached_bytes().is_none(), "built on first use");
            for _ in 0..2 {
                for (topo, sols) in cases {
                    let cached = cache.error_norms_estimated_many(topo, sols);
                    let evaluated = error_norms_estimated_many(mesh, topo, exact, sols, quad);
                    assert_eq!(all_bits(&cached), all_bits(&evaluated), "{quad:?}");
                    assert!(cached
                        .iter()
                        .all(|(e, q)| e.lambda_l2 > 0.0 && q.p_l2 > 0.0));
                }
                let [Some(reported), Some(higher)] = cache.cached_bytes().unwrap() else {
                    panic!("both rules fit in the budget");
                };
                assert!(reported < higher, "{reported} vs {higher}");
            }
            // the passes read the cache: with its values zeroed, every norm is another
            let mut cache = cache;
            for values in cache.built.get_mut().unwrap().values.iter_mut().flatten() {
                values.values.fill(0.0);
                values.jumps.fill(0.0);
            }
            for (topo, sols) in cases {
                let zeroed = cache.error_norms_estimated_many(topo, sols);
                let evaluated = error_norms_estimated_many(mesh, topo, exact, sols, quad);
                for ((z, _), (e, _)) in zeroed.into_iter().zip(evaluated) {
                    let (z, e) = (bits(z), bits(e));
                    assert!(z.iter().zip(&e).all(|(a, b)| a != b), "{quad:?}");
                }
            }
        }
    });
}

/// A rule whose values exceed what the budget leaves is evaluated in each pass instead (the
/// larger, higher rule kept first), with the same norms; the sizes counted before building are
/// those allocated, so a budget of exactly one rule's bytes keeps it.
#[test]
fn a_rule_over_the_budget_is_evaluated_in_each_pass() {
    with_open_crack_solutions(|mesh, exact, cases| {
        let quad = NormQuadrature::default();
        let (topo, sols) = &cases[0];
        let want = all_bits(&error_norms_estimated_many(mesh, topo, exact, sols, quad));
        let full = NormCache::new(mesh, exact, sols[0].source, quad, usize::MAX);
        full.error_norms_estimated_many(topo, sols);
        let [Some(r), Some(h)] = full.cached_bytes().unwrap() else {
            panic!("an unbounded cache keeps both rules");
        };
        for (budget, kept) in [
            (0, [None, None]),
            (1, [None, None]),
            (r - 1, [None, None]),
            (r, [Some(r), None]),
            (h, [None, Some(h)]),
            (r + h - 1, [None, Some(h)]),
            (r + h, [Some(r), Some(h)]),
        ] {
            let cache = NormCache::new(mesh, exact, sols[0].source, quad, budget);
            for _ in 0..2 {
                let got = all_bits(&cache.error_norms_estimated_many(topo, sols));
                assert_eq!(got, want, "budget {budget}");
                assert_eq!(cache.cached_bytes(), Some(kept), "budget {budget}");
            }
        }
    });
}

/// The higher rule of the quadrature-error estimate: ⌈4n/3⌉ points per direction.
#[test]
fn higher_rule_has_a_third_more_points_per_direction() {
    let q = NormQuadrature::default().higher();
    assert_eq!((q.degree, q.tip_degree), (14, 28));
    assert_eq!(q.tip, TipRule::Collapsed { points: 22 });
    assert_eq!(triangle_rule(q.degree).points.len(), 8 * 8);
    assert_eq!(triangle_rule(q.tip_degree).points.len(), 15 * 15);
    let graded = NormQuadrature {
        tip: TipRule::Graded { depth: 30 },
        ..NormQuadrature::default()
    };
    assert_eq!(graded.higher().tip, TipRule::Graded { depth: 30 });
}

/// The zero field's errors against u = sin(πx)cos(πy) on (−1, 1)² cut into 2 × 2 cells, whose
/// closed forms are ‖u‖ = 1, ‖∇u‖ = π√2 (∫ sin²(πx) = ∫ cos²(πx) = 1 over (−1, 1)): the
/// integrands are not polynomials, the degree-10 rule is off by a little on cells this wide,
/// and the estimate is not zero and bounds the rule's true error within the compare tool's
/// SAFETY factor 4 (compare/sdcompare_lib/checks.py).
#[test]
fn quadrature_estimate_of_a_non_polynomial_integrand_bounds_the_rules_error() {
    let mesh = uncracked_square([2, 2], 0);
    assert_eq!(mesh.triangles.len(), 2 * 2 * 2);
    let topo = mesh.u_topology(USpace::Continuous);
    let exact = exact_without_jump(
        "sin(pi*x)*cos(pi*y)",
        "pi*cos(pi*x)*cos(pi*y)",
        "-pi*sin(pi*x)*sin(pi*y)",
    );
    let field = Field::zero(&mesh, &topo, CrackField::PerNode(vec![]));
    let source = crate::expr::Expr::parse("2*pi^2*sin(pi*x)*cos(pi*y)").unwrap();
    let sol = field.solution(&source);
    let (e, estimate) =
        error_norms_estimated(&mesh, &topo, &exact, &sol, NormQuadrature::default());
    for (got, closed, q, what) in [
        (e.u_l2, 1.0, estimate.u_l2, "u_l2"),
        (e.p_l2, PI * 2f64.sqrt(), estimate.p_l2, "p_l2"),
    ] {
        let error = (got - closed).abs();
        assert!(
            error > 1e-12 * closed,
            "{what}: the rule is exact?: {error:e}"
        );
        assert!(q > 1e-12 * closed, "{what}: estimate {q:e}");
        assert!(
            error <= 4.0 * q && q <= 4.0 * error,
            "{what}: the rule's error {error:e} against its estimate {q:e}"
        );
    }
    assert!(estimate.p_x > 0.0);
    // several solutions in one pass: each gets the norms it gets alone, bit for bit
    let other_field = Field {
        u: (0..topo.n_dofs).map(|i| 0.1 * i as f64).collect(),
        p: (0..topo.n_dofs).map(|i| [0.3, -0.02 * i as f64]).collect(),
        bubbles: vec![[0.2, 0.1]; mesh.triangles.len()],
        lambda: CrackField::PerNode(vec![]),
    };
    let other = other_field.solution(&source);
    let both = error_norms_estimated_many(
        &mesh,
        &topo,
        &exact,
        &[sol, other],
        NormQuadrature::default(),
    );
    let alone = [
        error_norms_estimated(&mesh, &topo, &exact, &sol, NormQuadrature::default()),
        error_norms_estimated(&mesh, &topo, &exact, &other, NormQuadrature::default()),
    ];
    for (together, (e, q)) in both.into_iter().zip(alone) {
        assert_eq!(bits(together.0), bits(e));
        assert_eq!(bits(together.1), bits(q));
    }
    assert_ne!(bits(alone[0].0), bits(alone[1].0));
}
