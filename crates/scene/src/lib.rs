//! Scene files: the FLEX3D animation language `.PAR` (Nedel 1993 §5.2) and anima's RON scenes, both
//! read into one [`Flex3dScene`], plus the `.OBT` objects a scene names (Annex A-1).
//!
//! The key decision: a `.PAR` script is kept as written ([`par::ParScript`]) and only then turned into a
//! scene, because the language cannot say everything a run needs. What it leaves out (gravity above all,
//! spec S3.1) is supplied by the caller, and a RON scene, which can say all of it, is the lossless form:
//! `.PAR` → scene → RON → scene gives back exactly the same scene.
//!
//! This crate does not simulate and writes no frames (`anima_cloth` runs a scene; `anima_geom::obt`
//! writes `.OBT`). It checks what the grammar and the specification's validation rules say (counts,
//! index ranges, positive times and masses); whether a scene is physically sensible is not its business.

mod load;
pub mod oliveira;
pub mod par;
pub mod ron_scene;
pub mod sheet;
mod text;

pub use anima_cloth::flex3d::{FLEX3D_GRAVITY, Flex3dScene};
pub use anima_format::{END_OF_FILE, ParseError};
pub use load::{LoadOptions, LoadedScene, SceneError, convert_par_to_ron, load};
pub use text::decode;
