//! Issue #18's target speeds: walkers searched to walk at 0.5, 1.0 and 1.5 m/s on the flat, scored by
//! how closely they keep the speed, not by distance, with flight phases penalised. (The protocol's
//! walker, `walk-protocol.ron`, was searched for 1.0 m/s on every terrain, without a flight penalty.)
//!
//! `cargo xtask reproduce nunes-speeds` runs CMA-ES over the thesis's twelve leg-pose numbers from
//! `walk-protocol.ron`'s, on [`speed_score`], for each target from several seeds, commits each
//! target's winner to `assets/controllers/walk-speed-<v>.ron` and writes
//! `docs/reproduction/nunes-speeds.md`.

use std::fmt::Write as _;

use anima_body::{Relief, Support};
use anima_control::Controller;
use anyhow::Result;

use super::optimisers::{cmaes_search, walker_poses, with_poses};
use super::protocol::{self, MINUTE, SCORE_ITERATIONS, SCORE_PUSH, SPEED_WEIGHT, credit_at, humanoid};
use crate::nunes::{self, Push};
use crate::repo::Repo;

/// The speeds searched for, m/s.
pub const TARGETS: [f64; 3] = [0.5, 1.0, 1.5];

/// Weight of the fraction of a walk's control steps spent with neither foot on the ground: a walk
/// that is half flight costs as much as a whole walk's credit. Walking has no flight phase; a fast
/// walker that hops or runs is not what the target asks for.
pub const FLIGHT_WEIGHT: f64 = 2.0;

/// A walk on the flat of `iterations` control steps under `pushes`: (fraction walked before any fall,
/// distance, fraction of the steps walked with neither foot on the ground).
pub fn walk_with_flight(c: &Controller, iterations: u64, pushes: &[Push]) -> (f64, f64, f64) {
    let (mut walked, mut airborne) = (0u64, 0u64);
    let (fraction, distance) = protocol::walk_observed(c, humanoid, Relief::Flat, iterations, pushes, |ch| {
        walked += 1;
        airborne += u64::from(ch.env.sensors[0].support == Support::None);
    });
    (fraction, distance, airborne as f64 / walked.max(1) as f64)
}

/// The speed search's objective (at most 3): three 30 s walks on the flat — unpushed, and after torso
/// pushes of 70 N·s forward and backward 15 s in — each earning the fraction walked before any fall
/// times its progress (the distance over half of what `target` covers, at most 1); less
/// 4 × |v − target| (v the unpushed walk's mean speed) and [`FLIGHT_WEIGHT`] times each walk's
/// fraction of steps in flight. Nothing is drawn: every candidate sees the same walks.
pub fn speed_score(c: &Controller, target: f64) -> f64 {
    let t = SCORE_ITERATIONS;
    let seconds = t as f64 * nunes::DT;
    let (fraction, distance, flight) = walk_with_flight(c, t, &[]);
    let speed = distance / seconds;
    let mut total = credit_at((fraction, distance), target) - SPEED_WEIGHT * (speed - target).abs();
    total -= FLIGHT_WEIGHT * flight;
    for impulse in [SCORE_PUSH, -SCORE_PUSH] {
        let (fraction, distance, flight) = walk_with_flight(c, t, &[Push::torso(impulse, t / 2, 4)]);
        total += credit_at((fraction, distance), target) - FLIGHT_WEIGHT * flight;
    }
    total
}

/// What the report measures of a walker: over a minute on the flat, the fraction walked, the mean
/// speed and the fraction of steps in flight; the largest torso pushes survived each way (N·s, steps
/// of 5 up to 400).
#[derive(Debug, Clone, Copy)]
pub struct SpeedMeasures {
    pub fraction: f64,
    pub speed: f64,
    pub flight: f64,
    pub pushes: (f64, f64),
}

/// Measures `c`.
pub fn measure(c: &Controller) -> SpeedMeasures {
    let (fraction, distance, flight) = walk_with_flight(c, MINUTE, &[]);
    SpeedMeasures {
        fraction,
        speed: distance / 60.0,
        flight,
        pushes: (
            protocol::largest_torso_push(c, humanoid, 1.0, 5.0, 400.0),
            protocol::largest_torso_push(c, humanoid, -1.0, 5.0, 400.0),
        ),
    }
}

/// The file a target's walker is committed to, e.g. `walk-speed-0.5` (without `.ron`).
pub fn walker_name(target: f64) -> String {
    format!("walk-speed-{target:.1}")
}

/// CMA-ES evaluations of each speed search.
const BUDGET: usize = 300;

/// A row of the report's table.
fn row(label: &str, target: f64, score: f64, m: &SpeedMeasures) -> String {
    let up =
        if m.fraction >= 1.0 { "yes".to_string() } else { format!("falls at {:.1} s", m.fraction * 60.0) };
    format!(
        "| {label} | {target:.1} | {score:.3} | {up} | {:.2} | {:.2} | {:.1} % | {:.0} / {:.0} |",
        m.speed,
        (m.speed - target).abs(),
        100.0 * m.flight,
        m.pushes.0,
        m.pushes.1
    )
}

/// `reproduce nunes-speeds [--seeds N]`: for each of [`TARGETS`], CMA-ES over the twelve leg-pose
/// numbers from `walk-protocol.ron`'s on [`speed_score`], from `seeds` seeds; each winner measured as
/// it is written (its RON read back). Per target, the winner closest to its speed among those that
/// stay up for the minute (then the best score) is committed.
pub fn reproduce(repo: &Repo, seeds: usize) -> Result<()> {
    let seeds = seeds.max(1) as u64;
    let first = nunes::report::SEED;
    let start = nunes::controller("walk-protocol")?;
    let x0 = walker_poses(&start);
    let mut table = Vec::new();
    eprintln!("anima-lab: measuring walk-protocol.ron …");
    let protocol_measures = measure(&start);
    let mut committed = Vec::new();
    for target in TARGETS {
        let objective = |x: &[f64]| speed_score(&with_poses(&start, x), target);
        let start_score = objective(&x0);
        table.push(row(
            &format!("walk-protocol.ron, scored for {target:.1} m/s (the start)"),
            target,
            start_score,
            &protocol_measures,
        ));
        let mut found = Vec::new();
        for seed in first..first + seeds {
            let (x, score, _) = cmaes_search(
                &format!("speed {target:.1} m/s, seed {seed}"),
                nunes::walk_poses::space(),
                x0.clone(),
                &objective,
                seed,
                BUDGET,
            )?;
            let ron = with_poses(&start, &x).to_ron();
            eprintln!("anima-lab: measuring {target:.1} m/s, seed {seed} …");
            let m = measure(&nunes::parse(&ron)?);
            table.push(row(&format!("searched, seed {seed}"), target, score, &m));
            found.push((seed, score, ron, m));
        }
        let best = found
            .iter()
            .max_by(|a, b| {
                let key = |f: &(u64, f64, String, SpeedMeasures)| {
                    (f.3.fraction >= 1.0, -(f.3.speed - target).abs(), f.1)
                };
                key(a).partial_cmp(&key(b)).unwrap_or(std::cmp::Ordering::Equal)
            })
            .expect("at least one search");
        let name = walker_name(target);
        repo.write_text(
            format!("assets/controllers/{name}.ron"),
            &format!(
                "// Written by `cargo xtask reproduce nunes-speeds`: walk-protocol.ron's machines with their twelve\n\
                 // leg-pose numbers found by CMA-ES on anima_lab::nunes::speeds::speed_score for {target:.1} m/s\n\
                 // (seed {}): of {seeds} seeds, the winner that stays up closest to the speed.\n{}",
                best.0, best.2
            ),
        )?;
        committed.push((target, best.0, best.3));
    }
    let mut doc = String::from(
        "# Target speeds: walkers searched to keep a speed\n\n_Generated by `cargo xtask reproduce nunes-speeds`; \
         do not edit._\n\n",
    );
    let _ = writeln!(
        doc,
        "Issue #18 asks for target speeds of 0.5, 1.0 and 1.5 m/s, scored by how closely the speed is kept (not by \
         distance), with flight phases penalised. The protocol's walker (`walk-protocol.ron`, `nunes-protocol.md`) \
         keeps 1.0 m/s on every terrain, but its search did not penalise flight. For each target speed, CMA-ES \
         (σ₀ = 0.1 of each interval, no restarts, about {BUDGET} evaluations) searched the twelve leg-pose numbers of its machines from its own, from seeds {first} to {}, \
         maximising `anima_lab::nunes::speeds::speed_score` (at most 3): three 30 s walks on the flat — unpushed, \
         and after torso pushes of 70 N·s forward and backward 15 s in — each earning the fraction walked before any \
         fall times its progress (its distance over half of what the target speed covers, at most 1), less \
         {SPEED_WEIGHT} × |v − target| for the unpushed walk's mean speed v and {FLIGHT_WEIGHT} × the fraction of \
         each walk's control steps with neither foot on the ground.\n\n\
         Each walker is measured as it is written: a minute on the flat (still up, mean speed, its error, the share \
         of steps in flight) and the largest torso pushes survived (5 N·s steps up to 400, 20 s in, still up 10 s \
         later).\n",
        first + seeds - 1
    );
    doc.push_str(
        "| walker | target (m/s) | score | up after 60 s | speed (m/s) | speed error (m/s) | steps in flight | torso push forward / backward (N·s) |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for r in &table {
        doc.push_str(r);
        doc.push('\n');
    }
    doc.push_str("\nCommitted:\n\n");
    for (target, seed, m) in &committed {
        let ok = m.fraction >= 1.0 && (m.speed - target).abs() <= 0.1;
        let _ = writeln!(
            doc,
            "- {} `assets/controllers/{}.ron` (seed {seed}): {:.2} m/s for a target of {target:.1} (error {:.2}; within \
             ± 0.1 and up for the minute: {}), {:.1} % of steps in flight.",
            if ok { "✓" } else { "✗" },
            walker_name(*target),
            m.speed,
            (m.speed - target).abs(),
            if ok { "yes" } else { "no" },
            100.0 * m.flight
        );
    }
    repo.write_text("docs/reproduction/nunes-speeds.md", &doc)?;
    print!("{doc}");
    Ok(())
}
