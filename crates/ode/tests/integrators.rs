//! Convergence orders, energy behaviour, stability intervals and step control of every integrator, on
//! the FLEX3D Table 4.1 spring (x'' = −(x − 2), x(0) = 4, v(0) = 0; exact x = 2 + 2 cos t). The spring
//! is linear, so one Newton step solves the implicit methods' equations exactly and their observed
//! orders are the methods' own.

use anima_ode::stability::{damped_stability_limit, stability_limit};
use anima_ode::{
    IntegrationError, IntegrationStats, Integrator, OdeSystem, SingleSpring, State, StepControl, Stepper,
    integrate,
};

/// The spring from x = 4, v = 0 integrated from 0 to `t_end` by a fresh stepper of `integrator` under
/// `control`, `observe` called after every step: the state reached and the run's outcome.
fn run_spring(
    integrator: Integrator,
    control: StepControl,
    t_end: f64,
    observe: impl FnMut(f64, &State<f64>),
) -> (State<f64>, Result<IntegrationStats, IntegrationError>) {
    let mut st = Stepper::new(integrator, 1);
    let mut now = State::new(vec![4.0], vec![0.0]);
    let mut scratch = State::zeros(1);
    let outcome =
        integrate(&mut SingleSpring::thesis(), &mut st, control, 0.0, t_end, &mut now, &mut scratch, observe);
    (now, outcome)
}

/// Error of the state (x, v) at t_end for constant step h, against x = 2 + 2 cos t, v = −2 sin t.
fn error(integrator: Integrator, h: f64, t_end: f64) -> f64 {
    let (now, outcome) = run_spring(integrator, StepControl::Constant { dt: h }, t_end, |_, _| {});
    outcome.unwrap();
    (now.x[0] - (2.0 + 2.0 * t_end.cos())).hypot(now.v[0] + 2.0 * t_end.sin())
}

/// Observed orders from three step sizes h, h/2, h/4.
fn observed_orders(integrator: Integrator, h: f64) -> [f64; 2] {
    let e = [error(integrator, h, 2.0), error(integrator, h / 2.0, 2.0), error(integrator, h / 4.0, 2.0)];
    [(e[0] / e[1]).log2(), (e[1] / e[2]).log2()]
}

#[test]
fn convergence_orders_from_three_step_sizes() {
    for (integrator, h, order) in [
        (Integrator::ForwardEuler, 0.01, 1.0),
        (Integrator::SymplecticEuler, 0.01, 1.0),
        (Integrator::Midpoint, 0.01, 2.0),
        (Integrator::Rk4, 0.05, 4.0),
        (Integrator::AdamsBashforth4, 0.02, 4.0),
        (Integrator::AdamsBashforthMoulton4, 0.02, 4.0),
        (Integrator::DormandPrince, 0.1, 5.0),
        (Integrator::ImplicitEuler, 0.01, 1.0),
        (Integrator::Bdf2, 0.01, 2.0),
        (Integrator::GeneralizedAlpha, 0.01, 2.0),
    ] {
        let observed = observed_orders(integrator, h);
        for p in observed {
            assert!((p - order).abs() <= 0.2, "{integrator}: observed orders {observed:?}, expected {order}");
        }
    }
}

/// Energy of the unit-stiffness, unit-mass spring about its rest length.
fn energy(s: &State<f64>) -> f64 {
    0.5 * s.v[0] * s.v[0] + 0.5 * (s.x[0] - 2.0) * (s.x[0] - 2.0)
}

#[test]
fn symplectic_euler_keeps_energy_bounded_and_forward_euler_does_not() {
    let run = |integrator| {
        let mut worst = 0.0f64;
        let (now, outcome) = run_spring(integrator, StepControl::Constant { dt: 0.05 }, 5000.0, |_, s| {
            worst = worst.max((energy(s) - 2.0).abs() / 2.0)
        });
        outcome.unwrap();
        (worst, energy(&now))
    };
    let (drift, _) = run(Integrator::SymplecticEuler);
    assert!(drift < 0.03, "symplectic Euler energy drifted by {drift} over 1e5 steps");
    let (_, last) = run(Integrator::ForwardEuler);
    assert!(last > 2.0 * 1e10, "forward Euler must gain energy: {last}");
}

/// Damping narrows symplectic Euler's interval to exactly 2(√(1 + ζ²) − ζ) (its step matrix on
/// x'' = −ω²x − 2ζωx' has trace 2 − (hω)² − 2ζhω and determinant 1 − 2ζhω), and widens forward
/// Euler's from nothing to about 2ζ.
#[test]
fn damping_moves_the_stability_limits() {
    for zeta in [0.1f64, 0.3, 0.7, 1.5] {
        let exact = 2.0 * ((1.0 + zeta * zeta).sqrt() - zeta);
        let measured = damped_stability_limit(Integrator::SymplecticEuler, zeta);
        assert!((measured - exact).abs() < 2e-3, "ζ = {zeta}: {measured} against {exact}");
        let forward = damped_stability_limit(Integrator::ForwardEuler, zeta);
        assert!(forward > 0.5 * zeta && forward <= 2.0 * zeta + 2e-3, "ζ = {zeta}: forward Euler {forward}");
    }
    assert_eq!(
        damped_stability_limit(Integrator::SymplecticEuler, 0.0),
        stability_limit(Integrator::SymplecticEuler)
    );
}

#[test]
fn measured_stability_intervals_on_the_imaginary_axis() {
    // Known values: symplectic Euler 2, RK4 2√2; forward Euler and midpoint grow at every step.
    assert!((stability_limit(Integrator::SymplecticEuler) - 2.0).abs() < 2e-3);
    assert!((stability_limit(Integrator::Rk4) - 8f64.sqrt()).abs() < 2e-3);
    assert_eq!(stability_limit(Integrator::ForwardEuler), 0.0);
    assert_eq!(stability_limit(Integrator::AdaptiveEuler), 0.0);
    // Midpoint grows by y⁴/8 per step: 10⁻⁶ per radian is reached at y = 0.02.
    let midpoint = stability_limit(Integrator::Midpoint);
    assert!((0.015..0.025).contains(&midpoint), "midpoint {midpoint}");
    // AB4's interval ends at 0.43; Dormand–Prince's just below 1.
    assert!((stability_limit(Integrator::AdamsBashforth4) - 0.43).abs() < 0.01);
    let dopri = stability_limit(Integrator::DormandPrince);
    assert!((0.9..1.0).contains(&dopri), "dopri5 {dopri}");
    let abm4 = stability_limit(Integrator::AdamsBashforthMoulton4);
    assert!(abm4 > 0.0 && abm4 < 0.43, "ABM4 PECE grows slowly on the imaginary axis: {abm4}");
}

/// The position error |x − (2 + 2 cos t_end)| of a run to `t_end` under step control to `tolerance`
/// (first step 0.1, steps from `dt_min` to 1), and the run's statistics.
fn adaptive_position_error(
    integrator: Integrator,
    tolerance: f64,
    dt_min: f64,
    t_end: f64,
) -> (f64, IntegrationStats) {
    let control = StepControl::Adaptive { tolerance, dt_initial: 0.1, dt_min, dt_max: 1.0 };
    let (now, outcome) = run_spring(integrator, control, t_end, |_, _| {});
    let stats = outcome.unwrap();
    ((now.x[0] - (2.0 + 2.0 * t_end.cos())).abs(), stats)
}

#[test]
fn embedded_control_meets_its_tolerance_with_fewer_steps_when_looser() {
    let run = |tol: f64| adaptive_position_error(Integrator::DormandPrince, tol, 1e-6, 10.0);
    let (e_tight, s_tight) = run(1e-10);
    let (e_loose, s_loose) = run(1e-5);
    assert!(e_tight < 1e-7, "global error {e_tight} at tolerance 1e-10");
    assert!(e_loose < 1e-2 && e_loose > e_tight, "global error {e_loose} at tolerance 1e-5");
    assert!(s_loose.steps < s_tight.steps, "{} vs {} steps", s_loose.steps, s_tight.steps);
}

#[test]
fn thesis_adaptive_euler_takes_smaller_steps_for_a_tighter_error() {
    let run = |tol: f64| adaptive_position_error(Integrator::AdaptiveEuler, tol, 1e-7, 2.0);
    let (e1, s1) = run(1e-4);
    let (e2, s2) = run(1e-6);
    // h ∝ √tol, so 100× tighter means about 10× the steps and 10× less error (first order).
    let ratio = s2.steps as f64 / s1.steps as f64;
    assert!((7.0..14.0).contains(&ratio), "steps {} → {}", s1.steps, s2.steps);
    assert!(e2 < e1 / 5.0, "error {e1} → {e2}");
}

#[test]
fn non_finite_state_is_reported_with_its_step() {
    struct Blowup;
    impl OdeSystem for Blowup {
        type Coord = f64;
        fn n_coords(&self) -> usize {
            2
        }
        fn acceleration(&mut self, t: f64, _x: &[f64], _v: &[f64], a: &mut [f64]) {
            a[0] = 0.0;
            a[1] = if t >= 0.5 { f64::INFINITY } else { 1.0 };
        }
    }
    let mut st = Stepper::new(Integrator::ForwardEuler, 2);
    let mut now = State::zeros(2);
    let mut scratch = State::zeros(2);
    let err = integrate(
        &mut Blowup,
        &mut st,
        StepControl::Constant { dt: 0.1 },
        0.0,
        1.0,
        &mut now,
        &mut scratch,
        |_, _| {},
    )
    .unwrap_err();
    assert_eq!(
        err,
        anima_ode::IntegrationError::NonFinite { step: 6, time: 0.6000000000000001, coordinate: 1 }
    );
}

#[test]
fn implicit_methods_refuse_a_system_without_jacobians() {
    struct Plain;
    impl OdeSystem for Plain {
        type Coord = f64;
        fn n_coords(&self) -> usize {
            1
        }
        fn acceleration(&mut self, _t: f64, x: &[f64], _v: &[f64], a: &mut [f64]) {
            a[0] = -x[0];
        }
    }
    for integrator in [Integrator::ImplicitEuler, Integrator::Bdf2, Integrator::GeneralizedAlpha] {
        let mut st = Stepper::new(integrator, 1);
        let now = State::new(vec![4.0], vec![0.0]);
        let mut next = State::zeros(1);
        assert!(st.step(&mut Plain, 0.0, 0.1, &now, &mut next).is_err());
    }
}

/// BDF2 damps an undamped oscillator far less than backward Euler at the same step: after 10 periods at
/// 20 steps per period, backward Euler has lost most of the amplitude, BDF2 little.
#[test]
fn bdf2_damps_less_than_backward_euler() {
    let amplitude = |integrator| {
        let t_end = 20.0 * std::f64::consts::PI;
        let h = 2.0 * std::f64::consts::PI / 20.0;
        let (now, outcome) = run_spring(integrator, StepControl::Constant { dt: h }, t_end, |_, _| {});
        outcome.unwrap();
        (now.x[0] - 2.0).hypot(now.v[0]) / 2.0
    };
    let (be, bdf2) = (amplitude(Integrator::ImplicitEuler), amplitude(Integrator::Bdf2));
    assert!(be < 0.2, "backward Euler kept {be} of the amplitude");
    assert!(bdf2 > 0.5 && bdf2 < 1.0, "BDF2 kept {bdf2} of the amplitude");
}

#[test]
fn step_warning_fires_beyond_the_stability_limit_only() {
    use anima_ode::stability::check_step;
    assert!(check_step(Integrator::SymplecticEuler, 1.9, 1.0).is_none());
    let w = check_step(Integrator::SymplecticEuler, 2.1, 1.0).expect("beyond 2/ω");
    assert!(w.contains("exceeds the stable step"), "{w}");
    assert!(check_step(Integrator::ImplicitEuler, 100.0, 1.0).is_none());
}

#[test]
fn controller_stops_when_the_smallest_step_cannot_meet_the_tolerance() {
    let control = StepControl::Adaptive { tolerance: 1e-14, dt_initial: 0.5, dt_min: 0.1, dt_max: 1.0 };
    let err = run_spring(Integrator::DormandPrince, control, 10.0, |_, _| {}).1.unwrap_err();
    assert!(matches!(err, anima_ode::IntegrationError::StepTooSmall { dt, .. } if dt == 0.1), "{err}");
}

/// Energy of the spring after `steps` steps of `h` with generalised-α at spectral radius `rho`, and the
/// largest relative energy gain seen on the way.
fn alpha_energy(rho: f64, h: f64, steps: usize) -> (f64, f64) {
    let mut st = Stepper::new(Integrator::GeneralizedAlpha, 1);
    st.set_spectral_radius(rho);
    let mut now = State::new(vec![4.0], vec![0.0]);
    let mut next = State::zeros(1);
    let e0 = energy(&now);
    let mut gain = 0.0f64;
    for k in 0..steps {
        st.step(&mut SingleSpring::thesis(), k as f64 * h, h, &now, &mut next).unwrap();
        std::mem::swap(&mut now, &mut next);
        gain = gain.max((energy(&now) - e0) / e0);
    }
    (energy(&now) / e0, gain)
}

/// The undamped oscillator over 10⁴ steps of h ω = 0.1: generalised-α never gains energy; with the default
/// ρ∞ it keeps most of it (its low-frequency damping is of third order in h ω), and at ρ∞ = 1 (the
/// implicit midpoint rule) it keeps all of it to round-off.
#[test]
fn generalized_alpha_keeps_the_energy_of_an_undamped_oscillator_bounded() {
    let (kept, gain) = alpha_energy(anima_ode::DEFAULT_RHO_INF, 0.1, 10_000);
    assert!(gain <= 1e-12, "the default ρ∞ gained energy: {gain:e}");
    assert!(kept > 0.5 && kept <= 1.0, "the default ρ∞ kept {kept} of the energy over 10⁴ steps");
    let (kept, gain) = alpha_energy(1.0, 0.1, 10_000);
    assert!(
        gain <= 1e-10 && (kept - 1.0).abs() < 1e-10,
        "ρ∞ = 1 changed the energy: kept {kept}, gain {gain:e}"
    );
    // Backward Euler, for contrast, loses nearly all of it.
    let mut st = Stepper::new(Integrator::ImplicitEuler, 1);
    let mut now = State::new(vec![4.0], vec![0.0]);
    let mut next = State::zeros(1);
    for k in 0..10_000 {
        st.step(&mut SingleSpring::thesis(), k as f64 * 0.1, 0.1, &now, &mut next).unwrap();
        std::mem::swap(&mut now, &mut next);
    }
    assert!(energy(&now) < 1e-6 * 2.0, "backward Euler kept {}", energy(&now) / 2.0);
}

/// ρ∞ is the factor by which a step damps a mode it cannot resolve: at h ω = 10⁴ the amplitude falls by
/// ρ∞ per step. (All the step matrix's eigenvalues tend to −ρ∞ there, a repeated root, so the decay is
/// ρ∞ᵏ times a polynomial in k: it is measured over steps 20 to 30, where the polynomial adds under 10 %.)
#[test]
fn generalized_alpha_damps_unresolved_modes_by_its_spectral_radius() {
    for rho in [0.0, 0.2, 0.5, 0.8] {
        let h = 1e4;
        let mut st = Stepper::new(Integrator::GeneralizedAlpha, 1);
        st.set_spectral_radius(rho);
        let mut now = State::new(vec![4.0], vec![0.0]);
        let mut next = State::zeros(1);
        let mut amplitudes = Vec::new();
        for k in 0..30 {
            st.step(&mut SingleSpring::thesis(), k as f64 * h, h, &now, &mut next).unwrap();
            std::mem::swap(&mut now, &mut next);
            amplitudes.push((now.x[0] - 2.0).hypot(now.v[0]));
        }
        if rho == 0.0 {
            // Gone but for O(1/(h ω)).
            assert!(amplitudes[3] < 1e-3, "ρ∞ = 0 left {}", amplitudes[3]);
            continue;
        }
        let per_step = (amplitudes[29] / amplitudes[19]).powf(0.1);
        assert!((per_step / rho - 1.0).abs() < 0.1, "ρ∞ = {rho}: the amplitude fell by {per_step} per step");
    }
    // At h ω = 0.05 one step loses less than 10⁻⁶ of the amplitude.
    let (kept, _) = alpha_energy(anima_ode::DEFAULT_RHO_INF, 0.05, 1);
    assert!(kept > 1.0 - 2e-6, "one step at h ω = 0.05 kept {kept} of the energy");
}
