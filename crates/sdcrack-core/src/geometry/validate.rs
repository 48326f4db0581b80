//! Validation of the domain polygon and of the cracks: each requirement one check, the first
//! broken one reported as a [`GeometryError`].

use super::error::{GeometryError, MAX_COORDINATE};
use super::predicates::{
    edges, folds_back, is_finite, on_segment, orientation, point_in_polygon, polyline_segments,
    segments_intersect, Inside,
};

/// Whether a crack may end on ∂Ω: the switch between the scalar problem (every crack strictly
/// inside Ω) and the elastic one (docs/elasticity.md: an *edge crack*, whose end on ∂Ω is a
/// *mouth*). The scene loader turns it on for elastic scenes only.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum CrackEnds {
    /// Every crack point strictly inside Ω (the scalar problem).
    #[default]
    Inside,
    /// A crack's first and/or last point may lie on ∂Ω, not at a corner of Ω, the crack meeting
    /// ∂Ω transversally there and nowhere else; its other points strictly inside.
    MayBeMouths,
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
    validate_cracks_with(polygon, cracks, CrackEnds::Inside)
}

/// [`validate_cracks`] with the crack ends `ends` allows: with [`CrackEnds::Inside`] exactly
/// [`validate_cracks`]; with [`CrackEnds::MayBeMouths`] a first or last crack point may lie on
/// ∂Ω (a mouth), where it must not be a vertex of the polygon
/// ([`GeometryError::CrackMouthAtCorner`]), the crack's segment there must not run along the
/// domain edge ([`GeometryError::CrackMouthAlongBoundary`]), and no segment may meet ∂Ω
/// anywhere but at its mouths; a segment joining two mouths must run inside Ω
/// ([`GeometryError::CrackSegmentOutside`]).
///
/// # Errors
///
/// As [`validate_cracks`], and the three mouth errors above.
pub fn validate_cracks_with(
    polygon: &[[f64; 2]],
    cracks: &[Vec<[f64; 2]>],
    ends: CrackEnds,
) -> Result<(), GeometryError> {
    validate_polygon(polygon)?;
    for (index, crack) in cracks.iter().enumerate() {
        check_crack_shape(index, crack)?;
        match ends {
            CrackEnds::Inside => check_crack_in_domain(index, crack, polygon)?,
            CrackEnds::MayBeMouths => check_edge_crack_in_domain(index, crack, polygon)?,
        }
    }
    check_cracks_disjoint(cracks)
}

/// The crack tips of a validated geometry in the tips' order of docs/elasticity.md: for each
/// crack its first point, then its last, each unless it lies on ∂Ω (a mouth). The mesh's own
/// [`crate::mesh::Mesh::tips`] lists the same points in the same order.
pub fn crack_tips(polygon: &[[f64; 2]], cracks: &[Vec<[f64; 2]>]) -> Vec<[f64; 2]> {
    cracks
        .iter()
        .filter(|c| !c.is_empty())
        .flat_map(|c| [c[0], c[c.len() - 1]])
        .filter(|&p| point_in_polygon(p, polygon) != Inside::OnBoundary)
        .collect()
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

/// Checks that a crack lies inside the (valid) domain polygon but for its mouths: end points on
/// ∂Ω, each on one edge away from its ends, met transversally by the crack's end segment.
fn check_edge_crack_in_domain(
    crack: usize,
    points: &[[f64; 2]],
    polygon: &[[f64; 2]],
) -> Result<(), GeometryError> {
    let last = points.len() - 1;
    // per point: the domain edge its mouth lies on (ends only)
    let mut mouth_edge: Vec<Option<usize>> = vec![None; points.len()];
    for (point, &coords) in points.iter().enumerate() {
        let where_ = point_in_polygon(coords, polygon);
        let error = |variant: fn(usize, usize, [f64; 2]) -> GeometryError| {
            Err(variant(crack, point, coords))
        };
        match where_ {
            Inside::Inside => {}
            Inside::Outside => return error(point_outside),
            Inside::OnBoundary if point != 0 && point != last => return error(point_on_boundary),
            Inside::OnBoundary => {
                if polygon.contains(&coords) {
                    return error(mouth_at_corner);
                }
                // not a vertex: on exactly one edge, away from its ends
                mouth_edge[point] = edges(polygon)
                    .find(|&(_, e)| on_segment(coords, e))
                    .map(|(edge, _)| edge);
            }
        }
    }
    for (segment, s) in polyline_segments(points).enumerate() {
        let ends = [segment, segment + 1];
        for end in ends {
            if let Some(edge) = mouth_edge[end] {
                let [a, b] = edges(polygon).nth(edge).map(|(_, e)| e).unwrap_or_default();
                let other = points[if end == segment { segment + 1 } else { segment }];
                if orientation(a, b, other) == 0 {
                    return Err(GeometryError::CrackMouthAlongBoundary {
                        crack,
                        point: end,
                        coords: points[end],
                        edge,
                    });
                }
            }
        }
        // a transversal end segment meets its mouth's edge at the mouth only: that edge is
        // allowed, every other edge must stay clear of the segment
        let allowed = |edge: usize| ends.iter().any(|&p| mouth_edge[p] == Some(edge));
        let hit = edges(polygon).find(|&(edge, e)| !allowed(edge) && segments_intersect(s, e));
        if let Some((edge, edge_points)) = hit {
            return Err(GeometryError::CrackCrossesBoundary {
                crack,
                segment,
                edge,
                edge_points,
            });
        }
        if ends.iter().all(|&p| mouth_edge[p].is_some()) {
            // both ends on ∂Ω and no other contact: the open segment is wholly inside or
            // wholly outside Ω; its midpoint tells which
            let mid = [0.5 * (s[0][0] + s[1][0]), 0.5 * (s[0][1] + s[1][1])];
            if point_in_polygon(mid, polygon) != Inside::Inside {
                return Err(GeometryError::CrackSegmentOutside { crack, segment });
            }
        }
    }
    Ok(())
}

fn point_outside(crack: usize, point: usize, coords: [f64; 2]) -> GeometryError {
    GeometryError::CrackPointOutside {
        crack,
        point,
        coords,
    }
}

fn point_on_boundary(crack: usize, point: usize, coords: [f64; 2]) -> GeometryError {
    GeometryError::CrackPointOnBoundary {
        crack,
        point,
        coords,
    }
}

fn mouth_at_corner(crack: usize, point: usize, coords: [f64; 2]) -> GeometryError {
    GeometryError::CrackMouthAtCorner {
        crack,
        point,
        coords,
    }
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
