//! Running an Oliveira 2013 drape (`OliveiraScene(…)`, or `AdaptiveOliveiraScene(…)` with a remesher):
//! the one drape loop of [`crate::drape::run_drape`], OBJ frames at 30 per second (the mesh of each
//! frame, since a remesher changes it), pictures with the objects and the mesh drawn, and the summary's
//! numbers.

use std::ops::ControlFlow;
use std::path::Path;
use std::time::Instant;

use anima_cloth::oliveira::{AdaptiveCloth, OliveiraCloth};
use anima_geom::obj::write_obj;
use anima_geom::{Aabb, DVec3};
use anima_scene::oliveira::LoadedOliveira;
use anima_viz::gltf::UpAxis;
use anima_viz::{Camera, Image, RenderMesh, RenderSettings, render};
use anyhow::{Context, Result};
use serde::Serialize;

use super::export::GltfExport;
use super::{ClothFrames, Detail, Progress, RunOptions, SelfCollisionReport, Summary, sheet_frames};
use crate::drape::{Ended, object_meshes, run_drape};
use crate::output::write_atomic;

/// Frames written per simulated second (the scene format has no frame rate: a drape is a few tenths of
/// a second).
pub const FRAME_RATE_HZ: f64 = 30.0;

/// The numbers of a drape run.
#[derive(Debug, Clone, Serialize)]
pub struct OliveiraDetail {
    pub integrator: String,
    /// The remesher of an adaptive scene.
    pub remesher: Option<String>,
    pub particles_at_start: usize,
    pub particles: usize,
    pub faces: usize,
    /// The smallest and largest step taken, s.
    pub min_dt: f64,
    pub max_dt: f64,
    /// When the cloth first touched an object, s, and how many contact responses there were.
    pub first_contact: Option<f64>,
    pub contact_responses: u64,
    /// Particles inside an object at the end.
    pub penetrations: usize,
    pub max_speed: f64,
    pub kinetic_energy: f64,
    /// Particle P (the scene's tracked vertex) at the end, m.
    pub tracked_point: [f64; 3],
    /// Remeshing passes that changed the mesh, refinements and simplifications.
    pub remesh_rebuilds: u64,
    pub remesh_refinements: u64,
    pub remesh_simplifications: u64,
    pub self_collision: SelfCollisionReport,
}

/// A frame kept for the contact sheet: time, positions, triangles.
type Kept = (f64, Vec<DVec3>, Vec<[u32; 3]>);

/// Runs a drape to its end (or to the first failure).
pub fn run(
    loaded: &LoadedOliveira,
    label: &str,
    opts: &RunOptions,
    progress: &mut dyn Progress,
) -> Result<Summary> {
    let mut cloth = loaded.build().context("building the drape")?;
    opts.solve.configure(cloth.stepper_mut());
    let mut cloth = loaded.with_remesher(cloth);
    let duration = loaded.scene.duration_s;
    let n_frames = ((duration * FRAME_RATE_HZ).round() as usize).max(1);
    let frame_time = |k: usize| if k == n_frames { duration } else { k as f64 / FRAME_RATE_HZ };
    let shown = sheet_frames(n_frames);
    let particles_at_start = cloth.cloth().positions().len();
    if opts.frame0 {
        write_frame(opts, &cloth, 0)?;
    }
    let mut export = match opts.export_dir() {
        Some(_) => Some(gltf_export(loaded, &cloth, n_frames)?),
        None => None,
    };
    let (mut min_dt, mut max_dt) = (f64::INFINITY, 0.0f64);
    let mut next_frame = 1;
    let mut kept: Vec<Kept> = Vec::new();
    let mut write_error = None;
    let names = [
        ("kinetic energy".to_owned(), "J"),
        ("self-intersections".to_owned(), "crossing pairs"),
        ("vertices".to_owned(), "count"),
        ("contact responses (total)".to_owned(), "count"),
    ];
    let c = cloth.cloth();
    let mut per_frame =
        ClothFrames::new(opts, names, 0.0, c.positions(), c.triangles(), |n| frame_values(c, n));
    progress.begin((duration * 1e3).ceil() as u64);
    let start = Instant::now();
    let mut too_long = false;
    let ended = run_drape(&mut cloth, duration, |c, report, _| {
        // A remesher can shrink the step as the run goes: the run is bounded all the same.
        if c.cloth().steps() as f64 >= anima_scene::limits::MAX_STEPS {
            too_long = true;
            return ControlFlow::Break(());
        }
        if crate::interrupt::requested() {
            write_error = Some(crate::interrupt::Interrupted.into());
            return ControlFlow::Break(());
        }
        min_dt = min_dt.min(report.dt);
        max_dt = max_dt.max(report.dt);
        let t = c.cloth().time();
        while next_frame <= n_frames && t >= frame_time(next_frame) - 1e-12 {
            let written = per_frame.output.time(|| {
                write_frame(opts, c, next_frame)?;
                if let Some(e) = &mut export {
                    // The frame's own time: the state is that of the first step to reach it, as in the
                    // OBJ frames (a long step may reach two frame times at once).
                    export_frame(e, c, next_frame, frame_time(next_frame));
                }
                if opts.picture_dir().is_some() && shown.contains(&next_frame) {
                    kept.push((t, c.cloth().positions().to_vec(), c.cloth().triangles().to_vec()));
                }
                Ok(())
            });
            let (x, triangles) = (c.cloth().positions(), c.cloth().triangles());
            let done = written.and_then(|()| {
                per_frame
                    .frame(next_frame, frame_time(next_frame), x, triangles, |n| frame_values(c.cloth(), n))
            });
            if let Err(e) = done {
                write_error = Some(e);
                return ControlFlow::Break(());
            }
            progress.advance((t * 1e3) as u64);
            next_frame += 1;
        }
        ControlFlow::Continue(())
    });
    let wall_seconds = start.elapsed().as_secs_f64() - per_frame.watch.seconds();
    let output_seconds = per_frame.output.seconds();
    progress.end();
    if let Some(e) = write_error {
        return Err(e);
    }
    let mut warnings = Vec::new();
    let c = cloth.cloth();
    let watch = &mut per_frame.watch;
    watch.look(c.positions(), c.triangles());
    let stats = cloth.stats();
    super::closing_warnings(export, opts, Some(watch), progress, &mut warnings)?;
    let summary = Summary {
        scene: label.to_owned(),
        kind: "oliveira",
        steps: c.steps(),
        frames: next_frame - 1,
        simulated_seconds: c.time(),
        wall_seconds,
        output_seconds,
        all_finite: !matches!(ended, Ended::Failed(_)),
        error: match &ended {
            Ended::Failed(e) => Some(e.to_string()),
            _ if too_long => Some(format!(
                "stopped after {:e} steps (anima_scene::limits::MAX_STEPS)",
                anima_scene::limits::MAX_STEPS
            )),
            _ => None,
        },
        warnings,
        self_intersections: Some(watch.largest),
        detail: Detail::Oliveira(OliveiraDetail {
            integrator: loaded.scene.integrator.name().to_owned(),
            remesher: loaded.remesher.map(|r| format!("{r:?}")),
            particles_at_start,
            particles: c.positions().len(),
            faces: c.triangles().len(),
            min_dt,
            max_dt,
            first_contact: c.first_collision_time(),
            contact_responses: c.total_hits(),
            penetrations: c.penetrations().len(),
            max_speed: c.max_speed(),
            kinetic_energy: c.kinetic_energy(),
            tracked_point: c.tracked_position().to_array(),
            remesh_rebuilds: stats.rebuilds,
            remesh_refinements: stats.refinements,
            remesh_simplifications: stats.simplifications,
            self_collision: SelfCollisionReport::new(
                loaded.scene.options.self_collision,
                c.self_collision_stats(),
            ),
        }),
    };
    if let Some(dir) = opts.picture_dir() {
        write_pictures(dir, &cloth, &kept)?;
    }
    per_frame.write_series(opts)?;
    Ok(summary)
}

/// A frame's values in the order of the run's series: kinetic energy, crossings (`None`: the count was
/// abandoned), vertices, contact responses so far.
fn frame_values(c: &OliveiraCloth, crossings: Option<usize>) -> [Option<f64>; 4] {
    [
        Some(c.kinetic_energy()),
        crossings.map(|n| n as f64),
        Some(c.positions().len() as f64),
        Some(c.total_hits() as f64),
    ]
}

/// The export of a drape, with frame 0 in it: the cloth over its objects, as morph targets when no
/// remesher changes its mesh and as a mesh per frame when one does. Up is against the scene's gravity
/// (z in the shipped scenes).
fn gltf_export(loaded: &LoadedOliveira, cloth: &AdaptiveCloth, n_frames: usize) -> Result<GltfExport> {
    let c = cloth.cloth();
    let up = UpAxis::against(loaded.scene.gravity_m_s2, UpAxis::PlusZ);
    let objects: Vec<_> =
        c.colliders().iter().zip(object_meshes(c)).map(|(o, (mesh, _))| (o.name.clone(), mesh)).collect();
    let mut e = if loaded.remesher.is_none() {
        GltfExport::cloth(up, &objects, &[("cloth", c.positions().len(), c.triangles())], n_frames)?
    } else {
        GltfExport::remeshed(up, &objects, n_frames, c.positions().len())
    };
    export_frame(&mut e, cloth, 0, 0.0);
    Ok(e)
}

fn export_frame(e: &mut GltfExport, cloth: &AdaptiveCloth, k: usize, time_s: f64) {
    let c = cloth.cloth();
    e.cloth_frame(k, time_s, c.positions(), c.triangles());
}

/// Writes `cloth_<frame>.obj`: the positions and triangles of the cloth as they are now.
fn write_frame(opts: &RunOptions, cloth: &AdaptiveCloth, frame: usize) -> Result<()> {
    let Some(dir) = opts.frame_dir() else { return Ok(()) };
    let c = cloth.cloth();
    write_atomic(&dir.join(format!("cloth_{frame}.obj")), |w| {
        Ok(write_obj(w, "cloth", c.positions(), c.triangles())?)
    })
}

fn write_pictures(dir: &Path, cloth: &AdaptiveCloth, kept: &[Kept]) -> Result<()> {
    let c = cloth.cloth();
    let objects = object_meshes(c);
    let mut bounds = Aabb::from_points(c.positions().iter().copied().filter(|p| p.is_finite()));
    for (_, x, _) in kept {
        bounds = x.iter().filter(|p| p.is_finite()).fold(bounds, |b, p| b.including(*p));
    }
    for (o, unbounded) in &objects {
        if !unbounded {
            bounds = bounds.union(o.aabb());
        }
    }
    let camera = Camera::framing(bounds, DVec3::new(-0.55, -1.0, -0.6), DVec3::Z, 35.0);
    let picture = |x: &[DVec3], tris: &[[u32; 3]], (w, h): (u32, u32), label: &str| -> Result<Image> {
        let mut meshes: Vec<RenderMesh> =
            objects.iter().map(|(o, _)| RenderMesh::from_mesh(o, [150, 150, 160])).collect();
        meshes.push(RenderMesh::new(x, tris, [200, 70, 70]).with_edges());
        let mut img = render(&meshes, &camera, &RenderSettings::new(w, h))?;
        img.label(8, 6, label, (h as f64 / 18.0).clamp(12.0, 24.0))?;
        Ok(img)
    };
    let last = picture(c.positions(), c.triangles(), (960, 720), &format!("t = {:.3} s", c.time()))?;
    let tiles = kept
        .iter()
        .map(|(t, x, tris)| picture(x, tris, (400, 300), &format!("t = {t:.3} s, {} faces", tris.len())))
        .collect::<Result<Vec<_>>>()?;
    crate::picture::write_final_and_sheet(dir, &last, &tiles, 3)
}
