//! Running a body scene (`BodyScene(…)` RON, e.g. `assets/scenes/stand.ron`): the control-step loop,
//! box-figure frames as PNG (left limbs green, right limbs red, as in Nunes 2006), a contact sheet
//! and a JSON summary.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anima_body::{BodyPose, BodyScene, Sensors, Shape, Side, Skeleton, SkeletonSource, World};
use anima_viz::{Image, View2d, fill_disc, fill_polygon, stroke_polygon};
use anyhow::{Context, Result, bail};
use serde::Serialize;

use crate::output::write_atomic;

/// Whether the file at `path` is a body scene: a `.ron` whose top-level value is `BodyScene(…)`. The
/// FLEX3D RON scenes start with their own struct, so the two never clash and neither is parsed twice.
pub fn is_body_scene_file(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ron"))
        && std::fs::read_to_string(path).is_ok_and(|t| BodyScene::is_body_scene(&t))
}

/// What a body run writes and shows.
#[derive(Debug, Clone)]
pub struct BodyRunOptions {
    /// Folder for frames and pictures; `None` writes nothing.
    pub out_dir: Option<PathBuf>,
    /// Write `frame_<k>.png` for every frame, `final.png` and the `frames.png` sheet.
    pub pictures: bool,
    /// Overrides of the scene's step and duration, seconds.
    pub dt: Option<f64>,
    pub duration: Option<f64>,
    /// Show progress on standard error.
    pub progress: bool,
}

/// Per-model numbers of a run.
#[derive(Debug, Clone, Serialize)]
pub struct ModelSummary {
    pub name: String,
    pub pd_mode: String,
    pub gain_scale: f64,
    pub bodies: usize,
    pub actuators: usize,
    /// Lowest head (or highest body) centre seen, m; a standing figure keeps it high.
    pub min_head_height: f64,
    pub final_head_height: f64,
    /// Centre of mass at the start and the end, m, and the largest horizontal distance it moved.
    pub initial_com: [f64; 2],
    pub final_com: [f64; 2],
    pub max_com_drift: f64,
    /// Largest |joint angle| seen, rad.
    pub max_joint_angle: f64,
    /// Only feet touched the ground during the whole run.
    pub only_feet_touched: bool,
    /// The hip: the lowest joint anchor on the pelvis (the root body when no body is the pelvis),
    /// i.e. the torso's base. Its height at the start and the end, m, and the lowest seen.
    pub initial_hip_height_m: f64,
    pub hip_height_m: f64,
    pub min_hip_height_m: f64,
    /// The pelvis's final world angle about z (pitch), rad, counter-clockwise, 0 in the initial
    /// configuration; and the largest |pitch| seen.
    pub hip_pitch_rad: f64,
    pub max_abs_hip_pitch_rad: f64,
}

/// The body whose base is the hip and the hip's offset from that body's centre in the initial
/// configuration (where every angle is 0): the pelvis (or first root) and its lowest joint anchor.
fn hip_reference(sk: &Skeleton, s: &Sensors) -> (usize, [f64; 2]) {
    let body = s.layout.pelvis.unwrap_or(sk.roots()[0]);
    let centre = sk.body(body).centre;
    let anchor = (0..sk.n_joints())
        .filter(|&j| sk.joint_bodies(j).0 == body)
        .map(|j| sk.desc().joints[j].anchor)
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap_or(centre);
    (body, [anchor.0 - centre.0, anchor.1 - centre.1])
}

/// The hip's world height, m, and the hip body's pitch, rad.
fn hip_height_pitch(s: &Sensors, (body, offset): (usize, [f64; 2])) -> (f64, f64) {
    let th = s.body_angle[body];
    let (sin, cos) = th.sin_cos();
    (s.body_position[body][1] + sin * offset[0] + cos * offset[1], th)
}

/// The JSON summary of a body run.
#[derive(Debug, Clone, Serialize)]
pub struct BodySummary {
    pub scene: String,
    pub dt: f64,
    pub substeps: u32,
    pub solver_iterations: u32,
    pub steps: u64,
    pub frames: usize,
    pub simulated_seconds: f64,
    /// Wall time of the step loop, and the part of it spent drawing frames.
    pub wall_seconds: f64,
    pub picture_seconds: f64,
    pub steps_per_second: f64,
    pub all_finite: bool,
    /// The error that stopped the run, if any.
    pub diverged: Option<String>,
    pub models: Vec<ModelSummary>,
}

/// Reads a body scene and every skeleton file it names (relative to the scene's folder).
pub fn load(path: &Path) -> Result<(BodyScene, Vec<Skeleton>)> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let scene = BodyScene::from_ron_str(&text).with_context(|| format!("{}", path.display()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut skeletons = Vec::with_capacity(scene.models.len());
    for entry in &scene.models {
        let sk = match &entry.skeleton {
            SkeletonSource::Builtin(b) => b.load(),
            SkeletonSource::File(f) => {
                let p = dir.join(f);
                let t = std::fs::read_to_string(&p).with_context(|| format!("reading {}", p.display()))?;
                Skeleton::from_ron_str(&t).with_context(|| format!("{}", p.display()))?
            }
        };
        skeletons.push(sk);
    }
    Ok((scene, skeletons))
}

/// Runs a loaded body scene.
pub fn run(scene: &BodyScene, skeletons: &[Skeleton], opts: &BodyRunOptions) -> Result<BodySummary> {
    let mut scene = scene.clone();
    if let Some(dt) = opts.dt {
        if !(dt > 0.0 && dt.is_finite()) {
            bail!("--dt must be a positive number of seconds, found {dt}");
        }
        scene.world.dt = dt;
    }
    if let Some(d) = opts.duration {
        if !(d > 0.0 && d.is_finite()) {
            bail!("--duration must be a positive number of seconds, found {d}");
        }
        scene.duration = d;
    }
    let mut world = scene.build(skeletons)?;
    let n_models = world.n_models();
    let mut sensors: Vec<Sensors> =
        (0..n_models).map(|m| Sensors::new(&world, m)).collect::<Result<_, _>>()?;
    let mut stats: Vec<ModelSummary> = Vec::with_capacity(n_models);
    let mut hips = Vec::with_capacity(n_models);
    for (m, s) in sensors.iter_mut().enumerate() {
        world.sense(s)?;
        let sk = world.skeleton(m)?;
        let hip = hip_reference(sk, s);
        hips.push(hip);
        let (hip_height, hip_pitch) = hip_height_pitch(s, hip);
        stats.push(ModelSummary {
            name: sk.name().into(),
            pd_mode: format!("{:?}", sk.actuation().mode),
            gain_scale: sk.actuation().gain_scale,
            bodies: sk.n_bodies(),
            actuators: sk.n_actuators(),
            min_head_height: f64::INFINITY,
            final_head_height: 0.0,
            initial_com: s.com,
            final_com: s.com,
            max_com_drift: 0.0,
            max_joint_angle: 0.0,
            only_feet_touched: true,
            initial_hip_height_m: hip_height,
            hip_height_m: hip_height,
            min_hip_height_m: hip_height,
            hip_pitch_rad: hip_pitch,
            max_abs_hip_pitch_rad: hip_pitch.abs(),
        });
    }

    let n_steps = scene.n_steps();
    let frame_every = ((scene.frame_interval / scene.world.dt).round() as u64).max(1);
    let view = view_for(&world)?;
    let mut frames: Vec<Image> = Vec::new();
    let mut poses = Vec::new();
    let out = opts.out_dir.as_deref().filter(|_| opts.pictures);
    let mut picture = |world: &World, k: usize, frames: &mut Vec<Image>| -> Result<()> {
        let img = draw(world, &view, &mut poses)?;
        if let Some(dir) = out {
            write_png(&dir.join(format!("frame_{k:04}.png")), &img)?;
        }
        frames.push(img);
        Ok(())
    };
    if out.is_some() {
        picture(&world, 0, &mut frames)?;
    }

    let mut all_finite = true;
    let mut diverged = None;
    let mut picture_seconds = 0.0;
    let started = Instant::now();
    let mut steps = 0;
    for k in 1..=n_steps {
        if let Err(e) = world.step() {
            all_finite = false;
            diverged = Some(e.to_string());
            break;
        }
        steps = k;
        for (m, s) in sensors.iter_mut().enumerate() {
            world.sense(s)?;
            all_finite &= s.all_finite();
            let sk = world.skeleton(m)?;
            update_stats(&mut stats[m], s, sk, hips[m]);
        }
        if out.is_some() && k % frame_every == 0 {
            let t0 = Instant::now();
            picture(&world, frames.len(), &mut frames)?;
            picture_seconds += t0.elapsed().as_secs_f64();
        }
        if opts.progress && k % (n_steps / 20).max(1) == 0 {
            eprint!("\ranima: {:>3}% ({k}/{n_steps} steps)", 100 * k / n_steps);
        }
    }
    let wall_seconds = started.elapsed().as_secs_f64();
    let sim_seconds = (wall_seconds - picture_seconds).max(1e-12);
    if opts.progress {
        eprintln!();
    }
    if let Some(dir) = out {
        if let Some(last) = frames.last() {
            write_png(&dir.join("final.png"), last)?;
        }
        let pick = sheet_indices(frames.len(), 9);
        let tiles: Vec<Image> = pick.iter().map(|&i| frames[i].clone()).collect();
        if !tiles.is_empty() {
            write_png(&dir.join("frames.png"), &Image::grid(&tiles, 3, 6, [255, 255, 255])?)?;
        }
    }
    Ok(BodySummary {
        scene: scene.name.clone(),
        dt: scene.world.dt,
        substeps: scene.world.substeps,
        solver_iterations: scene.world.solver.iterations,
        steps,
        frames: frames.len(),
        simulated_seconds: steps as f64 * scene.world.dt,
        wall_seconds,
        picture_seconds,
        // Stepping and sensing every model each step; the pictures' time is left out.
        steps_per_second: steps as f64 / sim_seconds,
        all_finite,
        diverged,
        models: stats,
    })
}

fn update_stats(st: &mut ModelSummary, s: &Sensors, sk: &Skeleton, hip: (usize, [f64; 2])) {
    let (hip_height, hip_pitch) = hip_height_pitch(s, hip);
    st.hip_height_m = hip_height;
    st.min_hip_height_m = st.min_hip_height_m.min(hip_height);
    st.hip_pitch_rad = hip_pitch;
    st.max_abs_hip_pitch_rad = st.max_abs_hip_pitch_rad.max(hip_pitch.abs());
    let head = s.layout.head.map_or_else(
        || s.body_position.iter().map(|p| p[1]).fold(f64::NEG_INFINITY, f64::max),
        |h| s.body_position[h][1],
    );
    st.min_head_height = st.min_head_height.min(head);
    st.final_head_height = head;
    st.final_com = s.com;
    st.max_com_drift = st.max_com_drift.max((s.com[0] - st.initial_com[0]).abs());
    st.max_joint_angle = s.joint_angle.iter().fold(st.max_joint_angle, |a, q| a.max(q.abs()));
    st.only_feet_touched &= s
        .contacts
        .iter()
        .all(|c| c.other != anima_body::Touch::Ground || sk.body(c.body).role == anima_body::Role::Foot);
}

/// Nine (or fewer) frame indices spread evenly from the first to the last.
fn sheet_indices(n: usize, k: usize) -> Vec<usize> {
    if n <= k {
        return (0..n).collect();
    }
    (0..k).map(|i| i * (n - 1) / (k - 1)).collect()
}

fn write_png(path: &Path, img: &Image) -> Result<()> {
    write_atomic(path, |w| Ok(img.write_png(w)?))
}

const WIDTH: u32 = 480;
const HEIGHT: u32 = 360;
pub const SKY: [u8; 3] = [250, 250, 246];
const GROUND: [u8; 3] = [205, 195, 175];
const OUTLINE: [u8; 3] = [40, 40, 40];

/// A fixed view framing every model's initial configuration with room to move.
fn view_for(world: &World) -> Result<View2d> {
    let mut poses = Vec::new();
    let (mut x0, mut x1, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
    for m in 0..world.n_models() {
        world.body_poses(m, &mut poses)?;
        for p in &poses {
            x0 = x0.min(p.centre[0]);
            x1 = x1.max(p.centre[0]);
            y1 = y1.max(p.centre[1]);
        }
    }
    let ground = world.settings().ground.map_or(0.0, |g| g.height);
    Ok(View2d::fit(x0 - 1.0, ground - 0.3, x1 + 1.0, y1 + 0.4, WIDTH, HEIGHT, 8))
}

/// Box figures of every model: centre bodies grey-blue, left limbs green, right limbs red; the left
/// side is drawn last so that it lies in front, as the thesis's figures show it.
fn draw(world: &World, view: &View2d, poses: &mut Vec<BodyPose>) -> Result<Image> {
    let mut img = Image::new(WIDTH, HEIGHT, SKY)?;
    if let Some(g) = world.settings().ground {
        draw_ground(&mut img, view, g.height);
    }
    for m in 0..world.n_models() {
        world.body_poses(m, poses)?;
        draw_bodies(&mut img, view, poses, 1.0);
    }
    let t = format!("t = {:.2} s", world.time());
    img.label(8, 6, &t, 16.0)?;
    Ok(img)
}

/// Draws one model's bodies as box figures: centre bodies grey-blue, left limbs green, right limbs red,
/// balls orange; the left side last so that it lies in front, as the thesis's figures show it. `weight`
/// in (0, 1] fades the colours towards the sky (older frames of a strobe picture).
pub fn draw_bodies(img: &mut Image, view: &View2d, poses: &[BodyPose], weight: f64) {
    let fade = |c: [u8; 3]| {
        let w = weight.clamp(0.0, 1.0);
        [0, 1, 2].map(|i| (w * f64::from(c[i]) + (1.0 - w) * f64::from(SKY[i])).round() as u8)
    };
    for side in [Side::Right, Side::Centre, Side::Left] {
        for p in poses.iter().filter(|p| p.side == side) {
            let colour = fade(match p.side {
                Side::Left => [60, 170, 60],
                Side::Right => [210, 60, 50],
                Side::Centre => [120, 140, 170],
            });
            match p.shape {
                Shape::Box { width, height } => {
                    let (s, c) = p.angle.sin_cos();
                    let corner = |u: f64, v: f64| {
                        let (x, y) = (u * width / 2.0, v * height / 2.0);
                        view.to_px(p.centre[0] + c * x - s * y, p.centre[1] + s * x + c * y)
                    };
                    let pts = [corner(-1.0, -1.0), corner(1.0, -1.0), corner(1.0, 1.0), corner(-1.0, 1.0)];
                    fill_polygon(img, &pts, colour);
                    stroke_polygon(img, &pts, 1.0, fade(OUTLINE));
                }
                Shape::Ball { radius } => {
                    let c = view.to_px(p.centre[0], p.centre[1]);
                    fill_disc(img, c, radius * view.scale + 1.0, fade(OUTLINE));
                    fill_disc(img, c, radius * view.scale, fade([230, 140, 40]));
                }
            }
        }
    }
}

/// Fills everything below `height` (world metres) with the ground colour.
pub fn draw_ground(img: &mut Image, view: &View2d, height: f64) {
    let (_, row) = view.to_px(0.0, height);
    let (w, h) = (f64::from(img.width()), f64::from(img.height()));
    fill_polygon(img, &[(0.0, row), (w, row), (w, h), (0.0, h)], GROUND);
}

/// Writes the summary as pretty JSON.
pub fn write_summary(path: &Path, summary: &BodySummary) -> Result<()> {
    write_atomic(path, |w| Ok(serde_json::to_writer_pretty(w, summary)?))
}

/// `anima run SCENE` for a body scene: runs it, writes pictures and `summary.json` (or `summary`),
/// reports on standard error. Exit code 2 when the simulation diverged.
pub fn run_command(
    path: &Path,
    out: &Path,
    summary: Option<&Path>,
    opts: BodyRunOptions,
    quiet: bool,
) -> Result<std::process::ExitCode> {
    let (scene, skeletons) = load(path)?;
    if !quiet {
        eprintln!(
            "anima: {} — body scene `{}`: {} models, {} steps of {} s",
            path.display(),
            scene.name,
            scene.models.len(),
            scene.n_steps(),
            opts.dt.unwrap_or(scene.world.dt)
        );
    }
    let s = run(&scene, &skeletons, &opts)?;
    let summary_path = summary.map_or_else(|| out.join("summary.json"), Path::to_path_buf);
    write_summary(&summary_path, &s)?;
    if !quiet {
        for m in &s.models {
            eprintln!(
                "anima: {} ({}, G = {}): head lowest {:.3} m, centre of mass moved {:.3} m; \
                 hip {:.4} m (from {:.4}), pitch {:.2e} rad",
                m.name,
                m.pd_mode,
                m.gain_scale,
                m.min_head_height,
                m.max_com_drift,
                m.hip_height_m,
                m.initial_hip_height_m,
                m.hip_pitch_rad
            );
        }
        eprintln!(
            "anima: {} steps in {:.2} s ({:.0} steps/s); wrote {}",
            s.steps,
            s.wall_seconds,
            s.steps_per_second,
            summary_path.display()
        );
    }
    if let Some(e) = &s.diverged {
        eprintln!("anima: error: {e}");
        return Ok(std::process::ExitCode::from(2));
    }
    Ok(std::process::ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn asset(rel: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(rel)
    }

    #[test]
    fn body_scenes_are_told_from_flex3d_scenes() {
        assert!(is_body_scene_file(&asset("assets/scenes/stand.ron")));
        assert!(is_body_scene_file(&asset("assets/scenes/backflip-pair.ron")));
        assert!(!is_body_scene_file(&asset("assets/flex3d/curtain.ron")));
        assert!(!is_body_scene_file(&asset("assets/flex3d/a2-4-cortinas.par")));
    }

    #[test]
    fn the_stand_scene_runs_stands_and_writes_frames() {
        let dir = std::env::temp_dir().join(format!("anima-body-run-{}", std::process::id()));
        let (scene, skeletons) = load(&asset("assets/scenes/stand.ron")).unwrap();
        let opts = BodyRunOptions {
            out_dir: Some(dir.clone()),
            pictures: true,
            dt: None,
            duration: Some(4.0),
            progress: false,
        };
        let s = run(&scene, &skeletons, &opts).unwrap();
        assert_eq!(s.steps, 80);
        assert!(s.all_finite && s.diverged.is_none());
        assert_eq!(s.frames, 3, "frames at 0, 2 and 4 s");
        let m = &s.models[0];
        assert!(m.min_head_height > 1.6 && m.only_feet_touched, "{m:?}");
        for f in ["frame_0000.png", "frame_0002.png", "final.png", "frames.png"] {
            let bytes = std::fs::read(dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
            assert_eq!(&bytes[1..4], b"PNG");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_standard_biped_scene_reports_hip_height_and_pitch() {
        let (scene, skeletons) = load(&asset("assets/scenes/standard-biped.ron")).unwrap();
        assert_eq!(scene.n_steps(), 10_000, "10 s at 1 ms");
        let opts =
            BodyRunOptions { out_dir: None, pictures: false, dt: None, duration: Some(1.0), progress: false };
        let s = run(&scene, &skeletons, &opts).unwrap();
        assert_eq!(s.steps, 1000);
        let m = &s.models[0];
        assert!((m.initial_hip_height_m - 0.95).abs() < 1e-6, "hips start at 0.95 m: {m:?}");
        assert!(m.min_hip_height_m > 0.98 * m.initial_hip_height_m, "{m:?}");
        assert!(m.max_abs_hip_pitch_rad < 0.02 && m.only_feet_touched, "{m:?}");
    }
}
