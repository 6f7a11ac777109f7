//! Shared set-ups: the PD-held stance of each mode at the thesis's 0.05 s step (docs/body.md says how
//! these settings were found).

use anima_body::{Actuation, BuiltinSkeleton, PdMode, Placement, Sensors, Skeleton, World, WorldSettings};

/// Gain factor G of the stance (spec §4.3): the ankles need kp above m·g·h ≈ 800 N·m/rad.
pub const STANCE_GAIN: f64 = 100.0;

/// World settings for a PD-held stance in `mode` at Δt = 0.05 s.
pub fn stance_settings(mode: PdMode) -> WorldSettings {
    let mut s = WorldSettings::thesis();
    s.solver.iterations = 1;
    match mode {
        // Explicit springs on the 1.2 kg feet need h ≤ 0.005 s; the brakes need converged sweeps.
        PdMode::OdeBrake => {
            s.substeps = 10;
            s.solver.pgs_iterations = 8;
        }
        // Stable PD is unconditionally stable only for h ≤ 2 kd / (3 kp) = 0.022 s.
        PdMode::StablePd => s.substeps = 3,
        PdMode::Explicit => s.substeps = 50,
        PdMode::ImplicitSpring | PdMode::ImplicitMotor => {}
    }
    s
}

pub fn humanoid(mode: PdMode, gain: f64) -> Skeleton {
    let brake_rad_s = if mode == PdMode::OdeBrake { 1.0 } else { 4.0 };
    BuiltinSkeleton::Humanoid
        .load()
        .with_actuation(Actuation { mode, gain_scale: gain, torque_limit_rad: 1.0, brake_rad_s })
        .expect("valid actuation")
}

/// A world with one humanoid standing on the ground holding the initial pose.
pub fn stance(mode: PdMode) -> (World, usize, Sensors) {
    let sk = humanoid(mode, STANCE_GAIN);
    let mut world = World::new(stance_settings(mode)).expect("valid settings");
    let m = world.add_model(&sk, Placement::OnGround { dx: 0.0 }).expect("model");
    world.commands_mut(m).unwrap().hold(&vec![0.0; sk.n_actuators()]).unwrap();
    let sensors = Sensors::new(&world, m).unwrap();
    (world, m, sensors)
}

/// Velocity (m/s) of the world point `p` carried by body `b`.
pub fn point_velocity(s: &Sensors, b: usize, p: [f64; 2]) -> [f64; 2] {
    let (c, v, w) = (s.body_position[b], s.body_velocity[b], s.body_angular_velocity[b]);
    [v[0] - w * (p[1] - c[1]), v[1] + w * (p[0] - c[0])]
}

/// World position of the point at `local` (m, body frame) of body `b`.
pub fn body_point(s: &Sensors, b: usize, local: [f64; 2]) -> [f64; 2] {
    let (c, th) = (s.body_position[b], s.body_angle[b]);
    let (sn, cs) = th.sin_cos();
    [c[0] + cs * local[0] - sn * local[1], c[1] + sn * local[0] + cs * local[1]]
}
