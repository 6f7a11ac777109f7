//! The run's side of a live run (`anima run SCENE --live`): frames handed out as they are computed,
//! and a page's commands taken in at the run's own pace — pause, resume, step one frame, and set a
//! controller parameter at the next control step (Nunes 2006's on-line modification of a controller,
//! spec C-28 and C-39).
//!
//! Why a trait here and not `anima-view`'s channels: the runtime sits above the library crates and
//! below the command, and the viewer knows no anima type (`docs/architecture.md`); the command joins
//! the two by implementing [`LiveLink`] over the viewer's channels. So this crate needs no server,
//! no async runtime, and a test can drive a live run through a plain channel.
//!
//! When commands are taken: at every control step of a figure run (before the step, so a parameter
//! set now drives that step), and once a frame in a cloth run (a cloth has no controller; pausing
//! between frames is what a watcher needs). While paused the loop waits on the link, looking at
//! [`crate::interrupt`] ten times a second, so Ctrl-C still ends the run.
//!
//! What the page draws is sent as a JSON note before the first frame (`{"mesh":…}`: triangles over the
//! frame's points, their count, and colours for figures), again whenever a remesher changes the
//! triangles, and again with the next frame while a full queue keeps dropping it; every frame then
//! carries only the points (x, y, z as `f32`, metres). The server sends notes before frames, so frames
//! of the old mesh still queued can reach the page after a new mesh: the page draws only frames with
//! as many points as its mesh has. Figures are drawn as their bodies'
//! boxes (four corners, two triangles) and balls (an octagon) in the plane z = 0.
//!
//! The slider range of a parameter: the interval the controller file gives it (the optimisers'), else
//! one derived from its kind and file value, since a controller file gives no bounds for a fixed
//! number ([`slider_range`]); a value outside it is refused by the page's server, and refused again
//! here.

use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use anima_body::{BodyPose, Shape, Side, World};
use anima_control::{Controller, ParamId, ParamInfo, ParamKind};
use anima_geom::DVec3;
use serde::Serialize;

/// What a page may ask of a running simulation (the viewer's `Command`, without the viewer).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LiveCommand {
    Pause,
    Resume,
    /// Compute one frame, then stay paused.
    Step,
    /// Set parameter `params[index]` of [`Live::params`] to `value` at the next control step.
    Set {
        index: usize,
        value: f64,
    },
}

/// The two directions between a run and whoever watches it. Implemented by the `anima` command over
/// `anima-view`'s bounded channels; every call must return promptly, never waiting on a slow page.
pub trait LiveLink: Send {
    /// A JSON note for the page (what to draw, a parameter change, a warning); returns whether it was
    /// queued (a full queue drops it, and a mesh note is then sent again with the next frame).
    fn tell(&mut self, json: String) -> bool;
    /// A frame: its number, time (s) and points (x, y, z, m). Dropped rather than waited for.
    fn frame(&mut self, index: usize, time_s: f64, positions: Vec<f32>);
    /// The next command, waiting up to `wait` for one (`None`: not at all).
    fn command(&mut self, wait: Option<Duration>) -> Option<LiveCommand>;
}

/// A controller parameter a live page may set: its name on the page, its id in the controller's
/// table, its value in the file and its slider range.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveParam {
    pub name: String,
    pub id: ParamId,
    pub value: f64,
    pub min: f64,
    pub max: f64,
}

/// A parameter changed on line: when, which and to what. A character run's summary lists them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParamChange {
    /// The control step the new value first drove (1 for the first step).
    pub step: u64,
    pub time_s: f64,
    pub name: String,
    pub value: f64,
}

/// A live link with the parameters its page was offered; shared so that [`crate::run::RunOptions`]
/// stays `Clone` (clones share the one link).
#[derive(Clone)]
pub struct Live {
    link: Arc<Mutex<dyn LiveLink>>,
    params: Arc<[LiveParam]>,
    paused: bool,
}

impl std::fmt::Debug for Live {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Live").field("params", &self.params.len()).finish_non_exhaustive()
    }
}

impl Live {
    /// `link` with the parameters the page offers (from [`parameters`]; none for cloth).
    pub fn new(link: impl LiveLink + 'static, params: Vec<LiveParam>) -> Self {
        Self { link: Arc::new(Mutex::new(link)), params: params.into(), paused: false }
    }

    /// The run starts paused, after its first frame, until the page says `resume` or `step`: a
    /// watcher opens the page before anything moves.
    pub fn start_paused(self) -> Self {
        Self { paused: true, ..self }
    }

    pub fn params(&self) -> &[LiveParam] {
        &self.params
    }

    /// The link, for a note from outside the run loop (the command's progress and warnings).
    pub fn link(&self) -> MutexGuard<'_, dyn LiveLink + 'static> {
        // A panic elsewhere while holding the link leaves nothing half-done in it: take it anyway.
        self.link.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }
}

/// The parameters a live page may set for `scene`: a character's controller's ([`parameters`]);
/// none for the other kinds.
pub fn scene_parameters(scene: &anima_scene::Scene) -> Vec<LiveParam> {
    match scene {
        anima_scene::Scene::Character(c) => parameters(&c.controller),
        _ => Vec::new(),
    }
}

/// Every parameter of `controller` a page may set, in table order, named by its label with the
/// characters a command word cannot hold replaced (`W-LEGS/E1/hip_l` is `W-LEGS.E1.hip_l`); a name
/// that repeats gets `.2`, `.3`… .
pub fn parameters(controller: &Controller) -> Vec<LiveParam> {
    let mut out: Vec<LiveParam> = Vec::with_capacity(controller.params().len());
    for (k, info) in controller.params().iter().enumerate() {
        let id = ParamId(k);
        let base: String = info
            .label
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() || "_-.".contains(c) { c } else { '.' })
            .collect();
        let mut name = base.clone();
        let mut n = 1;
        while out.iter().any(|p| p.name == name) {
            n += 1;
            name = format!("{base}.{n}");
        }
        let value = controller.param(id);
        let (min, max) = slider_range(info, value);
        out.push(LiveParam { name, id, value, min, max });
    }
    out
}

/// The range a page's slider covers for parameter `info` whose value is `value`: the file's interval
/// when it gives one (widened to hold the value), else, by kind — a target angle ±π/2 rad about its
/// value, a gain or sensor parameter ±max(|v|, 1) about it, a weight [0, max(2v, 1)], a delay or time
/// [0, max(2v, 10)] iterations. Wide enough to push a walker to a fall, narrow enough for a slider to
/// place a value to a hundredth of its span.
pub fn slider_range(info: &ParamInfo, value: f64) -> (f64, f64) {
    if let Some((a, b)) = info.range {
        return (a.min(value), b.max(value));
    }
    match info.kind {
        ParamKind::TargetAngle => (value - std::f64::consts::FRAC_PI_2, value + std::f64::consts::FRAC_PI_2),
        ParamKind::SensorParam | ParamKind::FeedbackGain => {
            let span = value.abs().max(1.0);
            (value - span, value + span)
        }
        ParamKind::Weight => (0.0, (2.0 * value).max(1.0)),
        ParamKind::InterpolationDelay | ParamKind::Time | ParamKind::OscillationDelay => {
            (0.0, (2.0 * value).max(10.0))
        }
    }
}

/// The note that tells the page the run has ended, and how.
pub fn done_note(how: &str) -> String {
    serde_json::json!({ "done": how }).to_string()
}

/// A run loop's live state: paused or not, a frame to stop after, what the page was last sent.
pub(crate) struct LiveRun {
    live: Live,
    paused: bool,
    /// A `step` asked for one frame: pause again after the next frame.
    stepping: bool,
    /// The triangles the page holds, to send them again only when they change.
    triangles: Vec<[u32; 3]>,
    mesh_sent: bool,
    pub(crate) changes: Vec<ParamChange>,
}

/// How often a paused run looks at [`crate::interrupt`].
const PAUSED_POLL: Duration = Duration::from_millis(100);

impl LiveRun {
    pub(crate) fn new(live: &Live) -> Self {
        Self {
            live: live.clone(),
            paused: live.paused,
            stepping: false,
            triangles: Vec::new(),
            mesh_sent: false,
            changes: Vec::new(),
        }
    }

    /// Takes the commands that arrived, waiting while paused. A `set` is applied to `controller` (when
    /// the run has one) before control step `step` at time `time_s`, and acknowledged to the page.
    pub(crate) fn commands(
        &mut self,
        mut controller: Option<&mut Controller>,
        step: u64,
        time_s: f64,
    ) -> Result<(), crate::interrupt::Interrupted> {
        loop {
            let wait = self.paused.then_some(PAUSED_POLL);
            let command = self.live.link().command(wait);
            match command {
                Some(LiveCommand::Pause) => self.paused = true,
                Some(LiveCommand::Resume) => (self.paused, self.stepping) = (false, false),
                Some(LiveCommand::Step) => (self.paused, self.stepping) = (false, true),
                Some(LiveCommand::Set { index, value }) => {
                    let note = self.set(controller.as_deref_mut(), index, value, step, time_s);
                    self.live.link().tell(note);
                }
                None if self.paused => crate::interrupt::check()?,
                None => return Ok(()),
            }
        }
    }

    /// Applies one `set`, checked again here (the page's server checks it first), and says what
    /// happened as a JSON note.
    fn set(
        &mut self,
        controller: Option<&mut Controller>,
        index: usize,
        value: f64,
        step: u64,
        time_s: f64,
    ) -> String {
        let refused = |why: &str| serde_json::json!({ "refused": why }).to_string();
        let (Some(c), Some(p)) = (controller, self.live.params.get(index)) else {
            return refused("this run has no such parameter");
        };
        if !value.is_finite() || !(p.min..=p.max).contains(&value) {
            return refused(&format!("{}: {value} is outside [{}, {}]", p.name, p.min, p.max));
        }
        if !c.set_param(p.id, value) {
            return refused(&format!("{}: {value} refused by the controller", p.name));
        }
        let change = ParamChange { step, time_s, name: p.name.clone(), value: c.param(p.id) };
        let note = serde_json::json!({ "set": &change }).to_string();
        self.changes.push(change);
        note
    }

    /// Hands frame `index` at `time_s` to the page: the points `x` of the triangles `triangles` (sent
    /// again first when they changed); then takes the page's commands (a cloth run's once a frame).
    pub(crate) fn cloth_frame(
        &mut self,
        index: usize,
        time_s: f64,
        x: &[DVec3],
        triangles: &[[u32; 3]],
    ) -> Result<(), crate::interrupt::Interrupted> {
        if !self.mesh_sent || self.triangles != triangles {
            let note =
                serde_json::json!({ "mesh": { "kind": "cloth", "triangles": triangles, "points": x.len() } });
            // Taken as sent only once it was queued: a dropped mesh would leave the page drawing the
            // new points on the old triangles, or nothing, for the rest of the run.
            if self.live.link().tell(note.to_string()) {
                self.triangles.clear();
                self.triangles.extend_from_slice(triangles);
                self.mesh_sent = true;
            }
        }
        let positions = x.iter().flat_map(|p| [p.x as f32, p.y as f32, p.z as f32]).collect();
        self.frame(index, time_s, positions);
        self.commands(None, 0, time_s)
    }

    /// Hands frame `index` of `world`'s figures to the page (their bodies as boxes and balls in the
    /// plane z = 0; the mesh first, once). Commands are taken at control steps, not here.
    pub(crate) fn figure_frame(
        &mut self,
        index: usize,
        world: &World,
        poses: &mut Vec<BodyPose>,
    ) -> Result<(), anima_body::BodyError> {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        let mut colours = Vec::new();
        for m in 0..world.n_models() {
            world.body_poses(m, poses)?;
            for p in poses.iter() {
                let first = (positions.len() / 3) as u32;
                let (s, c) = p.angle.sin_cos();
                let mut corner = |u: f64, v: f64| {
                    let (x, y) = (p.centre[0] + c * u - s * v, p.centre[1] + s * u + c * v);
                    positions.extend([x as f32, y as f32, 0.0]);
                };
                let n = match p.shape {
                    Shape::Box { width, height } => {
                        for (u, v) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                            corner(u * width / 2.0, v * height / 2.0);
                        }
                        4
                    }
                    Shape::Ball { radius } => {
                        for k in 0..8 {
                            let a = f64::from(k) * std::f64::consts::FRAC_PI_4;
                            corner(radius * a.cos(), radius * a.sin());
                        }
                        8
                    }
                };
                if !self.mesh_sent {
                    triangles.extend((1..n - 1).map(|k| [first, first + k, first + k + 1]));
                    let colour = match (p.shape, p.side) {
                        (Shape::Ball { .. }, _) => [230, 140, 40],
                        (_, Side::Left) => [60, 170, 60],
                        (_, Side::Right) => [210, 60, 50],
                        (_, Side::Centre) => [120, 140, 170],
                    };
                    colours.push(colour);
                }
            }
        }
        if !self.mesh_sent {
            // One colour a body, in the order of the bodies' points.
            let points = positions.len() / 3;
            let note = serde_json::json!({ "mesh": { "kind": "figures", "triangles": triangles, "colours": colours, "points": points } });
            self.mesh_sent = self.live.link().tell(note.to_string());
        }
        self.frame(index, world.time(), positions);
        Ok(())
    }

    fn frame(&mut self, index: usize, time_s: f64, positions: Vec<f32>) {
        self.live.link().frame(index, time_s, positions);
        if self.stepping {
            (self.stepping, self.paused) = (false, true);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::mpsc;

    /// A link over plain channels, as a test (or another program) drives a run.
    pub(crate) struct ChannelLink {
        pub notes: mpsc::Sender<String>,
        pub frames: mpsc::Sender<usize>,
        pub commands: mpsc::Receiver<LiveCommand>,
    }

    impl LiveLink for ChannelLink {
        fn tell(&mut self, json: String) -> bool {
            self.notes.send(json).is_ok()
        }
        fn frame(&mut self, index: usize, _: f64, _: Vec<f32>) {
            let _ = self.frames.send(index);
        }
        fn command(&mut self, wait: Option<Duration>) -> Option<LiveCommand> {
            match wait {
                Some(w) => self.commands.recv_timeout(w).ok(),
                None => self.commands.try_recv().ok(),
            }
        }
    }

    /// A link whose note queue is full for the first `full` notes.
    struct FullAtFirst {
        full: usize,
        link: ChannelLink,
    }

    impl LiveLink for FullAtFirst {
        fn tell(&mut self, json: String) -> bool {
            if self.full > 0 {
                self.full -= 1;
                return false;
            }
            self.link.tell(json)
        }
        fn frame(&mut self, index: usize, time_s: f64, positions: Vec<f32>) {
            self.link.frame(index, time_s, positions);
        }
        fn command(&mut self, wait: Option<Duration>) -> Option<LiveCommand> {
            self.link.command(wait)
        }
    }

    /// A mesh note the queue dropped is sent again with the next frame (else the page would draw a
    /// remeshed cloth's points on the old triangles, or nothing, for the rest of the run), and a mesh
    /// says how many points its frames carry, so that the page can pass over frames of an older mesh.
    #[test]
    fn a_dropped_mesh_is_sent_again_and_says_its_point_count() {
        let (notes_tx, notes) = mpsc::channel();
        let (frames_tx, frames) = mpsc::channel();
        let (_commands, commands_rx) = mpsc::channel();
        let link = ChannelLink { notes: notes_tx, frames: frames_tx, commands: commands_rx };
        let live = Live::new(FullAtFirst { full: 2, link }, Vec::new());
        let mut run = LiveRun::new(&live);
        let x = [DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::ONE];
        let (one, two) = ([[0, 1, 2]], [[0, 1, 2], [1, 3, 2]]);
        let mut send = |k: usize, triangles: &[[u32; 3]]| {
            run.cloth_frame(k, k as f64, &x, triangles).unwrap();
            notes
                .try_iter()
                .map(|n| serde_json::from_str::<serde_json::Value>(&n).unwrap())
                .collect::<Vec<_>>()
        };
        assert!(send(0, &one).is_empty(), "the first note was dropped");
        assert!(send(1, &one).is_empty(), "and the second");
        let sent = send(2, &one);
        assert_eq!(sent.len(), 1, "sent again until queued");
        assert_eq!(sent[0]["mesh"]["triangles"], serde_json::json!(one));
        assert_eq!(sent[0]["mesh"]["points"], 4);
        assert!(send(3, &one).is_empty(), "not again once the page has it");
        let remeshed = send(4, &two);
        assert_eq!(remeshed.len(), 1);
        assert_eq!(remeshed[0]["mesh"]["triangles"], serde_json::json!(two));
        assert_eq!(frames.try_iter().collect::<Vec<_>>(), vec![0, 1, 2, 3, 4], "every frame offered");
    }

    fn info(kind: ParamKind, range: Option<(f64, f64)>) -> ParamInfo {
        ParamInfo {
            path: "p".into(),
            label: "p".into(),
            kind,
            range,
            owner: anima_control::ParamOwner::Sensor { sensor: 0 },
            auto: true,
        }
    }

    /// A walk with a page that sets a parameter and pauses before the first step, steps one frame,
    /// asks for what it may not (out of range, not finite, no such parameter), then resumes.
    #[test]
    fn a_live_walk_pauses_steps_and_takes_a_parameter_at_the_next_control_step() {
        use crate::run::{Detail, RunOptions, Silent, run};
        let mut scene =
            anima_scene::load(&crate::test_asset("scenes/walk.ron"), &anima_scene::LoadOptions::default())
                .unwrap();
        let anima_scene::Scene::Character(c) = &mut scene else { panic!("a character scene") };
        c.scene.duration = 2.0;
        let params = parameters(&c.controller);
        let k =
            params.iter().position(|p| c.controller.params()[p.id.0].kind == ParamKind::TargetAngle).unwrap();
        let (name, value) = (params[k].name.clone(), params[k].value + 0.1);
        assert!(params.iter().all(|p| p.min <= p.value && p.value <= p.max && !p.name.contains(' ')));

        let (notes_tx, notes) = mpsc::channel();
        let (frames_tx, frames) = mpsc::channel();
        let (commands, commands_rx) = mpsc::channel();
        let live =
            Live::new(ChannelLink { notes: notes_tx, frames: frames_tx, commands: commands_rx }, params);
        commands.send(LiveCommand::Set { index: k, value }).unwrap();
        commands.send(LiveCommand::Pause).unwrap();
        let opts = RunOptions { live: Some(live), ..RunOptions::quiet() };
        let walk = std::thread::spawn(move || run(&scene, "walk", &opts, &mut Silent));

        let wait = Duration::from_secs(60);
        assert!(notes.recv_timeout(wait).unwrap().starts_with("{\"mesh\""));
        let set: serde_json::Value = serde_json::from_str(&notes.recv_timeout(wait).unwrap()).unwrap();
        assert_eq!(set["set"]["name"], name.as_str());
        assert_eq!(set["set"]["step"], 1);
        assert_eq!(frames.recv_timeout(wait).unwrap(), 0);
        // Paused before the first step: no frame comes.
        assert!(frames.recv_timeout(Duration::from_millis(300)).is_err(), "a paused run went on");
        commands.send(LiveCommand::Step).unwrap();
        assert_eq!(frames.recv_timeout(wait).unwrap(), 1);
        assert!(frames.recv_timeout(Duration::from_millis(300)).is_err(), "a step went past one frame");
        for bad in [
            LiveCommand::Set { index: k, value: f64::NAN },
            LiveCommand::Set { index: k, value: 1e9 },
            LiveCommand::Set { index: usize::MAX, value: 0.0 },
        ] {
            commands.send(bad).unwrap();
            let note = notes.recv_timeout(wait).unwrap();
            assert!(note.starts_with("{\"refused\""), "{bad:?} gave {note}");
        }
        commands.send(LiveCommand::Resume).unwrap();
        let summary = walk.join().unwrap().unwrap();
        assert_eq!(frames.iter().last(), Some(4), "frames 2 to 4 after the resume");
        let Detail::Body(d) = &summary.detail else { panic!("figures") };
        assert_eq!(d.parameter_changes, vec![ParamChange { step: 1, time_s: 0.0, name, value }]);
        assert_eq!(summary.steps, 40);
    }

    #[test]
    fn slider_ranges_hold_the_value_and_follow_the_kind() {
        assert_eq!(slider_range(&info(ParamKind::TargetAngle, Some((-0.5, 0.5))), 0.7), (-0.5, 0.7));
        let (a, b) = slider_range(&info(ParamKind::TargetAngle, None), 0.2);
        assert!((a - (0.2 - std::f64::consts::FRAC_PI_2)).abs() < 1e-12 && b > 1.7);
        assert_eq!(slider_range(&info(ParamKind::Weight, None), 1.0), (0.0, 2.0));
        assert_eq!(slider_range(&info(ParamKind::Time, None), 3.0), (0.0, 10.0));
        assert_eq!(slider_range(&info(ParamKind::FeedbackGain, None), -3.0), (-6.0, 0.0));
    }
}
