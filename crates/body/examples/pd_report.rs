//! Measures what `docs/body.md` reports: the largest stable kp of each PD mode against the step on a
//! single hinge and on the foot, and the standing humanoid's speed and drift under each set-up.
//!
//! `cargo run --release -p anima-body --example pd_report` prints the markdown tables (a few minutes).

use std::time::Instant;

use anima_body::{
    Actuation, BuiltinSkeleton, PdMode, Placement, Sensors, Signal, Skeleton, World, WorldSettings,
};

const MODES: [PdMode; 5] =
    [PdMode::Explicit, PdMode::OdeBrake, PdMode::ImplicitMotor, PdMode::ImplicitSpring, PdMode::StablePd];

/// A fixed base and one link hinged to it. `link` is (width, height, mass, centre offset from the
/// hinge).
fn bench_skeleton(mode: PdMode, kp: f64, link: (f64, f64, f64, (f64, f64))) -> Skeleton {
    let (w, h, m, (dx, dy)) = link;
    let text = format!(
        r#"Skeleton(name: "bench", depth: 0.1,
          bodies: [
            Body(name: "base", shape: Box(width: 0.1, height: 0.4), mass: 4.16, centre: (0.0, 0.2), fixed: true),
            Body(name: "link", shape: Box(width: {w}, height: {h}), mass: {m}, centre: ({dx}, {y})),
          ],
          joints: [ Joint(name: "hinge", kind: Hinge, parent: "base", child: "link", anchor: (0.0, 0.0)) ],
          actuators: [ Actuator(name: "hinge", number: 1, drives: Joint("hinge"), kp: {kp}, kd: {kd}, max_torque: Some(1e12)) ],
          actuation: Actuation(mode: {mode:?}, gain_scale: 1.0, torque_limit_rad: 1.0, brake_rad_s: 1.0),
        )"#,
        y = dy,
        kd = kp / 30.0,
    );
    Skeleton::from_ron_str(&text).expect("valid bench skeleton")
}

/// Step response to a 0.1 rad target over four natural periods 2π√(I/kp) (300 to 20 000 steps):
/// stable when it never strays 1 rad from the target, never diverges, and its error in the last
/// quarter of the run is no larger than in the first.
fn stable(mode: PdMode, kp: f64, dt: f64, link: (f64, f64, f64, (f64, f64))) -> bool {
    let sk = bench_skeleton(mode, kp, link);
    let mut s = WorldSettings { dt, gravity: 0.0, ground: None, ..WorldSettings::thesis() };
    s.solver.iterations = 1;
    let mut world = World::new(s).expect("settings");
    let m = world.add_model(&sk, Placement::Offset { dx: 0.0, dy: 0.0 }).expect("model");
    world.commands_mut(m).expect("model").push(Signal::angle(0, 0.1)).expect("signal");
    let mut sensors = Sensors::new(&world, m).expect("sensors");
    let inertia = inertia_of(link);
    let period = std::f64::consts::TAU * (inertia / kp).sqrt();
    let n = ((4.0 * period / dt).round() as usize).clamp(300, 20_000);
    let (mut first, mut last) = (0.0f64, 0.0f64);
    for k in 0..n {
        if world.step().is_err() {
            return false;
        }
        world.sense(&mut sensors).expect("sense");
        let err = (sensors.joint_angle[0] - 0.1).abs();
        if err > 1.0 {
            return false;
        }
        if k < n / 4 {
            first = first.max(err);
        } else if k >= 3 * n / 4 {
            last = last.max(err);
        }
    }
    last <= first * 1.0001 + 1e-9
}

fn inertia_of(link: (f64, f64, f64, (f64, f64))) -> f64 {
    let (w, h, m, (dx, dy)) = link;
    m * (w * w + h * h) / 12.0 + m * (dx * dx + dy * dy)
}

/// Largest stable kp in [1, 1e9] by bisection on log kp (assumes stability below a threshold).
fn largest_stable_kp(mode: PdMode, dt: f64, link: (f64, f64, f64, (f64, f64))) -> f64 {
    let (mut lo, mut hi) = (1f64.ln(), 1e9f64.ln());
    if stable(mode, hi.exp(), dt, link) {
        return f64::INFINITY;
    }
    if !stable(mode, lo.exp(), dt, link) {
        return 0.0;
    }
    for _ in 0..18 {
        let mid = 0.5 * (lo + hi);
        if stable(mode, mid.exp(), dt, link) { lo = mid } else { hi = mid }
    }
    lo.exp()
}

fn fmt_kp(kp: f64) -> String {
    if kp.is_infinite() {
        "> 1e9".into()
    } else if kp == 0.0 {
        "< 1".into()
    } else {
        format!("{kp:.3e}")
    }
}

fn stability_tables() {
    // The single hinge: a 2 kg, 0.1 × 0.5 m link hinged at its top end; the foot: Table 6.1's foot
    // (1.2 kg, 0.25 × 0.1 m) hinged at the ankle, its centre 0.06 m forward and 0.05 m below.
    let systems =
        [("single hinge", (0.1, 0.5, 2.0, (0.0, -0.25))), ("foot", (0.25, 0.1, 1.2, (0.06, -0.05)))];
    let dts = [0.05, 0.02, 0.01, 1.0 / 120.0, 0.005, 0.001];
    for (name, link) in systems {
        let inertia = inertia_of(link);
        println!("\n#### {name} (I = {inertia:.5} kg·m² about the hinge, kd = kp/30)\n");
        print!("| Δt (s) | explicit bound |");
        for mode in MODES {
            print!(" {mode:?} |");
        }
        println!();
        println!("|---|---|{}", "---|".repeat(MODES.len()));
        for dt in dts {
            // kp·Δt²/I + 2·kd·Δt/I < 4 with kd = kp/30.
            let bound = 4.0 * inertia / (dt * dt + dt / 15.0);
            print!("| {dt:.4} | {} |", fmt_kp(bound));
            for mode in MODES {
                print!(" {} |", fmt_kp(largest_stable_kp(mode, dt, link)));
            }
            println!();
        }
    }
}

struct Stance {
    label: &'static str,
    mode: PdMode,
    dt: f64,
    substeps: u32,
    iterations: u32,
    pgs: u32,
    sleeping: bool,
}

/// The stance table's name of a mode.
fn label_of(mode: PdMode) -> &'static str {
    match mode {
        PdMode::ImplicitSpring => "implicit spring",
        PdMode::OdeBrake => "ODE-style brake",
        PdMode::StablePd => "stable PD",
        PdMode::ImplicitMotor => "implicit motor",
        PdMode::Explicit => "explicit",
    }
}

fn stance_table() {
    // (mode, Δt, physics sub-steps, Rapier sub-steps, PGS sweeps, sleeping)
    let rows = [
        (PdMode::ImplicitSpring, 0.05, 1, 1, 1, false),
        (PdMode::ImplicitSpring, 0.05, 1, 4, 1, false),
        (PdMode::ImplicitSpring, 0.05, 1, 1, 1, true),
        (PdMode::ImplicitSpring, 1.0 / 120.0, 1, 1, 1, false),
        (PdMode::ImplicitSpring, 1.0 / 120.0, 1, 4, 1, false),
        (PdMode::ImplicitSpring, 0.001, 1, 1, 1, false),
        (PdMode::OdeBrake, 0.05, 10, 1, 8, false),
        (PdMode::OdeBrake, 0.05, 10, 1, 1, false),
        (PdMode::OdeBrake, 0.05, 1, 1, 8, false),
        (PdMode::StablePd, 0.05, 3, 1, 1, false),
        (PdMode::StablePd, 0.05, 1, 1, 1, false),
        (PdMode::StablePd, 0.001, 1, 1, 1, false),
        (PdMode::ImplicitMotor, 0.05, 1, 4, 1, false),
        (PdMode::ImplicitMotor, 0.05, 1, 16, 1, false),
        (PdMode::ImplicitMotor, 0.001, 1, 1, 1, false),
        (PdMode::Explicit, 0.05, 50, 1, 1, false),
        (PdMode::Explicit, 0.001, 1, 1, 1, false),
    ]
    .map(|(mode, dt, substeps, iterations, pgs, sleeping)| Stance {
        label: label_of(mode),
        mode,
        dt,
        substeps,
        iterations,
        pgs,
        sleeping,
    });
    println!(
        "\n| mode | Δt (s) | physics sub-steps | Rapier sub-steps | PGS sweeps | sleeping | steps/s | stands 60 s | lowest head (m) | COM drift (m) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let brake_rad_s = if r.mode == PdMode::OdeBrake { 1.0 } else { 4.0 };
        let sk = BuiltinSkeleton::Humanoid
            .load()
            .with_actuation(Actuation { mode: r.mode, gain_scale: 100.0, torque_limit_rad: 1.0, brake_rad_s })
            .expect("actuation");
        let mut s = WorldSettings { dt: r.dt, substeps: r.substeps, ..WorldSettings::thesis() };
        s.solver.iterations = r.iterations;
        s.solver.pgs_iterations = r.pgs;
        s.solver.sleeping = r.sleeping;
        let mut world = World::new(s).expect("settings");
        let m = world.add_model(&sk, Placement::OnGround { dx: 0.0 }).expect("model");
        world.commands_mut(m).expect("model").hold(&[0.0; 14]).expect("pose");
        let mut sensors = Sensors::new(&world, m).expect("sensors");
        world.sense(&mut sensors).expect("sense");
        let com0 = sensors.com[0];
        let head = sk.body_index("head").expect("head");
        let n = (60.0 / r.dt).round() as usize;
        let (mut lowest, mut drift, mut ok, mut wall) = (f64::INFINITY, 0.0f64, true, 0.0);
        for _ in 0..n {
            let t0 = Instant::now();
            let stepped = world.step();
            wall += t0.elapsed().as_secs_f64();
            if stepped.is_err() {
                ok = false;
                break;
            }
            world.sense(&mut sensors).expect("sense");
            lowest = lowest.min(sensors.body_position[head][1]);
            drift = drift.max((sensors.com[0] - com0).abs());
        }
        let stands = ok && lowest > 1.5;
        println!(
            "| {} | {:.4} | {} | {} | {} | {} | {:.0} | {} | {} | {} |",
            r.label,
            r.dt,
            r.substeps,
            r.iterations,
            r.pgs,
            if r.sleeping { "yes" } else { "no" },
            world.steps() as f64 / wall,
            if stands { "yes" } else { "no" },
            if ok { format!("{lowest:.3}") } else { "diverged".into() },
            if ok { format!("{drift:.4}") } else { "—".into() },
        );
    }
}

fn main() {
    let which = std::env::args().nth(1).unwrap_or_default();
    if which.is_empty() || which == "stability" {
        stability_tables();
    }
    if which.is_empty() || which == "stance" {
        stance_table();
    }
}
