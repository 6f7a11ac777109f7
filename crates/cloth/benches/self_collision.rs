//! One step of a 64 × 64 free sheet lying folded onto itself (dropped upright onto a sphere on a
//! floor, 0.75 s earlier), generalised-α at 1/240 s with the contacts in its solve, with and without
//! the self-collision response. The example `self_collision_cost` times the two alternately and
//! splits the response's time by stage.

use anima_cloth::contact_mode::ContactMode;
use anima_cloth::network_sim::{Collider, NetworkSim};
use anima_cloth::self_collision::SelfCollision;
use anima_cloth::spring_net::SheetSpec;
use anima_geom::DVec3;
use anima_ode::Integrator;
use criterion::{Criterion, criterion_group, criterion_main};

fn folding_sheet(n: usize, x: Option<(&[DVec3], &[DVec3])>, self_collision: bool) -> NetworkSim {
    let spec = SheetSpec { pinned: vec![], height: 1.0, ..SheetSpec::standard(n) };
    let start = match x {
        Some((x, _)) => x.to_vec(),
        None => spec.positions().iter().map(|p| DVec3::new(p.x, 0.5 + 0.1 * p.y, 0.65 + p.y)).collect(),
    };
    let mut sim =
        NetworkSim::new(spec.build().unwrap(), start, Integrator::GeneralizedAlpha, 1.0 / 240.0).unwrap();
    sim.colliders = vec![
        Collider::Sphere { centre: DVec3::new(0.5, 0.45, 0.3), radius: 0.3 },
        Collider::Plane { point: DVec3::ZERO, normal: DVec3::Z },
    ];
    sim.friction = 0.3;
    sim.contact = ContactMode::InSolve;
    match x {
        Some((_, v)) => sim.state.v.copy_from_slice(v),
        None => sim.state.v.fill(DVec3::new(0.0, 0.3, 0.0)),
    }
    if self_collision {
        sim.enable_self_collision(SelfCollision::default(), spec.triangles());
    }
    sim
}

fn bench(c: &mut Criterion) {
    let n = 64;
    let mut folding = folding_sheet(n, None, true);
    folding.run(180).expect("the fold");
    let state = (folding.state.x.clone(), folding.state.v.clone());
    let mut group = c.benchmark_group("self_collision_step");
    group.sample_size(20);
    for (label, on) in [("off", false), ("on", true)] {
        let mut sim = folding_sheet(n, Some((&state.0, &state.1)), on);
        group.bench_function(format!("{label}/{n}x{n}-folded"), |b| b.iter(|| sim.run(1).expect("a step")));
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
