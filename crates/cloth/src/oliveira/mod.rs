//! Triangle-mesh cloth after Oliveira 2013 (spec `adaptive-cloth.md`), on a fixed mesh: every parameter
//! derived from material properties (§4.3), tension-only edge springs with dampers, the
//! Bridson–Marino–Fedkiw bending element, gravity and air drag, integrated by RK4 at the dynamic step
//! Δt = β·π·√(m_min/k^e_max); contact with static objects answered after each step by repulsion and
//! friction (§4.4.2.1).
//!
//! [`OliveiraCloth`] keeps its topology, which is what the thesis's coarse and fine reference runs (and
//! the static-mesh mode of spec A-43) do; [`AdaptiveCloth`] adds the adaptive remeshing of §4.5
//! ([`adaptive`], [`criteria`]) and the two remeshers it is compared with.
//!
//! Files by concern: [`material`] (Eqs. 4.1–4.4), [`springs`] (Eqs. 4.8–4.9 and their Jacobians),
//! [`bending`] (Eqs. 4.10–4.13), [`contact`] (Eqs. 4.16–4.18), [`forces`] (the ODE system), [`scene`]
//! (the scene schema and every reconstruction switch) and [`OliveiraCloth`] (the step loop of Fig. 4.1).

pub mod adaptive;
pub mod bending;
mod builder;
mod cloth;
pub mod contact;
pub mod criteria;
pub mod forces;
pub mod material;
pub mod scene;
pub mod springs;

pub use adaptive::{AdaptiveCloth, AdaptiveMethod, RemeshStats, SizingRemeshing, SubdivisionRemeshing};
pub use builder::ClothBuilder;
pub use cloth::{BuildError, MAX_SPLITS, OliveiraCloth, SPLIT_MOTION, StepReport, place_mesh};
pub use contact::Collider;
pub use criteria::{CurvatureLimit, OliveiraRemeshing, ShortEdgeRule};
pub use material::Material;
pub use scene::*;
