//! Character scenes (`CharacterScene(…)`): articulated figures in a world, driven by a controller file
//! (Nunes 2006 §3.2). The scene names its skeletons and its controller; both are parts, read once with
//! the scene and checked before anything runs.

use anima_body::{Actuation, Placement, Skeleton, SkeletonSource, WorldSettings};
use anima_control::Controller;
use serde::{Deserialize, Serialize};

/// One model of a character scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "Model", deny_unknown_fields)]
pub struct CharacterModel {
    /// The prefix of the model's actuator names in the controller (`acrobat` for `acrobat/hip_l`);
    /// with a single model the controller may use the model's own names.
    pub alias: String,
    pub skeleton: SkeletonSource,
    pub placement: Placement,
    /// Replaces the skeleton's own actuation settings.
    #[serde(default)]
    pub actuation: Option<Actuation>,
}

/// What a run of the scene measures besides the figures' motion: one of the thesis's evaluations
/// (spec §7.6, Eq. 6.1, §8.4), or none.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum Evaluation {
    #[default]
    None,
    /// Distance walked and whether (and when) the walker fell.
    Walk,
    /// The ball's flight against the thesis's basket: through the hoop, distance, height.
    Throw,
    /// The backflip's turn, landing and whether the acrobat and the pusher stand.
    Backflip,
}

/// A scene of articulated figures driven by a controller.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "CharacterScene", deny_unknown_fields)]
pub struct CharacterScene {
    pub name: String,
    /// Simulated time, s. Written `duration_s` as in every scene schema; the older `duration` still
    /// reads.
    #[serde(rename = "duration_s", alias = "duration")]
    pub duration: f64,
    /// Rendered frames per second, as every scene schema spells it (or the older `frame_interval`, in
    /// seconds between frames, which still reads: give one of the two; [`CharacterScene::frame_interval_s`]).
    #[serde(default, with = "anima_format::optional_number", skip_serializing_if = "Option::is_none")]
    pub frame_rate_hz: Option<f64>,
    #[serde(default, with = "anima_format::optional_number", skip_serializing_if = "Option::is_none")]
    pub frame_interval: Option<f64>,
    pub world: WorldSettings,
    pub models: Vec<CharacterModel>,
    /// The controller file, relative to the scene file's folder.
    pub controller: String,
    #[serde(default)]
    pub evaluation: Evaluation,
}

impl CharacterScene {
    /// Seconds between rendered frames; an error naming the field for a scene (built in code) that
    /// names neither, both, or a value that is not positive (a loaded scene was checked for this).
    pub fn frame_interval_s(&self) -> Result<f64, anima_body::SkeletonError> {
        anima_body::scene::frame_interval_of(self.frame_rate_hz, self.frame_interval)
            .map_err(|(field, why)| anima_body::SkeletonError::invalid(field, why))
    }

    /// Control iterations in the run.
    pub fn n_steps(&self) -> u64 {
        (self.duration / self.world.dt).round() as u64
    }
}

/// A character scene with its skeletons and its controller (parsed with the character procedures).
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedCharacter {
    pub scene: CharacterScene,
    /// The skeleton of each entry of `scene.models`, with the entry's actuation applied.
    pub skeletons: Vec<Skeleton>,
    pub controller: Controller,
}
