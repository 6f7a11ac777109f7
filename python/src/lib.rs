//! `anima._anima`: the compiled half of anima's Python package. The Python half (`python/package/anima/`)
//! re-exports it, turns JSON summaries into dicts and drives optimisations over Ray.
//!
//! Arrays cross as NumPy `float64` arrays of shape `(n, 3)`. Reading a state copies it once, from the
//! simulator's memory into a new array that Python owns (a view would alias memory the next step
//! rewrites, and an adaptive cloth reallocates); `read_positions(out)` fills a caller's array with no
//! allocation at all. Writing a state reads the caller's C-contiguous array in place (`bytemuck` views
//! its `f64`s as `DVec3`s) straight into the simulator. Simulating releases the GIL.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anima_control::optimise::{Optimiser, RunLog, resume, run};
use anima_control::{Controller, ParamId};
use anima_geom::DVec3;
use anima_ode::Integrator;
use anima_run::run::{Overrides, RunOptions, Silent, SolveOptions};
use anima_run::sim::{ClothSim, FigureSim};
use anima_scene::optimisation::{LoadedOptimisation, ObjectiveSpec};
use anima_scene::sheet::SheetScene;
use anima_scene::{LoadOptions, Scene};
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2, PyReadwriteArray2, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

create_exception!(
    _anima,
    SceneError,
    PyValueError,
    "A scene, controller, optimisation or log file anima cannot read. The message names the file, the \
     line and column, what was expected and what was found."
);
create_exception!(
    _anima,
    SimulationError,
    PyRuntimeError,
    "A simulation that cannot go on: a non-finite state (the message names the step where it appeared) \
     or a solve that failed."
);

fn scene_error(e: impl std::fmt::Display) -> PyErr {
    SceneError::new_err(e.to_string())
}

fn simulation_error(e: anyhow::Error) -> PyErr {
    SimulationError::new_err(format!("{e:#}"))
}

/// How often a long computation looks for Ctrl-C.
const POLL: Duration = Duration::from_millis(50);

/// The worker's stack: a character's world steps with the main thread's depth in mind.
const WORKER_STACK: usize = 16 << 20;

/// Runs `work` to its end without the GIL, answering Ctrl-C: the work runs on a worker thread while
/// this one looks for a signal every [`POLL`]; at a `KeyboardInterrupt` it asks the work to stop
/// ([`anima_run::interrupt`]), waits for it to end at its next step or iteration, and raises. (Python
/// runs its signal handlers on the main thread only, so the thread that called in must be the one
/// that looks.)
fn interruptible<R: Send>(py: Python<'_>, work: impl FnOnce() -> R + Send) -> PyResult<R> {
    anima_run::interrupt::clear();
    std::thread::scope(|s| {
        let (tx, mut rx) = std::sync::mpsc::channel();
        let worker = std::thread::Builder::new()
            .name("anima".into())
            .stack_size(WORKER_STACK)
            .spawn_scoped(s, move || {
                let _ = tx.send(work());
            })
            .map_err(|e| PyRuntimeError::new_err(format!("starting a worker thread: {e}")))?;
        loop {
            let (received, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
            rx = back;
            match received {
                Ok(r) => return Ok(r),
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
                    // The work panicked: raise it here as Python's PanicException.
                    match py.detach(|| worker.join()) {
                        Err(panic) => std::panic::resume_unwind(panic),
                        Ok(()) => {
                            return Err(PyRuntimeError::new_err("the worker thread ended without a result"));
                        }
                    }
                }
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                    if let Err(e) = py.check_signals() {
                        anima_run::interrupt::request();
                        let _ = py.detach(|| worker.join());
                        anima_run::interrupt::clear();
                        return Err(e);
                    }
                }
            }
        }
    })
}

/// Runs `chunk(sim, k)` without the GIL for k = 1, 2, 4, … (k doubled while a chunk takes under half a
/// [`POLL`]) until it returns `true` (done), looking for Ctrl-C between chunks. Interrupted, the state
/// is that of the last whole step.
fn in_chunks<S: Send>(
    py: Python<'_>,
    sim: &mut S,
    mut chunk: impl FnMut(&mut S, usize) -> anyhow::Result<bool> + Send,
) -> PyResult<()> {
    let mut k = 1usize;
    loop {
        let start = Instant::now();
        if py.detach(|| chunk(&mut *sim, k)).map_err(simulation_error)? {
            return Ok(());
        }
        if start.elapsed() < POLL / 2 {
            k = k.saturating_mul(2);
        }
        py.check_signals()?;
    }
}

fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

fn integrator(name: Option<&str>) -> PyResult<Option<Integrator>> {
    name.map(|n| n.parse::<Integrator>().map_err(value_error)).transpose()
}

fn load_scene(path: &Path, gravity: Option<[f64; 3]>) -> PyResult<Scene> {
    let opts = LoadOptions { gravity: gravity.map(DVec3::from_array) };
    anima_scene::load(path, &opts).map_err(scene_error)
}

/// An `(n, 3)` float64 array of `x` (one copy, into memory the array owns).
fn to_array<'py>(py: Python<'py>, x: &[DVec3]) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let flat: &[f64] = bytemuck::cast_slice(x);
    PyArray1::from_slice(py, flat).reshape([x.len(), 3])
}

/// The `DVec3`s of a C-contiguous `(n, 3)` float64 array, read in place.
fn as_points<'a>(a: &'a PyReadonlyArray2<'_, f64>, what: &str) -> PyResult<&'a [DVec3]> {
    let shape = a.shape();
    if shape[1] != 3 {
        return Err(value_error(format!("{what}: expected an array of shape (n, 3), found {shape:?}")));
    }
    let flat = a.as_slice().ok().filter(|_| a.is_c_contiguous()).ok_or_else(|| {
        value_error(format!("{what}: expected a C-contiguous array (numpy.ascontiguousarray makes one)"))
    })?;
    Ok(bytemuck::cast_slice(flat))
}

/// Copies `values` into the caller's C-contiguous `(n, 3)` float64 array `out`.
fn fill(mut out: PyReadwriteArray2<'_, f64>, values: &[DVec3]) -> PyResult<()> {
    let values: &[f64] = bytemuck::cast_slice(values);
    let c_order = out.is_c_contiguous();
    let slice = out
        .as_slice_mut()
        .ok()
        .filter(|_| c_order)
        .ok_or_else(|| value_error("out: expected a C-contiguous array"))?;
    if slice.len() != values.len() {
        return Err(value_error(format!(
            "out: expected shape ({}, 3), found {} values",
            values.len() / 3,
            slice.len()
        )));
    }
    slice.copy_from_slice(values);
    Ok(())
}

fn triangles_array<'py>(py: Python<'py>, t: &[[u32; 3]]) -> PyResult<Bound<'py, PyArray2<u32>>> {
    let flat: &[u32] = bytemuck::cast_slice(t);
    PyArray1::from_slice(py, flat).reshape([t.len(), 3])
}

/// A triangle mesh as NumPy arrays: vertices `(k, 3)` and triangles `(m, 3)`.
type Mesh<'py> = (Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<u32>>);

/// What a pickled [`Evaluator`] holds: its objective (RON), parameter indices and controller (RON).
type EvaluatorState = (String, Vec<usize>, String);

/// A cloth of any kind anima simulates — a spring sheet, FLEX3D surfaces, an Oliveira drape (remeshed
/// or not) — to step from Python. Positions and velocities are `(n, 3)` float64 arrays in metres and
/// m/s, in the scene's axes (z up for sheets and drapes, y up for FLEX3D scripts).
#[pyclass(module = "anima._anima")]
pub struct Cloth {
    sim: ClothSim,
    duration: f64,
}

impl std::fmt::Debug for Cloth {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Cloth({}, {} particles, t = {} s)",
            self.sim.kind(),
            self.sim.positions().len(),
            self.sim.time()
        )
    }
}

impl Cloth {
    fn from_scene(scene: &Scene) -> PyResult<Self> {
        let sim = ClothSim::new(scene, &SolveOptions::default()).map_err(simulation_error)?;
        Ok(Self { sim, duration: scene.duration_s() })
    }

    fn build(
        mut scene: Scene,
        integrator_name: Option<&str>,
        dt: Option<f64>,
        duration: Option<f64>,
    ) -> PyResult<Self> {
        let overrides =
            Overrides { integrator: integrator(integrator_name)?, dt, duration, ..Overrides::default() };
        overrides.apply(&mut scene).map_err(value_error)?;
        Self::from_scene(&scene)
    }
}

#[pymethods]
impl Cloth {
    /// The standard benchmark sheet of `docs/benchmarks.md`: `n` × `n` particles on a 1 m square,
    /// 0.2 kg, pinned at two corners, z up. `integrator` is any name `anima run --integrator` takes
    /// (the default: symplectic Euler at the sheet's common step).
    #[staticmethod]
    #[pyo3(signature = (n = 64, integrator = None, dt = None, duration = None))]
    fn sheet(n: usize, integrator: Option<&str>, dt: Option<f64>, duration: Option<f64>) -> PyResult<Self> {
        if !(2..=1024).contains(&n) {
            return Err(value_error(format!("n must be between 2 and 1024 particles per side, found {n}")));
        }
        let scene = SheetScene::standard(n);
        scene.check().map_err(value_error)?;
        Self::build(Scene::Sheet(scene), integrator, dt, duration)
    }

    /// One of Oliveira 2013's drapes that need no mesh file: `test` is `"table"` (Test II, the round
    /// table) or `"sphere"` (Test III), with a `vertices_per_side` × `vertices_per_side` cloth (the
    /// thesis's fine mesh is 17). The Bunny (Test I) needs its mesh: `anima.load` its scene file.
    #[staticmethod]
    #[pyo3(signature = (test, vertices_per_side = 17, integrator = None, dt = None, duration = None))]
    fn drape(
        test: &str,
        vertices_per_side: usize,
        integrator: Option<&str>,
        dt: Option<f64>,
        duration: Option<f64>,
    ) -> PyResult<Self> {
        let text = match test {
            "table" => include_str!("../scenes/test-2-table-17x17.ron"),
            "sphere" => include_str!("../scenes/test-3-sphere-17x17.ron"),
            other => {
                return Err(value_error(format!("expected the drape `table` or `sphere`, found `{other}`")));
            }
        };
        if !(2..=257).contains(&vertices_per_side) {
            return Err(value_error(format!(
                "vertices_per_side must be between 2 and 257, found {vertices_per_side}"
            )));
        }
        let mut scene = anima_scene::oliveira::from_ron_str(text).map_err(scene_error)?;
        scene.cloth.vertices_per_side = vertices_per_side;
        let loaded = anima_scene::oliveira::LoadedOliveira { scene, meshes: Vec::new(), remesher: None };
        Self::build(Scene::Oliveira(loaded), integrator, dt, duration)
    }

    /// `sheet`, `flex3d` or `oliveira`.
    #[getter]
    fn kind(&self) -> &'static str {
        self.sim.kind()
    }

    /// Particles now (an adaptive drape's count changes when it is remeshed).
    #[getter]
    fn n(&self) -> usize {
        self.sim.positions().len()
    }

    /// Simulated time, s.
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time()
    }

    /// Steps taken.
    #[getter]
    fn steps(&self) -> u64 {
        self.sim.steps()
    }

    /// The next step, s.
    #[getter]
    fn dt(&self) -> f64 {
        self.sim.dt()
    }

    /// The scene's duration, s (where `run()` stops).
    #[getter]
    fn duration(&self) -> f64 {
        self.duration
    }

    /// Takes `n` steps, the GIL released. Raises `SimulationError` at a non-finite state.
    #[pyo3(signature = (n = 1))]
    fn step(&mut self, py: Python<'_>, n: usize) -> PyResult<()> {
        let mut left = n;
        in_chunks(py, &mut self.sim, |sim, k| {
            let k = k.min(left);
            sim.run(k)?;
            left -= k;
            Ok(left == 0)
        })
    }

    /// Steps until the simulated time reaches `t` s (by default the scene's duration).
    #[pyo3(signature = (t = None))]
    fn run(&mut self, py: Python<'_>, t: Option<f64>) -> PyResult<()> {
        let t = t.unwrap_or(self.duration);
        if !t.is_finite() {
            return Err(value_error(format!("the time to run to must be finite, found {t}")));
        }
        // In spans of k steps' time, each run to its end (the steps are those of one run to `t`).
        let dt = self.sim.dt().max(1e-9);
        in_chunks(py, &mut self.sim, |sim, k| {
            sim.run_until(t.min(sim.time() + k as f64 * dt))?;
            Ok(sim.time() >= t - 1e-12)
        })
    }

    /// Positions, an `(n, 3)` float64 array (a copy).
    #[getter]
    fn positions<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        to_array(py, self.sim.positions())
    }

    /// Velocities, an `(n, 3)` float64 array (a copy).
    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        to_array(py, self.sim.velocities())
    }

    /// Writes the positions into `out`, a C-contiguous `(n, 3)` float64 array, allocating nothing.
    fn read_positions(&self, out: PyReadwriteArray2<'_, f64>) -> PyResult<()> {
        fill(out, self.sim.positions())
    }

    /// Writes the velocities into `out`, as `read_positions` does.
    fn read_velocities(&self, out: PyReadwriteArray2<'_, f64>) -> PyResult<()> {
        fill(out, self.sim.velocities())
    }

    /// Replaces the state: `positions` and (when given, else the current ones kept) `velocities`, each
    /// a C-contiguous `(n, 3)` float64 array, read in place. Multistep and implicit integrators start
    /// their history again.
    #[pyo3(signature = (positions, velocities = None))]
    fn set_state(
        &mut self,
        positions: PyReadonlyArray2<'_, f64>,
        velocities: Option<PyReadonlyArray2<'_, f64>>,
    ) -> PyResult<()> {
        let x = as_points(&positions, "positions")?;
        let r = match &velocities {
            Some(v) => {
                let v = as_points(v, "velocities")?;
                self.sim.set_state(x, v)
            }
            None => {
                let v = self.sim.velocities().to_vec();
                self.sim.set_state(x, &v)
            }
        };
        r.map_err(value_error)
    }

    /// The cloth's triangles, an `(m, 3)` uint32 array of particle indices.
    #[getter]
    fn triangles<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<u32>>> {
        triangles_array(py, self.sim.triangles())
    }

    /// The static objects as `(vertices (k, 3), triangles (m, 3))` pairs (spheres and cylinders
    /// tessellated), for plotting.
    fn obstacles<'py>(&self, py: Python<'py>) -> PyResult<Vec<Mesh<'py>>> {
        self.sim
            .obstacles()
            .iter()
            .map(|m| Ok((to_array(py, m.vertices())?, triangles_array(py, m.triangles())?)))
            .collect()
    }

    fn __repr__(&self) -> String {
        format!("{self:?}")
    }
}

/// Articulated figures of a body scene (holding poses) or a character scene (driven by its controller),
/// to step from Python. The figures are planar, in the x–y plane with y up.
#[pyclass(module = "anima._anima", unsendable)]
pub struct Figure {
    sim: FigureSim,
    duration: f64,
}

impl std::fmt::Debug for Figure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Figure(t = {} s)", self.sim.time())
    }
}

#[pymethods]
impl Figure {
    /// Simulated time, s.
    #[getter]
    fn time(&self) -> f64 {
        self.sim.time()
    }

    /// The control step, s.
    #[getter]
    fn dt(&self) -> f64 {
        self.sim.dt()
    }

    /// The scene's duration, s.
    #[getter]
    fn duration(&self) -> f64 {
        self.duration
    }

    /// Takes `n` control steps.
    #[pyo3(signature = (n = 1))]
    fn step(&mut self, py: Python<'_>, n: usize) -> PyResult<()> {
        // One control step at a time, looking for Ctrl-C after each (a step is milliseconds).
        for _ in 0..n {
            self.sim.run(1).map_err(simulation_error)?;
            py.check_signals()?;
        }
        Ok(())
    }

    /// Every body's centre and angle, a `(bodies, 3)` float64 array of (x, y, angle about z) in m and
    /// rad, model after model, in the order of `body_names`.
    #[getter]
    fn poses<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let poses = self.sim.poses().map_err(simulation_error)?;
        let flat: Vec<f64> = poses.iter().flat_map(|p| [p.centre[0], p.centre[1], p.angle]).collect();
        PyArray1::from_vec(py, flat).reshape([poses.len(), 3])
    }

    /// `model/body` for every body, in the order of `poses`.
    #[getter]
    fn body_names(&self) -> PyResult<Vec<String>> {
        self.sim.body_names().map_err(simulation_error)
    }

    fn __repr__(&self) -> String {
        format!("{self:?}")
    }
}

/// Loads a scene file of any kind (`.par`, or a `.ron` scene): a `Cloth` for sheets, FLEX3D and
/// Oliveira scenes, a `Figure` for body and character scenes. `gravity` (m/s²) replaces a FLEX3D
/// scene's. A file anima cannot read raises `SceneError` naming the file, line and column.
#[pyfunction]
#[pyo3(signature = (path, gravity = None))]
fn load(py: Python<'_>, path: PathBuf, gravity: Option<[f64; 3]>) -> PyResult<Py<PyAny>> {
    let scene = load_scene(&path, gravity)?;
    match scene {
        Scene::Body(_) | Scene::Character(_) => {
            let sim = FigureSim::new(&scene).map_err(simulation_error)?;
            Ok(Py::new(py, Figure { sim, duration: scene.duration_s() })?.into_any())
        }
        _ => Ok(Py::new(py, Cloth::from_scene(&scene)?)?.into_any()),
    }
}

/// Runs a scene file to its end as `anima run` does and returns its summary as JSON text (the Python
/// wrapper `anima.run` returns it as a dict). With `out`, frames, pictures and `summary.json` go there,
/// and with `export = "gltf"` the run as an animated glTF, `animation.glb` (`"usd"`: a USD stage,
/// `animation.usda`).
#[pyfunction]
#[pyo3(signature = (path, out = None, integrator = None, dt = None, duration = None, export = None))]
fn run_json(
    py: Python<'_>,
    path: PathBuf,
    out: Option<PathBuf>,
    integrator: Option<&str>,
    dt: Option<f64>,
    duration: Option<f64>,
    export: Option<&str>,
) -> PyResult<String> {
    let export = match export {
        None => None,
        Some("gltf") => Some(anima_run::run::export::Export::Gltf),
        Some("usd") => Some(anima_run::run::export::Export::Usd),
        Some(other) => {
            return Err(value_error(format!("expected the export `gltf` or `usd`, found `{other}`")));
        }
    };
    if export.is_some() && out.is_none() {
        return Err(value_error("export needs an `out` folder to write the animation to"));
    }
    let mut scene = load_scene(&path, None)?;
    let overrides =
        Overrides { integrator: self::integrator(integrator)?, dt, duration, ..Overrides::default() };
    overrides.apply(&mut scene).map_err(value_error)?;
    let opts = match &out {
        Some(dir) => RunOptions { export, ..RunOptions::writing_to(dir) },
        None => RunOptions::quiet(),
    };
    let label = path.display().to_string();
    let summary = interruptible(py, || {
        let summary = anima_run::run::run(&scene, &label, &opts, &mut Silent)?;
        if let Some(dir) = &out {
            anima_run::run::write_summary(&dir.join("summary.json"), &summary)?;
        }
        Ok(summary)
    })?
    .map_err(simulation_error)?;
    serde_json_text(&summary)
}

fn serde_json_text(v: &impl serde::Serialize) -> PyResult<String> {
    serde_json::to_string(v).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// The thesis's walking evaluation (Nunes 2006 §7.6) of a controller file over `iterations` control
/// steps, as JSON text: iterations run, distance (m), whether it fell or stopped, and the fitness.
#[pyfunction]
#[pyo3(signature = (controller, iterations = 1000))]
fn walk_json(py: Python<'_>, controller: PathBuf, iterations: u64) -> PyResult<String> {
    let text = std::fs::read_to_string(&controller)
        .map_err(|e| scene_error(format!("{}: {e}", controller.display())))?;
    let c = Controller::from_ron(&text, &anima_character::procedures())
        .map_err(|e| scene_error(format!("{}: {e}", controller.display())))?;
    // Bound to the walker here, so that a sensor or a procedure argument the walker cannot answer is
    // a SceneError at its line of the file, not a failure of the run.
    let character = anima_run::objectives::humanoid_character(c).map_err(|e| match e.field_error(&text) {
        Some(located) => scene_error(format!("{}: {located}", controller.display())),
        None => simulation_error(e.into()),
    })?;
    let rules = anima_run::objectives::WalkRules::default();
    let outcome = interruptible(py, || {
        anima_run::objectives::walk_character(character, iterations, &rules, &[], |_| ())
    })?
    .map_err(|e| simulation_error(e.into()))?;
    #[derive(serde::Serialize)]
    struct Walk {
        #[serde(flatten)]
        outcome: anima_run::objectives::WalkOutcome,
        fitness: f64,
    }
    serde_json_text(&Walk { fitness: outcome.fitness(), outcome })
}

/// What an optimisation evaluates: its objective for its controller with the selected parameters set.
/// Picklable (it travels as RON text), so that Ray can send it to workers on other machines, which
/// need no file of the spec's.
#[pyclass(module = "anima._anima", frozen)]
#[derive(Debug, Clone)]
pub struct Evaluator {
    objective: ObjectiveSpec,
    controller: Controller,
    ids: Vec<ParamId>,
}

#[pymethods]
impl Evaluator {
    /// The fitness of the parameter vector `x` (any sequence of floats; larger is better), the GIL
    /// released. Deterministic:
    /// the same `x` gives the same value on any machine of the same build.
    fn __call__(&self, py: Python<'_>, x: Vec<f64>) -> PyResult<f64> {
        if x.len() != self.ids.len() {
            return Err(value_error(format!("x: expected {} parameters, found {}", self.ids.len(), x.len())));
        }
        interruptible(py, || anima_run::optimise::fitness(&self.objective, &self.controller, &self.ids, &x))
    }

    #[staticmethod]
    fn _restore(objective: &str, ids: Vec<usize>, controller: &str) -> PyResult<Self> {
        let objective: ObjectiveSpec = ron::from_str(objective).map_err(scene_error)?;
        let controller =
            Controller::from_ron(controller, &anima_character::procedures()).map_err(scene_error)?;
        let n = controller.params().len();
        if let Some(bad) = ids.iter().find(|&&i| i >= n) {
            return Err(value_error(format!("parameter id {bad}: the controller has {n} parameters")));
        }
        Ok(Self { objective, controller, ids: ids.into_iter().map(ParamId).collect() })
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, EvaluatorState)> {
        let me = slf.get();
        let objective = ron::to_string(&me.objective).map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        let restore = slf.getattr("_restore")?;
        Ok((restore, (objective, me.ids.iter().map(|i| i.0).collect(), me.controller.to_ron())))
    }
}

/// A controller optimisation from a spec file (`assets/optimisations/*.ron`), as an ask/tell loop
/// the caller drives: `ask()` a generation, evaluate it anywhere (`evaluator()` is picklable), `tell()`
/// the fitnesses in candidate order. The optimiser is seeded and asks for every random draw up front,
/// so the log depends only on the fitnesses told, never on where or in which order they were computed.
#[pyclass(module = "anima._anima", unsendable)]
pub struct Optimisation {
    opt: Box<dyn Optimiser + Send>,
    /// The spec, to build a fresh optimiser when a log does not replay.
    loaded: LoadedOptimisation,
    evaluator: Evaluator,
    log: RunLog,
    /// The generation asked and not yet told: its stage and candidates.
    pending: Option<(usize, Vec<Vec<f64>>)>,
    budget: usize,
    names: Vec<String>,
    name: String,
}

impl std::fmt::Debug for Optimisation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Optimisation({}, {} of {} evaluations)", self.name, self.log.len(), self.budget)
    }
}

#[pymethods]
impl Optimisation {
    #[new]
    fn new(spec: PathBuf) -> PyResult<Self> {
        let loaded = anima_scene::load_optimisation(&spec).map_err(scene_error)?;
        let ids = loaded.controller.free_params(&loaded.spec.parameters);
        if ids.is_empty() {
            return Err(value_error(format!("{}: the selection names no free parameter", spec.display())));
        }
        let opt = anima_run::optimise::optimiser(&loaded, &ids).map_err(value_error)?;
        let space = loaded.controller.space(&ids);
        Ok(Self {
            opt,
            loaded: loaded.clone(),
            names: space.dims.iter().map(|d| d.name.clone()).collect(),
            evaluator: Evaluator {
                objective: loaded.spec.objective,
                controller: loaded.controller.clone(),
                ids,
            },
            log: RunLog::default(),
            pending: None,
            budget: loaded.spec.evaluations,
            name: loaded.spec.name.clone(),
        })
    }

    /// The spec's name.
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// The spec's evaluation budget.
    #[getter]
    fn budget(&self) -> usize {
        self.budget
    }

    /// The free parameters' names, in the order of a candidate's values.
    #[getter]
    fn names(&self) -> Vec<String> {
        self.names.clone()
    }

    /// Evaluations told so far.
    #[getter]
    fn evaluations(&self) -> usize {
        self.log.len()
    }

    /// The next generation's candidates, a `(λ, d)` float64 array, or `None` when the optimiser has
    /// finished. Asking again before telling returns the same generation.
    fn ask<'py>(&mut self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
        if self.pending.is_none() {
            let stage = self.opt.stage();
            let candidates = self.opt.ask();
            if candidates.is_empty() {
                return Ok(None);
            }
            self.pending = Some((stage, candidates));
        }
        let (_, candidates) = self.pending.as_ref().expect("set above");
        let d = self.names.len();
        let flat: Vec<f64> = candidates.iter().flatten().copied().collect();
        Ok(Some(PyArray1::from_vec(py, flat).reshape([candidates.len(), d])?))
    }

    /// The fitnesses of the generation just asked, in candidate order: finite numbers (a failed
    /// evaluation is a value, such as 0, never NaN). A wrong count or a non-finite fitness raises
    /// ValueError and leaves the generation to tell.
    fn tell(&mut self, fitness: Vec<f64>) -> PyResult<()> {
        let Some((_, candidates)) = &self.pending else {
            return Err(PyRuntimeError::new_err("tell() without a generation asked"));
        };
        if fitness.len() != candidates.len() {
            return Err(value_error(format!(
                "expected {} fitnesses, one per candidate, found {}",
                candidates.len(),
                fitness.len()
            )));
        }
        if let Some(k) = fitness.iter().position(|f| !f.is_finite()) {
            return Err(value_error(format!(
                "fitness {k} is {}: expected a finite number (a failed evaluation is a value, such as 0)",
                fitness[k]
            )));
        }
        let (stage, candidates) = self.pending.take().expect("checked above");
        let accepted = self.opt.tell(&candidates, &fitness);
        let generation = self.log.generations;
        for ((x, f), a) in candidates.into_iter().zip(fitness).zip(accepted) {
            self.log.evaluations.push(anima_control::optimise::Evaluation {
                generation,
                stage,
                x,
                fitness: f,
                accepted: a,
            });
        }
        self.log.generations += 1;
        if self.log.optimiser.is_empty() {
            self.log.optimiser = self.opt.name().to_owned();
        }
        Ok(())
    }

    /// The objective, picklable, to evaluate candidates wherever they run.
    fn evaluator(&self) -> Evaluator {
        self.evaluator.clone()
    }

    /// Runs the optimisation in this process to `budget` evaluations (the spec's by default),
    /// evaluating each generation on all cores; the same seed gives the same log as any ask/tell loop.
    #[pyo3(signature = (budget = None))]
    fn run(&mut self, py: Python<'_>, budget: Option<usize>) -> PyResult<()> {
        if self.pending.is_some() {
            return Err(PyRuntimeError::new_err("run() with a generation asked and not told"));
        }
        let budget = budget.unwrap_or(self.budget);
        let max = anima_scene::limits::MAX_EVALUATIONS;
        if budget == 0 || budget > max {
            return Err(value_error(format!(
                "expected a budget of 1 to {max} evaluations (anima's limit), found {budget}"
            )));
        }
        let (opt, log, e) = (&mut self.opt, &mut self.log, &self.evaluator);
        let ran = interruptible(py, || {
            // An evaluation cut short by Ctrl-C is no value: NaN makes `run` refuse its generation
            // whole, so the log holds only generations evaluated to their end.
            let objective =
                |x: &[f64]| match anima_run::optimise::fitness(&e.objective, &e.controller, &e.ids, x) {
                    _ if anima_run::interrupt::requested() => f64::NAN,
                    f => f,
                };
            run(opt.as_mut(), &objective, budget, log)
        });
        match ran {
            Ok(r) => r.map(|_| ()).map_err(value_error),
            Err(interrupted) => {
                // The optimiser asked a generation that was not told: rebuilt and replayed from the log,
                // it stands where the log ends, and `run()` goes on as if never interrupted.
                let mut fresh =
                    anima_run::optimise::optimiser(&self.loaded, &self.evaluator.ids).map_err(value_error)?;
                resume(fresh.as_mut(), &self.log).map_err(value_error)?;
                self.opt = fresh;
                Err(interrupted)
            }
        }
    }

    /// The best candidate told so far and its fitness, or `None`.
    #[getter]
    fn best<'py>(&self, py: Python<'py>) -> Option<(Bound<'py, PyArray1<f64>>, f64)> {
        self.log.best().map(|b| (PyArray1::from_slice(py, &b.x), b.fitness))
    }

    /// The log of every evaluation, as the RON text `anima optimise` writes.
    fn log_ron(&self) -> PyResult<String> {
        ron::ser::to_string_pretty(&self.log, ron::ser::PrettyConfig::default())
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// Writes the log to `path`, whole (a temporary file, then a rename).
    fn save_log(&self, path: PathBuf) -> PyResult<()> {
        let text = self.log_ron()?;
        anima_run::output::write_atomic(&path, |w| Ok(w.write_all(text.as_bytes())?))
            .map_err(|e| PyRuntimeError::new_err(format!("{e:#}")))
    }

    /// Replays a log written by `save_log` (or `anima optimise`) of a run of this spec, so that the
    /// optimisation goes on where it stopped. Only a fresh optimisation resumes; a log that does not
    /// replay raises ValueError and leaves it fresh.
    fn resume(&mut self, path: PathBuf) -> PyResult<()> {
        if !self.log.is_empty() || self.pending.is_some() {
            return Err(PyRuntimeError::new_err("resume() on an optimisation that has already begun"));
        }
        let text =
            std::fs::read_to_string(&path).map_err(|e| scene_error(format!("{}: {e}", path.display())))?;
        let log: RunLog =
            ron::from_str(&text).map_err(|e| scene_error(format!("{}: {e}", path.display())))?;
        if let Err(e) = resume(self.opt.as_mut(), &log) {
            // The replay may have told the optimiser part of the log: start it afresh.
            self.opt =
                anima_run::optimise::optimiser(&self.loaded, &self.evaluator.ids).map_err(value_error)?;
            return Err(value_error(format!("{}: {e}", path.display())));
        }
        self.log = log;
        Ok(())
    }

    fn __repr__(&self) -> String {
        format!("{self:?}")
    }
}

/// The version of the Rust crates this module was built from.
#[pymodule]
fn _anima(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add("SimulationError", m.py().get_type::<SimulationError>())?;
    m.add_class::<Cloth>()?;
    m.add_class::<Figure>()?;
    m.add_class::<Evaluator>()?;
    m.add_class::<Optimisation>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(run_json, m)?)?;
    m.add_function(wrap_pyfunction!(walk_json, m)?)?;
    Ok(())
}
