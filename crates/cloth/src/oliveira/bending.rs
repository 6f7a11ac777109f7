//! The Bridson–Marino–Fedkiw (2003) dihedral bending element, one per interior edge, as Oliveira 2013
//! §4.4.1.2 writes it (Eqs. 4.10–4.13, Figs. 4.3–4.4).
//!
//! Vertex order: the shared edge runs x₃ → x₄ in triangle 1 = (x₃, x₄, x₁) and x₄ → x₃ in
//! triangle 2 = (x₄, x₃, x₂), both counter-clockwise (`anima_geom::halfedge::EdgeStencil`). With
//!
//! N₁ = (x₁ − x₃) × (x₁ − x₄),  N₂ = (x₂ − x₄) × (x₂ − x₃),  e = x₄ − x₃,
//!
//! the bending mode is
//!
//! u₁ = |e| N₁/|N₁|²,  u₂ = |e| N₂/|N₂|²,
//! u₃ = (x₁ − x₄)·e/|e| N₁/|N₁|² + (x₂ − x₄)·e/|e| N₂/|N₂|²,
//! u₄ = −(x₁ − x₃)·e/|e| N₁/|N₁|² − (x₂ − x₃)·e/|e| N₂/|N₂|²,
//!
//! and the forces are
//!
//! f_i = k^e |e|²/(|N₁| + |N₂|) sin(θ/2) u_i − k^d |e| (Σ_j u_j·v_j) u_i,
//!
//! with θ the angle between the unit normals n̂₁, n̂₂, signed by (n̂₁ × n̂₂)·ê. The spec checked that this
//! is restoring and that the damping term dissipates exactly as printed, so the signs are kept as they
//! are (spec §5.3). The rest angle is zero: the cloth is cut flat.

use anima_geom::DVec3;

/// Every bending element of a mesh: vertex quadruples [x₁, x₂, x₃, x₄].
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BendingElements {
    pub stencils: Vec<[u32; 4]>,
}

/// sin(θ/2) of the angle between unit normals n̂₁ and n̂₂, signed by (n̂₁ × n̂₂)·e.
///
/// |n̂₁ − n̂₂| = 2 sin(|θ|/2) exactly, and unlike √((1 − n̂₁·n̂₂)/2) it has no cancellation near θ = 0:
/// a flat pair gives about 10⁻¹⁶, not 10⁻⁸ (the spec's atan2 form is equivalent and slower).
#[inline]
pub fn sin_half_angle(n1: DVec3, n2: DVec3, e: DVec3) -> f64 {
    let s = 0.5 * (n1 - n2).length();
    if n1.cross(n2).dot(e) < 0.0 { -s } else { s }
}

/// The bending mode u₁..u₄ of Eq. 4.10 and, for Eq. 4.11, |e|, |N₁|, |N₂| and sin(θ/2); `None` for a
/// degenerate element (a zero-length edge, or a triangle of zero area), which then exerts no force.
///
/// `height_floor` (η) bounds the mode of a sliver: when a triangle's |N| is below η|e|² (its height over
/// the hinge below η|e|) the whole mode is scaled by |N|/(η|e|²), so that neither |u₁| nor |u₂| exceeds 1/(η|e|) and
/// Σuᵢ = 0, Σxᵢ × uᵢ = 0 still hold (see [`crate::oliveira::Options::bending_height_floor`]). η = 0 is
/// Eq. 4.10 as printed; above the floor the arithmetic is the printed one to the bit.
///
/// Written for speed (this is most of a step's cost): one reciprocal per length instead of a division
/// per component, and (x₁ − x₄)·e = (x₁ − x₃)·e − |e|², so two dot products serve four.
#[inline]
pub fn bending_mode(x: [DVec3; 4], height_floor: f64) -> Option<BendingMode> {
    let [x1, x2, x3, x4] = x;
    let e = x4 - x3;
    let e2 = e.length_squared();
    let n1 = (x1 - x3).cross(x1 - x4);
    let n2 = (x2 - x4).cross(x2 - x3);
    let (a1, a2) = (n1.length_squared(), n2.length_squared());
    // Relative tolerance: |N| is twice a triangle area, |e|² the scale of one.
    let tiny = 1e-24 * e2 * e2;
    if e2 == 0.0 || a1 <= tiny || a2 <= tiny || !(a1.is_finite() && a2.is_finite()) {
        return None;
    }
    let e_len = e2.sqrt();
    let inv_e = 1.0 / e_len;
    let (l1, l2) = (a1.sqrt(), a2.sqrt());
    let (inv_l1, inv_l2) = (1.0 / l1, 1.0 / l2);
    let (n1_hat, n2_hat) = (n1 * inv_l1, n2 * inv_l2);
    // N/|N|².
    let (mut w1, mut w2) = (n1_hat * inv_l1, n2_hat * inv_l2);
    // Each triangle's part of the mode carries the same unit torque about the hinge, so a sliver's is
    // not bounded alone (that would break angular momentum): the whole mode is scaled instead.
    let floor = height_floor * e2;
    let thinnest = l1.min(l2);
    if thinnest < floor {
        let s = thinnest / floor;
        w1 *= s;
        w2 *= s;
    }
    let d1 = (x1 - x3).dot(e) * inv_e; // (x₁ − x₃)·e/|e|
    let d2 = (x2 - x3).dot(e) * inv_e;
    let u1 = w1 * e_len;
    let u2 = w2 * e_len;
    let u3 = w1 * (d1 - e_len) + w2 * (d2 - e_len);
    let u4 = -(w1 * d1) - w2 * d2;
    let sin_half = sin_half_angle(n1_hat, n2_hat, e);
    Some(BendingMode { u: [u1, u2, u3, u4], e_len, n1_len: l1, n2_len: l2, sin_half })
}

/// What [`bending_mode`] computes for one element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BendingMode {
    /// u₁..u₄ of Eq. 4.10, 1/m.
    pub u: [DVec3; 4],
    pub e_len: f64,
    /// |N₁|, |N₂|: twice the triangle areas.
    pub n1_len: f64,
    pub n2_len: f64,
    /// sin(θ/2), signed.
    pub sin_half: f64,
}

/// Forces of one element on x₁..x₄ (Eqs. 4.11 and 4.13), N; `height_floor` as for [`bending_mode`].
#[inline]
pub fn bending_forces(
    x: [DVec3; 4],
    v: [DVec3; 4],
    stiffness: f64,
    damping: f64,
    height_floor: f64,
) -> [DVec3; 4] {
    let Some(m) = bending_mode(x, height_floor) else {
        return [DVec3::ZERO; 4];
    };
    m.forces(v, stiffness, damping)
}

impl BendingMode {
    /// The element's forces (Eqs. 4.11 and 4.13) at velocities `v`, N.
    #[inline]
    pub fn forces(&self, v: [DVec3; 4], stiffness: f64, damping: f64) -> [DVec3; 4] {
        let u = self.u;
        let elastic = stiffness * self.e_len * self.e_len / (self.n1_len + self.n2_len) * self.sin_half;
        // Eq. 4.12's "dθ/dt", used as printed (spec §5.3).
        let rate = u[0].dot(v[0]) + u[1].dot(v[1]) + u[2].dot(v[2]) + u[3].dot(v[3]);
        let c = elastic - damping * self.e_len * rate;
        u.map(|ui| ui * c)
    }

    /// The unit mean of the two face normals, along which a flat element's mode points (u₁ and u₂ are
    /// along the face normals); the first face's normal when the element is folded flat onto itself.
    #[inline]
    pub fn mean_normal(&self) -> DVec3 {
        let (n1, n2) = (self.u[0].normalize_or_zero(), self.u[1].normalize_or_zero());
        (n1 + n2).try_normalize().unwrap_or(n1)
    }

    /// The coefficients of the element's force Jacobians in the mode: ∂f_a/∂x_b ≈ −k_x u_a u_bᵀ and
    /// ∂f_a/∂v_b = −k_v u_a u_bᵀ, returned as (k_x, k_v). Since u = −∂θ/∂x, the elastic force
    /// f_a = K sin(θ/2) u_a (K = k |e|²/(|N₁| + |N₂|)) has the Gauss–Newton Jacobian
    /// −K ½ cos(θ/2) u uᵀ (the curvature of θ and the change of K and of u are left out, which keeps
    /// it symmetric and negative semi-definite); the damper's is exact for the printed Eq. 4.13.
    #[inline]
    pub fn jacobian_coefficients(&self, stiffness: f64, damping: f64) -> (f64, f64) {
        let cos_half = (1.0 - self.sin_half * self.sin_half).max(0.0).sqrt();
        let k = stiffness * self.e_len * self.e_len / (self.n1_len + self.n2_len);
        (0.5 * k * cos_half, damping * self.e_len)
    }
}

impl BendingElements {
    pub fn len(&self) -> usize {
        self.stencils.len()
    }

    pub fn is_empty(&self) -> bool {
        self.stencils.is_empty()
    }

    /// Adds every element's forces to `f` (`height_floor` as for [`bending_mode`]).
    pub fn add_forces(
        &self,
        x: &[DVec3],
        v: &[DVec3],
        f: &mut [DVec3],
        stiffness: f64,
        damping: f64,
        height_floor: f64,
    ) {
        for s in &self.stencils {
            let idx = s.map(|i| i as usize);
            let forces =
                bending_forces(idx.map(|i| x[i]), idx.map(|i| v[i]), stiffness, damping, height_floor);
            for (k, &i) in idx.iter().enumerate() {
                f[i] += forces[k];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The pair of triangles around the edge x₃ = (0, 0, 0) → x₄ = (1, 0, 0), with x₁ on the left (+y)
    /// and x₂ on the right, folded by lifting x₂ to height `lift`.
    fn pair(lift: f64) -> [DVec3; 4] {
        [
            DVec3::new(0.3, 0.8, 0.0),
            DVec3::new(0.6, -0.7, lift),
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
        ]
    }

    /// A deterministic perturbation so the tests do not depend on symmetric layouts.
    fn jitter(x: [DVec3; 4], k: u64) -> [DVec3; 4] {
        let mut s = 0x9e37_79b9_7f4a_7c15u64.wrapping_mul(k + 1);
        let mut r = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        x.map(|p| p + DVec3::new(r(), r(), r()) * 0.2)
    }

    #[test]
    fn flat_pair_exerts_no_force() {
        let v = [DVec3::ZERO; 4];
        let f = bending_forces(pair(0.0), v, 1e-3, 1e-4, 0.0);
        assert!(f.iter().all(|fi| fi.length() < 1e-18), "{f:?}");
        // Also when the flat pair is rotated and moved rigidly.
        let rot = glam::DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
        let moved = pair(0.0).map(|p| rot * p + DVec3::new(3.0, -1.0, 2.0));
        let f = bending_forces(moved, v, 1e-3, 1e-4, 0.0);
        assert!(f.iter().all(|fi| fi.length() < 1e-17), "{f:?}");
    }

    #[test]
    fn forces_conserve_linear_and_angular_momentum() {
        for k in 0..50 {
            let x = jitter(pair(0.4 * (k as f64 / 10.0 - 2.5)), k);
            let v = jitter([DVec3::ZERO; 4], k + 100).map(|p| p * 10.0);
            for (ke, kd) in [(1e-3, 0.0), (0.0, 1e-4), (1e-3, 1e-4)] {
                let f = bending_forces(x, v, ke, kd, 0.0);
                let sum: DVec3 = f.iter().sum();
                let torque: DVec3 = x.iter().zip(&f).map(|(p, fi)| p.cross(*fi)).sum();
                let scale = f.iter().map(|fi| fi.length()).fold(0.0, f64::max).max(1e-30);
                assert!(sum.length() < 1e-12 * scale, "case {k}: Σf = {sum}");
                assert!(torque.length() < 1e-12 * scale, "case {k}: Σx×f = {torque}");
            }
        }
    }

    #[test]
    fn mode_is_minus_the_angle_gradient() {
        // u_i = −∂θ/∂x_i (spec §5.3), θ signed by (n̂₁ × n̂₂)·ê.
        let theta = |x: [DVec3; 4]| {
            let [x1, x2, x3, x4] = x;
            let e = x4 - x3;
            let n1 = (x1 - x3).cross(x1 - x4).normalize();
            let n2 = (x2 - x4).cross(x2 - x3).normalize();
            n1.cross(n2).dot(e.normalize()).atan2(n1.dot(n2))
        };
        for k in 0..20 {
            let x = jitter(pair(0.3), k);
            let u = bending_mode(x, 0.0).unwrap().u;
            for i in 0..4 {
                for axis in 0..3 {
                    let h = 1e-7;
                    let (mut a, mut b) = (x, x);
                    a[i] += DVec3::AXES[axis] * h;
                    b[i] -= DVec3::AXES[axis] * h;
                    let grad = (theta(a) - theta(b)) / (2.0 * h);
                    assert!((grad + u[i][axis]).abs() < 1e-5 * (1.0 + u[i].length()), "case {k}");
                }
            }
        }
    }

    #[test]
    fn bent_element_relaxes_towards_flat_and_damping_dissipates() {
        for lift in [0.5, -0.5, 0.05, -1.5] {
            let x = pair(lift);
            let f = bending_forces(x, [DVec3::ZERO; 4], 1e-3, 0.0, 0.0);
            let angle = |x: [DVec3; 4]| 2.0 * bending_mode(x, 0.0).unwrap().sin_half.abs().asin();
            let step = 1e-2;
            let moved: Vec<DVec3> = x.iter().zip(&f).map(|(p, fi)| *p + *fi * step).collect();
            let moved = [moved[0], moved[1], moved[2], moved[3]];
            assert!(angle(moved) < angle(x), "lift {lift}: |θ| grew along the elastic force");
        }
        for k in 0..20 {
            let x = jitter(pair(0.3), k);
            let v = jitter([DVec3::ZERO; 4], k + 7);
            let f = bending_forces(x, v, 0.0, 1e-4, 0.0);
            let power: f64 = f.iter().zip(&v).map(|(fi, vi)| fi.dot(*vi)).sum();
            assert!(power <= 1e-18, "case {k}: damping power {power} > 0");
        }
    }

    #[test]
    fn the_height_floor_bounds_a_sliver_and_changes_nothing_above_it() {
        // Every jittered pair has both heights well above 5 % of its hinge: the same bits.
        for k in 0..20 {
            let x = jitter(pair(0.3), k);
            let v = jitter([DVec3::ZERO; 4], k + 7);
            assert_eq!(bending_forces(x, v, 1e-3, 1e-4, 0.05), bending_forces(x, v, 1e-3, 1e-4, 0.0));
        }
        // x₁ brought to within h of the hinge (|e| = 1): as printed, the damping force grows as 1/h²;
        // with the floor it stops growing below h = η|e|, and momentum is still conserved.
        let v = [DVec3::Z, DVec3::ZERO, DVec3::ZERO, DVec3::ZERO];
        let force = |h: f64, eta: f64| {
            let mut x = pair(0.3);
            x[0] = DVec3::new(0.3, h, 0.0);
            bending_forces(x, v, 1e-3, 1e-4, eta)
        };
        let printed = force(1e-3, 0.0)[0].length() / force(1e-2, 0.0)[0].length();
        assert!(printed > 50.0, "as printed, 10× closer gives {printed}× the force");
        let floored = force(1e-3, 0.05)[0].length() / force(1e-2, 0.05)[0].length();
        assert!(floored < 1.5, "with the floor, 10× closer gives {floored}× the force");
        let mut x = pair(0.3);
        x[0] = DVec3::new(0.3, 1e-3, 0.0);
        let f = bending_forces(x, jitter([DVec3::ZERO; 4], 3), 1e-3, 1e-4, 0.05);
        let scale = f.iter().map(|fi| fi.length()).fold(0.0, f64::max);
        let sum: DVec3 = f.iter().sum();
        let torque: DVec3 = x.iter().zip(&f).map(|(p, fi)| p.cross(*fi)).sum();
        assert!(sum.length() < 1e-12 * scale && torque.length() < 1e-12 * scale, "{sum} {torque}");
    }

    #[test]
    fn degenerate_elements_exert_nothing() {
        let mut x = pair(0.3);
        x[0] = DVec3::new(0.5, 0.0, 0.0); // x₁ on the edge: triangle 1 has no area
        assert_eq!(bending_forces(x, [DVec3::ONE; 4], 1e-3, 1e-4, 0.0), [DVec3::ZERO; 4]);
        let mut y = pair(0.3);
        y[3] = y[2];
        assert_eq!(bending_forces(y, [DVec3::ONE; 4], 1e-3, 1e-4, 0.0), [DVec3::ZERO; 4]);
    }

    /// At a flat element the Gauss–Newton Jacobian is the exact one: the terms it leaves out carry
    /// sin(θ/2) = 0. Checked against central differences of the elastic force, on jittered flat
    /// pairs rotated out of the plane.
    #[test]
    fn the_jacobian_is_exact_at_a_flat_element() {
        let rot = glam::DQuat::from_axis_angle(DVec3::new(1.0, -2.0, 0.5).normalize(), 0.9);
        for k in 0..10 {
            let flat = jitter(pair(0.0), k).map(|p| DVec3::new(p.x, p.y, 0.0));
            let x = flat.map(|p| rot * p);
            let m = bending_mode(x, 0.0).unwrap();
            let (kx, _) = m.jacobian_coefficients(1e-3, 0.0);
            let still = [DVec3::ZERO; 4];
            let h = 1e-7;
            for b in 0..4 {
                for axis in 0..3 {
                    let (mut plus, mut minus) = (x, x);
                    plus[b] += DVec3::AXES[axis] * h;
                    minus[b] -= DVec3::AXES[axis] * h;
                    let (fp, fm) = (
                        bending_forces(plus, still, 1e-3, 0.0, 0.0),
                        bending_forces(minus, still, 1e-3, 0.0, 0.0),
                    );
                    for a in 0..4 {
                        let fd = (fp[a] - fm[a]) / (2.0 * h);
                        let gn = m.u[a] * (-kx * m.u[b][axis]);
                        assert!(
                            (fd - gn).length() < 1e-6 * (1.0 + gn.length()),
                            "case {k}, ∂f_{a}/∂x_{b}[{axis}]: {fd} vs {gn}"
                        );
                    }
                }
            }
        }
    }
}
