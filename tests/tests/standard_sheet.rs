//! The standard sheet of `benchmarks.md`, as other simulators also run it.

use anima_cloth::network_sim::NetworkSim;
use anima_cloth::spring_net::SheetSpec;
use anima_geom::DVec3;
use anima_ode::Integrator;

/// The reference centres of mass at t = 1 s from `benchmarks.md` (f64, symplectic Euler, step 1e-5 s).
fn reference_com(n: usize) -> DVec3 {
    match n {
        32 => DVec3::new(0.4999997, -0.4792614, 1.4655051),
        _ => DVec3::new(0.5000605, -0.4684101, 1.4631486),
    }
}

#[test]
fn centre_of_mass_at_the_common_step_is_within_2_mm_of_the_reference() {
    for (n, dt) in [(32usize, 2e-4), (64, 1e-4)] {
        let spec = SheetSpec::standard(n);
        let mut sim =
            NetworkSim::new(spec.build().unwrap(), spec.positions(), Integrator::SymplecticEuler, dt)
                .unwrap();
        sim.run((1.0 / dt).round() as usize).unwrap();
        let com = sim.network.centre_of_mass(&sim.state.x);
        let error = com.distance(reference_com(n));
        assert!(error < 2e-3, "N = {n}: centre of mass {com} is {:.2} mm from the reference", error * 1e3);
    }
}

#[test]
fn standard_sheet_spring_counts() {
    for n in [32usize, 64] {
        let (s, h, b) = SheetSpec::standard(n).build().unwrap().spring_counts();
        assert_eq!((s, h, b), (2 * n * (n - 1), 2 * (n - 1) * (n - 1), 2 * n * (n - 2)), "N = {n}");
    }
}
