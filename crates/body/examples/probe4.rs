use anima_body::*;
fn main() {
    let text = r#"Skeleton(name: "pendulum", depth: 0.1,
      bodies: [
        Body(name: "base", shape: Box(width: 0.2, height: 0.2), mass: 1.0, centre: (0.0, 1.0), fixed: true),
        Body(name: "link", shape: Box(width: 0.1, height: 1.0), mass: 1.0, centre: (0.0, 0.5)),
      ],
      joints: [ Joint(name: "hinge", kind: Hinge, parent: "base", child: "link", anchor: (0.0, 1.0)) ],
      actuators: [ Actuator(name: "hinge", number: 1, drives: Joint("hinge"), kp: 0.0, kd: 0.0, max_torque: Some(100.0)) ],
      actuation: Actuation(mode: Explicit, gain_scale: 1.0, torque_limit_rad: 1.0, brake_rad_s: 0.0),
    )"#;
    let sk = Skeleton::from_ron_str(text).unwrap();
    let mut s = WorldSettings::thesis();
    s.dt = 0.01;
    s.gravity = 0.0;
    s.ground = None;
    let mut w = World::new(s).unwrap();
    let m = w.add_model(&sk, Placement::Offset { dx: 0.0, dy: 0.0 }).unwrap();
    // kp = 0: use a fixed torque via DampingOnly? Use a world force instead: torque 1 N·m as a force couple.
    let mut sens = Sensors::new(&w, m).unwrap();
    for _ in 0..10 {
        // Couple: +1 N at (0.5, 0) ... apply a horizontal force 1 N at the link's tip (0, 0): torque about hinge (0,1) = r × F = (0,-1) × (1,0) = +1.
        w.apply_force(m, 1, [1.0, 0.0], [0.0, 0.0]).unwrap();
        w.step().unwrap();
    }
    w.sense(&mut sens).unwrap();
    let i = (0.01 + 1.0) / 12.0 + 0.25;
    println!(
        "after 0.1 s: angle {:.6} rate {:.6}; expected rate {:.6} (I = {i:.4})",
        sens.joint_angle[0],
        sens.joint_rate[0],
        0.1 / i
    );
}
