//! The elastic problem kind's data (issue 45): a 2-D linear elastic body Ω \ Γc whose crack faces
//! may open, slide or press on each other without friction,
//!
//! ```text
//!     −div σ(u) = f in Ω \ Γc,   σ(u) = λ tr ε(u) I + 2μ ε(u),
//!     u = g on the Dirichlet parts of ∂Ω,   σn = t on the traction parts,
//!     [u·ν] ≥ 0,  σ_νν ≤ 0,  σ_νν [u·ν] = 0,  σ_ντ = 0,  [σν] = 0   on Γc,
//! ```
//!
//! with [v] = v⁺ − v⁻ and ν the crack's normal pointing into its + face (docs/scenes.md).
//! This module owns the material ([`Material`]: plane strain or plane stress, from (E, ν) or
//! (λ, μ)), the loads ([`ElasticData`]: f, g, the tractions on named boundary parts, the fixed
//! points that remove rigid modes) and the exact fields ([`ElasticExact`]). The scene parser
//! (sdcrack-io) reads and validates them; the maths (references, compare tool, and the
//! smooth-domain solver of issue 46) take them from here.

use crate::expr::{Expr, Var};
use crate::problem::Domain;

/// Plane strain (ε_zz = 0) or plane stress (σ_zz = 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum PlaneModel {
    /// ε_zz = 0: the in-plane law with the 3-D Lamé constants.
    #[default]
    Strain,
    /// σ_zz = 0: the in-plane law with λ* = 2λμ/(λ + 2μ).
    Stress,
}

crate::scene_names!(PlaneModel { Strain => "strain", Stress => "stress" });

/// An isotropic material in the plane: the 3-D Lamé constants and the plane model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// The 3-D first Lamé constant λ.
    pub lambda: f64,
    /// The shear modulus μ > 0.
    pub mu: f64,
    /// Plane strain or plane stress.
    pub plane: PlaneModel,
}

impl Material {
    /// The material of Young's modulus E and Poisson's ratio ν:
    /// λ = Eν/((1 + ν)(1 − 2ν)), μ = E/(2(1 + ν)).
    pub fn from_young_poisson(e: f64, nu: f64, plane: PlaneModel) -> Material {
        Material {
            lambda: e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            mu: e / (2.0 * (1.0 + nu)),
            plane,
        }
    }

    /// The λ of the in-plane law σ = λ_in tr ε I + 2μ ε: λ in plane strain, 2λμ/(λ + 2μ) in
    /// plane stress.
    pub fn lambda_in_plane(&self) -> f64 {
        match self.plane {
            PlaneModel::Strain => self.lambda,
            PlaneModel::Stress => 2.0 * self.lambda * self.mu / (self.lambda + 2.0 * self.mu),
        }
    }

    /// Poisson's ratio ν = λ/(2(λ + μ)) of the 3-D constants.
    pub fn poisson(&self) -> f64 {
        self.lambda / (2.0 * (self.lambda + self.mu))
    }

    /// Young's modulus E = 2μ(1 + ν).
    pub fn young(&self) -> f64 {
        2.0 * self.mu * (1.0 + self.poisson())
    }

    /// Kolosov's constant κ: 3 − 4ν in plane strain, (3 − ν)/(1 + ν) in plane stress.
    pub fn kolosov(&self) -> f64 {
        let nu = self.poisson();
        match self.plane {
            PlaneModel::Strain => 3.0 - 4.0 * nu,
            PlaneModel::Stress => (3.0 - nu) / (1.0 + nu),
        }
    }

    /// E′ of Irwin's relation G = K²/E′: E/(1 − ν²) in plane strain, E in plane stress.
    pub fn e_prime(&self) -> f64 {
        let (nu, e) = (self.poisson(), self.young());
        match self.plane {
            PlaneModel::Strain => e / (1.0 - nu * nu),
            PlaneModel::Stress => e,
        }
    }
}

/// A named part of ∂Ω: a side of a rectangle (`left`, `right`, `bottom`, `top`) or an edge of a
/// polygon (`edge1` … `edgeN`, edge k from vertex k to vertex k + 1, 1-based, the last one back to
/// the first vertex).
#[derive(Clone, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct BoundaryPart(pub String);

/// A traction t = σn prescribed on a boundary part (n the outward normal of Ω).
#[derive(Clone, Debug)]
pub struct Traction {
    /// The part of ∂Ω it acts on.
    pub part: BoundaryPart,
    /// t_x, t_y as expressions of (x, y).
    pub t: [Expr; 2],
}

/// Displacement components held at zero at a corner of Ω (removes rigid modes where the
/// boundary is all traction).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedPoint {
    /// The corner of Ω (a mesh vertex on every level).
    pub point: [f64; 2],
    /// Which components are held: `[u_x, u_y]`.
    pub components: [bool; 2],
}

/// A displacement component, as `data.fixed`'s `components` name it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Component {
    /// u_x.
    X,
    /// u_y.
    Y,
}

crate::scene_names!(Component { X => "x", Y => "y" });

/// How many of the three rigid modes of the plane, (1, 0), (0, 1) and (−y, x), the fixed
/// components `fixed` remove: the rank of the rows (1, 0, −y) (u_x held at (x, y)) and
/// (0, 1, x) (u_y held), the modes' values in the held components. Every 3 × 3 minor of these
/// rows is a difference of corner coordinates (or zero), so a minor is zero exactly when the
/// corners make it so; the threshold `1e-12 · max(1, |x|, |y|)` only keeps round-off of the
/// determinant (a few units of the coordinates' last place) from counting.
pub fn rigid_modes_removed(fixed: &[FixedPoint]) -> usize {
    let rows: Vec<[f64; 3]> = (fixed.iter())
        .flat_map(|f| {
            let [x, y] = f.point;
            [
                (f.components[0], [1.0, 0.0, -y]),
                (f.components[1], [0.0, 1.0, x]),
            ]
        })
        .filter_map(|(held, row)| held.then_some(row))
        .collect();
    let scale = rows.iter().map(|r| r[2].abs()).fold(1.0, f64::max);
    let tol = 1e-12 * scale;
    let nonzero_row = rows.iter().any(|r| r.iter().any(|v| v.abs() > tol));
    let cross = |a: &[f64; 3], b: &[f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let mut rank2 = false;
    for (i, a) in rows.iter().enumerate() {
        for b in &rows[i + 1..] {
            let n = cross(a, b);
            if n.iter().any(|v| v.abs() > tol) {
                rank2 = true;
                let det = |c: &[f64; 3]| n[0] * c[0] + n[1] * c[1] + n[2] * c[2];
                if rows.iter().any(|c| det(c).abs() > tol) {
                    return 3;
                }
            }
        }
    }
    usize::from(nonzero_row) + usize::from(rank2)
}

/// A stress intensity factor pair at one crack tip, in the tip's frame (docs/scenes.md: e₁ points
/// ahead of the tip, out of the crack; e₂ is e₁ turned by +90°).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TipSif {
    /// Mode I, K_I.
    pub k1: f64,
    /// Mode II, K_II.
    pub k2: f64,
}

/// The exact fields of an elastic scene.
#[derive(Clone, Debug)]
pub struct ElasticExact {
    /// u_x, u_y.
    pub u: [Expr; 2],
    /// σ_xx, σ_yy, σ_xy (given, or Hooke's law of the symbolic derivatives of u).
    pub stress: [Expr; 3],
    /// [u·ν] on Γc, when given (otherwise from u on each face).
    pub opening: Option<Expr>,
    /// [u·τ] on Γc (τ = ν turned by −90°, the crack's direction), when given.
    pub slip: Option<Expr>,
    /// The contact pressure −σ_νν on Γc, when given (otherwise from the stress).
    pub pressure: Option<Expr>,
    /// (K_I, K_II) per crack tip, in the tips' order (each crack's first-point tip, then its
    /// last-point tip; a crack end on ∂Ω is a mouth, not a tip). Empty when not given.
    pub sif: Vec<TipSif>,
}

/// The data of an elastic scene.
#[derive(Clone, Debug)]
pub struct ElasticData {
    /// The material.
    pub material: Material,
    /// f_x, f_y.
    pub f: [Expr; 2],
    /// g_x, g_y on every boundary part without a traction (`None` when every part has one).
    pub g: Option<[Expr; 2]>,
    /// The tractions, one per part that has one.
    pub tractions: Vec<Traction>,
    /// Fixed points (only with an all-traction boundary).
    pub fixed: Vec<FixedPoint>,
    /// The exact fields, if the scene has them.
    pub exact: Option<ElasticExact>,
}

/// Hooke's law of the symbolic derivatives of u: (σ_xx, σ_yy, σ_xy) with
/// σ = λ_in tr ε(u) I + 2μ ε(u) ([`Material::lambda_in_plane`]). Built as text from the
/// derivatives' infix forms and parsed back (the expression language has no combinators), so the
/// result prints as a scene expression. Fails (the parser's [`crate::expr::ExprError`]) when
/// the text outgrows the expression language's limits on length and nesting: a long u should
/// then come with its stress given.
pub fn hooke_stress(u: &[Expr; 2], m: &Material) -> Result<[Expr; 3], crate::expr::ExprError> {
    let d = |c: usize, v: Var| format!("({})", u[c].derivative(v).to_string_infix());
    let (ux_x, uy_y) = (d(0, Var::X), d(1, Var::Y));
    let (ux_y, uy_x) = (d(0, Var::Y), d(1, Var::X));
    let (lam, mu) = (m.lambda_in_plane(), m.mu);
    let trace = format!("{lam} * ({ux_x} + {uy_y})");
    let texts = [
        format!("{trace} + 2 * {mu} * {ux_x}"),
        format!("{trace} + 2 * {mu} * {uy_y}"),
        format!("{mu} * ({ux_y} + {uy_x})"),
    ];
    let [xx, yy, xy] = texts;
    Ok([Expr::parse(&xx)?, Expr::parse(&yy)?, Expr::parse(&xy)?])
}

/// The part that is all of ∂Ω: the only part of a `[discretization] mesh` scene.
pub const WHOLE_BOUNDARY: &str = "boundary";

/// One edge of ∂Ω, a → b with Ω on its left, and the part it belongs to.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryEdge {
    /// The part: `left`, `right`, `bottom`, `top` or `edge1` … `edgeN`.
    pub part: BoundaryPart,
    /// First end (counter-clockwise order).
    pub a: [f64; 2],
    /// Second end.
    pub b: [f64; 2],
}

impl BoundaryEdge {
    /// The outward unit normal n of Ω on this edge: the direction a → b turned by −90°.
    pub fn outward_normal(&self) -> [f64; 2] {
        let (dx, dy) = (self.b[0] - self.a[0], self.b[1] - self.a[1]);
        let l = dx.hypot(dy);
        [dy / l, -dx / l]
    }

    /// True when the traction or Dirichlet datum of the part `part` acts on this edge: `part` is
    /// the edge's own part or [`WHOLE_BOUNDARY`].
    pub fn belongs_to(&self, part: &BoundaryPart) -> bool {
        *part == self.part || part.0 == WHOLE_BOUNDARY
    }
}

/// The edges of ∂Ω in [`Domain::polygon`]'s counter-clockwise order, each with its part: a
/// rectangle's `bottom`, `right`, `top`, `left`; a polygon's `edge1` … `edgeN`, edge k from the
/// k-th vertex of the polygon as stored (counter-clockwise from the scene's first vertex: a
/// polygon written clockwise is stored with its other vertices reversed) to the next.
pub fn boundary_edges(domain: &Domain) -> Vec<BoundaryEdge> {
    let polygon = domain.polygon();
    let parts = crate::mesh::BoundaryParts::of_domain(domain);
    (0..polygon.len())
        .map(|k| {
            let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
            let middle = [0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1])];
            let name = &parts.names()[parts.part_at(middle)];
            BoundaryEdge {
                part: BoundaryPart(name.clone()),
                a,
                b,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crack_ends_on_the_boundary_are_mouths_not_tips() {
        use crate::geometry::crack_tips;
        let square = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
        let interior = vec![[-0.5, 0.0], [0.5, 0.0]];
        let edge = vec![[-1.0, 0.0], [0.0, 0.0]];
        let through = vec![[0.0, -1.0], [0.0, -0.5], [0.5, 1.0]];
        assert_eq!(
            crack_tips(&square, std::slice::from_ref(&interior)).len(),
            2
        );
        assert_eq!(
            crack_tips(&square, &[edge, interior]),
            [[0.0, 0.0], [-0.5, 0.0], [0.5, 0.0]]
        );
        assert!(crack_tips(&square, &[through]).is_empty());
    }

    #[test]
    fn rigid_modes_of_fixed_corners() {
        let at = |point, x, y| FixedPoint {
            point,
            components: [x, y],
        };
        // both components at one corner: the translations, not the rotation about it
        assert_eq!(rigid_modes_removed(&[at([1.0, -1.0], true, true)]), 2);
        // and u_x at a corner above it: the rotation too
        let three = [at([1.0, -1.0], true, true), at([1.0, 1.0], true, false)];
        assert_eq!(rigid_modes_removed(&three), 3);
        // u_y at a corner above it: (0, 1, x) twice with the same x, still two
        let same_x = [at([1.0, -1.0], true, true), at([1.0, 1.0], false, true)];
        assert_eq!(rigid_modes_removed(&same_x), 2);
        // u_x at two corners: one translation and the rotation
        let xs = [at([1.0, -1.0], true, false), at([1.0, 1.0], true, false)];
        assert_eq!(rigid_modes_removed(&xs), 2);
        assert_eq!(rigid_modes_removed(&[]), 0);
        assert_eq!(rigid_modes_removed(&[at([0.0, 0.0], true, false)]), 1);
    }

    #[test]
    fn young_poisson_round_trip_and_constants() {
        let m = Material::from_young_poisson(1.0, 0.3, PlaneModel::Strain);
        assert!((m.poisson() - 0.3).abs() < 1e-15);
        assert!((m.kolosov() - 1.8).abs() < 1e-15);
        assert!((m.e_prime() - 1.0 / 0.91).abs() < 1e-14);
        let s = Material {
            plane: PlaneModel::Stress,
            ..m
        };
        assert!((s.kolosov() - 2.7 / 1.3).abs() < 1e-14);
        // Plane stress: λ* = 2λμ/(λ + 2μ) = Eν/(1 − ν²).
        assert!((s.lambda_in_plane() - 0.3 / 0.91).abs() < 1e-14);
    }

    #[test]
    fn hooke_stress_of_a_quadratic_field() {
        // u = (x² y, x − y²): ε_xx = 2xy, ε_yy = −2y, ε_xy = (x² + 1)/2.
        let u = [
            Expr::parse("x^2*y").unwrap(),
            Expr::parse("x - y^2").unwrap(),
        ];
        let m = Material {
            lambda: 2.0,
            mu: 0.5,
            plane: PlaneModel::Strain,
        };
        let [sxx, syy, sxy] = hooke_stress(&u, &m).unwrap();
        let (x, y) = (0.3, -0.7);
        let tr = 2.0 * x * y - 2.0 * y;
        assert!((sxx.eval(x, y) - (2.0 * tr + 2.0 * x * y)).abs() < 1e-14);
        assert!((syy.eval(x, y) - (2.0 * tr - 2.0 * y)).abs() < 1e-14);
        assert!((sxy.eval(x, y) - 0.5 * (x * x + 1.0)).abs() < 1e-14);
    }

    #[test]
    fn a_rectangles_sides_and_a_polygons_edges_with_their_outward_normals() {
        let r = Domain::Rectangle(crate::problem::Rectangle {
            min: [-1.0, -2.0],
            max: [3.0, 4.0],
        });
        let edges = boundary_edges(&r);
        let seen: Vec<_> = (edges.iter())
            .map(|e| (e.part.0.as_str(), e.outward_normal()))
            .collect();
        assert_eq!(
            seen,
            [
                ("bottom", [0.0, -1.0]),
                ("right", [1.0, 0.0]),
                ("top", [0.0, 1.0]),
                ("left", [-1.0, 0.0]),
            ]
        );
        assert_eq!((edges[3].a, edges[3].b), ([-1.0, 4.0], [-1.0, -2.0]));
        let whole = BoundaryPart(WHOLE_BOUNDARY.into());
        assert!(edges.iter().all(|e| e.belongs_to(&whole)));
        assert!(!edges[0].belongs_to(&BoundaryPart("top".into())));
        let triangle = Domain::Polygon(vec![[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]]);
        let edges = boundary_edges(&triangle);
        assert_eq!(edges[1].part, BoundaryPart("edge2".into()));
        let n = edges[1].outward_normal();
        assert!((n[0] - 0.5f64.sqrt()).abs() < 1e-15 && (n[1] - 0.5f64.sqrt()).abs() < 1e-15);
    }
}
