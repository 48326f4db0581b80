//! The validated scene: the problem (Ω, Γc, and the problem kind's data: f, g and the exact
//! solution of the scalar problem, or the elastic problem's material and loads), how its meshes
//! are made, the case axes of its study, the fields to write and what the verdict may expect.

use super::limits::Level0Size;
use super::verification::Verification;
use crate::case::CaseAxes;
use crate::elasticity::ElasticData;
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

/// The scalar problem's data: −Δu = f in Ω \ Γc, u = g on Γ, the contact conditions on Γc.
#[derive(Clone, Debug)]
pub struct ScalarProblem {
    /// Source term f of −Δu = f.
    pub f: Expr,
    /// Dirichlet data g on Γ.
    pub g: Expr,
    /// Exact solution, if the scene has one.
    pub exact: Option<Exact>,
}

/// The problem a scene poses on Ω \ Γc (`[problem] kind`): its data.
#[derive(Clone, Debug)]
pub enum Problem {
    /// The scalar problem (the default kind, `"scalar"`).
    Scalar(ScalarProblem),
    /// Linear elasticity with frictionless contact on the crack faces (`"elasticity"`,
    /// docs/elasticity.md).
    Elasticity(ElasticData),
}

/// The problem kinds of `[problem] kind`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProblemKind {
    /// −Δu = f with unilateral contact: the problem the smooth-domain solver solves.
    #[default]
    Scalar,
    /// Linear elasticity with frictionless non-penetration (docs/elasticity.md).
    Elasticity,
}

crate::scene_names!(ProblemKind { Scalar => "scalar", Elasticity => "elasticity" });

impl ProblemKind {
    /// Whether a case of this kind has the scalar method's axes (u space, p mass, p space):
    /// the elastic (AFW) method has none of them ([`crate::case`]).
    pub fn has_scalar_axes(self) -> bool {
        self == ProblemKind::Scalar
    }

    /// Whether a case key of this kind names its kind in the results files: every kind but the
    /// scalar one, whose files stay as they were before the axis ([`crate::case`]).
    pub fn is_named_in_keys(self) -> bool {
        self != ProblemKind::Scalar
    }
}

impl Problem {
    /// Which kind it is.
    pub fn kind(&self) -> ProblemKind {
        match self {
            Problem::Scalar(_) => ProblemKind::Scalar,
            Problem::Elasticity(_) => ProblemKind::Elasticity,
        }
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
    /// The problem posed and its data.
    pub problem: Problem,
    /// The cases to run: every combination of these values (an elastic scene: its levels only,
    /// the other axes empty, so no solver case until its solver exists, issue 46).
    pub axes: CaseAxes,
    /// Fields to write.
    pub fields: FieldSet,
    /// Reference tools to run (`dolfinx`, `freefem`).
    pub references: Vec<String>,
    /// What the verdict may expect of the scene (`[verification]`).
    pub verification: Verification,
}

impl Scene {
    /// Whether the scene gives exact fields (`[exact]`), whatever its problem kind.
    pub fn has_exact(&self) -> bool {
        match &self.problem {
            Problem::Scalar(p) => p.exact.is_some(),
            Problem::Elasticity(d) => d.exact.is_some(),
        }
    }

    /// The scalar problem's data; `None` for an elastic scene.
    pub fn scalar(&self) -> Option<&ScalarProblem> {
        match &self.problem {
            Problem::Scalar(p) => Some(p),
            Problem::Elasticity(_) => None,
        }
    }

    /// The scalar problem's data, to change; `None` for an elastic scene.
    pub fn scalar_mut(&mut self) -> Option<&mut ScalarProblem> {
        match &mut self.problem {
            Problem::Scalar(p) => Some(p),
            Problem::Elasticity(_) => None,
        }
    }

    /// The elastic problem's data; `None` for a scalar scene.
    pub fn elasticity(&self) -> Option<&ElasticData> {
        match &self.problem {
            Problem::Elasticity(d) => Some(d),
            Problem::Scalar(_) => None,
        }
    }

    /// The scene's meshes (runs gmsh for a `mesh_size` scene).
    pub fn mesh_source(&self) -> Result<crate::mesh::MeshSource, crate::mesh::MeshError> {
        Ok(
            crate::mesh::MeshSource::new(&self.domain, &self.cracks, &self.meshing)?
                .graded(self.grading),
        )
    }
}
