//! The aid used to re-author the walking poses the thesis only draws (spec §8.1.2 \[RECON\]): CMA-ES
//! over a symmetric description of W-LEGS's E1 and E3 (E4, E6 are their mirrors), rewarding the
//! distance walked before a fall over several sensor thresholds. Prints the best pose vector; the
//! numbers were then written into `assets/controllers/walk.ron` by hand.
//!
//! `cargo run --release -p anima-lab --example tune_walk -- [evaluations] [iterations]`
use anima_control::Selection;
use anima_control::optimise::{Cmaes, CmaesConfig, RunLog, run};
use anima_lab::nunes::walk_poses::{self, set as set_poses};
use anima_lab::nunes::{self, WalkRules};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let budget: usize = args.get(1).map_or(200, |a| a.parse().unwrap_or(0));
    let iters: u64 = args.get(2).map_or(400, |a| a.parse().unwrap_or(0));
    let base = nunes::controller("walk").expect("walk.ron");
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
    let x0 = walk_poses::SPEC.to_vec();
    let space = walk_poses::space();
    let mut cfg = CmaesConfig::new(x0.clone(), 0.2);
    cfg.lambda = Some(10);
    let mut opt = Cmaes::new(space, cfg, 7).expect("cmaes");
    let mut log = RunLog::default();
    eprintln!("x0 fitness {:.3}", objective(&x0));
    let mut best = f64::NEG_INFINITY;
    while log.len() < budget {
        let n = log.len() + 10;
        let r = run(&mut opt, &objective, n, &mut log).expect("a finite fitness");
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
