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
//! it ends, class by class. The symplectic-Euler run interleaves the phases row by row ([`step_band`]),
//! keeping only the few rows of first-end forces not yet used, with the same operations in the same
//! order, so the same bits.

use anima_geom::DVec3;
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
    /// The first-end forces of the last [`halo`] + 1 rows, per class, for the fused step (see
    /// [`step_band`]).
    ring: Vec<f64>,
    /// The rows at the start of a symplectic-Euler run, to rerun it when it goes non-finite.
    saved_pos: Vec<f64>,
    saved_vel: Vec<f64>,
    /// The best instruction set of this machine, found once.
    arch: pulp::Arch,
    /// The rows split into bands, one per thread, for a parallel symplectic-Euler run.
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
            ring: vec![0.0; ring_len(&classes, n)],
            classes,
            arch: pulp::Arch::new(),
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
            arch.dispatch(SumRowOp { classes, forces, f: f_in, n, j, row })
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
        let banded = parallel && self.run_banded(steps, h, particles, x, v);
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

    /// Splits the banded run into `count` bands whatever the machine's cores (tests: a band with
    /// neighbours on both sides needs at least three).
    #[cfg(test)]
    pub fn set_bands(&mut self, count: usize) {
        self.bands.count = Some(count);
    }

    /// Threads [`GridStencil::run_symplectic_euler`] uses with `parallel`: one per band of rows.
    pub fn fused_threads(&self) -> usize {
        banded::band_count(self.n)
    }

    /// Runs the steps on all cores, each thread moving a band of rows, from the rows in `pos` and `vel`,
    /// into (x, v): the same operations on every row as [`GridStencil::symplectic_euler_step`], so the
    /// same bits. Returns false, having done nothing, when the machine has one core or the sheet too few
    /// rows to share.
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

    /// One step on the caller's thread (the banded run is the parallel one): the whole sheet as one
    /// band, with no rows beside it.
    fn symplectic_euler_step(&mut self, h: f64, p: Particles<'_>) {
        let (classes, n) = (&self.classes, self.n);
        let (pos, vel, ring, acc) = (&mut self.pos, &mut self.vel, &mut self.ring, &mut self.acc);
        let band = BandRows { first: 0, pos, vel, below: [&[], &[]], above: [&[], &[]] };
        self.arch.dispatch(StepBandOp { classes, n, h, p, band, ring, acc: &mut acc[..3 * n] });
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
                arch.dispatch(ClassRowOp { class, n, p: [flat_row(pos, w, j), flat_row(vel, w, j)], q, out })
            });
        }
    }
}

// The kernels below run under `pulp`'s dispatch as `WithSimd` values whose `with_simd` is
// `#[inline(always)]` and calls only `#[inline(always)]` code, so that each is compiled in full for every
// instruction set. A closure handed to `Arch::dispatch` is a function of its own, compiled for the
// baseline and inlined into the AVX2 path only when LLVM chooses to; for these kernels it did not, and
// the AVX2 path ran SSE2 code (seen in the profile of the 64 × 64 sheet).

/// [`step_band`] as a dispatched kernel.
struct StepBandOp<'a> {
    classes: &'a [StencilClass],
    n: usize,
    h: f64,
    p: Particles<'a>,
    band: BandRows<'a>,
    ring: &'a mut [f64],
    acc: &'a mut [f64],
}

impl pulp::WithSimd for StepBandOp<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        step_band(self.classes, self.n, self.h, self.p, self.band, self.ring, self.acc);
    }
}

/// [`class_row`] as a dispatched kernel.
struct ClassRowOp<'a> {
    class: &'a StencilClass,
    n: usize,
    p: [&'a [f64]; 2],
    q: Option<[&'a [f64]; 2]>,
    out: &'a mut [f64],
}

impl pulp::WithSimd for ClassRowOp<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        class_row(self.class, self.n, self.p, self.q, self.out);
    }
}

/// Row j of the summed forces of [`GridStencil::add_forces`]: the forces in `f`, then the springs'.
struct SumRowOp<'a> {
    classes: &'a [StencilClass],
    forces: &'a [Vec<f64>],
    f: &'a [DVec3],
    n: usize,
    j: usize,
    row: &'a mut [f64],
}

impl pulp::WithSimd for SumRowOp<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Self { classes, forces, f, n, j, row } = self;
        let w = 3 * n;
        split_row(row, n, |c, i| f[j * n + i][c]);
        sum_row(classes, |k| flat_row(&forces[k], w, j), |k| flat_end(classes, forces, w, k, j), row);
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
    // The short row's loop and the block's call `spring_force` alike; one routine for both, through
    // arrays built by `map`, was measured 2–3 times slower (it no longer vectorised).
    if len < BLOCK {
        for t in 0..len {
            [ox[t], oy[t], oz[t]] = spring_force(
                k,
                c,
                rest_length,
                [px[t], py[t], pz[t]],
                [qx[t], qy[t], qz[t]],
                [ux[t], uy[t], uz[t]],
                [wx[t], wy[t], wz[t]],
            );
        }
        return;
    }
    // Blocks of a fixed length, which vectorise whole, the last overlapping the one before it rather
    // than leaving a remainder to go one spring at a time: a row of a 32 × 32 sheet has 30 or 31 springs
    // of a class, and a remainder of 2 or 3 cost nearly a block each (square roots and divisions cost
    // the same scalar or vector). The springs in the overlap are computed twice, to the same bits.
    let mut from = 0;
    loop {
        let t = from.min(len - BLOCK);
        let b = |s: &[f64]| -> [f64; BLOCK] { s[t..t + BLOCK].try_into().expect("a block") };
        let (bpx, bpy, bpz, bqx, bqy, bqz) = (b(px), b(py), b(pz), b(qx), b(qy), b(qz));
        let (bux, buy, buz, bwx, bwy, bwz) = (b(ux), b(uy), b(uz), b(wx), b(wy), b(wz));
        let (mut bx, mut by, mut bz) = ([0.0; BLOCK], [0.0; BLOCK], [0.0; BLOCK]);
        for u in 0..BLOCK {
            [bx[u], by[u], bz[u]] = spring_force(
                k,
                c,
                rest_length,
                [bpx[u], bpy[u], bpz[u]],
                [bqx[u], bqy[u], bqz[u]],
                [bux[u], buy[u], buz[u]],
                [bwx[u], bwy[u], bwz[u]],
            );
        }
        ox[t..t + BLOCK].copy_from_slice(&bx);
        oy[t..t + BLOCK].copy_from_slice(&by);
        oz[t..t + BLOCK].copy_from_slice(&bz);
        if t + BLOCK == len {
            break;
        }
        from += BLOCK;
    }
}

/// Springs [`class_row`] computes together.
const BLOCK: usize = 8;

/// The force on its first end, at p with velocity u, of a spring whose other end is at q with velocity
/// w.
#[inline(always)]
fn spring_force(
    k: f64,
    c: f64,
    rest_length: f64,
    p: [f64; 3],
    q: [f64; 3],
    u: [f64; 3],
    w: [f64; 3],
) -> [f64; 3] {
    let (dx, dy, dz) = (q[0] - p[0], q[1] - p[1], q[2] - p[2]);
    let l2 = dx * dx + dy * dy + dz * dz;
    // Branch-free, so that the loop vectorises: coincident ends have d = 0, hence n = 0 and no force,
    // while the clamp keeps 1/L finite.
    let inv_l = 1.0 / l2.max(f64::MIN_POSITIVE).sqrt();
    let (nx, ny, nz) = (dx * inv_l, dy * inv_l, dz * inv_l);
    let closing = (w[0] - u[0]) * nx + (w[1] - u[1]) * ny + (w[2] - u[2]) * nz;
    let magnitude = k * (l2 * inv_l - rest_length) + c * closing;
    [nx * magnitude, ny * magnitude, nz * magnitude]
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
        let start = &start(k)[..w];
        let Some(end) = end(k) else {
            for (a, s) in row.iter_mut().zip(start) {
                *a += *s;
            }
            continue;
        };
        let shift = class.dj_sign * class.di as isize;
        let (lo, hi) = (shift.max(0) as usize, (w as isize + shift.min(0)) as usize);
        let from = (lo as isize - shift) as usize;
        for (a, s) in row[..lo].iter_mut().zip(&start[..lo]) {
            *a += *s;
        }
        // Start and end in one pass, each entry (a + s) − e as two passes would give it.
        let ends = &end[from..from + (hi - lo)];
        for ((a, s), e) in row[lo..hi].iter_mut().zip(&start[lo..hi]).zip(ends) {
            *a = *a + *s - *e;
        }
        for (a, s) in row[hi..].iter_mut().zip(&start[hi..]) {
            *a += *s;
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

/// How many rows a spring reaches across: the rows of old state a band needs beyond its own.
fn halo(classes: &[StencilClass]) -> usize {
    classes.iter().map(|c| c.dj).max().unwrap_or(0)
}

/// The length of [`step_band`]'s ring: per class, [`halo`] + 1 rows of first-end forces.
fn ring_len(classes: &[StencilClass], n: usize) -> usize {
    classes.len() * (halo(classes) + 1) * 3 * n
}

/// Consecutive rows `first..` of the sheet that one thread moves (`pos`, `vel`), and copies of the
/// state before the step of the [`halo`] rows before them (`below`, empty for the first band) and after
/// them (`above`, as many as the sheet has, empty for the last band), positions then velocities.
struct BandRows<'a> {
    first: usize,
    pos: &'a mut [f64],
    vel: &'a mut [f64],
    below: [&'a [f64]; 2],
    above: [&'a [f64]; 2],
}

impl BandRows<'_> {
    /// Row r of the state before the step, positions (`c` = 0) or velocities (1): r lies in the band
    /// and has not moved yet, or lies in a halo.
    #[inline(always)]
    fn old(&self, c: usize, r: usize, w: usize) -> &[f64] {
        let own = if c == 0 { &*self.pos } else { &*self.vel };
        let last = self.first + own.len() / w;
        let (buf, from) = if r < self.first {
            (self.below[c], self.first - self.below[c].len() / w)
        } else if r < last {
            (own, self.first)
        } else {
            (self.above[c], last)
        };
        &buf[(r - from) * w..(r - from + 1) * w]
    }
}

/// One symplectic-Euler step of a band of rows in one pass, row by row: the springs that start in row
/// j ([`class_row`], from rows j.. that have not moved yet), then row j's sum ([`sum_row`], gravity
/// first) and its move ([`move_row`]). A spring's force is needed only until the row it ends in has
/// moved, [`halo`] rows on, so each class keeps its last [`halo`] + 1 rows in `ring` (in L1 cache, where
/// a buffer for every row of every class would not be). A band that does not start the sheet first
/// computes the springs that end in its rows from the rows below it, as the band below does for itself:
/// the same operations on the same values, so every band gives the bits of the serial step.
#[inline(always)]
fn step_band(
    classes: &[StencilClass],
    n: usize,
    h: f64,
    p: Particles<'_>,
    band: BandRows<'_>,
    ring: &mut [f64],
    acc: &mut [f64],
) {
    let w = 3 * n;
    let depth = halo(classes) + 1;
    let slot = |k: usize, r: usize| (k * depth + r % depth) * w;
    let first = band.first;
    let last = first + band.pos.len() / w;
    // A function, not a closure: a closure is compiled on its own, for the baseline instruction set,
    // unless LLVM chooses to inline it (see `StepBandOp`).
    #[inline(always)]
    fn springs_of_row(class: &StencilClass, n: usize, band: &BandRows<'_>, r: usize, out: &mut [f64]) {
        let w = 3 * n;
        let q = (r + class.dj < n).then(|| [band.old(0, r + class.dj, w), band.old(1, r + class.dj, w)]);
        class_row(class, n, [band.old(0, r, w), band.old(1, r, w)], q, out);
    }
    for r in first.saturating_sub(depth - 1)..first {
        for (k, class) in classes.iter().enumerate() {
            if r + class.dj >= first {
                springs_of_row(class, n, &band, r, &mut ring[slot(k, r)..slot(k, r) + w]);
            }
        }
    }
    for j in first..last {
        for (k, class) in classes.iter().enumerate() {
            springs_of_row(class, n, &band, j, &mut ring[slot(k, j)..slot(k, j) + w]);
        }
        let range = j * n..(j + 1) * n;
        split_row(acc, n, |c, i| p.gravity[c] * p.masses[range.start + i]);
        let ring = &*ring;
        sum_row(
            classes,
            |k| &ring[slot(k, j)..slot(k, j) + w],
            |k| {
                (j >= classes[k].dj)
                    .then(|| &ring[slot(k, j - classes[k].dj)..slot(k, j - classes[k].dj) + w])
            },
            acc,
        );
        let local = (j - first) * w..(j - first + 1) * w;
        let (inv_m, pinned) = (&p.inv_masses[range.clone()], &p.pinned[range]);
        move_row(n, h, acc, inv_m, pinned, &mut band.pos[local.clone()], &mut band.vel[local]);
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
    rayon::current_num_threads()
}

fn all_finite(x: &[DVec3], v: &[DVec3]) -> bool {
    x.iter().zip(v).all(|(x, v)| x.is_finite() && v.is_finite())
}

/// Calls `body(k, chunk)` for every `size`-long chunk k of `buf`, on all cores when asked. Chunks are
/// disjoint, so the result does not depend on the order.
fn for_each_chunk<T: Send>(
    buf: &mut [T],
    size: usize,
    parallel: bool,
    body: impl Fn(usize, &mut [T]) + Sync + Send,
) {
    if parallel {
        use rayon::prelude::*;
        buf.par_chunks_mut(size).enumerate().for_each(|(k, chunk)| body(k, chunk));
        return;
    }
    for (k, chunk) in buf.chunks_mut(size).enumerate() {
        body(k, chunk);
    }
}

/// The parallel symplectic-Euler run: the rows split into one band per thread, each thread moving its
/// band with [`step_band`], one barrier a step.
///
/// A band needs the state before the step of the [`halo`] rows on either side of it, which its
/// neighbours move in the same step; so at the start of a step every band copies its first and last
/// [`halo`] rows into its halo buffer, all wait at the barrier, and then each moves its rows, reading its
/// neighbours' halos. Halos alternate between two buffers from step to step: a band overwrites the one
/// it wrote two steps before, which its neighbours stopped reading before they reached the last barrier.
///
/// The threads are started once, with the first parallel run, and wait between runs; halos sit behind
/// read–write locks so that the threads share them without unsafe code, and the barrier and the
/// alternation keep the locks uncontended. A barrier is a spin on an atomic counter, under a
/// microsecond, where a pool's fork and join per pass, or threads started for every run, cost more than
/// a small sheet's pass (measured: threads started per 1/30 s frame made two threads slower than one on
/// the 32 × 32 sheet).
mod banded {
    use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
    use std::sync::mpsc::{Receiver, Sender, channel};
    use std::sync::{Arc, Mutex, RwLock};
    use std::thread::JoinHandle;

    use anima_geom::DVec3;

    use super::{BandRows, Particles, StencilClass, StepBandOp, halo, join_row, ring_len};

    /// The most threads a run uses.
    const MAX_BANDS: usize = 8;
    /// The fewest rows a band may have: fewer, and the barriers cost more than the band's work.
    const MIN_ROWS: usize = 8;

    /// The bands of a sheet and the threads that move them, kept between runs. A clone starts with none
    /// (they are scratch, filled at the start of every run, and threads are not shared).
    #[derive(Debug, Default)]
    pub(super) struct Bands {
        team: Option<Team>,
        /// Bands to use instead of [`band_count`]'s (tests: more bands than the machine has cores).
        pub count: Option<usize>,
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

    /// Consecutive rows `first..first + rows`: their state, which only the band's thread touches during
    /// a run, and their halos, which its neighbours read.
    #[derive(Debug)]
    struct Band {
        first: usize,
        rows: usize,
        state: Mutex<BandState>,
        /// By step parity: the band's first [`halo`] rows of positions, of velocities, then its last
        /// [`halo`] rows of positions, of velocities, as they were before the step.
        halos: [RwLock<Vec<f64>>; 2],
    }

    /// The band's positions, velocities, ring (see [`step_band`]) and one row of summed forces, in one
    /// buffer with [`PAD`] at either end.
    #[derive(Debug)]
    struct BandState {
        buf: Vec<f64>,
        rows_len: usize,
        ring_len: usize,
    }

    /// Doubles of padding at both ends of every buffer a band's thread writes: two cache lines, the pair
    /// that the processor's adjacent-line prefetch moves together, so that no two threads write into
    /// one pair. Without it, which band's steps ran up to 35 % slower changed with where the allocator
    /// happened to put the bands' buffers; with it, they did not (measured on the 32 × 32 sheet). That
    /// sharing a line pair was the cause is the likeliest reading, not one a counter confirmed.
    const PAD: usize = 16;

    impl BandState {
        fn new(rows_len: usize, ring_len: usize, w: usize) -> Self {
            Self { buf: vec![0.0; PAD + 2 * rows_len + ring_len + w + PAD], rows_len, ring_len }
        }

        /// Positions, velocities, ring and summed forces.
        fn parts(&mut self) -> [&mut [f64]; 4] {
            let end = self.buf.len() - PAD;
            let (pos, rest) = self.buf[PAD..end].split_at_mut(self.rows_len);
            let (vel, rest) = rest.split_at_mut(self.rows_len);
            let (ring, acc) = rest.split_at_mut(self.ring_len);
            [pos, vel, ring, acc]
        }
    }

    /// A halo buffer of `len` doubles, padded like [`BandState`].
    fn padded(len: usize) -> Vec<f64> {
        vec![0.0; PAD + len + PAD]
    }

    /// The halo in a padded buffer.
    fn unpadded(buf: &[f64]) -> &[f64] {
        &buf[PAD..buf.len() - PAD]
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

    /// Bands, one per thread, of a sheet of n rows: as many as the machine has cores, at most
    /// [`MAX_BANDS`], each of at least [`MIN_ROWS`] rows; 1 means no banded run.
    pub(super) fn band_count(n: usize) -> usize {
        let cores = std::thread::available_parallelism().map_or(1, |t| t.get());
        cores.min(MAX_BANDS).min(n / MIN_ROWS).max(1)
    }

    impl Bands {
        /// Splits n rows over [`band_count`] bands and starts their threads, unless they are there
        /// already; false when there would be only one band, or a band would be narrower than a halo.
        pub fn prepare(&mut self, n: usize, classes: &[StencilClass], arch: pulp::Arch) -> bool {
            let count = self.count.unwrap_or_else(|| band_count(n));
            if count < 2 {
                return false;
            }
            let rows_per_band = n.div_ceil(count);
            let depth = halo(classes);
            if n - (n.div_ceil(rows_per_band) - 1) * rows_per_band < depth.max(1) {
                return false;
            }
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
                    Band {
                        first,
                        rows,
                        state: Mutex::new(BandState::new(rows * w, ring_len(classes, n), w)),
                        halos: [(); 2].map(|()| RwLock::new(padded(4 * depth * w))),
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
                let mut state = band.state.lock().expect("lock");
                let [own_pos, own_vel, ..] = state.parts();
                own_pos.copy_from_slice(&pos[range.clone()]);
                own_vel.copy_from_slice(&vel[range]);
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
                let mut state = band.state.lock().expect("lock");
                let [own_pos, own_vel, ..] = state.parts();
                for (src, dst) in [(&*own_pos, &mut *x), (&*own_vel, &mut *v)] {
                    for (r, row) in src.chunks(w).enumerate() {
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
            let (n, w) = (self.n, 3 * self.n);
            let part = halo(&self.classes) * w;
            let band = &self.bands[b];
            let mut state = band.state.lock().expect("lock");
            let [pos, vel, ring, acc] = state.parts();
            let data = self.particles.read().expect("lock");
            let p = Particles {
                masses: &data.masses,
                inv_masses: &data.inv_masses,
                pinned: &data.pinned,
                gravity: data.gravity,
            };
            let (below, above) = (b.checked_sub(1).map(|b| &self.bands[b]), self.bands.get(b + 1));
            for step in 0..job.steps {
                let parity = step % 2;
                {
                    let mut out = band.halos[parity].write().expect("lock");
                    let end = out.len() - PAD;
                    let (head, tail) = out[PAD..end].split_at_mut(2 * part);
                    let end = pos.len() - part;
                    head[..part].copy_from_slice(&pos[..part]);
                    head[part..].copy_from_slice(&vel[..part]);
                    tail[..part].copy_from_slice(&pos[end..]);
                    tail[part..].copy_from_slice(&vel[end..]);
                }
                self.barrier.wait();
                let below = below.map(|band| band.halos[parity].read().expect("lock"));
                let above = above.map(|band| band.halos[parity].read().expect("lock"));
                let (below, above) =
                    (below.as_deref().map(|h| unpadded(h)), above.as_deref().map(|h| unpadded(h)));
                let rows = BandRows {
                    first: band.first,
                    pos: &mut *pos,
                    vel: &mut *vel,
                    below: below.map_or([&[], &[]], |h| [&h[2 * part..3 * part], &h[3 * part..]]),
                    above: above.map_or([&[], &[]], |h| [&h[..part], &h[part..2 * part]]),
                };
                let (classes, h) = (&self.classes[..], job.h);
                self.arch.dispatch(StepBandOp {
                    classes,
                    n,
                    h,
                    p,
                    band: rows,
                    ring: &mut *ring,
                    acc: &mut *acc,
                });
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

#[cfg(test)]
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
