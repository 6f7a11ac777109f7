//! Contact inside the implicit step (generalised-α, `ContactMode::InSolve`): Coulomb friction at the
//! velocity level holds a cloth on an incline it should stick to and lets it slide down one it should
//! not, at Δt = 1/60 s.

use anima_cloth::contact_mode::ContactMode;
use anima_cloth::network_sim::{Collider, NetworkSim};
use anima_cloth::spring_net::SheetSpec;
use anima_geom::DVec3;
use anima_ode::Integrator;

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
    let mut sim = NetworkSim::new(spec.build(), x, Integrator::GeneralizedAlpha, DT);
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
    eprintln!("slid {moved} expected {expected}");
    assert!(
        (moved - expected).abs() < 0.1 * expected,
        "slid {moved} m in 1 s, Coulomb friction gives {expected} m"
    );
}
