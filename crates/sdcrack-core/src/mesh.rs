//! Triangulations of the domain with the cracks as chains of mesh edges, their nested levels,
//! and the two u-space topologies (docs/design.md).
//!
//! A level's [`Mesh`] comes from a [`MeshSource`]: the structured grid of a rectangle
//! ([`structured`]: level ℓ has `2^ℓ·nx × 2^ℓ·ny` cells split by their SW–NE diagonals) or a
//! coarse triangulation (gmsh's, [`gmsh`]) refined uniformly ℓ times ([`refine`]: each triangle
//! into four, so levels are nested). Either way every crack is a chain of mesh vertices
//! `x_0 … x_I` (its ends first and last) joined by mesh edges, each edge lying on one segment of
//! the crack's polyline. An end strictly inside Ω is a *tip*; an end on ∂Ω (an edge crack of an
//! elastic scene, docs/elasticity.md) is a *mouth*, marked in [`CrackChain::mouths`].
//!
//! Sides: each crack edge carries the normal ν of its polyline segment (direction turned by
//! +90°). At an interior crack node v with neighbours a (before) and b (after) on the chain, a
//! triangle corner at v lies on the **+** face when the triangle is on the left of the path
//! a → v → b (for a straight crack: its centroid c has (c − v)·ν > 0). For the `broken` u space
//! every interior crack node (tips excluded) carries a second u degree of freedom, used by the
//! triangle corners on the − face; the vertex number itself serves the + face. That numbering
//! *is* the cracked mesh of the references (docs/design.md). A mouth is doubled like an interior
//! node (its − copy numbered with the interior nodes, in chain order); its corners take their
//! face from the crack's straight continuation through it, and so do the two boundary edges at
//! it ([`Mesh::boundary_edge_dofs`]).

pub mod bisect;
mod boundary_parts;
mod error;
pub mod gmsh;
pub mod refine;
mod source;
pub mod structured;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_mouths;
mod triangulation;

pub use boundary_parts::{BoundaryParts, RECTANGLE_PARTS};
pub use error::MeshError;
pub use source::{msh_file_geometry, msh_file_geometry_with, CoarseProvenance, MeshSource};
pub use triangulation::{
    centroid, frame_directions, CrackChain, Layout, Mesh, PCorner, PTopology, Side, UTopology,
};
