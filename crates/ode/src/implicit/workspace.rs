//! Everything an implicit step keeps between calls: the system's blocks, the solvers' buffers and
//! caches, the methods' histories, and an optional profile of where the time went.

use std::time::Instant;

use crate::Coord;
use crate::stepper::{OdeError, State};

use super::alpha::AlphaState;
use super::cg::{BlockJacobi, CgBuffers, CgOutcome, pcg};
use super::contact::ContactState;
use super::system::{Filter, SystemMatrix};
use super::{Jacobians, LinearSolver};

/// Where the time of the implicit steps went, s (opt-in: [`crate::Stepper::set_profiling`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveProfile {
    /// Steps profiled.
    pub steps: usize,
    /// Newton iterations (each one force-and-Jacobian evaluation and one linear solve).
    pub newton_iterations: usize,
    /// Force and Jacobian evaluation and assembly of A.
    pub assembly_s: f64,
    /// Preconditioner or factorisation set-up (numeric factorisations).
    pub setup_s: f64,
    /// The linear solves themselves (CG iterations, triangular solves).
    pub solve_s: f64,
    /// Contact detection and the active-set logic.
    pub contact_s: f64,
    /// Linear-solver iterations (CG).
    pub solver_iterations: usize,
    /// Numeric factorisations (Cholesky, or the two-level preconditioner's refreshes).
    pub factorizations: usize,
}

/// Scratch and caches of the implicit methods.
#[derive(Debug, Clone)]
pub(crate) struct ImplicitWorkspace<C: Coord> {
    pub solver: LinearSolver,
    /// Newton iterations per step: 1 (backward Euler's default) is Baraff–Witkin's single linearisation;
    /// BDF2 defaults to 2, since one linearisation about the start of the step costs it its second order
    /// on stiff, damped springs (measured on the Oliveira sheet of `cargo xtask bench`); generalised-α
    /// to [`super::alpha::DEFAULT_NEWTON_ITERATIONS`].
    pub newton_iterations: usize,
    /// Generalised-α stops its Newton iterations early once an update contracts to this fraction of
    /// the one before ([`super::alpha::DEFAULT_NEWTON_CONTRACTION`]; 0 never stops early).
    pub newton_contraction: f64,
    /// Generalised-α with contacts: Newton iterations beyond the planned ones while contacts still
    /// change regime ([`super::alpha::DEFAULT_REGIME_ITERATIONS`]).
    pub regime_iterations: usize,
    pub(super) f: Vec<C>,
    pub(super) jac: Jacobians<C>,
    pub(super) a: SystemMatrix<C>,
    /// The spring form's diagonal beyond the masses ([`super::Linearized::spring_form_diagonal`]).
    pub(super) extra_diagonal: Vec<f64>,
    pub(super) b: Vec<C>,
    /// Δv, kept between steps as the next solve's first guess.
    pub(super) dv: Vec<C>,
    pub(super) cg: CgBuffers<C>,
    #[cfg(feature = "sparse-cholesky")]
    pub(super) direct: super::cholesky::DirectCache,
    #[cfg(feature = "sparse-cholesky")]
    pub(super) two_level: Option<super::two_level::TwoLevel<C>>,
    #[cfg(feature = "sparse-cholesky")]
    pub(super) aggregation: Option<super::aggregation::RigidAggregation<C>>,
    /// The positions the rigid-aggregation preconditioner takes its patches' rigid motions about (set
    /// by the step before its first solve), and whether its coarse matrix is to be rebuilt at the next
    /// solve (at the first solve of every step).
    pub(super) positions: Vec<C>,
    pub(super) coarse_stale: bool,
    /// Whether the rigid aggregation's smoothing is damped by its estimated largest eigenvalue
    /// ([`crate::Stepper::set_bounded_smoothing`]).
    pub bounded_smoothing: bool,
    /// BDF2 only: the state one step back, and the step that led from it (0 when there is none).
    pub(super) bdf2: Option<State<C>>,
    pub(super) prev_h: f64,
    /// Backward Euler and BDF2: x̂ − x₀ + β v₀ (the vector K multiplies on the right-hand side), then v̂.
    /// Generalised-α: the velocity at which the force is evaluated.
    pub(super) w: Vec<C>,
    /// Positions of the current Newton iterate.
    pub(super) xk: Vec<C>,
    /// Generalised-α only.
    pub(crate) alpha: Option<AlphaState<C>>,
    pub(crate) contact: ContactState<C>,
    /// Generalised-α's line search: the iterate before the step, and the Newton step.
    pub(super) trial: Vec<C>,
    pub(super) delta: Vec<C>,
    pub(crate) profile: Option<SolveProfile>,
}

impl<C: Coord> ImplicitWorkspace<C> {
    /// Backward Euler (`bdf2` false) or BDF2.
    pub fn new(n: usize, bdf2: bool) -> Self {
        let zeros = || vec![C::default(); n];
        Self {
            solver: LinearSolver::default_cg(),
            newton_iterations: if bdf2 { 2 } else { 1 },
            newton_contraction: 0.0,
            regime_iterations: 0,
            f: zeros(),
            jac: Jacobians::new(n, 0),
            a: SystemMatrix::new(),
            extra_diagonal: Vec::new(),
            b: zeros(),
            dv: zeros(),
            cg: CgBuffers::default(),
            #[cfg(feature = "sparse-cholesky")]
            direct: Default::default(),
            #[cfg(feature = "sparse-cholesky")]
            two_level: None,
            #[cfg(feature = "sparse-cholesky")]
            aggregation: None,
            positions: Vec::new(),
            coarse_stale: true,
            bounded_smoothing: true,
            bdf2: bdf2.then(|| State::zeros(n)),
            prev_h: 0.0,
            w: zeros(),
            xk: zeros(),
            alpha: None,
            contact: ContactState::new(),
            trial: Vec::new(),
            delta: Vec::new(),
            profile: None,
        }
    }

    /// Forgets the methods' histories: BDF2 restarts with a backward Euler step, generalised-α takes its
    /// acceleration from the force again.
    pub fn reset_history(&mut self) {
        self.prev_h = 0.0;
        if let Some(a) = &mut self.alpha {
            a.valid = false;
        }
        self.contact.forget();
    }

    /// Solves A δ = b (both filtered) into `self.dv` with the chosen solver, starting CG from the δ
    /// already there. Returns the solver's iterations (0 for the direct one). With `strict`, CG that
    /// stops short of its tolerance is an error (backward Euler's and BDF2's contract); otherwise the
    /// last iterate is used, which is what an inexact Newton iteration wants. A non-finite right-hand
    /// side or solution is an error ([`OdeError::NonFiniteSystem`]).
    pub(super) fn solve(
        &mut self,
        pattern: &[(u32, u32)],
        filter: Filter<'_, C>,
        masses: &[f64],
        prescribed: &[bool],
        strict: bool,
    ) -> Result<usize, OdeError> {
        // A force or a stiffness that overflowed would otherwise pass silently: CG's residual turns NaN,
        // every comparison with it is false, and the step returns δ = 0, a state frozen but finite.
        if !self.b.iter().all(|b| b.is_finite()) {
            return Err(OdeError::NonFiniteSystem);
        }
        let iterations = self.solve_finite(pattern, filter, masses, prescribed, strict)?;
        if !self.dv.iter().all(|d| d.is_finite()) {
            return Err(OdeError::NonFiniteSystem);
        }
        Ok(iterations)
    }

    #[cfg_attr(
        not(feature = "sparse-cholesky"),
        expect(unused_variables, reason = "the masses and the prescribed set serve the sparse solvers only")
    )]
    fn solve_finite(
        &mut self,
        pattern: &[(u32, u32)],
        filter: Filter<'_, C>,
        masses: &[f64],
        prescribed: &[bool],
        strict: bool,
    ) -> Result<usize, OdeError> {
        let started = self.profile.is_some().then(Instant::now);
        // When a preconditioner's set-up ended: the solve's time is counted from there.
        #[cfg_attr(
            not(feature = "sparse-cholesky"),
            expect(unused_mut, reason = "set by the sparse solvers only")
        )]
        let mut setup_done = None;
        filter.apply(&mut self.dv);
        self.a.filter_jacobi(filter);
        let outcome: CgOutcome = match self.solver {
            LinearSolver::ConjugateGradient { tolerance, max_iterations } => pcg(
                &self.a,
                pattern,
                filter,
                &mut BlockJacobi,
                &self.b,
                &mut self.dv,
                &mut self.cg,
                tolerance,
                max_iterations,
            ),
            #[cfg(feature = "sparse-cholesky")]
            LinearSolver::SparseCholesky => {
                let n = masses.len();
                let fits = self.direct.0.as_ref().is_some_and(|d| d.fits(n, pattern));
                if !fits {
                    self.direct.0 = Some(
                        super::cholesky::SparseSolver::new::<C>(n, pattern)
                            .map_err(|e| OdeError::Factorization(e.to_string()))?,
                    );
                }
                let direct = self.direct.0.as_mut().expect("built above");
                direct
                    .solve::<C>(&self.a.diag, &self.a.off, filter, &self.b, &mut self.dv)
                    .map_err(|e| OdeError::Factorization(e.to_string()))?;
                if let Some(p) = &mut self.profile {
                    p.factorizations += 1;
                }
                CgOutcome { iterations: 0, relative_residual: 0.0, converged: true }
            }
            #[cfg(feature = "sparse-cholesky")]
            LinearSolver::TwoLevel { tolerance, max_iterations } => {
                let two_level = self.two_level.get_or_insert_with(Default::default);
                let before = two_level.refactorizations;
                two_level.update(&self.a, pattern, masses, prescribed).map_err(OdeError::Factorization)?;
                let refreshed = two_level.refactorizations - before;
                setup_done = setup_ended(&mut self.profile, started, refreshed);
                pcg(
                    &self.a,
                    pattern,
                    filter,
                    two_level,
                    &self.b,
                    &mut self.dv,
                    &mut self.cg,
                    tolerance,
                    max_iterations,
                )
            }
            #[cfg(feature = "sparse-cholesky")]
            LinearSolver::RigidAggregation { tolerance, max_iterations } => {
                let agg = self.aggregation.get_or_insert_with(Default::default);
                agg.bounded = self.bounded_smoothing;
                if self.positions.len() != masses.len() {
                    // No positions given: the rotations turn about the origin, which still spans them.
                    self.positions.clear();
                    self.positions.resize(masses.len(), C::default());
                }
                // Once per step, and again whenever the contacts constrain other directions than those
                // the coarse matrix was built for.
                if self.coarse_stale || !agg.is_built() || agg.filter_changed(filter) {
                    agg.update(&self.a, pattern, masses, prescribed, &self.positions, filter)
                        .map_err(OdeError::Factorization)?;
                    self.coarse_stale = false;
                    if let Some(p) = &mut self.profile {
                        p.factorizations += 1;
                    }
                }
                setup_done = setup_ended(&mut self.profile, started, 0);
                pcg(
                    &self.a,
                    pattern,
                    filter,
                    agg,
                    &self.b,
                    &mut self.dv,
                    &mut self.cg,
                    tolerance,
                    max_iterations,
                )
            }
        };
        if let (Some(p), Some(s)) = (&mut self.profile, setup_done.or(started)) {
            p.solve_s += s.elapsed().as_secs_f64();
            p.solver_iterations += outcome.iterations;
        }
        finish(outcome, strict)
    }
}

/// Ends a preconditioner's set-up that began at `started`: adds its time and `factorizations` to the
/// profile, and returns when it ended (`None` when not profiling).
#[cfg(feature = "sparse-cholesky")]
fn setup_ended(
    profile: &mut Option<SolveProfile>,
    started: Option<Instant>,
    factorizations: usize,
) -> Option<Instant> {
    let (p, s) = (profile.as_mut()?, started?);
    let done = Instant::now();
    p.setup_s += (done - s).as_secs_f64();
    p.factorizations += factorizations;
    Some(done)
}

fn finish(outcome: CgOutcome, strict: bool) -> Result<usize, OdeError> {
    if strict && !outcome.converged {
        return Err(OdeError::SolverDidNotConverge {
            iterations: outcome.iterations,
            residual: outcome.relative_residual,
        });
    }
    Ok(outcome.iterations)
}
