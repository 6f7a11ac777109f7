//! One drape of `cargo xtask bench --scale`, timed and profiled: `OBSTACLE` = bunny | sphere (bunny), or
//! `sheet` for the standard sheet of V × V particles (`T` seconds, one run), `MIN_EDGE` (m) to remesh
//! the drape after every step by the sizing field down to edges that short (the drape file of size V is
//! the start: 65 with 0.0078125 refines toward the 129² spacing),
//! `V` = 65 | 129 | 257 (65), `T` = simulated seconds (3; a 3 s run of a size whose converged references
//! are cached also prints its error), `THREADS` (every core), `GRAVITY` (a factor on gravity: 1),
//! `REGIME` (Newton iterations for contacts that change regime; the stepper's default), `REFERENCES=1`
//! (compute the size's converged references first when they are not cached: minutes),
//! `FRICTION_SMOOTHING` (ε in m/s for smoothed friction, `none` for the stick and slide regimes, instead
//! of the scene file's; `cargo xtask bench --scale` honours it too, and caches each model's references
//! apart).

use anima_lab::repo::Repo;

fn main() -> anyhow::Result<()> {
    let var = |k: &str| std::env::var(k).ok();
    let obstacle = var("OBSTACLE").unwrap_or_else(|| "bunny".into());
    let v: usize = var("V").and_then(|s| s.parse().ok()).unwrap_or(65);
    let t: f64 = var("T").and_then(|s| s.parse().ok()).unwrap_or(3.0);
    let gravity: f64 = var("GRAVITY").and_then(|s| s.parse().ok()).unwrap_or(1.0);
    let regime: Option<usize> = var("REGIME").and_then(|s| s.parse().ok());
    let threads: usize = var("THREADS").and_then(|s| s.parse().ok()).unwrap_or(0);
    let references = var("REFERENCES").is_some_and(|s| s == "1");
    let min_edge: Option<f64> = var("MIN_EDGE")
        .map(|s| s.parse().map_err(|_| anyhow::anyhow!("MIN_EDGE: expected a length in metres, found `{s}`")))
        .transpose()?;
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    let report = pool.install(|| match (obstacle.as_str(), min_edge) {
        ("sheet", _) => anima_lab::scale::sheet_probe(v, t),
        (_, Some(e)) => anima_lab::scale::adaptive_probe(&Repo::here(), &obstacle, v, t, gravity, regime, e),
        _ => anima_lab::scale::probe(&Repo::here(), &obstacle, v, t, gravity, regime, references),
    })?;
    println!("{report}");
    Ok(())
}
