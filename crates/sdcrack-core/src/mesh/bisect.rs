//! Meshes graded towards the crack tips by newest-vertex bisection.
//!
//! Near a tip u ~ r^{1/2}, and uniform meshes cap every rate at 1/2. A graded mesh uses elements
//! of size h·(r/R)^{1−β} within a radius R of each tip (r: the distance to the tip; β ≤ 1/2 for
//! the r^{1/2} singularity, β = 1 is uniform), floored at the size h·(h/R)^{(1−β)/β} of the
//! elements touching the tip, so that the number of elements stays O(h⁻²) and each level has
//! ~4× the previous one's unknowns.
//!
//! Construction, nested: level 0 is the scene's level-0 mesh bisected until every triangle meets
//! the target size for h = h₀ (its largest diameter); level ℓ + 1 is level ℓ with every triangle
//! bisected twice (into four), then bisected until it meets the target for h₀/2^{ℓ+1}. Every
//! bisection is newest-vertex bisection (each triangle's refinement edge is the one opposite its
//! newest vertex; initially its longest edge), closed after each round so that the mesh stays
//! conforming: a triangle with a split edge is bisected again. So each triangle of level ℓ + 1
//! lies in one triangle of level ℓ (`Mesh::parents`), crack and boundary edges are halved along
//! their own lines, and the tips stay vertices.

use std::collections::HashMap;

use super::triangulation::{diameter, CrackChain, Layout, Mesh};

pub use crate::problem::Grading;

/// Bisection rounds allowed per refinement step before giving up (a conforming closure needs a
/// few per step; the grading ~log₂(h/h_tip) ≈ (1−β)/β·log₂(R/h)).
const MAX_ROUNDS: usize = 400;

/// A triangle in newest-vertex form: `v[0]` is the newest vertex, (v[1], v[2]) the refinement
/// edge, counter-clockwise; `origin` its ancestor in the level it was refined from.
#[derive(Clone, Copy, Debug)]
struct Tri {
    v: [usize; 3],
    origin: usize,
}

/// Vertices and triangles under refinement, with the midpoint of every edge split so far.
struct Bisection {
    vertices: Vec<[f64; 2]>,
    tris: Vec<Tri>,
    midpoint: HashMap<(usize, usize), usize>,
}

fn key(a: usize, b: usize) -> (usize, usize) {
    (a.min(b), a.max(b))
}

fn dist(p: [f64; 2], q: [f64; 2]) -> f64 {
    (p[0] - q[0]).hypot(p[1] - q[1])
}

impl Bisection {
    /// `mesh` in newest-vertex form: each triangle rotated so that its longest edge is its
    /// refinement edge; origins are the triangle numbers of `mesh`.
    fn new(mesh: &Mesh) -> Bisection {
        let tris = mesh
            .triangles
            .iter()
            .enumerate()
            .map(|(origin, &[a, b, c])| {
                let p = |v: usize| mesh.vertices[v];
                // the edge opposite each corner; rotate the longest's opposite corner first
                let len = [dist(p(b), p(c)), dist(p(c), p(a)), dist(p(a), p(b))];
                let k = (0..3).fold(0, |k, i| if len[i] > len[k] { i } else { k });
                let v = [a, b, c];
                Tri {
                    v: [v[k], v[(k + 1) % 3], v[(k + 2) % 3]],
                    origin,
                }
            })
            .collect();
        Bisection {
            vertices: mesh.vertices.clone(),
            tris,
            midpoint: HashMap::new(),
        }
    }

    fn mid(&mut self, a: usize, b: usize) -> usize {
        let vertices = &mut self.vertices;
        *self.midpoint.entry(key(a, b)).or_insert_with(|| {
            let (p, q) = (vertices[a], vertices[b]);
            vertices.push([0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])]);
            vertices.len() - 1
        })
    }

    /// Bisects the marked triangles, then keeps bisecting every triangle that has a split edge
    /// until none has (a conforming mesh). Returns false if that took more than MAX_ROUNDS.
    fn bisect(&mut self, mut marked: Vec<bool>) -> bool {
        for _ in 0..MAX_ROUNDS {
            if !marked.iter().any(|&m| m) {
                return true;
            }
            let old = std::mem::take(&mut self.tris);
            let mut tris = Vec::with_capacity(old.len() + marked.len());
            for (t, m) in old.into_iter().zip(marked) {
                if !m {
                    tris.push(t);
                    continue;
                }
                let [v0, v1, v2] = t.v;
                let m = self.mid(v1, v2);
                tris.push(Tri {
                    v: [m, v0, v1],
                    origin: t.origin,
                });
                tris.push(Tri {
                    v: [m, v2, v0],
                    origin: t.origin,
                });
            }
            self.tris = tris;
            marked = self
                .tris
                .iter()
                .map(|t| {
                    let [a, b, c] = t.v;
                    [(a, b), (b, c), (c, a)]
                        .iter()
                        .any(|&(p, q)| self.midpoint.contains_key(&key(p, q)))
                })
                .collect();
        }
        false
    }

    /// Bisects (with closure) until every triangle meets the grading's target for size `h`.
    fn grade(&mut self, grading: Grading, h: f64, tips: &[[f64; 2]]) -> bool {
        for _ in 0..MAX_ROUNDS {
            let marked: Vec<bool> = self
                .tris
                .iter()
                .map(|t| {
                    let r =
                        t.v.iter()
                            .flat_map(|&v| tips.iter().map(move |&tip| (v, tip)))
                            .map(|(v, tip)| dist(self.vertices[v], tip))
                            .fold(f64::INFINITY, f64::min);
                    diameter(&self.vertices, &t.v) > grading.target(h, r) * (1.0 + 1e-12)
                })
                .collect();
            if !marked.iter().any(|&m| m) {
                return true;
            }
            if !self.bisect(marked) {
                return false;
            }
        }
        false
    }

    /// The edge a → b as the chain of edges it was split into (a first).
    fn split_edge(&self, a: usize, b: usize, out: &mut Vec<usize>) {
        match self.midpoint.get(&key(a, b)) {
            Some(&m) => {
                self.split_edge(a, m, out);
                self.split_edge(m, b, out);
            }
            None => out.push(b),
        }
    }

    /// The refined mesh of `from`: boundary and crack edges split like the triangles, each crack
    /// piece with its parent edge's normal; parents are the triangles' origins.
    fn into_mesh(self, from: &Mesh, level: u32, coarse_triangles: usize) -> Mesh {
        let chain = |a: usize, b: usize| {
            let mut out = Vec::new();
            self.split_edge(a, b, &mut out);
            out
        };
        let boundary_edges = from
            .boundary_edges
            .iter()
            .flat_map(|&[a, b]| {
                let mut prev = a;
                chain(a, b)
                    .into_iter()
                    .map(move |v| [std::mem::replace(&mut prev, v), v])
                    .collect::<Vec<_>>()
            })
            .collect();
        let cracks = from
            .cracks
            .iter()
            .map(|c| {
                let mut nodes = vec![c.nodes[0]];
                let mut normals = Vec::new();
                for (w, &nu) in c.nodes.windows(2).zip(&c.normals) {
                    let piece = chain(w[0], w[1]);
                    normals.extend(std::iter::repeat_n(nu, piece.len()));
                    nodes.extend(piece);
                }
                CrackChain::from_parts(nodes, normals)
            })
            .collect();
        let parents = self.tris.iter().map(|t| t.origin).collect();
        let triangles = self.tris.iter().map(|t| t.v).collect();
        let mut mesh = Mesh::new(
            level,
            Layout::Graded { coarse_triangles },
            self.vertices,
            triangles,
            boundary_edges,
            cracks,
        );
        mesh.parents = parents;
        mesh
    }
}

/// Why a graded level could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("grading (beta = {beta}, radius = {radius}) did not converge at level {level}: bisection went on for more than {MAX_ROUNDS} rounds")]
pub struct GradingError {
    /// β of the grading.
    pub beta: f64,
    /// R of the grading.
    pub radius: f64,
    /// The level being built.
    pub level: u32,
}

/// The graded levels 0..=`level` of `base` (the scene's ungraded level 0, largest diameter h₀):
/// see the module documentation. Level ℓ > 0 carries its parents in level ℓ − 1.
pub fn graded_levels(base: &Mesh, grading: Grading, level: u32) -> Result<Vec<Mesh>, GradingError> {
    let h0 = base
        .triangles
        .iter()
        .map(|t| diameter(&base.vertices, t))
        .fold(0.0, f64::max);
    let tips: Vec<[f64; 2]> = base.tips().iter().map(|&v| base.vertices[v]).collect();
    let coarse_triangles = base.triangles.len();
    let fail = |l| GradingError {
        beta: grading.beta,
        radius: grading.radius,
        level: l,
    };
    let mut b = Bisection::new(base);
    if !b.grade(grading, h0, &tips) {
        return Err(fail(0));
    }
    let mut levels = vec![b.into_mesh(base, 0, coarse_triangles)];
    levels[0].parents.clear(); // level 0 has no coarser level
    for l in 1..=level {
        let prev = &levels[l as usize - 1];
        let mut b = Bisection::new_keeping_labels(prev);
        let all = vec![true; b.tris.len()];
        let h = h0 / f64::from(1u32 << l.min(31));
        if !(b.bisect(all) && b.bisect(vec![true; b.tris.len()]) && b.grade(grading, h, &tips)) {
            return Err(fail(l));
        }
        let mesh = b.into_mesh(prev, l, coarse_triangles);
        levels.push(mesh);
    }
    Ok(levels)
}

impl Bisection {
    /// A graded level as it stands: its triangles are stored in newest-vertex form already
    /// (vertex 0 newest), so their labels carry over; origins are its triangle numbers.
    fn new_keeping_labels(mesh: &Mesh) -> Bisection {
        Bisection {
            vertices: mesh.vertices.clone(),
            tris: mesh
                .triangles
                .iter()
                .enumerate()
                .map(|(origin, &v)| Tri { v, origin })
                .collect(),
            midpoint: HashMap::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::structured::structured;
    use crate::problem::{Polyline, UNIT_SQUARE};

    fn base() -> Mesh {
        let crack = Polyline {
            points: vec![[-0.5, 0.0], [0.5, 0.0]],
        };
        structured(UNIT_SQUARE, [8, 8], &[crack], 0).expect("grid")
    }

    fn area(m: &Mesh, t: &[usize; 3]) -> f64 {
        let [a, b, c] = t.map(|v| m.vertices[v]);
        0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]))
    }

    /// Conforming: every interior edge is shared by exactly two triangles (with opposite
    /// orientations), every other edge is a boundary edge; no vertex lies inside an edge.
    fn assert_conforming(m: &Mesh) {
        let mut count: HashMap<(usize, usize), i32> = HashMap::new();
        for t in &m.triangles {
            assert!(area(m, t) > 0.0, "counter-clockwise");
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                *count.entry((a, b)).or_default() += 1;
            }
        }
        let mut boundary = 0;
        for (&(a, b), &n) in &count {
            assert_eq!(n, 1, "edge {a}->{b} used twice in one direction");
            if !count.contains_key(&(b, a)) {
                boundary += 1;
            }
        }
        assert_eq!(
            boundary,
            m.boundary_edges.len(),
            "hanging node or lost boundary edge"
        );
        for &[a, b] in &m.boundary_edges {
            assert!(
                count.contains_key(&(a, b)),
                "boundary edge {a}->{b} not in a triangle"
            );
        }
    }

    #[test]
    fn target_is_uniform_outside_the_radius_and_for_beta_one() {
        let g = Grading {
            beta: 0.5,
            radius: 0.25,
        };
        assert_eq!(g.target(0.1, 0.3), 0.1);
        assert!((g.target(0.1, 0.0625) - 0.05).abs() < 1e-15); // (1/4)^(1/2)
                                                               // the floor: r0 = R (h/R)^(1/β) = 0.25·0.16 = 0.04, size h·(r0/R)^(1/2) = 0.04
        assert!((g.target(0.1, 0.0) - 0.04).abs() < 1e-15);
        let uniform = Grading {
            beta: 1.0,
            radius: 0.25,
        };
        assert_eq!(uniform.target(0.1, 0.0), 0.1);
    }

    #[test]
    fn graded_levels_are_conforming_nested_and_meet_the_target() {
        let g = Grading {
            beta: 0.5,
            radius: 0.5,
        };
        let base = base();
        let levels = graded_levels(&base, g, 3).expect("graded");
        let tips = [[-0.5, 0.0], [0.5, 0.0]];
        let h0 = 0.25 * 2f64.sqrt();
        for (l, m) in levels.iter().enumerate() {
            assert_conforming(m);
            let total: f64 = m.triangles.iter().map(|t| area(m, t)).sum();
            assert!((total - 4.0).abs() < 1e-12, "level {l} covers Ω");
            let h = h0 / f64::from(1u32 << l);
            for t in &m.triangles {
                let p = t.map(|v| m.vertices[v]);
                let d = diameter(&m.vertices, t);
                let r = p
                    .iter()
                    .flat_map(|&q| tips.iter().map(move |&tip| dist(q, tip)))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    d <= g.target(h, r) * (1.0 + 1e-9),
                    "level {l}: {d} > target"
                );
            }
            // the crack: a chain from tip to tip along y = 0, every node a vertex
            let c = &m.cracks[0];
            assert_eq!(m.vertices[c.nodes[0]], [-0.5, 0.0]);
            assert_eq!(m.vertices[*c.nodes.last().unwrap()], [0.5, 0.0]);
            assert!(c.nodes.iter().all(|&v| m.vertices[v][1] == 0.0));
            assert_eq!(c.normals.len(), c.nodes.len() - 1);
            if l > 0 {
                // nested: each triangle's corners lie in (or on) its parent
                let prev = &levels[l - 1];
                assert_eq!(m.parents.len(), m.triangles.len());
                for (t, &p) in m.triangles.iter().zip(&m.parents) {
                    let [a, b, c] = prev.triangles[p].map(|v| prev.vertices[v]);
                    for v in t {
                        let q = m.vertices[*v];
                        let s = |u: [f64; 2], w: [f64; 2]| {
                            (w[0] - u[0]) * (q[1] - u[1]) - (w[1] - u[1]) * (q[0] - u[0])
                        };
                        assert!(s(a, b) >= -1e-12 && s(b, c) >= -1e-12 && s(c, a) >= -1e-12);
                    }
                }
                // ~4× the triangles per level (the grading adds a bounded number)
                let ratio = m.triangles.len() as f64 / prev.triangles.len() as f64;
                assert!((3.5..5.5).contains(&ratio), "level {l}: ratio {ratio}");
            }
        }
        // graded: the smallest element at the tip is far below the uniform size
        let m = &levels[3];
        let tip_size = m
            .triangles
            .iter()
            .filter(|t| t.iter().any(|&v| m.vertices[v] == [0.5, 0.0]))
            .map(|t| diameter(&m.vertices, t))
            .fold(f64::INFINITY, f64::min);
        assert!(tip_size < 0.1 * h0 / 8.0, "tip elements {tip_size}");
    }

    #[test]
    fn several_cracks_and_a_kink_stay_chains_of_edges_with_their_normals() {
        let cracks = [
            Polyline {
                points: vec![[-0.75, -0.5], [-0.25, -0.5], [-0.25, 0.0]],
            },
            Polyline {
                points: vec![[0.25, 0.25], [0.75, 0.25]],
            },
        ];
        let base = structured(UNIT_SQUARE, [8, 8], &cracks, 0).expect("grid");
        let g = Grading {
            beta: 0.3,
            radius: 0.3,
        };
        let levels = graded_levels(&base, g, 2).expect("graded");
        for m in &levels {
            assert_conforming(m);
            assert_eq!(m.cracks.len(), 2);
            for (chain, crack) in m.cracks.iter().zip(&cracks) {
                let tips = [chain.nodes[0], *chain.nodes.last().unwrap()].map(|v| m.vertices[v]);
                assert_eq!(tips, [crack.points[0], *crack.points.last().unwrap()]);
                for (w, nu) in chain.nodes.windows(2).zip(&chain.normals) {
                    let (a, b) = (m.vertices[w[0]], m.vertices[w[1]]);
                    // each piece lies on a segment of the polyline and carries its normal
                    let seg = (0..crack.segments())
                        .map(|k| crack.segment(k))
                        .find(|s| s.normal() == *nu)
                        .expect("a segment with this normal");
                    let d = [b[0] - a[0], b[1] - a[1]];
                    assert!(
                        (d[0] * nu[0] + d[1] * nu[1]).abs() < 1e-14,
                        "piece along ν⊥"
                    );
                    let off = (a[0] - seg.a[0]) * nu[0] + (a[1] - seg.a[1]) * nu[1];
                    assert!(off.abs() < 1e-14, "piece on its segment's line");
                }
            }
        }
        assert!(levels[2].triangles.len() > 16 * base.triangles.len());
    }

    #[test]
    fn beta_one_is_the_uniform_refinement() {
        let g = Grading {
            beta: 1.0,
            radius: 0.5,
        };
        let levels = graded_levels(&base(), g, 2).expect("uniform");
        assert_eq!(levels[0].triangles.len(), 128);
        assert_eq!(levels[1].triangles.len(), 512);
        assert_eq!(levels[2].triangles.len(), 2048);
    }
}
