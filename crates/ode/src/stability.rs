//! How large a step an explicit method can take before it blows up.
//!
//! For an undamped linear system x'' = −Ω² x the explicit methods are stable while h·ω_max stays inside
//! their stability interval on the imaginary axis, ω_max² being the largest eigenvalue of −∂a/∂x. This
//! module estimates ω_max for any [`OdeSystem`] (power iteration on finite differences of the
//! acceleration) or bounds it from above from a [`Linearized`] system's Jacobians (Gershgorin), and
//! measures each method's interval by running it on the unit oscillator, so that nothing is copied from
//! a table.

use crate::{Coord, Integrator, Jacobians, Linearized, OdeSystem, State, Stepper};

/// ω_max² ≈ largest eigenvalue of −∂a/∂x at (t, x, v), by `iterations` steps of power iteration with
/// finite-difference products J·p ≈ (a(x + εp) − a(x))/ε. Coordinates where `frozen` is true (pinned
/// particles) are left out.
pub fn max_frequency<S: OdeSystem + ?Sized>(
    sys: &mut S,
    t: f64,
    x: &[S::Coord],
    v: &[S::Coord],
    frozen: &[bool],
    iterations: usize,
) -> f64 {
    let mut p = vec![S::Coord::default(); x.len()];
    power_iteration(sys, t, x, v, frozen, iterations, &mut p)
}

/// [`max_frequency`], leaving the last iteration's (unnormalised) vector in `p`.
fn power_iteration<S: OdeSystem + ?Sized>(
    sys: &mut S,
    t: f64,
    x: &[S::Coord],
    v: &[S::Coord],
    frozen: &[bool],
    iterations: usize,
    p: &mut [S::Coord],
) -> f64 {
    let n = x.len();
    let mut a0 = vec![S::Coord::default(); n];
    let mut a1 = vec![S::Coord::default(); n];
    let mut xp = x.to_vec();
    sys.acceleration(t, x, v, &mut a0);
    // A fixed, deterministic start vector with every component non-zero.
    for (i, pi) in p.iter_mut().enumerate() {
        *pi = S::Coord::splat(1.0 + ((i * 7919) % 97) as f64 / 97.0);
    }
    let scale = x.iter().map(|c| c.max_abs()).fold(0.0, f64::max).max(1.0);
    let mut lambda = 0.0;
    for _ in 0..iterations {
        for (pi, &f) in p.iter_mut().zip(frozen) {
            if f {
                *pi = S::Coord::default();
            }
        }
        let norm = p.iter().map(|c| c.dot(*c)).sum::<f64>().sqrt();
        if norm == 0.0 {
            return 0.0;
        }
        let eps = 1e-7 * scale;
        for i in 0..n {
            p[i] = p[i] * (1.0 / norm);
            xp[i] = x[i] + p[i] * eps;
        }
        sys.acceleration(t, &xp, v, &mut a1);
        // q = −(a1 − a0)/ε ; Rayleigh quotient λ = p·q.
        let mut rayleigh = 0.0;
        for i in 0..n {
            let q = (a1[i] - a0[i]) * (-1.0 / eps);
            rayleigh += p[i].dot(q);
            p[i] = q;
        }
        lambda = rayleigh;
    }
    for (pi, &f) in p.iter_mut().zip(frozen) {
        if f {
            *pi = S::Coord::default();
        }
    }
    lambda.max(0.0).sqrt()
}

/// The highest undamped frequency ω_max ([`max_frequency`]) and the damping ratio ζ of that mode: the
/// power iteration's last vector p, the Rayleigh quotient c = −pᵀ(∂a/∂v)p / pᵀp of the velocity
/// Jacobian (by finite differences of the acceleration in v), ζ = c / (2 ω_max). Damping lowers the
/// largest stable step of the explicit methods ([`damped_stability_limit`]): a sheet whose spring
/// dampers are strong at its shortest wavelengths (the standard sheet at N = 256: ζ ≈ 0.7) blows up at
/// about half the step the undamped bound allows.
pub fn max_frequency_and_damping<S: OdeSystem + ?Sized>(
    sys: &mut S,
    t: f64,
    x: &[S::Coord],
    v: &[S::Coord],
    frozen: &[bool],
    iterations: usize,
) -> (f64, f64) {
    let n = x.len();
    let mut p = vec![S::Coord::default(); n];
    let omega = power_iteration(sys, t, x, v, frozen, iterations, &mut p);
    if omega <= 0.0 {
        return (omega, 0.0);
    }
    let mut a0 = vec![S::Coord::default(); n];
    let mut a1 = vec![S::Coord::default(); n];
    sys.acceleration(t, x, v, &mut a0);
    let norm = p.iter().map(|c| c.dot(*c)).sum::<f64>().sqrt();
    if norm == 0.0 {
        return (omega, 0.0);
    }
    let scale = v.iter().map(|c| c.max_abs()).fold(0.0, f64::max).max(1.0);
    let eps = 1e-7 * scale;
    let vp: Vec<S::Coord> = v.iter().zip(&p).map(|(&vi, &pi)| vi + pi * (eps / norm)).collect();
    sys.acceleration(t, x, &vp, &mut a1);
    let mut c = 0.0;
    for i in 0..n {
        c += (p[i] * (1.0 / norm)).dot((a1[i] - a0[i]) * (-1.0 / eps));
    }
    (omega, (c / (2.0 * omega)).max(0.0))
}

/// Upper bound on ω_max from the Jacobians (Gershgorin): ω_max² ≤ max_i Σ_j ‖K_ij‖∞ / m_i over free
/// coordinates.
pub fn gershgorin_frequency<C: Coord>(lin: &mut dyn Linearized<C>, t: f64, x: &[C], v: &[C]) -> f64 {
    let n = x.len();
    let mut jac = Jacobians::<C>::new(n, lin.pattern().len());
    let mut f = vec![C::default(); n];
    lin.force_and_jacobians(t, x, v, &mut f, &mut jac);
    let mut rows: Vec<C> = jac.k_diag.iter().map(|&b| C::block_row_abs_sums(b)).collect();
    for (e, &(i, j)) in lin.pattern().iter().enumerate() {
        let b = jac.k_off[e];
        rows[i as usize] += C::block_row_abs_sums(b);
        rows[j as usize] += C::block_col_abs_sums(b);
    }
    let (masses, fixed) = (lin.masses(), lin.prescribed());
    let worst = (0..n).filter(|&i| !fixed[i]).map(|i| rows[i].max_abs() / masses[i]).fold(0.0, f64::max);
    worst.sqrt()
}

/// Measured stability limit of `integrator` on the undamped unit oscillator x'' = −x: the largest h·ω
/// at which the amplitude grows by at most 10⁻⁶ per radian of motion (0.1 % over 160 periods), to three
/// digits. One-step methods are judged by the spectral radius of their 2×2 step matrix (measured by
/// stepping the two unit states); the multistep methods by running 4 000 steps and comparing the energy
/// late in the run with the energy early on. Forward Euler and the thesis's adaptive Euler grow at every
/// step (0); midpoint and the predictor–corrector grow so slowly at small steps that their limits are
/// small but not zero. Damping (friction) is what makes the growing methods usable.
pub fn stability_limit(integrator: Integrator) -> f64 {
    damped_stability_limit(integrator, 0.0)
}

/// Measured stability limit of `integrator` on the damped unit oscillator x'' = −x − 2ζ x': the largest
/// h·ω at which neither mode grows (as [`stability_limit`], which is ζ = 0). Damping narrows the
/// stable interval of the explicit methods: symplectic Euler, stable to h·ω = 2 undamped, is stable
/// exactly to 2(√(1 + ζ²) − ζ), 1.04 at ζ = 0.7.
pub fn damped_stability_limit(integrator: Integrator, zeta: f64) -> f64 {
    let zeta = if zeta.is_finite() { zeta.max(0.0) } else { 0.0 };
    if integrator.is_implicit() {
        return f64::INFINITY;
    }
    let stable = |hw: f64| -> bool {
        let allowed = 1.0 + 1e-6 * hw;
        if integrator.is_multistep() {
            multistep_growth_damped(integrator, hw, zeta).is_some_and(|rho| rho <= allowed)
        } else {
            spectral_radius_damped(integrator, hw, zeta) <= allowed
        }
    };
    if !stable(1e-3) {
        return 0.0;
    }
    let (mut lo, mut hi) = (1e-3, 4.0);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if stable(mid) { lo = mid } else { hi = mid }
    }
    (lo * 1000.0).floor() / 1000.0
}

/// The damped unit oscillator x'' = −x − 2ζ x'.
struct DampedOscillator(f64);

impl OdeSystem for DampedOscillator {
    type Coord = f64;
    fn n_coords(&self) -> usize {
        1
    }
    fn acceleration(&mut self, _t: f64, x: &[f64], v: &[f64], a: &mut [f64]) {
        a[0] = -x[0] - 2.0 * self.0 * v[0];
    }
}

/// Spectral radius of a one-step method's step matrix on the damped unit oscillator at step h.
fn spectral_radius_damped(integrator: Integrator, h: f64, zeta: f64) -> f64 {
    let mut st = Stepper::new(integrator, 1);
    let mut column = |x: f64, v: f64| {
        let mut next = State::zeros(1);
        st.step(&mut DampedOscillator(zeta), 0.0, h, &State::new(vec![x], vec![v]), &mut next)
            .expect("explicit step");
        (next.x[0], next.v[0])
    };
    let (a, c) = column(1.0, 0.0);
    let (b, d) = column(0.0, 1.0);
    let (tr, det) = (a + d, a * d - b * c);
    let disc = tr * tr / 4.0 - det;
    if disc < 0.0 { det.abs().sqrt() } else { (tr / 2.0).abs() + disc.sqrt() }
}

/// Amplitude growth per step of a multistep method on the damped unit oscillator at step h, from the
/// energy 2 000 steps apart; `None` if it blew up.
fn multistep_growth_damped(integrator: Integrator, h: f64, zeta: f64) -> Option<f64> {
    let mut st = Stepper::new(integrator, 1);
    let mut now = State::new(vec![1.0], vec![0.0]);
    let mut next = State::zeros(1);
    let (mut early, mut late) = (0.0f64, 0.0f64);
    for k in 0..4000 {
        st.step(&mut DampedOscillator(zeta), k as f64 * h, h, &now, &mut next).ok()?;
        std::mem::swap(&mut now, &mut next);
        let e = now.x[0] * now.x[0] + now.v[0] * now.v[0];
        if !e.is_finite() {
            return None;
        }
        if (1000..2000).contains(&k) {
            early = early.max(e);
        } else if k >= 3000 {
            late = late.max(e);
        }
    }
    if early == 0.0 {
        return Some(0.0);
    }
    Some((late / early).powf(1.0 / 4000.0))
}

/// A warning when `dt` is beyond what `integrator` is known to survive at frequency `omega_max`.
pub fn check_step(integrator: Integrator, dt: f64, omega_max: f64) -> Option<String> {
    let limit = stability_limit(integrator);
    if limit.is_infinite() || omega_max <= 0.0 {
        return None;
    }
    let allowed = limit / omega_max;
    if dt > allowed {
        Some(format!(
            "{integrator}: Δt = {dt:.3e} s exceeds the stable step {allowed:.3e} s (h·ω ≤ {limit} with ω_max = {omega_max:.3e} rad/s); the run will blow up without enough damping"
        ))
    } else {
        None
    }
}
