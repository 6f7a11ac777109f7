//! The broad phase for a moving cloth: which vertex–triangle and edge–edge pairs could come within
//! the thickness of each other during one step.
//!
//! Each element's box encloses its positions at the start and at the end of the step (a vertex moving
//! linearly stays inside the box of its two ends, and so does every point of an edge or triangle whose
//! corners move linearly), grown by half the thickness, so two elements that come within the thickness
//! of each other at any time of the step have overlapping boxes. The boxes of triangles and of edges
//! go into two [`Bvh`]s built when the topology changes and refitted on every other step; each vertex
//! queries the triangle tree and each edge the edge tree. Pairs that share a vertex are skipped: they
//! touch by construction, and keeping them apart is the cloth's own springs' job.

use glam::DVec3;

use super::bvh::Bvh;
use super::crossings::unique_edges_into;
use crate::Aabb;

/// A vertex and a triangle (not one of its corners) whose swept boxes overlap.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct VertexTrianglePair {
    pub vertex: u32,
    /// Index into the triangle list.
    pub triangle: u32,
}

/// Two edges without a common vertex whose swept boxes overlap, each as its two vertices (smaller
/// first), the pair ordered so that `edges[0] < edges[1]`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EdgeEdgePair {
    pub edges: [[u32; 2]; 2],
}

/// Candidate pairs for self-contact over one step, with the trees and buffers kept between steps so
/// that [`SelfContactBroadPhase::update`] allocates nothing once the buffers have grown to the mesh.
///
/// ```
/// use anima_geom::{DVec3, SelfContactBroadPhase};
///
/// // A vertex falling onto a triangle from above over one step.
/// let triangles = [[0, 1, 2]];
/// let start = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.2, 0.2, 1.0)];
/// let end = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.2, 0.2, -1.0)];
/// let mut broad = SelfContactBroadPhase::new();
/// broad.update(&triangles, &start, &end, 1.0e-3);
/// assert_eq!(broad.vertex_triangle_pairs().len(), 1);
/// ```
#[derive(Debug, Clone, Default)]
pub struct SelfContactBroadPhase {
    triangles: Vec<[u32; 3]>,
    edges: Vec<[u32; 2]>,
    triangle_tree: Bvh,
    edge_tree: Bvh,
    /// Swept vertex boxes, for [`SelfContactBroadPhase::update_moved`]'s queries from the triangles.
    vertex_tree: Bvh,
    stack: Vec<u32>,
    vertex_triangle: Vec<VertexTrianglePair>,
    edge_edge: Vec<EdgeEdgePair>,
    rebuild: bool,
}

impl SelfContactBroadPhase {
    /// An empty broad phase; the first [`update`](Self::update) builds its trees.
    pub fn new() -> Self {
        Self { rebuild: true, ..Self::default() }
    }

    /// The swept boxes of the step, grown by half the thickness, and the trees over them (rebuilt when
    /// the triangles changed, refitted otherwise).
    fn fit(&mut self, triangles: &[[u32; 3]], start: &[DVec3], end: &[DVec3], thickness: f64) {
        assert_eq!(start.len(), end.len(), "start and end positions must have one entry per vertex");
        assert!(thickness >= 0.0 && thickness.is_finite(), "thickness must be finite and non-negative");
        if self.triangles != triangles {
            self.triangles.clear();
            self.triangles.extend_from_slice(triangles);
            unique_edges_into(triangles, &mut self.edges);
            self.rebuild = true;
        }
        let pad = 0.5 * thickness;
        let swept = |i: u32| [start[i as usize], end[i as usize]];
        self.triangle_tree.boxes.clear();
        self.triangle_tree.boxes.extend(self.triangles.iter().map(|t| {
            let [[a0, a1], [b0, b1], [c0, c1]] = t.map(swept);
            grown(Aabb::from_points([a0, a1, b0, b1, c0, c1]), pad)
        }));
        self.edge_tree.boxes.clear();
        self.edge_tree.boxes.extend(self.edges.iter().map(|e| {
            let [[a0, a1], [b0, b1]] = e.map(swept);
            grown(Aabb::from_points([a0, a1, b0, b1]), pad)
        }));
        self.vertex_tree.boxes.clear();
        self.vertex_tree
            .boxes
            .extend(start.iter().zip(end).map(|(&x0, &x1)| grown(Aabb::from_points([x0, x1]), pad)));
        if self.rebuild {
            self.triangle_tree.build();
            self.edge_tree.build();
            self.vertex_tree.build();
            self.rebuild = false;
        } else {
            self.triangle_tree.refit();
            self.edge_tree.refit();
            self.vertex_tree.refit();
        }
    }

    /// Finds the candidate pairs of the step that moves vertex i linearly from `start[i]` to `end[i]`,
    /// for cloth of the given thickness (m): every vertex–triangle and edge–edge pair without a shared
    /// vertex that comes within `thickness` during the step is among them.
    ///
    /// The trees are rebuilt when `triangles` differs from the previous call's (remeshing) or after
    /// [`request_rebuild`](Self::request_rebuild), and refitted otherwise.
    ///
    /// # Panics
    /// If `start` and `end` differ in length, a triangle names a vertex outside them, or the thickness
    /// is negative or not finite.
    pub fn update(&mut self, triangles: &[[u32; 3]], start: &[DVec3], end: &[DVec3], thickness: f64) {
        self.fit(triangles, start, end, thickness);
        self.vertex_triangle.clear();
        for v in 0..start.len() as u32 {
            self.query_vertex(v);
        }

        self.edge_edge.clear();
        for e in 0..self.edges.len() {
            self.query_edge(e, |_, f| f > e);
        }
    }

    /// The candidate pairs of a step whose trajectories differ from the previous update's only at the
    /// vertices marked in `moved` (and the thickness may differ): the pairs with at least one moved
    /// vertex, found by querying from the moved vertices, the triangles and the edges that hold one.
    /// With `keep`, the previous update's pairs without a moved vertex stay too (their swept boxes have
    /// not changed, so they are still candidates when the thickness has not grown); without it, only
    /// the new pairs are listed — what a pass needs that has already tested the others on the same
    /// trajectories. Every pair is listed once; the trees are refitted.
    ///
    /// # Panics
    /// If the triangles are not the previous update's, or as [`update`](Self::update).
    pub fn update_moved(
        &mut self,
        triangles: &[[u32; 3]],
        start: &[DVec3],
        end: &[DVec3],
        thickness: f64,
        moved: &[bool],
        keep: bool,
    ) {
        assert!(
            self.triangles == triangles && !self.rebuild,
            "update_moved follows an update of the same mesh"
        );
        assert_eq!(moved.len(), start.len(), "one flag per vertex");
        self.fit(triangles, start, end, thickness);
        let moved_edge = |edges: &[[u32; 2]], e: usize| edges[e].iter().any(|&i| moved[i as usize]);
        if keep {
            let tris = &self.triangles;
            let moved_triangle = |t: u32| tris[t as usize].iter().any(|&i| moved[i as usize]);
            self.vertex_triangle.retain(|p| !moved[p.vertex as usize] && !moved_triangle(p.triangle));
            self.edge_edge.retain(|p| !p.edges.iter().flatten().any(|&i| moved[i as usize]));
        } else {
            self.vertex_triangle.clear();
            self.edge_edge.clear();
        }
        for v in 0..start.len() as u32 {
            if moved[v as usize] {
                self.query_vertex(v);
            }
        }
        // A triangle with a moved corner meets the vertices that did not move (the moved ones found it).
        for t in 0..self.triangles.len() as u32 {
            let corners = self.triangles[t as usize];
            if !corners.iter().any(|&i| moved[i as usize]) {
                continue;
            }
            let query = self.triangle_tree.boxes[t as usize];
            let pairs = &mut self.vertex_triangle;
            self.vertex_tree.query(&query, &mut self.stack, |vertex| {
                if !moved[vertex as usize] && !corners.contains(&vertex) {
                    pairs.push(VertexTrianglePair { vertex, triangle: t });
                }
            });
        }
        for e in 0..self.edges.len() {
            if moved_edge(&self.edges, e) {
                // A pair of two moved edges is listed from the one with the smaller index.
                self.query_edge(e, |edges, f| f > e || !moved_edge(edges, f));
            }
        }
    }

    /// Lists the triangles whose boxes overlap vertex `v`'s, not holding it.
    fn query_vertex(&mut self, vertex: u32) {
        let query = self.vertex_tree.boxes[vertex as usize];
        let (triangles, pairs) = (&self.triangles, &mut self.vertex_triangle);
        self.triangle_tree.query(&query, &mut self.stack, |t| {
            if !triangles[t as usize].contains(&vertex) {
                pairs.push(VertexTrianglePair { vertex, triangle: t });
            }
        });
    }

    /// Lists the edges whose boxes overlap edge `e`'s, share no vertex with it and pass `accept`
    /// (given the edge list and the other edge's index), as pairs ordered by index.
    fn query_edge(&mut self, e: usize, accept: impl Fn(&[[u32; 2]], usize) -> bool) {
        let query = self.edge_tree.boxes[e];
        let edge = self.edges[e];
        let (edges, pairs) = (&self.edges, &mut self.edge_edge);
        self.edge_tree.query(&query, &mut self.stack, |f| {
            let other = edges[f as usize];
            if accept(edges, f as usize) && !other.contains(&edge[0]) && !other.contains(&edge[1]) {
                let (first, second) = if (f as usize) > e { (edge, other) } else { (other, edge) };
                pairs.push(EdgeEdgePair { edges: [first, second] });
            }
        });
    }

    /// Makes the next [`update`](Self::update) rebuild the trees instead of refitting them: worth
    /// doing now and then when the cloth has deformed so much that the refitted boxes overlap widely.
    pub fn request_rebuild(&mut self) {
        self.rebuild = true;
    }

    /// Vertex–triangle candidates of the last update.
    pub fn vertex_triangle_pairs(&self) -> &[VertexTrianglePair] {
        &self.vertex_triangle
    }

    /// Edge–edge candidates of the last update.
    pub fn edge_edge_pairs(&self) -> &[EdgeEdgePair] {
        &self.edge_edge
    }

    /// The mesh's undirected edges, each once, smaller vertex first, sorted.
    pub fn edges(&self) -> &[[u32; 2]] {
        &self.edges
    }
}

/// `b` grown by `pad` on every side, plus a few ulps of its coordinates so that positions interpolated
/// in floating point between the step's ends cannot fall outside.
fn grown(b: Aabb, pad: f64) -> Aabb {
    let scale = b.min.abs().max(b.max.abs()).max_element();
    let r = DVec3::splat(pad + 8.0 * f64::EPSILON * scale);
    Aabb { min: b.min - r, max: b.max + r }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DiagonalPattern, MaterialMesh};

    #[test]
    fn adjacent_elements_are_never_candidates() {
        let mesh = MaterialMesh::grid(6, 1.0, DiagonalPattern::Alternating).unwrap();
        let x = mesh.place(DVec3::ZERO, DVec3::X, DVec3::Y);
        let mut broad = SelfContactBroadPhase::new();
        broad.update(mesh.triangles(), &x, &x, 0.05);
        for p in broad.vertex_triangle_pairs() {
            assert!(!mesh.triangles()[p.triangle as usize].contains(&p.vertex), "{p:?}");
        }
        for p in broad.edge_edge_pairs() {
            let [a, b] = p.edges;
            assert!(!b.contains(&a[0]) && !b.contains(&a[1]) && a < b, "{p:?}");
        }
        assert_eq!(broad.edges().len(), mesh.n_edges());
    }

    #[test]
    fn updates_after_warm_up_allocate_nothing() {
        // Warm up on the step with the most pairs (thick), then steps with fewer must reuse every
        // buffer: same addresses, same capacities.
        let mesh = MaterialMesh::grid(9, 1.0, DiagonalPattern::Alternating).unwrap();
        let x = mesh.place(DVec3::ZERO, DVec3::X, DVec3::Y);
        let wavy: Vec<DVec3> = x.iter().map(|p| *p + DVec3::Z * (5.0 * p.x).sin() * 0.01).collect();
        let mut broad = SelfContactBroadPhase::new();
        broad.update(mesh.triangles(), &x, &wavy, 0.3);
        let fingerprint = |b: &SelfContactBroadPhase| {
            [
                (b.triangles.as_ptr() as usize, b.triangles.capacity()),
                (b.edges.as_ptr() as usize, b.edges.capacity()),
                (b.stack.as_ptr() as usize, b.stack.capacity()),
                (b.vertex_triangle.as_ptr() as usize, b.vertex_triangle.capacity()),
                (b.edge_edge.as_ptr() as usize, b.edge_edge.capacity()),
                (b.triangle_tree.boxes.as_ptr() as usize, b.triangle_tree.boxes.capacity()),
                (b.edge_tree.boxes.as_ptr() as usize, b.edge_tree.boxes.capacity()),
            ]
        };
        let warm = fingerprint(&broad);
        for step in 0..5 {
            broad.update(mesh.triangles(), &wavy, &x, 0.01 * step as f64);
            assert_eq!(fingerprint(&broad), warm, "step {step}");
            broad.request_rebuild();
        }
    }

    #[test]
    fn moved_updates_find_what_a_full_update_finds() {
        // A wavy sheet folded over onto itself (two layers 0.15 apart), then some vertices given a
        // different end: the incremental update must list exactly the pairs a full update lists (with
        // `keep`), or exactly those with a moved vertex (without), each once.
        let mesh = MaterialMesh::grid(9, 1.0, DiagonalPattern::Alternating).unwrap();
        let fold = |p: DVec3| {
            if p.x < 0.5 { p } else { DVec3::new(1.0 - p.x, p.y, 0.15 + 0.02 * (7.0 * p.y).sin()) }
        };
        let start: Vec<DVec3> = mesh.place(DVec3::ZERO, DVec3::X, DVec3::Y).into_iter().map(fold).collect();
        let end: Vec<DVec3> = start.iter().map(|p| *p + DVec3::new(0.01, 0.0, -0.02 * p.z)).collect();
        let moved: Vec<bool> = (0..start.len()).map(|i| i % 7 == 3 || i % 11 == 0).collect();
        let end2: Vec<DVec3> =
            end.iter().zip(&moved).map(|(p, &m)| if m { *p - DVec3::Z * 0.12 } else { *p }).collect();
        let sorted = |b: &SelfContactBroadPhase| {
            let mut vt = b.vertex_triangle_pairs().to_vec();
            let mut ee = b.edge_edge_pairs().to_vec();
            let (n_vt, n_ee) = (vt.len(), ee.len());
            vt.sort_unstable();
            ee.sort_unstable();
            vt.dedup();
            ee.dedup();
            assert_eq!((vt.len(), ee.len()), (n_vt, n_ee), "a pair listed twice");
            (vt, ee)
        };
        let mut full = SelfContactBroadPhase::new();
        full.update(mesh.triangles(), &start, &end, 0.05);
        full.update(mesh.triangles(), &start, &end2, 0.03);
        let (vt_full, ee_full) = sorted(&full);

        let mut kept = SelfContactBroadPhase::new();
        kept.update(mesh.triangles(), &start, &end, 0.05);
        kept.update_moved(mesh.triangles(), &start, &end2, 0.03, &moved, true);
        let (vt_kept, ee_kept) = sorted(&kept);
        // Kept pairs were found with the thicker pad: a superset, and equal on the moved part.
        let has_moved_vt = |p: &VertexTrianglePair| {
            moved[p.vertex as usize]
                || mesh.triangles()[p.triangle as usize].iter().any(|&i| moved[i as usize])
        };
        let has_moved_ee = |p: &EdgeEdgePair| p.edges.iter().flatten().any(|&i| moved[i as usize]);
        assert!(vt_full.iter().all(|p| vt_kept.binary_search(p).is_ok()));
        assert!(ee_full.iter().all(|p| ee_kept.binary_search(p).is_ok()));
        let moved_only = |vt: &[VertexTrianglePair], ee: &[EdgeEdgePair]| {
            (
                vt.iter().filter(|p| has_moved_vt(p)).copied().collect::<Vec<_>>(),
                ee.iter().filter(|p| has_moved_ee(p)).copied().collect::<Vec<_>>(),
            )
        };
        let expected = moved_only(&vt_full, &ee_full);
        assert!(!expected.0.is_empty() && !expected.1.is_empty(), "the test must move pairs");
        assert_eq!(moved_only(&vt_kept, &ee_kept), expected);

        let mut fresh = SelfContactBroadPhase::new();
        fresh.update(mesh.triangles(), &start, &end, 0.05);
        fresh.update_moved(mesh.triangles(), &start, &end2, 0.03, &moved, false);
        assert_eq!(sorted(&fresh), expected);
    }

    #[test]
    fn distant_layers_give_no_pairs_and_close_ones_do() {
        // Two separate flat sheets 0.1 apart; thickness decides whether they are candidates.
        let mesh = MaterialMesh::grid(5, 1.0, DiagonalPattern::Uniform).unwrap();
        let n = mesh.n_vertices() as u32;
        let mut triangles = mesh.triangles().to_vec();
        triangles.extend(mesh.triangles().iter().map(|t| t.map(|i| i + n)));
        let mut x = mesh.place(DVec3::ZERO, DVec3::X, DVec3::Y);
        x.extend(mesh.place(DVec3::Z * 0.1, DVec3::X, DVec3::Y));
        let mut broad = SelfContactBroadPhase::new();
        broad.update(&triangles, &x, &x, 0.05);
        let across = |p: &VertexTrianglePair| (p.vertex < n) != (triangles[p.triangle as usize][0] < n);
        assert!(!broad.vertex_triangle_pairs().iter().any(across));
        broad.update(&triangles, &x, &x, 0.11);
        assert!(broad.vertex_triangle_pairs().iter().any(across));
        // The upper sheet dropping through the lower over one step is a candidate at any thickness.
        let end: Vec<DVec3> = x
            .iter()
            .enumerate()
            .map(|(i, &p)| if i >= n as usize { p - DVec3::Z * 0.3 } else { p })
            .collect();
        broad.update(&triangles, &x, &end, 0.0);
        assert!(broad.vertex_triangle_pairs().iter().any(across));
    }
}
