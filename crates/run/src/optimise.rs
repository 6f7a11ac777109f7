//! Controller optimisation from a spec file (`anima optimise SPEC`, and the thesis's runs of
//! `cargo xtask reproduce nunes`): the spec's objective over its free parameters, with its optimiser
//! and seed, one generation at a time, logging every evaluation after each generation and resuming from
//! that log when it is there. The optimisers are seeded, so a resumed run equals an uninterrupted one.

use std::path::{Path, PathBuf};

use anima_control::optimise::{
    Annealing, AnnealingConfig, Cmaes, CmaesConfig, GreedySearch, Objective, Optimiser, RandomSearch, RunLog,
    Space, resume, run,
};
use anima_control::{Controller, ParamId};
use anima_scene::optimisation::{LoadedOptimisation, ObjectiveSpec, OptimiserSpec};
use anyhow::{Context, Result, bail};

use crate::objectives;
use crate::output::write_atomic;
use crate::run::Progress;

/// The fitness of the spec's objective for `controller` with its parameters `ids` set to `x`: always
/// a finite number, a failed evaluation (a fall, a diverging simulation) scoring 0.
pub fn fitness(objective: &ObjectiveSpec, controller: &Controller, ids: &[ParamId], x: &[f64]) -> f64 {
    let mut c = controller.clone();
    c.apply(ids, x);
    match *objective {
        ObjectiveSpec::Walk { iterations, actuation } => {
            let walker = objectives::humanoid_with(c, actuation.unwrap_or_else(objectives::actuation));
            walker
                .and_then(|w| {
                    objectives::walk_character(w, iterations, &objectives::WalkRules::default(), &[], |_| ())
                })
                .map_or(0.0, |o| o.fitness())
        }
        ObjectiveSpec::Throw { iterations, height_cap } => {
            let cap = height_cap.then(|| objectives::throw_height_cap(&objectives::BASKET));
            objectives::throw(c, &objectives::BASKET, iterations, |_| ())
                .map_or(0.0, |o| o.fitness_capped(cap))
        }
    }
}

/// The spec's optimiser over the selected parameters, started from the controller's values.
pub fn optimiser(loaded: &LoadedOptimisation, ids: &[ParamId]) -> Result<Box<dyn Optimiser + Send>> {
    optimiser_in(loaded, ids, loaded.controller.space(ids))
}

/// [`optimiser`] over `space` (one dimension per parameter of `ids`) instead of the controller's
/// admissible intervals: a search kept in a region of them.
pub fn optimiser_in(
    loaded: &LoadedOptimisation,
    ids: &[ParamId],
    space: Space,
) -> Result<Box<dyn Optimiser + Send>> {
    let c = &loaded.controller;
    if space.len() != ids.len() {
        bail!("the search space has {} dimensions for {} free parameters", space.len(), ids.len());
    }
    let (x0, seed) = (c.values_of(ids), loaded.spec.seed);
    for stage in match &loaded.spec.optimiser {
        OptimiserSpec::Greedy { stages } => stages.as_slice(),
        _ => &[],
    } {
        if let Some(d) = stage.dims.iter().find(|&&d| d >= ids.len()) {
            bail!(
                "stage `{}` names parameter {d}, but the selection has {} free parameters",
                stage.name,
                ids.len()
            );
        }
    }
    Ok(match &loaded.spec.optimiser {
        OptimiserSpec::Greedy { stages } => Box::new(GreedySearch::new(space, stages.clone(), x0, seed)?),
        OptimiserSpec::Cmaes { sigma0, lambda, restarts } => {
            let cfg = CmaesConfig { lambda: *lambda, restarts: *restarts, ..CmaesConfig::new(x0, *sigma0) };
            Box::new(Cmaes::new(space, cfg, seed)?)
        }
        OptimiserSpec::RandomSearch { batch } => Box::new(RandomSearch::new(space, *batch, seed)?),
        OptimiserSpec::Annealing(cfg) => {
            let cfg =
                AnnealingConfig { x0: if cfg.x0.is_empty() { x0 } else { cfg.x0.clone() }, ..cfg.clone() };
            Box::new(Annealing::new(space, cfg, seed)?)
        }
    })
}

/// Runs the optimiser `build` makes to `budget` evaluations, one generation at a time, the log
/// written (whole) to `log_path` after each; an earlier log of the same run there is replayed first
/// and the run goes on from it. When that log does not replay, the optimiser it was replayed into is
/// dropped and the run starts over from a freshly built one, as a run without the log would.
/// `report` sees the log after every generation.
pub fn optimise_logged<O: Optimiser + ?Sized>(
    mut build: impl FnMut() -> Result<Box<O>>,
    objective: &(impl Objective + ?Sized),
    budget: usize,
    log_path: &Path,
    mut report: impl FnMut(&RunLog, Resumed),
) -> Result<RunLog> {
    let mut log = RunLog::default();
    let mut opt = build()?;
    if let Ok(text) = std::fs::read_to_string(log_path) {
        let old: RunLog = ron::from_str(&text).with_context(|| format!("reading {}", log_path.display()))?;
        match resume(opt.as_mut(), &old) {
            Ok(()) => {
                report(&old, Resumed::From(old.len()));
                log = old;
            }
            Err(e) => {
                // The replay may have told `opt` part of the log (see `resume`).
                opt = build()?;
                report(&log, Resumed::Refused(e.to_string()));
            }
        }
    }
    while log.len() < budget {
        let before = log.len();
        run(opt.as_mut(), objective, before + 1, &mut log)?;
        if log.len() == before {
            break;
        }
        let text = ron::ser::to_string_pretty(&log, ron::ser::PrettyConfig::default())?;
        write_atomic(log_path, |w| Ok(w.write_all(text.as_bytes())?))?;
        report(&log, Resumed::No);
    }
    Ok(log)
}

/// What [`optimise_logged`] did with an earlier log.
#[derive(Debug, Clone, PartialEq)]
pub enum Resumed {
    /// Nothing to say: a generation was evaluated.
    No,
    /// It replayed that many logged evaluations.
    From(usize),
    /// The log did not replay (another seed or configuration); the run started over.
    Refused(String),
}

/// Where `anima optimise` writes, and how much it runs.
#[derive(Debug, Clone)]
pub struct OptimiseOptions {
    pub out_dir: PathBuf,
    /// Overrides the spec's evaluation budget.
    pub evaluations: Option<usize>,
    /// Ignore an earlier log and start over.
    pub fresh: bool,
}

/// What a spec's run found.
#[derive(Debug, Clone)]
pub struct OptimiseOutcome {
    pub log: RunLog,
    /// Evaluations replayed from an earlier log.
    pub resumed: usize,
    pub best_x: Vec<f64>,
    pub best_fitness: f64,
    /// The controller's own fitness (the first evaluation of the run).
    pub start_fitness: f64,
    pub controller: Controller,
    pub log_path: PathBuf,
    pub controller_path: PathBuf,
}

/// Runs a spec: `<out>/<name>.log.ron` after every generation, `<out>/<name>.ron` (the best controller)
/// at the end. `progress` counts evaluations.
pub fn optimise(
    loaded: &LoadedOptimisation,
    opts: &OptimiseOptions,
    progress: &mut dyn Progress,
) -> Result<OptimiseOutcome> {
    let spec = &loaded.spec;
    let ids = loaded.controller.free_params(&spec.parameters);
    if ids.is_empty() {
        bail!(
            "the selection names no free parameter of the controller (a free parameter is written with an interval)"
        );
    }
    let budget = opts.evaluations.unwrap_or(spec.evaluations);
    let max = anima_scene::limits::MAX_EVALUATIONS;
    if budget == 0 || budget > max {
        bail!("expected a budget of 1 to {max} evaluations (anima's limit), found {budget}");
    }
    let log_path = opts.out_dir.join(format!("{}.log.ron", spec.name));
    if opts.fresh && log_path.exists() {
        std::fs::remove_file(&log_path).with_context(|| format!("removing {}", log_path.display()))?;
    }
    let objective = |x: &[f64]| fitness(&spec.objective, &loaded.controller, &ids, x);
    let mut resumed = 0;
    progress.begin(budget as u64);
    let build = || optimiser(loaded, &ids);
    let log = optimise_logged(build, &objective, budget, &log_path, |log, r| {
        match r {
            Resumed::From(n) => resumed = n,
            Resumed::Refused(why) => {
                progress.warn(&format!("not resuming from {} ({why}); starting over", log_path.display()))
            }
            Resumed::No => {}
        }
        progress.advance(log.len() as u64);
    })?;
    progress.end();
    let best = log.best().context("the optimiser evaluated nothing")?;
    let mut controller = loaded.controller.clone();
    controller.apply(&ids, &best.x);
    let controller_path = opts.out_dir.join(format!("{}.ron", spec.name));
    let text = format!(
        "// Written by `anima optimise` from the spec `{}`: {} evaluations, seed {}, best fitness {}.\n{}",
        spec.name,
        log.len(),
        spec.seed,
        best.fitness,
        controller.to_ron()
    );
    write_atomic(&controller_path, |w| Ok(w.write_all(text.as_bytes())?))?;
    Ok(OptimiseOutcome {
        resumed,
        best_x: best.x.clone(),
        best_fitness: best.fitness,
        start_fitness: log.evaluations[0].fitness,
        controller,
        log: log.clone(),
        log_path,
        controller_path,
    })
}

#[cfg(test)]
mod tests {
    use anima_control::optimise::{Space, Stage};

    use super::*;

    fn sphere(x: &[f64]) -> f64 {
        -x.iter().map(|v| (v - 0.3) * (v - 0.3)).sum::<f64>()
    }

    /// CMA-ES and the greedy search over a small box.
    fn build(kind: usize) -> Result<Box<dyn Optimiser + Send>> {
        let space = Space::cube(3, -1.0, 1.0);
        Ok(match kind {
            0 => Box::new(Cmaes::new(space, CmaesConfig::new(vec![0.5; 3], 0.3), 11)?),
            _ => {
                let stages = vec![Stage::global("g", vec![0, 1, 2], 10), Stage::global("h", vec![0, 1], 10)];
                Box::new(GreedySearch::new(space, stages, vec![0.5; 3], 11)?)
            }
        })
    }

    /// A log whose replay fails after its first generation is refused, and the run that follows equals
    /// a fresh one: the optimiser the log was replayed into is rebuilt.
    #[test]
    fn a_log_that_fails_to_replay_leaves_a_run_equal_to_a_fresh_one() {
        let dir = std::env::temp_dir().join(format!("anima-run-resume-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for kind in 0..2 {
            let (fresh_path, edited_path) =
                (dir.join(format!("fresh{kind}.ron")), dir.join(format!("edited{kind}.ron")));
            let _ = std::fs::remove_file(&fresh_path);
            let fresh = optimise_logged(|| build(kind), &sphere, 40, &fresh_path, |_, _| ()).unwrap();

            // The first two generations of that run, the second one's first point moved by one bit.
            let mut log = fresh.clone();
            log.evaluations.retain(|e| e.generation < 2);
            log.generations = 2;
            let second = log.evaluations.iter().position(|e| e.generation == 1).unwrap();
            let x = &mut log.evaluations[second].x[0];
            *x = f64::from_bits(x.to_bits() ^ 1);
            std::fs::write(&edited_path, ron::to_string(&log).unwrap()).unwrap();

            let mut refused = None;
            let again = optimise_logged(
                || build(kind),
                &sphere,
                40,
                &edited_path,
                |_, r| {
                    if let Resumed::Refused(why) = r {
                        refused = Some(why);
                    }
                },
            )
            .unwrap();
            let why = refused.expect("the edited log was resumed");
            assert!(why.contains(&format!("evaluation {second}")), "{why}");
            assert_eq!(again, fresh, "kind {kind}: the run after a refused log differs from a fresh one");
            assert_eq!(again.best(), fresh.best());
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
