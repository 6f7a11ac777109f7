//! Triangle meshes cut from a plane: 2-D material (rest) coordinates X per vertex, triangles, and their
//! half-edge adjacency. A cloth simulation places the mesh in 3-D and moves its vertices; rest lengths
//! and rest areas always come from X, so they do not change as the cloth deforms.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

use crate::halfedge::{HalfEdges, TopologyError};

/// Why a set of material coordinates and triangles was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MaterialMeshError {
    #[error("material coordinate {0} is not finite")]
    NonFinite(usize),
    #[error(
        "triangle {triangle} has rest area {area:e} m²; every triangle must be counter-clockwise in \
         material space with positive area"
    )]
    BadRestArea { triangle: usize, area: f64 },
    #[error(transparent)]
    Topology(#[from] TopologyError),
    #[error("a grid needs at least 2 × 2 vertices and a positive finite size, got {n} × {n} over {size} m")]
    BadGrid { n: usize, size: f64 },
}

/// Which diagonal splits each square of a regular grid (Oliveira 2013 §5.2.1 does not say; spec A-3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum DiagonalPattern {
    /// Every square split from its (row, col) corner to its (row + 1, col + 1) corner. The default:
    /// the spec's reference numbers (§7.5) assume one diagonal direction everywhere.
    #[default]
    Uniform,
    /// Every square split by the other diagonal, (row, col + 1) to (row + 1, col).
    Flipped,
    /// The two directions in a checkerboard, so the mesh has no preferred diagonal.
    Alternating,
}

/// A planar triangle mesh in material coordinates, validated once.
#[derive(Debug, Clone, PartialEq)]
pub struct MaterialMesh {
    rest: Vec<DVec2>,
    topology: HalfEdges,
}

impl MaterialMesh {
    /// Checks that coordinates are finite, that every triangle is counter-clockwise with positive rest
    /// area, and that the triangles form an oriented 2-manifold.
    pub fn new(rest: Vec<DVec2>, triangles: Vec<[u32; 3]>) -> Result<Self, MaterialMeshError> {
        if let Some(i) = rest.iter().position(|p| !p.is_finite()) {
            return Err(MaterialMeshError::NonFinite(i));
        }
        let topology = HalfEdges::new(rest.len(), &triangles)?;
        let mesh = Self { rest, topology };
        for t in 0..mesh.n_faces() {
            let area = mesh.rest_area(t);
            if area.is_nan() || area <= 0.0 {
                return Err(MaterialMeshError::BadRestArea { triangle: t, area });
            }
        }
        Ok(mesh)
    }

    /// A regular `n × n`-vertex grid over the square [0, size]², vertex (row, col) at index
    /// `row·n + col` with X = (col, row)·size/(n − 1). Triangles are counter-clockwise seen from +z
    /// when X is laid out on the x–y plane; two per square, split as `pattern` says.
    pub fn grid(n: usize, size: f64, pattern: DiagonalPattern) -> Result<Self, MaterialMeshError> {
        if n < 2
            || !(size > 0.0 && size.is_finite())
            || n.checked_mul(n).is_none_or(|m| m > u32::MAX as usize)
        {
            return Err(MaterialMeshError::BadGrid { n, size });
        }
        let h = size / (n - 1) as f64;
        let rest = (0..n * n).map(|k| DVec2::new((k % n) as f64 * h, (k / n) as f64 * h)).collect();
        let mut triangles = Vec::with_capacity(2 * (n - 1) * (n - 1));
        for row in 0..n - 1 {
            for col in 0..n - 1 {
                let p = (row * n + col) as u32;
                let right = p + 1;
                let up = p + n as u32;
                let diagonal = up + 1;
                let main = match pattern {
                    DiagonalPattern::Uniform => true,
                    DiagonalPattern::Flipped => false,
                    DiagonalPattern::Alternating => (row + col) % 2 == 0,
                };
                if main {
                    triangles.push([p, right, diagonal]);
                    triangles.push([p, diagonal, up]);
                } else {
                    triangles.push([p, right, up]);
                    triangles.push([right, diagonal, up]);
                }
            }
        }
        Self::new(rest, triangles)
    }

    /// Material coordinates X, m.
    pub fn rest(&self) -> &[DVec2] {
        &self.rest
    }

    pub fn triangles(&self) -> &[[u32; 3]] {
        self.topology.triangles()
    }

    pub fn topology(&self) -> &HalfEdges {
        &self.topology
    }

    pub fn n_vertices(&self) -> usize {
        self.rest.len()
    }

    pub fn n_edges(&self) -> usize {
        self.topology.n_edges()
    }

    pub fn n_faces(&self) -> usize {
        self.topology.n_faces()
    }

    /// Signed rest area of triangle `t` in material space, m² (positive when counter-clockwise).
    pub fn rest_area(&self, t: usize) -> f64 {
        let [a, b, c] = self.triangles()[t].map(|i| self.rest[i as usize]);
        0.5 * (b - a).perp_dot(c - a)
    }

    /// Rest length of every edge, in edge order, m.
    pub fn edge_rest_lengths(&self) -> Vec<f64> {
        self.topology
            .edges()
            .iter()
            .map(|e| self.rest[e.vertices[0] as usize].distance(self.rest[e.vertices[1] as usize]))
            .collect()
    }

    /// Area of influence of every vertex: one third of the rest area of each incident triangle
    /// (Oliveira 2013 §4.3.2.1, Fig. 4.2). The areas sum to the whole rest area.
    pub fn vertex_areas(&self) -> Vec<f64> {
        let mut areas = vec![0.0; self.n_vertices()];
        for (t, tri) in self.triangles().iter().enumerate() {
            let third = self.rest_area(t) / 3.0;
            for &v in tri {
                areas[v as usize] += third;
            }
        }
        areas
    }

    /// The mesh laid out in 3-D: x = origin + X.x·e_x + X.y·e_y.
    pub fn place(&self, origin: DVec3, e_x: DVec3, e_y: DVec3) -> Vec<DVec3> {
        self.rest.iter().map(|p| origin + e_x * p.x + e_y * p.y).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_match_the_spec_counts() {
        // Spec §7.5: 5 × 5 → V 25, E 56, F 32; 17 × 17 → V 289, E 800, F 512.
        for pattern in [DiagonalPattern::Uniform, DiagonalPattern::Flipped, DiagonalPattern::Alternating] {
            for (n, v, e, f) in [(5, 25, 56, 32), (17, 289, 800, 512)] {
                let m = MaterialMesh::grid(n, 1.0, pattern).unwrap();
                assert_eq!((m.n_vertices(), m.n_edges(), m.n_faces()), (v, e, f), "{n} {pattern:?}");
                m.topology().check_invariants().unwrap();
                assert_eq!(m.topology().n_boundary_edges(), 4 * (n - 1));
            }
        }
    }

    #[test]
    fn vertex_areas_match_the_spec_and_sum_to_the_sheet() {
        let m = MaterialMesh::grid(5, 1.0, DiagonalPattern::Uniform).unwrap();
        let a = m.vertex_areas();
        assert!((a.iter().sum::<f64>() - 1.0).abs() < 1e-14);
        // Interior 0.0625, border 0.03125, corners with one and two triangles (spec §7.5).
        assert!((a[2 * 5 + 2] - 0.0625).abs() < 1e-15);
        assert!((a[2] - 0.03125).abs() < 1e-15);
        let mut corners = [a[0], a[4], a[20], a[24]];
        corners.sort_by(f64::total_cmp);
        assert!((corners[0] - 0.0625 / 6.0).abs() < 1e-15 && (corners[1] - 0.0625 / 6.0).abs() < 1e-15);
        assert!((corners[3] - 0.0625 / 3.0).abs() < 1e-15);
        let lengths = m.edge_rest_lengths();
        let max = lengths.iter().copied().fold(0.0, f64::max);
        assert!((max - 0.25 * 2f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn refuses_clockwise_and_bad_grids() {
        let tri = vec![DVec2::ZERO, DVec2::X, DVec2::Y];
        assert!(MaterialMesh::new(tri.clone(), vec![[0, 1, 2]]).is_ok());
        assert!(matches!(
            MaterialMesh::new(tri.clone(), vec![[0, 2, 1]]),
            Err(MaterialMeshError::BadRestArea { triangle: 0, .. })
        ));
        assert!(matches!(
            MaterialMesh::new(tri, vec![[0, 1, 7]]),
            Err(MaterialMeshError::Topology(TopologyError::IndexOutOfRange { index: 7, .. }))
        ));
        assert!(MaterialMesh::grid(1, 1.0, DiagonalPattern::Uniform).is_err());
        assert!(MaterialMesh::grid(3, f64::NAN, DiagonalPattern::Uniform).is_err());
    }

    #[test]
    fn placed_grid_faces_up() {
        let m = MaterialMesh::grid(3, 2.0, DiagonalPattern::Alternating).unwrap();
        let x = m.place(DVec3::new(-1.0, -1.0, 0.5), DVec3::X, DVec3::Y);
        for &[a, b, c] in m.triangles() {
            let n = (x[b as usize] - x[a as usize]).cross(x[c as usize] - x[a as usize]);
            assert!(n.z > 0.0 && n.x == 0.0 && n.y == 0.0);
        }
        assert_eq!(x[8], DVec3::new(1.0, 1.0, 0.5));
    }
}
