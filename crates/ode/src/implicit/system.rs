//! The linear system of an implicit step, A = M − β_v D − β_x K, stored as blocks on the Jacobian
//! pattern; its product with a vector; and the filter that keeps constrained directions out of it.

#![allow(
    clippy::needless_range_loop,
    reason = "the loops walk several per-coordinate arrays in step; the index form mirrors the formulas"
)]

use crate::Coord;
use crate::parallel::{self, Scatter};

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
    /// The pattern's pairs split over the threads ([`Self::mul`] on every core, the serial product's
    /// bits).
    pub scatter: Scatter,
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
            scatter: Scatter::new(),
        }
    }

    /// Sets the sizes for `n` coordinates and the pattern's pairs, and splits the pairs over the
    /// threads; allocates only when the sizes grow or the pattern changed.
    pub fn resize(&mut self, n: usize, pattern: &[(u32, u32)]) {
        let z = C::block_identity(0.0);
        self.diag.resize(n, z);
        self.jacobi.resize(n, z);
        self.off.resize(pattern.len(), z);
        self.scatter.prepare(n, pattern.len(), |e| [pattern[e].0, pattern[e].1]);
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
    /// the diagonal and inverts the diagonal blocks; in spring form the diagonal's scalar part is the
    /// mass plus `extra` ([`super::Linearized::spring_form_diagonal`], which the blocks already hold).
    pub fn add_masses(&mut self, masses: &[f64], extra: &[f64]) {
        let (diag, jacobi) = (&mut self.diag, &mut self.jacobi);
        parallel::for_chunks2(diag, jacobi, |s, diag, jacobi| {
            for (k, (a, j)) in diag.iter_mut().zip(jacobi.iter_mut()).enumerate() {
                *a = C::block_combine(*a, 1.0, C::block_identity(masses[s + k]), 1.0);
                *j = C::block_inverse(*a);
            }
        });
        if self.spring_form {
            self.masses.clear();
            self.masses.extend(masses.iter().zip(extra).map(|(m, e)| m + e));
        }
    }

    /// Adds `d` I to coordinate i's diagonal block (a contact's friction as damping, already times η).
    pub fn add_diagonal(&mut self, i: usize, d: f64) {
        self.diag[i] = C::block_combine(self.diag[i], 1.0, C::block_identity(d), 1.0);
        self.jacobi[i] = C::block_inverse(self.diag[i]);
        if self.spring_form {
            self.masses[i] += d;
        }
    }

    /// Makes the block-Jacobi inverses those of the filtered system S A S for every coordinate whose
    /// projector S_i is neither the identity nor zero (a contact constrains one direction of it):
    /// J_i = S_i (S_i A_ii S_i + t (I − S_i))⁻¹ S_i, the inverse of A_ii on the free directions (t sets
    /// the constrained directions apart and drops out). S_i A_ii⁻¹ S_i, the unfiltered inverse
    /// projected, is a poor stand-in when A_ii is stiff along a direction that leans on the contact
    /// normal.
    pub fn filter_jacobi(&mut self, filter: Filter<'_, C>) {
        let Filter::Projected(s) = filter else { return };
        let identity = C::block_identity(1.0);
        let zero = C::block_identity(0.0);
        let same = |a: C::Block, b: C::Block| {
            (0..C::DIM).all(|r| (0..C::DIM).all(|c| C::block_entry(a, r, c) == C::block_entry(b, r, c)))
        };
        for (i, &si) in s.iter().enumerate() {
            if same(si, identity) || same(si, zero) {
                continue;
            }
            let a = self.diag[i];
            let t = (0..C::DIM).map(|k| C::block_entry(a, k, k).abs()).sum::<f64>() / C::DIM as f64;
            let sas = C::block_mul_blocks(C::block_mul_blocks(si, a), si);
            let shifted = C::block_combine(sas, 1.0, C::block_combine(identity, t, si, -t), 1.0);
            self.jacobi[i] = C::block_mul_blocks(C::block_mul_blocks(si, C::block_inverse(shifted)), si);
        }
    }

    /// y = A x, then filtered: on every core for large systems ([`Scatter`]), with the serial
    /// product's bits.
    pub fn mul(&self, pattern: &[(u32, u32)], filter: Filter<'_, C>, x: &[C], y: &mut [C]) {
        self.scatter.run(y, |range, pairs, y| {
            let s = range.start;
            if self.spring_form {
                // y_i = m_i x_i + Σ_e B_e (x_i − x_j), and its negative at j.
                for i in range.clone() {
                    y[i - s] = x[i] * self.masses[i];
                }
                for &e in pairs {
                    let SpringBlock { i, j, u, a } = self.springs[e as usize];
                    let (i, j) = (i as usize, j as usize);
                    let d = x[i] - x[j];
                    let b = u * u.dot(d) + d * a;
                    if range.contains(&i) {
                        y[i - s] += b;
                    }
                    if range.contains(&j) {
                        y[j - s] = y[j - s] - b;
                    }
                }
            } else {
                for i in range.clone() {
                    y[i - s] = C::block_mul(self.diag[i], x[i]);
                }
                for &e in pairs {
                    let e = e as usize;
                    let (i, j) = (pattern[e].0 as usize, pattern[e].1 as usize);
                    if range.contains(&i) {
                        y[i - s] += C::block_mul(self.off[e], x[j]);
                    }
                    if range.contains(&j) {
                        y[j - s] += C::block_mul_transpose(self.off[e], x[i]);
                    }
                }
            }
            for i in range {
                y[i - s] = filter.one(i, y[i - s]);
            }
        });
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
