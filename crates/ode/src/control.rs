//! Driving a [`Stepper`] over an interval with a [`StepControl`].

use crate::stepper::{OdeError, State, Stepper};
use crate::{Coord, Integrator, OdeSystem};

/// How the step size is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepControl {
    /// A constant step; the number of steps is round((t_end − t₀)/dt), counted as an integer.
    Constant { dt: f64 },
    /// Accept a step when its error estimate is at most `tolerance` (position units), else retry it
    /// smaller. Dormand–Prince uses h·min(5, max(0.2, 0.9 (tol/err)^{1/5})); the thesis's adaptive Euler
    /// uses h = √(2·tol/|f′|) (Nedel 1993 §4.2.1), growing at most ×2 per step. Methods without an error
    /// estimate run at `dt_initial`.
    Adaptive { tolerance: f64, dt_initial: f64, dt_min: f64, dt_max: f64 },
}

/// What an integration did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct IntegrationStats {
    pub steps: usize,
    pub rejected: usize,
    pub evaluations: usize,
    pub solver_iterations: usize,
    pub smallest_dt: f64,
    pub largest_dt: f64,
}

/// Why an integration stopped early.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IntegrationError {
    #[error("non-finite value at step {step} (t = {time} s), coordinate {coordinate}")]
    NonFinite { step: usize, time: f64, coordinate: usize },
    #[error(transparent)]
    Ode(#[from] OdeError),
    #[error(
        "the step controller reached its smallest step {dt} s at t = {time} s with the error still above tolerance"
    )]
    StepTooSmall { time: f64, dt: f64 },
}

/// Integrates `state` from `t0` to `t_end`. `scratch` is the second buffer of the double-buffered state
/// (same size). `observe` sees every accepted state with its time. Stops with the step and coordinate
/// where a value first went non-finite.
#[expect(clippy::too_many_arguments, reason = "the system, its stepper and two buffers are all the caller's")]
pub fn integrate<S: OdeSystem + ?Sized>(
    sys: &mut S,
    stepper: &mut Stepper<S::Coord>,
    control: StepControl,
    t0: f64,
    t_end: f64,
    state: &mut State<S::Coord>,
    scratch: &mut State<S::Coord>,
    mut observe: impl FnMut(f64, &State<S::Coord>),
) -> Result<IntegrationStats, IntegrationError> {
    let mut stats = IntegrationStats { smallest_dt: f64::INFINITY, ..Default::default() };
    let accept = |stats: &mut IntegrationStats, h: f64, t: f64, state: &State<S::Coord>| {
        stats.steps += 1;
        stats.smallest_dt = stats.smallest_dt.min(h);
        stats.largest_dt = stats.largest_dt.max(h);
        if let Some(coordinate) = state.first_non_finite() {
            return Err(IntegrationError::NonFinite { step: stats.steps, time: t, coordinate });
        }
        Ok(())
    };
    match control {
        StepControl::Constant { dt } => {
            let n = ((t_end - t0) / dt).round() as usize;
            for k in 0..n {
                let t = t0 + k as f64 * dt;
                let s = stepper.step(sys, t, dt, state, scratch)?;
                stats.evaluations += s.evaluations;
                stats.solver_iterations += s.solver_iterations;
                std::mem::swap(state, scratch);
                let t_next = t0 + (k + 1) as f64 * dt;
                accept(&mut stats, dt, t_next, state)?;
                observe(t_next, state);
            }
        }
        StepControl::Adaptive { tolerance, dt_initial, dt_min, dt_max } => {
            let mut t = t0;
            let mut h = dt_initial.clamp(dt_min, dt_max);
            while t_end - t > 1e-12 * (1.0 + t_end.abs()) {
                let h_try = h.min(t_end - t);
                let s = stepper.step(sys, t, h_try, state, scratch)?;
                stats.evaluations += s.evaluations;
                stats.solver_iterations += s.solver_iterations;
                let Some(err) = s.error else {
                    std::mem::swap(state, scratch);
                    t += h_try;
                    accept(&mut stats, h_try, t, state)?;
                    observe(t, state);
                    continue;
                };
                let proposed = next_step(stepper.integrator(), h_try, err, tolerance);
                if err > tolerance && h_try <= dt_min {
                    // Accepting here would march on at the smallest step with an error the user did
                    // not allow (typically after a blow-up); stop and say so instead.
                    return Err(IntegrationError::StepTooSmall { time: t, dt: h_try });
                }
                if err <= tolerance {
                    std::mem::swap(state, scratch);
                    t += h_try;
                    accept(&mut stats, h_try, t, state)?;
                    observe(t, state);
                } else {
                    stats.rejected += 1;
                }
                h = proposed.clamp(dt_min, dt_max);
            }
        }
    }
    if stats.steps == 0 {
        stats.smallest_dt = 0.0;
    }
    Ok(stats)
}

/// The step a controller proposes after a step of size `h` with error estimate `err`.
fn next_step(integrator: Integrator, h: f64, err: f64, tol: f64) -> f64 {
    if err <= 0.0 || !err.is_finite() {
        return if err.is_finite() { 2.0 * h } else { 0.2 * h };
    }
    match integrator {
        // Thesis rule: err = h²/2·|f′|, so h = √(2·tol/|f′|) = h·√(tol/err); growth capped at ×2.
        Integrator::AdaptiveEuler => (h * (tol / err).sqrt()).min(2.0 * h),
        _ => {
            let order = integrator.order().min(4) as f64 + 1.0;
            h * (0.9 * (tol / err).powf(1.0 / order)).clamp(0.2, 5.0)
        }
    }
}

impl<C: Coord> Stepper<C> {
    /// Sets how implicit Euler solves its linear systems.
    pub fn set_linear_solver(&mut self, solver: crate::LinearSolver) {
        self.set_solver(solver);
    }
}
