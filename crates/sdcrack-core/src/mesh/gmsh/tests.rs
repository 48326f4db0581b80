use super::coarse::{key, order_chain, signed_area};
use super::read::dist;
use super::run::{first_error_line, run_gmsh};
use super::*;
use std::collections::BTreeSet;
use std::collections::HashSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

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

/// A test's scratch directory `sdgmsh-{name}-{pid}` under the temporary directory, absent when
/// made (a leftover is removed) and removed again when the test passes; a failing test leaves
/// it for inspection.
struct Scratch(PathBuf);

impl Scratch {
    fn new(name: &str) -> Self {
        let dir = std::env::temp_dir().join(format!("sdgmsh-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        Scratch(dir)
    }
}

impl std::ops::Deref for Scratch {
    type Target = Path;

    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// The scratch directory of a test that runs gmsh, or `None` where gmsh is not installed (the
/// test is then skipped, saying so).
fn gmsh_scratch(name: &str) -> Option<Scratch> {
    have_gmsh().then(|| Scratch::new(name))
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
    let Some(dir) = gmsh_scratch("lshape") else {
        return;
    };
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
}

#[test]
fn gmsh_is_deterministic() {
    let (Some(d1), Some(d2)) = (gmsh_scratch("det1"), gmsh_scratch("det2")) else {
        return;
    };
    let (m1, r1) = mesh_polygon(&L_SHAPE, &l_cracks(), 0.25, &d1).expect("first run");
    let (m2, r2) = mesh_polygon(&L_SHAPE, &l_cracks(), 0.25, &d2).expect("second run");
    assert_eq!(r1.msh_text, r2.msh_text);
    assert_eq!(m1, m2);
}

#[test]
fn seventeen_digit_points_are_exact() {
    let Some(dir) = gmsh_scratch("digits") else {
        return;
    };
    // gmsh prints 16 significant digits: 0.1 + 0.2 = 0.30000000000000004 comes back as
    // 0.3, and 1/3 + 0.9 = 1.2333333333333334 as 1.233333333333333, unless restored.
    let polygon = [[0.0, 0.0], [1.0, 0.0], [0.1 + 0.2, 1.0 / 3.0 + 0.9]];
    let cracks = vec![vec![[0.1 + 0.2, 0.2], [0.6, 0.1 + 0.2]]];
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
    let Some(dir) = gmsh_scratch("msh22") else {
        return;
    };
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
    let mut elements: Vec<(i64, i64, &str)> = SQUARE_BOUNDARY.iter().map(|n| (1, 2, *n)).collect();
    for (c, lines) in cracks.iter().enumerate() {
        elements.extend(lines.iter().map(|n| (1, 3 + c as i64, *n)));
    }
    elements.extend(SQUARE_TRIANGLES.iter().map(|n| (2, 1, *n)));
    msh22(names, &elements)
}

fn square_ok() -> String {
    square(SQUARE_NAMES, &[&["6 5"]])
}

/// [`square_ok`] with the physical name `from` (quoted as in the file) renamed `to`.
fn square_renaming(from: &str, to: &str) -> String {
    square(&SQUARE_NAMES.replace(from, to), &[&["6 5"]])
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
    let text = square_renaming("\"boundary\"", "\"outer\"");
    assert_error(&text, &["no physical curve group named \"boundary\""]);
}

#[test]
fn missing_crack_group() {
    let text = square_renaming("\"crack1\"", "\"slit\"");
    assert_error(&text, &["no physical curve group named crack1"]);
    let text = square_renaming("\"crack1\"", "\"crack2\"");
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
    let mut elements: Vec<(i64, i64, &str)> = SQUARE_BOUNDARY.iter().map(|n| (1, 2, *n)).collect();
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
    let Some(dir) = gmsh_scratch("fail") else {
        return;
    };
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let geo = "Point(1) = {0, 0, 0, 1};\nLine(1) = {1, 2};\n";
    std::fs::write(dir.join("bad.geo"), geo).expect("write");
    let output = run_gmsh(&["bad.geo", "-2", "-v", "2"], &dir).expect("gmsh runs");
    assert!(!output.status.success());
    assert_eq!(
        first_error_line(&output),
        "Unknown control point 2 in GEO curve 1"
    );
}

#[test]
fn crack_leaving_the_domain_is_reported() {
    let Some(dir) = gmsh_scratch("outside") else {
        return;
    };
    let cracks = vec![vec![[0.5, -0.5], [1.5, -0.5]]];
    let e = mesh_polygon(&L_SHAPE, &cracks, 0.25, &dir).expect_err("crack crosses ∂Ω");
    let message = e.to_string();
    assert!(
        message.contains("gmsh failed") || message.contains("crack1"),
        "{e}"
    );
}

#[test]
fn gmsh_binary_output_is_refused() {
    let Some(dir) = gmsh_scratch("binary") else {
        return;
    };
    mesh_polygon(&L_SHAPE, &l_cracks(), 0.5, &dir).expect("meshing");
    let status = Command::new("gmsh")
        .args(["coarse.msh", "-0", "-bin", "-o", "binary.msh", "-v", "2"])
        .current_dir(&dir)
        .status()
        .expect("gmsh runs");
    assert!(status.success());
    let e = read_msh_file(&dir.join("binary.msh")).expect_err("binary");
    assert!(
        e.to_string().ends_with(
            "binary.msh: binary .msh files are not supported; save it as ASCII (Mesh.Binary = 0)"
        ),
        "{e}"
    );
    assert!(read_msh_file(&dir.join("coarse.msh")).is_ok());
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
    let dir = Scratch::new("bad-input");
    let e = mesh_polygon(&L_SHAPE, &l_cracks(), 0.0, &dir).expect_err("zero size");
    assert!(e.to_string().contains("mesh_size"), "{e}");
    let e = mesh_polygon(&L_SHAPE, &[], 0.25, &dir).expect_err("no cracks");
    assert!(e.to_string().contains("no cracks"), "{e}");
    assert!(!dir.exists());
}

// ---------------------------------------------------------------------------------------------
// Edge cracks: a crack chain ending on ∂Ω (a mouth)

/// The unit square with a vertex M = (0, 0.5) on its left side and P = (0.5, 0.5) inside,
/// fanned around P; `crack` lists the crack1 lines.
fn square_with_mouth(crack: &[&str]) -> String {
    let nodes = "6\n1 0 0 0\n2 1 0 0\n3 1 1 0\n4 0 1 0\n5 0 0.5 0\n6 0.5 0.5 0\n";
    let mut elements: Vec<(i64, i64, &str)> = ["1 2", "2 3", "3 4", "4 5", "5 1"]
        .iter()
        .map(|n| (1, 2, *n))
        .collect();
    elements.extend(crack.iter().map(|n| (1, 3, *n)));
    elements.extend(
        ["1 2 6", "2 3 6", "3 4 6", "4 5 6", "5 1 6"]
            .iter()
            .map(|n| (2, 1, *n)),
    );
    msh22(SQUARE_NAMES, &elements).replace(SQUARE_NODES, nodes)
}

fn read_with_mouths(text: &str, name: &str) -> Result<CoarseMesh, GmshError> {
    let dir = Scratch::new(name);
    std::fs::create_dir_all(&*dir).unwrap();
    let path = dir.join("m.msh");
    std::fs::write(&path, text).unwrap();
    read_msh_file_with(&path, crate::geometry::CrackEnds::MayBeMouths).map_err(|e| {
        GmshError::Input(
            e.to_string()
                .replace(&path.display().to_string(), "test.msh"),
        )
    })
}

#[test]
fn a_crack_chain_may_end_on_the_boundary_only_when_asked() {
    let text = square_with_mouth(&["5 6"]);
    // the scalar reader refuses it as before
    assert_error(&text, &["crack1 touches the boundary at vertex (0, 0.5)"]);
    let m = read_with_mouths(&text, "mouth-ok").expect("a mouth");
    assert_eq!(m.cracks.len(), 1);
    let chain: Vec<[f64; 2]> = m.cracks[0].iter().map(|&v| m.vertices[v]).collect();
    assert_eq!(chain, vec![[0.0, 0.5], [0.5, 0.5]]);
    // only an end may be on ∂Ω, and the chain must leave ∂Ω along an interior edge
    let along = read_with_mouths(&square_with_mouth(&["4 5", "5 6"]), "mouth-along").unwrap_err();
    assert!(
        along
            .to_string()
            .contains("crack1 touches the boundary at vertex (0, 0.5)"),
        "{along}"
    );
    let edge = read_with_mouths(&square_with_mouth(&["4 5"]), "mouth-edge").unwrap_err();
    assert!(
        edge.to_string()
            .contains("crack1 runs along the boundary (0, 1)–(0, 0.5)"),
        "{edge}"
    );
}

#[test]
fn geo_script_puts_a_mouth_on_the_boundary_curve() {
    let square = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let interior = vec![vec![[-0.5, 0.0], [0.0, 0.0]]];
    let plain = geo_script(&square, &interior, 0.5);
    assert!(plain.contains("Line(4) = {4, 1};"), "{plain}");
    let edge = vec![vec![[0.0, 0.0], [-1.0, 0.0]], vec![[1.0, 0.5], [0.5, 0.5]]];
    let geo = geo_script(&square, &edge, 0.5);
    // boundary: 1 (−1,−1), 2 (1,−1), 3 (1,0.5) the second crack's mouth, 4 (1,1), 5 (−1,1),
    // 6 (−1,0) the first crack's mouth; each crack uses its mouth's tag
    for line in [
        "Point(3) = {1.0, 0.5, 0, 0.5};",
        "Point(6) = {-1.0, 0.0, 0, 0.5};",
        "Line(6) = {6, 1};",
        "Curve Loop(1) = {1, 2, 3, 4, 5, 6};",
        "Point(7) = {0.0, 0.0, 0, 0.5};",
        "Line(7) = {7, 6};",
        "Point(8) = {0.5, 0.5, 0, 0.5};",
        "Line(8) = {3, 8};",
        "Physical Curve(\"boundary\") = {1, 2, 3, 4, 5, 6};",
    ] {
        assert!(geo.lines().any(|l| l == line), "`{line}` not in:\n{geo}");
    }
}

#[test]
fn gmsh_meshes_a_mouth_as_a_boundary_vertex() {
    let Some(dir) = gmsh_scratch("mouth") else {
        return;
    };
    // one mouth on the L's inner edge y = 0; two mouths (top side, inner edge x = 0), kinked
    let cracks = vec![
        vec![[0.5, 0.0], [0.5, -0.5]],
        vec![[-0.5, 1.0], [-0.5, 0.5], [0.0, 0.5]],
    ];
    let (m, _) = mesh_polygon(&L_SHAPE, &cracks, 0.3, &dir).expect("meshed");
    let boundary: HashSet<usize> = m.boundary_edges.iter().flatten().copied().collect();
    let mut mouths = Vec::new();
    for (chain, polyline) in m.cracks.iter().zip(&cracks) {
        check_chain(&m, chain, polyline);
        mouths.push([chain[0], chain[chain.len() - 1]].map(|v| boundary.contains(&v)));
        // only the ends touch ∂Ω
        assert!(chain[1..chain.len() - 1]
            .iter()
            .all(|v| !boundary.contains(v)));
    }
    assert_eq!(mouths, vec![[true, false], [true, true]]);
}
