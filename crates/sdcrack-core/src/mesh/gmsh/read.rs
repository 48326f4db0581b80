//! Reading `.msh` files: the text parsed ([`super::msh`]), nodes snapped onto exact points, the
//! coarse mesh assembled ([`super::coarse`]).

use std::path::Path;

use super::coarse::{assemble, CoarseMesh};
use super::error::{io_error, Result};
use super::msh::{parse_msh, RawNode};
use crate::geometry::CrackEnds;

/// Reads an ASCII gmsh mesh (format 4.1 or 2.2, with `$PhysicalNames`) into a [`CoarseMesh`];
/// `origin` names the file in error messages.
///
/// Requirements (each violation is a [`GmshError`](super::GmshError) naming the file and the group):
/// * a 1D physical group named `"boundary"` whose edges are exactly the edges that belong to
///   one triangle only (the outer boundary ∂Ω);
/// * 1D physical groups `crack1`, `crack2`, … (at least one, numbered consecutively from 1),
///   each made of 2-node lines forming one simple open chain of triangle edges, touching
///   neither ∂Ω nor another crack;
/// * triangles: the 3-node triangles (type 2) of the 2D physical groups, or every type-2
///   element if no 2D element has a physical group; any other 2D element type is an error;
/// * all nodes in the plane z = 0; node tags may be non-contiguous; no parametric
///   coordinates; binary files are refused.
///
/// Other physical groups and 0D elements are ignored.
pub fn read_msh(text: &str, origin: &str) -> Result<CoarseMesh> {
    read_msh_snapped(text, origin, &[], CrackEnds::Inside)
}

/// Reads an ASCII `.msh` file from disk with [`read_msh`] (the path is the origin); invalid
/// UTF-8 is replaced, so binary files reach the binary-format error.
pub fn read_msh_file(path: &Path) -> Result<CoarseMesh> {
    read_msh_file_with(path, CrackEnds::Inside)
}

/// [`read_msh_file`] with the crack ends `ends` allows: with [`CrackEnds::MayBeMouths`] a crack
/// chain may end on a boundary vertex (a mouth, elastic scenes), its other vertices and edges
/// still off ∂Ω.
pub fn read_msh_file_with(path: &Path, ends: CrackEnds) -> Result<CoarseMesh> {
    let bytes = std::fs::read(path).map_err(|e| io_error(path, &e))?;
    read_msh_snapped(
        &String::from_utf8_lossy(&bytes),
        &path.display().to_string(),
        &[],
        ends,
    )
}

pub(super) fn read_msh_snapped(
    text: &str,
    origin: &str,
    exact: &[[f64; 2]],
    ends: CrackEnds,
) -> Result<CoarseMesh> {
    let mut raw = parse_msh(text, origin)?;
    snap_nodes(&mut raw.nodes, exact);
    assemble(&raw, origin, ends)
}

/// Gives the node nearest to each exact point that point's coordinates, if it is within
/// rounding distance (gmsh prints 16 significant digits, not the 17 of a round trip).
fn snap_nodes(nodes: &mut [RawNode], exact: &[[f64; 2]]) {
    let scale = exact.iter().flatten().fold(1.0_f64, |m, v| m.max(v.abs()));
    let tol = 1e-12 * scale;
    for p in exact {
        let nearest = nodes.iter_mut().min_by(|a, b| {
            let (da, db) = (dist(a.xy, *p), dist(b.xy, *p));
            da.total_cmp(&db)
        });
        if let Some(node) = nearest.filter(|n| dist(n.xy, *p) <= tol) {
            node.xy = *p;
        }
    }
}

pub(super) fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}
