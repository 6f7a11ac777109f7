//! The self-intersection count of a run's summary: the checker sees the crossings of FLEX3D's
//! faithful sail (its velocity-swap response loses the cloth through itself after frame 14, the case
//! the self-collision issue starts from) and none on a sheet that hangs free.

use anima_lab::repo::Repo;
use anima_lab::run::{RunOptions, Silent, run};
use anima_scene::{LoadOptions, load};

fn self_intersections(asset: &str) -> usize {
    let scene = load(&Repo::here().assets(asset), &LoadOptions::default()).unwrap();
    let summary = run(&scene, asset, &RunOptions::quiet(), &mut Silent).unwrap();
    summary.self_intersections.expect("a cloth scene counts its self-intersections")
}

#[test]
fn the_faithful_sail_passes_through_itself_and_the_summary_says_so() {
    assert!(self_intersections("flex3d/a2-2-vento.par") > 0);
}

#[test]
fn a_hanging_sheet_never_passes_through_itself() {
    assert_eq!(self_intersections("scenes/standard-sheet-32.ron"), 0);
}
