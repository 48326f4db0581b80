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

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Stem of the field files in a results folder: `fields.h5` and the series under `fields/`.
pub const FIELDS_STEM: &str = "fields";

/// Stem of `verification.h5`: the HDF5 layout of `fields.h5` with every quantity (u, p, its
/// bubbles, λ), no XDMF series. A run writes it when the scene's `fields` does not list u, p and
/// λ, so that the compare tool can always recompute the reported errors from stored fields.
pub const VERIFICATION_STEM: &str = "verification";

/// The file of a results folder that holds every field the compare tool recomputes the errors
/// from: `fields.h5` when the scene lists u, p and λ, `verification.h5` otherwise (summary.json's
/// `recomputation_file`).
pub fn recomputation_file(fields: &sdcrack_core::scene::FieldSet) -> String {
    let stem = if fields.is_complete() {
        FIELDS_STEM
    } else {
        VERIFICATION_STEM
    };
    format!("{stem}.h5")
}

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

/// Writes `bytes` to `path` atomically: a temporary file in the same folder, flushed, renamed.
pub fn atomic_write(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    write_then_rename(path, &beside(path, "tmp"), std::convert::identity, |tmp| {
        let mut f = fs::File::create(tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })
}

/// `.NAME.KIND-PID` in the folder of `path` (named `NAME`): where `path` is written before it
/// is renamed into place.
pub fn beside(path: &Path, kind: &str) -> PathBuf {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    dir.join(format!(".{name}.{kind}-{}", std::process::id()))
}

/// Write-then-rename, the one way sdcrack replaces a file or a folder: `write` makes `tmp` (a
/// file or a folder in the same folder as `path`), which is then renamed to `path`, so that a
/// reader sees the entry whole or not at all. On any error `tmp` is removed (`rename_error`
/// turns the rename's error into the caller's) and `path` is left as it was.
pub fn write_then_rename<E>(
    path: &Path,
    tmp: &Path,
    rename_error: impl FnOnce(std::io::Error) -> E,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), E> {
    let result = write(tmp).and_then(|()| fs::rename(tmp, path).map_err(rename_error));
    if result.is_err() {
        let _ = if tmp.is_dir() {
            fs::remove_dir_all(tmp)
        } else {
            fs::remove_file(tmp)
        };
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

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

/// Errors while writing a run's files.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// summary.json could not be written.
    #[error("cannot write {path}: {reason}")]
    Io {
        /// File concerned.
        path: PathBuf,
        /// Reason.
        reason: String,
    },
    /// The field files (`fields.h5`, `fields/`, `verification.h5`) could not be written.
    #[error("cannot write field files: {0}")]
    Fields(#[from] xdmf::OutputError),
}

/// The copy of the scene file in a results folder (the embedded default's text for `sdcrack run`
/// without a file): what the run was asked to do, read by the compare tool.
pub const SCENE_COPY: &str = "scene.toml";

/// Writes `scene.toml` (the scene's text byte for byte), `summary.json` (with `provenance`),
/// when the scene asks for fields `fields.h5` + the series `fields/*.xdmf` with those fields, and
/// when it does not ask for all of u, p and λ `verification.h5` with all of them, into `dir`.
pub fn write_run(
    dir: &Path,
    loaded: &crate::scene_file::LoadedScene,
    plan: &sdcrack_core::study::CasePlan,
    study: &sdcrack_core::study::StudyResult,
    wall_s: f64,
    provenance: &summary::Provenance,
) -> Result<(), WriteError> {
    let scene = &loaded.scene;
    let copy = dir.join(SCENE_COPY);
    atomic_write(&copy, loaded.text.as_bytes()).map_err(|e| WriteError::Io {
        path: copy,
        reason: e.to_string(),
    })?;
    if let Some(msh) = study.coarse_mesh.as_ref().and_then(|c| c.msh_text.as_ref()) {
        let path = dir.join("coarse.msh");
        atomic_write(&path, msh.as_bytes()).map_err(|e| WriteError::Io {
            path,
            reason: e.to_string(),
        })?;
    }
    let t0 = std::time::Instant::now();
    write_fields(dir, scene, study)?;
    let fields_write_s = t0.elapsed().as_secs_f64();
    let summary = summary::Summary::of_run(scene, plan, study, wall_s, fields_write_s, provenance);
    let path = dir.join("summary.json");
    summary.write(&path).map_err(|e| WriteError::Io {
        path,
        reason: e.to_string(),
    })
}

/// Writes `fields.h5` + `fields/` with the fields the scene lists (none when it lists none) and,
/// unless it lists u, p and λ, `verification.h5` with all of them.
fn write_fields(
    dir: &Path,
    scene: &sdcrack_core::scene::Scene,
    study: &sdcrack_core::study::StudyResult,
) -> Result<(), WriteError> {
    let (meshes, all) = field_data(study);
    if scene.fields.is_complete() {
        xdmf::write_fields(dir, FIELDS_STEM, &meshes, &all)?;
        return Ok(());
    }
    if !scene.fields.is_empty() {
        let wanted: Vec<xdmf::CaseFields> =
            all.iter().map(|c| restrict(c, &scene.fields)).collect();
        xdmf::write_fields(dir, FIELDS_STEM, &meshes, &wanted)?;
    }
    xdmf::write_h5_only(dir, VERIFICATION_STEM, &meshes, &all)?;
    Ok(())
}

/// The meshes and every case's fields, all quantities: u, p, its bubbles (consistent p mass
/// only: the lumped p has none), λ and the jump [u_h] = u⁺ − u⁻ at the crack nodes.
fn field_data(
    study: &sdcrack_core::study::StudyResult,
) -> (Vec<xdmf::MeshData>, Vec<xdmf::CaseFields>) {
    use sdcrack_core::multiplier::CrackField;
    use xdmf::Meta;
    let meshes: Vec<xdmf::MeshData> = study
        .meshes
        .iter()
        .map(|m| xdmf::MeshData {
            key: m.key.name(),
            points: m.points.clone(),
            triangles: m.triangles.clone(),
        })
        .collect();
    let cases: Vec<xdmf::CaseFields> = study
        .cases
        .iter()
        .filter_map(|c| {
            let f = c.fields.as_ref()?;
            let record = (study.meshes.iter()).position(|m| m.key == c.key.mesh());
            let (crack_points, crack_segments) = record
                .map(|i| {
                    let m = &study.meshes[i];
                    (m.crack_points.clone(), m.crack_segments.clone())
                })
                .unwrap_or_default();
            let jump = record.filter(|_| !crack_points.is_empty()).map(|i| {
                (study.meshes[i].crack_dofs.iter())
                    .map(|&(p, m)| f.u[p] - f.u[m])
                    .collect()
            });
            Some(xdmf::CaseFields {
                name: c.key.case_name(),
                mesh_key: c.key.mesh().name(),
                u: Some(f.u.clone()),
                p: Some(f.p.clone()),
                // the lumped p mass has no bubble: no p_bubble dataset
                p_bubble: (!f.p_bubble.is_empty()).then(|| f.p_bubble.clone()),
                crack_points,
                crack_segments,
                lambda: Some(match &f.lambda {
                    CrackField::PerSegment(v) => (xdmf::Centering::Cell, v.clone()),
                    CrackField::PerNode(v) => (xdmf::Centering::Node, v.clone()),
                }),
                jump,
                series: c.key.series_name(),
                // the case's group attributes: summary.json's entries of its key
                metadata: (summary::SizedKey { key: c.key, h: c.h }
                    .entries()
                    .into_iter())
                .map(|(name, value)| (name.to_string(), Meta::from(value)))
                .collect(),
                constants: vec![("delta".into(), c.key.delta)],
            })
        })
        .collect();
    (meshes, cases)
}

/// `case` with only the quantities of `fields` (p's bubbles go with p).
fn restrict(case: &xdmf::CaseFields, fields: &sdcrack_core::scene::FieldSet) -> xdmf::CaseFields {
    xdmf::CaseFields {
        name: case.name.clone(),
        mesh_key: case.mesh_key.clone(),
        u: fields.u.then(|| case.u.clone()).flatten(),
        p: fields.p.then(|| case.p.clone()).flatten(),
        p_bubble: fields.p.then(|| case.p_bubble.clone()).flatten(),
        crack_points: case.crack_points.clone(),
        crack_segments: case.crack_segments.clone(),
        lambda: fields.lambda.then(|| case.lambda.clone()).flatten(),
        // the crack's own jump, whatever is listed: in every crack file, as in the references'
        jump: case.jump.clone(),
        series: case.series.clone(),
        metadata: case.metadata.clone(),
        constants: case.constants.clone(),
    }
}
