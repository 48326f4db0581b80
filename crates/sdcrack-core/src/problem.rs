//! The problem's vocabulary, shared by the scene parser and the maths modules: the domain Ω
//! ([`Domain`]: a [`Rectangle`] or a polygon), the cracks Γc ([`Polyline`]s of [`Segment`]s, each
//! with its normal ν and faces), how the level-0 mesh is made ([`Meshing`]), the exact solution
//! ([`Exact`]) and the discrete choices of a case: the u space ([`USpace`]), the multiplier cone
//! ([`MultiplierSpace`], paper (12)–(14)) and the p–p block ([`PMass`]). The maths modules
//! (mesh, assembly, norms, …) import these from here; the scene parser (sdcrack-io's `scene`,
//! which this crate cannot see) owns the TOML format and its validation and re-exports them for
//! its users.

use crate::expr::Expr;

/// A vocabulary: a type whose values are named ([`scene_names!`] implements it), so that code
/// can parse, list and suggest names of any of them.
pub trait Named: Copy + 'static {
    /// Every name, in the canonical order.
    const NAMES: &'static [&'static str];
    /// The name of this value.
    fn name(self) -> &'static str;
    /// The value of a name (`None` for any other text, case-sensitive).
    fn from_name(s: &str) -> Option<Self>;
}

/// Gives a fieldless enum its names in scene files, the CLI and result files, one table for
/// both directions: `name()` (variant → name), `from_name()` (name → variant, `None` for any
/// other text, case-sensitive) and `Display` (the name). Written `scene_names!(Type { Variant =>
/// "name", … })`; exported so that the io crate's enums can take their names the same way.
/// The same table gives serde's `Serialize` (the name, a JSON string) and `Deserialize` (the
/// name back; any other text is an unknown variant): the results files' case axes (the crate
/// using the macro must depend on serde). It is the vocabulary's one declaration: `ALL` (every
/// variant, in the table's order) and `NAMES` (their names) are what the scene schema, the
/// validation messages and `sdcrack schema` list.
#[macro_export]
macro_rules! scene_names {
    ($ty:ident { $($variant:ident => $name:expr),+ $(,)? }) => {
        impl $ty {
            /// Every variant, in the order of its names.
            pub const ALL: [$ty; [$($name),+].len()] = [$($ty::$variant),+];
            /// The names of [`Self::ALL`], in that order.
            pub const NAMES: &'static [&'static str] = &[$($name),+];
            /// Name used in scene files, the CLI and result files.
            pub fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name,)+
                }
            }
            /// Parses a scene/CLI name.
            pub fn from_name(s: &str) -> Option<$ty> {
                $ty::ALL.into_iter().find(|v| v.name() == s)
            }
        }

        impl $crate::problem::Named for $ty {
            const NAMES: &'static [&'static str] = $ty::NAMES;
            fn name(self) -> &'static str {
                $ty::name(self)
            }
            fn from_name(s: &str) -> Option<$ty> {
                $ty::from_name(s)
            }
        }

        impl ::std::fmt::Display for $ty {
            fn fmt(&self, f: &mut ::std::fmt::Formatter<'_>) -> ::std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl ::serde::Serialize for $ty {
            fn serialize<S: ::serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
                s.serialize_str(self.name())
            }
        }

        impl<'de> ::serde::Deserialize<'de> for $ty {
            fn deserialize<D: ::serde::Deserializer<'de>>(d: D) -> Result<$ty, D::Error> {
                let name = <String as ::serde::Deserialize>::deserialize(d)?;
                $ty::from_name(&name).ok_or_else(|| {
                    <D::Error as ::serde::de::Error>::unknown_variant(&name, $ty::NAMES)
                })
            }
        }
    };
}

/// How u is discretised (docs/design.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum USpace {
    /// Continuous P1 on the uncracked mesh (the paper's §3 literally).
    Continuous,
    /// P1 on each side of the crack: interior crack vertices carry one u value per face.
    Broken,
}

/// The discrete multiplier cone on the crack (paper (12)–(14)).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MultiplierSpace {
    /// P0 per crack segment, Λ_k ≥ 0, ∫_{t_k} p·ν ≤ 0 (paper (12)).
    M0,
    /// Continuous P1, nodal Λ_j ≥ 0, hat-weighted ∫ φ_j p·ν ≤ 0 (paper (13)).
    M1,
    /// Continuous P1 in the dual cone ∫ λ φ_j ≥ 0, nodal p·ν(x_j) ≤ 0 (paper (14)).
    M1Star,
}

/// The space of p = ∇u (docs/design.md, The p spaces): the paper's continuous MINI field, or
/// one whose tangential component may jump across the crack.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PSpace {
    /// The paper's X_h: continuous vector P1 ⊕ bubble on Ω (the default: a scene that lists no
    /// p space, a summary written before the axis).
    #[default]
    Continuous,
    /// X_h with the tangential component doubled at every interior crack vertex where the crack
    /// is straight: p·ν shared, p·τ one value per face; shared at tips and kinks. Still in
    /// H(div, Ω) (q·ν is one linear function on each crack edge). Runs with broken u only.
    BrokenTangential,
}

scene_names!(PSpace {
    Continuous => "continuous",
    BrokenTangential => "broken-tangential",
});

impl PSpace {
    /// Whether this p space can run with `u_space`: a p whose tangential part jumps needs a u
    /// that may jump (a continuous u cannot open the crack, docs/design.md).
    pub fn serves(self, u_space: USpace) -> bool {
        !(self == PSpace::BrokenTangential && u_space == USpace::Continuous)
    }
}

/// The p–p block of the condensed system: the paper's consistent MINI mass, or its
/// row-sum diagonal, which lets p be eliminated exactly (docs/design.md, The lumped p mass).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PMass {
    /// G̃ = the P1 vector mass after the bubble condensation, M_T − (7|T|/90) 1 1ᵀ per element.
    #[default]
    Consistent,
    /// D = the row sums of G̃, 0.1 Σ_{T∋i} |T| per component: p is the recovered gradient
    /// D⁻¹(G_Γ − B̃ᵀU − contact term), P1 without bubble.
    Lumped,
}

scene_names!(PMass {
    Consistent => "consistent",
    Lumped => "lumped",
});

scene_names!(USpace {
    Continuous => "continuous",
    Broken => "broken",
});

scene_names!(MultiplierSpace {
    M0 => "M0",
    M1 => "M1",
    M1Star => "M1star",
});

/// Axis-aligned rectangle Ω = [x0, x1] × [y0, y1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rectangle {
    /// Lower-left corner.
    pub min: [f64; 2],
    /// Upper-right corner.
    pub max: [f64; 2],
}

/// The domain Ω: an axis-aligned rectangle or a simple polygon.
#[derive(Clone, Debug, PartialEq)]
pub enum Domain {
    /// Ω = [x0, x1] × [y0, y1].
    Rectangle(Rectangle),
    /// A simple polygon, vertices counter-clockwise (the scene parser orients it), first vertex
    /// not repeated.
    Polygon(Vec<[f64; 2]>),
}

impl Domain {
    /// The boundary polygon, counter-clockwise (a rectangle's four corners from the lower left).
    pub fn polygon(&self) -> Vec<[f64; 2]> {
        match self {
            Domain::Rectangle(r) => vec![r.min, [r.max[0], r.min[1]], r.max, [r.min[0], r.max[1]]],
            Domain::Polygon(p) => p.clone(),
        }
    }
}

/// A crack Γc as a polyline x_0, …, x_n (n ≥ 1 segments); a straight crack is a polyline of two
/// points. Segment k runs from x_k to x_{k+1}; its normal ν_k is that direction turned by +90°,
/// and its + face is the side ν_k points into (docs/scenes.md).
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    /// The points x_0 (first tip), …, x_n (last tip).
    pub points: Vec<[f64; 2]>,
}

impl Polyline {
    /// Number of segments n.
    pub fn segments(&self) -> usize {
        self.points.len() - 1
    }
    /// Segment k as a [`Segment`].
    pub fn segment(&self, k: usize) -> Segment {
        Segment {
            a: self.points[k],
            b: self.points[k + 1],
        }
    }
    /// Total length Σ |x_{k+1} − x_k|.
    pub fn length(&self) -> f64 {
        (0..self.segments()).map(|k| self.segment(k).length()).sum()
    }
}

impl From<Segment> for Polyline {
    fn from(s: Segment) -> Polyline {
        Polyline {
            points: vec![s.a, s.b],
        }
    }
}

/// How the level-0 mesh of a scene is made (`[discretization]`).
#[derive(Clone, Debug, PartialEq)]
pub enum Meshing {
    /// The structured grid of a rectangle with these level-0 cells per direction; every crack
    /// segment must join level-0 vertices along a grid line or a SW–NE cell diagonal.
    Cells([usize; 2]),
    /// gmsh's triangulation with this target edge length, cracks embedded as edge chains.
    MeshSize(f64),
    /// A user's gmsh file (physical groups `boundary`, `crack1`, `crack2`, …; docs/scenes.md).
    File(std::path::PathBuf),
}

/// Meshes graded towards every crack tip (`[discretization] grading`): element size
/// h·(r/R)^{1−β} within the radius R of a tip (r: the distance to it), h elsewhere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grading {
    /// β in (0, 1]: 1/2 or less suits the r^{1/2} tip singularity; 1 is uniform.
    pub beta: f64,
    /// R > 0 (length unit of the scene): the radius of the graded zone around each tip.
    pub radius: f64,
}

impl Grading {
    /// The target diameter of an element at distance `r` from the nearest tip on a level whose
    /// ungraded size is `h`: h·(max(r, r₀)/R)^{1−β} inside R, h outside, with r₀ = R·(h/R)^{1/β}
    /// (the elements touching a tip have size h·(h/R)^{(1−β)/β}, so the number of elements
    /// stays O(h⁻²)).
    pub fn target(&self, h: f64, r: f64) -> f64 {
        if r >= self.radius || self.beta >= 1.0 {
            return h;
        }
        let r0 = self.radius * (h / self.radius).powf(1.0 / self.beta);
        h * (r.max(r0) / self.radius).min(1.0).powf(1.0 - self.beta)
    }
}

/// Ω = [−1, 1]², the square of the unit tests.
#[cfg(test)]
pub(crate) const UNIT_SQUARE: Rectangle = Rectangle {
    min: [-1.0, -1.0],
    max: [1.0, 1.0],
};

/// Straight crack from `a` to `b`; ν is (b − a)/|b − a| turned by +90° (the problem, docs/scenes.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// First end point (a tip).
    pub a: [f64; 2],
    /// Second end point (a tip).
    pub b: [f64; 2],
}

impl Segment {
    /// Length |b − a|.
    pub fn length(&self) -> f64 {
        (self.b[0] - self.a[0]).hypot(self.b[1] - self.a[1])
    }
    /// Unit normal ν: the direction a→b turned by +90°. The + face is the side ν points into.
    pub fn normal(&self) -> [f64; 2] {
        let l = self.length();
        [-(self.b[1] - self.a[1]) / l, (self.b[0] - self.a[0]) / l]
    }
}

/// The exact solution of a scene, when it has one: u, its gradient and its jump on Γc.
#[derive(Clone, Debug)]
pub struct Exact {
    /// u(x, y).
    pub u: Expr,
    /// ∂u/∂x (given, or the symbolic derivative of `u`).
    pub px: Expr,
    /// ∂u/∂y (given, or the symbolic derivative of `u`).
    pub py: Expr,
    /// \[u\] = u⁺ − u⁻ on Γc, when given explicitly; otherwise it is evaluated from `u` on each face.
    pub jump: Option<Expr>,
}

/// Evaluates `e` at a point `p` of the crack as the limit from one face.
///
/// `side` is +1 for the + face (the side ν points into) and −1 for the − face. Coordinates of `p`
/// that are exactly zero are given the sign of `side·ν` in that direction (+0.0 or −0.0), so the
/// IEEE signed zero selects the branch of `sign`, `atan2` and `abs`-kinks lying on the coordinate
/// axes: for a crack on y = 0 with ν = (0, 1), `atan2(y, x − 1)` is +π on the + face and −π on the
/// − face. Branch cuts along other lines are not resolved by this rule; scenes with an exact
/// solution should then give `[exact] jump` explicitly.
pub fn eval_on_face(e: &Expr, p: [f64; 2], normal: [f64; 2], side: f64) -> f64 {
    let q = face_point(p, normal, side);
    e.eval(q[0], q[1])
}

/// The crack point `p` as seen from the face `side` ([`eval_on_face`]'s rule): each coordinate
/// that is exactly zero, in a direction where ν has a component, gets the sign of `side·ν`.
pub fn face_point(p: [f64; 2], normal: [f64; 2], side: f64) -> [f64; 2] {
    let mut q = p;
    for d in 0..2 {
        if q[d] == 0.0 && normal[d] != 0.0 {
            q[d] = 0.0f64.copysign(side * normal[d]);
        }
    }
    q
}
