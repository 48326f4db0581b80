//! Polygonal domains, polyline and multiple cracks, gmsh meshes refined uniformly:
//! observed rates against exact closed-crack solutions on unstructured levels, the structured
//! special cases reproduced bit for bit, and the mesh export of several cracks.

mod common;

use common::orders::Orders;
use common::{error_series, rate, solve};
use sdcrack_core::case::CasePattern;
use sdcrack_core::mesh::{Layout, Side};
use sdcrack_core::problem::{Meshing, MultiplierSpace, PMass, PSpace, Polyline, USpace};
use sdcrack_core::scene::Scene;

/// The repository scene `name` at levels 0–3, δ = 0, consistent p mass, no fields.
fn exact_scene(name: &str) -> Scene {
    let mut scene = common::load(name);
    scene.axes.levels = vec![0, 1, 2, 3];
    scene.axes.deltas = vec![0.0];
    scene.axes.p_masses = vec![PMass::Consistent];
    scene.axes.p_spaces = vec![PSpace::Continuous];
    scene.fields = Default::default();
    scene
}

/// P1 theory on a closed crack (smooth u, [u] = 0): ‖u − u_h‖ = O(h²), ‖∇u − p_h‖ = O(h), for
/// both u spaces and every multiplier, λ_h = [u] = 0 exactly. The rates are asserted on the
/// last two of four unstructured levels: u above P1's order less the margin, p above the stricter
/// measured bound of scenes/orders.toml's [regression].
#[test]
fn closed_kinked_and_double_cracks_converge_at_the_p1_rates() {
    let o = Orders::repository();
    let s = o.regularity.smooth_s;
    let u_min = o.lowest_rate(o.p1_u(s));
    let p_min = o
        .lowest_rate(o.p1_p(s))
        .max(o.regression.gmsh_closed_p_rate);
    for name in ["kinked-exact", "two-cracks-exact"] {
        let scene = exact_scene(name);
        assert!(matches!(scene.meshing, Meshing::MeshSize(_)));
        let cases = solve(&scene, CasePattern::default());
        assert!(cases.iter().all(|c| c.converged), "{name}: all converge");
        for u in [USpace::Continuous, USpace::Broken] {
            for m in MultiplierSpace::ALL {
                let s = error_series(&cases, u, m);
                assert_eq!(s.len(), 4);
                let (a, b) = (s[2], s[3]);
                let ru = rate(a.0, a.1, b.0, b.1);
                let rp = rate(a.0, a.2, b.0, b.2);
                assert!(ru > u_min, "{name} {u} {m}: u rate {ru}");
                assert!(rp > p_min, "{name} {u} {m}: p rate {rp}");
                assert!(b.3 == 0.0, "{name} {u} {m}: λ_h = [u] = 0, got {}", b.3);
                // h halves exactly under uniform refinement
                assert!(
                    (a.0 / b.0 - 2.0).abs() < 1e-12,
                    "{name}: h {} → {}",
                    a.0,
                    b.0
                );
            }
        }
    }
}

/// A crack given as a polyline through a point of its own segment is the same crack: on the
/// structured grid every number of every case is identical to the single segment's.
#[test]
fn a_straight_polyline_is_the_segment_bit_for_bit() {
    let mut segment = common::load("mixed");
    segment.axes.levels = vec![0, 1, 2];
    segment.fields = Default::default();
    let mut polyline = segment.clone();
    polyline.cracks = vec![Polyline {
        points: vec![[-0.5, 0.0], [0.0, 0.0], [0.5, 0.0]],
    }];
    let a = solve(&segment, CasePattern::default());
    let b = solve(&polyline, CasePattern::default());
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(format!("{:?}", x.kkt), format!("{:?}", y.kkt));
        assert_eq!(x.iterations, y.iterations);
        assert_eq!(x.active, y.active);
        assert_eq!(x.unknowns, y.unknowns);
    }
}

/// The gmsh levels are nested (triangle 4t + c of level ℓ + 1 inside triangle t of level ℓ) and
/// every crack edge carries the normal of its polyline segment; triangle corners at a kink take
/// the face of the wedge they lie in.
#[test]
fn gmsh_levels_are_nested_with_segment_normals_and_faces() {
    let scene = common::load("kinked-exact");
    let source = scene.mesh_source().expect("gmsh meshes the scene");
    let provenance = source.provenance.clone().expect("gmsh ran");
    assert!(provenance.gmsh_version.unwrap().starts_with('4'));
    let m0 = source.level(0).unwrap();
    let m1 = source.level(1).unwrap();
    assert!(
        matches!(m1.layout, Layout::Refined { coarse_triangles } if coarse_triangles == m0.triangles.len())
    );
    assert_eq!(m1.triangles.len(), 4 * m0.triangles.len());
    for (t, parent) in m0.triangles.iter().enumerate() {
        let [a, b, c] = parent.map(|v| m0.vertices[v]);
        for child in &m1.triangles[4 * t..4 * t + 4] {
            let g = sdcrack_core::mesh::centroid(&m1.vertices, child);
            let edge = |p: [f64; 2], q: [f64; 2]| {
                (q[0] - p[0]) * (g[1] - p[1]) - (q[1] - p[1]) * (g[0] - p[0])
            };
            assert!(edge(a, b) > 0.0 && edge(b, c) > 0.0 && edge(c, a) > 0.0);
        }
    }
    let crack = &scene.cracks[0];
    let chain = &m1.cracks[0];
    assert_eq!(m1.vertices[chain.nodes[0]], crack.points[0]);
    assert_eq!(m1.vertices[*chain.nodes.last().unwrap()], crack.points[2]);
    let kink = chain
        .nodes
        .iter()
        .position(|&v| m1.vertices[v] == crack.points[1])
        .expect("the kink is a mesh vertex");
    for (k, nu) in chain.normals.iter().enumerate() {
        let segment = if k < kink { 0 } else { 1 };
        assert_eq!(*nu, crack.segment(segment).normal(), "edge {k}");
    }
    // at the kink (0, −0.2): + is the wedge left of (−0.6, −0.2) → (0, −0.2) → (0.5, 0.3),
    // i.e. above y = −0.2 and above the line y = x − 0.2
    let v = chain.nodes[kink];
    let mut seen = [false; 2];
    for (t, sides) in m1.triangles.iter().zip(&m1.corner_sides) {
        if let Some(k) = t.iter().position(|&w| w == v) {
            let g = sdcrack_core::mesh::centroid(&m1.vertices, t);
            let left = g[1] > -0.2 && g[1] > g[0] - 0.2;
            assert_eq!(sides[k] == Some(Side::Plus), left, "triangle {t:?}");
            seen[usize::from(left)] = true;
        }
    }
    assert_eq!(seen, [true, true], "both faces meet at the kink");
}

/// `sdcrack mesh` on two cracks: crack.txt holds both chains (tips plus = minus), cracks.txt
/// their row ranges, crack_normals.txt a unit normal per row, sides.txt three faces per triangle.
#[test]
fn the_export_of_two_cracks_lists_both_chains() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m");
    let o = common::sdcrack(&[
        "mesh",
        common::scene_path("two-cracks-exact").to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--level",
        "1",
    ]);
    assert!(o.status.success(), "{}", common::stderr(&o));
    let read = |f: &str| std::fs::read_to_string(out.join("level1").join(f)).unwrap();
    let rows: Vec<Vec<usize>> = read("crack.txt")
        .lines()
        .map(|l| l.split(' ').map(|t| t.parse().unwrap()).collect())
        .collect();
    let ranges: Vec<Vec<usize>> = read("cracks.txt")
        .lines()
        .map(|l| l.split(' ').map(|t| t.parse().unwrap()).collect())
        .collect();
    assert_eq!(ranges.len(), 2);
    assert_eq!(ranges[0][0], 0);
    assert_eq!(ranges[1][0], ranges[0][1]);
    assert_eq!(ranges[1][0] + ranges[1][1], rows.len());
    for r in &ranges {
        let (first, last) = (r[0], r[0] + r[1] - 1);
        assert_eq!(rows[first][0], rows[first][1], "tip");
        assert_eq!(rows[last][0], rows[last][1], "tip");
        assert!(rows[first + 1..last].iter().all(|p| p[0] != p[1]));
    }
    let normals: Vec<Vec<f64>> = read("crack_normals.txt")
        .lines()
        .map(|l| l.split(' ').map(|t| t.parse().unwrap()).collect())
        .collect();
    assert_eq!(normals.len(), rows.len());
    assert!(normals
        .iter()
        .all(|n| (n[0].hypot(n[1]) - 1.0).abs() < 1e-15));
    let sides = read("sides.txt");
    let triangles = read("triangles.txt");
    assert_eq!(sides.lines().count(), triangles.lines().count());
    assert!(sides.lines().all(|l| l.split(' ').count() == 3));
    let meta: serde_json::Value = serde_json::from_str(&read("mesh.json")).unwrap();
    assert_eq!(meta["kind"], "refined");
    assert_eq!(meta["n_cracks"], 2);
    assert!(meta["nx"].is_null());
}

/// scenes/open-kink.toml, an open right-angled kink with [u] = 1 at the kink node: M1star's λ_h
/// there is within 1 % of [u] at level 3 with the broken-tangential p, as M1's, and its L² order is
/// P1's (docs/design.md, Multipliers and the LCP: the kink row splits the moment ∫ λ_h φ in the
/// edges' shares; normalised to a unit normal it read 0.49 of [u] and converged at order 1/2).
#[test]
fn m1star_lambda_at_an_open_kink_is_the_jump() {
    use sdcrack_core::multiplier::CrackField;
    use sdcrack_core::study::{run_study, CasePlan, Silent};
    let mut scene = common::load("open-kink");
    scene.axes.levels = vec![0, 1, 2, 3];
    scene.axes.p_masses = vec![PMass::Consistent];
    scene.axes.p_spaces = vec![PSpace::BrokenTangential];
    scene.axes.multipliers = vec![MultiplierSpace::M1, MultiplierSpace::M1Star];
    let plan = CasePlan::new(&scene, &CasePattern::default());
    let study = run_study(&scene, &plan, &mut Silent).expect("study runs");
    let finest = study
        .meshes
        .iter()
        .find(|m| m.key.level == 3)
        .expect("level 3");
    let kink = finest
        .crack_points
        .iter()
        .position(|p| *p == [0.0, 0.0])
        .expect("the kink is a crack node");
    let o = Orders::repository();
    for m in [MultiplierSpace::M1, MultiplierSpace::M1Star] {
        let cases: Vec<_> = study
            .cases
            .iter()
            .filter(|c| c.key.multiplier == m)
            .collect();
        assert!(cases.iter().all(|c| c.converged), "{m}: all converge");
        let last = cases.iter().find(|c| c.key.level == 3).expect("level 3");
        let lambda = match &last.fields.as_ref().expect("fields kept").lambda {
            CrackField::PerNode(v) => v[kink],
            CrackField::PerSegment(_) => panic!("{m} is nodal"),
        };
        assert!((lambda - 1.0).abs() < 0.01, "{m}: λ_h at the kink {lambda}");
        let s: Vec<(f64, f64)> = cases
            .iter()
            .map(|c| (c.h, c.errors.expect("exact").lambda_l2))
            .collect();
        for w in s[1..].windows(2) {
            let r = rate(w[0].0, w[0].1, w[1].0, w[1].1);
            // [u] is smooth on the crack: P1 multipliers approximate it at P1's L² order
            assert!(
                r > o.lowest_rate(o.p1_u(o.regularity.smooth_s)),
                "{m}: λ rate {r}"
            );
        }
    }
}
