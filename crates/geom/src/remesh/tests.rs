//! Tests of the editable mesh and its operators: invariants and rest area after every operation.

use glam::{DVec2, DVec3};

use super::*;
use crate::{DiagonalPattern, MaterialMesh};

/// An `n × n`-vertex grid over [0, size]², flat at z = 0, with the linear velocity field
/// v = (X.y, −X.x, X.x + X.y) so that barycentric transfer can be checked exactly.
pub(crate) fn grid(n: usize, size: f64, pattern: DiagonalPattern) -> AdaptiveMesh {
    let m = MaterialMesh::grid(n, size, pattern).unwrap();
    let x = m.place(DVec3::ZERO, DVec3::X, DVec3::Y);
    let v = m.rest().iter().map(|p| field(*p)).collect();
    AdaptiveMesh::from_material(&m, x, v)
}

pub(crate) fn field(p: DVec2) -> DVec3 {
    DVec3::new(p.y, -p.x, p.x + p.y)
}

/// A small deterministic generator (xorshift64*), so the crate needs no `rand`.
pub(crate) struct Rng(pub u64);

impl Rng {
    pub(crate) fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    pub(crate) fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    #[allow(dead_code, reason = "used by the sizing and mesher tests")]
    pub(crate) fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn assert_valid(m: &AdaptiveMesh, area: f64, what: &str) {
    m.check_invariants().unwrap_or_else(|e| panic!("{what}: {e}"));
    let a = m.total_rest_area();
    assert!((a - area).abs() <= 1e-13 * area, "{what}: rest area {a} ≠ {area}");
    let va: f64 = m.vertex_areas().iter().sum();
    assert!((va - area).abs() <= 1e-13 * area, "{what}: vertex areas sum to {va}");
}

#[test]
fn split_interior_and_contour_edges() {
    let mut m = grid(3, 1.0, DiagonalPattern::Uniform);
    let area = m.total_rest_area();
    // Diagonal 0–4 is interior; 0–1 lies on the contour.
    let g = OpGuards::validity_only();
    let c = m.split_edge(0, 4, &g).unwrap();
    assert_valid(&m, area, "interior split");
    assert_eq!((m.n_vertices(), m.n_faces()), (10, 10));
    assert_eq!(m.rest()[c as usize], DVec2::splat(0.25));
    assert_eq!(m.velocities()[c as usize], field(DVec2::splat(0.25)));
    let b = m.split_edge(1, 0, &g).unwrap();
    assert_valid(&m, area, "contour split");
    assert!(m.is_boundary_vertex(b) && !m.is_boundary_vertex(c));
    let log = m.take_log();
    assert_eq!(log.counts.splits, 2);
    assert_eq!(log.new_vertices[0], NewVertex { vertex: c, parents: [0, 4, 0], weights: [0.5, 0.5, 0.0] });
    assert_eq!((log.removed_faces.len(), log.added_faces.len()), (3, 6));
    assert!(m.take_log().is_empty());
    // Too short for the guard.
    assert_eq!(m.split_edge(0, c, &OpGuards::with_min_edge_length(0.2)), Err(OpError::TooShort));
    assert_eq!(m.split_edge(0, 8, &g), Err(OpError::NoSuchEdge(0, 8)));
}

#[test]
fn flip_needs_an_interior_edge_and_a_convex_quad() {
    let mut m = grid(3, 1.0, DiagonalPattern::Uniform);
    let area = m.total_rest_area();
    let g = OpGuards::validity_only();
    assert_eq!(m.flip_edge(0, 1, &g), Err(OpError::BoundaryEdge));
    let (c, d) = m.flip_edge(0, 4, &g).unwrap();
    assert_eq!((c.min(d), c.max(d)), (1, 3));
    assert_valid(&m, area, "flip");
    // Flipping back restores the diagonal. After a split of that diagonal, the quad around edge
    // (midpoint, 1) has a straight angle at the midpoint, and the flip would make a flat triangle.
    m.flip_edge(1, 3, &g).unwrap();
    assert_valid(&m, area, "flip back");
    let mid = m.split_edge(0, 4, &g).unwrap();
    let before = m.clone();
    assert_eq!(m.flip_edge(mid, 1, &g), Err(OpError::Inverted));
    assert_eq!(m, before);
    assert_eq!(m.take_log().counts.flips, 2);
}

#[test]
fn collapse_keeps_the_contour_and_refuses_inversions() {
    let mut m = grid(4, 1.0, DiagonalPattern::Alternating);
    let area = m.total_rest_area();
    let g = OpGuards::validity_only();
    // Corner 0 cannot go anywhere; contour vertex 1 may slide into 2 along the straight contour, not
    // into the interior vertex 5.
    assert_eq!(m.collapse_edge(0, 1, &g), Err(OpError::Boundary));
    assert_eq!(m.collapse_edge(1, 5, &g), Err(OpError::Boundary));
    m.collapse_edge(1, 2, &g).unwrap();
    assert_valid(&m, area, "contour collapse");
    assert!(!m.is_vertex_alive(1));
    // Interior vertex 5 into 6 (its star is convex enough).
    let before = m.n_vertices();
    match m.collapse_edge(5, 6, &g) {
        Ok(()) => assert_eq!(m.n_vertices(), before - 1),
        Err(e) => assert!(matches!(e, OpError::Inverted | OpError::NonManifold), "{e}"),
    }
    assert_valid(&m, area, "interior collapse");
    let mut locked = grid(4, 1.0, DiagonalPattern::Alternating);
    locked.set_locked(1, true);
    assert_eq!(locked.collapse_edge(1, 2, &g), Err(OpError::Boundary));
}

#[test]
fn collapse_guards_world_normals_and_lengths() {
    let mut m = grid(3, 1.0, DiagonalPattern::Uniform);
    // Fold the sheet so that collapsing the centre onto a corner of the fold would flip a face.
    m.positions_mut()[4].z = 5.0;
    let r = m.collapse_edge(4, 0, &OpGuards { min_normal_cos: 0.9, ..OpGuards::validity_only() });
    assert!(matches!(r, Err(OpError::NormalFlip | OpError::Inverted)), "{r:?}");
    m.check_invariants().unwrap();
    assert_eq!(m.collapse_edge(4, 0, &OpGuards::with_min_edge_length(0.9)), Err(OpError::TooShort));
}

#[test]
fn region_border_and_patch_replacement() {
    let mut m = grid(4, 3.0, DiagonalPattern::Uniform);
    let area = m.total_rest_area();
    // The two faces of the centre square (vertices 5, 6, 9, 10).
    let faces: Vec<u32> = m
        .live_faces()
        .filter(|&f| m.face_slots()[f as usize].iter().all(|v| [5, 6, 9, 10].contains(v)))
        .collect();
    assert_eq!(faces.len(), 2);
    let loops = m.region_border(&faces);
    assert_eq!(loops, vec![vec![5, 6, 10, 9]]);
    // A fan around a new centre vertex.
    let c = m.n_vertex_slots() as u32;
    let tris = [[5, 6, c], [6, 10, c], [10, 9, c], [9, 5, c]];
    let ids = m.replace_patch(&faces, &[DVec2::new(1.5, 1.5)], &tris).unwrap();
    assert_valid(&m, area, "patch");
    assert_eq!(m.velocities()[ids[0] as usize], field(DVec2::new(1.5, 1.5)));
    // A patch that does not cover the hole, or that misses a shared edge, is refused unchanged.
    let fan: Vec<u32> = m.vertex_faces(ids[0]);
    let before = m.clone();
    let d = m.n_vertex_slots() as u32;
    let bad = [[5, 6, d], [6, 10, d], [10, 9, d]];
    assert_eq!(m.replace_patch(&fan, &[DVec2::new(1.5, 1.5)], &bad), Err(OpError::AreaMismatch));
    assert_eq!(m, before);
    // The whole sheet's border is one counter-clockwise loop of 12 contour vertices.
    let all: Vec<u32> = m.live_faces().collect();
    let loops = m.region_border(&all);
    assert_eq!(loops.len(), 1);
    assert_eq!(loops[0].len(), 12);
}

#[test]
fn compact_renumbers_densely() {
    let mut m = grid(4, 1.0, DiagonalPattern::Alternating);
    let area = m.total_rest_area();
    let g = OpGuards::validity_only();
    let s = m.split_edge(5, 6, &g).unwrap();
    m.collapse_edge(1, 2, &g).unwrap();
    let mut tag: Vec<u32> = (0..m.n_vertex_slots() as u32).collect();
    let renum = m.compact();
    renum.compact_vertex_data(&mut tag);
    assert_eq!(m.n_vertex_slots(), m.n_vertices());
    assert_eq!(m.n_face_slots(), m.n_faces());
    assert_eq!(renum.vertex[1], NONE);
    assert_eq!(tag[renum.vertex[s as usize] as usize], s);
    assert_valid(&m, area, "after compaction");
    assert_eq!(m.half_edges().n_faces(), m.n_faces());
}

/// Thousands of random operations on a randomly bent sheet, each checked: refused operations must
/// leave the mesh valid and unchanged, accepted ones valid with the same rest area.
#[test]
fn random_operations_keep_every_invariant() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut m = grid(7, 1.0, DiagonalPattern::Alternating);
    for i in 0..m.n_vertex_slots() {
        let p = m.rest()[i];
        m.positions_mut()[i].z = 0.3 * (6.0 * p.x).sin() * p.y;
    }
    let area = m.total_rest_area();
    let g = OpGuards { min_edge_length: 0.01, ..OpGuards::validity_only() };
    let mut accepted = [0usize; 3];
    for step in 0..3000 {
        let edges = m.edges();
        let (_, a, b) = edges[rng.below(edges.len())];
        let kind = rng.below(3);
        let before = m.clone();
        let r = match kind {
            0 if m.n_faces() < 400 => m.split_edge(a, b, &g).map(|_| ()),
            1 => m.flip_edge(a, b, &g).map(|_| ()),
            _ => m.collapse_edge(a, b, &g),
        };
        match r {
            Ok(()) => accepted[kind.min(2)] += 1,
            Err(_) => assert_eq!(m, before, "step {step}: a refused operation changed the mesh"),
        }
        if step % 7 == 0 || r.is_ok() {
            assert_valid(&m, area, &format!("step {step}, op {kind}"));
        }
        if step % 500 == 499 {
            m.compact();
        }
    }
    assert!(accepted.iter().all(|&n| n > 100), "too few accepted operations: {accepted:?}");
}
