//! A FLEX3D scene as data: what a `.PAR` script says, in SI terms, plus every reconstruction the
//! specification marks as a switch. This is also the schema of anima's RON scene files.

use anima_geom::{DVec3, RowDirection};
use anima_ode::Integrator;
use serde::{Deserialize, Serialize};

use crate::contact_mode::ContactMode;
use crate::self_collision::SelfCollisionMode;

/// Standard gravity as FLEX3D scenes use it: (0, −9.8, 0), y up (spec S3.1).
pub const FLEX3D_GRAVITY: DVec3 = DVec3::new(0.0, -9.8, 0.0);

/// A whole FLEX3D scene. Units: seconds, metres (FLEX3D scene units), kilograms, newtons.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Flex3dScene {
    /// `DURAÇÃO`: simulated time, s.
    pub duration_s: f64,
    /// `QUADROS_SEG`: frames written per second of animation.
    pub frame_rate_hz: f64,
    /// `DELTA_t`: integration step, s.
    pub dt_s: f64,
    /// Gravitational acceleration, m/s². The script language has none; FLEX3D scenes switch it per
    /// scene (spec S3.1, S6.0).
    pub gravity_m_s2: DVec3,
    /// `FORÇA_EXTERNA`: the same force on every free particle (wind), N.
    pub external_force_n: DVec3,
    /// `ATRITO`: the friction coefficient and how it is read.
    pub friction: Friction,
    /// `OBJETOS_NA_CENA`: static objects as `.OBT` files, relative to the scene file.
    #[serde(default)]
    pub objects: Vec<String>,
    pub surfaces: Vec<SurfaceDesc>,
    #[serde(default = "Integrator::default")]
    pub integrator: Integrator,
    /// Every reconstruction the thesis leaves open, with the specification's defaults.
    #[serde(default = "ModelOptions::thesis")]
    pub options: ModelOptions,
}

impl Flex3dScene {
    /// Integration steps in the run: round(duration / Δt), counted as an integer (spec S4.4).
    pub fn n_steps(&self) -> usize {
        (self.duration_s / self.dt_s).round() as usize
    }

    /// Frames in the run, numbered 1..=n_frames (spec S4.5).
    pub fn n_frames(&self) -> usize {
        (self.duration_s * self.frame_rate_hz).round() as usize
    }

    /// The step after which frame k (1-based) is written: round(k / (fps·Δt)) (spec S4.4).
    pub fn frame_step(&self, k: usize) -> usize {
        (k as f64 / (self.frame_rate_hz * self.dt_s)).round() as usize
    }
}

/// One rectangular surface (`SUPERFÍCIE … FIM_SUPERFÍCIE`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceDesc {
    /// Used in output file names: `<name>_<frame>.OBT`.
    pub name: String,
    /// `MALHA (m n)`: rows, columns.
    pub rows: usize,
    pub cols: usize,
    /// `DENSIDADE`: rest spacing r between grid neighbours, m.
    pub spacing_m: f64,
    /// `POSIC_NO_SRU`: world position of the mesh centre, m.
    pub centre_m: DVec3,
    /// `VETOR_NORMAL`: initial surface normal (need not be unit length).
    pub normal: DVec3,
    /// `MASSA`: mass of each particle, kg.
    pub particle_mass_kg: f64,
    /// `CONST_ELASTICIDADE (kh kv kd)`: horizontal, vertical, diagonal spring stiffness, N/m.
    pub stiffness_n_m: [f64; 3],
    /// `CONST_CURVATURA`: angular-spring stiffness for the horizontal, vertical and diagonal pairs, N/m.
    #[serde(default)]
    pub bending_n_m: [f64; 3],
    /// `PONTOS_FIXOS`: pinned particles as (row, column), 0-based.
    #[serde(default)]
    pub fixed: Vec<(usize, usize)>,
    /// `TRANSLAÇÃO / INI_TRANSL / FIM_TRANSL`: kinematic windows moving every pinned particle.
    #[serde(default)]
    pub translations: Vec<Translation>,
}

/// A translation of all pinned particles of a surface: `per_frame_m` per frame while
/// t ∈ [start_s, end_s) (spec S5.3). Overlapping windows add up.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Translation {
    pub per_frame_m: DVec3,
    pub start_s: f64,
    pub end_s: f64,
}

/// Friction (`ATRITO`, Nedel 1993 §3.2.7): the only dissipation in FLEX3D.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Friction {
    pub mode: FrictionMode,
    pub coefficient: f64,
}

/// How the friction coefficient μ is read (spec S3.7, ambiguity A-2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum FrictionMode {
    /// F = −μ·|F'|·v/|v|, F' the resultant of the other forces: "a percentage of the resultant force,
    /// opposing the motion". The default.
    #[default]
    Literal,
    /// F = −μ·v (air-resistance reading).
    Viscous,
}

/// Who a particle that strikes a surface triangle trades momentum with (spec S3.5.4, A-3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum ContactApproach {
    /// The triangle vertex with the largest barycentric weight. The default.
    #[default]
    NearestVertex,
    /// All three vertices, as one body of their summed mass moving with their mean velocity.
    ThreeVertices,
}

/// The new velocity of a particle that strikes a static object (spec S3.5.5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum StaticResponse {
    /// v ← −v: the thesis's 1-D elastic result with an immovable partner. The default.
    #[default]
    Reverse,
    /// v ← v − 2(v·n̂)n̂: reflect the normal component only.
    ReflectNormal,
}

/// How a `TRANSLAÇÃO` window moves the pinned particles (spec S5.3, A-6).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum TranslationMode {
    /// Constant velocity u = T·fps applied at every step. The default.
    #[default]
    Continuous,
    /// A jump of T at the first step of each frame inside the window (impulsive; not recommended).
    PerFrameJump,
}

/// Switches for every reconstruction the thesis leaves open. [`ModelOptions::thesis`] gives the
/// specification's recommended defaults, which reproduce the thesis's behaviour.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default = "ModelOptions::thesis")]
pub struct ModelOptions {
    /// Particle–triangle collisions (static objects, other surfaces, the surface itself). FLEX3D always
    /// ran them; switching them off is an anima extension for benchmarks.
    pub collisions: bool,
    pub contact: ContactApproach,
    pub static_response: StaticResponse,
    /// Read `FORÇA_EXTERNA` as an acceleration (multiply by the particle mass) (spec S3.2, A-4).
    pub external_force_is_acceleration: bool,
    /// Apply −F/2 to each outer particle of an angular spring, so bending conserves momentum (spec S3.4).
    pub bend_reaction: bool,
    pub row_direction: RowDirection,
    pub translation: TranslationMode,
    /// Limit friction so that on its own it cannot reverse a velocity within one step:
    /// |F_friction|·Δt/m ≤ |v| (spec S3.7 \[EXT\]). Off in the thesis; large steps need it, or friction
    /// makes a resting particle chatter.
    pub friction_clamp: bool,
    /// Where contact with static objects is answered: after the step by the thesis's elastic impact
    /// (the default), or inside the implicit solve (`InSolve`, generalised-α only), inelastic, with
    /// Coulomb friction of the scene's `ATRITO` coefficient (sticking and sliding) and release when the
    /// contact would pull (an anima extension). Contacts between surfaces stay after the step either way.
    #[serde(skip_serializing_if = "ContactMode::is_after_step")]
    pub object_contact: ContactMode,
    /// How surfaces are kept from passing through themselves and one another: the thesis's swept
    /// particle–triangle test with its elastic impact (`Faithful`, the default), the modern response of
    /// [`crate::self_collision`] after the step (`Modern`: repulsion, impact impulses, rigid impact
    /// zones; no step ends with a crossing), or nothing (`Off`). Static objects keep the response set
    /// above either way. Needs `collisions`; not written when it is the default.
    #[serde(skip_serializing_if = "SelfCollisionMode::is_faithful")]
    pub self_collision: SelfCollisionMode,
}

impl ModelOptions {
    /// The specification's defaults (spec S7.2).
    pub const fn thesis() -> Self {
        Self {
            collisions: true,
            contact: ContactApproach::NearestVertex,
            static_response: StaticResponse::Reverse,
            external_force_is_acceleration: false,
            bend_reaction: false,
            row_direction: RowDirection::Down,
            translation: TranslationMode::Continuous,
            friction_clamp: false,
            object_contact: ContactMode::AfterStep,
            self_collision: SelfCollisionMode::Faithful,
        }
    }
}

impl Default for ModelOptions {
    fn default() -> Self {
        Self::thesis()
    }
}
