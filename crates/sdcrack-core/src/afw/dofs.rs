//! The degrees of freedom of the AFW system on one mesh (docs/design.md, "Element"): the mesh's
//! edges with their fixed orientation (unit normal n_e), the two directions of each edge's σ
//! dofs ((e_x, e_y), or (s_e ν, s_e t) on a crack edge), what each edge is (interior, crack,
//! traction or Dirichlet boundary), the essential σ values (the traction interpolant, the zero
//! tangential crack dofs), and the numbering of the unknowns: the free σ dofs first, then
//! (u_x, u_y, γ) of each triangle.

use std::collections::HashMap;

use super::solution::AfwError;
use crate::elasticity::{BoundaryEdge, BoundaryPart, ElasticData};
use crate::expr::Expr;
use crate::fe::quadrature::gauss_legendre;
use crate::mesh::{BoundaryParts, Mesh};
use crate::problem::Domain;

/// Gauss–Legendre points per edge for the traction interpolant and the Dirichlet load (exact
/// for data of degree ≤ 8 along the edge, times the hat).
pub const EDGE_POINTS: usize = 5;

/// What an edge of the mesh is.
#[derive(Clone, Debug, PartialEq)]
pub enum EdgeKind {
    /// Between two triangles, not on a crack.
    Interior,
    /// On a crack: segment `segment` of chain `crack`, ν its normal into the + face,
    /// `chain_slots[j]` the end slot of the chain's j-th node of this segment.
    Crack {
        /// Index in `Mesh::cracks`.
        crack: usize,
        /// Segment along the chain.
        segment: usize,
        /// ν.
        normal: [f64; 2],
        /// End slots of the chain's nodes (nodes[segment], nodes[segment + 1]).
        chain_slots: [usize; 2],
    },
    /// On a traction part of ∂Ω (its σ dofs essential), `outward` the normal of Ω.
    Traction {
        /// The outward normal n.
        outward: [f64; 2],
        /// Index of the traction in `ElasticData::tractions`.
        traction: usize,
    },
    /// On a Dirichlet part of ∂Ω (u = g natural), `outward` the normal of Ω.
    Dirichlet {
        /// The outward normal n.
        outward: [f64; 2],
    },
}

/// One edge of the mesh.
#[derive(Clone, Debug)]
pub struct Edge {
    /// Its vertices, the smaller number first: end slot 0 and end slot 1.
    pub nodes: [usize; 2],
    /// n_e: the direction nodes[0] → nodes[1] turned by −90°, unit.
    pub normal: [f64; 2],
    /// Length ℓ_e.
    pub length: f64,
    /// The directions d of its dofs (k = 0, 1).
    pub directions: [[f64; 2]; 2],
    /// What it is.
    pub kind: EdgeKind,
}

/// The dofs of one mesh.
#[derive(Clone, Debug)]
pub struct AfwDofs {
    /// The edges.
    pub edges: Vec<Edge>,
    /// Per triangle, its edge opposite each of its vertices.
    pub triangle_edges: Vec<[usize; 3]>,
    /// Per σ dof 4e + 2s + k (edge e, end slot s, direction k): its unknown, or `None` when
    /// essential.
    pub sigma_unknown: Vec<Option<usize>>,
    /// Per σ dof: its essential value (0 for a free one).
    pub essential: Vec<f64>,
    /// Free σ dofs (the first unknowns).
    pub n_sigma: usize,
    /// The crack edges, crack by crack, each chain's segments in order.
    pub crack_edges: Vec<usize>,
}

/// The σ dof of edge `e`, end slot `s`, direction `k`.
pub fn sigma_dof(e: usize, s: usize, k: usize) -> usize {
    4 * e + 2 * s + k
}

impl AfwDofs {
    /// Number of triangles.
    pub fn triangles(&self) -> usize {
        self.triangle_edges.len()
    }

    /// Number of unknowns: the free σ dofs, 2 u and 1 γ per triangle.
    pub fn n(&self) -> usize {
        self.n_sigma + 3 * self.triangles()
    }

    /// The unknown of u_x (k = 0), u_y (k = 1) or γ (k = 2) of triangle `t`.
    pub fn element_unknown(&self, t: usize, k: usize) -> usize {
        self.n_sigma + 3 * t + k
    }

    /// The unknown of the normal dof (direction 0) of crack edge `e` at end slot `s`.
    pub fn normal_unknown(&self, e: usize, s: usize) -> usize {
        self.sigma_unknown[sigma_dof(e, s, 0)].expect("a crack edge's normal dofs are free")
    }

    /// The dofs of `mesh` with the boundary data of `data` on the parts of `domain`.
    ///
    /// # Errors
    /// [`AfwError::NoDirichletData`] for a boundary edge with neither a traction nor g,
    /// [`AfwError::NonFinite`] for a traction that is not finite at a quadrature point,
    /// [`AfwError::CrackOnBoundary`] for a crack edge of ∂Ω.
    pub fn new(mesh: &Mesh, domain: &Domain, data: &ElasticData) -> Result<AfwDofs, AfwError> {
        let (mut edges, triangle_edges, index) = mesh_edges(mesh);
        let crack_edges = mark_crack_edges(mesh, &mut edges, &index);
        let parts = BoundaryParts::of_domain(domain);
        let mut essential = vec![0.0; 4 * edges.len()];
        for &[a, b] in &mesh.boundary_edges {
            let e = index[&(a.min(b), a.max(b))];
            if edges[e].kind != EdgeKind::Interior {
                return Err(AfwError::CrackOnBoundary {
                    at: mesh.vertices[a],
                });
            }
            let (pa, pb) = (mesh.vertices[a], mesh.vertices[b]);
            let boundary = BoundaryEdge {
                part: BoundaryPart(parts.names()[parts.part_at(midpoint(pa, pb))].clone()),
                a: pa,
                b: pb,
            };
            let outward = boundary.outward_normal();
            let traction = data
                .tractions
                .iter()
                .position(|t| boundary.belongs_to(&t.part));
            edges[e].kind = match traction {
                Some(traction) => {
                    let values = traction_interpolant(
                        &edges[e],
                        mesh,
                        outward,
                        &data.tractions[traction].t,
                    )?;
                    essential[4 * e..4 * e + 4].copy_from_slice(&values);
                    EdgeKind::Traction { outward, traction }
                }
                None if data.g.is_some() => EdgeKind::Dirichlet { outward },
                None => {
                    return Err(AfwError::NoDirichletData {
                        part: boundary.part.0,
                    })
                }
            };
        }
        let mut sigma_unknown = vec![None; 4 * edges.len()];
        let mut n_sigma = 0;
        for (e, edge) in edges.iter().enumerate() {
            for s in 0..2 {
                for k in 0..2 {
                    let free = match edge.kind {
                        EdgeKind::Interior | EdgeKind::Dirichlet { .. } => true,
                        // σ_tν = 0: the tangential crack dofs are essential zeros
                        EdgeKind::Crack { .. } => k == 0,
                        EdgeKind::Traction { .. } => false,
                    };
                    if free {
                        sigma_unknown[sigma_dof(e, s, k)] = Some(n_sigma);
                        n_sigma += 1;
                    }
                }
            }
        }
        Ok(AfwDofs {
            edges,
            triangle_edges,
            sigma_unknown,
            essential,
            n_sigma,
            crack_edges,
        })
    }
}

fn midpoint(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])]
}

/// The edge of each vertex pair (smaller vertex first).
type EdgeIndex = HashMap<(usize, usize), usize>;

/// The edges of `mesh` (interior ones for now), each triangle's edges, and the edge of each
/// vertex pair (smaller first).
fn mesh_edges(mesh: &Mesh) -> (Vec<Edge>, Vec<[usize; 3]>, EdgeIndex) {
    let mut index: EdgeIndex =
        HashMap::with_capacity(3 * mesh.triangles.len() / 2 + mesh.boundary_edges.len());
    let mut edges = Vec::new();
    let triangle_edges = (mesh.triangles.iter())
        .map(|t| {
            std::array::from_fn(|i| {
                let (a, b) = (t[(i + 1) % 3], t[(i + 2) % 3]);
                let key = (a.min(b), a.max(b));
                *index.entry(key).or_insert_with(|| {
                    edges.push(edge(mesh, [key.0, key.1]));
                    edges.len() - 1
                })
            })
        })
        .collect();
    (edges, triangle_edges, index)
}

/// The edge `nodes` (smaller first) with its normal and the (x, y) directions.
fn edge(mesh: &Mesh, nodes: [usize; 2]) -> Edge {
    let [a, b] = nodes.map(|v| mesh.vertices[v]);
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let length = dx.hypot(dy);
    Edge {
        nodes,
        normal: [dy / length, -dx / length],
        length,
        directions: [[1.0, 0.0], [0.0, 1.0]],
        kind: EdgeKind::Interior,
    }
}

/// Marks the edges between consecutive nodes of each crack chain: kind, directions
/// (s_e ν, s_e t) with s_e = n_e·ν = ±1 and t = ν turned by −90°. Returns them in chain order.
fn mark_crack_edges(mesh: &Mesh, edges: &mut [Edge], index: &EdgeIndex) -> Vec<usize> {
    let mut crack_edges = Vec::new();
    for (c, chain) in mesh.cracks.iter().enumerate() {
        for (k, pair) in chain.nodes.windows(2).enumerate() {
            let key = (pair[0].min(pair[1]), pair[0].max(pair[1]));
            let e = index[&key];
            let nu = chain.normals[k];
            let edge = &mut edges[e];
            let s = (edge.normal[0] * nu[0] + edge.normal[1] * nu[1]).signum();
            let t = [nu[1], -nu[0]];
            edge.directions = [[s * nu[0], s * nu[1]], [s * t[0], s * t[1]]];
            let slot = |v: usize| usize::from(v != edge.nodes[0]);
            edge.kind = EdgeKind::Crack {
                crack: c,
                segment: k,
                normal: nu,
                chain_slots: [slot(pair[0]), slot(pair[1])],
            };
            crack_edges.push(e);
        }
    }
    crack_edges
}

/// The canonical BDM1 interpolant of the traction t on a traction edge: per row r, the L²(e)
/// projection of t_r (n_e·n) onto P1(e), as the values at the two ends — the dofs
/// (e, s, k = r) of the (x, y) directions, at 4s + r.
fn traction_interpolant(
    edge: &Edge,
    mesh: &Mesh,
    outward: [f64; 2],
    t: &[Expr; 2],
) -> Result<[f64; 4], AfwError> {
    let [a, b] = edge.nodes.map(|v| mesh.vertices[v]);
    let orientation = edge.normal[0] * outward[0] + edge.normal[1] * outward[1];
    let rule = gauss_legendre(EDGE_POINTS);
    let mut moments = [[0.0; 2]; 2]; // [row][end]
    for (&s, &w) in rule.points.iter().zip(&rule.weights) {
        let p = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])];
        for r in 0..2 {
            let v = t[r].eval(p[0], p[1]);
            if !v.is_finite() {
                return Err(AfwError::NonFinite {
                    name: "traction",
                    source_text: t[r].source().to_string(),
                    value: v,
                    x: p[0],
                    y: p[1],
                });
            }
            let v = v * orientation * w * edge.length;
            moments[r][0] += v * (1.0 - s);
            moments[r][1] += v * s;
        }
    }
    // M_e = ℓ/6 [[2, 1], [1, 2]], M_e⁻¹ = 2/ℓ [[2, −1], [−1, 2]]
    let mut values = [0.0; 4];
    for r in 0..2 {
        let [m0, m1] = moments[r];
        values[r] = 2.0 / edge.length * (2.0 * m0 - m1);
        values[2 + r] = 2.0 / edge.length * (2.0 * m1 - m0);
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::structured::structured;
    use crate::problem::Rectangle;
    use crate::scene::elastic_testing as et;

    fn williams_mesh() -> Mesh {
        let Domain::Rectangle(r) = et::square() else {
            unreachable!()
        };
        structured(r, [4, 4], &[et::crack([-1.0, 0.0], [0.0, 0.0])], 1).unwrap()
    }

    #[test]
    fn crack_edges_carry_the_chain_normal_and_rotated_directions() {
        let m = williams_mesh();
        let m_u = et::williams(1.0, 0.5, &et::steel_like());
        let data = et::Elastic::new(et::steel_like(), [&m_u[0], &m_u[1]], ["0", "0"])
            .g_is_u()
            .data;
        let dofs = AfwDofs::new(&m, &et::square(), &data).unwrap();
        assert_eq!(dofs.crack_edges.len(), 4);
        for &e in &dofs.crack_edges {
            let edge = &dofs.edges[e];
            let EdgeKind::Crack { normal, .. } = edge.kind else {
                panic!("not a crack edge")
            };
            assert_eq!(normal, [0.0, 1.0]);
            // s_e ν (the first direction) has ν·(s_e ν)·s_e = 1 with s_e = n_e·ν
            let s = edge.normal[1];
            assert_eq!(s.abs(), 1.0);
            assert_eq!(edge.directions[0], [0.0, s]);
            assert_eq!(edge.directions[1], [s, 0.0]);
            assert!(dofs.sigma_unknown[sigma_dof(e, 0, 1)].is_none());
            assert!(dofs.sigma_unknown[sigma_dof(e, 1, 0)].is_some());
        }
        // no tractions: every boundary edge Dirichlet, and 4 per edge free but the 4 tangential
        // crack dofs × 2 ends
        assert_eq!(dofs.n_sigma, 4 * dofs.edges.len() - 2 * 4);
    }

    /// A traction linear along each edge is interpolated exactly: (σ n_e) at each end equals
    /// (n_e·n) t there.
    #[test]
    fn the_traction_interpolant_is_exact_for_linear_tractions() {
        let r = Rectangle {
            min: [0.0, -0.5],
            max: [1.0, 0.5],
        };
        let m = structured(r, [3, 2], &[], 1).unwrap();
        let data = et::Elastic::new(et::steel_like(), ["0", "0"], ["0", "0"])
            .traction("boundary", ["1 + 2*x - y", "3*y - x"])
            .data;
        let dofs = AfwDofs::new(&m, &Domain::Rectangle(r), &data).unwrap();
        assert_eq!(
            dofs.n_sigma,
            4 * (dofs.edges.len() - m.boundary_edges.len())
        );
        for (e, edge) in dofs.edges.iter().enumerate() {
            let EdgeKind::Traction { outward, .. } = edge.kind else {
                continue;
            };
            let o = edge.normal[0] * outward[0] + edge.normal[1] * outward[1];
            for s in 0..2 {
                let p = m.vertices[edge.nodes[s]];
                let t = [1.0 + 2.0 * p[0] - p[1], 3.0 * p[1] - p[0]];
                for k in 0..2 {
                    let got = dofs.essential[sigma_dof(e, s, k)];
                    assert!((got - o * t[k]).abs() < 1e-13, "edge {e} end {s} row {k}");
                }
            }
        }
    }

    #[test]
    fn a_part_without_traction_needs_g() {
        let r = Rectangle {
            min: [0.0, 0.0],
            max: [1.0, 1.0],
        };
        let m = structured(r, [2, 2], &[], 0).unwrap();
        let data = et::Elastic::new(et::steel_like(), ["0", "0"], ["0", "0"])
            .traction("left", ["0", "0"])
            .data;
        let err = AfwDofs::new(&m, &Domain::Rectangle(r), &data).unwrap_err();
        assert!(
            matches!(err, AfwError::NoDirichletData { ref part } if part == "bottom"),
            "{err}"
        );
    }
}
