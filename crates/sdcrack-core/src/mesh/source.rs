//! The meshes of every level of a scene ([`MeshSource`]): the level-0 mesh made once (the
//! structured grid, gmsh's triangulation or a `.msh` file) and the levels built from it, with
//! what gmsh or the file contributed ([`CoarseProvenance`]).

use super::error::MeshError;
use super::triangulation::{CrackChain, Layout, Mesh};
use super::{bisect, gmsh, refine, structured};
use crate::geometry::CrackEnds;
use crate::problem::{Domain, Meshing, Polyline};

/// What a gmsh run or a mesh file contributed to a scene's meshes (recorded in the results).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CoarseProvenance {
    /// `gmsh` for generated meshes, or the mesh file's path.
    pub source: String,
    /// gmsh's version (`gmsh --version`), when gmsh ran.
    pub gmsh_version: Option<String>,
    /// Seconds gmsh took, when it ran.
    pub gmsh_seconds: Option<f64>,
    /// Level-0 vertices.
    pub vertices: usize,
    /// Level-0 triangles.
    pub triangles: usize,
    /// The level-0 mesh as gmsh wrote it (msh 4.1 text), when gmsh ran.
    #[serde(skip)]
    pub msh_text: Option<String>,
}

/// The meshes of every level of a scene: the level-0 mesh is made once (gmsh runs once), and
/// [`MeshSource::level`] builds any level from it.
#[derive(Clone, Debug)]
pub struct MeshSource {
    kind: SourceKind,
    /// The grading towards the tips (`[discretization] grading`), if any: levels are then graded
    /// from the ungraded level 0 ([`bisect`]).
    grading: Option<crate::problem::Grading>,
    /// Where an unstructured level 0 came from (`None` for the structured grid).
    pub provenance: Option<CoarseProvenance>,
}

#[derive(Clone, Debug)]
enum SourceKind {
    Structured {
        domain: crate::problem::Rectangle,
        cells: [usize; 2],
        cracks: Vec<Polyline>,
    },
    Refined {
        coarse: Box<Mesh>,
    },
}

impl MeshSource {
    /// The level-0 mesh of `domain` with `cracks` made as `meshing` says: the structured grid
    /// for `cells` (a rectangle only), gmsh for `mesh_size`, the file for a .msh. The geometry
    /// must have been validated ([`crate::geometry`]).
    pub fn new(
        domain: &Domain,
        cracks: &[Polyline],
        meshing: &Meshing,
    ) -> Result<MeshSource, MeshError> {
        match (meshing, domain) {
            (Meshing::Cells(cells), Domain::Rectangle(r)) => {
                // the level-0 grid checks every crack against the grid
                structured::structured(*r, *cells, cracks, 0)?;
                Ok(MeshSource {
                    kind: SourceKind::Structured {
                        domain: *r,
                        cells: *cells,
                        cracks: cracks.to_vec(),
                    },
                    grading: None,
                    provenance: None,
                })
            }
            (Meshing::Cells(_), Domain::Polygon(_)) => Err(MeshError::CellsNeedRectangle),
            (Meshing::MeshSize(size), _) => {
                let (coarse, run) = gmsh_level0(&domain.polygon(), cracks, *size)?;
                let mesh = coarse_mesh(coarse, cracks, "gmsh")?;
                Ok(MeshSource::refined(mesh, "gmsh".into(), Some(run)))
            }
            (Meshing::File(path), _) => {
                let origin = path.display().to_string();
                // the scene's validation ([`msh_file_geometry_with`]) decided whether the
                // file's cracks may end on ∂Ω
                let mesh = coarse_mesh(
                    read_msh_file(path, CrackEnds::MayBeMouths)?,
                    cracks,
                    &origin,
                )?;
                Ok(MeshSource::refined(mesh, origin, None))
            }
        }
    }

    /// Levels refined from `coarse`, which came from `source` (by the gmsh run `gmsh`, if any).
    fn refined(coarse: Mesh, source: String, gmsh: Option<gmsh::GmshRun>) -> MeshSource {
        let (version, seconds, msh_text) = match gmsh {
            Some(run) => (Some(run.version), Some(run.seconds), Some(run.msh_text)),
            None => (None, None, None),
        };
        MeshSource {
            provenance: Some(CoarseProvenance {
                source,
                gmsh_version: version,
                gmsh_seconds: seconds,
                vertices: coarse.vertices.len(),
                triangles: coarse.triangles.len(),
                msh_text,
            }),
            kind: SourceKind::Refined {
                coarse: Box::new(coarse),
            },
            grading: None,
        }
    }

    /// These meshes graded towards the crack tips by `grading` (None: unchanged).
    pub fn graded(mut self, grading: Option<crate::problem::Grading>) -> MeshSource {
        self.grading = grading.filter(|g| g.beta < 1.0);
        self
    }

    /// The mesh of level `level`.
    pub fn level(&self, level: u32) -> Result<Mesh, MeshError> {
        match self.grading {
            None => self.ungraded(level),
            Some(g) => {
                let mut levels = bisect::graded_levels(&self.ungraded(0)?, g, level)?;
                Ok(levels.pop().expect("levels 0..=level"))
            }
        }
    }

    /// The number of triangles of each of the levels 0..=`level`. A graded level's count depends
    /// on the grading, so graded levels are built (once, nested); ungraded ones are counted
    /// without being built where the count is known (every refinement splits a triangle in four).
    pub fn triangle_counts(&self, level: u32) -> Result<Vec<usize>, MeshError> {
        match self.grading {
            None => {
                let coarse = self.ungraded(0)?.triangles.len();
                Ok((0..=level).map(|l| coarse << (2 * l)).collect())
            }
            Some(g) => Ok(bisect::graded_levels(&self.ungraded(0)?, g, level)?
                .iter()
                .map(|m| m.triangles.len())
                .collect()),
        }
    }

    fn ungraded(&self, level: u32) -> Result<Mesh, MeshError> {
        match &self.kind {
            SourceKind::Structured {
                domain,
                cells,
                cracks,
            } => structured::structured(*domain, *cells, cracks, level),
            SourceKind::Refined { coarse } => {
                let mut mesh = (**coarse).clone();
                for _ in 0..level {
                    mesh = refine::refine(&mesh);
                }
                Ok(mesh)
            }
        }
    }
}

/// The geometry of a .msh file: the boundary loop as a polygon and the cracks as polylines, each
/// with its collinear runs merged into one segment (so a straight crack meshed in many edges is
/// one segment, with one normal), and the number of triangles. Every crack strictly inside
/// (the scalar problem): [`msh_file_geometry_with`] and [`CrackEnds::Inside`].
pub fn msh_file_geometry(
    path: &std::path::Path,
) -> Result<(Domain, Vec<Polyline>, usize), MeshError> {
    msh_file_geometry_with(path, CrackEnds::Inside)
}

/// [`msh_file_geometry`] with the crack ends `ends` allows. With [`CrackEnds::MayBeMouths`] a
/// crack group's chain may end on a boundary vertex (a mouth), not at a corner of the merged
/// boundary polygon. (Its tips: a mesh's [`crate::mesh::Mesh::tips`]; the exact predicates of
/// [`crate::geometry::crack_tips`] need a mouth exactly on the polygon's edge, which a file's
/// node on an inclined side need not be.)
pub fn msh_file_geometry_with(
    path: &std::path::Path,
    ends: CrackEnds,
) -> Result<(Domain, Vec<Polyline>, usize), MeshError> {
    let coarse = read_msh_file(path, ends)?;
    let boundary = boundary_loop(&coarse.boundary_edges).ok_or_else(|| {
        MeshError::Gmsh(format!(
            "{}: the boundary edges do not form one closed loop (only simply connected domains are supported)",
            path.display()
        ))
    })?;
    let polygon = merge_collinear(boundary.iter().map(|&v| coarse.vertices[v]).collect(), true);
    let cracks = coarse
        .cracks
        .iter()
        .map(|chain| Polyline {
            points: merge_collinear(chain.iter().map(|&v| coarse.vertices[v]).collect(), false),
        })
        .collect::<Vec<Polyline>>();
    // A mouth is found by the mesh's topology, not by the exact predicates: a node of a straight
    // but inclined side, printed with 16 digits, is not exactly on the merged polygon's edge.
    // The reader checked the rest (only a chain's ends on ∂Ω, its edges interior ones, no shared
    // vertex), which also makes the crack meet ∂Ω transversally there.
    let on_boundary: std::collections::HashSet<usize> =
        coarse.boundary_edges.iter().flatten().copied().collect();
    for (c, chain) in coarse.cracks.iter().enumerate() {
        for v in [chain[0], chain[chain.len() - 1]] {
            let p = coarse.vertices[v];
            if on_boundary.contains(&v) && polygon.contains(&p) {
                return Err(MeshError::Gmsh(format!(
                    "{}: crack{} ends at a corner of the boundary ({}, {}): a crack may end on the boundary only away from its corners",
                    path.display(),
                    c + 1,
                    p[0],
                    p[1]
                )));
            }
        }
    }
    Ok((Domain::Polygon(polygon), cracks, coarse.triangles.len()))
}

fn read_msh_file(path: &std::path::Path, ends: CrackEnds) -> Result<gmsh::CoarseMesh, MeshError> {
    gmsh::read_msh_file_with(path, ends).map_err(|e| MeshError::Gmsh(e.to_string()))
}

/// The vertices of a closed chain of edges in order, if the edges form exactly one loop.
fn boundary_loop(edges: &[[usize; 2]]) -> Option<Vec<usize>> {
    let next: std::collections::HashMap<usize, usize> =
        edges.iter().map(|e| (e[0], e[1])).collect();
    if next.len() != edges.len() {
        return None;
    }
    let start = edges.first()?[0];
    let mut chain = vec![start];
    let mut v = *next.get(&start)?;
    while v != start {
        chain.push(v);
        v = *next.get(&v)?;
        if chain.len() > edges.len() {
            return None;
        }
    }
    (chain.len() == edges.len()).then_some(chain)
}

/// Drops the points of a polyline (or closed polygon) where it goes straight on.
fn merge_collinear(points: Vec<[f64; 2]>, closed: bool) -> Vec<[f64; 2]> {
    let n = points.len();
    let straight = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        let (u, v) = ([b[0] - a[0], b[1] - a[1]], [c[0] - b[0], c[1] - b[1]]);
        let cross = u[0] * v[1] - u[1] * v[0];
        let dot = u[0] * v[0] + u[1] * v[1];
        dot > 0.0 && cross.abs() <= 1e-12 * u[0].hypot(u[1]) * v[0].hypot(v[1])
    };
    (0..n)
        .filter(|&i| {
            let interior = closed || (i > 0 && i + 1 < n);
            !interior || !straight(points[(i + n - 1) % n], points[i], points[(i + 1) % n])
        })
        .map(|i| points[i])
        .collect()
}

/// The level-0 [`Mesh`] of a gmsh triangulation whose crack chains run along `cracks`: each
/// chain edge gets the normal of the polyline segment it lies on (a chain passes the polyline's
/// points exactly, in order; a chain running backwards is reversed).
fn coarse_mesh(
    coarse: gmsh::CoarseMesh,
    cracks: &[Polyline],
    origin: &str,
) -> Result<Mesh, MeshError> {
    if coarse.cracks.len() != cracks.len() {
        return Err(MeshError::Mismatch(format!(
            "{origin}: the mesh has {} crack groups, the scene {} cracks",
            coarse.cracks.len(),
            cracks.len()
        )));
    }
    let mut chains = Vec::with_capacity(cracks.len());
    for (c, (mut nodes, crack)) in coarse.cracks.into_iter().zip(cracks).enumerate() {
        let at = |v: usize| coarse.vertices[v];
        if at(nodes[0]) != crack.points[0] {
            nodes.reverse();
        }
        let mut segment_of = Vec::with_capacity(nodes.len() - 1);
        let mut s = 0;
        for w in nodes.windows(2) {
            if s >= crack.segments() {
                return Err(crack_mismatch(origin, c));
            }
            segment_of.push(s);
            if at(w[1]) == crack.points[s + 1] {
                s += 1;
            }
        }
        if at(nodes[0]) != crack.points[0] || s != crack.segments() {
            return Err(crack_mismatch(origin, c));
        }
        chains.push(CrackChain::new(nodes, crack, &segment_of));
    }
    let layout = Layout::Refined {
        coarse_triangles: coarse.triangles.len(),
    };
    Ok(Mesh::new(
        0,
        layout,
        coarse.vertices,
        coarse.triangles,
        coarse.boundary_edges,
        chains,
    ))
}

fn crack_mismatch(origin: &str, crack: usize) -> MeshError {
    MeshError::Mismatch(format!(
        "{origin}: the edges of crack {} do not pass through its polyline's points in order",
        crack + 1
    ))
}

/// gmsh's triangulation of `polygon` with `cracks` at `size`, run once per process for a given
/// input (gmsh is deterministic; `sdcrack run` checks the scene's meshes, then solves them).
fn gmsh_level0(
    polygon: &[[f64; 2]],
    cracks: &[Polyline],
    size: f64,
) -> Result<(gmsh::CoarseMesh, gmsh::GmshRun), MeshError> {
    type Cache = Vec<(Vec<u64>, (gmsh::CoarseMesh, gmsh::GmshRun))>;
    static CACHE: std::sync::Mutex<Cache> = std::sync::Mutex::new(Vec::new());
    let polylines: Vec<Vec<[f64; 2]>> = cracks.iter().map(|c| c.points.clone()).collect();
    // the input, bit for bit: size, then the polygon, then each crack after its length
    let mut key = vec![size.to_bits(), polygon.len() as u64];
    key.extend(polygon.iter().flatten().map(|v| v.to_bits()));
    for c in &polylines {
        key.push(c.len() as u64);
        key.extend(c.iter().flatten().map(|v| v.to_bits()));
    }
    let cached = |cache: &Cache| {
        cache
            .iter()
            .find(|(k, _)| *k == key)
            .map(|(_, v)| v.clone())
    };
    if let Some(hit) = CACHE.lock().ok().and_then(|c| cached(&c)) {
        return Ok(hit);
    }
    let work = ScratchDir::new()?;
    let made = gmsh::mesh_polygon(polygon, &polylines, size, &work.0)
        .map_err(|e| MeshError::Gmsh(e.to_string()))?;
    if let Ok(mut cache) = CACHE.lock() {
        cache.push((key, made.clone()));
    }
    Ok(made)
}

/// A temporary folder for gmsh's files, removed when dropped.
struct ScratchDir(std::path::PathBuf);

impl ScratchDir {
    fn new() -> Result<ScratchDir, MeshError> {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static COUNT: AtomicUsize = AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "sdcrack-gmsh-{}-{}",
            std::process::id(),
            COUNT.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir).map_err(|e| {
            MeshError::Gmsh(format!("cannot create {} for gmsh: {e}", dir.display()))
        })?;
        Ok(ScratchDir(dir))
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
