//! What self-collision costs: a free N × N standard sheet (N = 64 unless given) dropped upright, edge
//! first, onto a sphere on a floor, so that it folds onto itself, run by generalised-α at 1/240 s with the contacts in
//! the solve, with and without the self-collision response. Prints the mean wall time of a step over
//! the last second of a 1.5 s run (the folded part), the response's stats and the crossings at the end.
//!
//! ```sh
//! cargo run --release -p anima-cloth --example self_collision_cost -- 64
//! ```

use std::time::Instant;

use anima_cloth::contact_mode::ContactMode;
use anima_cloth::network_sim::{Collider, NetworkSim};
use anima_cloth::self_collision::SelfCollision;
use anima_cloth::spring_net::SheetSpec;
use anima_geom::{DVec3, count_self_intersections};
use anima_ode::Integrator;

fn folding_sheet(n: usize, self_collision: bool) -> NetworkSim {
    let spec = SheetSpec { pinned: vec![], height: 1.0, ..SheetSpec::standard(n) };
    // Nearly upright (leaning 0.1 m over its height), its lower edge 5 cm above the sphere's top.
    let x = spec.positions().iter().map(|p| DVec3::new(p.x, 0.5 + 0.1 * p.y, 0.65 + p.y)).collect();
    let mut sim = NetworkSim::new(spec.build(), x, Integrator::GeneralizedAlpha, 1.0 / 240.0);
    sim.colliders = vec![
        Collider::Sphere { centre: DVec3::new(0.5, 0.45, 0.3), radius: 0.3 },
        Collider::Plane { point: DVec3::ZERO, normal: DVec3::Z },
    ];
    sim.friction = 0.3;
    sim.contact = ContactMode::InSolve;
    sim.state.v.fill(DVec3::new(0.0, 0.3, 0.0));
    if self_collision {
        sim.enable_self_collision(SelfCollision::default(), spec.triangles());
    } else {
        // The triangles only, for counting crossings.
        sim.enable_self_collision(SelfCollision::default(), spec.triangles());
        sim.self_collision = None;
    }
    sim
}

fn main() {
    let n: usize = std::env::args().nth(1).map_or(64, |a| a.parse().expect("N, particles per side"));
    println!("| self-collision | ms/step (last 1 s) | crossings at the end | stats |");
    println!("|---|---|---|---|");
    for on in [false, true] {
        let mut sim = folding_sheet(n, on);
        sim.run(120).expect("the first 0.5 s");
        let before = sim.self_collision_total;
        let started = Instant::now();
        sim.run(240).expect("the last second");
        let ms = started.elapsed().as_secs_f64() * 1e3 / 240.0;
        let crossings = count_self_intersections(&sim.state.x, sim.triangles());
        let mut stats = sim.self_collision_total;
        stats.repulsions -= before.repulsions;
        stats.impacts -= before.impacts;
        stats.zones -= before.zones;
        println!("| {on} | {ms:.2} | {crossings} | {stats:?} |");
    }
}
