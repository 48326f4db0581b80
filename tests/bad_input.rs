//! Catalogue of bad inputs, each run through the real binary.
//!
//! Every case must give: the documented exit code (2: bad usage or bad input, see `src/cli.rs`), no
//! panic, exactly one line on stderr starting `sdcrack: error: ` and holding the expected words
//! (what is wrong and where: file, key, line/column, level, coordinates), and no results folder or
//! staging leftover in `--out` (an existing results folder is left byte for byte as it was).

mod common;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A valid scene that every `edit` case changes in one place.
use common::SMALL_SCENE as SMALL;

/// A valid elastic scene (docs/elasticity.md) that every `edit_elastic` case changes in one place:
/// uniform compression across an interior crack, Dirichlet on the whole boundary.
const ELASTIC: &str = r#"name = "small"
[problem]
kind = "elasticity"
E = 1.0
nu = 0.3
[geometry]
domain = { rectangle = [[-1.0, -1.0], [1.0, 1.0]] }
crack = { segment = [[-0.5, 0.0], [0.5, 0.0]] }
[data]
fx = "0"
fy = "0"
gx = "0.1*x"
gy = "-0.1*y"
[exact]
ux = "0.1*x"
uy = "-0.1*y"
sif = [[0.0, 0.0], [0.0, 0.0]]
[discretization]
cells = [4, 4]
levels = [0, 1]
[outputs]
fields = ["u"]
references = []
"#;

/// Tractions on all four sides of [`ELASTIC`]'s square (uniaxial compression), in place of g.
const ALL_TRACTION: &str = "traction = { left = [\"0\", \"0\"], right = [\"0\", \"0\"], bottom = [\"0\", \"0.1\"], top = [\"0\", \"-0.1\"] }";

/// What is at the scene path.
enum Input {
    /// A file with these bytes.
    Scene(Vec<u8>),
    /// Nothing.
    Missing,
    /// A directory.
    Directory,
    /// A valid scene nobody may read (mode 000).
    Unreadable,
}

/// What `--out` is.
enum Out {
    /// A folder that does not exist yet.
    Fresh,
    /// A path under a regular file (cannot be created, even by root).
    UnderFile,
    /// A regular file itself.
    IsFile,
    /// A folder inside a read-only folder.
    ReadOnly,
    /// A folder already holding `small/`, earlier results of the same scene.
    Existing,
}

struct Case {
    what: &'static str,
    input: Input,
    /// Arguments after `sdcrack`; `{scene}` and `{out}` are replaced by the case's paths.
    args: Vec<&'static str>,
    /// Environment variable set for the run; `{dir}` in the value is the case's folder.
    env: Option<(&'static str, &'static str)>,
    out: Out,
    code: i32,
    /// Words the message must hold.
    needle: String,
    /// Further check of the message.
    check: Option<fn(&str)>,
}

fn case(what: &'static str, input: Input, needle: &str) -> Case {
    Case {
        what,
        input,
        args: vec!["run", "{scene}", "--out", "{out}", "--quiet"],
        env: None,
        out: Out::Fresh,
        code: 2,
        needle: needle.to_string(),
        check: None,
    }
}

/// `text` as the scene of `sdcrack run`.
fn scene(what: &'static str, text: &str, needle: &str) -> Case {
    case(what, Input::Scene(text.as_bytes().to_vec()), needle)
}

/// ELASTIC with its first `from` replaced by `to` (which must change it).
fn edit_elastic(what: &'static str, from: &str, to: &str, needle: &str) -> Case {
    assert!(
        ELASTIC.contains(from),
        "{what}: '{from}' is not in the scene"
    );
    scene(what, &ELASTIC.replacen(from, to, 1), needle)
}

/// ELASTIC with the Dirichlet data replaced by [`ALL_TRACTION`] and `fixed` (a line, or "").
fn all_traction(what: &'static str, fixed: &str, needle: &str) -> Case {
    let text = ELASTIC.replacen(
        "gx = \"0.1*x\"\ngy = \"-0.1*y\"",
        &format!("{ALL_TRACTION}\n{fixed}"),
        1,
    );
    assert_ne!(text, ELASTIC);
    scene(what, &text, needle)
}

/// SMALL with its first `from` replaced by `to` (which must change it).
fn edit(what: &'static str, from: &str, to: &str, needle: &str) -> Case {
    assert!(SMALL.contains(from), "{what}: '{from}' is not in the scene");
    scene(what, &SMALL.replacen(from, to, 1), needle)
}

/// The SMALL scene on the repository's mesh file `file` (in place of its [geometry] and cells).
fn mesh_file(what: &'static str, file: &str, needle: &str) -> Case {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
    let text = SMALL
        .replacen(
            "[geometry]\ndomain = { rectangle = [[-1.0, -1.0], [1.0, 1.0]] }\ncrack = { segment = [[-0.5, 0.0], [0.5, 0.0]] }\n",
            "",
            1,
        )
        .replacen(
            "cells = [4, 4]",
            &format!("mesh = {{ gmsh = {:?} }}", path.display().to_string()),
            1,
        );
    assert!(!text.contains("[geometry]"), "{what}: SMALL changed");
    scene(what, &text, needle)
}

/// The valid SMALL scene with extra command-line arguments.
fn cli(what: &'static str, extra: &[&'static str], needle: &str) -> Case {
    let mut c = scene(what, SMALL, needle);
    c.args.extend_from_slice(extra);
    c
}

/// Checks that the NaN reported for `f = "log(0.25 - x*x - y*y)"` is at a point of Ω where the
/// argument of log is ≤ 0, i.e. that the message names the real point.
fn nan_point_of_f(message: &str) {
    let (x, y) = point_in(message);
    assert!(x.abs() < 1.0 && y.abs() < 1.0, "point inside Ω: {message}");
    assert!(0.25 - x * x - y * y <= 0.0, "f is finite there: {message}");
}

/// Checks that the NaN reported for `g = "log(x - 0.5)"` is on Γ with x ≤ 0.5.
fn nan_point_of_g(message: &str) {
    let (x, y) = point_in(message);
    assert!(x <= 0.5, "g is finite there: {message}");
    assert!(
        (x.abs() - 1.0).abs() < 1e-12 || (y.abs() - 1.0).abs() < 1e-12,
        "g is evaluated on Γ only: {message}"
    );
}

/// The `(x, y)` after "quadrature point " in a message.
fn point_in(message: &str) -> (f64, f64) {
    let rest = message
        .split("quadrature point (")
        .nth(1)
        .unwrap_or_else(|| panic!("no point in: {message}"));
    let inner = rest.split(')').next().unwrap();
    let mut it = inner.split(',').map(|v| v.trim().parse::<f64>().unwrap());
    (it.next().unwrap(), it.next().unwrap())
}

/// `sdcrack check` of tests/data/scenes/bad-exact/`file`.toml: refused naming the key, both
/// values and a point of Ω ([`point_of_exact_data`]).
fn bad_exact(what: &'static str, file: &str, needle: &str) -> Case {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/scenes/bad-exact")
        .join(format!("{file}.toml"));
    Case {
        args: vec!["check", "{scene}"],
        check: Some(point_of_exact_data),
        ..scene(what, &std::fs::read_to_string(path).unwrap(), needle)
    }
}

/// The point an exact-data message names ("… at (x, y)") lies in Ω = [−1, 1]² (closed).
fn point_of_exact_data(message: &str) {
    let rest = message
        .split(" at (")
        .nth(1)
        .unwrap_or_else(|| panic!("no point in: {message}"));
    let inner = rest.split(')').next().unwrap();
    let v: Vec<f64> = inner
        .split(',')
        .map(|t| t.trim().parse::<f64>().unwrap())
        .collect();
    assert!(
        v.len() == 2 && v.iter().all(|c| c.abs() <= 1.0),
        "point in Ω: {message}"
    );
}

fn catalogue() -> Vec<Case> {
    let huge = format!("{SMALL}# {}\n", "x".repeat(1 << 20));
    let mut non_utf8 = SMALL.as_bytes().to_vec();
    non_utf8.splice(8..8, [0xff, 0xfe]);
    vec![
        // --- malformed TOML ---
        edit(
            "unclosed string",
            r#"name = "small""#,
            r#"name = "small"#,
            "invalid scene {scene}: name: invalid basic string (at line 1, column 14)",
        ),
        edit(
            "key without value",
            r#"name = "small""#,
            "name = ",
            r#"name: invalid string: expected `"`"#,
        ),
        edit(
            "unclosed table header",
            "[geometry]",
            "[geometry",
            "invalid table header: expected `.`, `]` (at line 2, column 10)",
        ),
        edit(
            "duplicate key",
            "g = \"0\"",
            "g = \"0\"\ng = \"1\"",
            "duplicate key `g` in table `data` (at line 8, column 1)",
        ),
        scene(
            "duplicate table",
            &format!("{SMALL}[data]\nf = \"1\"\ng = \"0\"\n"),
            "invalid table header: duplicate key `data` in document root (at line 17, column 1)",
        ),
        scene(
            "line that is not TOML",
            &format!("this is not toml\n{SMALL}"),
            "expected `.`, `=` (at line 1, column 6)",
        ),
        edit(
            "malformed number",
            "cells = [4, 4]",
            "cells = [4, 4x]",
            "discretization.cells: invalid array: expected `]` (at line 9, column 14)",
        ),
        edit(
            "unclosed array",
            "levels = [0, 1]",
            "levels = [0, 1",
            "invalid array: expected `]` in [discretization] (at line 11, column 1)",
        ),
        case(
            "not UTF-8",
            Input::Scene(non_utf8),
            "cannot read scene file {scene}: it is not UTF-8 text (invalid byte at line 1, column 9)",
        ),
        scene(
            "empty file",
            "",
            "invalid scene {scene}: the scene is empty; it needs at least name, [geometry], [data] and [discretization]",
        ),
        scene(
            "only whitespace and comments are not empty TOML but miss everything",
            "# nothing\n\n",
            "missing key `name` at the top level",
        ),
        scene(
            "huge file",
            &huge,
            &format!(
                "cannot read scene file {{scene}}: it has {} bytes, more than the 1 MiB (1048576 bytes) a scene may have",
                huge.len()
            ),
        ),
        // --- unknown keys, with "did you mean" ---
        edit(
            "unknown top-level key",
            "name =",
            "nmae =",
            "unknown key `nmae` at the top level at line 1, column 1; did you mean `name`?",
        ),
        edit(
            "misspelt table",
            "[discretization]",
            "[discretisation]",
            "unknown key `discretisation` at the top level at line 8, column 2; did you mean `discretization`?",
        ),
        edit(
            "unknown key in [discretization]",
            "cells =",
            "cels =",
            "unknown key `cels` in [discretization] at line 9, column 1; did you mean `cells`? (allowed: cells, mesh_size, mesh, grading, levels, u_spaces, multipliers, p_mass, p_spaces, deltas)",
        ),
        edit(
            "unknown key in [geometry]",
            "crack =",
            "crak =",
            "unknown key `crak` in [geometry] at line 4, column 1; did you mean `crack`?",
        ),
        edit(
            "unknown key in an inline table",
            "rectangle =",
            "rectangel =",
            "unknown key `rectangel` in [geometry.domain] at line 3, column 12; did you mean `rectangle`?",
        ),
        edit(
            "unknown key in [outputs]",
            "fields =",
            "field =",
            "unknown key `field` in [outputs] at line 15, column 1; did you mean `fields`?",
        ),
        edit(
            "key of another table",
            "g = \"0\"",
            "g = \"0\"\ncrack = 1",
            "unknown key `crack` in [data] at line 8, column 1; `crack` belongs in [geometry] (allowed: f, g, fx, fy, gx, gy, traction, fixed)",
        ),
        scene(
            "unknown key without a near one",
            &format!("{SMALL}colour = \"red\"\n"),
            "unknown key `colour` in [outputs] at line 17, column 1 (allowed: fields, references)",
        ),
        // --- wrong types and shapes ---
        edit(
            "string for an array",
            "cells = [4, 4]",
            "cells = \"4\"",
            "discretization.cells must be two integers [nx, ny], not the string \"4\" (at line 9, column 9)",
        ),
        edit(
            "integer for an array",
            "levels = [0, 1]",
            "levels = 0",
            "discretization.levels must be a list of integers, not the integer 0 (at line 10, column 10)",
        ),
        edit(
            "integer for a string",
            r#"name = "small""#,
            "name = 3",
            "name must be a string, not the integer 3 (at line 1, column 8)",
        ),
        edit(
            "number for an expression",
            "g = \"0\"",
            "g = 0",
            "data.g must be an expression in quotes, e.g. \"0\", not the integer 0 (at line 7, column 5)",
        ),
        edit(
            "string in the deltas",
            "deltas = [1e-2, 0.0]",
            "deltas = [\"a\"]",
            "discretization.deltas must be a list of numbers ≥ 0, not the string \"a\" (at line 13, column 11)",
        ),
        edit(
            "fractional cells",
            "cells = [4, 4]",
            "cells = [4.5, 4]",
            "discretization.cells must be two integers [nx, ny], not the number 4.5 (at line 9, column 10)",
        ),
        edit(
            "string in the levels",
            "levels = [0, 1]",
            "levels = [0, \"1\"]",
            "discretization.levels must be a list of integers, not the string \"1\" (at line 10, column 14)",
        ),
        edit(
            "string for the u spaces",
            "u_spaces = [\"continuous\", \"broken\"]",
            "u_spaces = \"broken\"",
            "discretization.u_spaces must be a list of names from \"continuous\", \"broken\", not the string \"broken\" (at line 11, column 12)",
        ),
        edit(
            "string in the crack",
            "segment = [[-0.5, 0.0], [0.5, 0.0]]",
            "segment = [[-0.5, \"0\"], [0.5, 0.0]]",
            "geometry.crack.segment must be two end points [[xa, ya], [xb, yb]] of numbers, not the string \"0\"",
        ),
        edit(
            "three cells",
            "cells = [4, 4]",
            "cells = [4, 4, 4]",
            "discretization.cells must be two integers [nx, ny]; got 3 number(s)",
        ),
        edit(
            "point with three coordinates",
            "[[-1.0, -1.0], [1.0, 1.0]]",
            "[[-1.0, -1.0, 0.0], [1.0, 1.0]]",
            "geometry.domain.rectangle must be two points [[x, y], [x, y]]; got 2 point(s) with [3, 2] coordinates",
        ),
        edit(
            "crack of one point",
            "[[-0.5, 0.0], [0.5, 0.0]]",
            "[[-0.5, 0.0]]",
            "geometry.crack.segment must be two points [[x, y], [x, y]]; got 1 point(s)",
        ),
        // --- missing tables and keys ---
        edit(
            "missing [data]",
            "[data]\nf = \"20*sin(2*pi*x)*sign(y)\"\ng = \"0\"\n",
            "",
            "missing table [data]",
        ),
        edit("missing key g", "g = \"0\"\n", "", "missing key `g` in [data]"),
        edit(
            "missing name",
            "name = \"small\"\n",
            "",
            "missing key `name` at the top level",
        ),
        edit(
            "missing crack",
            "crack = { segment = [[-0.5, 0.0], [0.5, 0.0]] }\n",
            "",
            "missing key `crack` in [geometry]",
        ),
        edit(
            "missing levels",
            "levels = [0, 1]\n",
            "",
            "missing key `levels` in [discretization]",
        ),
        // --- names ---
        edit(
            "name with a path",
            r#"name = "small""#,
            r#"name = "../evil""#,
            r#"name "../evil" must be 1-100 characters of letters, digits, '-' or '_'"#,
        ),
        edit(
            "name with a newline",
            r#"name = "small""#,
            r#"name = "a\nb""#,
            r#"name "a\nb" must be"#,
        ),
        // --- geometry ---
        edit(
            "crack off the mesh lines",
            "[-0.5, 0.0], [0.5, 0.0]",
            "[-0.4, 0.0], [0.5, 0.0]",
            "invalid scene {scene}: geometry.crack.segment: crack point (-0.4, 0) is not a vertex of the level-0 mesh (cells 4×4)",
        ),
        edit(
            "crack across the cell diagonals",
            "[-0.5, 0.0], [0.5, 0.0]",
            "[-0.5, 0.5], [0.5, -0.5]",
            "geometry.crack.segment: crack segment from (-0.5, 0.5) to (0.5, -0.5) is not along a mesh line",
        ),
        edit(
            "crack outside Ω",
            "[-0.5, 0.0], [0.5, 0.0]",
            "[-0.5, 0.0], [1.5, 0.0]",
            "geometry.crack.segment point 1 (1.5, 0) lies outside the domain",
        ),
        edit(
            "crack touching Γ",
            "[-0.5, 0.0], [0.5, 0.0]",
            "[-1.0, 0.0], [0.5, 0.0]",
            "geometry.crack.segment point 0 (-1, 0) touches the domain boundary",
        ),
        // --- polygons, polylines, several cracks, gmsh meshes ---
        edit(
            "self-intersecting polygon",
            "domain = { rectangle = [[-1.0, -1.0], [1.0, 1.0]] }",
            "domain = { polygon = [[-1, -1], [1, 1], [1, -1], [-1, 1]] }",
            "geometry.domain.polygon is not a simple polygon: edge 0 (from (-1, -1) to (1, 1)) crosses edge 2 (from (1, -1) to (-1, 1))",
        ),
        edit(
            "crack crossing the boundary of an L",
            "domain = { rectangle = [[-1.0, -1.0], [1.0, 1.0]] }\ncrack = { segment = [[-0.5, 0.0], [0.5, 0.0]] }",
            "domain = { polygon = [[-1, -1], [1, -1], [1, 0], [0, 0], [0, 1], [-1, 1]] }\ncrack = { segment = [[0.5, -0.5], [-0.5, 0.5]] }",
            "geometry.crack.segment segment 0 crosses the domain boundary",
        ),
        edit(
            "two crossing cracks",
            "crack = { segment = [[-0.5, 0.0], [0.5, 0.0]] }",
            "cracks = [{ segment = [[-0.5, 0.0], [0.5, 0.0]] }, { segment = [[0.0, -0.5], [0.0, 0.5]] }]",
            "geometry.cracks[0] and geometry.cracks[1] intersect (segment 0 and segment 0)",
        ),
        edit(
            "zero-length segment of a polyline",
            "crack = { segment = [[-0.5, 0.0], [0.5, 0.0]] }",
            "cracks = [{ polyline = [[-0.5, 0.0], [0.0, 0.0], [0.0, 0.0], [0.5, 0.0]] }]",
            "geometry.cracks[0] segment 1 has zero length (points 1 and 2 coincide)",
        ),
        edit(
            "polyline segment off the grid lines",
            "crack = { segment = [[-0.5, 0.0], [0.5, 0.0]] }",
            "cracks = [{ segment = [[-0.5, -0.5], [0.5, -0.5]] }, { polyline = [[-0.5, 0.5], [0.0, 0.5], [0.5, 0.0]] }]",
            "geometry.cracks[1]: crack segment from (0, 0.5) to (0.5, 0) is not along a mesh line",
        ),
        edit(
            "polygon with cells",
            "domain = { rectangle = [[-1.0, -1.0], [1.0, 1.0]] }",
            "domain = { polygon = [[-1, -1], [1, -1], [1, 1], [-1, 1]] }",
            "discretization.cells needs a rectangle domain; give discretization.mesh_size for a polygon",
        ),
        edit(
            "cells and mesh_size",
            "cells = [4, 4]",
            "cells = [4, 4]\nmesh_size = 0.5",
            "discretization must have exactly one of cells",
        ),
        edit(
            "gmsh level over the memory limit",
            "cells = [4, 4]\nlevels = [0, 1]",
            "mesh_size = 0.01\nlevels = [0, 6]",
            "discretization.levels: level 6 has about 5.68e8 triangles, which needs an estimated",
        ),
        edit(
            "negative mesh_size",
            "cells = [4, 4]",
            "mesh_size = -0.5",
            "discretization.mesh_size must be a positive number; got -0.5",
        ),
        edit(
            "grading beta 0",
            "cells = [4, 4]",
            "cells = [4, 4]\ngrading = { beta = 0.0, radius = 0.25 }",
            "discretization.grading.beta must be in (0, 1]",
        ),
        edit(
            "grading beta above 1",
            "cells = [4, 4]",
            "cells = [4, 4]\ngrading = { beta = 1.5, radius = 0.25 }",
            "discretization.grading.beta must be in (0, 1]",
        ),
        edit(
            "grading radius 0",
            "cells = [4, 4]",
            "cells = [4, 4]\ngrading = { beta = 0.5, radius = 0 }",
            "discretization.grading.radius must be a positive length; got 0",
        ),
        edit(
            "grading without radius",
            "cells = [4, 4]",
            "cells = [4, 4]\ngrading = { beta = 0.5 }",
            "missing key `radius` in [discretization.grading]",
        ),
        edit(
            "mesh file and [geometry]",
            "cells = [4, 4]",
            concat!("mesh = { gmsh = \"", env!("CARGO_MANIFEST_DIR"), "/scenes/meshes/trapezoid-two-cracks.msh\" }"),
            "[geometry] must be left out with discretization.mesh",
        ),
        mesh_file("missing mesh file", "tests/data/msh/no-such-file.msh", "no-such-file.msh"),
        mesh_file(
            "mesh file without a boundary group",
            "tests/data/msh/no-boundary-group.msh",
            "no physical curve group named \"boundary\"",
        ),
        mesh_file(
            "mesh file without crack groups",
            "tests/data/msh/no-crack-groups.msh",
            "no physical curve group named crack1",
        ),
        mesh_file(
            "binary mesh file",
            "tests/data/msh/binary-header.msh",
            "binary .msh files are not supported",
        ),
        edit(
            "crack of zero length",
            "[-0.5, 0.0], [0.5, 0.0]",
            "[0.5, 0.0], [0.5, 0.0]",
            "geometry.crack.segment has zero length",
        ),
        edit(
            "NaN crack end",
            "[-0.5, 0.0], [0.5, 0.0]",
            "[nan, 0.0], [0.5, 0.0]",
            "geometry.crack.segment has a non-finite coordinate (NaN, 0)",
        ),
        edit(
            "rectangle upside down",
            "[[-1.0, -1.0], [1.0, 1.0]]",
            "[[1.0, 1.0], [-1.0, -1.0]]",
            "geometry.domain.rectangle [[1, 1], [-1, -1]] must list the lower-left corner first",
        ),
        // --- cells and levels ---
        edit(
            "zero cells",
            "cells = [4, 4]",
            "cells = [0, 4]",
            "discretization.cells = [0, 4]: each entry must be between 1 and 4096",
        ),
        edit(
            "negative cells",
            "cells = [4, 4]",
            "cells = [4, -1]",
            "discretization.cells = [4, -1]: each entry must be between 1 and 4096",
        ),
        edit(
            "too many cells for memory",
            "cells = [4, 4]",
            "cells = [4096, 4096]",
            "discretization.levels: level 0 of cells [4096, 4096] is a 4096×4096 grid, which needs an estimated 225.1 GiB, more than the 16 GiB limit",
        ),
        edit(
            "level too fine for memory",
            "levels = [0, 1]",
            "levels = [0, 9]",
            "discretization.levels: level 9 of cells [4, 4] is a 2048×2048 grid, which needs an estimated 51.7 GiB",
        ),
        edit(
            "level above the maximum",
            "levels = [0, 1]",
            "levels = [13]",
            "discretization.levels: level 13 is outside 0..=12",
        ),
        edit(
            "negative level",
            "levels = [0, 1]",
            "levels = [-1]",
            "discretization.levels: level -1 is outside 0..=12",
        ),
        edit(
            "empty levels",
            "levels = [0, 1]",
            "levels = []",
            "discretization.levels is empty",
        ),
        edit(
            "duplicated level",
            "levels = [0, 1]",
            "levels = [1, 0, 1]",
            "discretization.levels: level 1 is listed twice",
        ),
        // --- u spaces, multipliers, outputs ---
        edit(
            "unknown multiplier",
            r#""M1star"]"#,
            r#""M2"]"#,
            r#"discretization.multipliers: unknown value "M2" (expected one of M0, M1, M1star); did you mean "M0"?"#,
        ),
        edit(
            "unknown u space",
            r#""broken""#,
            r#""brokn""#,
            r#"discretization.u_spaces: unknown value "brokn" (expected one of continuous, broken); did you mean "broken"?"#,
        ),
        edit(
            "unknown p space",
            "deltas = [1e-2, 0.0]",
            "deltas = [1e-2, 0.0]\np_spaces = [\"broken-tangentail\"]",
            r#"discretization.p_spaces: unknown value "broken-tangentail" (expected one of continuous, broken-tangential); did you mean "broken-tangential"? (at line 14, column 1)"#,
        ),
        edit(
            "broken-tangential p with continuous u only",
            r#"u_spaces = ["continuous", "broken"]"#,
            "u_spaces = [\"continuous\"]\np_spaces = [\"broken-tangential\"]",
            "discretization.p_spaces = [\"broken-tangential\"] needs broken u: a continuous u cannot open the crack",
        ),
        edit(
            "empty multipliers",
            r#"multipliers = ["M0", "M1", "M1star"]"#,
            "multipliers = []",
            "discretization.multipliers is empty",
        ),
        edit(
            "duplicated u space",
            r#""broken""#,
            r#""continuous""#,
            r#"discretization.u_spaces: "continuous" is listed twice"#,
        ),
        edit(
            "unknown field",
            r#""lambda""#,
            r#""lamda""#,
            r#"outputs.fields: unknown field "lamda" (expected u, p, lambda); did you mean "lambda"?"#,
        ),
        edit(
            "unknown reference",
            "references = []",
            r#"references = ["dolfin"]"#,
            r#"outputs.references: unknown reference "dolfin" (expected dolfinx, freefem); did you mean "dolfinx"?"#,
        ),
        // --- δ in the file ---
        edit(
            "negative δ",
            "deltas = [1e-2, 0.0]",
            "deltas = [-1.0]",
            "discretization.deltas: -1 is not a finite number ≥ 0",
        ),
        edit(
            "NaN δ",
            "deltas = [1e-2, 0.0]",
            "deltas = [nan]",
            "discretization.deltas: NaN is not a finite number ≥ 0",
        ),
        edit(
            "infinite δ",
            "deltas = [1e-2, 0.0]",
            "deltas = [1.0, inf]",
            "discretization.deltas: inf is not a finite number ≥ 0",
        ),
        edit(
            "empty deltas",
            "deltas = [1e-2, 0.0]",
            "deltas = []",
            "discretization.deltas is empty",
        ),
        edit(
            "duplicated δ",
            "deltas = [1e-2, 0.0]",
            "deltas = [0.0, 1e-2, 0.0]",
            "discretization.deltas: 0 is listed twice",
        ),
        // --- expressions ---
        edit(
            "unclosed parenthesis",
            "20*sin(2*pi*x)*sign(y)",
            "20*sin(2*pi*x*sign(y)",
            r#"invalid expression in data.f = "20*sin(2*pi*x*sign(y)": unclosed parenthesis at column 7"#,
        ),
        edit(
            "missing operand",
            "20*sin(2*pi*x)*sign(y)",
            "20*/x",
            "data.f = \"20*/x\": missing operand after '*' at column 3",
        ),
        edit(
            "unknown function",
            "20*sin(2*pi*x)",
            "20*sinn(2*pi*x)",
            "unknown function 'sinn' (did you mean 'sin'?) at column 4",
        ),
        edit(
            "unknown variable",
            "g = \"0\"",
            "g = \"z + 1\"",
            "data.g = \"z + 1\": unknown variable 'z' (expected x, y or pi) at column 1",
        ),
        edit(
            "empty expression",
            "g = \"0\"",
            "g = \"\"",
            "data.g = \"\": empty expression at column 1",
        ),
        edit(
            "control character in an expression",
            "g = \"0\"",
            "g = \"1 \\u0007\"",
            r#"data.g = "1 \u{7}": unexpected character '\u{7}' at column 3"#,
        ),
        edit(
            "bad exact solution",
            "[discretization]",
            "[exact]\nu = \"x*(y\"\n[discretization]",
            "invalid expression in exact.u = \"x*(y\": unclosed parenthesis at column 3",
        ),
        // --- data that is not finite at a quadrature point ---
        Case {
            check: Some(nan_point_of_f),
            ..edit(
                "f NaN inside Ω",
                "20*sin(2*pi*x)*sign(y)",
                "log(0.25 - x*x - y*y)",
                "invalid scene {scene}: data.f = \"log(0.25 - x*x - y*y)\" evaluates to NaN at the quadrature point (",
            )
        },
        Case {
            check: Some(nan_point_of_g),
            ..edit(
                "g NaN on Γ",
                "g = \"0\"",
                "g = \"log(x - 0.5)\"",
                "data.g = \"log(x - 0.5)\" evaluates to NaN at the quadrature point (",
            )
        },
        edit(
            "f infinite",
            "20*sin(2*pi*x)*sign(y)",
            "1/(x-x)",
            "data.f = \"1/(x-x)\" evaluates to inf at the quadrature point (",
        ),
        // --- files ---
        case(
            "missing scene file",
            Input::Missing,
            "cannot read scene file {scene}: there is no such file or folder",
        ),
        case(
            "directory as the scene",
            Input::Directory,
            "cannot read scene file {scene}: it is a directory, not a TOML file",
        ),
        case(
            "unreadable scene file",
            Input::Unreadable,
            "cannot read scene file {scene}: permission denied",
        ),
        Case {
            args: vec!["run", "/dev/zero", "--out", "{out}", "--quiet"],
            ..scene(
                "endless scene file",
                SMALL,
                "cannot read scene file /dev/zero: it has more than the 1 MiB (1048576 bytes) a scene may have",
            )
        },
        Case {
            out: Out::UnderFile,
            ..scene(
                "--out under a regular file",
                SMALL,
                "cannot write results under {out}: a part of the path is a file, not a folder",
            )
        },
        Case {
            out: Out::IsFile,
            ..scene(
                "--out is a regular file",
                SMALL,
                "--out {out} is a file, not a folder; give a folder for the results",
            )
        },
        Case {
            out: Out::ReadOnly,
            ..scene(
                "--out in a read-only folder",
                SMALL,
                "cannot write results under {out}: permission denied",
            )
        },
        Case {
            out: Out::Existing,
            ..scene(
                "existing results folder",
                SMALL,
                "results folder {out}/small already exists; remove it or choose another --out",
            )
        },
        Case {
            out: Out::Existing,
            args: vec!["mesh", "{scene}", "--out", "{out}/small"],
            ..scene(
                "mesh into an existing folder",
                SMALL,
                "mesh export folder {out}/small already exists; remove it or choose another --out",
            )
        },
        Case {
            env: Some(("SDCRACK_REFERENCES", "{dir}/no-such-folder")),
            ..edit(
                "reference tool not installed",
                "references = []",
                r#"references = ["dolfinx"]"#,
                "reference scripts not found at {dir}/no-such-folder; set SDCRACK_REFERENCES",
            )
        },
        // --- command line ---
        cli(
            "unknown flag",
            &["--levle", "1"],
            "unexpected argument '--levle' found; tip: a similar argument exists: '--level'",
        ),
        cli(
            "--level not a number",
            &["--level", "abc"],
            "invalid value 'abc' for '--level <LEVEL>': the level must be an integer from 0 to 12, got 'abc'",
        ),
        cli(
            "--level negative",
            &["--level", "-1"],
            "invalid value '-1' for '--level <LEVEL>'",
        ),
        cli(
            "--level above the maximum",
            &["--level", "13"],
            "the level must be an integer from 0 to 12, got '13'",
        ),
        cli(
            "--level too fine for memory",
            &["--level", "9"],
            "--level 9: level 9 of cells [4, 4] is a 2048×2048 grid, which needs an estimated 51.7 GiB, more than the 16 GiB limit",
        ),
        cli(
            "--u-space unknown",
            &["--u-space", "foo"],
            "unknown u space 'foo' (expected continuous or broken)",
        ),
        cli(
            "--p-space unknown",
            &["--p-space", "tangential"],
            "unknown p space 'tangential' (expected continuous or broken-tangential)",
        ),
        cli(
            "--u-space continuous with --p-space broken-tangential",
            &["--u-space", "continuous", "--p-space", "broken-tangential"],
            "the broken-tangential p needs broken u, and this run's u spaces are continuous: a continuous u cannot open the crack (pass --u-space broken, or --p-space continuous)",
        ),
        cli(
            "--multiplier unknown",
            &["--multiplier", "M3"],
            "unknown multiplier space 'M3' (expected M0, M1 or M1star)",
        ),
        cli(
            "--delta negative",
            &["--delta", "-1"],
            "invalid value '-1' for '--delta <DELTA>': δ must be a finite number ≥ 0, got '-1'",
        ),
        cli(
            "--delta NaN",
            &["--delta", "nan"],
            "δ must be a finite number ≥ 0, got 'nan'",
        ),
        cli(
            "--delta infinite",
            &["--delta", "inf"],
            "δ must be a finite number ≥ 0, got 'inf'",
        ),
        cli(
            "--delta not a number",
            &["--delta", "1e-3x"],
            "δ must be a finite number ≥ 0, got '1e-3x'",
        ),
        cli(
            "extra argument",
            &["extra"],
            "unexpected argument 'extra' found",
        ),
        Case {
            args: vec!["run", "{scene}", "--quiet", "--out"],
            ..scene(
                "--out without a value",
                SMALL,
                "a value is required for '--out <OUT>' but none was supplied",
            )
        },
        Case {
            args: vec!["frobnicate"],
            ..scene(
                "unknown sub-command",
                SMALL,
                "unrecognized subcommand 'frobnicate'",
            )
        },
        Case {
            args: vec!["check"],
            ..scene(
                "check without a scene",
                SMALL,
                "the following required arguments were not provided: <SCENE>",
            )
        },
        // --- the elastic problem kind (docs/elasticity.md): format and consistency ---
        edit_elastic(
            "unknown problem kind",
            "kind = \"elasticity\"",
            "kind = \"elastic\"",
            "problem.kind: unknown value \"elastic\" (expected one of scalar, elasticity) (at line 3, column 1)",
        ),
        edit_elastic(
            "Poisson's ratio 1/2 in plane strain",
            "nu = 0.3",
            "nu = 0.5",
            "problem.nu = 0.5 must be in (-1, 1/2): Poisson's ratio of a compressible body",
        ),
        edit_elastic(
            "Poisson's ratio 1/2 in plane stress",
            "nu = 0.3",
            "nu = 0.5\nplane = \"stress\"",
            "problem.nu = 0.5 must be in (-1, 1/2)",
        ),
        edit_elastic(
            "Young's modulus zero",
            "E = 1.0",
            "E = 0.0",
            "problem.E = 0 must be a finite number > 0 (Young's modulus) (at line 4, column 1)",
        ),
        edit_elastic(
            "shear modulus negative",
            "E = 1.0\nnu = 0.3",
            "lambda = 1.0\nmu = -1.0",
            "problem.mu = -1 must be a finite number > 0 (the shear modulus)",
        ),
        edit_elastic(
            "Lamé constants of a negative bulk modulus",
            "E = 1.0\nnu = 0.3",
            "lambda = -1.0\nmu = 1.0",
            "problem.lambda = -1 must be finite with 3 lambda + 2 mu > 0",
        ),
        edit_elastic(
            "both material pairs",
            "nu = 0.3",
            "nu = 0.3\nlambda = 1.0\nmu = 1.0",
            "problem.lambda is given and E, nu: give one pair, E and nu or lambda and mu",
        ),
        edit_elastic(
            "material pair incomplete",
            "nu = 0.3\n",
            "",
            "missing key `nu` in [problem]: E is given, and the material needs the pair E and nu (the table is at line 2",
        ),
        edit_elastic(
            "no material",
            "E = 1.0\nnu = 0.3\n",
            "",
            "missing key `E` in [problem]: an elastic body needs its material",
        ),
        edit_elastic(
            "friction",
            "nu = 0.3",
            "nu = 0.3\nfriction = 0.2",
            "problem.friction = 0.2: only frictionless contact is solved",
        ),
        edit_elastic(
            "unknown boundary part",
            "gy = \"-0.1*y\"",
            "gy = \"-0.1*y\"\ntraction = { middle = [\"0\", \"0\"] }",
            "data.traction.middle: unknown boundary part \"middle\" (this domain's parts: left, right, bottom, top) (at line 14, column 14)",
        ),
        edit_elastic(
            "boundary part listed twice",
            "gy = \"-0.1*y\"",
            "gy = \"-0.1*y\"\ntraction = { top = [\"0\", \"0\"], top = [\"0\", \"1\"] }",
            "duplicate key",
        ),
        edit_elastic(
            "traction not two expressions",
            "gy = \"-0.1*y\"",
            "gy = \"-0.1*y\"\ntraction = { top = [\"0\"] }",
            "data.traction.top must be two expressions [\"tx\", \"ty\"]; got 1",
        ),
        edit_elastic(
            "g missing with a Dirichlet part",
            "gx = \"0.1*x\"\n",
            "",
            "missing key `gx` in [data]: the boundary part(s) left, right, bottom, top have no traction, so u = (gx, gy) there",
        ),
        all_traction(
            "g given with no Dirichlet part",
            "gx = \"0\"\nfixed = [{ point = [-1.0, -1.0], components = [\"x\", \"y\"] }, { point = [-1.0, 1.0], components = [\"x\"] }]",
            "data.gx: every boundary part has a traction, so no part takes u = g",
        ),
        all_traction(
            "pure traction without rigid-mode constraints",
            "",
            "missing key `fixed` in [data]: every boundary part has a traction, so the body may translate and rotate freely",
        ),
        all_traction(
            "fixed points that leave the rotation free",
            "fixed = [{ point = [-1.0, -1.0], components = [\"x\", \"y\"] }, { point = [-1.0, 1.0], components = [\"y\"] }]",
            "data.fixed removes 2 of the 3 rigid modes",
        ),
        all_traction(
            "fixed point not a corner",
            "fixed = [{ point = [0.0, -1.0], components = [\"x\", \"y\"] }, { point = [-1.0, 1.0], components = [\"x\"] }]",
            "data.fixed[0].point = [0, -1] is not a corner of the domain",
        ),
        all_traction(
            "fixed component unknown",
            "fixed = [{ point = [-1.0, -1.0], components = [\"z\"] }]",
            "data.fixed[0].components: unknown component \"z\" (expected x, y)",
        ),
        edit_elastic(
            "fixed with a Dirichlet part",
            "gy = \"-0.1*y\"",
            "gy = \"-0.1*y\"\nfixed = [{ point = [-1.0, -1.0], components = [\"x\", \"y\"] }]",
            "data.fixed: fixed points are for a body whose whole boundary has tractions; the part(s) left, right, bottom, top take u = g",
        ),
        edit_elastic(
            "scalar f in an elastic scene",
            "fx = \"0\"",
            "f = \"0\"\nfx = \"0\"",
            "data.f is a key of the scalar problem, and this scene is elastic",
        ),
        edit_elastic(
            "scalar exact u in an elastic scene",
            "ux = \"0.1*x\"",
            "u = \"x\"\nux = \"0.1*x\"",
            "exact.u is a key of the scalar problem, and this scene is elastic",
        ),
        edit_elastic(
            "scalar case axis in an elastic scene",
            "levels = [0, 1]",
            "levels = [0, 1]\nu_spaces = [\"broken\"]",
            "discretization.u_spaces is a key of the scalar problem, and this scene is elastic",
        ),
        edit_elastic(
            "elastic deltas without multipliers",
            "levels = [0, 1]",
            "levels = [0, 1]\ndeltas = [0.0]",
            "missing key `multipliers` in [discretization]",
        ),
        edit_elastic(
            "a multiplier space the elastic solver does not have",
            "levels = [0, 1]",
            "levels = [0, 1]\nmultipliers = [\"M1star\", \"M1\"]\ndeltas = [0.0]",
            "discretization.multipliers: the elastic solver has no multiplier space M1 yet (it has M1star; docs/elasticity.md, \"The run\") (at line",
        ),
        edit_elastic(
            "scalar field in an elastic scene",
            "fields = [\"u\"]",
            "fields = [\"u\", \"lambda\"]",
            "outputs.fields: \"lambda\" is a field of the scalar problem; an elastic scene writes \"u\"",
        ),
        edit(
            "elastic data in a scalar scene",
            "g = \"0\"",
            "g = \"0\"\nfx = \"0\"",
            "data.fx is a key of the elastic problem, and this scene is scalar (set [problem] kind = \"elasticity\"",
        ),
        scene(
            "elastic material in a scalar scene",
            &SMALL.replacen("[geometry]", "[problem]\nkind = \"scalar\"\nE = 1.0\n[geometry]", 1),
            "problem.E is a key of the elastic problem, and this scene is scalar",
        ),
        edit_elastic(
            "stress incomplete",
            "uy = \"-0.1*y\"",
            "uy = \"-0.1*y\"\nsxx = \"0\"",
            "missing key `syy` in [exact]: give the stress's three components sxx, syy, sxy, or none",
        ),
        edit_elastic(
            "sif of the wrong number of tips",
            "sif = [[0.0, 0.0], [0.0, 0.0]]",
            "sif = [[0.0, 0.0]]",
            "exact.sif has 1 pair(s) [K_I, K_II]; the cracks have 2 tip(s)",
        ),
        edit_elastic(
            "sif not a pair",
            "sif = [[0.0, 0.0], [0.0, 0.0]]",
            "sif = [[0.0, 0.0], [0.0]]",
            "exact.sif[1] must be two finite numbers [K_I, K_II]; got [0.0]",
        ),
        Case {
            args: vec!["run", "{scene}", "--out", "{out}", "--u-space", "broken"],
            ..scene(
                "scalar case option on an elastic scene",
                ELASTIC,
                "--u-space selects a case of the scalar problem's solver, and scene 'small' is elastic",
            )
        },
        Case {
            args: vec!["run", "{scene}", "--out", "{out}", "--p-mass", "lumped"],
            ..scene(
                "p mass option on an elastic scene with cases",
                &ELASTIC.replacen(
                    "levels = [0, 1]",
                    "levels = [0, 1]\nmultipliers = [\"M1star\"]\ndeltas = [0.0]",
                    1,
                ),
                "--p-mass selects a case of the scalar problem's solver, and scene 'small' is elastic",
            )
        },
        Case {
            args: vec!["run", "{scene}", "--out", "{out}", "--multiplier", "M0"],
            ..scene(
                "a multiplier option the elastic solver does not have",
                &ELASTIC.replacen(
                    "levels = [0, 1]",
                    "levels = [0, 1]\nmultipliers = [\"M1star\"]\ndeltas = [0.0]",
                    1,
                ),
                "--multiplier M0: the elastic solver has no multiplier space M0 yet (it has M1star)",
            )
        },
        Case {
            args: vec!["run", "{scene}", "--out", "{out}", "--delta", "0"],
            ..scene(
                "a delta option on an elastic scene without solver cases",
                ELASTIC,
                "--multiplier and --delta select solver cases, and the elastic scene 'small' lists none",
            )
        },
        Case {
            args: vec!["bench", "{scene}", "--vertices", "100"],
            ..scene(
                "bench on an elastic scene",
                ELASTIC,
                "scene 'small' is elastic: this command times the scalar problem's solver only",
            )
        },
        Case {
            args: vec!["scene", "--template", "elastic"],
            ..scene(
                "unknown template kind",
                SMALL,
                "unknown problem kind 'elastic' (expected scalar or elasticity)",
            )
        },
        // --- exact data that are not those of an exact solution (issue 42): `check` refuses ---
        bad_exact("exact px of the wrong sign", "px-sign", "exact.px is not ∂u/∂x of exact.u: px = "),
        bad_exact("f wrong in one term", "f-term", "data.f is not −Δu of exact.u"),
        bad_exact("jump of the wrong sign", "jump-sign", "exact.jump is not u⁺ − u⁻ on Γc"),
        bad_exact("g not u on one side", "g-side", "data.g is not exact.u on ∂Ω"),
        Case {
            args: vec!["mesh", "{scene}"],
            ..scene(
                "mesh without --out",
                SMALL,
                "the following required arguments were not provided: --out <OUT>",
            )
        },
    ]
}

/// Every file under `dir` (relative path → bytes); empty when `dir` does not exist.
fn snapshot(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    fn walk(root: &Path, dir: &Path, out: &mut BTreeMap<PathBuf, Vec<u8>>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for e in entries {
            let p = e.unwrap().path();
            if p.is_dir() {
                out.insert(p.strip_prefix(root).unwrap().join(""), Vec::new());
                walk(root, &p, out);
            } else {
                out.insert(
                    p.strip_prefix(root).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                );
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(dir, dir, &mut out);
    out
}

/// True when this process can read a mode-000 file (root, or CAP_DAC_OVERRIDE).
fn permissions_ignored(dir: &Path) -> bool {
    use std::os::unix::fs::PermissionsExt;
    let probe = dir.join("probe");
    std::fs::write(&probe, b"x").unwrap();
    std::fs::set_permissions(&probe, std::fs::Permissions::from_mode(0o000)).unwrap();
    let ignored = std::fs::read(&probe).is_ok();
    std::fs::set_permissions(&probe, std::fs::Permissions::from_mode(0o600)).unwrap();
    std::fs::remove_file(&probe).unwrap();
    ignored
}

#[test]
fn catalogue_of_bad_inputs() {
    use std::os::unix::fs::PermissionsExt;
    let root = tempfile::tempdir().unwrap();
    let privileged = permissions_ignored(root.path());
    let cases = catalogue();
    let mut names: Vec<&str> = cases.iter().map(|c| c.what).collect();
    names.sort_unstable();
    names.dedup();
    assert_eq!(names.len(), cases.len(), "case names are distinct");
    assert!(cases.len() >= 45, "{} cases", cases.len());
    let mut skipped = Vec::new();
    for (k, c) in cases.iter().enumerate() {
        let dir = root.path().join(format!("case{k:02}"));
        std::fs::create_dir(&dir).unwrap();
        let scene = dir.join("scene.toml");
        match &c.input {
            Input::Scene(bytes) => std::fs::write(&scene, bytes).unwrap(),
            Input::Missing => {}
            Input::Directory => std::fs::create_dir(&scene).unwrap(),
            Input::Unreadable => {
                std::fs::write(&scene, SMALL).unwrap();
                std::fs::set_permissions(&scene, std::fs::Permissions::from_mode(0o000)).unwrap();
            }
        }
        let out = match c.out {
            Out::Fresh | Out::Existing => dir.join("out"),
            Out::UnderFile => {
                std::fs::write(dir.join("file"), b"a regular file").unwrap();
                dir.join("file").join("out")
            }
            Out::IsFile => {
                std::fs::write(dir.join("file"), b"a regular file").unwrap();
                dir.join("file")
            }
            Out::ReadOnly => {
                let ro = dir.join("ro");
                std::fs::create_dir(&ro).unwrap();
                std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
                ro.join("out")
            }
        };
        // Root reads mode-000 files and writes into mode-555 folders: those sub-cases cannot fail
        // there, so they are skipped (the `--out` under a regular file covers root).
        if privileged
            && matches!(
                (&c.input, &c.out),
                (Input::Unreadable, _) | (_, Out::ReadOnly)
            )
        {
            skipped.push(c.what);
            continue;
        }
        if matches!(c.out, Out::Existing) {
            let earlier = out.join("small");
            std::fs::create_dir_all(earlier.join("fields")).unwrap();
            std::fs::write(earlier.join("summary.json"), b"{\"scene\": \"small\"}\n").unwrap();
            std::fs::write(earlier.join("fields").join("a.xdmf"), [0u8, 1, 2, 255]).unwrap();
        }
        let before = snapshot(&out);
        let fill = |s: &str| {
            s.replace("{scene}", &scene.display().to_string())
                .replace("{out}", &out.display().to_string())
                .replace("{dir}", &dir.display().to_string())
        };
        let args: Vec<String> = c.args.iter().map(|a| fill(a)).collect();
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_sdcrack"));
        cmd.args(&args).env_remove("SDCRACK_REFERENCES");
        if let Some((key, value)) = c.env {
            cmd.env(key, fill(value));
        }
        let o = cmd.output().expect("binary runs");
        let err = String::from_utf8_lossy(&o.stderr).into_owned();
        let what = c.what;
        println!("{what}: {}", err.trim_end());
        assert!(
            !err.contains("panicked") && o.status.code() != Some(101),
            "{what}: panic: {err}"
        );
        assert_eq!(
            o.status.code(),
            Some(c.code),
            "{what}: exit code; stderr: {err}"
        );
        assert_eq!(
            err.lines().count(),
            1,
            "{what}: one line on stderr: {err:?}"
        );
        assert!(err.ends_with('\n'), "{what}: {err:?}");
        assert!(err.starts_with("sdcrack: error: "), "{what}: {err}");
        // An error in a scene file says where: the line and column of the
        // key, of the table a missing key belongs to, or of the bad byte or TOML syntax. Only
        // what is absent from the file has no place to point at.
        let absent = [
            "the scene is empty",
            "missing table [",
            "missing key `name` at the top level",
        ];
        if err.contains(": invalid scene ") && !absent.iter().any(|a| err.contains(a)) {
            assert!(
                err.contains(" line "),
                "{what}: no line and column in: {err}"
            );
        }
        let needle = fill(&c.needle);
        assert!(
            err.contains(&needle),
            "{what}: expected '{needle}' in: {err}"
        );
        if let Some(check) = c.check {
            check(&err);
        }
        let after = snapshot(&out);
        assert_eq!(
            after.keys().collect::<Vec<_>>(),
            before.keys().collect::<Vec<_>>(),
            "{what}: nothing added to or removed from --out"
        );
        assert!(
            after == before,
            "{what}: --out left byte for byte as it was"
        );
        if matches!(c.out, Out::ReadOnly) {
            std::fs::set_permissions(dir.join("ro"), std::fs::Permissions::from_mode(0o755))
                .unwrap();
        }
        if matches!(c.input, Input::Unreadable) {
            std::fs::set_permissions(&scene, std::fs::Permissions::from_mode(0o600)).unwrap();
        }
    }
    println!(
        "{} bad inputs checked, {} skipped (privileged: permissions do not apply): {skipped:?}",
        cases.len() - skipped.len(),
        skipped.len()
    );
}
