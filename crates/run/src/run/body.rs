//! Running articulated figures: body scenes (`BodyScene(…)`, figures holding poses, e.g.
//! `assets/scenes/stand.ron`) and character scenes (`CharacterScene(…)`, figures driven by a controller,
//! e.g. `assets/scenes/walk.ron`). One loop for both: box-figure frames as PNG (left limbs green, right
//! limbs red, as in Nunes 2006), a contact sheet, per-model numbers, and for characters the thesis's
//! evaluation when the scene asks for one.

use std::path::Path;
use std::time::Instant;

use anima_body::{BodyError, BodyPose, Ground, Sensors, Shape, Side, Skeleton, World};
use anima_character::{Character, procedures};
use anima_scene::body::LoadedBody;
use anima_scene::character::{Evaluation, LoadedCharacter};
use anima_viz::{Image, View2d, fill_disc, fill_polygon, stroke_polygon};
use anyhow::Result;
use serde::Serialize;

use super::export::GltfExport;
use super::series::FrameSeries;
use super::{Detail, OutputClock, Progress, RunOptions, Summary};
use crate::live::{LiveRun, ParamChange};
use crate::objectives::{self, FlipOutcome, ThrowOutcome, WalkOutcome};
use crate::output::write_atomic;

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

/// The numbers of a run of figures.
#[derive(Debug, Clone, Serialize)]
pub struct BodyDetail {
    pub dt: f64,
    pub substeps: u32,
    pub solver_iterations: u32,
    /// The part of the wall time spent drawing frames, s.
    pub picture_seconds: f64,
    /// Control steps per second of wall time, the pictures' time left out.
    pub steps_per_second: f64,
    pub models: Vec<ModelSummary>,
    /// A character scene's evaluation, when it asks for one.
    pub evaluation: Option<EvaluationOutcome>,
    /// Controller parameters a live page changed during the run (`anima run --live`), in order; left
    /// out of the summary when none was.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub parameter_changes: Vec<ParamChange>,
}

/// What a character scene's evaluation measured.
#[derive(Debug, Clone, Serialize)]
pub enum EvaluationOutcome {
    Walk(WalkOutcome),
    Throw(ThrowOutcome),
    Backflip { outcome: FlipOutcome, flipped: bool },
}

/// Figures a run steps: a world with its own sensor readings (body scenes), or a character whose
/// controller senses (character scenes).
pub(crate) trait Figures {
    fn world(&self) -> &World;
    fn sensors(&self) -> &[Sensors];
    /// One control step, the sensors read afterwards.
    fn step(&mut self) -> Result<(), BodyError>;
    /// The controller driving the figures, whose parameters a live page may set; `None` for figures
    /// holding poses.
    fn controller_mut(&mut self) -> Option<&mut anima_control::Controller> {
        None
    }
}

pub(crate) struct Posed {
    world: World,
    sensors: Vec<Sensors>,
}

impl Posed {
    /// A body scene's figures, built and sensed once.
    pub(crate) fn build(loaded: &LoadedBody) -> Result<Self> {
        let world = loaded.scene.build(&loaded.skeletons)?;
        let mut sensors: Vec<Sensors> =
            (0..world.n_models()).map(|m| Sensors::new(&world, m)).collect::<Result<_, _>>()?;
        for s in &mut sensors {
            world.sense(s)?;
        }
        Ok(Self { world, sensors })
    }
}

/// A character scene's figures with their controller, ready to step: the world settings, skeletons,
/// placements and controller the scene file names (`examples/walker.rs`).
pub fn build_character(loaded: &LoadedCharacter) -> Result<Character> {
    let scene = &loaded.scene;
    let mut world = World::new(scene.world)?;
    for (m, sk) in scene.models.iter().zip(&loaded.skeletons) {
        world.add_model(sk, m.placement)?;
    }
    let aliases: Vec<&str> = scene.models.iter().map(|m| m.alias.as_str()).collect();
    Ok(Character::new(world, loaded.controller.clone(), procedures(), &aliases)?)
}

impl Figures for Posed {
    fn world(&self) -> &World {
        &self.world
    }
    fn sensors(&self) -> &[Sensors] {
        &self.sensors
    }
    fn step(&mut self) -> Result<(), BodyError> {
        self.world.step()?;
        for s in &mut self.sensors {
            self.world.sense(s)?;
        }
        Ok(())
    }
}

impl Figures for Character {
    fn world(&self) -> &World {
        &self.env.world
    }
    fn sensors(&self) -> &[Sensors] {
        &self.env.sensors
    }
    fn step(&mut self) -> Result<(), BodyError> {
        Character::step(self)
    }
    fn controller_mut(&mut self) -> Option<&mut anima_control::Controller> {
        Some(&mut self.controller)
    }
}

/// Runs a body scene: every model holds its pose.
pub fn run_body(
    loaded: &LoadedBody,
    label: &str,
    opts: &RunOptions,
    progress: &mut dyn Progress,
) -> Result<Summary> {
    let scene = &loaded.scene;
    let mut figures = Posed::build(loaded)?;
    let n_steps = scene.n_steps();
    run_figures(&mut figures, label, n_steps, scene.frame_interval_s()?, opts, progress, |_| false)
}

/// Runs a character scene: the controller drives the models; the scene's evaluation, if any, is taken
/// over the run (until it ends the evaluation, after which the figures run on to the end).
pub fn run_character(
    loaded: &LoadedCharacter,
    label: &str,
    opts: &RunOptions,
    progress: &mut dyn Progress,
) -> Result<Summary> {
    let scene = &loaded.scene;
    let mut c = build_character(loaded)?;
    enum Tracker {
        None,
        Walk(objectives::WalkTracker),
        Throw(objectives::ThrowTracker),
        Flip(objectives::FlipTracker),
    }
    let mut tracker = match scene.evaluation {
        Evaluation::None => Tracker::None,
        Evaluation::Walk => {
            let rules = objectives::WalkRules {
                window: 0,
                stop_on_failure: true,
                ..objectives::WalkRules::default()
            };
            Tracker::Walk(objectives::WalkTracker::new(&c, &rules))
        }
        Evaluation::Throw => match objectives::ThrowTracker::new(&c, &objectives::BASKET)? {
            Some(t) => Tracker::Throw(t),
            None => anyhow::bail!("{label}: a throw evaluation needs a body `ball` on the first model"),
        },
        Evaluation::Backflip => match objectives::FlipTracker::new(&c) {
            Some(t) => Tracker::Flip(t),
            None => anyhow::bail!(
                "{label}: a backflip evaluation needs two models, the first with an abdomen and a pelvis"
            ),
        },
    };
    // The outcome is taken when the evaluation ends (a fall ends a walk), as the thesis's evaluators do.
    let outcome_of = |tracker: &Tracker, c: &Character| match tracker {
        Tracker::None => None,
        Tracker::Walk(t) => Some(EvaluationOutcome::Walk(t.outcome(c))),
        Tracker::Throw(t) => Some(EvaluationOutcome::Throw(t.outcome())),
        Tracker::Flip(t) => {
            let outcome = t.outcome(c);
            Some(EvaluationOutcome::Backflip { outcome, flipped: outcome.flipped() })
        }
    };
    let mut evaluation = None;
    let mut summary = run_figures(
        &mut c,
        label,
        scene.n_steps(),
        scene.frame_interval_s()?,
        opts,
        progress,
        |c: &Character| {
            if evaluation.is_none() {
                let over = match &mut tracker {
                    Tracker::None => false,
                    Tracker::Walk(t) => t.observe(c),
                    Tracker::Throw(t) => t.observe(c),
                    Tracker::Flip(t) => t.observe(c),
                };
                if over {
                    evaluation = outcome_of(&tracker, c);
                }
            }
            false
        },
    )?;
    let evaluation = evaluation.or_else(|| outcome_of(&tracker, &c));
    if let Detail::Body(d) = &mut summary.detail {
        d.evaluation = evaluation;
    }
    Ok(summary)
}

/// The one loop over figures: `after_step` sees them after every step and may stop the run.
fn run_figures<F: Figures>(
    figures: &mut F,
    label: &str,
    n_steps: u64,
    frame_interval: f64,
    opts: &RunOptions,
    progress: &mut dyn Progress,
    mut after_step: impl FnMut(&F) -> bool,
) -> Result<Summary> {
    let world = figures.world();
    let settings = *world.settings();
    let n_models = world.n_models();
    let mut stats: Vec<ModelSummary> = Vec::with_capacity(n_models);
    let mut hips = Vec::with_capacity(n_models);
    for (m, s) in figures.sensors().iter().enumerate() {
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
    let frame_every = ((frame_interval / settings.dt).round() as u64).max(1);
    let mut view = view_for(world)?;
    // How high above the picture's bottom the ground under the figures starts, m: the view keeps it.
    let ground_above_bottom = figures_middle(world, &mut Vec::new())?
        .zip(world.settings().ground)
        .map_or(0.0, |(x, g)| g.height_at(x) - view.y_min);
    let mut frames: Vec<Image> = Vec::new();
    let mut poses = Vec::new();
    let out = opts.picture_dir();
    let mut picture = |world: &World, k: usize, frames: &mut Vec<Image>| -> Result<()> {
        view = follow(view, ground_above_bottom, world, &mut poses)?;
        let img = draw(world, &view, &mut poses)?;
        if let Some(dir) = out {
            write_png(&dir.join(format!("frame_{k:04}.png")), &img)?;
        }
        frames.push(img);
        Ok(())
    };
    if out.is_some() {
        picture(world, 0, &mut frames)?;
    }
    // The export's frames are the pictures' frames: the start, then every `frame_every` steps.
    let mut export = match opts.export_dir() {
        Some(_) => {
            let mut e = GltfExport::figures(world, (n_steps / frame_every) as usize)?;
            e.figure_frame(0, world)?;
            Some(e)
        }
        None => None,
    };
    // Frame by frame, per model: the pelvis's height and speed and the contacts (series.json, when the
    // run writes output), at the pictures' frames.
    let mut series = match &opts.out_dir {
        Some(_) => {
            let mut names = Vec::new();
            for m in 0..n_models {
                let prefix =
                    if n_models > 1 { format!("{} ", world.skeleton(m)?.name()) } else { String::new() };
                names.push((format!("{prefix}pelvis height"), "m"));
                names.push((format!("{prefix}pelvis speed"), "m/s"));
                names.push((format!("{prefix}contacts"), "count"));
            }
            let mut f = FrameSeries::new(names);
            f.push(world.time(), &frame_values(figures.sensors(), &hips));
            Some(f)
        }
        None => None,
    };
    // A live page sees the start, then the export's frames; its commands are taken before each step.
    let mut live = opts.live.as_ref().map(LiveRun::new);
    let mut live_poses = Vec::new();
    if let Some(l) = &mut live {
        l.figure_frame(0, world, &mut live_poses)?;
    }
    let mut all_finite = true;
    let mut error = None;
    let mut pictures = OutputClock::default();
    progress.begin(n_steps);
    let started = Instant::now();
    let mut steps = 0;
    for k in 1..=n_steps {
        if let Some(l) = &mut live {
            let t = figures.world().time();
            l.commands(figures.controller_mut(), k, t)?;
        }
        if let Err(e) = figures.step() {
            all_finite = false;
            error = Some(e.to_string());
            break;
        }
        steps = k;
        for (m, s) in figures.sensors().iter().enumerate() {
            all_finite &= s.all_finite();
            update_stats(&mut stats[m], s, figures.world().skeleton(m)?, hips[m]);
        }
        if let Some(why) = through_the_ground(figures.world(), figures.sensors())? {
            error = Some(format!("step {k} (t = {:.4} s): {why}", k as f64 * settings.dt));
            break;
        }
        if out.is_some() && k % frame_every == 0 {
            pictures.time(|| picture(figures.world(), frames.len(), &mut frames))?;
        }
        if let Some(e) = &mut export
            && k % frame_every == 0
        {
            e.figure_frame((k / frame_every) as usize, figures.world())?;
        }
        if let Some(f) = &mut series
            && k % frame_every == 0
        {
            f.push(figures.world().time(), &frame_values(figures.sensors(), &hips));
        }
        if let Some(l) = &mut live
            && k % frame_every == 0
        {
            l.figure_frame((k / frame_every) as usize, figures.world(), &mut live_poses)?;
        }
        if k % (n_steps / 100).max(1) == 0 {
            progress.advance(k);
        }
        crate::interrupt::check()?;
        if after_step(figures) {
            break;
        }
    }
    let wall_seconds = started.elapsed().as_secs_f64();
    let picture_seconds = pictures.seconds();
    progress.end();
    let sim_seconds = (wall_seconds - picture_seconds).max(1e-12);
    let mut warnings = Vec::new();
    super::closing_warnings(export, opts, None, progress, &mut warnings)?;
    if let (Some(dir), Some(f)) = (&opts.out_dir, &series) {
        f.write(dir)?;
    }
    if let Some(dir) = out
        && let Some(last) = frames.last()
    {
        let tiles: Vec<Image> = sheet_indices(frames.len(), 9).iter().map(|&i| frames[i].clone()).collect();
        crate::picture::write_final_and_sheet(dir, last, &tiles, 3)?;
    }
    Ok(Summary {
        scene: label.to_owned(),
        kind: "figures",
        steps,
        frames: frames.len(),
        simulated_seconds: steps as f64 * settings.dt,
        wall_seconds,
        output_seconds: picture_seconds,
        all_finite,
        error,
        warnings,
        self_intersections: None,
        detail: Detail::Body(BodyDetail {
            dt: settings.dt,
            substeps: settings.substeps,
            solver_iterations: settings.solver.iterations,
            picture_seconds,
            // Stepping and sensing every model each step; the pictures' time is left out.
            steps_per_second: steps as f64 / sim_seconds,
            models: stats,
            evaluation: None,
            parameter_changes: live.map(|l| l.changes).unwrap_or_default(),
        }),
    })
}

/// Each model's pelvis height (m) and speed (m/s) and its number of contacts, as the series list them.
fn frame_values(sensors: &[Sensors], hips: &[(usize, [f64; 2])]) -> Vec<Option<f64>> {
    sensors
        .iter()
        .zip(hips)
        .flat_map(|(s, &(pelvis, _))| {
            let [vx, vy] = s.body_velocity[pelvis];
            [Some(s.body_position[pelvis][1]), Some(vx.hypot(vy)), Some(s.contacts.len() as f64)]
        })
        .collect()
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

/// The extent of every model's body centres: (leftmost x, rightmost x, highest y), m; infinite
/// without bodies.
fn figures_extent(world: &World, poses: &mut Vec<BodyPose>) -> Result<(f64, f64, f64)> {
    let (mut x0, mut x1, mut y1) = (f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
    for m in 0..world.n_models() {
        world.body_poses(m, poses)?;
        for p in poses.iter() {
            x0 = x0.min(p.centre[0]);
            x1 = x1.max(p.centre[0]);
            y1 = y1.max(p.centre[1]);
        }
    }
    Ok((x0, x1, y1))
}

/// A view framing every model's initial configuration with room to move.
fn view_for(world: &World) -> Result<View2d> {
    let (x0, x1, y1) = figures_extent(world, &mut Vec::new())?;
    let ground = world.settings().ground.map_or(0.0, |g| g.height_at(x0).min(g.height_at(x1)));
    Ok(View2d::fit(x0 - 1.0, ground - 0.3, x1 + 1.0, y1 + 0.4, WIDTH, HEIGHT, 8))
}

/// The middle of the span of every model's body centres across, m (`None` without bodies).
fn figures_middle(world: &World, poses: &mut Vec<BodyPose>) -> Result<Option<f64>> {
    let (x0, x1, _) = figures_extent(world, poses)?;
    Ok((x0.is_finite() && x1.is_finite()).then_some(0.5 * (x0 + x1)))
}

/// The view moved to keep the figures in sight: when the middle of their bodies' centres has left the
/// middle third of the picture across, the view is centred on it again; when the ground under it has
/// moved more than a sixth of the picture's height from `ground_above_bottom` (its height above the
/// picture's bottom in the first view), the view is raised or lowered to put it back there. The scale
/// stays. A figure that stays near where it started keeps its first view; a walker is followed along
/// its walk and up or down a slope.
fn follow(
    view: View2d,
    ground_above_bottom: f64,
    world: &World,
    poses: &mut Vec<BodyPose>,
) -> Result<View2d> {
    let Some(x) = figures_middle(world, poses)? else { return Ok(view) };
    let (w, h) = (f64::from(WIDTH) / view.scale, f64::from(view.height) / view.scale);
    let mut next = view;
    if (x - (view.x_min + w / 2.0)).abs() > w / 6.0 {
        next.x_min = x - w / 2.0;
    }
    if let Some(g) = world.settings().ground {
        let at = g.height_at(x);
        if (at - next.y_min - ground_above_bottom).abs() > h / 6.0 {
            next.y_min = at - ground_above_bottom;
        }
    }
    Ok(next)
}

/// Box figures of every model: centre bodies grey-blue, left limbs green, right limbs red; the left
/// side is drawn last so that it lies in front, as the thesis's figures show it.
fn draw(world: &World, view: &View2d, poses: &mut Vec<BodyPose>) -> Result<Image> {
    let mut img = Image::new(WIDTH, HEIGHT, SKY)?;
    if let Some(g) = world.settings().ground {
        draw_ground(&mut img, view, &g);
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
pub fn draw_ground(img: &mut Image, view: &View2d, ground: &Ground) {
    let (w, h) = (f64::from(img.width()), f64::from(img.height()));
    // The profile sampled every 4 pixels (x = x_min + px / scale), closed along the picture's bottom.
    let mut pts: Vec<(f64, f64)> = (0..=img.width().div_ceil(4))
        .map(|k| {
            let px = f64::from(k * 4).min(w);
            let x = view.x_min + px / view.scale;
            (px, view.to_px(x, ground.height_at(x)).1)
        })
        .collect();
    pts.extend([(w, h), (0.0, h)]);
    fill_polygon(img, &pts, GROUND);
}

/// How far below the ground under it a body's centre may lie, m: more than any body's half-size, so a
/// centre this deep is a body that went through the ground, not one pressed into it.
const THROUGH_THE_GROUND_M: f64 = 0.5;

/// The first body whose centre lies more than [`THROUGH_THE_GROUND_M`] under the ground, described,
/// or `None`. A physics step too long for the contacts lets a falling figure pass through the ground
/// and sink for ever, finite and quiet (a control step of 1 s once ended a walk with the head 8.56 m
/// under the ground and no word of it): this ends such a run at the step it happened.
fn through_the_ground(world: &World, sensors: &[Sensors]) -> Result<Option<String>> {
    let Some(ground) = world.settings().ground else { return Ok(None) };
    for (m, s) in sensors.iter().enumerate() {
        for (b, p) in s.body_position.iter().enumerate() {
            let depth = ground.height_at(p[0]) - p[1];
            if depth > THROUGH_THE_GROUND_M {
                let settings = world.settings();
                let skeleton = world.skeleton(m)?;
                return Ok(Some(format!(
                    "body `{}` of model `{}` is {depth:.2} m under the ground: it went through it. The physics \
                     step (dt_s / substeps = {:.4} s) is too long for the contacts; use a smaller dt_s or more \
                     substeps",
                    skeleton.body(b).name,
                    skeleton.name(),
                    settings.dt / f64::from(settings.substeps.max(1)),
                )));
            }
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::Silent;
    use anima_scene::{LoadOptions, Scene, load};

    fn asset(rel: &str) -> std::path::PathBuf {
        crate::test_asset(rel)
    }

    fn body(rel: &str) -> LoadedBody {
        match load(&asset(rel), &LoadOptions::default()).unwrap() {
            Scene::Body(b) => b,
            other => panic!("{rel}: a body scene, found {:?}", other.kind()),
        }
    }

    #[test]
    fn the_stand_scene_runs_stands_and_writes_frames() {
        let dir = std::env::temp_dir().join(format!("anima-body-run-{}", std::process::id()));
        let mut scene = body("scenes/stand.ron");
        scene.scene.duration = 4.0;
        let s = run_body(&scene, "stand", &RunOptions::writing_to(&dir), &mut Silent).unwrap();
        assert_eq!(s.steps, 80);
        assert!(s.all_finite && s.error.is_none());
        assert_eq!(s.frames, 3, "frames at 0, 2 and 4 s");
        let Detail::Body(d) = &s.detail else { panic!("figures") };
        let m = &d.models[0];
        assert!(m.min_head_height > 1.6 && m.only_feet_touched, "{m:?}");
        for f in ["frame_0000.png", "frame_0002.png", "final.png", "frames.png"] {
            let bytes = std::fs::read(dir.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
            assert_eq!(&bytes[1..4], b"PNG");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The humanoid standing `dx` along ground that rises at 10° from 2 m on.
    fn humanoid_on_a_slope(dx: f64) -> World {
        let mut settings = anima_body::WorldSettings::thesis();
        settings.ground = settings
            .ground
            .map(|g| Ground { relief: anima_body::Relief::Slope { from_x: 2.0, degrees: 10.0 }, ..g });
        let mut world = World::new(settings).unwrap();
        let sk = anima_body::BuiltinSkeleton::Humanoid.load();
        world.add_model(&sk, anima_body::Placement::OnGround { dx }).unwrap();
        world
    }

    #[test]
    fn the_view_follows_the_figures_along_and_up_the_ground() {
        let start = humanoid_on_a_slope(0.0);
        let first = view_for(&start).unwrap();
        let ground = |w: &World, x: f64| w.settings().ground.unwrap().height_at(x);
        let reference = ground(&start, 0.0) - first.y_min;
        let mut poses = Vec::new();
        // Where it started, the first view stays as it is.
        assert_eq!(follow(first, reference, &start, &mut poses).unwrap(), first);
        // 20 m up the slope, the view is centred on the figure and the ground under it is back where it
        // was in the first picture; the scale is the same.
        let later = humanoid_on_a_slope(20.0);
        let v = follow(first, reference, &later, &mut poses).unwrap();
        let x = figures_middle(&later, &mut poses).unwrap().unwrap();
        let width = f64::from(WIDTH) / v.scale;
        assert!((v.x_min + width / 2.0 - x).abs() < 1e-9, "{v:?}");
        assert!((ground(&later, x) - v.y_min - reference).abs() < 1e-9, "{v:?}");
        assert_eq!((v.scale, v.height), (first.scale, first.height));
    }

    #[test]
    fn the_standard_biped_scene_reports_hip_height_and_pitch() {
        let mut scene = body("scenes/standard-biped.ron");
        assert_eq!(scene.scene.n_steps(), 10_000, "10 s at 1 ms");
        scene.scene.duration = 1.0;
        let s = run_body(&scene, "biped", &RunOptions::quiet(), &mut Silent).unwrap();
        assert_eq!(s.steps, 1000);
        let Detail::Body(d) = &s.detail else { panic!("figures") };
        let m = &d.models[0];
        assert!((m.initial_hip_height_m - 0.95).abs() < 1e-6, "hips start at 0.95 m: {m:?}");
        assert!(m.min_hip_height_m > 0.98 * m.initial_hip_height_m, "{m:?}");
        assert!(m.max_abs_hip_pitch_rad < 0.02 && m.only_feet_touched, "{m:?}");
    }
}
