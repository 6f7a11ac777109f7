//! Runs the assisted backflip (`assets/controllers/backflip.ron`) at each spacing of the pair in
//! `nunes::FLIP_SPACINGS` (with `FLIP_FINE=1`, in steps of 5 mm) and prints one line per spacing
//! (rotation, launch, landing, standing):
//! `cargo run --release -p anima-lab --example flip_spacings -- [label=value…]`.
use anima_lab::nunes;

fn main() {
    // `FLIP_RON=file` runs another controller (e.g. one `tune_flip` wrote).
    let text = std::env::var("FLIP_RON")
        .map_or(nunes::controller_text("backflip").expect("backflip.ron"), |f| {
            std::fs::read_to_string(f).expect("controller file")
        });
    let mut c = nunes::parse(&text).expect("controller");
    for a in std::env::args().skip(1) {
        let (name, v) = a.split_once('=').expect("label=value");
        let id = c.param_id(name).unwrap_or_else(|| panic!("no parameter {name}"));
        c.set_param(id, v.parse().expect("number"));
    }
    // `FLIP_FINE=1`: every spacing of the range in steps of 5 mm instead.
    let spacings = if std::env::var_os("FLIP_FINE").is_some() {
        nunes::flip_fine_spacings()
    } else {
        nunes::FLIP_SPACINGS.to_vec()
    };
    for d in spacings {
        let o = nunes::backflip(c.clone(), d, 600, |_| ()).expect("backflip");
        println!(
            "{d:.3} m: rot max {:.2} end {:.2} | foot on hands {:?} push {:?} E6 {:?} landed {:?} | \
             pelvis max {:.2} end {:.2} | fell {} pusher fell {} standing {} flipped {}",
            o.max_rotation,
            o.final_rotation,
            o.foot_on_hands_at,
            o.push_at,
            o.acrobat_e6_at,
            o.landed_at,
            o.max_pelvis_height,
            o.final_pelvis_height,
            o.touched_down,
            o.pusher_fell,
            o.standing,
            o.flipped()
        );
    }
}
