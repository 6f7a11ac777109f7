//! A two-level preconditioner for A = M − β_v D − β_x K that keeps one sparse factorisation across
//! Newton iterations and steps.
//!
//! Why: for a stiff cloth at large steps the system is dominated by its springs, β_x k/m ≈ 2 000 on the
//! standard sheet at 1/60 s, so block-Jacobi CG needs about a hundred iterations per solve, and a sparse
//! Cholesky of A costs a fresh numeric factorisation at every Newton iteration (18 ms on that sheet,
//! 2.1 million entries in L). A factorisation of a *stale* A is no cure: its spring directions are those
//! of another state, and A⁻¹ amplifies a direction error θ by about β_x k θ/m, so a chord iteration with
//! it diverges after a few hundredths of a radian of rotation (measured).
//!
//! The coarse level here is what projective dynamics (Bouaziz et al. 2014) and Liu et al. (2013, "Fast
//! simulation of mass-spring systems") factorise once: the isotropic matrix
//!
//! Ŝ = M + Σ_(i,j) w_ij (e_i − e_j)(e_i − e_j)ᵀ,   w_ij = −tr(A_ij)/2,
//!
//! one scalar per particle, applied to each Cartesian component. It does not depend on the springs'
//! directions, only on their stiffness (−tr A_ij = β_x k (1 + 2g) + β_v c for a spring; half of it is
//! the in-plane stiffness k nnᵀ of a sheet, averaged over directions), so one factorisation serves
//! while the cloth swings, folds and rotates. It is refreshed only when Δt, the masses or the pattern
//! change, or when the stiffness a particle sees drifts by more than half from what was factorised (a
//! tension-only spring going slack or taut, for instance). Couplings much weaker than their
//! neighbours' strongest (the standard sheet's 10 N/m bend springs beside 1 000 N/m structural ones)
//! are left out of Ŝ, which halves the factor.
//!
//! Ŝ overestimates what the springs resist across their directions, so alone it is a poor
//! preconditioner for a cloth's soft, out-of-plane motion; block-Jacobi smoothing on the exact A
//! handles that part. One application is the symmetric multiplicative two-level cycle
//!
//! z₁ = ω J⁻¹ r,   z₂ = z₁ + Ŝ⁻¹(r − A z₁),   z = z₂ + ω J⁻¹(r − A z₂),
//!
//! J the diagonal blocks of A, ω = 0.7, everything filtered. Measured on the standard sheet (N = 64,
//! 1/60 s, generalised-α): about 12 CG iterations per solve to a relative residual of 10⁻², against
//! about 95 with block Jacobi alone, and 6 to the default 10⁻¹. An application costs two products with
//! A and one solve with Ŝ's factor for three right-hand sides: Ŝ is factorised simplicially (1.1·10⁵
//! entries in L on that sheet) and solved by [`LowerFactor`], all three components in one sweep,
//! 0.22 ms, where faer's supernodal solve took 0.42 ms.
//!
//! Generalised-α's default is now [`super::aggregation`], whose coarse level also sees the directions
//! of the springs; this one stays for the systems where refactorising a coarse matrix at every step is
//! not wanted.

#![allow(
    clippy::needless_range_loop,
    reason = "the loops walk several per-coordinate arrays in step; the index form mirrors the formulas"
)]

use crate::Coord;

use super::cg::Preconditioner;
use super::cholesky::{LowerFactor, MAX_RHS, SparseSolver};
use super::system::{Filter, SystemMatrix};

/// A coupling is left out of Ŝ when its weight is below this fraction of the strongest weight at
/// either of its ends.
const DROP_RATIO: f64 = 0.05;

/// The damping ω of the block-Jacobi smoothing steps, z += ω J⁻¹ (r − A z). Measured on the standard
/// sheet (N = 64, 1/60 s, four Newton iterations): ω = 1 took 1 830 CG iterations, 0.8 took 1 552, 0.7
/// took 1 496 and 0.6 took 1 558; undamped Jacobi overshoots the stiff springs' modes, which the coarse
/// level then has to undo.
const SMOOTHING: f64 = 0.7;

/// Ŝ is refactorised when some particle's diagonal Σ_j w_ij + m_i differs from the factorised one by
/// more than this fraction.
const DRIFT: f64 = 0.5;

/// The kept factorisation and the scratch of one application.
#[derive(Debug)]
pub(crate) struct TwoLevel<C: Coord> {
    /// What the structure was built for: particles, pattern pairs, and the pattern itself.
    pattern: Vec<(u32, u32)>,
    /// Indices (into the block pattern) of the couplings kept in Ŝ.
    kept: Vec<u32>,
    solver: Option<SparseSolver>,
    /// The factor copied out of `solver` for the three-component solve (when its LLᵀ succeeded).
    fast: Option<LowerFactor>,
    /// Residual and solution of the three-component solve.
    r3: Vec<[f64; 3]>,
    y3: Vec<[f64; 3]>,
    /// Ŝ's diagonal and off-diagonal values as factorised.
    s_diag: Vec<f64>,
    s_off: Vec<f64>,
    /// The diagonal the current A implies (for the drift test).
    diag_now: Vec<f64>,
    /// Masses the factorisation was made with.
    masses: Vec<f64>,
    /// Particles whose velocity is prescribed, eliminated from Ŝ.
    fixed: Vec<bool>,
    rhs: Vec<f64>,
    az: Vec<C>,
    t: Vec<C>,
    /// Numeric factorisations so far (symbolic ones counted in `rebuilds`).
    pub refactorizations: usize,
    pub rebuilds: usize,
}

impl<C: Coord> Default for TwoLevel<C> {
    fn default() -> Self {
        Self {
            pattern: Vec::new(),
            kept: Vec::new(),
            solver: None,
            fast: None,
            r3: Vec::new(),
            y3: Vec::new(),
            s_diag: Vec::new(),
            s_off: Vec::new(),
            diag_now: Vec::new(),
            masses: Vec::new(),
            fixed: Vec::new(),
            rhs: Vec::new(),
            az: Vec::new(),
            t: Vec::new(),
            refactorizations: 0,
            rebuilds: 0,
        }
    }
}

/// The coupling weight w = −tr(A_ij)/2 of a pair (for scalar coordinates, −A_ij).
fn weight<C: Coord>(block: C::Block) -> f64 {
    let trace: f64 = (0..C::DIM).map(|k| C::block_entry(block, k, k)).sum();
    let w = if C::DIM == 1 { -trace } else { -0.5 * trace };
    w.max(0.0)
}

impl<C: Coord> TwoLevel<C> {
    /// Makes Ŝ fit the current A: rebuilds the structure when the pattern, the masses or the prescribed
    /// set changed, refactorises when the stiffness drifted; otherwise keeps the factorisation.
    pub fn update(
        &mut self,
        a: &SystemMatrix<C>,
        pattern: &[(u32, u32)],
        masses: &[f64],
        prescribed: &[bool],
    ) -> Result<(), String> {
        let n = masses.len();
        if self.solver.is_none() && !self.s_diag.is_empty() {
            // A clone: factorise the values it carried, so that it steps as the original would.
            self.factorize_stored()?;
        }
        let same_structure = self.solver.is_some()
            && self.pattern == pattern
            && self.masses == masses
            && self.fixed == prescribed;
        if !same_structure {
            self.rebuild(a, pattern, masses, prescribed)?;
            return Ok(());
        }
        // Drift test on the diagonal: m_i + Σ_j w_ij over every coupling, kept or not.
        self.diag_now.clear();
        self.diag_now.extend_from_slice(masses);
        for (e, &(i, j)) in pattern.iter().enumerate() {
            let w = weight::<C>(a.off[e]);
            self.diag_now[i as usize] += w;
            self.diag_now[j as usize] += w;
        }
        let drifted = (0..n)
            .any(|i| !prescribed[i] && (self.diag_now[i] - self.s_diag[i]).abs() > DRIFT * self.s_diag[i]);
        if drifted {
            self.refactorize(a)?;
        }
        Ok(())
    }

    fn rebuild(
        &mut self,
        a: &SystemMatrix<C>,
        pattern: &[(u32, u32)],
        masses: &[f64],
        prescribed: &[bool],
    ) -> Result<(), String> {
        let n = masses.len();
        self.pattern.clear();
        self.pattern.extend_from_slice(pattern);
        self.masses.clear();
        self.masses.extend_from_slice(masses);
        self.fixed.clear();
        self.fixed.extend_from_slice(prescribed);
        let mut strongest = vec![0.0f64; n];
        for (e, &(i, j)) in pattern.iter().enumerate() {
            let w = weight::<C>(a.off[e]);
            strongest[i as usize] = strongest[i as usize].max(w);
            strongest[j as usize] = strongest[j as usize].max(w);
        }
        self.kept.clear();
        let mut scalar_pattern = Vec::new();
        for (e, &(i, j)) in pattern.iter().enumerate() {
            let w = weight::<C>(a.off[e]);
            let limit = DROP_RATIO * strongest[i as usize].max(strongest[j as usize]);
            if w > 0.0 && w >= limit {
                self.kept.push(e as u32);
                scalar_pattern.push((i, j));
            }
        }
        self.solver =
            Some(SparseSolver::with_layout::<f64>(n, &scalar_pattern, true).map_err(|e| e.to_string())?);
        self.rhs.resize(n * C::DIM, 0.0);
        self.az.resize(n, C::default());
        self.t.resize(n, C::default());
        self.rebuilds += 1;
        self.refactorize(a)
    }

    /// Ŝ from the current A: the kept couplings off the diagonal, every coupling (kept or dropped) on it,
    /// so that Ŝ's diagonal matches the stiffness A gives each particle.
    fn refactorize(&mut self, a: &SystemMatrix<C>) -> Result<(), String> {
        self.s_diag.clear();
        self.s_diag.extend_from_slice(&self.masses);
        for (e, &(i, j)) in self.pattern.iter().enumerate() {
            let w = weight::<C>(a.off[e]);
            self.s_diag[i as usize] += w;
            self.s_diag[j as usize] += w;
        }
        self.s_off.clear();
        for &e in &self.kept {
            self.s_off.push(-weight::<C>(a.off[e as usize]));
        }
        self.refactorizations += 1;
        self.factorize_stored()
    }

    /// Factorises the stored Ŝ (building the symbolic structure first if a clone left it out).
    fn factorize_stored(&mut self) -> Result<(), String> {
        if self.solver.is_none() {
            let scalar_pattern: Vec<(u32, u32)> =
                self.kept.iter().map(|&e| self.pattern[e as usize]).collect();
            let n = self.masses.len();
            self.solver =
                Some(SparseSolver::with_layout::<f64>(n, &scalar_pattern, true).map_err(|e| e.to_string())?);
        }
        let solver = self.solver.as_mut().expect("built above");
        solver
            .factorize::<f64>(&self.s_diag, &self.s_off, Filter::Prescribed(&self.fixed))
            .map_err(|e| e.to_string())?;
        self.fast = solver.lower_factor();
        Ok(())
    }

    /// z = (Ŝ⁻¹ ⊗ I) r for every component, filtered.
    fn coarse(&mut self, filter: Filter<'_, C>, r: &[C], z: &mut [C]) {
        let n = r.len();
        let d = C::DIM;
        debug_assert!(d <= MAX_RHS);
        if let Some(fast) = &mut self.fast {
            self.r3.resize(n, [0.0; 3]);
            self.y3.resize(n, [0.0; 3]);
            for i in 0..n {
                for k in 0..d {
                    self.r3[i][k] = r[i].component(k);
                }
            }
            fast.solve3(&self.r3, &mut self.y3);
            for i in 0..n {
                let mut y = C::default();
                for k in 0..d {
                    y.set_component(k, self.y3[i][k]);
                }
                z[i] = filter.one(i, y);
            }
            return;
        }
        for i in 0..n {
            for k in 0..d {
                self.rhs[k * n + i] = r[i].component(k);
            }
        }
        self.solver.as_mut().expect("updated before use").solve_in_place(&mut self.rhs, d);
        for i in 0..n {
            let mut y = C::default();
            for k in 0..d {
                y.set_component(k, self.rhs[k * n + i]);
            }
            z[i] = filter.one(i, y);
        }
    }
}

impl<C: Coord> Preconditioner<C> for TwoLevel<C> {
    fn apply(
        &mut self,
        a: &SystemMatrix<C>,
        pattern: &[(u32, u32)],
        filter: Filter<'_, C>,
        r: &[C],
        z: &mut [C],
    ) {
        let n = r.len();
        let mut az = std::mem::take(&mut self.az);
        let mut t = std::mem::take(&mut self.t);
        // Pre-smoothing (damped block Jacobi from z = 0).
        for i in 0..n {
            z[i] = filter.one(i, C::block_mul(a.jacobi[i], r[i])) * SMOOTHING;
        }
        // Coarse correction of the remaining residual.
        a.mul(pattern, filter, z, &mut az);
        for i in 0..n {
            az[i] = r[i] - az[i];
        }
        self.coarse(filter, &az, &mut t);
        for i in 0..n {
            z[i] += t[i];
        }
        // Post-smoothing.
        a.mul(pattern, filter, z, &mut az);
        for i in 0..n {
            z[i] += filter.one(i, C::block_mul(a.jacobi[i], r[i] - az[i])) * SMOOTHING;
        }
        self.az = az;
        self.t = t;
    }
}

/// A clone carries Ŝ's values but not faer's factor (which cannot be cloned): it factorises the same
/// values again before its first use, so a cloned stepper steps exactly as the original.
impl<C: Coord> Clone for TwoLevel<C> {
    fn clone(&self) -> Self {
        Self {
            pattern: self.pattern.clone(),
            kept: self.kept.clone(),
            solver: None,
            fast: None,
            r3: Vec::new(),
            y3: Vec::new(),
            s_diag: self.s_diag.clone(),
            s_off: self.s_off.clone(),
            diag_now: Vec::new(),
            masses: self.masses.clone(),
            fixed: self.fixed.clone(),
            rhs: self.rhs.clone(),
            az: self.az.clone(),
            t: self.t.clone(),
            refactorizations: self.refactorizations,
            rebuilds: self.rebuilds,
        }
    }
}
