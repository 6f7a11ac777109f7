//! Static solids and the queries a cloth needs against them: the first crossing of a swept segment (a
//! particle's path over one step, or a cloth edge), ray casts, inside tests and distances.
//!
//! Analytic solids (sphere, half-space, closed vertical cylinder) are answered in closed form. Closed
//! triangle meshes go through parry's 64-bit build (`parry3d-f64`) with its bounding-volume hierarchy:
//! ray casts visit only the boxes the ray crosses, and inside tests use the angle-weighted
//! pseudo-normals of an oriented mesh, so a point just under a face, edge or vertex is classified
//! correctly. Everything is `f64`: a particle resting on a surface moves about 10⁻¹¹ m per step, far
//! below what `f32` resolves at a metre from the origin.

use glam::DVec3;
use parry3d_f64::query::{PointQuery, Ray, RayCast};
use parry3d_f64::shape::{TriMesh, TriMeshFlags};

use crate::halfedge::{HalfEdges, TopologyError};
use crate::{Aabb, TriangleMesh};

/// Where a segment or ray first meets a solid's surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceHit {
    /// Parameter along the query: the hit point is a + s·(b − a) for a segment a → b, and
    /// origin + s·dir for a ray.
    pub s: f64,
    pub point: DVec3,
    /// Unit outward normal of the surface at the hit (for a mesh, of the triangle hit), whichever side
    /// the query came from.
    pub normal: DVec3,
    /// The triangle hit, for meshes.
    pub triangle: Option<u32>,
}

/// The nearest surface point to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Proximity {
    pub point: DVec3,
    /// Unsigned distance to the surface, m.
    pub distance: f64,
    pub inside: bool,
}

/// Why a triangle mesh cannot bound a solid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolidError {
    #[error("the mesh is not an oriented manifold: {0}")]
    Topology(#[from] TopologyError),
    #[error("the mesh is not closed: {0} edges have only one triangle")]
    Open(usize),
    #[error("the mesh encloses negative volume ({0:e} m³): its triangles face inwards")]
    InsideOut(f64),
    #[error("the mesh's volume is out of f64's range ({0:e} m³): its coordinates are too large")]
    OutOfRange(f64),
    #[error("the mesh has no triangles")]
    Empty,
}

/// A ball.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    pub centre: DVec3,
    pub radius: f64,
}

/// Everything on the far side of a plane from its normal: {p : n·(p − point) < 0}. A floor or an
/// incline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfSpace {
    pub point: DVec3,
    /// Unit normal pointing out of the solid.
    pub normal: DVec3,
}

/// A closed solid cylinder with a vertical (+z) axis: a round table top.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    /// Centre of the bottom disc.
    pub base_centre: DVec3,
    pub radius: f64,
    pub height: f64,
}

/// A closed, outward-oriented triangle mesh with its BVH and pseudo-normals.
#[derive(Clone)]
pub struct MeshSolid {
    shape: TriMesh,
    normals: Vec<DVec3>,
    aabb: Aabb,
}

impl std::fmt::Debug for MeshSolid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeshSolid")
            .field("n_vertices", &self.shape.vertices().len())
            .field("n_triangles", &self.shape.indices().len())
            .field("aabb", &self.aabb)
            .finish()
    }
}

/// A static solid a cloth can collide with.
#[derive(Debug, Clone)]
#[expect(clippy::large_enum_variant, reason = "a scene holds a handful of solids; boxing buys nothing")]
pub enum Solid {
    Sphere(Sphere),
    HalfSpace(HalfSpace),
    Cylinder(Cylinder),
    Mesh(MeshSolid),
}

impl Sphere {
    fn first_crossing(&self, a: DVec3, d: DVec3) -> Option<(f64, DVec3)> {
        let f = a - self.centre;
        let (qa, qb, qc) = (d.length_squared(), f.dot(d), f.length_squared() - self.radius * self.radius);
        let disc = qb * qb - qa * qc;
        if qa == 0.0 || disc < 0.0 {
            return None;
        }
        let root = disc.sqrt();
        // From outside (or on the surface) the first crossing is the entry; from inside, the exit.
        let s = if qc >= 0.0 {
            if qb >= 0.0 {
                return None; // moving away from (or grazing) the ball
            }
            (-qb - root) / qa
        } else {
            (-qb + root) / qa
        };
        (0.0..=1.0).contains(&s).then(|| {
            let p = a + d * s;
            (s, (p - self.centre) / self.radius)
        })
    }

    pub fn contains(&self, p: DVec3) -> bool {
        p.distance_squared(self.centre) < self.radius * self.radius
    }

    pub fn proximity(&self, p: DVec3) -> Proximity {
        let r = p - self.centre;
        let len = r.length();
        let dir = if len > 0.0 { r / len } else { DVec3::Z };
        Proximity {
            point: self.centre + dir * self.radius,
            distance: (len - self.radius).abs(),
            inside: len < self.radius,
        }
    }
}

impl HalfSpace {
    /// A half-space bounded by the plane through `point` with outward `normal` (normalised here;
    /// `None` if it is zero or not finite).
    pub fn new(point: DVec3, normal: DVec3) -> Option<Self> {
        Some(Self { point, normal: normal.try_normalize()? })
    }

    fn first_crossing(&self, a: DVec3, d: DVec3) -> Option<(f64, DVec3)> {
        let da = self.normal.dot(a - self.point);
        let db = self.normal.dot(a + d - self.point);
        let crosses = (da >= 0.0 && db < 0.0) || (da < 0.0 && db >= 0.0);
        crosses.then(|| ((da / (da - db)).clamp(0.0, 1.0), self.normal))
    }

    pub fn contains(&self, p: DVec3) -> bool {
        self.normal.dot(p - self.point) < 0.0
    }

    pub fn proximity(&self, p: DVec3) -> Proximity {
        let h = self.normal.dot(p - self.point);
        Proximity { point: p - self.normal * h, distance: h.abs(), inside: h < 0.0 }
    }
}

impl Cylinder {
    fn top(&self) -> f64 {
        self.base_centre.z + self.height
    }

    fn first_crossing(&self, a: DVec3, d: DVec3) -> Option<(f64, DVec3)> {
        let (z0, z1, r2) = (self.base_centre.z, self.top(), self.radius * self.radius);
        let c = self.base_centre.truncate();
        let (fa, dxy) = (a.truncate() - c, d.truncate());
        let mut best: Option<(f64, DVec3)> = None;
        let mut consider = |s: f64, normal: DVec3| {
            if (0.0..=1.0).contains(&s) && best.is_none_or(|(b, _)| s < b) {
                best = Some((s, normal));
            }
        };
        // The side: |fa + s·dxy|² = R² with z(s) within the height.
        let (qa, qb, qc) = (dxy.length_squared(), fa.dot(dxy), fa.length_squared() - r2);
        let disc = qb * qb - qa * qc;
        if qa > 0.0 && disc >= 0.0 {
            let root = disc.sqrt();
            for s in [(-qb - root) / qa, (-qb + root) / qa] {
                let p = a + d * s;
                if (z0..=z1).contains(&p.z) {
                    let n = (p.truncate() - c) / self.radius;
                    consider(s, n.extend(0.0));
                }
            }
        }
        // The two caps.
        if d.z != 0.0 {
            for (z, n) in [(z0, DVec3::NEG_Z), (z1, DVec3::Z)] {
                let s = (z - a.z) / d.z;
                if (fa + dxy * s).length_squared() <= r2 {
                    consider(s, n);
                }
            }
        }
        best
    }

    pub fn contains(&self, p: DVec3) -> bool {
        (p.truncate() - self.base_centre.truncate()).length_squared() < self.radius * self.radius
            && p.z > self.base_centre.z
            && p.z < self.top()
    }

    pub fn proximity(&self, p: DVec3) -> Proximity {
        let (z0, z1) = (self.base_centre.z, self.top());
        let c = self.base_centre.truncate();
        let rxy = p.truncate() - c;
        let r = rxy.length();
        let radial = if r > 0.0 { rxy / r } else { glam::DVec2::X };
        if self.contains(p) {
            // The nearest of the side and the two caps.
            let (side, below, above) = (self.radius - r, p.z - z0, z1 - p.z);
            let point = if side <= below && side <= above {
                (c + radial * self.radius).extend(p.z)
            } else if below <= above {
                p.truncate().extend(z0)
            } else {
                p.truncate().extend(z1)
            };
            return Proximity { point, distance: side.min(below).min(above), inside: true };
        }
        let clamped_r = r.min(self.radius);
        let point = (c + radial * clamped_r).extend(p.z.clamp(z0, z1));
        Proximity { point, distance: p.distance(point), inside: false }
    }
}

impl MeshSolid {
    /// Prepares a closed, outward-facing triangle mesh: checks its topology and orientation, then builds
    /// parry's BVH and pseudo-normals.
    pub fn new(mesh: &TriangleMesh) -> Result<Self, SolidError> {
        if mesh.n_triangles() == 0 {
            return Err(SolidError::Empty);
        }
        let topology = HalfEdges::new(mesh.n_vertices(), mesh.triangles())?;
        let open = topology.n_boundary_edges();
        if open > 0 {
            return Err(SolidError::Open(open));
        }
        let volume = mesh.signed_volume();
        if !volume.is_finite() {
            return Err(SolidError::OutOfRange(volume));
        }
        if volume <= 0.0 {
            return Err(SolidError::InsideOut(volume));
        }
        let normals = (0..mesh.n_triangles())
            .map(|t| {
                let [a, b, c] = mesh.corners(t);
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect();
        let shape =
            TriMesh::with_flags(mesh.vertices().to_vec(), mesh.triangles().to_vec(), TriMeshFlags::ORIENTED)
                .map_err(|_| SolidError::Empty)?;
        // The topology check above is parry's own condition for pseudo-normals.
        debug_assert!(shape.pseudo_normals().is_some());
        Ok(Self { shape, normals, aabb: mesh.aabb() })
    }

    pub fn n_triangles(&self) -> usize {
        self.normals.len()
    }

    fn first_crossing(&self, a: DVec3, d: DVec3) -> Option<(f64, DVec3, u32)> {
        let hit = self.shape.cast_local_ray_and_get_normal(&Ray::new(a, d), 1.0, false)?;
        let t = hit.subshape;
        Some((hit.time_of_impact, self.normals[t as usize], t))
    }

    pub fn contains(&self, p: DVec3) -> bool {
        self.aabb.contains(p) && self.shape.contains_local_point(p)
    }

    pub fn proximity(&self, p: DVec3) -> Proximity {
        use parry3d_f64::query::PointQueryWithLocation;
        let (proj, _) = self.shape.project_local_point_and_get_location(p, false);
        Proximity { point: proj.point, distance: p.distance(proj.point), inside: proj.is_inside }
    }

    /// The mesh's vertices and triangles, for pictures.
    pub fn to_mesh(&self) -> TriangleMesh {
        TriangleMesh::new(self.shape.vertices().to_vec(), self.shape.indices().to_vec())
            .expect("validated when the solid was built")
    }
}

impl Solid {
    /// The first point where the segment a → b meets the surface (s ∈ [0, 1]), entering or leaving.
    /// A segment of zero length meets nothing.
    pub fn segment_hit(&self, a: DVec3, b: DVec3) -> Option<SurfaceHit> {
        let d = b - a;
        if d == DVec3::ZERO {
            return None;
        }
        let (s, normal, triangle) = match self {
            Solid::Sphere(x) => x.first_crossing(a, d).map(|(s, n)| (s, n, None))?,
            Solid::HalfSpace(x) => x.first_crossing(a, d).map(|(s, n)| (s, n, None))?,
            Solid::Cylinder(x) => x.first_crossing(a, d).map(|(s, n)| (s, n, None))?,
            Solid::Mesh(x) => x.first_crossing(a, d).map(|(s, n, t)| (s, n, Some(t)))?,
        };
        Some(SurfaceHit { s, point: a + d * s, normal, triangle })
    }

    /// The first crossing of the ray origin + s·dir, 0 ≤ s ≤ max_s.
    pub fn ray_hit(&self, origin: DVec3, dir: DVec3, max_s: f64) -> Option<SurfaceHit> {
        let mut hit = self.segment_hit(origin, origin + dir * max_s)?;
        hit.s *= max_s;
        Some(hit)
    }

    /// Whether `p` is strictly inside (a point on the surface may go either way).
    pub fn contains(&self, p: DVec3) -> bool {
        match self {
            Solid::Sphere(x) => x.contains(p),
            Solid::HalfSpace(x) => x.contains(p),
            Solid::Cylinder(x) => x.contains(p),
            Solid::Mesh(x) => x.contains(p),
        }
    }

    /// The nearest surface point.
    pub fn proximity(&self, p: DVec3) -> Proximity {
        match self {
            Solid::Sphere(x) => x.proximity(p),
            Solid::HalfSpace(x) => x.proximity(p),
            Solid::Cylinder(x) => x.proximity(p),
            Solid::Mesh(x) => x.proximity(p),
        }
    }

    /// Whether `p` is inside or closer than `d` to the surface: what [`Solid::proximity`] answers
    /// (`inside || distance < d`), without its query where [`Solid::surely_beyond`] rules it out.
    pub fn near(&self, p: DVec3, d: f64) -> bool {
        if self.surely_beyond(p, d) {
            return false;
        }
        let prox = self.proximity(p);
        prox.inside || prox.distance < d
    }

    /// Whether `p` is certainly outside and farther than `d` from the surface, by a test that costs no
    /// query: it lies more than `d` outside a mesh's bounding box. `false` says nothing (every point of
    /// an analytic solid, whose query is cheap anyway).
    pub fn surely_beyond(&self, p: DVec3, d: f64) -> bool {
        matches!(self, Solid::Mesh(x) if x.aabb.distance_to(p) > d.max(0.0))
    }

    /// A lower bound on the distance from `p` to the surface, cheaper than [`Solid::proximity`] far
    /// from a mesh (the distance to its bounding box).
    pub fn clearance(&self, p: DVec3) -> f64 {
        match self {
            Solid::Mesh(x) => {
                let outside = x.aabb.distance_to(p);
                if outside > 0.0 { outside } else { x.proximity(p).distance }
            }
            other => other.proximity(p).distance,
        }
    }

    /// The highest point of the solid (largest z; the first such vertex of a mesh, the centre of a
    /// cylinder's top); `None` for a half-space, which has none or is unbounded.
    pub fn highest_point(&self) -> Option<DVec3> {
        match self {
            Solid::Sphere(s) => Some(s.centre + DVec3::Z * s.radius),
            Solid::HalfSpace(_) => None,
            Solid::Cylinder(c) => Some(c.base_centre + DVec3::Z * c.height),
            Solid::Mesh(m) => m.shape.vertices().iter().copied().reduce(|a, b| if b.z > a.z { b } else { a }),
        }
    }

    /// Bounding box (infinite for a half-space).
    pub fn aabb(&self) -> Aabb {
        match self {
            Solid::Sphere(s) => Aabb { min: s.centre - s.radius, max: s.centre + s.radius },
            Solid::HalfSpace(_) => Aabb { min: DVec3::NEG_INFINITY, max: DVec3::INFINITY },
            Solid::Cylinder(c) => Aabb {
                min: c.base_centre - DVec3::new(c.radius, c.radius, 0.0),
                max: c.base_centre + DVec3::new(c.radius, c.radius, c.height),
            },
            Solid::Mesh(m) => m.aabb,
        }
    }
}

impl TriangleMesh {
    /// Volume enclosed by a closed mesh, positive when its triangles face outwards (divergence theorem).
    pub fn signed_volume(&self) -> f64 {
        (0..self.n_triangles())
            .map(|t| {
                let [a, b, c] = self.corners(t);
                a.dot(b.cross(c))
            })
            .sum::<f64>()
            / 6.0
    }
}

impl Aabb {
    /// Whether `p` lies in the closed box.
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Distance from `p` to the box (zero inside).
    pub fn distance_to(&self, p: DVec3) -> f64 {
        let outside = (self.min - p).max(p - self.max).max(DVec3::ZERO);
        outside.length()
    }
}

/// Triangle meshes of the analytic solids, for pictures.
pub mod tessellate {
    use std::f64::consts::TAU;

    use glam::DVec3;

    use super::{Cylinder, HalfSpace, Sphere};
    use crate::TriangleMesh;

    /// A latitude–longitude sphere with `segments` around and `segments / 2` from pole to pole.
    pub fn sphere(s: &Sphere, segments: usize) -> TriangleMesh {
        let (n_around, n_rings) = (segments.max(3), (segments / 2).max(2));
        let mut v = vec![s.centre + DVec3::Z * s.radius];
        for ring in 1..n_rings {
            let polar = std::f64::consts::PI * ring as f64 / n_rings as f64;
            for k in 0..n_around {
                let az = TAU * k as f64 / n_around as f64;
                let dir = DVec3::new(polar.sin() * az.cos(), polar.sin() * az.sin(), polar.cos());
                v.push(s.centre + dir * s.radius);
            }
        }
        v.push(s.centre - DVec3::Z * s.radius);
        let (south, ring_start) = ((v.len() - 1) as u32, |r: usize| (1 + r * n_around) as u32);
        let mut t = Vec::new();
        for k in 0..n_around as u32 {
            let k1 = (k + 1) % n_around as u32;
            t.push([0, ring_start(0) + k, ring_start(0) + k1]);
            for r in 0..n_rings - 2 {
                let (a, b) = (ring_start(r), ring_start(r + 1));
                t.push([a + k, b + k, b + k1]);
                t.push([a + k, b + k1, a + k1]);
            }
            let last = ring_start(n_rings - 2);
            t.push([last + k, south, last + k1]);
        }
        TriangleMesh::new(v, t).expect("indices are in range by construction")
    }

    /// A closed cylinder with `segments` sides.
    pub fn cylinder(c: &Cylinder, segments: usize) -> TriangleMesh {
        let n = segments.max(3);
        let mut v = vec![c.base_centre, c.base_centre + DVec3::Z * c.height];
        for z in [0.0, c.height] {
            for k in 0..n {
                let az = TAU * k as f64 / n as f64;
                v.push(c.base_centre + DVec3::new(c.radius * az.cos(), c.radius * az.sin(), z));
            }
        }
        let (bottom, top) = (2u32, 2 + n as u32);
        let mut t = Vec::new();
        for k in 0..n as u32 {
            let k1 = (k + 1) % n as u32;
            t.push([0, bottom + k1, bottom + k]);
            t.push([1, top + k, top + k1]);
            t.push([bottom + k, bottom + k1, top + k1]);
            t.push([bottom + k, top + k1, top + k]);
        }
        TriangleMesh::new(v, t).expect("indices are in range by construction")
    }

    /// A square patch of the boundary plane, `half_size` from `centre` (projected onto the plane).
    pub fn plane_patch(h: &HalfSpace, centre: DVec3, half_size: f64) -> TriangleMesh {
        let n = h.normal;
        let u = n.any_orthonormal_vector();
        let w = n.cross(u);
        let c = centre - n * n.dot(centre - h.point);
        let v = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(a, b)| c + (u * a + w * b) * half_size)
            .to_vec();
        TriangleMesh::new(v, vec![[0, 1, 2], [0, 2, 3]]).expect("indices are in range by construction")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::box_mesh;

    fn solids() -> Vec<Solid> {
        vec![
            Solid::Sphere(Sphere { centre: DVec3::new(0.1, 0.2, 0.3), radius: 0.25 }),
            Solid::HalfSpace(HalfSpace::new(DVec3::new(0.0, 0.0, 0.3), DVec3::new(0.1, 0.0, 1.0)).unwrap()),
            Solid::Cylinder(Cylinder { base_centre: DVec3::new(0.1, 0.2, 0.0), radius: 0.35, height: 0.4 }),
            Solid::Mesh(
                MeshSolid::new(&box_mesh(DVec3::new(-0.2, 0.0, 0.1), DVec3::new(0.4, 0.5, 0.45))).unwrap(),
            ),
            Solid::Mesh(
                MeshSolid::new(&tessellate::sphere(
                    &Sphere { centre: DVec3::new(0.0, 0.1, 0.2), radius: 0.3 },
                    48,
                ))
                .unwrap(),
            ),
        ]
    }

    /// A deterministic scatter of points in a box.
    fn points(n: usize) -> Vec<DVec3> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n).map(|_| DVec3::new(next() - 0.45, next() - 0.3, next() - 0.1) * 1.2).collect()
    }

    #[test]
    fn segment_hits_agree_with_inside_tests() {
        // A segment from outside to inside crosses the surface first at a point where the inside test
        // flips; the hit normal points against the segment when entering.
        for solid in solids() {
            let pts = points(400);
            let mut entering = 0;
            for w in pts.windows(2) {
                let (a, b) = (w[0], w[1]);
                let hit = solid.segment_hit(a, b);
                if !solid.contains(a) && solid.contains(b) {
                    let hit = hit.unwrap_or_else(|| panic!("{solid:?}: {a} → {b} enters without a hit"));
                    assert!(hit.normal.dot(b - a) <= 1e-12, "{solid:?}: entering normal {}", hit.normal);
                    assert!(solid.proximity(hit.point).distance < 1e-9);
                    assert!((hit.normal.length() - 1.0).abs() < 1e-12);
                    entering += 1;
                }
                if let Some(h) = hit {
                    assert!((0.0..=1.0).contains(&h.s));
                    assert!(!solid.contains(a + (b - a) * h.s * 0.999_999) || solid.contains(a));
                }
            }
            assert!(entering > 5, "{solid:?}: only {entering} entering segments tested");
        }
    }

    #[test]
    fn proximity_agrees_with_contains_and_clearance_is_a_lower_bound() {
        for solid in solids() {
            for p in points(300) {
                let prox = solid.proximity(p);
                assert_eq!(prox.inside, solid.contains(p), "{solid:?} at {p}");
                assert!(solid.clearance(p) <= prox.distance + 1e-15);
                assert!((p.distance(prox.point) - prox.distance).abs() < 1e-12);
            }
        }
    }

    /// `near` answers what `proximity` does, for every solid, at distances across the bounding box's
    /// margin (points are spread in and around the solids, and far off them).
    #[test]
    fn near_answers_what_proximity_does() {
        let mut far = 0;
        for solid in solids() {
            for p in points(300).into_iter().chain(points(300).into_iter().map(|p| p * 3.0)) {
                for d in [0.0, 0.01, 0.1, 0.5] {
                    let prox = solid.proximity(p);
                    assert_eq!(solid.near(p, d), prox.inside || prox.distance < d, "{p} at {d}");
                    assert!(!solid.surely_beyond(p, d) || (!prox.inside && prox.distance > d), "{p} at {d}");
                    if let Solid::Mesh(m) = &solid {
                        far += usize::from(m.aabb.distance_to(p) > d);
                    }
                }
            }
        }
        assert!(far > 100, "only {far} points took the bounding box's answer");
    }

    #[test]
    fn mesh_sphere_is_close_to_the_analytic_one() {
        let s = Sphere { centre: DVec3::ZERO, radius: 1.0 };
        let m = Solid::Mesh(MeshSolid::new(&tessellate::sphere(&s, 64)).unwrap());
        let hit = m.segment_hit(DVec3::new(0.01, 0.02, 3.0), DVec3::new(0.01, 0.02, 0.0)).unwrap();
        assert!((hit.point.z - 1.0).abs() < 2e-3 && hit.normal.z > 0.99, "{hit:?}");
        assert!(m.contains(DVec3::new(0.5, 0.5, 0.5)) && !m.contains(DVec3::new(0.8, 0.8, 0.8)));
        let ray = m.ray_hit(DVec3::ZERO, DVec3::X, 5.0).unwrap();
        assert!((ray.s - 1.0).abs() < 2e-3 && ray.normal.x > 0.99);
    }

    #[test]
    fn open_and_inside_out_meshes_are_refused() {
        let b = box_mesh(DVec3::ZERO, DVec3::ONE);
        let open = TriangleMesh::new(b.vertices().to_vec(), b.triangles()[1..].to_vec()).unwrap();
        assert_eq!(MeshSolid::new(&open).unwrap_err(), SolidError::Open(3));
        let flipped: Vec<[u32; 3]> = b.triangles().iter().map(|&[a, b, c]| [a, c, b]).collect();
        let flipped = TriangleMesh::new(b.vertices().to_vec(), flipped).unwrap();
        assert!(matches!(MeshSolid::new(&flipped), Err(SolidError::InsideOut(_))));
    }

    #[test]
    fn tessellations_are_closed_and_outward() {
        for m in [
            tessellate::sphere(&Sphere { centre: DVec3::ONE, radius: 0.5 }, 24),
            tessellate::cylinder(&Cylinder { base_centre: DVec3::ZERO, radius: 0.35, height: 0.03 }, 64),
        ] {
            assert!(MeshSolid::new(&m).is_ok());
        }
    }
}
