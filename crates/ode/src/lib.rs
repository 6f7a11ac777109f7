//! Ordinary differential equations of motion and the integrators that step them.
//!
//! A system is second order, x'' = a(t, x, v), the shape of every mechanical model in anima; as a
//! first-order system its state is y = (x, v) with y' = (v, a). Each integrator here steps the same
//! [`OdeSystem`], so a scene can switch methods without touching its model. This crate knows nothing
//! about cloth: coordinates are any [`Coord`] (plain `f64` for the Table 4.1 spring, `DVec3` for
//! particles).
//!
//! Steps are double-buffered, as FLEX3D kept its state at t and at t + Δt (Nedel 1993, Fig. 5.3): the
//! integrator reads (x, v) and writes (x_new, v_new), and never updates a position while forces are
//! still being evaluated.

mod coord;
mod integrator;

pub use coord::Coord;
pub use integrator::{Integrator, ParseIntegratorError, State, Stepper};

/// A second-order system x'' = a(t, x, v) over `n_coords` coordinates.
pub trait OdeSystem {
    type Coord: Coord;

    /// Number of position coordinates; the state holds as many velocities.
    fn n_coords(&self) -> usize;

    /// Writes the acceleration at (t, x, v) into `a` (all slices have length `n_coords`).
    fn acceleration(&mut self, t: f64, x: &[Self::Coord], v: &[Self::Coord], a: &mut [Self::Coord]);
}
