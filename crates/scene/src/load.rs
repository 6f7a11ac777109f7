//! Loading a scene file and the objects it names.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use anima_cloth::flex3d::{FLEX3D_GRAVITY, Flex3dScene};
use anima_geom::obt::{IndexBase, ObtError, read_obt};
use anima_geom::{DVec3, MeshError, TriangleMesh};

use anima_format::utf8;

use crate::{ParseError, par, ron_scene};

/// Choices the caller makes over the file.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoadOptions {
    /// Gravity for the run, m/s². When given it replaces whatever the file says (a `.PAR` script's
    /// `GRAVIDADE`, a RON scene's `gravity_m_s2`): spec S3.1 lets the command line override the keyword.
    /// When `None`, a `.PAR` script without `GRAVIDADE` gets [`FLEX3D_GRAVITY`], "on" (spec S3.1).
    pub gravity: Option<DVec3>,
}

/// A scene with its static objects loaded.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedScene {
    pub scene: Flex3dScene,
    /// One mesh per name in `scene.objects`, in that order, paired with the name as the scene wrote it.
    pub objects: Vec<(String, TriangleMesh)>,
    /// The scene file, as given to [`load`]; output and object paths are relative to its folder.
    pub path: PathBuf,
}

/// Why a scene could not be loaded. Every variant names the file at fault.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("could not read {}: {source}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// A syntax or validation error; its `file` is set.
    #[error(transparent)]
    Parse(#[from] ParseError),
    #[error("{}: expected a scene file ending in .par or .ron", path.display())]
    UnknownExtension { path: PathBuf },
    #[error("{}: object file `{name}` not found in {} (tried the exact name, then ignoring case)", scene.display(), folder.display())]
    ObjectNotFound { scene: PathBuf, name: String, folder: PathBuf },
    #[error("{}:{source}", path.display())]
    Object {
        path: PathBuf,
        #[source]
        source: ObtError,
    },
    #[error("{}: {source}", path.display())]
    ObjectMesh {
        path: PathBuf,
        #[source]
        source: MeshError,
    },
}

/// Loads a `.par`/`.PAR` script or a `.ron` scene (by extension, any case) and every `.OBT` object it
/// names, resolved relative to the scene file's folder.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<LoadedScene, SceneError> {
    let file_name = path.display().to_string();
    let bytes = fs::read(path).map_err(|source| SceneError::Read { path: path.to_owned(), source })?;
    let extension = path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
    let mut scene = match extension.as_str() {
        "par" => par::parse(&bytes).map_err(|e| e.with_file(&file_name))?.to_scene(FLEX3D_GRAVITY),
        "ron" => ron_scene::from_ron_str(utf8(&bytes).map_err(|e| e.with_file(&file_name))?)
            .map_err(|e| e.with_file(&file_name))?,
        _ => return Err(SceneError::UnknownExtension { path: path.to_owned() }),
    };
    if let Some(g) = opts.gravity {
        scene.gravity_m_s2 = g;
    }

    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let objects = scene
        .objects
        .iter()
        .map(|name| {
            let obt = resolve(folder, name).ok_or_else(|| SceneError::ObjectNotFound {
                scene: path.to_owned(),
                name: name.clone(),
                folder: folder.to_owned(),
            })?;
            let bytes = fs::read(&obt).map_err(|source| SceneError::Read { path: obt.clone(), source })?;
            let object = read_obt(&bytes[..], IndexBase::Auto)
                .map_err(|source| SceneError::Object { path: obt.clone(), source })?;
            let mesh =
                object.to_mesh().map_err(|source| SceneError::ObjectMesh { path: obt.clone(), source })?;
            Ok((name.clone(), mesh))
        })
        .collect::<Result<_, SceneError>>()?;

    Ok(LoadedScene { scene, objects, path: path.to_owned() })
}

/// Converts a `.PAR` script to an equivalent RON scene. `gravity` applies when the script has no
/// `GRAVIDADE` (see [`par::ParScript::to_scene`]); `file_name` goes into errors.
pub fn convert_par_to_ron(src_bytes: &[u8], file_name: &str, gravity: DVec3) -> Result<String, ParseError> {
    let script = par::parse(src_bytes).map_err(|e| e.with_file(file_name))?;
    Ok(ron_scene::to_ron_string(&script.to_scene(gravity)))
}

/// The exact name first, then a case-insensitive match in the same folder (spec S2.5: A2.8 writes
/// `mesa.obt` while the format's extension is `.OBT`). Several case-insensitive matches: the first in
/// byte order, so the choice does not depend on the file system's listing order.
fn resolve(folder: &Path, name: &str) -> Option<PathBuf> {
    let exact = folder.join(name);
    if exact.is_file() {
        return Some(exact);
    }
    let wanted = exact.file_name()?.to_str()?.to_lowercase();
    let mut found: Vec<PathBuf> = fs::read_dir(exact.parent()?)
        .ok()?
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_str().is_some_and(|n| n.to_lowercase() == wanted))
        .map(|e| e.path())
        .filter(|p| p.is_file())
        .collect();
    found.sort();
    found.into_iter().next()
}
