//! Validation of the domain polygon and of the cracks: each requirement one check, the first
//! broken one reported as a [`GeometryError`].

use super::error::{GeometryError, MAX_COORDINATE};
use super::predicates::{
    edges, folds_back, is_finite, orientation, point_in_polygon, polyline_segments,
    segments_intersect, Inside,
};

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

fn in_range(p: [f64; 2]) -> bool {
    p[0].abs() <= MAX_COORDINATE && p[1].abs() <= MAX_COORDINATE
}
