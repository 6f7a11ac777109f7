//! Continuous collision detection over one step: the earliest time at which a vertex and a triangle,
//! or two edges, all moving linearly, touch (Provot 1997; Bridson, Fedkiw & Anderson 2002, §4).
//!
//! Four points x₀…x₃ moving as xᵢ(t) = xᵢ + t·Δxᵢ are coplanar when
//!
//!   f(t) = (x₁(t) − x₀(t)) × (x₂(t) − x₀(t)) · (x₃(t) − x₀(t)) = 0,
//!
//! a cubic in t. A vertex can only pass through a triangle, and an edge through another, at a root of
//! f; a root is a contact when, at that time, the elements are within the thickness (closest points of
//! [`point_triangle_proximity`] and [`edge_edge_proximity`]).
//!
//! The roots are found without the closed-form cubic formula, whose cancellation loses the small
//! roots that matter here: [0, 1] is split at the roots of f′ (a quadratic, solved in the stable
//! form), f is monotone on each piece, and a piece whose ends differ in sign holds exactly one root,
//! refined by Newton's method kept inside the bracket (bisection when a Newton step leaves it). This
//! needs no case analysis by degree: a vanishing leading coefficient just moves a critical point out of
//! [0, 1]. The critical points themselves are checked too, which catches an approach that comes within
//! the thickness of the plane without reaching it (a double root). Roots are visited in time order,
//! and the first contact is the answer.
//!
//! When f vanishes on the whole step (the elements stay coplanar: parallel edges, a vertex sliding in
//! the plane of a flat sheet), there is no instant of coplanarity to test. The earliest contact is then
//! found by conservative advancement (Mirtich 1996): from t = 0, step by (d(t) − thickness)/L, where L
//! bounds how fast the distance d can shrink (the largest displacement of each element, summed), so a
//! step never jumps over a contact.
//!
//! Configurations within the thickness that never become coplanar (two layers resting apart) are not
//! this test's business: the proximity tests at the end of the step handle them.

use glam::DVec3;

use super::proximity::{
    EdgeEdgeProximity, PointTriangleProximity, edge_edge_proximity, point_triangle_proximity,
};

/// Relative tolerance on the distance at a root, in units of the configuration's size: it absorbs the
/// error of the root's time (Newton to a few ulps) and of the cubic's coefficients, so a zero-thickness
/// test still accepts the coplanar instant it found.
const DISTANCE_TOL: f64 = 1.0e-10;
/// Below this (relative to the configuration's size cubed) the cubic is taken to vanish identically.
const DEGENERATE_TOL: f64 = 1.0e-12;
/// Most steps of conservative advancement; an undecided answer after them is reported as a contact.
const MAX_ADVANCES: usize = 256;

/// The first contact of a moving vertex with a moving triangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VertexTriangleImpact {
    /// Fraction of the step, in [0, 1], at which the contact happens: the instant the four points
    /// become coplanar, or, for motion coplanar throughout, the first instant within the thickness.
    pub t: f64,
    /// Unit contact normal at time t, pointing from the triangle to the vertex's side (the gap
    /// direction when they are apart, the face normal on the side the vertex came from when they
    /// touch): an impulse along +normal on the vertex (and −normal on the triangle) separates them.
    pub normal: DVec3,
    /// Weights of the triangle's corners at the point of contact.
    pub barycentric: [f64; 3],
    /// Vertex–triangle distance at time t, m (at most the thickness, up to the root tolerance).
    pub distance: f64,
}

/// The first contact of two moving edges a₀a₁ and b₀b₁.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EdgeEdgeImpact {
    /// Fraction of the step, in [0, 1], at which the contact happens (as for
    /// [`VertexTriangleImpact::t`]).
    pub t: f64,
    /// Unit contact normal at time t, pointing from edge b to edge a's side (as for
    /// [`VertexTriangleImpact::normal`]): an impulse along +normal on a (and −normal on b) separates
    /// them.
    pub normal: DVec3,
    /// Parameters of the contact points: a₀ + s₀(a₁ − a₀) and b₀ + s₁(b₁ − b₀).
    pub s: [f64; 2],
    /// Edge–edge distance at time t, m.
    pub distance: f64,
}

/// Earliest contact over the step between the vertex `[0]` and the triangle `[1], [2], [3]`, whose
/// positions move linearly from `start` to `end`; `None` when they never come within `thickness` at
/// an instant of coplanarity (see the module docs).
pub fn vertex_triangle_impact(
    start: [DVec3; 4],
    end: [DVec3; 4],
    thickness: f64,
) -> Option<VertexTriangleImpact> {
    let disp = [0, 1, 2, 3].map(|i| end[i] - start[i]);
    let at = |t: f64| [0, 1, 2, 3].map(|i| start[i] + disp[i] * t);
    let proximity = |t: f64| {
        let [p, a, b, c] = at(t);
        point_triangle_proximity(p, [a, b, c])
    };
    let [p, a, b, c] = start;
    let [dp, da, db, dc] = disp;
    let cubic = Cubic::triple([b - a, c - a, p - a], [db - da, dc - da, dp - da]);
    let scale =
        [b - a, c - a, p - a, db - da, dc - da, dp - da].iter().fold(0.0f64, |m, v| m.max(v.length()));
    let reach = thickness + DISTANCE_TOL * scale;
    let impact = |t: f64, q: PointTriangleProximity| {
        let [p, a, b, c] = at(t);
        let w = q.barycentric;
        let relative_start = start[0] - (start[1] * w[0] + start[2] * w[1] + start[3] * w[2]);
        let relative_velocity = dp - (da * w[0] + db * w[1] + dc * w[2]);
        let apart = q.distance > DISTANCE_TOL * scale;
        let normal =
            contact_normal((b - a).cross(c - a), p - q.point, apart, relative_start, relative_velocity);
        VertexTriangleImpact { t, normal, barycentric: w, distance: q.distance }
    };
    if cubic.vanishes(scale) {
        let speed = dp.length() + da.length().max(db.length()).max(dc.length());
        let t = conservative_advancement(|t| proximity(t).distance, speed, thickness, reach)?;
        return Some(impact(t, proximity(t)));
    }
    cubic.candidate_times().iter().find_map(|&t| {
        let q = proximity(t);
        (q.distance <= reach).then(|| impact(t, q))
    })
}

/// Earliest contact over the step between edges `[0]–[1]` and `[2]–[3]`, whose positions move linearly
/// from `start` to `end`; `None` when they never come within `thickness` at an instant of coplanarity
/// (see the module docs).
pub fn edge_edge_impact(start: [DVec3; 4], end: [DVec3; 4], thickness: f64) -> Option<EdgeEdgeImpact> {
    let disp = [0, 1, 2, 3].map(|i| end[i] - start[i]);
    let at = |t: f64| [0, 1, 2, 3].map(|i| start[i] + disp[i] * t);
    let proximity = |t: f64| {
        let [a0, a1, b0, b1] = at(t);
        edge_edge_proximity([a0, a1], [b0, b1])
    };
    let [a0, a1, b0, b1] = start;
    let [da0, da1, db0, db1] = disp;
    let e = [a1 - a0, b1 - b0, b0 - a0];
    let d = [da1 - da0, db1 - db0, db0 - da0];
    let cubic = Cubic::triple(e, d);
    let scale = e.iter().chain(&d).fold(0.0f64, |m, v| m.max(v.length()));
    let reach = thickness + DISTANCE_TOL * scale;
    let impact = |t: f64, q: EdgeEdgeProximity| {
        let [a0, a1, b0, b1] = at(t);
        let [s, u] = q.s;
        let relative_start = (start[0] + (start[1] - start[0]) * s) - (start[2] + (start[3] - start[2]) * u);
        let relative_velocity = (da0 + (da1 - da0) * s) - (db0 + (db1 - db0) * u);
        let axis = (a1 - a0).cross(b1 - b0);
        let parallel =
            axis.length_squared() <= 1.0e-24 * (a1 - a0).length_squared() * (b1 - b0).length_squared();
        let face = if parallel { DVec3::ZERO } else { axis };
        let apart = q.distance > DISTANCE_TOL * scale;
        let normal =
            contact_normal(face, q.points[0] - q.points[1], apart, relative_start, relative_velocity);
        EdgeEdgeImpact { t, normal, s: q.s, distance: q.distance }
    };
    if cubic.vanishes(scale) {
        let speed = da0.length().max(da1.length()) + db0.length().max(db1.length());
        let t = conservative_advancement(|t| proximity(t).distance, speed, thickness, reach)?;
        return Some(impact(t, proximity(t)));
    }
    cubic.candidate_times().iter().find_map(|&t| {
        let q = proximity(t);
        (q.distance <= reach).then(|| impact(t, q))
    })
}

/// The unit normal of a contact. When the elements are apart at contact (a thickness-wide contact,
/// often vertex to edge), it is the direction of the gap between the closest points, first element's
/// side. When they touch (a crossing caught at its coplanar instant), the gap has no direction and the
/// face direction `face` is used (else the separation at the start, else the velocity), turned to the
/// side the first element came from.
fn contact_normal(
    face: DVec3,
    gap: DVec3,
    apart: bool,
    relative_start: DVec3,
    relative_velocity: DVec3,
) -> DVec3 {
    if apart && let Some(n) = gap.try_normalize() {
        return n;
    }
    let n = [face, relative_start, -relative_velocity]
        .into_iter()
        .map(DVec3::normalize_or_zero)
        .find(|n| *n != DVec3::ZERO)
        .unwrap_or(DVec3::ZERO);
    let mut side = n.dot(relative_start);
    if side == 0.0 {
        side = -n.dot(relative_velocity);
    }
    if side < 0.0 { -n } else { n }
}

/// Earliest t in [0, 1] at which `distance(t) ≤ reach`, when the distance can shrink by at most
/// `speed` per unit t; `None` if there is none. See the module docs.
fn conservative_advancement(
    distance: impl Fn(f64) -> f64,
    speed: f64,
    thickness: f64,
    reach: f64,
) -> Option<f64> {
    let mut t = 0.0;
    for _ in 0..MAX_ADVANCES {
        let d = distance(t);
        if d <= reach {
            return Some(t);
        }
        if speed == 0.0 {
            return None;
        }
        t += (d - thickness) / speed;
        if t > 1.0 || t.is_nan() {
            return None;
        }
    }
    Some(t)
}

/// c₀ + c₁t + c₂t² + c₃t³.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Cubic(pub [f64; 4]);

/// Up to three roots and two critical points, sorted.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Times {
    t: [f64; 8],
    n: usize,
}

impl std::ops::Deref for Times {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.t[..self.n]
    }
}

impl Times {
    fn push(&mut self, t: f64) {
        self.t[self.n] = t;
        self.n += 1;
    }
}

impl Cubic {
    /// (e₀ + t d₀) × (e₁ + t d₁) · (e₂ + t d₂), expanded by multilinearity of the triple product.
    fn triple(e: [DVec3; 3], d: [DVec3; 3]) -> Self {
        let t = |a: DVec3, b: DVec3, c: DVec3| a.cross(b).dot(c);
        Self([
            t(e[0], e[1], e[2]),
            t(d[0], e[1], e[2]) + t(e[0], d[1], e[2]) + t(e[0], e[1], d[2]),
            t(d[0], d[1], e[2]) + t(d[0], e[1], d[2]) + t(e[0], d[1], d[2]),
            t(d[0], d[1], d[2]),
        ])
    }

    /// Whether the cubic is zero to rounding on [0, 1], for a configuration of size `scale` (its
    /// coefficients are volumes, so scale³ is their unit).
    fn vanishes(&self, scale: f64) -> bool {
        self.0.iter().map(|c| c.abs()).sum::<f64>() <= DEGENERATE_TOL * scale.powi(3)
    }

    #[inline]
    fn at(&self, t: f64) -> f64 {
        let [c0, c1, c2, c3] = self.0;
        ((c3 * t + c2) * t + c1) * t + c0
    }

    #[inline]
    fn slope(&self, t: f64) -> f64 {
        let [_, c1, c2, c3] = self.0;
        (3.0 * c3 * t + 2.0 * c2) * t + c1
    }

    /// The roots in [0, 1] and the critical points in (0, 1), in increasing order. See the module docs.
    pub(crate) fn candidate_times(&self) -> Times {
        let [_, c1, c2, c3] = self.0;
        let mut out = Times { t: [0.0; 8], n: 0 };
        let mut breaks = [0.0, 1.0, 1.0, 1.0];
        let mut n_breaks = 1;
        for t in quadratic_roots(3.0 * c3, 2.0 * c2, c1) {
            if t > 0.0 && t < 1.0 {
                breaks[n_breaks] = t;
                n_breaks += 1;
                out.push(t);
            }
        }
        breaks[n_breaks] = 1.0;
        n_breaks += 1;
        breaks[1..n_breaks - 1].sort_by(f64::total_cmp);
        for w in breaks[..n_breaks].windows(2) {
            let (lo, hi) = (w[0], w[1]);
            let (f_lo, f_hi) = (self.at(lo), self.at(hi));
            if f_lo == 0.0 {
                out.push(lo);
            } else if f_hi != 0.0 && (f_lo < 0.0) != (f_hi < 0.0) {
                out.push(self.root_in(lo, hi, f_lo));
            }
        }
        if self.at(1.0) == 0.0 {
            out.push(1.0);
        }
        out.t[..out.n].sort_by(f64::total_cmp);
        out
    }

    /// The root in [lo, hi], where the cubic is monotone and changes sign, f(lo) = `f_lo`: Newton's
    /// method, with bisection whenever a Newton step leaves the current bracket.
    fn root_in(&self, mut lo: f64, mut hi: f64, f_lo: f64) -> f64 {
        let mut t = 0.5 * (lo + hi);
        for _ in 0..100 {
            let f = self.at(t);
            if f == 0.0 {
                return t;
            }
            if (f < 0.0) == (f_lo < 0.0) {
                lo = t;
            } else {
                hi = t;
            }
            let newton = t - f / self.slope(t);
            let next = if newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
            if (next - t).abs() <= 4.0 * f64::EPSILON * t.abs().max(f64::MIN_POSITIVE)
                || hi - lo <= f64::EPSILON
            {
                return next;
            }
            t = next;
        }
        t
    }
}

/// Real roots of a t² + b t + c in the form that avoids cancellation (Numerical Recipes §5.6):
/// q = −(b + sign(b)·√(b² − 4ac))/2, roots q/a and c/q. A zero `a` leaves the linear root.
fn quadratic_roots(a: f64, b: f64, c: f64) -> impl Iterator<Item = f64> {
    let mut roots = [f64::NAN; 2];
    if a == 0.0 {
        if b != 0.0 {
            roots[0] = -c / b;
        }
    } else {
        let disc = b * b - 4.0 * a * c;
        if disc >= 0.0 {
            let q = -0.5 * (b + disc.sqrt().copysign(b));
            if q == 0.0 {
                roots[0] = 0.0;
            } else {
                roots = [q / a, c / q];
            }
        }
    }
    roots.into_iter().filter(|t| t.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn cubic_roots_are_found_in_order_without_the_closed_form() {
        // (t − 0.1)(t − 0.5)(t − 0.9) = t³ − 1.5t² + 0.59t − 0.045: three roots and two extrema.
        let times = Cubic([-0.045, 0.59, -1.5, 1.0]).candidate_times();
        assert_eq!(times.len(), 5, "{:?}", &*times);
        for (got, want) in [times[0], times[2], times[4]].into_iter().zip([0.1, 0.5, 0.9]) {
            assert!(close(got, want, 1e-14), "{got} vs {want}");
        }
        // A double root at 0.3: (t − 0.3)²(t − 2). No sign change there; the critical point finds it.
        let c = Cubic([-0.18, 1.29, -2.6, 1.0]);
        assert!(c.candidate_times().iter().any(|&t| close(t, 0.3, 1e-12)), "{:?}", &*c.candidate_times());
        // Quadratic and linear cases, and a leading coefficient at the edge of the range of f64.
        let t = Cubic([-0.25, 0.0, 1.0, 0.0]).candidate_times();
        assert!(close(t[0], 0.5, 1e-15), "{:?}", &*t);
        let t = Cubic([0.7, -1.0, 0.0, 0.0]).candidate_times();
        assert!(close(t[0], 0.7, 1e-15) && t.len() == 1);
        let t = Cubic([0.7, -1.0, 0.0, 1.0e-300]).candidate_times();
        assert!(close(t[0], 0.7, 1e-15) && t.len() == 1);
        // Small root next to large ones, where the cubic formula cancels: (t − 1e-9)(t − 50)(t + 70).
        let (r0, r1, r2) = (1.0e-9, 50.0, -70.0);
        let c = Cubic([-r0 * r1 * r2, r0 * r1 + r0 * r2 + r1 * r2, -(r0 + r1 + r2), 1.0]);
        let t = c.candidate_times();
        assert!(close(t[0], 1.0e-9, 1e-22), "{:?}", &*t);
        assert!(Cubic([1.0, 1.0, 1.0, 1.0]).candidate_times().is_empty());
    }

    fn tri() -> [DVec3; 3] {
        [DVec3::ZERO, DVec3::X, DVec3::Y]
    }

    fn vt(p: [DVec3; 2], tri0: [DVec3; 3], tri1: [DVec3; 3]) -> ([DVec3; 4], [DVec3; 4]) {
        ([p[0], tri0[0], tri0[1], tri0[2]], [p[1], tri1[0], tri1[1], tri1[2]])
    }

    #[test]
    fn vertex_falling_through_a_triangle_is_caught_at_the_analytic_time() {
        let (s, e) = vt([DVec3::new(0.2, 0.2, 1.0), DVec3::new(0.2, 0.2, -1.0)], tri(), tri());
        let hit = vertex_triangle_impact(s, e, 0.0).unwrap();
        assert!(close(hit.t, 0.5, 1e-14), "{hit:?}");
        assert!(close(hit.normal.z, 1.0, 1e-15) && hit.distance < 1e-12);
        let [w0, w1, w2] = hit.barycentric;
        assert!(close(w0, 0.6, 1e-12) && close(w1, 0.2, 1e-12) && close(w2, 0.2, 1e-12));
        // The triangle rising to z = 0.5 meanwhile: they meet when 1 − 2t = 0.5t, t = 0.4.
        let up = tri().map(|x| x + DVec3::Z * 0.5);
        let (s, e) = vt([DVec3::new(0.2, 0.2, 1.0), DVec3::new(0.2, 0.2, -1.0)], tri(), up);
        let hit = vertex_triangle_impact(s, e, 0.0).unwrap();
        assert!(close(hit.t, 0.4, 1e-14), "{hit:?}");
        // From below: the normal points down, to the vertex's side.
        let (s, e) = vt([DVec3::new(0.2, 0.2, -1.0), DVec3::new(0.2, 0.2, 3.0)], tri(), tri());
        let hit = vertex_triangle_impact(s, e, 0.0).unwrap();
        assert!(close(hit.t, 0.25, 1e-14) && close(hit.normal.z, -1.0, 1e-15), "{hit:?}");
    }

    #[test]
    fn rotating_triangle_is_caught_at_the_first_sign_change() {
        // The triangle tips about the x axis while the vertex moves sideways: a genuine cubic.
        let tipped = [DVec3::ZERO, DVec3::X, DVec3::new(0.0, 0.3, 0.9)];
        let (s, e) = vt([DVec3::new(0.3, 0.8, 0.1), DVec3::new(0.2, 0.1, 0.5)], tri(), tipped);
        let hit = vertex_triangle_impact(s, e, 0.0).expect("the vertex ends on the other side, inside");
        // Reference: the first sign change of the triple product on a fine grid.
        let f = |t: f64| {
            let [p, a, b, c] = [0, 1, 2, 3].map(|i| s[i] + (e[i] - s[i]) * t);
            (b - a).cross(c - a).dot(p - a)
        };
        let k = (1..=100_000).find(|&k| f(k as f64 * 1e-5).signum() != f(0.0).signum()).unwrap();
        assert!(
            hit.t > (k - 1) as f64 * 1e-5 - 1e-12 && hit.t <= k as f64 * 1e-5 + 1e-12,
            "{hit:?} vs {k}e-5"
        );
        assert!(hit.distance < 1e-9);
    }

    #[test]
    fn vertex_passing_beside_a_triangle_is_not_a_contact() {
        // It crosses the plane at (0.55, 0.55), 0.0707 m outside the hypotenuse.
        let (s, e) = vt([DVec3::new(0.55, 0.55, 1.0), DVec3::new(0.55, 0.55, -1.0)], tri(), tri());
        assert_eq!(vertex_triangle_impact(s, e, 0.0), None);
        assert_eq!(vertex_triangle_impact(s, e, 0.05), None);
        let hit = vertex_triangle_impact(s, e, 0.1).expect("within a 0.1 m thickness");
        assert!(close(hit.t, 0.5, 1e-12) && close(hit.barycentric[0], 0.0, 1e-12), "{hit:?}");
        // Moving parallel to the plane above it: never coplanar, no impact (the proximity test's job).
        let (s, e) = vt([DVec3::new(-1.0, 0.2, 0.01), DVec3::new(2.0, 0.2, 0.01)], tri(), tri());
        assert_eq!(vertex_triangle_impact(s, e, 0.001), None);
    }

    #[test]
    fn fast_vertex_through_a_thin_slab_hits_the_near_layer_first() {
        // Two layers 1 mm apart; a vertex at 20 m/s over a 1/60 s step moves 0.333 m.
        let travel = 20.0 / 60.0;
        let big = [DVec3::new(-1.0, -1.0, 0.0), DVec3::new(2.0, -1.0, 0.0), DVec3::new(-1.0, 2.0, 0.0)];
        let top = big.map(|x| x + DVec3::Z * 1.0e-3);
        let p = [DVec3::new(0.1, 0.1, 0.2), DVec3::new(0.1, 0.1, 0.2 - travel)];
        let (s, e) = vt(p, top, top);
        let hit_top = vertex_triangle_impact(s, e, 1.0e-4).unwrap();
        let (s, e) = vt(p, big, big);
        let hit_bottom = vertex_triangle_impact(s, e, 1.0e-4).unwrap();
        assert!(close(hit_top.t, (0.2 - 1.0e-3) / travel, 1e-12), "{hit_top:?}");
        assert!(hit_top.t < hit_bottom.t && close(hit_bottom.t, 0.2 / travel, 1e-12), "{hit_bottom:?}");
    }

    #[test]
    fn crossing_edges_are_caught_at_the_analytic_time() {
        let a = [DVec3::new(0.0, 0.5, 1.0), DVec3::new(1.0, 0.5, 1.0)];
        let b = [DVec3::new(0.25, 0.0, 0.0), DVec3::new(0.25, 1.0, 0.0)];
        let down = DVec3::Z * 2.0;
        let hit =
            edge_edge_impact([a[0], a[1], b[0], b[1]], [a[0] - down, a[1] - down, b[0], b[1]], 0.0).unwrap();
        assert!(
            close(hit.t, 0.5, 1e-14) && close(hit.s[0], 0.25, 1e-12) && close(hit.s[1], 0.5, 1e-12),
            "{hit:?}"
        );
        assert!(close(hit.normal.z, 1.0, 1e-15), "{hit:?}");
        // Shifted so that the segments pass each other without meeting.
        let b = b.map(|x| x + DVec3::X * 1.5);
        assert_eq!(
            edge_edge_impact([a[0], a[1], b[0], b[1]], [a[0] - down, a[1] - down, b[0], b[1]], 0.0),
            None
        );
    }

    #[test]
    fn parallel_edges_moving_together_are_caught_by_advancement() {
        // Coplanar at every instant, so the cubic vanishes identically.
        let a = [DVec3::new(0.0, 0.0, 1.0), DVec3::new(1.0, 0.0, 1.0)];
        let b = [DVec3::new(0.5, 0.0, 0.0), DVec3::new(1.5, 0.0, 0.0)];
        let down = DVec3::Z * 2.0;
        let (s, e) = ([a[0], a[1], b[0], b[1]], [a[0] - down, a[1] - down, b[0], b[1]]);
        let hit = edge_edge_impact(s, e, 1.0e-3).unwrap();
        assert!(close(hit.t, (1.0 - 1.0e-3) / 2.0, 1e-9) && close(hit.normal.z, 1.0, 1e-12), "{hit:?}");
        // Offset sideways by 0.3: the nearest approach, 0.3 m at t = 0.5, decides.
        let side = DVec3::Y * 0.3;
        let (s, e) = (s.map(|x| x + if x.z > 0.5 { side } else { DVec3::ZERO }), e);
        let e = [e[0] + side, e[1] + side, e[2], e[3]];
        assert_eq!(edge_edge_impact(s, e, 0.25), None);
        let hit = edge_edge_impact(s, e, 0.35).unwrap();
        let want = (1.0 - (0.35f64 * 0.35 - 0.09).sqrt()) / 2.0;
        assert!(close(hit.t, want, 1e-9) && close(hit.distance, 0.35, 1e-9), "{hit:?} vs {want}");
    }

    #[test]
    fn vertex_sliding_in_the_plane_of_a_flat_sheet_is_caught_by_advancement() {
        let (s, e) = vt([DVec3::new(-1.0, 0.2, 0.0), DVec3::new(1.0, 0.2, 0.0)], tri(), tri());
        let hit = vertex_triangle_impact(s, e, 1.0e-3).unwrap();
        assert!(close(hit.t, (1.0 - 1.0e-3) / 2.0, 1e-9), "{hit:?}");
        assert!(close(hit.normal.x, -1.0, 1e-12), "{hit:?}");
    }
}
