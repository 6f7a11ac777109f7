//! Oliveira drape scenes: an [`OliveiraScene`] written in RON (the struct is the schema; unknown fields
//! are errors), plus the OBJ meshes its objects name, resolved relative to the scene file.

use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use anima_cloth::oliveira::{BuildError, OliveiraCloth, OliveiraScene, ShapeDesc};
use anima_geom::{ObjError, TriangleMesh, read_obj};

use crate::ParseError;
use anima_format::utf8;

/// The comment every written scene starts with.
const HEADER: &str = "// anima Oliveira 2013 drape. Units are SI (s, m, kg, N); z is up.\n";

/// A scene with its meshes loaded.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedOliveiraScene {
    pub scene: OliveiraScene,
    /// One mesh per `Mesh` object, in scene order, with the file name as the scene wrote it.
    pub meshes: Vec<(String, TriangleMesh)>,
    /// The scene file, as given to [`load`].
    pub path: PathBuf,
}

impl LoadedOliveiraScene {
    /// The cloth at rest among its objects.
    pub fn build(&self) -> Result<OliveiraCloth, BuildError> {
        OliveiraCloth::new(&self.scene, self.meshes.iter().map(|(_, m)| m.clone()).collect())
    }
}

/// Why an Oliveira scene could not be loaded. Every variant names the file at fault.
#[derive(Debug, thiserror::Error)]
pub enum OliveiraSceneError {
    #[error("could not read {}: {source}", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    /// A syntax or schema error; its `file` is set.
    #[error(transparent)]
    Parse(#[from] ParseError),
    #[error("{}:{source}", path.display())]
    Mesh {
        path: PathBuf,
        #[source]
        source: ObjError,
    },
}

/// Reads a scene from RON text. Errors carry the line and column, what was expected and what was found.
pub fn from_ron_str(src: &str) -> Result<OliveiraScene, ParseError> {
    anima_format::ron_text::from_str(src)
}

/// Writes a scene as pretty RON after a header comment; [`from_ron_str`] reads back the same scene.
pub fn to_ron_string(scene: &OliveiraScene) -> String {
    let body = ron::ser::to_string_pretty(scene, ron::ser::PrettyConfig::new())
        .expect("a scene is plain data, which RON can always represent");
    format!("{HEADER}{body}\n")
}

/// Loads a `.ron` Oliveira scene and every OBJ mesh it names.
pub fn load(path: &Path) -> Result<LoadedOliveiraScene, OliveiraSceneError> {
    let name = path.display().to_string();
    let bytes =
        fs::read(path).map_err(|source| OliveiraSceneError::Read { path: path.to_owned(), source })?;
    let src = utf8(&bytes).map_err(|e| e.with_file(&name))?;
    let scene = from_ron_str(src).map_err(|e| e.with_file(&name))?;
    let folder = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut meshes = Vec::new();
    for object in &scene.objects {
        if let ShapeDesc::Mesh { file, .. } = &object.shape {
            let mesh_path = folder.join(file);
            let data = fs::read(&mesh_path)
                .map_err(|source| OliveiraSceneError::Read { path: mesh_path.clone(), source })?;
            let mesh =
                read_obj(&data[..]).map_err(|source| OliveiraSceneError::Mesh { path: mesh_path, source })?;
            meshes.push((file.clone(), mesh));
        }
    }
    Ok(LoadedOliveiraScene { scene, meshes, path: path.to_owned() })
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"(
    duration_s: 0.1,
    gravity_m_s2: (0.0, 0.0, -9.81),
    cloth: (vertices_per_side: 3, size_m: 1.0, centre: OverHighestPoint,
            height: AboveObjects(clearance_m: 0.001), tracked_vertex: (0, 0)),
    material: (density_kg_m3: 8000.0, thickness_m: 1e-4, permeability: 3.0, young_modulus_pa: 1e7,
               cross_section_m2: 2.5e-6, damping_ratio: 0.01, bending_stiffness: 1e-3,
               bending_damping: 1e-4, friction: 0.4),
    time_step: Provot(beta: 0.008, startup_dt_s: Some(1e-4)),
    restitution: 0.5,
    objects: [(name: "ball", friction: 0.05, shape: Sphere(centre_m: (0.0, 0.0, 0.0), radius_m: 0.25))],
)"#;

    #[test]
    fn minimal_scene_reads_defaults_and_round_trips() {
        let scene = from_ron_str(MINIMAL).unwrap();
        assert_eq!(scene.integrator, anima_ode::Integrator::Rk4);
        assert_eq!(scene.options, anima_cloth::oliveira::Options::thesis());
        assert_eq!(from_ron_str(&to_ron_string(&scene)).unwrap(), scene);
    }

    #[test]
    fn schema_errors_point_at_line_and_column() {
        let bad = MINIMAL.replace("restitution: 0.5", "restitutoin: 0.5");
        let e = from_ron_str(&bad).unwrap_err();
        assert_eq!((e.line, e.found.as_str()), (10, "restitutoin"), "{e}");
        assert!(e.expected.contains("`restitution`"), "{e}");
        let bad = MINIMAL.replace("Sphere(", "Ball(");
        let e = from_ron_str(&bad).unwrap_err();
        assert_eq!(e.line, 11, "{e}");
        assert!(e.expected.contains("`Sphere`") && e.found == "Ball", "{e}");
        let bad = MINIMAL.replace("radius_m: 0.25", "radius_m: big");
        assert_eq!(from_ron_str(&bad).unwrap_err().line, 11);
    }
}
