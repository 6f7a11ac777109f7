//! Delete-and-regenerate of a face set (spec §6.5–§6.8, A-34 to A-40): the border of the faces becomes
//! the input of the local mesh generator, contour edges on it may be bisected (refinement) or merged
//! where straight (simplification), and the generated patch replaces the faces.

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
            for i in 0..n {
                let (a, b) = (ring[i], ring[(i + 1) % n]);
                let contour = self.find_half_edge(a, b).is_some_and(|h| self.twin[h as usize] == NONE);
                let (pa, pb) = (self.rest[a as usize], self.rest[b as usize]);
                let prev = ring[(i + n - 1) % n];
                let keep = match settings.contour {
                    ContourRule::MergeStraight { max_length } => {
                        !self.droppable(prev, a, b, max_length, faces)
                    }
                    _ => true,
                };
                if keep {
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
        assert!(!m.is_vertex_alive(76), "a straight contour vertex is merged away");
    }
}
