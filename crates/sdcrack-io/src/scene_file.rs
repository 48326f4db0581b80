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
//! The errors (`error`) and the limits (`limits`) are the parts' common ground; reading a
//! scene, from its text to the validated scene, is `load`.
//!
//! [`Scene`]: sdcrack_core::scene::Scene
//! [`KeyPath`]: sdcrack_core::scene::KeyPath
//! [`Expr`]: sdcrack_core::expr::Expr

mod document;
mod elastic;
mod error;
mod limits;
mod load;
mod position;
mod raw;
pub mod schema;
#[cfg(test)]
mod tests;
mod toml_error;
mod validate;
pub mod verification;

pub use error::{KeyRole, SceneError};
pub use limits::{MAX_CELLS, MAX_SCENE_BYTES};
pub use load::{LoadedScene, TomlScene, DEFAULT_SCENE, ELASTIC_SCENE_TEMPLATE, SCENE_TEMPLATE};
pub use position::Position;
pub use schema::KNOWN_REFERENCES;
