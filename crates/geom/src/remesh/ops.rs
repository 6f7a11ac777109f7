//! The local operators on [`AdaptiveMesh`]: edge split, edge flip, edge collapse and patch replacement
//! (spec §6.1: "deleting a face-connected patch, inserting a patch, splitting a contour edge, merging
//! collinear contour edges"). Each checks its geometric guards first and then goes through
//! [`AdaptiveMesh::replace_faces`], which checks the topology; a refused operation changes nothing.
//!
//! Rest area is conserved by construction: a split puts the new vertex on the edge, a flip needs a
//! strictly convex quad, a collapse needs every new triangle counter-clockwise (so the new fan tiles
//! the old star) and removes contour vertices only where the contour is straight, and a patch must
//! cover the rest area it replaces.
//!
//! While [`AdaptiveMesh::guard_crossings`] is on, a flip or collapse that would pass the cloth through
//! itself in world space is refused too (splits cannot: their triangles tile the old ones).

use glam::{DVec2, DVec3};

use super::mesh::{AdaptiveMesh, NONE, OpError, cross2, is_proper, prev_h};

/// Limits every operator respects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OpGuards {
    /// No operation creates an edge shorter than this rest length, m (L⁰_min of spec §6.2).
    pub min_edge_length: f64,
    /// A collapse may turn a surviving face's world normal by at most acos(min_normal_cos); 0 refuses
    /// any face that would flip over.
    pub min_normal_cos: f64,
    /// Contour vertices count as on a straight line when |sin| of the angle between their two contour
    /// edges is at most this.
    pub collinear_tolerance: f64,
}

impl OpGuards {
    /// Guards with a minimum rest edge length, refusing flipped normals and bent contours.
    pub const fn with_min_edge_length(min_edge_length: f64) -> Self {
        Self { min_edge_length, min_normal_cos: 0.0, collinear_tolerance: 1e-12 }
    }

    /// Only the guards that keep the mesh valid (no length limit).
    pub const fn validity_only() -> Self {
        Self::with_min_edge_length(0.0)
    }
}

impl AdaptiveMesh {
    /// Splits the edge {a, b} at its rest-space midpoint; x and v of the new vertex are the averages of
    /// the ends (barycentric weights ½, ½). Each face at the edge becomes two. Works on contour edges
    /// too (the contour bisection of spec §6.5). Returns the new vertex.
    pub fn split_edge(&mut self, a: u32, b: u32, guards: &OpGuards) -> Result<u32, OpError> {
        let h = self.find_half_edge(a, b).ok_or(OpError::NoSuchEdge(a, b))?;
        let (a, b) = (self.origin(h), self.target(h));
        let t = self.twin[h as usize];
        let c = self.origin(prev_h(h));
        let (pa, pb) = (self.rest[a as usize], self.rest[b as usize]);
        let mid = 0.5 * (pa + pb);
        let min = guards.min_edge_length;
        if 0.5 * pa.distance(pb) < min || mid.distance(self.rest[c as usize]) < min {
            return Err(OpError::TooShort);
        }
        let d = if t == NONE { NONE } else { self.origin(prev_h(t)) };
        if d != NONE && mid.distance(self.rest[d as usize]) < min {
            return Err(OpError::TooShort);
        }
        let n_before = self.rest.len();
        let m = self.push_vertex(mid, [a, b, a], [0.5, 0.5, 0.0]);
        let mut tris = std::mem::take(&mut self.scratch.op_tris);
        tris.clear();
        tris.extend([[a, m, c], [m, b, c]]);
        let mut old = [h / 3, NONE];
        if d != NONE {
            tris.extend([[b, m, d], [m, a, d]]);
            old[1] = t / 3;
        }
        let old = if d == NONE { &old[..1] } else { &old[..] };
        let proper = tris.iter().all(|tri| self.proper(*tri));
        let result = if proper { self.replace_faces(old, &tris) } else { Err(OpError::Inverted) };
        self.scratch.op_tris = tris;
        match result {
            Ok(_) => {
                self.log.counts.splits += 1;
                Ok(m)
            }
            Err(e) => {
                self.pop_vertices(n_before);
                Err(e)
            }
        }
    }

    /// Replaces the interior edge {a, b} by the other diagonal of its two faces. Refused unless the
    /// quad is strictly convex in rest space (so the rest area stays) and the new edge respects the
    /// minimum length.
    pub fn flip_edge(&mut self, a: u32, b: u32, guards: &OpGuards) -> Result<(u32, u32), OpError> {
        let h = self.find_half_edge(a, b).ok_or(OpError::NoSuchEdge(a, b))?;
        let t = self.twin[h as usize];
        if t == NONE {
            return Err(OpError::BoundaryEdge);
        }
        let (a, b) = (self.origin(h), self.target(h));
        let c = self.origin(prev_h(h));
        let d = self.origin(prev_h(t));
        if self.rest[c as usize].distance(self.rest[d as usize]) < guards.min_edge_length {
            return Err(OpError::TooShort);
        }
        let tris = [[c, a, d], [d, b, c]];
        if !tris.iter().all(|tri| self.proper(*tri)) {
            return Err(OpError::Inverted);
        }
        if self.would_cross(&[h / 3, t / 3], &tris) {
            return Err(OpError::Crossing);
        }
        self.replace_faces(&[h / 3, t / 3], &tris)?;
        self.log.counts.flips += 1;
        Ok((c, d))
    }

    /// Removes vertex `remove` by merging it into its neighbour `keep` along their edge; `keep` stays
    /// where it is. Refused when `remove` is locked, when a contour vertex would leave the contour
    /// (the edge must be a contour edge and the contour straight at `remove`), when a new face would be
    /// inverted in rest space or turn its world normal past the guard, when a new edge would be too
    /// short, or when the result would be non-manifold (the link condition).
    pub fn collapse_edge(&mut self, remove: u32, keep: u32, guards: &OpGuards) -> Result<(), OpError> {
        let (v, u) = (remove, keep);
        if !self.is_vertex_alive(v) {
            return Err(OpError::NoSuchVertex(v));
        }
        if self.locked[v as usize] {
            return Err(OpError::Boundary);
        }
        let h = self.find_half_edge(v, u).ok_or(OpError::NoSuchEdge(v, u))?;
        let edge_on_contour = self.twin[h as usize] == NONE;
        let mut fan = std::mem::take(&mut self.scratch.op_fan);
        let v_on_contour = self.fan_into(v, &mut fan);
        let result = self.collapse_checked(v, u, edge_on_contour, v_on_contour, &fan, guards);
        self.scratch.op_fan = fan;
        result
    }

    fn collapse_checked(
        &mut self,
        v: u32,
        u: u32,
        edge_on_contour: bool,
        v_on_contour: bool,
        fan: &[u32],
        guards: &OpGuards,
    ) -> Result<(), OpError> {
        if v_on_contour {
            if !edge_on_contour {
                return Err(OpError::Boundary);
            }
            let n1 = self.target(fan[0]);
            let n2 = self.origin(prev_h(*fan.last().expect("a live vertex has faces")));
            let w = if n1 == u { n2 } else { n1 };
            let (pv, pu, pw) = (self.rest[v as usize], self.rest[u as usize], self.rest[w as usize]);
            let (du, dw) = (pu - pv, pw - pv);
            let straight = cross2(pv, pu, pw).abs() <= guards.collinear_tolerance * du.length() * dw.length();
            if w == u || !straight || du.dot(dw) >= 0.0 {
                return Err(OpError::Boundary);
            }
        }
        let mut tris = std::mem::take(&mut self.scratch.op_tris);
        tris.clear();
        let mut old = std::mem::take(&mut self.scratch.op_faces);
        old.clear();
        let mut verdict = Ok(());
        let pu = self.rest[u as usize];
        for &hv in fan {
            let f = hv / 3;
            old.push(f);
            let tri = self.faces[f as usize];
            if tri.contains(&u) {
                continue;
            }
            let new = tri.map(|c| if c == v { u } else { c });
            if !self.proper(new) {
                verdict = Err(OpError::Inverted);
                break;
            }
            if self.world_normal_of(new).dot(self.world_normal(f)) < guards.min_normal_cos {
                verdict = Err(OpError::NormalFlip);
                break;
            }
            if new.iter().any(|&c| c != u && self.rest[c as usize].distance(pu) < guards.min_edge_length) {
                verdict = Err(OpError::TooShort);
                break;
            }
            tris.push(new);
        }
        if verdict.is_ok() && self.would_cross(&old, &tris) {
            verdict = Err(OpError::Crossing);
        }
        if verdict.is_ok() {
            verdict = self.replace_faces(&old, &tris).map(|_| ());
        }
        self.scratch.op_tris = tris;
        self.scratch.op_faces = old;
        if verdict.is_ok() {
            self.log.counts.collapses += 1;
        }
        verdict
    }

    fn proper(&self, tri: [u32; 3]) -> bool {
        let [a, b, c] = tri.map(|i| self.rest[i as usize]);
        is_proper(a, b, c)
    }

    fn world_normal_of(&self, tri: [u32; 3]) -> DVec3 {
        let [a, b, c] = tri.map(|i| self.x[i as usize]);
        (b - a).cross(c - a).normalize_or_zero()
    }

    /// The border of a set of live faces as closed loops of vertices, each walked with the faces on
    /// its left (so an outer border runs counter-clockwise in rest space and the border of an island
    /// clockwise). A vertex where the region touches itself appears once per loop through it.
    pub fn region_border(&self, faces: &[u32]) -> Vec<Vec<u32>> {
        let mut inside = vec![false; self.faces.len()];
        for &f in faces {
            inside[f as usize] = true;
        }
        let on_border = |h: u32| {
            let t = self.twin[h as usize];
            t == NONE || !inside[t as usize / 3]
        };
        let mut seen = vec![false; 3 * self.faces.len()];
        let mut loops = Vec::new();
        for &f in faces {
            for k in 0..3 {
                let start = 3 * f + k;
                if seen[start as usize] || !on_border(start) {
                    continue;
                }
                let mut ring = Vec::new();
                let mut h = start;
                loop {
                    seen[h as usize] = true;
                    ring.push(self.origin(h));
                    // Turn around target(h) through the region to the next border half-edge.
                    let mut g = super::mesh::next_h(h);
                    while !on_border(g) {
                        g = super::mesh::next_h(self.twin[g as usize]);
                    }
                    h = g;
                    if h == start || ring.len() > 3 * faces.len() {
                        break;
                    }
                }
                loops.push(ring);
            }
        }
        loops
    }

    /// Replaces the live faces `old` by a new patch (spec §6.5–§6.7): `triangles` index existing
    /// vertices by their slot, and the patch's own new vertices as `n_vertex_slots() + i` for
    /// `new_points[i]`. The patch must cover exactly the rest area of `old` and meet every edge
    /// shared with the rest of the mesh; it may bisect contour edges (a new point on one) or merge
    /// straight contour runs (a contour vertex it leaves out is removed). New vertices take x and v by
    /// barycentric interpolation in the old face that contains them in rest space (spec §6.7). Returns
    /// the slots of the new vertices.
    pub fn replace_patch(
        &mut self,
        old: &[u32],
        new_points: &[DVec2],
        triangles: &[[u32; 3]],
    ) -> Result<Vec<u32>, OpError> {
        for &f in old {
            if !self.is_face_alive(f) {
                return Err(OpError::NoSuchFace(f));
            }
        }
        let base = self.rest.len() as u32;
        let point = |i: u32| {
            if i < base { self.rest[i as usize] } else { new_points[(i - base) as usize] }
        };
        for tri in triangles {
            for &c in tri {
                if c as usize >= base as usize + new_points.len() || (c < base && !self.is_vertex_alive(c)) {
                    return Err(OpError::NoSuchVertex(c));
                }
            }
            if !is_proper(point(tri[0]), point(tri[1]), point(tri[2])) {
                return Err(OpError::Inverted);
            }
        }
        let old_area: f64 = old.iter().map(|&f| self.rest_area(f)).sum();
        let new_area: f64 =
            triangles.iter().map(|t| 0.5 * cross2(point(t[0]), point(t[1]), point(t[2]))).sum();
        if (old_area - new_area).abs() > 1e-11 * old_area.abs().max(f64::MIN_POSITIVE) {
            return Err(OpError::AreaMismatch);
        }
        // Every edge the old faces share with the rest of the mesh must be met by the patch.
        for &f in old {
            for k in 0..3 {
                let t = self.twin[(3 * f + k) as usize];
                if t != NONE && !old.contains(&(t / 3)) {
                    let (a, b) = (self.target(t), self.origin(t));
                    let met =
                        triangles.iter().any(|tri| (0..3).any(|m| tri[m] == a && tri[(m + 1) % 3] == b));
                    if !met {
                        return Err(OpError::AreaMismatch);
                    }
                }
            }
        }
        let n_before = self.rest.len();
        let mut ids = Vec::with_capacity(new_points.len());
        for &p in new_points {
            let (parents, weights) = self.locate_in(old, p);
            ids.push(self.push_vertex(p, parents, weights));
        }
        match self.replace_faces(old, triangles) {
            Ok(_) => {
                self.log.counts.patches += 1;
                Ok(ids)
            }
            Err(e) => {
                self.pop_vertices(n_before);
                Err(e)
            }
        }
    }

    /// The face of `faces` whose rest triangle contains `p` (or comes closest), as its vertices and
    /// clamped barycentric weights.
    pub(crate) fn locate_in(&self, faces: &[u32], p: DVec2) -> ([u32; 3], [f64; 3]) {
        let mut best = ([0, 0, 0], [1.0, 0.0, 0.0]);
        let mut best_score = f64::NEG_INFINITY;
        for &f in faces {
            let tri = self.faces[f as usize];
            let [a, b, c] = tri.map(|i| self.rest[i as usize]);
            let area = cross2(a, b, c);
            let w = [cross2(p, b, c) / area, cross2(a, p, c) / area, cross2(a, b, p) / area];
            let score = w[0].min(w[1]).min(w[2]);
            if score > best_score {
                best_score = score;
                best = (tri, w);
            }
        }
        let (tri, w) = best;
        let w = w.map(|x| x.max(0.0));
        let sum = w[0] + w[1] + w[2];
        (tri, w.map(|x| x / sum))
    }
}

/// Points of a rest-space polygon for tests and callers: the rest coordinates of vertex loops.
pub fn loop_points(mesh: &AdaptiveMesh, ring: &[u32]) -> Vec<DVec2> {
    ring.iter().map(|&v| mesh.rest[v as usize]).collect()
}
