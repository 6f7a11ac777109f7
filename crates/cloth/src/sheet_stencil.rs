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
#[cfg(feature = "parallel")]
use banded::Bands;

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
    /// The rows split into bands, one per thread, for a parallel symplectic-Euler run.
    #[cfg(feature = "parallel")]
    bands: Bands,
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
            #[cfg(feature = "parallel")]
            bands: Bands::default(),
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
                sum_row(classes, |k| flat_row(&forces[k], w, j), |k| flat_end(classes, forces, w, k, j), row);
            })
        });
        let acc = &self.acc;
        for_each_chunk(f, n, parallel, |j, out| arch.dispatch(|| join_row(flat_row(acc, w, j), n, out)));
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
        // Rows in and out on the caller's thread: a copy once a run.
        self.load(x, v, false);
        self.saved_pos.clone_from(&self.pos);
        self.saved_vel.clone_from(&self.vel);
        #[cfg(feature = "parallel")]
        let banded = parallel && self.run_banded(steps, h, particles, x, v);
        #[cfg(not(feature = "parallel"))]
        let banded = {
            let _ = parallel;
            false
        };
        if !banded {
            for _ in 0..steps {
                self.symplectic_euler_step(h, particles);
            }
            self.store(x, v);
        }
        if all_finite(x, v) {
            return Ok(());
        }
        self.pos.clone_from(&self.saved_pos);
        self.vel.clone_from(&self.saved_vel);
        for k in 1..=steps {
            self.symplectic_euler_step(h, particles);
            self.store(x, v);
            if !all_finite(x, v) {
                return Err(k);
            }
        }
        // Not reached: the rerun repeats the same operations. Were it reached, the state is still not
        // finite after the last step.
        Err(steps)
    }

    /// Threads [`GridStencil::run_symplectic_euler`] uses with `parallel`: one per band of rows.
    pub fn fused_threads(&self) -> usize {
        #[cfg(feature = "parallel")]
        return banded::band_count(self.n);
        #[cfg(not(feature = "parallel"))]
        1
    }

    /// Runs the steps on all cores, each thread moving a band of rows, from the rows in `pos` and `vel`,
    /// into (x, v): the same operations on every row as [`GridStencil::symplectic_euler_step`], so the
    /// same bits. Returns false, having done nothing, when the machine has one core or the sheet too few
    /// rows to share.
    #[cfg(feature = "parallel")]
    fn run_banded(
        &mut self,
        steps: usize,
        h: f64,
        p: Particles<'_>,
        x: &mut [DVec3],
        v: &mut [DVec3],
    ) -> bool {
        if !self.bands.prepare(self.n, &self.classes, self.arch) {
            return false;
        }
        self.bands.run(&self.pos, &self.vel, p, steps, h, x, v);
        true
    }

    /// One step on the caller's thread (the banded run is the parallel one).
    fn symplectic_euler_step(&mut self, h: f64, p: Particles<'_>) {
        self.spring_forces(false);
        let (n, w, arch) = (self.n, 3 * self.n, self.arch);
        let (classes, forces) = (&self.classes, &self.forces);
        let rows = self.pos.chunks_mut(w).zip(self.vel.chunks_mut(w)).zip(self.acc.chunks_mut(w));
        for (j, ((pos, vel), acc)) in rows.enumerate() {
            arch.dispatch(|| {
                let range = j * n..(j + 1) * n;
                let (m, inv_m, pinned) =
                    (&p.masses[range.clone()], &p.inv_masses[range.clone()], &p.pinned[range]);
                // Gravity's force first, then the springs, as `acceleration` sums them.
                split_row(acc, n, |c, i| p.gravity[c] * m[i]);
                sum_row(classes, |k| flat_row(&forces[k], w, j), |k| flat_end(classes, forces, w, k, j), acc);
                move_row(n, h, acc, inv_m, pinned, pos, vel);
            });
        }
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
    fn store(&self, x: &mut [DVec3], v: &mut [DVec3]) {
        let (n, arch) = (self.n, self.arch);
        for (src, dst) in [(&self.pos, x), (&self.vel, v)] {
            for (row, out) in src.chunks(3 * n).zip(dst.chunks_mut(n)) {
                arch.dispatch(|| join_row(row, n, out));
            }
        }
    }

    /// Phase 1: the force of each spring on its first end, per class, row by row, from the rows of
    /// positions and velocities.
    fn spring_forces(&mut self, parallel: bool) {
        let (n, w, arch) = (self.n, 3 * self.n, self.arch);
        let (pos, vel) = (&self.pos, &self.vel);
        for (class, buf) in self.classes.iter().zip(self.forces.iter_mut()) {
            for_each_chunk(buf, w, parallel, |j, out| {
                let q = (j + class.dj < n)
                    .then(|| [flat_row(pos, w, j + class.dj), flat_row(vel, w, j + class.dj)]);
                arch.dispatch(|| class_row(class, n, [flat_row(pos, w, j), flat_row(vel, w, j)], q, out))
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

/// Writes the component rows `[x(N) y(N) z(N)]` of `row` into the N vectors of `out`.
#[inline(always)]
fn join_row(row: &[f64], n: usize, out: &mut [DVec3]) {
    for (i, o) in out.iter_mut().enumerate() {
        *o = DVec3::new(row[i], row[n + i], row[2 * n + i]);
    }
}

/// The force of every spring of `class` that starts in one row on its first end, into `out` (that row
/// of the class's buffer). `p` holds that row of positions and velocities, `q` the row the springs end in
/// (`None` past the last row: no spring starts here).
#[inline(always)]
fn class_row(class: &StencilClass, n: usize, p: [&[f64]; 2], q: Option<[&[f64]; 2]>, out: &mut [f64]) {
    out.fill(0.0);
    let Some(q) = q else { return };
    let shift = class.dj_sign * class.di as isize;
    let lo = (-shift).max(0) as usize;
    let hi = (n as isize - shift.max(0)) as usize;
    let len = hi - lo;
    let q_lo = (lo as isize + shift) as usize;
    fn at(row: &[f64], n: usize, len: usize, c: usize, from: usize) -> &[f64] {
        &row[c * n + from..c * n + from + len]
    }
    let at = |row, c, from| at(row, n, len, c, from);
    let ([pp, pv], [qp, qv]) = (p, q);
    let (px, py, pz) = (at(pp, 0, lo), at(pp, 1, lo), at(pp, 2, lo));
    let (qx, qy, qz) = (at(qp, 0, q_lo), at(qp, 1, q_lo), at(qp, 2, q_lo));
    let (ux, uy, uz) = (at(pv, 0, lo), at(pv, 1, lo), at(pv, 2, lo));
    let (wx, wy, wz) = (at(qv, 0, q_lo), at(qv, 1, q_lo), at(qv, 2, q_lo));
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
/// starts and subtracts those it ends, class by class: `start(k)` is row j of class k's first-end forces,
/// `end(k)` row j − dj (`None` before the first row).
///
/// Each is one loop over the whole row, its three components at once: particle i ends the spring that
/// starts at i − shift of row j − dj, and where no spring ends (at the ends of a component) the shifted
/// index falls on the neighbouring component's first-end forces where no spring starts, which are +0, and
/// subtracting +0 changes no value. The row's first and last |shift| entries are left out, as they would
/// reach outside the row.
#[inline(always)]
fn sum_row<'a>(
    classes: &[StencilClass],
    start: impl Fn(usize) -> &'a [f64],
    end: impl Fn(usize) -> Option<&'a [f64]>,
    row: &mut [f64],
) {
    let w = row.len();
    for (k, class) in classes.iter().enumerate() {
        for (a, b) in row.iter_mut().zip(start(k)) {
            *a += *b;
        }
        if let Some(end) = end(k) {
            let shift = class.dj_sign * class.di as isize;
            let (lo, hi) = (shift.max(0) as usize, (w as isize + shift.min(0)) as usize);
            let from = (lo as isize - shift) as usize;
            for (a, b) in row[lo..hi].iter_mut().zip(&end[from..from + (hi - lo)]) {
                *a -= *b;
            }
        }
    }
}

/// Moves one row's particles by symplectic Euler under the summed forces `acc`: v ← v + h a, then
/// x ← x + h v, with a = f/m (zero for pinned particles).
#[inline(always)]
fn move_row(n: usize, h: f64, acc: &[f64], inv_m: &[f64], pinned: &[bool], pos: &mut [f64], vel: &mut [f64]) {
    for c in 0..3 {
        let s = c * n..(c + 1) * n;
        let (x, v, a) = (&mut pos[s.clone()], &mut vel[s.clone()], &acc[s]);
        for i in 0..n {
            let a = if pinned[i] { 0.0 } else { a[i] * inv_m[i] };
            v[i] += a * h;
            x[i] += v[i] * h;
        }
    }
}

/// Row j of a buffer of rows of width w.
#[inline(always)]
fn flat_row(buf: &[f64], w: usize, j: usize) -> &[f64] {
    &buf[j * w..(j + 1) * w]
}

/// The row of class k's first-end forces whose springs end in row j, if any.
#[inline(always)]
fn flat_end<'a>(
    classes: &[StencilClass],
    forces: &'a [Vec<f64>],
    w: usize,
    k: usize,
    j: usize,
) -> Option<&'a [f64]> {
    let dj = classes[k].dj;
    (j >= dj).then(|| flat_row(&forces[k], w, j - dj))
}

/// Threads the per-pass parallel evaluation ([`GridStencil::add_forces`] with `parallel`) uses: the
/// rayon pool's.
pub(crate) fn pool_threads() -> usize {
    #[cfg(feature = "parallel")]
    return rayon::current_num_threads();
    #[cfg(not(feature = "parallel"))]
    1
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

/// The parallel symplectic-Euler run: the rows split into one band per thread, each thread computing
/// the springs that start in its rows and then moving its rows, with a barrier after each phase.
///
/// The threads are started once, with the first parallel run, and wait between runs; a band's rows sit
/// behind read–write locks so that the threads share them without unsafe code. The barriers order the
/// phases, so no lock is ever contended: in the first phase every thread reads every band's positions
/// and velocities and writes its own forces, in the second it reads every band's forces and writes its
/// own positions and velocities. A barrier is a spin on an atomic counter, under a microsecond, where a
/// pool's fork and join per pass, or threads started for every run, cost more than a small sheet's pass
/// (measured: threads started per 1/30 s frame made two threads slower than one on the 32 × 32 sheet).
#[cfg(feature = "parallel")]
mod banded {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use std::sync::mpsc::{Receiver, Sender, channel};
    use std::sync::{Arc, Mutex, RwLock, RwLockReadGuard};
    use std::thread::JoinHandle;

    use anima_geom::DVec3;

    use super::{Particles, StencilClass, class_row, join_row, move_row, split_row, sum_row};

    /// The most threads a run uses.
    const MAX_BANDS: usize = 8;
    /// The fewest rows a band may have: fewer, and the barriers cost more than the band's work.
    const MIN_ROWS: usize = 8;

    /// The bands of a sheet and the threads that move them, kept between runs. A clone starts with none
    /// (they are scratch, filled at the start of every run, and threads are not shared).
    #[derive(Debug, Default)]
    pub(super) struct Bands {
        team: Option<Team>,
    }

    impl Clone for Bands {
        fn clone(&self) -> Self {
            Self::default()
        }
    }

    /// The threads of bands 1.. (band 0 is moved by the caller's thread), what they share, and the
    /// channel on which they say that a run is done.
    #[derive(Debug)]
    struct Team {
        shared: Arc<Shared>,
        workers: Vec<(Sender<Job>, JoinHandle<()>)>,
        /// Behind a mutex only so that a network stays `Sync` (a receiver is not); only the caller's
        /// thread takes it.
        done: Mutex<Receiver<()>>,
    }

    impl Drop for Team {
        fn drop(&mut self) {
            // Closing a worker's channel ends its loop.
            for (jobs, handle) in self.workers.drain(..) {
                drop(jobs);
                let _ = handle.join();
            }
        }
    }

    #[derive(Debug, Clone, Copy)]
    struct Job {
        steps: usize,
        h: f64,
    }

    /// Consecutive rows `first..first + rows` and their buffers, laid out as the flat ones.
    #[derive(Debug)]
    struct Band {
        first: usize,
        rows: usize,
        pos: RwLock<Vec<f64>>,
        vel: RwLock<Vec<f64>>,
        /// Per class.
        forces: RwLock<Vec<Vec<f64>>>,
        /// One row of summed forces.
        acc: Mutex<Vec<f64>>,
    }

    /// The particles' constants, copied in at every run.
    #[derive(Debug, Default)]
    struct ParticleData {
        masses: Vec<f64>,
        inv_masses: Vec<f64>,
        pinned: Vec<bool>,
        gravity: DVec3,
    }

    #[derive(Debug)]
    struct Shared {
        n: usize,
        rows_per_band: usize,
        classes: Vec<StencilClass>,
        arch: pulp::Arch,
        bands: Vec<Band>,
        particles: RwLock<ParticleData>,
        barrier: SpinBarrier,
    }

    type Guards<'a, T> = [Option<RwLockReadGuard<'a, T>>; MAX_BANDS];

    /// Row r of the sheet, in the band that holds it.
    fn band_row<'g>(guards: &'g Guards<'_, Vec<f64>>, rpb: usize, w: usize, r: usize) -> &'g [f64] {
        let local = r % rpb;
        &guards[r / rpb].as_ref().expect("band")[local * w..(local + 1) * w]
    }

    /// Bands, one per thread, of a sheet of n rows: as many as the machine has cores, at most
    /// [`MAX_BANDS`], each of at least [`MIN_ROWS`] rows; 1 means no banded run.
    pub(super) fn band_count(n: usize) -> usize {
        let cores = std::thread::available_parallelism().map_or(1, |t| t.get());
        cores.min(MAX_BANDS).min(n / MIN_ROWS).max(1)
    }

    impl Bands {
        /// Splits n rows over [`band_count`] bands and starts their threads, unless they are there
        /// already; false when there would be only one band.
        pub fn prepare(&mut self, n: usize, classes: &[StencilClass], arch: pulp::Arch) -> bool {
            let count = band_count(n);
            if count < 2 {
                return false;
            }
            let rows_per_band = n.div_ceil(count);
            if let Some(team) = &self.team
                && team.shared.n == n
                && team.shared.rows_per_band == rows_per_band
                && team.shared.classes.len() == classes.len()
            {
                return true;
            }
            self.team = None;
            let w = 3 * n;
            let bands: Vec<Band> = (0..n.div_ceil(rows_per_band))
                .map(|b| {
                    let first = b * rows_per_band;
                    let rows = rows_per_band.min(n - first);
                    let zeros = || vec![0.0; rows * w];
                    Band {
                        first,
                        rows,
                        pos: RwLock::new(zeros()),
                        vel: RwLock::new(zeros()),
                        forces: RwLock::new((0..classes.len()).map(|_| zeros()).collect()),
                        acc: Mutex::new(vec![0.0; w]),
                    }
                })
                .collect();
            let shared = Arc::new(Shared {
                n,
                rows_per_band,
                classes: classes.to_vec(),
                arch,
                barrier: SpinBarrier::new(bands.len()),
                bands,
                particles: RwLock::new(ParticleData::default()),
            });
            let (done_tx, done) = channel();
            let workers = (1..shared.bands.len())
                .map(|b| {
                    let (jobs, inbox) = channel::<Job>();
                    let (shared, done_tx) = (Arc::clone(&shared), done_tx.clone());
                    let handle = std::thread::spawn(move || {
                        while let Ok(job) = inbox.recv() {
                            shared.worker(b, job);
                            if done_tx.send(()).is_err() {
                                break;
                            }
                        }
                    });
                    (jobs, handle)
                })
                .collect();
            self.team = Some(Team { shared, workers, done: Mutex::new(done) });
            true
        }

        /// Runs `steps` steps of h from the flat rows `pos`, `vel` into (x, v), one thread per band.
        #[allow(clippy::too_many_arguments)]
        pub fn run(
            &mut self,
            pos: &[f64],
            vel: &[f64],
            p: Particles<'_>,
            steps: usize,
            h: f64,
            x: &mut [DVec3],
            v: &mut [DVec3],
        ) {
            let team = self.team.as_mut().expect("prepared");
            let shared = &team.shared;
            let (n, w) = (shared.n, 3 * shared.n);
            {
                let mut data = shared.particles.write().expect("lock");
                copy_into(&mut data.masses, p.masses);
                copy_into(&mut data.inv_masses, p.inv_masses);
                copy_into(&mut data.pinned, p.pinned);
                data.gravity = p.gravity;
            }
            for band in &shared.bands {
                let range = band.first * w..(band.first + band.rows) * w;
                band.pos.write().expect("lock").copy_from_slice(&pos[range.clone()]);
                band.vel.write().expect("lock").copy_from_slice(&vel[range]);
            }
            let job = Job { steps, h };
            for (jobs, _) in &team.workers {
                jobs.send(job).expect("a band's thread is running");
            }
            shared.worker(0, job);
            let done = team.done.get_mut().expect("lock");
            for _ in &team.workers {
                done.recv().expect("a band's thread ended its run");
            }
            for band in &shared.bands {
                for (src, dst) in [(&band.pos, &mut *x), (&band.vel, &mut *v)] {
                    for (r, row) in src.read().expect("lock").chunks(w).enumerate() {
                        join_row(row, n, &mut dst[(band.first + r) * n..(band.first + r + 1) * n]);
                    }
                }
            }
        }
    }

    /// Copies `src` into `dst`, reusing its allocation.
    fn copy_into<T: Copy>(dst: &mut Vec<T>, src: &[T]) {
        dst.clear();
        dst.extend_from_slice(src);
    }

    impl Shared {
        /// Band b's part of a run.
        fn worker(&self, b: usize, job: Job) {
            // A panic here would leave the other threads waiting at a barrier for ever: it poisons the
            // barrier, and they panic in turn (the caller's thread with them).
            let _poison = PoisonOnPanic(&self.barrier);
            let (n, w, rpb) = (self.n, 3 * self.n, self.rows_per_band);
            let band = &self.bands[b];
            let mut acc = band.acc.lock().expect("lock");
            let p = self.particles.read().expect("lock");
            let read = |lock: fn(&Band) -> &RwLock<Vec<f64>>| -> Guards<'_, Vec<f64>> {
                std::array::from_fn(|k| self.bands.get(k).map(|b| lock(b).read().expect("lock")))
            };
            for _ in 0..job.steps {
                {
                    let (pos, vel) = (read(|b| &b.pos), read(|b| &b.vel));
                    let mut forces = band.forces.write().expect("lock");
                    for (class, out) in self.classes.iter().zip(forces.iter_mut()) {
                        for (local, out) in out.chunks_mut(w).enumerate() {
                            let j = band.first + local;
                            let row = |guards, r| band_row(guards, rpb, w, r);
                            let q = (j + class.dj < n)
                                .then(|| [row(&pos, j + class.dj), row(&vel, j + class.dj)]);
                            let here = [row(&pos, j), row(&vel, j)];
                            self.arch.dispatch(|| class_row(class, n, here, q, out));
                        }
                    }
                }
                self.barrier.wait();
                {
                    let forces: [Option<RwLockReadGuard<'_, Vec<Vec<f64>>>>; MAX_BANDS] =
                        std::array::from_fn(|k| self.bands.get(k).map(|b| b.forces.read().expect("lock")));
                    let force_row = |k: usize, r: usize| -> &[f64] {
                        let local = r % rpb;
                        &forces[r / rpb].as_ref().expect("band")[k][local * w..(local + 1) * w]
                    };
                    let (mut pos, mut vel) =
                        (band.pos.write().expect("lock"), band.vel.write().expect("lock"));
                    for (local, (x, v)) in pos.chunks_mut(w).zip(vel.chunks_mut(w)).enumerate() {
                        let j = band.first + local;
                        let range = j * n..(j + 1) * n;
                        let (m, inv_m, pinned) =
                            (&p.masses[range.clone()], &p.inv_masses[range.clone()], &p.pinned[range]);
                        self.arch.dispatch(|| {
                            let acc = &mut acc[..];
                            split_row(acc, n, |c, i| p.gravity[c] * m[i]);
                            sum_row(
                                &self.classes,
                                |k| force_row(k, j),
                                |k| (j >= self.classes[k].dj).then(|| force_row(k, j - self.classes[k].dj)),
                                acc,
                            );
                            move_row(n, job.h, acc, inv_m, pinned, x, v);
                        });
                    }
                }
                self.barrier.wait();
            }
        }
    }

    /// Threads wait at it until all have arrived: spinning for a few microseconds, then yielding (on a
    /// busy machine the thread it waits for may be sharing its core). Poisoned when a thread panics.
    #[derive(Debug)]
    pub(super) struct SpinBarrier {
        n: usize,
        arrived: AtomicUsize,
        generation: AtomicUsize,
        poisoned: AtomicBool,
    }

    /// Poisons its barrier when dropped by a panic.
    pub(super) struct PoisonOnPanic<'a>(pub(super) &'a SpinBarrier);

    impl Drop for PoisonOnPanic<'_> {
        fn drop(&mut self) {
            if std::thread::panicking() {
                self.0.poisoned.store(true, Ordering::Release);
            }
        }
    }

    impl SpinBarrier {
        pub(super) fn new(n: usize) -> Self {
            Self {
                n,
                arrived: AtomicUsize::new(0),
                generation: AtomicUsize::new(0),
                poisoned: AtomicBool::new(false),
            }
        }

        pub(super) fn wait(&self) {
            let generation = self.generation.load(Ordering::Acquire);
            if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.n {
                self.arrived.store(0, Ordering::Relaxed);
                self.generation.fetch_add(1, Ordering::Release);
                return;
            }
            let mut spins = 0u32;
            while self.generation.load(Ordering::Acquire) == generation {
                assert!(!self.poisoned.load(Ordering::Acquire), "another band's thread panicked");
                if spins < 1 << 11 {
                    spins += 1;
                    std::hint::spin_loop();
                } else {
                    std::thread::yield_now();
                }
            }
        }
    }
}

#[cfg(all(test, feature = "parallel"))]
mod tests {
    use super::banded::SpinBarrier;

    #[test]
    fn a_panic_in_one_thread_poisons_the_barrier_instead_of_hanging_the_others() {
        let barrier = SpinBarrier::new(2);
        let outcome = std::thread::scope(|scope| {
            let waiter = scope.spawn(|| barrier.wait());
            let failing = scope.spawn(|| {
                let _poison = super::banded::PoisonOnPanic(&barrier);
                panic!("a band's work failed");
            });
            (waiter.join().is_err(), failing.join().is_err())
        });
        assert_eq!(outcome, (true, true), "both threads end, with a panic");
    }
}
