//! A fuzzing harness for every reader and what a loaded scene builds: hostile inputs get an error,
//! never a panic, a hang or an unbounded allocation.
//!
//! Seeds are every scene file, part and spec under `assets/`, an optimisation's resume log, plus
//! `tests/corpus/`: inputs that once crashed a reader or a run (each kept there for good). Each round
//! takes a seed, mutates it (byte flips, cut and copied ranges, numbers and names that hostile files
//! use), writes it beside copies of the assets (so the parts it names resolve) and reads it as what it
//! is: a scene is loaded with `anima_scene::load` and, when it loads, built and run for three steps; a
//! controller is read, bound to the walker and stepped three times; a skeleton is read and placed in a
//! world; an optimisation spec is loaded and its optimiser built and asked for a generation; a log is
//! resumed into the spec's optimiser. A panic fails the test and prints the input that caused it; copy
//! it into `tests/corpus/` when fixing the cause.
//!
//! The mutations come from a seeded generator, so a run is repeatable: `ANIMA_FUZZ_ROUNDS` inputs (20 000 by
//! default, what CI runs: the same inputs on every machine), stopped early after `ANIMA_FUZZ_SECONDS`
//! (120 by default) on a slow one; `ANIMA_FUZZ_SEED` picks another sequence. Searching longer:
//! `ANIMA_FUZZ_ROUNDS=1000000 ANIMA_FUZZ_SECONDS=600 ANIMA_FUZZ_SEED=7 cargo test --release -p anima-lab --test fuzz`.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anima_body::{Placement, Skeleton, World, WorldSettings};
use anima_control::optimise::{RunLog, resume};
use anima_lab::run::{Overrides, RunOptions, Silent, run};
use anima_scene::{LoadOptions, load, load_optimisation};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/corpus")
}

/// Every `.par` and `.ron` file under `dir`, with its path relative to `dir`.
fn files(dir: &Path, rel: &Path, out: &mut Vec<(PathBuf, Vec<u8>)>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<_> = entries.map(|e| e.unwrap().path()).collect();
    entries.sort();
    for p in entries {
        let name = rel.join(p.file_name().unwrap());
        if p.is_dir() {
            files(&p, &name, out);
        } else if p
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("par") || e.eq_ignore_ascii_case("ron"))
        {
            out.push((name, std::fs::read(&p).unwrap()));
        }
    }
}

/// A copy of `assets/` to write mutated files into, so that the parts a scene names resolve and nothing
/// is written into the repository.
fn scratch_assets(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("anima-fuzz-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    fn copy(from: &Path, to: &Path) {
        std::fs::create_dir_all(to).unwrap();
        for e in std::fs::read_dir(from).unwrap() {
            let p = e.unwrap().path();
            let target = to.join(p.file_name().unwrap());
            if p.is_dir() { copy(&p, &target) } else { std::fs::copy(&p, &target).map(|_| ()).unwrap() }
        }
    }
    copy(&assets(), &dir);
    dir
}

/// Tokens hostile files use: huge, tiny, negative and non-finite numbers, path parts, brackets.
const TOKENS: &[&str] = &[
    "0",
    "-1",
    "1e308",
    "-1e308",
    "1e-300",
    "4294967296",
    "100000",
    "18446744073709551616",
    "NaN",
    "inf",
    "-inf",
    "0.0",
    "1.0e9",
    "../../x",
    "/",
    ".",
    "(",
    ")",
    "[",
    "]",
    ",",
    ":",
    "\"",
    "//",
    "Ç",
    "\u{feff}",
    "\n",
    " ",
    "None",
    "Some(",
    "MALHA",
    "PONTOS_FIXOS",
    "DELTA_t",
    "SUPERFÍCIE",
    "FIM_SUPERFÍCIE",
    "NUM_SUPERFÍCIES",
];

fn mutate(rng: &mut ChaCha8Rng, seed: &[u8], other: &[u8]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..rng.random_range(1..=4) {
        let len = b.len().max(1);
        let at = rng.random_range(0..len).min(b.len());
        match rng.random_range(0..6) {
            0 if !b.is_empty() => {
                let k = rng.random_range(0..b.len());
                b[k] ^= 1 << rng.random_range(0..8);
            }
            1 => {
                let end = (at + rng.random_range(1..64)).min(b.len());
                b.drain(at..end);
            }
            2 => {
                let end = (at + rng.random_range(1..64)).min(b.len());
                let copy = b[at..end].to_vec();
                let to = rng.random_range(0..=b.len());
                b.splice(to..to, copy);
            }
            3 | 4 => {
                // Replace the number or word at `at` by a hostile token.
                let start = b[..at]
                    .iter()
                    .rposition(|c| !c.is_ascii_alphanumeric() && !b".-+_".contains(c))
                    .map_or(0, |k| k + 1);
                let end = b[at..]
                    .iter()
                    .position(|c| !c.is_ascii_alphanumeric() && !b".-+_".contains(c))
                    .map_or(b.len(), |k| at + k);
                let t = TOKENS[rng.random_range(0..TOKENS.len())].as_bytes();
                b.splice(start..end.max(start), t.iter().copied());
            }
            _ if !other.is_empty() => {
                // Splice in a piece of another file.
                let from = rng.random_range(0..other.len());
                let end = (from + rng.random_range(1..200)).min(other.len());
                b.splice(at..at, other[from..end].iter().copied());
            }
            _ => {}
        }
    }
    b
}

/// The walk-cmaes spec, for the logs.
const LOG_SPEC: &str = "optimisations/walk-cmaes.ron";

/// A resume log of two generations of `LOG_SPEC`'s optimiser (fitnesses made up: the log's form is
/// what is fuzzed, not a walk), written as `anima optimise` writes it.
fn seed_log() -> Vec<u8> {
    let loaded = load_optimisation(&assets().join(LOG_SPEC)).unwrap();
    let ids = loaded.controller.free_params(&loaded.spec.parameters);
    let mut opt = anima_run::optimise::optimiser(&loaded, &ids).unwrap();
    let mut log = RunLog::default();
    let objective = |x: &[f64]| x.iter().sum::<f64>();
    anima_control::optimise::run(opt.as_mut(), &objective, 16, &mut log).unwrap();
    ron::ser::to_string_pretty(&log, ron::ser::PrettyConfig::default()).unwrap().into_bytes()
}

/// Reads `path` as what its folder holds and, when it reads, uses it a little: `Err` is fine, a panic
/// is not.
fn exercise(path: &Path, out: &Path) {
    let rel = path.to_string_lossy();
    let text = || std::fs::read(path).ok().and_then(|b| String::from_utf8(b).ok());
    if rel.ends_with(".log.ron") {
        let Some(text) = text() else { return };
        let Ok(log) = ron::from_str::<RunLog>(&text) else { return };
        let loaded = load_optimisation(&assets().join(LOG_SPEC)).unwrap();
        let ids = loaded.controller.free_params(&loaded.spec.parameters);
        let mut opt = anima_run::optimise::optimiser(&loaded, &ids).unwrap();
        if resume(opt.as_mut(), &log).is_ok() {
            let _ = opt.ask();
        }
        return;
    }
    if rel.contains("optimisations") {
        if let Ok(loaded) = load_optimisation(path) {
            let ids = loaded.controller.free_params(&loaded.spec.parameters);
            if let Ok(mut opt) = anima_run::optimise::optimiser(&loaded, &ids) {
                let _ = opt.ask();
            }
        }
        return;
    }
    if rel.contains("controllers") {
        let Some(text) = text() else { return };
        let Ok(c) = anima_run::objectives::parse(&text) else { return };
        let Ok(mut walker) = anima_run::objectives::humanoid_character(c) else { return };
        for _ in 0..3 {
            let _ = walker.step();
        }
        return;
    }
    if rel.contains("skeletons") {
        let Some(text) = text() else { return };
        let Ok(sk) = Skeleton::from_ron_str(&text) else { return };
        if let Ok(mut world) = World::new(WorldSettings::thesis()) {
            let _ = world.add_model(&sk, Placement::OnGround { dx: 0.0 });
        }
        return;
    }
    let Ok(mut scene) = load(path, &LoadOptions::default()) else { return };
    let dt = match &scene {
        anima_scene::Scene::Flex3d(l) => l.scene.dt_s,
        anima_scene::Scene::Sheet(s) => s.dt_s,
        anima_scene::Scene::Oliveira(l) => {
            // A drape's step comes from its material: run it only when three steps' worth of time is a
            // few steps (a legitimately tiny step would make this round take hours, not fail).
            let Ok(cloth) = l.build() else { return };
            let dt = l.step_estimate(&cloth);
            if dt.is_nan() || dt < 1e-6 {
                return;
            }
            dt
        }
        anima_scene::Scene::Body(l) => l.scene.world.dt,
        anima_scene::Scene::Character(l) => l.scene.world.dt,
    };
    let short = Overrides { duration: Some(3.0 * dt), ..Overrides::default() };
    if short.apply(&mut scene).is_err() {
        return;
    }
    let opts = RunOptions { out_dir: Some(out.to_owned()), frames: true, ..RunOptions::default() };
    let _ = run(&scene, "fuzz", &opts, &mut Silent);
}

fn check(path: &Path, bytes: &[u8], out: &Path) {
    std::fs::write(path, bytes).unwrap();
    if catch_unwind(AssertUnwindSafe(|| exercise(path, out))).is_err() {
        let shown = String::from_utf8_lossy(bytes);
        panic!("{} panicked on this input; add it to tests/corpus/:\n{shown}", path.display());
    }
}

#[test]
fn the_corpus_of_inputs_that_once_crashed_is_refused_or_runs() {
    let mut inputs = Vec::new();
    files(&corpus(), Path::new(""), &mut inputs);
    assert!(!inputs.is_empty(), "tests/corpus/ holds the inputs that once crashed");
    let dir = scratch_assets("corpus");
    let out = dir.join("out");
    for (name, bytes) in &inputs {
        // Written where a file of its kind lives, so that its parts resolve: the name's first word says
        // the kind (`spec-…`, `log-…`, `controller-…`, `skeleton-…`, else a scene).
        let file = name.file_name().unwrap().to_string_lossy();
        let place = match file.split('-').next().unwrap_or_default() {
            _ if name.extension().is_some_and(|e| e.eq_ignore_ascii_case("par")) => "flex3d",
            "spec" | "log" => "optimisations",
            "controller" => "controllers",
            "skeleton" => "skeletons",
            _ => "scenes",
        };
        check(&dir.join(place).join(name.file_name().unwrap()), bytes, &out);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn mutated_assets_get_errors_not_panics() {
    let rounds_wanted: usize =
        std::env::var("ANIMA_FUZZ_ROUNDS").ok().and_then(|s| s.parse().ok()).unwrap_or(20_000);
    let seconds: u64 = std::env::var("ANIMA_FUZZ_SECONDS").ok().and_then(|s| s.parse().ok()).unwrap_or(120);
    let seed: u64 = std::env::var("ANIMA_FUZZ_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(1993);
    let mut seeds = Vec::new();
    files(&assets(), Path::new(""), &mut seeds);
    seeds.push((PathBuf::from("optimisations/walk-cmaes.log.ron"), seed_log()));
    // The big fine-mesh drapes take long to build a few times over; their 5 × 5 forms say the same.
    seeds.retain(|(p, _)| !p.to_string_lossy().contains("17x17"));
    let dir = scratch_assets("mutated");
    let out = dir.join("out");
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let deadline = Instant::now() + Duration::from_secs(seconds);
    let mut rounds = 0;
    while rounds < rounds_wanted && Instant::now() < deadline {
        let (name, seed_bytes) = &seeds[rng.random_range(0..seeds.len())];
        let other = &seeds[rng.random_range(0..seeds.len())].1;
        let bytes = mutate(&mut rng, seed_bytes, other);
        let path = dir
            .join(name.parent().unwrap())
            .join(format!("fuzz-{}", name.file_name().unwrap().to_string_lossy()));
        check(&path, &bytes, &out);
        rounds += 1;
    }
    assert!(rounds > 100, "only {rounds} rounds in {seconds} s");
    eprintln!("fuzz: {rounds} mutated inputs, seed {seed}");
    std::fs::remove_dir_all(&dir).unwrap();
}
