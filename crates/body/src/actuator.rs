//! What a controller asks of the actuators: target signals, their weighted averaging (Nunes 2006
//! Eqs. 5.1–5.2) and the PD torque of one signal (Eq. 2.1).
//!
//! A controller pushes [`Signal`]s into a model's [`Commands`] — one per running machine whose pose
//! names the actuator — and they are held until it changes them. At every physics sub-step each
//! signal's torque is re-evaluated from the current state (spec §4.3) and averaged.

use serde::{Deserialize, Serialize};

use crate::error::BodyError;

/// What one pose asks of one actuator (spec §4.5).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Target {
    /// Track this angle, radians: T = kp (θd − θ) − kd θ̇.
    Angle(f64),
    /// Apply no torque: the signal is skipped in the average (it adds no weight).
    NoTorque,
    /// Damping only, T = −kd θ̇ (zero in the ODE-style mode, whose damping is the brake).
    DampingOnly,
    /// SIMBICON's stance hip (Yin, Loken & van de Panne 2007): no PD target of its own. The actuator
    /// holds the body it pushes against — its parent, the torso for a hip — at world angle `angle`
    /// (rad, the model's convention), and the other hip `swing` (an actuator index of the same model)
    /// shares the work: τ = −τ_torso − τ_swing, where τ_torso = kp (angle − θ_torso) − kd ω_torso is
    /// the PD torque, with this actuator's gains, that would hold the torso, and τ_swing the torque
    /// `swing` applies in the same physics step. The two hips then exert τ_torso on the torso
    /// between them (each hip acts −τ on its parent). Re-evaluated at every physics sub-step and
    /// applied as an explicit torque in every PD mode, clamped like any signal (§4.4); the torso is
    /// measured with its world angle and rate, not through the joint.
    Torso { angle: f64, swing: usize },
}

/// The frame an [`Target::Angle`] is measured in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum TargetFrame {
    /// The joint angle: the child relative to its parent (the thesis's only kind).
    #[default]
    Parent,
    /// The child body's angle in the world, θd(joint) = θd(world) − θ(parent, world); an extension
    /// for SIMBICON-like balance. For a body-pair actuator it means the same as `Parent`.
    World,
}

/// One target for one actuator from one source (a running state machine) with that source's weight.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Signal {
    pub actuator: usize,
    pub target: Target,
    #[serde(default)]
    pub frame: TargetFrame,
    /// P_ME of Eq. 5.1, the weight of the sending machine.
    pub weight: f64,
}

impl Signal {
    /// An angle target in the joint (parent) frame with weight 1.
    pub fn angle(actuator: usize, angle: f64) -> Self {
        Self { actuator, target: Target::Angle(angle), frame: TargetFrame::Parent, weight: 1.0 }
    }
}

/// The signals a model's actuators hold. Storage is reserved once for `max_signals_per_actuator`
/// signals per actuator, so pushing never allocates; a push beyond that is refused.
#[derive(Debug, Clone)]
pub struct Commands {
    signals: Vec<Signal>,
    n_actuators: usize,
    capacity: usize,
}

impl Commands {
    pub fn new(n_actuators: usize, max_signals_per_actuator: usize) -> Self {
        let capacity = n_actuators * max_signals_per_actuator.max(1);
        Self { signals: Vec::with_capacity(capacity), n_actuators, capacity }
    }

    /// Removes every signal: every actuator goes limp (no signal = no torque), except those with a
    /// fixed target and the ODE-style brakes.
    pub fn clear(&mut self) {
        self.signals.clear();
    }

    /// Adds a signal. Refused (and nothing changes) for an unknown actuator, a negative or non-finite
    /// weight, a non-finite angle, or when the reserved storage is full.
    pub fn push(&mut self, signal: Signal) -> Result<(), CommandError> {
        if signal.actuator >= self.n_actuators {
            return Err(CommandError::NoSuchActuator {
                actuator: signal.actuator,
                n_actuators: self.n_actuators,
            });
        }
        if !(signal.weight >= 0.0 && signal.weight.is_finite()) {
            return Err(CommandError::BadWeight(signal.weight));
        }
        if let Target::Angle(a) | Target::Torso { angle: a, .. } = signal.target
            && !a.is_finite()
        {
            return Err(CommandError::BadAngle(a));
        }
        if let Target::Torso { swing, .. } = signal.target
            && (swing >= self.n_actuators || swing == signal.actuator)
        {
            return Err(CommandError::BadSwing { actuator: signal.actuator, swing });
        }
        if self.signals.len() >= self.capacity {
            return Err(CommandError::Full { capacity: self.capacity });
        }
        self.signals.push(signal);
        Ok(())
    }

    /// Replaces every signal by one angle target per actuator with weight 1 (`angles[i]` for
    /// actuator i): the PD-held pose of a standing figure.
    pub fn hold(&mut self, angles: &[f64]) -> Result<(), CommandError> {
        if angles.len() != self.n_actuators {
            return Err(CommandError::PoseLength { expected: self.n_actuators, found: angles.len() });
        }
        self.clear();
        for (actuator, &a) in angles.iter().enumerate() {
            self.push(Signal::angle(actuator, a))?;
        }
        Ok(())
    }

    pub fn signals(&self) -> &[Signal] {
        &self.signals
    }

    pub fn n_actuators(&self) -> usize {
        self.n_actuators
    }
}

/// A signal that [`Commands::push`] refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CommandError {
    #[error("no actuator {actuator} (the model has {n_actuators})")]
    NoSuchActuator { actuator: usize, n_actuators: usize },
    #[error("a signal weight must be finite and not negative, found {0}")]
    BadWeight(f64),
    #[error("a target angle must be finite, found {0}")]
    BadAngle(f64),
    #[error("the commands hold at most {capacity} signals; raise `max_signals_per_actuator`")]
    Full { capacity: usize },
    #[error(
        "a torso signal on actuator {actuator} needs another actuator of the model as its swing, found {swing}"
    )]
    BadSwing { actuator: usize, swing: usize },
    #[error("a pose needs one angle per actuator: expected {expected}, found {found}")]
    PoseLength { expected: usize, found: usize },
}

impl From<CommandError> for BodyError {
    fn from(e: CommandError) -> Self {
        BodyError::Settings(e.to_string())
    }
}

/// Eq. 5.1–5.2 accumulators of one actuator for explicit torques: T_parcial and S_pesos.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct TorqueAverage {
    pub torque: f64,
    pub weight: f64,
}

impl TorqueAverage {
    /// T ← (S·T + T_i·P) / (S + P), S ← S + P. A signal whose weight would leave S + P = 0 is skipped.
    #[inline]
    pub fn add(&mut self, torque: f64, weight: f64) {
        let s = self.weight + weight;
        if s > 0.0 {
            self.torque = (self.weight * self.torque + torque * weight) / s;
            self.weight = s;
        }
    }
}

/// The linear summary of an actuator's signals for the implicit and stable-PD modes, where torques
/// cannot be evaluated signal by signal: without clamping, the weighted mean of the signals' PD
/// torques is kp·(W_angle/W)·(θ̄ − θ) − kd·θ̇ with θ̄ the weighted mean of the angle targets.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct TargetMix {
    /// Σ weights of every signal that is not NoTorque.
    pub weight: f64,
    /// Σ weights of the angle signals.
    pub angle_weight: f64,
    /// Σ weight · angle of the angle signals.
    pub weighted_angle: f64,
}

impl TargetMix {
    /// Stiffness factor W_angle / W (0 without signals).
    pub fn stiffness_factor(&self) -> f64 {
        if self.weight > 0.0 { self.angle_weight / self.weight } else { 0.0 }
    }

    /// Damping factor: 1 while any signal asks for torque, else 0 (limp).
    pub fn damping_factor(&self) -> f64 {
        if self.weight > 0.0 { 1.0 } else { 0.0 }
    }

    /// θ̄, the weighted mean target (0 without angle signals, where it has no effect).
    pub fn target(&self) -> f64 {
        if self.angle_weight > 0.0 { self.weighted_angle / self.angle_weight } else { 0.0 }
    }
}

/// PD torque of one signal, Eq. 2.1, clamped to ±max_torque (spec §4.4: each signal is clamped before
/// averaging). `kd` is 0 in the ODE-style mode. `None` for NoTorque, and for a torso signal, whose
/// torque needs the other actuators' ([`torso_torque`]).
#[inline]
pub(crate) fn signal_torque(
    target: Target,
    target_angle: f64,
    angle: f64,
    rate: f64,
    kp: f64,
    kd: f64,
    max_torque: f64,
) -> Option<f64> {
    let t = match target {
        Target::Angle(_) => kp * (target_angle - angle) - kd * rate,
        Target::NoTorque | Target::Torso { .. } => return None,
        Target::DampingOnly => -kd * rate,
    };
    Some(t.clamp(-max_torque, max_torque))
}

/// The stance hip's torque of a [`Target::Torso`] signal, clamped to ±max_torque (spec §4.4):
/// τ = −τ_torso − τ_swing with τ_torso = kp (θd − θ_torso) − kd ω_torso. All angles, rates and
/// torques counter-clockwise; `torso_angle`, `torso_rate` are the torso's world angle and rate.
#[inline]
pub(crate) fn torso_torque(
    target_angle: f64,
    torso_angle: f64,
    torso_rate: f64,
    swing_torque: f64,
    kp: f64,
    kd: f64,
    max_torque: f64,
) -> f64 {
    let torso = kp * (target_angle - torso_angle) - kd * torso_rate;
    (-torso - swing_torque).clamp(-max_torque, max_torque)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weighted_average_matches_eq_5_1() {
        // Torques 10 (weight 1), −2 (weight 3): mean (10 − 6) / 4 = 1.
        let mut acc = TorqueAverage::default();
        acc.add(10.0, 1.0);
        acc.add(-2.0, 3.0);
        assert!((acc.torque - 1.0).abs() < 1e-15);
        assert_eq!(acc.weight, 4.0);
        // A zero weight first is skipped (S + P = 0) and changes nothing later.
        let mut acc = TorqueAverage::default();
        acc.add(5.0, 0.0);
        acc.add(7.0, 2.0);
        assert_eq!(acc.torque, 7.0);
    }

    #[test]
    fn signals_are_clamped_before_averaging() {
        let t = signal_torque(Target::Angle(1.0), 1.0, 0.0, 0.0, 100.0, 0.0, 30.0).unwrap();
        assert_eq!(t, 30.0);
        assert_eq!(signal_torque(Target::NoTorque, 0.0, 0.3, 1.0, 100.0, 5.0, 30.0), None);
        assert_eq!(signal_torque(Target::DampingOnly, 0.0, 0.3, 2.0, 100.0, 5.0, 30.0), Some(-10.0));
    }

    #[test]
    fn target_mix_equals_the_mean_of_unclamped_torques() {
        let (kp, kd, th, rate) = (50.0, 3.0, 0.2, -0.7);
        let signals = [(Target::Angle(1.0), 2.0), (Target::Angle(-0.5), 1.0), (Target::DampingOnly, 1.0)];
        let mut acc = TorqueAverage::default();
        let mut mix = TargetMix::default();
        for (t, w) in signals {
            let a = if let Target::Angle(a) = t { a } else { 0.0 };
            acc.add(signal_torque(t, a, th, rate, kp, kd, f64::INFINITY).unwrap(), w);
            mix.weight += w;
            if let Target::Angle(a) = t {
                mix.angle_weight += w;
                mix.weighted_angle += w * a;
            }
        }
        let implicit = kp * mix.stiffness_factor() * (mix.target() - th) - kd * mix.damping_factor() * rate;
        assert!((implicit - acc.torque).abs() < 1e-12, "{implicit} vs {}", acc.torque);
    }

    #[test]
    fn the_stance_hip_torque_is_minus_the_torso_and_swing_torques() {
        // τ_torso = 300 (0.1 − 0.05) − 30 · 0.2 = 9; τ_swing = 4: τ = −13.
        let t = torso_torque(0.1, 0.05, 0.2, 4.0, 300.0, 30.0, 1000.0);
        assert!((t + 13.0).abs() < 1e-12, "{t}");
        // Clamped like every signal (§4.4).
        assert_eq!(torso_torque(0.1, 0.05, 0.2, 4.0, 300.0, 30.0, 10.0), -10.0);
        assert_eq!(signal_torque(Target::Torso { angle: 0.1, swing: 1 }, 0.1, 0.0, 0.0, 1.0, 1.0, 1.0), None);
    }

    #[test]
    fn commands_refuse_without_allocating() {
        let mut c = Commands::new(2, 1);
        c.push(Signal::angle(0, 0.1)).unwrap();
        c.push(Signal::angle(1, 0.1)).unwrap();
        assert!(matches!(c.push(Signal::angle(1, 0.2)), Err(CommandError::Full { capacity: 2 })));
        assert!(matches!(c.push(Signal::angle(2, 0.2)), Err(CommandError::NoSuchActuator { .. })));
        assert_eq!(c.signals().len(), 2);
        let mut c = Commands::new(2, 1);
        assert!(matches!(
            c.push(Signal { weight: -1.0, ..Signal::angle(0, 0.0) }),
            Err(CommandError::BadWeight(_))
        ));
        // A torso signal needs another actuator as its swing.
        for swing in [0, 2] {
            let torso = Signal { target: Target::Torso { angle: 0.0, swing }, ..Signal::angle(0, 0.0) };
            assert!(matches!(c.push(torso), Err(CommandError::BadSwing { .. })), "swing {swing}");
        }
        let torso = Signal { target: Target::Torso { angle: 0.0, swing: 1 }, ..Signal::angle(0, 0.0) };
        c.push(torso).unwrap();
    }
}
