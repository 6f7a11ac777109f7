//! `cargo xtask figures`: Fig. 4.1 and rendered frames of every FLEX3D scene, Oliveira's drapes and Nunes's
//! controller figures ([`crate::nunes::figures`]) into `docs/figures/`.

use crate::flex3d::{self, ThesisScene, run_to_frame};
use crate::picture::{camera_along, labelled_frame, scene_bounds};
use crate::repo::Repo;
use anima_cloth::flex3d::FrictionMode;
use anima_cloth::flex3d::mass_spring::{SingleSpring, TABLE_4_1_STEPS, trajectory};
use anima_ode::Integrator;
use anima_viz::{Image, LinePlot, Series};
use anyhow::Result;

/// The figure groups `cargo xtask figures --only` accepts.
pub const GROUPS: [&str; 3] = ["flex3d", "oliveira", "nunes"];

/// Regenerates every figure of `docs/figures/` (or one group of them) into `repo`.
pub fn all(repo: &Repo, only: Option<&str>) -> Result<()> {
    if let Some(group) = only
        && !GROUPS.contains(&group)
    {
        anyhow::bail!("unknown figure group `{group}` (known: {})", GROUPS.join(", "));
    }
    let wanted = |group: &str| only.is_none_or(|o| o == group);
    if wanted("flex3d") {
        repo.write_figure("fig-4-1-mass-spring.png", &fig_4_1()?)?;
        repo.write_figure("fig-4-2-step-size.png", &fig_4_2()?)?;
        for scene in ThesisScene::ALL {
            eprintln!("anima-lab: rendering {} …", scene.slug());
            repo.write_figure(&format!("flex3d-{}.png", scene.slug()), &scene_sheet(scene)?)?;
        }
    }
    if wanted("oliveira") {
        crate::oliveira::drapes::figures(repo)?;
    }
    if wanted("nunes") {
        crate::nunes::figures::figures(repo)?;
    }
    Ok(())
}

/// Fig. 4.1: position against time for every step of Table 4.1 (sampled finely) and 2 + 2 cos t.
fn fig_4_1() -> Result<Image> {
    let mut plot = LinePlot::new("Fig. 4.1 — one spring under forward Euler", "t", "x(t)");
    plot.y_range = Some((-20.0, 36.0));
    for h in TABLE_4_1_STEPS {
        // Integer sample times as in the table; for h < 1 also every step, so the curve shows the method.
        let samples = fine_trajectory(h);
        plot.series.push(Series::line(format!("h = {h}"), samples));
    }
    let spring = SingleSpring::thesis();
    let exact = (0..=1000).map(|i| (i as f64 * 0.01, spring.exact(i as f64 * 0.01))).collect();
    plot.series.push(Series::dashed("exact 2 + 2 cos t", exact).with_colour([0, 0, 0]));
    Ok(plot.render(1000, 650)?)
}

/// Positions at t = 0, 0.05, … (or at each step when larger) up to t = 10.
fn fine_trajectory(h: f64) -> Vec<(f64, f64)> {
    let every = (0.05 / h).round().max(1.0) as usize;
    let sample_h = every as f64 * h;
    let n = (10.0 / sample_h).round() as usize;
    // Integrate with the same counted steps as Table 4.1, sampling every `every` steps.
    let mut out = vec![(0.0, 4.0)];
    let mut sys = SingleSpring::thesis();
    let mut stepper = anima_ode::Stepper::new(Integrator::ForwardEuler, 1);
    let mut now = anima_ode::State::new(vec![4.0], vec![0.0]);
    let mut next = anima_ode::State::zeros(1);
    let mut k = 0usize;
    for s in 1..=n {
        for _ in 0..every {
            stepper
                .step(&mut sys, k as f64 * h, h, &now, &mut next)
                .expect("the spring gives its Jacobian, so every method steps it");
            std::mem::swap(&mut now, &mut next);
            k += 1;
        }
        out.push((s as f64 * sample_h, now.x[0]));
    }
    debug_assert!(
        (trajectory(Integrator::ForwardEuler, h, 1)[1] - out[(1.0 / sample_h).round() as usize].1).abs()
            < 1e-12
    );
    out
}

/// Fig. 4.2: frame 12 of the wind scene for the five step sizes.
fn fig_4_2() -> Result<Image> {
    let sweep = flex3d::e2_step_sweep(FrictionMode::Literal)?;
    let (_, world) = ThesisScene::Wind.world(|_| {})?;
    // Frame on the converged shape so the diverged one visibly leaves the picture.
    let bounds = scene_bounds([sweep.frames[4].as_slice(), world.positions()], &[]);
    let camera = camera_along(bounds, ThesisScene::Wind.view_dir());
    let tiles = sweep
        .frames
        .iter()
        .zip(&sweep.steps)
        .zip(["a", "b", "c", "d", "e"])
        .map(|((f, h), tag)| labelled_frame(&world, f, &camera, (360, 300), &format!("({tag}) h = {h}")))
        .collect::<Result<Vec<_>>>()?;
    Ok(Image::grid(&tiles, 5, 4, [255, 255, 255])?)
}

/// The frames of a scene that the thesis's figure shows, on one sheet with a fixed camera.
fn scene_sheet(scene: ThesisScene) -> Result<Image> {
    let (loaded, mut world) = scene.world(|_| {})?;
    let mut states = Vec::new();
    let frames = scene.figure_frames();
    if scene == ThesisScene::Curtain {
        states.push((0, world.positions().to_vec()));
    }
    for &k in &frames {
        run_to_frame(&loaded, &mut world, k)?;
        states.push((k, world.positions().to_vec()));
    }
    let bounds = scene_bounds(states.iter().map(|(_, s)| s.as_slice()), world.objects());
    let camera = camera_along(bounds, scene.view_dir());
    let fps = loaded.scene.frame_rate_hz;
    let tiles = states
        .iter()
        .map(|(k, s)| {
            let label = if *k == 0 {
                "initial".to_owned()
            } else {
                format!("frame {k} (t = {:.1} s)", *k as f64 / fps)
            };
            labelled_frame(&world, s, &camera, (400, 320), &label)
        })
        .collect::<Result<Vec<_>>>()?;
    let columns = if tiles.len() <= 2 {
        tiles.len()
    } else if tiles.len() <= 9 {
        3
    } else {
        4
    };
    Ok(Image::grid(&tiles, columns, 4, [255, 255, 255])?)
}
