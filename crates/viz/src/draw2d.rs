//! 2-D drawing onto an [`Image`]: filled convex polygons, thick lines and discs, with a mapping from
//! world metres (x right, y up) to pixels. Enough for stick and box figures (no anti-aliasing).

use crate::image::Image;

/// World → pixel mapping: `scale` pixels per metre, world point (`x_min`, `y_min`) at the bottom-left
/// corner of a picture `height` pixels high. Pixel rows grow downwards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct View2d {
    pub x_min: f64,
    pub y_min: f64,
    pub scale: f64,
    pub height: u32,
}

impl View2d {
    /// The largest uniform scale that shows the world box [x0, x1] × [y0, y1] inside a `width` ×
    /// `height` picture with `margin` pixels on every side, centred.
    pub fn fit(x0: f64, y0: f64, x1: f64, y1: f64, width: u32, height: u32, margin: u32) -> Self {
        let (w, h) = ((x1 - x0).max(1e-9), (y1 - y0).max(1e-9));
        let (aw, ah) = (
            f64::from(width.saturating_sub(2 * margin).max(1)),
            f64::from(height.saturating_sub(2 * margin).max(1)),
        );
        let scale = (aw / w).min(ah / h);
        // Centre the box: shift the origin so that the unused space is split evenly.
        let x_min = x0 - (f64::from(width) / scale - w) / 2.0;
        let y_min = y0 - (f64::from(height) / scale - h) / 2.0;
        Self { x_min, y_min, scale, height }
    }

    /// Pixel coordinates (column, row), fractional, of world point (x, y).
    pub fn to_px(&self, x: f64, y: f64) -> (f64, f64) {
        ((x - self.x_min) * self.scale, f64::from(self.height) - (y - self.y_min) * self.scale)
    }
}

/// Fills the convex or concave polygon with pixel-space vertices `pts` (even–odd rule, pixel centres).
pub fn fill_polygon(img: &mut Image, pts: &[(f64, f64)], colour: [u8; 3]) {
    if pts.len() < 3 {
        return;
    }
    let (h, w) = (img.height() as i64, img.width() as i64);
    let y_lo = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min).floor().max(0.0) as i64;
    let y_hi = (pts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max).ceil() as i64).min(h - 1);
    let mut xs: Vec<f64> = Vec::with_capacity(pts.len());
    for row in y_lo..=y_hi {
        let yc = row as f64 + 0.5;
        xs.clear();
        for k in 0..pts.len() {
            let (a, b) = (pts[k], pts[(k + 1) % pts.len()]);
            if (a.1 <= yc) != (b.1 <= yc) {
                xs.push(a.0 + (yc - a.1) * (b.0 - a.0) / (b.1 - a.1));
            }
        }
        xs.sort_by(f64::total_cmp);
        for pair in xs.chunks_exact(2) {
            let x0 = (pair[0] - 0.5).ceil().max(0.0) as i64;
            let x1 = ((pair[1] - 0.5).floor() as i64).min(w - 1);
            for col in x0..=x1 {
                img.set_pixel(col as u32, row as u32, colour);
            }
        }
    }
}

/// A line from `a` to `b` (pixels) `width` pixels thick, drawn as a filled quadrilateral.
pub fn draw_line(img: &mut Image, a: (f64, f64), b: (f64, f64), width: f64, colour: [u8; 3]) {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len = dx.hypot(dy);
    if len == 0.0 {
        fill_disc(img, a, width / 2.0, colour);
        return;
    }
    let (nx, ny) = (-dy / len * width / 2.0, dx / len * width / 2.0);
    fill_polygon(
        img,
        &[(a.0 + nx, a.1 + ny), (b.0 + nx, b.1 + ny), (b.0 - nx, b.1 - ny), (a.0 - nx, a.1 - ny)],
        colour,
    );
}

/// A filled disc of `radius` pixels centred at `c` (pixels).
pub fn fill_disc(img: &mut Image, c: (f64, f64), radius: f64, colour: [u8; 3]) {
    let (h, w) = (img.height() as i64, img.width() as i64);
    let (y0, y1) = (((c.1 - radius).floor() as i64).max(0), ((c.1 + radius).ceil() as i64).min(h - 1));
    let (x0, x1) = (((c.0 - radius).floor() as i64).max(0), ((c.0 + radius).ceil() as i64).min(w - 1));
    for row in y0..=y1 {
        for col in x0..=x1 {
            let (dx, dy) = (col as f64 + 0.5 - c.0, row as f64 + 0.5 - c.1);
            if dx * dx + dy * dy <= radius * radius {
                img.set_pixel(col as u32, row as u32, colour);
            }
        }
    }
}

/// The outline of the polygon `pts` (pixels), `width` pixels thick.
pub fn stroke_polygon(img: &mut Image, pts: &[(f64, f64)], width: f64, colour: [u8; 3]) {
    for k in 0..pts.len() {
        draw_line(img, pts[k], pts[(k + 1) % pts.len()], width, colour);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHITE: [u8; 3] = [255, 255, 255];
    const RED: [u8; 3] = [200, 0, 0];

    #[test]
    fn a_filled_square_covers_its_pixels_and_nothing_else() {
        let mut img = Image::new(20, 20, WHITE).unwrap();
        fill_polygon(&mut img, &[(5.0, 5.0), (15.0, 5.0), (15.0, 15.0), (5.0, 15.0)], RED);
        let n = (0..20)
            .flat_map(|y| (0..20).map(move |x| (x, y)))
            .filter(|&(x, y)| img.pixel(x, y) == RED)
            .count();
        assert_eq!(n, 100);
        assert_eq!(img.pixel(5, 5), RED);
        assert_eq!(img.pixel(4, 5), WHITE);
        assert_eq!(img.pixel(15, 15), WHITE);
    }

    #[test]
    fn the_view_puts_y_up_and_fits_the_box() {
        let v = View2d::fit(0.0, 0.0, 2.0, 1.0, 200, 100, 0);
        assert_eq!(v.scale, 100.0);
        assert_eq!(v.to_px(0.0, 0.0), (0.0, 100.0));
        assert_eq!(v.to_px(2.0, 1.0), (200.0, 0.0));
        // A square box in a wide picture is centred horizontally.
        let v = View2d::fit(0.0, 0.0, 1.0, 1.0, 300, 100, 0);
        assert_eq!(v.to_px(0.5, 0.5), (150.0, 50.0));
    }

    #[test]
    fn discs_and_lines_are_clipped_to_the_picture() {
        let mut img = Image::new(10, 10, WHITE).unwrap();
        fill_disc(&mut img, (0.0, 0.0), 4.0, RED);
        draw_line(&mut img, (-5.0, 5.0), (50.0, 5.0), 2.0, RED);
        assert_eq!(img.pixel(0, 0), RED);
        assert_eq!(img.pixel(9, 5), RED);
        assert_eq!(img.pixel(9, 9), WHITE);
    }
}
