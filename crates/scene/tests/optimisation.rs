//! Optimisation specs with counts above anima's limits are refused where the count is written, before
//! any optimiser is built (issue #40: `lambda: Some(1000000000000)` used to abort for want of memory,
//! `Walk(iterations: 18446744073709551615)` to run for ever).

use std::fs;
use std::path::{Path, PathBuf};

use anima_scene::limits::{MAX_EVALUATIONS, MAX_POPULATION};
use anima_scene::load_optimisation;

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

/// A fresh, empty folder for one test, holding the thesis's controllers.
fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("anima-scene-{}-{test}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    for c in ["walk.ron", "throw.ron"] {
        fs::copy(assets().join("controllers").join(c), dir.join(c)).unwrap();
    }
    dir
}

/// The spec `assets/optimisations/<spec>` with `from` (which must occur) replaced by `to`, written to
/// `dir` as `spec-<spec>` next to its controller (which may have the same name), and loaded.
fn load_edited(dir: &Path, spec: &str, from: &str, to: &str) -> Result<(), String> {
    let text = fs::read_to_string(assets().join("optimisations").join(spec)).unwrap();
    assert!(text.contains(from), "{from:?} is not in {spec}");
    let text = text.replace("\"../controllers/", "\"").replacen(from, to, 1);
    let path = dir.join(format!("spec-{spec}"));
    fs::write(&path, text).unwrap();
    load_optimisation(&path).map(|_| ()).map_err(|e| e.to_string())
}

#[test]
fn counts_above_the_limits_are_refused_at_their_line() {
    let dir = scratch("optimisation-counts");
    let cmaes = "Cmaes(sigma0: 0.25, lambda: Some(8), restarts: 0)";
    let huge = "1000000000000";
    let too_many_evaluations = (MAX_EVALUATIONS + 1).to_string();
    let too_many_candidates = (MAX_POPULATION + 1).to_string();
    for (spec, from, to, field, line) in [
        ("walk-cmaes.ron", "lambda: Some(8)", format!("lambda: Some({huge})"), "optimiser.lambda", 10),
        (
            "walk-cmaes.ron",
            "evaluations: 48",
            format!("evaluations: {too_many_evaluations}"),
            "evaluations",
            11,
        ),
        (
            "walk-cmaes.ron",
            "Walk(iterations: 1000)",
            format!("Walk(iterations: {})", u64::MAX),
            "objective.iterations",
            8,
        ),
        (
            "walk-cmaes.ron",
            cmaes,
            format!("RandomSearch(batch: {too_many_candidates})"),
            "optimiser.batch",
            10,
        ),
        (
            "walk-cmaes.ron",
            cmaes,
            format!("Annealing((x0: [], t0: 1.0, cooling: 0.9, step: 0.1, batch: {huge}))"),
            "optimiser.batch",
            10,
        ),
        (
            "walk.ron",
            "evaluations: 15",
            format!("evaluations: {huge}"),
            "optimiser.stages[0].evaluations",
            12,
        ),
        (
            "walk.ron",
            "LocalSingle(Fixed), batch: 1",
            format!("LocalSingle(Fixed), batch: {too_many_candidates}"),
            "optimiser.stages[1].batch",
            13,
        ),
        ("throw.ron", "iterations: 2000", "iterations: 1000000001".to_string(), "objective.iterations", 10),
    ] {
        let e = load_edited(&dir, spec, from, &to).expect_err(&to);
        assert!(
            e.contains(&format!("spec-{spec}:"))
                && e.contains(&format!("line {line}, column"))
                && e.contains(&format!("field `{field}`"))
                && e.contains("at most"),
            "{to}: {e}"
        );
    }
    // At the limits, the specs load.
    for (spec, from, to) in [
        ("walk-cmaes.ron", "lambda: Some(8)", format!("lambda: Some({MAX_POPULATION})")),
        ("walk-cmaes.ron", "evaluations: 48", format!("evaluations: {MAX_EVALUATIONS}")),
        ("walk-cmaes.ron", "Walk(iterations: 1000)", "Walk(iterations: 1000000000)".to_string()),
        ("walk.ron", "evaluations: 15", format!("evaluations: {MAX_EVALUATIONS}")),
        ("walk-cmaes.ron", cmaes, format!("RandomSearch(batch: {MAX_POPULATION})")),
    ] {
        load_edited(&dir, spec, from, &to).unwrap_or_else(|e| panic!("{to}: {e}"));
    }
    fs::remove_dir_all(&dir).unwrap();
}
