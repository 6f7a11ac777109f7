//! Walks a controller file and prints how far it got: `cargo run --release -p anima-lab --example
//! walk_probe -- assets/controllers/walk.ron [iterations] [p2 p3 p5 p6]`.
use anima_lab::nunes::{self, WalkRules};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let text = std::fs::read_to_string(&args[1]).expect("controller file");
    let n: u64 = args.get(2).map_or(1000, |a| a.parse().expect("iterations"));
    let mut c = nunes::parse(&text).expect("controller");
    if args.len() >= 7 {
        let ids = c.free_params(&anima_control::Selection::all());
        let x: Vec<f64> = args[3..7].iter().map(|a| a.parse().expect("number")).collect();
        c.apply(&ids, &x);
    }
    let rules = WalkRules { stop_on_failure: true, ..WalkRules::default() };
    let mut k = 0;
    let out = nunes::walk(c, n, &rules, &[], |ch| {
        k += 1;
        if k % 20 == 0 {
            let s = &ch.env.sensors[0];
            let st: Vec<String> =
                ch.controller.machines().iter().map(|m| format!("{:?}", m.current_state())).collect();
            eprintln!(
                "{k:5} com ({:.2}, {:.2}) v {:.2} pelvis_y {:.2} support {:?} states {}",
                s.com[0],
                s.com[1],
                s.com_velocity[0],
                s.body_position[s.layout.pelvis.unwrap()][1],
                s.support,
                st.join(",")
            );
        }
    })
    .expect("walk");
    println!("{out:?} fitness {:.3}", out.fitness());
}
