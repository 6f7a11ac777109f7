//! The equations of motion integrated by RK4 (Oliveira 2013 §4.4, Eq. 4.7): springs and dampers,
//! bending, gravity and air drag. Contact is not among them: it is answered after the step (§4.4.2.1).
//!
//! For the implicit integrators the model is also [`Linearized`]: the springs' exact Jacobians (the
//! geometric term clamped at zero so the system stays definite, as for every anima spring), the drag's
//! −C_i I on the velocity diagonal, and nothing for bending, which stays explicit inside the implicit
//! step. That split is sound here because Oliveira's bending is six orders of magnitude softer than
//! the stretch springs (k_b = 10⁻³ against k^e ≈ 400 N/m on the 17 × 17 mesh): its frequencies are far
//! below any step a user would choose, while the springs and dampers are what make explicit steps tiny.

use anima_geom::DVec3;
use anima_ode::{Jacobians, Linearized, OdeSystem};
use glam::DMat3;

use super::bending::BendingElements;
use super::scene::{DamperLaw, SpringLaw};
use super::springs::Springs;
use crate::membrane::Membrane;

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
    /// η of [`super::Options::bending_height_floor`].
    pub bending_height_floor: f64,
    pub spring_law: SpringLaw,
    pub damper_law: DamperLaw,
    /// The continuum model of [`super::Options::membrane`]: when present its elastic, bending and damping
    /// forces replace the springs' and the bending elements'.
    pub membrane: Option<Membrane>,
    /// The spring pattern and (empty) prescribed set the implicit integrators need, built on first use.
    pub(crate) implicit: ImplicitParts,
}

/// What [`Linearized`] hands out besides the masses, kept so the step loop does not rebuild it.
#[derive(Debug, Clone, Default)]
pub(crate) struct ImplicitParts {
    /// Per spring, its ends ordered (i < j).
    pattern: Vec<(u32, u32)>,
    prescribed: Vec<bool>,
}

impl ClothModel {
    /// Forgets the implicit pattern (after the springs changed: a remesh).
    pub fn invalidate_implicit(&mut self) {
        self.implicit = ImplicitParts::default();
    }

    fn ensure_implicit(&mut self) {
        let parts = &mut self.implicit;
        let n_pairs = self.membrane.as_ref().map_or(self.springs.len(), |m| Linearized::pattern(m).len());
        if parts.pattern.len() == n_pairs && parts.prescribed.len() == self.mass.len() {
            return;
        }
        parts.pattern = match &self.membrane {
            Some(m) => Linearized::pattern(m).to_vec(),
            None => self.springs.ends.iter().map(|&[i, j]| (i.min(j), i.max(j))).collect(),
        };
        parts.prescribed = vec![false; self.mass.len()];
    }
}

impl ClothModel {
    /// f_i = m_i g − C_i v_i: the forces every model shares.
    fn weight_and_drag(&self, v: &[DVec3], f: &mut [DVec3]) {
        for ((fi, (w, c)), vi) in f.iter_mut().zip(self.weight.iter().zip(&self.drag)).zip(v) {
            *fi = *w - *vi * *c;
        }
    }

    /// The total force on every particle, N: f_i = m_i g − C_i v_i + springs + bending (Eq. 4.7), or
    /// the membrane's forces in place of the springs and bending.
    pub fn forces(&self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3]) {
        self.weight_and_drag(v, f);
        if let Some(m) = &self.membrane {
            m.add_forces(x, v, f, None);
            return;
        }
        self.springs.add_forces(x, v, f, self.spring_law, self.damper_law);
        if self.bending_stiffness != 0.0 || self.bending_damping != 0.0 {
            self.bending.add_forces(
                x,
                v,
                f,
                self.bending_stiffness,
                self.bending_damping,
                self.bending_height_floor,
            );
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

    fn linearized(&mut self) -> Option<&mut dyn Linearized<DVec3>> {
        self.ensure_implicit();
        Some(self)
    }
}

impl Linearized<DVec3> for ClothModel {
    fn masses(&self) -> &[f64] {
        &self.mass
    }

    fn prescribed(&self) -> &[bool] {
        &self.implicit.prescribed
    }

    fn pattern(&self) -> &[(u32, u32)] {
        &self.implicit.pattern
    }

    fn force(&mut self, _t: f64, x: &[DVec3], v: &[DVec3], f: &mut [DVec3], _scratch: &mut Jacobians<DVec3>) {
        self.forces(x, v, f);
    }

    fn force_and_jacobians(
        &mut self,
        _t: f64,
        x: &[DVec3],
        v: &[DVec3],
        f: &mut [DVec3],
        jac: &mut Jacobians<DVec3>,
    ) {
        for (d, &c) in jac.d_diag.iter_mut().zip(&self.drag) {
            *d -= DMat3::from_diagonal(DVec3::splat(c));
        }
        if let Some(m) = &self.membrane {
            self.weight_and_drag(v, f);
            m.add_forces(x, v, f, Some(jac));
            return;
        }
        self.forces(x, v, f);
        let s = &self.springs;
        for (e, &[i, j]) in s.ends.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let (k, c) = super::springs::definite_spring_jacobians(
                x[i],
                x[j],
                s.rest_length[e],
                s.stiffness[e],
                s.damping[e],
                self.spring_law,
                self.damper_law,
            );
            jac.k_diag[i] -= k;
            jac.k_diag[j] -= k;
            jac.k_off[e] += k;
            jac.d_diag[i] -= c;
            jac.d_diag[j] -= c;
            jac.d_off[e] += c;
        }
    }
}
