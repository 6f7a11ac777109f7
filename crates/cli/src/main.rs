//! `anima`: run any scene, optimise a controller, convert a FLEX3D script.

mod live;
mod progress;

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use anima_cloth::contact_mode::ContactMode;
use anima_cloth::flex3d::{ContactApproach, FLEX3D_GRAVITY, FrictionMode, StaticResponse};
use anima_cloth::self_collision::SelfCollisionMode;
use anima_geom::DVec3;
use anima_ode::{Integrator, LinearSolver};
use anima_run::optimise::{OptimiseOptions, optimise};
use anima_run::run::{
    Detail, Export, Flex3dSwitches, Overrides, RunOptions, SolveOptions, Summary, write_summary,
};
use anima_scene::{LoadOptions, LoadedFlex3d, Scene};
use anyhow::{Context, Result};
use clap::builder::PossibleValue;
use clap::{Parser, Subcommand, ValueEnum};

use crate::progress::Bar;

/// Physically based animation: FLEX3D surfaces, Oliveira cloth, articulated characters.
#[derive(Debug, Parser)]
#[command(
    name = "anima",
    version,
    about,
    after_help = "Exit status: 0 when the command did what was asked; 1 for bad input (a scene, spec or option \
                  that cannot be used, an output that cannot be written: the message names the file, line and \
                  column); 2 when a run diverged (it stopped at the first non-finite value and says where).\n\n\
                  Limits (anima_format::limits; larger is refused where it is written): 4000000 particles a \
                  scene, 1e9 steps and 1e6 frames a run, 256 MiB a file, 1e6 m for an object's size or \
                  position, 1000 bodies or joints a skeleton, 10000 states, actuators or sensors a \
                  controller, 10000 candidates a generation, 1000000 evaluations an optimisation, 256 corners \
                  an OBJ face."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate a scene and write its frames, pictures and a JSON summary.
    ///
    /// Every kind of scene runs: a FLEX3D script (.par) or scene (Flex3dScene), a spring-network sheet
    /// (SheetScene), an Oliveira drape (OliveiraScene, AdaptiveOliveiraScene), figures holding poses
    /// (BodyScene) and figures driven by a controller (CharacterScene). Without a scene file, runs the
    /// built-in default: the FLEX3D tablecloth falling on a table (Nedel 1993, Fig. A2.8).
    Run(RunArgs),
    /// Optimise a controller from a spec (Optimisation): its objective over its free parameters, with
    /// its optimiser and seed. The log is written after every generation and an interrupted run resumes
    /// from it; the best controller is written as RON.
    Optimise(OptimiseArgs),
    /// Play a finished run in the browser: serves, on 127.0.0.1 only, a page with the run's
    /// animation.glb (play, pause, a timeline, an orbit camera) and plots of its frames beside it.
    ///
    /// The folder is one `anima run SCENE --out DIR --export gltf` wrote; the server only reads it.
    /// Open the address it prints; Ctrl-C ends it.
    View(ViewArgs),
    /// Convert a FLEX3D .PAR script to the equivalent anima RON scene.
    Convert {
        /// The .PAR script.
        input: PathBuf,
        /// Where to write the RON scene (default: the input with a .ron extension). Never the input.
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Overwrite the output file when it exists.
        #[arg(long)]
        force: bool,
        /// Gravity to record in the scene: on (0, −9.8, 0), off, or gx,gy,gz.
        #[arg(long, value_parser = parse_gravity)]
        gravity: Option<DVec3>,
    },
}

#[derive(Debug, clap::Args)]
struct ViewArgs {
    /// The run's output folder (with its animation.glb and summary.json).
    dir: PathBuf,
    /// The port on 127.0.0.1 (0: any free port; the address is printed).
    #[arg(long, default_value_t = 8410)]
    port: u16,
}

/// A time-stepping method (see `anima_ode::Integrator`).
#[derive(Debug, Clone, Copy)]
struct IntegratorArg(Integrator);

impl ValueEnum for IntegratorArg {
    fn value_variants<'a>() -> &'a [Self] {
        const ALL: [IntegratorArg; Integrator::ALL.len()] = {
            let mut out = [IntegratorArg(Integrator::ForwardEuler); Integrator::ALL.len()];
            let mut k = 0;
            while k < out.len() {
                out[k] = IntegratorArg(Integrator::ALL[k]);
                k += 1;
            }
            out
        };
        &ALL
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.0.name()).help(integrator_help(self.0)))
    }
}

/// One line of meaning per integrator for `--help`.
fn integrator_help(i: Integrator) -> &'static str {
    match i {
        Integrator::ForwardEuler => {
            "forward Euler as FLEX3D ran it (position from the old velocity; Table 4.1)"
        }
        Integrator::SymplecticEuler => "semi-implicit Euler: velocity first, then position (first order)",
        Integrator::Midpoint => "explicit midpoint, second-order Runge–Kutta",
        Integrator::Rk4 => "classical fourth-order Runge–Kutta",
        Integrator::DormandPrince => "Dormand–Prince 5(4) with error-controlled steps",
        Integrator::AdamsBashforth4 => "Adams–Bashforth 4, started by RK4",
        Integrator::AdamsBashforthMoulton4 => "Adams–Bashforth–Moulton 4 predictor–corrector",
        Integrator::AdaptiveEuler => "forward Euler with the thesis's adaptive step rule",
        Integrator::ImplicitEuler => "backward Euler (Baraff–Witkin): stable at any step, damps motion",
        Integrator::Bdf2 => "second-order backward differentiation: stable, less damping than backward Euler",
        Integrator::GeneralizedAlpha => {
            "generalised-α: second order, damps only what a step cannot resolve; accurate at large steps"
        }
    }
}

/// The linear solver of the implicit integrators.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum SolverArg {
    /// Conjugate gradients, block-Jacobi preconditioned: cheap per iteration.
    Cg,
    /// faer's sparse Cholesky: exact whatever the stiffness.
    Cholesky,
    /// Conjugate gradients with a factorised two-level preconditioner kept across steps.
    TwoLevel,
    /// Conjugate gradients preconditioned by the rigid motions of small patches (generalised-α's
    /// default).
    Aggregation,
}

/// Where contact with static objects is answered.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum ContactModeArg {
    /// After the integrator's step, by the model's own response (the theses' split).
    AfterStep,
    /// Inside generalised-α's implicit solve: constrained normal velocity, Coulomb friction.
    InSolve,
}

/// How the cloth is kept from passing through itself.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum SelfCollisionArg {
    /// The thesis's response: FLEX3D's swept particle–triangle test with its elastic impact (it leaves
    /// crossings once a sheet folds); none for the Oliveira cloth, as in its thesis.
    Faithful,
    /// Repulsion, impact impulses and rigid impact zones after each step: no step ends with a crossing.
    Modern,
    /// None: the cloth passes through itself.
    Off,
}

/// An animation of the whole run, written at its end.
#[derive(Debug, Clone, Copy, ValueEnum)]
enum ExportArg {
    /// Animated glTF 2.0 (OUT/animation.glb): cloth as morph targets (a mesh per frame when
    /// remeshed) over the static objects, figures as node hierarchies; metres, y up.
    Gltf,
    /// An animated USD stage in text form (OUT/animation.usda): time-sampled points (and topology when
    /// remeshed), figures' links as time-sampled transforms; metres, y up, a time code per millisecond.
    Usd,
}

/// FLEX3D's friction reading (spec S7.2).
#[derive(Debug, Clone, Copy, ValueEnum)]
enum FrictionArg {
    /// A fraction of the resultant force, against the motion (the thesis's text).
    Literal,
    /// −μv, proportional to the velocity.
    Viscous,
}

/// FLEX3D's particle–surface contact partner (spec S7.2).
#[derive(Debug, Clone, Copy, ValueEnum)]
enum ContactArg {
    /// The nearest vertex of the hit triangle.
    Nearest,
    /// The triangle's three vertices.
    Three,
}

/// FLEX3D's response against static objects (spec S7.2).
#[derive(Debug, Clone, Copy, ValueEnum)]
enum StaticResponseArg {
    /// v ← −v.
    Reverse,
    /// Reflect the normal component only.
    Reflect,
}

#[derive(Debug, clap::Args)]
struct RunArgs {
    /// Scene file (.par or .ron); omit for the built-in tablecloth.
    scene: Option<PathBuf>,
    /// Output folder for frames, pictures and the summary.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Time-stepping method (FLEX3D, sheet and Oliveira scenes).
    #[arg(long, value_enum)]
    integrator: Option<IntegratorArg>,
    /// Linear solver of the implicit integrators.
    #[arg(long, value_enum)]
    linear_solver: Option<SolverArg>,
    /// Generalised-α's spectral radius at infinite frequency, in [0, 1]: how strongly it damps the
    /// modes a step cannot resolve (0: in one step; 1: not at all, the implicit midpoint rule).
    #[arg(long, value_parser = parse_unit)]
    rho_inf: Option<f64>,
    /// Newton iterations per step of generalised-α.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=100))]
    newton_iterations: Option<u32>,
    /// Where contact with static objects is answered (FLEX3D and Oliveira scenes).
    #[arg(long, value_enum)]
    contact_mode: Option<ContactModeArg>,
    /// How the cloth is kept from passing through itself and, with several FLEX3D surfaces, through
    /// one another (FLEX3D and Oliveira scenes; the scene's `self_collision` option, `faithful` when it
    /// names none).
    #[arg(long, value_enum)]
    self_collision: Option<SelfCollisionArg>,
    /// Time step in seconds (overrides the scene's: DELTA_t, dt_s, a drape's step rule, a figure's
    /// control step).
    #[arg(long)]
    dt: Option<f64>,
    /// Simulated duration in seconds (overrides the scene's).
    #[arg(long)]
    duration: Option<f64>,
    /// Where to write the JSON summary (default: OUT/summary.json). A file outside OUT that is
    /// already there is replaced only with --force; a folder, device or FIFO never.
    #[arg(long)]
    summary: Option<PathBuf>,
    /// Replace an existing --summary file outside OUT.
    #[arg(long)]
    force: bool,
    /// Gravity (FLEX3D and Oliveira scenes): on (0, −9.8, 0), off, or gx,gy,gz. A .PAR script without
    /// GRAVIDADE defaults to on.
    #[arg(long, value_parser = parse_gravity)]
    gravity: Option<DVec3>,
    /// FLEX3D: the friction reading.
    #[arg(long, value_enum)]
    friction: Option<FrictionArg>,
    /// FLEX3D: the particle–surface contact partner.
    #[arg(long, value_enum)]
    contact: Option<ContactArg>,
    /// FLEX3D: the response against static objects.
    #[arg(long, value_enum)]
    static_response: Option<StaticResponseArg>,
    /// FLEX3D: read FORÇA_EXTERNA as an acceleration (multiplied by the particle mass).
    #[arg(long)]
    external_is_acceleration: bool,
    /// FLEX3D: apply −F/2 of each angular spring to its two outer particles (momentum-conserving
    /// bending).
    #[arg(long)]
    bend_reaction: bool,
    /// FLEX3D: limit friction so it cannot reverse a velocity within one step (needed at large steps).
    #[arg(long)]
    friction_clamp: bool,
    /// FLEX3D: switch particle–triangle collisions off (an extension; FLEX3D always ran them).
    #[arg(long)]
    no_collisions: bool,
    /// Also write the initial state as frame 0.
    #[arg(long)]
    frame0: bool,
    /// Do not write per-frame files.
    #[arg(long)]
    no_frames: bool,
    /// Do not render pictures.
    #[arg(long)]
    no_pictures: bool,
    /// Also write the whole run as one animation file (every scene kind).
    #[arg(long, value_enum)]
    export: Option<ExportArg>,
    /// No progress bar and no report on standard error.
    #[arg(long, short)]
    quiet: bool,
    /// Sheet scenes: an OBJ of reference positions (such as another run's final.obj); the summary then
    /// reports the RMS distance to it.
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Run on one thread. By default the implicit steps of every cloth use every core, and so does a
    /// sheet from 1 024 particles (32 × 32) with symplectic Euler and from 65 536 (256 × 256) with the
    /// other explicit methods; the results are the same to the bit.
    #[arg(long)]
    one_thread: bool,
    /// Watch and steer the run in the browser while it goes: serves, on 127.0.0.1 only, a page with
    /// the frames as they are computed, the progress and warnings, pause, resume and step one frame,
    /// and for a character a slider per controller parameter (applied at the next control step). The
    /// address is printed; the outputs are written at the end as without it, and the server stops.
    #[arg(long)]
    live: bool,
    /// The port of `--live` on 127.0.0.1 (0: any free port).
    #[arg(long, default_value_t = 8410, requires = "live")]
    port: u16,
    /// With `--live`: start paused after the first frame, until the page says resume or step.
    #[arg(long, requires = "live")]
    paused: bool,
    /// With `--live`: once a page has connected, its closing (the tab closed, the connection dropped)
    /// ends the run as Ctrl-C does: the files written so far stay, whole, the server stops and the exit
    /// status is 130. Without it the run goes on with no page.
    #[arg(long, requires = "live")]
    stop_with_page: bool,
}

#[derive(Debug, clap::Args)]
struct OptimiseArgs {
    /// The optimisation spec (`Optimisation(…)`, e.g. assets/optimisations/walk.ron).
    spec: PathBuf,
    /// Output folder: `<name>.log.ron` after every generation, `<name>.ron` (the best controller) at
    /// the end.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Evaluations in all (overrides the spec's).
    #[arg(long)]
    evaluations: Option<usize>,
    /// Start over, ignoring an earlier log in the output folder.
    #[arg(long)]
    fresh: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

fn parse_unit(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if (0.0..=1.0).contains(&v) => Ok(v),
        _ => Err(format!("expected a number in [0, 1], found `{s}`")),
    }
}

fn parse_gravity(s: &str) -> Result<DVec3, String> {
    match s.to_ascii_lowercase().as_str() {
        "on" => Ok(FLEX3D_GRAVITY),
        "off" => Ok(DVec3::ZERO),
        other => {
            let parts: Vec<f64> = other
                .split(',')
                .map(|p| p.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|e| format!("expected on, off or gx,gy,gz: {e}"))?;
            match parts[..] {
                [x, y, z] if [x, y, z].iter().all(|v| v.is_finite()) => Ok(DVec3::new(x, y, z)),
                _ => Err(format!("expected on, off or three finite comma-separated numbers, found `{s}`")),
            }
        }
    }
}

/// The built-in default scene: the FLEX3D tablecloth (spec E-8) with its reconstructed table.
const DEFAULT_SCENE: &str = include_str!("../scenes/tablecloth.ron");
const DEFAULT_TABLE: &str = include_str!("../scenes/mesa.obt");

fn load_default() -> Result<Scene> {
    let scene = anima_scene::flex3d::from_ron_str(DEFAULT_SCENE).context("the built-in scene")?;
    let table = anima_geom::obt::read_obt(DEFAULT_TABLE.as_bytes(), anima_geom::obt::IndexBase::Auto)
        .context("the built-in table")?
        .to_mesh()?;
    Ok(Scene::Flex3d(LoadedFlex3d { scene, objects: vec![("mesa.obt".into(), table)] }))
}

impl RunArgs {
    fn overrides(&self) -> Overrides {
        Overrides {
            integrator: self.integrator.map(|i| i.0),
            dt: self.dt,
            duration: self.duration,
            // A .PAR script takes gravity when it is read (its GRAVIDADE default is "on").
            gravity: self.gravity,
            contact_mode: self.contact_mode.map(|c| match c {
                ContactModeArg::AfterStep => ContactMode::AfterStep,
                ContactModeArg::InSolve => ContactMode::InSolve,
            }),
            self_collision: self.self_collision.map(|m| match m {
                SelfCollisionArg::Faithful => SelfCollisionMode::Faithful,
                SelfCollisionArg::Modern => SelfCollisionMode::Modern,
                SelfCollisionArg::Off => SelfCollisionMode::Off,
            }),
            flex3d: Flex3dSwitches {
                friction: self.friction.map(|f| match f {
                    FrictionArg::Literal => FrictionMode::Literal,
                    FrictionArg::Viscous => FrictionMode::Viscous,
                }),
                contact: self.contact.map(|c| match c {
                    ContactArg::Nearest => ContactApproach::NearestVertex,
                    ContactArg::Three => ContactApproach::ThreeVertices,
                }),
                static_response: self.static_response.map(|r| match r {
                    StaticResponseArg::Reverse => StaticResponse::Reverse,
                    StaticResponseArg::Reflect => StaticResponse::ReflectNormal,
                }),
                external_is_acceleration: self.external_is_acceleration,
                bend_reaction: self.bend_reaction,
                friction_clamp: self.friction_clamp,
                no_collisions: self.no_collisions,
            },
        }
    }

    fn options(&self) -> Result<RunOptions> {
        let reference = match &self.reference {
            Some(p) => {
                let bytes = anima_scene::read_limited(p)?;
                // Positions only: a frame written without faces, or a point cloud, compares as well.
                let x = anima_geom::read_obj_positions(&bytes[..])
                    .with_context(|| format!("reading {}", p.display()))?;
                Some(x)
            }
            None => None,
        };
        Ok(RunOptions {
            out_dir: Some(self.out.clone()),
            frames: !self.no_frames,
            frame0: self.frame0,
            pictures: !self.no_pictures,
            solve: SolveOptions {
                linear_solver: self.linear_solver.map(|s| match s {
                    SolverArg::Cg => LinearSolver::default_cg(),
                    SolverArg::Cholesky => LinearSolver::SparseCholesky,
                    SolverArg::TwoLevel => LinearSolver::default_two_level(),
                    SolverArg::Aggregation => LinearSolver::default_aggregation(),
                }),
                rho_inf: self.rho_inf,
                newton_iterations: self.newton_iterations.map(|k| k as usize),
            },
            reference,
            export: self.export.map(|e| match e {
                ExportArg::Gltf => Export::Gltf,
                ExportArg::Usd => Export::Usd,
            }),
            parallel: !self.one_thread,
            live: None,
        })
    }
}

fn run_command(args: RunArgs) -> Result<ExitCode> {
    let (mut scene, label) = match &args.scene {
        Some(path) => {
            (anima_scene::load(path, &LoadOptions { gravity: args.gravity })?, path.display().to_string())
        }
        None => (load_default()?, "built-in tablecloth".to_owned()),
    };
    args.overrides().apply(&mut scene)?;
    let opts = args.options()?;
    // Refused before the outputs are looked at (the run checks again, for library callers).
    opts.check(&scene)?;
    let summary_path = args.summary.clone().unwrap_or_else(|| args.out.join("summary.json"));
    // Both outputs are checked before the run spends its time.
    anima_run::output::check_output_path(&summary_path)?;
    // Inside OUT when its folder is OUT or below it, however either is spelled (`./out`, `out/`).
    let in_out = || {
        let parent = summary_path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        std::fs::canonicalize(parent)
            .ok()
            .zip(std::fs::canonicalize(&args.out).ok())
            .is_some_and(|(p, out)| p.starts_with(out))
    };
    if args.summary.is_some() && !args.force && summary_path.exists() && !in_out() {
        anyhow::bail!(
            "{} exists and is not in the output folder {}; pass --force to replace it",
            summary_path.display(),
            args.out.display()
        );
    }
    anima_run::output::check_writable(
        summary_path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new(".")),
    )?;
    if !args.quiet {
        eprintln!("anima: {label} — {}", scene.describe());
    }
    let mut bar = Bar::new(!args.quiet);
    let summary = if args.live {
        run_live(&scene, &label, opts, bar, &args)?
    } else {
        anima_run::run::run(&scene, &label, &opts, &mut bar)?
    };
    write_summary(&summary_path, &summary)?;
    if !args.quiet {
        report(&summary);
        eprintln!("anima: wrote {} and {}", args.out.display(), summary_path.display());
    }
    if let Detail::Flex3d(d) = &summary.detail
        && let Some(nf) = &d.non_finite
    {
        eprintln!(
            "anima: error: the state went non-finite at step {} (t = {} s), surface `{}`, particle ({}, {}); \
             try a smaller --dt or another --integrator",
            nf.step, nf.time, nf.surface, nf.row, nf.col
        );
        return Ok(ExitCode::from(2));
    }
    if let Some(e) = &summary.error {
        eprintln!("anima: error: the run stopped early: {e}");
        if !summary.all_finite {
            eprintln!("anima: try a smaller --dt or another --integrator");
        }
        return Ok(ExitCode::from(2));
    }
    Ok(ExitCode::SUCCESS)
}

/// A run with its live page: the server on its own thread for the run's length. The page is told
/// when the run has ended; the server then stops (`anima view OUT` plays the finished run).
fn run_live(scene: &Scene, label: &str, mut opts: RunOptions, bar: Bar, args: &RunArgs) -> Result<Summary> {
    let params = anima_run::live::scene_parameters(scene);
    let (frames, frames_rx) = anima_view::live::frame_channel();
    let (commands_tx, commands) = anima_view::live::command_channel();
    std::fs::create_dir_all(&args.out).with_context(|| format!("creating {}", args.out.display()))?;
    let view =
        anima_view::Live { params: live::view_params(&params), frames: frames_rx, commands: commands_tx };
    let server = anima_view::Server::bind_live(&args.out, args.port, view)?;
    let stopper = server.stopper();
    // With --stop-with-page, a page that goes away while the run is going stops the server, and the
    // serving thread then ends the run as Ctrl-C does.
    let finished = Arc::new(AtomicBool::new(false));
    let page_gone = Arc::new(AtomicBool::new(false));
    if args.stop_with_page {
        let (finished, page_gone, stopper) = (finished.clone(), page_gone.clone(), stopper.clone());
        server.on_page_closed(move || {
            if !finished.load(Ordering::SeqCst) {
                page_gone.store(true, Ordering::SeqCst);
                stopper.stop();
            }
        });
    }
    let ends = if args.stop_with_page { "Ctrl-C or closing the page ends it" } else { "Ctrl-C ends it" };
    println!("anima run --live: http://{}/ (the page follows the run; {ends})", server.local_addr());
    std::io::stdout().flush()?;
    let serving = std::thread::spawn(move || {
        let served = server.run();
        if page_gone.load(Ordering::SeqCst) {
            eprintln!("\nanima: the page closed");
            interrupted();
        }
        served
    });
    let mut link = anima_run::live::Live::new(live::ViewLink { frames, commands }, params);
    if args.paused {
        link = link.start_paused();
    }
    opts.live = Some(link.clone());
    let mut progress = live::LiveBar::new(bar, link.clone());
    let summary = anima_run::run::run(scene, label, &opts, &mut progress);
    finished.store(true, Ordering::SeqCst);
    let end = match &summary {
        Ok(s) => s.error.clone().unwrap_or_else(|| format!("{} steps, {} frames", s.steps, s.frames)),
        Err(e) => format!("{e:#}"),
    };
    link.link().tell(anima_run::live::done_note(&end));
    // Time for the last frames and the note to reach the page before the server closes its socket.
    std::thread::sleep(std::time::Duration::from_millis(500));
    stopper.stop();
    serving
        .join()
        .map_err(|_| anyhow::anyhow!("the live server panicked"))?
        .context("serving the live page")?;
    summary
}

/// The summary's main numbers on standard error.
fn report(s: &Summary) {
    eprintln!(
        "anima: {} steps, {} frames in {:.2} s ({:.2} s simulating, {:.2} s writing output)",
        s.steps,
        s.frames,
        s.wall_seconds,
        s.wall_seconds - s.output_seconds,
        s.output_seconds
    );
    if let Some(n) = s.self_intersections {
        eprintln!("anima: self-intersections: {n} crossing edge–triangle pairs at the worst frame");
    }
    match &s.detail {
        Detail::Flex3d(d) => eprintln!(
            "anima: {:.0} ns per particle-step; max speed {:.4}, penetrations {}",
            d.ns_per_particle_step, d.max_speed, d.penetrations
        ),
        Detail::Sheet(d) => {
            let c = d.center_of_mass;
            eprintln!(
                "anima: {:.1} ns per particle-step; centre of mass ({:.4}, {:.4}, {:.4}) m, max strain {:.4}",
                d.ns_per_particle_step, c[0], c[1], c[2], d.max_strain
            );
            if let Some(r) = d.rms_to_reference {
                eprintln!("anima: RMS distance to the reference {r:.3e} m");
            }
        }
        Detail::Oliveira(d) => eprintln!(
            "anima: {} → {} particles, {} faces; Δt {:.2e}…{:.2e} s; {} particles inside an object at the end",
            d.particles_at_start, d.particles, d.faces, d.min_dt, d.max_dt, d.penetrations
        ),
        Detail::Body(d) => {
            for m in &d.models {
                eprintln!(
                    "anima: {} ({}, G = {}): head lowest {:.3} m, centre of mass moved {:.3} m; hip {:.4} m (from {:.4})",
                    m.name,
                    m.pd_mode,
                    m.gain_scale,
                    m.min_head_height,
                    m.max_com_drift,
                    m.hip_height_m,
                    m.initial_hip_height_m
                );
            }
            if let Some(e) = &d.evaluation {
                eprintln!("anima: evaluation: {e:?}");
            }
        }
    }
}

fn optimise_command(args: OptimiseArgs) -> Result<ExitCode> {
    let loaded = anima_scene::load_optimisation(&args.spec)?;
    let opts =
        OptimiseOptions { out_dir: args.out.clone(), evaluations: args.evaluations, fresh: args.fresh };
    if !args.quiet {
        eprintln!(
            "anima: {} — optimising `{}` ({:?}), {} evaluations, seed {}",
            args.spec.display(),
            loaded.controller.name(),
            loaded.spec.objective,
            opts.evaluations.unwrap_or(loaded.spec.evaluations),
            loaded.spec.seed
        );
    }
    let mut bar = Bar::new(!args.quiet);
    let out = optimise(&loaded, &opts, &mut bar)?;
    if !args.quiet {
        if out.resumed > 0 {
            eprintln!("anima: resumed after {} logged evaluations", out.resumed);
        }
        eprintln!(
            "anima: best fitness {:.4} (start {:.4}) after {} evaluations at {:?}",
            out.best_fitness,
            out.start_fitness,
            out.log.len(),
            out.best_x
        );
        eprintln!("anima: wrote {} and {}", out.controller_path.display(), out.log_path.display());
    }
    Ok(ExitCode::SUCCESS)
}

fn convert_command(input: &Path, output: Option<PathBuf>, force: bool, gravity: Option<DVec3>) -> Result<()> {
    let out = output.unwrap_or_else(|| input.with_extension("ron"));
    let same = |a: &Path, b: &Path| {
        a == b
            || std::fs::canonicalize(a).ok().zip(std::fs::canonicalize(b).ok()).is_some_and(|(a, b)| a == b)
    };
    if same(input, &out) {
        anyhow::bail!("{}: the output would overwrite the input; name another with -o", out.display());
    }
    anima_run::output::check_output_path(&out)?;
    if out.exists() && !force {
        anyhow::bail!("{} exists; pass --force to overwrite it", out.display());
    }
    let bytes = anima_scene::read_limited(input)?;
    let name = input.display().to_string();
    let ron = anima_scene::convert_par_to_ron(&bytes, &name, gravity.unwrap_or(FLEX3D_GRAVITY))?;
    anima_run::output::write_atomic(&out, |w| Ok(w.write_all(ron.as_bytes())?))?;
    eprintln!("anima: wrote {}", out.display());
    Ok(())
}

/// An error and its causes on one line, each cause said once (a cause that the error's own text already
/// quotes is not repeated).
fn chain(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let c = cause.to_string();
        if !text.contains(&c) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&c);
        }
    }
    text
}

/// Serves the run until Ctrl-C, which ends the server (not the process) so that it closes cleanly.
fn view_command(args: ViewArgs) -> Result<ExitCode> {
    let server = anima_view::Server::bind(&args.dir, args.port)?;
    let stopper = server.stopper();
    ctrlc::set_handler(move || stopper.stop()).context("setting the Ctrl-C handler")?;
    println!("anima view: http://{}/ (Ctrl-C ends it)", server.local_addr());
    std::io::stdout().flush()?;
    server.run().context("serving the run")?;
    eprintln!("anima view: stopped");
    Ok(ExitCode::SUCCESS)
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        // Ctrl-C ends the server, which then returns.
        Command::View(args) => view_command(args),
        command => {
            // An interrupt leaves no half-written temporary file behind; every finished file is whole
            // already.
            let _ = ctrlc::set_handler(|| interrupted());
            match command {
                Command::Run(args) => run_command(args),
                Command::Optimise(args) => optimise_command(args),
                Command::Convert { input, output, force, gravity } => {
                    convert_command(&input, output, force, gravity).map(|()| ExitCode::SUCCESS)
                }
                Command::View(args) => view_command(args),
            }
        }
    };
    exit_code(result)
}

/// Ends the process as an interrupted command: no half-written temporary file left behind (every
/// finished file is whole already), exit status 130. Ctrl-C, and `--live --stop-with-page` when the
/// page goes away.
fn interrupted() -> ! {
    anima_run::output::remove_temporaries();
    eprintln!("\nanima: interrupted");
    std::process::exit(130);
}

/// The exit code of a command's result, its error said on standard error.
fn exit_code(result: Result<ExitCode>) -> ExitCode {
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("anima: error: {}", chain(&e));
            ExitCode::FAILURE
        }
    }
}
