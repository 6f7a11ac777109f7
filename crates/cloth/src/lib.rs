//! Particle–spring cloth. This model is FLEX3D (Nedel 1993): rectangular grids of particles
//! joined by Hooke springs to their eight neighbours, angular springs against bending, gravity, a uniform
//! external force, friction as the only dissipation, pinned and translated points, and swept
//! particle–triangle collisions against static objects and every surface.
//!
//! Knows nothing about rigid bodies or files: colliders are `anima_geom` meshes handed in by the caller.
//! Everything is `f64` and stored as flat arrays over all particles of all surfaces.

pub mod contact_mode;
pub mod flex3d;
pub mod network_sim;
pub mod oliveira;
pub mod spring_net;
