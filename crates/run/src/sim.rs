//! A scene as an object its caller steps: what `anima run` does in one call, taken apart for programs
//! that drive a simulation themselves (the Python package, a notebook, a game loop). Load or build a
//! scene, step it, read and write its state; the physics is the run loop's own, so a [`ClothSim`]
//! stepped to the end of its scene ends where `anima run` does, to the bit (a test).

use anima_body::{BodyPose, World};
use anima_character::Character;
use anima_cloth::StepError;
use anima_geom::{DVec3, TriangleMesh};
use anima_scene::Scene;
use anyhow::{Result, bail};

use crate::run::SolveOptions;
use crate::run::body::{Figures, Posed};
use crate::simulation::Deformable;

/// Any cloth model, through the contract every one keeps (sendable: the Python package steps it with
/// the interpreter's lock released).
pub(crate) type ClothModel = Box<dyn Deformable<Error = StepError> + Send + Sync>;

/// What a cloth scene's kind builds for a [`ClothSim`].
pub(crate) struct ClothParts {
    pub model: ClothModel,
    pub triangles: Vec<[u32; 3]>,
    pub obstacles: Vec<TriangleMesh>,
    /// `sheet`, `flex3d` or `oliveira`.
    pub kind: &'static str,
}

/// A cloth scene of any kind (a sheet, FLEX3D surfaces, an Oliveira drape, remeshed or not), ready to
/// step.
#[derive(Debug)]
pub struct ClothSim {
    model: ClothModel,
    /// The surfaces' triangles (particle indices), for the kinds whose mesh never changes.
    triangles: Vec<[u32; 3]>,
    /// The static objects the cloth meets, as triangle meshes (analytic shapes tessellated).
    obstacles: Vec<TriangleMesh>,
    kind: &'static str,
}

impl ClothSim {
    /// Builds a cloth scene as `anima run` would, with `solve`'s choices for the implicit integrators.
    /// Figures are not cloth: [`FigureSim::new`] takes them.
    pub fn new(scene: &Scene, solve: &SolveOptions) -> Result<Self> {
        let Some(parts) = crate::run::kind(scene).cloth() else {
            bail!("a {} scene holds figures, not cloth", scene.kind().name())
        };
        let ClothParts { mut model, triangles, obstacles, kind } = parts?;
        solve.configure(model.stepper_mut());
        Ok(Self { model, triangles, obstacles, kind })
    }

    /// `sheet`, `flex3d` or `oliveira`.
    pub fn kind(&self) -> &'static str {
        self.kind
    }

    /// One step (for Oliveira drapes, of the step the scene's rule chooses, then a remeshing pass when
    /// one is due). A non-finite state is an error naming the step where it appeared.
    pub fn step(&mut self) -> Result<()> {
        Ok(self.model.step()?)
    }

    /// `n` steps, stopping at the first failure.
    pub fn run(&mut self, n: usize) -> Result<()> {
        Ok(self.model.run(n as u64)?)
    }

    /// Steps until the simulated time reaches `t` (at least `t` − 10⁻¹² s; a step is never cut).
    pub fn run_until(&mut self, t: f64) -> Result<()> {
        if !t.is_finite() {
            bail!("the time to run to must be finite, found {t}");
        }
        while self.time() < t - 1e-12 {
            self.step()?;
        }
        Ok(())
    }

    pub fn time(&self) -> f64 {
        self.model.time()
    }

    /// Steps taken so far.
    pub fn steps(&self) -> u64 {
        self.model.steps()
    }

    /// The step the next call to [`ClothSim::step`] takes, s.
    pub fn dt(&self) -> f64 {
        self.model.dt()
    }

    pub fn positions(&self) -> &[DVec3] {
        self.model.positions()
    }

    pub fn velocities(&self) -> &[DVec3] {
        self.model.velocities()
    }

    /// Replaces every particle's position and velocity. Multistep and implicit integrators start their
    /// history again (the state jumped); the step count and time go on.
    pub fn set_state(&mut self, x: &[DVec3], v: &[DVec3]) -> Result<()> {
        let n = self.positions().len();
        if x.len() != n || v.len() != n {
            bail!(
                "expected {n} positions and velocities (one per particle), found {} and {}",
                x.len(),
                v.len()
            );
        }
        if let Some(i) = x.iter().zip(v).position(|(x, v)| !(x.is_finite() && v.is_finite())) {
            bail!("particle {i}'s position or velocity is not finite");
        }
        self.model.set_state(x, v);
        Ok(())
    }

    /// The cloth's triangles (particle indices). An Oliveira drape's change when it is remeshed.
    pub fn triangles(&self) -> &[[u32; 3]] {
        self.model.triangles().unwrap_or(&self.triangles)
    }

    /// The static objects the cloth meets, as triangle meshes (spheres and cylinders tessellated,
    /// planes as a patch around the origin).
    pub fn obstacles(&self) -> &[TriangleMesh] {
        &self.obstacles
    }
}

/// Where one body of a figure is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FigurePose {
    pub model: usize,
    pub body: usize,
    /// World position of the centre of mass, m (x forward, y up).
    pub centre: [f64; 2],
    /// World angle about z, rad, counter-clockwise.
    pub angle: f64,
}

/// Figures of a body scene (holding poses) or a character scene (driven by its controller), ready to
/// step.
#[derive(Debug)]
pub struct FigureSim {
    figures: FigureModel,
    poses: Vec<BodyPose>,
}

pub(crate) enum FigureModel {
    Posed(Box<Posed>),
    Character(Box<Character>),
}

impl std::fmt::Debug for FigureModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            FigureModel::Posed(_) => "Posed",
            FigureModel::Character(_) => "Character",
        })
    }
}

impl FigureSim {
    pub fn new(scene: &Scene) -> Result<Self> {
        let Some(figures) = crate::run::kind(scene).figures() else {
            bail!("a {} scene holds cloth, not figures", scene.kind().name())
        };
        let figures = figures?;
        Ok(Self { figures, poses: Vec::new() })
    }

    fn figures(&self) -> &dyn Figures {
        match &self.figures {
            FigureModel::Posed(p) => p.as_ref(),
            FigureModel::Character(c) => c.as_ref(),
        }
    }

    pub fn world(&self) -> &World {
        self.figures().world()
    }

    /// `n` control steps (each the sensors, the controller for characters, and the physics sub-steps).
    pub fn run(&mut self, n: usize) -> Result<()> {
        for _ in 0..n {
            match &mut self.figures {
                FigureModel::Posed(p) => Figures::step(p.as_mut())?,
                FigureModel::Character(c) => Figures::step(c.as_mut())?,
            }
        }
        Ok(())
    }

    pub fn time(&self) -> f64 {
        self.world().time()
    }

    /// The control step, s.
    pub fn dt(&self) -> f64 {
        self.world().settings().dt
    }

    /// Every body of every model, in model order.
    pub fn poses(&mut self) -> Result<Vec<FigurePose>> {
        let mut out = Vec::new();
        let world = match &self.figures {
            FigureModel::Posed(p) => p.world(),
            FigureModel::Character(c) => Figures::world(c.as_ref()),
        };
        for m in 0..world.n_models() {
            world.body_poses(m, &mut self.poses)?;
            out.extend(self.poses.iter().map(|p| FigurePose {
                model: m,
                body: p.body,
                centre: p.centre,
                angle: p.angle,
            }));
        }
        Ok(out)
    }

    /// The bodies' names, model after model, in the order of [`FigureSim::poses`].
    pub fn body_names(&self) -> Result<Vec<String>> {
        let world = self.world();
        let mut names = Vec::new();
        for m in 0..world.n_models() {
            let sk = world.skeleton(m)?;
            names.extend((0..sk.n_bodies()).map(|b| format!("{}/{}", sk.name(), sk.body(b).name)));
        }
        Ok(names)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stepped_sheet_ends_where_the_run_does() {
        let text = "SheetScene(sheet: SheetSpec(n: 8, size_m: 1.0, height_m: 1.5, total_mass_kg: 0.2, \
                    stiffness_n_m: (1000.0, 500.0, 10.0), damping_n_s_m: 0.02, pinned: [(0, 0), (7, 0)], \
                    gravity_m_s2: (0.0, 0.0, -9.81)), duration_s: 0.05, dt_s: 0.001, frame_rate_hz: 100.0, \
                    integrator: SymplecticEuler)";
        let scene = Scene::Sheet(anima_scene::sheet::from_ron_str(text).expect("a sheet"));
        let mut sim = ClothSim::new(&scene, &SolveOptions::default()).expect("builds");
        sim.run_until(0.05).expect("runs");
        assert_eq!(sim.steps(), 50);
        let dir = std::env::temp_dir().join(format!("anima-sim-{}", std::process::id()));
        let opts = crate::run::RunOptions { out_dir: Some(dir.clone()), frames: true, ..Default::default() };
        crate::run::run(&scene, "sheet", &opts, &mut crate::run::Silent).expect("runs");
        let text = std::fs::read_to_string(dir.join("sheet_5.obj")).expect("the last frame");
        let _ = std::fs::remove_dir_all(&dir);
        let x = anima_geom::read_obj(text.as_bytes()).expect("an OBJ").vertices().to_vec();
        assert_eq!(x.len(), sim.positions().len());
        for (a, b) in x.iter().zip(sim.positions()) {
            assert_eq!(a.to_array().map(f64::to_bits), b.to_array().map(f64::to_bits));
        }
        // A state set is the state stepped from: a sheet put back where it started with no velocity
        // retraces the first steps.
        let mut fresh = ClothSim::new(&scene, &SolveOptions::default()).expect("builds");
        let x0 = fresh.positions().to_vec();
        fresh.run(3).expect("runs");
        let after3 = fresh.positions().to_vec();
        fresh.set_state(&x0, &vec![DVec3::ZERO; x0.len()]).expect("same size");
        fresh.run(3).expect("runs");
        assert_eq!(fresh.positions(), &after3[..]);
        assert!(fresh.set_state(&x0[1..], &x0[1..]).is_err());
    }
}
