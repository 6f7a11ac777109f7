//! Scene files: every file anima reads to run something, read once and checked before anything runs.
//!
//! # What this crate is
//!
//! One [`load`] for every kind of scene, telling the kind by the extension (`.par`) or by the struct a
//! RON file starts with, and reading every part the scene names relative to its folder:
//!
//! | kind | file | parts |
//! |---|---|---|
//! | FLEX3D surfaces (Nedel 1993) | a `.PAR` script (§5.2) or `Flex3dScene(…)` | `.OBT` objects |
//! | a square sheet: springs, or the continuum membrane (`model: Membrane(…)`) | `SheetScene(…)` | — |
//! | an Oliveira 2013 drape | `OliveiraScene(…)`, `AdaptiveOliveiraScene(…)` | OBJ meshes |
//! | articulated figures holding poses | `BodyScene(…)` | skeletons |
//! | figures driven by a controller (Nunes 2006) | `CharacterScene(…)` | skeletons, a controller |
//!
//! and [`load_optimisation`] for `Optimisation(…)` specs, which name a controller to tune. Every error
//! is one [`SceneError`] that names the file, and for text errors the line, the column, what was
//! expected and what was found ([`ParseError`], [`anima_format::FieldError`]).
//!
//! The key decision for FLEX3D: a `.PAR` script is kept as written ([`par::ParScript`]) and only then
//! turned into a scene, because the language cannot say everything a run needs. What it leaves out
//! (gravity above all, spec S3.1) is supplied by the caller, and a RON scene, which can say all of it,
//! is the lossless form: `.PAR` → scene → RON → scene gives back exactly the same scene.
//!
//! # What it is not
//!
//! It does not simulate and writes no files: `anima-lab` runs a loaded [`Scene`], `anima_geom::obt`
//! writes `.OBT`. It checks what the grammars and the specifications' validation rules say (counts,
//! index ranges, positive times and masses, names that resolve); whether a scene is physically sensible
//! is not its business. It knows `anima-control` only to read a controller file.
//!
//! # Use
//!
//! ```
//! use std::path::Path;
//! use anima_scene::{LoadOptions, Scene, load};
//!
//! let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/scenes/standard-sheet-32.ron");
//! match load(&path, &LoadOptions::default()).unwrap() {
//!     Scene::Sheet(sheet) => assert_eq!(sheet.sheet.n, 32),
//!     other => panic!("a sheet scene, found {:?}", other.kind()),
//! }
//! let bad = std::env::temp_dir().join(format!("anima-scene-doc-{}.ron", std::process::id()));
//! std::fs::write(&bad, "SheetScene(\n    sheet: (n: 32),\n    duraton_s: 1.0,\n)").unwrap();
//! let e = load(&bad, &LoadOptions::default()).unwrap_err().to_string();
//! assert!(e.contains(":2:") || e.contains(":3:"), "the error names the line: {e}");
//! std::fs::remove_file(&bad).unwrap();
//! ```

pub mod body;
/// The largest scene anima agrees to build; defined beside the file formats so that every reader
/// (skeletons, controllers, optimisation specs, scenes) checks against the same numbers.
pub use anima_format::limits;
pub mod character;
mod error;
pub mod flex3d;
mod load;
pub mod oliveira;
pub mod optimisation;
pub mod par;
pub mod sheet;
mod text;

pub use anima_cloth::flex3d::{FLEX3D_GRAVITY, Flex3dScene};
pub use anima_format::{END_OF_FILE, ParseError};
pub use error::SceneError;
pub use flex3d::{LoadedFlex3d, convert_par_to_ron};
pub use load::{
    LoadOptions, Scene, SceneKind, figures_run_problem, load, load_flex3d, load_oliveira, load_optimisation,
    read_limited,
};
pub use text::decode;
