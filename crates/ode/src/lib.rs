//! Ordinary differential equations of motion and the integrators that step them.
//!
//! A system is second order, x'' = a(t, x, v), the shape of every mechanical model in anima; as a
//! first-order system its state is y = (x, v) with y' = (v, a). Every integrator here steps the same
//! [`OdeSystem`], so a scene can switch methods without touching its model. This crate knows nothing
//! about cloth: coordinates are any [`Coord`] (plain `f64` for the Table 4.1 spring, `DVec3` for
//! particles).
//!
//! - [`Stepper`] owns an [`Integrator`] and every scratch buffer it needs (so the step loop never
//!   allocates): explicit and symplectic Euler, midpoint (RK2), classical RK4, Dormand–Prince 5(4),
//!   Adams–Bashforth 4 and the Adams–Bashforth–Moulton 4 predictor–corrector (both started by RK4), the
//!   thesis's adaptive Euler, implicit (backward) Euler solved the Baraff–Witkin way (one Newton step,
//!   exact Jacobians from a [`Linearized`] system) and BDF2, and generalised-α (Chung & Hulbert 1993:
//!   second order, its damping of unresolved modes set by ρ∞, Newton's method with a safeguarding line
//!   search). Their linear systems are solved by preconditioned conjugate gradients (block Jacobi; a
//!   two-level preconditioner that keeps one factorisation of a scalar mass-plus-spring matrix across
//!   steps; or one whose coarse level is the rigid motions of small patches, projected with the
//!   current matrix, generalised-α's default) or by faer's sparse Cholesky with its symbolic
//!   factorisation reused ([`LinearSolver`]).
//! - [`contact`]: contacts with static surfaces constrained inside generalised-α's solve (normal
//!   velocity, Coulomb friction sticking or sliding, release when pulling), through a [`contact::ContactModel`]
//!   the caller implements with its geometry ([`Stepper::step_with_contacts`]).
//! - [`integrate`] drives a stepper with a [`StepControl`] (constant step, an embedded-error controller,
//!   or the thesis's Euler rule) and stops with the step and coordinate where a value went non-finite.
//! - [`SingleSpring`]: the Table 4.1 spring (Nedel 1993 §4.4), the test problem with an exact solution.
//! - [`stability`] estimates the largest frequency of a system and the largest stable step of each
//!   explicit method, so a user is warned before a step is known to blow up.
//!
//! Steps are double-buffered, as FLEX3D kept its state at t and at t + Δt (Nedel 1993, Fig. 5.3): the
//! integrator reads `now` and writes `next`, and never updates a position while forces are still being
//! evaluated.
//!
//! # Use
//!
//! ```
//! use anima_ode::{Integrator, OdeSystem, State, Stepper};
//!
//! /// x'' = −x: a unit spring with a unit mass, period 2π.
//! struct Spring;
//! impl OdeSystem for Spring {
//!     type Coord = f64;
//!     fn n_coords(&self) -> usize {
//!         1
//!     }
//!     fn acceleration(&mut self, _t: f64, x: &[f64], _v: &[f64], a: &mut [f64]) {
//!         a[0] = -x[0];
//!     }
//! }
//!
//! // One period with classical RK4 in 100 steps comes back to x = 1 to about 1e-7.
//! let (n, h) = (100, std::f64::consts::TAU / 100.0);
//! let mut stepper = Stepper::new(Integrator::Rk4, 1);
//! let (mut now, mut next) = (State::new(vec![1.0], vec![0.0]), State::zeros(1));
//! for k in 0..n {
//!     stepper.step(&mut Spring, k as f64 * h, h, &now, &mut next).unwrap();
//!     std::mem::swap(&mut now, &mut next);
//! }
//! assert!((now.x[0] - 1.0).abs() < 1e-6);
//! ```

mod control;
mod coord;
mod implicit;
mod integrator;
pub mod parallel;
mod spring;
pub mod stability;
mod stepper;

pub use control::{IntegrationError, IntegrationStats, StepControl, integrate};
pub use coord::Coord;
pub use implicit::alpha::{
    AlphaParameters, DEFAULT_NEWTON_CONTRACTION, DEFAULT_NEWTON_ITERATIONS, DEFAULT_REGIME_ITERATIONS,
    DEFAULT_RHO_INF,
};
pub use implicit::contact;
pub use implicit::workspace::SolveProfile;
pub use implicit::{Jacobians, LinearSolver, Linearized, SpringBlock, SystemOut};
pub use integrator::{Integrator, ParseIntegratorError};
pub use spring::SingleSpring;
pub use stepper::{OdeError, SavedHistory, State, StepStats, Stepper};

/// A second-order system x'' = a(t, x, v) over `n_coords` coordinates.
pub trait OdeSystem {
    type Coord: Coord;

    /// Number of position coordinates; the state holds as many velocities.
    fn n_coords(&self) -> usize;

    /// Writes the acceleration at (t, x, v) into `a` (all slices have length `n_coords`).
    fn acceleration(&mut self, t: f64, x: &[Self::Coord], v: &[Self::Coord], a: &mut [Self::Coord]);

    /// The system's force Jacobians, for implicit integration and stability bounds; `None` (the default)
    /// when it gives none, in which case implicit Euler refuses to step it.
    fn linearized(&mut self) -> Option<&mut dyn Linearized<Self::Coord>> {
        None
    }
}
