//! Scene files: the TOML description of one crack problem and its study (BRIEF §5).
//!
//! Owns parsing and *validation* of a scene: unknown keys are rejected (with a "did you mean"
//! suggestion), expressions are parsed once into [`Expr`] trees, and every number is checked
//! (cells > 0, levels distinct, δ ≥ 0 and finite, …). Geometry that depends on the mesh (crack on
//! mesh lines, inside Ω) is checked by [`crate::mesh`]. Everything downstream works on the
//! validated [`Scene`], never on raw TOML.

pub mod expr;

use std::fmt;
use std::path::Path;

use serde::Deserialize;

pub use expr::{Expr, ExprError, Var};

/// The embedded default scene (`sdcrack run` without argument): a partly open, partly closed crack.
pub const DEFAULT_SCENE: &str = include_str!("../../scenes/mixed.toml");

/// Errors found while reading or validating a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("cannot read scene file {path}: {reason}")]
    Read {
        /// File that was asked for.
        path: String,
        /// Operating-system reason.
        reason: String,
    },
    /// Malformed TOML, wrong types, missing or unknown keys.
    #[error("invalid scene: {0}")]
    Toml(String),
    /// An expression does not parse.
    #[error("invalid expression in {key} = \"{source_text}\": {error}")]
    Expression {
        /// Scene key holding the expression (e.g. `data.f`).
        key: String,
        /// The expression text.
        source_text: String,
        /// Parser error with its column.
        error: ExprError,
    },
    /// A value is out of its allowed range.
    #[error("invalid scene: {0}")]
    Value(String),
}

/// How u is discretised (BRIEF §2).
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

impl USpace {
    /// Name used in scene files, the CLI and result files.
    pub fn name(self) -> &'static str {
        match self {
            USpace::Continuous => "continuous",
            USpace::Broken => "broken",
        }
    }
    /// Parses a scene/CLI name.
    pub fn from_name(s: &str) -> Option<USpace> {
        match s {
            "continuous" => Some(USpace::Continuous),
            "broken" => Some(USpace::Broken),
            _ => None,
        }
    }
}

impl MultiplierSpace {
    /// All variants in their canonical order.
    pub const ALL: [MultiplierSpace; 3] = [
        MultiplierSpace::M0,
        MultiplierSpace::M1,
        MultiplierSpace::M1Star,
    ];
    /// Name used in scene files, the CLI and result files.
    pub fn name(self) -> &'static str {
        match self {
            MultiplierSpace::M0 => "M0",
            MultiplierSpace::M1 => "M1",
            MultiplierSpace::M1Star => "M1star",
        }
    }
    /// Parses a scene/CLI name.
    pub fn from_name(s: &str) -> Option<MultiplierSpace> {
        match s {
            "M0" => Some(MultiplierSpace::M0),
            "M1" => Some(MultiplierSpace::M1),
            "M1star" => Some(MultiplierSpace::M1Star),
            _ => None,
        }
    }
}

impl fmt::Display for USpace {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl fmt::Display for MultiplierSpace {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Axis-aligned rectangle Ω = [x0, x1] × [y0, y1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Rectangle {
    /// Lower-left corner.
    pub min: [f64; 2],
    /// Upper-right corner.
    pub max: [f64; 2],
}

/// Straight crack from `a` to `b`; ν is (b − a)/|b − a| turned by +90° (BRIEF §1).
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
    /// [u] = u⁺ − u⁻ on Γc, when given explicitly; otherwise it is evaluated from `u` on each face.
    pub jump: Option<Expr>,
}

/// Which fields are written to `fields.h5`/`fields.xdmf`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FieldSet {
    /// Write u at vertices.
    pub u: bool,
    /// Write p at vertices.
    pub p: bool,
    /// Write λ on the crack.
    pub lambda: bool,
}

impl FieldSet {
    /// True when no field file is to be written at all.
    pub fn is_empty(&self) -> bool {
        !(self.u || self.p || self.lambda)
    }
}

/// A validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Name, used for the results folder (letters, digits, `-`, `_`).
    pub name: String,
    /// Free text.
    pub description: String,
    /// The domain Ω.
    pub domain: Rectangle,
    /// The crack Γc.
    pub crack: Segment,
    /// Source term f of −Δu = f.
    pub f: Expr,
    /// Dirichlet data g on Γ.
    pub g: Expr,
    /// Exact solution, if the scene has one.
    pub exact: Option<Exact>,
    /// Level-0 cells per direction.
    pub cells: [usize; 2],
    /// Refinement levels to run (level ℓ has 2^ℓ·cells cells per direction).
    pub levels: Vec<u32>,
    /// u spaces to run.
    pub u_spaces: Vec<USpace>,
    /// Multiplier spaces to run.
    pub multipliers: Vec<MultiplierSpace>,
    /// Regularisation parameters δ ≥ 0 to run.
    pub deltas: Vec<f64>,
    /// Fields to write.
    pub fields: FieldSet,
    /// Reference tools to run (`dolfinx`, `freefem`).
    pub references: Vec<String>,
}

/// Largest refinement level accepted (4^13 · cells would not fit in memory anyway).
pub const MAX_LEVEL: u32 = 12;
/// Largest number of level-0 cells per direction.
pub const MAX_CELLS: usize = 4096;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneToml {
    name: String,
    #[serde(default)]
    description: String,
    geometry: GeometryToml,
    data: DataToml,
    exact: Option<ExactToml>,
    discretization: DiscretizationToml,
    outputs: Option<OutputsToml>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GeometryToml {
    domain: DomainToml,
    crack: CrackToml,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DomainToml {
    rectangle: [[f64; 2]; 2],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CrackToml {
    segment: [[f64; 2]; 2],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DataToml {
    f: String,
    g: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ExactToml {
    u: String,
    px: Option<String>,
    py: Option<String>,
    jump: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DiscretizationToml {
    cells: [i64; 2],
    levels: Vec<i64>,
    u_spaces: Vec<String>,
    multipliers: Vec<String>,
    deltas: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputsToml {
    fields: Vec<String>,
    references: Vec<String>,
}

/// Every key a scene may contain, by table, for "did you mean" suggestions.
const KNOWN_KEYS: &[&str] = &[
    "name",
    "description",
    "geometry",
    "data",
    "exact",
    "discretization",
    "outputs",
    "domain",
    "crack",
    "rectangle",
    "segment",
    "f",
    "g",
    "u",
    "px",
    "py",
    "jump",
    "cells",
    "levels",
    "u_spaces",
    "multipliers",
    "deltas",
    "fields",
    "references",
];

/// Reference tools the project knows how to run.
pub const KNOWN_REFERENCES: [&str; 2] = ["dolfinx", "freefem"];

impl Scene {
    /// Reads and validates a scene file.
    pub fn from_file(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| SceneError::Read {
            path: path.display().to_string(),
            reason: e.to_string(),
        })?;
        Scene::from_toml(&text)
    }

    /// The embedded default scene.
    pub fn default_scene() -> Scene {
        // The embedded text is validated by a unit test; failing here is a build defect.
        Scene::from_toml(DEFAULT_SCENE).expect("embedded default scene is valid")
    }

    /// Parses and validates scene TOML text.
    pub fn from_toml(text: &str) -> Result<Scene, SceneError> {
        if text.len() > 1 << 20 {
            return Err(SceneError::Value(format!(
                "scene file is {} bytes; the limit is 1 MiB",
                text.len()
            )));
        }
        let raw: SceneToml =
            toml::from_str(text).map_err(|e| SceneError::Toml(toml_message(&e)))?;
        raw.validate()
    }

    /// Total number of cases (level × u space × multiplier × δ).
    pub fn case_count(&self) -> usize {
        self.levels.len() * self.u_spaces.len() * self.multipliers.len() * self.deltas.len()
    }
}

/// One-line message for a TOML/serde error, with a suggestion for unknown keys.
fn toml_message(e: &toml::de::Error) -> String {
    let msg = e.message().trim().replace('\n', " ");
    let location = e
        .span()
        .map(|s| format!(" (at byte {})", s.start))
        .unwrap_or_default();
    if let Some(rest) = msg.strip_prefix("unknown field `") {
        if let Some(end) = rest.find('`') {
            let key = &rest[..end];
            if let Some(s) = suggest(key, KNOWN_KEYS) {
                return format!("{msg}; did you mean `{s}`?{location}");
            }
        }
    }
    format!("{msg}{location}")
}

/// The closest known word within edit distance 2, if any.
pub fn suggest<'a>(word: &str, known: &[&'a str]) -> Option<&'a str> {
    known
        .iter()
        .map(|k| (edit_distance(word, k), *k))
        .filter(|(d, _)| *d <= 2)
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

fn edit_distance(a: &str, b: &str) -> usize {
    let a: Vec<char> = a.chars().collect();
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.iter().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

fn parse_expr(key: &str, text: &str) -> Result<Expr, SceneError> {
    Expr::parse(text).map_err(|error| SceneError::Expression {
        key: key.to_string(),
        source_text: text.to_string(),
        error,
    })
}

fn check_finite_point(what: &str, p: [f64; 2]) -> Result<(), SceneError> {
    if p.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(SceneError::Value(format!(
            "{what} has a non-finite coordinate ({}, {})",
            p[0], p[1]
        )))
    }
}

impl SceneToml {
    fn validate(self) -> Result<Scene, SceneError> {
        let name = self.name.trim().to_string();
        if name.is_empty()
            || name.len() > 100
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(SceneError::Value(format!(
                "name \"{}\" must be 1-100 characters of letters, digits, '-' or '_' (it names the results folder)",
                self.name
            )));
        }
        let [lo, hi] = self.geometry.domain.rectangle;
        check_finite_point("geometry.domain.rectangle", lo)?;
        check_finite_point("geometry.domain.rectangle", hi)?;
        if !(hi[0] > lo[0] && hi[1] > lo[1]) {
            return Err(SceneError::Value(format!(
                "geometry.domain.rectangle [[{}, {}], [{}, {}]] must list the lower-left corner first and have positive width and height",
                lo[0], lo[1], hi[0], hi[1]
            )));
        }
        let [a, b] = self.geometry.crack.segment;
        check_finite_point("geometry.crack.segment", a)?;
        check_finite_point("geometry.crack.segment", b)?;
        let crack = Segment { a, b };
        if crack.length() <= 0.0 {
            return Err(SceneError::Value(
                "geometry.crack.segment has zero length (its two end points coincide)".into(),
            ));
        }
        let f = parse_expr("data.f", &self.data.f)?;
        let g = parse_expr("data.g", &self.data.g)?;
        let exact = match self.exact {
            None => None,
            Some(e) => {
                let u = parse_expr("exact.u", &e.u)?;
                let px = match e.px {
                    Some(s) => parse_expr("exact.px", &s)?,
                    None => u.derivative(Var::X),
                };
                let py = match e.py {
                    Some(s) => parse_expr("exact.py", &s)?,
                    None => u.derivative(Var::Y),
                };
                let jump = e.jump.map(|s| parse_expr("exact.jump", &s)).transpose()?;
                Some(Exact { u, px, py, jump })
            }
        };
        let d = self.discretization;
        let cells = validate_cells(d.cells)?;
        let levels = validate_levels(&d.levels, cells)?;
        let u_spaces = validate_names(
            "discretization.u_spaces",
            &d.u_spaces,
            USpace::from_name,
            &["continuous", "broken"],
        )?;
        let multipliers = validate_names(
            "discretization.multipliers",
            &d.multipliers,
            MultiplierSpace::from_name,
            &["M0", "M1", "M1star"],
        )?;
        let deltas = validate_deltas(&d.deltas)?;
        let (fields, references) = match self.outputs {
            None => (
                FieldSet {
                    u: true,
                    p: true,
                    lambda: true,
                },
                Vec::new(),
            ),
            Some(o) => (
                validate_fields(&o.fields)?,
                validate_references(&o.references)?,
            ),
        };
        Ok(Scene {
            name,
            description: self.description,
            domain: Rectangle { min: lo, max: hi },
            crack,
            f,
            g,
            exact,
            cells,
            levels,
            u_spaces,
            multipliers,
            deltas,
            fields,
            references,
        })
    }
}

fn validate_cells(cells: [i64; 2]) -> Result<[usize; 2], SceneError> {
    let mut out = [0usize; 2];
    for (o, c) in out.iter_mut().zip(cells) {
        if c <= 0 || c as usize > MAX_CELLS {
            return Err(SceneError::Value(format!(
                "discretization.cells = [{}, {}]: each entry must be between 1 and {MAX_CELLS}",
                cells[0], cells[1]
            )));
        }
        *o = c as usize;
    }
    Ok(out)
}

fn validate_levels(levels: &[i64], cells: [usize; 2]) -> Result<Vec<u32>, SceneError> {
    if levels.is_empty() {
        return Err(SceneError::Value(
            "discretization.levels is empty: list at least one level, e.g. [0, 1, 2]".into(),
        ));
    }
    let mut out = Vec::with_capacity(levels.len());
    for &l in levels {
        if !(0..=i64::from(MAX_LEVEL)).contains(&l) {
            return Err(SceneError::Value(format!(
                "discretization.levels: level {l} is outside 0..={MAX_LEVEL}"
            )));
        }
        let l = l as u32;
        if out.contains(&l) {
            return Err(SceneError::Value(format!(
                "discretization.levels: level {l} is listed twice"
            )));
        }
        let n = (cells[0] as u128 * cells[1] as u128) << (2 * l);
        if n > 50_000_000 {
            return Err(SceneError::Value(format!(
                "discretization: level {l} with cells [{}, {}] has {n} cells, more than the 5e7 this solver accepts",
                cells[0], cells[1]
            )));
        }
        out.push(l);
    }
    out.sort_unstable();
    Ok(out)
}

fn validate_names<T: PartialEq + Copy>(
    key: &str,
    names: &[String],
    parse: impl Fn(&str) -> Option<T>,
    known: &[&str],
) -> Result<Vec<T>, SceneError> {
    if names.is_empty() {
        return Err(SceneError::Value(format!(
            "{key} is empty: list at least one of {}",
            known.join(", ")
        )));
    }
    let mut out = Vec::new();
    for n in names {
        let v = parse(n).ok_or_else(|| {
            let hint = suggest(n, known)
                .map(|s| format!("; did you mean \"{s}\"?"))
                .unwrap_or_default();
            SceneError::Value(format!(
                "{key}: unknown value \"{n}\" (expected one of {}){hint}",
                known.join(", ")
            ))
        })?;
        if out.contains(&v) {
            return Err(SceneError::Value(format!("{key}: \"{n}\" is listed twice")));
        }
        out.push(v);
    }
    Ok(out)
}

fn validate_deltas(deltas: &[f64]) -> Result<Vec<f64>, SceneError> {
    if deltas.is_empty() {
        return Err(SceneError::Value(
            "discretization.deltas is empty: list at least one δ ≥ 0, e.g. [0.0]".into(),
        ));
    }
    let mut out: Vec<f64> = Vec::new();
    for &d in deltas {
        if !d.is_finite() || d < 0.0 {
            return Err(SceneError::Value(format!(
                "discretization.deltas: {d} is not a finite number ≥ 0"
            )));
        }
        if out.contains(&d) {
            return Err(SceneError::Value(format!(
                "discretization.deltas: {d} is listed twice"
            )));
        }
        out.push(d);
    }
    // Largest δ first: each solve warm-starts the next, and δ → 0 is the limit studied.
    out.sort_by(|a, b| b.total_cmp(a));
    Ok(out)
}

fn validate_fields(fields: &[String]) -> Result<FieldSet, SceneError> {
    let mut set = FieldSet::default();
    for f in fields {
        let slot = match f.as_str() {
            "u" => &mut set.u,
            "p" => &mut set.p,
            "lambda" => &mut set.lambda,
            other => {
                let hint = suggest(other, &["u", "p", "lambda"])
                    .map(|s| format!("; did you mean \"{s}\"?"))
                    .unwrap_or_default();
                return Err(SceneError::Value(format!(
                    "outputs.fields: unknown field \"{other}\" (expected u, p, lambda){hint}"
                )));
            }
        };
        if *slot {
            return Err(SceneError::Value(format!(
                "outputs.fields: \"{f}\" is listed twice"
            )));
        }
        *slot = true;
    }
    Ok(set)
}

fn validate_references(refs: &[String]) -> Result<Vec<String>, SceneError> {
    let mut out: Vec<String> = Vec::new();
    for r in refs {
        if !KNOWN_REFERENCES.contains(&r.as_str()) {
            let hint = suggest(r, &KNOWN_REFERENCES)
                .map(|s| format!("; did you mean \"{s}\"?"))
                .unwrap_or_default();
            return Err(SceneError::Value(format!(
                "outputs.references: unknown reference \"{r}\" (expected dolfinx, freefem){hint}"
            )));
        }
        if out.contains(r) {
            return Err(SceneError::Value(format!(
                "outputs.references: \"{r}\" is listed twice"
            )));
        }
        out.push(r.clone());
    }
    Ok(out)
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
    let mut q = p;
    for d in 0..2 {
        if q[d] == 0.0 && normal[d] != 0.0 {
            q[d] = 0.0f64.copysign(side * normal[d]);
        }
    }
    e.eval(q[0], q[1])
}
