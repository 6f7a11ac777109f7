//! What self-collision costs, and where its time goes: a free N × N standard sheet (N = 64 unless
//! given) dropped upright, edge first, onto a sphere on a floor, run with the self-collision response
//! for 0.75 s so that it lies folded onto itself, then stepped on from that state by two simulations,
//! one with the response and one without, timed alternately (rounds of a few steps each, so that both
//! see the same machine load). Generalised-α at 1/240 s with the contacts in its solve. Prints the
//! median and min–max wall time of a step of each, their ratio, and the response's time by stage.
//!
//! ```sh
//! cargo run --release -p anima-cloth --example self_collision_cost -- 64
//! ```
//!
//! The simulation without the response starts from the same folded state but passes through itself
//! from there on; its step costs what a step of the cloth costs without self-collision, which is the
//! denominator wanted.

use std::time::{Duration, Instant};

use anima_cloth::contact_mode::ContactMode;
use anima_cloth::network_sim::{Collider, NetworkSim};
use anima_cloth::self_collision::SelfCollision;
use anima_cloth::spring_net::SheetSpec;
use anima_geom::{DVec3, count_self_intersections};
use anima_ode::Integrator;

const DT: f64 = 1.0 / 240.0;

/// The folding sheet at its start (upright, its lower edge 5 cm above the sphere's top), or at
/// positions and velocities `from`.
fn folding_sheet(n: usize, self_collision: bool, from: Option<(&[DVec3], &[DVec3])>) -> NetworkSim {
    let spec = SheetSpec { pinned: vec![], height: 1.0, ..SheetSpec::standard(n) };
    let x = match from {
        Some((x, _)) => x.to_vec(),
        None => spec.positions().iter().map(|p| DVec3::new(p.x, 0.5 + 0.1 * p.y, 0.65 + p.y)).collect(),
    };
    let mut sim = NetworkSim::new(spec.build().unwrap(), x, Integrator::GeneralizedAlpha, DT).unwrap();
    sim.colliders = vec![
        Collider::Sphere { centre: DVec3::new(0.5, 0.45, 0.3), radius: 0.3 },
        Collider::Plane { point: DVec3::ZERO, normal: DVec3::Z },
    ];
    sim.friction = 0.3;
    sim.contact = ContactMode::InSolve;
    match from {
        Some((_, v)) => sim.state.v.copy_from_slice(v),
        None => sim.state.v.fill(DVec3::new(0.0, 0.3, 0.0)),
    }
    // The triangles are given either way, for counting crossings.
    sim.enable_self_collision(SelfCollision::default(), spec.triangles());
    if !self_collision {
        sim.self_collision = None;
    }
    sim
}

/// Median, smallest and largest, ms.
fn spread(times: &mut [Duration]) -> (f64, f64, f64) {
    times.sort();
    let ms = |d: Duration| d.as_secs_f64() * 1e3;
    (ms(times[times.len() / 2]), ms(times[0]), ms(times[times.len() - 1]))
}

fn main() {
    let n: usize = std::env::args().nth(1).map_or(64, |a| a.parse().expect("N, particles per side"));
    let (rounds, per_round) = (20, 6);
    let mut folding = folding_sheet(n, true, None);
    folding.run(180).expect("the fold");
    let (x, v) = (folding.state.x.clone(), folding.state.v.clone());
    let mut on = folding_sheet(n, true, Some((&x, &v)));
    let mut off = folding_sheet(n, false, Some((&x, &v)));
    on.run(4).expect("warm-up");
    off.run(4).expect("warm-up");
    let before = on.self_collision_total;
    let (mut t_on, mut t_off) = (Vec::new(), Vec::new());
    for _ in 0..rounds {
        for (sim, times) in [(&mut off, &mut t_off), (&mut on, &mut t_on)] {
            for _ in 0..per_round {
                let started = Instant::now();
                sim.run(1).expect("a step");
                times.push(started.elapsed());
            }
        }
    }
    let steps = (rounds * per_round) as f64;
    let total = on.self_collision_total;
    let ms_per_step = |a: Duration, b: Duration| (a - b).as_secs_f64() * 1e3 / steps;
    let (m_off, lo_off, hi_off) = spread(&mut t_off);
    let (m_on, lo_on, hi_on) = spread(&mut t_on);
    println!(
        "{n} × {n} sheet folded onto itself (0.75 s after its drop), generalised-α at 1/240 s, contacts in the solve;"
    );
    println!("{rounds} alternating rounds of {per_round} steps each.\n");
    println!("| self-collision | median ms/step | min–max | crossings at the end |");
    println!("|---|---|---|---|");
    let crossings = |s: &NetworkSim| count_self_intersections(&s.state.x, s.triangles());
    println!("| off | {m_off:.2} | {lo_off:.2}–{hi_off:.2} | {} |", crossings(&off));
    println!("| on | {m_on:.2} | {lo_on:.2}–{hi_on:.2} | {} |", crossings(&on));
    println!("\nratio of medians: {:.2}×\n", m_on / m_off);
    let (t, b) = (total.times, before.times);
    println!("| stage of the response | ms/step |");
    println!("|---|---|");
    println!("| broad phase (every stage) | {:.3} |", ms_per_step(t.broad_phase, b.broad_phase));
    println!("| proximity and repulsion | {:.3} |", ms_per_step(t.proximity, b.proximity));
    println!("| continuous tests and impact impulses | {:.3} |", ms_per_step(t.impacts, b.impacts));
    println!("| impact zones | {:.3} |", ms_per_step(t.zones, b.zones));
    println!("| all of the response | {:.3} |", ms_per_step(t.total(), b.total()));
    println!(
        "\nper step: {:.0} repulsions, {:.1} impacts in {:.2} passes, {:.2} zones",
        (total.repulsions - before.repulsions) as f64 / steps,
        (total.impacts - before.impacts) as f64 / steps,
        (total.impact_iterations - before.impact_iterations) as f64 / steps,
        (total.zones - before.zones) as f64 / steps,
    );
}
