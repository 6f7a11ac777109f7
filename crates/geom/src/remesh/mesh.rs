//! The editable material mesh: flat per-vertex and per-face arrays, half-edge twins kept up to date by
//! local edits, tombstones for removed elements until [`AdaptiveMesh::compact`].
//!
//! Every operation is a *face replacement*: a few faces go, a few come, and the twins of the new
//! half-edges are found on the ring of half-edges that bordered the removed faces. One primitive
//! checked once ([`AdaptiveMesh::replace_faces`]) therefore serves split, flip, collapse and patch
//! insertion, and an operation that would leave a non-manifold edge or vertex is undone before it is
//! seen.

use glam::{DVec2, DVec3};

use crate::halfedge::HalfEdges;

/// Marks "no element": a half-edge without twin, a vertex without face, a removed slot.
pub const NONE: u32 = u32::MAX;

/// Why an operation was refused. A refused operation leaves the mesh exactly as it was.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum OpError {
    #[error("there is no edge between vertices {0} and {1}")]
    NoSuchEdge(u32, u32),
    #[error("vertex {0} does not exist")]
    NoSuchVertex(u32),
    #[error("face {0} does not exist")]
    NoSuchFace(u32),
    #[error("the edge lies on the boundary, where this operation is not defined")]
    BoundaryEdge,
    #[error("the result would have an inverted or zero-area triangle in rest space")]
    Inverted,
    #[error("the result would turn a triangle's world normal by more than the allowed angle")]
    NormalFlip,
    #[error("the result would have an edge shorter than the minimum rest length")]
    TooShort,
    #[error("the result would be non-manifold (an edge with three faces, or a pinched vertex)")]
    NonManifold,
    #[error("the operation would move or remove the cloth contour or a locked vertex")]
    Boundary,
    #[error("the new patch does not cover the same rest area as the faces it replaces")]
    AreaMismatch,
    #[error("the result would pass the cloth through itself")]
    Crossing,
}

/// A vertex created by an operation, and where its state came from: X, x and v of `vertex` are
/// Σ wᵢ·(X, x, v)(parentᵢ). Unused parent slots have weight 0 (and repeat a real parent).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewVertex {
    pub vertex: u32,
    pub parents: [u32; 3],
    pub weights: [f64; 3],
}

/// Operation counts of a [`ChangeLog`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct OpCounts {
    pub splits: usize,
    pub flips: usize,
    pub collapses: usize,
    pub patches: usize,
}

/// What the edits since the last [`AdaptiveMesh::take_log`] changed, in slot numbering (before
/// [`AdaptiveMesh::compact`]), in the order it happened. A cloth uses it to give new particles their
/// state (replay `new_vertices` in order: a parent may itself be new), and to refresh masses, springs and
/// bending elements around `added_faces` only. An element made and removed within one log appears in
/// both lists.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ChangeLog {
    pub new_vertices: Vec<NewVertex>,
    pub removed_vertices: Vec<u32>,
    pub removed_faces: Vec<u32>,
    pub added_faces: Vec<u32>,
    pub counts: OpCounts,
}

impl ChangeLog {
    pub fn is_empty(&self) -> bool {
        self.new_vertices.is_empty() && self.removed_faces.is_empty() && self.added_faces.is_empty()
    }
}

/// Old slot → new index maps made by [`AdaptiveMesh::compact`]; [`NONE`] for removed slots.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Renumbering {
    pub vertex: Vec<u32>,
    pub face: Vec<u32>,
}

impl Renumbering {
    /// Compacts an array kept parallel to the vertex slots (a cloth's masses, pins, …) the same way.
    pub fn compact_vertex_data<T: Copy>(&self, data: &mut Vec<T>) {
        compact_by(&self.vertex, data);
    }

    /// Compacts an array kept parallel to the face slots.
    pub fn compact_face_data<T: Copy>(&self, data: &mut Vec<T>) {
        compact_by(&self.face, data);
    }
}

fn compact_by<T: Copy>(map: &[u32], data: &mut Vec<T>) {
    let mut n = 0;
    for (old, &new) in map.iter().enumerate() {
        if new != NONE {
            debug_assert_eq!(new as usize, n);
            data[n] = data[old];
            n += 1;
        }
    }
    data.truncate(n);
}

/// Why a mesh could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AdaptiveMeshError {
    #[error("{what} has {got} entries, but there are {expected} vertices")]
    Length { what: &'static str, got: usize, expected: usize },
    #[error(transparent)]
    Material(#[from] crate::MaterialMeshError),
}

/// A cloth mesh that can change its triangles: material (rest) coordinates X ∈ ℝ², world positions
/// x ∈ ℝ³ and velocities v ∈ ℝ³ per vertex, counter-clockwise triangles in material space.
///
/// Vertices and faces live in *slots*: an edit appends new ones and tombstones removed ones, so indices
/// stay valid during a remesh pass; [`AdaptiveMesh::compact`] renumbers densely afterwards.
#[derive(Debug, Clone)]
pub struct AdaptiveMesh {
    pub(crate) rest: Vec<DVec2>,
    pub(crate) x: Vec<DVec3>,
    pub(crate) v: Vec<DVec3>,
    pub(crate) vertex_alive: Vec<bool>,
    pub(crate) locked: Vec<bool>,
    /// A live face incident to each vertex, or [`NONE`].
    pub(crate) vertex_face: Vec<u32>,
    /// Number of live faces incident to each vertex.
    pub(crate) vertex_degree: Vec<u32>,
    pub(crate) faces: Vec<[u32; 3]>,
    pub(crate) face_alive: Vec<bool>,
    /// Twin of half-edge 3f + k (corner k → corner k + 1 of face f), or [`NONE`].
    pub(crate) twin: Vec<u32>,
    pub(crate) n_live_vertices: usize,
    pub(crate) n_live_faces: usize,
    pub(crate) log: ChangeLog,
    /// Scratch for fan walks and replacements, kept to avoid allocating per operation.
    pub(crate) scratch: Scratch,
    /// What flips and collapses check against while it is on ([`AdaptiveMesh::guard_crossings`]),
    /// kept while off for its buffers.
    pub(crate) crossing_guard: Option<Box<super::crossing_guard::CrossingGuard>>,
}

#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch {
    pub(crate) fan: Vec<u32>,
    pub(crate) ring: Vec<u32>,
    pub(crate) ring_old: Vec<u32>,
    pub(crate) touched: Vec<u32>,
    pub(crate) new_twin: Vec<u32>,
    /// For the operators, which hand their lists to `replace_faces`.
    pub(crate) op_fan: Vec<u32>,
    pub(crate) op_tris: Vec<[u32; 3]>,
    pub(crate) op_faces: Vec<u32>,
}

/// Two meshes are equal when they have the same vertices, faces, adjacency and log; which incident face
/// each vertex remembers, and the scratch buffers, do not count.
impl PartialEq for AdaptiveMesh {
    fn eq(&self, o: &Self) -> bool {
        self.rest == o.rest
            && self.x == o.x
            && self.v == o.v
            && self.vertex_alive == o.vertex_alive
            && self.locked == o.locked
            && self.vertex_degree == o.vertex_degree
            && self.faces == o.faces
            && self.face_alive == o.face_alive
            && self.twin == o.twin
            && self.log == o.log
    }
}

/// Twice the signed area of (a, b, c).
#[inline]
pub(crate) fn cross2(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

/// Whether (a, b, c) is counter-clockwise and not degenerate: twice its area exceeds 10⁻¹⁰ of its
/// longest edge squared (so the smallest angle is at least about 10⁻¹⁰ rad).
#[inline]
pub(crate) fn is_proper(a: DVec2, b: DVec2, c: DVec2) -> bool {
    let l2 = (b - a).length_squared().max((c - b).length_squared()).max((a - c).length_squared());
    cross2(a, b, c) > 1e-10 * l2
}

#[inline]
pub(crate) fn next_h(h: u32) -> u32 {
    if h % 3 == 2 { h - 2 } else { h + 1 }
}

#[inline]
pub(crate) fn prev_h(h: u32) -> u32 {
    if h.is_multiple_of(3) { h + 2 } else { h - 1 }
}

impl AdaptiveMesh {
    /// A mesh from material coordinates, world positions, velocities and counter-clockwise triangles,
    /// checked like [`crate::MaterialMesh::new`].
    pub fn new(
        rest: Vec<DVec2>,
        x: Vec<DVec3>,
        v: Vec<DVec3>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Self, AdaptiveMeshError> {
        let n = rest.len();
        for (what, got) in [("positions", x.len()), ("velocities", v.len())] {
            if got != n {
                return Err(AdaptiveMeshError::Length { what, got, expected: n });
            }
        }
        let material = crate::MaterialMesh::new(rest, triangles)?;
        Ok(Self::from_material(&material, x, v))
    }

    /// A mesh from a validated [`crate::MaterialMesh`] and its vertices' world state.
    ///
    /// # Panics
    /// If `x` or `v` do not have one entry per vertex.
    pub fn from_material(mesh: &crate::MaterialMesh, x: Vec<DVec3>, v: Vec<DVec3>) -> Self {
        let n = mesh.n_vertices();
        assert!(x.len() == n && v.len() == n, "one position and one velocity per vertex");
        let topo = mesh.topology();
        let nf = topo.n_faces();
        let twin = (0..3 * nf as u32).map(|h| topo.twin(h)).collect();
        let mut out = Self {
            rest: mesh.rest().to_vec(),
            x,
            v,
            vertex_alive: vec![true; n],
            locked: vec![false; n],
            vertex_face: vec![NONE; n],
            vertex_degree: vec![0; n],
            faces: topo.triangles().to_vec(),
            face_alive: vec![true; nf],
            twin,
            n_live_vertices: n,
            n_live_faces: nf,
            log: ChangeLog::default(),
            scratch: Scratch::default(),
            crossing_guard: None,
        };
        for (f, tri) in out.faces.iter().enumerate() {
            for &c in tri {
                out.vertex_face[c as usize] = f as u32;
                out.vertex_degree[c as usize] += 1;
            }
        }
        // Isolated vertices carry no material; they count as removed.
        for i in 0..n {
            if out.vertex_degree[i] == 0 {
                out.vertex_alive[i] = false;
                out.n_live_vertices -= 1;
            }
        }
        out
    }

    /// Number of vertex slots (live and removed).
    pub fn n_vertex_slots(&self) -> usize {
        self.rest.len()
    }

    /// Number of face slots (live and removed).
    pub fn n_face_slots(&self) -> usize {
        self.faces.len()
    }

    pub fn n_vertices(&self) -> usize {
        self.n_live_vertices
    }

    pub fn n_faces(&self) -> usize {
        self.n_live_faces
    }

    pub fn is_vertex_alive(&self, v: u32) -> bool {
        self.vertex_alive.get(v as usize).copied().unwrap_or(false)
    }

    pub fn is_face_alive(&self, f: u32) -> bool {
        self.face_alive.get(f as usize).copied().unwrap_or(false)
    }

    /// Material coordinates X per vertex slot, m.
    pub fn rest(&self) -> &[DVec2] {
        &self.rest
    }

    /// World positions x per vertex slot, m.
    pub fn positions(&self) -> &[DVec3] {
        &self.x
    }

    /// Velocities v per vertex slot, m/s.
    pub fn velocities(&self) -> &[DVec3] {
        &self.v
    }

    /// World positions, for a simulation to write its state back before remeshing.
    pub fn positions_mut(&mut self) -> &mut [DVec3] {
        &mut self.x
    }

    pub fn velocities_mut(&mut self) -> &mut [DVec3] {
        &mut self.v
    }

    /// Vertex triples per face slot (removed faces keep their last vertices).
    pub fn face_slots(&self) -> &[[u32; 3]] {
        &self.faces
    }

    /// Indices of the live faces, in slot order.
    pub fn live_faces(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.faces.len() as u32).filter(|&f| self.face_alive[f as usize])
    }

    /// The live faces' vertex triples (after [`AdaptiveMesh::compact`], the whole face list).
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        self.live_faces().map(|f| self.faces[f as usize]).collect()
    }

    /// Keeps a vertex from ever being removed by a collapse or a patch (a pinned particle, a tracked
    /// corner). It may still be the survivor of a collapse.
    pub fn set_locked(&mut self, v: u32, locked: bool) {
        self.locked[v as usize] = locked;
    }

    pub fn is_locked(&self, v: u32) -> bool {
        self.locked[v as usize]
    }

    /// Signed rest area of face slot `f`, m².
    pub fn rest_area(&self, f: u32) -> f64 {
        let [a, b, c] = self.faces[f as usize].map(|i| self.rest[i as usize]);
        0.5 * cross2(a, b, c)
    }

    /// Total rest area of the live faces, m².
    pub fn total_rest_area(&self) -> f64 {
        self.live_faces().map(|f| self.rest_area(f)).sum()
    }

    /// Area of influence per vertex slot: one third of the rest area of every incident live face
    /// (Oliveira 2013 §4.3.2.1; spec §4.2). They sum to the total rest area, so masses m = A·T·ρ
    /// conserve the total mass across every operation.
    pub fn vertex_areas(&self) -> Vec<f64> {
        let mut areas = vec![0.0; self.rest.len()];
        for f in self.live_faces() {
            let third = self.rest_area(f) / 3.0;
            for &c in &self.faces[f as usize] {
                areas[c as usize] += third;
            }
        }
        areas
    }

    /// Unit world normal of face slot `f` (zero for a degenerate face).
    pub fn world_normal(&self, f: u32) -> DVec3 {
        let [a, b, c] = self.faces[f as usize].map(|i| self.x[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// The edits since the last call.
    pub fn take_log(&mut self) -> ChangeLog {
        std::mem::take(&mut self.log)
    }

    pub fn log(&self) -> &ChangeLog {
        &self.log
    }

    #[inline]
    pub(crate) fn origin(&self, h: u32) -> u32 {
        self.faces[h as usize / 3][h as usize % 3]
    }

    #[inline]
    pub(crate) fn target(&self, h: u32) -> u32 {
        self.origin(next_h(h))
    }

    /// The half-edge leaving `v` in its anchor face.
    fn anchor_half(&self, v: u32) -> u32 {
        let f = self.vertex_face[v as usize];
        if f == NONE {
            return NONE;
        }
        let k = self.faces[f as usize].iter().position(|&c| c == v).expect("anchor face contains vertex");
        3 * f + k as u32
    }

    /// The half-edges leaving `v`, counter-clockwise, starting at the boundary when `v` is on it.
    /// Returns whether `v` is a boundary vertex. Assumes the fan is manifold; stops after visiting as
    /// many faces as `v` has.
    pub(crate) fn fan_into(&self, v: u32, out: &mut Vec<u32>) -> bool {
        out.clear();
        let start = self.anchor_half(v);
        if start == NONE {
            return false;
        }
        let limit = self.vertex_degree[v as usize] as usize;
        // Clockwise to the boundary (or all the way round).
        let mut h = start;
        let mut boundary = false;
        for _ in 0..limit {
            let t = self.twin[h as usize];
            if t == NONE {
                boundary = true;
                break;
            }
            let n = next_h(t);
            if n == start {
                break;
            }
            h = n;
        }
        let first = h;
        for _ in 0..limit {
            out.push(h);
            let t = self.twin[prev_h(h) as usize];
            if t == NONE || t == first {
                break;
            }
            h = t;
        }
        boundary
    }

    /// Whether vertex `v` is on the cloth contour.
    pub fn is_boundary_vertex(&self, v: u32) -> bool {
        let start = self.anchor_half(v);
        if start == NONE {
            return false;
        }
        let mut h = start;
        for _ in 0..self.vertex_degree[v as usize] {
            let t = self.twin[h as usize];
            if t == NONE {
                return true;
            }
            h = next_h(t);
            if h == start {
                return false;
            }
        }
        false
    }

    /// A half-edge of the edge {a, b}: a → b if that exists, else b → a. `None` if there is no edge.
    pub fn find_half_edge(&self, a: u32, b: u32) -> Option<u32> {
        if !self.is_vertex_alive(a) || !self.is_vertex_alive(b) {
            return None;
        }
        let mut fan = Vec::with_capacity(12);
        self.fan_into(a, &mut fan);
        let mut back = None;
        for &h in &fan {
            if self.target(h) == b {
                return Some(h);
            }
            let p = prev_h(h);
            if self.origin(p) == b {
                back = Some(p);
            }
        }
        back
    }

    /// The vertices sharing an edge with `v`, counter-clockwise.
    pub fn vertex_neighbours(&self, v: u32) -> Vec<u32> {
        let mut fan = Vec::with_capacity(12);
        let boundary = self.fan_into(v, &mut fan);
        let mut out: Vec<u32> = fan.iter().map(|&h| self.target(h)).collect();
        if boundary && let Some(&last) = fan.last() {
            out.push(self.origin(prev_h(last)));
        }
        out
    }

    /// The live faces around `v`, counter-clockwise.
    pub fn vertex_faces(&self, v: u32) -> Vec<u32> {
        let mut fan = Vec::with_capacity(12);
        self.fan_into(v, &mut fan);
        fan.iter().map(|&h| h / 3).collect()
    }

    /// Every live undirected edge once, as (half-edge, a, b) with the half-edge running a → b; interior
    /// edges are listed by their half-edge with a < b. In slot order, so deterministic.
    pub fn edges(&self) -> Vec<(u32, u32, u32)> {
        let mut out = Vec::with_capacity(self.n_live_faces * 3 / 2 + 8);
        for f in self.live_faces() {
            for k in 0..3 {
                let h = 3 * f + k;
                let (a, b) = (self.origin(h), self.target(h));
                if self.twin[h as usize] == NONE || a < b {
                    out.push((h, a, b));
                }
            }
        }
        out
    }

    /// Replaces the live faces `old` by the counter-clockwise triangles `new`, whose vertices must be
    /// live (new vertices are pushed before the call). Twins of the new half-edges are found among the
    /// new faces and on the ring of half-edges around `old`. Refuses, leaving everything as it was, if
    /// an edge would get three faces or a vertex's fan would be pinched. Vertices left with no face
    /// are removed. Logs the faces and removed vertices; returns the first new face slot.
    pub(crate) fn replace_faces(&mut self, old: &[u32], new: &[[u32; 3]]) -> Result<u32, OpError> {
        for &f in old {
            if !self.is_face_alive(f) {
                return Err(OpError::NoSuchFace(f));
            }
        }
        for tri in new {
            for &c in tri {
                if !self.is_vertex_alive(c) {
                    return Err(OpError::NoSuchVertex(c));
                }
            }
        }
        let mut s = std::mem::take(&mut self.scratch);
        let result = self.replace_faces_with(old, new, &mut s);
        self.scratch = s;
        result
    }

    fn replace_faces_with(&mut self, old: &[u32], new: &[[u32; 3]], s: &mut Scratch) -> Result<u32, OpError> {
        let is_old = |f: u32| old.contains(&f);
        // The ring: live half-edges outside `old` whose twin is in `old`.
        s.ring.clear();
        s.ring_old.clear();
        for &f in old {
            for k in 0..3 {
                let t = self.twin[(3 * f + k) as usize];
                if t != NONE && !is_old(t / 3) {
                    s.ring.push(t);
                    s.ring_old.push(3 * f + k);
                }
            }
        }
        // Directed edges of `new` are used once each; every undirected edge of `new` either pairs
        // within `new`, pairs with the ring, or does not exist outside `old` yet.
        let mut new_twin = std::mem::take(&mut s.new_twin);
        new_twin.clear();
        new_twin.resize(3 * new.len(), NONE);
        let base = self.faces.len() as u32;
        for (i, tri) in new.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                for (j, other) in new.iter().enumerate() {
                    for m in 0..3 {
                        let (c, d) = (other[m], other[(m + 1) % 3]);
                        if (i, k) != (j, m) && c == a && d == b {
                            s.new_twin = new_twin;
                            return Err(OpError::NonManifold);
                        }
                        if c == b && d == a {
                            new_twin[3 * i + k] = 3 * base + (3 * j + m) as u32;
                        }
                    }
                }
                if new_twin[3 * i + k] == NONE {
                    if let Some(&r) = s.ring.iter().find(|&&r| self.origin(r) == b && self.target(r) == a) {
                        new_twin[3 * i + k] = r;
                    } else if self.edge_exists_outside(a, b, old, &mut s.fan) {
                        s.new_twin = new_twin;
                        return Err(OpError::NonManifold);
                    }
                }
            }
        }
        // Commit.
        s.touched.clear();
        for &f in old {
            self.face_alive[f as usize] = false;
            for &c in &self.faces[f as usize] {
                self.vertex_degree[c as usize] -= 1;
                s.touched.push(c);
            }
        }
        for &r in &s.ring {
            self.twin[r as usize] = NONE;
        }
        for (i, tri) in new.iter().enumerate() {
            let f = base + i as u32;
            self.faces.push(*tri);
            self.face_alive.push(true);
            for k in 0..3 {
                let t = new_twin[3 * i + k];
                self.twin.push(t);
                if t != NONE && t < 3 * base {
                    self.twin[t as usize] = 3 * f + k as u32;
                }
            }
            for &c in tri {
                self.vertex_degree[c as usize] += 1;
                self.vertex_face[c as usize] = f;
                s.touched.push(c);
            }
        }
        s.new_twin = new_twin;
        s.touched.sort_unstable();
        s.touched.dedup();
        // Re-anchor vertices whose anchor died, then check every touched fan is one disc or half-disc.
        let mut ok = true;
        for idx in 0..s.touched.len() {
            let c = s.touched[idx];
            let anchor = self.vertex_face[c as usize];
            if anchor == NONE || !self.face_alive[anchor as usize] {
                let found = s
                    .ring
                    .iter()
                    .map(|&r| r / 3)
                    .find(|&f| self.face_alive[f as usize] && self.faces[f as usize].contains(&c));
                self.vertex_face[c as usize] = found.unwrap_or(NONE);
            }
            let degree = self.vertex_degree[c as usize] as usize;
            if degree > 0 {
                let boundary = self.fan_into(c, &mut s.fan);
                let _ = boundary;
                if s.fan.len() != degree {
                    ok = false;
                    break;
                }
            } else if self.locked[c as usize] {
                ok = false;
                break;
            }
        }
        if !ok {
            self.rollback(old, new.len(), base, s);
            return Err(OpError::NonManifold);
        }
        for &f in old {
            self.log.removed_faces.push(f);
        }
        self.n_live_faces = self.n_live_faces + new.len() - old.len();
        for i in 0..new.len() as u32 {
            self.log.added_faces.push(base + i);
        }
        self.guard_new_faces(base..base + new.len() as u32);
        for idx in 0..s.touched.len() {
            let c = s.touched[idx];
            if self.vertex_degree[c as usize] == 0 {
                self.vertex_alive[c as usize] = false;
                self.vertex_face[c as usize] = NONE;
                self.n_live_vertices -= 1;
                self.log.removed_vertices.push(c);
            }
        }
        Ok(base)
    }

    fn rollback(&mut self, old: &[u32], n_new: usize, base: u32, s: &mut Scratch) {
        for i in 0..n_new {
            for &c in &self.faces[base as usize + i] {
                self.vertex_degree[c as usize] -= 1;
            }
        }
        self.faces.truncate(base as usize);
        self.face_alive.truncate(base as usize);
        self.twin.truncate(3 * base as usize);
        for (&r, &o) in s.ring.iter().zip(&s.ring_old) {
            self.twin[r as usize] = o;
        }
        for &f in old {
            self.face_alive[f as usize] = true;
            for &c in &self.faces[f as usize] {
                self.vertex_degree[c as usize] += 1;
                self.vertex_face[c as usize] = f;
            }
        }
        // Vertices of neither old nor new faces were not touched; those only in new faces (fresh
        // vertices) go back to having no face.
        for idx in 0..s.touched.len() {
            let c = s.touched[idx];
            if self.vertex_degree[c as usize] == 0 {
                self.vertex_face[c as usize] = NONE;
            }
        }
    }

    /// Whether the undirected edge {a, b} is used by a live face not in `old`.
    fn edge_exists_outside(&self, a: u32, b: u32, old: &[u32], fan: &mut Vec<u32>) -> bool {
        if self.vertex_degree[a as usize] == 0 {
            return false;
        }
        self.fan_into(a, fan);
        fan.iter().any(|&h| !old.contains(&(h / 3)) && self.faces[h as usize / 3].contains(&b))
    }

    /// Appends a vertex and logs where it came from; returns its slot.
    pub(crate) fn push_vertex(&mut self, rest: DVec2, parents: [u32; 3], weights: [f64; 3]) -> u32 {
        let mut x = DVec3::ZERO;
        let mut v = DVec3::ZERO;
        for (&p, &w) in parents.iter().zip(&weights) {
            if w != 0.0 {
                x += self.x[p as usize] * w;
                v += self.v[p as usize] * w;
            }
        }
        let id = self.rest.len() as u32;
        self.rest.push(rest);
        self.x.push(x);
        self.v.push(v);
        self.vertex_alive.push(true);
        self.locked.push(false);
        self.vertex_face.push(NONE);
        self.vertex_degree.push(0);
        self.n_live_vertices += 1;
        self.log.new_vertices.push(NewVertex { vertex: id, parents, weights });
        id
    }

    /// Removes the vertices just pushed by a refused operation.
    pub(crate) fn pop_vertices(&mut self, n_before: usize) {
        let n = self.rest.len() - n_before;
        self.rest.truncate(n_before);
        self.x.truncate(n_before);
        self.v.truncate(n_before);
        self.vertex_alive.truncate(n_before);
        self.locked.truncate(n_before);
        self.vertex_face.truncate(n_before);
        self.vertex_degree.truncate(n_before);
        self.n_live_vertices -= n;
        let keep = self.log.new_vertices.len() - n;
        self.log.new_vertices.truncate(keep);
    }

    /// Drops removed vertices and faces and renumbers the rest densely, keeping their order. Returns
    /// the maps, so that arrays kept beside the mesh can follow ([`Renumbering::compact_vertex_data`]).
    pub fn compact(&mut self) -> Renumbering {
        let mut vmap = vec![NONE; self.rest.len()];
        let mut n = 0u32;
        for (i, m) in vmap.iter_mut().enumerate() {
            if self.vertex_alive[i] {
                *m = n;
                n += 1;
            }
        }
        let mut fmap = vec![NONE; self.faces.len()];
        let mut nf = 0u32;
        for (i, m) in fmap.iter_mut().enumerate() {
            if self.face_alive[i] {
                *m = nf;
                nf += 1;
            }
        }
        let renum = Renumbering { vertex: vmap, face: fmap };
        renum.compact_vertex_data(&mut self.rest);
        renum.compact_vertex_data(&mut self.x);
        renum.compact_vertex_data(&mut self.v);
        renum.compact_vertex_data(&mut self.locked);
        renum.compact_vertex_data(&mut self.vertex_degree);
        renum.compact_vertex_data(&mut self.vertex_face);
        for f in &mut self.vertex_face {
            *f = renum.face[*f as usize];
        }
        self.vertex_alive = vec![true; n as usize];
        // Twins: half-edge 3f + k moves with its face.
        let mut twin = Vec::with_capacity(3 * nf as usize);
        for (f, &m) in renum.face.iter().enumerate() {
            if m == NONE {
                continue;
            }
            for k in 0..3 {
                let t = self.twin[3 * f + k];
                twin.push(if t == NONE { NONE } else { 3 * renum.face[t as usize / 3] + t % 3 });
            }
        }
        self.twin = twin;
        renum.compact_face_data(&mut self.faces);
        for tri in &mut self.faces {
            *tri = tri.map(|c| renum.vertex[c as usize]);
        }
        self.face_alive = vec![true; nf as usize];
        renum
    }

    /// A [`HalfEdges`] rebuilt from scratch over the live faces (compacted numbering), e.g. to list
    /// springs and bending stencils after a remesh.
    pub fn half_edges(&self) -> HalfEdges {
        let mut copy = self.clone();
        copy.compact();
        HalfEdges::new(copy.rest.len(), &copy.faces).expect("an AdaptiveMesh is always an oriented manifold")
    }

    /// Checks every invariant: live faces counter-clockwise with positive rest area, maintained twins
    /// equal to a from-scratch [`HalfEdges`] build (whose own invariants must hold, including manifold
    /// vertex fans), anchors, degrees and counts consistent. Costs a full rebuild; for tests.
    pub fn check_invariants(&self) -> Result<(), String> {
        let mut degree = vec![0u32; self.rest.len()];
        for f in self.live_faces() {
            let [a, b, c] = self.faces[f as usize];
            for &i in &[a, b, c] {
                if !self.is_vertex_alive(i) {
                    return Err(format!("live face {f} uses removed vertex {i}"));
                }
                degree[i as usize] += 1;
            }
            let (pa, pb, pc) = (self.rest[a as usize], self.rest[b as usize], self.rest[c as usize]);
            if !is_proper(pa, pb, pc) {
                return Err(format!("face {f} is inverted or degenerate in rest space: {pa} {pb} {pc}"));
            }
            for k in 0..3 {
                let h = 3 * f + k;
                let t = self.twin[h as usize];
                if t != NONE {
                    if !self.face_alive[t as usize / 3] {
                        return Err(format!("half-edge {h} is twinned with {t} of a removed face"));
                    }
                    if self.twin[t as usize] != h {
                        return Err(format!("twin({t}) ≠ {h}"));
                    }
                    if self.origin(t) != self.target(h) || self.target(t) != self.origin(h) {
                        return Err(format!("half-edge {h} and its twin {t} do not run opposite ways"));
                    }
                }
            }
        }
        let mut n_alive = 0;
        #[expect(clippy::needless_range_loop, reason = "i indexes five parallel arrays")]
        for i in 0..self.rest.len() {
            if degree[i] != self.vertex_degree[i] {
                return Err(format!(
                    "vertex {i}: degree {} recorded, {} counted",
                    self.vertex_degree[i], degree[i]
                ));
            }
            if self.vertex_alive[i] {
                n_alive += 1;
                if degree[i] == 0 {
                    return Err(format!("live vertex {i} has no face"));
                }
                let f = self.vertex_face[i];
                if f == NONE || !self.is_face_alive(f) || !self.faces[f as usize].contains(&(i as u32)) {
                    return Err(format!("vertex {i} has a bad anchor face {f}"));
                }
                let mut fan = Vec::new();
                self.fan_into(i as u32, &mut fan);
                if fan.len() != degree[i] as usize {
                    return Err(format!("vertex {i}: fan walk reaches {} of {} faces", fan.len(), degree[i]));
                }
            }
        }
        if n_alive != self.n_live_vertices || self.live_faces().count() != self.n_live_faces {
            return Err("live counts are stale".to_owned());
        }
        // The maintained twins must be exactly what a fresh build finds.
        let mut copy = self.clone();
        let renum = copy.compact();
        let he = HalfEdges::new(copy.rest.len(), &copy.faces).map_err(|e| e.to_string())?;
        he.check_invariants()?;
        for f in self.live_faces() {
            for k in 0..3 {
                let h = 3 * f + k;
                let t = self.twin[h as usize];
                let mapped = 3 * renum.face[f as usize] + k;
                let expected = if t == NONE { NONE } else { 3 * renum.face[t as usize / 3] + t % 3 };
                if he.twin(mapped) != expected {
                    return Err(format!("half-edge {h}: maintained twin {t} disagrees with a rebuild"));
                }
            }
        }
        Ok(())
    }
}
