//! A drape built in code: a square cloth, its material and the objects it falls on, without a scene
//! file. [`OliveiraCloth::builder`] starts from the settings of the drapes at users' sizes
//! (`assets/scenes/drape-*.ron`): generalised-α at 1/60 s, contacts inside its solve, the modern
//! self-collision, Table 5.1's material. Every choice the scene schema has stays reachable through
//! [`ClothBuilder::options`] and [`ClothBuilder::scene`].

use anima_geom::{DVec2, DVec3, DiagonalPattern, TriangleMesh};
use anima_ode::Integrator;

use super::cloth::{BuildError, OliveiraCloth};
use super::material::Material;
use super::scene::{
    Centre, ClothDesc, Height, ObjectDesc, OliveiraScene, Options, ShapeDesc, StepRule, UpAxis,
};
use crate::contact_mode::ContactMode;
use crate::self_collision::SelfCollisionMode;

/// Builds an [`OliveiraCloth`]: a `vertices_per_side`² grid of side `size_m`, flat and horizontal
/// (z up), and the objects it meets.
#[derive(Debug, Clone)]
pub struct ClothBuilder {
    scene: OliveiraScene,
    meshes: Vec<TriangleMesh>,
}

impl OliveiraCloth {
    /// A builder for a `vertices_per_side` × `vertices_per_side` cloth of side `size_m`, centred over
    /// the highest point of its objects and 1 cm above them.
    pub fn builder(vertices_per_side: usize, size_m: f64) -> ClothBuilder {
        let scene = OliveiraScene {
            // A scene's run length; the built cloth steps for as long as its caller steps it.
            duration_s: 1.0,
            gravity_m_s2: DVec3::new(0.0, 0.0, -9.81),
            cloth: ClothDesc {
                vertices_per_side,
                size_m,
                diagonals: DiagonalPattern::Uniform,
                centre: Centre::OverHighestPoint,
                height: Height::AboveObjects { clearance_m: 0.01 },
                tracked_vertex: (0, 0),
            },
            material: Material::table_5_1(),
            time_step: StepRule::Fixed { dt_s: 1.0 / 60.0 },
            restitution: 0.0,
            objects: Vec::new(),
            integrator: Integrator::GeneralizedAlpha,
            options: Options {
                contact: ContactMode::InSolve,
                self_collision: SelfCollisionMode::Modern,
                ..Options::thesis()
            },
        };
        ClothBuilder { scene, meshes: Vec::new() }
    }
}

impl ClothBuilder {
    pub fn material(mut self, material: Material) -> Self {
        self.scene.material = material;
        self
    }

    /// A fixed step, s.
    pub fn dt(mut self, dt_s: f64) -> Self {
        self.scene.time_step = StepRule::Fixed { dt_s };
        self
    }

    pub fn integrator(mut self, integrator: Integrator) -> Self {
        self.scene.integrator = integrator;
        self
    }

    /// Friction smoothed below the sliding speed `speed_m_s` instead of Coulomb's stick and slide regimes
    /// ([`super::Options::friction_smoothing_m_s`]).
    pub fn smoothed_friction(mut self, speed_m_s: f64) -> Self {
        self.scene.options.friction_smoothing_m_s = Some(speed_m_s);
        self
    }

    pub fn gravity(mut self, g: DVec3) -> Self {
        self.scene.gravity_m_s2 = g;
        self
    }

    /// The cloth's centre, seen from above, at (x, y), m.
    pub fn centre(mut self, x: f64, y: f64) -> Self {
        self.scene.cloth.centre = Centre::At(DVec2::new(x, y));
        self
    }

    /// The cloth's height, m (instead of 1 cm above its objects).
    pub fn height(mut self, z_m: f64) -> Self {
        self.scene.cloth.height = Height::At { z_m };
        self
    }

    /// A closed triangle mesh, turned so that `up` is +z, scaled so that its longest horizontal extent
    /// is `length_m`, and placed with the centre of its bounding box's bottom at `base_centre`.
    pub fn mesh(
        mut self,
        name: &str,
        mesh: TriangleMesh,
        up: UpAxis,
        length_m: f64,
        base_centre: DVec3,
    ) -> Self {
        self.meshes.push(mesh);
        self.object(name, ShapeDesc::Mesh { file: name.to_owned(), up, length_m, base_centre_m: base_centre })
    }

    pub fn sphere(self, name: &str, centre: DVec3, radius_m: f64) -> Self {
        self.object(name, ShapeDesc::Sphere { centre_m: centre, radius_m })
    }

    /// A floor: everything below z = `z_m`.
    pub fn floor(self, z_m: f64) -> Self {
        self.object("floor", ShapeDesc::HalfSpace { point_m: DVec3::new(0.0, 0.0, z_m), normal: DVec3::Z })
    }

    /// An object with the cloth's friction (a contact takes the mean of the two, Eq. 4.17).
    fn object(mut self, name: &str, shape: ShapeDesc) -> Self {
        let friction = self.scene.material.friction;
        self.scene.objects.push(ObjectDesc { name: name.to_owned(), friction, shape });
        self
    }

    /// The model's switches (contact, self-collision, the reconstructions of the thesis's choices).
    pub fn options(mut self, options: Options) -> Self {
        self.scene.options = options;
        self
    }

    /// The scene the builder has made so far, to change what it has no method for (an object's
    /// friction, the restitution, the step rule).
    pub fn scene(&mut self) -> &mut OliveiraScene {
        &mut self.scene
    }

    /// The cloth, checked as a scene file is: a value out of range is a [`BuildError`] naming its field.
    pub fn build(self) -> Result<OliveiraCloth, BuildError> {
        OliveiraCloth::new(&self.scene, self.meshes)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_builder_checks_what_a_scene_file_is_checked_for() {
        let field_of = |b: ClothBuilder| match b.build() {
            Err(BuildError::Field { field, .. }) => field,
            other => panic!("expected a field error, found {other:?}"),
        };
        // Over a floor alone there is no highest point to centre on: the centre must be given.
        assert_eq!(field_of(OliveiraCloth::builder(4, 1.0).floor(0.0).height(0.5)), "cloth.centre");
        let cloth = OliveiraCloth::builder(4, 1.0)
            .floor(0.0)
            .centre(0.0, 0.0)
            .height(0.5)
            .build()
            .expect("a 4 × 4 cloth");
        assert_eq!(cloth.positions().len(), 16);
        assert!(cloth.positions().iter().all(|p| (p.z - 0.5).abs() < 1e-12));
        let one = OliveiraCloth::builder(1, 1.0).floor(0.0).centre(0.0, 0.0).build();
        assert!(matches!(one, Err(BuildError::Mesh(_))), "one vertex a side is no mesh: {one:?}");
        assert_eq!(field_of(OliveiraCloth::builder(4, -1.0).floor(0.0).centre(0.0, 0.0)), "cloth.size_m");
        let adaptive =
            OliveiraCloth::builder(4, 1.0).floor(0.0).centre(0.0, 0.0).integrator(Integrator::AdaptiveEuler);
        assert_eq!(field_of(adaptive), "integrator");
    }
}
