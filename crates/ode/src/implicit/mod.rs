//! Implicit integration of M x'' = f(t, x, v): the methods, their Newton iterations and the linear solves.
//!
//! Every implicit step here solves for the velocity w = v(t + h) at the end of the step, with the
//! position and the force's arguments affine in it:
//!
//! x* = X₀ + c_x w,   v* = V₀ + c_v w,   M (w − W₀) = η f(t*, x*, v*).
//!
//! Newton's method on G(w) = M (w − W₀) − η f(t*, x*, v*) solves the same linear system at every
//! iteration,
//!
//! (M − β_v D − β_x K) δ = −G(w),   β_v = η c_v,   β_x = η c_x,
//!
//! with K = ∂f/∂x and D = ∂f/∂v. It is symmetric positive definite when K and D are symmetric negative
//! semi-definite, which [`Linearized`] systems promise (spring Jacobians are made definite by clamping
//! their geometric term; see the cloth crate). Coordinates with a prescribed velocity are filtered out of
//! the solve (δ = 0 there), not stiffened.
//!
//! - Backward Euler (η = c_x = h, c_v = 1), linearised once about the start of the step as Baraff &
//!   Witkin ("Large steps in cloth simulation", 1998) do, and BDF2 (η = c_x = 2h/3, as Choi & Ko 2002
//!   used it for cloth): [`euler`].
//! - Generalised-α (Chung & Hulbert 1993), second order with its high-frequency damping as a parameter
//!   ρ∞: [`alpha`].
//!
//! The linear solves ([`LinearSolver`]): conjugate gradients with a block-Jacobi preconditioner
//! ([`cg`]); faer's sparse Cholesky ([`cholesky`]); conjugate gradients with a two-level
//! preconditioner that keeps one factorisation across Newton iterations and steps ([`two_level`]); and
//! conjugate gradients with a coarse level of rigid patch motions rebuilt every step ([`aggregation`]).
//! Velocity constraints from contact enter the generalised-α solve through [`contact`].

#[cfg(feature = "sparse-cholesky")]
pub(crate) mod aggregation;
pub(crate) mod alpha;
pub(crate) mod cg;
#[cfg(feature = "sparse-cholesky")]
pub(crate) mod cholesky;
pub mod contact;
pub(crate) mod euler;
pub(crate) mod system;
#[cfg(feature = "sparse-cholesky")]
pub mod two_level;
pub(crate) mod workspace;

use crate::Coord;

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

    /// Writes the force f(t, x, v) alone (not divided by the mass), where a step needs a residual but
    /// no new matrix (generalised-α's last line-search point). The default goes through
    /// [`Linearized::force_and_jacobians`] and `scratch`; a system with a cheaper force overrides it, and
    /// must give the same force to the bit.
    fn force(&mut self, t: f64, x: &[C], v: &[C], f: &mut [C], scratch: &mut Jacobians<C>) {
        scratch.resize(x.len(), self.pattern().len());
        scratch.clear();
        self.force_and_jacobians(t, x, v, f, scratch);
    }

    /// Whether the system matrix is that of a spring network: A = M + Σ_e B_e (e_i − e_j)(e_i − e_j)ᵀ
    /// over the pattern pairs e = (i, j), each B_e = u_e u_eᵀ + a_e I. Such a system writes its pairs
    /// in that form too ([`Linearized::force_and_system`]'s `springs`), and the solvers multiply by A
    /// from it: 4 numbers a pair instead of a 3 × 3 block, and one product instead of two (about 1.6
    /// times faster on the standard sheet). The default is no.
    fn spring_form(&self) -> bool {
        false
    }

    /// For a system in [`Linearized::spring_form`]: the multiple of the identity, beyond the mass and
    /// the springs, that its diagonal blocks hold (β_v C_i for a drag −C_i v_i), written per coordinate
    /// into `out` (which holds zeros). [`Linearized::force_and_system`] adds the same to `diag`. The
    /// default is none.
    fn spring_form_diagonal(&self, beta_v: f64, beta_x: f64, out: &mut [f64]) {
        let _ = (beta_v, beta_x, out);
    }

    /// Writes the force and the blocks of the system matrix A = M − β_v D − β_x K in one pass
    /// ([`SystemOut`]): `diag` gets −β_v D_ii − β_x K_ii (the mass is added by the caller) and `off`
    /// gets −β_v D_ij − β_x K_ij on the pattern; a system in [`Linearized::spring_form`] is passed
    /// `springs` and replaces its contents with one block per pattern pair, in the pattern's order
    /// (off_e = −(u uᵀ + a I), `diag` holding their sum exactly); it is passed an empty `off` when the
    /// solver needs no blocks. The implicit steps call this once per Newton iteration; the default
    /// goes through [`Linearized::force_and_jacobians`] and `scratch` and leaves `springs` as it is, and
    /// a system whose Jacobians are sums over pairs can override it to skip the four intermediate block
    /// arrays.
    #[expect(clippy::too_many_arguments, reason = "the state, the two coefficients and the outputs")]
    fn force_and_system(
        &mut self,
        t: f64,
        x: &[C],
        v: &[C],
        beta_v: f64,
        beta_x: f64,
        out: SystemOut<'_, C>,
        scratch: &mut Jacobians<C>,
    ) {
        scratch.resize(x.len(), self.pattern().len());
        scratch.clear();
        self.force_and_jacobians(t, x, v, out.f, scratch);
        for (a, (&d, &k)) in out.diag.iter_mut().zip(scratch.d_diag.iter().zip(&scratch.k_diag)) {
            *a = C::block_combine(d, -beta_v, k, -beta_x);
        }
        for (a, (&d, &k)) in out.off.iter_mut().zip(scratch.d_off.iter().zip(&scratch.k_off)) {
            *a = C::block_combine(d, -beta_v, k, -beta_x);
        }
    }
}

/// Where [`Linearized::force_and_system`] writes the force and the system matrix.
#[derive(Debug)]
pub struct SystemOut<'a, C: Coord> {
    /// The force f(t, x, v), not divided by the mass.
    pub f: &'a mut [C],
    /// −β_v D_ii − β_x K_ii per coordinate.
    pub diag: &'a mut [C::Block],
    /// −β_v D_ij − β_x K_ij per pattern pair; empty when the solver needs no blocks.
    pub off: &'a mut [C::Block],
    /// In spring form: one block per pattern pair, in the pattern's order.
    pub springs: Option<&'a mut Vec<SpringBlock<C>>>,
}

/// One pair of a matrix in spring form (see [`Linearized::spring_form`]): B = u uᵀ + a I between
/// coordinates `i` and `j`. 40 bytes for `DVec3`: the product with the matrix streams these.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpringBlock<C> {
    pub i: u32,
    pub j: u32,
    pub u: C,
    pub a: f64,
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

    /// Sets the sizes (no allocation once they are reached).
    pub fn resize(&mut self, n: usize, n_pairs: usize) {
        let z = C::block_identity(0.0);
        self.k_diag.resize(n, z);
        self.d_diag.resize(n, z);
        self.k_off.resize(n_pairs, z);
        self.d_off.resize(n_pairs, z);
    }
}

/// How an implicit step solves its linear systems.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LinearSolver {
    /// Conjugate gradients with a block-Jacobi preconditioner, to a relative residual `tolerance`.
    /// Cheap per iteration, but the iterations grow with the stiffness and the step.
    ConjugateGradient { tolerance: f64, max_iterations: usize },
    /// faer's sparse Cholesky (LLᵀ, falling back to LDLᵀ when A is not positive definite): exact to
    /// round-off whatever the stiffness; the symbolic factorisation is reused while the pattern holds,
    /// the numeric one is redone at every Newton iteration.
    #[cfg(feature = "sparse-cholesky")]
    SparseCholesky,
    /// Conjugate gradients with the two-level preconditioner (module `implicit::two_level`): block-Jacobi smoothing
    /// on the exact system and a global correction by a scalar "mass plus spring Laplacian" matrix,
    /// factorised once and kept across Newton iterations and steps (refreshed only when the step or the
    /// stiffness changes), to a relative residual `tolerance`.
    #[cfg(feature = "sparse-cholesky")]
    TwoLevel { tolerance: f64, max_iterations: usize },
    /// Conjugate gradients with a rigid-aggregation preconditioner (module `implicit::aggregation`): block-Jacobi
    /// smoothing and a coarse level of the rigid motions of small patches, projected with the A of each
    /// step's first Newton iteration and factorised once per step, to a relative residual `tolerance`.
    /// The default of generalised-α.
    #[cfg(feature = "sparse-cholesky")]
    RigidAggregation { tolerance: f64, max_iterations: usize },
}

impl LinearSolver {
    /// CG to a relative residual of 1e-8, at most 1 000 iterations.
    pub const fn default_cg() -> Self {
        LinearSolver::ConjugateGradient { tolerance: 1e-8, max_iterations: 1000 }
    }

    /// The two-level preconditioned CG with the tolerance generalised-α's Newton iterations need: a
    /// relative residual of 0.1 per Newton iteration, at most 200 iterations.
    #[cfg(feature = "sparse-cholesky")]
    pub const fn default_two_level() -> Self {
        LinearSolver::TwoLevel { tolerance: 0.1, max_iterations: 200 }
    }

    /// The rigid-aggregation preconditioned CG with the tolerance generalised-α's Newton iterations
    /// need: a relative residual of 0.1 per Newton iteration, at most 200 iterations. Measured on the
    /// standard sheet at 1/60 s with two Newton iterations: 0.1 errs 8.0 mm at the centre of mass
    /// (47 mm RMS) with 9.5 CG iterations per step, 0.05 14 mm (32 mm) with 13.3, 0.03 13 mm (29 mm)
    /// with 16.0; the default (at most three, ending on contraction) 5.8 mm (23 mm) with 10.1. With
    /// three, 0.2 saves a third of the iterations but let the very stiff sheet of the hard cases swing
    /// up.
    #[cfg(feature = "sparse-cholesky")]
    pub const fn default_aggregation() -> Self {
        LinearSolver::RigidAggregation { tolerance: 0.1, max_iterations: 200 }
    }

    /// The solver's name on the command line and in scene files: `cg`, `cholesky`, `two-level` or
    /// `aggregation`.
    pub fn name(&self) -> &'static str {
        match self {
            LinearSolver::ConjugateGradient { .. } => "cg",
            #[cfg(feature = "sparse-cholesky")]
            LinearSolver::SparseCholesky => "cholesky",
            #[cfg(feature = "sparse-cholesky")]
            LinearSolver::TwoLevel { .. } => "two-level",
            #[cfg(feature = "sparse-cholesky")]
            LinearSolver::RigidAggregation { .. } => "aggregation",
        }
    }

    /// Whether the solver reads the matrix's blocks (a factorisation or a preconditioner built from
    /// them), or only multiplies by the matrix and inverts its diagonal blocks.
    pub(crate) fn needs_blocks(&self) -> bool {
        match self {
            LinearSolver::ConjugateGradient { .. } => false,
            #[cfg(feature = "sparse-cholesky")]
            LinearSolver::RigidAggregation { .. } => false,
            #[cfg(feature = "sparse-cholesky")]
            LinearSolver::SparseCholesky | LinearSolver::TwoLevel { .. } => true,
        }
    }
}

impl std::str::FromStr for LinearSolver {
    type Err = String;

    /// `cg`, `two-level` or `aggregation` (their default tolerances) or `cholesky`.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "cg" => Ok(LinearSolver::default_cg()),
            #[cfg(feature = "sparse-cholesky")]
            "cholesky" => Ok(LinearSolver::SparseCholesky),
            #[cfg(feature = "sparse-cholesky")]
            "two-level" => Ok(LinearSolver::default_two_level()),
            #[cfg(feature = "sparse-cholesky")]
            "aggregation" => Ok(LinearSolver::default_aggregation()),
            _ => Err(format!(
                "unknown linear solver `{s}`; expected `cg`, `cholesky`, `two-level` or `aggregation`"
            )),
        }
    }
}
