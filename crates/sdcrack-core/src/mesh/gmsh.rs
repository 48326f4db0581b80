//! Coarse triangulations of cracked polygonal domains: made by the `gmsh` binary from a
//! generated `.geo` script, and read from ASCII `.msh` files (format 4.1 or 2.2).
//!
//! Physical group convention (both for generated and for user-supplied meshes):
//! the triangles are the 3-node triangles of the 2D physical groups (gmsh writes
//! `"domain"`), the 1D physical group `"boundary"` holds every edge of the outer boundary
//! ∂Ω, and the 1D physical groups `"crack1"`, `"crack2"`, … (numbered consecutively from 1)
//! each hold one crack as an open chain of mesh edges that touches neither ∂Ω nor
//! another crack — but for an edge crack's mouth (elastic scenes, [`read_msh_file_with`]): a
//! chain end on a boundary vertex.

mod coarse;
mod error;
mod msh;
mod read;
mod run;
#[cfg(test)]
mod tests;

pub use coarse::CoarseMesh;
pub use error::GmshError;
pub use read::{read_msh, read_msh_file, read_msh_file_with};
pub use run::{geo_script, gmsh_version, mesh_polygon, GmshRun};
