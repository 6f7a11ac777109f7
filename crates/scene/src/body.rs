//! Body scenes (`BodyScene(…)`): articulated figures holding poses, with the skeleton files they name.

use anima_body::{BodyScene, Skeleton};

/// A body scene with one checked skeleton per model.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedBody {
    pub scene: BodyScene,
    /// The skeleton of each entry of `scene.models`, in order.
    pub skeletons: Vec<Skeleton>,
}
