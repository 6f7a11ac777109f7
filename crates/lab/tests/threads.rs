//! A sheet run on every core ends where it ends on one thread, to the bit (issue #19: every core by
//! default in the `anima` binary for sheets large enough to pay): symplectic Euler's fused run, its rows
//! in bands on threads kept for the run, and the other explicit methods, whose spring passes are shared
//! out pass by pass.

use anima_lab::repo::Repo;
use anima_lab::run::{Detail, RunOptions, Silent, parallel_min_particles, run};
use anima_ode::Integrator;
use anima_scene::{LoadOptions, Scene, load};

/// The smallest square sheet that runs on every core with `integrator`, 40 steps at a step it is
/// stable at: one thread against all.
fn one_thread_and_all_agree(integrator: Integrator) {
    let mut scene =
        load(&Repo::here().assets("scenes/standard-sheet-64.ron"), &LoadOptions::default()).unwrap();
    let Scene::Sheet(sheet) = &mut scene else { panic!("a sheet scene") };
    sheet.sheet.n = (parallel_min_particles(integrator) as f64).sqrt().ceil() as usize;
    sheet.sheet.pinned = vec![(0, 0), (sheet.sheet.n - 1, 0)];
    sheet.integrator = integrator;
    sheet.dt_s = 2e-5;
    sheet.duration_s = 8e-4;
    let detail = |parallel: bool| {
        let s = run(&scene, "sheet", &RunOptions { parallel, ..RunOptions::quiet() }, &mut Silent).unwrap();
        assert!(s.all_finite, "{:?}", s.error);
        let Detail::Sheet(d) = s.detail else { panic!("a sheet's summary") };
        d
    };
    let (one, all) = (detail(false), detail(true));
    assert_eq!(one.threads, 1);
    let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
    if cores > 1 {
        assert!(
            (2..=cores).contains(&all.threads),
            "{integrator:?}: {} threads on {cores} cores",
            all.threads
        );
    }
    assert!(one.max_speed > 1e-3, "the sheet moves: {} m/s", one.max_speed);
    for (a, b) in one.center_of_mass.iter().zip(&all.center_of_mass) {
        assert_eq!(
            a.to_bits(),
            b.to_bits(),
            "{integrator:?}: centre of mass {:?} vs {:?}",
            one.center_of_mass,
            all.center_of_mass
        );
    }
    assert_eq!(one.kinetic_energy.to_bits(), all.kinetic_energy.to_bits(), "{integrator:?}");
    assert_eq!(one.max_strain.to_bits(), all.max_strain.to_bits(), "{integrator:?}");
}

#[test]
fn a_sheet_stepped_with_symplectic_euler_on_every_core_ends_where_it_ends_on_one() {
    one_thread_and_all_agree(Integrator::SymplecticEuler);
}

#[test]
fn a_sheet_stepped_with_rk4_on_every_core_ends_where_it_ends_on_one() {
    one_thread_and_all_agree(Integrator::Rk4);
}
