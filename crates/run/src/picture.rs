//! Pictures of FLEX3D states: the final frame and a contact sheet of frames, rendered with a fixed
//! camera so that frames can be compared by eye. FLEX3D scenes have y up.

use std::path::Path;

use anima_cloth::flex3d::{Flex3dWorld, SurfaceInfo};
use anima_geom::{Aabb, DVec3, TriangleMesh};
use anima_viz::{Camera, Image, RenderMesh, RenderSettings, render};
use anyhow::Result;

use crate::output::write_atomic;
use crate::run::flex3d::Snapshot;

/// Surface colours, in scene order (cloth-like tones; the table is wood brown).
const SURFACE_COLOURS: [[u8; 3]; 4] = [[200, 70, 70], [70, 110, 190], [90, 160, 90], [200, 160, 60]];
const OBJECT_COLOUR: [u8; 3] = [150, 110, 70];

/// Direction the camera looks along: from the front (+z), above and to the right.
pub const VIEW_DIR: DVec3 = DVec3::new(-0.45, -0.45, -1.0);

/// A camera that frames `bounds` from [`VIEW_DIR`] with y up.
pub fn camera_for(bounds: Aabb) -> Camera {
    camera_along(bounds, VIEW_DIR)
}

/// A camera that frames `bounds` looking along `view_dir`, with y up.
pub fn camera_along(bounds: Aabb, view_dir: DVec3) -> Camera {
    Camera::framing(bounds, view_dir, DVec3::Y, 35.0)
}

/// Bounds of the given particle states and the static objects.
pub fn scene_bounds<'a>(states: impl IntoIterator<Item = &'a [DVec3]>, objects: &[TriangleMesh]) -> Aabb {
    let mut b = Aabb::EMPTY;
    for s in states {
        b = s.iter().fold(b, |b, p| if p.is_finite() { b.including(*p) } else { b });
    }
    objects.iter().fold(b, |b, o| b.union(o.aabb()))
}

/// Renders the surfaces (positions for all particles, surface after surface) and the objects.
pub fn render_state(
    surfaces: &[SurfaceInfo],
    positions: &[DVec3],
    objects: &[TriangleMesh],
    camera: &Camera,
    width: u32,
    height: u32,
    edges: bool,
) -> Result<Image> {
    let mut meshes: Vec<RenderMesh> =
        objects.iter().map(|o| RenderMesh::from_mesh(o, OBJECT_COLOUR)).collect();
    for (k, s) in surfaces.iter().enumerate() {
        let mesh =
            RenderMesh::new(&positions[s.range()], &s.triangles, SURFACE_COLOURS[k % SURFACE_COLOURS.len()]);
        meshes.push(if edges { mesh.with_edges() } else { mesh });
    }
    Ok(render(&meshes, camera, &RenderSettings::new(width, height))?)
}

/// A labelled picture of one state.
pub fn labelled_frame(
    world: &Flex3dWorld,
    positions: &[DVec3],
    camera: &Camera,
    (width, height): (u32, u32),
    label: &str,
) -> Result<Image> {
    let mut img = render_state(world.surfaces(), positions, world.objects(), camera, width, height, true)?;
    img.label(10, 8, label, (height as f64 / 18.0).clamp(12.0, 24.0))?;
    Ok(img)
}

/// Writes `final.png` (the last state) and `frames.png` (the snapshots on one sheet) into `dir`.
pub fn write_pictures(dir: &Path, world: &Flex3dWorld, snapshots: &[Snapshot]) -> Result<()> {
    let bounds = scene_bounds(
        snapshots.iter().map(|s| s.positions.as_slice()).chain([world.positions()]),
        world.objects(),
    );
    let camera = camera_for(bounds);
    let last =
        labelled_frame(world, world.positions(), &camera, (960, 720), &format!("t = {:.2} s", world.time()))?;
    let tiles = snapshots
        .iter()
        .map(|s| {
            labelled_frame(
                world,
                &s.positions,
                &camera,
                (400, 300),
                &format!("frame {} (t = {:.1} s)", s.frame, s.time),
            )
        })
        .collect::<Result<Vec<_>>>()?;
    write_final_and_sheet(dir, &last, &tiles, 3)
}

/// Writes `final.png` and, when there are tiles, `frames.png`: the tiles on a sheet `columns` wide.
/// Every kind of run leaves its pictures in this form.
pub fn write_final_and_sheet(dir: &Path, last: &Image, tiles: &[Image], columns: usize) -> Result<()> {
    write_atomic(&dir.join("final.png"), |w| Ok(last.write_png(w)?))?;
    if !tiles.is_empty() {
        let sheet = Image::grid(tiles, columns, 4, [255, 255, 255])?;
        write_atomic(&dir.join("frames.png"), |w| Ok(sheet.write_png(w)?))?;
    }
    Ok(())
}
