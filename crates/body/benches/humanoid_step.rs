//! Physics steps per second for one thesis humanoid standing under PD on the ground, single-threaded:
//! the recommended set-up (implicit springs, one Rapier sub-step) at Δt = 0.05 s, 1/120 s and
//! 1/1000 s, and what other modes and solver settings cost. Throughput is reported as steps.

use anima_body::{Actuation, BuiltinSkeleton, PdMode, Placement, World, WorldSettings};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

fn standing(mode: PdMode, dt: f64, substeps: u32, iterations: u32, pgs: u32, sleeping: bool) -> World {
    let brake_rad_s = if mode == PdMode::OdeBrake { 1.0 } else { 4.0 };
    let sk = BuiltinSkeleton::Humanoid
        .load()
        .with_actuation(Actuation { mode, gain_scale: 100.0, torque_limit_rad: 1.0, brake_rad_s })
        .expect("valid actuation");
    let mut s = WorldSettings { dt, substeps, ..WorldSettings::thesis() };
    s.solver.iterations = iterations;
    s.solver.pgs_iterations = pgs;
    s.solver.sleeping = sleeping;
    let mut world = World::new(s).expect("valid settings");
    let m = world.add_model(&sk, Placement::OnGround { dx: 0.0 }).expect("model");
    world.commands_mut(m).expect("model").hold(&[0.0; 14]).expect("pose");
    // Settle onto the ground first: a second of simulated time.
    for _ in 0..(1.0 / dt).round() as usize {
        world.step().expect("stands");
    }
    world
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("humanoid_step");
    group.throughput(Throughput::Elements(1));
    for (label, dt) in [("0.05", 0.05), ("1/120", 1.0 / 120.0), ("1/1000", 0.001)] {
        let mut w = standing(PdMode::ImplicitSpring, dt, 1, 1, 1, false);
        group.bench_function(BenchmarkId::new("implicit-spring", label), |b| {
            b.iter(|| w.step().expect("finite"))
        });
    }
    let variants = [
        ("implicit-spring, 4 Rapier sub-steps", PdMode::ImplicitSpring, 1, 4, 1, false),
        ("implicit-spring, sleeping", PdMode::ImplicitSpring, 1, 1, 1, true),
        ("ode-brake, 10 sub-steps, 8 PGS", PdMode::OdeBrake, 10, 1, 8, false),
        ("stable-pd, 3 sub-steps", PdMode::StablePd, 3, 1, 1, false),
        ("implicit-motor, 4 Rapier sub-steps", PdMode::ImplicitMotor, 1, 4, 1, false),
    ];
    for (label, mode, substeps, iterations, pgs, sleeping) in variants {
        let mut w = standing(mode, 0.05, substeps, iterations, pgs, sleeping);
        group.bench_function(BenchmarkId::new(label, "0.05"), |b| {
            b.iter(|| {
                // A fallen figure still steps; the implicit motor falls at this step (docs/body.md).
                let _ = w.step();
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
