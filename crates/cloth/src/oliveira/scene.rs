//! An Oliveira drape as data: the cloth, its material, the time-step rule, the static objects, and a
//! switch for every reconstruction the spec marks. This is also the schema of the RON scene files in
//! `assets/oliveira/`.

use anima_geom::{DVec2, DVec3, DiagonalPattern};
use anima_ode::Integrator;
use serde::{Deserialize, Serialize};

use super::material::Material;
use crate::contact_mode::ContactMode;
use crate::membrane::MembraneMaterial;
use crate::self_collision::SelfCollisionMode;

/// Gravity in every Oliveira test: (0, 0, −9.81) m/s², z up (Tables 5.1, 5.3, 5.5).
pub const OLIVEIRA_GRAVITY: DVec3 = DVec3::new(0.0, 0.0, -9.81);

/// The start-up step of Tests I and II (Oliveira 2013 §5.2.1, §5.3.1), used until the first collision.
pub const STARTUP_DT_S: f64 = 1.0e-4;

/// A whole scene. Units are SI; z is up.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OliveiraScene {
    /// Simulated time, s. The thesis states 0.6 s for Test III only; the spec infers 0.5 s (Test I) and
    /// 1 s (Test II) from the snapshot times.
    pub duration_s: f64,
    pub gravity_m_s2: DVec3,
    pub cloth: ClothDesc,
    pub material: Material,
    pub time_step: StepRule,
    /// γ of Eq. 4.16, the tables' "damping factor (k)": the normal velocity after a hit is −γ times the
    /// one before.
    pub restitution: f64,
    pub objects: Vec<ObjectDesc>,
    /// The thesis ran classical RK4 (§4.2).
    #[serde(default = "default_integrator")]
    pub integrator: Integrator,
    #[serde(default = "Options::thesis")]
    pub options: Options,
}

fn default_integrator() -> Integrator {
    Integrator::Rk4
}

/// The square cloth: a regular grid in material space, laid flat and horizontal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClothDesc {
    /// N of the N × N-vertex grid (5 coarse, 17 fine in the thesis).
    pub vertices_per_side: usize,
    /// Side of the square, m (1 m in every test).
    pub size_m: f64,
    /// How each grid square is split (not stated by the thesis; spec A-3).
    #[serde(default)]
    pub diagonals: DiagonalPattern,
    /// Where the centre of the square goes in the horizontal plane.
    pub centre: Centre,
    pub height: Height,
    /// Particle P whose trajectory Figs. 5.4 and 5.9 plot, as (row, column) of the grid; row runs along
    /// material y, column along material x. The thesis does not say which it was; the scenes use a
    /// corner, which exists in every mesh.
    pub tracked_vertex: (usize, usize),
}

/// Where the cloth's centre starts, seen from above.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Centre {
    /// Over the highest point of the objects (for the Bunny, the tip of an ear), so the middle particle
    /// touches first, within milliseconds, as the thesis's frame counts imply (spec §7.5).
    OverHighestPoint,
    /// At this (x, y), m.
    At(DVec2),
}

/// How high the cloth starts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Height {
    /// `clearance_m` above the highest point of every bounded object (the spec's default, 1 mm: the
    /// frame counts put the first contact within about 6 ms of the start, §7.5).
    AboveObjects { clearance_m: f64 },
    /// At this height, m.
    At { z_m: f64 },
}

/// One static object.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectDesc {
    pub name: String,
    /// μ of the object; a contact uses the mean of the cloth's and the object's (Eq. 4.17).
    pub friction: f64,
    pub shape: ShapeDesc,
}

/// The axis a mesh file treats as up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum UpAxis {
    X,
    Y,
    Z,
}

/// The geometry of a static object.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ShapeDesc {
    /// A closed triangle mesh from an OBJ file (path relative to the scene file). It is rotated so that
    /// `up` becomes +z, scaled so that its longest horizontal extent is `length_m`, and moved so that the
    /// centre of the bottom of its bounding box sits at `base_centre_m`.
    Mesh {
        file: String,
        up: UpAxis,
        length_m: f64,
        base_centre_m: DVec3,
    },
    Sphere {
        centre_m: DVec3,
        radius_m: f64,
    },
    /// A closed cylinder with a vertical axis (a round table top), from its bottom disc's centre.
    Cylinder {
        base_centre_m: DVec3,
        radius_m: f64,
        height_m: f64,
    },
    /// Everything below the plane through `point_m` with outward `normal` (a floor, an incline).
    HalfSpace {
        point_m: DVec3,
        normal: DVec3,
    },
}

/// How Δt is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum StepRule {
    /// Δt = β·π·√(m_min / k^e_max) (Eq. 4.6), recomputed before every step, after `startup_dt_s` steps
    /// until the first collision (A-10; Q-13: Test III does not say, and the scenes use it there too).
    Provot { beta: f64, startup_dt_s: Option<f64> },
    /// A constant step, s (not the thesis's; for comparisons).
    Fixed { dt_s: f64 },
}

/// Force law of an edge spring (Eq. 4.8, A-12).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum SpringLaw {
    /// No elastic force while |x_j − x_i| ≤ L⁰: the thesis's law. The default.
    #[default]
    TensionOnly,
    /// The ordinary Hooke spring, pushing back when compressed too.
    TwoSided,
}

/// When the spring damper of Eq. 4.9 acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum DamperLaw {
    /// Always: Eq. 4.9 carries no condition. The default.
    #[default]
    Always,
    /// Only while the spring is stretched, like its elastic force.
    WithTension,
}

/// Which velocity the collision response of Eq. 4.16 starts from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum ContactVelocity {
    /// v^t, the velocity at the start of the step, as the text says. The default.
    #[default]
    StartOfStep,
    /// The velocity RK4 computed at the end of the step.
    EndOfStep,
}

/// What a hit does to a particle that is already moving away from the surface (spec §5.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum SeparatingContact {
    /// Keep its velocity (Eqs. 4.16–4.17 only when v·n̂ < 0); the position is still reset by Eq. 4.18.
    /// The default.
    #[default]
    KeepVelocity,
    /// Apply Eqs. 4.16–4.17 anyway, as printed.
    Literal,
}

/// Every reconstruction switch, and anima's own switches.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default = "Options::thesis")]
pub struct Options {
    pub spring: SpringLaw,
    pub damper: DamperLaw,
    pub contact_velocity: ContactVelocity,
    pub separating: SeparatingContact,
    /// Cast the corrected path x^t → x̄ of a particle that was hit again, and answer a crossing the same
    /// way (anima's addition, on by default). Eq. 4.18 restarts the particle from x^t with the new
    /// velocity without testing that path, which on a concave surface (the Bunny's creases, where it
    /// meets the floor) can carry it through a neighbouring face. Off gives the thesis's rule as printed.
    pub recheck_corrected_path: bool,
    /// Also cast every edge at the end of the step and answer a hit on both its ends as particle hits
    /// the thesis does this for colliding edges that remeshing may not refine further, and
    /// on a static mesh no edge can be refined). Off by default: the thesis's static reference runs do
    /// no remeshing pass, so no edge tests.
    pub edge_contacts: bool,
    /// Skip the exact path test of a particle whose path cannot reach any object (its length is below
    /// a lower bound on its distance from every surface). Changes no result; off only to check that.
    pub cull_collision_tests: bool,
    /// Provot's (1995) strain limit, an anima addition for large steps: after each step, springs
    /// stretched beyond (1 + τ)·L⁰ are shortened back to it (ends moved in inverse proportion to their
    /// masses, in up to ten sweeps) and the velocities take the correction over the step. `None` (the
    /// default, as in the thesis) leaves the springs alone; Provot used τ = 0.1.
    pub strain_limit: Option<f64>,
    /// Where contact with the objects is answered: after the step by Eqs. 4.16–4.18 (the thesis's
    /// split, the default), or inside the implicit solve (`InSolve`, generalised-α only): normal
    /// velocity constrained, Coulomb friction with μ the mean of the cloth's and the object's (Eq. 4.17)
    /// for both sticking and sliding, restitution γ on impact, release when the contact would pull; the
    /// switches above that shape the split's response (`contact_velocity`, `separating`,
    /// `recheck_corrected_path`, `edge_contacts`) do not apply to it. Not written when it is the default.
    #[serde(skip_serializing_if = "ContactMode::is_after_step")]
    pub contact: ContactMode,
    /// Whether the cloth is kept from passing through itself: the thesis has no self-collision, so
    /// `Faithful` (the default) and `Off` let it; `Modern` runs [`crate::self_collision`]'s response
    /// after every step (after the contacts with the objects), so that no step ends with a crossing.
    /// Not written when it is the default.
    #[serde(skip_serializing_if = "SelfCollisionMode::is_faithful")]
    pub self_collision: SelfCollisionMode,
    /// With `contact: InSolve`, friction smoothed below this sliding speed ε (m/s) instead of Coulomb's
    /// stick and slide regimes (anima's addition: [`anima_ode::contact::Friction::Smoothed`]). The
    /// regimes are a fixed point inside Newton that chatters between sticking and sliding at low speed;
    /// smoothed, friction is a damping the solve sees, and a sticking contact creeps slower than ε. On the
    /// 65² drapes of `cargo xtask bench --scale` the regimes make the runs chaotic (two converged runs
    /// with gravity × (1 ± 10⁻⁹) end 7.0 mm apart on the Bunny) and smoothing does not; with ε = 1 mm/s
    /// a step takes a quarter fewer Newton iterations and errs 2–3× less (the measurements are in
    /// [`anima_ode::contact::Friction::Smoothed`]'s docs). `None` (the default) keeps the regimes. Not
    /// written when it is the default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub friction_smoothing_m_s: Option<f64>,
    /// η, anima's guard on slivers in bending (a reading of the spec's "skip the element when |N₁| or
    /// |N₂| is below a tiny tolerance"): Eq. 4.10's u grows as the inverse of a triangle's height over
    /// its hinge and the damping of Eq. 4.13 as its square, and springs on edges alone do not stop a
    /// triangle passing through flat. A sliver then makes the explicit step unstable at any Δt the step
    /// rule gives (the rule sees springs only): the thesis's remesher under the literal short-edge rule
    /// diverged so on Test II. With η > 0 the mode of an element with a triangle whose height is below
    /// η·|e| is scaled down by that height over η·|e| ([`super::bending::bending_mode`]), which bounds it
    /// and keeps momentum; 0 gives Eqs. 4.10–4.13 as printed (η lies in [0, 1]). The default, 0.05,
    /// is never reached on the thesis's uniform drapes (their triangles keep at least 70 % of their rest
    /// area), which are the same to the bit with it. Not written when it is the default.
    #[serde(skip_serializing_if = "Options::is_default_bending_height_floor")]
    pub bending_height_floor: f64,
    /// The cloth's forces from a continuum model instead of the thesis's springs and bending elements
    /// (anima's addition, for measuring adaptivity: a spring network's response depends on its mesh, so
    /// its refinements do not converge): co-rotational constant-strain triangles and quadratic bending
    /// hinges of [`crate::membrane`] with this material, on the cloth's rest mesh and rebuilt at every
    /// remesh. Masses, gravity, air drag and contact stay the thesis's; the springs are still built, for
    /// the remeshing criteria and the step rule's k^e_max (Eq. 4.6), but exert no force. `None` (the
    /// default) is the thesis's model. Not written when it is the default.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub membrane: Option<MembraneMaterial>,
}

impl Options {
    /// The spec's defaults.
    pub const fn thesis() -> Self {
        Self {
            spring: SpringLaw::TensionOnly,
            damper: DamperLaw::Always,
            contact_velocity: ContactVelocity::StartOfStep,
            separating: SeparatingContact::KeepVelocity,
            recheck_corrected_path: true,
            edge_contacts: false,
            cull_collision_tests: true,
            strain_limit: None,
            contact: ContactMode::AfterStep,
            self_collision: SelfCollisionMode::Faithful,
            friction_smoothing_m_s: None,
            bending_height_floor: Self::BENDING_HEIGHT_FLOOR,
            membrane: None,
        }
    }

    /// The default η of [`Options::bending_height_floor`].
    pub const BENDING_HEIGHT_FLOOR: f64 = 0.05;

    fn is_default_bending_height_floor(eta: &f64) -> bool {
        *eta == Self::BENDING_HEIGHT_FLOOR
    }
}

impl Default for Options {
    fn default() -> Self {
        Self::thesis()
    }
}
