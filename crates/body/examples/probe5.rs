use anima_body::*;
fn main() {
    let brake: f64 = std::env::var("B").map(|s| s.parse().unwrap()).unwrap_or(100.0);
    let it: u32 = std::env::var("IT").map(|s| s.parse().unwrap()).unwrap_or(4);
    let text = format!(
        r#"Skeleton(name: "double", depth: 0.1,
      bodies: [
        Body(name: "base", shape: Box(width: 0.2, height: 0.2), mass: 1.0, centre: (0.0, 2.0), fixed: {}),
        Body(name: "l1", shape: Box(width: 0.1, height: 1.0), mass: 1.0, centre: (0.0, 1.5)),
        Body(name: "l2", shape: Box(width: 0.1, height: 1.0), mass: 1.0, centre: (0.0, 0.5)),
      ],
      joints: [ Joint(name: "h1", kind: Hinge, parent: "base", child: "l1", anchor: (0.0, 2.0)),
                Joint(name: "h2", kind: Hinge, parent: "l1", child: "l2", anchor: (0.0, 1.0)) ],
      actuators: [ Actuator(name: "h1", number: 1, drives: Joint("h1"), kp: 0.0, kd: 0.0, max_torque: Some(100.0), brake_torque: Some({brake})),
                   Actuator(name: "h2", number: 2, drives: Joint("h2"), kp: 50.0, kd: 0.0, max_torque: Some(100.0), brake_torque: Some(0.0)) ],
      actuation: Actuation(mode: OdeBrake, gain_scale: 1.0, torque_limit_rad: 1.0, brake_rad_s: 0.0),
    )"#,
        std::env::var("FREE").is_err()
    );
    let sk = Skeleton::from_ron_str(&text).unwrap();
    let mut s = WorldSettings::thesis();
    s.dt = 0.005;
    s.gravity = 0.0;
    s.ground = None;
    s.solver.iterations = it;
    let mut w = World::new(s).unwrap();
    let m = w.add_model(&sk, Placement::Offset { dx: 0.0, dy: 0.0 }).unwrap();
    w.commands_mut(m).unwrap().push(Signal::angle(1, 1.0)).unwrap();
    let mut sens = Sensors::new(&w, m).unwrap();
    for k in 0..100 {
        w.step().unwrap();
        w.sense(&mut sens).unwrap();
        if k % 10 == 0 {
            println!(
                "t {:.3} h1 {:.5} h2 {:.5} body0 {:.5}",
                sens.time, sens.joint_angle[0], sens.joint_angle[1], sens.body_angle[0]
            );
        }
    }
}
