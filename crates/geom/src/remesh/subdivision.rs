//! The 1-to-4 edge subdivision of Simnett, Laycock & Day 2009, the baseline of the thesis's Test III
//! (spec §2.3, §7.3, A-42).
//!
//! Refinement is edge-based and the mesh is always conforming. A tree face records which of its edges
//! are split (Simnett's states 0–7): with one or two split edges it is drawn as two or three "green"
//! triangles, which are not tree faces (state −1) and whose edges may not be split; when its third edge
//! splits it becomes "red": four children at the edge midpoints, each a tree face in state 0 one level
//! deeper. So an edge can be split only when every face beside it is a tree face, which is what makes
//! early refinement slow in Test III (spec §7.3). Merging an edge undoes its split when its halves are
//! unsplit and any red face beside it has only unrefined children. The criteria (compression, collision,
//! curvature with the 0.97·0.95^depth limit, the merge delay) belong to the cloth; this type knows only
//! the hierarchy, in rest space.

use glam::DVec2;

use super::mesh::NONE;

#[derive(Debug, Clone, Copy, PartialEq)]
struct SubEdge {
    v: [u32; 2],
    depth: u8,
    mid: u32,
    /// Halves: from `v[0]` to `mid` and from `mid` to `v[1]`.
    children: [u32; 2],
    /// Tree faces having this edge as a side.
    faces: [u32; 2],
    boundary: bool,
    alive: bool,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct SubFace {
    v: [u32; 3],
    /// Edge k joins v[k] and v[k + 1].
    e: [u32; 3],
    depth: u8,
    /// First of four children, or NONE.
    children: u32,
    /// The three interior edges of a red face.
    interior: [u32; 3],
    alive: bool,
}

/// Why a split or merge was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum SubdivisionError {
    #[error("edge {0} does not exist or is already split")]
    NotALeaf(u32),
    #[error("edge {0} is at the maximum depth")]
    TooDeep(u32),
    #[error("edge {0} borders a green (state −1) triangle")]
    BordersGreen(u32),
    #[error("edge {0} cannot be merged: it is not split, or its children are refined")]
    NotMergeable(u32),
}

/// A base triangle mesh under 1-to-4 subdivision.
#[derive(Debug, Clone, PartialEq)]
pub struct Subdivision {
    rest: Vec<DVec2>,
    vertex_alive: Vec<bool>,
    edges: Vec<SubEdge>,
    faces: Vec<SubFace>,
    max_depth: u8,
}

impl Subdivision {
    /// Starts from a conforming counter-clockwise triangle mesh (depth 0 everywhere).
    pub fn new(mesh: &crate::MaterialMesh, max_depth: u8) -> Self {
        let topo = mesh.topology();
        let edges = topo
            .edges()
            .iter()
            .map(|e| SubEdge {
                v: e.vertices,
                depth: 0,
                mid: NONE,
                children: [NONE; 2],
                faces: [topo.face(e.halves[0]), if e.is_boundary() { NONE } else { topo.face(e.halves[1]) }],
                boundary: e.is_boundary(),
                alive: true,
            })
            .collect();
        let faces = (0..topo.n_faces() as u32)
            .map(|f| SubFace {
                v: topo.triangles()[f as usize],
                e: [0, 1, 2].map(|k| topo.edge(3 * f + k)),
                depth: 0,
                children: NONE,
                interior: [NONE; 3],
                alive: true,
            })
            .collect();
        Self {
            rest: mesh.rest().to_vec(),
            vertex_alive: vec![true; mesh.n_vertices()],
            edges,
            faces,
            max_depth,
        }
    }

    /// Material coordinates per vertex slot.
    pub fn rest(&self) -> &[DVec2] {
        &self.rest
    }

    pub fn is_vertex_alive(&self, v: u32) -> bool {
        self.vertex_alive[v as usize]
    }

    /// The unsplit edges of tree faces, as (edge id, ends, depth): the edges the criteria look at.
    pub fn leaf_edges(&self) -> Vec<(u32, [u32; 2], u8)> {
        (0..self.edges.len() as u32)
            .filter(|&e| {
                let s = &self.edges[e as usize];
                s.alive && s.mid == NONE && s.faces.iter().any(|&f| f != NONE)
            })
            .map(|e| (e, self.edges[e as usize].v, self.edges[e as usize].depth))
            .collect()
    }

    /// The split edges whose merge is allowed now.
    pub fn mergeable_edges(&self) -> Vec<u32> {
        (0..self.edges.len() as u32).filter(|&e| self.can_merge(e)).collect()
    }

    /// Whether `e` may be split: unsplit, below the maximum depth, and every face beside it a tree face
    /// (not a green triangle).
    pub fn can_split(&self, e: u32) -> Result<(), SubdivisionError> {
        let s = self
            .edges
            .get(e as usize)
            .filter(|s| s.alive && s.mid == NONE)
            .ok_or(SubdivisionError::NotALeaf(e))?;
        if s.depth >= self.max_depth {
            return Err(SubdivisionError::TooDeep(e));
        }
        let n = s.faces.iter().filter(|&&f| f != NONE).count();
        if n == 0 || (n == 1 && !s.boundary) {
            return Err(SubdivisionError::BordersGreen(e));
        }
        Ok(())
    }

    /// Splits edge `e` at its midpoint; returns the new vertex (x and v are the mean of the ends',
    /// Simnett's rule). Faces beside it whose three edges are now split become red.
    pub fn split(&mut self, e: u32) -> Result<u32, SubdivisionError> {
        self.can_split(e)?;
        let s = self.edges[e as usize];
        let m = self.rest.len() as u32;
        self.rest.push(0.5 * (self.rest[s.v[0] as usize] + self.rest[s.v[1] as usize]));
        self.vertex_alive.push(true);
        let c0 = self.push_edge([s.v[0], m], s.depth + 1, s.boundary);
        let c1 = self.push_edge([m, s.v[1]], s.depth + 1, s.boundary);
        let se = &mut self.edges[e as usize];
        se.mid = m;
        se.children = [c0, c1];
        for f in s.faces {
            if f != NONE && self.faces[f as usize].e.iter().all(|&k| self.edges[k as usize].mid != NONE) {
                self.make_red(f);
            }
        }
        Ok(m)
    }

    fn push_edge(&mut self, v: [u32; 2], depth: u8, boundary: bool) -> u32 {
        self.edges.push(SubEdge {
            v,
            depth,
            mid: NONE,
            children: [NONE; 2],
            faces: [NONE; 2],
            boundary,
            alive: true,
        });
        self.edges.len() as u32 - 1
    }

    /// The half of split edge `e` that touches vertex `v`.
    fn half_at(&self, e: u32, v: u32) -> u32 {
        let s = &self.edges[e as usize];
        if self.edges[s.children[0] as usize].v.contains(&v) { s.children[0] } else { s.children[1] }
    }

    fn make_red(&mut self, f: u32) {
        let face = self.faces[f as usize];
        let [v0, v1, v2] = face.v;
        let [m0, m1, m2] = face.e.map(|e| self.edges[e as usize].mid);
        let d = face.depth + 1;
        let i0 = self.push_edge([m0, m2], d, false);
        let i1 = self.push_edge([m1, m0], d, false);
        let i2 = self.push_edge([m2, m1], d, false);
        let h = |s: &Self, k: usize, v: u32| s.half_at(face.e[k], v);
        let kids = [
            ([v0, m0, m2], [h(self, 0, v0), i0, h(self, 2, v0)]),
            ([m0, v1, m1], [h(self, 0, v1), h(self, 1, v1), i1]),
            ([m2, m1, v2], [i2, h(self, 1, v2), h(self, 2, v2)]),
            ([m0, m1, m2], [i1, i2, i0]),
        ];
        let first = self.faces.len() as u32;
        for (c, (v, e)) in kids.into_iter().enumerate() {
            let id = first + c as u32;
            self.faces.push(SubFace { v, e, depth: d, children: NONE, interior: [NONE; 3], alive: true });
            for k in e {
                let slot = self.edges[k as usize]
                    .faces
                    .iter()
                    .position(|&x| x == NONE)
                    .expect("an edge has two sides");
                self.edges[k as usize].faces[slot] = id;
            }
        }
        let fm = &mut self.faces[f as usize];
        fm.children = first;
        fm.interior = [i0, i1, i2];
    }

    /// Whether split edge `e` may be merged: its halves are unsplit, and every red face beside it has
    /// four unrefined children with no split edge.
    pub fn can_merge(&self, e: u32) -> bool {
        let Some(s) = self.edges.get(e as usize) else { return false };
        if !s.alive || s.mid == NONE || s.children.iter().any(|&c| self.edges[c as usize].mid != NONE) {
            return false;
        }
        s.faces.iter().filter(|&&f| f != NONE).all(|&f| {
            let c = self.faces[f as usize].children;
            c == NONE
                || (c..c + 4).all(|k| {
                    let kid = &self.faces[k as usize];
                    kid.children == NONE && kid.e.iter().all(|&x| self.edges[x as usize].mid == NONE)
                })
        })
    }

    /// Undoes the split of `e` (Simnett's merge); returns the removed midpoint vertex.
    pub fn merge(&mut self, e: u32) -> Result<u32, SubdivisionError> {
        if !self.can_merge(e) {
            return Err(SubdivisionError::NotMergeable(e));
        }
        let s = self.edges[e as usize];
        for f in s.faces {
            if f == NONE || self.faces[f as usize].children == NONE {
                continue;
            }
            let c = self.faces[f as usize].children;
            for k in c..c + 4 {
                self.faces[k as usize].alive = false;
                for x in self.faces[k as usize].e {
                    for slot in &mut self.edges[x as usize].faces {
                        if *slot == k {
                            *slot = NONE;
                        }
                    }
                }
            }
            for i in self.faces[f as usize].interior {
                self.edges[i as usize].alive = false;
            }
            let fm = &mut self.faces[f as usize];
            fm.children = NONE;
            fm.interior = [NONE; 3];
        }
        for c in s.children {
            self.edges[c as usize].alive = false;
        }
        self.vertex_alive[s.mid as usize] = false;
        let se = &mut self.edges[e as usize];
        se.mid = NONE;
        se.children = [NONE; 2];
        Ok(s.mid)
    }

    /// The conforming triangulation over the vertex slots: leaf tree faces, each drawn as one, two or
    /// three triangles by how many of its edges are split.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        let mut out = Vec::with_capacity(2 * self.faces.len());
        for f in &self.faces {
            if !f.alive || f.children != NONE {
                continue;
            }
            let m = f.e.map(|e| self.edges[e as usize].mid);
            let v = f.v;
            match m.iter().filter(|&&x| x != NONE).count() {
                0 => out.push(v),
                1 => {
                    let k = m.iter().position(|&x| x != NONE).unwrap();
                    let (a, b, c) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
                    out.extend([[a, m[k], c], [m[k], b, c]]);
                }
                _ => {
                    // Split edges k and k + 1 meet at v[k + 1].
                    let k = (0..3).find(|&k| m[k] != NONE && m[(k + 1) % 3] != NONE).unwrap();
                    let (a, b, c) = (v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
                    let (ma, mb) = (m[k], m[(k + 1) % 3]);
                    out.push([ma, b, mb]);
                    let p = |i: u32| self.rest[i as usize];
                    if p(a).distance_squared(p(mb)) <= p(ma).distance_squared(p(c)) {
                        out.extend([[a, ma, mb], [a, mb, c]]);
                    } else {
                        out.extend([[a, ma, c], [ma, mb, c]]);
                    }
                }
            }
        }
        out
    }

    /// Depth of the deepest leaf tree face.
    pub fn max_face_depth(&self) -> u8 {
        self.faces.iter().filter(|f| f.alive).map(|f| f.depth).max().unwrap_or(0)
    }

    /// Compacted vertices and triangles as a validated [`crate::MaterialMesh`].
    pub fn to_material_mesh(&self) -> Result<crate::MaterialMesh, crate::MaterialMeshError> {
        let mut map = vec![NONE; self.rest.len()];
        let mut rest = Vec::new();
        for (i, m) in map.iter_mut().enumerate() {
            if self.vertex_alive[i] {
                *m = rest.len() as u32;
                rest.push(self.rest[i]);
            }
        }
        let tris = self.triangles().iter().map(|t| t.map(|i| map[i as usize])).collect();
        crate::MaterialMesh::new(rest, tris)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::remesh::tests::Rng;
    use crate::{DiagonalPattern, MaterialMesh};

    fn check(s: &Subdivision, what: &str) -> MaterialMesh {
        let m = s.to_material_mesh().unwrap_or_else(|e| panic!("{what}: {e}"));
        m.topology().check_invariants().unwrap_or_else(|e| panic!("{what}: {e}"));
        let area: f64 = (0..m.n_faces()).map(|t| m.rest_area(t)).sum();
        assert!((area - 1.0).abs() < 1e-14, "{what}: area {area}");
        m
    }

    #[test]
    fn green_then_red_closure_and_the_state_minus_one_rule() {
        let base = MaterialMesh::grid(5, 1.0, DiagonalPattern::Uniform).unwrap();
        let mut s = Subdivision::new(&base, 3);
        // Split one interior diagonal: its two faces turn green (2 triangles each).
        let (e, _, _) = *s
            .leaf_edges()
            .iter()
            .find(|(e, v, _)| {
                let (a, b) = (base.rest()[v[0] as usize], base.rest()[v[1] as usize]);
                (a - b).x.abs() > 0.0 && (a - b).y.abs() > 0.0 && !s.edges[*e as usize].boundary
            })
            .unwrap();
        s.split(e).unwrap();
        assert_eq!(check(&s, "green").n_faces(), 34);
        // Its halves border green triangles: not splittable yet.
        let half = s.edges[e as usize].children[0];
        assert_eq!(s.can_split(half), Err(SubdivisionError::BordersGreen(half)));
        // Split the other edges of one face beside it: that face goes red, its children are tree faces.
        let f = s.edges[e as usize].faces[0];
        for k in s.faces[f as usize].e {
            if s.edges[k as usize].mid == NONE {
                s.split(k).unwrap();
            }
        }
        assert_ne!(s.faces[f as usize].children, NONE);
        check(&s, "red");
        assert!(s.can_split(half).is_ok() || s.faces[s.edges[e as usize].faces[1] as usize].children == NONE);
        // Merge everything back.
        while let Some(&e) = s.mergeable_edges().first() {
            s.merge(e).unwrap();
            check(&s, "merge");
        }
        assert_eq!(check(&s, "coarse again").n_faces(), 32);
    }

    #[test]
    fn random_refinement_respects_depth_and_stays_conforming() {
        let base = MaterialMesh::grid(5, 1.0, DiagonalPattern::Uniform).unwrap();
        let mut s = Subdivision::new(&base, 3);
        let mut rng = Rng(42);
        let (mut splits, mut merges) = (0, 0);
        for step in 0..1500 {
            if rng.below(3) < 2 {
                let leaves = s.leaf_edges();
                let (e, _, _) = leaves[rng.below(leaves.len())];
                if s.split(e).is_ok() {
                    splits += 1;
                }
            } else {
                let m = s.mergeable_edges();
                if !m.is_empty() {
                    s.merge(m[rng.below(m.len())]).unwrap();
                    merges += 1;
                }
            }
            let m = check(&s, &format!("step {step}"));
            let min = m.edge_rest_lengths().iter().copied().fold(f64::MAX, f64::min);
            assert!(min >= 0.25 / 8.0 - 1e-15, "step {step}: edge {min} below depth 3");
        }
        assert!(s.max_face_depth() == 3 && splits > 100 && merges > 50, "{splits} {merges}");
    }
}
