use anima_body::*;
fn main() {
    let ground = std::env::var("GROUND").is_ok();
    let sk = BuiltinSkeleton::Humanoid.load();
    let sk = sk
        .with_actuation(Actuation {
            mode: if std::env::var("EXPL").is_ok() { PdMode::Explicit } else { PdMode::OdeBrake },
            gain_scale: 100.0,
            torque_limit_rad: 1.0,
            brake_rad_s: 40.0,
        })
        .unwrap();
    let mut s = WorldSettings::thesis();
    s.dt = 0.005;
    s.solver.iterations = std::env::var("IT").map(|x| x.parse().unwrap()).unwrap_or(1);
    s.solver.pgs_iterations = std::env::var("PGS").map(|x| x.parse().unwrap()).unwrap_or(1);
    if !ground {
        s.ground = None;
    }
    let mut w = World::new(s).unwrap();
    let m = w.add_model(&sk, Placement::OnGround { dx: 0.0 }).unwrap();
    let mut pose = vec![0.0; sk.n_actuators()];
    pose[sk.actuator_index("knee_l").unwrap()] = -0.5;
    w.commands_mut(m).unwrap().hold(&pose).unwrap();
    let mut sens = Sensors::new(&w, m).unwrap();
    for k in 0..400 {
        w.step().unwrap();
        w.sense(&mut sens).unwrap();
        if k % 20 == 0 {
            let q: Vec<String> = sens.joint_angle.iter().map(|x| format!("{x:.3}")).collect();
            let t: Vec<String> = sens.actuator_torque.iter().map(|x| format!("{x:.0}")).collect();
            println!("t={:.3} q=[{}] tau=[{}]", sens.time, q.join(" "), t.join(" "));
        }
    }
}
