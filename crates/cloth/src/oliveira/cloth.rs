//! A cloth on a fixed triangle mesh stepped the way Oliveira 2013 does it (Fig. 4.1): the dynamic step
//! of Eq. 4.6, an RK4 step of the non-contact forces, then the path test and collision response.

use std::f64::consts::PI;

use anima_geom::query::HalfSpace;
use anima_geom::{
    Aabb, Cylinder, DVec2, DVec3, MaterialMesh, MaterialMeshError, MeshSolid, Solid, Sphere, TriangleMesh,
};
use anima_ode::{OdeError, SavedHistory, State, Stepper};

use super::bending::BendingElements;
use super::contact::{ClearanceCache, Collider, ContactPass, SolveContacts, first_hit};
use super::forces::ClothModel;
use super::material::Material;
use super::scene::{Centre, Height, OliveiraScene, Options, ShapeDesc, StepRule, UpAxis};
use super::springs::Springs;
use crate::bounds::{Bounds, BoundsWatch, Defaults};
use crate::contact_mode::ContactMode;
use crate::error::{NonFinite, StepError};
use crate::membrane::{Membrane, MembraneError, MembraneMaterial};
use crate::self_collision::{
    OBJECT_ROUNDS, SelfCollision, SelfCollisionMode, SelfCollisionResponse, SelfCollisionStats,
};

/// Why a scene could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    #[error("scene: `{field}` {message}")]
    Field { field: &'static str, message: String },
    #[error("object `{name}`: {message}")]
    Object { name: String, message: String },
    #[error("the scene names {expected} mesh objects but {given} meshes were given")]
    MeshCount { expected: usize, given: usize },
    #[error("cloth mesh: {0}")]
    Mesh(#[from] MaterialMeshError),
    #[error("cloth particle {vertex} starts inside object `{object}`")]
    StartsInside { vertex: usize, object: String },
}

/// How many times a step may be halved (so down to a quarter of it) when the self-collision response
/// had to freeze an impact zone. Measured on the 257² Bunny drape at 1/60 s (3.9 mm edges): at the
/// floor impact the fail-safe froze three zones of 29 particles, held where they started while the
/// cloth around them fell on by 5 cm; their springs reached 372 % strain, and two steps later the
/// drape was torn apart at 35 m/s (3 243 %), each step taking minutes. The same drape at 1/120 s goes
/// through the impact with its strain under 34 %.
pub const MAX_SPLITS: u32 = 2;

/// A frozen zone splits the step only if one of its particles would have moved more than this
/// fraction of the shortest spring's rest length: a zone frozen while it barely moves (layers resting
/// on the floor) stretches nothing. On the folding drape of the self-collision tests at 1/60 s, zones
/// froze in most steps; splitting every one of them took each step down to quarters.
pub const SPLIT_MOTION: f64 = 0.25;

/// What one step did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepReport {
    /// The step just taken, s.
    pub dt: f64,
    /// Particles whose path met an object.
    pub hits: usize,
}

/// The cloth, its objects and its state.
#[derive(Debug)]
pub struct OliveiraCloth {
    mesh: MaterialMesh,
    model: ClothModel,
    stepper: Stepper<DVec3>,
    now: State<DVec3>,
    next: State<DVec3>,
    colliders: Vec<Collider>,
    /// Per particle, a lower bound on its distance from every surface (see `Options::cull_collision_tests`).
    clearance: Vec<f64>,
    /// Per particle, whether the contact pass has answered it this step (with contact in the solve:
    /// whether it ended the step in contact).
    responded: Vec<bool>,
    /// Distance bounds of the in-solve contact model.
    solve_cache: ClearanceCache,
    /// Positions before the strain limit moved them (sized on first use).
    before_limit: Vec<DVec3>,
    material: Material,
    restitution: f64,
    rule: StepRule,
    options: Options,
    m_min: f64,
    k_max: f64,
    tracked: usize,
    time: f64,
    steps: u64,
    first_collision: Option<f64>,
    total_hits: u64,
    /// Steps taken again in halves because the self-collision response froze a zone.
    split_steps: u64,
    /// The integrator's history at the start of the step being taken, for a retake in halves.
    saved_history: SavedHistory<DVec3>,
    /// Edges cast at the end of every step and answered on both ends: the adaptive remesher
    /// sets them to the edges it may no longer refine. Empty for a static mesh.
    repelled_edges: Vec<[u32; 2]>,
    /// The modern self-collision response (`Options::self_collision` = `Modern`), its settings for the
    /// current mesh (the thickness follows the shortest rest edge), which particles it changed in the
    /// last step, and what it did over the run.
    self_collision: Option<SelfCollision>,
    self_response: SelfCollisionResponse,
    self_touched: Vec<bool>,
    /// The inverse masses the response sees: 0 for particles an object answered this step (or that the
    /// response would push into one), and the step's end before the response (for its next round).
    self_inv_mass: Vec<f64>,
    before_filter: (Vec<DVec3>, Vec<DVec3>),
    self_total: SelfCollisionStats,
    /// The physical bounds every step is checked against, and gravity (for the energy bound).
    bounds: BoundsWatch,
    gravity: DVec3,
}

/// The modern response's settings for `mesh`, when `options` ask for it.
fn self_collision_for(options: &Options, mesh: &MaterialMesh) -> Option<SelfCollision> {
    (options.self_collision == SelfCollisionMode::Modern).then(|| {
        let shortest = mesh.edge_rest_lengths().into_iter().fold(f64::INFINITY, f64::min);
        SelfCollision::for_spacing(shortest)
    })
}

/// The continuum model of [`Options::membrane`] on `mesh`'s rest shape (flat, z = 0), with the cloth's
/// surface density; gravity and drag stay with the cloth.
fn membrane_on(
    mesh: &MaterialMesh,
    m: MembraneMaterial,
    material: &Material,
) -> Result<Membrane, MembraneError> {
    let rest: Vec<DVec3> = mesh.rest().iter().map(|p| p.extend(0.0)).collect();
    let density = material.density_kg_m3 * material.thickness_m;
    Membrane::new(&rest, mesh.triangles(), m, density, vec![false; rest.len()], DVec3::ZERO)
}

fn field(field: &'static str, message: impl Into<String>) -> BuildError {
    BuildError::Field { field, message: message.into() }
}

fn finite_positive(name: &'static str, v: f64) -> Result<(), BuildError> {
    if v.is_finite() && v > 0.0 { Ok(()) } else { Err(field(name, format!("must be positive, got {v}"))) }
}

/// The rotation that takes a file's `up` axis to +z (a proper rotation, so triangle winding is kept).
fn to_z_up(up: UpAxis, p: DVec3) -> DVec3 {
    match up {
        UpAxis::X => DVec3::new(-p.z, p.y, p.x),
        UpAxis::Y => DVec3::new(p.x, -p.z, p.y),
        UpAxis::Z => p,
    }
}

/// A mesh rotated to z up, scaled to `length` along its longest horizontal side and stood with the
/// centre of its bounding box's bottom at `base_centre`.
pub fn place_mesh(
    mesh: &TriangleMesh,
    up: UpAxis,
    length: f64,
    base_centre: DVec3,
) -> Result<TriangleMesh, String> {
    let rotated: Vec<DVec3> = mesh.vertices().iter().map(|&p| to_z_up(up, p)).collect();
    let b = Aabb::from_points(rotated.iter().copied());
    let extent = b.size().x.max(b.size().y);
    if extent.is_nan() || extent <= 0.0 {
        return Err("the mesh has no horizontal extent".to_owned());
    }
    let scale = length / extent;
    let bottom = DVec3::new(b.centre().x, b.centre().y, b.min.z);
    let placed = rotated.iter().map(|&p| base_centre + (p - bottom) * scale).collect();
    TriangleMesh::new(placed, mesh.triangles().to_vec()).map_err(|e| e.to_string())
}

fn build_collider(
    desc: &super::scene::ObjectDesc,
    meshes: &mut impl Iterator<Item = TriangleMesh>,
) -> Result<Collider, BuildError> {
    let err = |message: String| BuildError::Object { name: desc.name.clone(), message };
    if !(desc.friction.is_finite() && desc.friction >= 0.0) {
        return Err(err(format!("friction must be non-negative, got {}", desc.friction)));
    }
    let max = anima_format::limits::MAX_LENGTH_M;
    let positive = |what: &str, v: f64| {
        if !(v.is_finite() && v > 0.0) {
            Err(err(format!("{what} must be positive, got {v}")))
        } else if v > max {
            Err(err(format!("{what} must be at most {max:e} m, got {v:e}")))
        } else {
            Ok(())
        }
    };
    let finite = |what: &str, v: DVec3| {
        if !v.is_finite() {
            Err(err(format!("{what} must be finite")))
        } else if v.abs().max_element() > max {
            Err(err(format!("{what} must lie within {max:e} m of the origin")))
        } else {
            Ok(())
        }
    };
    let solid = match &desc.shape {
        ShapeDesc::Mesh { file, up, length_m, base_centre_m } => {
            positive("length_m", *length_m)?;
            finite("base_centre_m", *base_centre_m)?;
            let raw = meshes.next().ok_or_else(|| err(format!("no mesh was loaded for `{file}`")))?;
            let placed = place_mesh(&raw, *up, *length_m, *base_centre_m).map_err(err)?;
            Solid::Mesh(MeshSolid::new(&placed).map_err(|e| err(format!("`{file}`: {e}")))?)
        }
        ShapeDesc::Sphere { centre_m, radius_m } => {
            positive("radius_m", *radius_m)?;
            finite("centre_m", *centre_m)?;
            Solid::Sphere(Sphere { centre: *centre_m, radius: *radius_m })
        }
        ShapeDesc::Cylinder { base_centre_m, radius_m, height_m } => {
            positive("radius_m", *radius_m)?;
            positive("height_m", *height_m)?;
            finite("base_centre_m", *base_centre_m)?;
            Solid::Cylinder(Cylinder { base_centre: *base_centre_m, radius: *radius_m, height: *height_m })
        }
        ShapeDesc::HalfSpace { point_m, normal } => {
            finite("point_m", *point_m)?;
            Solid::HalfSpace(
                HalfSpace::new(*point_m, *normal)
                    .ok_or_else(|| err("normal must be non-zero and finite".into()))?,
            )
        }
    };
    Ok(Collider { name: desc.name.clone(), solid, friction: desc.friction })
}

impl OliveiraCloth {
    /// Builds the cloth of `scene` at rest, with its objects. `meshes` are the loaded files of the
    /// scene's `Mesh` objects, in the order the scene lists them.
    pub fn new(scene: &OliveiraScene, meshes: Vec<TriangleMesh>) -> Result<Self, BuildError> {
        finite_positive("duration_s", scene.duration_s)?;
        crate::check_fixed_step_integrator(scene.integrator).map_err(|why| field("integrator", why))?;
        if !scene.gravity_m_s2.is_finite() {
            return Err(field("gravity_m_s2", "must be finite"));
        }
        if !(0.0..=1.0).contains(&scene.restitution) {
            return Err(field("restitution", format!("must lie in [0, 1], got {}", scene.restitution)));
        }
        let eta = scene.options.bending_height_floor;
        if !(0.0..=1.0).contains(&eta) {
            return Err(field("options.bending_height_floor", format!("must lie in [0, 1], got {eta}")));
        }
        if let Some(tau) = scene.options.strain_limit
            && !(tau.is_finite() && tau > 0.0)
        {
            return Err(field(
                "options.strain_limit",
                format!("must be a positive, finite strain, got {tau}"),
            ));
        }
        if let Some(eps) = scene.options.friction_smoothing_m_s
            && !(eps.is_finite() && eps > 0.0)
        {
            return Err(field(
                "options.friction_smoothing_m_s",
                format!("must be a positive, finite speed, got {eps}"),
            ));
        }
        if let Some(name) = scene.material.invalid_field() {
            return Err(field("material", format!("field `{name}` is out of range")));
        }
        match scene.time_step {
            StepRule::Provot { beta, startup_dt_s } => {
                finite_positive("time_step.beta", beta)?;
                if let Some(dt) = startup_dt_s {
                    finite_positive("time_step.startup_dt_s", dt)?;
                }
            }
            StepRule::Fixed { dt_s } => finite_positive("time_step.dt_s", dt_s)?,
        }
        let c = &scene.cloth;
        finite_positive("cloth.size_m", c.size_m)?;
        let n = c.vertices_per_side;
        let (row, col) = c.tracked_vertex;
        if row >= n || col >= n {
            return Err(field(
                "cloth.tracked_vertex",
                format!("({row}, {col}) is outside the {n} × {n} grid"),
            ));
        }

        let expected = scene.objects.iter().filter(|o| matches!(o.shape, ShapeDesc::Mesh { .. })).count();
        if expected != meshes.len() {
            return Err(BuildError::MeshCount { expected, given: meshes.len() });
        }
        let mut meshes = meshes.into_iter();
        let colliders =
            scene.objects.iter().map(|o| build_collider(o, &mut meshes)).collect::<Result<Vec<_>, _>>()?;

        let mesh = MaterialMesh::grid(n, c.size_m, c.diagonals)?;
        let z0 = match c.height {
            Height::At { z_m } if z_m.is_finite() => z_m,
            Height::AboveObjects { clearance_m } if clearance_m.is_finite() && clearance_m >= 0.0 => {
                let top = colliders
                    .iter()
                    .map(|o| o.solid.aabb().max.z)
                    .filter(|z| z.is_finite())
                    .fold(f64::NEG_INFINITY, f64::max);
                if top == f64::NEG_INFINITY {
                    return Err(field("cloth.height", "AboveObjects needs at least one bounded object"));
                }
                top + clearance_m
            }
            _ => return Err(field("cloth.height", "must be finite (and the clearance non-negative)")),
        };
        let half = DVec2::splat(c.size_m / 2.0);
        let centre = match c.centre {
            Centre::At(xy) if xy.is_finite() => xy,
            Centre::At(_) => return Err(field("cloth.centre", "must be finite")),
            Centre::OverHighestPoint => colliders
                .iter()
                .filter_map(|o| o.solid.highest_point())
                .reduce(|a, b| if b.z > a.z { b } else { a })
                .ok_or_else(|| field("cloth.centre", "OverHighestPoint needs at least one bounded object"))?
                .truncate(),
        };
        let origin = (centre - half).extend(z0);
        let x = mesh.place(origin, DVec3::X, DVec3::Y);
        for (vertex, p) in x.iter().enumerate() {
            if let Some(o) = colliders.iter().find(|o| o.solid.contains(*p)) {
                return Err(BuildError::StartsInside { vertex, object: o.name.clone() });
            }
        }

        let material = scene.material;
        let areas = mesh.vertex_areas();
        let mass: Vec<f64> = areas.iter().map(|&a| material.particle_mass(a)).collect();
        let rest_length = mesh.edge_rest_lengths();
        let springs = Springs {
            ends: mesh.topology().edges().iter().map(|e| e.vertices).collect(),
            stiffness: rest_length.iter().map(|&l| material.spring_stiffness(l)).collect(),
            damping: rest_length.iter().map(|&l| material.spring_damping(l)).collect(),
            rest_length,
        };
        let bending = BendingElements {
            stencils: mesh.topology().interior_stencils().iter().map(|s| s.vertices).collect(),
        };
        let m_min = mass.iter().copied().fold(f64::INFINITY, f64::min);
        let k_max = springs.max_stiffness();
        let model = ClothModel {
            inv_mass: mass.iter().map(|m| 1.0 / m).collect(),
            weight: mass.iter().map(|&m| scene.gravity_m_s2 * m).collect(),
            drag: areas.iter().map(|&a| material.particle_drag(a)).collect(),
            mass,
            springs,
            bending,
            bending_stiffness: material.bending_stiffness,
            bending_damping: material.bending_damping,
            bending_height_floor: scene.options.bending_height_floor,
            spring_law: scene.options.spring,
            damper_law: scene.options.damper,
            membrane: match scene.options.membrane {
                Some(m) => Some(
                    membrane_on(&mesh, m, &material)
                        .map_err(|e| field("options.membrane", format!("is not usable: {e}")))?,
                ),
                None => None,
            },
            implicit: Default::default(),
        };
        let n_vertices = x.len();
        let at_rest = vec![DVec3::ZERO; n_vertices];
        // Provot's strain limit moves particles and gives them the velocity of the move: energy from
        // outside the model, so no energy bound with it.
        let defaults = Defaults {
            passive: scene.options.strain_limit.is_none(),
            ..Defaults::passive(scene.gravity_m_s2)
        };
        let bounds = BoundsWatch::new(defaults, &x, &at_rest, &model.mass, scene.gravity_m_s2, 0.0);
        Ok(Self {
            bounds,
            gravity: scene.gravity_m_s2,
            stepper: {
                let mut stepper = Stepper::new(scene.integrator, n_vertices);
                if let Some(speed_m_s) = scene.options.friction_smoothing_m_s {
                    stepper.set_friction(anima_ode::contact::Friction::Smoothed { speed_m_s });
                }
                stepper
            },
            now: State::new(x, vec![DVec3::ZERO; n_vertices]),
            next: State::zeros(n_vertices),
            clearance: vec![0.0; n_vertices],
            before_limit: Vec::new(),
            responded: vec![false; n_vertices],
            solve_cache: ClearanceCache::default(),
            colliders,
            material,
            restitution: scene.restitution,
            rule: scene.time_step,
            options: scene.options,
            m_min,
            k_max,
            tracked: row * n + col,
            time: 0.0,
            steps: 0,
            first_collision: None,
            total_hits: 0,
            split_steps: 0,
            saved_history: SavedHistory::default(),
            repelled_edges: Vec::new(),
            self_collision: self_collision_for(&scene.options, &mesh),
            self_response: SelfCollisionResponse::new(),
            self_touched: vec![false; n_vertices],
            self_inv_mass: Vec::new(),
            before_filter: (Vec::new(), Vec::new()),
            self_total: SelfCollisionStats::default(),
            mesh,
            model,
        })
    }

    /// The step the next call to [`OliveiraCloth::step`] will take: the start-up step until the first
    /// collision, then Δt = β·π·√(m_min / k^e_max) (Eq. 4.6); the scene's step for a fixed rule.
    pub fn dt(&self) -> f64 {
        match self.rule {
            StepRule::Provot { startup_dt_s: Some(dt), .. } if self.first_collision.is_none() => dt,
            StepRule::Provot { beta, .. } => beta * PI * (self.m_min / self.k_max).sqrt(),
            StepRule::Fixed { dt_s } => dt_s,
        }
    }

    /// One step (Fig. 4.1): integrate the non-contact forces, then test every particle's path and answer
    /// hits (Eqs. 4.16–4.18). With `Options::contact` = `InSolve` the contacts are constrained inside the
    /// implicit step instead, and [`StepReport::hits`] counts the particles in contact at its end.
    pub fn step(&mut self) -> Result<StepReport, StepError> {
        if self.steps == 0 {
            // The bounds are taken from the state the run starts from.
            let elastic = self.elastic_energy();
            self.bounds.restart(&self.now.x, &self.now.v, &self.model.mass, self.gravity, elastic);
        }
        let dt = self.dt();
        let hits = self.advance(dt, 0)?;
        self.steps += 1;
        let springs = &self.model.springs;
        self.bounds.check(
            self.steps,
            self.time,
            &self.now.x,
            &self.now.v,
            &self.model.mass,
            self.gravity,
            springs.ends.iter().zip(&springs.rest_length).map(|(&[i, j], &l)| (i, j, l)),
        )?;
        Ok(StepReport { dt, hits })
    }

    /// Takes the cloth from the current state over `dt`: the integrator's step, the contacts, the
    /// self-collision response; then the result becomes the current state. When the response had to
    /// freeze an impact zone whose particles would have moved more than [`SPLIT_MOTION`] of the
    /// shortest spring (its fail-safe: the zone keeps its start positions while the cloth around it
    /// moves on, and at a large step that stretches the springs into it by several times their
    /// length), the step is discarded and taken again as two halves, at most [`MAX_SPLITS`] times
    /// deep. Returns the particles whose path met an object.
    fn advance(&mut self, dt: f64, depth: u32) -> Result<usize, StepError> {
        if self.self_collision.is_some() {
            self.stepper.save_history(&mut self.saved_history);
        }
        let hits = if self.options.contact == ContactMode::InSolve && !self.colliders.is_empty() {
            self.tentative_with_contacts_in_solve(dt)?
        } else {
            self.tentative(dt)?
        };
        if let Some(particle) = self.next.first_non_finite() {
            let (step, time) = (self.steps + 1, self.time + dt);
            return Err(NonFinite { step, time, particle, place: None }.into());
        }
        let held_back = match self.self_collision {
            Some(settings) => self.keep_apart(&settings, dt),
            None => 0.0,
        };
        if depth < MAX_SPLITS
            && held_back > 0.0
            && held_back > SPLIT_MOTION * self.model.springs.shortest_rest_length()
        {
            self.split_steps += 1;
            // The discarded step moved the integrator's history and the contact caches on: the history
            // is put back as it was before it, the caches start again from the current state.
            self.stepper.restore_history(&self.saved_history);
            self.solve_cache.reset(self.now.x.len());
            self.clearance.fill(0.0);
            let first = self.advance(0.5 * dt, depth + 1)?;
            return Ok(first + self.advance(0.5 * dt, depth + 1)?);
        }
        if hits > 0 {
            self.first_collision.get_or_insert(self.time + dt);
            self.total_hits += hits as u64;
        }
        std::mem::swap(&mut self.now, &mut self.next);
        self.time += dt;
        Ok(hits)
    }

    fn solver_error(&self, dt: f64, source: OdeError) -> StepError {
        StepError::Solver { step: self.steps + 1, time: self.time + dt, source }
    }

    /// The integrator's step into `next` with the objects answered after it.
    fn tentative(&mut self, dt: f64) -> Result<usize, StepError> {
        self.stepper
            .step(&mut self.model, self.time, dt, &self.now, &mut self.next)
            .map_err(|source| self.solver_error(dt, source))?;
        if let Some(tau) = self.options.strain_limit {
            self.limit_strain(tau, dt);
        }
        let pass = ContactPass {
            colliders: &self.colliders,
            dt,
            restitution: self.restitution,
            friction: self.material.friction,
            options: &self.options,
        };
        let mut hits = 0;
        if !self.colliders.is_empty() {
            hits = pass.particles(&self.now, &mut self.next, &mut self.clearance, &mut self.responded);
            if self.options.edge_contacts {
                let ends = &self.model.springs.ends;
                hits += pass.edges(ends, &self.now, &mut self.next, &mut self.clearance, &mut self.responded);
            } else if !self.repelled_edges.is_empty() {
                let ends = &self.repelled_edges;
                hits += pass.edges(ends, &self.now, &mut self.next, &mut self.clearance, &mut self.responded);
            }
        }
        if hits > 0 {
            // A multistep method's history no longer describes the state; generalised-α forgets the
            // acceleration of the particles answered only.
            self.stepper.reset_history_of(&self.responded);
        }
        Ok(hits)
    }

    /// The step into `next` with contacts inside the implicit solve (generalised-α): the stepper asks
    /// [`SolveContacts`] for them at every Newton iteration. Provot's strain limit, when set, still runs
    /// after the step (and can move a particle off its contact plane).
    fn tentative_with_contacts_in_solve(&mut self, dt: f64) -> Result<usize, StepError> {
        let mut contacts = SolveContacts {
            colliders: &self.colliders,
            friction: self.material.friction,
            restitution: self.restitution,
            cache: &mut self.solve_cache,
        };
        let stats = self
            .stepper
            .step_with_contacts(&mut self.model, &mut contacts, self.time, dt, &self.now, &mut self.next)
            .map_err(|source| self.solver_error(dt, source))?;
        if let Some(tau) = self.options.strain_limit {
            self.limit_strain(tau, dt);
        }
        self.responded.fill(false);
        for report in self.stepper.contact_reports() {
            if report.regime != anima_ode::contact::Regime::Free {
                self.responded[report.coordinate as usize] = true;
            }
        }
        Ok(stats.contacts)
    }

    /// The modern self-collision response on the step just taken, answered together with the objects:
    /// a particle an object answered this step is held by it (the response moves the layers around it
    /// instead); and a particle the response would push into an object is held too, and the response
    /// taken again from the step as the integrator and the contacts left it, until it pushes none in
    /// (at most [`OBJECT_ROUNDS`] times). Without this, a free particle near the floor or the sphere
    /// could be pushed inside by the layers above it, and the next step's contact thrown it out at tens
    /// of metres a second (measured on the folding drape of the self-collision tests: 22 particles inside
    /// the sphere, 39 m/s, springs at 5 times their length).
    fn keep_apart(&mut self, settings: &SelfCollision, dt: f64) -> f64 {
        self.self_inv_mass.clear();
        self.self_inv_mass.extend(
            self.model.inv_mass.iter().zip(&self.responded).map(|(&w, &held)| if held { 0.0 } else { w }),
        );
        self.before_filter.0.clear();
        self.before_filter.0.extend_from_slice(&self.next.x);
        self.before_filter.1.clear();
        self.before_filter.1.extend_from_slice(&self.next.v);
        for round in 0..=OBJECT_ROUNDS {
            if round > 0 {
                self.next.x.copy_from_slice(&self.before_filter.0);
                self.next.v.copy_from_slice(&self.before_filter.1);
            }
            self.self_touched.fill(false);
            let stats = self.self_response.filter_step(
                settings,
                dt,
                &self.now.x,
                &mut self.next.x,
                &mut self.next.v,
                &self.self_inv_mass,
                self.mesh.triangles(),
                &mut self.self_touched,
            );
            let mut pushed_in = false;
            if round < OBJECT_ROUNDS && !self.colliders.is_empty() {
                for i in 0..self.next.x.len() {
                    if !self.self_touched[i] || self.self_inv_mass[i] == 0.0 {
                        continue;
                    }
                    let (a, b) = (self.now.x[i], self.next.x[i]);
                    if first_hit(&self.colliders, a, b).is_some()
                        || self.colliders.iter().any(|o| o.solid.contains(b))
                    {
                        self.self_inv_mass[i] = 0.0;
                        pushed_in = true;
                    }
                }
            }
            if !pushed_in {
                self.self_total += stats;
                if stats.changed_particles > 0 {
                    self.stepper.reset_history_of(&self.self_touched);
                }
                return stats.frozen_motion;
            }
        }
        unreachable!("the last round pushes nothing in")
    }

    /// The physical bounds every step is checked against ([`crate::bounds`]; by default
    /// [`Bounds::for_start`] of the cloth at rest, with the energy bound).
    pub fn bounds(&self) -> Bounds {
        self.bounds.bounds
    }

    /// Sets the bounds; [`Bounds::unbounded`] checks finiteness only.
    pub fn set_bounds(&mut self, bounds: Bounds) {
        let elastic = self.elastic_energy();
        self.bounds.set(bounds, &self.now.x, &self.now.v, &self.model.mass, self.gravity, elastic);
    }

    /// Provot's strain limit on the tentative state, before the contact pass (which then tests the
    /// corrected paths): shortens every spring longer than (1 + τ)·L⁰, in up to ten Gauss–Seidel sweeps,
    /// and gives the moved particles the velocity of their correction.
    fn limit_strain(&mut self, tau: f64, dt: f64) {
        self.before_limit.clear();
        self.before_limit.extend_from_slice(&self.next.x);
        let (s, inv_mass, x) = (&self.model.springs, &self.model.inv_mass, &mut self.next.x);
        let mut any = false;
        for _ in 0..10 {
            let mut changed = false;
            for (e, &[i, j]) in s.ends.iter().enumerate() {
                let (i, j) = (i as usize, j as usize);
                let d = x[j] - x[i];
                let len = d.length();
                let limit = (1.0 + tau) * s.rest_length[e];
                if len <= limit {
                    continue;
                }
                let (wi, wj) = (inv_mass[i], inv_mass[j]);
                let push = d * ((len - limit) / (len * (wi + wj)));
                x[i] += push * wi;
                x[j] -= push * wj;
                changed = true;
            }
            any |= changed;
            if !changed {
                break;
            }
        }
        if !any {
            return;
        }
        // The corrected state is not the one a multistep method's history led to.
        self.stepper.reset_history();
        for ((v, x1), x0) in self.next.v.iter_mut().zip(&self.next.x).zip(&self.before_limit) {
            *v += (*x1 - *x0) / dt;
        }
    }

    /// Per particle, whether the last step's contact pass answered it.
    pub fn responded(&self) -> &[bool] {
        &self.responded
    }

    /// The integrator, to choose the linear solver or the Newton iterations of the implicit ones.
    pub fn stepper_mut(&mut self) -> &mut Stepper<DVec3> {
        &mut self.stepper
    }

    /// Steps until the time reaches `t_end` (the last step may pass it, as the thesis's loop does).
    pub fn run_until(&mut self, t_end: f64) -> Result<(), StepError> {
        while self.time < t_end {
            self.step()?;
        }
        Ok(())
    }

    pub fn mesh(&self) -> &MaterialMesh {
        &self.mesh
    }

    pub fn triangles(&self) -> &[[u32; 3]] {
        self.mesh.triangles()
    }

    /// Replaces the particles' positions and velocities (as many as there are particles), for instance to
    /// start the cloth somewhere the scene's flat start cannot describe. The integrator's history and the
    /// collision tests' distance bounds start again.
    pub fn set_state(&mut self, x: &[DVec3], v: &[DVec3]) {
        assert!(x.len() == self.now.x.len() && v.len() == x.len(), "one position and velocity per particle");
        self.now.x.copy_from_slice(x);
        self.now.v.copy_from_slice(v);
        self.clearance.fill(0.0);
        self.solve_cache.reset(x.len());
        self.stepper.reset_history();
        let elastic = self.elastic_energy();
        self.bounds.restart(&self.now.x, &self.now.v, &self.model.mass, self.gravity, elastic);
    }

    /// The energy stored in the stretched springs, ½ k (|d| − L⁰)² over those longer than their rest
    /// length, J (what the energy bound counts as available at a start that is not at rest length).
    fn elastic_energy(&self) -> f64 {
        let s = &self.model.springs;
        s.ends
            .iter()
            .enumerate()
            .map(|(e, &[i, j])| {
                let stretch =
                    (self.now.x[i as usize].distance(self.now.x[j as usize]) - s.rest_length[e]).max(0.0);
                0.5 * s.stiffness[e] * stretch * stretch
            })
            .sum()
    }

    pub fn positions(&self) -> &[DVec3] {
        &self.now.x
    }

    pub fn velocities(&self) -> &[DVec3] {
        &self.now.v
    }

    pub fn masses(&self) -> &[f64] {
        &self.model.mass
    }

    pub fn springs(&self) -> &Springs {
        &self.model.springs
    }

    pub fn bending(&self) -> &BendingElements {
        &self.model.bending
    }

    pub fn colliders(&self) -> &[Collider] {
        &self.colliders
    }

    pub fn time(&self) -> f64 {
        self.time
    }

    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// m_min, kg.
    pub fn min_mass(&self) -> f64 {
        self.m_min
    }

    /// k^e_max, N/m.
    pub fn max_stiffness(&self) -> f64 {
        self.k_max
    }

    /// The time at the end of the first step with a collision.
    pub fn first_collision_time(&self) -> Option<f64> {
        self.first_collision
    }

    /// Collision responses applied so far.
    pub fn total_hits(&self) -> u64 {
        self.total_hits
    }

    /// How many times a step (or a half of one) was taken again in two halves because the
    /// self-collision response had to freeze an impact zone ([`MAX_SPLITS`]).
    pub fn split_steps(&self) -> u64 {
        self.split_steps
    }

    /// What the modern self-collision response did over the run; `None` unless the scene asks for it.
    pub fn self_collision_stats(&self) -> Option<SelfCollisionStats> {
        self.self_collision.map(|_| self.self_total)
    }

    /// Index of particle P.
    pub fn tracked_vertex(&self) -> usize {
        self.tracked
    }

    pub fn tracked_position(&self) -> DVec3 {
        self.now.x[self.tracked]
    }

    pub fn kinetic_energy(&self) -> f64 {
        self.now.v.iter().zip(&self.model.mass).map(|(v, m)| 0.5 * m * v.length_squared()).sum()
    }

    pub fn max_speed(&self) -> f64 {
        self.now.v.iter().map(|v| v.length()).fold(0.0, f64::max)
    }

    /// Particles strictly inside an object, with the object's index.
    pub fn penetrations(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for (i, p) in self.now.x.iter().enumerate() {
            if let Some(k) = self.colliders.iter().position(|o| o.solid.contains(*p)) {
                out.push((i, k));
            }
        }
        out
    }

    /// The force model, e.g. to evaluate forces at a given state.
    pub fn model(&self) -> &ClothModel {
        &self.model
    }

    /// Takes a remeshed cloth (the adaptive drivers of `oliveira::adaptive`): the new mesh and its
    /// particles' state, masses and drag from the new vertex areas, springs from the new edges, bending
    /// elements from the new interior edges, m_min and k^e_max (hence the next Δt), a fresh stepper of
    /// the same integrator (generalised-α's acceleration zero), and particle P's new index. Time, step count
    /// and contact history are kept. `sources`, when given, names for each new particle an old one near
    /// it (the one it was made from, or itself): the in-solve contact's distance bounds are carried over
    /// from them ([`ClearanceCache::inherit`]) instead of starting again, which would query every
    /// particle against every object at the next step.
    pub(crate) fn replace_mesh(
        &mut self,
        mesh: MaterialMesh,
        x: Vec<DVec3>,
        v: Vec<DVec3>,
        tracked: usize,
        gravity: DVec3,
        sources: Option<&[u32]>,
    ) {
        let n = x.len();
        debug_assert!(v.len() == n && mesh.n_vertices() == n && tracked < n);
        let material = self.material;
        let areas = mesh.vertex_areas();
        let mass: Vec<f64> = areas.iter().map(|&a| material.particle_mass(a)).collect();
        let rest_length = mesh.edge_rest_lengths();
        let m = &mut self.model;
        m.springs = Springs {
            ends: mesh.topology().edges().iter().map(|e| e.vertices).collect(),
            stiffness: rest_length.iter().map(|&l| material.spring_stiffness(l)).collect(),
            damping: rest_length.iter().map(|&l| material.spring_damping(l)).collect(),
            rest_length,
        };
        m.bending = BendingElements {
            stencils: mesh.topology().interior_stencils().iter().map(|s| s.vertices).collect(),
        };
        if let Some(membrane) = self.options.membrane {
            // The material was accepted when the cloth was built, and a remeshed mesh's rest triangles
            // have positive area (the drivers check it after every remesh).
            m.membrane =
                Some(membrane_on(&mesh, membrane, &material).expect("a remeshed mesh takes the membrane"));
        }
        m.inv_mass = mass.iter().map(|m| 1.0 / m).collect();
        m.weight = mass.iter().map(|&m| gravity * m).collect();
        m.drag = areas.iter().map(|&a| material.particle_drag(a)).collect();
        self.m_min = mass.iter().copied().fold(f64::INFINITY, f64::min);
        self.k_max = m.springs.max_stiffness();
        m.mass = mass;
        m.invalidate_implicit();
        self.stepper = self.stepper.resized(n);
        // Generalised-α's acceleration restarts at zero, not at M⁻¹ f: the remeshed state is not one the
        // method stepped to, and M⁻¹ f of a particle resting on an object is its whole weight and its
        // springs' pull, unanswered by the contact, which the next step would carry explicitly (it
        // blew the drapes up within steps of the first contact at 1/60 s; the reason
        // `Stepper::reset_history_of` zeroes what a response touched).
        self.stepper.zero_acceleration();
        self.now = State::new(x, v);
        self.next = State::zeros(n);
        self.clearance = vec![0.0; n];
        self.responded = vec![false; n];
        match sources {
            Some(sources) => {
                debug_assert_eq!(sources.len(), n, "one source per new particle");
                self.solve_cache.inherit(sources);
            }
            None => self.solve_cache.reset(n),
        }
        self.tracked = tracked;
        self.repelled_edges.clear();
        // The new triangles make the response's broad phase rebuild its trees at its next update.
        self.self_collision = self_collision_for(&self.options, &mesh);
        self.self_touched = vec![false; n];
        self.mesh = mesh;
        // The particles changed: the energy bound counts from here.
        let elastic = self.elastic_energy();
        self.bounds.restart(&self.now.x, &self.now.v, &self.model.mass, gravity, elastic);
    }

    /// Edges to cast at the end of every step, their ends answered as particle hits (A-24: the thesis's
    /// repulsion on colliding edges that remeshing may no longer refine). Cleared by a remesh; ignored
    /// while `Options::edge_contacts` casts every edge.
    pub(crate) fn set_repelled_edges(&mut self, ends: impl IntoIterator<Item = [u32; 2]>) {
        self.repelled_edges.clear();
        self.repelled_edges.extend(ends);
    }
}

#[cfg(test)]
mod tests {
    use anima_geom::box_mesh;

    use super::*;

    #[test]
    fn placed_meshes_stand_on_their_base_scaled_and_still_outward() {
        // A 4 × 1 × 2 box (x × y × z).
        let b = box_mesh(DVec3::new(1.0, 2.0, 3.0), DVec3::new(5.0, 3.0, 5.0));
        for up in [UpAxis::X, UpAxis::Y, UpAxis::Z] {
            let m = place_mesh(&b, up, 0.5, DVec3::new(0.1, 0.2, 0.3)).unwrap();
            let bb = m.aabb();
            assert!((bb.min.z - 0.3).abs() < 1e-12, "{up:?}: bottom at {}", bb.min.z);
            assert!((bb.centre().truncate() - DVec2::new(0.1, 0.2)).length() < 1e-12, "{up:?}");
            assert!((bb.size().x.max(bb.size().y) - 0.5).abs() < 1e-12, "{up:?}");
            assert!(MeshSolid::new(&m).is_ok(), "{up:?}: the rotation must keep the winding outward");
        }
        // Y up: the box's 1-unit y side becomes its height (0.5/4 of it after scaling to 0.5 m).
        let m = place_mesh(&b, UpAxis::Y, 0.5, DVec3::ZERO).unwrap();
        assert!((m.aabb().size().z - 0.125).abs() < 1e-12);
    }
}
