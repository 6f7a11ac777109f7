//! Optimisation specs (`Optimisation(…)`): which controller to tune, against which of the thesis's
//! objectives, over which of its free parameters, with which optimiser, how many evaluations and which
//! seed (Nunes 2006 §5.4, spec §7). `anima optimise SPEC` runs one; the controller file it names is a
//! part, read once with the spec.

use anima_control::optimise::{AnnealingConfig, Stage};
use anima_control::{Controller, Selection};
use serde::{Deserialize, Serialize};

/// What an evaluation measures (higher is better).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum ObjectiveSpec {
    /// The walking fitness of spec §7.6 over `iterations` control steps: the distance walked, 0 after a
    /// fall or a stop.
    Walk { iterations: u64 },
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

/// A spec with its controller.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedOptimisation {
    pub spec: OptimisationSpec,
    pub controller: Controller,
}
