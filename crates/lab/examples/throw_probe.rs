//! Throws with `assets/controllers/throw.ron`, optionally with (s1, e1, s2, e2, τ2) set, and prints
//! the ball's path: `cargo run --release -p anima-lab --example throw_probe -- [s1 e1 s2 e2 t2]`.
use anima_control::Selection;
use anima_lab::nunes;

fn main() {
    let args: Vec<f64> = std::env::args().skip(1).map(|a| a.parse().expect("number")).collect();
    let mut c = nunes::controller("throw").expect("throw.ron");
    if args.len() == 5 {
        let ids = c.free_params(&Selection::all());
        c.apply(&ids, &args);
    }
    let mut k = 0;
    let out = nunes::throw(c, &nunes::BASKET, 2000, |ch| {
        k += 1;
        let s = &ch.env.sensors[0];
        if k % 6 == 0 {
            eprintln!(
                "{k:4} ball ({:.2}, {:.2}) v ({:.2}, {:.2}) com ({:.2},{:.2}) pelvis {:.2} ground {:?}",
                s.body_position[14][0],
                s.body_position[14][1],
                s.body_velocity[14][0],
                s.body_velocity[14][1],
                s.com[0],
                s.com[1],
                s.body_angle[3],
                s.on_ground
            );
        }
    })
    .expect("throw");
    println!("{out:?} fitness {:.3}", out.fitness());
}
