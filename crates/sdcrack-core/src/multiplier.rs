//! The Lagrange multiplier on the cracks (paper (12)–(14), docs/design.md, Multipliers and the
//! LCP): the normal-trace operator N, each multiplier space's constraint map S of D = S N, its
//! field λ_h, and its part of the KKT residuals. The one `match` on [`MultiplierSpace`] is
//! [`Multiplier::new`]; everything else reads the data it builds.
//!
//! **Normal traces.** p is continuous and its bubbles vanish on edges, so along each crack edge
//! p·ν is linear with ν the edge's normal. N maps P to the values p(x_j)·ν at the crack nodes,
//! one *trace row* per node and normal: a node whose two edges have the same normal (every
//! interior node of a straight crack) has one row, a tip one row, and a kink of a polyline two
//! rows, p(x_j)·ν_{k−1} then p(x_j)·ν_k. Cracks are concatenated in order (nodes, segments and
//! rows); nothing couples two cracks except through K.
//!
//! **p spaces.** With the broken-tangential p a doubled crack node's unknowns are (p·ν, p⁺·τ)
//! ([`crate::mesh::PTopology`]): its trace row reads p·ν as the unknown p·ν itself, weight
//! (1, 0), the same for both faces. `row_weights` holds each row's weights on the node's two
//! unknowns: its normal in the (x, y) frame, (ν_r·ν, ν_r·τ) in a node's (ν, τ) frame.
//!
//! **Constraint maps.** With ℓ_k the length of crack edge k (nodes k, k+1 of its crack):
//! - M0 (12): one multiplier per edge, ∫_{t_k} p·ν_k = ℓ_k/2 (p(x_k) + p(x_{k+1}))·ν_k ≤ 0.
//! - M1 (13): one per node, ∫ φ_j p·ν = Σ_{k ∋ j} ℓ_k/3 p(x_j)·ν_k + ℓ_k/6 p(x_other)·ν_k ≤ 0: on
//!   a straight crack S is the crack mass M_c. No choice is made at a kink: each edge's
//!   integral uses its own normal.
//! - M1star (14): one per node, p(x_j)·n_j ≤ 0 with the moment Λ̃_j = ∫ λ_h φ_j as its
//!   multiplier. Away from kinks n_j = ν (S = I). **At a kink** the contact term ∫ λ_h q·ν puts
//!   q(x_j)·ν_{k−1} under ∫_{t_{k−1}} λ_h φ_j and q(x_j)·ν_k under ∫_{t_k} λ_h φ_j; one moment
//!   Λ̃_j carries both, so its row splits it in the shares these integrals have for a locally
//!   constant λ_h, ℓ_{k−1} : ℓ_k: n_j = (ℓ_{k−1}ν_{k−1} + ℓ_kν_k)/(ℓ_{k−1} + ℓ_k) = ∫ φ_j ν / ∫ φ_j,
//!   M1's row for a constant p over the hat's integral (weights summing to 1, as at a straight
//!   node). The constraint is p(x_j)·n_j ≤ 0 (n_j is a positive multiple of the nodal normal
//!   ν̄_j of [`CrackOperators::node_normals`], so the cone is the same), and λ_h = M_c⁻¹ Λ̃ as on a
//!   straight crack (M_c the scalar P1 mass of the polyline). Normalising n_j to unit length
//!   instead (before issue 43) made Λ̃_j |n_j| the moment, λ_h at an open right-angled kink
//!   cos 45° of [u] (docs/design.md).

use crate::contact::KktResiduals;
use crate::mesh::{frame_directions, Mesh, PTopology};
use crate::problem::MultiplierSpace;

/// A discrete multiplier on the cracks (cracks concatenated in order).
#[derive(Clone, Debug)]
pub enum CrackField {
    /// One value per crack edge (M0), in the order of [`CrackOperators::segments`].
    PerSegment(Vec<f64>),
    /// Nodal values of a continuous P1 function on each crack (M1, M1star).
    PerNode(Vec<f64>),
}

/// One row of N: p at a crack node's vertex, dotted with a normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceRow {
    /// The crack node (index into [`CrackOperators::points`]).
    pub node: usize,
    /// The unit normal ν.
    pub normal: [f64; 2],
}

/// The crack geometry seen by the multipliers, and the normal-trace operator N.
#[derive(Clone, Debug)]
pub struct CrackOperators {
    /// For each crack node: the p unknowns (2v, 2v + 1) of its vertex v.
    pub node_p_dofs: Vec<[usize; 2]>,
    /// Crack node coordinates.
    pub points: Vec<[f64; 2]>,
    /// Crack edges as pairs of crack nodes (within one crack).
    pub segments: Vec<[usize; 2]>,
    /// Edge lengths ℓ_k.
    pub lengths: Vec<f64>,
    /// Edge normals ν_k.
    pub normals: Vec<[f64; 2]>,
    /// The rows of N.
    pub rows: Vec<TraceRow>,
    /// Per row: its weights on the two p unknowns of its node (`node_p_dofs`): the row's normal
    /// in the (x, y) frame; see [`CrackOperators::with_p_topology`].
    pub row_weights: Vec<[f64; 2]>,
    /// For each edge k: the rows (x_k, ν_k) and (x_{k+1}, ν_k).
    pub segment_rows: Vec<[usize; 2]>,
    /// Per crack: its first node and its node count.
    pub crack_nodes: Vec<(usize, usize)>,
}

impl CrackOperators {
    /// Builds N's data from the mesh's crack chains.
    pub fn new(mesh: &Mesh) -> CrackOperators {
        let mut ops = CrackOperators {
            node_p_dofs: Vec::new(),
            points: Vec::new(),
            segments: Vec::new(),
            lengths: Vec::new(),
            normals: Vec::new(),
            rows: Vec::new(),
            row_weights: Vec::new(),
            segment_rows: Vec::new(),
            crack_nodes: Vec::new(),
        };
        for chain in &mesh.cracks {
            let first = ops.points.len();
            ops.crack_nodes.push((first, chain.nodes.len()));
            let last = chain.nodes.len() - 1;
            // the first and last trace row of each node of this crack
            let mut node_rows = Vec::with_capacity(chain.nodes.len());
            for (j, &v) in chain.nodes.iter().enumerate() {
                let node = first + j;
                ops.node_p_dofs.push([2 * v, 2 * v + 1]);
                ops.points.push(mesh.vertices[v]);
                let before = (j > 0).then(|| chain.normals[j - 1]);
                let after = (j < last).then(|| chain.normals[j]);
                let first_row = ops.rows.len();
                match (before, after) {
                    (Some(a), Some(b)) if a != b => {
                        ops.rows.push(TraceRow { node, normal: a });
                        ops.rows.push(TraceRow { node, normal: b });
                    }
                    (Some(a), _) | (None, Some(a)) => ops.rows.push(TraceRow { node, normal: a }),
                    (None, None) => unreachable!("a crack chain has at least two nodes"),
                }
                node_rows.push((first_row, ops.rows.len() - 1));
            }
            for k in 0..last {
                let (a, b) = (ops.points[first + k], ops.points[first + k + 1]);
                ops.segments.push([first + k, first + k + 1]);
                ops.lengths.push((b[0] - a[0]).hypot(b[1] - a[1]));
                ops.normals.push(chain.normals[k]);
                // edge k: the last row of node k and the first row of node k + 1
                ops.segment_rows.push([node_rows[k].1, node_rows[k + 1].0]);
            }
        }
        ops.row_weights = ops.rows.iter().map(|r| r.normal).collect();
        ops
    }

    /// The same operators for the p unknowns of `ptopo`: a row at a node whose vertex has the
    /// (ν, τ) frame weighs its unknowns by (ν_r·ν, ν_r·τ), exactly (1, 0) where ν_r = ν (every
    /// row there: only nodes with one normal are doubled).
    pub fn with_p_topology(mut self, ptopo: &PTopology) -> CrackOperators {
        for (r, w) in self.rows.iter().zip(self.row_weights.iter_mut()) {
            let v = self.node_p_dofs[r.node][0] / 2;
            if let Some(nu) = ptopo.vertex_normal(v) {
                let [a, b] = r.normal;
                *w = if r.normal == nu {
                    [1.0, 0.0]
                } else {
                    frame_directions(nu).map(|d| a * d[0] + b * d[1])
                };
            }
        }
        self
    }

    /// Number of crack nodes (all cracks).
    pub fn nodes(&self) -> usize {
        self.node_p_dofs.len()
    }

    /// (NP)_r = p(x_node(r))·ν_r for every trace row r.
    pub fn apply_n(&self, p: &[f64]) -> Vec<f64> {
        self.rows
            .iter()
            .zip(&self.row_weights)
            .map(|(r, w)| {
                let d = self.node_p_dofs[r.node];
                p[d[0]] * w[0] + p[d[1]] * w[1]
            })
            .collect()
    }

    /// Adds Nᵀ y (y one value per trace row) to the p part `out`.
    pub fn add_nt(&self, y: &[f64], out: &mut [f64]) {
        for ((r, w), &v) in self.rows.iter().zip(&self.row_weights).zip(y) {
            let d = self.node_p_dofs[r.node];
            out[d[0]] += v * w[0];
            out[d[1]] += v * w[1];
        }
    }

    /// H_N = N A Nᵀ (row-major, rows × rows) from A = K⁻¹ restricted to the crack nodes' p
    /// unknowns, `inv` row-major over [`CrackOperators::node_p_dofs`] flattened.
    pub fn h_n_from_node_block(&self, inv: &[f64]) -> Vec<f64> {
        let (m, c) = (self.rows.len(), 2 * self.nodes());
        let mut h_n = vec![0.0; m * m];
        for (i, (ri, wi)) in self.rows.iter().zip(&self.row_weights).enumerate() {
            for (j, (rj, wj)) in self.rows.iter().zip(&self.row_weights).enumerate() {
                let mut v = 0.0;
                for a in 0..2 {
                    for b in 0..2 {
                        v += wi[a] * wj[b] * inv[(2 * ri.node + a) * c + 2 * rj.node + b];
                    }
                }
                h_n[i * m + j] = v;
            }
        }
        h_n
    }

    /// The nodal normal ν̄_j of each crack node: its edges' normal where they agree, and at a
    /// kink the normalised ℓ_{k−1}ν_{k−1} + ℓ_kν_k (M1star's constraint direction, module
    /// documentation). The references evaluate a face of the crack along it.
    pub fn node_normals(&self) -> Vec<[f64; 2]> {
        let mut sum = vec![[0.0, 0.0]; self.nodes()];
        let mut single: Vec<Option<[f64; 2]>> = vec![None; self.nodes()];
        let mut kink = vec![false; self.nodes()];
        for ((&[i, j], &l), &nu) in self.segments.iter().zip(&self.lengths).zip(&self.normals) {
            for n in [i, j] {
                sum[n] = [sum[n][0] + l * nu[0], sum[n][1] + l * nu[1]];
                match single[n] {
                    Some(other) if other != nu => kink[n] = true,
                    _ => single[n] = Some(nu),
                }
            }
        }
        (0..self.nodes())
            .map(|n| match (kink[n], single[n]) {
                (false, Some(nu)) => nu,
                _ => {
                    let norm = sum[n][0].hypot(sum[n][1]);
                    [sum[n][0] / norm, sum[n][1] / norm]
                }
            })
            .collect()
    }

    /// The scalar P1 mass matrix M_c of the cracks (dense, nodes², block diagonal by crack).
    pub fn crack_mass(&self) -> Vec<Vec<f64>> {
        let m = self.nodes();
        let mut mc = vec![vec![0.0; m]; m];
        for (&[i, j], &l) in self.segments.iter().zip(&self.lengths) {
            mc[i][i] += l / 3.0;
            mc[j][j] += l / 3.0;
            mc[i][j] += l / 6.0;
            mc[j][i] += l / 6.0;
        }
        mc
    }
}

/// How λ_h is read off the LCP unknowns μ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Recovery {
    /// λ_h = Λ, one value per edge.
    PerSegment,
    /// λ_h = Λ, nodal.
    PerNode,
    /// λ_h = M_c⁻¹ Λ̃ (μ are the dual-cone moments ∫ λ φ_j).
    DualMoments,
}

/// One multiplier space on the cracks: S of D = S N and how λ_h comes from μ.
#[derive(Clone, Debug)]
pub struct Multiplier {
    /// Which space.
    pub space: MultiplierSpace,
    /// S (rows: multipliers, columns: trace rows of N).
    pub s: Vec<Vec<f64>>,
    recovery: Recovery,
}

impl Multiplier {
    /// The space's constraint map on the cracks of `ops` (module documentation).
    pub fn new(space: MultiplierSpace, ops: &CrackOperators) -> Multiplier {
        let rows = ops.rows.len();
        let zeros = || vec![0.0; rows];
        let (s, recovery) = match space {
            MultiplierSpace::M0 => {
                let s = ops
                    .segment_rows
                    .iter()
                    .zip(&ops.lengths)
                    .map(|(&[a, b], &l)| {
                        let mut row = zeros();
                        row[a] = l / 2.0;
                        row[b] = l / 2.0;
                        row
                    })
                    .collect();
                (s, Recovery::PerSegment)
            }
            MultiplierSpace::M1 => {
                let mut s = vec![zeros(); ops.nodes()];
                for ((&[i, j], &[a, b]), &l) in
                    ops.segments.iter().zip(&ops.segment_rows).zip(&ops.lengths)
                {
                    s[i][a] += l / 3.0;
                    s[j][b] += l / 3.0;
                    s[i][b] += l / 6.0;
                    s[j][a] += l / 6.0;
                }
                (s, Recovery::PerNode)
            }
            MultiplierSpace::M1Star => (m1star_rows(ops), Recovery::DualMoments),
        };
        Multiplier { space, s, recovery }
    }

    /// Number of multipliers.
    pub fn len(&self) -> usize {
        self.s.len()
    }

    /// Whether there is no multiplier (no crack).
    pub fn is_empty(&self) -> bool {
        self.s.is_empty()
    }

    /// Sᵀ μ, one value per trace row.
    pub fn transpose_apply(&self, mu: &[f64]) -> Vec<f64> {
        let m = self.s.first().map_or(0, Vec::len);
        (0..m)
            .map(|j| self.s.iter().zip(mu).map(|(row, mu)| row[j] * mu).sum())
            .collect()
    }

    /// λ_h from the LCP unknowns μ.
    pub fn lambda_field(&self, ops: &CrackOperators, mu: &[f64]) -> CrackField {
        match self.recovery {
            Recovery::PerSegment => CrackField::PerSegment(mu.to_vec()),
            Recovery::PerNode => CrackField::PerNode(mu.to_vec()),
            Recovery::DualMoments => CrackField::PerNode(solve_tridiagonal(&ops.crack_mass(), mu)),
        }
    }

    /// Feasibility and complementarity of μ and y = D P = S N P, with P the p part of x:
    /// y is measured against ‖S‖_∞ ‖P‖_∞, the size of p (not of p·ν on Γc, ≈ 0 where a crack is
    /// open).
    pub fn kkt_constraint_part(&self, ops: &CrackOperators, mu: &[f64], p: &[f64]) -> KktResiduals {
        let np = ops.apply_n(p);
        let y: Vec<f64> = self
            .s
            .iter()
            .map(|row| row.iter().zip(&np).map(|(a, b)| a * b).sum())
            .collect();
        let s_norm = self
            .s
            .iter()
            .map(|row| row.iter().map(|v| v.abs()).sum::<f64>())
            .fold(0.0, f64::max);
        let p_inf = p.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        KktResiduals::constraint_part(mu, &y, s_norm * p_inf)
    }
}

/// M1star's rows: p(x_j)·n_j with n_j = ν away from kinks and
/// (ℓ_{k−1}ν_{k−1} + ℓ_kν_k)/(ℓ_{k−1} + ℓ_k) at a kink (module documentation).
fn m1star_rows(ops: &CrackOperators) -> Vec<Vec<f64>> {
    let rows = ops.rows.len();
    // the edges at each node: (edge, its row at this node)
    let mut edges_at: Vec<Vec<(usize, usize)>> = vec![Vec::new(); ops.nodes()];
    for (k, (&[i, j], &[a, b])) in ops.segments.iter().zip(&ops.segment_rows).enumerate() {
        edges_at[i].push((k, a));
        edges_at[j].push((k, b));
    }
    edges_at
        .iter()
        .map(|edges| {
            let mut row = vec![0.0; rows];
            let distinct: Vec<usize> = {
                let mut r: Vec<usize> = edges.iter().map(|e| e.1).collect();
                r.dedup();
                r
            };
            if let [r] = distinct[..] {
                row[r] = 1.0;
                return row;
            }
            // ∫ φ_j = (ℓ_{k−1} + ℓ_k)/2; each edge's row gets its share ℓ_k/(ℓ_{k−1} + ℓ_k)
            let hat: f64 = edges.iter().map(|&(k, _)| ops.lengths[k]).sum();
            for &(k, r) in edges {
                row[r] += ops.lengths[k] / hat;
            }
            row
        })
        .collect()
}

/// Solves a tridiagonal system given as a dense matrix (Thomas algorithm; M_c is SPD, and its
/// zero couplings between cracks split it into independent blocks).
fn solve_tridiagonal(a: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
    let n = b.len();
    let mut c = vec![0.0; n];
    let mut d = vec![0.0; n];
    for i in 0..n {
        let lower = if i > 0 { a[i][i - 1] } else { 0.0 };
        let upper = if i + 1 < n { a[i][i + 1] } else { 0.0 };
        let denom = a[i][i] - if i > 0 { lower * c[i - 1] } else { 0.0 };
        c[i] = upper / denom;
        d[i] = (b[i] - if i > 0 { lower * d[i - 1] } else { 0.0 }) / denom;
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        x[i] = d[i] - if i + 1 < n { c[i] * x[i + 1] } else { 0.0 };
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::structured::structured;
    use crate::problem::{Polyline, UNIT_SQUARE};

    fn mesh(cracks: &[Vec<[f64; 2]>], level: u32) -> Mesh {
        let cracks: Vec<Polyline> = cracks
            .iter()
            .map(|p| Polyline { points: p.clone() })
            .collect();
        structured(UNIT_SQUARE, [4, 4], &cracks, level).unwrap()
    }

    /// p = constant vector q at every vertex.
    fn constant_p(m: &Mesh, q: [f64; 2]) -> Vec<f64> {
        (0..m.vertices.len()).flat_map(|_| q).collect()
    }

    #[test]
    fn straight_crack_maps_are_the_papers() {
        let m = mesh(&[vec![[-0.5, 0.0], [0.5, 0.0]]], 2);
        let ops = CrackOperators::new(&m);
        assert_eq!(ops.rows.len(), ops.nodes(), "one trace row per node");
        for space in MultiplierSpace::ALL {
            let s = Multiplier::new(space, &ops).s;
            let total: f64 = s.iter().flatten().sum();
            let expected = if space == MultiplierSpace::M1Star {
                ops.nodes() as f64
            } else {
                1.0
            };
            assert!((total - expected).abs() < 1e-14, "{space}: {total}");
        }
        // M1's S is the crack mass matrix
        assert_eq!(
            Multiplier::new(MultiplierSpace::M1, &ops).s,
            ops.crack_mass()
        );
        // N applied to p = (0, 1) is ν·p = 1 at every node
        let p = constant_p(&m, [0.0, 1.0]);
        assert!(ops.apply_n(&p).iter().all(|&v| (v - 1.0).abs() < 1e-15));
    }

    /// A kinked crack (−0.5, 0) → (0, 0) → (0.5, 0.5): edges of the first segment have
    /// ν = (0, 1), of the second ν = (−1, 1)/√2; the kink node has two trace rows.
    #[test]
    fn kink_node_has_two_rows_and_the_stated_m1star_normal() {
        let m = mesh(&[vec![[-0.5, 0.0], [0.0, 0.0], [0.5, 0.5]]], 1);
        let ops = CrackOperators::new(&m);
        assert_eq!(ops.rows.len(), ops.nodes() + 1);
        let kink = ops.points.iter().position(|p| *p == [0.0, 0.0]).unwrap();
        let kink_rows: Vec<&TraceRow> = ops.rows.iter().filter(|r| r.node == kink).collect();
        assert_eq!(kink_rows.len(), 2);
        assert_eq!(kink_rows[0].normal, [0.0, 1.0]);
        let r = 0.5f64.sqrt();
        assert!((kink_rows[1].normal[0] + r).abs() < 1e-15);
        // every M0/M1 constraint of a constant p is ∫ φ p·ν: for p = q, Σ_rows S_ir (q·ν_r)
        // equals Σ over the edges of the multiplier's support of (∫ weight) q·ν_k
        let q = [0.3, -0.7];
        let np = ops.apply_n(&constant_p(&m, q));
        let dot = |nu: [f64; 2]| q[0] * nu[0] + q[1] * nu[1];
        let m1 = Multiplier::new(MultiplierSpace::M1, &ops);
        for (j, row) in m1.s.iter().enumerate() {
            let y: f64 = row.iter().zip(&np).map(|(a, b)| a * b).sum();
            let expected: f64 = ops
                .segments
                .iter()
                .enumerate()
                .filter(|(_, s)| s.contains(&j))
                .map(|(k, _)| ops.lengths[k] / 2.0 * dot(ops.normals[k]))
                .sum();
            assert!((y - expected).abs() < 1e-15, "M1 row {j}");
        }
        // M1star at the kink: p·n with n = (ℓ_a ν_a + ℓ_b ν_b)/(ℓ_a + ℓ_b) (the edges have the
        // level-1 lengths 0.25 and 0.25√2), M1's row of a constant p over ∫ φ_kink
        let star = Multiplier::new(MultiplierSpace::M1Star, &ops);
        let (la, lb) = (0.25, 0.25 * 2f64.sqrt());
        let n = [
            (la * 0.0 + lb * -r) / (la + lb),
            (la * 1.0 + lb * r) / (la + lb),
        ];
        let y: f64 = star.s[kink].iter().zip(&np).map(|(a, b)| a * b).sum();
        assert!((y - dot(n)).abs() < 1e-15);
        let y1: f64 = m1.s[kink].iter().zip(&np).map(|(a, b)| a * b).sum();
        assert!((y - y1 / ((la + lb) / 2.0)).abs() < 1e-15);
        assert!((star.s[kink].iter().sum::<f64>() - 1.0).abs() < 1e-15);
        // away from the kink the M1star rows are unit rows
        for (j, row) in star.s.iter().enumerate().filter(|(j, _)| *j != kink) {
            assert_eq!(row.iter().filter(|&&v| v != 0.0).count(), 1, "row {j}");
            assert_eq!(row.iter().sum::<f64>(), 1.0);
        }
    }

    /// A polyline whose points are collinear is the straight crack: same rows, same maps.
    #[test]
    fn collinear_polyline_is_the_straight_crack() {
        let straight = CrackOperators::new(&mesh(&[vec![[-0.5, 0.0], [0.5, 0.0]]], 2));
        let split = CrackOperators::new(&mesh(&[vec![[-0.5, 0.0], [0.0, 0.0], [0.5, 0.0]]], 2));
        assert_eq!(straight.rows, split.rows);
        for space in MultiplierSpace::ALL {
            assert_eq!(
                Multiplier::new(space, &straight).s,
                Multiplier::new(space, &split).s
            );
        }
    }

    /// Two cracks: nodes and segments concatenated, no edge joins them, M_c block diagonal.
    #[test]
    fn two_cracks_are_independent_blocks() {
        let m = mesh(
            &[
                vec![[-0.5, -0.5], [0.0, -0.5]],
                vec![[0.0, 0.5], [0.5, 0.5]],
            ],
            1,
        );
        let ops = CrackOperators::new(&m);
        assert_eq!(ops.crack_nodes, vec![(0, 3), (3, 3)]);
        assert_eq!(ops.segments, vec![[0, 1], [1, 2], [3, 4], [4, 5]]);
        let mc = ops.crack_mass();
        assert_eq!(mc[2][3], 0.0);
        assert_eq!(mc[3][2], 0.0);
        let star = Multiplier::new(MultiplierSpace::M1Star, &ops);
        // λ_h = M_c⁻¹ Λ̃: the moments of λ = 1 on both cracks give back 1
        let moments: Vec<f64> = mc.iter().map(|row| row.iter().sum()).collect();
        match star.lambda_field(&ops, &moments) {
            CrackField::PerNode(v) => assert!(v.iter().all(|x| (x - 1.0).abs() < 1e-14)),
            CrackField::PerSegment(_) => panic!("M1star is nodal"),
        }
    }
}
