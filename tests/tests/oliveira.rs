//! Oliveira 2013 cloth on static meshes: the committed scenes of Tests I–III, contact (no particle ends
//! inside the Bunny, the table or the sphere; friction on an incline), finiteness, determinism, and
//! clear errors for malformed scenes and meshes. Full-length fine runs live in `cargo xtask reproduce
//! oliveira`; here the fine meshes run for their first tens of milliseconds of contact.

use std::path::{Path, PathBuf};

use anima_cloth::oliveira::{
    BuildError, ContactVelocity, Height, Material, ObjectDesc, OliveiraCloth, Options, ShapeDesc, StepRule,
};
use anima_geom::DVec3;
// The incline of the report's friction runs (`cargo xtask reproduce oliveira-choices`).
use anima_lab::oliveira::choices::incline;
use anima_ode::Integrator;
use anima_scene::oliveira::LoadedOliveira;
use anima_scene::{SceneError, load_oliveira};

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../assets/oliveira")
}

const SCENES: [&str; 3] = ["test-1-bunny", "test-2-table", "test-3-sphere"];

fn scene(name: &str, n: usize) -> LoadedOliveira {
    let path = assets().join(format!("{name}-{n}x{n}.ron"));
    load_oliveira(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// Runs `cloth` until `t_end`, checking every `check_every` steps (and at the end) that no particle is
/// inside an object; every step already fails on a non-finite value.
fn run_checking(cloth: &mut OliveiraCloth, t_end: f64, check_every: u64, what: &str) {
    while cloth.time() < t_end {
        let step = cloth.steps() + 1;
        cloth.step().unwrap_or_else(|e| panic!("{what}: {e}"));
        if step.is_multiple_of(check_every) || cloth.time() >= t_end {
            let inside = cloth.penetrations();
            assert!(
                inside.is_empty(),
                "{what}: at step {step} (t = {:.5} s) particles {inside:?} are inside (particle, object)",
                cloth.time()
            );
        }
    }
    assert!(cloth.positions().iter().chain(cloth.velocities()).all(|p| p.is_finite()), "{what}: non-finite");
}

#[test]
fn committed_scenes_build_with_the_spec_counts_masses_and_stiffnesses() {
    for name in SCENES {
        for (n, v, e, f, k_max) in [(5, 25, 56, 32, 100.0), (17, 289, 800, 512, 400.0)] {
            let cloth = scene(name, n).build().unwrap();
            let m = cloth.mesh();
            assert_eq!((m.n_vertices(), m.n_edges(), m.n_faces()), (v, e, f), "{name} {n}");
            assert!(
                (cloth.max_stiffness() - k_max).abs() < 1e-9,
                "{name} {n}: k_max {}",
                cloth.max_stiffness()
            );
            // A one-triangle corner: (1/(n−1))²/6 of the square (spec §7.5: 8.33e-3 kg coarse at ρ = 8000).
            let rho_t = if name.contains("sphere") { 0.6 } else { 0.8 };
            let corner = rho_t / ((n - 1) * (n - 1)) as f64 / 6.0;
            assert!((cloth.min_mass() - corner).abs() < 1e-15, "{name} {n}: m_min {}", cloth.min_mass());
            let total: f64 = cloth.masses().iter().sum();
            assert!((total - rho_t).abs() < 1e-12, "{name} {n}: total mass {total}");
            assert_eq!(cloth.tracked_vertex(), 0);
        }
    }
}

#[test]
fn coarse_drapes_keep_every_particle_outside_and_finite() {
    for name in SCENES {
        let loaded = scene(name, 5);
        let mut cloth = loaded.build().unwrap();
        run_checking(&mut cloth, loaded.scene.duration_s, 1, &format!("{name} 5 × 5"));
        assert!(cloth.first_collision_time().is_some_and(|t| t < 0.02), "{name}: no early contact");
        assert!(cloth.total_hits() > 10, "{name}: only {} collision responses", cloth.total_hits());
    }
}

#[test]
fn fine_drapes_keep_every_particle_outside_during_first_contact() {
    // Contact starts at 14.5 ms; then 25 ms of it on the Bunny, 35 ms on the table, 45 ms on the sphere.
    for (name, t_end) in [("test-1-bunny", 0.04), ("test-2-table", 0.05), ("test-3-sphere", 0.06)] {
        let mut cloth = scene(name, 17).build().unwrap();
        run_checking(&mut cloth, t_end, 50, &format!("{name} 17 × 17"));
        assert!(cloth.total_hits() > 10, "{name}: only {} collision responses", cloth.total_hits());
    }
}

/// The fine drapes to their end times with the implicit integrators at a step a user would choose
/// (1/60 s, one hundred to a thousand times the thesis's): finite, and no particle inside an object at
/// any step.
#[test]
fn fine_drapes_run_implicitly_at_a_sixtieth_of_a_second() {
    for integrator in [Integrator::ImplicitEuler, Integrator::Bdf2] {
        for strain_limit in [None, Some(0.1)] {
            for name in SCENES {
                let mut loaded = scene(name, 17);
                loaded.scene.integrator = integrator;
                loaded.scene.time_step = StepRule::Fixed { dt_s: 1.0 / 60.0 };
                loaded.scene.options.strain_limit = strain_limit;
                let mut cloth = loaded.build().unwrap();
                let what = format!("{name} 17 × 17, {integrator} at 1/60 s, strain limit {strain_limit:?}");
                run_checking(&mut cloth, loaded.scene.duration_s, 1, &what);
                assert!(cloth.total_hits() > 10, "{what}: only {} collision responses", cloth.total_hits());
            }
        }
    }
}

/// Largest strain (|d| / L⁰ − 1) of the springs whose ends the last contact pass left alone (the
/// contact response restarts a hit particle from its start-of-step position, which no strain limit
/// applied before it can foresee).
fn max_free_strain(cloth: &OliveiraCloth) -> f64 {
    let (s, x, hit) = (cloth.springs(), cloth.positions(), cloth.responded());
    s.ends
        .iter()
        .zip(&s.rest_length)
        .filter(|&(&[i, j], _)| !hit[i as usize] && !hit[j as usize])
        .map(|(&[i, j], l0)| x[i as usize].distance(x[j as usize]) / l0 - 1.0)
        .fold(f64::MIN, f64::max)
}

/// Provot's limit keeps every spring away from contact within 10 % of its rest length where the cloth
/// without it stretches further (the sphere drape at 1/60 s).
#[test]
fn the_strain_limit_holds_springs_within_ten_percent() {
    let strain_after = |limit: Option<f64>| {
        let mut loaded = scene("test-3-sphere", 17);
        loaded.scene.integrator = Integrator::ImplicitEuler;
        loaded.scene.time_step = StepRule::Fixed { dt_s: 1.0 / 60.0 };
        loaded.scene.options.strain_limit = limit;
        loaded.scene.options.contact_velocity = ContactVelocity::EndOfStep;
        let mut cloth = loaded.build().unwrap();
        let mut worst = 0.0f64;
        while cloth.time() < loaded.scene.duration_s {
            cloth.step().unwrap();
            worst = worst.max(max_free_strain(&cloth));
        }
        worst
    };
    let (free, limited) = (strain_after(None), strain_after(Some(0.1)));
    assert!(free > 0.12, "without the limit the largest strain is only {free}");
    // Ten Gauss–Seidel sweeps leave a little of the excess where many springs pull on one particle.
    assert!(limited <= 0.1 + 5e-3, "with the limit the largest strain is {limited} (without: {free})");
}

#[test]
fn step_counts_follow_the_dynamic_step_rule() {
    // After the first collision Δt = β·π·√(m_min/k_max) (Eq. 4.6): 2.29e-4 s on the coarse Test I mesh.
    let loaded = scene("test-1-bunny", 5);
    let mut cloth = loaded.build().unwrap();
    assert_eq!(cloth.dt(), 1e-4, "the start-up step before any contact");
    cloth.run_until(0.05).unwrap();
    let expected = 0.008 * std::f64::consts::PI * (0.8 / 16.0 / 6.0 / 100.0f64).sqrt();
    assert!((cloth.dt() - expected).abs() < 1e-15, "Δt {} vs {expected}", cloth.dt());
}

#[test]
fn culling_collision_tests_changes_nothing() {
    let loaded = scene("test-1-bunny", 5);
    let mut exact = loaded.scene.clone();
    exact.options.cull_collision_tests = false;
    let mut a = loaded.build().unwrap();
    let mut b = OliveiraCloth::new(&exact, loaded.meshes.iter().map(|(_, m)| m.clone()).collect()).unwrap();
    a.run_until(0.3).unwrap();
    b.run_until(0.3).unwrap();
    assert_eq!(a.steps(), b.steps());
    assert_eq!(a.positions(), b.positions(), "culled and exact runs differ");
    assert_eq!(a.velocities(), b.velocities());
}

#[test]
fn repeated_runs_are_bit_identical() {
    let loaded = scene("test-3-sphere", 5);
    let run = || {
        let mut c = loaded.build().unwrap();
        c.run_until(0.2).unwrap();
        (c.positions().to_vec(), c.velocities().to_vec())
    };
    assert_eq!(run(), run());
}

#[test]
fn friction_holds_a_cloth_on_a_10_degree_incline_at_mu_0_4_and_lets_it_slide_at_0_05() {
    let slide = |mu: f64| {
        let mut cloth = OliveiraCloth::new(&incline(mu, 10.0), vec![]).unwrap();
        let start = cloth.tracked_position();
        run_checking(&mut cloth, 1.0, 1, &format!("incline μ = {mu}"));
        (cloth.tracked_position() - start).x
    };
    let held = slide(0.4);
    let slid = slide(0.05);
    assert!(held.abs() < 1e-3, "μ = 0.4: moved {held} m down the slope in 1 s");
    // Sliding with drag: g (sin θ − μ cos θ) accelerates it towards ≈ 0.33 m/s (ρT/κ = 0.267 s).
    assert!(slid > 0.05, "μ = 0.05: moved only {slid} m in 1 s");
}

#[test]
fn free_fall_reaches_the_drag_terminal_speed() {
    // C_i/m_i = κ/(ρT) for every particle, so a flat cloth falls like one body: v(t) = gτ(1 − e^(−t/τ)),
    // τ = ρT/κ = 0.2667 s (spec §4.2). RK4 at 1e-4 s matches it to round-off.
    let mut s = incline(0.0, 0.0);
    s.objects.clear();
    s.cloth.height = Height::At { z_m: 10.0 };
    let mut cloth = OliveiraCloth::new(&s, vec![]).unwrap();
    cloth.run_until(0.8 - 1e-9).unwrap();
    let tau = 8000.0 * 1e-4 / 3.0;
    let expected = 9.81 * tau * (1.0 - (-cloth.time() / tau).exp());
    for v in cloth.velocities() {
        assert!((v.z + expected).abs() < 1e-9 && v.x.abs() < 1e-12, "v = {v}, expected {expected}");
    }
}

/// A folder of its own under the system's temporary folder, for scene files the tests write.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("anima-oliveira-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn malformed_scenes_and_bad_meshes_give_errors_not_panics() {
    let good = std::fs::read_to_string(assets().join("test-1-bunny-5x5.ron")).unwrap();
    let dir = scratch("errors");
    let write = |file: &str, text: &str| {
        let p = dir.join(file);
        std::fs::write(&p, text).unwrap();
        p
    };

    // A misspelt field: the error names the file, the line and what was expected.
    let p = write("misspelt.ron", &good.replace("restitution:", "restitutoin:"));
    let e = load_oliveira(&p).unwrap_err().to_string();
    assert!(e.contains("misspelt.ron:") && e.contains("`restitution`") && e.contains("restitutoin"), "{e}");

    // An option out of range: file, line and the field.
    let sphere = std::fs::read_to_string(assets().join("test-3-sphere-5x5.ron")).unwrap();
    let bad =
        sphere.replace("restitution: 0.5,", "restitution: 0.5,\n    options: (bending_height_floor: -1.0),");
    let e = load_oliveira(&write("floor.ron", &bad)).unwrap_err().to_string();
    assert!(
        e.contains("floor.ron: line 36, column 15") && e.contains("bending_height_floor") && e.contains("-1"),
        "{e}"
    );

    // A membrane material out of range (ν ≥ 0.5): file, line and the field, and why.
    let bad = sphere.replace(
        "restitution: 0.5,",
        "restitution: 0.5,\n    options: (membrane: Some((young_thickness_n_m: 1000.0, poisson: 0.7, \
         bending_n_m: 0.001, damping_s: 0.001))),",
    );
    let e = load_oliveira(&write("membrane.ron", &bad)).unwrap_err().to_string();
    assert!(
        e.contains("membrane.ron: line 36, column 15") && e.contains("membrane") && e.contains("Poisson"),
        "{e}"
    );

    // Broken syntax.
    let p = write("syntax.ron", &good.replace("size_m: 1.0,", "size_m: 1.0.0,"));
    let e = load_oliveira(&p).unwrap_err();
    assert!(matches!(e, SceneError::Parse(ref pe) if pe.line > 1), "{e}");

    // A mesh file that is not there.
    let p = write("missing.ron", &good.replace("../meshes/bunny.obj", "nowhere.obj"));
    let e = load_oliveira(&p).unwrap_err().to_string();
    assert!(e.contains("nowhere.obj"), "{e}");

    // An OBJ whose face names a vertex that does not exist: file, line and column.
    write("bad-index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 9\n");
    let p = write("bad-index.ron", &good.replace("../meshes/bunny.obj", "bad-index.obj"));
    let e = load_oliveira(&p).unwrap_err();
    assert!(matches!(e, SceneError::Obj { .. }), "{e}");
    assert!(e.to_string().contains("bad-index.obj:6:7: vertex index 9 is out of range"), "{e}");

    // An open mesh reads but cannot be a solid: loading builds the drape and says which object, where
    // it is written and why.
    write("open.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\n");
    let p = write("open.ron", &good.replace("../meshes/bunny.obj", "open.obj"));
    let e = load_oliveira(&p).unwrap_err().to_string();
    assert!(e.contains("open.ron") && e.contains("objects[0]") && e.contains("line"), "{e}");
    assert!(e.contains("object `bunny`") && e.contains("not closed"), "{e}");

    // Values out of range are build errors naming the field.
    let mut s = load_oliveira(&assets().join("test-3-sphere-5x5.ron")).unwrap().scene;
    s.cloth.vertices_per_side = 1;
    assert!(matches!(OliveiraCloth::new(&s, vec![]), Err(BuildError::Mesh(_))));
    s.cloth.vertices_per_side = 5;
    s.cloth.tracked_vertex = (5, 0);
    assert!(OliveiraCloth::new(&s, vec![]).unwrap_err().to_string().contains("tracked_vertex"));
    s.cloth.tracked_vertex = (0, 0);
    s.material.young_modulus_pa = f64::NAN;
    assert!(OliveiraCloth::new(&s, vec![]).unwrap_err().to_string().contains("young_modulus_pa"));
    s.material = Material::table_5_5();
    s.options.bending_height_floor = f64::NAN;
    assert!(OliveiraCloth::new(&s, vec![]).unwrap_err().to_string().contains("bending_height_floor"));
    s.options.bending_height_floor = Options::BENDING_HEIGHT_FLOOR;
    s.cloth.height = Height::At { z_m: 0.25 };
    assert!(matches!(OliveiraCloth::new(&s, vec![]), Err(BuildError::StartsInside { .. })));
    // The scene names one mesh; none given.
    let bunny = load_oliveira(&assets().join("test-1-bunny-5x5.ron")).unwrap().scene;
    assert!(matches!(
        OliveiraCloth::new(&bunny, vec![]),
        Err(BuildError::MeshCount { expected: 1, given: 0 })
    ));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn edge_contacts_hold_an_edge_that_spans_a_small_ball() {
    // One square of cloth, its diagonal from (−0.5, −0.5) to (0.5, 0.5) passing 1 mm over a 5 cm ball:
    // no particle lies over the ball, so only the edge test can stop the diagonal.
    let mut s = incline(0.4, 0.0);
    s.cloth.size_m = 1.0;
    s.cloth.height = Height::At { z_m: 0.051 };
    s.objects = vec![ObjectDesc {
        name: "ball".into(),
        friction: 0.4,
        shape: ShapeDesc::Sphere { centre_m: DVec3::ZERO, radius_m: 0.05 },
    }];
    let diagonal_height = |edge_contacts: bool| {
        let mut scene = s.clone();
        scene.options.edge_contacts = edge_contacts;
        let mut cloth = OliveiraCloth::new(&scene, vec![]).unwrap();
        run_checking(&mut cloth, 0.3, 1, "ball");
        let x = cloth.positions();
        (x[0].z + x[3].z) / 2.0
    };
    let (held, fell) = (diagonal_height(true), diagonal_height(false));
    assert!(held > 0.04, "with edge contacts the diagonal's ends sank to {held}");
    assert!(fell < -0.1, "without them the cloth should fall past the ball, got {fell}");
}
