//! Controllers for physically based characters as data — the sensory state machines of Nunes 2006
//! — and the stochastic optimisers that tune them.
//!
//! # What this crate is
//!
//! A [`Controller`] is a set of state machines, each driving any subset of a character's actuators,
//! plus a set of sensors (spec §6.1). Every machine owns a cyclic vector of states; a state holds a
//! *pose* (a target per actuator: a joint angle, a world angle, a balance-feedback expression, a torso
//! target, no torque, or damping only) and the transitions between states fire after a time, when a
//! sensor turns non-zero, or when someone calls a method. SIMBICON (Yin et al. 2007) is a machine with
//! *roles* — the stance and swing legs — that a transition swaps, and a *torso* target on the stance
//! hip, whose torque the body computes as −τ_torso − τ_swing (`docs/control.md`). While a pose changes it is blended linearly over the transition's interpolation delay
//! (Eq. 5.3). Machines are *constant* (always run), *sensory* (run while their sensor is active) or
//! *default* (run while no sensory machine's sensor is active); several may drive one actuator, and
//! their targets are averaged by machine weight (Eqs. 5.1–5.2). Procedures — named Rust functions
//! from a [`Procedures`] registry — fire on states, transitions and sensors, and may change
//! parameters on line, switch machines or act on the world.
//!
//! Controllers are RON files ([`ControllerDesc`] mirrors one); every number in a file is a
//! parameter in one flat table, and a number written with an interval
//! (`(value: 0.25, min: -0.25, max: 0.75)`) is free for the optimisers in [`optimise`]: the thesis's
//! random modifier and staged greedy search, CMA-ES with IPOP restarts, random search and simulated
//! annealing. They are seeded, evaluate each generation in parallel with rayon with results that do
//! not depend on the number of threads, and log every evaluation so that a run can be resumed.
//!
//! # What it deliberately is not
//!
//! There is no physics here, and no anima crate below it. The controller talks to a body only
//! through plain values: each iteration the caller answers [`SensorInput::sensor`] queries (a
//! sensor's kind, fixed arguments and current parameters in; a real number out, 0 meaning inactive),
//! and [`Controller::step`] writes [`TargetSignal`]s — actuator index, target, frame, weight — into
//! caller-owned [`Targets`]. The scene layer maps those onto the body crate's actuator commands
//! (which average them by Eqs. 5.1–5.2 with the PD law) and its sensor catalogue onto the sensor
//! kinds. Keeping the two apart lets a controller be tested, optimised against synthetic objectives,
//! or driven by another physics engine without change.
//!
//! # Use
//!
//! ```
//! use anima_control::{Controller, Procedures, SensorQuery};
//!
//! let text = r#"Controller(
//!     name: "sway",
//!     actuators: ["hip_l", "hip_r"],
//!     machines: [Machine(
//!         name: "M", kind: Constant,
//!         states: [
//!             State(name: "E1", pose: [("hip_l", Angle(0.3)), ("hip_r", Angle(-0.3))]),
//!             State(name: "E2", pose: [("hip_l", Angle(-0.3)), ("hip_r", Angle(0.3))]),
//!         ],
//!         transitions: [
//!             Transition(when: Temporal(10), delay: 4),
//!             Transition(when: Sensory((kind: "foot_up", args: ["left"])), delay: 4),
//!         ],
//!     )],
//! )"#;
//! let procedures = Procedures::new();
//! let mut controller = Controller::from_ron(text, &procedures).unwrap();
//! let mut targets = controller.new_targets(); // reserved once: step never allocates
//! let mut sensors = |q: &SensorQuery| if q.kind == "foot_up" { 1.0 } else { 0.0 };
//! for _ in 0..30 {
//!     controller.step(&mut sensors, &procedures, &mut targets);
//!     for s in targets.signals() {
//!         // hand s.actuator, s.target, s.frame and s.weight to the body's actuator commands
//!         let _ = s;
//!     }
//! }
//! ```
//!
//! Timing follows the spec's reconstruction (§6.7): in each iteration a running machine first sends
//! its active state's (blended) pose, then checks its outgoing transition; a transition may fire only
//! once the blend is complete, and a state left by a temporal transition of time τ is used for
//! exactly τ iterations. `docs/control.md` describes the file format and the optimisers.

mod controller;
mod desc;
mod error;
mod io;
pub mod optimise;
mod param;
mod procedure;

pub use controller::{Controller, Machine, MachineSensor, MachineType, Scope, Selection, Sensor};
pub use desc::{
    ActuatorRef, Condition, ControllerDesc, FeedbackDesc, FeedbackTerm, FireMode, MachineDesc, MachineKind,
    MachineSensorDesc, PoseEntry, ProcedureCall, RolesDesc, SensorDesc, StateDesc, TargetDesc, TorsoDesc,
    TransitionDesc,
};
pub use error::{ControllerError, ControllerErrorKind};
pub use io::{Frame, SensorInput, SensorQuery, TargetKind, TargetSignal, Targets};
pub use param::{Param, ParamId, ParamInfo, ParamKind, ParamOwner};
pub use procedure::{ArgCheck, CallArgs, Origin, ProcCtx, ProcedureFn, Procedures};
