//! `sdcrack mesh SCENE --out DIR`: the meshes of every level of a scene, exported for the
//! reference solvers (the reference problem of docs/design.md), which never build their own mesh.
//!
//! Layout (plain text, one record a line, 0-based indices, coordinates printed with 17 significant
//! digits so they read back bit for bit):
//!
//! ```text
//! DIR/scene.json                  name, f, g, exact {u, px, py, jump}, crack {a, b, normal}, domain, cells, levels
//! DIR/level{L}/mesh.json          level, h, nx, ny, n_vertices, n_uncut_vertices, n_triangles, normal
//! DIR/level{L}/vertices.txt       x y   — the CRACKED mesh: uncut vertices, then a − copy of every
//!                                         interior crack node (same coordinates)
//! DIR/level{L}/triangles.txt      a b c — cracked numbering, counter-clockwise (− side uses − copies)
//! DIR/level{L}/vertices_uncut.txt x y   — the uncut mesh
//! DIR/level{L}/triangles_uncut.txt a b c
//! DIR/level{L}/crack.txt          plus minus — per crack node from tip a to tip b (tips: equal)
//! DIR/level{L}/boundary.txt       one vertex per line: the vertices on Γ
//! DIR/level{L}/sides.txt          per triangle: 1 (+ side), -1 (− side), 0 (no interior crack node)
//! ```
//!
//! The cracked numbering is the `broken` u space's dof numbering, so reference fields and solver
//! fields live on the same vertices. The folder is written under a temporary name and renamed.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use crate::mesh::{Mesh, MeshError, Side};
use crate::problem::USpace;
use crate::scene::Scene;

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

/// The scene's data as JSON for the references (expressions as their source text).
fn scene_json(scene: &Scene) -> serde_json::Value {
    let exact = scene.exact.as_ref().map(|e| {
        serde_json::json!({
            "u": e.u.source(),
            "px": e.px.source(),
            "py": e.py.source(),
            "jump": e.jump.as_ref().map(|j| j.source()),
        })
    });
    serde_json::json!({
        "name": scene.name,
        "f": scene.f.source(),
        "g": scene.g.source(),
        "exact": exact,
        "domain": {"min": scene.domain.min, "max": scene.domain.max},
        "crack": {"a": scene.crack.a, "b": scene.crack.b, "normal": scene.crack.normal()},
        "cells": scene.cells,
        "levels": scene.levels,
    })
}

fn write_level(dir: &Path, mesh: &Mesh) -> Result<(), ExportError> {
    std::fs::create_dir(dir).map_err(io(dir))?;
    let topo = mesh.u_topology(USpace::Broken);
    let points: Vec<[f64; 2]> = topo.dof_vertex.iter().map(|&v| mesh.vertices[v]).collect();
    let mut boundary: Vec<usize> = mesh.boundary_edges.iter().map(|e| e[0]).collect();
    boundary.sort_unstable();
    let sides: Vec<i8> = mesh
        .side
        .iter()
        .map(|s| match s {
            Some(Side::Plus) => 1,
            Some(Side::Minus) => -1,
            None => 0,
        })
        .collect();
    let meta = serde_json::json!({
        "level": mesh.level,
        "h": mesh.h(),
        "nx": mesh.nx,
        "ny": mesh.ny,
        "n_vertices": points.len(),
        "n_uncut_vertices": mesh.vertices.len(),
        "n_triangles": mesh.triangles.len(),
        "normal": mesh.crack.normal,
    });
    let files: [(&str, String); 8] = [
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
            "sides.txt",
            lines(&sides, |s, v| {
                let _ = write!(s, "{v}");
            }),
        ),
    ];
    for (name, text) in files {
        let path = dir.join(name);
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
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mesh".into());
    let tmp = parent.join(format!(".{name}.partial-{}", std::process::id()));
    let result = (|| {
        std::fs::create_dir(&tmp).map_err(io(&tmp))?;
        let mut json = scene_json(scene);
        json["levels"] = serde_json::json!(levels);
        let path = tmp.join("scene.json");
        std::fs::write(&path, format!("{json:#}\n")).map_err(io(&path))?;
        for &level in levels {
            let mesh = Mesh::structured(scene.domain, scene.cells, scene.crack, level)?;
            write_level(&tmp.join(format!("level{level}")), &mesh)?;
        }
        std::fs::rename(&tmp, out).map_err(io(out))
    })();
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
    }
    result.map(|_| out.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let mesh = Mesh::structured(scene.domain, scene.cells, scene.crack, 1).unwrap();
        assert_eq!(
            verts.len(),
            mesh.vertices.len() + mesh.crack.nodes.len() - 2
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
        assert_eq!(pairs.len(), mesh.crack.nodes.len());
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
