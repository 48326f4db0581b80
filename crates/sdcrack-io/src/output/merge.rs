//! Shards merged into one results folder: what `sdcrack merge` does.
//!
//! A campaign spread over many jobs (docs/workflow.md) runs each (level, u space, multiplier,
//! p mass) of a scene as `sdcrack run --solver-only` with filters and each (level, reference
//! tool) as `sdcrack reference`; every job writes a results folder of its own, a *shard*. This
//! module puts the shards of one scene together into the folder a single `sdcrack run` of the
//! scene writes: the same files, the cases in the same order, the numbers the same (the shards'
//! summaries are read into the one [`Summary`] type, every value parsed back to the same `f64`,
//! and written by the same [`Summary::write`]), the field
//! datasets of `fields.h5` and `verification.h5` copied bit for bit (HDF5's `H5Ocopy`), the
//! series files and reference outputs copied byte for byte, the mesh export written afresh by the
//! same code. What differs from a single run is what describes the process: the timings of each case are those of its shard, `wall_s` is
//! the sum of the shards' solve times, `provenance` is the merge's (the shards' own are kept
//! under `shards`), and each reference's summary keeps its first shard's provenance with every
//! shard's under `shards`.
//!
//! Before anything is written, the shards are checked: one scene (their `scene.toml` byte for
//! byte), one sdcrack build, every case of the scene's plan present exactly once and no other,
//! every reference level present exactly once per tool. The result is committed like a run's
//! (a hidden folder renamed at the end): an interrupted merge leaves nothing under the final name.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use serde_json::Value;

use super::atomic::atomic_write;
use super::results_dir::{
    recomputation_file, ResultsDir, ResultsError, FIELDS_STEM, SCENE_COPY, VERIFICATION_STEM,
};
use super::summary::{CaseEntry, Provenance, ShardRecord, Summary};
use crate::scene_file::TomlScene;
use sdcrack_core::case::{CaseAxes, CaseKey};
use sdcrack_core::scene::Scene;

/// Errors of a merge.
#[derive(Debug, thiserror::Error)]
pub enum MergeError {
    /// A shard cannot be read or does not fit the others (nothing is written).
    #[error("shard {path}: {reason}")]
    Shard {
        /// The shard folder.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// The shards together do not make up the scene's plan (nothing is written).
    #[error("{0}")]
    Incomplete(String),
    /// The merged folder cannot be created (it exists, or its parent cannot be written).
    #[error(transparent)]
    Results(#[from] ResultsError),
    /// Writing the merged folder failed (nothing is left under the final name).
    #[error("cannot write {path}: {reason}")]
    Write {
        /// File or folder concerned.
        path: PathBuf,
        /// Reason.
        reason: String,
    },
}

impl MergeError {
    /// True when the fault is in the input (the shards or the output location), not in the
    /// writing: the CLI's exit code 2 rather than 1.
    pub fn is_input_error(&self) -> bool {
        !matches!(self, MergeError::Write { .. })
    }
}

/// What a merge wrote.
#[derive(Debug)]
pub struct MergeOutcome {
    /// The merged results folder, `OUT/<scene name>`.
    pub path: PathBuf,
    /// The scene, parsed from the shards' `scene.toml`.
    pub scene: Scene,
    /// Solver cases merged.
    pub cases: usize,
    /// Solver cases that did not converge.
    pub not_converged: usize,
    /// Reference cases (all tools) whose `status` is not `converged`.
    pub references_not_converged: usize,
}

/// One shard as read from disk.
struct Shard {
    path: PathBuf,
    scene_text: String,
    /// `summary.json` of a solver shard.
    summary: Option<Summary>,
    /// `(tool, <tool>/summary.json)` of a reference shard.
    tools: Vec<(String, Value)>,
}

/// The folder the shards' scene file was in (its `mesh = { gmsh = … }` path is relative to it),
/// from the first solver shard's provenance: the scene file as given, in the working directory
/// of that run. "." when no shard says (an embedded scene has no mesh file).
fn scene_folder(shards: &[Shard]) -> PathBuf {
    let provenance = shards
        .iter()
        .find_map(|s| Some(&s.summary.as_ref()?.provenance));
    provenance
        .and_then(|p| {
            let scene = Path::new(&p.working_directory).join(&p.scene_origin);
            scene.parent().map(Path::to_path_buf)
        })
        .unwrap_or_else(|| PathBuf::from("."))
}

fn shard_err(path: &Path, reason: impl std::fmt::Display) -> MergeError {
    MergeError::Shard {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

fn write_err(path: &Path, reason: impl std::fmt::Display) -> MergeError {
    MergeError::Write {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

fn read_json(path: &Path, shard: &Path) -> Result<Value, MergeError> {
    let text = fs::read_to_string(path)
        .map_err(|e| shard_err(shard, format!("cannot read {}: {e}", path.display())))?;
    serde_json::from_str(&text)
        .map_err(|e| shard_err(shard, format!("{} is not JSON: {e}", path.display())))
}

impl Shard {
    /// Reads `dir` (a `<scene name>/` folder written by `sdcrack run` or `sdcrack reference`).
    fn read(dir: &Path) -> Result<Shard, MergeError> {
        if !dir.is_dir() {
            return Err(shard_err(dir, "no such folder"));
        }
        let scene_path = dir.join(SCENE_COPY);
        let scene_text = fs::read_to_string(&scene_path)
            .map_err(|e| shard_err(dir, format!("cannot read {SCENE_COPY}: {e}")))?;
        let summary_path = dir.join("summary.json");
        let summary = if summary_path.is_file() {
            let summary = Summary::read(&summary_path)
                .map_err(|e| shard_err(dir, format!("summary.json: {e}")))?;
            Some(summary)
        } else {
            None
        };
        let mut tools = Vec::new();
        for tool in crate::scene_file::KNOWN_REFERENCES {
            let path = dir.join(tool).join("summary.json");
            if path.is_file() {
                tools.push((tool.to_string(), read_json(&path, dir)?));
            }
        }
        if summary.is_none() && tools.is_empty() {
            return Err(shard_err(
                dir,
                "holds no results (neither summary.json nor a reference's <tool>/summary.json)",
            ));
        }
        Ok(Shard {
            path: dir.to_path_buf(),
            scene_text,
            summary,
            tools,
        })
    }
}

/// The position of a solver case in a single run's order ([`CaseAxes::keys`], the loops of
/// [`sdcrack_core::study::run_study`]).
type RunPosition = usize;

/// Where the case `key` sits in `order` (a plan's [`CaseAxes::keys`]), δ compared bit for bit;
/// `None` when it is not a case of the plan.
fn run_position(order: &[CaseKey], key: &CaseKey) -> Option<RunPosition> {
    (order.iter()).position(|k| k == key && k.delta.to_bits() == key.delta.to_bits())
}

/// Merges the shard folders `shards` into `out/<scene name>`; `provenance` is the merge's own.
pub fn merge_shards(
    shards: &[PathBuf],
    out: &Path,
    provenance: impl FnOnce(&str) -> Provenance,
) -> Result<MergeOutcome, MergeError> {
    let shards: Vec<Shard> = shards
        .iter()
        .map(|p| Shard::read(p))
        .collect::<Result<_, _>>()?;
    let Some(first) = shards.first() else {
        return Err(MergeError::Incomplete("no shard to merge".into()));
    };
    for s in &shards[1..] {
        if s.scene_text != first.scene_text {
            return Err(shard_err(
                &s.path,
                format!(
                    "its {SCENE_COPY} differs from that of {}: shards of different scenes (or of an edited scene) cannot be merged",
                    first.path.display()
                ),
            ));
        }
    }
    let scene = Scene::from_toml_in(&first.scene_text, &scene_folder(&shards))
        .map_err(|e| shard_err(&first.path, format!("invalid {SCENE_COPY}: {e}")))?;
    // the merge makes a single run of the whole scene: its plan is the scene's axes, unfiltered
    let plan = &scene.axes;

    let solver: Vec<SolverShard> = (shards.iter())
        .filter_map(|s| Some((s.path.as_path(), s.summary.as_ref()?)))
        .collect();
    // an elastic scene has no solver case until its solver exists (issue 46): its campaign runs
    // reference jobs only, and the merge makes the summary a run of the scene writes
    let lead = solver.first().map(|&(_, s)| s);
    if lead.is_none() && scene.elasticity().is_none() {
        return Err(MergeError::Incomplete(
            "no solver shard (summary.json) among the shards".into(),
        ));
    }
    if lead.is_some() {
        check_one_build(&solver)?;
    }
    let cases = ordered_cases(&solver, plan)?;
    let references = ordered_references(&shards, &scene, &plan.levels)?;
    // where level 0 came from: a solver shard's summary says; without one (an elastic scene),
    // the scene's mesh source as `sdcrack run` makes it (gmsh's level 0, kept as coarse.msh)
    let coarse_mesh = match lead {
        Some(_) => None,
        None => (scene.mesh_source())
            .map_err(|e| shard_err(&first.path, format!("its scene's level-0 mesh: {e}")))?
            .provenance
            .clone(),
    };

    let results = ResultsDir::create(out, &scene.name)?;
    let dir = results.work_path().to_path_buf();
    let scene_copy = dir.join(SCENE_COPY);
    atomic_write(&scene_copy, first.scene_text.as_bytes())
        .map_err(|e| write_err(&scene_copy, e))?;

    let t0 = std::time::Instant::now();
    // fields.h5 and its series when the scene lists fields, verification.h5 when it does not
    // list them all, coarse.msh for a gmsh scene: whatever the shards hold
    let sources: Vec<&Path> = solver.iter().map(|&(path, _)| path).collect();
    merge_field_files(&sources, &dir, &["summary.json", SCENE_COPY])?;
    let fields_write_s = t0.elapsed().as_secs_f64();

    let not_converged = cases.iter().filter(|c| !c.converged()).count();
    let n_cases = cases.len();
    let summary = match lead {
        Some(lead) => Summary {
            provenance: provenance(&lead.provenance.scene_origin),
            plan: plan.clone(),
            all_converged: not_converged == 0,
            wall_s: solver.iter().map(|(_, s)| s.wall_s).sum(),
            fields_write_s,
            recomputation_file: recomputation_file(&scene),
            cases,
            shards: Some(shard_records(&solver)),
            ..lead.clone()
        },
        None => {
            // the scene copy the merge read stands for the scene file a run is given
            let origin = first.path.join(SCENE_COPY).display().to_string();
            reference_only_summary(&scene, coarse_mesh, fields_write_s, provenance(&origin))
        }
    };
    if let Some(msh) = (summary.coarse_mesh.as_ref()).filter(|_| lead.is_none()) {
        if let Some(text) = &msh.msh_text {
            let path = dir.join("coarse.msh");
            atomic_write(&path, text.as_bytes()).map_err(|e| write_err(&path, e))?;
        }
    }
    let summary_path = dir.join("summary.json");
    (summary.write(&summary_path)).map_err(|e| write_err(&summary_path, e))?;

    let mut references_not_converged = 0;
    if !scene.references.is_empty() {
        let mesh_dir = dir.join("mesh");
        super::mesh_export::export_meshes(&scene, &plan.levels, &mesh_dir)
            .map_err(|e| write_err(&mesh_dir, e))?;
        for (tool, parts) in &references {
            references_not_converged += merge_reference(tool, parts, &dir.join(tool))?;
        }
    }
    let path = results.commit()?;
    Ok(MergeOutcome {
        path,
        scene,
        cases: n_cases,
        not_converged,
        references_not_converged,
    })
}

/// The summary of a merge without solver shards (an elastic scene's reference shards): the one
/// `sdcrack run` of the scene writes ([`Summary::of_run`] of the scene's plan, no case, level 0
/// from `coarse_mesh`), with the merge's `provenance` and no solver shard under `shards`.
fn reference_only_summary(
    scene: &Scene,
    coarse_mesh: Option<sdcrack_core::mesh::CoarseProvenance>,
    fields_write_s: f64,
    provenance: Provenance,
) -> Summary {
    let plan = sdcrack_core::study::CasePlan::new(scene, &Default::default());
    let study = sdcrack_core::study::StudyResult {
        coarse_mesh,
        ..Default::default()
    };
    Summary {
        shards: Some(Vec::new()),
        ..Summary::of_run(scene, &plan, &study, 0.0, fields_write_s, &provenance)
    }
}

/// A solver shard: its folder and its summary.
type SolverShard<'a> = (&'a Path, &'a Summary);

/// What identifies the sdcrack build that wrote a summary (version, commit, dirty): shards of
/// one merge must agree on it.
fn build_of(s: &Summary) -> (&str, Option<&str>, Option<bool>) {
    let p = &s.provenance;
    (&p.sdcrack_version, p.git_commit.as_deref(), p.git_dirty)
}

/// Refuses shards written by different sdcrack builds: their union would not be one run's.
fn check_one_build(solver: &[SolverShard]) -> Result<(), MergeError> {
    let (lead_path, lead) = solver[0];
    let reference = build_of(lead);
    for &(path, s) in &solver[1..] {
        if build_of(s) != reference {
            return Err(shard_err(
                path,
                format!(
                    "written by another sdcrack build than {} (version, commit, dirty: {:?} vs {:?})",
                    lead_path.display(),
                    build_of(s),
                    reference
                ),
            ));
        }
    }
    Ok(())
}

/// Every case of the plan, exactly once, in a single run's order.
fn ordered_cases(solver: &[SolverShard], plan: &CaseAxes) -> Result<Vec<CaseEntry>, MergeError> {
    let order = plan.keys();
    let mut found: BTreeMap<RunPosition, (&CaseEntry, &Path)> = BTreeMap::new();
    for &(path, s) in solver {
        for c in &s.cases {
            let key = c.key();
            let at = run_position(&order, key).ok_or_else(|| {
                shard_err(
                    path,
                    format!("case {} is not a case of the scene's plan", key),
                )
            })?;
            if let Some((_, other)) = found.get(&at) {
                return Err(shard_err(
                    path,
                    format!("case {} is also in shard {}", key, other.display()),
                ));
            }
            found.insert(at, (c, path));
        }
    }
    if found.len() != order.len() {
        let missing = (order.iter().enumerate())
            .find(|(i, _)| !found.contains_key(i))
            .map_or_else(|| "none".into(), |(_, k)| k.to_string());
        return Err(MergeError::Incomplete(format!(
            "the shards hold {} of the scene's {} cases; missing e.g. {missing}",
            found.len(),
            order.len()
        )));
    }
    Ok(found.into_values().map(|(c, _)| c.clone()).collect())
}

/// One reference tool's shards: `(level, shard folder, <tool>/summary.json)` by level.
type ReferenceParts<'a> = Vec<(u32, &'a Path, &'a Value)>;

/// For each reference the scene lists, its shards by level: every plan level exactly once.
fn ordered_references<'a>(
    shards: &'a [Shard],
    scene: &Scene,
    levels: &[u32],
) -> Result<Vec<(String, ReferenceParts<'a>)>, MergeError> {
    let mut out = Vec::new();
    for tool in &scene.references {
        let mut parts: ReferenceParts = Vec::new();
        for s in shards {
            for (t, summary) in &s.tools {
                if t != tool {
                    continue;
                }
                let cases = summary
                    .get("cases")
                    .and_then(Value::as_array)
                    .ok_or_else(|| {
                        shard_err(&s.path, format!("{tool}/summary.json has no cases"))
                    })?;
                for c in cases {
                    let level = c
                        .get("level")
                        .and_then(Value::as_u64)
                        .and_then(|l| u32::try_from(l).ok())
                        .ok_or_else(|| {
                            shard_err(&s.path, format!("{tool}/summary.json: a case has no level"))
                        })?;
                    if !levels.contains(&level) {
                        return Err(shard_err(
                            &s.path,
                            format!("{tool} level {level} is not a level of the scene's plan"),
                        ));
                    }
                    if let Some((_, other, _)) = parts.iter().find(|(l, _, _)| *l == level) {
                        return Err(shard_err(
                            &s.path,
                            format!("{tool} level {level} is also in shard {}", other.display()),
                        ));
                    }
                    parts.push((level, &s.path, summary));
                }
            }
        }
        if let Some(missing) = levels
            .iter()
            .find(|l| !parts.iter().any(|(p, _, _)| p == *l))
        {
            return Err(MergeError::Incomplete(format!(
                "no shard holds reference {tool} level {missing}"
            )));
        }
        parts.sort_by_key(|(l, _, _)| *l);
        out.push((tool.clone(), parts));
    }
    Ok(out)
}

/// Writes one reference's merged folder `dir` from its shards; returns the number of its cases
/// whose status is not `converged`.
fn merge_reference(tool: &str, parts: &ReferenceParts, dir: &Path) -> Result<usize, MergeError> {
    fs::create_dir_all(dir).map_err(|e| write_err(dir, e))?;
    let mut sources: Vec<&Path> = Vec::new();
    let mut cases = Vec::new();
    let mut shard_provenance = Vec::new();
    for (level, shard, summary) in parts {
        if !sources.contains(shard) {
            sources.push(shard);
            shard_provenance.push(summary.get("provenance").cloned().unwrap_or(Value::Null));
        }
        let case = summary
            .get("cases")
            .and_then(Value::as_array)
            .and_then(|cs| {
                cs.iter()
                    .find(|c| c.get("level").and_then(Value::as_u64) == Some(u64::from(*level)))
            })
            .cloned()
            .unwrap_or(Value::Null);
        cases.push(case);
    }
    let tool_dirs: Vec<PathBuf> = sources.iter().map(|s| s.join(tool)).collect();
    let tool_refs: Vec<&Path> = tool_dirs.iter().map(PathBuf::as_path).collect();
    merge_field_files(&tool_refs, dir, &["summary.json"])?;
    let not_converged = cases
        .iter()
        .filter(|c| c.get("status").and_then(Value::as_str) != Some("converged"))
        .count();
    let mut summary = parts[0].2.clone();
    if let Some(object) = summary.as_object_mut() {
        object.insert("cases".into(), Value::Array(cases));
        object.insert("shards".into(), Value::Array(shard_provenance));
    }
    write_json(&dir.join("summary.json"), &summary)?;
    Ok(not_converged)
}

/// The merged summary's record of its solver shards.
fn shard_records(solver: &[SolverShard]) -> Vec<ShardRecord> {
    (solver.iter())
        .map(|&(path, s)| ShardRecord {
            folder: path.display().to_string(),
            provenance: s.provenance.clone(),
            wall_s: s.wall_s,
        })
        .collect()
}

/// Writes a reference's merged `summary.json` (written by the reference tool, merged as JSON).
fn write_json(path: &Path, value: &Value) -> Result<(), MergeError> {
    let text = serde_json::to_string_pretty(value).map_err(|e| write_err(path, e))?;
    atomic_write(path, text.as_bytes()).map_err(|e| write_err(path, e))
}

/// Copies into `dir` every file of the folders `sources` (recursively) except `skip` (names at
/// their top level), `fields.h5` and `verification.h5`, which are merged: each the union of the
/// sources' HDF5 trees of that name. A file present in several sources must be the same bytes in
/// each.
fn merge_field_files(sources: &[&Path], dir: &Path, skip: &[&str]) -> Result<(), MergeError> {
    let h5_names = [FIELDS_STEM, VERIFICATION_STEM].map(|stem| format!("{stem}.h5"));
    let mut h5_sources: [Vec<PathBuf>; 2] = Default::default();
    for src in sources {
        for (name, found) in h5_names.iter().zip(&mut h5_sources) {
            let h5 = src.join(name);
            if h5.is_file() {
                found.push(h5);
            }
        }
        copy_files(src, dir, src, &|rel: &Path| {
            h5_names.iter().any(|n| rel == Path::new(n)) || skip.iter().any(|s| rel == Path::new(s))
        })?;
    }
    for (name, found) in h5_names.iter().zip(&h5_sources) {
        if !found.is_empty() {
            hdf5_union(found, &dir.join(name))?;
        }
    }
    Ok(())
}

/// Copies the files under `src` into `dst` (same relative paths), skipping hidden entries and
/// those `skip` names; `root` is the shard folder, for messages.
fn copy_files(
    src: &Path,
    dst: &Path,
    root: &Path,
    skip: &dyn Fn(&Path) -> bool,
) -> Result<(), MergeError> {
    let mut stack = vec![PathBuf::new()];
    while let Some(rel) = stack.pop() {
        let entries = fs::read_dir(src.join(&rel)).map_err(|e| shard_err(root, e))?;
        let mut names: Vec<_> = entries
            .filter_map(Result::ok)
            .map(|e| e.file_name())
            .collect();
        names.sort();
        for name in names {
            if name.to_string_lossy().starts_with('.') {
                continue;
            }
            let rel_path = rel.join(&name);
            if skip(&rel_path) {
                continue;
            }
            let from = src.join(&rel_path);
            let to = dst.join(&rel_path);
            if from.is_dir() {
                fs::create_dir_all(&to).map_err(|e| write_err(&to, e))?;
                stack.push(rel_path);
            } else if to.exists() {
                let same = fs::read(&from).ok() == fs::read(&to).ok();
                if !same {
                    return Err(shard_err(
                        root,
                        format!(
                            "{} differs from the same file of another shard",
                            rel_path.display()
                        ),
                    ));
                }
            } else {
                fs::copy(&from, &to).map_err(|e| write_err(&to, e))?;
            }
        }
    }
    Ok(())
}

/// Writes `dst` as the union of the HDF5 files `sources`: a copy of the first, then every group
/// or dataset of the others that it lacks, copied with `H5Ocopy` (data, attributes and soft links
/// as they are). Groups present in several files are merged member by member; a dataset present
/// in several must hold the same values (a mesh shared by shards), otherwise the merge stops.
fn hdf5_union(sources: &[PathBuf], dst: &Path) -> Result<(), MergeError> {
    fs::copy(&sources[0], dst).map_err(|e| write_err(dst, e))?;
    let h5 = |e: hdf5::Error| write_err(dst, e);
    let out = hdf5::File::open_rw(dst).map_err(h5)?;
    for src_path in &sources[1..] {
        let src = hdf5::File::open(src_path).map_err(|e| shard_err(src_path, e))?;
        union_group(&src, &out, "/", src_path)?;
    }
    out.close().map_err(h5)
}

fn union_group(
    src: &hdf5::File,
    dst: &hdf5::File,
    group: &str,
    src_path: &Path,
) -> Result<(), MergeError> {
    let read_err = |e: hdf5::Error| shard_err(src_path, e);
    let names = src
        .group(group)
        .map_err(read_err)?
        .member_names()
        .map_err(read_err)?;
    let dst_group = dst.group(group).map_err(|e| write_err(src_path, e))?;
    for name in names {
        let path = if group == "/" {
            format!("/{name}")
        } else {
            format!("{group}/{name}")
        };
        if !dst_group.link_exists(&name) {
            h5_copy(src, &path, dst, &path).map_err(|e| write_err(src_path, e))?;
        } else if src.group(&path).is_ok() {
            union_group(src, dst, &path, src_path)?;
        } else if !same_values(src, dst, &path) {
            return Err(shard_err(
                src_path,
                format!("dataset {path} differs from the same dataset of another shard"),
            ));
        }
    }
    Ok(())
}

/// True when the datasets `path` of `a` and `b` hold the same values (as f64: mesh points and
/// triangle indices, all below 2⁵³).
fn same_values(a: &hdf5::File, b: &hdf5::File, path: &str) -> bool {
    let read = |f: &hdf5::File| f.dataset(path).and_then(|d| d.read_raw::<f64>()).ok();
    match (read(a), read(b)) {
        (Some(x), Some(y)) => {
            x.len() == y.len() && x.iter().zip(&y).all(|(p, q)| p.to_bits() == q.to_bits())
        }
        _ => false,
    }
}

/// `H5Ocopy` of the object `src_path` of `src` to `dst_path` of `dst` (default copy properties:
/// data, attributes, soft links kept as soft links).
fn h5_copy(
    src: &hdf5::File,
    src_path: &str,
    dst: &hdf5::File,
    dst_path: &str,
) -> Result<(), String> {
    let s = std::ffi::CString::new(src_path).map_err(|e| e.to_string())?;
    let d = std::ffi::CString::new(dst_path).map_err(|e| e.to_string())?;
    // SAFETY: both ids are open files, both names NUL-terminated; H5P_DEFAULT property lists.
    let status = hdf5::sync::sync(|| unsafe {
        hdf5_sys::h5o::H5Ocopy(
            src.id(),
            s.as_ptr(),
            dst.id(),
            d.as_ptr(),
            hdf5_sys::h5p::H5P_DEFAULT,
            hdf5_sys::h5p::H5P_DEFAULT,
        )
    });
    if status < 0 {
        Err(format!("H5Ocopy of {src_path} failed"))
    } else {
        Ok(())
    }
}
