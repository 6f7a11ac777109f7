//! Running a FLEX3D scene: stepping, `.OBT` and OBJ frames, pictures and the summary's numbers.

use std::time::Instant;

use anima_cloth::StepError;
use anima_cloth::error::NonFinite;
use anima_cloth::flex3d::{Diagnostics, Flex3dWorld};
use anima_geom::obt::{ObtObject, write_obt};
use anima_geom::{DVec3, obj::write_obj};
use anima_scene::LoadedFlex3d;
use anima_viz::gltf::UpAxis;
use anyhow::{Context, Result};
use serde::Serialize;

use super::export::GltfExport;
use super::{
    ClothFrames, Detail, Progress, RunOptions, SelfCollisionReport, Summary, sheet_frames, stability_warning,
};
use crate::output::write_atomic;

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

impl From<&NonFinite> for NonFiniteReport {
    fn from(e: &NonFinite) -> Self {
        let place = e.place.as_ref().expect("FLEX3D places every particle on its surface's grid");
        let (surface, row, col) = (place.surface.clone(), place.row, place.col);
        Self { step: e.step as usize, time: e.time, surface, row, col }
    }
}

/// The numbers of a FLEX3D run.
#[derive(Debug, Clone, Serialize)]
pub struct Flex3dDetail {
    pub integrator: String,
    pub dt: f64,
    pub particles: usize,
    pub ns_per_particle_step: f64,
    pub non_finite: Option<NonFiniteReport>,
    pub max_speed: f64,
    pub kinetic_energy: f64,
    pub max_strain: f64,
    pub penetrations: usize,
    pub collisions_with_objects: u64,
    pub collisions_with_surfaces: u64,
    pub self_collision: SelfCollisionReport,
    pub frame_stats: Vec<FrameStats>,
}

/// Positions of every particle at one frame, kept for the contact sheet.
#[derive(Debug, Clone)]
pub struct Snapshot {
    pub frame: usize,
    pub time: f64,
    pub positions: Vec<DVec3>,
}

/// Runs `loaded` to its end (or to the first non-finite value), writing what `opts` asks for; returns
/// the summary and the world at the end.
pub fn run(
    loaded: &LoadedFlex3d,
    label: &str,
    opts: &RunOptions,
    progress: &mut dyn Progress,
) -> Result<(Summary, Flex3dWorld)> {
    let scene = &loaded.scene;
    // Surface names become file names: only plain ones (a scene built in code is not checked by a reader).
    if let Some((s, why)) =
        scene.surfaces.iter().find_map(|s| anima_format::not_a_plain_name(&s.name).map(|w| (s, w)))
    {
        anyhow::bail!("surface `{}`: expected {why}", s.name);
    }
    let mut world = Flex3dWorld::new(scene, loaded.meshes()).context("building the scene")?;
    opts.solve.configure(world.stepper_mut());
    let mut warnings = Vec::new();
    let damping = (scene.friction.coefficient > 0.0).then(|| {
        format!("{:?} friction μ = {}", scene.friction.mode, scene.friction.coefficient).to_lowercase()
    });
    if let Some(w) = stability_warning(
        scene.integrator,
        scene.dt_s,
        scene.n_steps(),
        world.max_frequency(),
        0.0,
        damping.as_deref(),
    ) {
        progress.warn(&w);
        warnings.push(w);
    }
    let n_frames = scene.n_frames();
    let n_steps = scene.n_steps();
    let particles = world.positions().len();
    // Frames 1..=n_frames at the scene's frame rate (spec S4.5); when the duration is not a whole number
    // of frame intervals (a shortened run, say), one more frame at the end, so the run always reaches
    // its duration.
    let extra = usize::from(n_frames == 0 || scene.frame_step(n_frames) < n_steps);
    let shown = if opts.picture_dir().is_some() { sheet_frames(n_frames + extra) } else { Vec::new() };
    let mut snapshots = Vec::new();
    let mut frame_stats = Vec::with_capacity(n_frames.min(100_000));
    if opts.frame0 {
        write_frame(opts, &world, 0)?;
    }
    // FLEX3D scenes have y up, as glTF does; the export starts from the state at t = 0.
    let mut export = match opts.export_dir() {
        Some(_) => {
            let surfaces: Vec<(&str, usize, &[[u32; 3]])> = world
                .surfaces()
                .iter()
                .enumerate()
                .map(|(s, info)| (info.name.as_str(), world.surface_positions(s).len(), &info.triangles[..]))
                .collect();
            let mut e = GltfExport::cloth(UpAxis::PlusY, &loaded.objects, &surfaces, n_frames + extra)?;
            e.deforming_frame(0, world.time(), |s| world.surface_positions(s));
            Some(e)
        }
        None => None,
    };
    progress.begin(n_steps as u64);
    let start = Instant::now();
    let mut failure = None;
    let mut frames_done = 0;
    // Every surface's triangles in the world's particle indices, so surfaces crossing one another count.
    let triangles = world.all_triangles();
    let names = [
        ("kinetic energy".to_owned(), "J"),
        ("self-intersections".to_owned(), "crossing pairs"),
        ("max speed".to_owned(), "m/s"),
    ];
    let d = world.diagnostics();
    let mut per_frame =
        ClothFrames::new(opts, names, world.time(), world.positions(), &triangles, |c| frame_values(&d, c));
    for k in 1..=n_frames + extra {
        let target = if k > n_frames { n_steps } else { scene.frame_step(k).min(n_steps) };
        if let Err(e) = step_to(&mut world, target as u64, progress) {
            failure = Some(e);
            break;
        }
        crate::interrupt::check()?;
        per_frame.output.time(|| -> Result<()> {
            write_frame(opts, &world, k)?;
            if let Some(e) = &mut export {
                e.deforming_frame(k, world.time(), |s| world.surface_positions(s));
            }
            if shown.contains(&k) {
                snapshots.push(Snapshot {
                    frame: k,
                    time: world.time(),
                    positions: world.positions().to_vec(),
                });
            }
            Ok(())
        })?;
        let d = world.diagnostics();
        per_frame.frame(k, world.time(), world.positions(), &triangles, |c| frame_values(&d, c))?;
        frame_stats.push(FrameStats {
            frame: k,
            time: world.time(),
            max_speed: d.max_speed,
            kinetic_energy: d.kinetic_energy,
            bounds_min: d.bounds.min.to_array(),
            bounds_max: d.bounds.max.to_array(),
        });
        frames_done = k;
    }
    let wall_seconds = start.elapsed().as_secs_f64() - per_frame.watch.seconds();
    let output_seconds = per_frame.output.seconds();
    progress.end();
    let watch = &mut per_frame.watch;
    watch.look(world.positions(), &triangles);
    let d = world.diagnostics();
    let counts = world.collision_counts();
    let steps = world.steps() as usize;
    super::closing_warnings(export, opts, Some(watch), progress, &mut warnings)?;
    let summary = Summary {
        scene: label.to_owned(),
        kind: "flex3d",
        steps: steps as u64,
        frames: frames_done,
        simulated_seconds: world.time(),
        wall_seconds,
        output_seconds,
        all_finite: !failure.as_ref().is_some_and(StepError::is_non_finite) && d.all_finite,
        error: failure.as_ref().map(|e| e.to_string()),
        warnings,
        self_intersections: Some(watch.largest),
        detail: Detail::Flex3d(Flex3dDetail {
            integrator: scene.integrator.name().to_owned(),
            dt: scene.dt_s,
            particles,
            ns_per_particle_step: (wall_seconds - output_seconds) * 1e9
                / (steps.max(1) * particles.max(1)) as f64,
            non_finite: match &failure {
                Some(StepError::NonFinite(e)) => Some(NonFiniteReport::from(e)),
                _ => None,
            },
            max_speed: d.max_speed,
            kinetic_energy: d.kinetic_energy,
            max_strain: world.max_strain(),
            penetrations: world.penetrations(),
            collisions_with_objects: counts.with_objects,
            collisions_with_surfaces: counts.with_surfaces,
            self_collision: SelfCollisionReport::new(
                scene.options.self_collision,
                world.self_collision_stats(),
            ),
            frame_stats,
        }),
    };
    if let Some(dir) = opts.picture_dir() {
        crate::picture::write_pictures(dir, &world, &snapshots)?;
    }
    per_frame.write_series(opts)?;
    Ok((summary, world))
}

/// A frame's values in the order of the run's series: kinetic energy, crossings (`None`: the count was
/// abandoned), the largest speed.
fn frame_values(d: &Diagnostics, crossings: Option<usize>) -> [Option<f64>; 3] {
    [Some(d.kinetic_energy), crossings.map(|n| n as f64), Some(d.max_speed)]
}

fn step_to(world: &mut Flex3dWorld, target: u64, progress: &mut dyn Progress) -> Result<(), StepError> {
    // Report in chunks so that the bar costs nothing measurable.
    const CHUNK: u64 = 1000;
    while world.steps() < target {
        let next = (world.steps() + CHUNK).min(target);
        world.run_to_step(next)?;
        progress.advance(world.steps());
    }
    Ok(())
}

/// Writes `<SURFACE>_<frame>.OBT` (spec S5.9) and `<SURFACE>_<frame>.obj` for every surface.
fn write_frame(opts: &RunOptions, world: &Flex3dWorld, frame: usize) -> Result<()> {
    let Some(dir) = opts.frame_dir() else { return Ok(()) };
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
