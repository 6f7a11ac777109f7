//! Collision response against static objects (Oliveira 2013 §4.4.2.1, Eqs. 4.16–4.18): after each
//! step, each particle's path is cast against the objects; a particle whose path meets a surface gets
//! an instantaneous velocity change, repulsion after Parent (2012) and friction after Bridson, Fedkiw
//! and Anderson (2002), and restarts from where it began the step.

use anima_geom::{DVec3, Solid};
use anima_ode::contact::{Contact, ContactModel};
use anima_ode::{State, parallel};

use super::scene::{ContactVelocity, Options, SeparatingContact};

/// A static object as the cloth sees it.
#[derive(Debug, Clone)]
pub struct Collider {
    pub name: String,
    pub solid: Solid,
    /// μ of the object.
    pub friction: f64,
}

/// The velocity after a hit (Eqs. 4.16–4.17), from the velocity `v` before it, the surface's unit
/// outward normal `n`, the restitution γ and the contact's friction μ (the mean of the cloth's and the
/// object's):
///
/// v̄_R = v − (1 + γ) v_N,  v_N = (v·n̂) n̂;
/// v̄_T = max(1 − μ Δv_N/|v_T|, 0) v_T,  Δv_N = (v̄_R − v)·n̂,  v_T = v − v_N;
/// v̄ = (v̄_R·n̂) n̂ + v̄_T.
///
/// With [`SeparatingContact::KeepVelocity`] a particle already moving away (v·n̂ ≥ 0) keeps `v`.
#[inline]
pub fn contact_velocity(
    v: DVec3,
    n: DVec3,
    restitution: f64,
    mu: f64,
    separating: SeparatingContact,
) -> DVec3 {
    let vn = v.dot(n);
    if vn >= 0.0 && separating == SeparatingContact::KeepVelocity {
        return v;
    }
    let v_normal = n * vn;
    let v_r = v - v_normal * (1.0 + restitution);
    let dvn = (v_r - v).dot(n);
    let v_t = v - v_normal;
    let vt_len = v_t.length();
    let v_t_after = if vt_len > 0.0 { v_t * (1.0 - mu * dvn / vt_len).max(0.0) } else { DVec3::ZERO };
    n * v_r.dot(n) + v_t_after
}

/// The first crossing of the segment a → b with any object: (path parameter, unit outward normal,
/// object index), ties going to the earlier object.
pub fn first_hit(colliders: &[Collider], a: DVec3, b: DVec3) -> Option<(f64, DVec3, usize)> {
    let mut first: Option<(f64, DVec3, usize)> = None;
    for (k, o) in colliders.iter().enumerate() {
        if let Some(hit) = o.solid.segment_hit(a, b)
            && first.is_none_or(|(s, _, _)| hit.s < s)
        {
            first = Some((hit.s, hit.normal, k));
        }
    }
    first
}

/// How many times a corrected path is re-tested before the particle is held where it started.
pub const MAX_RECHECKS: usize = 3;

/// The collision pass after one step: everything it reads, borrowed from the cloth.
#[derive(Debug, Clone, Copy)]
pub struct ContactPass<'a> {
    pub colliders: &'a [Collider],
    pub dt: f64,
    /// γ of Eq. 4.16.
    pub restitution: f64,
    /// μ of the cloth.
    pub friction: f64,
    pub options: &'a Options,
}

impl ContactPass<'_> {
    /// The new state of a particle that starts the step at `x0` with velocity `v` and hits object `k`
    /// with outward normal `normal`: Eqs. 4.16–4.17 for the velocity, x̄ = x0 + v̄·Δt (Eq. 4.18). With
    /// `Options::recheck_corrected_path` the corrected path x0 → x̄ is cast again and a crossing is
    /// answered the same way (up to [`MAX_RECHECKS`] times; after that the particle stays at x0 at rest).
    pub fn resolve(&self, x0: DVec3, mut v: DVec3, mut normal: DVec3, mut k: usize) -> (DVec3, DVec3) {
        let mut x = x0;
        for attempt in 0..=MAX_RECHECKS {
            let mu = 0.5 * (self.friction + self.colliders[k].friction);
            v = contact_velocity(v, normal, self.restitution, mu, self.options.separating);
            x = x0 + v * self.dt;
            if !self.options.recheck_corrected_path {
                break;
            }
            match first_hit(self.colliders, x0, x) {
                None => break,
                Some(_) if attempt == MAX_RECHECKS => {
                    // Wedged in a crease: every corrected path crosses a surface.
                    (x, v) = (x0, DVec3::ZERO);
                }
                Some((_, n, obj)) => (normal, k) = (n, obj),
            }
        }
        (x, v)
    }

    fn velocity_before(&self, now: &State<DVec3>, next: &State<DVec3>, i: usize) -> DVec3 {
        match self.options.contact_velocity {
            ContactVelocity::StartOfStep => now.v[i],
            ContactVelocity::EndOfStep => next.v[i],
        }
    }

    /// Type-2 tests (§4.4.2.1): casts each particle's path x^t → x over the step and answers the first
    /// hit. A path shorter than the particle's `clearance` (a lower bound on its distance from every
    /// surface) cannot hit and is not cast when `Options::cull_collision_tests` is on. Marks the particles
    /// hit in `responded` and returns how many there were.
    pub fn particles(
        &self,
        now: &State<DVec3>,
        next: &mut State<DVec3>,
        clearance: &mut [f64],
        responded: &mut [bool],
    ) -> usize {
        let cull = self.options.cull_collision_tests;
        let mut hits = 0;
        for i in 0..now.x.len() {
            responded[i] = false;
            let (a, b) = (now.x[i], next.x[i]);
            let path = a.distance(b);
            if cull && path < clearance[i] {
                clearance[i] -= path;
                continue;
            }
            let Some((_, normal, k)) = first_hit(self.colliders, a, b) else {
                if cull {
                    // A little less than the distance, so round-off in it cannot let a path through.
                    let d = self.colliders.iter().map(|o| o.solid.clearance(b)).fold(f64::INFINITY, f64::min);
                    clearance[i] = d * (1.0 - 1e-9) - 1e-12;
                }
                continue;
            };
            (next.x[i], next.v[i]) = self.resolve(a, self.velocity_before(now, next, i), normal, k);
            clearance[i] = 0.0;
            responded[i] = true;
            hits += 1;
        }
        hits
    }

    /// Type-1 tests answered as the thesis answers edges that may no longer be refined (§4.4.2.1,
    /// each edge's segment at the end of the step is cast against the objects, and on a hit
    /// both endpoints not already answered this step are treated as type-2 hits on that face, from their
    /// start-of-step state. Returns how many endpoints were answered.
    pub fn edges(
        &self,
        ends: &[[u32; 2]],
        now: &State<DVec3>,
        next: &mut State<DVec3>,
        clearance: &mut [f64],
        responded: &mut [bool],
    ) -> usize {
        let cull = self.options.cull_collision_tests;
        let mut answered = 0;
        for &[a, b] in ends {
            let (a, b) = (a as usize, b as usize);
            let (xa, xb) = (next.x[a], next.x[b]);
            // Every point of the edge is within |e| of both ends in total, so it cannot reach a
            // surface when their clearances add up to more than its length.
            if cull && clearance[a] + clearance[b] > xa.distance(xb) {
                continue;
            }
            let Some((_, normal, k)) = first_hit(self.colliders, xa, xb) else { continue };
            for i in [a, b] {
                if !responded[i] {
                    (next.x[i], next.v[i]) =
                        self.resolve(now.x[i], self.velocity_before(now, next, i), normal, k);
                    clearance[i] = 0.0;
                    responded[i] = true;
                    answered += 1;
                }
            }
        }
        answered
    }
}

/// How far outside a surface the solve keeps a particle in contact, m: enough that round-off cannot put
/// a particle resting on a surface strictly inside it, far below the cloth's 62.5 mm spacing.
pub const SOLVE_CONTACT_THICKNESS_M: f64 = 1e-4;

/// Per particle, a position and a lower bound on its distance from every surface there, kept between
/// the queries of the in-solve contact model so that particles far from every object cost a subtraction.
#[derive(Debug, Clone, Default)]
pub struct ClearanceCache {
    reference: Vec<DVec3>,
    clearance: Vec<f64>,
    /// Per particle, the contact the last query found (scratch, listed in particle order after it).
    found: Vec<Option<Contact<DVec3>>>,
}

impl ClearanceCache {
    /// Forgets every bound (for a new particle count).
    pub fn reset(&mut self, n: usize) {
        self.reference.clear();
        self.reference.resize(n, DVec3::ZERO);
        self.clearance.clear();
        self.clearance.resize(n, 0.0);
        self.found.clear();
        self.found.resize(n, None);
    }

    /// Carries the bounds over to a changed set of particles: particle k takes the reference point and
    /// bound of old particle `sources[k]` (none, and so a query at its next step, when that is out of
    /// range). A bound is a distance from its reference point to every surface, not a property of the
    /// particle that had it, so it holds for whichever particle inherits it; one inherited from the
    /// particle a remesh made it from (its parent) skips that particle's queries while it stays in the
    /// open, as the parent's would have. The queries answered are the same as with a reset cache.
    pub fn inherit(&mut self, sources: &[u32]) {
        let old = (std::mem::take(&mut self.reference), std::mem::take(&mut self.clearance));
        let take = |k: u32| {
            let k = k as usize;
            if k < old.0.len() && k < old.1.len() { (old.0[k], old.1[k]) } else { (DVec3::ZERO, 0.0) }
        };
        (self.reference, self.clearance) = sources.iter().map(|&k| take(k)).unzip();
        self.found.clear();
        self.found.resize(sources.len(), None);
    }
}

/// The objects as the implicit solve sees them ([`super::scene::Options::contact`] = `InSolve`): a
/// particle whose path crosses a surface is in contact at the crossing, one that ends inside or within
/// twice [`SOLVE_CONTACT_THICKNESS_M`] of a surface at its nearest point; the contact plane is moved out
/// by that thickness. Friction μ is the mean of the cloth's and the object's (Eq. 4.17), the restitution γ of
/// Eq. 4.16.
#[derive(Debug)]
pub struct SolveContacts<'a> {
    pub colliders: &'a [Collider],
    /// μ of the cloth.
    pub friction: f64,
    pub restitution: f64,
    pub cache: &'a mut ClearanceCache,
}

impl ContactModel<DVec3> for SolveContacts<'_> {
    /// Every particle's query on its own, on every core (`anima_ode::parallel`), the contacts then listed
    /// in particle order: the same list on any thread count.
    fn contacts(&mut self, start: &[DVec3], end: &[DVec3], out: &mut Vec<Contact<DVec3>>) {
        let thickness = SOLVE_CONTACT_THICKNESS_M;
        if self.cache.reference.len() != start.len() {
            self.cache.reset(start.len());
        }
        let (colliders, friction, restitution) = (self.colliders, self.friction, self.restitution);
        let cache = &mut *self.cache;
        let ClearanceCache { reference, clearance, found } = cache;
        parallel::for_chunks3(reference, clearance, found, |s, reference, clearance, found| {
            for (k, ((reference, clearance), found)) in
                reference.iter_mut().zip(clearance.iter_mut()).zip(found.iter_mut()).enumerate()
            {
                let i = s + k;
                *found = None;
                let (a, b) = (start[i], end[i]);
                // Every point of the path lies within max(|a − r|, |b − r|) of the reference point r.
                let reach = a.distance(*reference).max(b.distance(*reference));
                if *clearance - reach > thickness {
                    continue;
                }
                let hit = match first_hit(colliders, a, b) {
                    Some((s, normal, k)) => Some((a + (b - a) * s, normal, k)),
                    // Within twice the thickness: a resting particle is found at once and keeps its
                    // regime.
                    None => nearest(colliders, b, 2.0 * thickness),
                };
                *reference = b;
                match hit {
                    Some((surface, normal, k)) => {
                        *clearance = 0.0;
                        let mu = 0.5 * (friction + colliders[k].friction);
                        *found = Some(Contact {
                            coordinate: i as u32,
                            normal,
                            point: surface + normal * thickness,
                            static_friction: mu,
                            kinetic_friction: mu,
                            restitution,
                        });
                    }
                    None => {
                        let d = colliders.iter().map(|o| o.solid.clearance(b)).fold(f64::INFINITY, f64::min);
                        // A little less than the distance, so round-off in it cannot let a path through.
                        *clearance = d * (1.0 - 1e-9) - 1e-12;
                    }
                }
            }
        });
        out.extend(cache.found.iter().flatten());
    }
}

/// The surface point nearest to `p`, its outward normal and the object, when `p` is inside an object or
/// closer than `thickness` to one (the deepest or nearest first).
fn nearest(colliders: &[Collider], p: DVec3, thickness: f64) -> Option<(DVec3, DVec3, usize)> {
    let mut best: Option<(f64, DVec3, DVec3, usize)> = None;
    for (k, o) in colliders.iter().enumerate() {
        // (A half-space's clearance is its unsigned distance, so the inside test comes first.)
        if !o.solid.contains(p) && o.solid.clearance(p) > thickness {
            continue;
        }
        let prox = o.solid.proximity(p);
        let signed = if prox.inside { -prox.distance } else { prox.distance };
        if signed > thickness || best.is_some_and(|(d, ..)| d <= signed) {
            continue;
        }
        let away = if prox.inside { prox.point - p } else { p - prox.point };
        let normal = match away.try_normalize() {
            Some(n) => n,
            // On the surface: the normal of the face the segment from the object's inside meets.
            None => o
                .solid
                .segment_hit(p - DVec3::Z * thickness, p + DVec3::Z * thickness)
                .map_or(DVec3::Z, |h| h.normal),
        };
        best = Some((signed, prox.point, normal, k));
    }
    best.map(|(_, point, normal, k)| (point, normal, k))
}

/// Approximate vertex normals (§4.5.1.3): the sum of the unit normals of the triangles around each
/// vertex, normalised (the sum of unit normals, spec Q-8); zero for a vertex with no proper triangle.
pub fn vertex_normals(triangles: &[[u32; 3]], x: &[DVec3], out: &mut [DVec3]) {
    out.fill(DVec3::ZERO);
    for &[a, b, c] in triangles {
        let (a, b, c) = (a as usize, b as usize, c as usize);
        let n = (x[b] - x[a]).cross(x[c] - x[a]).normalize_or_zero();
        out[a] += n;
        out[b] += n;
        out[c] += n;
    }
    for n in out.iter_mut() {
        *n = n.normalize_or_zero();
    }
}

/// Type-3 response (§4.4.2.1, A-23) for a particle found inside `solid` (in the thesis, a particle just
/// inserted by remeshing), from its position `x` and velocity `v`. The hit point is unknown, so the
/// normal is the particle's own vertex normal turned against its motion (towards the outside of the
/// solid's centre when it does not move across it); then Eqs. 4.16–4.18 with x^t = x. A particle that is
/// still inside (Eq. 4.16 cannot move one at rest) is moved along that normal to just past where a ray
/// from it leaves the solid, keeping the new velocity.
#[expect(clippy::too_many_arguments, reason = "the particle, the solid and the three response constants")]
pub fn push_out(
    solid: &Solid,
    x: DVec3,
    v: DVec3,
    vertex_normal: DVec3,
    dt: f64,
    restitution: f64,
    mu: f64,
    separating: SeparatingContact,
) -> (DVec3, DVec3) {
    let nv = vertex_normal.normalize_or_zero();
    let along = nv.dot(v);
    let n = if along > 0.0 {
        -nv
    } else if along < 0.0 {
        nv
    } else {
        let centre = solid.aabb().centre();
        let away = if centre.is_finite() { x - centre } else { solid.proximity(x).point - x };
        if nv.dot(away) < 0.0 { -nv } else { nv }
    };
    let n = if n == DVec3::ZERO { (solid.proximity(x).point - x).normalize_or(DVec3::Z) } else { n };
    let v_new = contact_velocity(v, n, restitution, mu, separating);
    let mut x_new = x + v_new * dt;
    if solid.contains(x_new) {
        let reach = solid.aabb().diagonal_length();
        let reach = if reach.is_finite() { reach } else { solid.proximity(x_new).distance * 2.0 + 1.0 };
        x_new = match solid.ray_hit(x_new, n, reach + 1.0) {
            Some(exit) => exit.point + n * 1e-9,
            None => {
                let p = solid.proximity(x_new).point;
                p + (p - x_new).normalize_or(n) * 1e-9
            }
        };
    }
    (x_new, v_new)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_velocity_reverses_scaled_by_restitution() {
        let v = DVec3::new(0.0, 0.0, -2.0);
        let out = contact_velocity(v, DVec3::Z, 0.5, 0.3, SeparatingContact::KeepVelocity);
        assert!((out - DVec3::new(0.0, 0.0, 1.0)).length() < 1e-15);
    }

    #[test]
    fn friction_slows_sliding_and_can_stop_it() {
        // Δv_N = (1 + γ)·2 = 3 m/s; μΔv_N = 0.3 m/s off a 1 m/s slide, or all of it with μ = 0.5.
        let v = DVec3::new(1.0, 0.0, -2.0);
        let slow = contact_velocity(v, DVec3::Z, 0.5, 0.1, SeparatingContact::KeepVelocity);
        assert!((slow - DVec3::new(0.7, 0.0, 1.0)).length() < 1e-15, "{slow}");
        let stop = contact_velocity(v, DVec3::Z, 0.5, 0.5, SeparatingContact::KeepVelocity);
        assert!((stop - DVec3::new(0.0, 0.0, 1.0)).length() < 1e-15, "{stop}");
    }

    #[test]
    fn separating_particles_keep_their_velocity_unless_literal() {
        let v = DVec3::new(1.0, 0.0, 0.5);
        assert_eq!(contact_velocity(v, DVec3::Z, 0.5, 0.4, SeparatingContact::KeepVelocity), v);
        // As printed: the normal part turns into the surface and friction speeds the slide up.
        let lit = contact_velocity(v, DVec3::Z, 0.5, 0.4, SeparatingContact::Literal);
        assert!((lit - DVec3::new(1.3, 0.0, -0.25)).length() < 1e-15, "{lit}");
    }

    /// A ball on a floor, and `n` points scattered within a centimetre of the ball's surface (some
    /// inside it) with where they move to.
    fn ball_floor_and_cloud(n: usize) -> ([Collider; 2], Vec<DVec3>, Vec<DVec3>) {
        use anima_geom::{HalfSpace, Sphere};
        let colliders = [
            Collider {
                name: "ball".into(),
                solid: Solid::Sphere(Sphere { centre: DVec3::ZERO, radius: 0.25 }),
                friction: 0.2,
            },
            Collider {
                name: "floor".into(),
                solid: Solid::HalfSpace(HalfSpace { point: DVec3::new(0.0, 0.0, -0.25), normal: DVec3::Z }),
                friction: 0.4,
            },
        ];
        let wobble = |k: usize, s: f64| ((k as f64 + 1.0) * s).sin();
        let start: Vec<DVec3> = (0..n)
            .map(|k| {
                let dir = DVec3::new(wobble(k, 1.3), wobble(k, 2.7), wobble(k, 0.9)).normalize_or(DVec3::Z);
                dir * (0.25 + 0.01 * wobble(k, 5.1))
            })
            .collect();
        let end: Vec<DVec3> =
            start.iter().enumerate().map(|(k, p)| *p * (1.0 - 0.02 * wobble(k, 3.3))).collect();
        (colliders, start, end)
    }

    /// The in-solve contact queries run over the particles on every core: the contacts found, their
    /// order and the clearance cache are the same on one thread as on two and four (a cloud large
    /// enough to split, around a ball on a floor, queried twice so that the cache is read too).
    #[test]
    fn solve_contacts_are_the_same_on_any_thread_count() {
        let (colliders, start, end) = ball_floor_and_cloud(12_000);
        let query = |threads: usize| {
            rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
                let mut cache = ClearanceCache::default();
                let mut model = SolveContacts {
                    colliders: &colliders,
                    friction: 0.3,
                    restitution: 0.1,
                    cache: &mut cache,
                };
                let (mut first, mut second) = (Vec::new(), Vec::new());
                model.contacts(&start, &end, &mut first);
                model.contacts(&end, &start, &mut second);
                format!("{first:?} {second:?} {:?} {:?}", cache.reference, cache.clearance)
            })
        };
        let one = query(1);
        assert!(one.matches("coordinate").count() > 1000, "too few contacts to test");
        assert!(one == query(2) && one == query(4), "the contacts depend on the thread count");
    }

    /// A remeshed cloth's particles inherit the distance bounds of the particles they were made from:
    /// the contacts found afterwards are those a cache started afresh finds, while the inherited bounds
    /// spare the queries of particles still in the open.
    #[test]
    fn inherited_clearance_bounds_find_what_fresh_queries_find() {
        let (colliders, start, end) = ball_floor_and_cloud(2_000);
        // Half the cloud pulled out to 0.3–0.35 m, where its bounds are worth keeping.
        let out = |p: &[DVec3]| -> Vec<DVec3> {
            p.iter().enumerate().map(|(k, &x)| if k % 2 == 0 { x * (1.2 + 0.2 * x.z) } else { x }).collect()
        };
        let (start, end) = (out(&start), out(&end));
        let mut cache = ClearanceCache::default();
        let mut model =
            SolveContacts { colliders: &colliders, friction: 0.3, restitution: 0.1, cache: &mut cache };
        model.contacts(&start, &end, &mut Vec::new());
        // The "remesh": every other particle is dropped, and a new one is made between each kept
        // particle and the next (some of them inside the ball), from the kept one.
        let kept: Vec<usize> = (0..end.len()).step_by(2).collect();
        let mut sources = Vec::new();
        let mut now = Vec::new();
        for (n, &k) in kept.iter().enumerate() {
            let next = kept[(n + 1) % kept.len()];
            sources.extend([k as u32, k as u32]);
            now.extend([end[k], 0.5 * (end[k] + end[next])]);
        }
        let later: Vec<DVec3> = now.iter().map(|&p| p * 0.97).collect();
        let contacts = |cache: &mut ClearanceCache| {
            let mut found = Vec::new();
            SolveContacts { colliders: &colliders, friction: 0.3, restitution: 0.1, cache }
                .contacts(&now, &later, &mut found);
            format!("{found:?}")
        };
        cache.inherit(&sources);
        assert!(cache.clearance.iter().filter(|&&c| c > 0.01).count() > 300, "no bound worth inheriting");
        let mut fresh = ClearanceCache::default();
        let inherited = contacts(&mut cache);
        assert!(inherited.matches("coordinate").count() > 100, "too few contacts to test");
        assert_eq!(inherited, contacts(&mut fresh), "the inherited bounds hid a contact");
    }

    #[test]
    fn push_out_leaves_the_solid() {
        use anima_geom::Sphere;
        let ball = Solid::Sphere(Sphere { centre: DVec3::ZERO, radius: 0.25 });
        // At rest just under the top: Eq. 4.16 cannot move it, so it is moved past the exit point.
        let (x, v) = push_out(
            &ball,
            DVec3::new(0.0, 0.0, 0.24),
            DVec3::ZERO,
            DVec3::Z,
            1e-3,
            0.5,
            0.2,
            SeparatingContact::KeepVelocity,
        );
        assert!(!ball.contains(x) && (x.z - 0.25).abs() < 1e-6 && v == DVec3::ZERO, "{x} {v}");
        // Moving down with its normal up: the velocity turns up, then the position is made outside.
        let (x, v) = push_out(
            &ball,
            DVec3::new(0.05, 0.0, 0.2),
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::Z,
            1e-3,
            0.5,
            0.2,
            SeparatingContact::KeepVelocity,
        );
        assert!(!ball.contains(x) && v.z > 0.0, "{x} {v}");
    }

    #[test]
    fn vertex_normals_of_a_flat_sheet_point_up() {
        let x = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let mut n = [DVec3::ZERO; 4];
        vertex_normals(&[[0, 1, 2], [0, 2, 3]], &x, &mut n);
        assert!(n.iter().all(|v| (*v - DVec3::Z).length() < 1e-15), "{n:?}");
    }
}
