//! Backward Euler linearised once per step (Baraff & Witkin, "Large steps in cloth simulation", 1998):
//!
//! (M − h D − h² K) Δv = h (f₀ + h K v₀),   v₁ = v₀ + Δv,   x₁ = x₀ + h v₁,
//!
//! with K = ∂f/∂x and D = ∂f/∂v at the start of the step. The matrix is symmetric positive definite when
//! K and D are symmetric negative semi-definite, which [`Linearized`] systems promise (spring Jacobians
//! are made definite by clamping their geometric term; see the cloth crate), so the solve is
//! preconditioned conjugate gradients. Coordinates with a prescribed velocity are handled exactly by
//! filtering them out of the solve (Δv = 0 there), not by a large stiffness.

#![allow(
    clippy::needless_range_loop,
    reason = "the loops walk several per-coordinate arrays in step; the index form mirrors the formulas"
)]

use crate::Coord;
use crate::stepper::{OdeError, State, StepStats};

/// A system that can give its force and the force's Jacobians, for implicit integration.
pub trait Linearized<C: Coord> {
    /// Lumped mass of each coordinate.
    fn masses(&self) -> &[f64];
    /// Coordinates whose velocity is prescribed (pinned or kinematic): the implicit step keeps their
    /// velocity as it is.
    fn prescribed(&self) -> &[bool];
    /// The off-diagonal pairs (i < j) where the Jacobians may be non-zero. Constant while the topology is.
    fn pattern(&self) -> &[(u32, u32)];
    /// Writes the force f(t, x, v) (not divided by the mass) and its Jacobians K = ∂f/∂x, D = ∂f/∂v on
    /// [`Linearized::pattern`]. Both must be symmetric: block (j, i) is the transpose of block (i, j).
    fn force_and_jacobians(&mut self, t: f64, x: &[C], v: &[C], f: &mut [C], jac: &mut Jacobians<C>);
}

/// Block-sparse symmetric Jacobians: diagonal blocks, and one block per pattern pair (i, j), i < j,
/// holding ∂f_i/∂x_j (the (j, i) block is its transpose).
#[derive(Debug, Clone)]
pub struct Jacobians<C: Coord> {
    pub k_diag: Vec<C::Block>,
    pub k_off: Vec<C::Block>,
    pub d_diag: Vec<C::Block>,
    pub d_off: Vec<C::Block>,
}

impl<C: Coord> Jacobians<C> {
    pub fn new(n: usize, n_pairs: usize) -> Self {
        let z = C::block_identity(0.0);
        Self { k_diag: vec![z; n], k_off: vec![z; n_pairs], d_diag: vec![z; n], d_off: vec![z; n_pairs] }
    }

    /// Sets every block to zero, keeping the sizes.
    pub fn clear(&mut self) {
        let z = C::block_identity(0.0);
        for v in [&mut self.k_diag, &mut self.k_off, &mut self.d_diag, &mut self.d_off] {
            v.fill(z);
        }
    }

    fn resize(&mut self, n: usize, n_pairs: usize) {
        let z = C::block_identity(0.0);
        self.k_diag.resize(n, z);
        self.d_diag.resize(n, z);
        self.k_off.resize(n_pairs, z);
        self.d_off.resize(n_pairs, z);
    }
}

/// How the implicit step solves its linear system.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LinearSolver {
    /// Conjugate gradients with a block-Jacobi preconditioner, to a relative residual `tolerance`.
    ConjugateGradient { tolerance: f64, max_iterations: usize },
}

impl LinearSolver {
    /// CG to a relative residual of 1e-8, at most 1 000 iterations.
    pub const fn default_cg() -> Self {
        LinearSolver::ConjugateGradient { tolerance: 1e-8, max_iterations: 1000 }
    }
}

#[derive(Debug, Clone)]
pub(crate) struct ImplicitWorkspace<C: Coord> {
    pub solver: LinearSolver,
    f: Vec<C>,
    jac: Jacobians<C>,
    a_diag: Vec<C::Block>,
    a_off: Vec<C::Block>,
    precond: Vec<C::Block>,
    b: Vec<C>,
    /// Δv, kept between steps as the next solve's first guess.
    dv: Vec<C>,
    r: Vec<C>,
    z: Vec<C>,
    p: Vec<C>,
    q: Vec<C>,
}

impl<C: Coord> ImplicitWorkspace<C> {
    pub fn new(n: usize) -> Self {
        let zeros = || vec![C::default(); n];
        let zb = || vec![C::block_identity(0.0); n];
        Self {
            solver: LinearSolver::default_cg(),
            f: zeros(),
            jac: Jacobians::new(n, 0),
            a_diag: zb(),
            a_off: Vec::new(),
            precond: zb(),
            b: zeros(),
            dv: zeros(),
            r: zeros(),
            z: zeros(),
            p: zeros(),
            q: zeros(),
        }
    }

    pub fn step(
        &mut self,
        lin: &mut dyn Linearized<C>,
        t: f64,
        h: f64,
        now: &State<C>,
        next: &mut State<C>,
    ) -> Result<StepStats, OdeError> {
        let n = now.len();
        let n_pairs = lin.pattern().len();
        self.jac.resize(n, n_pairs);
        self.jac.clear();
        self.a_off.resize(n_pairs, C::block_identity(0.0));
        lin.force_and_jacobians(t, &now.x, &now.v, &mut self.f, &mut self.jac);
        let (masses, prescribed, pattern) = (lin.masses(), lin.prescribed(), lin.pattern());
        let h2 = h * h;
        // A = M − h D − h² K and b = h (f + h K v).
        for i in 0..n {
            let m = C::block_identity(masses[i]);
            let hd = C::block_combine(self.jac.d_diag[i], h, self.jac.k_diag[i], h2);
            self.a_diag[i] = C::block_combine(m, 1.0, hd, -1.0);
            self.precond[i] = C::block_inverse(self.a_diag[i]);
            self.b[i] = C::block_mul(self.jac.k_diag[i], now.v[i]);
        }
        for (e, &(i, j)) in pattern.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            self.a_off[e] = C::block_combine(self.jac.d_off[e], -h, self.jac.k_off[e], -h2);
            let k = self.jac.k_off[e];
            let bi = C::block_mul(k, now.v[j]);
            let bj = C::block_mul_transpose(k, now.v[i]);
            self.b[i] += bi;
            self.b[j] += bj;
        }
        for i in 0..n {
            self.b[i] = if prescribed[i] { C::default() } else { (self.f[i] + self.b[i] * h) * h };
            if prescribed[i] {
                self.dv[i] = C::default();
            }
        }
        let LinearSolver::ConjugateGradient { tolerance, max_iterations } = self.solver;
        let iterations = self.cg(pattern, prescribed, tolerance, max_iterations)?;
        for i in 0..n {
            let v1 = now.v[i] + self.dv[i];
            next.v[i] = v1;
            next.x[i] = now.x[i] + v1 * h;
        }
        Ok(StepStats { evaluations: 1, error: None, solver_iterations: iterations })
    }

    /// y = A p, with prescribed coordinates filtered out (y_i = 0 there).
    fn apply(&mut self, pattern: &[(u32, u32)], prescribed: &[bool]) {
        for i in 0..self.p.len() {
            self.q[i] = C::block_mul(self.a_diag[i], self.p[i]);
        }
        for (e, &(i, j)) in pattern.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let (qi, qj) =
                (C::block_mul(self.a_off[e], self.p[j]), C::block_mul_transpose(self.a_off[e], self.p[i]));
            self.q[i] += qi;
            self.q[j] += qj;
        }
        for (q, &fixed) in self.q.iter_mut().zip(prescribed) {
            if fixed {
                *q = C::default();
            }
        }
    }

    /// Filtered, block-Jacobi preconditioned conjugate gradients for A Δv = b, started from the previous
    /// Δv. Returns the iterations used.
    fn cg(
        &mut self,
        pattern: &[(u32, u32)],
        prescribed: &[bool],
        tol: f64,
        max_iter: usize,
    ) -> Result<usize, OdeError> {
        let n = self.b.len();
        let dot = |a: &[C], b: &[C]| a.iter().zip(b).map(|(x, y)| x.dot(*y)).sum::<f64>();
        let b_norm2 = dot(&self.b, &self.b);
        if b_norm2 == 0.0 {
            self.dv.fill(C::default());
            return Ok(0);
        }
        // r = b − A Δv₀
        self.p.copy_from_slice(&self.dv);
        self.apply(pattern, prescribed);
        for i in 0..n {
            self.r[i] = self.b[i] - self.q[i];
            self.z[i] = C::block_mul(self.precond[i], self.r[i]);
            if prescribed[i] {
                self.z[i] = C::default();
            }
        }
        self.p.copy_from_slice(&self.z);
        let mut rz = dot(&self.r, &self.z);
        let target = tol * tol * b_norm2;
        for it in 0..max_iter {
            let r2 = dot(&self.r, &self.r);
            if r2 <= target {
                return Ok(it);
            }
            self.apply(pattern, prescribed);
            let pq = dot(&self.p, &self.q);
            if pq.is_nan() || pq <= 0.0 {
                return Err(OdeError::SolverDidNotConverge {
                    iterations: it,
                    residual: (r2 / b_norm2).sqrt(),
                });
            }
            let alpha = rz / pq;
            for i in 0..n {
                self.dv[i] += self.p[i] * alpha;
                self.r[i] = self.r[i] - self.q[i] * alpha;
                self.z[i] =
                    if prescribed[i] { C::default() } else { C::block_mul(self.precond[i], self.r[i]) };
            }
            let rz_new = dot(&self.r, &self.z);
            let beta = rz_new / rz;
            rz = rz_new;
            for i in 0..n {
                self.p[i] = self.z[i] + self.p[i] * beta;
            }
        }
        let r2 = dot(&self.r, &self.r);
        if r2 <= target {
            Ok(max_iter)
        } else {
            Err(OdeError::SolverDidNotConverge { iterations: max_iter, residual: (r2 / b_norm2).sqrt() })
        }
    }
}
