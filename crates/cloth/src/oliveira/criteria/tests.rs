//! One test per criterion of spec §6.2–§6.4 on meshes small enough that the answer can be stated by
//! hand. Each test checks both sides of its threshold, so that a criterion that is dropped, inverted or
//! given another constant fails it.

use std::collections::BTreeMap;

use anima_geom::remesh::AdaptiveMesh;
use anima_geom::{DVec3, DiagonalPattern, HalfSpace, MaterialMesh, Solid};
use glam::DQuat;

use super::*;
use crate::oliveira::contact::Collider;

/// An `n × n`-vertex grid over [0, size]², flat at z = 0 and at rest; vertex (row, col) is `row·n + col`
/// and square (row, col) holds faces `2(row·(n − 1) + col)` = [p, p + 1, p + n + 1] and the next one
/// = [p, p + n + 1, p + n].
fn sheet(n: usize, size: f64) -> AdaptiveMesh {
    let m = MaterialMesh::grid(n, size, DiagonalPattern::Uniform).unwrap();
    let x = m.place(DVec3::ZERO, DVec3::X, DVec3::Y);
    let v = vec![DVec3::ZERO; x.len()];
    AdaptiveMesh::from_material(&m, x, v)
}

/// The unit square as two triangles, A = [0, 1, 3] and B = [0, 3, 2], with vertex 2 turned about the
/// diagonal 0–3 by `angle`: the dihedral angle between A and B is `angle`, so the vertex normals of 0 and
/// 3 (the mean of both faces) are `angle`/2 away from those of 1 and 2.
fn folded_square(size: f64, angle: f64) -> AdaptiveMesh {
    let mut m = sheet(2, size);
    let axis = DVec3::new(1.0, 1.0, 0.0).normalize();
    let x2 = DQuat::from_axis_angle(axis, angle) * m.positions()[2];
    m.positions_mut()[2] = x2;
    m
}

fn key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

fn sorted(mut keys: Vec<(u32, u32)>) -> Vec<(u32, u32)> {
    keys.sort_unstable();
    keys
}

/// Test III's parameters (Table 5.5) with simplification off, so that only refinement is looked at.
fn refine_only() -> OliveiraRemeshing {
    OliveiraRemeshing { simplify: false, ..OliveiraRemeshing::test_3() }
}

fn select(mesh: &AdaptiveMesh, colliders: &[Collider], p: &OliveiraRemeshing) -> Selection {
    select_edges(mesh, colliders, &BTreeMap::new(), 0.0, p)
}

#[test]
fn compression_selects_the_edge_shorter_than_seventy_percent_of_its_rest_length() {
    // Vertex 3 pulled along the diagonal: |x0 − x3| / L⁰ = s, while the sides 1–3 and 2–3 keep
    // √((1 − s)² + s²)/1 of their rest length (≥ 0.71 for s ≤ 0.7).
    for (s, picked) in [(0.65, true), (0.69, true), (0.71, false), (0.9, false)] {
        let mut m = sheet(2, 1.0);
        m.positions_mut()[3] = DVec3::new(s, s, 0.0);
        let sel = select(&m, &[], &refine_only());
        if picked {
            assert_eq!(sel.refine, vec![key(0, 3)], "s = {s}");
            assert_eq!(sel.by_criterion, [1, 0, 0], "s = {s}");
        } else {
            assert!(sel.refine.is_empty(), "s = {s}: {sel:?}");
        }
    }
    // The guard of A-25: an edge with L⁰ < L⁰_min is never refined, however compressed.
    let mut m = sheet(2, 0.05);
    m.positions_mut()[3] = DVec3::splat(0.01).with_z(0.0);
    assert!(select(&m, &[], &refine_only()).refine.is_empty());
}

#[test]
fn curvature_refines_edges_whose_vertex_normals_differ_by_more_than_the_limit() {
    // Folded by 40°, the sides are 20° apart at their ends: cos 20° = 0.940 < 0.97. Folded by 20°, they
    // are 10° apart: cos 10° = 0.985 > 0.97. The diagonal's ends share one normal.
    let p = OliveiraRemeshing { smoothing_ratio: 0.5, ..refine_only() };
    let sides = vec![key(0, 1), key(0, 2), key(1, 3), key(2, 3)];
    let sel = select(&folded_square(1.0, 40f64.to_radians()), &[], &p);
    assert_eq!(sorted(sel.refine), sides);
    assert_eq!(sel.by_criterion, [0, 0, 4]);
    let sel = select(&folded_square(1.0, 20f64.to_radians()), &[], &p);
    assert!(sel.refine.is_empty(), "{sel:?}");
}

#[test]
fn curvature_limit_rises_as_the_faces_shrink() {
    // Spec §6.2.3: cos θ^eff = 0.97 · min(1, Ā/A⁰_max). Test III's A⁰_max = (√3/4)·0.25² =
    // 0.02706 m². A square of side 1 (Ā = 0.5) keeps 0.97; one of side 0.2 (Ā = 0.02, ratio 0.739) asks
    // for cos < 0.717 (44°), so the 40° fold (20° between normals) is refined on the large square only.
    let p = OliveiraRemeshing { smoothing_ratio: 0.5, ..refine_only() };
    assert_eq!(select(&folded_square(1.0, 40f64.to_radians()), &[], &p).refine.len(), 4);
    assert!(select(&folded_square(0.2, 40f64.to_radians()), &[], &p).refine.is_empty());
    // A 100° fold (50° between normals, cos 0.643 < 0.717) is refined on the small square too.
    assert_eq!(select(&folded_square(0.2, 100f64.to_radians()), &[], &p).refine.len(), 4);
}

#[test]
fn literal_curvature_limit_refines_flat_faces_larger_than_the_maximum_area() {
    // Literal: cos θ^eff = 0.97 · Ā/A⁰_max, unclamped. On the flat unit square Ā/A⁰_max = 18.5, so the
    // limit is above 1 and every edge is refined although nothing is bent; clamped, none is. On a square
    // of side 0.2 (ratio 0.739) both readings agree: flat is not refined.
    let literal = OliveiraRemeshing { curvature_limit: CurvatureLimit::Literal, ..refine_only() };
    let clamped = refine_only();
    let flat = sheet(2, 1.0);
    let sel = select(&flat, &[], &literal);
    assert_eq!(sel.refine.len(), 5);
    assert_eq!(sel.by_criterion, [0, 0, 5]);
    assert!(select(&flat, &[], &clamped).refine.is_empty());
    assert!(select(&sheet(2, 0.2), &[], &literal).refine.is_empty());
}

/// A floor at z = 0.
fn floor() -> Vec<Collider> {
    vec![Collider {
        name: "floor".into(),
        solid: Solid::HalfSpace(HalfSpace { point: DVec3::ZERO, normal: DVec3::Z }),
        friction: 0.0,
    }]
}

/// The unit square turned rigidly by `tilt` about the line x = 0.5, z = 0: the side x = 1 is below the
/// floor, and the edges 0–1, 2–3 and 0–3 cross it.
fn tilted_square(tilt: f64) -> AdaptiveMesh {
    let mut m = sheet(2, 1.0);
    let r = DQuat::from_rotation_y(tilt);
    for x in m.positions_mut() {
        *x = r * (*x - DVec3::new(0.5, 0.0, 0.0));
    }
    m
}

#[test]
fn collision_refines_crossing_edges_unless_the_cloth_lies_parallel_to_the_object() {
    // The angle guard (spec §6.2.2, Q-6): refine when |n̂_cloth · n̂_obj| < 0.97, i.e. when the cloth is
    // tilted more than 14.07° from the surface.
    let crossing = vec![key(0, 1), key(0, 3), key(2, 3)];
    let sel = select(&tilted_square(30f64.to_radians()), &floor(), &refine_only());
    assert_eq!(sorted(sel.refine), crossing);
    assert_eq!(sel.by_criterion, [0, 3, 0]);
    let sel = select(&tilted_square(10f64.to_radians()), &floor(), &refine_only());
    assert!(sel.refine.is_empty(), "a cloth 10° off the floor passes the guard: {sel:?}");
    // Without the object nothing is picked: it is the collision that selects.
    assert!(select(&tilted_square(30f64.to_radians()), &[], &refine_only()).refine.is_empty());
    // Crossing edges that may no longer be refined are listed for the repulsion of A-24.
    let p = OliveiraRemeshing { min_rest_length: 2.0, ..refine_only() };
    let sel = select(&tilted_square(30f64.to_radians()), &floor(), &p);
    assert!(sel.refine.is_empty());
    assert_eq!(sorted(sel.colliding_unrefinable), crossing);
}

#[test]
fn smoothing_adds_much_longer_neighbours_of_refined_edges() {
    // Eq. 4.19: a neighbour j of a selected edge i joins when L⁰_i / L⁰_j < c₂. Compressing the diagonal
    // (L⁰ = √2) selects it; its neighbours, the sides (L⁰ = 1), have L⁰_i/L⁰_j = 1.41 and never join.
    // Folding by 40° selects the sides (curvature); the diagonal has L⁰_i/L⁰_j = 1/√2 = 0.707: it joins
    // with c₂ = 0.75 (Tests I and III) but not with c₂ = 0.65 (Test II).
    let folded = folded_square(1.0, 40f64.to_radians());
    let sides = vec![key(0, 1), key(0, 2), key(1, 3), key(2, 3)];
    let p = |c2: f64| OliveiraRemeshing { smoothing_ratio: c2, ..refine_only() };
    let sel = select(&folded, &[], &p(0.75));
    assert_eq!(sel.by_criterion, [0, 0, 4]);
    assert_eq!(sorted(sel.refine), sorted([sides.clone(), vec![key(0, 3)]].concat()));
    assert_eq!(sorted(select(&folded, &[], &p(0.65)).refine), sides);
    let mut pressed = sheet(2, 1.0);
    pressed.positions_mut()[3] = DVec3::new(0.6, 0.6, 0.0);
    assert_eq!(select(&pressed, &[], &p(0.75)).refine, vec![key(0, 3)]);
}

#[test]
fn flat_edges_are_simplified_only_after_the_delay_since_their_refinement() {
    // A flat 3 × 3 sheet of side 0.2 m (edges 0.1 and 0.141 m, under Test III's L⁰_max = 0.25 m): every
    // edge has n̂_a · n̂_b = 1 > 0.999995. An edge refined at t₀ may be simplified
    // from t₀ + t_simp (0.1 s in Test III); edges with no stamp are old.
    let m = sheet(3, 0.2);
    let p = OliveiraRemeshing::test_3();
    let all: Vec<(u32, u32)> = criteria_edges(&m);
    assert_eq!(all.len(), 16);
    let sel = select_edges(&m, &[], &BTreeMap::new(), 0.0, &p);
    assert_eq!(sorted(sel.simplify), all);
    let stamped: BTreeMap<(u32, u32), f64> = all.iter().map(|&k| (k, 1.0)).collect();
    for (t, picked) in [(1.0, false), (1.05, false), (1.0999, false), (1.1, true), (1.5, true)] {
        let sel = select_edges(&m, &[], &stamped, t, &p);
        assert_eq!(sel.simplify.len(), if picked { 16 } else { 0 }, "t = {t}");
    }
    // L⁰_max guard: edges longer than L⁰_max are never simplified.
    let short_max = OliveiraRemeshing { max_rest_length: 0.12, ..p };
    let sel = select_edges(&m, &[], &BTreeMap::new(), 0.0, &short_max);
    assert_eq!(sel.simplify.len(), 12, "the four diagonals (0.141 m) stay: {sel:?}");
    // The angle threshold: with the diagonal made 5 ms ago (too young to be picked or to join), the
    // sides are simplified when their normals are 0.1° apart (cos = 0.9999985 > 0.999995) and not when
    // they are 0.5° apart (cos = 0.999962).
    let young: BTreeMap<(u32, u32), f64> = [(key(0, 3), 0.0)].into();
    let sides = vec![key(0, 1), key(0, 2), key(1, 3), key(2, 3)];
    let sel = select_edges(&folded_square(0.2, 0.2f64.to_radians()), &[], &young, 0.005, &p);
    assert_eq!(sorted(sel.simplify), sides);
    let sel = select_edges(&folded_square(0.2, 1f64.to_radians()), &[], &young, 0.005, &p);
    assert!(sel.simplify.is_empty(), "{sel:?}");
}

/// Every edge key of a mesh, sorted.
fn criteria_edges(m: &AdaptiveMesh) -> Vec<(u32, u32)> {
    sorted(mesh_edges(m).iter().map(MeshEdge::key).collect())
}

#[test]
fn simplification_spreads_to_neighbours_at_least_a_tenth_of_the_delay_old() {
    // Spec §6.3: a neighbour j of an edge selected for simplification joins when
    // t − t_refined(j) ≥ 0.1·t_simp. On the flat 3 × 3 sheet, every edge but 0–1 was refined at t = 1 s,
    // so only 0–1 is picked by the criterion; its face [0, 1, 4] brings 1–4 and 0–4 once they are
    // 0.01 s old (Test III's t_simp = 0.1 s), in one pass (not their own neighbours).
    let m = sheet(3, 0.2);
    let p = OliveiraRemeshing::test_3();
    let stamped: BTreeMap<(u32, u32), f64> =
        criteria_edges(&m).into_iter().filter(|&k| k != key(0, 1)).map(|k| (k, 1.0)).collect();
    let sel = select_edges(&m, &[], &stamped, 1.009, &p);
    assert_eq!(sel.simplify, vec![key(0, 1)]);
    let sel = select_edges(&m, &[], &stamped, 1.011, &p);
    assert_eq!(sorted(sel.simplify), vec![key(0, 1), key(0, 4), key(1, 4)]);
}

#[test]
fn components_join_edges_that_share_a_face_not_a_vertex() {
    // 3 × 3 sheet: faces f0 = [0,1,4], f1 = [0,4,3], f2 = [1,2,5], f3 = [1,5,4], f4 = [3,4,7],
    // f5 = [3,7,6], f6 = [4,5,8], f7 = [4,8,7]. Edges 0–1 (f0) and 1–4 (f0, f3) share f0; 4–8 (f6, f7)
    // touches them only at vertex 4.
    let m = sheet(3, 1.0);
    assert_eq!(m.face_slots()[3], [1, 5, 4]);
    let keys = [key(0, 1), key(1, 4), key(4, 8)];
    assert_eq!(edge_components(&m, &keys, &[]), vec![vec![0, 3], vec![6, 7]]);
    // 4–5 (f3, f6) bridges the two.
    let bridged = [key(0, 1), key(1, 4), key(4, 8), key(4, 5)];
    assert_eq!(edge_components(&m, &bridged, &[]), vec![vec![0, 3, 6, 7]]);
    // Excluded faces (taken by refinement) drop the edges that touch them.
    assert_eq!(edge_components(&m, &keys, &[3]), vec![vec![0], vec![6, 7]]);
    assert!(edge_components(&m, &[], &[]).is_empty());
}

#[test]
fn refinement_takes_priority_over_simplification_on_shared_faces() {
    // simplify edges that share a face with a refine component are dropped. The 3 × 3 sheet is
    // flat (all edges would be simplified) but edge 0–4 is compressed to 60 % (0–1 and 0–3 keep 72 %).
    let mut m = sheet(3, 0.2);
    m.positions_mut()[0] = DVec3::new(0.04, 0.04, 0.0);
    let p = OliveiraRemeshing { smoothing_ratio: 0.5, ..OliveiraRemeshing::test_3() };
    let sel = select_edges(&m, &[], &BTreeMap::new(), 0.0, &p);
    assert_eq!(sel.refine, vec![key(0, 4)]);
    let refine = edge_components(&m, &sel.refine, &[]);
    assert_eq!(refine, vec![vec![0, 1]]);
    let simplify = edge_components(&m, &sel.simplify, &refine.concat());
    assert!(simplify.iter().flatten().all(|&f| f >= 2), "{simplify:?}");
    assert!(!simplify.is_empty());
}
