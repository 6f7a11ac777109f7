//! What the contact tests share: free particles under a uniform gravity.

use anima_ode::{Jacobians, Linearized, OdeSystem};
use glam::DVec3;

/// Particles under the uniform acceleration `gravity` alone (zero: a step's motion is a straight line
/// until it meets a surface).
pub struct Particles {
    pub masses: Vec<f64>,
    pub prescribed: Vec<bool>,
    pub gravity: DVec3,
}

impl Linearized<DVec3> for Particles {
    fn masses(&self) -> &[f64] {
        &self.masses
    }
    fn prescribed(&self) -> &[bool] {
        &self.prescribed
    }
    fn pattern(&self) -> &[(u32, u32)] {
        &[]
    }
    fn force_and_jacobians(
        &mut self,
        _t: f64,
        _x: &[DVec3],
        _v: &[DVec3],
        f: &mut [DVec3],
        _jac: &mut Jacobians<DVec3>,
    ) {
        for (f, m) in f.iter_mut().zip(&self.masses) {
            *f = self.gravity * *m;
        }
    }
}

impl OdeSystem for Particles {
    type Coord = DVec3;
    fn n_coords(&self) -> usize {
        self.masses.len()
    }
    fn acceleration(&mut self, _t: f64, _x: &[DVec3], _v: &[DVec3], a: &mut [DVec3]) {
        a.fill(self.gravity);
    }
    fn linearized(&mut self) -> Option<&mut dyn Linearized<DVec3>> {
        Some(self)
    }
}
