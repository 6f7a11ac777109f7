//! Divergence caught when it happens: the physical bounds a cloth run must stay inside.
//!
//! A run that blows up is usually finite for a long while before it is non-finite: a sheet past its
//! stable step reaches tens of m/s and stretches its springs by tens of per cent within milliseconds,
//! and a cloth thrown about by a bad step can fly at hundreds of m/s for seconds without a NaN. So every
//! cloth model checks, besides finiteness, three bounds that no cloth in a scene that makes sense
//! crosses, and stops with the step, the time, the particle or spring and the bound when one is:
//!
//! - **Speed**: no particle faster than a multiple ([`SPEED_FACTOR`]) of the speed the scene can give
//!   it: a fall through its whole extent, plus the fastest it starts with or is driven at, plus what
//!   the elastic energy it starts with could give its lightest particle.
//! - **Strain**: no spring or edge longer than (1 + [`Bounds::max_strain`]) times its rest length,
//!   a hundred times by default: hard cases that recover stretch springs by many times their length
//!   for a step or two (a sheet whose middle row starts collapsed onto one point, released at 1/60 s:
//!   11 times), while a run that blows up grows by orders of magnitude within a few steps.
//! - **Energy** (models whose only source of energy is gravity): the kinetic energy no more than
//!   [`ENERGY_FACTOR`] times what the start and gravity's work since then can have supplied,
//!   E_k ≤ f·(E_k(0) + E_el(0) + Σ m g·(x − x(0))), with a floor of 10⁻³ of the scene's weight times
//!   its extent so that a cloth at rest is not judged on round-off.
//!
//! A passive, damped system cannot break the energy bound at all; the speed and strain bounds hold
//! with a wide margin in every scene anima ships (the fastest, FLEX3D's sail in the wind, reaches a
//! tenth of its speed bound; drapes stretch their springs by a few per cent). Users with a scene that
//! means to go further set their own ([`Bounds`] is a field of every model) or turn the checks off
//! ([`Bounds::unbounded`]).

use anima_geom::DVec3;

/// The speed bound as a multiple of the speed a scene can give a particle.
pub const SPEED_FACTOR: f64 = 20.0;
/// The default strain bound: a spring a hundred times its rest length.
pub const MAX_STRAIN: f64 = 99.0;
/// The energy bound as a multiple of the energy available.
pub const ENERGY_FACTOR: f64 = 2.0;
/// Explicit steps between two checks of the bounds (implicit steps are checked every step): a check
/// costs about as much as a step of the sheet's fused kernel, and a run that diverges grows by orders of
/// magnitude over a few dozen steps, so checking every step would buy nothing but time.
pub const EXPLICIT_CHECK_EVERY: usize = 64;

/// The bounds of one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bounds {
    /// Largest particle speed (m/s, or a FLEX3D scene's units per second).
    pub max_speed: f64,
    /// Largest strain |d|/L⁰ − 1 of a spring or edge.
    pub max_strain: f64,
    /// Whether the energy bound is checked (models driven only by gravity), and its factor.
    pub energy_factor: Option<f64>,
}

impl Bounds {
    /// The default bounds for particles starting at `x` with velocities `v` and masses `masses`:
    /// speed [`SPEED_FACTOR`] × (√(2 a H) + v₀ + √(2 E_el / m_min)), with H the diagonal of the
    /// particles' bounding box (1 when that is 0), a the largest body acceleration (|g|, or gravity and
    /// wind), v₀ the fastest start or drive and E_el the elastic energy stored at the start; strain
    /// [`MAX_STRAIN`]; energy when `passive` (gravity the only source of energy).
    pub fn for_start(x: &[DVec3], v: &[DVec3], masses: &[f64], defaults: Defaults, elastic: f64) -> Self {
        let extent = extent(x);
        let fastest = v.iter().map(|v| v.length()).fold(defaults.driven, f64::max);
        let fall = (2.0 * defaults.acceleration * extent).sqrt();
        let lightest = masses.iter().copied().fold(f64::INFINITY, f64::min);
        let release = if lightest > 0.0 && elastic > 0.0 { (2.0 * elastic / lightest).sqrt() } else { 0.0 };
        Self {
            max_speed: SPEED_FACTOR * (fall + fastest + release).max(f64::MIN_POSITIVE),
            max_strain: defaults.max_strain,
            energy_factor: defaults.passive.then_some(ENERGY_FACTOR),
        }
    }

    /// No bound at all (finiteness is still checked).
    pub fn unbounded() -> Self {
        Self { max_speed: f64::INFINITY, max_strain: f64::INFINITY, energy_factor: None }
    }
}

/// What a model's default bounds are taken from, besides its state ([`Bounds::for_start`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Defaults {
    /// The largest body acceleration, m/s² (|g|; a FLEX3D scene adds its wind).
    pub acceleration: f64,
    /// The fastest prescribed motion (pinned, translated particles), m/s.
    pub driven: f64,
    /// Whether gravity is the only source of energy (the energy bound applies).
    pub passive: bool,
    /// The strain bound ([`MAX_STRAIN`] for springs that resist stretching; FLEX3D's soft springs
    /// are not bounded).
    pub max_strain: f64,
}

impl Defaults {
    /// A passive cloth under gravity `g`, nothing driven, the default strain bound.
    pub fn passive(gravity: DVec3) -> Self {
        Self { acceleration: gravity.length(), driven: 0.0, passive: true, max_strain: MAX_STRAIN }
    }
}

/// The diagonal of the points' bounding box, 1 when they all coincide.
fn extent(x: &[DVec3]) -> f64 {
    let (lo, hi) =
        x.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    let d = (hi - lo).length();
    if d.is_finite() && d > 0.0 { d } else { 1.0 }
}

/// Which bound a run left, with the numbers that say so.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    Speed { particle: usize, speed: f64, limit: f64 },
    Strain { ends: [u32; 2], strain: f64, limit: f64 },
    Energy { kinetic: f64, available: f64, factor: f64 },
}

impl Bound {
    /// `speed`, `strain` or `energy`.
    pub fn name(&self) -> &'static str {
        match self {
            Bound::Speed { .. } => "speed",
            Bound::Strain { .. } => "strain",
            Bound::Energy { .. } => "energy",
        }
    }
}

impl std::fmt::Display for Bound {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Bound::Speed { particle, speed, limit } => {
                write!(f, "particle {particle} moves at {speed:.4e}, beyond the speed bound {limit:.4e}")
            }
            Bound::Strain { ends: [i, j], strain, limit } => write!(
                f,
                "the spring between particles {i} and {j} is stretched {:.1} % beyond its rest length, past the \
                 strain bound of {:.0} %",
                100.0 * strain,
                100.0 * limit
            ),
            Bound::Energy { kinetic, available, factor } => write!(
                f,
                "the kinetic energy {kinetic:.4e} J is more than {factor} times the {available:.4e} J the start \
                 and gravity can have supplied"
            ),
        }
    }
}

/// A run that left its bounds: where, when and which.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[error("the run diverged at step {step} (t = {time} s): {bound} (bound: {})", bound.name())]
pub struct OutOfBounds {
    pub step: u64,
    pub time: f64,
    pub bound: Bound,
}

/// What the energy bound measures from: the start's positions, energy and scale.
#[derive(Debug, Clone)]
struct EnergyBase {
    /// The particles and Σ m x at the start: gravity's work since is g · (Σ m x − Σ m x₀).
    particles: usize,
    moment0: DVec3,
    /// E_k(0) + E_el(0), J.
    energy: f64,
    /// 10⁻³ of the weight times the extent, J.
    floor: f64,
}

/// A model's bounds and what checking them needs between steps.
#[derive(Debug, Clone)]
pub struct BoundsWatch {
    pub bounds: Bounds,
    /// What the default bounds are taken from at each start; `None` once a caller set its own.
    defaults: Option<Defaults>,
    energy: Option<EnergyBase>,
}

impl BoundsWatch {
    /// The default bounds of `defaults`, taken from the start (x, v) with `masses` under `gravity`;
    /// `elastic` is the elastic energy stored at the start (0 for a cloth at rest length).
    pub fn new(
        defaults: Defaults,
        x: &[DVec3],
        v: &[DVec3],
        masses: &[f64],
        gravity: DVec3,
        elastic: f64,
    ) -> Self {
        let mut watch = Self { bounds: Bounds::unbounded(), defaults: Some(defaults), energy: None };
        watch.restart(x, v, masses, gravity, elastic);
        watch
    }

    /// Sets the bounds (they no longer follow the start) and measures the energy from the state (x, v).
    pub fn set(
        &mut self,
        bounds: Bounds,
        x: &[DVec3],
        v: &[DVec3],
        masses: &[f64],
        gravity: DVec3,
        elastic: f64,
    ) {
        self.defaults = None;
        self.bounds = bounds;
        self.restart(x, v, masses, gravity, elastic);
    }

    /// Starts again from the state (x, v): the default bounds are taken from it (unless set), and the
    /// energy bound counts from it (after a remesh changed the particles, or a caller set the state).
    pub fn restart(&mut self, x: &[DVec3], v: &[DVec3], masses: &[f64], gravity: DVec3, elastic: f64) {
        if let Some(defaults) = self.defaults {
            self.bounds = Bounds::for_start(x, v, masses, defaults, elastic);
        }
        let kinetic: f64 = v.iter().zip(masses).map(|(v, m)| 0.5 * m * v.length_squared()).sum();
        let weight = masses.iter().sum::<f64>() * gravity.length();
        self.energy = self.bounds.energy_factor.map(|_| EnergyBase {
            particles: x.len(),
            moment0: x.iter().zip(masses).map(|(x, m)| *x * *m).sum(),
            energy: kinetic + elastic,
            floor: 1e-3 * weight * extent(x),
        });
    }

    /// Checks the state at `step` (time `time`): speeds, the strain of every spring `(i, j, L⁰)` of
    /// `springs`, and the energy. The first bound left, in that order, is the error.
    #[expect(clippy::too_many_arguments, reason = "the step, the state, the model's masses and springs")]
    pub fn check(
        &self,
        step: u64,
        time: f64,
        x: &[DVec3],
        v: &[DVec3],
        masses: &[f64],
        gravity: DVec3,
        springs: impl Iterator<Item = (u32, u32, f64)>,
    ) -> Result<(), OutOfBounds> {
        let out = |bound| Err(OutOfBounds { step, time, bound });
        let b = &self.bounds;
        if b.max_speed.is_finite() {
            let limit2 = b.max_speed * b.max_speed;
            if let Some(particle) = v.iter().position(|v| v.length_squared() > limit2) {
                return out(Bound::Speed { particle, speed: v[particle].length(), limit: b.max_speed });
            }
        }
        if b.max_strain.is_finite() {
            let stretch = 1.0 + b.max_strain;
            for (i, j, rest) in springs {
                let len = x[i as usize].distance(x[j as usize]);
                if rest > 0.0 && len > stretch * rest {
                    let strain = len / rest - 1.0;
                    return out(Bound::Strain { ends: [i, j], strain, limit: b.max_strain });
                }
            }
        }
        if let (Some(factor), Some(base)) = (b.energy_factor, &self.energy)
            && base.particles == x.len()
        {
            let kinetic: f64 = v.iter().zip(masses).map(|(v, m)| 0.5 * m * v.length_squared()).sum();
            let moment: DVec3 = x.iter().zip(masses).map(|(x, m)| *x * *m).sum();
            let work = gravity.dot(moment - base.moment0);
            let available = base.energy + work;
            if kinetic > factor * available.max(0.0) + base.floor {
                return out(Bound::Energy { kinetic, available, factor });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_bound_is_named_with_its_numbers() {
        let x = vec![DVec3::ZERO, DVec3::X];
        let g = DVec3::new(0.0, 0.0, -9.81);
        let defaults = Defaults { max_strain: 1.0, ..Defaults::passive(g) };
        let watch = BoundsWatch::new(defaults, &x, &[DVec3::ZERO; 2], &[1.0, 1.0], g, 0.0);
        // √(2 · 9.81 · 1) · 20 ≈ 88.6.
        assert!((watch.bounds.max_speed - 20.0 * (2.0f64 * 9.81).sqrt()).abs() < 1e-12);
        let spring = || [(0u32, 1u32, 1.0)].into_iter();
        assert!(watch.check(1, 0.1, &x, &[DVec3::ZERO; 2], &[1.0, 1.0], g, spring()).is_ok());
        let fast = [DVec3::ZERO, DVec3::X * 100.0];
        let e = watch.check(2, 0.2, &x, &fast, &[1.0, 1.0], g, spring()).unwrap_err();
        assert!(matches!(e.bound, Bound::Speed { particle: 1, .. }), "{e}");
        assert!(e.to_string().contains("step 2") && e.to_string().contains("speed"), "{e}");
        let stretched = [DVec3::ZERO, DVec3::X * 2.5];
        let e = watch.check(3, 0.3, &stretched, &[DVec3::ZERO; 2], &[1.0, 1.0], g, spring()).unwrap_err();
        assert!(matches!(e.bound, Bound::Strain { ends: [0, 1], .. }), "{e}");
        // Moving sideways at 5 m/s with no fall: energy from nowhere.
        let sideways = [DVec3::X * 5.0, DVec3::X * 5.0];
        let e = watch.check(4, 0.4, &x, &sideways, &[1.0, 1.0], g, spring()).unwrap_err();
        assert!(matches!(e.bound, Bound::Energy { .. }), "{e}");
        // The same speed after falling far enough for gravity to have supplied it is fine.
        let fallen: Vec<DVec3> = x.iter().map(|p| *p - DVec3::Z * 2.0).collect();
        assert!(watch.check(5, 0.5, &fallen, &sideways, &[1.0, 1.0], g, spring()).is_ok());
        let mut free = watch.clone();
        free.set(Bounds::unbounded(), &x, &fast, &[1.0; 2], g, 0.0);
        assert!(free.check(6, 0.6, &stretched, &fast, &[1.0; 2], g, spring()).is_ok());
        // A start with velocities and stored elastic energy raises the speed bound.
        let mut moving = BoundsWatch::new(defaults, &x, &[DVec3::ZERO; 2], &[1.0, 1.0], g, 0.0);
        moving.restart(&x, &fast, &[1.0, 1.0], g, 50.0);
        assert!((moving.bounds.max_speed - 20.0 * ((2.0f64 * 9.81).sqrt() + 100.0 + 10.0)).abs() < 1e-9);
    }
}
