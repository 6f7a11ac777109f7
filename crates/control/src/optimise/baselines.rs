//! Baselines against which the thesis's search and CMA-ES are judged: pure random search and
//! simulated annealing.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::{Normal, OptimiseError, Optimiser, Space, check_population, reflect, uniform};

/// Uniform samples of the whole box, `batch` per generation (at most
/// [`MAX_POPULATION`](anima_format::limits::MAX_POPULATION)); keeps the best.
#[derive(Debug, Clone)]
pub struct RandomSearch {
    space: Space,
    batch: usize,
    rng: ChaCha8Rng,
    best: Option<(Vec<f64>, f64)>,
}

impl RandomSearch {
    pub fn new(space: Space, batch: usize, seed: u64) -> Result<Self, OptimiseError> {
        space.check_bounded("random search")?;
        check_population("a random search's batch", batch)?;
        Ok(Self { space, batch: batch.max(1), rng: ChaCha8Rng::seed_from_u64(seed), best: None })
    }
}

impl Optimiser for RandomSearch {
    fn name(&self) -> &'static str {
        "random"
    }

    fn dimension(&self) -> usize {
        self.space.len()
    }

    fn stage(&self) -> usize {
        0
    }

    fn ask(&mut self) -> Vec<Vec<f64>> {
        (0..self.batch)
            .map(|_| self.space.dims.iter().map(|d| d.admit(uniform(&mut self.rng, d.min, d.max))).collect())
            .collect()
    }

    fn tell(&mut self, candidates: &[Vec<f64>], fitness: &[f64]) -> Vec<bool> {
        candidates
            .iter()
            .zip(fitness)
            .map(|(c, &f)| {
                let better = !f.is_nan() && self.best.as_ref().is_none_or(|(_, b)| f > *b);
                if better {
                    self.best = Some((c.clone(), f));
                }
                better
            })
            .collect()
    }

    fn best(&self) -> Option<(&[f64], f64)> {
        self.best.as_ref().map(|(x, f)| (x.as_slice(), *f))
    }
}

/// Simulated-annealing settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AnnealingConfig {
    pub x0: Vec<f64>,
    /// Initial temperature, in fitness units.
    pub t0: f64,
    /// Temperature factor per generation (T ← cooling · T).
    pub cooling: f64,
    /// Gaussian step, as a fraction of each dimension's width.
    pub step: f64,
    /// Proposals per generation, all from the state at the start of the generation and then
    /// accepted or rejected in order (1 is classical annealing; more evaluates in parallel). At most
    /// [`MAX_POPULATION`](anima_format::limits::MAX_POPULATION).
    pub batch: usize,
}

/// Simulated annealing with Metropolis acceptance: a worse candidate (Δ = f − f_current < 0) is
/// accepted with probability exp(Δ / T).
#[derive(Debug, Clone)]
pub struct Annealing {
    space: Space,
    cfg: AnnealingConfig,
    rng: ChaCha8Rng,
    normal: Normal,
    x: Vec<f64>,
    f: Option<f64>,
    t: f64,
    best: Option<(Vec<f64>, f64)>,
}

impl Annealing {
    pub fn new(space: Space, cfg: AnnealingConfig, seed: u64) -> Result<Self, OptimiseError> {
        space.check_bounded("simulated annealing")?;
        check_population("annealing's batch", cfg.batch)?;
        let t0_ok = cfg.t0 > 0.0 && cfg.t0.is_finite();
        let cooling_ok = cfg.cooling > 0.0 && cfg.cooling <= 1.0;
        if cfg.x0.len() != space.len() || !t0_ok || !cooling_ok {
            return Err(OptimiseError::Config(
                "annealing needs one x0 value per dimension, t0 > 0 and 0 < cooling ≤ 1".into(),
            ));
        }
        if let Some((d, v)) = space.dims.iter().zip(&cfg.x0).find(|(d, v)| !(d.min..=d.max).contains(*v)) {
            return Err(OptimiseError::Config(format!(
                "annealing starts inside the box: x0's `{}` is {v}, outside [{}, {}]",
                d.name, d.min, d.max
            )));
        }
        Ok(Self {
            x: cfg.x0.clone(),
            t: cfg.t0,
            space,
            cfg,
            rng: ChaCha8Rng::seed_from_u64(seed),
            normal: Normal::default(),
            f: None,
            best: None,
        })
    }

    pub fn temperature(&self) -> f64 {
        self.t
    }
}

impl Optimiser for Annealing {
    fn name(&self) -> &'static str {
        "annealing"
    }

    fn dimension(&self) -> usize {
        self.space.len()
    }

    fn stage(&self) -> usize {
        0
    }

    fn ask(&mut self) -> Vec<Vec<f64>> {
        if self.f.is_none() {
            return vec![self.x.clone()];
        }
        (0..self.cfg.batch.max(1))
            .map(|_| {
                self.space
                    .dims
                    .iter()
                    .zip(&self.x)
                    .map(|(d, &x)| {
                        let v = x + self.cfg.step * d.width() * self.normal.sample(&mut self.rng);
                        d.admit(reflect(v, d.min, d.max))
                    })
                    .collect()
            })
            .collect()
    }

    fn tell(&mut self, candidates: &[Vec<f64>], fitness: &[f64]) -> Vec<bool> {
        let mut accepted = Vec::with_capacity(candidates.len());
        for (c, &f) in candidates.iter().zip(fitness) {
            let f = if f.is_nan() { f64::NEG_INFINITY } else { f };
            let ok = match self.f {
                None => true,
                Some(cur) if f >= cur => true,
                Some(cur) => uniform(&mut self.rng, 0.0, 1.0) < ((f - cur) / self.t).exp(),
            };
            if ok {
                self.x.clone_from(c);
                self.f = Some(f);
            }
            if self.best.as_ref().is_none_or(|(_, b)| f > *b) {
                self.best = Some((c.clone(), f));
            }
            accepted.push(ok);
        }
        self.t *= self.cfg.cooling;
        accepted
    }

    fn best(&self) -> Option<(&[f64], f64)> {
        self.best.as_ref().map(|(x, f)| (x.as_slice(), *f))
    }
}
