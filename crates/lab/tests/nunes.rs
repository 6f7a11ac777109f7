//! The controller–body adapter (`anima_character`) and the Nunes 2006 experiments built on it.

use anima_body::sensors::catalogue;
use anima_body::{Target, TargetFrame};
use anima_control::{SensorInput, SensorQuery};
use anima_lab::nunes::{self, WalkRules};

const SMALL: &str = r#"Controller(
    name: "probe",
    actuators: ["hip_l", "knee_r", "elbow_l", "ankle_r"],
    machines: [
        Machine(name: "A", kind: Constant, weight: 2.0,
            states: [State(name: "E1", pose: [("hip_l", Angle(0.3)), ("knee_r", Angle(-0.2)), ("elbow_l", NoTorque)])],
            transitions: [Transition(when: Sensory((kind: "foot_up", args: ["left"])))]),
        Machine(name: "B", kind: Constant, weight: 0.5,
            states: [State(name: "E1", pose: [("hip_l", Angle(-0.1)), ("ankle_r", DampingOnly)])],
            transitions: [Transition(when: Sensory((kind: "cog_ahead", args: ["right"], params: [0.02])))]),
    ],
)"#;

#[test]
fn targets_become_body_signals_and_sensors_answer_from_the_catalogue() {
    let c = nunes::parse(SMALL).unwrap();
    let mut ch = nunes::humanoid_character(c).unwrap();
    for _ in 0..5 {
        ch.step().unwrap();
    }
    let sk = ch.env.world.skeleton(0).unwrap();
    let idx = |n: &str| sk.actuator_index(n).unwrap();
    let want = [
        (idx("hip_l"), Target::Angle(0.3), 2.0),
        (idx("knee_r"), Target::Angle(-0.2), 2.0),
        (idx("elbow_l"), Target::NoTorque, 2.0),
        (idx("hip_l"), Target::Angle(-0.1), 0.5),
        (idx("ankle_r"), Target::DampingOnly, 0.5),
    ];
    let got = ch.env.world.commands(0).unwrap().signals().to_vec();
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (a, t, w) in want {
        assert!(
            got.iter()
                .any(|s| s.actuator == a && s.target == t && s.weight == w && s.frame == TargetFrame::Parent),
            "missing {a} {t:?} {w} in {got:?}"
        );
    }
    assert_eq!(
        ch.actuator_map(),
        &[(0, idx("hip_l")), (0, idx("knee_r")), (0, idx("elbow_l")), (0, idx("ankle_r"))]
    );
    // Every sensor of the controller answers what the catalogue says of the same reading.
    let sensors: Vec<_> = ch.controller.sensors().to_vec();
    for (id, s) in sensors.iter().enumerate() {
        let params = [0.02];
        let q = SensorQuery {
            id,
            name: &s.name,
            kind: &s.kind,
            args: &s.args,
            params: &params[..s.params.len()],
        };
        let reading = ch.env.sensors[0].clone();
        let expected = match s.kind.as_str() {
            "foot_up" => catalogue::foot_up(&reading, 0),
            "cog_ahead" => catalogue::cog_ahead(&reading, 1, 0.02),
            k => panic!("unexpected kind {k}"),
        };
        assert_eq!(ch.env.sensor(&q), expected, "sensor {}", s.name);
    }
    // Standing still: both feet on the ground.
    assert_eq!(catalogue::foot_up(&ch.env.sensors[0], 0), 0.0);
}

#[test]
fn a_short_walk_is_deterministic() {
    let run = || {
        let mut trace = Vec::new();
        let c = nunes::controller("walk").unwrap();
        let out =
            nunes::walk(c, 200, &WalkRules::default(), &[], |ch| trace.push(ch.env.sensors[0].com)).unwrap();
        (out, trace)
    };
    let (a, ta) = run();
    let (b, tb) = run();
    assert_eq!(a, b);
    assert_eq!(ta, tb);
    assert_eq!(a.iterations, 200);
}

#[test]
fn the_optimised_walker_walks_without_falling() {
    let c = nunes::controller("walk-optimised").unwrap();
    let out = nunes::walk(c, 1000, &WalkRules::default(), &[], |_| ()).unwrap();
    assert!(!out.fell && !out.stopped, "{out:?}");
    assert_eq!(out.iterations, 1000);
    assert!(out.distance > 10.0, "{out:?}");
}

#[test]
fn the_faithful_configuration_falls_before_the_search_and_walks_after_it() {
    // Table 6.3's before-and-after on the humanoid with gains × 27 (`nunes-results.md`): the
    // unoptimised walker falls within the 50 s evaluation, the thesis's search's winner walks it.
    let rules = WalkRules::default();
    let run = |name: &str| {
        let c = nunes::controller(name).unwrap();
        nunes::walk_character(nunes::faithful_character(c).unwrap(), 1000, &rules, &[], |_| ()).unwrap()
    };
    let before = run("walk");
    assert!(before.fell && before.fitness() == 0.0, "{before:?}");
    let after = run(anima_lab::nunes::report::FAITHFUL_OPTIMISED);
    assert!(!after.fell && !after.stopped && after.iterations == 1000, "{after:?}");
    assert!(after.fitness() > 10.0, "{after:?}");
}

/// A walk pushed on the head with `impulse` N·s at 10 s: whether the head touched the ground in the
/// 3 s after, and whether PROTECT-FWD ran.
fn head_push(name: &str, impulse: f64) -> (bool, bool) {
    let rules = WalkRules { window: 0, stop_on_failure: false, ..WalkRules::default() };
    let push = nunes::Push::impulse(impulse, 200, 2);
    let (mut head_down, mut protected) = (false, false);
    let c = nunes::controller(name).unwrap();
    nunes::walk(c, 260, &rules, &[push], |c| {
        let s = &c.env.sensors[0];
        head_down |= s.layout.head.is_some_and(|h| s.on_ground[h]);
        protected |=
            c.controller.machines().iter().any(|m| m.name() == "PROTECT-FWD" && m.current_state().is_some());
    })
    .unwrap();
    (head_down, protected)
}

#[test]
fn the_protective_machines_keep_the_head_off_the_ground_in_a_forward_fall() {
    // Variant C (spec §8.1.9, nunes-results.md): pushed from behind, walk.ron falls on its head;
    // walk-protected.ron raises its arms and lands on them.
    assert_eq!(head_push("walk", 100.0), (true, false));
    assert_eq!(head_push("walk-protected", 100.0), (false, true));
}

#[test]
fn a_push_on_the_torso_at_the_centre_of_mass_height_acts() {
    // SIMBICON's push (0.2 s on the torso, nunes-robustness.md): the thesis's walker takes 30 N·s
    // forward and falls under 200.
    let c = nunes::controller("walk-optimised").unwrap();
    let rules = WalkRules { window: 0, ..WalkRules::default() };
    let run = |impulse: f64| {
        nunes::walk(c.clone(), 600, &rules, &[nunes::Push::torso(impulse, 400, 4)], |_| ()).unwrap()
    };
    assert!(!run(30.0).fell);
    assert!(run(200.0).fell);
}

#[test]
fn the_protected_walker_walks_as_walk_ron_until_it_falls() {
    // walk-protected.ron is walk.ron plus two sensory machines that stay idle while it walks.
    let run = |name: &str| {
        nunes::walk(nunes::controller(name).unwrap(), 400, &WalkRules::default(), &[], |_| ()).unwrap()
    };
    let (plain, protected) = (run("walk"), run("walk-protected"));
    assert!(!plain.fell, "{plain:?}");
    assert_eq!(plain.distance.to_bits(), protected.distance.to_bits(), "{plain:?} {protected:?}");
}

#[test]
fn the_thrower_releases_the_ball_when_t2_fires() {
    // T1: 80 iterations in E1 (0–79); T2: τ2 = 20 iterations in E2 (80–99), the release fires on its
    // switch at the end of iteration 99 (spec §6.7, §8.3.1).
    let c = nunes::controller("throw").unwrap();
    let mut ch = nunes::thrower_character(c).unwrap();
    for k in 0..120u64 {
        ch.step().unwrap();
        let holds = ch.env.world.weld_holds(0, 0).unwrap() || ch.env.world.weld_holds(0, 1).unwrap();
        assert_eq!(holds, k < 99, "iteration {k}");
    }
    assert_eq!(ch.env.released_at, Some(99));
}

#[test]
fn the_optimised_thrower_puts_the_ball_through_the_hoop() {
    let c = nunes::controller("throw-optimised").unwrap();
    let out = nunes::throw(c, &nunes::BASKET, 2000, |_| ()).unwrap();
    assert!(out.scored && !out.fell, "{out:?}");
    let cap = Some(nunes::throw_height_cap(&nunes::BASKET));
    // Better than the unoptimised throw under the capped fitness it was optimised for.
    let before = nunes::throw(nunes::controller("throw").unwrap(), &nunes::BASKET, 2000, |_| ()).unwrap();
    assert!(out.fitness_capped(cap) > before.fitness_capped(cap) + 2.0, "{out:?} {before:?}");
}

#[test]
fn the_overhand_thrower_scores_under_the_literal_fitness() {
    // assets/controllers/throw-overhand.ron: the best overhand throw through the hoop that the
    // thesis's search on the literal Eq. 6.1 found (`cargo xtask reproduce nunes-throw`, issue #39).
    let c = nunes::controller("throw-overhand").unwrap();
    let (out, release) = nunes::report::throw_released(c).unwrap();
    assert!(out.scored && !out.fell, "{out:?}");
    // Overhand: the ball turns clockwise about the thorax over the release step (thrower facing +x),
    // flung by a moving arm (more than 0.1 rad in that step), not let go by an arm at rest.
    let release = release.expect("the ball is released");
    assert_eq!(release.style(), "overhand", "{release:?}");
    assert!(release.turn < -0.1, "{release:?}");
    // Better than the unoptimised throw under the literal Eq. 6.1 it was searched with.
    let before = nunes::throw(nunes::controller("throw").unwrap(), &nunes::BASKET, 2000, |_| ()).unwrap();
    assert!(out.fitness() > before.fitness() + 2.0, "{out:?} {before:?}");
}

#[test]
fn the_committed_backflip_turns_over_and_lands_standing() {
    let c = nunes::controller("backflip").unwrap();
    // 30 s: the landing comes at about iteration 245, so both humanoids stand for 17 s after it.
    let out = nunes::backflip(c, nunes::FLIP_SPACING, 600, |_| ()).unwrap();
    // A full backward turn of the trunk (at least 2π − 0.5 rad), both feet down after the flight, no
    // body of the acrobat but its feet ever on the ground, and at the end both feet down, the pelvis
    // above 0.7 m and the trunk within 0.5 rad of upright. The pusher never falls.
    assert!(out.flipped(), "{out:?}");
    assert!(!out.pusher_fell, "{out:?}");
    assert_eq!(out.iterations, 600, "{out:?}");
    // The thesis's timing (spec §8.4.5): the acrobat's T5 fires 5 iterations after the push begins.
    assert_eq!(out.acrobat_e6_at.unwrap() - out.push_at.unwrap(), 5, "{out:?}");
}

/// Issue #18: the committed flip at spacing `d`, judged as the report judges it.
fn flips_at(d: f64) {
    let out = nunes::backflip(nunes::controller("backflip").unwrap(), d, 600, |_| ()).unwrap();
    assert!(out.flipped(), "spacing {d}: {out:?}");
    assert!(!out.pusher_fell, "spacing {d}: {out:?}");
    assert_eq!(out.iterations, 600, "spacing {d}: {out:?}");
}

#[test]
fn the_backflip_lands_standing_with_the_pusher_nearest() {
    flips_at(nunes::FLIP_SPACINGS[0]);
}

#[test]
fn the_backflip_lands_standing_with_the_pusher_farthest() {
    flips_at(nunes::FLIP_SPACINGS[nunes::FLIP_SPACINGS.len() - 1]);
}

#[test]
fn without_its_recovery_step_the_acrobat_falls_with_the_pusher_nearest() {
    // At 0.86 m the acrobat over-rotates a little and lands with about 1 m/s of backward speed: its
    // capture point lies behind its heels, T8 fires and it steps back (E9) and stands (E10). With T8's
    // margin so wide that it never fires, it keeps its landing stance E8 and falls. So its standing
    // there is the step's work.
    let c = nunes::controller("backflip").unwrap();
    let d = nunes::FLIP_SPACINGS[0];
    let with = nunes::backflip(c.clone(), d, 600, |_| ()).unwrap();
    assert!(with.flipped(), "{with:?}");
    let without = nunes::backflip(nunes::without_recovery_step(c), d, 600, |_| ()).unwrap();
    assert!(without.touched_down && !without.standing, "{without:?}");
}

#[test]
fn without_its_recovery_feedback_the_pusher_falls_after_the_push() {
    // At 0.88 m the pusher stays up with the ankle feedback of its relaxed stance E4 and, with its four
    // gains set to 0 (fixed ankle targets), drifts forward after the push and falls. So its standing
    // there is the feedback's work.
    let mut c = nunes::controller("backflip").unwrap();
    let d = nunes::FLIP_SPACINGS[1];
    let with = nunes::backflip(c.clone(), d, 600, |_| ()).unwrap();
    assert!(!with.pusher_fell, "{with:?}");
    for act in ["ankle_l", "ankle_r"] {
        for k in ["k0", "k1"] {
            let id = c.param_id(&format!("B-PUSHER/E4/pusher/{act}/{k}")).unwrap();
            c.set_param(id, 0.0);
        }
    }
    let without = nunes::backflip(c, d, 600, |_| ()).unwrap();
    assert!(without.pusher_fell, "{without:?}");
}

#[test]
fn without_its_balance_feedback_the_acrobat_falls_after_the_landing() {
    // The same flip with the feedback gains of the landing state E8 set to 0 (fixed targets θ₀) and the
    // recovery step off (which would otherwise catch it): the acrobat lands, cannot stop its backward
    // speed, and falls. With the step off but E8's feedback on it stands at this spacing. So E8's
    // standing landing is the feedback's work.
    let c = nunes::without_recovery_step(nunes::controller("backflip").unwrap());
    let with = nunes::backflip(c.clone(), nunes::FLIP_SPACING, 600, |_| ()).unwrap();
    assert!(with.flipped(), "{with:?}");
    let mut c = c;
    for act in ["waist", "ankle_l", "ankle_r"] {
        for k in ["k0", "k1"] {
            let id = c.param_id(&format!("B-ACRO-BODY/E8/acrobat/{act}/{k}")).unwrap();
            c.set_param(id, 0.0);
        }
    }
    let out = nunes::backflip(c, nunes::FLIP_SPACING, 600, |_| ()).unwrap();
    assert!(out.landed_at.is_some(), "{out:?}");
    assert!(out.touched_down && !out.flipped(), "{out:?}");
}

#[test]
fn the_simbicon_form_puts_feedback_on_the_swing_hip_only() {
    // simbicon::controller turns W-LEGS's swing hips into world-frame feedback targets (and the
    // inter-thigh target with them) and the trunk into a world angle, and leaves everything else.
    let walker = nunes::controller("walk").unwrap();
    let mut c = nunes::simbicon::controller(&walker).unwrap();
    for label in
        ["W-LEGS/E1/hip_l/k0", "W-LEGS/E3/hip_l/k1", "W-LEGS/E4/hip_r/k0", "W-LEGS/E6/inter_thigh/k1"]
    {
        assert!(c.param_id(label).is_some(), "{label}");
    }
    for label in
        ["W-LEGS/E1/hip_r/k0", "W-LEGS/E4/hip_l/k0", "W-LEGS/E1/knee_l/k0", "W-ARMS/E1/shoulder_l/k0"]
    {
        assert!(c.param_id(label).is_none(), "{label}");
    }
    let mut x: Vec<f64> = nunes::walk_poses::SPEC.to_vec();
    x.extend([0.7, 0.3]);
    nunes::simbicon::set(&mut c, &x);
    let get = |c: &anima_control::Controller, l: &str| c.param(c.param_id(l).unwrap());
    assert_eq!(get(&c, "W-LEGS/E4/hip_r/k0"), 0.7);
    assert_eq!(get(&c, "W-LEGS/E1/inter_thigh/k1"), 0.3);
    // A right swing moves hip_r, so hip_l − hip_r moves the other way.
    assert_eq!(get(&c, "W-LEGS/E4/inter_thigh/k1"), -0.3);
    assert_eq!(get(&c, "W-LEGS/E1/hip_l"), x[1]);
    assert!(c.to_ron().contains("WorldAngle"));
}

#[test]
fn the_simbicon_walker_walks_and_needs_its_feedback() {
    // The committed SIMBICON walker walks the thesis's 1000 iterations; with its two gains set to 0
    // (the same poses, fixed swing-hip targets in the world frame) it falls.
    let walk = |gains: Option<f64>| {
        let mut c = nunes::controller("walk-simbicon").unwrap();
        if let Some(g) = gains {
            let ids: Vec<_> = c
                .params()
                .iter()
                .enumerate()
                .filter(|(_, p)| p.kind == anima_control::ParamKind::FeedbackGain)
                .map(|(i, _)| i)
                .collect();
            assert_eq!(ids.len(), 16, "two gains on the swing hip and inter-thigh in four states");
            for i in ids {
                c.set_param(anima_control::ParamId(i), g);
            }
        }
        let rules = WalkRules { window: 0, ..WalkRules::default() };
        nunes::walk(c, 1000, &rules, &[], |_| ()).unwrap()
    };
    let with = walk(None);
    assert!(!with.fell && with.distance > 10.0, "{with:?}");
    let without = walk(Some(0.0));
    assert!(without.fell, "{without:?}");
}

#[test]
fn a_hard_push_on_the_head_knocks_the_walker_down() {
    // The push the optimiser comparison measures robustness with (a force on the head for two control
    // steps): nothing happens without it, and an impulse far beyond any reported survival fells the
    // walker, so the reported survivals are pushes that act.
    let c = nunes::controller("walk-optimised").unwrap();
    let rules = WalkRules { window: 0, ..WalkRules::default() };
    let run = |impulse: f64| {
        let push = nunes::Push::impulse(impulse, 400, 2);
        nunes::walk(c.clone(), 600, &rules, &[push], |_| ()).unwrap()
    };
    assert!(!run(0.0).fell);
    assert!(run(400.0).fell, "a 400 N·s forward push");
    assert!(run(-400.0).fell, "a 400 N·s backward push");
}

#[test]
fn the_symmetric_walker_copies_its_thresholds_on_e1() {
    // Variant A (spec §8.1.7): E1's procedure copies p2 → p5 and p3 → p6, so only p2 and p3 are
    // free. Without the procedure (walk.ron) p5 and p6 keep their own values.
    for (text, copies) in [
        (nunes::controller_text("walk-symmetric").unwrap().as_str(), true),
        (nunes::controller_text("walk").unwrap().as_str(), false),
    ] {
        let mut c = nunes::parse(text).unwrap();
        let id = |c: &anima_control::Controller, l: &str| c.param_id(l).unwrap();
        let (p2, p3, p5, p6) =
            (id(&c, "W-LEGS/T2/p0"), id(&c, "W-LEGS/T3/p0"), id(&c, "W-LEGS/T5/p0"), id(&c, "W-LEGS/T6/p0"));
        c.set_param(p2, 0.4);
        c.set_param(p3, 0.1);
        let free =
            c.free_params(&anima_control::Selection::machines(&["W-LEGS"], anima_control::Scope::Both));
        assert_eq!(free.len(), if copies { 2 } else { 4 });
        let mut seen = (f64::NAN, f64::NAN);
        nunes::walk(c, 10, &WalkRules::default(), &[], |ch| {
            seen = (ch.controller.param(p5), ch.controller.param(p6))
        })
        .unwrap();
        if copies {
            assert_eq!(seen, (0.4, 0.1));
        } else {
            assert_eq!(seen, (0.25, 0.25));
        }
    }
}

#[test]
fn the_temporal_walker_changes_state_on_time_alone() {
    // Variant B (spec §8.1.8): T2, T3, T5, T6 are temporal, so every visit to E2 lasts as long as
    // T2 says, whatever the body does; changing T2 changes every such visit by the same amount.
    let visits = |t2: f64| {
        let mut c = nunes::controller("walk-temporal").unwrap();
        c.set_param(c.param_id("W-LEGS/T2/time").unwrap(), t2);
        let legs = c.machine_index("W-LEGS").unwrap();
        let rules = WalkRules { window: 0, stop_on_failure: false, ..WalkRules::default() };
        let mut states = Vec::new();
        nunes::walk(c, 400, &rules, &[], |ch| states.push(ch.controller.machines()[legs].current_state()))
            .unwrap();
        // Lengths of the complete runs of E2 (state index 1).
        let mut lengths = Vec::new();
        let mut run = 0;
        for w in states.windows(2) {
            if w[1] == Some(1) {
                run += 1;
            } else if w[0] == Some(1) {
                lengths.push(run);
                run = 0;
            }
        }
        // The first visit is one iteration shorter than the rest (measured: 11 then 12s for T2 = 12);
        // compare the steady ones.
        lengths.split_off(1)
    };
    let (short, long) = (visits(12.0), visits(18.0));
    assert!(short.len() >= 3 && long.len() >= 3, "{short:?} {long:?}");
    assert!(short.iter().all(|&l| l == short[0]), "{short:?}");
    assert!(long.iter().all(|&l| l == long[0]), "{long:?}");
    assert_eq!(long[0] - short[0], 6, "{short:?} {long:?}");
}

#[test]
fn the_robust_walker_survives_20_n_s_pushes_both_ways() {
    // The goal beyond the thesis: the CMA-ES walker (nunes-robust) stays up 10 s after a 20 N·s push
    // on the head, forward and backward, 20 s into its walk.
    let c = nunes::controller("walk-robust").unwrap();
    let rules = WalkRules { window: 0, ..WalkRules::default() };
    for impulse in [20.0, -20.0] {
        let push = nunes::Push::impulse(impulse, 400, 2);
        let out = nunes::walk(c.clone(), 600, &rules, &[push], |_| ()).unwrap();
        assert!(!out.fell && out.distance > 10.0, "{impulse} N·s: {out:?}");
    }
}

#[test]
fn feedback_targets_read_the_centre_of_mass_sensors() {
    // A SIMBICON-style target on the humanoid: θ₀ + c_d·d + c_v·v with d = com_offset (ahead of the
    // right foot) and v = com_speed, both from the body catalogue, in the world frame.
    let text = r#"Controller(name: "f", actuators: ["hip_l"], machines: [Machine(name: "M", kind: Constant,
        states: [State(name: "E1", pose: [("hip_l", Feedback((base: 0.1, world: true, terms: [
            (gain: 2.0, sensor: (kind: "com_offset", args: ["right"])),
            (gain: 3.0, sensor: (kind: "com_speed")),
        ])))])],
        transitions: [Transition(when: Method)])])"#;
    let mut ch = nunes::humanoid_character(nunes::parse(text).unwrap()).unwrap();
    let mut moved = false;
    for _ in 0..20 {
        let s = ch.env.sensors[0].clone();
        ch.step().unwrap();
        let want = 0.1 + 2.0 * catalogue::com_offset(&s, 1) + 3.0 * catalogue::com_speed(&s);
        let sig = ch.env.world.commands(0).unwrap().signals()[0];
        assert_eq!(sig.frame, TargetFrame::World);
        let Target::Angle(got) = sig.target else { panic!("{sig:?}") };
        assert!((got - want).abs() < 1e-12, "{got} against {want}");
        moved |= (want - 0.1).abs() > 1e-3;
    }
    assert!(moved, "the sensors never moved the target");
}

/// A character scene of `assets/scenes/`, run through `anima run`'s code, with its evaluation.
fn run_scene(name: &str) -> anima_lab::run::body::EvaluationOutcome {
    use anima_lab::run::{Detail, RunOptions, Silent};
    let path = anima_lab::repo::Repo::here().assets(format!("scenes/{name}.ron"));
    let scene = anima_scene::load(&path, &anima_scene::LoadOptions::default()).unwrap();
    assert_eq!(scene.kind(), anima_scene::SceneKind::Character, "{name}");
    let s = anima_lab::run::run(&scene, name, &RunOptions::quiet(), &mut Silent).unwrap();
    let Detail::Body(d) = s.detail else { panic!("{name}: a figures summary") };
    d.evaluation.unwrap_or_else(|| panic!("{name}: the scene asks for an evaluation"))
}

#[test]
fn the_shipped_character_scenes_are_the_thesis_experiments() {
    use anima_lab::run::body::EvaluationOutcome;
    // The walk scene's evaluation is the walking evaluation of the optimised walker, to the bit.
    let EvaluationOutcome::Walk(w) = run_scene("walk") else { panic!("a walk evaluation") };
    let rules = WalkRules { window: 0, ..WalkRules::default() };
    let thesis =
        nunes::walk(nunes::controller("walk-optimised").unwrap(), 1000, &rules, &[], |_| ()).unwrap();
    assert_eq!(w, thesis);
    assert!(w.distance > 10.0 && !w.fell, "{w:?}");
    let EvaluationOutcome::Throw(t) = run_scene("throw") else { panic!("a throw evaluation") };
    let thesis =
        nunes::throw(nunes::controller("throw-optimised").unwrap(), &nunes::BASKET, 2000, |_| ()).unwrap();
    assert_eq!(t, thesis);
    assert!(t.scored, "{t:?}");
    let EvaluationOutcome::Backflip { outcome, flipped } = run_scene("backflip") else {
        panic!("a backflip")
    };
    let thesis =
        nunes::backflip(nunes::controller("backflip").unwrap(), nunes::FLIP_SPACING, 600, |_| ()).unwrap();
    assert_eq!(outcome, thesis);
    assert!(flipped, "{outcome:?}");
}

// ---------------------------------------------------------------------------------------------
// SIMBICON as published (`nunes::faithful`)

#[test]
fn the_faithful_walker_holds_the_torso_with_the_stance_hip_and_swaps_legs_at_the_strike() {
    use nunes::faithful;
    let mut ch = faithful::character(
        faithful::controller().unwrap(),
        &faithful::skeleton(),
        faithful::world_settings(),
    )
    .unwrap();
    let sk = ch.env.world.skeleton(0).unwrap().clone();
    let (hip_l, hip_r) = (sk.actuator_index("hip_l").unwrap(), sk.actuator_index("hip_r").unwrap());
    let torso = |ch: &anima_character::Character| -> Vec<(usize, Target)> {
        let signals = ch.env.world.commands(0).unwrap().signals();
        signals
            .iter()
            .filter(|s| matches!(s.target, Target::Torso { .. }))
            .map(|s| (s.actuator, s.target))
            .collect()
    };
    // The right leg stands first: its hip holds the pelvis upright, the left hip swings.
    ch.step().unwrap();
    assert_eq!(torso(&ch), vec![(hip_r, Target::Torso { angle: 0.0, swing: hip_l })]);
    let machine = ch.controller.machine_index(faithful::MACHINE).unwrap();
    let phase = |ch: &anima_character::Character| ch.controller.machines()[machine].phase();
    // Walk a few steps, until the left foot strikes: the legs change roles.
    for _ in 0..40 {
        ch.step().unwrap();
    }
    while phase(&ch) != Some(0) {
        ch.step().unwrap();
    }
    let mut k = 0;
    while phase(&ch) == Some(0) {
        ch.step().unwrap();
        k += 1;
        assert!(k < 40, "no foot strike in 2 s");
    }
    assert_eq!(catalogue::foot_down(&ch.env.sensors[0], 0), 1.0, "the left foot struck");
    // The next iteration reads this reading: the swing hip's balance feedback now reads the left
    // (stance) ankle.
    let (d, v) =
        (catalogue::com_ahead_of_ankle(&ch.env.sensors[0], 0), catalogue::com_speed(&ch.env.sensors[0]));
    ch.step().unwrap();
    assert_eq!(torso(&ch), vec![(hip_l, Target::Torso { angle: 0.0, swing: hip_r })]);
    let [(cd, cv), _] = faithful::gains(&ch.controller).unwrap();
    let swing =
        ch.env.world.commands(0).unwrap().signals().iter().find(|s| s.actuator == hip_r).copied().unwrap();
    assert_eq!(swing.frame, TargetFrame::World);
    let Target::Angle(a) = swing.target else { panic!("the swing hip tracks an angle") };
    assert!((a - (0.4 + cd * d + cv * v)).abs() < 1e-12, "swing hip target {a}, d = {d}, v = {v}");
    assert!(v.abs() > 0.05, "a case where the feedback counts: v = {v}");
}

#[test]
fn the_faithful_walker_walks_a_minute_with_its_gains_and_falls_without_them() {
    use nunes::faithful;
    let shipped = faithful::controller().unwrap();
    assert_eq!(faithful::gains(&shipped).unwrap(), [(0.0, 0.2), (2.2, 0.0)], "Table 1's walk");
    let with = faithful::walk_as_shipped(shipped.clone(), 60.0).unwrap();
    assert!(!with.outcome.fell && with.seconds == 60.0, "{with:?}");
    assert!((0.5..1.5).contains(&with.speed()), "{with:?}");
    assert!(with.strikes > 60, "a step at least every second: {with:?}");
    let without = faithful::walk_as_shipped(faithful::without_feedback(&shipped), 60.0).unwrap();
    assert!(without.outcome.fell && without.seconds < 5.0, "{without:?}");
    // The walk is SIMBICON's, not the figure's alone: on the thesis's gains it falls.
    let thesis = anima_body::BuiltinSkeleton::Humanoid.load().with_actuation(nunes::actuation()).unwrap();
    let c = faithful::character(shipped, &thesis, faithful::world_settings()).unwrap();
    let on_thesis = faithful::walk(c, 60.0).unwrap();
    assert!(on_thesis.outcome.fell, "{on_thesis:?}");
}

#[test]
fn the_simbicon_scene_is_the_faithful_walker() {
    use anima_lab::run::body::EvaluationOutcome;
    let EvaluationOutcome::Walk(w) = run_scene("walk-simbicon") else { panic!("a walk evaluation") };
    let walker = nunes::faithful::walk_as_shipped(nunes::faithful::controller().unwrap(), 60.0).unwrap();
    assert_eq!(w, walker.outcome);
    assert!(!w.fell && w.distance > 30.0, "{w:?}");
}

/// Issue #18's first two criteria for walker `c`: 1.0 ± 0.1 m/s over a minute on the flat, and still up
/// after SIMBICON's 70 N·s torso push forward and backward.
fn keeps_its_speed_and_survives_simbicons_push(c: &anima_control::Controller) {
    use anima_body::Relief;
    use nunes::protocol::{self, humanoid};
    let (fraction, distance) = protocol::walk_on(c, humanoid, Relief::Flat, protocol::MINUTE, &[]);
    assert!(
        fraction >= 1.0 && (distance / 60.0 - 1.0).abs() <= 0.1,
        "flat: {fraction}, {distance} m in 60 s"
    );
    assert!(protocol::survives_torso_push(c, humanoid, 70.0), "70 N·s forward");
    assert!(protocol::survives_torso_push(c, humanoid, -70.0), "70 N·s backward");
}

/// Issue #18's protocol: the walker CMA-ES found for it (`walk-protocol.ron`, `reproduce
/// nunes-protocol`) keeps 1.0 ± 0.1 m/s on the flat, survives SIMBICON's torso push of 70 N·s forward
/// and backward, and walks a minute (at least 30 m) up and down a 5° slope, down a 10° one and up and
/// down 5 cm steps. (Up 10° it stays up but covers 21 m: not pinned, not met; its slope form,
/// `walk-slopes.ron`, meets it below.)
#[test]
fn the_protocol_walker_keeps_its_speed_survives_simbicons_push_and_walks_slopes_and_steps() {
    use anima_body::Relief;
    use nunes::protocol::{self, humanoid};
    let c = nunes::controller("walk-protocol").unwrap();
    keeps_its_speed_and_survives_simbicons_push(&c);
    let minute = protocol::MINUTE;
    let slope = protocol::slope;
    let stairs = |rise| Relief::Stairs { from_x: 2.0, rise, run: 2.0, count: 1000 };
    for relief in [slope(5.0), slope(-5.0), slope(-10.0), stairs(0.05), stairs(-0.05)] {
        let (fraction, distance) = protocol::walk_on(&c, humanoid, relief, minute, &[]);
        assert!(fraction >= 1.0 && distance >= 30.0, "{relief:?}: {fraction} of the minute, {distance} m");
    }
}

/// Issue #18's protocol, all eight criteria: the protocol walker in its slope form (`walk-slopes.ron`,
/// `reproduce nunes-slopes`) keeps 1.0 ± 0.1 m/s, survives SIMBICON's 70 N·s torso push both ways, and
/// walks a minute (at least 30 m) up and down 5° and 10° slopes and 5 cm steps.
#[test]
fn the_slope_walker_meets_every_criterion_of_the_protocol() {
    use nunes::protocol::{self, humanoid};
    let c = nunes::controller("walk-slopes").unwrap();
    keeps_its_speed_and_survives_simbicons_push(&c);
    let minute = protocol::MINUTE;
    for (label, relief) in protocol::terrains() {
        let (fraction, distance) = protocol::walk_on(&c, humanoid, relief, minute, &[]);
        assert!(fraction >= 1.0 && distance >= 30.0, "{label}: {fraction} of the minute, {distance} m");
    }
}

/// The slope walker's gains serve the slopes between the protocol's too (gains searched on the
/// protocol's slopes alone fell within seconds at −7.5°): a minute on each of −7.5°, −2.5°, 2.5° and
/// 7.5° without falling.
#[test]
fn the_slope_walker_stays_up_on_the_slopes_between() {
    use nunes::protocol::{self, humanoid};
    let c = nunes::controller("walk-slopes").unwrap();
    let minute = protocol::MINUTE;
    for degrees in protocol::BETWEEN_SLOPES {
        let (fraction, distance) = protocol::walk_on(&c, humanoid, protocol::slope(degrees), minute, &[]);
        assert!(fraction >= 1.0, "{degrees}°: fell after {fraction} of the minute ({distance} m)");
    }
}

/// The slope form changes nothing on level ground: `walk-slopes.ron` walks the flat and the stairs
/// exactly as `walk-protocol.ron` does (the ground_slope sensor reads 0 there), and differs up a slope.
#[test]
fn the_slope_walker_is_the_protocol_walker_on_level_ground() {
    use anima_body::Relief;
    use nunes::protocol::{self, humanoid};
    let (slopes, start) =
        (nunes::controller("walk-slopes").unwrap(), nunes::controller("walk-protocol").unwrap());
    let stairs = Relief::Stairs { from_x: 2.0, rise: 0.05, run: 2.0, count: 1000 };
    for relief in [Relief::Flat, stairs] {
        let a = protocol::walk_on(&slopes, humanoid, relief, 400, &[]);
        let b = protocol::walk_on(&start, humanoid, relief, 400, &[]);
        assert_eq!(a, b, "{relief:?}");
    }
    let up = protocol::slope(10.0);
    let (a, b) = (
        protocol::walk_on(&slopes, humanoid, up, 400, &[]),
        protocol::walk_on(&start, humanoid, up, 400, &[]),
    );
    assert_ne!(a, b);
}

/// The slope form's gains mirror between the legs as the poses do: writing a vector as gains
/// (`slope_form::set`) puts on every entry's slope term what writing it as poses (`walk_poses::set`)
/// puts on its θ₀, except the E3/E6 stance knee, whose pose is fixed and whose gain stays 0.
#[test]
fn the_slope_gains_follow_the_pose_numbers() {
    use nunes::walk_poses::{self, Source};
    let mut c = nunes::slope_form::controller(&nunes::controller("walk-protocol").unwrap()).unwrap();
    let x: Vec<f64> = (0..12).map(|i| 0.1 * (i as f64 + 1.0) * if i % 2 == 0 { 1.0 } else { -1.0 }).collect();
    nunes::slope_form::set(&mut c, &x);
    walk_poses::set(&mut c, &x);
    let get = |label: &str| c.param(c.param_id(label).unwrap_or_else(|| panic!("no parameter {label}")));
    for (label, source) in walk_poses::layout() {
        let gain = get(&format!("{label}/k0"));
        match source {
            Source::Fixed(_) => assert_eq!(gain, 0.0, "{label}"),
            _ => assert_eq!(gain, get(&label), "{label}"),
        }
    }
    assert_eq!(walk_poses::layout().len(), 32);
}

#[test]
fn the_speed_walkers_keep_their_speeds_without_flight() {
    // Issue #18's target speeds: each committed walker stays up for a minute on the flat within
    // 0.1 m/s of its target, with no control step spent with neither foot on the ground (the search
    // penalised flight; the protocol walker, searched without that penalty, spends 12 % of its steps
    // in the air).
    for target in nunes::speeds::TARGETS {
        let c = nunes::controller(&nunes::speeds::walker_name(target)).unwrap();
        let (fraction, distance, flight) = nunes::speeds::walk_with_flight(&c, nunes::protocol::MINUTE, &[]);
        let speed = distance / 60.0;
        assert_eq!(fraction, 1.0, "{target} m/s: fell");
        assert!((speed - target).abs() <= 0.1, "{target} m/s: walks at {speed:.3} m/s");
        assert!(flight <= 0.01, "{target} m/s: {:.1} % of steps in flight", 100.0 * flight);
    }
}
