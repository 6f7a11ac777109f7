//! The controller file format: plain serde types that mirror a RON controller file one to one.
//! [`crate::Controller::from_desc`] checks them and turns names into indices.

use std::fmt;

use serde::de::{self, Visitor};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::param::Param;

fn yes() -> bool {
    true
}

fn is_false(b: &bool) -> bool {
    !*b
}

fn one() -> Param {
    Param::fixed(1.0)
}

fn zero() -> Param {
    Param::fixed(0.0)
}

/// A whole controller: the actuators it may address, its sensor set and its state machines
/// (spec §6.1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Controller", deny_unknown_fields)]
pub struct ControllerDesc {
    pub name: String,
    /// The actuators, by the names the body's skeleton gives them; a pose addresses one by name or
    /// by its index in this list. A controller that drives several models prefixes the model:
    /// `"pusher/hip_l"` (the scene layer resolves the names).
    pub actuators: Vec<String>,
    /// The sensor set: machine sensors that sensory machines are bound to (spec §5.2).
    #[serde(default)]
    pub sensors: Vec<MachineSensorDesc>,
    pub machines: Vec<MachineDesc>,
}

/// A sensor of the controller's sensor set: a sensor with an oscillation delay (hold-off, spec §5.3)
/// and an optional procedure (§5.4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Sensor", deny_unknown_fields)]
pub struct MachineSensorDesc {
    /// Unique among the sensor set; sensory machines name it.
    pub name: String,
    /// Which computation: a name the caller's sensor input understands (the body crate's catalogue:
    /// `foot_up`, `cog_ahead`, `landing`, `falling_forward`, …).
    pub kind: String,
    /// Fixed arguments of the computation (a foot side, a model), passed through as strings.
    #[serde(default)]
    pub args: Vec<String>,
    /// The sensor's ordered parameters (spec §5.1: meaning set by the designer).
    #[serde(default)]
    pub params: Vec<Param>,
    /// Iterations the filtered state is held after each change; whole iterations.
    #[serde(default = "zero")]
    pub oscillation_delay: Param,
    #[serde(default)]
    pub procedure: Option<ProcedureCall>,
    #[serde(default)]
    pub fire: FireMode,
    /// Automatically modifiable (spec §7.2).
    #[serde(default = "yes")]
    pub auto: bool,
}

/// The sensor of a sensory transition: no hold-off, no procedure of its own (spec §5.2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "TransitionSensor", deny_unknown_fields)]
pub struct SensorDesc {
    pub kind: String,
    #[serde(default)]
    pub args: Vec<String>,
    #[serde(default)]
    pub params: Vec<Param>,
}

/// When a machine sensor's procedure fires (spec §5.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum FireMode {
    /// Only in the iteration the (filtered) sensor becomes active.
    #[default]
    OnActivation,
    /// In every iteration the sensor is active.
    WhileActive,
}

/// A procedure named in the registry, with fixed arguments it may read.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Call", deny_unknown_fields)]
pub struct ProcedureCall {
    pub name: String,
    #[serde(default)]
    pub args: Vec<String>,
}

/// When a machine runs (spec §6.2).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub enum MachineKind {
    /// Always.
    Constant,
    /// While the named sensor of the sensor set is active.
    Sensory(String),
    /// While no sensory machine's sensor is active (Fig. 5.3).
    Default,
}

/// One state machine: a cyclic vector of states, `transitions[i]` leading from `states[i]` to
/// `states[(i + 1) % n]` (spec §6.4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Machine", deny_unknown_fields)]
pub struct MachineDesc {
    pub name: String,
    pub kind: MachineKind,
    /// P_ME of Eq. 5.1.
    #[serde(default = "one")]
    pub weight: Param,
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Automatically modifiable (spec §7.2).
    #[serde(default = "yes")]
    pub auto: bool,
    /// Roles that swap between two phases (SIMBICON's stance and swing legs): pose entries and sensor
    /// arguments may name a role instead of an actuator or an argument, and a transition with
    /// `swap_roles` exchanges the two phases' assignments. `None`: no roles, one phase (and nothing
    /// written, so that controllers without roles read and write as they did before roles).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub roles: Option<RolesDesc>,
    pub states: Vec<StateDesc>,
    pub transitions: Vec<TransitionDesc>,
}

/// The roles of a machine (an anima extension for SIMBICON, Yin et al. 2007): who plays each role in
/// the machine's first phase and who in its second. A machine starts in the first phase; each
/// transition with `swap_roles: true` switches to the other. SIMBICON's four states are then two
/// states written once for "the stance leg" and "the swing leg", with the parameters shared by both
/// sides:
///
/// ```ron
/// roles: Some(Roles(
///     actuators: [("stance_hip", "hip_l", "hip_r"), ("swing_hip", "hip_r", "hip_l")],
///     args: [("stance", "left", "right"), ("swing", "right", "left")],
/// )),
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Roles", deny_unknown_fields)]
pub struct RolesDesc {
    /// (role, the actuator that plays it in the first phase, the one in the second). A pose entry or
    /// a torso target's `swing` may name the role.
    #[serde(default)]
    pub actuators: Vec<(String, ActuatorRef, ActuatorRef)>,
    /// (role, the sensor argument that plays it in the first phase, the one in the second): an
    /// argument of a feedback term's or a sensory transition's sensor that names the role is
    /// replaced by the phase's argument (`"stance"` → `"left"`).
    #[serde(default)]
    pub args: Vec<(String, String, String)>,
}

/// A state: a pose on any subset of the actuators and an optional procedure fired in every iteration
/// the state is active (spec §6.4, §6.8).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "State", deny_unknown_fields)]
pub struct StateDesc {
    pub name: String,
    #[serde(default)]
    pub pose: Vec<PoseEntry>,
    /// Use the pose (the very same parameters) of another state of this machine, for the thesis's
    /// "identical to E1" states; `pose` must then be empty.
    #[serde(default)]
    pub same_pose_as: Option<String>,
    #[serde(default)]
    pub procedure: Option<ProcedureCall>,
    #[serde(default = "yes")]
    pub auto: bool,
}

/// One actuator's entry in a pose: `("hip_l", Angle(0.6))`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PoseEntry(pub ActuatorRef, pub TargetDesc);

/// What a pose asks of one actuator (spec §4.5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum TargetDesc {
    /// Joint angle (child relative to parent), rad.
    Angle(Param),
    /// The child body's angle in the world, rad (an extension for SIMBICON-like balance; the thesis
    /// uses joint angles only).
    WorldAngle(Param),
    /// A balance-feedback target, θ₀ + Σ gainᵢ · sensorᵢ, evaluated every iteration (an anima
    /// extension for SIMBICON-style control: e.g. the swing hip's world angle θ₀ + c_d·d + c_v·v with
    /// d, v the centre of mass's offset from and speed over the stance foot).
    Feedback(FeedbackDesc),
    /// SIMBICON's stance hip (Yin et al. 2007; an anima extension): no target of its own, but the
    /// torque that holds the actuator's parent body (the torso, for a hip) at a world angle through
    /// this actuator, τ = −τ_torso − τ_swing, with τ_swing the torque of the other hip.
    Torso(TorsoDesc),
    /// Apply no torque for this pose.
    NoTorque,
    /// Damping only (hold the current angle).
    DampingOnly,
}

/// A feedback target: `Feedback((base: 0.3, world: true, terms: [(gain: 0.5, sensor: (kind:
/// "com_offset", args: ["right"]))]))`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeedbackDesc {
    /// θ₀, rad.
    pub base: Param,
    /// The target is the child body's angle in the world (as [`TargetDesc::WorldAngle`]) rather than
    /// the joint angle.
    #[serde(default)]
    pub world: bool,
    pub terms: Vec<FeedbackTerm>,
}

/// A torso target: `Torso((angle: 0.0, swing: "swing_hip"))`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TorsoDesc {
    /// The torso's world angle, rad.
    pub angle: Param,
    /// The other actuator on the torso (the swing hip), by name, index or role; its torque is taken
    /// off, so that the two together hold the torso.
    pub swing: ActuatorRef,
}

/// One term of a feedback target: a gain times a sensor's return value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeedbackTerm {
    pub gain: Param,
    /// A continuous sensor (its value is used, not only whether it is non-zero).
    pub sensor: SensorDesc,
}

/// An actuator by name (from the controller's `actuators` list) or by 0-based index.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ActuatorRef {
    Name(String),
    Index(usize),
}

impl ActuatorRef {
    /// The actuator's name, looked up in the controller's `actuators` list for an index (`None` for an
    /// index out of range).
    pub fn name<'a>(&'a self, actuators: &'a [String]) -> Option<&'a str> {
        match self {
            Self::Name(n) => Some(n),
            Self::Index(i) => actuators.get(*i).map(String::as_str),
        }
    }
}

impl fmt::Display for ActuatorRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Name(n) => write!(f, "`{n}`"),
            Self::Index(i) => write!(f, "{i}"),
        }
    }
}

impl Serialize for ActuatorRef {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Self::Name(n) => s.serialize_str(n),
            Self::Index(i) => s.serialize_u64(*i as u64),
        }
    }
}

impl<'de> Deserialize<'de> for ActuatorRef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct RefVisitor;
        impl<'de> Visitor<'de> for RefVisitor {
            type Value = ActuatorRef;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("an actuator name (string) or a 0-based actuator index")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<ActuatorRef, E> {
                Ok(ActuatorRef::Name(v.to_string()))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ActuatorRef, E> {
                Ok(ActuatorRef::Index(v as usize))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ActuatorRef, E> {
                usize::try_from(v)
                    .map(ActuatorRef::Index)
                    .map_err(|_| E::custom(format_args!("an actuator index cannot be negative, found {v}")))
            }
        }
        d.deserialize_any(RefVisitor)
    }
}

/// A transition (spec §6.4): its condition, interpolation delay D_I and optional procedure fired when
/// it switches.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Transition", deny_unknown_fields)]
pub struct TransitionDesc {
    /// Defaults to `T<k>` (1-based, as the thesis numbers them).
    #[serde(default)]
    pub name: String,
    pub when: Condition,
    /// Interpolation delay D_I, iterations.
    #[serde(default = "zero")]
    pub delay: Param,
    #[serde(default)]
    pub procedure: Option<ProcedureCall>,
    /// Switch the machine's roles to the other phase when this transition fires (SIMBICON's foot
    /// strike); only in a machine with `roles`. Written only when set.
    #[serde(default, skip_serializing_if = "is_false")]
    pub swap_roles: bool,
    #[serde(default = "yes")]
    pub auto: bool,
}

/// When a transition fires.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Condition {
    /// After the origin state has been used for this many iterations (spec §6.7).
    Temporal(Param),
    /// When its own sensor returns non-zero.
    Sensory(SensorDesc),
    /// When [`crate::Controller::trigger`] is called for it; never, if nobody does (a linear machine's
    /// last transition).
    Method,
}
