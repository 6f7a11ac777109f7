//! anima's own scene files: a [`Flex3dScene`] written in RON.
//!
//! A `.PAR` script cannot say everything a run needs (gravity, the friction reading, the integrator,
//! the reconstruction switches of spec S7.2); a RON scene says all of it, field for field as
//! `anima_cloth::flex3d::Flex3dScene` declares it, so the struct is the schema. Unknown fields are
//! errors, not silently ignored: a misspelt option would otherwise fall back to its default unseen.

use anima_cloth::flex3d::Flex3dScene;

use crate::ParseError;

/// The comment every written scene starts with.
const HEADER: &str = "// anima FLEX3D scene (Nedel 1993). Units are SI (s, m, kg, N); y is up.\n";

/// Reads a scene. Errors carry ron's position and its reason split into expected and found.
pub fn from_ron_str(src: &str) -> Result<Flex3dScene, ParseError> {
    anima_format::ron_text::from_str(src)
}

/// Writes a scene as pretty RON after a header comment. Reals are printed in their shortest form that
/// reads back to the same bits, so [`from_ron_str`] returns exactly the scene written.
pub fn to_ron_string(scene: &Flex3dScene) -> String {
    let config = ron::ser::PrettyConfig::new();
    // The scene is plain data (numbers, strings, enums), which RON can always represent.
    let body = ron::ser::to_string_pretty(scene, config).expect("a scene always serialises to RON");
    format!("{HEADER}{body}\n")
}
