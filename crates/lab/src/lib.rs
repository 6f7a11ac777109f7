//! anima's experiments and runs.

pub mod flex3d;
pub mod nunes;
pub mod output;
pub mod picture;
pub mod run;
