//! What a cloth user reaches for first, with the integrators and geometry the models take, in one
//! import: `use anima_cloth::prelude::*;`.
//!
//! The models ([`OliveiraCloth`] and its builder, [`NetworkSim`] on a [`SheetSpec`] with its
//! [`Threads`], [`MembraneSim`], [`Flex3dWorld`], [`AdaptiveCloth`]), the one step error, where contact
//! and self-contact are answered, and from the layers below the integrators and solvers (`anima_ode`)
//! and the vectors, meshes and mesh reader (`anima_geom`). The obstacle types stay in their models' modules
//! (`oliveira::Collider`, `network_sim::Collider`): each model takes its own.

pub use anima_geom::{DVec3, TriangleMesh, read_obj};
pub use anima_ode::{Integrator, LinearSolver, State, Stepper};

pub use crate::StepError;
pub use crate::contact_mode::ContactMode;
pub use crate::flex3d::Flex3dWorld;
pub use crate::membrane::{MembraneSheetSpec, MembraneSim};
pub use crate::network_sim::NetworkSim;
pub use crate::oliveira::{AdaptiveCloth, ClothBuilder, Material, OliveiraCloth, UpAxis};
pub use crate::self_collision::SelfCollisionMode;
pub use crate::spring_net::{SheetSpec, Threads};
