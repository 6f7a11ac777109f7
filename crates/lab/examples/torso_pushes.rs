//! The first part of issue #18's robustness protocol, SIMBICON's push: the largest push on the torso
//! at the height of the centre of mass, over 0.2 s, that each committed walker survives forward and
//! backward, in N·s and as the velocity change Δv = J/m it gives the whole body, beside the thesis's
//! push on the head (0.1 s). Survived: still up 10 s after a push given 20 s into the walk, in steps of
//! 5 N·s up to the first push that fells it.
//!
//! `cargo run --release -p anima-lab --example torso_pushes` writes
//! `docs/reproduction/nunes-robustness.md` (a minute).

use std::path::Path;

use anima_body::BuiltinSkeleton;
use anima_character::Character;
use anima_control::Controller;
use anima_lab::nunes::{self, Push, WalkRules, faithful};

const AT: u64 = 400;
const RECOVERY: u64 = 200;
const STEP: f64 = 5.0;
const MAX: f64 = 400.0;

type Build = fn(Controller) -> Character;

fn humanoid(c: Controller) -> Character {
    nunes::humanoid_character(c).expect("humanoid")
}

fn simbicon_humanoid(c: Controller) -> Character {
    faithful::character(c, &faithful::skeleton(), faithful::world_settings()).expect("humanoid")
}

fn survives(c: &Controller, build: Build, push: Option<Push>) -> bool {
    let rules = WalkRules { window: 0, ..WalkRules::default() };
    let pushes: Vec<Push> = push.into_iter().collect();
    nunes::walk_character(build(c.clone()), AT + RECOVERY, &rules, &pushes, |_| ()).is_ok_and(|o| !o.fell)
}

/// The largest impulse survived in `direction` (±1) before the first that fells the walker.
fn largest(c: &Controller, build: Build, direction: f64, push: fn(f64) -> Push) -> f64 {
    if !survives(c, build, None) {
        return 0.0;
    }
    let mut j = 0.0;
    while j + STEP <= MAX && survives(c, build, Some(push(direction * (j + STEP)))) {
        j += STEP;
    }
    j
}

fn main() {
    let torso = |j: f64| Push::torso(j, AT, 4);
    let head = |j: f64| Push::impulse(j, AT, 2);
    let walkers: [(&str, &str, Build, f64); 4] = [
        (
            "thesis's search (`walk-optimised.ron`)",
            "walk-optimised",
            humanoid,
            BuiltinSkeleton::Humanoid.load().total_mass(),
        ),
        (
            "thesis's machines, robust search (`walk-robust.ron`)",
            "walk-robust",
            humanoid,
            BuiltinSkeleton::Humanoid.load().total_mass(),
        ),
        (
            "SIMBICON form (`walk-simbicon.ron`)",
            "walk-simbicon",
            humanoid,
            BuiltinSkeleton::Humanoid.load().total_mass(),
        ),
        (
            "SIMBICON as published (`walk-simbicon-faithful.ron`)",
            "walk-simbicon-faithful",
            simbicon_humanoid,
            faithful::skeleton().total_mass(),
        ),
    ];
    let mut doc = String::from(
        "# Robustness: SIMBICON's push on anima's walkers\n\n\
         Written by `cargo run --release -p anima-lab --example torso_pushes`; do not edit by hand.\n\n\
         The first part of issue #18's protocol. Yin, Loken & van de Panne (2007) report a SIMBICON walker \
         surviving a push of 350 N for 0.2 s on the torso (70 N·s). Here each committed walker is pushed \
         20 s into its walk, horizontally, on the abdomen at the height of the whole body's centre of mass \
         for 0.2 s (4 control steps), and counts as surviving when it is still up 10 s later; pushes grow \
         in steps of 5 N·s to the first that fells it. Δv = J/m is the velocity change the push gives the \
         whole body. The thesis's push, on the head for 0.1 s, is beside it. Slopes, steps and speed \
         targets, and a walker optimised for them, are not done yet.\n\n\
         | walker | mass (kg) | mean speed (m/s) | torso push survived, forward / backward (N·s) | Δv forward / backward (m/s) | head push survived, forward / backward (N·s) |\n\
         |---|---|---|---|---|---|\n",
    );
    let mut simbicon_sized = Vec::new();
    for (name, file, build, mass) in walkers {
        let c = nunes::controller(file).expect("controller");
        let rules = WalkRules { window: 0, ..WalkRules::default() };
        let free = nunes::walk_character(build(c.clone()), AT + RECOVERY, &rules, &[], |_| ()).expect("walk");
        let speed = free.distance / ((AT + RECOVERY) as f64 * nunes::DT);
        let (tf, tb) = (largest(&c, build, 1.0, torso), largest(&c, build, -1.0, torso));
        let (hf, hb) = (largest(&c, build, 1.0, head), largest(&c, build, -1.0, head));
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
    }
    doc += &if simbicon_sized.is_empty() {
        "\nNone of them survives SIMBICON's 70 N·s both forward and backward. ".to_string()
    } else {
        format!("\nSurviving SIMBICON's 70 N·s both ways: {}. ", simbicon_sized.join(", "))
    };
    doc += "A walker optimised for the whole protocol (CMA-ES, a robust objective with common random \
            numbers) is the part still to do.\n";
    let out = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/reproduction/nunes-robustness.md");
    let tmp = out.with_extension("md.tmp");
    std::fs::write(&tmp, &doc).expect("write");
    std::fs::rename(&tmp, &out).expect("rename");
    println!("wrote {}", out.display());
}
