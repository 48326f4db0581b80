use super::*;
use crate::problem::{PSpace, Polyline, Segment, USpace, UNIT_SQUARE};

fn seg(a: [f64; 2], b: [f64; 2]) -> Segment {
    Segment { a, b }
}

/// The structured mesh of [`UNIT_SQUARE`] = (−1, 1)² with `cells` at level 0, cut by the one
/// straight crack from `a` to `b`, at `level`.
fn cut_square(cells: [usize; 2], a: [f64; 2], b: [f64; 2], level: u32) -> Result<Mesh, MeshError> {
    structured::structured(UNIT_SQUARE, cells, &[seg(a, b).into()], level)
}

#[test]
fn counts_and_nesting() {
    let m = cut_square([4, 2], [-0.5, 0.0], [0.5, 0.0], 2).unwrap();
    assert_eq!(m.layout, Layout::Structured { nx: 16, ny: 8 });
    assert_eq!(m.vertices.len(), 17 * 9);
    assert_eq!(m.triangles.len(), 2 * 16 * 8);
    assert_eq!(m.boundary_edges.len(), 2 * (16 + 8));
    assert_eq!(m.cracks[0].nodes.len(), 9);
    // every triangle counter-clockwise with the cell area / 2
    for t in &m.triangles {
        let [a, b, c] = t.map(|v| m.vertices[v]);
        let area = 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]));
        assert!((area - 0.5 * (2.0 / 16.0) * (2.0 / 8.0)).abs() < 1e-14);
    }
    // crack nodes exactly on y = 0 with positive zero
    for &v in &m.cracks[0].nodes {
        assert_eq!(m.vertices[v][1].to_bits(), 0.0f64.to_bits());
    }
}

#[test]
fn sides_and_broken_topology() {
    let m = cut_square([4, 4], [-0.5, 0.0], [0.5, 0.0], 1).unwrap();
    assert_eq!(m.cracks[0].normals[0], [0.0, 1.0]);
    let topo = m.u_topology(USpace::Broken);
    let interior = m.cracks[0].nodes.len() - 2;
    assert_eq!(topo.n_dofs, m.vertices.len() + interior);
    for (t, (dofs, sides)) in m
        .triangles
        .iter()
        .zip(topo.triangle_dofs.iter().zip(&m.corner_sides))
    {
        let c = centroid(&m.vertices, t);
        for side in sides {
            match side {
                Some(Side::Minus) => assert!(c[1] < 0.0),
                Some(Side::Plus) => assert!(c[1] > 0.0),
                None => {}
            }
        }
        if sides.iter().all(Option::is_none) {
            assert_eq!(dofs, t);
        }
        if c[1] > 0.0 {
            assert_eq!(dofs, t, "+ side keeps vertex numbers");
        }
    }
    let (p, q) = topo.crack_dofs[0];
    assert_eq!(p, q, "tips are not duplicated");
    let (p, q) = topo.crack_dofs[2];
    assert_ne!(p, q);
    let cont = m.u_topology(USpace::Continuous);
    assert_eq!(cont.n_dofs, m.vertices.len());
}

/// The broken-tangential p doubles exactly the interior nodes with one normal
/// (not the tips, not the kink) and stays in H(div, Ω): for any values of the unknowns, at
/// every crack node the + and − faces' corners give the same p·ν, bit for bit up to one
/// rounding, while at a doubled node their p·τ are the two independent unknowns; at tips and
/// at the kink both faces see the same p.
#[test]
fn broken_tangential_p_keeps_the_normal_component_shared() {
    let kinked = Polyline {
        points: vec![[-0.5, 0.0], [0.0, 0.0], [0.5, 0.5]],
    };
    let m = structured::structured(UNIT_SQUARE, [4, 4], &[kinked], 1).unwrap();
    let chain = &m.cracks[0];
    let kink = chain.nodes[2];
    assert_ne!(chain.normals[1], chain.normals[2], "node 2 is the kink");
    let p = m.p_topology(PSpace::BrokenTangential);
    let interior = chain.nodes.len() - 2;
    assert_eq!(
        p.doubled.len(),
        interior - 1,
        "every interior node but the kink"
    );
    assert_eq!(p.n_dofs, 2 * m.vertices.len() + interior - 1);
    assert!(p.doubled.iter().all(|&(v, _)| v != kink));
    let continuous = m.p_topology(PSpace::Continuous);
    assert_eq!(continuous.n_dofs, 2 * m.vertices.len());
    // arbitrary unknowns, no two alike
    let values: Vec<f64> = (0..p.n_dofs)
        .map(|i| ((i * 7919) % 1013) as f64 / 101.0 - 5.0)
        .collect();
    for (j, &v) in chain.nodes.iter().enumerate() {
        let normals: Vec<[f64; 2]> = [j.checked_sub(1), (j < interior + 1).then_some(j)]
            .into_iter()
            .flatten()
            .map(|k| chain.normals[k])
            .collect();
        let mut seen: Vec<(Side, [f64; 2])> = Vec::new();
        for (t, tri) in m.triangles.iter().enumerate() {
            for k in 0..3 {
                if tri[k] == v {
                    let side = m.corner_sides[t][k].unwrap_or(Side::Plus);
                    seen.push((side, p.corner(&m, t, k).value(&values)));
                }
            }
        }
        let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
        let plus: Vec<_> = seen.iter().filter(|s| s.0 == Side::Plus).collect();
        let minus: Vec<_> = seen.iter().filter(|s| s.0 == Side::Minus).collect();
        for a in &plus {
            for b in plus.iter().chain(&minus) {
                for &nu in &normals {
                    let (x, y) = (dot(a.1, nu), dot(b.1, nu));
                    assert!(
                        (x - y).abs() <= 1e-15 * x.abs().max(1.0),
                        "node {j}: {x} vs {y}"
                    );
                }
            }
        }
        let doubled = p.doubled.iter().any(|&(w, _)| w == v);
        let differ = plus.iter().any(|a| minus.iter().any(|b| a.1 != b.1));
        assert_eq!(differ, doubled, "node {j}: the faces differ iff doubled");
    }
}

#[test]
fn crack_directions() {
    // vertical crack: ν = (-1, 0)
    let m = cut_square([4, 4], [0.0, -0.5], [0.0, 0.5], 0).unwrap();
    assert_eq!(m.cracks[0].nodes.len(), 3);
    assert!((m.cracks[0].normals[0][0] + 1.0).abs() < 1e-15);
    // diagonal crack
    let m = cut_square([4, 4], [-0.5, -0.5], [0.5, 0.5], 1).unwrap();
    assert_eq!(m.cracks[0].nodes.len(), 5);
}

#[test]
fn crack_errors() {
    let e = cut_square([4, 4], [-0.4, 0.0], [0.5, 0.0], 0).unwrap_err();
    assert!(matches!(e, MeshError::OffMesh { .. }));
    let e = cut_square([4, 4], [-0.5, 0.0], [1.5, 0.0], 0).unwrap_err();
    assert!(matches!(
        e,
        MeshError::NotInside {
            what: "lies outside the domain",
            ..
        }
    ));
    // a crack end may lie on a side (a mouth), not at a corner, and no other point on ∂Ω
    assert!(cut_square([4, 4], [-1.0, 0.0], [0.5, 0.0], 0).is_ok());
    for (a, b) in [([-1.0, -1.0], [0.0, 0.0]), ([0.5, 0.5], [1.0, 1.0])] {
        let e = cut_square([4, 4], a, b, 0).unwrap_err();
        assert!(matches!(
            e,
            MeshError::NotInside {
                what: "touches the boundary",
                ..
            }
        ));
    }
    let through = Polyline {
        points: vec![[0.0, 0.5], [1.0, 0.5], [0.5, 0.0]],
    };
    let e = structured::structured(UNIT_SQUARE, [4, 4], &[through], 0).unwrap_err();
    assert!(matches!(
        e,
        MeshError::NotInside {
            what: "touches the boundary",
            ..
        }
    ));
    let e = cut_square([4, 4], [-0.5, 0.0], [0.5, 0.5], 0).unwrap_err();
    assert!(matches!(e, MeshError::NotOnMeshLine { .. }));
    // NW-SE diagonal is not a mesh line
    let e = cut_square([4, 4], [-0.5, 0.5], [0.5, -0.5], 0).unwrap_err();
    assert!(matches!(e, MeshError::NotOnMeshLine { .. }));
}
