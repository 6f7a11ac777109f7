//! A general particle–spring network with damped Hooke springs, the model of the standard benchmark
//! sheet (`benchmarks.md`) and of the integrator studies: it gives exact force Jacobians, so every
//! integrator in `anima_ode`, implicit Euler included, can step it.
//!
//! Spring force on i from the spring (i, j), with d = x_j − x_i, L = |d|, n = d/L:
//! f_i = (k (L − L0) + c (v_j − v_i)·n) n, f_j = −f_i (k in N/m, c in N·s/m).

use anima_geom::DVec3;
use anima_ode::{Jacobians, Linearized, OdeSystem, SpringBlock};
use glam::DMat3;

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
    /// Evaluate the stencil rows on all cores (with the `parallel` feature); the result is
    /// bit-identical to the serial one.
    pub parallel: bool,
}

/// The springs of a regular N×N sheet as classes of identical springs between (i, j) and
/// (i ± di, j + dj), particle index j·N + i. Forces are computed in two phases so that every particle
/// sums its springs in one fixed order, whether rows run serially or in parallel: first the force of each
/// spring on its first end, per class, into a buffer (each spring written once); then each particle adds
/// the springs it starts and subtracts those it ends, class by class.
#[derive(Debug, Clone)]
struct GridStencil {
    n: usize,
    classes: Vec<StencilClass>,
    /// Positions and velocities by rows of x, y, z components: row j is `[x(N) y(N) z(N)]`.
    pos: Vec<f64>,
    vel: Vec<f64>,
    /// Per class, first-end forces laid out like `pos` (zero where no spring starts).
    forces: Vec<Vec<f64>>,
    /// The summed forces, laid out like `pos`.
    acc: Vec<f64>,
}

#[derive(Debug, Clone, Copy)]
struct StencilClass {
    di: usize,
    /// −1, 0 or +1 column offset (anti-diagonal shear uses −1).
    dj_sign: isize,
    dj: usize,
    k: f64,
    c: f64,
    rest: f64,
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
        assert_eq!(pinned.len(), n, "one pin flag per particle");
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
        Ok(Self {
            inv_masses: masses.iter().map(|m| 1.0 / m).collect(),
            masses,
            pinned,
            springs,
            pattern,
            gravity,
            definite_jacobians: true,
            stencil: None,
            parallel: false,
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

    /// Adds the spring forces at (x, v) to `f`. The hot loop of a sheet step.
    #[inline]
    fn add_spring_forces(&mut self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
        if let Some(stencil) = &mut self.stencil {
            stencil.add_forces(x, v, f, self.parallel);
            return;
        }
        self.add_forces_by_spring(x, v, f);
    }

    /// The springs' forces added spring by spring, in their order.
    fn add_forces_by_spring(&self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
        for s in &self.springs {
            let (i, j) = (s.i as usize, s.j as usize);
            let d = x[j] - x[i];
            let l = d.length();
            if l == 0.0 {
                continue;
            }
            let fs = spring_pull(s, d / l, l, v[i], v[j]);
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

impl GridStencil {
    /// Adds the forces of every spring to `f`.
    ///
    /// Positions and velocities are first copied into rows of separate x, y, z arrays, so that each
    /// class's inner loop runs over contiguous slices of equal length without branches, which the
    /// compiler turns into vector instructions (square roots and divisions two at a time).
    fn add_forces(&mut self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3], parallel: bool) {
        let n = self.n;
        let w = 3 * n;
        for (dst, src) in [(&mut self.pos, x), (&mut self.vel, v)] {
            for_each_chunk(dst, w, parallel, |j, row| {
                let (rx, rest) = row.split_at_mut(n);
                let (ry, rz) = rest.split_at_mut(n);
                for (i, p) in src[j * n..(j + 1) * n].iter().enumerate() {
                    rx[i] = p.x;
                    ry[i] = p.y;
                    rz[i] = p.z;
                }
            });
        }
        let (pos, vel, classes) = (&self.pos, &self.vel, &self.classes);
        // Phase 1: the force of each spring on its first end, per class, row by row.
        for (class, buf) in classes.iter().zip(self.forces.iter_mut()) {
            for_each_chunk(buf, w, parallel, |j, out| {
                out.fill(0.0);
                if j + class.dj >= n {
                    return;
                }
                let shift = class.dj_sign * class.di as isize;
                let lo = (-shift).max(0) as usize;
                let hi = (n as isize - shift.max(0)) as usize;
                let len = hi - lo;
                let q_lo = (lo as isize + shift) as usize;
                let (p_row, q_row) = (j * w, (j + class.dj) * w);
                let px = &pos[p_row + lo..p_row + lo + len];
                let py = &pos[p_row + n + lo..p_row + n + lo + len];
                let pz = &pos[p_row + 2 * n + lo..p_row + 2 * n + lo + len];
                let qx = &pos[q_row + q_lo..q_row + q_lo + len];
                let qy = &pos[q_row + n + q_lo..q_row + n + q_lo + len];
                let qz = &pos[q_row + 2 * n + q_lo..q_row + 2 * n + q_lo + len];
                let ux = &vel[p_row + lo..p_row + lo + len];
                let uy = &vel[p_row + n + lo..p_row + n + lo + len];
                let uz = &vel[p_row + 2 * n + lo..p_row + 2 * n + lo + len];
                let wx = &vel[q_row + q_lo..q_row + q_lo + len];
                let wy = &vel[q_row + n + q_lo..q_row + n + q_lo + len];
                let wz = &vel[q_row + 2 * n + q_lo..q_row + 2 * n + q_lo + len];
                let (ox, rest) = out.split_at_mut(n);
                let (oy, oz) = rest.split_at_mut(n);
                let (ox, oy, oz) = (&mut ox[lo..hi], &mut oy[lo..hi], &mut oz[lo..hi]);
                let (k, c, rest_length) = (class.k, class.c, class.rest);
                for t in 0..len {
                    let (dx, dy, dz) = (qx[t] - px[t], qy[t] - py[t], qz[t] - pz[t]);
                    let l2 = dx * dx + dy * dy + dz * dz;
                    // Branch-free, so that the loop vectorises: coincident ends have d = 0, hence n = 0 and no
                    // force, while the clamp keeps 1/L finite.
                    let inv_l = 1.0 / l2.max(f64::MIN_POSITIVE).sqrt();
                    let (nx, ny, nz) = (dx * inv_l, dy * inv_l, dz * inv_l);
                    let closing = (wx[t] - ux[t]) * nx + (wy[t] - uy[t]) * ny + (wz[t] - uz[t]) * nz;
                    let magnitude = k * (l2 * inv_l - rest_length) + c * closing;
                    ox[t] = nx * magnitude;
                    oy[t] = ny * magnitude;
                    oz[t] = nz * magnitude;
                }
            });
        }
        // Phase 2: every particle adds the springs it starts and subtracts those it ends, class by class,
        // on component rows (vectorised), then the sums go back into `f`.
        let forces = &self.forces;
        let f_in: &[DVec3] = f;
        for_each_chunk(&mut self.acc, w, parallel, |j, row| {
            let (ax, rest) = row.split_at_mut(n);
            let (ay, az) = rest.split_at_mut(n);
            for (i, p) in f_in[j * n..(j + 1) * n].iter().enumerate() {
                ax[i] = p.x;
                ay[i] = p.y;
                az[i] = p.z;
            }
            for (class, buf) in classes.iter().zip(forces) {
                let start = &buf[j * w..(j + 1) * w];
                for (c, a) in [&mut *ax, &mut *ay, &mut *az].into_iter().enumerate() {
                    for (a, b) in a.iter_mut().zip(&start[c * n..(c + 1) * n]) {
                        *a += *b;
                    }
                }
                if j >= class.dj {
                    // Particle i ends the spring that starts at i − shift of row j − dj.
                    let shift = class.dj_sign * class.di as isize;
                    let lo = shift.max(0) as usize;
                    let hi = (n as isize + shift.min(0)) as usize;
                    let from = (lo as isize - shift) as usize;
                    let end = &buf[(j - class.dj) * w..(j - class.dj + 1) * w];
                    for (c, a) in [&mut *ax, &mut *ay, &mut *az].into_iter().enumerate() {
                        let src = &end[c * n + from..c * n + from + (hi - lo)];
                        for (a, b) in a[lo..hi].iter_mut().zip(src) {
                            *a -= *b;
                        }
                    }
                }
            }
        });
        let acc = &self.acc;
        for_each_chunk(f, n, parallel, |j, row| {
            let a = &acc[j * w..(j + 1) * w];
            for (i, out) in row.iter_mut().enumerate() {
                *out = DVec3::new(a[i], a[n + i], a[2 * n + i]);
            }
        });
    }
}

/// Calls `body(k, chunk)` for every `size`-long chunk k of `buf`, on all cores when asked and available
/// (the `parallel` feature). Chunks are disjoint, so the result does not depend on the order.
fn for_each_chunk<T: Send>(
    buf: &mut [T],
    size: usize,
    parallel: bool,
    body: impl Fn(usize, &mut [T]) + Sync + Send,
) {
    #[cfg(feature = "parallel")]
    if parallel {
        use rayon::prelude::*;
        buf.par_chunks_mut(size).enumerate().for_each(|(k, chunk)| body(k, chunk));
        return;
    }
    let _ = parallel;
    for (k, chunk) in buf.chunks_mut(size).enumerate() {
        body(k, chunk);
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
        f: &mut [DVec3],
        diag: &mut [DMat3],
        off: &mut [DMat3],
        mut springs: Option<&mut Vec<SpringBlock<DVec3>>>,
        _scratch: &mut Jacobians<DVec3>,
    ) {
        for (fi, m) in f.iter_mut().zip(&self.masses) {
            *fi = self.gravity * *m;
        }
        diag.fill(DMat3::ZERO);
        let blocks = !off.is_empty();
        if let Some(list) = springs.as_deref_mut() {
            list.clear();
        }
        for (e, s) in self.springs.iter().enumerate() {
            let (i, j) = (s.i as usize, s.j as usize);
            let d = x[j] - x[i];
            let l = d.length();
            if blocks {
                off[e] = DMat3::ZERO;
            }
            if l == 0.0 {
                if let Some(list) = springs.as_deref_mut() {
                    list.push(SpringBlock { i: s.i, j: s.j, u: DVec3::ZERO, a: 0.0 });
                }
                continue;
            }
            let n = d / l;
            let fs = spring_pull(s, n, l, v[i], v[j]);
            f[i] += fs;
            f[j] -= fs;
            let mut g = 1.0 - s.rest_length / l;
            if self.definite_jacobians {
                g = g.max(0.0);
            }
            let along = beta_x * s.stiffness * (1.0 - g) + beta_v * s.damping;
            let across = beta_x * s.stiffness * g;
            let block = DMat3::from_cols(n * (n.x * along), n * (n.y * along), n * (n.z * along))
                + DMat3::from_diagonal(DVec3::splat(across));
            if blocks {
                off[e] = -block;
            }
            diag[i] += block;
            diag[j] += block;
            if let Some(list) = springs.as_deref_mut() {
                // B = u uᵀ + a I with u = n √along (along ≥ 0: 1 − g = L0/L and the damping ≥ 0).
                list.push(SpringBlock { i: s.i, j: s.j, u: n * along.sqrt(), a: across });
            }
        }
    }

    /// Every pair block is one spring's, B = (β_x k (1 − g) + β_v c) n nᵀ + β_x k g I.
    fn spring_form(&self) -> bool {
        true
    }

    /// The force of [`Linearized::force_and_system`] without the blocks, summed in its order (the same
    /// bits).
    fn force(&mut self, _t: f64, x: &[DVec3], v: &[DVec3], f: &mut [DVec3], _scratch: &mut Jacobians<DVec3>) {
        for (fi, m) in f.iter_mut().zip(&self.masses) {
            *fi = self.gravity * *m;
        }
        self.add_forces_by_spring(x, v, f);
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
            let (i, j) = (s.i as usize, s.j as usize);
            let d = x[j] - x[i];
            let l = d.length();
            if l == 0.0 {
                continue;
            }
            let n = d / l;
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
            pinned: vec![(0, 0), (n - 1, 0)],
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
        let h = self.size / (self.n - 1) as f64;
        (0..self.n * self.n)
            .map(|p| DVec3::new((p % self.n) as f64 * h, (p / self.n) as f64 * h, self.height))
            .collect()
    }

    /// The sheet's surface, two triangles per cell (the triangulation its OBJ frames are written with).
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        anima_geom::grid_triangles(self.n, self.n)
    }

    /// Builds the network: springs at their initial lengths, structural then shear then bend.
    pub fn build(&self) -> SpringNetwork {
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
        let mut net = SpringNetwork::new(vec![m; n * n], springs, pinned, self.gravity)
            .expect("a grid sheet is well formed");
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
        let zeros = || vec![0.0; 3 * n * n];
        net.stencil = Some(GridStencil {
            n,
            pos: zeros(),
            vel: zeros(),
            acc: zeros(),
            forces: (0..classes.len()).map(|_| zeros()).collect(),
            classes,
        });
        net
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_sheet_has_the_spring_counts_its_definition_implies() {
        for n in [32usize, 64] {
            let net = SheetSpec::standard(n).build();
            let expected = (2 * n * (n - 1), 2 * (n - 1) * (n - 1), 2 * n * (n - 2));
            assert_eq!(net.spring_counts(), expected, "N = {n}");
        }
        assert_eq!(SheetSpec::standard(64).build().springs().len(), 23_938);
    }

    #[test]
    fn jacobians_match_finite_differences() {
        // No damping here: its dependence on x is left out of K on purpose (checked through D below).
        let spec = SheetSpec { n: 4, pinned: vec![], damping: 0.0, ..SheetSpec::standard(4) };
        let mut net = spec.build();
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
        let mut net = spec.build();
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
        net.force_and_system(0.0, &x, &v, bv, bx, &mut f1, &mut d1, &mut o1, None, &mut scratch);
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
        let mut net = spec.build();
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
        let spec = SheetSpec::standard(9);
        let mut fast = spec.build();
        assert!(fast.stencil.is_some(), "a built sheet takes the stencil path");
        let mut list = fast.clone();
        list.stencil = None;
        let (x, v) = perturbed(&spec);
        let (mut a, mut b) = (vec![DVec3::ZERO; 81], vec![DVec3::ZERO; 81]);
        fast.acceleration(0.0, &x, &v, &mut a);
        list.acceleration(0.0, &x, &v, &mut b);
        for (p, (a, b)) in a.iter().zip(&b).enumerate() {
            assert!((*a - *b).length() <= 1e-9 * (1.0 + b.length()), "particle {p}: {a} vs {b}");
        }
    }

    #[test]
    fn parallel_sheet_forces_are_bit_identical_to_serial() {
        let spec = SheetSpec::standard(33);
        let mut serial = spec.build();
        let mut parallel = spec.build();
        parallel.parallel = true;
        let (x, v) = perturbed(&spec);
        let (mut a, mut b) = (vec![DVec3::ZERO; 33 * 33], vec![DVec3::ZERO; 33 * 33]);
        serial.acceleration(0.0, &x, &v, &mut a);
        parallel.acceleration(0.0, &x, &v, &mut b);
        assert_eq!(a, b);
    }
}
