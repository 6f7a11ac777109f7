//! The broad phase for a moving cloth: which vertex–triangle and edge–edge pairs could come within
//! the thickness of each other during one step.
//!
//! Each element's box encloses its positions at the start and at the end of the step (a vertex moving
//! linearly stays inside the box of its two ends, and so does every point of an edge or triangle whose
//! corners move linearly), grown by half the thickness, so two elements that come within the thickness
//! of each other at any time of the step have overlapping boxes. Pairs that share a vertex are skipped:
//! they touch by construction, and keeping them apart is the cloth's own springs' job.
//!
//! The triangles go into one tree ([`super::patch_tree`]), built when the topology changes and refitted
//! every step, whose nodes also know the cone of their normals over the step. The tree is walked
//! against itself, pairs of nodes whose boxes overlap, and a node that is one edge-connected piece of
//! cloth staying nearly flat over the step is not looked into at all: most of a draped or falling
//! cloth is such pieces, and the pairs of neighbouring elements inside them, whose boxes overlap
//! wherever the cloth is, were most of the work. From each pair of triangles whose boxes overlap come
//! the pairs of their features; every vertex and every edge belongs to one triangle (the first that
//! has it), and a feature is only paired from its own triangle, so each pair is listed once.

use glam::DVec3;

use super::crossings::unique_edges_into;
use super::patch_tree::{PatchTree, Visitor};
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

/// Candidate pairs for self-contact over one step, with the tree and buffers kept between steps so
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
    /// Per triangle, the corners (bit k: corner k) and the edges (bit k: corner k to corner k + 1)
    /// that belong to it.
    own_corners: Vec<u8>,
    own_edges: Vec<u8>,
    /// Vertices of no triangle (particles beside the surface), paired by a query of their own.
    loose: Vec<u32>,
    stack: Vec<u32>,
    tree: PatchTree,
    /// Swept vertex boxes grown by half the thickness, and the triangles' boxes (their unions).
    vertex_boxes: Vec<Aabb>,
    triangle_boxes: Vec<Aabb>,
    vertex_triangle: Vec<VertexTrianglePair>,
    edge_edge: Vec<EdgeEdgePair>,
    rebuild: bool,
    /// Whether flat, connected pieces are skipped (on unless turned off for a check against the pairs of
    /// every box overlap).
    no_flat_pieces: bool,
}

/// The pairs found for a pair of leaves, with the broad phase's borrowed state.
struct Collect<'a> {
    triangles: &'a [[u32; 3]],
    order: &'a [u32],
    own_corners: &'a [u8],
    own_edges: &'a [u8],
    vertex_boxes: &'a [Aabb],
    triangle_boxes: &'a [Aabb],
    moved: Option<&'a [bool]>,
    vertex_triangle: &'a mut Vec<VertexTrianglePair>,
    edge_edge: &'a mut Vec<EdgeEdgePair>,
}

impl Collect<'_> {
    fn pair(&mut self, t1: u32, t2: u32) {
        let (a, b) = (self.triangles[t1 as usize], self.triangles[t2 as usize]);
        if !self.triangle_boxes[t1 as usize].overlaps(&self.triangle_boxes[t2 as usize]) {
            return;
        }
        let moved = |ids: &[u32]| self.moved.is_none_or(|m| ids.iter().any(|&i| m[i as usize]));
        // Corners of one triangle against the other.
        for (own, tri, other, t_other) in
            [(self.own_corners[t1 as usize], a, b, t2), (self.own_corners[t2 as usize], b, a, t1)]
        {
            for (k, &v) in tri.iter().enumerate() {
                if own & (1 << k) == 0 || other.contains(&v) {
                    continue;
                }
                if self.vertex_boxes[v as usize].overlaps(&self.triangle_boxes[t_other as usize])
                    && moved(&[v, other[0], other[1], other[2]])
                {
                    self.vertex_triangle.push(VertexTrianglePair { vertex: v, triangle: t_other });
                }
            }
        }
        // Edges of one against edges of the other.
        let (ea, eb) = (self.own_edges[t1 as usize], self.own_edges[t2 as usize]);
        if ea == 0 || eb == 0 {
            return;
        }
        for k in 0..3 {
            if ea & (1 << k) == 0 {
                continue;
            }
            let e = [a[k], a[(k + 1) % 3]];
            let box_e = self.vertex_boxes[e[0] as usize].union(self.vertex_boxes[e[1] as usize]);
            for l in 0..3 {
                if eb & (1 << l) == 0 {
                    continue;
                }
                let f = [b[l], b[(l + 1) % 3]];
                if f.contains(&e[0]) || f.contains(&e[1]) {
                    continue;
                }
                let box_f = self.vertex_boxes[f[0] as usize].union(self.vertex_boxes[f[1] as usize]);
                if box_e.overlaps(&box_f) && moved(&[e[0], e[1], f[0], f[1]]) {
                    let (e, f) = ([e[0].min(e[1]), e[0].max(e[1])], [f[0].min(f[1]), f[0].max(f[1])]);
                    self.edge_edge.push(EdgeEdgePair { edges: if e < f { [e, f] } else { [f, e] } });
                }
            }
        }
    }
}

impl Visitor for Collect<'_> {
    fn leaves(&mut self, a: std::ops::Range<usize>, b: std::ops::Range<usize>) {
        let same = a == b;
        for i in a {
            let b = if same { i + 1..b.end } else { b.clone() };
            for j in b {
                self.pair(self.order[i], self.order[j]);
            }
        }
    }
}

impl SelfContactBroadPhase {
    /// An empty broad phase; the first [`update`](Self::update) builds its tree.
    pub fn new() -> Self {
        Self { rebuild: true, ..Self::default() }
    }

    /// Turns off the skipping of flat, connected pieces: every pair of elements whose boxes overlap is
    /// then listed (what tests compare the tree's pairs with).
    pub fn list_every_overlap(&mut self) {
        self.no_flat_pieces = true;
    }

    /// The swept boxes of the step, grown by half the thickness, and the tree over them (rebuilt when the
    /// triangles changed, refitted otherwise), with the triangles that hold a moved vertex marked.
    fn fit(
        &mut self,
        triangles: &[[u32; 3]],
        start: &[DVec3],
        end: &[DVec3],
        thickness: f64,
        moved: Option<&[bool]>,
    ) {
        assert_eq!(start.len(), end.len(), "start and end positions must have one entry per vertex");
        assert!(thickness >= 0.0 && thickness.is_finite(), "thickness must be finite and non-negative");
        if self.triangles != triangles {
            self.triangles.clear();
            self.triangles.extend_from_slice(triangles);
            unique_edges_into(triangles, &mut self.edges);
            self.assign_features(start.len());
            self.rebuild = true;
        }
        let pad = 0.5 * thickness;
        self.vertex_boxes.clear();
        self.vertex_boxes
            .extend(start.iter().zip(end).map(|(&x0, &x1)| grown(Aabb::from_points([x0, x1]), pad)));
        self.triangle_boxes.clear();
        let boxes = &self.vertex_boxes;
        self.triangle_boxes.extend(
            self.triangles
                .iter()
                .map(|t| boxes[t[0] as usize].union(boxes[t[1] as usize]).union(boxes[t[2] as usize])),
        );
        if self.rebuild || self.tree.is_empty() != self.triangles.is_empty() {
            self.tree.build(&self.triangle_boxes, &self.triangles);
            self.rebuild = false;
        }
        self.tree.refit(&self.triangle_boxes, &self.triangles, start, end, moved);
    }

    /// Each vertex and edge belongs to the first triangle that has it.
    fn assign_features(&mut self, n_vertices: usize) {
        self.own_corners.clear();
        self.own_corners.resize(self.triangles.len(), 0);
        self.own_edges.clear();
        self.own_edges.resize(self.triangles.len(), 0);
        let mut vertex_taken = vec![false; n_vertices];
        self.loose.clear();
        let mut edge_taken = std::collections::HashSet::with_capacity(self.edges.len());
        for (t, tri) in self.triangles.iter().enumerate() {
            for k in 0..3 {
                let v = tri[k] as usize;
                if !vertex_taken[v] {
                    vertex_taken[v] = true;
                    self.own_corners[t] |= 1 << k;
                }
                let (i, j) = (tri[k], tri[(k + 1) % 3]);
                if i != j && edge_taken.insert([i.min(j), i.max(j)]) {
                    self.own_edges[t] |= 1 << k;
                }
            }
        }
        self.loose.extend((0..n_vertices as u32).filter(|&v| !vertex_taken[v as usize]));
    }

    fn collect(&mut self, moved: Option<&[bool]>) {
        let mut collect = Collect {
            triangles: &self.triangles,
            order: &self.tree.order,
            own_corners: &self.own_corners,
            own_edges: &self.own_edges,
            vertex_boxes: &self.vertex_boxes,
            triangle_boxes: &self.triangle_boxes,
            moved,
            vertex_triangle: &mut self.vertex_triangle,
            edge_edge: &mut self.edge_edge,
        };
        self.tree.self_pairs(moved.is_some(), !self.no_flat_pieces, &mut collect);
        // Vertices of no triangle against the triangles their boxes meet.
        for &v in &self.loose {
            let query = self.vertex_boxes[v as usize];
            let moved_v = moved.is_some_and(|m| m[v as usize]);
            let (triangles, order, boxes) = (&self.triangles, &self.tree.order, &self.triangle_boxes);
            let pairs = &mut self.vertex_triangle;
            self.tree.query(&query, moved.is_some() && !moved_v, &mut self.stack, |slots| {
                for slot in slots {
                    let t = order[slot];
                    let tri = triangles[t as usize];
                    let any_moved = moved.is_none_or(|m| moved_v || tri.iter().any(|&i| m[i as usize]));
                    if !tri.contains(&v) && boxes[t as usize].overlaps(&query) && any_moved {
                        pairs.push(VertexTrianglePair { vertex: v, triangle: t });
                    }
                }
            });
        }
    }

    /// Finds the candidate pairs of the step that moves vertex i linearly from `start[i]` to `end[i]`,
    /// for cloth of the given thickness (m): every vertex–triangle and edge–edge pair without a shared
    /// vertex that comes within `thickness` during the step is among them, except those inside a piece
    /// of cloth that stays nearly flat over the step (module docs), which cannot.
    ///
    /// The tree is rebuilt when `triangles` differs from the previous call's (remeshing) or after
    /// [`request_rebuild`](Self::request_rebuild), and refitted otherwise.
    ///
    /// # Panics
    /// If `start` and `end` differ in length, a triangle names a vertex outside them, or the thickness
    /// is negative or not finite.
    pub fn update(&mut self, triangles: &[[u32; 3]], start: &[DVec3], end: &[DVec3], thickness: f64) {
        self.fit(triangles, start, end, thickness, None);
        self.vertex_triangle.clear();
        self.edge_edge.clear();
        self.collect(None);
    }

    /// The candidate pairs of a step whose trajectories differ from the previous update's only at the
    /// vertices marked in `moved` (and the thickness may differ): the pairs with at least one moved
    /// vertex, found by walking the tree only where a node holds one. With `keep`, the previous update's
    /// pairs without a moved vertex stay too (their swept boxes have not changed, so they are still
    /// candidates when the thickness has not grown); without it, only the new pairs are listed — what a
    /// pass needs that has already tested the others on the same trajectories. Every pair is listed once.
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
        self.fit(triangles, start, end, thickness, Some(moved));
        if keep {
            let tris = &self.triangles;
            let moved_triangle = |t: u32| tris[t as usize].iter().any(|&i| moved[i as usize]);
            self.vertex_triangle.retain(|p| !moved[p.vertex as usize] && !moved_triangle(p.triangle));
            self.edge_edge.retain(|p| !p.edges.iter().flatten().any(|&i| moved[i as usize]));
        } else {
            self.vertex_triangle.clear();
            self.edge_edge.clear();
        }
        self.collect(Some(moved));
    }

    /// Makes the next [`update`](Self::update) rebuild the tree instead of refitting it: worth doing
    /// now and then when the cloth has deformed so much that the refitted boxes overlap widely.
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
                (b.vertex_boxes.as_ptr() as usize, b.vertex_boxes.capacity()),
                (b.vertex_triangle.as_ptr() as usize, b.vertex_triangle.capacity()),
                (b.edge_edge.as_ptr() as usize, b.edge_edge.capacity()),
                (b.triangle_boxes.as_ptr() as usize, b.triangle_boxes.capacity()),
                (b.tree.order.as_ptr() as usize, b.tree.order.capacity()),
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
