//! The validated scene: the problem (Ω, Γc, f, g, the exact solution), how its meshes are made,
//! the case axes of its study, the fields to write and what the verdict may expect.

use super::limits::Level0Size;
use super::verification::Verification;
use crate::case::CaseAxes;
use crate::expr::Expr;
use crate::problem::{Domain, Exact, Meshing, Polyline};

/// Which fields are written to `fields.h5` and the series `fields/*.xdmf` (the results folder
/// keeps all of them in `verification.h5` when this set is not complete).
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

    /// True when u, p and λ are all listed: `fields.h5` then holds everything the compare tool
    /// recomputes the errors from, and no `verification.h5` is written.
    pub fn is_complete(&self) -> bool {
        self.u && self.p && self.lambda
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
    pub domain: Domain,
    /// The cracks Γc, in the scene's order.
    pub cracks: Vec<Polyline>,
    /// How the level-0 mesh is made.
    pub meshing: Meshing,
    /// Grading of every level towards the crack tips (`[discretization] grading`), if any.
    pub grading: Option<crate::problem::Grading>,
    /// The level-0 mesh's size, for memory estimates before meshing.
    pub level0: Level0Size,
    /// Source term f of −Δu = f.
    pub f: Expr,
    /// Dirichlet data g on Γ.
    pub g: Expr,
    /// Exact solution, if the scene has one.
    pub exact: Option<Exact>,
    /// The cases to run: every combination of these values.
    pub axes: CaseAxes,
    /// Fields to write.
    pub fields: FieldSet,
    /// Reference tools to run (`dolfinx`, `freefem`).
    pub references: Vec<String>,
    /// What the verdict may expect of the scene (`[verification]`).
    pub verification: Verification,
}

impl Scene {
    /// The scene's meshes (runs gmsh for a `mesh_size` scene).
    pub fn mesh_source(&self) -> Result<crate::mesh::MeshSource, crate::mesh::MeshError> {
        Ok(
            crate::mesh::MeshSource::new(&self.domain, &self.cracks, &self.meshing)?
                .graded(self.grading),
        )
    }
}
