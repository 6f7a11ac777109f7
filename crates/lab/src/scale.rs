//! `cargo xtask bench --scale`: cloth at the size users simulate (issue #37). The standard sheet at
//! N = 64, 128 and 256 and the drapes of `benchmarks.md` (a 1 m cloth on the Stanford Bunny or on a
//! sphere, each on a floor) at 65², 129² and 257² vertices, all at 1/60 s by generalised-α, the drapes
//! with contact in the solve and the modern self-collision response: what a step costs per particle on
//! one core and on every core, where its time goes, whether the drapes stay out of their obstacles and
//! out of themselves at every step, how far a 1/60 s drape lies from the same model converged (beside
//! the band two converged runs with gravity × (1 ± 10⁻⁹) span), the peers on the same drapes, and the
//! stability estimate of the explicit sheet against its measured largest stable step. Writes
//! `docs/benchmarks-scale.md` and its figures. Speed lives here, never in a test.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use anima_cloth::network_sim::NetworkSim;
use anima_cloth::oliveira::OliveiraCloth;
use anima_cloth::spring_net::SheetSpec;
use anima_geom::{Aabb, DVec3, count_self_intersections};
use anima_ode::{Integrator, SolveProfile};
use anima_scene::oliveira::LoadedOliveira;
use anima_viz::{Camera, LinePlot, RenderMesh, RenderSettings, Series, SeriesStyle, render};
use anyhow::{Context, Result, bail};

use crate::oliveira::object_meshes;
use crate::repo::Repo;

/// The users' step.
const DT: f64 = 1.0 / 60.0;

/// Alternated repeats of the sheet timings (medians reported, min–max beside them).
const SHEET_REPEATS: usize = 3;

/// What the scale study runs.
#[derive(Debug, Clone, Copy, Default)]
pub struct ScaleOptions {
    /// The smaller sizes only (no 256² drape, no 256 × 256 sheet), for a quick look.
    pub quick: bool,
}

/// Runs `f` on a pool of `threads` threads (the parallel loops of anima use the pool they run in).
fn on_threads<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> Result<T> {
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build()?;
    Ok(pool.install(f))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn range(v: &[f64]) -> (f64, f64) {
    (v.iter().copied().fold(f64::INFINITY, f64::min), v.iter().copied().fold(0.0, f64::max))
}

fn rms(a: &[DVec3], b: &[DVec3]) -> f64 {
    (a.iter().zip(b).map(|(p, q)| p.distance_squared(*q)).sum::<f64>() / a.len() as f64).sqrt()
}

// ------------------------------------------------------------------------------------------ sheets

/// One timed sheet run: wall time, steps and the solver's profile.
#[derive(Debug, Clone, Copy)]
struct SheetRun {
    seconds: f64,
    steps: usize,
    profile: SolveProfile,
}

/// The standard sheet N × N, `steps` steps at 1/60 s by generalised-α.
fn sheet_run(n: usize, steps: usize) -> Result<SheetRun> {
    let spec = SheetSpec::standard(n);
    let mut sim = NetworkSim::new(spec.build()?, spec.positions(), Integrator::GeneralizedAlpha, DT)?;
    sim.stepper_mut().set_profiling(true);
    let started = Instant::now();
    sim.run(steps).with_context(|| format!("the standard sheet N = {n}"))?;
    let seconds = started.elapsed().as_secs_f64();
    Ok(SheetRun { seconds, steps, profile: sim.stepper_mut().profile().unwrap_or_default() })
}

/// A row of the cost table: a scene at a size, on some threads.
#[derive(Debug, Clone)]
struct CostRow {
    scene: &'static str,
    particles: usize,
    threads: usize,
    /// Seconds per step: median and range over the runs.
    per_step: f64,
    per_step_range: (f64, f64),
    newton: f64,
    cg: f64,
    /// The run stopped before its end (its wall-time budget): its cost is of the steps it took.
    cut_short: bool,
}

impl CostRow {
    fn micros_per_particle_step(&self) -> f64 {
        1e6 * self.per_step / self.particles as f64
    }
}

fn sheet_costs(sizes: &[usize], cores: usize) -> Result<Vec<CostRow>> {
    let mut rows = Vec::new();
    for &n in sizes {
        eprintln!("anima-lab: scale: standard sheet N = {n} …");
        let mut runs: Vec<Vec<SheetRun>> = vec![Vec::new(), Vec::new()];
        for _ in 0..SHEET_REPEATS {
            // Alternated: one core, then every core, so that the machine's load drifts over both alike.
            for (k, threads) in [1, cores].into_iter().enumerate() {
                runs[k].push(on_threads(threads, || sheet_run(n, 60))??);
            }
        }
        for (k, threads) in [1, cores].into_iter().enumerate() {
            let per_step: Vec<f64> = runs[k].iter().map(|r| r.seconds / r.steps as f64).collect();
            let p = runs[k][0].profile;
            let steps = runs[k][0].steps as f64;
            rows.push(CostRow {
                scene: "standard sheet",
                particles: n * n,
                threads,
                per_step: median(per_step.clone()),
                per_step_range: range(&per_step),
                newton: p.newton_iterations as f64 / steps,
                cg: p.solver_iterations as f64 / steps,
                cut_short: false,
            });
        }
    }
    Ok(rows)
}

// ------------------------------------------------------------------------------------------ drapes

/// One drape run, watched at every step.
#[derive(Debug, Clone)]
struct DrapeRun {
    name: String,
    particles: usize,
    threads: usize,
    steps: u64,
    /// Wall time of the steps alone, s (the watching below is not in it).
    seconds: f64,
    profile: SolveProfile,
    /// The self-collision response's time, s.
    self_seconds: f64,
    /// The most particles inside an obstacle and the most crossing edge–triangle pairs after any step.
    inside: usize,
    crossings: usize,
    max_speed: f64,
    max_strain: f64,
    max_kinetic: f64,
    final_kinetic: f64,
    error: Option<String>,
    /// Set when the run used up its wall-time budget before its 3 s: the simulated time it reached.
    cut_short: Option<f64>,
    /// Steps taken again in halves ([`OliveiraCloth::split_steps`]).
    split_steps: u64,
    final_x: Vec<DVec3>,
}

/// Wall time a 257² drape may take (the steps and the watching) before it is stopped and reported as
/// far as it got: the issue asks for its 3 s in 2 minutes, and an over-budget run must not hold the
/// study for an hour.
const BUDGET_257_S: f64 = 480.0;

/// The drape scene `assets/scenes/drape-{obstacle}-{v}.ron`, with gravity scaled by `gravity`, the
/// step `dt` and the friction model of [`friction_smoothing_override`] when one is set.
fn drape_scene(repo: &Repo, obstacle: &str, v: usize, gravity: f64, dt: f64) -> Result<LoadedOliveira> {
    let path = repo.assets(format!("scenes/drape-{obstacle}-{v}.ron"));
    let scene =
        anima_scene::load(&path, &Default::default()).with_context(|| format!("{}", path.display()))?;
    let anima_scene::Scene::Oliveira(mut loaded) = scene else { bail!("{} is not a drape", path.display()) };
    loaded.scene.gravity_m_s2 *= gravity;
    loaded.scene.time_step = anima_cloth::oliveira::StepRule::Fixed { dt_s: dt };
    if let Some(eps) = friction_smoothing_override() {
        loaded.scene.options.friction_smoothing_m_s = eps;
    }
    Ok(loaded)
}

fn drape_cloth(repo: &Repo, obstacle: &str, v: usize, gravity: f64, dt: f64) -> Result<OliveiraCloth> {
    Ok(drape_scene(repo, obstacle, v, gravity, dt)?.build()?)
}

/// The drapes' friction model for a comparison, overriding their scene files' (`FRICTION_SMOOTHING` in
/// the environment: a sliding speed ε in m/s for smoothed friction, or `none` for the stick and slide
/// regimes; `cargo run --release -p anima-lab --example scale_probe` documents it).
fn friction_smoothing_override() -> Option<Option<f64>> {
    let value = std::env::var("FRICTION_SMOOTHING").ok()?;
    Some(value.parse().ok())
}

/// Where [`converged`] caches its positions: one file per model (the friction too) and gravity.
fn converged_path(repo: &Repo, obstacle: &str, v: usize, gravity: f64, dt: f64) -> PathBuf {
    let smoothing =
        drape_scene(repo, obstacle, v, 1.0, dt).ok().and_then(|l| l.scene.options.friction_smoothing_m_s);
    let friction = smoothing.map(|eps| format!("-smooth{eps}")).unwrap_or_default();
    repo.cache(format!("scale/drape-{obstacle}-{v}-dt{:.0}-g{:+.0e}{friction}.f64", 1.0 / dt, gravity - 1.0))
}

/// Runs a drape to its 3 s; with `watch`, counts particles inside the obstacles and crossing pairs after
/// every step (outside the timed part).
fn drape_run(repo: &Repo, obstacle: &str, v: usize, gravity: f64, dt: f64, watch: bool) -> Result<DrapeRun> {
    let budget = if v > 129 { BUDGET_257_S } else { f64::INFINITY };
    let wall = Instant::now();
    let mut cloth = drape_cloth(repo, obstacle, v, gravity, dt)?;
    cloth.stepper_mut().set_profiling(true);
    let n_steps = (3.0 / dt).round() as u64;
    let mut run = DrapeRun {
        name: format!("{obstacle} {v}²"),
        particles: cloth.positions().len(),
        threads: anima_ode::parallel::threads(),
        steps: 0,
        seconds: 0.0,
        profile: SolveProfile::default(),
        self_seconds: 0.0,
        inside: 0,
        crossings: 0,
        max_speed: 0.0,
        max_strain: 0.0,
        max_kinetic: 0.0,
        final_kinetic: 0.0,
        error: None,
        cut_short: None,
        split_steps: 0,
        final_x: Vec::new(),
    };
    for _ in 0..n_steps {
        if wall.elapsed().as_secs_f64() > budget {
            run.cut_short = Some(cloth.time());
            break;
        }
        let started = Instant::now();
        let stepped = cloth.step();
        run.seconds += started.elapsed().as_secs_f64();
        if let Err(e) = stepped {
            run.error = Some(e.to_string());
            break;
        }
        run.steps += 1;
        run.max_speed = run.max_speed.max(cloth.max_speed());
        run.max_kinetic = run.max_kinetic.max(cloth.kinetic_energy());
        if watch {
            let x = cloth.positions();
            run.inside = run.inside.max(cloth.penetrations().len());
            run.crossings = run.crossings.max(count_self_intersections(x, cloth.triangles()));
            let s = cloth.springs();
            let strain = s
                .ends
                .iter()
                .zip(&s.rest_length)
                .map(|(&[i, j], l)| x[i as usize].distance(x[j as usize]) / l - 1.0)
                .fold(0.0, f64::max);
            run.max_strain = run.max_strain.max(strain);
        }
    }
    run.final_kinetic = cloth.kinetic_energy();
    run.profile = cloth.stepper_mut().profile().unwrap_or_default();
    run.split_steps = cloth.split_steps();
    run.self_seconds = cloth.self_collision_stats().map_or(0.0, |s| s.times.total().as_secs_f64());
    run.final_x = cloth.positions().to_vec();
    if watch {
        repo.write_figure(&format!("scale-drape-{obstacle}-{v}.png"), &drape_picture(&cloth, &run.name)?)?;
    }
    Ok(run)
}

/// The drape's final state over its obstacles.
fn drape_picture(cloth: &OliveiraCloth, name: &str) -> Result<anima_viz::Image> {
    let objects = object_meshes(cloth);
    let mut bounds = Aabb::from_points(cloth.positions().iter().copied().filter(|p| p.is_finite()));
    for (o, unbounded) in &objects {
        if !unbounded {
            bounds = bounds.union(o.aabb());
        }
    }
    let camera = Camera::framing(bounds, DVec3::new(-0.55, -1.0, -0.6), DVec3::Z, 35.0);
    let mut meshes: Vec<RenderMesh> =
        objects.iter().map(|(o, _)| RenderMesh::from_mesh(o, [150, 150, 160])).collect();
    meshes.push(RenderMesh::new(cloth.positions(), cloth.triangles(), [200, 70, 70]));
    let mut img = render(&meshes, &camera, &RenderSettings::new(800, 600))?;
    img.label(8, 6, &format!("{name} at t = {:.2} s", cloth.time()), 22.0)?;
    Ok(img)
}

// ------------------------------------------------------------------------------------- references

/// Positions at 3 s of a converged drape (step `dt`, gravity × `gravity`), cached under
/// `target/anima-lab/scale/`.
fn converged(repo: &Repo, obstacle: &str, v: usize, gravity: f64, dt: f64) -> Result<Vec<DVec3>> {
    let path = converged_path(repo, obstacle, v, gravity, dt);
    if let Some(x) = read_points(&path) {
        return Ok(x);
    }
    eprintln!("anima-lab: scale: converged {obstacle} {v}² at 1/{:.0} s, gravity × {gravity} …", 1.0 / dt);
    let run = drape_run(repo, obstacle, v, gravity, dt, false)?;
    if let Some(e) = run.error {
        bail!("the converged {obstacle} {v}² drape failed: {e}");
    }
    write_points(&path, &run.final_x)?;
    Ok(run.final_x)
}

fn write_points(path: &Path, points: &[DVec3]) -> Result<()> {
    std::fs::create_dir_all(path.parent().context("a cache folder")?)?;
    let bytes: Vec<u8> = points.iter().flat_map(|p| p.to_array()).flat_map(|v| v.to_le_bytes()).collect();
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, bytes)?;
    std::fs::rename(&tmp, path)?;
    Ok(())
}

fn read_points(path: &Path) -> Option<Vec<DVec3>> {
    let bytes = std::fs::read(path).ok()?;
    if bytes.len() % 24 != 0 {
        return None;
    }
    let v: Vec<f64> =
        bytes.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
    Some(v.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect())
}

fn centre(x: &[DVec3]) -> DVec3 {
    x.iter().sum::<DVec3>() / x.len() as f64
}

// ------------------------------------------------------------------------------------------ peers

/// The peers' Python (`ANIMA_PEERS_PYTHON`), when set.
fn peers_python() -> Option<PathBuf> {
    std::env::var_os("ANIMA_PEERS_PYTHON").map(PathBuf::from)
}

/// One peer run's `RESULT` line.
fn peer(repo: &Repo, python: &Path, script: &str, args: &[String]) -> Result<serde_json::Value> {
    let dir = repo.root().join("bench/peers");
    let out = Command::new(python)
        .arg(dir.join(script))
        .args(args)
        .current_dir(&dir)
        .output()
        .with_context(|| format!("running {script}"))?;
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout.lines().find_map(|l| l.strip_prefix("RESULT ")).with_context(|| {
        format!("{script} {args:?} printed no RESULT line: {}", String::from_utf8_lossy(&out.stderr))
    })?;
    Ok(serde_json::from_str(line)?)
}

/// Positions a peer saved with `--save` (NumPy's `.npy`, float64, little-endian, C order).
fn read_npy(path: &Path) -> Result<Vec<DVec3>> {
    let bytes = std::fs::read(path)?;
    anyhow::ensure!(
        bytes.len() > 10 && &bytes[..6] == b"\x93NUMPY",
        "{} is not an .npy file",
        path.display()
    );
    let header_len = if bytes[6] == 1 {
        u16::from_le_bytes([bytes[8], bytes[9]]) as usize + 10
    } else {
        u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize + 12
    };
    let header = String::from_utf8_lossy(&bytes[..header_len]);
    anyhow::ensure!(
        header.contains("<f8") && header.contains("False"),
        "{}: not little-endian f64 in C order",
        path.display()
    );
    let v: Vec<f64> = bytes[header_len..]
        .chunks_exact(8)
        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes")))
        .collect();
    Ok(v.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect())
}

// ----------------------------------------------------------------------------------------- report

/// Runs the study and writes `docs/benchmarks-scale.md`.
pub fn run(repo: &Repo, options: ScaleOptions) -> Result<()> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let machine = crate::bench::machine();
    let sizes: &[usize] = if options.quick { &[65, 129] } else { &[65, 129, 257] };
    let sheets: &[usize] = if options.quick { &[64, 128] } else { &[64, 128, 256] };
    let mut doc = String::new();
    let _ = write!(
        doc,
        "# Cloth at the size users simulate\n\n_Generated by `cargo xtask bench --scale`{} on {}; do not edit. Machine: \
         {machine}, {cores} cores; f64, release build._\n\n\
         The scenes: the standard sheet of `benchmarks.md` at N = {} (`assets/scenes/standard-sheet-N.ron`) and its \
         drapes, a 1 m cloth of V × V vertices with the material of Oliveira 2013 Table 5.5 falling onto the Stanford \
         Bunny or a sphere on a floor (`assets/scenes/drape-bunny-V.ron`, `drape-sphere-V.ron`, V = {}), 3 s. Every \
         run is generalised-α at 1/60 s (the step users take); the drapes answer contact inside its solve and keep \
         the cloth from passing through itself with the modern response. Real time is 16.7 ms a step.\n\n",
        if options.quick { " --quick" } else { "" },
        crate::report::today(),
        sheets.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", "),
        sizes.iter().map(|n| n.to_string()).collect::<Vec<_>>().join(", "),
    );

    // The cost of a step per particle, on one core and on every core.
    let mut costs = sheet_costs(sheets, cores)?;
    let mut drapes = Vec::new();
    for &v in sizes {
        for obstacle in ["bunny", "sphere"] {
            eprintln!("anima-lab: scale: {obstacle} drape {v}² on {cores} threads …");
            let run = on_threads(cores, || drape_run(repo, obstacle, v, 1.0, DT, true))??;
            if obstacle == "bunny" && v <= 129 {
                eprintln!("anima-lab: scale: {obstacle} drape {v}² on one thread …");
                let one = on_threads(1, || drape_run(repo, obstacle, v, 1.0, DT, false))??;
                costs.push(drape_cost(&one));
            }
            if obstacle == "bunny" {
                costs.push(drape_cost(&run));
            }
            drapes.push(run);
        }
    }
    doc.push_str(&cost_section(repo, &costs, cores)?);
    doc.push_str(&drape_section(&drapes, sizes));
    // A section that fails says so in the report instead of losing the others' hours.
    let or_failure = |title: &str, section: Result<String>| {
        section.unwrap_or_else(|e| {
            format!(
                "## {title}

Not measured in this run: {e:#}

"
            )
        })
    };
    doc.push_str(&or_failure("How far a 1/60 s drape lies from the converged one", error_section(repo)));
    doc.push_str(&or_failure("Beside the peers", peers_section(repo, &drapes)));
    doc.push_str(&or_failure("The explicit sheet's largest stable step", stability_section(sheets)));
    repo.write_text("docs/benchmarks-scale.md", &doc)
}

fn drape_cost(run: &DrapeRun) -> CostRow {
    let steps = run.steps.max(1) as f64;
    let per_step = run.seconds / steps;
    CostRow {
        scene: "Bunny drape",
        particles: run.particles,
        threads: run.threads,
        per_step,
        per_step_range: (per_step, per_step),
        newton: run.profile.newton_iterations as f64 / steps,
        cg: run.profile.solver_iterations as f64 / steps,
        cut_short: run.cut_short.is_some(),
    }
}

fn cost_section(repo: &Repo, rows: &[CostRow], cores: usize) -> Result<String> {
    let mut out = String::from(
        "## What a step costs per particle\n\nWall time of the steps (the drapes' whole 3 s, watched from outside the \
         timing; the sheet's 1 s, the median of three runs alternated with the other thread count, min–max beside \
         it) over steps and particles. The implicit step's products, sums, preconditioner and spring assembly run \
         on every core with the same bits on any thread count (`anima_ode::parallel`).\n\n\
         | scene | particles | threads | ms per step | µs per particle-step | Newton / step | CG / step |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let (lo, hi) = r.per_step_range;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {:.1} ({:.1}–{:.1}) | {:.2} | {:.2} | {:.1} |",
            r.scene,
            r.particles,
            r.threads,
            1e3 * r.per_step,
            1e3 * lo,
            1e3 * hi,
            r.micros_per_particle_step(),
            r.newton,
            r.cg
        );
    }
    let mut plot = LinePlot::new("Cost of a 1/60 s step per particle", "particles", "µs per particle-step");
    plot.log_x = true;
    for scene in ["standard sheet", "Bunny drape"] {
        for threads in [1, cores] {
            let points: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.scene == scene && r.threads == threads)
                .map(|r| (r.particles as f64, r.micros_per_particle_step()))
                .collect();
            if !points.is_empty() {
                let label = format!("{scene}, {threads} thread{}", if threads == 1 { "" } else { "s" });
                plot.series.push(Series::new(label, points, SeriesStyle::LineWithMarkers));
            }
        }
    }
    repo.write_figure("scale-cost.png", &plot.render(900, 560)?)?;
    out.push_str("\n![cost per particle-step](figures/scale-cost.png)\n\n");
    for scene in ["standard sheet", "Bunny drape"] {
        // A run cut short paid for the steps it took, not for the drape: the comparison leaves it out.
        let on_all: Vec<&CostRow> =
            rows.iter().filter(|r| r.scene == scene && r.threads == cores && !r.cut_short).collect();
        if let (Some(small), Some(large)) = (on_all.first(), on_all.last())
            && large.particles > small.particles
        {
            let _ = writeln!(
                out,
                "{scene} on {cores} threads: {:.2} µs per particle-step at {} particles, {:.2} at {}: {:.2} times as much \
                 per particle at {:.0} times the size.\n",
                small.micros_per_particle_step(),
                small.particles,
                large.micros_per_particle_step(),
                large.particles,
                large.micros_per_particle_step() / small.micros_per_particle_step(),
                large.particles as f64 / small.particles as f64
            );
        }
    }
    Ok(out)
}

fn drape_section(runs: &[DrapeRun], sizes: &[usize]) -> String {
    let mut out = String::from(
        "## The drapes, step by step\n\nEvery run watched after every step: particles strictly inside an obstacle, \
         crossing edge–triangle pairs of the cloth (`anima_geom::count_self_intersections`), speeds, the springs' \
         strain and the kinetic energy. Where a step's time goes: the force and system assembly, the preconditioner's \
         set-up, the linear solves, contact detection and its active set, and the self-collision response. \
         \"Split\": steps taken again in halves because the self-collision fail-safe froze a zone that would have \
         moved more than a quarter of the shortest spring (`anima_cloth::oliveira::MAX_SPLITS`).\n\n\
         | drape | particles | threads | simulated in | ms per step | assembly | set-up | solves | contact | self-collision | \
         split | most inside | most crossings | fastest (m/s) | most strain | largest / final E_k (J) |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut notes = Vec::new();
    for r in runs {
        let steps = r.steps.max(1) as f64;
        let ms = |s: f64| format!("{:.1}", 1e3 * s / steps);
        let p = &r.profile;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {:.2} s in {:.1} s | {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2} | {:.1} % | {:.3} / {:.2e} |",
            r.name,
            r.particles,
            r.threads,
            r.steps as f64 * DT,
            r.seconds,
            ms(r.seconds),
            ms(p.assembly_s),
            ms(p.setup_s),
            ms(p.solve_s),
            ms(p.contact_s),
            ms(r.self_seconds),
            r.split_steps,
            r.inside,
            r.crossings,
            r.max_speed,
            100.0 * r.max_strain,
            r.max_kinetic,
            r.final_kinetic
        );
        if let Some(e) = &r.error {
            notes.push(format!("**{} stopped:** {e}", r.name));
        }
        if let Some(t) = r.cut_short {
            notes.push(format!(
                "**{} did not finish:** stopped at t = {t:.2} s of 3 s when its {BUDGET_257_S:.0} s of wall time \
                 (steps and watching) were spent; its row covers the steps it took.",
                r.name
            ));
        }
    }
    out.push('\n');
    for note in notes {
        let _ = write!(out, "{note}\n\n");
    }
    for &v in sizes {
        let _ = write!(
            out,
            "![Bunny {v}²](figures/scale-drape-bunny-{v}.png) ![sphere {v}²](figures/scale-drape-sphere-{v}.png)\n\n"
        );
    }
    out
}

fn error_section(repo: &Repo) -> Result<String> {
    let mut out = String::from(
        "## How far a 1/60 s drape lies from the converged one\n\nThe same model at 1/960 s is the reference; two more \
         runs at 1/960 s with gravity × (1 ± 10⁻⁹) span the band within which converged runs of this chaotic motion \
         (a cloth that folds and slides) disagree. The 1/60 s error is stated beside that band, and in bands; the \
         centre of mass converges where positions do not.\n\n\
         | drape | step | RMS distance to the reference | band (RMS between the two nudged references) | bands | centre of mass off by |\n\
         |---|---|---|---|---|---|\n",
    );
    let fine = 1.0 / 960.0;
    for obstacle in ["bunny", "sphere"] {
        let v = 65;
        let reference = converged(repo, obstacle, v, 1.0, fine)?;
        let up = converged(repo, obstacle, v, 1.0 + 1e-9, fine)?;
        let down = converged(repo, obstacle, v, 1.0 - 1e-9, fine)?;
        let band = rms(&up, &down);
        for dt in [DT, 1.0 / 240.0] {
            let run = drape_run(repo, obstacle, v, 1.0, dt, false)?;
            if let Some(e) = &run.error {
                bail!("the {obstacle} {v}² drape at 1/{:.0} s failed: {e}", 1.0 / dt);
            }
            let error = rms(&run.final_x, &reference);
            let _ = writeln!(
                out,
                "| {obstacle} {v}² | 1/{:.0} s | {:.1} mm | {:.1} mm | {:.1} | {:.1} mm |",
                1.0 / dt,
                1e3 * error,
                1e3 * band,
                error / band.max(f64::MIN_POSITIVE),
                1e3 * centre(&run.final_x).distance(centre(&reference))
            );
        }
    }
    out.push('\n');
    Ok(out)
}

fn peers_section(repo: &Repo, drapes: &[DrapeRun]) -> Result<String> {
    let mut out = String::from("## Beside the peers\n\n");
    let Some(python) = peers_python() else {
        out.push_str(
            "Not measured in this run: `ANIMA_PEERS_PYTHON` names no Python with the peers installed (`bench/peers/README.md`).\n\n",
        );
        return Ok(out);
    };
    out.push_str(
        "The drapes in Newton 1.8's VBD (implicit Euler by vertex block descent, Warp's CPU device, 10 iterations) and \
         MuJoCo 4.0's flex (its implicit `discrete` step), by the scripts of `bench/peers/` with the material mapped as \
         their README says, at 1/60 s. Each peer run is timed between two runs of anima's same drape, one right before \
         and one right after it: anima's cost is their mean (the two beside it), and the speed-up is the peer's \
         over it (over each of the two beside it). Their wall time is their loop alone, as anima's. A peer's error \
         is against a converged run of its own model (1/600 s).\n\n\
         | drape | simulator | ms per step | anima's ms per step | anima's speed-up | most inside | crossings | mean strain | error (own 1/600 s) |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    let save = |name: &str| repo.cache(format!("scale/peer-{name}.npy"));
    for run in drapes.iter().filter(|r| r.particles <= 129 * 129) {
        let (obstacle, v) = run.name.split_once(' ').context("a drape name")?;
        let v = v.trim_end_matches('²');
        for (label, script, extra) in [
            ("Newton VBD, self-contact off", "drape_newton.py", vec!["--no-self-contact".to_owned()]),
            ("Newton VBD, self-contact on", "drape_newton.py", vec![]),
            ("MuJoCo flex", "drape_mujoco.py", vec!["--bunny-collision".to_owned(), "prisms".to_owned()]),
        ] {
            if label.contains("contact on") && (v != "65" || obstacle != "bunny") {
                // 20 times the cost of self-contact off (2 s a step at 65²): the Bunny at 65² only.
                continue;
            }
            let tag = format!("{}-{obstacle}-{v}", script.trim_end_matches(".py"));
            let mut args = vec![v.to_owned(), "--obstacle".to_owned(), obstacle.to_owned()];
            args.extend(extra.iter().cloned());
            if script == "drape_mujoco.py" && obstacle != "bunny" {
                args.truncate(3);
            }
            eprintln!("anima-lab: scale: {label} on the {obstacle} {v}² drape …");
            let mut at_60 = args.clone();
            at_60.extend(["--save".to_owned(), save(&format!("{tag}-60")).display().to_string()]);
            // anima's same drape timed right before and right after the peer, so that the ratio compares
            // two runs on the machine as it was then (it is shared and noisy).
            let v_n: usize = v.parse().context("a drape size")?;
            let ours_before = drape_run(repo, obstacle, v_n, 1.0, DT, false)?;
            let r = peer(repo, &python, script, &at_60)?;
            let ours_after = drape_run(repo, obstacle, v_n, 1.0, DT, false)?;
            let error = if v == "65" && !label.contains("contact on") {
                let mut fine = args.clone();
                fine.insert(1, (1.0f64 / 600.0).to_string());
                let fine_path = save(&format!("{tag}-600"));
                if !fine_path.exists() {
                    fine.extend(["--save".to_owned(), fine_path.display().to_string()]);
                    peer(repo, &python, script, &fine)?;
                }
                let (a, b) = (read_npy(&save(&format!("{tag}-60")))?, read_npy(&fine_path)?);
                format!("{:.0} mm", 1e3 * rms(&a, &b))
            } else {
                "–".to_owned()
            };
            let ms = r["ms_per_step"].as_f64().unwrap_or(f64::NAN);
            let per_step = |d: &DrapeRun| 1e3 * d.seconds / d.steps.max(1) as f64;
            let (a, b) = (per_step(&ours_before), per_step(&ours_after));
            let ours = 0.5 * (a + b);
            let _ = writeln!(
                out,
                "| {obstacle} {v}² | {label} | {ms:.0} | {ours:.1} ({:.1}–{:.1}) | {:.1}× ({:.1}–{:.1}×) | {} | {} | {:.1} % | {error} |",
                a.min(b),
                a.max(b),
                ms / ours,
                ms / a.max(b),
                ms / a.min(b),
                r["inside"]["total"],
                r["crossing_pairs"],
                100.0 * r["mean_abs_strain"].as_f64().unwrap_or(f64::NAN),
            );
        }
    }
    out.push('\n');
    Ok(out)
}

fn stability_section(sheets: &[usize]) -> Result<String> {
    let mut out = String::from(
        "## The explicit sheet's largest stable step, estimated and measured\n\nSymplectic Euler on the standard \
         sheet. The estimate is what `anima run` warns by: ω_max by power iteration, the damping ratio ζ of that mode \
         from the springs' dampers, and the damped oscillator's stability limit h·ω ≤ 2(√(1 + ζ²) − ζ) \
         (`anima_ode::stability::damped_stability_limit`); the undamped limit 2/ω_max beside it. Measured: the \
         largest step (bisection to 2 %) at which 0.2 s stays inside the run's bounds.\n\n\
         | N | ω_max (rad/s) | ζ | undamped 2/ω_max | damped estimate | measured |\n|---|---|---|---|---|---|\n",
    );
    for &n in sheets.iter().chain(std::iter::once(&32)).collect::<std::collections::BTreeSet<_>>() {
        let spec = SheetSpec::standard(n);
        let mut net = spec.build()?;
        let x = spec.positions();
        let frozen = net.pinned().to_vec();
        let (omega, zeta) = anima_ode::stability::max_frequency_and_damping(
            &mut net,
            0.0,
            &x,
            &vec![DVec3::ZERO; x.len()],
            &frozen,
            200,
        );
        let limit = anima_ode::stability::damped_stability_limit(Integrator::SymplecticEuler, zeta) / omega;
        let stable = |dt: f64| {
            let Ok(mut sim) = spec
                .build()
                .and_then(|net| NetworkSim::new(net, spec.positions(), Integrator::SymplecticEuler, dt))
            else {
                return false;
            };
            sim.run((0.2 / dt).round() as usize).is_ok()
        };
        let (mut lo, mut hi) = (0.5 * limit, 2.0 * limit);
        if !stable(lo) {
            lo = 0.0;
        }
        while hi - lo > 0.02 * hi {
            let mid = 0.5 * (lo + hi);
            if stable(mid) { lo = mid } else { hi = mid }
        }
        let _ = writeln!(
            out,
            "| {n} | {omega:.4e} | {zeta:.2} | {:.3e} s | {limit:.3e} s | {lo:.3e} s ({:+.0} %) |",
            2.0 / omega,
            100.0 * (lo / limit - 1.0)
        );
    }
    out.push('\n');
    Ok(out)
}

/// A profile's phases in ms per step over `steps` steps (the probes' wording).
fn phases(p: &SolveProfile, steps: f64) -> String {
    let ms = |s: f64| 1e3 * s / steps;
    format!(
        "assembly {:.1}, set-up {:.1}, solves {:.1}, contact {:.1}",
        ms(p.assembly_s),
        ms(p.setup_s),
        ms(p.solve_s),
        ms(p.contact_s)
    )
}

/// A quick look at one drape for whoever tunes its step (`cargo run --release -p anima-lab --example
/// scale_probe`): `seconds` of the drape `obstacle` at `v`² (gravity × `gravity`, `regime` Newton
/// iterations for contacts that change regime when given) on the pool it runs in, with where the time
/// went and, for a 3 s run of a size whose converged references are cached, its error beside their band
/// (with `references`, the references are computed first when missing).
pub fn probe(
    repo: &Repo,
    obstacle: &str,
    v: usize,
    seconds: f64,
    gravity: f64,
    regime: Option<usize>,
    references: bool,
) -> Result<String> {
    let wall = Instant::now();
    let mut cloth = drape_cloth(repo, obstacle, v, gravity, DT)?;
    cloth.stepper_mut().set_profiling(true);
    if let Some(k) = regime {
        cloth.stepper_mut().set_regime_iterations(k);
    }
    let n_steps = (seconds / DT).round() as u64;
    let mut stepping = 0.0;
    let (mut inside, mut crossings, mut fastest) = (0, 0, 0.0f64);
    for k in 0..n_steps {
        let started = Instant::now();
        cloth.step().with_context(|| format!("step {k}"))?;
        stepping += started.elapsed().as_secs_f64();
        inside = inside.max(cloth.penetrations().len());
        fastest = fastest.max(cloth.max_speed());
        if k % 10 == 9 || k + 1 == n_steps {
            crossings = crossings.max(count_self_intersections(cloth.positions(), cloth.triangles()));
        }
    }
    let p = cloth.stepper_mut().profile().unwrap_or_default();
    let steps = n_steps.max(1) as f64;
    let ms = |s: f64| 1e3 * s / steps;
    let stats = cloth.self_collision_stats().unwrap_or_default();
    let times = stats.times;
    let self_s = times.total().as_secs_f64();
    let mut out = format!(
        "{obstacle} {v}², {seconds} s on {} threads: {:.1} ms per step ({}, \
         self-collision {:.1}: broad phase {:.1}, proximity {:.1}, impacts {:.1}, zones {:.1}); Newton {:.2}, CG {:.1}, coarse set-ups {:.2} per step; most inside {inside}, \
         most crossings {crossings} (every 10th step), fastest {fastest:.2} m/s; self-collision repulsions {}, impacts {}; wall {:.1} s",
        anima_ode::parallel::threads(),
        ms(stepping),
        phases(&p, steps),
        ms(self_s),
        ms(times.broad_phase.as_secs_f64()),
        ms(times.proximity.as_secs_f64()),
        ms(times.impacts.as_secs_f64()),
        ms(times.zones.as_secs_f64()),
        p.newton_iterations as f64 / steps,
        p.solver_iterations as f64 / steps,
        p.factorizations as f64 / steps,
        stats.repulsions,
        stats.impacts,
        wall.elapsed().as_secs_f64(),
    );
    if references {
        for g in [1.0, 1.0 + 1e-9, 1.0 - 1e-9] {
            converged(repo, obstacle, v, g, 1.0 / 960.0)?;
        }
    }
    let cached = |g: f64| read_points(&converged_path(repo, obstacle, v, g, 1.0 / 960.0));
    if (seconds - 3.0).abs() < 1e-9
        && let (Some(reference), Some(up), Some(down)) = (cached(1.0), cached(1.0 + 1e-9), cached(1.0 - 1e-9))
    {
        let (error, band) = (rms(cloth.positions(), &reference), rms(&up, &down));
        let _ = write!(
            out,
            "\nRMS error {:.1} mm against the 1/960 s reference, band {:.1} mm ({:.1} bands), centre of mass off by {:.1} mm",
            1e3 * error,
            1e3 * band,
            error / band,
            1e3 * centre(cloth.positions()).distance(centre(&reference))
        );
    }
    Ok(out)
}

/// The drape `obstacle` at `v`² for `seconds` (gravity × `gravity`, `regime` Newton iterations for
/// contacts that change regime when given), remeshed after every step by the sizing field down to
/// edges of `min_edge_m` (`MIN_EDGE` of the `scale_probe` example): the step's cost and where it went
/// (the remeshing passes with the cloth rebuilt on each new mesh, and what nothing times), the mesh at
/// the end, and the crossing pairs and particles inside an object after every step.
pub fn adaptive_probe(
    repo: &Repo,
    obstacle: &str,
    v: usize,
    seconds: f64,
    gravity: f64,
    regime: Option<usize>,
    min_edge_m: f64,
) -> Result<String> {
    let mut loaded = drape_scene(repo, obstacle, v, gravity, DT)?;
    let remesher =
        anima_scene::oliveira::Remesher::SizingField { min_edge_m, interval_s: DT, refuse_crossings: true };
    // Checked here as a scene file's remesher is when it loads: a bad edge is an error, not a static run.
    remesher.method().map_err(|why| anyhow::anyhow!("MIN_EDGE: {why}"))?;
    loaded.remesher = Some(remesher);
    let mut cloth = loaded.build()?;
    cloth.stepper_mut().set_profiling(true);
    if let Some(k) = regime {
        cloth.stepper_mut().set_regime_iterations(k);
    }
    let mut cloth = loaded.with_remesher(cloth);
    let n_steps = (seconds / DT).round().max(1.0) as u64;
    let (mut stepping, mut inside, mut crossings) = (0.0, 0, 0);
    for k in 0..n_steps {
        let started = Instant::now();
        cloth.step().with_context(|| format!("step {k}"))?;
        stepping += started.elapsed().as_secs_f64();
        let c = cloth.cloth();
        inside = inside.max(c.penetrations().len());
        crossings = crossings.max(count_self_intersections(c.positions(), c.triangles()));
    }
    let self_s = cloth.cloth().self_collision_stats().unwrap_or_default().times.total().as_secs_f64();
    let p = cloth.stepper_mut().profile().unwrap_or_default();
    let ms = |s: f64| 1e3 * s / n_steps as f64;
    // The passes (the cloth rebuilt on each new mesh included), and what nothing above times.
    let remeshing = cloth.stats().wall_s;
    let rest = stepping - p.assembly_s - p.setup_s - p.solve_s - p.contact_s - self_s - remeshing;
    let c = cloth.cloth();
    Ok(format!(
        "{obstacle} {v}² remeshed to edges of {min_edge_m} m, {seconds} s on {} threads: {:.1} ms per step \
         ({}, self-collision {:.1}, remeshing {:.1}, the rest {:.1}); \
         Newton {:.2}, CG {:.1} per step; {} particles and {} faces at the end; most inside {inside}, most \
         crossings {crossings} (after every step)",
        anima_ode::parallel::threads(),
        ms(stepping),
        phases(&p, n_steps as f64),
        ms(self_s),
        ms(remeshing),
        ms(rest),
        p.newton_iterations as f64 / n_steps as f64,
        p.solver_iterations as f64 / n_steps as f64,
        c.positions().len(),
        c.triangles().len(),
    ))
}

/// The standard sheet N × N for `seconds` at 1/60 s by generalised-α on the pool it runs in, with where
/// a step's time went (`OBSTACLE=sheet V=N` of the `scale_probe` example).
pub fn sheet_probe(n: usize, seconds: f64) -> Result<String> {
    let steps = (seconds / DT).round().max(1.0) as usize;
    let SheetRun { seconds: wall, profile: p, .. } = sheet_run(n, steps)?;
    let per = |s: f64| 1e3 * s / steps as f64;
    Ok(format!(
        "standard sheet {n}², {seconds} s on {} threads: {:.2} ms per step, {:.3} µs per particle-step \
         (assembly {:.2}, set-up {:.2}, solves {:.2}); Newton {:.2}, CG {:.2}, coarse set-ups {:.2} per step",
        anima_ode::parallel::threads(),
        per(wall),
        1e6 * wall / (steps as f64 * (n * n) as f64),
        per(p.assembly_s),
        per(p.setup_s),
        per(p.solve_s),
        p.newton_iterations as f64 / steps as f64,
        p.solver_iterations as f64 / steps as f64,
        p.factorizations as f64 / steps as f64,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn npy_files_read_back() {
        let dir = std::env::temp_dir().join(format!("anima-npy-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let header = "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }";
        let mut bytes = b"\x93NUMPY\x01\x00".to_vec();
        let pad = 64 - (10 + header.len() + 1) % 64;
        let full = format!("{header}{}\n", " ".repeat(pad));
        bytes.extend((full.len() as u16).to_le_bytes());
        bytes.extend(full.as_bytes());
        for v in [1.0f64, 2.0, 3.0, -4.0, 5.5, 6.25] {
            bytes.extend(v.to_le_bytes());
        }
        let path = dir.join("x.npy");
        std::fs::write(&path, bytes).unwrap();
        assert_eq!(read_npy(&path).unwrap(), vec![DVec3::new(1.0, 2.0, 3.0), DVec3::new(-4.0, 5.5, 6.25)]);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
