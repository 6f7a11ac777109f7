//! The library behind the `anima` command: running a scene to frames, pictures and a summary. The
//! xtask and the integration tests drive scenes through the same code, so what they measure is what a
//! user runs.

pub mod body_run;
pub mod experiments;
pub mod output;
pub mod picture;
pub mod runner;
pub mod sheet_run;
