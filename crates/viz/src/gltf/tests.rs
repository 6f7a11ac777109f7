use ::gltf::animation::util::ReadOutputs;
use anima_geom::box_mesh;

use super::*;

const UPS: [UpAxis; 6] =
    [UpAxis::PlusX, UpAxis::MinusX, UpAxis::PlusY, UpAxis::MinusY, UpAxis::PlusZ, UpAxis::MinusZ];

#[test]
fn each_up_axis_becomes_plus_y_by_a_rotation() {
    for up in UPS {
        let axis = match up {
            UpAxis::PlusX => DVec3::X,
            UpAxis::MinusX => -DVec3::X,
            UpAxis::PlusY => DVec3::Y,
            UpAxis::MinusY => -DVec3::Y,
            UpAxis::PlusZ => DVec3::Z,
            UpAxis::MinusZ => -DVec3::Z,
        };
        let r = |v: DVec3| DVec3::from_array(up.to_gltf(v.to_array()));
        assert_eq!(r(axis), DVec3::Y, "{up:?}");
        assert_eq!(UpAxis::against(-9.81 * axis, UpAxis::PlusY), up);
        // A rotation keeps cross products (a reflection would flip them, and every triangle's winding).
        let (a, b) = (DVec3::new(0.3, -1.2, 2.5), DVec3::new(-0.7, 0.4, 1.1));
        assert_eq!(r(a.cross(b)), r(a).cross(r(b)), "{up:?}");
        assert_eq!(up.from_gltf(up.to_gltf(a.to_array())), a.to_array(), "{up:?}");
        // The quaternion of a rotation about an axis turns into one about the turned axis.
        let q = up.rotation_to_gltf(DQuat::from_axis_angle(a.normalize(), 0.7));
        assert!((q * r(b) - r(DQuat::from_axis_angle(a.normalize(), 0.7) * b)).length() < 1e-12);
    }
    assert_eq!(UpAxis::against(DVec3::ZERO, UpAxis::PlusZ), UpAxis::PlusZ);
    assert_eq!(UpAxis::against(DVec3::new(0.1, -9.8, 0.3), UpAxis::PlusZ), UpAxis::PlusY);
}

/// A strip of two triangles falling and stretching, a box beside it, a remeshed square that gains a
/// vertex, and a two-link arm swinging in the x–y plane.
fn sample(up: UpAxis) -> Animation {
    let mut anim = Animation::new(up);
    anim.statics.push(StaticMesh::new("box", box_mesh(DVec3::splat(-1.0), DVec3::ZERO), [150, 150, 160]));
    let mut cloth = DeformingMesh::new("cloth", 4, vec![[0, 1, 2], [0, 2, 3]], [200, 70, 70]).unwrap();
    for k in 0..4 {
        let s = 1.0 + 0.1 * k as f64;
        let z = 2.0 - 0.05 * (k * k) as f64;
        let x = [
            DVec3::new(0.0, 0.0, z),
            DVec3::new(s, 0.0, z),
            DVec3::new(s, s, z - 0.3),
            DVec3::new(0.0, s, z),
        ];
        cloth.push_frame(k as f64 / 30.0, &x).unwrap();
    }
    anim.deforming.push(cloth);
    let mut remeshed = RemeshedMesh::new("adaptive", [200, 70, 70]);
    let square = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    remeshed.push_frame(0.0, &square, &[[0, 1, 2], [0, 2, 3]]).unwrap();
    let mut five = square.to_vec();
    five.push(DVec3::new(0.5, 0.5, 0.1));
    remeshed.push_frame(0.1, &five, &[[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]).unwrap();
    remeshed.push_frame(0.2, &five, &[[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]]).unwrap();
    anim.remeshed.push(remeshed);
    let link = |name: &str, parent| Link {
        name: name.into(),
        parent,
        shape: box_mesh(DVec3::new(-0.25, -0.05, -0.05), DVec3::new(0.25, 0.05, 0.05)),
        colour: [60, 170, 60],
    };
    let mut arm = Figure::new("arm", vec![link("upper", None), link("fore", Some(0))]).unwrap();
    for k in 0..5 {
        let (a, b) = (0.3 * k as f64, -0.5 + 0.8 * k as f64);
        let elbow = DVec3::new(0.5 * a.cos(), 1.0 + 0.5 * a.sin(), 0.0);
        let upper = Pose::planar([0.25 * a.cos(), 1.0 + 0.25 * a.sin()], a);
        let fore = Pose::planar([elbow.x + 0.25 * (a + b).cos(), elbow.y + 0.25 * (a + b).sin()], a + b);
        arm.push_frame(0.05 * k as f64, &[upper, fore]).unwrap();
    }
    anim.figures.push(arm);
    anim
}

fn glb(anim: &Animation) -> Vec<u8> {
    let mut bytes = Vec::new();
    anim.write_glb(&mut bytes).unwrap();
    bytes
}

#[test]
fn a_written_file_reads_back_frame_by_frame() {
    for up in [UpAxis::PlusZ, UpAxis::PlusY, UpAxis::MinusX] {
        let anim = sample(up);
        let bytes = glb(&anim);
        let file = ::gltf::Gltf::from_slice(&bytes).unwrap();
        let blob = file.blob.as_deref().unwrap();
        // The deforming mesh: base plus target k − 1 is frame k, in the run's axes, to f32 rounding.
        let cloth = file.meshes().find(|m| m.name() == Some("cloth")).unwrap();
        let prim = cloth.primitives().next().unwrap();
        let reader = prim.reader(|_| Some(blob));
        let base: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        let targets: Vec<Vec<[f32; 3]>> =
            reader.read_morph_targets().map(|(p, _, _)| p.unwrap().collect()).collect();
        let d = &anim.deforming[0];
        assert_eq!(targets.len(), d.n_frames() - 1);
        for k in 0..d.n_frames() {
            for (i, want) in d.frame(k).iter().enumerate() {
                let got = [0, 1, 2].map(|c| {
                    f64::from(base[i][c]) + if k == 0 { 0.0 } else { f64::from(targets[k - 1][i][c]) }
                });
                let got = up.from_gltf(got);
                for c in 0..3 {
                    let err = (got[c] - f64::from(want[c])).abs();
                    assert!(
                        err <= 4.0 * f64::from(f32::EPSILON),
                        "{up:?} frame {k} vertex {i}: {got:?} ≠ {want:?}"
                    );
                }
            }
        }
        // The weights track: one-hot on target k − 1 at frame k.
        let animation = file.animations().next().unwrap();
        let weights = animation
            .channels()
            .find(|c| c.target().node().mesh().is_some_and(|m| m.name() == Some("cloth")))
            .unwrap();
        let r = weights.reader(|_| Some(blob));
        let times: Vec<f32> = r.read_inputs().unwrap().collect();
        assert_eq!(times, d.times());
        let Some(ReadOutputs::MorphTargetWeights(w)) = r.read_outputs() else { panic!("weights") };
        let w: Vec<f32> = w.into_f32().collect();
        let n = d.n_frames();
        for k in 0..n {
            for j in 0..n - 1 {
                assert_eq!(w[k * (n - 1) + j], if j + 1 == k { 1.0 } else { 0.0 }, "key {k}, target {j}");
            }
        }
        // The figure: composing each link's node transform with its parent's gives the world pose.
        let fig = &anim.figures[0];
        let node_of = |name: &str| file.nodes().find(|n| n.name() == Some(name)).unwrap();
        let track = |node: &::gltf::Node, k: usize| {
            let (mut t, mut q) = (None, None);
            for c in animation.channels().filter(|c| c.target().node().index() == node.index()) {
                match c.reader(|_| Some(blob)).read_outputs().unwrap() {
                    ReadOutputs::Translations(mut it) => t = it.nth(k),
                    ReadOutputs::Rotations(it) => q = it.into_f32().nth(k),
                    _ => panic!("a link has translation and rotation tracks"),
                }
            }
            let t = DVec3::from_array(t.unwrap().map(f64::from));
            let q = q.unwrap().map(f64::from);
            (t, DQuat::from_xyzw(q[0], q[1], q[2], q[3]))
        };
        for k in 0..fig.n_frames() {
            let (t0, q0) = track(&node_of("upper"), k);
            let (t1, q1) = track(&node_of("fore"), k);
            let (t, q) = (t0 + q0 * t1, q0 * q1);
            let want = fig.frame(k)[1];
            let t = DVec3::from_array(up.from_gltf(t.to_array()));
            assert!((t - want.translation).length() < 1e-6, "{up:?} frame {k}: {t} ≠ {}", want.translation);
            let want_q = up.rotation_to_gltf(want.rotation);
            assert!(q.dot(want_q).abs() > 1.0 - 1e-6, "{up:?} frame {k}: {q} ≠ {want_q}");
        }
        // The remeshed mesh: one node per frame, shown by a STEP scale track from its frame's time on.
        for k in 0..3 {
            let node = node_of(&format!("adaptive frame {k}"));
            let c = animation.channels().find(|c| c.target().node().index() == node.index()).unwrap();
            assert_eq!(c.sampler().interpolation(), ::gltf::animation::Interpolation::Step);
            let r = c.reader(|_| Some(blob));
            let keys: Vec<f32> = r.read_inputs().unwrap().collect();
            let Some(ReadOutputs::Scales(s)) = r.read_outputs() else { panic!("scales") };
            let shown: Vec<(f32, f32)> = keys.into_iter().zip(s.map(|s| s[0])).collect();
            let t = |j: usize| j as f32 * 0.1;
            let want = match k {
                0 => vec![(t(0), 1.0), (t(1), 0.0)],
                1 => vec![(t(0), 0.0), (t(1), 1.0), (t(2), 0.0)],
                _ => vec![(t(1), 0.0), (t(2), 1.0)],
            };
            assert_eq!(shown, want, "frame {k}");
        }
    }
}

#[test]
fn bad_input_is_refused_with_its_reason() {
    let mut m = DeformingMesh::new("m", 3, vec![[0, 1, 2]], [0; 3]).unwrap();
    let x = [DVec3::ZERO, DVec3::X, DVec3::Y];
    m.push_frame(0.0, &x).unwrap();
    let e = m.push_frame(0.0, &x).unwrap_err().to_string();
    assert!(e.contains("does not come after"), "{e}");
    let e = m.push_frame(1.0, &x[..2]).unwrap_err().to_string();
    assert!(e.contains("has 2 vertices, the mesh 3"), "{e}");
    let e = m.push_frame(1.0, &[DVec3::ZERO, DVec3::X, DVec3::splat(f64::NAN)]).unwrap_err().to_string();
    assert!(e.contains("vertex 2") && e.contains("not finite"), "{e}");
    let e = m.push_frame(1.0, &[DVec3::ZERO, DVec3::X, DVec3::splat(1e300)]).unwrap_err().to_string();
    assert!(e.contains("not finite in f32"), "{e}");
    assert_eq!(m.n_frames(), 1, "refused frames are not kept");
    m.push_frame(1.0, &x).unwrap();
    m.pop_frame();
    m.push_frame(0.5, &x).unwrap();
    assert_eq!(m.times(), [0.0, 0.5]);
    let e = DeformingMesh::new("m", 2, vec![[0, 1, 2]], [0; 3]).unwrap_err().to_string();
    assert!(e.contains("beyond the 2"), "{e}");
    let link =
        |parent| Link { name: "l".into(), parent, shape: box_mesh(DVec3::ZERO, DVec3::ONE), colour: [0; 3] };
    let e = Figure::new("f", vec![link(Some(1)), link(Some(0))]).unwrap_err().to_string();
    assert!(e.contains("cycle"), "{e}");
    let e = Figure::new("f", vec![link(Some(0))]).unwrap_err().to_string();
    assert!(e.contains("not another"), "{e}");
}

#[test]
fn an_empty_animation_is_still_a_glb() {
    let bytes = glb(&Animation::new(UpAxis::PlusY));
    let file = ::gltf::Gltf::from_slice(&bytes).unwrap();
    assert_eq!(file.nodes().count(), 0);
    assert!(file.blob.is_none());
}

/// Writes the sample for the Khronos validator (`ANIMA_GLTF_SAMPLE=path cargo test -p anima-viz`);
/// the integration tests run the validator on what anima's runs write.
#[test]
fn sample_file_for_the_validator() {
    if let Some(path) = std::env::var_os("ANIMA_GLTF_SAMPLE") {
        std::fs::write(path, glb(&sample(UpAxis::PlusZ))).unwrap();
    }
}
