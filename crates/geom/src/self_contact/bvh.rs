//! A bounding-volume hierarchy of axis-aligned boxes, built by median splits (the crossing count's; the
//! broad phase keeps a tree of its own with normal cones, [`super::patch_tree`]).
//!
//! Median split of box centres along the widest axis, at most [`LEAF_SIZE`] boxes per leaf, children
//! stored after their parent. Every buffer is kept between calls, so neither building nor querying
//! allocates once the capacities have grown to the mesh.

use crate::Aabb;

/// Largest number of boxes in a leaf.
const LEAF_SIZE: u32 = 4;

#[derive(Debug, Clone, Copy)]
struct Node {
    aabb: Aabb,
    /// For a leaf, the first slot of its boxes in `order`; for an inner node, the index of its first
    /// child (the second is `first + 1`).
    first: u32,
    /// Number of boxes of a leaf; 0 marks an inner node.
    count: u32,
}

#[derive(Debug, Clone, Default)]
pub(crate) struct Bvh {
    nodes: Vec<Node>,
    /// Box indices in leaf order.
    order: Vec<u32>,
    /// One box per item, filled by the caller before [`Bvh::build`].
    pub boxes: Vec<Aabb>,
    build_stack: Vec<(u32, u32, u32)>,
}

impl Bvh {
    /// Builds the tree over `self.boxes`.
    pub fn build(&mut self) {
        let n = u32::try_from(self.boxes.len()).expect("fewer than 2³² boxes");
        self.nodes.clear();
        self.order.clear();
        self.order.extend(0..n);
        if n == 0 {
            return;
        }
        self.nodes.push(Node { aabb: Aabb::EMPTY, first: 0, count: 0 });
        self.build_stack.clear();
        self.build_stack.push((0, 0, n));
        while let Some((node, start, end)) = self.build_stack.pop() {
            let items = &mut self.order[start as usize..end as usize];
            let mut aabb = Aabb::EMPTY;
            let mut centres = Aabb::EMPTY;
            for &i in items.iter() {
                let b = self.boxes[i as usize];
                aabb = aabb.union(b);
                centres = centres.including(b.centre());
            }
            if end - start <= LEAF_SIZE {
                self.nodes[node as usize] = Node { aabb, first: start, count: end - start };
                continue;
            }
            let extent = centres.size();
            let axis = if extent.x >= extent.y && extent.x >= extent.z {
                0
            } else if extent.y >= extent.z {
                1
            } else {
                2
            };
            let mid = (start + end) / 2;
            let boxes = &self.boxes;
            items.select_nth_unstable_by((mid - start) as usize, |&i, &j| {
                boxes[i as usize].centre()[axis].total_cmp(&boxes[j as usize].centre()[axis])
            });
            let first = self.nodes.len() as u32;
            self.nodes.push(Node { aabb: Aabb::EMPTY, first: 0, count: 0 });
            self.nodes.push(Node { aabb: Aabb::EMPTY, first: 0, count: 0 });
            self.nodes[node as usize] = Node { aabb, first, count: 0 };
            self.build_stack.push((first, start, mid));
            self.build_stack.push((first + 1, mid, end));
        }
    }

    /// Calls `visit` with every item whose box overlaps `query` (closed boxes: touching counts), in a
    /// deterministic order. `stack` is scratch space the caller keeps.
    #[inline]
    pub fn query(&self, query: &Aabb, stack: &mut Vec<u32>, mut visit: impl FnMut(u32)) {
        stack.clear();
        if !self.nodes.is_empty() {
            stack.push(0);
        }
        while let Some(k) = stack.pop() {
            let node = &self.nodes[k as usize];
            if !node.aabb.overlaps(query) {
                continue;
            }
            if node.count > 0 {
                for &i in &self.order[node.first as usize..(node.first + node.count) as usize] {
                    if self.boxes[i as usize].overlaps(query) {
                        visit(i);
                    }
                }
            } else {
                stack.push(node.first + 1);
                stack.push(node.first);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    fn boxes(n: usize, offset: f64) -> Vec<Aabb> {
        (0..n)
            .map(|k| {
                let p = DVec3::new((k % 7) as f64, (k / 7 % 5) as f64, (k / 35) as f64 * 0.5 + offset);
                Aabb { min: p, max: p + DVec3::splat(0.6) }
            })
            .collect()
    }

    fn brute(boxes: &[Aabb], q: &Aabb) -> Vec<u32> {
        (0..boxes.len() as u32).filter(|&i| boxes[i as usize].overlaps(q)).collect()
    }

    #[test]
    fn query_matches_brute_force() {
        let mut bvh = Bvh { boxes: boxes(200, 0.0), ..Bvh::default() };
        bvh.build();
        let mut stack = Vec::new();
        let queries = boxes(200, 0.3);
        for q in &queries {
            let mut found = Vec::new();
            bvh.query(q, &mut stack, |i| found.push(i));
            found.sort_unstable();
            assert_eq!(found, brute(&bvh.boxes, q));
        }
    }

    #[test]
    fn empty_tree_finds_nothing() {
        let mut bvh = Bvh::default();
        bvh.build();
        bvh.query(&Aabb { min: DVec3::splat(-1.0), max: DVec3::ONE }, &mut Vec::new(), |_| {
            panic!("no boxes")
        });
    }
}
