//! [`GeometryError`]: why a domain polygon or a set of cracks is rejected, one variant per
//! broken requirement, each message one line naming the offending item; the coordinate bound
//! [`MAX_COORDINATE`] it enforces, and the display of points and segments in its messages.

use std::fmt;

/// Largest accepted magnitude of a coordinate.
///
/// Below this bound the cross products used by the predicates cannot overflow, so their signs are
/// meaningful; larger (but finite) coordinates are rejected by the validation functions.
pub const MAX_COORDINATE: f64 = 1e100;

/// Why a domain polygon or a set of cracks is not acceptable.
///
/// Every message is one line naming the offending item: crack indices are the scene's 0-based
/// `cracks[i]`, written `geometry.cracks[i]`; polygon edges are written
/// `domain.polygon edge k (from (x, y) to (x, y))`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GeometryError {
    /// The domain polygon has fewer than 3 vertices.
    #[error("domain.polygon has too few vertices ({count}); at least 3 are required")]
    PolygonTooFewVertices {
        /// Number of vertices given.
        count: usize,
    },
    /// A domain vertex has a NaN or infinite coordinate.
    #[error("domain.polygon vertex {vertex} {} has a non-finite coordinate", pt(.point))]
    PolygonNonFinite {
        /// Index of the vertex.
        vertex: usize,
        /// The vertex as given.
        point: [f64; 2],
    },
    /// A domain vertex has a coordinate larger in magnitude than [`MAX_COORDINATE`].
    #[error(
        "domain.polygon vertex {vertex} {} has a coordinate larger in magnitude than {max:e}",
        pt(.point),
        max = MAX_COORDINATE
    )]
    PolygonCoordinateTooLarge {
        /// Index of the vertex.
        vertex: usize,
        /// The vertex as given.
        point: [f64; 2],
    },
    /// Two consecutive domain vertices coincide (including the last and the first one).
    #[error(
        "domain.polygon edge {edge} ({}) has zero length (vertices {edge} and {next} coincide)",
        point_edge(.point)
    )]
    PolygonZeroLengthEdge {
        /// Index of the edge (and of its first vertex).
        edge: usize,
        /// Index of the edge's second vertex, `(edge + 1) % n`.
        next: usize,
        /// The repeated vertex.
        point: [f64; 2],
    },
    /// All domain vertices lie on one straight line, so the polygon has zero area.
    #[error("domain.polygon has zero area (all vertices are collinear)")]
    PolygonCollinear,
    /// Two non-adjacent domain edges cross or touch.
    #[error(
        "geometry.domain.polygon is not a simple polygon: edge {first} ({}) crosses edge {second} ({})",
        seg(.first_edge),
        seg(.second_edge)
    )]
    PolygonSelfIntersection {
        /// Index of the first edge (the smaller one).
        first: usize,
        /// End points of the first edge.
        first_edge: [[f64; 2]; 2],
        /// Index of the second edge.
        second: usize,
        /// End points of the second edge.
        second_edge: [[f64; 2]; 2],
    },
    /// Two adjacent domain edges run back along the same line and overlap.
    #[error(
        "geometry.domain.polygon is not a simple polygon: edge {first} ({}) folds back onto edge {second} ({})",
        seg(.first_edge),
        seg(.second_edge)
    )]
    PolygonFoldsBack {
        /// Index of the first edge.
        first: usize,
        /// End points of the first edge.
        first_edge: [[f64; 2]; 2],
        /// Index of the following edge, `(first + 1) % n`.
        second: usize,
        /// End points of the second edge.
        second_edge: [[f64; 2]; 2],
    },
    /// A crack has fewer than 2 points.
    #[error("geometry.cracks[{crack}] has too few points ({count}); at least 2 are required")]
    CrackTooFewPoints {
        /// Index of the crack.
        crack: usize,
        /// Number of points given.
        count: usize,
    },
    /// A crack point has a NaN or infinite coordinate.
    #[error("geometry.cracks[{crack}] point {point} {} has a non-finite coordinate", pt(.coords))]
    CrackNonFinite {
        /// Index of the crack.
        crack: usize,
        /// Index of the point within the crack.
        point: usize,
        /// The point as given.
        coords: [f64; 2],
    },
    /// A crack point has a coordinate larger in magnitude than [`MAX_COORDINATE`].
    #[error(
        "geometry.cracks[{crack}] point {point} {} has a coordinate larger in magnitude than {max:e}",
        pt(.coords),
        max = MAX_COORDINATE
    )]
    CrackCoordinateTooLarge {
        /// Index of the crack.
        crack: usize,
        /// Index of the point within the crack.
        point: usize,
        /// The point as given.
        coords: [f64; 2],
    },
    /// Two consecutive crack points coincide.
    #[error(
        "geometry.cracks[{crack}] segment {segment} has zero length (points {segment} and {} coincide)",
        .segment + 1
    )]
    CrackZeroLengthSegment {
        /// Index of the crack.
        crack: usize,
        /// Index of the segment (and of its first point).
        segment: usize,
    },
    /// Two non-adjacent segments of one crack cross or touch.
    #[error("geometry.cracks[{crack}] intersects itself (segment {first} and segment {second})")]
    CrackSelfIntersection {
        /// Index of the crack.
        crack: usize,
        /// Index of the first segment (the smaller one).
        first: usize,
        /// Index of the second segment.
        second: usize,
    },
    /// Two consecutive segments of one crack run back along the same line and overlap.
    #[error(
        "geometry.cracks[{crack}] folds back on itself (segment {first} and segment {second} overlap)"
    )]
    CrackFoldsBack {
        /// Index of the crack.
        crack: usize,
        /// Index of the first segment.
        first: usize,
        /// Index of the following segment, `first + 1`.
        second: usize,
    },
    /// A crack point lies outside the domain.
    #[error("geometry.cracks[{crack}] point {point} {} lies outside the domain", pt(.coords))]
    CrackPointOutside {
        /// Index of the crack.
        crack: usize,
        /// Index of the point within the crack.
        point: usize,
        /// The point as given.
        coords: [f64; 2],
    },
    /// A crack point lies on the domain boundary.
    #[error("geometry.cracks[{crack}] point {point} {} touches the domain boundary", pt(.coords))]
    CrackPointOnBoundary {
        /// Index of the crack.
        crack: usize,
        /// Index of the point within the crack.
        point: usize,
        /// The point as given.
        coords: [f64; 2],
    },
    /// A crack segment crosses or touches a domain edge (its end points being inside).
    #[error(
        "geometry.cracks[{crack}] segment {segment} crosses the domain boundary (edge {edge} {})",
        seg(.edge_points)
    )]
    CrackCrossesBoundary {
        /// Index of the crack.
        crack: usize,
        /// Index of the segment within the crack.
        segment: usize,
        /// Index of the domain edge.
        edge: usize,
        /// End points of the domain edge.
        edge_points: [[f64; 2]; 2],
    },
    /// An edge crack's end point (a mouth) is a vertex of the domain polygon.
    #[error(
        "geometry.cracks[{crack}] point {point} {} is a corner of the domain: a crack may end on the boundary only away from its corners",
        pt(.coords)
    )]
    CrackMouthAtCorner {
        /// Index of the crack.
        crack: usize,
        /// Index of the point within the crack (its first or last).
        point: usize,
        /// The point as given.
        coords: [f64; 2],
    },
    /// An edge crack's end segment runs along the domain edge its mouth lies on.
    #[error(
        "geometry.cracks[{crack}] point {point} {} lies on domain edge {edge} and the crack runs along that edge: a crack must leave the boundary transversally",
        pt(.coords)
    )]
    CrackMouthAlongBoundary {
        /// Index of the crack.
        crack: usize,
        /// Index of the point within the crack (its first or last).
        point: usize,
        /// The point as given.
        coords: [f64; 2],
        /// Index of the domain edge the point lies on.
        edge: usize,
    },
    /// A crack segment joins two points of ∂Ω outside the domain.
    #[error(
        "geometry.cracks[{crack}] segment {segment} joins two boundary points outside the domain"
    )]
    CrackSegmentOutside {
        /// Index of the crack.
        crack: usize,
        /// Index of the segment within the crack.
        segment: usize,
    },
    /// Two cracks cross or touch.
    #[error(
        "geometry.cracks[{first}] and geometry.cracks[{second}] intersect \
         (segment {first_segment} and segment {second_segment})"
    )]
    CracksIntersect {
        /// Index of the first crack (the smaller one).
        first: usize,
        /// Index of the second crack.
        second: usize,
        /// Index of the segment within the first crack.
        first_segment: usize,
        /// Index of the segment within the second crack.
        second_segment: usize,
    },
}

/// Displays a point as `(x, y)`.
struct Pt([f64; 2]);

impl fmt::Display for Pt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "({}, {})", self.0[0], self.0[1])
    }
}

/// Displays a segment as `from (x, y) to (x, y)`.
struct Seg([[f64; 2]; 2]);

impl fmt::Display for Seg {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "from {} to {}", Pt(self.0[0]), Pt(self.0[1]))
    }
}

fn pt(p: &[f64; 2]) -> Pt {
    Pt(*p)
}

fn seg(s: &[[f64; 2]; 2]) -> Seg {
    Seg(*s)
}

/// A zero-length edge at `p`.
fn point_edge(p: &[f64; 2]) -> Seg {
    Seg([*p, *p])
}

impl GeometryError {
    /// The scene crack an error is about (the first of two that intersect), if any: the caller
    /// names it as the scene does.
    pub fn crack(&self) -> Option<usize> {
        match self {
            GeometryError::CrackTooFewPoints { crack, .. }
            | GeometryError::CrackNonFinite { crack, .. }
            | GeometryError::CrackCoordinateTooLarge { crack, .. }
            | GeometryError::CrackZeroLengthSegment { crack, .. }
            | GeometryError::CrackSelfIntersection { crack, .. }
            | GeometryError::CrackFoldsBack { crack, .. }
            | GeometryError::CrackPointOutside { crack, .. }
            | GeometryError::CrackPointOnBoundary { crack, .. }
            | GeometryError::CrackCrossesBoundary { crack, .. }
            | GeometryError::CrackMouthAtCorner { crack, .. }
            | GeometryError::CrackMouthAlongBoundary { crack, .. }
            | GeometryError::CrackSegmentOutside { crack, .. } => Some(*crack),
            GeometryError::CracksIntersect { first, .. } => Some(*first),
            _ => None,
        }
    }
}
