//! The body crate's acceptance tests (issue 4): model counts and masses, planar motion, PD-held
//! stances, the inter-thigh actuator's momentum, determinism, releasing the ball, skeleton errors,
//! the explicit-PD stability bound, sensors.

mod common;

use anima_body::sensors::catalogue;
use anima_body::{
    Actuation, BodyError, BodyScene, BuiltinSkeleton, PdMode, Placement, Role, SensorDelay, Sensors, Signal,
    Skeleton, SkeletonErrorKind, Support, Target, TargetFrame, Touch, World, WorldSettings,
};
use common::*;

// ---------------------------------------------------------------------------------------------
// Models

#[test]
fn thesis_models_have_the_counts_and_masses_of_tables_6_1_and_6_2() {
    let h = BuiltinSkeleton::Humanoid.load();
    assert_eq!((h.n_bodies(), h.n_joints(), h.n_actuators()), (14, 13, 14));
    // Table 6.1: 5.89 + 9.75 + 19.51 + 16.61 + 2 (8.35 + 4.16 + 1.20 + 2.79 + 1.76) = 88.28.
    assert!((h.total_mass() - 88.28).abs() < 1e-9, "humanoid mass {}", h.total_mass());
    assert_eq!(h.roots().len(), 1, "one tree rooted at the pelvis");
    assert_eq!(h.body(h.roots()[0]).name, "pelvis");
    // Arms are actuators 11–14; the inter-thigh actuator drives a body pair.
    for (n, name) in [(11, "shoulder_l"), (12, "elbow_l"), (13, "shoulder_r"), (14, "elbow_r")] {
        assert_eq!(h.actuators()[h.actuator_by_number(n).unwrap()].name, name);
    }
    let it = &h.actuators()[h.actuator_index("inter_thigh").unwrap()];
    assert!(matches!(it.drive, anima_body::DriveSpec::BodyPair { .. }));

    let t = BuiltinSkeleton::Thrower.load();
    assert_eq!((t.n_bodies(), t.n_joints(), t.n_actuators(), t.n_welds()), (15, 13, 14, 2));
    assert!((t.total_mass() - (88.28 + 0.6)).abs() < 1e-9);
    let ball = t.body_index("ball").unwrap();
    assert_eq!(t.body(ball).role, Role::Prop);
    assert!(!t.bodies_collide(ball, t.body_index("forearm_l").unwrap()), "ball–humanoid collisions off");

    let p = BuiltinSkeleton::Pusher.load();
    assert_eq!((p.n_bodies(), p.n_joints(), p.n_actuators()), (16, 15, 16));
    assert!((p.total_mass() - (88.28 + 1.0)).abs() < 1e-9);
    assert_eq!(p.sign(), -1.0, "the pusher faces −x");
    assert!(p.body(p.body_index("foot_l").unwrap()).centre.0 < 0.0, "toes point to −x");
}

#[test]
fn the_world_builds_one_multibody_dof_per_hinge_plus_three_for_the_root() {
    let (world, m, mut s) = stance(PdMode::ImplicitSpring);
    world.sense(&mut s).unwrap();
    // Zero joint angles in the initial pose; soles on the ground.
    assert!(s.joint_angle.iter().all(|&q| q == 0.0), "{:?}", s.joint_angle);
    let sk = world.skeleton(m).unwrap();
    let foot = sk.body_index("foot_l").unwrap();
    assert!((s.body_position[foot][1] - 0.05).abs() < 1e-6, "sole at y = 0: foot centre at 0.05 m");
}

// ---------------------------------------------------------------------------------------------
// Planar motion

#[test]
fn motion_stays_in_the_plane_to_round_off() {
    // A thrower waving its arms, pushed on the head, releasing the ball: every kind of force.
    let sk = BuiltinSkeleton::Thrower.load();
    let sk = sk.with_actuation(Actuation { gain_scale: STANCE_GAIN, ..*sk.actuation() }).unwrap();
    let mut world = World::new(WorldSettings { substeps: 10, ..WorldSettings::thesis() }).unwrap();
    let m = world.add_model(&sk, Placement::OnGround { dx: 0.0 }).unwrap();
    let head = sk.body_index("head").unwrap();
    let shoulder = sk.actuator_index("shoulder_l").unwrap();
    let mut s = Sensors::new(&world, m).unwrap();
    for k in 0..200 {
        let c = world.commands_mut(m).unwrap();
        c.clear();
        c.push(Signal::angle(shoulder, 2.0 * (0.1 * k as f64).sin())).unwrap();
        if k == 40 {
            world.sense(&mut s).unwrap();
            let p = s.body_position[head];
            world.apply_force(m, head, [150.0, 0.0], [p[0], p[1] + 0.05]).unwrap();
        }
        if k == 60 {
            world.release_weld(m, 0).unwrap();
            world.release_weld(m, 1).unwrap();
        }
        world.step().unwrap();
        let (z, tilt) = world.planar_deviation(m).unwrap();
        assert!(z == 0.0 && tilt < 1e-6, "left the plane at step {k}: z = {z} m, tilt = {tilt} rad");
    }
}

// ---------------------------------------------------------------------------------------------
// PD-held stance at the thesis's step

fn stands_for_60_s(mode: PdMode) {
    let (mut world, m, mut s) = stance(mode);
    let sk = world.skeleton(m).unwrap().clone();
    let (head, pelvis) = (sk.body_index("head").unwrap(), sk.body_index("pelvis").unwrap());
    let steps = (60.0 / world.settings().dt).round() as u64;
    for k in 0..steps {
        world.step().unwrap_or_else(|e| panic!("{mode:?}: {e}"));
        world.sense(&mut s).unwrap();
        assert!(s.all_finite(), "{mode:?}: non-finite sensors at step {k}");
        assert!(
            s.body_position[head][1] > 1.5,
            "{mode:?}: head at {} m at t = {} s",
            s.body_position[head][1],
            s.time
        );
        assert!(
            s.body_position[pelvis][1] > 0.9,
            "{mode:?}: pelvis at {} m at t = {} s",
            s.body_position[pelvis][1],
            s.time
        );
        let not_feet = s.contacts.iter().find(|c| sk.body(c.body).role != Role::Foot);
        assert!(not_feet.is_none(), "{mode:?}: {:?} touches at t = {} s", not_feet, s.time);
    }
    assert_eq!(s.support, Support::Both, "{mode:?}: both feet on the ground at the end");
    assert!(s.com[0].abs() < 0.1, "{mode:?}: the centre of mass crept to x = {} m", s.com[0]);
}

#[test]
fn pd_stance_stays_up_for_60_s_in_the_ode_style_mode() {
    stands_for_60_s(PdMode::OdeBrake);
}

#[test]
fn pd_stance_stays_up_for_60_s_with_implicit_springs() {
    stands_for_60_s(PdMode::ImplicitSpring);
}

#[test]
fn pd_stance_stays_up_for_60_s_with_stable_pd() {
    stands_for_60_s(PdMode::StablePd);
}

#[test]
fn explicit_pd_at_the_thesis_step_without_sub_steps_diverges() {
    // The counterpart of the three stances: G = 100 gains held over 0.05 s break the explicit bound
    // (kp·Δt²/I = 675 · 0.0025 / 0.0146 ≈ 116 ≫ 4 for a foot).
    let sk = humanoid(PdMode::Explicit, STANCE_GAIN);
    let mut world = World::new(WorldSettings::thesis()).unwrap();
    let m = world.add_model(&sk, Placement::OnGround { dx: 0.0 }).unwrap();
    world.commands_mut(m).unwrap().hold(&vec![0.0; sk.n_actuators()]).unwrap();
    let diverged = (0..200).any(|_| world.step().is_err());
    assert!(diverged, "explicit PD past its stability bound did not diverge");
}

// ---------------------------------------------------------------------------------------------
// Inter-thigh actuator

#[test]
fn inter_thigh_torque_leaves_angular_momentum_unchanged_in_free_fall() {
    let run = |balanced: bool| {
        let sk = humanoid(PdMode::Explicit, 10.0);
        let settings = WorldSettings { dt: 0.001, ground: None, ..WorldSettings::thesis() };
        let mut world = World::new(settings).unwrap();
        let m = world.add_model(&sk, Placement::Offset { dx: 0.0, dy: 10.0 }).unwrap();
        let it = sk.actuator_index("inter_thigh").unwrap();
        let (tl, tr) = (sk.body_index("thigh_l").unwrap(), sk.body_index("thigh_r").unwrap());
        world.commands_mut(m).unwrap().push(Signal::angle(it, 0.6)).unwrap();
        let mut s = Sensors::new(&world, m).unwrap();
        let (mut l_max, mut swing, mut scale) = (0.0f64, 0.0f64, 0.0f64);
        for _ in 0..1000 {
            if !balanced {
                // The same torque on the left thigh alone: no reaction, so L must change.
                world.sense(&mut s).unwrap();
                // A couple of +T on the right thigh cancels the actuator's −T there.
                let t = s.actuator_torque[it];
                let p = s.body_position[tr];
                world.apply_force(m, tr, [0.0, t], [p[0] + 1.0, p[1]]).unwrap();
                world.apply_force(m, tr, [0.0, -t], [p[0], p[1]]).unwrap();
            }
            world.step().unwrap();
            world.sense(&mut s).unwrap();
            let l = world.momentum(m).unwrap().angular;
            l_max = l_max.max(l.abs());
            swing = swing.max(s.actuator_angle[it].abs());
            // |I ω| of one thigh about its centre, a scale for L.
            scale = scale.max(0.15 * s.body_angular_velocity[tl].abs());
        }
        (l_max, swing, scale)
    };
    let (l_max, swing, scale) = run(true);
    assert!(swing > 0.3, "the thighs barely moved apart ({swing} rad)");
    assert!(l_max < 0.02 * scale, "angular momentum drifted to {l_max} kg·m²/s (thigh scale {scale})");
    // Control: forces that cancel the pair's reaction on the right thigh make L grow.
    let (l_unbalanced, _, _) = run(false);
    assert!(l_unbalanced > 10.0 * l_max, "the control did not change L ({l_unbalanced} vs {l_max})");
}

// ---------------------------------------------------------------------------------------------
// Determinism

fn trajectory(mode: PdMode) -> Vec<u64> {
    let (mut world, m, mut s) = stance(mode);
    let n = world.skeleton(m).unwrap().n_actuators();
    let mut bits = Vec::new();
    for k in 0..120 {
        let c = world.commands_mut(m).unwrap();
        c.clear();
        for a in 0..n {
            // A pose that changes every step, two signals on the first actuator.
            c.push(Signal::angle(a, 0.2 * ((k * (a + 1)) as f64 * 0.07).sin())).unwrap();
        }
        c.push(Signal { weight: 0.5, ..Signal::angle(0, -0.3) }).unwrap();
        world.step().unwrap();
        world.sense(&mut s).unwrap();
        bits.extend(s.body_position.iter().flatten().map(|x| x.to_bits()));
        bits.extend(s.joint_rate.iter().map(|x| x.to_bits()));
    }
    bits
}

#[test]
fn same_inputs_give_bit_identical_trajectories() {
    for mode in [PdMode::OdeBrake, PdMode::ImplicitSpring, PdMode::StablePd, PdMode::Explicit] {
        let (a, b) = (trajectory(mode), trajectory(mode));
        assert_eq!(a.len(), b.len());
        if let Some(i) = a.iter().zip(&b).position(|(x, y)| x != y) {
            panic!("{mode:?}: runs differ at value {i}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// The thrower's ball

#[test]
fn releasing_the_ball_hands_it_the_hands_velocity() {
    let sk = BuiltinSkeleton::Thrower.load();
    let sk = sk
        .with_actuation(Actuation {
            mode: PdMode::ImplicitSpring,
            gain_scale: STANCE_GAIN,
            ..*sk.actuation()
        })
        .unwrap();
    let mut world = World::new(WorldSettings { dt: 0.01, ..WorldSettings::thesis() }).unwrap();
    let m = world.add_model(&sk, Placement::OnGround { dx: 0.0 }).unwrap();
    let mut pose = vec![0.0; sk.n_actuators()];
    for name in ["shoulder_l", "shoulder_r"] {
        pose[sk.actuator_index(name).unwrap()] = 2.0; // swing both arms forward and up
    }
    world.commands_mut(m).unwrap().hold(&pose).unwrap();
    let (ball, fl) = (sk.body_index("ball").unwrap(), sk.body_index("forearm_l").unwrap());
    let mut s = Sensors::new(&world, m).unwrap();
    for _ in 0..25 {
        world.step().unwrap();
    }
    world.sense(&mut s).unwrap();
    // The left hand: the distal end of the forearm, 0.15 m below its centre in the body frame.
    let hand = body_point(&s, fl, [0.0, -0.15]);
    let v_hand = point_velocity(&s, fl, hand);
    let speed = v_hand[0].hypot(v_hand[1]);
    assert!(speed > 1.0, "the hands move too slowly to test ({speed} m/s)");
    let v_held = s.body_velocity[ball];
    let gap = (v_held[0] - v_hand[0]).hypot(v_held[1] - v_hand[1]);
    assert!(gap < 0.02 * speed, "held ball moves at {v_held:?}, hand at {v_hand:?}");

    world.release_weld(m, 0).unwrap();
    world.release_weld(m, 1).unwrap();
    assert!(!world.weld_holds(m, 0).unwrap());
    assert!(matches!(world.release_weld(m, 0), Err(BodyError::AlreadyReleased { .. })));
    world.step().unwrap();
    world.sense(&mut s).unwrap();
    // Free flight: the velocity at release plus one step of gravity, nothing else.
    let dt = world.settings().dt;
    let v_free = s.body_velocity[ball];
    let expected = [v_hand[0], v_hand[1] - 9.81 * dt];
    let err = (v_free[0] - expected[0]).hypot(v_free[1] - expected[1]);
    assert!(err < 0.02 * speed, "released ball at {v_free:?}, expected {expected:?}");
    // And it keeps flying ballistically while the arms move on.
    let v0 = v_free;
    for _ in 0..10 {
        world.step().unwrap();
    }
    world.sense(&mut s).unwrap();
    let v1 = s.body_velocity[ball];
    assert!((v1[0] - v0[0]).abs() < 1e-3 && (v1[1] - (v0[1] - 9.81 * 10.0 * dt)).abs() < 1e-3, "{v1:?}");
}

// ---------------------------------------------------------------------------------------------
// Skeleton files

fn replace_once(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "`{from}` not in the skeleton");
    text.replacen(from, to, 1)
}

fn line_of(text: &str, needle: &str) -> usize {
    text.lines().position(|l| l.contains(needle)).expect("needle") + 1
}

#[test]
fn a_malformed_skeleton_gets_an_error_naming_the_field_and_the_line() {
    let good = BuiltinSkeleton::Humanoid.ron();
    // A string where a number belongs.
    let bad = replace_once(good, "mass: 19.51", "mass: \"heavy\"");
    let e = Skeleton::from_ron_str(&bad).unwrap_err();
    assert_eq!(e.kind, SkeletonErrorKind::Syntax);
    assert_eq!(e.field, "bodies[2].mass", "{e}");
    assert_eq!(e.line, Some(line_of(&bad, "\"heavy\"")), "{e}");
    assert!(e.to_string().contains("bodies[2].mass") && e.to_string().contains("line"), "{e}");

    // An unknown body name in a joint.
    let bad = replace_once(good, "child: \"shank_r\"", "child: \"shin_r\"");
    let e = Skeleton::from_ron_str(&bad).unwrap_err();
    assert_eq!(e.kind, SkeletonErrorKind::Invalid);
    assert_eq!(e.field, "joints[7].child", "{e}");
    assert_eq!(e.line, Some(line_of(&bad, "shin_r")));
    assert!(e.message.contains("shin_r"));

    // A negative mass.
    let bad = replace_once(good, "mass: 4.16", "mass: -4.16");
    let e = Skeleton::from_ron_str(&bad).unwrap_err();
    assert_eq!((e.field.as_str(), e.line), ("bodies[5].mass", Some(line_of(&bad, "-4.16"))), "{e}");

    // A missing field: ron reports it at the end of the struct; we name the struct's field.
    let bad = replace_once(
        good,
        "kp: 6.75, kd: 0.225),\n        Actuator(name: \"hip_r\"",
        "kp: 6.75),\n        Actuator(name: \"hip_r\"",
    );
    let e = Skeleton::from_ron_str(&bad).unwrap_err();
    assert_eq!(e.field, "actuators[5].kd", "{e}");
    assert_eq!(e.line, Some(line_of(&bad, "\"ankle_l\", number: 6")), "{e}");

    // An unknown field, and a misspelt enum variant.
    let bad = replace_once(good, "role: Head", "rol: Head");
    let e = Skeleton::from_ron_str(&bad).unwrap_err();
    assert_eq!((e.field.as_str(), e.line), ("bodies[0].rol", Some(line_of(&bad, "rol: Head"))), "{e}");
    let bad = replace_once(
        good,
        "kind: Hinge, parent: \"pelvis\", child: \"abdomen\"",
        "kind: Hinj, parent: \"pelvis\", child: \"abdomen\"",
    );
    let e = Skeleton::from_ron_str(&bad).unwrap_err();
    assert_eq!((e.field.as_str(), e.line), ("joints[2].kind", Some(line_of(&bad, "Hinj"))), "{e}");

    // A cycle of joints, and a body hanging from two joints.
    let bad =
        replace_once(good, "parent: \"thorax\", child: \"head\"", "parent: \"thorax\", child: \"pelvis\"");
    let e = Skeleton::from_ron_str(&bad).unwrap_err();
    assert_eq!(e.kind, SkeletonErrorKind::Invalid);
    assert!(e.field.starts_with("joints["), "{e}");
    assert!(e.line.is_some(), "{e}");
}

#[test]
fn every_shipped_skeleton_parses() {
    for b in BuiltinSkeleton::ALL {
        Skeleton::from_ron_str(b.ron()).unwrap_or_else(|e| panic!("{}: {e}", b.file_name()));
    }
}

// ---------------------------------------------------------------------------------------------
// Explicit PD stability bound on a single hinge

fn single_hinge(mode: PdMode, kp: f64, kd: f64, dt: f64) -> bool {
    let text = format!(
        r#"Skeleton(name: "hinge", depth: 0.1,
          bodies: [
            Body(name: "base", shape: Box(width: 0.2, height: 0.2), mass: 1.0, centre: (0.0, 1.0), fixed: true),
            Body(name: "link", shape: Box(width: 0.1, height: 0.5), mass: 2.0, centre: (0.0, 0.75)),
          ],
          joints: [ Joint(name: "hinge", kind: Hinge, parent: "base", child: "link", anchor: (0.0, 1.0)) ],
          actuators: [ Actuator(name: "hinge", number: 1, drives: Joint("hinge"), kp: {kp}, kd: {kd}, max_torque: Some(1e9)) ],
          actuation: Actuation(mode: {mode:?}, gain_scale: 1.0, torque_limit_rad: 1.0, brake_rad_s: 0.0),
        )"#
    );
    let sk = Skeleton::from_ron_str(&text).unwrap();
    // One Rapier sub-step: the torque is then held over exactly one symplectic Euler step, the
    // integrator the bound is derived for (docs/body.md).
    let mut settings = WorldSettings { dt, gravity: 0.0, ground: None, ..WorldSettings::thesis() };
    settings.solver.iterations = 1;
    let mut world = World::new(settings).unwrap();
    let m = world.add_model(&sk, Placement::Offset { dx: 0.0, dy: 0.0 }).unwrap();
    world.commands_mut(m).unwrap().push(Signal::angle(0, 0.1)).unwrap();
    let mut s = Sensors::new(&world, m).unwrap();
    for _ in 0..400 {
        if world.step().is_err() {
            return false;
        }
        world.sense(&mut s).unwrap();
        if (s.joint_angle[0] - 0.1).abs() > 1.0 {
            return false;
        }
    }
    (s.joint_angle[0] - 0.1).abs() < 0.1
}

#[test]
fn explicit_pd_follows_its_stability_bound_on_a_single_hinge() {
    // Link: 2 kg, 0.1 × 0.5 m, hinged at its top: I = m (w² + h²)/12 + m (h/2)² = 0.1683 kg·m².
    let i = 2.0 * (0.01 + 0.25) / 12.0 + 2.0 * 0.0625;
    let dt = 0.01;
    let kd = 0.5;
    // Bound kp·Δt²/I + 2·kd·Δt/I < 4 → kp < (4 − 2 kd Δt / I) I / Δt².
    let kp_max = (4.0 - 2.0 * kd * dt / i) * i / (dt * dt);
    assert!(single_hinge(PdMode::Explicit, 0.9 * kp_max, kd, dt), "explicit PD unstable below its bound");
    assert!(!single_hinge(PdMode::Explicit, 1.1 * kp_max, kd, dt), "explicit PD stable above its bound");
    // The implicit spring holds far past it, whatever the damping.
    assert!(single_hinge(PdMode::ImplicitSpring, 100.0 * kp_max, kd, dt));
    assert!(single_hinge(PdMode::ImplicitSpring, 100.0 * kp_max, 100.0 * kp_max * dt, dt));
    // Stable PD holds far past it while kd ≥ 1.5·kp·Δt, and not below (docs/body.md derives the
    // condition kp·Δt² < (4 I + 2 kd Δt) / 3).
    assert!(single_hinge(PdMode::StablePd, 100.0 * kp_max, 2.0 * 100.0 * kp_max * dt, dt));
    assert!(!single_hinge(PdMode::StablePd, 100.0 * kp_max, 0.5 * 100.0 * kp_max * dt, dt));
}

// ---------------------------------------------------------------------------------------------
// Actuator signals

#[test]
fn weighted_signals_equal_one_signal_at_the_weighted_mean_in_implicit_modes() {
    // Eq. 5.1 without clamping is linear: weights 1 and 3 on targets 0.4 and −0.2 equal a single
    // target of 0.4·1/4 − 0.2·3/4 = −0.05.
    let run = |signals: &[(f64, f64)]| {
        let (mut world, m, mut s) = stance(PdMode::ImplicitSpring);
        let knee = world.skeleton(m).unwrap().actuator_index("knee_l").unwrap();
        for k in 0..40 {
            let c = world.commands_mut(m).unwrap();
            c.hold(&[0.0; 14]).unwrap();
            c.clear();
            for a in (0..14).filter(|&a| a != knee) {
                c.push(Signal::angle(a, 0.0)).unwrap();
            }
            for &(t, w) in signals {
                c.push(Signal { weight: w, ..Signal::angle(knee, t * (k as f64 / 40.0)) }).unwrap();
            }
            world.step().unwrap();
        }
        world.sense(&mut s).unwrap();
        s.joint_angle.clone()
    };
    let two = run(&[(0.4, 1.0), (-0.2, 3.0)]);
    let one = run(&[(-0.05, 1.0)]);
    for (a, b) in two.iter().zip(&one) {
        assert!((a - b).abs() < 1e-5, "{two:?}\nvs\n{one:?}");
    }
}

#[test]
fn no_torque_signals_leave_an_actuator_limp_and_world_targets_hold_world_angles() {
    // Zero gravity, no ground: a limp knee does not move; a world-frame target on the shoulder holds
    // the upper arm's world angle while the trunk is turned by the waist.
    let sk = humanoid(PdMode::ImplicitSpring, 10.0);
    let mut world =
        World::new(WorldSettings { dt: 0.01, gravity: 0.0, ground: None, ..WorldSettings::thesis() })
            .unwrap();
    let m = world.add_model(&sk, Placement::Offset { dx: 0.0, dy: 0.0 }).unwrap();
    let (knee, waist, shoulder) = (
        sk.actuator_index("knee_l").unwrap(),
        sk.actuator_index("waist").unwrap(),
        sk.actuator_index("shoulder_l").unwrap(),
    );
    let c = world.commands_mut(m).unwrap();
    c.push(Signal { target: Target::NoTorque, ..Signal::angle(knee, 1.0) }).unwrap();
    c.push(Signal::angle(waist, 0.5)).unwrap();
    c.push(Signal { frame: TargetFrame::World, ..Signal::angle(shoulder, 0.3) }).unwrap();
    let mut s = Sensors::new(&world, m).unwrap();
    for _ in 0..300 {
        world.step().unwrap();
    }
    world.sense(&mut s).unwrap();
    assert_eq!(s.actuator_torque[knee], 0.0, "a knee with only NoTorque signals applies no torque");
    let arm = sk.body_index("upper_arm_l").unwrap();
    assert!(s.joint_angle[sk.joint_index("waist").unwrap()] > 0.3, "the waist turned the trunk");
    assert!((s.body_angle[arm] - 0.3).abs() < 0.05, "upper arm at {} rad in the world", s.body_angle[arm]);
}

// ---------------------------------------------------------------------------------------------
// Torso signals: SIMBICON's stance hip

/// Zero gravity, no ground, Δt = 0.01 s in one physics step, the figure at rest in its initial pose.
fn floating_humanoid(mode: PdMode) -> (World, usize, Skeleton) {
    let sk = humanoid(mode, 10.0);
    let mut settings = WorldSettings { dt: 0.01, gravity: 0.0, ground: None, ..WorldSettings::thesis() };
    settings.solver.iterations = 1;
    let mut world = World::new(settings).unwrap();
    let m = world.add_model(&sk, Placement::Offset { dx: 0.0, dy: 0.0 }).unwrap();
    (world, m, sk)
}

/// The right hip holds the pelvis at `angle` in the world, sharing the work with the left hip, whose
/// joint angle target is `swing_target`.
fn torso_signals(world: &mut World, m: usize, sk: &Skeleton, angle: f64, swing_target: f64) {
    let (hip_l, hip_r) = (sk.actuator_index("hip_l").unwrap(), sk.actuator_index("hip_r").unwrap());
    let c = world.commands_mut(m).unwrap();
    c.clear();
    c.push(Signal { target: Target::Torso { angle, swing: hip_l }, ..Signal::angle(hip_r, 0.0) }).unwrap();
    c.push(Signal::angle(hip_l, swing_target)).unwrap();
}

#[test]
fn the_stance_hip_applies_minus_the_torso_and_the_swing_torques() {
    // At rest in the initial pose (every angle and rate 0): the left hip asks 0.2 rad, τ_swing =
    // kp·0.2; the right hip holds the pelvis at 0.1 rad in the world, τ_torso = kp·0.1, so it applies
    // τ_stance = −τ_torso − τ_swing = −0.3 kp — in every mode, since a torso signal is explicit.
    for mode in [PdMode::Explicit, PdMode::ImplicitSpring, PdMode::StablePd, PdMode::ImplicitMotor] {
        let (mut world, m, sk) = floating_humanoid(mode);
        let (hip_l, hip_r) = (sk.actuator_index("hip_l").unwrap(), sk.actuator_index("hip_r").unwrap());
        torso_signals(&mut world, m, &sk, 0.1, 0.2);
        world.step().unwrap();
        let mut s = Sensors::new(&world, m).unwrap();
        world.sense(&mut s).unwrap();
        let kp = sk.actuators()[hip_r].kp;
        assert_eq!(kp, sk.actuators()[hip_l].kp);
        assert!(
            (s.actuator_torque[hip_l] - 0.2 * kp).abs() < 1e-9,
            "{mode:?}: swing {}",
            s.actuator_torque[hip_l]
        );
        let stance = s.actuator_torque[hip_r];
        assert!(
            (stance + 0.3 * kp).abs() < 1e-9,
            "{mode:?}: stance hip {stance} N·m, expected {}",
            -0.3 * kp
        );
        // Each hip acts −τ on the pelvis: together they turn it towards 0.1 rad.
        let pelvis = sk.body_index("pelvis").unwrap();
        assert!(s.body_angle[pelvis] > 0.0, "{mode:?}: the pelvis turned {} rad", s.body_angle[pelvis]);
    }
    // Clamped like every signal (spec §4.4): a target 10 rad away asks more than the cap.
    let (mut world, m, sk) = floating_humanoid(PdMode::ImplicitSpring);
    torso_signals(&mut world, m, &sk, 10.0, 0.0);
    world.step().unwrap();
    let mut s = Sensors::new(&world, m).unwrap();
    world.sense(&mut s).unwrap();
    let hip_r = sk.actuator_index("hip_r").unwrap();
    assert_eq!(s.actuator_torque[hip_r], -sk.actuators()[hip_r].max_torque);
}

#[test]
fn a_torso_signal_turns_the_pelvis_to_its_world_angle() {
    // Floating free, the hips can only hold the pelvis by turning the legs the other way.
    let (mut world, m, sk) = floating_humanoid(PdMode::ImplicitSpring);
    let pelvis = sk.body_index("pelvis").unwrap();
    let mut s = Sensors::new(&world, m).unwrap();
    torso_signals(&mut world, m, &sk, 0.2, 0.0);
    for _ in 0..300 {
        world.step().unwrap();
    }
    world.sense(&mut s).unwrap();
    assert!((s.body_angle[pelvis] - 0.2).abs() < 0.02, "pelvis at {} rad, target 0.2", s.body_angle[pelvis]);
    // The other way round too.
    torso_signals(&mut world, m, &sk, -0.3, 0.0);
    for _ in 0..300 {
        world.step().unwrap();
    }
    world.sense(&mut s).unwrap();
    assert!((s.body_angle[pelvis] + 0.3).abs() < 0.02, "pelvis at {} rad, target −0.3", s.body_angle[pelvis]);
}

#[test]
fn the_simbicon_humanoid_is_the_thesis_humanoid_with_simbicon_gains() {
    let (h, sb) = (BuiltinSkeleton::Humanoid.load(), BuiltinSkeleton::HumanoidSimbicon.load());
    assert_eq!(h.desc().bodies, sb.desc().bodies);
    assert_eq!(h.desc().joints, sb.desc().joints);
    assert_eq!(h.desc().groups, sb.desc().groups);
    assert_eq!(h.n_actuators(), sb.n_actuators());
    for (a, b) in h.actuators().iter().zip(sb.actuators()) {
        assert_eq!((&a.name, a.drive), (&b.name, b.drive));
        assert_eq!((b.kp, b.kd, b.max_torque), (300.0, 30.0, 300.0), "{}", b.name);
    }
    assert_eq!(sb.actuation().mode, PdMode::ImplicitSpring);
}

// ---------------------------------------------------------------------------------------------
// Sensors

#[test]
fn sensors_read_contacts_support_and_the_catalogue() {
    let (mut world, m, mut s) = stance(PdMode::ImplicitSpring);
    for _ in 0..20 {
        world.step().unwrap();
    }
    world.sense(&mut s).unwrap();
    let sk = world.skeleton(m).unwrap();
    let [fl, fr] = s.layout.feet;
    assert!(s.on_ground[fl.unwrap()] && s.on_ground[fr.unwrap()]);
    assert!(s.touches(fl.unwrap(), Touch::Ground));
    assert_eq!(s.support, Support::Both);
    // Feet centres are 0.06 m ahead of the ankles; the centre of mass is near x = 0.
    let over = s.com_over_support.unwrap();
    let feet_x = 0.5 * (s.body_position[fl.unwrap()][0] + s.body_position[fr.unwrap()][0]);
    assert!((over - (s.com[0] - feet_x)).abs() < 1e-12);
    assert!(over < -0.03, "the centre of mass is behind the feet's centres ({over} m)");
    assert!((s.mass - 88.28).abs() < 1e-9);
    assert_eq!(catalogue::foot_up(&s, 0), 0.0);
    assert_eq!(catalogue::both_feet_down(&s), 1.0);
    assert_eq!(catalogue::cog_low(&s, 2.0), 1.0);
    assert_eq!(catalogue::cog_low(&s, 0.5), 0.0);
    assert_eq!(catalogue::cog_ahead(&s, 0, -0.25), 1.0);
    assert_eq!(catalogue::cog_ahead(&s, 0, 0.5), 0.0);
    assert_eq!(catalogue::landing(&s, 0, 10.0, catalogue::LandCombine::Or), 1.0);
    assert_eq!(catalogue::landing(&s, 0, 10.0, catalogue::LandCombine::And), 0.0);
    assert_eq!(catalogue::falling_forward(&s, 0.1), 0.0);
    assert_eq!(catalogue::falling_backward(&s, 0.1), 0.0);
    assert_eq!(catalogue::flip_brake(&s, 0.1), 0.0);
    assert_eq!(catalogue::trunk_angle(&s, sk.joint_index("waist").unwrap()), s.joint_angle[2]);
    // The ankles stand 0.25 − 0.15 m above the ground, 0.06 m behind the feet's centres.
    for side in 0..2 {
        let ankle = catalogue::ankle_position(&s, side).unwrap();
        assert!(ankle[0].abs() < 5e-3 && (ankle[1] - 0.10).abs() < 5e-3, "ankle {side} at {ankle:?}");
        let d = catalogue::com_ahead_of_ankle(&s, side);
        assert!((d - (s.com[0] - ankle[0])).abs() < 1e-12);
        assert!((d - catalogue::com_offset(&s, side) - 0.06).abs() < 5e-3, "{d}");
        assert_eq!(catalogue::foot_down(&s, side), 1.0);
    }
    // Standing still, the capture point is the centre of mass, between the ankles' margins; moving at
    // 1 m/s it lies v/ω = 1/√(g/h) ahead or behind (h ≈ 1 m: about 0.3 m), beyond the feet.
    let cp = catalogue::capture_point(&s).unwrap();
    assert!((cp - s.com[0]).abs() < 0.01, "capture point {cp} m, centre of mass {} m", s.com[0]);
    assert_eq!(catalogue::capture_outside(&s, 0.05), 0.0);
    let height = s.com[1] - s.body_position[fl.unwrap()][1].min(s.body_position[fr.unwrap()][1]);
    for v in [-1.0, 1.0] {
        let mut moving = s.clone();
        moving.com_velocity[0] = v;
        let expected = s.com[0] + v * (height / catalogue::CAPTURE_GRAVITY).sqrt();
        assert!((catalogue::capture_point(&moving).unwrap() - expected).abs() < 1e-12);
        assert!((expected - s.com[0]).abs() > 0.25, "{expected}");
        assert_eq!(catalogue::capture_outside(&moving, 0.05), 1.0, "at {v} m/s");
        assert_eq!(catalogue::capture_outside(&moving, 0.5), 0.0, "at {v} m/s, 0.5 m margin");
    }
}

#[test]
fn delayed_sensors_return_the_reading_from_n_steps_ago() {
    let (mut world, _m, mut s) = stance(PdMode::ImplicitSpring);
    let mut delay = SensorDelay::new(&s, 3);
    assert!(delay.delayed().is_none());
    let mut history = Vec::new();
    for k in 0..8usize {
        world.step().unwrap();
        world.sense(&mut s).unwrap();
        delay.push(&s);
        history.push(s.clone());
        let expected = &history[k.saturating_sub(3)];
        assert_eq!(delay.delayed().unwrap(), expected, "at push {k}");
    }
}

#[test]
fn the_pusher_and_the_acrobat_collide_with_each_other_but_not_themselves() {
    // The backflip pair: two models facing each other, the acrobat pushed into the pusher.
    let text = include_str!("../../../assets/scenes/backflip-pair.ron");
    let scene = BodyScene::from_ron_str(text).unwrap();
    let skeletons: Vec<_> =
        scene.models.iter().map(|e| BodyScene::builtin_skeleton(&e.skeleton).unwrap()).collect();
    let mut world = scene.build(&skeletons).unwrap();
    assert_eq!(world.n_models(), 2);
    let (acrobat, pusher) = (0, 1);
    let n_bodies: usize = (0..2).map(|m| world.skeleton(m).unwrap().n_bodies()).sum();
    assert_eq!(n_bodies, 14 + 16);
    let mut s = Sensors::new(&world, acrobat).unwrap();
    let head = world.skeleton(acrobat).unwrap().body_index("head").unwrap();
    let mut met = false;
    for _ in 0..60 {
        world.sense(&mut s).unwrap();
        let p = s.body_position[head];
        world.apply_force(acrobat, head, [300.0, 0.0], p).unwrap();
        world.step().unwrap();
        world.sense(&mut s).unwrap();
        met |= s.contacts.iter().any(|c| matches!(c.other, Touch::Body { model, .. } if model == pusher));
        assert!(
            !s.contacts.iter().any(|c| matches!(c.other, Touch::Body { model, .. } if model == acrobat)),
            "the acrobat touched itself"
        );
    }
    assert!(met, "the acrobat never touched the pusher");
}

#[test]
fn a_scene_built_in_code_without_a_frame_rate_says_so() {
    // A loaded scene names its frame rate; one filled in code may not, and must not run as if it had
    // asked for a frame at every step.
    let text = include_str!("../../../assets/scenes/backflip-pair.ron");
    let mut scene = BodyScene::from_ron_str(text).unwrap();
    let rate = scene.frame_rate_hz.or(scene.frame_interval.map(|i| 1.0 / i)).unwrap();
    assert!((scene.frame_interval_s().unwrap() - 1.0 / rate).abs() < 1e-15);
    scene.frame_rate_hz = None;
    scene.frame_interval = None;
    let e = scene.frame_interval_s().unwrap_err().to_string();
    assert!(e.contains("frame_rate_hz"), "{e}");
    scene.frame_rate_hz = Some(30.0);
    scene.frame_interval = Some(0.1);
    let e = scene.frame_interval_s().unwrap_err().to_string();
    assert!(e.contains("not both"), "{e}");
    scene.frame_interval = None;
    scene.frame_rate_hz = Some(-1.0);
    assert!(scene.frame_interval_s().is_err());
}

// ---------------------------------------------------------------------------------------------
// Terrain

/// The humanoid holding its stance for `steps` control steps with its feet at `dx` on `relief`: how far
/// its feet's centres end up above the ground under them, and whether the feet, and only they, touch it.
fn stand_on(relief: anima_body::Relief, dx: f64, steps: usize) -> (f64, bool) {
    let mode = PdMode::ImplicitSpring;
    let sk = humanoid(mode, STANCE_GAIN);
    let mut settings = stance_settings(mode);
    let ground = anima_body::Ground { relief, ..settings.ground.unwrap() };
    settings.ground = Some(ground);
    let mut world = World::new(settings).unwrap();
    let m = world.add_model(&sk, Placement::OnGround { dx }).unwrap();
    world.commands_mut(m).unwrap().hold(&vec![0.0; sk.n_actuators()]).unwrap();
    let mut s = Sensors::new(&world, m).unwrap();
    for _ in 0..steps {
        world.step().unwrap();
    }
    world.sense(&mut s).unwrap();
    let feet: Vec<usize> = s.layout.feet.iter().flatten().copied().collect();
    let only_feet = s.on_ground.iter().enumerate().all(|(b, &g)| !g || feet.contains(&b));
    let lowest_gap = feet
        .iter()
        .map(|&f| s.body_position[f][1] - ground.height_at(s.body_position[f][0]))
        .fold(f64::INFINITY, f64::min);
    (lowest_gap, only_feet && feet.iter().all(|&f| s.on_ground[f]))
}

#[test]
fn a_figure_stands_where_the_ground_is_on_steps_and_slopes() {
    use anima_body::Relief;
    let flat = stand_on(Relief::Flat, 0.0, 40);
    assert!(flat.1, "standing on the flat ground");
    // On the first step of a flight 5 cm up (and one down) beginning 1 m behind it, for 2 s: its feet
    // rest on the ground under them as they do on the flat.
    for relief in [
        Relief::Stairs { from_x: -1.0, rise: 0.05, run: 2.0, count: 3 },
        Relief::Stairs { from_x: -1.0, rise: -0.05, run: 2.0, count: 3 },
    ] {
        let (gap, feet_only) = stand_on(relief, 0.0, 40);
        assert!(feet_only, "{relief:?}: only the feet touch the ground");
        assert!(
            (gap - flat.0).abs() < 1e-3,
            "{relief:?}: feet {gap} m above the ground, {} on the flat",
            flat.0
        );
    }
    // On slopes, for 0.2 s: a figure holding its upright pose leans with its feet and tips over
    // backwards within 2 s even at 2°, so only the first moments show where the ground is. Within the
    // rise of the slope under half a foot.
    for degrees in [5.0, -5.0, 10.0] {
        let relief = Relief::Slope { from_x: -3.0, degrees };
        let (gap, feet_only) = stand_on(relief, 0.0, 4);
        let tolerance = 0.15 * f64::tan(f64::to_radians(degrees)).abs() + 1e-3;
        assert!(feet_only, "{relief:?}: only the feet touch the ground");
        assert!(
            (gap - flat.0).abs() < tolerance,
            "{relief:?}: feet {gap} m above the ground, {} on the flat",
            flat.0
        );
    }
}

#[test]
fn the_ground_height_follows_its_relief() {
    use anima_body::{Ground, Relief};
    let g = |relief| Ground { height: 0.5, friction: 1.0, relief };
    let slope = g(Relief::Slope { from_x: 1.0, degrees: 45.0 });
    assert_eq!(slope.height_at(0.0), 0.5);
    assert!((slope.height_at(3.0) - 2.5).abs() < 1e-12);
    let down = g(Relief::Slope { from_x: 1.0, degrees: -45.0 });
    assert!((down.height_at(3.0) + 1.5).abs() < 1e-12);
    let stairs = g(Relief::Stairs { from_x: 1.0, rise: 0.1, run: 0.5, count: 3 });
    let h: Vec<f64> = [0.9, 1.0, 1.4, 1.5, 2.4, 9.0].iter().map(|&x| stairs.height_at(x)).collect();
    let expected = [0.5, 0.6, 0.6, 0.7, 0.8, 0.8];
    assert!(h.iter().zip(expected).all(|(a, b)| (a - b).abs() < 1e-12), "{h:?}");
    // Its inclination: the slope's angle past its start, 0 before it, on the flat and on stairs' treads.
    let quarter = std::f64::consts::FRAC_PI_4;
    assert_eq!((slope.slope_at(0.0), slope.slope_at(3.0), down.slope_at(3.0)), (0.0, quarter, -quarter));
    assert!([0.9, 1.2, 9.0].iter().all(|&x| stairs.slope_at(x) == 0.0));
    assert_eq!(g(Relief::Flat).slope_at(5.0), 0.0);
    // A relief the world cannot build is refused.
    let steep = WorldSettings {
        ground: Some(g(Relief::Slope { from_x: 0.0, degrees: 75.0 })),
        ..WorldSettings::thesis()
    };
    assert!(World::new(steep).is_err());
}

#[test]
fn the_sensors_read_the_inclination_of_the_ground_under_the_centre_of_mass() {
    use anima_body::Relief;
    let mode = PdMode::ImplicitSpring;
    let sk = humanoid(mode, STANCE_GAIN);
    for (relief, expected) in [
        (Relief::Slope { from_x: -3.0, degrees: 10.0 }, 10f64.to_radians()),
        (Relief::Slope { from_x: -3.0, degrees: -5.0 }, -(5f64.to_radians())),
        (Relief::Slope { from_x: 3.0, degrees: 10.0 }, 0.0),
        (Relief::Stairs { from_x: -1.0, rise: 0.05, run: 2.0, count: 3 }, 0.0),
    ] {
        let mut settings = stance_settings(mode);
        settings.ground = Some(anima_body::Ground { relief, ..settings.ground.unwrap() });
        let mut world = World::new(settings).unwrap();
        let m = world.add_model(&sk, Placement::OnGround { dx: 0.0 }).unwrap();
        let mut s = Sensors::new(&world, m).unwrap();
        world.sense(&mut s).unwrap();
        assert_eq!(s.ground_slope, expected, "{relief:?}");
    }
}

// ---------------------------------------------------------------------------------------------
// Limits

/// A chain of `bodies` bodies `b0…` (one a line after the `bodies: [` line, 2), jointed in order by
/// `joints` hinges `j1…` listed from the chain's end, with an actuator on each.
fn chain(bodies: usize, joints: usize) -> String {
    let mut text = String::from("Skeleton(name: \"chain\", depth: 0.1,\n  bodies: [\n");
    for i in 0..bodies {
        text.push_str(&format!(
            "    Body(name: \"b{i}\", shape: Box(width: 0.1, height: 0.1), mass: 1.0, centre: (0.0, {i}.0)),\n"
        ));
    }
    text.push_str("  ],\n  joints: [\n");
    for j in (1..=joints).rev() {
        let (p, c) = (j - 1, j);
        text.push_str(&format!(
            "    Joint(name: \"j{j}\", kind: Hinge, parent: \"b{p}\", child: \"b{c}\", anchor: (0.0, {j}.0)),\n"
        ));
    }
    text.push_str("  ],\n  actuators: [\n");
    for j in 1..=joints {
        text.push_str(&format!(
            "    Actuator(name: \"a{j}\", number: {j}, drives: Joint(\"j{j}\"), kp: 1.0, kd: 0.1),\n"
        ));
    }
    text.push_str(
        "  ],\n  actuation: Actuation(mode: Explicit, gain_scale: 1.0, torque_limit_rad: 1.0, brake_rad_s: 0.0),\n)\n",
    );
    text
}

/// More bodies or joints than anima's limit are refused at their list's line before anything is built
/// for them; at the limit the checks are linear (issue #40).
#[test]
fn bodies_and_joints_above_the_limit_are_refused_and_checks_are_linear() {
    use anima_format::limits::MAX_BODIES;
    let e = Skeleton::from_ron_str(&chain(MAX_BODIES + 1, 1)).unwrap_err();
    assert_eq!((e.kind, e.field.as_str(), e.line), (SkeletonErrorKind::Invalid, "bodies", Some(2)), "{e}");
    assert!(e.message.contains("at most 1000 bodies"), "{e}");
    let text = chain(MAX_BODIES, MAX_BODIES + 1);
    let e = Skeleton::from_ron_str(&text).unwrap_err();
    assert_eq!((e.field.as_str(), e.line), ("joints", Some(line_of(&text, "joints: ["))), "{e}");
    assert!(e.message.contains("at most 1000 joints"), "{e}");

    let start = std::time::Instant::now();
    let text = chain(MAX_BODIES, MAX_BODIES - 1);
    let sk = Skeleton::from_ron_str(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        (sk.n_bodies(), sk.n_joints(), sk.n_actuators()),
        (MAX_BODIES, MAX_BODIES - 1, MAX_BODIES - 1)
    );
    // Breadth first from the root, though the joints are listed from the chain's end.
    assert!(sk.tree_order().iter().copied().eq(0..MAX_BODIES));
    assert_eq!(sk.actuator_index("a999"), Some(MAX_BODIES - 2));
    // A duplicate at the end is still found, at its line.
    let last = MAX_BODIES - 1;
    let bad = replace_once(&text, &format!("name: \"b{last}\""), "name: \"b0\"");
    let e = Skeleton::from_ron_str(&bad).unwrap_err();
    assert_eq!((e.field.as_str(), e.line), (format!("bodies[{last}].name").as_str(), Some(3 + last)), "{e}");
    let bad = replace_once(&text, &format!("number: {last}"), "number: 1");
    let e = Skeleton::from_ron_str(&bad).unwrap_err();
    assert!(e.field == format!("actuators[{}].number", last - 1) && e.message.contains("also `a1`'s"), "{e}");
    let took = start.elapsed();
    assert!(took.as_secs_f64() < 10.0, "{took:?}");
}
