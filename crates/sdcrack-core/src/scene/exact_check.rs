//! The common ground of the exact-data checks, scalar ([`super::exact_data`]) and elastic
//! ([`super::elastic_exact_data`]): where they sample, the tolerance a sampled comparison is
//! judged to, the one-sided limits on the crack faces, and the error they report. The reasoning
//! behind the constants is stated once, in [`super::exact_data`]'s module documentation; both
//! checks follow it.

use super::key_path::KeyPath;
use crate::geometry::{point_in_polygon, Inside};
use crate::problem::{Domain, Polyline};

/// Grid points per direction over Ω's bounding box.
pub const GRID: usize = 20;
/// Offset of the grid points within their cells, as a fraction of a cell: 2 − φ (φ the golden
/// ratio), irrational, so that the points miss the lines x, y = simple fractions of the box.
pub const GRID_OFFSET: f64 = 0.381_966_011_250_105;
/// Samples per crack segment: the points at k/CRACK_SAMPLES of it, 0 < k < CRACK_SAMPLES.
pub const CRACK_SAMPLES: usize = 8;
/// Distance of the near-crack points from the crack, relative to the segment's length.
pub const NEAR_CRACK: f64 = 1e-3;
/// Samples per edge of ∂Ω (at (k + GRID_OFFSET)/BOUNDARY_SAMPLES of the edge).
pub const BOUNDARY_SAMPLES: usize = 12;
/// The larger step ε of the one-sided limits, relative to the segment's length.
pub const LIMIT_STEP: f64 = 1e-4;
/// Margin on the first-order round-off bounds.
pub const ROUNDOFF_SAFETY: f64 = 4.0;
/// Margin on the Richardson truncation estimate of a one-sided limit.
pub const TRUNCATION_SAFETY: f64 = 4.0;

/// A value with the tolerance it is known to: round-off bound plus truncation estimate.
#[derive(Clone, Copy, Debug)]
pub(super) struct Known {
    pub(super) value: f64,
    /// What the value may be off by: ROUNDOFF_SAFETY × round-off + TRUNCATION_SAFETY × truncation.
    pub(super) tolerance: f64,
}

impl Known {
    /// A value and its first-order round-off bound ([`crate::expr::Expr::eval_bounded`]).
    pub(super) fn bounded((value, roundoff): (f64, f64)) -> Known {
        Known {
            value,
            tolerance: ROUNDOFF_SAFETY * roundoff,
        }
    }

    /// `self − other`, known to the sum of both tolerances (the subtraction's own rounding is
    /// below either value's ulp and inside the margin of 4).
    pub(super) fn minus(self, other: Known) -> Known {
        Known {
            value: self.value - other.value,
            tolerance: self.tolerance + other.tolerance,
        }
    }

    fn judgeable(self) -> bool {
        self.value.is_finite() && self.tolerance.is_finite()
    }

    /// Certainly different from `other` (both judgeable, apart by more than both tolerances).
    pub(super) fn differs(self, other: Known) -> bool {
        self.judgeable()
            && other.judgeable()
            && (self.value - other.value).abs() > self.tolerance + other.tolerance
    }

    /// Certainly not zero (judgeable, farther from 0 than its tolerance).
    pub(super) fn certainly_nonzero(self) -> bool {
        self.judgeable() && self.value.abs() > self.tolerance
    }

    pub(super) fn certainly_positive(self) -> bool {
        self.judgeable() && self.value > self.tolerance
    }

    pub(super) fn certainly_negative(self) -> bool {
        self.judgeable() && self.value < -self.tolerance
    }
}

/// Σ cᵢ·vᵢ of values vᵢ with round-off bounds eᵢ (coefficients cᵢ exact), with its first-order
/// round-off bound Σ |cᵢ| eᵢ + n·ε·Σ |cᵢ vᵢ|: each of the n products and n − 1 additions rounds
/// by at most ε/2 of a partial result, each of which is at most Σ |cᵢ vᵢ|.
pub(super) fn combination(terms: &[(f64, (f64, f64))]) -> (f64, f64) {
    let value = terms.iter().map(|&(c, (v, _))| c * v).sum::<f64>();
    let propagated = (terms.iter())
        .map(|&(c, (_, e))| if e == 0.0 { 0.0 } else { c.abs() * e })
        .sum::<f64>();
    let size = terms.iter().map(|&(c, (v, _))| (c * v).abs()).sum::<f64>();
    (value, propagated + terms.len() as f64 * f64::EPSILON * size)
}

/// A number as the messages print it: six significant digits.
pub(super) fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&v.abs()) {
        let s = format!("{v:.6}");
        let s = if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        };
        if s == "-0" {
            "0".into()
        } else {
            s
        }
    } else {
        format!("{v:.5e}")
    }
}

/// A point or a vector as the messages print it: `(x, y)`.
pub(super) fn at(p: [f64; 2]) -> String {
    format!("({}, {})", num(p[0]), num(p[1]))
}

/// One point of a crack: where it is, the normal ν of its segment and the segment's length.
pub(super) struct CrackPoint {
    pub(super) p: [f64; 2],
    pub(super) normal: [f64; 2],
    pub(super) length: f64,
}

/// The points k/CRACK_SAMPLES along every crack segment, 0 < k < CRACK_SAMPLES: never a crack
/// end (a tip or a mouth) nor a kink, where u may be singular.
pub(super) fn crack_points(cracks: &[Polyline]) -> Vec<CrackPoint> {
    let mut out = Vec::new();
    for crack in cracks {
        for k in 0..crack.segments() {
            let s = crack.segment(k);
            for i in 1..CRACK_SAMPLES {
                let t = i as f64 / CRACK_SAMPLES as f64;
                out.push(CrackPoint {
                    p: [
                        s.a[0] + t * (s.b[0] - s.a[0]),
                        s.a[1] + t * (s.b[1] - s.a[1]),
                    ],
                    normal: s.normal(),
                    length: s.length(),
                });
            }
        }
    }
    out
}

/// The grid points inside Ω, then the points beside every crack on both faces.
pub(super) fn interior_points(domain: &Domain, cracks: &[Polyline]) -> Vec<[f64; 2]> {
    let polygon = domain.polygon();
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for v in &polygon {
        for d in 0..2 {
            lo[d] = lo[d].min(v[d]);
            hi[d] = hi[d].max(v[d]);
        }
    }
    let mut out = Vec::new();
    for i in 0..GRID {
        for j in 0..GRID {
            let p = [
                lo[0] + (i as f64 + GRID_OFFSET) / GRID as f64 * (hi[0] - lo[0]),
                lo[1] + (j as f64 + GRID_OFFSET) / GRID as f64 * (hi[1] - lo[1]),
            ];
            if point_in_polygon(p, &polygon) == Inside::Inside {
                out.push(p);
            }
        }
    }
    for c in crack_points(cracks) {
        for side in [1.0, -1.0] {
            let d = side * NEAR_CRACK * c.length;
            out.push([c.p[0] + d * c.normal[0], c.p[1] + d * c.normal[1]]);
        }
    }
    out
}

/// The samples of the edge a → b of ∂Ω: at (k + GRID_OFFSET)/BOUNDARY_SAMPLES of it, never an
/// end.
pub(super) fn edge_points(a: [f64; 2], b: [f64; 2]) -> Vec<[f64; 2]> {
    (0..BOUNDARY_SAMPLES)
        .map(|i| {
            let t = (i as f64 + GRID_OFFSET) / BOUNDARY_SAMPLES as f64;
            [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]
        })
        .collect()
}

/// The samples of every edge of ∂Ω ([`edge_points`]), edge by edge.
pub(super) fn boundary_points(domain: &Domain) -> Vec<[f64; 2]> {
    let polygon = domain.polygon();
    (0..polygon.len())
        .flat_map(|k| edge_points(polygon[k], polygon[(k + 1) % polygon.len()]))
        .collect()
}

/// The limit of `e` at the crack point `c` from the face `side` (+1: the side ν points into),
/// extrapolated from c + side·ε·ν at ε and ε/2 (see [`super::exact_data`]'s module docs).
pub(super) fn one_sided(e: &dyn Fn([f64; 2]) -> (f64, f64), c: &CrackPoint, side: f64) -> Known {
    let sample = |eps: f64| {
        let d = side * eps;
        e([c.p[0] + d * c.normal[0], c.p[1] + d * c.normal[1]])
    };
    let eps = LIMIT_STEP * c.length;
    let (a1, e1) = sample(eps);
    let (a2, e2) = sample(eps / 2.0);
    Known {
        value: 2.0 * a2 - a1,
        tolerance: ROUNDOFF_SAFETY * (2.0 * e2 + e1) + TRUNCATION_SAFETY * (a1 - a2).abs(),
    }
}

/// `+` or `−`, the face `side` names in messages.
pub(super) fn face_name(side: f64) -> &'static str {
    if side > 0.0 {
        "+"
    } else {
        "−"
    }
}

/// Exact data that is not a solution of the scene's problem: the key it is about and one line
/// naming that key first (`exact.px is not ∂u/∂x: …`), the values and the point.
#[derive(Clone, Debug, PartialEq)]
pub struct ExactDataError {
    /// The key the message is about (`exact.px`, `data.f`, …).
    pub key: KeyPath,
    /// The message, naming the key first.
    pub message: String,
}

impl ExactDataError {
    /// The error about the key `dotted` (`exact.px`), with its message.
    pub(super) fn new(dotted: &str, message: String) -> ExactDataError {
        ExactDataError::at_key(KeyPath::keys(dotted), message)
    }

    /// The error about the key `key` (which may carry an index: `data.fixed\[1\]`).
    pub(super) fn at_key(key: KeyPath, message: String) -> ExactDataError {
        ExactDataError { key, message }
    }
}

impl std::fmt::Display for ExactDataError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}
