//! Filtered, preconditioned conjugate gradients for A δ = b (Baraff & Witkin 1998, §5.3: the filter S
//! keeps every iterate inside the free directions, so constrained directions stay exactly as given).

#![allow(
    clippy::needless_range_loop,
    reason = "the loops walk several per-coordinate arrays in step; the index form mirrors the formulas"
)]

use crate::Coord;
use crate::parallel::{self, Sum};

use super::system::{Filter, SystemMatrix};

/// A symmetric positive definite approximation P⁻¹ of A⁻¹.
pub(crate) trait Preconditioner<C: Coord> {
    /// z = S P⁻¹ r for a residual r that is already filtered.
    fn apply(
        &mut self,
        a: &SystemMatrix<C>,
        pattern: &[(u32, u32)],
        filter: Filter<'_, C>,
        r: &[C],
        z: &mut [C],
    );
}

/// Block Jacobi: P = the diagonal blocks of A.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct BlockJacobi;

impl<C: Coord> Preconditioner<C> for BlockJacobi {
    fn apply(&mut self, a: &SystemMatrix<C>, _: &[(u32, u32)], filter: Filter<'_, C>, r: &[C], z: &mut [C]) {
        parallel::for_chunks(z, |s, z| {
            for (k, z) in z.iter_mut().enumerate() {
                *z = filter.one(s + k, C::block_mul(a.jacobi[s + k], r[s + k]));
            }
        });
    }
}

/// The vectors of one solve, kept between solves.
#[derive(Debug, Clone, Default)]
pub(crate) struct CgBuffers<C> {
    r: Vec<C>,
    z: Vec<C>,
    p: Vec<C>,
    q: Vec<C>,
    /// b scaled down when ‖b‖² overflows.
    scaled_b: Vec<C>,
    /// The partial sums of the dot products.
    sum: Sum,
}

/// How a solve ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CgOutcome {
    pub iterations: usize,
    /// ‖r‖/‖b‖ at the end.
    pub relative_residual: f64,
    /// Whether the residual reached the tolerance; false also when A turned out not to be positive
    /// definite along a search direction (the iterate is then the last good one).
    pub converged: bool,
}

/// Solves A x = b to ‖b − A x‖ ≤ `tol`·‖b‖, starting from the given x (filtered). `b` must be filtered.
#[expect(clippy::too_many_arguments, reason = "the system, its filter, the preconditioner and the controls")]
pub(crate) fn pcg<C: Coord>(
    a: &SystemMatrix<C>,
    pattern: &[(u32, u32)],
    filter: Filter<'_, C>,
    precond: &mut dyn Preconditioner<C>,
    b: &[C],
    x: &mut [C],
    buf: &mut CgBuffers<C>,
    tol: f64,
    max_iter: usize,
) -> CgOutcome {
    let n = b.len();
    for v in [&mut buf.r, &mut buf.z, &mut buf.p, &mut buf.q] {
        v.resize(n, C::default());
    }
    let b_norm2 = buf.sum.dot(b, b);
    if b_norm2.is_infinite() {
        // ‖b‖² overflows while b is finite (forces beyond 1e154): every residual would compare as
        // converged with an infinite target and the solve would return x₀. CG is linear, so solve for
        // b/s and x/s instead, with s the largest component of b.
        let s = b.iter().map(|c| c.max_abs()).fold(0.0, f64::max);
        if s.is_finite() {
            let mut scaled = std::mem::take(&mut buf.scaled_b);
            scaled.clear();
            scaled.extend(b.iter().map(|&c| c * (1.0 / s)));
            x.iter_mut().for_each(|c| *c = *c * (1.0 / s));
            let outcome = pcg(a, pattern, filter, precond, &scaled, x, buf, tol, max_iter);
            x.iter_mut().for_each(|c| *c = *c * s);
            buf.scaled_b = scaled;
            return outcome;
        }
    }
    if b_norm2 == 0.0 {
        x.fill(C::default());
        return CgOutcome { iterations: 0, relative_residual: 0.0, converged: true };
    }
    // r = b − A x₀ (no product when x₀ = 0, the implicit steps' start: r = b to the bit).
    if x.iter().all(|c| c.max_abs() == 0.0) {
        buf.r.copy_from_slice(b);
    } else {
        a.mul(pattern, filter, x, &mut buf.q);
        let q = &buf.q;
        parallel::for_chunks(&mut buf.r, |s, r| {
            for (k, r) in r.iter_mut().enumerate() {
                *r = b[s + k] - q[s + k];
            }
        });
    }
    // A residual at the bottom of the floating-point range counts as solved: tol²‖b‖² underflows to zero
    // there (a motion that has decayed to nothing over thousands of steps), and p·Ap with it.
    let target = (tol * tol * b_norm2).max(f64::MIN_POSITIVE);
    let mut r2 = buf.sum.dot(&buf.r, &buf.r);
    if r2 <= target {
        return CgOutcome { iterations: 0, relative_residual: (r2 / b_norm2).sqrt(), converged: true };
    }
    precond.apply(a, pattern, filter, &buf.r, &mut buf.z);
    buf.p.copy_from_slice(&buf.z);
    let mut rz = buf.sum.dot(&buf.r, &buf.z);
    for it in 0..max_iter {
        a.mul(pattern, filter, &buf.p, &mut buf.q);
        let pq = buf.sum.dot(&buf.p, &buf.q);
        if pq.is_nan() || pq <= 0.0 {
            return CgOutcome { iterations: it, relative_residual: (r2 / b_norm2).sqrt(), converged: false };
        }
        let alpha = rz / pq;
        let (p, q) = (&buf.p, &buf.q);
        parallel::for_chunks2(x, &mut buf.r, |s, x, r| {
            for k in 0..x.len() {
                x[k] += p[s + k] * alpha;
                r[k] = r[k] - q[s + k] * alpha;
            }
        });
        // Converged: the preconditioner (its products with A) is not applied to a residual no
        // iteration will use.
        r2 = buf.sum.dot(&buf.r, &buf.r);
        if r2 <= target {
            return CgOutcome {
                iterations: it + 1,
                relative_residual: (r2 / b_norm2).sqrt(),
                converged: true,
            };
        }
        precond.apply(a, pattern, filter, &buf.r, &mut buf.z);
        let rz_new = buf.sum.dot(&buf.r, &buf.z);
        let beta = rz_new / rz;
        rz = rz_new;
        let z = &buf.z;
        parallel::for_chunks(&mut buf.p, |s, p| {
            for (k, p) in p.iter_mut().enumerate() {
                *p = z[s + k] + *p * beta;
            }
        });
    }
    CgOutcome { iterations: max_iter, relative_residual: (r2 / b_norm2).sqrt(), converged: r2 <= target }
}
