//! One contract for everything anima steps: the cloth models (a spring network, a membrane, FLEX3D's
//! surfaces, the Oliveira cloth and its adaptive form), the posed figures of a body scene and a
//! character. A run loop, a game loop or the Python package steps any of them through [`Simulation`];
//! what has particles also reads and writes them through [`Deformable`].

use anima_body::BodyError;
use anima_character::Character;
use anima_cloth::StepError;
use anima_cloth::flex3d::Flex3dWorld;
use anima_cloth::membrane::MembraneSim;
use anima_cloth::network_sim::NetworkSim;
use anima_cloth::oliveira::{AdaptiveCloth, OliveiraCloth};
use anima_geom::DVec3;
use anima_ode::Stepper;

use crate::run::body::{Figures, Posed};

/// Something stepped in time. Steps are counted (time is steps × Δt where Δt is fixed, never a sum of
/// floating-point steps where it can be); a step that fails leaves an error naming it.
pub trait Simulation {
    type Error: std::error::Error + Send + Sync + 'static;

    /// One step of [`Simulation::dt`].
    fn step(&mut self) -> Result<(), Self::Error>;

    /// `n` steps, stopping at the first failure. A model with a faster path for many steps (the fused
    /// sheet run) takes it: the same bits as `n` calls of [`Simulation::step`].
    fn run(&mut self, n: u64) -> Result<(), Self::Error> {
        (0..n).try_for_each(|_| self.step())
    }

    /// Steps until the time has moved on by `duration` s (to within 10⁻¹² s; a step is never cut):
    /// one frame of a game loop.
    fn advance(&mut self, duration: f64) -> Result<(), Self::Error> {
        let end = self.time() + duration;
        while self.time() < end - 1e-12 {
            self.step()?;
        }
        Ok(())
    }

    /// Steps taken so far.
    fn steps(&self) -> u64;

    /// The simulated time, s.
    fn time(&self) -> f64;

    /// The step the next call to [`Simulation::step`] takes, s.
    fn dt(&self) -> f64;
}

/// A simulation of particles: cloth of any model.
pub trait Deformable: Simulation + std::fmt::Debug {
    /// Every particle's position, in the model's order.
    fn positions(&self) -> &[DVec3];
    fn velocities(&self) -> &[DVec3];
    /// Replaces every particle's position and velocity; multistep and implicit integrators start their
    /// history again, the step count and time go on.
    ///
    /// # Panics
    /// If `x` or `v` does not hold one value per particle.
    fn set_state(&mut self, x: &[DVec3], v: &[DVec3]);
    /// The surface's current triangles where the model holds them (the Oliveira cloth, whose remeshing
    /// changes them); `None` for grids, whose triangles the caller built and which never change.
    fn triangles(&self) -> Option<&[[u32; 3]]> {
        None
    }
    /// The integrator, to configure its solver.
    fn stepper_mut(&mut self) -> &mut Stepper<DVec3>;
}

/// The clock and state every cloth model spells the same way (`anima_cloth`'s one vocabulary).
macro_rules! cloth_vocabulary {
    () => {
        type Error = StepError;
        fn steps(&self) -> u64 {
            Self::steps(self)
        }
        fn time(&self) -> f64 {
            Self::time(self)
        }
        fn dt(&self) -> f64 {
            Self::dt(self)
        }
    };
}

macro_rules! cloth_state {
    () => {
        fn positions(&self) -> &[DVec3] {
            Self::positions(self)
        }
        fn velocities(&self) -> &[DVec3] {
            Self::velocities(self)
        }
        fn set_state(&mut self, x: &[DVec3], v: &[DVec3]) {
            Self::set_state(self, x, v)
        }
        fn stepper_mut(&mut self) -> &mut Stepper<DVec3> {
            Self::stepper_mut(self)
        }
    };
}

impl Simulation for NetworkSim {
    cloth_vocabulary!();
    fn step(&mut self) -> Result<(), StepError> {
        Self::step(self)
    }
    fn run(&mut self, n: u64) -> Result<(), StepError> {
        Self::run(self, n as usize)
    }
}

impl Deformable for NetworkSim {
    cloth_state!();
}

impl Simulation for MembraneSim {
    cloth_vocabulary!();
    fn step(&mut self) -> Result<(), StepError> {
        Self::run(self, 1)
    }
    fn run(&mut self, n: u64) -> Result<(), StepError> {
        Self::run(self, n as usize)
    }
}

impl Deformable for MembraneSim {
    cloth_state!();
}

impl Simulation for Flex3dWorld {
    cloth_vocabulary!();
    fn step(&mut self) -> Result<(), StepError> {
        Self::step(self)
    }
    fn run(&mut self, n: u64) -> Result<(), StepError> {
        self.run_to_step(Self::steps(self) + n)
    }
}

impl Deformable for Flex3dWorld {
    cloth_state!();
}

impl Simulation for OliveiraCloth {
    cloth_vocabulary!();
    fn step(&mut self) -> Result<(), StepError> {
        Self::step(self).map(|_| ())
    }
}

impl Deformable for OliveiraCloth {
    cloth_state!();
    fn triangles(&self) -> Option<&[[u32; 3]]> {
        Some(Self::triangles(self))
    }
}

impl Simulation for AdaptiveCloth {
    cloth_vocabulary!();
    /// One step of the cloth, then a remeshing pass when one is due.
    fn step(&mut self) -> Result<(), StepError> {
        Self::step(self).map(|_| ())
    }
}

impl Deformable for AdaptiveCloth {
    cloth_state!();
    fn triangles(&self) -> Option<&[[u32; 3]]> {
        Some(Self::triangles(self))
    }
}

/// One control step: the sensors, the controller, the physics sub-steps.
impl Simulation for Character {
    type Error = BodyError;
    fn step(&mut self) -> Result<(), BodyError> {
        Character::step(self)
    }
    fn steps(&self) -> u64 {
        self.env.world.steps()
    }
    fn time(&self) -> f64 {
        self.env.world.time()
    }
    fn dt(&self) -> f64 {
        self.env.world.settings().dt
    }
}

/// One control step of figures holding their poses, the sensors read afterwards.
impl Simulation for Posed {
    type Error = BodyError;
    fn step(&mut self) -> Result<(), BodyError> {
        Figures::step(self)
    }
    fn steps(&self) -> u64 {
        self.world().steps()
    }
    fn time(&self) -> f64 {
        self.world().time()
    }
    fn dt(&self) -> f64 {
        self.world().settings().dt
    }
}
