//! The animated glTF export of a run (`RunOptions::export`): every kind of run hands its frames to a
//! `GltfExport`, which gathers them as `anima_viz::gltf` plain data and writes `animation.glb` into
//! the output folder when the run ends, also when it stopped early (what ran is exported).
//!
//! The frames are the run's own: frame 0 is the state at t = 0 (whether or not the OBJ frame 0 is
//! written) and keyframe k is the run's frame k, at the run's time for it, so a reader can set a
//! file's frame k beside the run's `<name>_<k>.obj`. Static objects go in as they are; cloth of fixed
//! topology as morph targets, a remeshed cloth as a mesh per frame, figures as node hierarchies (the
//! module docs of `anima_viz::gltf` say why).
//!
//! Axes: glTF's up is +y. FLEX3D scenes and figures already have y up (FLEX3D scripts are written so;
//! figures move in the x–y plane with gravity along −y); sheets and Oliveira drapes have their up
//! axis against their gravity (−z in every shipped scene, so z up), and z up when gravity is off.
//!
//! Long runs are thinned: at most [`MAX_KEYFRAMES`] keyframes and [`MAX_VERTEX_FRAMES`] vertex
//! positions over all of them are kept, by keeping every s-th frame (and the last one whatever its
//! number); the summary then says so. Without thinning a morph-target file costs about
//! frames × vertices × 12 bytes (the weights track frames² × 4 bytes more).

use std::path::Path;

use anima_body::{BodyPose, Shape, Side, World};
use anima_geom::query::tessellate;
use anima_geom::{DVec3, Sphere, TriangleMesh, box_mesh};
use anima_viz::VizError;
use anima_viz::gltf::{Animation, DeformingMesh, Figure, Link, Pose, RemeshedMesh, StaticMesh, UpAxis};
use anyhow::Result;

use crate::output::write_atomic;

/// What a run exports beside its frames (`anima run --export`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Export {
    /// Animated glTF 2.0, `animation.glb` in the output folder.
    Gltf,
    /// An animated USD stage in text form, `animation.usda` in the output folder (film and VFX
    /// pipelines; a remeshed cloth keeps its changing topology; `anima_viz::gltf::usd`).
    Usd,
}

impl Export {
    /// The file the export writes in the output folder.
    pub fn file(self) -> &'static str {
        match self {
            Export::Gltf => GLTF_FILE,
            Export::Usd => USD_FILE,
        }
    }
}

/// The file a glTF export writes in the output folder.
pub const GLTF_FILE: &str = "animation.glb";

/// The file a USD export writes in the output folder.
pub const USD_FILE: &str = "animation.usda";

/// The most keyframes an export keeps: the morph weights track grows as their square (4 MB here).
pub const MAX_KEYFRAMES: usize = 1000;

/// The most vertex positions an export keeps over all its keyframes (2²⁵: 400 MB of f32 positions).
pub const MAX_VERTEX_FRAMES: usize = 1 << 25;

/// Cloth colours, sRGB (the pictures' tones).
pub(crate) const CLOTH_COLOURS: [[u8; 3]; 4] = [[200, 70, 70], [70, 110, 190], [90, 160, 90], [200, 160, 60]];
pub(crate) const OBJECT_COLOUR: [u8; 3] = [150, 150, 160];
const GROUND_COLOUR: [u8; 3] = [205, 195, 175];

/// A run's frames on their way into a glTF file.
#[derive(Debug)]
pub(crate) struct GltfExport {
    animation: Animation,
    /// Frame k is kept for good when k is a multiple of the stride.
    stride: usize,
    /// Frames in every object of the animation.
    n_kept: usize,
    /// The last frame is not a multiple of the stride: the next frame replaces it.
    provisional: bool,
    /// Why the export took no more frames, when a frame could not be exported.
    stopped: Option<String>,
    /// Figures: scratch for the world's poses, the ground's height and the x range the figures
    /// covered (the ground is drawn under it).
    poses: Vec<BodyPose>,
    ground: Option<f64>,
    x_range: (f64, f64),
}

impl GltfExport {
    fn new(animation: Animation, n_frames: usize, vertices_per_frame: usize) -> Self {
        let keyframes = n_frames + 1;
        let stride = keyframes
            .div_ceil(MAX_KEYFRAMES)
            .max((keyframes * vertices_per_frame).div_ceil(MAX_VERTEX_FRAMES));
        Self {
            animation,
            stride: stride.max(1),
            n_kept: 0,
            provisional: false,
            stopped: None,
            poses: Vec::new(),
            ground: None,
            x_range: (f64::INFINITY, f64::NEG_INFINITY),
        }
    }

    /// Cloth of fixed topology (each surface's name, vertex count and triangles) over static objects,
    /// for a run of `n_frames` frames after frame 0.
    pub fn cloth(
        up: UpAxis,
        objects: &[(String, TriangleMesh)],
        surfaces: &[(&str, usize, &[[u32; 3]])],
        n_frames: usize,
    ) -> Result<Self> {
        let mut anim = Animation::new(up);
        anim.statics = statics(objects);
        for (k, &(name, n, triangles)) in surfaces.iter().enumerate() {
            let colour = CLOTH_COLOURS[k % CLOTH_COLOURS.len()];
            anim.deforming.push(DeformingMesh::new(name, n, triangles.to_vec(), colour)?);
        }
        let vertices = surfaces.iter().map(|s| s.1).sum();
        Ok(Self::new(anim, n_frames, vertices))
    }

    /// A remeshed cloth over static objects; `n_vertices` is its size at the start.
    pub fn remeshed(
        up: UpAxis,
        objects: &[(String, TriangleMesh)],
        n_frames: usize,
        n_vertices: usize,
    ) -> Self {
        let mut anim = Animation::new(up);
        anim.statics = statics(objects);
        anim.remeshed.push(RemeshedMesh::new("cloth", CLOTH_COLOURS[0]));
        Self::new(anim, n_frames, n_vertices)
    }

    /// Every model of `world` as a figure: a link per body, parented as the skeleton's joints, each
    /// a box of the body's width and height (a ball a sphere), as deep as its smaller side; left
    /// limbs 0.1 m in front of the plane (+z) and right limbs 0.1 m behind it, as the pictures draw
    /// them, so that a pair of legs does not look like one. The ground, if any, is a strip under the
    /// ground the figures covered.
    pub fn figures(world: &World, n_frames: usize) -> Result<Self> {
        let mut anim = Animation::new(UpAxis::PlusY);
        for m in 0..world.n_models() {
            let sk = world.skeleton(m)?;
            let links = (0..sk.n_bodies())
                .map(|b| {
                    let body = sk.body(b);
                    let z = match body.side {
                        Side::Left => 0.1,
                        Side::Right => -0.1,
                        Side::Centre => 0.0,
                    };
                    let (shape, colour) = match body.shape {
                        Shape::Box { width, height } => {
                            let half = DVec3::new(width, height, width.min(height)) / 2.0;
                            let centre = DVec3::new(0.0, 0.0, z);
                            let colour = match body.side {
                                Side::Left => [60, 170, 60],
                                Side::Right => [210, 60, 50],
                                Side::Centre => [120, 140, 170],
                            };
                            (box_mesh(centre - half, centre + half), colour)
                        }
                        Shape::Ball { radius } => (
                            tessellate::sphere(&Sphere { centre: DVec3::new(0.0, 0.0, z), radius }, 16),
                            [230, 140, 40],
                        ),
                    };
                    Link {
                        name: body.name.clone(),
                        parent: sk.parent_joint(b).map(|j| sk.joint_bodies(j).0),
                        shape,
                        colour,
                    }
                })
                .collect();
            anim.figures.push(Figure::new(sk.name(), links)?);
        }
        let mut export = Self::new(anim, n_frames, 0);
        export.ground = world.settings().ground.map(|g| g.height);
        Ok(export)
    }

    /// Frame `k` at `time_s` of the fixed-topology surfaces: `positions(s)` is surface s's.
    pub fn deforming_frame<'a>(&mut self, k: usize, time_s: f64, positions: impl Fn(usize) -> &'a [DVec3]) {
        self.record(k, |anim| {
            anim.deforming.iter_mut().enumerate().try_for_each(|(s, d)| d.push_frame(time_s, positions(s)))
        });
    }

    /// Frame `k` at `time_s` of a one-piece cloth, exported either way: the triangles matter only
    /// to a remeshed cloth (a fixed one has its own).
    pub fn cloth_frame(&mut self, k: usize, time_s: f64, positions: &[DVec3], triangles: &[[u32; 3]]) {
        if self.animation.remeshed.is_empty() {
            self.deforming_frame(k, time_s, |_| positions);
        } else {
            self.record(k, |anim| anim.remeshed[0].push_frame(time_s, positions, triangles));
        }
    }

    /// Frame `k` of the figures: every body's pose in `world` now.
    pub fn figure_frame(&mut self, k: usize, world: &World) -> Result<()> {
        if self.stopped.is_some() {
            return Ok(());
        }
        let mut all = Vec::with_capacity(world.n_models());
        for m in 0..world.n_models() {
            world.body_poses(m, &mut self.poses)?;
            for p in self.poses.iter().filter(|p| p.centre[0].is_finite()) {
                self.x_range = (self.x_range.0.min(p.centre[0]), self.x_range.1.max(p.centre[0]));
            }
            all.push(self.poses.iter().map(|p| Pose::planar(p.centre, p.angle)).collect::<Vec<_>>());
        }
        let t = world.time();
        self.record(k, |anim| anim.figures.iter_mut().zip(&all).try_for_each(|(f, p)| f.push_frame(t, p)));
        Ok(())
    }

    /// Adds frame `k` to every object through `push`, all or none: a frame that cannot be exported (a
    /// non-finite position) ends the export there, with a warning.
    fn record(&mut self, k: usize, push: impl FnOnce(&mut Animation) -> Result<(), VizError>) {
        if self.stopped.is_some() {
            return;
        }
        if self.provisional {
            self.n_kept -= 1;
            self.truncate();
        }
        match push(&mut self.animation) {
            Ok(()) => {
                self.n_kept += 1;
                self.provisional = !k.is_multiple_of(self.stride);
            }
            Err(e) => {
                self.truncate();
                self.provisional = false;
                self.stopped = Some(format!("{e} (run frame {k}); the file holds the frames before it"));
            }
        }
    }

    /// Drops frames beyond `n_kept` from every object.
    fn truncate(&mut self) {
        let a = &mut self.animation;
        let n = self.n_kept;
        a.deforming.iter_mut().for_each(|d| (n..d.n_frames()).for_each(|_| d.pop_frame()));
        a.remeshed.iter_mut().for_each(|r| (n..r.n_frames()).for_each(|_| r.pop_frame()));
        a.figures.iter_mut().for_each(|f| (n..f.n_frames()).for_each(|_| f.pop_frame()));
    }

    /// Writes `dir/animation.glb` or `dir/animation.usda` (whole: a temporary file renamed into place);
    /// returns what the summary should warn about (thinned frames, an export that ended early).
    pub fn write(mut self, dir: &Path, format: Export) -> Result<Vec<String>> {
        if let Some(height) = self.ground {
            let (x0, x1) = if self.x_range.0 <= self.x_range.1 { self.x_range } else { (0.0, 0.0) };
            let ground =
                box_mesh(DVec3::new(x0 - 1.5, height - 0.05, -1.0), DVec3::new(x1 + 1.5, height, 1.0));
            self.animation.statics.push(StaticMesh::new("ground", ground, GROUND_COLOUR));
        }
        let file = format.file();
        match format {
            Export::Gltf => write_atomic(&dir.join(file), |w| Ok(self.animation.write_glb(w)?))?,
            Export::Usd => write_atomic(&dir.join(file), |w| Ok(self.animation.write_usda(w)?))?,
        }
        let mut warnings = Vec::new();
        if self.stride > 1 {
            warnings.push(format!(
                "{file} keeps one frame in {} and the last ({} keyframes; an export keeps at most \
                 {MAX_KEYFRAMES} keyframes and {MAX_VERTEX_FRAMES} vertex positions in all)",
                self.stride, self.n_kept
            ));
        }
        warnings.extend(self.stopped);
        Ok(warnings)
    }
}

fn statics(objects: &[(String, TriangleMesh)]) -> Vec<StaticMesh> {
    objects.iter().map(|(name, mesh)| StaticMesh::new(name.clone(), mesh.clone(), OBJECT_COLOUR)).collect()
}
