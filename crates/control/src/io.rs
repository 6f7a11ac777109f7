//! What the controller reads and writes each iteration: sensor values in through [`SensorInput`],
//! weighted targets out into caller-owned [`Targets`].

use serde::{Deserialize, Serialize};

/// A sensor the controller asks about: the caller computes its return value (0 = inactive, spec
/// §5.1) from the body's state and the sensor's current parameters.
#[derive(Debug, Clone, Copy)]
pub struct SensorQuery<'a> {
    /// Index in [`crate::Controller::sensors`]; stable for a controller, so a caller may bind each
    /// index to a function once and dispatch on it.
    pub id: usize,
    /// `fall_fwd` for a sensor of the sensor set; `W-LEGS/T2` for a transition's own sensor.
    pub name: &'a str,
    /// The computation, e.g. `cog_ahead`.
    pub kind: &'a str,
    /// Its fixed arguments, e.g. `["right"]`.
    pub args: &'a [String],
    /// Its parameters' current values, in file order.
    pub params: &'a [f64],
}

/// The frame of an angle target (spec §4.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Frame {
    /// Joint angle: child relative to parent (the thesis's only kind).
    #[default]
    Parent,
    /// The child body's angle in the world.
    World,
}

/// Where the controller's inputs come from. Implemented by the scene layer over the body's sensor
/// readings; in tests by a closure `FnMut(&SensorQuery) -> f64`.
pub trait SensorInput {
    /// The return value of one sensor in this iteration (0 = inactive).
    fn sensor(&mut self, query: &SensorQuery<'_>) -> f64;

    /// The measured angle of `actuator` in `frame`, rad. Used once when a pose switches an actuator
    /// from a NoTorque/DampingOnly entry to an angle, to start the blend from where the joint is
    /// (spec §6.5). `None` (the default) starts from the new angle at once.
    fn actuator_angle(&mut self, actuator: usize, frame: Frame) -> Option<f64> {
        let _ = (actuator, frame);
        None
    }
}

impl<F: FnMut(&SensorQuery<'_>) -> f64> SensorInput for F {
    fn sensor(&mut self, query: &SensorQuery<'_>) -> f64 {
        self(query)
    }
}

/// What one signal asks of an actuator (spec §4.5).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum TargetKind {
    /// Track this angle, rad.
    Angle(f64),
    /// No torque from this signal: skipped in the average.
    NoTorque,
    /// Damping only: T = −kd θ̇.
    DampingOnly,
    /// SIMBICON's stance hip: the torque τ = −τ_torso − τ_swing that holds the actuator's parent
    /// body (the torso) at world angle `angle` (rad) with actuator `swing` (an index in the
    /// controller's `actuators`) applying τ_swing. The body computes it at every physics sub-step.
    Torso { angle: f64, swing: usize },
}

/// One target for one actuator from one running machine, with the machine's weight P_ME.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TargetSignal {
    /// Index in the controller's `actuators` list.
    pub actuator: usize,
    pub target: TargetKind,
    pub frame: Frame,
    /// P_ME of Eq. 5.1.
    pub weight: f64,
    /// The sending machine (index in [`crate::Controller::machines`]).
    pub machine: usize,
}

/// The signals of one iteration, in machine execution order. Storage is reserved by
/// [`crate::Controller::new_targets`] for the largest possible iteration, so the step never
/// allocates.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Targets {
    pub(crate) signals: Vec<TargetSignal>,
}

impl Targets {
    /// Storage for at most `capacity` signals per iteration.
    pub fn with_capacity(capacity: usize) -> Self {
        Self { signals: Vec::with_capacity(capacity) }
    }

    pub fn signals(&self) -> &[TargetSignal] {
        &self.signals
    }

    pub fn capacity(&self) -> usize {
        self.signals.capacity()
    }

    /// The signals for one actuator.
    pub fn for_actuator(&self, actuator: usize) -> impl Iterator<Item = &TargetSignal> + '_ {
        self.signals.iter().filter(move |s| s.actuator == actuator)
    }

    /// Eqs. 5.1–5.2 for one actuator: the weighted mean of `torque(signal)` over its signals,
    /// computed incrementally, T ← (S·T + Tᵢ·P)/(S + P), S ← S + P. `torque` returns `None` for a
    /// signal that adds nothing (NoTorque); a signal that would leave S + P = 0 is skipped. `None`
    /// when no signal counted. The body crate does this itself with its PD law; this is the
    /// reference the tests and a torque-free caller use.
    pub fn weighted_mean(
        &self,
        actuator: usize,
        mut torque: impl FnMut(&TargetSignal) -> Option<f64>,
    ) -> Option<f64> {
        let (mut t, mut s) = (0.0, 0.0);
        for sig in self.for_actuator(actuator) {
            let Some(ti) = torque(sig) else { continue };
            if s + sig.weight > 0.0 {
                t = (s * t + ti * sig.weight) / (s + sig.weight);
                s += sig.weight;
            }
        }
        (s > 0.0).then_some(t)
    }

    /// The weighted mean of the angle targets of one actuator (NoTorque and DampingOnly left out).
    /// For PD servos with one gain and no clamping, the averaged torque of Eq. 5.1 equals the torque
    /// towards this angle when every signal is an angle.
    pub fn mean_angle(&self, actuator: usize) -> Option<f64> {
        self.weighted_mean(actuator, |s| match s.target {
            TargetKind::Angle(a) => Some(a),
            _ => None,
        })
    }
}
