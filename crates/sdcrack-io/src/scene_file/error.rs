//! The errors of a scene ([`SceneError`], one line each) and how their messages name a key
//! ([`KeyRole`]) and a crack ([`CrackName`]).

use std::path::PathBuf;

use super::position::{key_position, Position};
use crate::one_line::escape_controls;
use sdcrack_core::expr::ExprError;
use sdcrack_core::scene::KeyPath;

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
