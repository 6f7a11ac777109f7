//! The thesis's scripts, the loader, and the errors a malformed scene must produce.

use std::fs;
use std::path::{Path, PathBuf};

use anima_cloth::flex3d::{FrictionMode, ModelOptions, Translation};
use anima_geom::DVec3;
use anima_ode::Integrator;
use anima_scene::flex3d::{from_ron_str, to_ron_string};
use anima_scene::par::{self, Curvature, ParScript};
use anima_scene::{
    END_OF_FILE, FLEX3D_GRAVITY, LoadOptions, ParseError, SceneError, convert_par_to_ron, load_flex3d,
};

/// A2.2, the wind scene: short, and it has every part of a surface block.
const WIND: &str = include_str!("../../../assets/flex3d/a2-2-vento.par");

const THESIS_SCRIPTS: [&str; 6] = [
    "fig6-2-cortina.par",
    "fig6-4-papel.par",
    "a2-2-vento.par",
    "a2-4-cortinas.par",
    "a2-6-papelao.par",
    "a2-8-toalha.par",
];

/// The 22 pinned points of the paper scenes (Figs. 6.4 and A2.6).
const PAPER_FIXED: [(usize, usize); 22] = [
    (9, 0),
    (9, 1),
    (9, 2),
    (9, 3),
    (9, 4),
    (9, 5),
    (9, 6),
    (9, 7),
    (9, 8),
    (9, 9),
    (8, 3),
    (8, 4),
    (8, 5),
    (8, 6),
    (8, 7),
    (8, 8),
    (8, 9),
    (7, 6),
    (7, 7),
    (7, 8),
    (7, 9),
    (6, 9),
];

fn asset(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/flex3d").join(name)
}

fn parse_asset(name: &str) -> ParScript {
    let bytes = fs::read(asset(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
    par::parse(&bytes).unwrap_or_else(|e| panic!("{}", e.with_file(name)))
}

/// A fresh, empty folder for one test.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("anima-scene-{}-{test}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

/// Parses `WIND` with `from` replaced by `to` (which must occur) and returns the error.
fn wind_error(from: &str, to: &str) -> ParseError {
    assert!(WIND.contains(from), "{from:?} is not in the wind script");
    match par::parse_str(&WIND.replacen(from, to, 1)) {
        Ok(_) => panic!("replacing {from:?} by {to:?} still parses"),
        Err(e) => e,
    }
}

#[track_caller]
fn assert_error(e: &ParseError, line: usize, column: usize, expected: &str, found: &str) {
    assert_eq!((e.line, e.column), (line, column), "position of: {e}");
    assert_eq!(e.expected, expected, "expected of: {e}");
    assert_eq!(e.found, found, "found of: {e}");
    let message = e.to_string();
    assert!(message.contains(expected), "{message}");
    let quoted = if found == END_OF_FILE { found.to_owned() } else { format!("\"{found}\"") };
    assert!(message.ends_with(&format!("found {quoted}")), "{message}");
}

// ---------------------------------------------------------------- the thesis scripts

#[test]
fn curtain_fig_6_2_pins_the_whole_top_row() {
    let s = parse_asset("fig6-2-cortina.par");
    assert_eq!((s.duration_s, s.frame_rate_hz, s.dt_s, s.friction), (25.0, 1.0, 0.001, 0.5));
    assert_eq!(s.external_force_n, DVec3::ZERO);
    assert!(s.objects.is_empty() && s.gravity_m_s2.is_none());
    assert_eq!(s.surfaces.len(), 1);
    let c = &s.surfaces[0];
    assert_eq!(c.name.as_deref(), Some("cortina"));
    assert_eq!((c.rows, c.cols, c.spacing_m, c.particle_mass_kg), (20, 20, 1.85, 0.1));
    assert_eq!(c.centre_m, DVec3::new(-55.0, 40.0, 20.0));
    assert_eq!(c.normal, DVec3::Z);
    assert_eq!(c.stiffness_n_m, [10.0; 3]);
    assert_eq!(c.curvature, Curvature::PerPair([0.0; 3]));
    assert_eq!(c.fixed, (0..20).map(|j| (0, j)).collect::<Vec<_>>());
    assert_eq!(c.translations, [Translation { per_frame_m: DVec3::ZERO, start_s: 0.0, end_s: 0.0 }]);
}

#[test]
fn paper_fig_6_4_repaired_pins_the_staircase() {
    let s = parse_asset("fig6-4-papel.par");
    assert_eq!(s.external_force_n, DVec3::new(0.0, -0.39, 0.2));
    assert_eq!(s.surfaces.len(), 1);
    assert_eq!(s.surfaces[0].name.as_deref(), Some("papel"));
    assert_eq!(s.surfaces[0].fixed, PAPER_FIXED);
    assert_eq!(s.surfaces[0].translations.len(), 1);
}

#[test]
fn wind_a2_2_unnamed_surface_is_superficie1() {
    let s = parse_asset("a2-2-vento.par");
    assert_eq!(s.surfaces[0].name, None);
    assert_eq!(s.surfaces[0].fixed, [(0, 0), (0, 9), (9, 0)]);
    assert_eq!(s.surface_name(0), "SUPERFICIE1");
    let scene = s.to_scene(DVec3::ZERO);
    assert_eq!(scene.surfaces[0].name, "SUPERFICIE1");
    assert_eq!(scene.external_force_n, DVec3::new(0.0, 0.0, 9.8));
}

#[test]
fn curtains_a2_4_two_surfaces_two_translations_each() {
    let s = parse_asset("a2-4-cortinas.par");
    assert_eq!(s.duration_s, 145.0);
    let names: Vec<_> = s.surfaces.iter().map(|x| x.name.as_deref().unwrap()).collect();
    assert_eq!(names, ["corte", "cortd"]);
    let t = |x: f64, start_s: f64, end_s: f64| Translation {
        per_frame_m: DVec3::new(x, 0.0, 0.0),
        start_s,
        end_s,
    };
    assert_eq!(s.surfaces[0].translations, [t(0.43, 25.0, 78.0), t(-0.57, 100.0, 140.0)]);
    assert_eq!(s.surfaces[1].translations, [t(-0.43, 25.0, 78.0), t(0.57, 100.0, 140.0)]);
    assert_eq!(s.surfaces[1].centre_m, DVec3::new(18.0, 40.0, 23.0));
    for surface in &s.surfaces {
        assert_eq!(surface.fixed, (0..20).map(|j| (0, j)).collect::<Vec<_>>());
    }
}

#[test]
fn papelao_a2_6_is_the_paper_with_bending() {
    let s = parse_asset("a2-6-papelao.par");
    assert_eq!(s.surfaces[0].name.as_deref(), Some("papelao"));
    assert_eq!(s.surfaces[0].curvature, Curvature::PerPair([10.0; 3]));
    assert_eq!(s.surfaces[0].fixed, PAPER_FIXED);
    let paper = parse_asset("fig6-4-papel.par");
    let same_but_bending = ParScript {
        surfaces: vec![par::ParSurface {
            name: Some("papelao".into()),
            curvature: Curvature::PerPair([10.0; 3]),
            ..paper.surfaces[0].clone()
        }],
        ..paper
    };
    assert_eq!(s, same_but_bending);
}

#[test]
fn tablecloth_a2_8_names_the_table_and_pins_nothing() {
    let s = parse_asset("a2-8-toalha.par");
    assert_eq!(s.objects, ["mesa.obt"]);
    assert_eq!(s.external_force_n, DVec3::new(0.0, -9.8, 0.0));
    let t = &s.surfaces[0];
    assert_eq!(t.name.as_deref(), Some("toalha"));
    assert!(t.fixed.is_empty());
    assert_eq!(t.translations.len(), 1);
    assert_eq!((t.rows, t.cols, t.particle_mass_kg), (20, 20, 2.0));
    assert_eq!(t.normal, DVec3::Y);
    assert_eq!(t.stiffness_n_m, [50.0; 3]);
}

#[test]
fn scene_takes_literal_friction_default_integrator_and_thesis_options() {
    let scene = parse_asset("fig6-2-cortina.par").to_scene(FLEX3D_GRAVITY);
    assert_eq!(scene.gravity_m_s2, FLEX3D_GRAVITY);
    assert_eq!(scene.friction.mode, FrictionMode::Literal);
    assert_eq!(scene.friction.coefficient, 0.5);
    assert_eq!(scene.integrator, Integrator::default());
    assert_eq!(scene.options, ModelOptions::thesis());
    assert_eq!(scene.surfaces[0].fixed.len(), 20);
    assert_eq!(scene.surfaces[0].bending_n_m, [0.0; 3]);
    assert_eq!((scene.n_steps(), scene.n_frames()), (25_000, 25));
}

#[test]
fn par_to_ron_to_scene_is_exact_for_every_thesis_script() {
    for name in THESIS_SCRIPTS {
        let bytes = fs::read(asset(name)).unwrap();
        let direct = par::parse(&bytes).unwrap().to_scene(FLEX3D_GRAVITY);
        let ron = convert_par_to_ron(&bytes, name, FLEX3D_GRAVITY).unwrap();
        assert!(ron.starts_with("// "), "{name}: no header comment");
        let via_ron = from_ron_str(&ron).unwrap_or_else(|e| panic!("{name}: {e}\n{ron}"));
        assert_eq!(via_ron, direct, "{name}");
        assert_eq!(to_ron_string(&via_ron), ron, "{name}: RON text is not stable");
    }
}

#[test]
fn ron_round_trip_keeps_every_bit() {
    let mut scene = parse_asset("a2-4-cortinas.par").to_scene(FLEX3D_GRAVITY);
    scene.dt_s = 0.1 + 0.2; // 0.30000000000000004
    scene.surfaces[0].spacing_m = std::f64::consts::PI / 3.0;
    scene.surfaces[1].centre_m = DVec3::new(1e-300, -1.0 / 3.0, 6.02214076e23);
    let back = from_ron_str(&to_ron_string(&scene)).unwrap();
    assert_eq!(back.dt_s.to_bits(), scene.dt_s.to_bits());
    assert_eq!(back, scene);
}

// ---------------------------------------------------------------- spellings the language tolerates

#[test]
fn latin1_and_ascii_spellings_parse_like_utf8() {
    let expect = par::parse_str(WIND).unwrap();
    let latin1: Vec<u8> = WIND.chars().map(|c| u8::try_from(u32::from(c)).unwrap()).collect();
    assert!(std::str::from_utf8(&latin1).is_err());
    assert_eq!(par::parse(&latin1).unwrap(), expect);
    let ascii = WIND
        .replace("DURAÇÃO", "DURACAO")
        .replace("FORÇA", "forca")
        .replace("SUPERFÍCIE", "Superficie")
        .replace("RESTRIÇÕES", "RESTRICCOES")
        .replace("TRANSLAÇÃO", "translacao");
    assert_eq!(par::parse_str(&ascii).unwrap(), expect);
}

#[test]
fn separators_may_be_glued_missing_or_added() {
    let expect = par::parse_str(WIND).unwrap();
    let glued = WIND
        .replace("DELTA_t = 0.001", "DELTA_t=0.001")
        .replace("POSIC_NO_SRU (0.0 40.0 0.0)", "POSIC_NO_SRU(0.0 40.0 0.0)")
        .replace("MALHA (10 10)", "MALHA = 10 10")
        .replace("FORÇA_EXTERNA = (0.0 0.0 9.8)", "FORÇA_EXTERNA 0.0 0.0 9.8");
    assert_eq!(par::parse_str(&glued).unwrap(), expect);
    let flat = WIND.split_whitespace().collect::<Vec<_>>().join(" ");
    assert_eq!(par::parse_str(&flat).unwrap(), expect);
}

#[test]
fn const_curvatura_takes_one_value() {
    let s =
        par::parse_str(&WIND.replace("CONST_CURVATURA = (0.0 0.0 0.0)", "CONST_CURVATURA = 5.0")).unwrap();
    assert_eq!(s.surfaces[0].curvature, Curvature::One(5.0));
    assert_eq!(s.to_scene(DVec3::ZERO).surfaces[0].bending_n_m, [5.0; 3]);
}

#[test]
fn gravidade_keyword_wins_over_the_default_and_loses_to_the_override() {
    let src = WIND.replace("NUM_SUPERFÍCIES", "GRAVIDADE = (0.0 -1.6 0.0)\nNUM_SUPERFÍCIES");
    let s = par::parse_str(&src).unwrap();
    assert_eq!(s.gravity_m_s2, Some(DVec3::new(0.0, -1.6, 0.0)));
    assert_eq!(s.to_scene(FLEX3D_GRAVITY).gravity_m_s2, DVec3::new(0.0, -1.6, 0.0));
    assert_eq!(par::parse_str(WIND).unwrap().to_scene(DVec3::ZERO).gravity_m_s2, DVec3::ZERO);

    let dir = scratch("gravidade");
    let path = dir.join("lua.PAR");
    fs::write(&path, &src).unwrap();
    assert_eq!(
        load_flex3d(&path, &LoadOptions::default()).unwrap().scene.gravity_m_s2,
        DVec3::new(0.0, -1.6, 0.0)
    );
    let off = LoadOptions { gravity: Some(DVec3::ZERO) };
    assert_eq!(load_flex3d(&path, &off).unwrap().scene.gravity_m_s2, DVec3::ZERO);
    fs::remove_dir_all(dir).unwrap();
}

// ---------------------------------------------------------------- the loader

#[test]
fn load_a2_8_finds_mesa_obt() {
    let loaded = load_flex3d(&asset("a2-8-toalha.par"), &LoadOptions::default()).unwrap();
    assert_eq!(loaded.scene.gravity_m_s2, FLEX3D_GRAVITY, "no GRAVIDADE and no override: gravity on");
    assert_eq!(loaded.objects.len(), 1);
    let (name, mesh) = &loaded.objects[0];
    assert_eq!(name, "mesa.obt");
    assert_eq!((mesh.n_vertices(), mesh.n_triangles()), (8, 12));
    let top = mesh.aabb();
    assert_eq!((top.min, top.max), (DVec3::new(-10.5, 0.0, -10.5), DVec3::new(10.5, 10.0, 10.5)));

    let off = LoadOptions { gravity: Some(DVec3::ZERO) };
    assert_eq!(load_flex3d(&asset("a2-8-toalha.par"), &off).unwrap().scene.gravity_m_s2, DVec3::ZERO);
}

#[test]
fn load_matches_object_names_ignoring_case_and_reads_ron() {
    let dir = scratch("case");
    fs::copy(asset("a2-8-toalha.par"), dir.join("TOALHA.PAR")).unwrap();
    fs::copy(asset("mesa.obt"), dir.join("MESA.OBT")).unwrap();
    let from_par = load_flex3d(&dir.join("TOALHA.PAR"), &LoadOptions::default()).unwrap();
    assert_eq!(from_par.objects[0].1.n_triangles(), 12);

    let ron = convert_par_to_ron(&fs::read(asset("a2-8-toalha.par")).unwrap(), "a2-8", DVec3::ZERO).unwrap();
    fs::write(dir.join("toalha.ron"), ron).unwrap();
    let from_ron = load_flex3d(&dir.join("toalha.ron"), &LoadOptions::default()).unwrap();
    assert_eq!(from_ron.scene.gravity_m_s2, DVec3::ZERO, "a RON scene keeps its own gravity");
    assert_eq!(from_ron.objects, from_par.objects);
    let g = LoadOptions { gravity: Some(FLEX3D_GRAVITY) };
    assert_eq!(load_flex3d(&dir.join("toalha.ron"), &g).unwrap().scene, from_par.scene);
    fs::remove_dir_all(dir).unwrap();
}

#[test]
fn load_errors_name_the_file() {
    let dir = scratch("errors");
    fs::copy(asset("a2-8-toalha.par"), dir.join("toalha.par")).unwrap();
    let e = load_flex3d(&dir.join("toalha.par"), &LoadOptions::default()).unwrap_err();
    assert!(matches!(&e, SceneError::PartNotFound { name, .. } if name == "mesa.obt"), "{e}");
    assert!(e.to_string().contains("toalha.par") && e.to_string().contains("mesa.obt"), "{e}");

    fs::write(dir.join("mesa.obt"), "$OBJETO mesa 0 0 0 1 $VÉRTICES 1 0 0 0 $FACES x").unwrap();
    let e = load_flex3d(&dir.join("toalha.par"), &LoadOptions::default()).unwrap_err();
    assert!(matches!(e, SceneError::Obt { .. }), "{e}");
    assert!(e.to_string().contains("mesa.obt:1:") && e.to_string().contains("found \"x\""), "{e}");

    let e = load_flex3d(&dir.join("missing.par"), &LoadOptions::default()).unwrap_err();
    assert!(matches!(e, SceneError::Read { .. }) && e.to_string().contains("missing.par"), "{e}");

    let ocr = load_flex3d(&asset("fig6-4-papel-ocr.par"), &LoadOptions::default()).unwrap_err();
    let SceneError::Parse(p) = &ocr else { panic!("{ocr}") };
    assert!(p.file.as_deref().is_some_and(|f| f.ends_with("fig6-4-papel-ocr.par")), "{ocr}");
    assert!(ocr.to_string().contains("fig6-4-papel-ocr.par:18:5: expected a row index"), "{ocr}");
    fs::remove_dir_all(dir).unwrap();
}

// ---------------------------------------------------------------- malformed scripts

#[test]
fn misspelt_keyword() {
    let e = wind_error("QUADROS_SEG = 5", "QUADROS_SEGS = 5");
    assert_error(&e, 2, 1, "`QUADROS_SEG`", "QUADROS_SEGS");
}

#[test]
fn missing_number() {
    let e = wind_error("DELTA_t = 0.001", "DELTA_t =");
    assert_error(&e, 4, 1, "a number for `DELTA_t`", "FORÇA_EXTERNA");
}

#[test]
fn letter_where_a_number_goes() {
    let e = wind_error("MASSA = 0.5", "MASSA = O.5");
    assert_error(&e, 13, 13, "a number for `MASSA`", "O.5");
}

#[test]
fn fewer_fixed_points_than_declared() {
    // The list ends at TRANSLAÇÃO, which is where the fourth pair should have been.
    let e = wind_error("PONTOS_FIXOS = 3", "PONTOS_FIXOS = 4");
    assert_error(&e, 21, 9, "a row index 0 ≤ i < 10 (fixed point 4 of 4)", "TRANSLAÇÃO");
}

#[test]
fn more_fixed_points_than_declared() {
    let e = wind_error("PONTOS_FIXOS = 3", "PONTOS_FIXOS = 2");
    assert_error(&e, 20, 9, "`TRANSLAÇÃO` or `FIM_RESTRIÇÕES` (`PONTOS_FIXOS` = 2 declares 2 pairs)", "9");
}

#[test]
fn fixed_point_outside_the_mesh() {
    let e = wind_error("        9 0\n", "        9 10\n");
    assert_error(&e, 20, 11, "a column index 0 ≤ j < 10 (fixed point 3 of 3)", "10");
}

#[test]
fn num_superficies_larger_than_the_surfaces_given() {
    let e = wind_error("NUM_SUPERFÍCIES = 1", "NUM_SUPERFÍCIES = 2");
    assert_error(&e, 25, 15, "`SUPERFÍCIE` (surface 2 of 2 declared by `NUM_SUPERFÍCIES`)", END_OF_FILE);
}

#[test]
fn num_superficies_smaller_than_the_surfaces_given() {
    let surface = &WIND[WIND.find("SUPERFÍCIE\n").unwrap()..];
    let e = par::parse_str(&format!("{WIND}{surface}")).unwrap_err();
    assert_error(&e, 26, 1, "end of file (`NUM_SUPERFÍCIES` = 1)", "SUPERFÍCIE");
}

#[test]
fn missing_fim_superficie_at_end_of_file() {
    let e = wind_error("FIM_SUPERFÍCIE\n", "");
    assert_error(&e, 24, 19, "`FIM_SUPERFÍCIE`", END_OF_FILE);
}

#[test]
fn negative_delta_t() {
    let e = wind_error("DELTA_t = 0.001", "DELTA_t = -0.001");
    assert_error(&e, 3, 11, "a positive number for `DELTA_t`", "-0.001");
}

#[test]
fn zero_normal() {
    let e = wind_error("VETOR_NORMAL (0.0 0.0 1.0)", "VETOR_NORMAL (0.0 0.0 0.0)");
    assert_error(&e, 12, 19, "a non-zero `VETOR_NORMAL`", "0.0 0.0 0.0");
}

#[test]
fn mesh_smaller_than_2_by_2() {
    let e = wind_error("MALHA (10 10)", "MALHA (1 10)");
    assert_error(&e, 9, 12, "a whole number of rows ≥ 2 for `MALHA`", "1");
}

#[test]
fn unclosed_parenthesis() {
    let e = wind_error("(0.0 0.0 9.8)", "(0.0 0.0 9.8");
    assert_error(&e, 5, 1, "`)` closing `FORÇA_EXTERNA`", "ATRITO");
}

#[test]
fn const_curvatura_with_two_values() {
    let e = wind_error("CONST_CURVATURA = (0.0 0.0 0.0)", "CONST_CURVATURA = (0.0 0.0)");
    assert_error(&e, 15, 31, "a number for `CONST_CURVATURA` (it takes 1 value or 3)", ")");
}

#[test]
fn object_count_without_file_names() {
    let e = wind_error("OBJETOS_NA_CENA = 0", "OBJETOS_NA_CENA = 1");
    assert_error(&e, 7, 1, "an .OBT file name (1 of 1 declared by `OBJETOS_NA_CENA`)", "NUM_SUPERFÍCIES");
}

#[test]
fn more_object_names_than_declared() {
    let e = wind_error("OBJETOS_NA_CENA = 0", "OBJETOS_NA_CENA = 0\nmesa.obt");
    assert_error(&e, 7, 1, "`NUM_SUPERFÍCIES` (`OBJETOS_NA_CENA` = 0 declares 0 file names)", "mesa.obt");
    let e = wind_error("NUM_SUPERFÍCIES", "NUM_SUPERFICIE");
    assert_error(&e, 7, 1, "`GRAVIDADE` or `NUM_SUPERFÍCIES`", "NUM_SUPERFICIE");
}

#[test]
fn empty_script() {
    let e = par::parse_str("\n\n").unwrap_err();
    assert_error(&e, 1, 1, "`DURAÇÃO`", END_OF_FILE);
}

#[test]
fn ocr_fig_6_4_is_rejected() {
    // The OCR glued each pair into one number: `90` is read as row 90 of a 10-row mesh.
    let bytes = fs::read(asset("fig6-4-papel-ocr.par")).unwrap();
    let e = par::parse(&bytes).unwrap_err();
    assert_error(&e, 18, 5, "a row index 0 ≤ i < 10 (fixed point 1 of 22)", "90");
    let e = convert_par_to_ron(&bytes, "fig6-4-papel-ocr.par", FLEX3D_GRAVITY).unwrap_err();
    assert!(e.to_string().starts_with("fig6-4-papel-ocr.par:18:5: expected a row index"), "{e}");
}

#[test]
fn ocr_inl_transl_alone_is_rejected() {
    let repaired = fs::read_to_string(asset("fig6-4-papel.par")).unwrap();
    let e = par::parse_str(&repaired.replace("INI_TRANSL", "INL_TRANSL")).unwrap_err();
    assert_error(&e, 41, 3, "`INI_TRANSL`", "INL_TRANSL");
}

// ---------------------------------------------------------------- malformed RON scenes

fn wind_ron() -> String {
    convert_par_to_ron(WIND.as_bytes(), "a2-2-vento.par", DVec3::ZERO).unwrap()
}

/// Line and column (1-based, in characters) where `needle` starts in `text`.
fn position_of(text: &str, needle: &str) -> (usize, usize) {
    let at = text.find(needle).unwrap();
    let before = &text[..at];
    (1 + before.matches('\n').count(), 1 + before.rsplit('\n').next().unwrap().chars().count())
}

#[test]
fn ron_unknown_integrator() {
    let ron = wind_ron().replace("integrator: ForwardEuler", "integrator: Euler");
    let e = from_ron_str(&ron).unwrap_err();
    let (line, column) = position_of(&ron, "Euler,");
    assert_eq!((e.line, e.column), (line, column), "{e}");
    assert!(e.expected.contains("`Integrator`") && e.expected.contains("`Rk4`"), "{e}");
    assert_eq!(e.found, "Euler");
    assert!(e.to_string().ends_with("found \"Euler\""), "{e}");
}

#[test]
fn ron_unknown_field() {
    let ron = wind_ron().replace("    dt_s:", "    gravity: (0.0, 0.0, 0.0),\n    dt_s:");
    let e = from_ron_str(&ron).unwrap_err().with_file("vento.ron");
    let (line, column) = position_of(&ron, "gravity:");
    assert_eq!((e.line, e.column), (line, column), "{e}");
    assert!(e.expected.contains("`Flex3dScene`") && e.expected.contains("`gravity_m_s2`"), "{e}");
    assert_eq!(e.found, "gravity");
    assert!(e.to_string().starts_with(&format!("vento.ron:{line}:{column}: expected a field")), "{e}");
}

#[test]
fn ron_letter_where_a_number_goes() {
    let ron = wind_ron().replace("dt_s: 0.001", "dt_s: abc");
    let e = from_ron_str(&ron).unwrap_err();
    assert_eq!((e.line, e.column), position_of(&ron, "abc"), "{e}");
    assert_eq!((e.expected.as_str(), e.found.as_str()), ("float", "abc"));
}

#[test]
fn ron_enum_variant_in_the_wrong_case_is_refused() {
    let ron = wind_ron().replace("mode: Literal", "mode: literal");
    let e = from_ron_str(&ron).unwrap_err();
    assert_eq!((e.line, e.column), position_of(&ron, "literal,"), "{e}");
    assert!(e.expected.contains("`Literal`") && e.expected.contains("`Viscous`"), "{e}");
    assert_eq!(e.found, "literal");
}

mod kinds {
    use std::path::{Path, PathBuf};

    use anima_scene::{LoadOptions, Scene, SceneError, SceneKind, load};

    fn write(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("anima-scene-kinds-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    fn assets(rel: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets").join(rel)
    }

    fn kind_error(path: &Path) -> String {
        match load(path, &LoadOptions::default()) {
            Err(e @ SceneError::Kind { .. }) => e.to_string(),
            other => panic!("{}: expected a kind error, found {other:?}", path.display()),
        }
    }

    #[test]
    fn the_kind_is_told_by_the_struct_name_or_by_a_field_only_that_kind_has() {
        let kind = |rel: &str| load(&assets(rel), &LoadOptions::default()).unwrap().kind();
        assert_eq!(kind("flex3d/a2-8-toalha.par"), SceneKind::Flex3d);
        assert_eq!(kind("flex3d/tablecloth.ron"), SceneKind::Flex3d);
        assert_eq!(kind("scenes/standard-sheet-32.ron"), SceneKind::Sheet);
        assert_eq!(kind("oliveira/test-3-sphere-5x5.ron"), SceneKind::Oliveira);
        assert_eq!(kind("oliveira/test-3-sphere-adaptive.ron"), SceneKind::Oliveira);
        assert_eq!(kind("scenes/stand.ron"), SceneKind::Body);
        assert_eq!(kind("scenes/walk.ron"), SceneKind::Character);
        // Files written before scenes were named: told by their fields.
        let flex3d =
            std::fs::read_to_string(assets("flex3d/curtain.ron")).unwrap().replacen("Flex3dScene(", "(", 1);
        let k = load(&write("unnamed-flex3d.ron", &flex3d), &LoadOptions::default()).map(|s| s.kind());
        assert_eq!(k.unwrap(), SceneKind::Flex3d);
        let oliveira = std::fs::read_to_string(assets("oliveira/test-3-sphere-5x5.ron")).unwrap().replacen(
            "OliveiraScene(",
            "(",
            1,
        );
        let k = load(&write("unnamed-oliveira.ron", &oliveira), &LoadOptions::default()).map(|s| s.kind());
        assert_eq!(k.unwrap(), SceneKind::Oliveira);
    }

    #[test]
    fn parts_and_specs_are_not_scenes_and_unknown_kinds_are_named() {
        let e = kind_error(&assets("skeletons/humanoid.ron"));
        assert!(e.contains("skeleton") && e.contains("part of a scene"), "{e}");
        let e = kind_error(&assets("controllers/walk.ron"));
        assert!(e.contains("controller") && e.contains("part of a scene"), "{e}");
        let e = kind_error(&assets("optimisations/walk.ron"));
        assert!(e.contains("anima optimise"), "{e}");
        let e = kind_error(&write("other.ron", "Wardrobe(\n    doors: 2,\n)"));
        assert!(e.contains("`Wardrobe`") && e.contains("`CharacterScene`"), "{e}");
        let e = kind_error(&write("fieldless.ron", "(\n    doors: 2,\n)"));
        assert!(e.contains("cannot tell which kind"), "{e}");
        let e = kind_error(&write("scene.txt", "anything"));
        assert!(e.contains(".par or .ron"), "{e}");
    }

    #[test]
    fn character_scenes_check_their_parts_before_anything_runs() {
        // The scene in a folder of its own, naming its parts by absolute paths.
        let parts = assets("").display().to_string();
        let walk = std::fs::read_to_string(assets("scenes/walk.ron")).unwrap().replace("../", &parts);
        let at = |name: &str, text: &str| {
            let p = write(&format!("{name}.ron"), text);
            load(&p, &LoadOptions::default()).unwrap_err().to_string()
        };
        // A controller that is not there.
        let e = at("missing", &walk.replace("walk-optimised.ron", "nowhere.ron"));
        assert!(e.contains("controller file") && e.contains("nowhere.ron` not found"), "{e}");
        // A controller for another figure: its actuators name no actuator of the scene's models.
        let e = at("wrong", &walk.replace("walk-optimised.ron", "backflip.ron"));
        assert!(e.contains("names no actuator of the scene's models") && e.contains("line"), "{e}");
        // A bad value, located.
        let e = at("dt", &walk.replace("dt_s: 0.05,", "dt_s: -0.05,"));
        assert!(e.contains("world.dt_s") && e.contains("line 11, column 9"), "{e}");
        // The older spellings of the run header (`duration`, the world's `dt`, `frame_interval` in
        // seconds) still read.
        let old = walk
            .replace("duration_s:", "duration:")
            .replace("dt_s:", "dt:")
            .replace("frame_rate_hz: 2.0,", "frame_interval: 0.5,");
        assert!(old.contains("duration:") && old.contains("dt:") && !old.contains("dt_s"));
        assert!(old.contains("frame_interval:") && !old.contains("frame_rate_hz"));
        let p = write("old-spelling.ron", &old);
        let Ok(Scene::Character(l)) = load(&p, &LoadOptions::default()) else {
            panic!("the old spelling reads")
        };
        assert_eq!(
            (l.scene.duration, l.scene.world.dt, l.scene.frame_interval_s().expect("checked")),
            (50.0, 0.05, 0.5)
        );
        let Ok(Scene::Character(new)) = load(&write("new-spelling.ron", &walk), &LoadOptions::default())
        else {
            panic!("the scene reads")
        };
        assert_eq!(new.scene.frame_interval_s().expect("checked").to_bits(), 0.5f64.to_bits());
        // One of the two frame clocks, positive.
        let both = walk.replace("frame_rate_hz: 2.0,", "frame_rate_hz: 2.0,\n    frame_interval: 0.5,");
        let e = at("both", &both);
        assert!(e.contains("frame_interval") && e.contains("not both"), "{e}");
        let e = at("neither", &walk.replace("frame_rate_hz: 2.0,", ""));
        assert!(e.contains("frame_rate_hz"), "{e}");
        let e = at("zero-rate", &walk.replace("frame_rate_hz: 2.0,", "frame_rate_hz: 0.0,"));
        assert!(e.contains("frame_rate_hz") && e.contains("line 9"), "{e}");
    }
}

#[test]
fn ron_scenes_with_times_a_run_cannot_use_are_refused_at_their_line() {
    let dir = std::env::temp_dir().join(format!("anima-scene-times-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    for (rel, from, to, field) in [
        ("scenes/standard-sheet-32.ron", "dt_s: 0.0002", "dt_s: -0.0002", "dt_s"),
        ("scenes/standard-sheet-32.ron", "frame_rate_hz: 30.0", "frame_rate_hz: 0.0", "frame_rate_hz"),
        ("flex3d/curtain.ron", "duration_s: 25.0", "duration_s: inf", "duration_s"),
        // An adaptive integrator where the model steps at a fixed Δt.
        ("flex3d/curtain.ron", "integrator: ForwardEuler", "integrator: AdaptiveEuler", "integrator"),
        ("oliveira/test-2-table-17x17.ron", "integrator: Rk4", "integrator: AdaptiveEuler", "integrator"),
    ] {
        let text = fs::read_to_string(root.join(rel)).unwrap();
        assert!(text.contains(from), "{rel}");
        let p = dir.join(Path::new(rel).file_name().unwrap());
        fs::write(&p, text.replace(from, to)).unwrap();
        let e = load_flex3d_or_any(&p);
        assert!(e.contains(&format!("field `{field}`")) && e.contains("line"), "{rel}: {e}");
    }
    fs::remove_dir_all(&dir).unwrap();
}

fn load_flex3d_or_any(p: &Path) -> String {
    anima_scene::load(p, &LoadOptions::default()).unwrap_err().to_string()
}
