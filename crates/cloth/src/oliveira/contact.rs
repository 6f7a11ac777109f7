//! Collision response against static objects (Oliveira 2013 §4.4.2.1, Eqs. 4.16–4.18): after each
//! step, each particle's path is cast against the objects; a particle whose path meets a surface gets
//! an instantaneous velocity change, repulsion after Parent (2012) and friction after Bridson, Fedkiw
//! and Anderson (2002), and restarts from where it began the step.

use anima_geom::{DVec3, Solid};

use super::scene::SeparatingContact;

/// A static object as the cloth sees it.
#[derive(Debug, Clone)]
pub struct Collider {
    pub name: String,
    pub solid: Solid,
    /// μ of the object.
    pub friction: f64,
}

/// The velocity after a hit (Eqs. 4.16–4.17), from the velocity `v` before it, the surface's unit
/// outward normal `n`, the restitution γ and the contact's friction μ (the mean of the cloth's and the
/// object's):
///
/// v̄_R = v − (1 + γ) v_N,  v_N = (v·n̂) n̂;
/// v̄_T = max(1 − μ Δv_N/|v_T|, 0) v_T,  Δv_N = (v̄_R − v)·n̂,  v_T = v − v_N;
/// v̄ = (v̄_R·n̂) n̂ + v̄_T.
///
/// With [`SeparatingContact::KeepVelocity`] a particle already moving away (v·n̂ ≥ 0) keeps `v`.
#[inline]
pub fn contact_velocity(
    v: DVec3,
    n: DVec3,
    restitution: f64,
    mu: f64,
    separating: SeparatingContact,
) -> DVec3 {
    let vn = v.dot(n);
    if vn >= 0.0 && separating == SeparatingContact::KeepVelocity {
        return v;
    }
    let v_normal = n * vn;
    let v_r = v - v_normal * (1.0 + restitution);
    let dvn = (v_r - v).dot(n);
    let v_t = v - v_normal;
    let vt_len = v_t.length();
    let v_t_after = if vt_len > 0.0 { v_t * (1.0 - mu * dvn / vt_len).max(0.0) } else { DVec3::ZERO };
    n * v_r.dot(n) + v_t_after
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_velocity_reverses_scaled_by_restitution() {
        let v = DVec3::new(0.0, 0.0, -2.0);
        let out = contact_velocity(v, DVec3::Z, 0.5, 0.3, SeparatingContact::KeepVelocity);
        assert!((out - DVec3::new(0.0, 0.0, 1.0)).length() < 1e-15);
    }

    #[test]
    fn friction_slows_sliding_and_can_stop_it() {
        // Δv_N = (1 + γ)·2 = 3 m/s; μΔv_N = 0.3 m/s off a 1 m/s slide, or all of it with μ = 0.5.
        let v = DVec3::new(1.0, 0.0, -2.0);
        let slow = contact_velocity(v, DVec3::Z, 0.5, 0.1, SeparatingContact::KeepVelocity);
        assert!((slow - DVec3::new(0.7, 0.0, 1.0)).length() < 1e-15, "{slow}");
        let stop = contact_velocity(v, DVec3::Z, 0.5, 0.5, SeparatingContact::KeepVelocity);
        assert!((stop - DVec3::new(0.0, 0.0, 1.0)).length() < 1e-15, "{stop}");
    }

    #[test]
    fn separating_particles_keep_their_velocity_unless_literal() {
        let v = DVec3::new(1.0, 0.0, 0.5);
        assert_eq!(contact_velocity(v, DVec3::Z, 0.5, 0.4, SeparatingContact::KeepVelocity), v);
        // As printed: the normal part turns into the surface and friction speeds the slide up.
        let lit = contact_velocity(v, DVec3::Z, 0.5, 0.4, SeparatingContact::Literal);
        assert!((lit - DVec3::new(1.3, 0.0, -0.25)).length() < 1e-15, "{lit}");
    }
}
