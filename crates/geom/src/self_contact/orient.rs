//! The orientation predicate the crossing checker is built on, with a certified sign.
//!
//! orient3d(a, b, c, d) is the sign of (b − a) × (c − a) · (d − a), six times the signed volume of the
//! tetrahedron abcd. It is evaluated in `f64` on the differences to d and compared against Shewchuk's
//! forward error bound ("Adaptive precision floating-point arithmetic and fast robust geometric
//! predicates", 1997, the `o3derrboundA` of his `orient3d`): when |det| exceeds the bound the sign is
//! the sign of the exact determinant of the (exactly representable) input coordinates. Inside the
//! bound this predicate answers 0, "in the plane or too close to it for `f64` to tell", instead of
//! falling back to exact arithmetic. Callers treat 0 as coplanar, so a near-degenerate configuration is
//! classified consistently rather than by rounding noise.

use glam::DVec3;

/// Unit roundoff of `f64` (half an ulp of 1).
const EPS: f64 = f64::EPSILON * 0.5;
/// Shewchuk's relative error bound for the floating-point orient3d determinant.
const O3D_ERR_BOUND: f64 = (7.0 + 56.0 * EPS) * EPS;

/// Certified sign of (b − a) × (c − a) · (d − a): +1 when d lies on the side the normal of the
/// counter-clockwise triangle abc points to, −1 on the other side, 0 when d is in the plane of abc or
/// within the rounding error of it (see the module docs). Non-finite input gives 0.
#[inline]
pub fn orient3d(a: DVec3, b: DVec3, c: DVec3, d: DVec3) -> i8 {
    let (ad, bd, cd) = (a - d, b - d, c - d);
    let bdxcdy = bd.x * cd.y;
    let cdxbdy = cd.x * bd.y;
    let cdxady = cd.x * ad.y;
    let adxcdy = ad.x * cd.y;
    let adxbdy = ad.x * bd.y;
    let bdxady = bd.x * ad.y;
    // det[a − d; b − d; c − d], which is −(b − a) × (c − a) · (d − a).
    let det = ad.z * (bdxcdy - cdxbdy) + bd.z * (cdxady - adxcdy) + cd.z * (adxbdy - bdxady);
    let permanent = (bdxcdy.abs() + cdxbdy.abs()) * ad.z.abs()
        + (cdxady.abs() + adxcdy.abs()) * bd.z.abs()
        + (adxbdy.abs() + bdxady.abs()) * cd.z.abs();
    let bound = O3D_ERR_BOUND * permanent;
    if det > bound {
        -1
    } else if -det > bound {
        1
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sign_follows_the_normal_of_the_counter_clockwise_triangle() {
        let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
        assert_eq!(orient3d(a, b, c, DVec3::Z), 1);
        assert_eq!(orient3d(a, b, c, -DVec3::Z), -1);
        assert_eq!(orient3d(a, c, b, DVec3::Z), -1);
        assert_eq!(orient3d(a, b, c, DVec3::new(0.3, 7.0, 0.0)), 0);
    }

    #[test]
    fn points_in_a_skew_plane_are_coplanar_not_noise() {
        // Points on the plane x + y + z = 1 built from exact dyadic coordinates: the floating-point
        // determinant is exactly zero or within the bound, never a wrong sign.
        let a = DVec3::new(1.0, 0.0, 0.0);
        let b = DVec3::new(0.0, 1.0, 0.0);
        let c = DVec3::new(0.0, 0.0, 1.0);
        for k in 0..64 {
            let u = k as f64 / 64.0;
            let d = DVec3::new(u, 0.5 - u * 0.5, 0.5 - u * 0.5);
            assert_eq!(orient3d(a, b, c, d), 0, "k = {k}");
        }
        assert_eq!(orient3d(a, b, c, DVec3::splat(0.5)), 1);
        assert_eq!(orient3d(a, b, c, DVec3::splat(f64::NAN)), 0);
    }

    #[test]
    fn tiny_offsets_far_from_the_origin_keep_their_sign() {
        let o = DVec3::splat(1.0e3);
        let (a, b, c) = (o, o + DVec3::X, o + DVec3::Y);
        assert_eq!(orient3d(a, b, c, o + DVec3::new(0.25, 0.25, 1.0e-9)), 1);
        assert_eq!(orient3d(a, b, c, o + DVec3::new(0.25, 0.25, -1.0e-9)), -1);
    }
}
