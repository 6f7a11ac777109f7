//! What a user of whole scenes reaches for first, in one import: `use anima_run::prelude::*;`.
//!
//! Loading a scene file of any kind ([`load`], [`Scene`]), stepping it ([`ClothSim`], [`FigureSim`],
//! a character from [`build_character`], all through [`Simulation`] and, with particles, [`Deformable`]),
//! or running it to its end as `anima run` does ([`run`](crate::run::run) with [`RunOptions`]).

pub use anima_scene::{LoadOptions, Scene, load};

pub use crate::run::body::build_character;
pub use crate::run::{RunOptions, Silent, SolveOptions, Summary};
pub use crate::sim::{ClothSim, FigureSim};
pub use crate::simulation::{Deformable, Simulation};
