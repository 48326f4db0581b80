//! `sdcrack mesh SCENE --out DIR`: the meshes of every level of a scene, exported for the
//! reference solvers (the reference problem of docs/design.md), which never build their own mesh.
//!
//! Layout (plain text, one record a line, 0-based indices, coordinates printed with 17 significant
//! digits so they read back bit for bit):
//!
//! ```text
//! DIR/scene.json                  name, f, g, exact {u, px, py, jump}, domain {min, max} or {polygon},
//!                                 cracks [{points}], cells or null, mesh_size or null, levels, and
//!                                 crack {a, b, normal} when there is one straight crack
//! DIR/level{L}/mesh.json          level, kind ("structured": nx, ny; "refined": nx = ny = null,
//!                                 triangle 4t + c of level L+1 lies in triangle t of level L;
//!                                 "graded": graded towards the tips, see parents.txt),
//!                                 h, coarse_triangles, n_cracks, n_vertices, n_uncut_vertices,
//!                                 n_triangles, and normal for one straight crack; with
//!                                 boundary parts: boundary_parts, the part names
//!                                 ([`sdcrack_core::mesh::BoundaryParts`])
//! DIR/level{L}/vertices.txt       x y   — the CRACKED mesh: uncut vertices, then a − copy of every
//!                                         interior crack node (same coordinates)
//! DIR/level{L}/triangles.txt      a b c — cracked numbering, counter-clockwise (− side uses − copies)
//! DIR/level{L}/vertices_uncut.txt x y   — the uncut mesh
//! DIR/level{L}/triangles_uncut.txt a b c
//! DIR/level{L}/crack.txt          plus minus — per crack node, cracks concatenated, each from its
//!                                 first end to its last (tips: plus = minus; a mouth, a crack end
//!                                 on ∂Ω, is doubled: plus ≠ minus, both on ∂Ω)
//! DIR/level{L}/cracks.txt         first n — per crack: its rows of crack.txt; a crack with a
//!                                 mouth: first n tip_first tip_last (1 = that end is a tip,
//!                                 0 = a mouth)
//! DIR/level{L}/crack_normals.txt  nx ny — per crack.txt row: the node's normal ν̄ (the edge
//!                                 normal; at a kink the normalised ℓ-weighted mean of the two)
//! DIR/level{L}/boundary.txt       one vertex per line: the vertices on Γ (cracked numbering:
//!                                 both copies of a mouth)
//! DIR/level{L}/sides.txt          per triangle, per corner: 1 (+ face), -1 (− face), 0 (the
//!                                 corner is not a doubled crack node: an interior node or a mouth)
//! DIR/level{L}/boundary_edges.txt v0 v1 part — with MeshExportOptions::boundary_parts (elastic
//!                                 scenes): per boundary edge, counter-clockwise along Γ, its
//!                                 cracked-mesh vertices (at a mouth, its own face's copy) and the
//!                                 index of its part in mesh.json's "boundary_parts"
//! DIR/level{L}/parents.txt        "graded" levels L > 0: per triangle, the triangle of level L−1
//!                                 it lies in
//! ```
//!
//! The cracked numbering is the `broken` u space's dof numbering, so reference fields and solver
//! fields live on the same vertices. The folder is written under a temporary name and renamed.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use sdcrack_core::elasticity::{Component, ElasticData};
use sdcrack_core::expr::Expr;
use sdcrack_core::mesh::{BoundaryParts, Layout, Mesh, MeshError, Side};
use sdcrack_core::multiplier::CrackOperators;
use sdcrack_core::problem::{Domain, Meshing, USpace};
use sdcrack_core::scene::{Problem, ProblemKind, ScalarProblem, Scene};

/// Errors of the mesh export.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    /// The crack does not fit a mesh.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The target exists.
    #[error("mesh export folder {0} already exists; remove it or choose another --out")]
    Exists(PathBuf),
    /// File system failure.
    #[error("cannot write {path}: {reason}")]
    Io {
        /// Path concerned.
        path: PathBuf,
        /// Reason.
        reason: String,
    },
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> ExportError + '_ {
    move |e| ExportError::Io {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
}

fn lines<T>(items: &[T], f: impl Fn(&mut String, &T)) -> String {
    let mut s = String::with_capacity(items.len() * 24);
    for it in items {
        f(&mut s, it);
        s.push('\n');
    }
    s
}

fn points_text(points: &[[f64; 2]]) -> String {
    lines(points, |s, p| {
        let _ = write!(s, "{:.17e} {:.17e}", p[0], p[1]);
    })
}

fn triangles_text(tris: &[[usize; 3]]) -> String {
    lines(tris, |s, t| {
        let _ = write!(s, "{} {} {}", t[0], t[1], t[2]);
    })
}

/// The scene's data as JSON for the references (expressions as their source text): a scalar
/// scene's f, g and exact solution, or an elastic scene's problem, loads and exact fields
/// (docs/elasticity.md), then the geometry and meshing.
fn scene_json(scene: &Scene) -> serde_json::Value {
    let mut json = match &scene.problem {
        Problem::Scalar(p) => scalar_json(scene, p),
        Problem::Elasticity(d) => elastic_json(scene, d),
    };
    // the single straight crack of older exports, for readers that know only that
    if let [c] = &scene.cracks[..] {
        if c.points.len() == 2 {
            let s = c.segment(0);
            json["crack"] = serde_json::json!({"a": s.a, "b": s.b, "normal": s.normal()});
        }
    }
    json
}

/// The scene's geometry and meshing, as every scene.json has them.
fn geometry_json(scene: &Scene) -> serde_json::Value {
    serde_json::json!({
        "name": scene.name,
        "domain": match &scene.domain {
            Domain::Rectangle(r) => serde_json::json!({"min": r.min, "max": r.max}),
            Domain::Polygon(p) => serde_json::json!({"polygon": p}),
        },
        "cracks": scene.cracks.iter().map(|c| serde_json::json!({"points": c.points})).collect::<Vec<_>>(),
        "cells": match scene.meshing { Meshing::Cells(c) => Some(c), _ => None },
        "mesh_size": match scene.meshing { Meshing::MeshSize(h) => Some(h), _ => None },
        "levels": scene.axes.levels,
    })
}

/// An elastic scene's scene.json (docs/elasticity.md, The mesh export).
fn elastic_json(scene: &Scene, d: &ElasticData) -> serde_json::Value {
    let m = &d.material;
    let pair = |e: &[Expr; 2]| [e[0].source().to_string(), e[1].source().to_string()];
    let exact = d.exact.as_ref().map(|e| {
        let given = |x: &Option<Expr>| x.as_ref().map(|x| x.source().to_string());
        serde_json::json!({
            "ux": e.u[0].source(),
            "uy": e.u[1].source(),
            "sxx": e.stress[0].source(),
            "syy": e.stress[1].source(),
            "sxy": e.stress[2].source(),
            "opening": given(&e.opening),
            "slip": given(&e.slip),
            "pressure": given(&e.pressure),
            "sif": (!e.sif.is_empty()).then(|| e.sif.iter().map(|k| [k.k1, k.k2]).collect::<Vec<_>>()),
        })
    });
    let components = |c: [bool; 2]| {
        (Component::ALL.iter().zip(c))
            .filter(|(_, held)| *held)
            .map(|(c, _)| c.name())
            .collect::<Vec<_>>()
    };
    let mut json = geometry_json(scene);
    let loads = serde_json::json!({
        "problem": {
            "kind": ProblemKind::Elasticity.name(),
            "plane": m.plane.name(),
            "E": m.young(),
            "nu": m.poisson(),
            "lambda": m.lambda,
            "mu": m.mu,
            "lambda_in_plane": m.lambda_in_plane(),
            "kolosov": m.kolosov(),
            "e_prime": m.e_prime(),
        },
        "f": pair(&d.f),
        "g": d.g.as_ref().map(pair),
        "tractions": (d.tractions.iter())
            .map(|t| (t.part.0.clone(), serde_json::json!(pair(&t.t))))
            .collect::<serde_json::Map<_, _>>(),
        "fixed": (d.fixed.iter())
            .map(|f| serde_json::json!({"point": f.point, "components": components(f.components)}))
            .collect::<Vec<_>>(),
        "exact": exact,
    });
    if let (Some(json), serde_json::Value::Object(loads)) = (json.as_object_mut(), loads) {
        json.extend(loads);
    }
    json
}

/// A scalar scene's scene.json: f, g, exact {u, px, py, jump}, the geometry (unchanged since
/// the elastic kind came: no `problem` key means scalar).
fn scalar_json(scene: &Scene, problem: &ScalarProblem) -> serde_json::Value {
    let exact = problem.exact.as_ref().map(|e| {
        serde_json::json!({
            "u": e.u.source(),
            "px": e.px.source(),
            "py": e.py.source(),
            "jump": e.jump.as_ref().map(|j| j.source()),
        })
    });
    let mut json = serde_json::Map::new();
    json.insert("name".into(), scene.name.clone().into());
    json.insert("f".into(), problem.f.source().into());
    json.insert("g".into(), problem.g.source().into());
    json.insert("exact".into(), exact.into());
    if let serde_json::Value::Object(geometry) = geometry_json(scene) {
        json.extend(geometry.into_iter().filter(|(key, _)| key != "name"));
    }
    serde_json::Value::Object(json)
}

/// What the export writes beyond the scalar problem's files (all off: the scalar export).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MeshExportOptions {
    /// `level{L}/boundary_edges.txt` and mesh.json's `"boundary_parts"` (elastic scenes).
    pub boundary_parts: bool,
}

impl MeshExportOptions {
    /// What a scene's problem needs: the boundary parts for an elastic scene (its tractions and
    /// Dirichlet data live on them), nothing more for a scalar one.
    pub fn for_scene(scene: &Scene) -> MeshExportOptions {
        MeshExportOptions {
            boundary_parts: scene.problem.kind() == ProblemKind::Elasticity,
        }
    }
}

fn write_level(dir: &Path, mesh: &Mesh, parts: Option<&BoundaryParts>) -> Result<(), ExportError> {
    std::fs::create_dir(dir).map_err(io(dir))?;
    let topo = mesh.u_topology(USpace::Broken);
    let points: Vec<[f64; 2]> = topo.dof_vertex.iter().map(|&v| mesh.vertices[v]).collect();
    let boundary_edges = mesh.boundary_edge_dofs(&topo);
    // Γ's vertices in the cracked mesh: both ends of its edges (a mouth's two copies end and
    // start the edges of its two faces; without a mouth every vertex starts one edge)
    let mut boundary: Vec<usize> = boundary_edges.iter().flatten().copied().collect();
    boundary.sort_unstable();
    boundary.dedup();
    let side = |s: &Option<Side>| match s {
        Some(Side::Plus) => 1,
        Some(Side::Minus) => -1,
        None => 0,
    };
    let ops = CrackOperators::new(mesh);
    let (kind, nx, ny, coarse) = match mesh.layout {
        Layout::Structured { nx, ny } => (
            "structured",
            Some(nx),
            Some(ny),
            2 * (nx >> mesh.level) * (ny >> mesh.level),
        ),
        Layout::Refined { coarse_triangles } => ("refined", None, None, coarse_triangles),
        Layout::Graded { coarse_triangles } => ("graded", None, None, coarse_triangles),
    };
    let mut meta = serde_json::json!({
        "level": mesh.level,
        "kind": kind,
        "h": mesh.h(),
        "nx": nx,
        "ny": ny,
        "coarse_triangles": coarse,
        "n_cracks": mesh.cracks.len(),
        "n_vertices": points.len(),
        "n_uncut_vertices": mesh.vertices.len(),
        "n_triangles": mesh.triangles.len(),
    });
    if let [c] = &mesh.cracks[..] {
        if c.normals.iter().all(|&n| n == c.normals[0]) {
            meta["normal"] = serde_json::json!(c.normals[0]);
        }
    }
    if let Some(parts) = parts {
        meta["boundary_parts"] = serde_json::json!(parts.names());
    }
    // per crack: its rows of crack.txt, and which ends are tips when one is a mouth
    let crack_rows: Vec<String> = ops
        .crack_nodes
        .iter()
        .zip(&mesh.cracks)
        .map(|((first, n), c)| match c.mouths {
            [false, false] => format!("{first} {n}"),
            [m0, m1] => format!("{first} {n} {} {}", u8::from(!m0), u8::from(!m1)),
        })
        .collect();
    let files: [(&str, String); 10] = [
        ("mesh.json", format!("{meta:#}\n")),
        ("vertices.txt", points_text(&points)),
        ("triangles.txt", triangles_text(&topo.triangle_dofs)),
        ("vertices_uncut.txt", points_text(&mesh.vertices)),
        ("triangles_uncut.txt", triangles_text(&mesh.triangles)),
        (
            "crack.txt",
            lines(&topo.crack_dofs, |s, (p, m)| {
                let _ = write!(s, "{p} {m}");
            }),
        ),
        (
            "boundary.txt",
            lines(&boundary, |s, v| {
                let _ = write!(s, "{v}");
            }),
        ),
        ("cracks.txt", lines(&crack_rows, |s, row| s.push_str(row))),
        ("crack_normals.txt", points_text(&ops.node_normals())),
        (
            "sides.txt",
            lines(&mesh.corner_sides, |s, c| {
                let [a, b, d] = c.map(|v| side(&v));
                let _ = write!(s, "{a} {b} {d}");
            }),
        ),
    ];
    for (name, text) in files {
        let path = dir.join(name);
        std::fs::write(&path, text).map_err(io(&path))?;
    }
    if let Some(parts) = parts {
        let path = dir.join("boundary_edges.txt");
        let of = parts.of_edges(mesh);
        let rows: Vec<(&[usize; 2], &usize)> = boundary_edges.iter().zip(&of).collect();
        let text = lines(&rows, |s, ([a, b], k)| {
            let _ = write!(s, "{a} {b} {k}");
        });
        std::fs::write(&path, text).map_err(io(&path))?;
    }
    if !mesh.parents.is_empty() {
        let path = dir.join("parents.txt");
        let text = lines(&mesh.parents, |s, p| {
            let _ = write!(s, "{p}");
        });
        std::fs::write(&path, text).map_err(io(&path))?;
    }
    Ok(())
}

/// Writes the export of every level of `scene` (or only `levels` when given) into `out`, with
/// the files its problem kind needs ([`MeshExportOptions::for_scene`]).
pub fn export_meshes(scene: &Scene, levels: &[u32], out: &Path) -> Result<PathBuf, ExportError> {
    export_meshes_with(scene, levels, out, MeshExportOptions::for_scene(scene))
}

/// [`export_meshes`] with the extra files `options` asks for.
pub fn export_meshes_with(
    scene: &Scene,
    levels: &[u32],
    out: &Path,
    options: MeshExportOptions,
) -> Result<PathBuf, ExportError> {
    if out.exists() {
        return Err(ExportError::Exists(out.to_path_buf()));
    }
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent).map_err(io(&parent))?;
    let tmp = super::atomic::beside(out, "partial");
    super::atomic::write_then_rename(out, &tmp, io(out), |tmp| {
        std::fs::create_dir(tmp).map_err(io(tmp))?;
        let mut json = scene_json(scene);
        json["levels"] = serde_json::json!(levels);
        let path = tmp.join("scene.json");
        std::fs::write(&path, format!("{json:#}\n")).map_err(io(&path))?;
        let source = scene.mesh_source()?;
        let parts = options
            .boundary_parts
            .then(|| BoundaryParts::of(&scene.domain, &scene.meshing));
        for &level in levels {
            let mesh = source.level(level)?;
            write_level(&tmp.join(format!("level{level}")), &mesh, parts.as_ref())?;
        }
        Ok(())
    })?;
    Ok(out.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene_file::TomlScene;

    #[test]
    fn export_round_trips_coordinates_and_pairs() {
        let scene = Scene::default_scene();
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("m");
        export_meshes(&scene, &[0, 1], &out).unwrap();
        let lvl = out.join("level1");
        let verts: Vec<[f64; 2]> = std::fs::read_to_string(lvl.join("vertices.txt"))
            .unwrap()
            .lines()
            .map(|l| {
                let v: Vec<f64> = l.split(' ').map(|t| t.parse().unwrap()).collect();
                [v[0], v[1]]
            })
            .collect();
        let mesh = scene.mesh_source().unwrap().level(1).unwrap();
        assert_eq!(
            verts.len(),
            mesh.vertices.len() + mesh.cracks[0].nodes.len() - 2
        );
        assert_eq!(
            &verts[..mesh.vertices.len()],
            &mesh.vertices[..],
            "bit-exact coordinates"
        );
        let pairs: Vec<(usize, usize)> = std::fs::read_to_string(lvl.join("crack.txt"))
            .unwrap()
            .lines()
            .map(|l| {
                let v: Vec<usize> = l.split(' ').map(|t| t.parse().unwrap()).collect();
                (v[0], v[1])
            })
            .collect();
        assert_eq!(pairs.len(), mesh.cracks[0].nodes.len());
        assert_eq!(pairs[0].0, pairs[0].1);
        for &(p, m) in &pairs[1..pairs.len() - 1] {
            assert_ne!(p, m);
            assert_eq!(verts[p], verts[m], "copies coincide");
        }
        assert!(
            export_meshes(&scene, &[0], &out).is_err(),
            "never overwrites"
        );
    }

    fn read_rows(path: &Path) -> Vec<Vec<i64>> {
        std::fs::read_to_string(path)
            .unwrap()
            .lines()
            .map(|l| l.split(' ').map(|t| t.parse().unwrap()).collect())
            .collect()
    }

    /// The default scene cut by an edge crack from (−1, 0) (a mouth) to (0, 0) (a tip).
    fn edge_crack_scene() -> Scene {
        let mut scene = Scene::default_scene();
        scene.domain = Domain::Rectangle(sdcrack_core::problem::Rectangle {
            min: [-1.0, -1.0],
            max: [1.0, 1.0],
        });
        scene.cracks = vec![sdcrack_core::problem::Polyline {
            points: vec![[-1.0, 0.0], [0.0, 0.0]],
        }];
        scene.meshing = Meshing::Cells([4, 4]);
        scene.grading = None;
        scene
    }

    #[test]
    fn a_mouth_is_exported_doubled_with_its_boundary_edges_split_between_faces() {
        let scene = edge_crack_scene();
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("m");
        let options = MeshExportOptions {
            boundary_parts: true,
        };
        export_meshes_with(&scene, &[0, 1], &out, options).unwrap();
        for level in [0, 1] {
            let lvl = out.join(format!("level{level}"));
            let n = 2 << level; // crack edges: from x = −1 to 0 on 4·2^level cells of (−1, 1)
            assert_eq!(
                read_rows(&lvl.join("cracks.txt")),
                vec![vec![0, n + 1, 0, 1]]
            );
            let crack = read_rows(&lvl.join("crack.txt"));
            let (plus, minus) = (crack[0][0], crack[0][1]);
            assert_ne!(plus, minus, "the mouth is doubled");
            let tip = &crack[crack.len() - 1];
            assert_eq!(tip[0], tip[1], "the tip is not");
            let verts = std::fs::read_to_string(lvl.join("vertices.txt")).unwrap();
            let verts: Vec<&str> = verts.lines().collect();
            assert_eq!(verts[plus as usize], verts[minus as usize]);
            let meta: serde_json::Value =
                serde_json::from_str(&std::fs::read_to_string(lvl.join("mesh.json")).unwrap())
                    .unwrap();
            assert_eq!(
                meta["boundary_parts"],
                serde_json::json!(["left", "right", "bottom", "top"])
            );
            let edges = read_rows(&lvl.join("boundary_edges.txt"));
            assert_eq!(edges.len(), 4 * (4 << level));
            // the mouth's two edges, both on `left`: the one above takes the + copy
            let at: Vec<&Vec<i64>> = edges
                .iter()
                .filter(|e| e[..2].contains(&plus) || e[..2].contains(&minus))
                .collect();
            assert_eq!(at.len(), 2);
            assert!(at.iter().all(|e| e[2] == 0), "{at:?}");
            let y = |v: i64| -> f64 {
                verts[v as usize]
                    .split(' ')
                    .nth(1)
                    .unwrap()
                    .parse()
                    .unwrap()
            };
            for e in at {
                let other = if e[0] == plus || e[0] == minus {
                    e[1]
                } else {
                    e[0]
                };
                let copy = if y(other) > 0.0 { plus } else { minus };
                assert!(e[..2].contains(&copy), "{e:?}");
            }
            let boundary: Vec<i64> = read_rows(&lvl.join("boundary.txt")).concat();
            assert!(boundary.contains(&plus) && boundary.contains(&minus));
            assert_eq!(
                boundary.len(),
                edges.len() + 1,
                "the loop is cut open at the mouth"
            );
        }
        // without the option: no boundary_edges.txt, no boundary_parts
        let plain = root.path().join("plain");
        export_meshes(&scene, &[0], &plain).unwrap();
        assert!(!plain.join("level0/boundary_edges.txt").exists());
        let meta = std::fs::read_to_string(plain.join("level0/mesh.json")).unwrap();
        assert!(!meta.contains("boundary_parts"));
    }

    #[test]
    fn a_scalar_export_keeps_two_columns_and_no_boundary_edges() {
        let scene = Scene::default_scene();
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("m");
        export_meshes(&scene, &[0], &out).unwrap();
        let rows = read_rows(&out.join("level0/cracks.txt"));
        assert!(rows.iter().all(|r| r.len() == 2), "{rows:?}");
        assert!(!out.join("level0/boundary_edges.txt").exists());
    }

    /// The export of [`edge_crack_scene`] (levels 0, 1, boundary parts) that
    /// compare/tests/test_edge_crack_export.py reads: this test fails when the committed copy is
    /// not what the exporter writes (SDCRACK_WRITE_FIXTURES=1 rewrites it).
    #[test]
    fn the_committed_edge_crack_export_is_the_exporters() {
        let fixture = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../compare/tests/data/edge-crack-export");
        let root = tempfile::tempdir().unwrap();
        let out = root.path().join("m");
        let options = MeshExportOptions {
            boundary_parts: true,
        };
        export_meshes_with(&edge_crack_scene(), &[0, 1], &out, options).unwrap();
        let files = |dir: &Path| -> Vec<(String, Vec<u8>)> {
            let mut all = Vec::new();
            for sub in ["", "level0", "level1"] {
                let d = dir.join(sub);
                let mut names: Vec<_> = std::fs::read_dir(&d)
                    .unwrap()
                    .map(|e| e.unwrap().path())
                    .filter(|p| p.is_file())
                    .collect();
                names.sort();
                for p in names {
                    let name = format!("{sub}/{}", p.file_name().unwrap().to_string_lossy());
                    all.push((name, std::fs::read(&p).unwrap()));
                }
            }
            all
        };
        if std::env::var_os("SDCRACK_WRITE_FIXTURES").is_some() {
            let _ = std::fs::remove_dir_all(&fixture);
            std::fs::create_dir_all(fixture.parent().unwrap()).unwrap();
            copy_dir(&out, &fixture);
        }
        let (fresh, committed) = (files(&out), files(&fixture));
        let names = |v: &[(String, Vec<u8>)]| v.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
        assert_eq!(names(&fresh), names(&committed));
        for ((name, a), (_, b)) in fresh.iter().zip(&committed) {
            assert!(a == b, "{name} differs from the committed fixture");
        }
    }

    fn copy_dir(from: &Path, to: &Path) {
        std::fs::create_dir_all(to).unwrap();
        for e in std::fs::read_dir(from).unwrap() {
            let p = e.unwrap().path();
            let target = to.join(p.file_name().unwrap());
            if p.is_dir() {
                copy_dir(&p, &target);
            } else {
                std::fs::copy(&p, &target).unwrap();
            }
        }
    }
}
