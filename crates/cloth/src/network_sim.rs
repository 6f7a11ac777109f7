//! Running a [`SpringNetwork`] with any integrator, with analytic static colliders. Contacts are resolved
//! after each step by default (a split: the integrator steps the smooth forces, then contacts project
//! positions and remove the approaching normal velocity, with Coulomb friction on the tangential part),
//! or, with [`ContactMode::InSolve`] and generalised-α, constrained inside the implicit solve
//! ([`AnalyticContacts`]).
//!
//! With [`NetworkSim::self_collision`] set (and the network's triangles given with
//! [`NetworkSim::enable_self_collision`]), the cloth is also kept from passing through itself: after the
//! step and the colliders, the step's motion goes through the [`SelfCollisionResponse`] velocity filter
//! (Bridson, Fedkiw & Anderson 2002), whatever the integrator.

use anima_geom::DVec3;
use anima_ode::contact::{Contact, ContactModel};
use anima_ode::{Integrator, OdeError, State, StepStats, Stepper};

use crate::bounds::{Bounds, BoundsWatch, Defaults, OutOfBounds};
use crate::contact_mode::ContactMode;
use crate::error::{NonFinite, StepError};
use crate::self_collision::{OBJECT_ROUNDS, SelfCollision, SelfCollisionResponse, SelfCollisionStats};
use crate::spring_net::{NetworkError, SpringNetwork};

/// A static obstacle given analytically.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Collider {
    /// The half-space below the plane through `point` with outward `normal`.
    Plane {
        point: DVec3,
        normal: DVec3,
    },
    Sphere {
        centre: DVec3,
        radius: f64,
    },
    /// An axis-aligned box.
    Box {
        min: DVec3,
        max: DVec3,
    },
}

impl Collider {
    /// Where the path `from → to` first enters the collider (grown by `margin`), with the outward normal
    /// there, when `from` is outside. Fast particles are caught at their entry point, not pushed out
    /// through whichever face is nearest after they have tunnelled deep inside.
    pub fn entry(&self, from: DVec3, to: DVec3, margin: f64) -> Option<(DVec3, DVec3)> {
        if self.push_out(from, margin).is_some() || self.push_out(to, margin).is_none() {
            return None;
        }
        let d = to - from;
        match *self {
            Collider::Plane { point, normal } => {
                let n = normal.normalize();
                let (a, b) = ((from - point).dot(n) - margin, d.dot(n));
                (b < 0.0).then(|| (from + d * (-a / b), n))
            }
            Collider::Sphere { centre, radius } => {
                let r = radius + margin;
                let f = from - centre;
                let (a, b, c) = (d.dot(d), 2.0 * f.dot(d), f.dot(f) - r * r);
                let disc = b * b - 4.0 * a * c;
                (disc >= 0.0 && a > 0.0).then(|| {
                    let s = ((-b - disc.sqrt()) / (2.0 * a)).clamp(0.0, 1.0);
                    let q = from + d * s;
                    (q, (q - centre).normalize_or(DVec3::Z))
                })
            }
            Collider::Box { min, max } => {
                let (lo, hi) = (min - DVec3::splat(margin), max + DVec3::splat(margin));
                // Slab method: the entry parameter is the largest of the per-axis entry parameters, and
                // its axis the face entered. The largest is taken over every axis (not only positive
                // ones), so that a path starting on a face is given that face, not the x axis.
                let (mut s_in, mut axis) = (f64::NEG_INFINITY, 0usize);
                for k in 0..3 {
                    if d[k] != 0.0 {
                        let (t0, t1) = ((lo[k] - from[k]) / d[k], (hi[k] - from[k]) / d[k]);
                        let enter = t0.min(t1);
                        if enter > s_in {
                            s_in = enter;
                            axis = k;
                        }
                    }
                }
                let q = from + d * s_in.max(0.0);
                let mut n = DVec3::ZERO;
                n[axis] = if d[axis] > 0.0 { -1.0 } else { 1.0 };
                Some((q, n))
            }
        }
    }

    /// If `p` is inside (or closer than `margin`), the nearest point on the surface pushed out by the
    /// margin, and the outward normal there.
    pub fn push_out(&self, p: DVec3, margin: f64) -> Option<(DVec3, DVec3)> {
        match *self {
            Collider::Plane { point, normal } => {
                let n = normal.normalize();
                let d = (p - point).dot(n);
                (d < margin).then(|| (p + n * (margin - d), n))
            }
            Collider::Sphere { centre, radius } => {
                let r = p - centre;
                let d = r.length();
                if d >= radius + margin {
                    return None;
                }
                let n = if d > 0.0 { r / d } else { DVec3::Z };
                Some((centre + n * (radius + margin), n))
            }
            Collider::Box { min, max } => {
                let (lo, hi) = (min - DVec3::splat(margin), max + DVec3::splat(margin));
                if p.cmple(lo).any() || p.cmpge(hi).any() {
                    return None;
                }
                // Leave through the nearest face.
                let dists = [p.x - lo.x, hi.x - p.x, p.y - lo.y, hi.y - p.y, p.z - lo.z, hi.z - p.z];
                let (face, _) = dists
                    .iter()
                    .enumerate()
                    .fold((0, f64::INFINITY), |b, (k, &d)| if d < b.1 { (k, d) } else { b });
                // Faces 2a and 2a + 1 are the low and high sides of axis a.
                let axis = face / 2;
                let mut q = p;
                let n = if face % 2 == 0 {
                    q[axis] = lo[axis];
                    -DVec3::AXES[axis]
                } else {
                    q[axis] = hi[axis];
                    DVec3::AXES[axis]
                };
                Some((q, n))
            }
        }
    }
}

/// A network, its integrator, its double-buffered state and its colliders.
#[derive(Debug)]
pub struct NetworkSim {
    pub network: SpringNetwork,
    stepper: Stepper<DVec3>,
    pub state: State<DVec3>,
    scratch: State<DVec3>,
    pub colliders: Vec<Collider>,
    /// Friction coefficient of every contact.
    pub friction: f64,
    /// Contacts keep particles this far outside colliders, m.
    pub margin: f64,
    /// Where contacts are answered: after the step (the default) or inside the implicit solve.
    pub contact: ContactMode,
    /// Self-collision response after the step, when set (see [`NetworkSim::enable_self_collision`]).
    /// Off by default: the theses' sheets pass through themselves.
    pub self_collision: Option<SelfCollision>,
    /// The cloth surface self-collision keeps apart; empty until enabled.
    triangles: Vec<[u32; 3]>,
    self_response: SelfCollisionResponse,
    /// Inverse masses with 0 for pinned particles, as the self-collision response takes them.
    inv_mass: Vec<f64>,
    /// What the self-collision response did at the last step, and summed over the run.
    pub self_collision_last: SelfCollisionStats,
    pub self_collision_total: SelfCollisionStats,
    /// Per particle, whether the last contact pass after the step moved it.
    touched: Vec<bool>,
    /// Per particle, whether a collider answered it this step (the self-collision response holds it),
    /// and the step's end before that response (for its next round).
    held: Vec<bool>,
    before_filter: (Vec<DVec3>, Vec<DVec3>),
    step: u64,
    dt: f64,
    pub stats: StepStats,
    /// The physical bounds the run is checked against ([`crate::bounds`]), and the fastest drive of
    /// the pinned particles so far (m/s).
    bounds: BoundsWatch,
    driven: f64,
}

impl NetworkSim {
    /// The network at rest at `x`, stepped by `integrator` at `dt` s. A position count other than the
    /// network's, or a step that is not positive and finite, is an error.
    pub fn new(
        network: SpringNetwork,
        x: Vec<DVec3>,
        integrator: Integrator,
        dt: f64,
    ) -> Result<Self, NetworkError> {
        let n = network.n_particles();
        if x.len() != n {
            return Err(NetworkError::Count { what: "position", n, found: x.len() });
        }
        if !(dt.is_finite() && dt > 0.0) {
            return Err(NetworkError::Step(dt));
        }
        let at_rest = vec![DVec3::ZERO; n];
        let masses = anima_ode::Linearized::masses(&network);
        let elastic = network.elastic_energy(&x);
        let bounds = BoundsWatch::new(
            Defaults::passive(network.gravity),
            &x,
            &at_rest,
            masses,
            network.gravity,
            elastic,
        );
        Ok(Self {
            bounds,
            driven: 0.0,
            stepper: Stepper::new(integrator, n),
            state: State::new(x, vec![DVec3::ZERO; n]),
            scratch: State::zeros(n),
            network,
            colliders: Vec::new(),
            friction: 0.0,
            margin: 1e-3,
            contact: ContactMode::AfterStep,
            self_collision: None,
            triangles: Vec::new(),
            self_response: SelfCollisionResponse::new(),
            inv_mass: Vec::new(),
            self_collision_last: SelfCollisionStats::default(),
            self_collision_total: SelfCollisionStats::default(),
            touched: vec![false; n],
            held: vec![false; n],
            before_filter: (Vec::new(), Vec::new()),
            step: 0,
            dt,
            stats: StepStats::default(),
        })
    }

    pub fn time(&self) -> f64 {
        self.step as f64 * self.dt
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.step
    }

    /// The step, s.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// Every particle's position, in the network's order.
    pub fn positions(&self) -> &[DVec3] {
        &self.state.x
    }

    pub fn velocities(&self) -> &[DVec3] {
        &self.state.v
    }

    /// Replaces every particle's position and velocity; a multistep or implicit integrator starts its
    /// history again (the state jumped), the step count and time go on.
    ///
    /// # Panics
    /// If `x` or `v` does not hold one value per particle.
    pub fn set_state(&mut self, x: &[DVec3], v: &[DVec3]) {
        assert!(
            x.len() == self.state.x.len() && v.len() == x.len(),
            "one position and velocity per particle"
        );
        self.state.x.copy_from_slice(x);
        self.state.v.copy_from_slice(v);
        self.stepper.reset_history();
    }

    pub fn stepper_mut(&mut self) -> &mut Stepper<DVec3> {
        &mut self.stepper
    }

    /// Turns the self-collision response on for the cloth surface `triangles` (particle indices; for a
    /// sheet, [`crate::spring_net::SheetSpec::triangles`]). Several disjoint surfaces in one network are
    /// one triangle list.
    ///
    /// # Panics
    /// If a triangle names a particle outside the network or repeats a particle.
    pub fn enable_self_collision(&mut self, settings: SelfCollision, triangles: Vec<[u32; 3]>) {
        let n = self.network.n_particles();
        for (k, t) in triangles.iter().enumerate() {
            assert!(t.iter().all(|&i| (i as usize) < n), "triangle {k} names a particle outside the network");
            assert!(t[0] != t[1] && t[1] != t[2] && t[0] != t[2], "triangle {k} repeats a particle");
        }
        self.self_collision = Some(settings);
        self.triangles = triangles;
    }

    /// The surface self-collision acts on (empty until [`NetworkSim::enable_self_collision`]).
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Moves pinned particles along a prescribed path: sets each pinned particle's velocity so that the
    /// next step ends it on `target(particle_idx)`. Pinned particles have no acceleration in any
    /// integrator and move x₁ = x₀ + h v (generalised-α included), so the step lands them exactly; call
    /// before every step. Only a frozen self-collision impact zone holds one back (it then stays put for
    /// the step), and the next call's velocity makes up for it.
    pub fn drive_pinned(&mut self, mut target: impl FnMut(usize) -> DVec3) {
        let inv_dt = 1.0 / self.dt;
        let mut fastest = 0.0f64;
        for (p, &pin) in self.network.pinned().iter().enumerate() {
            if pin {
                self.state.v[p] = (target(p) - self.state.x[p]) * inv_dt;
                fastest = fastest.max(self.state.v[p].length());
            }
        }
        // A driven network is given energy and speed from outside: no energy bound, and a speed bound
        // that admits the drive.
        self.driven = self.driven.max(fastest);
        let b = &mut self.bounds.bounds;
        b.energy_factor = None;
        b.max_speed = b.max_speed.max(crate::bounds::SPEED_FACTOR * fastest);
    }

    /// The physical bounds the run is checked against ([`crate::bounds`]: by default
    /// [`Bounds::for_start`] of the network at rest, with the energy bound until pinned particles are
    /// driven).
    pub fn bounds(&self) -> Bounds {
        self.bounds.bounds
    }

    /// Sets the bounds; [`Bounds::unbounded`] checks finiteness only.
    pub fn set_bounds(&mut self, bounds: Bounds) {
        let masses = anima_ode::Linearized::masses(&self.network);
        let elastic = self.network.elastic_energy(&self.state.x);
        self.bounds.set(bounds, &self.state.x, &self.state.v, masses, self.network.gravity, elastic);
    }

    /// Takes the bounds from the state as it is now (defaults from it, the energy counted from it):
    /// for a caller that changed [`NetworkSim::state`] in the middle of a run (a throw, a kick), which
    /// gives the network energy the bounds would otherwise take for a blow-up. The first step does this
    /// by itself.
    pub fn restart_bounds(&mut self) {
        let masses = anima_ode::Linearized::masses(&self.network);
        let elastic = self.network.elastic_energy(&self.state.x);
        self.bounds.restart(&self.state.x, &self.state.v, masses, self.network.gravity, elastic);
        if self.driven > 0.0 {
            let b = &mut self.bounds.bounds;
            b.energy_factor = None;
            b.max_speed = b.max_speed.max(crate::bounds::SPEED_FACTOR * self.driven);
        }
    }

    /// At the first step: the default bounds are taken from the state the run starts from (a caller may
    /// have set velocities or moved particles since the network was built).
    fn start_bounds(&mut self) {
        if self.step == 0 {
            self.restart_bounds();
        }
    }

    /// Checks the state against the bounds ([`crate::bounds`]).
    fn check_bounds(&self) -> Result<(), OutOfBounds> {
        self.check_bounds_at(self.step, self.time())
    }

    /// Checks the state as it is now against the bounds, for a caller that integrates the network
    /// itself (an adaptive integrator under its step controller, after
    /// [`NetworkSim::restart_bounds`]): `step` and `time` are the caller's count and clock, for the
    /// error.
    pub fn check_bounds_at(&self, step: u64, time: f64) -> Result<(), OutOfBounds> {
        let masses = anima_ode::Linearized::masses(&self.network);
        let springs = self.network.springs().iter().map(|s| (s.i, s.j, s.rest_length));
        let (x, v) = (&self.state.x, &self.state.v);
        self.bounds.check(step, time, x, v, masses, self.network.gravity, springs)
    }

    /// One step: integrate, then resolve contacts (or integrate with the contacts constrained inside the
    /// solve, with [`ContactMode::InSolve`]); a non-finite state or one that left the bounds is an error
    /// naming the step.
    pub fn step(&mut self) -> Result<(), StepError> {
        self.start_bounds();
        let step = self.step + 1;
        let time = step as f64 * self.dt;
        self.step_unchecked().map_err(|source| StepError::Solver { step, time, source })?;
        self.check_step()?;
        Ok(self.check_bounds()?)
    }

    /// A non-finite state is an error naming the step and the particle.
    fn check_step(&self) -> Result<(), StepError> {
        match self.state.first_non_finite() {
            Some(particle) => Err(self.non_finite(particle)),
            None => Ok(()),
        }
    }

    fn non_finite(&self, particle: usize) -> StepError {
        StepError::NonFinite(NonFinite { step: self.step, time: self.time(), particle, place: None })
    }

    fn step_unchecked(&mut self) -> Result<(), OdeError> {
        let t = self.time();
        let in_solve = self.contact == ContactMode::InSolve && !self.colliders.is_empty();
        let s = if in_solve {
            let mut contacts =
                AnalyticContacts { colliders: &self.colliders, margin: self.margin, friction: self.friction };
            self.stepper.step_with_contacts(
                &mut self.network,
                &mut contacts,
                t,
                self.dt,
                &self.state,
                &mut self.scratch,
            )?
        } else {
            self.stepper.step(&mut self.network, t, self.dt, &self.state, &mut self.scratch)?
        };
        self.stats.evaluations += s.evaluations;
        self.stats.solver_iterations += s.solver_iterations;
        self.stats.contacts = s.contacts;
        self.stats.late_contacts += s.late_contacts;
        std::mem::swap(&mut self.state, &mut self.scratch);
        self.held.clear();
        self.held.resize(self.state.x.len(), false);
        if !in_solve && !self.colliders.is_empty() && self.resolve_contacts() {
            self.stepper.reset_history_of(&self.touched);
            self.held.copy_from_slice(&self.touched);
        }
        if in_solve {
            for report in self.stepper.contact_reports() {
                if report.regime != anima_ode::contact::Regime::Free {
                    self.held[report.coordinate as usize] = true;
                }
            }
        }
        if let Some(settings) = self.self_collision
            && !self.triangles.is_empty()
            && self.resolve_self_collisions(&settings)
        {
            self.stepper.reset_history_of(&self.touched);
        }
        self.step += 1;
        Ok(())
    }

    /// Whether [`NetworkSim::run`] takes the network's fused run ([`SpringNetwork::run_symplectic_euler`])
    /// when the network is a sheet: symplectic Euler with nothing but the springs.
    fn fuses(&self) -> bool {
        self.stepper.integrator() == Integrator::SymplecticEuler
            && self.colliders.is_empty()
            && self.self_collision.is_none()
    }

    /// Threads [`NetworkSim::run`] uses ([`SpringNetwork::thread_count`]).
    pub fn threads(&self) -> usize {
        self.network.thread_count(self.fuses())
    }

    /// Runs `n` steps, stopping at the first non-finite state; returns the step where it appeared.
    ///
    /// A sheet with nothing but its springs, stepped with symplectic Euler, takes the network's fused
    /// path ([`SpringNetwork::run_symplectic_euler`]): the same bits, with fewer passes over memory.
    pub fn run(&mut self, n: usize) -> Result<(), StepError> {
        self.start_bounds();
        // Explicit steps are checked against the bounds every few dozen steps, implicit ones every step.
        let every =
            if self.stepper.integrator().is_implicit() { 1 } else { crate::bounds::EXPLICIT_CHECK_EVERY };
        let mut left = n;
        if self.fuses() {
            while left > 0 {
                let chunk = left.min(every);
                let Some(outcome) =
                    self.network.run_symplectic_euler(chunk, self.dt, &mut self.state.x, &mut self.state.v)
                else {
                    break;
                };
                let done = outcome.err().unwrap_or(chunk);
                self.step += done as u64;
                self.stats.evaluations += done;
                if outcome.is_err() {
                    let particle = self.state.first_non_finite().unwrap_or(0);
                    return Err(self.non_finite(particle));
                }
                self.check_bounds()?;
                left -= chunk;
            }
        }
        for k in 0..left {
            let step = self.step + 1;
            let time = step as f64 * self.dt;
            self.step_unchecked().map_err(|source| StepError::Solver { step, time, source })?;
            self.check_step()?;
            if (k + 1) % every == 0 || k + 1 == left {
                self.check_bounds()?;
            }
        }
        Ok(())
    }

    /// The self-collision filter on the step just taken ([`SelfCollisionResponse::filter_step`]),
    /// answered together with the colliders as the Oliveira cloth's is: a particle a collider answered
    /// this step is held (inverse mass 0), and a particle the filter would push into a collider is held
    /// too and the filter taken again from the step's end before it, at most
    /// [`OBJECT_ROUNDS`] more times. Returns whether any particle changed.
    fn resolve_self_collisions(&mut self, settings: &SelfCollision) -> bool {
        let masses = anima_ode::Linearized::masses(&self.network);
        let pinned = self.network.pinned();
        self.inv_mass.clear();
        self.inv_mass.extend(
            masses.iter().zip(pinned).zip(&self.held).map(|((m, &p), &h)| if p || h { 0.0 } else { 1.0 / m }),
        );
        self.before_filter.0.clear();
        self.before_filter.0.extend_from_slice(&self.state.x);
        self.before_filter.1.clear();
        self.before_filter.1.extend_from_slice(&self.state.v);
        let rounds = OBJECT_ROUNDS;
        for round in 0..=rounds {
            if round > 0 {
                self.state.x.copy_from_slice(&self.before_filter.0);
                self.state.v.copy_from_slice(&self.before_filter.1);
            }
            self.touched.fill(false);
            // After the swap, `scratch` holds the step's start and `state` its end.
            let stats = self.self_response.filter_step(
                settings,
                self.dt,
                &self.scratch.x,
                &mut self.state.x,
                &mut self.state.v,
                &self.inv_mass,
                &self.triangles,
                &mut self.touched,
            );
            let mut pushed_in = false;
            if round < rounds {
                for i in 0..self.state.x.len() {
                    if !self.touched[i] || self.inv_mass[i] == 0.0 {
                        continue;
                    }
                    let (a, b) = (self.scratch.x[i], self.state.x[i]);
                    if self
                        .colliders
                        .iter()
                        .any(|c| c.push_out(b, 0.0).is_some() || c.entry(a, b, 0.0).is_some())
                    {
                        self.inv_mass[i] = 0.0;
                        pushed_in = true;
                    }
                }
            }
            if !pushed_in {
                self.self_collision_last = stats;
                self.self_collision_total += stats;
                return stats.changed_particles > 0;
            }
        }
        unreachable!("the last round returns")
    }

    /// Pushes particles out of colliders (at their entry point when they crossed the surface during the
    /// step), sets their velocity to the displacement the contact allowed, removes its approaching normal
    /// part and applies Coulomb friction to the tangential part (|Δv_t| ≤ μ |Δv_n|). Returns whether any
    /// contact was found.
    fn resolve_contacts(&mut self) -> bool {
        let mut any = false;
        self.touched.fill(false);
        let pinned = self.network.pinned();
        for (p, _) in pinned.iter().enumerate().filter(|(_, pin)| !**pin) {
            let from = self.scratch.x[p];
            for c in &self.colliders {
                let contact = c
                    .entry(from, self.state.x[p], self.margin)
                    .or_else(|| c.push_out(self.state.x[p], self.margin));
                if let Some((q, n)) = contact {
                    any = true;
                    self.touched[p] = true;
                    self.state.x[p] = q;
                    // The velocity becomes the motion the contact allowed over the step, so that a
                    // particle held at an edge does not keep a velocity into the obstacle; then the
                    // approaching normal part goes and friction acts on the tangential part.
                    let v = (q - from) * (1.0 / self.dt);
                    let vn = v.dot(n).min(0.0);
                    let vt = v - n * v.dot(n);
                    let st = vt.length();
                    let scale = if st > 0.0 { (1.0 - self.friction * (-vn) / st).max(0.0) } else { 0.0 };
                    self.state.v[p] = vt * scale + n * v.dot(n).max(0.0);
                }
            }
        }
        any
    }
}

/// The analytic colliders as the implicit solve sees them: a particle whose path enters a collider
/// (grown by the margin) is in contact at its entry point, one that ends inside, or within one more
/// margin of it, at the nearest point of the grown surface; Coulomb friction `friction`, no restitution
/// (the split's response removes the approaching normal velocity too).
#[derive(Debug, Clone, Copy)]
pub struct AnalyticContacts<'a> {
    pub colliders: &'a [Collider],
    pub margin: f64,
    pub friction: f64,
}

impl ContactModel<DVec3> for AnalyticContacts<'_> {
    fn contacts(&mut self, start: &[DVec3], end: &[DVec3], out: &mut Vec<Contact<DVec3>>) {
        for (p, (&from, &to)) in start.iter().zip(end).enumerate() {
            // The earliest entry along the path; failing that, the deepest end inside a collider. Keys
            // order entries (0, distance along the path) before push-outs (1, −depth).
            let mut best: Option<((u8, f64), DVec3, DVec3)> = None;
            for c in self.colliders {
                // A particle within twice the margin is reported too, so that a resting contact is
                // found at once and keeps its regime; its plane stays at the margin.
                let found = match c.entry(from, to, self.margin) {
                    Some((q, n)) => Some(((0, q.distance(from)), q, n)),
                    None => c
                        .push_out(to, 2.0 * self.margin)
                        .map(|(q, n)| ((1, -q.distance(to)), q - n * self.margin, n)),
                };
                if let Some(f) = found
                    && best.is_none_or(|b| f.0 < b.0)
                {
                    best = Some(f);
                }
            }
            if let Some((_, point, normal)) = best {
                out.push(Contact {
                    coordinate: p as u32,
                    normal,
                    point,
                    static_friction: self.friction,
                    kinetic_friction: self.friction,
                    restitution: 0.0,
                });
            }
        }
    }
}
