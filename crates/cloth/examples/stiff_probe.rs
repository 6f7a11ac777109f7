use anima_cloth::network_sim::NetworkSim;
use anima_cloth::spring_net::SheetSpec;
use anima_ode::Integrator;
fn main() {
    let spec = SheetSpec { n: 16, stiffness: [1e5, 1e5, 10.0], ..SheetSpec::standard(16) };
    let mut sim = NetworkSim::new(spec.build(), spec.positions(), Integrator::GeneralizedAlpha, 1.0 / 60.0);
    let k: usize = std::env::var("NEWTON").ok().and_then(|s| s.parse().ok()).unwrap_or(3);
    sim.stepper_mut().set_newton_iterations(k);
    let mut worst: f64 = 0.0;
    for _ in 0..120 {
        sim.run(1).unwrap();
        worst = worst.max(sim.network.max_strain(&sim.state.x));
    }
    let fastest = sim.state.v.iter().map(|v| v.length()).fold(0.0, f64::max);
    println!("largest strain {worst:.4}, end strain {:.4}, fastest {fastest:.3}", sim.network.max_strain(&sim.state.x));
}
