//! SIMBICON as it was published (Yin, Loken & van de Panne 2007) in anima's representation, beside the
//! SIMBICON-style form of [`super::simbicon`]: `assets/controllers/walk-simbicon-faithful.ron` is the
//! 2-D walk of the paper's Table 1, unoptimised — one machine whose legs swap roles at each foot strike,
//! the stance hip holding the torso (τ_stance = −τ_torso − τ_swing, a `Torso` target), the swing hip's
//! world angle θ_d0 + c_d·d + c_v·v, LIFT timed and STRIDE ended by the swing foot's strike — on the
//! thesis's humanoid with SIMBICON-style PD gains (`assets/skeletons/humanoid-simbicon.ron`).
//!
//! `cargo xtask reproduce nunes-simbicon-faithful` measures it with and without its feedback gains, at
//! another control rate and on the thesis's gains, and writes its section of
//! `docs/reproduction/nunes-simbicon.md` (seconds; the section beside it, the SIMBICON-style search,
//! takes an hour).

use std::fmt::Write as _;

use anima_body::{Actuation, BuiltinSkeleton, Placement, Skeleton, World, WorldSettings};
use anima_character::{Character, CharacterError, procedures};
use anima_control::{Controller, ParamKind};
use anyhow::{Context as _, Result};

use super::{DT, SUBSTEPS, WalkOutcome, WalkRules};
use crate::repo::Repo;
use crate::report::Document;

/// The faithful walker, `assets/controllers/walk-simbicon-faithful.ron`.
pub const CONTROLLER: &str = "walk-simbicon-faithful";

/// The machine of the walker and its timed transition (LIFT's duration, whole control iterations).
pub const MACHINE: &str = "SIMBICON";
pub const LIFT_TIME: &str = "SIMBICON/LIFTED/time";

/// SIMBICON's state 0 lasts dt = 0.3 s (Table 1).
pub const LIFT_SECONDS: f64 = 0.3;

/// The walker as shipped.
pub fn controller() -> Result<Controller> {
    super::controller(CONTROLLER)
}

/// The faithful walker's figure: the thesis's humanoid with SIMBICON-style gains.
pub fn skeleton() -> Skeleton {
    BuiltinSkeleton::HumanoidSimbicon.load()
}

/// `controller` driving `skeleton` (with its own actuation) standing on the ground of a world with
/// `settings`.
pub fn character(
    controller: Controller,
    skeleton: &Skeleton,
    settings: WorldSettings,
) -> Result<Character, CharacterError> {
    let mut world = World::new(settings)?;
    world.add_model(skeleton, Placement::OnGround { dx: 0.0 })?;
    Character::new(world, controller, procedures(), &[])
}

/// The world of every Nunes experiment: Δt = 0.05 s, 4 physics sub-steps (h = 0.0125 s).
pub fn world_settings() -> WorldSettings {
    super::world_settings(SUBSTEPS)
}

/// The states of the walker, and the labels of the swing hip's two gains in each: c_d (the first
/// feedback term, on `com_ahead_of_ankle`) and c_v (the second, on `com_speed`).
pub const STATES: [&str; 2] = ["LIFT", "STRIDE"];

fn gain_label(state: &str, term: usize) -> String {
    format!("{MACHINE}/{state}/swing_hip/k{term}")
}

/// The shipped walker's (c_d, c_v) in each of [`STATES`].
pub fn gains(controller: &Controller) -> Result<[(f64, f64); 2]> {
    let get = |state: &str, term: usize| -> Result<f64> {
        let label = gain_label(state, term);
        let id = controller.param_id(&label).with_context(|| format!("no parameter {label}"))?;
        Ok(controller.param(id))
    };
    Ok([(get(STATES[0], 0)?, get(STATES[0], 1)?), (get(STATES[1], 0)?, get(STATES[1], 1)?)])
}

/// The walker with c_d (`term` 0) or c_v (`term` 1) set to 0 in every state.
pub fn without_term(controller: &Controller, term: usize) -> Result<Controller> {
    let mut c = controller.clone();
    for state in STATES {
        let label = gain_label(state, term);
        let id = c.param_id(&label).with_context(|| format!("no parameter {label}"))?;
        c.set_param(id, 0.0);
    }
    Ok(c)
}

/// `controller` with every balance-feedback gain (c_d and c_v of every state) set to 0.
pub fn without_feedback(controller: &Controller) -> Controller {
    let mut c = controller.clone();
    let gains: Vec<_> = (0..c.params().len())
        .filter(|&i| c.params()[i].kind == ParamKind::FeedbackGain)
        .map(anima_control::ParamId)
        .collect();
    c.apply(&gains, &vec![0.0; gains.len()]);
    c
}

/// What one walk measured.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Gait {
    pub outcome: WalkOutcome,
    /// Seconds walked (to the fall, if it fell).
    pub seconds: f64,
    /// Foot strikes: the times the walker's legs swapped roles.
    pub strikes: u64,
    /// The largest tilt of the torso (the pelvis's world angle), rad.
    pub max_torso_tilt: f64,
}

impl Gait {
    /// Mean forward speed of the centre of mass over the walk, m/s.
    pub fn speed(&self) -> f64 {
        self.outcome.distance / self.seconds
    }

    /// Mean distance per step, m.
    pub fn step_length(&self) -> f64 {
        self.outcome.distance / self.strikes.max(1) as f64
    }
}

/// Walks `c` for `seconds` (stopping at a fall; no stop test, as the scenes run it) and measures the
/// gait. The foot strikes are counted on the first machine whose roles swap.
pub fn walk(c: Character, seconds: f64) -> Result<Gait, CharacterError> {
    let dt = c.env.world.settings().dt;
    let iterations = (seconds / dt).round() as u64;
    let machine = c.controller.machines().iter().position(|m| m.has_roles());
    let rules = WalkRules { window: 0, stop_on_failure: true, ..WalkRules::default() };
    let (mut strikes, mut phase, mut tilt) = (0, None, 0.0f64);
    let outcome = super::walk_character(c, iterations, &rules, &[], |c| {
        let now = machine.and_then(|m| c.controller.machines()[m].phase());
        if phase.is_some() && now != phase {
            strikes += 1;
        }
        phase = now;
        let s = &c.env.sensors[0];
        if let Some(p) = s.layout.pelvis {
            tilt = tilt.max(s.body_angle[p].abs());
        }
    })?;
    Ok(Gait { outcome, seconds: outcome.iterations as f64 * dt, strikes, max_torso_tilt: tilt })
}

/// The shipped walker on its figure in the experiments' world, for `seconds`.
pub fn walk_as_shipped(controller: Controller, seconds: f64) -> Result<Gait, CharacterError> {
    walk(character(controller, &skeleton(), world_settings())?, seconds)
}

/// One row of the report: a walker, its figure and its world.
struct Case {
    walker: &'static str,
    figure: String,
    controller: Controller,
    skeleton: Skeleton,
    settings: WorldSettings,
    seconds: f64,
}

/// The thesis's humanoid with Table 6.2's gains × `gain_scale` (implicit springs, as every Nunes
/// experiment).
fn thesis_humanoid(gain_scale: f64) -> Result<Skeleton> {
    let actuation = Actuation { gain_scale, ..super::actuation() };
    Ok(BuiltinSkeleton::Humanoid.load().with_actuation(actuation)?)
}

/// The left hip's actuator index.
fn hip(skeleton: &Skeleton) -> Result<usize> {
    skeleton.actuator_index("hip_l").context("the humanoid has a left hip")
}

/// The rows of the report: the walker as shipped (a minute and ten), without its gains, at another
/// control rate and sub-step count, and on the thesis's gains.
fn cases() -> Result<Vec<Case>> {
    let shipped = controller()?;
    let mut at_100_hz = shipped.clone();
    let lift = at_100_hz.param_id(LIFT_TIME).context("the faithful walker times LIFT")?;
    at_100_hz.set_param(lift, (LIFT_SECONDS / 0.01).round());
    let fine = WorldSettings { dt: 0.01, substeps: 1, ..world_settings() };
    let substeps = |n: u32| WorldSettings { substeps: n, ..world_settings() };
    let on_simbicon = |walker, controller: &Controller, settings, seconds| Case {
        walker,
        figure: "humanoid-simbicon (kp 300, kd 30)".to_string(),
        controller: controller.clone(),
        skeleton: skeleton(),
        settings,
        seconds,
    };
    let on_thesis = |gain_scale: f64, figure: &str| -> Result<Case> {
        Ok(Case {
            walker: "Table 1 (as shipped)",
            figure: figure.to_string(),
            controller: shipped.clone(),
            skeleton: thesis_humanoid(gain_scale)?,
            settings: world_settings(),
            seconds: 60.0,
        })
    };
    Ok(vec![
        on_simbicon("Table 1 (as shipped)", &shipped, world_settings(), 60.0),
        on_simbicon("Table 1 (as shipped)", &shipped, world_settings(), 600.0),
        on_simbicon("c_d = c_v = 0", &without_feedback(&shipped), world_settings(), 60.0),
        on_simbicon("c_d = 0 (c_v kept)", &without_term(&shipped, 0)?, world_settings(), 60.0),
        on_simbicon("c_v = 0 (c_d kept)", &without_term(&shipped, 1)?, world_settings(), 60.0),
        on_simbicon("Table 1, control at 100 Hz (LIFT 30 iterations)", &at_100_hz, fine, 60.0),
        on_simbicon("Table 1, 8 physics sub-steps", &shipped, substeps(8), 60.0),
        on_simbicon("Table 1, 2 physics sub-steps", &shipped, substeps(2), 60.0),
        on_thesis(100.0, "humanoid, Table 6.2 × 100 (the thesis's experiments)")?,
        on_thesis(25.0, "humanoid, Table 6.2 × 25")?,
    ])
}

/// The table row of one case and what it measured (`None`: the simulation diverged).
fn row(k: &Case) -> Result<(String, Option<Gait>)> {
    let c = character(k.controller.clone(), &k.skeleton, k.settings)?;
    let (dt, n) = (k.settings.dt, k.settings.substeps);
    Ok(match walk(c, k.seconds) {
        Ok(g) => (
            format!(
                "| {} | {} | {dt} / {n} | {:.2} | {:.2} | {:.2} | {} | {:.2} | {:.3} | {} |",
                k.walker,
                k.figure,
                g.seconds,
                g.outcome.distance,
                g.speed(),
                g.strikes,
                g.step_length(),
                g.max_torso_tilt,
                if g.outcome.fell { "yes" } else { "no" }
            ),
            Some(g),
        ),
        Err(e) => (
            format!("| {} | {} | {dt} / {n} | — | — | — | — | — | — | diverged: {e} |", k.walker, k.figure),
            None,
        ),
    })
}

/// The section of `docs/reproduction/nunes-simbicon.md` that `reproduce nunes-simbicon-faithful`
/// writes (a few seconds; deterministic, so a test compares it with the committed file).
pub fn section() -> Result<String> {
    let shipped = controller()?;
    let base = |state: &str| -> Result<f64> {
        let label = format!("{MACHINE}/{state}/swing_hip");
        Ok(shipped.param(shipped.param_id(&label).with_context(|| format!("no parameter {label}"))?))
    };
    let [(cd0, cv0), (cd1, cv1)] = gains(&shipped)?;
    let (lift, stride) = (base(STATES[0])?, base(STATES[1])?);
    let mut s = String::new();
    writeln!(s, "## SIMBICON as published (Yin, Loken & van de Panne 2007)\n")?;
    writeln!(
        s,
        "`cargo xtask reproduce nunes-simbicon-faithful`: `walk-simbicon-faithful.ron`, SIMBICON's 2-D walk of the \
         paper's Table 1 without optimisation — one machine whose legs swap roles at each foot strike; in both \
         states the stance hip holds the torso (the pelvis) at a world angle, τ_stance = −τ_torso − τ_swing, and the \
         swing hip tracks the world angle θ_d0 + c_d·d + c_v·v (d: the centre of mass ahead of the stance ankle, \
         v: its forward speed); LIFT (state 0: θ_d0 = {lift}, c_d = {cd0}, c_v = {cv0}) lasts {LIFT_SECONDS} s, \
         STRIDE (state 1: θ_d0 = {stride}, c_d = {cd1}, c_v = {cv1}) ends at the swing foot's strike — on the \
         thesis's humanoid with SIMBICON-style gains (`humanoid-simbicon.ron`: kp = 300 N·m/rad, kd = 30 N·m·s/rad \
         on every joint). The world is every Nunes experiment's (Δt = {DT} s, {SUBSTEPS} physics sub-steps, \
         implicit springs; the torso's torque is explicit, re-evaluated at every sub-step) unless a row says \
         otherwise. A walk stops at the first fall (a body other than a foot on the ground, or the pelvis below \
         0.7 m); the walker starts from standing still.\n"
    )?;
    writeln!(
        s,
        "| walker | figure | control step (s) / physics sub-steps | walked (s) | distance (m) | mean speed (m/s) | \
         foot strikes | mean step (m) | largest torso tilt (rad) | fell |"
    )?;
    writeln!(s, "|---|---|---|---|---|---|---|---|---|---|")?;
    let mut gaits = Vec::new();
    for k in &cases()? {
        let (text, gait) = row(k)?;
        eprintln!("anima-lab: {text}");
        writeln!(s, "{text}")?;
        gaits.push(gait);
    }
    if let Some(w) = gaits[0] {
        s.push_str(&summary(&w, &gaits)?);
    }
    Ok(s)
}

/// The paragraph under the table, from what [`cases`] measured (in its order).
fn summary(w: &Gait, gaits: &[Option<Gait>]) -> Result<String> {
    let fell_at = |g: &Option<Gait>| match g {
        Some(g) if g.outcome.fell => format!("falls after {:.2} s", g.seconds),
        Some(g) => format!("walks {:.1} m in {:.0} s", g.outcome.distance, g.seconds),
        None => "diverges".to_string(),
    };
    let walks = |g: &Option<Gait>| g.is_some_and(|g| !g.outcome.fell);
    let period = w.seconds / w.strikes.max(1) as f64;
    let stiffer = thesis_humanoid(100.0)?.actuators()[hip(&thesis_humanoid(100.0)?)?].kp
        / skeleton().actuators()[hip(&skeleton())?].kp;
    Ok(format!(
        "\nWith the published gains the walker {} ({:.2} m/s, a step every {period:.2} s, {:.2} m long), and in 10 \
         minutes it {}; with c_d = c_v = 0 it {}. With c_d = 0 alone it {}, with c_v = 0 alone it {}{}. STRIDE ends \
         {:.2} s after LIFT on average. At 100 Hz the walker {}; with 8 physics sub-steps per control step it {}, \
         with 2 it {}. On the thesis's humanoid, whose hips are {stiffer:.1} times stiffer with Table 6.2's gains × \
         100, it {} (× 25: {}).\n",
        fell_at(&gaits[0]),
        w.speed(),
        w.step_length(),
        fell_at(&gaits[1]),
        fell_at(&gaits[2]),
        fell_at(&gaits[3]),
        fell_at(&gaits[4]),
        if walks(&gaits[3]) && !walks(&gaits[4]) { ": LIFT's c_v is the gain that keeps it up" } else { "" },
        period - LIFT_SECONDS,
        fell_at(&gaits[5]),
        fell_at(&gaits[6]),
        fell_at(&gaits[7]),
        fell_at(&gaits[8]),
        fell_at(&gaits[9]),
    ))
}

/// The report with `section` as its faithful section (the other one kept from the file on disk when
/// written with [`Repo::write_report`]).
pub fn document(section: &str) -> Document {
    let mut doc = Document::new(REPORT_HEADER, &REPORT_SECTIONS);
    doc.section("faithful", section);
    doc
}

/// `reproduce nunes-simbicon-faithful`: the faithful walker as published, without its feedback gains, at
/// other control rates, and on the thesis's gains; writes its section of
/// `docs/reproduction/nunes-simbicon.md` and returns its text.
pub fn reproduce(repo: &Repo) -> Result<String> {
    let s = section()?;
    repo.write_report(REPORT, &document(&s))?;
    Ok(s)
}

/// `docs/reproduction/nunes-simbicon.md`: the SIMBICON-style search (`nunes-simbicon`) and SIMBICON as
/// published (`nunes-simbicon-faithful`), each command rewriting its own section.
pub const REPORT: &str = "reproduction/nunes-simbicon.md";
pub const REPORT_SECTIONS: [&str; 2] = ["simbicon-form", "faithful"];
pub const REPORT_HEADER: &str = "# SIMBICON: balance feedback in the thesis's representation, and SIMBICON as published\n\n\
     Written by `cargo xtask reproduce nunes-simbicon` (the SIMBICON-style form against the thesis's machines, \
     about an hour) and `cargo xtask reproduce nunes-simbicon-faithful` (SIMBICON as published, seconds); each \
     rewrites its own section.";
