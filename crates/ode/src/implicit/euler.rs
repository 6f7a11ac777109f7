//! Backward Euler linearised once per step (Baraff & Witkin, "Large steps in cloth simulation", 1998):
//!
//! (M − h D − h² K) Δv = h (f₀ + h K v₀),   v₁ = v₀ + Δv,   x₁ = x₀ + h v₁,
//!
//! with K = ∂f/∂x and D = ∂f/∂v at the start of the step.
//!
//! BDF2 (as Choi & Ko 2002 used it for cloth) is the same solve with other coefficients. With
//! β = 2h/3, x̂ = (4 x₀ − x₋₁)/3 and v̂ = (4 v₀ − v₋₁)/3 it asks x₁ = x̂ + β v₁ and M v₁ = M v̂ + β f(x₁, v₁);
//! linearising f about (x₀, v₀) gives
//!
//! (M − β D − β² K) Δv = M (v̂ − v₀) + β (f₀ + K (x̂ − x₀ + β v₀)),
//!
//! which for x̂ = x₀, v̂ = v₀, β = h is the backward Euler system above. One backward Euler step starts
//! it, and restarts it whenever the history is invalid (a collision response, a change of step). Further
//! Newton iterations (`Stepper::set_newton_iterations`) linearise about the current iterate.

#![allow(
    clippy::needless_range_loop,
    reason = "the loops walk several per-coordinate arrays in step; the index form mirrors the formulas"
)]

use crate::Coord;
use crate::stepper::{OdeError, State, StepStats};

use super::Linearized;
use super::system::Filter;
use super::workspace::ImplicitWorkspace;

impl<C: Coord> ImplicitWorkspace<C> {
    pub fn step_euler(
        &mut self,
        lin: &mut dyn Linearized<C>,
        t: f64,
        h: f64,
        now: &State<C>,
        next: &mut State<C>,
    ) -> Result<StepStats, OdeError> {
        let n = now.len();
        let n_pairs = lin.pattern().len();
        self.jac.resize(n, n_pairs);
        self.a.resize(n, lin.pattern());
        #[cfg(feature = "sparse-cholesky")]
        if matches!(self.solver, super::LinearSolver::RigidAggregation { .. }) {
            self.coarse_stale = true;
            self.positions.clear();
            self.positions.extend_from_slice(&now.x);
        }
        // BDF2 when the last step had the same size; backward Euler otherwise.
        let bdf2 = self.bdf2.is_some() && self.prev_h == h;
        let beta = if bdf2 { 2.0 * h / 3.0 } else { h };
        // x̂ and v̂ (held in `next` while iterating), and w = x̂ − x₀ + β v₀.
        for i in 0..n {
            (next.x[i], next.v[i]) = match &self.bdf2 {
                Some(prev) if bdf2 => (
                    now.x[i] + (now.x[i] - prev.x[i]) * (1.0 / 3.0),
                    now.v[i] + (now.v[i] - prev.v[i]) * (1.0 / 3.0),
                ),
                _ => (now.x[i], now.v[i]),
            };
            self.w[i] = next.x[i] - now.x[i] + now.v[i] * beta;
        }
        // Newton's first iteration, linearised about the start of the step (Baraff–Witkin):
        // b = M (v̂ − v₀) + β (f + K w), solved for Δv = v₁ − v₀.
        let started = self.profile.is_some().then(std::time::Instant::now);
        self.jac.clear();
        lin.force_and_jacobians(t, &now.x, &now.v, &mut self.f, &mut self.jac);
        let (masses, prescribed) = (lin.masses(), lin.prescribed());
        self.a.assemble(&self.jac, masses, beta, beta * beta);
        for i in 0..n {
            self.b[i] = C::block_mul(self.jac.k_diag[i], self.w[i]);
        }
        for (e, &(i, j)) in lin.pattern().iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let k = self.jac.k_off[e];
            let (bi, bj) = (C::block_mul(k, self.w[j]), C::block_mul_transpose(k, self.w[i]));
            self.b[i] += bi;
            self.b[j] += bj;
        }
        for i in 0..n {
            self.b[i] = if prescribed[i] {
                C::default()
            } else {
                (next.v[i] - now.v[i]) * masses[i] + (self.f[i] + self.b[i]) * beta
            };
        }
        if let (Some(p), Some(s)) = (&mut self.profile, started) {
            p.assembly_s += s.elapsed().as_secs_f64();
            p.newton_iterations += 1;
        }
        let mut iterations =
            self.solve(lin.pattern(), Filter::Prescribed(prescribed), masses, prescribed, true)?;
        // v̂ goes to `v_hat` (kept in self.w, no longer needed as w), the iterate v₁ to next.v.
        for i in 0..n {
            self.w[i] = next.v[i];
            next.v[i] = now.v[i] + self.dv[i];
        }
        let place = |x_hat: C, x0: C, v1: C, fixed: bool| if fixed { x0 + v1 * h } else { x_hat + v1 * beta };
        // Further Newton iterations on G(v) = M (v − v̂) − β f(x̂ + β v, v) = 0, each linearised about the
        // current iterate: (M − β D − β² K) δ = −G(v).
        for _ in 1..self.newton_iterations {
            let prescribed = lin.prescribed();
            for i in 0..n {
                self.xk[i] = place(next.x[i], now.x[i], next.v[i], prescribed[i]);
            }
            let started = self.profile.is_some().then(std::time::Instant::now);
            self.jac.clear();
            lin.force_and_jacobians(t + h, &self.xk, &next.v, &mut self.f, &mut self.jac);
            let (masses, prescribed) = (lin.masses(), lin.prescribed());
            self.a.assemble(&self.jac, masses, beta, beta * beta);
            for i in 0..n {
                self.b[i] = if prescribed[i] {
                    C::default()
                } else {
                    self.f[i] * beta - (next.v[i] - self.w[i]) * masses[i]
                };
                self.dv[i] = C::default();
            }
            if let (Some(p), Some(s)) = (&mut self.profile, started) {
                p.assembly_s += s.elapsed().as_secs_f64();
                p.newton_iterations += 1;
            }
            iterations +=
                self.solve(lin.pattern(), Filter::Prescribed(prescribed), masses, prescribed, true)?;
            for i in 0..n {
                next.v[i] += self.dv[i];
            }
        }
        let prescribed = lin.prescribed();
        for i in 0..n {
            next.x[i] = place(next.x[i], now.x[i], next.v[i], prescribed[i]);
        }
        if let Some(prev) = &mut self.bdf2 {
            prev.x.copy_from_slice(&now.x);
            prev.v.copy_from_slice(&now.v);
        }
        self.prev_h = if self.bdf2.is_some() { h } else { 0.0 };
        if let Some(p) = &mut self.profile {
            p.steps += 1;
        }
        Ok(StepStats {
            evaluations: self.newton_iterations,
            solver_iterations: iterations,
            ..Default::default()
        })
    }
}
