//! Rectangular particle grids placed by centre, normal and spacing (Nedel 1993 §3.1, §5.5).

use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Which way row indices run within the surface plane. The thesis gives only a normal, so this is a
/// reconstruction (spec S2.3, ambiguity ): with `Down`, row 0 is the top edge of a curtain whose
/// normal is +z, which is what the curtain scenes need.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum RowDirection {
    /// e_i = e_j × n (row 0 at the top for a +z normal). The default.
    #[default]
    Down,
    /// e_i = n × e_j (row 0 at the bottom for a +z normal).
    Up,
}

/// The in-plane axes of a grid: columns advance along `e_j`, rows along `e_i`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridFrame {
    pub centre: DVec3,
    pub normal: DVec3,
    pub e_i: DVec3,
    pub e_j: DVec3,
}

impl GridFrame {
    /// The FLEX3D convention (spec S2.3): e_j is world x projected onto the plane (world −z when the
    /// normal is almost along x), e_i = e_j × n for [`RowDirection::Down`].
    ///
    /// Returns `None` when the normal is zero or not finite.
    pub fn from_normal(centre: DVec3, normal: DVec3, rows: RowDirection) -> Option<Self> {
        let n = normal.try_normalize()?;
        let x = if n.dot(DVec3::X).abs() > 0.999 { DVec3::NEG_Z } else { DVec3::X };
        let e_j = (x - n * x.dot(n)).normalize();
        let e_i = match rows {
            RowDirection::Down => e_j.cross(n),
            RowDirection::Up => n.cross(e_j),
        };
        Some(Self { centre, normal: n, e_i, e_j })
    }
}

/// An `rows × cols` grid with spacing `spacing`, centred on `frame.centre`. Particle (i, j) has index
/// `i·cols + j` (row-major), as FLEX3D stored its matrix M.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfaceGrid {
    pub rows: usize,
    pub cols: usize,
    pub spacing: f64,
    pub frame: GridFrame,
}

impl SurfaceGrid {
    #[inline]
    pub fn index(&self, i: usize, j: usize) -> usize {
        i * self.cols + j
    }

    pub fn n_particles(&self) -> usize {
        self.rows * self.cols
    }

    /// Rest positions: P_ij = C + (j − (n−1)/2)·r·e_j + (i − (m−1)/2)·r·e_i.
    pub fn positions(&self) -> Vec<DVec3> {
        let (m, n, r) = (self.rows as f64, self.cols as f64, self.spacing);
        let f = &self.frame;
        let mut out = Vec::with_capacity(self.n_particles());
        for i in 0..self.rows {
            for j in 0..self.cols {
                let a = (j as f64 - (n - 1.0) / 2.0) * r;
                let b = (i as f64 - (m - 1.0) / 2.0) * r;
                out.push(f.centre + f.e_j * a + f.e_i * b);
            }
        }
        out
    }

    /// Two triangles per cell, split along the (i, j)–(i+1, j+1) diagonal (spec S2.4):
    /// T1 = [(i,j), (i+1,j), (i+1,j+1)], T2 = [(i,j), (i+1,j+1), (i,j+1)]; 2(m−1)(n−1) in all.
    pub fn triangles(&self) -> Vec<[u32; 3]> {
        grid_triangles(self.rows, self.cols)
    }
}

/// The triangulation of [`SurfaceGrid::triangles`] for any `rows × cols` row-major grid.
pub fn grid_triangles(rows: usize, cols: usize) -> Vec<[u32; 3]> {
    let mut out = Vec::with_capacity(2 * rows.saturating_sub(1) * cols.saturating_sub(1));
    for i in 0..rows.saturating_sub(1) {
        for j in 0..cols.saturating_sub(1) {
            let p = (i * cols + j) as u32;
            let below = p + cols as u32;
            out.push([p, below, below + 1]);
            out.push([p, below + 1, p + 1]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curtain_spans_the_spec_worked_example() {
        // Spec S2.3: 20×20, r = 1.85, C = (−55, 40, 20), normal +z → x ∈ [−72.575, −37.425], y ∈ [22.425, 57.575].
        let frame =
            GridFrame::from_normal(DVec3::new(-55.0, 40.0, 20.0), DVec3::Z, RowDirection::Down).unwrap();
        let g = SurfaceGrid { rows: 20, cols: 20, spacing: 1.85, frame };
        let p = g.positions();
        let first = p[g.index(0, 0)];
        let last = p[g.index(19, 19)];
        assert!((first - DVec3::new(-72.575, 57.575, 20.0)).length() < 1e-12, "{first}");
        assert!((last - DVec3::new(-37.425, 22.425, 20.0)).length() < 1e-12, "{last}");
    }

    #[test]
    fn horizontal_sheet_has_rows_along_z() {
        let frame =
            GridFrame::from_normal(DVec3::new(0.0, 15.0, -1.0), DVec3::Y, RowDirection::Down).unwrap();
        assert!((frame.e_j - DVec3::X).length() < 1e-15);
        assert!((frame.e_i - DVec3::Z).length() < 1e-15);
        let up = GridFrame::from_normal(DVec3::ZERO, DVec3::Z, RowDirection::Up).unwrap();
        assert!((up.e_i - DVec3::Y).length() < 1e-15);
    }

    #[test]
    fn triangulation_counts_and_orientation() {
        let t = grid_triangles(3, 4);
        assert_eq!(t.len(), 2 * 2 * 3);
        assert_eq!(t[0], [0, 4, 5]);
        assert_eq!(t[1], [0, 5, 1]);
        assert!(GridFrame::from_normal(DVec3::ZERO, DVec3::ZERO, RowDirection::Down).is_none());
    }
}
