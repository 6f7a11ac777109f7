//! One FLEX3D step of an n×n surface (springs on every edge and diagonal, gravity, literal friction,
//! top row pinned), forward Euler, with and without the collision pass.

use anima_cloth::flex3d::{
    FLEX3D_GRAVITY, Flex3dScene, Flex3dWorld, Friction, FrictionMode, ModelOptions, SurfaceDesc,
};
use anima_geom::DVec3;
use anima_ode::Integrator;
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};

fn sheet(n: usize, collisions: bool, integrator: Integrator) -> Flex3dWorld {
    let scene = Flex3dScene {
        duration_s: 1.0,
        frame_rate_hz: 1.0,
        dt_s: 0.001,
        gravity_m_s2: FLEX3D_GRAVITY,
        external_force_n: DVec3::ZERO,
        friction: Friction { mode: FrictionMode::Literal, coefficient: 0.5 },
        objects: vec![],
        integrator,
        options: ModelOptions { collisions, ..ModelOptions::thesis() },
        surfaces: vec![SurfaceDesc {
            name: "sheet".into(),
            rows: n,
            cols: n,
            spacing_m: 1.0,
            centre_m: DVec3::ZERO,
            normal: DVec3::Z,
            particle_mass_kg: 0.1,
            stiffness_n_m: [10.0; 3],
            bending_n_m: [0.0; 3],
            fixed: (0..n).map(|j| (0, j)).collect(),
            translations: vec![],
        }],
    };
    let mut world = Flex3dWorld::new(&scene, vec![]).expect("valid scene");
    // Move off the flat rest state so that every spring is stretched and every particle moves.
    world.run_to_step(200).expect("finite");
    world
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("flex3d_step");
    for n in [20usize, 100] {
        group.throughput(Throughput::Elements((n * n) as u64));
        for (label, collisions, integrator) in [
            ("euler", false, Integrator::ForwardEuler),
            ("euler+collisions", true, Integrator::ForwardEuler),
            ("rk4", false, Integrator::Rk4),
        ] {
            let mut world = sheet(n, collisions, integrator);
            group.bench_with_input(BenchmarkId::new(label, format!("{n}x{n}")), &n, |b, _| {
                b.iter(|| world.step().expect("finite"));
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
