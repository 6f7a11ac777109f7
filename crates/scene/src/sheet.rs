//! Sheet scenes: a spring-network sheet (`anima_cloth::spring_net::SheetSpec`) with its run settings, in
//! RON. The file starts with the struct name, `SheetScene(`, which is how `anima run` tells it from a
//! FLEX3D scene.

use anima_cloth::spring_net::SheetSpec;
use anima_ode::Integrator;
use serde::{Deserialize, Serialize};

use crate::ParseError;

/// A sheet and how to run it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SheetScene {
    pub sheet: SheetSpec,
    /// Simulated time, s.
    pub duration_s: f64,
    /// Integration step, s (the first step for the adaptive methods).
    pub dt_s: f64,
    /// Frames written per second.
    pub frame_rate_hz: f64,
    pub integrator: Integrator,
}

impl SheetScene {
    /// The standard sheet of `benchmarks.md` at its common step (2·10⁻⁴ s for N = 32, 10⁻⁴ s for N = 64).
    pub fn standard(n: usize) -> Self {
        Self {
            sheet: SheetSpec::standard(n),
            duration_s: 1.0,
            dt_s: if n <= 32 { 2e-4 } else { 1e-4 },
            frame_rate_hz: 30.0,
            integrator: Integrator::SymplecticEuler,
        }
    }
}

impl SheetScene {
    /// What a run needs that the format cannot say: positive, finite times and a sheet that is one.
    /// The error names the field (placed at its line by the loader).
    pub fn check(&self) -> Result<(), anima_format::FieldError> {
        let bad = |field: &str, expected: &str, v: f64| {
            Err(anima_format::FieldError::invalid(field, format!("expected {expected}, found {v}")))
        };
        for (field, v) in
            [("duration_s", self.duration_s), ("dt_s", self.dt_s), ("frame_rate_hz", self.frame_rate_hz)]
        {
            if !(v > 0.0 && v.is_finite()) {
                return bad(field, "a positive number", v);
            }
        }
        if self.sheet.n < 2 {
            return bad("sheet.n", "at least 2 particles per side", self.sheet.n as f64);
        }
        Ok(())
    }
}

/// Reads a sheet scene; errors name line and column.
pub fn from_ron_str(src: &str) -> Result<SheetScene, ParseError> {
    anima_format::ron_text::from_str(src)
}

/// Writes a sheet scene as pretty RON, with its struct name so that its kind is recognisable.
pub fn to_ron_string(scene: &SheetScene) -> String {
    let config = ron::ser::PrettyConfig::new().struct_names(true);
    let body = ron::ser::to_string_pretty(scene, config).expect("a sheet scene always serialises to RON");
    format!("// anima sheet scene. Units are SI (s, m, kg, N); z is up.\n{body}\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_errors() {
        let s = SheetScene::standard(32);
        let text = to_ron_string(&s);
        assert!(text.contains("SheetScene("), "{text}");
        assert_eq!(from_ron_str(&text).unwrap(), s);
        let bad = text.replace("damping_n_s_m", "damping");
        let e = from_ron_str(&bad).unwrap_err();
        assert!(e.found == "damping" && e.line > 1, "{e}");
    }
}

#[cfg(test)]
mod asset_tests {
    use super::*;

    #[test]
    fn the_standard_sheet_assets_are_the_definition() {
        for n in [32, 64] {
            let path = format!("{}/../../assets/scenes/standard-sheet-{n}.ron", env!("CARGO_MANIFEST_DIR"));
            let src = std::fs::read_to_string(&path).unwrap();
            assert_eq!(from_ron_str(&src).unwrap(), SheetScene::standard(n), "{path}");
        }
    }
}
