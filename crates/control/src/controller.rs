//! The compiled controller: names resolved to indices, parameters in one table, the runtime state of
//! every machine and machine sensor, and the per-iteration step (spec §6.3–§6.9).

use std::collections::{HashMap, HashSet};
use std::ops::Range;

use anima_format::limits::MAX_STATES;

use serde::{Deserialize, Serialize};

use crate::desc::{
    ActuatorRef, Condition, ControllerDesc, FireMode, MachineDesc, MachineKind, PoseEntry, ProcedureCall,
    SensorDesc, TargetDesc,
};
use crate::error::ControllerError;
use crate::io::{Frame, SensorInput, SensorQuery, TargetKind, TargetSignal, Targets};
use crate::optimise::{Dim, Space};
use crate::param::{Param, ParamId, ParamInfo, ParamKind, ParamOwner};
use crate::procedure::{CallArgs, Origin, ProcCtx, Procedures};

/// A sensor the controller queries: one of the sensor set, or a sensory transition's own.
#[derive(Debug, Clone, PartialEq)]
pub struct Sensor {
    pub name: String,
    /// Where the file describes it (`sensors[2]`, `machines[0].transitions[1].when`), so that a
    /// caller that binds it to a body can point at the file's line.
    pub field: String,
    pub kind: String,
    pub args: Vec<String>,
    /// Its parameters: consecutive ids in the parameter table.
    pub params: Range<usize>,
}

/// When a machine runs, by index.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MachineType {
    Constant,
    /// Bound to this machine sensor (index in the sensor set).
    Sensory(usize),
    Default,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum PoseTarget {
    Angle(ParamId, Frame),
    /// θ₀ + Σ gainᵢ · sensorᵢ over `Controller::feedback[start..start + len]`.
    Feedback {
        base: ParamId,
        frame: Frame,
        start: u32,
        len: u32,
    },
    /// SIMBICON's stance hip: the torso at world angle `angle`, with `swing`'s torque taken off.
    Torso {
        angle: ParamId,
        swing: usize,
    },
    NoTorque,
    DampingOnly,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct PoseItem {
    actuator: usize,
    target: PoseTarget,
}

#[derive(Debug, Clone, PartialEq)]
struct StateDef {
    name: String,
    /// The pose in each phase of the machine's roles (the same index twice without roles).
    pose: [usize; 2],
    procedure: Option<usize>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Cond {
    Temporal(ParamId),
    Sensory(usize),
    Method,
}

#[derive(Debug, Clone, PartialEq)]
struct TransitionDef {
    name: String,
    /// The condition in each phase of the machine's roles (a sensory one reads the phase's sensor).
    cond: [Cond; 2],
    delay: ParamId,
    procedure: Option<usize>,
    /// Switches the machine's roles to the other phase.
    swap_roles: bool,
}

/// The pose a machine blends from (P_anterior of Eq. 5.3), one entry per actuator of the previous
/// state's pose; `angle` is `None` for NoTorque/DampingOnly entries.
#[derive(Debug, Clone, Copy, PartialEq)]
struct PrevEntry {
    actuator: usize,
    angle: Option<f64>,
    frame: Frame,
}

#[derive(Debug, Clone, PartialEq, Default)]
struct MachineRt {
    /// Ran in the previous iteration (so its progress is kept).
    running: bool,
    ran_now: bool,
    state: usize,
    /// N_I: iterations the current state has already been used.
    n: u32,
    /// D_I of the transition that led to the current state (0 after a start).
    d_in: u32,
    has_prev: bool,
    prev: Vec<PrevEntry>,
    /// The current outgoing (method) transition was invoked.
    triggered: bool,
    /// The phase of the machine's roles: 0 as declared, 1 swapped.
    phase: usize,
}

/// One state machine (spec §6.4).
#[derive(Debug, Clone, PartialEq)]
pub struct Machine {
    name: String,
    kind: MachineType,
    weight: ParamId,
    enabled: bool,
    poses: Vec<Vec<PoseItem>>,
    states: Vec<StateDef>,
    transitions: Vec<TransitionDef>,
    roles: bool,
    rt: MachineRt,
}

impl Machine {
    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn kind(&self) -> MachineType {
        self.kind
    }

    pub fn weight_param(&self) -> ParamId {
        self.weight
    }

    pub fn enabled(&self) -> bool {
        self.enabled
    }

    pub fn n_states(&self) -> usize {
        self.states.len()
    }

    pub fn state_name(&self, state: usize) -> &str {
        &self.states[state].name
    }

    pub fn transition_name(&self, transition: usize) -> &str {
        &self.transitions[transition].name
    }

    pub fn state_index(&self, name: &str) -> Option<usize> {
        self.states.iter().position(|s| s.name == name)
    }

    pub fn transition_index(&self, name: &str) -> Option<usize> {
        self.transitions.iter().position(|t| t.name == name)
    }

    /// The active state, while the machine is running (it ran in the last iteration).
    pub fn current_state(&self) -> Option<usize> {
        self.rt.running.then_some(self.rt.state)
    }

    /// (N_I, D_I) of Eq. 5.3 for the active state: iterations it has been used, and the delay of the
    /// transition that led to it.
    pub fn interpolation(&self) -> (u32, u32) {
        (self.rt.n, self.rt.d_in)
    }

    /// The phase of the machine's roles while it runs: 0 (as declared) or 1 (swapped); always 0 for a
    /// machine without roles.
    pub fn phase(&self) -> Option<usize> {
        self.rt.running.then_some(self.rt.phase)
    }

    /// Whether the machine has roles that swap.
    pub fn has_roles(&self) -> bool {
        self.roles
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct HoldOff {
    value: f64,
    active: bool,
    iters: u32,
    just_activated: bool,
}

/// A sensor of the sensor set with its hold-off state (spec §5.3).
#[derive(Debug, Clone, PartialEq)]
pub struct MachineSensor {
    sensor: usize,
    oscillation_delay: ParamId,
    procedure: Option<usize>,
    fire: FireMode,
    rt: HoldOff,
}

impl MachineSensor {
    /// Index in [`Controller::sensors`].
    pub fn sensor(&self) -> usize {
        self.sensor
    }

    /// The filtered (held) state.
    pub fn active(&self) -> bool {
        self.rt.active
    }

    /// The last raw return value.
    pub fn value(&self) -> f64 {
        self.rt.value
    }

    pub fn oscillation_delay_param(&self) -> ParamId {
        self.oscillation_delay
    }
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Call {
    pub proc: usize,
    pub args: Vec<String>,
    /// The call's field in the file (`machines[0].states[1].procedure`).
    pub path: String,
}

/// Which parameters an optimisation stage may change (spec §7.2): the hierarchical
/// "automatically modifiable" flags always apply; this narrows further.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Selection {
    /// Only these machines (by name); `None` for all.
    pub machines: Option<Vec<String>>,
    pub scope: Scope,
    /// Machine weights.
    pub weights: bool,
    /// Parameters of the sensor set (sensor parameters, oscillation delays).
    pub sensors: bool,
}

impl Selection {
    /// Every free parameter.
    pub fn all() -> Self {
        Self { machines: None, scope: Scope::Both, weights: true, sensors: true }
    }

    /// The free parameters of the named machines' states and/or transitions only.
    pub fn machines(names: &[&str], scope: Scope) -> Self {
        Self {
            machines: Some(names.iter().map(|s| s.to_string()).collect()),
            scope,
            weights: false,
            sensors: false,
        }
    }
}

/// Per-machine restriction of a stage (spec §7.2): state parameters, transition parameters, or both.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Scope {
    States,
    Transitions,
    Both,
}

/// A controller: state machines over subsets of actuators, a sensor set, procedures by name, and a
/// table of parameters (spec §6). Build it from a RON text or a [`ControllerDesc`], then call
/// [`Controller::step`] once per control iteration.
#[derive(Debug, Clone, PartialEq)]
pub struct Controller {
    name: String,
    actuators: Vec<String>,
    params: Vec<ParamInfo>,
    values: Vec<f64>,
    file_values: Vec<f64>,
    sensors: Vec<Sensor>,
    /// The terms of every feedback target: (gain, sensor).
    feedback: Vec<(ParamId, usize)>,
    machine_sensors: Vec<MachineSensor>,
    machines: Vec<Machine>,
    constant: Vec<usize>,
    sensory: Vec<usize>,
    default: Vec<usize>,
    pub(crate) calls: Vec<Call>,
    n_procedures: usize,
    iteration: u64,
    max_signals: usize,
    warnings: Vec<String>,
    desc: ControllerDesc,
}

struct Builder<'a> {
    params: Vec<ParamInfo>,
    values: Vec<f64>,
    calls: Vec<Call>,
    proc_names: &'a [String],
}

impl Builder<'_> {
    #[allow(clippy::too_many_arguments)]
    fn param(
        &mut self,
        p: &Param,
        kind: ParamKind,
        path: String,
        label: String,
        owner: ParamOwner,
        auto: bool,
    ) -> Result<ParamId, ControllerError> {
        let err = |m: String| Err(ControllerError::invalid(path.clone(), m));
        if !p.value.is_finite() {
            return err(format!("expected a finite number, found {}", p.value));
        }
        if kind.is_integer() && p.value.fract() != 0.0 {
            return err(format!("expected whole iterations, found {}", p.value));
        }
        if kind.is_non_negative() && p.value < 0.0 {
            return err(format!("expected a value ≥ 0, found {}", p.value));
        }
        if let Some((min, max)) = p.range {
            if !(min.is_finite() && max.is_finite() && min <= max) {
                return err(format!("the interval [{min}, {max}] is not a finite interval with min ≤ max"));
            }
            if kind.is_non_negative() && min < 0.0 {
                return err(format!("the interval [{min}, {max}] admits negative values"));
            }
            if !(min..=max).contains(&p.value) {
                return err(format!("value {} lies outside its admissible interval [{min}, {max}]", p.value));
            }
        }
        self.params.push(ParamInfo { path, label, kind, range: p.range, owner, auto });
        self.values.push(p.value);
        Ok(ParamId(self.values.len() - 1))
    }

    fn call(&mut self, call: &Option<ProcedureCall>, path: String) -> Result<Option<usize>, ControllerError> {
        let Some(call) = call else { return Ok(None) };
        let Some(proc) = self.proc_names.iter().position(|n| *n == call.name) else {
            return Err(ControllerError::invalid(
                format!("{path}.name"),
                format!("unknown procedure `{}`; registered: {}", call.name, list(self.proc_names)),
            ));
        };
        self.calls.push(Call { proc, args: call.args.clone(), path });
        Ok(Some(self.calls.len() - 1))
    }
}

/// A machine's roles, resolved (spec extension for SIMBICON, see [`crate::RolesDesc`]): each actuator
/// role's actuator in the two phases, and each argument role's argument.
struct Roles {
    actuators: Vec<(String, [usize; 2])>,
    args: Vec<(String, [String; 2])>,
    /// Index in `actuators` (and in `args`) by role name, so that resolving a pose entry or a sensor's
    /// arguments scans nothing.
    actuator_roles: HashMap<String, usize>,
    arg_roles: HashMap<String, usize>,
}

impl Roles {
    /// Checks and resolves machine `m`'s roles (none: no roles).
    fn compile(md: &MachineDesc, actuators: &Actuators, m: usize) -> Result<Self, ControllerError> {
        let mut roles = Roles {
            actuators: Vec::new(),
            args: Vec::new(),
            actuator_roles: HashMap::new(),
            arg_roles: HashMap::new(),
        };
        let Some(rd) = &md.roles else { return Ok(roles) };
        let at = |f: String| format!("machines[{m}].roles.{f}");
        for (i, (role, first, second)) in rd.actuators.iter().enumerate() {
            let path = at(format!("actuators[{i}]"));
            if role.is_empty() || actuators.index.contains_key(role.as_str()) {
                return Err(inv(
                    path,
                    format!("role `{role}` needs a name of its own (not empty, not one of the actuators)"),
                ));
            }
            if roles.actuator_roles.contains_key(role) {
                return Err(inv(path, format!("a second role named `{role}`")));
            }
            let pair = [actuator_index(first, actuators, &path)?, actuator_index(second, actuators, &path)?];
            roles.actuator_roles.insert(role.clone(), roles.actuators.len());
            roles.actuators.push((role.clone(), pair));
        }
        for (i, (role, first, second)) in rd.args.iter().enumerate() {
            let path = at(format!("args[{i}]"));
            if role.is_empty() || roles.arg_roles.contains_key(role) {
                return Err(inv(path, format!("argument role `{role}` is empty or named twice")));
            }
            roles.arg_roles.insert(role.clone(), roles.args.len());
            roles.args.push((role.clone(), [first.clone(), second.clone()]));
        }
        Ok(roles)
    }

    /// An actuator by role (the same in both phases when it names no role) and the name its
    /// parameters' labels use: the role's, else the actuator's.
    fn actuator(
        &self,
        r: &ActuatorRef,
        actuators: &Actuators,
        path: &str,
    ) -> Result<([usize; 2], String), ControllerError> {
        if let ActuatorRef::Name(n) = r
            && let Some(&k) = self.actuator_roles.get(n)
        {
            let (role, pair) = &self.actuators[k];
            return Ok((*pair, role.clone()));
        }
        let a = actuator_index(r, actuators, path).map_err(|e| {
            if self.actuators.is_empty() {
                e
            } else {
                let names: Vec<String> = self.actuators.iter().map(|(r, _)| r.clone()).collect();
                inv(path, format!("{}; the machine's roles: {}", e.message, list(&names)))
            }
        })?;
        Ok(([a, a], actuators.names[a].clone()))
    }

    /// A sensor's arguments in phase `p`: each argument that names a role replaced by its argument.
    fn args(&self, args: &[String], p: usize) -> Vec<String> {
        args.iter()
            .map(|a| self.arg_roles.get(a).map_or_else(|| a.clone(), |&k| self.args[k].1[p].clone()))
            .collect()
    }

    /// Adds the sensor `sd` asks for, with parameters `params`: one sensor, or one per phase when a
    /// role argument makes the phases read different sensors. Returns the sensor of each phase.
    fn sensors(
        &self,
        sensors: &mut Vec<Sensor>,
        name: String,
        field: String,
        sd: &SensorDesc,
        params: Range<usize>,
    ) -> [usize; 2] {
        let [first, second] = [self.args(&sd.args, 0), self.args(&sd.args, 1)];
        let swapped = first != second;
        let second_name = format!("{name} (roles swapped)");
        let kind = sd.kind.clone();
        sensors.push(Sensor {
            name,
            field: field.clone(),
            kind: kind.clone(),
            args: first,
            params: params.clone(),
        });
        let id = sensors.len() - 1;
        if !swapped {
            return [id, id];
        }
        sensors.push(Sensor { name: second_name, field, kind, args: second, params });
        [id, id + 1]
    }
}

/// The controller's actuators, with an index by name (the first of a name: a second one is an error
/// found before any lookup), so that resolving a pose entry scans nothing.
struct Actuators<'a> {
    names: &'a [String],
    index: HashMap<&'a str, usize>,
}

impl<'a> Actuators<'a> {
    fn new(names: &'a [String]) -> Self {
        let mut index = HashMap::with_capacity(names.len());
        for (i, n) in names.iter().enumerate() {
            index.entry(n.as_str()).or_insert(i);
        }
        Self { names, index }
    }
}

/// An actuator by name or index.
fn actuator_index(r: &ActuatorRef, actuators: &Actuators, path: &str) -> Result<usize, ControllerError> {
    let n_act = actuators.names.len();
    match r {
        ActuatorRef::Index(i) if *i < n_act => Ok(*i),
        ActuatorRef::Index(i) => Err(inv(
            path,
            format!("actuator index {i} is out of range (the controller has {n_act} actuators)"),
        )),
        ActuatorRef::Name(n) => actuators.index.get(n.as_str()).copied().ok_or_else(|| {
            inv(
                path,
                format!("unknown actuator `{n}`; the controller's actuators are: {}", list(actuators.names)),
            )
        }),
    }
}

/// What compiling one state's pose entries needs to know.
struct PoseCtx<'a> {
    actuators: &'a Actuators<'a>,
    roles: &'a Roles,
    owner: ParamOwner,
    auto: bool,
    n_phases: usize,
}

impl PoseCtx<'_> {
    /// One pose entry, as an item per phase (the second a copy without roles): its parameters are
    /// registered once, in the order of [`for_each_param_mut`]; feedback terms and sensors are added
    /// per phase where a role argument makes the phases differ.
    fn item(
        &self,
        b: &mut Builder,
        sensors: &mut Vec<Sensor>,
        feedback: &mut Vec<(ParamId, usize)>,
        entry: &PoseEntry,
        path: String,
        label_of: impl Fn(&str) -> String,
    ) -> Result<[PoseItem; 2], ControllerError> {
        let (actuator, name) = self.roles.actuator(&entry.0, self.actuators, &path)?;
        let label = label_of(&name);
        let (owner, auto) = (self.owner, self.auto);
        let target: [PoseTarget; 2] = match &entry.1 {
            TargetDesc::Angle(p) => {
                [PoseTarget::Angle(
                    b.param(p, ParamKind::TargetAngle, path, label, owner, auto)?,
                    Frame::Parent,
                ); 2]
            }
            TargetDesc::WorldAngle(p) => {
                [PoseTarget::Angle(
                    b.param(p, ParamKind::TargetAngle, path, label, owner, auto)?,
                    Frame::World,
                ); 2]
            }
            TargetDesc::Feedback(fd) => {
                let base = b.param(
                    &fd.base,
                    ParamKind::TargetAngle,
                    format!("{path}.base"),
                    label.clone(),
                    owner,
                    auto,
                )?;
                let mut terms: Vec<(ParamId, [usize; 2])> = Vec::with_capacity(fd.terms.len());
                for (i, term) in fd.terms.iter().enumerate() {
                    let tpath = format!("{path}.terms[{i}]");
                    if term.sensor.kind.is_empty() {
                        return Err(inv(
                            format!("{tpath}.sensor.kind"),
                            "a sensor needs a kind (the computation to run)",
                        ));
                    }
                    let gain = b.param(
                        &term.gain,
                        ParamKind::FeedbackGain,
                        format!("{tpath}.gain"),
                        format!("{label}/k{i}"),
                        owner,
                        auto,
                    )?;
                    let first = b.values.len();
                    for (j, p) in term.sensor.params.iter().enumerate() {
                        b.param(
                            p,
                            ParamKind::SensorParam,
                            format!("{tpath}.sensor.params[{j}]"),
                            format!("{label}/k{i}/p{j}"),
                            owner,
                            auto,
                        )?;
                    }
                    let ids = self.roles.sensors(
                        sensors,
                        format!("{label}/k{i}"),
                        format!("{tpath}.sensor"),
                        &term.sensor,
                        first..b.values.len(),
                    );
                    terms.push((gain, ids));
                }
                let frame = if fd.world { Frame::World } else { Frame::Parent };
                let len = fd.terms.len() as u32;
                let mut starts = [feedback.len() as u32; 2];
                feedback.extend(terms.iter().map(|&(gain, ids)| (gain, ids[0])));
                if self.n_phases == 2 && terms.iter().any(|(_, ids)| ids[0] != ids[1]) {
                    starts[1] = feedback.len() as u32;
                    feedback.extend(terms.iter().map(|&(gain, ids)| (gain, ids[1])));
                }
                starts.map(|start| PoseTarget::Feedback { base, frame, start, len })
            }
            TargetDesc::Torso(td) => {
                let angle =
                    b.param(&td.angle, ParamKind::TargetAngle, format!("{path}.angle"), label, owner, auto)?;
                let spath = format!("{path}.swing");
                let (swing, _) = self.roles.actuator(&td.swing, self.actuators, &spath)?;
                if swing.iter().zip(&actuator).take(self.n_phases).any(|(s, a)| s == a) {
                    return Err(inv(
                        spath,
                        format!(
                            "the swing actuator must be another one than `{name}`, which holds the torso: the \
                             two share the torque that holds it"
                        ),
                    ));
                }
                swing.map(|swing| PoseTarget::Torso { angle, swing })
            }
            TargetDesc::NoTorque => [PoseTarget::NoTorque; 2],
            TargetDesc::DampingOnly => [PoseTarget::DampingOnly; 2],
        };
        Ok([0, 1].map(|p| PoseItem { actuator: actuator[p], target: target[p] }))
    }
}

fn inv(field: impl Into<String>, message: impl Into<String>) -> ControllerError {
    ControllerError::invalid(field, message)
}

fn list(names: &[String]) -> String {
    if names.is_empty() { "none".to_string() } else { names.join(", ") }
}

/// The first name that repeats an earlier one, with its index (one pass: a file of many states costs
/// no quadratic scan).
fn duplicate<'a>(names: impl Iterator<Item = &'a str>) -> Option<(usize, &'a str)> {
    let mut seen = HashSet::new();
    names.enumerate().find(|&(_, n)| !seen.insert(n))
}

impl Controller {
    /// Reads a controller from RON text. Procedures are looked up by name in `procedures`; pass the
    /// same registry to [`Controller::step`]. Errors name the line, column and field.
    pub fn from_ron<E>(text: &str, procedures: &Procedures<E>) -> Result<Self, ControllerError> {
        let desc: ControllerDesc = ron::from_str(text).map_err(|e| ControllerError::syntax(text, &e))?;
        Self::from_desc(desc, procedures).map_err(|e| e.locate(text))
    }

    /// Checks a description and builds the controller.
    pub fn from_desc<E>(desc: ControllerDesc, procedures: &Procedures<E>) -> Result<Self, ControllerError> {
        let c = Self::build(desc, procedures.names())?;
        c.check_calls(procedures)?;
        Ok(c)
    }

    /// Runs each procedure's argument check on the calls that name it (see [`Procedures::register_checked`]).
    fn check_calls<E>(&self, procedures: &Procedures<E>) -> Result<(), ControllerError> {
        if self.calls.iter().all(|c| procedures.checks()[c.proc].is_none()) {
            return Ok(());
        }
        // One index of every name a parameter answers to, so that the checks stay linear.
        let names: HashSet<&str> =
            self.params.iter().flat_map(|p| [p.path.as_str(), p.label.as_str()]).collect();
        let is_param = |s: &str| names.contains(s);
        for call in &self.calls {
            if let Some(check) = procedures.checks()[call.proc] {
                check(&CallArgs { args: &call.args, is_param: &is_param }).map_err(|why| {
                    inv(
                        format!("{}.args", call.path),
                        format!("procedure `{}`: {why}", procedures.names()[call.proc]),
                    )
                })?;
            }
        }
        Ok(())
    }

    /// Every procedure call of the file: the procedure's index in the registry the controller was read
    /// with, its fixed arguments, and its field in the file (for callers that check arguments against
    /// what they bind, such as the bodies a `push` names).
    pub fn calls(&self) -> impl Iterator<Item = (usize, &[String], &str)> {
        self.calls.iter().map(|c| (c.proc, c.args.as_slice(), c.path.as_str()))
    }

    fn build(desc: ControllerDesc, proc_names: &[String]) -> Result<Self, ControllerError> {
        let mut b = Builder { params: Vec::new(), values: Vec::new(), calls: Vec::new(), proc_names };
        let mut warnings = Vec::new();
        for (field, n) in [("actuators", desc.actuators.len()), ("sensors", desc.sensors.len())] {
            if n > MAX_STATES {
                let why = format!(
                    "expected at most {MAX_STATES} {field} in a controller (anima's limit), found {n}"
                );
                return Err(inv(field, why));
            }
        }
        if let Some((i, n)) = duplicate(desc.actuators.iter().map(String::as_str)) {
            return Err(inv(format!("actuators[{i}]"), format!("a second actuator named `{n}`")));
        }
        if desc.machines.is_empty() {
            return Err(inv("machines", "a controller needs at least one machine"));
        }
        // Counted before anything is built for them; every check below is linear in the file.
        let mut n_states = 0usize;
        for (m, md) in desc.machines.iter().enumerate() {
            n_states = n_states.saturating_add(md.states.len());
            if n_states > MAX_STATES {
                let total = desc.machines.iter().fold(0usize, |n, md| n.saturating_add(md.states.len()));
                return Err(inv(
                    format!("machines[{m}].states"),
                    format!(
                        "expected at most {MAX_STATES} states in a controller (anima's limit), found {total}"
                    ),
                ));
            }
        }
        let actuators = Actuators::new(&desc.actuators);

        // The sensor set first: machine sensors keep indices 0..k in `sensors`.
        let mut sensors = Vec::new();
        let mut feedback: Vec<(ParamId, usize)> = Vec::new();
        let mut machine_sensors = Vec::new();
        if let Some((i, n)) = duplicate(desc.sensors.iter().map(|s| s.name.as_str())) {
            return Err(inv(format!("sensors[{i}].name"), format!("a second sensor named `{n}`")));
        }
        let sensor_index: HashMap<&str, usize> =
            desc.sensors.iter().enumerate().map(|(k, s)| (s.name.as_str(), k)).collect();
        for (k, s) in desc.sensors.iter().enumerate() {
            let at = |f: &str| format!("sensors[{k}].{f}");
            if s.kind.is_empty() {
                return Err(inv(at("kind"), "a sensor needs a kind (the computation to run)"));
            }
            let owner = ParamOwner::Sensor { sensor: k };
            let start = b.values.len();
            for (i, p) in s.params.iter().enumerate() {
                let (path, label) = (at(&format!("params[{i}]")), format!("{}/p{i}", s.name));
                b.param(p, ParamKind::SensorParam, path, label, owner, s.auto)?;
            }
            let params = start..b.values.len();
            let od = b.param(
                &s.oscillation_delay,
                ParamKind::OscillationDelay,
                at("oscillation_delay"),
                format!("{}/oscillation_delay", s.name),
                owner,
                s.auto,
            )?;
            let procedure = b.call(&s.procedure, at("procedure"))?;
            sensors.push(Sensor {
                name: s.name.clone(),
                field: format!("sensors[{k}]"),
                kind: s.kind.clone(),
                args: s.args.clone(),
                params,
            });
            machine_sensors.push(MachineSensor {
                sensor: k,
                oscillation_delay: od,
                procedure,
                fire: s.fire,
                rt: HoldOff::default(),
            });
        }

        if let Some((i, n)) = duplicate(desc.machines.iter().map(|m| m.name.as_str())) {
            return Err(inv(format!("machines[{i}].name"), format!("a second machine named `{n}`")));
        }
        let mut machines = Vec::with_capacity(desc.machines.len());
        for (m, md) in desc.machines.iter().enumerate() {
            let at = |f: &str| format!("machines[{m}].{f}");
            let kind = match &md.kind {
                MachineKind::Constant => MachineType::Constant,
                MachineKind::Default => MachineType::Default,
                MachineKind::Sensory(name) => {
                    let Some(&k) = sensor_index.get(name.as_str()) else {
                        let names: Vec<String> = desc.sensors.iter().map(|s| s.name.clone()).collect();
                        return Err(inv(
                            at("kind"),
                            format!("unknown sensor `{name}`; the sensor set has: {}", list(&names)),
                        ));
                    };
                    MachineType::Sensory(k)
                }
            };
            let weight = b.param(
                &md.weight,
                ParamKind::Weight,
                at("weight"),
                format!("{}/weight", md.name),
                ParamOwner::Machine { machine: m },
                md.auto,
            )?;
            if md.states.is_empty() {
                return Err(inv(at("states"), "a machine needs at least one state"));
            }
            if md.transitions.len() != md.states.len() {
                return Err(inv(
                    at("transitions"),
                    format!(
                        "expected one transition per state ({}; transitions[i] leads from states[i] to the \
                         next, the last one back to the first), found {}",
                        md.states.len(),
                        md.transitions.len()
                    ),
                ));
            }
            if let Some((i, n)) = duplicate(md.states.iter().map(|s| s.name.as_str())) {
                return Err(inv(at(&format!("states[{i}].name")), format!("a second state named `{n}`")));
            }

            // Poses: states with their own pose first, then the shared ones; with roles, each pose
            // once per phase, over the same parameters.
            let roles = Roles::compile(md, &actuators, m)?;
            let n_phases = if md.roles.is_some() { 2 } else { 1 };
            let mut poses: Vec<Vec<PoseItem>> = Vec::new();
            let mut pose_of = vec![[usize::MAX; 2]; md.states.len()];
            for (s, sd) in md.states.iter().enumerate() {
                if sd.same_pose_as.is_some() {
                    if !sd.pose.is_empty() {
                        return Err(inv(
                            at(&format!("states[{s}].pose")),
                            "a state with `same_pose_as` takes the other state's pose; leave `pose` empty",
                        ));
                    }
                    continue;
                }
                let ctx = PoseCtx {
                    actuators: &actuators,
                    roles: &roles,
                    owner: ParamOwner::State { machine: m, state: s },
                    auto: md.auto && sd.auto,
                    n_phases,
                };
                let mut items: [Vec<PoseItem>; 2] =
                    [Vec::with_capacity(sd.pose.len()), Vec::with_capacity(sd.pose.len())];
                let mut posed: [HashSet<usize>; 2] = Default::default();
                for (e, entry) in sd.pose.iter().enumerate() {
                    let path = at(&format!("states[{s}].pose[{e}]"));
                    let label_of = |name: &str| format!("{}/{}/{name}", md.name, sd.name);
                    let new = ctx.item(&mut b, &mut sensors, &mut feedback, entry, path, label_of)?;
                    for (p, item) in new.iter().enumerate().take(n_phases) {
                        if !posed[p].insert(item.actuator) {
                            let phase = if p == 1 { " (with the roles swapped)" } else { "" };
                            return Err(inv(
                                at(&format!("states[{s}].pose[{e}]")),
                                format!(
                                    "actuator {} appears twice in this pose{phase}",
                                    desc.actuators[item.actuator]
                                ),
                            ));
                        }
                        items[p].push(*item);
                    }
                }
                let [first, second] = items;
                pose_of[s] = [poses.len(), poses.len() + n_phases - 1];
                poses.push(first);
                if n_phases == 2 {
                    poses.push(second);
                }
            }
            let state_index: HashMap<&str, usize> =
                md.states.iter().enumerate().map(|(s, sd)| (sd.name.as_str(), s)).collect();
            for (s, sd) in md.states.iter().enumerate() {
                let Some(other) = &sd.same_pose_as else { continue };
                let path = at(&format!("states[{s}].same_pose_as"));
                match state_index.get(other.as_str()).copied() {
                    None => {
                        return Err(inv(path, format!("unknown state `{other}` in machine `{}`", md.name)));
                    }
                    Some(o) if md.states[o].same_pose_as.is_some() => {
                        return Err(inv(path, format!("state `{other}` has no pose of its own")));
                    }
                    Some(o) => pose_of[s] = pose_of[o],
                }
            }
            let mut states = Vec::with_capacity(md.states.len());
            for (s, sd) in md.states.iter().enumerate() {
                let procedure = b.call(&sd.procedure, at(&format!("states[{s}].procedure")))?;
                states.push(StateDef { name: sd.name.clone(), pose: pose_of[s], procedure });
            }

            let mut transitions = Vec::with_capacity(md.transitions.len());
            let mut transition_names = HashSet::with_capacity(md.transitions.len());
            for (t, td) in md.transitions.iter().enumerate() {
                let tat = |f: &str| at(&format!("transitions[{t}].{f}"));
                let name = if td.name.is_empty() { format!("T{}", t + 1) } else { td.name.clone() };
                if !transition_names.insert(name.clone()) {
                    return Err(inv(tat("name"), format!("a second transition named `{name}`")));
                }
                if td.swap_roles && md.roles.is_none() {
                    return Err(inv(
                        tat("swap_roles"),
                        format!("machine `{}` has no roles to swap; give it `roles`", md.name),
                    ));
                }
                let owner = ParamOwner::Transition { machine: m, transition: t };
                let auto = md.auto && td.auto;
                let delay = b.param(
                    &td.delay,
                    ParamKind::InterpolationDelay,
                    tat("delay"),
                    format!("{}/{name}/delay", md.name),
                    owner,
                    auto,
                )?;
                let cond = match &td.when {
                    Condition::Temporal(p) => {
                        [Cond::Temporal(b.param(
                            p,
                            ParamKind::Time,
                            tat("when"),
                            format!("{}/{name}/time", md.name),
                            owner,
                            auto,
                        )?); 2]
                    }
                    Condition::Method => [Cond::Method; 2],
                    Condition::Sensory(sd) => {
                        if sd.kind.is_empty() {
                            return Err(inv(
                                tat("when.kind"),
                                "a sensor needs a kind (the computation to run)",
                            ));
                        }
                        let start = b.values.len();
                        for (i, p) in sd.params.iter().enumerate() {
                            let path = tat(&format!("when.params[{i}]"));
                            let label = format!("{}/{name}/p{i}", md.name);
                            b.param(p, ParamKind::SensorParam, path, label, owner, auto)?;
                        }
                        let ids = roles.sensors(
                            &mut sensors,
                            format!("{}/{name}", md.name),
                            tat("when"),
                            sd,
                            start..b.values.len(),
                        );
                        ids.map(Cond::Sensory)
                    }
                };
                let procedure = b.call(&td.procedure, tat("procedure"))?;
                transitions.push(TransitionDef { name, cond, delay, procedure, swap_roles: td.swap_roles });
            }
            if md.roles.is_some() && !transitions.iter().any(|t| t.swap_roles) {
                warnings.push(format!(
                    "machine `{}` has roles, but no transition swaps them (`swap_roles: true`)",
                    md.name
                ));
            }
            // Spec §6.5: blends are meant between poses listing the same actuators.
            for s in 0..states.len() {
                let next = (s + 1) % states.len();
                let phase = usize::from(transitions[s].swap_roles);
                let (p, q) = (&poses[states[s].pose[0]], &poses[states[next].pose[phase]]);
                // A pose lists each actuator once, so equal lengths and p ⊆ q make equal sets.
                let same = p.len() == q.len() && {
                    let q: HashSet<usize> = q.iter().map(|b| b.actuator).collect();
                    p.iter().all(|a| q.contains(&a.actuator))
                };
                if !same {
                    warnings.push(format!(
                        "machine `{}`: states `{}` and `{}` pose different actuator sets; actuators only in \
                         the new pose start at once, those only in the old one are dropped",
                        md.name, states[s].name, states[next].name
                    ));
                }
            }
            let max_pose = poses.iter().map(Vec::len).max().unwrap_or(0);
            machines.push(Machine {
                name: md.name.clone(),
                kind,
                weight,
                enabled: md.enabled,
                poses,
                states,
                transitions,
                roles: md.roles.is_some(),
                rt: MachineRt { prev: Vec::with_capacity(max_pose), ..MachineRt::default() },
            });
        }
        let bound: HashSet<usize> = machines
            .iter()
            .filter_map(|m| match m.kind {
                MachineType::Sensory(k) => Some(k),
                _ => None,
            })
            .collect();
        for (k, _) in desc.sensors.iter().enumerate() {
            if !bound.contains(&k) {
                warnings.push(format!(
                    "sensor `{}` drives no sensory machine; it does not suppress default machines (Fig. 5.3)",
                    desc.sensors[k].name
                ));
            }
        }

        let by = |t: fn(&MachineType) -> bool| -> Vec<usize> {
            machines.iter().enumerate().filter(|(_, m)| t(&m.kind)).map(|(i, _)| i).collect()
        };
        let constant = by(|k| *k == MachineType::Constant);
        let sensory = by(|k| matches!(k, MachineType::Sensory(_)));
        let default = by(|k| *k == MachineType::Default);
        let max_signals = machines.iter().map(|m| m.poses.iter().map(Vec::len).max().unwrap_or(0)).sum();
        let mut c = Controller {
            name: desc.name.clone(),
            actuators: desc.actuators.clone(),
            params: b.params,
            file_values: b.values.clone(),
            values: b.values,
            sensors,
            feedback,
            machine_sensors,
            machines,
            constant,
            sensory,
            default,
            calls: b.calls,
            n_procedures: proc_names.len(),
            iteration: 0,
            max_signals,
            warnings,
            desc,
        };
        c.reset();
        Ok(c)
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The actuator names, in index order (what [`TargetSignal::actuator`] indexes).
    pub fn actuators(&self) -> &[String] {
        &self.actuators
    }

    /// Every sensor the controller queries: the sensor set first (indices 0..k, as in the file), then
    /// the sensory transitions' own sensors.
    pub fn sensors(&self) -> &[Sensor] {
        &self.sensors
    }

    /// The sensor set with its hold-off states.
    pub fn machine_sensors(&self) -> &[MachineSensor] {
        &self.machine_sensors
    }

    pub fn machines(&self) -> &[Machine] {
        &self.machines
    }

    pub fn machine_index(&self, name: &str) -> Option<usize> {
        self.machines.iter().position(|m| m.name == name)
    }

    /// Remarks from the checks that are not errors (e.g. consecutive poses over different actuators).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// Iterations stepped since the last reset.
    pub fn iteration(&self) -> u64 {
        self.iteration
    }

    /// Storage for the targets of one iteration, large enough that [`Controller::step`] never
    /// allocates.
    pub fn new_targets(&self) -> Targets {
        Targets::with_capacity(self.max_signals)
    }

    /// The most signals one iteration can produce.
    pub fn max_signals(&self) -> usize {
        self.max_signals
    }

    /// Every (actuator, swing actuator) pair a torso target may send ([`TargetKind::Torso`]), in
    /// either phase of its machine's roles: what a caller checks once, e.g. that both drive one body.
    pub fn torso_pairs(&self) -> Vec<(usize, usize)> {
        let mut pairs = Vec::new();
        for item in self.machines.iter().flat_map(|m| m.poses.iter().flatten()) {
            if let PoseTarget::Torso { swing, .. } = item.target
                && !pairs.contains(&(item.actuator, swing))
            {
                pairs.push((item.actuator, swing));
            }
        }
        pairs
    }

    // ---- parameters -------------------------------------------------------------------------

    /// The parameter table.
    pub fn params(&self) -> &[ParamInfo] {
        &self.params
    }

    pub fn param_values(&self) -> &[f64] {
        &self.values
    }

    pub fn param(&self, id: ParamId) -> f64 {
        self.values[id.0]
    }

    /// A parameter by its path (`machines[0].transitions[1].when.params[0]`) or label
    /// (`W-LEGS/T2/p0`). Allocation-free, linear in the number of parameters.
    pub fn param_id(&self, path_or_label: &str) -> Option<ParamId> {
        self.params.iter().position(|p| p.path == path_or_label || p.label == path_or_label).map(ParamId)
    }

    /// Sets a parameter (whole-iteration kinds are rounded). The admissible interval is not enforced:
    /// it bounds the optimisers, not on-line modification. A non-finite value is refused (`false`).
    pub fn set_param(&mut self, id: ParamId, value: f64) -> bool {
        if !value.is_finite() {
            return false;
        }
        self.values[id.0] = self.params[id.0].normalise(value);
        true
    }

    /// Puts every parameter back to its value in the file.
    pub fn reset_params(&mut self) {
        self.values.copy_from_slice(&self.file_values);
    }

    /// The free parameters a stage may change (spec §7.2), in table order.
    pub fn free_params(&self, sel: &Selection) -> Vec<ParamId> {
        let machine_ok =
            |m: usize| sel.machines.as_ref().is_none_or(|ms| ms.iter().any(|n| *n == self.machines[m].name));
        (0..self.params.len())
            .filter(|&i| {
                let p = &self.params[i];
                p.is_free()
                    && match p.owner {
                        ParamOwner::Machine { machine } => sel.weights && machine_ok(machine),
                        ParamOwner::State { machine, .. } => {
                            sel.scope != Scope::Transitions && machine_ok(machine)
                        }
                        ParamOwner::Transition { machine, .. } => {
                            sel.scope != Scope::States && machine_ok(machine)
                        }
                        ParamOwner::Sensor { .. } => sel.sensors,
                    }
            })
            .map(ParamId)
            .collect()
    }

    /// The search space of `ids`: their admissible intervals (a fixed parameter gets [v, v]).
    pub fn space(&self, ids: &[ParamId]) -> Space {
        Space {
            dims: ids
                .iter()
                .map(|&id| {
                    let p = &self.params[id.0];
                    let (min, max) = p.range.unwrap_or((self.values[id.0], self.values[id.0]));
                    Dim { name: p.label.clone(), min, max, integer: p.kind.is_integer() }
                })
                .collect(),
        }
    }

    /// The current values of `ids`.
    pub fn values_of(&self, ids: &[ParamId]) -> Vec<f64> {
        ids.iter().map(|id| self.values[id.0]).collect()
    }

    /// Sets `ids` to `x` (a point of [`Controller::space`]).
    pub fn apply(&mut self, ids: &[ParamId], x: &[f64]) {
        assert_eq!(ids.len(), x.len(), "one value per parameter");
        for (&id, &v) in ids.iter().zip(x) {
            self.set_param(id, v);
        }
    }

    /// The description with the current parameter values, e.g. to save an optimised controller.
    pub fn to_desc(&self) -> ControllerDesc {
        let mut desc = self.desc.clone();
        let mut k = 0;
        for_each_param_mut(&mut desc, &mut |p| {
            p.value = self.values[k];
            k += 1;
        });
        debug_assert_eq!(k, self.values.len());
        desc
    }

    /// The controller as RON text, with the current parameter values.
    pub fn to_ron(&self) -> String {
        let cfg = ron::ser::PrettyConfig::new().struct_names(true);
        ron::ser::to_string_pretty(&self.to_desc(), cfg).expect("a controller description always serialises")
    }

    // ---- on-line control --------------------------------------------------------------------

    pub fn set_enabled(&mut self, machine: usize, enabled: bool) {
        self.machines[machine].enabled = enabled;
    }

    /// Invokes a method transition (spec §6.7): it fires at the machine's next check once the
    /// interpolation delay has passed. Ignored (`false`) unless the machine is running and
    /// `transition` is its current outgoing transition and a method transition.
    pub fn trigger(&mut self, machine: usize, transition: usize) -> bool {
        let Some(m) = self.machines.get_mut(machine) else { return false };
        let ok = m.rt.running
            && m.rt.state == transition
            && matches!(m.transitions.get(transition).map(|t| t.cond[m.rt.phase]), Some(Cond::Method));
        if ok {
            m.rt.triggered = true;
        }
        ok
    }

    /// Discards all runtime state: machines restart at their first state, machine sensors are
    /// inactive with their hold-off elapsed, the iteration count is 0. Parameters are kept.
    pub fn reset(&mut self) {
        self.iteration = 0;
        for m in &mut self.machines {
            m.rt.running = false;
            m.rt.ran_now = false;
            m.rt.state = 0;
            m.rt.n = 0;
            m.rt.d_in = 0;
            m.rt.has_prev = false;
            m.rt.prev.clear();
            m.rt.triggered = false;
            m.rt.phase = 0;
        }
        for k in 0..self.machine_sensors.len() {
            let delay = self.count(self.machine_sensors[k].oscillation_delay);
            self.machine_sensors[k].rt =
                HoldOff { value: 0.0, active: false, iters: delay, just_activated: false };
        }
    }

    // ---- the step ---------------------------------------------------------------------------

    fn count(&self, id: ParamId) -> u32 {
        self.values[id.0].max(0.0) as u32
    }

    /// The angle an angle or feedback target asks for now, and its frame.
    fn pose_angle<E: SensorInput>(&self, target: PoseTarget, env: &mut E) -> (f64, Frame) {
        match target {
            PoseTarget::Angle(p, frame) => (self.values[p.0], frame),
            PoseTarget::Feedback { base, frame, start, len } => {
                let terms = &self.feedback[start as usize..(start + len) as usize];
                let sum: f64 = terms
                    .iter()
                    .map(|&(gain, sensor)| self.values[gain.0] * env.sensor(&self.query(sensor)))
                    .sum();
                (self.values[base.0] + sum, frame)
            }
            PoseTarget::Torso { .. } | PoseTarget::NoTorque | PoseTarget::DampingOnly => (0.0, Frame::Parent),
        }
    }

    fn query(&self, sensor: usize) -> SensorQuery<'_> {
        let s = &self.sensors[sensor];
        SensorQuery {
            id: sensor,
            name: &s.name,
            kind: &s.kind,
            args: &s.args,
            params: &self.values[s.params.clone()],
        }
    }

    fn fire<E>(&mut self, call: usize, env: &mut E, procs: &Procedures<E>, value: f64, origin: Origin) {
        let proc = self.calls[call].proc;
        let mut ctx = ProcCtx { controller: self, env, value, call, origin };
        procs.call(proc, &mut ctx);
    }

    /// One control iteration (spec §6.9): machine sensors with hold-off and their procedures, then the
    /// machines in the order of Fig. 5.3 (constant, sensory, default; declaration order within each),
    /// each sending its (interpolated) pose into `out` and then checking its outgoing transition.
    /// `out` is cleared first; with storage from [`Controller::new_targets`] nothing is allocated.
    ///
    /// `procedures` must be the registry the controller was built with.
    pub fn step<E: SensorInput>(&mut self, env: &mut E, procedures: &Procedures<E>, out: &mut Targets) {
        assert!(
            procedures.names().len() >= self.n_procedures,
            "step needs the procedure registry the controller was built with"
        );
        out.signals.clear();

        // 1. Machine sensors (spec §5.3, §5.4).
        for k in 0..self.machine_sensors.len() {
            let v = env.sensor(&self.query(self.machine_sensors[k].sensor));
            let delay = self.count(self.machine_sensors[k].oscillation_delay);
            let ms = &mut self.machine_sensors[k];
            let h = &mut ms.rt;
            h.value = v;
            h.iters = h.iters.saturating_add(1);
            h.just_activated = false;
            let raw = v != 0.0;
            if raw != h.active && h.iters >= delay {
                h.active = raw;
                h.iters = 0;
                h.just_activated = raw;
            }
            let fire = h.just_activated || (h.active && ms.fire == FireMode::WhileActive);
            if let (true, Some(call)) = (fire, ms.procedure) {
                self.fire(call, env, procedures, v, Origin::Sensor { sensor: k });
            }
        }

        // 2. Select and execute machines (Fig. 5.3).
        for m in &mut self.machines {
            m.rt.ran_now = false;
        }
        for i in 0..self.constant.len() {
            let m = self.constant[i];
            if self.machines[m].enabled {
                self.execute(m, env, procedures, out);
            }
        }
        let mut default_allowed = true;
        for i in 0..self.sensory.len() {
            let m = self.sensory[i];
            let MachineType::Sensory(k) = self.machines[m].kind else { unreachable!() };
            if self.machine_sensors[k].rt.active {
                if self.machines[m].enabled {
                    self.execute(m, env, procedures, out);
                }
                // Literal Fig. 5.3: an active but disabled sensory machine still suppresses defaults.
                default_allowed = false;
            }
        }
        if default_allowed {
            for i in 0..self.default.len() {
                let m = self.default[i];
                if self.machines[m].enabled {
                    self.execute(m, env, procedures, out);
                }
            }
        }
        // A machine that did not run loses its progress (spec §6.6).
        for m in &mut self.machines {
            if !m.rt.ran_now {
                m.rt.running = false;
            }
        }
        self.iteration += 1;
    }

    fn execute<E: SensorInput>(&mut self, m: usize, env: &mut E, procs: &Procedures<E>, out: &mut Targets) {
        {
            let rt = &mut self.machines[m].rt;
            if !rt.running {
                // Start at the first state, its pose sent as it is (spec §6.6).
                rt.running = true;
                rt.state = 0;
                rt.n = 0;
                rt.d_in = 0;
                rt.has_prev = false;
                rt.prev.clear();
                rt.triggered = false;
                rt.phase = 0;
            }
            rt.ran_now = true;
        }
        let s = self.machines[m].rt.state;
        if let Some(call) = self.machines[m].states[s].procedure {
            self.fire(call, env, procs, 0.0, Origin::State { machine: m, state: s });
        }

        // Send the pose, Eq. 5.3: P = P_prev (1 − N/D) + P_act (N/D) while N < D.
        let mach = &self.machines[m];
        let rt = &mach.rt;
        let weight = self.values[mach.weight.0];
        let blend = rt.has_prev && rt.n < rt.d_in;
        let alpha = if blend { f64::from(rt.n) / f64::from(rt.d_in) } else { 1.0 };
        let phase = rt.phase;
        for (e, item) in mach.poses[mach.states[s].pose[phase]].iter().enumerate() {
            let (target, frame) = match item.target {
                PoseTarget::Angle(..) | PoseTarget::Feedback { .. } => {
                    let (new, frame) = self.pose_angle(item.target, env);
                    let prev = if blend { find_prev(&rt.prev, item.actuator, e) } else { None };
                    let a = match prev {
                        Some(PrevEntry { angle: Some(old), frame: f, .. }) if f == frame => {
                            old * (1.0 - alpha) + new * alpha
                        }
                        _ => new,
                    };
                    (TargetKind::Angle(a), frame)
                }
                // Not blended: SIMBICON switches its poses at once.
                PoseTarget::Torso { angle, swing } => {
                    (TargetKind::Torso { angle: self.values[angle.0], swing }, Frame::World)
                }
                PoseTarget::NoTorque => (TargetKind::NoTorque, Frame::Parent),
                PoseTarget::DampingOnly => (TargetKind::DampingOnly, Frame::Parent),
            };
            debug_assert!(out.signals.len() < out.signals.capacity(), "targets storage too small");
            out.signals.push(TargetSignal { actuator: item.actuator, target, frame, weight, machine: m });
        }

        // Check the outgoing transition: only once the blend is complete (spec §6.5).
        let (n, d_in) = (rt.n, rt.d_in);
        let tr = &mach.transitions[s];
        let (cond, delay, procedure) = (tr.cond[phase], tr.delay, tr.procedure);
        let next_phase = phase ^ usize::from(tr.swap_roles);
        let mut value = 0.0;
        let fires = n >= d_in
            && match cond {
                // The origin state is used for exactly τ iterations (spec §6.7).
                Cond::Temporal(p) => n + 1 >= self.count(p),
                Cond::Sensory(sensor) => {
                    value = env.sensor(&self.query(sensor));
                    value != 0.0
                }
                Cond::Method => rt.triggered,
            };
        if fires {
            if let Some(call) = procedure {
                self.fire(call, env, procs, value, Origin::Transition { machine: m, transition: s });
            }
            let next = (s + 1) % self.machines[m].states.len();
            self.snapshot(m, (s, phase), (next, next_phase), env);
            let d = self.count(delay);
            let rt = &mut self.machines[m].rt;
            rt.d_in = d;
            rt.state = next;
            rt.phase = next_phase;
            rt.n = 0;
            rt.triggered = false;
            rt.has_prev = true;
        } else {
            let rt = &mut self.machines[m].rt;
            rt.n = rt.n.saturating_add(1);
        }
    }

    /// Keeps state `s`'s pose (fully reached: transitions wait for the blend) as P_anterior for the
    /// next state. An entry that was NoTorque/DampingOnly/Torso, or in another frame, and becomes an
    /// angle starts from the measured angle (spec §6.5). States come with the phase of the roles they
    /// are posed in.
    fn snapshot<E: SensorInput>(
        &mut self,
        m: usize,
        (s, phase): (usize, usize),
        (next, next_phase): (usize, usize),
        env: &mut E,
    ) {
        let pose = self.machines[m].states[s].pose[phase];
        self.machines[m].rt.prev.clear();
        for k in 0..self.machines[m].poses[pose].len() {
            let item = self.machines[m].poses[pose][k];
            let entry = match item.target {
                PoseTarget::Angle(..) | PoseTarget::Feedback { .. } => {
                    let (angle, frame) = self.pose_angle(item.target, env);
                    PrevEntry { actuator: item.actuator, angle: Some(angle), frame }
                }
                _ => PrevEntry { actuator: item.actuator, angle: None, frame: Frame::Parent },
            };
            self.machines[m].rt.prev.push(entry);
        }
        let mach = &mut self.machines[m];
        let rt = &mut mach.rt;
        for item in &mach.poses[mach.states[next].pose[next_phase]] {
            let frame = match item.target {
                PoseTarget::Angle(_, frame) | PoseTarget::Feedback { frame, .. } => frame,
                _ => continue,
            };
            let Some(prev) = rt.prev.iter_mut().find(|p| p.actuator == item.actuator) else { continue };
            if prev.angle.is_none() || prev.frame != frame {
                prev.angle = env.actuator_angle(item.actuator, frame);
                prev.frame = frame;
            }
        }
    }
}

fn find_prev(prev: &[PrevEntry], actuator: usize, hint: usize) -> Option<PrevEntry> {
    match prev.get(hint) {
        Some(p) if p.actuator == actuator => Some(*p),
        _ => prev.iter().find(|p| p.actuator == actuator).copied(),
    }
}

/// Visits every number of a description in the order [`Controller::from_desc`] numbers them.
fn for_each_param_mut(desc: &mut ControllerDesc, f: &mut impl FnMut(&mut Param)) {
    for s in &mut desc.sensors {
        s.params.iter_mut().for_each(&mut *f);
        f(&mut s.oscillation_delay);
    }
    for m in &mut desc.machines {
        f(&mut m.weight);
        for s in &mut m.states {
            if s.same_pose_as.is_some() {
                continue;
            }
            for e in &mut s.pose {
                match &mut e.1 {
                    TargetDesc::Angle(p) | TargetDesc::WorldAngle(p) => f(p),
                    TargetDesc::Feedback(fd) => {
                        f(&mut fd.base);
                        for t in &mut fd.terms {
                            f(&mut t.gain);
                            t.sensor.params.iter_mut().for_each(&mut *f);
                        }
                    }
                    TargetDesc::Torso(td) => f(&mut td.angle),
                    TargetDesc::NoTorque | TargetDesc::DampingOnly => {}
                }
            }
        }
        for t in &mut m.transitions {
            f(&mut t.delay);
            match &mut t.when {
                Condition::Temporal(p) => f(p),
                Condition::Sensory(sd) => sd.params.iter_mut().for_each(&mut *f),
                Condition::Method => {}
            }
        }
    }
}
