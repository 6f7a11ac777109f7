//! Scene files: the RON conversions of the thesis scripts, determinism, and runs through the CLI library.

use anima_cloth::flex3d::Flex3dWorld;
use anima_lab::flex3d::{ThesisScene, flex3d_assets};
use anima_lab::run::flex3d::run;
use anima_lab::run::{Detail, RunOptions, Silent};
use anima_scene::LoadOptions;

/// Runs a loaded scene for `steps` steps and returns the final positions.
fn positions_after(loaded: &anima_scene::LoadedFlex3d, steps: u64) -> Vec<anima_geom::DVec3> {
    let mut world = Flex3dWorld::new(&loaded.scene, loaded.meshes()).unwrap();
    world.run_to_step(steps).unwrap();
    world.positions().to_vec()
}

#[test]
fn par_and_its_ron_conversion_run_identically() {
    for scene in ThesisScene::ALL {
        let par = scene.load().unwrap();
        let ron_path = flex3d_assets().join(format!("{}.ron", scene.slug()));
        let ron = anima_scene::load_flex3d(&ron_path, &LoadOptions::default()).unwrap();
        assert_eq!(par.scene, ron.scene, "{}: the committed RON must say what the script says", scene.slug());
        assert_eq!(positions_after(&par, 500), positions_after(&ron, 500), "{}", scene.slug());
    }
}

#[test]
fn committed_ron_scenes_are_what_convert_writes() {
    for scene in ThesisScene::ALL {
        let bytes = std::fs::read(flex3d_assets().join(scene.script())).unwrap();
        let fresh = anima_scene::convert_par_to_ron(&bytes, scene.script(), scene.gravity()).unwrap();
        let committed =
            std::fs::read_to_string(flex3d_assets().join(format!("{}.ron", scene.slug()))).unwrap();
        assert_eq!(
            fresh,
            committed,
            "assets/flex3d/{}.ron is stale: run `cargo run --release -p anima-cli -- convert assets/flex3d/{} -o assets/flex3d/{}.ron --gravity {}`",
            scene.slug(),
            scene.script(),
            scene.slug(),
            if scene.gravity() == anima_geom::DVec3::ZERO { "off" } else { "on" }
        );
    }
}

#[test]
fn repeated_runs_are_bit_identical() {
    for scene in [ThesisScene::Tablecloth, ThesisScene::Cardboard] {
        let loaded = scene.load().unwrap();
        assert_eq!(positions_after(&loaded, 3000), positions_after(&loaded, 3000), "{}", scene.slug());
    }
}

#[test]
fn every_integrator_keeps_the_curtain_finite_at_the_thesis_step() {
    for integrator in anima_ode::Integrator::ALL {
        let mut loaded = ThesisScene::Curtain.load().unwrap();
        loaded.scene.integrator = integrator;
        if integrator.is_adaptive() {
            // They choose their own steps, which a FLEX3D world does not give them: refused.
            let e = Flex3dWorld::new(&loaded.scene, loaded.meshes()).unwrap_err();
            assert!(e.to_string().contains("chooses its own steps"), "{integrator}: {e}");
            continue;
        }
        let p = positions_after(&loaded, 5000);
        assert!(p.iter().all(|x| x.is_finite()), "{integrator}");
    }
}

/// A run far beyond its stable step is stopped by its speed bound while still finite, at the step
/// where a particle first outran it; with the bounds off, when it goes non-finite, naming the surface.
#[test]
fn a_diverging_run_reports_the_step_where_it_left_its_bounds_or_went_non_finite() {
    let mut loaded = ThesisScene::Curtain.load().unwrap();
    loaded.scene.dt_s = 0.5;
    let mut world = Flex3dWorld::new(&loaded.scene, vec![]).unwrap();
    let anima_cloth::StepError::Diverged(err) = world.run_to_step(100_000).unwrap_err() else {
        panic!("expected the bounds to stop it")
    };
    assert!(matches!(err.bound, anima_cloth::bounds::Bound::Speed { .. }), "{err}");
    assert!(err.step > 1 && err.step < 100, "{err}");
    let mut world = Flex3dWorld::new(&loaded.scene, vec![]).unwrap();
    world.set_bounds(anima_cloth::bounds::Bounds::unbounded());
    let anima_cloth::StepError::NonFinite(late) = world.run_to_step(100_000).unwrap_err() else {
        panic!("expected a non-finite state")
    };
    assert!(late.step > err.step && late.step < 100_000, "{late}");
    assert_eq!(late.place.as_ref().map(|p| p.surface.as_str()), Some("cortina"));
    assert!(late.to_string().contains("non-finite state at step"), "{late}");
}

#[test]
fn run_writes_frames_pictures_and_summary() {
    let dir = std::env::temp_dir().join(format!("anima-run-test-{}", std::process::id()));
    let mut loaded = ThesisScene::Tablecloth.load().unwrap();
    loaded.scene.duration_s = 1.0;
    let opts = RunOptions { frame0: true, ..RunOptions::writing_to(&dir) };
    let (s, world) = run(&loaded, "tablecloth", &opts, &mut Silent).unwrap();
    assert_eq!((s.steps, s.frames), (1000, 2));
    let Detail::Flex3d(d) = &s.detail else { panic!("a FLEX3D summary") };
    assert!(s.all_finite && d.non_finite.is_none());
    assert_eq!(d.penetrations, 0);
    for name in ["toalha_0.OBT", "toalha_1.OBT", "toalha_2.OBT", "toalha_2.obj", "final.png", "frames.png"] {
        assert!(dir.join(name).is_file(), "{name} missing");
    }
    let obt =
        anima_geom::obt::read_obt(std::fs::File::open(dir.join("toalha_2.OBT")).unwrap(), Default::default())
            .unwrap();
    assert_eq!((obt.vertices.len(), obt.faces.len()), (400, 2 * 19 * 19));
    for (a, b) in obt.vertices.iter().zip(world.positions()) {
        assert!((*a - *b).abs().max_element() <= 5e-7, "frame file must hold the final state to 6 decimals");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn implicit_euler_settles_the_curtain_at_sixty_times_the_thesis_step() {
    let mut loaded = ThesisScene::Curtain.load().unwrap();
    loaded.scene.integrator = anima_ode::Integrator::ImplicitEuler;
    loaded.scene.dt_s = 1.0 / 60.0;
    // At this step literal friction would reverse slow particles' velocities every step (chatter).
    loaded.scene.options.friction_clamp = true;
    let objects = vec![];
    let mut world = Flex3dWorld::new(&loaded.scene, objects).unwrap();
    let mut peak = 0.0f64;
    for second in 1..=25 {
        world.run_to_step(second * 60).unwrap();
        peak = peak.max(world.diagnostics().max_speed);
    }
    let x = world.surface_positions(0);
    let bottom = x[380..400].iter().map(|p| p.y).sum::<f64>() / 20.0;
    // The explicit run at 0.001 s settles at 12.535: the implicit one must hang at the same place, and
    // its motion must have died down to 1 % of its peak (the slow vertical bounce of the hanging sheet
    // decays more slowly than under forward Euler: literal friction vanishes near equilibrium).
    assert!((bottom - 12.535).abs() < 0.1, "bottom row at {bottom}");
    let last = world.diagnostics().max_speed;
    assert!(last < 0.01 * peak, "max speed {last} against a peak of {peak}");
}
