//! `cargo xtask`: reproduce the thesis experiments beside the thesis's own numbers and regenerate every
//! figure in `docs/figures/`.

mod bench;
mod figures;
mod nunes;
mod nunes_figures;
mod nunes_optimisers;
mod oliveira;
mod oliveira_adaptive;
mod oliveira_implicit;
mod reproduce;

use std::path::PathBuf;

use anyhow::Result;
use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(name = "xtask", about = "anima project tasks")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Re-run a thesis experiment and print the thesis's numbers beside ours:
    /// table-4-1, e-2 … e-8, or all (which also writes docs/reproduction/flex3d-results.md).
    /// Oliveira 2013's drapes on static meshes: oliveira-1, oliveira-2, oliveira-3, or oliveira (all three,
    /// which also writes docs/reproduction/oliveira-results.md); oliveira-implicit: the fine drapes with
    /// implicit integrators against a converged reference (docs/reproduction/oliveira-implicit.md).
    /// Nunes 2006's controllers: nunes-walk, nunes-throw, nunes-flip, or nunes (all, which also writes
    /// docs/reproduction/nunes-results.md); beyond the thesis: nunes-optimisers (four optimisers over
    /// --seeds seeds, docs/reproduction/nunes-optimisers.md), nunes-robust (CMA-ES over pushes,
    /// assets/controllers/walk-robust.ron) and nunes-simbicon (the same with balance feedback,
    /// docs/reproduction/nunes-simbicon.md, assets/controllers/walk-simbicon.ron).
    Reproduce {
        experiment: String,
        /// Friction reading for the scene experiments: literal (default) or viscous.
        #[arg(long, default_value = "literal")]
        friction: String,
        /// With oliveira[-N]: the adaptive runs (uniform meshes and three remeshers), written to
        /// docs/reproduction/oliveira-adaptive.md.
        #[arg(long)]
        adaptive: bool,
        /// With nunes-optimisers: seeds per optimiser (default 10); with nunes-simbicon: CMA-ES seeds
        /// per form (default 5).
        #[arg(long)]
        seeds: Option<usize>,
    },
    /// Regenerate every reference plot and figure scene into docs/figures/ (a few minutes);
    /// `--only nunes` draws only the controller figures (strobe pictures and optimiser comparisons).
    Figures {
        #[arg(long)]
        only: Option<String>,
    },
    /// Speed against error for every integrator, stability limits and the standard sheet: writes
    /// docs/benchmarks.md and its plots (several minutes; --quick skips the smallest steps).
    Bench {
        #[arg(long)]
        quick: bool,
        /// Measure one sheet scene only (standard-32, standard-64, oliveira-32) and print its table
        /// instead of rewriting docs/benchmarks.md.
        #[arg(long)]
        only: Option<String>,
    },
}

/// The repository root (xtask lives one folder below it).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn main() -> Result<()> {
    match Cli::parse().command {
        Command::Reproduce { experiment, adaptive: true, .. } => match experiment.strip_prefix("oliveira") {
            Some(which) => oliveira_adaptive::reproduce(which),
            None => anyhow::bail!("--adaptive applies to oliveira, oliveira-1, oliveira-2 and oliveira-3"),
        },
        Command::Reproduce { experiment, friction, seeds, .. } => {
            reproduce::run(&experiment, &friction, seeds)
        }
        Command::Figures { only } => figures::run(only.as_deref()),
        Command::Bench { quick, only } => bench::run(quick, only.as_deref()),
    }
}
