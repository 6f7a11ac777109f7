use std::ops::{Add, AddAssign, Mul, Sub};

/// A coordinate an integrator can combine linearly: a real or a 3-vector.
pub trait Coord:
    Copy + Default + Add<Output = Self> + Sub<Output = Self> + Mul<f64, Output = Self> + AddAssign + Send + Sync
{
    fn is_finite(self) -> bool;
}

impl Coord for f64 {
    #[inline]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
}

impl Coord for glam::DVec3 {
    #[inline]
    fn is_finite(self) -> bool {
        glam::DVec3::is_finite(self)
    }
}
