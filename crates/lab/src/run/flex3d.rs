//! Running a loaded scene: stepping, frame output, snapshots for pictures, and the run summary.

use std::path::PathBuf;
use std::time::Instant;

use anima_cloth::flex3d::{Flex3dWorld, NonFiniteError, StepError};
use anima_geom::obt::{ObtObject, write_obt};
use anima_geom::{DVec3, obj::write_obj};
use anima_scene::LoadedScene;
use anyhow::{Context, Result};
use serde::Serialize;

use crate::output::write_atomic;

/// What a run writes and shows.
#[derive(Debug, Clone)]
pub struct RunOptions {
    /// Folder for frames, pictures and the summary; `None` writes nothing.
    pub out_dir: Option<PathBuf>,
    /// Write `<SURFACE>_<frame>.OBT` and `.obj` for every frame.
    pub write_frames: bool,
    /// Also write the initial state as frame 0.
    pub frame0: bool,
    /// Render `final.png` and a `frames.png` contact sheet.
    pub pictures: bool,
    /// Show a progress bar on standard error.
    pub progress: bool,
    /// Warn on standard error when the step is beyond the integrator's stability limit.
    pub warn_stability: bool,
    /// The linear solver of the implicit integrators (`None`: conjugate gradients).
    pub linear_solver: Option<anima_ode::LinearSolver>,
}

impl RunOptions {
    /// Nothing written, nothing shown: for tests and experiments that only want the numbers.
    pub fn quiet() -> Self {
        Self {
            out_dir: None,
            write_frames: false,
            frame0: false,
            pictures: false,
            progress: false,
            warn_stability: false,
            linear_solver: None,
        }
    }
}

/// Per-frame measurements (spec F-37).
#[derive(Debug, Clone, Serialize)]
pub struct FrameStats {
    pub frame: usize,
    pub time: f64,
    pub max_speed: f64,
    pub kinetic_energy: f64,
    pub bounds_min: [f64; 3],
    pub bounds_max: [f64; 3],
}

/// Where a run went non-finite.
#[derive(Debug, Clone, Serialize)]
pub struct NonFiniteReport {
    pub step: usize,
    pub time: f64,
    pub surface: String,
    pub row: usize,
    pub col: usize,
}

impl From<&NonFiniteError> for NonFiniteReport {
    fn from(e: &NonFiniteError) -> Self {
        Self { step: e.step, time: e.time, surface: e.surface.clone(), row: e.row, col: e.col }
    }
}

/// The JSON summary of a run.
#[derive(Debug, Clone, Serialize)]
pub struct RunSummary {
    pub scene: String,
    pub integrator: String,
    pub dt: f64,
    pub particles: usize,
    pub steps: usize,
    pub frames: usize,
    pub simulated_seconds: f64,
    pub wall_seconds: f64,
    pub ns_per_particle_step: f64,
    pub all_finite: bool,
    pub non_finite: Option<NonFiniteReport>,
    /// Why the run stopped early, if it did.
    pub error: Option<String>,
    pub max_speed: f64,
    pub kinetic_energy: f64,
    pub max_strain: f64,
    pub penetrations: usize,
    pub collisions_with_objects: u64,
    pub collisions_with_surfaces: u64,
    pub frame_stats: Vec<FrameStats>,
}

/// Positions of every particle at one frame, kept for the contact sheet.
#[derive(Debug, Clone)]
pub struct Snapshot {
    pub frame: usize,
    pub time: f64,
    pub positions: Vec<DVec3>,
}

/// The result of a run: its summary, the world at the end, and the frames kept for pictures.
#[derive(Debug)]
pub struct RunOutcome {
    pub summary: RunSummary,
    pub world: Flex3dWorld,
    pub snapshots: Vec<Snapshot>,
}

/// Frames shown on the contact sheet: nine spread evenly over the run, ending with the last one.
pub fn sheet_frames(n_frames: usize) -> Vec<usize> {
    let shown = n_frames.min(9);
    let mut frames: Vec<usize> = (1..=shown).map(|k| (k * n_frames).div_ceil(shown)).collect();
    frames.dedup();
    frames
}

/// Runs `loaded` to its end (or to the first non-finite value), writing what `opts` asks for.
/// `on_frame` sees the world after every written frame.
pub fn run(
    loaded: &LoadedScene,
    opts: &RunOptions,
    mut on_frame: impl FnMut(usize, &Flex3dWorld),
) -> Result<RunOutcome> {
    let scene = &loaded.scene;
    let objects = loaded.objects.iter().map(|(_, m)| m.clone()).collect();
    let mut world = Flex3dWorld::new(scene, objects).context("building the scene")?;
    if let Some(solver) = opts.linear_solver {
        world.stepper_mut().set_linear_solver(solver);
    }
    if opts.progress || opts.warn_stability {
        let omega = world.max_frequency();
        if let Some(w) = anima_ode::stability::check_step(scene.integrator, scene.dt_s, omega) {
            eprintln!("anima: warning: {w}");
        }
    }
    let n_frames = scene.n_frames();
    let n_steps = scene.n_steps();
    let particles = world.positions().len();
    let shown = if opts.pictures { sheet_frames(n_frames) } else { Vec::new() };
    let mut snapshots = Vec::new();
    let mut frame_stats = Vec::with_capacity(n_frames);
    let bar = opts.progress.then(|| progress_bar(n_steps as u64));
    if opts.frame0 {
        write_frame(opts, &world, 0)?;
    }
    let start = Instant::now();
    let mut failure = None;
    let mut frames_done = 0;
    for k in 1..=n_frames {
        let target = scene.frame_step(k).min(n_steps);
        if let Err(e) = step_to(&mut world, target, bar.as_ref()) {
            failure = Some(e);
            break;
        }
        write_frame(opts, &world, k)?;
        let d = world.diagnostics();
        frame_stats.push(FrameStats {
            frame: k,
            time: world.time(),
            max_speed: d.max_speed,
            kinetic_energy: d.kinetic_energy,
            bounds_min: d.bounds.min.to_array(),
            bounds_max: d.bounds.max.to_array(),
        });
        if shown.contains(&k) {
            snapshots.push(Snapshot { frame: k, time: world.time(), positions: world.positions().to_vec() });
        }
        on_frame(k, &world);
        frames_done = k;
    }
    let wall_seconds = start.elapsed().as_secs_f64();
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let d = world.diagnostics();
    let counts = world.collision_counts();
    let steps = world.steps_taken();
    let summary = RunSummary {
        scene: loaded.path.display().to_string(),
        integrator: scene.integrator.name().to_owned(),
        dt: scene.dt_s,
        particles,
        steps,
        frames: frames_done,
        simulated_seconds: world.time(),
        wall_seconds,
        ns_per_particle_step: wall_seconds * 1e9 / (steps.max(1) * particles.max(1)) as f64,
        all_finite: !matches!(failure, Some(StepError::NonFinite(_))) && d.all_finite,
        non_finite: match &failure {
            Some(StepError::NonFinite(e)) => Some(NonFiniteReport::from(e)),
            _ => None,
        },
        error: failure.as_ref().map(|e| e.to_string()),
        max_speed: d.max_speed,
        kinetic_energy: d.kinetic_energy,
        max_strain: world.max_strain(),
        penetrations: world.penetrations(),
        collisions_with_objects: counts.with_objects,
        collisions_with_surfaces: counts.with_surfaces,
        frame_stats,
    };
    if opts.pictures
        && let Some(dir) = &opts.out_dir
    {
        crate::picture::write_pictures(dir, &world, &snapshots)?;
    }
    Ok(RunOutcome { summary, world, snapshots })
}

fn step_to(
    world: &mut Flex3dWorld,
    target: usize,
    bar: Option<&indicatif::ProgressBar>,
) -> Result<(), StepError> {
    // Update the bar in chunks so that it costs nothing measurable.
    const CHUNK: usize = 1000;
    while world.steps_taken() < target {
        let next = (world.steps_taken() + CHUNK).min(target);
        world.run_to_step(next)?;
        if let Some(bar) = bar {
            bar.set_position(world.steps_taken() as u64);
        }
    }
    Ok(())
}

fn progress_bar(steps: u64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(steps);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} steps ({eta} left)",
        )
        .expect("valid template"),
    );
    bar
}

/// Writes `<SURFACE>_<frame>.OBT` (spec S5.9) and `<SURFACE>_<frame>.obj` for every surface.
fn write_frame(opts: &RunOptions, world: &Flex3dWorld, frame: usize) -> Result<()> {
    let Some(dir) = opts.out_dir.as_ref().filter(|_| opts.write_frames) else { return Ok(()) };
    for (s, info) in world.surfaces().iter().enumerate() {
        let positions = world.surface_positions(s);
        let obt = ObtObject::from_surface(&info.name, positions, &info.triangles);
        write_atomic(&dir.join(format!("{}_{frame}.OBT", info.name)), |w| Ok(write_obt(w, &obt)?))?;
        write_atomic(&dir.join(format!("{}_{frame}.obj", info.name)), |w| {
            Ok(write_obj(w, &info.name, positions, &info.triangles)?)
        })?;
    }
    Ok(())
}

/// Writes the summary as pretty JSON.
pub fn write_summary(path: &std::path::Path, summary: &RunSummary) -> Result<()> {
    write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, summary)?;
        writeln!(w)?;
        Ok(())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contact_sheet_frames() {
        assert_eq!(sheet_frames(20), vec![3, 5, 7, 9, 12, 14, 16, 18, 20]);
        assert_eq!(sheet_frames(4), vec![1, 2, 3, 4]);
        assert_eq!(sheet_frames(0), Vec::<usize>::new());
    }
}
