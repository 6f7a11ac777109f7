//! Errors as values: what went wrong, and for a skeleton file, at which line and in which field.

use std::fmt;

/// What kind of problem a skeleton has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SkeletonErrorKind {
    /// The text is not valid RON for the skeleton format (ron's own message).
    Syntax,
    /// The text parses but describes no valid skeleton (unknown name, negative mass, a cycle …).
    Invalid,
}

/// A skeleton that could not be read or built: the field (`bodies[3].mass`), the line when the
/// skeleton came from text, and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub struct SkeletonError {
    pub kind: SkeletonErrorKind,
    /// Path of the offending field: struct fields joined by `.`, list items as `[index]`.
    pub field: String,
    /// 1-based line in the skeleton text; `None` for a skeleton built in code.
    pub line: Option<usize>,
    /// 1-based column, when ron reported one.
    pub column: Option<usize>,
    pub message: String,
}

impl fmt::Display for SkeletonError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (self.line, self.column) {
            (Some(l), Some(c)) => write!(f, "line {l}, column {c}, ")?,
            (Some(l), None) => write!(f, "line {l}, ")?,
            _ => {}
        }
        if self.field.is_empty() {
            write!(f, "skeleton: {}", self.message)
        } else {
            write!(f, "field `{}`: {}", self.field, self.message)
        }
    }
}

impl SkeletonError {
    pub(crate) fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            kind: SkeletonErrorKind::Invalid,
            field: field.into(),
            line: None,
            column: None,
            message: message.into(),
        }
    }
}

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
