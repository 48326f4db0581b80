//! Result files: the results folder of a run, `summary.json`, the HDF5/XDMF fields, and
//! `verification.h5` (every field, for the compare tool, when the scene does not list them all).
//!
//! A run writes into a fresh hidden folder `OUT/.NAME.partial-PID` and renames it to `OUT/NAME`
//! only when everything is written, so an interrupted run leaves no folder under the final name
//! and an existing `OUT/NAME` is never touched: a run refuses to start when it exists. Single files
//! are written under a temporary name, flushed and renamed ([`atomic_write`]); a file or folder
//! written whole is renamed into place by [`write_then_rename`], the one write-then-rename.

pub mod merge;
pub mod mesh_export;
pub mod summary;
pub mod xdmf;

mod atomic;
mod results_dir;
mod run;

pub use atomic::{atomic_write, beside, write_then_rename};
pub use results_dir::{
    recomputation_file, ResultsDir, ResultsError, FIELDS_STEM, SCENE_COPY, VERIFICATION_STEM,
};
pub use run::{write_run, WriteError};
