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

/// Where a point lies relative to a polygon; see [`point_in_polygon`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Inside {
    /// Strictly inside the polygon.
    Inside,
    /// Strictly outside the polygon.
    Outside,
    /// On an edge or a vertex of the polygon.
    OnBoundary,
}

/// Signed area of a polygon (vertices in order, first vertex not repeated at the end).
///
/// Positive for counter-clockwise, negative for clockwise order; 0 for fewer than 3 vertices.
/// For a self-intersecting polygon this is the sum of the signed areas of its lobes.
#[must_use]
pub fn signed_area(polygon: &[[f64; 2]]) -> f64 {
    let Some(&origin) = polygon.first() else {
        return 0.0;
    };
    // Fan triangulation from the first vertex: better conditioned than the plain shoelace sum
    // when the polygon lies far from the coordinate origin.
    let twice: f64 = polygon
        .windows(2)
        .skip(1)
        .map(|w| cross(sub(w[0], origin), sub(w[1], origin)))
        .sum();
    0.5 * twice
}

/// The same polygon in counter-clockwise order.
///
/// A clockwise polygon (negative [`signed_area`]) is reversed keeping its first vertex first:
/// `[v0, v1, …, vn-1]` becomes `[v0, vn-1, …, v1]`. Any other polygon (including a degenerate one
/// with zero area) is returned unchanged.
#[must_use]
pub fn counter_clockwise(polygon: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut result = polygon.to_vec();
    if signed_area(polygon) < 0.0 {
        result[1..].reverse();
    }
    result
}

/// Classifies `p` against a polygon of either orientation.
///
/// A point on an edge or vertex is [`Inside::OnBoundary`]; otherwise the winding number decides,
/// so a self-overlapping polygon counts the overlaps as inside. The tests are exact-sign
/// predicates (no tolerance). A non-finite point, any point against a polygon with a non-finite
/// coordinate, and any point not on a polygon with fewer than 3 vertices is [`Inside::Outside`].
#[must_use]
pub fn point_in_polygon(p: [f64; 2], polygon: &[[f64; 2]]) -> Inside {
    if !is_finite(p) || !polygon.iter().all(|&v| is_finite(v)) {
        return Inside::Outside;
    }
    if edges(polygon).any(|(_, edge)| on_segment(p, edge)) {
        return Inside::OnBoundary;
    }
    if winding_number(p, polygon) == 0 {
        Inside::Outside
    } else {
        Inside::Inside
    }
}

/// Whether two closed segments `[start, end]` share at least one point.
///
/// Touching counts: an end point on the other segment, shared end points and collinear overlap
/// all return `true`. A segment whose end points coincide is treated as a single point. Exact-sign
/// predicates; any non-finite coordinate gives `false`.
#[must_use]
pub fn segments_intersect(a: [[f64; 2]; 2], b: [[f64; 2]; 2]) -> bool {
    if !a.iter().chain(&b).all(|&p| is_finite(p)) {
        return false;
    }
    let d1 = orientation(b[0], b[1], a[0]);
    let d2 = orientation(b[0], b[1], a[1]);
    let d3 = orientation(a[0], a[1], b[0]);
    let d4 = orientation(a[0], a[1], b[1]);
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    (d1 == 0 && in_box(a[0], b))
        || (d2 == 0 && in_box(a[1], b))
        || (d3 == 0 && in_box(b[0], a))
        || (d4 == 0 && in_box(b[1], a))
}

/// Checks that `polygon` is a usable domain: a simple polygon of non-zero area.
///
/// Either orientation is accepted and the first vertex must not be repeated at the end. Checks,
/// in this order: every coordinate finite (so NaN is always reported as such), every coordinate
/// at most [`MAX_COORDINATE`] in magnitude, at least 3 vertices, no zero-length edge (including
/// last → first), not all vertices collinear, no two adjacent edges folding back onto each other,
/// no two non-adjacent edges crossing or touching.
///
/// # Errors
///
/// The first failed check, as one of the `Polygon*` variants of [`GeometryError`].
pub fn validate_polygon(polygon: &[[f64; 2]]) -> Result<(), GeometryError> {
    check_polygon_coordinates(polygon)?;
    if polygon.len() < 3 {
        return Err(GeometryError::PolygonTooFewVertices {
            count: polygon.len(),
        });
    }
    check_polygon_edge_lengths(polygon)?;
    if all_collinear(polygon) {
        return Err(GeometryError::PolygonCollinear);
    }
    check_polygon_simple(polygon)
}

/// Checks that `cracks` are acceptable in the domain `polygon`.
///
/// The polygon is validated first with [`validate_polygon`] and its error returned if any. An
/// empty crack list is accepted (whether a scene needs a crack is the caller's decision). Then,
/// crack by crack in order: every coordinate finite, at least 2 points, coordinates within
/// [`MAX_COORDINATE`], no zero-length segment, no self-intersection (non-adjacent segments
/// touching, or consecutive segments folding back), every point strictly inside Ω (not outside,
/// not on ∂Ω), no segment crossing or touching a domain edge. Finally no two cracks may cross or
/// touch.
///
/// # Errors
///
/// The first failed check: a `Polygon*` variant of [`GeometryError`] for the domain, a `Crack*`
/// variant for a single crack, [`GeometryError::CracksIntersect`] for a pair.
pub fn validate_cracks(
    polygon: &[[f64; 2]],
    cracks: &[Vec<[f64; 2]>],
) -> Result<(), GeometryError> {
    validate_polygon(polygon)?;
    for (index, crack) in cracks.iter().enumerate() {
        check_crack_shape(index, crack)?;
        check_crack_in_domain(index, crack, polygon)?;
    }
    check_cracks_disjoint(cracks)
}

// ---------------------------------------------------------------------------------------------
// Polygon checks

fn check_polygon_coordinates(polygon: &[[f64; 2]]) -> Result<(), GeometryError> {
    if let Some(vertex) = polygon.iter().position(|&p| !is_finite(p)) {
        return Err(GeometryError::PolygonNonFinite {
            vertex,
            point: polygon[vertex],
        });
    }
    if let Some(vertex) = polygon.iter().position(|&p| !in_range(p)) {
        return Err(GeometryError::PolygonCoordinateTooLarge {
            vertex,
            point: polygon[vertex],
        });
    }
    Ok(())
}

fn check_polygon_edge_lengths(polygon: &[[f64; 2]]) -> Result<(), GeometryError> {
    match edges(polygon).find(|(_, [start, end])| start == end) {
        Some((edge, [point, _])) => Err(GeometryError::PolygonZeroLengthEdge {
            edge,
            next: (edge + 1) % polygon.len(),
            point,
        }),
        None => Ok(()),
    }
}

/// Whether every vertex lies on the line through the first two (which must differ).
fn all_collinear(polygon: &[[f64; 2]]) -> bool {
    let (a, b) = (polygon[0], polygon[1]);
    polygon[2..].iter().all(|&p| orientation(a, b, p) == 0)
}

/// Requires at least 3 vertices and no zero-length edge.
fn check_polygon_simple(polygon: &[[f64; 2]]) -> Result<(), GeometryError> {
    let n = polygon.len();
    let edge = |k: usize| [polygon[k], polygon[(k + 1) % n]];
    for first in 0..n {
        let second = (first + 1) % n;
        if folds_back(polygon[first], polygon[second], polygon[(first + 2) % n]) {
            return Err(GeometryError::PolygonFoldsBack {
                first,
                first_edge: edge(first),
                second,
                second_edge: edge(second),
            });
        }
    }
    for first in 0..n {
        // Edge n - 1 is adjacent to edge 0.
        let last = if first == 0 { n - 1 } else { n };
        for second in (first + 2)..last {
            if segments_intersect(edge(first), edge(second)) {
                return Err(GeometryError::PolygonSelfIntersection {
                    first,
                    first_edge: edge(first),
                    second,
                    second_edge: edge(second),
                });
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------
// Crack checks

/// Checks of one crack on its own: coordinates, point count, segment lengths, self-intersection.
fn check_crack_shape(crack: usize, points: &[[f64; 2]]) -> Result<(), GeometryError> {
    if let Some(point) = points.iter().position(|&p| !is_finite(p)) {
        return Err(GeometryError::CrackNonFinite {
            crack,
            point,
            coords: points[point],
        });
    }
    if points.len() < 2 {
        return Err(GeometryError::CrackTooFewPoints {
            crack,
            count: points.len(),
        });
    }
    if let Some(point) = points.iter().position(|&p| !in_range(p)) {
        return Err(GeometryError::CrackCoordinateTooLarge {
            crack,
            point,
            coords: points[point],
        });
    }
    if let Some(segment) = points.windows(2).position(|w| w[0] == w[1]) {
        return Err(GeometryError::CrackZeroLengthSegment { crack, segment });
    }
    check_crack_not_self_intersecting(crack, points)
}

/// Requires at least 2 points and no zero-length segment.
fn check_crack_not_self_intersecting(
    crack: usize,
    points: &[[f64; 2]],
) -> Result<(), GeometryError> {
    if let Some(first) = points.windows(3).position(|w| folds_back(w[0], w[1], w[2])) {
        return Err(GeometryError::CrackFoldsBack {
            crack,
            first,
            second: first + 1,
        });
    }
    let segments: Vec<_> = polyline_segments(points).collect();
    for (first, &a) in segments.iter().enumerate() {
        for (second, &b) in segments.iter().enumerate().skip(first + 2) {
            if segments_intersect(a, b) {
                return Err(GeometryError::CrackSelfIntersection {
                    crack,
                    first,
                    second,
                });
            }
        }
    }
    Ok(())
}

/// Checks that a crack lies strictly inside the (valid) domain polygon.
fn check_crack_in_domain(
    crack: usize,
    points: &[[f64; 2]],
    polygon: &[[f64; 2]],
) -> Result<(), GeometryError> {
    for (point, &coords) in points.iter().enumerate() {
        match point_in_polygon(coords, polygon) {
            Inside::Inside => {}
            Inside::Outside => {
                return Err(GeometryError::CrackPointOutside {
                    crack,
                    point,
                    coords,
                });
            }
            Inside::OnBoundary => {
                return Err(GeometryError::CrackPointOnBoundary {
                    crack,
                    point,
                    coords,
                });
            }
        }
    }
    for (segment, s) in polyline_segments(points).enumerate() {
        if let Some((edge, edge_points)) = edges(polygon).find(|&(_, e)| segments_intersect(s, e)) {
            return Err(GeometryError::CrackCrossesBoundary {
                crack,
                segment,
                edge,
                edge_points,
            });
        }
    }
    Ok(())
}

/// Checks that no two cracks share a point.
fn check_cracks_disjoint(cracks: &[Vec<[f64; 2]>]) -> Result<(), GeometryError> {
    for (first, a) in cracks.iter().enumerate() {
        for (second, b) in cracks.iter().enumerate().skip(first + 1) {
            if let Some((first_segment, second_segment)) = polylines_intersection(a, b) {
                return Err(GeometryError::CracksIntersect {
                    first,
                    second,
                    first_segment,
                    second_segment,
                });
            }
        }
    }
    Ok(())
}

/// First pair of segment indices at which two polylines cross or touch.
fn polylines_intersection(a: &[[f64; 2]], b: &[[f64; 2]]) -> Option<(usize, usize)> {
    polyline_segments(a).enumerate().find_map(|(i, sa)| {
        polyline_segments(b)
            .position(|sb| segments_intersect(sa, sb))
            .map(|j| (i, j))
    })
}

// ---------------------------------------------------------------------------------------------
// Elementary helpers

/// Edges of a closed polygon with their indices: edge `k` is `[v_k, v_(k+1) mod n]`.
fn edges(polygon: &[[f64; 2]]) -> impl Iterator<Item = (usize, [[f64; 2]; 2])> + '_ {
    let n = polygon.len();
    (0..n).map(move |k| (k, [polygon[k], polygon[(k + 1) % n]]))
}

/// Segments of an open polyline: segment `k` is `[p_k, p_(k+1)]`.
fn polyline_segments(points: &[[f64; 2]]) -> impl Iterator<Item = [[f64; 2]; 2]> + '_ {
    points.windows(2).map(|w| [w[0], w[1]])
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// Sign of the turn `a → b → c`: 1 for left (counter-clockwise), -1 for right, 0 for collinear
/// (exact-zero test; NaN also gives 0).
fn orientation(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i32 {
    let value = cross(sub(b, a), sub(c, a));
    if value > 0.0 {
        1
    } else if value < 0.0 {
        -1
    } else {
        0
    }
}

/// Whether `p` lies in the closed bounding box of segment `s`.
fn in_box(p: [f64; 2], s: [[f64; 2]; 2]) -> bool {
    (0..2).all(|k| s[0][k].min(s[1][k]) <= p[k] && p[k] <= s[0][k].max(s[1][k]))
}

/// Whether `p` lies on the closed segment `s`.
fn on_segment(p: [f64; 2], s: [[f64; 2]; 2]) -> bool {
    orientation(s[0], s[1], p) == 0 && in_box(p, s)
}

/// Whether the consecutive segments `p → v` and `v → q` (both of non-zero length) overlap along
/// more than their shared point `v`, i.e. `q` turns straight back towards `p`.
fn folds_back(p: [f64; 2], v: [f64; 2], q: [f64; 2]) -> bool {
    orientation(p, v, q) == 0 && dot(sub(p, v), sub(q, v)) > 0.0
}

/// Winding number of the polygon around `p`, which must not lie on the boundary.
fn winding_number(p: [f64; 2], polygon: &[[f64; 2]]) -> i32 {
    edges(polygon)
        .map(|(_, [a, b])| {
            if a[1] <= p[1] && b[1] > p[1] && orientation(a, b, p) > 0 {
                1
            } else if a[1] > p[1] && b[1] <= p[1] && orientation(a, b, p) < 0 {
                -1
            } else {
                0
            }
        })
        .sum()
}

fn is_finite(p: [f64; 2]) -> bool {
    p[0].is_finite() && p[1].is_finite()
}

fn in_range(p: [f64; 2]) -> bool {
    p[0].abs() <= MAX_COORDINATE && p[1].abs() <= MAX_COORDINATE
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

#[cfg(test)]
mod tests {
    use super::*;

    fn l_shape_reversed() -> Vec<[f64; 2]> {
        L_SHAPE.iter().rev().copied().collect()
    }

    fn square(half: f64) -> Vec<[f64; 2]> {
        vec![[-half, -half], [half, -half], [half, half], [-half, half]]
    }

    /// Rotates `p` by `degrees` counter-clockwise about the origin.
    fn rotate(p: [f64; 2], degrees: f64) -> [f64; 2] {
        let (s, c) = degrees.to_radians().sin_cos();
        [c * p[0] - s * p[1], s * p[0] + c * p[1]]
    }

    fn rotated(points: &[[f64; 2]], degrees: f64) -> Vec<[f64; 2]> {
        points.iter().map(|&p| rotate(p, degrees)).collect()
    }

    fn err_cracks(polygon: &[[f64; 2]], cracks: &[Vec<[f64; 2]>]) -> GeometryError {
        validate_cracks(polygon, cracks).expect_err("cracks should be rejected")
    }

    // --- signed_area / counter_clockwise -------------------------------------------------------

    #[test]
    fn l_shape_area_and_orientation() {
        assert_eq!(signed_area(&L_SHAPE), 3.0);
        assert_eq!(signed_area(&l_shape_reversed()), -3.0);
        assert_eq!(counter_clockwise(&L_SHAPE), L_SHAPE.to_vec());
    }

    #[test]
    fn counter_clockwise_reverses_keeping_first_vertex() {
        let ccw = counter_clockwise(&l_shape_reversed());
        assert_eq!(signed_area(&ccw), 3.0);
        assert_eq!(ccw[0], [-1.0, 1.0]);
        assert_eq!(ccw[1], [-1.0, -1.0]);
        let mut sorted_in = l_shape_reversed();
        let mut sorted_out = ccw.clone();
        sorted_in.sort_by(|a, b| a.partial_cmp(b).unwrap());
        sorted_out.sort_by(|a, b| a.partial_cmp(b).unwrap());
        assert_eq!(sorted_in, sorted_out);
    }

    #[test]
    fn degenerate_area_inputs() {
        assert_eq!(signed_area(&[]), 0.0);
        assert_eq!(signed_area(&[[1.0, 2.0]]), 0.0);
        assert_eq!(signed_area(&[[1.0, 2.0], [3.0, 4.0]]), 0.0);
        assert!(counter_clockwise(&[]).is_empty());
        assert_eq!(counter_clockwise(&[[1.0, 2.0]]), vec![[1.0, 2.0]]);
        let far: Vec<_> = square(0.5)
            .iter()
            .map(|p| [p[0] + 1e8, p[1] - 1e8])
            .collect();
        assert_eq!(signed_area(&far), 1.0);
    }

    // --- point_in_polygon ------------------------------------------------------------------------

    #[test]
    fn point_in_l_shape() {
        for polygon in [L_SHAPE.to_vec(), l_shape_reversed()] {
            let at = |x, y| point_in_polygon([x, y], &polygon);
            assert_eq!(at(-0.5, -0.5), Inside::Inside);
            assert_eq!(at(0.5, -0.5), Inside::Inside);
            assert_eq!(at(-0.5, 0.5), Inside::Inside);
            // Horizontal ray through the vertices (0, 0) and (1, 0).
            assert_eq!(at(-0.5, 0.0), Inside::Inside);
            // The missing quadrant and far away.
            assert_eq!(at(0.5, 0.5), Inside::Outside);
            assert_eq!(at(2.0, 0.0), Inside::Outside);
            assert_eq!(at(-2.0, 0.0), Inside::Outside);
            assert_eq!(at(-2.0, -1.0), Inside::Outside);
            assert_eq!(at(0.5, 1.0), Inside::Outside);
            // On edges.
            assert_eq!(at(0.5, -1.0), Inside::OnBoundary);
            assert_eq!(at(0.5, 0.0), Inside::OnBoundary);
            assert_eq!(at(0.0, 0.5), Inside::OnBoundary);
            assert_eq!(at(-1.0, 0.25), Inside::OnBoundary);
            // On vertices, including the re-entrant corner.
            assert_eq!(at(0.0, 0.0), Inside::OnBoundary);
            assert_eq!(at(-1.0, 1.0), Inside::OnBoundary);
            assert_eq!(at(1.0, -1.0), Inside::OnBoundary);
            // Non-finite points are never inside.
            assert_eq!(at(f64::NAN, 0.0), Inside::Outside);
            assert_eq!(at(f64::INFINITY, 0.0), Inside::Outside);
        }
    }

    #[test]
    fn point_in_degenerate_polygon_does_not_panic() {
        assert_eq!(point_in_polygon([0.0, 0.0], &[]), Inside::Outside);
        assert_eq!(
            point_in_polygon([0.0, 0.0], &[[0.0, 0.0]]),
            Inside::OnBoundary
        );
        let nan_polygon = [[f64::NAN, 0.0], [1.0, 0.0], [0.0, 1.0]];
        assert_eq!(point_in_polygon([0.2, 0.2], &nan_polygon), Inside::Outside);
    }

    // --- segments_intersect ----------------------------------------------------------------------

    #[test]
    fn segment_intersection_cases() {
        let s = |a: [f64; 2], b: [f64; 2]| [a, b];
        let base = s([0.0, 0.0], [2.0, 0.0]);
        let cases = [
            (s([1.0, -1.0], [1.0, 1.0]), true),     // proper crossing
            (s([2.0, 0.0], [3.0, 1.0]), true),      // shared end point
            (s([1.0, 0.0], [1.0, 1.0]), true),      // T: end point on interior
            (s([1.0, 0.0], [3.0, 0.0]), true),      // collinear overlap
            (s([2.0, 0.0], [3.0, 0.0]), true),      // collinear, touching at an end
            (s([-1.0, 0.0], [3.0, 0.0]), true),     // collinear, containing
            (s([2.5, 0.0], [3.0, 0.0]), false),     // collinear, disjoint
            (s([0.0, 1.0], [2.0, 1.0]), false),     // parallel
            (s([3.0, -1.0], [3.0, 1.0]), false),    // lines cross outside the segment
            (s([1.0, 0.5], [1.0, 1.0]), false),     // would touch if extended
            (s([1.0, 0.0], [1.0, 0.0]), true),      // point on the segment
            (s([1.0, 1e-12], [1.0, 1e-12]), false), // point just off it
        ];
        for (other, expected) in cases {
            assert_eq!(segments_intersect(base, other), expected, "{other:?}");
            assert_eq!(
                segments_intersect(other, base),
                expected,
                "{other:?} swapped"
            );
            let flipped = [other[1], other[0]];
            assert_eq!(
                segments_intersect(base, flipped),
                expected,
                "{other:?} flipped"
            );
        }
        let nan = s([f64::NAN, 0.0], [1.0, 0.0]);
        assert!(!segments_intersect(base, nan));
    }

    // --- validate_polygon ------------------------------------------------------------------------

    #[test]
    fn valid_polygons() {
        assert_eq!(validate_polygon(&L_SHAPE), Ok(()));
        assert_eq!(validate_polygon(&l_shape_reversed()), Ok(()));
        assert_eq!(
            validate_polygon(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]),
            Ok(())
        );
        assert_eq!(validate_polygon(&rotated(&square(1.0), 30.0)), Ok(()));
        // A collinear run of vertices along one side is fine.
        let with_midpoint = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [0.0, 1.0]];
        assert_eq!(validate_polygon(&with_midpoint), Ok(()));
    }

    #[test]
    fn polygon_too_few_vertices() {
        let err = validate_polygon(&[[0.0, 0.0], [1.0, 0.0]]).unwrap_err();
        assert_eq!(err, GeometryError::PolygonTooFewVertices { count: 2 });
        assert_eq!(
            err.to_string(),
            "domain.polygon has too few vertices (2); at least 3 are required"
        );
        assert_eq!(
            validate_polygon(&[]),
            Err(GeometryError::PolygonTooFewVertices { count: 0 })
        );
    }

    #[test]
    fn polygon_non_finite_comes_first() {
        let err = validate_polygon(&[[0.0, 0.0], [f64::NAN, 1.0]]).unwrap_err();
        assert!(matches!(
            err,
            GeometryError::PolygonNonFinite { vertex: 1, .. }
        ));
        assert_eq!(
            err.to_string(),
            "domain.polygon vertex 1 (NaN, 1) has a non-finite coordinate"
        );
        let bow_tie_with_inf = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, f64::INFINITY]];
        assert_eq!(
            validate_polygon(&bow_tie_with_inf),
            Err(GeometryError::PolygonNonFinite {
                vertex: 3,
                point: [0.0, f64::INFINITY]
            })
        );
    }

    #[test]
    fn polygon_coordinate_too_large() {
        let err = validate_polygon(&[[0.0, 0.0], [1e200, 0.0], [0.0, 1.0]]).unwrap_err();
        assert_eq!(
            err,
            GeometryError::PolygonCoordinateTooLarge {
                vertex: 1,
                point: [1e200, 0.0]
            }
        );
        assert_eq!(
            err.to_string(),
            format!(
                "domain.polygon vertex 1 ({}, 0) has a coordinate larger in magnitude than 1e100",
                1e200
            )
        );
    }

    #[test]
    fn polygon_repeated_vertex() {
        let err = validate_polygon(&[[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [0.0, 1.0]]).unwrap_err();
        assert_eq!(
            err,
            GeometryError::PolygonZeroLengthEdge {
                edge: 1,
                next: 2,
                point: [1.0, 0.0]
            }
        );
        assert_eq!(
            err.to_string(),
            "domain.polygon edge 1 (from (1, 0) to (1, 0)) has zero length (vertices 1 and 2 coincide)"
        );
        // First vertex repeated at the end.
        let closed = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [0.0, 0.0]];
        assert!(matches!(
            validate_polygon(&closed),
            Err(GeometryError::PolygonZeroLengthEdge {
                edge: 3,
                next: 0,
                ..
            })
        ));
    }

    #[test]
    fn polygon_collinear() {
        let err = validate_polygon(&[[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]]).unwrap_err();
        assert_eq!(err, GeometryError::PolygonCollinear);
        assert_eq!(
            err.to_string(),
            "domain.polygon has zero area (all vertices are collinear)"
        );
        let diagonal = [[0.0, 0.0], [1.0, 1.0], [3.0, 3.0], [2.0, 2.0]];
        assert_eq!(
            validate_polygon(&diagonal),
            Err(GeometryError::PolygonCollinear)
        );
    }

    #[test]
    fn polygon_bow_tie() {
        let bow_tie = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        let err = validate_polygon(&bow_tie).unwrap_err();
        assert!(matches!(
            err,
            GeometryError::PolygonSelfIntersection {
                first: 0,
                second: 2,
                ..
            }
        ));
        assert_eq!(
            err.to_string(),
            "geometry.domain.polygon is not a simple polygon: edge 0 (from (0, 0) to (1, 1)) \
             crosses edge 2 (from (1, 0) to (0, 1))"
        );
    }

    #[test]
    fn polygon_vertex_touching_edge() {
        let pinched = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [2.0, 0.0], [0.0, 4.0]];
        assert!(matches!(
            validate_polygon(&pinched),
            Err(GeometryError::PolygonSelfIntersection {
                first: 0,
                second: 2,
                ..
            })
        ));
        // Figure eight through a shared vertex.
        let eight = [
            [0.0, 0.0],
            [1.0, 1.0],
            [2.0, 0.0],
            [2.0, 2.0],
            [1.0, 1.0],
            [0.0, 2.0],
        ];
        assert!(matches!(
            validate_polygon(&eight),
            Err(GeometryError::PolygonSelfIntersection { .. })
        ));
    }

    #[test]
    fn polygon_folds_back() {
        let spike = [[0.0, 0.0], [2.0, 0.0], [1.0, 0.0], [1.0, 1.0]];
        let err = validate_polygon(&spike).unwrap_err();
        assert_eq!(
            err,
            GeometryError::PolygonFoldsBack {
                first: 0,
                first_edge: [[0.0, 0.0], [2.0, 0.0]],
                second: 1,
                second_edge: [[2.0, 0.0], [1.0, 0.0]],
            }
        );
        assert_eq!(
            err.to_string(),
            "geometry.domain.polygon is not a simple polygon: edge 0 (from (0, 0) to (2, 0)) \
             folds back onto edge 1 (from (2, 0) to (1, 0))"
        );
        // Fold back across the closing vertex (edges 3 and 0).
        let spike_at_start = [[2.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 0.0]];
        assert!(matches!(
            validate_polygon(&spike_at_start),
            Err(GeometryError::PolygonFoldsBack {
                first: 3,
                second: 0,
                ..
            })
        ));
    }

    // --- validate_cracks: valid scenes -----------------------------------------------------------

    fn l_shape_cracks() -> Vec<Vec<[f64; 2]>> {
        vec![
            vec![[-0.7, -0.5], [-0.2, -0.3], [0.4, -0.6]],
            vec![[-0.8, 0.5], [-0.3, 0.7]],
        ]
    }

    #[test]
    fn valid_cracks_in_l_shape() {
        assert_eq!(validate_cracks(&L_SHAPE, &l_shape_cracks()), Ok(()));
        assert_eq!(
            validate_cracks(&l_shape_reversed(), &l_shape_cracks()),
            Ok(())
        );
    }

    #[test]
    fn empty_crack_list_is_allowed() {
        assert_eq!(validate_cracks(&L_SHAPE, &[]), Ok(()));
    }

    #[test]
    fn invalid_polygon_is_reported_by_validate_cracks() {
        let bow_tie = [[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]];
        assert!(matches!(
            validate_cracks(&bow_tie, &[]),
            Err(GeometryError::PolygonSelfIntersection { .. })
        ));
    }

    #[test]
    fn rotated_cracks_at_30_degrees_are_valid() {
        let domain = square(1.0);
        // A straight crack at 30° to the axes.
        let straight = rotated(&[[-0.5, 0.0], [0.5, 0.0]], 30.0);
        // An open polyline along three sides of a rectangle rotated by 30°.
        let rectangle_sides = rotated(&[[-0.4, -0.2], [0.4, -0.2], [0.4, 0.2], [-0.4, 0.2]], 30.0);
        assert_eq!(
            validate_cracks(&domain, std::slice::from_ref(&straight)),
            Ok(())
        );
        assert_eq!(
            validate_cracks(&domain, &[rectangle_sides.clone(), straight]),
            Err(GeometryError::CracksIntersect {
                first: 0,
                second: 1,
                first_segment: 1,
                second_segment: 0
            })
        );
        let short: Vec<_> = rotated(&[[-0.2, 0.0], [0.2, 0.0]], 30.0);
        assert_eq!(validate_cracks(&domain, &[rectangle_sides, short]), Ok(()));
        // A rotated rectangular domain with a crack along its long axis, and one poking out.
        let rotated_domain = rotated(&[[-2.0, -1.0], [2.0, -1.0], [2.0, 1.0], [-2.0, 1.0]], 30.0);
        let axis = rotated(&[[-1.5, 0.0], [1.5, 0.0]], 30.0);
        assert_eq!(validate_cracks(&rotated_domain, &[axis]), Ok(()));
        let poking = rotated(&[[0.0, 0.0], [0.0, 1.5]], 30.0);
        assert!(matches!(
            validate_cracks(&rotated_domain, &[poking]),
            Err(GeometryError::CrackPointOutside { point: 1, .. })
        ));
    }

    // --- validate_cracks: per-crack errors -------------------------------------------------------

    #[test]
    fn crack_too_few_points() {
        let mut cracks = l_shape_cracks();
        cracks.push(vec![[-0.5, -0.5]]);
        let err = err_cracks(&L_SHAPE, &cracks);
        assert_eq!(err, GeometryError::CrackTooFewPoints { crack: 2, count: 1 });
        assert_eq!(
            err.to_string(),
            "geometry.cracks[2] has too few points (1); at least 2 are required"
        );
        assert_eq!(
            err_cracks(&L_SHAPE, &[vec![]]),
            GeometryError::CrackTooFewPoints { crack: 0, count: 0 }
        );
    }

    #[test]
    fn crack_non_finite_comes_first() {
        let err = err_cracks(&L_SHAPE, &[vec![[f64::NAN, 0.0]]]);
        assert!(matches!(
            err,
            GeometryError::CrackNonFinite {
                crack: 0,
                point: 0,
                ..
            }
        ));
        assert_eq!(
            err.to_string(),
            "geometry.cracks[0] point 0 (NaN, 0) has a non-finite coordinate"
        );
        // A NaN must not be reported as a point outside the domain or a crossing.
        let cracks = vec![vec![[5.0, 5.0], [-0.5, f64::NEG_INFINITY]]];
        assert!(matches!(
            err_cracks(&L_SHAPE, &cracks),
            GeometryError::CrackNonFinite {
                crack: 0,
                point: 1,
                ..
            }
        ));
    }

    #[test]
    fn crack_coordinate_too_large() {
        let err = err_cracks(&L_SHAPE, &[vec![[-0.5, -0.5], [-1e300, 0.0]]]);
        assert_eq!(
            err,
            GeometryError::CrackCoordinateTooLarge {
                crack: 0,
                point: 1,
                coords: [-1e300, 0.0]
            }
        );
    }

    #[test]
    fn crack_zero_length_segment() {
        let cracks = vec![
            l_shape_cracks()[0].clone(),
            vec![[-0.9, 0.2], [-0.7, 0.3], [-0.5, 0.3], [-0.5, 0.3]],
        ];
        let err = err_cracks(&L_SHAPE, &cracks);
        assert_eq!(
            err,
            GeometryError::CrackZeroLengthSegment {
                crack: 1,
                segment: 2
            }
        );
        assert_eq!(
            err.to_string(),
            "geometry.cracks[1] segment 2 has zero length (points 2 and 3 coincide)"
        );
    }

    #[test]
    fn crack_z_crossing_itself() {
        let z = vec![[0.0, 0.0], [2.0, 0.0], [0.0, 1.0], [1.0, -1.0]];
        let err = err_cracks(&square(10.0), &[z]);
        assert_eq!(
            err,
            GeometryError::CrackSelfIntersection {
                crack: 0,
                first: 0,
                second: 2
            }
        );
        assert_eq!(
            err.to_string(),
            "geometry.cracks[0] intersects itself (segment 0 and segment 2)"
        );
        // A closed loop touches itself at its start.
        let triangle = vec![[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 0.0]];
        assert!(matches!(
            err_cracks(&square(10.0), &[triangle]),
            GeometryError::CrackSelfIntersection {
                first: 0,
                second: 2,
                ..
            }
        ));
    }

    #[test]
    fn crack_folds_back() {
        let fold = vec![[0.0, 0.0], [0.5, 0.0], [0.2, 0.0]];
        let err = err_cracks(&square(10.0), &[fold]);
        assert_eq!(
            err,
            GeometryError::CrackFoldsBack {
                crack: 0,
                first: 0,
                second: 1
            }
        );
        assert_eq!(
            err.to_string(),
            "geometry.cracks[0] folds back on itself (segment 0 and segment 1 overlap)"
        );
        // Going straight on along the same line is fine.
        let straight = vec![[0.0, 0.0], [0.5, 0.0], [0.7, 0.0]];
        assert_eq!(validate_cracks(&square(10.0), &[straight]), Ok(()));
    }

    #[test]
    fn crack_point_outside_in_re_entrant_corner() {
        let err = err_cracks(&L_SHAPE, &[vec![[0.5, -0.5], [0.5, 0.5]]]);
        assert_eq!(
            err,
            GeometryError::CrackPointOutside {
                crack: 0,
                point: 1,
                coords: [0.5, 0.5]
            }
        );
        assert_eq!(
            err.to_string(),
            "geometry.cracks[0] point 1 (0.5, 0.5) lies outside the domain"
        );
    }

    #[test]
    fn crack_point_on_boundary() {
        let err = err_cracks(&L_SHAPE, &[vec![[-0.5, 0.0], [-0.5, 1.0]]]);
        assert_eq!(
            err,
            GeometryError::CrackPointOnBoundary {
                crack: 0,
                point: 1,
                coords: [-0.5, 1.0]
            }
        );
        assert_eq!(
            err.to_string(),
            "geometry.cracks[0] point 1 (-0.5, 1) touches the domain boundary"
        );
        // The re-entrant corner itself is on the boundary too.
        assert!(matches!(
            err_cracks(&L_SHAPE, &[vec![[0.0, 0.0], [-0.5, -0.5]]]),
            GeometryError::CrackPointOnBoundary { point: 0, .. }
        ));
    }

    #[test]
    fn crack_segment_crosses_boundary() {
        // Both end points inside, the segment cuts across the missing quadrant.
        let cracks = vec![l_shape_cracks()[1].clone(), vec![[0.5, -0.5], [-0.5, 0.6]]];
        let err = err_cracks(&L_SHAPE, &cracks);
        assert_eq!(
            err,
            GeometryError::CrackCrossesBoundary {
                crack: 1,
                segment: 0,
                edge: 2,
                edge_points: [[1.0, 0.0], [0.0, 0.0]]
            }
        );
        assert_eq!(
            err.to_string(),
            "geometry.cracks[1] segment 0 crosses the domain boundary (edge 2 from (1, 0) to (0, 0))"
        );
        // Passing exactly through the re-entrant vertex counts as touching.
        let through_corner = vec![[-0.5, -0.5], [0.5, -0.5], [-0.5, 0.5]];
        assert!(matches!(
            err_cracks(&L_SHAPE, &[through_corner]),
            GeometryError::CrackCrossesBoundary {
                segment: 1,
                edge: 2,
                ..
            }
        ));
    }

    // --- validate_cracks: pairs of cracks --------------------------------------------------------

    #[test]
    fn two_crossing_cracks() {
        let cracks = vec![
            vec![[-0.8, -0.8], [-0.2, -0.2]],
            // Segment 0 lies on the first crack's line but beyond its end; segment 1 crosses it.
            vec![[-0.9, -0.9], [-0.85, -0.2], [-0.2, -0.8]],
        ];
        let err = err_cracks(&L_SHAPE, &cracks);
        assert_eq!(
            err,
            GeometryError::CracksIntersect {
                first: 0,
                second: 1,
                first_segment: 0,
                second_segment: 1
            }
        );
        assert_eq!(
            err.to_string(),
            "geometry.cracks[0] and geometry.cracks[1] intersect (segment 0 and segment 1)"
        );
    }

    #[test]
    fn cracks_touching_at_an_end_point() {
        let shared_end = vec![
            vec![[-0.8, 0.2], [-0.5, 0.5]],
            vec![[-0.5, 0.5], [-0.2, 0.3]],
        ];
        assert!(matches!(
            err_cracks(&L_SHAPE, &shared_end),
            GeometryError::CracksIntersect {
                first: 0,
                second: 1,
                ..
            }
        ));
        // An end point on the interior of another crack (T junction), checked after valid cracks.
        let mut t_junction = l_shape_cracks();
        t_junction.push(vec![[-0.6, -0.9], [-0.6, -0.7]]);
        t_junction.push(vec![[-0.6, -0.8], [-0.4, -0.8]]);
        assert_eq!(
            err_cracks(&L_SHAPE, &t_junction),
            GeometryError::CracksIntersect {
                first: 2,
                second: 3,
                first_segment: 0,
                second_segment: 0
            }
        );
    }

    #[test]
    fn collinear_cracks_overlapping_or_not() {
        let overlapping = vec![
            vec![[-0.9, -0.5], [-0.4, -0.5]],
            vec![[-0.6, -0.5], [-0.1, -0.5]],
        ];
        assert!(matches!(
            err_cracks(&L_SHAPE, &overlapping),
            GeometryError::CracksIntersect { .. }
        ));
        let disjoint = vec![
            vec![[-0.9, -0.5], [-0.6, -0.5]],
            vec![[-0.4, -0.5], [-0.1, -0.5]],
        ];
        assert_eq!(validate_cracks(&L_SHAPE, &disjoint), Ok(()));
    }

    // --- robustness --------------------------------------------------------------------------

    /// Feeds many small scenes built from awkward values through every public function: nothing
    /// may panic, and any non-finite value must be reported as such.
    #[test]
    fn awkward_inputs_never_panic() {
        let values = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            0.5,
            1e-300,
            1e100,
            -1e100,
            1e300,
            f64::MAX,
            f64::MIN_POSITIVE,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let mut state: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = |bound: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % bound as u64) as usize
        };
        for _ in 0..3000 {
            let polygon: Vec<[f64; 2]> = (0..next(7))
                .map(|_| [values[next(values.len())], values[next(values.len())]])
                .collect();
            let cracks: Vec<Vec<[f64; 2]>> = (0..next(3))
                .map(|_| {
                    (0..next(4))
                        .map(|_| [values[next(values.len())], values[next(values.len())]])
                        .collect()
                })
                .collect();
            let _ = signed_area(&polygon);
            let _ = counter_clockwise(&polygon);
            let _ = point_in_polygon([values[next(values.len())], 0.25], &polygon);
            if polygon.len() >= 2 {
                let _ = segments_intersect([polygon[0], polygon[1]], [polygon[1], polygon[0]]);
            }
            let polygon_has_nan = polygon.iter().any(|&p| !is_finite(p));
            match validate_cracks(&polygon, &cracks) {
                Err(GeometryError::PolygonNonFinite { .. }) => assert!(polygon_has_nan),
                _ => assert!(!polygon_has_nan),
            }
            if let Err(err) = validate_cracks(&square(1.0), &cracks) {
                assert!(!err.to_string().contains('\n'));
                let finite = |crack: usize| cracks[crack].iter().all(|&p| is_finite(p));
                match err {
                    GeometryError::CrackNonFinite { crack, .. } => assert!(!finite(crack)),
                    GeometryError::CrackTooFewPoints { crack, .. }
                    | GeometryError::CrackCoordinateTooLarge { crack, .. }
                    | GeometryError::CrackZeroLengthSegment { crack, .. }
                    | GeometryError::CrackSelfIntersection { crack, .. }
                    | GeometryError::CrackFoldsBack { crack, .. }
                    | GeometryError::CrackPointOutside { crack, .. }
                    | GeometryError::CrackPointOnBoundary { crack, .. }
                    | GeometryError::CrackCrossesBoundary { crack, .. } => assert!(finite(crack)),
                    GeometryError::CracksIntersect { first, second, .. } => {
                        assert!(finite(first) && finite(second))
                    }
                    other => panic!("unexpected polygon error for a valid square: {other}"),
                }
            }
        }
    }
}
