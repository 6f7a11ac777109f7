//! Edge springs and dampers (Oliveira 2013 §4.4.1.1, Eqs. 4.8–4.9): one per mesh edge, acting as both
//! structural and shear spring.

use anima_geom::DVec3;
use glam::DMat3;

use super::scene::{DamperLaw, SpringLaw};

/// Every spring of a mesh as flat arrays (one entry per edge).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Springs {
    pub ends: Vec<[u32; 2]>,
    /// L⁰ from material coordinates, m.
    pub rest_length: Vec<f64>,
    /// k^e = E·A⁰/L⁰, N/m.
    pub stiffness: Vec<f64>,
    /// k^d = α·k^e, N·s/m.
    pub damping: Vec<f64>,
}

/// The force one spring puts on its first particle i (particle j gets the opposite):
///
/// f_i = k^e (|d| − L⁰) d/|d|  (only while |d| > L⁰ for [`SpringLaw::TensionOnly`])
///     + k^d ((v_j − v_i)·d) d/|d|²,   d = x_j − x_i  (Eqs. 4.8, 4.9).
///
/// Coincident ends give no force (the direction is undefined).
#[inline]
#[expect(clippy::too_many_arguments, reason = "the two ends and the three parameters of Eqs. 4.8–4.9")]
pub fn spring_force(
    xi: DVec3,
    xj: DVec3,
    vi: DVec3,
    vj: DVec3,
    rest_length: f64,
    stiffness: f64,
    damping: f64,
    law: SpringLaw,
    damper: DamperLaw,
) -> DVec3 {
    let d = xj - xi;
    let len2 = d.length_squared();
    if len2 == 0.0 {
        return DVec3::ZERO;
    }
    let len = len2.sqrt();
    let inv_len = 1.0 / len;
    let stretched = len > rest_length;
    let elastic =
        if stretched || law == SpringLaw::TwoSided { stiffness * (len - rest_length) * inv_len } else { 0.0 };
    let viscous = if stretched || damper == DamperLaw::Always {
        damping * (vj - vi).dot(d) * inv_len * inv_len
    } else {
        0.0
    };
    d * (elastic + viscous)
}

impl Springs {
    pub fn len(&self) -> usize {
        self.ends.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ends.is_empty()
    }

    /// Adds every spring's force to `f`.
    pub fn add_forces(&self, x: &[DVec3], v: &[DVec3], f: &mut [DVec3], law: SpringLaw, damper: DamperLaw) {
        for (s, &[i, j]) in self.ends.iter().enumerate() {
            let (i, j) = (i as usize, j as usize);
            let fi = spring_force(
                x[i],
                x[j],
                v[i],
                v[j],
                self.rest_length[s],
                self.stiffness[s],
                self.damping[s],
                law,
                damper,
            );
            f[i] += fi;
            f[j] -= fi;
        }
    }

    /// Largest stiffness k^e_max, N/m (0 without springs).
    pub fn max_stiffness(&self) -> f64 {
        self.stiffness.iter().copied().fold(0.0, f64::max)
    }

    /// Shortest rest length, m (infinite without springs).
    pub fn shortest_rest_length(&self) -> f64 {
        self.rest_length.iter().copied().fold(f64::INFINITY, f64::min)
    }
}

/// Jacobians of one spring's force on particle i with respect to particle j's position and velocity,
/// K_ij = ∂f_i/∂x_j and D_ij = ∂f_i/∂v_j (the seam for implicit integration; the diagonal blocks are
/// K_ii = −K_ij, D_ii = −D_ij). With u = d/|d|:
///
/// K_ij = k^e [u uᵀ + (1 − L⁰/|d|)(I − u uᵀ)] while the elastic force acts, and
/// D_ij = k^d u uᵀ while the damper acts. The damper's dependence on position is left out, as usual
/// (Baraff & Witkin 1998), which keeps both blocks symmetric.
pub fn spring_jacobians(
    xi: DVec3,
    xj: DVec3,
    rest_length: f64,
    stiffness: f64,
    damping: f64,
    law: SpringLaw,
    damper: DamperLaw,
) -> (DMat3, DMat3) {
    let d = xj - xi;
    let len = d.length();
    if len == 0.0 {
        return (DMat3::ZERO, DMat3::ZERO);
    }
    let u = d / len;
    let uu = DMat3::from_cols(u * u.x, u * u.y, u * u.z);
    let stretched = len > rest_length;
    let k = if stretched || law == SpringLaw::TwoSided {
        (uu + (DMat3::IDENTITY - uu) * (1.0 - rest_length / len)) * stiffness
    } else {
        DMat3::ZERO
    };
    let c = if stretched || damper == DamperLaw::Always { uu * damping } else { DMat3::ZERO };
    (k, c)
}

/// [`spring_jacobians`] with the geometric term clamped at zero, which is what the implicit
/// integrators assemble: a compressed two-sided spring's (1 − L⁰/|d|) < 0 would make K indefinite.
pub fn definite_spring_jacobians(
    xi: DVec3,
    xj: DVec3,
    rest_length: f64,
    stiffness: f64,
    damping: f64,
    law: SpringLaw,
    damper: DamperLaw,
) -> (DMat3, DMat3) {
    let (k, c) = spring_jacobians(xi, xj, rest_length, stiffness, damping, law, damper);
    let len = (xj - xi).length();
    if law == SpringLaw::TwoSided && len > 0.0 && len < rest_length {
        let u = (xj - xi) / len;
        (DMat3::from_cols(u * u.x, u * u.y, u * u.z) * stiffness, c)
    } else {
        (k, c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const LAWS: [SpringLaw; 2] = [SpringLaw::TensionOnly, SpringLaw::TwoSided];

    #[test]
    fn tension_only_springs_push_nothing_when_compressed() {
        let (xi, xj) = (DVec3::ZERO, DVec3::new(0.3, 0.4, 0.0)); // |d| = 0.5
        let still = DVec3::ZERO;
        let f = |l0, law| spring_force(xi, xj, still, still, l0, 100.0, 1.0, law, DamperLaw::Always);
        // Compressed (rest 0.8): nothing with the thesis's law, a push apart with the two-sided one.
        assert_eq!(f(0.8, SpringLaw::TensionOnly), DVec3::ZERO);
        let push = f(0.8, SpringLaw::TwoSided);
        assert!(push.dot(xj - xi) < 0.0 && (push.length() - 30.0).abs() < 1e-12, "{push}");
        // Stretched (rest 0.4): both pull i towards j with k (|d| − L⁰) = 10 N.
        for law in LAWS {
            let pull = f(0.4, law);
            assert!((pull - (xj - xi) / 0.5 * 10.0).length() < 1e-12, "{law:?}: {pull}");
        }
    }

    #[test]
    fn damper_acts_along_the_spring_and_can_be_limited_to_tension() {
        let (xi, xj) = (DVec3::ZERO, DVec3::X);
        let (vi, vj) = (DVec3::new(0.0, 5.0, 0.0), DVec3::new(-2.0, 5.0, 3.0));
        // Approaching at 2 m/s along x, rest length 1.5 (compressed), k^d = 0.5: f_i = −1 N along x.
        let f = spring_force(xi, xj, vi, vj, 1.5, 100.0, 0.5, SpringLaw::TensionOnly, DamperLaw::Always);
        assert!((f - DVec3::new(-1.0, 0.0, 0.0)).length() < 1e-15, "{f}");
        let g = spring_force(xi, xj, vi, vj, 1.5, 100.0, 0.5, SpringLaw::TensionOnly, DamperLaw::WithTension);
        assert_eq!(g, DVec3::ZERO);
    }

    #[test]
    fn jacobians_match_finite_differences() {
        let (xi, xj) = (DVec3::new(0.1, -0.2, 0.05), DVec3::new(0.5, 0.1, -0.1));
        let (vi, vj) = (DVec3::new(0.3, 0.0, -0.2), DVec3::new(-0.1, 0.4, 0.2));
        for (l0, law) in
            [(0.3, SpringLaw::TensionOnly), (0.3, SpringLaw::TwoSided), (0.7, SpringLaw::TwoSided)]
        {
            let (k, d) = spring_jacobians(xi, xj, l0, 80.0, 0.8, law, DamperLaw::Always);
            let h = 1e-6;
            for axis in 0..3 {
                let e = DVec3::AXES[axis] * h;
                let f = |xj: DVec3, vj: DVec3| {
                    spring_force(xi, xj, vi, vj, l0, 80.0, 0.8, law, DamperLaw::Always)
                };
                let fd_v = (f(xj, vj + e) - f(xj, vj - e)) / (2.0 * h);
                assert!((fd_v - d.col(axis)).length() < 1e-6, "D column {axis}");
                // The elastic part alone (the damper's position dependence is left out on purpose).
                let fe = |xj: DVec3| spring_force(xi, xj, vi, vi, l0, 80.0, 0.0, law, DamperLaw::Always);
                let fd_x = (fe(xj + e) - fe(xj - e)) / (2.0 * h);
                assert!((fd_x - k.col(axis)).length() < 1e-5, "{law:?} L0 {l0}: K column {axis}");
            }
        }
    }
}
