//! Beyond the thesis's search (issue: controllers and optimisation):
//!
//! * `cargo xtask reproduce nunes-optimisers [--seeds N]`: the thesis's staged greedy search, CMA-ES,
//!   random search and simulated annealing, each over N seeds (10 by default), searching the walker's
//!   twelve symmetric leg-pose numbers from the spec's proposal, with which our humanoid falls. Per run:
//!   evaluations until a walk of 10 m in 50 s without a fall, the best walker's distance in a 10-minute
//!   run, and the largest push it survives forward and backward. Writes
//!   `docs/reproduction/nunes-optimisers.md` and a best-fitness-per-evaluation CSV per run under
//!   `target/nunes/`.
//! * `cargo xtask reproduce nunes-robust`: CMA-ES on a robust objective (the mean over six pushes of
//!   ±20 N·s at random times, the same pushes for every candidate: common random numbers) from the
//!   re-authored walker, written to `assets/controllers/walk-robust.ron`, with the same measurements.
//! * `cargo xtask reproduce nunes-simbicon`: the same search for the walker with SIMBICON-style
//!   feedback (`anima_lab::nunes::simbicon`), written to `assets/controllers/walk-simbicon.ron`, and
//!   compared with the thesis's machines.

use std::fmt::Write as _;

use crate::nunes::report::SEED;
use crate::nunes::{self, Push, WalkRules, walk_poses};
use crate::repo::Repo;
use anima_control::Controller;
use anima_control::optimise::{
    Annealing, AnnealingConfig, Cmaes, CmaesConfig, GreedySearch, Interval, Optimiser, RandomSearch, RunLog,
    Stage, run,
};
use anyhow::Result;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Evaluations per optimiser run.
const BUDGET: usize = 100;
/// Iterations of one walking evaluation (50 s, the thesis's 1000).
const WALK_ITERATIONS: u64 = 1000;
/// A completed evaluation (no fall, no stop, all 1000 iterations) scores this plus its distance; one
/// that fails scores its distance before the failure (at least −1 m) plus 5 × the fraction survived.
/// So "walks 10 m in 50 s without falling" is a fitness of at least `COMPLETED + 10`.
const COMPLETED: f64 = 100.0;
/// Iterations of the long run: 10 minutes.
const LONG_ITERATIONS: u64 = 12_000;
/// Pushes: a horizontal force on the head for `PUSH_ITERATIONS` control steps (0.1 s) from
/// iteration `PUSH_AT` (20 s into the walk, in a steady gait); survived when the walker is still up
/// `PUSH_RECOVERY` iterations (10 s) later.
const PUSH_AT: u64 = 400;
const PUSH_ITERATIONS: u64 = 2;
const PUSH_RECOVERY: u64 = 200;
/// Impulses tried, N·s: 2.5, 5, … up to 100; the largest before the first failure is reported.
const PUSH_STEP: f64 = 2.5;
const PUSH_MAX: f64 = 100.0;

/// The shaped walking score (see `COMPLETED`) of `c` under `pushes`.
fn score(c: Controller, pushes: &[Push]) -> f64 {
    match nunes::walk(c, WALK_ITERATIONS, &WalkRules::default(), pushes, |_| ()) {
        Ok(o) if o.iterations == WALK_ITERATIONS && !o.fell && !o.stopped => COMPLETED + o.distance,
        Ok(o) => o.distance.max(-1.0) + 5.0 * o.iterations as f64 / WALK_ITERATIONS as f64,
        Err(_) => -1.0,
    }
}

pub(crate) fn with_poses(base: &Controller, x: &[f64]) -> Controller {
    let mut c = base.clone();
    walk_poses::set(&mut c, x);
    c
}

/// The thesis's walker with the spec's proposed leg poses (it falls within seconds).
pub fn spec_walker() -> Result<Controller> {
    Ok(with_poses(&nunes::controller("walk")?, &walk_poses::SPEC))
}

/// A push of `impulse` N·s (positive forward) on the head.
fn push(impulse: f64, at: u64) -> Push {
    Push::impulse(impulse, at, PUSH_ITERATIONS)
}

fn survives(c: &Controller, impulse: f64) -> bool {
    let rules = WalkRules { window: 0, ..WalkRules::default() };
    nunes::walk(c.clone(), PUSH_AT + PUSH_RECOVERY, &rules, &[push(impulse, PUSH_AT)], |_| ())
        .is_ok_and(|o| !o.fell)
}

/// The largest impulse (N·s, in `direction` ±1) survived before the first failure, in steps of
/// `PUSH_STEP`; 0 when even the first fails (or the walker falls without a push).
fn largest_push(c: &Controller, direction: f64) -> f64 {
    if !survives(c, 0.0) {
        return 0.0;
    }
    let mut j = 0.0;
    while j + PUSH_STEP <= PUSH_MAX && survives(c, direction * (j + PUSH_STEP)) {
        j += PUSH_STEP;
    }
    j
}

/// Distance walked in a 10-minute run, stopping at the first fall, and whether it fell.
fn ten_minutes(c: &Controller) -> (f64, bool) {
    let rules = WalkRules { window: 0, ..WalkRules::default() };
    nunes::walk(c.clone(), LONG_ITERATIONS, &rules, &[], |_| ()).map_or((0.0, true), |o| (o.distance, o.fell))
}

/// What one optimiser run measured.
struct Measured {
    optimiser: &'static str,
    seed: u64,
    evaluations: usize,
    to_ten_metres: Option<usize>,
    best: f64,
    ten_minutes: (f64, bool),
    push: (f64, f64),
}

fn optimiser(kind: usize, seed: u64) -> Result<(&'static str, Box<dyn Optimiser>)> {
    let x0 = walk_poses::SPEC.to_vec();
    let space = walk_poses::space();
    let all: Vec<usize> = (0..x0.len()).collect();
    Ok(match kind {
        0 => (
            "greedy (thesis)",
            Box::new(GreedySearch::new(
                space,
                vec![
                    Stage::global("global", all.clone(), BUDGET / 3),
                    Stage::local_single("single", all, BUDGET - BUDGET / 3, Interval::Fixed),
                ],
                x0,
                seed,
            )?),
        ),
        1 => ("CMA-ES", Box::new(Cmaes::new(space, CmaesConfig::new(x0, 0.2), seed)?)),
        2 => ("random search", Box::new(RandomSearch::new(space, 4, seed)?)),
        _ => (
            "annealing",
            Box::new(Annealing::new(
                space,
                AnnealingConfig { x0, t0: 5.0, cooling: 0.95, step: 0.1, batch: 1 },
                seed,
            )?),
        ),
    })
}

fn csv(log: &RunLog) -> String {
    let mut s = String::from("evaluation,fitness,best\n");
    let mut best = f64::NEG_INFINITY;
    for (k, e) in log.evaluations.iter().enumerate() {
        best = best.max(e.fitness);
        let _ = writeln!(s, "{},{},{}", k + 1, e.fitness, best);
    }
    s
}

fn one_run(repo: &Repo, kind: usize, seed: u64) -> Result<Measured> {
    let base = nunes::controller("walk")?;
    let (name, mut opt) = optimiser(kind, seed)?;
    let objective = |x: &[f64]| score(with_poses(&base, x), &[]);
    let mut log = RunLog::default();
    run(opt.as_mut(), &objective, BUDGET, &mut log)?;
    let dir = repo.cache("nunes/optimisers");
    std::fs::create_dir_all(&dir)?;
    let slug: String = name.chars().filter(char::is_ascii_alphanumeric).collect();
    crate::output::write_atomic(&dir.join(format!("{slug}-seed{seed}.csv")), |w| {
        Ok(w.write_all(csv(&log).as_bytes())?)
    })?;
    let best = log.best().map(|e| (e.x.clone(), e.fitness)).unwrap_or((walk_poses::SPEC.to_vec(), f64::NAN));
    let to_ten_metres = log.evaluations.iter().position(|e| e.fitness >= COMPLETED + 10.0).map(|i| i + 1);
    let winner = with_poses(&base, &best.0);
    let m = Measured {
        optimiser: name,
        seed,
        evaluations: log.len(),
        to_ten_metres,
        best: best.1,
        ten_minutes: ten_minutes(&winner),
        push: (largest_push(&winner, 1.0), largest_push(&winner, -1.0)),
    };
    eprintln!(
        "anima-lab:   {name}, seed {seed}: 10 m after {}, best {:.1}, 10 min {:.0} m{}, pushes +{} / −{} N·s",
        m.to_ten_metres.map_or("never".to_string(), |k| format!("{k} evaluations")),
        m.best,
        m.ten_minutes.0,
        if m.ten_minutes.1 { " (fell)" } else { "" },
        m.push.0,
        m.push.1
    );
    Ok(m)
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}

/// `reproduce nunes-optimisers`.
pub fn optimisers(repo: &Repo, seeds: usize) -> Result<String> {
    let spec = spec_walker()?;
    let before = nunes::walk(spec.clone(), WALK_ITERATIONS, &WalkRules::default(), &[], |_| ())?;
    eprintln!(
        "anima-lab: the spec's walker: {:.2} m in {} iterations{}",
        before.distance,
        before.iterations,
        if before.fell { ", falls" } else { "" }
    );
    let jobs: Vec<(usize, u64)> = (0..4).flat_map(|k| (0..seeds as u64).map(move |s| (k, s))).collect();
    let results: Vec<Measured> = jobs.par_iter().map(|&(k, s)| one_run(repo, k, s)).collect::<Result<_>>()?;
    let mut s = String::new();
    writeln!(s, "# Optimisers compared on the walker\n")?;
    writeln!(
        s,
        "`cargo xtask reproduce nunes-optimisers --seeds {seeds}`. Each optimiser searches the twelve symmetric \
         leg-pose numbers of `anima_lab::nunes::walk_poses` (E1/E3 by swing and stance leg, E4/E6 mirrored) \
         from the spec's §8.1.2 proposal, with which our humanoid falls ({:.2} m, {} of 1000 iterations), for \
         {BUDGET} evaluations per run, seeds 0–{}. The score of an evaluation is {COMPLETED} + the distance for a \
         completed 50 s walk (1000 iterations, no fall, no stop), else the distance before the failure plus 5 × \
         the fraction survived, so every optimiser sees a slope towards walking. Settings: greedy = the thesis's \
         two stages ({} global draws, then one-parameter draws over the whole interval); CMA-ES σ₀ = 0.2 of each \
         interval, default λ; random search in batches of 4; annealing T₀ = 5, cooling 0.95, steps of 0.1 of each \
         interval.\n",
        before.distance,
        before.iterations,
        seeds - 1,
        BUDGET / 3
    )?;
    writeln!(
        s,
        "Measured on the best walker of each run: the distance of a 10-minute run (12 000 iterations, stopped at \
         the first fall) and the largest push survived, forward and backward: a horizontal force on the head for \
         0.1 s from 20 s into the walk, in steps of {PUSH_STEP} N·s up to the first impulse it does not survive \
         (still up 10 s later).\n"
    )?;
    writeln!(
        s,
        "| optimiser | runs reaching 10 m in 50 s | evaluations to 10 m (median of those) | best 50 s distance (median, m) | 10-minute distance (median, m) | runs that walk 10 minutes | push forward (median, N·s) | push backward (median, N·s) |"
    )?;
    writeln!(s, "|---|---|---|---|---|---|---|---|")?;
    for name in ["greedy (thesis)", "CMA-ES", "random search", "annealing"] {
        let rs: Vec<&Measured> = results.iter().filter(|r| r.optimiser == name).collect();
        let reached: Vec<f64> = rs.iter().filter_map(|r| r.to_ten_metres.map(|k| k as f64)).collect();
        let best50 = median(rs.iter().map(|r| (r.best - COMPLETED).max(0.0)).collect());
        writeln!(
            s,
            "| {name} | {} / {} | {} | {:.1} | {:.0} | {} / {} | {:.1} | {:.1} |",
            reached.len(),
            rs.len(),
            if reached.is_empty() { "—".to_string() } else { format!("{:.0}", median(reached.clone())) },
            best50,
            median(rs.iter().map(|r| r.ten_minutes.0).collect()),
            rs.iter().filter(|r| !r.ten_minutes.1).count(),
            rs.len(),
            median(rs.iter().map(|r| r.push.0).collect()),
            median(rs.iter().map(|r| r.push.1).collect()),
        )?;
    }
    writeln!(s, "\nEvery run:\n")?;
    writeln!(
        s,
        "| optimiser | seed | evaluations | to 10 m | best score | 10 minutes (m) | push forward / backward (N·s) |"
    )?;
    writeln!(s, "|---|---|---|---|---|---|---|")?;
    for r in &results {
        writeln!(
            s,
            "| {} | {} | {} | {} | {:.2} | {:.0}{} | {} / {} |",
            r.optimiser,
            r.seed,
            r.evaluations,
            r.to_ten_metres.map_or("never".to_string(), |k| k.to_string()),
            r.best,
            r.ten_minutes.0,
            if r.ten_minutes.1 { " (fell)" } else { "" },
            r.push.0,
            r.push.1
        )?;
    }
    writeln!(
        s,
        "\nThe best-so-far score of every run is in `target/nunes/optimisers/<optimiser>-seed<k>.csv`.\n"
    )?;
    repo.write_text("docs/reproduction/nunes-optimisers.md", &s)?;
    Ok(s)
}

/// The robust objective's pushes: six of ±20 N·s at random times (seeded), the same for every
/// candidate (common random numbers).
const ROBUST_PUSHES: usize = 6;
const ROBUST_IMPULSE: f64 = 20.0;
/// CMA-ES evaluations of a robust run.
const ROBUST_BUDGET: usize = 150;

fn robust_pushes() -> Vec<Push> {
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    (0..ROBUST_PUSHES)
        .map(|k| {
            let at = rng.random_range(200..800);
            push(if k % 2 == 0 { ROBUST_IMPULSE } else { -ROBUST_IMPULSE }, at)
        })
        .collect()
}

/// The mean walking score of `c` over `pushes`, one walk per push.
fn robust_score(c: &Controller, pushes: &[Push]) -> f64 {
    pushes.iter().map(|p| score(c.clone(), std::slice::from_ref(p))).sum::<f64>() / pushes.len() as f64
}

/// The re-authored walker's own twelve pose numbers, read back from `walk.ron` and clamped into
/// [`walk_poses::space`].
pub(crate) fn walker_poses(base: &Controller) -> Vec<f64> {
    walk_poses::get(base)
        .iter()
        .zip(walk_poses::LO.iter().zip(walk_poses::HI))
        .map(|(&x, (&lo, hi))| x.clamp(lo, hi))
        .collect()
}

/// CMA-ES (σ₀ = 0.1 of each interval, no restarts) on the robust objective from `x0`; returns the
/// best point and its score.
fn robust_search(
    name: &str,
    space: anima_control::optimise::Space,
    x0: Vec<f64>,
    objective: &(impl Fn(&[f64]) -> f64 + Sync),
    seed: u64,
) -> Result<(Vec<f64>, f64, usize)> {
    cmaes_search(name, space, x0, objective, seed, ROBUST_BUDGET)
}

/// CMA-ES (σ₀ = 0.1 of each interval, no restarts) maximising `objective` from `x0` for about `budget`
/// evaluations (whole generations), its progress logged; returns the best point, its score and the
/// evaluations made.
pub(crate) fn cmaes_search(
    name: &str,
    space: anima_control::optimise::Space,
    x0: Vec<f64>,
    objective: &(impl Fn(&[f64]) -> f64 + Sync),
    seed: u64,
    budget: usize,
) -> Result<(Vec<f64>, f64, usize)> {
    let f0 = objective(&x0);
    let mut cfg = CmaesConfig::new(x0.clone(), 0.1);
    cfg.restarts = 0;
    let mut opt = Cmaes::new(space, cfg, seed)?;
    let mut log = RunLog::default();
    while log.len() < budget {
        let before = log.len();
        run(&mut opt, objective, before + 1, &mut log)?;
        if log.len() == before {
            break;
        }
        eprintln!(
            "anima-lab:   CMA-ES {name}: {} evaluations, best {:.2}",
            log.len(),
            log.best().map_or(f64::NAN, |e| e.fitness)
        );
    }
    let (x, f) = log.best().map(|e| (e.x.clone(), e.fitness)).unwrap_or((x0, f0));
    Ok((x, f, log.len()))
}

/// What the walker comparisons measure: 10-minute distance (m) and whether it fell, and the largest
/// pushes survived forward and backward (N·s).
struct Robustness {
    distance: f64,
    fell: bool,
    forward: f64,
    backward: f64,
}

fn robustness(c: &Controller) -> Robustness {
    let ((distance, fell), (forward, backward)) =
        rayon::join(|| ten_minutes(c), || rayon::join(|| largest_push(c, 1.0), || largest_push(c, -1.0)));
    Robustness { distance, fell, forward, backward }
}

/// One row of a walker comparison: robust score, 10-minute distance, mean speed, largest pushes.
fn measure_row(s: &mut String, name: &str, c: &Controller, robust: f64) -> Result<()> {
    let r = robustness(c);
    writeln!(
        s,
        "| {name} | {robust:.2} | {:.0}{} | {:.2} | {} / {} |",
        r.distance,
        if r.fell { " (fell)" } else { "" },
        r.distance / (LONG_ITERATIONS as f64 * nunes::DT),
        r.forward,
        r.backward
    )?;
    Ok(())
}

fn pushes_list(pushes: &[Push]) -> String {
    pushes
        .iter()
        .map(|p| format!("{}{}", if p.force[0] > 0.0 { "+" } else { "−" }, p.at))
        .collect::<Vec<_>>()
        .join(", ")
}

const WALKER_TABLE_HEAD: &str = "| walker | robust score | 10-minute distance (m) | mean speed (m/s) | largest push forward / backward (N·s) |\n|---|---|---|---|---|";

/// `reproduce nunes-robust`: CMA-ES on the mean score over six pushes (common random numbers).
pub fn robust(repo: &Repo) -> Result<String> {
    let base = nunes::controller("walk")?;
    let pushes = robust_pushes();
    let objective = |x: &[f64]| robust_score(&with_poses(&base, x), &pushes);
    let x0 = walker_poses(&base);
    let start = with_poses(&base, &x0);
    let f0 = objective(&x0);
    eprintln!("anima-lab: robust objective of the re-authored walker: {f0:.2}");
    let (best, fbest, evaluations) = robust_search("robust", walk_poses::space(), x0, &objective, SEED)?;
    let winner = with_poses(&base, &best);
    let path = "assets/controllers/walk-robust.ron";
    let text = format!(
        "// Written by `cargo xtask reproduce nunes-robust`: walk.ron with its twelve symmetric leg-pose numbers\n\
         // (anima_lab::nunes::walk_poses) found by CMA-ES on the mean walking score over six ±{ROBUST_IMPULSE} N·s head\n\
         // pushes at random times (common random numbers, seed {}).\n{}",
        SEED,
        winner.to_ron()
    );
    repo.write_text(path, &text)?;
    let mut s = String::new();
    writeln!(s, "## A walker optimised for pushes (CMA-ES, robust objective)\n")?;
    writeln!(
        s,
        "`cargo xtask reproduce nunes-robust`: CMA-ES (σ₀ = 0.1 of each interval, no restarts, {evaluations} evaluations) \
         over the twelve leg-pose numbers from the re-authored walker, maximising the mean score over six pushes \
         of ±{ROBUST_IMPULSE} N·s on the head (0.1 s, at iterations {}) — the same six for every candidate (common \
         random numbers). The winner is `assets/controllers/walk-robust.ron`.\n",
        pushes_list(&pushes)
    )?;
    writeln!(s, "{WALKER_TABLE_HEAD}")?;
    measure_row(&mut s, "walk.ron (re-authored)", &start, f0)?;
    measure_row(&mut s, "walk-robust.ron (CMA-ES)", &winner, fbest)?;
    writeln!(s)?;
    Ok(s)
}

/// `reproduce nunes-simbicon [--seeds N]`: the thesis's walking machines with SIMBICON-style balance
/// feedback (swing hip θ₀ + c_d·d + c_v·v in the world frame, trunk at a world angle), optimised
/// exactly as `nunes-robust` optimises the thesis's machine (same start poses, pushes, budget) with
/// c_d and c_v as two more numbers. Both forms are searched with `seeds` CMA-ES seeds from 2006 on;
/// seed 2006's SIMBICON winner is written to `assets/controllers/walk-simbicon.ron` (its thesis-form
/// winner is `walk-robust.ron`), and the text to its section of `docs/reproduction/nunes-simbicon.md`.
pub fn simbicon(repo: &Repo, seeds: usize) -> Result<String> {
    let walker = nunes::controller("walk")?;
    let base = nunes::simbicon::controller(&walker)?;
    let pushes = robust_pushes();
    let with = |x: &[f64]| {
        let mut c = base.clone();
        nunes::simbicon::set(&mut c, x);
        c
    };
    let thesis_objective = |x: &[f64]| robust_score(&with_poses(&walker, x), &pushes);
    let objective = |x: &[f64]| robust_score(&with(x), &pushes);
    let x0_thesis = walker_poses(&walker);
    let mut x0 = x0_thesis.clone();
    x0.extend([0.0, 0.0]);
    let f0 = objective(&x0);
    eprintln!("anima-lab: robust objective of the SIMBICON form with gains 0: {f0:.2}");
    struct Row {
        seed: u64,
        thesis: (f64, Robustness),
        simbicon: (f64, Robustness, f64, f64),
    }
    let mut rows = Vec::new();
    let mut winner = None;
    let mut evaluations = 0;
    for seed in SEED..SEED + seeds as u64 {
        let (xt, ft, _) = robust_search(
            &format!("thesis form, seed {seed}"),
            walk_poses::space(),
            x0_thesis.clone(),
            &thesis_objective,
            seed,
        )?;
        let (xs, fs, n) = robust_search(
            &format!("SIMBICON form, seed {seed}"),
            nunes::simbicon::space(),
            x0.clone(),
            &objective,
            seed,
        )?;
        evaluations = n;
        let (rt, rs) = rayon::join(|| robustness(&with_poses(&walker, &xt)), || robustness(&with(&xs)));
        eprintln!(
            "anima-lab: seed {seed}: thesis form {ft:.2} ({:.0} m, {} / {} N·s), SIMBICON {fs:.2} ({:.0} m, {} / {} N·s)",
            rt.distance, rt.forward, rt.backward, rs.distance, rs.forward, rs.backward
        );
        if winner.is_none() {
            winner = Some(xs.clone());
        }
        rows.push(Row { seed, thesis: (ft, rt), simbicon: (fs, rs, xs[12], xs[13]) });
    }
    let best = winner.unwrap_or_else(|| x0.clone());
    let winner = with(&best);
    let path = "assets/controllers/walk-simbicon.ron";
    let text = format!(
        "// Written by `cargo xtask reproduce nunes-simbicon`: walk.ron's machines with SIMBICON-style balance\n\
         // feedback (anima_lab::nunes::simbicon): the swing hip's world angle θ₀ + c_d·d + c_v·v and the trunk at a\n\
         // world angle. c_d = {:.3}, c_v = {:.3} and the twelve leg-pose numbers found by CMA-ES on the mean walking\n\
         // score over six ±{ROBUST_IMPULSE} N·s head pushes (common random numbers, seed {}).\n{}",
        best[12],
        best[13],
        SEED,
        winner.to_ron()
    );
    repo.write_text(path, &text)?;
    let mut s = String::new();
    writeln!(s, "## SIMBICON-style feedback against the thesis's machines\n")?;
    writeln!(
        s,
        "`cargo xtask reproduce nunes-simbicon --seeds {seeds}`: W-LEGS of `walk.ron` with the swing hip's target in \
         the world frame, θ₀ + c_d·d + c_v·v (d: the centre of mass ahead of the stance foot; v: its forward speed), \
         the inter-thigh target following it, and the trunk at a world angle; states, sensory transitions and arms \
         are the thesis's. For each seed, CMA-ES (σ₀ = 0.1 of each interval, no restarts, {evaluations} \
         evaluations) searched the thesis's form (the twelve leg-pose numbers, as `nunes-robust`) and the SIMBICON \
         form (the same twelve plus c_d ∈ [{}, {}] and c_v ∈ [{}, {}], starting at 0), both from the re-authored \
         walker's poses, on the robust objective of `nunes-robust`: the mean walking score over the same six \
         ±{ROBUST_IMPULSE} N·s head pushes at iterations {}. Seed {}'s winners are `walk-robust.ron` and \
         `walk-simbicon.ron`.\n",
        nunes::simbicon::GAINS_LO[0],
        nunes::simbicon::GAINS_HI[0],
        nunes::simbicon::GAINS_LO[1],
        nunes::simbicon::GAINS_HI[1],
        pushes_list(&pushes),
        SEED,
    )?;
    writeln!(
        s,
        "| seed | thesis's machines: robust score | 10-minute distance (m) | largest push forward / backward (N·s) \
         | SIMBICON form: robust score | 10-minute distance (m) | largest push forward / backward (N·s) | c_d | c_v |"
    )?;
    writeln!(s, "|---|---|---|---|---|---|---|---|---|")?;
    let dist = |r: &Robustness| format!("{:.0}{}", r.distance, if r.fell { " (fell)" } else { "" });
    for r in &rows {
        writeln!(
            s,
            "| {} | {:.2} | {} | {} / {} | {:.2} | {} | {} / {} | {:.3} | {:.3} |",
            r.seed,
            r.thesis.0,
            dist(&r.thesis.1),
            r.thesis.1.forward,
            r.thesis.1.backward,
            r.simbicon.0,
            dist(&r.simbicon.1),
            r.simbicon.1.forward,
            r.simbicon.1.backward,
            r.simbicon.2,
            r.simbicon.3
        )?;
    }
    let med = |f: &dyn Fn(&Row) -> f64| median(rows.iter().map(f).collect());
    writeln!(
        s,
        "| median | {:.2} | {:.0} | {} / {} | {:.2} | {:.0} | {} / {} | {:.3} | {:.3} |",
        med(&|r| r.thesis.0),
        med(&|r| r.thesis.1.distance),
        med(&|r| r.thesis.1.forward),
        med(&|r| r.thesis.1.backward),
        med(&|r| r.simbicon.0),
        med(&|r| r.simbicon.1.distance),
        med(&|r| r.simbicon.1.forward),
        med(&|r| r.simbicon.1.backward),
        med(&|r| r.simbicon.2),
        med(&|r| r.simbicon.3)
    )?;
    let wins = |f: &dyn Fn(&Row) -> bool| rows.iter().filter(|r| f(r)).count();
    writeln!(
        s,
        "\nThe SIMBICON form scored higher on the robust objective in {} of {seeds} seeds, survived the larger \
         forward push in {} and the larger backward push in {}, and walked 10 minutes without falling in {} \
         (the thesis's form: {}).\n",
        wins(&|r| r.simbicon.0 > r.thesis.0),
        wins(&|r| r.simbicon.1.forward > r.thesis.1.forward),
        wins(&|r| r.simbicon.1.backward > r.thesis.1.backward),
        wins(&|r| !r.simbicon.1.fell),
        wins(&|r| !r.thesis.1.fell),
    )?;
    writeln!(s, "Seed {}'s SIMBICON winner, and what its gains do:\n", SEED)?;
    writeln!(s, "{WALKER_TABLE_HEAD}")?;
    measure_row(&mut s, "SIMBICON form, gains 0 (the start)", &with(&x0), f0)?;
    measure_row(
        &mut s,
        "walk-simbicon.ron (CMA-ES)",
        &winner,
        rows.first().map_or(f64::NAN, |r| r.simbicon.0),
    )?;
    let mut zero = best.clone();
    zero[12] = 0.0;
    zero[13] = 0.0;
    let no_gains = with(&zero);
    measure_row(&mut s, "walk-simbicon.ron with c_d = c_v = 0", &no_gains, robust_score(&no_gains, &pushes))?;
    writeln!(s)?;
    use nunes::faithful::{REPORT, REPORT_HEADER, REPORT_SECTIONS};
    let mut doc = crate::report::Document::new(REPORT_HEADER, &REPORT_SECTIONS);
    doc.section("simbicon-form", s.clone());
    repo.write_report(REPORT, &doc)?;
    Ok(s)
}
