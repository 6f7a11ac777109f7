//! Indexed triangle meshes with validated indices.

use glam::DVec3;

use crate::intersect::Aabb;

/// Why a triangle mesh was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("triangle {triangle} refers to vertex {index}, but the mesh has {n_vertices} vertices")]
    IndexOutOfRange { triangle: usize, index: u32, n_vertices: usize },
    #[error("vertex {0} is not finite")]
    NonFiniteVertex(usize),
}

/// An indexed triangle mesh: vertex positions and triangles as index triples (0-based).
///
/// The constructor checks every index once, so code that walks the triangles never needs to.
#[derive(Debug, Clone, PartialEq)]
pub struct TriangleMesh {
    vertices: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
}

impl TriangleMesh {
    /// Builds a mesh after checking that every index names a vertex and every vertex is finite.
    pub fn new(vertices: Vec<DVec3>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        if let Some(i) = vertices.iter().position(|v| !v.is_finite()) {
            return Err(MeshError::NonFiniteVertex(i));
        }
        for (t, tri) in triangles.iter().enumerate() {
            for &index in tri {
                if index as usize >= vertices.len() {
                    return Err(MeshError::IndexOutOfRange {
                        triangle: t,
                        index,
                        n_vertices: vertices.len(),
                    });
                }
            }
        }
        Ok(Self { vertices, triangles })
    }

    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices
    }

    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    pub fn n_vertices(&self) -> usize {
        self.vertices.len()
    }

    pub fn n_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `t`.
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [self.vertices[a as usize], self.vertices[b as usize], self.vertices[c as usize]]
    }

    /// Bounding box of all vertices (empty box for an empty mesh).
    pub fn aabb(&self) -> Aabb {
        Aabb::from_points(self.vertices.iter().copied())
    }

    /// Whether `p` lies inside the closed surface the mesh bounds, by the parity of crossings of a ray.
    ///
    /// The ray direction is slightly skewed so that it does not run along the edges and faces of
    /// axis-aligned meshes (the FLEX3D table is a box); a point on the surface may go either way.
    pub fn contains_point(&self, p: DVec3) -> bool {
        let dir = DVec3::new(0.573_576_436, 0.001_234_567, 0.819_152_044).normalize();
        let far = self.aabb().diagonal_length() * 2.0 + 1.0;
        let mut crossings = 0usize;
        for t in 0..self.triangles.len() {
            let tri = crate::PreparedTriangle::new(self.corners(t));
            if let Some(hit) = crate::segment_triangle(p, dir * far, &tri)
                && hit.s > 0.0
            {
                crossings += 1;
            }
        }
        crossings % 2 == 1
    }
}
