//! A run's files in its results folder: the scene's copy, `summary.json` and the field files.

use std::path::{Path, PathBuf};

use super::atomic::atomic_write;
use super::results_dir::{FIELDS_STEM, SCENE_COPY, VERIFICATION_STEM};
use super::{summary, xdmf};

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
    match scene.problem.kind() {
        sdcrack_core::scene::ProblemKind::Scalar => write_fields(dir, scene, study)?,
        // its fields when the scene lists any and the run has cases (no verification.h5: the
        // compare tool recomputes no elastic solver error yet)
        sdcrack_core::scene::ProblemKind::Elasticity => {
            if !scene.fields.is_empty() && !study.elastic.is_empty() {
                let (meshes, cases) = elastic_field_data(study);
                xdmf::write_fields(dir, FIELDS_STEM, &meshes, &cases)?;
            }
        }
    }
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
                metadata: key_metadata(c.key, c.h),
                constants: vec![("delta".into(), c.key.delta)],
                extra: Vec::new(),
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
        extra: case.extra.clone(),
    }
}

/// The name of level `level`'s broken mesh in an elastic run's field files: `level2-elasticity`.
fn elastic_mesh_key(level: u32) -> String {
    format!(
        "level{level}-{}",
        sdcrack_core::scene::ProblemKind::Elasticity
    )
}

/// The elastic cases' meshes and fields (docs/elasticity.md, "The run"): each level's *broken*
/// mesh (triangle t's vertices are the points 3t, 3t + 1, 3t + 2), on which σ_h (raw and
/// symmetrised) and u* are node fields and u_h, γ_h cell fields; the crack as one segment per
/// crack edge with its own two points, carrying the opening, slip, pressure and closed flags at
/// the edge's ends.
fn elastic_field_data(
    study: &sdcrack_core::study::StudyResult,
) -> (Vec<xdmf::MeshData>, Vec<xdmf::CaseFields>) {
    let meshes: Vec<xdmf::MeshData> = (study.elastic_meshes.iter())
        .map(|m| xdmf::MeshData {
            key: elastic_mesh_key(m.level),
            points: m
                .triangles
                .iter()
                .flat_map(|t| t.map(|v| m.points[v]))
                .collect(),
            triangles: (0..m.triangles.len())
                .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
                .collect(),
        })
        .collect();
    let cases = (study.elastic.iter())
        .filter_map(|c| {
            let f = c.fields.as_ref()?;
            let mesh = study
                .elastic_meshes
                .iter()
                .find(|m| m.level == c.key.level)?;
            Some(elastic_case_fields(c, f, mesh))
        })
        .collect();
    (meshes, cases)
}

/// One elastic case's fields on its level's broken mesh.
fn elastic_case_fields(
    c: &sdcrack_core::study::elastic::ElasticCaseResult,
    f: &sdcrack_core::study::elastic::ElasticFields,
    mesh: &sdcrack_core::study::elastic::ElasticMeshRecord,
) -> xdmf::CaseFields {
    use xdmf::{Centering, Field, FieldKind, GridPart};
    let field = |name: &str, part, center, kind, values| Field {
        name: name.to_string(),
        part,
        center,
        kind,
        values,
    };
    let s = &f.solution;
    // the in-plane tensor in 3-D, row-major, its z row and column zero
    let tensor = |[xx, xy, yx, yy]: [f64; 4]| [xx, xy, 0.0, yx, yy, 0.0, 0.0, 0.0, 0.0];
    let raw: Vec<f64> = s.stress.iter().flatten().flat_map(|&v| tensor(v)).collect();
    let r = &f.recovered;
    // sym σ_h as recovered: [σ_xx, σ_yy, σ_xy]
    let symmetric: Vec<f64> = (r.stress_sym.iter().flatten())
        .flat_map(|&[xx, yy, xy]| tensor([xx, xy, xy, yy]))
        .collect();
    let vector = |[x, y]: [f64; 2]| [x, y, 0.0];
    let u_star: Vec<f64> = r.u_star.iter().flatten().flat_map(|&v| vector(v)).collect();
    let u_h: Vec<f64> = s.displacement.iter().flat_map(|&v| vector(v)).collect();
    let ends = |v: &[[f64; 2]]| v.iter().flatten().copied().collect::<Vec<f64>>();
    let closed: Vec<f64> = (s.crack.iter())
        .flat_map(|e| e.closed.map(|c| if c { 1.0 } else { 0.0 }))
        .collect();
    let node = Centering::Node;
    let extra = vec![
        field("sigma", GridPart::Mesh, node, FieldKind::Tensor, symmetric),
        field("sigma_raw", GridPart::Mesh, node, FieldKind::Tensor, raw),
        field("u_star", GridPart::Mesh, node, FieldKind::Vector, u_star),
        field(
            "u_h",
            GridPart::Mesh,
            Centering::Cell,
            FieldKind::Vector,
            u_h,
        ),
        field(
            "gamma_h",
            GridPart::Mesh,
            Centering::Cell,
            FieldKind::Scalar,
            s.rotation.clone(),
        ),
        field(
            "opening",
            GridPart::Crack,
            node,
            FieldKind::Scalar,
            ends(&r.opening),
        ),
        field(
            "slip",
            GridPart::Crack,
            node,
            FieldKind::Scalar,
            ends(&r.slip),
        ),
        field(
            "pressure",
            GridPart::Crack,
            node,
            FieldKind::Scalar,
            ends(&r.pressure),
        ),
        field("closed", GridPart::Crack, node, FieldKind::Scalar, closed),
    ];
    xdmf::CaseFields {
        name: c.key.case_name(),
        mesh_key: elastic_mesh_key(c.key.level),
        u: None,
        p: None,
        p_bubble: None,
        crack_points: (s.crack.iter())
            .flat_map(|e| e.nodes.map(|v| mesh.points[v]))
            .collect(),
        crack_segments: (0..s.crack.len()).map(|e| [2 * e, 2 * e + 1]).collect(),
        lambda: None,
        jump: None,
        series: c.key.series_name(),
        metadata: key_metadata(c.key, c.h),
        constants: vec![("delta".into(), c.key.delta)],
        extra,
    }
}

/// A case's group attributes in the field files: summary.json's entries of its key and h.
fn key_metadata(key: sdcrack_core::case::CaseKey, h: f64) -> Vec<(String, xdmf::Meta)> {
    (summary::SizedKey { key, h }.entries().into_iter())
        .map(|(name, value)| (name.to_string(), xdmf::Meta::from(value)))
        .collect()
}
