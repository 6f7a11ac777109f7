//! FLEX3D scenes in RON: a [`Flex3dScene`] field for field, so the struct is the schema.
//!
//! A `.PAR` script cannot say everything a run needs (gravity, the friction reading, the integrator,
//! the reconstruction switches of spec S7.2); a RON scene says all of it. Unknown fields are errors, not
//! silently ignored: a misspelt option would otherwise fall back to its default unseen. Written scenes
//! start with the struct name, `Flex3dScene(`, which is how [`crate::load`] tells their kind; files
//! without a name are read as FLEX3D scenes when their fields say so (the form older versions wrote).

use anima_cloth::flex3d::Flex3dScene;
use anima_geom::{DVec3, TriangleMesh};

use crate::{ParseError, par};

/// The comment every written scene starts with.
const HEADER: &str = "// anima FLEX3D scene (Nedel 1993). Units are SI (s, m, kg, N); y is up.\n";

/// A FLEX3D scene with its static objects loaded.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedFlex3d {
    pub scene: Flex3dScene,
    /// One mesh per name in `scene.objects`, in that order, paired with the name as the scene wrote it.
    pub objects: Vec<(String, TriangleMesh)>,
}

impl LoadedFlex3d {
    /// The objects' meshes, in scene order (what `Flex3dWorld::new` takes).
    pub fn meshes(&self) -> Vec<TriangleMesh> {
        self.objects.iter().map(|(_, m)| m.clone()).collect()
    }
}

/// Reads a scene. Errors carry ron's position and its reason split into expected and found.
pub fn from_ron_str(src: &str) -> Result<Flex3dScene, ParseError> {
    anima_format::ron_text::from_str(src)
}

/// Writes a scene as pretty RON after a header comment, named `Flex3dScene(…)`. Reals are printed in
/// their shortest form that reads back to the same bits, so [`from_ron_str`] returns exactly the scene
/// written.
pub fn to_ron_string(scene: &Flex3dScene) -> String {
    // The scene is plain data (numbers, strings, enums), which RON can always represent.
    let body = ron::ser::to_string_pretty(scene, ron::ser::PrettyConfig::new())
        .expect("a scene always serialises to RON");
    format!("{HEADER}Flex3dScene{body}\n")
}

/// Converts a `.PAR` script to an equivalent RON scene. `gravity` applies when the script has no
/// `GRAVIDADE` (see [`par::ParScript::to_scene`]); `file_name` goes into errors.
pub fn convert_par_to_ron(src_bytes: &[u8], file_name: &str, gravity: DVec3) -> Result<String, ParseError> {
    let script = par::parse(src_bytes).map_err(|e| e.with_file(file_name))?;
    Ok(to_ron_string(&script.to_scene(gravity)))
}
