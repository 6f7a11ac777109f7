//! The aid used to re-author the walking poses the thesis only draws (spec §8.1.2 [RECON]): CMA-ES
//! over a symmetric description of W-LEGS's E1 and E3 (E4, E6 are their mirrors), rewarding the
//! distance walked before a fall over several sensor thresholds. Prints the best pose vector; the
//! numbers were then written into `assets/controllers/walk.ron` by hand.
//!
//! `cargo run --release -p anima-scene --example tune_walk -- [evaluations] [iterations]`
use anima_control::optimise::{Cmaes, CmaesConfig, Dim, RunLog, Space, run};
use anima_control::{Controller, Selection};
use anima_scene::nunes::{self, WalkRules};

const NAMES: [&str; 12] = [
    "waist",
    "e1_hip_sw",
    "e1_knee_sw",
    "e1_ankle_sw",
    "e1_hip_st",
    "e1_knee_st",
    "e1_ankle_st",
    "e3_hip_sw",
    "e3_knee_sw",
    "e3_ankle_sw",
    "e3_hip_st",
    "e3_ankle_st",
];

/// Writes pose vector `x` into the walking controller (E1/E3 and mirrored E4/E6).
pub fn set_poses(c: &mut Controller, x: &[f64]) {
    let mut set = |label: String, v: f64| {
        let id = c.param_id(&label).unwrap_or_else(|| panic!("no parameter {label}"));
        c.set_param(id, v);
    };
    for (state, sw, st) in [("E1", "l", "r"), ("E4", "r", "l")] {
        set(format!("W-LEGS/{state}/waist"), x[0]);
        set(format!("W-LEGS/{state}/hip_{sw}"), x[1]);
        set(format!("W-LEGS/{state}/knee_{sw}"), x[2]);
        set(format!("W-LEGS/{state}/ankle_{sw}"), x[3]);
        set(format!("W-LEGS/{state}/hip_{st}"), x[4]);
        set(format!("W-LEGS/{state}/knee_{st}"), x[5]);
        set(format!("W-LEGS/{state}/ankle_{st}"), x[6]);
        let s = if sw == "l" { 1.0 } else { -1.0 };
        set(format!("W-LEGS/{state}/inter_thigh"), s * (x[1] - x[4]));
    }
    for (state, sw, st) in [("E3", "l", "r"), ("E6", "r", "l")] {
        set(format!("W-LEGS/{state}/waist"), x[0]);
        set(format!("W-LEGS/{state}/hip_{sw}"), x[7]);
        set(format!("W-LEGS/{state}/knee_{sw}"), x[8]);
        set(format!("W-LEGS/{state}/ankle_{sw}"), x[9]);
        set(format!("W-LEGS/{state}/hip_{st}"), x[10]);
        set(format!("W-LEGS/{state}/knee_{st}"), -0.05);
        set(format!("W-LEGS/{state}/ankle_{st}"), x[11]);
        let s = if sw == "l" { 1.0 } else { -1.0 };
        set(format!("W-LEGS/{state}/inter_thigh"), s * (x[7] - x[10]));
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let budget: usize = args.get(1).map_or(200, |a| a.parse().unwrap_or(0));
    let iters: u64 = args.get(2).map_or(400, |a| a.parse().unwrap_or(0));
    let base = nunes::parse(nunes::WALK_RON).expect("walk.ron");
    if args[1] == "show" {
        let x: Vec<f64> = args[2..14].iter().map(|a| a.parse().expect("number")).collect();
        let p: Vec<f64> = args[14..18].iter().map(|a| a.parse().expect("number")).collect();
        let mut c = base.clone();
        set_poses(&mut c, &x);
        c.apply(&base.free_params(&Selection::all()), &p);
        let mut k = 0;
        let rules = WalkRules { window: 0, ..WalkRules::default() };
        let out = nunes::walk(c, 1000, &rules, &[], |ch| {
            k += 1;
            let s = &ch.env.sensors[0];
            if k % 10 == 0 {
                let st: Vec<String> =
                    ch.controller.machines().iter().map(|m| format!("{:?}", m.current_state())).collect();
                eprintln!(
                    "{k:5} com ({:.2}, {:.2}) v {:.2} pelvis ({:.2},{:.2}) ang {:.2} feet {:.2} {:.2} support {:?} {}",
                    s.com[0], s.com[1], s.com_velocity[0], s.body_position[3][0], s.body_position[3][1],
                    s.body_angle[3], s.body_position[6][0], s.body_position[9][0], s.support, st.join(",")
                );
            }
        })
        .expect("walk");
        println!("{out:?}");
        return;
    }
    let ps = base.free_params(&Selection::all());
    let settings: [[f64; 4]; 3] = [[0.25; 4], [0.0; 4], [-0.15, 0.4, -0.15, 0.4]];
    let objective = |x: &[f64]| {
        let mut total = 0.0;
        for p in &settings {
            let mut c = base.clone();
            set_poses(&mut c, x);
            c.apply(&ps, p);
            let rules = WalkRules { window: 0, ..WalkRules::default() };
            // A walk, not a run: no flight phases, at most 0.5 m/s counted.
            let mut flight = 0.0;
            let out = nunes::walk(c, iters, &rules, &[], |ch| {
                if ch.env.sensors[0].support == anima_body::Support::None {
                    flight += 1.0;
                }
            })
            .expect("walk");
            let cap = 0.5 * out.iterations as f64 * nunes::DT;
            total +=
                out.distance.clamp(-1.0, cap) + 4.0 * out.iterations as f64 / iters as f64 - 0.05 * flight;
        }
        total / settings.len() as f64
    };
    let lo = [-0.4, 0.0, -1.6, -0.4, -0.6, -0.6, -0.4, -0.2, -1.0, -0.4, -0.6, -0.4];
    let hi = [0.2, 1.2, 0.0, 0.6, 0.4, 0.0, 0.6, 1.0, 0.0, 0.4, 0.4, 0.6];
    let x0 = vec![-0.05, 0.6, -1.1, 0.2, -0.1, -0.05, 0.0, 0.4, -0.05, 0.0, -0.2, 0.1];
    let space =
        Space { dims: NAMES.iter().zip(lo.iter().zip(hi)).map(|(n, (&a, b))| Dim::new(n, a, b)).collect() };
    let mut cfg = CmaesConfig::new(x0.clone(), 0.2);
    cfg.lambda = Some(10);
    let mut opt = Cmaes::new(space, cfg, 7).expect("cmaes");
    let mut log = RunLog::default();
    eprintln!("x0 fitness {:.3}", objective(&x0));
    let mut best = f64::NEG_INFINITY;
    while log.len() < budget {
        let n = log.len() + 10;
        let r = run(&mut opt, &objective, n, &mut log);
        if let Some((x, f)) = r
            && f > best
        {
            best = f;
            eprintln!(
                "{:4} best {f:.3} x {}",
                log.len(),
                x.iter().map(|v| format!("{v:.3}")).collect::<Vec<_>>().join(", ")
            );
        }
        if log.len() < n {
            break;
        }
    }
}
