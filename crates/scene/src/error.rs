//! The one error of every scene reader: which file, where in it, and what was wrong.

use std::io;
use std::path::PathBuf;

use anima_format::{FieldError, ParseError};
use anima_geom::obt::ObtError;
use anima_geom::{MeshError, ObjError};

/// Why a scene (or a file it names) could not be loaded. Every variant names the file at fault.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("could not read {}: {source}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// A syntax or schema error; its `file` is set.
    #[error(transparent)]
    Parse(#[from] ParseError),
    /// A skeleton, body scene or controller that parses but describes nothing valid (or does not
    /// parse: these formats report ron's errors by field path).
    #[error("{}: {source}", path.display())]
    Description {
        path: PathBuf,
        #[source]
        source: FieldError,
    },
    #[error("{}: {why}", path.display())]
    Kind { path: PathBuf, why: String },
    #[error("{}: {what} `{name}` not found in {}", scene.display(), folder.display())]
    PartNotFound { scene: PathBuf, what: &'static str, name: String, folder: PathBuf },
    #[error("{}:{source}", path.display())]
    Obt {
        path: PathBuf,
        #[source]
        source: ObtError,
    },
    #[error("{}:{source}", path.display())]
    Obj {
        path: PathBuf,
        #[source]
        source: ObjError,
    },
    #[error("{}: {source}", path.display())]
    Mesh {
        path: PathBuf,
        #[source]
        source: MeshError,
    },
    /// A value the format accepts but a run cannot use (a controller that names no actuator of the
    /// scene's models, say).
    #[error("{}: {why}", path.display())]
    Invalid { path: PathBuf, why: String },
}

impl SceneError {
    /// A read error of `path`.
    pub(crate) fn read(path: impl Into<PathBuf>) -> impl FnOnce(io::Error) -> SceneError {
        let path = path.into();
        move |source| SceneError::Read { path, source }
    }
}
