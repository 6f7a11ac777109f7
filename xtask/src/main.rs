//! `cargo xtask`: reproduce the thesis experiments beside the thesis's own numbers, regenerate every
//! figure in `docs/figures/` and run the benchmarks. Every experiment is a function of `anima-lab`; this
//! binary only parses the command and names the repository the reports are written into.

mod test;

use anima_cloth::flex3d::FrictionMode;
use anima_lab::repo::Repo;
use anima_lab::{bench, figures, flex3d, nunes, oliveira};
use anyhow::{Result, bail};
use clap::{Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(name = "xtask", about = "anima project tasks")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The friction reading of the FLEX3D experiments.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum Friction {
    /// A fraction of the resultant force, against the motion (the thesis's text).
    Literal,
    /// −μv (the viscous reading).
    Viscous,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Re-run a thesis experiment and print the thesis's numbers beside ours, writing its section of the
    /// report (a partial run rewrites only its own sections).
    ///
    /// FLEX3D (docs/reproduction/flex3d-results.md): table-4-1, e-1 … e-8, or all.
    /// Oliveira 2013 (oliveira-results.md): oliveira-1, oliveira-2, oliveira-3, oliveira-choices (the
    /// scenes and what the switches for the open choices change), or oliveira (all four); with
    /// --adaptive the remeshers (oliveira-adaptive.md); oliveira-implicit: the fine drapes with implicit
    /// integrators (oliveira-implicit.md); membrane: mesh convergence of the spring models and of the
    /// continuum membrane (membrane.md).
    /// Nunes 2006 (nunes-results.md): nunes-walk, nunes-throw, nunes-flip, or nunes; beyond the thesis:
    /// nunes-walk-faithful (the actuation readings scanned for a walker that falls before the thesis's
    /// search and walks after it; nunes-walk-faithful.md, about two minutes),
    /// nunes-robustness (SIMBICON's push, slopes and steps on every committed walker;
    /// nunes-robustness.md), nunes-optimisers (four optimisers over --seeds seeds), nunes-robust (CMA-ES over pushes,
    /// assets/controllers/walk-robust.ron), nunes-simbicon (the same with balance feedback) and
    /// nunes-simbicon-faithful (SIMBICON as published, unoptimised; nunes-simbicon.md) and
    /// nunes-protocol (CMA-ES for pushes, slopes, steps and 1 m/s, both walker forms over --seeds
    /// seeds; nunes-protocol.md), nunes-slopes (the protocol walker's slope gains, over --seeds
    /// seeds, default 3; nunes-slopes.md) and nunes-speeds (walkers for 0.5, 1.0 and 1.5 m/s, over
    /// --seeds seeds, default 2; nunes-speeds.md).
    Reproduce {
        experiment: String,
        /// Friction reading for the FLEX3D experiments (the report holds the literal reading's results;
        /// with viscous they are printed only).
        #[arg(long, value_enum, default_value_t = Friction::Literal)]
        friction: Friction,
        /// With oliveira[-N]: the adaptive runs (uniform meshes and three remeshers).
        #[arg(long)]
        adaptive: bool,
        /// With nunes-optimisers: seeds per optimiser (default 10); with nunes-simbicon: CMA-ES seeds
        /// per form (default 5).
        #[arg(long)]
        seeds: Option<usize>,
    },
    /// Regenerate every reference plot and figure scene into docs/figures/ (a few minutes); `--only`
    /// draws one group: flex3d, oliveira or nunes.
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
        /// Instead: time anima beside the peers (Warp, MuJoCo) on the standard scenes, alternately in one
        /// run, and write docs/benchmarks-peers.md. Needs ANIMA_PEERS (the peers' script folder) and a
        /// Python with them (ANIMA_PEERS_PYTHON); installs nothing, and without them times anima alone.
        #[arg(long)]
        peers: bool,
        /// Instead: cloth at the size users simulate (the standard sheet at N = 64–256, the Bunny and
        /// sphere drapes at 65²–257² vertices, 1/60 s): cost per particle-step on one core and every core,
        /// where a step's time goes, contact and crossings at every step, errors against converged runs,
        /// the peers of bench/peers/ (when ANIMA_PEERS_PYTHON names their Python) and the explicit sheet's
        /// stability estimate; writes docs/benchmarks-scale.md (about half an hour; --quick: up to 129²).
        #[arg(long)]
        scale: bool,
    },
    /// Every test: the Rust workspace's, the glTF validator's, `anima view` in headless Chromium and the
    /// Python package's (pytest, with a local Ray cluster). Installs what it needs under target/ (npm's
    /// gltf-validator, a Python virtual environment) and, as root, Debian's chromium when it is missing.
    /// --rust, --gltf, --viewer, --python run only those parts.
    Test {
        #[arg(long)]
        rust: bool,
        #[arg(long)]
        gltf: bool,
        #[arg(long)]
        viewer: bool,
        #[arg(long)]
        python: bool,
    },
}

fn reproduce(
    repo: &Repo,
    experiment: &str,
    friction: Friction,
    adaptive: bool,
    seeds: Option<usize>,
) -> Result<()> {
    if adaptive {
        return match experiment.strip_prefix("oliveira") {
            Some(which) => oliveira::adaptive::reproduce(repo, which),
            None => bail!("--adaptive applies to oliveira, oliveira-1, oliveira-2 and oliveira-3"),
        };
    }
    match experiment {
        "oliveira-implicit" => return oliveira::implicit::reproduce(repo),
        "membrane" => return oliveira::membrane::reproduce(repo),
        "nunes-optimisers" => {
            print!("{}", nunes::optimisers::optimisers(repo, seeds.unwrap_or(10))?);
            return Ok(());
        }
        "nunes-simbicon" => {
            print!("{}", nunes::optimisers::simbicon(repo, seeds.unwrap_or(5))?);
            return Ok(());
        }
        "nunes-walk-faithful" => return nunes::faithful_walk::reproduce(repo),
        "nunes-robustness" => return nunes::robustness::reproduce(repo),
        "nunes-simbicon-faithful" => {
            print!("{}", nunes::faithful::reproduce(repo)?);
            return Ok(());
        }
        "nunes-protocol" => return nunes::protocol::reproduce(repo, seeds.unwrap_or(5)),
        "nunes-slopes" => return nunes::protocol::reproduce_slopes(repo, seeds.unwrap_or(3)),
        "nunes-speeds" => return nunes::speeds::reproduce(repo, seeds.unwrap_or(2)),
        "nunes-robust" => {
            print!("{}", nunes::optimisers::robust(repo)?);
            return Ok(());
        }
        _ => {}
    }
    if let Some(which) = experiment.strip_prefix("oliveira") {
        return oliveira::drapes::reproduce(repo, which);
    }
    if let Some(which) = experiment.strip_prefix("nunes") {
        return nunes::report::reproduce(repo, which);
    }
    let friction = match friction {
        Friction::Literal => FrictionMode::Literal,
        Friction::Viscous => FrictionMode::Viscous,
    };
    let (doc, failed) = flex3d::report::reproduce(experiment, friction)?;
    for (_, text) in flex3d::report::EXPERIMENTS.iter().filter_map(|e| doc.get(e).map(|t| (e, t))) {
        print!("{text}\n\n");
    }
    // The committed report is the literal reading's; another reading is printed only.
    if matches!(friction, FrictionMode::Literal) {
        repo.write_report("reproduction/flex3d-results.md", &doc)?;
        flex3d::report::write_narrative(repo, &doc)?;
    }
    if !failed.is_empty() {
        bail!("criteria did not hold for: {}", failed.join(", "));
    }
    Ok(())
}

fn main() -> Result<()> {
    let repo = Repo::here();
    match Cli::parse().command {
        Command::Reproduce { experiment, friction, adaptive, seeds } => {
            reproduce(&repo, &experiment, friction, adaptive, seeds)
        }
        Command::Figures { only } => figures::all(&repo, only.as_deref()),
        Command::Bench { peers: true, .. } => {
            // The binary a user runs, built as they build it.
            let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
            let status = std::process::Command::new(cargo)
                .args(["build", "--release", "--quiet", "-p", "anima-cli"])
                .current_dir(repo.root())
                .status()?;
            anyhow::ensure!(status.success(), "building anima failed");
            let target = std::env::var_os("CARGO_TARGET_DIR")
                .map_or_else(|| repo.root().join("target"), std::path::PathBuf::from);
            anima_lab::peers::run(&repo, &target.join("release/anima"))
        }
        Command::Bench { scale: true, quick, .. } => {
            anima_lab::scale::run(&repo, anima_lab::scale::ScaleOptions { quick })
        }
        Command::Bench { quick, only, .. } => bench::run(&repo, quick, only.as_deref()),
        Command::Test { rust, gltf, viewer, python } => {
            let all = !(rust || gltf || viewer || python);
            test::run(
                repo.root(),
                test::Parts {
                    rust: rust || all,
                    gltf: gltf || all,
                    viewer: viewer || all,
                    python: python || all,
                },
            )
        }
    }
}
