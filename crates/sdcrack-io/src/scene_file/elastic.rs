//! Validation of an elastic scene's keys (`[problem] kind = "elasticity"`, docs/elasticity.md)
//! into sdcrack-core's [`ElasticData`]: the material ([`Material`]: one pair of (E, ν) and
//! (λ, μ), E > 0 and −1 < ν < ½), frictionless contact only, the loads (f; g on every boundary
//! part without a traction; the tractions by part; the fixed points of an all-traction body,
//! corners of Ω that remove the three rigid modes) and the exact fields (stress by Hooke's law
//! unless given, one (K_I, K_II) per crack tip). Which keys belong to which problem kind is
//! [`super::validate`]'s; the exact data's agreement with the problem is checked by
//! `sdcrack check`, not here.

use sdcrack_core::elasticity::{
    hooke_stress, rigid_modes_removed, BoundaryPart, Component, ElasticData, ElasticExact,
    FixedPoint, Material, PlaneModel, TipSif, Traction,
};
use sdcrack_core::expr::Expr;
use sdcrack_core::problem::{Domain, Meshing, Named, Polyline};
use sdcrack_core::scene::KeyPath;

use super::error::{KeyRole, SceneError};
use super::raw::{DataToml, ExactToml, FixedToml, ProblemToml};
use crate::did_you_mean::suggest;

/// What an elastic scene's validation needs of the rest of the scene.
pub(super) struct ElasticContext<'a> {
    /// Ω.
    pub(super) domain: &'a Domain,
    /// Γc, in the scene's order.
    pub(super) cracks: &'a [Polyline],
    /// How level 0 is made (a mesh file's boundary is one part, `boundary`).
    pub(super) meshing: &'a Meshing,
}

/// The elastic problem's data of `[problem]`, `[data]` and `[exact]`.
pub(super) fn validate_elastic(
    problem: &ProblemToml,
    data: &DataToml,
    exact: Option<&ExactToml>,
    at: &ElasticContext<'_>,
) -> Result<ElasticData, SceneError> {
    let material = validate_material(problem)?;
    let f = [
        required_expr(&data.fx, "data", "fx")?,
        required_expr(&data.fy, "data", "fy")?,
    ];
    let parts = boundary_parts(at.domain, at.meshing);
    let tractions = validate_tractions(data, &parts)?;
    let dirichlet: Vec<&str> = (parts.iter())
        .filter(|p| !tractions.iter().any(|t| t.part.0 == **p))
        .map(String::as_str)
        .collect();
    let g = validate_dirichlet(data, &dirichlet)?;
    let fixed = validate_fixed(data, &dirichlet, at.domain)?;
    let exact = exact
        .map(|e| validate_exact(e, &material, at))
        .transpose()?;
    Ok(ElasticData {
        material,
        f,
        g,
        tractions,
        fixed,
        exact,
    })
}

fn key(dotted: &str) -> KeyPath {
    KeyPath::keys(dotted)
}

/// `missing key `name` in [table]`, then `message`.
fn missing(table: &str, name: &str, message: &str) -> SceneError {
    SceneError::key(key(table), KeyRole::Missing(name.into()), message)
}

fn expr_at(at: KeyPath, text: &str) -> Result<Expr, SceneError> {
    Expr::parse(text).map_err(|error| SceneError::Expression {
        key: at,
        source_text: text.to_string(),
        error,
        at: None,
    })
}

/// The expression of `table.name`, which must be there.
fn required_expr(text: &Option<String>, table: &str, name: &str) -> Result<Expr, SceneError> {
    match text {
        Some(t) => expr_at(key(table).key(name), t),
        None => Err(missing(table, name, "")),
    }
}

/// `problem.plane`, and one pair of (E, ν) and (λ, μ) with E > 0 and −1 < ν < ½ (λ, μ: μ > 0
/// and 3λ + 2μ > 0, the same body); friction 0 or absent.
fn validate_material(p: &ProblemToml) -> Result<Material, SceneError> {
    if let Some(c) = p.friction {
        if c != 0.0 {
            return Err(SceneError::value(
                key("problem.friction"),
                format!(
                    " = {c}: only frictionless contact is solved; give 0 or leave friction out"
                ),
            ));
        }
    }
    let plane = match &p.plane {
        None => PlaneModel::default(),
        Some(name) => one_name::<PlaneModel>("problem.plane", name)?,
    };
    let positive = |k: &str, v: f64, what: &str| {
        if v.is_finite() && v > 0.0 {
            Ok(v)
        } else {
            Err(SceneError::value(
                key(k),
                format!(" = {v} must be a finite number > 0 ({what})"),
            ))
        }
    };
    match (p.young, p.nu, p.lambda, p.mu) {
        (Some(e), Some(nu), None, None) => {
            let e = positive("problem.E", e, "Young's modulus")?;
            if !(nu.is_finite() && nu > -1.0 && nu < 0.5) {
                return Err(SceneError::value(
                    key("problem.nu"),
                    format!(" = {nu} must be in (-1, 1/2): Poisson's ratio of a compressible body (at 1/2 the Lamé λ is infinite)"),
                ));
            }
            Ok(Material::from_young_poisson(e, nu, plane))
        }
        (None, None, Some(lambda), Some(mu)) => {
            let mu = positive("problem.mu", mu, "the shear modulus")?;
            // E > 0 and −1 < ν < ½ with μ > 0: 3λ + 2μ > 0 (a positive bulk modulus)
            if !(lambda.is_finite() && 3.0 * lambda + 2.0 * mu > 0.0) {
                return Err(SceneError::value(
                    key("problem.lambda"),
                    format!(" = {lambda} must be finite with 3 lambda + 2 mu > 0 (a positive bulk modulus: E > 0 and -1 < nu < 1/2); mu = {mu}"),
                ));
            }
            Ok(Material { lambda, mu, plane })
        }
        (e, nu, lambda, mu) => Err(pair_error(
            [("E", e), ("nu", nu)],
            [("lambda", lambda), ("mu", mu)],
        )),
    }
}

/// The error of a material that is not exactly one complete pair.
fn pair_error(young: [(&str, Option<f64>); 2], lame: [(&str, Option<f64>); 2]) -> SceneError {
    let has = |pair: &[(&str, Option<f64>); 2]| pair.iter().any(|(_, v)| v.is_some());
    let both = " and E, nu: give one pair, E and nu or lambda and mu";
    match (has(&young), has(&lame)) {
        (true, true) => SceneError::value(
            key(&format!(
                "problem.{}",
                lame.iter()
                    .find(|(_, v)| v.is_some())
                    .map_or("lambda", |(k, _)| k)
            )),
            format!(" is given{both}"),
        ),
        (false, false) => missing(
            "problem",
            "E",
            ": an elastic body needs its material: E and nu (or lambda and mu)",
        ),
        (true, false) => incomplete(&young),
        (false, true) => incomplete(&lame),
    }
}

/// `missing key` for the absent member of a pair that has one member given.
fn incomplete(pair: &[(&str, Option<f64>); 2]) -> SceneError {
    let (given, absent) = match pair {
        [(g, Some(_)), (a, None)] | [(a, None), (g, Some(_))] => (*g, *a),
        _ => ("", ""),
    };
    missing(
        "problem",
        absent,
        &format!(": {given} is given, and the material needs the pair {given} and {absent}"),
    )
}

/// `name` as a value of the vocabulary `T`, or an error at `dotted` listing them.
fn one_name<T: Named>(dotted: &str, name: &str) -> Result<T, SceneError> {
    T::from_name(name).ok_or_else(|| {
        let hint = suggest(name, T::NAMES)
            .map(|s| format!("; did you mean \"{s}\"?"))
            .unwrap_or_default();
        SceneError::value(
            key(dotted),
            format!(
                ": unknown value {name:?} (expected one of {}){hint}",
                T::NAMES.join(", ")
            ),
        )
    })
}

/// The names of ∂Ω's parts: a rectangle's sides, a polygon's edges `edge1` … `edgeN`, a mesh
/// file's one `boundary`.
pub(super) fn boundary_parts(domain: &Domain, meshing: &Meshing) -> Vec<String> {
    sdcrack_core::mesh::BoundaryParts::of(domain, meshing)
        .names()
        .to_vec()
}

/// `data.traction`: each part a known one (a TOML table cannot hold a key twice), with two
/// expressions.
fn validate_tractions(data: &DataToml, parts: &[String]) -> Result<Vec<Traction>, SceneError> {
    let Some(table) = &data.traction else {
        return Ok(Vec::new());
    };
    let known: Vec<&str> = parts.iter().map(String::as_str).collect();
    let mut out = Vec::new();
    for (part, t) in table {
        let at = key("data.traction").key(part);
        if !known.contains(&part.as_str()) {
            let hint = suggest(part, &known)
                .map(|s| format!("; did you mean \"{s}\"?"))
                .unwrap_or_default();
            return Err(SceneError::value(
                at,
                format!(
                    ": unknown boundary part {part:?} (this domain's parts: {}){hint}",
                    known.join(", ")
                ),
            ));
        }
        let [tx, ty] = &t[..] else {
            return Err(SceneError::value(
                at,
                format!(" must be two expressions [\"tx\", \"ty\"]; got {}", t.len()),
            ));
        };
        out.push(Traction {
            part: BoundaryPart(part.clone()),
            t: [
                expr_at(at.clone().index(0), tx)?,
                expr_at(at.clone().index(1), ty)?,
            ],
        });
    }
    Ok(out)
}

/// g = (gx, gy): required when some part has no traction (`dirichlet`), refused when none.
fn validate_dirichlet(
    data: &DataToml,
    dirichlet: &[&str],
) -> Result<Option<[Expr; 2]>, SceneError> {
    if dirichlet.is_empty() {
        return match (&data.gx, &data.gy) {
            (None, None) => Ok(None),
            (gx, _) => Err(SceneError::value(
                key(if gx.is_some() { "data.gx" } else { "data.gy" }),
                ": every boundary part has a traction, so no part takes u = g; leave gx and gy out",
            )),
        };
    }
    let why = format!(
        ": the boundary part(s) {} have no traction, so u = (gx, gy) there",
        dirichlet.join(", ")
    );
    let gx = data
        .gx
        .as_ref()
        .ok_or_else(|| missing("data", "gx", &why))?;
    let gy = data
        .gy
        .as_ref()
        .ok_or_else(|| missing("data", "gy", &why))?;
    Ok(Some([
        expr_at(key("data.gx"), gx)?,
        expr_at(key("data.gy"), gy)?,
    ]))
}

/// `data.fixed`: only with an all-traction boundary, where it must remove the three rigid modes;
/// each point a corner of Ω with a non-empty set of components.
fn validate_fixed(
    data: &DataToml,
    dirichlet: &[&str],
    domain: &Domain,
) -> Result<Vec<FixedPoint>, SceneError> {
    let list = data.fixed.as_deref().unwrap_or(&[]);
    if !dirichlet.is_empty() {
        if data.fixed.is_some() {
            return Err(SceneError::value(
                key("data.fixed"),
                format!(
                    ": fixed points are for a body whose whole boundary has tractions; the part(s) {} take u = g, which already holds it",
                    dirichlet.join(", ")
                ),
            ));
        }
        return Ok(Vec::new());
    }
    let corners = domain.polygon();
    let fixed = (list.iter().enumerate())
        .map(|(i, f)| validate_fixed_point(f, key("data.fixed").index(i), &corners))
        .collect::<Result<Vec<_>, _>>()?;
    let removed = rigid_modes_removed(&fixed);
    if removed < 3 {
        let what = " every boundary part has a traction, so the body may translate and rotate freely: hold components at corners so that the translations in x and y and the rotation (-y, x) are removed, e.g. fixed = [{ point = [x1, y1], components = [\"x\", \"y\"] }, { point = [x2, y2], components = [\"x\"] }] with y2 != y1";
        return Err(if data.fixed.is_none() {
            missing("data", "fixed", &format!(":{what}"))
        } else {
            SceneError::value(
                key("data.fixed"),
                format!(" removes {removed} of the 3 rigid modes:{what}"),
            )
        });
    }
    Ok(fixed)
}

fn validate_fixed_point(
    f: &FixedToml,
    at: KeyPath,
    corners: &[[f64; 2]],
) -> Result<FixedPoint, SceneError> {
    let point_key = at.clone().key("point");
    let &[x, y] = &f.point[..] else {
        return Err(SceneError::value(
            point_key,
            format!(" must be a point [x, y]; got {} number(s)", f.point.len()),
        ));
    };
    if !corners.contains(&[x, y]) {
        let list: Vec<String> = corners
            .iter()
            .map(|c| format!("[{}, {}]", c[0], c[1]))
            .collect();
        return Err(SceneError::value(
            point_key,
            format!(
                " = [{x}, {y}] is not a corner of the domain (a vertex of every level's mesh): one of {}",
                list.join(", ")
            ),
        ));
    }
    let components_key = at.key("components");
    if f.components.is_empty() {
        return Err(SceneError::value(
            components_key,
            " is empty: list \"x\", \"y\" or both",
        ));
    }
    let mut held = [false; 2];
    for name in &f.components {
        let c = one_name::<Component>(&components_key.schema_path(), name).map_err(|_| {
            SceneError::value(
                components_key.clone(),
                format!(": unknown component {name:?} (expected x, y)"),
            )
        })?;
        let slot = &mut held[usize::from(c == Component::Y)];
        if *slot {
            return Err(SceneError::value(
                components_key,
                format!(": {name:?} is listed twice"),
            ));
        }
        *slot = true;
    }
    Ok(FixedPoint {
        point: [x, y],
        components: held,
    })
}

/// `[exact]` of an elastic scene: ux, uy; the stress all three or none (then Hooke's law of ∂u);
/// the crack quantities as given; one finite (K_I, K_II) per tip.
fn validate_exact(
    e: &ExactToml,
    material: &Material,
    at: &ElasticContext<'_>,
) -> Result<ElasticExact, SceneError> {
    let u = [
        required_expr(&e.ux, "exact", "ux")?,
        required_expr(&e.uy, "exact", "uy")?,
    ];
    let stress = match (&e.sxx, &e.syy, &e.sxy) {
        (None, None, None) => hooke_stress(&u, material).map_err(|e| {
            SceneError::value(
                key("exact.ux"),
                format!(": its Hooke stress cannot be derived ({e}): give exact.sxx, exact.syy and exact.sxy"),
            )
        })?,
        (Some(xx), Some(yy), Some(xy)) => [
            expr_at(key("exact.sxx"), xx)?,
            expr_at(key("exact.syy"), yy)?,
            expr_at(key("exact.sxy"), xy)?,
        ],
        (xx, yy, _) => {
            let absent = if xx.is_none() {
                "sxx"
            } else if yy.is_none() {
                "syy"
            } else {
                "sxy"
            };
            return Err(missing(
                "exact",
                absent,
                ": give the stress's three components sxx, syy, sxy, or none (then Hooke's law of u)",
            ));
        }
    };
    let optional = |text: &Option<String>, name: &str| {
        text.as_ref()
            .map(|t| expr_at(key("exact").key(name), t))
            .transpose()
    };
    Ok(ElasticExact {
        u,
        stress,
        opening: optional(&e.opening, "opening")?,
        slip: optional(&e.slip, "slip")?,
        pressure: optional(&e.pressure, "pressure")?,
        sif: validate_sif(e.sif.as_deref(), at)?,
    })
}

/// `exact.sif`: one pair of finite numbers per crack tip (crack ends not on ∂Ω), in the tips'
/// order.
fn validate_sif(
    sif: Option<&[Vec<f64>]>,
    at: &ElasticContext<'_>,
) -> Result<Vec<TipSif>, SceneError> {
    let Some(sif) = sif else {
        return Ok(Vec::new());
    };
    let polylines: Vec<Vec<[f64; 2]>> = at.cracks.iter().map(|c| c.points.clone()).collect();
    let tips = sdcrack_core::geometry::crack_tips(&at.domain.polygon(), &polylines).len();
    if sif.len() != tips {
        return Err(SceneError::value(
            key("exact.sif"),
            format!(
                " has {} pair(s) [K_I, K_II]; the cracks have {tips} tip(s) (crack ends inside the domain, each crack's first point then its last)",
                sif.len()
            ),
        ));
    }
    (sif.iter().enumerate())
        .map(|(i, pair)| match pair[..] {
            [k1, k2] if k1.is_finite() && k2.is_finite() => Ok(TipSif { k1, k2 }),
            _ => Err(SceneError::value(
                key("exact.sif").index(i),
                format!(" must be two finite numbers [K_I, K_II]; got {pair:?}"),
            )),
        })
        .collect()
}
