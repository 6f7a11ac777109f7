//! Self-collision response: a velocity filter after the integrator's step that leaves a cloth which
//! started the step without crossings still without crossings at its end (issue #16), after Bridson,
//! Fedkiw & Anderson 2002 (§7) and the rigid impact zones of Provot 1997 as refined by Harmon et al.
//! 2008.
//!
//! The filter works on the step's average velocities v̄: the step moves each particle linearly,
//! x₁ = x₀ + h v̄ (the Bridson position update), so the response only has to make that straight path
//! collision-free. The model decides what v̄ is (for symplectic Euler the end velocity; for a method
//! whose positions do not follow its end velocity, (x₁ − x₀)/h) and how the change reaches its own end
//! velocity ([`crate::network_sim::NetworkSim`] adds it). In three stages:
//!
//! 1. **Proximity (repulsion).** Every vertex–triangle and edge–edge pair closer than the thickness at
//!    x₀ gets an impulse along the normal at x₀ that stops the approach (inelastic) and adds a small
//!    separating speed: the relative normal speed becomes at least d / max(τ, h), d the missing part of
//!    the thickness and τ [`SelfCollision::repulsion_time_s`], so the repulsion never restores more than
//!    the thickness in one step (the bound of Bridson's spring impulse) and resting layers do not jitter.
//!    Coulomb friction caps the change of the tangential relative velocity at μ times the normal change.
//! 2. **Impacts.** Continuous detection over x₀ → x₀ + h v̄ with the current velocities (and contacts
//!    at the end of the step, below); each impact gets an inelastic impulse (relative normal velocity
//!    at the point of impact to zero, friction as above), processed one after the other so that later impacts see earlier impulses (Gauss–Seidel). Repeated
//!    until a pass finds nothing, at most [`SelfCollision::max_impact_iterations`] passes.
//! 3. **Rigid impact zones (the fail-safe).** The particles of the impacts that remain are merged into
//!    zones; each zone moves with the rigid velocity field that keeps its linear and angular momentum
//!    (v = v_c + ω × (x₀ − x_c), ω = I⁻¹ L); detection runs again and zones grow until no impact remains.
//!    A zone that holds a pinned particle, or that still collides with itself, is frozen (velocity zero).
//!
//! Why the fail-safe terminates and guarantees the claim: a rigid velocity field moves a zone by the
//! affine map x ↦ x + t h (v_c + ω × (x − x_c)), whose matrix I + t h W (W the cross-product matrix
//! of ω) has determinant 1 + (t h |ω|)² > 0, so elements of one zone never become coplanar during the step unless they started
//! so; every detection round either merges two zones or freezes one, so rounds are at most twice the
//! particle count; and a frozen particle ends where it started, so impacts among frozen particles only
//! are not impacts of the step. Hence: if x₀ has no crossings, x₀ + h v̄ after the filter has none. (A
//! last resort, freezing everything, stands behind a round cap that no test has reached; the stats say
//! when it acted.)
//!
//! Obstacles are answered before this filter, by the model's own response, which projects particles
//! that end a step inside a collider onto its surface, and so can put two layers exactly on the same
//! plane at the end of the step. Continuous detection alone misses that (the instant of coplanarity is
//! t = 1, where rounding hides the cubic's root), and two layers that start a step touching cannot be
//! told apart by any impulse: on the folding-sheet tests every such pair then froze a zone, step after
//! step. So the impact stages also take elements that end the step closer than the impact distance,
//! on the side they started on, and push them to twice that distance apart; with it those tests need
//! no zone at all.
//!
//! Pinned particles (inverse mass 0) take no impulse; they keep their (possibly prescribed) velocity
//! unless a zone they join is frozen, in which case they stay put for the step.

use anima_geom::self_contact::{edge_edge_proximity, point_triangle_proximity};
use anima_geom::{DVec3, SelfContactBroadPhase, edge_edge_impact, vertex_triangle_impact};
use glam::DMat3;
use serde::{Deserialize, Serialize};
use std::time::{Duration, Instant};

/// How a model keeps its cloth from passing through itself (and, with several surfaces, through one
/// another). A closed choice that scene files and `anima run --self-collision` name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum SelfCollisionMode {
    /// The thesis's own response: for FLEX3D, the swept particle–triangle test with the 1-D elastic
    /// impact (Nedel 1993 §3.5.4), which leaves crossings behind once a sheet folds; Oliveira 2013 has
    /// none, so for its cloth this is [`SelfCollisionMode::Off`]. The default: faithful first.
    #[default]
    Faithful,
    /// This module's response after the step ([`SelfCollisionResponse`]): a step that starts without
    /// crossings ends without them.
    Modern,
    /// No self-collision at all: the cloth passes through itself freely.
    Off,
}

impl SelfCollisionMode {
    /// Whether this is the default: scene structs skip the field when writing it, so that every scene
    /// file written before the switch existed is written the same.
    pub fn is_faithful(&self) -> bool {
        *self == SelfCollisionMode::Faithful
    }

    /// The name on the command line: `faithful`, `modern` or `off`.
    pub fn name(self) -> &'static str {
        match self {
            SelfCollisionMode::Faithful => "faithful",
            SelfCollisionMode::Modern => "modern",
            SelfCollisionMode::Off => "off",
        }
    }
}

impl std::fmt::Display for SelfCollisionMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for SelfCollisionMode {
    type Err = String;

    /// `faithful` (also `thesis`), `modern` or `off` (also `none`).
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "faithful" | "thesis" => Ok(SelfCollisionMode::Faithful),
            "modern" => Ok(SelfCollisionMode::Modern),
            "off" | "none" => Ok(SelfCollisionMode::Off),
            _ => Err(format!("unknown self-collision mode `{s}`; expected `faithful`, `modern` or `off`")),
        }
    }
}

/// Settings of the self-collision response. Lengths in m, times in s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfCollision {
    /// Thickness of the cloth, m: pairs closer than this at the start of a step are repelled.
    pub thickness: f64,
    /// Coulomb friction coefficient between layers.
    pub friction: f64,
    /// Time over which a missing thickness d is restored: the repulsion gives a separating speed of at
    /// least d / max(τ, h), s. Longer is gentler on resting layers; the step size bounds it below, so
    /// one step never restores more than the whole thickness.
    pub repulsion_time_s: f64,
    /// Distance at which continuous detection calls two elements in contact, m. Much smaller than the
    /// thickness: it is the safety margin of the impact stages, not the cloth's thickness, and a larger
    /// one sends layers resting at the thickness into the impact stages for nothing.
    pub impact_distance: f64,
    /// Most passes of impact impulses before the rigid impact zones take over.
    pub max_impact_iterations: usize,
}

impl SelfCollision {
    /// The response for a cloth of the given thickness (m), with the other settings of [`Default`]
    /// scaled to it: impact distance 1 % of the thickness.
    pub fn with_thickness(thickness: f64) -> Self {
        Self { thickness, impact_distance: 0.01 * thickness, ..Self::default() }
    }

    /// The response the models' `Modern` mode uses on a cloth whose smallest rest spacing between
    /// neighbouring particles is `spacing` (m, or a FLEX3D scene's units): thickness
    /// [`THICKNESS_OF_SPACING`] times it, the rest as [`SelfCollision::with_thickness`].
    pub fn for_spacing(spacing: f64) -> Self {
        Self::with_thickness(THICKNESS_OF_SPACING * spacing)
    }
}

/// The models' cloth thickness as a fraction of their smallest particle spacing: thin enough that
/// layers resting at it look like touching sheets, thick enough that one step of a fast cloth (the
/// sail of FLEX3D's E-5 moves a tenth of its spacing per step at most) does not cross it. The default
/// response's 2 mm on a 64 × 64 metre sheet is an eighth of its spacing.
pub const THICKNESS_OF_SPACING: f64 = 0.1;

impl Default for SelfCollision {
    /// Thickness 2 mm (a few times thinner than a 64 × 64 metre sheet's spacing), friction 0.3,
    /// repulsion time 0.02 s, impact distance 20 µm, five impact passes (Bridson et al. found a few
    /// enough for the zones to be rare).
    fn default() -> Self {
        Self {
            thickness: 2e-3,
            friction: 0.3,
            repulsion_time_s: 0.02,
            impact_distance: 2e-5,
            max_impact_iterations: 5,
        }
    }
}

/// What one application of the response did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SelfCollisionStats {
    /// Proximity pairs that received a repulsion impulse.
    pub repulsions: usize,
    /// Impacts answered by an impulse, over all impact passes.
    pub impacts: usize,
    /// Impact passes run (a pass that finds nothing ends them).
    pub impact_iterations: usize,
    /// Rigid impact zones at the end (0 when the impulses sufficed).
    pub zones: usize,
    /// Particles in those zones.
    pub zone_particles: usize,
    /// Zones frozen (pinned member, or still colliding with themselves).
    pub frozen_zones: usize,
    /// Detection rounds of the impact-zone stage.
    pub zone_iterations: usize,
    /// Whether the last resort (every particle frozen) acted.
    pub froze_everything: bool,
    /// The farthest a particle of a frozen zone would have moved over the step when it joined its
    /// zone, m (0 without frozen zones; the largest over the calls when summed): what the fail-safe
    /// held back, and so how far the springs into the zone can be stretched by it.
    pub frozen_motion: f64,
    /// Particles whose motion over the step the response changed
    /// ([`SelfCollisionResponse::filter_step`] only).
    pub changed_particles: usize,
    /// Where the time went.
    pub times: StageTimes,
}

/// Wall time of the response's stages, summed over the calls.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StageTimes {
    /// The broad phase of every stage: swept boxes, refitted (or rebuilt) trees, candidate pairs.
    pub broad_phase: Duration,
    /// Proximity tests and repulsion impulses.
    pub proximity: Duration,
    /// Continuous tests (the coplanarity cubic) and impact impulses, every pass.
    pub impacts: Duration,
    /// Rigid impact zones: their detection rounds and rigid velocities (broad phase apart).
    pub zones: Duration,
}

impl StageTimes {
    pub fn total(&self) -> Duration {
        self.broad_phase + self.proximity + self.impacts + self.zones
    }
}

impl std::ops::AddAssign for StageTimes {
    fn add_assign(&mut self, o: Self) {
        self.broad_phase += o.broad_phase;
        self.proximity += o.proximity;
        self.impacts += o.impacts;
        self.zones += o.zones;
    }
}

impl std::ops::AddAssign for SelfCollisionStats {
    fn add_assign(&mut self, o: Self) {
        self.repulsions += o.repulsions;
        self.impacts += o.impacts;
        self.impact_iterations += o.impact_iterations;
        self.zones += o.zones;
        self.zone_particles += o.zone_particles;
        self.frozen_zones += o.frozen_zones;
        self.zone_iterations += o.zone_iterations;
        self.froze_everything |= o.froze_everything;
        self.frozen_motion = self.frozen_motion.max(o.frozen_motion);
        self.changed_particles += o.changed_particles;
        self.times += o.times;
    }
}

/// The response's scratch: the broad phase and per-particle buffers, kept between steps so that a
/// step allocates nothing once they have grown to the mesh.
#[derive(Debug, Clone, Default)]
pub struct SelfCollisionResponse {
    broad: SelfContactBroadPhase,
    /// Candidate end positions x₀ + h v̄.
    x1: Vec<DVec3>,
    /// Impact zones: union–find parents and, per root, the zone's sums.
    parent: Vec<u32>,
    frozen: Vec<bool>,
    members: Vec<u32>,
    in_zone: Vec<bool>,
    /// Per zone member, h |v| when it joined its zone (entries of other particles are stale).
    join_motion: Vec<f64>,
    mass: Vec<f64>,
    moment: Vec<DVec3>,
    momentum: Vec<DVec3>,
    angular: Vec<DVec3>,
    inertia: Vec<DMat3>,
    impacts: Vec<[u32; 4]>,
    /// Zones (by root) found colliding with themselves in a round.
    self_impacts: Vec<u32>,
    /// [`SelfCollisionResponse::filter_step`]'s average velocities of the step, before and after, and
    /// the step's end positions before it (the particles it does not change keep them to the bit).
    step_velocity: Vec<DVec3>,
    filtered_velocity: Vec<DVec3>,
    end_before: Vec<DVec3>,
    /// Time spent in the broad phase during the current call.
    broad_time: Duration,
    /// Velocities at the start of the current stage or pass, and the particles whose velocity it
    /// changed: the next pass tests only the pairs that hold one of them.
    v_before: Vec<DVec3>,
    moved: Vec<bool>,
}

/// Rounds of the response after the first that a model runs when the response pushed particles into an
/// object: the models hold such particles (inverse mass 0) and run the response again from the step's
/// end before it, until it pushes none in (the Oliveira cloth's `keep_apart`, the networks' filter).
pub const OBJECT_ROUNDS: usize = 4;

/// The most a particle's velocity may change per unit change of a contact's relative velocity: an
/// impulse that would change one more is not applied, and the contact goes to the rigid impact zones
/// (which freeze a zone holding a held particle). Without the bound, a contact carried by held
/// particles was answered through the small weight of a free one: 20–45 m/s given to single particles
/// of a cloth moving at 2 m/s (measured on the folding drape of the self-collision tests).
const MAX_AMPLIFICATION: f64 = 4.0;

/// A contact between four particles: relative velocity Σ wₖ vₖ along `normal` (weights +1 for the
/// vertex or first edge, minus the barycentric weights for the triangle or second edge).
#[derive(Debug, Clone, Copy)]
struct Stencil {
    particles: [usize; 4],
    weights: [f64; 4],
    normal: DVec3,
}

impl SelfCollisionResponse {
    pub fn new() -> Self {
        Self::default()
    }

    /// Filters the average velocities `v` of a step of size `h` from `x0` so that the straight motion
    /// x₀ + h v crosses nothing, and writes those end positions into `x1` (bit for bit the positions the
    /// detection tested, so a caller should take them rather than recompute them). `inv_mass` is 0 for
    /// pinned particles. See the module docs for the stages.
    ///
    /// # Panics
    /// If the slices differ in length or a triangle names a particle outside them.
    #[expect(clippy::too_many_arguments, reason = "the state of a step, each slice one physical field")]
    pub fn apply(
        &mut self,
        settings: &SelfCollision,
        h: f64,
        x0: &[DVec3],
        v: &mut [DVec3],
        inv_mass: &[f64],
        triangles: &[[u32; 3]],
        x1: &mut [DVec3],
    ) -> SelfCollisionStats {
        let n = x0.len();
        assert!(v.len() == n && inv_mass.len() == n && x1.len() == n, "one entry per particle");
        let mut stats = SelfCollisionStats::default();
        self.x1.resize(n, DVec3::ZERO);
        self.broad_time = Duration::ZERO;
        let started = Instant::now();

        // 1. Proximity at x₀, on the pairs of the swept boxes grown by the thickness (a superset of the
        // pairs within the thickness at x₀).
        self.predict(x0, v, h);
        self.broad_update(triangles, x0, settings.thickness);
        self.v_before.clear();
        self.v_before.extend_from_slice(v);
        let target = |gap: f64| (settings.thickness - gap) / settings.repulsion_time_s.max(h);
        for pair in self.broad.vertex_triangle_pairs() {
            let p = pair.vertex as usize;
            let [a, b, c] = triangles[pair.triangle as usize].map(|i| i as usize);
            let q = point_triangle_proximity(x0[p], [x0[a], x0[b], x0[c]]);
            if q.distance >= settings.thickness {
                continue;
            }
            let w = q.barycentric;
            let face = (x0[b] - x0[a]).cross(x0[c] - x0[a]);
            let Some(normal) = separation_normal(x0[p] - q.point, face, relative(v, [p, a, b, c], w)) else {
                continue;
            };
            let s = Stencil { particles: [p, a, b, c], weights: [1.0, -w[0], -w[1], -w[2]], normal };
            if s.impulse(v, inv_mass, target(q.distance), settings.friction) {
                stats.repulsions += 1;
            }
        }
        for pair in self.broad.edge_edge_pairs() {
            let [[a0, a1], [b0, b1]] = pair.edges.map(|e| e.map(|i| i as usize));
            let q = edge_edge_proximity([x0[a0], x0[a1]], [x0[b0], x0[b1]]);
            if q.distance >= settings.thickness {
                continue;
            }
            let [s0, s1] = q.s;
            let weights = [1.0 - s0, s0, -(1.0 - s1), -s1];
            let particles = [a0, a1, b0, b1];
            let axis = (x0[a1] - x0[a0]).cross(x0[b1] - x0[b0]);
            let rel = (0..4).fold(DVec3::ZERO, |r, k| r + v[particles[k]] * weights[k]);
            let Some(normal) = separation_normal(q.points[0] - q.points[1], axis, rel) else {
                continue;
            };
            let s = Stencil { particles, weights, normal };
            if s.impulse(v, inv_mass, target(q.distance), settings.friction) {
                stats.repulsions += 1;
            }
        }

        let proximity_done = Instant::now();
        stats.times.proximity = proximity_done - started - self.broad_time;
        let broad_before = self.broad_time;

        // 2. Impact passes. An impact among particles that all have inverse mass 0 (pinned, or held
        // by an object) takes no impulse; it goes straight to the zones, which freeze it.
        //
        // Each pass tests only the pairs that can have changed since they were last tested: a pair
        // whose four particles kept their velocities moves as it did, so its test would say the same.
        // The first pass takes the proximity stage's candidates without a particle the repulsion moved
        // (still candidates: the impact distance is below the thickness) and queries the trees, refitted,
        // from the moved ones; later passes query from the particles the pass before moved only.
        let mut clear = false;
        let mut any_immovable = false;
        let incremental = settings.impact_distance <= settings.thickness;
        for pass in 0..settings.max_impact_iterations {
            stats.impact_iterations += 1;
            self.predict(x0, v, h);
            if incremental {
                self.moved.clear();
                self.moved.extend(v.iter().zip(&self.v_before).map(|(a, b)| a != b));
                let started = Instant::now();
                self.broad.update_moved(
                    triangles,
                    x0,
                    &self.x1,
                    settings.impact_distance,
                    &self.moved,
                    pass == 0,
                );
                self.broad_time += started.elapsed();
            } else {
                self.broad_update(triangles, x0, settings.impact_distance);
            }
            self.v_before.clear();
            self.v_before.extend_from_slice(v);
            let (answered, immovable) = self.impact_pass(settings, h, x0, v, inv_mass, triangles);
            stats.impacts += answered;
            any_immovable |= immovable > 0;
            if answered == 0 {
                clear = !any_immovable;
                break;
            }
        }

        let impacts_done = Instant::now();
        stats.times.impacts = impacts_done - proximity_done - (self.broad_time - broad_before);
        let broad_before = self.broad_time;

        // 3. Rigid impact zones, unless the last pass found nothing.
        if !clear {
            self.impact_zones(settings, h, x0, v, inv_mass, triangles, &mut stats);
        }
        for i in 0..n {
            x1[i] = x0[i] + v[i] * h;
        }
        stats.times.zones = impacts_done.elapsed() - (self.broad_time - broad_before);
        stats.times.broad_phase = self.broad_time;
        stats
    }

    /// The broad phase over the candidate end positions `self.x1`, timed.
    fn broad_update(&mut self, triangles: &[[u32; 3]], x0: &[DVec3], thickness: f64) {
        let started = Instant::now();
        self.broad.update(triangles, x0, &self.x1, thickness);
        self.broad_time += started.elapsed();
    }

    /// The response on a step a model has already taken, from `x0` to `x1` with end velocities `v1`:
    /// filters the step's average velocities v̄ = (x₁ − x₀)/h (the motion the step made, whatever the
    /// integrator), puts the positions at x₀ + h v̄' (the Bridson position update: the straight path
    /// the response made collision-free) and gives the end velocity the same change, v₁ += v̄' − v̄ (for
    /// symplectic Euler v₁ = v̄, so it becomes v̄'; other methods keep the part of their end velocity
    /// that differs from the average). Marks in `touched` the particles it changed (and leaves the
    /// others as they were), so that the caller can reset a multistep history for them.
    ///
    /// # Panics
    /// As [`SelfCollisionResponse::apply`], and if `touched` has not one entry per particle.
    #[expect(clippy::too_many_arguments, reason = "the state of a step, each slice one physical field")]
    pub fn filter_step(
        &mut self,
        settings: &SelfCollision,
        h: f64,
        x0: &[DVec3],
        x1: &mut [DVec3],
        v1: &mut [DVec3],
        inv_mass: &[f64],
        triangles: &[[u32; 3]],
        touched: &mut [bool],
    ) -> SelfCollisionStats {
        assert!(v1.len() == x0.len() && touched.len() == x0.len(), "one entry per particle");
        let mut step_velocity = std::mem::take(&mut self.step_velocity);
        let mut filtered = std::mem::take(&mut self.filtered_velocity);
        step_velocity.clear();
        step_velocity.extend(x0.iter().zip(x1.iter()).map(|(a, b)| (*b - *a) / h));
        filtered.clear();
        filtered.extend_from_slice(&step_velocity);
        let mut end = std::mem::take(&mut self.end_before);
        end.clear();
        end.extend_from_slice(x1);
        let mut stats = self.apply(settings, h, x0, &mut filtered, inv_mass, triangles, x1);
        for (i, (after, before)) in filtered.iter().zip(&step_velocity).enumerate() {
            if after != before {
                v1[i] += *after - *before;
                touched[i] = true;
                stats.changed_particles += 1;
            } else {
                // Untouched: the step's own end, not x₀ + h (x₁ − x₀)/h rounded.
                x1[i] = end[i];
            }
        }
        self.end_before = end;
        self.step_velocity = step_velocity;
        self.filtered_velocity = filtered;
        stats
    }

    fn predict(&mut self, x0: &[DVec3], v: &[DVec3], h: f64) {
        for ((p, &x), &vi) in self.x1.iter_mut().zip(x0).zip(v) {
            *p = x + vi * h;
        }
    }

    /// One Gauss–Seidel pass of inelastic impulses over the impacts of the current velocities, among
    /// the broad phase's candidates (the caller updates it); returns how many impacts it answered, and
    /// how many it found among immovable particles only.
    fn impact_pass(
        &mut self,
        settings: &SelfCollision,
        h: f64,
        x0: &[DVec3],
        v: &mut [DVec3],
        inv_mass: &[f64],
        triangles: &[[u32; 3]],
    ) -> (usize, usize) {
        let (mut found, mut immovable) = (0, 0);
        let delta = settings.impact_distance;
        for k in 0..self.broad.vertex_triangle_pairs().len() {
            let pair = self.broad.vertex_triangle_pairs()[k];
            let p = pair.vertex as usize;
            let [a, b, c] = triangles[pair.triangle as usize].map(|i| i as usize);
            let ids = [p, a, b, c];
            let end = ids.map(|i| x0[i] + v[i] * h);
            if let Some(hit) = vertex_triangle_contact(ids.map(|i| x0[i]), end, delta) {
                if hit.answer(ids, v, inv_mass, h, delta, settings.friction) {
                    found += 1;
                } else {
                    immovable += 1;
                }
            }
        }
        for k in 0..self.broad.edge_edge_pairs().len() {
            let pair = self.broad.edge_edge_pairs()[k];
            let [[a0, a1], [b0, b1]] = pair.edges.map(|e| e.map(|i| i as usize));
            let ids = [a0, a1, b0, b1];
            let end = ids.map(|i| x0[i] + v[i] * h);
            if let Some(hit) = edge_edge_contact(ids.map(|i| x0[i]), end, delta) {
                if hit.answer(ids, v, inv_mass, h, delta, settings.friction) {
                    found += 1;
                } else {
                    immovable += 1;
                }
            }
        }
        (found, immovable)
    }

    /// The fail-safe: grows rigid impact zones until the step has no impact left (module docs).
    #[expect(clippy::too_many_arguments, reason = "the state of a step, plus the stats it reports into")]
    fn impact_zones(
        &mut self,
        settings: &SelfCollision,
        h: f64,
        x0: &[DVec3],
        v: &mut [DVec3],
        inv_mass: &[f64],
        triangles: &[[u32; 3]],
        stats: &mut SelfCollisionStats,
    ) {
        let n = x0.len();
        self.parent.clear();
        self.parent.extend(0..n as u32);
        self.frozen.clear();
        self.frozen.resize(n, false);
        self.in_zone.clear();
        self.in_zone.resize(n, false);
        self.join_motion.resize(n, 0.0);
        self.members.clear();
        // Every round merges two zones or freezes one (module docs), so this cap is never the reason
        // the loop ends unless rounding defeats the argument; then everything is frozen.
        let max_rounds = 2 * n + 2;
        loop {
            if stats.zone_iterations >= max_rounds {
                v.fill(DVec3::ZERO);
                stats.froze_everything = true;
                break;
            }
            stats.zone_iterations += 1;
            self.collect_impacts(settings, h, x0, v, triangles);
            if self.impacts.is_empty() {
                break;
            }
            // A zone that already moved rigidly and still collides with itself (only coplanar starts
            // do that, module docs) is frozen: decided on the zones as they were before this round's
            // merges, which would otherwise make every impact of a growing zone look like its own.
            self.self_impacts.clear();
            for k in 0..self.impacts.len() {
                let roots = self.impacts[k].map(|i| self.find(i));
                if self.in_zone[roots[0] as usize] && roots.iter().all(|&r| r == roots[0]) {
                    self.self_impacts.push(roots[0]);
                }
            }
            for k in 0..self.impacts.len() {
                let ids = self.impacts[k];
                for &i in &ids {
                    if !self.in_zone[i as usize] {
                        self.in_zone[i as usize] = true;
                        self.join_motion[i as usize] = h * v[i as usize].length();
                        self.members.push(i);
                        self.frozen[i as usize] = inv_mass[i as usize] == 0.0;
                    }
                }
                let mut root = self.find(ids[0]);
                for &i in &ids[1..] {
                    root = self.union(root, i);
                }
            }
            for k in 0..self.self_impacts.len() {
                let root = self.find(self.self_impacts[k]);
                self.frozen[root as usize] = true;
            }
            self.rigidify(x0, v, inv_mass);
        }
        let mut zones = 0;
        for k in 0..self.members.len() {
            let i = self.members[k];
            let root = self.find(i);
            if root == i {
                zones += 1;
                stats.frozen_zones += usize::from(self.frozen[i as usize]);
            }
            if self.frozen[root as usize] {
                stats.frozen_motion = stats.frozen_motion.max(self.join_motion[i as usize]);
            }
        }
        stats.zones = zones;
        stats.zone_particles = self.members.len();
    }

    /// The impacts of the current velocities, skipping those whose four particles all stay put (they
    /// end where they started, which crossed nothing).
    fn collect_impacts(
        &mut self,
        settings: &SelfCollision,
        h: f64,
        x0: &[DVec3],
        v: &[DVec3],
        triangles: &[[u32; 3]],
    ) {
        self.predict(x0, v, h);
        self.broad_update(triangles, x0, settings.impact_distance);
        self.impacts.clear();
        let delta = settings.impact_distance;
        let still = |ids: &[usize; 4]| ids.iter().all(|&i| v[i] == DVec3::ZERO);
        for pair in self.broad.vertex_triangle_pairs() {
            let p = pair.vertex as usize;
            let [a, b, c] = triangles[pair.triangle as usize].map(|i| i as usize);
            let ids = [p, a, b, c];
            if !still(&ids)
                && vertex_triangle_contact(ids.map(|i| x0[i]), ids.map(|i| self.x1[i]), delta).is_some()
            {
                self.impacts.push(ids.map(|i| i as u32));
            }
        }
        for pair in self.broad.edge_edge_pairs() {
            let [[a0, a1], [b0, b1]] = pair.edges.map(|e| e.map(|i| i as usize));
            let ids = [a0, a1, b0, b1];
            if !still(&ids) && edge_edge_contact(ids.map(|i| x0[i]), ids.map(|i| self.x1[i]), delta).is_some()
            {
                self.impacts.push(ids.map(|i| i as u32));
            }
        }
    }

    /// Gives every zone the rigid velocity field with its particles' linear and angular momentum about
    /// the centre of mass at x₀, or zero velocity when it is frozen.
    fn rigidify(&mut self, x0: &[DVec3], v: &mut [DVec3], inv_mass: &[f64]) {
        self.mass.resize(x0.len(), 0.0);
        self.moment.resize(x0.len(), DVec3::ZERO);
        self.momentum.resize(x0.len(), DVec3::ZERO);
        self.angular.resize(x0.len(), DVec3::ZERO);
        self.inertia.resize(x0.len(), DMat3::ZERO);
        for k in 0..self.members.len() {
            let r = self.find(self.members[k]) as usize;
            self.mass[r] = 0.0;
            self.moment[r] = DVec3::ZERO;
            self.momentum[r] = DVec3::ZERO;
            self.angular[r] = DVec3::ZERO;
            self.inertia[r] = DMat3::ZERO;
        }
        // Pinned members froze their zone, so every mass summed here is finite.
        for k in 0..self.members.len() {
            let i = self.members[k] as usize;
            let r = self.find(i as u32) as usize;
            if !self.frozen[r] {
                let m = 1.0 / inv_mass[i];
                self.mass[r] += m;
                self.moment[r] += x0[i] * m;
                self.momentum[r] += v[i] * m;
            }
        }
        for k in 0..self.members.len() {
            let i = self.members[k] as usize;
            let r = self.find(i as u32) as usize;
            if !self.frozen[r] {
                let m = 1.0 / inv_mass[i];
                let (xc, vc) = (self.moment[r] / self.mass[r], self.momentum[r] / self.mass[r]);
                let d = x0[i] - xc;
                self.angular[r] += d.cross(v[i] - vc) * m;
                self.inertia[r] += (DMat3::IDENTITY * d.length_squared() - outer(d, d)) * m;
            }
        }
        for k in 0..self.members.len() {
            let i = self.members[k] as usize;
            let r = self.find(i as u32) as usize;
            if self.frozen[r] {
                v[i] = DVec3::ZERO;
                continue;
            }
            let (xc, vc) = (self.moment[r] / self.mass[r], self.momentum[r] / self.mass[r]);
            v[i] = vc + angular_velocity(self.inertia[r], self.angular[r]).cross(x0[i] - xc);
        }
    }

    fn find(&mut self, mut i: u32) -> u32 {
        while self.parent[i as usize] != i {
            let up = self.parent[self.parent[i as usize] as usize];
            self.parent[i as usize] = up;
            i = up;
        }
        i
    }

    /// Joins the zone of `i` to the zone whose root is `root`; returns the new root, frozen when
    /// either was.
    fn union(&mut self, root: u32, i: u32) -> u32 {
        let other = self.find(i);
        if other == root {
            return root;
        }
        self.parent[other as usize] = root;
        self.frozen[root as usize] |= self.frozen[other as usize];
        root
    }
}

impl Stencil {
    /// Raises the relative normal velocity to at least `target_vn` (no change if it already is) with
    /// the mass-weighted impulse J that needs: Δv_k = w_k m_k⁻¹ J, so that Δv_rel = (Σ w_k² m_k⁻¹) J.
    /// Coulomb friction removes up to μ Δv_n of the tangential relative velocity in the same impulse.
    /// Returns whether it acted.
    fn impulse(&self, v: &mut [DVec3], inv_mass: &[f64], target_vn: f64, friction: f64) -> bool {
        let vn = self.relative(v).dot(self.normal);
        if vn >= target_vn {
            return false;
        }
        self.raise(v, inv_mass, target_vn - vn, friction)
    }

    fn relative(&self, v: &[DVec3]) -> DVec3 {
        (0..4).fold(DVec3::ZERO, |r, k| r + v[self.particles[k]] * self.weights[k])
    }

    /// Whether the stencil can take an impulse without throwing a particle: the change of particle k is
    /// |w_k| m_k⁻¹ / Σ w_j² m_j⁻¹ times the change of the relative velocity, which is large when the
    /// particles that carry the contact's weight are held (inverse mass 0) and a free one takes it
    /// through a small weight (a triangle's corner far from the contact point, its other corners on an
    /// object).
    fn movable(&self, inv_mass: &[f64]) -> bool {
        let denom: f64 = (0..4).map(|k| self.weights[k].powi(2) * inv_mass[self.particles[k]]).sum();
        denom > 0.0
            && (0..4)
                .all(|k| self.weights[k].abs() * inv_mass[self.particles[k]] <= MAX_AMPLIFICATION * denom)
    }

    /// Adds `dvn` > 0 to the relative normal velocity, with friction; see [`Stencil::impulse`]. Does
    /// nothing, and returns false, on a stencil that is not [`Stencil::movable`].
    fn raise(&self, v: &mut [DVec3], inv_mass: &[f64], dvn: f64, friction: f64) -> bool {
        let rel = self.relative(v);
        let vn = rel.dot(self.normal);
        let denom: f64 = (0..4).map(|k| self.weights[k].powi(2) * inv_mass[self.particles[k]]).sum();
        if !self.movable(inv_mass) {
            return false;
        }
        let vt = rel - self.normal * vn;
        let st = vt.length();
        let dvt = if st > 0.0 { vt * -(friction * dvn / st).min(1.0) } else { DVec3::ZERO };
        let j = (self.normal * dvn + dvt) / denom;
        for k in 0..4 {
            let i = self.particles[k];
            v[i] += j * (self.weights[k] * inv_mass[i]);
        }
        true
    }
}

/// A contact of the impact stages, over the step: an impact found by continuous detection, or two
/// elements that end the step closer than the impact distance without having met on the way.
#[derive(Debug, Clone, Copy)]
struct Hit {
    weights: [f64; 4],
    normal: DVec3,
    /// For an end-of-step contact, the normal distance at the end, m; `None` for an impact.
    end_gap: Option<f64>,
}

impl Hit {
    /// An impact gets the inelastic impulse (relative normal velocity to zero); an end-of-step contact
    /// the relative normal velocity that ends the step twice the impact distance `delta` apart. The latter
    /// matters because continuous detection sees a contact at its instant of coplanarity, and elements
    /// that become coplanar exactly at the end of the step (an obstacle's projection puts two layers
    /// on its surface) have that instant at t = 1, where rounding can hide the cubic's root; left
    /// alone, they would start the next step touching, which no impulse can undo.
    ///
    /// Returns false, and changes nothing, when the contact cannot be moved: its particles with weight
    /// are immovable (inverse mass 0), or so nearly so that the impulse would throw a particle of small
    /// weight away ([`Stencil::movable`]).
    fn answer(
        &self,
        ids: [usize; 4],
        v: &mut [DVec3],
        inv_mass: &[f64],
        h: f64,
        delta: f64,
        friction: f64,
    ) -> bool {
        let s = Stencil { particles: ids, weights: self.weights, normal: self.normal };
        if !s.movable(inv_mass) {
            return false;
        }
        match self.end_gap {
            None => {
                s.impulse(v, inv_mass, 0.0, friction);
            }
            Some(gap) => {
                s.raise(v, inv_mass, (2.0 * delta - gap).max(0.0) / h, friction);
            }
        }
        true
    }
}

/// The impact of vertex `[0]` with triangle `[1..]` over the step `start → end`, or their contact at
/// the end of it (closer than `delta` there, on the side the vertex started on).
fn vertex_triangle_contact(start: [DVec3; 4], end: [DVec3; 4], delta: f64) -> Option<Hit> {
    if let Some(hit) = vertex_triangle_impact(start, end, delta) {
        let w = hit.barycentric;
        return Some(Hit { weights: [1.0, -w[0], -w[1], -w[2]], normal: hit.normal, end_gap: None });
    }
    let [p, a, b, c] = end;
    let q = point_triangle_proximity(p, [a, b, c]);
    if q.distance > delta {
        return None;
    }
    let side = (start[2] - start[1]).cross(start[3] - start[1]).dot(start[0] - start[1]);
    let face = (b - a).cross(c - a).try_normalize()?;
    let normal = if side < 0.0 {
        -face
    } else if side > 0.0 {
        face
    } else {
        return None;
    };
    let w = q.barycentric;
    let gap = (p - q.point).dot(normal).max(0.0);
    Some(Hit { weights: [1.0, -w[0], -w[1], -w[2]], normal, end_gap: Some(gap) })
}

/// The impact of edges `[0]–[1]` and `[2]–[3]` over the step, or their contact at the end of it (as
/// [`vertex_triangle_contact`], the side taken along the edges' common normal at the start).
fn edge_edge_contact(start: [DVec3; 4], end: [DVec3; 4], delta: f64) -> Option<Hit> {
    if let Some(hit) = edge_edge_impact(start, end, delta) {
        let [s0, s1] = hit.s;
        return Some(Hit { weights: [1.0 - s0, s0, -(1.0 - s1), -s1], normal: hit.normal, end_gap: None });
    }
    let [a0, a1, b0, b1] = end;
    let q = edge_edge_proximity([a0, a1], [b0, b1]);
    if q.distance > delta {
        return None;
    }
    let axis0 = (start[1] - start[0]).cross(start[3] - start[2]);
    let side = axis0.dot(start[0] - start[2]);
    let axis = (a1 - a0).cross(b1 - b0).try_normalize()?;
    let normal = if side < 0.0 {
        -axis
    } else if side > 0.0 {
        axis
    } else {
        return None;
    };
    let [s0, s1] = q.s;
    let gap = (q.points[0] - q.points[1]).dot(normal).max(0.0);
    Some(Hit { weights: [1.0 - s0, s0, -(1.0 - s1), -s1], normal, end_gap: Some(gap) })
}

/// Relative velocity of a vertex `ids[0]` and the point of triangle `ids[1..]` with weights `w`.
fn relative(v: &[DVec3], ids: [usize; 4], w: [f64; 3]) -> DVec3 {
    v[ids[0]] - v[ids[1]] * w[0] - v[ids[2]] * w[1] - v[ids[3]] * w[2]
}

/// The direction that separates two elements in proximity: their gap when it has one, else the face
/// (or edge-cross) direction turned against the approach; `None` when neither exists.
fn separation_normal(gap: DVec3, face: DVec3, relative_velocity: DVec3) -> Option<DVec3> {
    let scale = face.length().max(1e-300);
    if gap.length() > 1e-9 * scale.sqrt() {
        return gap.try_normalize();
    }
    let n = face.try_normalize()?;
    Some(if n.dot(gap) < 0.0 || (n.dot(gap) == 0.0 && n.dot(relative_velocity) > 0.0) { -n } else { n })
}

fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// ω = I⁻¹ L, with I regularised by a trace-relative 10⁻¹² so that a collinear zone (I singular about
/// its line, where L has no component either) gets no spin about that line instead of a NaN.
fn angular_velocity(inertia: DMat3, angular: DVec3) -> DVec3 {
    let trace = inertia.x_axis.x + inertia.y_axis.y + inertia.z_axis.z;
    if trace <= 0.0 {
        return DVec3::ZERO;
    }
    let reg = inertia + DMat3::from_diagonal(DVec3::splat(1e-12 * trace));
    reg.inverse() * angular
}

#[cfg(test)]
mod tests {
    use super::*;
    use anima_geom::count_self_intersections;

    /// A triangle in z = 0 and a vertex above it moving down at `speed` (m/s) over a step of 0.01 s,
    /// far enough to pass through it; the triangle's corners have inverse mass `triangle_inv_mass`.
    fn falling_vertex(speed: f64, triangle_inv_mass: f64) -> (Vec<DVec3>, Vec<DVec3>, Vec<f64>) {
        let x0 = vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::new(0.2, 0.2, 0.01)];
        let v = vec![DVec3::ZERO, DVec3::ZERO, DVec3::ZERO, DVec3::new(0.0, 0.0, -speed)];
        (x0, v, vec![triangle_inv_mass, triangle_inv_mass, triangle_inv_mass, 1.0])
    }

    /// The vertex's edges to the triangle's plane make the crossing countable: a second triangle
    /// hangs from the vertex and stays put, so it is an (edge, triangle) crossing when the vertex passes
    /// through.
    const TRIANGLES: [[u32; 3]; 2] = [[0, 1, 2], [3, 4, 5]];

    fn with_tail(
        mut x: Vec<DVec3>,
        mut v: Vec<DVec3>,
        mut m: Vec<f64>,
    ) -> (Vec<DVec3>, Vec<DVec3>, Vec<f64>) {
        x.extend([x[3] + DVec3::new(0.1, 0.0, 0.05), x[3] + DVec3::new(0.0, 0.1, 0.05)]);
        v.extend([DVec3::ZERO, DVec3::ZERO]);
        m.extend([1.0, 1.0]);
        (x, v, m)
    }

    #[test]
    fn a_fast_vertex_is_stopped_on_a_pinned_triangle() {
        let (x0, mut v, m) = {
            let (x, v, m) = falling_vertex(10.0, 0.0);
            with_tail(x, v, m)
        };
        let h = 0.01;
        let mut x1 = vec![DVec3::ZERO; x0.len()];
        let ends: Vec<DVec3> = x0.iter().zip(&v).map(|(x, v)| *x + *v * h).collect();
        assert!(count_self_intersections(&ends, &TRIANGLES) > 0, "the unfiltered step must cross");
        let stats = SelfCollisionResponse::new().apply(
            &SelfCollision::default(),
            h,
            &x0,
            &mut v,
            &m,
            &TRIANGLES,
            &mut x1,
        );
        assert_eq!(count_self_intersections(&x1, &TRIANGLES), 0, "{stats:?}");
        assert!(stats.impacts > 0, "{stats:?}");
        assert!(v[..3].iter().all(|v| *v == DVec3::ZERO), "pinned corners moved");
        assert!(x1[3].z > 0.0, "{:?}", x1[3]);
    }

    #[test]
    fn impact_zones_keep_momentum_and_end_without_crossings() {
        // No impulse passes: the zones alone must answer the impact.
        let settings = SelfCollision { max_impact_iterations: 0, ..SelfCollision::default() };
        let (x0, mut v, m) = {
            let (x, mut v, m) = falling_vertex(10.0, 1.0);
            v[1] = DVec3::new(0.0, 0.0, 3.0);
            with_tail(x, v, m)
        };
        let momentum = |v: &[DVec3]| v.iter().zip(&m).map(|(v, m)| *v / *m).sum::<DVec3>();
        let before = momentum(&v);
        let h = 0.01;
        let mut x1 = vec![DVec3::ZERO; x0.len()];
        let stats = SelfCollisionResponse::new().apply(&settings, h, &x0, &mut v, &m, &TRIANGLES, &mut x1);
        assert!(stats.zones > 0 && stats.frozen_zones == 0, "{stats:?}");
        assert!((momentum(&v) - before).length() < 1e-12, "{:?} → {:?}", before, momentum(&v));
        assert_eq!(count_self_intersections(&x1, &TRIANGLES), 0, "{stats:?}");
    }

    #[test]
    fn steps_after_warm_up_allocate_nothing() {
        // Warm up on the step with the most work (the zones), then lighter steps must reuse every buffer.
        let (x0, v, m) = {
            let (x, mut v, m) = falling_vertex(10.0, 1.0);
            v[1] = DVec3::new(0.0, 0.0, 3.0);
            with_tail(x, v, m)
        };
        let settings = SelfCollision { max_impact_iterations: 0, ..SelfCollision::default() };
        let mut response = SelfCollisionResponse::new();
        let mut x1 = vec![DVec3::ZERO; x0.len()];
        response.apply(&settings, 0.01, &x0, &mut v.clone(), &m, &TRIANGLES, &mut x1);
        let fingerprint = |r: &SelfCollisionResponse| {
            [
                (r.x1.as_ptr() as usize, r.x1.capacity()),
                (r.parent.as_ptr() as usize, r.parent.capacity()),
                (r.members.as_ptr() as usize, r.members.capacity()),
                (r.mass.as_ptr() as usize, r.mass.capacity()),
                (r.inertia.as_ptr() as usize, r.inertia.capacity()),
                (r.impacts.as_ptr() as usize, r.impacts.capacity()),
            ]
        };
        let warm = fingerprint(&response);
        for speed in [10.0, 1.0, 0.0] {
            let mut v = v.clone();
            v[3].z = -speed;
            response.apply(&settings, 0.01, &x0, &mut v, &m, &TRIANGLES, &mut x1);
            assert_eq!(fingerprint(&response), warm, "speed {speed}");
        }
    }
}
