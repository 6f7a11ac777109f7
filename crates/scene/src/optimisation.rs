//! Optimisation specs (`Optimisation(…)`): which controller to tune, against which of the thesis's
//! objectives, over which of its free parameters, with which optimiser, how many evaluations and which
//! seed (Nunes 2006 §5.4, spec §7). `anima optimise SPEC` runs one; the controller file it names is a
//! part, read once with the spec.

use anima_control::optimise::{AnnealingConfig, Stage};
use anima_control::{Controller, Selection};
use anima_format::limits::{MAX_EVALUATIONS, MAX_POPULATION, MAX_STEPS};
use serde::{Deserialize, Serialize};

/// What an evaluation measures (higher is better).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum ObjectiveSpec {
    /// The walking fitness of spec §7.6 over `iterations` control steps: the distance walked, 0 after a
    /// fall or a stop. The walker is the humanoid with the experiments' actuation (implicit springs,
    /// gains × 100), or with `actuation` (the thesis-faithful walker: gains × 27).
    Walk {
        iterations: u64,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        actuation: Option<anima_body::Actuation>,
    },
    /// Eq. 6.1 for the thesis's basket over `iterations` control steps; with `height_cap` the height
    /// term counts only up to 0.5 m above the aimed point (anima's reading, which keeps the search off
    /// 12 m throws that miss).
    Throw { iterations: u64, height_cap: bool },
}

/// How candidates are drawn.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum OptimiserSpec {
    /// The thesis's staged greedy search (§5.4.3): the stages in order, each from the last one's winner;
    /// `dims` index the selected parameters in the controller's order.
    Greedy { stages: Vec<Stage> },
    /// CMA-ES with IPOP restarts; `sigma0` in units of each parameter's interval width.
    Cmaes { sigma0: f64, lambda: Option<usize>, restarts: usize },
    /// Uniform draws in the box, `batch` per generation.
    RandomSearch { batch: usize },
    /// Simulated annealing (`x0` is the controller's values and may be left empty).
    Annealing(AnnealingConfig),
}

/// An optimisation run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Optimisation", deny_unknown_fields)]
pub struct OptimisationSpec {
    /// The run's name: its log is `<name>.log.ron` and its winner `<name>.ron` in the output folder.
    pub name: String,
    /// The controller file to tune, relative to the spec's folder.
    pub controller: String,
    pub objective: ObjectiveSpec,
    /// The free parameters (written with an interval in the controller file) the search may change.
    pub parameters: Selection,
    pub optimiser: OptimiserSpec,
    /// Evaluations in all, counting the starting point.
    pub evaluations: usize,
    pub seed: u64,
}

impl OptimisationSpec {
    /// The first count of the spec above anima's [limits](crate::limits) — the budget, a greedy
    /// stage's evaluations or batch, CMA-ES's λ, a random search's or annealing's batch, the
    /// objective's iterations — as the field's path and what was expected there; `None` when every
    /// count is within them. Checked before any optimiser is built, so a hostile number is an error
    /// that names its line, never an allocation that aborts or a run that does not end.
    pub fn count_problem(&self) -> Option<(String, String)> {
        let over = |field: String, what: &str, max: String, found: String| {
            Some((field, format!("expected at most {max} {what} (anima's limit), found {found}")))
        };
        let iterations = match self.objective {
            ObjectiveSpec::Walk { iterations, .. } | ObjectiveSpec::Throw { iterations, .. } => iterations,
        };
        // u64 to f64 rounds, but only far above the limit, where it cannot turn a refusal into a run.
        if iterations as f64 > MAX_STEPS {
            return over(
                "objective.iterations".into(),
                "control steps",
                format!("{MAX_STEPS:e}"),
                iterations.to_string(),
            );
        }
        if self.evaluations > MAX_EVALUATIONS {
            return over(
                "evaluations".into(),
                "evaluations",
                MAX_EVALUATIONS.to_string(),
                self.evaluations.to_string(),
            );
        }
        let population = |field: &str, n: usize| {
            if n > MAX_POPULATION {
                over(field.into(), "candidates a generation", MAX_POPULATION.to_string(), n.to_string())
            } else {
                None
            }
        };
        match &self.optimiser {
            OptimiserSpec::Greedy { stages } => stages.iter().enumerate().find_map(|(k, st)| {
                if st.evaluations > MAX_EVALUATIONS {
                    return over(
                        format!("optimiser.stages[{k}].evaluations"),
                        "evaluations",
                        MAX_EVALUATIONS.to_string(),
                        st.evaluations.to_string(),
                    );
                }
                population(&format!("optimiser.stages[{k}].batch"), st.batch)
            }),
            OptimiserSpec::Cmaes { lambda, .. } => population("optimiser.lambda", lambda.unwrap_or(0)),
            OptimiserSpec::RandomSearch { batch } => population("optimiser.batch", *batch),
            OptimiserSpec::Annealing(cfg) => population("optimiser.batch", cfg.batch),
        }
    }
}

/// A spec with its controller.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedOptimisation {
    pub spec: OptimisationSpec,
    pub controller: Controller,
}
