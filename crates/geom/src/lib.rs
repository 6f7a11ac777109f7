//! Geometry for anima: rectangular particle grids (FLEX3D, Nedel 1993 §3.1 and §5.5), indexed triangle
//! meshes, primitive shapes, the `.OBT` object format (Annex A-1) and the Badouel segment–triangle test
//! (Graphics Gems, 1990) that FLEX3D used for collision detection.
//!
//! Everything is `f64` (`glam::DVec3`): the thesis's Table 4.1 is only reproduced exactly in double
//! precision, and the cloth and integrator crates share these types.
//!
//! This crate knows no physics and does no file I/O of its own: readers take `impl Read`, writers
//! `impl Write`.
//!
//! ```
//! use anima_geom::{DVec3, PreparedTriangle, TriangleMesh, box_mesh, obj, read_obj, segment_triangle};
//!
//! // A particle moving from above through a triangle: FLEX3D's swept test finds where it crossed.
//! let tri = PreparedTriangle::new([DVec3::ZERO, DVec3::X, DVec3::Y]);
//! let hit = segment_triangle(DVec3::new(0.2, 0.2, 1.0), DVec3::new(0.0, 0.0, -2.0), &tri).unwrap();
//! assert!((hit.s - 0.5).abs() < 1e-12);
//!
//! // A closed mesh knows its inside, and OBJ frames read back exactly.
//! let cube: TriangleMesh = box_mesh(DVec3::ZERO, DVec3::ONE);
//! assert!(cube.contains_point(DVec3::splat(0.5)) && !cube.contains_point(DVec3::splat(1.5)));
//! let mut text = Vec::new();
//! obj::write_obj(&mut text, "cube", cube.vertices(), cube.triangles()).unwrap();
//! assert_eq!(read_obj(&text[..]).unwrap().vertices(), cube.vertices());
//! ```

mod grid;
mod grid_mesh;
pub mod halfedge;
mod intersect;
mod mesh;
pub mod obj;
mod obj_read;
pub mod obt;
pub mod query;
pub mod remesh;
pub mod self_contact;
mod shapes;

pub use glam::{DVec2, DVec3};
pub use grid::{GridFrame, RowDirection, SurfaceGrid, grid_triangles};
pub use grid_mesh::{DiagonalPattern, MaterialMesh, MaterialMeshError};
pub use halfedge::{HalfEdges, TopologyError};
pub use intersect::{Aabb, PreparedTriangle, SegmentHit, segment_triangle};
pub use mesh::{MeshError, TriangleMesh};
pub use obj_read::{MAX_FACE_CORNERS, ObjError, read_obj, read_obj_positions};
pub use query::{Cylinder, HalfSpace, MeshSolid, Proximity, Solid, SolidError, Sphere, SurfaceHit};
/// Self-contact of a cloth with itself: the crossing checker tests and run summaries use to judge any
/// response (a count of 0 is "never passed through itself"), and the detection a response is built on
/// (swept broad phase, proximity, continuous time of impact). Re-exported at the root because the cloth
/// crate and the run summaries need nothing else from the module.
pub use self_contact::{
    CountAbandoned, EdgeEdgeImpact, EdgeEdgePair, EdgeTriangleCrossing, SelfContactBroadPhase,
    VertexTriangleImpact, VertexTrianglePair, count_self_intersections, count_self_intersections_within,
    edge_edge_impact, self_intersections, vertex_triangle_impact,
};
pub use shapes::box_mesh;
