//! The one-spring test problem of Nedel 1993 §4.4 (FLEX3D's Table 4.1): a unit mass on a spring of
//! stiffness 1 and rest length 2, fixed at the origin, released from x = 4 at rest. Exact solution
//! x(t) = 2 + 2 cos t. The integrator tests step it, and the cloth crate's FLEX3D experiments
//! reproduce the thesis's table with it.

use crate::{Jacobians, Linearized, OdeSystem};

/// x'' = −k (x − L0)/m with k = 1, m = 1, L0 = 2.
#[derive(Debug, Clone, Copy)]
pub struct SingleSpring {
    pub stiffness: f64,
    pub mass: f64,
    pub rest_length: f64,
}

impl SingleSpring {
    /// The spring of Table 4.1.
    pub const fn thesis() -> Self {
        Self { stiffness: 1.0, mass: 1.0, rest_length: 2.0 }
    }

    /// Exact position for the release from x = 4 at rest: 2 + 2 cos(ω t), ω = √(k/m).
    pub fn exact(&self, t: f64) -> f64 {
        let amplitude = 4.0 - self.rest_length;
        self.rest_length + amplitude * ((self.stiffness / self.mass).sqrt() * t).cos()
    }
}

impl OdeSystem for SingleSpring {
    type Coord = f64;

    fn n_coords(&self) -> usize {
        1
    }

    fn acceleration(&mut self, _t: f64, x: &[f64], _v: &[f64], a: &mut [f64]) {
        a[0] = -self.stiffness * (x[0] - self.rest_length) / self.mass;
    }

    fn linearized(&mut self) -> Option<&mut dyn Linearized<f64>> {
        Some(self)
    }
}

/// f = −k (x − L0), ∂f/∂x = −k.
impl Linearized<f64> for SingleSpring {
    fn masses(&self) -> &[f64] {
        std::slice::from_ref(&self.mass)
    }

    fn prescribed(&self) -> &[bool] {
        &[false]
    }

    fn pattern(&self) -> &[(u32, u32)] {
        &[]
    }

    fn force_and_jacobians(
        &mut self,
        _t: f64,
        x: &[f64],
        _v: &[f64],
        f: &mut [f64],
        jac: &mut Jacobians<f64>,
    ) {
        f[0] = -self.stiffness * (x[0] - self.rest_length);
        jac.k_diag[0] = -self.stiffness;
    }
}
