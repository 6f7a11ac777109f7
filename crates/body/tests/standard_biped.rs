//! The standard biped of the shared benchmark scenes (issue 8, part 3): the skeleton as defined
//! (7 bodies, 6 PD hinges, 28 kg, feet alone colliding) stands under explicit PD at Δt = 1 ms.

use anima_body::{BodyScene, PdMode, Role, Sensors, Skeleton, Touch, World};

const SKELETON: &str = include_str!("../../../assets/skeletons/standard-biped.ron");
const SCENE: &str = include_str!("../../../assets/scenes/standard-biped.ron");

/// The scene's world with the biped holding its initial pose (or limp), and the torso's index.
fn biped(limp: bool) -> (World, Sensors, usize) {
    let sk = Skeleton::from_ron_str(SKELETON).expect("valid skeleton");
    let mut scene = BodyScene::from_ron_str(SCENE).expect("valid scene");
    if limp {
        scene.models[0].pose = anima_body::Pose::Limp;
    }
    let world = scene.build(&[sk]).expect("builds");
    let sensors = Sensors::new(&world, 0).expect("model 0");
    let torso = world.skeleton(0).unwrap().body_index("torso").unwrap();
    (world, sensors, torso)
}

/// Hip (torso base, 0.25 m below the torso's centre) height and torso pitch.
fn hip(s: &Sensors, torso: usize) -> (f64, f64) {
    let th = s.body_angle[torso];
    (s.body_position[torso][1] - 0.25 * th.cos(), th)
}

#[test]
fn the_standard_biped_has_the_defined_bodies_joints_and_mass() {
    let sk = Skeleton::from_ron_str(SKELETON).unwrap();
    assert_eq!((sk.n_bodies(), sk.n_joints(), sk.n_actuators()), (7, 6, 6));
    assert!((sk.total_mass() - 28.0).abs() < 1e-12, "10 + 2·5 + 2·3 + 2·1 kg, found {}", sk.total_mass());
    assert_eq!(sk.roots().len(), 1, "one tree rooted at the torso (planar root: x, y, pitch)");
    assert_eq!(sk.body(sk.roots()[0]).name, "torso");
    assert_eq!(sk.actuation().mode, PdMode::Explicit);
    for a in sk.actuators() {
        assert_eq!((a.kp, a.kd, a.max_torque), (1000.0, 10.0, 1000.0), "{}", a.name);
    }
    for (name, len) in [("torso", 0.5), ("thigh_l", 0.45), ("shin_r", 0.45), ("foot_l", 0.2)] {
        let b = sk.body(sk.body_index(name).unwrap());
        let anima_body::Shape::Box { width, height } = b.shape else { panic!("{name} is a box") };
        assert_eq!(if b.role == Role::Foot { width } else { height }, len, "{name}");
    }
    // Feet alone collide: no body pair of the figure touches, and only the feet's group the ground.
    for i in 0..sk.n_bodies() {
        for j in 0..sk.n_bodies() {
            assert!(i == j || !sk.bodies_collide(i, j), "{} – {}", sk.body(i).name, sk.body(j).name);
        }
        let g = &sk.groups()[sk.body_group(i)];
        assert_eq!(g.ground, sk.body(i).role == Role::Foot, "{}", sk.body(i).name);
    }
}

#[test]
fn the_standard_biped_stands_under_explicit_pd_at_one_millisecond() {
    let (mut world, mut s, torso) = biped(false);
    world.sense(&mut s).unwrap();
    let (h0, p0) = hip(&s, torso);
    assert!((h0 - 0.95).abs() < 1e-6 && p0.abs() < 1e-9, "starts upright, hips at 0.95 m: {h0}, {p0}");
    let (mut min_h, mut max_p) = (h0, 0.0_f64);
    for _ in 0..2500 {
        world.step().expect("finite");
        world.sense(&mut s).unwrap();
        assert!(s.all_finite());
        let (h, p) = hip(&s, torso);
        min_h = min_h.min(h);
        max_p = max_p.max(p.abs());
        for c in &s.contacts {
            assert!(c.other != Touch::Ground || s.layout.feet.contains(&Some(c.body)), "only feet touch");
        }
    }
    assert!(min_h > 0.98 * h0, "hips sagged to {min_h} m from {h0} m");
    assert!(max_p < 0.02, "torso pitched {max_p} rad");
    assert!(s.joint_angle.iter().all(|q| q.abs() < 0.01), "joints held near 0: {:?}", s.joint_angle);
    for foot in s.layout.feet {
        assert!(s.touches(foot.expect("two feet"), Touch::Ground), "both feet stay down");
    }
}

#[test]
fn the_limp_biped_falls_so_the_standing_check_can_fail() {
    let (mut world, mut s, torso) = biped(true);
    world.sense(&mut s).unwrap();
    let (h0, _) = hip(&s, torso);
    for _ in 0..2500 {
        world.step().expect("finite");
    }
    world.sense(&mut s).unwrap();
    let (h, _) = hip(&s, torso);
    assert!(h < 0.98 * h0, "a limp biped cannot keep its hips at {h} m of {h0} m");
}
