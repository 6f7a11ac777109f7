//! The simulated world: skeletons turned into Rapier multibodies, ground, the step loop with the PD
//! actuator layer, welds, external pushes.
//!
//! Planar motion. Every body that hangs from no joint (a root: the pelvis, a free ball) is joined to
//! a fixed anchor by a joint that leaves only x, y and the rotation about z free; hinges turn about z.
//! The state is the reduced coordinates of those joints, so z, and the rotations about x and y, stay
//! exactly zero: no constraint has to hold them.

use rapier3d::na;
use rapier3d::prelude as rp;
use serde::{Deserialize, Serialize};

use crate::actuator::{Commands, Target, TargetFrame, TargetMix, TorqueAverage, signal_torque, torso_torque};
use crate::dense::SpdSystem;
use crate::error::BodyError;
use crate::skeleton::{DriveSpec, PdMode, Shape, Side, Skeleton};

/// Ground: a horizontal plane, or one with a slope or a flight of steps beyond a point (the terrains
/// of a robustness protocol; issue #18).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ground {
    /// Height of the plane (of its flat part before the relief), metres.
    pub height: f64,
    /// Coulomb friction coefficient μ of every contact (spec §3.1 proposes 1).
    pub friction: f64,
    /// What the ground does beyond its flat part; `Flat` when left out.
    #[serde(default)]
    pub relief: Relief,
}

/// The shape of the ground along x (the walking direction) beyond its flat part.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum Relief {
    /// Flat everywhere.
    #[default]
    Flat,
    /// Flat up to `from_x`, then rising at `degrees` (negative: falling) for ever.
    Slope { from_x: f64, degrees: f64 },
    /// Flat up to `from_x`, then `count` steps of `rise` metres (negative: down) every `run` metres, flat
    /// after the last.
    Stairs { from_x: f64, rise: f64, run: f64, count: u32 },
}

impl Ground {
    /// Height of the ground at x, m.
    pub fn height_at(&self, x: f64) -> f64 {
        match self.relief {
            Relief::Flat => self.height,
            Relief::Slope { from_x, degrees } => {
                self.height + (x - from_x).max(0.0) * degrees.to_radians().tan()
            }
            Relief::Stairs { from_x, rise, run, count } => {
                if x < from_x {
                    self.height
                } else {
                    let k = (((x - from_x) / run).floor() + 1.0).min(f64::from(count));
                    self.height + rise * k
                }
            }
        }
    }

    /// Inclination of the ground at x, rad, positive rising towards +x: the slope's angle past its
    /// start, 0 on the flat and on the treads of stairs (whose risers are vertical steps, not a slope).
    pub fn slope_at(&self, x: f64) -> f64 {
        match self.relief {
            Relief::Slope { from_x, degrees } if x > from_x => degrees.to_radians(),
            Relief::Flat | Relief::Slope { .. } | Relief::Stairs { .. } => 0.0,
        }
    }

    /// The ground's pieces as fixed boxes: (centre, angle about z, half-extents in x and y). A box's top
    /// face is the ground; boxes are 10 m deep and reach 1 km each way (and across, in z).
    fn pieces(&self) -> Vec<([f64; 2], f64, [f64; 2])> {
        const FAR: f64 = 1000.0;
        const DEEP: f64 = 5.0;
        let flat_until = |x: f64, top: f64| ([(x - FAR) * 0.5 + x * 0.5, top - DEEP], 0.0, [FAR * 0.5, DEEP]);
        match self.relief {
            Relief::Flat => Vec::new(),
            Relief::Slope { from_x, degrees } => {
                let a = degrees.to_radians();
                // Top face from (from_x, height) along (cos a, sin a); the box hangs below it.
                let (c, s) = (a.cos(), a.sin());
                let top = [from_x + FAR * 0.5 * c, self.height + FAR * 0.5 * s];
                let centre = [top[0] + DEEP * s, top[1] - DEEP * c];
                vec![flat_until(from_x, self.height), (centre, a, [FAR * 0.5, DEEP])]
            }
            Relief::Stairs { from_x, rise, run, count } => {
                let mut out = vec![flat_until(from_x, self.height)];
                for k in 1..=count {
                    let x0 = from_x + f64::from(k - 1) * run;
                    let half = if k == count { FAR * 0.5 } else { run * 0.5 };
                    let top = self.height + rise * f64::from(k);
                    out.push(([x0 + half, top - DEEP], 0.0, [half, DEEP]));
                }
                out
            }
        }
    }
}

/// Rapier's solver settings. Each costs time and buys accuracy; `docs/body.md` measures them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSettings {
    /// Rapier's sub-steps per physics step (`num_solver_iterations`): contacts, joint motors and
    /// welds are re-solved at each; explicit torques are held over all of them.
    pub iterations: u32,
    /// Projected Gauss–Seidel sweeps per Rapier sub-step.
    pub pgs_iterations: u32,
    /// Let bodies at rest fall asleep (skipped until woken). A commanded model is woken when its
    /// commands change; a resting figure under explicit torques stays frozen while asleep.
    pub sleeping: bool,
}

impl SolverSettings {
    /// Rapier 0.36's defaults: 4 sub-steps, 1 PGS sweep, no sleeping (sleeping would freeze a PD-held
    /// figure, which is not physics).
    pub fn rapier_default() -> Self {
        Self { iterations: 4, pgs_iterations: 1, sleeping: false }
    }
}

/// The knobs of a world.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldSettings {
    /// Control step Δt, seconds: commands and sensors are exchanged once per step (0.05 s in the
    /// thesis, §5.2). Written `dt_s` as in every scene schema; the older `dt` still reads.
    #[serde(rename = "dt_s", alias = "dt")]
    pub dt: f64,
    /// Physics sub-steps per control step: targets are held, but every PD torque is re-evaluated
    /// from the state at each sub-step of Δt/substeps (spec §4.3).
    pub substeps: u32,
    /// Gravitational acceleration along −y, m/s².
    pub gravity: f64,
    pub ground: Option<Ground>,
    pub solver: SolverSettings,
    /// Signals each actuator can hold at once (storage reserved up front).
    pub max_signals_per_actuator: usize,
}

impl WorldSettings {
    /// The thesis's world: Δt = 0.05 s, one physics step per control step, g = 9.81 m/s², ground at
    /// y = 0 with μ = 1 (spec §3.1 proposals), Rapier's default solver.
    pub fn thesis() -> Self {
        Self {
            dt: 0.05,
            substeps: 1,
            gravity: 9.81,
            ground: Some(Ground { height: 0.0, friction: 1.0, relief: Relief::Flat }),
            solver: SolverSettings::rapier_default(),
            max_signals_per_actuator: 8,
        }
    }

    /// Physics step length, seconds.
    pub fn physics_dt(&self) -> f64 {
        self.dt / f64::from(self.substeps)
    }

    /// Whether a world can be built with these settings: positive finite times, at least one (and at
    /// most 10 000) sub-steps and solver iterations, 1 to 256 signals per actuator (the command buffers
    /// are sized by it).
    pub fn check(&self) -> Result<(), BodyError> {
        let bad = |m: String| Err(BodyError::Settings(m));
        if !(self.dt > 0.0 && self.dt.is_finite()) {
            return bad(format!("dt must be a positive number of seconds, found {}", self.dt));
        }
        if !(1..=10_000).contains(&self.substeps) {
            return bad(format!("substeps must lie in 1..=10000, found {}", self.substeps));
        }
        if !(1..=256).contains(&self.max_signals_per_actuator) {
            return bad(format!(
                "max_signals_per_actuator must lie in 1..=256, found {}",
                self.max_signals_per_actuator
            ));
        }
        if !self.gravity.is_finite() {
            return bad(format!("gravity must be finite, found {}", self.gravity));
        }
        if let Some(g) = self.ground
            && !(g.height.is_finite() && g.friction >= 0.0 && g.friction.is_finite())
        {
            return bad(format!("ground needs a finite height and μ ≥ 0, found {g:?}"));
        }
        match self.ground.map(|g| g.relief) {
            Some(Relief::Slope { from_x, degrees }) if !(from_x.is_finite() && degrees.abs() < 60.0) => {
                return bad(format!(
                    "a slope needs a finite start and less than 60°, found {from_x} m, {degrees}°"
                ));
            }
            Some(Relief::Stairs { from_x, rise, run, count })
                if !(from_x.is_finite()
                    && rise.is_finite()
                    && rise.abs() <= 1.0
                    && run > 0.05
                    && run.is_finite()
                    && (1..=1000).contains(&count)) =>
            {
                return bad(format!(
                    "stairs need a finite start, a rise of at most 1 m, a run of more than 5 cm and 1 to 1000 steps, found {from_x} m, {rise} m, {run} m, {count}"
                ));
            }
            _ => {}
        }
        let its = [self.solver.iterations, self.solver.pgs_iterations];
        if its.iter().any(|&n| !(1..=10_000).contains(&n)) {
            return bad(format!("solver iterations must lie in 1..=10000, found {its:?}"));
        }
        Ok(())
    }
}

/// Where a model goes: its initial configuration translated by (dx, dy).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Placement {
    /// Translate by (dx, dy) metres.
    Offset { dx: f64, dy: f64 },
    /// Translate by dx and stand the lowest point exactly on the ground (or y = 0 without one).
    OnGround { dx: f64 },
}

/// A body's pose for drawing and inspection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyPose {
    pub body: usize,
    /// World position of the centre of mass, metres.
    pub centre: [f64; 2],
    /// World angle about z, radians, counter-clockwise (not wrapped).
    pub angle: f64,
    pub shape: Shape,
    pub side: Side,
}

/// Linear and angular momentum of a model: p = Σ m v (kg·m/s), L about the centre of mass
/// = Σ [I ω + m (r − c) × (v − v_c)]_z (kg·m²/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Momentum {
    pub linear: [f64; 2],
    pub angular: f64,
}

/// One jointed tree of a model (a figure, or a free prop such as the ball) and its scratch.
#[derive(Debug)]
struct Tree {
    multibody: rp::MultibodyIndex,
    ndofs: usize,
    bodies: Vec<usize>,
    /// Generalised coordinates and velocities (f64 copies), scratch for the mass matrix, right-hand
    /// side and solution.
    q: Vec<f64>,
    qd: Vec<f64>,
    rhs: Vec<f64>,
    sol: Vec<f64>,
    /// Jacobian rows x, y and θz of one link, per column.
    jac: Vec<[f64; 3]>,
    mass: SpdSystem,
    /// `mass` holds its Cholesky factor (not the matrix) since the last assembly.
    factored: bool,
    /// Needs the mass matrix this mode (stable PD, or a body-pair actuator in another mode).
    needs_mass: bool,
    actuators: Vec<usize>,
}

/// Runtime data of one actuator.
#[derive(Debug)]
struct ActuatorRt {
    tree: usize,
    /// θ_ccw = Σ coeff · q[dof]: one entry for a hinge, the two bodies' angle paths for a pair.
    selection: Vec<(usize, f64)>,
    /// Bodies that receive +τ and −τ.
    plus: usize,
    minus: usize,
    /// Joint (multibody handle, dof) for the joint-based modes.
    joint: Option<(rp::MultibodyJointHandle, usize)>,
    /// Parent body of the driven joint (world-frame targets).
    parent: Option<usize>,
}

#[derive(Debug, Clone, Copy)]
struct ExternalForce {
    body: usize,
    force: [f64; 2],
    point: [f64; 2],
}

#[derive(Debug)]
struct Model {
    skeleton: Skeleton,
    sign: f64,
    offset: [f64; 2],
    handles: Vec<rp::RigidBodyHandle>,
    colliders: Vec<rp::ColliderHandle>,
    /// Per body: its tree, its multibody link id, and the dofs whose sum is its world angle.
    body_tree: Vec<usize>,
    body_link: Vec<usize>,
    body_angle_dofs: Vec<Vec<usize>>,
    /// Per joint: the dof of its angle.
    joint_dof: Vec<usize>,
    trees: Vec<Tree>,
    actuators: Vec<ActuatorRt>,
    welds: Vec<Option<rp::ImpulseJointHandle>>,
    commands: Commands,
    commands_changed: bool,
    forces: Vec<ExternalForce>,
    /// Per actuator, current scratch: angle and rate (ccw), mix, average, torque applied (model
    /// convention, last physics step).
    angle: Vec<f64>,
    rate: Vec<f64>,
    mix: Vec<TargetMix>,
    avg: Vec<TorqueAverage>,
    torque: Vec<f64>,
    /// Per actuator: the torque it exerts in this physics step as best known (counter-clockwise; for
    /// the implicit modes the PD torque at the current state, damping included): the τ_swing of a
    /// torso signal.
    applied: Vec<f64>,
    /// Per actuator: holds a torso signal in this physics step (driven explicitly, after the others).
    torso: Vec<bool>,
    /// Collision bits per group.
    group_bits: Vec<u32>,
}

/// A world of planar articulated models on Rapier multibodies. Stepping allocates nothing in this
/// crate's layer (Rapier's own multibody step does allocate; see `docs/body.md`).
pub struct World {
    settings: WorldSettings,
    physics: rp::PhysicsWorld,
    ground: Option<rp::ColliderHandle>,
    models: Vec<Model>,
    steps: u64,
    /// (model, body) owning each collider, by collider slot index.
    collider_owner: Vec<Option<(usize, usize)>>,
    next_bit: u32,
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("settings", &self.settings)
            .field("models", &self.models.iter().map(|m| m.skeleton.name()).collect::<Vec<_>>())
            .field("steps", &self.steps)
            .finish_non_exhaustive()
    }
}

const GROUND_BIT: u32 = 1;
/// A body this far from the origin (m), this fast (m/s) or spinning this fast (rad/s) has diverged.
const DIVERGED_POSITION_M: f32 = 1.0e5;
const DIVERGED_SPEED_M_S: f32 = 1.0e3;
const DIVERGED_SPIN_RAD_S: f32 = 1.0e4;
/// Index of the rotation about z in Rapier's 6-D joint layout.
const ANG_Z: usize = 5;

fn v3(x: f64, y: f64) -> rp::Vector {
    rp::Vector::new(x as f32, y as f32, 0.0)
}

impl World {
    pub fn new(settings: WorldSettings) -> Result<Self, BodyError> {
        settings.check()?;
        let mut physics = rp::PhysicsWorld {
            gravity: rp::Vector::new(0.0, -settings.gravity as f32, 0.0),
            ..rp::PhysicsWorld::default()
        };
        let p = &mut physics.integration_parameters;
        p.dt = settings.physics_dt() as f32;
        p.num_solver_iterations = settings.solver.iterations as usize;
        p.num_internal_pgs_iterations = settings.solver.pgs_iterations as usize;
        let mut world = World {
            settings,
            physics,
            ground: None,
            models: Vec::new(),
            steps: 0,
            collider_owner: Vec::new(),
            next_bit: 1,
        };
        if let Some(g) = settings.ground {
            let groups = rp::InteractionGroups::new(
                rp::Group::from_bits_retain(GROUND_BIT),
                rp::Group::ALL,
                rp::InteractionTestMode::And,
            );
            if g.relief == Relief::Flat {
                let body =
                    world.physics.insert_body(rp::RigidBodyBuilder::fixed().translation(v3(0.0, g.height)));
                let collider = rp::ColliderBuilder::halfspace(na::Unit::new_unchecked(rp::Vector::Y))
                    .friction(g.friction as f32)
                    .restitution(0.0)
                    .collision_groups(groups);
                world.ground = Some(world.physics.insert_collider(collider, Some(body)));
            } else {
                // A relief is boxes whose top faces are the ground; every collider that belongs to no
                // model counts as ground for the sensors.
                for (centre, angle, half) in g.pieces() {
                    let body = world.physics.insert_body(
                        rp::RigidBodyBuilder::fixed()
                            .translation(v3(centre[0], centre[1]))
                            .rotation(rp::Vector::new(0.0, 0.0, angle as f32)),
                    );
                    let collider = rp::ColliderBuilder::cuboid(half[0] as f32, half[1] as f32, 1000.0)
                        .friction(g.friction as f32)
                        .restitution(0.0)
                        .collision_groups(groups);
                    let handle = world.physics.insert_collider(collider, Some(body));
                    world.ground.get_or_insert(handle);
                }
            }
        }
        Ok(world)
    }

    pub fn settings(&self) -> &WorldSettings {
        &self.settings
    }

    /// Adds a model in its initial configuration (zero joint angles, at rest). Returns its index.
    pub fn add_model(&mut self, skeleton: &Skeleton, placement: Placement) -> Result<usize, BodyError> {
        let model_idx = self.models.len();
        let n_groups = skeleton.groups().len() as u32;
        if self.next_bit + n_groups > 32 {
            return Err(BodyError::Settings("too many models: collision groups are exhausted (31)".into()));
        }
        for j in 0..skeleton.n_joints() {
            if skeleton.actuators().iter().filter(|a| a.drive == DriveSpec::Joint(j)).count() > 1 {
                return Err(BodyError::Settings(format!(
                    "skeleton `{}`: joint `{}` has more than one actuator",
                    skeleton.name(),
                    skeleton.desc().joints[j].name
                )));
            }
        }
        let group_bits: Vec<u32> = (0..n_groups).map(|k| 1u32 << (self.next_bit + k)).collect();
        self.next_bit += n_groups;
        let ground_y = self.settings.ground.map_or(0.0, |g| {
            g.height_at(match placement {
                Placement::OnGround { dx } => dx,
                _ => 0.0,
            })
        });
        let offset = match placement {
            Placement::Offset { dx, dy } => [dx, dy],
            Placement::OnGround { dx } => [dx, ground_y - skeleton.lowest_point()],
        };
        let sign = skeleton.sign();
        let mode = skeleton.actuation().mode;
        let friction = self.settings.ground.map_or(1.0, |g| g.friction) as f32;
        let depth = skeleton.desc().depth;
        let can_sleep = self.settings.solver.sleeping;

        // Bodies and colliders.
        let n = skeleton.n_bodies();
        let mut handles = Vec::with_capacity(n);
        let mut colliders = Vec::with_capacity(n);
        for (b, desc) in skeleton.desc().bodies.iter().enumerate() {
            let c = [desc.centre.0 + offset[0], desc.centre.1 + offset[1]];
            let rb = if desc.fixed { rp::RigidBodyBuilder::fixed() } else { rp::RigidBodyBuilder::dynamic() };
            let rb = rb.translation(v3(c[0], c[1])).can_sleep(can_sleep);
            let shape = match desc.shape {
                Shape::Box { width, height } => {
                    rp::ColliderBuilder::cuboid(0.5 * width as f32, 0.5 * height as f32, 0.5 * depth as f32)
                }
                Shape::Ball { radius } => rp::ColliderBuilder::ball(radius as f32),
            };
            let collider = shape.mass(desc.mass as f32).friction(friction).restitution(0.0);
            let (h, ch) = self.physics.insert(rb, collider);
            handles.push(h);
            colliders.push(ch);
            let slot = ch.into_raw_parts().0 as usize;
            if self.collider_owner.len() <= slot {
                self.collider_owner.resize(slot + 1, None);
            }
            self.collider_owner[slot] = Some((model_idx, b));
        }

        // Trees: an anchor and a planar joint per root, then the hinges parent-first.
        let centre = |b: usize| {
            let d = &skeleton.desc().bodies[b];
            [d.centre.0 + offset[0], d.centre.1 + offset[1]]
        };
        let mut joint_handles = vec![None; skeleton.n_joints()];
        for &root in skeleton.roots() {
            if skeleton.body(root).fixed {
                continue;
            }
            let c = centre(root);
            let anchor = self.physics.insert_body(rp::RigidBodyBuilder::fixed().translation(v3(c[0], c[1])));
            let planar = rp::GenericJointBuilder::new(
                rp::JointAxesMask::LIN_Z | rp::JointAxesMask::ANG_X | rp::JointAxesMask::ANG_Y,
            )
            .contacts_enabled(false)
            .build();
            self.physics
                .insert_multibody_joint(anchor, handles[root], planar)
                .ok_or_else(|| BodyError::Settings("Rapier refused a planar root joint".into()))?;
        }
        for &b in skeleton.tree_order() {
            let Some(j) = skeleton.parent_joint(b) else { continue };
            let jd = &skeleton.desc().joints[j];
            let (p, c) = skeleton.joint_bodies(j);
            let a = [jd.anchor.0 + offset[0], jd.anchor.1 + offset[1]];
            let (cp, cc) = (centre(p), centre(c));
            let mut hinge = rp::GenericJointBuilder::new(
                rp::JointAxesMask::LIN_AXES | rp::JointAxesMask::ANG_X | rp::JointAxesMask::ANG_Y,
            )
            .local_anchor1(v3(a[0] - cp[0], a[1] - cp[1]))
            .local_anchor2(v3(a[0] - cc[0], a[1] - cc[1]))
            .contacts_enabled(false);
            if let Some((lo, hi)) = jd.limits {
                // Limits are in the model's convention; Rapier's angle is counter-clockwise.
                let (lo, hi) = if sign > 0.0 { (lo, hi) } else { (-hi, -lo) };
                hinge = hinge.limits(rp::JointAxis::AngZ, [lo as f32, hi as f32]);
            }
            let h = self
                .physics
                .insert_multibody_joint(handles[p], handles[c], hinge.build())
                .ok_or_else(|| BodyError::Settings(format!("Rapier refused joint `{}`", jd.name)))?;
            joint_handles[j] = Some(h);
        }
        let joint_handles: Vec<rp::MultibodyJointHandle> =
            joint_handles.into_iter().map(|h| h.expect("every joint was inserted")).collect();

        // Fix every multibody's degrees of freedom now (Rapier would on the first step), then read the
        // links and dofs.
        let mut trees = Vec::with_capacity(skeleton.roots().len());
        let mut body_tree = vec![0; n];
        let mut body_link = vec![0; n];
        for (t, &root) in skeleton.roots().iter().enumerate() {
            let Some(&link) = self.physics.multibody_joints.rigid_body_link(handles[root]) else {
                return Err(BodyError::Settings(format!(
                    "skeleton `{}`: fixed body `{}` carries no joint (nothing would move)",
                    skeleton.name(),
                    skeleton.body(root).name
                )));
            };
            let mb =
                self.physics.multibody_joints.get_multibody_mut(link.multibody).expect("multibody exists");
            mb.forward_kinematics(&self.physics.bodies, true);
            // Rapier damps every free angular dof by 0.1 N·m·s/rad by default; the thesis has no such
            // damping (it would slow a somersault).
            mb.damping_mut().fill(0.0);
            let bodies: Vec<usize> = (0..n).filter(|&b| skeleton.root_of(b) == root).collect();
            let ndofs = mb.ndofs();
            for &b in &bodies {
                body_tree[b] = t;
                body_link[b] = self.physics.multibody_joints.rigid_body_link(handles[b]).expect("a link").id;
            }
            trees.push(Tree {
                multibody: link.multibody,
                ndofs,
                bodies,
                q: vec![0.0; ndofs],
                qd: vec![0.0; ndofs],
                rhs: vec![0.0; ndofs],
                sol: vec![0.0; ndofs],
                jac: vec![[0.0; 3]; ndofs],
                mass: SpdSystem::new(ndofs),
                factored: false,
                needs_mass: false,
                actuators: Vec::new(),
            });
        }
        // Dofs: a root's planar joint has x, y, θ (θ is its third dof); a hinge has one.
        let mut link_dof = vec![0usize; n];
        let mut root_angle_dof: Vec<Option<usize>> = vec![None; trees.len()];
        for (t, tree) in trees.iter().enumerate() {
            let mb = self.physics.multibody_joints.get_multibody(tree.multibody).expect("multibody");
            for &b in &tree.bodies {
                let link = mb.link(body_link[b]).expect("link");
                link_dof[b] = link.assembly_id();
                if skeleton.parent_joint(b).is_none() && !skeleton.body(b).fixed {
                    root_angle_dof[t] = Some(link.assembly_id() + 2);
                }
            }
        }
        let joint_dof: Vec<usize> =
            (0..skeleton.n_joints()).map(|j| link_dof[skeleton.joint_bodies(j).1]).collect();
        let mut body_angle_dofs = Vec::with_capacity(n);
        for b in 0..n {
            let mut dofs = Vec::new();
            let mut x = b;
            while let Some(j) = skeleton.parent_joint(x) {
                dofs.push(joint_dof[j]);
                x = skeleton.joint_bodies(j).0;
            }
            dofs.extend(root_angle_dof[body_tree[b]]);
            body_angle_dofs.push(dofs);
        }

        // Actuators.
        let mut actuators = Vec::with_capacity(skeleton.n_actuators());
        for (i, spec) in skeleton.actuators().iter().enumerate() {
            let rt = match spec.drive {
                DriveSpec::Joint(j) => {
                    let (p, c) = skeleton.joint_bodies(j);
                    ActuatorRt {
                        tree: body_tree[c],
                        selection: vec![(joint_dof[j], 1.0)],
                        plus: c,
                        minus: p,
                        joint: Some((joint_handles[j], joint_dof[j])),
                        parent: Some(p),
                    }
                }
                DriveSpec::BodyPair { a, b } => {
                    let mut selection: Vec<(usize, f64)> = Vec::new();
                    for (dofs, s) in [(&body_angle_dofs[a], 1.0), (&body_angle_dofs[b], -1.0)] {
                        for &d in dofs {
                            match selection.iter_mut().find(|(x, _)| *x == d) {
                                Some(e) => e.1 += s,
                                None => selection.push((d, s)),
                            }
                        }
                    }
                    selection.retain(|&(_, c)| c != 0.0);
                    selection.sort_by_key(|&(d, _)| d);
                    ActuatorRt { tree: body_tree[a], selection, plus: a, minus: b, joint: None, parent: None }
                }
            };
            let tree = &mut trees[rt.tree];
            tree.actuators.push(i);
            if rt.joint.is_none() {
                tree.needs_mass = true;
            }
            actuators.push(rt);
        }

        // Per-mode joint set-up: the ODE-style brake is Rapier's dry joint friction on the dof (a
        // zero-velocity constraint whose torque is capped, as ODE's motor with zero target speed);
        // motors are force based (kp in N·m/rad, not normalised by mass).
        for (spec, rt) in skeleton.actuators().iter().zip(&actuators) {
            let Some((handle, dof)) = rt.joint else { continue };
            let (mb, link_id) = self.physics.multibody_joints.get_mut(handle).expect("joint exists");
            match mode {
                PdMode::OdeBrake => mb.frictions_mut()[dof] = spec.brake_torque as f32,
                PdMode::ImplicitMotor => {
                    let data = &mut mb.link_mut(link_id).expect("link").joint.data;
                    data.set_motor_model(rp::JointAxis::AngZ, rp::MotorModel::ForceBased);
                    data.set_motor(rp::JointAxis::AngZ, 0.0, 0.0, 0.0, 0.0);
                    data.set_motor_max_force(rp::JointAxis::AngZ, 0.0);
                }
                PdMode::Explicit | PdMode::ImplicitSpring | PdMode::StablePd => {}
            }
        }

        let n_act = skeleton.n_actuators();
        self.models.push(Model {
            skeleton: skeleton.clone(),
            sign,
            offset,
            handles,
            colliders,
            body_tree,
            body_link,
            body_angle_dofs,
            joint_dof,
            trees,
            actuators,
            welds: Vec::new(),
            commands: Commands::new(n_act, self.settings.max_signals_per_actuator),
            commands_changed: true,
            forces: Vec::with_capacity(16),
            angle: vec![0.0; n_act],
            rate: vec![0.0; n_act],
            mix: vec![TargetMix::default(); n_act],
            avg: vec![TorqueAverage::default(); n_act],
            torque: vec![0.0; n_act],
            applied: vec![0.0; n_act],
            torso: vec![false; n_act],
            group_bits,
        });

        // Welds (impulse fixed joints, removable).
        let mut welds = Vec::with_capacity(skeleton.n_welds());
        for (w, wd) in skeleton.desc().welds.iter().enumerate() {
            let (a, b) = skeleton.weld_bodies(w);
            let m = &self.models[model_idx];
            let (ca, cb) = (centre(a), centre(b));
            let anchor = [wd.anchor.0 + offset[0], wd.anchor.1 + offset[1]];
            let weld = rp::GenericJointBuilder::new(rp::JointAxesMask::LOCKED_FIXED_AXES)
                .local_anchor1(v3(anchor[0] - ca[0], anchor[1] - ca[1]))
                .local_anchor2(v3(anchor[0] - cb[0], anchor[1] - cb[1]))
                .contacts_enabled(false)
                .build();
            let (ha, hb) = (m.handles[a], m.handles[b]);
            welds.push(Some(self.physics.insert_impulse_joint(ha, hb, weld)));
        }
        self.models[model_idx].welds = welds;
        self.update_collision_groups();
        Ok(model_idx)
    }

    /// Recomputes every model collider's membership and filter (a new model changes who meets whom).
    fn update_collision_groups(&mut self) {
        let other_bits: Vec<u32> = self
            .models
            .iter()
            .map(|m| {
                m.skeleton
                    .groups()
                    .iter()
                    .zip(&m.group_bits)
                    .filter(|(g, _)| g.other_models)
                    .fold(0, |acc, (_, &bit)| acc | bit)
            })
            .collect();
        for (mi, m) in self.models.iter().enumerate() {
            let sk = &m.skeleton;
            for (b, &ch) in m.colliders.iter().enumerate() {
                let gi = sk.body_group(b);
                let g = &sk.groups()[gi];
                let mut filter = if g.ground { GROUND_BIT } else { 0 };
                for (gj, &bit) in m.group_bits.iter().enumerate() {
                    let other = &sk.groups()[gj];
                    if g.groups.contains(&other.name) || other.groups.contains(&g.name) {
                        filter |= bit;
                    }
                }
                if g.other_models {
                    for (mj, &bits) in other_bits.iter().enumerate() {
                        if mj != mi {
                            filter |= bits;
                        }
                    }
                }
                let groups = rp::InteractionGroups::new(
                    rp::Group::from_bits_retain(m.group_bits[gi]),
                    rp::Group::from_bits_retain(filter),
                    rp::InteractionTestMode::And,
                );
                if let Some(c) = self.physics.colliders.get_mut(ch) {
                    c.set_collision_groups(groups);
                }
            }
        }
    }

    pub fn n_models(&self) -> usize {
        self.models.len()
    }

    fn model(&self, model: usize) -> Result<&Model, BodyError> {
        self.models.get(model).ok_or(BodyError::NoSuchModel(model))
    }

    pub fn skeleton(&self, model: usize) -> Result<&Skeleton, BodyError> {
        Ok(&self.model(model)?.skeleton)
    }

    /// The translation applied to the model's initial configuration, metres.
    pub fn model_offset(&self, model: usize) -> Result<[f64; 2], BodyError> {
        Ok(self.model(model)?.offset)
    }

    /// Completed steps.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Simulated time, seconds: steps · Δt (counted, never accumulated).
    pub fn time(&self) -> f64 {
        self.steps as f64 * self.settings.dt
    }

    /// The model's actuator commands, held until changed.
    pub fn commands_mut(&mut self, model: usize) -> Result<&mut Commands, BodyError> {
        let m = self.models.get_mut(model).ok_or(BodyError::NoSuchModel(model))?;
        m.commands_changed = true;
        Ok(&mut m.commands)
    }

    pub fn commands(&self, model: usize) -> Result<&Commands, BodyError> {
        Ok(&self.model(model)?.commands)
    }

    /// Releases weld `weld_idx` (e.g. a hand letting go of the ball) before the next step. The two
    /// bodies keep the velocities they have.
    pub fn release_weld(&mut self, model: usize, weld_idx: usize) -> Result<(), BodyError> {
        let m = self.models.get_mut(model).ok_or(BodyError::NoSuchModel(model))?;
        let name = m.skeleton.name().to_string();
        let slot = m.welds.get_mut(weld_idx).ok_or(BodyError::NoSuchIndex {
            model: name.clone(),
            what: "weld",
            index: weld_idx,
        })?;
        let h = slot.take().ok_or_else(|| BodyError::AlreadyReleased {
            model: name,
            weld: m.skeleton.desc().welds[weld_idx].name.clone(),
        })?;
        self.physics.impulse_joints.remove(h, true);
        Ok(())
    }

    /// Whether weld `weld_idx` still holds.
    pub fn weld_holds(&self, model: usize, weld_idx: usize) -> Result<bool, BodyError> {
        let m = self.model(model)?;
        m.welds.get(weld_idx).map(Option::is_some).ok_or(BodyError::NoSuchIndex {
            model: m.skeleton.name().into(),
            what: "weld",
            index: weld_idx,
        })
    }

    /// Applies `force` (N, world x and y) at world `point` (m) of a body during the next step only
    /// (e.g. a push on the head, spec §3.6).
    pub fn apply_force(
        &mut self,
        model: usize,
        body: usize,
        force: [f64; 2],
        point: [f64; 2],
    ) -> Result<(), BodyError> {
        let m = self.models.get_mut(model).ok_or(BodyError::NoSuchModel(model))?;
        if body >= m.handles.len() {
            return Err(BodyError::NoSuchIndex {
                model: m.skeleton.name().into(),
                what: "body",
                index: body,
            });
        }
        if m.forces.len() == m.forces.capacity() {
            return Err(BodyError::Settings("at most 16 external forces per model and step".into()));
        }
        m.forces.push(ExternalForce { body, force, point });
        Ok(())
    }

    /// Advances one control step: `substeps` physics steps, each re-evaluating the PD torques from
    /// the held commands.
    pub fn step(&mut self) -> Result<(), BodyError> {
        let h = self.settings.physics_dt();
        for _ in 0..self.settings.substeps {
            for mi in 0..self.models.len() {
                self.actuate(mi, h);
            }
            self.physics.step();
        }
        for m in &mut self.models {
            m.forces.clear();
        }
        self.steps += 1;
        self.check_finite()
    }

    fn check_finite(&self) -> Result<(), BodyError> {
        let quarantined = self.physics.quarantine().bodies();
        for m in &self.models {
            for (b, &h) in m.handles.iter().enumerate() {
                let rb = &self.physics.bodies[h];
                // Beyond these the state is meaningless even if finite: an explicit PD far past its
                // stability bound grows without limit.
                let (x, v, w) = (rb.translation(), rb.linvel(), rb.angvel());
                let ok = x.is_finite()
                    && v.is_finite()
                    && w.is_finite()
                    && x.abs().max_element() < DIVERGED_POSITION_M
                    && v.length() < DIVERGED_SPEED_M_S
                    && w.length() < DIVERGED_SPIN_RAD_S;
                if !ok || quarantined.contains(&h) {
                    return Err(BodyError::NonFinite {
                        step: self.steps,
                        time: self.time(),
                        model: m.skeleton.name().into(),
                        body: m.skeleton.body(b).name.clone(),
                    });
                }
            }
        }
        Ok(())
    }

    /// Reads the trees' coordinates, evaluates the actuators for one physics step of length `h` and
    /// applies torques, joint springs, damping and external forces.
    fn actuate(&mut self, mi: usize, h: f64) {
        let World { physics, models, settings, .. } = self;
        let m = &mut models[mi];
        let mode = m.skeleton.actuation().mode;

        // Clear last step's forces; wake a sleeping model whose commands changed.
        let wake = settings.solver.sleeping && m.commands_changed;
        for &hb in &m.handles {
            let rb = &mut physics.bodies[hb];
            rb.reset_forces(false);
            rb.reset_torques(false);
            if wake {
                rb.wake_up(true);
            }
        }
        m.commands_changed = false;

        read_state(physics, m);
        let any_torso = gather_signals(m);
        // Mass matrices, for body-pair actuators only (their inertia), once per physics step.
        for tree in &mut m.trees {
            if tree.needs_mass {
                let mb = physics.multibody_joints.get_multibody(tree.multibody).expect("multibody");
                assemble_mass_matrix(mb, &m.skeleton, &m.body_link, tree, settings.gravity);
            }
        }

        let sign = m.sign;
        for a in 0..m.actuators.len() {
            let spec = &m.skeleton.actuators()[a];
            let rt = &m.actuators[a];
            let (th, om, mix) = (m.angle[a], m.rate[a], m.mix[a]);
            // Gains as the signals' weighted mix asks (W_angle/W of kp; kd while any signal asks).
            let (kp, kd) = (spec.kp * mix.stiffness_factor(), spec.kd * mix.damping_factor());
            if m.torso[a] {
                // Driven by an explicit torque once every other actuator's is known: the joint
                // hosts no spring, damper or motor in this step.
                release_joint(physics, mode, rt.joint);
                continue;
            }
            let tau = match (mode, rt.joint) {
                (PdMode::Explicit, _) => m.avg[a].torque,
                (PdMode::OdeBrake, Some(_)) => m.avg[a].torque,
                (PdMode::OdeBrake, None) => {
                    // No joint hosts a brake for a body pair: stop the relative rate with the pair's
                    // effective inertia, within the brake torque (explicit emulation).
                    let i_eff = effective_inertia(&mut m.trees[rt.tree], &rt.selection);
                    m.avg[a].torque + (-i_eff * om / h).clamp(-spec.brake_torque, spec.brake_torque)
                }
                (PdMode::ImplicitSpring, Some((handle, dof))) => {
                    let (mb, link_id) = physics.multibody_joints.get_mut(handle).expect("joint");
                    mb.link_mut(link_id).expect("link").joint.set_spring(
                        ANG_Z,
                        kp as f32,
                        mix.target() as f32,
                    );
                    mb.damping_mut()[dof] = kd as f32;
                    // Not applied by us: what the implicit spring and damper exert at this state.
                    m.applied[a] = kp * (mix.target() - th) - kd * om;
                    m.torque[a] = sign * m.applied[a];
                    continue;
                }
                (PdMode::ImplicitMotor, Some((handle, _))) => {
                    let (mb, link_id) = physics.multibody_joints.get_mut(handle).expect("joint");
                    let data = &mut mb.link_mut(link_id).expect("link").joint.data;
                    data.set_motor(rp::JointAxis::AngZ, mix.target() as f32, 0.0, kp as f32, kd as f32);
                    let cap = if mix.weight > 0.0 { spec.max_torque } else { 0.0 };
                    data.set_motor_max_force(rp::JointAxis::AngZ, cap as f32);
                    m.applied[a] =
                        (kp * (mix.target() - th) - kd * om).clamp(-spec.max_torque, spec.max_torque);
                    m.torque[a] = sign * m.applied[a];
                    continue;
                }
                (PdMode::StablePd, Some((handle, dof))) => {
                    // Tan, Liu & Turk's τ = −kp (q + h q̇ − q̄) − kd (q̇ + h q̈): the proportional part
                    // as a torque, the damping part as Rapier's implicit joint damping, so that q̈
                    // is Rapier's own articulated solve (gravity and Coriolis terms included).
                    let (mb, _) = physics.multibody_joints.get_mut(handle).expect("joint");
                    mb.damping_mut()[dof] = kd as f32;
                    (kp * (mix.target() - th - h * om)).clamp(-spec.max_torque, spec.max_torque)
                }
                (PdMode::ImplicitSpring | PdMode::ImplicitMotor | PdMode::StablePd, None) => {
                    // A body pair has no joint to host a spring, motor or damping: stable PD on its
                    // own effective inertia I, τ = (kp (θ̄ − θ − h θ̇) − kd θ̇) / (1 + h kd / I).
                    let i_eff = effective_inertia(&mut m.trees[rt.tree], &rt.selection);
                    let t = (kp * (mix.target() - th - h * om) - kd * om) / (1.0 + h * kd / i_eff);
                    t.clamp(-spec.max_torque, spec.max_torque)
                }
            };
            m.torque[a] = sign * tau;
            // Stable PD's damping is Rapier's, implicit: what it adds is about −kd θ̇.
            let implicit_damping = matches!((mode, rt.joint), (PdMode::StablePd, Some(_)));
            m.applied[a] = if implicit_damping { tau - kd * om } else { tau };
            add_torque_pair(physics, &m.handles, rt.plus, rt.minus, tau);
        }
        if any_torso {
            torso_pass(physics, m);
        }
        for f in &m.forces {
            physics.bodies[m.handles[f.body]].add_force_at_point(
                v3(f.force[0], f.force[1]),
                v3(f.point[0], f.point[1]),
                true,
            );
        }
    }

    /// Fills `out` with the pose of every body of a model (cleared first; reuse it to avoid
    /// allocating).
    pub fn body_poses(&self, model: usize, out: &mut Vec<BodyPose>) -> Result<(), BodyError> {
        let m = self.model(model)?;
        out.clear();
        for (b, &h) in m.handles.iter().enumerate() {
            let rb = &self.physics.bodies[h];
            let c = rb.center_of_mass();
            let desc = m.skeleton.body(b);
            out.push(BodyPose {
                body: b,
                centre: [f64::from(c.x), f64::from(c.y)],
                angle: self.body_angle_of(m, b),
                shape: desc.shape,
                side: desc.side,
            });
        }
        Ok(())
    }

    /// World angle of a body, counter-clockwise, from the joint coordinates (not wrapped).
    fn body_angle_of(&self, m: &Model, b: usize) -> f64 {
        let tree = &m.trees[m.body_tree[b]];
        let mb = self.physics.multibody_joints.get_multibody(tree.multibody).expect("multibody");
        m.body_angle_dofs[b].iter().map(|&d| coordinate(mb, d)).sum()
    }

    /// How far a model's motion has left the x–y plane: the largest |z| of a body centre (m) and
    /// the largest tilt of a body's rotation axis away from z (rad, from the quaternion's x and y
    /// parts). Both stay zero to round-off: the reduced coordinates have no out-of-plane freedom.
    pub fn planar_deviation(&self, model: usize) -> Result<(f64, f64), BodyError> {
        let m = self.model(model)?;
        let (mut z, mut tilt) = (0.0f64, 0.0f64);
        for &h in &m.handles {
            let rb = &self.physics.bodies[h];
            z = z.max(f64::from(rb.translation().z.abs()));
            let q = rb.rotation();
            tilt = tilt.max(2.0 * f64::from(q.x.hypot(q.y)));
        }
        Ok((z, tilt))
    }

    /// Momentum of a model's bodies (props included).
    pub fn momentum(&self, model: usize) -> Result<Momentum, BodyError> {
        let m = self.model(model)?;
        let (mut mass, mut c, mut p) = (0.0, [0.0; 2], [0.0; 2]);
        for (b, &h) in m.handles.iter().enumerate() {
            let rb = &self.physics.bodies[h];
            let mb = m.skeleton.body(b).mass;
            let (x, v) = (rb.center_of_mass(), rb.linvel());
            mass += mb;
            c[0] += mb * f64::from(x.x);
            c[1] += mb * f64::from(x.y);
            p[0] += mb * f64::from(v.x);
            p[1] += mb * f64::from(v.y);
        }
        let (c, vc) = ([c[0] / mass, c[1] / mass], [p[0] / mass, p[1] / mass]);
        let mut l = 0.0;
        for (b, &h) in m.handles.iter().enumerate() {
            let rb = &self.physics.bodies[h];
            let d = m.skeleton.body(b);
            let (x, v) = (rb.center_of_mass(), rb.linvel());
            let (rx, ry) = (f64::from(x.x) - c[0], f64::from(x.y) - c[1]);
            let (vx, vy) = (f64::from(v.x) - vc[0], f64::from(v.y) - vc[1]);
            l += d.shape.inertia_zz(d.mass) * f64::from(rb.angvel().z) + d.mass * (rx * vy - ry * vx);
        }
        Ok(Momentum { linear: p, angular: l })
    }

    pub(crate) fn sense_raw(&self, model: usize) -> Result<SenseView<'_>, BodyError> {
        let m = self.model(model)?;
        Ok(SenseView { world: self, model: m, model_idx: model })
    }

    /// Which (model, body) a collider belongs to; `None` for the ground.
    fn owner(&self, c: rp::ColliderHandle) -> Option<(usize, usize)> {
        self.collider_owner.get(c.into_raw_parts().0 as usize).copied().flatten()
    }
}

/// Read access for the sensors module.
pub(crate) struct SenseView<'a> {
    world: &'a World,
    model: &'a Model,
    pub model_idx: usize,
}

/// Something a body touches.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Touch {
    Ground,
    /// A body of a model (possibly this same model).
    Body {
        model: usize,
        body: usize,
    },
}

impl SenseView<'_> {
    pub fn skeleton(&self) -> &Skeleton {
        &self.model.skeleton
    }
    pub fn sign(&self) -> f64 {
        self.model.sign
    }
    pub fn steps(&self) -> u64 {
        self.world.steps
    }
    pub fn time(&self) -> f64 {
        self.world.time()
    }
    pub fn joint_angle_rate(&self, j: usize) -> (f64, f64) {
        let b = self.model.skeleton.joint_bodies(j).1;
        let tree = &self.model.trees[self.model.body_tree[b]];
        let mb = self.world.physics.multibody_joints.get_multibody(tree.multibody).expect("multibody");
        let d = self.model.joint_dof[j];
        (coordinate(mb, d), f64::from(mb.generalized_velocity()[d]))
    }
    pub fn actuator_angle_rate(&self, a: usize) -> (f64, f64) {
        let rt = &self.model.actuators[a];
        let tree = &self.model.trees[rt.tree];
        let mb = self.world.physics.multibody_joints.get_multibody(tree.multibody).expect("multibody");
        let v = mb.generalized_velocity();
        rt.selection
            .iter()
            .fold((0.0, 0.0), |(x, y), &(d, c)| (x + c * coordinate(mb, d), y + c * f64::from(v[d])))
    }
    pub fn actuator_torque(&self, a: usize) -> f64 {
        self.model.torque[a]
    }
    pub fn body_state(&self, b: usize) -> ([f64; 2], [f64; 2], f64, f64) {
        let rb = &self.world.physics.bodies[self.model.handles[b]];
        let (c, v) = (rb.center_of_mass(), rb.linvel());
        (
            [f64::from(c.x), f64::from(c.y)],
            [f64::from(v.x), f64::from(v.y)],
            self.world.body_angle_of(self.model, b),
            f64::from(rb.angvel().z),
        )
    }
    /// Calls `f(body, touch)` for every touching contact of this model's bodies.
    pub fn for_each_contact(&self, mut f: impl FnMut(usize, Touch)) {
        for pair in self.world.physics.narrow_phase.contact_pairs() {
            if !pair.has_any_active_contact() {
                continue;
            }
            let (o1, o2) = (self.world.owner(pair.collider1), self.world.owner(pair.collider2));
            let touch = |o: Option<(usize, usize)>| match o {
                Some((model, body)) => Touch::Body { model, body },
                None => Touch::Ground,
            };
            if let Some((mi, b)) = o1
                && mi == self.model_idx
            {
                f(b, touch(o2));
            }
            if let Some((mi, b)) = o2
                && mi == self.model_idx
            {
                f(b, touch(o1));
            }
        }
    }
}

/// Coordinate `dof` of a multibody: the unwrapped angle of a hinge or of a root's rotation, or a
/// root's displacement.
fn coordinate(mb: &rp::Multibody, dof: usize) -> f64 {
    // Find the link owning `dof` (few links; no allocation).
    for link in mb.links() {
        let (start, n) = (link.assembly_id(), link.joint().ndofs());
        if dof >= start && dof < start + n {
            let k = dof - start;
            let coords = link.joint().coords();
            // Free axes in Rapier's order: the unlocked linear ones, then the unlocked angular ones.
            return f64::from(if n == 1 {
                coords[ANG_Z]
            } else {
                match k {
                    0 => coords[0],
                    1 => coords[1],
                    _ => coords[ANG_Z],
                }
            });
        }
    }
    f64::NAN
}

fn read_coordinates(mb: &rp::Multibody, q: &mut [f64], qd: &mut [f64]) {
    let v = mb.generalized_velocity();
    for link in mb.links() {
        let (start, n) = (link.assembly_id(), link.joint().ndofs());
        let coords = link.joint().coords();
        match n {
            1 => q[start] = f64::from(coords[ANG_Z]),
            3 => {
                q[start] = f64::from(coords[0]);
                q[start + 1] = f64::from(coords[1]);
                q[start + 2] = f64::from(coords[ANG_Z]);
            }
            _ => {}
        }
        for k in 0..n {
            qd[start + k] = f64::from(v[start + k]);
        }
    }
}

/// Coordinates and velocities of every tree, then each actuator's angle and rate (counter-clockwise).
fn read_state(physics: &rp::PhysicsWorld, m: &mut Model) {
    for tree in &mut m.trees {
        let mb = physics.multibody_joints.get_multibody(tree.multibody).expect("multibody");
        read_coordinates(mb, &mut tree.q, &mut tree.qd);
    }
    for (a, rt) in m.actuators.iter().enumerate() {
        let t = &m.trees[rt.tree];
        m.angle[a] = rt.selection.iter().map(|&(d, c)| c * t.q[d]).sum();
        m.rate[a] = rt.selection.iter().map(|&(d, c)| c * t.qd[d]).sum();
    }
}

/// The held signals → per actuator, the Eq. 5.1–5.2 average of clamped torques (explicit modes) and
/// the linear mix of targets (all modes). Angles are counter-clockwise here; `sign` converts the
/// model's convention. An actuator with a fixed target ignores the signals. Torso signals are only
/// marked (`Model::torso`): their torque needs the other actuators' ([`torso_pass`]). Returns whether
/// any actuator holds one.
fn gather_signals(m: &mut Model) -> bool {
    let sk = &m.skeleton;
    let mode = sk.actuation().mode;
    let sign = m.sign;
    // The ODE-style mode has kd = 0 in Eq. 2.1: its damping is the brake.
    let kd_of = |kd: f64| if mode == PdMode::OdeBrake { 0.0 } else { kd };
    let mut any_torso = false;
    for (a, spec) in sk.actuators().iter().enumerate() {
        m.avg[a] = TorqueAverage::default();
        m.mix[a] = TargetMix::default();
        m.torso[a] = false;
        if let Some(fixed) = spec.fixed_target {
            let target = sign * fixed;
            let t = signal_torque(
                Target::Angle(target),
                target,
                m.angle[a],
                m.rate[a],
                spec.kp,
                kd_of(spec.kd),
                spec.max_torque,
            );
            m.avg[a].add(t.unwrap_or(0.0), 1.0);
            m.mix[a] = TargetMix { weight: 1.0, angle_weight: 1.0, weighted_angle: target };
        }
    }
    for s in m.commands.signals() {
        let a = s.actuator;
        let spec = &sk.actuators()[a];
        if spec.fixed_target.is_some() {
            continue;
        }
        if let Target::Torso { .. } = s.target {
            m.torso[a] = true;
            any_torso = true;
            continue;
        }
        let rt = &m.actuators[a];
        let target = match (s.target, s.frame, rt.parent) {
            (Target::Angle(t), TargetFrame::World, Some(p)) => {
                let tree = &m.trees[rt.tree];
                sign * t - m.body_angle_dofs[p].iter().map(|&d| tree.q[d]).sum::<f64>()
            }
            (Target::Angle(t), _, _) => sign * t,
            _ => 0.0,
        };
        if let Some(t) =
            signal_torque(s.target, target, m.angle[a], m.rate[a], spec.kp, kd_of(spec.kd), spec.max_torque)
        {
            m.avg[a].add(t, s.weight);
        }
        let mix = &mut m.mix[a];
        match s.target {
            Target::Angle(_) => {
                mix.weight += s.weight;
                mix.angle_weight += s.weight;
                mix.weighted_angle += s.weight * target;
            }
            Target::DampingOnly => mix.weight += s.weight,
            Target::NoTorque | Target::Torso { .. } => {}
        }
    }
    any_torso
}

/// τ on `plus`, −τ on `minus` (counter-clockwise, N·m): an actuator's equal and opposite pair.
fn add_torque_pair(
    physics: &mut rp::PhysicsWorld,
    handles: &[rp::RigidBodyHandle],
    plus: usize,
    minus: usize,
    tau: f64,
) {
    let tau = tau as f32;
    if tau != 0.0 {
        physics.bodies[handles[plus]].add_torque(rp::Vector::new(0.0, 0.0, tau), false);
        physics.bodies[handles[minus]].add_torque(rp::Vector::new(0.0, 0.0, -tau), false);
    }
}

/// Takes the joint of an actuator that a torso signal drives out of the implicit modes for this step:
/// no spring, no damping, no motor (the ODE-style brake, Rapier's joint friction, stays).
fn release_joint(
    physics: &mut rp::PhysicsWorld,
    mode: PdMode,
    joint: Option<(rp::MultibodyJointHandle, usize)>,
) {
    let Some((handle, dof)) = joint else { return };
    let (mb, link_id) = physics.multibody_joints.get_mut(handle).expect("joint");
    match mode {
        PdMode::ImplicitSpring => {
            mb.link_mut(link_id).expect("link").joint.set_spring(ANG_Z, 0.0, 0.0);
            mb.damping_mut()[dof] = 0.0;
        }
        PdMode::ImplicitMotor => {
            let data = &mut mb.link_mut(link_id).expect("link").joint.data;
            data.set_motor(rp::JointAxis::AngZ, 0.0, 0.0, 0.0, 0.0);
            data.set_motor_max_force(rp::JointAxis::AngZ, 0.0);
        }
        PdMode::StablePd => mb.damping_mut()[dof] = 0.0,
        PdMode::Explicit | PdMode::OdeBrake => {}
    }
}

/// The torso signals (SIMBICON's stance hip, [`Target::Torso`]), once every other actuator's torque
/// of this physics step is known: each adds τ = −τ_torso − τ_swing to its actuator's Eq. 5.1 average
/// (beside the explicit PD torques of any other signals it holds), and every actuator holding one
/// applies that average as an explicit torque pair. τ_torso is the PD torque, with the actuator's
/// own gains kp and kd, that would hold the body it pushes against (the parent of a hinge) at the
/// signal's world angle; τ_swing is what the swing actuator exerts in this step (`Model::applied`;
/// a swing that is itself driven by a torso signal contributes its previous step's torque).
fn torso_pass(physics: &mut rp::PhysicsWorld, m: &mut Model) {
    let Model {
        skeleton,
        sign,
        commands,
        actuators,
        trees,
        body_tree,
        body_angle_dofs,
        avg,
        applied,
        torso,
        torque,
        handles,
        ..
    } = m;
    let sign = *sign;
    for s in commands.signals() {
        let Target::Torso { angle, swing } = s.target else { continue };
        let a = s.actuator;
        let spec = &skeleton.actuators()[a];
        if spec.fixed_target.is_some() {
            continue;
        }
        let body = actuators[a].minus;
        let tree = &trees[body_tree[body]];
        let dofs = &body_angle_dofs[body];
        let theta: f64 = dofs.iter().map(|&d| tree.q[d]).sum();
        let omega: f64 = dofs.iter().map(|&d| tree.qd[d]).sum();
        let t = torso_torque(sign * angle, theta, omega, applied[swing], spec.kp, spec.kd, spec.max_torque);
        avg[a].add(t, s.weight);
    }
    for a in 0..actuators.len() {
        if !torso[a] {
            continue;
        }
        let tau = avg[a].torque;
        torque[a] = sign * tau;
        applied[a] = tau;
        add_torque_pair(physics, handles, actuators[a].plus, actuators[a].minus, tau);
    }
}

/// M = Σ_links m Jᵥᵀ Jᵥ + I_zz J_θᵀ J_θ (planar rows only), and the generalised gravity force
/// Σ_links −m g J_yᵀ into `tree.rhs`.
fn assemble_mass_matrix(mb: &rp::Multibody, sk: &Skeleton, body_link: &[usize], tree: &mut Tree, g: f64) {
    let n = tree.ndofs;
    tree.mass.clear();
    tree.factored = false;
    tree.rhs.fill(0.0);
    for &b in &tree.bodies {
        let j: &na::OMatrix<f32, na::U6, na::Dyn> = mb.body_jacobian(body_link[b]);
        let d = sk.body(b);
        let (mass, izz) = (d.mass, d.shape.inertia_zz(d.mass));
        for c in 0..n {
            tree.jac[c] = [f64::from(j[(0, c)]), f64::from(j[(1, c)]), f64::from(j[(5, c)])];
        }
        for r in 0..n {
            let jr = tree.jac[r];
            if jr == [0.0; 3] {
                continue;
            }
            tree.rhs[r] -= mass * g * jr[1];
            for c in 0..n {
                let jc = tree.jac[c];
                tree.mass.add(r, c, mass * (jr[0] * jc[0] + jr[1] * jc[1]) + izz * jr[2] * jc[2]);
            }
        }
    }
}

/// 1 / (sᵀ M⁻¹ s): the inertia a torque along selection s meets (M as last assembled; factorised
/// on first use).
fn effective_inertia(tree: &mut Tree, selection: &[(usize, f64)]) -> f64 {
    if !tree.factored {
        if !tree.mass.factorise() {
            return f64::INFINITY;
        }
        tree.factored = true;
    }
    tree.sol.fill(0.0);
    for &(d, c) in selection {
        tree.sol[d] = c;
    }
    tree.mass.solve(&mut tree.sol);
    let s_minv_s: f64 = selection.iter().map(|&(d, c)| c * tree.sol[d]).sum();
    1.0 / s_minv_s
}
