//! anima's experiments and runs.

pub mod bench;
pub mod figures;
pub mod flex3d;
pub mod nunes;
pub mod oliveira;
pub mod optimise;
pub mod output;
pub mod picture;
pub mod repo;
pub mod report;
pub mod run;
