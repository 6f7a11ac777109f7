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
pub const GROUPS: [&str; 4] = ["flex3d", "oliveira", "nunes", "self-collision"];

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
    if wanted("self-collision") {
        eprintln!("anima-lab: rendering the folded drape …");
        repo.write_figure("self-collision-folded-drape.png", &folded_drape()?)?;
    }
    Ok(())
}

/// A 32 × 32 sheet dropped upright onto a sphere over a floor (the folding sheet of the self-collision
/// tests and cost example), 1.5 s of generalised-α at 1/240 s with contact in the solve, with and without
/// the self-collision response; each picture is labelled with the most crossing (edge, triangle) pairs
/// of any step.
fn folded_drape() -> Result<Image> {
    use anima_cloth::contact_mode::ContactMode;
    use anima_cloth::network_sim::{Collider, NetworkSim};
    use anima_cloth::self_collision::SelfCollision;
    use anima_cloth::spring_net::SheetSpec;
    use anima_geom::query::tessellate;
    use anima_geom::{DVec3, Sphere, count_self_intersections};
    use anima_viz::{RenderMesh, RenderSettings, render};

    let n = 32;
    let spec = SheetSpec { pinned: vec![], height: 1.0, ..SheetSpec::standard(n) };
    let sphere = Sphere { centre: DVec3::new(0.5, 0.45, 0.3), radius: 0.3 };
    let triangles = spec.triangles();
    let mut tiles = Vec::new();
    for response in [true, false] {
        let x = spec.positions().iter().map(|p| DVec3::new(p.x, 0.5 + 0.1 * p.y, 0.65 + p.y)).collect();
        let mut sim = NetworkSim::new(spec.build()?, x, Integrator::GeneralizedAlpha, 1.0 / 240.0)?;
        sim.colliders = vec![
            Collider::Sphere { centre: sphere.centre, radius: sphere.radius },
            Collider::Plane { point: DVec3::ZERO, normal: DVec3::Z },
        ];
        sim.friction = 0.3;
        sim.contact = ContactMode::InSolve;
        sim.state.v.fill(DVec3::new(0.0, 0.3, 0.0));
        if response {
            sim.enable_self_collision(SelfCollision::default(), triangles.clone());
        }
        let mut most = 0;
        for _ in 0..360 {
            sim.step()?;
            most = most.max(count_self_intersections(&sim.state.x, &triangles));
        }
        // z is up in this scene; the pictures want y up.
        let up = |p: DVec3| DVec3::new(p.x, p.z, -p.y);
        let cloth: Vec<DVec3> = sim.state.x.iter().map(|&p| up(p)).collect();
        let ball = tessellate::sphere(&sphere, 48);
        let ball_vertices: Vec<DVec3> = ball.vertices().iter().map(|&p| up(p)).collect();
        let floor_vertices: Vec<DVec3> = [(-0.3, -0.4), (1.3, -0.4), (1.3, 1.4), (-0.3, 1.4)]
            .iter()
            .map(|&(x, y)| up(DVec3::new(x, y, 0.0)))
            .collect();
        let floor_triangles = [[0, 1, 2], [0, 2, 3]];
        let meshes = [
            RenderMesh::new(&floor_vertices, &floor_triangles, [190, 190, 180]),
            RenderMesh::new(&ball_vertices, ball.triangles(), [150, 110, 70]),
            RenderMesh::new(&cloth, &triangles, [200, 70, 70]).with_edges(),
        ];
        let bounds = scene_bounds([cloth.as_slice(), ball_vertices.as_slice()], &[]);
        let camera = camera_along(bounds, DVec3::new(-0.5, -0.9, 0.7));
        let mut img = render(&meshes, &camera, &RenderSettings::new(640, 480))?;
        let label = if response {
            format!("with the self-collision response: {most} crossings at any step")
        } else {
            format!("without it: up to {most} crossing pairs")
        };
        img.label(10, 8, &label, 18.0)?;
        tiles.push(img);
    }
    Ok(Image::grid(&tiles, 2, 8, [255, 255, 255])?)
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
