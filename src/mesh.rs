//! Structured triangulations of the rectangle, nested levels, the crack as a chain of mesh edges,
//! and the two u-space topologies (docs/design.md).
//!
//! Level ℓ has `2^ℓ·nx × 2^ℓ·ny` cells, each split by its SW–NE diagonal into two counter-clockwise
//! triangles, so levels are nested. The crack segment must join two level-0 vertices along a mesh
//! line (horizontal, vertical or SW–NE diagonal) and stay strictly inside Ω; its nodes
//! `x_0 = a, …, x_I = b` are mesh vertices and its segments mesh edges.
//!
//! Sides: ν is a→b turned by +90°; a triangle touching an interior crack node lies on the **+**
//! side when its centroid c has (c − a)·ν > 0. For the `broken` u space every interior crack node
//! (tips excluded) carries a second u degree of freedom, used by the triangles on the − side; the
//! original vertex number serves the + side. That numbering *is* the cracked mesh of the references (docs/design.md).

use crate::problem::{Rectangle, Segment, USpace};

/// Errors in building a mesh for a scene.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    /// A crack end point is not a vertex of the level-0 mesh.
    #[error("crack end point ({x}, {y}) is not a vertex of the level-0 mesh (cells {nx}×{ny}); move it onto the grid or change discretization.cells")]
    OffMesh {
        /// x of the end point.
        x: f64,
        /// y of the end point.
        y: f64,
        /// Level-0 cells in x.
        nx: usize,
        /// Level-0 cells in y.
        ny: usize,
    },
    /// A crack end point lies outside Ω or on Γ.
    #[error("crack end point ({x}, {y}) {what}; the crack must lie strictly inside the domain")]
    NotInside {
        /// x of the end point.
        x: f64,
        /// y of the end point.
        y: f64,
        /// "lies outside the domain" or "touches the boundary".
        what: &'static str,
    },
    /// The crack is not along a mesh line.
    #[error("crack from ({ax}, {ay}) to ({bx}, {by}) is not along a mesh line: it must be horizontal, vertical or along the SW–NE cell diagonals")]
    NotOnMeshLine {
        /// Start x.
        ax: f64,
        /// Start y.
        ay: f64,
        /// End x.
        bx: f64,
        /// End y.
        by: f64,
    },
}

/// Which face of the crack a triangle lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// The side ν points into.
    Plus,
    /// The other side.
    Minus,
}

/// The crack as a chain of mesh vertices.
#[derive(Clone, Debug)]
pub struct CrackChain {
    /// Vertex numbers of x_0 = a, …, x_I = b (both tips included).
    pub nodes: Vec<usize>,
    /// The unit normal ν (a→b turned by +90°).
    pub normal: [f64; 2],
    /// The crack segment.
    pub segment: Segment,
}

impl CrackChain {
    /// Number of crack segments I.
    pub fn segments(&self) -> usize {
        self.nodes.len() - 1
    }
}

/// A structured triangulation of one level with its crack chain.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Refinement level ℓ.
    pub level: u32,
    /// Cells in x at this level.
    pub nx: usize,
    /// Cells in y at this level.
    pub ny: usize,
    /// Vertex coordinates; vertex (i, j) has number j·(nx+1) + i.
    pub vertices: Vec<[f64; 2]>,
    /// Triangles, counter-clockwise.
    pub triangles: Vec<[usize; 3]>,
    /// Boundary edges, oriented counter-clockwise along Γ (outward normal = (dy, −dx)/|e|).
    pub boundary_edges: Vec<[usize; 2]>,
    /// The crack chain.
    pub crack: CrackChain,
    /// Side of each triangle that touches an interior crack node (`None` for all others).
    pub side: Vec<Option<Side>>,
}

/// Degrees of freedom of a u space on a mesh.
#[derive(Clone, Debug)]
pub struct UTopology {
    /// Which space.
    pub space: USpace,
    /// Number of u unknowns.
    pub n_dofs: usize,
    /// The u dofs of each triangle (same vertex order as `Mesh::triangles`).
    pub triangle_dofs: Vec<[usize; 3]>,
    /// The mesh vertex each dof sits at.
    pub dof_vertex: Vec<usize>,
    /// For each crack node, its (+ dof, − dof); equal at the tips and in the continuous space.
    pub crack_dofs: Vec<(usize, usize)>,
}

/// Grid index of a coordinate on `n` cells of [lo, hi], if it is a grid point.
fn grid_index(v: f64, lo: f64, hi: f64, n: usize) -> Option<i64> {
    let t = (v - lo) / (hi - lo) * n as f64;
    let r = t.round();
    ((t - r).abs() <= 1e-9 * n as f64).then_some(r as i64)
}

/// Coordinate of grid line `i` of `n` on [lo, hi], exact at both ends and at the midpoint.
fn grid_coord(lo: f64, hi: f64, i: usize, n: usize) -> f64 {
    let t = i as f64 / n as f64;
    lo * (1.0 - t) + hi * t
}

impl Mesh {
    /// Builds level `level` of the structured mesh with `cells` level-0 cells and the crack chain.
    pub fn structured(
        domain: Rectangle,
        cells: [usize; 2],
        crack: Segment,
        level: u32,
    ) -> Result<Mesh, MeshError> {
        let (ia, ja) = Self::crack_end_index(domain, cells, crack.a)?;
        let (ib, jb) = Self::crack_end_index(domain, cells, crack.b)?;
        let (di, dj) = (ib - ia, jb - ja);
        if !(di == 0 || dj == 0 || di == dj) {
            return Err(MeshError::NotOnMeshLine {
                ax: crack.a[0],
                ay: crack.a[1],
                bx: crack.b[0],
                by: crack.b[1],
            });
        }
        let scale = 1usize << level;
        let (nx, ny) = (cells[0] * scale, cells[1] * scale);
        let vertices = Self::grid_vertices(domain, nx, ny);
        let triangles = Self::grid_triangles(nx, ny);
        let boundary_edges = Self::grid_boundary(nx, ny);
        let steps = di.abs().max(dj.abs()) as usize * scale;
        let (si, sj) = (di.signum(), dj.signum());
        let s = scale as i64;
        let mut nodes = Vec::with_capacity(steps + 1);
        let mut vertices = vertices;
        for k in 0..=steps {
            let i = (ia * s + si * k as i64) as usize;
            let j = (ja * s + sj * k as i64) as usize;
            let v = j * (nx + 1) + i;
            // Crack nodes lie exactly on the segment's parametrisation (signed zeros on y = 0 etc.).
            let t = k as f64 / steps as f64;
            vertices[v] = [
                crack.a[0] * (1.0 - t) + crack.b[0] * t,
                crack.a[1] * (1.0 - t) + crack.b[1] * t,
            ];
            nodes.push(v);
        }
        let chain = CrackChain {
            nodes,
            normal: crack.normal(),
            segment: crack,
        };
        let side = Self::triangle_sides(&vertices, &triangles, &chain);
        Ok(Mesh {
            level,
            nx,
            ny,
            vertices,
            triangles,
            boundary_edges,
            crack: chain,
            side,
        })
    }

    fn crack_end_index(
        domain: Rectangle,
        cells: [usize; 2],
        p: [f64; 2],
    ) -> Result<(i64, i64), MeshError> {
        let inside = (0..2).all(|d| p[d] >= domain.min[d] && p[d] <= domain.max[d]);
        if !inside {
            return Err(MeshError::NotInside {
                x: p[0],
                y: p[1],
                what: "lies outside the domain",
            });
        }
        let i = grid_index(p[0], domain.min[0], domain.max[0], cells[0]);
        let j = grid_index(p[1], domain.min[1], domain.max[1], cells[1]);
        let (Some(i), Some(j)) = (i, j) else {
            return Err(MeshError::OffMesh {
                x: p[0],
                y: p[1],
                nx: cells[0],
                ny: cells[1],
            });
        };
        if i <= 0 || j <= 0 || i >= cells[0] as i64 || j >= cells[1] as i64 {
            return Err(MeshError::NotInside {
                x: p[0],
                y: p[1],
                what: "touches the boundary",
            });
        }
        Ok((i, j))
    }

    fn grid_vertices(domain: Rectangle, nx: usize, ny: usize) -> Vec<[f64; 2]> {
        let mut v = Vec::with_capacity((nx + 1) * (ny + 1));
        for j in 0..=ny {
            let y = grid_coord(domain.min[1], domain.max[1], j, ny);
            for i in 0..=nx {
                v.push([grid_coord(domain.min[0], domain.max[0], i, nx), y]);
            }
        }
        v
    }

    fn grid_triangles(nx: usize, ny: usize) -> Vec<[usize; 3]> {
        let mut t = Vec::with_capacity(2 * nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let v00 = j * (nx + 1) + i;
                let (v10, v01, v11) = (v00 + 1, v00 + nx + 1, v00 + nx + 2);
                t.push([v00, v10, v11]);
                t.push([v00, v11, v01]);
            }
        }
        t
    }

    fn grid_boundary(nx: usize, ny: usize) -> Vec<[usize; 2]> {
        let id = |i: usize, j: usize| j * (nx + 1) + i;
        let mut e = Vec::with_capacity(2 * (nx + ny));
        e.extend((0..nx).map(|i| [id(i, 0), id(i + 1, 0)]));
        e.extend((0..ny).map(|j| [id(nx, j), id(nx, j + 1)]));
        e.extend((0..nx).rev().map(|i| [id(i + 1, ny), id(i, ny)]));
        e.extend((0..ny).rev().map(|j| [id(0, j + 1), id(0, j)]));
        e
    }

    fn triangle_sides(
        vertices: &[[f64; 2]],
        triangles: &[[usize; 3]],
        chain: &CrackChain,
    ) -> Vec<Option<Side>> {
        let n = chain.nodes.len();
        let mut interior = vec![false; vertices.len()];
        for &v in &chain.nodes[1..n - 1] {
            interior[v] = true;
        }
        let a = chain.segment.a;
        let nu = chain.normal;
        triangles
            .iter()
            .map(|t| {
                if !t.iter().any(|&v| interior[v]) {
                    return None;
                }
                let c = centroid(vertices, t);
                let s = (c[0] - a[0]) * nu[0] + (c[1] - a[1]) * nu[1];
                Some(if s > 0.0 { Side::Plus } else { Side::Minus })
            })
            .collect()
    }

    /// Mesh size h: the diameter of the triangles (the cell diagonal).
    pub fn h(&self) -> f64 {
        let t = &self.triangles[0];
        let p = |k: usize| self.vertices[t[k]];
        let d = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
        d(p(0), p(1)).max(d(p(1), p(2))).max(d(p(0), p(2)))
    }

    /// The u degrees of freedom of `space` on this mesh.
    pub fn u_topology(&self, space: USpace) -> UTopology {
        let nv = self.vertices.len();
        let nodes = &self.crack.nodes;
        let interior = &nodes[1..nodes.len() - 1];
        let mut minus_of = vec![usize::MAX; nv];
        let mut dof_vertex: Vec<usize> = (0..nv).collect();
        if space == USpace::Broken {
            for (k, &v) in interior.iter().enumerate() {
                minus_of[v] = nv + k;
                dof_vertex.push(v);
            }
        }
        let triangle_dofs = self
            .triangles
            .iter()
            .zip(&self.side)
            .map(|(t, side)| match side {
                Some(Side::Minus) if space == USpace::Broken => t.map(|v| {
                    if minus_of[v] != usize::MAX {
                        minus_of[v]
                    } else {
                        v
                    }
                }),
                _ => *t,
            })
            .collect();
        let crack_dofs = nodes
            .iter()
            .map(|&v| {
                let m = if minus_of[v] != usize::MAX {
                    minus_of[v]
                } else {
                    v
                };
                (v, m)
            })
            .collect();
        UTopology {
            space,
            n_dofs: dof_vertex.len(),
            triangle_dofs,
            dof_vertex,
            crack_dofs,
        }
    }
}

/// Centroid of a triangle.
pub fn centroid(vertices: &[[f64; 2]], t: &[usize; 3]) -> [f64; 2] {
    let [a, b, c] = t.map(|v| vertices[v]);
    [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit() -> Rectangle {
        Rectangle {
            min: [-1.0, -1.0],
            max: [1.0, 1.0],
        }
    }

    fn seg(a: [f64; 2], b: [f64; 2]) -> Segment {
        Segment { a, b }
    }

    #[test]
    fn counts_and_nesting() {
        let m = Mesh::structured(unit(), [4, 2], seg([-0.5, 0.0], [0.5, 0.0]), 2).unwrap();
        assert_eq!((m.nx, m.ny), (16, 8));
        assert_eq!(m.vertices.len(), 17 * 9);
        assert_eq!(m.triangles.len(), 2 * 16 * 8);
        assert_eq!(m.boundary_edges.len(), 2 * (16 + 8));
        assert_eq!(m.crack.nodes.len(), 9);
        // every triangle counter-clockwise with the cell area / 2
        for t in &m.triangles {
            let [a, b, c] = t.map(|v| m.vertices[v]);
            let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
            assert!((area - 0.5 * (2.0 / 16.0) * (2.0 / 8.0)).abs() < 1e-14);
        }
        // crack nodes exactly on y = 0 with positive zero
        for &v in &m.crack.nodes {
            assert_eq!(m.vertices[v][1].to_bits(), 0.0f64.to_bits());
        }
    }

    #[test]
    fn sides_and_broken_topology() {
        let m = Mesh::structured(unit(), [4, 4], seg([-0.5, 0.0], [0.5, 0.0]), 1).unwrap();
        assert_eq!(m.crack.normal, [0.0, 1.0]);
        let topo = m.u_topology(USpace::Broken);
        let interior = m.crack.nodes.len() - 2;
        assert_eq!(topo.n_dofs, m.vertices.len() + interior);
        for (t, (dofs, side)) in m
            .triangles
            .iter()
            .zip(topo.triangle_dofs.iter().zip(&m.side))
        {
            let c = centroid(&m.vertices, t);
            match side {
                Some(Side::Minus) => assert!(c[1] < 0.0),
                Some(Side::Plus) => assert!(c[1] > 0.0),
                None => assert_eq!(dofs, t),
            }
            if c[1] > 0.0 {
                assert_eq!(dofs, t, "+ side keeps vertex numbers");
            }
        }
        let (p, q) = topo.crack_dofs[0];
        assert_eq!(p, q, "tips are not duplicated");
        let (p, q) = topo.crack_dofs[2];
        assert_ne!(p, q);
        let cont = m.u_topology(USpace::Continuous);
        assert_eq!(cont.n_dofs, m.vertices.len());
    }

    #[test]
    fn crack_directions() {
        // vertical crack: ν = (-1, 0)
        let m = Mesh::structured(unit(), [4, 4], seg([0.0, -0.5], [0.0, 0.5]), 0).unwrap();
        assert_eq!(m.crack.nodes.len(), 3);
        assert!((m.crack.normal[0] + 1.0).abs() < 1e-15);
        // diagonal crack
        let m = Mesh::structured(unit(), [4, 4], seg([-0.5, -0.5], [0.5, 0.5]), 1).unwrap();
        assert_eq!(m.crack.nodes.len(), 5);
    }

    #[test]
    fn crack_errors() {
        let e = Mesh::structured(unit(), [4, 4], seg([-0.4, 0.0], [0.5, 0.0]), 0).unwrap_err();
        assert!(matches!(e, MeshError::OffMesh { .. }));
        let e = Mesh::structured(unit(), [4, 4], seg([-0.5, 0.0], [1.5, 0.0]), 0).unwrap_err();
        assert!(matches!(
            e,
            MeshError::NotInside {
                what: "lies outside the domain",
                ..
            }
        ));
        let e = Mesh::structured(unit(), [4, 4], seg([-1.0, 0.0], [0.5, 0.0]), 0).unwrap_err();
        assert!(matches!(
            e,
            MeshError::NotInside {
                what: "touches the boundary",
                ..
            }
        ));
        let e = Mesh::structured(unit(), [4, 4], seg([-0.5, 0.0], [0.5, 0.5]), 0).unwrap_err();
        assert!(matches!(e, MeshError::NotOnMeshLine { .. }));
        // NW-SE diagonal is not a mesh line
        let e = Mesh::structured(unit(), [4, 4], seg([-0.5, 0.5], [0.5, -0.5]), 0).unwrap_err();
        assert!(matches!(e, MeshError::NotOnMeshLine { .. }));
    }
}
