//! The anima-control test binary: state-machine semantics, controller files, optimisers.

mod files;
mod machines;
mod optimise;
mod roles;
