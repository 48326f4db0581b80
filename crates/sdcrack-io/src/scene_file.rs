//! Scene files: the TOML description of one crack problem and its study (docs/scenes.md).
//!
//! Owns reading a scene ([`LoadedScene`]: the validated scene beside its text, and
//! [`TomlScene`] for the users that want the scene only) and its errors ([`SceneError`], one
//! line each, naming the key with its line and column). The parts: the serde structs that are
//! the one scene schema (`raw`), the schema derived from them ([`schema`], what `sdcrack schema`
//! prints), the document read into the structs with every error as data (`document`), their
//! validation into sdcrack-core's [`Scene`] (`validate`, [`verification`]: unknown keys
//! rejected with a "did you mean", expressions parsed once into [`Expr`] trees, every number
//! checked), positions in the text (`position`) and the read errors in words (`toml_error`).
//! An error about a key carries the key as a [`KeyPath`]; its line and column are added once,
//! from the key path and the spans of the text ([`SceneError::located`]). Geometry that depends
//! on the mesh (crack on mesh lines, inside Ω) is checked by [`sdcrack_core::mesh`]
//! ([`LoadedScene::mesh_error`] names the crack). Everything downstream works on the validated
//! [`Scene`], never on raw TOML.

mod document;
mod position;
mod raw;
pub mod schema;
#[cfg(test)]
mod tests;
mod toml_error;
mod validate;
pub mod verification;

use std::path::{Path, PathBuf};

use crate::did_you_mean::suggest;
use crate::one_line::escape_controls;
pub use position::Position;
use position::{key_position, line_column};

use sdcrack_core::expr::ExprError;
use sdcrack_core::scene::KeyPath;
use sdcrack_core::scene::Scene;

/// The commented scene template printed by `sdcrack scene --template` (a valid, small scene).
pub const SCENE_TEMPLATE: &str = include_str!("../../../docs/scene-template.toml");

/// The embedded default scene (`sdcrack run` without argument): a partly open, partly closed crack.
pub const DEFAULT_SCENE: &str = include_str!("../../../scenes/mixed.toml");

/// Errors found while reading or validating a scene. An error about a key carries the key as a
/// [`KeyPath`] and, once [`SceneError::located`] in the scene's text, the key's line and column.
#[derive(Debug)]
pub enum SceneError {
    /// The scene file could not be read.
    Read {
        /// File that was asked for.
        path: String,
        /// Operating-system reason.
        reason: String,
    },
    /// Malformed TOML, wrong types, missing or unknown keys (the message says where).
    Toml(String),
    /// An expression does not parse.
    Expression {
        /// Scene key holding the expression (e.g. `data.f`).
        key: KeyPath,
        /// The expression text.
        source_text: String,
        /// Parser error with its column.
        error: ExprError,
        /// Where the key is in the scene file.
        at: Option<Position>,
    },
    /// An error about a key: the key, how the message shows it ([`KeyRole`]), what is wrong.
    Key {
        /// The key (or table) the error is about.
        key: KeyPath,
        /// How the message shows the key.
        role: KeyRole,
        /// What is wrong, written after the key (or, for [`KeyRole::Named`], the whole message).
        message: String,
        /// Where the key is in the scene file.
        at: Option<Position>,
    },
    /// A message about the whole scene (its size) or a part of it no key writes (a crack of a
    /// mesh file).
    Scene(String),
    /// An error of the scene file `path` (the message then names the file).
    InFile {
        /// The scene file.
        path: String,
        /// What is wrong in it.
        error: Box<SceneError>,
    },
}

/// How a [`SceneError::Key`] shows its key, and what its line and column are.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum KeyRole {
    /// A value out of its range: `key`, then the message (`: level 13 is outside 0..=12`,
    /// ` = -1 must be a finite number > 0`, ` is empty: …`); at the key.
    Value,
    /// A table that must not be there, or must be: `[key]`, then the message; at its header.
    Table,
    /// A key the table `key` lacks: ``missing key `NAME` in [key]``, then the message; at the
    /// table, `(the table is at line L, column C)`.
    Missing(String),
    /// A message of sdcrack-core's that names the key in its own words (a crack that crosses
    /// the domain, exact data that is not a solution); at the key.
    Named,
}

impl std::error::Error for SceneError {}

impl std::fmt::Display for SceneError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SceneError::Read { path, reason } => write!(
                f,
                "cannot read scene file {}: {}",
                escape_controls(path),
                escape_controls(reason)
            ),
            SceneError::InFile { path, error } => match **error {
                SceneError::Read { .. } | SceneError::InFile { .. } => write!(f, "{error}"),
                _ => write!(
                    f,
                    "invalid scene {}: {}",
                    escape_controls(path),
                    error.detail()
                ),
            },
            // an expression's message names what it is
            SceneError::Expression { .. } => write!(f, "{}", self.detail()),
            _ => write!(f, "invalid scene: {}", self.detail()),
        }
    }
}

/// ` (at line L, column C)`, or nothing where the key is not written.
fn at_words(at: &Option<Position>) -> String {
    at.map(|(l, c)| format!(" (at line {l}, column {c})"))
        .unwrap_or_default()
}

impl SceneError {
    /// What is wrong, after `invalid scene …: `.
    fn detail(&self) -> String {
        match self {
            SceneError::Toml(m) | SceneError::Scene(m) => m.clone(),
            SceneError::Expression {
                key,
                source_text,
                error,
                at,
            } => format!(
                "invalid expression in {key} = {source_text:?}: {}{}",
                escape_controls(&error.to_string()),
                at_words(at)
            ),
            SceneError::Key {
                key,
                role,
                message,
                at,
            } => match role {
                KeyRole::Value => format!("{key}{message}{}", at_words(at)),
                KeyRole::Table => format!("[{key}]{message}{}", at_words(at)),
                KeyRole::Missing(name) => format!(
                    "missing key `{name}` in [{key}]{message}{}",
                    at.map(|(l, c)| format!(" (the table is at line {l}, column {c})"))
                        .unwrap_or_default()
                ),
                KeyRole::Named => format!("{message}{}", at_words(at)),
            },
            SceneError::Read { .. } | SceneError::InFile { .. } => self.to_string(),
        }
    }

    /// An error about `key` shown as `role` says.
    pub fn key(key: KeyPath, role: KeyRole, message: impl Into<String>) -> SceneError {
        SceneError::Key {
            key,
            role,
            message: message.into(),
            at: None,
        }
    }

    /// A value error: `key`, then `message`.
    pub fn value(key: KeyPath, message: impl Into<String>) -> SceneError {
        SceneError::key(key, KeyRole::Value, message)
    }

    /// A message of the core's naming its `key` in its own words.
    pub fn named(key: KeyPath, message: impl Into<String>) -> SceneError {
        SceneError::key(key, KeyRole::Named, message)
    }

    /// This error with the line and column of its key (or table) in the scene `text`, where the
    /// text writes it: the one place a position is added to a message about a key.
    pub fn located(self, text: &str) -> SceneError {
        let at = |key: &KeyPath| key_position(text, key);
        match self {
            SceneError::Expression {
                key,
                source_text,
                error,
                at: _,
            } => SceneError::Expression {
                at: at(&key),
                key,
                source_text,
                error,
            },
            SceneError::Key {
                key, role, message, ..
            } => SceneError::Key {
                at: at(&key),
                key,
                role,
                message,
            },
            SceneError::InFile { path, error } => SceneError::InFile {
                path,
                error: Box::new(error.located(text)),
            },
            other => other,
        }
    }
}

/// Largest number of level-0 cells per direction.
pub const MAX_CELLS: usize = 4096;
/// Largest scene file accepted, in bytes (1 MiB; the repository's scenes are under 2 KiB).
pub const MAX_SCENE_BYTES: usize = 1 << 20;

/// Reference tools the project knows how to run.
pub const KNOWN_REFERENCES: [&str; 2] = ["dolfinx", "freefem"];

/// A scene as read: the validated [`Scene`] (sdcrack-core's, format-free), the TOML text it was
/// read from (copied byte for byte into a results folder, and where messages find a key's line
/// and column) and the file, if any.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The validated scene.
    pub scene: Scene,
    /// The scene's TOML text as read.
    pub text: String,
    /// The scene file; None for a text (the embedded default scene).
    pub path: Option<PathBuf>,
    /// Where each crack of the scene is written, in the scene's order.
    cracks: Vec<CrackName>,
}

/// How messages name a crack: by its key (`geometry.crack.segment`, `geometry.cracks[1]`), or,
/// for a crack of a mesh file, by its number and file.
#[derive(Clone, Debug)]
pub(crate) enum CrackName {
    /// A crack written in `[geometry]`.
    Key(KeyPath),
    /// Crack `number` (1-based) of the mesh file `file`.
    MeshFile {
        /// 1-based.
        number: usize,
        /// The mesh file, as the scene gives it (relative to the scene's folder).
        file: PathBuf,
    },
}

impl std::fmt::Display for CrackName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CrackName::Key(k) => write!(f, "{k}"),
            CrackName::MeshFile { number, file } => {
                write!(f, "crack{number} of {}", file.display())
            }
        }
    }
}

impl LoadedScene {
    /// Reads and validates a scene file; errors name the file.
    ///
    /// Refuses directories, files over [`MAX_SCENE_BYTES`] (without reading more than that) and
    /// text that is not UTF-8.
    pub fn from_file(path: &Path) -> Result<LoadedScene, SceneError> {
        let shown = path.display().to_string();
        let text = read_scene_file(path)?;
        let base_dir = path.parent().unwrap_or(Path::new("."));
        let mut loaded =
            LoadedScene::from_toml_in(&text, base_dir).map_err(|error| SceneError::InFile {
                path: shown,
                error: Box::new(error),
            })?;
        loaded.path = Some(path.to_path_buf());
        Ok(loaded)
    }

    /// The embedded default scene.
    pub fn default_scene() -> LoadedScene {
        // The embedded text is validated by a unit test; failing here is a build defect.
        LoadedScene::from_toml_in(DEFAULT_SCENE, Path::new("."))
            .expect("embedded default scene is valid")
    }

    /// Parses and validates scene TOML text, reading a `discretization.mesh` file relative to
    /// `base_dir`. Errors about a key carry its line and column in `text`.
    pub fn from_toml_in(text: &str, base_dir: &Path) -> Result<LoadedScene, SceneError> {
        if text.len() > MAX_SCENE_BYTES {
            return Err(SceneError::Scene(format!(
                "the scene has {} bytes, more than the 1 MiB ({MAX_SCENE_BYTES} bytes) a scene may have",
                text.len()
            )));
        }
        if text.trim().is_empty() {
            return Err(SceneError::Toml(
                "the scene is empty; it needs at least name, [geometry], [data] and [discretization] (see scenes/mixed.toml)".into(),
            ));
        }
        let doc = toml_edit::ImDocument::parse(text)
            .map_err(|e| SceneError::Toml(toml_error::syntax_message(&e, text)))?;
        let raw: raw::SceneToml = document::from_document(&doc)
            .map_err(|e| SceneError::Toml(toml_error::raw_message(&e, text)))?;
        let (scene, cracks) = raw.validate(base_dir).map_err(|e| e.located(text))?;
        Ok(LoadedScene {
            scene,
            text: text.to_string(),
            path: None,
            cracks,
        })
    }

    /// `error`, found after the scene was read (a crack off a finer mesh, exact data that is
    /// not a solution), with its key's line and column in the scene's text.
    pub fn locate(&self, error: SceneError) -> SceneError {
        error.located(&self.text)
    }

    /// A mesh error of this scene, at the key it concerns (which [`LoadedScene::locate`]
    /// finds): the crack, named as the scene does, or `discretization.cells` for cells given
    /// with a polygon.
    pub fn mesh_error(&self, e: &sdcrack_core::mesh::MeshError) -> SceneError {
        if let sdcrack_core::mesh::MeshError::CellsNeedRectangle = e {
            return SceneError::named(KeyPath::keys("discretization.cells"), e.to_string());
        }
        match e.crack().and_then(|c| self.cracks.get(c)) {
            Some(CrackName::Key(key)) => SceneError::value(key.clone(), format!(": {e}")),
            Some(name @ CrackName::MeshFile { .. }) => SceneError::Scene(format!("{name}: {e}")),
            None => SceneError::Scene(e.to_string()),
        }
    }
}

/// The text of the scene file `path`, refusing directories, files over [`MAX_SCENE_BYTES`]
/// (without reading more than that) and text that is not UTF-8.
fn read_scene_file(path: &Path) -> Result<String, SceneError> {
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
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let (line, column) = line_column(&String::from_utf8_lossy(&e.into_bytes()), at);
        read_error(format!(
            "it is not UTF-8 text (invalid byte at line {line}, column {column})"
        ))
    })
}

/// A [`Scene`]'s TOML format, for the users that want the validated scene only: reading and
/// validating a scene file or text through [`LoadedScene`]. The scene struct is sdcrack-core's
/// (format-free); bring this trait into scope with it (`use sdcrack::scene::{Scene,
/// TomlScene}`) to call `Scene::from_file` and the rest.
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
}

impl TomlScene for Scene {
    fn from_file(path: &Path) -> Result<Scene, SceneError> {
        LoadedScene::from_file(path).map(|l| l.scene)
    }

    const SCENE_TEMPLATE: &'static str = include_str!("../../../docs/scene-template.toml");

    fn default_scene() -> Scene {
        LoadedScene::default_scene().scene
    }

    fn from_toml(text: &str) -> Result<Scene, SceneError> {
        Scene::from_toml_in(text, Path::new("."))
    }

    fn from_toml_in(text: &str, base_dir: &Path) -> Result<Scene, SceneError> {
        LoadedScene::from_toml_in(text, base_dir).map(|l| l.scene)
    }
}
