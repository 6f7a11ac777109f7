//! Running a scene to its end: stepping, frames, pictures and a summary, one module per scene kind, one
//! set of options and one summary for all of them. The `anima run` command is this module's caller;
//! the tests drive scenes through the same code, so what they check is what a user runs.

pub mod body;
pub mod export;
pub mod flex3d;
mod kind;
pub mod oliveira;
pub mod series;
pub mod sheet;

use std::path::{Path, PathBuf};

use anima_cloth::contact_mode::ContactMode;
use anima_cloth::flex3d::{ContactApproach, FrictionMode, StaticResponse};
use anima_cloth::self_collision::SelfCollisionMode;
use anima_geom::DVec3;
use anima_ode::{Integrator, LinearSolver};
use anima_scene::Scene;
use anyhow::Result;
use serde::Serialize;

pub use export::Export;
pub(crate) use kind::kind;
use series::FrameSeries;

use crate::output::write_atomic;

/// What a run writes. Nothing is written outside `out_dir`.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Folder for frames, pictures and the summary; `None` writes nothing.
    pub out_dir: Option<PathBuf>,
    /// Write a file per frame (`.OBT` and `.obj` for FLEX3D surfaces, `.obj` for cloths; figures are
    /// pictures).
    pub frames: bool,
    /// Also write the initial state as frame 0.
    pub frame0: bool,
    /// Render `final.png` and a `frames.png` contact sheet (and, for figures, a picture per frame).
    pub pictures: bool,
    /// How the implicit integrators solve (`None` everywhere: the integrator's defaults).
    pub solve: SolveOptions,
    /// Sheet scenes: reference positions (another run's `final.obj`); the summary then reports the RMS
    /// distance to them.
    pub reference: Option<Vec<DVec3>>,
    /// An animation of the whole run to write at its end (`animation.glb` for glTF), beside the frames.
    pub export: Option<Export>,
    /// Run on every core (the `anima` binary's default; `--one-thread` turns it off): the implicit
    /// steps of every cloth kind (`anima_ode::parallel`), and a sheet's explicit integrators when it has
    /// at least [`PARALLEL_MIN_PARTICLES`] particles, or [`PARALLEL_MIN_PARTICLES_FUSED`] for symplectic
    /// Euler. The results are the same to the bit as on one thread.
    pub parallel: bool,
    /// A page watching the run (`anima run --live`): frames as they are computed, and its commands
    /// taken at each control step of a figure run and at each frame of a cloth run ([`crate::live`]).
    pub live: Option<crate::live::Live>,
}

pub use anima_cloth::spring_net::{
    PARALLEL_MIN_PARTICLES, PARALLEL_MIN_PARTICLES_FUSED, parallel_min_particles,
};

impl RunOptions {
    /// Nothing written: for tests and experiments that only want the numbers.
    pub fn quiet() -> Self {
        Self::default()
    }

    /// Frames and pictures into `dir`.
    pub fn writing_to(dir: impl Into<PathBuf>) -> Self {
        Self { out_dir: Some(dir.into()), frames: true, pictures: true, ..Self::default() }
    }

    /// The folder frames go to, when frames are written.
    fn frame_dir(&self) -> Option<&Path> {
        self.out_dir.as_deref().filter(|_| self.frames)
    }

    /// The folder pictures go to, when pictures are drawn.
    fn picture_dir(&self) -> Option<&Path> {
        self.out_dir.as_deref().filter(|_| self.pictures)
    }

    /// The folder the animation (`animation.glb` or `animation.usda`) goes to, when the run is exported.
    fn export_dir(&self) -> Option<&Path> {
        self.out_dir.as_deref().filter(|_| self.export.is_some())
    }

    /// Says which option does not apply to `scene`, if one does not: a reference for a scene that is
    /// not a sheet, solver choices for an explicit integrator, ρ∞ and Newton iterations for any
    /// integrator but generalised-α. [`run`] checks it first, so an option is never silently ignored.
    pub fn check(&self, scene: &Scene) -> Result<()> {
        if self.reference.is_some() && !kind::kind(scene).takes_reference() {
            anyhow::bail!("--reference applies to sheet scenes only");
        }
        let integrator = scene.integrator();
        if self.solve.linear_solver.is_some() && !integrator.is_some_and(Integrator::is_implicit) {
            anyhow::bail!(
                "--linear-solver applies to the implicit integrators only (implicit-euler, bdf2, generalized-alpha)"
            );
        }
        if (self.solve.rho_inf.is_some() || self.solve.newton_iterations.is_some())
            && integrator != Some(Integrator::GeneralizedAlpha)
        {
            anyhow::bail!("--rho-inf and --newton-iterations apply to generalized-alpha only");
        }
        Ok(())
    }
}

/// How an implicit integrator solves its steps; `None` keeps the integrator's default.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveOptions {
    pub linear_solver: Option<LinearSolver>,
    /// Generalised-α's spectral radius at infinite frequency ρ∞ in [0, 1] (0: unresolved modes damped in
    /// one step; 1: the undamped implicit midpoint rule).
    pub rho_inf: Option<f64>,
    /// Newton iterations per step of generalised-α.
    pub newton_iterations: Option<usize>,
}

impl SolveOptions {
    /// Sets these choices on a run's stepper.
    pub fn configure(&self, stepper: &mut anima_ode::Stepper<DVec3>) {
        if let Some(s) = self.linear_solver {
            stepper.set_linear_solver(s);
        }
        if let Some(r) = self.rho_inf {
            stepper.set_spectral_radius(r);
        }
        if let Some(k) = self.newton_iterations {
            stepper.set_newton_iterations(k);
        }
    }
}

/// What a run tells its caller while it goes: how far it is, and warnings worth reading before the
/// end (a step beyond the integrator's stability limit). The `anima` command draws a progress bar.
pub trait Progress {
    /// The run will take `total` steps (or, for adaptive cloths, `total` milliseconds of simulated time).
    fn begin(&mut self, total: u64);
    fn advance(&mut self, done: u64);
    fn warn(&mut self, message: &str);
    fn end(&mut self);
}

/// A [`Progress`] that shows nothing; its warnings end up in the summary only.
#[derive(Debug, Clone, Copy, Default)]
pub struct Silent;

impl Progress for Silent {
    fn begin(&mut self, _: u64) {}
    fn advance(&mut self, _: u64) {}
    fn warn(&mut self, _: &str) {}
    fn end(&mut self) {}
}

/// The JSON summary of a run: what every kind reports, then the kind's own numbers.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    pub scene: String,
    pub kind: &'static str,
    pub steps: u64,
    pub frames: usize,
    pub simulated_seconds: f64,
    /// Wall time of the step loop (frames and pictures included, start-up not), s.
    pub wall_seconds: f64,
    /// Of `wall_seconds`, the time spent on output inside the loop, s: for cloth runs writing frames
    /// and exports and keeping the pictures' states, for figure runs drawing the pictures (their glTF
    /// frames are not counted). The rest is the simulation's.
    pub output_seconds: f64,
    /// Every value stayed finite.
    pub all_finite: bool,
    /// Why the run stopped early, if it did.
    pub error: Option<String>,
    pub warnings: Vec<String>,
    /// Cloth scenes: the most crossing (edge, triangle) pairs of the cloth with itself — and, with
    /// several FLEX3D surfaces, with one another — at any frame and at the end, counted by
    /// `anima_geom::count_self_intersections` (0: it never passed through itself where it was looked
    /// at). The counting is left out of `wall_seconds`.
    pub self_intersections: Option<usize>,
    #[serde(flatten)]
    pub detail: Detail,
}

/// The warnings a run gives at its end: the export's, written now, and the crossing watch's (when
/// it watched), each shown on `progress` and kept for the summary.
pub(crate) fn closing_warnings(
    export: Option<export::GltfExport>,
    opts: &RunOptions,
    watch: Option<&CrossingWatch>,
    progress: &mut dyn Progress,
    warnings: &mut Vec<String>,
) -> Result<()> {
    let written = match (export, opts.export_dir(), opts.export) {
        (Some(e), Some(dir), Some(format)) => e.write(dir, format)?,
        _ => Vec::new(),
    };
    for w in written.into_iter().chain(watch.and_then(CrossingWatch::warning)) {
        progress.warn(&w);
        warnings.push(w);
    }
    Ok(())
}

/// Counts a cloth's self-intersections at each frame: the largest count, and the time spent counting
/// (so that a run's wall time stays the time of the run).
#[derive(Debug, Default)]
pub(crate) struct CrossingWatch {
    pub largest: usize,
    spent: std::time::Duration,
    /// Whether a count was abandoned for its work budget (a tangled or exploded mesh), and the first
    /// such look's reason.
    pub abandoned: Option<String>,
}

impl CrossingWatch {
    /// Counts the crossings of the state, within the count's work budget
    /// ([`anima_geom::count_self_intersections_within`]): a mesh that blew up is not walked for minutes.
    /// Returns the count, or `None` when it was abandoned.
    pub fn look(&mut self, x: &[DVec3], triangles: &[[u32; 3]]) -> Option<usize> {
        let started = std::time::Instant::now();
        let count = match anima_geom::count_self_intersections_within(x, triangles, None) {
            Ok(n) => {
                self.largest = self.largest.max(n);
                Some(n)
            }
            Err(e) => {
                self.abandoned.get_or_insert_with(|| e.to_string());
                None
            }
        };
        self.spent += started.elapsed();
        count
    }

    /// The warning for the summary when a count was abandoned.
    pub fn warning(&self) -> Option<String> {
        self.abandoned.as_ref().map(|why| format!("self-intersections not counted at every frame: {why}"))
    }

    /// Seconds spent counting.
    pub fn seconds(&self) -> f64 {
        self.spent.as_secs_f64()
    }
}

/// What a cloth run keeps at every frame besides its frame files, the same for every cloth kind: the
/// crossing pairs counted (within the count's budget, [`CrossingWatch`]), a row of `series.json` (when
/// the run writes output) and the frame shown to a live page; and the time spent on output.
pub(crate) struct ClothFrames {
    pub watch: CrossingWatch,
    pub output: OutputClock,
    live: Option<crate::live::LiveRun>,
    series: Option<FrameSeries>,
}

impl ClothFrames {
    /// The series `names` (with frame 0's row, `values` of the state at `t0` from its crossing count:
    /// they are counted here, before the run's clock starts, and not in the summary's largest), and the
    /// live page of `opts`.
    pub fn new<const N: usize>(
        opts: &RunOptions,
        names: [(String, &'static str); N],
        t0: f64,
        x: &[DVec3],
        triangles: &[[u32; 3]],
        values: impl FnOnce(Option<usize>) -> [Option<f64>; N],
    ) -> Self {
        let series = opts.out_dir.as_ref().map(|_| {
            let mut f = FrameSeries::new(names);
            let crossings = anima_geom::count_self_intersections_within(x, triangles, None);
            f.push(t0, &values(crossings.ok()));
            f
        });
        let live = opts.live.as_ref().map(crate::live::LiveRun::new);
        Self { watch: CrossingWatch::default(), output: OutputClock::default(), live, series }
    }

    /// Frame `k` at time `t`, written: its crossings counted (`None` when abandoned for the count's
    /// budget), its row of the series from them (`values`, in the order of the names), and the live page
    /// shown it (which may pause the run here).
    pub fn frame<const N: usize>(
        &mut self,
        k: usize,
        t: f64,
        x: &[DVec3],
        triangles: &[[u32; 3]],
        values: impl FnOnce(Option<usize>) -> [Option<f64>; N],
    ) -> Result<()> {
        let crossings = self.watch.look(x, triangles);
        if let Some(f) = &mut self.series {
            f.push(t, &values(crossings));
        }
        if let Some(l) = &mut self.live {
            l.cloth_frame(k, t, x, triangles)?;
        }
        Ok(())
    }

    /// Writes `series.json` into the output folder, when the run writes output.
    pub fn write_series(&self, opts: &RunOptions) -> Result<()> {
        match (&opts.out_dir, &self.series) {
            (Some(dir), Some(f)) => f.write(dir),
            _ => Ok(()),
        }
    }
}

/// Time spent on output inside a step loop (frames, exports, the pictures' states), kept apart so that
/// a run can say how long the simulation itself took.
#[derive(Debug, Default)]
pub(crate) struct OutputClock {
    spent: std::time::Duration,
}

impl OutputClock {
    /// Runs `f`, counting its time as output.
    pub fn time<T>(&mut self, f: impl FnOnce() -> T) -> T {
        let started = std::time::Instant::now();
        let out = f();
        self.spent += started.elapsed();
        out
    }

    /// Seconds spent on output.
    pub fn seconds(&self) -> f64 {
        self.spent.as_secs_f64()
    }
}

/// How a cloth run kept its cloth from passing through itself: the mode, and what the modern
/// response did over the run (absent for the other modes).
#[derive(Debug, Clone, Serialize)]
pub struct SelfCollisionReport {
    pub mode: &'static str,
    pub repulsions: Option<usize>,
    pub impacts: Option<usize>,
    pub impact_zones: Option<usize>,
    pub frozen_zones: Option<usize>,
}

impl SelfCollisionReport {
    pub fn new(
        mode: SelfCollisionMode,
        stats: Option<anima_cloth::self_collision::SelfCollisionStats>,
    ) -> Self {
        Self {
            mode: mode.name(),
            repulsions: stats.map(|s| s.repulsions),
            impacts: stats.map(|s| s.impacts),
            impact_zones: stats.map(|s| s.zones),
            frozen_zones: stats.map(|s| s.frozen_zones),
        }
    }
}

/// The numbers only one kind of scene has.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum Detail {
    Flex3d(flex3d::Flex3dDetail),
    Sheet(sheet::SheetDetail),
    Oliveira(oliveira::OliveiraDetail),
    Body(body::BodyDetail),
}

/// Writes the summary as pretty JSON, whole.
pub fn write_summary(path: &Path, summary: &Summary) -> Result<()> {
    write_atomic(path, |w| {
        serde_json::to_writer_pretty(&mut *w, summary)?;
        writeln!(w)?;
        Ok(())
    })
}

/// Runs a loaded scene of any kind; `label` names it in the summary. The options are checked against
/// the scene first ([`RunOptions::check`]) and the output folder checked writable; the frames an
/// earlier run of the same kind left there are removed (with a warning), so the folder holds this
/// run's frames only; so is an earlier `animation.glb` or
/// `series.json`, whatever its kind, since it shows an earlier run (this run writes its own at its end
/// when it exports, or keeps series).
pub fn run(scene: &Scene, label: &str, opts: &RunOptions, progress: &mut dyn Progress) -> Result<Summary> {
    opts.check(scene)?;
    if let Some(dir) = &opts.out_dir {
        crate::output::check_writable(dir)?;
        let kind = kind::kind(scene);
        let ours = |name: &str| {
            kind.is_frame_file(name)
                || name == export::GLTF_FILE
                || name == export::USD_FILE
                || name == series::SERIES_FILE
        };
        let removed = crate::output::remove_stale(dir, ours)?;
        if removed > 0 {
            progress.warn(&format!(
                "removed {removed} output files (frames, animation, series) of an earlier run from {}",
                dir.display()
            ));
        }
    }
    let run = |progress: &mut dyn Progress| kind::kind(scene).run(label, opts, progress);
    if opts.parallel {
        return run(progress);
    }
    anima_ode::parallel::on_one_thread(|| run(progress))
}

/// Frames shown on a contact sheet: nine spread evenly over the run, ending with the last one.
pub fn sheet_frames(n_frames: usize) -> Vec<usize> {
    let shown = n_frames.min(9);
    let mut frames: Vec<usize> = (1..=shown).map(|k| (k * n_frames).div_ceil(shown)).collect();
    frames.dedup();
    frames
}

/// Changes to a loaded scene from the command line, checked once for every kind. A change that does
/// not apply to the scene's kind is an error, never silently ignored.
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    pub integrator: Option<Integrator>,
    /// Time step, s (a FLEX3D or sheet step, a cloth's fixed step, a figure's control step).
    pub dt: Option<f64>,
    /// Simulated time, s.
    pub duration: Option<f64>,
    /// Gravity, m/s² (FLEX3D and Oliveira scenes; FLEX3D `.PAR` scripts take it when loading).
    pub gravity: Option<DVec3>,
    /// Where contact with static objects is answered (FLEX3D and Oliveira scenes).
    pub contact_mode: Option<ContactMode>,
    /// How the cloth is kept from passing through itself (FLEX3D and Oliveira scenes).
    pub self_collision: Option<SelfCollisionMode>,
    pub flex3d: Flex3dSwitches,
}

/// The FLEX3D reconstructions the thesis leaves open (spec S7.2), each a switch.
#[derive(Debug, Clone, Default)]
pub struct Flex3dSwitches {
    pub friction: Option<FrictionMode>,
    pub contact: Option<ContactApproach>,
    pub static_response: Option<StaticResponse>,
    pub external_is_acceleration: bool,
    pub bend_reaction: bool,
    pub friction_clamp: bool,
    pub no_collisions: bool,
}

impl Flex3dSwitches {
    fn any(&self) -> bool {
        self.friction.is_some()
            || self.contact.is_some()
            || self.static_response.is_some()
            || self.external_is_acceleration
            || self.bend_reaction
            || self.friction_clamp
            || self.no_collisions
    }
}

fn positive(what: &str, v: f64) -> Result<f64> {
    if v > 0.0 && v.is_finite() {
        Ok(v)
    } else {
        anyhow::bail!("{what} must be a positive number of seconds, found {v}")
    }
}

impl Overrides {
    /// Applies the changes to `scene`, or says which one does not apply to its kind.
    pub fn apply(&self, scene: &mut Scene) -> Result<()> {
        let dt = self.dt.map(|d| positive("--dt", d)).transpose()?;
        let duration = self.duration.map(|d| positive("--duration", d)).transpose()?;
        let changes = kind::Changes { overrides: self, dt, duration, kind: scene.kind().name() };
        kind::kind_mut(scene).apply(&changes)?;
        self.check_after(scene)
    }

    /// The run the changed scene asks for must still be one anima can run (`anima_scene::limits`): the
    /// loader checked the file's numbers, this checks the command line's.
    fn check_after(&self, scene: &Scene) -> Result<()> {
        let problem = kind::kind(scene).problem();
        match problem {
            Some(why) => anyhow::bail!("with the options as given: {why}"),
            None => Ok(()),
        }
    }
}

/// What a step beyond the integrator's stability limit means for the scene at hand, or `None` when it
/// means nothing worth a warning. `omega_max` is the scene's highest undamped frequency (rad/s), `zeta`
/// that mode's damping ratio (the limit is the damped oscillator's,
/// [`anima_ode::stability::damped_stability_limit`]) and `n_steps` the run's length; `damping` describes the scene's damping ("literal friction μ = 0.6"),
/// `None` when it has none.
///
/// Forward Euler has no stable step at all for an undamped oscillation: each step multiplies its
/// amplitude by √(1 + (h·ω)²). Over a whole run that may be nothing (the tablecloth grows an undamped
/// mode at most 2.7× over its 10⁴ steps, and its friction damps it), so for forward Euler the warning is
/// given when that growth over the run passes 10×. Other explicit methods are stable up to a limit
/// h·ω ≤ c and blow up fast beyond it, so any step past c is worth a warning.
pub fn stability_warning(
    integrator: Integrator,
    dt: f64,
    n_steps: usize,
    omega_max: f64,
    zeta: f64,
    damping: Option<&str>,
) -> Option<String> {
    let limit = anima_ode::stability::damped_stability_limit(integrator, zeta);
    if limit.is_infinite() || omega_max <= 0.0 || dt * omega_max <= limit {
        return None;
    }
    let h_omega = dt * omega_max;
    let forward_euler = matches!(integrator, Integrator::ForwardEuler | Integrator::AdaptiveEuler);
    let head = if forward_euler {
        // ln of the run's growth: (n/2)·ln(1 + (h·ω)²).
        let ln_growth = 0.5 * n_steps as f64 * h_omega.powi(2).ln_1p();
        if ln_growth < 10f64.ln() {
            return None;
        }
        format!(
            "{integrator} at Δt = {dt:.3e} s: an undamped oscillation at the scene's highest frequency \
             (ω_max = {omega_max:.3e} rad/s, h·ω = {h_omega:.3}) grows ×{} over the run's {n_steps} steps",
            if ln_growth > 700.0 { "∞".to_owned() } else { format!("{:.2e}", ln_growth.exp()) }
        )
    } else {
        let oscillation = if zeta > 0.0 {
            format!("an oscillation damped as the scene damps its fastest mode (ζ = {zeta:.2})")
        } else {
            "an undamped oscillation".to_owned()
        };
        format!(
            "{integrator} at Δt = {dt:.3e} s: h·ω_max = {h_omega:.3} with ω_max = {omega_max:.3e} rad/s, beyond the \
             stability limit h·ω ≤ {limit} (Δt ≤ {:.3e} s) of {oscillation}",
            limit / omega_max
        )
    };
    Some(match damping {
        None => format!("{head}; this scene has no damping, so the run will go non-finite"),
        Some(d) => {
            // Forward Euler on x'' = −ω²x − 2ζωx' is stable exactly when ζ ≥ h·ω/2.
            let need = if forward_euler {
                format!(
                    " (forward Euler needs a damping ratio ζ ≥ h·ω/2 = {:.3} on that mode)",
                    h_omega / 2.0
                )
            } else {
                String::new()
            };
            format!(
                "{head}; it stays bounded only if the scene's damping ({d}) takes energy out of the fastest \
                 modes faster than the integrator puts it in{need}; the run stops at the first non-finite value"
            )
        }
    })
}

/// What keeps a figures run of `duration` at step `dt` from running, with its frame clock as the scene
/// gives it (an error when the scene names none).
fn figures_problem(
    duration: f64,
    dt: f64,
    interval: Result<f64, anima_body::SkeletonError>,
) -> Option<String> {
    match interval {
        Ok(f) => anima_scene::figures_run_problem(duration, dt, f),
        Err(e) => Some(e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An option that does not apply to the scene is refused by the run itself, before anything is
    /// written, not only by the command line.
    #[test]
    fn a_run_refuses_an_option_its_scene_does_not_take() {
        let sheet = Scene::Sheet(anima_scene::sheet::SheetScene::standard(4));
        let stand = anima_scene::load(&crate::test_asset("scenes/stand.ron"), &Default::default()).unwrap();
        let with = |f: fn(&mut RunOptions)| {
            let mut o = RunOptions::quiet();
            f(&mut o);
            o
        };
        let reference = with(|o| o.reference = Some(vec![DVec3::ZERO; 16]));
        assert!(reference.check(&sheet).is_ok());
        let err = run(&stand, "stand", &reference, &mut Silent).unwrap_err().to_string();
        assert!(err.contains("--reference applies to sheet scenes only"), "{err}");
        // The standard sheet steps by symplectic Euler: no linear solver, no ρ∞.
        let solver = with(|o| {
            o.solve.linear_solver =
                Some(LinearSolver::ConjugateGradient { tolerance: 1e-3, max_iterations: 10 })
        });
        let err = run(&sheet, "sheet", &solver, &mut Silent).unwrap_err().to_string();
        assert!(err.contains("--linear-solver applies to the implicit integrators only"), "{err}");
        let rho = with(|o| o.solve.rho_inf = Some(0.3));
        let err = rho.check(&sheet).unwrap_err().to_string();
        assert!(err.contains("apply to generalized-alpha only"), "{err}");
        let Scene::Sheet(mut alpha) = sheet else { unreachable!() };
        alpha.integrator = Integrator::GeneralizedAlpha;
        let alpha = Scene::Sheet(alpha);
        assert!(rho.check(&alpha).is_ok() && solver.check(&alpha).is_ok());
    }

    #[test]
    fn stability_warnings_say_what_the_step_means_for_the_scene() {
        // The default tablecloth: forward Euler, h·ω = 0.014 over 10⁴ steps grows an undamped mode 2.7×.
        assert_eq!(
            stability_warning(Integrator::ForwardEuler, 1e-3, 10_000, 13.93, 0.0, Some("friction")),
            None
        );
        // Ten times the step: ×10⁴¹ over the run.
        let w = stability_warning(
            Integrator::ForwardEuler,
            1e-2,
            10_000,
            13.93,
            0.0,
            Some("literal friction μ = 0.6"),
        )
        .expect("a warning");
        assert!(w.contains("grows ×") && w.contains("μ = 0.6") && w.contains("ζ ≥ h·ω/2 = 0.070"), "{w}");
        let w =
            stability_warning(Integrator::ForwardEuler, 1e-2, 10_000, 13.93, 0.0, None).expect("a warning");
        assert!(w.contains("no damping") && w.contains("will go non-finite"), "{w}");
        // RK4 is stable up to h·ω ≈ 2.83: no warning below, one above whatever the run's length.
        assert_eq!(stability_warning(Integrator::Rk4, 0.1, 1_000_000, 28.0, 0.0, None), None);
        let w = stability_warning(Integrator::Rk4, 0.1, 10, 29.0, 0.0, Some("spring damping"))
            .expect("a warning");
        assert!(w.contains("beyond the stability limit h·ω ≤ 2.8"), "{w}");
        assert_eq!(stability_warning(Integrator::ImplicitEuler, 1.0, 10, 1e6, 0.0, None), None);
        // Damping at the highest mode narrows symplectic Euler's limit: h·ω = 1.5 is stable undamped
        // and not at ζ = 0.7 (limit 1.04).
        assert_eq!(stability_warning(Integrator::SymplecticEuler, 1.5e-4, 10, 1e4, 0.0, Some("c")), None);
        let w = stability_warning(Integrator::SymplecticEuler, 1.5e-4, 10, 1e4, 0.7, Some("c"))
            .expect("a warning");
        assert!(w.contains("h·ω ≤ 1.04") && w.contains("ζ = 0.70"), "{w}");
    }

    #[test]
    fn contact_sheet_frames() {
        assert_eq!(sheet_frames(20), vec![3, 5, 7, 9, 12, 14, 16, 18, 20]);
        assert_eq!(sheet_frames(4), vec![1, 2, 3, 4]);
        assert_eq!(sheet_frames(0), Vec::<usize>::new());
    }
}
