//! Contact inside the implicit step (generalised-α, `ContactMode::InSolve`): Coulomb friction at the
//! velocity level holds a cloth on an incline it should stick to and lets it slide down one it should
//! not, at Δt = 1/60 s; and Oliveira's three fine drapes at 1/60 s never have a particle inside an
//! object.

use anima_cloth::contact_mode::ContactMode;
use anima_cloth::network_sim::{Collider, NetworkSim};
use anima_cloth::oliveira::{OliveiraCloth, ShapeDesc, StepRule};
use anima_cloth::spring_net::SheetSpec;
use anima_geom::DVec3;
use anima_ode::Integrator;

mod common;

use common::load_scene;

const DT: f64 = 1.0 / 60.0;

/// A 9 × 9 sheet, 0.3 m square, lying at rest on a plane through the origin inclined by `degrees`
/// about the y axis, its downhill direction +x; returns the sim and the downhill unit vector.
fn sheet_on_incline(degrees: f64, mu: f64) -> (NetworkSim, DVec3) {
    let theta = degrees.to_radians();
    let normal = DVec3::new(theta.sin(), 0.0, theta.cos());
    let downhill = DVec3::new(theta.cos(), 0.0, -theta.sin());
    let spec = SheetSpec { n: 9, size: 0.3, pinned: vec![], ..SheetSpec::standard(9) };
    let margin = 1e-3;
    let x: Vec<DVec3> =
        spec.positions().iter().map(|p| downhill * p.x + DVec3::Y * p.y + normal * margin).collect();
    let mut sim = NetworkSim::new(spec.build().unwrap(), x, Integrator::GeneralizedAlpha, DT).unwrap();
    sim.colliders = vec![Collider::Plane { point: DVec3::ZERO, normal }];
    sim.friction = mu;
    sim.margin = margin;
    sim.contact = ContactMode::InSolve;
    (sim, downhill)
}

fn centre(sim: &NetworkSim) -> DVec3 {
    sim.network.centre_of_mass(&sim.state.x)
}

#[test]
fn cloth_on_a_10_degree_incline_sticks_with_mu_0_4() {
    let (mut sim, downhill) = sheet_on_incline(10.0, 0.4);
    let start = centre(&sim);
    for step in 1..=120 {
        sim.run(1).unwrap_or_else(|e| panic!("step {step}: {e}"));
        let moved = (centre(&sim) - start).dot(downhill);
        assert!(moved.abs() < 1e-3, "the cloth slid {moved} m by step {step} (t = {} s)", sim.time());
    }
    let below = sim
        .state
        .x
        .iter()
        .map(|p| p.dot(DVec3::new(10f64.to_radians().sin(), 0.0, 10f64.to_radians().cos())))
        .fold(f64::INFINITY, f64::min);
    assert!(below > 0.0, "a particle went through the incline: {below}");
}

#[test]
fn cloth_on_a_10_degree_incline_slides_with_mu_0_05() {
    let (mut sim, downhill) = sheet_on_incline(10.0, 0.05);
    let start = centre(&sim);
    sim.run(60).unwrap();
    let theta = 10f64.to_radians();
    // Coulomb sliding: a = g (sin θ − μ cos θ), so s = a t²/2 after 1 s.
    let expected = 0.5 * 9.81 * (theta.sin() - 0.05 * theta.cos());
    let moved = (centre(&sim) - start).dot(downhill);
    assert!(
        (moved - expected).abs() < 0.1 * expected,
        "slid {moved} m in 1 s, Coulomb friction gives {expected} m"
    );
}

/// Oliveira's cloth (tension-only springs, Bridson bending) on the same incline, with contact in the
/// solve: μ = 0.4 holds it, μ = 0.05 lets it slide by the Coulomb distance. Air drag is off (it would
/// slow the slide), and cloth and incline get the same μ, so that Eq. 4.17's mean is μ.
#[test]
fn oliveira_cloth_on_a_10_degree_incline_sticks_or_slides() {
    let theta = 10f64.to_radians();
    let normal = DVec3::new(theta.sin(), 0.0, theta.cos());
    let downhill = DVec3::new(theta.cos(), 0.0, -theta.sin());
    for (mu, sticks) in [(0.4, true), (0.05, false)] {
        let mut scene = load_scene("oliveira", "test-3-sphere-17x17.ron").0;
        scene.material.permeability = 0.0;
        scene.material.friction = mu;
        scene.cloth.size_m = 0.4;
        scene.cloth.centre = anima_cloth::oliveira::Centre::At(anima_geom::DVec2::ZERO);
        scene.cloth.height = anima_cloth::oliveira::Height::At { z_m: 1.0 };
        scene.objects = vec![anima_cloth::oliveira::ObjectDesc {
            name: "incline".into(),
            friction: mu,
            shape: ShapeDesc::HalfSpace { point_m: DVec3::ZERO, normal },
        }];
        scene.integrator = Integrator::GeneralizedAlpha;
        scene.time_step = StepRule::Fixed { dt_s: 1.0 / 60.0 };
        scene.options.contact = ContactMode::InSolve;
        let mut cloth = OliveiraCloth::new(&scene, vec![]).unwrap();
        // Lay the cloth on the incline: its flat grid rotated into the plane, 0.15 mm above it.
        let masses = cloth.masses().to_vec();
        let total: f64 = masses.iter().sum();
        let flat: Vec<DVec3> = cloth.positions().to_vec();
        let placed: Vec<DVec3> =
            flat.iter().map(|p| downhill * p.x + DVec3::Y * p.y + normal * 1.5e-4).collect();
        cloth.set_state(&placed, &vec![DVec3::ZERO; placed.len()]);
        let centre = |c: &OliveiraCloth| {
            c.positions().iter().zip(&masses).map(|(p, m)| *p * *m).sum::<DVec3>() / total
        };
        let start = centre(&cloth);
        for step in 1..=60 {
            cloth.step().unwrap_or_else(|e| panic!("μ = {mu}, step {step}: {e}"));
            assert!(
                cloth.penetrations().is_empty(),
                "μ = {mu}: a particle is inside the incline at step {step}"
            );
        }
        let moved = (centre(&cloth) - start).dot(downhill);
        if sticks {
            assert!(moved.abs() < 1e-3, "μ = {mu}: the cloth slid {moved} m");
        } else {
            let expected = 0.5 * 9.81 * (theta.sin() - mu * theta.cos());
            assert!(
                (moved - expected).abs() < 0.1 * expected,
                "μ = {mu}: slid {moved} m, Coulomb gives {expected} m"
            );
        }
    }
}

/// Oliveira's three fine drapes at 1/60 s with generalised-α and contact in the solve: no particle is
/// inside an object after any step, and the runs end finite.
#[test]
fn no_particle_inside_an_object_at_any_step_of_the_three_drapes_at_1_60_s() {
    for file in ["test-1-bunny-17x17.ron", "test-2-table-17x17.ron", "test-3-sphere-17x17.ron"] {
        let (mut scene, meshes) = load_scene("oliveira", file);
        scene.integrator = Integrator::GeneralizedAlpha;
        scene.time_step = StepRule::Fixed { dt_s: 1.0 / 60.0 };
        scene.options.contact = ContactMode::InSolve;
        let mut cloth = OliveiraCloth::new(&scene, meshes).unwrap();
        let mut touched = 0;
        while cloth.time() < scene.duration_s - 1e-9 {
            let report = cloth.step().unwrap_or_else(|e| panic!("{file}: {e}"));
            touched = touched.max(report.hits);
            let inside = cloth.penetrations();
            assert!(
                inside.is_empty(),
                "{file}: particles inside an object after step {}: {inside:?}",
                cloth.steps()
            );
        }
        assert!(touched > 0, "{file}: the cloth never touched the object");
    }
}

/// A FLEX3D surface (16 × 16, spacing 1) dropped flat onto a box at Δt = 1/60 s with generalised-α and the
/// box's contacts in the solve: no particle is ever inside the box, the part over the box rests on its
/// top, and the motion dies down.
#[test]
fn flex3d_surface_rests_on_a_box_with_contact_in_the_solve() {
    use anima_cloth::flex3d::{Flex3dScene, Flex3dWorld, Friction, FrictionMode, ModelOptions, SurfaceDesc};
    let scene = Flex3dScene {
        duration_s: 4.0,
        frame_rate_hz: 1.0,
        dt_s: 1.0 / 60.0,
        gravity_m_s2: DVec3::new(0.0, -9.8, 0.0),
        external_force_n: DVec3::ZERO,
        friction: Friction { mode: FrictionMode::Viscous, coefficient: 0.5 },
        objects: vec![],
        integrator: Integrator::GeneralizedAlpha,
        options: ModelOptions { object_contact: ContactMode::InSolve, ..ModelOptions::thesis() },
        surfaces: vec![SurfaceDesc {
            name: "sheet".into(),
            rows: 16,
            cols: 16,
            spacing_m: 1.0,
            centre_m: DVec3::new(0.0, 8.0, 0.0),
            normal: DVec3::Y,
            particle_mass_kg: 0.2,
            stiffness_n_m: [50.0; 3],
            bending_n_m: [0.0; 3],
            fixed: vec![],
            translations: vec![],
        }],
    };
    let table = anima_geom::box_mesh(DVec3::new(-4.0, 0.0, -4.0), DVec3::new(4.0, 5.0, 4.0));
    let mut world = Flex3dWorld::new(&scene, vec![table]).unwrap();
    let mut peak = 0.0f64;
    for step in 1..=scene.n_steps() {
        world.step().unwrap_or_else(|e| panic!("step {step}: {e}"));
        assert_eq!(world.penetrations(), 0, "a particle is inside the box after step {step}");
        peak = peak.max(world.diagnostics().kinetic_energy);
    }
    // The particles over the box's top lie on it (within the contact thickness of 0.5 % of the
    // spacing, twice), and the sheet has come to rest.
    let on_top = world
        .positions()
        .iter()
        .filter(|p| p.x.abs() < 3.5 && p.z.abs() < 3.5)
        .map(|p| p.y)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!((5.0..5.02).contains(&on_top), "the highest particle over the top is at y = {on_top}");
    // The overhanging sides swing down and wrap the box; the viscous friction (rate 2.5/s) settles them.
    let d = world.diagnostics();
    assert!(
        d.all_finite && d.kinetic_energy < 0.01 * peak,
        "kinetic energy {} J after 4 s, {peak} J at its peak",
        d.kinetic_energy
    );
}

/// Same inputs, same results: two runs of the 20 m/s drop with contact in the solve are bit-identical.
#[test]
fn contact_in_the_solve_is_deterministic() {
    let run = || {
        let spec = SheetSpec { pinned: vec![], ..SheetSpec::standard(12) };
        let mut sim =
            NetworkSim::new(spec.build().unwrap(), spec.positions(), Integrator::GeneralizedAlpha, DT)
                .unwrap();
        sim.state.v.iter_mut().for_each(|v| *v = DVec3::new(0.3, 0.0, -20.0));
        sim.colliders = vec![
            Collider::Box { min: DVec3::new(0.2, 0.2, 0.0), max: DVec3::new(0.8, 0.8, 1.0) },
            Collider::Plane { point: DVec3::ZERO, normal: DVec3::Z },
        ];
        sim.friction = 0.3;
        sim.contact = ContactMode::InSolve;
        sim.run(40).unwrap();
        sim.state
    };
    assert_eq!(run(), run());
}

/// Smoothed friction (`options.friction_smoothing_m_s`): a 17² cloth dropped on a ball on a floor at
/// 1/60 s drapes without a particle inside either and comes to rest; a speed that is not positive is
/// refused, named.
#[test]
fn smoothed_friction_drapes_a_ball_and_refuses_a_bad_speed() {
    let build = |eps: f64| {
        OliveiraCloth::builder(17, 0.6)
            .sphere("ball", DVec3::new(0.0, 0.0, 0.15), 0.15)
            .floor(0.0)
            .smoothed_friction(eps)
            .build()
    };
    for eps in [0.0, -1e-3, f64::NAN] {
        let err = build(eps).expect_err("a speed that is not positive").to_string();
        assert!(err.contains("options.friction_smoothing_m_s"), "{err}");
    }
    let mut cloth = build(1e-3).unwrap();
    let (mut peak, mut last_second) = (0.0f64, 0.0f64);
    for step in 0..300 {
        cloth.step().unwrap();
        assert!(cloth.penetrations().is_empty(), "step {step}: particles inside {:?}", cloth.penetrations());
        let kinetic = cloth.kinetic_energy();
        peak = peak.max(kinetic);
        if step >= 240 {
            last_second = last_second.max(kinetic);
        }
    }
    // It comes to rest over the ball: in its fifth second the kinetic energy stays below a thousandth of
    // its peak (measured: 1.0·10⁻⁵ J against 4.9·10⁻² J; the active set's, 2.9·10⁻⁶ J).
    assert!(last_second < 1e-3 * peak, "kinetic energy {last_second} J in the fifth second, peak {peak} J");
}
