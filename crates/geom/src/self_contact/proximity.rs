//! Closest points between the elements of a cloth: a point and a triangle, and two segments. These are
//! the proximity half of the narrow phase (two pieces of cloth closer than the thickness are in
//! contact) and the test the continuous half applies at each instant of coplanarity.
//!
//! Both follow the Voronoi-region formulation of Ericson (Real-Time Collision Detection, 2005, §5.1.5
//! and §5.1.9): the answer comes with the barycentric weights a response needs to spread an impulse
//! over the vertices, and stays finite for degenerate triangles, zero-length and parallel segments.

use glam::DVec3;

/// The point of a triangle nearest to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointTriangleProximity {
    /// Weights (w₀, w₁, w₂) of the triangle's corners, non-negative and summing to 1.
    pub barycentric: [f64; 3],
    /// The nearest point of the triangle, w₀·a + w₁·b + w₂·c.
    pub point: DVec3,
    /// Distance from the query point to the triangle, m.
    pub distance: f64,
}

/// The nearest pair of points of two segments a₀a₁ and b₀b₁.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeEdgeProximity {
    /// Parameters in [0, 1]: the points are a₀ + s₀(a₁ − a₀) and b₀ + s₁(b₁ − b₀).
    pub s: [f64; 2],
    pub points: [DVec3; 2],
    /// Distance between the segments, m.
    pub distance: f64,
}

/// The point of triangle abc nearest to `p`. A triangle of zero area is treated as the union of its
/// three edges.
pub fn point_triangle_proximity(p: DVec3, [a, b, c]: [DVec3; 3]) -> PointTriangleProximity {
    let ab = b - a;
    let ac = c - a;
    let normal = ab.cross(ac);
    // Relative test: a sliver whose area is at rounding level of its edge lengths has no usable face.
    if normal.length_squared() <= (f64::EPSILON * ab.length_squared().max(ac.length_squared())).powi(2) {
        return degenerate_triangle(p, [a, b, c]);
    }
    let weights = |w: [f64; 3]| {
        let point = a * w[0] + b * w[1] + c * w[2];
        PointTriangleProximity { barycentric: w, point, distance: (p - point).length() }
    };
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return weights([1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return weights([0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return weights([1.0 - v, v, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return weights([0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return weights([1.0 - w, 0.0, w]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return weights([0.0, 1.0 - w, w]);
    }
    let denom = va + vb + vc;
    let (v, w) = (vb / denom, vc / denom);
    weights([1.0 - v - w, v, w])
}

fn degenerate_triangle(p: DVec3, [a, b, c]: [DVec3; 3]) -> PointTriangleProximity {
    let edges = [(a, b, [0, 1]), (b, c, [1, 2]), (c, a, [2, 0])];
    let mut best: Option<PointTriangleProximity> = None;
    for (x, y, [i, j]) in edges {
        let s = point_segment_parameter(p, x, y);
        let point = x + (y - x) * s;
        let distance = (p - point).length();
        if best.is_none_or(|b| distance < b.distance) {
            let mut barycentric = [0.0; 3];
            barycentric[i] = 1.0 - s;
            barycentric[j] += s;
            best = Some(PointTriangleProximity { barycentric, point, distance });
        }
    }
    best.expect("three edges")
}

/// Parameter in [0, 1] of the point of segment xy nearest to p (0 for a zero-length segment).
fn point_segment_parameter(p: DVec3, x: DVec3, y: DVec3) -> f64 {
    let d = y - x;
    let len2 = d.length_squared();
    if len2 == 0.0 { 0.0 } else { ((p - x).dot(d) / len2).clamp(0.0, 1.0) }
}

/// The nearest points of segments a₀a₁ and b₀b₁.
///
/// For parallel (or nearly parallel) segments every point of the overlap is equally near; the pair
/// returned then starts from a₀'s end (s₀ = 0) and is re-projected, so it is one of the nearest pairs.
pub fn edge_edge_proximity([a0, a1]: [DVec3; 2], [b0, b1]: [DVec3; 2]) -> EdgeEdgeProximity {
    let da = a1 - a0;
    let db = b1 - b0;
    let r = a0 - b0;
    let aa = da.length_squared();
    let bb = db.length_squared();
    let f = db.dot(r);
    let (s, u);
    if aa == 0.0 && bb == 0.0 {
        (s, u) = (0.0, 0.0);
    } else if aa == 0.0 {
        (s, u) = (0.0, (f / bb).clamp(0.0, 1.0));
    } else {
        let c = da.dot(r);
        if bb == 0.0 {
            (s, u) = ((-c / aa).clamp(0.0, 1.0), 0.0);
        } else {
            let ab = da.dot(db);
            let denom = aa * bb - ab * ab;
            // denom = |da × db|²; below rounding level of aa·bb the lines are parallel for f64.
            let s0 = if denom > 4.0 * f64::EPSILON * aa * bb {
                ((ab * f - c * bb) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let u0 = (ab * s0 + f) / bb;
            (s, u) = if u0 < 0.0 {
                ((-c / aa).clamp(0.0, 1.0), 0.0)
            } else if u0 > 1.0 {
                (((ab - c) / aa).clamp(0.0, 1.0), 1.0)
            } else {
                (s0, u0)
            };
        }
    }
    let pa = a0 + da * s;
    let pb = b0 + db * u;
    EdgeEdgeProximity { s: [s, u], points: [pa, pb], distance: (pa - pb).length() }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tri() -> [DVec3; 3] {
        [DVec3::ZERO, DVec3::X, DVec3::Y]
    }

    #[test]
    fn point_over_the_face_projects_onto_it() {
        let q = point_triangle_proximity(DVec3::new(0.2, 0.3, 0.5), tri());
        assert!((q.distance - 0.5).abs() < 1e-15);
        let [w0, w1, w2] = q.barycentric;
        assert!((w0 - 0.5).abs() < 1e-15 && (w1 - 0.2).abs() < 1e-15 && (w2 - 0.3).abs() < 1e-15);
    }

    #[test]
    fn points_outside_go_to_the_nearest_edge_or_corner() {
        let q = point_triangle_proximity(DVec3::new(-1.0, -1.0, 0.0), tri());
        assert_eq!(q.barycentric, [1.0, 0.0, 0.0]);
        let q = point_triangle_proximity(DVec3::new(0.5, -1.0, 1.0), tri());
        assert_eq!(q.barycentric, [0.5, 0.5, 0.0]);
        assert!((q.distance - 2f64.sqrt()).abs() < 1e-15);
        let q = point_triangle_proximity(DVec3::new(1.0, 1.0, 0.0), tri());
        assert!((q.barycentric[1] - 0.5).abs() < 1e-15 && (q.barycentric[2] - 0.5).abs() < 1e-15);
        assert!((q.distance - 0.5f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn degenerate_triangle_answers_with_its_edges() {
        let q = point_triangle_proximity(DVec3::new(0.5, 1.0, 0.0), [DVec3::ZERO, DVec3::X, DVec3::X * 2.0]);
        assert!((q.distance - 1.0).abs() < 1e-15);
        assert!(q.barycentric.iter().all(|w| w.is_finite()));
        assert!((q.barycentric.iter().sum::<f64>() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn crossing_segments_meet_at_their_crossing() {
        let q = edge_edge_proximity(
            [DVec3::new(0.0, 0.5, 1.0), DVec3::new(1.0, 0.5, 1.0)],
            [DVec3::new(0.25, 0.0, 0.0), DVec3::new(0.25, 1.0, 0.0)],
        );
        assert!((q.s[0] - 0.25).abs() < 1e-15 && (q.s[1] - 0.5).abs() < 1e-15);
        assert!((q.distance - 1.0).abs() < 1e-15);
    }

    #[test]
    fn parallel_and_zero_length_segments_stay_finite() {
        // Overlapping parallel segments 0.1 apart: any overlap point is nearest.
        let q = edge_edge_proximity(
            [DVec3::ZERO, DVec3::X],
            [DVec3::new(0.5, 0.1, 0.0), DVec3::new(1.5, 0.1, 0.0)],
        );
        assert!((q.distance - 0.1).abs() < 1e-15, "{q:?}");
        // Disjoint collinear segments: the gap between the facing ends.
        let q = edge_edge_proximity(
            [DVec3::ZERO, DVec3::X],
            [DVec3::new(3.0, 0.0, 0.0), DVec3::new(2.0, 0.0, 0.0)],
        );
        assert!((q.distance - 1.0).abs() < 1e-15 && q.s == [1.0, 1.0], "{q:?}");
        let q = edge_edge_proximity([DVec3::Y, DVec3::Y], [DVec3::ZERO, DVec3::X]);
        assert!((q.distance - 1.0).abs() < 1e-15);
        let q = edge_edge_proximity([DVec3::Y, DVec3::Y], [DVec3::ZERO, DVec3::ZERO]);
        assert!((q.distance - 1.0).abs() < 1e-15);
    }
}
