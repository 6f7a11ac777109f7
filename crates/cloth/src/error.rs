//! The one error of every cloth model's step: FLEX3D's world, the spring and membrane sheets, the
//! Oliveira cloth and its adaptive form stop for the same three reasons, and say where with the same
//! fields, so that a caller (a run loop, a game loop, the Python package) matches one type.

use anima_ode::OdeError;

use crate::bounds::OutOfBounds;

/// Why a cloth step could not be completed. The step count and time are those of the step that
/// failed (the state it would have produced, for [`StepError::NonFinite`]; the state it started from
/// stays in place for [`StepError::Solver`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    /// A position or velocity went non-finite.
    #[error(transparent)]
    NonFinite(#[from] NonFinite),
    /// The state left its physical bounds ([`crate::bounds`]) while still finite.
    #[error(transparent)]
    Diverged(#[from] OutOfBounds),
    /// The integrator refused the step (an implicit step's linear system or Newton iteration).
    #[error("step {step} (t = {time} s): {source}")]
    Solver { step: u64, time: f64, source: OdeError },
}

impl StepError {
    /// Whether the run went non-finite: in its state, or in the linear system of an implicit step
    /// (which refuses the step and leaves the state as it was).
    pub fn is_non_finite(&self) -> bool {
        matches!(self, StepError::NonFinite(_) | StepError::Solver { source: OdeError::NonFiniteSystem, .. })
    }
}

/// A value went non-finite: the first particle (in the model's order) with a non-finite position or
/// velocity.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("non-finite state at step {step} (t = {time} s): {}", describe(*.particle, .place.as_ref()))]
pub struct NonFinite {
    pub step: u64,
    pub time: f64,
    pub particle: usize,
    /// Where the particle lies on a FLEX3D surface; `None` for the models without named grids.
    pub place: Option<GridPlace>,
}

/// A particle's surface and grid position (FLEX3D's surfaces are named grids of rows and columns).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct GridPlace {
    pub surface: String,
    pub row: usize,
    pub col: usize,
}

fn describe(particle: usize, place: Option<&GridPlace>) -> String {
    match place {
        Some(p) => format!("surface `{}`, particle ({}, {})", p.surface, p.row, p.col),
        None => format!("particle {particle}"),
    }
}
