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
