//! From the raw `.msh` content to the [`CoarseMesh`]: the `"boundary"` and `crackN` physical
//! groups, the triangles selected and oriented counter-clockwise, the vertices numbered in
//! node order, and every crack group ordered as one open chain of triangle edges.

use std::collections::{BTreeMap, HashMap, HashSet};

use super::error::{invalid, unsupported, Result};
use super::msh::{type_name, RawElement, RawMesh};

/// A coarse conforming triangulation of a planar domain Ω with cracks embedded as chains of
/// mesh edges.
///
/// Conventions:
/// * `vertices` holds only the nodes used by triangles, numbered `0..n` in the order of the
///   file's `$Nodes` section;
/// * every triangle is counter-clockwise (strictly positive signed area);
/// * every edge of the outer boundary ∂Ω appears once in `boundary_edges`, oriented so that
///   Ω lies on its left (as the edge appears in its unique counter-clockwise triangle);
/// * `cracks[c]` is the physical group `crack{c+1}` as the ordered chain of vertex numbers
///   from its first tip to its last tip; a crack is an ordinary interior edge chain of the
///   triangulation here (the mesh is not cut along it).
#[derive(Debug, Clone, PartialEq)]
pub struct CoarseMesh {
    /// Vertex coordinates (x, y); only vertices used by triangles, in gmsh node order.
    pub vertices: Vec<[f64; 2]>,
    /// Triangles as vertex numbers, counter-clockwise.
    pub triangles: Vec<[usize; 3]>,
    /// Edges of ∂Ω as vertex numbers, oriented with Ω on the left, in the file order of the
    /// `"boundary"` group's line elements.
    pub boundary_edges: Vec<[usize; 2]>,
    /// Crack `c` (physical group `crack{c+1}`) as the chain of vertex numbers from its first
    /// tip to its last tip. The chain runs in the stored direction (node a → node b) of the
    /// group's first line element in the file; for meshes made by [`mesh_polygon`](super::mesh_polygon) this is
    /// from the polyline's first point to its last.
    pub cracks: Vec<Vec<usize>>,
}

/// The physical tags of the named 1D groups.
pub(super) struct Groups {
    boundary: HashSet<i64>,
    /// crack1, crack2, … in order: (name, physical tags).
    cracks: Vec<(String, HashSet<i64>)>,
}

pub(super) fn find_groups(names: &HashMap<(u8, i64), String>, origin: &str) -> Result<Groups> {
    let mut boundary = HashSet::new();
    let mut cracks: BTreeMap<usize, (String, HashSet<i64>)> = BTreeMap::new();
    for (&(dim, tag), name) in names {
        if dim != 1 {
            continue;
        }
        if name == "boundary" {
            boundary.insert(tag);
            continue;
        }
        let Some(number) = crack_number(name) else {
            continue;
        };
        if number == 0 {
            return Err(invalid(
                origin,
                format!("physical group \"{name}\": crack numbers start at 1"),
            ));
        }
        let entry = cracks
            .entry(number)
            .or_insert_with(|| (name.clone(), HashSet::new()));
        if entry.0 != *name {
            return Err(invalid(
                origin,
                format!(
                    "physical groups \"{}\" and \"{name}\" both name crack{number}",
                    entry.0
                ),
            ));
        }
        entry.1.insert(tag);
    }
    if boundary.is_empty() {
        return Err(invalid(
            origin,
            "no physical curve group named \"boundary\" (the outer boundary ∂Ω)".to_string(),
        ));
    }
    if cracks.is_empty() {
        return Err(invalid(
            origin,
            "no physical curve group named crack1, crack2, …".to_string(),
        ));
    }
    if let Some(missing) = (1..=cracks.len()).find(|n| !cracks.contains_key(n)) {
        return Err(invalid(
            origin,
            format!(
                "physical groups crack1, crack2, … are not numbered consecutively (crack{missing} is missing)"
            ),
        ));
    }
    Ok(Groups {
        boundary,
        cracks: cracks.into_values().collect(),
    })
}

/// N for a name `crack<N>` (decimal digits only).
pub(super) fn crack_number(name: &str) -> Option<usize> {
    let digits = name.strip_prefix("crack")?;
    if digits.is_empty() || !digits.bytes().all(|c| c.is_ascii_digit()) {
        return None;
    }
    Some(digits.parse().unwrap_or(usize::MAX))
}

/// The coarse mesh of `raw`; a crack chain may end on ∂Ω (a mouth) only if `ends` allows it,
/// and then it must leave ∂Ω along an interior edge.
pub(super) fn assemble(
    raw: &RawMesh,
    origin: &str,
    ends: crate::geometry::CrackEnds,
) -> Result<CoarseMesh> {
    let groups = find_groups(&raw.names, origin)?;
    let mut node_index = HashMap::with_capacity(raw.nodes.len());
    for (i, n) in raw.nodes.iter().enumerate() {
        if node_index.insert(n.tag, i).is_some() {
            return Err(invalid(
                origin,
                format!("node tag {} appears twice in $Nodes", n.tag),
            ));
        }
    }
    let tris = select_triangles(raw, origin, &node_index)?;
    let (vertices, vertex_of) = number_vertices(raw, &tris);
    let triangles = orient_triangles(&tris, &vertices, &vertex_of, origin)?;
    let edges = EdgeTable::new(&triangles, &vertices, origin)?;
    let ctx = Ctx {
        raw,
        origin,
        node_index: &node_index,
        vertex_of: &vertex_of,
        edges: &edges,
    };
    let boundary_edges = ctx.boundary_edges(&groups.boundary)?;
    let on_boundary: HashSet<usize> = boundary_edges.iter().flatten().copied().collect();
    let mut owner: HashMap<usize, &str> = HashMap::new();
    let mut cracks = Vec::with_capacity(groups.cracks.len());
    for (name, tags) in &groups.cracks {
        let chain = ctx.crack_chain(name, tags)?;
        let mouths_allowed = ends == crate::geometry::CrackEnds::MayBeMouths;
        let last = chain.len() - 1;
        for (j, &v) in chain.iter().enumerate() {
            let [x, y] = vertices[v];
            let end = j == 0 || j == last;
            if on_boundary.contains(&v) && !(mouths_allowed && end) {
                return Err(invalid(
                    origin,
                    format!("{name} touches the boundary at vertex ({x}, {y})"),
                ));
            }
            if let Some(other) = owner.insert(v, name) {
                return Err(invalid(
                    origin,
                    format!("{other} and {name} share the vertex ({x}, {y})"),
                ));
            }
        }
        if mouths_allowed {
            // a chain edge on ∂Ω would run along the boundary (the mouth must be entered
            // transversally): every crack edge is an edge of two triangles
            for w in chain.windows(2) {
                if edges.get(w[0], w[1]).map(|e| e.0) != Some(2) {
                    let ([xa, ya], [xb, yb]) = (vertices[w[0]], vertices[w[1]]);
                    return Err(invalid(
                        origin,
                        format!("{name} runs along the boundary ({xa}, {ya})–({xb}, {yb})"),
                    ));
                }
            }
        }
        cracks.push(chain);
    }
    Ok(CoarseMesh {
        vertices,
        triangles,
        boundary_edges,
        cracks,
    })
}

/// The triangles as node indices (into `raw.nodes`), without repeats; checks the 2D types.
pub(super) fn select_triangles(
    raw: &RawMesh,
    origin: &str,
    node_index: &HashMap<i64, usize>,
) -> Result<Vec<[usize; 3]>> {
    if let Some(e) = raw.elements.iter().find(|e| e.dim == 3) {
        return Err(unsupported(
            origin,
            format!(
                "element {} (line {}) is a 3D {}; only planar triangle meshes are read",
                e.tag,
                e.line,
                type_name(e.etype)
            ),
        ));
    }
    if let Some(e) = raw.elements.iter().find(|e| e.dim == 2 && e.etype != 2) {
        return Err(unsupported(
            origin,
            format!(
                "element {} (line {}) is a {}; only 3-node triangles (type 2) are read",
                e.tag,
                e.line,
                type_name(e.etype)
            ),
        ));
    }
    let physical_only = raw
        .elements
        .iter()
        .any(|e| e.dim == 2 && !e.physicals.is_empty());
    let mut seen = HashSet::new();
    let mut tris = Vec::new();
    for e in &raw.elements {
        if e.dim != 2 || (physical_only && e.physicals.is_empty()) {
            continue;
        }
        let mut t = [0; 3];
        for (slot, &tag) in t.iter_mut().zip(&e.nodes) {
            *slot = lookup_node(node_index, tag, e, origin)?;
        }
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return Err(invalid(
                origin,
                format!("triangle {} (line {}) repeats a node", e.tag, e.line),
            ));
        }
        let mut key = t;
        key.sort_unstable();
        if seen.insert(key) {
            tris.push(t);
        }
    }
    if tris.is_empty() {
        return Err(invalid(
            origin,
            "no triangles (3-node triangle elements, type 2)".to_string(),
        ));
    }
    Ok(tris)
}

pub(super) fn lookup_node(
    node_index: &HashMap<i64, usize>,
    tag: i64,
    e: &RawElement,
    origin: &str,
) -> Result<usize> {
    node_index.get(&tag).copied().ok_or_else(|| {
        invalid(
            origin,
            format!(
                "element {} (line {}) uses node {tag}, which is not in $Nodes",
                e.tag, e.line
            ),
        )
    })
}

/// Vertices: the nodes used by triangles, in node order; and node index → vertex number.
pub(super) fn number_vertices(
    raw: &RawMesh,
    tris: &[[usize; 3]],
) -> (Vec<[f64; 2]>, Vec<Option<usize>>) {
    let mut used = vec![false; raw.nodes.len()];
    for &i in tris.iter().flatten() {
        used[i] = true;
    }
    let mut vertices = Vec::new();
    let mut vertex_of = vec![None; raw.nodes.len()];
    for (i, n) in raw.nodes.iter().enumerate() {
        if used[i] {
            vertex_of[i] = Some(vertices.len());
            vertices.push(n.xy);
        }
    }
    (vertices, vertex_of)
}

pub(super) fn orient_triangles(
    tris: &[[usize; 3]],
    vertices: &[[f64; 2]],
    vertex_of: &[Option<usize>],
    origin: &str,
) -> Result<Vec<[usize; 3]>> {
    let mut out = Vec::with_capacity(tris.len());
    for t in tris {
        let mut v = [0; 3];
        for (slot, &i) in v.iter_mut().zip(t) {
            *slot = vertex_of[i].unwrap_or_default(); // every triangle node is a vertex
        }
        let area = signed_area(vertices[v[0]], vertices[v[1]], vertices[v[2]]);
        if area == 0.0 {
            let [x, y] = vertices[v[0]];
            return Err(invalid(
                origin,
                format!("a triangle at vertex ({x}, {y}) has zero area"),
            ));
        }
        if area < 0.0 {
            v.swap(1, 2);
        }
        out.push(v);
    }
    Ok(out)
}

pub(super) fn signed_area(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
}

/// The edges of the triangulation: unordered pair → (number of triangles, the edge as it
/// appears in its first counter-clockwise triangle).
pub(super) struct EdgeTable {
    map: HashMap<(usize, usize), (usize, [usize; 2])>,
}

impl EdgeTable {
    fn new(triangles: &[[usize; 3]], vertices: &[[f64; 2]], origin: &str) -> Result<Self> {
        let mut map: HashMap<(usize, usize), (usize, [usize; 2])> = HashMap::new();
        for t in triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                map.entry(key(a, b)).or_insert((0, [a, b])).0 += 1;
            }
        }
        for t in triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                let n = map.get(&key(a, b)).map_or(0, |e| e.0);
                if n > 2 {
                    let ([xa, ya], [xb, yb]) = (vertices[a], vertices[b]);
                    return Err(invalid(
                        origin,
                        format!(
                            "the edge ({xa}, {ya})–({xb}, {yb}) belongs to {n} triangles (not a planar triangulation)"
                        ),
                    ));
                }
            }
        }
        Ok(EdgeTable { map })
    }

    fn get(&self, a: usize, b: usize) -> Option<(usize, [usize; 2])> {
        self.map.get(&key(a, b)).copied()
    }
}

pub(super) fn key(a: usize, b: usize) -> (usize, usize) {
    (a.min(b), a.max(b))
}

/// Shared lookups for checking the 1D groups.
pub(super) struct Ctx<'a> {
    raw: &'a RawMesh,
    origin: &'a str,
    node_index: &'a HashMap<i64, usize>,
    vertex_of: &'a [Option<usize>],
    edges: &'a EdgeTable,
}

impl Ctx<'_> {
    /// The distinct 2-node lines of a group, as node tags in file order and stored direction.
    fn group_lines(&self, name: &str, tags: &HashSet<i64>) -> Result<Vec<[i64; 2]>> {
        let mut seen = HashSet::new();
        let mut lines = Vec::new();
        for e in &self.raw.elements {
            if e.dim != 1 || !e.physicals.iter().any(|p| tags.contains(p)) {
                continue;
            }
            let [a, b] = e.nodes[..] else {
                return Err(unsupported(
                    self.origin,
                    format!(
                        "physical group \"{name}\" contains a {}; only 2-node lines (type 1) are read",
                        type_name(e.etype)
                    ),
                ));
            };
            if a == b {
                return Err(invalid(
                    self.origin,
                    format!(
                        "{name} line element {} (line {}) has equal end nodes",
                        e.tag, e.line
                    ),
                ));
            }
            lookup_node(self.node_index, a, e, self.origin)?;
            lookup_node(self.node_index, b, e, self.origin)?;
            if seen.insert((a.min(b), a.max(b))) {
                lines.push([a, b]);
            }
        }
        if lines.is_empty() {
            return Err(invalid(
                self.origin,
                format!("physical group \"{name}\" has no line elements"),
            ));
        }
        Ok(lines)
    }

    /// The vertex numbers of a group line, if it is an edge of the triangulation.
    fn edge(&self, name: &str, [a, b]: [i64; 2]) -> Result<(usize, [usize; 2])> {
        let vertex = |tag: i64| self.node_index.get(&tag).and_then(|&i| self.vertex_of[i]);
        let found = vertex(a)
            .zip(vertex(b))
            .and_then(|(va, vb)| self.edges.get(va, vb));
        match found {
            Some(edge) => Ok(edge),
            None if name == "boundary" => Err(invalid(
                self.origin,
                format!("boundary edge ({a}, {b}) is not an edge of the triangulation"),
            )),
            None => Err(invalid(
                self.origin,
                format!(
                    "{name} edge ({a}, {b}) is not an edge of the triangulation (crack must be embedded in the mesh)"
                ),
            )),
        }
    }

    /// The boundary edges, oriented with the domain on the left; checks they are exactly the
    /// edges with one triangle.
    fn boundary_edges(&self, tags: &HashSet<i64>) -> Result<Vec<[usize; 2]>> {
        let mut out = Vec::new();
        let mut interior = 0;
        for line in self.group_lines("boundary", tags)? {
            let (count, oriented) = self.edge("boundary", line)?;
            if count == 1 {
                out.push(oriented);
            } else {
                interior += 1;
            }
        }
        if interior > 0 {
            return Err(invalid(
                self.origin,
                format!(
                    "physical group \"boundary\" contains {interior} interior edges (edges of two triangles); it must be exactly the outer boundary"
                ),
            ));
        }
        let outer = self.edges.map.values().filter(|(n, _)| *n == 1).count();
        if outer > out.len() {
            return Err(invalid(
                self.origin,
                format!(
                    "physical group \"boundary\" does not cover the outer boundary ({} edges missing)",
                    outer - out.len()
                ),
            ));
        }
        Ok(out)
    }

    /// The crack group as an ordered chain of vertex numbers.
    fn crack_chain(&self, name: &str, tags: &HashSet<i64>) -> Result<Vec<usize>> {
        let lines = self.group_lines(name, tags)?;
        let chain = order_chain(&lines).map_err(|why| {
            invalid(
                self.origin,
                format!("physical group \"{name}\" is not one open chain of edges ({why})"),
            )
        })?;
        for line in &lines {
            self.edge(name, *line)?;
        }
        let vertex = |tag: &i64| {
            self.node_index
                .get(tag)
                .and_then(|&i| self.vertex_of[i])
                .unwrap_or_default()
        };
        Ok(chain.iter().map(vertex).collect())
    }
}

/// Orders the lines (node tags) as one simple open chain that traverses the first line in its
/// stored direction; otherwise says why not.
pub(super) fn order_chain(lines: &[[i64; 2]]) -> std::result::Result<Vec<i64>, String> {
    let mut adjacent: HashMap<i64, Vec<i64>> = HashMap::new();
    for &[a, b] in lines {
        adjacent.entry(a).or_default().push(b);
        adjacent.entry(b).or_default().push(a);
    }
    let most = adjacent.values().map(Vec::len).max().unwrap_or(0);
    if most > 2 {
        return Err(format!("a vertex has {most} crack edges"));
    }
    let pieces = count_pieces(&adjacent);
    if pieces > 1 {
        return Err(format!("it is in {pieces} pieces"));
    }
    if adjacent.values().all(|v| v.len() == 2) {
        return Err("it is a closed loop".to_string());
    }
    let [a, b] = lines[0];
    let forward = walk(&adjacent, a, b);
    let backward = walk(&adjacent, b, a);
    let mut chain: Vec<i64> = backward.into_iter().rev().collect();
    chain.extend(forward);
    Ok(chain)
}

/// The path from `from` through `to` onward until its end (including `to`, excluding `from`).
pub(super) fn walk(adjacent: &HashMap<i64, Vec<i64>>, from: i64, to: i64) -> Vec<i64> {
    let (mut prev, mut cur) = (from, to);
    let mut path = vec![cur];
    while let Some(&next) = adjacent
        .get(&cur)
        .and_then(|n| n.iter().find(|&&x| x != prev))
    {
        path.push(next);
        (prev, cur) = (cur, next);
    }
    path
}

pub(super) fn count_pieces(adjacent: &HashMap<i64, Vec<i64>>) -> usize {
    let mut seen = HashSet::new();
    let mut pieces = 0;
    for &start in adjacent.keys() {
        if !seen.insert(start) {
            continue;
        }
        pieces += 1;
        let mut stack = vec![start];
        while let Some(v) = stack.pop() {
            for &w in adjacent.get(&v).into_iter().flatten() {
                if seen.insert(w) {
                    stack.push(w);
                }
            }
        }
    }
    pieces
}
