//! A particle bouncing off a plane inside generalised-α's solve: the bounce happens where and when it
//! hits, not at the end of the step.

use anima_ode::contact::{Contact, ContactModel};
mod common;

use anima_ode::{Integrator, State, Stepper};
use common::Particles;
use glam::DVec3;

/// The plane z = 0, frictionless, with restitution `e`: a particle whose step ends below it, or within
/// 1 mm above it, is in contact at the point of the plane under its end.
struct Floor {
    e: f64,
}

impl ContactModel<DVec3> for Floor {
    fn contacts(&mut self, _start: &[DVec3], end: &[DVec3], out: &mut Vec<Contact<DVec3>>) {
        for (i, p) in end.iter().enumerate() {
            if p.z < 1e-3 {
                out.push(Contact {
                    coordinate: i as u32,
                    normal: DVec3::Z,
                    point: DVec3::new(p.x, p.y, 0.0),
                    static_friction: 0.0,
                    kinetic_friction: 0.0,
                    restitution: self.e,
                });
            }
        }
    }
}

/// One particle 0.1 m above the floor falling at 3 m/s (and drifting at 0.2 m/s), steps of 0.05 s: it
/// hits after 1/30 s, two thirds into the first step.
fn drop(e: f64, steps: usize) -> State<DVec3> {
    let h = 0.05;
    let mut sys = Particles { masses: vec![0.01], prescribed: vec![false], gravity: DVec3::ZERO };
    let mut floor = Floor { e };
    let mut stepper = Stepper::new(Integrator::GeneralizedAlpha, 1);
    let mut now = State::new(vec![DVec3::new(0.0, 0.0, 0.1)], vec![DVec3::new(0.2, 0.0, -3.0)]);
    let mut next = now.clone();
    for s in 0..steps {
        stepper.step_with_contacts(&mut sys, &mut floor, s as f64 * h, h, &now, &mut next).expect("step");
        std::mem::swap(&mut now, &mut next);
    }
    now
}

#[test]
fn a_bounce_starts_at_the_moment_of_impact() {
    // A free particle bouncing at t* = 1/30 s with e = 0.5 leaves at 1.5 m/s and is 1.5 × (0.05 − 1/30)
    // = 25 mm up at the end of the step. Prescribing 1.5 m/s as the step's end velocity alone (without
    // the time of impact) leaves it 84 mm up.
    let after = drop(0.5, 1);
    let x = after.x[0];
    let v = after.v[0];
    assert!((x.z - 0.025).abs() < 1e-9, "height after the impact step {} m, expected 0.025", x.z);
    assert!((v.z - 1.5).abs() < 1e-9, "rising at {} m/s, expected 1.5", v.z);
    assert!((x.x - 0.01).abs() < 1e-9 && (v.x - 0.2).abs() < 1e-9, "the frictionless drift changed: {x} {v}");
    // The next step is free flight.
    let later = drop(0.5, 2);
    assert!((later.x[0].z - 0.1).abs() < 1e-9, "height a step later {} m, expected 0.1", later.x[0].z);
}

#[test]
fn an_inelastic_impact_ends_on_the_plane_at_rest() {
    let after = drop(0.0, 1);
    assert!(after.x[0].z.abs() < 1e-9, "height {} m", after.x[0].z);
    assert!(after.v[0].z.abs() < 1e-9, "normal velocity {} m/s", after.v[0].z);
    // It stays there.
    let later = drop(0.0, 3);
    assert!(later.x[0].z.abs() < 1e-9 && later.v[0].z.abs() < 1e-9, "{:?}", later);
}
