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
//! tip, the norms' earlier rule) is kept as the check of the collapsed one: they agree to 1e-10
//! relative on every repository scene with a tip (tests/convergence.rs). Cross-checked by the
//! compare tool's independent computation from the stored fields (compare/sdcompare_lib/exact.py):
//! agreement ≤ 2e-10 relative (1.8e-10 at worst, on graded meshes; docs/design.md). On Γc the exact jump is the scene's `jump` expression or u⁺ − u⁻
//! evaluated with the signed-zero side convention of [`crate::problem::eval_on_face`].
//!
//! The exact data at the points (u, ∇u and f on the triangles, \[u\] on the cracks) cost ~80 % of a
//! pass; a [`NormCache`] evaluates them once per mesh, for both rules, within a memory budget
//! ([`NORM_CACHE_BUDGET`]), and every later pass on that mesh reads them. The cached and the
//! evaluated values go through the same code (`norms_pass`): the norms are the same bit for bit.

use std::sync::OnceLock;

use crate::expr::{BatchScratch, Expr, ExprBatch};
use crate::fe::mini::mini_value;
use crate::fe::p1::TriangleGeometry;
use crate::fe::quadrature::{
    collapsed_tip_rule, extend_physical_points, gauss_legendre, triangle_rule, PhysicalPoint,
    TriangleRule, REFERENCE_TRIANGLE,
};
use crate::mesh::{Mesh, UTopology};
use crate::multiplier::CrackField;
use crate::problem::{eval_on_face, Exact};

#[cfg(test)]
mod tests;

/// Declares [`ErrorNorms`] and its vocabulary [`Quantity`] from one table: each quantity's
/// field, variant and name (summary.json's `errors` keys, a scene's `quantity`).
macro_rules! error_norms {
    ($( $(#[$doc:meta])* $field:ident => $variant:ident ),+ $(,)?) => {
        /// The error norms of a case, one per [`Quantity`].
        #[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
        pub struct ErrorNorms {
            $( $(#[$doc])* pub $field: f64, )+
        }

        /// An error quantity of a case: a field of [`ErrorNorms`], named as its field.
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum Quantity {
            $( $(#[$doc])* $variant, )+
        }

        crate::scene_names!(Quantity { $( $variant => stringify!($field), )+ });

        impl ErrorNorms {
            /// The norm of quantity `q`.
            pub fn get(&self, q: Quantity) -> f64 {
                match q {
                    $( Quantity::$variant => self.$field, )+
                }
            }

            /// The norms whose value for `q` is `value(q)`.
            pub fn from_fn(mut value: impl FnMut(Quantity) -> f64) -> ErrorNorms {
                ErrorNorms {
                    $( $field: value(Quantity::$variant), )+
                }
            }
        }
    };
}

error_norms! {
    /// ‖u_h − u‖_{L²(Ω)}.
    u_l2 => UL2,
    /// ‖p_h − ∇u‖_{L²(Ω_c)}.
    p_l2 => PL2,
    /// ‖p_h − ∇u‖_X, the paper's mesh-dependent norm (L² plus h_T² ‖div(p_h − ∇u)‖²_T).
    p_x => PX,
    /// ‖λ_h − \[u\]‖_{L²(Γc)}.
    lambda_l2 => LambdaL2,
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
    /// with the `tip_degree` rule; tip segments cut at 2^{-i}, i = 1..depth. The norms' earlier
    /// rule, with far more points per tip triangle than `Collapsed`; kept to check the collapsed
    /// rule.
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
pub(crate) enum PieceRule {
    /// Degree `degree`: away from the tips.
    Regular,
    /// Degree `tip_degree`: near a tip, or a piece of a graded tip triangle.
    NearTip,
    /// Collapsed at the piece's first vertex, a tip.
    Collapsed,
}

/// A piece of a triangle in its reference coordinates, with its rule.
pub(crate) type Piece = (PieceRule, [[f64; 2]; 3]);

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
    /// u, ∂u/∂x, ∂u/∂y, f at the points, one after the other (when not read from a cache).
    values: Vec<f64>,
    scratch: BatchScratch,
}

/// Values the norms need of the exact data at a point: u, ∂u/∂x, ∂u/∂y and f.
const EXACT_VALUES: usize = 4;

/// Triangles per chunk of a pass: fixed chunks summed in order, then the chunk sums in order.
const CHUNK: usize = 4096;

/// The norms' rule on the triangles of one mesh: which rule each piece of a triangle gets.
/// Shared with the elastic norms ([`crate::afw::norms`]), which integrate over the same points.
pub(crate) struct MeshRule {
    tip: TipRule,
    regular: TriangleRule,
    near: TriangleRule,
    collapsed: TriangleRule,
    tips: Vec<usize>,
    /// The vertices of the triangles touching a tip: a triangle with one of them is near a tip.
    tip_patch: Vec<bool>,
}

impl MeshRule {
    pub(crate) fn new(mesh: &Mesh, quad: NormQuadrature) -> MeshRule {
        let regular = triangle_rule(quad.degree);
        let near = triangle_rule(quad.tip_degree);
        let collapsed = match quad.tip {
            TipRule::Collapsed { points } => collapsed_tip_rule(points),
            TipRule::Graded { .. } => near.clone(),
        };
        let tips = mesh.tips();
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
        MeshRule {
            tip: quad.tip,
            regular,
            near,
            collapsed,
            tips,
            tip_patch,
        }
    }

    fn rule_of(&self, r: PieceRule) -> &TriangleRule {
        match r {
            PieceRule::Regular => &self.regular,
            PieceRule::NearTip => &self.near,
            PieceRule::Collapsed => &self.collapsed,
        }
    }

    /// The pieces of triangle `t` with their rules, into `out`.
    fn pieces(&self, t: &[usize; 3], out: &mut Vec<Piece>) {
        let near_tip = t.iter().any(|&v| self.tip_patch[v]);
        out.clear();
        pieces(t.map(|v| self.tips.contains(&v)), near_tip, self.tip, out);
    }

    /// The number of points of triangle `t` (`buffer`: scratch for its pieces).
    fn count(&self, t: &[usize; 3], buffer: &mut Vec<Piece>) -> usize {
        self.pieces(t, buffer);
        buffer
            .iter()
            .map(|&(rule, _)| self.rule_of(rule).points.len())
            .sum()
    }

    /// The points of triangle `t` (of geometry `geo`), piece after piece, into `work.points`.
    fn points(&self, t: &[usize; 3], geo: &TriangleGeometry, work: &mut ElementWork) {
        self.triangle_points(t, geo, &mut work.pieces, &mut work.points);
    }

    /// The points of triangle `t` (of geometry `geo`), piece after piece, into `points`
    /// (`pieces`: scratch for its pieces).
    pub(crate) fn triangle_points(
        &self,
        t: &[usize; 3],
        geo: &TriangleGeometry,
        pieces: &mut Vec<Piece>,
        points: &mut Vec<PhysicalPoint>,
    ) {
        self.pieces(t, pieces);
        points.clear();
        for &(rule, piece) in pieces.iter() {
            extend_physical_points(self.rule_of(rule), geo.vertices, piece, points);
        }
    }
}

/// u, ∂u/∂x, ∂u/∂y and f compiled together into one program ([`ExprBatch`]).
fn exact_program(exact: &Exact, source: &Expr) -> ExprBatch {
    ExprBatch::new(&[&exact.u, &exact.px, &exact.py, source])
}

/// The program's values at `work.points` into `out` (u, ∂u/∂x, ∂u/∂y, f, one after the other:
/// [`EXACT_VALUES`] × n values), a triangle's points at once. The one place where a norm pass, or
/// a [`NormCache`] for all of them, evaluates the exact data on the triangles.
fn evaluate(program: &ExprBatch, work: &mut ElementWork, out: &mut [f64]) {
    work.xs.clear();
    work.xs.extend(work.points.iter().map(|q| q.x[0]));
    work.ys.clear();
    work.ys.extend(work.points.iter().map(|q| q.x[1]));
    program.eval(&work.xs, &work.ys, &mut work.scratch, out);
}

/// The points of the λ error's rule on the cracks, chains in order: a crack segment's pieces
/// ([`segment_pieces`]) with `tip_degree / 2 + 1` Gauss points each. Shared with the elastic
/// norms ([`crate::afw::norms`]).
pub(crate) struct CrackRule {
    pub(crate) points: Vec<CrackPoint>,
    /// The points of each chain of the mesh, in its order.
    pub(crate) chains: Vec<std::ops::Range<usize>>,
}

/// A point of the [`CrackRule`].
pub(crate) struct CrackPoint {
    /// The physical point.
    pub(crate) x: [f64; 2],
    /// The normal of its crack segment.
    pub(crate) normal: [f64; 2],
    /// Its crack segment k (x_k → x_{k+1}) within its chain.
    pub(crate) segment: usize,
    /// Its local coordinate s ∈ (0, 1) on the segment.
    pub(crate) s: f64,
    /// The weight (Gauss weight × ds × segment length).
    pub(crate) weight: f64,
}

impl CrackRule {
    pub(crate) fn new(mesh: &Mesh, quad: NormQuadrature) -> CrackRule {
        let g = gauss_legendre(quad.tip_degree / 2 + 1);
        let mut points = Vec::new();
        let mut chains = Vec::with_capacity(mesh.cracks.len());
        for chain in &mesh.cracks {
            let start = points.len();
            let nodes = &chain.nodes;
            let last = nodes.len() - 2;
            for k in 0..nodes.len() - 1 {
                let (a, b) = (mesh.vertices[nodes[k]], mesh.vertices[nodes[k + 1]]);
                let len = (b[0] - a[0]).hypot(b[1] - a[1]);
                // a chain's end is a tip unless it is a mouth (an edge crack's end on ∂Ω,
                // elastic scenes only: a scalar chain has none, so its rule is unchanged)
                let (from_tip, to_tip) =
                    (k == 0 && !chain.mouths[0], k == last && !chain.mouths[1]);
                for (s0, s1, collapsed) in segment_pieces(from_tip, to_tip, quad.tip) {
                    for (&t, &w) in g.points.iter().zip(&g.weights) {
                        // s from s0 (a tip where `collapsed`) toward s1;
                        // s − s0 = (s1 − s0) σ² there
                        let (s, ds) = if collapsed {
                            (s0 + t * t * (s1 - s0), 2.0 * t * (s1 - s0).abs())
                        } else {
                            (s0 + t * (s1 - s0), (s1 - s0).abs())
                        };
                        points.push(CrackPoint {
                            x: [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])],
                            normal: chain.normals[k],
                            segment: k,
                            s,
                            weight: w * ds * len,
                        });
                    }
                }
            }
            chains.push(start..points.len());
        }
        CrackRule { points, chains }
    }

    /// The exact jump at every point ([`exact_jump`]).
    fn jumps(&self, exact: &Exact) -> Vec<f64> {
        self.points
            .iter()
            .map(|q| exact_jump(exact, q.x, q.normal))
            .collect()
    }

    /// ‖λ_h − \[u\]‖_{L²(Γc)} with \[u\] = `jumps` at the points: ∫ (λ_h − \[u\])² per chain, the
    /// chains' integrals added in order.
    fn lambda_error(&self, mesh: &Mesh, lambda: &CrackField, jumps: &[f64]) -> f64 {
        let mut total = 0.0;
        // λ's node and segment numbers run on over the cracks in order
        let (mut node0, mut seg0) = (0, 0);
        for (chain, range) in mesh.cracks.iter().zip(&self.chains) {
            let mut chain_total = 0.0;
            for (q, &jump) in self.points[range.clone()].iter().zip(&jumps[range.clone()]) {
                let (k, s) = (q.segment, q.s);
                let lh = match lambda {
                    CrackField::PerSegment(v) => v[seg0 + k],
                    CrackField::PerNode(v) => (1.0 - s) * v[node0 + k] + s * v[node0 + k + 1],
                };
                let d = lh - jump;
                chain_total += q.weight * d * d;
            }
            total += chain_total;
            node0 += chain.nodes.len();
            seg0 += chain.segments();
        }
        total.sqrt()
    }
}

/// The exact data at every point of one rule on one mesh: what a norm pass reads instead of
/// evaluating them ([`NormCache`]).
struct RuleValues {
    /// Triangle i's values are `values[offsets[i]..offsets[i + 1]]`.
    offsets: Vec<usize>,
    /// Per triangle, u, ∂u/∂x, ∂u/∂y, f at its points ([`evaluate`]'s layout).
    values: Vec<f64>,
    /// \[u\] at the points of the [`CrackRule`].
    jumps: Vec<f64>,
}

impl RuleValues {
    /// Bytes of the values of `rule` and `crack` (offsets, values and jumps), counted before any
    /// is allocated: the points of every triangle, without computing them.
    fn bytes(mesh: &Mesh, rule: &MeshRule, crack: &CrackRule) -> usize {
        let mut buffer = Vec::new();
        let points: usize = mesh
            .triangles
            .iter()
            .map(|t| rule.count(t, &mut buffer))
            .sum();
        let words = mesh.triangles.len() + 1 + EXACT_VALUES * points + crack.points.len();
        words * std::mem::size_of::<f64>()
    }

    /// Evaluates the exact data at every point of `rule` and `crack`, in parallel over the same
    /// chunks as a pass.
    fn build(
        mesh: &Mesh,
        rule: &MeshRule,
        crack: &CrackRule,
        exact: &Exact,
        program: &ExprBatch,
    ) -> RuleValues {
        use rayon::prelude::*;
        let triangles = &mesh.triangles;
        let mut buffer = Vec::new();
        let mut offsets = Vec::with_capacity(triangles.len() + 1);
        offsets.push(0);
        for t in triangles {
            let next = offsets[offsets.len() - 1] + EXACT_VALUES * rule.count(t, &mut buffer);
            offsets.push(next);
        }
        let mut values = vec![0.0; offsets[triangles.len()]];
        // the chunks' parts of `values`, each filled by one thread
        let mut parts = Vec::with_capacity(triangles.len().div_ceil(CHUNK));
        let mut rest = values.as_mut_slice();
        for start in (0..triangles.len()).step_by(CHUNK) {
            let end = (start + CHUNK).min(triangles.len());
            let (part, tail) = rest.split_at_mut(offsets[end] - offsets[start]);
            parts.push((start..end, part));
            rest = tail;
        }
        parts.into_par_iter().for_each(|(range, part)| {
            let mut work = ElementWork::default();
            let base = offsets[range.start];
            for ti in range {
                let t = &triangles[ti];
                let geo = TriangleGeometry::new(t.map(|v| mesh.vertices[v]));
                rule.points(t, &geo, &mut work);
                evaluate(
                    program,
                    &mut work,
                    &mut part[offsets[ti] - base..offsets[ti + 1] - base],
                );
            }
        });
        RuleValues {
            offsets,
            values,
            jumps: crack.jumps(exact),
        }
    }

    /// Triangle `ti`'s values.
    fn triangle(&self, ti: usize) -> &[f64] {
        &self.values[self.offsets[ti]..self.offsets[ti + 1]]
    }
}

/// The error norms of `sols` with one rule (`rule`, `crack`) in one pass over its points: the
/// exact data read from `cached`, or evaluated here a triangle at a time. The one home of the
/// norms' sums: the cached and the uncached values are the same f64 values ([`evaluate`] on the
/// same points), consumed by the same operations in the same order, so the norms are the same
/// bit for bit.
fn norms_pass(
    mesh: &Mesh,
    rule: &MeshRule,
    crack: &CrackRule,
    topo: &UTopology,
    exact: &Exact,
    sols: &[DiscreteSolution],
    cached: Option<&RuleValues>,
) -> Vec<ErrorNorms> {
    use rayon::prelude::*;
    let Some(first) = sols.first() else {
        return Vec::new();
    };
    assert!(
        sols.iter().all(|s| std::ptr::eq(s.source, first.source)),
        "the solutions of one pass share their source f"
    );
    assert_eq!(
        topo.triangle_dofs.len(),
        mesh.triangles.len(),
        "a topology of the rule's mesh"
    );
    let program = match cached {
        Some(_) => None,
        None => Some(exact_program(exact, first.source)),
    };
    let add = |a: (f64, f64, f64), b: (f64, f64, f64)| (a.0 + b.0, a.1 + b.1, a.2 + b.2);
    // One triangle's contributions (∫ (u_h − u)², ∫ |p_h − ∇u|², h_T² ∫ (div p_h + f)²), added
    // to each solution's sums in `acc`.
    let element =
        |ti: usize, t: &[usize; 3], work: &mut ElementWork, acc: &mut [(f64, f64, f64)]| {
            let geo = TriangleGeometry::new(t.map(|v| mesh.vertices[v]));
            rule.points(t, &geo, work);
            let n = work.points.len();
            let values = match (cached, &program) {
                (Some(cached), _) => cached.triangle(ti),
                (None, Some(program)) => {
                    let mut values = std::mem::take(&mut work.values);
                    values.resize(EXACT_VALUES * n, 0.0);
                    evaluate(program, work, &mut values);
                    work.values = values;
                    &work.values
                }
                (None, None) => unreachable!("a program without a cache"),
            };
            assert_eq!(values.len(), EXACT_VALUES * n, "the cache's points");
            let (u, rest) = values.split_at(n);
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
    // [u] at the crack points once for all the solutions
    let evaluated;
    let jumps = match cached {
        Some(cached) => &cached.jumps,
        None => {
            evaluated = crack.jumps(exact);
            &evaluated
        }
    };
    sols.iter()
        .zip(sums)
        .map(|(sol, (eu, ep, ediv))| ErrorNorms {
            u_l2: eu.sqrt(),
            p_l2: ep.sqrt(),
            p_x: (ep + ediv).sqrt(),
            lambda_l2: crack.lambda_error(mesh, sol.lambda, jumps),
        })
        .collect()
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
    let (rule, crack) = (MeshRule::new(mesh, quad), CrackRule::new(mesh, quad));
    norms_pass(mesh, &rule, &crack, topo, exact, sols, None)
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

/// [`error_norms_estimated`] of several solutions in one pass per rule ([`error_norms_many`]),
/// the exact data evaluated in each pass: a [`NormCache`] with no budget.
pub fn error_norms_estimated_many(
    mesh: &Mesh,
    topo: &UTopology,
    exact: &Exact,
    sols: &[DiscreteSolution],
    quad: NormQuadrature,
) -> Vec<(ErrorNorms, ErrorNorms)> {
    let Some(first) = sols.first() else {
        return Vec::new();
    };
    NormCache::new(mesh, exact, first.source, quad, 0).error_norms_estimated_many(topo, sols)
}

/// The budget of the study's [`NormCache`]s: 256 MiB. The cache holds 32 bytes per quadrature
/// point (u, ∂u/∂x, ∂u/∂y, f), ~100 points per triangle for the two rules (36 + 64 away from the
/// tips): about as much per triangle as the whole case needs at its peak, factorisation
/// included, so a cache without a bound would double the memory of every case. The budget keeps
/// both rules on the small levels, only the reported rule on the next ones and none on the
/// largest, so a cache never adds gigabytes.
pub const NORM_CACHE_BUDGET: usize = 256 << 20;

/// The error norms of every discrete solution on one mesh against one exact solution, with their
/// quadrature-error estimates ([`error_norms_estimated_many`]), the exact data at the points of
/// both rules (u, ∇u and f on the triangles, \[u\] on the cracks) evaluated once, on first use,
/// and read by every later pass: the study keeps one per level, for all its u spaces, p spaces,
/// p masses, δ and multipliers. Each rule's values are counted before they are allocated; a rule
/// whose values do not fit in what the budget leaves is evaluated in each pass instead (the
/// larger rule, the higher one, is kept first). The norms are the same bit for bit either way.
pub struct NormCache<'a> {
    mesh: &'a Mesh,
    exact: &'a Exact,
    source: &'a Expr,
    quad: NormQuadrature,
    budget: usize,
    built: OnceLock<CachedRules>,
}

/// What a [`NormCache`] builds on first use: the rule and the higher rule, and the values of
/// those that fit.
struct CachedRules {
    rules: [(MeshRule, CrackRule); 2],
    values: [Option<RuleValues>; 2],
}

impl<'a> NormCache<'a> {
    /// An empty cache of the norms with `quad` on `mesh` against `exact` and the source `source`
    /// (−Δu = f), whose values may take up to `budget` bytes ([`NORM_CACHE_BUDGET`]).
    pub fn new(
        mesh: &'a Mesh,
        exact: &'a Exact,
        source: &'a Expr,
        quad: NormQuadrature,
        budget: usize,
    ) -> NormCache<'a> {
        NormCache {
            mesh,
            exact,
            source,
            quad,
            budget,
            built: OnceLock::new(),
        }
    }

    /// [`error_norms_estimated_many`] of `sols` (on `topo`, a topology of the cache's mesh, with
    /// the cache's source), reading the cached values.
    pub fn error_norms_estimated_many(
        &self,
        topo: &UTopology,
        sols: &[DiscreteSolution],
    ) -> Vec<(ErrorNorms, ErrorNorms)> {
        assert!(
            sols.iter().all(|s| std::ptr::eq(s.source, self.source)),
            "the solutions have the cache's source f"
        );
        if sols.is_empty() {
            return Vec::new();
        }
        let built = self.built.get_or_init(|| self.build());
        let [reported, higher] = [0, 1].map(|i| {
            let (rule, crack) = &built.rules[i];
            let cached = built.values[i].as_ref();
            norms_pass(self.mesh, rule, crack, topo, self.exact, sols, cached)
        });
        reported
            .into_iter()
            .zip(higher)
            .map(|(e, h)| {
                let estimate = ErrorNorms::from_fn(|q| (e.get(q) - h.get(q)).abs());
                (e, estimate)
            })
            .collect()
    }

    /// The bytes of the values kept for the rule and the higher rule (`None`: evaluated in each
    /// pass); `None` before the first use.
    pub fn cached_bytes(&self) -> Option<[Option<usize>; 2]> {
        self.built.get().map(|built| {
            built.values.each_ref().map(|v| {
                v.as_ref().map(|v| {
                    (v.offsets.len() + v.values.len() + v.jumps.len()) * std::mem::size_of::<f64>()
                })
            })
        })
    }

    /// The rules, and the values of those that fit in the budget, the larger first.
    fn build(&self) -> CachedRules {
        let rules = [self.quad, self.quad.higher()].map(|quad| {
            (
                MeshRule::new(self.mesh, quad),
                CrackRule::new(self.mesh, quad),
            )
        });
        let bytes = if self.budget == 0 {
            [usize::MAX; 2]
        } else {
            rules
                .each_ref()
                .map(|(rule, crack)| RuleValues::bytes(self.mesh, rule, crack))
        };
        let mut keep = [false; 2];
        let mut left = self.budget;
        let mut order = [0, 1];
        order.sort_by_key(|&i| std::cmp::Reverse(bytes[i]));
        for i in order {
            if bytes[i] <= left {
                keep[i] = true;
                left -= bytes[i];
            }
        }
        let program = keep
            .contains(&true)
            .then(|| exact_program(self.exact, self.source));
        let mut values = [None, None];
        for i in 0..2 {
            if let (true, Some(program)) = (keep[i], &program) {
                let (rule, crack) = &rules[i];
                values[i] = Some(RuleValues::build(
                    self.mesh, rule, crack, self.exact, program,
                ));
            }
        }
        CachedRules { rules, values }
    }
}

/// The exact jump \[u\] at a crack point.
pub fn exact_jump(exact: &Exact, p: [f64; 2], normal: [f64; 2]) -> f64 {
    match &exact.jump {
        Some(j) => j.eval(p[0], p[1]),
        None => eval_on_face(&exact.u, p, normal, 1.0) - eval_on_face(&exact.u, p, normal, -1.0),
    }
}

/// The pieces (s0, s1, collapsed at s0) of a crack segment [0, 1] in its local coordinate s, for
/// a segment starting (`from_tip`) or ending (`to_tip`) at a tip (a chain's end, not a mouth): graded cuts at 2^{-i}
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
