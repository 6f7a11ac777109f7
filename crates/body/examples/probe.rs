use anima_body::*;
use std::time::Instant;

fn run(mode: PdMode, g: f64, dt: f64, substeps: u32, iters: u32, secs: f64, lean: f64) {
    let sk = BuiltinSkeleton::Humanoid.load();
    let sk = sk
        .with_actuation(Actuation {
            mode,
            gain_scale: g,
            torque_limit_rad: 1.0,
            brake_rad_s: std::env::var("BRAKE").map(|s| s.parse().unwrap()).unwrap_or(4.0),
        })
        .unwrap();
    let mut s = WorldSettings::thesis();
    s.dt = dt;
    s.substeps = substeps;
    s.solver.iterations = iters;
    s.solver.pgs_iterations = std::env::var("PGS").map(|x| x.parse().unwrap()).unwrap_or(1);
    let mut w = World::new(s).unwrap();
    let m = w.add_model(&sk, Placement::OnGround { dx: 0.0 }).unwrap();
    let mut pose = vec![0.0; sk.n_actuators()];
    pose[sk.actuator_index("ankle_l").unwrap()] = lean;
    pose[sk.actuator_index("ankle_r").unwrap()] = lean;
    w.commands_mut(m).unwrap().hold(&pose).unwrap();
    let mut sens = Sensors::new(&w, m).unwrap();
    let n = (secs / dt).round() as u64;
    let t0 = Instant::now();
    let mut min_head = f64::INFINITY;
    let mut err = None;
    for _ in 0..n {
        if let Err(e) = w.step() {
            err = Some(e);
            break;
        }
        w.sense(&mut sens).unwrap();
        min_head = min_head.min(sens.body_position[0][1]);
        if std::env::var("TRACE").is_ok()
            && (w.steps()
                % ((std::env::var("EVERY").map(|s| s.parse::<f64>().unwrap()).unwrap_or(0.5) / dt) as u64)
                == 0
                || (std::env::var("EARLY").is_ok() && w.steps() < 12))
        {
            println!(
                "  t {:.2} head {:.3} com_x {:.4} ankle {:.4} {:.4} knee {:.4} hip {:.4} foot_ang {:.4} on_ground {:?} tau {:?}",
                sens.time,
                sens.body_position[0][1],
                sens.com[0],
                sens.joint_angle[5],
                sens.joint_angle[8],
                sens.joint_angle[4],
                sens.joint_angle[3],
                sens.body_angle[6],
                sens.support,
                sens.actuator_torque.iter().map(|x| x.round()).collect::<Vec<_>>()
            );
        }
    }
    let el = t0.elapsed().as_secs_f64();
    w.sense(&mut sens).unwrap();
    println!(
        "{mode:?} G={g} dt={dt} sub={substeps} it={iters}: {:.0} steps/s, head_min {:.3} head {:.3} pelvis ({:.3},{:.3}) com_x {:.4} max|q| {:.3} {:?}",
        w.steps() as f64 / el,
        min_head,
        sens.body_position[0][1],
        sens.body_position[3][0],
        sens.body_position[3][1],
        sens.com[0],
        sens.joint_angle.iter().fold(0.0f64, |a, b| a.max(b.abs())),
        err.map(|e| e.to_string())
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let g: f64 = args.get(1).map(|s| s.parse().unwrap()).unwrap_or(100.0);
    let dt: f64 = args.get(2).map(|s| s.parse().unwrap()).unwrap_or(0.05);
    let sub: u32 = args.get(3).map(|s| s.parse().unwrap()).unwrap_or(1);
    let it: u32 = args.get(4).map(|s| s.parse().unwrap()).unwrap_or(4);
    let secs: f64 = args.get(5).map(|s| s.parse().unwrap()).unwrap_or(60.0);
    let modes: Vec<PdMode> = match args.get(6).map(|s| s.as_str()) {
        Some("b") => vec![PdMode::OdeBrake],
        Some("a") => vec![PdMode::Explicit],
        Some("c") => vec![PdMode::ImplicitMotor],
        Some("s") => vec![PdMode::ImplicitSpring],
        Some("d") => vec![PdMode::StablePd],
        _ => vec![
            PdMode::Explicit,
            PdMode::OdeBrake,
            PdMode::ImplicitMotor,
            PdMode::ImplicitSpring,
            PdMode::StablePd,
        ],
    };
    for mode in modes {
        run(mode, g, dt, sub, it, secs, args.get(7).map(|s| s.parse().unwrap()).unwrap_or(0.0));
    }
}
