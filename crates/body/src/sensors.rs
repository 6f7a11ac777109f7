//! Sensors as plain values: one [`Sensors`] reading per model and step, filled into caller-owned
//! storage, a delay line for delayed sensing, and the thesis's sensor catalogue (spec §5.5) as
//! functions of a reading.
//!
//! Conventions: joint and actuator angles are in the model's convention (counter-clockwise for a
//! model facing +x, clockwise for one facing −x), zero in the initial pose. Positions, velocities
//! and body angles are world values (x right, y up, counter-clockwise), body angles unwrapped.

use crate::error::BodyError;
use crate::skeleton::{Role, Side};
use crate::world::{Touch, World};

/// Bodies the catalogue asks about, found once from roles and names.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BodyLayout {
    /// Feet [left, right] (role `Foot`).
    pub feet: [Option<usize>; 2],
    /// Hands [left, right] (role `Hand`).
    pub hands: [Option<usize>; 2],
    pub pelvis: Option<usize>,
    pub head: Option<usize>,
    /// The body named `abdomen`, if any.
    pub abdomen: Option<usize>,
    /// Per foot [left, right]: where the ankle (the joint that hangs the foot from the leg) sits
    /// relative to the foot's centre, in the foot's own frame (the initial pose's offset), m.
    pub ankles: [Option<[f64; 2]>; 2],
}

/// One contact: body `body` of this model touches `other`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Contact {
    pub body: usize,
    pub other: Touch,
}

/// Which feet are on the ground.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Support {
    #[default]
    None,
    Left,
    Right,
    Both,
}

/// Everything the sensors of one model read at one instant. Build with [`Sensors::new`] and refill
/// with [`World::sense`]: refilling allocates nothing.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensors {
    pub model: usize,
    pub step: u64,
    /// Seconds.
    pub time: f64,
    /// Per joint: angle (rad) and rate (rad/s), child relative to parent.
    pub joint_angle: Vec<f64>,
    pub joint_rate: Vec<f64>,
    /// Per actuator: angle, rate and the torque applied in the last physics step (N·m; for the
    /// implicit modes the PD torque evaluated at the current state).
    pub actuator_angle: Vec<f64>,
    pub actuator_rate: Vec<f64>,
    pub actuator_torque: Vec<f64>,
    /// Per body: centre of mass (m), its velocity (m/s), world angle (rad) and angular velocity
    /// (rad/s).
    pub body_position: Vec<[f64; 2]>,
    pub body_velocity: Vec<[f64; 2]>,
    pub body_angle: Vec<f64>,
    pub body_angular_velocity: Vec<f64>,
    /// Per body: touches the ground.
    pub on_ground: Vec<bool>,
    /// Every touching contact of this model's bodies (ground, other models, own bodies where groups
    /// allow), up to the reserved capacity; `contacts_truncated` says when some were left out.
    pub contacts: Vec<Contact>,
    pub contacts_truncated: bool,
    /// Centre of mass of the figure (bodies with role `Prop` left out), m, and its velocity, m/s.
    pub com: [f64; 2],
    pub com_velocity: [f64; 2],
    /// Figure mass, kg.
    pub mass: f64,
    pub support: Support,
    /// Horizontal distance from the support foot's centre (the mean of both feet on double support)
    /// to the centre of mass, m, signed along the facing direction; `None` in flight.
    pub com_over_support: Option<f64>,
    /// Inclination of the ground under the centre of mass, rad, positive rising in the facing
    /// direction (0 without a ground): what a walker sees of the terrain it is on.
    pub ground_slope: f64,
    pub layout: BodyLayout,
    /// +1 facing +x, −1 facing −x.
    pub facing: f64,
}

impl Sensors {
    /// Storage for readings of `model`, sized for its skeleton.
    pub fn new(world: &World, model: usize) -> Result<Self, BodyError> {
        let sk = world.skeleton(model)?;
        let (nb, nj, na) = (sk.n_bodies(), sk.n_joints(), sk.n_actuators());
        let find = |role: Role, side: Side| {
            (0..nb).find(|&b| sk.body(b).role == role && (side == Side::Centre || sk.body(b).side == side))
        };
        let feet = [find(Role::Foot, Side::Left), find(Role::Foot, Side::Right)];
        // Body angles are zero in the initial pose, so the file's offset is the one in the foot's frame.
        let ankle = |foot: Option<usize>| {
            let (f, j) = (foot?, sk.parent_joint(foot?)?);
            let (anchor, centre) = (sk.desc().joints[j].anchor, sk.body(f).centre);
            Some([anchor.0 - centre.0, anchor.1 - centre.1])
        };
        let layout = BodyLayout {
            feet,
            hands: [find(Role::Hand, Side::Left), find(Role::Hand, Side::Right)],
            pelvis: find(Role::Pelvis, Side::Centre),
            head: find(Role::Head, Side::Centre),
            abdomen: sk.body_index("abdomen"),
            ankles: [ankle(feet[0]), ankle(feet[1])],
        };
        Ok(Sensors {
            model,
            step: 0,
            time: 0.0,
            joint_angle: vec![0.0; nj],
            joint_rate: vec![0.0; nj],
            actuator_angle: vec![0.0; na],
            actuator_rate: vec![0.0; na],
            actuator_torque: vec![0.0; na],
            body_position: vec![[0.0; 2]; nb],
            body_velocity: vec![[0.0; 2]; nb],
            body_angle: vec![0.0; nb],
            body_angular_velocity: vec![0.0; nb],
            on_ground: vec![false; nb],
            contacts: Vec::with_capacity(8 * nb),
            contacts_truncated: false,
            com: [0.0; 2],
            com_velocity: [0.0; 2],
            mass: 0.0,
            support: Support::None,
            com_over_support: None,
            ground_slope: 0.0,
            layout,
            facing: sk.sign(),
        })
    }

    /// Whether `body` touches `other`.
    pub fn touches(&self, body: usize, other: Touch) -> bool {
        self.contacts.iter().any(|c| c.body == body && c.other == other)
    }

    /// Every value finite.
    pub fn all_finite(&self) -> bool {
        let f = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let f2 = |v: &[[f64; 2]]| v.iter().all(|x| x[0].is_finite() && x[1].is_finite());
        f(&self.joint_angle)
            && f(&self.joint_rate)
            && f(&self.actuator_angle)
            && f(&self.actuator_rate)
            && f(&self.actuator_torque)
            && f2(&self.body_position)
            && f2(&self.body_velocity)
            && f(&self.body_angle)
            && f(&self.body_angular_velocity)
            && self.com.iter().chain(&self.com_velocity).all(|x| x.is_finite())
    }
}

impl World {
    /// Reads model `sensors.model` into `sensors` (no allocation).
    pub fn sense(&self, sensors: &mut Sensors) -> Result<(), BodyError> {
        let view = self.sense_raw(sensors.model)?;
        let sk = view.skeleton();
        if sensors.body_position.len() != sk.n_bodies() || sensors.actuator_angle.len() != sk.n_actuators() {
            return Err(BodyError::Layout {
                what: "sensors",
                expected: sk.n_bodies(),
                found: sensors.body_position.len(),
            });
        }
        let sign = view.sign();
        sensors.step = view.steps();
        sensors.time = view.time();
        for j in 0..sk.n_joints() {
            let (q, qd) = view.joint_angle_rate(j);
            sensors.joint_angle[j] = sign * q;
            sensors.joint_rate[j] = sign * qd;
        }
        for a in 0..sk.n_actuators() {
            let (q, qd) = view.actuator_angle_rate(a);
            sensors.actuator_angle[a] = sign * q;
            sensors.actuator_rate[a] = sign * qd;
            sensors.actuator_torque[a] = view.actuator_torque(a);
        }
        let (mut mass, mut c, mut v) = (0.0, [0.0; 2], [0.0; 2]);
        for b in 0..sk.n_bodies() {
            let (x, xd, th, om) = view.body_state(b);
            sensors.body_position[b] = x;
            sensors.body_velocity[b] = xd;
            sensors.body_angle[b] = th;
            sensors.body_angular_velocity[b] = om;
            let d = sk.body(b);
            if d.role != Role::Prop {
                mass += d.mass;
                for k in 0..2 {
                    c[k] += d.mass * x[k];
                    v[k] += d.mass * xd[k];
                }
            }
        }
        sensors.mass = mass;
        sensors.com = [c[0] / mass, c[1] / mass];
        sensors.com_velocity = [v[0] / mass, v[1] / mass];

        sensors.on_ground.fill(false);
        sensors.contacts.clear();
        sensors.contacts_truncated = false;
        view.for_each_contact(|body, other| {
            if other == Touch::Ground {
                sensors.on_ground[body] = true;
            }
            if sensors.contacts.len() < sensors.contacts.capacity() {
                sensors.contacts.push(Contact { body, other });
            } else {
                sensors.contacts_truncated = true;
            }
        });
        let down = |f: Option<usize>| f.is_some_and(|b| sensors.on_ground[b]);
        let [fl, fr] = sensors.layout.feet;
        sensors.support = match (down(fl), down(fr)) {
            (true, true) => Support::Both,
            (true, false) => Support::Left,
            (false, true) => Support::Right,
            (false, false) => Support::None,
        };
        let foot_x = |f: Option<usize>| f.map(|b| sensors.body_position[b][0]);
        let x_ref = match sensors.support {
            Support::Both => foot_x(fl).zip(foot_x(fr)).map(|(a, b)| 0.5 * (a + b)),
            Support::Left => foot_x(fl),
            Support::Right => foot_x(fr),
            Support::None => None,
        };
        sensors.com_over_support = x_ref.map(|x| sensors.facing * (sensors.com[0] - x));
        sensors.ground_slope =
            self.settings().ground.map_or(0.0, |g| sensors.facing * g.slope_at(sensors.com[0]));
        Ok(())
    }
}

/// Readings delayed by a whole number of steps: push the current reading every step, read the one
/// from `delay` steps ago. Storage is a ring of `delay + 1` readings filled by copy.
#[derive(Debug, Clone)]
pub struct SensorDelay {
    ring: Vec<Sensors>,
    next: usize,
    filled: usize,
}

impl SensorDelay {
    /// A delay line of `delay` steps for readings shaped like `template`.
    pub fn new(template: &Sensors, delay: usize) -> Self {
        Self { ring: vec![template.clone(); delay + 1], next: 0, filled: 0 }
    }

    pub fn delay(&self) -> usize {
        self.ring.len() - 1
    }

    /// Stores the current reading (copied into reserved storage).
    pub fn push(&mut self, reading: &Sensors) {
        self.ring[self.next].clone_from(reading);
        self.next = (self.next + 1) % self.ring.len();
        self.filled = (self.filled + 1).min(self.ring.len());
    }

    /// The reading from `delay` pushes ago; before that many pushes, the oldest one. `None` before
    /// the first push.
    pub fn delayed(&self) -> Option<&Sensors> {
        if self.filled == 0 {
            return None;
        }
        let n = self.ring.len();
        let back = self.filled - 1; // readings available before the newest
        let k = (self.next + n - 1 - back.min(n - 1)) % n;
        Some(&self.ring[k])
    }
}

/// The thesis's sensors (spec §5.5). Each returns a real number, 0 meaning inactive (§5.1).
pub mod catalogue {
    use super::{Sensors, Support};
    use crate::world::Touch;

    /// How S-LAND combines its two tests (spec §5.5 note: OR reproduces Table 6.3).
    #[derive(Debug, Clone, Copy, PartialEq, Eq)]
    pub enum LandCombine {
        Or,
        And,
    }

    fn on(active: bool) -> f64 {
        if active { 1.0 } else { 0.0 }
    }

    /// S-COGH: 1 if the centre of mass is lower than `min_height` m.
    pub fn cog_low(s: &Sensors, min_height: f64) -> f64 {
        on(s.com[1] < min_height)
    }

    /// S-TRUNKANG: the trunk–pelvis angle itself (the waist joint, rad); non-zero when not straight.
    pub fn trunk_angle(s: &Sensors, waist_joint: usize) -> f64 {
        s.joint_angle[waist_joint]
    }

    /// d of SIMBICON-style feedback: how far the centre of mass is ahead of foot `side`'s centre,
    /// m, in the facing direction (0 for a model without that foot). Continuous, not a switch.
    pub fn com_offset(s: &Sensors, side: usize) -> f64 {
        s.layout.feet[side].map_or(0.0, |f| s.facing * (s.com[0] - s.body_position[f][0]))
    }

    /// The world position of foot `side`'s ankle, m (`None` for a model without that foot or
    /// whose foot hangs from no joint).
    pub fn ankle_position(s: &Sensors, side: usize) -> Option<[f64; 2]> {
        let (f, r) = (s.layout.feet[side]?, s.layout.ankles[side]?);
        let (c, (sin, cos)) = (s.body_position[f], s.body_angle[f].sin_cos());
        Some([c[0] + cos * r[0] - sin * r[1], c[1] + sin * r[0] + cos * r[1]])
    }

    /// d of SIMBICON (Yin, Loken & van de Panne 2007): how far the centre of mass is ahead of the
    /// ankle of foot `side` (the stance ankle), m, in the facing direction; 0 without that ankle.
    /// Continuous, not a switch.
    pub fn com_ahead_of_ankle(s: &Sensors, side: usize) -> f64 {
        ankle_position(s, side).map_or(0.0, |a| s.facing * (s.com[0] - a[0]))
    }

    /// S-FOOTDOWN(f), anima's: 1 if foot `side` touches the ground — SIMBICON's foot strike, which
    /// ends a swing.
    pub fn foot_down(s: &Sensors, side: usize) -> f64 {
        on(s.layout.feet[side].is_some_and(|f| s.on_ground[f]))
    }

    /// v of SIMBICON-style feedback: the centre of mass's horizontal speed in the facing direction,
    /// m/s. Continuous, not a switch.
    pub fn com_speed(s: &Sensors) -> f64 {
        s.facing * s.com_velocity[0]
    }

    /// The inclination of the ground under the centre of mass, anima's: rad, positive uphill in the
    /// facing direction ([`Sensors::ground_slope`]). Continuous, not a switch; a walker's feedback
    /// targets can lean into a slope with it and leave the flat gait as it is.
    pub fn ground_slope(s: &Sensors) -> f64 {
        s.ground_slope
    }

    /// The trunk's rotation rate, anima's: the abdomen's angular velocity (the pelvis's without an
    /// abdomen), rad/s, positive backwards (counter-clockwise for a model facing +x). Continuous, not
    /// a switch; in the backflip's flight it measures how fast the somersault turns.
    pub fn trunk_rate(s: &Sensors) -> f64 {
        s.layout.abdomen.or(s.layout.pelvis).map_or(0.0, |b| s.facing * s.body_angular_velocity[b])
    }

    /// S-FOOTUP(f): 1 if foot `side` (0 left, 1 right) has no ground contact.
    pub fn foot_up(s: &Sensors, side: usize) -> f64 {
        on(s.layout.feet[side].is_some_and(|f| !s.on_ground[f]))
    }

    /// S-COGAHEAD(f): 1 if the centre of mass is more than `p` m ahead of foot `side`'s centre.
    pub fn cog_ahead(s: &Sensors, side: usize, p: f64) -> f64 {
        on(s.layout.feet[side].is_some() && com_offset(s, side) > p)
    }

    /// S-LAND(f): foot `side` touches the ground, OR (AND) the forward centre-of-mass velocity
    /// exceeds `p` m/s.
    pub fn landing(s: &Sensors, side: usize, p: f64, combine: LandCombine) -> f64 {
        let touch = s.layout.feet[side].is_some_and(|f| s.on_ground[f]);
        let fast = s.facing * s.com_velocity[0] > p;
        on(match combine {
            LandCombine::Or => touch || fast,
            LandCombine::And => touch && fast,
        })
    }

    fn feet_x(s: &Sensors) -> Option<(f64, f64)> {
        let [l, r] = s.layout.feet;
        Some((s.facing * s.body_position[l?][0], s.facing * s.body_position[r?][0]))
    }

    /// S-FALLFWD: 1 if the pelvis is more than `tol` m ahead of the foremost foot.
    pub fn falling_forward(s: &Sensors, tol: f64) -> f64 {
        let (Some((l, r)), Some(p)) = (feet_x(s), s.layout.pelvis) else { return 0.0 };
        on(s.facing * s.body_position[p][0] - l.max(r) > tol)
    }

    /// S-FALLBACK: 1 if the pelvis is more than `tol` m behind the hindmost foot.
    pub fn falling_backward(s: &Sensors, tol: f64) -> f64 {
        let (Some((l, r)), Some(p)) = (feet_x(s), s.layout.pelvis) else { return 0.0 };
        on(l.min(r) - s.facing * s.body_position[p][0] > tol)
    }

    /// Standard gravity, m/s², for the capture point's pendulum ([`capture_outside`]).
    pub const CAPTURE_GRAVITY: f64 = 9.81;

    /// The capture point along the facing direction, m: x + v/ω with ω = √(g/h), h the centre of
    /// mass's height above the lower foot. It is where a linear inverted pendulum with the figure's
    /// centre of mass would have to put its foot to come to rest (Pratt et al. 2006). `None` for a
    /// model without both feet.
    pub fn capture_point(s: &Sensors) -> Option<f64> {
        let [Some(l), Some(r)] = s.layout.feet else { return None };
        let height = s.com[1] - s.body_position[l][1].min(s.body_position[r][1]);
        let omega = (CAPTURE_GRAVITY / height.max(0.1)).sqrt();
        Some(s.facing * (s.com[0] + s.com_velocity[0] / omega))
    }

    /// anima's: 1 if the capture point ([`capture_point`]) lies more than `margin` m behind the
    /// hindmost ankle or ahead of the foremost one: the figure cannot come to rest on the feet it
    /// has and must step. Read in the facing direction.
    pub fn capture_outside(s: &Sensors, margin: f64) -> f64 {
        let ankles = [0, 1].map(|f| ankle_position(s, f).map(|a| s.facing * a[0]));
        let ([Some(a), Some(b)], Some(c)) = (ankles, capture_point(s)) else { return 0.0 };
        on(c < a.min(b) - margin || c > a.max(b) + margin)
    }

    /// S-FOOTONHANDS: 1 if one foot of the acrobat touches both hands of the pusher (the model and
    /// hand bodies of the `pusher` reading).
    pub fn foot_on_hands(acrobat: &Sensors, pusher: &Sensors) -> f64 {
        let [Some(hl), Some(hr)] = pusher.layout.hands else { return 0.0 };
        let (hl, hr) =
            (Touch::Body { model: pusher.model, body: hl }, Touch::Body { model: pusher.model, body: hr });
        on(acrobat.layout.feet.iter().flatten().any(|&f| acrobat.touches(f, hl) && acrobat.touches(f, hr)))
    }

    /// S-FLIPBRAKE: 1 if the abdomen is above the head and more than `margin` m behind it (the
    /// thesis's 0.1 m, "to its left" for a model facing +x), using body centres.
    pub fn flip_brake(s: &Sensors, margin: f64) -> f64 {
        let (Some(a), Some(h)) = (s.layout.abdomen, s.layout.head) else { return 0.0 };
        let (pa, ph) = (s.body_position[a], s.body_position[h]);
        on(pa[1] > ph[1] && s.facing * pa[0] < s.facing * ph[0] - margin)
    }

    /// S-BOTHFEET: 1 if both feet touch the ground.
    pub fn both_feet_down(s: &Sensors) -> f64 {
        on(s.support == Support::Both)
    }
}
