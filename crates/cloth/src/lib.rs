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
//! split), or inside the implicit step ([`contact_mode::ContactMode`], generalised-α only). A sheet can
//! also be kept from passing through itself ([`self_collision`]: repulsion, impact impulses and rigid
//! impact zones after the step, a modern option beside the theses' responses).
//!
//! [`prelude`] holds the models and what they take from the layers below, for one import.
//!
//! Knows nothing about rigid bodies or files: colliders are `anima_geom` shapes and meshes handed in by
//! the caller. Everything is `f64` and stored as flat arrays over all particles of all surfaces.
//!
//! # Use
//!
//! ```
//! use anima_cloth::contact_mode::ContactMode;
//! use anima_cloth::network_sim::{Collider, NetworkSim};
//! use anima_cloth::spring_net::SheetSpec;
//! use anima_ode::Integrator;
//! use glam::DVec3;
//!
//! // A 16 × 16 standard sheet, free (no pins), dropped on a sphere at 1/60 s by generalised-α with the
//! // contacts inside its solve.
//! let spec = SheetSpec { pinned: vec![], ..SheetSpec::standard(16) };
//! let network = spec.build().unwrap();
//! let mut sim = NetworkSim::new(network, spec.positions(), Integrator::GeneralizedAlpha, 1.0 / 60.0).unwrap();
//! let (centre, radius) = (DVec3::new(0.5, 0.5, 1.0), 0.3);
//! sim.colliders.push(Collider::Sphere { centre, radius });
//! sim.friction = 0.3;
//! sim.contact = ContactMode::InSolve;
//! sim.run(60).unwrap();
//!
//! // After a second it drapes the sphere: nothing inside it, and its middle rests on the top.
//! assert!(sim.state.x.iter().all(|p| p.distance(centre) > radius - 1e-3));
//! let middle = sim.state.x[8 * 16 + 8];
//! assert!((middle.z - (centre.z + radius)).abs() < 0.02);
//! ```

mod assembly;
pub mod bounds;
pub mod contact_mode;
pub mod error;
pub mod flex3d;
pub mod membrane;
pub mod network_sim;
pub mod oliveira;
pub mod prelude;
pub mod self_collision;
mod sheet_stencil;
pub mod spring_net;

pub use error::StepError;

/// Whether a model that steps at its scene's Δt can take `integrator`: the adaptive methods (the
/// thesis's adaptive Euler, Dormand–Prince) choose their own steps, which only the sheets' run loop
/// gives them. A FLEX3D world or an Oliveira cloth would take them at the fixed step (adaptive Euler as
/// forward Euler), silently; both refuse them with this reason.
pub fn check_fixed_step_integrator(integrator: anima_ode::Integrator) -> Result<(), String> {
    if integrator.is_adaptive() {
        return Err(format!(
            "expected an integrator for a fixed step, found {integrator}, which chooses its own steps: \
             FLEX3D and Oliveira scenes step at their Δt (sheet scenes run it adaptively)"
        ));
    }
    Ok(())
}
