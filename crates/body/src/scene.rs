//! Body scenes: a RON file naming a world, the models in it, the pose each holds and how long to run
//! (`assets/scenes/stand.ron`). The `anima run` command reads them; skeleton files named by a scene
//! are read by the caller (this crate does no file I/O).

use serde::{Deserialize, Serialize};

use crate::actuator::{CommandError, Signal, Target, TargetFrame};
use crate::error::{BodyError, SkeletonError};
use crate::skeleton::{Actuation, BuiltinSkeleton, Skeleton};
use crate::world::{Placement, World, WorldSettings};

/// Errors in a scene file: the same shape as skeleton errors (line, field, message).
pub type SceneError = SkeletonError;

/// Where a model's skeleton comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum SkeletonSource {
    /// A skeleton file, relative to the scene file's folder.
    File(String),
    /// One of the shipped skeletons.
    Builtin(BuiltinSkeleton),
}

/// The targets a model holds for the whole run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Pose {
    /// Every actuator holds angle 0: the initial configuration (Fig. 6.4).
    Initial,
    /// No signals: every actuator limp (ODE-style brakes stay on).
    Limp,
    /// The named actuators hold these angles (rad), every other one 0.
    Angles(Vec<(String, f64)>),
}

/// One model of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Model", deny_unknown_fields)]
pub struct ModelEntry {
    pub skeleton: SkeletonSource,
    pub placement: Placement,
    /// Replaces the skeleton's own actuation settings.
    #[serde(default)]
    pub actuation: Option<Actuation>,
    pub pose: Pose,
}

/// A scene of articulated figures.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "BodyScene", deny_unknown_fields)]
pub struct BodyScene {
    pub name: String,
    /// Simulated time, seconds. Written `duration_s` as in every scene schema; the older `duration`
    /// still reads.
    #[serde(rename = "duration_s", alias = "duration")]
    pub duration: f64,
    /// Rendered frames per second, as every scene schema spells it (or the older `frame_interval`, in
    /// seconds between frames, which still reads: give one of the two; [`BodyScene::frame_interval_s`]).
    #[serde(default, with = "anima_format::optional_number", skip_serializing_if = "Option::is_none")]
    pub frame_rate_hz: Option<f64>,
    #[serde(default, with = "anima_format::optional_number", skip_serializing_if = "Option::is_none")]
    pub frame_interval: Option<f64>,
    pub world: WorldSettings,
    pub models: Vec<ModelEntry>,
}

/// Seconds between rendered frames from a scene's `frame_rate_hz` or its older `frame_interval`
/// (exactly one of them, positive and finite); otherwise the field to blame and why.
pub fn frame_interval_of(
    frame_rate_hz: Option<f64>,
    frame_interval: Option<f64>,
) -> Result<f64, (&'static str, String)> {
    let positive = |v: f64| v > 0.0 && v.is_finite();
    match (frame_rate_hz, frame_interval) {
        (Some(r), None) if positive(r) => Ok(1.0 / r),
        (Some(r), None) => {
            Err(("frame_rate_hz", format!("expected a positive number of frames a second, found {r}")))
        }
        (None, Some(i)) if positive(i) => Ok(i),
        (None, Some(i)) => {
            Err(("frame_interval", format!("expected a positive number of seconds, found {i}")))
        }
        (Some(_), Some(_)) => {
            Err(("frame_interval", "give frame_rate_hz or the older frame_interval, not both".to_owned()))
        }
        (None, None) => {
            Err(("frame_rate_hz", "expected the frames a second to render, frame_rate_hz".to_owned()))
        }
    }
}

impl BodyScene {
    /// Whether `text`'s top-level value is a `BodyScene(…)` (comments and blank space skipped).
    pub fn is_body_scene(text: &str) -> bool {
        anima_format::ron_text::struct_name(text) == Some("BodyScene")
    }

    /// Parses and checks a scene. Errors name the line and the field.
    pub fn from_ron_str(text: &str) -> Result<Self, SceneError> {
        let scene: BodyScene = ron::from_str(text).map_err(|e| SkeletonError::syntax(text, &e))?;
        scene.check().map_err(|e| e.locate(text))?;
        Ok(scene)
    }

    fn check(&self) -> Result<(), SceneError> {
        let bad = |f: &str, m: String| Err(SkeletonError::invalid(f, m));
        if let Err(e) = self.world.check() {
            return bad("world", e.to_string());
        }
        if !(self.duration > 0.0 && self.duration.is_finite()) {
            return bad(
                "duration_s",
                format!("expected a positive number of seconds, found {}", self.duration),
            );
        }
        if let Err((field, why)) = frame_interval_of(self.frame_rate_hz, self.frame_interval) {
            return bad(field, why);
        }
        if !(self.world.dt > 0.0 && self.world.dt.is_finite()) {
            return bad(
                "world.dt_s",
                format!("expected a positive number of seconds, found {}", self.world.dt),
            );
        }
        if self.world.substeps == 0 {
            return bad("world.substeps", "expected at least 1".into());
        }
        if self.models.is_empty() {
            return bad("models", "a scene needs at least one model".into());
        }
        Ok(())
    }

    /// Seconds between rendered frames; an error naming the field for a scene (built in code) that
    /// names neither, both, or a value that is not positive (a loaded scene was checked for this).
    pub fn frame_interval_s(&self) -> Result<f64, SkeletonError> {
        frame_interval_of(self.frame_rate_hz, self.frame_interval)
            .map_err(|(field, why)| SkeletonError::invalid(field, why))
    }

    /// Number of control steps: ⌈duration / Δt⌉ (rounded to the nearest step when within 1e-9).
    pub fn n_steps(&self) -> u64 {
        let r = self.duration / self.world.dt;
        let n = r.round();
        (if (r - n).abs() < 1e-9 { n } else { r.ceil() }) as u64
    }

    /// Builds the world with `skeletons[i]` for model i (the caller resolves [`SkeletonSource`]s; see
    /// [`BodyScene::builtin_skeleton`]) and sets each model's pose.
    pub fn build(&self, skeletons: &[Skeleton]) -> Result<World, BodyError> {
        if skeletons.len() != self.models.len() {
            return Err(BodyError::Layout {
                what: "skeleton list",
                expected: self.models.len(),
                found: skeletons.len(),
            });
        }
        let mut world = World::new(self.world)?;
        for (entry, sk) in self.models.iter().zip(skeletons) {
            let sk = match entry.actuation {
                Some(a) => sk.with_actuation(a)?,
                None => sk.clone(),
            };
            let model = world.add_model(&sk, entry.placement)?;
            let commands = world.commands_mut(model)?;
            commands.clear();
            match &entry.pose {
                Pose::Limp => {}
                Pose::Initial => commands.hold(&vec![0.0; sk.n_actuators()])?,
                Pose::Angles(named) => {
                    let mut angles = vec![0.0; sk.n_actuators()];
                    for (name, angle) in named {
                        let a = sk.actuator_index(name).ok_or_else(|| BodyError::NoSuchName {
                            model: sk.name().into(),
                            what: "actuator",
                            name: name.clone(),
                        })?;
                        angles[a] = *angle;
                    }
                    for (actuator, &angle) in angles.iter().enumerate() {
                        commands
                            .push(Signal {
                                actuator,
                                target: Target::Angle(angle),
                                frame: TargetFrame::Parent,
                                weight: 1.0,
                            })
                            .map_err(|e: CommandError| BodyError::from(e))?;
                    }
                }
            }
        }
        Ok(world)
    }

    /// The skeleton of a builtin source, `None` for a file.
    pub fn builtin_skeleton(source: &SkeletonSource) -> Option<Skeleton> {
        match source {
            SkeletonSource::Builtin(b) => Some(b.load()),
            SkeletonSource::File(_) => None,
        }
    }
}
