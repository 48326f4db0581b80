//! The elementary predicates on points, segments and polygons: signed area, orientation,
//! point in polygon, segment intersection, with the exact-zero sign tests of the module
//! documentation of [`crate::geometry`].

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

/// The first edge `k` of `polygon` (from vertex k to vertex k + 1) on which `p` lies, by the
/// exact predicates; `None` when `p` is not on ∂Ω.
#[must_use]
pub fn boundary_edge_of(p: [f64; 2], polygon: &[[f64; 2]]) -> Option<usize> {
    edges(polygon)
        .find(|&(_, edge)| on_segment(p, edge))
        .map(|(k, _)| k)
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

// ---------------------------------------------------------------------------------------------
// Elementary helpers

/// Edges of a closed polygon with their indices: edge `k` is `[v_k, v_(k+1) mod n]`.
pub(super) fn edges(polygon: &[[f64; 2]]) -> impl Iterator<Item = (usize, [[f64; 2]; 2])> + '_ {
    let n = polygon.len();
    (0..n).map(move |k| (k, [polygon[k], polygon[(k + 1) % n]]))
}

/// Segments of an open polyline: segment `k` is `[p_k, p_(k+1)]`.
pub(super) fn polyline_segments(points: &[[f64; 2]]) -> impl Iterator<Item = [[f64; 2]; 2]> + '_ {
    points.windows(2).map(|w| [w[0], w[1]])
}

pub(super) fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

pub(super) fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

pub(super) fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// Sign of the turn `a → b → c`: 1 for left (counter-clockwise), -1 for right, 0 for collinear
/// (exact-zero test; NaN also gives 0).
pub(super) fn orientation(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> i32 {
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
pub(super) fn in_box(p: [f64; 2], s: [[f64; 2]; 2]) -> bool {
    (0..2).all(|k| s[0][k].min(s[1][k]) <= p[k] && p[k] <= s[0][k].max(s[1][k]))
}

/// Whether `p` lies on the closed segment `s`.
pub(super) fn on_segment(p: [f64; 2], s: [[f64; 2]; 2]) -> bool {
    orientation(s[0], s[1], p) == 0 && in_box(p, s)
}

/// Whether the consecutive segments `p → v` and `v → q` (both of non-zero length) overlap along
/// more than their shared point `v`, i.e. `q` turns straight back towards `p`.
pub(super) fn folds_back(p: [f64; 2], v: [f64; 2], q: [f64; 2]) -> bool {
    orientation(p, v, q) == 0 && dot(sub(p, v), sub(q, v)) > 0.0
}

/// Winding number of the polygon around `p`, which must not lie on the boundary.
pub(super) fn winding_number(p: [f64; 2], polygon: &[[f64; 2]]) -> i32 {
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

pub(super) fn is_finite(p: [f64; 2]) -> bool {
    p[0].is_finite() && p[1].is_finite()
}
