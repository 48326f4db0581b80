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
#[cfg(test)]
mod tests;

pub use error::{GeometryError, MAX_COORDINATE};

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
