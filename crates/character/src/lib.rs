//! Characters: an `anima-control` [`Controller`] driving the articulated models of an `anima-body`
//! [`World`] — the adapter between the two crates (Nunes 2006, spec §3.2, §6.9), and the only crate that
//! knows both.
//!
//! # What this crate is
//!
//! Each control iteration of Δt (0.05 s in the thesis, spec §3.1–§3.2):
//!
//! 1. every model is sensed into its [`Sensors`] reading (no allocation);
//! 2. the controller steps: its sensor queries are answered by the body's sensor catalogue
//!    ([`catalogue`]), through a binding made once per sensor when the character is built; its
//!    procedures act on the world (`release_ball` releases the hand–ball welds, `push` applies a force);
//! 3. its target signals become the models' actuator [`Commands`](anima_body::Commands), one
//!    [`Signal`] per signal, which the body averages by Eqs. 5.1–5.2 (a torso target — SIMBICON's
//!    stance hip — becomes a [`Target::Torso`] whose torque the body computes at every sub-step);
//! 4. the world advances Δt in its physics sub-steps (`WorldSettings::substeps`).
//!
//! Actuator names are a model's own (`hip_l`) for a one-model character, or `alias/name`
//! (`acrobat/hip_l`, `pusher/hip_l`) with the aliases given when the character is built. Sensor
//! arguments that are model aliases select the model; `left`/`right` select the side; `or`/`and`
//! combine the landing tests.
//!
//! # What it is not
//!
//! No files (scene files that name a skeleton and a controller are read by `anima-scene`), no
//! evaluators or objectives (the thesis's walking, throwing and backflip measures live in `anima-lab`).
//!
//! # Use
//!
//! ```
//! use anima_body::{BuiltinSkeleton, Placement, World, WorldSettings};
//! use anima_character::{Character, procedures};
//! use anima_control::Controller;
//!
//! let text = r#"Controller(
//!     name: "kneel",
//!     actuators: ["knee_l", "knee_r"],
//!     machines: [Machine(
//!         name: "M", kind: Constant,
//!         states: [State(name: "E1", pose: [("knee_l", Angle(-0.6)), ("knee_r", Angle(-0.6))])],
//!         transitions: [Transition(when: Temporal(1000), delay: 10)],
//!     )],
//! )"#;
//! let procedures = procedures();
//! let controller = Controller::from_ron(text, &procedures).unwrap();
//! let mut world = World::new(WorldSettings::thesis()).unwrap();
//! world.add_model(&BuiltinSkeleton::Humanoid.load(), Placement::OnGround { dx: 0.0 }).unwrap();
//! let mut character = Character::new(world, controller, procedures, &[]).unwrap();
//! for _ in 0..20 {
//!     character.step().unwrap(); // one control iteration of 0.05 s
//! }
//! let knee = character.env.world.skeleton(0).unwrap().actuator_index("knee_l").unwrap();
//! assert!(character.env.sensors[0].actuator_angle[knee] < 0.0, "the knees bend towards their target");
//! ```

use anima_body::sensors::catalogue::{self, LandCombine};
use anima_body::{BodyError, Sensors, Signal, Skeleton, Target, TargetFrame, World};
use anima_control::{
    Controller, ControllerError, Frame, Procedures, SensorInput, SensorQuery, TargetKind, Targets,
};

/// What can go wrong when a controller is bound to a world.
#[derive(Debug, thiserror::Error)]
pub enum CharacterError {
    /// A controller or skeleton description that is not valid (both report [`ControllerError`]'s
    /// located form).
    #[error(transparent)]
    Description(#[from] ControllerError),
    #[error(transparent)]
    Body(#[from] BodyError),
    #[error("controller actuator `{0}` names no actuator of the world's models")]
    Actuator(String),
    #[error("a torso target on `{actuator}` names `{swing}` as its swing: the two must drive one model")]
    TorsoAcrossModels { actuator: String, swing: String },
    #[error("sensor `{name}`: {why}")]
    Sensor { name: String, field: String, why: String },
    #[error("{why}")]
    Procedure { field: String, why: String },
}

impl CharacterError {
    /// The error as the controller file's located error, when it concerns one of the file's fields (a
    /// sensor, a procedure call): `text` is the file's text, for the line and column.
    pub fn field_error(&self, text: &str) -> Option<ControllerError> {
        match self {
            Self::Description(e) => Some(e.clone()),
            Self::Sensor { name, field, why } => {
                Some(ControllerError::invalid(field.as_str(), format!("sensor `{name}`: {why}")).locate(text))
            }
            Self::Procedure { field, why } => {
                Some(ControllerError::invalid(field.as_str(), why.as_str()).locate(text))
            }
            _ => None,
        }
    }
}

/// One sensor's computation, resolved once from its kind and arguments.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Binding {
    FootUp {
        model: usize,
        side: usize,
    },
    CogAhead {
        model: usize,
        side: usize,
    },
    Landing {
        model: usize,
        side: usize,
        combine: LandCombine,
    },
    FallingForward {
        model: usize,
    },
    FallingBackward {
        model: usize,
    },
    FootOnHands {
        acrobat: usize,
        pusher: usize,
    },
    FlipBrake {
        model: usize,
    },
    BothFeetDown {
        model: usize,
    },
    CogLow {
        model: usize,
    },
    TrunkAngle {
        model: usize,
        joint: usize,
    },
    ComOffset {
        model: usize,
        side: usize,
    },
    ComSpeed {
        model: usize,
    },
    TrunkRate {
        model: usize,
    },
    GroundSlope {
        model: usize,
    },
    ComAheadOfAnkle {
        model: usize,
        side: usize,
    },
    FootDown {
        model: usize,
        side: usize,
    },
    CaptureOutside {
        model: usize,
    },
    /// Always 0 (a sensor the adapter was told to ignore).
    Never,
}

/// The controller's environment: the world, one sensor reading per model, the sensor bindings. It
/// answers the controller's sensor queries and is what procedures act on.
#[derive(Debug)]
pub struct BodyEnv {
    pub world: World,
    /// Per model, the reading the current iteration's sensors use.
    pub sensors: Vec<Sensors>,
    bindings: Vec<Binding>,
    /// Controller actuator → (model, actuator of that model).
    actuators: Vec<(usize, usize)>,
    /// The iteration at which `release_ball` fired, if it has.
    pub released_at: Option<u64>,
    iteration: u64,
}

impl BodyEnv {
    /// The control iteration being computed (0 = the first).
    pub fn iteration(&self) -> u64 {
        self.iteration
    }

    /// Releases every weld of every model that still holds (the thesis's ball release, §4.5.3).
    pub fn release_all_welds(&mut self) -> Result<(), BodyError> {
        for m in 0..self.world.n_models() {
            for w in 0..self.world.skeleton(m)?.n_welds() {
                if self.world.weld_holds(m, w)? {
                    self.world.release_weld(m, w)?;
                }
            }
        }
        self.released_at.get_or_insert(self.iteration);
        Ok(())
    }
}

fn param(params: &[f64], k: usize) -> f64 {
    params.get(k).copied().unwrap_or(0.0)
}

impl SensorInput for BodyEnv {
    fn sensor(&mut self, q: &SensorQuery<'_>) -> f64 {
        let s = &self.sensors;
        match self.bindings[q.id] {
            Binding::FootUp { model, side } => catalogue::foot_up(&s[model], side),
            Binding::CogAhead { model, side } => catalogue::cog_ahead(&s[model], side, param(q.params, 0)),
            Binding::Landing { model, side, combine } => {
                catalogue::landing(&s[model], side, param(q.params, 0), combine)
            }
            Binding::FallingForward { model } => catalogue::falling_forward(&s[model], param(q.params, 0)),
            Binding::FallingBackward { model } => catalogue::falling_backward(&s[model], param(q.params, 0)),
            Binding::FootOnHands { acrobat, pusher } => catalogue::foot_on_hands(&s[acrobat], &s[pusher]),
            Binding::FlipBrake { model } => catalogue::flip_brake(&s[model], param(q.params, 0)),
            Binding::BothFeetDown { model } => catalogue::both_feet_down(&s[model]),
            Binding::CogLow { model } => catalogue::cog_low(&s[model], param(q.params, 0)),
            Binding::TrunkAngle { model, joint } => catalogue::trunk_angle(&s[model], joint),
            Binding::ComOffset { model, side } => catalogue::com_offset(&s[model], side),
            Binding::ComSpeed { model } => catalogue::com_speed(&s[model]),
            Binding::TrunkRate { model } => catalogue::trunk_rate(&s[model]),
            Binding::GroundSlope { model } => catalogue::ground_slope(&s[model]),
            Binding::ComAheadOfAnkle { model, side } => catalogue::com_ahead_of_ankle(&s[model], side),
            Binding::FootDown { model, side } => catalogue::foot_down(&s[model], side),
            Binding::CaptureOutside { model } => catalogue::capture_outside(&s[model], param(q.params, 0)),
            Binding::Never => 0.0,
        }
    }

    fn actuator_angle(&mut self, actuator: usize, frame: Frame) -> Option<f64> {
        let (m, a) = *self.actuators.get(actuator)?;
        match frame {
            Frame::Parent => Some(self.sensors[m].actuator_angle[a]),
            Frame::World => None,
        }
    }
}

/// `push(model, body, fx, fy)`: four arguments, the force's two finite numbers; the model and the body
/// are checked against the skeletons when the controller is bound ([`check_controller`]).
fn check_push(a: &anima_control::CallArgs<'_>) -> Result<(), String> {
    a.expect_count(4, "model, body, fx, fy")?;
    a.expect_number(2)?;
    a.expect_number(3)
}

/// The procedures every character offers besides the controller crate's built-ins:
///
/// - `release_ball`: releases every hand–ball weld (spec §8.3.1, on the throw's T2);
/// - `push(model, body, fx, fy)`: applies a force (N) at a body's centre for this iteration (spec
///   §3.6; model and body by name, e.g. `push("", "head", -150, 0)`).
pub fn procedures() -> Procedures<BodyEnv> {
    let mut p: Procedures<BodyEnv> = Procedures::with_builtins();
    p.register_checked(
        "release_ball",
        |a| a.expect_count(0, "none"),
        |ctx| {
            // A release of welds that exist cannot fail; nothing to report from inside a step.
            let _ = ctx.env.release_all_welds();
        },
    );
    p.register_checked("push", check_push, |ctx| {
        let args = ctx.args().to_vec();
        let num = |k: usize| args.get(k).and_then(|a| a.parse::<f64>().ok()).unwrap_or(0.0);
        let env = &mut *ctx.env;
        let model = (0..env.world.n_models())
            .find(|&m| env.world.skeleton(m).is_ok_and(|sk| sk.name() == args[0]))
            .unwrap_or(0);
        let Some(body) = env.world.skeleton(model).ok().and_then(|sk| sk.body_index(&args[1])) else {
            return;
        };
        let at = env.sensors[model].body_position[body];
        let _ = env.world.apply_force(model, body, [num(2), num(3)], at);
    });
    p
}

/// A controller bound to a world. Build with [`Character::new`], then call [`Character::step`] once
/// per control iteration.
#[derive(Debug)]
pub struct Character {
    pub env: BodyEnv,
    pub controller: Controller,
    procedures: Procedures<BodyEnv>,
    targets: Targets,
}

fn side_of(args: &[String]) -> Option<usize> {
    args.iter().find_map(|a| match a.as_str() {
        "left" => Some(0),
        "right" => Some(1),
        _ => None,
    })
}

/// What binding a controller to its models resolves once: each controller actuator's (model,
/// actuator) and each sensor's computation.
struct Bound {
    actuators: Vec<(usize, usize)>,
    bindings: Vec<Binding>,
}

/// Checks that `controller` can drive models with these skeletons (`aliases` as in [`Character::new`]):
/// every actuator names one of theirs, every sensor is a kind the catalogue computes with the
/// arguments it needs, every `push` names a model and a body they have. Needs no world, so a scene
/// reader can check a controller file when it reads it; the errors that concern a field of the file
/// name it ([`CharacterError::field_error`]).
pub fn check_controller(
    controller: &Controller,
    skeletons: &[&Skeleton],
    procedures: &Procedures<BodyEnv>,
    aliases: &[&str],
) -> Result<(), CharacterError> {
    bind(controller, skeletons, procedures, aliases).map(|_| ())
}

fn bind(
    controller: &Controller,
    skeletons: &[&Skeleton],
    procedures: &Procedures<BodyEnv>,
    aliases: &[&str],
) -> Result<Bound, CharacterError> {
    let n_models = skeletons.len();
    let skeleton = |m: usize| skeletons.get(m).copied().ok_or(BodyError::NoSuchModel(m));
    let model_of = |name: &str| aliases.iter().position(|a| *a == name);
    let mut actuators = Vec::with_capacity(controller.actuators().len());
    for name in controller.actuators() {
        let (m, local) = match name.split_once('/') {
            Some((alias, local)) => {
                (model_of(alias).ok_or_else(|| CharacterError::Actuator(name.clone()))?, local)
            }
            None => (0, name.as_str()),
        };
        let a = skeleton(m)?.actuator_index(local).ok_or_else(|| CharacterError::Actuator(name.clone()))?;
        actuators.push((m, a));
    }
    let mut bindings = Vec::with_capacity(controller.sensors().len());
    for s in controller.sensors() {
        let models: Vec<usize> = s.args.iter().filter_map(|a| model_of(a)).collect();
        let model = models.first().copied().unwrap_or(0);
        // `part`: the sensor's field at fault, `kind` or `args`.
        let err = |part: &str, why: &str| CharacterError::Sensor {
            name: s.name.clone(),
            field: format!("{}.{part}", s.field),
            why: why.into(),
        };
        let side = || side_of(&s.args).ok_or_else(|| err("args", "needs a side, `left` or `right`"));
        let b = match s.kind.as_str() {
            "foot_up" => Binding::FootUp { model, side: side()? },
            "cog_ahead" => Binding::CogAhead { model, side: side()? },
            "landing" => Binding::Landing {
                model,
                side: side()?,
                combine: if s.args.iter().any(|a| a == "and") { LandCombine::And } else { LandCombine::Or },
            },
            "falling_forward" => Binding::FallingForward { model },
            "falling_backward" => Binding::FallingBackward { model },
            "foot_on_hands" => {
                let acrobat = model_of("acrobat").unwrap_or(0);
                let pusher = model_of("pusher").unwrap_or(1.min(n_models.saturating_sub(1)));
                Binding::FootOnHands { acrobat, pusher }
            }
            "flip_brake" => Binding::FlipBrake { model },
            "both_feet_down" => Binding::BothFeetDown { model },
            "cog_low" => Binding::CogLow { model },
            "trunk_angle" => {
                let joint =
                    skeleton(model)?.joint_index("waist").ok_or_else(|| err("kind", "no `waist` joint"))?;
                Binding::TrunkAngle { model, joint }
            }
            "com_offset" => Binding::ComOffset { model, side: side()? },
            "com_speed" => Binding::ComSpeed { model },
            "trunk_rate" => Binding::TrunkRate { model },
            "ground_slope" => Binding::GroundSlope { model },
            "com_ahead_of_ankle" => Binding::ComAheadOfAnkle { model, side: side()? },
            "foot_down" => Binding::FootDown { model, side: side()? },
            "capture_outside" => Binding::CaptureOutside { model },
            "never" => Binding::Never,
            other => return Err(err("kind", &format!("unknown sensor kind `{other}`"))),
        };
        bindings.push(b);
    }
    for (a, swing) in controller.torso_pairs() {
        if actuators[a].0 != actuators[swing].0 {
            let names = controller.actuators();
            return Err(CharacterError::TorsoAcrossModels {
                actuator: names[a].clone(),
                swing: names[swing].clone(),
            });
        }
    }
    if let Some(push) = procedures.index("push") {
        for (_, args, field) in controller.calls().filter(|&(p, ..)| p == push) {
            let why = |why: String| CharacterError::Procedure { field: format!("{field}.args"), why };
            let model = match args.first().map(String::as_str) {
                None | Some("") => 0,
                Some(name) => skeletons.iter().position(|sk| sk.name() == name).ok_or_else(|| {
                    let names: Vec<&str> = skeletons.iter().map(|sk| sk.name()).collect();
                    why(format!("`push`: no model named `{name}`; the models: {}", names.join(", ")))
                })?,
            };
            let body = args.get(1).map_or("", String::as_str);
            if skeleton(model)?.body_index(body).is_none() {
                return Err(why(format!("`push`: model {model} has no body named `{body}`")));
            }
        }
    }
    Ok(Bound { actuators, bindings })
}

impl Character {
    /// Binds `controller` to `world`. `aliases[m]` is the prefix of model m's actuator names in the
    /// controller (`"acrobat"` for `acrobat/hip_l`); with a single model, pass `&[]` and use the
    /// model's own names. `procedures` must be the registry the controller was parsed with (start
    /// from [`procedures`]).
    pub fn new(
        world: World,
        controller: Controller,
        procedures: Procedures<BodyEnv>,
        aliases: &[&str],
    ) -> Result<Self, CharacterError> {
        let skeletons: Vec<&Skeleton> =
            (0..world.n_models()).map(|m| world.skeleton(m)).collect::<Result<_, _>>()?;
        let Bound { actuators, bindings } = bind(&controller, &skeletons, &procedures, aliases)?;
        let n_models = skeletons.len();
        let sensors = (0..n_models).map(|m| Sensors::new(&world, m)).collect::<Result<Vec<_>, _>>()?;
        let targets = controller.new_targets();
        let mut c = Self {
            env: BodyEnv { world, sensors, bindings, actuators, released_at: None, iteration: 0 },
            controller,
            procedures,
            targets,
        };
        c.sense()?;
        Ok(c)
    }

    fn sense(&mut self) -> Result<(), BodyError> {
        for s in &mut self.env.sensors {
            self.env.world.sense(s)?;
        }
        Ok(())
    }

    /// The registry the controller runs with.
    pub fn procedures(&self) -> &Procedures<BodyEnv> {
        &self.procedures
    }

    /// The signals sent in the last iteration.
    pub fn targets(&self) -> &Targets {
        &self.targets
    }

    /// (model, actuator) of each controller actuator.
    pub fn actuator_map(&self) -> &[(usize, usize)] {
        &self.env.actuators
    }

    /// One control iteration: sense, run the controller, command the actuators, step the world.
    pub fn step(&mut self) -> Result<(), BodyError> {
        self.env.iteration = self.controller.iteration();
        self.controller.step(&mut self.env, &self.procedures, &mut self.targets);
        for m in 0..self.env.world.n_models() {
            self.env.world.commands_mut(m)?.clear();
        }
        for s in self.targets.signals() {
            let (m, actuator) = self.env.actuators[s.actuator];
            let target = match s.target {
                TargetKind::Angle(a) => Target::Angle(a),
                TargetKind::NoTorque => Target::NoTorque,
                TargetKind::DampingOnly => Target::DampingOnly,
                // Checked in `new`: the swing actuator drives the same model.
                TargetKind::Torso { angle, swing } => {
                    Target::Torso { angle, swing: self.env.actuators[swing].1 }
                }
            };
            let frame = match s.frame {
                Frame::Parent => TargetFrame::Parent,
                Frame::World => TargetFrame::World,
            };
            self.env.world.commands_mut(m)?.push(Signal { actuator, target, frame, weight: s.weight })?;
        }
        self.env.world.step()?;
        self.sense()
    }
}
