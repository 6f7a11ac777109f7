//! Backward Euler linearised once per step (Baraff & Witkin, "Large steps in cloth simulation", 1998):
//!
//! (M − h D − h² K) Δv = h (f₀ + h K v₀),   v₁ = v₀ + Δv,   x₁ = x₀ + h v₁,
//!
//! with K = ∂f/∂x and D = ∂f/∂v at the start of the step.
//!
//! BDF2 (as Choi & Ko 2002 used it for cloth) is the same solve with other coefficients. With
//! β = 2h/3, x̂ = (4 x₀ − x₋₁)/3 and v̂ = (4 v₀ − v₋₁)/3 it asks x₁ = x̂ + β v₁ and M v₁ = M v̂ + β f(x₁, v₁);
//! linearising f about (x₀, v₀) gives
//!
//! (M − β D − β² K) Δv = M (v̂ − v₀) + β (f₀ + K (x̂ − x₀ + β v₀)),
//!
//! which for x̂ = x₀, v̂ = v₀, β = h is the backward Euler system above. One backward Euler step starts
//! it, and restarts it whenever the history is invalid (a collision response, a change of step). The matrix is symmetric positive definite when
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
    /// Cheap per iteration, but the iterations grow with the stiffness and the step.
    ConjugateGradient { tolerance: f64, max_iterations: usize },
    /// faer's sparse Cholesky (LLᵀ, falling back to LDLᵀ when A is not positive definite): exact to
    /// round-off whatever the stiffness; the symbolic factorisation is reused while the pattern holds.
    #[cfg(feature = "sparse-cholesky")]
    SparseCholesky,
}

impl LinearSolver {
    /// CG to a relative residual of 1e-8, at most 1 000 iterations.
    pub const fn default_cg() -> Self {
        LinearSolver::ConjugateGradient { tolerance: 1e-8, max_iterations: 1000 }
    }

    /// The solver's name on the command line and in scene files: `cg` or `cholesky`.
    pub fn name(&self) -> &'static str {
        match self {
            LinearSolver::ConjugateGradient { .. } => "cg",
            #[cfg(feature = "sparse-cholesky")]
            LinearSolver::SparseCholesky => "cholesky",
        }
    }
}

impl std::str::FromStr for LinearSolver {
    type Err = String;

    /// `cg` (the default tolerances) or `cholesky`.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "cg" => Ok(LinearSolver::default_cg()),
            #[cfg(feature = "sparse-cholesky")]
            "cholesky" => Ok(LinearSolver::SparseCholesky),
            _ => Err(format!("unknown linear solver `{s}`; expected `cg` or `cholesky`")),
        }
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
    #[cfg(feature = "sparse-cholesky")]
    direct: crate::sparse::DirectCache,
    /// BDF2 only: the state one step back, and the step that led from it (0 when there is none).
    bdf2: Option<State<C>>,
    prev_h: f64,
    /// x̂ − x₀ + β v₀ (the vector K multiplies on the right-hand side), then v̂.
    w: Vec<C>,
    /// Positions of the current Newton iterate.
    xk: Vec<C>,
    /// Newton iterations per step: 1 (backward Euler's default) is Baraff–Witkin's single linearisation;
    /// BDF2 defaults to 2, since one linearisation about the start of the step costs it its second order
    /// on stiff, damped springs (measured on the Oliveira sheet of `cargo xtask bench`).
    pub newton_iterations: usize,
}

impl<C: Coord> ImplicitWorkspace<C> {
    pub fn new(n: usize, bdf2: bool) -> Self {
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
            #[cfg(feature = "sparse-cholesky")]
            direct: Default::default(),
            bdf2: bdf2.then(|| State::zeros(n)),
            prev_h: 0.0,
            w: zeros(),
            xk: zeros(),
            newton_iterations: if bdf2 { 2 } else { 1 },
        }
    }

    /// Forgets the step before the last (BDF2 restarts with a backward Euler step).
    pub fn reset_history(&mut self) {
        self.prev_h = 0.0;
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
        self.a_off.resize(n_pairs, C::block_identity(0.0));
        // BDF2 when the last step had the same size; backward Euler otherwise.
        let bdf2 = self.bdf2.is_some() && self.prev_h == h;
        let beta = if bdf2 { 2.0 * h / 3.0 } else { h };
        // x̂ and v̂ (held in `next` while iterating), and w = x̂ − x₀ + β v₀.
        for i in 0..n {
            (next.x[i], next.v[i]) = match &self.bdf2 {
                Some(prev) if bdf2 => (
                    now.x[i] + (now.x[i] - prev.x[i]) * (1.0 / 3.0),
                    now.v[i] + (now.v[i] - prev.v[i]) * (1.0 / 3.0),
                ),
                _ => (now.x[i], now.v[i]),
            };
            self.w[i] = next.x[i] - now.x[i] + now.v[i] * beta;
        }
        // Newton's first iteration, linearised about the start of the step (Baraff–Witkin):
        // b = M (v̂ − v₀) + β (f + K w), solved for Δv = v₁ − v₀.
        self.jac.clear();
        lin.force_and_jacobians(t, &now.x, &now.v, &mut self.f, &mut self.jac);
        let (masses, prescribed) = (lin.masses(), lin.prescribed());
        self.assemble(masses, lin.pattern(), beta);
        for i in 0..n {
            self.b[i] = C::block_mul(self.jac.k_diag[i], self.w[i]);
        }
        for (e, &(i, j)) in lin.pattern().iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let k = self.jac.k_off[e];
            let (bi, bj) = (C::block_mul(k, self.w[j]), C::block_mul_transpose(k, self.w[i]));
            self.b[i] += bi;
            self.b[j] += bj;
        }
        for i in 0..n {
            self.b[i] = if prescribed[i] {
                C::default()
            } else {
                (next.v[i] - now.v[i]) * masses[i] + (self.f[i] + self.b[i]) * beta
            };
        }
        let mut iterations = self.solve(lin.pattern(), prescribed, n)?;
        // v̂ goes to `v_hat` (kept in self.w, no longer needed as w), the iterate v₁ to next.v.
        for i in 0..n {
            self.w[i] = next.v[i];
            next.v[i] = now.v[i] + self.dv[i];
        }
        let place = |x_hat: C, x0: C, v1: C, fixed: bool| if fixed { x0 + v1 * h } else { x_hat + v1 * beta };
        // Further Newton iterations on G(v) = M (v − v̂) − β f(x̂ + β v, v) = 0, each linearised about the
        // current iterate: (M − β D − β² K) δ = −G(v).
        for _ in 1..self.newton_iterations {
            let prescribed = lin.prescribed();
            for i in 0..n {
                self.xk[i] = place(next.x[i], now.x[i], next.v[i], prescribed[i]);
            }
            self.jac.clear();
            lin.force_and_jacobians(t + h, &self.xk, &next.v, &mut self.f, &mut self.jac);
            let (masses, prescribed) = (lin.masses(), lin.prescribed());
            self.assemble(masses, lin.pattern(), beta);
            for i in 0..n {
                self.b[i] = if prescribed[i] {
                    C::default()
                } else {
                    self.f[i] * beta - (next.v[i] - self.w[i]) * masses[i]
                };
                self.dv[i] = C::default();
            }
            iterations += self.solve(lin.pattern(), prescribed, n)?;
            for i in 0..n {
                next.v[i] += self.dv[i];
            }
        }
        let prescribed = lin.prescribed();
        for i in 0..n {
            next.x[i] = place(next.x[i], now.x[i], next.v[i], prescribed[i]);
        }
        if let Some(prev) = &mut self.bdf2 {
            prev.x.copy_from_slice(&now.x);
            prev.v.copy_from_slice(&now.v);
        }
        self.prev_h = if self.bdf2.is_some() { h } else { 0.0 };
        Ok(StepStats { evaluations: self.newton_iterations, error: None, solver_iterations: iterations })
    }

    /// A = M − β D − β² K from the current Jacobians, and its block-Jacobi preconditioner.
    fn assemble(&mut self, masses: &[f64], pattern: &[(u32, u32)], beta: f64) {
        let beta2 = beta * beta;
        for i in 0..masses.len() {
            let m = C::block_identity(masses[i]);
            let hd = C::block_combine(self.jac.d_diag[i], beta, self.jac.k_diag[i], beta2);
            self.a_diag[i] = C::block_combine(m, 1.0, hd, -1.0);
            self.precond[i] = C::block_inverse(self.a_diag[i]);
        }
        for e in 0..pattern.len() {
            self.a_off[e] = C::block_combine(self.jac.d_off[e], -beta, self.jac.k_off[e], -beta2);
        }
    }

    /// Solves A Δv = b into `self.dv` with the chosen solver; returns CG iterations (0 for the direct one).
    fn solve(&mut self, pattern: &[(u32, u32)], prescribed: &[bool], n: usize) -> Result<usize, OdeError> {
        for (dv, &fixed) in self.dv.iter_mut().zip(prescribed) {
            if fixed {
                *dv = C::default();
            }
        }
        Ok(match self.solver {
            LinearSolver::ConjugateGradient { tolerance, max_iterations } => {
                self.cg(pattern, prescribed, tolerance, max_iterations)?
            }
            #[cfg(feature = "sparse-cholesky")]
            LinearSolver::SparseCholesky => {
                let fits = self.direct.0.as_ref().is_some_and(|d| d.fits(n, pattern));
                if !fits {
                    self.direct.0 = Some(
                        crate::sparse::SparseSolver::new::<C>(n, pattern)
                            .map_err(|e| OdeError::Factorization(e.to_string()))?,
                    );
                }
                let direct = self.direct.0.as_mut().expect("built above");
                direct
                    .solve::<C>(&self.a_diag, &self.a_off, prescribed, &self.b, &mut self.dv)
                    .map_err(|e| OdeError::Factorization(e.to_string()))?;
                0
            }
        })
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
