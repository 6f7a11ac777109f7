//! Running a sheet scene (`SheetScene(…)`, such as the standard benchmark sheets): OBJ frames, pictures
//! and the summary's numbers.

use std::path::Path;
use std::time::Instant;

use anima_cloth::StepError;
use anima_cloth::membrane::{MembraneSheetSpec, MembraneSim};
use anima_cloth::network_sim::NetworkSim;
use anima_cloth::spring_net::Threads;
use anima_geom::obj::write_obj;
use anima_geom::{Aabb, DVec3, grid_triangles};
use anima_ode::{IntegrationError, OdeSystem, State, StepControl, Stepper, integrate};
use anima_scene::sheet::{SheetModel, SheetScene};
use anima_viz::gltf::UpAxis;
use anima_viz::{Camera, Image, RenderMesh, RenderSettings, render};
use anyhow::{Result, bail};
use serde::Serialize;

use super::export::GltfExport;
use super::{ClothFrames, Detail, Progress, RunOptions, Summary, sheet_frames, stability_warning};
use crate::output::write_atomic;
use crate::simulation::Deformable;

/// The numbers of a sheet run.
#[derive(Debug, Clone, Serialize)]
pub struct SheetDetail {
    /// `springs` or `membrane` ([`SheetModel`]).
    pub model: &'static str,
    pub integrator: String,
    pub dt: f64,
    pub particles: usize,
    /// Springs of a spring sheet; 0 for a membrane.
    pub springs: usize,
    /// Triangles of a membrane; 0 for a spring sheet.
    pub triangles: usize,
    pub ns_per_particle_step: f64,
    /// Threads the spring forces were evaluated on ([`RunOptions::parallel`]; 1 for the implicit
    /// integrators).
    pub threads: usize,
    /// Mass-weighted centre of the particles at the end, m.
    pub center_of_mass: [f64; 3],
    /// RMS particle distance to the reference, m (with `--reference`).
    pub rms_to_reference: Option<f64>,
    pub max_strain: f64,
    pub max_speed: f64,
    pub kinetic_energy: f64,
    pub solver_iterations: usize,
}

/// Runs a sheet scene to its end (or to the first failure).
pub fn run(
    scene: &SheetScene,
    label: &str,
    opts: &RunOptions,
    progress: &mut dyn Progress,
) -> Result<Summary> {
    let n = scene.sheet.n * scene.sheet.n;
    if let Some(r) = &opts.reference
        && r.len() != n
    {
        bail!("the reference has {} vertices, the sheet {n} particles", r.len());
    }
    let (mut sim, triangles) = new_cloth(scene, opts.parallel)?;
    let (n_springs, n_triangles) = sim.springs_and_triangles();
    let threads = sim.threads();
    opts.solve.configure(sim.stepper_mut());
    let mut warnings = Vec::new();
    let pinned: Vec<bool> = {
        let mut p = vec![false; n];
        for &(i, j) in &scene.sheet.pinned {
            p[j * scene.sheet.n + i] = true;
        }
        p
    };
    let v = vec![DVec3::ZERO; n];
    let x0 = sim.positions().to_vec();
    // 200 iterations: 60 underestimated ω_max of the 256 × 256 sheet, whose spectrum is dense at the top.
    let (omega, zeta) =
        anima_ode::stability::max_frequency_and_damping(sim.system(), 0.0, &x0, &v, &pinned, 200);
    let damping = match scene.model {
        SheetModel::Springs => {
            (scene.sheet.damping > 0.0).then(|| format!("spring damping c = {} N·s/m", scene.sheet.damping))
        }
        SheetModel::Membrane(m) => {
            (m.damping > 0.0).then(|| format!("stiffness-proportional damping c_d = {} s", m.damping))
        }
    };
    if let Some(w) = stability_warning(
        scene.integrator,
        scene.dt_s,
        (scene.duration_s / scene.dt_s).round() as usize,
        omega,
        zeta,
        damping.as_deref(),
    ) {
        progress.warn(&w);
        warnings.push(w);
    }
    let n_steps = (scene.duration_s / scene.dt_s).round() as usize;
    // At least one frame, and the last frame is always the end of the run.
    let n_frames = ((scene.duration_s * scene.frame_rate_hz).round() as usize).max(1);
    let mut snapshots: Vec<(usize, f64, Vec<DVec3>)> = Vec::new();
    let shown = sheet_frames(n_frames);
    // The sheet's up is against its gravity (z up in the standard sheets).
    let mut export = match opts.export_dir() {
        Some(_) => {
            let up = UpAxis::against(scene.sheet.gravity, UpAxis::PlusZ);
            let mut e = GltfExport::cloth(up, &[], &[("sheet", n, &triangles)], n_frames)?;
            e.deforming_frame(0, sim.time(), |_| sim.positions());
            Some(e)
        }
        None => None,
    };
    // Frame by frame, what the summary reports at the end (series.json, when the run writes output).
    let names = [("kinetic energy".to_owned(), "J"), ("self-intersections".to_owned(), "crossing pairs")];
    let mass = scene.sheet.total_mass;
    let values =
        |sim: &Cloth, crossings: Option<usize>| [Some(sim.kinetic_energy(mass)), crossings.map(|c| c as f64)];
    let mut per_frame = ClothFrames::new(opts, names, 0.0, sim.positions(), &triangles, |c| values(&sim, c));
    progress.begin(n_steps as u64);
    let start = Instant::now();
    let mut error = None;
    let mut diverged = false;
    let mut frames = 0;
    // What the adaptive methods did (the model's own clock counts fixed steps only).
    let mut adaptive_steps: Option<(u64, f64)> = None;
    if scene.integrator.is_adaptive() {
        // Adaptive methods choose their own steps under the embedded controller, frame by frame, each
        // frame starting at the step the last one ended with; at most ADAPTIVE_STEP_BUDGET times the
        // fixed-step count, so that a stiff sheet the controller crawls through ends on its own.
        let mut stepper = Stepper::new(scene.integrator, n);
        let mut state = State::new(sim.positions().to_vec(), sim.velocities().to_vec());
        let mut scratch = State::zeros(n);
        let budget = (ADAPTIVE_STEP_BUDGET * n_steps.max(1)) as u64;
        let (mut t, mut h, mut taken, mut evaluations) = (0.0, scene.dt_s, 0u64, 0usize);
        // The model's own steps are not taken, so its bounds are checked here, once a frame: a divergence
        // that stays finite ends the run as it does at a fixed step.
        sim.restart_bounds();
        for k in 1..=n_frames {
            let t_end = if k == n_frames { scene.duration_s } else { k as f64 / scene.frame_rate_hz };
            let control =
                StepControl::Adaptive { tolerance: 1e-6, dt_initial: h, dt_min: 1e-8, dt_max: 0.01 };
            let stepped =
                integrate(sim.system(), &mut stepper, control, t, t_end, &mut state, &mut scratch, |_, _| {});
            match stepped {
                Ok(stats) => {
                    taken += stats.steps as u64;
                    evaluations += stats.evaluations;
                    if stats.largest_dt > 0.0 {
                        h = stats.largest_dt;
                    }
                    t = t_end;
                }
                Err(e) => {
                    diverged = matches!(e, IntegrationError::NonFinite { .. });
                    error = Some(e.to_string());
                    break;
                }
            }
            sim.set_state(&state.x, &state.v);
            if let Err(e) = sim.check_bounds_at(taken, t) {
                error = Some(e.to_string());
                break;
            }
            frames = k;
            progress.advance(((t / scene.duration_s) * n_steps as f64) as u64);
            crate::interrupt::check()?;
            per_frame.output.time(|| {
                let frame = Frame { k, t, x: sim.positions(), triangles: &triangles };
                frame.write(opts, export.as_mut(), shown.contains(&k).then_some(&mut snapshots))
            })?;
            per_frame.frame(k, t, sim.positions(), &triangles, |c| values(&sim, c))?;
            if taken > budget && k < n_frames {
                error = Some(format!(
                    "stopped at t = {t} s after {taken} adaptive steps, {ADAPTIVE_STEP_BUDGET} times the {n_steps} steps \
                     of the scene's dt_s: the controller is crawling (a stiff or diverging sheet); try a fixed-step \
                     or implicit integrator"
                ));
                break;
            }
        }
        sim.set_evaluations(evaluations);
        adaptive_steps = Some((taken, t));
    } else {
        for k in 1..=n_frames {
            let target = if k == n_frames {
                n_steps
            } else {
                ((k as f64 / (scene.frame_rate_hz * scene.dt_s)).round() as usize).min(n_steps)
            };
            let left = (target as u64).saturating_sub(sim.steps());
            if let Err(e) = sim.run(left) {
                diverged = e.is_non_finite();
                error = Some(e.to_string());
                break;
            }
            frames = k;
            progress.advance(sim.steps());
            crate::interrupt::check()?;
            per_frame.output.time(|| {
                let frame = Frame { k, t: sim.time(), x: sim.positions(), triangles: &triangles };
                frame.write(opts, export.as_mut(), shown.contains(&k).then_some(&mut snapshots))
            })?;
            per_frame.frame(k, sim.time(), sim.positions(), &triangles, |c| values(&sim, c))?;
        }
    }
    let wall_seconds = start.elapsed().as_secs_f64() - per_frame.watch.seconds();
    let output_seconds = per_frame.output.seconds();
    progress.end();
    let x = sim.positions();
    per_frame.watch.look(x, &triangles);
    let (steps, simulated_seconds) = adaptive_steps.unwrap_or((sim.steps(), sim.time()));
    super::closing_warnings(export, opts, Some(&per_frame.watch), progress, &mut warnings)?;
    let summary = Summary {
        scene: label.to_owned(),
        kind: "sheet",
        steps,
        frames,
        simulated_seconds,
        wall_seconds,
        output_seconds,
        all_finite: !diverged && x.iter().chain(sim.velocities()).all(|p| p.is_finite()),
        error,
        warnings,
        self_intersections: Some(per_frame.watch.largest),
        detail: Detail::Sheet(SheetDetail {
            model: match scene.model {
                SheetModel::Springs => "springs",
                SheetModel::Membrane(_) => "membrane",
            },
            integrator: scene.integrator.name().to_owned(),
            dt: scene.dt_s,
            particles: n,
            springs: n_springs,
            triangles: n_triangles,
            ns_per_particle_step: (wall_seconds - output_seconds) * 1e9 / (steps.max(1) as usize * n) as f64,
            threads,
            center_of_mass: sim.centre_of_mass(x).to_array(),
            rms_to_reference: opts.reference.as_ref().map(|r| {
                (x.iter().zip(r).map(|(a, b)| a.distance_squared(*b)).sum::<f64>() / n as f64).sqrt()
            }),
            max_strain: sim.max_strain(x),
            max_speed: sim.velocities().iter().map(|v| v.length()).fold(0.0, f64::max),
            kinetic_energy: sim.kinetic_energy(scene.sheet.total_mass),
            solver_iterations: sim.solver_iterations(),
        }),
    };
    if let Some(dir) = &opts.out_dir {
        write_atomic(&dir.join("final.obj"), |w| Ok(write_obj(w, "sheet", x, &triangles)?))?;
    }
    per_frame.write_series(opts)?;
    if let Some(dir) = opts.picture_dir() {
        write_pictures(dir, x, sim.time(), &snapshots, &triangles)?;
    }
    Ok(summary)
}

/// Adaptive integrators may take many times the scene's fixed-step count (they are not held to
/// `dt_s`), but not without bound: a sheet the step controller crawls through is stopped past this
/// multiple of `duration_s / dt_s` accepted steps, with a message saying so.
const ADAPTIVE_STEP_BUDGET: usize = 100;

/// One output frame of a sheet run: written as OBJ, added to the glTF export, and kept for the
/// pictures when `snapshot` is given.
struct Frame<'a> {
    k: usize,
    t: f64,
    x: &'a [DVec3],
    triangles: &'a [[u32; 3]],
}

impl Frame<'_> {
    fn write(
        &self,
        opts: &RunOptions,
        export: Option<&mut GltfExport>,
        snapshot: Option<&mut Vec<(usize, f64, Vec<DVec3>)>>,
    ) -> Result<()> {
        if let Some(e) = export {
            e.deforming_frame(self.k, self.t, |_| self.x);
        }
        if let Some(dir) = opts.frame_dir() {
            write_atomic(&dir.join(format!("sheet_{}.obj", self.k)), |w| {
                Ok(write_obj(w, "sheet", self.x, self.triangles)?)
            })?;
        }
        if opts.picture_dir().is_some()
            && let Some(s) = snapshot
        {
            s.push((self.k, self.t, self.x.to_vec()));
        }
        Ok(())
    }
}

/// The cloth of a sheet scene, in either model (also what [`crate::sim::ClothSim`] steps): the contract
/// every cloth model keeps, and what a sheet run reads of its model beyond it.
pub(crate) trait SheetCloth: Deformable<Error = StepError> + Send + Sync {
    /// Springs of a spring sheet, triangles of a membrane (0 for the other).
    fn springs_and_triangles(&self) -> (usize, usize);
    /// Threads the forces are evaluated on ([`RunOptions::parallel`]).
    fn threads(&self) -> usize;
    /// The model as an ODE system, for a run that integrates it itself (the adaptive methods) and for
    /// the stability estimate.
    fn system(&mut self) -> &mut dyn OdeSystem<Coord = DVec3>;
    /// Takes the bounds from the state as it is now (for a run that integrates the system itself).
    fn restart_bounds(&mut self);
    /// Checks the state as it is now against the model's bounds, at the caller's step count and time.
    fn check_bounds_at(&self, step: u64, time: f64) -> Result<(), StepError>;
    fn centre_of_mass(&self, x: &[DVec3]) -> DVec3;
    /// The largest spring strain, or the largest principal strain of a membrane triangle.
    fn max_strain(&self, x: &[DVec3]) -> f64;
    /// The kinetic energy now, J, of a sheet of `total_mass` kg.
    fn kinetic_energy(&self, total_mass: f64) -> f64;
    fn solver_iterations(&self) -> usize;
    /// Records the force evaluations of a run that integrated the system itself.
    fn set_evaluations(&mut self, evaluations: usize);
}

pub(crate) type Cloth = Box<dyn SheetCloth>;

/// The scene's cloth at rest and its triangles (the frames' faces); `parallel` as
/// [`RunOptions::parallel`].
pub(crate) fn new_cloth(scene: &SheetScene, parallel: bool) -> Result<(Cloth, Vec<[u32; 3]>)> {
    let sheet = &scene.sheet;
    Ok(match scene.model {
        SheetModel::Springs => {
            let mut net = sheet.build()?;
            // The implicit steps evaluate their forces with the system, spring by spring, on one
            // thread.
            net.threads =
                if parallel && !scene.integrator.is_implicit() { Threads::Auto } else { Threads::One };
            let sim = NetworkSim::new(net, sheet.positions(), scene.integrator, scene.dt_s)?;
            (Box::new(sim), grid_triangles(sheet.n, sheet.n))
        }
        SheetModel::Membrane(material) => {
            let spec = MembraneSheetSpec {
                n: sheet.n,
                size: sheet.size,
                height: sheet.height,
                total_mass: sheet.total_mass,
                material,
                pinned: sheet.pinned.clone(),
                gravity: sheet.gravity,
            };
            let sim = MembraneSim::new(spec.build()?, spec.positions(), scene.integrator, scene.dt_s)?;
            (Box::new(sim), spec.triangles())
        }
    })
}

impl SheetCloth for NetworkSim {
    fn springs_and_triangles(&self) -> (usize, usize) {
        (self.network.springs().len(), 0)
    }
    fn threads(&self) -> usize {
        NetworkSim::threads(self)
    }
    fn system(&mut self) -> &mut dyn OdeSystem<Coord = DVec3> {
        &mut self.network
    }
    fn restart_bounds(&mut self) {
        NetworkSim::restart_bounds(self)
    }
    fn check_bounds_at(&self, step: u64, time: f64) -> Result<(), StepError> {
        Ok(NetworkSim::check_bounds_at(self, step, time)?)
    }
    fn centre_of_mass(&self, x: &[DVec3]) -> DVec3 {
        self.network.centre_of_mass(x)
    }
    fn max_strain(&self, x: &[DVec3]) -> f64 {
        self.network.max_strain(x)
    }
    /// Equal particles: ½ (M/n) Σ v².
    fn kinetic_energy(&self, total_mass: f64) -> f64 {
        let v = &self.state.v;
        0.5 * total_mass / v.len() as f64 * v.iter().map(|v| v.length_squared()).sum::<f64>()
    }
    fn solver_iterations(&self) -> usize {
        self.stats.solver_iterations
    }
    fn set_evaluations(&mut self, evaluations: usize) {
        self.stats.evaluations = evaluations;
    }
}

impl SheetCloth for MembraneSim {
    fn springs_and_triangles(&self) -> (usize, usize) {
        (0, self.membrane.n_triangles())
    }
    fn threads(&self) -> usize {
        1
    }
    fn system(&mut self) -> &mut dyn OdeSystem<Coord = DVec3> {
        &mut self.membrane
    }
    fn restart_bounds(&mut self) {
        MembraneSim::restart_bounds(self)
    }
    fn check_bounds_at(&self, step: u64, time: f64) -> Result<(), StepError> {
        MembraneSim::check_bounds_at(self, step, time)
    }
    fn centre_of_mass(&self, x: &[DVec3]) -> DVec3 {
        self.membrane.centre_of_mass(x)
    }
    fn max_strain(&self, x: &[DVec3]) -> f64 {
        self.membrane.max_strain(x)
    }
    /// A third of each triangle's mass at each corner.
    fn kinetic_energy(&self, _total_mass: f64) -> f64 {
        self.membrane.kinetic_energy(&self.state.v)
    }
    fn solver_iterations(&self) -> usize {
        self.solver_iterations
    }
    /// A membrane keeps no count of force evaluations.
    fn set_evaluations(&mut self, _evaluations: usize) {}
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
    let last = picture(last, 960, 720, &format!("t = {t:.2} s"))?;
    let tiles = snapshots
        .iter()
        .map(|(k, t, x)| picture(x, 400, 300, &format!("frame {k} (t = {t:.2} s)")))
        .collect::<Result<Vec<_>>>()?;
    crate::picture::write_final_and_sheet(dir, &last, &tiles, 3)
}
