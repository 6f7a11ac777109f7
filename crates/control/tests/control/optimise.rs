//! The optimisers: Table 6.3 replayed through the greedy rule, CMA-ES on standard test functions,
//! thread-count independence, and resuming from a log.

use anima_control::optimise::{
    Annealing, AnnealingConfig, Cmaes, CmaesConfig, GreedySearch, Interval, Objective, Optimiser,
    RandomSearch, ResumeError, RunLog, Space, Stage, resume,
};
use anima_control::{Controller, Procedures, Selection};

/// [`anima_control::optimise::run`] of an objective whose every fitness is finite.
fn run<O: Optimiser + ?Sized, F: Objective + ?Sized>(
    opt: &mut O,
    objective: &F,
    budget: usize,
    log: &mut RunLog,
) -> Option<(Vec<f64>, f64)> {
    anima_control::optimise::run(opt, objective, budget, log).expect("every fitness is finite")
}

/// Table 6.3 (Nunes 2006 p.69–70; spec §8.1.5): (T2, T3, T5, T6, fitness) per evaluation.
const INITIAL: [f64; 5] = [0.250, 0.250, 0.250, 0.250, 0.000];
const STAGE_1: [[f64; 5]; 15] = [
    [-0.013, 0.417, 0.093, 0.331, 8.133],
    [0.363, 0.264, 0.134, 0.291, 0.000],
    [-0.237, 0.362, 0.093, 0.126, 7.290],
    [0.359, 0.314, 0.345, -0.085, 0.000],
    [0.044, -0.090, -0.211, 0.232, 8.284],
    [-0.087, 0.205, 0.034, -0.116, 8.372],
    [0.069, 0.672, 0.644, 0.249, 0.000],
    [-0.218, 0.349, 0.087, 0.386, 0.000],
    [0.282, 0.276, 0.340, 0.215, 0.000],
    [-0.228, 0.663, 0.299, 0.423, 0.000],
    [0.404, 0.547, 0.425, -0.069, 0.000],
    [0.331, -0.088, 0.302, 0.036, 0.000],
    [0.061, 0.505, 0.018, 0.597, 7.660],
    [0.720, -0.144, 0.553, -0.145, 0.000],
    [-0.019, 0.179, 0.584, -0.232, 0.000],
];
const STAGE_2: [[f64; 5]; 30] = [
    [-0.087, 0.205, 0.034, 0.628, 0.000],
    [-0.087, 0.205, 0.522, -0.116, 0.000],
    [0.067, 0.205, 0.034, -0.116, 8.693],
    [0.067, 0.205, 0.034, 0.195, 8.225],
    [0.067, -0.230, 0.034, -0.116, 8.798],
    [0.067, -0.230, 0.034, -0.068, 8.798],
    [0.209, -0.230, 0.034, -0.116, 0.000],
    [0.067, -0.230, 0.146, -0.116, 0.000],
    [0.327, -0.230, 0.034, -0.116, 0.000],
    [0.069, -0.230, 0.034, -0.116, 8.870],
    [0.069, -0.230, 0.034, -0.023, 8.870],
    [0.704, -0.230, 0.034, -0.116, 0.000],
    [0.069, -0.230, 0.628, -0.116, 0.000],
    [0.069, -0.149, 0.034, -0.116, 8.870],
    [0.069, -0.049, 0.034, -0.116, 8.870],
    [0.069, -0.230, 0.698, -0.116, 0.000],
    [0.661, -0.230, 0.034, -0.116, 0.000],
    [0.069, -0.230, -0.153, -0.116, 8.936],
    [0.069, 0.557, -0.153, -0.116, 7.595],
    [0.069, -0.230, 0.489, -0.116, 0.000],
    [0.069, -0.230, 0.060, -0.116, 9.709],
    [0.069, 0.665, 0.060, -0.116, 8.883],
    [-0.179, -0.230, 0.060, -0.116, 10.528],
    [-0.179, -0.000, 0.060, -0.116, 10.528],
    [-0.179, 0.384, 0.060, -0.116, 8.946],
    [-0.179, -0.230, -0.001, -0.116, 0.000],
    [-0.179, -0.230, 0.060, 0.082, 10.528],
    [-0.179, -0.230, 0.060, 0.380, 8.289],
    [-0.179, 0.134, 0.060, -0.116, 0.000],
    [-0.179, -0.021, 0.060, -0.116, 10.528],
];

fn walking_stages() -> Vec<Stage> {
    vec![
        Stage::global("stage 1", vec![0, 1, 2, 3], 15),
        Stage::local_single("stage 2", vec![0, 1, 2, 3], 30, Interval::Fixed),
    ]
}

#[test]
fn table_6_3_replay_picks_winners_6_and_23() {
    let space = Space::cube(4, -0.25, 0.75);
    let mut g = GreedySearch::new(space, walking_stages(), INITIAL[..4].to_vec(), 0).unwrap();
    let tell = |g: &mut GreedySearch, row: &[f64; 5]| g.tell(&[row[..4].to_vec()], &[row[4]])[0];
    assert!(tell(&mut g, &INITIAL));
    let acc1: Vec<usize> = (1..=15).filter(|&i| tell(&mut g, &STAGE_1[i - 1])).collect();
    assert_eq!(acc1, vec![1, 5, 6]);
    assert_eq!(g.stage(), 1);
    let mut acc2 = Vec::new();
    for (i, row) in STAGE_2.iter().enumerate() {
        // Every stage-2 row is one parameter away from our incumbent: the thesis's incumbent
        // tracking (strict acceptance, ties rejected) is ours.
        let inc = g.incumbent().0.to_vec();
        let changed = (0..4).filter(|&d| (row[d] - inc[d]).abs() > 1e-12).count();
        assert!(changed <= 1, "stage-2 evaluation {} changes {changed} parameters of {inc:?}", i + 1);
        if tell(&mut g, row) {
            acc2.push(i + 1);
        }
    }
    assert_eq!(acc2, vec![3, 5, 10, 18, 21, 23]);
    let r = g.results();
    assert_eq!((r[0].winner, r[0].fitness), (Some(6), 8.372));
    assert_eq!((r[1].winner, r[1].fitness), (Some(23), 10.528));
    assert_eq!(r[1].x, STAGE_2[22][..4].to_vec());
    assert!(g.finished());
}

/// A smooth stand-in for the walker's fitness over (p2, p3, p5, p6).
fn walker_like(x: &[f64]) -> f64 {
    let d: f64 = x.iter().zip([-0.18, -0.23, 0.06, -0.12]).map(|(a, b)| (a - b) * (a - b)).sum();
    if d > 0.3 { 0.0 } else { 11.0 - 10.0 * d }
}

#[test]
fn the_staged_search_on_the_walker_file_has_the_table_6_3_structure() {
    let text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/controllers/walk.ron"))
            .unwrap();
    let ctl = Controller::from_ron(&text, &Procedures::<()>::new()).unwrap();
    let ids = ctl.free_params(&Selection::all());
    let space = ctl.space(&ids);
    // The objective sets the parameters into a copy of the controller, as an evaluator would.
    let objective = |x: &[f64]| {
        let mut c = ctl.clone();
        c.apply(&ids, x);
        walker_like(&c.values_of(&ids))
    };
    let mut g = GreedySearch::new(space, walking_stages(), ctl.values_of(&ids), 2006).unwrap();
    let mut log = RunLog::default();
    let (best, f) = run(&mut g, &objective, usize::MAX, &mut log).unwrap();
    assert_eq!(log.len(), 46, "initial + 15 + 30");
    assert_eq!(log.evaluations.iter().filter(|e| e.stage == 0).count(), 16);
    assert!(log.evaluations.iter().all(|e| e.x.iter().all(|v| (-0.25..=0.75).contains(v))));
    // The incumbent entering stage 2: the last accepted evaluation of stage 1.
    let mut inc = log.evaluations[..16].iter().rfind(|e| e.accepted).unwrap().x.clone();
    for e in log.evaluations.iter().filter(|e| e.stage == 1) {
        let changed = (0..4).filter(|&d| e.x[d] != inc[d]).count();
        assert!(changed <= 1, "a local-single evaluation changed {changed} parameters");
        if e.accepted {
            inc.clone_from(&e.x);
        }
    }
    assert_eq!(best, inc);
    assert!(f >= log.evaluations[0].fitness);
    assert_eq!(f, log.best().unwrap().fitness);
}

fn rosenbrock(x: &[f64]) -> f64 {
    x.windows(2).map(|w| 100.0 * (w[1] - w[0] * w[0]).powi(2) + (1.0 - w[0]).powi(2)).sum()
}

fn sphere(x: &[f64]) -> f64 {
    x.iter().map(|v| v * v).sum()
}

fn ellipsoid(x: &[f64]) -> f64 {
    let n = x.len() as f64;
    x.iter().enumerate().map(|(i, v)| 1e6f64.powf(i as f64 / (n - 1.0)) * v * v).sum()
}

/// Minimises `f` from x0 = (0.5, …) with CMA-ES until f < 1e-8; returns the evaluations used.
fn cmaes_evaluations(f: fn(&[f64]) -> f64, n: usize, seed: u64, budget: usize) -> (usize, f64) {
    let mut cfg = CmaesConfig::new(vec![0.5; n], 0.5);
    cfg.target = Some(-1e-8);
    let mut opt = Cmaes::new(Space::unbounded(n), cfg, seed).unwrap();
    let mut log = RunLog::default();
    let (_, best) = run(&mut opt, &|x: &[f64]| -f(x), budget, &mut log).unwrap();
    (log.len(), -best)
}

#[test]
fn cmaes_solves_10d_rosenbrock_within_1e4_evaluations() {
    let mut counts = Vec::new();
    for seed in 0..3 {
        let (n, f) = cmaes_evaluations(rosenbrock, 10, seed, 30_000);
        assert!(f < 1e-8, "seed {seed}: f = {f:e} after {n} evaluations");
        counts.push(n);
    }
    println!("CMA-ES, 10-D Rosenbrock to f < 1e-8: {counts:?} evaluations (seeds 0, 1, 2)");
    assert!(counts.iter().all(|&n| n <= 10_000), "{counts:?}");
}

#[test]
fn cmaes_solves_sphere_and_ellipsoid_quickly() {
    let (n, f) = cmaes_evaluations(sphere, 10, 1, 10_000);
    println!("CMA-ES, 10-D sphere to f < 1e-8: {n} evaluations");
    assert!(f < 1e-8 && n <= 2_500, "sphere: f = {f:e} after {n}");
    let (n, f) = cmaes_evaluations(ellipsoid, 10, 1, 20_000);
    println!("CMA-ES, 10-D ellipsoid (condition 1e6) to f < 1e-8: {n} evaluations");
    assert!(f < 1e-8 && n <= 8_000, "ellipsoid: f = {f:e} after {n}");
}

#[test]
fn cmaes_respects_bounds_and_finds_an_optimum_on_the_boundary() {
    // Optimum (2, 2, 2) outside the box [−1, 1]³: the answer is the corner (1, 1, 1).
    let mut cfg = CmaesConfig::new(vec![0.0; 3], 0.3);
    cfg.restarts = 0;
    let mut opt = Cmaes::new(Space::cube(3, -1.0, 1.0), cfg, 5).unwrap();
    let mut log = RunLog::default();
    let (x, _) =
        run(&mut opt, &|x: &[f64]| -x.iter().map(|v| (v - 2.0) * (v - 2.0)).sum::<f64>(), 4000, &mut log)
            .unwrap();
    assert!(log.evaluations.iter().all(|e| e.x.iter().all(|v| (-1.0..=1.0).contains(v))));
    assert!(x.iter().all(|v| (v - 1.0).abs() < 1e-6), "{x:?}");
}

#[test]
fn ipop_restarts_double_the_population() {
    // Rastrigin is multimodal: plain CMA-ES with a small population stops in a local optimum and IPOP
    // restarts with λ doubled.
    let rastrigin =
        |x: &[f64]| -x.iter().map(|v| v * v - 10.0 * (std::f64::consts::TAU * v).cos() + 10.0).sum::<f64>();
    let mut cfg = CmaesConfig::new(vec![3.0; 5], 2.0);
    cfg.restarts = 3;
    let mut opt = Cmaes::new(Space::unbounded(5), cfg, 3).unwrap();
    let lambda0 = opt.lambda();
    let mut log = RunLog::default();
    run(&mut opt, &rastrigin, 200_000, &mut log);
    assert!(opt.restarts() >= 1, "no restart happened");
    assert_eq!(opt.lambda(), lambda0 << opt.restarts());
    let stages: Vec<usize> = log.evaluations.iter().map(|e| e.stage).collect();
    assert!(stages.windows(2).all(|w| w[1] >= w[0]), "stages are restarts, in order");
}

/// The baselines improve on the initial point.
#[test]
fn random_search_and_annealing_improve() {
    let f = |x: &[f64]| -sphere(&x.iter().map(|v| v - 0.3).collect::<Vec<_>>());
    let space = Space::cube(4, -1.0, 1.0);
    let mut rs = RandomSearch::new(space.clone(), 8, 1).unwrap();
    let mut log = RunLog::default();
    let (_, best) = run(&mut rs, &f, 800, &mut log).unwrap();
    assert!(best > f(&[0.0; 4]), "{best}");
    let cfg = AnnealingConfig { x0: vec![-0.9; 4], t0: 0.5, cooling: 0.99, step: 0.1, batch: 4 };
    let mut sa = Annealing::new(space, cfg, 1).unwrap();
    let mut log = RunLog::default();
    let (_, best) = run(&mut sa, &f, 2000, &mut log).unwrap();
    assert!(best > -0.02, "{best}");
}

fn optimisers(seed: u64) -> Vec<Box<dyn Optimiser>> {
    let space = Space::cube(6, -2.0, 2.0);
    let mut stages = vec![Stage::global("g", (0..6).collect(), 40)];
    let mut local =
        Stage::local_single("l", (0..6).collect(), 60, Interval::PartiallyReduced { fraction: 0.5 });
    local.batch = 6;
    stages.push(local);
    let mut cfg = CmaesConfig::new(vec![1.0; 6], 0.3);
    cfg.restarts = 2;
    vec![
        Box::new(GreedySearch::new(space.clone(), stages, vec![1.5; 6], seed).unwrap()),
        Box::new(Cmaes::new(space.clone(), cfg, seed).unwrap()),
        Box::new(RandomSearch::new(space.clone(), 16, seed).unwrap()),
        Box::new(
            Annealing::new(
                space,
                AnnealingConfig { x0: vec![1.0; 6], t0: 1.0, cooling: 0.98, step: 0.05, batch: 8 },
                seed,
            )
            .unwrap(),
        ),
    ]
}

/// Rosenbrock with a little extra work so that threads really interleave.
fn busy(x: &[f64]) -> f64 {
    let mut acc = 0.0;
    for k in 0..200 {
        acc += (x[0] * f64::from(k)).sin() * 1e-12;
    }
    -rosenbrock(x) + acc
}

#[test]
fn results_are_identical_with_one_and_two_threads() {
    let run_with = |threads: usize| -> Vec<RunLog> {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            optimisers(42)
                .into_iter()
                .map(|mut o| {
                    let mut log = RunLog::default();
                    run(o.as_mut(), &busy, 600, &mut log);
                    log
                })
                .collect()
        })
    };
    let (one, two) = (run_with(1), run_with(2));
    for (a, b) in one.iter().zip(&two) {
        assert_eq!(a, b, "{}: logs differ between 1 and 2 threads", a.optimiser);
        assert!(a.len() >= 100);
    }
}

#[test]
fn a_resumed_run_equals_an_uninterrupted_one() {
    for k in 0..4 {
        let mut whole = optimisers(7).swap_remove(k);
        let mut full = RunLog::default();
        let full_best = run(whole.as_mut(), &busy, 500, &mut full);

        // Stop after about 200 evaluations and keep only the serialised log.
        let mut first = optimisers(7).swap_remove(k);
        let mut log = RunLog::default();
        run(first.as_mut(), &busy, 200, &mut log);
        let saved = ron::to_string(&log).unwrap();
        drop(first);

        let log: RunLog = ron::from_str(&saved).unwrap();
        let mut again = optimisers(7).swap_remove(k);
        let mut log2 = log.clone();
        resume(again.as_mut(), &log).unwrap();
        let best = run(again.as_mut(), &busy, 500, &mut log2);
        assert_eq!(log2, full, "{}: resumed log differs", full.optimiser);
        assert_eq!(best, full_best);
    }
}

#[test]
fn resuming_with_another_seed_is_refused() {
    let mut a = optimisers(1).swap_remove(1);
    let mut log = RunLog::default();
    run(a.as_mut(), &busy, 100, &mut log);
    let mut b = optimisers(2).swap_remove(1);
    assert!(matches!(resume(b.as_mut(), &log), Err(ResumeError::Mismatch { evaluation: 0 })));
    let mut c = optimisers(1).swap_remove(0);
    assert!(matches!(resume(c.as_mut(), &log), Err(ResumeError::Optimiser { .. })));
}

/// Populations and budgets above anima's limits are configuration errors, found before anything is
/// allocated for them (issue #40: λ = 10¹² aborted for want of memory).
#[test]
fn populations_and_budgets_above_the_limits_are_refused() {
    use anima_control::optimise::OptimiseError;
    use anima_format::limits::{MAX_EVALUATIONS, MAX_POPULATION};
    let space = Space::cube(4, -1.0, 1.0);
    let refused = |r: Result<(), OptimiseError>, what: &str| match r {
        Err(OptimiseError::Config(why)) => assert!(why.contains("at most"), "{what}: {why}"),
        other => panic!("{what}: {other:?}"),
    };
    for lambda in [MAX_POPULATION + 1, 1_000_000_000_000, usize::MAX] {
        let cfg = CmaesConfig { lambda: Some(lambda), ..CmaesConfig::new(vec![0.0; 4], 0.3) };
        refused(Cmaes::new(space.clone(), cfg, 1).map(drop), "λ");
        refused(RandomSearch::new(space.clone(), lambda, 1).map(drop), "random batch");
        let cfg = AnnealingConfig { x0: vec![0.0; 4], t0: 1.0, cooling: 0.9, step: 0.1, batch: lambda };
        refused(Annealing::new(space.clone(), cfg, 1).map(drop), "annealing batch");
        let mut stage = Stage::local_single("l", vec![0], 10, Interval::Fixed);
        stage.batch = lambda;
        refused(GreedySearch::new(space.clone(), vec![stage], vec![0.0; 4], 1).map(drop), "stage batch");
    }
    let stage = Stage::global("g", vec![0, 1], MAX_EVALUATIONS + 1);
    refused(GreedySearch::new(space.clone(), vec![stage], vec![0.0; 4], 1).map(drop), "stage evaluations");
    // At the limits they build (and a generation of 10 000 is asked at once).
    let cfg = CmaesConfig { lambda: Some(MAX_POPULATION), ..CmaesConfig::new(vec![0.0; 4], 0.3) };
    assert_eq!(Cmaes::new(space.clone(), cfg, 1).unwrap().ask().len(), MAX_POPULATION);
    assert_eq!(RandomSearch::new(space.clone(), MAX_POPULATION, 1).unwrap().ask().len(), MAX_POPULATION);
    let stage = Stage::global("g", vec![0, 1], MAX_EVALUATIONS);
    assert!(GreedySearch::new(space.clone(), vec![stage], vec![0.0; 4], 1).is_ok());
}

/// IPOP's growing population stops at the limit, even with an absurd increase.
#[test]
fn ipop_restarts_stop_growing_at_the_population_limit() {
    use anima_format::limits::MAX_POPULATION;
    let mut cfg = CmaesConfig::new(vec![0.5; 2], 0.3);
    cfg.increase = f64::INFINITY;
    cfg.restarts = 3;
    cfg.tol_x = 1e3; // every run stops after its first generation
    let mut opt = Cmaes::new(Space::cube(2, 0.0, 1.0), cfg, 1).unwrap();
    let mut log = RunLog::default();
    run(&mut opt, &sphere, 50_000, &mut log);
    assert_eq!(opt.restarts(), 3);
    assert_eq!(opt.lambda(), MAX_POPULATION);
}

/// A log is checked whole before the optimiser is touched: an edited one with a non-finite fitness
/// or point, a point of another dimension, or generations that do not count up from 0 is refused, and
/// the optimiser still asks what a fresh one asks.
#[test]
fn a_log_is_checked_whole_before_the_optimiser_is_touched() {
    let mut first = optimisers(5).swap_remove(1);
    let mut good = RunLog::default();
    run(first.as_mut(), &busy, 100, &mut good);
    let n = good.len();
    assert!(good.generations >= 3, "{}", good.generations);
    type Edit = Box<dyn Fn(&mut RunLog)>;
    let edits: Vec<(&str, Edit)> = vec![
        ("an infinite fitness", Box::new(move |l| l.evaluations[n - 1].fitness = f64::INFINITY)),
        ("a NaN fitness", Box::new(move |l| l.evaluations[n - 1].fitness = f64::NAN)),
        ("a NaN value", Box::new(move |l| l.evaluations[n - 1].x[2] = f64::NAN)),
        ("a value too many", Box::new(move |l| l.evaluations[n - 1].x.push(0.0))),
        ("generations from 1", Box::new(|l| l.evaluations.iter_mut().for_each(|e| e.generation += 1))),
        ("a generation back", Box::new(move |l| l.evaluations[n - 1].generation = 0)),
        ("a generation skipped", Box::new(move |l| l.evaluations[n - 1].generation += 1)),
        ("a wrong count", Box::new(|l| l.generations += 1)),
    ];
    for (what, edit) in edits {
        let mut log = good.clone();
        edit(&mut log);
        let mut opt = optimisers(5).swap_remove(1);
        let e = resume(opt.as_mut(), &log).expect_err(what);
        assert!(
            matches!(
                e,
                ResumeError::Fitness { .. }
                    | ResumeError::Point { .. }
                    | ResumeError::Generation { .. }
                    | ResumeError::Generations { .. }
            ),
            "{what}: {e}"
        );
        assert_eq!(opt.ask(), optimisers(5).swap_remove(1).ask(), "{what}: the optimiser was touched");
    }
    resume(optimisers(5).swap_remove(1).as_mut(), &good).unwrap();
}

/// A log whose replay fails after its first generation has changed the optimiser; rebuilt, as
/// `resume` asks, the run equals a fresh one.
#[test]
fn after_a_replay_that_fails_a_rebuilt_optimiser_runs_as_a_fresh_one() {
    for k in 0..4 {
        let mut fresh = optimisers(9).swap_remove(k);
        let mut fresh_log = RunLog::default();
        let fresh_best = run(fresh.as_mut(), &busy, 300, &mut fresh_log);

        // The second generation's first point moved by one bit: only asking finds it.
        let mut log = RunLog::default();
        run(optimisers(9).swap_remove(k).as_mut(), &busy, 100, &mut log);
        let second = log.evaluations.iter().position(|e| e.generation == 1).unwrap();
        let x = &mut log.evaluations[second].x[0];
        *x = f64::from_bits(x.to_bits() ^ 1);
        let mut opt = optimisers(9).swap_remove(k);
        let e = resume(opt.as_mut(), &log).unwrap_err();
        assert_eq!(e, ResumeError::Mismatch { evaluation: second }, "{}", log.optimiser);
        assert_ne!(opt.ask(), optimisers(9).swap_remove(k).ask(), "{}: the replay went on", log.optimiser);

        let mut opt = optimisers(9).swap_remove(k);
        let mut again = RunLog::default();
        let best = run(opt.as_mut(), &busy, 300, &mut again);
        assert_eq!(again, fresh_log, "{}", log.optimiser);
        assert_eq!(best, fresh_best);
    }
}

/// An objective that gives a non-finite fitness is refused: its generation is neither told nor
/// logged, and the error names it.
#[test]
fn a_non_finite_fitness_is_refused() {
    use anima_control::optimise::FitnessError;
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut opt = optimisers(3).swap_remove(2);
        let mut log = RunLog::default();
        run(opt.as_mut(), &busy, 32, &mut log);
        let before = log.clone();
        let objective = |x: &[f64]| if x[0] > 0.0 { bad } else { busy(x) };
        let e: FitnessError =
            anima_control::optimise::run(opt.as_mut(), &objective, 64, &mut log).unwrap_err();
        assert_eq!(log, before, "the refused generation is not logged");
        assert!(e.evaluation >= before.len() && e.x[0] > 0.0 && e.fitness.to_bits() == bad.to_bits(), "{e}");
        assert!(e.to_string().contains("finite"), "{e}");
    }
}

/// An annealing start that is NaN or outside its interval is refused (a NaN start used to write a
/// controller anima then refused to read).
#[test]
fn an_annealing_start_outside_the_box_is_refused() {
    use anima_control::optimise::OptimiseError;
    let space = Space::cube(2, -1.0, 1.0);
    for x0 in [vec![f64::NAN, 0.0], vec![0.0, 1.5], vec![f64::NEG_INFINITY, 0.0]] {
        let cfg = AnnealingConfig { x0: x0.clone(), t0: 1.0, cooling: 0.9, step: 0.1, batch: 1 };
        match Annealing::new(space.clone(), cfg, 1) {
            Err(OptimiseError::Config(why)) => assert!(why.contains("outside"), "{why}"),
            other => panic!("{x0:?}: {:?}", other.map(|_| ())),
        }
    }
    let cfg = AnnealingConfig { x0: vec![-1.0, 1.0], t0: 1.0, cooling: 0.9, step: 0.1, batch: 1 };
    assert!(Annealing::new(space, cfg, 1).is_ok(), "the interval's ends are inside");
}
