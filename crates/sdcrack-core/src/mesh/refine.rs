//! Uniform refinement of an unstructured level: every triangle into four by its edge midpoints,
//! so levels are nested and a coarse P1 field is exactly a fine one (the compare tool's exact
//! norms between levels rely on it).
//!
//! Numbering: the coarse vertices keep their numbers; the midpoint of each edge is numbered next,
//! edges taken in the order they first appear (triangles in order, edges 01, 12, 20). Triangle
//! t = [a, b, c] with midpoints m_ab, m_bc, m_ca becomes 4t + 0 = [a, m_ab, m_ca],
//! 4t + 1 = [m_ab, b, m_bc], 4t + 2 = [m_ca, m_bc, c], 4t + 3 = [m_ab, m_bc, m_ca] (all
//! counter-clockwise). Boundary and crack edges are halved in place, keeping their orientation
//! and, on a crack, the edge's normal.

use std::collections::HashMap;

use super::triangulation::{CrackChain, Layout, Mesh};

/// The next level of `mesh` (uniform refinement, numbering of the module documentation).
pub fn refine(mesh: &Mesh) -> Mesh {
    let mut vertices = mesh.vertices.clone();
    let mut midpoint: HashMap<(usize, usize), usize> = HashMap::with_capacity(
        mesh.vertices.len() + mesh.triangles.len() + mesh.boundary_edges.len(),
    );
    let mut mid = |a: usize, b: usize, vertices: &mut Vec<[f64; 2]>| -> usize {
        *midpoint.entry((a.min(b), a.max(b))).or_insert_with(|| {
            let (p, q) = (vertices[a], vertices[b]);
            vertices.push([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]);
            vertices.len() - 1
        })
    };
    let mut triangles = Vec::with_capacity(4 * mesh.triangles.len());
    for &[a, b, c] in &mesh.triangles {
        let ab = mid(a, b, &mut vertices);
        let bc = mid(b, c, &mut vertices);
        let ca = mid(c, a, &mut vertices);
        triangles.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    let boundary_edges = mesh
        .boundary_edges
        .iter()
        .flat_map(|&[a, b]| {
            let m = mid(a, b, &mut vertices);
            [[a, m], [m, b]]
        })
        .collect();
    let cracks = mesh
        .cracks
        .iter()
        .map(|chain| {
            let mut nodes = Vec::with_capacity(2 * chain.nodes.len() - 1);
            let mut normals = Vec::with_capacity(2 * chain.normals.len());
            nodes.push(chain.nodes[0]);
            for (w, &nu) in chain.nodes.windows(2).zip(&chain.normals) {
                nodes.push(mid(w[0], w[1], &mut vertices));
                nodes.push(w[1]);
                normals.extend([nu, nu]);
            }
            CrackChain::from_parts(nodes, normals)
        })
        .collect();
    let coarse_triangles = match mesh.layout {
        Layout::Refined { coarse_triangles } | Layout::Graded { coarse_triangles } => {
            coarse_triangles
        }
        Layout::Structured { .. } => mesh.triangles.len(),
    };
    Mesh::new(
        mesh.level + 1,
        Layout::Refined { coarse_triangles },
        vertices,
        triangles,
        boundary_edges,
        cracks,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::Side;

    /// [0, 2]² on a 3×3 vertex grid, cells split by their SW–NE diagonals, no crack.
    fn coarse() -> Mesh {
        // vertices of [0,2]² on a 3×3 grid, triangles split by SW–NE diagonals
        let mut vertices = Vec::new();
        for j in 0..3 {
            for i in 0..3 {
                vertices.push([i as f64, j as f64]);
            }
        }
        let mut triangles = Vec::new();
        for j in 0..2 {
            for i in 0..2 {
                let v = j * 3 + i;
                triangles.push([v, v + 1, v + 4]);
                triangles.push([v, v + 4, v + 3]);
            }
        }
        let boundary_edges = vec![
            [0, 1],
            [1, 2],
            [2, 5],
            [5, 8],
            [8, 7],
            [7, 6],
            [6, 3],
            [3, 0],
        ];
        Mesh::new(
            0,
            Layout::Refined {
                coarse_triangles: 8,
            },
            vertices,
            triangles,
            boundary_edges,
            vec![],
        )
    }

    fn area(m: &Mesh, t: &[usize; 3]) -> f64 {
        let [a, b, c] = t.map(|v| m.vertices[v]);
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
    }

    #[test]
    fn children_tile_their_parent_counter_clockwise() {
        let m0 = coarse();
        let m1 = refine(&m0);
        let m2 = refine(&m1);
        assert_eq!(m2.level, 2);
        assert_eq!(m2.triangles.len(), 128);
        // V − E + T = 1 on a disc: 3×3 → 5×5 → 9×9 vertices
        assert_eq!(m1.vertices.len(), 25);
        assert_eq!(m2.vertices.len(), 81);
        assert_eq!(m2.boundary_edges.len(), 32);
        for (t, parent) in m0.triangles.iter().enumerate() {
            let pa = area(&m0, parent);
            let kids: f64 = (0..4).map(|c| area(&m1, &m1.triangles[4 * t + c])).sum();
            assert!((kids - pa).abs() < 1e-15);
            for c in 0..4 {
                let a = area(&m1, &m1.triangles[4 * t + c]);
                assert!((a - pa / 4.0).abs() < 1e-15, "child {c} of {t}");
                // the child's centroid lies in the parent
                let g = crate::mesh::centroid(&m1.vertices, &m1.triangles[4 * t + c]);
                let [p, q, r] = parent.map(|v| m0.vertices[v]);
                let side = |a: [f64; 2], b: [f64; 2]| {
                    (b[0] - a[0]) * (g[1] - a[1]) - (b[1] - a[1]) * (g[0] - a[0])
                };
                assert!(side(p, q) > 0.0 && side(q, r) > 0.0 && side(r, p) > 0.0);
            }
        }
        // boundary stays counter-clockwise: Σ x dy − y dx = 2 · area = 8
        let twice: f64 = m2
            .boundary_edges
            .iter()
            .map(|&[a, b]| {
                let (p, q) = (m2.vertices[a], m2.vertices[b]);
                p[0] * q[1] - p[1] * q[0]
            })
            .sum();
        assert!((twice - 8.0).abs() < 1e-12);
    }

    #[test]
    fn crack_chains_are_halved_with_their_normals() {
        // a kinked crack strictly inside needs level-1 vertices: refine first, then crack
        let m1 = refine(&coarse());
        // level-1 grid is 5×5 (0..25 not in grid order); find vertices by coordinates
        let at = |m: &Mesh, x: f64, y: f64| {
            m.vertices
                .iter()
                .position(|p| p[0] == x && p[1] == y)
                .unwrap()
        };
        let chain = CrackChain::from_parts(
            vec![at(&m1, 0.5, 1.0), at(&m1, 1.0, 1.0), at(&m1, 1.5, 1.5)],
            vec![[0.0, 1.0], [-0.5f64.sqrt(), 0.5f64.sqrt()]],
        );
        let m1 = Mesh::new(
            1,
            m1.layout,
            m1.vertices.clone(),
            m1.triangles.clone(),
            m1.boundary_edges.clone(),
            vec![chain],
        );
        let m2 = refine(&m1);
        let c = &m2.cracks[0];
        assert_eq!(c.nodes.len(), 5);
        assert_eq!(c.normals[0], [0.0, 1.0]);
        assert_eq!(c.normals[1], [0.0, 1.0]);
        assert_eq!(c.normals[3][0], -(0.5f64.sqrt()));
        assert_eq!(m2.vertices[c.nodes[1]], [0.75, 1.0]);
        assert_eq!(m2.vertices[c.nodes[3]], [1.25, 1.25]);
        // every interior crack corner has a side; + is left of the path
        for (t, sides) in m2.triangles.iter().zip(&m2.corner_sides) {
            for (k, s) in sides.iter().enumerate() {
                let v = t[k];
                let interior = c.nodes[1..4].contains(&v);
                assert_eq!(s.is_some(), interior);
                if let Some(s) = s {
                    let g = crate::mesh::centroid(&m2.vertices, t);
                    // left of the path (0.5,1) → (1,1) → (1.5,1.5): above y = 1 on the first
                    // segment, above y = x on the second, and the wedge above both at the kink
                    let left = match k {
                        _ if v == c.nodes[1] => g[1] > 1.0,
                        _ if v == c.nodes[3] => g[1] > g[0],
                        _ => g[1] > 1.0 && g[1] > g[0],
                    };
                    assert_eq!(*s == Side::Plus, left, "corner {k} of {t:?}");
                }
            }
        }
    }
}
