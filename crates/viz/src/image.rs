//! An owned 8-bit RGB picture: pixel access, PNG encoding, contact sheets and text labels.

use std::io::Write;

use plotters::prelude::*;

use crate::error::{VizError, draw_error};
use crate::text;

/// An 8-bit RGB picture, rows top to bottom, `rgb.len() == 3 · width · height`.
///
/// The fields are private because of that length invariant; [`Image::from_rgb`] checks it.
#[derive(Clone, PartialEq, Eq)]
pub struct Image {
    width: u32,
    height: u32,
    rgb: Vec<u8>,
}

impl std::fmt::Debug for Image {
    // The pixel buffer is megabytes; printing it helps nobody.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Image")
            .field("width", &self.width)
            .field("height", &self.height)
            .finish_non_exhaustive()
    }
}

impl Image {
    /// The largest width or height accepted, in pixels. plotters computes `width · height` in `u32`,
    /// and 16384² · 3 bytes still fits comfortably.
    pub const MAX_SIDE: u32 = 16_384;

    /// A `width × height` picture filled with `background`.
    pub fn new(width: u32, height: u32, background: [u8; 3]) -> Result<Self, VizError> {
        check_size(width, height)?;
        let rgb = background.repeat(width as usize * height as usize);
        Ok(Self { width, height, rgb })
    }

    /// Wraps an existing RGB buffer (rows top to bottom, 3 bytes a pixel).
    pub fn from_rgb(width: u32, height: u32, rgb: Vec<u8>) -> Result<Self, VizError> {
        check_size(width, height)?;
        let expected = 3 * width as usize * height as usize;
        if rgb.len() != expected {
            return Err(VizError::BufferLength { width, height, expected, found: rgb.len() });
        }
        Ok(Self { width, height, rgb })
    }

    pub fn width(&self) -> u32 {
        self.width
    }

    pub fn height(&self) -> u32 {
        self.height
    }

    /// The pixel bytes, `[r, g, b, r, g, b, …]`, rows top to bottom.
    pub fn rgb(&self) -> &[u8] {
        &self.rgb
    }

    pub fn rgb_mut(&mut self) -> &mut [u8] {
        &mut self.rgb
    }

    pub fn into_rgb(self) -> Vec<u8> {
        self.rgb
    }

    #[inline]
    fn offset(&self, x: u32, y: u32) -> usize {
        assert!(x < self.width && y < self.height, "pixel ({x}, {y}) outside {}×{}", self.width, self.height);
        3 * (y as usize * self.width as usize + x as usize)
    }

    /// The colour at column `x`, row `y` (row 0 at the top). Panics outside the picture, like slice
    /// indexing.
    #[inline]
    pub fn pixel(&self, x: u32, y: u32) -> [u8; 3] {
        let i = self.offset(x, y);
        [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]]
    }

    /// Sets the colour at column `x`, row `y`. Panics outside the picture.
    #[inline]
    pub fn set_pixel(&mut self, x: u32, y: u32, colour: [u8; 3]) {
        let i = self.offset(x, y);
        self.rgb[i..i + 3].copy_from_slice(&colour);
    }

    /// Encodes the picture as an 8-bit RGB PNG into `w`.
    pub fn write_png(&self, w: impl Write) -> Result<(), VizError> {
        let mut encoder = png::Encoder::new(w, self.width, self.height);
        encoder.set_color(png::ColorType::Rgb);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header()?;
        writer.write_image_data(&self.rgb)?;
        writer.finish()?;
        Ok(())
    }

    /// Tiles equal-sized `images` row by row into one sheet with `columns` tiles a row, e.g. the 3×3
    /// frame panels of a figure. `gap` pixels of `background` separate the tiles and surround the sheet,
    /// so the sheet is `c·w + (c + 1)·gap` wide and `r·h + (r + 1)·gap` high, with c = min(columns, n)
    /// and r = ⌈n / columns⌉. Empty cells of the last row stay `background`.
    pub fn grid(images: &[Image], columns: usize, gap: u32, background: [u8; 3]) -> Result<Image, VizError> {
        let Some(first) = images.first().filter(|_| columns > 0) else {
            return Err(VizError::EmptyGrid { n_images: images.len(), columns });
        };
        let (w, h) = (first.width, first.height);
        for (index, img) in images.iter().enumerate() {
            if (img.width, img.height) != (w, h) {
                return Err(VizError::GridTileSize {
                    index,
                    width: w,
                    height: h,
                    found_width: img.width,
                    found_height: img.height,
                });
            }
        }
        let cols = columns.min(images.len());
        let rows = images.len().div_ceil(columns);
        let side = |n: usize, tile: u32| n as u64 * u64::from(tile) + (n as u64 + 1) * u64::from(gap);
        let clamp = |v: u64| u32::try_from(v).unwrap_or(u32::MAX);
        let (sheet_w, sheet_h) = (clamp(side(cols, w)), clamp(side(rows, h)));
        let mut sheet = Image::new(sheet_w, sheet_h, background)?;
        let row_bytes = 3 * w as usize;
        for (k, img) in images.iter().enumerate() {
            let x0 = gap + (k % columns) as u32 * (w + gap);
            let y0 = gap + (k / columns) as u32 * (h + gap);
            for y in 0..h {
                let dst = sheet.offset(x0, y0 + y);
                let src = img.offset(0, y);
                sheet.rgb[dst..dst + row_bytes].copy_from_slice(&img.rgb[src..src + row_bytes]);
            }
        }
        Ok(sheet)
    }

    /// Draws `text` in near-black DejaVu Sans with its top-left corner at pixel (`x`, `y`); `size` is the
    /// font size in pixels. Text running off the picture is cut.
    pub fn label(&mut self, x: i32, y: i32, text: &str, size: f64) -> Result<(), VizError> {
        self.label_with_colour(x, y, text, size, [20, 20, 20])
    }

    /// [`Image::label`] in a chosen colour.
    pub fn label_with_colour(
        &mut self,
        x: i32,
        y: i32,
        text: &str,
        size: f64,
        colour: [u8; 3],
    ) -> Result<(), VizError> {
        text::register_fonts();
        let (w, h) = (self.width, self.height);
        let root = BitMapBackend::with_buffer(&mut self.rgb, (w, h)).into_drawing_area();
        let colour = RGBColor(colour[0], colour[1], colour[2]);
        let style = text::font(size).color(&colour);
        root.draw_text(text, &style, (x, y)).map_err(draw_error)?;
        root.present().map_err(draw_error)
    }
}

pub(crate) fn check_size(width: u32, height: u32) -> Result<(), VizError> {
    if width == 0 || height == 0 || width > Image::MAX_SIDE || height > Image::MAX_SIDE {
        return Err(VizError::InvalidSize { width, height });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHITE: [u8; 3] = [255, 255, 255];

    #[test]
    fn png_starts_with_signature_and_ihdr_holds_the_size() {
        let mut img = Image::new(37, 21, [10, 200, 30]).unwrap();
        img.set_pixel(36, 20, [1, 2, 3]);
        let mut bytes = Vec::new();
        img.write_png(&mut bytes).unwrap();
        assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
        // The first chunk is IHDR: length (4 bytes), type, then width and height big-endian.
        assert_eq!(&bytes[12..16], b"IHDR");
        assert_eq!(u32::from_be_bytes(bytes[16..20].try_into().unwrap()), 37);
        assert_eq!(u32::from_be_bytes(bytes[20..24].try_into().unwrap()), 21);
    }

    #[test]
    fn grid_has_tiles_gaps_and_border() {
        let tiles: Vec<Image> = (0..7).map(|k| Image::new(30, 20, [k * 30, 0, 0]).unwrap()).collect();
        let sheet = Image::grid(&tiles, 3, 4, WHITE).unwrap();
        assert_eq!((sheet.width(), sheet.height()), (3 * 30 + 4 * 4, 3 * 20 + 4 * 4));
        assert_eq!(sheet.pixel(0, 0), WHITE);
        assert_eq!(sheet.pixel(4, 4), [0, 0, 0]);
        // Tile 4 is the middle of the second row.
        assert_eq!(sheet.pixel(4 + 34 + 5, 4 + 24 + 5), [120, 0, 0]);
        // The last row has one tile; the rest of it is background.
        assert_eq!(sheet.pixel(4 + 34 + 5, 4 + 48 + 5), WHITE);
    }

    #[test]
    fn grid_with_fewer_images_than_columns_is_one_row_wide_enough() {
        let tiles = vec![Image::new(10, 10, WHITE).unwrap(); 2];
        let sheet = Image::grid(&tiles, 5, 0, WHITE).unwrap();
        assert_eq!((sheet.width(), sheet.height()), (20, 10));
    }

    #[test]
    fn grid_rejects_mixed_sizes_and_empty_input() {
        let tiles = [Image::new(10, 10, WHITE).unwrap(), Image::new(11, 10, WHITE).unwrap()];
        assert!(matches!(Image::grid(&tiles, 2, 1, WHITE), Err(VizError::GridTileSize { index: 1, .. })));
        assert!(matches!(Image::grid(&[], 2, 1, WHITE), Err(VizError::EmptyGrid { .. })));
        assert!(matches!(Image::grid(&tiles[..1], 0, 1, WHITE), Err(VizError::EmptyGrid { .. })));
    }

    #[test]
    fn from_rgb_checks_length_and_new_checks_size() {
        assert!(matches!(Image::from_rgb(2, 2, vec![0; 11]), Err(VizError::BufferLength { .. })));
        assert!(Image::from_rgb(2, 2, vec![0; 12]).is_ok());
        assert!(matches!(Image::new(0, 5, WHITE), Err(VizError::InvalidSize { .. })));
    }

    #[test]
    fn label_draws_dark_pixels_near_its_anchor() {
        let mut img = Image::new(120, 40, WHITE).unwrap();
        img.label(5, 5, "t = 1.5 s", 20.0).unwrap();
        let dark =
            (0..40).flat_map(|y| (0..120).map(move |x| (x, y))).filter(|&(x, y)| img.pixel(x, y)[0] < 128);
        let (mut n, mut max_x) = (0, 0);
        for (x, _) in dark {
            n += 1;
            max_x = max_x.max(x);
        }
        assert!(n > 30, "only {n} dark pixels");
        assert!(max_x < 110, "text ran to column {max_x}");
    }
}
