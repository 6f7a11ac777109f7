//! Oliveira 2013's three drapes (spec `adaptive-cloth.md` §7): one test table, one run loop, and the
//! reports built on them — the static meshes beside Tables 5.2/5.4/5.6 ([`drapes`]), the fine drapes
//! with implicit integrators ([`implicit`]) and the adaptive meshes ([`adaptive`]).

pub mod adaptive;
pub mod choices;
pub mod drapes;
pub mod implicit;
pub mod membrane;

use std::path::PathBuf;

use anima_cloth::oliveira::{OliveiraCloth, criteria::interpolate_at};
use anima_geom::{DVec2, DVec3};

pub use anima_run::drape::{Ended, object_meshes, run_drape, unremeshed};

use crate::repo::Repo;

/// One thesis test: its scene files and what the thesis printed about it.
#[derive(Debug)]
pub struct DrapeTest {
    pub number: usize,
    pub title: &'static str,
    /// The title of the implicit-integration report.
    pub short_title: &'static str,
    pub slug: &'static str,
    /// Snapshot times of Figs. 5.2, 5.7, 5.12, s; the last is the thesis's end time.
    pub snapshots: [f64; 4],
    pub figure: &'static str,
    /// The thesis's timing table: (mesh, total s, frames, s per frame).
    pub table: &'static str,
    pub thesis: &'static [(&'static str, f64, u64, f64)],
    /// Simulated time of the shortened adaptive runs (`ANIMA_ADAPTIVE_SHORT=1`), s.
    pub short: f64,
}

/// Tests I, II and III.
pub const TESTS: [DrapeTest; 3] = [
    DrapeTest {
        number: 1,
        title: "Test I — cloth on the Stanford Bunny",
        short_title: "Test I — Stanford Bunny",
        slug: "bunny",
        snapshots: [0.1, 0.25, 0.35, 0.5],
        figure: "Fig. 5.2",
        table: "Table 5.2",
        thesis: &[
            ("coarse 5 × 5", 24.8, 2236, 0.01109),
            ("adaptive", 10401.7, 134127, 0.07755),
            ("fine 17 × 17", 19237.7, 174312, 0.11036),
        ],
        short: 0.2,
    },
    DrapeTest {
        number: 2,
        title: "Test II — tablecloth on a round table",
        short_title: "Test II — round table",
        slug: "table",
        snapshots: [0.15, 0.5, 0.75, 1.0],
        figure: "Fig. 5.7",
        table: "Table 5.4",
        thesis: &[
            ("coarse 5 × 5", 14.3, 4391, 0.00326),
            ("adaptive", 35986.4, 1020828, 0.03525),
            ("fine 17 × 17", 13870.7, 346795, 0.03999),
        ],
        short: 0.2,
    },
    DrapeTest {
        number: 3,
        title: "Test III — cloth on a sphere",
        short_title: "Test III — sphere",
        slug: "sphere",
        snapshots: [0.15, 0.3, 0.45, 0.6],
        figure: "Fig. 5.12",
        table: "Table 5.6",
        thesis: &[("1-to-4 subdivision", 20086.4, 122509, 0.16395), ("remeshing", 21204.5, 269071, 0.07880)],
        short: 0.3,
    },
];

impl DrapeTest {
    /// The scene file of the `n` × `n` mesh (5 and 17 are shipped).
    pub fn scene_path(&self, repo: &Repo, n: usize) -> PathBuf {
        repo.assets(format!("oliveira/test-{}-{}-{n}x{n}.ron", self.number, self.slug))
    }

    /// "I", "II" or "III".
    pub fn roman(&self) -> &'static str {
        ["I", "II", "III"][self.number - 1]
    }

    /// The thesis's wall time for its finest drape, s: the fine mesh of Tables 5.2 and 5.4; Test III
    /// ran no fine mesh, so its remeshing run.
    pub fn thesis_fine_s(&self) -> f64 {
        self.thesis.iter().find(|r| r.0.starts_with("fine")).unwrap_or(&self.thesis[self.thesis.len() - 1]).1
    }

    /// Tests selected by the suffix of an experiment name: "" or "-all" for all three, "-1", "-2", "-3".
    pub fn select(which: &str) -> Option<Vec<&'static DrapeTest>> {
        match which {
            "" | "-all" => Some(TESTS.iter().collect()),
            "-1" => Some(vec![&TESTS[0]]),
            "-2" => Some(vec![&TESTS[1]]),
            "-3" => Some(vec![&TESTS[2]]),
            _ => None,
        }
    }
}

/// The 25 material points of the coarse 5 × 5 grid, in material coordinates (m).
pub fn material_points() -> Vec<DVec2> {
    (0..5).flat_map(|r| (0..5).map(move |c| DVec2::new(c as f64 * 0.25, r as f64 * 0.25))).collect()
}

/// Where the cloth has the 25 material points now.
pub fn at_material_points(cloth: &OliveiraCloth) -> Vec<DVec3> {
    material_points()
        .iter()
        .map(|&p| interpolate_at(cloth.mesh().rest(), cloth.triangles(), cloth.positions(), p))
        .collect()
}

/// RMS distance between two lists of corresponding points, over all of them.
pub fn rms(a: &[Vec<DVec3>], b: &[Vec<DVec3>]) -> f64 {
    let (mut s, mut n) = (0.0, 0);
    for (pa, pb) in a.iter().zip(b) {
        for (x, y) in pa.iter().zip(pb) {
            s += x.distance_squared(*y);
            n += 1;
        }
    }
    (s / n.max(1) as f64).sqrt()
}
