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
//!                                 n_triangles, and normal for one straight crack
//! DIR/level{L}/vertices.txt       x y   — the CRACKED mesh: uncut vertices, then a − copy of every
//!                                         interior crack node (same coordinates)
//! DIR/level{L}/triangles.txt      a b c — cracked numbering, counter-clockwise (− side uses − copies)
//! DIR/level{L}/vertices_uncut.txt x y   — the uncut mesh
//! DIR/level{L}/triangles_uncut.txt a b c
//! DIR/level{L}/crack.txt          plus minus — per crack node, cracks concatenated, each from its
//!                                 first tip to its last (tips: plus = minus)
//! DIR/level{L}/cracks.txt         first n — per crack: its rows of crack.txt
//! DIR/level{L}/crack_normals.txt  nx ny — per crack.txt row: the node's normal ν̄ (the edge
//!                                 normal; at a kink the normalised ℓ-weighted mean of the two)
//! DIR/level{L}/boundary.txt       one vertex per line: the vertices on Γ
//! DIR/level{L}/sides.txt          per triangle, per corner: 1 (+ face), -1 (− face), 0 (the
//!                                 corner is not an interior crack node)
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
use sdcrack_core::mesh::{Layout, Mesh, MeshError, Side};
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
    serde_json::json!({
        "name": scene.name,
        "f": problem.f.source(),
        "g": problem.g.source(),
        "exact": exact,
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

fn write_level(dir: &Path, mesh: &Mesh) -> Result<(), ExportError> {
    std::fs::create_dir(dir).map_err(io(dir))?;
    let topo = mesh.u_topology(USpace::Broken);
    let points: Vec<[f64; 2]> = topo.dof_vertex.iter().map(|&v| mesh.vertices[v]).collect();
    let mut boundary: Vec<usize> = mesh.boundary_edges.iter().map(|e| e[0]).collect();
    boundary.sort_unstable();
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
        (
            "cracks.txt",
            lines(&ops.crack_nodes, |s, (first, n)| {
                let _ = write!(s, "{first} {n}");
            }),
        ),
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
    if !mesh.parents.is_empty() {
        let path = dir.join("parents.txt");
        let text = lines(&mesh.parents, |s, p| {
            let _ = write!(s, "{p}");
        });
        std::fs::write(&path, text).map_err(io(&path))?;
    }
    Ok(())
}

/// Writes the export of every level of `scene` (or only `levels` when given) into `out`.
pub fn export_meshes(scene: &Scene, levels: &[u32], out: &Path) -> Result<PathBuf, ExportError> {
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
        for &level in levels {
            let mesh = source.level(level)?;
            write_level(&tmp.join(format!("level{level}")), &mesh)?;
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
}
