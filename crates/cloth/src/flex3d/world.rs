//! A FLEX3D world: every surface of a scene as one flat particle state, stepped together.

use anima_geom::{Aabb, DVec3, GridFrame, PreparedTriangle, SurfaceGrid, TriangleMesh, grid_triangles};
use anima_ode::{OdeSystem, State, Stepper};

use super::broadphase::{Binning, TriangleGrid};
use super::desc::{
    ContactApproach, Flex3dScene, FrictionMode, ModelOptions, StaticResponse, TranslationMode,
};
use super::forces::{SurfaceForces, acceleration_with_friction, add_bending_forces, add_spring_forces};
use super::solve_contact::{StaticContacts, THICKNESS_OF_SPACING};
use crate::bounds::{Bounds, BoundsWatch, Defaults};
use crate::contact_mode::ContactMode;
use crate::error::{GridPlace, NonFinite, StepError};
use crate::self_collision::{SelfCollision, SelfCollisionMode, SelfCollisionResponse, SelfCollisionStats};
use anima_geom::self_contact::point_triangle_proximity;

/// Why a scene could not be turned into a world.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    #[error("surface `{surface}`: {message}")]
    Surface { surface: String, message: String },
    #[error("scene: {0}")]
    Scene(String),
}

/// How many collision responses the run has applied, by partner kind.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CollisionCounts {
    /// With contacts in the solve (`ModelOptions::object_contact`), the particles constrained at the end
    /// of each step, summed over the steps.
    pub with_objects: u64,
    pub with_surfaces: u64,
}

/// Whole-state measurements used to check rest, divergence and settling (spec F-37).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Diagnostics {
    pub max_speed: f64,
    pub kinetic_energy: f64,
    pub bounds: Aabb,
    pub all_finite: bool,
}

/// One surface's place in the world.
#[derive(Debug, Clone)]
pub struct SurfaceInfo {
    pub name: String,
    pub rows: usize,
    pub cols: usize,
    pub spacing: f64,
    pub particle_mass: f64,
    /// First particle of the surface in the world's flat arrays.
    pub offset: usize,
    pub grid: SurfaceGrid,
    /// Triangles in the surface's own (0-based) particle indices.
    pub triangles: Vec<[u32; 3]>,
}

impl SurfaceInfo {
    pub fn n_particles(&self) -> usize {
        self.rows * self.cols
    }

    pub fn range(&self) -> std::ops::Range<usize> {
        self.offset..self.offset + self.n_particles()
    }
}

/// A `TRANSLAÇÃO` window in step indices: active for steps whose start index s − 1 lies in [first, end).
#[derive(Debug, Clone, Copy)]
struct StepWindow {
    first: usize,
    end: usize,
    per_frame: DVec3,
}

/// The ODE system: forces of every surface, with pinned particles' accelerations held at zero.
#[derive(Debug, Clone)]
struct Model {
    surfaces: Vec<SurfaceForces>,
    pinned: Vec<bool>,
    friction_mode: FrictionMode,
    friction: f64,
    bend_reaction: bool,
    /// Δt when friction is clamped (spec S3.7 [EXT]).
    friction_clamp: Option<f64>,
    n: usize,
    /// Per-particle masses and the Hooke springs as a list, for implicit integration only (built when
    /// the scene asks for an integrator that needs Jacobians).
    masses: Vec<f64>,
    springs: Vec<(u32, u32, f64, f64)>,
    pattern: Vec<(u32, u32)>,
}

impl Model {
    /// Lists every Hooke spring (i, j, k, L0) of every surface with its Jacobian pattern.
    fn list_springs(&mut self) {
        for s in &self.surfaces {
            let (m, n, o) = (s.rows, s.cols, s.offset);
            let rd = s.spacing * std::f64::consts::SQRT_2;
            let [kh, kv, kd] = s.k;
            for i in 0..m {
                for j in 0..n {
                    let p = o + i * n + j;
                    let mut add = |q: usize, k: f64, l0: f64| {
                        if k != 0.0 {
                            self.springs.push((p as u32, q as u32, k, l0));
                            self.pattern.push((p as u32, q as u32));
                        }
                    };
                    if j + 1 < n {
                        add(p + 1, kh, s.spacing);
                    }
                    if i + 1 < m {
                        add(p + n, kv, s.spacing);
                        if j + 1 < n {
                            add(p + n + 1, kd, rd);
                        }
                        if j > 0 {
                            add(p + n - 1, kd, rd);
                        }
                    }
                }
            }
        }
    }
}

/// For implicit Euler: the force is the whole FLEX3D resultant (friction and angular springs included),
/// and the Jacobian holds the Hooke springs exactly (geometric term clamped at zero so the system stays
/// definite). Angular springs (no reaction, so not symmetric) and friction (not smooth) stay explicit.
impl anima_ode::Linearized<DVec3> for Model {
    fn masses(&self) -> &[f64] {
        &self.masses
    }

    fn prescribed(&self) -> &[bool] {
        &self.pinned
    }

    fn pattern(&self) -> &[(u32, u32)] {
        &self.pattern
    }

    fn force_and_jacobians(
        &mut self,
        t: f64,
        x: &[DVec3],
        v: &[DVec3],
        f: &mut [DVec3],
        jac: &mut anima_ode::Jacobians<DVec3>,
    ) {
        self.acceleration(t, x, v, f);
        for (fi, m) in f.iter_mut().zip(&self.masses) {
            *fi *= *m;
        }
        for (e, &(i, j, k, l0)) in self.springs.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let d = x[j] - x[i];
            let l = d.length();
            if l == 0.0 {
                continue;
            }
            let ks = crate::spring_net::spring_stiffness_block(d / l, l, k, l0, true);
            jac.k_diag[i] -= ks;
            jac.k_diag[j] -= ks;
            jac.k_off[e] += ks;
        }
    }
}

impl OdeSystem for Model {
    type Coord = DVec3;

    fn n_coords(&self) -> usize {
        self.n
    }

    fn linearized(&mut self) -> Option<&mut dyn anima_ode::Linearized<DVec3>> {
        if self.masses.is_empty() { None } else { Some(self) }
    }

    /// Resultant of gravity, external force, springs and angular springs, then friction (Nedel 1993 §3.2,
    /// evaluation order of §5.6), divided by the particle mass. Pinned particles follow their prescribed
    /// motion, so their acceleration is zero.
    fn acceleration(&mut self, _t: f64, x: &[DVec3], v: &[DVec3], a: &mut [DVec3]) {
        for s in &self.surfaces {
            let r = s.offset..s.offset + s.n_particles();
            let (xs, vs, fs) = (&x[r.clone()], &v[r.clone()], &mut a[r.clone()]);
            fs.fill(s.body_force);
            add_spring_forces(s, xs, fs);
            if s.kc != [0.0; 3] {
                add_bending_forces(s, xs, fs, self.bend_reaction);
            }
            let inv_mass = 1.0 / s.mass;
            let pinned = &self.pinned[r];
            for ((f, &vel), &pin) in fs.iter_mut().zip(vs).zip(pinned) {
                *f = if pin {
                    DVec3::ZERO
                } else {
                    acceleration_with_friction(
                        *f,
                        vel,
                        inv_mass,
                        self.friction_mode,
                        self.friction,
                        self.friction_clamp,
                    )
                };
            }
        }
    }
}

/// Collision data: static triangles prepared and binned once; surface triangles boxed every step from
/// their start-of-step positions (spec S3.5.5, A-14), binned with room to move (see [`SurfaceBins`]) and
/// prepared at most once per pass, when a path comes near them.
#[derive(Debug, Clone, Default)]
struct Colliders {
    n_static: usize,
    static_prepared: Vec<PreparedTriangle>,
    /// Corners of the static triangles (for the in-solve contacts' nearest points).
    static_corners: Vec<[DVec3; 3]>,
    /// Boxes of all triangles: static objects first, then every surface's.
    boxes: Vec<Aabb>,
    /// Particles of each triangle; `u32::MAX` for the corners of static triangles.
    corners: Vec<[u32; 3]>,
    static_grid: TriangleGrid,
    surface_bins: SurfaceBins,
    /// Test every triangle, as FLEX3D did; only for checking that the grid changes nothing.
    #[cfg(test)]
    brute_force: bool,
}

/// The surfaces' triangles binned with room to move, and a clearance per particle, so that the grid is
/// rebuilt only every so many steps and a particle far from every triangle is not tested at all (at
/// FLEX3D's steps of 10⁻⁴ s the cloth moves a fraction of a millimetre per step; rebuilding the grid
/// was the largest part of a step's cost, and testing particles against their neighbours' triangles
/// the next).
///
/// Each surface triangle is binned with its box grown by `margin` around the positions of `anchor`.
/// While no particle is farther than `margin` from its anchor in any coordinate (checked at every pass),
/// every triangle's current box lies inside its grown one, so a query finds every triangle whose current
/// box it overlaps (and some more, which the exact box test drops): the candidates that reach the exact
/// test are those of a grid rebuilt at every step.
///
/// `clearance[p]` is a lower bound, valid for as long as the grid is, on the distance from `anchor[p]`
/// to every surface triangle that does not contain p, at its current position: at most `reach`, and
/// for the triangles within reach their distance at the anchor positions less √3·`margin`, the farthest
/// any of their points can have moved. `static_clearance[p]` is the same for the static objects' triangles,
/// which do not move. A path that stays within the clearance of its particle's anchor cannot meet a
/// surface triangle, and is not tested against the surfaces; one within the static clearance is not
/// tested against the static objects. The two are kept apart because a cloth resting on a table is
/// within a hair of the table but far from its own triangles: its paths are tested against the table
/// only. Skipping only tests that cannot hit, and never changing the candidates of the others, the pass
/// gives the results of the brute force, to the bit (checked by the tests below and by
/// `docs/reproduction/flex3d-results.md`).
#[derive(Debug, Clone, Default)]
struct SurfaceBins {
    grid: TriangleGrid,
    anchor: Vec<DVec3>,
    margin: f64,
    reach: f64,
    clearance: Vec<f64>,
    static_clearance: Vec<f64>,
    grown: Vec<Aabb>,
    /// Surface triangles prepared at this pass's positions: `prepared[t]` is valid when
    /// `prepared_in[t] == pass`.
    prepared: Vec<PreparedTriangle>,
    prepared_in: Vec<u64>,
    pass: u64,
    /// Grid rebuilds, paths left untested for being within both clearances, and paths tested against
    /// the static objects only, so far.
    rebuilds: u64,
    skipped: u64,
    static_only: u64,
}

/// A triangle's box grows by this fraction of the surfaces' mean triangle extent when binned. With 0.1
/// a particle's room (√3·margin) stays well inside its distance from its neighbours' triangles on a
/// regular grid (about 0.7 of the spacing), so that almost every particle of a smooth surface skips its
/// tests; a larger room rebuilds less often but lets fewer particles skip. Measured (wall time of E-6
/// and E-8, two runs each, on a shared machine): 0.05 took 5.7–6.6 s and 0.9–1.5 s, 0.1 3.6–5.7 s and
/// 0.77–0.84 s, 0.2 3.4 s and 0.88–0.92 s, and 0.4 24–36 s and 2.8–3.5 s (the room then exceeds the
/// clearances and nothing is skipped).
const BIN_MARGIN: f64 = 0.1;

/// How far a clearance looks, in mean triangle extents.
const CLEARANCE_REACH: f64 = 1.0;

impl SurfaceBins {
    /// Starts a collision pass over the surface triangles `corners` (particle indices), with boxes
    /// `boxes` at the start-of-step positions `x`: rebuilds the grid and the clearances when a particle
    /// has left its room, and forgets the prepared triangles.
    fn begin(
        &mut self,
        boxes: &[Aabb],
        corners: &[[u32; 3]],
        x: &[DVec3],
        static_grid: &mut TriangleGrid,
        static_corners: &[[DVec3; 3]],
    ) {
        let moved =
            x.iter().zip(&self.anchor).map(|(a, b)| (*a - *b).abs().max_element()).fold(0.0, f64::max);
        // (A non-finite position is never skipped, its distance comparing false, and the step reports it.)
        if self.anchor.len() != x.len() || moved.is_nan() || moved > self.margin {
            self.rebuild(boxes, corners, x, static_grid, static_corners);
        }
        if self.prepared.len() != boxes.len() {
            self.prepared = vec![PreparedTriangle::new([DVec3::ZERO; 3]); boxes.len()];
            self.prepared_in = vec![0; boxes.len()];
        }
        self.pass += 1;
    }

    fn rebuild(
        &mut self,
        boxes: &[Aabb],
        corners: &[[u32; 3]],
        x: &[DVec3],
        static_grid: &mut TriangleGrid,
        static_corners: &[[DVec3; 3]],
    ) {
        let extent = boxes.iter().map(|b| b.size().max_element()).sum::<f64>() / boxes.len().max(1) as f64;
        self.margin = BIN_MARGIN * extent;
        self.reach = CLEARANCE_REACH * extent;
        let m = DVec3::splat(self.margin);
        self.grown.clear();
        self.grown.extend(boxes.iter().map(|b| Aabb { min: b.min - m, max: b.max + m }));
        self.grid.rebuild(&self.grown, Binning::MinCorner);
        self.anchor.clear();
        self.anchor.extend_from_slice(x);
        self.rebuilds += 1;
        let room = 3f64.sqrt() * self.margin;
        self.clearance.clear();
        self.clearance.resize(x.len(), 0.0);
        self.static_clearance.clear();
        self.static_clearance.resize(x.len(), 0.0);
        // A little less, so that round-off in the distances cannot let a path through.
        let shrink = |c: f64| c * (1.0 - 1e-9) - 1e-12;
        for (p, &a) in x.iter().enumerate() {
            let around = Aabb { min: a - DVec3::splat(self.reach), max: a + DVec3::splat(self.reach) };
            // A triangle's box is never farther than the triangle: one whose box is already beyond the
            // clearance found so far cannot lower it, and its exact distance is not computed.
            let mut c = self.reach;
            self.grid.query(&around, |t| {
                if !corners[t].contains(&(p as u32)) && boxes[t].distance_to(a) - room < c {
                    let tri = corners[t].map(|i| x[i as usize]);
                    c = c.min(point_triangle_proximity(a, tri).distance - room);
                }
            });
            self.clearance[p] = shrink(c);
            let mut c = self.reach;
            static_grid.query(&around, |t| {
                let tri = static_corners[t];
                if Aabb::from_points(tri).distance_to(a) < c {
                    c = c.min(point_triangle_proximity(a, tri).distance);
                }
            });
            self.static_clearance[p] = shrink(c);
        }
    }
}

/// All surfaces of a FLEX3D scene and the static objects they collide with.
#[derive(Debug)]
pub struct Flex3dWorld {
    model: Model,
    stepper: Stepper<DVec3>,
    /// State at t and the tentative state at t + Δt (Nedel 1993, Fig. 5.3).
    now: State<DVec3>,
    next: State<DVec3>,
    mass: Vec<f64>,
    surfaces: Vec<SurfaceInfo>,
    pinned_of_surface: Vec<Vec<usize>>,
    windows: Vec<Vec<StepWindow>>,
    objects: Vec<TriangleMesh>,
    colliders: Colliders,
    options: ModelOptions,
    dt: f64,
    frame_rate: f64,
    steps_per_frame: usize,
    step: u64,
    counts: CollisionCounts,
    /// `ATRITO`'s coefficient, the Coulomb coefficient of contacts in the solve.
    friction: f64,
    /// How far off a static surface the contacts in the solve keep a particle.
    contact_thickness: f64,
    /// Per particle, whether this step's collision pass or constraints changed it after the integrator.
    touched: Vec<bool>,
    /// The modern response between surfaces (`SelfCollisionMode::Modern`), when the scene asks for it.
    modern: Option<ModernSelfCollision>,
    /// The physical bounds every step is checked against, and the surfaces' row and column neighbours
    /// with their rest spacing (the springs whose strain is bounded).
    bounds: BoundsWatch,
    bounded_springs: Vec<(u32, u32, f64)>,
}

/// What the modern self-collision response of a world keeps: its settings, every surface's triangles
/// in world particle indices (one list, so surfaces are kept apart from one another too), the inverse
/// masses (0 for pinned particles), its scratch and what it did.
#[derive(Debug)]
struct ModernSelfCollision {
    settings: SelfCollision,
    triangles: Vec<[u32; 3]>,
    inv_mass: Vec<f64>,
    response: SelfCollisionResponse,
    total: SelfCollisionStats,
}

impl Flex3dWorld {
    /// Builds the flat surfaces of `scene` (spec S2.3, S5.7) with zero velocity, and the static
    /// colliders from `objects` (the meshes of `scene.objects`, in order).
    pub fn new(scene: &Flex3dScene, objects: Vec<TriangleMesh>) -> Result<Self, BuildError> {
        let bad = |m: &str| BuildError::Scene(m.to_owned());
        if !(scene.dt_s > 0.0 && scene.dt_s.is_finite()) {
            return Err(bad("the time step must be positive"));
        }
        if !(scene.frame_rate_hz > 0.0 && scene.frame_rate_hz.is_finite()) {
            return Err(bad("the frame rate must be positive"));
        }
        crate::check_fixed_step_integrator(scene.integrator).map_err(BuildError::Scene)?;
        if !(scene.gravity_m_s2.is_finite() && scene.external_force_n.is_finite()) {
            return Err(bad("gravity and external force must be finite"));
        }
        let opts = scene.options;
        let mut surfaces = Vec::new();
        let mut forces = Vec::new();
        let mut pinned_of_surface = Vec::new();
        let mut windows = Vec::new();
        let (mut x, mut mass, mut pinned) = (Vec::new(), Vec::new(), Vec::new());
        for s in &scene.surfaces {
            let err = |message: String| BuildError::Surface { surface: s.name.clone(), message };
            if s.rows < 2 || s.cols < 2 {
                return Err(err(format!("mesh must be at least 2×2, got {}×{}", s.rows, s.cols)));
            }
            if !(s.spacing_m > 0.0 && s.particle_mass_kg > 0.0) {
                return Err(err("spacing and particle mass must be positive".into()));
            }
            let frame = GridFrame::from_normal(s.centre_m, s.normal, opts.row_direction)
                .ok_or_else(|| err("the normal must be a non-zero finite vector".into()))?;
            let grid = SurfaceGrid { rows: s.rows, cols: s.cols, spacing: s.spacing_m, frame };
            let offset = x.len();
            x.extend(grid.positions());
            mass.extend(std::iter::repeat_n(s.particle_mass_kg, grid.n_particles()));
            pinned.extend(std::iter::repeat_n(false, grid.n_particles()));
            let mut pins = Vec::new();
            for &(i, j) in &s.fixed {
                if i >= s.rows || j >= s.cols {
                    return Err(err(format!(
                        "fixed point ({i}, {j}) is outside the {}×{} mesh",
                        s.rows, s.cols
                    )));
                }
                let p = offset + grid.index(i, j);
                if !pinned[p] {
                    pinned[p] = true;
                    pins.push(p);
                }
            }
            pinned_of_surface.push(pins);
            windows.push(
                s.translations
                    .iter()
                    .map(|t| StepWindow {
                        first: (t.start_s / scene.dt_s).round().max(0.0) as usize,
                        end: (t.end_s / scene.dt_s).round().max(0.0) as usize,
                        per_frame: t.per_frame_m,
                    })
                    .collect(),
            );
            let m = s.particle_mass_kg;
            let ext = if opts.external_force_is_acceleration {
                scene.external_force_n * m
            } else {
                scene.external_force_n
            };
            forces.push(SurfaceForces {
                offset,
                rows: s.rows,
                cols: s.cols,
                spacing: s.spacing_m,
                mass: m,
                k: s.stiffness_n_m,
                kc: s.bending_n_m,
                body_force: scene.gravity_m_s2 * m + ext,
            });
            surfaces.push(SurfaceInfo {
                name: s.name.clone(),
                rows: s.rows,
                cols: s.cols,
                spacing: s.spacing_m,
                particle_mass: m,
                offset,
                grid,
                triangles: grid_triangles(s.rows, s.cols),
            });
        }
        let n = x.len();
        let model = Model {
            surfaces: forces,
            pinned,
            friction_mode: scene.friction.mode,
            friction: scene.friction.coefficient,
            bend_reaction: opts.bend_reaction,
            friction_clamp: opts.friction_clamp.then_some(scene.dt_s),
            n,
            masses: Vec::new(),
            springs: Vec::new(),
            pattern: Vec::new(),
        };
        let mut model = model;
        if scene.integrator.needs_jacobians() {
            model.masses = mass.clone();
            model.list_springs();
        }
        if opts.self_collision == SelfCollisionMode::Modern && !opts.collisions {
            return Err(bad("the modern self-collision response needs collisions on"));
        }
        let min_spacing = scene.surfaces.iter().map(|s| s.spacing_m).fold(f64::INFINITY, f64::min);
        let modern = (opts.self_collision == SelfCollisionMode::Modern).then(|| ModernSelfCollision {
            settings: SelfCollision::for_spacing(min_spacing),
            triangles: surfaces
                .iter()
                .flat_map(|s| s.triangles.iter().map(|t| t.map(|i| i + s.offset as u32)))
                .collect(),
            inv_mass: mass.iter().zip(&model.pinned).map(|(m, &p)| if p { 0.0 } else { 1.0 / m }).collect(),
            response: SelfCollisionResponse::new(),
            total: SelfCollisionStats::default(),
        });
        let mut colliders = Colliders::default();
        if opts.collisions {
            for mesh in &objects {
                for t in 0..mesh.n_triangles() {
                    let c = mesh.corners(t);
                    colliders.static_prepared.push(PreparedTriangle::new(c));
                    colliders.static_corners.push(c);
                    colliders.boxes.push(Aabb::from_points(c));
                    colliders.corners.push([u32::MAX; 3]);
                }
            }
            colliders.n_static = colliders.static_prepared.len();
            colliders.static_grid.rebuild(&colliders.boxes, Binning::Spanning);
            for s in &surfaces {
                for t in &s.triangles {
                    colliders.corners.push(t.map(|i| i + s.offset as u32));
                }
            }
            colliders.boxes.resize(colliders.corners.len(), Aabb::EMPTY);
        }
        // FLEX3D scenes are driven (wind, translated points) and their soft springs stretch far in the
        // thesis's own scenes (the sail of E-5 to 11 times its rest spacing, the cardboard and the
        // paper to 3 times): only the speed is bounded by default. The speed a particle can be given: a
        // fall through the scene under the strongest body force (gravity and wind, per unit mass), plus
        // the fastest translation.
        let acceleration = model.surfaces.iter().map(|f| f.body_force.length() / f.mass).fold(0.0, f64::max);
        let driven = windows
            .iter()
            .flatten()
            .map(|w: &StepWindow| w.per_frame.length() * scene.frame_rate_hz)
            .fold(0.0, f64::max);
        let at_rest = vec![DVec3::ZERO; n];
        let defaults = Defaults { acceleration, driven, passive: false, max_strain: f64::INFINITY };
        let bounds = BoundsWatch::new(defaults, &x, &at_rest, &mass, scene.gravity_m_s2, 0.0);
        let mut bounded_springs = Vec::new();
        for s in &surfaces {
            for i in 0..s.rows {
                for j in 0..s.cols {
                    let p = (s.offset + i * s.cols + j) as u32;
                    if j + 1 < s.cols {
                        bounded_springs.push((p, p + 1, s.spacing));
                    }
                    if i + 1 < s.rows {
                        bounded_springs.push((p, p + s.cols as u32, s.spacing));
                    }
                }
            }
        }
        Ok(Self {
            bounds,
            bounded_springs,
            stepper: Stepper::new(scene.integrator, n),
            model,
            next: State::new(x.clone(), vec![DVec3::ZERO; n]),
            now: State::new(x, vec![DVec3::ZERO; n]),
            mass,
            surfaces,
            pinned_of_surface,
            windows,
            objects,
            colliders,
            options: opts,
            dt: scene.dt_s,
            frame_rate: scene.frame_rate_hz,
            steps_per_frame: (1.0 / (scene.frame_rate_hz * scene.dt_s)).round().max(1.0) as usize,
            step: 0,
            counts: CollisionCounts::default(),
            friction: scene.friction.coefficient,
            contact_thickness: THICKNESS_OF_SPACING * min_spacing,
            touched: vec![false; n],
            modern,
        })
    }

    /// Time at the current state: steps taken × Δt (counted, never accumulated).
    pub fn time(&self) -> f64 {
        self.step as f64 * self.dt
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.step
    }

    pub fn dt(&self) -> f64 {
        self.dt
    }

    pub fn surfaces(&self) -> &[SurfaceInfo] {
        &self.surfaces
    }

    pub fn objects(&self) -> &[TriangleMesh] {
        &self.objects
    }

    /// Positions of every particle of every surface, surface after surface, row-major.
    pub fn positions(&self) -> &[DVec3] {
        &self.now.x
    }

    pub fn velocities(&self) -> &[DVec3] {
        &self.now.v
    }

    /// Replaces every particle's position and velocity (surface after surface, as [`Self::positions`]
    /// lists them), for a caller that drives the surfaces itself. The integrator's history starts again
    /// and the collision pass rebuilds its grid and clearances at the next step. Pinned particles take
    /// the given positions too; their prescribed motion goes on from there.
    ///
    /// # Panics
    /// If `x` or `v` does not hold one value per particle.
    pub fn set_state(&mut self, x: &[DVec3], v: &[DVec3]) {
        assert!(x.len() == self.now.x.len() && v.len() == x.len(), "one position and velocity per particle");
        self.now.x.copy_from_slice(x);
        self.now.v.copy_from_slice(v);
        self.stepper.reset_history();
        self.colliders.surface_bins.anchor.clear();
    }

    pub fn surface_positions(&self, surface: usize) -> &[DVec3] {
        &self.now.x[self.surfaces[surface].range()]
    }

    pub fn is_pinned(&self, particle: usize) -> bool {
        self.model.pinned[particle]
    }

    pub fn collision_counts(&self) -> CollisionCounts {
        self.counts
    }

    /// What the modern self-collision response did over the run; `None` unless the scene asks for it.
    pub fn self_collision_stats(&self) -> Option<SelfCollisionStats> {
        self.modern.as_ref().map(|m| m.total)
    }

    /// Every surface's triangles in world particle indices, surface after surface: the mesh whose
    /// crossings with itself (a surface through itself or through another) count as self-intersections.
    pub fn all_triangles(&self) -> Vec<[u32; 3]> {
        self.surfaces
            .iter()
            .flat_map(|info| info.triangles.iter().map(|t| t.map(|i| i + info.offset as u32)))
            .collect()
    }

    /// Advances one step of Δt with the scene's integrator: tentative state from the integrator, then
    /// prescribed motion of pinned particles, then the collision pass over free particles (spec S4.4);
    /// with `ModelOptions::self_collision` = `Modern`, that pass tests static objects only and the
    /// modern response keeps the surfaces apart after it.
    ///
    /// With `ModelOptions::object_contact` = `InSolve`, contacts with static objects are constrained inside the
    /// implicit step instead, and the collision pass tests the surfaces only.
    pub fn step(&mut self) -> Result<(), StepError> {
        if self.step == 0 {
            // The bounds are taken from the state the run starts from.
            self.bounds.restart(&self.now.x, &self.now.v, &self.mass, DVec3::ZERO, 0.0);
        }
        let t = self.time();
        let in_solve = self.options.object_contact == ContactMode::InSolve
            && self.options.collisions
            && self.colliders.n_static > 0;
        let stepped = if in_solve {
            let mut contacts = StaticContacts {
                prepared: &self.colliders.static_prepared,
                corners: &self.colliders.static_corners,
                grid: &mut self.colliders.static_grid,
                thickness: self.contact_thickness,
                friction: self.friction,
            };
            self.stepper
                .step_with_contacts(&mut self.model, &mut contacts, t, self.dt, &self.now, &mut self.next)
                .map(|stats| self.counts.with_objects += stats.contacts as u64)
        } else {
            self.stepper.step(&mut self.model, t, self.dt, &self.now, &mut self.next).map(|_| ())
        };
        stepped.map_err(|source| StepError::Solver {
            step: self.step + 1,
            time: (self.step + 1) as f64 * self.dt,
            source,
        })?;
        self.touched.fill(false);
        let constraints_changed = self.apply_constraints();
        if constraints_changed {
            for pins in &self.pinned_of_surface {
                for &p in pins {
                    self.touched[p] = true;
                }
            }
        }
        let surfaces = self.options.self_collision == SelfCollisionMode::Faithful
            && self.colliders.corners.len() > self.colliders.n_static;
        if self.options.collisions && (surfaces || (!in_solve && self.colliders.n_static > 0)) {
            self.collide(!in_solve, surfaces);
        }
        if let Some(m) = &mut self.modern {
            let stats = m.response.filter_step(
                &m.settings,
                self.dt,
                &self.now.x,
                &mut self.next.x,
                &mut self.next.v,
                &m.inv_mass,
                &m.triangles,
                &mut self.touched,
            );
            m.total += stats;
        }
        // A multistep method's history no longer describes the motion after a velocity jump (spec
        // S4.2.3: restart after any collision response or constraint discontinuity); generalised-α forgets
        // the acceleration of the particles the jump touched only.
        if self.touched.contains(&true) {
            self.stepper.reset_history_of(&self.touched);
        }
        std::mem::swap(&mut self.now, &mut self.next);
        self.step += 1;
        self.check_finite()?;
        let gravity = DVec3::ZERO;
        let springs = self.bounded_springs.iter().copied();
        Ok(self.bounds.check(
            self.step,
            self.time(),
            &self.now.x,
            &self.now.v,
            &self.mass,
            gravity,
            springs,
        )?)
    }

    /// The physical bounds every step is checked against ([`crate::bounds`]: speed and strain, by
    /// default [`Bounds::for_start`] of the scene with its strongest body force and fastest translation).
    pub fn bounds(&self) -> Bounds {
        self.bounds.bounds
    }

    /// Sets the bounds (the energy bound does not apply to FLEX3D's driven scenes); [`Bounds::unbounded`]
    /// checks finiteness only.
    pub fn set_bounds(&mut self, bounds: Bounds) {
        let bounds = Bounds { energy_factor: None, ..bounds };
        self.bounds.set(bounds, &self.now.x, &self.now.v, &self.mass, DVec3::ZERO, 0.0);
    }

    /// Pinned particles: x̃ = x + u·Δt, ṽ = u with u the sum of active translation velocities (spec S3.6).
    /// This runs before the collision pass so that a pinned collision partner already moves with its
    /// prescribed velocity; collisions never change a pinned particle.
    /// Returns whether any pinned particle's velocity changed (a window opened or closed).
    fn apply_constraints(&mut self) -> bool {
        let mut changed = false;
        let s0 = self.step as usize; // the step starting at t = s0·Δt
        for (pins, windows) in self.pinned_of_surface.iter().zip(&self.windows) {
            let mut u = DVec3::ZERO;
            let mut jump = DVec3::ZERO;
            for w in windows.iter().filter(|w| w.first <= s0 && s0 < w.end) {
                match self.options.translation {
                    TranslationMode::Continuous => u += w.per_frame * self.frame_rate,
                    TranslationMode::PerFrameJump => {
                        if s0.is_multiple_of(self.steps_per_frame) {
                            jump += w.per_frame;
                        }
                    }
                }
            }
            for &p in pins {
                self.next.x[p] = self.now.x[p] + u * self.dt + jump;
                changed |= self.now.v[p] != u || jump != DVec3::ZERO;
                self.next.v[p] = u;
            }
        }
        changed
    }

    /// The collision pass of spec S3.5.5 over all free particles in a fixed order (surface order, then
    /// row-major). Each path x → x̃ is tested against every triangle that does not contain the particle,
    /// static objects and surfaces alike (surfaces at their start-of-step positions); the first hit
    /// (smallest segment parameter, then lowest triangle index) is answered with a 1-D elastic impact, and
    /// the particle stays where it was at the start of the step. Without `static_objects` only the
    /// surfaces' triangles are tested (the static ones are the implicit solve's); without `surfaces`
    /// only the static ones (the surfaces are the modern response's, or pass through one another).
    fn collide(&mut self, static_objects: bool, surfaces: bool) {
        let Self { colliders, now, next, model, mass, options, counts, touched, .. } = self;
        let (x, x_new, v_new) = (&now.x, &mut next.x, &mut next.v);
        #[cfg(test)]
        let brute_force = colliders.brute_force;
        #[cfg(not(test))]
        let brute_force = false;
        let Colliders {
            n_static,
            static_prepared,
            static_corners,
            boxes,
            corners,
            static_grid,
            surface_bins,
            ..
        } = colliders;
        let n_static = *n_static;
        let last = if surfaces { corners.len() } else { n_static };
        if surfaces {
            for t in n_static..corners.len() {
                boxes[t] = Aabb::from_points(corners[t].map(|i| x[i as usize]));
            }
            surface_bins.begin(&boxes[n_static..], &corners[n_static..], x, static_grid, static_corners);
        }
        let SurfaceBins {
            grid: surface_grid,
            prepared,
            prepared_in,
            pass,
            anchor,
            clearance,
            static_clearance,
            skipped,
            static_only,
            ..
        } = surface_bins;
        let pass = *pass;
        let pinned = &model.pinned;
        for p in 0..x.len() {
            if pinned[p] {
                continue;
            }
            let o = x[p];
            let dir = x_new[p] - o;
            if dir == DVec3::ZERO {
                continue;
            }
            // A path within its particle's clearances cannot meet a triangle (see `SurfaceBins`; the
            // clearances are kept only while the surfaces are tested).
            let (mut test_static, mut test_surfaces) = (static_objects && n_static > 0, surfaces);
            if surfaces && !brute_force {
                // (A non-finite reach is within no clearance: such a path is tested.)
                let reach = o.distance(anchor[p]) + dir.length();
                let within = |c: f64| reach < c;
                test_surfaces = !within(clearance[p]);
                test_static &= !within(static_clearance[p]);
                if !test_surfaces {
                    if !test_static {
                        *skipped += 1;
                        continue;
                    }
                    *static_only += 1;
                }
            }
            let seg = Aabb::from_points([o, x_new[p]]);
            let mut best: Option<(f64, usize, [f64; 3])> = None;
            let mut test = |t: usize| {
                // A particle lies on the boxes of the triangles around it, so the cheap ownership test goes
                // first.
                if corners[t].contains(&(p as u32)) || !seg.overlaps(&boxes[t]) {
                    return;
                }
                let tri = if t < n_static {
                    static_prepared[t]
                } else {
                    let k = t - n_static;
                    if prepared_in[k] != pass {
                        prepared[k] = PreparedTriangle::new(corners[t].map(|i| x[i as usize]));
                        prepared_in[k] = pass;
                    }
                    prepared[k]
                };
                if let Some(hit) = anima_geom::segment_triangle(o, dir, &tri) {
                    let better = match best {
                        None => true,
                        Some((s, bt, _)) => hit.s < s || (hit.s == s && t < bt),
                    };
                    if better {
                        best = Some((hit.s, t, hit.barycentric));
                    }
                }
            };
            if brute_force {
                let first = if static_objects { 0 } else { n_static };
                (first..last).for_each(&mut test);
            } else {
                if test_static {
                    static_grid.query(&seg, &mut test);
                }
                if test_surfaces {
                    surface_grid.query(&seg, |t| test(t + n_static));
                }
            }
            let Some((_, t, bary)) = best else { continue };
            let v_tilde = v_new[p];
            touched[p] = true;
            if t < n_static {
                v_new[p] = match options.static_response {
                    StaticResponse::Reverse => -v_tilde,
                    StaticResponse::ReflectNormal => {
                        let n = static_prepared[t].unit_normal();
                        v_tilde - n * (2.0 * v_tilde.dot(n))
                    }
                };
                counts.with_objects += 1;
            } else {
                let tri = corners[t].map(|i| i as usize);
                match options.contact {
                    ContactApproach::NearestVertex => {
                        let k = if bary[0] >= bary[1] && bary[0] >= bary[2] {
                            0
                        } else if bary[1] >= bary[2] {
                            1
                        } else {
                            2
                        };
                        let q = tri[k];
                        if pinned[q] {
                            // An immovable partner moving with its prescribed velocity u: v ← 2u − ṽ.
                            v_new[p] = v_new[q] * 2.0 - v_tilde;
                        } else {
                            let (vp, vq) = elastic_1d(mass[p], v_tilde, mass[q], v_new[q]);
                            v_new[p] = vp;
                            v_new[q] = vq;
                            touched[q] = true;
                        }
                    }
                    ContactApproach::ThreeVertices => {
                        let mean = (v_new[tri[0]] + v_new[tri[1]] + v_new[tri[2]]) * (1.0 / 3.0);
                        if tri.iter().any(|&q| pinned[q]) {
                            v_new[p] = mean * 2.0 - v_tilde;
                        } else {
                            let body_mass = mass[tri[0]] + mass[tri[1]] + mass[tri[2]];
                            let (vp, vb) = elastic_1d(mass[p], v_tilde, body_mass, mean);
                            v_new[p] = vp;
                            for q in tri {
                                v_new[q] += vb - mean;
                                touched[q] = true;
                            }
                        }
                    }
                }
                counts.with_surfaces += 1;
            }
            x_new[p] = o;
        }
    }

    /// Largest frequency ω_max of the model at the current state (power iteration on the acceleration's
    /// finite differences; pinned particles excluded), for the stability warning of explicit methods.
    pub fn max_frequency(&mut self) -> f64 {
        let t = self.time();
        let pinned = self.model.pinned.clone();
        anima_ode::stability::max_frequency(&mut self.model, t, &self.now.x, &self.now.v, &pinned, 60)
    }

    /// The integrator, to choose its linear solver or reset its history.
    pub fn stepper_mut(&mut self) -> &mut Stepper<DVec3> {
        &mut self.stepper
    }

    /// The scene's integrator.
    pub fn integrator(&self) -> anima_ode::Integrator {
        self.stepper.integrator()
    }

    /// Steps until `steps() == target` (no-op if already there or past it).
    pub fn run_to_step(&mut self, target: u64) -> Result<(), StepError> {
        while self.step < target {
            self.step()?;
        }
        Ok(())
    }

    fn check_finite(&self) -> Result<(), NonFinite> {
        let Some(p) = self.now.first_non_finite() else { return Ok(()) };
        let s = self.surfaces.iter().find(|s| s.range().contains(&p)).expect("every particle has a surface");
        let local = p - s.offset;
        Err(NonFinite {
            step: self.step,
            time: self.time(),
            particle: p,
            place: Some(GridPlace { surface: s.name.clone(), row: local / s.cols, col: local % s.cols }),
        })
    }

    /// Maximum speed, kinetic energy Σ ½ m |v|², bounding box, finiteness (spec F-37).
    pub fn diagnostics(&self) -> Diagnostics {
        let mut max_speed = 0.0f64;
        let mut kinetic_energy = 0.0;
        for (v, m) in self.now.v.iter().zip(&self.mass) {
            let s2 = v.length_squared();
            max_speed = max_speed.max(s2.sqrt());
            kinetic_energy += 0.5 * m * s2;
        }
        let all_finite = self.now.x.iter().chain(&self.now.v).all(|p| p.is_finite());
        Diagnostics {
            max_speed,
            kinetic_energy,
            bounds: Aabb::from_points(self.now.x.iter().copied()),
            all_finite,
        }
    }

    /// Particles that lie inside a static object (a closed mesh) now.
    pub fn penetrations(&self) -> usize {
        let boxes: Vec<Aabb> = self.objects.iter().map(|o| o.aabb()).collect();
        self.now
            .x
            .iter()
            .filter(|&&p| {
                self.objects
                    .iter()
                    .zip(&boxes)
                    .any(|(o, b)| b.overlaps(&Aabb::from_points([p])) && o.contains_point(p))
            })
            .count()
    }

    /// Largest relative spring strain |L − L0|/L0 over the structural and diagonal springs.
    pub fn max_strain(&self) -> f64 {
        let mut worst = 0.0f64;
        for s in &self.surfaces {
            let x = &self.now.x[s.range()];
            let (m, n, r) = (s.rows, s.cols, s.spacing);
            let rd = r * std::f64::consts::SQRT_2;
            let mut check =
                |p: usize, q: usize, l0: f64| worst = worst.max(((x[p] - x[q]).length() - l0).abs() / l0);
            for i in 0..m {
                for j in 0..n {
                    let p = i * n + j;
                    if j + 1 < n {
                        check(p, p + 1, r);
                    }
                    if i + 1 < m {
                        check(p, p + n, r);
                        if j + 1 < n {
                            check(p, p + n + 1, rd);
                        }
                        if j > 0 {
                            check(p, p + n - 1, rd);
                        }
                    }
                }
            }
        }
        worst
    }
}

/// Velocities after a 1-D perfectly elastic impact (Nedel 1993 Eqs. 3.2–3.6), applied to each component:
/// v1f = ((m1 − m2) v1 + 2 m2 v2)/(m1 + m2), v2f = (2 m1 v1 + (m2 − m1) v2)/(m1 + m2). Equal masses swap
/// velocities exactly.
fn elastic_1d(m1: f64, v1: DVec3, m2: f64, v2: DVec3) -> (DVec3, DVec3) {
    if m1 == m2 {
        return (v2, v1);
    }
    let total = m1 + m2;
    ((v1 * (m1 - m2) + v2 * (2.0 * m2)) / total, (v1 * (2.0 * m1) + v2 * (m2 - m1)) / total)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::flex3d::{Friction, SurfaceDesc};

    /// A sheet pinned along one edge, blown back onto itself and dropped on a box: many surface and
    /// object contacts.
    fn folding_scene() -> (Flex3dScene, Vec<TriangleMesh>) {
        let scene = Flex3dScene {
            duration_s: 4.0,
            frame_rate_hz: 1.0,
            dt_s: 0.002,
            gravity_m_s2: super::super::FLEX3D_GRAVITY,
            external_force_n: DVec3::new(0.0, 0.0, -2.0),
            friction: Friction { mode: FrictionMode::Literal, coefficient: 0.2 },
            objects: vec![],
            integrator: Default::default(),
            options: ModelOptions::thesis(),
            surfaces: vec![SurfaceDesc {
                name: "s".into(),
                rows: 16,
                cols: 16,
                spacing_m: 1.0,
                centre_m: DVec3::new(0.0, 8.0, 0.0),
                normal: DVec3::new(0.2, 1.0, 0.3),
                particle_mass_kg: 0.2,
                stiffness_n_m: [5.0; 3],
                bending_n_m: [0.0; 3],
                fixed: vec![],
                translations: vec![],
            }],
        };
        let table = anima_geom::box_mesh(DVec3::new(-3.0, 0.0, -3.0), DVec3::new(3.0, 5.0, 3.0));
        (scene, vec![table])
    }

    #[test]
    fn broad_phase_changes_no_result() {
        let (scene, objects) = folding_scene();
        let mut grid = Flex3dWorld::new(&scene, objects.clone()).unwrap();
        let mut brute = Flex3dWorld::new(&scene, objects).unwrap();
        brute.colliders.brute_force = true;
        for step in 0..scene.n_steps() {
            grid.step().unwrap();
            brute.step().unwrap();
            assert_eq!(grid.positions(), brute.positions(), "positions differ after step {step}");
        }
        let c = grid.collision_counts();
        assert!(c.with_objects > 100 && c.with_surfaces > 10, "the scene must exercise both kinds: {c:?}");
        assert_eq!(c, brute.collision_counts());
        // The persistent grid and the clearances did their work (or the comparison tested nothing).
        let bins = &grid.colliders.surface_bins;
        assert!(bins.rebuilds < scene.n_steps() as u64 / 2, "{} rebuilds", bins.rebuilds);
        assert!(bins.skipped > 0, "no path was skipped");
        assert!(bins.static_only > 0, "no path was tested against the box alone");
    }

    #[test]
    fn elastic_impact_conserves_momentum_and_energy() {
        let (v1, v2) = (DVec3::new(1.0, -2.0, 0.5), DVec3::new(-0.5, 0.0, 2.0));
        let (a, b) = elastic_1d(2.0, v1, 3.0, v2);
        assert!((v1 * 2.0 + v2 * 3.0 - (a * 2.0 + b * 3.0)).length() < 1e-12);
        let e = |x: DVec3, y: DVec3| 2.0 * x.length_squared() + 3.0 * y.length_squared();
        assert!((e(v1, v2) - e(a, b)).abs() < 1e-12);
        assert_eq!(elastic_1d(1.0, v1, 1.0, v2), (v2, v1));
    }
}
