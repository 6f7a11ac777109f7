//! The self-intersection checker: how many (edge, triangle) pairs of a triangle mesh cross.
//!
//! It is independent of any collision response, so tests and run summaries can use it to judge one
//! (the field `self_intersections` of a run summary is meant to be this count). A cloth that passes
//! through itself has at least one edge piercing a triangle along every line where two sheets cross,
//! so a count of 0 is the claim "never passes through itself", and a positive count measures how much
//! it does.
//!
//! Conventions, chosen so that the count is a property of the geometry and not of rounding:
//! * each undirected edge is counted once, however many triangles share it;
//! * an edge and a triangle that share a vertex are never a crossing (they meet by construction);
//! * a crossing needs the edge's two ends strictly on opposite sides of the triangle's plane, by the
//!   certified [`orient3d`] sign. An edge lying in the plane, or with an end in it, is touching, not
//!   crossing; so is a configuration whose sides `f64` cannot certify (see [`orient3d`]). A resting
//!   layer exactly on another therefore counts 0;
//! * the line of the edge must pass through the closed triangle (the three orientations of the edge
//!   with the triangle's edges do not disagree). An edge through the shared edge or corner of
//!   neighbouring triangles is counted once for each of them.
//!
//! Triangles go into a [`Bvh`] of their boxes and each edge visits only the triangles whose boxes its
//! box overlaps, so a cloth sheet costs O(n log n) rather than O(n²) pair tests.

use glam::DVec3;

use super::bvh::Bvh;
use super::orient::orient3d;
use crate::Aabb;

/// One edge crossing one triangle of the same mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EdgeTriangleCrossing {
    /// The edge's vertices, smaller index first.
    pub edge: [u32; 2],
    pub triangle: u32,
}

/// Number of (edge, triangle) pairs of the mesh whose edge segment crosses the triangle, with each
/// undirected edge counted once and pairs that share a vertex excluded. 0 for a mesh that does not
/// pass through itself. See the module docs for what counts as crossing.
///
/// # Panics
/// If a triangle names a vertex outside `vertices`.
pub fn count_self_intersections(vertices: &[DVec3], triangles: &[[u32; 3]]) -> usize {
    let mut n = 0;
    for_each_crossing(vertices, triangles, usize::MAX, |_| n += 1).expect("no budget");
    n
}

/// Candidate (edge, triangle) pairs per edge that [`count_self_intersections_within`]'s default budget
/// allows: a cloth, folded or resting in layers, has a few dozen per edge (boxes of neighbouring
/// elements overlap); a mesh whose edges span the scene, as after a blow-up, has as many as it has
/// triangles.
pub const CROSSING_CANDIDATES_PER_EDGE: usize = 256;

/// The count was abandoned: more (edge, triangle) box overlaps than the budget allows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("the crossing count gave up after {candidates} candidate pairs (the mesh is tangled or exploded)")]
pub struct CountAbandoned {
    pub candidates: usize,
}

/// [`count_self_intersections`] with a bound on its work: at most `budget` candidate (edge, triangle)
/// pairs tested (`None`: [`CROSSING_CANDIDATES_PER_EDGE`] per edge of the mesh), so that a mesh whose
/// boxes all overlap (a run that exploded) costs a bounded time instead of a quadratic one.
pub fn count_self_intersections_within(
    vertices: &[DVec3],
    triangles: &[[u32; 3]],
    budget: Option<usize>,
) -> Result<usize, CountAbandoned> {
    let budget = budget.unwrap_or(CROSSING_CANDIDATES_PER_EDGE * 3 * triangles.len());
    let mut n = 0;
    for_each_crossing(vertices, triangles, budget, |_| n += 1)?;
    Ok(n)
}

/// The crossing pairs [`count_self_intersections`] counts, ordered by edge, then triangle.
pub fn self_intersections(vertices: &[DVec3], triangles: &[[u32; 3]]) -> Vec<EdgeTriangleCrossing> {
    let mut crossings = Vec::new();
    for_each_crossing(vertices, triangles, usize::MAX, |c| crossings.push(c)).expect("no budget");
    crossings.sort_unstable();
    crossings
}

/// Whether the segment ab crosses triangle pqr: a and b strictly on opposite sides of its plane, and
/// the line through them meeting the closed triangle. Touching and coplanar segments do not cross.
#[inline]
pub fn segment_crosses_triangle(a: DVec3, b: DVec3, [p, q, r]: [DVec3; 3]) -> bool {
    let side_a = orient3d(p, q, r, a);
    let side_b = orient3d(p, q, r, b);
    if side_a == 0 || side_b == 0 || side_a == side_b {
        return false;
    }
    let s = [orient3d(a, b, p, q), orient3d(a, b, q, r), orient3d(a, b, r, p)];
    !(s.contains(&1) && s.contains(&-1))
}

/// The undirected edges of a triangle list, each once, smaller vertex first, sorted. Written into
/// `edges` (cleared first) so that a caller can keep the buffer.
pub(crate) fn unique_edges_into(triangles: &[[u32; 3]], edges: &mut Vec<[u32; 2]>) {
    edges.clear();
    for &[a, b, c] in triangles {
        for (i, j) in [(a, b), (b, c), (c, a)] {
            if i != j {
                edges.push([i.min(j), i.max(j)]);
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
}

/// Calls `found` with every crossing, testing at most `budget` candidate pairs.
fn for_each_crossing(
    vertices: &[DVec3],
    triangles: &[[u32; 3]],
    budget: usize,
    mut found: impl FnMut(EdgeTriangleCrossing),
) -> Result<(), CountAbandoned> {
    let corners = |t: [u32; 3]| t.map(|i| vertices[i as usize]);
    let mut tree = Bvh::default();
    tree.boxes.extend(triangles.iter().map(|&t| Aabb::from_points(corners(t))));
    tree.build();
    let mut edges = Vec::new();
    unique_edges_into(triangles, &mut edges);
    let mut stack = Vec::new();
    let mut candidates = 0usize;
    for &edge in &edges {
        if candidates > budget {
            return Err(CountAbandoned { candidates });
        }
        let [a, b] = edge.map(|i| vertices[i as usize]);
        tree.query(&Aabb::from_points([a, b]), &mut stack, |t| {
            candidates += 1;
            let tri = triangles[t as usize];
            if !tri.contains(&edge[0])
                && !tri.contains(&edge[1])
                && segment_crosses_triangle(a, b, corners(tri))
            {
                found(EdgeTriangleCrossing { edge, triangle: t });
            }
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DiagonalPattern, MaterialMesh};

    /// Every (edge, triangle) pair tested, no broad phase: the reference the tree must reproduce.
    fn brute_force(vertices: &[DVec3], triangles: &[[u32; 3]]) -> Vec<EdgeTriangleCrossing> {
        let mut edges = Vec::new();
        unique_edges_into(triangles, &mut edges);
        let mut out = Vec::new();
        for &edge in &edges {
            for (t, tri) in triangles.iter().enumerate() {
                if tri.contains(&edge[0]) || tri.contains(&edge[1]) {
                    continue;
                }
                let [a, b] = edge.map(|i| vertices[i as usize]);
                if segment_crosses_triangle(a, b, tri.map(|i| vertices[i as usize])) {
                    out.push(EdgeTriangleCrossing { edge, triangle: t as u32 });
                }
            }
        }
        out
    }

    /// An n × n grid sheet over [0, 1]², bent along x into the polyline `path` (arc-length
    /// parametrised by the grid's x), extruded along y.
    fn bent_sheet(n: usize, path: &[[f64; 2]]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let mesh = MaterialMesh::grid(n, 1.0, DiagonalPattern::Alternating).unwrap();
        let lengths: Vec<f64> =
            path.windows(2).map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1])).collect();
        let total: f64 = lengths.iter().sum();
        let vertices = mesh
            .rest()
            .iter()
            .map(|x| {
                let mut s = x.x * total;
                let mut k = 0;
                while k + 1 < lengths.len() && s > lengths[k] {
                    s -= lengths[k];
                    k += 1;
                }
                let f = s / lengths[k];
                let (p, q) = (path[k], path[k + 1]);
                DVec3::new(p[0] + f * (q[0] - p[0]), x.y, p[1] + f * (q[1] - p[1]))
            })
            .collect();
        (vertices, mesh.triangles().to_vec())
    }

    #[test]
    fn two_crossing_triangles_are_counted() {
        // Triangle 0 flat on z = 0; triangle 1 vertical, one edge piercing triangle 0 and triangle 0's
        // edge (0, 1) piercing triangle 1.
        let vertices = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
            DVec3::new(0.5, 0.5, -1.0),
            DVec3::new(0.5, 0.5, 1.0),
            DVec3::new(0.5, -1.0, 0.3),
        ];
        let triangles = vec![[0, 1, 2], [3, 4, 5]];
        let crossings = self_intersections(&vertices, &triangles);
        assert_eq!(
            crossings,
            vec![
                EdgeTriangleCrossing { edge: [0, 1], triangle: 1 },
                EdgeTriangleCrossing { edge: [3, 4], triangle: 0 },
            ]
        );
        assert_eq!(count_self_intersections(&vertices, &triangles), 2);
        // Lift triangle 1 clear of triangle 0: nothing crosses.
        let lifted: Vec<DVec3> =
            vertices.iter().enumerate().map(|(i, &v)| if i >= 3 { v + DVec3::Z * 1.5 } else { v }).collect();
        assert_eq!(count_self_intersections(&lifted, &triangles), 0);
    }

    #[test]
    fn flat_and_gently_curved_sheets_have_no_crossings() {
        let mesh = MaterialMesh::grid(17, 1.0, DiagonalPattern::Uniform).unwrap();
        let flat = mesh.place(DVec3::ZERO, DVec3::X, DVec3::Y);
        assert_eq!(count_self_intersections(&flat, mesh.triangles()), 0);
        let wavy: Vec<DVec3> = flat.iter().map(|p| p + DVec3::Z * (6.0 * p.x).sin() * 0.2).collect();
        assert_eq!(count_self_intersections(&wavy, mesh.triangles()), 0);
        // A sheet folded exactly onto itself is touching everywhere, crossing nowhere.
        let (folded, triangles) = bent_sheet(17, &[[0.0, 0.0], [0.5, 0.0], [0.0, 0.0]]);
        assert_eq!(count_self_intersections(&folded, &triangles), 0);
    }

    #[test]
    fn sheet_folded_through_itself_is_counted_and_matches_brute_force() {
        // A Z-fold whose third panel comes back down through the first.
        let (vertices, triangles) = bent_sheet(15, &[[0.0, 0.0], [1.0, 0.0], [0.2, 0.3], [0.61, -0.3]]);
        let crossings = self_intersections(&vertices, &triangles);
        assert!(
            crossings.len() >= 14,
            "one crossing line across the 14 columns of squares: {}",
            crossings.len()
        );
        assert_eq!(crossings, brute_force(&vertices, &triangles));
    }

    #[test]
    fn pairs_sharing_a_vertex_are_not_crossings() {
        // A fan of two triangles around vertex 0, the second standing through the first: its edges out
        // of vertex 0 meet triangle 0 only at the shared corner (excluded), while its far edge (3, 4)
        // pierces triangle 0 and is the one crossing.
        let vertices = vec![
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::new(0.5, 0.2, 1.0),
            DVec3::new(0.5, 0.2, -1.0),
        ];
        let triangles = vec![[0, 1, 2], [0, 3, 4]];
        assert_eq!(
            self_intersections(&vertices, &triangles),
            vec![EdgeTriangleCrossing { edge: [3, 4], triangle: 0 }]
        );
        assert_eq!(brute_force(&vertices, &triangles).len(), 1);
        // The geometric rule alone agrees: a segment from a corner of the triangle only touches it.
        assert!(!segment_crosses_triangle(vertices[0], vertices[4], [vertices[0], vertices[1], vertices[2]]));
    }

    #[test]
    fn edge_in_the_triangle_plane_is_not_a_crossing() {
        let vertices = vec![
            DVec3::ZERO,
            DVec3::X * 2.0,
            DVec3::Y * 2.0,
            DVec3::new(0.2, 0.2, 0.0),
            DVec3::new(0.6, 0.3, 0.0),
            DVec3::new(0.4, 0.9, 1.0),
        ];
        assert_eq!(count_self_intersections(&vertices, &[[0, 1, 2], [3, 4, 5]]), 0);
    }
}
