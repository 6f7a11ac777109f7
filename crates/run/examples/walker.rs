//! A walker from the shipped files: `assets/scenes/walk.ron` names the skeleton, the controller, and
//! the actuation and world settings it walks with; the scene is loaded, built and stepped for 20 s:
//! `cargo run --release -p anima-run --example walker`.

use anima_run::prelude::*;

fn main() -> anyhow::Result<()> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/scenes/walk.ron");
    let Scene::Character(loaded) = load(path.as_ref(), &LoadOptions::default())? else {
        anyhow::bail!("walk.ron is a character scene");
    };
    let mut walker = build_character(&loaded)?;
    let x0 = walker.env.sensors[0].com[0];
    // 20 control steps a second (Δt = 0.05 s), each sensing, the controller and the physics sub-steps.
    for step in 1..=400 {
        walker.step()?;
        if step % 80 == 0 {
            let s = &walker.env.sensors[0];
            println!(
                "t = {:4.1} s  walked {:5.2} m  support {:?}",
                walker.env.world.time(),
                s.com[0] - x0,
                s.support
            );
        }
    }
    let walked = walker.env.sensors[0].com[0] - x0;
    let pelvis = walker.env.sensors[0].layout.pelvis.expect("the humanoid has a pelvis");
    let height = walker.env.sensors[0].body_position[pelvis][1];
    println!("walked {walked:.2} m in 20 s; pelvis {height:.2} m above the ground");
    anyhow::ensure!(walked > 5.0 && height > 0.7, "the walker should walk upright");
    Ok(())
}
