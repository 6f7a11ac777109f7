//! Sheet scenes: a spring-network sheet (`anima_cloth::spring_net::SheetSpec`) with its run settings, in
//! RON. The file starts with the struct name, `SheetScene(`, which is how `anima run` tells it from a
//! FLEX3D scene.

use anima_cloth::membrane::MembraneMaterial;
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
    /// The cloth model: the sheet's springs (`Springs`, the default when the field is left out) or the
    /// continuum membrane of `anima_cloth::membrane` (`Membrane((young_thickness_n_m: …, poisson: …,
    /// bending_n_m: …, damping_s: …))`), whose refinement converges; with it the sheet's stiffnesses
    /// and damping are unused.
    #[serde(default)]
    pub model: SheetModel,
}

/// The cloth model of a sheet scene.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub enum SheetModel {
    /// The sheet's structural, shear and bend springs.
    #[default]
    Springs,
    /// Co-rotational constant-strain triangles and quadratic bending in this material.
    Membrane(MembraneMaterial),
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
            model: SheetModel::Springs,
        }
    }
}

impl SheetScene {
    /// What a run needs that the format cannot say: positive, finite times and a run of at most
    /// [`crate::limits::MAX_STEPS`] steps; a sheet of 2 to √[`crate::limits::MAX_PARTICLES`] particles a
    /// side with a positive size and mass, finite non-negative stiffnesses and damping, pins inside the
    /// grid. The error names the field (placed at its line by the loader).
    pub fn check(&self) -> Result<(), anima_format::FieldError> {
        let bad = |field: String, why: String| Err(anima_format::FieldError::invalid(field, why));
        for (field, v) in
            [("duration_s", self.duration_s), ("dt_s", self.dt_s), ("frame_rate_hz", self.frame_rate_hz)]
        {
            if !(v > 0.0 && v.is_finite()) {
                return bad(field.into(), format!("expected a positive number, found {v}"));
            }
        }
        if let Some(why) =
            crate::limits::run_length_problem(self.duration_s, self.dt_s, Some(self.frame_rate_hz))
        {
            return bad("dt_s".into(), format!("expected {why}"));
        }
        let sheet = &self.sheet;
        let max_side = crate::limits::MAX_PARTICLES.isqrt();
        if !(2..=max_side).contains(&sheet.n) {
            return bad(
                "sheet.n".into(),
                format!("expected 2 to {max_side} particles a side, found {}", sheet.n),
            );
        }
        for (field, v) in [("sheet.size_m", sheet.size), ("sheet.total_mass_kg", sheet.total_mass)] {
            if !(v > 0.0 && v.is_finite()) {
                return bad(field.into(), format!("expected a positive number, found {v}"));
            }
        }
        let non_negative = [("sheet.damping_n_s_m".to_owned(), sheet.damping)]
            .into_iter()
            .chain((0..3).map(|c| (format!("sheet.stiffness_n_m[{c}]"), sheet.stiffness[c])));
        for (field, v) in non_negative {
            if !(v >= 0.0 && v.is_finite()) {
                return bad(field, format!("expected a finite number ≥ 0, found {v}"));
            }
        }
        if !(sheet.height.is_finite() && sheet.gravity.is_finite()) {
            return bad("sheet.height_m".into(), "expected a finite height and gravity".into());
        }
        if let SheetModel::Membrane(m) = self.model {
            let fields = [
                ("model.young_thickness_n_m", m.young_thickness),
                ("model.bending_n_m", m.bending),
                ("model.damping_s", m.damping),
            ];
            for (field, v) in fields {
                if !(v >= 0.0 && v.is_finite()) {
                    return bad(field.into(), format!("expected a finite number ≥ 0, found {v}"));
                }
            }
            if !(0.0..0.5).contains(&m.poisson) {
                return bad(
                    "model.poisson".into(),
                    format!("expected a number in [0, 0.5), found {}", m.poisson),
                );
            }
        }
        if let Some(p) = sheet.pinned.iter().position(|&(i, j)| i >= sheet.n || j >= sheet.n) {
            let (i, j) = sheet.pinned[p];
            return bad(
                format!("sheet.pinned[{p}]"),
                format!(
                    "expected a particle (i, j) of the {n} × {n} sheet, 0 ≤ i, j < {n}, found ({i}, {j})",
                    n = sheet.n
                ),
            );
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

    #[test]
    fn a_membrane_sheet_round_trips_and_its_material_is_checked() {
        let s = SheetScene {
            model: SheetModel::Membrane(MembraneMaterial::STANDARD),
            ..SheetScene::standard(16)
        };
        let text = to_ron_string(&s);
        assert!(text.contains("Membrane("), "{text}");
        assert_eq!(from_ron_str(&text).unwrap(), s);
        assert!(s.check().is_ok());
        let bad = SheetScene {
            model: SheetModel::Membrane(MembraneMaterial { poisson: 0.7, ..MembraneMaterial::STANDARD }),
            ..s.clone()
        };
        assert!(bad.check().unwrap_err().to_string().contains("model.poisson"));
        let bad = SheetScene {
            model: SheetModel::Membrane(MembraneMaterial { bending: f64::NAN, ..MembraneMaterial::STANDARD }),
            ..s
        };
        assert!(bad.check().unwrap_err().to_string().contains("model.bending_n_m"));
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
