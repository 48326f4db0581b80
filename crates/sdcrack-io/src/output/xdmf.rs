//! HDF5 + XDMF 3 field files: [`write_fields`] writes the fields of every solved case;
//! [`write_h5_only`] writes the same HDF5 file without the XDMF series (the results folder's
//! `verification.h5`, kept for the compare tool's recomputation, not for viewers).
//!
//! # Files
//!
//! For `write_fields(DIR, STEM, meshes, cases)`:
//!
//! ```text
//! DIR/STEM.h5                          all heavy data (HDF5)
//! DIR/STEM/CASE.xdmf                   one case's triangle grid: one state (meshio.read)
//! DIR/STEM/CASE.crack.xdmf             its crack polylines (when it has a crack)
//! DIR/STEM/SERIES.series.xdmf          the triangle grids of one series, one time step per case
//!                                      (meshio.xdmf.TimeSeriesReader)
//! DIR/STEM/SERIES.crack.series.xdmf    the crack polylines of the same series
//! ```
//!
//! A *series* is a list of cases on one mesh that a viewer walks through with its time slider;
//! the solver makes one series per (level, u space, multiplier, p mass), whose steps are the δ
//! sweep in the order solved (δ decreasing, so the slider walks δ → 0).
//!
//! The convention, the same in the reference scripts' fields (compare/sdshared/sdfields.py):
//! a file `NAME.xdmf` holds one state, a single grid, which `meshio.read` and ParaView read;
//! a file `NAME.series.xdmf` holds a temporal collection, which `meshio.xdmf.TimeSeriesReader`
//! and ParaView read. No one file serves both meshio readers: `meshio.read` accepts exactly one
//! grid with no `Time`, and `TimeSeriesReader` needs a temporal collection.
//!
//! `write_h5_only(DIR, STEM, meshes, cases)` writes `DIR/STEM.h5` alone: the same datasets with
//! the same values and attributes as `write_fields` would, validated and committed the same way;
//! no series folder.
//!
//! # HDF5 datasets (`STEM.h5`)
//!
//! ```text
//! /meshes/KEY/points               f64 (N, 3)  mesh nodes, z = 0
//! /meshes/KEY/triangles            i64 (T, 3)  node indices, 0-based
//! /cases/CASE/mesh                 soft link to /meshes/KEY
//! /cases/CASE/u                    f64 (N,)    optional
//! /cases/CASE/p                    f64 (N, 3)  optional, z = 0
//! /cases/CASE/p_bubble             f64 (T, 2)  with p: bubble coefficients of the MINI p per
//!                                              triangle (p_h = Σ p_i λ_i + p_bubble · 27 λ0 λ1 λ2)
//! /cases/CASE/crack/points         f64 (N_c, 3) crack nodes, z = 0 (all cracks, concatenated)
//! /cases/CASE/crack/segments       i64 (I, 2)  the crack segments [k, k+1], within each crack
//! /cases/CASE/crack/lambda         f64 (N_c,) per node or (I,) per segment, optional
//! /cases/CASE/crack/jump           f64 (N_c,)  per node, optional: [u_h] = u⁺ − u⁻ (see
//!                                              [`CaseFields::jump`])
//! /cases/CASE/NAME                 f64 (N,)    a constant field of [`CaseFields::constants`]
//! /cases/CASE/crack/NAME           f64 (I+1,)  the same on the crack nodes
//! ```
//!
//! The group `/cases/CASE` and every field dataset in it (`u`, `p`, `p_bubble`, `crack/lambda`,
//! `crack/jump`, the constants) carry the case's [`CaseFields::metadata`] as HDF5 attributes (the solver's:
//! `level`, `h`, `u_space`, `multiplier`, `p_mass`, `delta`), plus `series` (text) and `step` (integer).
//! The solver's only constant field is `delta`: ParaView ignores XDMF `Information` and shows no
//! step names, so δ is also a point attribute whose value (its range in the information panel, or
//! the "Annotate Attribute Data" filter) says which δ the time slider is on; meshio reads it as
//! point data. (A `Center="Grid"` attribute would cost one number, but meshio rejects it.)
//!
//! Each mesh is stored once, however many cases use it; only meshes used by at least one case are
//! written. A case whose `crack_points` is empty (and has no `lambda` or `jump`) has no `crack`
//! group and no crack grid. Data are stored contiguously, uncompressed.
//!
//! # XDMF series (`STEM/SERIES.series.xdmf`, `STEM/SERIES.crack.series.xdmf`)
//!
//! ```text
//! <Xdmf Version="3.0">
//!   <Domain>
//!     <Grid Name="SERIES" GridType="Collection" CollectionType="Temporal">
//!       <Grid Name="CASE" GridType="Uniform">       one per case of the series, in order
//!         <Time Value="k"/>                         k = 0, 1, ...: the step's index
//!         <Information Name="delta" Value="0.01"/>  the case's metadata, one element per key
//!         Triangle topology, XYZ geometry,
//!         Attributes u (Scalar), p (Vector), delta (Scalar), Center="Node"
//!       ...
//! ```
//!
//! The crack file has the same shape with Polyline topology (`NodesPerElement="2"`) and the
//! attributes `lambda` (Scalar, `Center="Node"` or `"Cell"`), `jump` (Scalar, Node) and `delta`
//! (Scalar, Node). All `DataItem`s are `Format="HDF"`
//! and name the heavy file relative to the XDMF file (`../STEM.h5:/cases/CASE/u`); the steps of
//! a series point at the same `/meshes/KEY/...` datasets.
//!
//! This is the shape both clients read: ParaView's default XDMF 3 reader opens a temporal
//! collection as one dataset with time steps, and meshio 5's `meshio.xdmf.TimeSeriesReader`
//! reads the points and cells of the first step and the data and `Time` of every step (it skips
//! `Information`, and would reject `Center="Grid"` attributes, which are therefore not used).
//! No file holds more than one series: overlapping grids of several levels or δ in one spatial
//! collection are what a viewer cannot show.
//!
//! # XDMF states (`STEM/CASE.xdmf`, `STEM/CASE.crack.xdmf`)
//!
//! One `<Grid Name="CASE" GridType="Uniform">` directly in the `Domain`, with the same topology,
//! geometry and attributes as the case's step in its series and neither `Time` nor
//! `Information`.
//!
//! # Names
//!
//! `STEM`, mesh keys, case names and series names are used as file names, HDF5 link names and
//! inside XDMF `DataItem`s, so they must be non-empty, not `.` or `..`, and free of `/`, `\`,
//! `:` and control characters. XML special characters are allowed and escaped.
//!
//! # Atomicity
//!
//! Everything is validated before anything is written. The outputs are then written under
//! temporary names in `DIR` (`.STEM.h5.tmp-PID-N`, folder `.STEM.tmp-PID-N`), fsynced, and
//! renamed in the order `STEM.h5`, `STEM/`. Each rename is atomic; an existing `STEM/` folder is
//! first moved aside (`.STEM.old-PID-N`) and deleted after the new one is in place. On any error
//! before the renames every temporary is removed and existing files under the final names are
//! left untouched. Whether overwriting is allowed is the caller's decision: this module always
//! replaces.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

#[cfg(test)]
mod tests;
mod xml;

use xml::{crack_grid_xml, document, mesh_grid_xml, temporal};

/// Errors of [`write_fields`] and [`write_h5_only`].
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    /// The HDF5 library reported an error.
    #[error("HDF5 error: {0}")]
    Hdf5(String),
    /// A file or folder could not be created, written, synced or renamed.
    #[error("cannot write {path}: {source}")]
    Io {
        /// File or folder concerned.
        path: PathBuf,
        /// Operating-system error.
        source: std::io::Error,
    },
    /// The input is inconsistent (unknown mesh, wrong lengths, non-finite values, bad names, ...).
    #[error("invalid field output: {0}")]
    Invalid(String),
}

/// A triangle mesh, shared by all cases whose `mesh_key` equals its `key`.
#[derive(Clone, Debug, PartialEq)]
pub struct MeshData {
    /// Identifier referenced by [`CaseFields::mesh_key`]; also the HDF5 group name under `/meshes`.
    pub key: String,
    /// Node coordinates (written with z = 0).
    pub points: Vec<[f64; 2]>,
    /// Triangles as 0-based node indices.
    pub triangles: Vec<[usize; 3]>,
}

/// Where a crack field lives.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Centering {
    /// One value per crack node (`I + 1` values).
    Node,
    /// One value per crack segment (`I` values).
    Cell,
}

/// The fields of one solved case.
#[derive(Clone, Debug, PartialEq)]
pub struct CaseFields {
    /// Grid name (unique); also HDF5 group name under `/cases` and per-case file name.
    pub name: String,
    /// Key of the [`MeshData`] the point fields live on.
    pub mesh_key: String,
    /// Displacement, one value per mesh node.
    pub u: Option<Vec<f64>>,
    /// Flux / gradient variable, one 2-vector per mesh node (written with z = 0).
    pub p: Option<Vec<[f64; 2]>>,
    /// Bubble coefficients of p, one 2-vector per mesh triangle (same order as the triangles):
    /// on triangle T, p_h = Σ_i p_i λ_i + p_bubble\[T\] · 27 λ0 λ1 λ2 (the MINI field). Only with `p`.
    pub p_bubble: Option<Vec<[f64; 2]>>,
    /// Crack nodes (every crack's, concatenated; empty for no crack grid).
    pub crack_points: Vec<[f64; 2]>,
    /// Crack segments as pairs of indices into `crack_points` (within one crack; `I` of them).
    pub crack_segments: Vec<[usize; 2]>,
    /// The multiplier λ_h of the smooth-domain method on the crack, per node or per segment
    /// (it approximates the jump [u]).
    pub lambda: Option<(Centering, Vec<f64>)>,
    /// [u_h] = u⁺ − u⁻ of the case's own u at each crack node (`crack_points`' order), + the face
    /// the crack normal ν (the segment direction turned by +90°) points into: the references'
    /// `jump`. Zero at the tips and, for the continuous u space, everywhere.
    pub jump: Option<Vec<f64>>,
    /// Name of the series the case is a step of (see the module documentation): the cases of
    /// one series share one mesh and one crack, and are its steps in the order given.
    pub series: String,
    /// Named values describing the case (the solver's: level, h, u space, multiplier, δ),
    /// written as HDF5 attributes and XDMF `Information` elements.
    pub metadata: Vec<(String, Meta)>,
    /// Values also written as constant point fields of the mesh and crack grids (the solver's:
    /// `delta`), so that a viewer that ignores `Information` (ParaView) shows them per step.
    pub constants: Vec<(String, f64)>,
}

/// Dataset names of a case group that a constant field must not take.
const RESERVED: [&str; 9] = [
    "u", "p", "p_bubble", "mesh", "crack", "points", "segments", "lambda", "jump",
];

/// A metadata value of a case.
#[derive(Clone, Debug, PartialEq)]
pub enum Meta {
    /// An integer.
    Int(i64),
    /// A number, written in XDMF as its shortest round-trip form (`0.01` as `1e-2`, zero as `0`).
    Float(f64),
    /// A text.
    Text(String),
}

impl From<sdcrack_core::case::AxisValue> for Meta {
    /// A case axis' value as its group's attribute.
    fn from(v: sdcrack_core::case::AxisValue) -> Meta {
        use sdcrack_core::case::AxisValue;
        match v {
            AxisValue::Int(i) => Meta::Int(i64::from(i)),
            AxisValue::Number(x) => Meta::Float(x),
            AxisValue::Name(n) => Meta::Text(n.to_string()),
        }
    }
}

impl std::fmt::Display for Meta {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Meta::Int(i) => write!(f, "{i}"),
            Meta::Float(x) if *x == 0.0 => write!(f, "0"),
            Meta::Float(x) => write!(f, "{x:e}"),
            Meta::Text(t) => f.write_str(t),
        }
    }
}

/// Writes `DIR/<stem>.h5` and the series files `DIR/<stem>/<series>.xdmf` and
/// `DIR/<stem>/<series>.crack.xdmf` atomically (see the module documentation for the layout and
/// the commit order); on any error the temporaries are removed and nothing existing under the
/// final names is touched. The inputs are validated first: every `mesh_key` must exist, field
/// lengths must match the mesh / crack, names must be unique and usable as file and HDF5 names,
/// the cases of a series must share their mesh and crack, triangle indices must be in range and
/// all values finite; otherwise [`OutputError::Invalid`] names the case and field.
pub fn write_fields(
    dir: &Path,
    stem: &str,
    meshes: &[MeshData],
    cases: &[CaseFields],
) -> Result<(), OutputError> {
    write(dir, stem, meshes, cases, true)
}

/// Writes `DIR/<stem>.h5` alone, with no series files: the same HDF5 file as [`write_fields`]
/// (same layout, datasets and attributes, including each case's `series` and `step`), validated
/// and committed the same way (temporary name, fsync, atomic rename); `DIR/<stem>/` is neither
/// written nor looked at.
pub fn write_h5_only(
    dir: &Path,
    stem: &str,
    meshes: &[MeshData],
    cases: &[CaseFields],
) -> Result<(), OutputError> {
    write(dir, stem, meshes, cases, false)
}

/// [`write_fields`] (`with_series`) or [`write_h5_only`].
fn write(
    dir: &Path,
    stem: &str,
    meshes: &[MeshData],
    cases: &[CaseFields],
    with_series: bool,
) -> Result<(), OutputError> {
    check_name("stem", stem)?;
    let plan = validate(meshes, cases)?;
    match fs::metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(OutputError::Invalid(format!(
                "{} is not a directory",
                dir.display()
            )))
        }
        Err(source) => {
            return Err(OutputError::Io {
                path: dir.to_path_buf(),
                source,
            })
        }
    }
    let final_h5 = dir.join(format!("{stem}.h5"));
    let final_cases = dir.join(stem);
    if with_series {
        match fs::symlink_metadata(&final_cases) {
            Ok(m) if !m.is_dir() => {
                return Err(OutputError::Invalid(format!(
                    "{} exists and is not a directory; cannot write the per-case XDMF files there",
                    final_cases.display()
                )))
            }
            _ => {}
        }
    }

    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let tag = format!(
        "{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    );
    let temps = Temporaries {
        h5: dir.join(format!(".{stem}.h5.tmp-{tag}")),
        cases: dir.join(format!(".{stem}.tmp-{tag}")),
        old_cases: dir.join(format!(".{stem}.old-{tag}")),
    };

    // Heavy data.
    write_h5(&temps.h5, meshes, cases, &plan)?;
    sync_path(&temps.h5)?;

    if with_series {
        write_series(&temps.cases, stem, meshes, cases, &plan)?;
    }

    // Commit.
    fs::rename(&temps.h5, &final_h5).map_err(io_err(&final_h5))?;
    if with_series {
        replace_dir(&temps.cases, &final_cases, &temps.old_cases)?;
    }
    // Persist the renames; failure here leaves correct files, so it is not an error.
    let _ = sync_path(dir);
    Ok(())
}

/// Writes the series files of every series into the new folder `folder` (fsynced), pointing at
/// `../<stem>.h5`.
fn write_series(
    folder: &Path,
    stem: &str,
    meshes: &[MeshData],
    cases: &[CaseFields],
    plan: &Plan,
) -> Result<(), OutputError> {
    fs::create_dir(folder).map_err(io_err(folder))?;
    let h5 = format!("../{stem}.h5");
    for series in &plan.series {
        let first = &cases[series.cases[0]];
        let mesh = &meshes[plan.case_mesh[series.cases[0]]];
        let steps: Vec<&CaseFields> = series.cases.iter().map(|&c| &cases[c]).collect();
        // One part (`part`: "" triangle grid, ".crack" crack grid): the series file, then each
        // case's one-state file.
        let write_part = |part: &str, grid: &dyn Fn(&CaseFields, Option<usize>, &str) -> String| {
            let body: String = (steps.iter().enumerate())
                .map(|(k, c)| grid(c, Some(k), "      "))
                .collect();
            write_synced(
                &folder.join(series_file(&first.series, part)),
                &document(&temporal(&first.series, &body)),
            )?;
            for c in &steps {
                write_synced(
                    &folder.join(state_file(&c.name, part)),
                    &document(&grid(c, None, "    ")),
                )?;
            }
            Ok::<(), OutputError>(())
        };
        write_part("", &|c, k, indent| mesh_grid_xml(&h5, mesh, c, k, indent))?;
        if has_crack(first) {
            write_part(".crack", &|c, k, indent| crack_grid_xml(&h5, c, k, indent))?;
        }
    }
    sync_path(folder)
}

/// The one-state file of case `name` (`part`: "" for the triangle grid, ".crack" for the crack):
/// a single grid, what `meshio.read` reads.
pub fn state_file(name: &str, part: &str) -> String {
    format!("{name}{part}.xdmf")
}

/// The time-series file of series `name` (`part` as in [`state_file`]): a temporal collection,
/// what `meshio.xdmf.TimeSeriesReader` reads.
pub fn series_file(name: &str, part: &str) -> String {
    format!("{name}{part}{SERIES_SUFFIX}.xdmf")
}

/// What tells a time-series file from a one-state file: `NAME.series.xdmf`.
pub const SERIES_SUFFIX: &str = ".series";

/// Temporary paths of one [`write_fields`] or [`write_h5_only`] call, removed on drop (success or failure).
struct Temporaries {
    h5: PathBuf,
    cases: PathBuf,
    old_cases: PathBuf,
}

impl Drop for Temporaries {
    fn drop(&mut self) {
        let _ = fs::remove_file(&self.h5);
        let _ = fs::remove_dir_all(&self.cases);
        let _ = fs::remove_dir_all(&self.old_cases);
    }
}

/// Result of validation: index into `meshes` of each case's mesh, which meshes are used, and
/// the series in order of first appearance.
struct Plan {
    case_mesh: Vec<usize>,
    used: Vec<bool>,
    series: Vec<Series>,
}

/// The cases (indices into `cases`) of one series, in order: its steps.
struct Series {
    cases: Vec<usize>,
}

impl Plan {
    /// Index of case `c` within its series.
    fn step(&self, c: usize) -> usize {
        self.series
            .iter()
            .find_map(|s| s.cases.iter().position(|&i| i == c))
            .unwrap_or(0)
    }
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> OutputError + '_ {
    move |source| OutputError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn h5_err(path: &Path) -> impl Fn(hdf5::Error) -> OutputError + '_ {
    move |e| OutputError::Hdf5(format!("{}: {e}", path.display()))
}

fn has_crack(case: &CaseFields) -> bool {
    !case.crack_points.is_empty()
}

fn check_name(what: &str, name: &str) -> Result<(), OutputError> {
    let bad = name.is_empty()
        || name == "."
        || name == ".."
        || name
            .chars()
            .any(|ch| ch == '/' || ch == '\\' || ch == ':' || ch.is_control());
    if bad {
        return Err(OutputError::Invalid(format!(
            "{what} {name:?} is not a valid name: it must be non-empty, not \".\" or \"..\", \
             and contain no '/', '\\', ':' or control characters"
        )));
    }
    Ok(())
}

fn check_finite<const D: usize>(
    values: &[[f64; D]],
    what: impl Fn() -> String,
) -> Result<(), OutputError> {
    for (i, v) in values.iter().enumerate() {
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return Err(OutputError::Invalid(format!(
                "{}: value {i} is not finite ({x})",
                what()
            )));
        }
    }
    Ok(())
}

fn check_finite_scalar(values: &[f64], what: impl Fn() -> String) -> Result<(), OutputError> {
    match values.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(OutputError::Invalid(format!(
            "{}: value {i} is not finite ({})",
            what(),
            values[i]
        ))),
        None => Ok(()),
    }
}

/// A node field `field` of `case` with `len` values on a mesh of `n` points: an error unless
/// it has one value per point.
fn check_on_points(
    case: &CaseFields,
    field: &str,
    len: usize,
    n: usize,
) -> Result<(), OutputError> {
    if len == n {
        return Ok(());
    }
    Err(OutputError::Invalid(format!(
        "case {:?}: field {field} has {len} values, mesh {:?} has {n} points",
        case.name, case.mesh_key
    )))
}

fn validate(meshes: &[MeshData], cases: &[CaseFields]) -> Result<Plan, OutputError> {
    use std::collections::{HashMap, HashSet};
    let mut by_key: HashMap<&str, usize> = HashMap::new();
    for (m, mesh) in meshes.iter().enumerate() {
        check_name("mesh key", &mesh.key)?;
        if by_key.insert(&mesh.key, m).is_some() {
            return Err(OutputError::Invalid(format!(
                "mesh key {:?} is given twice",
                mesh.key
            )));
        }
        check_finite(&mesh.points, || format!("mesh {:?}: points", mesh.key))?;
        let n = mesh.points.len();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            if let Some(i) = tri.iter().find(|&&i| i >= n) {
                return Err(OutputError::Invalid(format!(
                    "mesh {:?}: triangle {t} refers to node {i}, but the mesh has {n} points",
                    mesh.key
                )));
            }
        }
        if i64::try_from(n).is_err() {
            return Err(OutputError::Invalid(format!(
                "mesh {:?}: too many points",
                mesh.key
            )));
        }
    }
    let mut names = HashSet::new();
    let mut case_mesh = Vec::with_capacity(cases.len());
    let mut used = vec![false; meshes.len()];
    for case in cases {
        let name = &case.name;
        check_name("case name", name)?;
        if !names.insert(name.as_str()) {
            return Err(OutputError::Invalid(format!(
                "case name {name:?} is given twice"
            )));
        }
        check_name("series name", &case.series)?;
        for (key, value) in &case.constants {
            check_name("constant field name", key)?;
            if RESERVED.contains(&key.as_str()) || !value.is_finite() {
                return Err(OutputError::Invalid(format!(
                    "case {name:?}: constant field {key:?} = {value} clashes with a stored field \
                     or is not finite"
                )));
            }
        }
        let Some(&m) = by_key.get(case.mesh_key.as_str()) else {
            return Err(OutputError::Invalid(format!(
                "case {name:?}: mesh {:?} is not among the meshes given",
                case.mesh_key
            )));
        };
        case_mesh.push(m);
        used[m] = true;
        let n = meshes[m].points.len();
        if let Some(u) = &case.u {
            check_on_points(case, "u", u.len(), n)?;
            check_finite_scalar(u, || format!("case {name:?}: field u"))?;
        }
        if let Some(p) = &case.p {
            check_on_points(case, "p", p.len(), n)?;
            check_finite(p, || format!("case {name:?}: field p"))?;
        }
        if let Some(b) = &case.p_bubble {
            let t = meshes[m].triangles.len();
            if case.p.is_none() || b.len() != t {
                return Err(OutputError::Invalid(format!(
                    "case {name:?}: field p_bubble has {} values, mesh {:?} has {t} triangles \
                     (and it needs p)",
                    b.len(),
                    case.mesh_key
                )));
            }
            check_finite(b, || format!("case {name:?}: field p_bubble"))?;
        }
        let nc = case.crack_points.len();
        if nc == 1 || (nc == 0 && (case.lambda.is_some() || case.jump.is_some())) {
            return Err(OutputError::Invalid(format!(
                "case {name:?}: the crack polyline has {nc} points, at least 2 are needed"
            )));
        }
        check_finite(&case.crack_points, || {
            format!("case {name:?}: field crack_points")
        })?;
        if (nc > 0 && case.crack_segments.is_empty())
            || case.crack_segments.iter().flatten().any(|&k| k >= nc)
        {
            return Err(OutputError::Invalid(format!(
                "case {name:?}: the crack segments must be pairs of the {nc} crack points"
            )));
        }
        if let Some((centering, lambda)) = &case.lambda {
            let (want, per) = match centering {
                Centering::Node => (nc, "crack nodes"),
                Centering::Cell => (case.crack_segments.len(), "crack segments"),
            };
            if lambda.len() != want {
                return Err(OutputError::Invalid(format!(
                    "case {name:?}: field lambda has {} values, the crack has {want} {per}",
                    lambda.len()
                )));
            }
            check_finite_scalar(lambda, || format!("case {name:?}: field lambda"))?;
        }
        if let Some(jump) = &case.jump {
            if jump.len() != nc {
                return Err(OutputError::Invalid(format!(
                    "case {name:?}: field jump has {} values, the crack has {nc} crack nodes",
                    jump.len()
                )));
            }
            check_finite_scalar(jump, || format!("case {name:?}: field jump"))?;
        }
    }
    let series = group_series(cases, &case_mesh)?;
    Ok(Plan {
        case_mesh,
        used,
        series,
    })
}

/// Groups the cases into series (in order of first appearance) and checks that the cases of a
/// series share mesh and crack, and that no two series' files clash.
fn group_series(cases: &[CaseFields], case_mesh: &[usize]) -> Result<Vec<Series>, OutputError> {
    use std::collections::{HashMap, HashSet};
    let mut index: HashMap<&str, usize> = HashMap::new();
    let mut series: Vec<Series> = Vec::new();
    for (c, case) in cases.iter().enumerate() {
        match index.get(case.series.as_str()) {
            Some(&s) => {
                let first = series[s].cases[0];
                if case_mesh[first] != case_mesh[c]
                    || cases[first].crack_points != case.crack_points
                    || cases[first].crack_segments != case.crack_segments
                {
                    return Err(OutputError::Invalid(format!(
                        "case {:?}: series {:?} mixes meshes or cracks (case {:?} has another)",
                        case.name, case.series, cases[first].name
                    )));
                }
                series[s].cases.push(c);
            }
            None => {
                index.insert(&case.series, series.len());
                series.push(Series { cases: vec![c] });
            }
        }
    }
    let mut files = HashSet::new();
    for s in &series {
        let name = &cases[s.cases[0]].series;
        let own = [series_file(name, ""), series_file(name, ".crack")];
        let states = s.cases.iter().flat_map(|&c| {
            let case = &cases[c].name;
            [state_file(case, ""), state_file(case, ".crack")]
        });
        for file in own.into_iter().chain(states) {
            if !files.insert(file.clone()) {
                return Err(OutputError::Invalid(format!(
                    "series {name:?}: file {file:?} clashes with another file of the series or cases"
                )));
            }
        }
    }
    Ok(series)
}

fn pad3(points: &[[f64; 2]]) -> Vec<f64> {
    points.iter().flat_map(|&[x, y]| [x, y, 0.0]).collect()
}

fn write_f64(
    group: &hdf5::Group,
    name: &str,
    data: &[f64],
    shape: Vec<usize>,
) -> hdf5::Result<hdf5::Dataset> {
    let ds = group.new_dataset::<f64>().shape(shape).create(name)?;
    if !data.is_empty() {
        ds.write_raw(data)?;
    }
    Ok(ds)
}

/// Writes `meta` as scalar attributes of `loc` (a group or a dataset).
fn write_attrs(loc: &hdf5::Location, meta: &[(String, Meta)]) -> hdf5::Result<()> {
    for (key, value) in meta {
        match value {
            Meta::Int(i) => loc
                .new_attr::<i64>()
                .shape(())
                .create(key.as_str())?
                .write_scalar(i)?,
            Meta::Float(x) => loc
                .new_attr::<f64>()
                .shape(())
                .create(key.as_str())?
                .write_scalar(x)?,
            Meta::Text(t) => {
                let text: hdf5::types::VarLenUnicode = t
                    .parse()
                    .map_err(|e| hdf5::Error::from(format!("attribute {key}: {e}")))?;
                loc.new_attr::<hdf5::types::VarLenUnicode>()
                    .shape(())
                    .create(key.as_str())?
                    .write_scalar(&text)?
            }
        }
    }
    Ok(())
}

/// The attributes of case `c`: its metadata, its series and its step.
fn case_attrs(cases: &[CaseFields], plan: &Plan, c: usize) -> Vec<(String, Meta)> {
    let mut meta = cases[c].metadata.clone();
    meta.push(("series".into(), Meta::Text(cases[c].series.clone())));
    meta.push(("step".into(), Meta::Int(to_i64(plan.step(c)))));
    meta
}

fn write_i64(group: &hdf5::Group, name: &str, data: &[i64], shape: Vec<usize>) -> hdf5::Result<()> {
    let ds = group.new_dataset::<i64>().shape(shape).create(name)?;
    if !data.is_empty() {
        ds.write_raw(data)?;
    }
    Ok(())
}

/// Indices were range-checked against a point count that fits in i64.
fn to_i64(i: usize) -> i64 {
    i64::try_from(i).unwrap_or(i64::MAX)
}

fn write_h5(
    path: &Path,
    meshes: &[MeshData],
    cases: &[CaseFields],
    plan: &Plan,
) -> Result<(), OutputError> {
    // Create through std first for a clear I/O error (missing or read-only folder).
    fs::File::create(path).map_err(io_err(path))?;
    let result = (|| -> hdf5::Result<()> {
        let file = hdf5::File::create(path)?;
        {
            let gm = file.create_group("meshes")?;
            for (mesh, _) in meshes.iter().zip(&plan.used).filter(|(_, &u)| u) {
                let g = gm.create_group(&mesh.key)?;
                write_f64(
                    &g,
                    "points",
                    &pad3(&mesh.points),
                    vec![mesh.points.len(), 3],
                )?;
                let tris: Vec<i64> = mesh.triangles.iter().flat_map(|t| t.map(to_i64)).collect();
                write_i64(&g, "triangles", &tris, vec![mesh.triangles.len(), 3])?;
            }
            let gc = file.create_group("cases")?;
            for (c, case) in cases.iter().enumerate() {
                let meta = case_attrs(cases, plan, c);
                let g = gc.create_group(&case.name)?;
                write_attrs(&g, &meta)?;
                g.link_soft(&format!("/meshes/{}", case.mesh_key), "mesh")?;
                if let Some(u) = &case.u {
                    let ds = write_f64(&g, "u", u, vec![u.len()])?;
                    write_attrs(&ds, &meta)?;
                }
                if let Some(p) = &case.p {
                    let ds = write_f64(&g, "p", &pad3(p), vec![p.len(), 3])?;
                    write_attrs(&ds, &meta)?;
                }
                if let Some(b) = &case.p_bubble {
                    let flat: Vec<f64> = b.iter().flatten().copied().collect();
                    let ds = write_f64(&g, "p_bubble", &flat, vec![b.len(), 2])?;
                    write_attrs(&ds, &meta)?;
                }
                for (name, value) in &case.constants {
                    let n = meshes[plan.case_mesh[c]].points.len();
                    let ds = write_f64(&g, name, &vec![*value; n], vec![n])?;
                    write_attrs(&ds, &meta)?;
                }
                if has_crack(case) {
                    let gk = g.create_group("crack")?;
                    let n = case.crack_points.len();
                    write_f64(&gk, "points", &pad3(&case.crack_points), vec![n, 3])?;
                    let segs: Vec<i64> = case
                        .crack_segments
                        .iter()
                        .flat_map(|s| s.map(to_i64))
                        .collect();
                    let ns = case.crack_segments.len();
                    write_i64(&gk, "segments", &segs, vec![ns, 2])?;
                    if let Some((_, lambda)) = &case.lambda {
                        let ds = write_f64(&gk, "lambda", lambda, vec![lambda.len()])?;
                        write_attrs(&ds, &meta)?;
                    }
                    if let Some(jump) = &case.jump {
                        let ds = write_f64(&gk, "jump", jump, vec![n])?;
                        write_attrs(&ds, &meta)?;
                    }
                    for (name, value) in &case.constants {
                        let ds = write_f64(&gk, name, &vec![*value; n], vec![n])?;
                        write_attrs(&ds, &meta)?;
                    }
                }
            }
        }
        file.close()
    })();
    result.map_err(h5_err(path))
}

fn write_synced(path: &Path, text: &str) -> Result<(), OutputError> {
    let mut f = fs::File::create(path).map_err(io_err(path))?;
    f.write_all(text.as_bytes()).map_err(io_err(path))?;
    f.sync_all().map_err(io_err(path))
}

/// fsyncs a file or folder by path.
fn sync_path(path: &Path) -> Result<(), OutputError> {
    fs::File::open(path)
        .and_then(|f| f.sync_all())
        .map_err(io_err(path))
}

/// Puts folder `new` at `target`, moving an existing `target` folder to `aside` first.
fn replace_dir(new: &Path, target: &Path, aside: &Path) -> Result<(), OutputError> {
    let had_old = match fs::symlink_metadata(target) {
        Ok(m) if m.is_dir() => {
            fs::rename(target, aside).map_err(io_err(target))?;
            true
        }
        Ok(_) => {
            return Err(OutputError::Invalid(format!(
                "{} exists and is not a directory",
                target.display()
            )))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => false,
        Err(source) => {
            return Err(OutputError::Io {
                path: target.to_path_buf(),
                source,
            })
        }
    };
    if let Err(source) = fs::rename(new, target) {
        if had_old {
            let _ = fs::rename(aside, target);
        }
        return Err(OutputError::Io {
            path: target.to_path_buf(),
            source,
        });
    }
    Ok(())
}
