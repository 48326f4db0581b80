//! Test support of the AFW stages after the solve: synthetic [`AfwSolution`]s built from exact
//! fields (their interpolants, cell means and edge moments), so that the recovery and the norms
//! are tested without the solver, and the meshes they live on.

use super::norms::{exact_opening, exact_slip};
use super::solution::{AfwSolution, CrackEdge};
use crate::contact::{KktResiduals, LcpStatus};
use crate::elasticity::ElasticExact;
use crate::expr::{Expr, Var};
use crate::fe::p1::TriangleGeometry;
use crate::fe::quadrature::{gauss_legendre, physical_points, triangle_rule, REFERENCE_TRIANGLE};
use crate::mesh::Mesh;
use crate::problem::{eval_on_face, MultiplierSpace, Polyline, Rectangle};

/// Level `level` of the structured mesh of (−1, 1)² with `cells` level-0 cells per direction
/// and the cracks `cracks`.
pub(crate) fn square_mesh(cells: usize, level: u32, cracks: &[Polyline]) -> Mesh {
    let square = Rectangle {
        min: [-1.0, -1.0],
        max: [1.0, 1.0],
    };
    crate::mesh::structured::structured(square, [cells, cells], cracks, level).unwrap()
}

/// The edge crack y = 0, x ≤ 0 of (−1, 1)² (mouth at (−1, 0), tip at the origin).
pub(crate) fn edge_crack() -> Polyline {
    Polyline {
        points: vec![[-1.0, 0.0], [0.0, 0.0]],
    }
}

/// The vertex `x` of a triangle of centroid `c`, as seen from inside the triangle: each
/// coordinate that is exactly zero gets the sign of the centroid's offset (the signed-zero rule
/// of [`crate::problem::eval_on_face`] for the triangle's face of a crack on an axis).
pub(crate) fn seen_from(x: [f64; 2], c: [f64; 2]) -> [f64; 2] {
    let mut q = x;
    for d in 0..2 {
        if q[d] == 0.0 {
            q[d] = 0.0f64.copysign(c[d] - x[d]);
        }
    }
    q
}

/// γ = ½(∂_y u_x − ∂_x u_y) of `exact`'s u.
pub(crate) fn rotation_of(exact: &ElasticExact) -> Expr {
    let (a, b) = (
        exact.u[0].derivative(Var::Y).to_string_infix(),
        exact.u[1].derivative(Var::X).to_string_infix(),
    );
    Expr::parse(&format!("0.5*(({a}) - ({b}))")).unwrap()
}

/// The mean of `f` over triangle `geo` by the degree-20 Gauss rule (exact for polynomials of
/// degree ≤ 20; independent of the norms' rule).
pub(crate) fn cell_mean(geo: &TriangleGeometry, f: impl Fn([f64; 2]) -> f64) -> f64 {
    let points = physical_points(&triangle_rule(20), geo.vertices, REFERENCE_TRIANGLE);
    points.iter().map(|q| q.weight * f(q.x)).sum::<f64>() / geo.area
}

/// The hat moments (∫_e g φ_a, ∫_e g φ_b) of `g` on the edge a → b, by 12 Gauss points (exact
/// for polynomials of degree ≤ 22 along the edge).
pub(crate) fn hat_moments(a: [f64; 2], b: [f64; 2], g: impl Fn([f64; 2]) -> f64) -> [f64; 2] {
    let rule = gauss_legendre(12);
    let len = (b[0] - a[0]).hypot(b[1] - a[1]);
    let mut m = [0.0; 2];
    for (&s, &w) in rule.points.iter().zip(&rule.weights) {
        let x = [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])];
        let v = w * len * g(x);
        m[0] += (1.0 - s) * v;
        m[1] += s * v;
    }
    m
}

/// The synthetic solution of `exact` on `mesh`: σ_h the interpolant of the exact stress at each
/// triangle's vertices (seen from inside it), u_h and γ_h the cell means of u and γ, on each crack
/// edge σ_νν at its ends (+ face) and the hat moments of the exact opening and slip.
pub(crate) fn interpolant(
    mesh: &Mesh,
    exact: &ElasticExact,
    multiplier: MultiplierSpace,
) -> AfwSolution {
    let gamma = rotation_of(exact);
    let mut stress = Vec::new();
    let mut displacement = Vec::new();
    let mut rotation = Vec::new();
    for t in &mesh.triangles {
        let geo = TriangleGeometry::new(t.map(|v| mesh.vertices[v]));
        let [p, q, r] = geo.vertices;
        let c = [(p[0] + q[0] + r[0]) / 3.0, (p[1] + q[1] + r[1]) / 3.0];
        stress.push(geo.vertices.map(|x| {
            let y = seen_from(x, c);
            let [xx, yy, xy] = exact.stress.each_ref().map(|e| e.eval(y[0], y[1]));
            [xx, xy, xy, yy]
        }));
        displacement.push([0, 1].map(|i| cell_mean(&geo, |x| exact.u[i].eval(x[0], x[1]))));
        rotation.push(cell_mean(&geo, |x| gamma.eval(x[0], x[1])));
    }
    let mut crack = Vec::new();
    for (ci, chain) in mesh.cracks.iter().enumerate() {
        for k in 0..chain.segments() {
            let nodes = [chain.nodes[k], chain.nodes[k + 1]];
            let [a, b] = nodes.map(|v| mesh.vertices[v]);
            let nu = chain.normals[k];
            let snn = |x: [f64; 2]| {
                let s = exact.stress.each_ref().map(|e| eval_on_face(e, x, nu, 1.0));
                nu[0] * nu[0] * s[0] + nu[1] * nu[1] * s[1] + 2.0 * nu[0] * nu[1] * s[2]
            };
            crack.push(CrackEdge {
                crack: ci,
                segment: k,
                nodes,
                normal: nu,
                normal_stress: [snn(a), snn(b)],
                opening_moment: hat_moments(a, b, |x| exact_opening(exact, x, nu)),
                slip_moment: hat_moments(a, b, |x| exact_slip(exact, x, nu)),
                closed: [false; 2],
            });
        }
    }
    AfwSolution {
        unknowns: 0,
        stress,
        displacement,
        rotation,
        crack,
        multiplier,
        delta: 0.0,
        lcp_iterations: 0,
        lcp_status: LcpStatus::Converged,
        kkt: KktResiduals {
            equations: 0.0,
            primal: 0.0,
            dual: 0.0,
            complementarity: 0.0,
        },
    }
}
