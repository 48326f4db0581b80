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
    // unknowns of each vertex, in CSR form (kept in increasing unknown order)
    let mut start = vec![0usize; n_vertices + 1];
    for (k, &v) in vertex_of.iter().enumerate() {
        assert!(
            v < n_vertices,
            "nested_dissection: vertex {v} outside the grid"
        );
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
        if ni >= nj {
            let mid = block.i0 + ni / 2;
            let end = (mid + r).min(block.i1);
            self.dissect(Block { i1: mid, ..block }, order);
            self.dissect(Block { i0: end, ..block }, order);
            self.emit(
                Block {
                    i0: mid,
                    i1: end,
                    ..block
                },
                order,
            );
        } else {
            let mid = block.j0 + nj / 2;
            let end = (mid + r).min(block.j1);
            self.dissect(Block { j1: mid, ..block }, order);
            self.dissect(Block { j0: end, ..block }, order);
            self.emit(
                Block {
                    j0: mid,
                    j1: end,
                    ..block
                },
                order,
            );
        }
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
}
