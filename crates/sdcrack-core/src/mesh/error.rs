//! [`MeshError`]: why the meshes of a scene cannot be made, naming the crack concerned.

use super::bisect;

/// Errors in building a mesh for a scene. `crack` is the 0-based index of the scene's crack.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    /// A crack point is not a vertex of the level-0 grid.
    #[error("crack point ({x}, {y}) is not a vertex of the level-0 mesh (cells {nx}×{ny}); move it onto the grid or change discretization.cells")]
    OffMesh {
        /// Which crack.
        crack: usize,
        /// x of the point.
        x: f64,
        /// y of the point.
        y: f64,
        /// Level-0 cells in x.
        nx: usize,
        /// Level-0 cells in y.
        ny: usize,
    },
    /// A crack point lies outside Ω or on Γ.
    #[error("crack point ({x}, {y}) {what}; the crack must lie strictly inside the domain")]
    NotInside {
        /// Which crack.
        crack: usize,
        /// x of the point.
        x: f64,
        /// y of the point.
        y: f64,
        /// "lies outside the domain" or "touches the boundary".
        what: &'static str,
    },
    /// A crack segment is not along a grid line.
    #[error("crack segment from ({ax}, {ay}) to ({bx}, {by}) is not along a mesh line: on a structured grid it must be horizontal, vertical or along the SW–NE cell diagonals (use mesh_size for any direction)")]
    NotOnMeshLine {
        /// Which crack.
        crack: usize,
        /// Start x.
        ax: f64,
        /// Start y.
        ay: f64,
        /// End x.
        bx: f64,
        /// End y.
        by: f64,
    },
    /// Two cracks share a grid vertex or edge.
    #[error("cracks {first} and {second} share the mesh vertex ({x}, {y}); cracks must not touch")]
    Touching {
        /// The first crack.
        first: usize,
        /// The second crack.
        second: usize,
        /// x of the vertex.
        x: f64,
        /// y of the vertex.
        y: f64,
    },
    /// `cells` with a polygon domain.
    #[error("discretization.cells needs a rectangle domain; give discretization.mesh_size for a polygon")]
    CellsNeedRectangle,
    /// gmsh failed, or a .msh file is not usable.
    #[error("{0}")]
    Gmsh(String),
    /// The cracks of a .msh file do not match the scene's.
    #[error("{0}")]
    Mismatch(String),
    /// A graded level could not be built.
    #[error(transparent)]
    Grading(#[from] bisect::GradingError),
}

impl MeshError {
    /// The scene crack an error is about, if any (the caller names it as the scene does).
    pub fn crack(&self) -> Option<usize> {
        match self {
            MeshError::OffMesh { crack, .. }
            | MeshError::NotInside { crack, .. }
            | MeshError::NotOnMeshLine { crack, .. } => Some(*crack),
            _ => None,
        }
    }
}
