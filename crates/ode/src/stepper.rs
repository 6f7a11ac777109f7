//! [`Stepper`]: one integrator with the scratch buffers it needs.

#![allow(
    clippy::needless_range_loop,
    reason = "the loops walk several per-coordinate arrays in step; the index form mirrors the formulas"
)]

use crate::implicit::contact::ContactModel;
use crate::implicit::workspace::{ImplicitWorkspace, SolveProfile};
use crate::{Coord, Integrator, OdeSystem};

/// Positions and velocities of a second-order system.
#[derive(Debug, Clone, PartialEq)]
pub struct State<C> {
    pub x: Vec<C>,
    pub v: Vec<C>,
}

impl<C: Coord> State<C> {
    pub fn new(x: Vec<C>, v: Vec<C>) -> Self {
        assert_eq!(x.len(), v.len(), "as many velocities as positions");
        Self { x, v }
    }

    /// `n` coordinates, all zero.
    pub fn zeros(n: usize) -> Self {
        Self { x: vec![C::default(); n], v: vec![C::default(); n] }
    }

    pub fn len(&self) -> usize {
        self.x.len()
    }

    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// Index of the first coordinate whose position or velocity is not finite.
    pub fn first_non_finite(&self) -> Option<usize> {
        self.x.iter().zip(&self.v).position(|(x, v)| !(x.is_finite() && v.is_finite()))
    }
}

/// What one step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats {
    /// Acceleration (or force-and-Jacobian) evaluations.
    pub evaluations: usize,
    /// Estimated local error of the step, in position units (max norm over coordinates of the position
    /// error and h × the velocity error), for the adaptive methods.
    pub error: Option<f64>,
    /// Conjugate-gradient iterations of an implicit step.
    pub solver_iterations: usize,
    /// Contacts constrained inside the solve at the end of the step ([`Stepper::step_with_contacts`]).
    pub contacts: usize,
    /// Coordinates whose inward normal velocity had to be removed after the Newton iterations because
    /// their end position would still have crossed a surface.
    pub late_contacts: usize,
}

/// Why a step could not be taken.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OdeError {
    #[error("{0} needs the system's Jacobians, and this system gives none")]
    NoJacobians(Integrator),
    #[error(
        "the linear solve of an implicit step did not converge ({iterations} iterations, residual {residual:e})"
    )]
    SolverDidNotConverge { iterations: usize, residual: f64 },
    #[error("the direct solve of an implicit step failed: {0}")]
    Factorization(String),
    #[error("{0} cannot constrain contacts inside its step; generalized-alpha can")]
    ContactsUnsupported(Integrator),
    #[error("the linear system of an implicit step holds a non-finite value (a force overflowed)")]
    NonFiniteSystem,
}

/// Butcher tableau of an explicit Runge–Kutta method; `e` holds b − b̂ for an embedded error estimate.
struct Tableau {
    c: &'static [f64],
    a: &'static [&'static [f64]],
    b: &'static [f64],
    e: Option<&'static [f64]>,
}

const MIDPOINT: Tableau = Tableau { c: &[0.0, 0.5], a: &[&[], &[0.5]], b: &[0.0, 1.0], e: None };

/// Dormand & Prince (1980), the RK5(4)7M pair.
const DOPRI5: Tableau = Tableau {
    c: &[0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0],
    a: &[
        &[],
        &[1.0 / 5.0],
        &[3.0 / 40.0, 9.0 / 40.0],
        &[44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0],
        &[19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0],
        &[9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0],
        &[35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
    ],
    b: &[35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0, 0.0],
    e: Some(&[
        71.0 / 57600.0,
        0.0,
        -71.0 / 16695.0,
        71.0 / 1920.0,
        -17253.0 / 339200.0,
        22.0 / 525.0,
        -1.0 / 40.0,
    ]),
};

/// History of a multistep method: f = (v, a) at the last four steps, newest first.
#[derive(Debug, Clone)]
struct History<C> {
    v: [Vec<C>; 4],
    a: [Vec<C>; 4],
    len: usize,
    h: f64,
}

/// An integrator with the scratch buffers it needs, owned by the caller so that the step loop never
/// allocates.
#[derive(Debug, Clone)]
pub struct Stepper<C: Coord> {
    integrator: Integrator,
    n: usize,
    a: Vec<C>,
    xs: Vec<C>,
    vs: Vec<C>,
    dx: Vec<C>,
    dv: Vec<C>,
    /// Stage slopes of the tableau methods: kx = stage velocity, kv = stage acceleration.
    kx: Vec<Vec<C>>,
    kv: Vec<Vec<C>>,
    history: Option<History<C>>,
    implicit: Option<ImplicitWorkspace<C>>,
}

/// What a [`Stepper`] carries from one step to the next, saved by [`Stepper::save_history`].
#[derive(Debug, Clone, Default)]
pub struct SavedHistory<C> {
    alpha: Vec<C>,
    alpha_valid: bool,
    /// The contacts' last regime, reaction and friction, per coordinate in contact.
    regimes: Vec<(u32, crate::contact::Regime, C, C)>,
}

impl<C: Coord> Stepper<C> {
    pub fn new(integrator: Integrator, n_coords: usize) -> Self {
        let n = n_coords;
        let zeros = || vec![C::default(); n];
        let stages = match integrator {
            Integrator::Midpoint => 2,
            Integrator::DormandPrince => 7,
            _ => 0,
        };
        let rk4_buffers = matches!(
            integrator,
            Integrator::Rk4 | Integrator::AdamsBashforth4 | Integrator::AdamsBashforthMoulton4
        );
        let buf = |on: bool| if on { zeros() } else { Vec::new() };
        Self {
            integrator,
            n,
            a: zeros(),
            xs: buf(rk4_buffers || stages > 0 || integrator == Integrator::AdaptiveEuler),
            vs: buf(rk4_buffers || stages > 0 || integrator == Integrator::AdaptiveEuler),
            dx: buf(rk4_buffers),
            dv: buf(rk4_buffers),
            kx: (0..stages).map(|_| zeros()).collect(),
            kv: (0..stages).map(|_| zeros()).collect(),
            history: integrator.is_multistep().then(|| History {
                v: std::array::from_fn(|_| zeros()),
                a: std::array::from_fn(|_| zeros()),
                len: 0,
                h: 0.0,
            }),
            implicit: match integrator {
                Integrator::GeneralizedAlpha => Some(ImplicitWorkspace::new_alpha(n)),
                i if i.is_implicit() => Some(ImplicitWorkspace::new(n, i == Integrator::Bdf2)),
                _ => None,
            },
        }
    }

    pub fn integrator(&self) -> Integrator {
        self.integrator
    }

    /// A fresh stepper for `n_coords` coordinates (after a topology change) with this one's integrator,
    /// linear solver, Newton iterations, ρ∞, friction model and profile (its sums so far kept); the
    /// history starts empty (generalised-α then takes its acceleration from M⁻¹ f: see
    /// [`Stepper::zero_acceleration`] for a state that rests on contacts).
    pub fn resized(&self, n_coords: usize) -> Self {
        let mut s = Stepper::new(self.integrator, n_coords);
        if let (Some(from), Some(to)) = (&self.implicit, &mut s.implicit) {
            to.solver = from.solver;
            to.newton_iterations = from.newton_iterations;
            to.newton_contraction = from.newton_contraction;
            to.regime_iterations = from.regime_iterations;
            to.bounded_smoothing = from.bounded_smoothing;
            to.contact.friction_model = from.contact.friction_model;
            if let (Some(a), Some(b)) = (&from.alpha, &mut to.alpha) {
                b.params = a.params;
            }
            // The profile so far goes on, so that a remeshed run is timed whole.
            to.profile = from.profile;
        }
        s
    }

    /// ρ∞ of generalised-α, the spectral radius of its step at infinite h ω (clamped to [0, 1]): 1 damps
    /// nothing (the implicit midpoint rule), 0 removes the unresolved modes in one step. The default is
    /// [`crate::DEFAULT_RHO_INF`]. No effect on other integrators.
    pub fn set_spectral_radius(&mut self, rho_inf: f64) {
        if let Some(a) = self.implicit.as_mut().and_then(|w| w.alpha.as_mut()) {
            a.params = crate::AlphaParameters::new(rho_inf);
        }
    }

    /// ρ∞ of generalised-α (`None` for other integrators).
    pub fn spectral_radius(&self) -> Option<f64> {
        self.implicit.as_ref().and_then(|w| w.alpha.as_ref()).map(|a| a.params.rho_inf)
    }

    /// The implicit methods' linear solver (`None` for explicit integrators).
    pub fn linear_solver(&self) -> Option<crate::LinearSolver> {
        self.implicit.as_ref().map(|w| w.solver)
    }

    /// Newton iterations per step of the implicit methods (`None` for explicit integrators).
    pub fn newton_iterations(&self) -> Option<usize> {
        self.implicit.as_ref().map(|w| w.newton_iterations)
    }

    /// Starts (or stops, with `false`) timing where the implicit steps spend their time; see
    /// [`Stepper::profile`]. Timing changes no result.
    pub fn set_profiling(&mut self, on: bool) {
        if let Some(ws) = &mut self.implicit {
            ws.profile = on.then(SolveProfile::default);
        }
    }

    /// The contacts of the last [`Stepper::step_with_contacts`], with their regimes and forces.
    pub fn contact_reports(&self) -> impl Iterator<Item = crate::contact::ContactReport<C>> + '_ {
        self.implicit.iter().flat_map(|w| w.contact.reports())
    }

    /// The time the implicit steps spent, by part, since profiling started.
    pub fn profile(&self) -> Option<SolveProfile> {
        self.implicit.as_ref().and_then(|w| w.profile)
    }

    pub(crate) fn set_solver(&mut self, solver: crate::LinearSolver) {
        if let Some(ws) = &mut self.implicit {
            ws.solver = solver;
        }
    }

    /// Newton iterations per step of the implicit methods (at least 1). Backward Euler defaults to 1,
    /// Baraff and Witkin's single linearisation; BDF2 to 2; generalised-α to
    /// [`crate::DEFAULT_NEWTON_ITERATIONS`]. More iterations solve the nonlinear step equations more
    /// closely, which BDF2 needs to keep its second order on stiff, damped springs. A count set here
    /// runs in full: it also turns generalised-α's early stop off ([`Stepper::set_newton_contraction`],
    /// which can turn it on again afterwards).
    pub fn set_newton_iterations(&mut self, iterations: usize) {
        if let Some(ws) = &mut self.implicit {
            ws.newton_iterations = iterations.max(1);
            ws.newton_contraction = 0.0;
        }
    }

    /// Generalised-α's early stop: after two Newton iterations the rest are skipped once an update is at
    /// most `ratio` times the one before in the mass norm. The default is
    /// [`crate::DEFAULT_NEWTON_CONTRACTION`]; 0 runs every planned iteration. No effect on other
    /// integrators.
    pub fn set_newton_contraction(&mut self, ratio: f64) {
        if let Some(ws) = &mut self.implicit {
            ws.newton_contraction = ratio.max(0.0);
        }
    }

    /// Generalised-α with contacts in its solve: up to `iterations` Newton iterations beyond the planned
    /// ones while contacts still change regime (stick, slide, free) at the last iterate. The default is
    /// [`crate::DEFAULT_REGIME_ITERATIONS`], where the measurements behind it are. No effect on other
    /// integrators or without contacts.
    pub fn set_regime_iterations(&mut self, iterations: usize) {
        if let Some(ws) = &mut self.implicit {
            ws.regime_iterations = iterations;
        }
    }

    /// Whether the rigid-aggregation preconditioner (generalised-α's default solver) damps its
    /// block-Jacobi smoothing by an estimate of the system's largest eigenvalue, so that the smoothing
    /// never amplifies the stiffest modes (on by default; the measurements and the reason are at
    /// `implicit::aggregation::SMOOTHING_BOUND`). A cloth mesh graded by remeshing needs it: its bending
    /// elements lift that eigenvalue past what the fixed damping allows (the largest uniform drapes pass
    /// it too, once they touch). Where the fixed damping already contracts the bound changes no bit.
    /// Off, the damping is fixed and nothing is estimated. No effect on other solvers.
    pub fn set_bounded_smoothing(&mut self, on: bool) {
        if let Some(ws) = &mut self.implicit {
            ws.bounded_smoothing = on;
        }
    }

    /// How friction enters the contacts of generalised-α's solve: [`crate::contact::Friction::ActiveSet`]
    /// (the default) or smoothed. No effect on other integrators or without contacts.
    pub fn set_friction(&mut self, friction: crate::contact::Friction) {
        if let Some(ws) = &mut self.implicit {
            ws.contact.friction_model = friction;
        }
    }

    /// The friction model of the contacts in the solve (`None` for explicit integrators).
    pub fn friction(&self) -> Option<crate::contact::Friction> {
        self.implicit.as_ref().map(|w| w.contact.friction_model)
    }

    /// Generalised-α's iterations for contacts that change regime (`None` for explicit integrators).
    pub fn regime_iterations(&self) -> Option<usize> {
        self.implicit.as_ref().map(|w| w.regime_iterations)
    }

    /// Generalised-α's early-stop ratio (`None` for explicit integrators).
    pub fn newton_contraction(&self) -> Option<f64> {
        self.implicit.as_ref().map(|w| w.newton_contraction)
    }

    /// Like [`Stepper::reset_history`], for a change that touched only the coordinates flagged in
    /// `changed` (a collision response answered after the step). Generalised-α forgets the acceleration of
    /// those coordinates only (sets it to zero: their velocity was redefined by an impulse the method's
    /// acceleration must not carry into the next step), and keeps the rest. Restarting every coordinate
    /// from M⁻¹ f instead puts the whole force of springs stretched by the response into the next step
    /// explicitly, with weight ĉ ≈ h/4, which blew up Oliveira's drapes at 1/60 s (measured, even at
    /// ρ∞ = 0). The multistep methods and BDF2 forget their whole history, as `reset_history` does.
    pub fn reset_history_of(&mut self, changed: &[bool]) {
        if let Some(a) = self.implicit.as_mut().and_then(|w| w.alpha.as_mut())
            && a.valid
        {
            for (a, &c) in a.a.iter_mut().zip(changed) {
                if c {
                    *a = C::default();
                }
            }
            return;
        }
        self.reset_history();
    }

    /// Generalised-α's acceleration set to zero at every coordinate, as [`Stepper::reset_history_of`]
    /// does for the coordinates it is given (the other integrators forget their history, as
    /// [`Stepper::reset_history`]). For a state the method did not step to, such as a remeshed cloth's
    /// (see [`Stepper::resized`]).
    pub fn zero_acceleration(&mut self) {
        self.reset_history();
        if let Some(ws) = &mut self.implicit
            && ws.alpha.is_some()
        {
            ws.alpha_acceleration_mut().fill(C::default());
        }
    }

    /// Saves what the implicit methods carry from one step to the next (generalised-α's acceleration,
    /// the contacts' last regimes) into `saved`, so that a step can be discarded and
    /// taken again from the same start ([`Stepper::restore_history`]). Copies only; `saved` keeps its
    /// buffers between calls.
    pub fn save_history(&self, saved: &mut SavedHistory<C>) {
        saved.alpha.clear();
        saved.alpha_valid = false;
        saved.regimes.clear();
        if let Some(ws) = &self.implicit {
            if let Some(a) = &ws.alpha {
                saved.alpha.extend_from_slice(&a.a);
                saved.alpha_valid = a.valid;
            }
            let c = &ws.contact;
            saved.regimes.extend(c.last_active.iter().map(|&i| {
                let k = i as usize;
                (i, c.last_regime[k], c.last_reaction[k], c.last_friction[k])
            }));
        }
    }

    /// Puts back what [`Stepper::save_history`] saved, after a step from the same start was discarded.
    /// Everything else starts again as after [`Stepper::reset_history`]: the multistep methods and BDF2,
    /// whose history the discarded step moved on (BDF2's state one step back is now the start itself).
    /// Restarting generalised-α from M⁻¹ f instead would put the whole force of the springs the
    /// discarded step's contacts stretched into the next step explicitly (see
    /// [`Stepper::reset_history_of`]).
    pub fn restore_history(&mut self, saved: &SavedHistory<C>) {
        self.reset_history();
        let Some(ws) = &mut self.implicit else { return };
        if let Some(a) = &mut ws.alpha
            && saved.alpha.len() == a.a.len()
        {
            a.a.copy_from_slice(&saved.alpha);
            a.valid = saved.alpha_valid;
        }
        let c = &mut ws.contact;
        for &(i, regime, reaction, friction) in &saved.regimes {
            let k = i as usize;
            if k < c.last_regime.len() && k < c.last_reaction.len() && k < c.last_friction.len() {
                c.last_regime[k] = regime;
                c.last_reaction[k] = reaction;
                c.last_friction[k] = friction;
                c.last_active.push(i);
            }
        }
    }

    /// Forgets the history of a multistep method, so that the next steps start it again with RK4 (BDF2
    /// with backward Euler, generalised-α with M⁻¹ f as its acceleration). Call after anything changed
    /// the state outside the integrator (a collision response, a constraint).
    pub fn reset_history(&mut self) {
        if let Some(h) = &mut self.history {
            h.len = 0;
        }
        if let Some(ws) = &mut self.implicit {
            ws.reset_history();
        }
    }

    /// One step of size `h` from `now` (at time `t`) into `next`.
    pub fn step<S: OdeSystem<Coord = C> + ?Sized>(
        &mut self,
        sys: &mut S,
        t: f64,
        h: f64,
        now: &State<C>,
        next: &mut State<C>,
    ) -> Result<StepStats, OdeError> {
        let n = self.n;
        assert!(
            sys.n_coords() == n && now.len() == n && next.len() == n,
            "the stepper, the system and both states must have the same size"
        );
        let (x, v) = (&now.x[..], &now.v[..]);
        Ok(match self.integrator {
            Integrator::ForwardEuler => {
                sys.acceleration(t, x, v, &mut self.a);
                for i in 0..n {
                    next.x[i] = x[i] + v[i] * h;
                    next.v[i] = v[i] + self.a[i] * h;
                }
                StepStats { evaluations: 1, ..Default::default() }
            }
            Integrator::SymplecticEuler => {
                sys.acceleration(t, x, v, &mut self.a);
                for i in 0..n {
                    let vi = v[i] + self.a[i] * h;
                    next.v[i] = vi;
                    next.x[i] = x[i] + vi * h;
                }
                StepStats { evaluations: 1, ..Default::default() }
            }
            Integrator::Rk4 => {
                sys.acceleration(t, x, v, &mut self.a);
                self.rk4_from_a(sys, t, h, now, next);
                StepStats { evaluations: 4, ..Default::default() }
            }
            Integrator::Midpoint => self.tableau(sys, t, h, now, next, &MIDPOINT),
            Integrator::DormandPrince => self.tableau(sys, t, h, now, next, &DOPRI5),
            Integrator::AdamsBashforth4 | Integrator::AdamsBashforthMoulton4 => {
                self.multistep(sys, t, h, now, next)
            }
            Integrator::AdaptiveEuler => self.adaptive_euler(sys, t, h, now, next),
            Integrator::ImplicitEuler | Integrator::Bdf2 => {
                let ws = self.implicit.as_mut().expect("allocated for the implicit methods");
                let lin = sys.linearized().ok_or(OdeError::NoJacobians(self.integrator))?;
                ws.step_euler(lin, t, h, now, next)?
            }
            Integrator::GeneralizedAlpha => self.alpha_step(sys, None, t, h, now, next)?,
        })
    }

    /// One step like [`Stepper::step`], with the contacts `contacts` reports constrained inside the
    /// implicit solve (see [`crate::contact`]): only generalised-α can; other integrators return
    /// [`OdeError::ContactsUnsupported`].
    pub fn step_with_contacts<S: OdeSystem<Coord = C> + ?Sized>(
        &mut self,
        sys: &mut S,
        contacts: &mut dyn ContactModel<C>,
        t: f64,
        h: f64,
        now: &State<C>,
        next: &mut State<C>,
    ) -> Result<StepStats, OdeError> {
        if self.integrator != Integrator::GeneralizedAlpha {
            return Err(OdeError::ContactsUnsupported(self.integrator));
        }
        let n = self.n;
        assert!(
            sys.n_coords() == n && now.len() == n && next.len() == n,
            "the stepper, the system and both states must have the same size"
        );
        self.alpha_step(sys, Some(contacts), t, h, now, next)
    }

    fn alpha_step<S: OdeSystem<Coord = C> + ?Sized>(
        &mut self,
        sys: &mut S,
        contacts: Option<&mut dyn ContactModel<C>>,
        t: f64,
        h: f64,
        now: &State<C>,
        next: &mut State<C>,
    ) -> Result<StepStats, OdeError> {
        let ws = self.implicit.as_mut().expect("allocated for the implicit methods");
        let mut extra = 0;
        if ws.alpha_needs_acceleration() {
            // The method's acceleration starts as M⁻¹ f, after a start or a reset.
            sys.acceleration(t, &now.x, &now.v, ws.alpha_acceleration_mut());
            extra = 1;
        }
        let lin = sys.linearized().ok_or(OdeError::NoJacobians(self.integrator))?;
        let mut stats = ws.step_alpha(lin, contacts, t, h, now, next)?;
        stats.evaluations += extra;
        Ok(stats)
    }

    /// Classical RK4 given a = a(t, x, v) already in `self.a`. Increments are accumulated in (dx, dv) with
    /// weights 1, 2, 2, 1 and applied once at the end.
    fn rk4_from_a<S: OdeSystem<Coord = C> + ?Sized>(
        &mut self,
        sys: &mut S,
        t: f64,
        h: f64,
        now: &State<C>,
        next: &mut State<C>,
    ) {
        let (x, v, n) = (&now.x[..], &now.v[..], self.n);
        let half = 0.5 * h;
        for i in 0..n {
            self.dx[i] = v[i];
            self.dv[i] = self.a[i];
            self.xs[i] = x[i] + v[i] * half;
            self.vs[i] = v[i] + self.a[i] * half;
        }
        // Stages 2 and 3 at the midpoint; stage 3's slope then carries the state a full step.
        for step_to in [half, h] {
            sys.acceleration(t + half, &self.xs, &self.vs, &mut self.a);
            for i in 0..n {
                let (kx, kv) = (self.vs[i], self.a[i]);
                self.dx[i] += kx * 2.0;
                self.dv[i] += kv * 2.0;
                self.xs[i] = x[i] + kx * step_to;
                self.vs[i] = v[i] + kv * step_to;
            }
        }
        sys.acceleration(t + h, &self.xs, &self.vs, &mut self.a);
        let w = h / 6.0;
        for i in 0..n {
            next.x[i] = x[i] + (self.dx[i] + self.vs[i]) * w;
            next.v[i] = v[i] + (self.dv[i] + self.a[i]) * w;
        }
    }

    /// Any explicit Runge–Kutta method given by its tableau, with the embedded error estimate if it has one.
    fn tableau<S: OdeSystem<Coord = C> + ?Sized>(
        &mut self,
        sys: &mut S,
        t: f64,
        h: f64,
        now: &State<C>,
        next: &mut State<C>,
        tab: &Tableau,
    ) -> StepStats {
        let (x, v, n) = (&now.x[..], &now.v[..], self.n);
        for (s, row) in tab.a.iter().enumerate() {
            for i in 0..n {
                let (mut xs, mut vs) = (x[i], v[i]);
                for (j, &aij) in row.iter().enumerate() {
                    if aij != 0.0 {
                        xs += self.kx[j][i] * (h * aij);
                        vs += self.kv[j][i] * (h * aij);
                    }
                }
                self.xs[i] = xs;
                self.vs[i] = vs;
            }
            sys.acceleration(t + tab.c[s] * h, &self.xs, &self.vs, &mut self.kv[s]);
            self.kx[s].copy_from_slice(&self.vs);
        }
        let mut error = 0.0f64;
        for i in 0..n {
            let (mut xn, mut vn) = (x[i], v[i]);
            for (j, &bj) in tab.b.iter().enumerate() {
                if bj != 0.0 {
                    xn += self.kx[j][i] * (h * bj);
                    vn += self.kv[j][i] * (h * bj);
                }
            }
            next.x[i] = xn;
            next.v[i] = vn;
            if let Some(e) = tab.e {
                let (mut ex, mut ev) = (C::default(), C::default());
                for (j, &ej) in e.iter().enumerate() {
                    if ej != 0.0 {
                        ex += self.kx[j][i] * (h * ej);
                        ev += self.kv[j][i] * (h * ej);
                    }
                }
                error = error.max(ex.max_abs()).max(h * ev.max_abs());
            }
        }
        StepStats { evaluations: tab.c.len(), error: tab.e.map(|_| error), ..Default::default() }
    }

    /// Adams–Bashforth 4, or the PECE Adams–Bashforth–Moulton 4 pair; RK4 while the history fills.
    fn multistep<S: OdeSystem<Coord = C> + ?Sized>(
        &mut self,
        sys: &mut S,
        t: f64,
        h: f64,
        now: &State<C>,
        next: &mut State<C>,
    ) -> StepStats {
        let (x, v, n) = (&now.x[..], &now.v[..], self.n);
        let hist = self.history.as_mut().expect("allocated for multistep methods");
        if hist.len > 0 && hist.h != h {
            hist.len = 0;
        }
        hist.h = h;
        // Shift the history and put f_n = (v_n, a_n) in front.
        hist.v.rotate_right(1);
        hist.a.rotate_right(1);
        hist.v[0].copy_from_slice(v);
        sys.acceleration(t, x, v, &mut hist.a[0]);
        hist.len = (hist.len + 1).min(4);
        if hist.len < 4 {
            self.a.copy_from_slice(&self.history.as_ref().expect("present").a[0]);
            self.rk4_from_a(sys, t, h, now, next);
            return StepStats { evaluations: 4, ..Default::default() };
        }
        let w = h / 24.0;
        let (hv, ha) = (&hist.v, &hist.a);
        for i in 0..n {
            next.x[i] = x[i] + (hv[0][i] * 55.0 - hv[1][i] * 59.0 + hv[2][i] * 37.0 - hv[3][i] * 9.0) * w;
            next.v[i] = v[i] + (ha[0][i] * 55.0 - ha[1][i] * 59.0 + ha[2][i] * 37.0 - ha[3][i] * 9.0) * w;
        }
        if self.integrator == Integrator::AdamsBashforth4 {
            return StepStats { evaluations: 1, ..Default::default() };
        }
        // Evaluate at the prediction, then correct with Adams–Moulton.
        sys.acceleration(t + h, &next.x, &next.v, &mut self.a);
        let hist = self.history.as_ref().expect("present");
        let (hv, ha) = (&hist.v, &hist.a);
        for i in 0..n {
            let vp = next.v[i];
            next.x[i] = x[i] + (vp * 9.0 + hv[0][i] * 19.0 - hv[1][i] * 5.0 + hv[2][i]) * w;
            next.v[i] = v[i] + (self.a[i] * 9.0 + ha[0][i] * 19.0 - ha[1][i] * 5.0 + ha[2][i]) * w;
        }
        StepStats { evaluations: 2, ..Default::default() }
    }

    /// Forward Euler plus the thesis's error estimate h²/2·|f′| (Nedel 1993 §4.2.1), with f′ taken from
    /// the difference of f over the step: for the position rows f′ = a, for the velocity rows
    /// f′ ≈ (a(t + h) − a(t))/h. The error is reported in position units (velocity rows × h).
    fn adaptive_euler<S: OdeSystem<Coord = C> + ?Sized>(
        &mut self,
        sys: &mut S,
        t: f64,
        h: f64,
        now: &State<C>,
        next: &mut State<C>,
    ) -> StepStats {
        let (x, v, n) = (&now.x[..], &now.v[..], self.n);
        sys.acceleration(t, x, v, &mut self.a);
        for i in 0..n {
            next.x[i] = x[i] + v[i] * h;
            next.v[i] = v[i] + self.a[i] * h;
        }
        sys.acceleration(t + h, &next.x, &next.v, &mut self.vs);
        let mut fprime = 0.0f64;
        for i in 0..n {
            fprime = fprime.max(self.a[i].max_abs()).max((self.vs[i] - self.a[i]).max_abs());
        }
        StepStats { evaluations: 2, error: Some(0.5 * h * h * fprime), ..Default::default() }
    }
}
