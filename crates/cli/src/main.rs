//! `anima`: run, convert and render scenes.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anima_cloth::flex3d::{ContactApproach, FLEX3D_GRAVITY, FrictionMode, StaticResponse};
use anima_geom::DVec3;
use anima_lab::run::flex3d::{RunOptions, run, write_summary};
use anima_ode::Integrator;
use anima_scene::{LoadOptions, LoadedScene};
use anyhow::{Context, Result, bail};
use clap::{Parser, Subcommand};

/// Physically based animation: FLEX3D surfaces and beyond.
#[derive(Debug, Parser)]
#[command(name = "anima", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Simulate a scene (.par, .ron or a body scene .ron) and write its frames, pictures and a JSON summary.
    ///
    /// Without a scene file, runs the built-in default: the FLEX3D tablecloth falling on a table
    /// (Nedel 1993, Fig. A2.8).
    Run(RunArgs),
    /// Convert a FLEX3D .PAR script to the equivalent anima RON scene.
    Convert {
        /// The .PAR script.
        input: PathBuf,
        /// Where to write the RON scene (default: the input with a .ron extension).
        #[arg(short, long)]
        output: Option<PathBuf>,
        /// Gravity to record in the scene: on (0, −9.8, 0), off, or gx,gy,gz.
        #[arg(long, value_parser = parse_gravity)]
        gravity: Option<DVec3>,
    },
}

#[derive(Debug, clap::Args)]
struct RunArgs {
    /// Scene file (.par or .ron); omit for the built-in tablecloth.
    scene: Option<PathBuf>,
    /// Output folder for frames, pictures and the summary.
    #[arg(long, default_value = "out")]
    out: PathBuf,
    /// Integrator: forward-euler (FLEX3D's), symplectic-euler, midpoint, rk4, dopri5, ab4, abm4,
    /// adaptive-euler, implicit-euler or bdf2.
    #[arg(long)]
    integrator: Option<Integrator>,
    /// Linear solver of implicit-euler and bdf2: cg (conjugate gradients, the default) or cholesky
    /// (faer's sparse Cholesky; exact whatever the stiffness).
    #[arg(long)]
    linear_solver: Option<anima_ode::LinearSolver>,
    /// Time step in seconds (overrides DELTA_t).
    #[arg(long)]
    dt: Option<f64>,
    /// Simulated duration in seconds (overrides DURAÇÃO).
    #[arg(long)]
    duration: Option<f64>,
    /// Where to write the JSON summary (default: OUT/summary.json).
    #[arg(long)]
    summary: Option<PathBuf>,
    /// Gravity: on (0, −9.8, 0), off, or gx,gy,gz. A .PAR script without GRAVIDADE defaults to on.
    #[arg(long, value_parser = parse_gravity)]
    gravity: Option<DVec3>,
    /// Friction reading: literal (fraction of the resultant, against the motion) or viscous (−μv).
    #[arg(long)]
    friction: Option<String>,
    /// Particle–surface contact partner: nearest (vertex) or three (vertices).
    #[arg(long)]
    contact: Option<String>,
    /// Response against static objects: reverse (v ← −v) or reflect (normal component only).
    #[arg(long)]
    static_response: Option<String>,
    /// Read FORÇA_EXTERNA as an acceleration (multiplied by the particle mass).
    #[arg(long)]
    external_is_acceleration: bool,
    /// Apply −F/2 of each angular spring to its two outer particles (momentum-conserving bending).
    #[arg(long)]
    bend_reaction: bool,
    /// Limit friction so it cannot reverse a velocity within one step (needed at large steps).
    #[arg(long)]
    friction_clamp: bool,
    /// Switch particle–triangle collisions off (an extension; FLEX3D always ran them).
    #[arg(long)]
    no_collisions: bool,
    /// Also write the initial state as frame 0.
    #[arg(long)]
    frame0: bool,
    /// Do not write per-frame .OBT/.obj files.
    #[arg(long)]
    no_frames: bool,
    /// Do not render pictures.
    #[arg(long)]
    no_pictures: bool,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
    /// Sheet scenes: an OBJ of reference positions (such as another run's final.obj); the summary then
    /// reports the RMS distance to it.
    #[arg(long)]
    reference: Option<PathBuf>,
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
                [x, y, z] => Ok(DVec3::new(x, y, z)),
                _ => Err(format!("expected on, off or three comma-separated numbers, found `{s}`")),
            }
        }
    }
}

/// The built-in default scene: the FLEX3D tablecloth (spec E-8) with its reconstructed table.
const DEFAULT_SCENE: &str = include_str!("../../../assets/flex3d/tablecloth.ron");
const DEFAULT_TABLE: &str = include_str!("../../../assets/flex3d/mesa.obt");

fn load_default() -> Result<LoadedScene> {
    let scene = anima_scene::ron_scene::from_ron_str(DEFAULT_SCENE).context("the built-in scene")?;
    let table = anima_geom::obt::read_obt(DEFAULT_TABLE.as_bytes(), anima_geom::obt::IndexBase::Auto)
        .context("the built-in table")?
        .to_mesh()?;
    Ok(LoadedScene {
        scene,
        objects: vec![("mesa.obt".into(), table)],
        path: PathBuf::from("built-in tablecloth"),
    })
}

/// The struct name a RON scene file starts with (after comments), which says what kind of scene it is.
fn ron_struct_name(src: &str) -> Option<&str> {
    let mut rest = src;
    loop {
        rest = rest.trim_start();
        if let Some(r) = rest.strip_prefix("//") {
            rest = r.split_once('\n').map_or("", |(_, after)| after);
        } else if rest.starts_with("#![") {
            rest = rest.split_once('\n').map_or("", |(_, after)| after);
        } else {
            break;
        }
    }
    let end = rest.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(rest.len());
    (end > 0).then(|| &rest[..end])
}

fn run_sheet_command(args: &RunArgs, path: &Path, src: &str) -> Result<ExitCode> {
    let mut scene =
        anima_scene::sheet::from_ron_str(src).map_err(|e| e.with_file(path.display().to_string()))?;
    if let Some(i) = args.integrator {
        scene.integrator = i;
    }
    if let Some(dt) = args.dt {
        scene.dt_s = dt;
    }
    if let Some(d) = args.duration {
        scene.duration_s = d;
    }
    let opts = anima_lab::run::sheet::SheetRunOptions {
        out_dir: Some(args.out.clone()),
        reference: args.reference.clone(),
        write_frames: !args.no_frames,
        pictures: !args.no_pictures,
        progress: !args.quiet && std::io::IsTerminal::is_terminal(&std::io::stderr()),
        warn_stability: !args.quiet,
        linear_solver: args.linear_solver,
    };
    if !args.quiet {
        eprintln!(
            "anima: {} — {} particles, {} s at {} s ({})",
            path.display(),
            scene.sheet.n * scene.sheet.n,
            scene.duration_s,
            scene.dt_s,
            scene.integrator
        );
    }
    let s = anima_lab::run::sheet::run_sheet(&scene, &path.display().to_string(), &opts)?;
    let summary_path = args.summary.clone().unwrap_or_else(|| args.out.join("summary.json"));
    anima_lab::output::write_atomic(&summary_path, |w| {
        serde_json::to_writer_pretty(&mut *w, &s)?;
        Ok(w.write_all(b"\n")?)
    })?;
    if !args.quiet {
        let c = s.center_of_mass;
        eprintln!(
            "anima: {} steps in {:.2} s ({:.1} ns per particle-step); centre of mass ({:.4}, {:.4}, {:.4}) m, max strain {:.4}",
            s.steps, s.wall_seconds, s.ns_per_particle_step, c[0], c[1], c[2], s.max_strain
        );
        if let Some(r) = s.rms_to_reference {
            eprintln!("anima: RMS distance to the reference {r:.3e} m");
        }
    }
    if let Some(e) = &s.error {
        eprintln!("anima: error: the run stopped early: {e}");
        return Ok(ExitCode::from(2));
    }
    Ok(ExitCode::SUCCESS)
}

fn run_command(args: RunArgs) -> Result<ExitCode> {
    // A RON file whose top-level value is `BodyScene(…)` is an articulated-figure scene.
    if let Some(path) = args.scene.as_deref().filter(|p| anima_lab::run::body::is_body_scene_file(p)) {
        let progress = !args.quiet && std::io::IsTerminal::is_terminal(&std::io::stderr());
        let opts = anima_lab::run::body::BodyRunOptions {
            out_dir: Some(args.out.clone()),
            pictures: !args.no_pictures,
            dt: args.dt,
            duration: args.duration,
            progress,
        };
        return anima_lab::run::body::run_command(path, &args.out, args.summary.as_deref(), opts, args.quiet);
    }
    if let Some(path) =
        args.scene.as_ref().filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("ron")))
    {
        let src = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
        if ron_struct_name(&src) == Some("SheetScene") {
            return run_sheet_command(&args, path, &src);
        }
    }
    let mut loaded = match &args.scene {
        Some(path) => anima_scene::load(path, &LoadOptions { gravity: args.gravity })?,
        None => load_default()?,
    };
    let scene = &mut loaded.scene;
    if args.scene.is_none()
        && let Some(g) = args.gravity
    {
        scene.gravity_m_s2 = g;
    }
    if let Some(i) = args.integrator {
        scene.integrator = i;
    }
    if let Some(dt) = args.dt {
        if !(dt > 0.0 && dt.is_finite()) {
            bail!("--dt must be a positive number of seconds, found {dt}");
        }
        scene.dt_s = dt;
    }
    if let Some(d) = args.duration {
        if !(d > 0.0 && d.is_finite()) {
            bail!("--duration must be a positive number of seconds, found {d}");
        }
        scene.duration_s = d;
    }
    if let Some(f) = &args.friction {
        scene.friction.mode = match f.as_str() {
            "literal" => FrictionMode::Literal,
            "viscous" => FrictionMode::Viscous,
            _ => bail!("--friction: expected literal or viscous, found `{f}`"),
        };
    }
    if let Some(c) = &args.contact {
        scene.options.contact = match c.as_str() {
            "nearest" | "nearest-vertex" => ContactApproach::NearestVertex,
            "three" | "three-vertices" => ContactApproach::ThreeVertices,
            _ => bail!("--contact: expected nearest or three, found `{c}`"),
        };
    }
    if let Some(r) = &args.static_response {
        scene.options.static_response = match r.as_str() {
            "reverse" => StaticResponse::Reverse,
            "reflect" | "reflect-normal" => StaticResponse::ReflectNormal,
            _ => bail!("--static-response: expected reverse or reflect, found `{r}`"),
        };
    }
    scene.options.external_force_is_acceleration |= args.external_is_acceleration;
    scene.options.bend_reaction |= args.bend_reaction;
    scene.options.friction_clamp |= args.friction_clamp;
    if args.no_collisions {
        scene.options.collisions = false;
    }
    let opts = RunOptions {
        out_dir: Some(args.out.clone()),
        write_frames: !args.no_frames,
        frame0: args.frame0,
        pictures: !args.no_pictures,
        progress: !args.quiet && std::io::IsTerminal::is_terminal(&std::io::stderr()),
        warn_stability: !args.quiet,
        linear_solver: args.linear_solver,
    };
    let n_frames = loaded.scene.n_frames();
    if !args.quiet {
        eprintln!(
            "anima: {} — {} steps of {} s ({}), {} frames",
            loaded.path.display(),
            loaded.scene.n_steps(),
            loaded.scene.dt_s,
            loaded.scene.integrator,
            n_frames
        );
    }
    let outcome = run(&loaded, &opts, |_, _| {})?;
    let summary_path = args.summary.clone().unwrap_or_else(|| args.out.join("summary.json"));
    write_summary(&summary_path, &outcome.summary)?;
    let s = &outcome.summary;
    if !args.quiet {
        eprintln!(
            "anima: {} steps in {:.2} s ({:.0} ns per particle-step); max speed {:.4}, penetrations {}",
            s.steps, s.wall_seconds, s.ns_per_particle_step, s.max_speed, s.penetrations
        );
        eprintln!("anima: wrote {} and {}", args.out.display(), summary_path.display());
    }
    if let Some(nf) = &s.non_finite {
        eprintln!(
            "anima: error: the state went non-finite at step {} (t = {} s), surface `{}`, particle ({}, {}); \
             try a smaller --dt or another --integrator",
            nf.step, nf.time, nf.surface, nf.row, nf.col
        );
        return Ok(ExitCode::from(2));
    }
    if let Some(e) = &s.error {
        eprintln!("anima: error: the run stopped early: {e}");
        return Ok(ExitCode::from(2));
    }
    Ok(ExitCode::SUCCESS)
}

fn convert_command(input: &Path, output: Option<PathBuf>, gravity: Option<DVec3>) -> Result<()> {
    let bytes = std::fs::read(input).with_context(|| format!("reading {}", input.display()))?;
    let name = input.display().to_string();
    let ron = anima_scene::convert_par_to_ron(&bytes, &name, gravity.unwrap_or(FLEX3D_GRAVITY))?;
    let out = output.unwrap_or_else(|| input.with_extension("ron"));
    anima_lab::output::write_atomic(&out, |w| Ok(w.write_all(ron.as_bytes())?))?;
    eprintln!("anima: wrote {}", out.display());
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(args) => run_command(args),
        Command::Convert { input, output, gravity } => {
            convert_command(&input, output, gravity).map(|()| ExitCode::SUCCESS)
        }
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("anima: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
