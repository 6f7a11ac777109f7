//! `cargo xtask figures` for Nunes 2006: strobe pictures of the walker before and after optimisation
//! (Fig. 6.7), the throw (Fig. 6.12) and the assisted backflip (Fig. 6.17), the robust and SIMBICON
//! walkers under pushes, variant C's protective machines under head pushes (Figs. 4.7, 6.9), and the
//! best fitness against evaluations of every optimiser on the walking and throwing objectives.
//!
//! A strobe picture overlays the figure every few control iterations, older frames faded towards the
//! sky, in the thesis's side view (x forward, y up).

use crate::nunes::{self, WalkRules};
use crate::repo::Repo;
use crate::run::body::{SKY, draw_bodies, draw_ground};
use anima_body::BodyPose;
use anima_character::Character;
use anima_control::optimise::{
    Annealing, AnnealingConfig, Cmaes, CmaesConfig, GreedySearch, Optimiser, RandomSearch, RunLog, run,
};
use anima_viz::{Image, LinePlot, Series, View2d, draw_line, fill_disc};
use anyhow::{Context, Result};

use crate::nunes::report::{SEED, thesis_spec};
use anima_scene::optimisation::OptimiserSpec;

/// Every body of every model after one control iteration.
type Frame = Vec<Vec<BodyPose>>;

fn capture(c: &Character) -> Frame {
    let world = &c.env.world;
    (0..world.n_models())
        .map(|m| {
            let mut poses = Vec::new();
            world.body_poses(m, &mut poses).expect("a model of this world");
            poses
        })
        .collect()
}

/// World-space bounds (x0, y0, x1, y1) of the body centres of `frames`, with `pad` metres around.
fn bounds<'a>(frames: impl Iterator<Item = &'a Frame>, pad: f64) -> (f64, f64, f64, f64) {
    let mut b = (f64::INFINITY, 0.0f64, f64::NEG_INFINITY, f64::NEG_INFINITY);
    for p in frames.flatten().flatten() {
        b.0 = b.0.min(p.centre[0]);
        b.2 = b.2.max(p.centre[0]);
        b.3 = b.3.max(p.centre[1]);
    }
    (b.0 - pad, -0.15, b.2 + pad, b.3 + pad)
}

/// Draws `frames` (oldest first) over the ground, fading the older ones.
fn strobe(img: &mut Image, view: &View2d, frames: &[&Frame]) {
    draw_ground(
        img,
        view,
        &anima_body::WorldSettings::thesis().ground.expect("the thesis's world has a ground"),
    );
    let n = frames.len().max(2) - 1;
    for (k, f) in frames.iter().enumerate() {
        let weight = 0.3 + 0.7 * k as f64 / n as f64;
        for model in f.iter() {
            draw_bodies(img, view, model, weight);
        }
    }
}

/// Copies `panels` below one another into one picture.
fn stack(panels: &[Image]) -> Result<Image> {
    let w = panels.iter().map(Image::width).max().unwrap_or(1);
    let h = panels.iter().map(Image::height).sum();
    let mut out = Image::new(w, h, SKY)?;
    let mut top = 0;
    for p in panels {
        for y in 0..p.height() {
            for x in 0..p.width() {
                out.set_pixel(x, top + y, p.pixel(x, y));
            }
        }
        top += p.height();
    }
    Ok(out)
}

/// Fig. 6.7: the first `SECONDS` of the walker with the spec's proposed poses (it falls, as the
/// thesis's did before optimisation), with our re-authored poses, and after the thesis's optimisation;
/// then the same before and after on the humanoid with gains × 27, where the unoptimised walker falls
/// (after half a minute: those two panels show the `SECONDS` up to and past its fall).
fn fig_6_7() -> Result<Image> {
    const SECONDS: f64 = 8.0;
    const EVERY: usize = 8;
    /// Where the gains × 27 panels begin, s (the unoptimised walker there falls at 30.75 s).
    const LATE: f64 = 25.0;
    let rules = WalkRules { window: 0, stop_on_failure: false, ..WalkRules::default() };
    type Build = fn(anima_control::Controller) -> Result<Character, anima_character::CharacterError>;
    let (gains_100, gains_27): (Build, Build) = (nunes::humanoid_character, nunes::faithful_character);
    let faithful = crate::nunes::report::FAITHFUL_OPTIMISED;
    let walkers = [
        (
            "the spec's §8.1.2 poses (before re-authoring)",
            crate::nunes::optimisers::spec_walker()?,
            gains_100,
            0.0,
        ),
        (
            "walk.ron (re-authored; before the thesis's optimisation)",
            nunes::controller("walk")?,
            gains_100,
            0.0,
        ),
        ("walk-optimised.ron (after)", nunes::controller("walk-optimised")?, gains_100, 0.0),
        (
            "gains x 27: walk.ron (before the thesis's optimisation)",
            nunes::controller("walk")?,
            gains_27,
            LATE,
        ),
        ("gains x 27: walk-faithful-optimised.ron (after)", nunes::controller(faithful)?, gains_27, LATE),
    ];
    let mut runs = Vec::new();
    for (name, c, build, from) in walkers {
        let (skip, iterations) =
            ((from / nunes::DT).round() as usize, ((from + SECONDS) / nunes::DT).round() as u64);
        let mut frames = Vec::new();
        let out = nunes::walk_character(build(c)?, iterations, &rules, &[], |c| frames.push(capture(c)))?;
        frames.drain(..skip.min(frames.len()));
        runs.push((name, out, frames, from));
    }
    // One scale for every panel, each panel centred on its own frames.
    let boxes: Vec<_> = runs.iter().map(|r| bounds(r.2.iter(), 0.6)).collect();
    let span = boxes.iter().map(|b| b.2 - b.0).fold(0.0, f64::max);
    let top = boxes.iter().map(|b| b.3).fold(f64::NEG_INFINITY, f64::max);
    let (width, height) = (1600, 300);
    let mut panels = Vec::new();
    for ((name, out, frames, from), b) in runs.iter().zip(&boxes) {
        let from = *from;
        let x0 = 0.5 * (b.0 + b.2 - span);
        let view = View2d::fit(x0, b.1, x0 + span, top, width, height, 8);
        let mut img = Image::new(width, height, SKY)?;
        let picked: Vec<&Frame> = frames.iter().step_by(EVERY).collect();
        strobe(&mut img, &view, &picked);
        let fell = if out.fell { ", falls (later frames lie on the ground)" } else { "" };
        img.label(
            8,
            6,
            &format!(
                "{name}: {:.1} m in {} s{fell}; {from:.0} to {:.0} s, a frame every {:.1} s",
                out.distance,
                from + SECONDS,
                from + SECONDS,
                EVERY as f64 * nunes::DT
            ),
            16.0,
        )?;
        panels.push(img);
    }
    stack(&panels)
}

/// Fig. 6.12: the optimised throw, the ball's path and the hoop.
fn fig_6_12() -> Result<Image> {
    let mut frames = Vec::new();
    let out = nunes::throw(nunes::controller("throw-optimised")?, &nunes::BASKET, 2000, |c| {
        frames.push(capture(c))
    })?;
    let ball =
        |f: &Frame| f[0].iter().find(|p| matches!(p.shape, anima_body::Shape::Ball { .. })).map(|p| p.centre);
    let path: Vec<[f64; 2]> = frames.iter().filter_map(ball).collect();
    let hoop = nunes::BASKET.hoop;
    let r = nunes::BASKET.radius;
    let x1 = path.iter().map(|p| p[0]).fold(hoop[0] + r, f64::max) + 0.4;
    let y1 = path.iter().map(|p| p[1]).fold(hoop[1], f64::max) + 0.3;
    let (x0, ..) = bounds(frames.iter(), 0.6);
    let (width, height) = (900, 600);
    let view = View2d::fit(x0, -0.15, x1, y1, width, height, 8);
    let mut img = Image::new(width, height, SKY)?;
    // The thrower until the release and a little after; the ball's whole path.
    let last = out.released_at.map_or(frames.len(), |r| (r as usize + 10).min(frames.len()));
    let picked: Vec<&Frame> = frames[..last].iter().step_by(4).collect();
    strobe(&mut img, &view, &picked);
    for w in path.windows(2) {
        draw_line(&mut img, view.to_px(w[0][0], w[0][1]), view.to_px(w[1][0], w[1][1]), 2.0, [230, 140, 40]);
    }
    for p in path.iter().step_by(3) {
        fill_disc(&mut img, view.to_px(p[0], p[1]), 3.0, [200, 100, 20]);
    }
    // The hoop (a rim seen from the side) and its post.
    let rim = [40, 40, 40];
    draw_line(
        &mut img,
        view.to_px(hoop[0] - r, hoop[1]),
        view.to_px(hoop[0] + r, hoop[1]),
        4.0,
        [200, 40, 40],
    );
    draw_line(&mut img, view.to_px(hoop[0] + r, hoop[1]), view.to_px(hoop[0] + r + 0.1, hoop[1]), 2.0, rim);
    draw_line(
        &mut img,
        view.to_px(hoop[0] + r + 0.1, 0.0),
        view.to_px(hoop[0] + r + 0.1, hoop[1] + 0.5),
        3.0,
        rim,
    );
    img.label(
        8,
        6,
        &format!(
            "throw-optimised.ron: H_max {:.2} m, closest {:.2} m from the aimed point, {}",
            out.h_max,
            out.d_min,
            if out.scored { "through the hoop" } else { "misses the hoop" }
        ),
        16.0,
    )?;
    Ok(img)
}

/// Fig. 6.17: the assisted backflip, from the push to the landing (or the end of the run).
fn fig_6_17() -> Result<Image> {
    let mut frames = Vec::new();
    let out = nunes::backflip(nunes::controller("backflip")?, nunes::FLIP_SPACING, 380, |c| {
        frames.push(capture(c))
    })?;
    let start = out.push_at.map_or(0, |p| (p as usize).saturating_sub(6));
    let end = out.landed_at.map_or(frames.len(), |l| (l as usize + 12).min(frames.len()));
    let picked: Vec<&Frame> = frames[start..end.max(start + 1)].iter().step_by(3).collect();
    let (x0, y0, x1, y1) = bounds(picked.iter().copied(), 0.8);
    let (width, height) = (900, 560);
    let view = View2d::fit(x0, y0, x1, y1, width, height, 8);
    let mut img = Image::new(width, height, SKY)?;
    strobe(&mut img, &view, &picked);
    img.label(
        8,
        6,
        &format!(
            "backflip.ron: trunk turned {:.2} rad (a full turn is 6.28); {}",
            out.max_rotation,
            if out.flipped() {
                "lands and stands"
            } else if out.landed_at.is_some() {
                "lands, does not stay standing"
            } else {
                "does not land on its feet"
            }
        ),
        16.0,
    )?;
    Ok(img)
}

/// The push figure: the walker optimised under pushes with the thesis's machines (`walk-robust.ron`)
/// and its SIMBICON form (`walk-simbicon.ron`), each pushed 20 N·s forward and backward on the head
/// 20 s into the walk (the pushes of `nunes-optimisers`), from 0.5 s before the push to 5 s after.
fn fig_pushes() -> Result<Image> {
    let walkers = [
        ("walk-robust.ron (the thesis's machines)", "walk-robust"),
        ("walk-simbicon.ron (SIMBICON form)", "walk-simbicon"),
    ];
    // 10 s after the push, as the push survival of `nunes-optimisers` counts it.
    stack(&push_panels(&walkers, 20.0, 400, 100, 200, 5)?)
}

/// Variant C (spec §8.1.9, the thesis's Figs. 4.7 and 6.9): `walk.ron` and `walk-protected.ron`
/// pushed on the head, forward and backward, 100 N·s over 0.1 s.
fn fig_protective() -> Result<Image> {
    let walkers = [
        ("walk.ron (no protective machines)", "walk"),
        ("walk-protected.ron (PROTECT-FWD, PROTECT-BACK)", "walk-protected"),
    ];
    stack(&push_panels(&walkers, 100.0, 200, 40, 60, 4)?)
}

/// Strobes of each walker pushed on the head `impulse` N·s forward and then backward over two
/// iterations from iteration `at`: from 10 iterations before the push to `shown` after it, a frame
/// every `every`, the run going on `run` iterations after the push.
fn push_panels(
    walkers: &[(&str, &str)],
    impulse: f64,
    at: u64,
    shown: u64,
    run: u64,
    every: u64,
) -> Result<Vec<Image>> {
    const DURATION: u64 = 2;
    let (first, last) = (at - 10, at + shown);
    let rules = WalkRules { window: 0, stop_on_failure: false, ..WalkRules::default() };
    let (width, height) = (1600, 260);
    let mut panels = Vec::new();
    for (name, text) in walkers {
        for direction in [1.0, -1.0] {
            let push = nunes::Push::impulse(direction * impulse, at, DURATION);
            let mut frames = Vec::new();
            let mut k = 0;
            let out = nunes::walk(nunes::controller(text)?, at + run, &rules, &[push], |c| {
                k += 1;
                if (first..=last).contains(&k) && (k - first) % every == 0 {
                    frames.push(capture(c));
                }
            })?;
            let picked: Vec<&Frame> = frames.iter().collect();
            let (x0, y0, x1, y1) = bounds(picked.iter().copied(), 0.6);
            let view = View2d::fit(x0, y0, x1, y1, width, height, 8);
            let mut img = Image::new(width, height, SKY)?;
            strobe(&mut img, &view, &picked);
            // An arrow onto the head where the push began.
            let pushed = &frames[((at - first) / every) as usize];
            if let Some(head) = pushed.iter().flatten().map(|p| p.centre).max_by(|a, b| a[1].total_cmp(&b[1]))
            {
                let tail = [head[0] - direction * 0.6, head[1]];
                let red = [200, 30, 30];
                draw_line(&mut img, view.to_px(tail[0], tail[1]), view.to_px(head[0], head[1]), 4.0, red);
                fill_disc(&mut img, view.to_px(head[0], head[1]), 6.0, red);
            }
            img.label(
                8,
                6,
                &format!(
                    "{name}: {impulse} N·s {} on the head at {:.0} s; {} {:.0} s later; a frame every {:.2} s",
                    if direction > 0.0 { "forward" } else { "backward" },
                    at as f64 * nunes::DT,
                    if out.fell { "fallen" } else { "still walking" },
                    run as f64 * nunes::DT,
                    every as f64 * nunes::DT
                ),
                16.0,
            )?;
            panels.push(img);
        }
    }
    Ok(panels)
}

/// Best fitness so far against evaluations, one line per optimiser.
pub fn fitness_plot(title: &str, y_label: &str, logs: &[(&str, RunLog)]) -> Result<Image> {
    let mut plot = LinePlot::new(title, "evaluations", y_label);
    for (name, log) in logs {
        let mut best = f64::NEG_INFINITY;
        let pts = log
            .evaluations
            .iter()
            .enumerate()
            .map(|(k, e)| {
                if e.fitness > best {
                    best = e.fitness;
                }
                ((k + 1) as f64, best)
            })
            .collect();
        plot.series.push(Series::line(*name, pts));
    }
    Ok(plot.render(720, 440)?)
}

/// The four optimisers on one objective from `x0`, each to `budget` evaluations: the thesis's greedy
/// search with `stages`, CMA-ES, random search and simulated annealing (seed 2006 for each).
fn compare(
    space: anima_control::optimise::Space,
    x0: &[f64],
    greedy: Vec<anima_control::optimise::Stage>,
    budget: usize,
    temperature: f64,
    objective: &dyn anima_control::optimise::Objective,
) -> Result<Vec<(&'static str, RunLog)>> {
    let mut opts: Vec<(&'static str, Box<dyn Optimiser>)> = vec![
        ("greedy (thesis)", Box::new(GreedySearch::new(space.clone(), greedy, x0.to_vec(), SEED)?)),
        ("CMA-ES", Box::new(Cmaes::new(space.clone(), CmaesConfig::new(x0.to_vec(), 0.2), SEED)?)),
        ("random search", Box::new(RandomSearch::new(space.clone(), 4, SEED)?)),
        (
            "annealing",
            Box::new(Annealing::new(
                space,
                AnnealingConfig { x0: x0.to_vec(), t0: temperature, cooling: 0.95, step: 0.1, batch: 1 },
                SEED,
            )?),
        ),
    ];
    let mut logs = Vec::new();
    for (name, opt) in &mut opts {
        eprintln!("anima-lab:   {name}, {budget} evaluations …");
        let mut log = RunLog::default();
        run(opt.as_mut(), objective, budget, &mut log)?;
        let best = log.best().map_or(f64::NAN, |e| e.fitness);
        eprintln!("anima-lab:   {name}: best {best:.3} after {} evaluations", log.len());
        logs.push((*name, log));
    }
    Ok(logs)
}

/// The four optimisers on one of the thesis's specs (`walk` or `throw`): the greedy search with the
/// spec's stages against CMA-ES, random search and annealing over the spec's objective and budget.
fn spec_logs(repo: &Repo, name: &str, sigma: f64) -> Result<Vec<(&'static str, RunLog)>> {
    let loaded = thesis_spec(repo, name)?;
    let (spec, base) = (&loaded.spec, &loaded.controller);
    let ids = base.free_params(&spec.parameters);
    let x0 = base.values_of(&ids);
    let OptimiserSpec::Greedy { stages } = &spec.optimiser else {
        anyhow::bail!("{name}: the thesis's spec is a greedy search")
    };
    let objective = |x: &[f64]| crate::optimise::fitness(&spec.objective, base, &ids, x);
    compare(base.space(&ids), &x0, stages.clone(), spec.evaluations - 1, sigma, &objective)
}

fn walk_fitness_figure(repo: &Repo) -> Result<Image> {
    let logs = spec_logs(repo, "walk", 2.0)?;
    fitness_plot("Walking: distance in 50 s (p2, p3, p5, p6)", "best fitness (m)", &logs)
}

fn throw_fitness_figure(repo: &Repo) -> Result<Image> {
    let logs = spec_logs(repo, "throw", 0.5)?;
    fitness_plot("Throwing: Eq. 6.1 with the height cap", "best fitness", &logs)
}

/// Writes every Nunes figure through `save`.
pub fn figures(repo: &Repo) -> Result<()> {
    let save = |name: &str, img: &Image| repo.write_figure(name, img);
    eprintln!("anima-lab: Fig. 6.7 (walker strobe) …");
    save("nunes-fig-6-7-walk.png", &fig_6_7().context("Fig. 6.7")?)?;
    eprintln!("anima-lab: Fig. 6.12 (throw strobe) …");
    save("nunes-fig-6-12-throw.png", &fig_6_12().context("Fig. 6.12")?)?;
    eprintln!("anima-lab: Fig. 6.17 (backflip strobe) …");
    save("nunes-fig-6-17-backflip.png", &fig_6_17().context("Fig. 6.17")?)?;
    eprintln!("anima-lab: pushes on the robust and SIMBICON walkers …");
    save("nunes-pushes.png", &fig_pushes().context("push figure")?)?;
    eprintln!("anima-lab: variant C under head pushes (Figs. 4.7, 6.9) …");
    save("nunes-protective.png", &fig_protective().context("protective figure")?)?;
    eprintln!("anima-lab: walking fitness against evaluations …");
    save("nunes-walk-fitness.png", &walk_fitness_figure(repo)?)?;
    eprintln!("anima-lab: throwing fitness against evaluations …");
    save("nunes-throw-fitness.png", &throw_fitness_figure(repo)?)?;
    Ok(())
}
