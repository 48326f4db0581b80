//! Error norms against an exact solution (docs/design.md, Error norms), with quadrature collapsed at the crack tips.
//!
//! e_u = ‖u_h − u‖_{L²(Ω)}, e_p = ‖p_h − ∇u‖_{L²(Ω_c)} (p_h with its bubbles), e_λ = ‖λ_h − \[u\]‖_{L²(Γc)},
//! and the paper's mesh-dependent X-norm of the p error (§4):
//! ‖p_h − ∇u‖²_X = Σ_T ‖p_h − ∇u‖²_T + h_T² ‖div p_h − Δu‖²_T with Δu = −f off the crack.
//! Each triangle lies on one side of the crack, so u and ∇u are smooth on it except at a tip vertex,
//! where u ~ r^{1/2}. A triangle with a tip as a vertex gets the Duffy rule collapsed at the tip
//! with r = σ² ([`collapsed_tip_rule`], [`TipRule::Collapsed`]); crack segments ending at a tip get
//! the same substitution in their length coordinate. The triangles around them get the Gauss rule
//! of degree `tip_degree`, the others that of degree `degree` ([`NormQuadrature`]). All points are
//! interior, so data are never evaluated on Γc. [`TipRule::Graded`] (recursive splits toward the
//! tip, the rule before issue 26) is kept as the check of the collapsed one: they agree to 1e-10
//! relative on every repository scene with a tip (tests/convergence.rs). Cross-checked by the
//! compare tool's independent computation from the stored fields (compare/sdcompare_lib/exact.py):
//! agreement ≤ 2e-10 relative (1.8e-10 at worst, on graded meshes; docs/design.md). On Γc the exact jump is the scene's `jump` expression or u⁺ − u⁻
//! evaluated with the signed-zero side convention of [`crate::problem::eval_on_face`].

use crate::expr::{BatchScratch, ExprBatch};
use crate::fe::mini::mini_value;
use crate::fe::p1::TriangleGeometry;
use crate::fe::quadrature::{
    collapsed_tip_rule, gauss_legendre, physical_points, triangle_rule, PhysicalPoint,
    TriangleRule, REFERENCE_TRIANGLE,
};
use crate::mesh::{Mesh, UTopology};
use crate::multiplier::CrackField;
use crate::problem::{eval_on_face, Exact};

/// The three error norms of a case.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ErrorNorms {
    /// ‖u_h − u‖_{L²(Ω)}.
    pub u_l2: f64,
    /// ‖p_h − ∇u‖_{L²(Ω_c)}.
    pub p_l2: f64,
    /// ‖p_h − ∇u‖_X, the paper's mesh-dependent norm (L² plus h_T² ‖div(p_h − ∇u)‖²_T).
    pub p_x: f64,
    /// ‖λ_h − \[u\]‖_{L²(Γc)}.
    pub lambda_l2: f64,
}

/// The rule on triangles and crack segments that end at a crack tip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TipRule {
    /// The Duffy rule collapsed at the tip with r = σ² ([`collapsed_tip_rule`]), `points`
    /// Gauss–Legendre points in σ and in the angle (`points`² per tip triangle); tip segments
    /// with s = σ² from the tip. A triangle with two or three tips as vertices is split into its
    /// four midpoint children, each child at a tip collapsed there.
    Collapsed {
        /// Gauss points per direction.
        points: usize,
    },
    /// Recursive splits toward the tip (the corner child split again `depth` times), each piece
    /// with the `tip_degree` rule; tip segments cut at 2^{-i}, i = 1..depth. The norms' rule up to
    /// issue 26: ~7 000 points per tip triangle at depth 30, against 256 for `Collapsed { points:
    /// 16 }`; kept to check the collapsed rule.
    Graded {
        /// Recursive splits toward each tip.
        depth: usize,
    },
}

/// Quadrature used by the norms.
///
/// The defaults were set against an independent computation (compare/sdcompare_lib/exact.py:
/// Duffy rules collapsed at the tips): with a degree-10 rule and 16 splits everywhere, the p error
/// of the open crack (∇u ~ r^{-1/2}) came out 5e-8 to 1.3e-7 too small, from the tip triangles and
/// their neighbours; with degree 20 around the tips they agree to ~1e-11 (graded tips, depth 30 to
/// 40, or collapsed tips with 16 points).
#[derive(Clone, Copy, Debug)]
pub struct NormQuadrature {
    /// Total degree of the rule on triangles away from the tips.
    pub degree: usize,
    /// Total degree of the rule near the tips: on the triangles that share a vertex with a
    /// triangle touching a tip (the pieces of graded tip triangles included), and of the Gauss
    /// rule on crack segments (tip_degree / 2 + 1 points).
    pub tip_degree: usize,
    /// The rule on triangles and segments ending at a tip.
    pub tip: TipRule,
}

impl Default for NormQuadrature {
    fn default() -> Self {
        NormQuadrature {
            degree: 10,
            tip_degree: 20,
            tip: TipRule::Collapsed { points: 16 },
        }
    }
}

/// Points per direction of the estimate's rule against those of the reported rule:
/// [`NormQuadrature::higher`] takes ⌈n · 4/3⌉ for each rule's n. Why 4/3: where the integrand is
/// not smooth on a triangle (a kink of the exact solution across it) a rule's error falls only
/// algebraically, e_n ~ n^{−k} with k ≥ 1 for a bounded integrand, and the difference of the two
/// rules, e_n (1 − (n/n')^k), is then at least a quarter of the reported rule's error e_n; where it
/// is smooth the higher rule's error is negligible and the difference is e_n itself. The compare
/// tool multiplies the estimate by its SAFETY 4 for this (compare/sdcompare_lib/checks.py).
pub const HIGHER_RULE_RATIO: (usize, usize) = (4, 3);

impl NormQuadrature {
    /// The rule of the quadrature-error estimate ([`error_norms_estimated`]): every rule with
    /// ⌈n · 4/3⌉ points per direction for its n ([`HIGHER_RULE_RATIO`]): degree 10 (6 points) →
    /// 14 (8), tip degree 20 (11 points, and 11 Gauss points on the crack) → 28 (15), the collapsed
    /// tip rule 16 → 22 points; the graded tip rule keeps its splits.
    pub fn higher(self) -> NormQuadrature {
        let (num, den) = HIGHER_RULE_RATIO;
        let more = |n: usize| (n * num).div_ceil(den);
        // a degree d rule has d / 2 + 1 points per direction, and that many points give degree
        // 2(n − 1)
        let degree = |d: usize| 2 * (more(d / 2 + 1) - 1);
        NormQuadrature {
            degree: degree(self.degree),
            tip_degree: degree(self.tip_degree),
            tip: match self.tip {
                TipRule::Collapsed { points } => TipRule::Collapsed {
                    points: more(points),
                },
                graded @ TipRule::Graded { .. } => graded,
            },
        }
    }
}

/// The discrete solution needed for norms.
#[derive(Clone, Copy)]
pub struct DiscreteSolution<'a> {
    /// u dofs.
    pub u: &'a [f64],
    /// p at the u dofs (the vertex value seen from the dof's face: p⁺, p⁻ where the
    /// broken-tangential p doubles a crack vertex).
    pub p: &'a [[f64; 2]],
    /// Bubble coefficients of p per triangle.
    pub bubbles: &'a [[f64; 2]],
    /// λ_h.
    pub lambda: &'a CrackField,
    /// The source f (−Δu = f), for the divergence part of the X-norm.
    pub source: &'a crate::expr::Expr,
}

/// Sub-triangles (in reference coordinates of the parent) graded toward the local vertex `corner`.
fn graded_pieces(corner: Option<usize>, depth: usize) -> Vec<[[f64; 2]; 3]> {
    let full = REFERENCE_TRIANGLE;
    let Some(c) = corner else {
        return vec![full];
    };
    let mut pieces = Vec::new();
    let mut current = full;
    // keep the corner vertex first
    current.rotate_left(c);
    for _ in 0..depth {
        let [a, b, d] = current;
        let mid = |p: [f64; 2], q: [f64; 2]| [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
        let (ab, bd, ad) = (mid(a, b), mid(b, d), mid(a, d));
        pieces.push([ab, b, bd]);
        pieces.push([ad, bd, d]);
        pieces.push([ab, bd, ad]);
        current = [a, ab, ad];
    }
    pieces.push(current);
    pieces
}

/// Which rule a piece of a triangle gets.
#[derive(Clone, Copy, Debug, PartialEq)]
enum PieceRule {
    /// Degree `degree`: away from the tips.
    Regular,
    /// Degree `tip_degree`: near a tip, or a piece of a graded tip triangle.
    NearTip,
    /// Collapsed at the piece's first vertex, a tip.
    Collapsed,
}

/// A piece of a triangle in its reference coordinates, with its rule.
type Piece = (PieceRule, [[f64; 2]; 3]);

/// The pieces of a triangle whose local vertices `at_tip` are crack tips (`near_tip`: it shares a
/// vertex with a triangle touching a tip), appended to `out`.
fn pieces(at_tip: [bool; 3], near_tip: bool, tip: TipRule, out: &mut Vec<Piece>) {
    let corner = (0..3).find(|&k| at_tip[k]);
    let Some(c) = corner else {
        let rule = if near_tip {
            PieceRule::NearTip
        } else {
            PieceRule::Regular
        };
        out.push((rule, REFERENCE_TRIANGLE));
        return;
    };
    match tip {
        TipRule::Graded { depth } => out.extend(
            graded_pieces(corner, depth)
                .into_iter()
                .map(|p| (PieceRule::NearTip, p)),
        ),
        TipRule::Collapsed { .. } if at_tip.iter().filter(|&&b| b).count() == 1 => {
            let mut piece = REFERENCE_TRIANGLE;
            piece.rotate_left(c);
            out.push((PieceRule::Collapsed, piece));
        }
        TipRule::Collapsed { .. } => {
            // several tips: the four midpoint children, each corner child first at its corner
            let v = REFERENCE_TRIANGLE;
            let mid = |p: [f64; 2], q: [f64; 2]| [(p[0] + q[0]) / 2.0, (p[1] + q[1]) / 2.0];
            for k in 0..3 {
                let (a, b, d) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
                let rule = if at_tip[k] {
                    PieceRule::Collapsed
                } else {
                    PieceRule::NearTip
                };
                out.push((rule, [a, mid(a, b), mid(a, d)]));
            }
            out.push((
                PieceRule::NearTip,
                [mid(v[0], v[1]), mid(v[1], v[2]), mid(v[0], v[2])],
            ));
        }
    }
}

/// Buffers of one thread's triangles: their quadrature points and the exact data there.
#[derive(Default)]
struct ElementWork {
    pieces: Vec<Piece>,
    points: Vec<PhysicalPoint>,
    xs: Vec<f64>,
    ys: Vec<f64>,
    /// u, ∂u/∂x, ∂u/∂y, f at the points, one after the other.
    values: Vec<f64>,
    scratch: BatchScratch,
}

/// Computes e_u, e_p, e_λ of `sol` against `exact`.
pub fn error_norms(
    mesh: &Mesh,
    topo: &UTopology,
    exact: &Exact,
    sol: &DiscreteSolution,
    quad: NormQuadrature,
) -> ErrorNorms {
    error_norms_many(mesh, topo, exact, std::slice::from_ref(sol), quad)[0]
}

/// [`error_norms`] of several discrete solutions on the same mesh, against the same exact
/// solution and source (the multipliers of one δ), in one pass over the quadrature points: the
/// exact solution is evaluated once per point for all of them. Each solution's norms are those of
/// [`error_norms`] alone, bit for bit: its sums run over the same points in the same order.
pub fn error_norms_many(
    mesh: &Mesh,
    topo: &UTopology,
    exact: &Exact,
    sols: &[DiscreteSolution],
    quad: NormQuadrature,
) -> Vec<ErrorNorms> {
    use rayon::prelude::*;
    let Some(first) = sols.first() else {
        return Vec::new();
    };
    assert!(
        sols.iter().all(|s| std::ptr::eq(s.source, first.source)),
        "the solutions of one pass share their source f"
    );
    let regular = triangle_rule(quad.degree);
    let near = triangle_rule(quad.tip_degree);
    let collapsed = match quad.tip {
        TipRule::Collapsed { points } => collapsed_tip_rule(points),
        TipRule::Graded { .. } => near.clone(),
    };
    let rule_of = |r: PieceRule| -> &TriangleRule {
        match r {
            PieceRule::Regular => &regular,
            PieceRule::NearTip => &near,
            PieceRule::Collapsed => &collapsed,
        }
    };
    let tips = mesh.tips();
    // vertices of the triangles touching a tip: a triangle with one of them is near a tip
    let mut tip_patch = vec![false; mesh.vertices.len()];
    for t in mesh
        .triangles
        .iter()
        .filter(|t| t.iter().any(|v| tips.contains(v)))
    {
        for &v in t {
            tip_patch[v] = true;
        }
    }
    // u, ∂u/∂x, ∂u/∂y and f evaluated together, a triangle's points at once.
    let program = ExprBatch::new(&[&exact.u, &exact.px, &exact.py, first.source]);
    let add = |a: (f64, f64, f64), b: (f64, f64, f64)| (a.0 + b.0, a.1 + b.1, a.2 + b.2);
    // One triangle's contributions (∫ (u_h − u)², ∫ |p_h − ∇u|², h_T² ∫ (div p_h + f)²), added
    // to each solution's sums in `acc`.
    let element =
        |ti: usize, t: &[usize; 3], work: &mut ElementWork, acc: &mut [(f64, f64, f64)]| {
            let geo = TriangleGeometry::new(t.map(|v| mesh.vertices[v]));
            let near_tip = t.iter().any(|&v| tip_patch[v]);
            work.pieces.clear();
            pieces(
                t.map(|v| tips.contains(&v)),
                near_tip,
                quad.tip,
                &mut work.pieces,
            );
            work.points.clear();
            for &(rule, piece) in &work.pieces {
                work.points
                    .extend(physical_points(rule_of(rule), geo.vertices, piece));
            }
            let n = work.points.len();
            work.xs.clear();
            work.xs.extend(work.points.iter().map(|q| q.x[0]));
            work.ys.clear();
            work.ys.extend(work.points.iter().map(|q| q.x[1]));
            work.values.resize(4 * n, 0.0);
            program.eval(&work.xs, &work.ys, &mut work.scratch, &mut work.values);
            let (u, rest) = work.values.split_at(n);
            let (px, rest) = rest.split_at(n);
            let (py, f) = rest.split_at(n);
            let dofs = topo.triangle_dofs[ti];
            let [a, b, c] = geo.vertices;
            let d = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).hypot(p[1] - q[1]);
            // h_T, the longest edge
            let h_t = d(a, b).max(d(b, c)).max(d(a, c));
            for (sol, acc) in sols.iter().zip(acc.iter_mut()) {
                let pv = dofs.map(|d| sol.p[d]);
                let bc = sol.bubbles[ti];
                // div of the P1 part (constant)
                let div_linear: f64 = (0..3)
                    .map(|k| pv[k][0] * geo.grad[k][0] + pv[k][1] * geo.grad[k][1])
                    .sum();
                let (mut su, mut sp, mut sd) = (0.0, 0.0, 0.0);
                for (j, q) in work.points.iter().enumerate() {
                    let (l, w) = (TriangleGeometry::barycentric(q.xi), q.weight);
                    let uh: f64 = (0..3).map(|k| l[k] * sol.u[dofs[k]]).sum();
                    let ph = mini_value(&pv, bc, l);
                    let du = uh - u[j];
                    let dpx = ph[0] - px[j];
                    let dpy = ph[1] - py[j];
                    // ∇b_T = 27 (∇λ0 λ1 λ2 + λ0 ∇λ1 λ2 + λ0 λ1 ∇λ2)
                    let grad_b = [0, 1].map(|k| {
                        27.0 * (geo.grad[0][k] * l[1] * l[2]
                            + geo.grad[1][k] * l[0] * l[2]
                            + geo.grad[2][k] * l[0] * l[1])
                    });
                    let div_h = div_linear + bc[0] * grad_b[0] + bc[1] * grad_b[1];
                    let ddiv = div_h + f[j];
                    su += w * du * du;
                    sp += w * (dpx * dpx + dpy * dpy);
                    sd += w * h_t * h_t * ddiv * ddiv;
                }
                *acc = add(*acc, (su, sp, sd));
            }
        };
    // Fixed chunks summed in order, then the chunk sums in order: the same additions in the same
    // order whatever the threads do, so a case gives the same norms bit for bit in any run
    // (rayon's adaptive `reduce` splits differently from run to run), and with any other
    // solutions beside it.
    const CHUNK: usize = 4096;
    let zero = vec![(0.0, 0.0, 0.0); sols.len()];
    let sums = mesh
        .triangles
        .par_chunks(CHUNK)
        .enumerate()
        .map(|(c, tris)| {
            let mut work = ElementWork::default();
            let mut acc = zero.clone();
            for (j, t) in tris.iter().enumerate() {
                element(c * CHUNK + j, t, &mut work, &mut acc);
            }
            acc
        })
        .collect::<Vec<_>>()
        .into_iter()
        .fold(zero.clone(), |total, chunk| {
            total
                .into_iter()
                .zip(chunk)
                .map(|(a, b)| add(a, b))
                .collect()
        });
    sols.iter()
        .zip(sums)
        .map(|(sol, (eu, ep, ediv))| ErrorNorms {
            u_l2: eu.sqrt(),
            p_l2: ep.sqrt(),
            p_x: (ep + ediv).sqrt(),
            lambda_l2: lambda_error(mesh, exact, sol.lambda, quad),
        })
        .collect()
}

/// The error norms of [`error_norms`] with `quad` (the numbers reported, unchanged) and an
/// estimate of the quadrature error of each: |e(quad) − e(quad.higher())|, per quantity, in the
/// units of the error ([`NormQuadrature::higher`]). summary.json reports it as
/// `errors_quadrature`; the compare tool's "independent errors" check allows a reported error to
/// differ from its own by a multiple of these estimates and its own (compare/README.md).
pub fn error_norms_estimated(
    mesh: &Mesh,
    topo: &UTopology,
    exact: &Exact,
    sol: &DiscreteSolution,
    quad: NormQuadrature,
) -> (ErrorNorms, ErrorNorms) {
    error_norms_estimated_many(mesh, topo, exact, std::slice::from_ref(sol), quad)[0]
}

/// [`error_norms_estimated`] of several solutions in one pass per rule ([`error_norms_many`]).
pub fn error_norms_estimated_many(
    mesh: &Mesh,
    topo: &UTopology,
    exact: &Exact,
    sols: &[DiscreteSolution],
    quad: NormQuadrature,
) -> Vec<(ErrorNorms, ErrorNorms)> {
    let reported = error_norms_many(mesh, topo, exact, sols, quad);
    let higher = error_norms_many(mesh, topo, exact, sols, quad.higher());
    reported
        .into_iter()
        .zip(higher)
        .map(|(e, h)| {
            let estimate = ErrorNorms {
                u_l2: (e.u_l2 - h.u_l2).abs(),
                p_l2: (e.p_l2 - h.p_l2).abs(),
                p_x: (e.p_x - h.p_x).abs(),
                lambda_l2: (e.lambda_l2 - h.lambda_l2).abs(),
            };
            (e, estimate)
        })
        .collect()
}

/// The exact jump \[u\] at a crack point.
pub fn exact_jump(exact: &Exact, p: [f64; 2], normal: [f64; 2]) -> f64 {
    match &exact.jump {
        Some(j) => j.eval(p[0], p[1]),
        None => eval_on_face(&exact.u, p, normal, 1.0) - eval_on_face(&exact.u, p, normal, -1.0),
    }
}

/// ‖λ_h − [u]‖_{L²(Γc)} over every crack, with the tip rule on the segments at the chains' ends.
fn lambda_error(mesh: &Mesh, exact: &Exact, lambda: &CrackField, quad: NormQuadrature) -> f64 {
    let g = gauss_legendre(quad.tip_degree / 2 + 1);
    let mut total = 0.0;
    // λ's node and segment numbers run on over the cracks in order
    let (mut node0, mut seg0) = (0, 0);
    for chain in &mesh.cracks {
        total += chain_lambda_error(mesh, chain, exact, lambda, (node0, seg0), &g, quad);
        node0 += chain.nodes.len();
        seg0 += chain.segments();
    }
    total.sqrt()
}

/// ∫ (λ_h − [u])² over one crack chain whose first node and segment are λ's `offsets`.
fn chain_lambda_error(
    mesh: &Mesh,
    chain: &crate::mesh::CrackChain,
    exact: &Exact,
    lambda: &CrackField,
    offsets: (usize, usize),
    g: &crate::fe::quadrature::LineRule,
    quad: NormQuadrature,
) -> f64 {
    let nodes = &chain.nodes;
    let last = nodes.len() - 2;
    let mut total = 0.0;
    for k in 0..nodes.len() - 1 {
        let (a, b) = (mesh.vertices[nodes[k]], mesh.vertices[nodes[k + 1]]);
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        let (from_tip, to_tip) = (k == 0, k == last);
        for (s0, s1, collapsed) in segment_pieces(from_tip, to_tip, quad.tip) {
            for (&t, &w) in g.points.iter().zip(&g.weights) {
                // s from s0 (a tip where `collapsed`) toward s1; s − s0 = (s1 − s0) σ² there
                let (s, ds) = if collapsed {
                    (s0 + t * t * (s1 - s0), 2.0 * t * (s1 - s0).abs())
                } else {
                    (s0 + t * (s1 - s0), (s1 - s0).abs())
                };
                let p = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])];
                let lh = match lambda {
                    CrackField::PerSegment(v) => v[offsets.1 + k],
                    CrackField::PerNode(v) => {
                        (1.0 - s) * v[offsets.0 + k] + s * v[offsets.0 + k + 1]
                    }
                };
                let d = lh - exact_jump(exact, p, chain.normals[k]);
                total += w * ds * len * d * d;
            }
        }
    }
    total
}

/// The pieces (s0, s1, collapsed at s0) of a crack segment [0, 1] in its local coordinate s, for
/// a segment starting (`from_tip`) or ending (`to_tip`) at a chain's end: graded cuts at 2^{-i}
/// toward those ends, or one piece from each such end collapsed there (halves when both are).
fn segment_pieces(from_tip: bool, to_tip: bool, tip: TipRule) -> Vec<(f64, f64, bool)> {
    match tip {
        TipRule::Graded { depth } => {
            let mut cuts = vec![0.0, 1.0];
            if from_tip {
                cuts.extend((1..=depth).map(|i| 0.5f64.powi(i as i32)));
            }
            if to_tip {
                cuts.extend((1..=depth).map(|i| 1.0 - 0.5f64.powi(i as i32)));
            }
            cuts.sort_by(f64::total_cmp);
            cuts.dedup();
            cuts.windows(2).map(|w| (w[0], w[1], false)).collect()
        }
        TipRule::Collapsed { .. } => match (from_tip, to_tip) {
            (true, true) => vec![(0.0, 0.5, true), (1.0, 0.5, true)],
            (true, false) => vec![(0.0, 1.0, true)],
            (false, true) => vec![(1.0, 0.0, true)],
            (false, false) => vec![(0.0, 1.0, false)],
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
    use crate::scene::Scene;
    use std::f64::consts::PI;

    /// The error norms of the zero discrete solution of a repository scene at `level`.
    fn zero_field_norms(scene_toml: &str, level: u32) -> (ErrorNorms, Mesh) {
        let scene = Scene::from_toml(scene_toml).expect("repository scene is valid");
        let mesh = scene.mesh_source().unwrap().level(level).unwrap();
        let topo = mesh.u_topology(USpace::Broken);
        let exact = scene.exact.as_ref().expect("exact scene");
        let u = vec![0.0; topo.n_dofs];
        let p = vec![[0.0; 2]; topo.n_dofs];
        let bubbles = vec![[0.0; 2]; mesh.triangles.len()];
        let lambda = CrackField::PerNode(vec![0.0; mesh.cracks[0].nodes.len()]);
        let sol = DiscreteSolution {
            u: &u,
            p: &p,
            bubbles: &bubbles,
            lambda: &lambda,
            source: &scene.f,
        };
        let norms = error_norms(&mesh, &topo, exact, &sol, NormQuadrature::default());
        (norms, mesh)
    }

    /// The error of the zero field is the norm of the exact solution, here in closed form:
    /// u = sin(πx)cos(πy) − y on (−1, 1)² has ‖u‖² = 1 + 4/3, ‖∇u‖² = 2π² + 4, and
    /// f = −Δu = 2π² sin(πx)cos(πy) has ‖f‖² = 4π⁴ (the X-norm adds h_T²‖f‖²_T with h_T the
    /// diagonal of a cell). A quadrature weight off by a constant factor fails this test.
    #[test]
    fn zero_field_error_is_the_closed_form_norm_of_the_exact_solution() {
        let (n, mesh) = zero_field_norms(include_str!("../scenes/closed-exact.toml"), 1);
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
        let (n, _) = zero_field_norms(include_str!("../scenes/open-exact.toml"), 0);
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
        let mesh = crate::mesh::structured::structured(
            crate::problem::Rectangle {
                min: [-1.0, -1.0],
                max: [1.0, 1.0],
            },
            [4, 4],
            &[],
            1,
        )
        .unwrap();
        assert_eq!(mesh.triangles.len(), 2 * 8 * 8);
        let topo = mesh.u_topology(USpace::Continuous);
        let parse = |s: &str| crate::expr::Expr::parse(s).unwrap();
        let exact = Exact {
            u: parse("x^2 + x*y + 3*y"),
            px: parse("2*x + y"),
            py: parse("x + 3"),
            jump: None,
        };
        let (beta, c, s) = (0.6, [0.3, -0.2], 0.25);
        let u = vec![0.0; topo.n_dofs];
        let p: Vec<[f64; 2]> = mesh
            .vertices
            .iter()
            .map(|&[x, y]| [2.0 * x + y + beta * x, x + 3.0])
            .collect();
        let bubbles = vec![c; mesh.triangles.len()];
        let lambda = CrackField::PerNode(vec![]);
        let source = parse("-2");
        let sol = DiscreteSolution {
            u: &u,
            p: &p,
            bubbles: &bubbles,
            lambda: &lambda,
            source: &source,
        };
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
        let mesh = crate::mesh::structured::structured(
            crate::problem::Rectangle {
                min: [-1.0, -1.0],
                max: [1.0, 1.0],
            },
            [2, 2],
            &[],
            0,
        )
        .unwrap();
        assert_eq!(mesh.triangles.len(), 2 * 2 * 2);
        let topo = mesh.u_topology(USpace::Continuous);
        let parse = |s: &str| crate::expr::Expr::parse(s).unwrap();
        let exact = Exact {
            u: parse("sin(pi*x)*cos(pi*y)"),
            px: parse("pi*cos(pi*x)*cos(pi*y)"),
            py: parse("-pi*sin(pi*x)*sin(pi*y)"),
            jump: None,
        };
        let u = vec![0.0; topo.n_dofs];
        let p = vec![[0.0; 2]; topo.n_dofs];
        let bubbles = vec![[0.0; 2]; mesh.triangles.len()];
        let lambda = CrackField::PerNode(vec![]);
        let source = parse("2*pi^2*sin(pi*x)*cos(pi*y)");
        let sol = DiscreteSolution {
            u: &u,
            p: &p,
            bubbles: &bubbles,
            lambda: &lambda,
            source: &source,
        };
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
        let u2: Vec<f64> = (0..topo.n_dofs).map(|i| 0.1 * i as f64).collect();
        let p2: Vec<[f64; 2]> = (0..topo.n_dofs).map(|i| [0.3, -0.02 * i as f64]).collect();
        let b2 = vec![[0.2, 0.1]; mesh.triangles.len()];
        let other = DiscreteSolution {
            u: &u2,
            p: &p2,
            bubbles: &b2,
            lambda: &lambda,
            source: &source,
        };
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
        let bits = |n: ErrorNorms| [n.u_l2, n.p_l2, n.p_x, n.lambda_l2].map(f64::to_bits);
        for (together, (e, q)) in both.into_iter().zip(alone) {
            assert_eq!(bits(together.0), bits(e));
            assert_eq!(bits(together.1), bits(q));
        }
        assert_ne!(bits(alone[0].0), bits(alone[1].0));
    }
}
