//! Broad phase plus narrow phase against every pair, on small random meshes moving over one step.

use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::Aabb;

/// Random triangles over a few vertices in the unit cube, and random displacements over one step.
fn random_step(rng: &mut ChaCha8Rng) -> (Vec<[u32; 3]>, Vec<DVec3>, Vec<DVec3>) {
    let n_vertices = rng.random_range(4..14);
    let point = |rng: &mut ChaCha8Rng, r: f64| {
        DVec3::new(rng.random_range(-r..r), rng.random_range(-r..r), rng.random_range(-r..r))
    };
    let start: Vec<DVec3> = (0..n_vertices).map(|_| point(rng, 1.0)).collect();
    let end: Vec<DVec3> = start.iter().map(|&x| x + point(rng, 0.6)).collect();
    let n_triangles = rng.random_range(1..10);
    let triangles = (0..n_triangles)
        .map(|_| {
            loop {
                let t = [0, 1, 2].map(|_| rng.random_range(0..n_vertices as u32));
                if t[0] != t[1] && t[1] != t[2] && t[0] != t[2] {
                    break t;
                }
            }
        })
        .collect();
    (triangles, start, end)
}

fn swept(x0: &[DVec3], x1: &[DVec3], ids: &[u32], thickness: f64) -> Aabb {
    let b = Aabb::from_points(ids.iter().flat_map(|&i| [x0[i as usize], x1[i as usize]]));
    let r = DVec3::splat(0.5 * thickness);
    Aabb { min: b.min - r, max: b.max + r }
}

/// With every box overlap listed, the candidates are exactly brute force's; with flat, connected
/// pieces skipped (the default), every impact brute force finds is still among them.
#[test]
fn broad_and_narrow_phase_match_brute_force_on_random_meshes() {
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    let mut broad = SelfContactBroadPhase::new();
    broad.list_every_overlap();
    let mut culled = SelfContactBroadPhase::new();
    let (mut n_vt_hits, mut n_ee_hits) = (0, 0);
    for case in 0..400 {
        let (triangles, x0, x1) = random_step(&mut rng);
        let thickness = [0.0, 0.01, 0.1][case % 3];
        broad.update(&triangles, &x0, &x1, thickness);
        culled.update(&triangles, &x0, &x1, thickness);
        let vt = |v: u32, t: u32| {
            let [a, b, c] = triangles[t as usize].map(|i| i as usize);
            let v = v as usize;
            vertex_triangle_impact([x0[v], x0[a], x0[b], x0[c]], [x1[v], x1[a], x1[b], x1[c]], thickness)
        };
        let ee = |[a, b]: [[u32; 2]; 2]| {
            let [a0, a1, b0, b1] = [a[0], a[1], b[0], b[1]].map(|i| i as usize);
            edge_edge_impact([x0[a0], x0[a1], x0[b0], x0[b1]], [x1[a0], x1[a1], x1[b0], x1[b1]], thickness)
        };

        // Candidates: exactly the non-adjacent pairs whose swept boxes overlap.
        let mut got: Vec<VertexTrianglePair> = broad.vertex_triangle_pairs().to_vec();
        got.sort_unstable();
        let mut want_vt = Vec::new();
        let mut hits_vt = Vec::new();
        for v in 0..x0.len() as u32 {
            for (t, tri) in triangles.iter().enumerate() {
                if tri.contains(&v) {
                    continue;
                }
                let pair = VertexTrianglePair { vertex: v, triangle: t as u32 };
                if swept(&x0, &x1, &[v], thickness).overlaps(&swept(&x0, &x1, tri, thickness)) {
                    want_vt.push(pair);
                }
                if vt(v, t as u32).is_some() {
                    hits_vt.push(pair);
                }
            }
        }
        assert_eq!(got, want_vt, "vertex–triangle candidates, case {case}");
        let mut narrow_vt: Vec<_> =
            got.iter().copied().filter(|p| vt(p.vertex, p.triangle).is_some()).collect();
        narrow_vt.sort_unstable();
        assert_eq!(narrow_vt, hits_vt, "vertex–triangle impacts, case {case}");
        let kept: std::collections::HashSet<_> = culled.vertex_triangle_pairs().iter().copied().collect();
        assert!(hits_vt.iter().all(|p| kept.contains(p)), "a vertex–triangle impact skipped, case {case}");
        n_vt_hits += hits_vt.len();

        let edges = broad.edges();
        let mut got: Vec<EdgeEdgePair> = broad.edge_edge_pairs().to_vec();
        got.sort_unstable();
        let mut want_ee = Vec::new();
        let mut hits_ee = Vec::new();
        for (i, &a) in edges.iter().enumerate() {
            for &b in &edges[i + 1..] {
                if b.contains(&a[0]) || b.contains(&a[1]) {
                    continue;
                }
                let pair = EdgeEdgePair { edges: [a, b] };
                if swept(&x0, &x1, &a, thickness).overlaps(&swept(&x0, &x1, &b, thickness)) {
                    want_ee.push(pair);
                }
                if ee(pair.edges).is_some() {
                    hits_ee.push(pair);
                }
            }
        }
        assert_eq!(got, want_ee, "edge–edge candidates, case {case}");
        let mut narrow_ee: Vec<_> = got.iter().copied().filter(|p| ee(p.edges).is_some()).collect();
        narrow_ee.sort_unstable();
        assert_eq!(narrow_ee, hits_ee, "edge–edge impacts, case {case}");
        let kept: std::collections::HashSet<_> = culled.edge_edge_pairs().iter().copied().collect();
        assert!(
            hits_ee.iter().all(|p| kept.contains(p)),
            "an edge–edge impact skipped, case {case}: {:?} of {triangles:?}\nx0 {x0:?}\nx1 {x1:?}",
            hits_ee.iter().find(|p| !kept.contains(p))
        );
        n_ee_hits += hits_ee.len();
    }
    // The comparison means something only if contacts happened.
    assert!(n_vt_hits > 50 && n_ee_hits > 50, "{n_vt_hits} vertex–triangle, {n_ee_hits} edge–edge impacts");
}

#[test]
fn every_reported_impact_is_a_contact_at_its_time() {
    let mut rng = ChaCha8Rng::seed_from_u64(1616);
    let thickness = 0.01;
    for case in 0..2000 {
        let s: [DVec3; 4] = std::array::from_fn(|_| {
            DVec3::new(rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0))
        });
        let e: [DVec3; 4] = std::array::from_fn(|i| {
            s[i] + DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
        });
        let at = |t: f64| std::array::from_fn::<DVec3, 4, _>(|i| s[i] + (e[i] - s[i]) * t);
        if let Some(hit) = vertex_triangle_impact(s, e, thickness) {
            let [p, a, b, c] = at(hit.t);
            let q = point_triangle_proximity(p, [a, b, c]);
            assert!((0.0..=1.0).contains(&hit.t) && q.distance <= thickness + 1e-9, "case {case}: {hit:?}");
            assert!((hit.normal.length() - 1.0).abs() < 1e-12, "case {case}: {hit:?}");
        }
        if let Some(hit) = edge_edge_impact(s, e, thickness) {
            let [a0, a1, b0, b1] = at(hit.t);
            let q = edge_edge_proximity([a0, a1], [b0, b1]);
            assert!((0.0..=1.0).contains(&hit.t) && q.distance <= thickness + 1e-9, "case {case}: {hit:?}");
            assert!((hit.normal.length() - 1.0).abs() < 1e-12, "case {case}: {hit:?}");
        }
        // A vertex that ends on the other side of a static triangle and crosses inside it is caught.
        let (ts, te) = ([s[0], s[1], s[2], s[3]], [e[0], s[1], s[2], s[3]]);
        if segment_crosses_triangle(s[0], e[0], [s[1], s[2], s[3]]) {
            assert!(vertex_triangle_impact(ts, te, 0.0).is_some(), "case {case}: missed a crossing");
        }
    }
}

#[test]
fn sheet_at_20_m_s_through_a_thin_slab_is_caught_though_the_end_state_is_clean() {
    // A 1 mm double layer (two 9 × 9 sheets) and a third sheet 0.2 m above it, falling at 20 m/s for
    // a 1/60 s step: it starts and ends clear of the slab, so only the continuous test can see it.
    use crate::{DiagonalPattern, MaterialMesh};
    let mesh = MaterialMesh::grid(9, 1.0, DiagonalPattern::Alternating).unwrap();
    let n = mesh.n_vertices() as u32;
    let thickness = 1.0e-4;
    let travel = 20.0 / 60.0;
    let mut triangles = Vec::new();
    let mut x0 = Vec::new();
    let mut x1 = Vec::new();
    let offset = DVec3::new(0.04, 0.03, 0.0);
    for (layer, z0, drop) in [(0, 0.0, 0.0), (1, 1.0e-3, 0.0), (2, 0.2, travel)] {
        triangles.extend(mesh.triangles().iter().map(|t| t.map(|i| i + layer * n)));
        let shift = if layer == 2 { offset } else { DVec3::ZERO };
        x0.extend(mesh.place(DVec3::Z * z0 + shift, DVec3::X, DVec3::Y));
        x1.extend(mesh.place(DVec3::Z * (z0 - drop) + shift, DVec3::X, DVec3::Y));
    }
    assert_eq!(count_self_intersections(&x0, &triangles), 0);
    assert_eq!(count_self_intersections(&x1, &triangles), 0);

    let mut broad = SelfContactBroadPhase::new();
    broad.update(&triangles, &x0, &x1, thickness);
    let mut first_hit = vec![f64::INFINITY; x0.len()];
    for p in broad.vertex_triangle_pairs() {
        let [a, b, c] = triangles[p.triangle as usize].map(|i| i as usize);
        let v = p.vertex as usize;
        if let Some(hit) =
            vertex_triangle_impact([x0[v], x0[a], x0[b], x0[c]], [x1[v], x1[a], x1[b], x1[c]], thickness)
        {
            first_hit[v] = first_hit[v].min(hit.t);
        }
    }
    // The time reported is the instant of coplanarity with the top layer.
    let want = (0.2 - 1.0e-3) / travel;
    for v in 2 * n as usize..x0.len() {
        let p = x0[v];
        if p.x < 1.0 && p.y < 1.0 {
            assert!((first_hit[v] - want).abs() < 1e-12, "vertex {v} at {p}: first hit {}", first_hit[v]);
        }
    }
}

/// A manifold sheet folding onto itself over a step, in many random folds: the broad phase that skips
/// flat, connected pieces keeps every impact brute force finds; a flat sheet falling with a ripple gives
/// no candidate at all, and the folding ones far fewer than every box overlap.
#[test]
fn skipping_flat_pieces_loses_no_impact_of_a_folding_sheet() {
    use crate::{DiagonalPattern, MaterialMesh};
    let mesh = MaterialMesh::grid(10, 1.0, DiagonalPattern::Alternating).unwrap();
    let flat = mesh.place(DVec3::ZERO, DVec3::X, DVec3::Y);
    let triangles = mesh.triangles();
    let mut rng = ChaCha8Rng::seed_from_u64(37);
    let (mut hits, mut culled_pairs, mut all_pairs) = (0, 0, 0);
    for case in 0..60 {
        // Folded about x = fold by an angle near 180°, then moved on by a little more folding and noise.
        let fold = rng.random_range(0.3..0.7);
        let (a0, a1) = (rng.random_range(2.6..3.1f64), rng.random_range(3.0..3.3f64));
        let shape = |angle: f64, lift: f64| -> Vec<DVec3> {
            flat.iter()
                .map(|p| {
                    if p.x <= fold {
                        *p
                    } else {
                        let r = p.x - fold;
                        DVec3::new(fold + r * angle.cos(), p.y, r * angle.sin() + lift)
                    }
                })
                .collect()
        };
        let x0 = shape(a0, 0.02);
        let x1: Vec<DVec3> = shape(a1, -0.01)
            .into_iter()
            .map(|p| p + DVec3::new(rng.random_range(-1e-3..1e-3), rng.random_range(-1e-3..1e-3), 0.0))
            .collect();
        let thickness = 0.01;
        let mut every = SelfContactBroadPhase::new();
        every.list_every_overlap();
        every.update(triangles, &x0, &x1, thickness);
        let mut culled = SelfContactBroadPhase::new();
        culled.update(triangles, &x0, &x1, thickness);
        let kept_vt: std::collections::HashSet<_> = culled.vertex_triangle_pairs().iter().copied().collect();
        let kept_ee: std::collections::HashSet<_> = culled.edge_edge_pairs().iter().copied().collect();
        for p in every.vertex_triangle_pairs() {
            let [a, b, c] = triangles[p.triangle as usize].map(|i| i as usize);
            let v = p.vertex as usize;
            if vertex_triangle_impact([x0[v], x0[a], x0[b], x0[c]], [x1[v], x1[a], x1[b], x1[c]], thickness)
                .is_some()
            {
                hits += 1;
                assert!(kept_vt.contains(p), "case {case}: {p:?} skipped");
            }
        }
        for p in every.edge_edge_pairs() {
            let [[a0, a1], [b0, b1]] = p.edges.map(|e| e.map(|i| i as usize));
            if edge_edge_impact([x0[a0], x0[a1], x0[b0], x0[b1]], [x1[a0], x1[a1], x1[b0], x1[b1]], thickness)
                .is_some()
            {
                hits += 1;
                assert!(kept_ee.contains(p), "case {case}: {p:?} skipped");
            }
        }
        culled_pairs += kept_vt.len() + kept_ee.len();
        all_pairs += every.vertex_triangle_pairs().len() + every.edge_edge_pairs().len();
    }
    assert!(hits > 100, "the folds must make impacts: {hits}");
    assert!(culled_pairs <= all_pairs);
    // A flat sheet falling with a gentle ripple: no candidate at all, where every box overlap gives
    // hundreds (the neighbours of every element).
    let x1: Vec<DVec3> =
        flat.iter().map(|p| *p + DVec3::new(0.0, 0.0, -0.05 + 0.01 * (3.0 * p.x).sin())).collect();
    let mut culled = SelfContactBroadPhase::new();
    culled.update(triangles, &flat, &x1, 0.01);
    assert_eq!((culled.vertex_triangle_pairs().len(), culled.edge_edge_pairs().len()), (0, 0));
    let mut every = SelfContactBroadPhase::new();
    every.list_every_overlap();
    every.update(triangles, &flat, &x1, 0.01);
    assert!(every.vertex_triangle_pairs().len() + every.edge_edge_pairs().len() > 200);
}

/// `update_moved` after an update lists exactly the pairs with a moved vertex that an update of the new
/// trajectories on the same tree lists, though it computes again only the cones of the triangles with a
/// moved corner: a flat sheet whose marked vertices fold a strip of it over itself (a flat piece that
/// stops being flat) and, in other cases, only ripple.
#[test]
fn an_update_of_the_moved_vertices_lists_what_a_fresh_update_lists_for_them() {
    fn sorted<T: Ord>(mut v: Vec<T>) -> Vec<T> {
        v.sort();
        v
    }
    use crate::{DiagonalPattern, MaterialMesh};
    let mesh = MaterialMesh::grid(12, 1.0, DiagonalPattern::Alternating).unwrap();
    let flat = mesh.place(DVec3::ZERO, DVec3::X, DVec3::Y);
    let triangles = mesh.triangles();
    let mut rng = ChaCha8Rng::seed_from_u64(41);
    let x1: Vec<DVec3> = flat.iter().map(|p| *p + DVec3::new(0.0, 0.0, -0.02)).collect();
    let mut found = 0;
    for case in 0..40 {
        // The vertices past x = fold fold back over the sheet in half the cases, and ripple otherwise.
        let fold = rng.random_range(0.4..0.7);
        let folding = case % 2 == 0;
        let moved: Vec<bool> = flat.iter().map(|p| p.x > fold).collect();
        let x2: Vec<DVec3> = flat
            .iter()
            .zip(&x1)
            .map(|(p, &q)| {
                if p.x <= fold {
                    q
                } else if folding {
                    DVec3::new(2.0 * fold - p.x, p.y, 0.004 * (p.x - fold) - 0.02)
                } else {
                    q + DVec3::new(0.0, 0.0, 0.003 * (9.0 * p.y).sin())
                }
            })
            .collect();
        let thickness = 0.01;
        let mut incremental = SelfContactBroadPhase::new();
        incremental.update(triangles, &flat, &x1, thickness);
        incremental.update_moved(triangles, &flat, &x2, thickness, &moved, false);
        // The same tree (built at the first update, refitted since) listing every pair afresh.
        let mut fresh = SelfContactBroadPhase::new();
        fresh.update(triangles, &flat, &x1, thickness);
        fresh.update(triangles, &flat, &x2, thickness);
        let any = |ids: &[u32]| ids.iter().any(|&i| moved[i as usize]);
        let fresh_vt = sorted(
            fresh
                .vertex_triangle_pairs()
                .iter()
                .filter(|p| any(&[p.vertex]) || any(&triangles[p.triangle as usize]))
                .copied()
                .collect::<Vec<_>>(),
        );
        let fresh_ee = sorted(
            fresh
                .edge_edge_pairs()
                .iter()
                .filter(|p| any(p.edges.as_flattened()))
                .copied()
                .collect::<Vec<_>>(),
        );
        let listed = sorted(incremental.vertex_triangle_pairs().to_vec());
        assert!(
            listed == fresh_vt,
            "case {case}: {} pairs listed, {} expected",
            listed.len(),
            fresh_vt.len()
        );
        assert_eq!(sorted(incremental.edge_edge_pairs().to_vec()), fresh_ee, "case {case}");
        if folding {
            assert!(!fresh_vt.is_empty(), "case {case}: the fold must bring pairs");
        }
        found += fresh_vt.len() + fresh_ee.len();
    }
    assert!(found > 100, "{found}");
}
