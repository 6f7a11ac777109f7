//! A bounding-volume hierarchy of a cloth's triangles whose nodes also carry the cone of their
//! triangles' normals over a step, so that a piece of cloth that stays nearly flat is known not to
//! touch itself without looking at its pairs (Volino & Magnenat-Thalmann 1994; Provot 1997's
//! curvature test; Tang et al. 2009).
//!
//! A node whose triangles form one edge-connected, consistently oriented piece of surface (every edge
//! shared by at most two of them), and whose normals over the whole step lie
//! within a cone of half-angle below 90° minus a margin, is a height field over the cone's axis
//! throughout the step: no vertex of it can reach a triangle of it that it is not a corner of, and no
//! two of its edges can cross, except through a fold that would turn some normal by more than 90°.
//! The cone of a triangle over a step is that of the three control vectors of its normal, which moves
//! as a quadratic Bézier curve when its corners move linearly (n(t) = (b − a)(t) × (c − a)(t)), so the
//! normal at every instant is a positive combination of them. (Volino's second condition, that the
//! piece's contour does not overlap itself in projection, is not checked: the pieces are compact
//! patches of a cloth, built from its shape when the topology is first seen, that its springs keep
//! from winding round in the plane.)
//!
//! Cones are kept as an axis and the cosine and sine of their half-angle, and merged with the angle
//! sum bound (the half-angle of a parent about its axis is at most the angle between the axes plus
//! the child's half-angle), so a refit takes square roots but no inverse cosines.

use glam::DVec3;

use crate::Aabb;

/// Largest number of triangles in a leaf.
const LEAF_SIZE: usize = 8;

/// A node flat enough to skip: its cone's half-angle is below 90° by this margin (radians, as its
/// sine: cos θ ≥ sin(margin)), which absorbs the rounding of the cones' merges.
const FLAT_MARGIN: f64 = 0.05;

#[derive(Debug, Clone, Copy)]
pub(crate) struct Cone {
    axis: DVec3,
    cos: f64,
    sin: f64,
}

impl Cone {
    const FULL: Cone = Cone { axis: DVec3::Z, cos: -1.0, sin: 0.0 };

    /// Whether every direction of the cone lies within 90° − [`FLAT_MARGIN`] of its axis.
    fn flat(&self) -> bool {
        self.cos >= FLAT_MARGIN.sin()
    }

    /// The cone about `axis` (unit) that holds cones `cones` (each as axis, cos, sin): for each, the angle
    /// between the axes plus its half-angle, the largest of them.
    fn around(axis: DVec3, cones: impl Iterator<Item = Cone>) -> Cone {
        let (mut cos, mut sin) = (1.0f64, 0.0f64);
        for c in cones {
            let ca = axis.dot(c.axis).clamp(-1.0, 1.0);
            let sa = (1.0 - ca * ca).max(0.0).sqrt();
            // cos and sin of the angle between the axes plus the child's half-angle.
            let (cs, ss) = (ca * c.cos - sa * c.sin, sa * c.cos + ca * c.sin);
            if ss < 0.0 || c.cos <= -1.0 {
                // Past π: the cone covers everything.
                return Cone::FULL;
            }
            if cs < cos {
                (cos, sin) = (cs, ss);
            }
        }
        Cone { axis, cos, sin }
    }
}

#[derive(Debug, Clone, Copy)]
struct Node {
    aabb: Aabb,
    cone: Cone,
    /// Leaf: the first slot of its triangles in `order`; inner node: its first child (the second is
    /// `first + 1`).
    first: u32,
    /// Triangles of a leaf; 0 marks an inner node.
    count: u32,
    /// Whether the node's triangles form one edge-connected, consistently oriented piece of surface
    /// (fixed at the build).
    connected: bool,
    /// Whether a triangle of the node has a corner marked moved (set by the refit).
    moved: bool,
}

/// The tree over a mesh's triangles, built once per topology and refitted every step.
#[derive(Debug, Clone, Default)]
pub(crate) struct PatchTree {
    nodes: Vec<Node>,
    /// Triangle indices in leaf order.
    pub order: Vec<u32>,
    build_stack: Vec<(u32, u32, u32)>,
    /// Per triangle, its unit swept-normal cone (refit scratch).
    cones: Vec<Cone>,
}

/// Per node, which pairs of its subtrees to visit.
pub(crate) trait Visitor {
    /// Two leaves (or one leaf with itself, `a == b`) whose boxes overlap: their triangle slots in
    /// `order`.
    fn leaves(&mut self, a: std::ops::Range<usize>, b: std::ops::Range<usize>);
}

impl PatchTree {
    /// Builds the tree over `boxes` (one per triangle) by median splits of their centres, and marks the
    /// nodes whose triangles are edge-connected (`triangles` gives their corners).
    pub fn build(&mut self, boxes: &[Aabb], triangles: &[[u32; 3]]) {
        let n = u32::try_from(boxes.len()).expect("fewer than 2³² triangles");
        self.nodes.clear();
        self.cones.clear();
        self.order.clear();
        self.order.extend(0..n);
        if n == 0 {
            return;
        }
        let blank =
            Node { aabb: Aabb::EMPTY, cone: Cone::FULL, first: 0, count: 0, connected: false, moved: true };
        self.nodes.push(blank);
        self.build_stack.clear();
        self.build_stack.push((0, 0, n));
        while let Some((node, start, end)) = self.build_stack.pop() {
            let items = &mut self.order[start as usize..end as usize];
            let connected = edge_connected(items, triangles);
            if (end - start) as usize <= LEAF_SIZE {
                self.nodes[node as usize] = Node { first: start, count: end - start, connected, ..blank };
                continue;
            }
            let centres = items.iter().fold(Aabb::EMPTY, |b, &i| b.including(boxes[i as usize].centre()));
            let extent = centres.size();
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            let mid = (start + end) / 2;
            items.select_nth_unstable_by((mid - start) as usize, |&i, &j| {
                boxes[i as usize].centre()[axis].total_cmp(&boxes[j as usize].centre()[axis])
            });
            let first = self.nodes.len() as u32;
            self.nodes.push(blank);
            self.nodes.push(blank);
            self.nodes[node as usize] = Node { first, count: 0, connected, ..blank };
            self.build_stack.push((first, start, mid));
            self.build_stack.push((first + 1, mid, end));
        }
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Recomputes every node's box (from `boxes`, one per triangle), cone (from the triangles' corners
    /// at the start and the end of the step) and moved flag, bottom up. With `moved`, the trajectories
    /// are the last refit's except at the marked vertices, so only the triangles with a marked corner
    /// have their cones computed again (the others' are the same numbers): on a 129² drape most of the
    /// cones of a step's later broad phases, which were a third of its self-collision time.
    pub fn refit(
        &mut self,
        boxes: &[Aabb],
        triangles: &[[u32; 3]],
        start: &[DVec3],
        end: &[DVec3],
        moved: Option<&[bool]>,
    ) {
        let cone = |t: &[u32; 3]| triangle_cone(t.map(|i| (start[i as usize], end[i as usize])));
        match moved {
            Some(m) if self.cones.len() == triangles.len() => {
                for (t, c) in triangles.iter().zip(&mut self.cones) {
                    if t.iter().any(|&i| m[i as usize]) {
                        *c = cone(t);
                    }
                }
            }
            _ => {
                self.cones.clear();
                self.cones.extend(triangles.iter().map(cone));
            }
        }
        for k in (0..self.nodes.len()).rev() {
            let Node { first, count, .. } = self.nodes[k];
            let (aabb, cone, any_moved) = if count > 0 {
                let items = &self.order[first as usize..(first + count) as usize];
                let aabb = items.iter().fold(Aabb::EMPTY, |b, &i| b.union(boxes[i as usize]));
                let sum = items.iter().fold(DVec3::ZERO, |s, &i| s + self.cones[i as usize].axis);
                let cone = match sum.try_normalize() {
                    Some(axis) => Cone::around(axis, items.iter().map(|&i| self.cones[i as usize])),
                    None => Cone::FULL,
                };
                let any_moved = moved.is_none_or(|m| {
                    items.iter().any(|&i| triangles[i as usize].iter().any(|&v| m[v as usize]))
                });
                (aabb, cone, any_moved)
            } else {
                let (a, b) = (self.nodes[first as usize], self.nodes[first as usize + 1]);
                let cone = match (a.cone.axis + b.cone.axis).try_normalize() {
                    Some(axis) if a.cone.cos > -1.0 && b.cone.cos > -1.0 => {
                        Cone::around(axis, [a.cone, b.cone].into_iter())
                    }
                    _ => Cone::FULL,
                };
                (a.aabb.union(b.aabb), cone, a.moved || b.moved)
            };
            let node = &mut self.nodes[k];
            node.aabb = aabb;
            node.cone = cone;
            node.moved = any_moved;
        }
    }

    /// Visits every pair of leaves (a leaf with itself included) whose boxes overlap and, with
    /// `skip_flat`, that are not inside one flat, connected node; with `moved_only`, only pairs with a
    /// node holding a moved corner.
    pub fn self_pairs(&self, moved_only: bool, skip_flat: bool, visitor: &mut impl Visitor) {
        if self.nodes.is_empty() {
            return;
        }
        self.visit_self(0, moved_only, skip_flat, visitor);
    }

    /// Calls `visit` with the triangles (as slots of `order`) of every leaf whose box overlaps `query`;
    /// with `moved_only`, only the leaves holding a moved corner.
    pub fn query(
        &self,
        query: &Aabb,
        moved_only: bool,
        stack: &mut Vec<u32>,
        mut visit: impl FnMut(std::ops::Range<usize>),
    ) {
        stack.clear();
        if !self.nodes.is_empty() {
            stack.push(0);
        }
        while let Some(k) = stack.pop() {
            let node = &self.nodes[k as usize];
            if !node.aabb.overlaps(query) || (moved_only && !node.moved) {
                continue;
            }
            if node.count > 0 {
                visit(node.first as usize..(node.first + node.count) as usize);
            } else {
                stack.push(node.first + 1);
                stack.push(node.first);
            }
        }
    }

    fn visit_self(&self, k: u32, moved_only: bool, skip_flat: bool, visitor: &mut impl Visitor) {
        let node = &self.nodes[k as usize];
        if (moved_only && !node.moved) || (skip_flat && node.connected && node.cone.flat()) {
            return;
        }
        if node.count > 0 {
            let r = node.first as usize..(node.first + node.count) as usize;
            visitor.leaves(r.clone(), r);
            return;
        }
        self.visit_self(node.first, moved_only, skip_flat, visitor);
        self.visit_self(node.first + 1, moved_only, skip_flat, visitor);
        self.visit_pair(node.first, node.first + 1, moved_only, visitor);
    }

    fn visit_pair(&self, a: u32, b: u32, moved_only: bool, visitor: &mut impl Visitor) {
        let (na, nb) = (&self.nodes[a as usize], &self.nodes[b as usize]);
        if (moved_only && !na.moved && !nb.moved) || !na.aabb.overlaps(&nb.aabb) {
            return;
        }
        match (na.count > 0, nb.count > 0) {
            (true, true) => visitor.leaves(
                na.first as usize..(na.first + na.count) as usize,
                nb.first as usize..(nb.first + nb.count) as usize,
            ),
            // Descend into the inner node, or into the larger box when both are inner.
            (true, false) => {
                self.visit_pair(a, nb.first, moved_only, visitor);
                self.visit_pair(a, nb.first + 1, moved_only, visitor);
            }
            (false, true) => {
                self.visit_pair(na.first, b, moved_only, visitor);
                self.visit_pair(na.first + 1, b, moved_only, visitor);
            }
            (false, false) => {
                if na.aabb.size().length_squared() >= nb.aabb.size().length_squared() {
                    self.visit_pair(na.first, b, moved_only, visitor);
                    self.visit_pair(na.first + 1, b, moved_only, visitor);
                } else {
                    self.visit_pair(a, nb.first, moved_only, visitor);
                    self.visit_pair(a, nb.first + 1, moved_only, visitor);
                }
            }
        }
    }
}

/// The cone of a triangle's unit normals over a step, from its corners' (start, end): the directions of
/// the three control vectors of n(t) (module docs). A triangle that degenerates during the step (a
/// control vector of zero length) covers every direction.
fn triangle_cone([(a0, a1), (b0, b1), (c0, c1)]: [(DVec3, DVec3); 3]) -> Cone {
    let (u0, v0) = (b0 - a0, c0 - a0);
    let (u1, v1) = (b1 - a1, c1 - a1);
    let n0 = u0.cross(v0);
    let n1 = u1.cross(v1);
    let nm = (u0.cross(v1) + u1.cross(v0)) * 0.5;
    let (Some(d0), Some(dm), Some(d1)) = (n0.try_normalize(), nm.try_normalize(), n1.try_normalize()) else {
        return Cone::FULL;
    };
    let Some(axis) = (d0 + dm + d1).try_normalize() else { return Cone::FULL };
    let point = |d: DVec3| Cone { axis: d, cos: 1.0, sin: 0.0 };
    Cone::around(axis, [point(d0), point(dm), point(d1)].into_iter())
}

/// Whether the triangles `items` form one piece of surface: connected through shared edges, every edge
/// shared by at most two of them, and the two that share one running along it in opposite directions
/// (consistently oriented, so that their normals are comparable).
fn edge_connected(items: &[u32], triangles: &[[u32; 3]]) -> bool {
    if items.len() <= 1 {
        return true;
    }
    // (edge, forward, local triangle) sorted by edge: triangles with the same edge are joined.
    let mut edges: Vec<([u32; 2], bool, u32)> = Vec::with_capacity(3 * items.len());
    for (k, &t) in items.iter().enumerate() {
        let [a, b, c] = triangles[t as usize];
        for (i, j) in [(a, b), (b, c), (c, a)] {
            edges.push(([i.min(j), i.max(j)], i < j, k as u32));
        }
    }
    edges.sort_unstable();
    let mut parent: Vec<u32> = (0..items.len() as u32).collect();
    fn find(parent: &mut [u32], mut i: u32) -> u32 {
        while parent[i as usize] != i {
            parent[i as usize] = parent[parent[i as usize] as usize];
            i = parent[i as usize];
        }
        i
    }
    let mut pieces = items.len();
    for (k, w) in edges.windows(2).enumerate() {
        if w[0].0 != w[1].0 {
            continue;
        }
        // A third triangle on the edge, or two along it the same way: not one oriented surface.
        if edges.get(k + 2).is_some_and(|e| e.0 == w[0].0) || w[0].1 == w[1].1 {
            return false;
        }
        let (a, b) = (find(&mut parent, w[0].2), find(&mut parent, w[1].2));
        if a != b {
            parent[a as usize] = b;
            pieces -= 1;
        }
    }
    pieces == 1
}
