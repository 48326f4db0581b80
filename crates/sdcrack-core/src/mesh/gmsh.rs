//! Coarse triangulations of cracked polygonal domains: made by the `gmsh` binary from a
//! generated `.geo` script, and read from ASCII `.msh` files (format 4.1 or 2.2).
//!
//! Physical group convention (both for generated and for user-supplied meshes):
//! the triangles are the 3-node triangles of the 2D physical groups (gmsh writes
//! `"domain"`), the 1D physical group `"boundary"` holds every edge of the outer boundary
//! ∂Ω, and the 1D physical groups `"crack1"`, `"crack2"`, … (numbered consecutively from 1)
//! each hold one crack as an open chain of mesh edges that touches neither ∂Ω nor
//! another crack.

use std::path::Path;

use coarse::assemble;
use msh::{parse_msh, RawNode};

/// A coarse conforming triangulation of a planar domain Ω with cracks embedded as chains of
/// mesh edges.
///
/// Conventions:
/// * `vertices` holds only the nodes used by triangles, numbered `0..n` in the order of the
///   file's `$Nodes` section;
/// * every triangle is counter-clockwise (strictly positive signed area);
/// * every edge of the outer boundary ∂Ω appears once in `boundary_edges`, oriented so that
///   Ω lies on its left (as the edge appears in its unique counter-clockwise triangle);
/// * `cracks[c]` is the physical group `crack{c+1}` as the ordered chain of vertex numbers
///   from its first tip to its last tip; a crack is an ordinary interior edge chain of the
///   triangulation here (the mesh is not cut along it).
#[derive(Debug, Clone, PartialEq)]
pub struct CoarseMesh {
    /// Vertex coordinates (x, y); only vertices used by triangles, in gmsh node order.
    pub vertices: Vec<[f64; 2]>,
    /// Triangles as vertex numbers, counter-clockwise.
    pub triangles: Vec<[usize; 3]>,
    /// Edges of ∂Ω as vertex numbers, oriented with Ω on the left, in the file order of the
    /// `"boundary"` group's line elements.
    pub boundary_edges: Vec<[usize; 2]>,
    /// Crack `c` (physical group `crack{c+1}`) as the chain of vertex numbers from its first
    /// tip to its last tip. The chain runs in the stored direction (node a → node b) of the
    /// group's first line element in the file; for meshes made by [`mesh_polygon`] this is
    /// from the polyline's first point to its last.
    pub cracks: Vec<Vec<usize>>,
}

/// What one run of the `gmsh` binary did.
#[derive(Debug, Clone)]
pub struct GmshRun {
    /// The output of `gmsh --version`, trimmed (e.g. `4.8.4`).
    pub version: String,
    /// Wall-clock seconds of the meshing call (process start to exit).
    pub seconds: f64,
    /// The ASCII msh 4.1 text gmsh produced.
    pub msh_text: String,
}

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
    /// The polygon, cracks or mesh size given to [`mesh_polygon`] cannot be meshed.
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

type Result<T> = std::result::Result<T, GmshError>;

mod coarse;
mod msh;
mod run;
#[cfg(test)]
mod tests;

pub use run::{geo_script, gmsh_version, mesh_polygon};

fn io_error(path: &Path, e: &std::io::Error) -> GmshError {
    GmshError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

// ---------------------------------------------------------------------------------------
// Reading .msh files
// ---------------------------------------------------------------------------------------

/// Reads an ASCII gmsh mesh (format 4.1 or 2.2, with `$PhysicalNames`) into a [`CoarseMesh`];
/// `origin` names the file in error messages.
///
/// Requirements (each violation is a [`GmshError`] naming the file and the group):
/// * a 1D physical group named `"boundary"` whose edges are exactly the edges that belong to
///   one triangle only (the outer boundary ∂Ω);
/// * 1D physical groups `crack1`, `crack2`, … (at least one, numbered consecutively from 1),
///   each made of 2-node lines forming one simple open chain of triangle edges, touching
///   neither ∂Ω nor another crack;
/// * triangles: the 3-node triangles (type 2) of the 2D physical groups, or every type-2
///   element if no 2D element has a physical group; any other 2D element type is an error;
/// * all nodes in the plane z = 0; node tags may be non-contiguous; no parametric
///   coordinates; binary files are refused.
///
/// Other physical groups and 0D elements are ignored.
pub fn read_msh(text: &str, origin: &str) -> Result<CoarseMesh> {
    read_msh_snapped(text, origin, &[])
}

/// Reads an ASCII `.msh` file from disk with [`read_msh`] (the path is the origin); invalid
/// UTF-8 is replaced, so binary files reach the binary-format error.
pub fn read_msh_file(path: &Path) -> Result<CoarseMesh> {
    let bytes = std::fs::read(path).map_err(|e| io_error(path, &e))?;
    read_msh(
        &String::from_utf8_lossy(&bytes),
        &path.display().to_string(),
    )
}

fn read_msh_snapped(text: &str, origin: &str, exact: &[[f64; 2]]) -> Result<CoarseMesh> {
    let mut raw = parse_msh(text, origin)?;
    snap_nodes(&mut raw.nodes, exact);
    assemble(&raw, origin)
}

/// Gives the node nearest to each exact point that point's coordinates, if it is within
/// rounding distance (gmsh prints 16 significant digits, not the 17 of a round trip).
fn snap_nodes(nodes: &mut [RawNode], exact: &[[f64; 2]]) {
    let scale = exact.iter().flatten().fold(1.0_f64, |m, v| m.max(v.abs()));
    let tol = 1e-12 * scale;
    for p in exact {
        let nearest = nodes.iter_mut().min_by(|a, b| {
            let (da, db) = (dist(a.xy, *p), dist(b.xy, *p));
            da.total_cmp(&db)
        });
        if let Some(node) = nearest.filter(|n| dist(n.xy, *p) <= tol) {
            node.xy = *p;
        }
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

// ---- raw file content ------------------------------------------------------------------
// ---- from raw content to the coarse mesh -------------------------------------------------

/// At most 40 characters of file content, for messages.
fn snippet(text: &str) -> String {
    match text.char_indices().nth(40) {
        Some((cut, _)) => format!("{}…", &text[..cut]),
        None => text.to_string(),
    }
}

fn malformed(origin: &str, section: &str, line: usize, detail: impl Into<String>) -> GmshError {
    GmshError::Malformed {
        origin: origin.to_string(),
        section: format!("${section}"),
        line,
        detail: detail.into(),
    }
}

fn unsupported(origin: &str, message: String) -> GmshError {
    GmshError::Unsupported {
        origin: origin.to_string(),
        message,
    }
}

fn invalid(origin: &str, message: String) -> GmshError {
    GmshError::Invalid {
        origin: origin.to_string(),
        message,
    }
}
