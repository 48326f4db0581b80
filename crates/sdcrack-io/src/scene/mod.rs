//! Scene files: the TOML description of one crack problem and its study (docs/scenes.md).
//!
//! Owns parsing and *validation* of a scene: unknown keys are rejected (with a "did you mean"
//! suggestion), expressions are parsed once into [`Expr`] trees, and every number is checked
//! (cells > 0, levels distinct, δ ≥ 0 and finite, …). Geometry that depends on the mesh (crack on
//! mesh lines, inside Ω) is checked by [`crate::mesh`]. Everything downstream works on the
//! validated [`Scene`], never on raw TOML.

pub mod verification;

use std::path::Path;

use serde::Deserialize;

pub use crate::expr::{BatchScratch, Expr, ExprBatch, ExprError, Var};
// The problem's vocabulary lives in crate::problem (the maths modules use it without this
// parser); re-exported so that a scene's users find it here too.
pub use crate::problem::{
    eval_on_face, Domain, Exact, Meshing, MultiplierSpace, PMass, PSpace, Polyline, Rectangle,
    Segment, USpace,
};
// The validated scene and its limits are sdcrack-core's (the study runs them without this
// parser); re-exported so that a scene's users find them here too.
pub use sdcrack_core::scene::{
    check_level, estimated_memory_bytes, ExpectedFailure, FieldSet, Level0Size, Scene,
    Verification, MAX_LEVEL, MAX_MEMORY_BYTES, MEMORY_BYTES_PER_CELL,
};

/// The commented scene template printed by `sdcrack scene --template` (a valid, small scene).
pub const SCENE_TEMPLATE: &str = include_str!("../../../../docs/scene-template.toml");

/// The embedded default scene (`sdcrack run` without argument): a partly open, partly closed crack.
pub const DEFAULT_SCENE: &str = include_str!("../../../../scenes/mixed.toml");

/// Errors found while reading or validating a scene.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The scene file could not be read.
    #[error(
        "cannot read scene file {}: {}",
        escape_controls(path),
        escape_controls(reason)
    )]
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
    #[error("invalid expression in {key} = {source_text:?}: {}{at}", escape_controls(&error.to_string()))]
    Expression {
        /// Scene key holding the expression (e.g. `data.f`).
        key: String,
        /// The expression text.
        source_text: String,
        /// Parser error with its column.
        error: ExprError,
        /// Where the key is in the scene file, ` (at line L, column C)`, or empty.
        at: String,
    },
    /// A value is out of its allowed range.
    #[error("invalid scene: {0}")]
    Value(String),
    /// An error of the scene file `path` (the message then names the file).
    #[error("{}", in_file_message(path, error))]
    InFile {
        /// The scene file.
        path: String,
        /// What is wrong in it.
        error: Box<SceneError>,
    },
}

/// `s` with control characters (newlines, tabs, …) written as escapes, so that text from a scene
/// file or a path cannot break a one-line message.
pub fn escape_controls(s: &str) -> String {
    if !s.chars().any(char::is_control) {
        return s.to_string();
    }
    s.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// `invalid scene FILE: …` for an error found in a file.
fn in_file_message(path: &str, error: &SceneError) -> String {
    match error {
        SceneError::Toml(m) | SceneError::Value(m) => {
            format!("invalid scene {}: {m}", escape_controls(path))
        }
        SceneError::Expression { .. } => {
            format!("invalid scene {}: {error}", escape_controls(path))
        }
        SceneError::Read { .. } | SceneError::InFile { .. } => error.to_string(),
    }
}

/// Largest number of level-0 cells per direction.
pub const MAX_CELLS: usize = 4096;
/// Largest scene file accepted, in bytes (1 MiB; the repository's scenes are under 2 KiB).
pub const MAX_SCENE_BYTES: usize = 1 << 20;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneToml {
    name: String,
    #[serde(default)]
    description: String,
    geometry: Option<GeometryToml>,
    data: DataToml,
    exact: Option<ExactToml>,
    discretization: DiscretizationToml,
    outputs: Option<OutputsToml>,
    verification: Option<verification::VerificationToml>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GeometryToml {
    domain: Option<DomainToml>,
    crack: Option<CrackToml>,
    cracks: Option<Vec<CrackToml>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DomainToml {
    rectangle: Option<Vec<Vec<f64>>>,
    polygon: Option<Vec<Vec<f64>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CrackToml {
    segment: Option<Vec<Vec<f64>>>,
    polyline: Option<Vec<Vec<f64>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshFileToml {
    gmsh: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GradingToml {
    beta: f64,
    radius: f64,
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
    cells: Option<Vec<i64>>,
    mesh_size: Option<f64>,
    mesh: Option<MeshFileToml>,
    #[serde(default)]
    grading: Option<GradingToml>,
    levels: Vec<i64>,
    u_spaces: Vec<String>,
    multipliers: Vec<String>,
    #[serde(default)]
    p_mass: Option<Vec<String>>,
    #[serde(default)]
    p_spaces: Option<Vec<String>>,
    deltas: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct OutputsToml {
    fields: Vec<String>,
    references: Vec<String>,
}

/// Every table of a scene with its keys, for messages and "did you mean" suggestions. The order
/// of each list is that of the structs above (serde names them in that order).
const TABLE_KEYS: &[(&str, &[&str])] = &[
    (
        "",
        &[
            "name",
            "description",
            "geometry",
            "data",
            "exact",
            "discretization",
            "outputs",
            "verification",
        ],
    ),
    ("geometry", &["domain", "crack", "cracks"]),
    ("geometry.domain", &["rectangle", "polygon"]),
    ("geometry.crack", &["segment", "polyline"]),
    ("geometry.cracks", &["segment", "polyline"]),
    ("discretization.mesh", &["gmsh"]),
    ("discretization.grading", &["beta", "radius"]),
    ("data", &["f", "g"]),
    ("exact", &["u", "px", "py", "jump"]),
    (
        "discretization",
        &[
            "cells",
            "mesh_size",
            "mesh",
            "grading",
            "levels",
            "u_spaces",
            "multipliers",
            "p_mass",
            "p_spaces",
            "deltas",
        ],
    ),
    ("outputs", &["fields", "references"]),
    ("verification", verification::VERIFICATION_KEYS),
    (
        "verification.expected_failure",
        verification::EXPECTED_FAILURE_KEYS,
    ),
    (
        "verification.expected_rate",
        verification::EXPECTED_RATE_KEYS,
    ),
    (
        "verification.not_applicable",
        verification::NOT_APPLICABLE_KEYS,
    ),
];

/// Reference tools the project knows how to run.
pub const KNOWN_REFERENCES: [&str; 2] = ["dolfinx", "freefem"];

/// A [`Scene`]'s TOML format: reading and validating a scene file or text, and locating a
/// message's key in it. The scene struct is sdcrack-core's (format-free); bring this trait into
/// scope with it (`use sdcrack::scene::{Scene, TomlScene}`) to call `Scene::from_file` and the rest.
pub trait TomlScene: Sized {
    /// Reads and validates a scene file; errors name the file.
    fn from_file(path: &Path) -> Result<Self, SceneError>;
    /// The commented scene template printed by `sdcrack scene --template` (a valid, small scene).
    const SCENE_TEMPLATE: &'static str;
    /// The embedded default scene.
    fn default_scene() -> Self;
    /// Parses and validates scene TOML text.
    fn from_toml(text: &str) -> Result<Self, SceneError>;
    /// As [`TomlScene::from_toml`], reading a `discretization.mesh` file relative to `base_dir`.
    fn from_toml_in(text: &str, base_dir: &Path) -> Result<Self, SceneError>;
    /// `message` about this scene, naming a key first, with that key's line and column in the
    /// scene file appended.
    fn locate(&self, message: String) -> String;
}

impl TomlScene for Scene {
    /// Reads and validates a scene file; errors name the file.
    ///
    /// Refuses directories, files over [`MAX_SCENE_BYTES`] (without reading more than that) and
    /// text that is not UTF-8.
    fn from_file(path: &Path) -> Result<Scene, SceneError> {
        let shown = path.display().to_string();
        let read_error = |reason: String| SceneError::Read {
            path: shown.clone(),
            reason,
        };
        let plain = |e: std::io::Error| read_error(crate::plain::io_reason(&e));
        let meta = std::fs::metadata(path).map_err(plain)?;
        if meta.is_dir() {
            return Err(read_error("it is a directory, not a TOML file".into()));
        }
        if meta.is_file() && meta.len() > MAX_SCENE_BYTES as u64 {
            return Err(read_error(format!(
                "it has {} bytes, more than the 1 MiB ({MAX_SCENE_BYTES} bytes) a scene may have",
                meta.len()
            )));
        }
        let file = std::fs::File::open(path).map_err(plain)?;
        let mut bytes = Vec::new();
        std::io::Read::read_to_end(
            &mut std::io::Read::take(file, MAX_SCENE_BYTES as u64 + 1),
            &mut bytes,
        )
        .map_err(plain)?;
        if bytes.len() > MAX_SCENE_BYTES {
            return Err(read_error(format!(
                "it has more than the 1 MiB ({MAX_SCENE_BYTES} bytes) a scene may have"
            )));
        }
        let text = String::from_utf8(bytes).map_err(|e| {
            let at = e.utf8_error().valid_up_to();
            let (line, column) = line_column(&String::from_utf8_lossy(&e.into_bytes()), at);
            read_error(format!(
                "it is not UTF-8 text (invalid byte at line {line}, column {column})"
            ))
        })?;
        let base_dir = path.parent().unwrap_or(Path::new("."));
        Scene::from_toml_in(&text, base_dir).map_err(|error| SceneError::InFile {
            path: shown,
            error: Box::new(error),
        })
    }

    /// The commented scene template printed by `sdcrack scene --template` (a valid, small scene).
    const SCENE_TEMPLATE: &'static str = include_str!("../../../../docs/scene-template.toml");

    /// The embedded default scene.
    fn default_scene() -> Scene {
        // The embedded text is validated by a unit test; failing here is a build defect.
        Scene::from_toml(DEFAULT_SCENE).expect("embedded default scene is valid")
    }

    /// Parses and validates scene TOML text.
    fn from_toml(text: &str) -> Result<Scene, SceneError> {
        Scene::from_toml_in(text, Path::new("."))
    }

    /// As [`Scene::from_toml`], reading a `discretization.mesh` file relative to `base_dir`.
    fn from_toml_in(text: &str, base_dir: &Path) -> Result<Scene, SceneError> {
        if text.len() > MAX_SCENE_BYTES {
            return Err(SceneError::Value(format!(
                "the scene has {} bytes, more than the 1 MiB ({MAX_SCENE_BYTES} bytes) a scene may have",
                text.len()
            )));
        }
        if text.trim().is_empty() {
            return Err(SceneError::Toml(
                "the scene is empty; it needs at least name, [geometry], [data] and [discretization] (see scenes/mixed.toml)".into(),
            ));
        }
        let raw: SceneToml =
            toml::from_str(text).map_err(|e| SceneError::Toml(toml_message(&e, text)))?;
        let mut scene = raw.validate(base_dir).map_err(|e| located(e, text))?;
        scene.source = text.to_string();
        Ok(scene)
    }

    /// `message` about this scene, naming a key first (`data.f = "…" evaluates to NaN …`,
    /// `geometry.cracks[1]: crack segment … is not along a mesh line`), with that key's line and
    /// column in the scene file appended, as the scene's own validation errors have them.
    fn locate(&self, message: String) -> String {
        locate_message(message, &self.source)
    }
}

/// 1-based line and column (in characters) of byte `offset` of `text`.
fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    (line, before[line_start..].chars().count() + 1)
}

/// `error` with the line and column of the key it is about, ` (at line L, column C)` as TOML
/// syntax errors have them: a value error names its key first (`discretization.levels: …`,
/// `geometry.cracks[1].polyline must …`), an expression error in `key`. Unchanged when the key is
/// not written in `text` (a missing table, a default).
fn located(error: SceneError, text: &str) -> SceneError {
    let at =
        |key: &str| key_position(text, key).map(|(l, c)| format!(" (at line {l}, column {c})"));
    match error {
        SceneError::Value(m) => SceneError::Value(locate_message(m, text)),
        SceneError::Expression {
            key,
            source_text,
            error,
            at: _,
        } => SceneError::Expression {
            at: at(&key).unwrap_or_default(),
            key,
            source_text,
            error,
        },
        other => other,
    }
}

/// ` (the table is at line L, column C)` for a table written in `text` (inline tables too),
/// where a missing key belongs; empty when it is not written.
fn table_position(text: &str, table: &str) -> String {
    key_position(text, table)
        .map(|(l, c)| format!(" (the table is at line {l}, column {c})"))
        .unwrap_or_default()
}

/// `message`, which names a scene key first (`discretization.levels: …`, `data.f = …`,
/// `geometry.cracks[1]: …`), with the key's line and column in the TOML `text` appended as
/// ` (at line L, column C)`; unchanged when the text does not write that key.
fn locate_message(message: String, text: &str) -> String {
    if let Some(rest) = message.strip_prefix("missing key `") {
        // a key that is not there: where its table is
        let table = rest
            .split_once(" in [")
            .and_then(|(_, t)| t.split_once(']'));
        return match table {
            Some((t, _)) => format!("{message}{}", table_position(text, t)),
            None => message,
        };
    }
    let key: String = match message.strip_prefix('[') {
        // `[geometry] must be left out …`: a table
        Some(rest) => rest.split(']').next().unwrap_or("").to_string(),
        None => message
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '.' | '[' | ']'))
            .collect(),
    };
    match key_position(text, key.trim_end_matches('.')) {
        Some((l, c)) => format!("{message} (at line {l}, column {c})"),
        None => message,
    }
}

/// The steps of a key path: names and, for an array of tables, an index (`expected_failure[1]`).
fn key_steps(path: &str) -> Vec<(String, Option<usize>)> {
    path.split('.')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .map(|s| match s.split_once('[') {
            Some((name, rest)) => (
                name.to_string(),
                rest.trim_end_matches(']').parse::<usize>().ok(),
            ),
            None => (s.to_string(), None),
        })
        .collect()
}

/// Whether key path `a` is a prefix of `b` (names equal; indices equal where both have one).
fn key_prefix(a: &[(String, Option<usize>)], b: &[(String, Option<usize>)]) -> bool {
    a.len() <= b.len()
        && a.iter()
            .zip(b)
            .all(|(x, y)| x.0 == y.0 && (x.1.is_none() || y.1.is_none() || x.1 == y.1))
}

/// 1-based line and column of the key `path` (`data.f`, `discretization.grading.beta`,
/// `verification.expected_failure[1].u_space`) in the TOML `text`: the `key =` that sets it, a
/// key of an inline table on its line, or the `[table]` header when the path is a table. None
/// when the text does not write it. A line scan, enough for the scene layout (dotted keys, inline
/// tables on one line, arrays of tables); an index into an inline array points at its key.
fn key_position(text: &str, path: &str) -> Option<(usize, usize)> {
    let want = key_steps(path);
    if want.is_empty() {
        return None;
    }
    let mut header: Vec<(String, Option<usize>)> = Vec::new();
    let mut counts: std::collections::HashMap<String, usize> = Default::default();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.trim_start();
        let indent = raw.chars().count() - line.chars().count();
        if line.starts_with('[') {
            let name = line
                .trim_start_matches('[')
                .split(']')
                .next()
                .unwrap_or("")
                .trim();
            header = key_steps(name);
            if line.starts_with("[[") {
                let n = counts.entry(name.to_string()).or_insert(0);
                if let Some(last) = header.last_mut() {
                    last.1 = Some(*n);
                }
                *n += 1;
            }
            if header.len() == want.len() && key_prefix(&header, &want) {
                return Some((i + 1, indent + 1));
            }
            continue;
        }
        let Some(eq) = line.find('=') else { continue };
        if line.starts_with('#') {
            continue;
        }
        let mut full = header.clone();
        full.extend(key_steps(line[..eq].trim().trim_matches(['"', '\''])));
        if full.is_empty() || !key_prefix(&full, &want) {
            continue;
        }
        // deeper than the line's key: the keys of an inline table written on this line
        let mut column = indent + 1;
        let mut from = eq + 1;
        for (name, _) in &want[full.len()..] {
            let rest = &line[from..];
            let found = rest.match_indices(name.as_str()).find(|(k, _)| {
                let before = rest[..*k].trim_end();
                rest[k + name.len()..].trim_start().starts_with('=')
                    && (before.ends_with('{') || before.ends_with(','))
            });
            let Some((k, _)) = found else { break };
            column = indent + 1 + line[..from + k].chars().count();
            from += k + name.len();
        }
        return Some((i + 1, column));
    }
    None
}

/// The `[table]` header in force at byte `offset` (`""` before the first header).
fn table_at(text: &str, offset: usize) -> String {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    // The line holding `offset` counts: a missing-key error points at the table's header.
    let end = text[offset..].find('\n').map_or(text.len(), |i| offset + i);
    text[..end]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| {
            l.trim_start_matches('[')
                .split(']')
                .next()
                .unwrap_or("")
                .trim()
                .to_string()
        })
        .unwrap_or_default()
}

/// The key whose value starts at byte `offset`, when `offset` follows `key =` on its line.
fn key_at(text: &str, offset: usize) -> Option<String> {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    let before = &text[line_start..offset];
    let eq = before.rfind('=')?;
    let key = before[..eq]
        .rsplit(['{', ','])
        .next()
        .unwrap_or("")
        .trim()
        .trim_matches(['"', '\'']);
    let simple = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-' || c == '.');
    simple.then(|| key.to_string())
}

/// `in [table]`, or `at the top level` for `""`.
fn table_name(table: &str) -> String {
    if table.is_empty() {
        "at the top level".to_string()
    } else {
        // a header may hold a tab or other control character (`[verification.\tx]`)
        format!("in [{}]", escape_controls(table))
    }
}

/// One-line message for a TOML/serde error: what is wrong, the key or table, line and column, and
/// for an unknown key the closest key of that table ("did you mean").
fn toml_message(e: &toml::de::Error, text: &str) -> String {
    // toml puts a detail on a second line ("invalid string\nexpected `\"`"): join with ": ".
    let msg = e
        .message()
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect::<Vec<_>>()
        .join(": ");
    let msg = escape_controls(&msg);
    let start = e.span().map(|s| s.start);
    let (line, column) = start.map_or((0, 0), |s| line_column(text, s));
    let at = format!("line {line}, column {column}");
    let table_here = || start.map(|s| table_at(text, s)).unwrap_or_default();
    if let Some(rest) = msg.strip_prefix("unknown field `") {
        let key = rest.split('`').next().unwrap_or("");
        // The keys serde expected tell which table (inline tables included) the key is in.
        let expected: Vec<&str> = rest
            .split_once("expected")
            .map(|(_, list)| list.split('`').skip(1).step_by(2).collect())
            .unwrap_or_default();
        let table = TABLE_KEYS
            .iter()
            .find(|(_, keys)| *keys == expected.as_slice())
            .map_or_else(table_here, |(t, _)| t.to_string());
        let known: &[&str] = TABLE_KEYS
            .iter()
            .find(|(t, _)| *t == table)
            .map_or(&[], |(_, keys)| keys);
        let hint = if let Some(s) = suggest(key, known) {
            format!("; did you mean `{s}`?")
        } else if let Some((t, _)) = TABLE_KEYS.iter().find(|(_, keys)| keys.contains(&key)) {
            format!("; `{key}` belongs {}", table_name(t))
        } else {
            String::new()
        };
        let allowed = if known.is_empty() {
            String::new()
        } else {
            format!(" (allowed: {})", known.join(", "))
        };
        let location = if start.is_some() {
            format!(" at {at}")
        } else {
            String::new()
        };
        return format!(
            "unknown key `{key}` {}{location}{hint}{allowed}",
            table_name(&table)
        );
    }
    if let Some(rest) = msg.strip_prefix("missing field `") {
        let key = rest.split('`').next().unwrap_or("");
        if TABLE_KEYS.iter().any(|(t, _)| *t == key) {
            return format!("missing table [{key}]");
        }
        // Every key belongs to one table; the span may point at the next table's header.
        return match TABLE_KEYS.iter().find(|(_, keys)| keys.contains(&key)) {
            Some(("", _)) => format!("missing key `{key}` at the top level"),
            Some((t, _)) => format!("missing key `{key}` in [{t}]{}", table_position(text, t)),
            None => match (table_here(), start) {
                (t, Some(_)) if !t.is_empty() => {
                    format!("missing key `{key}` in [{t}] (near {at})")
                }
                _ => format!("missing key `{key}`"),
            },
        };
    }
    let Some(start) = start else {
        return msg;
    };
    match key_at(text, start) {
        Some(key) => {
            let table = table_at(text, start);
            let path = if table.is_empty() || key.contains('.') {
                key
            } else {
                format!("{table}.{key}")
            };
            match (key_type(&path), got(&msg)) {
                (Some((path, words)), Some(got)) => {
                    format!("{path} must be {words}, not {got} (at {at})")
                }
                _ => format!("{path}: {msg} (at {at})"),
            }
        }
        None => {
            let line_text = text.lines().nth(line - 1).unwrap_or("").trim_start();
            match table_at(text, start) {
                // An error in a header itself, or before any header: the line says it all.
                t if t.is_empty() || line_text.starts_with('[') || msg.contains("table `") => {
                    format!("{msg} (at {at})")
                }
                t => format!("{msg} in [{t}] (at {at})"),
            }
        }
    }
}

/// What each key's value must be, in the words of docs/scenes.md, for type errors (serde says
/// "expected i64"; a user wants "levels must be a list of integers"). Keyed by the last part of
/// the key's path; the first string is the full path to show.
const KEY_TYPES: &[(&str, &str, &str)] = &[
    ("name", "name", "a string"),
    ("description", "description", "a string"),
    (
        "rectangle",
        "geometry.domain.rectangle",
        "two corner points [[x0, y0], [x1, y1]] of numbers",
    ),
    (
        "segment",
        "geometry.crack.segment",
        "two end points [[xa, ya], [xb, yb]] of numbers",
    ),
    (
        "polygon",
        "geometry.domain.polygon",
        "a list of at least three points [[x, y], ...] of numbers",
    ),
    (
        "polyline",
        "geometry.cracks[i].polyline",
        "a list of at least two points [[x, y], ...] of numbers",
    ),
    (
        "cracks",
        "geometry.cracks",
        "a list of cracks, each { segment = [[xa, ya], [xb, yb]] } or { polyline = [[x, y], ...] }",
    ),
    (
        "mesh_size",
        "discretization.mesh_size",
        "a positive number (the coarse mesh's target edge length)",
    ),
    (
        "gmsh",
        "discretization.mesh.gmsh",
        "the path of a .msh file in quotes",
    ),
    ("f", "data.f", "an expression in quotes, e.g. \"sin(pi*x)\""),
    ("g", "data.g", "an expression in quotes, e.g. \"0\""),
    ("u", "exact.u", "an expression in quotes"),
    ("px", "exact.px", "an expression in quotes"),
    ("py", "exact.py", "an expression in quotes"),
    ("jump", "exact.jump", "an expression in quotes"),
    ("cells", "discretization.cells", "two integers [nx, ny]"),
    ("levels", "discretization.levels", "a list of integers"),
    (
        "u_spaces",
        "discretization.u_spaces",
        "a list of names from \"continuous\", \"broken\"",
    ),
    (
        "multipliers",
        "discretization.multipliers",
        "a list of names from \"M0\", \"M1\", \"M1star\"",
    ),
    ("deltas", "discretization.deltas", "a list of numbers ≥ 0"),
    (
        "p_mass",
        "discretization.p_mass",
        "a list of names from \"consistent\", \"lumped\"",
    ),
    (
        "p_spaces",
        "discretization.p_spaces",
        "a list of names from \"continuous\", \"broken-tangential\"",
    ),
    (
        "fields",
        "outputs.fields",
        "a list of names from \"u\", \"p\", \"lambda\"",
    ),
    (
        "references",
        "outputs.references",
        "a list of names from \"dolfinx\", \"freefem\"",
    ),
    ("smoke", "verification.smoke", "true or false"),
    ("kkt_tolerance", "verification.kkt_tolerance", "a number"),
    (
        "reference_agreement",
        "verification.reference_agreement",
        "a number",
    ),
    (
        "delta_slope_tolerance",
        "verification.delta_slope_tolerance",
        "a number",
    ),
    ("min_rate", "verification.min_rate", "a number"),
    (
        "u_space",
        "verification.expected_failure.u_space",
        "a string",
    ),
    (
        "multiplier",
        "verification.expected_failure.multiplier",
        "a string",
    ),
    (
        "quantity",
        "verification.expected_failure.quantity",
        "a string",
    ),
    ("reason", "verification.expected_failure.reason", "a string"),
];

/// The full path and the expected value in words of the key shown as `path`.
fn key_type(path: &str) -> Option<(&'static str, &'static str)> {
    let last = path.rsplit('.').next().unwrap_or(path);
    KEY_TYPES
        .iter()
        .find(|(key, _, _)| *key == last)
        .map(|&(_, full, words)| (full, words))
}

/// What was found, in words, from serde's "invalid type: string \"a\", expected i64".
fn got(msg: &str) -> Option<String> {
    let found = msg
        .strip_prefix("invalid type: ")?
        .split(", expected")
        .next()?;
    let (kind, value) = found.split_once(' ').unwrap_or((found, ""));
    let value = value.trim_matches('`');
    Some(match kind {
        "string" => format!("the string {value}"),
        "integer" => format!("the integer {value}"),
        "floating" => format!("the number {}", value.trim_start_matches("point `")),
        "boolean" => format!("the boolean {value}"),
        "sequence" => "a list".to_string(),
        "map" => "a table".to_string(),
        _ => found.to_string(),
    })
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
        at: String::new(),
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
    /// `base_dir`: the folder relative mesh file paths are read from (the scene file's).
    fn validate(self, base_dir: &Path) -> Result<Scene, SceneError> {
        let name = self.name.trim().to_string();
        if name.is_empty()
            || name.len() > 100
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(SceneError::Value(format!(
                "name {:?} must be 1-100 characters of letters, digits, '-' or '_' (it names the results folder)",
                self.name
            )));
        }
        let d = self.discretization;
        let meshing = validate_meshing(&d, base_dir)?;
        let grading = d.grading.as_ref().map(validate_grading).transpose()?;
        let mut file_triangles = 0;
        let (domain, cracks, crack_names) = match (&meshing, self.geometry) {
            (Meshing::File(path), None) => {
                let (domain, cracks, triangles) = crate::mesh::msh_file_geometry(path)
                    .map_err(|e| SceneError::Value(format!("discretization.mesh: {e}")))?;
                file_triangles = triangles;
                let names = (1..=cracks.len())
                    .map(|i| format!("crack{i} of {}", path.display()))
                    .collect();
                (domain, cracks, names)
            }
            (Meshing::File(_), Some(_)) => {
                return Err(SceneError::Value(
                    "[geometry] must be left out with discretization.mesh: the domain and the cracks come from the mesh file's physical groups".into(),
                ))
            }
            (_, None) => {
                return Err(SceneError::Value(
                    "[geometry] is missing: give geometry.domain and geometry.crack (or geometry.cracks)".into(),
                ))
            }
            (_, Some(g)) => validate_geometry(g)?,
        };
        let level0 = match meshing {
            Meshing::Cells(c) => Level0Size::Grid(c),
            Meshing::MeshSize(h) => {
                let area = crate::geometry::signed_area(&domain.polygon()).abs();
                Level0Size::Triangles(1.5 * area / (3f64.sqrt() / 4.0 * h * h))
            }
            Meshing::File(_) => Level0Size::Triangles(file_triangles as f64),
        };
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
        let levels = validate_levels(&d.levels, level0)?;
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
        let p_masses = match &d.p_mass {
            None => vec![PMass::Consistent],
            Some(names) => validate_names(
                "discretization.p_mass",
                names,
                PMass::from_name,
                &["consistent", "lumped"],
            )?,
        };
        let p_spaces = match &d.p_spaces {
            None => vec![PSpace::Continuous],
            Some(names) => validate_names(
                "discretization.p_spaces",
                names,
                PSpace::from_name,
                &["continuous", "broken-tangential"],
            )?,
        };
        if !p_spaces
            .iter()
            .any(|p| u_spaces.iter().any(|&u| p.serves(u)))
        {
            return Err(SceneError::Value(
                "discretization.p_spaces = [\"broken-tangential\"] needs broken u: a continuous u cannot open the crack, so u_spaces must list \"broken\" (or p_spaces \"continuous\")".into(),
            ));
        }
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
        let verification = match self.verification {
            None => Verification::default(),
            Some(v) => v.validate(&u_spaces, &multipliers)?,
        };
        Ok(Scene {
            name,
            description: self.description,
            domain,
            cracks,
            crack_names,
            meshing,
            grading,
            level0,
            f,
            g,
            exact,
            levels,
            u_spaces,
            multipliers,
            p_masses,
            p_spaces,
            deltas,
            fields,
            references,
            verification,
            source: String::new(),
        })
    }
}

/// `[[x, y], [x, y]]`: exactly two points of two numbers each (TOML arrays have any length).
fn two_points(key: &str, v: &[Vec<f64>]) -> Result<[[f64; 2]; 2], SceneError> {
    match v {
        [a, b] if a.len() == 2 && b.len() == 2 => Ok([[a[0], a[1]], [b[0], b[1]]]),
        _ => Err(SceneError::Value(format!(
            "{key} must be two points [[x, y], [x, y]]; got {} point(s) with {:?} coordinates",
            v.len(),
            v.iter().map(Vec::len).take(8).collect::<Vec<_>>()
        ))),
    }
}

/// Domain and cracks of `[geometry]`, validated ([`crate::geometry`]), with each crack's name
/// for messages. A polygon is stored counter-clockwise.
fn validate_geometry(g: GeometryToml) -> Result<(Domain, Vec<Polyline>, Vec<String>), SceneError> {
    let value = |m: String| SceneError::Value(m);
    let Some(domain) = g.domain else {
        return Err(value(
            "geometry.domain is missing: give { rectangle = [[x0, y0], [x1, y1]] } or { polygon = [[x, y], ...] }".into(),
        ));
    };
    let domain = match (domain.rectangle, domain.polygon) {
        (Some(r), None) => {
            let [lo, hi] = two_points("geometry.domain.rectangle", &r)?;
            check_finite_point("geometry.domain.rectangle", lo)?;
            check_finite_point("geometry.domain.rectangle", hi)?;
            if !(hi[0] > lo[0] && hi[1] > lo[1]) {
                return Err(value(format!(
                    "geometry.domain.rectangle [[{}, {}], [{}, {}]] must list the lower-left corner first and have positive width and height",
                    lo[0], lo[1], hi[0], hi[1]
                )));
            }
            Domain::Rectangle(Rectangle { min: lo, max: hi })
        }
        (None, Some(p)) => {
            let points = points_of("geometry.domain.polygon", &p)?;
            crate::geometry::validate_polygon(&points).map_err(|e| value(e.to_string()))?;
            Domain::Polygon(crate::geometry::counter_clockwise(&points))
        }
        _ => {
            return Err(value(
                "geometry.domain must have exactly one of rectangle and polygon".into(),
            ))
        }
    };
    let (cracks, names): (Vec<Polyline>, Vec<String>) = match (g.crack, g.cracks) {
        (Some(c), None) => {
            let (crack, name) = validate_crack(c, "geometry.crack")?;
            (vec![crack], vec![name])
        }
        (None, Some(list)) if !list.is_empty() => list
            .into_iter()
            .enumerate()
            .map(|(i, c)| validate_crack(c, &format!("geometry.cracks[{i}]")))
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .unzip(),
        (None, Some(_)) => {
            return Err(value(
                "geometry.cracks is empty: give at least one crack".into(),
            ))
        }
        (None, None) => {
            return Err(value(
                "missing key `crack` in [geometry]: give crack = { segment = [[xa, ya], [xb, yb]] } or a list cracks = [...]".into(),
            ))
        }
        _ => {
            return Err(value(
                "geometry must have exactly one of crack (a single crack) and cracks (a list)"
                    .into(),
            ))
        }
    };
    let polylines: Vec<Vec<[f64; 2]>> = cracks.iter().map(|c| c.points.clone()).collect();
    crate::geometry::validate_cracks(&domain.polygon(), &polylines).map_err(|e| {
        // name the cracks as the scene does
        let mut m = e.to_string();
        for (i, name) in names.iter().enumerate().rev() {
            m = m.replace(&format!("geometry.cracks[{i}]"), name);
        }
        value(m)
    })?;
    Ok((domain, cracks, names))
}

/// One crack: `{ segment = [a, b] }` or `{ polyline = [x0, x1, ...] }`, and its name.
fn validate_crack(c: CrackToml, at: &str) -> Result<(Polyline, String), SceneError> {
    match (c.segment, c.polyline) {
        (Some(seg), None) => {
            let key = format!("{at}.segment");
            let [a, b] = two_points(&key, &seg)?;
            check_finite_point(&key, a)?;
            check_finite_point(&key, b)?;
            if (Segment { a, b }).length() <= 0.0 {
                return Err(SceneError::Value(format!(
                    "{key} has zero length (its two end points coincide)"
                )));
            }
            let name = if at == "geometry.crack" {
                key
            } else {
                at.to_string()
            };
            Ok((Polyline { points: vec![a, b] }, name))
        }
        (None, Some(line)) => {
            let key = format!("{at}.polyline");
            let points = points_of(&key, &line)?;
            if points.len() < 2 {
                return Err(SceneError::Value(format!(
                    "{key} must have at least two points; got {}",
                    points.len()
                )));
            }
            let name = if at == "geometry.crack" {
                key
            } else {
                at.to_string()
            };
            Ok((Polyline { points }, name))
        }
        _ => Err(SceneError::Value(format!(
            "{at} must have exactly one of segment and polyline"
        ))),
    }
}

/// A list of points `[[x, y], ...]` with finite coordinates.
fn points_of(key: &str, v: &[Vec<f64>]) -> Result<Vec<[f64; 2]>, SceneError> {
    v.iter()
        .map(|p| match p[..] {
            [x, y] => {
                check_finite_point(key, [x, y])?;
                Ok([x, y])
            }
            _ => Err(SceneError::Value(format!(
                "{key} must be a list of points [x, y]; a point has {} coordinate(s)",
                p.len()
            ))),
        })
        .collect()
}

/// `grading = { beta, radius }`: 0 < β ≤ 1, R > 0.
fn validate_grading(g: &GradingToml) -> Result<crate::problem::Grading, SceneError> {
    if !(g.beta.is_finite() && g.beta > 0.0 && g.beta <= 1.0) {
        return Err(SceneError::Value(format!(
            "discretization.grading.beta must be in (0, 1] (1/2 or less for the r^(1/2) crack tip; 1 is uniform); got {}",
            g.beta
        )));
    }
    if !(g.radius.is_finite() && g.radius > 0.0) {
        return Err(SceneError::Value(format!(
            "discretization.grading.radius must be a positive length; got {}",
            g.radius
        )));
    }
    Ok(crate::problem::Grading {
        beta: g.beta,
        radius: g.radius,
    })
}

/// Exactly one of `cells`, `mesh_size` and `mesh`.
fn validate_meshing(d: &DiscretizationToml, base_dir: &Path) -> Result<Meshing, SceneError> {
    match (&d.cells, d.mesh_size, &d.mesh) {
        (Some(c), None, None) => Ok(Meshing::Cells(validate_cells(c)?)),
        (None, Some(h), None) => {
            if !(h.is_finite() && h > 0.0) {
                return Err(SceneError::Value(format!(
                    "discretization.mesh_size must be a positive number; got {h}"
                )));
            }
            Ok(Meshing::MeshSize(h))
        }
        (None, None, Some(m)) => {
            if m.gmsh.is_empty() || m.gmsh.chars().any(char::is_control) {
                return Err(SceneError::Value(format!(
                    "discretization.mesh.gmsh {:?} must be a non-empty file path without control characters",
                    m.gmsh
                )));
            }
            Ok(Meshing::File(base_dir.join(&m.gmsh)))
        }
        _ => Err(SceneError::Value(
            "discretization must have exactly one of cells (structured grid of a rectangle), mesh_size (gmsh) and mesh = { gmsh = \"file.msh\" }".into(),
        )),
    }
}

fn validate_cells(cells: &[i64]) -> Result<[usize; 2], SceneError> {
    let &[nx, ny] = cells else {
        return Err(SceneError::Value(format!(
            "discretization.cells must be two integers [nx, ny]; got {} number(s)",
            cells.len()
        )));
    };
    let cells = [nx, ny];
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

fn validate_levels(levels: &[i64], size: Level0Size) -> Result<Vec<u32>, SceneError> {
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
        check_level(size, l)
            .map_err(|m| SceneError::Value(format!("discretization.levels: {m}")))?;
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
                "{key}: unknown value {n:?} (expected one of {}){hint}",
                known.join(", ")
            ))
        })?;
        if out.contains(&v) {
            return Err(SceneError::Value(format!("{key}: {n:?} is listed twice")));
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
                    "outputs.fields: unknown field {other:?} (expected u, p, lambda){hint}"
                )));
            }
        };
        if *slot {
            return Err(SceneError::Value(format!(
                "outputs.fields: {f:?} is listed twice"
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
                "outputs.references: unknown reference {r:?} (expected dolfinx, freefem){hint}"
            )));
        }
        if out.contains(r) {
            return Err(SceneError::Value(format!(
                "outputs.references: {r:?} is listed twice"
            )));
        }
        out.push(r.clone());
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where a value error points: a key of a table, a dotted key, a key of an inline table, a
    /// key in the second of an array of tables, a table header; nothing for an absent key.
    #[test]
    fn key_positions_in_the_scene_text() {
        let text = "name = \"x\"\n\n[data]\nf = \"1\"\n  g = \"0\"\n[discretization]\n\
                    grading = { beta = 0.5, radius = 0.25 }\nlevels = [0, 1]\n\
                    [[verification.expected_failure]]\nu_space = \"continuous\"\n\
                    [[verification.expected_failure]]\nmultiplier = \"M0\"\nu_space = \"broken\"\n";
        assert_eq!(key_position(text, "name"), Some((1, 1)));
        assert_eq!(key_position(text, "data.f"), Some((4, 1)));
        assert_eq!(key_position(text, "data.g"), Some((5, 3)));
        assert_eq!(key_position(text, "data"), Some((3, 1)));
        assert_eq!(key_position(text, "discretization.grading"), Some((7, 1)));
        assert_eq!(
            key_position(text, "discretization.grading.radius"),
            Some((7, 25))
        );
        assert_eq!(key_position(text, "discretization.levels"), Some((8, 1)));
        assert_eq!(
            key_position(text, "verification.expected_failure[0].u_space"),
            Some((10, 1))
        );
        assert_eq!(
            key_position(text, "verification.expected_failure[1].u_space"),
            Some((13, 1))
        );
        assert_eq!(
            key_position(text, "verification.expected_failure[1]"),
            Some((11, 1))
        );
        assert_eq!(key_position(text, "discretization.deltas"), None);
        assert_eq!(key_position(text, "geometry"), None);
        assert_eq!(
            locate_message("data.g = \"0\" evaluates to NaN".into(), text),
            "data.g = \"0\" evaluates to NaN (at line 5, column 3)"
        );
        assert_eq!(
            locate_message("missing key `cells` in [discretization]".into(), text),
            "missing key `cells` in [discretization] (the table is at line 6, column 1)"
        );
        assert_eq!(locate_message("no key here".into(), text), "no key here");
    }

    /// The template is a valid scene, names every table and key (commented or not), and its
    /// optional tables, uncommented, are valid too.
    #[test]
    fn template_is_a_valid_scene_naming_every_key() {
        let scene = Scene::from_toml(SCENE_TEMPLATE).expect("template parses");
        assert_eq!(scene.name, "my-crack");
        for (table, keys) in TABLE_KEYS {
            let last = table.rsplit('.').next().unwrap_or(table);
            let named = SCENE_TEMPLATE.contains(&format!("[{table}]"))
                || SCENE_TEMPLATE.contains(&format!("{last} = {{"))
                || SCENE_TEMPLATE.contains(&format!("{last} = [{{"));
            assert!(table.is_empty() || named, "template lacks [{table}]");
            for key in *keys {
                assert!(
                    SCENE_TEMPLATE.contains(&format!("{key} ="))
                        || TABLE_KEYS.iter().any(|(t, _)| t.ends_with(key)),
                    "template lacks `{key}` of [{table}]"
                );
            }
        }
        // Uncomment the optional [exact] and expected-failure blocks: still a valid scene.
        let full = SCENE_TEMPLATE
            .replace("# [exact]", "[exact]")
            .replace("# u = \"...\"", "u = \"sin(pi*x)\"")
            .replace("# [[verification", "[[verification")
            .replace("# u_space = ", "u_space = ")
            .replace(
                "u_spaces = [\"broken\"]",
                "u_spaces = [\"continuous\", \"broken\"]",
            )
            .replace("# reason = ", "reason = ")
            .replace("# rate = ", "rate = ")
            .replace("# check = ", "check = ");
        let scene = Scene::from_toml(&full).expect("template with its options parses");
        assert!(scene.exact.is_some());
    }

    /// Peak resident memory measured with `/usr/bin/time -f %M` for
    /// `sdcrack run scenes/mixed.toml --level L --u-space broken --multiplier M1 --delta 0`
    /// (cells [8, 8]; docs/design.md): the estimate must stay above each.
    #[test]
    fn memory_estimate_is_above_measured_peaks_and_admits_the_nightly() {
        for (level, peak_kib) in [(3u32, 135_612u64), (4, 165_316), (5, 507_484)] {
            let estimate = estimated_memory_bytes(Level0Size::Grid([8, 8]), level);
            assert!(
                estimate > peak_kib * 1024,
                "level {level}: estimate {estimate} B below the measured {peak_kib} KiB"
            );
        }
        // ci/nightly runs every repository scene up to level 5: cells [8, 8] and [16, 8].
        for cells in [[8, 8], [16, 8]] {
            for level in 0..=5 {
                assert_eq!(
                    check_level(Level0Size::Grid(cells), level),
                    Ok(()),
                    "{cells:?} level {level}"
                );
            }
        }
        let refused = check_level(Level0Size::Grid([8, 8]), 8).unwrap_err();
        assert!(refused.contains("more than the 16 GiB limit"), "{refused}");
        assert!(check_level(Level0Size::Grid([1, 1]), MAX_LEVEL + 1).is_err());
        assert_eq!(
            estimated_memory_bytes(Level0Size::Grid([4096, 4096]), 64),
            u64::MAX
        );
    }

    #[test]
    fn toml_errors_name_table_key_line_and_column() {
        let scene = DEFAULT_SCENE.replacen("levels =", "levles =", 1);
        let e = Scene::from_toml(&scene).unwrap_err().to_string();
        assert!(
            e.contains("unknown key `levles` in [discretization] at line")
                && e.contains("did you mean `levels`?"),
            "{e}"
        );
        let scene = DEFAULT_SCENE.replacen("cells = [8, 8]", "cells = [8, \"8\"]", 1);
        let e = Scene::from_toml(&scene).unwrap_err().to_string();
        assert!(
            e.contains("discretization.cells must be two integers [nx, ny], not the string \"8\""),
            "{e}"
        );
        assert_eq!(line_column("ab\ncδe", 6), (2, 3));
        assert_eq!(
            line_column("ab\ncδe", 5),
            (2, 2),
            "inside δ: snapped to its start"
        );
        assert_eq!(key_at("x = { rectangle = [1", 18), Some("rectangle".into()));
        assert_eq!(key_at("[data]", 3), None);
        assert_eq!(table_at("a = 1\n[data]\nf = 2\n[x.y]\n", 14), "data");
        assert_eq!(table_at("a = 1\n[data]\n", 2), "");
    }

    #[test]
    fn messages_escape_control_characters() {
        assert_eq!(escape_controls("a\nb\tc"), "a\\nb\\tc");
        assert_eq!(escape_controls("δ ≥ 0"), "δ ≥ 0");
        let scene = DEFAULT_SCENE.replacen("name = \"mixed\"", "name = \"a\\r\\nb\"", 1);
        let e = Scene::from_toml(&scene).unwrap_err().to_string();
        assert!(e.contains(r#"name "a\r\nb" must be"#), "{e}");
        assert!(!e.chars().any(char::is_control), "{e:?}");
    }
}
