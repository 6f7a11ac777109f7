//! Where the picture is taken from: a look-at camera with a perspective or orthographic lens.

use anima_geom::{Aabb, DVec3};

/// How camera space is flattened onto the picture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Projection {
    /// A pinhole camera; `fov_y_deg` is the vertical field of view in degrees (clamped to 1°–170°).
    Perspective { fov_y_deg: f64 },
    /// Parallel rays; `half_height` is half the visible height in world units, and the visible width
    /// follows from the picture's aspect ratio.
    Orthographic { half_height: f64 },
}

/// A camera at `eye` looking at `target`, with `up` pointing to the top of the picture (it need not be
/// perpendicular to the viewing direction, only not parallel to it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    pub eye: DVec3,
    pub target: DVec3,
    pub up: DVec3,
    pub projection: Projection,
}

/// The picture fills this fraction of the field of view when a camera frames a box, leaving a margin.
const FRAMING_FILL: f64 = 0.9;

impl Camera {
    /// A perspective camera with a vertical field of view of `fov_y_deg` degrees.
    pub fn look_at(eye: DVec3, target: DVec3, up: DVec3, fov_y_deg: f64) -> Self {
        Self { eye, target, up, projection: Projection::Perspective { fov_y_deg } }
    }

    /// An orthographic camera showing `half_height` world units above and below `target`.
    pub fn orthographic(eye: DVec3, target: DVec3, up: DVec3, half_height: f64) -> Self {
        Self { eye, target, up, projection: Projection::Orthographic { half_height } }
    }

    /// A perspective camera looking along `view_dir` (from the eye towards the scene) at `aabb`, placed
    /// as close as it can be while all eight corners fit inside a square of the vertical field of view
    /// with a small margin, and shifted sideways so the box's picture is centred. The box therefore fills
    /// the picture's height (or its width, if that is the tighter fit); a wider picture gains room at the
    /// sides.
    ///
    /// An empty or non-finite box is replaced by the unit cube at the origin, a degenerate one (a point)
    /// by a unit cube around it; a zero `view_dir` looks along −z.
    pub fn framing(aabb: Aabb, view_dir: DVec3, up: DVec3, fov_y_deg: f64) -> Self {
        let frame = Framing::new(aabb, view_dir, up);
        let t = (clamp_fov(fov_y_deg).to_radians() / 2.0).tan() * FRAMING_FILL;
        // With the eye at distance d from the box centre along the view axis and shifted sideways by s,
        // a corner (x, y across the view, z towards the eye) is in view when
        // |x − s| ≤ t (d − z), i.e. x − t (d − z) ≤ s ≤ x + t (d − z), and likewise in y. Some shift
        // fits every corner once x_i − x_j ≤ t (2d − z_i − z_j) for all pairs, which gives the least d;
        // the shift is then the middle of the allowed interval.
        let c = &frame.corners;
        let mut distance = frame.max_depth + 1e-3 * frame.radius;
        for i in c {
            for j in c {
                let spread = (i.x - j.x).max(i.y - j.y);
                distance = distance.max((spread / t + i.z + j.z) / 2.0);
            }
        }
        let shift = |coord: fn(&DVec3) -> f64| {
            let lo = c.iter().map(|p| coord(p) - t * (distance - p.z)).fold(f64::NEG_INFINITY, f64::max);
            let hi = c.iter().map(|p| coord(p) + t * (distance - p.z)).fold(f64::INFINITY, f64::min);
            (lo + hi) / 2.0
        };
        let target = frame.centre + frame.right * shift(|p| p.x) + frame.up * shift(|p| p.y);
        Self::look_at(target - frame.forward * distance, target, up, fov_y_deg)
    }

    /// An orthographic camera looking along `view_dir` at the centre of `aabb`, wide enough that the box
    /// fills the picture's height with a small margin. Degenerate inputs are treated as in
    /// [`Camera::framing`].
    pub fn framing_orthographic(aabb: Aabb, view_dir: DVec3, up: DVec3) -> Self {
        let frame = Framing::new(aabb, view_dir, up);
        let half_height =
            frame.corners.iter().map(|c| c.x.abs().max(c.y.abs())).fold(0.0, f64::max) / FRAMING_FILL;
        let eye = frame.centre - frame.forward * (frame.max_depth + frame.radius);
        Self::orthographic(eye, frame.centre, up, half_height.max(1e-9))
    }

    /// The unit direction the camera looks along, or `None` when eye and target coincide or are not finite.
    pub fn view_dir(&self) -> Option<DVec3> {
        (self.target - self.eye).try_normalize()
    }

    /// The camera's orthonormal frame, or `None` when it is degenerate.
    pub(crate) fn basis(&self) -> Option<Basis> {
        Basis::new(self.view_dir()?, self.up)
    }
}

fn clamp_fov(fov_y_deg: f64) -> f64 {
    if fov_y_deg.is_finite() { fov_y_deg.clamp(1.0, 170.0) } else { 45.0 }
}

/// A right-handed camera frame: `right × up = back`, and the camera looks along −`back`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Basis {
    pub right: DVec3,
    pub up: DVec3,
    pub back: DVec3,
}

impl Basis {
    fn new(forward: DVec3, up_hint: DVec3) -> Option<Self> {
        // An `up` parallel to the view would leave the roll undefined; fall back to the world axis least
        // aligned with the view rather than fail.
        let right = forward.cross(up_hint).try_normalize().or_else(|| {
            let a = forward.abs();
            let axis = if a.x <= a.y && a.x <= a.z {
                DVec3::X
            } else if a.y <= a.z {
                DVec3::Y
            } else {
                DVec3::Z
            };
            forward.cross(axis).try_normalize()
        })?;
        Some(Self { right, up: right.cross(forward), back: -forward })
    }

    /// Camera coordinates of a world-space offset: x right, y up, z towards the viewer.
    #[inline]
    pub fn camera_coords(&self, d: DVec3) -> DVec3 {
        DVec3::new(d.dot(self.right), d.dot(self.up), d.dot(self.back))
    }
}

/// A box's corners in the frame of a camera about to look at its centre.
struct Framing {
    centre: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    /// Corners relative to the centre: x right, y up, z towards the eye.
    corners: [DVec3; 8],
    max_depth: f64,
    radius: f64,
}

impl Framing {
    fn new(aabb: Aabb, view_dir: DVec3, up: DVec3) -> Self {
        let usable = !aabb.is_empty() && aabb.min.is_finite() && aabb.max.is_finite();
        let (mut min, mut max) =
            if usable { (aabb.min, aabb.max) } else { (DVec3::splat(-0.5), DVec3::splat(0.5)) };
        if (max - min).length() < 1e-12 * (1.0 + min.abs().max_element()) {
            min -= DVec3::splat(0.5);
            max += DVec3::splat(0.5);
        }
        let centre = (min + max) * 0.5;
        let forward = view_dir.try_normalize().unwrap_or(DVec3::NEG_Z);
        let basis = Basis::new(forward, up).expect("a unit forward always has a perpendicular axis");
        let corners = std::array::from_fn(|k| {
            let c = DVec3::new(
                if k & 1 == 0 { min.x } else { max.x },
                if k & 2 == 0 { min.y } else { max.y },
                if k & 4 == 0 { min.z } else { max.z },
            );
            basis.camera_coords(c - centre)
        });
        let max_depth = corners.iter().map(|c| c.z).fold(f64::NEG_INFINITY, f64::max);
        Self {
            centre,
            forward,
            right: basis.right,
            up: basis.up,
            corners,
            max_depth,
            radius: (max - min).length() / 2.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn framing_keeps_every_corner_inside_the_field_of_view() {
        let aabb = Aabb { min: DVec3::new(-2.0, 0.0, -1.0), max: DVec3::new(3.0, 1.0, 1.0) };
        let cam = Camera::framing(aabb, DVec3::new(-1.0, -0.7, -1.3), DVec3::Y, 40.0);
        let basis = cam.basis().unwrap();
        let tan_half = 20f64.to_radians().tan();
        let mut widest: f64 = 0.0;
        for k in 0..8 {
            let c = DVec3::new(
                if k & 1 == 0 { aabb.min.x } else { aabb.max.x },
                if k & 2 == 0 { aabb.min.y } else { aabb.max.y },
                if k & 4 == 0 { aabb.min.z } else { aabb.max.z },
            );
            let p = basis.camera_coords(c - cam.eye);
            assert!(p.z < 0.0, "corner {k} behind the camera");
            let spread = (p.x.abs().max(p.y.abs())) / (-p.z * tan_half);
            assert!(spread <= 1.0, "corner {k} outside the view ({spread})");
            widest = widest.max(spread);
        }
        assert!(widest > 0.89, "box fills only {widest} of the view");
    }

    #[test]
    fn degenerate_inputs_still_give_a_usable_camera() {
        let cam = Camera::framing(Aabb::EMPTY, DVec3::ZERO, DVec3::Y, f64::NAN);
        assert!(cam.eye.is_finite() && cam.basis().is_some());
        let up_along_view = Camera::look_at(DVec3::new(0.0, 5.0, 0.0), DVec3::ZERO, DVec3::Y, 45.0);
        assert!(up_along_view.basis().is_some());
        let point = Aabb::from_points([DVec3::ONE]);
        let ortho = Camera::framing_orthographic(point, DVec3::NEG_Z, DVec3::Y);
        assert!(matches!(ortho.projection, Projection::Orthographic { half_height } if half_height > 0.1));
        assert!(Camera::look_at(DVec3::ONE, DVec3::ONE, DVec3::Y, 45.0).basis().is_none());
    }
}
