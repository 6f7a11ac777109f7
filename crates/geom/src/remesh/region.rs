//! Delete-and-regenerate of a face set (spec §6.5–§6.8, A-34 to A-40): the border of the faces becomes
//! the input of the local mesh generator, contour edges on it may be bisected (refinement) or merged
//! where straight (simplification), and the generated patch replaces the faces.

use std::collections::BTreeMap;

use glam::DVec2;

use super::local_mesh::{LocalMeshError, RetryRule, mesh_hole_with_retries};
use super::mesh::{AdaptiveMesh, NONE, OpError};

/// What to do with cloth-contour edges on the hole's border (spec §6.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContourRule {
    /// Keep them as they are.
    Keep,
    /// Refinement: bisect each contour edge with rest length ≥ `min_length` (L⁰_min guard (spec reconstruction)).
    Bisect { min_length: f64 },
    /// Simplification: drop a contour vertex whose two contour edges are collinear in rest space, if
    /// the merged edge stays ≤ `max_length` (L⁰_max guard (spec reconstruction)) and the vertex is not locked.
    MergeStraight { max_length: f64 },
}

/// Settings of [`AdaptiveMesh::remesh_region`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RegionRemeshing {
    /// The density factor d given to the generator (already scaled by the refine/simplify percentage).
    pub density: f64,
    pub retry: RetryRule,
    pub contour: ContourRule,
    pub improvement_rounds: usize,
}

/// Why a region could not be remeshed. The mesh is unchanged.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RegionError {
    #[error("the region's border touches itself at vertex {0}; pinched holes are not remeshed")]
    Pinched(u32),
    #[error(transparent)]
    Mesher(#[from] LocalMeshError),
    #[error(transparent)]
    Op(#[from] OpError),
}

/// What [`AdaptiveMesh::remesh_region`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct RegionReport {
    pub new_vertices: Vec<u32>,
    pub tries: usize,
    pub density: f64,
    pub ear_clipped: bool,
}

/// The density factor of spec §6.4 (Eq. 4.22): the mean over the border edges of the face set of
/// L⁰²/(2A⁰), A⁰ the rest area of the face of the set that holds the edge.
pub fn border_density(mesh: &AdaptiveMesh, faces: &[u32]) -> f64 {
    let (mut sum, mut n) = (0.0, 0);
    for &f in faces {
        for k in 0..3 {
            let h = 3 * f + k;
            let t = mesh.twin[h as usize];
            if t == NONE || !faces.contains(&(t / 3)) {
                let l2 =
                    mesh.rest[mesh.origin(h) as usize].distance_squared(mesh.rest[mesh.target(h) as usize]);
                sum += l2 / (2.0 * mesh.rest_area(f));
                n += 1;
            }
        }
    }
    sum / n.max(1) as f64
}

impl AdaptiveMesh {
    /// Deletes the live faces `faces` and fills the hole with a patch from the local mesh generator
    /// (with the thesis's retry loop), handling contour edges on the border as `settings.contour`
    /// says. New vertices take x and v barycentrically from the deleted faces (spec §6.7).
    pub fn remesh_region(
        &mut self,
        faces: &[u32],
        settings: &RegionRemeshing,
    ) -> Result<RegionReport, RegionError> {
        for &f in faces {
            if !self.is_face_alive(f) {
                return Err(OpError::NoSuchFace(f).into());
            }
        }
        let loops = self.region_border(faces);
        let mut seen: Vec<u32> = loops.iter().flatten().copied().collect();
        seen.sort_unstable();
        if let Some(w) = seen.windows(2).find(|w| w[0] == w[1]) {
            return Err(RegionError::Pinched(w[0]));
        }
        // Border points: existing vertices (Some) or contour midpoints (None), per loop.
        let mut border: Vec<Vec<(Option<u32>, DVec2)>> = Vec::with_capacity(loops.len());
        for ring in &loops {
            let n = ring.len();
            let mut out = Vec::with_capacity(2 * n);
            let keep = match settings.contour {
                ContourRule::MergeStraight { max_length } => self.merge_keep(ring, max_length, faces),
                _ => vec![true; n],
            };
            for i in 0..n {
                let (a, b) = (ring[i], ring[(i + 1) % n]);
                let contour = self.find_half_edge(a, b).is_some_and(|h| self.twin[h as usize] == NONE);
                let (pa, pb) = (self.rest[a as usize], self.rest[b as usize]);
                if keep[i] {
                    out.push((Some(a), pa));
                }
                if let ContourRule::Bisect { min_length } = settings.contour
                    && contour
                    && pa.distance(pb) >= min_length
                {
                    out.push((None, 0.5 * (pa + pb)));
                }
            }
            border.push(out);
        }
        let points: Vec<Vec<DVec2>> = border.iter().map(|l| l.iter().map(|p| p.1).collect()).collect();
        let r =
            mesh_hole_with_retries(&points, settings.density, &settings.retry, settings.improvement_rounds)?;
        let base = self.n_vertex_slots() as u32;
        let mut new_points = Vec::new();
        let mut map = Vec::with_capacity(r.mesh.points.len());
        for &(id, p) in border.iter().flatten() {
            map.push(id.unwrap_or_else(|| {
                new_points.push(p);
                base + new_points.len() as u32 - 1
            }));
        }
        for &p in &r.mesh.points[r.mesh.n_border..] {
            new_points.push(p);
            map.push(base + new_points.len() as u32 - 1);
        }
        let tris: Vec<[u32; 3]> = r.mesh.triangles.iter().map(|t| t.map(|i| map[i as usize])).collect();
        let new_vertices = self.replace_patch(faces, &new_points, &tris)?;
        Ok(RegionReport { new_vertices, tries: r.tries, density: r.density, ear_clipped: r.ear_clipped })
    }

    /// The vertices that [`AdaptiveMesh::remesh_region`] of `faces` under `contour` is free to remove
    /// without making an edge longer than `max_span` (rest space): those with every face in the set
    /// that are neither locked nor on the cloth contour and whose star, once they are gone, can be
    /// triangulated with no edge longer than `max_span`, and the
    /// contour vertices [`ContourRule::MergeStraight`] would drop. A region with none cannot lose a
    /// face within the bound: the mesher keeps every border point, and a disc with b border points and
    /// i inside has b − 2 + 2i triangles.
    pub fn removable_vertices(&self, faces: &[u32], contour: ContourRule, max_span: f64) -> Vec<u32> {
        let mut out = Vec::new();
        for ring in self.region_border(faces) {
            if let ContourRule::MergeStraight { max_length } = contour {
                let keep = self.merge_keep(&ring, max_length, faces);
                out.extend(ring.iter().zip(keep).filter(|(_, k)| !k).map(|(&a, _)| a));
            }
        }
        let mut vertices: Vec<u32> = faces.iter().flat_map(|&f| self.face_slots()[f as usize]).collect();
        vertices.sort_unstable();
        vertices.dedup();
        for v in vertices {
            let span = || {
                let ring: Vec<DVec2> = self.star_ring(v).iter().map(|&w| self.rest[w as usize]).collect();
                minimax_triangulation(&ring) <= max_span
            };
            if !self.locked[v as usize]
                && !self.is_boundary_vertex(v)
                && self.vertex_faces(v).iter().all(|f| faces.contains(f))
                && span()
            {
                out.push(v);
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Removes interior vertex `v` and fills its star with the triangulation of its neighbours whose
    /// longest edge is smallest, when that edge is at most `max_span`, every new edge at least
    /// `min_length` and every neighbour left with at least `min_vertex_area` (a third of the rest area
    /// of its faces, what a lumped mass follows): two faces fewer, no point moved or added. Returns the
    /// new faces, or `None` (the mesh unchanged) when `v` is locked, on the contour, or has no such
    /// triangulation.
    pub fn remove_vertex(
        &mut self,
        v: u32,
        max_span: f64,
        min_length: f64,
        min_vertex_area: f64,
    ) -> Option<Vec<u32>> {
        if !self.is_vertex_alive(v) || self.locked[v as usize] || self.is_boundary_vertex(v) {
            return None;
        }
        let ring = self.star_ring(v);
        let star = self.vertex_faces(v);
        if ring.len() != star.len() {
            return None;
        }
        let points: Vec<DVec2> = ring.iter().map(|&w| self.rest[w as usize]).collect();
        let (longest, triangles) = minimax_triangles(&points)?;
        let n = ring.len();
        let shortest_new = triangles
            .iter()
            .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
            .filter(|&(a, b)| (a + 1) % n != b && (b + 1) % n != a)
            .map(|(a, b)| points[a].distance(points[b]))
            .fold(f64::INFINITY, f64::min);
        if longest > max_span || shortest_new < min_length {
            return None;
        }
        let star_area = |k: usize| -> f64 {
            star.iter()
                .filter(|&&f| self.face_slots()[f as usize].contains(&ring[k]))
                .map(|&f| self.rest_area(f))
                .sum()
        };
        let new_area = |k: usize| -> f64 {
            triangles
                .iter()
                .filter(|t| t.contains(&k))
                .map(|t| 0.5 * super::mesh::cross2(points[t[0]], points[t[1]], points[t[2]]))
                .sum()
        };
        if (0..n)
            .any(|k| self.vertex_rest_area(ring[k]) + (new_area(k) - star_area(k)) / 3.0 < min_vertex_area)
        {
            return None;
        }
        let tris: Vec<[u32; 3]> = triangles.iter().map(|t| t.map(|k| ring[k])).collect();
        let first = self.log().added_faces.len();
        self.replace_patch(&star, &[], &tris).ok()?;
        Some(self.log().added_faces[first..].to_vec())
    }

    /// A third of the rest area of `v`'s faces: the share of the cloth's area a lumped mass follows.
    pub fn vertex_rest_area(&self, v: u32) -> f64 {
        self.vertex_faces(v).iter().map(|&f| self.rest_area(f)).sum::<f64>() / 3.0
    }

    /// The neighbours of interior vertex `v` in counter-clockwise order (the border of its star).
    fn star_ring(&self, v: u32) -> Vec<u32> {
        let faces = self.vertex_faces(v);
        // Each face [v, a, b] (rotated to start at v) gives the ring edge a → b.
        let next: BTreeMap<u32, u32> = faces
            .iter()
            .map(|&f| {
                let t = self.face_slots()[f as usize];
                let k = t.iter().position(|&c| c == v).expect("a face of v holds v");
                (t[(k + 1) % 3], t[(k + 2) % 3])
            })
            .collect();
        let Some((&start, _)) = next.iter().next() else { return Vec::new() };
        let mut ring = vec![start];
        while let Some(&w) = next.get(ring.last().expect("not empty")) {
            if w == start || ring.len() > next.len() {
                break;
            }
            ring.push(w);
        }
        ring
    }

    /// Which vertices of border loop `ring` the straight-contour merge keeps. Walking from a vertex no
    /// merge can drop, a vertex goes when it may be dropped on its own and the edge from the last kept
    /// vertex to its successor stays straight and no longer than `max_length` (so a run of droppable
    /// vertices is merged into edges of at most `max_length`, not into one long edge).
    fn merge_keep(&self, ring: &[u32], max_length: f64, faces: &[u32]) -> Vec<bool> {
        let n = ring.len();
        let mut keep = vec![true; n];
        let at = |i: usize| (ring[(i + n - 1) % n], ring[i], ring[(i + 1) % n]);
        let Some(s) = (0..n).find(|&i| {
            let (prev, a, next) = at(i);
            !self.droppable(prev, a, next, max_length, faces)
        }) else {
            return keep;
        };
        let mut anchor = self.rest[ring[s] as usize];
        for k in 1..n {
            let i = (s + k) % n;
            let (prev, a, next) = at(i);
            let (q, r) = (self.rest[a as usize], self.rest[next as usize]);
            let straight =
                super::mesh::cross2(anchor, q, r).abs() <= 1e-12 * anchor.distance(q) * q.distance(r);
            if self.droppable(prev, a, next, max_length, faces)
                && straight
                && anchor.distance(r) <= max_length
            {
                keep[i] = false;
            } else {
                anchor = q;
            }
        }
        keep
    }

    /// Whether border vertex `a` (between `prev` and `next` on the loop) may be dropped: both its loop
    /// edges are contour edges, they are collinear, the merged edge is short enough, it is not locked
    /// and all its faces are in the region.
    fn droppable(&self, prev: u32, a: u32, next: u32, max_length: f64, faces: &[u32]) -> bool {
        let on_contour =
            |x: u32, y: u32| self.find_half_edge(x, y).is_some_and(|h| self.twin[h as usize] == NONE);
        if self.locked[a as usize] || !on_contour(prev, a) || !on_contour(a, next) {
            return false;
        }
        let (p, q, r) = (self.rest[prev as usize], self.rest[a as usize], self.rest[next as usize]);
        let straight = super::mesh::cross2(p, q, r).abs() <= 1e-12 * p.distance(q) * q.distance(r);
        straight && p.distance(r) <= max_length && self.vertex_faces(a).iter().all(|f| faces.contains(f))
    }
}

/// Whether segments ab and cd cross at a point inside both.
fn cross_properly(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let (d1, d2) = (super::mesh::cross2(a, b, c), super::mesh::cross2(a, b, d));
    let (d3, d4) = (super::mesh::cross2(c, d, a), super::mesh::cross2(c, d, b));
    d1 * d2 < 0.0 && d3 * d4 < 0.0
}

/// Whether `q` lies inside the closed polygon `p` (crossing number).
fn contains(p: &[DVec2], q: DVec2) -> bool {
    let n = p.len();
    let mut inside = false;
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        if (a.y > q.y) != (b.y > q.y) && q.x < a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y) {
            inside = !inside;
        }
    }
    inside
}

/// The smallest possible longest edge over the triangulations of the simple counter-clockwise polygon
/// `p` that add no point (its sides included); ∞ when it has none (fewer than three points, or no
/// proper triangulation). Dynamic programming over sub-chains, O(n³): used on vertex stars, n ≈ 6.
fn minimax_triangulation(p: &[DVec2]) -> f64 {
    minimax_triangles(p).map_or(f64::INFINITY, |(longest, _)| longest)
}

/// [`minimax_triangulation`]'s triangulation: its longest edge and its triangles (indices into `p`,
/// counter-clockwise); `None` when there is none.
fn minimax_triangles(p: &[DVec2]) -> Option<(f64, Vec<[usize; 3]>)> {
    let n = p.len();
    if n < 3 {
        return None;
    }
    let crosses = |a: usize, b: usize| {
        (0..n).any(|i| {
            let j = (i + 1) % n;
            i != a && i != b && j != a && j != b && cross_properly(p[a], p[b], p[i], p[j])
        })
    };
    // A chord of the polygon: a side, or a diagonal crossing no side with its midpoint inside.
    let chord = |a: usize, b: usize| {
        (b == (a + 1) % n || a == (b + 1) % n) || (!crosses(a, b) && contains(p, 0.5 * (p[a] + p[b])))
    };
    let mut best = vec![vec![f64::INFINITY; n]; n];
    let mut split = vec![vec![usize::MAX; n]; n];
    for i in 0..n - 1 {
        best[i][i + 1] = 0.0;
    }
    for gap in 2..n {
        for i in 0..n - gap {
            let j = i + gap;
            if !chord(i, j) {
                continue;
            }
            for k in i + 1..j {
                if super::mesh::is_proper(p[i], p[k], p[j]) {
                    let worst = best[i][k].max(best[k][j]).max(p[i].distance(p[k])).max(p[k].distance(p[j]));
                    if worst < best[i][j] {
                        best[i][j] = worst;
                        split[i][j] = k;
                    }
                }
            }
        }
    }
    let longest = best[0][n - 1].max(p[0].distance(p[n - 1]));
    if !longest.is_finite() {
        return None;
    }
    let mut triangles = Vec::with_capacity(n - 2);
    let mut todo = vec![(0, n - 1)];
    while let Some((i, j)) = todo.pop() {
        if j <= i + 1 {
            continue;
        }
        let k = split[i][j];
        triangles.push([i, k, j]);
        todo.push((i, k));
        todo.push((k, j));
    }
    Some((longest, triangles))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::DiagonalPattern;
    use crate::remesh::tests::{field, grid};

    fn block(m: &AdaptiveMesh, lo: DVec2, hi: DVec2) -> Vec<u32> {
        m.live_faces()
            .filter(|&f| {
                m.face_slots()[f as usize].iter().all(|&v| {
                    let p = m.rest()[v as usize];
                    p.cmpge(lo - 1e-12).all() && p.cmple(hi + 1e-12).all()
                })
            })
            .collect()
    }

    #[test]
    fn density_factor_is_the_mean_border_edge_factor() {
        // Eq. 4.22, fator_j = L⁰_j² / (2 A⁰_j), over the border edges of the face set. A right-isosceles
        // grid triangle has 1 on each leg and 2 on its hypotenuse; a square of two has four legs; an
        // equilateral triangle has 2/√3 on every side. The factor does not depend on size.
        for size in [1.0, 0.1] {
            let m = grid(2, size, DiagonalPattern::Uniform);
            assert!((border_density(&m, &[0]) - 4.0 / 3.0).abs() < 1e-12, "one face, side {size}");
            assert!((border_density(&m, &[0, 1]) - 1.0).abs() < 1e-12, "both faces, side {size}");
        }
        let h = 0.75f64.sqrt();
        let rest = vec![DVec2::ZERO, DVec2::X, DVec2::new(0.5, h)];
        let x = rest.iter().map(|p| p.extend(0.0)).collect();
        let tri = AdaptiveMesh::new(rest, x, vec![glam::DVec3::ZERO; 3], vec![[0, 1, 2]]).unwrap();
        assert!((border_density(&tri, &[0]) - 2.0 / 3f64.sqrt()).abs() < 1e-12);
        // The whole 3 × 3 grid: its inner edges (hypotenuses among them) do not count, only the eight
        // contour legs.
        let m = grid(3, 1.0, DiagonalPattern::Uniform);
        let all: Vec<u32> = (0..8).collect();
        assert!((border_density(&m, &all) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn removable_vertices_are_inside_unlocked_and_within_the_span() {
        // 3 × 3 grid of side 1: only the centre, 4, has all its faces inside and is off the contour. Its
        // star, the hexagon 0, 1, 5, 8, 7, 3, closes at best with edges of 1 m (diagonals 1–7, 1–3 and
        // 5–7; every triangulation needs one of 1–7, 3–5 or a longer one).
        let mut m = grid(3, 1.0, DiagonalPattern::Uniform);
        let all: Vec<u32> = (0..8).collect();
        let span = 1.0;
        assert_eq!(m.removable_vertices(&all, ContourRule::Keep, span), vec![4]);
        assert!(m.removable_vertices(&all, ContourRule::Keep, 0.99 * span).is_empty(), "span too short");
        assert!(m.removable_vertices(&all[1..], ContourRule::Keep, span).is_empty(), "a face of 4 is out");
        // Straight contour vertices (1, 3, 5, 7) join when the merge may drop them (merged edge 1 m).
        let merge = ContourRule::MergeStraight { max_length: 1.0 };
        assert_eq!(m.removable_vertices(&all, merge, span), vec![1, 3, 4, 5, 7]);
        let short = ContourRule::MergeStraight { max_length: 0.9 };
        assert_eq!(m.removable_vertices(&all, short, span), vec![4]);
        assert_eq!(minimax_triangulation(&[0, 1, 5, 8, 7, 3].map(|v| m.rest()[v])), 1.0);
        m.set_locked(4, true);
        m.set_locked(7, true);
        assert_eq!(m.removable_vertices(&all, merge, span), vec![1, 3, 5]);
    }

    #[test]
    fn removing_a_vertex_fills_its_star_within_the_bounds() {
        // The 3 × 3 grid's centre: its hexagon star closes at best with 1 m edges (see above), with
        // diagonals of 1 m and √0.5 m.
        let mut m = grid(3, 1.0, DiagonalPattern::Uniform);
        let (faces, area) = (m.n_faces(), m.total_rest_area());
        assert_eq!(m.remove_vertex(4, 0.99, 0.0, 0.0), None, "span too short");
        assert_eq!(m.remove_vertex(4, 1.0, 1.01, 0.0), None, "a new edge under the short-edge limit");
        assert_eq!(m.remove_vertex(1, 2.0, 0.0, 0.0), None, "a contour vertex stays");
        assert_eq!(m.n_faces(), faces, "refusals leave the mesh as it was");
        // The neighbours' areas after the removal: they still share the whole area, and a floor above
        // the smallest of them refuses.
        let mut probe = m.clone();
        probe.remove_vertex(4, 1.0, 0.7, 0.0).expect("within the bounds");
        let shares: Vec<f64> = (0..9).filter(|&v| v != 4).map(|v| probe.vertex_rest_area(v)).collect();
        assert!((shares.iter().sum::<f64>() - area).abs() < 1e-12);
        let least = shares.iter().copied().fold(f64::INFINITY, f64::min);
        assert_eq!(m.remove_vertex(4, 1.0, 0.7, 1.01 * least), None, "a neighbour's share too small");
        let new = m.remove_vertex(4, 1.0, 0.7, 0.99 * least).expect("within the bounds");
        assert_eq!(new.len(), 4);
        assert_eq!(m.n_faces(), faces - 2);
        assert!(!m.is_vertex_alive(4));
        assert!((m.total_rest_area() - area).abs() < 1e-12);
        for &f in &new {
            let t = m.face_slots()[f as usize];
            for k in 0..3 {
                let l = m.rest()[t[k] as usize].distance(m.rest()[t[(k + 1) % 3] as usize]);
                assert!(l <= 1.0 + 1e-12, "edge {l}");
            }
        }
        let mut locked = grid(3, 1.0, DiagonalPattern::Uniform);
        locked.set_locked(4, true);
        assert_eq!(locked.remove_vertex(4, 2.0, 0.0, 0.0), None, "a locked vertex stays");
    }

    #[test]
    fn refine_and_simplify_a_region_in_place() {
        let mut m = grid(9, 1.0, DiagonalPattern::Uniform);
        let area = m.total_rest_area();
        // Refine an interior block and a block on the contour (its contour edges are bisected).
        for (lo, hi) in
            [(DVec2::splat(0.25), DVec2::splat(0.75)), (DVec2::new(0.0, 0.0), DVec2::new(0.25, 0.25))]
        {
            let faces = block(&m, lo, hi);
            let d = border_density(&m, &faces) * 1.01 * 2.0;
            let settings = RegionRemeshing {
                density: d,
                retry: RetryRule::refinement(Some(0.01)),
                contour: ContourRule::Bisect { min_length: 0.05 },
                improvement_rounds: 3,
            };
            let n_before = m.n_faces();
            let r = m.remesh_region(&faces, &settings).unwrap();
            m.check_invariants().unwrap();
            assert!((m.total_rest_area() - area).abs() < 1e-13);
            assert!(m.n_faces() > n_before && !r.new_vertices.is_empty(), "{r:?}");
            for &v in &r.new_vertices {
                let want = field(m.rest()[v as usize]);
                assert!((m.velocities()[v as usize] - want).length() < 1e-12, "barycentric transfer at {v}");
                assert!(m.positions()[v as usize].z.abs() < 1e-15);
            }
        }
        // Simplify the top strip, merging straight contour runs.
        let faces = block(&m, DVec2::new(0.0, 0.75), DVec2::new(1.0, 1.0));
        let n_before = m.n_faces();
        let settings = RegionRemeshing {
            density: border_density(&m, &faces) * 0.35,
            retry: RetryRule::simplification(),
            contour: ContourRule::MergeStraight { max_length: 0.3 },
            improvement_rounds: 3,
        };
        m.remesh_region(&faces, &settings).unwrap();
        m.check_invariants().unwrap();
        assert!((m.total_rest_area() - area).abs() < 1e-13);
        assert!(m.n_faces() < n_before, "{} from {n_before}", m.n_faces());
        assert!(m.is_vertex_alive(72) && m.is_vertex_alive(80), "corners stay");
        // Straight contour vertices of the top edge are merged away, into edges no longer than 0.3 m
        // (pairs of 0.125 m edges: the eight become five or fewer, never one 1 m edge).
        let top: Vec<u32> = (72..=80).filter(|&v| m.is_vertex_alive(v)).collect();
        assert!(top.len() < 9 && top.len() >= 5, "{top:?}");
        for w in top.windows(2) {
            let l = m.rest()[w[0] as usize].distance(m.rest()[w[1] as usize]);
            assert!(l <= 0.3 + 1e-12, "merged contour edge {w:?} of {l} m");
        }
    }
}
