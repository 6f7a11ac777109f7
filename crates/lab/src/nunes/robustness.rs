//! The first part of issue #18's robustness protocol, SIMBICON's push: the largest push on the torso
//! at the height of the centre of mass, over 0.2 s, that each committed walker survives forward and
//! backward, in N·s and as the velocity change Δv = J/m it gives the whole body, beside the thesis's
//! push on the head (0.1 s). Survived: still up 10 s after a push given 20 s into the walk, in steps of
//! 5 N·s up to the first push that fells it.
//!
//! Then its terrains: each walker for 60 s on ground that slopes at ±5° and ±10°, and over flights of
//! 5 cm steps up and down, each beginning 2 m ahead of where it starts.
//!
//! `cargo xtask reproduce nunes-robustness` writes `docs/reproduction/nunes-robustness.md`.

use anima_body::{BuiltinSkeleton, Ground, Relief, WorldSettings};
use anima_character::{Character, CharacterError};
use anima_control::Controller;
use anyhow::Result;

use super::{self as nunes, Push, faithful, protocol};
use crate::repo::Repo;

/// The report this study writes, under `docs/`.
pub const REPORT: &str = "reproduction/nunes-robustness.md";

const STEP: f64 = 5.0;
const MAX: f64 = 400.0;

type BuildOn = protocol::Build;

/// Seconds walked on each terrain.
const TERRAIN_SECONDS: f64 = 60.0;

fn simbicon_humanoid_on(c: Controller, g: Ground) -> Result<Character, CharacterError> {
    let settings = WorldSettings { ground: Some(g), ..faithful::world_settings() };
    faithful::character(c, &faithful::skeleton(), settings)
}

/// A walk of [`TERRAIN_SECONDS`] on `relief`: "✓ (d m)" when it stays up, "falls at t s" when not;
/// walked (`true`) when it stays up and covers at least 30 m (half of what 1.0 m/s would).
fn on_terrain(c: &Controller, build: BuildOn, relief: Relief) -> (bool, String) {
    let steps = (TERRAIN_SECONDS / nunes::DT).round() as u64;
    match protocol::walk_on(c, build, relief, steps, &[]) {
        (f, d) if f >= 1.0 => (d >= 0.5 * protocol::TARGET_SPEED * TERRAIN_SECONDS, format!("✓ {d:.0} m")),
        (f, _) => (false, format!("falls at {:.1} s", f * TERRAIN_SECONDS)),
    }
}

/// Runs the study, printing each row as it ends, and writes [`REPORT`].
pub fn reproduce(repo: &Repo) -> Result<()> {
    let doc = document()?;
    repo.write_text(std::path::Path::new("docs").join(REPORT), &doc)
}

/// The report's text: every committed walker pushed and walked on the terrains.
pub fn document() -> Result<String> {
    let walkers: [(&str, &str, BuildOn, f64); 6] = [
        (
            "thesis's search (`walk-optimised.ron`)",
            "walk-optimised",
            protocol::humanoid,
            BuiltinSkeleton::Humanoid.load().total_mass(),
        ),
        (
            "thesis's machines, robust search (`walk-robust.ron`)",
            "walk-robust",
            protocol::humanoid,
            BuiltinSkeleton::Humanoid.load().total_mass(),
        ),
        (
            "SIMBICON form (`walk-simbicon.ron`)",
            "walk-simbicon",
            protocol::humanoid,
            BuiltinSkeleton::Humanoid.load().total_mass(),
        ),
        (
            "thesis's machines searched for the protocol (`walk-protocol.ron`)",
            "walk-protocol",
            protocol::humanoid,
            BuiltinSkeleton::Humanoid.load().total_mass(),
        ),
        (
            "the same, leaning into slopes (`walk-slopes.ron`)",
            "walk-slopes",
            protocol::humanoid,
            BuiltinSkeleton::Humanoid.load().total_mass(),
        ),
        (
            "SIMBICON as published (`walk-simbicon-faithful.ron`)",
            "walk-simbicon-faithful",
            simbicon_humanoid_on,
            faithful::skeleton().total_mass(),
        ),
    ];
    let mut doc = String::from(
        "# Robustness: SIMBICON's push, slopes and steps on anima's walkers\n\n\
         Written by `cargo xtask reproduce nunes-robustness`; do not edit by hand.\n\n\
         The first part of issue #18's protocol. Yin, Loken & van de Panne (2007) report a SIMBICON walker \
         surviving a push of 350 N for 0.2 s on the torso (70 N·s). Here each committed walker is pushed \
         20 s into its walk, horizontally, on the abdomen at the height of the whole body's centre of mass \
         for 0.2 s (4 control steps), and counts as surviving when it is still up 10 s later; pushes grow \
         in steps of 5 N·s to the first that fells it. Δv = J/m is the velocity change the push gives the \
         whole body. The thesis's push, on the head for 0.1 s, is beside it.\n\n\
         | walker | mass (kg) | mean speed (m/s) | torso push survived, forward / backward (N·s) | Δv forward / backward (m/s) | head push survived, forward / backward (N·s) |\n\
         |---|---|---|---|---|---|\n",
    );
    let mut simbicon_sized = Vec::new();
    let mut terrain_rows = String::new();
    let mut everywhere = Vec::new();
    let (at, recovery) = (protocol::PUSH_AT, protocol::PUSH_RECOVERY);
    for (name, file, build_on, mass) in walkers {
        let c = nunes::controller(file)?;
        let (_, distance) = protocol::walk_on(&c, build_on, Relief::Flat, at + recovery, &[]);
        let speed = distance / ((at + recovery) as f64 * nunes::DT);
        let largest = |push: &dyn Fn(f64) -> Push| protocol::largest_push(&c, build_on, push, STEP, MAX);
        let (tf, tb) = (largest(&|j| Push::torso(j, at, 4)), largest(&|j| Push::torso(-j, at, 4)));
        let (hf, hb) = (largest(&|j| Push::impulse(j, at, 2)), largest(&|j| Push::impulse(-j, at, 2)));
        let row = format!(
            "| {name} | {mass:.1} | {speed:.2} | {tf:.0} / {tb:.0} | {:.2} / {:.2} | {hf:.0} / {hb:.0} |\n",
            tf / mass,
            tb / mass
        );
        print!("{row}");
        doc += &row;
        if tf >= 70.0 && tb >= 70.0 {
            simbicon_sized.push(file);
        }
        let mut row = format!("| {name} |");
        let mut all = true;
        for (_, relief) in protocol::terrains() {
            let (up, cell) = on_terrain(&c, build_on, relief);
            all &= up;
            row += &format!(" {cell} |");
        }
        println!("{row}");
        terrain_rows += &row;
        terrain_rows.push('\n');
        if all {
            everywhere.push(file);
        }
    }
    doc += &if simbicon_sized.is_empty() {
        "\nNone of them survives SIMBICON's 70 N·s both forward and backward.".to_string()
    } else {
        format!("\nSurviving SIMBICON's 70 N·s both ways: {}.", simbicon_sized.join(", "))
    };
    doc += &format!(
        "\n\n## Slopes and steps\n\n\
         Each walker for {TERRAIN_SECONDS:.0} s on ground that is flat for its first 2 m and then slopes (the \
         whole way) or rises or falls in 5 cm steps every 2 m; ✓ with the distance walked when it is still \
         up at the end, or when it fell. The fall test is the walks' (a body other than a foot on the \
         ground, or the pelvis less than 0.7 m above the ground under it). No walker here was tuned for \
         any of this.\n\n\
         | walker |"
    );
    for (label, _) in protocol::terrains() {
        doc += &format!(" {label} |");
    }
    doc += "\n|---|";
    for _ in protocol::terrains() {
        doc += "---|";
    }
    doc += "\n";
    doc += &terrain_rows;
    doc += &if everywhere.is_empty() {
        "\nNone of them walks every terrain: up for the whole minute and at least 30 m along it. ".to_string()
    } else {
        format!(
            "\nWalking every terrain (up for the whole minute, at least 30 m): {}. ",
            everywhere.join(", ")
        )
    };
    doc += "The walker searched for the whole protocol (`walk-protocol.ron`, CMA-ES with a speed-tracking \
            score) and the issue's criteria checked against it are in `nunes-protocol.md`; its slope form \
            (`walk-slopes.ron`) in `nunes-slopes.md`.\n";
    Ok(doc)
}
