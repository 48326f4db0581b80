//! sdcrack — the smooth-domain mixed method for a crack with unilateral contact
//! (Belhachmi, Sac-Epée, Sokolowski, C. R. Math. 338 (2004) 499–504).
//!
//! A workspace of three crates, layered (tests/python/test_layout.py states the graph), each used
//! by its own name:
//! - `sdcrack-core` (crates/sdcrack-core): the maths and the study — `problem`, `case`, `expr`,
//!   `mesh`, `geometry`, `fe`, `assembly`, `linalg`, `ordering`, `contact`, `multiplier`,
//!   `krylov`, `norms`, the validated `scene` struct and `study`, which drives the stages over
//!   levels, u spaces, δ and multipliers; no TOML, CLI or HDF5 crate;
//! - `sdcrack-io` (crates/sdcrack-io): the formats — `scene_file` (the TOML scene, validated) and
//!   `output` (`summary.json`, HDF5/XDMF fields, the mesh export, merge);
//! - `sdcrack` (this package): the binary — [`cli`], [`bench`](mod@bench) and [`references`] (runs the
//!   dolfinx and FreeFEM reference solvers the scene asks for).

pub mod bench;
pub mod cli;
pub mod references;

/// How this binary was built: the package version and the git provenance that build.rs records.
pub const BUILD: sdcrack_io::output::summary::Build = sdcrack_io::output::summary::Build {
    version: env!("CARGO_PKG_VERSION"),
    git_commit: env!("SDCRACK_GIT_COMMIT"),
    git_dirty: env!("SDCRACK_GIT_DIRTY"),
};
