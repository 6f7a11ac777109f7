//! Contact with static surfaces inside an implicit step: velocity constraints in the Newton solve.
//!
//! A coordinate in contact has its velocity at the end of the step constrained, the way Baraff & Witkin
//! (1998, §5.3) constrain cloth particles: its normal component along the surface's outward normal n
//! is prescribed, w·n = u, and while it sticks its tangential components are too (w_t = 0 on a static
//! surface). The solve filters those directions out (S_i = I − n nᵀ, or 0 when sticking) and imposes
//! the prescribed change z_i on them, so every Newton iterate meets the constraints exactly. Here u is
//! the smallest normal velocity that leaves the end-of-step position on the outer side of the surface's
//! tangent plane, x(t + h) = X₁ + c w: u = −n·(X₁ − p)/c, p a surface point moved out by the contact's
//! thickness.
//!
//! With a restitution e > 0 a coordinate arriving at a surface (not in contact at the end of the last
//! step) bounces where and when it hits: moving at v_a = −n·v₀ toward the surface from a gap g, it hits
//! at t* = g/v_a into the step and ends it e v_a (h − t*) out from the tangent plane, leaving with e v_a,
//! as a free particle bouncing at t* would. The first version prescribed e v_a as the end velocity w·n
//! instead, which leaves the particle wherever the method's position update X₁ + c w takes it,
//! unrelated to when it hit: a free particle hitting two thirds into a 0.05 s step with e = 0.5 ended
//! 84 mm up where its bounce leaves it 25 mm up (`tests/contact_bounce.rs`). On Oliveira's drapes at
//! 1/60–1/240 s the bounce in place lowered the error against the converged model in eight of nine
//! cases when this was introduced (on the sphere at 1/60 s from 23.4 to 16.4 mm, each against its own
//! converged run). `docs/reproduction/oliveira-implicit.md` holds the errors as they are now. A
//! coordinate already in contact that approaches (it rests, or it chatters) leaves with at least
//! −e (n·v₀) as before.
//!
//! The constraint force follows from the residual: at a solution M (w − W₀) = η (f + F_c), so after each
//! iterate F_c = (M (w − W₀) − η f)/η on the constrained coordinates. An active set decides the
//! regimes between Newton iterations (Coulomb friction at the velocity level):
//!
//! - a free coordinate whose iterate ends beyond the surface becomes active, sticking if μ_s > 0;
//! - an active one whose constraint would pull (F_c·n < 0) is released;
//! - a sticking one whose tangential force exceeds μ_s F_n slides, its friction force μ_k F_n against
//!   the direction the constraint held it in; a sliding one feels −μ_k F_n t̂ (t̂ the direction of its
//!   tangential velocity, F_n from the last iterate) as an applied force, and sticks again when its
//!   tangential velocity turns against that force.
//!
//! That is [`Friction::ActiveSet`], the default. [`Friction::Smoothed`] replaces the stick and slide
//! regimes by one: every active contact slides, under friction smoothed below a sliding speed ε and
//! taken into the system matrix as the damping it is, so only the normal constraint's activations and
//! releases remain as regime changes.
//!
//! After the last Newton iteration every reported contact is checked once more and a coordinate that
//! would still end beyond its tangent plane has its inward normal velocity removed, so that no step
//! ends inside an object (up to the planar approximation, which the caller's model refreshes every
//! step).

#![allow(
    clippy::needless_range_loop,
    reason = "the loops walk several per-coordinate arrays in step; the index form mirrors the formulas"
)]

use crate::Coord;

/// A coordinate in contact with a static surface, as a [`ContactModel`] reports it for one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact<C> {
    pub coordinate: u32,
    /// Unit outward normal of the surface.
    pub normal: C,
    /// A point of the surface (locally a plane) moved out along the normal by the contact's thickness:
    /// the step keeps n·(x(t + h) − point) ≥ 0.
    pub point: C,
    /// Coulomb coefficients: sticking holds while |F_t| ≤ μ_s F_n; sliding feels μ_k F_n.
    pub static_friction: f64,
    pub kinetic_friction: f64,
    /// Normal restitution e: an approaching coordinate leaves with a normal velocity of at least
    /// −e (n·v(t)). 0 is a perfectly inelastic contact.
    pub restitution: f64,
}

/// Where a system meets static objects: the geometry the implicit step asks for contacts.
pub trait ContactModel<C: Coord> {
    /// The contacts of the motion from `start` (positions at t) to `end` (a Newton iterate's positions
    /// at t + h): every free coordinate whose path crosses a surface or that ends inside, or within the
    /// model's reach of, one; at most one contact per coordinate, appended to `out` (which the caller
    /// clears) in increasing coordinate order.
    fn contacts(&mut self, start: &[C], end: &[C], out: &mut Vec<Contact<C>>);
}

/// The regime of one contact within a step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Regime {
    /// Reported, not constrained (separating, or released).
    Free,
    /// Normal velocity prescribed, tangential free under kinetic friction.
    Slide,
    /// Whole velocity prescribed.
    Stick,
}

/// What became of one contact in the last step ([`crate::Stepper::contact_reports`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactReport<C> {
    pub coordinate: u32,
    pub regime: Regime,
    /// The force the constraint exerted, N (zero when free).
    pub force: C,
}

/// One contact during a step.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Slot<C> {
    pub contact: Contact<C>,
    pub regime: Regime,
    /// Whether the constraint was imposed in the last solve (its reaction is meaningful).
    pub imposed: bool,
    /// Not in contact at the end of the last step: it arrives in this one.
    pub arrival: bool,
    /// Released this step because it pulled: it is activated again only by a clear violation.
    pub released: bool,
    /// Regime changes this step (capped, so that an active set cannot cycle for ever).
    pub switches: u8,
    /// The normal velocity the constraint prescribes.
    pub target: f64,
    /// Kinetic friction force on a sliding coordinate, N.
    pub friction: C,
    /// The last reaction F_c, N.
    pub reaction: C,
    /// [`Friction::Smoothed`]: the lagged friction coefficient μ F_n f₁(s)/s of the last update, N s/m
    /// (the friction is −damping · w_t).
    pub damping: f64,
}

/// Where a step starts: positions, velocities and the step, for the contacts' bounces.
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepStart<'a, C> {
    pub x: &'a [C],
    pub v: &'a [C],
    pub h: f64,
}

/// Tangential speed below which a sliding contact counts as stopped, m/s.
const SPEED_FLOOR: f64 = 1e-6;

/// Regime changes allowed per contact and step.
const MAX_SWITCHES: u8 = 4;

/// A violation larger than this fraction of the target speed scale re-activates a released contact.
const REACTIVATE: f64 = 1e-3;

/// How friction enters the contacts of an implicit step ([`crate::Stepper::set_friction`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Friction {
    /// Coulomb friction by an active set: a contact sticks (its whole velocity prescribed) until its
    /// tangential reaction exceeds μ_s F_n, then slides under −μ_k F_n t̂ as an applied force, and sticks
    /// again when its velocity turns against that force. Exact Coulomb at the velocity level, but the
    /// regimes are a fixed point inside Newton: on the drapes at users' sizes a quarter of the contacts
    /// change regime at every iteration, chattering between stick and slide near zero sliding speed.
    #[default]
    ActiveSet,
    /// Coulomb friction smoothed below a sliding speed ε and lagged (as in Li et al. 2020, IPC §5): every
    /// active contact slides, its friction F = −μ F_n f₁(s)/s · w_t with s = |w_t|, f₁(s) = 1 above ε
    /// and s/ε (2 − s/ε) below it, F_n and the coefficient taken from the last iterate. The coefficient's
    /// η times enters the system matrix's diagonal, so the solve sees friction as the damping it is and
    /// Newton can converge on it; sticking becomes creep slower than ε. No regimes to chatter.
    ///
    /// Measured on the 65² drapes of `cargo xtask bench --scale` (3 s at 1/60 s, ε = 1 mm/s, each model
    /// against its own converged run at 1/960 s; `cargo run --release -p anima-lab --example
    /// scale_probe` with `FRICTION_SMOOTHING`), active set → smoothed:
    ///
    /// | drape | Newton a step | CG a step | RMS error | band of the converged runs | ms a step |
    /// |---|---|---|---|---|---|
    /// | Bunny | 4.93 → 3.69 | 19.0 → 16.0 | 17.2 → 10.5 mm | 7.0 → 0.02 mm | 44.3, 47.1 → 42.3, 41.2 |
    /// | sphere | 4.97 → 3.55 | 18.4 → 24.1 | 19.5 → 6.1 mm | 1.7 → 0.00 mm | 46.0, 48.9 → 44.4, 42.7 |
    ///
    /// (the band: two converged runs with gravity × (1 ± 10⁻⁹); the times: two runs of each, alternated,
    /// 2 threads.) The drapes' sensitivity came from the regimes' switching; smoothed, the error is a
    /// discretisation error that a finer step lowers, not noise. A step costs less than its Newton count
    /// says: a sticking particle, filtered out of the active set's solve, stays in this one under a drag
    /// up to 2 μ F_n/ε, and on the sphere CG then takes 6.8 iterations a solve instead of 3.7. ε = 1 cm/s
    /// saves a little more (Newton 3.38 on the sphere) and errs 27.6 mm: the creep it allows is error.
    ///
    /// It does not pay at the larger drapes, which is why they keep the active set. Measured on the same
    /// scenes at 129² and 257² (3 s, one run of each model on 2 threads of a loaded machine, so the times
    /// are rough; `V=129` or `V=257`), active set → smoothed:
    ///
    /// | drape | Newton a step | CG a solve | ms a step |
    /// |---|---|---|---|
    /// | Bunny 129² | 4.94 → 4.75 | 4.1 → 6.9 | 119 → 164 |
    /// | sphere 129² | 4.97 → 3.65 | 3.6 → 8.1 | 120 → 154 |
    /// | Bunny 257² | 5.06 → 4.83 | 4.6 → 10.2 | 1058 → 1043 |
    /// | sphere 257² | 4.97 → 4.52 | 5.2 → 16.2 | 1121 → 2155 |
    ///
    /// The drag that stands in for sticking scales with a particle's weight, as the square of the edge
    /// length, while a spring's stiffness E A⁰/L grows as the edges shorten: at 129² it is an eighth as
    /// strong against the springs as at 65². A resting cloth's in-plane motion, which the active set holds,
    /// is then left to a light drag, and CG's iterations a solve grow with the mesh where the active
    /// set's stay near flat. The Bunny drapes also fold more under it (self-collision repulsions 361 →
    /// 9 613 at 129²).
    Smoothed {
        /// ε, m/s: the sliding speed below which friction turns into a stiff viscous drag.
        speed_m_s: f64,
    },
}

/// The contacts of the step in progress and the filter they make.
#[derive(Debug, Clone)]
pub(crate) struct ContactState<C: Coord> {
    pub found: Vec<Contact<C>>,
    pub slots: Vec<Slot<C>>,
    /// Per coordinate, its slot + 1 (0: none).
    pub slot_of: Vec<u32>,
    /// Per coordinate, S_i.
    pub filter: Vec<C::Block>,
    /// Per coordinate, the prescribed change along the constrained directions.
    pub z: Vec<C>,
    /// Coordinates whose end position had to be corrected after the last iteration.
    pub late: usize,
    /// The coordinates in contact at the end of the step, their normals and the normal velocity each
    /// must leave with at least (0, or the restitution's bounce).
    pub clamp: Vec<(u32, C, f64)>,
    /// Per coordinate, the regime, reaction and friction its contact ended the last step with: a contact
    /// found again starts from them, so a resting or sliding contact keeps its regime from step to step
    /// instead of starting free (or sticking) every step.
    pub last_regime: Vec<Regime>,
    pub last_reaction: Vec<C>,
    pub last_friction: Vec<C>,
    /// The coordinates whose `last_*` entries are set.
    pub last_active: Vec<u32>,
    pub friction_model: Friction,
}

impl<C: Coord> ContactState<C> {
    pub fn new() -> Self {
        Self {
            found: Vec::new(),
            slots: Vec::new(),
            slot_of: Vec::new(),
            filter: Vec::new(),
            z: Vec::new(),
            late: 0,
            clamp: Vec::new(),
            last_regime: Vec::new(),
            last_reaction: Vec::new(),
            last_friction: Vec::new(),
            last_active: Vec::new(),
            friction_model: Friction::ActiveSet,
        }
    }

    /// Starts a step: no contacts, every prescribed coordinate filtered out.
    pub fn begin(&mut self, prescribed: &[bool]) {
        let n = prescribed.len();
        self.slots.clear();
        self.slot_of.clear();
        self.slot_of.resize(n, 0);
        self.filter.clear();
        self.filter.extend(prescribed.iter().map(|&p| C::block_identity(if p { 0.0 } else { 1.0 })));
        self.z.clear();
        self.z.resize(n, C::default());
        self.late = 0;
        self.clamp.clear();
        if self.last_regime.len() != n {
            self.last_regime.clear();
            self.last_regime.resize(n, Regime::Free);
            self.last_reaction.clear();
            self.last_reaction.resize(n, C::default());
            self.last_friction.clear();
            self.last_friction.resize(n, C::default());
            self.last_active.clear();
        }
    }

    /// Ends a step: remembers the regimes its contacts ended in.
    pub fn end(&mut self) {
        for &i in &self.last_active {
            self.last_regime[i as usize] = Regime::Free;
        }
        self.last_active.clear();
        for s in &self.slots {
            if s.regime != Regime::Free {
                let i = s.contact.coordinate as usize;
                self.last_regime[i] = s.regime;
                self.last_reaction[i] = s.reaction;
                self.last_friction[i] = s.friction;
                self.last_active.push(s.contact.coordinate);
            }
        }
    }

    /// Forgets the regimes of the last step (the state was changed from outside).
    pub fn forget(&mut self) {
        for &i in &self.last_active {
            self.last_regime[i as usize] = Regime::Free;
        }
        self.last_active.clear();
    }

    /// Merges the contacts just found: new ones start free, known ones take the fresh geometry.
    pub fn merge(&mut self, prescribed: &[bool]) {
        for c in &self.found {
            let i = c.coordinate as usize;
            if prescribed[i] {
                continue;
            }
            match self.slot_of[i] {
                0 => {
                    // A contact of the last step starts in the regime it ended in, with its reaction and
                    // friction as first estimates (not yet imposed in this step's solve).
                    self.slots.push(Slot {
                        contact: *c,
                        regime: self.last_regime[i],
                        arrival: self.last_regime[i] == Regime::Free,
                        imposed: false,
                        released: false,
                        switches: 0,
                        target: 0.0,
                        friction: self.last_friction[i],
                        reaction: self.last_reaction[i],
                        damping: 0.0,
                    });
                    self.slot_of[i] = self.slots.len() as u32;
                }
                s => self.slots[s as usize - 1].contact = *c,
            }
        }
    }

    /// The active-set update between Newton iterations, from the iterate `w`, the affine map to the
    /// end position x(t + h) = `x1` + `c`·w, the step's `start`, and the residual `b` = η (f + friction)
    /// − M (w − W₀) just computed at `w` (before filtering). Sets the filter, the prescribed changes and
    /// the friction forces (returned through `friction_into_b`, to be added to b times η).
    /// Returns whether any regime changed.
    pub fn update(&mut self, w: &[C], x1: &[C], c: f64, start: StepStart<'_, C>, b: &[C], eta: f64) -> bool {
        let tangential_speed_floor = SPEED_FLOOR;
        let smoothing = match self.friction_model {
            Friction::ActiveSet => None,
            Friction::Smoothed { speed_m_s } => Some(speed_m_s.max(SPEED_FLOOR)),
        };
        let mut changed = false;
        for slot in &mut self.slots {
            let i = slot.contact.coordinate as usize;
            let n = slot.contact.normal;
            // The geometric bound decides whether the contact is needed; once it is, an approaching
            // coordinate leaves with at least its restitution.
            let geometric = -n.dot(x1[i] - slot.contact.point) / c;
            let approach = n.dot(start.v[i]).min(0.0);
            let bounce = -slot.contact.restitution * approach;
            let wn = n.dot(w[i]);
            if slot.imposed {
                // The reaction the constraint supplied at this iterate: F_c = −b/η − (the friction force
                // applied last iteration, which b does not hold yet).
                slot.reaction = b[i] * (-1.0 / eta) - slot.friction;
            }
            let fn_ = slot.reaction.dot(n);
            let can_switch = slot.switches < MAX_SWITCHES;
            let mut next = slot.regime;
            match slot.regime {
                Regime::Free if smoothing.is_some() => {
                    let violation = geometric - wn;
                    let scale = geometric.abs().max(tangential_speed_floor);
                    if violation > 0.0 && (!slot.released || violation > REACTIVATE * scale) {
                        next = Regime::Slide;
                    }
                }
                Regime::Stick | Regime::Slide if smoothing.is_some() => {
                    if slot.imposed && fn_ < 0.0 {
                        next = Regime::Free;
                        slot.released = true;
                    } else {
                        next = Regime::Slide;
                    }
                }
                Regime::Free => {
                    let violation = geometric - wn;
                    let scale = geometric.abs().max(tangential_speed_floor);
                    if violation > 0.0 && (!slot.released || violation > REACTIVATE * scale) {
                        next = if slot.contact.static_friction > 0.0 { Regime::Stick } else { Regime::Slide };
                    }
                }
                Regime::Stick | Regime::Slide if slot.imposed && fn_ < 0.0 => {
                    next = Regime::Free;
                    slot.released = true;
                }
                Regime::Stick if slot.imposed => {
                    let ft = slot.reaction - n * fn_;
                    let limit = slot.contact.static_friction * fn_;
                    let size = ft.dot(ft).sqrt();
                    if size > limit {
                        next = Regime::Slide;
                        // Friction keeps acting where the constraint held, at the kinetic level.
                        slot.friction = ft * (slot.contact.kinetic_friction * fn_ / size);
                    }
                }
                Regime::Slide if slot.imposed => {
                    let wt = w[i] - n * wn;
                    let speed = wt.dot(wt).sqrt();
                    let mu = slot.contact.kinetic_friction * fn_.max(0.0);
                    if speed > tangential_speed_floor {
                        let turned = slot.friction.dot(wt) > 0.0;
                        if turned && slot.contact.static_friction > 0.0 {
                            next = Regime::Stick;
                        } else {
                            slot.friction = wt * (-mu / speed);
                        }
                    } else if slot.contact.static_friction > 0.0 {
                        next = Regime::Stick;
                    }
                }
                _ => {}
            }
            if next != slot.regime && can_switch {
                slot.regime = next;
                slot.switches += 1;
                changed = true;
            }
            slot.damping = 0.0;
            if slot.regime != Regime::Slide {
                slot.friction = C::default();
            } else if let Some(eps) = smoothing {
                // The lagged smoothed friction at this iterate: its coefficient goes into the matrix.
                let wt = w[i] - n * wn;
                let speed = wt.dot(wt).sqrt();
                let f1_over_s = if speed < eps { (2.0 - speed / eps) / eps } else { 1.0 / speed };
                slot.damping = slot.contact.kinetic_friction * fn_.max(0.0) * f1_over_s;
                slot.friction = wt * -slot.damping;
            }
            // With no restitution the bound is the geometric one alone: its velocity may still point
            // into the surface at the end of the step (the position is on it), which the step's end
            // removes (`clamp`).
            let target = if bounce > 0.0 && slot.arrival {
                // The bounce at the time of impact: e v_a (h − t*) out from the tangent plane.
                let speed = -approach;
                let gap = n.dot(start.x[i] - slot.contact.point).max(0.0);
                let hit = (gap / speed).min(start.h);
                geometric + slot.contact.restitution * speed * (start.h - hit) / c
            } else if bounce > 0.0 {
                geometric.max(bounce)
            } else {
                geometric
            };
            slot.target = target;
            // The filter and the prescribed change.
            let identity = C::block_identity(1.0);
            let nn = C::block_outer(n, n);
            (self.filter[i], self.z[i]) = match slot.regime {
                Regime::Free => (identity, C::default()),
                Regime::Slide => (C::block_combine(identity, 1.0, nn, -1.0), n * (target - wn)),
                Regime::Stick => (C::block_identity(0.0), n * target - w[i]),
            };
            slot.imposed = slot.regime != Regime::Free;
        }
        changed
    }

    /// The contacts of the last step.
    pub fn reports(&self) -> impl Iterator<Item = ContactReport<C>> + '_ {
        self.slots.iter().map(|s| ContactReport {
            coordinate: s.contact.coordinate,
            regime: s.regime,
            force: if s.regime == Regime::Free { C::default() } else { s.reaction },
        })
    }

    /// Active contacts now.
    pub fn active(&self) -> usize {
        self.slots.iter().filter(|s| s.regime != Regime::Free).count()
    }
}
