//! [`GmshError`], the error of meshing with gmsh and of reading `.msh` files, with the
//! constructors of its messages and the crate's `Result` over it.

use std::path::Path;

/// Errors of meshing with gmsh and of reading `.msh` files; every message is one line and
/// names the file (or the gmsh call) it is about.
#[derive(Debug, thiserror::Error)]
pub enum GmshError {
    /// The `gmsh` binary is not on `PATH`.
    #[error(
        "gmsh is not installed (apt-get install gmsh); it meshes scenes with a polygon domain or mesh_size"
    )]
    NotInstalled,
    /// Reading or writing a file, or starting gmsh, failed.
    #[error("{path}: {message}")]
    Io {
        /// The file (or program) concerned.
        path: String,
        /// The operating system's message.
        message: String,
    },
    /// gmsh exited with a failure status.
    #[error("gmsh failed on {path} ({status}): {message}")]
    Failed {
        /// The `.geo` file given to gmsh.
        path: String,
        /// The exit status, as the OS reports it.
        status: String,
        /// gmsh's first error line (the cause; later ones are usually consequences).
        message: String,
    },
    /// The polygon, cracks or mesh size given to [`mesh_polygon`](super::mesh_polygon) cannot be meshed.
    #[error("cannot mesh the polygon: {0}")]
    Input(String),
    /// A `.msh` section does not follow the format.
    #[error("{origin}: malformed {section} section at line {line}: {detail}")]
    Malformed {
        /// The file name.
        origin: String,
        /// The section name with its `$`, e.g. `$Nodes`.
        section: String,
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong there.
        detail: String,
    },
    /// A `.msh` feature that is not read (binary files, other versions, other element types).
    #[error("{origin}: {message}")]
    Unsupported {
        /// The file name.
        origin: String,
        /// What is not supported.
        message: String,
    },
    /// A well-formed `.msh` file that breaks a requirement on the mesh or its physical groups.
    #[error("{origin}: {message}")]
    Invalid {
        /// The file name.
        origin: String,
        /// Which requirement is broken, naming the physical group concerned.
        message: String,
    },
}

pub(super) type Result<T> = std::result::Result<T, GmshError>;

pub(super) fn io_error(path: &Path, e: &std::io::Error) -> GmshError {
    GmshError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// At most 40 characters of file content, for messages.
pub(super) fn snippet(text: &str) -> String {
    match text.char_indices().nth(40) {
        Some((cut, _)) => format!("{}…", &text[..cut]),
        None => text.to_string(),
    }
}

pub(super) fn malformed(
    origin: &str,
    section: &str,
    line: usize,
    detail: impl Into<String>,
) -> GmshError {
    GmshError::Malformed {
        origin: origin.to_string(),
        section: format!("${section}"),
        line,
        detail: detail.into(),
    }
}

pub(super) fn unsupported(origin: &str, message: String) -> GmshError {
    GmshError::Unsupported {
        origin: origin.to_string(),
        message,
    }
}

pub(super) fn invalid(origin: &str, message: String) -> GmshError {
    GmshError::Invalid {
        origin: origin.to_string(),
        message,
    }
}
