//! The structured triangulation of a rectangle: level ℓ has `2^ℓ·nx × 2^ℓ·ny` cells, each split by
//! its SW–NE diagonal into two counter-clockwise triangles, so levels are nested. Every crack
//! segment must join two level-0 vertices along a grid line (horizontal, vertical or SW–NE
//! diagonal) strictly inside Ω, but for a crack's first or last point, which may lie on a side
//! of the rectangle away from its corners (a mouth, elastic scenes only: the scene's geometry
//! validation refuses it for the scalar problem); its nodes are then grid vertices and its pieces
//! grid edges.

use super::error::MeshError;
use super::triangulation::{CrackChain, Layout, Mesh};
use crate::problem::{Polyline, Rectangle};

/// Grid index of a coordinate on `n` cells of [lo, hi], if it is a grid point.
fn grid_index(v: f64, lo: f64, hi: f64, n: usize) -> Option<i64> {
    let t = (v - lo) / (hi - lo) * n as f64;
    let r = t.round();
    ((t - r).abs() <= 1e-9 * n as f64).then_some(r as i64)
}

/// Coordinate of grid line `i` of `n` on [lo, hi], exact at both ends and at the midpoint.
fn grid_coord(lo: f64, hi: f64, i: usize, n: usize) -> f64 {
    let t = i as f64 / n as f64;
    lo * (1.0 - t) + hi * t
}

/// Builds level `level` of the structured mesh with `cells` level-0 cells and the crack chains.
pub fn structured(
    domain: Rectangle,
    cells: [usize; 2],
    cracks: &[Polyline],
    level: u32,
) -> Result<Mesh, MeshError> {
    let scale = 1usize << level;
    let (nx, ny) = (cells[0] * scale, cells[1] * scale);
    let mut vertices = grid_vertices(domain, nx, ny);
    let triangles = grid_triangles(nx, ny);
    let boundary_edges = grid_boundary(nx, ny);
    let mut owner = vec![usize::MAX; vertices.len()];
    let mut chains = Vec::with_capacity(cracks.len());
    for (c, crack) in cracks.iter().enumerate() {
        let last = crack.points.len() - 1;
        let ends = crack
            .points
            .iter()
            .enumerate()
            .map(|(k, &p)| end_index(domain, cells, p, c, k == 0 || k == last))
            .collect::<Result<Vec<_>, _>>()?;
        let mut nodes = Vec::new();
        let mut segment_of = Vec::new();
        for (s, w) in ends.windows(2).enumerate() {
            let ((ia, ja), (ib, jb)) = (w[0], w[1]);
            let (di, dj) = (ib - ia, jb - ja);
            if !(di == 0 || dj == 0 || di == dj) {
                let seg = crack.segment(s);
                return Err(MeshError::NotOnMeshLine {
                    crack: c,
                    ax: seg.a[0],
                    ay: seg.a[1],
                    bx: seg.b[0],
                    by: seg.b[1],
                });
            }
            let steps = di.abs().max(dj.abs()) as usize * scale;
            let (si, sj) = (di.signum(), dj.signum());
            let s64 = scale as i64;
            let seg = crack.segment(s);
            // the segment's first node is the previous segment's last
            for k in usize::from(s > 0)..=steps {
                let i = (ia * s64 + si * k as i64) as usize;
                let j = (ja * s64 + sj * k as i64) as usize;
                let v = j * (nx + 1) + i;
                // Crack nodes lie exactly on the segment's parametrisation (signed zeros on y = 0 etc.).
                let t = k as f64 / steps as f64;
                vertices[v] = [
                    seg.a[0] * (1.0 - t) + seg.b[0] * t,
                    seg.a[1] * (1.0 - t) + seg.b[1] * t,
                ];
                if owner[v] != usize::MAX {
                    return Err(MeshError::Touching {
                        first: owner[v].min(c),
                        second: owner[v].max(c),
                        x: vertices[v][0],
                        y: vertices[v][1],
                    });
                }
                owner[v] = c;
                nodes.push(v);
            }
            segment_of.extend(std::iter::repeat_n(s, steps));
        }
        chains.push(CrackChain::new(nodes, crack, &segment_of));
    }
    Ok(Mesh::new(
        level,
        Layout::Structured { nx, ny },
        vertices,
        triangles,
        boundary_edges,
        chains,
    ))
}

/// The grid index (i, j) of a crack point on the level-0 grid; an end of the crack (`end`) may
/// lie on a side of the rectangle, not at a corner.
fn end_index(
    domain: Rectangle,
    cells: [usize; 2],
    p: [f64; 2],
    crack: usize,
    end: bool,
) -> Result<(i64, i64), MeshError> {
    let inside = (0..2).all(|d| p[d] >= domain.min[d] && p[d] <= domain.max[d]);
    if !inside {
        return Err(MeshError::NotInside {
            crack,
            x: p[0],
            y: p[1],
            what: "lies outside the domain",
        });
    }
    let i = grid_index(p[0], domain.min[0], domain.max[0], cells[0]);
    let j = grid_index(p[1], domain.min[1], domain.max[1], cells[1]);
    let (Some(i), Some(j)) = (i, j) else {
        return Err(MeshError::OffMesh {
            crack,
            x: p[0],
            y: p[1],
            nx: cells[0],
            ny: cells[1],
        });
    };
    let on_side = [
        i == 0 || i == cells[0] as i64,
        j == 0 || j == cells[1] as i64,
    ];
    let allowed = match on_side {
        [false, false] => true,
        [true, true] => false, // a corner
        _ => end,
    };
    if !allowed {
        return Err(MeshError::NotInside {
            crack,
            x: p[0],
            y: p[1],
            what: "touches the boundary",
        });
    }
    Ok((i, j))
}

fn grid_vertices(domain: Rectangle, nx: usize, ny: usize) -> Vec<[f64; 2]> {
    let mut v = Vec::with_capacity((nx + 1) * (ny + 1));
    for j in 0..=ny {
        let y = grid_coord(domain.min[1], domain.max[1], j, ny);
        for i in 0..=nx {
            v.push([grid_coord(domain.min[0], domain.max[0], i, nx), y]);
        }
    }
    v
}

/// The triangles of the `nx × ny` cells of a grid whose `(nx + 1) × (ny + 1)` vertices are
/// numbered row by row (vertex (i, j) is `j (nx + 1) + i`): each cell cut by its diagonal from
/// the lower left to the upper right corner into two counter-clockwise triangles, lower right
/// one first, cells row by row.
pub fn grid_triangles(nx: usize, ny: usize) -> Vec<[usize; 3]> {
    let mut t = Vec::with_capacity(2 * nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let v00 = j * (nx + 1) + i;
            let (v10, v01, v11) = (v00 + 1, v00 + nx + 1, v00 + nx + 2);
            t.push([v00, v10, v11]);
            t.push([v00, v11, v01]);
        }
    }
    t
}

fn grid_boundary(nx: usize, ny: usize) -> Vec<[usize; 2]> {
    let id = |i: usize, j: usize| j * (nx + 1) + i;
    let mut e = Vec::with_capacity(2 * (nx + ny));
    e.extend((0..nx).map(|i| [id(i, 0), id(i + 1, 0)]));
    e.extend((0..ny).map(|j| [id(nx, j), id(nx, j + 1)]));
    e.extend((0..nx).rev().map(|i| [id(i + 1, ny), id(i, ny)]));
    e.extend((0..ny).rev().map(|j| [id(0, j + 1), id(0, j)]));
    e
}
