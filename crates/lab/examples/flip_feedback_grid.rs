//! The aid that chose the pusher's recovery feedback in `assets/controllers/backflip.ron`: turns the
//! joints `JOINTS` (default `ankle_l,ankle_r`) of state `STATE` (default E4) of machine `MACHINE`
//! (default B-PUSHER), for model `MODEL` (default pusher), into balance feedback
//! θ₀ + k_d·com_offset + k_v·com_speed, and prints for each pair of gains from the arguments how the
//! flip ends at each of `nunes::FLIP_SPACINGS` (p/P: the pusher up/fell; a/A: the flip incomplete/
//! complete). With `OUT=file` it writes the controller with the first two arguments as gains instead
//! (none: the controller as it is, in `Controller::to_ron`'s form).
//!
//! `FLIP_RON=assets/controllers/backflip.ron cargo run --release -p anima-lab --example
//! flip_feedback_grid -- -1 -0.6 0`
use anima_control::{Controller, FeedbackDesc, FeedbackTerm, Param, SensorDesc, TargetDesc};
use anima_lab::nunes;

fn with_gains(c: &Controller, joints: &[&str], kd: f64, kv: f64) -> Controller {
    let mut desc = c.to_desc();
    let machine = std::env::var("MACHINE").unwrap_or_else(|_| "B-PUSHER".into());
    let state = std::env::var("STATE").unwrap_or_else(|_| "E4".into());
    let model = std::env::var("MODEL").unwrap_or_else(|_| "pusher".into());
    let m = desc.machines.iter_mut().find(|m| m.name == machine).expect("machine");
    let e4 = m.states.iter_mut().find(|s| s.name == state).expect("state");
    for entry in &mut e4.pose {
        let Some(name) = entry.0.name(c.actuators()) else { continue };
        // A joint that already has feedback keeps its θ₀ and gets the new gains.
        let p = match &entry.1 {
            TargetDesc::Angle(p) => *p,
            TargetDesc::Feedback(fd) if !fd.world => fd.base,
            _ => continue,
        };
        if joints.iter().any(|j| name == format!("{model}/{j}")) {
            let sensor =
                |kind: &str, args: Vec<String>| SensorDesc { kind: kind.into(), args, params: vec![] };
            entry.1 = TargetDesc::Feedback(FeedbackDesc {
                base: p,
                world: false,
                terms: vec![
                    FeedbackTerm {
                        gain: Param::fixed(kd),
                        sensor: sensor("com_offset", vec![model.clone(), "left".into()]),
                    },
                    FeedbackTerm { gain: Param::fixed(kv), sensor: sensor("com_speed", vec![model.clone()]) },
                ],
            });
        }
    }
    Controller::from_desc(desc, &anima_character::procedures()).expect("controller")
}

fn main() {
    let text = std::fs::read_to_string(std::env::var("FLIP_RON").expect("FLIP_RON")).expect("file");
    let c = nunes::parse(&text).expect("controller");
    let joints: Vec<String> = std::env::var("JOINTS")
        .unwrap_or_else(|_| "ankle_l,ankle_r".into())
        .split(',')
        .map(String::from)
        .collect();
    let joints: Vec<&str> = joints.iter().map(String::as_str).collect();
    let ks: Vec<f64> = std::env::args().skip(1).map(|a| a.parse().expect("gain")).collect();
    if let Ok(out) = std::env::var("OUT") {
        let c = if ks.is_empty() { c } else { with_gains(&c, &joints, ks[0], ks[1]) };
        std::fs::write(out, c.to_ron()).expect("write");
        return;
    }
    for &kd in &ks {
        for &kv in &ks {
            let c = with_gains(&c, &joints, kd, kv);
            let cells: Vec<String> = nunes::FLIP_SPACINGS
                .iter()
                .map(|&d| match nunes::backflip(c.clone(), d, 600, |_| ()) {
                    Ok(o) => format!(
                        "{}{}",
                        if o.pusher_fell { "P" } else { "p" },
                        if o.flipped() { "A" } else { "a" }
                    ),
                    Err(_) => "err".into(),
                })
                .collect();
            println!("kd {kd:+.2} kv {kv:+.2}: {}", cells.join(" "));
        }
    }
}
