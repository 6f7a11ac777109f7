//! Primitive shapes as triangle meshes.

use glam::DVec3;

use crate::TriangleMesh;

/// An axis-aligned box from `min` to `max` as 12 triangles with outward-facing (counter-clockwise seen
/// from outside) winding. Vertex order: bottom face (y = min.y) then top face, each counter-clockwise
/// seen from above, as in the FLEX3D table `mesa.obt`.
pub fn box_mesh(min: DVec3, max: DVec3) -> TriangleMesh {
    let v = vec![
        DVec3::new(min.x, min.y, min.z),
        DVec3::new(max.x, min.y, min.z),
        DVec3::new(max.x, min.y, max.z),
        DVec3::new(min.x, min.y, max.z),
        DVec3::new(min.x, max.y, min.z),
        DVec3::new(max.x, max.y, min.z),
        DVec3::new(max.x, max.y, max.z),
        DVec3::new(min.x, max.y, max.z),
    ];
    let t = vec![
        [4, 7, 6],
        [4, 6, 5], // top
        [0, 1, 2],
        [0, 2, 3], // bottom
        [3, 2, 6],
        [3, 6, 7], // +z
        [0, 4, 5],
        [0, 5, 1], // -z
        [1, 5, 6],
        [1, 6, 2], // +x
        [0, 3, 7],
        [0, 7, 4], // -x
    ];
    TriangleMesh::new(v, t).expect("box indices are in range")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_contains_its_centre_and_not_outside_points() {
        let b = box_mesh(DVec3::new(-10.5, 0.0, -10.5), DVec3::new(10.5, 10.0, 10.5));
        assert!(b.contains_point(DVec3::new(0.0, 5.0, 0.0)));
        assert!(b.contains_point(DVec3::new(10.0, 9.9, -10.0)));
        assert!(!b.contains_point(DVec3::new(0.0, 10.5, 0.0)));
        assert!(!b.contains_point(DVec3::new(11.0, 5.0, 0.0)));
        assert!(!b.contains_point(DVec3::new(0.0, -0.1, 0.0)));
    }
}
