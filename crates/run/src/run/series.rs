//! Per-frame numbers of a run, written as `series.json` beside the summary: the summary keeps totals
//! and extremes, this file the same quantities frame by frame (what `anima view` plots).
//!
//! The file is `{"time_s": [t_0, …], "series": [{"name", "unit", "values": [v_0, …]}, …]}`, one value
//! per series at each time, frame 0 (the start) first; a value that could not be had is `null` (a
//! self-intersection count abandoned for its work budget).

use std::path::Path;

use anyhow::Result;
use serde::Serialize;

use crate::output::write_atomic;

/// The file a run's series go to, in its output folder.
pub const SERIES_FILE: &str = "series.json";

/// A run's per-frame series, filled a frame at a time.
#[derive(Debug, Clone, Serialize)]
pub struct FrameSeries {
    pub time_s: Vec<f64>,
    pub series: Vec<Series>,
}

/// One quantity over the frames.
#[derive(Debug, Clone, Serialize)]
pub struct Series {
    pub name: String,
    pub unit: &'static str,
    /// `None` where the value could not be had (written as `null`).
    pub values: Vec<Option<f64>>,
}

impl FrameSeries {
    /// Empty series of these names and units.
    pub fn new(names: impl IntoIterator<Item = (String, &'static str)>) -> Self {
        let series =
            names.into_iter().map(|(name, unit)| Series { name, unit, values: Vec::new() }).collect();
        Self { time_s: Vec::new(), series }
    }

    /// The frame at `time_s`, one value for each series in order.
    pub fn push(&mut self, time_s: f64, values: &[Option<f64>]) {
        debug_assert_eq!(values.len(), self.series.len());
        self.time_s.push(time_s);
        for (s, v) in self.series.iter_mut().zip(values) {
            s.values.push(v.filter(|v| v.is_finite()));
        }
    }

    /// Writes `dir/series.json`, whole.
    pub fn write(&self, dir: &Path) -> Result<()> {
        write_atomic(&dir.join(SERIES_FILE), |w| {
            serde_json::to_writer(&mut *w, self)?;
            writeln!(w)?;
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use std::path::{Path, PathBuf};

    use anima_scene::{LoadOptions, Scene};
    use serde_json::Value;

    use crate::run::{Detail, Overrides, RunOptions, Silent, Summary, run};

    fn scene(rel: &str, duration_s: f64) -> Scene {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets").join(rel);
        let mut scene = anima_scene::load(&path, &LoadOptions::default()).unwrap();
        Overrides { duration: Some(duration_s), ..Overrides::default() }.apply(&mut scene).unwrap();
        scene
    }

    fn temp_dir(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("anima-series-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }

    /// Runs `assets/<rel>` for `duration_s`, pictures off, into a fresh folder named after `name`: the
    /// folder, the summary and the run's series.
    fn run_with_series(rel: &str, duration_s: f64, name: &str) -> (PathBuf, Summary, Value) {
        let dir = temp_dir(name);
        let opts = RunOptions { pictures: false, ..RunOptions::writing_to(&dir) };
        let summary = run(&scene(rel, duration_s), "t", &opts, &mut Silent).unwrap();
        let series: Value =
            serde_json::from_slice(&std::fs::read(dir.join(super::SERIES_FILE)).unwrap()).unwrap();
        (dir, summary, series)
    }

    /// The most crossings at a frame after frame 0 are the summary's largest (frame 0's are not counted
    /// there).
    fn assert_largest_crossings_are_the_summarys(series: &Value, summary: &Summary) {
        let crossings = values(series, "self-intersections");
        assert_eq!(
            crossings[1..].iter().copied().fold(0.0, f64::max),
            summary.self_intersections.unwrap() as f64
        );
    }

    fn values(series: &Value, name: &str) -> Vec<f64> {
        let s = series["series"].as_array().unwrap().iter().find(|s| s["name"] == name).unwrap();
        s["values"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect()
    }

    #[test]
    fn a_sheet_run_writes_a_value_per_frame_from_frame_0_that_ends_where_the_summary_does() {
        let (dir, summary, series) = run_with_series("scenes/standard-sheet-32.ron", 0.2, "sheet");
        let t: Vec<f64> = series["time_s"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
        assert_eq!(t.len(), summary.frames + 1, "frame 0 and every frame");
        assert_eq!((t[0], *t.last().unwrap()), (0.0, summary.simulated_seconds));
        let energy = values(&series, "kinetic energy");
        let Detail::Sheet(d) = &summary.detail else { panic!("a sheet") };
        assert_eq!((energy[0], *energy.last().unwrap()), (0.0, d.kinetic_energy));
        assert_eq!(values(&series, "self-intersections").len(), t.len());
        assert_largest_crossings_are_the_summarys(&series, &summary);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_remeshed_drape_writes_its_energy_crossings_and_vertex_count_per_frame() {
        let (dir, summary, series) = run_with_series("oliveira/test-2-table-adaptive.ron", 0.1, "drape");
        let Detail::Oliveira(d) = &summary.detail else { panic!("a drape") };
        let vertices = values(&series, "vertices");
        assert_eq!(vertices.len(), summary.frames + 1);
        assert_eq!(
            (vertices[0], *vertices.last().unwrap()),
            (d.particles_at_start as f64, d.particles as f64)
        );
        assert_eq!(*values(&series, "kinetic energy").last().unwrap(), d.kinetic_energy);
        assert_largest_crossings_are_the_summarys(&series, &summary);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_flex3d_run_writes_its_energy_and_crossings_per_frame() {
        let (dir, summary, series) = run_with_series("flex3d/curtain.ron", 0.2, "flex3d");
        let Detail::Flex3d(d) = &summary.detail else { panic!("a FLEX3D scene") };
        let energy = values(&series, "kinetic energy");
        assert_eq!(energy.len(), summary.frames + 1);
        assert_eq!(*energy.last().unwrap(), d.kinetic_energy);
        assert_eq!(values(&series, "self-intersections").len(), energy.len());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_walk_writes_the_pelvis_and_contacts_at_each_picture_frame() {
        let (dir, _, series) = run_with_series("scenes/walk.ron", 2.0, "walk");
        let t = series["time_s"].as_array().unwrap();
        // The walk's frames are 0.5 s apart: 0, 0.5, …, 2.
        assert_eq!(t.len(), 5, "{series}");
        let height = values(&series, "pelvis height");
        assert!(height.iter().all(|h| (0.8..1.1).contains(h)), "{height:?}");
        assert!(values(&series, "pelvis speed")[4] > 0.5, "walking");
        assert!(values(&series, "contacts")[1..].iter().all(|&c| c >= 1.0), "a foot on the ground");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
