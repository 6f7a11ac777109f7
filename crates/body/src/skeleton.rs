//! Skeletons as data: the RON format (bodies, hinges, welds, actuators, collision groups, actuation
//! settings), its checks, and the skeletons the thesis uses.
//!
//! Coordinates are the model's own initial configuration in metres, x forward for a model facing +x,
//! y up, all centres at z = 0 (Nunes 2006 Table 6.1); a world places the model by a translation. Joint
//! angles are zero in that configuration (§3.3 of the spec).

use std::collections::HashMap;

use anima_format::limits::MAX_BODIES;
use serde::{Deserialize, Serialize};

use crate::error::SkeletonError;

/// Body shapes. Planar: every shape is extruded over the skeleton's `depth` along z, which matters
/// only for drawing and for the (irrelevant) inertia about x and y.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Shape {
    /// A box `width` (x) by `height` (y), in metres. Moment of inertia about z: m (w² + h²) / 12.
    Box { width: f64, height: f64 },
    /// A sphere of `radius` metres. Moment of inertia about z: 2 m r² / 5.
    Ball { radius: f64 },
}

impl Shape {
    /// Moment of inertia about the z axis through the centre, kg·m², for mass `mass` kg.
    pub fn inertia_zz(&self, mass: f64) -> f64 {
        match *self {
            Shape::Box { width, height } => mass * (width * width + height * height) / 12.0,
            Shape::Ball { radius } => 0.4 * mass * radius * radius,
        }
    }
}

/// Which side of the figure a body belongs to: the thesis draws left limbs green and right limbs red.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Side {
    #[default]
    Centre,
    Left,
    Right,
}

/// What a body is for sensors that ask about feet and hands (contacts, the support foot).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Role {
    #[default]
    Other,
    Foot,
    Hand,
    Head,
    Pelvis,
    /// A thrown or held object (the thrower's ball): not part of the figure's centre of mass.
    Prop,
}

/// The direction a model faces. A model facing −x (the backflip pusher) reads every joint angle,
/// inter-thigh angle and actuator torque with the opposite sign, so that one anatomical pose has the
/// same numbers on both humanoids (spec §3.5.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Facing {
    #[default]
    PlusX,
    MinusX,
}

impl Facing {
    /// +1 for a model facing +x, −1 for one facing −x.
    pub fn sign(self) -> f64 {
        match self {
            Facing::PlusX => 1.0,
            Facing::MinusX => -1.0,
        }
    }
}

/// One rigid body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Body", deny_unknown_fields)]
pub struct BodyDesc {
    pub name: String,
    pub shape: Shape,
    /// Mass in kg (see the units decision in `docs/body.md`).
    pub mass: f64,
    /// Centre of mass in the initial configuration, metres.
    pub centre: (f64, f64),
    #[serde(default)]
    pub side: Side,
    #[serde(default)]
    pub role: Role,
    /// Collision group (by name); `None` is the skeleton's first group.
    #[serde(default)]
    pub group: Option<String>,
    /// Fixed in the world (a test bench's base). Only a body that hangs from no joint can be fixed.
    #[serde(default)]
    pub fixed: bool,
}

/// Joint kinds. Only hinges exist in the thesis's models; the enum leaves room for more.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum JointKind {
    /// One rotational degree of freedom about z; the angle is the child's rotation relative to the
    /// parent, counter-clockwise positive (in the model's facing convention), zero initially.
    Hinge,
}

/// A joint of the tree: `child` hangs from `parent` at `anchor`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Joint", deny_unknown_fields)]
pub struct JointDesc {
    pub name: String,
    pub kind: JointKind,
    pub parent: String,
    pub child: String,
    /// Joint position in the initial configuration, metres.
    pub anchor: (f64, f64),
    /// Joint stops (min, max) in radians, in the model's facing convention. The thesis has none.
    #[serde(default)]
    pub limits: Option<(f64, f64)>,
}

/// A rigid weld between two bodies that can be released at run time (the thrower's hands on the
/// ball). Welds may close loops; they are solved as constraints beside the tree.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Weld", deny_unknown_fields)]
pub struct WeldDesc {
    pub name: String,
    pub a: String,
    pub b: String,
    /// Weld point in the initial configuration, metres.
    pub anchor: (f64, f64),
}

/// What an actuator turns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Drive {
    /// The angle of a hinge (by joint name).
    Joint(String),
    /// The world-angle difference θ(a) − θ(b) of two bodies, with torque +T on `a` and −T on `b`: the
    /// thesis's inter-thigh actuator (§3.4.3), which turns the thighs apart without loading the pelvis.
    BodyPair { a: String, b: String },
}

/// One PD actuator (Eq. 2.1): T = kp (θd − θ) − kd θ̇, clamped to ±max_torque.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Actuator", deny_unknown_fields)]
pub struct ActuatorDesc {
    pub name: String,
    /// The thesis's 1-based actuator number (arms are 11–14); the controller addresses by name or
    /// number.
    pub number: u32,
    pub drives: Drive,
    /// Stiffness, N·m/rad, before the skeleton's `gain_scale`.
    pub kp: f64,
    /// Damping, N·m·s/rad, before the skeleton's `gain_scale`.
    pub kd: f64,
    /// Torque cap, N·m, before `gain_scale`; `None` is `torque_limit_rad · kp` (spec §4.4).
    #[serde(default)]
    pub max_torque: Option<f64>,
    /// Brake torque of the ODE-style velocity motor, N·m, before `gain_scale`; `None` is
    /// `brake_rad_s · kd` (spec §4.3).
    #[serde(default)]
    pub brake_torque: Option<f64>,
    /// An actuator-level target, radians: the actuator then ignores every pose signal (spec §4.5).
    #[serde(default)]
    pub fixed_target: Option<f64>,
}

/// A collision group: which other bodies the bodies of this group touch. A pair of bodies of one
/// model collides when either group lists the other (or both are the same group listing itself).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Group", deny_unknown_fields)]
pub struct CollisionGroupDesc {
    pub name: String,
    /// Touches the ground.
    pub ground: bool,
    /// Touches every body of every other model in the world (the backflip's two humanoids).
    pub other_models: bool,
    /// Groups of this same model it touches; the thesis's models list none (no self-collision).
    #[serde(default)]
    pub groups: Vec<String>,
}

/// How the PD actuators are turned into motion. Compared in `docs/body.md`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum PdMode {
    /// (a) Eq. 2.1 as an explicit torque, held over the step: stable only while
    /// kp·Δt²/I + 2·kd·Δt/I < 4 for the lightest effective inertia I.
    Explicit,
    /// (b) The thesis's ODE set-up (§6.2): kd = 0 in Eq. 2.1 and a zero-velocity joint motor whose
    /// torque is capped at the brake torque (Rapier's per-DoF dry joint friction).
    OdeBrake,
    /// (c) Rapier's joint motor with a position target, stiffness kp and damping kd (force based),
    /// solved implicitly with the contacts, its impulse capped at max_torque·Δt.
    ImplicitMotor,
    /// (c′) Rapier's implicit joint spring (kp, target) and joint damping (kd) in the multibody's
    /// generalised mass matrix: backward Euler, no torque cap.
    ImplicitSpring,
    /// (d) Stable PD (Tan, Liu & Turk 2011): explicit torques from the state predicted one step ahead
    /// with the articulated mass matrix, τ = −kp (q + Δt q̇ − q̄) − kd (q̇ + Δt q̈).
    StablePd,
}

/// Actuation settings that belong to the skeleton (the controller cannot change them), overridable
/// when a model is added to a world.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Actuation", deny_unknown_fields)]
pub struct Actuation {
    pub mode: PdMode,
    /// Global factor G on every kp, kd, torque cap and brake (spec §4.3; 1 is the thesis's table).
    pub gain_scale: f64,
    /// Default torque cap per unit kp, rad: T_max = torque_limit_rad · kp (spec §4.4, c_max).
    pub torque_limit_rad: f64,
    /// Default brake per unit kd, rad/s: brake = brake_rad_s · kd (spec §4.3, c_damp). Used by
    /// [`PdMode::OdeBrake`] only.
    pub brake_rad_s: f64,
}

impl Actuation {
    /// The thesis's gains as printed (G = 1), the ODE-style brake with c_damp = 4 rad/s and caps at
    /// 1 rad of error: the literal reading of §6.2 (too weak to stand under g = 9.81, spec §4.3).
    pub fn thesis_literal() -> Self {
        Self { mode: PdMode::OdeBrake, gain_scale: 1.0, torque_limit_rad: 1.0, brake_rad_s: 4.0 }
    }
}

/// A skeleton as written in a RON file: names, not indices. [`Skeleton::new`] checks it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Skeleton", deny_unknown_fields)]
pub struct SkeletonDesc {
    pub name: String,
    #[serde(default)]
    pub facing: Facing,
    /// Extent of every shape along z, metres (drawing only; the motion is planar).
    pub depth: f64,
    pub bodies: Vec<BodyDesc>,
    pub joints: Vec<JointDesc>,
    #[serde(default)]
    pub welds: Vec<WeldDesc>,
    pub actuators: Vec<ActuatorDesc>,
    /// Collision groups; empty means one group touching the ground and other models only.
    #[serde(default)]
    pub groups: Vec<CollisionGroupDesc>,
    pub actuation: Actuation,
}

/// An actuator after the checks: indices instead of names, gains scaled.
#[derive(Debug, Clone, PartialEq)]
pub struct ActuatorSpec {
    pub name: String,
    pub number: u32,
    pub drive: DriveSpec,
    /// N·m/rad, with the gain scale applied.
    pub kp: f64,
    /// N·m·s/rad, with the gain scale applied.
    pub kd: f64,
    /// N·m, with the gain scale applied.
    pub max_torque: f64,
    /// N·m, with the gain scale applied.
    pub brake_torque: f64,
    pub fixed_target: Option<f64>,
}

/// What an actuator turns, by index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DriveSpec {
    /// Joint index.
    Joint(usize),
    /// Body indices a and b: angle θ(a) − θ(b), torque +T on a, −T on b.
    BodyPair { a: usize, b: usize },
}

/// A checked skeleton: unique names, a forest of hinges (each body the child of at most one joint,
/// no cycles), known references, positive masses and sizes, actuator numbers 1..=n.
#[derive(Debug, Clone, PartialEq)]
pub struct Skeleton {
    desc: SkeletonDesc,
    /// For each body, the joint whose child it is.
    parent_joint: Vec<Option<usize>>,
    /// Joint indices by name order of the file, with parent and child body indices.
    joint_bodies: Vec<(usize, usize)>,
    /// Bodies that are no joint's child: each roots a tree that moves freely in the plane.
    roots: Vec<usize>,
    /// Bodies in an order where every parent comes before its children (roots first).
    tree_order: Vec<usize>,
    /// For each body, the root of its tree.
    root_of: Vec<usize>,
    weld_bodies: Vec<(usize, usize)>,
    actuators: Vec<ActuatorSpec>,
    /// Collision group index of every body.
    body_group: Vec<usize>,
    groups: Vec<CollisionGroupDesc>,
}

/// The skeletons shipped in `assets/skeletons/`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum BuiltinSkeleton {
    /// The thesis's walking humanoid: 14 bodies, 13 hinges, 14 actuators (Tables 6.1–6.2).
    Humanoid,
    /// The humanoid holding a ball with both hands by two releasable welds (§3.5.1).
    Thrower,
    /// The backflip's pusher: the humanoid mirrored to face −x, with hands and wrists (§3.5.2).
    Pusher,
    /// The walking humanoid with SIMBICON-style PD gains (kp = 300 N·m/rad, kd = 30 N·m·s/rad on every
    /// actuator, implicit springs; Yin et al. 2007) instead of Table 6.2's: the faithful SIMBICON
    /// walker's figure.
    HumanoidSimbicon,
}

impl BuiltinSkeleton {
    pub const ALL: [BuiltinSkeleton; 4] = [
        BuiltinSkeleton::Humanoid,
        BuiltinSkeleton::Thrower,
        BuiltinSkeleton::Pusher,
        BuiltinSkeleton::HumanoidSimbicon,
    ];

    /// The RON text of this skeleton, as shipped in `assets/skeletons/`.
    pub fn ron(self) -> &'static str {
        match self {
            BuiltinSkeleton::Humanoid => include_str!("../skeletons/humanoid.ron"),
            BuiltinSkeleton::Thrower => include_str!("../skeletons/thrower.ron"),
            BuiltinSkeleton::Pusher => include_str!("../skeletons/pusher.ron"),
            BuiltinSkeleton::HumanoidSimbicon => {
                include_str!("../skeletons/humanoid-simbicon.ron")
            }
        }
    }

    /// The file name under `assets/skeletons/`.
    pub fn file_name(self) -> &'static str {
        match self {
            BuiltinSkeleton::Humanoid => "humanoid.ron",
            BuiltinSkeleton::Thrower => "thrower.ron",
            BuiltinSkeleton::Pusher => "pusher.ron",
            BuiltinSkeleton::HumanoidSimbicon => "humanoid-simbicon.ron",
        }
    }

    /// The checked skeleton. The shipped files are tested, so this cannot fail.
    pub fn load(self) -> Skeleton {
        match Skeleton::from_ron_str(self.ron()) {
            Ok(s) => s,
            Err(e) => unreachable!("shipped skeleton {} is invalid: {e}", self.file_name()),
        }
    }
}

impl Skeleton {
    /// Parses and checks a RON skeleton. Errors name the line and the field (`bodies[3].mass`).
    pub fn from_ron_str(text: &str) -> Result<Self, SkeletonError> {
        let desc: SkeletonDesc = ron::from_str(text).map_err(|e| SkeletonError::syntax(text, &e))?;
        Skeleton::new(desc).map_err(|e| e.locate(text))
    }

    /// Checks a skeleton description.
    pub fn new(desc: SkeletonDesc) -> Result<Self, SkeletonError> {
        check_positive("depth", desc.depth)?;
        let a = &desc.actuation;
        check_positive("actuation.gain_scale", a.gain_scale)?;
        check_positive("actuation.torque_limit_rad", a.torque_limit_rad)?;
        check_non_negative("actuation.brake_rad_s", a.brake_rad_s)?;
        if desc.bodies.is_empty() {
            return Err(err("bodies", "a skeleton needs at least one body"));
        }
        // Counted before anything is built for them; every check below is linear in the file.
        for (field, n) in
            [("bodies", desc.bodies.len()), ("joints", desc.joints.len()), ("welds", desc.welds.len())]
        {
            if n > MAX_BODIES {
                return Err(err(
                    field,
                    format!("expected at most {MAX_BODIES} {field} in a skeleton (anima's limit), found {n}"),
                ));
            }
        }

        // Bodies.
        let n_bodies = desc.bodies.len();
        let mut body_index: HashMap<&str, usize> = HashMap::with_capacity(n_bodies);
        for (i, b) in desc.bodies.iter().enumerate() {
            let at = |f: &str| format!("bodies[{i}].{f}");
            if b.name.is_empty() {
                return Err(err(at("name"), "empty name"));
            }
            if body_index.insert(&b.name, i).is_some() {
                return Err(err(at("name"), format!("a second body named `{}`", b.name)));
            }
            check_positive(&at("mass"), b.mass)?;
            check_finite(&at("centre"), b.centre.0)?;
            check_finite(&at("centre"), b.centre.1)?;
            match b.shape {
                Shape::Box { width, height } => {
                    check_positive(&at("shape.width"), width)?;
                    check_positive(&at("shape.height"), height)?;
                }
                Shape::Ball { radius } => check_positive(&at("shape.radius"), radius)?,
            }
        }
        let body = |field: String, name: &str| -> Result<usize, SkeletonError> {
            body_index.get(name).copied().ok_or_else(|| err(field, format!("no body named `{name}`")))
        };

        // Joints: a forest.
        let mut parent_joint: Vec<Option<usize>> = vec![None; n_bodies];
        let mut joint_bodies = Vec::with_capacity(desc.joints.len());
        let mut joint_index: HashMap<&str, usize> = HashMap::with_capacity(desc.joints.len());
        for (j, joint) in desc.joints.iter().enumerate() {
            let at = |f: &str| format!("joints[{j}].{f}");
            if joint.name.is_empty() {
                return Err(err(at("name"), "empty name"));
            }
            if joint_index.insert(&joint.name, j).is_some() {
                return Err(err(at("name"), format!("a second joint named `{}`", joint.name)));
            }
            let p = body(at("parent"), &joint.parent)?;
            let c = body(at("child"), &joint.child)?;
            if p == c {
                return Err(err(at("child"), "a body cannot be jointed to itself"));
            }
            if let Some(other) = parent_joint[c] {
                return Err(err(
                    at("child"),
                    format!(
                        "`{}` already hangs from joint `{}`; joints must form a tree (use a weld to close a loop)",
                        joint.child, desc.joints[other].name
                    ),
                ));
            }
            parent_joint[c] = Some(j);
            check_finite(&at("anchor"), joint.anchor.0)?;
            check_finite(&at("anchor"), joint.anchor.1)?;
            if let Some((lo, hi)) = joint.limits
                && !(lo.is_finite() && hi.is_finite() && lo < hi)
            {
                return Err(err(at("limits"), format!("expected min < max, found ({lo}, {hi})")));
            }
            joint_bodies.push((p, c));
        }
        // Cycles: walking up from any body must reach a root within n steps.
        let mut root_of = vec![0; n_bodies];
        for (start, slot) in root_of.iter_mut().enumerate() {
            let mut b = start;
            let mut steps = 0;
            while let Some(j) = parent_joint[b] {
                b = joint_bodies[j].0;
                steps += 1;
                if steps > n_bodies {
                    return Err(err(
                        format!("joints[{j}].parent"),
                        format!("the joints through body `{}` form a cycle", desc.bodies[start].name),
                    ));
                }
            }
            *slot = b;
        }
        let roots: Vec<usize> = (0..n_bodies).filter(|&b| parent_joint[b].is_none()).collect();
        for (i, b) in desc.bodies.iter().enumerate() {
            if b.fixed && parent_joint[i].is_some() {
                return Err(err(
                    format!("bodies[{i}].fixed"),
                    "only a body that hangs from no joint can be fixed",
                ));
            }
        }
        // Breadth first from the roots, each body's children in joint order.
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n_bodies];
        for &(jp, jc) in &joint_bodies {
            children[jp].push(jc);
        }
        let mut tree_order = roots.clone();
        let mut k = 0;
        while k < tree_order.len() {
            let p = tree_order[k];
            tree_order.extend_from_slice(&children[p]);
            k += 1;
        }
        debug_assert_eq!(tree_order.len(), n_bodies);

        // Welds.
        let mut weld_bodies = Vec::with_capacity(desc.welds.len());
        let mut weld_names = HashMap::with_capacity(desc.welds.len());
        for (w, weld) in desc.welds.iter().enumerate() {
            let at = |f: &str| format!("welds[{w}].{f}");
            if weld_names.insert(weld.name.as_str(), w).is_some() {
                return Err(err(at("name"), format!("a second weld named `{}`", weld.name)));
            }
            let a = body(at("a"), &weld.a)?;
            let b = body(at("b"), &weld.b)?;
            if a == b {
                return Err(err(at("b"), "a body cannot be welded to itself"));
            }
            check_finite(&at("anchor"), weld.anchor.0)?;
            check_finite(&at("anchor"), weld.anchor.1)?;
            weld_bodies.push((a, b));
        }

        // Actuators.
        let g = a.gain_scale;
        let mut actuators = Vec::with_capacity(desc.actuators.len());
        let mut actuator_names = HashMap::with_capacity(desc.actuators.len());
        // The actuator holding each number 1..=len (checked in range before it is used).
        let mut numbered: Vec<Option<usize>> = vec![None; desc.actuators.len()];
        for (i, act) in desc.actuators.iter().enumerate() {
            let at = |f: &str| format!("actuators[{i}].{f}");
            if actuator_names.insert(act.name.as_str(), i).is_some() {
                return Err(err(at("name"), format!("a second actuator named `{}`", act.name)));
            }
            if act.number == 0 || act.number as usize > desc.actuators.len() {
                return Err(err(
                    at("number"),
                    format!("expected a number in 1..={}, found {}", desc.actuators.len(), act.number),
                ));
            }
            let slot = &mut numbered[act.number as usize - 1];
            if let Some(o) = *slot {
                let other = &desc.actuators[o].name;
                return Err(err(at("number"), format!("number {} is also `{other}`'s", act.number)));
            }
            *slot = Some(i);
            let drive = match &act.drives {
                Drive::Joint(name) => DriveSpec::Joint(
                    joint_index
                        .get(name.as_str())
                        .copied()
                        .ok_or_else(|| err(at("drives"), format!("no joint named `{name}`")))?,
                ),
                Drive::BodyPair { a: na, b: nb } => {
                    let (ia, ib) = (body(at("drives.a"), na)?, body(at("drives.b"), nb)?);
                    if ia == ib {
                        return Err(err(at("drives.b"), "the two bodies must differ"));
                    }
                    if root_of[ia] != root_of[ib] {
                        return Err(err(at("drives.b"), "the two bodies must belong to one jointed tree"));
                    }
                    DriveSpec::BodyPair { a: ia, b: ib }
                }
            };
            check_non_negative(&at("kp"), act.kp)?;
            check_non_negative(&at("kd"), act.kd)?;
            let max_torque = match act.max_torque {
                Some(t) => {
                    check_positive(&at("max_torque"), t)?;
                    t
                }
                None => a.torque_limit_rad * act.kp,
            };
            let brake = match act.brake_torque {
                Some(t) => {
                    check_non_negative(&at("brake_torque"), t)?;
                    t
                }
                None => a.brake_rad_s * act.kd,
            };
            if let Some(t) = act.fixed_target {
                check_finite(&at("fixed_target"), t)?;
            }
            actuators.push(ActuatorSpec {
                name: act.name.clone(),
                number: act.number,
                drive,
                kp: g * act.kp,
                kd: g * act.kd,
                max_torque: g * max_torque,
                brake_torque: g * brake,
                fixed_target: act.fixed_target,
            });
        }

        // Collision groups.
        let groups = if desc.groups.is_empty() {
            vec![CollisionGroupDesc { name: "body".into(), ground: true, other_models: true, groups: vec![] }]
        } else {
            desc.groups.clone()
        };
        if groups.len() > 8 {
            return Err(err("groups", format!("at most 8 collision groups, found {}", groups.len())));
        }
        for (gi, group) in groups.iter().enumerate() {
            if groups[..gi].iter().any(|o| o.name == group.name) {
                return Err(err(format!("groups[{gi}].name"), format!("a second group `{}`", group.name)));
            }
            for (k, other) in group.groups.iter().enumerate() {
                if !groups.iter().any(|o| &o.name == other) {
                    return Err(err(
                        format!("groups[{gi}].groups[{k}]"),
                        format!("no group named `{other}`"),
                    ));
                }
            }
        }
        let mut body_group = Vec::with_capacity(n_bodies);
        for (i, b) in desc.bodies.iter().enumerate() {
            body_group.push(match &b.group {
                None => 0,
                Some(name) => groups.iter().position(|g| &g.name == name).ok_or_else(|| {
                    err(format!("bodies[{i}].group"), format!("no collision group named `{name}`"))
                })?,
            });
        }

        Ok(Skeleton {
            desc,
            parent_joint,
            joint_bodies,
            roots,
            tree_order,
            root_of,
            weld_bodies,
            actuators,
            body_group,
            groups,
        })
    }

    pub fn desc(&self) -> &SkeletonDesc {
        &self.desc
    }

    pub fn name(&self) -> &str {
        &self.desc.name
    }

    pub fn n_bodies(&self) -> usize {
        self.desc.bodies.len()
    }

    pub fn n_joints(&self) -> usize {
        self.desc.joints.len()
    }

    pub fn n_actuators(&self) -> usize {
        self.actuators.len()
    }

    pub fn n_welds(&self) -> usize {
        self.desc.welds.len()
    }

    /// Total mass, kg.
    pub fn total_mass(&self) -> f64 {
        self.desc.bodies.iter().map(|b| b.mass).sum()
    }

    pub fn body(&self, body_idx: usize) -> &BodyDesc {
        &self.desc.bodies[body_idx]
    }

    pub fn body_index(&self, name: &str) -> Option<usize> {
        self.desc.bodies.iter().position(|b| b.name == name)
    }

    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.desc.joints.iter().position(|j| j.name == name)
    }

    pub fn actuator_index(&self, name: &str) -> Option<usize> {
        self.actuators.iter().position(|a| a.name == name)
    }

    /// The actuator with the thesis's 1-based `number`.
    pub fn actuator_by_number(&self, number: u32) -> Option<usize> {
        self.actuators.iter().position(|a| a.number == number)
    }

    pub fn weld_index(&self, name: &str) -> Option<usize> {
        self.desc.welds.iter().position(|w| w.name == name)
    }

    pub fn actuators(&self) -> &[ActuatorSpec] {
        &self.actuators
    }

    /// (parent, child) body indices of joint `joint_idx`.
    pub fn joint_bodies(&self, joint_idx: usize) -> (usize, usize) {
        self.joint_bodies[joint_idx]
    }

    /// The joint whose child `body_idx` is, if any.
    pub fn parent_joint(&self, body_idx: usize) -> Option<usize> {
        self.parent_joint[body_idx]
    }

    /// Bodies that hang from no joint: each roots a tree moving freely in the plane.
    pub fn roots(&self) -> &[usize] {
        &self.roots
    }

    /// The root of the tree `body_idx` belongs to.
    pub fn root_of(&self, body_idx: usize) -> usize {
        self.root_of[body_idx]
    }

    /// Every body once, each parent before its children.
    pub fn tree_order(&self) -> &[usize] {
        &self.tree_order
    }

    /// (a, b) body indices of weld `weld_idx`.
    pub fn weld_bodies(&self, weld_idx: usize) -> (usize, usize) {
        self.weld_bodies[weld_idx]
    }

    /// Collision groups (one default group when the file lists none).
    pub fn groups(&self) -> &[CollisionGroupDesc] {
        &self.groups
    }

    /// Index into [`Skeleton::groups`] of the group of `body_idx`.
    pub fn body_group(&self, body_idx: usize) -> usize {
        self.body_group[body_idx]
    }

    /// Whether two bodies of this model may touch.
    pub fn bodies_collide(&self, a: usize, b: usize) -> bool {
        let (ga, gb) = (&self.groups[self.body_group[a]], &self.groups[self.body_group[b]]);
        ga.groups.contains(&gb.name) || gb.groups.contains(&ga.name)
    }

    /// +1 facing +x, −1 facing −x.
    pub fn sign(&self) -> f64 {
        self.desc.facing.sign()
    }

    /// Lowest point of any shape in the initial configuration, metres (for placing on the ground).
    pub fn lowest_point(&self) -> f64 {
        self.desc
            .bodies
            .iter()
            .map(|b| match b.shape {
                Shape::Box { height, .. } => b.centre.1 - 0.5 * height,
                Shape::Ball { radius } => b.centre.1 - radius,
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The same skeleton with other actuation settings (gains are rescaled from the file's values).
    pub fn with_actuation(&self, actuation: Actuation) -> Result<Skeleton, SkeletonError> {
        let mut desc = self.desc.clone();
        desc.actuation = actuation;
        Skeleton::new(desc)
    }

    pub fn actuation(&self) -> &Actuation {
        &self.desc.actuation
    }
}

fn err(field: impl Into<String>, message: impl Into<String>) -> SkeletonError {
    SkeletonError::invalid(field, message)
}

fn check_finite(field: &str, v: f64) -> Result<(), SkeletonError> {
    if v.is_finite() {
        Ok(())
    } else {
        Err(SkeletonError::invalid(field, format!("expected a finite number, found {v}")))
    }
}

fn check_positive(field: &str, v: f64) -> Result<(), SkeletonError> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(SkeletonError::invalid(field, format!("expected a positive number, found {v}")))
    }
}

fn check_non_negative(field: &str, v: f64) -> Result<(), SkeletonError> {
    if v >= 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(SkeletonError::invalid(field, format!("expected zero or a positive number, found {v}")))
    }
}
