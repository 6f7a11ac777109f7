//! The two linear solvers of implicit Euler — conjugate gradients and faer's sparse Cholesky — solve the
//! same system; the direct one keeps prescribed coordinates exact and survives an indefinite matrix.

use anima_ode::{Integrator, Jacobians, LinearSolver, Linearized, OdeSystem, SavedHistory, State, Stepper};
use glam::{DMat3, DVec3};

/// A chain of particles joined by linear springs, the first one pinned, under gravity: exact spring
/// Jacobians (stretched springs, so K is negative semi-definite).
struct Chain {
    rest: f64,
    k: f64,
    c: f64,
    gravity: f64,
    masses: Vec<f64>,
    prescribed: Vec<bool>,
    pattern: Vec<(u32, u32)>,
}

impl Chain {
    fn new(n: usize) -> Self {
        let masses = (0..n).map(|i| 0.01 * (1.0 + (i % 3) as f64)).collect();
        let mut prescribed = vec![false; n];
        prescribed[0] = true;
        let pattern = (0..n as u32 - 1).map(|i| (i, i + 1)).collect();
        Self { rest: 0.1, k: 500.0, c: 0.2, gravity: 9.81, masses, prescribed, pattern }
    }
}

impl Linearized<DVec3> for Chain {
    fn masses(&self) -> &[f64] {
        &self.masses
    }
    fn prescribed(&self) -> &[bool] {
        &self.prescribed
    }
    fn pattern(&self) -> &[(u32, u32)] {
        &self.pattern
    }
    fn force_and_jacobians(
        &mut self,
        _t: f64,
        x: &[DVec3],
        v: &[DVec3],
        f: &mut [DVec3],
        jac: &mut Jacobians<DVec3>,
    ) {
        for (fi, &m) in f.iter_mut().zip(&self.masses) {
            *fi = DVec3::new(0.0, -self.gravity * m, 0.0);
        }
        for (e, &(i, j)) in self.pattern.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let d = x[j] - x[i];
            let len = d.length();
            let u = d / len;
            let force = u * (self.k * (len - self.rest)) + u * (self.c * (v[j] - v[i]).dot(u));
            f[i] += force;
            f[j] -= force;
            let uu = DMat3::from_cols(u * u.x, u * u.y, u * u.z);
            let geometric = (DMat3::IDENTITY - uu) * (1.0 - self.rest / len).max(0.0);
            let kb = (uu + geometric) * -self.k;
            let db = uu * -self.c;
            jac.k_diag[i] += kb;
            jac.k_diag[j] += kb;
            jac.k_off[e] -= kb;
            jac.d_diag[i] += db;
            jac.d_diag[j] += db;
            jac.d_off[e] -= db;
        }
    }
}

impl OdeSystem for Chain {
    type Coord = DVec3;
    fn n_coords(&self) -> usize {
        self.masses.len()
    }
    /// Only generalised-α calls this, for its starting acceleration.
    fn acceleration(&mut self, t: f64, x: &[DVec3], v: &[DVec3], a: &mut [DVec3]) {
        let mut jac = Jacobians::new(x.len(), self.pattern.len());
        self.force_and_jacobians(t, x, v, a, &mut jac);
        for ((a, m), &fixed) in a.iter_mut().zip(&self.masses).zip(&self.prescribed) {
            *a = if fixed { DVec3::ZERO } else { *a / *m };
        }
    }
    fn linearized(&mut self) -> Option<&mut dyn Linearized<DVec3>> {
        Some(self)
    }
}

fn start(n: usize) -> State<DVec3> {
    let mut s = State::new(vec![DVec3::ZERO; n], vec![DVec3::ZERO; n]);
    for i in 0..n {
        let t = i as f64;
        s.x[i] = DVec3::new(0.12 * t, -0.01 * t * t, 0.02 * (t * 0.7).sin());
        s.v[i] = DVec3::new(0.0, -0.1 * (t * 0.3).cos(), 0.05);
    }
    s.v[0] = DVec3::new(0.3, 0.0, 0.0); // a moving pin
    s
}

fn run(solver: LinearSolver, n: usize, steps: usize, h: f64) -> State<DVec3> {
    let mut chain = Chain::new(n);
    let mut stepper = Stepper::new(Integrator::ImplicitEuler, n);
    stepper.set_linear_solver(solver);
    let mut now = start(n);
    let mut next = now.clone();
    for s in 0..steps {
        stepper.step(&mut chain, s as f64 * h, h, &now, &mut next).expect("step");
        std::mem::swap(&mut now, &mut next);
    }
    now
}

#[test]
fn cholesky_and_conjugate_gradients_give_the_same_steps() {
    let (n, steps, h) = (40, 30, 1.0 / 60.0);
    let cg = run(LinearSolver::ConjugateGradient { tolerance: 1e-13, max_iterations: 10_000 }, n, steps, h);
    let direct = run(LinearSolver::SparseCholesky, n, steps, h);
    let scale = cg.x.iter().map(|p| p.length()).fold(0.0, f64::max);
    let worst = cg.x.iter().zip(&direct.x).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    assert!(worst <= 1e-9 * scale, "positions differ by {worst:e} (scale {scale})");
    // The chain did move: the comparison is not between two copies of the start.
    let moved = start(n).x.iter().zip(&direct.x).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    assert!(moved > 1e-2, "moved only {moved}");
}

/// The two preconditioned CG solvers that keep factorisations (the scalar two-level one, with its
/// hand-written three-component triangular solve, and the rigid-aggregation one) converge to the steps
/// of the direct solver when their tolerance is tight.
#[test]
fn two_level_and_aggregation_solves_give_the_cholesky_steps() {
    let (n, steps, h) = (40, 30, 1.0 / 60.0);
    let direct = run(LinearSolver::SparseCholesky, n, steps, h);
    let scale = direct.x.iter().map(|p| p.length()).fold(0.0, f64::max);
    for solver in [
        LinearSolver::TwoLevel { tolerance: 1e-13, max_iterations: 10_000 },
        LinearSolver::RigidAggregation { tolerance: 1e-13, max_iterations: 10_000 },
    ] {
        let it = run(solver, n, steps, h);
        let worst = it.x.iter().zip(&direct.x).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
        assert!(worst <= 1e-9 * scale, "{}: positions differ by {worst:e} (scale {scale})", solver.name());
        assert_eq!(it.v[0], DVec3::new(0.3, 0.0, 0.0), "{}: the pin's velocity", solver.name());
    }
}

/// Generalised-α with the rigid-aggregation solve (its default) converges with its Newton iterations to
/// the step the direct solver gives.
#[test]
fn generalized_alpha_with_aggregation_converges_to_the_direct_step() {
    let (n, h) = (40, 1.0 / 60.0);
    let step = |solver: LinearSolver| {
        let mut chain = Chain::new(n);
        let mut stepper = Stepper::new(Integrator::GeneralizedAlpha, n);
        stepper.set_linear_solver(solver);
        stepper.set_newton_iterations(12);
        let (mut now, mut next) = (start(n), start(n));
        for s in 0..10 {
            stepper.step(&mut chain, s as f64 * h, h, &now, &mut next).expect("step");
            std::mem::swap(&mut now, &mut next);
        }
        now
    };
    let direct = step(LinearSolver::SparseCholesky);
    let agg = step(LinearSolver::RigidAggregation { tolerance: 1e-12, max_iterations: 10_000 });
    let worst = agg.x.iter().zip(&direct.x).map(|(a, b)| (*a - *b).length()).fold(0.0, f64::max);
    assert!(worst < 1e-8, "positions differ by {worst:e}");
}

#[test]
fn cholesky_keeps_a_prescribed_velocity_exactly() {
    let (n, steps, h) = (10, 20, 1.0 / 30.0);
    let end = run(LinearSolver::SparseCholesky, n, steps, h);
    assert_eq!(end.v[0], DVec3::new(0.3, 0.0, 0.0));
    let x0 = start(n).x[0] + DVec3::new(0.3, 0.0, 0.0) * (h * steps as f64);
    assert!((end.x[0] - x0).length() < 1e-12);
}

/// Two scalar coordinates with a destabilising (positive) stiffness: A = M − h²K is symmetric and
/// indefinite, so LLᵀ must fail and LDLᵀ solve it.
struct AntiSpring {
    masses: [f64; 2],
    prescribed: [bool; 2],
    pattern: [(u32, u32); 1],
}

impl Linearized<f64> for AntiSpring {
    fn masses(&self) -> &[f64] {
        &self.masses
    }
    fn prescribed(&self) -> &[bool] {
        &self.prescribed
    }
    fn pattern(&self) -> &[(u32, u32)] {
        &self.pattern
    }
    fn force_and_jacobians(
        &mut self,
        _t: f64,
        _x: &[f64],
        _v: &[f64],
        f: &mut [f64],
        jac: &mut Jacobians<f64>,
    ) {
        f[0] = 1.0;
        f[1] = -2.0;
        jac.k_diag[0] = 3.0;
        jac.k_diag[1] = 0.0;
        jac.k_off[0] = 0.5;
    }
}

impl OdeSystem for AntiSpring {
    type Coord = f64;
    fn n_coords(&self) -> usize {
        2
    }
    fn acceleration(&mut self, _t: f64, _x: &[f64], _v: &[f64], _a: &mut [f64]) {
        unreachable!()
    }
    fn linearized(&mut self) -> Option<&mut dyn Linearized<f64>> {
        Some(self)
    }
}

#[test]
fn an_indefinite_system_falls_back_to_ldlt_and_is_solved_exactly() {
    let mut sys = AntiSpring { masses: [1.0, 1.0], prescribed: [false; 2], pattern: [(0, 1)] };
    let mut stepper = Stepper::new(Integrator::ImplicitEuler, 2);
    stepper.set_linear_solver(LinearSolver::SparseCholesky);
    let mut now = State::new(vec![0.0; 2], vec![0.0; 2]);
    now.v = vec![0.5, -1.0];
    let mut next = now.clone();
    let h = 1.0;
    stepper.step(&mut sys, 0.0, h, &now, &mut next).expect("LDLᵀ solves an indefinite system");
    // A = [[1 − 3, −0.5], [−0.5, 1]], b = h (f + h K v) = [1 + 1.5 − 0.5, −2 + 0.25].
    let (a, b, d) = (-2.0, -0.5, 1.0);
    let (r0, r1) = (2.0, -1.75);
    let det = a * d - b * b;
    let dv = [(d * r0 - b * r1) / det, (a * r1 - b * r0) / det];
    for (k, (v1, (v0, d))) in next.v.iter().zip(now.v.iter().zip(dv)).enumerate() {
        assert!((v1 - (v0 + d)).abs() < 1e-12, "v[{k}] = {v1}");
    }
}

#[test]
fn solver_names_parse() {
    assert_eq!("cholesky".parse::<LinearSolver>(), Ok(LinearSolver::SparseCholesky));
    assert_eq!("cg".parse::<LinearSolver>(), Ok(LinearSolver::default_cg()));
    assert_eq!("two-level".parse::<LinearSolver>(), Ok(LinearSolver::default_two_level()));
    assert_eq!("aggregation".parse::<LinearSolver>(), Ok(LinearSolver::default_aggregation()));
    assert!(
        "lu".parse::<LinearSolver>()
            .unwrap_err()
            .contains("expected `cg`, `cholesky`, `two-level` or `aggregation`")
    );
    for s in [
        LinearSolver::SparseCholesky,
        LinearSolver::default_cg(),
        LinearSolver::default_two_level(),
        LinearSolver::default_aggregation(),
    ] {
        assert_eq!(s.name().parse::<LinearSolver>(), Ok(s));
    }
}

/// Residual of the backward Euler equations M (v₁ − v₀) − h f(x₀ + h v₁, v₁) over the free particles.
fn backward_euler_residual(chain: &mut Chain, now: &State<DVec3>, next: &State<DVec3>, h: f64) -> f64 {
    let n = now.len();
    let mut f = vec![DVec3::ZERO; n];
    let mut jac = Jacobians::new(n, chain.pattern.len());
    chain.force_and_jacobians(0.0, &next.x, &next.v, &mut f, &mut jac);
    (1..n).map(|i| ((next.v[i] - now.v[i]) * chain.masses[i] - f[i] * h).length()).fold(0.0, f64::max)
}

#[test]
fn newton_iterations_converge_to_the_nonlinear_step() {
    let (n, h) = (30, 1.0 / 30.0);
    let residual = |iterations: usize| {
        let mut chain = Chain::new(n);
        let mut stepper = Stepper::new(Integrator::ImplicitEuler, n);
        stepper.set_linear_solver(LinearSolver::SparseCholesky);
        stepper.set_newton_iterations(iterations);
        let now = start(n);
        let mut next = now.clone();
        stepper.step(&mut chain, 0.0, h, &now, &mut next).expect("step");
        backward_euler_residual(&mut chain, &now, &next, h)
    };
    let r: Vec<f64> = (1..=5).map(residual).collect();
    // The damping force's dependence on x is left out of K, so convergence is linear, not quadratic:
    // each iteration must still cut the residual at least tenfold.
    for w in r.windows(2) {
        assert!(w[1] < 0.1 * w[0], "residuals after 1..5 Newton iterations: {r:?}");
    }
    assert!(r[4] < 1e-6 * r[0], "residuals after 1..5 Newton iterations: {r:?}");
}

/// A 30-particle chain and its stepper after five steps of `h`, and the state they reached.
fn after_five_steps(integrator: Integrator, h: f64) -> (Chain, Stepper<DVec3>, State<DVec3>) {
    let n = 30;
    let mut chain = Chain::new(n);
    let mut stepper = Stepper::new(integrator, n);
    let mut now = start(n);
    let mut next = now.clone();
    for s in 0..5 {
        stepper.step(&mut chain, s as f64 * h, h, &now, &mut next).expect("step");
        std::mem::swap(&mut now, &mut next);
    }
    (chain, stepper, now)
}

/// A cloned generalised-α stepper (whose preconditioner keeps a factorisation made before the clone)
/// steps exactly as the original.
#[test]
fn a_cloned_generalized_alpha_stepper_steps_identically() {
    let h = 1.0 / 60.0;
    let (mut chain, mut stepper, now) = after_five_steps(Integrator::GeneralizedAlpha, h);
    let mut twin = stepper.clone();
    let (mut a, mut b) = (now.clone(), now.clone());
    let (mut a_next, mut b_next) = (now.clone(), now);
    for s in 5..15 {
        stepper.step(&mut chain, s as f64 * h, h, &a, &mut a_next).expect("step");
        twin.step(&mut chain, s as f64 * h, h, &b, &mut b_next).expect("step");
        std::mem::swap(&mut a, &mut a_next);
        std::mem::swap(&mut b, &mut b_next);
    }
    assert_eq!(a, b);
}

/// A discarded step leaves no trace once the history saved before it is put back: the step taken
/// again is the first one to the bit, in whole and in halves alike; without the restore, generalised-α
/// carries the discarded step's acceleration into the retry.
#[test]
fn a_step_taken_again_after_restoring_the_history_is_the_same_step() {
    let h = 1.0 / 60.0;
    let (mut chain, mut stepper, now) = after_five_steps(Integrator::GeneralizedAlpha, h);
    let mut saved = SavedHistory::default();
    stepper.save_history(&mut saved);
    let mut halves = stepper.clone();
    let (mut first, mut half, mut mid) = (now.clone(), now.clone(), now.clone());
    stepper.step(&mut chain, 5.0 * h, h, &now, &mut first).expect("step");
    halves.step(&mut chain, 5.0 * h, 0.5 * h, &now, &mut mid).expect("step");
    halves.step(&mut chain, 5.5 * h, 0.5 * h, &mid, &mut half).expect("step");
    // Without the restore the retry differs.
    let mut again = now.clone();
    let mut unrestored = stepper.clone();
    unrestored.step(&mut chain, 5.0 * h, h, &now, &mut again).expect("step");
    assert_ne!(again, first, "the history made no difference");
    // Restored, it is the same step; and the same two halves.
    stepper.restore_history(&saved);
    stepper.step(&mut chain, 5.0 * h, h, &now, &mut again).expect("step");
    assert_eq!(again, first);
    stepper.restore_history(&saved);
    let mut again_mid = now.clone();
    stepper.step(&mut chain, 5.0 * h, 0.5 * h, &now, &mut again_mid).expect("step");
    stepper.step(&mut chain, 5.5 * h, 0.5 * h, &again_mid, &mut again).expect("step");
    assert_eq!(again, half);
}

/// BDF2 keeps the state one step back, which a discarded step has moved onto the start itself: after
/// the restore it starts again with a backward Euler step, as after a reset, not with BDF2 on two equal
/// states.
#[test]
fn bdf2_starts_again_after_a_discarded_step() {
    let h = 1.0 / 60.0;
    let (mut chain, mut stepper, now) = after_five_steps(Integrator::Bdf2, h);
    let mut saved = SavedHistory::default();
    stepper.save_history(&mut saved);
    let mut fresh = stepper.clone();
    fresh.reset_history();
    let mut restarted = now.clone();
    fresh.step(&mut chain, 5.0 * h, h, &now, &mut restarted).expect("step");
    let mut discarded = now.clone();
    stepper.step(&mut chain, 5.0 * h, h, &now, &mut discarded).expect("step");
    let apart = |a: &State<DVec3>, b: &State<DVec3>| {
        a.x.iter().zip(&b.x).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max)
    };
    let bdf2_vs_euler = apart(&discarded, &restarted);
    stepper.restore_history(&saved);
    let mut again = now.clone();
    stepper.step(&mut chain, 5.0 * h, h, &now, &mut again).expect("step");
    // Not to the bit: conjugate gradients starts from the last solve's update, the discarded step's.
    let off = apart(&again, &restarted);
    assert!(off < 1e-6 * bdf2_vs_euler, "{off} m from the restarted step, BDF2 is {bdf2_vs_euler} m from it");
}

/// Under a gravity of 1e200 the pinned chain's springs overflow after one step (a length of 1e196
/// squares to infinity) and the force turns NaN. Every implicit integrator with every solver must say so
/// at that step, not return a frozen, finite state: before the check, CG's NaN residual compared false
/// with its tolerance and the step came back with δ = 0.
#[test]
fn an_overflowing_force_is_an_error_not_a_frozen_state() {
    let solvers = [
        LinearSolver::default_cg(),
        LinearSolver::SparseCholesky,
        LinearSolver::default_two_level(),
        LinearSolver::default_aggregation(),
    ];
    for integrator in [Integrator::ImplicitEuler, Integrator::Bdf2, Integrator::GeneralizedAlpha] {
        for solver in solvers {
            let n = 8;
            let mut chain = Chain::new(n);
            chain.gravity = 1e200;
            let mut stepper = Stepper::new(integrator, n);
            stepper.set_linear_solver(solver);
            let mut now = start(n);
            let mut next = now.clone();
            let mut failed_at = None;
            for s in 0..10 {
                match stepper.step(&mut chain, s as f64 * 0.01, 0.01, &now, &mut next) {
                    Ok(_) if next.first_non_finite().is_some() => {
                        failed_at = Some(s);
                        break;
                    }
                    Ok(_) => std::mem::swap(&mut now, &mut next),
                    Err(e) => {
                        assert!(
                            matches!(e, anima_ode::OdeError::NonFiniteSystem),
                            "{integrator} with {}: {e}",
                            solver.name()
                        );
                        failed_at = Some(s);
                        break;
                    }
                }
            }
            let failed_at = failed_at.unwrap_or_else(|| {
                panic!(
                    "{integrator} with {} ran 10 steps under 1e200 gravity and said nothing",
                    solver.name()
                )
            });
            assert!(failed_at <= 2, "{integrator} with {}: noticed only at step {failed_at}", solver.name());
        }
    }
}

/// Generalised-α's default Newton count stops early once the updates contract; a count set by hand
/// runs in full.
#[test]
fn generalized_alpha_stops_newton_early_only_by_default() {
    let (n, h, steps) = (40, 1.0 / 60.0, 10);
    let newton_per_step = |set: Option<usize>| {
        let mut chain = Chain::new(n);
        let mut stepper = Stepper::new(Integrator::GeneralizedAlpha, n);
        if let Some(k) = set {
            stepper.set_newton_iterations(k);
        }
        stepper.set_profiling(true);
        let (mut now, mut next) = (start(n), start(n));
        for s in 0..steps {
            stepper.step(&mut chain, s as f64 * h, h, &now, &mut next).expect("step");
            std::mem::swap(&mut now, &mut next);
        }
        let p = stepper.profile().expect("profiled");
        p.newton_iterations as f64 / p.steps as f64
    };
    let default = newton_per_step(None);
    assert!((2.0..3.0).contains(&default), "{default} Newton iterations per step by default");
    assert_eq!(newton_per_step(Some(3)), 3.0);
}

/// A stepper resized for a new mesh keeps its profile's sums, so that a remeshed run is timed whole.
#[test]
fn a_resized_stepper_keeps_its_profile() {
    let (n, h) = (12, 1.0 / 60.0);
    let mut chain = Chain::new(n);
    let mut stepper = Stepper::new(Integrator::GeneralizedAlpha, n);
    stepper.set_profiling(true);
    let (now, mut next) = (start(n), start(n));
    stepper.step(&mut chain, 0.0, h, &now, &mut next).expect("step");
    let before = stepper.profile().expect("profiled");
    assert_eq!(before.steps, 1);
    let resized = stepper.resized(n + 3);
    let after = resized.profile().expect("still profiled");
    assert_eq!((after.steps, after.newton_iterations), (before.steps, before.newton_iterations));
}
