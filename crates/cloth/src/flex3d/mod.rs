//! The FLEX3D surface model (Nedel 1993, spec `flex3d.md`).

mod broadphase;
mod desc;
mod forces;
pub mod mass_spring;
mod solve_contact;
mod world;

pub use desc::*;
pub use world::{BuildError, CollisionCounts, Diagnostics, Flex3dWorld, SurfaceInfo};
