//! Runs the reference solvers (the reference problem of docs/design.md) that a scene lists in `[outputs] references`.
//!
//! Each reference is an independent program under `references/<tool>/solve.py`, run with Debian's
//! `/usr/bin/python3` as `solve.py MESH_EXPORT --out RESULTS/<tool> [--fields]`, with the folder
//! `compare/` beside `references/` (the package `sdshared`, whose modules the scripts share with
//! each other and the compare tool) first on `PYTHONPATH` ([`python`]). It reads the mesh
//! export written by [`sdcrack_io::output::mesh_export`] (the same vertices and triangles as the solver)
//! and writes `summary.json` (and fields) into its own subfolder of the results. Before anything is
//! solved, every requested tool is checked to be installed; a missing one is reported in one line
//! with the command that installs it.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// The Python interpreter that has Debian's dolfinx, numpy, h5py and meshio.
pub const PYTHON: &str = "/usr/bin/python3";

/// Errors of a reference run.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// A tool is not installed.
    #[error("reference '{tool}' is not available: {what}; install it with `{install}` (or run ci/setup)")]
    Missing {
        /// Tool name.
        tool: String,
        /// What was not found.
        what: String,
        /// Install command.
        install: &'static str,
    },
    /// The installed tool is a version the reference script does not support.
    #[error("reference '{tool}' cannot run here: {message}")]
    Unsupported {
        /// Tool name.
        tool: String,
        /// The script's one-line reason.
        message: String,
    },
    /// The scripts folder is missing.
    #[error("reference scripts not found at {0}; set SDCRACK_REFERENCES to the repository's references/ folder")]
    NoScripts(PathBuf),
    /// The tool ran and failed.
    #[error("reference '{tool}' failed (exit {code}): {message}")]
    Failed {
        /// Tool name.
        tool: String,
        /// Exit code (-1 when killed by a signal).
        code: i32,
        /// Last line of its stderr.
        message: String,
    },
    /// It could not be started.
    #[error("cannot start reference '{tool}': {reason}")]
    Spawn {
        /// Tool name.
        tool: String,
        /// Reason.
        reason: String,
    },
}

/// Folder holding `dolfinx/solve.py` and `freefem/solve.py`: `$SDCRACK_REFERENCES`, else the
/// repository's `references/` (this crate's source folder).
pub fn scripts_dir() -> PathBuf {
    std::env::var_os("SDCRACK_REFERENCES")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("references"))
}

/// `/usr/bin/python3 SCRIPT` with `PYTHONPATH` starting with the folder `compare/` beside
/// [`scripts_dir`] (where the package `sdshared` that the scripts import lives), followed by
/// any `PYTHONPATH` of the caller. The one place that says where the scripts find their package.
fn python(script: &Path) -> Command {
    let package_dir = scripts_dir()
        .parent()
        .map(|root| root.join("compare"))
        .unwrap_or_else(|| PathBuf::from("compare"));
    let inherited = std::env::var_os("PYTHONPATH").unwrap_or_default();
    // An empty entry would put the working directory on the path: only the caller's real ones.
    let inherited = std::env::split_paths(&inherited).filter(|p| !p.as_os_str().is_empty());
    let path =
        std::env::join_paths(std::iter::once(package_dir).chain(inherited)).unwrap_or_default();
    let mut cmd = serial_python();
    cmd.arg(script).env("PYTHONPATH", path);
    cmd
}

/// Prefixes of the variables a Slurm job step sets for its tasks (`SLURM_*`) and for the MPI
/// library's process-management interface (`PMI_*`, `PMIX_*`).
const JOB_STEP_VARIABLES: [&str; 3] = ["SLURM_", "PMI_", "PMIX_"];

/// `/usr/bin/python3` without the variables of [`JOB_STEP_VARIABLES`]. A reference is one serial
/// process, but dolfinx initialises MPI on import, and Debian's Open MPI, finding itself in a
/// Slurm step (the campaign's jobs under `--profile slurm` run in `srun`), takes itself for a
/// rank launched by `srun` and aborts where Slurm has no PMI plugin configured ("OMPI was not
/// built with SLURM's PMI support"). Without them it starts as the singleton it is.
fn serial_python() -> Command {
    let mut cmd = Command::new(PYTHON);
    remove_job_step_variables(&mut cmd, std::env::vars_os().map(|(key, _)| key));
    cmd
}

/// Removes from `cmd`'s environment those of the variables `names` that [`JOB_STEP_VARIABLES`]
/// names.
fn remove_job_step_variables(cmd: &mut Command, names: impl Iterator<Item = std::ffi::OsString>) {
    for name in names {
        let is_step_variable = name
            .to_str()
            .is_some_and(|n| JOB_STEP_VARIABLES.iter().any(|p| n.starts_with(p)));
        if is_step_variable {
            cmd.env_remove(name);
        }
    }
}

/// The last non-empty line of a program's stderr (its one-line error), or `no message`.
fn last_line(stderr: &[u8]) -> String {
    String::from_utf8_lossy(stderr)
        .lines()
        .rev()
        .find(|l| !l.trim().is_empty())
        .unwrap_or("no message")
        .trim()
        .to_string()
}

/// True when the command runs and exits 0.
fn succeeds(cmd: &mut Command) -> bool {
    cmd.stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

/// Checks that `tool` can run here.
pub fn check_available(tool: &str) -> Result<(), ReferenceError> {
    let dir = scripts_dir();
    let script = dir.join(tool).join("solve.py");
    if !script.is_file() {
        return Err(ReferenceError::NoScripts(dir));
    }
    let missing = |what: &str, install| ReferenceError::Missing {
        tool: tool.to_string(),
        what: what.to_string(),
        install,
    };
    let python_ok =
        |module: &str| succeeds(serial_python().args(["-c", &format!("import {module}")]));
    if tool == "dolfinx" && !python_ok("dolfinx") {
        return Err(missing(
            "python module dolfinx under /usr/bin/python3",
            "apt-get install python3-dolfinx",
        ));
    }
    if tool == "dolfinx" {
        // The script refuses a dolfinx outside the versions it supports, in one line.
        let check = python(&script)
            .arg("--check-install")
            .output()
            .map_err(|e| ReferenceError::Spawn {
                tool: tool.to_string(),
                reason: e.to_string(),
            })?;
        if !check.status.success() {
            return Err(ReferenceError::Unsupported {
                tool: tool.to_string(),
                message: last_line(&check.stderr),
            });
        }
    }
    if tool == "freefem" && which("FreeFem++").is_none() {
        return Err(missing(
            "the FreeFem++ binary",
            "apt-get install freefem++ libfreefem++",
        ));
    }
    if !python_ok("numpy") {
        return Err(missing(
            "numpy under /usr/bin/python3",
            "apt-get install python3-numpy",
        ));
    }
    Ok(())
}

fn which(bin: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|p| p.join(bin))
            .find(|p| p.is_file())
    })
}

/// Exit status of a reference script that wrote its results but has a case whose `status` is not
/// "converged" (references/freefem/README.md).
pub const EXIT_NOT_CONVERGED: i32 = 3;

/// What a reference run gave: its wall time and whether every case converged.
#[derive(Clone, Copy, Debug)]
pub struct ReferenceRun {
    /// Wall time of the script, seconds.
    pub seconds: f64,
    /// False when the script exited [`EXIT_NOT_CONVERGED`]: results written, some case not converged.
    pub all_converged: bool,
}

/// The command that runs `tool` on the mesh export `mesh_dir` into `out`, whatever the scene's
/// problem kind (the scripts read it from the export's scene.json):
/// `/usr/bin/python3 SCRIPTS/<tool>/solve.py MESH_DIR --out OUT [--fields]`, absolute paths.
fn reference_command(tool: &str, mesh_dir: &Path, out: &Path, fields: bool) -> Command {
    let script = scripts_dir().join(tool).join("solve.py");
    // Absolute paths: a tool may change its working directory.
    let absolute = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut cmd = python(&script);
    cmd.arg(absolute(mesh_dir)).arg("--out").arg(absolute(out));
    if fields {
        cmd.arg("--fields");
    }
    cmd.env("FF_LOADPATH", "/usr/lib/freefem++");
    cmd
}

/// Runs `tool` on the mesh export `mesh_dir`, writing into `out`.
pub fn run_reference(
    tool: &str,
    mesh_dir: &Path,
    out: &Path,
    fields: bool,
) -> Result<ReferenceRun, ReferenceError> {
    let start = Instant::now();
    let output = reference_command(tool, mesh_dir, out, fields)
        .output()
        .map_err(|e| ReferenceError::Spawn {
            tool: tool.to_string(),
            reason: e.to_string(),
        })?;
    let not_converged = output.status.code() == Some(EXIT_NOT_CONVERGED);
    if !output.status.success() && !not_converged {
        return Err(ReferenceError::Failed {
            tool: tool.to_string(),
            code: output.status.code().unwrap_or(-1),
            message: last_line(&output.stderr),
        });
    }
    Ok(ReferenceRun {
        seconds: start.elapsed().as_secs_f64(),
        all_converged: !not_converged,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reference_runs_its_script_on_the_export_with_fields_when_asked() {
        let args = |fields| {
            let cmd = reference_command(
                "freefem",
                Path::new("/r/mesh"),
                Path::new("/r/freefem"),
                fields,
            );
            assert_eq!(cmd.get_program(), PYTHON);
            cmd.get_args()
                .map(|a| a.to_string_lossy().into_owned())
                .collect::<Vec<_>>()
        };
        let script = scripts_dir().join("freefem/solve.py").display().to_string();
        assert_eq!(
            args(true),
            [&script, "/r/mesh", "--out", "/r/freefem", "--fields"]
        );
        assert_eq!(args(false), [&script, "/r/mesh", "--out", "/r/freefem"]);
    }

    #[test]
    fn a_reference_leaves_the_slurm_step_and_its_pmi_behind_and_keeps_the_rest() {
        let mut cmd = Command::new(PYTHON);
        let names = [
            "SLURM_JOB_ID",
            "SLURM_STEP_ID",
            "PMIX_RANK",
            "PMI_FD",
            "PATH",
            "OMPI_MCA_x",
        ];
        remove_job_step_variables(&mut cmd, names.iter().map(std::ffi::OsString::from));
        let removed: Vec<_> = cmd
            .get_envs()
            .filter(|(_, value)| value.is_none())
            .map(|(name, _)| name.to_string_lossy().into_owned())
            .collect();
        assert_eq!(
            removed,
            ["PMIX_RANK", "PMI_FD", "SLURM_JOB_ID", "SLURM_STEP_ID"]
        );
    }
}
