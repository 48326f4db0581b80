//! A triangulation of one level with its crack chains ([`Mesh`], [`CrackChain`], the faces
//! [`Side`] of the corners at crack nodes, the numbering [`Layout`]), the degrees of freedom of
//! the u and p spaces on it ([`UTopology`], [`PTopology`]), and the triangle measures its makers
//! share ([`diameter`], [`centroid`]).

use crate::problem::{PSpace, Polyline, USpace};

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
    /// Vertex numbers of x_0, …, x_I (both ends included).
    pub nodes: Vec<usize>,
    /// Per chain edge k (x_k → x_{k+1}): the unit normal ν of the polyline segment it lies on.
    pub normals: Vec<[f64; 2]>,
    /// Whether x_0, resp. x_I, is a *mouth* (a vertex of ∂Ω: an edge crack, docs/elasticity.md)
    /// rather than a tip. Set by [`Mesh::new`] from the boundary edges.
    pub mouths: [bool; 2],
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
        CrackChain::from_parts(nodes, normals)
    }

    /// The chain of `nodes` with the edge normals `normals` (its mouths are found by
    /// [`Mesh::new`]).
    pub fn from_parts(nodes: Vec<usize>, normals: Vec<[f64; 2]>) -> CrackChain {
        CrackChain {
            nodes,
            normals,
            mouths: [false; 2],
        }
    }

    /// The ends x_0 and x_I that are tips (not mouths), first end first.
    pub fn tips(&self) -> impl Iterator<Item = usize> + '_ {
        [self.nodes[0], self.nodes[self.nodes.len() - 1]]
            .into_iter()
            .zip(self.mouths)
            .filter_map(|(v, mouth)| (!mouth).then_some(v))
    }

    /// The nodes whose vertex is doubled in the cracked mesh, in chain order: every node but the
    /// tips (the interior nodes and the mouths).
    pub fn doubled_nodes(&self) -> impl Iterator<Item = usize> + '_ {
        let last = self.nodes.len() - 1;
        self.nodes
            .iter()
            .enumerate()
            .filter(move |&(j, _)| (0 < j && j < last) || self.mouths[usize::from(j == last)])
            .map(|(_, &v)| v)
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
    /// Graded towards the crack tips by newest-vertex bisection ([`bisect`](super::bisect)):
    /// each triangle of level ℓ + 1 lies in triangle `parents[t]` of level ℓ.
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
        mut cracks: Vec<CrackChain>,
    ) -> Mesh {
        mark_mouths(&mut cracks, &boundary_edges);
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

    /// The tips: the first and last node of every crack that are not mouths, cracks in order.
    pub fn tips(&self) -> Vec<usize> {
        self.cracks.iter().flat_map(CrackChain::tips).collect()
    }

    /// The crack nodes with two u copies (every crack node but the tips: the interior nodes
    /// and the mouths), cracks in order.
    fn doubled_crack_nodes(&self) -> impl Iterator<Item = usize> + '_ {
        self.cracks.iter().flat_map(CrackChain::doubled_nodes)
    }

    /// The boundary edges in the numbering of `topo` (for the `broken` space: the cracked mesh),
    /// each edge's ends as the u dofs of the one triangle it belongs to: at a mouth, each of the
    /// two boundary edges takes the copy of its own face.
    pub fn boundary_edge_dofs(&self, topo: &UTopology) -> Vec<[usize; 2]> {
        let index: std::collections::HashMap<(usize, usize), usize> = self
            .boundary_edges
            .iter()
            .enumerate()
            .map(|(i, &[a, b])| ((a, b), i))
            .collect();
        let mut out = self.boundary_edges.clone();
        for (t, dofs) in self.triangles.iter().zip(&topo.triangle_dofs) {
            for k in 0..3 {
                // Ω lies left of a boundary edge, so it is an edge of its counter-clockwise triangle
                if let Some(&i) = index.get(&(t[k], t[(k + 1) % 3])) {
                    out[i] = [dofs[k], dofs[(k + 1) % 3]];
                }
            }
        }
        out
    }

    /// The u degrees of freedom of `space` on this mesh.
    pub fn u_topology(&self, space: USpace) -> UTopology {
        let nv = self.vertices.len();
        let mut minus_of = vec![usize::MAX; nv];
        let mut dof_vertex: Vec<usize> = (0..nv).collect();
        if space == USpace::Broken {
            for (k, v) in self.doubled_crack_nodes().enumerate() {
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

/// The longest edge of a triangle.
/// The largest edge length of triangle `t`.
pub(crate) fn diameter(vertices: &[[f64; 2]], t: &[usize; 3]) -> f64 {
    let p = |k: usize| vertices[t[k]];
    let d = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    d(p(0), p(1)).max(d(p(1), p(2))).max(d(p(0), p(2)))
}

/// The face of every triangle corner that is an interior crack node (module documentation of
/// [`crate::mesh`]).
fn corner_sides(
    vertices: &[[f64; 2]],
    triangles: &[[usize; 3]],
    cracks: &[CrackChain],
) -> Vec<[Option<Side>; 3]> {
    // for each doubled crack node: the directions to its chain neighbours (after, before)
    let mut around: Vec<Option<([f64; 2], [f64; 2])>> = vec![None; vertices.len()];
    let dir = |v: usize, q: usize| {
        [
            vertices[q][0] - vertices[v][0],
            vertices[q][1] - vertices[v][1],
        ]
    };
    let minus = |d: [f64; 2]| [-d[0], -d[1]];
    for c in cracks {
        for w in c.nodes.windows(3) {
            around[w[1]] = Some((dir(w[1], w[2]), dir(w[1], w[0])));
        }
        // A mouth has one neighbour: Ω near it is a half-plane the crack enters transversally,
        // so the crack's continuation straight through the mouth (outside Ω) splits it as the
        // crack does — its + face is the left of the path, as at an interior node.
        let (first, last) = (c.nodes[0], c.nodes[c.nodes.len() - 1]);
        if c.mouths[0] {
            let out = dir(first, c.nodes[1]);
            around[first] = Some((out, minus(out)));
        }
        if c.mouths[1] {
            let back = dir(last, c.nodes[c.nodes.len() - 2]);
            around[last] = Some((minus(back), back));
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

/// Marks the crack ends that are vertices of the boundary `edges` as mouths.
fn mark_mouths(cracks: &mut [CrackChain], edges: &[[usize; 2]]) {
    let on_boundary: std::collections::HashSet<usize> = edges.iter().flatten().copied().collect();
    for c in cracks {
        let ends = [c.nodes[0], c.nodes[c.nodes.len() - 1]];
        c.mouths = ends.map(|v| on_boundary.contains(&v));
    }
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
