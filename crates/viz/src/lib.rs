//! Pictures for anima: a small flat-shading software rasteriser for triangle meshes, line plots of
//! series, an RGB [`Image`] that can be labelled, tiled into figure sheets and written as PNG, and the
//! animated glTF exporter.
//!
//! This crate knows no physics: it draws vertices, triangles and (x, y) points handed to it, whatever
//! they came from. It does no file I/O of its own: writers take `impl Write`. Everything is drawn in
//! software with an embedded font (DejaVu Sans), so pictures come out the same on a machine without a
//! GPU, a display or system fonts.
//!
//! - [`render`] draws [`RenderMesh`]es seen by a [`Camera`] with z-buffered, two-sided flat shading
//!   (cloth has no inside), optional edge lines, and a sky-and-ground background.
//! - [`LinePlot`] draws [`Series`] with plotters: legend, linear or log axes, clipping to given ranges.
//! - [`Image::grid`] tiles frames into a sheet; [`Image::label`] writes text on a picture.
//! - [`gltf`] writes an animated glTF 2.0 file (`.glb`) of moving meshes and articulated figures.
//!
//! ```
//! use anima_geom::{DVec3, box_mesh};
//! use anima_viz::{Camera, LinePlot, RenderMesh, RenderSettings, Series, render};
//!
//! let cube = box_mesh(DVec3::ZERO, DVec3::ONE);
//! let camera = Camera::framing(cube.aabb(), DVec3::new(-1.0, -0.7, -0.5), DVec3::Z, 35.0);
//! let mut img = render(&[RenderMesh::from_mesh(&cube, [200, 70, 70])], &camera, &RenderSettings::new(160, 120)).unwrap();
//! img.label(4, 4, "a cube", 12.0).unwrap();
//! assert_ne!(img.pixel(80, 60), img.pixel(2, 118), "the cube covers the middle of the picture");
//!
//! let mut plot = LinePlot::new("x(t)", "t (s)", "x (m)");
//! plot.series.push(Series::line("cos t", (0..100).map(|i| (i as f64 * 0.1, (i as f64 * 0.1).cos())).collect()));
//! let mut png = Vec::new();
//! plot.render(400, 300).unwrap().write_png(&mut png).unwrap();
//! assert_eq!(&png[1..4], b"PNG");
//! ```

mod camera;
mod draw2d;
mod error;
pub mod gltf;
mod image;
mod plot;
mod raster;
mod render;
mod text;

#[cfg(test)]
mod preview;

pub use anima_geom::{Aabb, DVec3};
pub use camera::{Camera, Projection};
pub use draw2d::{View2d, draw_line, fill_disc, fill_polygon, stroke_polygon};
pub use error::VizError;
pub use image::Image;
pub use plot::{LegendPosition, LinePlot, PALETTE, Series, SeriesStyle};
pub use render::{Background, RenderMesh, RenderSettings, render};
