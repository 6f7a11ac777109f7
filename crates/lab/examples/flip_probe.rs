//! Runs the assisted backflip (`assets/controllers/backflip.ron`) and prints the acrobat's path:
//! `cargo run --release -p anima-lab --example flip_probe -- [iterations] [spacing]`.
use anima_lab::nunes;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let iters = args.first().map_or(600, |a| a.parse().expect("iterations"));
    let mut spacing = nunes::FLIP_SPACING;
    // `FLIP_RON=file` runs another controller (e.g. one `tune_flip` wrote).
    let text = std::env::var("FLIP_RON")
        .map_or(nunes::controller_text("backflip").expect("backflip.ron"), |f| {
            std::fs::read_to_string(f).expect("controller file")
        });
    let mut c = nunes::parse(&text).expect("controller");
    // Overrides: `label=value` (a controller parameter, e.g. `B-PUSHER/E1/hip_l=0.5`) or `spacing=0.8`.
    for a in args.iter().skip(1) {
        let (name, v) = a.split_once('=').expect("label=value");
        let v: f64 = v.parse().expect("number");
        if name == "spacing" {
            spacing = v;
        } else {
            let id = c.param_id(name).unwrap_or_else(|| panic!("no parameter {name}"));
            c.set_param(id, v);
        }
    }
    let mut k = 0;
    let out = nunes::backflip(c, spacing, iters, |ch| {
        k += 1;
        let (a, p) = (&ch.env.sensors[0], &ch.env.sensors[1]);
        let st: Vec<String> =
            ch.controller.machines().iter().map(|m| format!("{:?}", m.current_state())).collect();
        if k % 5 == 0 || std::env::var("EVERY").is_ok() {
            eprintln!(
                "{k:4} P pelvis ({:.2},{:.2}) ang {:.2} pg {:?} | A pelvis ({:.2},{:.2}) abd ang {:.2} w {:.2} com v ({:.2},{:.2}) feet y {:.2} {:.2} pusher hands ({:.2},{:.2}) {} ground {:?}",
                p.body_position[3][0],
                p.body_position[3][1],
                p.body_angle[2],
                p.on_ground.iter().enumerate().filter(|(_, g)| **g).map(|(b, _)| b).collect::<Vec<_>>(),
                a.body_position[3][0],
                a.body_position[3][1],
                a.body_angle[2],
                a.body_angular_velocity[2],
                a.com_velocity[0],
                a.com_velocity[1],
                a.body_position[6][1],
                a.body_position[9][1],
                p.body_position[12][0],
                p.body_position[12][1],
                st.join(","),
                a.on_ground.iter().enumerate().filter(|(_, g)| **g).map(|(b, _)| b).collect::<Vec<_>>()
            );
        }
    })
    .expect("backflip");
    println!("{out:#?}\nflipped: {}", out.flipped());
}
