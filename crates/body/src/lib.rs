//! Planar articulated figures — the humanoids of Nunes 2006 — simulated on Rapier multibody joints,
//! with our own PD actuator layer and a sensor library.
//!
//! - [`Skeleton`]: bodies, hinges, welds, actuators and collision groups as data (a RON format with
//!   errors that name line and field), and the thesis's models ([`BuiltinSkeleton`]).
//! - [`World`]: skeletons become Rapier multibodies moving exactly in the x–y plane, on a ground; a
//!   fixed control step with physics sub-steps; welds released at run time; pushes.
//! - Actuators: a controller holds [`Signal`]s in a model's [`Commands`]; several targets on one
//!   actuator are averaged by weight (Eqs. 5.1–5.2), and the PD law runs in the [`PdMode`] the skeleton
//!   chooses — explicit, the thesis's ODE-style brake, Rapier's implicit motors or springs, or stable PD;
//!   a [`Target::Torso`] signal is SIMBICON's stance hip, τ = −τ_torso − τ_swing, applied explicitly after
//!   every other actuator's torque is known.
//! - [`Sensors`]: plain values read into caller-owned storage, a [`SensorDelay`] line, and the
//!   thesis's sensor catalogue ([`sensors::catalogue`]).
//!
//! This is the only anima crate that links rapier3d, and no Rapier type crosses its public API:
//! callers see indices, `f64` values and plain structs, so the engine can change underneath them. It
//! is not a controller (state machines and optimisers live in anima-control) and it does no file I/O:
//! skeletons and scenes are parsed from strings the caller reads.
//!
//! Units are SI: the thesis's tables are read as kg, N·m/rad and N·m·s/rad (see `docs/body.md` for
//! that decision and for the PD stability report).
//!
//! ```
//! use anima_body::{Actuation, BuiltinSkeleton, PdMode, Placement, Sensors, Signal, World, WorldSettings};
//!
//! // The thesis's humanoid, its gains × 100 as implicit springs, standing on the ground at Δt = 0.05 s.
//! let actuation = Actuation { mode: PdMode::ImplicitSpring, gain_scale: 100.0, torque_limit_rad: 1.0, brake_rad_s: 4.0 };
//! let humanoid = BuiltinSkeleton::Humanoid.load().with_actuation(actuation).unwrap();
//! let mut world = World::new(WorldSettings::thesis()).unwrap();
//! let m = world.add_model(&humanoid, Placement::OnGround { dx: 0.0 }).unwrap();
//! let knee = humanoid.actuator_index("knee_l").unwrap();
//! let mut sensors = Sensors::new(&world, m).unwrap();
//! for _ in 0..20 {
//!     // Every actuator holds its initial angle but the left knee, which bends.
//!     let commands = world.commands_mut(m).unwrap();
//!     commands.clear();
//!     for a in 0..humanoid.n_actuators() {
//!         commands.push(Signal::angle(a, if a == knee { -0.5 } else { 0.0 })).unwrap();
//!     }
//!     world.step().unwrap();
//! }
//! world.sense(&mut sensors).unwrap();
//! assert!(sensors.actuator_angle[knee] < -0.2, "the knee follows its target");
//! assert!(sensors.all_finite());
//! ```

mod actuator;
mod dense;
mod error;
pub mod scene;
pub mod sensors;
mod skeleton;
mod world;

pub use actuator::{CommandError, Commands, Signal, Target, TargetFrame};
pub use error::{BodyError, SkeletonError, SkeletonErrorKind};
pub use scene::{BodyScene, ModelEntry, Pose, SceneError, SkeletonSource};
pub use sensors::{BodyLayout, Contact, SensorDelay, Sensors, Support};
pub use skeleton::{
    Actuation, ActuatorDesc, ActuatorSpec, BodyDesc, BuiltinSkeleton, CollisionGroupDesc, Drive, DriveSpec,
    Facing, JointDesc, JointKind, PdMode, Role, Shape, Side, Skeleton, SkeletonDesc, WeldDesc,
};
pub use world::{BodyPose, Ground, Momentum, Placement, Relief, SolverSettings, Touch, World, WorldSettings};
