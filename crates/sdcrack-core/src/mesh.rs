//! Triangulations of the domain with the cracks as chains of mesh edges, their nested levels,
//! and the two u-space topologies (docs/design.md).
//!
//! A level's [`Mesh`] comes from a [`MeshSource`]: the structured grid of a rectangle
//! ([`structured`]: level ℓ has `2^ℓ·nx × 2^ℓ·ny` cells split by their SW–NE diagonals) or a
//! coarse triangulation (gmsh's, [`gmsh`]) refined uniformly ℓ times ([`refine`]: each triangle
//! into four, so levels are nested). Either way every crack is a chain of mesh vertices
//! `x_0 … x_I` (its tips first and last) joined by mesh edges, each edge lying on one segment of
//! the crack's polyline.
//!
//! Sides: each crack edge carries the normal ν of its polyline segment (direction turned by
//! +90°). At an interior crack node v with neighbours a (before) and b (after) on the chain, a
//! triangle corner at v lies on the **+** face when the triangle is on the left of the path
//! a → v → b (for a straight crack: its centroid c has (c − v)·ν > 0). For the `broken` u space
//! every interior crack node (tips excluded) carries a second u degree of freedom, used by the
//! triangle corners on the − face; the vertex number itself serves the + face. That numbering
//! *is* the cracked mesh of the references (docs/design.md).

pub mod bisect;
pub mod gmsh;
pub mod refine;
pub mod structured;

use crate::problem::{Domain, Meshing, PSpace, Polyline, USpace};

#[cfg(test)]
mod tests;

/// Errors in building a mesh for a scene. `crack` is the 0-based index of the scene's crack.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum MeshError {
    /// A crack point is not a vertex of the level-0 grid.
    #[error("crack point ({x}, {y}) is not a vertex of the level-0 mesh (cells {nx}×{ny}); move it onto the grid or change discretization.cells")]
    OffMesh {
        /// Which crack.
        crack: usize,
        /// x of the point.
        x: f64,
        /// y of the point.
        y: f64,
        /// Level-0 cells in x.
        nx: usize,
        /// Level-0 cells in y.
        ny: usize,
    },
    /// A crack point lies outside Ω or on Γ.
    #[error("crack point ({x}, {y}) {what}; the crack must lie strictly inside the domain")]
    NotInside {
        /// Which crack.
        crack: usize,
        /// x of the point.
        x: f64,
        /// y of the point.
        y: f64,
        /// "lies outside the domain" or "touches the boundary".
        what: &'static str,
    },
    /// A crack segment is not along a grid line.
    #[error("crack segment from ({ax}, {ay}) to ({bx}, {by}) is not along a mesh line: on a structured grid it must be horizontal, vertical or along the SW–NE cell diagonals (use mesh_size for any direction)")]
    NotOnMeshLine {
        /// Which crack.
        crack: usize,
        /// Start x.
        ax: f64,
        /// Start y.
        ay: f64,
        /// End x.
        bx: f64,
        /// End y.
        by: f64,
    },
    /// Two cracks share a grid vertex or edge.
    #[error("cracks {first} and {second} share the mesh vertex ({x}, {y}); cracks must not touch")]
    Touching {
        /// The first crack.
        first: usize,
        /// The second crack.
        second: usize,
        /// x of the vertex.
        x: f64,
        /// y of the vertex.
        y: f64,
    },
    /// `cells` with a polygon domain.
    #[error("discretization.cells needs a rectangle domain; give discretization.mesh_size for a polygon")]
    CellsNeedRectangle,
    /// gmsh failed, or a .msh file is not usable.
    #[error("{0}")]
    Gmsh(String),
    /// The cracks of a .msh file do not match the scene's.
    #[error("{0}")]
    Mismatch(String),
    /// A graded level could not be built.
    #[error(transparent)]
    Grading(#[from] bisect::GradingError),
}

impl MeshError {
    /// The scene crack an error is about, if any (the caller names it as the scene does).
    pub fn crack(&self) -> Option<usize> {
        match self {
            MeshError::OffMesh { crack, .. }
            | MeshError::NotInside { crack, .. }
            | MeshError::NotOnMeshLine { crack, .. } => Some(*crack),
            _ => None,
        }
    }
}

/// Which face of the crack a triangle corner lies on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    /// The side ν points into.
    Plus,
    /// The other side.
    Minus,
}

/// One crack as a chain of mesh vertices.
#[derive(Clone, Debug)]
pub struct CrackChain {
    /// Vertex numbers of x_0, …, x_I (both tips included).
    pub nodes: Vec<usize>,
    /// Per chain edge k (x_k → x_{k+1}): the unit normal ν of the polyline segment it lies on.
    pub normals: Vec<[f64; 2]>,
}

impl CrackChain {
    /// Number of crack edges I.
    pub fn segments(&self) -> usize {
        self.nodes.len() - 1
    }

    /// The chain of `crack`'s polyline through `nodes`, with each edge's segment normal: edge k
    /// lies on the segment whose end points bracket it (`segment_of[k]`).
    pub fn new(nodes: Vec<usize>, crack: &Polyline, segment_of: &[usize]) -> CrackChain {
        let normals = segment_of
            .iter()
            .map(|&s| crack.segment(s).normal())
            .collect();
        CrackChain { nodes, normals }
    }
}

/// How a level's vertices and triangles are numbered.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    /// The structured grid: vertex (i, j) is j·(nx + 1) + i; triangles 2(j·nx + i) (below the
    /// cell diagonal) and 2(j·nx + i) + 1.
    Structured {
        /// Cells in x at this level.
        nx: usize,
        /// Cells in y at this level.
        ny: usize,
    },
    /// A coarse mesh refined uniformly: triangle 4t + c of level ℓ + 1 lies in triangle t of
    /// level ℓ (children 0, 1, 2 at the parent's corners 0, 1, 2, child 3 in the middle).
    Refined {
        /// Triangles of level 0.
        coarse_triangles: usize,
    },
    /// Graded towards the crack tips by newest-vertex bisection ([`bisect`]): each triangle of
    /// level ℓ + 1 lies in triangle `parents[t]` of level ℓ.
    Graded {
        /// Triangles of the ungraded level 0 the levels were made from.
        coarse_triangles: usize,
    },
}

/// A triangulation of one level with its crack chains.
#[derive(Clone, Debug)]
pub struct Mesh {
    /// Refinement level ℓ.
    pub level: u32,
    /// Numbering of vertices and triangles.
    pub layout: Layout,
    /// Vertex coordinates.
    pub vertices: Vec<[f64; 2]>,
    /// Triangles, counter-clockwise.
    pub triangles: Vec<[usize; 3]>,
    /// Boundary edges, oriented counter-clockwise along Γ (outward normal = (dy, −dx)/|e|).
    pub boundary_edges: Vec<[usize; 2]>,
    /// The crack chains, in the scene's order.
    pub cracks: Vec<CrackChain>,
    /// Per triangle corner: its face where the corner is an interior crack node, else `None`.
    pub corner_sides: Vec<[Option<Side>; 3]>,
    /// [`Layout::Graded`] levels above 0: per triangle, the triangle of the previous level it lies
    /// in; empty otherwise.
    pub parents: Vec<usize>,
}

/// Degrees of freedom of a u space on a mesh.
#[derive(Clone, Debug)]
pub struct UTopology {
    /// Which space.
    pub space: USpace,
    /// Number of u unknowns.
    pub n_dofs: usize,
    /// The u dofs of each triangle (same vertex order as `Mesh::triangles`).
    pub triangle_dofs: Vec<[usize; 3]>,
    /// The mesh vertex each dof sits at.
    pub dof_vertex: Vec<usize>,
    /// For each crack node (cracks concatenated in order), its (+ dof, − dof); equal at the tips
    /// and in the continuous space.
    pub crack_dofs: Vec<(usize, usize)>,
}

impl Mesh {
    /// A mesh from its parts; computes the faces of the triangle corners at crack nodes.
    pub fn new(
        level: u32,
        layout: Layout,
        vertices: Vec<[f64; 2]>,
        triangles: Vec<[usize; 3]>,
        boundary_edges: Vec<[usize; 2]>,
        cracks: Vec<CrackChain>,
    ) -> Mesh {
        let corner_sides = corner_sides(&vertices, &triangles, &cracks);
        Mesh {
            level,
            layout,
            vertices,
            triangles,
            boundary_edges,
            cracks,
            corner_sides,
            parents: Vec::new(),
        }
    }

    /// Mesh size h: the largest triangle diameter (on a structured grid every triangle has the
    /// cell diagonal as diameter, read off the first one).
    pub fn h(&self) -> f64 {
        match self.layout {
            Layout::Structured { .. } => diameter(&self.vertices, &self.triangles[0]),
            Layout::Refined { .. } | Layout::Graded { .. } => self
                .triangles
                .iter()
                .map(|t| diameter(&self.vertices, t))
                .fold(0.0, f64::max),
        }
    }

    /// The crack nodes of every crack, concatenated in order.
    pub fn crack_nodes(&self) -> impl Iterator<Item = usize> + '_ {
        self.cracks.iter().flat_map(|c| c.nodes.iter().copied())
    }

    /// The tips: first and last node of every crack.
    pub fn tips(&self) -> Vec<usize> {
        self.cracks
            .iter()
            .flat_map(|c| [c.nodes[0], c.nodes[c.nodes.len() - 1]])
            .collect()
    }

    /// The interior crack nodes (tips excluded), cracks in order.
    fn interior_crack_nodes(&self) -> impl Iterator<Item = usize> + '_ {
        self.cracks
            .iter()
            .flat_map(|c| c.nodes[1..c.nodes.len() - 1].iter().copied())
    }

    /// The u degrees of freedom of `space` on this mesh.
    pub fn u_topology(&self, space: USpace) -> UTopology {
        let nv = self.vertices.len();
        let mut minus_of = vec![usize::MAX; nv];
        let mut dof_vertex: Vec<usize> = (0..nv).collect();
        if space == USpace::Broken {
            for (k, v) in self.interior_crack_nodes().enumerate() {
                minus_of[v] = nv + k;
                dof_vertex.push(v);
            }
        }
        let triangle_dofs = self
            .triangles
            .iter()
            .zip(&self.corner_sides)
            .map(|(t, sides)| {
                let mut dofs = *t;
                for (d, side) in dofs.iter_mut().zip(sides) {
                    if *side == Some(Side::Minus) && minus_of[*d] != usize::MAX {
                        *d = minus_of[*d];
                    }
                }
                dofs
            })
            .collect();
        let crack_dofs = self
            .crack_nodes()
            .map(|v| match minus_of[v] {
                usize::MAX => (v, v),
                m => (v, m),
            })
            .collect();
        UTopology {
            space,
            n_dofs: dof_vertex.len(),
            triangle_dofs,
            dof_vertex,
            crack_dofs,
        }
    }

    /// The p unknowns of `space` on this mesh ([`PTopology`]): for the broken-tangential space
    /// the interior crack nodes whose two crack edges share one normal are doubled, cracks in
    /// order.
    pub fn p_topology(&self, space: PSpace) -> PTopology {
        let nv = self.vertices.len();
        let mut doubled = Vec::new();
        let mut doubled_index = Vec::new();
        if space == PSpace::BrokenTangential {
            doubled_index = vec![u32::MAX; nv];
            for chain in &self.cracks {
                for j in 1..chain.nodes.len() - 1 {
                    let normal = chain.normals[j];
                    if chain.normals[j - 1] == normal {
                        doubled_index[chain.nodes[j]] = doubled.len() as u32;
                        doubled.push((chain.nodes[j], normal));
                    }
                }
            }
        }
        PTopology {
            space,
            n_dofs: 2 * nv + doubled.len(),
            doubled,
            doubled_index,
        }
    }
}

/// Degrees of freedom of a p space on a mesh (docs/design.md, The p spaces).
///
/// The unknowns 2v, 2v + 1 are p at vertex v, in the (x, y) frame, except at a *doubled* vertex
/// of [`PSpace::BrokenTangential`] (an interior crack node where the crack is straight, normal
/// ν): there 2v is p·ν (shared by both faces), 2v + 1 is p⁺·τ (the + face) and one more unknown,
/// numbered after the 2·(vertices) of the mesh, is p⁻·τ, with τ = ν turned by −90° (the
/// direction of the crack, so that ν is τ turned by +90°). Tips and kinks are never doubled: at a
/// kink, q·ν_{k−1} and q·ν_k both shared fix all of q, and at a tip p is shared as u is.
#[derive(Clone, Debug)]
pub struct PTopology {
    /// Which space.
    pub space: PSpace,
    /// Number of p unknowns: 2 per vertex plus one per doubled vertex.
    pub n_dofs: usize,
    /// The doubled vertices with their normal ν, in the order of their p⁻·τ unknowns.
    pub doubled: Vec<(usize, [f64; 2])>,
    /// Per vertex: its index in `doubled`, or `u32::MAX` (empty for the continuous space).
    doubled_index: Vec<u32>,
}

/// How a triangle corner sees p: its two unknowns and the frame they are written in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PCorner {
    /// The two unknowns of p at this corner.
    pub dofs: [usize; 2],
    /// `None`: the unknowns are (p_x, p_y); `Some(ν)`: they are (p·ν, p·τ), τ = (ν_y, −ν_x).
    pub normal: Option<[f64; 2]>,
}

/// The directions of the two p unknowns of a vertex in the frame of the crack normal ν, row by
/// row: ν, then τ = ν turned by −90° (the direction of the crack), so that p = (p·ν) ν + (p·τ) τ.
/// The one home of the frame's convention ([`PCorner`], the assembly's rotation, N's weights).
pub fn frame_directions([nx, ny]: [f64; 2]) -> [[f64; 2]; 2] {
    [[nx, ny], [ny, -nx]]
}

impl PCorner {
    /// The directions of this corner's two unknowns, row by row: [`frame_directions`] of its
    /// normal, the identity in the (x, y) frame.
    pub fn directions(&self) -> [[f64; 2]; 2] {
        self.normal
            .map_or([[1.0, 0.0], [0.0, 1.0]], frame_directions)
    }

    /// p in (x, y) at this corner from the unknowns `values` = (P[dofs[0]], P[dofs[1]]).
    pub fn to_xy(&self, values: [f64; 2]) -> [f64; 2] {
        if self.normal.is_none() {
            return values;
        }
        let [a, b] = values;
        let [nu, tau] = self.directions();
        [a * nu[0] + b * tau[0], a * nu[1] + b * tau[1]]
    }

    /// The corner's value read from the p unknowns `p`, in (x, y).
    pub fn value(&self, p: &[f64]) -> [f64; 2] {
        self.to_xy([p[self.dofs[0]], p[self.dofs[1]]])
    }
}

impl PTopology {
    /// The corner `k` of triangle `t` of `mesh`.
    pub fn corner(&self, mesh: &Mesh, t: usize, k: usize) -> PCorner {
        let v = mesh.triangles[t][k];
        let plain = PCorner {
            dofs: [2 * v, 2 * v + 1],
            normal: None,
        };
        match self.doubled_index.get(v) {
            Some(&i) if i != u32::MAX => {
                let (_, normal) = self.doubled[i as usize];
                let tangential = match mesh.corner_sides[t][k] {
                    Some(Side::Minus) => 2 * mesh.vertices.len() + i as usize,
                    _ => 2 * v + 1,
                };
                PCorner {
                    dofs: [2 * v, tangential],
                    normal: Some(normal),
                }
            }
            _ => plain,
        }
    }

    /// Whether triangle `t` has a corner at a doubled vertex.
    pub fn has_frame(&self, mesh: &Mesh, t: usize) -> bool {
        !self.doubled.is_empty()
            && mesh.triangles[t]
                .iter()
                .any(|&v| self.doubled_index[v] != u32::MAX)
    }

    /// The vertex each p unknown sits at.
    pub fn dof_vertex(&self, vertices: usize) -> Vec<usize> {
        (0..2 * vertices)
            .map(|k| k / 2)
            .chain(self.doubled.iter().map(|&(v, _)| v))
            .collect()
    }

    /// The frame normal of vertex `v`'s unknowns 2v, 2v + 1 (`None`: the (x, y) frame).
    pub fn vertex_normal(&self, v: usize) -> Option<[f64; 2]> {
        match self.doubled_index.get(v) {
            Some(&i) if i != u32::MAX => Some(self.doubled[i as usize].1),
            _ => None,
        }
    }

    /// p at every u dof of `topo` (the dof's vertex seen from its face), from the p unknowns:
    /// what the fields store and the norms integrate, exact for every u space this p space
    /// serves ([`PSpace::serves`]: a doubled vertex always has one u dof per face).
    pub fn at_u_dofs(&self, mesh: &Mesh, topo: &UTopology, p: &[f64]) -> Vec<[f64; 2]> {
        let mut out: Vec<[f64; 2]> = topo
            .dof_vertex
            .iter()
            .map(|&v| [p[2 * v], p[2 * v + 1]])
            .collect();
        if self.doubled.is_empty() {
            return out;
        }
        for (t, dofs) in topo.triangle_dofs.iter().enumerate() {
            for (k, &d) in dofs.iter().enumerate() {
                let c = self.corner(mesh, t, k);
                if c.normal.is_some() {
                    out[d] = c.value(p);
                }
            }
        }
        out
    }
}

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
                let mesh = coarse_mesh(read_msh_file(path)?, cracks, &origin)?;
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
/// one segment, with one normal), and the number of triangles.
pub fn msh_file_geometry(
    path: &std::path::Path,
) -> Result<(Domain, Vec<Polyline>, usize), MeshError> {
    let coarse = read_msh_file(path)?;
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
        .collect();
    Ok((Domain::Polygon(polygon), cracks, coarse.triangles.len()))
}

fn read_msh_file(path: &std::path::Path) -> Result<gmsh::CoarseMesh, MeshError> {
    gmsh::read_msh_file(path).map_err(|e| MeshError::Gmsh(e.to_string()))
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

/// The longest edge of a triangle.
/// The largest edge length of triangle `t`.
pub(crate) fn diameter(vertices: &[[f64; 2]], t: &[usize; 3]) -> f64 {
    let p = |k: usize| vertices[t[k]];
    let d = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    d(p(0), p(1)).max(d(p(1), p(2))).max(d(p(0), p(2)))
}

/// The face of every triangle corner that is an interior crack node (module documentation).
fn corner_sides(
    vertices: &[[f64; 2]],
    triangles: &[[usize; 3]],
    cracks: &[CrackChain],
) -> Vec<[Option<Side>; 3]> {
    // for each interior crack node: the directions to its chain neighbours (after, before)
    let mut around: Vec<Option<([f64; 2], [f64; 2])>> = vec![None; vertices.len()];
    for c in cracks {
        for w in c.nodes.windows(3) {
            let v = vertices[w[1]];
            let dir = |q: usize| [vertices[q][0] - v[0], vertices[q][1] - v[1]];
            around[w[1]] = Some((dir(w[2]), dir(w[0])));
        }
    }
    triangles
        .iter()
        .map(|t| {
            let c = centroid(vertices, t);
            t.map(|v| {
                let (out, back) = around[v]?;
                let d = [c[0] - vertices[v][0], c[1] - vertices[v][1]];
                Some(if left_of_path(out, back, d) {
                    Side::Plus
                } else {
                    Side::Minus
                })
            })
        })
        .collect()
}

/// Whether direction `d` from a crack node lies left of the path that arrives from direction
/// `back` and leaves along `out`: counter-clockwise from `out`, before reaching `back`.
fn left_of_path(out: [f64; 2], back: [f64; 2], d: [f64; 2]) -> bool {
    let cross = |a: [f64; 2], b: [f64; 2]| a[0] * b[1] - a[1] * b[0];
    let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
    if cross(out, back) == 0.0 && dot(out, back) < 0.0 {
        // straight through: the left half-plane of `out`
        return cross(out, d) > 0.0;
    }
    let angle = |x: [f64; 2]| {
        let a = cross(out, x).atan2(dot(out, x));
        if a < 0.0 {
            a + std::f64::consts::TAU
        } else {
            a
        }
    };
    angle(d) < angle(back)
}

/// Centroid of a triangle.
pub fn centroid(vertices: &[[f64; 2]], t: &[usize; 3]) -> [f64; 2] {
    let [a, b, c] = t.map(|v| vertices[v]);
    [(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0]
}
