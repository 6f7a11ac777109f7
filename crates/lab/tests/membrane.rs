//! The membrane sheet scene (`assets/scenes/membrane-sheet-33.ron`) runs through `anima run`'s path: the
//! continuum cloth of `anima_cloth::membrane` in place of the springs, with the summary saying so.

use anima_lab::repo::Repo;
use anima_lab::run::{Detail, RunOptions, Silent, run};
use anima_ode::Integrator;
use anima_scene::{LoadOptions, Scene, load};

fn membrane_scene() -> Scene {
    load(&Repo::here().assets("scenes/membrane-sheet-33.ron"), &LoadOptions::default()).unwrap()
}

#[test]
fn the_membrane_sheet_falls_and_swings_at_large_steps() {
    let mut scene = membrane_scene();
    let Scene::Sheet(sheet) = &mut scene else { panic!("a sheet scene") };
    sheet.duration_s = 0.5;
    let s = run(&scene, "membrane", &RunOptions::quiet(), &mut Silent).unwrap();
    assert!(s.all_finite, "{:?}", s.error);
    let Detail::Sheet(d) = s.detail else { panic!("a sheet's summary") };
    assert_eq!((d.model, d.springs, d.triangles), ("membrane", 0, 2 * 32 * 32));
    // Pinned at two corners of one edge, the sheet swings down: its centre of mass is well below the
    // start (1.5 m); and it has not made energy: its kinetic energy is at most the potential energy its
    // centre of mass gave up (the elastic energy is ≥ 0, damping and the method only take energy out).
    assert!(d.center_of_mass[2] < 1.3, "centre of mass {:?}", d.center_of_mass);
    let released = 0.2 * 9.81 * (1.5 - d.center_of_mass[2]);
    assert!(
        d.kinetic_energy > 0.1 * released && d.kinetic_energy <= released,
        "kinetic energy {} J, potential energy released {released} J",
        d.kinetic_energy
    );
    assert!(d.max_strain > 0.0 && d.max_strain.is_finite(), "largest strain {}", d.max_strain);
}

#[test]
fn an_explicit_integrator_steps_the_membrane_too() {
    let mut scene = membrane_scene();
    let Scene::Sheet(sheet) = &mut scene else { panic!("a sheet scene") };
    sheet.integrator = Integrator::Rk4;
    sheet.dt_s = 2e-5;
    sheet.duration_s = 0.02;
    let s = run(&scene, "membrane", &RunOptions::quiet(), &mut Silent).unwrap();
    assert!(s.all_finite, "{:?}", s.error);
    let Detail::Sheet(d) = s.detail else { panic!("a sheet's summary") };
    // 20 ms of free fall away from the pins: about g t²/2 = 2 mm for the centre of mass.
    let drop = 1.5 - d.center_of_mass[2];
    assert!((1.0e-3..2.0e-3).contains(&drop), "the centre of mass fell {drop} m");
}
