//! Self-contact detection for cloth: the geometry that lets a cloth never pass through itself
//! (issue #16), and the checker that tells whether it did.
//!
//! * [`count_self_intersections`] / [`self_intersections`] — how many (edge, triangle) pairs of a
//!   mesh cross. Independent of any response, so it can judge one; meant to be reported in run
//!   summaries as `self_intersections`. Certified orientation signs ([`orient3d`]) make the count a
//!   property of the geometry, not of rounding.
//! * [`SelfContactBroadPhase`] — the vertex–triangle and edge–edge pairs whose boxes, swept over a
//!   step and grown by the cloth's thickness, overlap: bounding-volume hierarchies refitted each step
//!   and rebuilt when the topology changes, with every buffer kept, so a step allocates nothing.
//! * Narrow phase: [`point_triangle_proximity`] and [`edge_edge_proximity`] (closest points with
//!   barycentric weights) for contacts within the thickness; [`vertex_triangle_impact`] and
//!   [`edge_edge_impact`] for the first time of impact over a step, from the roots of the coplanarity
//!   cubic (Bridson, Fedkiw & Anderson 2002).
//!
//! What this module is not: it applies no response (impulses, impact zones) and knows no physics;
//! positions in, pairs and times out. Every test is in `f64`.
//!
//! ```
//! use anima_geom::{DVec3, SelfContactBroadPhase, vertex_triangle_impact};
//!
//! // One triangle and a vertex falling through it over a step: the broad phase pairs them and the
//! // continuous test finds the moment they meet, halfway through.
//! let triangles = [[0, 1, 2]];
//! let start = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.2, 0.2, 1.0)];
//! let end = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.2, 0.2, -1.0)];
//! let thickness = 1.0e-3;
//! let mut broad = SelfContactBroadPhase::new();
//! broad.update(&triangles, &start, &end, thickness);
//! for pair in broad.vertex_triangle_pairs() {
//!     let [a, b, c] = triangles[pair.triangle as usize].map(|i| i as usize);
//!     let v = pair.vertex as usize;
//!     let hit = vertex_triangle_impact(
//!         [start[v], start[a], start[b], start[c]],
//!         [end[v], end[a], end[b], end[c]],
//!         thickness,
//!     )
//!     .unwrap();
//!     assert!((hit.t - 0.5).abs() < 1e-3 && hit.normal.z > 0.0);
//! }
//! ```

mod broad_phase;
mod bvh;
mod ccd;
mod crossings;
mod orient;
mod patch_tree;
mod proximity;
#[cfg(test)]
mod tests;

pub use broad_phase::{EdgeEdgePair, SelfContactBroadPhase, VertexTrianglePair};
pub use ccd::{EdgeEdgeImpact, VertexTriangleImpact, edge_edge_impact, vertex_triangle_impact};
pub use crossings::{
    CROSSING_CANDIDATES_PER_EDGE, CountAbandoned, EdgeTriangleCrossing, count_self_intersections,
    count_self_intersections_within, segment_crosses_triangle, self_intersections,
};
pub use orient::orient3d;
pub use proximity::{
    EdgeEdgeProximity, PointTriangleProximity, edge_edge_proximity, point_triangle_proximity,
};
