//! Fill-reducing elimination order of the condensed system: geometric nested dissection.
//!
//! Owns the choice of the order in which the sparse LDLᵀ eliminates the unknowns. The mesh is a
//! structured `nx × ny` grid of vertices `v = j (nx + 1) + i`, and every matrix entry couples two
//! vertices of one triangle, so `|Δi| ≤ 1` and `|Δj| ≤ 1` along every edge of the matrix graph: a
//! full grid line of vertices separates the two halves of a box. The order is built by recursive
//! bisection of the vertex box along its longer side (halves first, then the separating line), with
//! all unknowns of a vertex kept together, and the unknowns flagged `last` (the crack's p unknowns)
//! moved behind everything else. Those then form the trailing block of the factor, from which
//! [`crate::linalg::Ldlt::trailing_inverse`] reads `K⁻¹` restricted to the crack.
//!
//! On a 2D grid nested dissection gives O(n log n) fill and O(n^{3/2}) flops (George 1973), and the
//! order is computed in O(n) time, where faer's AMD spends several seconds on 10⁶ vertices.
//!
//! Unstructured meshes ([`nested_dissection_mesh`]) get the same recursion on the vertex graph:
//! the vertices of a part are split at the median coordinate along the part's longer side, and
//! the separator is the layer of the lower half's vertices with a neighbour in the upper half
//! (`reach` layers thick, each the neighbours of the previous one), so no matrix entry couples the
//! two remaining halves. Geometric bisection of a quasi-uniform mesh gives O(√n) separators, as
//! grid lines do, in O(n log n) time.

use crate::mesh::{Layout, Mesh, PTopology, UTopology};
use crate::multiplier::CrackOperators;
use crate::problem::PMass;

/// Boxes with at most this many vertices are not split further (ordered row by row).
const LEAF_VERTICES: usize = 64;

/// Elimination order of a set of unknowns attached to the vertices of an `nx × ny` grid.
///
/// `vertex_of[k]` is the grid vertex `j (nx + 1) + i` of unknown `k`; the unknowns with
/// `last[k] = true` are placed at the end, in increasing index order. Returns `order`, with
/// `order[position] = unknown` (a permutation of `0..vertex_of.len()`).
///
/// # Panics
/// If a vertex index is outside the grid or `last.len() != vertex_of.len()` (caller bug).
pub fn nested_dissection(nx: usize, ny: usize, vertex_of: &[usize], last: &[bool]) -> Vec<usize> {
    nested_dissection_with_reach(nx, ny, vertex_of, last, 1)
}

/// As [`nested_dissection`] for a matrix whose entries couple vertices up to `reach` grid steps
/// apart (`|Δi|, |Δj| ≤ reach`): separators are `reach` grid lines thick. `reach = 1` is
/// [`nested_dissection`]; the lumped p mass's S(δ) = C + δM + B̃D⁻¹B̃ᵀ has `reach = 2` (two u
/// dofs couple through a p vertex of both their patches).
///
/// # Panics
/// As [`nested_dissection`], and if `reach == 0`.
pub fn nested_dissection_with_reach(
    nx: usize,
    ny: usize,
    vertex_of: &[usize],
    last: &[bool],
    reach: usize,
) -> Vec<usize> {
    assert!(reach >= 1, "nested_dissection: reach 0");
    assert_eq!(vertex_of.len(), last.len(), "nested_dissection: lengths");
    let n_vertices = (nx + 1) * (ny + 1);
    let (start, unknowns) = unknowns_by_vertex(n_vertices, vertex_of, last);
    let grid = Grid {
        reach,
        stride: nx + 1,
        start: &start,
        unknowns: &unknowns,
    };
    let mut order = Vec::with_capacity(vertex_of.len());
    grid.dissect(
        Block {
            i0: 0,
            i1: nx + 1,
            j0: 0,
            j1: ny + 1,
        },
        &mut order,
    );
    order.extend((0..vertex_of.len()).filter(|&k| last[k]));
    order
}

/// The unknowns of each of `n_vertices` vertices in CSR form (`unknowns[start[v]..start[v + 1]]`,
/// in increasing unknown order), leaving out those flagged `last`.
///
/// # Panics
/// If a vertex index is `n_vertices` or more (caller bug).
fn unknowns_by_vertex(
    n_vertices: usize,
    vertex_of: &[usize],
    last: &[bool],
) -> (Vec<usize>, Vec<usize>) {
    let mut start = vec![0usize; n_vertices + 1];
    for (k, &v) in vertex_of.iter().enumerate() {
        assert!(v < n_vertices, "nested dissection: vertex {v} out of range");
        if !last[k] {
            start[v + 1] += 1;
        }
    }
    for v in 0..n_vertices {
        start[v + 1] += start[v];
    }
    let mut fill = start.clone();
    let mut unknowns = vec![0usize; start[n_vertices]];
    for (k, &v) in vertex_of.iter().enumerate() {
        if !last[k] {
            unknowns[fill[v]] = k;
            fill[v] += 1;
        }
    }
    (start, unknowns)
}

/// A half-open box `[i0, i1) × [j0, j1)` of grid vertices.
#[derive(Clone, Copy, Debug)]
struct Block {
    i0: usize,
    i1: usize,
    j0: usize,
    j1: usize,
}

impl Block {
    fn vertices(&self) -> usize {
        (self.i1 - self.i0) * (self.j1 - self.j0)
    }

    /// The block cut across its i lines (`along_i`) or its j lines: `[before, after,
    /// separator]`, the separator being the `reach` lines from the middle one `mid = lo +
    /// (hi − lo)/2` of the range `[lo, hi)` (clipped at `hi`), before and after the lines on
    /// either side of it.
    fn split(self, along_i: bool, reach: usize) -> [Block; 3] {
        let (lo, hi) = if along_i {
            (self.i0, self.i1)
        } else {
            (self.j0, self.j1)
        };
        let mid = lo + (hi - lo) / 2;
        let end = (mid + reach).min(hi);
        let lines = |start: usize, stop: usize| {
            if along_i {
                Block {
                    i0: start,
                    i1: stop,
                    ..self
                }
            } else {
                Block {
                    j0: start,
                    j1: stop,
                    ..self
                }
            }
        };
        [lines(lo, mid), lines(end, hi), lines(mid, end)]
    }
}

/// The grid's unknowns grouped by vertex.
struct Grid<'a> {
    /// Separator thickness in grid lines.
    reach: usize,
    stride: usize,
    start: &'a [usize],
    unknowns: &'a [usize],
}

impl Grid<'_> {
    /// Appends the unknowns of `block` in nested-dissection order.
    fn dissect(&self, block: Block, order: &mut Vec<usize>) {
        if block.i1 <= block.i0 || block.j1 <= block.j0 {
            return;
        }
        let (ni, nj) = (block.i1 - block.i0, block.j1 - block.j0);
        let r = self.reach;
        if block.vertices() <= LEAF_VERTICES || (ni < 2 * r + 1 && nj < 2 * r + 1) {
            self.emit(block, order);
            return;
        }
        let [before, after, separator] = block.split(ni >= nj, r);
        self.dissect(before, order);
        self.dissect(after, order);
        self.emit(separator, order);
    }

    /// Appends every unknown of `block`, vertex by vertex.
    fn emit(&self, block: Block, order: &mut Vec<usize>) {
        for j in block.j0..block.j1 {
            for i in block.i0..block.i1 {
                let v = j * self.stride + i;
                order.extend_from_slice(&self.unknowns[self.start[v]..self.start[v + 1]]);
            }
        }
    }
}

/// Elimination order of unknowns attached to the vertices of an unstructured triangulation,
/// with every matrix entry coupling vertices at most `reach` edges apart (module
/// documentation). `vertex_of` and `last` as in [`nested_dissection`].
///
/// # Panics
/// If a vertex index is out of range, `last.len() != vertex_of.len()` or `reach == 0`.
pub fn nested_dissection_mesh(
    vertices: &[[f64; 2]],
    triangles: &[[usize; 3]],
    vertex_of: &[usize],
    last: &[bool],
    reach: usize,
) -> Vec<usize> {
    assert!(reach >= 1, "nested_dissection_mesh: reach 0");
    assert_eq!(
        vertex_of.len(),
        last.len(),
        "nested_dissection_mesh: lengths"
    );
    let n = vertices.len();
    let (start, unknowns) = unknowns_by_vertex(n, vertex_of, last);
    let graph = VertexGraph::new(n, triangles);
    let mut dissection = Dissection {
        vertices,
        graph: &graph,
        reach,
        stamp: vec![0; n],
        next_stamp: 0,
        vertex_order: Vec::with_capacity(n),
    };
    dissection.dissect((0..n).collect());
    let mut order = Vec::with_capacity(vertex_of.len());
    for &v in &dissection.vertex_order {
        order.extend_from_slice(&unknowns[start[v]..start[v + 1]]);
    }
    order.extend((0..vertex_of.len()).filter(|&k| last[k]));
    order
}

/// Vertex adjacency (vertices sharing a triangle), CSR.
struct VertexGraph {
    start: Vec<usize>,
    neighbours: Vec<usize>,
}

impl VertexGraph {
    fn new(n: usize, triangles: &[[usize; 3]]) -> VertexGraph {
        let mut pairs: Vec<(usize, usize)> = triangles
            .iter()
            .flat_map(|t| {
                [(0, 1), (1, 2), (2, 0)]
                    .into_iter()
                    .flat_map(move |(a, b)| [(t[a], t[b]), (t[b], t[a])])
            })
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        let mut start = vec![0usize; n + 1];
        for &(a, _) in &pairs {
            start[a + 1] += 1;
        }
        for v in 0..n {
            start[v + 1] += start[v];
        }
        VertexGraph {
            start,
            neighbours: pairs.into_iter().map(|(_, b)| b).collect(),
        }
    }

    fn of(&self, v: usize) -> &[usize] {
        &self.neighbours[self.start[v]..self.start[v + 1]]
    }
}

/// The recursion of [`nested_dissection_mesh`]; `stamp` marks the vertices of a set in O(1).
struct Dissection<'a> {
    vertices: &'a [[f64; 2]],
    graph: &'a VertexGraph,
    reach: usize,
    stamp: Vec<u32>,
    next_stamp: u32,
    vertex_order: Vec<usize>,
}

impl Dissection<'_> {
    fn mark(&mut self, set: &[usize]) -> u32 {
        self.next_stamp += 1;
        for &v in set {
            self.stamp[v] = self.next_stamp;
        }
        self.next_stamp
    }

    /// Appends the vertices of `part` in nested-dissection order.
    fn dissect(&mut self, mut part: Vec<usize>) {
        if part.len() <= LEAF_VERTICES {
            part.sort_unstable();
            self.vertex_order.extend(part);
            return;
        }
        let (lo, hi) = part.iter().fold(
            ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
            |(lo, hi), &v| {
                let p = self.vertices[v];
                (
                    [lo[0].min(p[0]), lo[1].min(p[1])],
                    [hi[0].max(p[0]), hi[1].max(p[1])],
                )
            },
        );
        let axis = usize::from(hi[1] - lo[1] > hi[0] - lo[0]);
        let mid = part.len() / 2;
        let key = |v: usize| (self.vertices[v][axis], v);
        part.select_nth_unstable_by(mid, |&a, &b| key(a).partial_cmp(&key(b)).expect("finite"));
        let upper = part.split_off(mid);
        let mut lower = part;
        // separator layers: lower vertices next to the upper half, then next to the last layer
        let mut separator = Vec::new();
        let mut front = self.mark(&upper);
        for _ in 0..self.reach {
            let layer: Vec<usize> = lower
                .iter()
                .copied()
                .filter(|&v| self.graph.of(v).iter().any(|&w| self.stamp[w] == front))
                .collect();
            if layer.is_empty() {
                break;
            }
            let in_layer = self.mark(&layer);
            lower.retain(|&v| self.stamp[v] != in_layer);
            separator.extend(layer);
            front = in_layer;
        }
        if lower.is_empty() {
            // nothing separated (a part too thin to cut): emit it as a leaf
            let mut all = separator;
            all.extend(upper);
            all.sort_unstable();
            self.vertex_order.extend(all);
            return;
        }
        self.dissect(lower);
        self.dissect(upper);
        separator.sort_unstable();
        self.vertex_order.extend(separator);
    }
}

/// The elimination order of K, with the crack nodes' p unknowns last so that the factor's
/// trailing block yields H_N.
///
/// Consistent p mass: nested dissection of the vertex grid, p and u unknowns of a vertex
/// together. Lumped p mass: the p–p block is diagonal, so the other p unknowns go first: each
/// is a diagonal pivot whose elimination adds B̃D⁻¹B̃ᵀ to the u block and nothing else, so what
/// the factor then does on the u unknowns (in nested-dissection order) is exactly the Cholesky
/// of −S(δ) = −(C + δM + B̃D⁻¹B̃ᵀ), one unknown per dof instead of three.
pub fn elimination_order(
    mesh: &Mesh,
    topo: &UTopology,
    ptopo: &PTopology,
    ops: &CrackOperators,
    p_mass: PMass,
) -> Vec<usize> {
    let n_p = ptopo.n_dofs;
    let mut crack_p = vec![false; n_p];
    for &k in ops.node_p_dofs.iter().flatten() {
        crack_p[k] = true;
    }
    match p_mass {
        PMass::Consistent => {
            let vertex_of: Vec<usize> = ptopo
                .dof_vertex(mesh.vertices.len())
                .into_iter()
                .chain(topo.dof_vertex.iter().copied())
                .collect();
            let mut last = crack_p;
            last.resize(vertex_of.len(), false);
            vertex_order(mesh, &vertex_of, &last, 1)
        }
        PMass::Lumped => {
            // S couples u dofs two grid steps apart (through a p vertex of both patches)
            let u_order = vertex_order(
                mesh,
                &topo.dof_vertex,
                &vec![false; topo.dof_vertex.len()],
                2,
            );
            (0..n_p)
                .filter(|&k| !crack_p[k])
                .chain(u_order.into_iter().map(|k| n_p + k))
                .chain((0..n_p).filter(|&k| crack_p[k]))
                .collect()
        }
    }
}

/// Nested dissection of unknowns on the vertices of `mesh`: by grid
/// lines on a structured grid, by the vertex graph on a refined mesh.
fn vertex_order(mesh: &Mesh, vertex_of: &[usize], last: &[bool], reach: usize) -> Vec<usize> {
    match mesh.layout {
        Layout::Structured { nx, ny } => {
            nested_dissection_with_reach(nx, ny, vertex_of, last, reach)
        }
        Layout::Refined { .. } | Layout::Graded { .. } => {
            nested_dissection_mesh(&mesh.vertices, &mesh.triangles, vertex_of, last, reach)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn is_a_permutation_with_flagged_unknowns_last() {
        let (nx, ny) = (37, 20);
        let nv = (nx + 1) * (ny + 1);
        // three unknowns per vertex plus a few duplicated ones, like the broken u space
        let mut vertex_of: Vec<usize> = (0..3 * nv).map(|k| k / 3).collect();
        vertex_of.extend([5, 6, 7]);
        let last: Vec<bool> = (0..vertex_of.len()).map(|k| k % 97 == 3).collect();
        let order = nested_dissection(nx, ny, &vertex_of, &last);
        let mut seen = vec![false; vertex_of.len()];
        for &k in &order {
            assert!(!seen[k]);
            seen[k] = true;
        }
        assert!(seen.iter().all(|&s| s));
        let flagged = last.iter().filter(|&&l| l).count();
        assert!(order[order.len() - flagged..].iter().all(|&k| last[k]));
        assert!(order[..order.len() - flagged].iter().all(|&k| !last[k]));
    }

    #[test]
    fn a_reach_two_separator_is_two_lines_thick() {
        // 40 × 2 cells, reach 2: the first cut is the lines i = 20, 21, eliminated last.
        let (nx, ny) = (40, 2);
        let vertex_of: Vec<usize> = (0..(nx + 1) * (ny + 1)).collect();
        let last = vec![false; vertex_of.len()];
        let order = nested_dissection_with_reach(nx, ny, &vertex_of, &last, 2);
        let mut tail: Vec<usize> = order[order.len() - 6..].to_vec();
        tail.sort_unstable();
        assert_eq!(tail, vec![20, 21, 61, 62, 102, 103]);
        let mut sorted = order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, vertex_of, "a permutation");
    }

    #[test]
    fn separator_is_eliminated_after_both_halves() {
        // 40 × 2 cells: the first cut is the vertical line i = 20, emitted after everything else.
        let (nx, ny) = (40, 2);
        let vertex_of: Vec<usize> = (0..(nx + 1) * (ny + 1)).collect();
        let last = vec![false; vertex_of.len()];
        let order = nested_dissection(nx, ny, &vertex_of, &last);
        let tail: Vec<usize> = order[order.len() - 3..].to_vec();
        assert_eq!(tail, vec![20, 20 + 41, 20 + 82]);
    }

    /// On the structured grid's triangles the mesh version is a permutation with the flagged
    /// unknowns last, and its separators are genuine: the fill of a Cholesky factor in this
    /// order is far below the fill of the natural order.
    #[test]
    fn mesh_dissection_is_a_permutation_with_separators() {
        let (nx, ny) = (30, 30);
        let vertices: Vec<[f64; 2]> = (0..=ny)
            .flat_map(|j| (0..=nx).map(move |i| [i as f64, j as f64]))
            .collect();
        let triangles = crate::mesh::structured::grid_triangles(nx, ny);
        for reach in [1, 2] {
            let vertex_of: Vec<usize> = (0..2 * vertices.len()).map(|k| k / 2).collect();
            let last: Vec<bool> = (0..vertex_of.len()).map(|k| k % 101 == 7).collect();
            let order = nested_dissection_mesh(&vertices, &triangles, &vertex_of, &last, reach);
            let mut sorted = order.clone();
            sorted.sort_unstable();
            assert_eq!(sorted, (0..vertex_of.len()).collect::<Vec<_>>());
            let flagged = last.iter().filter(|&&l| l).count();
            assert!(order[order.len() - flagged..].iter().all(|&k| last[k]));
            // the last unflagged vertices form the first separator: a line across the square
            let tail: Vec<usize> = order[order.len() - flagged - 2 * (ny + 1) * reach..]
                .iter()
                .filter(|&&k| !last[k])
                .map(|&k| vertex_of[k])
                .collect();
            let xs: std::collections::BTreeSet<i64> =
                tail.iter().map(|&v| vertices[v][0] as i64).collect();
            assert!(
                xs.len() <= reach + 1,
                "reach {reach}: separator columns {xs:?}"
            );
        }
    }
}
