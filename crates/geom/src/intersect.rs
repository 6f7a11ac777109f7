//! Segment–triangle intersection after Badouel ("An efficient ray–polygon intersection", Graphics Gems,
//! 1990), the test FLEX3D ran between each particle's path over one step and every triangle of the scene
//! (Nedel 1993 §5.3). Axis-aligned boxes for culling.

use glam::DVec3;

/// A triangle with the data Badouel's test precomputes: the plane and the two axes to project onto.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PreparedTriangle {
    v0: DVec3,
    /// Unnormalised normal (V1 − V0) × (V2 − V0).
    normal: DVec3,
    /// Plane offset d = −N·V0.
    d: f64,
    /// The two axes that remain after dropping the dominant axis of the normal.
    i1: usize,
    i2: usize,
    /// Edge components on those axes: (u1, v1) for V1 − V0, (u2, v2) for V2 − V0.
    u1: f64,
    v1: f64,
    u2: f64,
    v2: f64,
}

/// Where a segment meets a triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentHit {
    /// Segment parameter in [0, 1]: the hit point is O + s·D.
    pub s: f64,
    /// Barycentric coordinates (w0, w1, w2) of the hit point with respect to (V0, V1, V2).
    pub barycentric: [f64; 3],
}

impl PreparedTriangle {
    pub fn new([v0, v1, v2]: [DVec3; 3]) -> Self {
        let e1 = v1 - v0;
        let e2 = v2 - v0;
        let normal = e1.cross(e2);
        let a = normal.abs();
        let i0 = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let (i1, i2) = match i0 {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        Self { v0, normal, d: -normal.dot(v0), i1, i2, u1: e1[i1], v1: e1[i2], u2: e2[i1], v2: e2[i2] }
    }

    /// True for a triangle of zero area, which collision detection ignores.
    pub fn is_degenerate(&self) -> bool {
        self.normal == DVec3::ZERO
    }

    /// Unit normal (zero for a degenerate triangle).
    pub fn unit_normal(&self) -> DVec3 {
        self.normal.normalize_or_zero()
    }
}

/// First (and only) intersection of the segment `o → o + dir` with the triangle, inclusive of both ends
/// and of the triangle's edges. Segments parallel to the plane and degenerate triangles never hit.
#[inline]
pub fn segment_triangle(o: DVec3, dir: DVec3, tri: &PreparedTriangle) -> Option<SegmentHit> {
    let den = tri.normal.dot(dir);
    if den == 0.0 {
        return None;
    }
    let s = -(tri.d + tri.normal.dot(o)) / den;
    if !(0.0..=1.0).contains(&s) {
        return None;
    }
    let q = o + dir * s;
    let u0 = q[tri.i1] - tri.v0[tri.i1];
    let v0 = q[tri.i2] - tri.v0[tri.i2];
    let (alpha, beta);
    if tri.u1 == 0.0 {
        beta = u0 / tri.u2;
        if !(0.0..=1.0).contains(&beta) {
            return None;
        }
        alpha = (v0 - beta * tri.v2) / tri.v1;
    } else {
        let det = tri.v2 * tri.u1 - tri.u2 * tri.v1;
        beta = (v0 * tri.u1 - u0 * tri.v1) / det;
        if !(0.0..=1.0).contains(&beta) {
            return None;
        }
        // Badouel's α = (u0 − β u2)/u1 divides by u1, which can be a rounding residue (1e-16 on an edge
        // that is parallel to the axis in exact arithmetic): β rounded to 1 then made α exactly 0 and
        // reported a point √2 m outside the triangle as on its edge. Cramer's rule divides by the
        // projected area instead.
        alpha = (u0 * tri.v2 - tri.u2 * v0) / det;
    }
    if alpha >= 0.0 && alpha + beta <= 1.0 {
        Some(SegmentHit { s, barycentric: [1.0 - alpha - beta, alpha, beta] })
    } else {
        None
    }
}

/// An axis-aligned bounding box. An empty box has `min > max`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub const EMPTY: Aabb = Aabb { min: DVec3::splat(f64::INFINITY), max: DVec3::splat(f64::NEG_INFINITY) };

    pub fn from_points(points: impl IntoIterator<Item = DVec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.including(p))
    }

    #[inline]
    pub fn including(self, p: DVec3) -> Self {
        Self { min: self.min.min(p), max: self.max.max(p) }
    }

    #[inline]
    pub fn union(self, other: Aabb) -> Self {
        Self { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    #[inline]
    pub fn overlaps(&self, other: &Aabb) -> bool {
        self.min.cmple(other.max).all() && other.min.cmple(self.max).all()
    }

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    pub fn size(&self) -> DVec3 {
        if self.is_empty() { DVec3::ZERO } else { self.max - self.min }
    }

    pub fn centre(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    pub fn diagonal_length(&self) -> f64 {
        self.size().length()
    }
}

#[cfg(test)]
mod tests {
    /// A path from the fourth corner of a grid square, tested against the square's other triangle, whose
    /// edge V0V1 is parallel to the y axis up to a rounding residue (u1 = 1.1e-16): Badouel's α = (u0 −
    /// β u2)/u1 came out exactly 0 and reported the corner, √2 m from the triangle, as on its edge (found
    /// on the sail of FLEX3D's E-5).
    #[test]
    fn a_point_off_the_triangle_is_not_on_its_edge_when_an_edge_is_nearly_axis_parallel() {
        let tri = PreparedTriangle::new([
            DVec3::new(-1.0, 38.995158604, 0.009682792000000008),
            DVec3::new(-0.9999999999999999, 36.995158604, 0.009682792000000008),
            DVec3::new(1.0, 36.995158604, 0.009682791999999996),
        ]);
        let o = DVec3::new(1.0, 38.995158604, 0.009682791999999996);
        let dir = DVec3::new(0.0, -0.0002830239999980222, 0.0005660479999999996);
        assert_eq!(segment_triangle(o, dir, &tri), None);
    }

    use super::*;

    fn unit_tri() -> PreparedTriangle {
        PreparedTriangle::new([DVec3::ZERO, DVec3::X, DVec3::Y])
    }

    #[test]
    fn segment_through_interior_hits_with_barycentrics() {
        let hit =
            segment_triangle(DVec3::new(0.25, 0.25, 1.0), DVec3::new(0.0, 0.0, -2.0), &unit_tri()).unwrap();
        assert!((hit.s - 0.5).abs() < 1e-15);
        let [w0, w1, w2] = hit.barycentric;
        assert!((w0 - 0.5).abs() < 1e-15 && (w1 - 0.25).abs() < 1e-15 && (w2 - 0.25).abs() < 1e-15);
    }

    #[test]
    fn segment_stopping_short_misses() {
        assert!(
            segment_triangle(DVec3::new(0.25, 0.25, 1.0), DVec3::new(0.0, 0.0, -0.5), &unit_tri()).is_none()
        );
    }

    #[test]
    fn segment_outside_triangle_misses() {
        assert!(
            segment_triangle(DVec3::new(0.8, 0.8, 1.0), DVec3::new(0.0, 0.0, -2.0), &unit_tri()).is_none()
        );
        assert!(
            segment_triangle(DVec3::new(-0.1, 0.3, 1.0), DVec3::new(0.0, 0.0, -2.0), &unit_tri()).is_none()
        );
    }

    #[test]
    fn parallel_segment_misses_and_endpoints_are_inclusive() {
        assert!(
            segment_triangle(DVec3::new(0.1, 0.1, 0.0), DVec3::new(0.2, 0.0, 0.0), &unit_tri()).is_none()
        );
        let hit =
            segment_triangle(DVec3::new(0.2, 0.2, 1.0), DVec3::new(0.0, 0.0, -1.0), &unit_tri()).unwrap();
        assert_eq!(hit.s, 1.0);
    }

    #[test]
    fn triangle_with_zero_first_edge_component_uses_other_branch() {
        // V1 − V0 has no component on the first projected axis: exercises Badouel's u1 == 0 branch.
        let tri = PreparedTriangle::new([DVec3::ZERO, DVec3::new(0.0, 1.0, 0.0), DVec3::new(1.0, 0.0, 0.0)]);
        let hit = segment_triangle(DVec3::new(0.3, 0.3, -1.0), DVec3::new(0.0, 0.0, 2.0), &tri).unwrap();
        let q = hit.barycentric[1] * DVec3::Y + hit.barycentric[2] * DVec3::X;
        assert!((q - DVec3::new(0.3, 0.3, 0.0)).length() < 1e-14);
    }

    #[test]
    fn degenerate_triangle_never_hits() {
        let tri = PreparedTriangle::new([DVec3::ZERO, DVec3::X, DVec3::X * 2.0]);
        assert!(tri.is_degenerate());
        assert!(segment_triangle(DVec3::new(0.5, 0.0, 1.0), DVec3::new(0.0, 0.0, -2.0), &tri).is_none());
    }
}
