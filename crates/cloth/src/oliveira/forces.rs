//! The equations of motion integrated by RK4 (Oliveira 2013 §4.4, Eq. 4.7): springs and dampers,
//! bending, gravity and air drag. Contact is not among them: it is answered after the step (§4.4.2.1).

use anima_geom::DVec3;
use anima_ode::OdeSystem;

use super::bending::BendingElements;
use super::scene::{DamperLaw, SpringLaw};
use super::springs::Springs;

/// Everything the acceleration depends on, as flat arrays over particles, springs and elements.
#[derive(Debug, Clone)]
pub struct ClothModel {
    pub springs: Springs,
    pub bending: BendingElements,
    pub mass: Vec<f64>,
    pub inv_mass: Vec<f64>,
    /// m_i·g, N.
    pub weight: Vec<DVec3>,
    /// C_i = A_i·κ, kg/s.
    pub drag: Vec<f64>,
    pub bending_stiffness: f64,
    pub bending_damping: f64,
    pub spring_law: SpringLaw,
    pub damper_law: DamperLaw,
}

impl ClothModel {
    /// The total force on every particle, N: f_i = m_i g − C_i v_i + springs + bending (Eq. 4.7).
    pub fn forces(&self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
        for ((fi, (w, c)), vi) in f.iter_mut().zip(self.weight.iter().zip(&self.drag)).zip(v) {
            *fi = *w - *vi * *c;
        }
        self.springs.add_forces(x, v, f, self.spring_law, self.damper_law);
        if self.bending_stiffness != 0.0 || self.bending_damping != 0.0 {
            self.bending.add_forces(x, v, f, self.bending_stiffness, self.bending_damping);
        }
    }
}

impl OdeSystem for ClothModel {
    type Coord = DVec3;

    fn n_coords(&self) -> usize {
        self.mass.len()
    }

    fn acceleration(&mut self, _t: f64, x: &[DVec3], v: &[DVec3], a: &mut [DVec3]) {
        self.forces(x, v, a);
        for (ai, m) in a.iter_mut().zip(&self.inv_mass) {
            *ai *= *m;
        }
    }
}
