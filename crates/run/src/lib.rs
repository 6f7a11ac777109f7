//! anima's runtime: what `anima run`, `anima optimise` and the Python package do with a scene, apart
//! from the thesis experiments (`anima-lab`).
//!
//! # What this crate is
//!
//! - [`run`](mod@run): a loaded scene of any kind ([`anima_scene::Scene`]) run to its end, with frames,
//!   pictures, a glTF export and one JSON [`run::Summary`];
//! - [`sim`]: a scene as an object its caller steps and whose state it reads and writes ([`sim::ClothSim`],
//!   [`sim::FigureSim`]);
//! - [`Simulation`] and [`Deformable`]: one contract for everything anima steps (every cloth model,
//!   posed figures, a character) and for what has particles;
//! - [`optimise`]: a controller optimisation from a spec file, logged and resumable;
//! - [`objectives`]: the objectives a spec can name (walking, throwing, the backflip), the figures they
//!   are measured on, and their trackers, which a character scene's run reports;
//! - [`prelude`]: the types above a user reaches for first, in one import;
//! - [`interrupt`]: a request from outside (Python's Ctrl-C) that a long computation stop;
//! - [`live`]: a run watched and steered while it goes (`anima run --live`): frames out, a page's
//!   pause, step and controller parameters in, through a [`live::LiveLink`] its caller implements;
//! - [`drape`]: the Oliveira cloth's drape loop; [`output`]: files written whole (a temporary file, then
//!   a rename); [`picture`]: the pictures a run writes.
//!
//! # What it is not
//!
//! No physics of its own (the models are `anima-cloth`'s and `anima-body`'s), no file format (scene files
//! are `anima-scene`'s), no thesis experiment and no report (`anima-lab`'s), no command line. It writes
//! only into the folder its caller names.
//!
//! # Use
//!
//! ```
//! use anima_run::run::{Detail, RunOptions, Silent, run};
//! use anima_scene::{LoadOptions, load};
//!
//! // Any scene file, run as `anima run` runs it (here without writing anything).
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/scenes/standard-sheet-32.ron");
//! let scene = load(path.as_ref(), &LoadOptions::default()).unwrap();
//! let summary = run(&scene, "standard sheet", &RunOptions::quiet(), &mut Silent).unwrap();
//! let Detail::Sheet(sheet) = &summary.detail else { unreachable!() };
//! assert!(summary.all_finite && (sheet.center_of_mass[2] - 1.4655).abs() < 2e-3);
//! ```

pub mod drape;
pub mod interrupt;
pub mod live;
pub mod objectives;
pub mod optimise;
pub mod output;
pub mod picture;
pub mod prelude;
pub mod run;
pub mod sim;
pub mod simulation;

pub use simulation::{Deformable, Simulation};

/// The repository's `assets/` folder, for the tests.
#[cfg(test)]
pub(crate) fn test_asset(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets").join(rel)
}
