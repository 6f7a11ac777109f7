//! FLEX3D scenes in RON: a [`Flex3dScene`] field for field, so the struct is the schema.
//!
//! A `.PAR` script cannot say everything a run needs (gravity, the friction reading, the integrator,
//! the reconstruction switches of spec S7.2); a RON scene says all of it. Unknown fields are errors, not
//! silently ignored: a misspelt option would otherwise fall back to its default unseen. Written scenes
//! start with the struct name, `Flex3dScene(`, which is how [`crate::load`] tells their kind; files
//! without a name are read as FLEX3D scenes when their fields say so (the form older versions wrote).

use anima_cloth::flex3d::Flex3dScene;
use anima_format::FieldError;
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

/// What a FLEX3D run needs that the RON format cannot say, checked with the field at fault: positive
/// and finite times, sizes and masses, non-negative finite stiffnesses and friction, plain surface names
/// that no two surfaces share (they name the frame files), pins inside their grid, and a scene of at
/// most [`crate::limits::MAX_PARTICLES`] particles and [`crate::limits::MAX_STEPS`] steps. A `.PAR`
/// script is checked the same way by its parser, at the token.
pub fn check(scene: &Flex3dScene) -> Result<(), FieldError> {
    let bad = |field: String, why: String| Err(FieldError::invalid(field, why));
    if let Err(why) = anima_cloth::check_fixed_step_integrator(scene.integrator) {
        return bad("integrator".into(), why);
    }
    let positive = |field: &str, v: f64| {
        if v > 0.0 && v.is_finite() {
            Ok(())
        } else {
            bad(field.into(), format!("expected a positive number, found {v}"))
        }
    };
    let non_negative = |field: String, v: f64| {
        if v >= 0.0 && v.is_finite() {
            Ok(())
        } else {
            bad(field, format!("expected a finite number ≥ 0, found {v}"))
        }
    };
    let finite = |field: &str, v: DVec3| {
        if v.is_finite() { Ok(()) } else { bad(field.into(), format!("expected finite numbers, found {v}")) }
    };
    positive("duration_s", scene.duration_s)?;
    positive("frame_rate_hz", scene.frame_rate_hz)?;
    positive("dt_s", scene.dt_s)?;
    if let Some(why) =
        crate::limits::run_length_problem(scene.duration_s, scene.dt_s, Some(scene.frame_rate_hz))
    {
        return bad("dt_s".into(), format!("expected {why}"));
    }
    if scene.options.object_contact == anima_cloth::contact_mode::ContactMode::InSolve
        && scene.integrator != anima_ode::Integrator::GeneralizedAlpha
    {
        return bad(
            "options.object_contact".into(),
            format!("expected generalized-alpha for contact in the solve, found {}", scene.integrator),
        );
    }
    finite("gravity_m_s2", scene.gravity_m_s2)?;
    finite("external_force_n", scene.external_force_n)?;
    non_negative("friction.coefficient".into(), scene.friction.coefficient)?;
    if scene.surfaces.is_empty() {
        return bad("surfaces".into(), "expected at least one surface".into());
    }
    let mut particles = 0usize;
    for (k, s) in scene.surfaces.iter().enumerate() {
        let field = |f: &str| format!("surfaces[{k}].{f}");
        if let Some(why) = anima_format::not_a_plain_name(&s.name) {
            return bad(field("name"), format!("expected {why}, found `{}`", s.name));
        }
        if let Some(first) = scene.surfaces[..k].iter().position(|o| o.name == s.name) {
            return bad(
                field("name"),
                format!("expected a name no other surface has (surfaces[{first}] is `{}` too)", s.name),
            );
        }
        if s.rows < 2 || s.cols < 2 {
            return bad(
                field("rows"),
                format!("expected at least 2 rows and 2 columns, found {} × {}", s.rows, s.cols),
            );
        }
        let max = crate::limits::MAX_PARTICLES;
        particles =
            match s.rows.checked_mul(s.cols).and_then(|n| n.checked_add(particles)).filter(|&n| n <= max) {
                Some(n) => n,
                None => {
                    return bad(
                        field("rows"),
                        format!(
                            "expected at most {max} particles in all, found {} × {} here",
                            s.rows, s.cols
                        ),
                    );
                }
            };
        positive(&field("spacing_m"), s.spacing_m)?;
        positive(&field("particle_mass_kg"), s.particle_mass_kg)?;
        finite(&field("centre_m"), s.centre_m)?;
        if !(s.normal.is_finite() && s.normal != DVec3::ZERO) {
            return bad(field("normal"), format!("expected a finite non-zero vector, found {}", s.normal));
        }
        for c in 0..3 {
            non_negative(format!("surfaces[{k}].stiffness_n_m[{c}]"), s.stiffness_n_m[c])?;
            non_negative(format!("surfaces[{k}].bending_n_m[{c}]"), s.bending_n_m[c])?;
        }
        if let Some(p) = s.fixed.iter().position(|&(i, j)| i >= s.rows || j >= s.cols) {
            let (i, j) = s.fixed[p];
            return bad(
                format!("surfaces[{k}].fixed[{p}]"),
                format!("expected a particle of the {} × {} grid, found ({i}, {j})", s.rows, s.cols),
            );
        }
        for (p, t) in s.translations.iter().enumerate() {
            if !(t.per_frame_m.is_finite()
                && t.start_s.is_finite()
                && t.end_s.is_finite()
                && t.start_s <= t.end_s)
            {
                return bad(
                    format!("surfaces[{k}].translations[{p}]"),
                    "expected a finite motion over a window with start_s ≤ end_s".into(),
                );
            }
        }
    }
    Ok(())
}
