//! A general particle–spring network with damped Hooke springs, the model of the standard benchmark
//! sheet (`benchmarks.md`) and of the integrator studies: it gives exact force Jacobians, so every
//! integrator in `anima_ode`, implicit Euler included, can step it.
//!
//! Spring force on i from the spring (i, j), with d = x_j − x_i, L = |d|, n = d/L:
//! f_i = (k (L − L0) + c (v_j − v_i)·n) n, f_j = −f_i (k in N/m, c in N·s/m).

use anima_geom::DVec3;
use anima_ode::{Jacobians, Linearized, OdeSystem, SystemOut};
use glam::DMat3;

use crate::assembly::{SpringAssembly, SpringTerm};
use crate::sheet_stencil::{GridStencil, Particles, StencilClass};

/// What a spring stands for in a sheet; only used for counting and reporting.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpringKind {
    /// Grid neighbours along rows and columns.
    Structural,
    /// Both diagonals of every cell.
    Shear,
    /// Skip-one neighbours along rows and columns.
    Bend,
}

/// One damped spring between particles `i` and `j`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spring {
    pub i: u32,
    pub j: u32,
    pub rest_length: f64,
    pub stiffness: f64,
    pub damping: f64,
    pub kind: SpringKind,
}

impl Spring {
    /// The ends (i, j), the unit direction n = d / L from i to j and the length L = |d| of
    /// d = x_j − x_i; `None` when the ends coincide (no direction: the spring gives nothing).
    fn direction(&self, x: &[DVec3]) -> Option<(usize, usize, DVec3, f64)> {
        let (i, j) = (self.i as usize, self.j as usize);
        let d = x[j] - x[i];
        let l = d.length();
        (l != 0.0).then(|| (i, j, d / l, l))
    }
}

/// How many threads a network's own passes over its springs use (the explicit integrators' force
/// evaluations and the fused symplectic-Euler run of a sheet; the implicit solves share out their work
/// through `anima_ode::parallel` whatever this says). Every choice gives the same bits; inside
/// `anima_ode::parallel::on_one_thread` every choice runs on the calling thread.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Threads {
    /// The calling thread only.
    One,
    /// Every core where it pays (the default): a sheet's fused symplectic-Euler run from
    /// [`PARALLEL_MIN_PARTICLES_FUSED`] particles, its per-pass force evaluation from
    /// [`PARALLEL_MIN_PARTICLES`], on a machine with more than one core.
    #[default]
    Auto,
    /// Every core whatever the size (the tests of the parallel paths run them on small sheets).
    Every,
}

/// Sheets smaller than this evaluate their forces on one thread under [`Threads::Auto`], unless stepped
/// by the fused symplectic-Euler run ([`PARALLEL_MIN_PARTICLES_FUSED`]): the other explicit methods
/// share out each pass over the springs on the pool, and below it two threads do not pay for their
/// hand-over at every pass. Measured when symplectic Euler still ran that way, on this project's 2-core
/// machine, alternating one and two threads (`anima run` with and without `--one-thread`): the standard
/// sheet N = 64 took 3.5–3.7 s on two threads against 1.29–1.33 s on one, N = 128 0.75–0.85 s against
/// 0.59–0.61 s, and N = 256 (65 536 particles) 2.50–2.62 s against 2.97–3.00 s, the first size where
/// the second core pays.
pub const PARALLEL_MIN_PARTICLES: usize = 65_536;

/// Sheets stepped by the fused symplectic-Euler run ([`SpringNetwork::run_symplectic_euler`]) use every
/// core from this size under [`Threads::Auto`]: that run keeps its threads between steps, with a spin
/// barrier between its two phases, so the second core pays much earlier. Measured on the 2-core
/// machine, alternating, three runs each (`anima run` loop times): the standard sheet N = 32 (1 024
/// particles) at 2·10⁻⁴ s took 0.13–0.14 s on two threads against 0.17–0.19 s on one, N = 64 at
/// 10⁻⁴ s 0.71–0.73 s against 1.12–1.13 s.
pub const PARALLEL_MIN_PARTICLES_FUSED: usize = 1_024;

/// The size from which a sheet stepped with `integrator` uses every core under [`Threads::Auto`].
pub fn parallel_min_particles(integrator: anima_ode::Integrator) -> usize {
    if integrator == anima_ode::Integrator::SymplecticEuler {
        PARALLEL_MIN_PARTICLES_FUSED
    } else {
        PARALLEL_MIN_PARTICLES
    }
}

/// Particles, springs, pins and gravity. Pinned particles keep their velocity (zero unless set).
#[derive(Debug, Clone)]
pub struct SpringNetwork {
    masses: Vec<f64>,
    inv_masses: Vec<f64>,
    pinned: Vec<bool>,
    springs: Vec<Spring>,
    pattern: Vec<(u32, u32)>,
    pub gravity: DVec3,
    /// Clamp the geometric term (1 − L0/L) of each spring Jacobian at zero, which keeps the implicit
    /// system positive definite under compression (Choi & Ko 2002). On by default.
    pub definite_jacobians: bool,
    /// For sheets built by [`SheetSpec::build`]: the springs as stencils on the grid, the fast path.
    stencil: Option<GridStencil>,
    /// How many threads the sheet's stencil passes use ([`Threads`]; every core where it pays unless
    /// set); the result is bit-identical whatever it is.
    pub threads: Threads,
    /// Each spring's ends as it is oriented (its force acts on `.0`), and the implicit assembly that
    /// shares the springs out over the threads.
    ends: Vec<(u32, u32)>,
    assembly: SpringAssembly,
}

/// Why a network was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NetworkError {
    #[error("spring {spring} joins particle {index}, but there are {n} particles")]
    BadIndex { spring: usize, index: u32, n: usize },
    #[error("spring {0} joins a particle to itself")]
    SelfSpring(usize),
    #[error("particle {0} has a non-positive or non-finite mass")]
    BadMass(usize),
    #[error("spring {0} has a negative or non-finite rest length, stiffness or damping")]
    BadSpring(usize),
    #[error("expected one {what} per particle ({n}), found {found}")]
    Count { what: &'static str, n: usize, found: usize },
    #[error("the sheet: {0}")]
    Sheet(String),
    #[error("the time step must be positive and finite, found {0} s")]
    Step(f64),
}

impl SpringNetwork {
    /// Checks indices, masses and spring constants once.
    pub fn new(
        masses: Vec<f64>,
        springs: Vec<Spring>,
        pinned: Vec<bool>,
        gravity: DVec3,
    ) -> Result<Self, NetworkError> {
        let n = masses.len();
        if pinned.len() != n {
            return Err(NetworkError::Count { what: "pin flag", n, found: pinned.len() });
        }
        if let Some(i) = masses.iter().position(|m| !(m.is_finite() && *m > 0.0)) {
            return Err(NetworkError::BadMass(i));
        }
        for (s, sp) in springs.iter().enumerate() {
            for index in [sp.i, sp.j] {
                if index as usize >= n {
                    return Err(NetworkError::BadIndex { spring: s, index, n });
                }
            }
            if sp.i == sp.j {
                return Err(NetworkError::SelfSpring(s));
            }
            let ok = |v: f64| v.is_finite() && v >= 0.0;
            if !(ok(sp.rest_length) && ok(sp.stiffness) && ok(sp.damping)) {
                return Err(NetworkError::BadSpring(s));
            }
        }
        let pattern = springs.iter().map(|s| (s.i.min(s.j), s.i.max(s.j))).collect();
        let ends = springs.iter().map(|s| (s.i, s.j)).collect();
        Ok(Self {
            ends,
            assembly: SpringAssembly::default(),
            inv_masses: masses.iter().map(|m| 1.0 / m).collect(),
            masses,
            pinned,
            springs,
            pattern,
            gravity,
            definite_jacobians: true,
            stencil: None,
            threads: Threads::Auto,
        })
    }

    pub fn n_particles(&self) -> usize {
        self.masses.len()
    }

    pub fn springs(&self) -> &[Spring] {
        &self.springs
    }

    pub fn pinned(&self) -> &[bool] {
        &self.pinned
    }

    /// Number of springs of each kind: (structural, shear, bend).
    pub fn spring_counts(&self) -> (usize, usize, usize) {
        let count = |k| self.springs.iter().filter(|s| s.kind == k).count();
        (count(SpringKind::Structural), count(SpringKind::Shear), count(SpringKind::Bend))
    }

    /// Smallest particle mass and largest stiffness, for the step rule Δt = β·π·√(m_min/k_max)
    /// (Oliveira 2013).
    pub fn stiffest(&self) -> (f64, f64) {
        let m_min = self.masses.iter().copied().fold(f64::INFINITY, f64::min);
        let k_max = self.springs.iter().map(|s| s.stiffness).fold(0.0, f64::max);
        (m_min, k_max)
    }

    /// Oliveira's dynamic step: Δt = β·π·√(m_min/k_max).
    pub fn stiffest_spring_step(&self, beta: f64) -> f64 {
        let (m, k) = self.stiffest();
        beta * std::f64::consts::PI * (m / k).sqrt()
    }

    /// Mass-weighted centre of the particles.
    pub fn centre_of_mass(&self, x: &[DVec3]) -> DVec3 {
        let total: f64 = self.masses.iter().sum();
        x.iter().zip(&self.masses).map(|(p, m)| *p * *m).sum::<DVec3>() / total
    }

    /// Largest relative strain |L − L0|/L0 over springs with a positive rest length.
    pub fn max_strain(&self, x: &[DVec3]) -> f64 {
        self.springs
            .iter()
            .filter(|s| s.rest_length > 0.0)
            .map(|s| ((x[s.j as usize] - x[s.i as usize]).length() - s.rest_length).abs() / s.rest_length)
            .fold(0.0, f64::max)
    }

    /// The energy the springs store at `x`, ½ k (|d| − L0)², J.
    pub fn elastic_energy(&self, x: &[DVec3]) -> f64 {
        self.springs
            .iter()
            .map(|s| {
                let stretch = (x[s.j as usize] - x[s.i as usize]).length() - s.rest_length;
                0.5 * s.stiffness * stretch * stretch
            })
            .sum()
    }

    /// Adds the spring forces at (x, v) to `f`. The hot loop of a sheet step.
    #[inline]
    fn add_spring_forces(&mut self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
        let parallel = self.parallel(false);
        if let Some(stencil) = &mut self.stencil {
            stencil.add_forces(x, v, f, parallel);
            return;
        }
        self.add_forces_by_spring(x, v, f);
    }

    /// Whether the stencil's passes run on every core: for [`SpringNetwork::run_symplectic_euler`]
    /// (`fused`) or for each force evaluation, as [`SpringNetwork::threads`] says.
    fn parallel(&self, fused: bool) -> bool {
        if anima_ode::parallel::kept_on_one_thread() {
            return false;
        }
        match self.threads {
            Threads::One => false,
            Threads::Every => true,
            // On one core the banded run declines (one band) and the pool has one thread: no check
            // here, which runs at every force evaluation.
            Threads::Auto => {
                self.n_particles()
                    >= if fused { PARALLEL_MIN_PARTICLES_FUSED } else { PARALLEL_MIN_PARTICLES }
            }
        }
    }

    /// Threads a run on this network uses: 1 unless the network is a sheet built by
    /// [`SheetSpec::build`] whose [`SpringNetwork::threads`] setting runs it on every core; then, for
    /// [`SpringNetwork::run_symplectic_euler`] (`fused`), one per band of rows, else the pool's that
    /// shares out each pass over the springs.
    pub fn thread_count(&self, fused: bool) -> usize {
        match &self.stencil {
            Some(stencil) if self.parallel(fused) => {
                if fused {
                    stencil.fused_threads()
                } else {
                    crate::sheet_stencil::pool_threads()
                }
            }
            _ => 1,
        }
    }

    /// Runs `steps` steps of symplectic Euler of length h from (x, v) on a sheet's stencil (a network
    /// built by [`SheetSpec::build`]), with the state kept in rows of components between steps. The
    /// same bits as stepping the network with `anima_ode`'s symplectic Euler, with fewer passes over
    /// memory.
    ///
    /// `Err(k)`: the state first went non-finite at step k (1-based); (x, v) then hold the state after
    /// step k. Returns `None` when the network has no stencil (nothing is run).
    pub fn run_symplectic_euler(
        &mut self,
        steps: usize,
        h: f64,
        x: &mut [DVec3],
        v: &mut [DVec3],
    ) -> Option<Result<(), usize>> {
        let particles = Particles {
            masses: &self.masses,
            inv_masses: &self.inv_masses,
            pinned: &self.pinned,
            gravity: self.gravity,
        };
        let parallel = self.parallel(true);
        let stencil = self.stencil.as_mut()?;
        Some(stencil.run_symplectic_euler(steps, h, particles, x, v, parallel))
    }

    /// The springs' forces added spring by spring, in their order.
    fn add_forces_by_spring(&self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
        for s in &self.springs {
            let Some((i, j, n, l)) = s.direction(x) else {
                continue;
            };
            let fs = spring_pull(s, n, l, v[i], v[j]);
            f[i] += fs;
            f[j] -= fs;
        }
    }
}

impl OdeSystem for SpringNetwork {
    type Coord = DVec3;

    fn n_coords(&self) -> usize {
        self.masses.len()
    }

    fn acceleration(&mut self, _t: f64, x: &[DVec3], v: &[DVec3], a: &mut [DVec3]) {
        for (ai, m) in a.iter_mut().zip(&self.masses) {
            *ai = self.gravity * *m;
        }
        self.add_spring_forces(x, v, a);
        for ((ai, inv_m), &pin) in a.iter_mut().zip(&self.inv_masses).zip(&self.pinned) {
            *ai = if pin { DVec3::ZERO } else { *ai * *inv_m };
        }
    }

    fn linearized(&mut self) -> Option<&mut dyn Linearized<DVec3>> {
        Some(self)
    }
}

/// ∂f_i/∂x_j of a Hooke spring along unit n with length l: k [n nᵀ + (1 − L0/l)(I − n nᵀ)], the
/// geometric term clamped at zero when `definite` (so that the implicit system stays positive definite
/// under compression). Shared by every spring model that gives Jacobians.
pub fn spring_stiffness_block(n: DVec3, l: f64, k: f64, rest_length: f64, definite: bool) -> DMat3 {
    let nn = DMat3::from_cols(n * n.x, n * n.y, n * n.z);
    let mut geometric = 1.0 - rest_length / l;
    if definite {
        geometric = geometric.max(0.0);
    }
    nn * k + (DMat3::IDENTITY - nn) * (k * geometric)
}

/// The force of spring `s` on its first end, along its unit direction `n` (first end to second) at
/// length `l`: (k (l − L0) + c (v_j − v_i)·n) n.
#[inline]
fn spring_pull(s: &Spring, n: DVec3, l: f64, vi: DVec3, vj: DVec3) -> DVec3 {
    n * (s.stiffness * (l - s.rest_length) + s.damping * (vj - vi).dot(n))
}

/// Exact Jacobians of the damped springs (Baraff & Witkin 1998):
/// ∂f_i/∂x_j = k [n nᵀ + (1 − L0/L)(I − n nᵀ)] (the geometric term clamped at 0 when `definite_jacobians`),
/// ∂f_i/∂v_j = c n nᵀ, and ∂f_i/∂x_i, ∂f_i/∂v_i their negatives. The damping force's dependence on n
/// through x is left out, as is usual: it is small and not symmetric.
impl Linearized<DVec3> for SpringNetwork {
    fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// The fused form of the Jacobians above: per spring one symmetric block
    /// B = (β_x k (1 − g) + β_v c) n nᵀ + β_x k g I, g = 1 − L0/L clamped at 0 when `definite_jacobians`,
    /// written once to the pair (−B, unless `off` is empty) and added to both diagonals (+B), and the
    /// spring's force, in one pass over the springs (d, L and n computed once for both). About half
    /// the time of building K and D and combining them (measured on the standard sheet, N = 64), and
    /// a third less than taking the force from the stencil kernel in a pass of its own.
    fn force_and_system(
        &mut self,
        _t: f64,
        x: &[DVec3],
        v: &[DVec3],
        beta_v: f64,
        beta_x: f64,
        out: SystemOut<'_, DVec3>,
        _scratch: &mut Jacobians<DVec3>,
    ) {
        let SystemOut { f, diag, off, springs, .. } = out;
        let (list, masses, gravity, definite) =
            (&self.springs, &self.masses, self.gravity, self.definite_jacobians);
        self.assembly.force_and_system(
            &self.ends,
            |i| gravity * masses[i],
            |e| {
                let s = &list[e];
                let Some((i, j, n, l)) = s.direction(x) else {
                    return SpringTerm::default();
                };
                let force = spring_pull(s, n, l, v[i], v[j]);
                let mut g = 1.0 - s.rest_length / l;
                if definite {
                    g = g.max(0.0);
                }
                // B = along n nᵀ + across I; in spring form u = n √along (along ≥ 0: 1 − g = L0/L and
                // the damping ≥ 0).
                let along = beta_x * s.stiffness * (1.0 - g) + beta_v * s.damping;
                let across = beta_x * s.stiffness * g;
                SpringTerm { n, along, across, force, live: true }
            },
            f,
            diag,
            off,
            springs,
        );
    }

    /// Every pair block is one spring's, B = (β_x k (1 − g) + β_v c) n nᵀ + β_x k g I.
    fn spring_form(&self) -> bool {
        true
    }

    /// The force of [`Linearized::force_and_system`] without the blocks, summed in its order (the same
    /// bits).
    fn force(&mut self, _t: f64, x: &[DVec3], v: &[DVec3], f: &mut [DVec3], _scratch: &mut Jacobians<DVec3>) {
        let (list, masses, gravity) = (&self.springs, &self.masses, self.gravity);
        self.assembly.forces(
            &self.ends,
            |i| gravity * masses[i],
            |e| {
                let s = &list[e];
                let Some((i, j, n, l)) = s.direction(x) else {
                    return SpringTerm::default();
                };
                SpringTerm { force: spring_pull(s, n, l, v[i], v[j]), live: true, ..SpringTerm::default() }
            },
            f,
        );
    }

    fn prescribed(&self) -> &[bool] {
        &self.pinned
    }

    fn pattern(&self) -> &[(u32, u32)] {
        &self.pattern
    }

    fn force_and_jacobians(
        &mut self,
        _t: f64,
        x: &[DVec3],
        v: &[DVec3],
        f: &mut [DVec3],
        jac: &mut Jacobians<DVec3>,
    ) {
        for (fi, m) in f.iter_mut().zip(&self.masses) {
            *fi = self.gravity * *m;
        }
        self.add_spring_forces(x, v, f);
        for (e, s) in self.springs.iter().enumerate() {
            let Some((i, j, n, l)) = s.direction(x) else {
                continue;
            };
            let ks = spring_stiffness_block(n, l, s.stiffness, s.rest_length, self.definite_jacobians);
            let ds = DMat3::from_cols(n * n.x, n * n.y, n * n.z) * s.damping;
            jac.k_diag[i] -= ks;
            jac.k_diag[j] -= ks;
            jac.d_diag[i] -= ds;
            jac.d_diag[j] -= ds;
            // ∂f_i/∂x_j = ks for the pattern pair (min, max); symmetric, so the orientation does not matter.
            jac.k_off[e] += ks;
            jac.d_off[e] += ds;
        }
    }
}

/// The flat n × n grid of side `size` at `height` (z up): vertex (i, j) at (i·h, j·h, height), index
/// j·n + i. Both sheet models lay their vertices out so.
pub(crate) fn grid_positions(n: usize, size: f64, height: f64) -> Vec<DVec3> {
    let h = size / (n - 1) as f64;
    (0..n * n).map(|p| DVec3::new((p % n) as f64 * h, (p / n) as f64 * h, height)).collect()
}

/// A rectangular sheet of springs on an N×N grid. Also the `sheet` part of a RON sheet scene, with the
/// units in the field names.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SheetSpec {
    /// Particles per side.
    pub n: usize,
    /// Side length, m.
    #[serde(rename = "size_m")]
    pub size: f64,
    /// Height of the flat sheet, m (z up).
    #[serde(rename = "height_m")]
    pub height: f64,
    /// Total mass, kg, split equally.
    #[serde(rename = "total_mass_kg")]
    pub total_mass: f64,
    /// Stiffness of structural, shear and bend springs, N/m (0 leaves the set out).
    #[serde(rename = "stiffness_n_m")]
    pub stiffness: [f64; 3],
    /// Damping along each spring, N·s/m.
    #[serde(rename = "damping_n_s_m")]
    pub damping: f64,
    /// Pinned particles as (i, j), particle (i, j) at (i·h, j·h, height) with index j·N + i.
    pub pinned: Vec<(usize, usize)>,
    #[serde(rename = "gravity_m_s2")]
    pub gravity: DVec3,
}

impl SheetSpec {
    /// The standard sheet of `benchmarks.md`: 1 m, 0.2 kg, structural 1000, shear 500, bend 10 N/m,
    /// damping 0.02 N·s/m, pinned at (0, 0) and (N−1, 0), gravity −9.81 along z.
    pub fn standard(n: usize) -> Self {
        Self {
            n,
            size: 1.0,
            height: 1.5,
            total_mass: 0.2,
            stiffness: [1000.0, 500.0, 10.0],
            damping: 0.02,
            pinned: vec![(0, 0), (n.saturating_sub(1), 0)],
            gravity: DVec3::new(0.0, 0.0, -9.81),
        }
    }

    /// The standard sheet with the cloth of Oliveira 2013 (Table 5.1): 8 000 kg/m³ × 0.1 mm = 0.8 kg/m²,
    /// stretch and shear stiffness k = E·A⁰/L0 with E·A⁰ = 25 N (E = 10⁷ N/m², A⁰ = 2.5·10⁻⁶ m², the
    /// value the adaptive-cloth specification infers), damping 1 % of k, bend springs at the standard 10 N/m.
    pub fn oliveira_cloth(n: usize) -> Self {
        let l0 = 1.0 / (n - 1) as f64;
        let ea = 1e7 * 2.5e-6;
        let k = ea / l0;
        Self {
            total_mass: 0.8,
            stiffness: [k, ea / (l0 * std::f64::consts::SQRT_2), 10.0],
            damping: 0.01 * k,
            ..Self::standard(n)
        }
    }

    /// The particle positions at rest.
    pub fn positions(&self) -> Vec<DVec3> {
        grid_positions(self.n, self.size, self.height)
    }

    /// The sheet's surface, two triangles per cell (the triangulation its OBJ frames are written with).
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        anima_geom::grid_triangles(self.n, self.n)
    }

    /// Why this sheet cannot be built, or `None`: at least 2 × 2 particles, no more than anima's
    /// particle limit, a positive size, mass and finite height and gravity, non-negative stiffnesses
    /// and damping, pins on the grid.
    pub fn problem(&self) -> Option<String> {
        let n = self.n;
        let max = anima_format::limits::MAX_PARTICLES;
        if n < 2 || n.checked_mul(n).is_none_or(|p| p > max) {
            return Some(format!("expected 2 to {} particles a side, found {n}", max.isqrt()));
        }
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if !positive(self.size) || !positive(self.total_mass) || !self.height.is_finite() {
            return Some(format!(
                "expected a positive size and mass and a finite height, found {} m, {} kg, {} m",
                self.size, self.total_mass, self.height
            ));
        }
        let ok = |v: f64| v.is_finite() && v >= 0.0;
        if !self.stiffness.iter().all(|&k| ok(k)) || !ok(self.damping) || !self.gravity.is_finite() {
            return Some("expected non-negative, finite stiffnesses and damping and a finite gravity".into());
        }
        self.pinned
            .iter()
            .find(|&&(i, j)| i >= n || j >= n)
            .map(|(i, j)| format!("pin ({i}, {j}) lies outside the {n} × {n} grid"))
    }

    /// Builds the network: springs at their initial lengths, structural then shear then bend.
    /// A sheet that [`SheetSpec::problem`] refuses is an error.
    pub fn build(&self) -> Result<SpringNetwork, NetworkError> {
        if let Some(why) = self.problem() {
            return Err(NetworkError::Sheet(why));
        }
        let (n, x) = (self.n, self.positions());
        let idx = |i: usize, j: usize| (j * n + i) as u32;
        let mut springs = Vec::new();
        let mut add = |a: u32, b: u32, k: f64, kind| {
            if k > 0.0 {
                let rest = x[a as usize].distance(x[b as usize]);
                springs.push(Spring {
                    i: a,
                    j: b,
                    rest_length: rest,
                    stiffness: k,
                    damping: self.damping,
                    kind,
                });
            }
        };
        let [ks, kh, kb] = self.stiffness;
        for j in 0..n {
            for i in 0..n {
                if i + 1 < n {
                    add(idx(i, j), idx(i + 1, j), ks, SpringKind::Structural);
                }
                if j + 1 < n {
                    add(idx(i, j), idx(i, j + 1), ks, SpringKind::Structural);
                }
            }
        }
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                add(idx(i, j), idx(i + 1, j + 1), kh, SpringKind::Shear);
                add(idx(i + 1, j), idx(i, j + 1), kh, SpringKind::Shear);
            }
        }
        for j in 0..n {
            for i in 0..n {
                if i + 2 < n {
                    add(idx(i, j), idx(i + 2, j), kb, SpringKind::Bend);
                }
                if j + 2 < n {
                    add(idx(i, j), idx(i, j + 2), kb, SpringKind::Bend);
                }
            }
        }
        let mut pinned = vec![false; n * n];
        for &(i, j) in &self.pinned {
            pinned[idx(i, j) as usize] = true;
        }
        let m = self.total_mass / (n * n) as f64;
        let mut net = SpringNetwork::new(vec![m; n * n], springs, pinned, self.gravity)?;
        let h = self.size / (n - 1) as f64;
        let class = |di: usize, dj_sign: isize, dj: usize, k: f64| StencilClass {
            di,
            dj_sign,
            dj,
            k,
            c: self.damping,
            rest: h * ((di * di + dj * dj) as f64).sqrt(),
        };
        // Along rows (i + 1), along columns (j + 1), both diagonals, then skip-one along rows and columns.
        let classes: Vec<StencilClass> = [
            class(1, 1, 0, ks),
            class(0, 1, 1, ks),
            class(1, 1, 1, kh),
            class(1, -1, 1, kh),
            class(2, 1, 0, kb),
            class(0, 1, 2, kb),
        ]
        .into_iter()
        .filter(|c| c.k > 0.0)
        .collect();
        net.stencil = Some(GridStencil::new(n, classes));
        Ok(net)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_sheet_has_the_spring_counts_its_definition_implies() {
        for n in [32usize, 64] {
            let net = SheetSpec::standard(n).build().unwrap();
            let expected = (2 * n * (n - 1), 2 * (n - 1) * (n - 1), 2 * n * (n - 2));
            assert_eq!(net.spring_counts(), expected, "N = {n}");
        }
        assert_eq!(SheetSpec::standard(64).build().unwrap().springs().len(), 23_938);
    }

    #[test]
    fn a_sheet_that_cannot_be_built_is_an_error_not_a_panic() {
        for n in [0, 1] {
            let e = SheetSpec::standard(n).build().unwrap_err();
            assert!(e.to_string().contains(&format!("particles a side, found {n}")), "{e}");
        }
        let off = SheetSpec { pinned: vec![(0, 0), (9, 0)], ..SheetSpec::standard(8) };
        assert!(off.build().unwrap_err().to_string().contains("pin (9, 0) lies outside the 8 × 8 grid"));
        let massless = SheetSpec { total_mass: 0.0, ..SheetSpec::standard(8) };
        assert!(massless.build().is_err());
        let huge = SheetSpec::standard(1 << 33);
        assert!(huge.build().is_err(), "refused before anything is allocated");
        let net = SheetSpec::standard(4).build().unwrap();
        let wrong = crate::network_sim::NetworkSim::new(
            net.clone(),
            vec![DVec3::ZERO; 3],
            anima_ode::Integrator::Rk4,
            1e-3,
        );
        assert!(wrong.unwrap_err().to_string().contains("one position per particle (16), found 3"));
        let x = SheetSpec::standard(4).positions();
        for dt in [0.0, -1.0, f64::NAN] {
            assert!(
                crate::network_sim::NetworkSim::new(net.clone(), x.clone(), anima_ode::Integrator::Rk4, dt)
                    .is_err()
            );
        }
    }

    #[test]
    fn jacobians_match_finite_differences() {
        // No damping here: its dependence on x is left out of K on purpose (checked through D below).
        let spec = SheetSpec { n: 4, pinned: vec![], damping: 0.0, ..SheetSpec::standard(4) };
        let mut net = spec.build().unwrap();
        net.definite_jacobians = false;
        let mut x = spec.positions();
        // Move off the rest state so every spring is stretched or compressed.
        for (k, p) in x.iter_mut().enumerate() {
            *p +=
                DVec3::new((k as f64 * 0.37).sin(), (k as f64 * 0.91).cos(), (k as f64 * 0.13).sin()) * 0.05;
        }
        let v = vec![DVec3::ZERO; 16];
        let mut f = vec![DVec3::ZERO; 16];
        let mut jac = Jacobians::new(16, net.pattern().len());
        net.force_and_jacobians(0.0, &x, &v, &mut f, &mut jac);
        // Column (j, axis) of K by central differences; compare with the assembled blocks.
        let eps = 1e-6;
        for j in [0usize, 5, 10] {
            for axis in 0..3 {
                let (mut xp, mut xm) = (x.clone(), x.clone());
                xp[j][axis] += eps;
                xm[j][axis] -= eps;
                let (mut fp, mut fm) = (vec![DVec3::ZERO; 16], vec![DVec3::ZERO; 16]);
                let mut scratch = Jacobians::new(16, net.pattern().len());
                net.force_and_jacobians(0.0, &xp, &v, &mut fp, &mut scratch);
                scratch.clear();
                net.force_and_jacobians(0.0, &xm, &v, &mut fm, &mut scratch);
                for i in 0..16 {
                    let numeric = (fp[i] - fm[i]) / (2.0 * eps);
                    let mut block = if i == j { jac.k_diag[i] } else { DMat3::ZERO };
                    for (e, &(a, b)) in net.pattern().iter().enumerate() {
                        if (a as usize, b as usize) == (i, j) {
                            block += jac.k_off[e];
                        } else if (a as usize, b as usize) == (j, i) {
                            block += jac.k_off[e].transpose();
                        }
                    }
                    let analytic = block.col(axis);
                    let scale = 1.0 + analytic.length();
                    assert!(
                        (numeric - analytic).length() < 1e-6 * scale,
                        "i {i} j {j} axis {axis}: {numeric} vs {analytic}"
                    );
                }
            }
        }
    }
}

#[cfg(test)]
mod system_tests {
    use super::*;

    /// The fused system blocks equal −β_v D − β_x K assembled from the Jacobians.
    #[test]
    fn fused_system_blocks_equal_the_jacobians_combined() {
        let spec = SheetSpec { n: 5, damping: 0.3, ..SheetSpec::standard(5) };
        let mut net = spec.build().unwrap();
        let x: Vec<DVec3> = spec
            .positions()
            .iter()
            .enumerate()
            .map(|(k, p)| {
                *p + DVec3::new((k as f64).sin(), (k as f64 * 0.7).cos(), (k as f64 * 0.3).sin()) * 0.05
            })
            .collect();
        let v: Vec<DVec3> = (0..25).map(|k| DVec3::new(0.1 * k as f64, -0.2, 0.05)).collect();
        let (bv, bx) = (0.013, 0.0021);
        let pairs = net.pattern().len();
        let (mut f1, mut f2) = (vec![DVec3::ZERO; 25], vec![DVec3::ZERO; 25]);
        let (mut d1, mut o1) = (vec![DMat3::ZERO; 25], vec![DMat3::ZERO; pairs]);
        let mut scratch = Jacobians::new(25, pairs);
        let out = SystemOut { f: &mut f1, diag: &mut d1, off: &mut o1, springs: None };
        net.force_and_system(0.0, &x, &v, bv, bx, out, &mut scratch);
        let mut jac = Jacobians::new(25, pairs);
        net.force_and_jacobians(0.0, &x, &v, &mut f2, &mut jac);
        for i in 0..25 {
            let expected = jac.d_diag[i] * -bv + jac.k_diag[i] * -bx;
            assert!((d1[i] - expected).abs().to_cols_array().iter().all(|e| *e < 1e-12), "diagonal {i}");
            assert!((f1[i] - f2[i]).length() < 1e-12, "force {i}");
        }
        for (e, block) in o1.iter().enumerate() {
            let expected = jac.d_off[e] * -bv + jac.k_off[e] * -bx;
            assert!((*block - expected).abs().to_cols_array().iter().all(|x| *x < 1e-12), "pair {e}");
        }
    }
}

#[cfg(test)]
mod damping_tests {
    use super::*;

    #[test]
    fn damping_jacobian_matches_finite_differences_in_velocity() {
        let spec = SheetSpec { n: 3, pinned: vec![], damping: 0.5, ..SheetSpec::standard(3) };
        let mut net = spec.build().unwrap();
        let x = spec.positions();
        let v: Vec<DVec3> = (0..9).map(|k| DVec3::new(0.1 * k as f64, -0.2, 0.05 * k as f64)).collect();
        let mut f = vec![DVec3::ZERO; 9];
        let mut jac = Jacobians::new(9, net.pattern().len());
        net.force_and_jacobians(0.0, &x, &v, &mut f, &mut jac);
        let j = 4;
        for axis in 0..3 {
            let mut vp = v.clone();
            vp[j][axis] += 1e-3;
            let mut fp = vec![DVec3::ZERO; 9];
            let mut scratch = Jacobians::new(9, net.pattern().len());
            net.force_and_jacobians(0.0, &x, &vp, &mut fp, &mut scratch);
            for i in 0..9 {
                let numeric = (fp[i] - f[i]) / 1e-3;
                let mut block = if i == j { jac.d_diag[i] } else { DMat3::ZERO };
                for (e, &(a, b)) in net.pattern().iter().enumerate() {
                    if (a as usize, b as usize) == (i, j) || (a as usize, b as usize) == (j, i) {
                        block += jac.d_off[e];
                    }
                }
                assert!((numeric - block.col(axis)).length() < 1e-9, "i {i} axis {axis}");
            }
        }
    }
}

#[cfg(test)]
mod stencil_tests {
    use super::*;
    use anima_ode::{Integrator, State, Stepper};

    fn perturbed(spec: &SheetSpec) -> (Vec<DVec3>, Vec<DVec3>) {
        let x: Vec<DVec3> = spec
            .positions()
            .iter()
            .enumerate()
            .map(|(k, p)| {
                *p + DVec3::new((k as f64 * 0.37).sin(), (k as f64 * 0.91).cos(), (k as f64).sin()) * 0.004
            })
            .collect();
        let v = (0..x.len()).map(|k| DVec3::new((k as f64 * 0.3).cos(), 0.2, -0.1) * 0.5).collect();
        (x, v)
    }

    #[test]
    fn stencil_forces_equal_the_spring_list_forces() {
        // Rows of 5 (shorter than a block of the kernel: one spring at a time), 9 (one block and one
        // overlapping it) and 20 (blocks and an overlap) particles.
        for n in [5, 9, 20] {
            let spec = SheetSpec::standard(n);
            let mut fast = spec.build().unwrap();
            assert!(fast.stencil.is_some(), "a built sheet takes the stencil path");
            let mut list = fast.clone();
            list.stencil = None;
            let (x, v) = perturbed(&spec);
            let (mut a, mut b) = (vec![DVec3::ZERO; n * n], vec![DVec3::ZERO; n * n]);
            fast.acceleration(0.0, &x, &v, &mut a);
            list.acceleration(0.0, &x, &v, &mut b);
            for (p, (a, b)) in a.iter().zip(&b).enumerate() {
                assert!((*a - *b).length() <= 1e-9 * (1.0 + b.length()), "n = {n}, particle {p}: {a} vs {b}");
            }
        }
    }

    /// Symplectic Euler through `anima_ode`'s stepper, step by step; the index of the first step after
    /// which the state is not finite, if any.
    fn stepped(
        net: &mut SpringNetwork,
        steps: usize,
        h: f64,
        x: &[DVec3],
        v: &[DVec3],
    ) -> (State<DVec3>, Option<usize>) {
        let mut stepper = Stepper::new(Integrator::SymplecticEuler, x.len());
        let (mut now, mut next) = (State::new(x.to_vec(), v.to_vec()), State::zeros(x.len()));
        for k in 1..=steps {
            stepper.step(net, 0.0, h, &now, &mut next).expect("explicit steps do not fail");
            std::mem::swap(&mut now, &mut next);
            if now.first_non_finite().is_some() {
                return (now, Some(k));
            }
        }
        (now, None)
    }

    #[test]
    fn fused_symplectic_euler_gives_the_steppers_bits() {
        let spec = SheetSpec::standard(9);
        let mut net = spec.build().unwrap();
        let (x0, v0) = perturbed(&spec);
        let (reference, went) = stepped(&mut net.clone(), 300, 1e-4, &x0, &v0);
        assert_eq!(went, None);
        let (mut x, mut v) = (x0.clone(), v0.clone());
        // In three runs of different lengths: the rows are reloaded between runs.
        for steps in [1, 99, 200] {
            assert_eq!(net.run_symplectic_euler(steps, 1e-4, &mut x, &mut v), Some(Ok(())));
        }
        assert_eq!(x, reference.x);
        assert_eq!(v, reference.v);
        assert_ne!(x, x0, "the sheet moved");
        // A network without a stencil is not run.
        let mut list = net.clone();
        list.stencil = None;
        assert_eq!(list.run_symplectic_euler(1, 1e-4, &mut x, &mut v), None);
    }

    #[test]
    fn fused_symplectic_euler_names_the_step_where_the_state_went_non_finite() {
        // h·ω ≈ 6 on the stiffest springs: the motion grows about fortyfold a step until it overflows.
        let spec = SheetSpec::standard(9);
        let mut net = spec.build().unwrap();
        let (x0, v0) = perturbed(&spec);
        let (reference, went) = stepped(&mut net.clone(), 2000, 1e-2, &x0, &v0);
        let went = went.expect("the step is far beyond the stable limit");
        assert!(went > 10, "non-finite only after growing for a while (step {went})");
        // Serially and in bands on every core.
        for threads in [Threads::One, Threads::Every] {
            net.threads = threads;
            let (mut x, mut v) = (x0.clone(), v0.clone());
            assert_eq!(net.run_symplectic_euler(2000, 1e-2, &mut x, &mut v), Some(Err(went)));
            // The state is the one after that step, bit for bit (NaN compared by its bits).
            let bits =
                |p: &[DVec3]| p.iter().flat_map(|p| p.to_array().map(f64::to_bits)).collect::<Vec<_>>();
            assert_eq!(bits(&x), bits(&reference.x));
            assert_eq!(bits(&v), bits(&reference.v));
        }
    }

    #[test]
    fn parallel_fused_symplectic_euler_is_bit_identical_to_serial() {
        // 33 rows: bands of 17 and 16 on two cores, of 9, 9, 9 and 6 on four.
        let spec = SheetSpec::standard(33);
        let (mut serial, mut parallel) = (spec.build().unwrap(), spec.build().unwrap());
        serial.threads = Threads::One;
        parallel.threads = Threads::Every;
        let (x0, v0) = perturbed(&spec);
        let (mut xa, mut va, mut xb, mut vb) = (x0.clone(), v0.clone(), x0, v0);
        // Two runs: the bands are kept and reloaded between them.
        for steps in [50, 30] {
            assert_eq!(serial.run_symplectic_euler(steps, 1e-4, &mut xa, &mut va), Some(Ok(())));
            assert_eq!(parallel.run_symplectic_euler(steps, 1e-4, &mut xb, &mut vb), Some(Ok(())));
        }
        assert_eq!((xa, va), (xb, vb));
    }

    #[test]
    fn fused_symplectic_euler_in_three_and_four_bands_is_bit_identical_to_serial() {
        // Bands of 11 rows (three) and of 9, 9, 9 and 6 (four): the middle bands read halos on both
        // sides, which two bands, all a two-core machine makes, never do.
        let spec = SheetSpec::standard(33);
        let mut serial = spec.build().unwrap();
        serial.threads = Threads::One;
        let (x0, v0) = perturbed(&spec);
        let (mut xa, mut va) = (x0.clone(), v0.clone());
        assert_eq!(serial.run_symplectic_euler(40, 1e-4, &mut xa, &mut va), Some(Ok(())));
        for count in [3, 4] {
            let mut banded = spec.build().unwrap();
            banded.threads = Threads::Every;
            banded.stencil.as_mut().expect("a sheet's stencil").set_bands(count);
            let (mut xb, mut vb) = (x0.clone(), v0.clone());
            assert_eq!(banded.run_symplectic_euler(40, 1e-4, &mut xb, &mut vb), Some(Ok(())));
            assert_eq!((&xa, &va), (&xb, &vb), "{count} bands");
        }
    }

    #[test]
    fn threads_are_a_runtime_setting_every_core_where_it_pays_by_default() {
        let small = SheetSpec::standard(16).build().unwrap();
        assert_eq!(small.threads, Threads::Auto);
        assert_eq!(small.thread_count(true), 1, "256 particles: below the fused run's size");
        let mut sheet = SheetSpec::standard(33).build().unwrap();
        let cores = std::thread::available_parallelism().map_or(1, |c| c.get());
        if cores > 1 {
            assert!(sheet.thread_count(true) > 1, "1 089 particles: the fused run takes every core");
        }
        assert_eq!(sheet.thread_count(false), 1, "the per-pass evaluation pays only from 65 536");
        // One switch keeps a whole run on one thread, whatever the setting.
        sheet.threads = Threads::Every;
        assert_eq!(anima_ode::parallel::on_one_thread(|| sheet.thread_count(true)), 1);
        assert_eq!(anima_ode::parallel::on_one_thread(|| sheet.thread_count(false)), 1);
        sheet.threads = Threads::One;
        assert_eq!(sheet.thread_count(true), 1);
    }

    #[test]
    fn parallel_sheet_forces_are_bit_identical_to_serial() {
        let spec = SheetSpec::standard(33);
        let mut serial = spec.build().unwrap();
        serial.threads = Threads::One;
        let mut parallel = spec.build().unwrap();
        parallel.threads = Threads::Every;
        let (x, v) = perturbed(&spec);
        let (mut a, mut b) = (vec![DVec3::ZERO; 33 * 33], vec![DVec3::ZERO; 33 * 33]);
        serial.acceleration(0.0, &x, &v, &mut a);
        parallel.acceleration(0.0, &x, &v, &mut b);
        assert_eq!(a, b);
    }
}
