//! The objectives an optimisation spec can name, and the figures and worlds they are measured on
//! (Nunes 2006, spec §7.4, §7.6): the thesis's humanoid, thrower and backflip pair in the experiments'
//! world; the walking, throwing and backflip evaluations as trackers a run loop feeds one control step
//! at a time ([`WalkTracker`], [`ThrowTracker`], [`FlipTracker`]); whole evaluations ([`walk`],
//! [`throw`], [`backflip`]) with their outcomes and fitness. `anima optimise`, a character scene's run
//! and the Python package's `walk` measure with these; the thesis's experiments (`anima-lab`'s
//! `nunes`) re-export them.

use anima_body::{Actuation, BuiltinSkeleton, PdMode, Placement, SolverSettings, World, WorldSettings};
use anima_character::{Character, CharacterError, procedures};
use anima_control::Controller;

/// The control step of the thesis, seconds (spec §3.1: 20 iterations = 1 s).
pub const DT: f64 = 0.05;

/// The world every experiment runs in: Δt = 0.05 s, g = 9.81, ground μ = 1, with `substeps` physics
/// steps per control step (one Rapier sub-step each).
pub fn world_settings(substeps: u32) -> WorldSettings {
    WorldSettings {
        dt: DT,
        substeps,
        solver: SolverSettings { iterations: 1, pgs_iterations: 1, sleeping: false },
        ..WorldSettings::thesis()
    }
}

/// The actuation the experiments use: implicit springs (backward Euler, no torque cap), gains ×100
/// (`docs/body.md`: the thesis's gains cannot hold the body under g = 9.81).
pub fn actuation() -> Actuation {
    Actuation { mode: PdMode::ImplicitSpring, gain_scale: 100.0, torque_limit_rad: 1.0, brake_rad_s: 4.0 }
}

/// Physics sub-steps per 0.05 s control step in the experiments (h = 0.0125 s).
pub const SUBSTEPS: u32 = 4;

/// A humanoid standing on the ground, driven by `controller`.
pub fn humanoid_character(controller: Controller) -> Result<Character, CharacterError> {
    humanoid_with(controller, actuation())
}

/// [`humanoid_character`] on another ground (a slope or steps of the robustness protocol).
pub fn humanoid_on(controller: Controller, ground: anima_body::Ground) -> Result<Character, CharacterError> {
    let mut world = World::new(WorldSettings { ground: Some(ground), ..world_settings(SUBSTEPS) })?;
    let sk = BuiltinSkeleton::Humanoid.load().with_actuation(actuation())?;
    world.add_model(&sk, Placement::OnGround { dx: 0.0 })?;
    Character::new(world, controller, procedures(), &[])
}

/// A humanoid with `actuation` standing on the ground, driven by `controller`.
pub fn humanoid_with(controller: Controller, actuation: Actuation) -> Result<Character, CharacterError> {
    let mut world = World::new(world_settings(SUBSTEPS))?;
    let sk = BuiltinSkeleton::Humanoid.load().with_actuation(actuation)?;
    world.add_model(&sk, Placement::OnGround { dx: 0.0 })?;
    Character::new(world, controller, procedures(), &[])
}

/// Parses a controller with the character procedures.
pub fn parse(text: &str) -> Result<Controller, CharacterError> {
    Ok(Controller::from_ron(text, &procedures())?)
}

/// A push on a body during a walk (spec §8.1.6, Fig. 6.8): `force` N applied for `duration`
/// iterations from iteration `at`, on the head (the thesis's pushes) or on the torso at the height of
/// the centre of mass (SIMBICON's).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Push {
    pub at: u64,
    pub duration: u64,
    pub force: [f64; 2],
    pub target: PushTarget,
}

/// Where a [`Push`] is applied.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PushTarget {
    /// The head's centre.
    Head,
    /// The abdomen, at the height of the whole body's centre of mass (Yin et al. 2007 push the torso
    /// there, so the push moves the body without turning it).
    TorsoAtCom,
}

impl Push {
    /// A horizontal push of `impulse` N·s (positive forward, along +x) on the head, spread evenly over
    /// `duration` iterations from iteration `at`.
    pub fn impulse(impulse: f64, at: u64, duration: u64) -> Self {
        Self { at, duration, force: [impulse / (duration as f64 * DT), 0.0], target: PushTarget::Head }
    }

    /// The same push on the torso at the height of the centre of mass.
    pub fn torso(impulse: f64, at: u64, duration: u64) -> Self {
        Self { target: PushTarget::TorsoAtCom, ..Self::impulse(impulse, at, duration) }
    }
}

/// How a walk ended.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct WalkOutcome {
    /// Iterations simulated (all of them unless it fell or stopped).
    pub iterations: u64,
    /// Horizontal distance the whole-body centre of mass travelled, m (spec §7.6).
    pub distance: f64,
    pub fell: bool,
    pub stopped: bool,
}

impl WalkOutcome {
    /// The thesis's walking fitness: the distance, or 0 after a fall or stop (spec §7.6).
    pub fn fitness(&self) -> f64 {
        if self.fell || self.stopped { 0.0 } else { self.distance }
    }
}

/// The walking evaluation's failure tests (spec §7.6 \[GAP\] proposals).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WalkRules {
    /// Fallen when the pelvis centre is lower than this, m.
    pub min_pelvis_height: f64,
    /// Stopped when the centre of mass advances less than `min_advance` m in `window` iterations
    /// (checked after the first `window` iterations); `window = 0` turns the test off.
    pub window: u64,
    pub min_advance: f64,
    /// Stop the run at the first failure (the optimisation does; a long run to see how far it goes
    /// does too).
    pub stop_on_failure: bool,
}

impl Default for WalkRules {
    fn default() -> Self {
        Self { min_pelvis_height: 0.7, window: 100, min_advance: 0.05, stop_on_failure: true }
    }
}

/// Whether the model has fallen: a body other than a foot touches the ground, or the pelvis is low
/// (above the ground under it, when there is one).
pub fn fallen(s: &anima_body::Sensors, rules: &WalkRules, ground: Option<&anima_body::Ground>) -> bool {
    let feet = s.layout.feet;
    let body_down = s.on_ground.iter().enumerate().any(|(b, &g)| g && !feet.contains(&Some(b)));
    let low = s.layout.pelvis.is_some_and(|p| {
        let [x, y] = s.body_position[p];
        y - ground.map_or(0.0, |g| g.height_at(x)) < rules.min_pelvis_height
    });
    body_down || low || !s.all_finite()
}

/// The walking evaluation (spec §7.4, §7.6) of a character's first model, one control step at a time:
/// fallen and stopped tests and the distance walked. [`walk`] runs it on the thesis's humanoid; a
/// character scene's run uses it as is.
#[derive(Debug, Clone)]
pub struct WalkTracker {
    rules: WalkRules,
    x0: f64,
    history: std::collections::VecDeque<f64>,
    fell: bool,
    stopped: bool,
    done: u64,
}

impl WalkTracker {
    /// Starts at the character's present state.
    pub fn new(c: &Character, rules: &WalkRules) -> Self {
        Self {
            rules: *rules,
            x0: c.env.sensors[0].com[0],
            history: std::collections::VecDeque::with_capacity(rules.window as usize + 1),
            fell: false,
            stopped: false,
            done: 0,
        }
    }

    /// Takes in the state after a control step; `true` when the rules end the evaluation here.
    pub fn observe(&mut self, c: &Character) -> bool {
        self.done += 1;
        let s = &c.env.sensors[0];
        if !self.fell && fallen(s, &self.rules, c.env.world.settings().ground.as_ref()) {
            self.fell = true;
        }
        if self.rules.window > 0 {
            self.history.push_back(s.com[0]);
            if self.history.len() > self.rules.window as usize {
                let old = self.history.pop_front().unwrap_or(s.com[0]);
                if !self.stopped && s.com[0] - old < self.rules.min_advance {
                    self.stopped = true;
                }
            }
        }
        self.rules.stop_on_failure && (self.fell || self.stopped)
    }

    pub fn outcome(&self, c: &Character) -> WalkOutcome {
        let distance = c.env.sensors[0].com[0] - self.x0;
        WalkOutcome { iterations: self.done, distance, fell: self.fell, stopped: self.stopped }
    }
}

/// Applies the pushes due at control step `k` (0-based) to model 0's head.
pub fn apply_pushes(c: &mut Character, pushes: &[Push], k: u64) -> Result<(), CharacterError> {
    if pushes.is_empty() {
        return Ok(());
    }
    for p in pushes {
        if !(k >= p.at && k < p.at + p.duration) {
            continue;
        }
        let s = &c.env.sensors[0];
        let hit = match p.target {
            PushTarget::Head => s.layout.head.map(|h| (h, s.body_position[h])),
            PushTarget::TorsoAtCom => s.layout.abdomen.map(|t| (t, [s.body_position[t][0], s.com[1]])),
        };
        if let Some((body, at)) = hit {
            c.env.world.apply_force(0, body, p.force, at)?;
        }
    }
    Ok(())
}

/// Runs a walker for `iterations` control steps (spec §7.4): fitness per §7.6. `observe` sees the
/// character after every step (for strobe pictures); pass `|_| ()` otherwise.
pub fn walk(
    controller: Controller,
    iterations: u64,
    rules: &WalkRules,
    pushes: &[Push],
    observe: impl FnMut(&Character),
) -> Result<WalkOutcome, CharacterError> {
    walk_character(humanoid_character(controller)?, iterations, rules, pushes, observe)
}

/// [`walk`] for any character whose first model walks (another figure, another world).
pub fn walk_character(
    mut c: Character,
    iterations: u64,
    rules: &WalkRules,
    pushes: &[Push],
    mut observe: impl FnMut(&Character),
) -> Result<WalkOutcome, CharacterError> {
    let mut tracker = WalkTracker::new(&c, rules);
    for k in 0..iterations {
        // Ended early on a stop asked from outside: the caller that asked discards the outcome.
        if crate::interrupt::requested() {
            break;
        }
        apply_pushes(&mut c, pushes, k)?;
        c.step()?;
        observe(&c);
        if tracker.observe(&c) {
            break;
        }
    }
    Ok(tracker.outcome(&c))
}

/// The thrower (both hands welded to the ball) standing on the ground, driven by `controller`.
pub fn thrower_character(controller: Controller) -> Result<Character, CharacterError> {
    let mut world = World::new(world_settings(SUBSTEPS))?;
    let sk = BuiltinSkeleton::Thrower.load().with_actuation(actuation())?;
    world.add_model(&sk, Placement::OnGround { dx: 0.0 })?;
    Character::new(world, controller, procedures(), &[])
}

/// The basket of the throw (spec §8.3, \[GAP\]: the thesis gives no geometry): hoop centre, m, and
/// the hoop's radius. Eq. 6.1 measures the distance to the point 0.25 m above the hoop centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Basket {
    pub hoop: [f64; 2],
    pub radius: f64,
}

/// anima's basket: 2.5 m in front of the thrower, hoop 2.5 m high, radius 0.2 m \[GAP\].
pub const BASKET: Basket = Basket { hoop: [2.5, 2.5], radius: 0.2 };

/// How a throw ended.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ThrowOutcome {
    /// Highest ball centre, m.
    pub h_max: f64,
    /// Closest approach of the ball centre to the point 0.25 m above the hoop, m.
    pub d_min: f64,
    /// The ball fell through the hoop (crossed the hoop's height downwards within its radius).
    pub scored: bool,
    pub fell: bool,
    pub released_at: Option<u64>,
    pub iterations: u64,
}

/// anima's cap on the height term of Eq. 6.1 \[RECON\]: H_max counts up to 0.5 m above the point
/// Eq. 6.1 aims at (the point 0.25 m above the hoop). The thesis's weak arms (spec §8.3.3: fitness
/// 11.042 means H_max ≈ 3.1 m with a near-zero Δ_min) could not throw much higher than the basket;
/// our stiffer arms (gains ×100) throw the ball 12 m high, where H_max/3 outweighs a 1 m miss and
/// the literal Eq. 6.1 rewards missing high. With the cap, height pays only up to a lob that drops
/// into the hoop from above, and Δ_min decides the rest.
pub fn throw_height_cap(basket: &Basket) -> f64 {
    basket.hoop[1] + 0.25 + 0.5
}

impl ThrowOutcome {
    /// Eq. 6.1: 10 + H_max/3 − Δ_min, 0 when the thrower falls (spec §7.6).
    pub fn fitness(&self) -> f64 {
        if self.fell { 0.0 } else { 10.0 + self.h_max / 3.0 - self.d_min }
    }

    /// Eq. 6.1 with H_max counted up to `cap` m (anima's \[RECON\] switch, [`throw_height_cap`]);
    /// `None` is the literal Eq. 6.1.
    pub fn fitness_capped(&self, cap: Option<f64>) -> f64 {
        if self.fell { 0.0 } else { 10.0 + self.h_max.min(cap.unwrap_or(f64::INFINITY)) / 3.0 - self.d_min }
    }
}

/// The throwing evaluation (Eq. 6.1) of a character whose first model holds the ball, one control step
/// at a time: highest point, nearest approach to the aimed point, whether it went through the hoop.
#[derive(Debug, Clone)]
pub struct ThrowTracker {
    basket: Basket,
    ball: usize,
    target: [f64; 2],
    prev: [f64; 2],
    out: ThrowOutcome,
}

impl ThrowTracker {
    /// Starts at the character's present state; `None` when its first model has no body `ball`.
    pub fn new(c: &Character, basket: &Basket) -> Result<Option<Self>, CharacterError> {
        let Some(ball) = c.env.world.skeleton(0)?.body_index("ball") else { return Ok(None) };
        Ok(Some(Self {
            basket: *basket,
            ball,
            target: [basket.hoop[0], basket.hoop[1] + 0.25],
            prev: c.env.sensors[0].body_position[ball],
            out: ThrowOutcome {
                h_max: f64::NEG_INFINITY,
                d_min: f64::INFINITY,
                scored: false,
                fell: false,
                released_at: None,
                iterations: 0,
            },
        }))
    }

    /// Takes in the state after a control step; `true` when the throw is over (the thrower fell, or the
    /// ball touched the ground after its release).
    pub fn observe(&mut self, c: &Character) -> bool {
        let (basket, ball, target, out) = (&self.basket, self.ball, self.target, &mut self.out);
        out.iterations += 1;
        let s = &c.env.sensors[0];
        let p = s.body_position[ball];
        out.h_max = out.h_max.max(p[1]);
        out.d_min = out.d_min.min(((p[0] - target[0]).powi(2) + (p[1] - target[1]).powi(2)).sqrt());
        let prev = self.prev;
        if prev[1] >= basket.hoop[1] && p[1] < basket.hoop[1] {
            let t = (prev[1] - basket.hoop[1]) / (prev[1] - p[1]);
            let x = prev[0] + t * (p[0] - prev[0]);
            out.scored |= (x - basket.hoop[0]).abs() < basket.radius;
        }
        self.prev = p;
        let feet = s.layout.feet;
        let body_down =
            s.on_ground.iter().enumerate().any(|(b, &g)| g && b != ball && !feet.contains(&Some(b)));
        let low =
            s.layout.pelvis.is_some_and(|pv| s.body_position[pv][1] < WalkRules::default().min_pelvis_height);
        if body_down || low || !s.all_finite() {
            out.fell = true;
            return true;
        }
        out.released_at = c.env.released_at;
        out.released_at.is_some() && s.on_ground[ball]
    }

    pub fn outcome(&self) -> ThrowOutcome {
        self.out
    }
}

/// Runs a throw until the ball touches the ground after its release (at most `max_iterations`).
pub fn throw(
    controller: Controller,
    basket: &Basket,
    max_iterations: u64,
    mut observe: impl FnMut(&Character),
) -> Result<ThrowOutcome, CharacterError> {
    let mut c = thrower_character(controller)?;
    let mut tracker = ThrowTracker::new(&c, basket)?.expect("the thrower has a ball");
    for _ in 0..max_iterations {
        // Ended early on a stop asked from outside: the caller that asked discards the outcome.
        if crate::interrupt::requested() {
            break;
        }
        c.step()?;
        observe(&c);
        if tracker.observe(&c) {
            break;
        }
    }
    Ok(tracker.outcome())
}

pub const FLIP_SPACING: f64 = 0.9;

/// The backflip pair (spec §3.5.2): the acrobat facing +x at x = 0 and the pusher facing −x
/// `spacing` m in front of it, driven by one controller with model aliases `acrobat` and `pusher`.
pub fn backflip_character(controller: Controller, spacing: f64) -> Result<Character, CharacterError> {
    let mut world = World::new(world_settings(SUBSTEPS))?;
    let acrobat = BuiltinSkeleton::Humanoid.load().with_actuation(actuation())?;
    let pusher = BuiltinSkeleton::Pusher.load().with_actuation(actuation())?;
    world.add_model(&acrobat, Placement::OnGround { dx: 0.0 })?;
    world.add_model(&pusher, Placement::OnGround { dx: spacing })?;
    Character::new(world, controller, procedures(), &["acrobat", "pusher"])
}

/// How a backflip ended (spec §8.4.6, §8.5 item 8).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FlipOutcome {
    /// The acrobat's abdomen rotation from the start, rad, positive backwards (counter-clockwise for
    /// a model facing +x): the largest reached, and the value at the end.
    pub max_rotation: f64,
    pub final_rotation: f64,
    /// Iteration at which S-FOOTONHANDS first fired (k₀ of spec §8.4.5).
    pub foot_on_hands_at: Option<u64>,
    /// Iterations at which the pusher's E3 (the push) and the acrobat's E6 began.
    pub push_at: Option<u64>,
    pub acrobat_e6_at: Option<u64>,
    /// Iteration at which both acrobat feet were back on the ground after the flight.
    pub landed_at: Option<u64>,
    /// The acrobat's highest pelvis centre, m.
    pub max_pelvis_height: f64,
    /// At the end: pelvis height (m), and whether a body of the acrobat other than a foot has
    /// touched the ground (a fall; the run stops there).
    pub final_pelvis_height: f64,
    pub touched_down: bool,
    /// The pusher fell (a body other than a foot on the ground) at some point.
    pub pusher_fell: bool,
    /// At the end: no fall, both feet on the ground, the pelvis above 0.7 m and the trunk within
    /// 0.5 rad of upright (one full turn).
    pub standing: bool,
    pub iterations: u64,
}

impl FlipOutcome {
    /// A complete flip: at least 2π − 0.5 rad backwards, landed on the feet, standing at the end.
    pub fn flipped(&self) -> bool {
        // `standing` already excludes a fall.
        self.max_rotation >= 2.0 * std::f64::consts::PI - 0.5 && self.standing
    }
}

/// The backflip's evaluation (spec §8.4) of a two-model character (acrobat, pusher), one control step
/// at a time: the acrobat's turn, the timing of the push, the landing, falls.
#[derive(Debug, Clone)]
pub struct FlipTracker {
    pusher_machine: Option<usize>,
    acrobat_machine: Option<usize>,
    abdomen: usize,
    pelvis: usize,
    a0: f64,
    airborne: bool,
    k: u64,
    out: FlipOutcome,
}

impl FlipTracker {
    /// Starts at the character's present state; `None` unless it has two models and the first has an
    /// abdomen and a pelvis.
    pub fn new(c: &Character) -> Option<Self> {
        if c.env.sensors.len() < 2 {
            return None;
        }
        let machine = |name: &str| c.controller.machine_index(name);
        let s0 = &c.env.sensors[0];
        let (abdomen, pelvis) = (s0.layout.abdomen?, s0.layout.pelvis?);
        Some(Self {
            pusher_machine: machine("B-PUSHER"),
            acrobat_machine: machine("B-ACRO-BODY"),
            abdomen,
            pelvis,
            a0: s0.body_angle[abdomen],
            airborne: false,
            k: 0,
            out: FlipOutcome {
                max_rotation: 0.0,
                final_rotation: 0.0,
                foot_on_hands_at: None,
                push_at: None,
                acrobat_e6_at: None,
                landed_at: None,
                max_pelvis_height: f64::NEG_INFINITY,
                final_pelvis_height: 0.0,
                touched_down: false,
                pusher_fell: false,
                standing: false,
                iterations: 0,
            },
        })
    }

    /// Takes in the state after a control step; `true` when the acrobat touched down with a body other
    /// than a foot (or went non-finite), which ends the evaluation.
    pub fn observe(&mut self, c: &Character) -> bool {
        let k = self.k;
        self.k += 1;
        let out = &mut self.out;
        out.iterations = k + 1;
        let (a, p) = (&c.env.sensors[0], &c.env.sensors[1]);
        let state = |m: Option<usize>| m.and_then(|m| c.controller.machines()[m].current_state());
        if out.foot_on_hands_at.is_none() && anima_body::sensors::catalogue::foot_on_hands(a, p) > 0.0 {
            out.foot_on_hands_at = Some(k);
        }
        if out.push_at.is_none() && state(self.pusher_machine) == Some(2) {
            out.push_at = Some(k);
        }
        if out.acrobat_e6_at.is_none() && state(self.acrobat_machine) == Some(5) {
            out.acrobat_e6_at = Some(k);
        }
        let rot = a.facing * (a.body_angle[self.abdomen] - self.a0);
        out.max_rotation = out.max_rotation.max(rot);
        out.final_rotation = rot;
        out.max_pelvis_height = out.max_pelvis_height.max(a.body_position[self.pelvis][1]);
        out.final_pelvis_height = a.body_position[self.pelvis][1];
        if out.acrobat_e6_at.is_some() && a.on_ground.iter().all(|g| !g) {
            self.airborne = true;
        }
        let down = |s: &anima_body::Sensors| {
            let feet = s.layout.feet;
            s.on_ground.iter().enumerate().any(|(b, &g)| g && !feet.contains(&Some(b)))
        };
        out.touched_down |= down(a);
        out.pusher_fell |= down(p);
        if self.airborne && out.landed_at.is_none() && a.support == anima_body::Support::Both {
            out.landed_at = Some(k);
        }
        if out.touched_down || !a.all_finite() || !p.all_finite() {
            out.touched_down |= !a.all_finite();
            return true;
        }
        false
    }

    /// The outcome with the character as it is now: standing is judged on the final state.
    pub fn outcome(&self, c: &Character) -> FlipOutcome {
        let mut out = self.out;
        let a = &c.env.sensors[0];
        let upright = (out.final_rotation - 2.0 * std::f64::consts::PI).abs() < 0.5;
        out.standing = !out.touched_down
            && out.landed_at.is_some()
            && a.support == anima_body::Support::Both
            && upright
            && out.final_pelvis_height > 0.7;
        out
    }
}

/// Runs the backflip for `iterations` control steps; `observe` sees the character after each.
pub fn backflip(
    controller: Controller,
    spacing: f64,
    iterations: u64,
    mut observe: impl FnMut(&Character),
) -> Result<FlipOutcome, CharacterError> {
    let mut c = backflip_character(controller, spacing)?;
    let mut tracker = FlipTracker::new(&c).expect("the acrobat has an abdomen and a pelvis");
    for _ in 0..iterations {
        // Ended early on a stop asked from outside: the caller that asked discards the outcome.
        if crate::interrupt::requested() {
            break;
        }
        c.step()?;
        observe(&c);
        if tracker.observe(&c) {
            break;
        }
    }
    Ok(tracker.outcome(&c))
}
