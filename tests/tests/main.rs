//! anima's integration tests: one binary, one module per subject.

mod flex3d_experiments;
mod flex3d_scenes;
mod gltf_export;
mod oliveira;
mod reports;
mod standard_sheet;
