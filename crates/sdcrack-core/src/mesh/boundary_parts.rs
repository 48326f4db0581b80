//! The named parts of ∂Ω (docs/elasticity.md, Boundary parts) — where the elastic problem's
//! tractions and Dirichlet data live — and which part every boundary edge of a level lies on.
//!
//! A rectangle's parts are its sides `left`, `right`, `bottom`, `top`; a polygon's are its edges
//! `edge1` … `edgeN` (edge k from vertex k to vertex k + 1, 1-based, of the polygon as the scene
//! stores it: counter-clockwise, the given order when that is counter-clockwise, else the first
//! vertex then the others reversed, [`crate::geometry::counter_clockwise`]); a `.msh` file's
//! boundary is one part, `boundary`.

use super::triangulation::Mesh;
use crate::problem::{Domain, Meshing, Rectangle};

/// The named parts of a scene's ∂Ω.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryParts {
    names: Vec<String>,
    shape: Shape,
}

#[derive(Clone, Debug, PartialEq)]
enum Shape {
    Rectangle(Rectangle),
    Polygon(Vec<[f64; 2]>),
    Whole,
}

/// A rectangle's parts in their index order (the order of `mesh.json`'s `"boundary_parts"`).
pub const RECTANGLE_PARTS: [&str; 4] = ["left", "right", "bottom", "top"];

impl BoundaryParts {
    /// The parts of `domain` meshed as `meshing` says (a mesh file's boundary is one part,
    /// [`crate::elasticity::WHOLE_BOUNDARY`]).
    pub fn of(domain: &Domain, meshing: &Meshing) -> BoundaryParts {
        match meshing {
            Meshing::File(_) => BoundaryParts {
                names: vec![crate::elasticity::WHOLE_BOUNDARY.to_string()],
                shape: Shape::Whole,
            },
            _ => BoundaryParts::of_domain(domain),
        }
    }

    /// The parts of the drawn domain: a rectangle's sides, a polygon's edges.
    pub fn of_domain(domain: &Domain) -> BoundaryParts {
        match domain {
            Domain::Rectangle(r) => BoundaryParts {
                names: RECTANGLE_PARTS.iter().map(|s| s.to_string()).collect(),
                shape: Shape::Rectangle(*r),
            },
            Domain::Polygon(p) => BoundaryParts {
                names: (1..=p.len()).map(|k| format!("edge{k}")).collect(),
                shape: Shape::Polygon(p.clone()),
            },
        }
    }

    /// The part names, in index order.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The index of the part `name`, if ∂Ω has one.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// The part of each of `mesh.boundary_edges`, as an index into [`BoundaryParts::names`].
    ///
    /// An edge's part is the side (polygon edge) nearest to its midpoint. Every boundary edge
    /// of a level lies on one side — its ends are the scene's points, gmsh's (16 digits) or
    /// midpoints of such edges, on the side up to round-off — and its midpoint is then at
    /// least half its length times the sine of the corner's angle from every other side, so
    /// the nearest side is its own for any mesh whose edges are not at round-off scale.
    pub fn of_edges(&self, mesh: &Mesh) -> Vec<usize> {
        mesh.boundary_edges
            .iter()
            .map(|&[a, b]| {
                let (p, q) = (mesh.vertices[a], mesh.vertices[b]);
                self.part_at([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])])
            })
            .collect()
    }

    /// The part nearest to the point `m` of ∂Ω (an index into [`BoundaryParts::names`]).
    pub fn part_at(&self, m: [f64; 2]) -> usize {
        match &self.shape {
            Shape::Whole => 0,
            Shape::Rectangle(r) => nearest(&[
                m[0] - r.min[0],
                r.max[0] - m[0],
                m[1] - r.min[1],
                r.max[1] - m[1],
            ]),
            Shape::Polygon(p) => {
                let n = p.len();
                let d: Vec<f64> = (0..n)
                    .map(|k| segment_distance(m, p[k], p[(k + 1) % n]))
                    .collect();
                nearest(&d)
            }
        }
    }
}

/// The index of the smallest of `d` (the first of equals).
fn nearest(d: &[f64]) -> usize {
    let mut best = 0;
    for (k, &v) in d.iter().enumerate() {
        if v.abs() < d[best].abs() {
            best = k;
        }
    }
    best
}

/// The distance from `p` to the segment `a`–`b`.
fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}
