//! Running a sheet scene (`SheetScene(...)` RON files, such as the standard benchmark sheets).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anima_cloth::network_sim::NetworkSim;
use anima_geom::obj::write_obj;
use anima_geom::{Aabb, DVec3, grid_triangles};
use anima_ode::{State, StepControl, Stepper, integrate};
use anima_scene::sheet::SheetScene;
use anima_viz::{Camera, Image, RenderMesh, RenderSettings, render};
use anyhow::{Context, Result, bail};
use serde::Serialize;

use crate::output::write_atomic;

/// What a sheet run writes.
#[derive(Debug, Clone)]
pub struct SheetRunOptions {
    pub out_dir: Option<PathBuf>,
    /// An OBJ whose vertices are the reference positions (e.g. another run's `final.obj`).
    pub reference: Option<PathBuf>,
    pub write_frames: bool,
    pub pictures: bool,
    pub progress: bool,
    /// Warn when the step is beyond the integrator's stability limit.
    pub warn_stability: bool,
    /// The linear solver of the implicit integrators (`None`: conjugate gradients).
    pub linear_solver: Option<anima_ode::LinearSolver>,
}

/// The JSON summary of a sheet run.
#[derive(Debug, Clone, Serialize)]
pub struct SheetSummary {
    pub scene: String,
    pub integrator: String,
    pub dt: f64,
    pub particles: usize,
    pub springs: usize,
    pub steps: usize,
    pub frames: usize,
    pub simulated_seconds: f64,
    pub wall_seconds: f64,
    pub ns_per_particle_step: f64,
    pub all_finite: bool,
    pub error: Option<String>,
    /// Mass-weighted centre of the particles at the end, m.
    pub center_of_mass: [f64; 3],
    /// RMS particle distance to the reference, m (with `--reference`).
    pub rms_to_reference: Option<f64>,
    pub max_strain: f64,
    pub max_speed: f64,
    pub kinetic_energy: f64,
    pub solver_iterations: usize,
}

/// Reads the vertices of an OBJ file (the `v x y z` lines, in order).
pub fn read_obj_vertices(path: &Path) -> Result<Vec<DVec3>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let mut parts = line.split_whitespace();
        if parts.next() != Some("v") {
            continue;
        }
        let nums: Vec<f64> = parts
            .map(str::parse)
            .collect::<Result<_, _>>()
            .with_context(|| format!("{}:{}: expected three numbers after `v`", path.display(), k + 1))?;
        match nums[..] {
            [x, y, z, ..] => out.push(DVec3::new(x, y, z)),
            _ => {
                bail!("{}:{}: expected three numbers after `v`, found {}", path.display(), k + 1, nums.len())
            }
        }
    }
    Ok(out)
}

/// Runs a sheet scene to its end (or to the first failure).
pub fn run_sheet(scene: &SheetScene, label: &str, opts: &SheetRunOptions) -> Result<SheetSummary> {
    if !(scene.dt_s > 0.0 && scene.duration_s > 0.0 && scene.frame_rate_hz > 0.0) {
        bail!("{label}: dt_s, duration_s and frame_rate_hz must be positive");
    }
    let reference = match &opts.reference {
        Some(p) => {
            let r = read_obj_vertices(p)?;
            let n = scene.sheet.n * scene.sheet.n;
            if r.len() != n {
                bail!("{}: the reference has {} vertices, the sheet {n} particles", p.display(), r.len());
            }
            Some(r)
        }
        None => None,
    };
    let net = scene.sheet.build();
    let n_springs = net.springs().len();
    let n = net.n_particles();
    let triangles = grid_triangles(scene.sheet.n, scene.sheet.n);
    let mut sim = NetworkSim::new(net, scene.sheet.positions(), scene.integrator, scene.dt_s);
    if let Some(solver) = opts.linear_solver {
        sim.stepper_mut().set_linear_solver(solver);
    }
    if opts.warn_stability {
        let pinned = sim.network.pinned().to_vec();
        let v = vec![DVec3::ZERO; n];
        let omega = anima_ode::stability::max_frequency(&mut sim.network, 0.0, &sim.state.x, &v, &pinned, 60);
        if let Some(w) = anima_ode::stability::check_step(scene.integrator, scene.dt_s, omega) {
            eprintln!("anima: warning: {w}");
        }
    }
    let n_steps = (scene.duration_s / scene.dt_s).round() as usize;
    // At least one frame, and the last frame is always the end of the run.
    let n_frames = ((scene.duration_s * scene.frame_rate_hz).round() as usize).max(1);
    let bar = opts.progress.then(|| indicatif::ProgressBar::new(n_steps as u64));
    let mut snapshots: Vec<(usize, f64, Vec<DVec3>)> = Vec::new();
    let shown = crate::run::flex3d::sheet_frames(n_frames);
    let start = Instant::now();
    let mut error = None;
    let mut frames = 0;
    if scene.integrator.is_adaptive() {
        // Adaptive methods choose their own steps: run the whole interval under the embedded controller.
        let mut stepper = Stepper::new(scene.integrator, n);
        let mut state = sim.state.clone();
        let mut scratch = State::zeros(n);
        let control =
            StepControl::Adaptive { tolerance: 1e-6, dt_initial: scene.dt_s, dt_min: 1e-8, dt_max: 0.01 };
        match integrate(
            &mut sim.network,
            &mut stepper,
            control,
            0.0,
            scene.duration_s,
            &mut state,
            &mut scratch,
            |_, _| {},
        ) {
            Ok(stats) => sim.stats.evaluations = stats.evaluations,
            Err(e) => error = Some(e.to_string()),
        }
        sim.state = state;
        frames = n_frames;
    } else {
        for k in 1..=n_frames {
            let target = if k == n_frames {
                n_steps
            } else {
                ((k as f64 / (scene.frame_rate_hz * scene.dt_s)).round() as usize).min(n_steps)
            };
            if let Err(e) = sim.run(target - sim.steps_taken()) {
                error = Some(e.to_string());
                break;
            }
            frames = k;
            if let Some(bar) = &bar {
                bar.set_position(sim.steps_taken() as u64);
            }
            if let Some(dir) = opts.out_dir.as_ref().filter(|_| opts.write_frames) {
                write_atomic(&dir.join(format!("sheet_{k}.obj")), |w| {
                    Ok(write_obj(w, "sheet", &sim.state.x, &triangles)?)
                })?;
            }
            if opts.pictures && shown.contains(&k) {
                snapshots.push((k, sim.time(), sim.state.x.clone()));
            }
        }
    }
    let wall_seconds = start.elapsed().as_secs_f64();
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    let x = &sim.state.x;
    let com = sim.network.centre_of_mass(x);
    let summary = SheetSummary {
        scene: label.to_owned(),
        integrator: scene.integrator.name().to_owned(),
        dt: scene.dt_s,
        particles: n,
        springs: n_springs,
        steps: sim.steps_taken(),
        frames,
        simulated_seconds: sim.time(),
        wall_seconds,
        ns_per_particle_step: wall_seconds * 1e9 / (sim.steps_taken().max(1) * n) as f64,
        all_finite: sim.state.first_non_finite().is_none(),
        error,
        center_of_mass: com.to_array(),
        rms_to_reference: reference
            .as_ref()
            .map(|r| (x.iter().zip(r).map(|(a, b)| a.distance_squared(*b)).sum::<f64>() / n as f64).sqrt()),
        max_strain: sim.network.max_strain(x),
        max_speed: sim.state.v.iter().map(|v| v.length()).fold(0.0, f64::max),
        kinetic_energy: 0.5 * scene.sheet.total_mass / n as f64
            * sim.state.v.iter().map(|v| v.length_squared()).sum::<f64>(),
        solver_iterations: sim.stats.solver_iterations,
    };
    if let Some(dir) = &opts.out_dir {
        write_atomic(&dir.join("final.obj"), |w| Ok(write_obj(w, "sheet", x, &triangles)?))?;
        if opts.pictures {
            write_pictures(dir, x, sim.time(), &snapshots, &triangles)?;
        }
    }
    Ok(summary)
}

fn write_pictures(
    dir: &Path,
    last: &[DVec3],
    t: f64,
    snapshots: &[(usize, f64, Vec<DVec3>)],
    triangles: &[[u32; 3]],
) -> Result<()> {
    let mut bounds = Aabb::from_points(last.iter().copied().filter(|p| p.is_finite()));
    for (_, _, s) in snapshots {
        bounds = s.iter().filter(|p| p.is_finite()).fold(bounds, |b, p| b.including(*p));
    }
    let camera = Camera::framing(bounds, DVec3::new(0.8, 0.6, -0.45), DVec3::Z, 35.0);
    let picture = |x: &[DVec3], w: u32, h: u32, label: &str| -> Result<Image> {
        let mesh = RenderMesh::new(x, triangles, [70, 110, 190]);
        let mut img = render(&[mesh], &camera, &RenderSettings::new(w, h))?;
        img.label(10, 8, label, (h as f64 / 18.0).clamp(12.0, 24.0))?;
        Ok(img)
    };
    let img = picture(last, 960, 720, &format!("t = {t:.2} s"))?;
    write_atomic(&dir.join("final.png"), |w| Ok(img.write_png(w)?))?;
    if !snapshots.is_empty() {
        let tiles = snapshots
            .iter()
            .map(|(k, t, x)| picture(x, 400, 300, &format!("frame {k} (t = {t:.2} s)")))
            .collect::<Result<Vec<_>>>()?;
        let sheet = Image::grid(&tiles, 3, 4, [255, 255, 255])?;
        write_atomic(&dir.join("frames.png"), |w| Ok(sheet.write_png(w)?))?;
    }
    Ok(())
}
