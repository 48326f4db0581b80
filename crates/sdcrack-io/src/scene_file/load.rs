//! Reading a scene: the text of a scene file or the embedded default, parsed, read into the
//! serde structs and validated into sdcrack-core's [`Scene`] ([`LoadedScene`], [`TomlScene`]).

use std::path::{Path, PathBuf};

use super::error::{CrackName, SceneError};
use super::limits::MAX_SCENE_BYTES;
use super::position::line_column;
use super::{document, raw, toml_error};
use sdcrack_core::scene::KeyPath;
use sdcrack_core::scene::Scene;

/// The commented scene template printed by `sdcrack scene --template` (a valid, small scene).
pub const SCENE_TEMPLATE: &str = include_str!("../../../../docs/scene-template.toml");

/// The commented elastic scene template printed by `sdcrack scene --template elasticity` (a
/// valid, small elastic scene naming every key of the elastic problem kind).
pub const ELASTIC_SCENE_TEMPLATE: &str =
    include_str!("../../../../docs/scene-template-elasticity.toml");

/// The embedded default scene (`sdcrack run` without argument): a partly open, partly closed crack.
pub const DEFAULT_SCENE: &str = include_str!("../../../../scenes/mixed.toml");

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

    const SCENE_TEMPLATE: &'static str = include_str!("../../../../docs/scene-template.toml");

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
