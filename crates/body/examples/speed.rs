use anima_body::*;
use std::time::Instant;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let mode = match a[1].as_str() {
        "b" => PdMode::OdeBrake,
        "s" => PdMode::ImplicitSpring,
        "d" => PdMode::StablePd,
        "c" => PdMode::ImplicitMotor,
        _ => PdMode::Explicit,
    };
    let dt: f64 = a[2].parse().unwrap();
    let sub: u32 = a[3].parse().unwrap();
    let it: u32 = a[4].parse().unwrap();
    let pgs: u32 = a[5].parse().unwrap();
    let sk = BuiltinSkeleton::Humanoid
        .load()
        .with_actuation(Actuation { mode, gain_scale: 100.0, torque_limit_rad: 1.0, brake_rad_s: 1.0 })
        .unwrap();
    let mut s = WorldSettings::thesis();
    s.dt = dt;
    s.substeps = sub;
    s.solver.iterations = it;
    s.solver.pgs_iterations = pgs;
    let mut w = World::new(s).unwrap();
    let m = w.add_model(&sk, Placement::OnGround { dx: 0.0 }).unwrap();
    w.commands_mut(m).unwrap().hold(&vec![0.0; 14]).unwrap();
    for _ in 0..((1.0 / dt) as usize) {
        w.step().unwrap();
    }
    let n = 4000;
    let t0 = Instant::now();
    for _ in 0..n {
        w.step().unwrap();
    }
    let el = t0.elapsed().as_secs_f64();
    let mut sens = Sensors::new(&w, m).unwrap();
    w.sense(&mut sens).unwrap();
    println!(
        "{mode:?} dt={dt} sub={sub} it={it} pgs={pgs}: {:.0} steps/s  head {:.3} com_x {:.4}",
        n as f64 / el,
        sens.body_position[0][1],
        sens.com[0]
    );
}
