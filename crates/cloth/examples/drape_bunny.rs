//! Drapes a 64 × 64 cloth over the Stanford Bunny standing on a floor, at 1/60 s with generalised-α,
//! contacts inside its solve and the modern self-collision (the builder's defaults):
//! `cargo run --release -p anima-cloth --example drape_bunny`.

use anima_cloth::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/meshes/bunny.obj");
    let bunny = read_obj(std::fs::File::open(path)?)?;
    // The Bunny 0.5 m long, upright (its file's up is +y), on the floor at z = 0.
    let mut cloth = OliveiraCloth::builder(64, 1.0)
        .mesh("bunny", bunny, UpAxis::Y, 0.5, DVec3::ZERO)
        .floor(0.0)
        .build()?;
    let top = cloth.positions().iter().map(|p| p.z).fold(f64::MIN, f64::max);
    // Two seconds of frames: a failed step (non-finite, out of physical bounds) is an error naming it.
    while cloth.time() < 2.0 - 1e-9 {
        cloth.step()?;
        if cloth.steps() % 30 == 0 {
            let lowest = cloth.positions().iter().map(|p| p.z).fold(f64::MAX, f64::min);
            println!("t = {:.2} s  lowest {lowest:.3} m  fastest {:.3} m/s", cloth.time(), cloth.max_speed());
        }
    }
    // Draped: nothing inside the Bunny or the floor, resting (slow), lower than it started.
    let inside = cloth.penetrations().len();
    let highest = cloth.positions().iter().map(|p| p.z).fold(f64::MIN, f64::max);
    println!("{inside} particles inside an object; highest point {highest:.3} m (started at {top:.3} m)");
    assert_eq!(inside, 0, "particles inside an object");
    assert!(cloth.max_speed() < 0.5 && highest < top, "the cloth has not settled on the Bunny");
    Ok(())
}
