//! Validation of a scene file's structs ([`super::raw`]) into sdcrack-core's [`Scene`]: every
//! expression parsed once into an [`Expr`] tree, every number checked (cells > 0, levels
//! distinct, δ ≥ 0 and finite, …), every name one the schema allows ([`super::schema::ALLOWED`]).
//! Errors are [`SceneError`]s carrying their key as a [`KeyPath`]; the loader adds where the key
//! is written ([`SceneError::located`]).

use std::path::Path;

use super::elastic::{validate_elastic, ElasticContext};
use super::error::{CrackName, KeyRole, SceneError};
use super::limits::MAX_CELLS;
use super::raw::{
    CrackToml, DataToml, DiscretizationToml, ExactToml, GeometryToml, GradingToml, OutputsToml,
    ProblemToml, SceneToml,
};
use super::schema::{ELASTIC_FIELDS, FIELDS, KNOWN_REFERENCES};
use crate::did_you_mean::suggest;
use sdcrack_core::case::CaseAxes;
use sdcrack_core::expr::{Expr, Var};
use sdcrack_core::geometry::CrackEnds;
use sdcrack_core::problem::Named;
use sdcrack_core::problem::{
    Domain, Exact, Meshing, MultiplierSpace, Polyline, Rectangle, Segment, USpace,
};
use sdcrack_core::scene::{
    check_level, FieldSet, KeyPath, Level0Size, Problem, ProblemKind, ScalarProblem, Scene,
    Verification, MAX_LEVEL,
};

fn parse_expr(key: &str, text: &str) -> Result<Expr, SceneError> {
    Expr::parse(text).map_err(|error| SceneError::Expression {
        key: KeyPath::keys(key),
        source_text: text.to_string(),
        error,
        at: None,
    })
}

/// A value error about the key `dotted` (a name the program writes: no indices).
fn value(dotted: &str, message: impl Into<String>) -> SceneError {
    SceneError::value(KeyPath::keys(dotted), message)
}

fn check_finite_point(what: &KeyPath, p: [f64; 2]) -> Result<(), SceneError> {
    if p.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(SceneError::value(
            what.clone(),
            format!(" has a non-finite coordinate ({}, {})", p[0], p[1]),
        ))
    }
}

/// `[geometry]`, then `message`.
fn geometry_table(message: &str) -> SceneError {
    SceneError::key(KeyPath::keys("geometry"), KeyRole::Table, message)
}

impl SceneToml {
    /// `base_dir`: the folder relative mesh file paths are read from (the scene file's). With
    /// the scene, where each of its cracks is written (for messages about a crack).
    pub(super) fn validate(self, base_dir: &Path) -> Result<(Scene, Vec<CrackName>), SceneError> {
        let name = self.name.trim().to_string();
        if name.is_empty()
            || name.len() > 100
            || !name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
        {
            return Err(value(
                "name",
                format!(
                    " {:?} must be 1-100 characters of letters, digits, '-' or '_' (it names the results folder)",
                    self.name
                ),
            ));
        }
        // the problem kind first: what the rest of the scene may hold depends on it
        let kind = problem_kind(self.problem.as_ref())?;
        let d = &self.discretization;
        let meshing = validate_meshing(d, base_dir)?;
        let grading = d.grading.as_ref().map(validate_grading).transpose()?;
        let mut file_triangles = 0;
        let ends = crack_ends(kind);
        let (domain, cracks, crack_names) = match (&meshing, self.geometry) {
            (Meshing::File(path), None) => {
                let (domain, cracks, triangles) =
                    sdcrack_core::mesh::msh_file_geometry_with(path, ends)
                    .map_err(|e| value("discretization.mesh", format!(": {e}")))?;
                file_triangles = triangles;
                let names = (1..=cracks.len())
                    .map(|number| CrackName::MeshFile {
                        number,
                        file: path.clone(),
                    })
                    .collect();
                (domain, cracks, names)
            }
            (Meshing::File(_), Some(_)) => {
                return Err(geometry_table(
                    " must be left out with discretization.mesh: the domain and the cracks come from the mesh file's physical groups",
                ))
            }
            (_, None) => {
                return Err(geometry_table(
                    " is missing: give geometry.domain and geometry.crack (or geometry.cracks)",
                ))
            }
            (_, Some(g)) => validate_geometry(g, ends)?,
        };
        let level0 = match meshing {
            Meshing::Cells(c) => Level0Size::Grid(c),
            Meshing::MeshSize(h) => {
                let area = sdcrack_core::geometry::signed_area(&domain.polygon()).abs();
                Level0Size::Triangles(1.5 * area / (3f64.sqrt() / 4.0 * h * h))
            }
            Meshing::File(_) => Level0Size::Triangles(file_triangles as f64),
        };
        let (problem, axes, fields, references, verification) = match kind {
            ProblemKind::Scalar => {
                refuse_elastic_keys(self.problem.as_ref(), &self.data, self.exact.as_ref())?;
                let problem = scalar_problem(&self.data, self.exact.as_ref())?;
                let levels = validate_levels(&d.levels, level0)?;
                let (axes, u_spaces, multipliers) = scalar_axes(d, levels)?;
                let (fields, references) = validate_outputs(self.outputs.as_ref(), FIELDS)?;
                let verification = match self.verification {
                    None => Verification::default(),
                    Some(v) => v.validate(&u_spaces, &multipliers)?,
                };
                (
                    Problem::Scalar(problem),
                    axes,
                    fields,
                    references,
                    verification,
                )
            }
            ProblemKind::Elasticity => {
                refuse_scalar_keys(&self.data, self.exact.as_ref(), d)?;
                let context = ElasticContext {
                    domain: &domain,
                    cracks: &cracks,
                    meshing: &meshing,
                };
                let no_problem = ProblemToml::default();
                let data = validate_elastic(
                    self.problem.as_ref().unwrap_or(&no_problem),
                    &self.data,
                    self.exact.as_ref(),
                    &context,
                )?;
                let levels = validate_levels(&d.levels, level0)?;
                let axes = elastic_axes(d, levels)?;
                let (fields, references) = validate_outputs(self.outputs.as_ref(), ELASTIC_FIELDS)?;
                let verification = match self.verification {
                    None => Verification::default(),
                    Some(v) => v.validate(&[], &[])?,
                };
                (
                    Problem::Elasticity(data),
                    axes,
                    fields,
                    references,
                    verification,
                )
            }
        };
        let scene = Scene {
            name,
            description: self.description,
            domain,
            cracks,
            meshing,
            grading,
            level0,
            problem,
            axes,
            fields,
            references,
            verification,
        };
        Ok((scene, crack_names))
    }
}

/// `[problem] kind`: scalar (the default, also without `[problem]`) or elasticity.
fn problem_kind(problem: Option<&ProblemToml>) -> Result<ProblemKind, SceneError> {
    match problem.and_then(|p| p.kind.as_deref()) {
        None => Ok(ProblemKind::Scalar),
        Some(name) => ProblemKind::from_name(name).ok_or_else(|| {
            let hint = suggest(name, ProblemKind::NAMES)
                .map(|s| format!("; did you mean \"{s}\"?"))
                .unwrap_or_default();
            value(
                "problem.kind",
                format!(
                    ": unknown value {name:?} (expected one of {}){hint}",
                    ProblemKind::NAMES.join(", ")
                ),
            )
        }),
    }
}

/// The first key of `keys` (dotted, with whether the scene gives it) that the scene gives,
/// refused with `why`.
fn refuse_given(keys: &[(&str, bool)], why: &str) -> Result<(), SceneError> {
    match keys.iter().find(|(_, given)| *given) {
        Some((k, _)) => Err(value(k, why)),
        None => Ok(()),
    }
}

/// A scalar scene gives none of the elastic problem's keys.
fn refuse_elastic_keys(
    problem: Option<&ProblemToml>,
    d: &DataToml,
    exact: Option<&ExactToml>,
) -> Result<(), SceneError> {
    let mut keys: Vec<(&str, bool)> = Vec::new();
    if let Some(p) = problem {
        keys.extend([
            ("problem.plane", p.plane.is_some()),
            ("problem.E", p.young.is_some()),
            ("problem.nu", p.nu.is_some()),
            ("problem.lambda", p.lambda.is_some()),
            ("problem.mu", p.mu.is_some()),
            ("problem.friction", p.friction.is_some()),
        ]);
    }
    keys.extend([
        ("data.fx", d.fx.is_some()),
        ("data.fy", d.fy.is_some()),
        ("data.gx", d.gx.is_some()),
        ("data.gy", d.gy.is_some()),
        ("data.traction", d.traction.is_some()),
        ("data.fixed", d.fixed.is_some()),
    ]);
    if let Some(e) = exact {
        keys.extend([
            ("exact.ux", e.ux.is_some()),
            ("exact.uy", e.uy.is_some()),
            ("exact.sxx", e.sxx.is_some()),
            ("exact.syy", e.syy.is_some()),
            ("exact.sxy", e.sxy.is_some()),
            ("exact.opening", e.opening.is_some()),
            ("exact.slip", e.slip.is_some()),
            ("exact.pressure", e.pressure.is_some()),
            ("exact.sif", e.sif.is_some()),
        ]);
    }
    refuse_given(
        &keys,
        " is a key of the elastic problem, and this scene is scalar (set [problem] kind = \"elasticity\" for an elastic body; docs/elasticity.md)",
    )
}

/// An elastic scene gives none of the scalar problem's keys (data, exact solution, case axes).
fn refuse_scalar_keys(
    d: &DataToml,
    exact: Option<&ExactToml>,
    x: &DiscretizationToml,
) -> Result<(), SceneError> {
    let mut keys: Vec<(&str, bool)> = vec![("data.f", d.f.is_some()), ("data.g", d.g.is_some())];
    if let Some(e) = exact {
        keys.extend([
            ("exact.u", e.u.is_some()),
            ("exact.px", e.px.is_some()),
            ("exact.py", e.py.is_some()),
            ("exact.jump", e.jump.is_some()),
        ]);
    }
    keys.extend([
        ("discretization.u_spaces", x.u_spaces.is_some()),
        ("discretization.p_mass", x.p_mass.is_some()),
        ("discretization.p_spaces", x.p_spaces.is_some()),
    ]);
    refuse_given(
        &keys,
        " is a key of the scalar problem, and this scene is elastic ([problem] kind = \"elasticity\": data fx, fy, gx, gy, traction, fixed; exact ux, uy, ...; case axes levels, multipliers, deltas; docs/elasticity.md)",
    )
}

/// The elastic problem's case axes (`levels` validated): levels × multipliers × δ of the AFW
/// method (docs/elasticity.md, "The run"). `multipliers` and `deltas` go together: a scene that
/// lists neither has no solver case (its references only); a multiplier space the elastic
/// solver does not have ([`sdcrack_core::afw::MULTIPLIER_SPACES`]) is refused.
fn elastic_axes(d: &DiscretizationToml, levels: Vec<u32>) -> Result<CaseAxes, SceneError> {
    let (multipliers, deltas) = match (d.multipliers.as_deref(), d.deltas.as_deref()) {
        (None, None) => (Vec::new(), Vec::new()),
        (Some(_), None) => return Err(missing("discretization", "deltas")),
        (None, Some(_)) => return Err(missing("discretization", "multipliers")),
        (Some(m), Some(deltas)) => {
            let key = "discretization.multipliers";
            let multipliers = validate_names::<MultiplierSpace>(key, m)?;
            let solved = sdcrack_core::afw::MULTIPLIER_SPACES;
            if let Some(m) = multipliers.iter().find(|m| !solved.contains(m)) {
                let names: Vec<&str> = solved.iter().map(|m| m.name()).collect();
                return Err(value(
                    key,
                    format!(
                        ": the elastic solver has no multiplier space {m} yet (it has {}; docs/elasticity.md, \"The run\")",
                        names.join(", ")
                    ),
                ));
            }
            (multipliers, validate_deltas(deltas)?)
        }
    };
    // the scalar problem's axes (u space, p mass, p space) are not the elastic method's: empty
    Ok(CaseAxes {
        levels,
        u_spaces: Vec::new(),
        multipliers,
        p_masses: Vec::new(),
        p_spaces: Vec::new(),
        deltas,
        problems: vec![ProblemKind::Elasticity],
    })
}

/// `missing key `name` in [table]`.
fn missing(table: &str, name: &str) -> SceneError {
    SceneError::key(KeyPath::keys(table), KeyRole::Missing(name.into()), "")
}

/// The scalar problem's f, g and exact solution.
fn scalar_problem(data: &DataToml, exact: Option<&ExactToml>) -> Result<ScalarProblem, SceneError> {
    let f = parse_expr(
        "data.f",
        data.f.as_deref().ok_or_else(|| missing("data", "f"))?,
    )?;
    let g = parse_expr(
        "data.g",
        data.g.as_deref().ok_or_else(|| missing("data", "g"))?,
    )?;
    let exact = match exact {
        None => None,
        Some(e) => {
            let u = e.u.as_deref().ok_or_else(|| missing("exact", "u"))?;
            let u = parse_expr("exact.u", u)?;
            let px = match &e.px {
                Some(s) => parse_expr("exact.px", s)?,
                None => u.derivative(Var::X),
            };
            let py = match &e.py {
                Some(s) => parse_expr("exact.py", s)?,
                None => u.derivative(Var::Y),
            };
            let jump = (e.jump.as_deref())
                .map(|s| parse_expr("exact.jump", s))
                .transpose()?;
            Some(Exact { u, px, py, jump })
        }
    };
    Ok(ScalarProblem { f, g, exact })
}

/// The scalar problem's case axes (`levels` validated): u spaces, multipliers, p masses,
/// p spaces and δ, with the u spaces and multipliers for `[verification]`.
fn scalar_axes(
    d: &DiscretizationToml,
    levels: Vec<u32>,
) -> Result<(CaseAxes, Vec<USpace>, Vec<MultiplierSpace>), SceneError> {
    let u_spaces = d
        .u_spaces
        .as_deref()
        .ok_or_else(|| missing("discretization", "u_spaces"))?;
    let u_spaces = validate_names::<USpace>("discretization.u_spaces", u_spaces)?;
    let multipliers =
        (d.multipliers.as_deref()).ok_or_else(|| missing("discretization", "multipliers"))?;
    let multipliers = validate_names::<MultiplierSpace>("discretization.multipliers", multipliers)?;
    // a scene that leaves an axis out runs the key's default (sdcrack-core's case)
    let mut axes = CaseAxes::defaults();
    let p_masses = names_or("discretization.p_mass", &d.p_mass, axes.p_masses.take())?;
    let p_spaces = names_or("discretization.p_spaces", &d.p_spaces, axes.p_spaces.take())?;
    if !p_spaces
        .iter()
        .any(|p| u_spaces.iter().any(|&u| p.serves(u)))
    {
        return Err(value(
            "discretization.p_spaces",
            " = [\"broken-tangential\"] needs broken u: a continuous u cannot open the crack, so u_spaces must list \"broken\" (or p_spaces \"continuous\")",
        ));
    }
    let deltas = d
        .deltas
        .as_deref()
        .ok_or_else(|| missing("discretization", "deltas"))?;
    let deltas = validate_deltas(deltas)?;
    // the lists the scene gives; the axes it may leave out keep their defaults
    axes.levels = Some(levels);
    axes.u_spaces = Some(u_spaces.clone());
    axes.multipliers = Some(multipliers.clone());
    axes.p_masses = Some(p_masses);
    axes.p_spaces = Some(p_spaces);
    axes.deltas = Some(deltas);
    let axes = axes.complete().map_err(|axis| {
        SceneError::value(
            KeyPath::keys("discretization"),
            format!(": no list of {axis} (a defect of sdcrack)"),
        )
    })?;
    Ok((axes, u_spaces, multipliers))
}

/// `[outputs]`: the fields (names of `known`) and the references; absent: every field of
/// `known`, no reference.
fn validate_outputs(
    outputs: Option<&OutputsToml>,
    known: &[&str],
) -> Result<(FieldSet, Vec<String>), SceneError> {
    match outputs {
        None => Ok((
            FieldSet {
                u: known.contains(&"u"),
                p: known.contains(&"p"),
                lambda: known.contains(&"lambda"),
            },
            Vec::new(),
        )),
        Some(o) => Ok((
            validate_fields(&o.fields, known)?,
            validate_references(&o.references)?,
        )),
    }
}

/// `[[x, y], [x, y]]`: exactly two points of two numbers each (TOML arrays have any length).
fn two_points(key: &KeyPath, v: &[Vec<f64>]) -> Result<[[f64; 2]; 2], SceneError> {
    match v {
        [a, b] if a.len() == 2 && b.len() == 2 => Ok([[a[0], a[1]], [b[0], b[1]]]),
        _ => Err(SceneError::value(
            key.clone(),
            format!(
                " must be two points [[x, y], [x, y]]; got {} point(s) with {:?} coordinates",
                v.len(),
                v.iter().map(Vec::len).take(8).collect::<Vec<_>>()
            ),
        )),
    }
}

/// Where a crack may end: an elastic scene's crack may end on ∂Ω (an edge crack's mouth,
/// docs/elasticity.md); a scalar scene's cracks stay strictly inside Ω.
fn crack_ends(kind: ProblemKind) -> CrackEnds {
    match kind {
        ProblemKind::Elasticity => CrackEnds::MayBeMouths,
        ProblemKind::Scalar => CrackEnds::Inside,
    }
}

/// Domain and cracks of `[geometry]`, validated ([`sdcrack_core::geometry`]), with each crack's name
/// for messages. A polygon is stored counter-clockwise.
fn validate_geometry(
    g: GeometryToml,
    ends: CrackEnds,
) -> Result<(Domain, Vec<Polyline>, Vec<CrackName>), SceneError> {
    let Some(domain) = g.domain else {
        return Err(value(
            "geometry.domain",
            " is missing: give { rectangle = [[x0, y0], [x1, y1]] } or { polygon = [[x, y], ...] }",
        ));
    };
    let domain = match (domain.rectangle, domain.polygon) {
        (Some(r), None) => {
            let key = KeyPath::keys("geometry.domain.rectangle");
            let [lo, hi] = two_points(&key, &r)?;
            check_finite_point(&key, lo)?;
            check_finite_point(&key, hi)?;
            if !(hi[0] > lo[0] && hi[1] > lo[1]) {
                return Err(SceneError::value(key, format!(
                    " [[{}, {}], [{}, {}]] must list the lower-left corner first and have positive width and height",
                    lo[0], lo[1], hi[0], hi[1]
                )));
            }
            Domain::Rectangle(Rectangle { min: lo, max: hi })
        }
        (None, Some(p)) => {
            let key = KeyPath::keys("geometry.domain.polygon");
            let points = points_of(&key, &p)?;
            sdcrack_core::geometry::validate_polygon(&points)
                .map_err(|e| SceneError::named(key, e.to_string()))?;
            Domain::Polygon(sdcrack_core::geometry::counter_clockwise(&points))
        }
        _ => {
            return Err(value(
                "geometry.domain",
                " must have exactly one of rectangle and polygon",
            ))
        }
    };
    let (cracks, names): (Vec<Polyline>, Vec<KeyPath>) = match (g.crack, g.cracks) {
        (Some(c), None) => {
            let (crack, name) = validate_crack(c, &KeyPath::keys("geometry.crack"))?;
            (vec![crack], vec![name])
        }
        (None, Some(list)) if !list.is_empty() => list
            .into_iter()
            .enumerate()
            .map(|(i, c)| validate_crack(c, &KeyPath::keys("geometry.cracks").index(i)))
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .unzip(),
        (None, Some(_)) => {
            return Err(value(
                "geometry.cracks",
                " is empty: give at least one crack",
            ))
        }
        (None, None) => {
            return Err(SceneError::key(
                KeyPath::keys("geometry"),
                KeyRole::Missing("crack".into()),
                ": give crack = { segment = [[xa, ya], [xb, yb]] } or a list cracks = [...]",
            ))
        }
        _ => {
            return Err(value(
                "geometry",
                " must have exactly one of crack (a single crack) and cracks (a list)",
            ))
        }
    };
    let polylines: Vec<Vec<[f64; 2]>> = cracks.iter().map(|c| c.points.clone()).collect();
    sdcrack_core::geometry::validate_cracks_with(&domain.polygon(), &polylines, ends).map_err(
        |e| {
            // the core names crack i `geometry.cracks[i]`: name the cracks as the scene does
            let mut m = e.to_string();
            for (i, name) in names.iter().enumerate().rev() {
                m = m.replace(&format!("geometry.cracks[{i}]"), &name.to_string());
            }
            match e.crack().and_then(|c| names.get(c)) {
                Some(key) => SceneError::named(key.clone(), m),
                None => SceneError::Scene(m),
            }
        },
    )?;
    Ok((
        domain,
        cracks,
        names.into_iter().map(CrackName::Key).collect(),
    ))
}

/// One crack: `{ segment = [a, b] }` or `{ polyline = [x0, x1, ...] }`, and the key messages
/// name it by: `geometry.crack.segment` (or `.polyline`) for the one crack, `geometry.cracks[i]`
/// for one of a list.
fn validate_crack(c: CrackToml, at: &KeyPath) -> Result<(Polyline, KeyPath), SceneError> {
    let single = *at == KeyPath::keys("geometry.crack");
    let name = |key: KeyPath| if single { key } else { at.clone() };
    match (c.segment, c.polyline) {
        (Some(seg), None) => {
            let key = at.clone().key("segment");
            let [a, b] = two_points(&key, &seg)?;
            check_finite_point(&key, a)?;
            check_finite_point(&key, b)?;
            if (Segment { a, b }).length() <= 0.0 {
                return Err(SceneError::value(
                    key,
                    " has zero length (its two end points coincide)",
                ));
            }
            Ok((Polyline { points: vec![a, b] }, name(key)))
        }
        (None, Some(line)) => {
            let key = at.clone().key("polyline");
            let points = points_of(&key, &line)?;
            if points.len() < 2 {
                return Err(SceneError::value(
                    key,
                    format!(" must have at least two points; got {}", points.len()),
                ));
            }
            Ok((Polyline { points }, name(key)))
        }
        _ => Err(SceneError::value(
            at.clone(),
            " must have exactly one of segment and polyline",
        )),
    }
}

/// A list of points `[[x, y], ...]` with finite coordinates.
fn points_of(key: &KeyPath, v: &[Vec<f64>]) -> Result<Vec<[f64; 2]>, SceneError> {
    v.iter()
        .map(|p| match p[..] {
            [x, y] => {
                check_finite_point(key, [x, y])?;
                Ok([x, y])
            }
            _ => Err(SceneError::value(
                key.clone(),
                format!(
                    " must be a list of points [x, y]; a point has {} coordinate(s)",
                    p.len()
                ),
            )),
        })
        .collect()
}

/// `grading = { beta, radius }`: 0 < β ≤ 1, R > 0.
fn validate_grading(g: &GradingToml) -> Result<sdcrack_core::problem::Grading, SceneError> {
    if !(g.beta.is_finite() && g.beta > 0.0 && g.beta <= 1.0) {
        return Err(value(
            "discretization.grading.beta",
            format!(
                " must be in (0, 1] (1/2 or less for the r^(1/2) crack tip; 1 is uniform); got {}",
                g.beta
            ),
        ));
    }
    if !(g.radius.is_finite() && g.radius > 0.0) {
        return Err(value(
            "discretization.grading.radius",
            format!(" must be a positive length; got {}", g.radius),
        ));
    }
    Ok(sdcrack_core::problem::Grading {
        beta: g.beta,
        radius: g.radius,
    })
}

/// Exactly one of `cells`, `mesh_size` and `mesh`.
fn validate_meshing(d: &DiscretizationToml, base_dir: &Path) -> Result<Meshing, SceneError> {
    match (&d.cells, d.mesh_size, &d.mesh) {
        (Some(c), None, None) => Ok(Meshing::Cells(validate_cells(c)?)),
        (None, Some(h), None) => {
            if !(h.is_finite() && h > 0.0) {
                return Err(value("discretization.mesh_size", format!(
                    " must be a positive number; got {h}"
                )));
            }
            Ok(Meshing::MeshSize(h))
        }
        (None, None, Some(m)) => {
            if m.gmsh.is_empty() || m.gmsh.chars().any(char::is_control) {
                return Err(value("discretization.mesh.gmsh", format!(
                    " {:?} must be a non-empty file path without control characters",
                    m.gmsh
                )));
            }
            Ok(Meshing::File(base_dir.join(&m.gmsh)))
        }
        _ => Err(value(
            "discretization",
            " must have exactly one of cells (structured grid of a rectangle), mesh_size (gmsh) and mesh = { gmsh = \"file.msh\" }",
        )),
    }
}

fn validate_cells(cells: &[i64]) -> Result<[usize; 2], SceneError> {
    let &[nx, ny] = cells else {
        return Err(value(
            "discretization.cells",
            format!(
                " must be two integers [nx, ny]; got {} number(s)",
                cells.len()
            ),
        ));
    };
    let cells = [nx, ny];
    let mut out = [0usize; 2];
    for (o, c) in out.iter_mut().zip(cells) {
        if c <= 0 || c as usize > MAX_CELLS {
            return Err(value(
                "discretization.cells",
                format!(
                    " = [{}, {}]: each entry must be between 1 and {MAX_CELLS}",
                    cells[0], cells[1]
                ),
            ));
        }
        *o = c as usize;
    }
    Ok(out)
}

fn validate_levels(levels: &[i64], size: Level0Size) -> Result<Vec<u32>, SceneError> {
    if levels.is_empty() {
        return Err(value(
            "discretization.levels",
            " is empty: list at least one level, e.g. [0, 1, 2]",
        ));
    }
    let mut out = Vec::with_capacity(levels.len());
    for &l in levels {
        if !(0..=i64::from(MAX_LEVEL)).contains(&l) {
            return Err(value(
                "discretization.levels",
                format!(": level {l} is outside 0..={MAX_LEVEL}"),
            ));
        }
        let l = l as u32;
        if out.contains(&l) {
            return Err(value(
                "discretization.levels",
                format!(": level {l} is listed twice"),
            ));
        }
        check_level(size, l).map_err(|m| value("discretization.levels", format!(": {m}")))?;
        out.push(l);
    }
    out.sort_unstable();
    Ok(out)
}

/// The optional list `names` of the vocabulary `T` ([`validate_names`]), or `default` when the
/// scene leaves it out.
fn names_or<T: Named + PartialEq>(
    key: &str,
    names: &Option<Vec<String>>,
    default: Option<Vec<T>>,
) -> Result<Vec<T>, SceneError> {
    match names {
        None => Ok(default.unwrap_or_default()),
        Some(names) => validate_names(key, names),
    }
}

fn validate_names<T: Named + PartialEq>(key: &str, names: &[String]) -> Result<Vec<T>, SceneError> {
    let (parse, known) = (T::from_name, T::NAMES);
    if names.is_empty() {
        return Err(value(
            key,
            format!(" is empty: list at least one of {}", known.join(", ")),
        ));
    }
    let mut out = Vec::new();
    for n in names {
        let v = parse(n).ok_or_else(|| {
            let hint = suggest(n, known)
                .map(|s| format!("; did you mean \"{s}\"?"))
                .unwrap_or_default();
            value(
                key,
                format!(
                    ": unknown value {n:?} (expected one of {}){hint}",
                    known.join(", ")
                ),
            )
        })?;
        if out.contains(&v) {
            return Err(value(key, format!(": {n:?} is listed twice")));
        }
        out.push(v);
    }
    Ok(out)
}

fn validate_deltas(deltas: &[f64]) -> Result<Vec<f64>, SceneError> {
    if deltas.is_empty() {
        return Err(value(
            "discretization.deltas",
            " is empty: list at least one δ ≥ 0, e.g. [0.0]",
        ));
    }
    let mut out: Vec<f64> = Vec::new();
    for &d in deltas {
        if !d.is_finite() || d < 0.0 {
            return Err(value(
                "discretization.deltas",
                format!(": {d} is not a finite number ≥ 0"),
            ));
        }
        if out.contains(&d) {
            return Err(value(
                "discretization.deltas",
                format!(": {d} is listed twice"),
            ));
        }
        out.push(d);
    }
    // Largest δ first: each solve warm-starts the next, and δ → 0 is the limit studied.
    out.sort_by(|a, b| b.total_cmp(a));
    Ok(out)
}

/// `outputs.fields`: names of `known` (the problem kind's fields), each once.
fn validate_fields(fields: &[String], known: &[&str]) -> Result<FieldSet, SceneError> {
    let mut set = FieldSet::default();
    for f in fields {
        if FIELDS.contains(&f.as_str()) && !known.contains(&f.as_str()) {
            return Err(value(
                "outputs.fields",
                format!(
                    ": {f:?} is a field of the scalar problem; an elastic scene writes {}",
                    known
                        .iter()
                        .map(|k| format!("{k:?}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        let slot = match f.as_str() {
            "u" => &mut set.u,
            "p" => &mut set.p,
            "lambda" => &mut set.lambda,
            other => {
                let hint = suggest(other, FIELDS)
                    .map(|s| format!("; did you mean \"{s}\"?"))
                    .unwrap_or_default();
                return Err(value(
                    "outputs.fields",
                    format!(": unknown field {other:?} (expected u, p, lambda){hint}"),
                ));
            }
        };
        if *slot {
            return Err(value("outputs.fields", format!(": {f:?} is listed twice")));
        }
        *slot = true;
    }
    Ok(set)
}

fn validate_references(refs: &[String]) -> Result<Vec<String>, SceneError> {
    let mut out: Vec<String> = Vec::new();
    for r in refs {
        if !KNOWN_REFERENCES.contains(&r.as_str()) {
            let hint = suggest(r, &KNOWN_REFERENCES)
                .map(|s| format!("; did you mean \"{s}\"?"))
                .unwrap_or_default();
            return Err(value(
                "outputs.references",
                format!(": unknown reference {r:?} (expected dolfinx, freefem){hint}"),
            ));
        }
        if out.contains(r) {
            return Err(value(
                "outputs.references",
                format!(": {r:?} is listed twice"),
            ));
        }
        out.push(r.clone());
    }
    Ok(out)
}
