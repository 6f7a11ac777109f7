//! Large steps that stay accurate (issue 15): the measurements behind generalised-α, the two-level solve
//! and contact inside the solve. Every study is a plain function (scene and method in, numbers out);
//! `main` prints them as Markdown tables.
//!
//! ```sh
//! cargo run --release -p anima-lab --example large_steps -- spring     # Table 4.1 spring: energy, phase, order
//! cargo run --release -p anima-lab --example large_steps -- sheet      # standard sheet N = 64, 1 s
//! cargo run --release -p anima-lab --example large_steps -- breakdown  # where a step's time goes
//! cargo run --release -p anima-lab --example large_steps -- drapes     # Oliveira's three fine drapes
//! NEWTON=2 SOLVER=two-level CGTOL=0.03 cargo run --release -p anima-lab --example large_steps -- probe
//!                                                    # one generalised-α sheet run, set from the environment
//! QUICK=1 REPEATS=5 …  -- sheet                      # the first four sheet rows only, five alternated runs
//! cargo run --release -p anima-lab --example large_steps -- all
//! ```
//!
//! References are computed once and cached under `target/anima-lab/large-steps/` (the standard sheet:
//! RK4 at 10⁻⁵ s, about a minute and a half; each drape: RK4 at the thesis's rule with β = 10⁻³, the
//! faithful reference of `docs/reproduction/oliveira-implicit.md`, 20 to 45 s). Wall times are medians
//! of alternated repeats, single thread, f64.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anima_cloth::contact_mode::ContactMode;
use anima_cloth::flex3d::mass_spring::SingleSpring;
use anima_cloth::network_sim::NetworkSim;
use anima_cloth::oliveira::{OliveiraCloth, OliveiraScene, ShapeDesc, StepRule};
use anima_cloth::spring_net::SheetSpec;
use anima_geom::{DVec3, TriangleMesh, read_obj};
use anima_lab::oliveira::implicit::{rms_at_material_points, worst_rms};
use anima_lab::run::SolveOptions;
use anima_ode::{Integrator, LinearSolver, SolveProfile, State, Stepper};

type Error = Box<dyn std::error::Error>;

// ------------------------------------------------------------------------------------------ methods

/// An integrator at a step, with the solver settings a study varies (`None` keeps the stepper's
/// default, as for `anima run`).
#[derive(Debug, Clone, Copy)]
pub struct Method {
    pub integrator: Integrator,
    pub dt: f64,
    pub solve: SolveOptions,
}

impl Method {
    pub fn new(integrator: Integrator, dt: f64) -> Self {
        Self { integrator, dt, solve: SolveOptions::default() }
    }

    /// The same method with another linear solver.
    fn with_solver(mut self, solver: LinearSolver) -> Self {
        self.solve.linear_solver = Some(solver);
        self
    }

    /// The same method with `k` Newton iterations a step.
    fn with_newton(mut self, k: usize) -> Self {
        self.solve.newton_iterations = Some(k);
        self
    }

    /// The same method with generalised-α's ρ∞.
    fn with_rho_inf(mut self, rho_inf: f64) -> Self {
        self.solve.rho_inf = Some(rho_inf);
        self
    }

    fn configure(&self, stepper: &mut Stepper<DVec3>) {
        self.solve.configure(stepper);
    }

    pub fn label(&self) -> String {
        let mut s = self.integrator.to_string();
        if let Some(r) = self.solve.rho_inf {
            s += &format!(" ρ∞={r}");
        }
        if let Some(solver) = self.solve.linear_solver {
            s += &format!(" +{}", solver.name());
        }
        if let Some(k) = self.solve.newton_iterations {
            s += &format!(" newton={k}");
        }
        s
    }

    pub fn step_label(&self) -> String {
        if self.dt >= 1e-3 { format!("1/{:.0} s", 1.0 / self.dt) } else { format!("{:.2e} s", self.dt) }
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn rms(a: &[DVec3], b: &[DVec3]) -> f64 {
    (a.iter().zip(b).map(|(p, q)| p.distance_squared(*q)).sum::<f64>() / a.len() as f64).sqrt()
}

fn cache_dir() -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    root.join("target/anima-lab/large-steps")
}

fn write_points(path: &Path, head: &[f64], points: &[DVec3]) -> Result<(), Error> {
    std::fs::create_dir_all(path.parent().expect("has a parent"))?;
    let vals: Vec<f64> = head.iter().copied().chain(points.iter().flat_map(|p| p.to_array())).collect();
    std::fs::write(path, vals.iter().flat_map(|v| v.to_le_bytes()).collect::<Vec<u8>>())?;
    Ok(())
}

fn read_points(path: &Path, head: usize) -> Option<(Vec<f64>, Vec<DVec3>)> {
    let bytes = std::fs::read(path).ok()?;
    let vals: Vec<f64> =
        bytes.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
    if vals.len() < head || !(vals.len() - head).is_multiple_of(3) {
        return None;
    }
    let points = vals[head..].chunks_exact(3).map(|c| DVec3::new(c[0], c[1], c[2])).collect();
    Some((vals[..head].to_vec(), points))
}

// ------------------------------------------------------------------------------------------ spring

/// The Table 4.1 spring x'' = −(x − 2), x(0) = 4, v(0) = 0 (ω = 1): energy kept after 10⁴ steps of h,
/// phase error after ten periods (rad, positive: ahead), and the observed order from h = 0.02, 0.01,
/// 0.005 over t ∈ [0, 2].
#[derive(Debug, Clone, Copy)]
pub struct SpringRow {
    pub energy_kept: f64,
    pub phase_error: f64,
    pub order: f64,
}

fn spring_run(integrator: Integrator, rho: Option<f64>, h: f64, steps: usize) -> State<f64> {
    let mut st = Stepper::new(integrator, 1);
    if let Some(r) = rho {
        st.set_spectral_radius(r);
    }
    let mut now = State::new(vec![4.0], vec![0.0]);
    let mut next = State::zeros(1);
    for k in 0..steps {
        st.step(&mut SingleSpring::thesis(), k as f64 * h, h, &now, &mut next).expect("spring step");
        std::mem::swap(&mut now, &mut next);
    }
    now
}

pub fn spring_study(integrator: Integrator, rho: Option<f64>, h: f64) -> SpringRow {
    let energy = |s: &State<f64>| 0.5 * s.v[0] * s.v[0] + 0.5 * (s.x[0] - 2.0).powi(2);
    let end = spring_run(integrator, rho, h, 10_000);
    // Phase of (x − 2, −v) against the exact angle t after ten periods (steps rounded): the
    // accumulated phase error, small enough there not to wrap.
    let steps = (20.0 * std::f64::consts::PI / h).round() as usize;
    let t = steps as f64 * h;
    let s = spring_run(integrator, rho, h, steps);
    let mut phase_error = ((-s.v[0]).atan2(s.x[0] - 2.0) - t).rem_euclid(std::f64::consts::TAU);
    if phase_error > std::f64::consts::PI {
        phase_error -= std::f64::consts::TAU;
    }
    let err = |h: f64| {
        let n = (2.0 / h).round() as usize;
        let s = spring_run(integrator, rho, h, n);
        (s.x[0] - (2.0 + 2.0 * 2f64.cos())).hypot(s.v[0] + 2.0 * 2f64.sin())
    };
    let (e1, e2, e3) = (err(0.02), err(0.01), err(0.005));
    let order = 0.5 * ((e1 / e2).log2() + (e2 / e3).log2());
    SpringRow { energy_kept: energy(&end) / 2.0, phase_error, order }
}

// ------------------------------------------------------------------------------------------ sheet

/// The reference centre of mass at t = 1 s of `benchmarks.md` (f64, symplectic Euler at 10⁻⁵ s).
pub fn reference_com(n: usize) -> DVec3 {
    if n == 64 {
        DVec3::new(0.5000605, -0.4684101, 1.4631486)
    } else {
        DVec3::new(0.4999997, -0.4792614, 1.4655051)
    }
}

/// One run of the standard sheet for `duration` seconds.
#[derive(Debug, Clone)]
pub struct SheetOutcome {
    pub x: Vec<DVec3>,
    pub wall_s: f64,
    pub steps: usize,
    pub solver_iterations: usize,
    pub profile: Option<SolveProfile>,
    pub error: Option<String>,
}

pub fn run_sheet(spec: &SheetSpec, method: &Method, duration: f64) -> SheetOutcome {
    let mut sim =
        NetworkSim::new(spec.build().unwrap(), spec.positions(), method.integrator, method.dt).unwrap();
    method.configure(sim.stepper_mut());
    sim.stepper_mut().set_profiling(true);
    let steps = (duration / method.dt).round() as usize;
    let start = Instant::now();
    let result = sim.run(steps);
    let wall_s = start.elapsed().as_secs_f64();
    SheetOutcome {
        profile: sim.stepper_mut().profile(),
        x: sim.state.x.clone(),
        wall_s,
        steps: sim.steps() as usize,
        solver_iterations: sim.stats.solver_iterations,
        error: result.err().map(|e| e.to_string()),
    }
}

/// The converged sheet: RK4 at 10⁻⁵ s, cached.
pub fn sheet_reference(spec: &SheetSpec) -> Result<Vec<DVec3>, Error> {
    let path = cache_dir().join(format!("sheet-{}-rk4-1e-5.bin", spec.n));
    if let Some((_, x)) = read_points(&path, 0).filter(|(_, x)| x.len() == spec.n * spec.n) {
        return Ok(x);
    }
    eprintln!("large_steps: the sheet reference (RK4 at 1e-5 s) …");
    let out = run_sheet(spec, &Method::new(Integrator::Rk4, 1e-5), 1.0);
    write_points(&path, &[], &out.x)?;
    Ok(out.x)
}

/// A measured sheet method: median wall time over `repeats` (the runs alternate with the other methods
/// of the same table), and the errors of the last run.
#[derive(Debug, Clone)]
pub struct SheetRow {
    pub method: Method,
    pub wall_s: f64,
    pub min_s: f64,
    pub max_s: f64,
    pub com_error_m: f64,
    pub rms_m: f64,
    pub per_step_ms: f64,
    pub outcome: SheetOutcome,
}

pub fn sheet_table(spec: &SheetSpec, methods: &[Method], repeats: usize) -> Result<Vec<SheetRow>, Error> {
    let reference = sheet_reference(spec)?;
    let com_ref = reference_com(spec.n);
    let net = spec.build().unwrap();
    let mut walls: Vec<Vec<f64>> = vec![Vec::new(); methods.len()];
    let mut last: Vec<Option<SheetOutcome>> = vec![None; methods.len()];
    for _ in 0..repeats {
        for (k, m) in methods.iter().enumerate() {
            // Slow runs once only.
            if walls[k].first().is_some_and(|&w| w > 3.0) {
                continue;
            }
            let out = run_sheet(spec, m, 1.0);
            walls[k].push(out.wall_s);
            last[k] = Some(out);
        }
    }
    Ok(methods
        .iter()
        .zip(walls)
        .zip(last)
        .map(|((m, w), out)| {
            let out = out.expect("ran at least once");
            let com = net.centre_of_mass(&out.x);
            let finite = out.x.iter().all(|p| p.is_finite());
            let (min_s, max_s) =
                (w.iter().copied().fold(f64::INFINITY, f64::min), w.iter().copied().fold(0.0, f64::max));
            let wall_s = median(w);
            SheetRow {
                method: *m,
                wall_s,
                min_s,
                max_s,
                com_error_m: if finite { com.distance(com_ref) } else { f64::NAN },
                rms_m: if finite { rms(&out.x, &reference) } else { f64::NAN },
                per_step_ms: wall_s * 1e3 / out.steps.max(1) as f64,
                outcome: out,
            }
        })
        .collect())
}

// ------------------------------------------------------------------------------------------ drapes

/// One of Oliveira's three fine drapes: scene file and snapshot times (the last is the end).
#[derive(Debug, Clone, Copy)]
pub struct Drape {
    pub title: &'static str,
    pub file: &'static str,
    pub slug: &'static str,
    pub snapshots: [f64; 4],
}

pub const DRAPES: [Drape; 3] = [
    Drape {
        title: "Test I — Bunny",
        file: "test-1-bunny-17x17.ron",
        slug: "bunny",
        snapshots: [0.1, 0.25, 0.35, 0.5],
    },
    Drape {
        title: "Test II — table",
        file: "test-2-table-17x17.ron",
        slug: "table",
        snapshots: [0.15, 0.5, 0.75, 1.0],
    },
    Drape {
        title: "Test III — sphere",
        file: "test-3-sphere-17x17.ron",
        slug: "sphere",
        snapshots: [0.15, 0.3, 0.45, 0.6],
    },
];

/// A scene file of `assets/oliveira/` and the OBJ meshes it names.
pub fn load_drape(d: &Drape) -> Result<(OliveiraScene, Vec<TriangleMesh>), Error> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/oliveira");
    let path = dir.join(d.file);
    let text = std::fs::read_to_string(&path)?;
    let scene: OliveiraScene = ron::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut meshes = Vec::new();
    for o in &scene.objects {
        if let ShapeDesc::Mesh { file, .. } = &o.shape {
            let f = std::fs::File::open(dir.join(file))?;
            meshes.push(read_obj(std::io::BufReader::new(f)).map_err(|e| format!("{file}: {e}"))?);
        }
    }
    Ok((scene, meshes))
}

/// How a drape is integrated.
#[derive(Debug, Clone, Copy)]
pub struct DrapeMethod {
    pub method: Method,
    /// `None`: a fixed step of `method.dt`.
    pub rule: Option<StepRule>,
    pub contact: ContactMode,
}

impl DrapeMethod {
    pub fn fixed(integrator: Integrator, dt: f64, contact: ContactMode) -> Self {
        Self { method: Method::new(integrator, dt), rule: None, contact }
    }

    pub fn label(&self) -> String {
        format!("{}, contact {}", self.method.label(), self.contact)
    }

    pub fn step_label(&self) -> String {
        match self.rule {
            Some(StepRule::Provot { beta, .. }) => format!("β = {beta:.0e}"),
            _ => self.method.step_label(),
        }
    }
}

/// Positions at the snapshot times, wall time, steps, and the most particles found inside an object
/// after any step.
#[derive(Debug, Clone)]
pub struct DrapeOutcome {
    pub snapshots: Vec<Vec<DVec3>>,
    pub wall_s: f64,
    pub steps: u64,
    pub most_inside: usize,
    pub profile: Option<SolveProfile>,
}

pub fn run_drape(
    scene: &OliveiraScene,
    meshes: &[TriangleMesh],
    m: &DrapeMethod,
    snapshots: &[f64],
    check_every_step: bool,
) -> Result<DrapeOutcome, Error> {
    let mut scene = scene.clone();
    scene.integrator = m.method.integrator;
    scene.time_step = m.rule.unwrap_or(StepRule::Fixed { dt_s: m.method.dt });
    scene.options.contact = m.contact;
    let mut cloth = OliveiraCloth::new(&scene, meshes.to_vec())?;
    m.method.configure(cloth.stepper_mut());
    cloth.stepper_mut().set_profiling(true);
    let mut out = Vec::new();
    let mut most_inside = 0;
    let mut wall = 0.0;
    for &t in snapshots {
        while cloth.time() < t - 1e-9 {
            let start = Instant::now();
            cloth.step()?;
            wall += start.elapsed().as_secs_f64();
            if check_every_step {
                most_inside = most_inside.max(cloth.penetrations().len());
            }
        }
        out.push(cloth.positions().to_vec());
    }
    most_inside = most_inside.max(cloth.penetrations().len());
    Ok(DrapeOutcome {
        snapshots: out,
        wall_s: wall,
        steps: cloth.steps(),
        most_inside,
        profile: cloth.stepper_mut().profile(),
    })
}

/// A drape reference, cached: the snapshots of `m` (run once).
pub fn drape_reference(d: &Drape, m: &DrapeMethod, name: &str) -> Result<Vec<Vec<DVec3>>, Error> {
    let path = cache_dir().join(format!("drape-{}-{name}.bin", d.slug));
    let n = 17 * 17;
    if let Some((_, x)) = read_points(&path, 0).filter(|(_, x)| x.len() == n * d.snapshots.len()) {
        return Ok(x.chunks_exact(n).map(<[DVec3]>::to_vec).collect());
    }
    eprintln!("large_steps: {} — the reference `{name}` ({} at {}) …", d.title, m.label(), m.step_label());
    let (scene, meshes) = load_drape(d)?;
    let out = run_drape(&scene, &meshes, m, &d.snapshots, false)?;
    let flat: Vec<DVec3> = out.snapshots.iter().flatten().copied().collect();
    write_points(&path, &[], &flat)?;
    Ok(out.snapshots)
}

/// The thesis's faithful run: RK4 at Δt = β·π·√(m_min/k_max) with β = 10⁻³ after 10⁻⁴ s steps.
pub fn faithful() -> DrapeMethod {
    DrapeMethod {
        method: Method::new(Integrator::Rk4, 1e-4),
        rule: Some(StepRule::Provot { beta: 1e-3, startup_dt_s: Some(1e-4) }),
        contact: ContactMode::AfterStep,
    }
}

/// The in-solve model run to convergence: generalised-α with contact in the solve at 1/16 000 s.
pub fn converged_in_solve() -> DrapeMethod {
    // Eight Newton iterations: with the default count the stick/slide regimes do not settle within a
    // step and the runs do not converge as the step shrinks (see anima-lab's `oliveira::implicit`).
    let mut m = DrapeMethod::fixed(Integrator::GeneralizedAlpha, 1.0 / 16_000.0, ContactMode::InSolve);
    m.method.solve.newton_iterations = Some(8);
    m
}

// ------------------------------------------------------------------------------------------ main

fn print_profile(label: &str, p: &SolveProfile, wall: f64) {
    let steps = p.steps.max(1) as f64;
    let other = wall - p.assembly_s - p.setup_s - p.solve_s - p.contact_s;
    println!(
        "| {label} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.1} | {:.1} | {} |",
        wall * 1e3 / steps,
        p.assembly_s * 1e3 / steps,
        p.setup_s * 1e3 / steps,
        p.solve_s * 1e3 / steps,
        p.contact_s * 1e3 / steps,
        other * 1e3 / steps,
        p.newton_iterations as f64 / steps,
        p.solver_iterations as f64 / steps,
        p.solver_iterations as f64 / p.newton_iterations.max(1) as f64,
        p.factorizations,
    );
}

fn spring_section() {
    println!("## The Table 4.1 spring (ω = 1)\n");
    println!(
        "| method | h | energy kept after 10⁴ steps | phase error after 10 periods (rad) | observed order |"
    );
    println!("|---|---|---|---|---|");
    let rows: [(Integrator, Option<f64>, &str); 8] = [
        (Integrator::SymplecticEuler, None, "symplectic-euler"),
        (Integrator::ImplicitEuler, None, "implicit-euler"),
        (Integrator::Bdf2, None, "bdf2"),
        (Integrator::GeneralizedAlpha, Some(1.0), "generalized-alpha ρ∞=1 (implicit midpoint)"),
        (Integrator::GeneralizedAlpha, Some(0.6), "generalized-alpha ρ∞=0.6"),
        (Integrator::GeneralizedAlpha, None, "generalized-alpha (default ρ∞=0.2)"),
        (Integrator::GeneralizedAlpha, Some(0.0), "generalized-alpha ρ∞=0"),
        (Integrator::Rk4, None, "rk4"),
    ];
    for h in [0.1, 0.05] {
        for (integrator, rho, label) in rows {
            let r = spring_study(integrator, rho, h);
            println!("| {label} | {h} | {:.4} | {:+.3e} | {:.2} |", r.energy_kept, r.phase_error, r.order);
        }
    }
    println!();
}

fn sheet_section() -> Result<(), Error> {
    let spec = SheetSpec::standard(64);
    let dt = 1.0 / 60.0;
    let ga = |dt: f64| Method::new(Integrator::GeneralizedAlpha, dt);
    let two_level = LinearSolver::default_two_level();
    let mut methods = vec![
        Method::new(Integrator::SymplecticEuler, 1e-4),
        ga(dt),
        Method::new(Integrator::SymplecticEuler, 1.5e-4),
        ga(dt).with_solver(two_level).with_newton(4),
        ga(1.0 / 30.0),
        ga(1.0 / 120.0),
        ga(1.0 / 240.0),
        ga(dt).with_newton(3),
        ga(dt).with_newton(4),
        ga(dt).with_solver(two_level).with_newton(2),
        ga(dt).with_rho_inf(0.0),
        ga(dt).with_rho_inf(0.4),
        ga(dt).with_solver(LinearSolver::SparseCholesky).with_newton(8),
        Method::new(Integrator::ImplicitEuler, dt).with_solver(LinearSolver::SparseCholesky),
        Method::new(Integrator::Bdf2, dt).with_solver(LinearSolver::SparseCholesky),
        Method::new(Integrator::ImplicitEuler, dt),
        Method::new(Integrator::Bdf2, dt),
    ];
    let repeats = std::env::var("REPEATS").ok().and_then(|s| s.parse().ok()).unwrap_or(5);
    if std::env::var("QUICK").is_ok() {
        methods.truncate(4);
    }
    let rows = sheet_table(&spec, &methods, repeats)?;
    let se = &rows[0];
    println!(
        "## Standard sheet, N = 64, 1 s (single thread, f64; medians of {repeats} alternated runs, min–max)\n"
    );
    println!(
        "| method | step | wall time (min–max) | ms per step | vs symplectic Euler at 1e-4 s | CoM error | RMS error | CG iterations | failure |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for r in &rows {
        println!(
            "| {} | {} | {:.3} s ({:.3}–{:.3}) | {:.2} | {:.2}× | {:.2} mm | {:.2} mm | {} | {} |",
            r.method.label(),
            r.method.step_label(),
            r.wall_s,
            r.min_s,
            r.max_s,
            r.per_step_ms,
            se.wall_s / r.wall_s,
            r.com_error_m * 1e3,
            r.rms_m * 1e3,
            r.outcome.solver_iterations,
            r.outcome.error.as_deref().unwrap_or(""),
        );
    }
    println!();
    Ok(())
}

fn breakdown_section() {
    let spec = SheetSpec::standard(64);
    let dt = 1.0 / 60.0;
    println!("## Where a step's time goes: standard sheet N = 64 at 1/60 s (ms per step, one run each)\n");
    println!(
        "| method | total | force + Jacobian + assembly | factorisation / preconditioner set-up | linear solves | contact | rest | Newton its/step | CG its/step | CG its/Newton | factorisations |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let methods = [
        Method::new(Integrator::ImplicitEuler, dt).with_solver(LinearSolver::SparseCholesky),
        Method::new(Integrator::ImplicitEuler, dt),
        Method::new(Integrator::Bdf2, dt).with_solver(LinearSolver::SparseCholesky),
        Method::new(Integrator::Bdf2, dt),
        Method::new(Integrator::GeneralizedAlpha, dt).with_solver(LinearSolver::SparseCholesky),
        Method::new(Integrator::GeneralizedAlpha, dt).with_solver(LinearSolver::default_cg()),
        Method::new(Integrator::GeneralizedAlpha, dt)
            .with_solver(LinearSolver::default_two_level())
            .with_newton(4),
        Method::new(Integrator::GeneralizedAlpha, dt),
    ];
    for m in methods {
        let out = run_sheet(&spec, &m, 1.0);
        if let Some(p) = out.profile {
            print_profile(&format!("{} at {}", m.label(), m.step_label()), &p, out.wall_s);
        }
    }
    println!();
}

/// One generalised-α run of the standard sheet set from the environment (`DT`, `NEWTON`, `RHO`,
/// `SOLVER` = cg | cholesky | two-level | aggregation, `CGTOL`), printed on one line.
fn probe_section() -> Result<(), Error> {
    let spec = SheetSpec::standard(64);
    let reference = sheet_reference(&spec)?;
    let com_ref = reference_com(64);
    let net = spec.build().unwrap();
    let env = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<f64>().ok());
    let dt = env("DT").unwrap_or(1.0 / 60.0);
    let mut m = Method::new(Integrator::GeneralizedAlpha, dt);
    m.solve.newton_iterations = env("NEWTON").map(|k| k as usize);
    m.solve.rho_inf = env("RHO");
    if let Ok(name) = std::env::var("SOLVER") {
        m.solve.linear_solver = Some(name.parse()?);
    }
    if let Some(tolerance) = env("CGTOL") {
        m.solve.linear_solver = match m.solve.linear_solver.unwrap_or(LinearSolver::default_aggregation()) {
            LinearSolver::TwoLevel { max_iterations, .. } => {
                Some(LinearSolver::TwoLevel { tolerance, max_iterations })
            }
            LinearSolver::ConjugateGradient { max_iterations, .. } => {
                Some(LinearSolver::ConjugateGradient { tolerance, max_iterations })
            }
            LinearSolver::RigidAggregation { max_iterations, .. } => {
                Some(LinearSolver::RigidAggregation { tolerance, max_iterations })
            }
            other => Some(other),
        };
    }
    let out = run_sheet(&spec, &m, 1.0);
    let com = net.centre_of_mass(&out.x);
    let p = out.profile.unwrap_or_default();
    let steps = p.steps.max(1) as f64;
    println!(
        "{}: wall {:.3} s  {:.2} ms/step  CoM {:.2} mm  RMS {:.2} mm  newton/step {:.2}  cg/step {:.2}  asm {:.2} setup {:.2} solve {:.2} ms/step  fact {} {}",
        m.label(),
        out.wall_s,
        out.wall_s * 1e3 / steps,
        com.distance(com_ref) * 1e3,
        rms(&out.x, &reference) * 1e3,
        p.newton_iterations as f64 / steps,
        p.solver_iterations as f64 / steps,
        p.assembly_s * 1e3 / steps,
        p.setup_s * 1e3 / steps,
        p.solve_s * 1e3 / steps,
        p.factorizations,
        out.error.as_deref().unwrap_or("")
    );
    Ok(())
}

fn drapes_section() -> Result<(), Error> {
    let contact_in = ContactMode::InSolve;
    let after = ContactMode::AfterStep;
    let alpha_60 = DrapeMethod::fixed(Integrator::GeneralizedAlpha, 1.0 / 60.0, contact_in);
    let methods = [
        alpha_60,
        DrapeMethod { method: alpha_60.method.with_rho_inf(0.0), ..alpha_60 },
        DrapeMethod { method: alpha_60.method.with_rho_inf(0.4), ..alpha_60 },
        DrapeMethod { method: alpha_60.method.with_newton(8), ..alpha_60 },
        DrapeMethod { method: alpha_60.method.with_solver(LinearSolver::SparseCholesky), ..alpha_60 },
        DrapeMethod::fixed(Integrator::GeneralizedAlpha, 1.0 / 120.0, contact_in),
        DrapeMethod::fixed(Integrator::GeneralizedAlpha, 1.0 / 240.0, contact_in),
        DrapeMethod::fixed(Integrator::GeneralizedAlpha, 1.0 / 1000.0, contact_in),
        DrapeMethod::fixed(Integrator::GeneralizedAlpha, 1.0 / 4000.0, contact_in),
        DrapeMethod::fixed(Integrator::GeneralizedAlpha, 1.0 / 60.0, after),
        DrapeMethod::fixed(Integrator::ImplicitEuler, 1.0 / 60.0, after),
        DrapeMethod::fixed(Integrator::Bdf2, 1.0 / 60.0, after),
    ];
    for d in &DRAPES {
        let faithful_ref = drape_reference(d, &faithful(), "rk4-beta-1e-3")?;
        let converged_ref = drape_reference(d, &converged_in_solve(), "alpha-in-solve-16000-newton-8")?;
        let (scene, meshes) = load_drape(d)?;
        println!("## {} (end {} s)\n", d.title, d.snapshots[3]);
        println!(
            "The converged in-solve model (generalised-α, contact in the solve, 1/16 000 s) differs from the faithful reference by {:.2} mm (largest RMS over {:?} s).\n",
            worst_rms(&converged_ref, &faithful_ref) * 1e3,
            d.snapshots
        );
        println!(
            "| method | step | steps | wall time | RMS vs faithful | RMS vs converged in-solve | most particles inside after a step |"
        );
        println!("|---|---|---|---|---|---|---|");
        for m in &methods {
            let mut walls = Vec::new();
            let mut last = None;
            for _ in 0..3 {
                let out = run_drape(&scene, &meshes, m, &d.snapshots, true)?;
                walls.push(out.wall_s);
                let slow = out.wall_s > 2.0;
                last = Some(out);
                if slow {
                    break;
                }
            }
            let out = last.expect("ran");
            println!(
                "| {} | {} | {} | {:.3} s | {:.2} mm | {:.2} mm | {} |",
                m.label(),
                m.step_label(),
                out.steps,
                median(walls),
                worst_rms(&out.snapshots, &faithful_ref) * 1e3,
                worst_rms(&out.snapshots, &converged_ref) * 1e3,
                out.most_inside
            );
        }
        let m = DrapeMethod::fixed(Integrator::GeneralizedAlpha, 1.0 / 60.0, contact_in);
        let out = run_drape(&scene, &meshes, &m, &d.snapshots, false)?;
        if let Some(p) = out.profile {
            println!(
                "\n| method | total | force + Jacobian + assembly | set-up | solves | contact | rest | Newton its/step | CG its/step | CG its/Newton | factorisations |"
            );
            println!("|---|---|---|---|---|---|---|---|---|---|---|");
            print_profile("generalized-alpha in-solve at 1/60 s (ms per step)", &p, out.wall_s);
        }
        println!();
    }
    Ok(())
}

/// One generalised-α drape with contact in the solve, set from the environment (`DRAPE` = bunny |
/// table | sphere, `DT`, `NEWTON`, `RHO`; `E` and `MU` change the scene's restitution and friction,
/// for the run and the converged reference; the thesis's run keeps the scene's own): its error at
/// each snapshot time against both references; with `POINTS` set, first each material point's distance from the faithful run at the last snapshot
/// (mm, with the faithful position); with `TRACE` = a particle's index, first its position in the run
/// and in both references at each snapshot. `TIMES` (comma-separated seconds, on the step's grid)
/// replaces the thesis's snapshot times, both references then run afresh.
fn drape_probe_section() -> Result<(), Error> {
    let env = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<f64>().ok());
    let slug = std::env::var("DRAPE").unwrap_or_else(|_| "sphere".into());
    let d = DRAPES.iter().find(|d| d.slug == slug).ok_or_else(|| format!("no drape `{slug}`"))?;
    // `TIMES` (comma-separated seconds) compares at other times than the thesis's snapshots; both
    // references are then run afresh.
    let times: Option<Vec<f64>> = match std::env::var("TIMES") {
        Ok(s) => Some(
            s.split(',')
                .map(|t| {
                    t.trim()
                        .parse::<f64>()
                        .map_err(|e| format!("TIMES: `{}` is not a time in seconds: {e}", t.trim()))
                })
                .collect::<Result<_, _>>()?,
        ),
        Err(_) => None,
    };
    let snaps = times.clone().unwrap_or_else(|| d.snapshots.to_vec());
    // The fine drapes' 17 × 17 particles.
    let trace = match env("TRACE") {
        Some(k) if k >= 0.0 && k.fract() == 0.0 && k < (17 * 17) as f64 => Some(k as usize),
        Some(k) => return Err(format!("TRACE: {k} is not a particle index (0 to {})", 17 * 17 - 1).into()),
        None => None,
    };
    let (mut scene, meshes) = load_drape(d)?;
    let faithful_ref = if times.is_some() {
        run_drape(&scene, &meshes, &faithful(), &snaps, false)?.snapshots
    } else {
        drape_reference(d, &faithful(), "rk4-beta-1e-3")?
    };
    // `E` (restitution) and `MU` (friction of the cloth and every object) change the scene; the
    // converged reference is then run afresh with them instead of read from the cache.
    let (e, mu) = (env("E"), env("MU"));
    if let Some(e) = e {
        scene.restitution = e;
    }
    if let Some(mu) = mu {
        scene.material.friction = mu;
        for o in &mut scene.objects {
            o.friction = mu;
        }
    }
    let converged_ref = if e.is_some() || mu.is_some() || times.is_some() {
        run_drape(&scene, &meshes, &converged_in_solve(), &snaps, false)?.snapshots
    } else {
        drape_reference(d, &converged_in_solve(), "alpha-in-solve-16000-newton-8")?
    };
    let mut m = DrapeMethod::fixed(
        Integrator::GeneralizedAlpha,
        env("DT").unwrap_or(1.0 / 60.0),
        ContactMode::InSolve,
    );
    m.method.solve.newton_iterations = env("NEWTON").map(|k| k as usize);
    m.method.solve.rho_inf = env("RHO");
    let out = run_drape(&scene, &meshes, &m, &snaps, true)?;
    let per = |r: &[Vec<DVec3>]| {
        out.snapshots
            .iter()
            .zip(r)
            .map(|(a, b)| format!("{:.1}", rms_at_material_points(a, b) * 1e3))
            .collect::<Vec<_>>()
            .join(" ")
    };
    if let Some(k) = trace {
        for ((t, a), (b, f)) in snaps.iter().zip(&out.snapshots).zip(converged_ref.iter().zip(&faithful_ref))
        {
            println!("t {t:.4}: {:+.4?} converged {:+.4?} thesis {:+.4?}", a[k], b[k], f[k]);
        }
    }
    if std::env::var("POINTS").is_ok() {
        let (a, b) = (out.snapshots.last().expect("snapshots"), faithful_ref.last().expect("snapshots"));
        for r in (0..17).step_by(4) {
            let row: Vec<String> = (0..17)
                .step_by(4)
                .map(|c| {
                    let (p, q) = (a[r * 17 + c], b[r * 17 + c]);
                    format!("{:5.1} ({:+.2},{:+.2},{:+.2})", p.distance(q) * 1e3, q.x, q.y, q.z)
                })
                .collect();
            println!("{}", row.join("  "));
        }
    }
    println!(
        "{} {}: wall {:.3} s, inside {}; RMS (mm) at {:?} s vs thesis [{}], vs converged [{}]",
        d.slug,
        m.label(),
        out.wall_s,
        out.most_inside,
        snaps,
        per(&faithful_ref),
        per(&converged_ref)
    );
    Ok(())
}

fn main() -> Result<(), Error> {
    let what = std::env::args().nth(1).unwrap_or_else(|| "all".into());
    let all = what == "all";
    if all || what == "spring" {
        spring_section();
    }
    if all || what == "sheet" {
        sheet_section()?;
    }
    if all || what == "breakdown" {
        breakdown_section();
    }
    if what == "probe" {
        probe_section()?;
    }
    if what == "drape-probe" {
        drape_probe_section()?;
    }
    if all || what == "drapes" {
        drapes_section()?;
    }
    Ok(())
}
