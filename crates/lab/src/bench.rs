//! `cargo xtask bench`: speed against error for every integrator, the largest stable steps, a stability
//! map, and the standard sheet beside the peers of `benchmarks.md`. Writes `docs/benchmarks.md` and its
//! plots in `docs/figures/`.

use std::fmt::Write as _;
use std::time::Instant;

use anima_cloth::flex3d::mass_spring::SingleSpring;
use anima_cloth::network_sim::NetworkSim;
use anima_cloth::spring_net::SheetSpec;
use anima_geom::DVec3;
use anima_ode::stability::{max_frequency, stability_limit};
use anima_ode::{Integrator, LinearSolver, State, StepControl, Stepper, integrate};
use anima_viz::{LinePlot, Series, SeriesStyle};
use anyhow::{Context, Result};

use crate::repo::Repo;

/// One measured run: wall time (s), error, step (or tolerance) used.
#[derive(Debug, Clone, Copy)]
struct Point {
    knob: f64,
    /// Wall time: the median of [`REPEATS`] runs when one run takes less than [`REPEAT_BELOW_S`].
    seconds: f64,
    /// The fastest and slowest of those runs (both `seconds` for a run timed once).
    seconds_range: (f64, f64),
    error: f64,
    /// Distance of the final centre of mass from the reference value of `benchmarks.md`, m.
    com_error: f64,
}

/// One integrator (with its linear solver, for the implicit ones) on one scene.
#[derive(Debug, Clone)]
struct Curve {
    integrator: Integrator,
    solver: Option<LinearSolver>,
    points: Vec<Point>,
    largest_stable: Option<f64>,
    /// The run at the largest stable step.
    at_largest: Option<Point>,
}

impl Curve {
    fn new(integrator: Integrator) -> Self {
        Self { integrator, solver: None, points: vec![], largest_stable: None, at_largest: None }
    }

    /// The integrator's name, with `+cholesky` when an implicit method solves directly.
    fn label(&self) -> String {
        match self.solver {
            Some(s @ LinearSolver::SparseCholesky) => format!("{}+{}", self.integrator, s.name()),
            _ => self.integrator.to_string(),
        }
    }
}

// ------------------------------------------------------------------------------------- sheets

/// A sheet scene of the study: its spec and duration, and the reference centre of mass.
struct BenchSheet {
    name: &'static str,
    title: String,
    spec: SheetSpec,
    duration: f64,
    /// The centre of mass at the end given by `benchmarks.md`, where it gives one.
    com_reference: Option<DVec3>,
}

/// Runs a sheet; returns final positions and wall time, or None if it went non-finite or wild.
fn run_sheet(
    scene: &BenchSheet,
    integrator: Integrator,
    solver: Option<LinearSolver>,
    control: StepControl,
) -> Option<(Vec<DVec3>, f64)> {
    let configure = |stepper: &mut Stepper<DVec3>| {
        if let Some(s) = solver {
            stepper.set_linear_solver(s);
        }
    };
    run_sheet_from(scene, scene.spec.positions(), integrator, control, &configure)
}

/// [`run_sheet`] from the positions `start` (at rest), with the stepper set up by `configure`.
fn run_sheet_from(
    scene: &BenchSheet,
    start: Vec<DVec3>,
    integrator: Integrator,
    control: StepControl,
    configure: &dyn Fn(&mut Stepper<DVec3>),
) -> Option<(Vec<DVec3>, f64)> {
    let net = scene.spec.build().ok()?;
    let n = net.n_particles();
    let dt = match control {
        StepControl::Constant { dt } => dt,
        StepControl::Adaptive { dt_initial, .. } => dt_initial,
    };
    let mut sim = NetworkSim::new(net, start, integrator, dt).ok()?;
    configure(sim.stepper_mut());
    let start = Instant::now();
    let ok = match control {
        StepControl::Constant { dt } => {
            let steps = (scene.duration / dt).round() as usize;
            let chunk = (steps / 20).max(1);
            let mut done = 0;
            let mut ok = true;
            while done < steps && ok {
                let k = chunk.min(steps - done);
                ok = sim.run(k).is_ok() && sim.state.v.iter().all(|v| v.length() < 100.0);
                done += k;
            }
            ok
        }
        adaptive => {
            let mut stepper = Stepper::new(integrator, n);
            configure(&mut stepper);
            let mut state = sim.state.clone();
            let mut scratch = State::zeros(n);
            let r = integrate(
                &mut sim.network,
                &mut stepper,
                adaptive,
                0.0,
                scene.duration,
                &mut state,
                &mut scratch,
                |_, _| {},
            );
            sim.state = state;
            r.is_ok() && sim.state.v.iter().all(|v| v.length() < 100.0)
        }
    };
    let seconds = start.elapsed().as_secs_f64();
    ok.then_some((sim.state.x, seconds))
}

/// The converged reference: RK4 at 10⁻⁵ s, cached under target/.
fn reference(repo: &Repo, scene: &BenchSheet) -> Result<Vec<DVec3>> {
    let path = repo.cache(format!("bench/{}-rk4-1e-5.bin", scene.name));
    if let Ok(bytes) = std::fs::read(&path) {
        let vals: Vec<f64> =
            bytes.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
        if vals.len() == 3 * scene.spec.n * scene.spec.n {
            return Ok(vals.chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect());
        }
    }
    eprintln!("anima-lab: computing the reference for {} (RK4, 1e-5 s) …", scene.name);
    let (x, secs) = run_sheet(scene, Integrator::Rk4, None, StepControl::Constant { dt: 1e-5 })
        .context("reference diverged")?;
    eprintln!("anima-lab: reference took {secs:.1} s");
    std::fs::create_dir_all(path.parent().expect("a cache folder"))?;
    let bytes: Vec<u8> = x.iter().flat_map(|p| p.to_array()).flat_map(f64::to_le_bytes).collect();
    std::fs::write(&path, bytes)?;
    Ok(x)
}

/// A run's wall time, s: the median, and the fastest and slowest run.
type Timing = (f64, (f64, f64));

/// A run's point: its wall time and its errors.
fn measure(
    scene: &BenchSheet,
    knob: f64,
    (seconds, seconds_range): Timing,
    x: &[DVec3],
    reference: &[DVec3],
) -> Point {
    let com = scene.spec.build().expect("a benchmark sheet is valid").centre_of_mass(x);
    let com_error = scene.com_reference.map_or(f64::NAN, |r| com.distance(r));
    Point { knob, seconds, seconds_range, error: rms(x, reference), com_error }
}

/// Runs shorter than this are timed [`REPEATS`] times (on a shared machine one short run can be a tenth
/// off); longer ones once, since the sweep would otherwise take hours.
const REPEAT_BELOW_S: f64 = 1.0;

/// Timings of a short run: the median is reported, with the fastest and slowest.
const REPEATS: usize = 5;

/// Runs a sheet as [`run_sheet`] does; a run shorter than [`REPEAT_BELOW_S`] is repeated (the same
/// bits each time) and its wall time is the median of [`REPEATS`], with their range.
fn timed_run(
    scene: &BenchSheet,
    integrator: Integrator,
    solver: Option<LinearSolver>,
    control: StepControl,
) -> Option<(Vec<DVec3>, Timing)> {
    let (x, first) = run_sheet(scene, integrator, solver, control)?;
    if first >= REPEAT_BELOW_S {
        return Some((x, (first, (first, first))));
    }
    let mut times = vec![first];
    for _ in 1..REPEATS {
        times.push(run_sheet(scene, integrator, solver, control)?.1);
    }
    times.sort_by(f64::total_cmp);
    Some((x, (times[times.len() / 2], (times[0], times[times.len() - 1]))))
}

fn rms(a: &[DVec3], b: &[DVec3]) -> f64 {
    (a.iter().zip(b).map(|(p, q)| p.distance_squared(*q)).sum::<f64>() / a.len() as f64).sqrt()
}

/// Largest constant step (log bisection between 10⁻⁶ and 0.1 s) at which the sheet stays finite and slow
/// for its whole duration.
fn largest_stable_step(scene: &BenchSheet, integrator: Integrator) -> f64 {
    let stable = |dt: f64| run_sheet(scene, integrator, None, StepControl::Constant { dt }).is_some();
    let (mut lo, mut hi) = (1e-6f64, 0.1f64);
    if stable(hi) {
        return hi;
    }
    for _ in 0..8 {
        let mid = (lo * hi).sqrt();
        if stable(mid) { lo = mid } else { hi = mid }
    }
    lo
}

fn sheet_curves(repo: &Repo, scene: &BenchSheet, quick: bool) -> Result<(Vec<Curve>, Vec<DVec3>)> {
    let reference = reference(repo, scene)?;
    let mut curves = Vec::new();
    // Backward Euler and BDF2 twice: with conjugate gradients and with the sparse Cholesky solve;
    // generalised-α with its own default (conjugate gradients with the two-level preconditioner).
    let variants = Integrator::ALL.into_iter().flat_map(|i| {
        let solvers = if i.is_implicit() && i != Integrator::GeneralizedAlpha {
            vec![Some(LinearSolver::default_cg()), Some(LinearSolver::SparseCholesky)]
        } else {
            vec![None]
        };
        solvers.into_iter().map(move |s| (i, s))
    });
    for (integrator, solver) in variants {
        // The thesis's adaptive Euler sizes its step by the largest acceleration, which on the 64 × 64
        // sheet means hundreds of thousands of tiny steps per run; it is measured on the N = 32 sheet.
        if integrator == Integrator::AdaptiveEuler && scene.spec.n > 32 {
            curves.push(Curve::new(integrator));
            continue;
        }
        let mut curve = Curve { solver, ..Curve::new(integrator) };
        eprintln!("anima-lab: {} — {}", scene.name, curve.label());
        let adaptive = |tols: &[f64]| -> Vec<(f64, StepControl)> {
            let control =
                |tol| StepControl::Adaptive { tolerance: tol, dt_initial: 1e-4, dt_min: 1e-7, dt_max: 0.01 };
            tols.iter().map(|&tol| (tol, control(tol))).collect()
        };
        let constant = |dts: &[f64]| -> Vec<(f64, StepControl)> {
            dts.iter().map(|&dt| (dt, StepControl::Constant { dt })).collect()
        };
        let knobs = match integrator {
            Integrator::DormandPrince => adaptive(&[1e-3, 1e-4, 1e-5, 1e-6]),
            // The thesis's rule takes h ∝ √tol against the largest acceleration: tight tolerances cost
            // hundreds of thousands of steps on a stiff sheet, so the sweep stops at 10⁻⁴.
            Integrator::AdaptiveEuler => adaptive(&[1e-2, 1e-3, 1e-4]),
            // 5e-4 s only on the N = 32 sheets: at N = 64 it would cost minutes per solver.
            Integrator::ImplicitEuler | Integrator::Bdf2 if scene.spec.n > 32 => {
                constant(&[1.0 / 30.0, 1.0 / 60.0, 1.0 / 120.0, 1.0 / 240.0, 1e-3])
            }
            Integrator::ImplicitEuler | Integrator::Bdf2 => {
                constant(&[1.0 / 30.0, 1.0 / 60.0, 1.0 / 120.0, 1.0 / 240.0, 1e-3, 5e-4])
            }
            Integrator::GeneralizedAlpha => {
                constant(&[1.0 / 30.0, 1.0 / 60.0, 1.0 / 120.0, 1.0 / 240.0, 1.0 / 480.0])
            }
            _ => constant(&[5e-4, 2e-4, 1e-4, 5e-5]),
        };
        let mut points = Vec::new();
        for (knob, control) in knobs {
            if quick && knob < 5e-5 {
                continue;
            }
            if let Some((x, timing)) = timed_run(scene, integrator, solver, control) {
                points.push(measure(scene, knob, timing, &x, &reference));
            }
        }
        curve.points = points;
        curve.largest_stable = (!integrator.is_adaptive() && !integrator.is_implicit() && !quick)
            .then(|| largest_stable_step(scene, integrator));
        curve.at_largest = curve.largest_stable.and_then(|dt| {
            timed_run(scene, integrator, None, StepControl::Constant { dt })
                .map(|(x, timing)| measure(scene, dt, timing, &x, &reference))
        });
        curves.push(curve);
    }
    Ok((curves, reference))
}

/// Wall time to reach `target` error: log–log interpolation between the measured points.
fn time_at(curve: &Curve, target: f64) -> Option<f64> {
    let mut pts: Vec<Point> = curve.points.clone();
    pts.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
    // The cheapest run that meets the target, refined by interpolation with the next cheaper one.
    let k = pts.iter().position(|p| p.error <= target)?;
    if k == 0 {
        return Some(pts[0].seconds);
    }
    let (a, b) = (pts[k - 1], pts[k]);
    if a.error <= b.error {
        return Some(b.seconds);
    }
    let s = (target.ln() - a.error.ln()) / (b.error.ln() - a.error.ln());
    Some((a.seconds.ln() + s * (b.seconds.ln() - a.seconds.ln())).exp())
}

// ------------------------------------------------------------------------------------- mass–spring

fn mass_spring_curves() -> Vec<Curve> {
    let exact = SingleSpring::thesis();
    Integrator::ALL
        .iter()
        .map(|&integrator| {
            let knobs: Vec<(f64, StepControl)> = if integrator.is_adaptive() {
                [1e-2, 1e-4, 1e-6, 1e-8, 1e-10]
                    .iter()
                    .map(|&tol| {
                        (
                            tol,
                            StepControl::Adaptive {
                                tolerance: tol,
                                dt_initial: 0.01,
                                dt_min: 1e-8,
                                dt_max: 0.5,
                            },
                        )
                    })
                    .collect()
            } else {
                [0.5, 0.1, 0.05, 0.01, 0.005, 0.001, 0.0005, 0.0001]
                    .iter()
                    .map(|&dt| (dt, StepControl::Constant { dt }))
                    .collect()
            };
            let points = knobs
                .into_iter()
                .filter_map(|(knob, control)| {
                    // Repeat the (tiny) run until 20 ms have passed, for a measurable time.
                    let start = Instant::now();
                    let (mut reps, mut error) = (0u32, 0.0);
                    while reps == 0 || start.elapsed().as_secs_f64() < 0.02 {
                        let mut sys = SingleSpring::thesis();
                        let mut st = Stepper::new(integrator, 1);
                        let mut now = State::new(vec![4.0], vec![0.0]);
                        let mut scratch = State::zeros(1);
                        let mut worst = 0.0f64;
                        integrate(&mut sys, &mut st, control, 0.0, 10.0, &mut now, &mut scratch, |t, s| {
                            worst = worst.max((s.x[0] - exact.exact(t)).abs())
                        })
                        .ok()?;
                        error = worst;
                        reps += 1;
                    }
                    let seconds = start.elapsed().as_secs_f64() / reps as f64;
                    (error.is_finite() && error < 10.0).then_some(Point {
                        knob,
                        seconds,
                        seconds_range: (seconds, seconds),
                        error,
                        com_error: f64::NAN,
                    })
                })
                .collect();
            Curve { points, largest_stable: Some(stability_limit(integrator)), ..Curve::new(integrator) }
        })
        .collect()
}

// ------------------------------------------------------------------------------------- report

fn plot(title: &str, curves: &[Curve], error_label: &str) -> Result<anima_viz::Image> {
    let mut p = LinePlot::new(title, "wall time (s)", error_label);
    p.log_x = true;
    p.log_y = true;
    for c in curves.iter().filter(|c| !c.points.is_empty()) {
        let pts = c.points.iter().map(|p| (p.seconds, p.error.max(1e-16))).collect();
        p.series.push(Series::new(c.label(), pts, SeriesStyle::LineWithMarkers));
    }
    Ok(p.render(900, 600)?)
}

fn table(out: &mut String, curves: &[Curve], levels: &[(f64, &str)], stable_label: &str, stable_unit: &str) {
    let _ = write!(out, "| integrator | {stable_label} |");
    for (_, l) in levels {
        let _ = write!(out, " wall time at {l} |");
    }
    out.push_str(" runs (step or tolerance: error) |\n|---|---|");
    out.push_str(&"---|".repeat(levels.len() + 1));
    out.push('\n');
    for c in curves {
        let stable = match c.largest_stable {
            Some(s) if s.is_infinite() => "unbounded".to_owned(),
            Some(s) => format!("{s:.3e}{stable_unit}"),
            None => "—".to_owned(),
        };
        let _ = write!(out, "| {} | {stable} |", c.label());
        for (level, _) in levels {
            match time_at(c, *level) {
                Some(t) => {
                    let _ = write!(out, " {t:.3e} s |");
                }
                None => out.push_str(" not reached |"),
            }
        }
        let runs: Vec<String> = c.points.iter().map(|p| format!("{:.0e}: {:.1e}", p.knob, p.error)).collect();
        let _ = writeln!(out, " {} |", runs.join(", "));
    }
    for (level, l) in levels {
        let best = curves
            .iter()
            .filter_map(|c| time_at(c, *level).map(|t| (t, c.label())))
            .min_by(|a, b| a.0.total_cmp(&b.0));
        match best {
            Some((t, i)) => {
                let _ = writeln!(out, "\nFastest to {l}: **{i}** ({t:.3e} s).");
            }
            None => {
                let _ = writeln!(out, "\nNo method reached {l}.");
            }
        }
    }
    out.push('\n');
}

/// `cargo xtask bench [--quick] [--only SCENE]`: measures and writes `docs/benchmarks.md` (or prints one
/// scene's table).
/// The CPU's model name, for a report's header.
pub(crate) fn machine() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_owned())
        })
        .unwrap_or_else(|| "unknown CPU".to_owned())
}

pub fn run(repo: &Repo, quick: bool, only: Option<&str>) -> Result<()> {
    // Single-threaded, as the report says (the implicit steps would otherwise use every core).
    anima_ode::parallel::on_one_thread(|| run_single(repo, quick, only))
}

fn run_single(repo: &Repo, quick: bool, only: Option<&str>) -> Result<()> {
    let mut doc = String::new();
    let machine = machine();
    let cores = std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1);
    let _ = write!(
        doc,
        "# anima benchmarks\n\n_Generated by `cargo xtask bench`{} on {}; do not edit. Machine: {machine}, {cores} cores; \
         single-threaded, f64, release build._\n\n",
        if quick { " --quick" } else { "" },
        crate::report::today()
    );

    // The sheets of (b) and (c).
    let scenes = [
        BenchSheet {
            name: "standard-32",
            title: "(b) standard sheet, N = 32".into(),
            spec: SheetSpec::standard(32),
            duration: 1.0,
            com_reference: Some(DVec3::new(0.4999997, -0.4792614, 1.4655051)),
        },
        BenchSheet {
            name: "standard-64",
            title: "(b) standard sheet, N = 64".into(),
            spec: SheetSpec::standard(64),
            duration: 1.0,
            com_reference: Some(DVec3::new(0.5000605, -0.4684101, 1.4631486)),
        },
        BenchSheet {
            name: "oliveira-32",
            title: "(c) Oliveira's cloth (E = 10⁷ N/m²), N = 32".into(),
            spec: SheetSpec::oliveira_cloth(32),
            duration: 1.0,
            com_reference: None,
        },
    ];
    if let Some(name) = only {
        let scene = scenes.iter().find(|s| s.name == name).with_context(|| {
            format!("no sheet scene `{name}`; expected standard-32, standard-64 or oliveira-32")
        })?;
        let (curves, _) = sheet_curves(repo, scene, quick)?;
        let mut out = String::new();
        table(
            &mut out,
            &curves,
            &[(1e-2, "1 % (10 mm)"), (1e-3, "0.1 % (1 mm)")],
            "largest stable step",
            " s",
        );
        println!("{out}");
        return Ok(());
    }

    // (a) Table 4.1 spring.
    eprintln!("anima-lab: mass–spring …");
    let curves = mass_spring_curves();
    repo.write_figure(
        "bench-mass-spring.png",
        &plot("Table 4.1 spring: error against wall time", &curves, "max |x − (2 + 2 cos t)|, t ≤ 10")?,
    )?;
    doc.push_str("## (a) The Table 4.1 spring against 2 + 2 cos t\n\nError: largest |x(t) − 2 − 2 cos t| over t ∈ [0, 10]. \
                  Stability: the measured interval h·ω on the imaginary axis (ω = 1 here), from `anima_ode::stability`.\n\n");
    table(&mut doc, &curves, &[(1e-2, "error 10⁻²"), (1e-4, "error 10⁻⁴")], "stable h·ω", "");
    doc.push_str("![mass-spring](figures/bench-mass-spring.png)\n\n");

    let mut peers = String::new();
    for scene in &scenes {
        let (curves, _) = sheet_curves(repo, scene, quick)?;
        let png = format!("bench-{}.png", scene.name);
        repo.write_figure(&png, &plot(&scene.title, &curves, "RMS position error (m)")?)?;
        let (m, k) = scene.spec.build()?.stiffest();
        let _ = write!(
            doc,
            "## {}\n\nThe sheet of `benchmarks.md` ({} particles, pinned at two corners, 1 s); particle mass {m:.3e} kg, \
             largest stiffness {k:.0} N/m. Error: RMS particle distance at t = 1 s from RK4 at 10⁻⁵ s; 1 % and 0.1 % of the \
             1 m sheet are 10 mm and 1 mm. Largest stable step: the largest constant step that stays finite and below \
             100 m/s for the whole second.\n\n",
            scene.title,
            scene.spec.n * scene.spec.n
        );
        table(
            &mut doc,
            &curves,
            &[(1e-2, "1 % (10 mm)"), (1e-3, "0.1 % (1 mm)")],
            "largest stable step",
            " s",
        );
        let _ = writeln!(doc, "![{}](figures/{png})\n", scene.name);
        if scene.com_reference.is_some() {
            peers.push_str(&peer_table(scene, &curves));
        }
    }
    doc.push_str(&sensitivity_section(repo, &scenes[..2])?);
    doc.push_str(&peers_section(&peers));

    // Stability map.
    eprintln!("anima-lab: stability map …");
    doc.push_str(&stability_map(repo)?);

    repo.write_text("docs/benchmarks.md", &doc)
}

/// The peers' numbers from `benchmarks.md` (wall time for 1 s; N = 32, N = 64), measured there on this
/// machine class.
const PEERS: [(&str, &str, &str, &str); 7] = [
    ("NVIDIA Warp, CPU, f32, symplectic Euler", "0.34 s", "4.29 s", "1.0–1.3 mm"),
    ("Newton (on Warp), semi-implicit", "0.42 s", "5.39 s", "0.8–0.9 mm"),
    ("Taichi, CPU, 2 threads", "2.31 s", "7.45 s", "1.0–1.1 mm"),
    ("MuJoCo 4.0 flex (membrane FEM), Euler", "5.88 s", "49.3 s", "4.4–4.8 mm"),
    ("PyBullet deformable", "16.8 s", "242 s", "8.6–19 mm"),
    ("Newton VBD (implicit), largest stable step", "2.18 s at 4e-3", "17.6 s at 2e-3", "118–125 mm"),
    ("MuJoCo flex, implicit (`discrete`), 1/60 s", "0.63 s", "9.0 s", "339–346 mm"),
];

fn peer_table(scene: &BenchSheet, curves: &[Curve]) -> String {
    let n = scene.spec.n;
    let common = if n <= 32 { 2e-4 } else { 1e-4 };
    let mut out = format!(
        "### N = {n}: anima at the common step ({common:.0e} s), at each explicit method's largest stable step and \
         at the implicit methods' large steps\n\n\
         | integrator | step (s) | wall time | centre-of-mass error | RMS error |\n|---|---|---|---|---|\n"
    );
    for c in curves {
        let mut rows: Vec<(&str, Point)> = Vec::new();
        if let Some(p) = c.points.iter().find(|p| (p.knob - common).abs() < 1e-12) {
            rows.push(("common", *p));
        }
        if let Some(p) = c.at_largest {
            rows.push(("largest stable", p));
        }
        if c.integrator.is_implicit() {
            for p in c.points.iter().filter(|p| p.knob > 1e-3) {
                rows.push(("large", *p));
            }
        }
        if c.integrator.is_adaptive()
            && let Some(p) = c.points.iter().min_by(|a, b| a.seconds.total_cmp(&b.seconds))
        {
            rows.push(("tolerance", *p));
        }
        for (what, p) in rows {
            let _ = writeln!(
                out,
                "| {} | {:.2e} ({what}) | {} | {:.2} mm | {:.2} mm |",
                c.label(),
                p.knob,
                wall(&p),
                p.com_error * 1e3,
                p.error * 1e3
            );
        }
        // Explicit methods are run at the common step, so a missing row there means the run blew up;
        // the implicit ones are run only at large steps, and say nothing about it.
        if !c.points.iter().any(|p| (p.knob - common).abs() < 1e-12)
            && !c.integrator.is_adaptive()
            && !c.integrator.is_implicit()
        {
            let _ = writeln!(out, "| {} | {common:.0e} (common) | unstable | — | — |", c.label());
        }
    }
    out.push('\n');
    out
}

/// The sheet's grid with every particle moved by ±`eps` in the plane of the sheet (a fixed pattern, the
/// same in every run).
fn nudged_grid(spec: &SheetSpec, eps: f64) -> Vec<DVec3> {
    let mut x = spec.positions();
    for (i, p) in x.iter_mut().enumerate() {
        let s = if (i * 7919) % 13 < 6 { eps } else { -eps };
        p.x += s;
        p.y -= s;
    }
    x
}

/// How much of the standard sheet's error at 1 s is the sheet's own sensitivity: each of a few runs
/// again from a grid nudged by 1 nm, and the distance between the two at 1 s.
fn sensitivity_section(repo: &Repo, scenes: &[BenchSheet]) -> Result<String> {
    let mut out = String::from(
        "## How much of the sheet's error is its own chaos\n\nThe sheet folds as it falls, and folding amplifies \
         small differences. Each run below is repeated from a grid whose particles are moved by 1 nm (a fixed \
         pattern of ±1 nm in the plane of the sheet); the table gives how far apart the two runs end at 1 s. \
         An RMS error against the reference no larger than that distance says nothing about the step: two runs \
         of one method that start 1 nm apart differ by as much. The centre-of-mass column shows how much \
         steadier an average is.\n\n\
         | sheet | integrator | step | RMS between the two runs | centre of mass between the two runs | RMS vs the reference, unnudged / nudged |\n\
         |---|---|---|---|---|---|\n",
    );
    for scene in scenes {
        let n = scene.spec.n;
        let common = if n <= 32 { 2e-4 } else { 1e-4 };
        eprintln!("anima-lab: sensitivity of {} …", scene.name);
        let reference = reference(repo, scene)?;
        let net = scene.spec.build()?;
        for (integrator, dt) in [
            (Integrator::SymplecticEuler, common),
            (Integrator::Rk4, common),
            (Integrator::GeneralizedAlpha, 1.0 / 60.0),
            (Integrator::GeneralizedAlpha, 1.0 / 240.0),
        ] {
            let control = StepControl::Constant { dt };
            let runs = [0.0, 1e-9].map(|eps| {
                run_sheet_from(scene, nudged_grid(&scene.spec, eps), integrator, control, &|_| ())
                    .map(|r| r.0)
            });
            let [Some(a), Some(b)] = runs else {
                let _ = writeln!(out, "| N = {n} | {integrator} | {dt:.2e} s | diverged | — | — |");
                continue;
            };
            let _ = writeln!(
                out,
                "| N = {n} | {integrator} | {dt:.2e} s | {:.2} mm | {:.2} mm | {:.2} / {:.2} mm |",
                rms(&a, &b) * 1e3,
                net.centre_of_mass(&a).distance(net.centre_of_mass(&b)) * 1e3,
                rms(&a, &reference) * 1e3,
                rms(&b, &reference) * 1e3
            );
        }
    }
    out.push('\n');
    out.push_str(&converged_alpha_table(repo, scenes)?);
    Ok(out)
}

/// Newton iterations and CG tolerance of [`converged_alpha_table`]: enough that more change nothing
/// the table shows.
const CONVERGED_NEWTON: usize = 6;
const CONVERGED_CG_TOLERANCE: f64 = 1e-7;

/// Generalised-α on the N = 64 sheet with every step's Newton iterations converged: the method's own
/// discretisation error, apart from the inexact solves of its default.
fn converged_alpha_table(repo: &Repo, scenes: &[BenchSheet]) -> Result<String> {
    let Some(scene) = scenes.iter().find(|s| s.spec.n == 64) else { return Ok(String::new()) };
    let reference = reference(repo, scene)?;
    let net = scene.spec.build()?;
    let mut out = format!(
        "Generalised-α's error on the N = 64 sheet with each step solved to convergence ({CONVERGED_NEWTON} \
         Newton iterations, CG with rigid aggregation to a relative residual of {CONVERGED_CG_TOLERANCE:.0e}), \
         against its default above: what is left is the step's own discretisation error, to be read beside \
         the sensitivity above.\n\n\
         | step | RMS vs the reference | centre of mass vs the reference |\n|---|---|---|\n"
    );
    for per_s in [60.0, 120.0, 240.0, 480.0, 960.0] {
        let dt = 1.0 / per_s;
        eprintln!("anima-lab: {} — generalized-alpha converged at 1/{per_s} s …", scene.name);
        let converged = |stepper: &mut Stepper<DVec3>| {
            stepper.set_linear_solver(LinearSolver::RigidAggregation {
                tolerance: CONVERGED_CG_TOLERANCE,
                max_iterations: 1000,
            });
            stepper.set_newton_iterations(CONVERGED_NEWTON);
            stepper.set_newton_contraction(0.0);
        };
        let control = StepControl::Constant { dt };
        let positions = scene.spec.positions();
        let Some((x, _)) =
            run_sheet_from(scene, positions, Integrator::GeneralizedAlpha, control, &converged)
        else {
            let _ = writeln!(out, "| 1/{per_s:.0} s | failed | — |");
            continue;
        };
        let _ = writeln!(
            out,
            "| 1/{per_s:.0} s | {:.2} mm | {:.2} mm |",
            rms(&x, &reference) * 1e3,
            scene.com_reference.map_or(f64::NAN, |r| net.centre_of_mass(&x).distance(r)) * 1e3
        );
    }
    out.push('\n');
    Ok(out)
}

/// A wall time, with its range when it is the median of several runs.
fn wall(p: &Point) -> String {
    let (lo, hi) = p.seconds_range;
    if lo == hi { format!("{:.3} s", p.seconds) } else { format!("{:.3} s ({lo:.3}–{hi:.3})", p.seconds) }
}

fn peers_section(tables: &str) -> String {
    let mut out = String::from(
        "## The standard sheet beside other simulators\n\nWhat other simulators measured for 1 simulated second when \
         `benchmarks.md` was written (same machine class, 2 cores, another day). These are context, not the \
         denominator of a ratio: a speed ratio needs both timed alternately in one run (`cargo xtask bench --peers` \
         is where that belongs).\n\n| system and method | N = 32 | N = 64 | centre-of-mass error |\n|---|---|---|---|\n",
    );
    for (name, a, b, e) in PEERS {
        let _ = writeln!(out, "| {name} | {a} | {b} | {e} |");
    }
    out.push_str(
        "\nanima's numbers below are single-threaded and f64, timed in this run; a run shorter than a second is \
         timed five times, and its median is given with the fastest and slowest in brackets. The centre-of-mass error is the \
         distance from the reference centre of mass in `benchmarks.md`.\n\n",
    );
    out.push_str(tables);
    out
}

/// Largest stable step against stiffness for each explicit method on a 16×16 undamped sheet, beside the
/// bound h·ω_max = (the method's measured interval) with ω_max from power iteration.
fn stability_map(repo: &Repo) -> Result<String> {
    let mut out = String::from(
        "## Stability map\n\nLargest constant step that keeps a 16 × 16 standard sheet (undamped) finite and below 100 m/s \
         for 0.5 s, against its structural stiffness (shear at half, bend fixed), beside the theoretical bound \
         h_max = c/ω_max: c is the method's measured stability interval on the imaginary axis and ω_max the largest \
         frequency of the sheet at rest, from power iteration.\n\n| stiffness (N/m) | ω_max (rad/s) |",
    );
    let methods = [
        Integrator::SymplecticEuler,
        Integrator::Rk4,
        Integrator::AdamsBashforth4,
        Integrator::DormandPrince,
    ];
    for m in methods {
        let _ = write!(out, " {m} measured / bound |");
    }
    out.push_str("\n|---|---|");
    out.push_str(&"---|".repeat(methods.len()));
    out.push('\n');
    // Per method: (stiffness, measured step) and (stiffness, bound) points.
    type Points = Vec<(f64, f64)>;
    let mut series: Vec<(Integrator, Points, Points)> =
        methods.iter().map(|&m| (m, vec![], vec![])).collect();
    for k in [100.0, 1000.0, 1e4] {
        let spec =
            SheetSpec { n: 16, damping: 0.0, stiffness: [k, k / 2.0, 10.0], ..SheetSpec::standard(16) };
        let mut net = spec.build()?;
        let x = spec.positions();
        let frozen = net.pinned().to_vec();
        let omega = max_frequency(&mut net, 0.0, &x, &vec![DVec3::ZERO; x.len()], &frozen, 200);
        let _ = write!(out, "| {k:.0e} | {omega:.0} |");
        let scene =
            BenchSheet { name: "map", title: String::new(), spec, duration: 0.5, com_reference: None };
        for (m, measured, bound) in &mut series {
            let limit = stability_limit(*m) / omega;
            let got = largest_stable_step(&scene, *m);
            let _ = write!(out, " {got:.2e} / {limit:.2e} |");
            measured.push((k, got));
            bound.push((k, limit));
        }
        out.push('\n');
    }
    let mut p = LinePlot::new(
        "Largest stable step against stiffness (16 × 16 sheet)",
        "structural stiffness (N/m)",
        "Δt (s)",
    );
    p.log_x = true;
    p.log_y = true;
    for (m, measured, bound) in series {
        p.series.push(Series::new(format!("{m} measured"), measured, SeriesStyle::LineWithMarkers));
        p.series.push(Series::new(format!("{m} bound"), bound, SeriesStyle::Dashed));
    }
    repo.write_figure("bench-stability-map.png", &p.render(900, 600)?)?;
    out.push_str("\nForward Euler and midpoint have no stable interval on the imaginary axis: undamped, they grow at \
                  every step, and only damping lets them run.\n\n![stability map](figures/bench-stability-map.png)\n\n");
    Ok(out)
}
