//! The software rasteriser: z-buffered, flat-shaded, two-sided triangles with optional edge lines over a
//! soft sky-and-ground background.
//!
//! Shading per triangle: c = colour · (ambient + diffuse · |n · l|), times `back_face_shade` when the
//! viewer sees the triangle's back (its winding is clockwise on screen). The absolute value makes cloth,
//! which has no inside, lit from either side; the darker back faces make folds read.

use anima_geom::{DVec3, TriangleMesh};

use crate::camera::{Basis, Camera, Projection};
use crate::error::VizError;
use crate::image::{Image, check_size};
use crate::raster::{EdgeStyle, ScreenVertex, Target};

/// One mesh to draw: borrowed vertices and triangles, a base colour, and whether to draw its edges.
#[derive(Debug, Clone, Copy)]
pub struct RenderMesh<'a> {
    pub vertices: &'a [DVec3],
    /// Vertex indices; triangles with an index out of range are skipped.
    pub triangles: &'a [[u32; 3]],
    pub colour: [u8; 3],
    pub draw_edges: bool,
}

impl<'a> RenderMesh<'a> {
    /// A mesh drawn without edge lines.
    pub fn new(vertices: &'a [DVec3], triangles: &'a [[u32; 3]], colour: [u8; 3]) -> Self {
        Self { vertices, triangles, colour, draw_edges: false }
    }

    pub fn from_mesh(mesh: &'a TriangleMesh, colour: [u8; 3]) -> Self {
        Self::new(mesh.vertices(), mesh.triangles(), colour)
    }

    /// The same mesh with thin dark lines along its triangle edges.
    pub fn with_edges(self) -> Self {
        Self { draw_edges: true, ..self }
    }
}

/// A vertical gradient behind the scene: sky above the horizon (the plane through the eye perpendicular
/// to the camera's `up`), ground below it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Background {
    pub zenith: [u8; 3],
    pub sky_horizon: [u8; 3],
    pub ground_horizon: [u8; 3],
    pub nadir: [u8; 3],
}

impl Background {
    /// Pale blue-grey sky fading to near-white at the horizon over a light warm-grey ground.
    pub fn studio() -> Self {
        Self {
            zenith: [196, 211, 228],
            sky_horizon: [242, 244, 246],
            ground_horizon: [226, 223, 217],
            nadir: [201, 197, 190],
        }
    }

    /// One colour everywhere.
    pub fn plain(colour: [u8; 3]) -> Self {
        Self { zenith: colour, sky_horizon: colour, ground_horizon: colour, nadir: colour }
    }
}

/// How to render: picture size, light, materials of lines and background.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    /// Each pixel is the mean of `supersample²` samples (anti-aliasing); clamped to 1–4.
    pub supersample: u32,
    /// Direction towards the light in camera coordinates (x right, y up, z towards the viewer), so the
    /// lighting follows the camera and every view is lit from the front.
    pub light_dir: DVec3,
    /// Fraction of the base colour every face gets.
    pub ambient: f64,
    /// Fraction added in proportion to |n · l|.
    pub diffuse: f64,
    /// Factor on the shade of faces seen from their back side.
    pub back_face_shade: f64,
    pub edge_colour: [u8; 3],
    /// Edge line width in output pixels.
    pub edge_width: f64,
    pub background: Background,
}

impl RenderSettings {
    /// A `width × height` picture, 2×2 supersampled, lit from the upper left front
    /// (`light_dir` = (−0.35, 0.55, 0.75)), ambient 0.35, diffuse 0.65, back faces at 0.8 of the shade,
    /// near-black 1-pixel edges, [`Background::studio`].
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            supersample: 2,
            light_dir: DVec3::new(-0.35, 0.55, 0.75),
            ambient: 0.35,
            diffuse: 0.65,
            back_face_shade: 0.8,
            edge_colour: [30, 32, 38],
            edge_width: 1.0,
            background: Background::studio(),
        }
    }
}

/// Opacity of edge lines at full strength; lines are meant to hint at the mesh, not hide the shading.
const EDGE_OPACITY: f32 = 0.65;
/// Triangles smaller than about this many output pixels across get fainter edge lines.
const EDGE_FADE_SIZE: f64 = 8.0;

/// Renders `meshes` as seen by `camera`. Triangles with non-finite or out-of-range vertices, and
/// zero-area ones, are skipped; triangles crossing the camera's near plane are clipped, ones behind it
/// dropped. A degenerate camera (eye at the target) gives the background alone.
///
/// Fails only for a picture size of zero or above [`Image::MAX_SIDE`].
pub fn render(meshes: &[RenderMesh], camera: &Camera, settings: &RenderSettings) -> Result<Image, VizError> {
    let (width, height) = (settings.width, settings.height);
    check_size(width, height)?;
    let ss = settings.supersample.clamp(1, 4) as usize;
    let mut target = Target::new(width as usize * ss, height as usize * ss);

    let Some(view) = View::new(camera, target.width, target.height) else {
        let fallback =
            View::new(&Camera::look_at(DVec3::Z, DVec3::ZERO, DVec3::Y, 45.0), target.width, target.height)
                .expect("the fallback camera is valid");
        fill_background(&mut target, &fallback, &settings.background);
        return Image::from_rgb(width, height, target.downsample(ss));
    };
    fill_background(&mut target, &view, &settings.background);

    let light = settings.light_dir.try_normalize().unwrap_or(DVec3::Z);
    let edge_style = EdgeStyle {
        colour: settings.edge_colour.map(f32::from),
        half_width: settings.edge_width.max(0.0) * ss as f64 / 2.0,
        opacity: EDGE_OPACITY,
        fade_size: EDGE_FADE_SIZE * ss as f64,
    };
    let mut cam = Vec::new();
    let mut screen = Vec::new();
    for mesh in meshes {
        cam.clear();
        cam.extend(mesh.vertices.iter().map(|&p| view.basis.camera_coords(p - view.eye)));
        screen.clear();
        screen.extend(cam.iter().map(|&c| view.project(c)));
        let base = mesh.colour.map(f32::from);
        let edges = (mesh.draw_edges && edge_style.half_width > 0.0).then_some(&edge_style);

        for tri in mesh.triangles {
            let idx = tri.map(|i| i as usize);
            if idx.iter().any(|&i| i >= cam.len()) {
                continue;
            }
            let c = idx.map(|i| cam[i]);
            if !c.iter().all(|p| p.is_finite()) {
                continue;
            }
            let Some(n) = (c[1] - c[0]).cross(c[2] - c[0]).try_normalize() else { continue };
            let faces_viewer = match view.lens {
                Lens::Perspective { .. } => n.dot(-c[0]) >= 0.0,
                Lens::Orthographic { .. } => n.z >= 0.0,
            };
            let mut shade = settings.ambient + settings.diffuse * n.dot(light).abs();
            if !faces_viewer {
                shade *= settings.back_face_shade;
            }
            let colour = base.map(|b| (b * shade as f32).clamp(0.0, 255.0));

            let in_front = c.map(|p| p.z <= -view.near);
            if in_front.iter().all(|&f| f) {
                target.triangle(idx.map(|i| screen[i]), 0b111, colour, edges);
            } else if in_front.iter().any(|&f| f) {
                let (poly, flags, n_poly) = clip_near(c, view.near);
                for k in 1..n_poly - 1 {
                    let mask = u8::from(k == 1 && flags[0])
                        | (u8::from(flags[k]) << 1)
                        | (u8::from(k + 1 == n_poly - 1 && flags[n_poly - 1]) << 2);
                    let v = [poly[0], poly[k], poly[k + 1]].map(|p| view.project(p));
                    target.triangle(v, mask, colour, edges);
                }
            }
        }
    }
    Image::from_rgb(width, height, target.downsample(ss))
}

/// Clips a camera-space triangle to z ≤ −near (Sutherland–Hodgman against one plane). Returns up to four
/// polygon vertices, whether the edge from each to the next lies on an original edge, and their count.
fn clip_near(c: [DVec3; 3], near: f64) -> ([DVec3; 4], [bool; 4], usize) {
    let mut poly = [DVec3::ZERO; 4];
    let mut flags = [false; 4];
    let mut n = 0;
    let mut push = |p: DVec3, real: bool| {
        poly[n] = p;
        flags[n] = real;
        n += 1;
    };
    for k in 0..3 {
        let (a, b) = (c[k], c[(k + 1) % 3]);
        let (a_in, b_in) = (a.z <= -near, b.z <= -near);
        if a_in {
            push(a, true);
        }
        if a_in != b_in {
            let t = (-near - a.z) / (b.z - a.z);
            // Leaving: the next edge runs along the near plane. Entering: it continues the original edge.
            push(a + (b - a) * t, b_in);
        }
    }
    (poly, flags, n)
}

#[derive(Debug, Clone, Copy)]
enum Lens {
    /// `scale` is pixels per unit of x/(−z).
    Perspective { scale: f64 },
    /// `scale` is pixels per world unit.
    Orthographic { scale: f64 },
}

/// A camera resolved for a buffer size.
#[derive(Debug, Clone, Copy)]
struct View {
    basis: Basis,
    eye: DVec3,
    near: f64,
    lens: Lens,
    centre: (f64, f64),
    /// The world's up in camera coordinates, for the horizon.
    up: DVec3,
}

impl View {
    fn new(camera: &Camera, width: usize, height: usize) -> Option<Self> {
        let basis = camera.basis()?;
        let half_h = height as f64 / 2.0;
        let distance = (camera.target - camera.eye).length();
        let (lens, near) = match camera.projection {
            Projection::Perspective { fov_y_deg } => {
                let fov = if fov_y_deg.is_finite() { fov_y_deg.clamp(1.0, 170.0) } else { 45.0 };
                (Lens::Perspective { scale: half_h / (fov.to_radians() / 2.0).tan() }, 1e-3 * distance)
            }
            Projection::Orthographic { half_height } => {
                let hh = if half_height.is_finite() && half_height > 0.0 { half_height } else { 1.0 };
                (Lens::Orthographic { scale: half_h / hh }, 0.0)
            }
        };
        let up = basis.camera_coords(camera.up.try_normalize().unwrap_or(basis.up));
        Some(Self { basis, eye: camera.eye, near, lens, centre: (width as f64 / 2.0, half_h), up })
    }

    /// Pixel position and depth key of a camera-space point in front of the camera.
    #[inline]
    fn project(&self, c: DVec3) -> ScreenVertex {
        let (cx, cy) = self.centre;
        match self.lens {
            Lens::Perspective { scale } => {
                let inv_depth = 1.0 / -c.z;
                ScreenVertex {
                    x: cx + c.x * scale * inv_depth,
                    y: cy - c.y * scale * inv_depth,
                    key: inv_depth,
                }
            }
            Lens::Orthographic { scale } => {
                ScreenVertex { x: cx + c.x * scale, y: cy - c.y * scale, key: c.z }
            }
        }
    }
}

fn fill_background(target: &mut Target, view: &View, bg: &Background) {
    // An orthographic camera has no ray directions; borrow those of a 50° lens so that its horizon
    // still falls where a perspective camera with the same framing would put it.
    let scale = match view.lens {
        Lens::Perspective { scale } => scale,
        Lens::Orthographic { .. } => view.centre.1 / 25f64.to_radians().tan(),
    };
    let mix = |p: [u8; 3], q: [u8; 3], t: f64| -> [f32; 3] {
        std::array::from_fn(|k| (f64::from(p[k]) + (f64::from(q[k]) - f64::from(p[k])) * t) as f32)
    };
    let (cx, cy) = view.centre;
    for y in 0..target.height {
        let dy = -(y as f64 + 0.5 - cy) / scale;
        for x in 0..target.width {
            let dx = (x as f64 + 0.5 - cx) / scale;
            let dir = DVec3::new(dx, dy, -1.0);
            let elevation = dir.dot(view.up) / dir.length();
            target.rgb[y * target.width + x] = if elevation >= 0.0 {
                mix(bg.sky_horizon, bg.zenith, elevation.sqrt())
            } else {
                mix(bg.ground_horizon, bg.nadir, (-elevation).sqrt())
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use anima_geom::{Aabb, box_mesh};

    use super::*;

    const WHITE: [u8; 3] = [255, 255, 255];

    fn flat_settings(width: u32, height: u32) -> RenderSettings {
        RenderSettings {
            supersample: 1,
            background: Background::plain(WHITE),
            ..RenderSettings::new(width, height)
        }
    }

    fn unit_box() -> TriangleMesh {
        box_mesh(DVec3::splat(-0.5), DVec3::splat(0.5))
    }

    /// The square (±1, ±1, 0) as two triangles sharing its diagonal from (−1, −1) to (1, 1).
    fn unit_square() -> ([DVec3; 4], [[u32; 3]; 2]) {
        let vertices = [
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(-1.0, 1.0, 0.0),
        ];
        (vertices, [[0, 1, 2], [0, 2, 3]])
    }

    /// The unit box in `colour`, framed from the direction (−1, −0.8, −1.2), on a `width` × `height` flat
    /// picture: the camera, the settings and the picture.
    fn oblique_unit_box(width: u32, height: u32, colour: [u8; 3]) -> (Camera, RenderSettings, Image) {
        let mesh = unit_box();
        let camera = Camera::framing(mesh.aabb(), DVec3::new(-1.0, -0.8, -1.2), DVec3::Y, 40.0);
        let settings = flat_settings(width, height);
        let img = render(&[RenderMesh::from_mesh(&mesh, colour)], &camera, &settings).unwrap();
        (camera, settings, img)
    }

    /// Pixel of world point `p` as `render` places it (supersample 1).
    fn pixel_of(camera: &Camera, settings: &RenderSettings, p: DVec3) -> (u32, u32) {
        let view = View::new(camera, settings.width as usize, settings.height as usize).unwrap();
        let s = view.project(view.basis.camera_coords(p - view.eye));
        (s.x as u32, s.y as u32)
    }

    #[test]
    fn oblique_unit_box_fills_the_centre_and_leaves_corners_empty() {
        let (_, _, img) = oblique_unit_box(160, 120, [200, 120, 80]);
        assert_ne!(img.pixel(80, 60), WHITE, "centre not shaded");
        for (x, y) in [(0, 0), (159, 0), (0, 119), (159, 119)] {
            assert_eq!(img.pixel(x, y), WHITE, "corner ({x}, {y}) drawn on");
        }
    }

    #[test]
    fn faces_with_different_normals_get_different_shades() {
        let (camera, settings, img) = oblique_unit_box(200, 200, [200, 200, 200]);
        let shade = |p: DVec3| {
            let (x, y) = pixel_of(&camera, &settings, p);
            img.pixel(x, y)
        };
        let (top, front, side) = (shade(0.5 * DVec3::Y), shade(0.5 * DVec3::Z), shade(0.5 * DVec3::X));
        assert!(top != front && front != side && top != side, "top {top:?} front {front:?} side {side:?}");
        assert!([top, front, side].iter().all(|&c| c != WHITE));
    }

    #[test]
    fn back_faces_are_darker_than_front_faces() {
        // One square, seen from either side with the light straight from the viewer: |n · l| = 1 both times.
        let (vertices, triangles) = unit_square();
        let mesh = [RenderMesh::new(&vertices, &triangles, [200, 200, 200])];
        let settings = RenderSettings { light_dir: DVec3::Z, ..flat_settings(40, 40) };
        let front = render(
            &mesh,
            &Camera::look_at(DVec3::new(0.0, 0.0, 4.0), DVec3::ZERO, DVec3::Y, 40.0),
            &settings,
        );
        let back = render(
            &mesh,
            &Camera::look_at(DVec3::new(0.0, 0.0, -4.0), DVec3::ZERO, DVec3::Y, 40.0),
            &settings,
        );
        let (f, b) = (front.unwrap().pixel(20, 20), back.unwrap().pixel(20, 20));
        assert_eq!(f, [200, 200, 200]);
        assert_eq!(b, [160, 160, 160]);
    }

    #[test]
    fn mesh_behind_the_camera_draws_nothing() {
        let mesh = box_mesh(DVec3::new(-1.0, -1.0, 4.0), DVec3::new(1.0, 1.0, 6.0));
        let camera = Camera::look_at(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), DVec3::Y, 60.0);
        let settings = RenderSettings::new(64, 48);
        let empty = render(&[], &camera, &settings).unwrap();
        let img =
            render(&[RenderMesh::from_mesh(&mesh, [255, 0, 0]).with_edges()], &camera, &settings).unwrap();
        assert_eq!(img, empty);
    }

    #[test]
    fn triangle_through_the_eye_plane_is_clipped_and_drawn() {
        // A floor running from behind the camera to far in front of it.
        let vertices =
            [DVec3::new(-5.0, -1.0, 5.0), DVec3::new(5.0, -1.0, 5.0), DVec3::new(0.0, -1.0, -50.0)];
        let triangles = [[0, 1, 2]];
        let camera = Camera::look_at(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0), DVec3::Y, 60.0);
        let settings = flat_settings(64, 48);
        let mesh = RenderMesh::new(&vertices, &triangles, [0, 0, 255]).with_edges();
        let img = render(&[mesh], &camera, &settings).unwrap();
        assert_ne!(img.pixel(32, 46), WHITE, "floor below the centre not drawn");
        assert_eq!(img.pixel(32, 2), WHITE, "floor drawn above the horizon");
    }

    #[test]
    fn nan_infinite_and_out_of_range_vertices_are_skipped() {
        let vertices = [
            DVec3::new(-1.0, -1.0, 0.0),
            DVec3::new(1.0, -1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
            DVec3::NAN,
            DVec3::new(f64::INFINITY, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
        ];
        let triangles = [[0, 1, 2], [0, 3, 1], [4, 1, 2], [0, 1, 99], [2, 2, 2], [0, 5, 2], [0, 1, 5]];
        let camera = Camera::look_at(DVec3::new(0.0, 0.0, 5.0), DVec3::ZERO, DVec3::Y, 45.0);
        let settings = flat_settings(50, 50);
        let img =
            render(&[RenderMesh::new(&vertices, &triangles, [90, 90, 90]).with_edges()], &camera, &settings);
        assert_ne!(img.unwrap().pixel(25, 30), WHITE);
        let all_nan = [DVec3::NAN; 3];
        let camera = Camera::framing(Aabb::from_points(all_nan), DVec3::NEG_Z, DVec3::Y, 45.0);
        render(&[RenderMesh::new(&all_nan, &[[0, 1, 2]], WHITE)], &camera, &settings).unwrap();
    }

    #[test]
    fn orthographic_camera_and_degenerate_camera_render() {
        let mesh = unit_box();
        let settings = flat_settings(80, 60);
        let camera = Camera::framing_orthographic(mesh.aabb(), DVec3::new(-1.0, -1.0, -1.0), DVec3::Y);
        let img = render(&[RenderMesh::from_mesh(&mesh, [10, 200, 10])], &camera, &settings).unwrap();
        assert_ne!(img.pixel(40, 30), WHITE);
        assert_eq!(img.pixel(0, 0), WHITE);
        let stuck = Camera::look_at(DVec3::ONE, DVec3::ONE, DVec3::Y, 45.0);
        let img = render(&[RenderMesh::from_mesh(&mesh, [10, 200, 10])], &stuck, &settings).unwrap();
        assert_eq!(img.pixel(40, 30), WHITE);
    }

    #[test]
    fn edges_darken_pixels_along_shared_edges_only() {
        let (vertices, triangles) = unit_square();
        let camera = Camera::look_at(DVec3::new(0.0, 0.0, 3.0), DVec3::ZERO, DVec3::Y, 60.0);
        let settings = flat_settings(101, 101);
        let plain =
            render(&[RenderMesh::new(&vertices, &triangles, [200, 200, 200])], &camera, &settings).unwrap();
        let edged = render(
            &[RenderMesh::new(&vertices, &triangles, [200, 200, 200]).with_edges()],
            &camera,
            &settings,
        )
        .unwrap();
        // The diagonal from (−1, −1) to (1, 1) passes through the centre; (0.5, 0) lies inside a face.
        assert!(edged.pixel(50, 50)[0] < plain.pixel(50, 50)[0] - 40);
        let (x, y) = pixel_of(&camera, &settings, DVec3::new(0.5, 0.0, 0.0));
        assert_eq!(edged.pixel(x, y), plain.pixel(x, y));
    }

    #[test]
    fn zero_sized_picture_is_an_error() {
        let camera = Camera::look_at(DVec3::Z, DVec3::ZERO, DVec3::Y, 45.0);
        assert!(matches!(
            render(&[], &camera, &RenderSettings::new(0, 10)),
            Err(VizError::InvalidSize { .. })
        ));
    }
}
