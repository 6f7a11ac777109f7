//! Half-edge adjacency for a fixed triangle mesh (Mäntylä 1988), in the compact form where the three
//! half-edges of triangle `f` are `3f`, `3f + 1` and `3f + 2`.
//!
//! Half-edge `3f + k` runs from corner `k` of triangle `f` to corner `(k + 1) mod 3`, so `next` and the
//! owning face need no storage; only the twin (the opposite half-edge in the neighbouring triangle) and
//! the undirected edge are stored. The mesh must be an oriented 2-manifold, possibly with boundary: every
//! directed edge is used at most once, which means every edge has one or two faces and the two faces of
//! an interior edge agree on their orientation. [`HalfEdges::new`] refuses anything else.

/// Marks a half-edge with no twin (a boundary half-edge) in [`HalfEdges::twin`].
pub const NO_TWIN: u32 = u32::MAX;

/// Why a triangle list is not an oriented 2-manifold.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TopologyError {
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has {n_vertices} vertices")]
    IndexOutOfRange { triangle: usize, index: u32, n_vertices: usize },
    #[error("triangle {triangle} uses vertex {vertex} twice")]
    RepeatedVertex { triangle: usize, vertex: u32 },
    #[error(
        "the directed edge {from} → {to} is used by triangles {first} and {second}: either the edge has \
         more than two triangles or the two are oriented inconsistently"
    )]
    NonManifoldEdge { from: u32, to: u32, first: usize, second: usize },
    #[error("too many triangles for 32-bit half-edge indices: {0}")]
    TooLarge(usize),
}

/// One undirected edge: its two vertices (in the direction of its first half-edge) and its half-edges.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Edge {
    pub vertices: [u32; 2],
    /// `halves[0]` runs `vertices[0] → vertices[1]`; `halves[1]` is its twin, or [`NO_TWIN`] on the boundary.
    pub halves: [u32; 2],
}

impl Edge {
    /// Whether the edge lies on the mesh boundary (the cloth contour).
    pub fn is_boundary(&self) -> bool {
        self.halves[1] == NO_TWIN
    }
}

/// The four vertices around an interior edge, in the order of the Bridson–Marino–Fedkiw bending element
/// (Oliveira 2013, Fig. 4.3): the edge runs x₃ → x₄ in triangle 1 = (x₃, x₄, x₁) and x₄ → x₃ in
/// triangle 2 = (x₄, x₃, x₂), both listed in their counter-clockwise order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdgeStencil {
    /// [x₁, x₂, x₃, x₄] as vertex indices.
    pub vertices: [u32; 4],
    /// The edge this stencil bends about.
    pub edge: u32,
}

/// Half-edge adjacency of a triangle list.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HalfEdges {
    triangles: Vec<[u32; 3]>,
    twin: Vec<u32>,
    edge_of_half: Vec<u32>,
    edges: Vec<Edge>,
    /// One outgoing half-edge per vertex; for a boundary vertex, the one whose edge is on the boundary
    /// (so that walking the fan with `twin(prev(h))` sweeps every face). [`NO_TWIN`] for unused vertices.
    vertex_half: Vec<u32>,
    boundary_vertex: Vec<bool>,
}

impl HalfEdges {
    /// Builds the adjacency of `triangles` over `n_vertices` vertices, checking that it is an oriented
    /// 2-manifold (with boundary). Edges are numbered in order of first appearance, so the numbering
    /// depends only on the triangle list.
    pub fn new(n_vertices: usize, triangles: &[[u32; 3]]) -> Result<Self, TopologyError> {
        let n_half = triangles.len().checked_mul(3).filter(|&n| n < NO_TWIN as usize);
        let n_half = n_half.ok_or(TopologyError::TooLarge(triangles.len()))?;
        for (t, tri) in triangles.iter().enumerate() {
            for (k, &index) in tri.iter().enumerate() {
                if index as usize >= n_vertices {
                    return Err(TopologyError::IndexOutOfRange { triangle: t, index, n_vertices });
                }
                if tri[(k + 1) % 3] == index {
                    return Err(TopologyError::RepeatedVertex { triangle: t, vertex: index });
                }
            }
        }
        // Sort the directed edges so that a half-edge and its twin can be found by binary search.
        let mut directed: Vec<(u32, u32, u32)> = (0..n_half as u32)
            .map(|h| {
                let tri = triangles[h as usize / 3];
                let k = h as usize % 3;
                (tri[k], tri[(k + 1) % 3], h)
            })
            .collect();
        directed.sort_unstable();
        for w in directed.windows(2) {
            if w[0].0 == w[1].0 && w[0].1 == w[1].1 {
                return Err(TopologyError::NonManifoldEdge {
                    from: w[0].0,
                    to: w[0].1,
                    first: w[0].2 as usize / 3,
                    second: w[1].2 as usize / 3,
                });
            }
        }
        let mut twin = vec![NO_TWIN; n_half];
        for &(a, b, h) in &directed {
            if let Ok(pos) = directed.binary_search_by(|&(x, y, _)| (x, y).cmp(&(b, a))) {
                twin[h as usize] = directed[pos].2;
            }
        }
        let mut edge_of_half = vec![u32::MAX; n_half];
        let mut edges = Vec::with_capacity(n_half / 2 + 1);
        for h in 0..n_half {
            if edge_of_half[h] != u32::MAX {
                continue;
            }
            let e = edges.len() as u32;
            let tw = twin[h];
            edge_of_half[h] = e;
            if tw != NO_TWIN {
                edge_of_half[tw as usize] = e;
            }
            let tri = triangles[h / 3];
            let k = h % 3;
            edges.push(Edge { vertices: [tri[k], tri[(k + 1) % 3]], halves: [h as u32, tw] });
        }
        let mut vertex_half = vec![NO_TWIN; n_vertices];
        let mut boundary_vertex = vec![false; n_vertices];
        for h in 0..n_half {
            let v = triangles[h / 3][h % 3] as usize;
            if twin[h] == NO_TWIN {
                boundary_vertex[v] = true;
                boundary_vertex[triangles[h / 3][(h % 3 + 1) % 3] as usize] = true;
                vertex_half[v] = h as u32;
            } else if vertex_half[v] == NO_TWIN {
                vertex_half[v] = h as u32;
            }
        }
        Ok(Self { triangles: triangles.to_vec(), twin, edge_of_half, edges, vertex_half, boundary_vertex })
    }

    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    pub fn n_vertices(&self) -> usize {
        self.vertex_half.len()
    }

    pub fn n_half_edges(&self) -> usize {
        self.twin.len()
    }

    pub fn n_edges(&self) -> usize {
        self.edges.len()
    }

    pub fn n_faces(&self) -> usize {
        self.triangles.len()
    }

    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// The opposite half-edge, or [`NO_TWIN`] on the boundary.
    #[inline]
    pub fn twin(&self, h: u32) -> u32 {
        self.twin[h as usize]
    }

    /// The next half-edge around the same face.
    #[inline]
    pub fn next(&self, h: u32) -> u32 {
        if h % 3 == 2 { h - 2 } else { h + 1 }
    }

    /// The previous half-edge around the same face.
    #[inline]
    pub fn prev(&self, h: u32) -> u32 {
        if h.is_multiple_of(3) { h + 2 } else { h - 1 }
    }

    #[inline]
    pub fn face(&self, h: u32) -> u32 {
        h / 3
    }

    /// The vertex a half-edge starts from.
    #[inline]
    pub fn origin(&self, h: u32) -> u32 {
        self.triangles[h as usize / 3][h as usize % 3]
    }

    /// The vertex a half-edge points to.
    #[inline]
    pub fn target(&self, h: u32) -> u32 {
        self.origin(self.next(h))
    }

    /// The undirected edge a half-edge belongs to.
    #[inline]
    pub fn edge(&self, h: u32) -> u32 {
        self.edge_of_half[h as usize]
    }

    /// Whether the vertex is on the boundary (cloth contour).
    pub fn is_boundary_vertex(&self, v: u32) -> bool {
        self.boundary_vertex[v as usize]
    }

    /// Number of edges on the boundary.
    pub fn n_boundary_edges(&self) -> usize {
        self.edges.iter().filter(|e| e.is_boundary()).count()
    }

    /// Faces around vertex `v`, walking its fan counter-clockwise from the boundary (if any).
    pub fn vertex_faces(&self, v: u32) -> Vec<u32> {
        let mut out = Vec::new();
        let start = self.vertex_half[v as usize];
        if start == NO_TWIN {
            return out;
        }
        let mut h = start;
        loop {
            out.push(self.face(h));
            let back = self.twin(self.prev(h));
            if back == NO_TWIN || back == start {
                break;
            }
            h = back;
            if out.len() > self.triangles.len() {
                break; // a pinched (non-manifold) vertex; never loop forever
            }
        }
        out
    }

    /// The bending stencil of every interior edge, in edge order (Oliveira 2013, Fig. 4.3).
    pub fn interior_stencils(&self) -> Vec<EdgeStencil> {
        self.edges
            .iter()
            .enumerate()
            .filter(|(_, e)| !e.is_boundary())
            .map(|(i, e)| {
                let [h, t] = e.halves;
                let x3 = self.origin(h);
                let x4 = self.target(h);
                let x1 = self.origin(self.prev(h));
                let x2 = self.origin(self.prev(t));
                EdgeStencil { vertices: [x1, x2, x3, x4], edge: i as u32 }
            })
            .collect()
    }

    /// Checks every structural invariant; returns the first one broken. Cheap enough for tests and
    /// debug assertions, not meant for hot loops.
    pub fn check_invariants(&self) -> Result<(), String> {
        for h in 0..self.n_half_edges() as u32 {
            let t = self.twin(h);
            if t != NO_TWIN {
                if self.twin(t) != h {
                    return Err(format!("twin(twin({h})) = {} ≠ {h}", self.twin(t)));
                }
                if self.origin(t) != self.target(h) || self.target(t) != self.origin(h) {
                    return Err(format!("half-edge {h} and its twin {t} do not run opposite ways"));
                }
                if self.face(t) == self.face(h) {
                    return Err(format!("half-edge {h} is twinned within its own face"));
                }
            }
            if self.next(self.next(self.next(h))) != h || self.prev(self.next(h)) != h {
                return Err(format!("next/prev of {h} do not close the face"));
            }
            let e = self.edges[self.edge(h) as usize];
            if !e.halves.contains(&h) {
                return Err(format!("edge {} does not list its half-edge {h}", self.edge(h)));
            }
        }
        for (i, e) in self.edges.iter().enumerate() {
            let [a, b] = e.vertices;
            if self.origin(e.halves[0]) != a || self.target(e.halves[0]) != b {
                return Err(format!("edge {i} disagrees with its first half-edge"));
            }
            if e.halves[1] != self.twin(e.halves[0]) {
                return Err(format!("edge {i}: second half-edge is not the twin of the first"));
            }
        }
        // Euler: every half-edge belongs to exactly one edge, interior edges to two.
        let n_interior = self.edges.iter().filter(|e| !e.is_boundary()).count();
        if 2 * n_interior + self.n_boundary_edges() != self.n_half_edges() {
            return Err("half-edge count does not match the edges".to_owned());
        }
        let mut degree = vec![0usize; self.n_vertices()];
        for tri in &self.triangles {
            for &v in tri {
                degree[v as usize] += 1;
            }
        }
        for v in 0..self.n_vertices() as u32 {
            let h = self.vertex_half[v as usize];
            if h != NO_TWIN && self.origin(h) != v {
                return Err(format!("vertex {v}'s half-edge does not start at it"));
            }
            // A manifold vertex's faces form one fan: walking it must reach every incident face.
            let reached = self.vertex_faces(v).len();
            if reached != degree[v as usize] {
                return Err(format!(
                    "vertex {v} is pinched: its fan reaches {reached} of {} faces",
                    degree[v as usize]
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two counter-clockwise triangles sharing the edge 0–2 of a unit square.
    fn square() -> HalfEdges {
        HalfEdges::new(4, &[[0, 1, 2], [0, 2, 3]]).unwrap()
    }

    #[test]
    fn square_has_five_edges_one_interior() {
        let h = square();
        h.check_invariants().unwrap();
        assert_eq!((h.n_edges(), h.n_boundary_edges(), h.n_faces()), (5, 4, 2));
        let s = h.interior_stencils();
        assert_eq!(s.len(), 1);
        // Edge 2 → 0 lies in triangle 0 as its half-edge 2; triangle (2, 0, 1) and twin triangle (0, 2, 3).
        assert_eq!(s[0].vertices, [1, 3, 2, 0]);
        assert!((0..4).all(|v| h.is_boundary_vertex(v)));
    }

    #[test]
    fn closed_tetrahedron_has_no_boundary() {
        let h = HalfEdges::new(4, &[[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]]).unwrap();
        h.check_invariants().unwrap();
        assert_eq!((h.n_edges(), h.n_boundary_edges()), (6, 0));
        assert_eq!(h.interior_stencils().len(), 6);
        assert_eq!(h.vertex_faces(0).len(), 3);
    }

    #[test]
    fn refuses_bad_indices_repeats_and_flipped_neighbours() {
        assert_eq!(
            HalfEdges::new(3, &[[0, 1, 3]]),
            Err(TopologyError::IndexOutOfRange { triangle: 0, index: 3, n_vertices: 3 })
        );
        assert!(matches!(HalfEdges::new(3, &[[0, 1, 1]]), Err(TopologyError::RepeatedVertex { .. })));
        // The second triangle is wound the other way, so both use the directed edge 2 → 0.
        let err = HalfEdges::new(4, &[[0, 1, 2], [2, 0, 3]]).unwrap_err();
        assert!(
            matches!(err, TopologyError::NonManifoldEdge { from: 2, to: 0, first: 0, second: 1 }),
            "{err}"
        );
        // Three triangles on one edge.
        assert!(HalfEdges::new(5, &[[0, 1, 2], [1, 0, 3], [0, 1, 4]]).is_err());
    }

    #[test]
    fn pinched_vertex_fails_the_invariants() {
        // Two triangles touching only at vertex 0: a valid edge manifold, but not a vertex manifold.
        let h = HalfEdges::new(5, &[[0, 1, 2], [0, 3, 4]]).unwrap();
        assert!(h.check_invariants().unwrap_err().contains("pinched"));
    }

    #[test]
    fn fan_of_an_interior_vertex_is_complete() {
        // A hexagon fan around vertex 0.
        let tris: Vec<[u32; 3]> = (0..6).map(|k| [0, 1 + k, 1 + (k + 1) % 6]).collect();
        let h = HalfEdges::new(7, &tris).unwrap();
        h.check_invariants().unwrap();
        let mut faces = h.vertex_faces(0);
        faces.sort_unstable();
        assert_eq!(faces, vec![0, 1, 2, 3, 4, 5]);
        assert!(!h.is_boundary_vertex(0));
        assert_eq!(h.vertex_faces(1).len(), 2);
    }
}
