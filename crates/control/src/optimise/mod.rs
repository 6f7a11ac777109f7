//! Derivative-free optimisers over a box of parameters (spec §7): the thesis's random modifier and
//! staged greedy search, CMA-ES with IPOP restarts, and random search and simulated annealing as
//! baselines.
//!
//! Every optimiser is an ask/tell state machine ([`Optimiser`]) that owns a `ChaCha8Rng` seeded by
//! the caller. [`run`] asks for a generation (all candidates drawn sequentially from that rng),
//! evaluates it in parallel with rayon, and tells the fitnesses back in candidate order, so a run is
//! bit-identical for any number of threads. Fitness is *larger is better*, as in the thesis; to
//! minimise a cost, maximise its negative.
//!
//! Every evaluation goes to a [`RunLog`] (serde). [`resume`] replays a log into a fresh optimiser
//! built with the same configuration and seed — asking each generation again and telling it the
//! logged fitnesses instead of re-evaluating — which restores the exact state, so a stopped run
//! continued by [`run`] equals an uninterrupted one. A log that does not replay leaves the optimiser
//! to be rebuilt: see [`resume`].
//!
//! A fitness is always a finite number: an evaluation that fails (a fall, a simulation that
//! diverges) is scored with a value — anima's objectives give it 0 — never NaN. [`run`] refuses a
//! non-finite fitness, and [`resume`] a log that holds one.

mod baselines;
mod cmaes;
mod eigen;
mod greedy;
mod modifier;

pub use baselines::{Annealing, AnnealingConfig, RandomSearch};
pub use cmaes::{Cmaes, CmaesConfig};
pub use greedy::{GreedySearch, Stage, StageResult};
pub use modifier::{GroupChoice, Interval, Modifier, propose};

use anima_format::limits::{MAX_EVALUATIONS, MAX_POPULATION};
use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// One dimension of a search space: an admissible interval, possibly whole numbers only.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Dim {
    pub name: String,
    pub min: f64,
    pub max: f64,
    /// Whole numbers (iterations): candidates are rounded.
    pub integer: bool,
}

impl Dim {
    pub fn new(name: &str, min: f64, max: f64) -> Self {
        Self { name: name.to_string(), min, max, integer: false }
    }

    pub fn bounded(&self) -> bool {
        self.min.is_finite() && self.max.is_finite()
    }

    pub fn width(&self) -> f64 {
        self.max - self.min
    }

    /// `v` made admissible: rounded for whole-number dimensions, clamped to [min, max].
    pub fn admit(&self, v: f64) -> f64 {
        let v = if self.integer { v.round() } else { v };
        let (lo, hi) = if self.integer { (self.min.ceil(), self.max.floor()) } else { (self.min, self.max) };
        if lo <= hi { v.clamp(lo, hi) } else { v.clamp(self.min, self.max) }
    }
}

/// A box of parameters.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Space {
    pub dims: Vec<Dim>,
}

impl Space {
    /// `n` unbounded real dimensions (for test functions).
    pub fn unbounded(n: usize) -> Self {
        Self { dims: (0..n).map(|i| Dim::new(&format!("x{i}"), f64::NEG_INFINITY, f64::INFINITY)).collect() }
    }

    /// `n` real dimensions in [min, max].
    pub fn cube(n: usize, min: f64, max: f64) -> Self {
        Self { dims: (0..n).map(|i| Dim::new(&format!("x{i}"), min, max)).collect() }
    }

    pub fn len(&self) -> usize {
        self.dims.len()
    }

    pub fn is_empty(&self) -> bool {
        self.dims.is_empty()
    }

    fn check_bounded(&self, who: &str) -> Result<(), OptimiseError> {
        match self.dims.iter().position(|d| !d.bounded() || d.min > d.max) {
            Some(i) => {
                Err(OptimiseError::Unbounded { optimiser: who.to_string(), dim: self.dims[i].name.clone() })
            }
            None => Ok(()),
        }
    }
}

/// A configuration an optimiser cannot run with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OptimiseError {
    #[error("{optimiser} samples its whole interval, but dimension `{dim}` has no finite interval")]
    Unbounded { optimiser: String, dim: String },
    #[error("invalid configuration: {0}")]
    Config(String),
}

/// `Config` error unless `n` (`what`, e.g. "λ") is at most [`MAX_POPULATION`] candidates a generation:
/// checked before anything is allocated for a generation.
fn check_population(what: &str, n: usize) -> Result<(), OptimiseError> {
    if n > MAX_POPULATION {
        return Err(OptimiseError::Config(format!(
            "{what} must be at most {MAX_POPULATION} candidates a generation (anima's limit), found {n}"
        )));
    }
    Ok(())
}

/// What is maximised. Implemented for every `Fn(&[f64]) -> f64 + Sync`.
pub trait Objective: Sync {
    /// The fitness of `x` (larger is better), a finite number. Must be deterministic: the same `x`
    /// gives the same value on any thread. A failed evaluation is a value (the thesis's objectives
    /// give 0 to a walker that falls), not NaN: [`run`] refuses a non-finite fitness.
    fn fitness(&self, x: &[f64]) -> f64;
}

impl<F: Fn(&[f64]) -> f64 + Sync> Objective for F {
    fn fitness(&self, x: &[f64]) -> f64 {
        self(x)
    }
}

/// An ask/tell optimiser.
pub trait Optimiser {
    /// A short name for logs.
    fn name(&self) -> &'static str;

    /// The number of values of a candidate (the dimensions of its space).
    fn dimension(&self) -> usize;

    /// The stage the next generation belongs to (the greedy search's stage, CMA-ES's restart).
    fn stage(&self) -> usize;

    /// The next generation's candidates, every random draw made now, in order. Empty when the
    /// optimiser has finished (its stages are done, or its target or restart limit was reached).
    fn ask(&mut self) -> Vec<Vec<f64>>;

    /// The fitnesses of the generation just asked, in candidate order. Returns, per candidate,
    /// whether it was accepted (became the incumbent or the best so far).
    fn tell(&mut self, candidates: &[Vec<f64>], fitness: &[f64]) -> Vec<bool>;

    /// The best candidate evaluated so far and its fitness.
    fn best(&self) -> Option<(&[f64], f64)>;
}

/// One logged evaluation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Evaluation {
    /// Generation (0-based, counted over the whole run).
    pub generation: usize,
    pub stage: usize,
    pub x: Vec<f64>,
    pub fitness: f64,
    pub accepted: bool,
}

/// Every evaluation of a run, in order.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RunLog {
    pub optimiser: String,
    pub generations: usize,
    pub evaluations: Vec<Evaluation>,
}

impl RunLog {
    /// The best logged evaluation (the first of equals).
    pub fn best(&self) -> Option<&Evaluation> {
        self.evaluations.iter().filter(|e| !e.fitness.is_nan()).fold(
            None,
            |b: Option<&Evaluation>, e| match b {
                Some(b) if e.fitness <= b.fitness => Some(b),
                _ => Some(e),
            },
        )
    }

    pub fn len(&self) -> usize {
        self.evaluations.len()
    }

    pub fn is_empty(&self) -> bool {
        self.evaluations.is_empty()
    }
}

/// A fitness that is not a finite number, refused by [`run`].
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "evaluation {evaluation} (x = {x:?}) has fitness {fitness}: an objective gives a finite number (a \
     failed evaluation is a value, such as 0, never NaN)"
)]
pub struct FitnessError {
    /// Its index in the log, had it been logged.
    pub evaluation: usize,
    pub x: Vec<f64>,
    pub fitness: f64,
}

/// Runs `opt` until it finishes or `log` holds at least `budget` evaluations (a generation is never
/// cut, so the last one may pass the budget). Candidates of a generation are evaluated in parallel
/// on the current rayon pool; results do not depend on the number of threads. Continues an existing
/// log (after [`resume`]). Returns the best candidate and fitness.
///
/// A generation with a fitness that is not finite is refused whole: it is neither told nor logged,
/// and the error names its first such evaluation. `log` then holds every generation before it, and
/// `opt` has asked the refused one: rebuild it and [`resume`] from the log to go on.
pub fn run<O, F>(
    opt: &mut O,
    objective: &F,
    budget: usize,
    log: &mut RunLog,
) -> Result<Option<(Vec<f64>, f64)>, FitnessError>
where
    O: Optimiser + ?Sized,
    F: Objective + ?Sized,
{
    if log.optimiser.is_empty() {
        log.optimiser = opt.name().to_string();
    }
    while log.evaluations.len() < budget {
        let stage = opt.stage();
        let candidates = opt.ask();
        if candidates.is_empty() {
            break;
        }
        let fitness: Vec<f64> = candidates.par_iter().map(|x| objective.fitness(x)).collect();
        if let Some(k) = fitness.iter().position(|f| !f.is_finite()) {
            let evaluation = log.evaluations.len() + k;
            return Err(FitnessError { evaluation, x: candidates[k].clone(), fitness: fitness[k] });
        }
        let accepted = opt.tell(&candidates, &fitness);
        let generation = log.generations;
        for ((x, f), a) in candidates.into_iter().zip(fitness).zip(accepted) {
            log.evaluations.push(Evaluation { generation, stage, x, fitness: f, accepted: a });
        }
        log.generations += 1;
    }
    Ok(opt.best().map(|(x, f)| (x.to_vec(), f)))
}

/// A log that does not replay into the given optimiser.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ResumeError {
    #[error("the log was written by `{logged}`, not `{this}`")]
    Optimiser { logged: String, this: String },
    #[error(
        "evaluation {evaluation} of the log differs from what the optimiser asks: another seed or \
         configuration"
    )]
    Mismatch { evaluation: usize },
    #[error("the log ends inside a generation (evaluation {evaluation})")]
    Partial { evaluation: usize },
    #[error("the optimiser finished before the log's evaluation {evaluation}")]
    Finished { evaluation: usize },
    #[error("evaluation {evaluation} of the log has fitness {fitness}; a fitness is a finite number")]
    Fitness { evaluation: usize, fitness: f64 },
    #[error(
        "evaluation {evaluation} of the log has {found} values, not finite or not the optimiser's {dimension}"
    )]
    Point { evaluation: usize, found: usize, dimension: usize },
    #[error("evaluation {evaluation} of the log is in generation {generation}, expected {expected}")]
    Generation { evaluation: usize, generation: usize, expected: String },
    #[error("the log counts {counted} generations but its evaluations are in {found}")]
    Generations { counted: usize, found: usize },
}

/// What [`resume`] checks before it touches the optimiser: every fitness finite, every point of
/// `dimension` finite values, generations counted from 0 up by one, the log's count of them right.
fn check_log(log: &RunLog, dimension: usize) -> Result<(), ResumeError> {
    let mut previous: Option<usize> = None;
    for (i, e) in log.evaluations.iter().enumerate() {
        if !e.fitness.is_finite() {
            return Err(ResumeError::Fitness { evaluation: i, fitness: e.fitness });
        }
        if e.x.len() != dimension || e.x.iter().any(|v| !v.is_finite()) {
            return Err(ResumeError::Point { evaluation: i, found: e.x.len(), dimension });
        }
        let ok = match previous {
            None => e.generation == 0,
            Some(g) => e.generation == g || Some(e.generation) == g.checked_add(1),
        };
        if !ok {
            let expected = previous.map_or("0".to_string(), |g| format!("{g} or {}", g.saturating_add(1)));
            return Err(ResumeError::Generation { evaluation: i, generation: e.generation, expected });
        }
        previous = Some(e.generation);
    }
    let found = previous.map_or(0, |g| g.saturating_add(1));
    if log.generations != found {
        return Err(ResumeError::Generations { counted: log.generations, found });
    }
    Ok(())
}

/// Replays `log` into `opt`, which must be freshly built with the configuration and seed of the
/// logged run: each generation is asked again (checked bit for bit against the log) and told the
/// logged fitnesses. Afterwards [`run`] with the same log continues exactly where it stopped.
///
/// The whole log is checked first, without touching `opt`: the optimiser's name, every fitness
/// finite, every point of the optimiser's dimension and finite, generations counted from 0 up by one
/// (see [`ResumeError`]). What can only be found by asking — a generation that differs from the
/// log ([`ResumeError::Mismatch`]), a log that ends inside a generation or goes on after the
/// optimiser finished — is found after the generations before it were replayed into `opt`. So on
/// any error, **rebuild the optimiser** (the same configuration and seed) before running it: a run
/// from the rebuilt one equals a fresh run.
pub fn resume<O: Optimiser + ?Sized>(opt: &mut O, log: &RunLog) -> Result<(), ResumeError> {
    if !log.optimiser.is_empty() && log.optimiser != opt.name() {
        return Err(ResumeError::Optimiser { logged: log.optimiser.clone(), this: opt.name().to_string() });
    }
    check_log(log, opt.dimension())?;
    let mut i = 0;
    let mut generation = 0;
    while i < log.evaluations.len() {
        let candidates = opt.ask();
        if candidates.is_empty() {
            return Err(ResumeError::Finished { evaluation: i });
        }
        let n = candidates.len();
        if i + n > log.evaluations.len() {
            return Err(ResumeError::Partial { evaluation: i });
        }
        let logged = &log.evaluations[i..i + n];
        for (k, (c, e)) in candidates.iter().zip(logged).enumerate() {
            let same = c.len() == e.x.len() && c.iter().zip(&e.x).all(|(a, b)| a.to_bits() == b.to_bits());
            if !same || e.generation != generation {
                return Err(ResumeError::Mismatch { evaluation: i + k });
            }
        }
        let fitness: Vec<f64> = logged.iter().map(|e| e.fitness).collect();
        opt.tell(&candidates, &fitness);
        i += n;
        generation += 1;
    }
    Ok(())
}

/// Standard normal draws by the Box–Muller transform (no dependency beyond rand; the second value
/// of each pair is kept for the next call).
#[derive(Debug, Clone, Default)]
pub(crate) struct Normal {
    spare: Option<f64>,
}

impl Normal {
    pub fn sample(&mut self, rng: &mut ChaCha8Rng) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let u1 = loop {
            let u: f64 = rng.random();
            if u > 0.0 {
                break u;
            }
        };
        let u2: f64 = rng.random();
        let r = (-2.0 * u1.ln()).sqrt();
        let th = std::f64::consts::TAU * u2;
        self.spare = Some(r * th.sin());
        r * th.cos()
    }
}

/// A uniform draw in [lo, hi].
pub(crate) fn uniform(rng: &mut ChaCha8Rng, lo: f64, hi: f64) -> f64 {
    let u: f64 = rng.random();
    lo + (hi - lo) * u
}

/// `u` mirrored back into [lo, hi] as often as needed (either bound may be infinite).
pub(crate) fn reflect(u: f64, lo: f64, hi: f64) -> f64 {
    match (lo.is_finite(), hi.is_finite()) {
        (true, true) => {
            let w = hi - lo;
            if w <= 0.0 {
                return lo;
            }
            let mut y = (u - lo).rem_euclid(2.0 * w);
            if y > w {
                y = 2.0 * w - y;
            }
            lo + y
        }
        (true, false) if u < lo => 2.0 * lo - u,
        (false, true) if u > hi => 2.0 * hi - u,
        _ => u,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflection_stays_inside() {
        assert_eq!(reflect(1.25, 0.0, 1.0), 0.75);
        assert_eq!(reflect(-0.25, 0.0, 1.0), 0.25);
        assert!((reflect(3.3, 0.0, 1.0) - 0.7).abs() < 1e-12);
        assert_eq!(reflect(-3.0, -1.0, f64::INFINITY), 1.0);
        assert_eq!(reflect(5.0, f64::NEG_INFINITY, f64::INFINITY), 5.0);
    }

    #[test]
    fn normal_draws_have_unit_variance() {
        use rand::SeedableRng;
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let mut n = Normal::default();
        let xs: Vec<f64> = (0..20000).map(|_| n.sample(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64;
        assert!(mean.abs() < 0.03 && (var - 1.0).abs() < 0.05, "mean {mean}, var {var}");
    }
}
