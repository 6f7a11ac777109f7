//! Generalised-α (Chung & Hulbert, "A time integration algorithm for structural dynamics with improved
//! numerical dissipation: the generalized-α method", J. Appl. Mech. 60, 1993) for M x'' = f(t, x, v):
//!
//! M [(1 − α_m) a₁ + α_m a₀] = f(t + (1 − α_f) h, (1 − α_f) x₁ + α_f x₀, (1 − α_f) v₁ + α_f v₀),
//! x₁ = x₀ + h v₀ + h² [(½ − β) a₀ + β a₁],   v₁ = v₀ + h [(1 − γ) a₀ + γ a₁],
//!
//! with the parameters chosen from the spectral radius at infinite step ρ∞ ∈ [0, 1]:
//!
//! α_m = (2ρ∞ − 1)/(ρ∞ + 1),  α_f = ρ∞/(ρ∞ + 1),  γ = ½ − α_m + α_f,  β = ¼ (1 − α_m + α_f)².
//!
//! It is second order for every ρ∞, unconditionally stable on linear problems, and damps the modes a
//! step cannot resolve (h ω → ∞) by the factor ρ∞ per step while damping the resolved ones only at
//! third order in h ω (the least low-frequency dissipation for a given high-frequency one). ρ∞ = 1 is
//! the implicit midpoint rule (Newmark's average acceleration: no numerical damping at all), ρ∞ = 0
//! damps the unresolved modes in one step.
//!
//! Why this method, and why ρ∞ = [`DEFAULT_RHO_INF`]. On the standard sheet (N = 64, 1 s at Δt = 1/60 s,
//! error of the centre of mass with the Newton iterations converged), ρ∞ = 0 errs 18 mm, 0.2 errs 8 mm,
//! 0.3 errs 3.7 mm, 0.4 errs 2.9 mm, and 0.6 and above go wrong (224 mm at 0.6: the implicit midpoint
//! rule's Newton iterations stop converging). Converged backward Euler errs 198 mm there and BDF2
//! 14 mm (N = 32). The stretch modes of the springs (h ω ≈ 100 at 1/60 s) are physically damped within a
//! millisecond by the springs' dampers, and a rule that keeps them ringing at nearly full amplitude
//! (|R| → 1) feeds their energy into the nonlinear springs. With contact the bound is tighter: a 16 × 16
//! sheet dropped at 20 m/s onto a box (the hard case of `implicit_hard_cases`), converged, keeps its
//! energy falling (43 J to 2 J in 2 s) for ρ∞ ≤ 0.2, while ρ∞ = 0.3 first climbs to 147 J and 0.4 to
//! 400–800 J: the impacts excite exactly the unresolved modes, and generalised-α, stable on linear
//! problems, is not on these nonlinear ones (Kuhl & Crisfield 1999 show the same for nonlinear
//! structures). 0.2 is the largest value that is robust there. The stepper's
//! [`crate::Stepper::set_spectral_radius`] changes ρ∞.
//!
//! The unknown is the end velocity w = v₁; with a₁ = (w − v₀)/(γh) − (1 − γ)/γ a₀ the force is evaluated
//! at x* = α_f x₀ + (1 − α_f) x₁(w), v* = α_f v₀ + (1 − α_f) w, and the equations become
//!
//! M (w − v₀ − ĉ a₀) = η f(t*, x*, v*),  η = γh/(1 − α_m),  ĉ = h [(1 − γ) − α_m γ/(1 − α_m)],
//!
//! solved by Newton's method with the matrix M − β_v D − β_x K, β_v = η (1 − α_f),
//! β_x = η (1 − α_f) β h/γ. The acceleration a is the method's own state between steps; it starts (and
//! restarts after anything changed the state from outside) as M⁻¹ f.

#![allow(
    clippy::needless_range_loop,
    reason = "the loops walk several per-coordinate arrays in step; the index form mirrors the formulas"
)]

use std::time::Instant;

use crate::Coord;
use crate::stepper::{OdeError, State, StepStats};

use super::Linearized;
use super::contact::{ContactModel, Friction, Regime, StepStart};
use super::system::Filter;
use super::workspace::ImplicitWorkspace;

/// ρ∞ when none is set: see the module documentation for the measurements behind it.
pub const DEFAULT_RHO_INF: f64 = 0.2;

/// Newton iterations per step when none is set (the planned ones; more can run while contacts change
/// regime, [`DEFAULT_REGIME_ITERATIONS`]). Measured on the standard sheet (N = 64, 1 s at 1/60 s) with
/// the default solver (rigid-aggregation CG to a relative residual of 0.1 per iteration; `cargo run
/// --release -p anima-lab --example large_steps -- probe`, with `NEWTON=k`, before the spring-form matrix): 2
/// iterations err 6.5 mm at the centre of mass (34 mm RMS per particle against RK4 at 10⁻⁵ s) in 8.5 ms
/// per step, 3 iterations 13 mm (28 mm RMS) in 11.4 ms. Three, because two are not enough on the very
/// stiff sheet of the hard cases (k = 10⁵ N/m, `implicit_hard_cases`): its largest strain reaches 11.6 % with two (7.8 % with
/// three; a looser relative residual of 0.2 with three let it swing up to 23 m/s). With exact solves
/// one iteration, linearised at the predicted state, errs 490 mm and two 12 mm (ρ∞ = 0.4). The centre
/// of mass of a folding sheet moves chaotically with small changes: the RMS error is the steadier
/// measure, and differences in the centre of mass below 10 mm are noise.
///
/// These are the most a step runs: after two, the rest are skipped once the updates have contracted
/// ([`DEFAULT_NEWTON_CONTRACTION`]); on the standard sheet a step then runs 2.1 on average.
///
/// Predicting the end velocity from earlier steps instead of w = v₀ (constant acceleration, the last
/// step's velocity change, linear or quadratic extrapolation of the positions) was measured worse
/// with every Newton count: the method's acceleration and velocity carry the unconverged residue of
/// the stiff springs, and extrapolating it starts Newton far from the solution (metres of error with
/// inexact solves). Stopping Newton on a residual ratio instead of a count did not pay either: the
/// ratio after two iterations is spread alike on the standard sheet and on the stiff one. The ratio of
/// successive updates separates them better but not cleanly (medians 0.17 and 0.46, tails
/// overlapping), so it ends iterations early within the count rather than replacing it; more
/// iterations for the stiff sheet when it has not contracted (4 at most) were measured to swing it
/// harder, not less (largest strain 99 % against 9 % with three).
pub const DEFAULT_NEWTON_ITERATIONS: usize = 3;

/// The method's parameters for a spectral radius ρ∞ (clamped to [0, 1]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlphaParameters {
    pub rho_inf: f64,
    pub alpha_m: f64,
    pub alpha_f: f64,
    pub gamma: f64,
    pub beta: f64,
}

impl AlphaParameters {
    pub fn new(rho_inf: f64) -> Self {
        let rho = rho_inf.clamp(0.0, 1.0);
        let alpha_m = (2.0 * rho - 1.0) / (rho + 1.0);
        let alpha_f = rho / (rho + 1.0);
        let gamma = 0.5 - alpha_m + alpha_f;
        let beta = 0.25 * (1.0 - alpha_m + alpha_f).powi(2);
        Self { rho_inf: rho, alpha_m, alpha_f, gamma, beta }
    }
}

/// Newton iterations before the contraction test may end them ([`DEFAULT_NEWTON_CONTRACTION`]).
const MIN_NEWTON_ITERATIONS: usize = 2;

/// The planned Newton iterations stop early, after at least two, once an update is at most this
/// fraction of the one before it in the mass norm (‖δ_k‖_M ≤ θ ‖δ_{k−1}‖_M: the
/// iterate is then near where Newton's method is going, and the next update would be smaller still).
/// Measured at 1/60 s with three planned iterations: on the standard sheet (N = 64) ‖δ₂‖/‖δ₁‖ has a
/// median of 0.17 and exceeds 0.3 in 5 of 60 steps; on the very stiff sheet of the hard cases
/// (k = 10⁵ N/m) its median is 0.46 and it exceeds 0.3 in 103 of 120 steps. That sheet needs its
/// third iteration (with two its largest strain reaches 33 % and a particle 10 m/s); the standard
/// one does not (6.5 mm at the centre of mass with two, 13 mm with three). Not while contacts are
/// constrained in the solve: their stick and slide regimes need the iterations (stopping early there
/// took Oliveira's Bunny drape at 1/60 s from 31 to 67 mm RMS off the thesis's run). 0 turns the test
/// off.
pub const DEFAULT_NEWTON_CONTRACTION: f64 = 0.3;

/// Newton iterations beyond the planned ones while contacts still change regime, when none is set
/// ([`crate::Stepper::set_regime_iterations`]).
///
/// Two. On the drapes of `cargo xtask bench --scale` (Oliveira's cloth on the Bunny and on a sphere at
/// 1/60 s; `cargo run --release -p anima-lab --example scale_probe`) the active sets never settle: from
/// the first Newton iteration to the fifth, 25–35 % of the contacts change regime at every iteration,
/// mostly sticking and sliding in turn (a sliding particle's velocity turns against its friction, it
/// sticks, its tangential reaction then exceeds the static limit, it slides), and a contact released
/// because it pulls is found beyond its plane again at the next iterate. So the two extra iterations
/// run in almost every step (4.9 Newton iterations a step instead of 3), and without them a step is a
/// quarter cheaper (118 against 85 ms on the 129² Bunny, alternated runs). None was measured as the
/// default and is not one, because the iterations are needed as Newton iterations, not for the
/// regimes as such: with none the 257² Bunny drape stretched a spring to 11 times its length, its
/// self-collision response then took seconds a step, and it had not reached 1.4 s of its 3 s after 8
/// minutes (with two it ends in 2 minutes, no spring past twice its length). The theses' 17 × 17 Bunny
/// drape at 1/60 s errs 31.6 mm against its converged model with two (`docs/reproduction/oliveira-implicit.md`,
/// whose runs take the defaults). Probe runs of that drape when the default was chosen erred 69.9 mm
/// with none, and 35.3 mm with five planned iterations and none extra. On the 65² drapes the errors
/// were alike (`scale_probe` with `REGIME=0` and the default: Bunny 15.2–17.6 mm with none, 12.6–17.2
/// mm with two, band 7.0 mm; sphere 22.5–23.0 against 19.3–19.6 mm, band 1.7 mm), and one extra
/// iteration erred more than either. What would make the cheaper step safe is a test of Newton's convergence that contacts do
/// not upset, which the contraction test ([`DEFAULT_NEWTON_CONTRACTION`]) is not.
///
/// Why no such test was found (65² drapes, 3 s, `scale_probe`). The Newton updates there do not
/// contract at all: over a step's five iterations ‖δ‖_M stays between 2 and 9·10⁻³ and the largest
/// velocity change between 1 and 9 cm/s (sphere, sampled steps), so a test on the update ends nothing
/// early. The regime changes are not one contact chattering: a contact that changes from sliding to
/// sticking moves its velocity by 10⁻⁴–10⁻³ m/s, but the estimated pull of one that starts to slide or
/// is released is mostly 0.1–10 m/s (its reaction over its mass, times η), and ignoring changes below 1 mm/s
/// or 1 cm/s left every step as it was. Capping each contact at one, two or three changes a step
/// (instead of four) left Newton at 4.84–4.96 a step, since other contacts change for the first time,
/// and raised the error (Bunny 30.6, 20.3, 18.1 mm against 17.2; sphere 33.4, 20.2, 18.3 against 19.5).
pub const DEFAULT_REGIME_ITERATIONS: usize = 2;

/// Detection rounds of the last look at the contacts.
const SETTLE_ROUNDS: usize = 3;

/// Line-search halvings per Newton iteration.
const MAX_HALVINGS: usize = 3;

/// A Newton step is halved only when it more than doubles the residual. Requiring a decrease (Armijo)
/// was measured to cost accuracy on the standard sheet (76 mm at the centre of mass with three Newton
/// iterations, against 7 mm): in the M⁻¹ norm the residual is dominated by the stiff springs, and a
/// good step in the soft directions often raises it a little. The search is a safeguard against the
/// overshoots of very stiff springs, not a globalisation.
const GROWTH_ALLOWED: f64 = 2.0;

/// The coefficients of one step of size h.
#[derive(Debug, Clone, Copy)]
struct Coefficients {
    params: AlphaParameters,
    h: f64,
    /// η = γh/(1 − α_m).
    eta: f64,
    /// ĉ = h [(1 − γ) − α_m γ/(1 − α_m)].
    c_hat: f64,
    /// β_v = η (1 − α_f), β_x = η (1 − α_f) β h/γ.
    beta_v: f64,
    beta_x: f64,
    /// x₁(w) = X₁ + c_end w: c_end = β h/γ.
    end: f64,
}

impl Coefficients {
    fn new(params: AlphaParameters, h: f64) -> Self {
        let AlphaParameters { alpha_m, alpha_f, gamma, beta, .. } = params;
        let eta = gamma * h / (1.0 - alpha_m);
        Self {
            params,
            h,
            eta,
            c_hat: h * ((1.0 - gamma) - alpha_m * gamma / (1.0 - alpha_m)),
            beta_v: eta * (1.0 - alpha_f),
            beta_x: eta * (1.0 - alpha_f) * beta * h / gamma,
            end: beta * h / gamma,
        }
    }
}

/// The method's state between steps.
#[derive(Debug, Clone)]
pub(crate) struct AlphaState<C> {
    /// The algorithmic acceleration a₀ of `now`.
    pub a: Vec<C>,
    /// Whether `a` describes the state the next step starts from.
    pub valid: bool,
    pub params: AlphaParameters,
}

impl<C: Coord> ImplicitWorkspace<C> {
    /// Generalised-α's workspace for `n` coordinates.
    pub fn new_alpha(n: usize) -> Self {
        let mut ws = Self::new(n, false);
        ws.alpha = Some(AlphaState {
            a: vec![C::default(); n],
            valid: false,
            params: AlphaParameters::new(DEFAULT_RHO_INF),
        });
        ws.newton_iterations = DEFAULT_NEWTON_ITERATIONS;
        ws.newton_contraction = DEFAULT_NEWTON_CONTRACTION;
        ws.regime_iterations = DEFAULT_REGIME_ITERATIONS;
        #[cfg(feature = "sparse-cholesky")]
        {
            ws.solver = super::LinearSolver::default_aggregation();
        }
        ws
    }

    /// Whether the acceleration must be taken from the force before the next step.
    pub fn alpha_needs_acceleration(&self) -> bool {
        self.alpha.as_ref().is_some_and(|a| !a.valid)
    }

    /// Where the caller writes a₀ = M⁻¹ f(t, x, v) (then [`Self::alpha_needs_acceleration`] is false).
    pub fn alpha_acceleration_mut(&mut self) -> &mut [C] {
        let a = self.alpha.as_mut().expect("generalised-α workspace");
        a.valid = true;
        &mut a.a
    }

    /// One generalised-α step from `now` into `next`, with contacts from `contacts` constrained inside the
    /// solve when given.
    ///
    /// Newton's method with a safeguarding line search on the filtered residual ‖S G(w)‖_M⁻¹: a full step
    /// that more than doubles it is halved (at most three times). Undamped Newton oscillates on very
    /// stiff springs (k = 10⁵ N/m at 1/60 s: residuals 24 → 33 → 20 → 33 → …, measured), because a step
    /// that overshoots a spring's length reverses a force many thousand times the particle's weight. The
    /// trial point's evaluation is the next iteration's linearisation, so the search costs one extra
    /// evaluation per step when every full step is accepted.
    pub fn step_alpha(
        &mut self,
        lin: &mut dyn Linearized<C>,
        mut contacts: Option<&mut dyn ContactModel<C>>,
        t: f64,
        h: f64,
        now: &State<C>,
        next: &mut State<C>,
    ) -> Result<StepStats, OdeError> {
        let n = now.len();
        self.a.resize(n, lin.pattern());
        self.trial.resize(n, C::default());
        self.delta.resize(n, C::default());
        let state = self.alpha.as_ref().expect("generalised-α workspace");
        debug_assert!(state.valid, "the stepper sets a₀ before the step");
        let c = Coefficients::new(state.params, h);
        let profiling = self.profile.is_some();
        // The predictor w = v₀; prescribed coordinates keep their velocity throughout.
        next.v.copy_from_slice(&now.v);
        if contacts.is_some() {
            self.contact.begin(lin.prescribed());
        } else {
            self.contact.slots.clear();
        }
        self.evaluate(lin, &c, t, now, next, true);
        // The rigid-aggregation preconditioner takes its patches' rotations about the predicted end
        // positions and builds its coarse matrix at the step's first solve.
        self.coarse_stale = true;
        self.positions.clear();
        self.positions.extend_from_slice(&next.x);
        // A force that overflowed at the predictor: the merit would be NaN, no Newton iteration would
        // run, and the step would end at the predictor, finite and wrong.
        if !self.b.iter().all(|b| b.is_finite()) {
            return Err(OdeError::NonFiniteSystem);
        }
        let mut merit = self.merit(lin.masses(), lin.prescribed(), contacts.is_some(), c.eta, &next.v);
        let mut iterations = 0;
        let mut evaluations = 1;
        let (mut newton, mut extra) = (0, 0);
        // ‖δ‖_M of the last Newton update, and whether the updates have contracted enough to stop.
        let mut last_update = f64::INFINITY;
        let mut contracted = false;
        let contraction = self.newton_contraction;
        loop {
            let started = profiling.then(Instant::now);
            let prescribed = lin.prescribed();
            let mut regimes_changed = false;
            // With contacts, the projectors are moved out of the contact state for the solve (and back).
            let projectors = if let Some(model) = contacts.as_deref_mut() {
                // X₁ = x₁ − c_end w, kept in xk (the force no longer needs it).
                for i in 0..n {
                    self.xk[i] = next.x[i] - next.v[i] * c.end;
                }
                self.contact.found.clear();
                model.contacts(&now.x, &next.x, &mut self.contact.found);
                self.contact.merge(prescribed);
                regimes_changed = self.contact.update(
                    &next.v,
                    &self.xk,
                    c.end,
                    StepStart { x: &now.x, v: &now.v, h },
                    &self.b,
                    c.eta,
                );
                // Smoothed friction is known only once a contact's normal reaction is: the merit that
                // decides whether Newton goes on must hold it (a contact arriving on a floor has none in
                // its first solve, and without this its step would end without friction).
                if matches!(self.contact.friction_model, Friction::Smoothed { .. }) {
                    merit = self.merit(lin.masses(), lin.prescribed(), true, c.eta, &next.v);
                }
                for s in &self.contact.slots {
                    let i = s.contact.coordinate as usize;
                    self.b[i] += s.friction * c.eta;
                    // Smoothed friction is linear in w with its lagged coefficient: −η ∂F/∂w = η d (I − n nᵀ),
                    // and the filter removes the normal part.
                    if s.damping > 0.0 {
                        self.a.add_diagonal(i, s.damping * c.eta);
                    }
                }
                if let (Some(p), Some(s)) = (&mut self.profile, started) {
                    p.contact_s += s.elapsed().as_secs_f64();
                }
                Some(std::mem::take(&mut self.contact.filter))
            } else {
                None
            };
            // The planned iterations, and up to `regime_iterations` more while the contacts keep
            // changing (a regime change is only honoured by a solve).
            let planned = newton < self.newton_iterations && !contracted && (merit > 0.0 || regimes_changed);
            let more = regimes_changed && extra < self.regime_iterations;
            if !(planned || more) {
                if let Some(s) = projectors {
                    self.contact.filter = s;
                }
                break;
            }
            if !planned {
                extra += 1;
            }
            newton += 1;
            let filter = match &projectors {
                Some(s) => Filter::Projected(s),
                None => Filter::Prescribed(prescribed),
            };
            // S A S y = S (b − A z), δ = y + z (z = 0 without contacts).
            let constrained = projectors.is_some() && !self.contact.slots.is_empty();
            if constrained {
                self.a.mul(lin.pattern(), Filter::None, &self.contact.z, &mut self.dv);
                for i in 0..n {
                    self.b[i] = self.b[i] - self.dv[i];
                }
            }
            filter.apply(&mut self.b);
            self.dv.fill(C::default());
            let solved = self.solve(lin.pattern(), filter, lin.masses(), prescribed, false);
            if let Some(s) = projectors {
                self.contact.filter = s;
            }
            iterations += solved?;
            let (mut largest, mut update) = (0.0f64, 0.0);
            let masses = lin.masses();
            for i in 0..n {
                let d = if constrained { self.dv[i] + self.contact.z[i] } else { self.dv[i] };
                largest = largest.max(d.max_abs());
                update += d.dot(d) * masses[i];
                self.delta[i] = d;
            }
            let update = update.sqrt();
            contracted =
                !constrained && newton >= MIN_NEWTON_ITERATIONS && update <= contraction * last_update;
            last_update = update;
            if let Some(p) = &mut self.profile {
                p.newton_iterations += 1;
            }
            if largest == 0.0 {
                break;
            }
            // A contracted update ends the iterations, and it is taken whole, without the line search's
            // evaluation: the search guards against the overshoots of stiff springs far from the
            // solution, which an update a third of the one before does not make. On the standard sheet
            // (N = 64, 1/60 s) the search still halved some final updates (the M⁻¹-norm residual rises
            // with good steps in the soft directions): without it the RMS error went from 34.2 to
            // 31.9 mm (the centre of mass from 13.3 to 3.4 mm, within its chaotic spread), and a step
            // saves a force evaluation, 7 % of its time.
            if contracted && contacts.is_none() {
                for i in 0..n {
                    next.v[i] += self.delta[i];
                }
                break;
            }
            // The line search; not when a contact changed its regime, since the residual it measures then
            // jumps with the constraints, not with the step.
            self.trial.copy_from_slice(&next.v);
            let mut step = 1.0;
            let halvings = if regimes_changed { 0 } else { MAX_HALVINGS };
            // A solve follows only while planned iterations remain or, with contacts, while iterations
            // for regime changes may still run: otherwise the trial point needs its residual only (for
            // the contacts' last update), not a new matrix.
            let with_matrix = (newton < self.newton_iterations && !contracted)
                || (contacts.is_some() && extra < self.regime_iterations);
            for attempt in 0..=halvings {
                for i in 0..n {
                    next.v[i] = self.trial[i] + self.delta[i] * step;
                }
                self.evaluate(lin, &c, t, now, next, with_matrix);
                evaluations += 1;
                let trial = self.merit(lin.masses(), lin.prescribed(), contacts.is_some(), c.eta, &next.v);
                let finite = self.b.iter().all(|b| b.is_finite());
                if !finite && attempt == halvings {
                    return Err(OdeError::NonFiniteSystem);
                }
                if finite && (trial <= GROWTH_ALLOWED * merit || attempt == halvings) {
                    merit = trial;
                    break;
                }
                step *= 0.5;
            }
        }
        // The end state, with a last look at the contacts: a coordinate whose end position would still lie
        // beyond its surface's tangent plane loses its inward normal velocity.
        let late = match contacts.as_deref_mut() {
            Some(model) => {
                for i in 0..n {
                    self.xk[i] = next.x[i] - next.v[i] * c.end;
                }
                self.settle_contacts(model, now, next, c.end, lin.prescribed())
            }
            None => 0,
        };
        let prescribed = lin.prescribed();
        let (gamma, beta) = (c.params.gamma, c.params.beta);
        let state = self.alpha.as_mut().expect("present");
        for i in 0..n {
            let w = next.v[i];
            if prescribed[i] {
                next.x[i] = now.x[i] + w * h;
                state.a[i] = C::default();
            } else {
                let a1 = (w - now.v[i]) * (1.0 / (gamma * h)) - state.a[i] * ((1.0 - gamma) / gamma);
                next.x[i] = now.x[i] + now.v[i] * h + (state.a[i] * (0.5 - beta) + a1 * beta) * (h * h);
                state.a[i] = a1;
            }
        }
        // Along a constrained direction the motion is the contact's: the acceleration there would carry an
        // impact into the next step. A coordinate in contact ends on its surface's tangent plane (the
        // position bound; or, arriving with a restitution, as far out as its bounce took it since the
        // impact), and leaves the step with the normal velocity of an inelastic impact, zero (or its
        // restitution's bounce): x₁ = X₁ + c w alone cannot express that. The w that put it on the
        // plane points out of the surface by as much as the inertial part X₁ of the step went in (for
        // ρ∞ = 0.4, 82 % of the speed it arrived with), and kept as the velocity it is a bounce that
        // pumps energy into the cloth (measured: a 20 m/s drop onto a box went from 43 J to 300 J).
        if contacts.is_some() {
            for s in &self.contact.slots {
                let i = s.contact.coordinate as usize;
                if s.regime != Regime::Free || s.released {
                    state.a[i] = C::block_mul(self.contact.filter[i], state.a[i]);
                }
                if s.regime != Regime::Free {
                    let n = s.contact.normal;
                    let bounce = -s.contact.restitution * n.dot(now.v[i]).min(0.0);
                    self.contact.clamp.push((s.contact.coordinate, n, bounce));
                }
            }
            for &(i, n, bounce) in &self.contact.clamp {
                let i = i as usize;
                let vn = n.dot(next.v[i]);
                next.v[i] += n * (bounce - vn);
                let an = n.dot(state.a[i]);
                state.a[i] = state.a[i] - n * an;
            }
            self.contact.end();
        }
        if let Some(p) = &mut self.profile {
            p.steps += 1;
        }
        Ok(StepStats {
            evaluations,
            solver_iterations: iterations,
            contacts: self.contact_count(contacts.is_some()),
            late_contacts: late,
            ..Default::default()
        })
    }

    /// At the iterate w = `next.v`: its end positions (into `next.x`), the force and the system matrix at
    /// the evaluation point, and b = −G(w) = η f − M (w − v₀ − ĉ a₀) (zero on prescribed coordinates,
    /// without contact friction).
    fn evaluate(
        &mut self,
        lin: &mut dyn Linearized<C>,
        c: &Coefficients,
        t: f64,
        now: &State<C>,
        next: &mut State<C>,
        with_matrix: bool,
    ) {
        let started = self.profile.is_some().then(Instant::now);
        let n = now.len();
        let (h, gamma, beta, alpha_f) = (c.h, c.params.gamma, c.params.beta, c.params.alpha_f);
        let a0 = &self.alpha.as_ref().expect("present").a;
        let prescribed = lin.prescribed();
        for i in 0..n {
            let w = next.v[i];
            let x1 = if prescribed[i] {
                now.x[i] + w * h
            } else {
                let a1 = (w - now.v[i]) * (1.0 / (gamma * h)) - a0[i] * ((1.0 - gamma) / gamma);
                now.x[i] + now.v[i] * h + (a0[i] * (0.5 - beta) + a1 * beta) * (h * h)
            };
            next.x[i] = x1;
            self.xk[i] = now.x[i] * alpha_f + x1 * (1.0 - alpha_f);
            self.w[i] = now.v[i] * alpha_f + w * (1.0 - alpha_f);
        }
        let t_star = t + (1.0 - alpha_f) * h;
        if with_matrix {
            self.a.spring_form = lin.spring_form();
            // Conjugate gradients and the rigid aggregation work from the spring form alone.
            let blocks = !self.a.spring_form || self.solver.needs_blocks();
            let off = if blocks { &mut self.a.off[..] } else { &mut [] };
            let spring_form = self.a.spring_form;
            lin.force_and_system(
                t_star,
                &self.xk,
                &self.w,
                c.beta_v,
                c.beta_x,
                super::SystemOut {
                    f: &mut self.f,
                    diag: &mut self.a.diag,
                    off,
                    springs: spring_form.then_some(&mut self.a.springs),
                },
                &mut self.jac,
            );
            let extra = &mut self.extra_diagonal;
            extra.clear();
            extra.resize(n, 0.0);
            if self.a.spring_form {
                lin.spring_form_diagonal(c.beta_v, c.beta_x, extra);
            }
            self.a.add_masses(lin.masses(), extra);
        } else {
            lin.force(t_star, &self.xk, &self.w, &mut self.f, &mut self.jac);
        }
        let masses = lin.masses();
        let prescribed = lin.prescribed();
        let a0 = &self.alpha.as_ref().expect("present").a;
        for i in 0..n {
            self.b[i] = if prescribed[i] {
                C::default()
            } else {
                self.f[i] * c.eta - (next.v[i] - now.v[i] - a0[i] * c.c_hat) * masses[i]
            };
        }
        if let (Some(p), Some(s)) = (&mut self.profile, started) {
            p.assembly_s += s.elapsed().as_secs_f64();
        }
    }

    /// ‖S b‖ in the M⁻¹ norm, with the kinetic friction of sliding contacts: the residual the solve
    /// can act on (constrained directions carry the contacts' reactions instead).
    /// Smoothed friction is evaluated at the iterate `w` with its lagged coefficient, as the solve saw it.
    fn merit(&self, masses: &[f64], prescribed: &[bool], with_contacts: bool, eta: f64, w: &[C]) -> f64 {
        let mut sum = 0.0;
        for i in 0..masses.len() {
            if prescribed[i] {
                continue;
            }
            let mut r = self.b[i];
            if with_contacts && self.contact.slot_of[i] != 0 {
                let s = &self.contact.slots[self.contact.slot_of[i] as usize - 1];
                let friction = if s.damping > 0.0 {
                    let n = s.contact.normal;
                    (w[i] - n * n.dot(w[i])) * -s.damping
                } else {
                    s.friction
                };
                r = C::block_mul(self.contact.filter[i], r + friction * eta);
            }
            sum += r.dot(r) / masses[i];
        }
        sum.sqrt()
    }

    /// The last look at the contacts after the Newton iterations: up to three rounds of detection at the
    /// end positions, each removing the inward normal velocity of a coordinate that would end beyond its
    /// surface's tangent plane. `self.xk` holds X₁ (x₁ = X₁ + c_end w). Returns how many corrections
    /// were made.
    fn settle_contacts(
        &mut self,
        model: &mut dyn ContactModel<C>,
        now: &State<C>,
        next: &mut State<C>,
        c_end: f64,
        prescribed: &[bool],
    ) -> usize {
        let started = self.profile.is_some().then(Instant::now);
        let mut late = 0;
        for _round in 0..SETTLE_ROUNDS {
            for i in 0..now.len() {
                if !prescribed[i] {
                    next.x[i] = self.xk[i] + next.v[i] * c_end;
                }
            }
            self.contact.found.clear();
            model.contacts(&now.x, &next.x, &mut self.contact.found);
            let mut corrected = false;
            for c in &self.contact.found {
                let i = c.coordinate as usize;
                if prescribed[i] {
                    continue;
                }
                let target = -c.normal.dot(self.xk[i] - c.point) / c_end;
                let wn = c.normal.dot(next.v[i]);
                // Round-off leaves a coordinate that met its bound exactly a few ulps short of it.
                if target - wn > 1e-12 * (1.0 + target.abs() + wn.abs()) {
                    next.v[i] += c.normal * (target - wn);
                    self.contact.clamp.push((c.coordinate, c.normal, 0.0));
                    late += 1;
                    corrected = true;
                }
            }
            if !corrected {
                break;
            }
        }
        if let (Some(p), Some(s)) = (&mut self.profile, started) {
            p.contact_s += s.elapsed().as_secs_f64();
        }
        late
    }

    fn contact_count(&self, with_contacts: bool) -> usize {
        if with_contacts { self.contact.active() } else { 0 }
    }
}
