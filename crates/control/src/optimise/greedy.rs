//! The thesis's optimiser (Nunes 2006 §5.4.3, spec §7.5): stages run in sequence from the previous
//! stage's winner; each evaluation perturbs the incumbent with the stage's random modifier, and a
//! candidate is kept only if its fitness is *strictly* better (Table 6.3 rejects ties).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::{
    Interval, MAX_EVALUATIONS, Modifier, OptimiseError, Optimiser, Space, check_population, propose,
};

/// One stage: which dimensions, how many evaluations, which modifier.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stage {
    pub name: String,
    /// Indices into the space of the dimensions this stage may change.
    pub dims: Vec<usize>,
    /// At most [`MAX_EVALUATIONS`](anima_format::limits::MAX_EVALUATIONS).
    pub evaluations: usize,
    pub modifier: Modifier,
    /// Candidates drawn per generation for the local modifiers, all from the incumbent at the start of
    /// the generation and then accepted in order. 1 (the thesis) makes every candidate a perturbation
    /// of the latest incumbent; more evaluates in parallel at the cost of that. A global stage ignores
    /// it: its candidates do not depend on the incumbent, so the whole stage is one generation with
    /// the same result. At most [`MAX_POPULATION`](anima_format::limits::MAX_POPULATION).
    pub batch: usize,
}

impl Stage {
    /// Every dimension in `dims` drawn in its whole interval, `evaluations` times.
    pub fn global(name: &str, dims: Vec<usize>, evaluations: usize) -> Self {
        Self { name: name.to_string(), dims, evaluations, modifier: Modifier::Global, batch: 1 }
    }

    /// One dimension of `dims` per evaluation, drawn in `interval`.
    pub fn local_single(name: &str, dims: Vec<usize>, evaluations: usize, interval: Interval) -> Self {
        Self {
            name: name.to_string(),
            dims,
            evaluations,
            modifier: Modifier::LocalSingle(interval),
            batch: 1,
        }
    }
}

/// How a stage ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageResult {
    /// The 1-based evaluation of the stage that became its winner; `None` when none beat the
    /// incumbent the stage started from.
    pub winner: Option<usize>,
    pub x: Vec<f64>,
    pub fitness: f64,
}

/// The staged greedy stochastic search. The first generation is the initial point alone (the
/// "Initial" row of Table 6.3); then the stages in order.
#[derive(Debug, Clone)]
pub struct GreedySearch {
    space: Space,
    stages: Vec<Stage>,
    x: Vec<f64>,
    f: Option<f64>,
    stage: usize,
    done: usize,
    winner: Option<usize>,
    results: Vec<StageResult>,
    rng: ChaCha8Rng,
}

impl GreedySearch {
    pub fn new(space: Space, stages: Vec<Stage>, x0: Vec<f64>, seed: u64) -> Result<Self, OptimiseError> {
        if x0.len() != space.len() {
            return Err(OptimiseError::Config(format!(
                "the initial point has {} values for {} dimensions",
                x0.len(),
                space.len()
            )));
        }
        for (k, st) in stages.iter().enumerate() {
            if st.evaluations > MAX_EVALUATIONS {
                return Err(OptimiseError::Config(format!(
                    "stage {k} must have at most {MAX_EVALUATIONS} evaluations (anima's limit), found {}",
                    st.evaluations
                )));
            }
            check_population(&format!("stage {k}'s batch"), st.batch)?;
            let dims: Vec<usize> = match &st.modifier {
                Modifier::LocalSubset { groups, .. } => groups.iter().flatten().copied().collect(),
                _ => st.dims.clone(),
            };
            if let Some(&d) = dims.iter().find(|&&d| d >= space.len()) {
                return Err(OptimiseError::Config(format!(
                    "stage {k} names dimension {d} of {}",
                    space.len()
                )));
            }
            for &d in &dims {
                let dim = &space.dims[d];
                if !dim.bounded() {
                    return Err(OptimiseError::Unbounded {
                        optimiser: "greedy".into(),
                        dim: dim.name.clone(),
                    });
                }
            }
        }
        Ok(Self {
            space,
            stages,
            x: x0,
            f: None,
            stage: 0,
            done: 0,
            winner: None,
            results: Vec::new(),
            rng: ChaCha8Rng::seed_from_u64(seed),
        })
    }

    /// The incumbent and its fitness (`None` before the initial evaluation).
    pub fn incumbent(&self) -> (&[f64], Option<f64>) {
        (&self.x, self.f)
    }

    /// The stages finished so far.
    pub fn results(&self) -> &[StageResult] {
        &self.results
    }

    pub fn finished(&self) -> bool {
        self.f.is_some() && self.stage >= self.stages.len()
    }

    fn close_empty_stages(&mut self) {
        while self.stage < self.stages.len() && self.done >= self.stages[self.stage].evaluations {
            let f = self.f.unwrap_or(f64::NEG_INFINITY);
            self.results.push(StageResult { winner: self.winner, x: self.x.clone(), fitness: f });
            self.stage += 1;
            self.done = 0;
            self.winner = None;
        }
    }
}

impl Optimiser for GreedySearch {
    fn name(&self) -> &'static str {
        "greedy"
    }

    fn dimension(&self) -> usize {
        self.space.len()
    }

    fn stage(&self) -> usize {
        self.stage
    }

    fn ask(&mut self) -> Vec<Vec<f64>> {
        if self.f.is_none() {
            return vec![self.x.clone()];
        }
        let Some(st) = self.stages.get(self.stage) else { return Vec::new() };
        let remaining = st.evaluations - self.done;
        let k = match st.modifier {
            Modifier::Global => remaining,
            _ => st.batch.max(1).min(remaining),
        };
        (0..k)
            .map(|j| {
                let i = self.done + j + 1;
                propose(&st.modifier, &self.space, &st.dims, &self.x, i, st.evaluations, &mut self.rng)
            })
            .collect()
    }

    /// Strict improvement, in candidate order. Also accepts candidates that were not asked (a replay
    /// of a recorded trace such as Table 6.3): only the fitness decides.
    fn tell(&mut self, candidates: &[Vec<f64>], fitness: &[f64]) -> Vec<bool> {
        assert_eq!(candidates.len(), fitness.len(), "one fitness per candidate");
        let mut accepted = Vec::with_capacity(candidates.len());
        for (c, &f) in candidates.iter().zip(fitness) {
            let f = if f.is_nan() { f64::NEG_INFINITY } else { f };
            match self.f {
                None => {
                    self.x.clone_from(c);
                    self.f = Some(f);
                    accepted.push(true);
                }
                Some(best) => {
                    self.done += 1;
                    let ok = f > best;
                    if ok {
                        self.x.clone_from(c);
                        self.f = Some(f);
                        self.winner = Some(self.done);
                    }
                    accepted.push(ok);
                }
            }
            self.close_empty_stages();
        }
        accepted
    }

    fn best(&self) -> Option<(&[f64], f64)> {
        self.f.map(|f| (self.x.as_slice(), f))
    }
}
