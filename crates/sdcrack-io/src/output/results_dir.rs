//! The results folder of a run: its name being written and its final name ([`ResultsDir`]), and
//! the names of the files it holds.

use std::fs;
use std::path::{Path, PathBuf};

use super::atomic::beside;

/// Stem of the field files in a results folder: `fields.h5` and the series under `fields/`.
pub const FIELDS_STEM: &str = "fields";

/// Stem of `verification.h5`: the HDF5 layout of `fields.h5` with every quantity (u, p, its
/// bubbles, λ), no XDMF series. A run writes it when the scene's `fields` does not list u, p and
/// λ, so that the compare tool can always recompute the reported errors from stored fields.
pub const VERIFICATION_STEM: &str = "verification";

/// The file of a results folder that holds every field the compare tool recomputes the errors
/// from: `fields.h5` when the scene lists u, p and λ, `verification.h5` otherwise (summary.json's
/// `recomputation_file`); none for an elastic scene, whose run has no solver case (issue 46).
pub fn recomputation_file(scene: &sdcrack_core::scene::Scene) -> Option<String> {
    scene.scalar()?;
    let stem = if scene.fields.is_complete() {
        FIELDS_STEM
    } else {
        VERIFICATION_STEM
    };
    Some(format!("{stem}.h5"))
}
/// The copy of the scene file in a results folder (the embedded default's text for `sdcrack run`
/// without a file): what the run was asked to do, read by the compare tool.
pub const SCENE_COPY: &str = "scene.toml";
/// Errors of the results folder.
#[derive(Debug, thiserror::Error)]
pub enum ResultsError {
    /// The final folder exists already.
    #[error("results folder {0} already exists; remove it or choose another --out (earlier results are never overwritten)")]
    Exists(PathBuf),
    /// `--out` names a file.
    #[error("--out {0} is a file, not a folder; give a folder for the results")]
    OutIsAFile(PathBuf),
    /// The output location cannot be created or written.
    #[error("cannot write results under {path}: {reason}")]
    Unwritable {
        /// Folder concerned.
        path: PathBuf,
        /// Operating-system reason.
        reason: String,
    },
}

/// A results folder being written.
#[derive(Debug)]
pub struct ResultsDir {
    final_path: PathBuf,
    work_path: PathBuf,
    committed: bool,
}

impl ResultsDir {
    /// Prepares `out/name`: fails if it exists or `out` cannot be written.
    pub fn create(out: &Path, name: &str) -> Result<ResultsDir, ResultsError> {
        let unwritable = |path: &Path, e: std::io::Error| ResultsError::Unwritable {
            path: path.to_path_buf(),
            reason: crate::plain::io_reason(&e),
        };
        if out.exists() && !out.is_dir() {
            return Err(ResultsError::OutIsAFile(out.to_path_buf()));
        }
        fs::create_dir_all(out).map_err(|e| unwritable(out, e))?;
        let final_path = out.join(name);
        if final_path.exists() {
            return Err(ResultsError::Exists(final_path));
        }
        let work_path = beside(&final_path, "partial");
        if work_path.exists() {
            fs::remove_dir_all(&work_path).map_err(|e| unwritable(&work_path, e))?;
        }
        fs::create_dir(&work_path).map_err(|e| unwritable(&work_path, e))?;
        Ok(ResultsDir {
            final_path,
            work_path,
            committed: false,
        })
    }

    /// Folder to write files into until [`ResultsDir::commit`].
    pub fn work_path(&self) -> &Path {
        &self.work_path
    }

    /// The folder the results will have.
    pub fn final_path(&self) -> &Path {
        &self.final_path
    }

    /// Moves the finished folder to its final name.
    pub fn commit(mut self) -> Result<PathBuf, ResultsError> {
        if self.final_path.exists() {
            return Err(ResultsError::Exists(self.final_path.clone()));
        }
        fs::rename(&self.work_path, &self.final_path).map_err(|e| ResultsError::Unwritable {
            path: self.final_path.clone(),
            reason: e.to_string(),
        })?;
        self.committed = true;
        Ok(self.final_path.clone())
    }
}

impl Drop for ResultsDir {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.work_path);
        }
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::atomic_write;

    #[test]
    fn results_dir_refuses_existing_and_cleans_up() {
        let root = tempfile::tempdir().unwrap();
        let d = ResultsDir::create(root.path(), "s").unwrap();
        atomic_write(&d.work_path().join("a.txt"), b"x").unwrap();
        let final_path = d.commit().unwrap();
        assert_eq!(fs::read(final_path.join("a.txt")).unwrap(), b"x");
        let e = ResultsDir::create(root.path(), "s").unwrap_err();
        assert!(e.to_string().contains("already exists"));
        {
            let d = ResultsDir::create(root.path(), "t").unwrap();
            atomic_write(&d.work_path().join("b.txt"), b"y").unwrap();
            // dropped without commit: nothing left
        }
        let names: Vec<_> = fs::read_dir(root.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, vec![std::ffi::OsString::from("s")]);
    }
}
