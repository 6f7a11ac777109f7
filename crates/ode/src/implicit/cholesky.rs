//! The direct solver of the implicit steps: the block system A Δv = b assembled as a scalar sparse matrix
//! (upper triangle, compressed columns) and factorised by faer's sparse Cholesky.
//!
//! Why a direct solver beside conjugate gradients: CG's cost grows with the condition number of A, which
//! grows with h²·k/m — exactly the stiff cloth and large steps implicit Euler is for. A sparse LLᵀ costs
//! the same whatever the stiffness, and its symbolic part (ordering, elimination tree, supernodes) depends
//! only on the sparsity pattern, so it is computed once and reused while the topology stays the same;
//! each step pays the numeric factorisation and two triangular solves.
//!
//! Prescribed coordinates are eliminated without changing the pattern: their rows and columns are
//! zeroed and their diagonal set to one, with a zero right-hand side, so Δv = 0 there exactly and the
//! symbolic factorisation survives a particle being pinned or released.
//!
//! When A is not numerically positive definite (a [`Linearized`](crate::Linearized) system that breaks
//! its promise of negative semi-definite Jacobians), LLᵀ fails and the step falls back to LDLᵀ on the
//! same symbolic factorisation, which needs only non-zero pivots.

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMat, Triplet};
use faer::{Conj, MatMut, Par, Side};

use crate::Coord;

use super::system::Filter;

/// No slot: an entry of a diagonal block below its diagonal (only the upper triangle is stored).
const NONE: usize = usize::MAX;

/// Which factorisation a solve used.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Factorization {
    /// LLᵀ: A was positive definite.
    Cholesky,
    /// LDLᵀ, after LLᵀ met a non-positive pivot.
    Ldlt,
}

/// Assembly map, symbolic factorisation and every buffer of the direct solve, kept between steps.
pub(crate) struct SparseSolver {
    /// The block pattern the structure was built for; a different one rebuilds it.
    pattern: Vec<(u32, u32)>,
    n_blocks: usize,
    matrix: SparseColMat<usize, f64>,
    /// Per diagonal block, DIM² value slots (row-major within the block; `NONE` below the diagonal).
    diag_slots: Vec<usize>,
    /// Per pattern pair, DIM² value slots (row-major within the block).
    off_slots: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    buffer: MemBuffer,
    rhs: Vec<f64>,
    /// Scalar size of a block (`C::DIM` of the coordinates it was built for).
    dim: usize,
    /// The kind of the last numeric factorisation.
    kind: Factorization,
}

/// Right-hand sides one call to [`SparseSolver::solve_in_place`] may solve at once.
pub(crate) const MAX_RHS: usize = 3;

impl std::fmt::Debug for SparseSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseSolver")
            .field("n_blocks", &self.n_blocks)
            .field("pairs", &self.pattern.len())
            .field("factor_len", &self.l_values.len())
            .finish_non_exhaustive()
    }
}

/// Why the direct solve failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SparseSolveError {
    #[error("sparse factorisation: {0}")]
    Factorization(String),
}

impl SparseSolver {
    /// Builds the scalar structure for `n_blocks` blocks of size `C::DIM` coupled by `pattern`, and its
    /// symbolic factorisation (approximate minimum degree ordering).
    pub fn new<C: Coord>(n_blocks: usize, pattern: &[(u32, u32)]) -> Result<Self, SparseSolveError> {
        Self::with_layout::<C>(n_blocks, pattern, false)
    }

    /// Like [`SparseSolver::new`], with a simplicial factor when `simplicial` (one column of L at a time,
    /// which [`SparseSolver::lower_factor`] can copy out).
    pub fn with_layout<C: Coord>(
        n_blocks: usize,
        pattern: &[(u32, u32)],
        simplicial: bool,
    ) -> Result<Self, SparseSolveError> {
        let d = C::DIM;
        let size = n_blocks * d;
        let mut triplets = Vec::with_capacity(n_blocks * d * (d + 1) / 2 + pattern.len() * d * d);
        for i in 0..n_blocks {
            for r in 0..d {
                for c in r..d {
                    triplets.push(Triplet::new(d * i + r, d * i + c, 0.0));
                }
            }
        }
        for &(i, j) in pattern {
            let (i, j) = (i as usize, j as usize);
            debug_assert!(i < j && j < n_blocks, "pattern pairs are (i, j) with i < j < n");
            for r in 0..d {
                for c in 0..d {
                    triplets.push(Triplet::new(d * i + r, d * j + c, 0.0));
                }
            }
        }
        let err = |e: &dyn std::fmt::Debug| SparseSolveError::Factorization(format!("{e:?}"));
        let matrix =
            SparseColMat::<usize, f64>::try_new_from_triplets(size, size, &triplets).map_err(|e| err(&e))?;
        let (col_ptr, row_idx) = (matrix.symbolic().col_ptr(), matrix.symbolic().row_idx());
        let slot = |row: usize, col: usize| -> usize {
            let rows = &row_idx[col_ptr[col]..col_ptr[col + 1]];
            col_ptr[col] + rows.binary_search(&row).expect("every assembled entry is in the structure")
        };
        let mut diag_slots = vec![NONE; n_blocks * d * d];
        for i in 0..n_blocks {
            for r in 0..d {
                for c in r..d {
                    diag_slots[(i * d + r) * d + c] = slot(d * i + r, d * i + c);
                }
            }
        }
        let mut off_slots = vec![NONE; pattern.len() * d * d];
        for (e, &(i, j)) in pattern.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            for r in 0..d {
                for c in 0..d {
                    off_slots[(e * d + r) * d + c] = slot(d * i + r, d * j + c);
                }
            }
        }
        // Supernodal always: the 3 × 3 blocks of a cloth make dense supernodes, and faer's automatic
        // choice picked the simplicial factorisation, measured 4–5 times slower per step on a 17 × 17
        // cloth (867 unknowns).
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: if simplicial {
                SupernodalThreshold::FORCE_SIMPLICIAL
            } else {
                SupernodalThreshold::FORCE_SUPERNODAL
            },
            ..Default::default()
        };
        let symbolic =
            factorize_symbolic_cholesky(matrix.symbolic(), Side::Upper, SymmetricOrdering::Amd, params)
                .map_err(|e| err(&e))?;
        let par = Par::Seq;
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()),
            symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(MAX_RHS, par),
        ]);
        let buffer = MemBuffer::try_new(req).map_err(|e| err(&e))?;
        Ok(Self {
            pattern: pattern.to_vec(),
            n_blocks,
            l_values: vec![0.0; symbolic.len_val()],
            matrix,
            diag_slots,
            off_slots,
            symbolic,
            buffer,
            rhs: vec![0.0; size],
            dim: d,
            kind: Factorization::Cholesky,
        })
    }

    /// Whether this structure was built for `n_blocks` blocks and this `pattern`.
    pub fn fits(&self, n_blocks: usize, pattern: &[(u32, u32)]) -> bool {
        self.n_blocks == n_blocks && self.pattern == pattern
    }

    /// Solves A Δv = b for the block matrix with diagonal `a_diag` and off-diagonal blocks `a_off` on
    /// the pattern, filtered: S A S + (I − S) is factorised, so Δv has no component outside the free
    /// directions (`b` must already be filtered).
    pub fn solve<C: Coord>(
        &mut self,
        a_diag: &[C::Block],
        a_off: &[C::Block],
        filter: Filter<'_, C>,
        b: &[C],
        dv: &mut [C],
    ) -> Result<Factorization, SparseSolveError> {
        let kind = self.factorize::<C>(a_diag, a_off, filter)?;
        let d = C::DIM;
        for (i, bi) in b.iter().enumerate() {
            for k in 0..d {
                self.rhs[i * d + k] = bi.component(k);
            }
        }
        let mut rhs = std::mem::take(&mut self.rhs);
        self.solve_in_place(&mut rhs, 1);
        self.rhs = rhs;
        for (i, v) in dv.iter_mut().enumerate() {
            for k in 0..d {
                v.set_component(k, self.rhs[i * d + k]);
            }
        }
        Ok(kind)
    }

    /// Assembles and factorises the filtered matrix S A S + (I − S) (numeric factorisation on the kept
    /// symbolic one): LLᵀ, or LDLᵀ when it is not numerically positive definite. A prescribed
    /// coordinate's rows and columns become those of the identity.
    pub fn factorize<C: Coord>(
        &mut self,
        a_diag: &[C::Block],
        a_off: &[C::Block],
        filter: Filter<'_, C>,
    ) -> Result<Factorization, SparseSolveError> {
        let d = C::DIM;
        let values = self.matrix.val_mut();
        values.fill(0.0);
        let identity = C::block_identity(1.0);
        // S_i, and whether it is the identity (most coordinates), so the common case costs no products.
        let projector = |i: usize| -> (C::Block, bool) {
            match filter {
                Filter::None => (identity, true),
                Filter::Prescribed(fixed) => {
                    if fixed[i] {
                        (C::block_identity(0.0), false)
                    } else {
                        (identity, true)
                    }
                }
                Filter::Projected(s) => (s[i], false),
            }
        };
        for (i, &block) in a_diag.iter().enumerate() {
            let (s, free) = projector(i);
            // S A S + (I − S), the identity on the constrained directions.
            let filtered = if free {
                block
            } else {
                let sas = C::block_mul_blocks(s, C::block_mul_blocks(block, s));
                C::block_combine(sas, 1.0, C::block_combine(identity, 1.0, s, -1.0), 1.0)
            };
            for r in 0..d {
                for c in r..d {
                    values[self.diag_slots[(i * d + r) * d + c]] += C::block_entry(filtered, r, c);
                }
            }
        }
        for (e, (&(i, j), &block)) in self.pattern.iter().zip(a_off).enumerate() {
            let ((si, free_i), (sj, free_j)) = (projector(i as usize), projector(j as usize));
            let filtered = match (free_i, free_j) {
                (true, true) => block,
                _ => C::block_mul_blocks(si, C::block_mul_blocks(block, sj)),
            };
            for r in 0..d {
                for c in 0..d {
                    values[self.off_slots[(e * d + r) * d + c]] += C::block_entry(filtered, r, c);
                }
            }
        }
        let par = Par::Seq;
        let stack = MemStack::new(&mut self.buffer);
        let positive_definite = self
            .symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.l_values,
                self.matrix.as_ref(),
                Side::Upper,
                LltRegularization::default(),
                par,
                stack,
                Default::default(),
            )
            .is_ok();
        if !positive_definite {
            self.symbolic
                .factorize_numeric_ldlt::<f64>(
                    &mut self.l_values,
                    self.matrix.as_ref(),
                    Side::Upper,
                    LdltRegularization::default(),
                    par,
                    stack,
                    Default::default(),
                )
                .map_err(|e| SparseSolveError::Factorization(format!("{e:?}")))?;
        }
        self.kind = if positive_definite { Factorization::Cholesky } else { Factorization::Ldlt };
        Ok(self.kind)
    }

    /// Solves in place for `n_rhs` right-hand sides stored column after column in `rhs` (each of the
    /// matrix's scalar size), with the last factorisation.
    pub fn solve_in_place(&mut self, rhs: &mut [f64], n_rhs: usize) {
        let size = self.n_blocks * self.dim;
        debug_assert!(n_rhs <= MAX_RHS && rhs.len() == size * n_rhs);
        let par = Par::Seq;
        let stack = MemStack::new(&mut self.buffer);
        let rhs = MatMut::from_column_major_slice_mut(rhs, size, n_rhs);
        match self.kind {
            Factorization::Cholesky => LltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                par,
                stack,
            ),
            Factorization::Ldlt => LdltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
                Conj::No,
                rhs,
                par,
                stack,
            ),
        }
    }
}

impl SparseSolver {
    /// The last LLᵀ factorisation as a [`LowerFactor`], when it was simplicial and positive definite.
    pub fn lower_factor(&self) -> Option<LowerFactor> {
        use faer::sparse::linalg::cholesky::SymbolicCholeskyRaw;
        let SymbolicCholeskyRaw::Simplicial(simplicial) = self.symbolic.raw() else {
            return None;
        };
        if self.kind != Factorization::Cholesky {
            return None;
        }
        let n = simplicial.nrows();
        let (col_ptr, row_idx) = (simplicial.col_ptr(), simplicial.row_idx());
        let fwd: Vec<u32> = match self.symbolic.perm() {
            Some(p) => p.arrays().0.iter().map(|&i| i as u32).collect(),
            None => (0..n as u32).collect(),
        };
        let mut f = LowerFactor {
            fwd,
            inv_diag: Vec::with_capacity(n),
            col_ptr: Vec::with_capacity(n + 1),
            row_idx: Vec::with_capacity(row_idx.len()),
            values: Vec::with_capacity(row_idx.len()),
            work: vec![[0.0; 3]; n],
        };
        f.col_ptr.push(0);
        for j in 0..n {
            let (start, end) = (col_ptr[j], col_ptr[j + 1]);
            if end == start || row_idx[start] != j {
                return None;
            }
            f.inv_diag.push(1.0 / self.l_values[start]);
            for (&i, &l) in row_idx[start + 1..end].iter().zip(&self.l_values[start + 1..end]) {
                f.row_idx.push(i as u32);
                f.values.push(l);
            }
            f.col_ptr.push(f.row_idx.len() as u32);
        }
        Some(f)
    }
}

/// A sparse Cholesky factor L (P A Pᵀ = L Lᵀ) copied out of faer's simplicial factorisation, solved by
/// hand for three right-hand sides at once: each entry of L is loaded once and applied to the three
/// components together, where faer's solve sweeps L once per right-hand side.
#[derive(Debug, Clone)]
pub(crate) struct LowerFactor {
    /// Permuted index k holds original index `fwd[k]`.
    fwd: Vec<u32>,
    inv_diag: Vec<f64>,
    /// Strictly lower entries, column by column.
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    values: Vec<f64>,
    work: Vec<[f64; 3]>,
}

impl LowerFactor {
    /// Solves A y = r for the three components of every entry of `r` (a block of three right-hand sides,
    /// one per Cartesian component), into `y`.
    pub fn solve3(&mut self, r: &[[f64; 3]], y: &mut [[f64; 3]]) {
        let n = self.inv_diag.len();
        let w = &mut self.work;
        for k in 0..n {
            w[k] = r[self.fwd[k] as usize];
        }
        // L z = w, by columns.
        for j in 0..n {
            let d = self.inv_diag[j];
            let z = [w[j][0] * d, w[j][1] * d, w[j][2] * d];
            w[j] = z;
            let (start, end) = (self.col_ptr[j] as usize, self.col_ptr[j + 1] as usize);
            for (&i, &l) in self.row_idx[start..end].iter().zip(&self.values[start..end]) {
                let t = &mut w[i as usize];
                t[0] -= l * z[0];
                t[1] -= l * z[1];
                t[2] -= l * z[2];
            }
        }
        // Lᵀ y = z, by columns of L (rows of Lᵀ).
        for j in (0..n).rev() {
            let mut s = w[j];
            let (start, end) = (self.col_ptr[j] as usize, self.col_ptr[j + 1] as usize);
            for (&i, &l) in self.row_idx[start..end].iter().zip(&self.values[start..end]) {
                let t = w[i as usize];
                s[0] -= l * t[0];
                s[1] -= l * t[1];
                s[2] -= l * t[2];
            }
            let d = self.inv_diag[j];
            w[j] = [s[0] * d, s[1] * d, s[2] * d];
        }
        for k in 0..n {
            y[self.fwd[k] as usize] = w[k];
        }
    }
}

/// The direct solver as a cache: built on first use, rebuilt when the pattern changes. A clone starts
/// empty (the factorisation is a cache of the matrix, not state), so a cloned stepper steps identically.
#[derive(Debug, Default)]
pub(crate) struct DirectCache(pub Option<SparseSolver>);

impl Clone for DirectCache {
    fn clone(&self) -> Self {
        DirectCache(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hand-written three-component solve gives faer's answer, prescribed rows included.
    #[test]
    fn lower_factor_solves_like_faer() {
        // A 6 × 6 grid Laplacian plus a mass, one coordinate prescribed.
        let side = 6usize;
        let n = side * side;
        let mut pattern = Vec::new();
        for r in 0..side {
            for c in 0..side {
                let i = (r * side + c) as u32;
                if c + 1 < side {
                    pattern.push((i, i + 1));
                }
                if r + 1 < side {
                    pattern.push((i, i + side as u32));
                }
            }
        }
        let off: Vec<f64> = (0..pattern.len()).map(|e| -1.0 - 0.1 * (e % 3) as f64).collect();
        let mut diag = vec![0.5; n];
        for (e, &(i, j)) in pattern.iter().enumerate() {
            diag[i as usize] -= off[e];
            diag[j as usize] -= off[e];
        }
        let mut fixed = vec![false; n];
        fixed[7] = true;
        let mut solver = SparseSolver::with_layout::<f64>(n, &pattern, true).expect("structure");
        solver.factorize::<f64>(&diag, &off, Filter::Prescribed(&fixed)).expect("factor");
        let mut fast = solver.lower_factor().expect("simplicial LLᵀ");
        let r: Vec<[f64; 3]> = (0..n)
            .map(|i| if fixed[i] { [0.0; 3] } else { [i as f64, 1.0, (i * i) as f64 * 0.01] })
            .collect();
        let mut y = vec![[0.0; 3]; n];
        fast.solve3(&r, &mut y);
        let mut rhs: Vec<f64> = (0..3).flat_map(|k| r.iter().map(move |v| v[k])).collect();
        solver.solve_in_place(&mut rhs, 3);
        for i in 0..n {
            for k in 0..3 {
                let want = rhs[k * n + i];
                assert!(
                    (y[i][k] - want).abs() <= 1e-12 * (1.0 + want.abs()),
                    "({i}, {k}): {} vs {want}",
                    y[i][k]
                );
            }
        }
    }
}
