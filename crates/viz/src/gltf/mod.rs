//! Animated glTF 2.0 export: what a run did, as one binary `.glb` file that any glTF viewer (Blender,
//! three.js, the Khronos sample viewer) plays back; the same [`Animation`] also as a USD stage
//! ([`usd`]) for film pipelines.
//!
//! The input is plain data and knows no scene: an [`Animation`] holds
//! - [`StaticMesh`]es: objects that do not move (a table, the Bunny, the ground);
//! - [`DeformingMesh`]es: meshes of fixed topology whose vertices move (a FLEX3D surface, a sheet, an
//!   Oliveira cloth on a static mesh);
//! - [`RemeshedMesh`]es: meshes whose topology changes from frame to frame (Oliveira's adaptive cloth);
//! - [`Figure`]s: articulated figures, links each with a parent and a world pose per frame.
//!
//! # How each kind moves
//!
//! **Fixed topology: morph targets.** Frame 0 is the mesh's base positions; every later frame k is a
//! morph target holding the displacement p_k − p_0 (f32, metres); a `weights` channel with LINEAR
//! interpolation sets weight k − 1 to one at frame k's time and every other weight to zero. Between
//! frames k and k + 1 the weights cross-fade, so a viewer shows (1 − s)·p_k + s·p_{k+1}: playback
//! interpolates positions linearly between frames, at any playback rate. The alternative, one mesh per
//! frame shown by a STEP visibility track, would cost as much position data (vertices × 12 bytes per
//! frame either way), repeat the triangle indices every frame and play back as a flip-book at the
//! run's frame rate; morph targets store the triangles once and play back smoothly. Their price is
//! the weights track: frames × (frames − 1) floats, 4 MB at a thousand frames, which is why the
//! caller should thin a long run's frames (anima's runs keep at most a thousand, see
//! `anima_lab::run::export`). Some viewers cap the number of morph targets they blend at once; only
//! two weights are non-zero at any time here, which every viewer we know of handles.
//!
//! **Changing topology: a mesh per frame.** Morph targets need one topology, so a remeshed cloth gets
//! one mesh and one node per frame, under one parent node, and each frame node a `scale` channel with
//! STEP interpolation: 1 from its frame's time to the next frame's, 0 otherwise. Each track has at
//! most three keys (the previous frame's time, its own, the next one's), so the tracks grow linearly
//! with the number of frames, not quadratically. Outside the animation (a static viewer) frame 0 shows.
//!
//! **Figures: a node per link.** Each link is a node parented as the skeleton, with a mesh in the
//! link's own frame and `translation` and `rotation` channels (LINEAR; rotations are slerped, and
//! consecutive quaternions are kept in one hemisphere so that the slerp takes the short way). The
//! callers give world poses; the file holds each link's pose relative to its parent,
//! q_local = q_parent⁻¹·q, t_local = q_parent⁻¹·(t − t_parent), as glTF asks.
//!
//! # Units and axes
//!
//! glTF is metres with +y up. The run's coordinates are taken as metres and turned so that the
//! scene's up axis ([`UpAxis`]) becomes +y: a rotation that only permutes coordinates and flips signs,
//! so it is exact in floating point and a reader gets the run's numbers back by the inverse
//! ([`UpAxis::from_gltf`]). Positions are stored as f32, as glTF asks.
//!
//! # What a validator checks, and how it holds here
//!
//! Every POSITION accessor (bases and morph targets) carries the exact `min` and `max` of its f32
//! data; every animation input carries its bounds and is strictly increasing in f32 (a frame whose
//! time would not advance in f32 is refused when it is pushed); every buffer view starts on a 4-byte
//! boundary and no two accessors share one; there are no normals (viewers then compute flat normals,
//! which also follow the morphed positions); rotations are unit quaternions. Frames with a non-finite
//! coordinate (or one beyond f32's range) are refused when pushed, so what is written is finite.
//!
//! ```
//! use anima_geom::{DVec3, box_mesh};
//! use anima_viz::gltf::{Animation, DeformingMesh, StaticMesh, UpAxis};
//!
//! let mut anim = Animation::new(UpAxis::PlusZ);
//! anim.statics.push(StaticMesh::new("table", box_mesh(DVec3::splat(-1.0), DVec3::ZERO), [150, 150, 160]));
//! let mut cloth = DeformingMesh::new("cloth", 3, vec![[0, 1, 2]], [200, 70, 70]).unwrap();
//! for k in 0..3 {
//!     let z = 1.0 - 0.1 * k as f64;
//!     let x = [DVec3::new(0.0, 0.0, z), DVec3::new(1.0, 0.0, z), DVec3::new(0.0, 1.0, z)];
//!     cloth.push_frame(k as f64 / 30.0, &x).unwrap();
//! }
//! anim.deforming.push(cloth);
//! let mut glb = Vec::new();
//! anim.write_glb(&mut glb).unwrap();
//! assert_eq!(&glb[..4], b"glTF");
//! ```

pub mod usd;
mod write;

use anima_geom::{DVec3, TriangleMesh};
use glam::DQuat;

use crate::VizError;

/// Which of the run's coordinate axes points up. glTF's up is +y; [`UpAxis::to_gltf`] turns the
/// run's coordinates so that this axis becomes +y, by a rotation that permutes coordinates and flips
/// signs (determinant +1, so triangles keep their winding).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UpAxis {
    PlusX,
    MinusX,
    PlusY,
    MinusY,
    PlusZ,
    MinusZ,
}

impl UpAxis {
    /// The coordinate axis closest to −`gravity` (gravity pulls down), or `fallback` when gravity is
    /// zero or not finite.
    pub fn against(gravity: DVec3, fallback: UpAxis) -> UpAxis {
        let up = -gravity;
        if !up.is_finite() || up == DVec3::ZERO {
            return fallback;
        }
        let a = up.abs();
        if a.x >= a.y && a.x >= a.z {
            if up.x > 0.0 { UpAxis::PlusX } else { UpAxis::MinusX }
        } else if a.y >= a.z {
            if up.y > 0.0 { UpAxis::PlusY } else { UpAxis::MinusY }
        } else if up.z > 0.0 {
            UpAxis::PlusZ
        } else {
            UpAxis::MinusZ
        }
    }

    /// The run's coordinates (x, y, z) in glTF's axes. For +z up: (x, z, −y), a quarter turn about x.
    pub fn to_gltf<T: Copy + std::ops::Neg<Output = T>>(self, [x, y, z]: [T; 3]) -> [T; 3] {
        match self {
            UpAxis::PlusY => [x, y, z],
            UpAxis::MinusY => [x, -y, -z],
            UpAxis::PlusZ => [x, z, -y],
            UpAxis::MinusZ => [x, -z, y],
            UpAxis::PlusX => [-y, x, z],
            UpAxis::MinusX => [y, -x, z],
        }
    }

    /// glTF's coordinates back in the run's axes: the inverse of [`UpAxis::to_gltf`].
    pub fn from_gltf<T: Copy + std::ops::Neg<Output = T>>(self, [x, y, z]: [T; 3]) -> [T; 3] {
        match self {
            UpAxis::PlusY => [x, y, z],
            UpAxis::MinusY => [x, -y, -z],
            UpAxis::PlusZ => [x, -z, y],
            UpAxis::MinusZ => [x, z, -y],
            UpAxis::PlusX => [y, -x, z],
            UpAxis::MinusX => [-y, x, z],
        }
    }

    /// A rotation in the run's axes as the same rotation in glTF's axes: the quaternion's vector part
    /// turns with the coordinates (R q R⁻¹ for a rotation R), its scalar part stays.
    pub fn rotation_to_gltf(self, q: DQuat) -> DQuat {
        let [x, y, z] = self.to_gltf([q.x, q.y, q.z]);
        DQuat::from_xyzw(x, y, z, q.w)
    }
}

/// An object that does not move.
#[derive(Debug, Clone)]
pub struct StaticMesh {
    pub name: String,
    pub mesh: TriangleMesh,
    /// sRGB base colour.
    pub colour: [u8; 3],
}

impl StaticMesh {
    pub fn new(name: impl Into<String>, mesh: TriangleMesh, colour: [u8; 3]) -> Self {
        Self { name: name.into(), mesh, colour }
    }
}

/// A mesh of fixed topology whose vertices move: frames of positions at increasing times, each as
/// many as the mesh has vertices. Written as a base mesh (frame 0) and one morph target per later
/// frame (see the module's docs).
#[derive(Debug, Clone)]
pub struct DeformingMesh {
    name: String,
    colour: [u8; 3],
    n_vertices: usize,
    triangles: Vec<[u32; 3]>,
    times: Vec<f32>,
    /// Every frame's positions, frame after frame, in the run's axes.
    positions: Vec<[f32; 3]>,
}

impl DeformingMesh {
    /// A mesh of `n_vertices` vertices and these triangles, with no frame yet. Each index must be a
    /// vertex, and there must be a triangle.
    pub fn new(
        name: impl Into<String>,
        n_vertices: usize,
        triangles: Vec<[u32; 3]>,
        colour: [u8; 3],
    ) -> Result<Self, VizError> {
        let name = name.into();
        check_triangles(&name, None, n_vertices, &triangles)?;
        Ok(Self { name, colour, n_vertices, triangles, times: Vec::new(), positions: Vec::new() })
    }

    /// Adds a frame at `time_s` (later than the last frame's, also in f32).
    pub fn push_frame(&mut self, time_s: f64, positions: &[DVec3]) -> Result<(), VizError> {
        let frame = self.times.len();
        if positions.len() != self.n_vertices {
            return Err(input(
                &self.name,
                format!("frame {frame} has {} vertices, the mesh {}", positions.len(), self.n_vertices),
            ));
        }
        let t = next_time(&self.name, &self.times, time_s)?;
        push_positions(&self.name, frame, positions, &mut self.positions)?;
        self.times.push(t);
        Ok(())
    }

    /// Removes the last frame (a caller thinning a long run keeps only the latest of the frames it
    /// does not keep for good).
    pub fn pop_frame(&mut self) {
        if self.times.pop().is_some() {
            self.positions.truncate(self.times.len() * self.n_vertices);
        }
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn n_frames(&self) -> usize {
        self.times.len()
    }

    pub fn n_vertices(&self) -> usize {
        self.n_vertices
    }

    /// The time of each frame, s, as written (f32).
    pub fn times(&self) -> &[f32] {
        &self.times
    }

    /// Frame `k`'s positions as written (f32, the run's axes).
    pub fn frame(&self, k: usize) -> &[[f32; 3]] {
        &self.positions[k * self.n_vertices..(k + 1) * self.n_vertices]
    }
}

/// One frame of a [`RemeshedMesh`].
#[derive(Debug, Clone)]
struct MeshFrame {
    time: f32,
    positions: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
}

/// A mesh whose topology changes over the run (a remeshed cloth): each frame its own positions and
/// triangles. Written as one mesh and node per frame, shown in turn (see the module's docs).
#[derive(Debug, Clone)]
pub struct RemeshedMesh {
    name: String,
    colour: [u8; 3],
    frames: Vec<MeshFrame>,
}

impl RemeshedMesh {
    pub fn new(name: impl Into<String>, colour: [u8; 3]) -> Self {
        Self { name: name.into(), colour, frames: Vec::new() }
    }

    /// Adds a frame at `time_s` (later than the last frame's, also in f32): the mesh as it is then.
    pub fn push_frame(
        &mut self,
        time_s: f64,
        positions: &[DVec3],
        triangles: &[[u32; 3]],
    ) -> Result<(), VizError> {
        let frame = self.frames.len();
        check_triangles(&self.name, Some(frame), positions.len(), triangles)?;
        let times: Vec<f32> = self.frames.last().map(|f| f.time).into_iter().collect();
        let time = next_time(&self.name, &times, time_s)?;
        let mut p = Vec::with_capacity(positions.len());
        push_positions(&self.name, frame, positions, &mut p)?;
        self.frames.push(MeshFrame { time, positions: p, triangles: triangles.to_vec() });
        Ok(())
    }

    /// Removes the last frame.
    pub fn pop_frame(&mut self) {
        self.frames.pop();
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn n_frames(&self) -> usize {
        self.frames.len()
    }
}

/// A rigid link of a [`Figure`]: its parent link (`None` for a root), and its shape in its own frame
/// (the frame its [`Pose`] places).
#[derive(Debug, Clone)]
pub struct Link {
    pub name: String,
    pub parent: Option<usize>,
    pub shape: TriangleMesh,
    /// sRGB base colour.
    pub colour: [u8; 3],
}

/// Where a link is in the world: its frame's origin, m, and its orientation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    pub translation: DVec3,
    pub rotation: DQuat,
}

impl Pose {
    /// A pose in the x–y plane: origin (x, y, 0) and a counter-clockwise rotation of `angle` rad about z.
    pub fn planar(centre: [f64; 2], angle: f64) -> Self {
        Self { translation: DVec3::new(centre[0], centre[1], 0.0), rotation: DQuat::from_rotation_z(angle) }
    }
}

/// An articulated figure: links in a forest (each link's parent another link), and the world pose of
/// every link at each frame.
#[derive(Debug, Clone)]
pub struct Figure {
    name: String,
    links: Vec<Link>,
    times: Vec<f32>,
    /// Every frame's world poses, frame after frame.
    poses: Vec<Pose>,
}

impl Figure {
    /// A figure of these links, with no frame yet. Each parent must be another link, and following
    /// parents must end at a root.
    pub fn new(name: impl Into<String>, links: Vec<Link>) -> Result<Self, VizError> {
        let name = name.into();
        for (i, link) in links.iter().enumerate() {
            let mut at = i;
            for _ in 0..=links.len() {
                match links[at].parent {
                    None => break,
                    Some(p) if p >= links.len() || p == at => {
                        return Err(input(
                            &name,
                            format!(
                                "link `{}`: parent {p} is not another of its {} links",
                                links[at].name,
                                links.len()
                            ),
                        ));
                    }
                    Some(p) => at = p,
                }
            }
            if links[at].parent.is_some() {
                return Err(input(&name, format!("link `{}`: its parents form a cycle", link.name)));
            }
        }
        Ok(Self { name, links, times: Vec::new(), poses: Vec::new() })
    }

    /// Adds a frame at `time_s` (later than the last frame's, also in f32): every link's world pose, in
    /// the order of the links. Rotations are normalised.
    pub fn push_frame(&mut self, time_s: f64, poses: &[Pose]) -> Result<(), VizError> {
        let frame = self.times.len();
        if poses.len() != self.links.len() {
            return Err(input(
                &self.name,
                format!("frame {frame} has {} poses, the figure {} links", poses.len(), self.links.len()),
            ));
        }
        let t = next_time(&self.name, &self.times, time_s)?;
        for (p, link) in poses.iter().zip(&self.links) {
            let finite = p.translation.is_finite() && p.rotation.is_finite() && p.rotation.length() > 0.0;
            if !finite || p.translation.abs().max_element() > f64::from(f32::MAX) {
                return Err(input(
                    &self.name,
                    format!("frame {frame}: link `{}` has no finite pose", link.name),
                ));
            }
        }
        self.poses.extend(poses.iter().map(|p| Pose { rotation: p.rotation.normalize(), ..*p }));
        self.times.push(t);
        Ok(())
    }

    /// Removes the last frame.
    pub fn pop_frame(&mut self) {
        if self.times.pop().is_some() {
            self.poses.truncate(self.times.len() * self.links.len());
        }
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn links(&self) -> &[Link] {
        &self.links
    }

    pub fn n_frames(&self) -> usize {
        self.times.len()
    }

    /// Frame `k`'s world poses, one per link.
    pub fn frame(&self, k: usize) -> &[Pose] {
        let n = self.links.len();
        &self.poses[k * n..(k + 1) * n]
    }
}

/// Everything one file holds, in the run's coordinates; [`Animation::write_glb`] turns `up` to +y.
#[derive(Debug, Clone)]
pub struct Animation {
    pub up: UpAxis,
    pub statics: Vec<StaticMesh>,
    pub deforming: Vec<DeformingMesh>,
    pub remeshed: Vec<RemeshedMesh>,
    pub figures: Vec<Figure>,
}

impl Animation {
    /// Nothing yet, in a run whose up axis is `up`.
    pub fn new(up: UpAxis) -> Self {
        Self { up, statics: Vec::new(), deforming: Vec::new(), remeshed: Vec::new(), figures: Vec::new() }
    }

    /// Writes the binary glTF (`.glb`): one scene, one animation named "anima" holding every track.
    /// Objects without a frame are left out; a mesh with one frame is written still.
    pub fn write_glb(&self, w: impl std::io::Write) -> Result<(), VizError> {
        write::write_glb(self, w)
    }
}

fn input(object: &str, reason: String) -> VizError {
    VizError::GltfInput { object: object.to_owned(), reason }
}

fn check_triangles(
    name: &str,
    frame: Option<usize>,
    n_vertices: usize,
    triangles: &[[u32; 3]],
) -> Result<(), VizError> {
    let at = frame.map(|k| format!("frame {k}: ")).unwrap_or_default();
    if triangles.is_empty() {
        return Err(input(name, format!("{at}a mesh needs at least one triangle")));
    }
    if let Some(t) = triangles.iter().find(|t| t.iter().any(|&i| i as usize >= n_vertices)) {
        return Err(input(
            name,
            format!("{at}triangle {t:?} names a vertex beyond the {n_vertices} there are"),
        ));
    }
    Ok(())
}

/// `time_s` as an animation input after `times`: finite, not negative, later than the last in f32.
fn next_time(name: &str, times: &[f32], time_s: f64) -> Result<f32, VizError> {
    let t = time_s as f32;
    if !t.is_finite() || t < 0.0 {
        return Err(input(name, format!("frame {}: time {time_s} s is not a finite time ≥ 0", times.len())));
    }
    if let Some(&last) = times.last()
        && t <= last
    {
        return Err(input(
            name,
            format!(
                "frame {}: time {time_s} s does not come after the last frame's ({last} s in f32)",
                times.len()
            ),
        ));
    }
    Ok(t)
}

/// Appends `positions` as f32, or refuses them whole when one is not finite in f32.
fn push_positions(
    name: &str,
    frame: usize,
    positions: &[DVec3],
    out: &mut Vec<[f32; 3]>,
) -> Result<(), VizError> {
    let start = out.len();
    for (i, p) in positions.iter().enumerate() {
        let q = p.as_vec3().to_array();
        if !q.iter().all(|c| c.is_finite()) {
            out.truncate(start);
            return Err(input(name, format!("frame {frame}: vertex {i} at {p} is not finite in f32")));
        }
        out.push(q);
    }
    Ok(())
}

#[cfg(test)]
mod tests;
