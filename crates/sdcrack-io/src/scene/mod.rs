//! Scene files: the TOML description of one crack problem and its study (docs/scenes.md).
//!
//! Owns reading a scene ([`TomlScene`]) and its errors ([`SceneError`], one line each, naming
//! the key with its line and column). The parts: the serde structs that are the one scene schema
//! (`raw`), the schema derived from them ([`schema`], what `sdcrack schema` prints), their
//! validation into sdcrack-core's [`Scene`] (`validate`, [`verification`]: unknown keys
//! rejected with a "did you mean", expressions parsed once into [`Expr`] trees, every number
//! checked), positions in the text (`position`) and toml's errors in words (`toml_error`).
//! Geometry that depends on the mesh (crack on mesh lines, inside Ω) is checked by
//! [`crate::mesh`]. Everything downstream works on the validated [`Scene`], never on raw TOML.

mod position;
mod raw;
pub mod schema;
#[cfg(test)]
mod tests;
mod toml_error;
mod validate;
pub mod verification;

use std::path::Path;

pub use crate::did_you_mean::suggest;
pub use crate::one_line::escape_controls;
use position::{key_position, line_column, locate_message};

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
    check_level, estimated_memory_bytes, estimated_memory_bytes_of_cells,
    estimated_mesh_memory_bytes, exact_data, ExpectedFailure, FieldSet, Level0Size, Scene,
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
        let raw: raw::SceneToml = toml::from_str(text)
            .map_err(|e| SceneError::Toml(toml_error::toml_message(&e, text)))?;
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
