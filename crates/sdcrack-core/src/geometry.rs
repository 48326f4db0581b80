//! Scene geometry of a 2D crack problem: elementary predicates and validation.
//!
//! Conventions used throughout this module:
//! - a point is `[x, y]`;
//! - the domain Ω is a polygon given by its vertices in either orientation, without repeating the
//!   first vertex at the end; edge `k` runs from vertex `k` to vertex `(k + 1) % n`;
//! - a crack is an open polyline of at least two points; segment `k` runs from point `k` to
//!   point `k + 1`;
//! - all indices (vertices, edges, cracks, points, segments) are 0-based;
//! - predicates use the sign of the floating-point cross product with an exact-zero test (no
//!   tolerance), which is exact for the coordinates users type in; coordinates are limited to
//!   [`MAX_COORDINATE`] in magnitude so that no intermediate product can overflow.
//!
//! Validation errors name the offending item the way the scene file does: `domain.polygon` for the
//! domain and `geometry.cracks[i]` for crack `i`.

mod error;
mod predicates;
#[cfg(test)]
mod tests;
mod validate;

pub use error::{GeometryError, MAX_COORDINATE};
pub use predicates::{
    boundary_edge_of, counter_clockwise, point_in_polygon, segments_intersect, signed_area, Inside,
};
pub use validate::{
    crack_tips, validate_cracks, validate_cracks_with, validate_polygon, CrackEnds,
};

/// The L-shaped domain of the unit tests (here and in [`crate::mesh::gmsh`]), counter-clockwise.
#[cfg(test)]
pub(crate) const L_SHAPE: [[f64; 2]; 6] = [
    [-1.0, -1.0],
    [1.0, -1.0],
    [1.0, 0.0],
    [0.0, 0.0],
    [0.0, 1.0],
    [-1.0, 1.0],
];
