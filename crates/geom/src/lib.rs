//! Geometry for anima: rectangular particle grids (FLEX3D, Nedel 1993 §3.1 and §5.5), indexed triangle
//! meshes, primitive shapes, the `.OBT` object format (Annex A-1) and the Badouel segment–triangle test
//! (Graphics Gems, 1990) that FLEX3D used for collision detection.
//!
//! Everything is `f64` (`glam::DVec3`): the thesis's Table 4.1 is only reproduced exactly in double
//! precision, and the cloth and integrator crates share these types.
//!
//! This crate knows no physics and does no file I/O of its own: readers take `impl Read`, writers
//! `impl Write`.

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
mod shapes;

pub use glam::{DVec2, DVec3};
pub use grid::{GridFrame, RowDirection, SurfaceGrid, grid_triangles};
pub use grid_mesh::{DiagonalPattern, MaterialMesh, MaterialMeshError};
pub use halfedge::{HalfEdges, TopologyError};
pub use intersect::{Aabb, PreparedTriangle, SegmentHit, segment_triangle};
pub use mesh::{MeshError, TriangleMesh};
pub use obj_read::{ObjError, read_obj};
pub use query::{Cylinder, HalfSpace, MeshSolid, Proximity, Solid, SolidError, Sphere, SurfaceHit};
pub use shapes::box_mesh;
