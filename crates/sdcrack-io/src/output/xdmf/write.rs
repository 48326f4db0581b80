//! The writer of the field files: validation, the HDF5 file, the XDMF series and their commit
//! (the layout and the order of the renames are described in the parent module).

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

#[cfg(test)]
mod tests;

use super::data::{CaseFields, Centering, Field, GridPart, MeshData, Meta};
use super::xml::{crack_grid_xml, document, mesh_grid_xml, temporal};

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
/// Dataset names of a case group that a constant field must not take.
const RESERVED: [&str; 9] = [
    "u", "p", "p_bubble", "mesh", "crack", "points", "segments", "lambda", "jump",
];
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

/// Values per field of `field`'s grid and centering for `case` on `mesh`: its nodes or cells.
fn field_items(field: &Field, case: &CaseFields, mesh: &MeshData) -> usize {
    match (field.part, field.center) {
        (GridPart::Mesh, Centering::Node) => mesh.points.len(),
        (GridPart::Mesh, Centering::Cell) => mesh.triangles.len(),
        (GridPart::Crack, Centering::Node) => case.crack_points.len(),
        (GridPart::Crack, Centering::Cell) => case.crack_segments.len(),
    }
}

/// Checks `case`'s further fields ([`CaseFields::extra`]) on `mesh`: names usable and unique,
/// none of the reserved datasets or the constants, one value per node or cell of its grid, a
/// crack field only with a crack, all finite.
fn check_extra(case: &CaseFields, mesh: &MeshData) -> Result<(), OutputError> {
    let name = &case.name;
    let mut seen = std::collections::HashSet::new();
    for f in &case.extra {
        check_name("field name", &f.name)?;
        let clash = RESERVED.contains(&f.name.as_str())
            || case.constants.iter().any(|(c, _)| *c == f.name)
            || !seen.insert((f.part == GridPart::Crack, f.name.as_str()));
        if clash {
            return Err(OutputError::Invalid(format!(
                "case {name:?}: field {:?} clashes with another field of its grid",
                f.name
            )));
        }
        if f.part == GridPart::Crack && !has_crack(case) {
            return Err(OutputError::Invalid(format!(
                "case {name:?}: crack field {:?} without a crack grid",
                f.name
            )));
        }
        let want = field_items(f, case, mesh) * f.kind.components();
        if f.values.len() != want {
            return Err(OutputError::Invalid(format!(
                "case {name:?}: field {:?} has {} numbers, its grid needs {want}",
                f.name,
                f.values.len()
            )));
        }
        check_finite_scalar(&f.values, || format!("case {name:?}: field {}", f.name))?;
    }
    Ok(())
}

/// The dataset shape of `field`: (values) for a scalar, (values, components) otherwise.
fn field_shape(field: &Field) -> Vec<usize> {
    let c = field.kind.components();
    let n = field.values.len() / c;
    if c == 1 {
        vec![n]
    } else {
        vec![n, c]
    }
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
        check_extra(case, &meshes[m])?;
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
                for f in case.extra.iter().filter(|f| f.part == GridPart::Mesh) {
                    let ds = write_f64(&g, &f.name, &f.values, field_shape(f))?;
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
                    for f in case.extra.iter().filter(|f| f.part == GridPart::Crack) {
                        let ds = write_f64(&gk, &f.name, &f.values, field_shape(f))?;
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
