//! Particle–spring cloth, three models on one set of integrators (`anima_ode`):
//!
//! - [`flex3d`]: FLEX3D (Nedel 1993), rectangular grids of particles joined by Hooke springs to their
//!   eight neighbours, angular springs against bending, gravity, a uniform external force, friction as
//!   the only dissipation, pinned and translated points, and swept particle–triangle collisions against
//!   static objects and every surface;
//! - [`spring_net`] and [`network_sim`]: damped spring networks with exact Jacobians (the standard
//!   benchmark sheet) and analytic colliders;
//! - [`oliveira`]: Oliveira 2013's triangle-mesh cloth on static solids, and its adaptive remeshing.
//!
//! Contact with static objects is answered after the step by each model's own response (the theses'
//! split), or inside the implicit step ([`contact_mode::ContactMode`], generalised-α only).
//!
//! Knows nothing about rigid bodies or files: colliders are `anima_geom` shapes and meshes handed in by
//! the caller. Everything is `f64` and stored as flat arrays over all particles of all surfaces.

pub mod contact_mode;
pub mod flex3d;
pub mod network_sim;
pub mod oliveira;
pub mod spring_net;
