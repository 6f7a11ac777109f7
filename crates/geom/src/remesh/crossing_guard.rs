//! Keeping a remesh from passing the cloth through itself.
//!
//! A split puts its new vertex on the edge it splits, so its triangles tile the old ones in world
//! space and cannot cross anything the old ones did not. A flip and a collapse change the surface:
//! the flip of edge ab to cd replaces two triangles by the other two faces of the tetrahedron abcd,
//! and a collapse sweeps each triangle of the removed vertex's star onto its neighbour. Cloth lying
//! within a few edge lengths (a fold, a layer resting on another) can then end up crossed, and no
//! self-collision response undoes a crossing once it exists. Measured on the Bunny drape at 1/60 s
//! (17² remeshed by the sizing field to about 2 200 particles, `min_edge_m` = 1.56 cm): one remesh at
//! 0.62 s made 8 crossing pairs, which stayed to the end.
//!
//! So while the guard is on, a flip or collapse is refused when its new triangles would cross (an edge
//! through a triangle, [`segment_crosses_triangle`]) the live triangles outside the operation in more
//! pairs than the triangles they replace did. The live triangles that can meet the new ones are found in a
//! grid of the faces' world boxes (cells of the median edge length), to which every face an operation
//! makes is added. A face whose box spans more than [`MAX_CELLS`] cells (a mesh torn apart by a run
//! that left its bounds) is kept in a list that every query reads instead, and a query whose box spans
//! more reads every live face, so the guard's memory and work stay bounded on any mesh.

use glam::DVec3;

use super::mesh::AdaptiveMesh;
use crate::self_contact::segment_crosses_triangle;

/// The most grid cells a face is entered in, or a query reads.
pub(crate) const MAX_CELLS: usize = 512;

/// The faces of a mesh in cubic cells of their world boxes, hashed into buckets, each bucket a list
/// threaded through `entries` from `head` (a face is in the bucket of each of its cells; cells that
/// share a bucket share its list, and the queries' box test sorts them out). Built afresh on every
/// pass into the buffers of the last, and faces are added in place: a remesh each step allocates
/// nothing here once they have grown.
#[derive(Debug, Clone, Default)]
pub(crate) struct CrossingGuard {
    /// Whether flips and collapses are checked ([`AdaptiveMesh::guard_crossings`]).
    pub(crate) on: bool,
    cell: f64,
    /// Per bucket, its last entry (or [`END`]).
    head: Vec<u32>,
    /// (face, the bucket's entry before this one).
    entries: Vec<(u32, u32)>,
    /// Faces whose boxes span more than [`MAX_CELLS`] cells.
    large: Vec<u32>,
    /// Operations refused since the guard was built.
    pub(crate) refused: usize,
    faces: Vec<u32>,
    lengths: Vec<f64>,
}

/// The end of a bucket's list.
const END: u32 = u32::MAX;

impl CrossingGuard {
    /// The cells of a box, or `None` when they are more than [`MAX_CELLS`].
    fn keys(&self, lo: DVec3, hi: DVec3) -> Option<impl Iterator<Item = [i64; 3]> + use<>> {
        let (a, b) = ((lo / self.cell).floor(), (hi / self.cell).floor());
        let span = (b - a + DVec3::ONE).max(DVec3::ONE);
        let cells = span.x * span.y * span.z;
        // Not finite (NaN positions) counts as too many.
        if cells.is_nan() || cells > MAX_CELLS as f64 {
            return None;
        }
        let (a, b) = (a.as_i64vec3(), b.as_i64vec3());
        Some(
            (a.x..=b.x).flat_map(move |i| (a.y..=b.y).flat_map(move |j| (a.z..=b.z).map(move |k| [i, j, k]))),
        )
    }

    /// The bucket of a cell (a fixed hash: the same buckets on every run).
    fn bucket(&self, key: [i64; 3]) -> usize {
        let h = (key[0] as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ (key[1] as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F)
            ^ (key[2] as u64).wrapping_mul(0x1656_67B1_9E37_79F9);
        ((h ^ (h >> 29)) as usize) & (self.head.len() - 1)
    }

    /// Empties the guard into `buckets` buckets (a power of two).
    fn clear(&mut self, buckets: usize) {
        self.head.clear();
        self.head.resize(buckets, END);
        self.entries.clear();
        self.large.clear();
    }

    /// Adds face `f` with corners `p`.
    fn insert(&mut self, f: u32, p: [DVec3; 3]) {
        let (lo, hi) = (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2]));
        match self.keys(lo, hi) {
            Some(keys) => {
                for key in keys {
                    let b = self.bucket(key);
                    self.entries.push((f, self.head[b]));
                    self.head[b] = (self.entries.len() - 1) as u32;
                }
            }
            None => self.large.push(f),
        }
    }
}

impl AdaptiveMesh {
    /// Turns the crossing guard on (built from the current world positions: rebuild it whenever they
    /// change) or off. While it is on, [`AdaptiveMesh::flip_edge`] and [`AdaptiveMesh::collapse_edge`]
    /// refuse with [`super::OpError::Crossing`] an operation that would make the cloth cross itself.
    pub fn guard_crossings(&mut self, on: bool) {
        let mut g = self.crossing_guard.take().unwrap_or_default();
        g.on = on;
        g.refused = 0;
        if on {
            // Cells of the median edge: torn faces (a run that left its bounds) do not make them large.
            g.lengths.clear();
            g.lengths.extend(self.live_faces().flat_map(|f| {
                let [a, b, c] = self.corners(f);
                [a.distance(b), b.distance(c), c.distance(a)]
            }));
            let cell = if g.lengths.is_empty() {
                1.0
            } else {
                let mid = g.lengths.len() / 2;
                *g.lengths.select_nth_unstable_by(mid, f64::total_cmp).1
            };
            g.cell = if cell > 1e-9 { cell } else { 1e-9 };
            g.clear((2 * self.n_faces()).next_power_of_two().max(64));
            for f in self.live_faces() {
                g.insert(f, self.corners(f));
            }
        }
        self.crossing_guard = Some(g);
    }

    fn corners(&self, f: u32) -> [DVec3; 3] {
        self.faces[f as usize].map(|i| self.x[i as usize])
    }

    /// Adds faces made by an operation to the guard, when it is on.
    pub(crate) fn guard_new_faces(&mut self, faces: std::ops::Range<u32>) {
        if let Some(mut g) = self.crossing_guard.take() {
            if g.on {
                for f in faces {
                    g.insert(f, self.corners(f));
                }
            }
            self.crossing_guard = Some(g);
        }
    }

    /// Whether replacing the faces `old` by `new` would add crossings with the live faces outside `old`
    /// (false when the guard is off); counts a refusal when it would. Crossings that were there before
    /// (the old faces crossed as many) do not refuse an operation: the remesh makes none, and it may go
    /// on where the cloth already crosses itself.
    pub(crate) fn would_cross(&mut self, old: &[u32], new: &[[u32; 3]]) -> bool {
        let Some(mut g) = self.crossing_guard.take_if(|g| g.on) else { return false };
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for tri in new {
            for p in tri.map(|i| self.x[i as usize]) {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        g.faces.clear();
        let outside = |f: &u32| self.is_face_alive(*f) && !old.contains(f);
        match g.keys(lo, hi) {
            Some(keys) => {
                for key in keys {
                    let mut e = g.head[g.bucket(key)];
                    while e != END {
                        let (f, next) = g.entries[e as usize];
                        if outside(&f) {
                            g.faces.push(f);
                        }
                        e = next;
                    }
                }
                g.faces.extend(g.large.iter().filter(|f| outside(f)));
            }
            None => g.faces.extend(self.live_faces().filter(|f| outside(f))),
        }
        g.faces.sort_unstable();
        g.faces.dedup();
        // Only faces whose boxes meet the new triangles' can cross them (or be crossed by the old ones
        // within that box).
        g.faces.retain(|&f| {
            let q = self.corners(f);
            let (flo, fhi) = (q[0].min(q[1]).min(q[2]), q[0].max(q[1]).max(q[2]));
            !(flo.cmpgt(hi).any() || fhi.cmplt(lo).any())
        });
        let crosses = |edge_of: [u32; 3], through: [u32; 3]| {
            let p = edge_of.map(|i| self.x[i as usize]);
            let q = through.map(|i| self.x[i as usize]);
            (0..3).any(|k| {
                let (a, b) = (edge_of[k], edge_of[(k + 1) % 3]);
                !through.contains(&a)
                    && !through.contains(&b)
                    && segment_crosses_triangle(p[k], p[(k + 1) % 3], q)
            })
        };
        // Crossing pairs of the new faces, and of the old ones, with the live faces around them.
        let count = |tris: &mut dyn Iterator<Item = [u32; 3]>| -> usize {
            tris.map(|n| {
                g.faces
                    .iter()
                    .filter(|&&f| {
                        let tri = self.faces[f as usize];
                        crosses(n, tri) || crosses(tri, n)
                    })
                    .count()
            })
            .sum()
        };
        let made = count(&mut new.iter().copied());
        let found = made > 0 && made > count(&mut old.iter().map(|&f| self.faces[f as usize]));
        g.refused += usize::from(found);
        self.crossing_guard = Some(g);
        found
    }
}

#[cfg(test)]
mod tests {
    use glam::DVec2;

    use super::super::{OpError, OpGuards};
    use super::*;
    use crate::count_self_intersections;

    /// A unit square of two triangles split by the diagonal 0–2, with corners 1 and 3 raised to z = 1,
    /// and apart from it in rest space a small upright triangle whose world position is `at` + its
    /// shape, in the plane x = y. Flipping the diagonal to 1–3 makes an edge at z = 1 across the middle,
    /// through that triangle when it stands at (0.5, 0.5).
    fn folded_square_beside(at: DVec3) -> AdaptiveMesh {
        let rest = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0], [2.0, 0.0], [3.0, 0.0], [2.0, 1.0]]
            .map(|[x, y]| DVec2::new(x, y));
        let x = [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 1.0),
            at + DVec3::new(-0.2, -0.2, -0.2),
            at + DVec3::new(0.2, 0.2, -0.2),
            at + DVec3::new(0.0, 0.0, 0.3),
        ];
        let triangles = vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]];
        AdaptiveMesh::new(rest.to_vec(), x.to_vec(), vec![DVec3::ZERO; 7], triangles).unwrap()
    }

    fn crossings(mesh: &AdaptiveMesh) -> usize {
        count_self_intersections(mesh.positions(), &mesh.triangles())
    }

    #[test]
    fn a_flip_through_other_cloth_is_refused_while_guarded() {
        let guards = OpGuards::validity_only();
        let through = DVec3::new(0.5, 0.5, 1.0);
        // Unguarded, the flip passes the square through the small triangle.
        let mut free = folded_square_beside(through);
        assert_eq!(crossings(&free), 0);
        free.flip_edge(0, 2, &guards).unwrap();
        assert!(crossings(&free) > 0, "the test's flip must cross the small triangle");
        // Guarded, it is refused and nothing changes.
        let mut guarded = folded_square_beside(through);
        guarded.guard_crossings(true);
        let before = guarded.clone();
        assert_eq!(guarded.flip_edge(0, 2, &guards), Err(OpError::Crossing));
        assert_eq!(guarded, before);
        assert_eq!(guarded.crossing_guard.as_ref().map(|g| g.refused), Some(1));
        // With the small triangle out of the way the same flip goes through.
        let mut clear = folded_square_beside(DVec3::new(0.5, 0.5, 3.0));
        clear.guard_crossings(true);
        clear.flip_edge(0, 2, &guards).unwrap();
        assert_eq!(crossings(&clear), 0);
    }

    #[test]
    fn faces_an_operation_makes_are_guarded_too() {
        // Split the small triangle's bottom edge while guarded: its face dies, and only the two new
        // faces, which the split adds to the guard's grid, stand in the flip's way.
        let guards = OpGuards::validity_only();
        let at = DVec3::new(0.45, 0.45, 1.0);
        let mut free = folded_square_beside(at);
        free.split_edge(4, 5, &guards).unwrap();
        free.flip_edge(0, 2, &guards).unwrap();
        assert!(crossings(&free) > 0, "the test's flip must cross the split triangle");
        let mut guarded = folded_square_beside(at);
        guarded.guard_crossings(true);
        guarded.split_edge(4, 5, &guards).unwrap();
        assert_eq!(guarded.flip_edge(0, 2, &guards), Err(OpError::Crossing));
        assert_eq!(crossings(&guarded), 0);
    }

    #[test]
    fn a_torn_mesh_is_guarded_within_bounded_memory() {
        // The small triangle blown up to kilometres (as after a run that left its bounds): it goes in the
        // list of large faces, not in millions of cells, and still refuses the flip through it.
        let guards = OpGuards::validity_only();
        let mut mesh = folded_square_beside(DVec3::new(0.5, 0.5, 1.0));
        for p in &mut mesh.positions_mut()[4..] {
            *p = DVec3::new(0.5, 0.5, 1.0) + (*p - DVec3::new(0.5, 0.5, 1.0)) * 1e4;
        }
        mesh.guard_crossings(true);
        let g = mesh.crossing_guard.as_ref().unwrap();
        assert_eq!(g.large, vec![2]);
        assert!(g.entries.len() <= 2 * MAX_CELLS);
        assert_eq!(mesh.flip_edge(0, 2, &guards), Err(OpError::Crossing));
    }
}
