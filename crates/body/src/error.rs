//! Errors as values: what went wrong, and for a skeleton file, at which line and in which field.

/// What kind of problem a skeleton has: the shared kind of every located description error.
pub type SkeletonErrorKind = anima_format::FieldErrorKind;

/// A skeleton (or body scene) that could not be read or built: the field (`bodies[3].mass`), the line
/// and column when it came from text, and what is wrong. The same type as controller errors.
pub type SkeletonError = anima_format::FieldError;

/// A world or model operation that cannot be done.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BodyError {
    #[error(transparent)]
    Skeleton(#[from] SkeletonError),
    #[error("invalid world settings: {0}")]
    Settings(String),
    #[error("there is no model {0} in this world")]
    NoSuchModel(usize),
    #[error("model `{model}` has no {what} with index {index}")]
    NoSuchIndex { model: String, what: &'static str, index: usize },
    #[error("model `{model}` has no {what} named `{name}`")]
    NoSuchName { model: String, what: &'static str, name: String },
    #[error(
        "actuator commands of model `{model}` are full ({capacity} signals); \
         raise `max_signals_per_actuator` in the world settings"
    )]
    CommandsFull { model: String, capacity: usize },
    #[error("weld `{weld}` of model `{model}` was already released")]
    AlreadyReleased { model: String, weld: String },
    #[error("the {what} buffer was built for another model layout (expected {expected}, found {found})")]
    Layout { what: &'static str, expected: usize, found: usize },
    #[error(
        "the simulation diverged at step {step} (t = {time} s), model `{model}`, body `{body}` \
         (non-finite, faster than 1000 m/s or farther than 100 km); try a smaller step, more \
         sub-steps or another PD mode"
    )]
    NonFinite { step: u64, time: f64, model: String, body: String },
}
