//! The animated glTF export (`anima run --export gltf`): files read back with the `gltf` crate hold the
//! run's own frames (cloth positions of frame k equal to the OBJ frame k of the same run, link poses of
//! frame k equal to the figure's), and every kind of file passes the Khronos glTF-Validator.

use std::path::{Path, PathBuf};

use anima_geom::DVec3;
use anima_lab::repo::Repo;
use anima_lab::run::{Export, Overrides, RunOptions, Silent, Summary, run};
use anima_scene::{LoadOptions, Scene};
use anima_viz::gltf::UpAxis;
use glam::DQuat;
use gltf::animation::util::ReadOutputs;

/// A folder of its own under the system's temporary folder.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("anima-gltf-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn load(rel: &str, duration_s: f64) -> Scene {
    let mut scene = anima_scene::load(&Repo::here().assets(rel), &LoadOptions::default()).unwrap();
    Overrides { duration: Some(duration_s), ..Overrides::default() }.apply(&mut scene).unwrap();
    scene
}

/// Runs `scene` writing OBJ frames and `animation.glb` (no pictures) into `dir`.
fn run_exporting(scene: &Scene, dir: &Path) -> Summary {
    let opts = RunOptions {
        pictures: false,
        frame0: true,
        export: Some(Export::Gltf),
        ..RunOptions::writing_to(dir)
    };
    let summary = run(scene, "test", &opts, &mut Silent).unwrap();
    assert!(summary.error.is_none() && summary.warnings.is_empty(), "{summary:?}");
    summary
}

/// A written file, parsed, with its binary chunk.
struct Glb {
    doc: gltf::Gltf,
}

impl Glb {
    fn read(path: &Path) -> Self {
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        Self { doc: gltf::Gltf::from_slice(&bytes).unwrap() }
    }

    fn blob(&self) -> &[u8] {
        self.doc.blob.as_deref().expect("a binary chunk")
    }

    fn node(&self, name: &str) -> gltf::Node<'_> {
        self.doc.nodes().find(|n| n.name() == Some(name)).unwrap_or_else(|| panic!("no node `{name}`"))
    }

    /// The positions (in glTF's axes) and triangles of a mesh without morph targets.
    fn mesh(&self, node: &gltf::Node) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let prim = node.mesh().expect("a mesh").primitives().next().unwrap();
        let r = prim.reader(|_| Some(self.blob()));
        let p = r.read_positions().unwrap().collect();
        let i: Vec<u32> = r.read_indices().unwrap().into_u32().collect();
        (p, i.chunks(3).map(|t| [t[0], t[1], t[2]]).collect())
    }

    /// Frame k of a morph-target mesh, in the run's axes: its base plus target k − 1 (frame 0 is the
    /// base), added in f64 as the file's two f32 numbers.
    fn morph_frame(&self, node: &gltf::Node, k: usize, up: UpAxis) -> Vec<DVec3> {
        let prim = node.mesh().expect("a mesh").primitives().next().unwrap();
        let r = prim.reader(|_| Some(self.blob()));
        let base = r.read_positions().unwrap();
        let p: Vec<[f64; 3]> = match k {
            0 => base.map(|b| b.map(f64::from)).collect(),
            _ => {
                let (target, _, _) = r.read_morph_targets().nth(k - 1).expect("a target per frame");
                base.zip(target.unwrap())
                    .map(|(b, d)| [0, 1, 2].map(|c| f64::from(b[c]) + f64::from(d[c])))
                    .collect()
            }
        };
        p.into_iter().map(|q| DVec3::from_array(up.from_gltf(q))).collect()
    }

    /// The keys of `node`'s track along `path`: times and values (each value as f32s).
    fn track(&self, node: &gltf::Node, path: gltf::animation::Property) -> (Vec<f32>, Vec<Vec<f32>>) {
        let anim = self.doc.animations().next().expect("an animation");
        let c = anim
            .channels()
            .find(|c| c.target().node().index() == node.index() && c.target().property() == path)
            .unwrap_or_else(|| panic!("no {path:?} track on `{}`", node.name().unwrap_or("?")));
        let r = c.reader(|_| Some(self.blob()));
        let times = r.read_inputs().unwrap().collect();
        let values = match r.read_outputs().unwrap() {
            ReadOutputs::Translations(v) => v.map(|v| v.to_vec()).collect(),
            ReadOutputs::Rotations(v) => v.into_f32().map(|v| v.to_vec()).collect(),
            ReadOutputs::Scales(v) => v.map(|v| v.to_vec()).collect(),
            ReadOutputs::MorphTargetWeights(v) => v.into_f32().map(|w| vec![w]).collect(),
        };
        (times, values)
    }
}

/// The vertices of an OBJ frame file the run wrote.
fn obj(path: &Path) -> anima_geom::TriangleMesh {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    anima_geom::read_obj(&bytes[..]).unwrap()
}

/// `got` equals `want` to the f32 rounding of the file: half a unit in the last place of each
/// coordinate and of the frame's displacement, with room for the largest coordinate's.
fn assert_close(got: &[DVec3], want: &[DVec3], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: vertex count");
    let scale = want.iter().fold(1.0f64, |m, p| m.max(p.abs().max_element()));
    let tol = 2.0 * f64::from(f32::EPSILON) * scale;
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!(
            (*g - *w).abs().max_element() <= tol,
            "{what}: vertex {i} is {g} in the file, {w} in the run"
        );
    }
}

#[test]
fn a_sheet_runs_frames_read_back_from_its_gltf() {
    let dir = scratch("sheet");
    let scene = load("scenes/standard-sheet-32.ron", 0.2);
    let s = run_exporting(&scene, &dir);
    assert_eq!(s.frames, 6);
    let glb = Glb::read(&dir.join("animation.glb"));
    let node = glb.node("sheet");
    // The standard sheet falls along −z: glTF's y is its z.
    let up = UpAxis::PlusZ;
    let Scene::Sheet(sheet) = &scene else { unreachable!() };
    assert_close(&glb.morph_frame(&node, 0, up), &sheet.sheet.positions(), "frame 0");
    for k in 1..=s.frames {
        let want = obj(&dir.join(format!("sheet_{k}.obj")));
        assert_close(&glb.morph_frame(&node, k, up), want.vertices(), &format!("frame {k}"));
    }
    // One weights key per frame, at the frame's time, the last at the run's end.
    let (times, weights) = glb.track(&node, gltf::animation::Property::MorphTargetWeights);
    assert_eq!(times.len(), s.frames + 1);
    assert_eq!(weights.len(), times.len() * s.frames);
    assert_eq!(times[0], 0.0);
    assert_eq!(*times.last().unwrap(), s.simulated_seconds as f32);
    assert!(times.windows(2).all(|w| w[0] < w[1]), "{times:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_long_run_keeps_one_frame_in_s_and_its_last_and_a_stopped_run_what_ran() {
    // 2,500 frames: more than the export keeps (a thousand keyframes), so one frame in 3 is kept, and
    // the last frame, 2,500, which is no multiple of 3.
    let dir = scratch("long");
    let mut scene = load("scenes/standard-sheet-32.ron", 0.5);
    let Scene::Sheet(sheet) = &mut scene else { unreachable!() };
    sheet.frame_rate_hz = 5000.0;
    let opts = RunOptions { export: Some(Export::Gltf), ..RunOptions::quiet() };
    let s =
        run(&scene, "long", &RunOptions { out_dir: Some(dir.clone()), ..opts.clone() }, &mut Silent).unwrap();
    assert_eq!(s.frames, 2500);
    assert!(
        s.warnings.iter().any(|w| w.contains("keeps one frame in 3 and the last (835 keyframes")),
        "{:?}",
        s.warnings
    );
    let glb = Glb::read(&dir.join("animation.glb"));
    let node = glb.node("sheet");
    let (times, _) = glb.track(&node, gltf::animation::Property::MorphTargetWeights);
    assert_eq!(times.len(), 835);
    assert_eq!((times[1], times[833], times[834]), (3.0 / 5000.0, 2499.0 / 5000.0, 0.5));
    let last = obj(&dir.join("final.obj"));
    assert_close(&glb.morph_frame(&node, 834, UpAxis::PlusZ), last.vertices(), "the last frame");
    std::fs::remove_dir_all(&dir).unwrap();

    // A run that diverges stops at that frame (its bounds stop it, or it goes non-finite): the frames
    // before it are exported, or those before the first that f32 cannot hold.
    let dir = scratch("diverging");
    // 0.2 s: 200 frames, too few for the export to thin them.
    let mut scene = load("scenes/standard-sheet-32.ron", 0.2);
    let Scene::Sheet(sheet) = &mut scene else { unreachable!() };
    // A fifth beyond the stable step, with a frame every 2.5 steps: it leaves its speed bound after some
    // frames (the bounds are checked at every frame's end).
    sheet.dt_s = 0.0004;
    sheet.frame_rate_hz = 1000.0;
    let s =
        run(&scene, "diverging", &RunOptions { out_dir: Some(dir.clone()), ..opts }, &mut Silent).unwrap();
    assert!(
        s.error.as_deref().is_some_and(|e| e.contains("diverged")) && (2..100).contains(&s.frames),
        "{s:?}"
    );
    let glb = Glb::read(&dir.join("animation.glb"));
    let (times, _) = glb.track(&glb.node("sheet"), gltf::animation::Property::MorphTargetWeights);
    let beyond_f32 = s.warnings.iter().find(|w| w.contains("not finite in f32"));
    match beyond_f32 {
        None => assert_eq!(times.len(), s.frames + 1, "frame 0 and every frame the run reached"),
        Some(w) => {
            let k = times.len();
            assert!(
                k >= 2 && w.contains(&format!("(run frame {k}); the file holds the frames before it")),
                "{w}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_oliveira_drapes_frames_read_back_from_its_gltf() {
    // On a static mesh: morph targets, with the Bunny and the floor as static meshes.
    let dir = scratch("bunny");
    let s = run_exporting(&load("oliveira/test-1-bunny-5x5.ron", 0.2), &dir);
    assert_eq!(s.frames, 6);
    let glb = Glb::read(&dir.join("animation.glb"));
    for object in ["bunny", "floor"] {
        assert!(glb.node(object).mesh().is_some(), "{object}");
    }
    let cloth = glb.node("cloth");
    for k in 0..=s.frames {
        let want = obj(&dir.join(format!("cloth_{k}.obj")));
        assert_close(&glb.morph_frame(&cloth, k, UpAxis::PlusZ), want.vertices(), &format!("frame {k}"));
    }
    std::fs::remove_dir_all(&dir).unwrap();

    // Remeshed: a mesh per frame, each with the frame's own triangles, shown by a STEP scale track.
    let dir = scratch("adaptive");
    let s = run_exporting(&load("oliveira/test-2-table-adaptive.ron", 0.1), &dir);
    assert_eq!(s.frames, 3);
    let glb = Glb::read(&dir.join("animation.glb"));
    assert!(glb.node("table").mesh().is_some());
    let mut faces = Vec::new();
    for k in 0..=s.frames {
        let want = obj(&dir.join(format!("cloth_{k}.obj")));
        let node = glb.node(&format!("cloth frame {k}"));
        let (p, triangles) = glb.mesh(&node);
        let p: Vec<DVec3> =
            p.into_iter().map(|q| DVec3::from_array(UpAxis::PlusZ.from_gltf(q.map(f64::from)))).collect();
        assert_close(&p, want.vertices(), &format!("frame {k}"));
        assert_eq!(triangles, want.triangles(), "frame {k}");
        faces.push(triangles.len());
        let (times, scales) = glb.track(&node, gltf::animation::Property::Scale);
        let shown: Vec<f32> = scales.iter().map(|s| s[0]).collect();
        let at = |j: usize| if j == s.frames { 0.1f32 } else { (j as f64 / 30.0) as f32 };
        let (want_times, want_shown) = match k {
            0 => (vec![at(0), at(1)], vec![1.0, 0.0]),
            k if k == s.frames => (vec![at(k - 1), at(k)], vec![0.0, 1.0]),
            k => (vec![at(k - 1), at(k), at(k + 1)], vec![0.0, 1.0, 0.0]),
        };
        assert_eq!((times, shown), (want_times, want_shown), "frame {k}");
    }
    assert!(faces.windows(2).any(|w| w[0] != w[1]), "the remesher changed the mesh: {faces:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_figures_link_poses_read_back_from_its_gltf() {
    let dir = scratch("figure");
    let mut scene = load("scenes/stand.ron", 2.0);
    let Scene::Body(body) = &mut scene else { unreachable!() };
    body.scene.frame_rate_hz = Some(4.0);
    body.scene.frame_interval = None;
    let (duration, dt) = (body.scene.duration, body.scene.world.dt);
    run_exporting(&scene, &dir);
    let glb = Glb::read(&dir.join("animation.glb"));
    let Scene::Body(body) = &scene else { unreachable!() };
    // The same figures again (runs are bit-identical), stepped to each frame.
    let mut world = body.scene.build(&body.skeletons).unwrap();
    let skeleton = &body.skeletons[0];
    let every = (0.25 / dt).round() as usize;
    let n_frames = (duration / dt).round() as usize / every;
    let mut poses = Vec::new();
    let mut moved = 0.0f64;
    for k in 0..=n_frames {
        while world.time() < (k * every) as f64 * dt - 1e-9 {
            world.step().unwrap();
        }
        world.body_poses(0, &mut poses).unwrap();
        for (b, pose) in poses.iter().enumerate() {
            // The link's world transform: its node's keys composed up the skeleton.
            let (mut t, mut q) = (DVec3::ZERO, DQuat::IDENTITY);
            let mut at = Some(b);
            while let Some(link) = at {
                let node = glb.node(&skeleton.body(link).name);
                let (times, tr) = glb.track(&node, gltf::animation::Property::Translation);
                let (_, rot) = glb.track(&node, gltf::animation::Property::Rotation);
                assert_eq!(times.len(), n_frames + 1);
                assert_eq!(times[k], world.time() as f32, "frame {k}");
                let lt = DVec3::new(tr[k][0].into(), tr[k][1].into(), tr[k][2].into());
                let lq =
                    DQuat::from_xyzw(rot[k][0].into(), rot[k][1].into(), rot[k][2].into(), rot[k][3].into());
                (t, q) = (lt + lq * t, lq * q);
                at = skeleton.parent_joint(link).map(|j| skeleton.joint_bodies(j).0);
            }
            let want_t = DVec3::new(pose.centre[0], pose.centre[1], 0.0);
            assert!(
                (t - want_t).length() < 1e-5,
                "frame {k}, body {b}: at {t} in the file, {want_t} in the run"
            );
            let want_q = DQuat::from_rotation_z(pose.angle);
            assert!(
                q.dot(want_q).abs() > 1.0 - 1e-6,
                "frame {k}, body {b}: {q} in the file, {want_q} in the run"
            );
            if k == n_frames {
                moved = moved.max(pose.angle.abs());
            }
        }
    }
    assert!(moved > 1e-4, "the figure moved, so frames differ");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Runs the Khronos glTF-Validator on every kind of file anima writes. Needs the validator's npm package
/// in the folder `ANIMA_GLTF_VALIDATOR` names (`npm install --prefix "$ANIMA_GLTF_VALIDATOR"
/// gltf-validator`) and Node.js; `tests/gltf/validate.cjs` prints each report.
#[test]
#[ignore = "needs the gltf-validator npm package; cargo xtask test installs it"]
fn every_kind_of_gltf_passes_the_khronos_validator() {
    let validator = std::env::var_os("ANIMA_GLTF_VALIDATOR").map(PathBuf::from).expect(
        "ANIMA_GLTF_VALIDATOR must name a folder where `npm install gltf-validator` was run \
         (cargo xtask test sets it up)",
    );
    let modules = validator.join("node_modules");
    assert!(
        modules.join("gltf-validator").is_dir(),
        "{} has no gltf-validator: run `npm install --prefix {} gltf-validator`",
        modules.display(),
        validator.display()
    );
    let dir = scratch("validator");
    let kinds = [
        ("tablecloth", "flex3d/tablecloth.ron", 2.0),
        ("sheet", "scenes/standard-sheet-32.ron", 0.2),
        ("bunny", "oliveira/test-1-bunny-5x5.ron", 0.2),
        ("sphere", "oliveira/test-3-sphere-5x5.ron", 0.2),
        ("adaptive", "oliveira/test-2-table-adaptive.ron", 0.1),
        ("stand", "scenes/stand.ron", 4.0),
        ("throw", "scenes/throw.ron", 2.0),
    ];
    let mut files = Vec::new();
    for (name, rel, duration) in kinds {
        let out = dir.join(name);
        run_exporting(&load(rel, duration), &out);
        files.push(out.join("animation.glb"));
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("gltf/validate.cjs");
    let output = std::process::Command::new("node")
        .arg(&script)
        .args(&files)
        .env("NODE_PATH", &modules)
        .output()
        .expect("running node (Node.js must be installed)");
    let report = String::from_utf8_lossy(&output.stdout);
    println!("{report}{}", String::from_utf8_lossy(&output.stderr));
    assert!(output.status.success(), "the validator found errors (or could not run):\n{report}");
    assert_eq!(report.matches(": 0 errors").count(), files.len(), "{report}");
    std::fs::remove_dir_all(&dir).unwrap();
}
