//! The one drape loop of the Oliveira cloth (static or remeshed), which `anima run` and the thesis's
//! drape experiments share, and the objects' meshes for pictures.

use std::ops::ControlFlow;
use std::time::Instant;

use anima_cloth::StepError;
use anima_cloth::oliveira::{AdaptiveCloth, AdaptiveMethod, OliveiraCloth, StepReport};
use anima_geom::query::tessellate;
use anima_geom::{DVec3, Solid, TriangleMesh};

/// How a drape run ended.
#[derive(Debug)]
pub enum Ended {
    /// It reached the end time.
    Done,
    /// The observer stopped it (a wall-time cap, say).
    Stopped,
    /// A step failed (a non-finite state): the run stops there.
    Failed(StepError),
}

/// The one drape loop: steps `cloth` (static or remeshed) until `t_end`, handing every step to
/// `observe` with its report and its own wall time, s (the observer's work is not in it). The observer
/// may stop the run.
pub fn run_drape(
    cloth: &mut AdaptiveCloth,
    t_end: f64,
    mut observe: impl FnMut(&AdaptiveCloth, &StepReport, f64) -> ControlFlow<()>,
) -> Ended {
    while cloth.cloth().time() < t_end {
        let start = Instant::now();
        let report = match cloth.step() {
            Ok(r) => r,
            Err(e) => return Ended::Failed(e),
        };
        let wall = start.elapsed().as_secs_f64();
        if observe(cloth, &report, wall).is_break() {
            return Ended::Stopped;
        }
    }
    Ended::Done
}

/// A static cloth in the run loop's wrapper (no remesher: the steps are the cloth's own).
pub fn unremeshed(cloth: OliveiraCloth, gravity: DVec3) -> AdaptiveCloth {
    AdaptiveCloth::new(cloth, gravity, AdaptiveMethod::Static)
}

/// Triangle meshes of the objects, for pictures, each with whether it is unbounded (a half-space,
/// drawn as a square around the cloth).
pub fn object_meshes(cloth: &OliveiraCloth) -> Vec<(TriangleMesh, bool)> {
    cloth
        .colliders()
        .iter()
        .map(|c| match &c.solid {
            Solid::Mesh(m) => (m.to_mesh(), false),
            Solid::Sphere(s) => (tessellate::sphere(s, 64), false),
            Solid::Cylinder(c) => (tessellate::cylinder(c, 96), false),
            Solid::HalfSpace(h) => (tessellate::plane_patch(h, DVec3::ZERO, 0.9), true),
        })
        .collect()
}
