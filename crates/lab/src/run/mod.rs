//! Running a scene to its end: stepping, frames, pictures and a summary, one module per scene kind.

pub mod body;
pub mod flex3d;
pub mod sheet;
