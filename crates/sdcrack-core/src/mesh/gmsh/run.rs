//! Meshing with the `gmsh` binary: the `.geo` script written for a polygon with cracks, the
//! gmsh process (version query, meshing call, first error line) and the input checks made
//! before gmsh is started. Coordinates are written in their shortest round-trip form.

use std::fmt::Write as _;
use std::path::Path;
use std::process::{Command, Output};
use std::time::Instant;

use super::coarse::CoarseMesh;
use super::error::{io_error, GmshError, Result};
use super::read::read_msh_snapped;

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
// ---------------------------------------------------------------------------------------
// Running gmsh
// ---------------------------------------------------------------------------------------

/// The `.geo` script that [`mesh_polygon`] gives to gmsh.
///
/// `polygon` is the outer boundary, counter-clockwise or clockwise, closed implicitly (a last
/// point equal to the first is dropped); `cracks` are polylines of at least two points strictly
/// inside the polygon but for their ends, which may lie on an edge (a mouth: the point is then
/// inserted into the boundary curve, between the edge's vertices, and the crack uses it; not
/// validated here). Points are numbered boundary first (with no mouth: the polygon's vertices),
/// then each crack's other points in order; every point gets characteristic length `mesh_size`; crack segment k is a Line from
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
    // the boundary points: the polygon's vertices with the cracks' mouths inserted along their
    // edges (an edge crack's end must be a point of the boundary curve); no mouth, no change
    let boundary = boundary_points(polygon, cracks);
    let n = boundary.len();
    for (k, p) in boundary.iter().enumerate() {
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
        let mut tags = Vec::with_capacity(crack.len());
        for (k, p) in crack.iter().enumerate() {
            let end = k == 0 || k + 1 == crack.len();
            match boundary.iter().position(|b| b == p).filter(|_| end) {
                Some(mouth) => tags.push(mouth + 1),
                None => {
                    let _ = writeln!(s, "Point({next}) = {{{:?}, {:?}, 0, {h:?}}};", p[0], p[1]);
                    tags.push(next);
                    next += 1;
                }
            }
        }
        let mut lines = Vec::new();
        for w in tags.windows(2) {
            let _ = writeln!(s, "Line({next_line}) = {{{}, {}}};", w[0], w[1]);
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
pub(super) fn geo_options(h: f64) -> String {
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

/// The polygon's vertices in order with every crack end that lies on an edge (exactly, not at
/// a vertex: a mouth) inserted into that edge, ordered along it.
fn boundary_points(polygon: &[[f64; 2]], cracks: &[Vec<[f64; 2]>]) -> Vec<[f64; 2]> {
    let ends = cracks
        .iter()
        .filter(|c| c.len() >= 2)
        .flat_map(|c| [c[0], c[c.len() - 1]]);
    let mut on_edge: Vec<Vec<[f64; 2]>> = vec![Vec::new(); polygon.len()];
    for p in ends {
        if polygon.contains(&p) {
            continue;
        }
        if let Some(k) = crate::geometry::boundary_edge_of(p, polygon) {
            on_edge[k].push(p);
        }
    }
    let mut out = Vec::with_capacity(polygon.len());
    for (&v, mouths) in polygon.iter().zip(&mut on_edge) {
        out.push(v);
        let d = |p: &[f64; 2]| (p[0] - v[0]).hypot(p[1] - v[1]);
        mouths.sort_by(|a, b| d(a).total_cmp(&d(b)));
        mouths.dedup();
        out.extend(mouths.iter().copied());
    }
    out
}

pub(super) fn join(tags: &[usize]) -> String {
    let items: Vec<String> = tags.iter().map(|t| t.to_string()).collect();
    items.join(", ")
}

/// The polygon without a repeated closing point.
pub(super) fn open_polygon(polygon: &[[f64; 2]]) -> &[[f64; 2]] {
    match polygon {
        [first, .., last] if polygon.len() > 1 && first == last => &polygon[..polygon.len() - 1],
        _ => polygon,
    }
}

/// Meshes the polygon with its cracks by running gmsh in `workdir`.
///
/// Writes `workdir/coarse.geo` ([`geo_script`]), runs
/// `gmsh coarse.geo -2 -o coarse.msh -format msh41 -v 2 -nt 1` there (creating `workdir` if
/// needed), and reads `workdir/coarse.msh` with the rules of [`read_msh`](super::read_msh). The
/// vertices at the given polygon and crack points carry the given coordinates exactly (gmsh
/// writes only 16 significant digits, so they are restored from the input); other crack
/// vertices lie on the crack segments up to rounding. `cracks[c]` of the result runs from `cracks[c][0]` to the
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
    // the geometry was validated by the caller: crack ends on ∂Ω are mouths the script made
    let mesh = read_msh_snapped(
        &msh_text,
        &msh.display().to_string(),
        &exact,
        crate::geometry::CrackEnds::MayBeMouths,
    )?;
    let run = GmshRun {
        version,
        seconds,
        msh_text,
    };
    Ok((mesh, run))
}

pub(super) fn validate_input(
    polygon: &[[f64; 2]],
    cracks: &[Vec<[f64; 2]>],
    mesh_size: f64,
) -> Result<()> {
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

pub(super) fn run_gmsh(args: &[&str], dir: &Path) -> Result<Output> {
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
pub(super) fn first_error_line(output: &Output) -> String {
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
