//! Triangle fill into a colour and depth buffer: half-space (edge function) rasterisation at pixel
//! centres, one flat colour per triangle, optional anti-aliased edge lines drawn inside the triangle.

/// A projected vertex: pixel coordinates (x right, y down) and a depth key that is affine in screen
/// space and larger for nearer points (1/distance for perspective, camera z for orthographic).
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScreenVertex {
    pub x: f64,
    pub y: f64,
    pub key: f64,
}

/// Edge lines as the rasteriser draws them.
#[derive(Debug, Clone, Copy)]
pub(crate) struct EdgeStyle {
    pub colour: [f32; 3],
    /// Half the line width in buffer pixels.
    pub half_width: f64,
    /// Opacity of a line at full coverage.
    pub opacity: f32,
    /// Triangles smaller than about this many buffer pixels across get fainter edges, so that a fine
    /// mesh reads as a surface instead of a dark mesh of lines.
    pub fade_size: f64,
}

/// The colour and depth buffers being drawn into.
#[derive(Debug)]
pub(crate) struct Target {
    pub width: usize,
    pub height: usize,
    pub rgb: Vec<[f32; 3]>,
    pub depth: Vec<f32>,
}

impl Target {
    pub fn new(width: usize, height: usize) -> Self {
        let n = width * height;
        Self { width, height, rgb: vec![[0.0; 3]; n], depth: vec![f32::NEG_INFINITY; n] }
    }

    /// Fills one triangle. Bit k of `real_edges` says whether the edge from vertex k to vertex k + 1 is an
    /// edge of the original mesh (and not one made by clipping); only those get edge lines.
    pub fn triangle(
        &mut self,
        v: [ScreenVertex; 3],
        real_edges: u8,
        colour: [f32; 3],
        edge: Option<&EdgeStyle>,
    ) {
        let [a, mut b, mut c] = v;
        let mut area = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
        let mut mask = real_edges;
        if !area.is_finite() || area.abs() < 1e-12 {
            return;
        }
        if area < 0.0 {
            // Make the winding positive in pixel space; the edges a→b, b→c, c→a become c→a, b→c, a→b.
            std::mem::swap(&mut b, &mut c);
            area = -area;
            mask = ((mask & 1) << 2) | (mask & 2) | ((mask >> 2) & 1);
        }

        let (w, h) = (self.width as f64, self.height as f64);
        let min_x = a.x.min(b.x).min(c.x).max(0.0).floor();
        let max_x = a.x.max(b.x).max(c.x).min(w).ceil();
        let min_y = a.y.min(b.y).min(c.y).max(0.0).floor();
        let max_y = a.y.max(b.y).max(c.y).min(h).ceil();
        if min_x >= max_x || min_y >= max_y {
            return;
        }
        let (x0, x1, y0, y1) = (min_x as usize, max_x as usize, min_y as usize, max_y as usize);

        // Edge function of the edge p→q at s: positive on the triangle's side.
        let edge_fn = |p: ScreenVertex, q: ScreenVertex, sx: f64, sy: f64| {
            (q.x - p.x) * (sy - p.y) - (q.y - p.y) * (sx - p.x)
        };
        let (px, py) = (x0 as f64 + 0.5, y0 as f64 + 0.5);
        // e_bc weighs a, e_ca weighs b, e_ab weighs c.
        let row_start = [edge_fn(b, c, px, py), edge_fn(c, a, px, py), edge_fn(a, b, px, py)];
        let step_x = [-(c.y - b.y), -(a.y - c.y), -(b.y - a.y)];
        let step_y = [c.x - b.x, a.x - c.x, b.x - a.x];
        let inv_area = 1.0 / area;
        let key_x = (a.key * step_x[0] + b.key * step_x[1] + c.key * step_x[2]) * inv_area;
        let key_start = (a.key * row_start[0] + b.key * row_start[1] + c.key * row_start[2]) * inv_area;
        let key_y = (a.key * step_y[0] + b.key * step_y[1] + c.key * step_y[2]) * inv_area;

        // For edge lines: 1/length turns an edge function into a distance in pixels. Edge i of the
        // positive-winding triangle is bc, ca, ab, i.e. bit (i + 1) % 3 of the mask.
        let lines = edge.map(|style| {
            let len = [dist(b, c), dist(c, a), dist(a, b)];
            let inv = std::array::from_fn::<f64, 3, _>(|i| {
                if mask & (1 << ((i + 1) % 3)) != 0 && len[i] > 0.0 { 1.0 / len[i] } else { 0.0 }
            });
            let size = (area / 2.0).sqrt();
            let fade = ((size - 0.25 * style.fade_size) / (0.75 * style.fade_size)).clamp(0.0, 1.0) as f32;
            (inv, style.opacity * fade, style)
        });
        let lines = lines.filter(|(inv, opacity, _)| *opacity > 0.0 && inv.iter().any(|&k| k > 0.0));

        let mut e_row = row_start;
        let mut key_row = key_start;
        for y in y0..y1 {
            let mut e = e_row;
            let mut key = key_row;
            let line = y * self.width;
            for x in x0..x1 {
                if e[0] >= 0.0 && e[1] >= 0.0 && e[2] >= 0.0 {
                    let i = line + x;
                    let z = key as f32;
                    if z > self.depth[i] {
                        self.depth[i] = z;
                        self.rgb[i] = match &lines {
                            None => colour,
                            Some((inv, opacity, style)) => {
                                let d = (0..3)
                                    .filter(|&k| inv[k] > 0.0)
                                    .map(|k| e[k] * inv[k])
                                    .fold(f64::INFINITY, f64::min);
                                let coverage = (style.half_width + 0.5 - d).clamp(0.0, 1.0) as f32 * opacity;
                                std::array::from_fn(|k| colour[k] + (style.colour[k] - colour[k]) * coverage)
                            }
                        };
                    }
                }
                e = [e[0] + step_x[0], e[1] + step_x[1], e[2] + step_x[2]];
                key += key_x;
            }
            e_row = [e_row[0] + step_y[0], e_row[1] + step_y[1], e_row[2] + step_y[2]];
            key_row += key_y;
        }
    }

    /// Averages `factor × factor` blocks into 8-bit RGB.
    pub fn downsample(&self, factor: usize) -> Vec<u8> {
        let (w, h) = (self.width / factor, self.height / factor);
        let norm = 1.0 / (factor * factor) as f32;
        let mut out = Vec::with_capacity(3 * w * h);
        for y in 0..h {
            for x in 0..w {
                let mut sum = [0.0f32; 3];
                for sy in 0..factor {
                    let row = (y * factor + sy) * self.width + x * factor;
                    for p in &self.rgb[row..row + factor] {
                        sum = [sum[0] + p[0], sum[1] + p[1], sum[2] + p[2]];
                    }
                }
                out.extend(sum.map(|s| (s * norm).round().clamp(0.0, 255.0) as u8));
            }
        }
        out
    }
}

fn dist(p: ScreenVertex, q: ScreenVertex) -> f64 {
    (q.x - p.x).hypot(q.y - p.y)
}
