//! A sheet whose spring forces are evaluated on every core ends where it ends on one thread, to the
//! bit (issue #19: every core by default in the `anima` binary for sheets large enough to pay).

use anima_lab::repo::Repo;
use anima_lab::run::{Detail, PARALLEL_MIN_PARTICLES, RunOptions, Silent, run};
use anima_scene::{LoadOptions, Scene, load};

#[test]
fn a_sheet_on_every_core_ends_where_it_ends_on_one() {
    let mut scene =
        load(&Repo::here().assets("scenes/standard-sheet-64.ron"), &LoadOptions::default()).unwrap();
    let Scene::Sheet(sheet) = &mut scene else { panic!("a sheet scene") };
    // The smallest square sheet that runs on every core, 40 steps of symplectic Euler at a step it
    // is stable at.
    sheet.sheet.n = (PARALLEL_MIN_PARTICLES as f64).sqrt().ceil() as usize;
    sheet.sheet.pinned = vec![(0, 0), (sheet.sheet.n - 1, 0)];
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
    assert_eq!(all.threads, rayon::current_num_threads());
    assert!(one.max_speed > 1e-3, "the sheet moves: {} m/s", one.max_speed);
    for (a, b) in one.center_of_mass.iter().zip(&all.center_of_mass) {
        assert_eq!(
            a.to_bits(),
            b.to_bits(),
            "centre of mass {:?} vs {:?}",
            one.center_of_mass,
            all.center_of_mass
        );
    }
    assert_eq!(one.kinetic_energy.to_bits(), all.kinetic_energy.to_bits());
    assert_eq!(one.max_strain.to_bits(), all.max_strain.to_bits());
}
