use super::predicates::is_finite;
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

/// The kind of a polygon error that names two edges, with the two: (edge, next) of a
/// zero-length edge, (first, second) of a self-intersection or a fold-back; `None` for the
/// other errors.
fn edges_named(err: &GeometryError) -> Option<(&'static str, usize, usize)> {
    match *err {
        GeometryError::PolygonZeroLengthEdge { edge, next, .. } => {
            Some(("zero length", edge, next))
        }
        GeometryError::PolygonSelfIntersection { first, second, .. } => {
            Some(("self-intersection", first, second))
        }
        GeometryError::PolygonFoldsBack { first, second, .. } => {
            Some(("folds back", first, second))
        }
        _ => None,
    }
}

/// [`edges_named`] by the error `validate_polygon` gives for `polygon` (it must give one).
fn polygon_fault(polygon: &[[f64; 2]]) -> Option<(&'static str, usize, usize)> {
    edges_named(&validate_polygon(polygon).expect_err("an invalid polygon"))
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
    assert_eq!(polygon_fault(&closed), Some(("zero length", 3, 0)));
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
    assert_eq!(edges_named(&err), Some(("self-intersection", 0, 2)));
    assert_eq!(
        err.to_string(),
        "geometry.domain.polygon is not a simple polygon: edge 0 (from (0, 0) to (1, 1)) \
         crosses edge 2 (from (1, 0) to (0, 1))"
    );
}

#[test]
fn polygon_vertex_touching_edge() {
    let pinched = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [2.0, 0.0], [0.0, 4.0]];
    assert_eq!(polygon_fault(&pinched), Some(("self-intersection", 0, 2)));
    // Figure eight through a shared vertex.
    let eight = [
        [0.0, 0.0],
        [1.0, 1.0],
        [2.0, 0.0],
        [2.0, 2.0],
        [1.0, 1.0],
        [0.0, 2.0],
    ];
    assert_eq!(
        polygon_fault(&eight).map(|f| f.0),
        Some("self-intersection")
    );
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
    assert_eq!(polygon_fault(&spike_at_start), Some(("folds back", 3, 0)));
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
            // every crack error names its crack (GeometryError::crack), a polygon error none
            match (&err, err.crack()) {
                (GeometryError::CrackNonFinite { crack, .. }, _) => assert!(!finite(*crack)),
                (GeometryError::CracksIntersect { first, second, .. }, Some(c)) => {
                    assert!(c == *first && finite(*first) && finite(*second))
                }
                (_, Some(crack)) => assert!(finite(crack)),
                (other, None) => panic!("unexpected polygon error for a valid square: {other}"),
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Edge cracks (CrackEnds::MayBeMouths, docs/elasticity.md)

fn mouths(polygon: &[[f64; 2]], crack: &[[f64; 2]]) -> Result<(), GeometryError> {
    validate_cracks_with(polygon, &[crack.to_vec()], CrackEnds::MayBeMouths)
}

#[test]
fn an_edge_crack_is_refused_for_the_scalar_problem_with_todays_message() {
    let crack = vec![[-1.0, 0.0], [0.0, 0.0]];
    let expected = GeometryError::CrackPointOnBoundary {
        crack: 0,
        point: 0,
        coords: [-1.0, 0.0],
    };
    for ends in [None, Some(CrackEnds::Inside)] {
        let got = match ends {
            None => validate_cracks(&square(1.0), std::slice::from_ref(&crack)),
            Some(e) => validate_cracks_with(&square(1.0), std::slice::from_ref(&crack), e),
        };
        assert_eq!(got, Err(expected.clone()));
    }
    assert_eq!(
        expected.to_string(),
        "geometry.cracks[0] point 0 (-1, 0) touches the domain boundary"
    );
}

#[test]
fn edge_cracks_with_one_or_two_mouths_are_accepted() {
    let sq = square(1.0);
    assert_eq!(mouths(&sq, &[[-1.0, 0.0], [0.0, 0.0]]), Ok(()));
    assert_eq!(mouths(&sq, &[[0.0, 0.25], [1.0, 0.25]]), Ok(()));
    // through the whole square, and a kinked one with both ends on ∂Ω
    assert_eq!(mouths(&sq, &[[-1.0, 0.5], [1.0, -0.5]]), Ok(()));
    assert_eq!(mouths(&sq, &[[-0.5, -1.0], [0.0, 0.0], [1.0, 0.5]]), Ok(()));
    // oblique on a rotated square, both orientations of the polygon
    let rot = rotated(&sq, 30.0);
    let mid = [0.5 * (rot[0][0] + rot[1][0]), 0.5 * (rot[0][1] + rot[1][1])];
    let mut reversed = rot.clone();
    reversed.reverse();
    for poly in [&rot, &reversed] {
        // the midpoint of an edge may round off ∂Ω: accept it only where it is exactly on it
        if point_in_polygon(mid, poly) == Inside::OnBoundary {
            assert_eq!(mouths(poly, &[mid, [0.0, 0.0]]), Ok(()));
        }
    }
    // the L-shape's re-entrant edges
    assert_eq!(mouths(&L_SHAPE, &[[0.5, 0.0], [0.5, -0.5]]), Ok(()));
    assert_eq!(mouths(&L_SHAPE, &[[0.0, 0.5], [-0.5, 0.5]]), Ok(()));
}

#[test]
fn edge_crack_errors_name_the_broken_requirement() {
    let sq = square(1.0);
    // a corner of Ω
    assert_eq!(
        mouths(&sq, &[[-1.0, -1.0], [0.0, 0.0]]),
        Err(GeometryError::CrackMouthAtCorner {
            crack: 0,
            point: 0,
            coords: [-1.0, -1.0]
        })
    );
    // an interior point of the polyline on ∂Ω
    assert_eq!(
        mouths(&sq, &[[0.0, 0.0], [1.0, 0.0], [0.5, 0.5]]),
        Err(GeometryError::CrackPointOnBoundary {
            crack: 0,
            point: 1,
            coords: [1.0, 0.0]
        })
    );
    // along the boundary edge (the other end on the edge's line, outside the square)
    let e = mouths(&sq, &[[0.5, -1.0], [1.5, -1.0]]).unwrap_err();
    assert!(
        matches!(e, GeometryError::CrackPointOutside { point: 1, .. }),
        "{e}"
    );
    let along = mouths(&L_SHAPE, &[[0.5, 0.0], [-0.5, 0.0]]).unwrap_err();
    assert!(
        matches!(
            along,
            GeometryError::CrackMouthAlongBoundary {
                point: 0,
                edge: 2,
                ..
            }
        ),
        "{along}"
    );
    // a segment from a mouth that crosses ∂Ω: from the L-shape's top edge across the notch
    assert_eq!(
        mouths(&L_SHAPE, &[[-0.5, 1.0], [0.5, -0.5]]),
        Err(GeometryError::CrackCrossesBoundary {
            crack: 0,
            segment: 0,
            edge: 2,
            edge_points: [[1.0, 0.0], [0.0, 0.0]]
        })
    );
    // two mouths joined outside Ω: across the L-shape's missing quadrant
    assert_eq!(
        mouths(&L_SHAPE, &[[0.5, 0.0], [0.0, 0.5]]),
        Err(GeometryError::CrackSegmentOutside {
            crack: 0,
            segment: 0
        })
    );
    // two cracks sharing a mouth
    let two = vec![vec![[-1.0, 0.0], [0.0, 0.0]], vec![[-1.0, 0.0], [0.0, 0.5]]];
    assert!(matches!(
        validate_cracks_with(&sq, &two, CrackEnds::MayBeMouths),
        Err(GeometryError::CracksIntersect { .. })
    ));
    for e in [
        GeometryError::CrackMouthAtCorner {
            crack: 2,
            point: 0,
            coords: [0.0, 0.0],
        },
        GeometryError::CrackSegmentOutside {
            crack: 2,
            segment: 0,
        },
    ] {
        assert_eq!(e.crack(), Some(2));
        assert!(!e.to_string().contains('\n'));
    }
}
