//! The linear system of an implicit step, A = M − β_v D − β_x K, stored as blocks on the Jacobian
//! pattern; its product with a vector; and the filter that keeps constrained directions out of it.

#![allow(
    clippy::needless_range_loop,
    reason = "the loops walk several per-coordinate arrays in step; the index form mirrors the formulas"
)]

use crate::Coord;

use super::{Jacobians, SpringBlock};

/// A = M − β_v D − β_x K: one diagonal block per coordinate and one block A_ij per pattern pair (i < j)
/// (A_ji = A_ijᵀ), with the inverses of the diagonal blocks for block-Jacobi preconditioning.
#[derive(Debug, Clone)]
pub(crate) struct SystemMatrix<C: Coord> {
    pub diag: Vec<C::Block>,
    pub off: Vec<C::Block>,
    /// A_ii⁻¹ (or the inverse of its diagonal when A_ii is singular).
    pub jacobi: Vec<C::Block>,
    /// The pattern's pairs in spring form, off_e = −(u uᵀ + a I), when `spring_form`.
    pub springs: Vec<SpringBlock<C>>,
    /// The masses of the diagonal, when `spring_form`.
    pub masses: Vec<f64>,
    /// Whether `springs` and `masses` describe the matrix: A = M + Σ_e B_e (e_i − e_j)(e_i − e_j)ᵀ
    /// ([`super::Linearized::spring_form`]), and [`Self::mul`] multiplies from them.
    pub spring_form: bool,
}

impl<C: Coord> SystemMatrix<C> {
    pub fn new() -> Self {
        Self {
            diag: Vec::new(),
            off: Vec::new(),
            jacobi: Vec::new(),
            springs: Vec::new(),
            masses: Vec::new(),
            spring_form: false,
        }
    }

    /// Sets the sizes; allocates only when they grow.
    pub fn resize(&mut self, n: usize, n_pairs: usize) {
        let z = C::block_identity(0.0);
        self.diag.resize(n, z);
        self.jacobi.resize(n, z);
        self.off.resize(n_pairs, z);
    }

    /// A = M − β D − β₂ K from Jacobians (backward Euler and BDF2 pass β₂ = β²), and its block-Jacobi
    /// preconditioner.
    pub fn assemble(&mut self, jac: &Jacobians<C>, masses: &[f64], beta: f64, beta2: f64) {
        self.spring_form = false;
        for i in 0..masses.len() {
            let m = C::block_identity(masses[i]);
            let hd = C::block_combine(jac.d_diag[i], beta, jac.k_diag[i], beta2);
            self.diag[i] = C::block_combine(m, 1.0, hd, -1.0);
            self.jacobi[i] = C::block_inverse(self.diag[i]);
        }
        for e in 0..self.off.len() {
            self.off[e] = C::block_combine(jac.d_off[e], -beta, jac.k_off[e], -beta2);
        }
    }

    /// Completes a matrix whose blocks [`super::Linearized::force_and_system`] wrote: adds the masses to
    /// the diagonal and inverts the diagonal blocks.
    pub fn add_masses(&mut self, masses: &[f64]) {
        for ((a, j), &m) in self.diag.iter_mut().zip(self.jacobi.iter_mut()).zip(masses) {
            *a = C::block_combine(*a, 1.0, C::block_identity(m), 1.0);
            *j = C::block_inverse(*a);
        }
        if self.spring_form {
            self.masses.clear();
            self.masses.extend_from_slice(masses);
        }
    }

    /// y = A x, then filtered.
    pub fn mul(&self, pattern: &[(u32, u32)], filter: Filter<'_, C>, x: &[C], y: &mut [C]) {
        if self.spring_form {
            // y_i = m_i x_i + Σ_e B_e (x_i − x_j), and its negative at j.
            for i in 0..x.len() {
                y[i] = x[i] * self.masses[i];
            }
            for &SpringBlock { i, j, u, a } in &self.springs {
                let (i, j) = (i as usize, j as usize);
                let d = x[i] - x[j];
                let b = u * u.dot(d) + d * a;
                y[i] += b;
                y[j] = y[j] - b;
            }
            filter.apply(y);
            return;
        }
        for i in 0..x.len() {
            y[i] = C::block_mul(self.diag[i], x[i]);
        }
        for (e, &(i, j)) in pattern.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let (yi, yj) = (C::block_mul(self.off[e], x[j]), C::block_mul_transpose(self.off[e], x[i]));
            y[i] += yi;
            y[j] += yj;
        }
        filter.apply(y);
    }
}

/// Which directions of each coordinate the solve may change.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Filter<'a, C: Coord> {
    /// Every direction free.
    None,
    /// All directions of a free coordinate, none of a prescribed one.
    Prescribed(&'a [bool]),
    /// Per coordinate, the orthogonal projector S_i onto its free directions (Baraff & Witkin 1998,
    /// §5.3): I when free, I − n nᵀ when its velocity along n is constrained, 0 when it is fixed.
    Projected(&'a [C::Block]),
}

impl<C: Coord> Filter<'_, C> {
    /// y ← S y.
    pub fn apply(&self, y: &mut [C]) {
        match *self {
            Filter::None => {}
            Filter::Prescribed(fixed) => {
                for (y, &fixed) in y.iter_mut().zip(fixed) {
                    if fixed {
                        *y = C::default();
                    }
                }
            }
            Filter::Projected(s) => {
                for (y, &s) in y.iter_mut().zip(s) {
                    *y = C::block_mul(s, *y);
                }
            }
        }
    }

    /// S_i y_i for one coordinate.
    #[inline]
    pub fn one(&self, i: usize, y: C) -> C {
        match *self {
            Filter::None => y,
            Filter::Prescribed(fixed) => {
                if fixed[i] {
                    C::default()
                } else {
                    y
                }
            }
            Filter::Projected(s) => C::block_mul(s[i], y),
        }
    }
}
