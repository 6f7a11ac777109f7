//! A uniform grid over triangle bounding boxes, so that each particle's path is tested only against nearby
//! triangles. It changes no result: the candidates it returns are a superset of the triangles the path can
//! meet, and the exact test and tie-breaking stay those of the brute force.
//!
//! Two ways to bin: [`Binning::Spanning`] puts a triangle in every cell its box overlaps (for static
//! objects, built once, whose triangles may be large), and [`Binning::MinCorner`] puts it only in the cell
//! of its box's lowest corner, with cells as large as the largest box, so that a query widened by one cell
//! still finds it (for surfaces, whose boxes move and are rebinned every few steps: one entry per
//! triangle keeps a rebuild cheap).

use anima_geom::{Aabb, DVec3};

/// How triangles are put into cells.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum Binning {
    #[default]
    Spanning,
    MinCorner,
}

#[derive(Debug, Default, Clone)]
pub(crate) struct TriangleGrid {
    binning: Binning,
    origin: DVec3,
    inv_cell: f64,
    dims: [usize; 3],
    /// CSR layout: triangles of cell c are `entries[starts[c]..starts[c + 1]]`.
    starts: Vec<u32>,
    entries: Vec<u32>,
    /// Fill cursors, kept to avoid an allocation per rebuild.
    fill: Vec<u32>,
    /// Per-triangle stamp of the last query that returned it, for de-duplication.
    stamps: Vec<u32>,
    stamp: u32,
}

impl TriangleGrid {
    /// Rebuilds the grid for the given triangle boxes. Buffers are reused between steps.
    pub fn rebuild(&mut self, boxes: &[Aabb], binning: Binning) {
        self.binning = binning;
        let bounds = boxes.iter().fold(Aabb::EMPTY, |b, t| b.union(*t));
        self.stamps.clear();
        self.stamps.resize(boxes.len(), 0);
        self.stamp = 0;
        if boxes.is_empty() {
            self.dims = [0; 3];
            self.starts.clear();
            self.entries.clear();
            return;
        }
        // Cell size: spanning bins use the mean triangle extent, so a triangle covers a few cells;
        // min-corner bins need cells at least as large as the largest box. Either way the grid is capped
        // at about four cells per triangle.
        let extent = match binning {
            Binning::Spanning => {
                boxes.iter().map(|b| b.size().max_element()).sum::<f64>() / boxes.len() as f64
            }
            Binning::MinCorner => boxes.iter().map(|b| b.size().max_element()).fold(0.0, f64::max),
        };
        let size = bounds.size();
        let mut cell = extent.max(size.max_element() * 1e-6).max(f64::MIN_POSITIVE);
        let max_cells = (4 * boxes.len()).max(64) as f64;
        if !size.is_finite() {
            // A box with a non-finite corner, from a state the step is about to report as non-finite:
            // one cell holds every triangle (every index maps to it), so that the pass still ends.
            self.dims = [1, 1, 1];
            cell = f64::INFINITY;
        } else {
            loop {
                let d = (size / cell).floor() + DVec3::ONE;
                if d.x * d.y * d.z <= max_cells {
                    self.dims = [d.x as usize, d.y as usize, d.z as usize];
                    break;
                }
                cell *= 1.5;
            }
        }
        self.origin = bounds.min;
        self.inv_cell = 1.0 / cell;
        let n_cells = self.dims[0] * self.dims[1] * self.dims[2];
        self.starts.clear();
        self.starts.resize(n_cells + 1, 0);
        for b in boxes {
            let (lo, hi) = self.insert_range(b);
            for c in self.cells(lo, hi) {
                self.starts[c + 1] += 1;
            }
        }
        for c in 0..n_cells {
            self.starts[c + 1] += self.starts[c];
        }
        self.entries.clear();
        self.entries.resize(self.starts[n_cells] as usize, 0);
        self.fill.clear();
        self.fill.extend_from_slice(&self.starts);
        for (t, b) in boxes.iter().enumerate() {
            let (lo, hi) = self.insert_range(b);
            for c in self.cells(lo, hi) {
                self.entries[self.fill[c] as usize] = t as u32;
                self.fill[c] += 1;
            }
        }
    }

    /// Linear indices of the cells in the inclusive range lo..=hi.
    fn cells(&self, lo: [usize; 3], hi: [usize; 3]) -> impl Iterator<Item = usize> + use<> {
        let [dx, dy, _] = self.dims;
        (lo[2]..=hi[2]).flat_map(move |z| {
            (lo[1]..=hi[1]).flat_map(move |y| (lo[0]..=hi[0]).map(move |x| (z * dy + y) * dx + x))
        })
    }

    /// Cells a triangle with box `b` goes into.
    fn insert_range(&self, b: &Aabb) -> ([usize; 3], [usize; 3]) {
        match self.binning {
            Binning::Spanning => self.cell_range(b),
            Binning::MinCorner => {
                let (lo, _) = self.cell_range(b);
                (lo, lo)
            }
        }
    }

    /// Cells overlapped by a box, clamped to the grid (a box outside the grid maps to its border cells,
    /// which is safe because only triangles inside the grid exist).
    fn cell_range(&self, b: &Aabb) -> ([usize; 3], [usize; 3]) {
        let clamp =
            |v: f64, d: usize| -> usize { if v.is_nan() || v <= 0.0 { 0 } else { (v as usize).min(d - 1) } };
        let lo = (b.min - self.origin) * self.inv_cell;
        let hi = (b.max - self.origin) * self.inv_cell;
        (
            [clamp(lo.x, self.dims[0]), clamp(lo.y, self.dims[1]), clamp(lo.z, self.dims[2])],
            [clamp(hi.x, self.dims[0]), clamp(hi.y, self.dims[1]), clamp(hi.z, self.dims[2])],
        )
    }

    /// Calls `visit` once for every triangle whose cells the box overlaps.
    pub fn query(&mut self, b: &Aabb, mut visit: impl FnMut(usize)) {
        if self.dims[0] == 0 {
            return;
        }
        self.stamp = self.stamp.wrapping_add(1);
        if self.stamp == 0 {
            self.stamps.iter_mut().for_each(|s| *s = 0);
            self.stamp = 1;
        }
        let (mut lo, hi) = self.cell_range(b);
        if self.binning == Binning::MinCorner {
            // A box overlapping `b` has its lowest corner at most one cell below `b`'s, and it is in one
            // cell only, so no de-duplication is needed.
            lo = lo.map(|c| c.saturating_sub(1));
            for c in self.cells(lo, hi) {
                for &t in &self.entries[self.starts[c] as usize..self.starts[c + 1] as usize] {
                    visit(t as usize);
                }
            }
            return;
        }
        for c in self.cells(lo, hi) {
            for &t in &self.entries[self.starts[c] as usize..self.starts[c + 1] as usize] {
                let slot = &mut self.stamps[t as usize];
                if *slot != self.stamp {
                    *slot = self.stamp;
                    visit(t as usize);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box(at: f64) -> Aabb {
        Aabb { min: DVec3::splat(at), max: DVec3::splat(at + 1.0) }
    }

    #[test]
    fn a_non_finite_box_gives_one_cell_that_holds_everything() {
        // A state gone non-finite reaches the collision pass before the step reports it: the rebuild
        // must end (it once looked for a cell size forever) and still find every triangle.
        for bad in [f64::INFINITY, f64::NEG_INFINITY, f64::NAN] {
            for binning in [Binning::Spanning, Binning::MinCorner] {
                let broken = if bad < 0.0 {
                    Aabb { min: DVec3::new(0.0, bad, 0.0), max: DVec3::ONE }
                } else {
                    Aabb { min: DVec3::ZERO, max: DVec3::new(1.0, bad, 1.0) }
                };
                let boxes = [unit_box(0.0), broken, unit_box(5.0)];
                let mut grid = TriangleGrid::default();
                grid.rebuild(&boxes, binning);
                let mut found = Vec::new();
                grid.query(&unit_box(0.5), |t| found.push(t));
                found.sort_unstable();
                if bad.is_nan() {
                    // A NaN corner drops out of the bounds (min and max ignore it): an ordinary grid.
                    assert!(found.contains(&0), "{binning:?}");
                } else {
                    assert_eq!(grid.dims, [1, 1, 1]);
                    assert_eq!(found, vec![0, 1, 2], "{bad} {binning:?}");
                }
            }
        }
        // Finite boxes still get a grid of several cells.
        let boxes: Vec<Aabb> = (0..100).map(|i| unit_box(i as f64)).collect();
        let mut grid = TriangleGrid::default();
        grid.rebuild(&boxes, Binning::Spanning);
        assert!(grid.dims.iter().product::<usize>() > 1);
    }
}
