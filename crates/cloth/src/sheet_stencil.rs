//! The springs of a regular N×N sheet as stencils on its grid: the fast path of
//! [`SpringNetwork`](crate::spring_net::SpringNetwork) for sheets built by
//! [`SheetSpec::build`](crate::spring_net::SheetSpec::build).
//!
//! Springs come in classes of identical springs between (i, j) and (i ± di, j + dj), particle index
//! j·N + i. Positions and velocities are held in rows of separate x, y, z arrays, so that each class's
//! inner loop runs over contiguous slices of equal length without branches, which the compiler turns
//! into vector instructions. The row kernels are compiled twice: for the baseline instruction set and for
//! AVX2 with FMA, chosen at run time (`pulp`'s dispatch; no unsafe code here). Rust never fuses a
//! multiply and an add on its own, so both give the same bits.
//!
//! Forces are computed in two phases so that every particle sums its springs in one fixed order, whether
//! rows run serially or in parallel: first the force of each spring on its first end, per class, into a
//! buffer (each spring written once); then each particle adds the springs it starts and subtracts those
//! it ends, class by class.

use anima_geom::DVec3;

#[derive(Debug, Clone)]
pub(crate) struct GridStencil {
    n: usize,
    classes: Vec<StencilClass>,
    /// Positions and velocities by rows of x, y, z components: row j is `[x(N) y(N) z(N)]`.
    pos: Vec<f64>,
    vel: Vec<f64>,
    /// Per class, first-end forces laid out like `pos` (zero where no spring starts).
    forces: Vec<Vec<f64>>,
    /// The summed forces, laid out like `pos`.
    acc: Vec<f64>,
    /// The rows at the start of a symplectic-Euler run, to rerun it when it goes non-finite.
    saved_pos: Vec<f64>,
    saved_vel: Vec<f64>,
    /// The best instruction set of this machine, found once.
    arch: pulp::Arch,
}

#[derive(Debug, Clone, Copy)]
pub(crate) struct StencilClass {
    pub di: usize,
    /// −1, 0 or +1 column offset (anti-diagonal shear uses −1).
    pub dj_sign: isize,
    pub dj: usize,
    pub k: f64,
    pub c: f64,
    pub rest: f64,
}

/// Per-particle constants of the symplectic-Euler update, laid out by particle index.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Particles<'a> {
    pub masses: &'a [f64],
    pub inv_masses: &'a [f64],
    pub pinned: &'a [bool],
    pub gravity: DVec3,
}

impl GridStencil {
    pub fn new(n: usize, classes: Vec<StencilClass>) -> Self {
        let zeros = || vec![0.0; 3 * n * n];
        Self {
            n,
            pos: zeros(),
            vel: zeros(),
            acc: zeros(),
            saved_pos: Vec::new(),
            saved_vel: Vec::new(),
            forces: (0..classes.len()).map(|_| zeros()).collect(),
            classes,
            arch: pulp::Arch::new(),
        }
    }

    /// Adds the forces of every spring at (x, v) to `f`.
    pub fn add_forces(&mut self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3], parallel: bool) {
        self.load(x, v, parallel);
        self.spring_forces(parallel);
        let (n, w, arch) = (self.n, 3 * self.n, self.arch);
        let (classes, forces) = (&self.classes, &self.forces);
        let f_in: &[DVec3] = f;
        for_each_chunk(&mut self.acc, w, parallel, |j, row| {
            arch.dispatch(|| {
                split_row(row, n, |c, i| f_in[j * n + i][c]);
                sum_row(classes, forces, n, j, row);
            })
        });
        let acc = &self.acc;
        for_each_chunk(f, n, parallel, |j, out| {
            arch.dispatch(|| {
                let a = &acc[j * w..(j + 1) * w];
                for (i, o) in out.iter_mut().enumerate() {
                    *o = DVec3::new(a[i], a[n + i], a[2 * n + i]);
                }
            })
        });
    }

    /// Runs `steps` steps of symplectic Euler of length h from (x, v), and leaves the state in (x, v).
    ///
    /// The state stays in rows between steps, and each row's forces are summed and its particles moved
    /// in one pass: the same operations in the same order as evaluating the accelerations through
    /// [`SpringNetwork`](crate::spring_net::SpringNetwork)'s `acceleration` and stepping with
    /// `anima_ode`'s symplectic Euler (v ← v + h a, x ← x + h v), so the same bits, at less than half
    /// the passes over memory.
    ///
    /// A state gone non-finite stays non-finite (springs spread a NaN to every neighbour, and nothing
    /// takes one out), so the state is checked once, at the end; when it is not finite, the steps are
    /// run again one at a time from the start, checked after each, and `Err(k)` says that the state
    /// first went non-finite at step k (1-based), (x, v) holding the state after that step.
    pub fn run_symplectic_euler(
        &mut self,
        steps: usize,
        h: f64,
        particles: Particles<'_>,
        x: &mut [DVec3],
        v: &mut [DVec3],
        parallel: bool,
    ) -> Result<(), usize> {
        self.load(x, v, parallel);
        self.saved_pos.clone_from(&self.pos);
        self.saved_vel.clone_from(&self.vel);
        for _ in 0..steps {
            self.symplectic_euler_step(h, particles, parallel);
        }
        self.store(x, v, parallel);
        if all_finite(x, v) {
            return Ok(());
        }
        self.pos.clone_from(&self.saved_pos);
        self.vel.clone_from(&self.saved_vel);
        for k in 1..=steps {
            self.symplectic_euler_step(h, particles, parallel);
            self.store(x, v, parallel);
            if !all_finite(x, v) {
                return Err(k);
            }
        }
        // Not reached: the rerun repeats the same operations. Were it reached, the state is still not
        // finite after the last step.
        Err(steps)
    }

    fn symplectic_euler_step(&mut self, h: f64, p: Particles<'_>, parallel: bool) {
        self.spring_forces(parallel);
        let (n, w, arch) = (self.n, 3 * self.n, self.arch);
        let (classes, forces) = (&self.classes, &self.forces);
        let body = |j: usize, ((pos, vel), acc): ((&mut [f64], &mut [f64]), &mut [f64])| {
            arch.dispatch(|| {
                let range = j * n..(j + 1) * n;
                let (m, inv_m, pinned) =
                    (&p.masses[range.clone()], &p.inv_masses[range.clone()], &p.pinned[range]);
                // Gravity's force first, then the springs, as `acceleration` sums them.
                split_row(acc, n, |c, i| p.gravity[c] * m[i]);
                sum_row(classes, forces, n, j, acc);
                for c in 0..3 {
                    let s = c * n..(c + 1) * n;
                    let (x, v, a) = (&mut pos[s.clone()], &mut vel[s.clone()], &acc[s]);
                    for i in 0..n {
                        let a = if pinned[i] { 0.0 } else { a[i] * inv_m[i] };
                        v[i] += a * h;
                        x[i] += v[i] * h;
                    }
                }
            })
        };
        #[cfg(feature = "parallel")]
        if parallel {
            use rayon::prelude::*;
            let rows =
                self.pos.par_chunks_mut(w).zip(self.vel.par_chunks_mut(w)).zip(self.acc.par_chunks_mut(w));
            rows.enumerate().for_each(|(j, r)| body(j, r));
            return;
        }
        let _ = parallel;
        let rows = self.pos.chunks_mut(w).zip(self.vel.chunks_mut(w)).zip(self.acc.chunks_mut(w));
        rows.enumerate().for_each(|(j, r)| body(j, r));
    }

    /// Copies (x, v) into rows.
    fn load(&mut self, x: &[DVec3], v: &[DVec3], parallel: bool) {
        let (n, arch) = (self.n, self.arch);
        for (dst, src) in [(&mut self.pos, x), (&mut self.vel, v)] {
            for_each_chunk(dst, 3 * n, parallel, |j, row| {
                arch.dispatch(|| split_row(row, n, |c, i| src[j * n + i][c]))
            });
        }
    }

    /// Copies the rows back into (x, v).
    fn store(&self, x: &mut [DVec3], v: &mut [DVec3], parallel: bool) {
        let (n, arch) = (self.n, self.arch);
        for (src, dst) in [(&self.pos, x), (&self.vel, v)] {
            for_each_chunk(dst, n, parallel, |j, out| {
                arch.dispatch(|| {
                    let r = &src[j * 3 * n..(j + 1) * 3 * n];
                    for (i, o) in out.iter_mut().enumerate() {
                        *o = DVec3::new(r[i], r[n + i], r[2 * n + i]);
                    }
                })
            });
        }
    }

    /// Phase 1: the force of each spring on its first end, per class, row by row, from the rows of
    /// positions and velocities.
    fn spring_forces(&mut self, parallel: bool) {
        let (n, w, arch) = (self.n, 3 * self.n, self.arch);
        let (pos, vel) = (&self.pos, &self.vel);
        for (class, buf) in self.classes.iter().zip(self.forces.iter_mut()) {
            for_each_chunk(buf, w, parallel, |j, out| {
                arch.dispatch(|| class_row(class, n, j, pos, vel, out))
            });
        }
    }
}

/// Fills the component rows `[x(N) y(N) z(N)]` of `row` with `value(component, i)`.
#[inline(always)]
fn split_row(row: &mut [f64], n: usize, value: impl Fn(usize, usize) -> f64) {
    let (rx, rest) = row.split_at_mut(n);
    let (ry, rz) = rest.split_at_mut(n);
    for i in 0..n {
        rx[i] = value(0, i);
        ry[i] = value(1, i);
        rz[i] = value(2, i);
    }
}

/// The force of every spring of `class` that starts in row j on its first end, into `out` (row j of the
/// class's buffer).
#[inline(always)]
fn class_row(class: &StencilClass, n: usize, j: usize, pos: &[f64], vel: &[f64], out: &mut [f64]) {
    let w = 3 * n;
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
    fn at(buf: &[f64], n: usize, len: usize, row: usize, c: usize, from: usize) -> &[f64] {
        &buf[row + c * n + from..row + c * n + from + len]
    }
    let at = |buf, row, c, from| at(buf, n, len, row, c, from);
    let (px, py, pz) = (at(pos, p_row, 0, lo), at(pos, p_row, 1, lo), at(pos, p_row, 2, lo));
    let (qx, qy, qz) = (at(pos, q_row, 0, q_lo), at(pos, q_row, 1, q_lo), at(pos, q_row, 2, q_lo));
    let (ux, uy, uz) = (at(vel, p_row, 0, lo), at(vel, p_row, 1, lo), at(vel, p_row, 2, lo));
    let (wx, wy, wz) = (at(vel, q_row, 0, q_lo), at(vel, q_row, 1, q_lo), at(vel, q_row, 2, q_lo));
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
}

/// Phase 2 for row j: adds to `row` (component rows, holding the other forces) the springs each particle
/// starts and subtracts those it ends, class by class.
///
/// Each is one loop over the whole row, its three components at once: particle i ends the spring that
/// starts at i − shift of row j − dj, and where no spring ends (at the ends of a component) the shifted
/// index falls on the neighbouring component's first-end forces where no spring starts, which are +0, and
/// subtracting +0 changes no value. The row's first and last |shift| entries are left out, as they would
/// reach outside the row.
#[inline(always)]
fn sum_row(classes: &[StencilClass], forces: &[Vec<f64>], n: usize, j: usize, row: &mut [f64]) {
    let w = 3 * n;
    for (class, buf) in classes.iter().zip(forces) {
        for (a, b) in row.iter_mut().zip(&buf[j * w..(j + 1) * w]) {
            *a += *b;
        }
        if j >= class.dj {
            let shift = class.dj_sign * class.di as isize;
            let (lo, hi) = (shift.max(0) as usize, (w as isize + shift.min(0)) as usize);
            let from = (j - class.dj) * w + (lo as isize - shift) as usize;
            for (a, b) in row[lo..hi].iter_mut().zip(&buf[from..from + (hi - lo)]) {
                *a -= *b;
            }
        }
    }
}

fn all_finite(x: &[DVec3], v: &[DVec3]) -> bool {
    x.iter().zip(v).all(|(x, v)| x.is_finite() && v.is_finite())
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
