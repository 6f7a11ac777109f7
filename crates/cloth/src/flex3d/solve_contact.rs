//! FLEX3D's static objects as the implicit solve sees them (`ModelOptions::object_contact` = `InSolve`): their
//! triangles, found through the broad-phase grid, give each particle at most one contact plane per
//! Newton iterate.

use anima_geom::{Aabb, DVec3, PreparedTriangle, segment_triangle};
use anima_ode::contact::{Contact, ContactModel};

use super::broadphase::TriangleGrid;

/// The contact planes keep particles this fraction of the smallest grid spacing off a surface: enough
/// that round-off cannot put a resting particle on the wrong side of a two-sided sheet of triangles.
pub(crate) const THICKNESS_OF_SPACING: f64 = 5e-3;

/// Static triangles (prepared, with their corners) and the grid that bins them.
#[derive(Debug)]
pub(crate) struct StaticContacts<'a> {
    pub prepared: &'a [PreparedTriangle],
    pub corners: &'a [[DVec3; 3]],
    pub grid: &'a mut TriangleGrid,
    /// How far off a surface the contact plane lies, scene units.
    pub thickness: f64,
    /// Coulomb coefficient (the scene's `ATRITO`).
    pub friction: f64,
}

impl ContactModel<DVec3> for StaticContacts<'_> {
    /// A particle whose path crosses a triangle is in contact there; one that ends within twice the
    /// thickness of a triangle, at its nearest point. The objects are open sheets of triangles (a table top), so
    /// the normal is turned towards the side the particle started on.
    fn contacts(&mut self, start: &[DVec3], end: &[DVec3], out: &mut Vec<Contact<DVec3>>) {
        // Within twice the thickness a particle is reported: a resting one is found at once and keeps its
        // regime from step to step.
        let reach = 2.0 * self.thickness;
        let grow = DVec3::splat(reach);
        // Pinned particles are reported too; the solve ignores contacts of prescribed coordinates.
        for p in 0..start.len() {
            let (a, b) = (start[p], end[p]);
            let seg = Aabb { min: a.min(b) - grow, max: a.max(b) + grow };
            // (path parameter or 1 + distance, surface point, triangle), the crossing first.
            let mut best: Option<(f64, DVec3, usize)> = None;
            let (prepared, corners, thickness) = (self.prepared, self.corners, self.thickness);
            self.grid.query(&seg, |t| {
                let tri = &prepared[t];
                if tri.is_degenerate() {
                    return;
                }
                let found = match segment_triangle(a, b - a, tri) {
                    Some(hit) => Some((hit.s, a + (b - a) * hit.s)),
                    None => {
                        let q = closest_point_on_triangle(b, corners[t]);
                        let d = q.distance(b);
                        (d < 2.0 * thickness).then_some((1.0 + d, q))
                    }
                };
                if let Some((key, q)) = found
                    && best.is_none_or(|(k, _, bt)| key < k || (key == k && t < bt))
                {
                    best = Some((key, q, t));
                }
            });
            if let Some((_, q, t)) = best {
                let n = prepared[t].unit_normal();
                let side = n.dot(a - corners[t][0]);
                let normal = if side < 0.0 { -n } else { n };
                out.push(Contact {
                    coordinate: p as u32,
                    normal,
                    point: q + normal * thickness,
                    static_friction: self.friction,
                    kinetic_friction: self.friction,
                    restitution: 0.0,
                });
            }
        }
    }
}

/// The point of triangle `[a, b, c]` nearest to `p` (Ericson, "Real-Time Collision Detection", 2005,
/// §5.1.5: Voronoi regions of the vertices, then the edges, then the face).
pub(crate) fn closest_point_on_triangle(p: DVec3, [a, b, c]: [DVec3; 3]) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn closest_points_in_every_region() {
        let tri = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let cases = [
            (DVec3::new(0.2, 0.2, 1.0), DVec3::new(0.2, 0.2, 0.0)),
            (DVec3::new(-1.0, -1.0, 0.5), DVec3::ZERO),
            (DVec3::new(2.0, -0.5, 0.0), DVec3::X),
            (DVec3::new(0.5, -1.0, 0.0), DVec3::new(0.5, 0.0, 0.0)),
            (DVec3::new(1.0, 1.0, 0.0), DVec3::new(0.5, 0.5, 0.0)),
            (DVec3::new(-1.0, 0.5, 2.0), DVec3::new(0.0, 0.5, 0.0)),
        ];
        for (p, expected) in cases {
            let q = closest_point_on_triangle(p, tri);
            assert!((q - expected).length() < 1e-12, "{p}: {q} instead of {expected}");
        }
    }
}
