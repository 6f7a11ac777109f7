//! anima's experiments: every thesis experiment as a function, with the reports that set anima's numbers
//! beside the theses', the figures and the benchmarks.
//!
//! # What this crate is
//!
//! - [`flex3d`], [`oliveira`], [`nunes`]: the experiments of the three theses (Nedel 1993's E-1…E-8,
//!   Oliveira 2013's Tests I–III on static, implicit and adaptive meshes, Nunes 2006's walker, thrower
//!   and backflip), the reports that set our numbers beside the theses', and the figures;
//!   [`bench`](mod@bench), [`scale`] and [`peers`]: speed against error, at users' sizes and beside
//!   other simulators.
//! - The runtime it runs them on is `anima-run`'s ([`run`](mod@run), [`sim`], [`optimise`],
//!   [`output`], [`picture`], re-exported here): the experiments run scenes as `anima run` does.
//! - [`report`]: reports as documents of named sections, so a partial run updates its own sections;
//!   [`repo`]: where assets are read and reports, figures and caches are written.
//!
//! # What it is not
//!
//! No physics of its own (the models are `anima-cloth`'s and `anima-body`'s), no file formats (scene
//! files are `anima-scene`'s), no command line, and nothing the `anima` command or the Python package
//! needs (that is `anima-run`): `cargo xtask` is a thin caller of this crate, and the integration tests
//! check the numbers the reports print through the same functions.
//! It writes files only where its caller says: a run's output folder, or the repository a [`repo::Repo`]
//! names.
//!
//! # Use
//!
//! ```
//! use anima_lab::flex3d::e1_table_4_1;
//! use anima_lab::repo::Repo;
//! use anima_lab::run::{Detail, RunOptions, Silent, run};
//! use anima_ode::Integrator;
//! use anima_scene::{LoadOptions, load};
//!
//! // Nedel 1993's Table 4.1, to the last printed digit.
//! assert_eq!(e1_table_4_1(Integrator::ForwardEuler).matches, 66);
//!
//! // Any scene file, run as `anima run` runs it (here without writing anything).
//! let scene = load(&Repo::here().assets("scenes/standard-sheet-32.ron"), &LoadOptions::default()).unwrap();
//! let summary = run(&scene, "standard sheet", &RunOptions::quiet(), &mut Silent).unwrap();
//! let Detail::Sheet(sheet) = &summary.detail else { unreachable!() };
//! assert!(summary.all_finite && (sheet.center_of_mass[2] - 1.4655).abs() < 2e-3);
//! ```

pub mod bench;
pub mod figures;
pub mod flex3d;
pub mod nunes;
pub mod oliveira;
pub mod peers;
pub mod repo;
pub mod report;
pub mod scale;

pub use anima_run::{optimise, output, picture, run, sim};
