//! Oliveira drape scenes: an [`OliveiraScene`] written in RON (the struct is the schema; unknown fields
//! are errors), `OliveiraScene(…)` for a static mesh or `AdaptiveOliveiraScene(drape: …, remesher: …)`
//! for a remeshed one, plus the OBJ meshes its objects name, resolved relative to the scene file.

use anima_cloth::oliveira::{
    AdaptiveCloth, AdaptiveMethod, BuildError, OliveiraCloth, OliveiraRemeshing, OliveiraScene,
    ShortEdgeRule, SizingRemeshing, SubdivisionRemeshing,
};
use anima_geom::TriangleMesh;
use serde::{Deserialize, Serialize};

use crate::ParseError;

/// The comment every written scene starts with.
const HEADER: &str = "// anima Oliveira 2013 drape. Units are SI (s, m, kg, N); z is up.\n";

/// Which remesher an adaptive drape runs (Oliveira 2013 §4.5 and the baselines beside it), with the
/// parameters the thesis's tests fixed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Remesher {
    /// The thesis's remesher with the parameters of its Test `test` (1, 2 or 3; Tables 5.1, 5.3, 5.5),
    /// the short-edge rule of the retry loop (spec Q-9) and a pass every `interval_s` (0: after every
    /// step, as the thesis did).
    Oliveira { test: u8, short_edge: ShortEdgeRule, interval_s: f64 },
    /// Simnett's 1-to-4 subdivision with Table 5.5's parameters, a pass every `interval_s`.
    Subdivision { interval_s: f64 },
    /// A sizing-field remesher for a 1 m cloth (edges between `min_edge_m` and 25 cm), a pass every
    /// `interval_s`. `refuse_crossings` (true when left out) keeps the flips and collapses that would pass
    /// the cloth through itself from happening ([`SizingRemeshing::refuse_crossings`]); false lets them
    /// happen, to see what the guard prevents.
    SizingField {
        min_edge_m: f64,
        interval_s: f64,
        #[serde(default = "refuse_crossings_by_default", skip_serializing_if = "is_true")]
        refuse_crossings: bool,
    },
}

fn refuse_crossings_by_default() -> bool {
    true
}

fn is_true(b: &bool) -> bool {
    *b
}

impl Remesher {
    /// The cloth crate's remesher with these parameters; an error names what is out of range.
    pub fn method(&self) -> Result<AdaptiveMethod, String> {
        let interval = |i: f64| {
            if i >= 0.0 && i.is_finite() {
                Ok(i)
            } else {
                Err(format!("expected a pass interval ≥ 0 s, found {i}"))
            }
        };
        Ok(match *self {
            Remesher::Oliveira { test, short_edge, interval_s } => {
                let base = match test {
                    1 => OliveiraRemeshing::test_1(),
                    2 => OliveiraRemeshing::test_2(),
                    3 => OliveiraRemeshing::test_3(),
                    other => return Err(format!("expected the thesis's test 1, 2 or 3, found {other}")),
                };
                AdaptiveMethod::Oliveira(OliveiraRemeshing {
                    short_edge,
                    interval_s: interval(interval_s)?,
                    ..base
                })
            }
            Remesher::Subdivision { interval_s } => AdaptiveMethod::Subdivision(SubdivisionRemeshing {
                interval_s: interval(interval_s)?,
                ..SubdivisionRemeshing::test_3()
            }),
            Remesher::SizingField { min_edge_m, interval_s, refuse_crossings } => {
                if !(min_edge_m > 0.0 && min_edge_m < 0.25) {
                    return Err(format!("expected a shortest edge between 0 and 0.25 m, found {min_edge_m}"));
                }
                AdaptiveMethod::SizingField(SizingRemeshing {
                    interval_s: interval(interval_s)?,
                    refuse_crossings,
                    ..SizingRemeshing::for_cloth(min_edge_m)
                })
            }
        })
    }
}

/// A drape on a remeshed cloth: the static scene and the remesher.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename = "AdaptiveOliveiraScene", deny_unknown_fields)]
pub struct AdaptiveOliveiraScene {
    pub drape: OliveiraScene,
    pub remesher: Remesher,
}

/// A drape with its meshes loaded.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedOliveira {
    pub scene: OliveiraScene,
    /// One mesh per `Mesh` object, in scene order, with the file name as the scene wrote it.
    pub meshes: Vec<(String, TriangleMesh)>,
    /// The remesher of an adaptive scene; `None` for a static mesh.
    pub remesher: Option<Remesher>,
}

impl LoadedOliveira {
    /// The cloth at rest among its objects.
    pub fn build(&self) -> Result<OliveiraCloth, BuildError> {
        OliveiraCloth::new(&self.scene, self.meshes.iter().map(|(_, m)| m.clone()).collect())
    }

    /// The step the scene's rule gives `cloth` (built from this scene) at rest: the fixed step, or the
    /// smaller of the start-up step and β·π·√(m_min/k_max) (Eq. 4.6). A remesher may make it smaller as
    /// the run goes; it is a lower bound on the steps a run of the scene takes.
    pub fn step_estimate(&self, cloth: &OliveiraCloth) -> f64 {
        use anima_cloth::oliveira::StepRule;
        match self.scene.time_step {
            StepRule::Fixed { dt_s } => dt_s,
            StepRule::Provot { beta, startup_dt_s } => {
                let rule = beta * std::f64::consts::PI * (cloth.min_mass() / cloth.max_stiffness()).sqrt();
                startup_dt_s.map_or(rule, |s| s.min(rule))
            }
        }
    }

    /// The scene's remesher as the cloth crate takes it (`Static` for a static scene).
    pub fn method(&self) -> AdaptiveMethod {
        match &self.remesher {
            // Checked when the scene was loaded.
            Some(r) => r.method().unwrap_or(AdaptiveMethod::Static),
            None => AdaptiveMethod::Static,
        }
    }

    /// `cloth` (built by [`LoadedOliveira::build`], perhaps changed since) with the scene's remesher:
    /// what a run steps.
    pub fn with_remesher(&self, cloth: OliveiraCloth) -> AdaptiveCloth {
        AdaptiveCloth::new(cloth, self.scene.gravity_m_s2, self.method())
    }
}

/// Contact inside the solve needs generalised-α (the one integrator that constrains contacts in its
/// Newton solve): `Err` says so when the scene asks for it with another.
pub fn check_contact(scene: &OliveiraScene) -> Result<(), String> {
    use anima_cloth::contact_mode::ContactMode;
    if scene.options.contact == ContactMode::InSolve
        && scene.integrator != anima_ode::Integrator::GeneralizedAlpha
    {
        return Err(format!(
            "expected generalized-alpha for contact in the solve (options.contact: InSolve), found {}",
            scene.integrator
        ));
    }
    Ok(())
}

/// Reads a static scene from RON text. Errors carry the line and column, what was expected and what
/// was found.
pub fn from_ron_str(src: &str) -> Result<OliveiraScene, ParseError> {
    anima_format::ron_text::from_str(src)
}

/// Reads an adaptive scene from RON text.
pub fn adaptive_from_ron_str(src: &str) -> Result<AdaptiveOliveiraScene, ParseError> {
    anima_format::ron_text::from_str(src)
}

/// Writes a static scene as pretty RON, `OliveiraScene(…)`, after a header comment; [`from_ron_str`]
/// reads back the same scene.
pub fn to_ron_string(scene: &OliveiraScene) -> String {
    let body = ron::ser::to_string_pretty(scene, ron::ser::PrettyConfig::new())
        .expect("a scene is plain data, which RON can always represent");
    format!("{HEADER}OliveiraScene{body}\n")
}

/// Writes an adaptive scene as pretty RON after a header comment.
pub fn adaptive_to_ron_string(scene: &AdaptiveOliveiraScene) -> String {
    let body = ron::ser::to_string_pretty(scene, ron::ser::PrettyConfig::new())
        .expect("a scene is plain data, which RON can always represent");
    format!("{HEADER}AdaptiveOliveiraScene{body}\n")
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
        let text = to_ron_string(&scene);
        assert_eq!(anima_format::ron_text::struct_name(&text), Some("OliveiraScene"));
        assert_eq!(from_ron_str(&text).unwrap(), scene);
    }

    #[test]
    fn adaptive_scenes_round_trip_and_check_their_remesher() {
        let drape = from_ron_str(MINIMAL).unwrap();
        let scene = AdaptiveOliveiraScene {
            drape,
            remesher: Remesher::Oliveira { test: 1, short_edge: ShortEdgeRule::MinLength, interval_s: 1e-3 },
        };
        let text = adaptive_to_ron_string(&scene);
        assert_eq!(anima_format::ron_text::struct_name(&text), Some("AdaptiveOliveiraScene"));
        assert_eq!(adaptive_from_ron_str(&text).unwrap(), scene);
        let AdaptiveMethod::Oliveira(p) = scene.remesher.method().unwrap() else {
            panic!("the thesis's remesher")
        };
        assert_eq!((p.short_edge, p.interval_s), (ShortEdgeRule::MinLength, 1e-3));
        assert_eq!(p.min_rest_length, OliveiraRemeshing::test_1().min_rest_length);
        let bad = Remesher::Oliveira { test: 4, short_edge: ShortEdgeRule::MinLength, interval_s: 0.0 };
        assert!(bad.method().unwrap_err().contains("test 1, 2 or 3"));
        assert!(
            Remesher::SizingField { min_edge_m: 0.0, interval_s: 0.1, refuse_crossings: true }
                .method()
                .is_err()
        );
        assert!(Remesher::Subdivision { interval_s: -1.0 }.method().is_err());
    }

    #[test]
    fn a_sizing_field_scene_refuses_crossings_unless_it_says_not_to() {
        let refuses = |remesher: &str| {
            let text = format!("AdaptiveOliveiraScene(drape: {MINIMAL}, remesher: {remesher})");
            let scene = adaptive_from_ron_str(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
            let AdaptiveMethod::SizingField(p) = scene.remesher.method().unwrap() else {
                panic!("sizing field")
            };
            let again = adaptive_from_ron_str(&adaptive_to_ron_string(&scene)).unwrap();
            assert_eq!(again, scene, "round trip");
            p.refuse_crossings
        };
        assert!(refuses("SizingField(min_edge_m: 0.03, interval_s: 0.01)"));
        assert!(refuses("SizingField(min_edge_m: 0.03, interval_s: 0.01, refuse_crossings: true)"));
        assert!(!refuses("SizingField(min_edge_m: 0.03, interval_s: 0.01, refuse_crossings: false)"));
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
