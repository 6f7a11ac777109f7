//! State-machine semantics of spec §6 on small synthetic controllers.

use std::sync::{Arc, Mutex};

use anima_control::{Controller, Frame, Procedures, SensorInput, SensorQuery, TargetKind, Targets};

/// Sensor input from a closure of (sensor kind, iteration).
struct Script<F: FnMut(&str, u64) -> f64> {
    f: F,
    iteration: u64,
    measured: Option<f64>,
}

impl<F: FnMut(&str, u64) -> f64> SensorInput for Script<F> {
    fn sensor(&mut self, q: &SensorQuery<'_>) -> f64 {
        (self.f)(q.kind, self.iteration)
    }
    fn actuator_angle(&mut self, _actuator: usize, _frame: Frame) -> Option<f64> {
        self.measured
    }
}

fn script<F: FnMut(&str, u64) -> f64>(f: F) -> Script<F> {
    Script { f, iteration: 0, measured: None }
}

fn build(text: &str) -> Controller {
    Controller::from_ron(text, &Procedures::<()>::new()).unwrap_or_else(|e| panic!("{e}"))
}

/// Steps `n` iterations and returns the angle sent to `actuator` each iteration (`None` if none).
fn angles<F: FnMut(&str, u64) -> f64>(
    c: &mut Controller,
    input: &mut Script<F>,
    n: u64,
    actuator: usize,
) -> Vec<Option<f64>> {
    let procs = Procedures::new();
    let mut t = c.new_targets();
    (0..n)
        .map(|k| {
            input.iteration = k;
            c.step(input, &procs, &mut t);
            t.mean_angle(actuator)
        })
        .collect()
}

const TWO_STATES: &str = r#"Controller(
    name: "two",
    actuators: ["a"],
    machines: [Machine(
        name: "M", kind: Constant,
        states: [State(name: "E1", pose: [("a", Angle(0.0))]), State(name: "E2", pose: [("a", Angle(1.0))])],
        transitions: [
            Transition(when: Temporal(3), delay: 4),
            Transition(when: Sensory((kind: "always")), delay: 2),
        ],
    )],
)"#;

#[test]
fn pose_is_blended_linearly_over_the_interpolation_delay() {
    let mut c = build(TWO_STATES);
    let mut input = script(|_, _| 1.0);
    let a: Vec<f64> = angles(&mut c, &mut input, 8, 0).into_iter().map(Option::unwrap).collect();
    // E1 is used for exactly τ = 3 iterations (0, 1, 2), sent directly (no previous state). E2 starts
    // in iteration 3 with N_I = 0, which still sends P_anterior; Eq. 5.3 then reaches P_ativa at
    // N_I = D_I = 4 (iteration 7).
    assert_eq!(a, vec![0.0, 0.0, 0.0, 0.0, 0.25, 0.5, 0.75, 1.0]);
}

#[test]
fn transitions_wait_for_the_blend_to_finish() {
    let mut c = build(TWO_STATES);
    let mut input = script(|_, _| 1.0);
    let procs = Procedures::new();
    let mut t = c.new_targets();
    let mut states = Vec::new();
    for k in 0..16 {
        input.iteration = k;
        c.step(&mut input, &procs, &mut t);
        states.push(c.machines()[0].current_state().unwrap());
    }
    // The state used in iteration k+1 after step k. T2's sensor is always active, but E2 (entered
    // with D_I = 4) may leave only at N_I = 4: E2 is used in iterations 3..=7. E1 is then entered
    // with D_I = 2 and τ = 3 ≥ D_I + 1, so it is used for exactly 3 iterations (8..=10).
    let used: Vec<usize> = std::iter::once(0).chain(states.iter().copied()).take(16).collect();
    assert_eq!(used, vec![0, 0, 0, 1, 1, 1, 1, 1, 0, 0, 0, 1, 1, 1, 1, 1]);
}

#[test]
fn temporal_time_shorter_than_the_delay_waits_for_the_delay() {
    let text = r#"Controller(name: "t", actuators: ["a"], machines: [Machine(name: "M", kind: Constant,
        states: [State(name: "E1", pose: [("a", Angle(0.0))]), State(name: "E2", pose: [("a", Angle(1.0))])],
        transitions: [Transition(when: Temporal(1), delay: 5), Transition(when: Temporal(2), delay: 5)])])"#;
    let mut c = build(text);
    let procs = Procedures::new();
    let mut t = c.new_targets();
    let mut input = script(|_, _| 0.0);
    let mut entered = Vec::new();
    let mut last = 0;
    for k in 0..20 {
        c.step(&mut input, &procs, &mut t);
        let s = c.machines()[0].current_state().unwrap();
        if s != last {
            entered.push((k + 1, s));
            last = s;
        }
    }
    // E1 first: τ = 1, no incoming delay → one iteration. Every later state has D_I = 5 > τ − 1, so it
    // is used D_I + 1 = 6 iterations.
    assert_eq!(entered, vec![(1, 1), (7, 0), (13, 1), (19, 0)]);
}

#[test]
fn machine_sensor_hold_off_filters_chatter() {
    let text = r#"Controller(name: "h", actuators: ["a"],
        sensors: [Sensor(name: "s", kind: "raw", oscillation_delay: 3)],
        machines: [
            Machine(name: "REFLEX", kind: Sensory("s"),
                states: [State(name: "E1", pose: [("a", Angle(1.0))])], transitions: [Transition(when: Method)]),
            Machine(name: "IDLE", kind: Default,
                states: [State(name: "E1", pose: [("a", Angle(-1.0))])], transitions: [Transition(when: Method)]),
        ])"#;
    let raw = [0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 2.5, 0.0];
    let mut c = build(text);
    let mut input = script(|_, k| raw[k as usize]);
    let sent = angles(&mut c, &mut input, raw.len() as u64, 0);
    // Hold-off of 3: a change of the filtered state is held for at least 3 iterations; the first
    // activation is immediate. The sensory machine runs while active, the default one otherwise.
    let active = [false, true, true, true, true, false, false, false, false, true, true];
    let expected: Vec<Option<f64>> = active.iter().map(|&a| Some(if a { 1.0 } else { -1.0 })).collect();
    assert_eq!(sent, expected);
    assert_eq!(c.machine_sensors()[0].value(), 0.0);
    assert!(c.machine_sensors()[0].active());
}

#[test]
fn a_machine_restarts_at_its_first_state_without_blending() {
    let text = r#"Controller(name: "r", actuators: ["a"],
        sensors: [Sensor(name: "s", kind: "raw")],
        machines: [Machine(name: "M", kind: Sensory("s"),
            states: [State(name: "E1", pose: [("a", Angle(0.0))]), State(name: "E2", pose: [("a", Angle(1.0))])],
            transitions: [Transition(when: Temporal(2), delay: 2), Transition(when: Temporal(10), delay: 2)])])"#;
    let on = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 1.0, 1.0];
    let mut c = build(text);
    let mut input = script(|_, k| on[k as usize]);
    let sent = angles(&mut c, &mut input, on.len() as u64, 0);
    // E1 twice, E2 blended in (0, 0.5, 1, 1), then off (no targets, progress lost), then E1 again
    // from its own pose (no blend from E2's).
    assert_eq!(
        sent,
        vec![Some(0.0), Some(0.0), Some(0.0), Some(0.5), Some(1.0), Some(1.0), None, Some(0.0), Some(0.0)]
    );
    // E1 was used twice again (iterations 7 and 8), so E2 comes next.
    assert_eq!(c.machines()[0].current_state(), Some(1));

    // Disabling and re-enabling also restarts.
    let mut c = build(text);
    let procs = Procedures::new();
    let mut t = c.new_targets();
    let mut input = script(|_, _| 1.0);
    for _ in 0..4 {
        c.step(&mut input, &procs, &mut t);
    }
    assert_eq!(c.machines()[0].current_state(), Some(1));
    c.set_enabled(0, false);
    c.step(&mut input, &procs, &mut t);
    assert!(t.signals().is_empty());
    assert_eq!(c.machines()[0].current_state(), None);
    c.set_enabled(0, true);
    c.step(&mut input, &procs, &mut t);
    assert_eq!(t.mean_angle(0), Some(0.0));
}

#[test]
fn disabled_active_sensory_machine_still_suppresses_default_machines() {
    let text = r#"Controller(name: "d", actuators: ["a"],
        sensors: [Sensor(name: "s", kind: "raw")],
        machines: [
            Machine(name: "S", kind: Sensory("s"), enabled: false,
                states: [State(name: "E1", pose: [("a", Angle(1.0))])], transitions: [Transition(when: Method)]),
            Machine(name: "D", kind: Default,
                states: [State(name: "E1", pose: [("a", Angle(-1.0))])], transitions: [Transition(when: Method)]),
        ])"#;
    let mut c = build(text);
    let mut input = script(|_, k| if k < 2 { 0.0 } else { 1.0 });
    // Literal Fig. 5.3: nobody drives the actuator once the sensor is active.
    assert_eq!(angles(&mut c, &mut input, 4, 0), vec![Some(-1.0), Some(-1.0), None, None]);
}

#[test]
fn several_machines_on_one_actuator_are_averaged_by_weight() {
    let text = r#"Controller(name: "w", actuators: ["a", "b"], machines: [
        Machine(name: "A", kind: Constant, weight: 1.0,
            states: [State(name: "E1", pose: [("a", Angle(0.4)), ("b", Angle(0.2))])], transitions: [Transition(when: Method)]),
        Machine(name: "B", kind: Constant, weight: 3.0,
            states: [State(name: "E1", pose: [("a", Angle(-0.4)), ("b", DampingOnly)])], transitions: [Transition(when: Method)]),
        Machine(name: "C", kind: Constant, weight: 5.0,
            states: [State(name: "E1", pose: [(0, NoTorque), (1, NoTorque)])], transitions: [Transition(when: Method)]),
    ])"#;
    let mut c = build(text);
    let procs = Procedures::new();
    let mut t = c.new_targets();
    c.step(&mut script(|_, _| 0.0), &procs, &mut t);
    assert_eq!(t.signals().len(), 6);
    // Eq. 5.1 with NoTorque skipped: (0.4·1 − 0.4·3)/4.
    assert!((t.mean_angle(0).unwrap() + 0.2).abs() < 1e-15);
    // PD torques kp(θd − θ) with kp = 10, θ = 0.1; DampingOnly gives −kd θ̇ = 0 at rest.
    let torque = |s: &anima_control::TargetSignal| match s.target {
        TargetKind::Angle(a) => Some(10.0 * (a - 0.1)),
        TargetKind::DampingOnly => Some(0.0),
        TargetKind::NoTorque | TargetKind::Torso { .. } => None,
    };
    let tb = t.weighted_mean(1, torque).unwrap();
    assert!((tb - 10.0 * 0.1 * 1.0 / 4.0).abs() < 1e-12, "{tb}");
    let weights: Vec<f64> = t.for_actuator(0).map(|s| s.weight).collect();
    assert_eq!(weights, vec![1.0, 3.0, 5.0]);
}

#[test]
fn special_entries_switch_at_once_and_blends_start_from_the_measured_angle() {
    let text = r#"Controller(name: "m", actuators: ["a", "b"], machines: [Machine(name: "M", kind: Constant,
        states: [
            State(name: "E1", pose: [("a", NoTorque), ("b", Angle(0.0))]),
            State(name: "E2", pose: [("a", Angle(1.0)), ("b", DampingOnly)]),
        ],
        transitions: [Transition(when: Temporal(1), delay: 2), Transition(when: Method)])])"#;
    let mut c = build(text);
    let procs = Procedures::new();
    let mut t = c.new_targets();
    let mut input = script(|_, _| 0.0);
    input.measured = Some(0.5);
    c.step(&mut input, &procs, &mut t);
    let got: Vec<_> = (0..3)
        .map(|_| {
            c.step(&mut input, &procs, &mut t);
            (t.signals()[0].target, t.signals()[1].target)
        })
        .collect();
    // a: from the measured 0.5 towards 1.0 over D_I = 2; b: DampingOnly from the first iteration.
    assert_eq!(
        got,
        vec![
            (TargetKind::Angle(0.5), TargetKind::DampingOnly),
            (TargetKind::Angle(0.75), TargetKind::DampingOnly),
            (TargetKind::Angle(1.0), TargetKind::DampingOnly),
        ]
    );
}

#[test]
fn method_transitions_fire_only_when_invoked_on_the_current_transition() {
    let text = r#"Controller(name: "k", actuators: ["a"], machines: [Machine(name: "M", kind: Constant,
        states: [State(name: "E1", pose: [("a", Angle(0.0))]), State(name: "E2", pose: [("a", Angle(1.0))])],
        transitions: [Transition(name: "go", when: Method, delay: 0), Transition(name: "back", when: Method)])])"#;
    let mut c = build(text);
    let procs = Procedures::new();
    let mut t = c.new_targets();
    let mut input = script(|_, _| 0.0);
    assert!(!c.trigger(0, 0), "not running yet");
    c.step(&mut input, &procs, &mut t);
    assert!(!c.trigger(0, 1), "not the current transition");
    for _ in 0..5 {
        c.step(&mut input, &procs, &mut t);
    }
    assert_eq!(c.machines()[0].current_state(), Some(0));
    let go = c.machines()[0].transition_index("go").unwrap();
    assert!(c.trigger(0, go));
    c.step(&mut input, &procs, &mut t);
    assert_eq!(c.machines()[0].current_state(), Some(1));
    c.step(&mut input, &procs, &mut t);
    assert_eq!(t.mean_angle(0), Some(1.0));
}

#[test]
fn procedures_fire_on_states_transitions_and_sensors() {
    let text = r#"Controller(name: "p", actuators: ["waist"],
        sensors: [
            Sensor(name: "tilt", kind: "trunk_angle", procedure: Some(Call(name: "negate_into", args: ["BAL/E1/waist"])),
                fire: WhileActive),
            Sensor(name: "edge", kind: "raw", procedure: Some(Call(name: "log", args: ["sensor"]))),
        ],
        machines: [
            Machine(name: "BAL", kind: Sensory("tilt"),
                states: [State(name: "E1", pose: [("waist", Angle(0.0))])], transitions: [Transition(when: Method)]),
            Machine(name: "M", kind: Constant,
                states: [
                    State(name: "E1", procedure: Some(Call(name: "log", args: ["state"]))),
                    State(name: "E2"),
                ],
                transitions: [
                    Transition(when: Temporal(2), procedure: Some(Call(name: "log", args: ["transition"]))),
                    Transition(when: Temporal(2)),
                ]),
        ])"#;
    let events = Arc::new(Mutex::new(Vec::<(u64, String, f64)>::new()));
    let mut procs = Procedures::<Script<fn(&str, u64) -> f64>>::with_builtins();
    let ev = events.clone();
    procs.register("log", move |ctx| {
        let what = ctx.args()[0].clone();
        ev.lock().unwrap().push((ctx.iteration(), what, ctx.value()));
    });
    let mut c = Controller::from_ron(text, &procs).unwrap_or_else(|e| panic!("{e}"));
    fn raw(kind: &str, k: u64) -> f64 {
        match kind {
            "trunk_angle" => [0.0, 0.3, -0.2, 0.0, 0.0, 0.0][k as usize],
            _ => [0.0, 1.0, 1.0, 0.0, 1.0, 1.0][k as usize],
        }
    }
    let mut input = Script { f: raw as fn(&str, u64) -> f64, iteration: 0, measured: None };
    let mut t = c.new_targets();
    let mut waist = Vec::new();
    for k in 0..6 {
        input.iteration = k;
        c.step(&mut input, &procs, &mut t);
        waist.push(t.mean_angle(0));
    }
    // Fig. 4.6: while the trunk sensor is active its procedure sets θd = −α before the machine runs.
    assert_eq!(waist, vec![None, Some(-0.3), Some(0.2), None, None, None]);
    let ev = events.lock().unwrap().clone();
    let of = |w: &str| ev.iter().filter(|e| e.1 == w).map(|e| e.0).collect::<Vec<_>>();
    // State procedure: every iteration E1 is active (0, 1, then 4, 5 after a full cycle).
    assert_eq!(of("state"), vec![0, 1, 4, 5]);
    // Transition procedure: once per switch (at the end of E1's second iteration).
    assert_eq!(of("transition"), vec![1, 5]);
    // Sensor procedure, OnActivation mode: at each rising edge, with the return value.
    assert_eq!(of("sensor"), vec![1, 4]);
    assert!(ev.iter().filter(|e| e.1 == "sensor").all(|e| e.2 == 1.0));
}

#[test]
fn the_step_does_not_allocate_target_storage() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/controllers/backflip.ron"
    ))
    .unwrap();
    let procs = Procedures::<Script<fn(&str, u64) -> f64>>::with_builtins();
    let mut c = Controller::from_ron(&text, &procs).unwrap();
    let mut t: Targets = c.new_targets();
    let (ptr, cap) = (t.signals().as_ptr(), t.capacity());
    fn raw(_: &str, k: u64) -> f64 {
        f64::from(u8::from(k % 7 == 3))
    }
    let mut input = Script { f: raw as fn(&str, u64) -> f64, iteration: 0, measured: None };
    for k in 0..2000 {
        input.iteration = k;
        c.step(&mut input, &procs, &mut t);
        assert!(t.signals().len() <= cap);
    }
    assert_eq!((t.signals().as_ptr(), t.capacity()), (ptr, cap), "targets storage was reallocated");
}

const FEEDBACK: &str = r#"Controller(
    name: "simbicon",
    actuators: ["swing_hip"],
    machines: [Machine(
        name: "M", kind: Constant,
        states: [State(name: "E1", pose: [("swing_hip", Feedback((
            base: 0.5,
            world: true,
            terms: [
                (gain: (value: 0.3, min: 0.0, max: 1.0), sensor: (kind: "com_offset", args: ["right"])),
                (gain: -0.2, sensor: (kind: "com_speed")),
            ],
        )))])],
        transitions: [Transition(when: Method)],
    )],
)"#;

#[test]
fn a_feedback_target_is_its_base_plus_gains_times_sensors_every_iteration() {
    // SIMBICON-style: θ = θ₀ + c_d·d + c_v·v with d, v read from the sensor input each iteration.
    let mut c = build(FEEDBACK);
    let mut input = script(|kind, k| match kind {
        "com_offset" => 0.1 * k as f64,
        "com_speed" => 1.0 - 0.5 * k as f64,
        _ => 0.0,
    });
    let a: Vec<f64> = angles(&mut c, &mut input, 4, 0).into_iter().map(Option::unwrap).collect();
    for (k, got) in a.iter().enumerate() {
        let k = k as f64;
        let want = 0.5 + 0.3 * (0.1 * k) - 0.2 * (1.0 - 0.5 * k);
        assert!((got - want).abs() < 1e-12, "iteration {k}: {got} against {want}");
    }
    let procs = Procedures::new();
    let mut t = c.new_targets();
    c.step(&mut input, &procs, &mut t);
    assert_eq!(t.signals()[0].frame, Frame::World);
    // The gains are parameters: c_d free (it has an interval), c_v fixed.
    let free = c.free_params(&anima_control::Selection::all());
    let labels: Vec<&str> = free.iter().map(|&i| c.params()[i.0].label.as_str()).collect();
    assert_eq!(labels, ["M/E1/swing_hip/k0"]);
    c.set_param(free[0], 0.0);
    let mut again = script(|kind, _| if kind == "com_speed" { 2.0 } else { 5.0 });
    let a = angles(&mut c, &mut again, 1, 0)[0].unwrap();
    assert!((a - (0.5 - 0.4)).abs() < 1e-12, "{a}");
}

#[test]
fn feedback_targets_survive_a_round_trip_and_name_a_missing_sensor_kind() {
    let c = build(FEEDBACK);
    let back = build(&c.to_ron());
    assert_eq!(back.params().len(), c.params().len());
    let bad = FEEDBACK.replace(r#"(kind: "com_speed")"#, r#"(kind: "")"#);
    let err = Controller::from_ron(&bad, &Procedures::<()>::new()).unwrap_err().to_string();
    assert!(err.contains("terms[1].sensor.kind"), "{err}");
    let typo = FEEDBACK.replace("gain: -0.2", "gian: -0.2");
    let err = Controller::from_ron(&typo, &Procedures::<()>::new()).unwrap_err().to_string();
    assert!(err.contains("gian") && err.contains("line"), "{err}");
}
