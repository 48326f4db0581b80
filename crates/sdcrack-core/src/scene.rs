//! The validated scene: one crack problem and its study, free of any file format. The TOML
//! format and its validation live in sdcrack-io's `scene_file`, which builds this struct; the
//! study ([`crate::study`]) runs it. This file only declares the parts and re-exports them: the
//! scene ([`validated`]), its limits ([`limits`]), its `[verification]` settings, the exact data's
//! checks (scalar and elastic, on their common ground [`exact_check`]) and the key paths its
//! errors carry.

pub mod elastic_exact_data;
#[cfg(test)]
pub(crate) mod elastic_testing;
pub mod exact_check;
pub mod exact_data;
pub mod key_path;
pub mod limits;
#[cfg(test)]
pub(crate) mod testing;
pub mod validated;
pub mod verification;

pub use key_path::{KeyPath, PathSegment};
pub use limits::{
    check_level, estimated_memory_bytes, estimated_memory_bytes_of_cells,
    estimated_mesh_memory_bytes, Level0Size, MAX_LEVEL, MAX_MEMORY_BYTES, MEMORY_BASE_BYTES,
    MEMORY_BYTES_PER_CELL,
};
pub use validated::{FieldSet, Problem, ProblemKind, ScalarProblem, Scene};
pub use verification::{ExpectedFailure, Verification};
