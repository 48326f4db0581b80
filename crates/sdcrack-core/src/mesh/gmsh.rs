//! Coarse triangulations of cracked polygonal domains: made by the `gmsh` binary from a
//! generated `.geo` script, and read from ASCII `.msh` files (format 4.1 or 2.2).
//!
//! Physical group convention (both for generated and for user-supplied meshes):
//! the triangles are the 3-node triangles of the 2D physical groups (gmsh writes
//! `"domain"`), the 1D physical group `"boundary"` holds every edge of the outer boundary
//! ∂Ω, and the 1D physical groups `"crack1"`, `"crack2"`, … (numbered consecutively from 1)
//! each hold one crack as an open chain of mesh edges that touches neither ∂Ω nor
//! another crack.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::fmt::Write as _;
use std::path::Path;
use std::process::{Command, Output};
use std::time::Instant;

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
    /// group's first line element in the file; for meshes made by [`mesh_polygon`] this is
    /// from the polyline's first point to its last.
    pub cracks: Vec<Vec<usize>>,
}

/// What one run of the `gmsh` binary did.
#[derive(Debug, Clone)]
pub struct GmshRun {
    /// The output of `gmsh --version`, trimmed (e.g. `4.8.4`).
    pub version: String,
    /// Wall-clock seconds of the meshing call (process start to exit).
    pub seconds: f64,
    /// The ASCII msh 4.1 text gmsh produced.
    pub msh_text: String,
}

/// Errors of meshing with gmsh and of reading `.msh` files; every message is one line and
/// names the file (or the gmsh call) it is about.
#[derive(Debug, thiserror::Error)]
pub enum GmshError {
    /// The `gmsh` binary is not on `PATH`.
    #[error(
        "gmsh is not installed (apt-get install gmsh); it meshes scenes with a polygon domain or mesh_size"
    )]
    NotInstalled,
    /// Reading or writing a file, or starting gmsh, failed.
    #[error("{path}: {message}")]
    Io {
        /// The file (or program) concerned.
        path: String,
        /// The operating system's message.
        message: String,
    },
    /// gmsh exited with a failure status.
    #[error("gmsh failed on {path} ({status}): {message}")]
    Failed {
        /// The `.geo` file given to gmsh.
        path: String,
        /// The exit status, as the OS reports it.
        status: String,
        /// gmsh's first error line (the cause; later ones are usually consequences).
        message: String,
    },
    /// The polygon, cracks or mesh size given to [`mesh_polygon`] cannot be meshed.
    #[error("cannot mesh the polygon: {0}")]
    Input(String),
    /// A `.msh` section does not follow the format.
    #[error("{origin}: malformed {section} section at line {line}: {detail}")]
    Malformed {
        /// The file name.
        origin: String,
        /// The section name with its `$`, e.g. `$Nodes`.
        section: String,
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong there.
        detail: String,
    },
    /// A `.msh` feature that is not read (binary files, other versions, other element types).
    #[error("{origin}: {message}")]
    Unsupported {
        /// The file name.
        origin: String,
        /// What is not supported.
        message: String,
    },
    /// A well-formed `.msh` file that breaks a requirement on the mesh or its physical groups.
    #[error("{origin}: {message}")]
    Invalid {
        /// The file name.
        origin: String,
        /// Which requirement is broken, naming the physical group concerned.
        message: String,
    },
}

type Result<T> = std::result::Result<T, GmshError>;

// ---------------------------------------------------------------------------------------
// Running gmsh
// ---------------------------------------------------------------------------------------

/// The `.geo` script that [`mesh_polygon`] gives to gmsh.
///
/// `polygon` is the outer boundary, counter-clockwise or clockwise, closed implicitly (a last
/// point equal to the first is dropped); `cracks` are polylines of at least two points strictly
/// inside the polygon (not validated here). Points are numbered polygon first, then each crack
/// in order; every point gets characteristic length `mesh_size`; crack segment k is a Line from
/// point k to point k+1, so gmsh's line elements run from the first tip toward the last. The
/// crack lines are embedded in the surface. Physical groups: `"domain"` (the surface),
/// `"boundary"` (all polygon lines), `"crack1"`, `"crack2"`, … in the order of `cracks`.
/// Coordinates are written in Rust's shortest round-trip form, so the Points are exact.
pub fn geo_script(polygon: &[[f64; 2]], cracks: &[Vec<[f64; 2]>], mesh_size: f64) -> String {
    let polygon = open_polygon(polygon);
    let h = mesh_size;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "// sdcrack coarse mesh: polygon with {} vertices, {} crack(s), mesh_size {h:?}",
        polygon.len(),
        cracks.len()
    );
    s.push_str(&geo_options(h));
    let n = polygon.len();
    for (k, p) in polygon.iter().enumerate() {
        let _ = writeln!(
            s,
            "Point({}) = {{{:?}, {:?}, 0, {h:?}}};",
            k + 1,
            p[0],
            p[1]
        );
    }
    for k in 1..=n {
        let _ = writeln!(s, "Line({k}) = {{{k}, {}}};", k % n + 1);
    }
    let outer: Vec<usize> = (1..=n).collect();
    let _ = writeln!(s, "Curve Loop(1) = {{{}}};", join(&outer));
    s.push_str("Plane Surface(1) = {1};\n");
    let mut next = n + 1; // next free point and line tag (they coincide up to here)
    let mut next_line = n + 1;
    let mut crack_lines = Vec::new();
    for (c, crack) in cracks.iter().enumerate() {
        let _ = writeln!(s, "// crack{}", c + 1);
        let first = next;
        for p in crack {
            let _ = writeln!(s, "Point({next}) = {{{:?}, {:?}, 0, {h:?}}};", p[0], p[1]);
            next += 1;
        }
        let mut lines = Vec::new();
        for k in 0..crack.len().saturating_sub(1) {
            let _ = writeln!(
                s,
                "Line({next_line}) = {{{}, {}}};",
                first + k,
                first + k + 1
            );
            lines.push(next_line);
            next_line += 1;
        }
        if !lines.is_empty() {
            let _ = writeln!(s, "Line{{{}}} In Surface{{1}};", join(&lines));
        }
        crack_lines.push(lines);
    }
    s.push_str("Physical Surface(\"domain\") = {1};\n");
    let _ = writeln!(s, "Physical Curve(\"boundary\") = {{{}}};", join(&outer));
    for (c, lines) in crack_lines.iter().enumerate() {
        let _ = writeln!(
            s,
            "Physical Curve(\"crack{}\") = {{{}}};",
            c + 1,
            join(lines)
        );
    }
    s
}

/// Meshing options: msh 4.1 ASCII, Frontal-Delaunay, one thread, fixed random seed, linear
/// triangles, sizes from the points only.
fn geo_options(h: f64) -> String {
    format!(
        "Mesh.MshFileVersion = 4.1;\n\
         Mesh.Binary = 0;\n\
         Mesh.SaveAll = 0;\n\
         Mesh.Algorithm = 6;\n\
         Mesh.ElementOrder = 1;\n\
         Mesh.RecombineAll = 0;\n\
         Mesh.SubdivisionAlgorithm = 0;\n\
         Mesh.CharacteristicLengthFactor = 1;\n\
         Mesh.CharacteristicLengthMin = 0;\n\
         Mesh.CharacteristicLengthMax = {h:?};\n\
         Mesh.CharacteristicLengthFromPoints = 1;\n\
         Mesh.CharacteristicLengthFromCurvature = 0;\n\
         Mesh.CharacteristicLengthExtendFromBoundary = 1;\n\
         Mesh.RandomSeed = 1;\n\
         General.NumThreads = 1;\n"
    )
}

fn join(tags: &[usize]) -> String {
    let items: Vec<String> = tags.iter().map(|t| t.to_string()).collect();
    items.join(", ")
}

/// The polygon without a repeated closing point.
fn open_polygon(polygon: &[[f64; 2]]) -> &[[f64; 2]] {
    match polygon {
        [first, .., last] if polygon.len() > 1 && first == last => &polygon[..polygon.len() - 1],
        _ => polygon,
    }
}

/// Meshes the polygon with its cracks by running gmsh in `workdir`.
///
/// Writes `workdir/coarse.geo` ([`geo_script`]), runs
/// `gmsh coarse.geo -2 -o coarse.msh -format msh41 -v 2 -nt 1` there (creating `workdir` if
/// needed), and reads `workdir/coarse.msh` with the rules of [`read_msh`]. The vertices at the
/// given polygon and crack points carry the given coordinates exactly (gmsh writes only 16
/// significant digits, so they are restored from the input); other crack vertices lie on the
/// crack segments up to rounding. `cracks[c]` of the result runs from `cracks[c][0]` to the
/// last point of `cracks[c]`. The same input gives a byte-identical `.msh`.
pub fn mesh_polygon(
    polygon: &[[f64; 2]],
    cracks: &[Vec<[f64; 2]>],
    mesh_size: f64,
    workdir: &Path,
) -> Result<(CoarseMesh, GmshRun)> {
    validate_input(polygon, cracks, mesh_size)?;
    let version = gmsh_version()?;
    std::fs::create_dir_all(workdir).map_err(|e| io_error(workdir, &e))?;
    let geo = workdir.join("coarse.geo");
    let msh = workdir.join("coarse.msh");
    std::fs::write(&geo, geo_script(polygon, cracks, mesh_size)).map_err(|e| io_error(&geo, &e))?;
    match std::fs::remove_file(&msh) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(io_error(&msh, &e)),
        _ => {}
    }
    let start = Instant::now();
    let output = run_gmsh(
        &[
            "coarse.geo",
            "-2",
            "-o",
            "coarse.msh",
            "-format",
            "msh41",
            "-v",
            "2",
            "-nt",
            "1",
        ],
        workdir,
    )?;
    let seconds = start.elapsed().as_secs_f64();
    if !output.status.success() {
        return Err(GmshError::Failed {
            path: geo.display().to_string(),
            status: output.status.to_string(),
            message: first_error_line(&output),
        });
    }
    let bytes = std::fs::read(&msh).map_err(|e| io_error(&msh, &e))?;
    let msh_text = String::from_utf8_lossy(&bytes).into_owned();
    let exact: Vec<[f64; 2]> = polygon
        .iter()
        .chain(cracks.iter().flatten())
        .copied()
        .collect();
    let mesh = read_msh_snapped(&msh_text, &msh.display().to_string(), &exact)?;
    let run = GmshRun {
        version,
        seconds,
        msh_text,
    };
    Ok((mesh, run))
}

fn validate_input(polygon: &[[f64; 2]], cracks: &[Vec<[f64; 2]>], mesh_size: f64) -> Result<()> {
    let bad = |m: String| Err(GmshError::Input(m));
    if !(mesh_size.is_finite() && mesh_size > 0.0) {
        return bad(format!("mesh_size {mesh_size} is not a positive number"));
    }
    if open_polygon(polygon).len() < 3 {
        return bad(format!(
            "the polygon has {} points (3 or more needed)",
            polygon.len()
        ));
    }
    if cracks.is_empty() {
        return bad("no cracks given (a coarse mesh has at least one crack)".to_string());
    }
    if let Some(c) = cracks.iter().position(|c| c.len() < 2) {
        return bad(format!("crack{} has fewer than 2 points", c + 1));
    }
    let all = polygon.iter().chain(cracks.iter().flatten());
    if let Some(p) = all
        .into_iter()
        .find(|p| !(p[0].is_finite() && p[1].is_finite()))
    {
        return bad(format!("point ({}, {}) is not finite", p[0], p[1]));
    }
    Ok(())
}

/// The version of the `gmsh` on `PATH` (`gmsh --version`, trimmed), or
/// [`GmshError::NotInstalled`].
pub fn gmsh_version() -> Result<String> {
    let output = run_gmsh(&["--version"], Path::new("."))?;
    if !output.status.success() {
        return Err(GmshError::Failed {
            path: "gmsh --version".to_string(),
            status: output.status.to_string(),
            message: first_error_line(&output),
        });
    }
    // gmsh 4.8 prints the version on stdout, older versions on stderr.
    let stdout = String::from_utf8_lossy(&output.stdout).trim().to_string();
    if stdout.is_empty() {
        Ok(String::from_utf8_lossy(&output.stderr).trim().to_string())
    } else {
        Ok(stdout)
    }
}

fn run_gmsh(args: &[&str], dir: &Path) -> Result<Output> {
    Command::new("gmsh")
        .args(args)
        .current_dir(dir)
        .output()
        .map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => GmshError::NotInstalled,
            _ => GmshError::Io {
                path: "gmsh".to_string(),
                message: e.to_string(),
            },
        })
}

/// gmsh's first `Error` line (stderr, then stdout) without its `Error   :` prefix, skipping
/// the error-summary boilerplate; the last output line if there is no error line.
fn first_error_line(output: &Output) -> String {
    let stderr = String::from_utf8_lossy(&output.stderr);
    let stdout = String::from_utf8_lossy(&output.stdout);
    let boilerplate = ["----", "error summary", "warnings", "errors", "full log"];
    let is_cause = |l: &&str| l.starts_with("Error") && !boilerplate.iter().any(|b| l.contains(b));
    let lines = stderr.lines().chain(stdout.lines()).map(str::trim);
    let found = match lines.clone().find(is_cause) {
        Some(line) => line
            .trim_start_matches("Error")
            .trim_start()
            .trim_start_matches(':')
            .trim_start(),
        None => lines.clone().rfind(|l| !l.is_empty()).unwrap_or_default(),
    };
    if found.is_empty() {
        "no error message".to_string()
    } else {
        found.to_string()
    }
}

fn io_error(path: &Path, e: &std::io::Error) -> GmshError {
    GmshError::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

// ---------------------------------------------------------------------------------------
// Reading .msh files
// ---------------------------------------------------------------------------------------

/// Reads an ASCII gmsh mesh (format 4.1 or 2.2, with `$PhysicalNames`) into a [`CoarseMesh`];
/// `origin` names the file in error messages.
///
/// Requirements (each violation is a [`GmshError`] naming the file and the group):
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
    read_msh_snapped(text, origin, &[])
}

/// Reads an ASCII `.msh` file from disk with [`read_msh`] (the path is the origin); invalid
/// UTF-8 is replaced, so binary files reach the binary-format error.
pub fn read_msh_file(path: &Path) -> Result<CoarseMesh> {
    let bytes = std::fs::read(path).map_err(|e| io_error(path, &e))?;
    read_msh(
        &String::from_utf8_lossy(&bytes),
        &path.display().to_string(),
    )
}

fn read_msh_snapped(text: &str, origin: &str, exact: &[[f64; 2]]) -> Result<CoarseMesh> {
    let mut raw = parse_msh(text, origin)?;
    snap_nodes(&mut raw.nodes, exact);
    assemble(&raw, origin)
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

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

// ---- raw file content ------------------------------------------------------------------

#[derive(Debug, Clone, Copy, PartialEq)]
enum Version {
    V22,
    V41,
}

#[derive(Debug)]
struct RawNode {
    tag: i64,
    xy: [f64; 2],
}

#[derive(Debug)]
struct RawElement {
    line: usize,
    tag: i64,
    etype: i64,
    dim: u8,
    physicals: Vec<i64>,
    nodes: Vec<i64>,
}

#[derive(Debug, Default)]
struct RawMesh {
    /// (dimension, physical tag) → name.
    names: HashMap<(u8, i64), String>,
    nodes: Vec<RawNode>,
    elements: Vec<RawElement>,
}

type Line<'a> = (usize, &'a str);

struct Section<'a> {
    name: &'a str,
    start: usize,
    end: usize,
    body: Vec<Line<'a>>,
}

fn parse_msh(text: &str, origin: &str) -> Result<RawMesh> {
    let version = mesh_format(text, origin)?;
    let sections = split_sections(text, origin)?;
    let once = |name: &str| -> Result<Option<&Section>> {
        let mut found = sections.iter().filter(|s| s.name == name);
        let first = found.next();
        match found.next() {
            Some(second) => Err(malformed(
                origin,
                name,
                second.start,
                "the section appears twice",
            )),
            None => Ok(first),
        }
    };
    if let Some(s) = once("PartitionedEntities")? {
        return Err(unsupported(
            origin,
            format!(
                "partitioned meshes ($PartitionedEntities at line {}) are not supported",
                s.start
            ),
        ));
    }
    let mut raw = RawMesh::default();
    if let Some(s) = once("PhysicalNames")? {
        raw.names = parse_physical_names(&mut Body::new(origin, s))?;
    }
    let entities = match (version, once("Entities")?) {
        (Version::V41, Some(s)) => parse_entities(&mut Body::new(origin, s))?,
        _ => HashMap::new(),
    };
    let nodes = once("Nodes")?.ok_or_else(|| invalid(origin, "no $Nodes section".to_string()))?;
    let elements =
        once("Elements")?.ok_or_else(|| invalid(origin, "no $Elements section".to_string()))?;
    let (mut nb, mut eb) = (Body::new(origin, nodes), Body::new(origin, elements));
    match version {
        Version::V41 => {
            raw.nodes = parse_nodes41(&mut nb)?;
            raw.elements = parse_elements41(&mut eb, &entities)?;
        }
        Version::V22 => {
            raw.nodes = parse_nodes22(&mut nb)?;
            raw.elements = parse_elements22(&mut eb)?;
        }
    }
    Ok(raw)
}

/// The version from the `$MeshFormat` header; refuses binary files before anything else is
/// read.
fn mesh_format(text: &str, origin: &str) -> Result<Version> {
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim()));
    if !lines.any(|(_, l)| l == "$MeshFormat") {
        return Err(invalid(
            origin,
            "not a gmsh .msh file (no $MeshFormat section)".to_string(),
        ));
    }
    let (line, header) = lines
        .find(|(_, l)| !l.is_empty())
        .ok_or_else(|| malformed(origin, "MeshFormat", 1, "the file ends after $MeshFormat"))?;
    let fields: Vec<&str> = header.split_whitespace().collect();
    let [version, file_type, _data_size] = fields[..] else {
        return Err(malformed(
            origin,
            "MeshFormat",
            line,
            format!(
                "expected `version file-type data-size`, found `{}`",
                snippet(header)
            ),
        ));
    };
    if file_type != "0" {
        return Err(unsupported(
            origin,
            "binary .msh files are not supported; save it as ASCII (Mesh.Binary = 0)".to_string(),
        ));
    }
    match version {
        "4.1" => Ok(Version::V41),
        "2" | "2.0" | "2.1" | "2.2" => Ok(Version::V22),
        _ => Err(unsupported(
            origin,
            format!("msh format version {version} is not supported (ASCII 4.1 or 2.2 are read)"),
        )),
    }
}

fn split_sections<'a>(text: &'a str, origin: &str) -> Result<Vec<Section<'a>>> {
    let mut sections = Vec::new();
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim()));
    while let Some((start, line)) = lines.next() {
        let Some(name) = line.strip_prefix('$') else {
            continue; // text outside sections is ignored, as gmsh does
        };
        let end_tag = format!("$End{name}");
        let mut body = Vec::new();
        let mut end = None;
        for (n, l) in lines.by_ref() {
            if l == end_tag {
                end = Some(n);
                break;
            }
            if !l.is_empty() {
                body.push((n, l));
            }
        }
        let end =
            end.ok_or_else(|| malformed(origin, name, start, format!("no {end_tag} closes it")))?;
        sections.push(Section {
            name,
            start,
            end,
            body,
        });
    }
    Ok(sections)
}

/// A cursor over the non-empty lines of one section.
struct Body<'a> {
    origin: &'a str,
    section: &'a str,
    lines: &'a [Line<'a>],
    pos: usize,
    end: usize,
}

impl<'a> Body<'a> {
    fn new(origin: &'a str, s: &'a Section<'a>) -> Self {
        Body {
            origin,
            section: s.name,
            lines: &s.body,
            pos: 0,
            end: s.end,
        }
    }

    fn error(&self, line: usize, detail: impl Into<String>) -> GmshError {
        malformed(self.origin, self.section, line, detail)
    }

    fn next(&mut self, what: &str) -> Result<Line<'a>> {
        let line = self.lines.get(self.pos).copied();
        self.pos += 1;
        line.ok_or_else(|| {
            self.error(
                self.end,
                format!("the section ends where {what} was expected"),
            )
        })
    }

    /// The next line as a token reader.
    fn tokens(&mut self, what: &'a str) -> Result<Tokens<'a>> {
        let (line, text) = self.next(what)?;
        Ok(Tokens {
            origin: self.origin,
            section: self.section,
            line,
            what,
            it: text.split_whitespace(),
        })
    }

    /// The next line as exactly `n` integers.
    fn ints(&mut self, what: &'a str, n: usize) -> Result<(usize, Vec<i64>)> {
        let mut t = self.tokens(what)?;
        let values = (0..n).map(|_| t.int()).collect::<Result<Vec<_>>>()?;
        t.done()?;
        Ok((t.line, values))
    }

    /// Lines not consumed yet (bounds preallocation by counts read from the file).
    fn remaining(&self) -> usize {
        self.lines.len().saturating_sub(self.pos)
    }

    fn finish(&self) -> Result<()> {
        match self.lines.get(self.pos) {
            Some(&(line, text)) => {
                Err(self.error(line, format!("unexpected extra line `{}`", snippet(text))))
            }
            None => Ok(()),
        }
    }
}

/// Whitespace-separated fields of one line.
struct Tokens<'a> {
    origin: &'a str,
    section: &'a str,
    line: usize,
    what: &'a str,
    it: std::str::SplitWhitespace<'a>,
}

impl<'a> Tokens<'a> {
    fn error(&self, detail: String) -> GmshError {
        malformed(self.origin, self.section, self.line, detail)
    }

    fn field(&mut self) -> Result<&'a str> {
        let what = self.what;
        self.it
            .next()
            .ok_or_else(|| self.error(format!("too few fields in {what}")))
    }

    fn int(&mut self) -> Result<i64> {
        let f = self.field()?;
        f.parse::<i64>()
            .map_err(|_| self.error(format!("`{}` is not an integer", snippet(f))))
    }

    fn count(&mut self) -> Result<usize> {
        let v = self.int()?;
        usize::try_from(v).map_err(|_| self.error(format!("negative count {v}")))
    }

    fn float(&mut self) -> Result<f64> {
        let f = self.field()?;
        match f.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.error(format!("`{}` is not a finite number", snippet(f)))),
        }
    }

    /// The remaining fields as integers.
    fn rest_ints(&mut self) -> Result<Vec<i64>> {
        let mut out = Vec::new();
        while let Some(f) = self.it.next() {
            let v = f
                .parse::<i64>()
                .map_err(|_| self.error(format!("`{}` is not an integer", snippet(f))))?;
            out.push(v);
        }
        Ok(out)
    }

    fn done(&mut self) -> Result<()> {
        match self.it.next() {
            Some(f) => Err(self.error(format!(
                "unexpected field `{}` in {}",
                snippet(f),
                self.what
            ))),
            None => Ok(()),
        }
    }
}

fn parse_physical_names(b: &mut Body) -> Result<HashMap<(u8, i64), String>> {
    let (line, header) = b.ints("the number of names", 1)?;
    let n = usize::try_from(header[0]).map_err(|_| b.error(line, "negative count"))?;
    let mut names = HashMap::new();
    for _ in 0..n {
        let (line, text) = b.next("`dimension tag \"name\"`")?;
        let parsed = split_name_line(text);
        let (dim, tag, name) = parsed.ok_or_else(|| {
            b.error(
                line,
                format!(
                    "expected `dimension tag \"name\"`, found `{}`",
                    snippet(text)
                ),
            )
        })?;
        let dim = dimension(dim).ok_or_else(|| b.error(line, format!("bad dimension {dim}")))?;
        names.insert((dim, tag), name.to_string());
    }
    b.finish()?;
    Ok(names)
}

fn split_name_line(text: &str) -> Option<(i64, i64, &str)> {
    let (dim, rest) = text.split_once(char::is_whitespace)?;
    let (tag, rest) = rest.trim_start().split_once(char::is_whitespace)?;
    let name = rest.trim().strip_prefix('"')?.strip_suffix('"')?;
    Some((dim.parse().ok()?, tag.parse().ok()?, name))
}

fn dimension(d: i64) -> Option<u8> {
    u8::try_from(d).ok().filter(|d| *d <= 3)
}

/// msh 4.1 `$Entities`: (dimension, entity tag) → physical tags.
fn parse_entities(b: &mut Body) -> Result<HashMap<(u8, i64), Vec<i64>>> {
    let (line, counts) = b.ints("`numPoints numCurves numSurfaces numVolumes`", 4)?;
    let mut map = HashMap::new();
    for (dim, &count) in counts.iter().enumerate() {
        let count = usize::try_from(count).map_err(|_| b.error(line, "negative entity count"))?;
        let dim = dim as u8;
        for _ in 0..count {
            let mut t = b.tokens("an entity line")?;
            let tag = t.int()?;
            let coords = if dim == 0 { 3 } else { 6 };
            for _ in 0..coords {
                t.float()?;
            }
            let n = t.count()?;
            let physicals = (0..n).map(|_| t.int()).collect::<Result<Vec<_>>>()?;
            if dim > 0 {
                let nb = t.count()?;
                for _ in 0..nb {
                    t.int()?;
                }
            }
            t.done()?;
            map.insert((dim, tag), physicals);
        }
    }
    b.finish()?;
    Ok(map)
}

fn parse_nodes41(b: &mut Body) -> Result<Vec<RawNode>> {
    let (line, header) = b.ints("`numEntityBlocks numNodes minNodeTag maxNodeTag`", 4)?;
    let (blocks, total) = (header[0], header[1]);
    let mut nodes = Vec::with_capacity(b.remaining());
    for _ in 0..blocks.max(0) {
        let (bline, block) = b.ints("`entityDim entityTag parametric numNodesInBlock`", 4)?;
        if block[2] != 0 {
            return Err(unsupported(
                b.origin,
                format!(
                    "parametric node coordinates ($Nodes block at line {bline}) are not supported; save with Mesh.SaveParametric = 0"
                ),
            ));
        }
        let n = usize::try_from(block[3]).map_err(|_| b.error(bline, "negative node count"))?;
        let mut tags = Vec::with_capacity(n.min(b.remaining()));
        for _ in 0..n {
            tags.push(b.ints("a node tag", 1)?.1[0]);
        }
        for tag in tags {
            let mut t = b.tokens("`x y z`")?;
            let xyz = [t.float()?, t.float()?, t.float()?];
            t.done()?;
            nodes.push(node(b, t.line, tag, xyz)?);
        }
    }
    if i64::try_from(nodes.len()).ok() != Some(total) || blocks < 0 {
        return Err(b.error(
            line,
            format!(
                "the header announces {total} nodes, the blocks hold {}",
                nodes.len()
            ),
        ));
    }
    b.finish()?;
    Ok(nodes)
}

fn parse_nodes22(b: &mut Body) -> Result<Vec<RawNode>> {
    let (line, header) = b.ints("the number of nodes", 1)?;
    let n = usize::try_from(header[0]).map_err(|_| b.error(line, "negative node count"))?;
    let mut nodes = Vec::with_capacity(n.min(b.remaining()));
    for _ in 0..n {
        let mut t = b.tokens("`node-number x y z`")?;
        let tag = t.int()?;
        let xyz = [t.float()?, t.float()?, t.float()?];
        t.done()?;
        nodes.push(node(b, t.line, tag, xyz)?);
    }
    b.finish()?;
    Ok(nodes)
}

fn node(b: &Body, line: usize, tag: i64, xyz: [f64; 3]) -> Result<RawNode> {
    if tag < 1 {
        return Err(b.error(line, format!("node tag {tag} is not positive")));
    }
    if xyz[2] != 0.0 {
        return Err(invalid(
            b.origin,
            format!(
                "node {tag} has z = {}; only planar meshes in the z = 0 plane are read",
                xyz[2]
            ),
        ));
    }
    Ok(RawNode {
        tag,
        xy: [xyz[0], xyz[1]],
    })
}

fn parse_elements41(
    b: &mut Body,
    entities: &HashMap<(u8, i64), Vec<i64>>,
) -> Result<Vec<RawElement>> {
    let (line, header) = b.ints(
        "`numEntityBlocks numElements minElementTag maxElementTag`",
        4,
    )?;
    let (blocks, total) = (header[0], header[1]);
    let mut elements = Vec::with_capacity(b.remaining());
    for _ in 0..blocks.max(0) {
        let (bline, block) = b.ints("`entityDim entityTag elementType numElementsInBlock`", 4)?;
        let dim = dimension(block[0])
            .ok_or_else(|| b.error(bline, format!("bad dimension {}", block[0])))?;
        let physicals = entities.get(&(dim, block[1])).cloned().unwrap_or_default();
        let etype = block[2];
        let n = usize::try_from(block[3]).map_err(|_| b.error(bline, "negative element count"))?;
        for _ in 0..n {
            let mut t = b.tokens("`elementTag nodeTag …`")?;
            let tag = t.int()?;
            let nodes = t.rest_ints()?;
            let element = RawElement {
                line: t.line,
                tag,
                etype,
                dim,
                physicals: physicals.clone(),
                nodes,
            };
            check_node_count(b, &element)?;
            elements.push(element);
        }
    }
    if i64::try_from(elements.len()).ok() != Some(total) || blocks < 0 {
        return Err(b.error(
            line,
            format!(
                "the header announces {total} elements, the blocks hold {}",
                elements.len()
            ),
        ));
    }
    b.finish()?;
    Ok(elements)
}

fn parse_elements22(b: &mut Body) -> Result<Vec<RawElement>> {
    let (line, header) = b.ints("the number of elements", 1)?;
    let n = usize::try_from(header[0]).map_err(|_| b.error(line, "negative element count"))?;
    let mut elements = Vec::with_capacity(n.min(b.remaining()));
    for _ in 0..n {
        let mut t = b.tokens("`elm-number elm-type number-of-tags tags… nodes…`")?;
        let (tag, etype, ntags) = (t.int()?, t.int()?, t.count()?);
        let tags = (0..ntags).map(|_| t.int()).collect::<Result<Vec<_>>>()?;
        let nodes = t.rest_ints()?;
        let line = t.line;
        let (dim, _, _) = element_type(etype).ok_or_else(|| {
            unsupported(
                b.origin,
                format!("element type {etype} (line {line}) is not supported"),
            )
        })?;
        let physicals = tags
            .first()
            .copied()
            .filter(|&p| p != 0)
            .into_iter()
            .collect();
        let element = RawElement {
            line,
            tag,
            etype,
            dim,
            physicals,
            nodes,
        };
        check_node_count(b, &element)?;
        elements.push(element);
    }
    b.finish()?;
    Ok(elements)
}

fn check_node_count(b: &Body, e: &RawElement) -> Result<()> {
    match element_type(e.etype) {
        Some((_, n, name)) if n != e.nodes.len() => Err(b.error(
            e.line,
            format!(
                "element {} is a {name} but lists {} nodes",
                e.tag,
                e.nodes.len()
            ),
        )),
        _ => Ok(()),
    }
}

/// (dimension, number of nodes, name) of the gmsh element types.
fn element_type(etype: i64) -> Option<(u8, usize, &'static str)> {
    let info = match etype {
        1 => (1, 2, "2-node line"),
        2 => (2, 3, "3-node triangle"),
        3 => (2, 4, "4-node quadrangle"),
        4 => (3, 4, "4-node tetrahedron"),
        5 => (3, 8, "8-node hexahedron"),
        6 => (3, 6, "6-node prism"),
        7 => (3, 5, "5-node pyramid"),
        8 => (1, 3, "3-node line"),
        9 => (2, 6, "6-node triangle"),
        10 => (2, 9, "9-node quadrangle"),
        11 => (3, 10, "10-node tetrahedron"),
        12 => (3, 27, "27-node hexahedron"),
        13 => (3, 18, "18-node prism"),
        14 => (3, 14, "14-node pyramid"),
        15 => (0, 1, "1-node point"),
        16 => (2, 8, "8-node quadrangle"),
        17 => (3, 20, "20-node hexahedron"),
        18 => (3, 15, "15-node prism"),
        19 => (3, 13, "13-node pyramid"),
        20 => (2, 9, "9-node triangle"),
        21 => (2, 10, "10-node triangle"),
        22 => (2, 12, "12-node triangle"),
        23 => (2, 15, "15-node triangle"),
        24 => (2, 15, "15-node incomplete triangle"),
        25 => (2, 21, "21-node triangle"),
        26 => (1, 4, "4-node line"),
        27 => (1, 5, "5-node line"),
        28 => (1, 6, "6-node line"),
        _ => return None,
    };
    Some(info)
}

fn type_name(etype: i64) -> String {
    match element_type(etype) {
        Some((_, _, name)) => format!("{name} (type {etype})"),
        None => format!("element type {etype}"),
    }
}

// ---- from raw content to the coarse mesh -------------------------------------------------

/// The physical tags of the named 1D groups.
struct Groups {
    boundary: HashSet<i64>,
    /// crack1, crack2, … in order: (name, physical tags).
    cracks: Vec<(String, HashSet<i64>)>,
}

fn find_groups(names: &HashMap<(u8, i64), String>, origin: &str) -> Result<Groups> {
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
fn crack_number(name: &str) -> Option<usize> {
    let digits = name.strip_prefix("crack")?;
    if digits.is_empty() || !digits.bytes().all(|c| c.is_ascii_digit()) {
        return None;
    }
    Some(digits.parse().unwrap_or(usize::MAX))
}

fn assemble(raw: &RawMesh, origin: &str) -> Result<CoarseMesh> {
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
        for &v in &chain {
            let [x, y] = vertices[v];
            if on_boundary.contains(&v) {
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
fn select_triangles(
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

fn lookup_node(
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
fn number_vertices(raw: &RawMesh, tris: &[[usize; 3]]) -> (Vec<[f64; 2]>, Vec<Option<usize>>) {
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

fn orient_triangles(
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

fn signed_area(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
}

/// The edges of the triangulation: unordered pair → (number of triangles, the edge as it
/// appears in its first counter-clockwise triangle).
struct EdgeTable {
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

fn key(a: usize, b: usize) -> (usize, usize) {
    (a.min(b), a.max(b))
}

/// Shared lookups for checking the 1D groups.
struct Ctx<'a> {
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
fn order_chain(lines: &[[i64; 2]]) -> std::result::Result<Vec<i64>, String> {
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
fn walk(adjacent: &HashMap<i64, Vec<i64>>, from: i64, to: i64) -> Vec<i64> {
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

fn count_pieces(adjacent: &HashMap<i64, Vec<i64>>) -> usize {
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

/// At most 40 characters of file content, for messages.
fn snippet(text: &str) -> String {
    match text.char_indices().nth(40) {
        Some((cut, _)) => format!("{}…", &text[..cut]),
        None => text.to_string(),
    }
}

fn malformed(origin: &str, section: &str, line: usize, detail: impl Into<String>) -> GmshError {
    GmshError::Malformed {
        origin: origin.to_string(),
        section: format!("${section}"),
        line,
        detail: detail.into(),
    }
}

fn unsupported(origin: &str, message: String) -> GmshError {
    GmshError::Unsupported {
        origin: origin.to_string(),
        message,
    }
}

fn invalid(origin: &str, message: String) -> GmshError {
    GmshError::Invalid {
        origin: origin.to_string(),
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;
    use std::path::PathBuf;

    use crate::geometry::L_SHAPE;

    fn l_cracks() -> Vec<Vec<[f64; 2]>> {
        vec![
            vec![[-0.7, -0.5], [-0.2, -0.3], [0.4, -0.6]],
            vec![[-0.8, 0.5], [-0.3, 0.7]],
        ]
    }

    fn have_gmsh() -> bool {
        match gmsh_version() {
            Ok(_) => true,
            Err(e) => {
                println!("skipping a gmsh test: {e}");
                false
            }
        }
    }

    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("sdgmsh-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    fn area(m: &CoarseMesh, t: &[usize; 3]) -> f64 {
        signed_area(m.vertices[t[0]], m.vertices[t[1]], m.vertices[t[2]])
    }

    fn edge_count(m: &CoarseMesh) -> usize {
        let edges: HashSet<(usize, usize)> = m
            .triangles
            .iter()
            .flat_map(|t| (0..3).map(move |k| key(t[k], t[(k + 1) % 3])))
            .collect();
        edges.len()
    }

    fn segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let s = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy);
        let s = s.clamp(0.0, 1.0);
        dist(p, [a[0] + s * dx, a[1] + s * dy])
    }

    fn polyline_length(points: &[[f64; 2]]) -> f64 {
        points.windows(2).map(|w| dist(w[0], w[1])).sum()
    }

    /// Checks triangles, area, boundary, Euler characteristic and the crack chains.
    fn check_mesh(m: &CoarseMesh, polygon_area: f64, perimeter: f64, cracks: &[Vec<[f64; 2]>]) {
        assert!(
            m.triangles.iter().all(|t| area(m, t) > 0.0),
            "a triangle is not CCW"
        );
        let total: f64 = m.triangles.iter().map(|t| area(m, t)).sum();
        assert!((total - polygon_area).abs() < 1e-12, "area {total}");
        let directed: HashSet<[usize; 2]> = m
            .triangles
            .iter()
            .flat_map(|t| (0..3).map(move |k| [t[k], t[(k + 1) % 3]]))
            .collect();
        assert!(m.boundary_edges.iter().all(|e| directed.contains(e)));
        let length: f64 = m
            .boundary_edges
            .iter()
            .map(|e| dist(m.vertices[e[0]], m.vertices[e[1]]))
            .sum();
        assert!(
            (length - perimeter).abs() < 1e-12,
            "boundary length {length}"
        );
        let shoelace: f64 = m
            .boundary_edges
            .iter()
            .map(|&[a, b]| signed_area([0.0, 0.0], m.vertices[a], m.vertices[b]))
            .sum();
        assert!(
            (shoelace - polygon_area).abs() < 1e-12,
            "boundary not CCW: {shoelace}"
        );
        let euler = m.vertices.len() as i64 - edge_count(m) as i64 + m.triangles.len() as i64;
        assert_eq!(euler, 1);
        assert_eq!(m.cracks.len(), cracks.len());
        for (chain, polyline) in m.cracks.iter().zip(cracks) {
            check_chain(m, chain, polyline);
        }
    }

    fn check_chain(m: &CoarseMesh, chain: &[usize], polyline: &[[f64; 2]]) {
        let points: Vec<[f64; 2]> = chain.iter().map(|&v| m.vertices[v]).collect();
        assert_eq!(points.first(), polyline.first(), "first tip");
        assert_eq!(points.last(), polyline.last(), "last tip");
        let mut from = 0;
        for p in polyline {
            let at = points[from..]
                .iter()
                .position(|q| q == p)
                .expect("polyline point is a vertex");
            from += at;
        }
        for &p in &points {
            let d = polyline
                .windows(2)
                .map(|w| segment_distance(p, w[0], w[1]))
                .fold(f64::INFINITY, f64::min);
            assert!(d < 1e-12, "crack vertex {p:?} is {d} off the polyline");
        }
        let (lc, lp) = (polyline_length(&points), polyline_length(polyline));
        assert!((lc - lp).abs() < 1e-12, "chain length {lc} vs {lp}");
    }

    #[test]
    fn geo_script_names_groups_and_embeds_cracks() {
        let geo = geo_script(&L_SHAPE, &l_cracks(), 0.25);
        for needle in [
            "Point(1) = {-1.0, -1.0, 0, 0.25};",
            "Point(7) = {-0.7, -0.5, 0, 0.25};",
            "Line(6) = {6, 1};",
            "Line(7) = {7, 8};",
            "Line(8) = {8, 9};",
            "Line{7, 8} In Surface{1};",
            "Line{9} In Surface{1};",
            "Physical Surface(\"domain\") = {1};",
            "Physical Curve(\"boundary\") = {1, 2, 3, 4, 5, 6};",
            "Physical Curve(\"crack1\") = {7, 8};",
            "Physical Curve(\"crack2\") = {9};",
            "Mesh.RandomSeed = 1;",
        ] {
            assert!(geo.contains(needle), "missing `{needle}` in\n{geo}");
        }
    }

    #[test]
    fn l_shape_mesh_is_valid() {
        if !have_gmsh() {
            return;
        }
        let dir = scratch("lshape");
        let (mesh, run) = mesh_polygon(&L_SHAPE, &l_cracks(), 0.25, &dir).expect("meshing");
        println!(
            "gmsh {}: L-shape, {} vertices, {} triangles in {:.3} s",
            run.version,
            mesh.vertices.len(),
            mesh.triangles.len(),
            run.seconds
        );
        check_mesh(&mesh, 3.0, 8.0, &l_cracks());
        assert!(run.msh_text.starts_with("$MeshFormat\n4.1 0 8"));
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn gmsh_is_deterministic() {
        if !have_gmsh() {
            return;
        }
        let (d1, d2) = (scratch("det1"), scratch("det2"));
        let (m1, r1) = mesh_polygon(&L_SHAPE, &l_cracks(), 0.25, &d1).expect("first run");
        let (m2, r2) = mesh_polygon(&L_SHAPE, &l_cracks(), 0.25, &d2).expect("second run");
        assert_eq!(r1.msh_text, r2.msh_text);
        assert_eq!(m1, m2);
        let _ = std::fs::remove_dir_all(&d1);
        let _ = std::fs::remove_dir_all(&d2);
    }

    #[test]
    fn seventeen_digit_points_are_exact() {
        if !have_gmsh() {
            return;
        }
        // gmsh prints 16 significant digits: 0.1 + 0.2 = 0.30000000000000004 comes back as
        // 0.3, and 1/3 + 0.9 = 1.2333333333333334 as 1.233333333333333, unless restored.
        let polygon = [[0.0, 0.0], [1.0, 0.0], [0.1 + 0.2, 1.0 / 3.0 + 0.9]];
        let cracks = vec![vec![[0.1 + 0.2, 0.2], [0.6, 0.1 + 0.2]]];
        let dir = scratch("digits");
        let (mesh, run) = mesh_polygon(&polygon, &cracks, 0.1, &dir).expect("meshing");
        let unrestored = read_msh(&run.msh_text, "coarse.msh").expect("reading");
        assert!(!unrestored.vertices.contains(&cracks[0][0]));
        assert!(!unrestored.vertices.contains(&cracks[0][1]));
        let double_area = 1.0 * (1.0 / 3.0 + 0.9);
        let perimeter = polyline_length(&[polygon[0], polygon[1], polygon[2], polygon[0]]);
        check_mesh(&mesh, 0.5 * double_area, perimeter, &cracks);
        for p in polygon {
            assert!(mesh.vertices.contains(&p), "polygon vertex {p:?} not exact");
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Coordinates as bits, triangles rotated to start at their least vertex.
    type Canonical = (
        BTreeSet<[u64; 2]>,
        BTreeSet<[[u64; 2]; 3]>,
        BTreeSet<[[u64; 2]; 2]>,
        Vec<Vec<[u64; 2]>>,
    );

    fn canonical(m: &CoarseMesh) -> Canonical {
        let bits = |v: usize| [m.vertices[v][0].to_bits(), m.vertices[v][1].to_bits()];
        let tri = |t: &[usize; 3]| {
            let c = [bits(t[0]), bits(t[1]), bits(t[2])];
            let k = (0..3).min_by_key(|&k| c[k]).unwrap_or(0);
            [c[k], c[(k + 1) % 3], c[(k + 2) % 3]]
        };
        (
            (0..m.vertices.len()).map(bits).collect(),
            m.triangles.iter().map(tri).collect(),
            m.boundary_edges
                .iter()
                .map(|e| [bits(e[0]), bits(e[1])])
                .collect(),
            m.cracks
                .iter()
                .map(|c| c.iter().map(|&v| bits(v)).collect())
                .collect(),
        )
    }

    #[test]
    fn msh22_conversion_reads_the_same_mesh() {
        if !have_gmsh() {
            return;
        }
        let dir = scratch("msh22");
        let (mesh, _) = mesh_polygon(&L_SHAPE, &l_cracks(), 0.25, &dir).expect("meshing");
        let status = Command::new("gmsh")
            .args([
                "coarse.msh",
                "-0",
                "-format",
                "msh22",
                "-o",
                "coarse22.msh",
                "-v",
                "2",
            ])
            .current_dir(&dir)
            .status()
            .expect("gmsh runs");
        assert!(status.success());
        let text = std::fs::read_to_string(dir.join("coarse22.msh")).expect("msh22 written");
        assert!(text.starts_with("$MeshFormat\n2.2 0 8"));
        let mesh22 = read_msh(&text, "coarse22.msh").expect("reading msh 2.2");
        assert_eq!(canonical(&mesh), canonical(&mesh22));
        check_mesh(&mesh22, 3.0, 8.0, &l_cracks());
        let _ = std::fs::remove_dir_all(&dir);
    }

    // ---- hand-written files: the unit square with an interior crack P–Q ----------------
    //
    //  D(4) ---------- C(3)
    //   |   \        / |
    //   |    P(5)--Q(6)|
    //   |   /        \ |
    //  A(1) ---------- B(2)

    const SQUARE_NODES: &str = "6\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 0.4 0.5 0\n6 0.6 0.5 0\n";
    /// Triangles ABQ, AQP (clockwise), BCQ, CDP (clockwise), CPQ, DAP.
    const SQUARE_TRIANGLES: [&str; 6] = ["1 2 6", "1 5 6", "2 3 6", "3 5 4", "3 5 6", "4 1 5"];
    const SQUARE_BOUNDARY: [&str; 4] = ["1 2", "2 3", "3 4", "4 1"];
    const SQUARE_NAMES: &str = "3\n1 2 \"boundary\"\n1 3 \"crack1\"\n2 1 \"domain\"\n";

    /// The same square in msh 4.1 with node tags 10, 20, …, 60 in two entity blocks.
    const SQUARE_41: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n\
            1 2 \"boundary\"\n1 3 \"crack1\"\n2 1 \"domain\"\n$EndPhysicalNames\n\
            $Entities\n0 2 1 0\n1 0 0 0 1 1 0 1 2 0\n2 0.4 0.5 0 0.6 0.5 0 1 3 0\n\
            1 0 0 0 1 1 0 1 1 0\n$EndEntities\n\
            $Nodes\n2 6 10 60\n1 1 0 4\n10\n20\n30\n40\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n\
            1 2 0 2\n50\n60\n0.4 0.5 0\n0.6 0.5 0\n$EndNodes\n\
            $Elements\n3 11 1 11\n1 1 1 4\n1 10 20\n2 20 30\n3 30 40\n4 40 10\n\
            1 2 1 1\n5 60 50\n2 1 2 6\n6 10 20 60\n7 10 50 60\n8 20 30 60\n9 30 50 40\n\
            10 30 50 60\n11 40 10 50\n$EndElements\n";

    /// A msh 2.2 square: `names` is the $PhysicalNames body; each element is
    /// `(type, physical, nodes)`.
    fn msh22(names: &str, elements: &[(i64, i64, &str)]) -> String {
        let mut s = format!(
            "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n{names}$EndPhysicalNames\n\
             $Nodes\n{SQUARE_NODES}$EndNodes\n$Elements\n{}\n",
            elements.len()
        );
        for (k, (etype, physical, nodes)) in elements.iter().enumerate() {
            let _ = writeln!(s, "{} {etype} 2 {physical} {physical} {nodes}", k + 1);
        }
        s.push_str("$EndElements\n");
        s
    }

    /// The square with these crack groups (physical 3 = crack1, 4 = crack2, …).
    fn square(names: &str, cracks: &[&[&str]]) -> String {
        let mut elements: Vec<(i64, i64, &str)> =
            SQUARE_BOUNDARY.iter().map(|n| (1, 2, *n)).collect();
        for (c, lines) in cracks.iter().enumerate() {
            elements.extend(lines.iter().map(|n| (1, 3 + c as i64, *n)));
        }
        elements.extend(SQUARE_TRIANGLES.iter().map(|n| (2, 1, *n)));
        msh22(names, &elements)
    }

    fn square_ok() -> String {
        square(SQUARE_NAMES, &[&["6 5"]])
    }

    fn error_of(text: &str) -> String {
        match read_msh(text, "test.msh") {
            Ok(m) => panic!("expected an error, read {m:?}"),
            Err(e) => {
                let message = e.to_string();
                assert!(message.starts_with("test.msh: "), "{message}");
                assert!(!message.contains('\n'), "{message}");
                message
            }
        }
    }

    fn assert_error(text: &str, words: &[&str]) {
        let message = error_of(text);
        for w in words {
            assert!(message.contains(w), "`{w}` not in: {message}");
        }
    }

    #[test]
    fn reads_handwritten_msh22() {
        let m = read_msh(&square_ok(), "square.msh").expect("reading");
        assert_eq!(m.vertices.len(), 6);
        assert_eq!(m.vertices[4], [0.4, 0.5]);
        assert_eq!(m.cracks, vec![vec![5, 4]]);
        assert_eq!(m.boundary_edges, vec![[0, 1], [1, 2], [2, 3], [3, 0]]);
        check_mesh(&m, 1.0, 4.0, &[vec![[0.6, 0.5], [0.4, 0.5]]]);
    }

    #[test]
    fn reads_msh41_with_sparse_node_tags() {
        let text = SQUARE_41;
        let m41 = read_msh(text, "sparse.msh").expect("reading 4.1");
        let m22 = read_msh(&square_ok(), "square.msh").expect("reading 2.2");
        assert_eq!(m41, m22);
        let six = text.replace("3 11 1 11", "4 12 1 12").replace(
            "$EndElements",
            "2 1 9 1\n12 10 20 30 40 50 60\n$EndElements",
        );
        assert_error(&six, &["6-node triangle"]);
        let z = text.replace("0.4 0.5 0\n", "0.4 0.5 0.25\n");
        assert_error(&z, &["node 50 has z = 0.25", "z = 0 plane"]);
        let parametric = text.replace("1 2 0 2\n", "1 2 1 2\n");
        assert_error(&parametric, &["parametric"]);
        let truncated = text.replace("0.6 0.5 0\n$EndNodes", "0.6 0.5\n$EndNodes");
        assert_error(
            &truncated,
            &["malformed $Nodes section at line", "too few fields"],
        );
        let bad_number = text.replace("0.6 0.5 0\n", "0.6 abc 0\n");
        assert_error(&bad_number, &["malformed $Nodes section", "`abc`"]);
        let short = text.replace("2 6 10 60\n", "2 7 10 60\n");
        assert_error(&short, &["malformed $Nodes section", "7 nodes"]);
    }

    #[test]
    fn missing_boundary_group() {
        let text = square(
            &SQUARE_NAMES.replace("\"boundary\"", "\"outer\""),
            &[&["6 5"]],
        );
        assert_error(&text, &["no physical curve group named \"boundary\""]);
    }

    #[test]
    fn missing_crack_group() {
        let text = square(&SQUARE_NAMES.replace("\"crack1\"", "\"slit\""), &[&["6 5"]]);
        assert_error(&text, &["no physical curve group named crack1"]);
        let text = square(
            &SQUARE_NAMES.replace("\"crack1\"", "\"crack2\""),
            &[&["6 5"]],
        );
        assert_error(&text, &["crack1 is missing"]);
    }

    #[test]
    fn crack_group_not_a_chain() {
        let branch = square(SQUARE_NAMES, &[&["6 5", "5 1", "5 4"]]);
        assert_error(
            &branch,
            &[
                "\"crack1\" is not one open chain",
                "a vertex has 3 crack edges",
            ],
        );
        let ring = square(SQUARE_NAMES, &[&["5 6", "6 3", "3 5"]]);
        assert_error(&ring, &["\"crack1\" is not one open chain", "closed loop"]);
        let pieces = square(SQUARE_NAMES, &[&["5 6", "1 2"]]);
        assert_error(&pieces, &["\"crack1\" is not one open chain", "2 pieces"]);
    }

    #[test]
    fn crack_chain_follows_first_element() {
        assert_eq!(
            order_chain(&[[3, 4], [2, 3], [4, 5], [1, 2]]),
            Ok(vec![1, 2, 3, 4, 5])
        );
        assert_eq!(order_chain(&[[4, 3], [2, 3], [4, 5]]), Ok(vec![5, 4, 3, 2]));
        assert_eq!(order_chain(&[[7, 8]]), Ok(vec![7, 8]));
        // D–P then Q–P: the chain runs D → P → Q and meets the boundary at D first.
        let text = square(SQUARE_NAMES, &[&["4 5", "6 5"]]);
        assert_error(&text, &["crack1 touches the boundary at vertex (0, 1)"]);
    }

    #[test]
    fn cracks_sharing_a_vertex() {
        let names = "4\n1 2 \"boundary\"\n1 3 \"crack1\"\n1 4 \"crack2\"\n2 1 \"domain\"\n";
        let two = square(names, &[&["5 6"], &["6 5"]]);
        assert_error(&two, &["crack1 and crack2 share the vertex (0.6, 0.5)"]);
    }

    #[test]
    fn crack_touching_boundary() {
        let text = square(SQUARE_NAMES, &[&["6 2"]]);
        assert_error(&text, &["crack1 touches the boundary at vertex (1, 0)"]);
    }

    #[test]
    fn crack_not_embedded() {
        let text = square(SQUARE_NAMES, &[&["5 2"]]);
        assert_error(
            &text,
            &["crack1 edge (5, 2) is not an edge of the triangulation"],
        );
    }

    #[test]
    fn boundary_incomplete() {
        let mut elements: Vec<(i64, i64, &str)> =
            vec![(1, 2, "1 2"), (1, 2, "2 3"), (1, 2, "3 4"), (1, 3, "6 5")];
        elements.extend(SQUARE_TRIANGLES.iter().map(|n| (2, 1, *n)));
        let text = msh22(SQUARE_NAMES, &elements);
        assert_error(
            &text,
            &["\"boundary\" does not cover the outer boundary (1 edges missing)"],
        );
    }

    #[test]
    fn binary_file() {
        let text = "$MeshFormat\n4.1 1 8\n\u{1}\0\0\0\n$EndMeshFormat\n$Nodes\n\u{7}\u{3}\0";
        assert_error(
            text,
            &["binary .msh files are not supported", "Mesh.Binary = 0"],
        );
    }

    #[test]
    fn quad_elements() {
        let mut elements: Vec<(i64, i64, &str)> =
            SQUARE_BOUNDARY.iter().map(|n| (1, 2, *n)).collect();
        elements.push((1, 3, "6 5"));
        elements.push((3, 1, "1 2 3 4"));
        assert_error(
            &msh22(SQUARE_NAMES, &elements),
            &["4-node quadrangle", "only 3-node triangles"],
        );
    }

    #[test]
    fn garbage_text() {
        assert_error("hello\nworld\n", &["not a gmsh .msh file"]);
        assert_error("", &["not a gmsh .msh file"]);
        assert_error("$MeshFormat\n", &["malformed $MeshFormat"]);
        assert_error(
            "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n",
            &["version 3.0 is not supported"],
        );
        let unclosed = square_ok().replace("$EndElements\n", "");
        assert_error(
            &unclosed,
            &["malformed $Elements section", "no $EndElements"],
        );
        let bad = square_ok().replace("\n7 2 2 1 1 1 5 6\n", "\n7 2 2 1 1 1 5 x\n");
        assert_error(&bad, &["malformed $Elements section at line", "`x`"]);
        let missing = square_ok().replace("\n7 2 2 1 1 1 5 6\n", "\n7 2 2 1 1 1 5 99\n");
        assert_error(&missing, &["node 99", "not in $Nodes"]);
    }

    #[test]
    fn gmsh_failure_reports_the_cause() {
        if !have_gmsh() {
            return;
        }
        let dir = scratch("fail");
        std::fs::create_dir_all(&dir).expect("scratch dir");
        let geo = "Point(1) = {0, 0, 0, 1};\nLine(1) = {1, 2};\n";
        std::fs::write(dir.join("bad.geo"), geo).expect("write");
        let output = run_gmsh(&["bad.geo", "-2", "-v", "2"], &dir).expect("gmsh runs");
        assert!(!output.status.success());
        assert_eq!(
            first_error_line(&output),
            "Unknown control point 2 in GEO curve 1"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn crack_leaving_the_domain_is_reported() {
        if !have_gmsh() {
            return;
        }
        let dir = scratch("outside");
        let cracks = vec![vec![[0.5, -0.5], [1.5, -0.5]]];
        let e = mesh_polygon(&L_SHAPE, &cracks, 0.25, &dir).expect_err("crack crosses ∂Ω");
        let message = e.to_string();
        assert!(
            message.contains("gmsh failed") || message.contains("crack1"),
            "{e}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn gmsh_binary_output_is_refused() {
        if !have_gmsh() {
            return;
        }
        let dir = scratch("binary");
        mesh_polygon(&L_SHAPE, &l_cracks(), 0.5, &dir).expect("meshing");
        let status = Command::new("gmsh")
            .args(["coarse.msh", "-0", "-bin", "-o", "binary.msh", "-v", "2"])
            .current_dir(&dir)
            .status()
            .expect("gmsh runs");
        assert!(status.success());
        let e = read_msh_file(&dir.join("binary.msh")).expect_err("binary");
        assert!(e.to_string().ends_with("binary.msh: binary .msh files are not supported; save it as ASCII (Mesh.Binary = 0)"), "{e}");
        assert!(read_msh_file(&dir.join("coarse.msh")).is_ok());
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn not_installed_message() {
        assert_eq!(
            GmshError::NotInstalled.to_string(),
            "gmsh is not installed (apt-get install gmsh); it meshes scenes with a polygon domain or mesh_size"
        );
    }

    #[test]
    fn damaged_files_give_errors_not_panics() {
        let text = square_ok();
        for (cut, _) in text.char_indices() {
            let _ = read_msh(&text[..cut], "cut.msh");
        }
        let lines: Vec<&str> = text.lines().collect();
        for k in 0..lines.len() {
            for replacement in [
                "",
                "x",
                "-1",
                "99999999999999999999",
                "1 1",
                "nan",
                "$Nodes",
            ] {
                let mut damaged = lines.clone();
                damaged[k] = replacement;
                let _ = read_msh(&damaged.join("\n"), "damaged.msh");
            }
        }
    }

    #[test]
    fn mesh_polygon_rejects_bad_input() {
        let dir = scratch("bad-input");
        let e = mesh_polygon(&L_SHAPE, &l_cracks(), 0.0, &dir).expect_err("zero size");
        assert!(e.to_string().contains("mesh_size"), "{e}");
        let e = mesh_polygon(&L_SHAPE, &[], 0.25, &dir).expect_err("no cracks");
        assert!(e.to_string().contains("no cracks"), "{e}");
        assert!(!dir.exists());
    }
}
