//! Times the self-contact detection on a 64 × 64-square sheet (8192 triangles), once: the crossing
//! count on a flat and on a folded sheet, and a broad-phase update with its narrow phase.
//!
//! `cargo run --release -p anima-geom --example self_contact_timing`

use std::time::Instant;

use anima_geom::{
    DVec3, DiagonalPattern, MaterialMesh, SelfContactBroadPhase, count_self_intersections, edge_edge_impact,
    vertex_triangle_impact,
};

fn main() {
    let mesh = MaterialMesh::grid(65, 1.0, DiagonalPattern::Uniform).expect("valid grid");
    let triangles = mesh.triangles();
    let flat = mesh.place(DVec3::ZERO, DVec3::X, DVec3::Y);
    // Folded through itself: the right half tipped past flat so it dips back through the left half.
    let folded: Vec<DVec3> = flat
        .iter()
        .map(|p| {
            if p.x <= 0.5 {
                *p
            } else {
                DVec3::new(1.0 - p.x, p.y, 0.3 * (p.x - 0.5) - 0.1 * (p.x - 0.5).sqrt())
            }
        })
        .collect();
    for (name, x) in [("flat", &flat), ("folded", &folded)] {
        let start = Instant::now();
        let n = count_self_intersections(x, triangles);
        println!(
            "count_self_intersections, {name} sheet of {} triangles: {n} crossings in {:.2} ms",
            triangles.len(),
            start.elapsed().as_secs_f64() * 1e3
        );
    }

    // One step of a sheet waving downwards, thickness 1 mm.
    let x1: Vec<DVec3> = flat.iter().map(|p| *p + DVec3::Z * (0.01 * (8.0 * p.x).sin() - 0.005)).collect();
    let mut broad = SelfContactBroadPhase::new();
    for label in ["build", "refit"] {
        let start = Instant::now();
        broad.update(triangles, &flat, &x1, 1.0e-3);
        let broad_ms = start.elapsed().as_secs_f64() * 1e3;
        let start = Instant::now();
        let mut hits = 0;
        for p in broad.vertex_triangle_pairs() {
            let [a, b, c] = triangles[p.triangle as usize].map(|i| i as usize);
            let v = p.vertex as usize;
            let s = [flat[v], flat[a], flat[b], flat[c]];
            let e = [x1[v], x1[a], x1[b], x1[c]];
            hits += usize::from(vertex_triangle_impact(s, e, 1.0e-3).is_some());
        }
        for p in broad.edge_edge_pairs() {
            let [[a0, a1], [b0, b1]] = p.edges.map(|e| e.map(|i| i as usize));
            let s = [flat[a0], flat[a1], flat[b0], flat[b1]];
            let e = [x1[a0], x1[a1], x1[b0], x1[b1]];
            hits += usize::from(edge_edge_impact(s, e, 1.0e-3).is_some());
        }
        println!(
            "broad phase ({label}): {} vertex–triangle and {} edge–edge candidates in {broad_ms:.2} ms; \
             narrow phase: {hits} impacts in {:.2} ms",
            broad.vertex_triangle_pairs().len(),
            broad.edge_edge_pairs().len(),
            start.elapsed().as_secs_f64() * 1e3
        );
    }
}
