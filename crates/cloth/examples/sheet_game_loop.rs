//! A spring sheet in a game loop: pinned at two corners, stepped once per 1/60 s frame by generalised-α,
//! its positions read for drawing and a corner dragged by the "player":
//! `cargo run --release -p anima-cloth --example sheet_game_loop`.

use anima_cloth::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // The standard benchmark sheet (1 m, 0.2 kg) at 32 × 32, pinned at (0, 0) and (31, 0).
    let spec = SheetSpec::standard(32);
    let mut sheet =
        NetworkSim::new(spec.build()?, spec.positions(), Integrator::GeneralizedAlpha, 1.0 / 60.0)?;
    let start = sheet.positions().to_vec();
    let n = spec.n;
    for frame in 1..=180 {
        // Input: the second pinned corner moves 0.3 m along x over the first second, then stays.
        let shift = 0.3 * (frame as f64 / 60.0).min(1.0);
        sheet.drive_pinned(|i| if i == n - 1 { start[i] + DVec3::new(-shift, 0.0, 0.0) } else { start[i] });
        sheet.step()?;
        // Drawing would read the positions here; the frame's numbers stand in for it.
        if frame % 60 == 0 {
            let lowest = sheet.positions().iter().map(|p| p.z).fold(f64::MAX, f64::min);
            println!("frame {frame}: t = {:.2} s, lowest point {lowest:.3} m", sheet.time());
        }
    }
    // Hanging from its two corners, 0.7 m apart now: below them, and every value finite.
    let lowest = sheet.positions().iter().map(|p| p.z).fold(f64::MAX, f64::min);
    assert!(lowest < start[0].z - 0.5, "the sheet should hang below its pins");
    assert!(sheet.positions()[n - 1].distance(start[0]) < 0.7 + 1e-9);
    Ok(())
}
