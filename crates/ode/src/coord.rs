use std::fmt::Debug;
use std::ops::{Add, AddAssign, Mul, Sub};

use glam::{DMat3, DVec3};

/// A coordinate an integrator can combine linearly: a real or a 3-vector. `Block` is the matching
/// Jacobian block (a real, or a 3×3 matrix) that implicit integrators assemble.
pub trait Coord:
    Copy
    + Default
    + Debug
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<f64, Output = Self>
    + AddAssign
    + Send
    + Sync
{
    /// Deliberately not `Default`: glam's matrices default to the identity, not zero.
    type Block: Copy + Debug + Send + Sync;

    fn is_finite(self) -> bool;
    /// Every component equal to `s`.
    fn splat(s: f64) -> Self;
    fn dot(self, other: Self) -> f64;
    /// Largest absolute component (for max-norm error estimates).
    fn max_abs(self) -> f64;
    /// s·I.
    fn block_identity(s: f64) -> Self::Block;
    /// B·c.
    fn block_mul(b: Self::Block, c: Self) -> Self;
    /// Bᵀ·c.
    fn block_mul_transpose(b: Self::Block, c: Self) -> Self;
    /// a bᵀ.
    fn block_outer(a: Self, b: Self) -> Self::Block;
    /// A·B.
    fn block_mul_blocks(a: Self::Block, b: Self::Block) -> Self::Block;
    /// α·A + β·B.
    fn block_combine(a: Self::Block, alpha: f64, b: Self::Block, beta: f64) -> Self::Block;
    /// B⁻¹, or the inverse of its diagonal when B is singular.
    fn block_inverse(b: Self::Block) -> Self::Block;
    /// Sum of absolute entries of each row, as a coordinate (for Gershgorin bounds).
    fn block_row_abs_sums(b: Self::Block) -> Self;
    /// Sum of absolute entries of each column (the row sums of the transpose).
    fn block_col_abs_sums(b: Self::Block) -> Self;

    /// Number of scalar components (1 or 3): the size of a block, for assembling scalar sparse matrices.
    const DIM: usize;
    /// Component `k` (< DIM).
    fn component(self, k: usize) -> f64;
    /// Sets component `k` (< DIM).
    fn set_component(&mut self, k: usize, value: f64);
    /// Entry (row `r`, column `c`) of a block.
    fn block_entry(b: Self::Block, r: usize, c: usize) -> f64;
    /// The block with entries `e[r][c]` (only the leading DIM × DIM are read).
    fn block_from_entries(e: [[f64; 3]; 3]) -> Self::Block;
}

impl Coord for f64 {
    type Block = f64;
    const DIM: usize = 1;

    #[inline]
    fn component(self, _k: usize) -> f64 {
        self
    }
    #[inline]
    fn set_component(&mut self, _k: usize, value: f64) {
        *self = value;
    }
    #[inline]
    fn block_entry(b: f64, _r: usize, _c: usize) -> f64 {
        b
    }
    #[inline]
    fn block_from_entries(e: [[f64; 3]; 3]) -> f64 {
        e[0][0]
    }

    #[inline]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
    #[inline]
    fn splat(s: f64) -> f64 {
        s
    }
    #[inline]
    fn dot(self, other: Self) -> f64 {
        self * other
    }
    #[inline]
    fn max_abs(self) -> f64 {
        self.abs()
    }
    #[inline]
    fn block_identity(s: f64) -> f64 {
        s
    }
    #[inline]
    fn block_mul(b: f64, c: f64) -> f64 {
        b * c
    }
    #[inline]
    fn block_mul_transpose(b: f64, c: f64) -> f64 {
        b * c
    }
    #[inline]
    fn block_outer(a: f64, b: f64) -> f64 {
        a * b
    }
    #[inline]
    fn block_mul_blocks(a: f64, b: f64) -> f64 {
        a * b
    }
    #[inline]
    fn block_combine(a: f64, alpha: f64, b: f64, beta: f64) -> f64 {
        alpha * a + beta * b
    }
    #[inline]
    fn block_inverse(b: f64) -> f64 {
        if b != 0.0 { 1.0 / b } else { 0.0 }
    }
    #[inline]
    fn block_row_abs_sums(b: f64) -> f64 {
        b.abs()
    }
    #[inline]
    fn block_col_abs_sums(b: f64) -> f64 {
        b.abs()
    }
}

impl Coord for DVec3 {
    type Block = DMat3;
    const DIM: usize = 3;

    #[inline]
    fn component(self, k: usize) -> f64 {
        self[k]
    }
    #[inline]
    fn set_component(&mut self, k: usize, value: f64) {
        self[k] = value;
    }
    #[inline]
    fn block_entry(b: DMat3, r: usize, c: usize) -> f64 {
        b.col(c)[r]
    }
    #[inline]
    fn block_from_entries(e: [[f64; 3]; 3]) -> DMat3 {
        DMat3::from_cols_array_2d(&e).transpose()
    }

    #[inline]
    fn is_finite(self) -> bool {
        DVec3::is_finite(self)
    }
    #[inline]
    fn splat(s: f64) -> DVec3 {
        DVec3::splat(s)
    }
    #[inline]
    fn dot(self, other: Self) -> f64 {
        DVec3::dot(self, other)
    }
    #[inline]
    fn max_abs(self) -> f64 {
        self.abs().max_element()
    }
    #[inline]
    fn block_identity(s: f64) -> DMat3 {
        DMat3::from_diagonal(DVec3::splat(s))
    }
    #[inline]
    fn block_mul(b: DMat3, c: DVec3) -> DVec3 {
        b * c
    }
    #[inline]
    fn block_mul_transpose(b: DMat3, c: DVec3) -> DVec3 {
        b.transpose() * c
    }
    #[inline]
    fn block_outer(a: DVec3, b: DVec3) -> DMat3 {
        DMat3::from_cols(a * b.x, a * b.y, a * b.z)
    }
    #[inline]
    fn block_mul_blocks(a: DMat3, b: DMat3) -> DMat3 {
        a * b
    }
    #[inline]
    fn block_combine(a: DMat3, alpha: f64, b: DMat3, beta: f64) -> DMat3 {
        a * alpha + b * beta
    }
    fn block_inverse(b: DMat3) -> DMat3 {
        let det = b.determinant();
        if det.is_finite() && det.abs() > 1e-300 {
            b.inverse()
        } else {
            let d = DVec3::new(b.x_axis.x, b.y_axis.y, b.z_axis.z);
            DMat3::from_diagonal(DVec3::select(d.cmpne(DVec3::ZERO), d.recip(), DVec3::ZERO))
        }
    }
    #[inline]
    fn block_row_abs_sums(b: DMat3) -> DVec3 {
        let t = b.transpose();
        DVec3::new(t.x_axis.abs().element_sum(), t.y_axis.abs().element_sum(), t.z_axis.abs().element_sum())
    }
    #[inline]
    fn block_col_abs_sums(b: DMat3) -> DVec3 {
        DVec3::new(b.x_axis.abs().element_sum(), b.y_axis.abs().element_sum(), b.z_axis.abs().element_sum())
    }
}
