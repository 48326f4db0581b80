//! Edge cracks: a crack end on ∂Ω (a mouth) doubled like an interior crack node, on every way of
//! making the levels (the grid, uniform refinement, grading).

use std::collections::HashMap;

use super::*;
use crate::problem::{Grading, Polyline, USpace, UNIT_SQUARE};

/// The structured levels of (−1, 1)² with `cells`, cut by `cracks`.
fn grid(cells: [usize; 2], cracks: &[&[[f64; 2]]], level: u32) -> Mesh {
    let cracks: Vec<Polyline> = cracks
        .iter()
        .map(|c| Polyline { points: c.to_vec() })
        .collect();
    structured::structured(UNIT_SQUARE, cells, &cracks, level).expect("grid")
}

fn on_square_boundary(p: [f64; 2]) -> bool {
    p[0].abs() == 1.0 || p[1].abs() == 1.0
}

fn on_l_boundary(p: [f64; 2]) -> bool {
    crate::geometry::point_in_polygon(p, &crate::geometry::L_SHAPE)
        == crate::geometry::Inside::OnBoundary
}

/// The cracked mesh (the `broken` u numbering) is a conforming triangulation of Ω \ Γc: every
/// edge in at most two triangles, and its boundary — the edges of one triangle — is exactly the
/// boundary edges in cracked numbering ([`Mesh::boundary_edge_dofs`]) and both faces of every
/// crack edge. At a mouth this fails unless the mouth is cut through.
pub(super) fn assert_cracked_mesh_conforms(m: &Mesh) {
    let topo = m.u_topology(USpace::Broken);
    let key = |a: usize, b: usize| (a.min(b), a.max(b));
    let mut count: HashMap<(usize, usize), usize> = HashMap::new();
    for t in &topo.triangle_dofs {
        for k in 0..3 {
            *count.entry(key(t[k], t[(k + 1) % 3])).or_default() += 1;
        }
    }
    assert!(
        count.values().all(|&n| n <= 2),
        "an edge in three triangles"
    );
    let mut one: Vec<_> = count
        .iter()
        .filter(|(_, &n)| n == 1)
        .map(|(&e, _)| e)
        .collect();
    one.sort_unstable();
    let mut expected: Vec<_> = m
        .boundary_edge_dofs(&topo)
        .iter()
        .map(|&[a, b]| key(a, b))
        .collect();
    let mut row = 0;
    for c in &m.cracks {
        let pairs = &topo.crack_dofs[row..row + c.nodes.len()];
        for w in pairs.windows(2) {
            let (plus, minus) = (key(w[0].0, w[1].0), key(w[0].1, w[1].1));
            // an edge between two tips (a crack of one edge) is not cut
            if plus != minus {
                expected.extend([plus, minus]);
            }
        }
        row += c.nodes.len();
    }
    expected.sort_unstable();
    assert_eq!(one, expected, "the cracked mesh's boundary");
}

/// Every mouth's two copies sit on ∂Ω and the two boundary edges at the mouth take one copy each.
fn assert_mouths_doubled(m: &Mesh, expected_mouths: &[[bool; 2]]) {
    assert_mouths_doubled_on(m, expected_mouths, on_square_boundary);
}

fn assert_mouths_doubled_on(
    m: &Mesh,
    expected_mouths: &[[bool; 2]],
    on_boundary: fn([f64; 2]) -> bool,
) {
    let topo = m.u_topology(USpace::Broken);
    let found: Vec<[bool; 2]> = m.cracks.iter().map(|c| c.mouths).collect();
    assert_eq!(found, expected_mouths);
    let bdofs = m.boundary_edge_dofs(&topo);
    let mut row = 0;
    for c in &m.cracks {
        let last = c.nodes.len() - 1;
        for (end, j) in [(0, 0), (1, last)] {
            let (plus, minus) = topo.crack_dofs[row + j];
            let v = c.nodes[j];
            if !c.mouths[end] {
                assert_eq!(plus, minus, "a tip is not doubled");
                continue;
            }
            assert_ne!(plus, minus, "a mouth is doubled");
            assert_eq!((topo.dof_vertex[plus], topo.dof_vertex[minus]), (v, v));
            assert!(on_boundary(m.vertices[v]));
            let at: Vec<usize> = bdofs
                .iter()
                .flatten()
                .copied()
                .filter(|&d| d == plus || d == minus)
                .collect();
            assert_eq!(at.len(), 2, "two boundary edges at a mouth");
            assert!(
                at.contains(&plus) && at.contains(&minus),
                "one copy each: {at:?}"
            );
        }
        row += c.nodes.len();
    }
    assert_eq!(
        topo.n_dofs,
        m.vertices.len()
            + m.cracks
                .iter()
                .map(|c| c.doubled_nodes().count())
                .sum::<usize>()
    );
}

#[test]
fn a_grid_mouth_is_doubled_and_its_faces_split_the_boundary() {
    for level in 0..3 {
        let m = grid([4, 4], &[&[[-1.0, 0.0], [0.0, 0.0]]], level);
        assert_mouths_doubled(&m, &[[true, false]]);
        assert_cracked_mesh_conforms(&m);
        assert_eq!(
            m.tips(),
            vec![m.cracks[0].nodes[m.cracks[0].nodes.len() - 1]]
        );
        // the mouth's faces: + above y = 0 (ν = (0, 1)), − below, for corners and boundary edges
        let topo = m.u_topology(USpace::Broken);
        let (plus, minus) = topo.crack_dofs[0];
        for (t, (dofs, sides)) in m
            .triangles
            .iter()
            .zip(topo.triangle_dofs.iter().zip(&m.corner_sides))
        {
            let c = centroid(&m.vertices, t);
            for k in 0..3 {
                if t[k] == plus {
                    let (side, dof) = if c[1] > 0.0 {
                        (Side::Plus, plus)
                    } else {
                        (Side::Minus, minus)
                    };
                    assert_eq!((sides[k], dofs[k]), (Some(side), dof));
                }
            }
        }
        for (e, d) in m.boundary_edges.iter().zip(m.boundary_edge_dofs(&topo)) {
            if e.contains(&plus) {
                let other = m.vertices[if e[0] == plus { e[1] } else { e[0] }];
                let copy = if other[1] > 0.0 { plus } else { minus };
                assert!(d.contains(&copy), "{e:?} → {d:?}");
            } else {
                assert_eq!(*e, d, "away from the mouth the numbers are the uncut ones");
            }
        }
    }
}

#[test]
fn two_mouths_kinks_and_several_cracks_on_the_grid() {
    // a crack through the square (two mouths), a kinked one from the top side, an interior one
    let through: &[[f64; 2]] = &[[-1.0, -0.5], [1.0, -0.5]];
    let kinked: &[[f64; 2]] = &[[0.5, 1.0], [0.5, 0.5], [0.0, 0.0]];
    let inside: &[[f64; 2]] = &[[-0.5, 0.5], [-0.25, 0.5]];
    for level in 0..2 {
        let m = grid([8, 8], &[through, kinked, inside], level);
        assert_mouths_doubled(&m, &[[true, true], [true, false], [false, false]]);
        assert_cracked_mesh_conforms(&m);
        // the tips, in order: the kinked crack's last point, the interior crack's two
        let tips: Vec<[f64; 2]> = m.tips().iter().map(|&v| m.vertices[v]).collect();
        assert_eq!(tips, vec![[0.0, 0.0], [-0.5, 0.5], [-0.25, 0.5]]);
        let square = crate::problem::Domain::Rectangle(UNIT_SQUARE).polygon();
        let lines: Vec<Vec<[f64; 2]>> = [through, kinked, inside]
            .iter()
            .map(|c| c.to_vec())
            .collect();
        assert_eq!(crate::geometry::crack_tips(&square, &lines), tips);
    }
}

#[test]
fn refined_and_graded_levels_keep_the_mouth_doubled_and_nested() {
    let crack: &[[f64; 2]] = &[[-1.0, 0.0], [0.0, 0.0]];
    let coarse = grid([4, 4], &[crack], 0);
    let mut m = coarse.clone();
    for _ in 0..2 {
        let fine = refine::refine(&m);
        assert_mouths_doubled(&fine, &[[true, false]]);
        assert_cracked_mesh_conforms(&fine);
        assert_eq!(
            fine.cracks[0].nodes[0], m.cracks[0].nodes[0],
            "the mouth keeps its number"
        );
        m = fine;
    }
    let grading = Grading {
        beta: 0.4,
        radius: 0.25,
    };
    let levels = bisect::graded_levels(&coarse, grading, 2).expect("graded");
    for (l, m) in levels.iter().enumerate() {
        assert_mouths_doubled(m, &[[true, false]]);
        assert_cracked_mesh_conforms(m);
        if l > 0 {
            // nested: each triangle's centroid in its parent
            let prev = &levels[l - 1];
            for (t, &p) in m.triangles.iter().zip(&m.parents) {
                let c = centroid(&m.vertices, t);
                let [a, b, d] = prev.triangles[p].map(|v| prev.vertices[v]);
                let cross = |p: [f64; 2], q: [f64; 2]| {
                    (q[0] - p[0]) * (c[1] - p[1]) - (q[1] - p[1]) * (c[0] - p[0])
                };
                assert!(cross(a, b) >= 0.0 && cross(b, d) >= 0.0 && cross(d, a) >= 0.0);
            }
        }
    }
}

/// The smallest diameter of the triangles at vertex `v`.
fn smallest_at(m: &Mesh, v: usize) -> f64 {
    m.triangles
        .iter()
        .filter(|t| t.contains(&v))
        .map(|t| triangulation::diameter(&m.vertices, t))
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn grading_refines_towards_tips_never_towards_mouths() {
    let grading = Grading {
        beta: 0.4,
        radius: 0.5,
    };
    // the mouth (−1, 0) is 1 from the tip (0, 0), outside the graded zone R = 1/2
    let coarse = grid([8, 8], &[&[[-1.0, 0.0], [0.0, 0.0]]], 0);
    let uniform_h = triangulation::diameter(&coarse.vertices, &coarse.triangles[0]);
    let levels = bisect::graded_levels(&coarse, grading, 2).expect("graded");
    for (l, m) in levels.iter().enumerate() {
        let c = &m.cracks[0];
        let (mouth, tip) = (c.nodes[0], c.nodes[c.nodes.len() - 1]);
        let h = uniform_h / f64::from(1u32 << l);
        // at the mouth: the level's uniform size h exactly (no bisection beyond the uniform
        // two per level step); at the tip: graded below it (a bisection of a grid triangle
        // divides its diameter by √2, so ≤ h/2 is two grading bisections at least)
        assert_eq!(
            smallest_at(m, mouth),
            h,
            "level {l}: the mouth is not graded"
        );
        assert!(
            smallest_at(m, tip) <= 0.5 * h,
            "level {l}: tip {} vs h {h}",
            smallest_at(m, tip)
        );
    }
    // the same crack with its mouth made a tip (moved inside) is graded at that end too
    let inner = grid([8, 8], &[&[[-0.5, 0.0], [0.0, 0.0]]], 0);
    let levels = bisect::graded_levels(&inner, grading, 1).expect("graded");
    let m = &levels[1];
    let first = m.cracks[0].nodes[0];
    assert!(smallest_at(m, first) <= 0.5 * uniform_h / 2.0);
}

fn polylines(cracks: &[&[[f64; 2]]]) -> Vec<Polyline> {
    cracks
        .iter()
        .map(|c| Polyline { points: c.to_vec() })
        .collect()
}

#[test]
fn gmsh_levels_with_mouths_are_cut_through_refined_and_graded() {
    if gmsh::gmsh_version().is_err() {
        println!("skipping: gmsh is not installed");
        return;
    }
    let domain = crate::problem::Domain::Polygon(crate::geometry::L_SHAPE.to_vec());
    let cracks = polylines(&[
        &[[0.5, 0.0], [0.5, -0.5]],
        &[[-0.5, 1.0], [-0.5, 0.5], [0.0, 0.5]],
    ]);
    let mouths = [[true, false], [true, true]];
    let source =
        MeshSource::new(&domain, &cracks, &crate::problem::Meshing::MeshSize(0.4)).expect("gmsh");
    for level in 0..2 {
        let m = source.level(level).expect("level");
        assert_mouths_doubled_on(&m, &mouths, on_l_boundary);
        assert_cracked_mesh_conforms(&m);
    }
    let graded = source.graded(Some(Grading {
        beta: 0.4,
        radius: 0.25,
    }));
    let m = graded.level(1).expect("graded level");
    assert_mouths_doubled_on(&m, &mouths, on_l_boundary);
    assert_cracked_mesh_conforms(&m);
}

#[test]
fn a_mesh_file_with_a_mouth_is_read_only_when_asked() {
    // (−1, 1)² fanned around (0, 0), a boundary vertex at (−1, 0): crack1 from there to (0, 0)
    let text = "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n1 2 \"boundary\"\n\
        1 3 \"crack1\"\n2 1 \"domain\"\n$EndPhysicalNames\n$Nodes\n6\n1 -1 -1 0\n2 1 -1 0\n\
        3 1 1 0\n4 -1 1 0\n5 -1 0 0\n6 0 0 0\n$EndNodes\n$Elements\n11\n1 1 2 2 2 1 2\n\
        2 1 2 2 2 2 3\n3 1 2 2 2 3 4\n4 1 2 2 2 4 5\n5 1 2 2 2 5 1\n6 1 2 3 3 5 6\n\
        7 2 2 1 1 1 2 6\n8 2 2 1 1 2 3 6\n9 2 2 1 1 3 4 6\n10 2 2 1 1 4 5 6\n\
        11 2 2 1 1 5 1 6\n$EndElements\n";
    let dir = std::env::temp_dir().join(format!("sdcrack-mouth-msh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("mouth.msh");
    std::fs::write(&path, text).unwrap();
    let scalar = msh_file_geometry(&path).unwrap_err().to_string();
    assert!(
        scalar.contains("crack1 touches the boundary at vertex (-1, 0)"),
        "{scalar}"
    );
    let (domain, cracks, triangles) =
        msh_file_geometry_with(&path, crate::geometry::CrackEnds::MayBeMouths).expect("a mouth");
    assert_eq!(triangles, 5);
    assert_eq!(cracks[0].points, vec![[-1.0, 0.0], [0.0, 0.0]]);
    let meshing = crate::problem::Meshing::File(path.clone());
    let source = MeshSource::new(&domain, &cracks, &meshing).expect("levels");
    for level in 0..3 {
        let m = source.level(level).expect("level");
        assert_mouths_doubled(&m, &[[true, false]]);
        assert_cracked_mesh_conforms(&m);
    }
    // a crack ending at a corner of the file's boundary is refused by the geometry check:
    // (−1, −1) moved to (−1/2, −1) makes (−1, 0) a corner
    std::fs::write(&path, text.replace("1 -1 -1 0", "1 -0.5 -1 0")).unwrap();
    let corner = msh_file_geometry_with(&path, crate::geometry::CrackEnds::MayBeMouths);
    let _ = std::fs::remove_dir_all(&dir);
    let corner = corner.unwrap_err().to_string();
    assert!(corner.ends_with("mouth.msh: crack1 ends at a corner of the boundary (-1, 0): a crack may end on the boundary only away from its corners"), "{corner}");
}

/// The boundary parts cover ∂Ω: each boundary edge lies on the side of its part (both ends
/// within `tol` of it) and each part's edges add up to the side's length.
fn assert_parts_cover(m: &Mesh, parts: &BoundaryParts, sides: &[[[f64; 2]; 2]], tol: f64) {
    let of = parts.of_edges(m);
    assert_eq!(of.len(), m.boundary_edges.len());
    let mut length = vec![0.0; sides.len()];
    let dist = |p: [f64; 2], [a, b]: [[f64; 2]; 2]| {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        ((p[0] - a[0]) * dy - (p[1] - a[1]) * dx).abs() / dx.hypot(dy)
    };
    for (&[a, b], &k) in m.boundary_edges.iter().zip(&of) {
        let (p, q) = (m.vertices[a], m.vertices[b]);
        assert!(
            dist(p, sides[k]) <= tol && dist(q, sides[k]) <= tol,
            "{p:?}–{q:?} not on part {k}"
        );
        length[k] += (q[0] - p[0]).hypot(q[1] - p[1]);
    }
    for (k, s) in sides.iter().enumerate() {
        let side = (s[1][0] - s[0][0]).hypot(s[1][1] - s[0][1]);
        assert!(
            (length[k] - side).abs() <= 1e-12 * side,
            "part {k}: {} of {side}",
            length[k]
        );
    }
}

#[test]
fn boundary_parts_cover_the_rectangle_the_polygon_and_a_mesh_file() {
    let rect = crate::problem::Domain::Rectangle(UNIT_SQUARE);
    let parts = BoundaryParts::of(&rect, &crate::problem::Meshing::Cells([4, 4]));
    assert_eq!(parts.names(), ["left", "right", "bottom", "top"]);
    assert_eq!(parts.index("top"), Some(3));
    assert_eq!(parts.index("edge1"), None);
    let (lo, hi) = (-1.0, 1.0);
    let sides = [
        [[lo, lo], [lo, hi]],
        [[hi, lo], [hi, hi]],
        [[lo, lo], [hi, lo]],
        [[lo, hi], [hi, hi]],
    ];
    let coarse = grid([4, 4], &[&[[-1.0, 0.0], [0.0, 0.0]]], 0);
    let graded = bisect::graded_levels(
        &coarse,
        Grading {
            beta: 0.4,
            radius: 0.25,
        },
        1,
    )
    .expect("graded");
    for m in [coarse.clone(), refine::refine(&coarse), graded[1].clone()] {
        // the sides are exact: grid coordinates and midpoints of side edges
        assert_parts_cover(&m, &parts, &sides, 0.0);
    }
    let l_shape = crate::geometry::L_SHAPE.to_vec();
    let domain = crate::problem::Domain::Polygon(l_shape.clone());
    let parts = BoundaryParts::of(&domain, &crate::problem::Meshing::MeshSize(0.4));
    assert_eq!(parts.names().len(), 6);
    assert_eq!(parts.index("edge6"), Some(5));
    let file = BoundaryParts::of(&domain, &crate::problem::Meshing::File("m.msh".into()));
    assert_eq!(file.names(), ["boundary"]);
    if gmsh::gmsh_version().is_ok() {
        let cracks = polylines(&[&[[0.5, 0.0], [0.5, -0.5]]]);
        let source = MeshSource::new(&domain, &cracks, &crate::problem::Meshing::MeshSize(0.4))
            .expect("gmsh");
        let sides: Vec<[[f64; 2]; 2]> =
            (0..6).map(|k| [l_shape[k], l_shape[(k + 1) % 6]]).collect();
        for level in 0..2 {
            let m = source.level(level).expect("level");
            assert_parts_cover(&m, &parts, &sides, 1e-15);
            assert!(file.of_edges(&m).iter().all(|&k| k == 0));
        }
    }
}
