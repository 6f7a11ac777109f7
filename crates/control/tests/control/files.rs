//! Controller files: the shipped thesis controllers, round trips, and errors that name line, column
//! and field.

use anima_control::{
    Controller, ControllerError, ControllerErrorKind, Procedures, Selection, SensorInput, SensorQuery,
    TargetKind,
};

type Env = fn(&SensorQuery<'_>) -> f64;

fn procedures() -> Procedures<Env> {
    let mut p = Procedures::with_builtins();
    // The scene layer's weld release; here it only has to exist.
    p.register("release_ball", |_| {});
    p
}

fn asset(name: &str) -> String {
    let path = format!("{}/../../assets/controllers/{name}", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("reading {path}: {e}"))
}

/// The sensor kinds of the body crate's catalogue (`anima_body::sensors::catalogue`).
const CATALOGUE: &[&str] = &[
    "cog_low",
    "trunk_angle",
    "foot_up",
    "cog_ahead",
    "landing",
    "falling_forward",
    "falling_backward",
    "foot_on_hands",
    "flip_brake",
    "both_feet_down",
    "com_offset",
    "com_speed",
    "com_ahead_of_ankle",
    "foot_down",
    "trunk_rate",
    "ground_slope",
    "capture_outside",
];

#[test]
fn every_shipped_controller_parses() {
    let dir = format!("{}/../../assets/controllers", env!("CARGO_MANIFEST_DIR"));
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".ron"))
        .collect();
    names.sort();
    assert!(names.len() >= 3, "{names:?}");
    for name in &names {
        let c = Controller::from_ron(&asset(name), &procedures()).unwrap_or_else(|e| panic!("{name}: {e}"));
        for s in c.sensors() {
            assert!(
                CATALOGUE.contains(&s.kind.as_str()),
                "{name}: sensor kind `{}` not in the catalogue",
                s.kind
            );
        }
        assert!(c.warnings().is_empty(), "{name}: {:?}", c.warnings());
    }
}

#[test]
fn the_walker_has_the_thesis_structure_and_free_parameters() {
    let c = Controller::from_ron(&asset("walk.ron"), &procedures()).unwrap();
    let legs = &c.machines()[c.machine_index("W-LEGS").unwrap()];
    let arms = &c.machines()[c.machine_index("W-ARMS").unwrap()];
    assert_eq!((legs.n_states(), arms.n_states()), (6, 4));
    let free = c.free_params(&Selection::all());
    let labels: Vec<&str> = free.iter().map(|id| c.params()[id.0].label.as_str()).collect();
    assert_eq!(labels, ["W-LEGS/T2/p0", "W-LEGS/T3/p0", "W-LEGS/T5/p0", "W-LEGS/T6/p0"]);
    let space = c.space(&free);
    assert!(space.dims.iter().all(|d| (d.min, d.max) == (-0.25, 0.75)));
    assert_eq!(c.values_of(&free), vec![0.25; 4]);
}

#[test]
fn the_thrower_mirrors_its_arms_and_releases_the_ball_on_t2() {
    let released = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(u64::MAX));
    let mut procs = procedures();
    let r = released.clone();
    procs.register("release_ball", move |ctx| r.store(ctx.iteration(), std::sync::atomic::Ordering::SeqCst));
    let mut c = Controller::from_ron(&asset("throw.ron"), &procs).unwrap();
    let free = c.free_params(&Selection::all());
    assert_eq!(free.len(), 5, "s1, e1, s2, e2, τ2");
    let s2 = c.param_id("T-ARMS/E2/shoulder_l").unwrap();
    c.set_param(s2, 2.2);
    let mut t = c.new_targets();
    let mut env: Env = |_| 0.0;
    let mut right_shoulder = Vec::new();
    for _ in 0..110 {
        c.step(&mut env, &procs, &mut t);
        right_shoulder.push(t.mean_angle(12));
    }
    // E1 for 80 iterations (0..=79), E2 for τ2 = 20 (80..=99); the release fires with T2 at the end
    // of iteration 99; then E3's NoTorque entries leave no angle on the arms.
    assert_eq!(released.load(std::sync::atomic::Ordering::SeqCst), 99);
    assert_eq!(right_shoulder[79], Some(1.5));
    assert_eq!(right_shoulder[80], Some(2.2), "the symmetry procedure copied E2's left shoulder");
    assert_eq!(right_shoulder[100], None);
    assert!(t.signals().iter().filter(|s| s.actuator >= 10).all(|s| s.target == TargetKind::NoTorque));
}

#[test]
fn the_backflip_acrobat_t5_fires_five_iterations_after_the_push_starts() {
    // Spec §8.4.5: both S-FOOTONHANDS tests become true in the same iteration k0; the pusher counts
    // 100 iterations and pushes (E3), the acrobat crouches 85 and pushes off 20, so its E6 begins
    // 5 iterations after the pusher's E3.
    struct Flip {
        iteration: u64,
        on_from: u64,
    }
    impl SensorInput for Flip {
        fn sensor(&mut self, q: &SensorQuery<'_>) -> f64 {
            f64::from(u8::from(q.kind == "foot_on_hands" && self.iteration >= self.on_from))
        }
    }
    let procs = Procedures::<Flip>::with_builtins();
    let mut c = Controller::from_ron(&asset("backflip.ron"), &procs).unwrap();
    let pusher = c.machine_index("B-PUSHER").unwrap();
    let acro = c.machine_index("B-ACRO-BODY").unwrap();
    let k0 = 130u64; // the acrobat reaches E3 at 80 + 40 = 120
    let mut t = c.new_targets();
    let entered = |c: &Controller, m: usize, state: &str, k: u64, log: &mut Vec<(usize, String, u64)>| {
        let s = c.machines()[m].current_state().unwrap();
        let name = c.machines()[m].state_name(s).to_string();
        if !log.iter().any(|(mm, n, _)| *mm == m && *n == name) && name != state {
            log.push((m, name, k + 1));
        }
    };
    let mut log = Vec::new();
    for k in 0..400u64 {
        let mut env = Flip { iteration: c.iteration(), on_from: k0 };
        c.step(&mut env, &procs, &mut t);
        entered(&c, pusher, "E1", k, &mut log);
        entered(&c, acro, "E1", k, &mut log);
    }
    let at = |m: usize, s: &str| log.iter().find(|(mm, n, _)| *mm == m && n == s).map(|e| e.2).unwrap();
    assert_eq!(at(acro, "E3"), 120);
    assert_eq!(at(pusher, "E2"), k0 + 1);
    assert_eq!(at(acro, "E4"), k0 + 1);
    assert_eq!(at(pusher, "E3"), k0 + 1 + 100);
    assert_eq!(at(acro, "E5"), k0 + 1 + 85);
    assert_eq!(at(acro, "E6"), k0 + 1 + 105);
    assert_eq!(at(acro, "E6") - at(pusher, "E3"), 5);
}

#[test]
fn a_controller_survives_a_round_trip_through_ron() {
    for name in ["walk.ron", "throw.ron", "backflip.ron"] {
        let mut c = Controller::from_ron(&asset(name), &procedures()).unwrap();
        // Change a value so the round trip has to carry it.
        let id = c.free_params(&Selection::all()).first().copied().unwrap_or(anima_control::ParamId(0));
        c.set_param(id, c.param(id) + 0.125);
        let text = c.to_ron();
        let back =
            Controller::from_ron(&text, &procedures()).unwrap_or_else(|e| panic!("{name}: {e}\n{text}"));
        assert_eq!(back.param_values(), c.param_values(), "{name}");
        assert_eq!(back.params(), c.params(), "{name}");
    }
}

fn error(text: &str) -> ControllerError {
    Controller::from_ron(text, &procedures()).expect_err("the controller should be refused")
}

const GOOD: &str = r#"Controller(
    name: "probe",
    actuators: ["a", "b"],
    sensors: [Sensor(name: "s", kind: "foot_up", args: ["left"])],
    machines: [
        Machine(
            name: "M",
            kind: Constant,
            weight: 1.0,
            states: [
                State(name: "E1", pose: [("a", Angle(0.1)), (1, Angle(0.2))]),
                State(name: "E2", pose: [("a", Angle(0.3)), (1, NoTorque)]),
            ],
            transitions: [
                Transition(when: Temporal(20), delay: 2),
                Transition(when: Sensory((kind: "cog_ahead", params: [(value: 0.25, min: -0.25, max: 0.75)]))),
            ],
        ),
        Machine(name: "R", kind: Sensory("s"),
            states: [State(name: "E1", pose: [("b", Angle(0.0))])], transitions: [Transition(when: Method)]),
    ],
)"#;

/// `GOOD` with `from` replaced by `to` (which must occur exactly once).
fn broken(from: &str, to: &str) -> String {
    assert_eq!(GOOD.matches(from).count(), 1, "`{from}` must occur once");
    GOOD.replace(from, to)
}

#[test]
fn the_probe_controller_is_valid() {
    let c = Controller::from_ron(GOOD, &procedures()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(c.machines().len(), 2);
}

#[track_caller]
fn check(
    e: &ControllerError,
    kind: ControllerErrorKind,
    field: &str,
    line: usize,
    column: usize,
    says: &str,
) {
    assert_eq!(e.kind, kind, "{e}");
    assert_eq!(e.field, field, "{e}");
    assert_eq!((e.line, e.column), (Some(line), Some(column)), "{e}");
    assert!(e.message.contains(says), "`{}` should mention `{says}`", e.message);
    let shown = e.to_string();
    assert!(shown.contains(&format!("line {line}")) && shown.contains(field), "{shown}");
}

#[test]
fn a_misspelt_variant_names_line_column_and_field() {
    let e = error(&broken("Temporal(20)", "Temporl(20)"));
    check(&e, ControllerErrorKind::Syntax, "machines[0].transitions[0].when", 15, 34, "Temporl");
}

#[test]
fn an_unknown_field_names_line_column_and_field() {
    let e = error(&broken("weight: 1.0", "wieght: 1.0"));
    check(&e, ControllerErrorKind::Syntax, "machines[0].wieght", 9, 13, "wieght");
}

#[test]
fn a_value_of_the_wrong_type_names_line_column_and_field() {
    let e = error(&broken("delay: 2", "delay: \"two\""));
    check(&e, ControllerErrorKind::Syntax, "machines[0].transitions[0].delay", 15, 56, "number");
}

#[test]
fn an_unknown_sensor_names_line_column_and_field() {
    let e = error(&broken("Sensory(\"s\")", "Sensory(\"fall\")"));
    check(&e, ControllerErrorKind::Invalid, "machines[1].kind", 19, 28, "unknown sensor `fall`");
}

#[test]
fn an_actuator_index_out_of_range_names_line_column_and_field() {
    let e = error(&broken("(1, NoTorque)", "(7, NoTorque)"));
    check(&e, ControllerErrorKind::Invalid, "machines[0].states[1].pose[1]", 12, 61, "out of range");
}

#[test]
fn an_unknown_actuator_name_names_line_column_and_field() {
    let e = error(&broken("(\"a\", Angle(0.3))", "(\"c\", Angle(0.3))"));
    check(&e, ControllerErrorKind::Invalid, "machines[0].states[1].pose[0]", 12, 42, "unknown actuator `c`");
}

#[test]
fn a_parameter_outside_its_interval_names_line_column_and_field() {
    let e = error(&broken("value: 0.25", "value: 0.95"));
    check(&e, ControllerErrorKind::Invalid, "machines[0].transitions[1].when.params[0]", 16, 71, "outside");
}

#[test]
fn an_unknown_procedure_names_line_column_and_field() {
    let e = error(&broken(
        "State(name: \"E1\", pose: [(\"a\"",
        "State(name: \"E1\", procedure: Some(Call(name: \"mirror\")), pose: [(\"a\"",
    ));
    check(
        &e,
        ControllerErrorKind::Invalid,
        "machines[0].states[0].procedure.name",
        11,
        56,
        "unknown procedure `mirror`",
    );
}

#[test]
fn a_missing_transition_is_reported_on_the_transitions_field() {
    let e = error(&broken("                Transition(when: Temporal(20), delay: 2),\n", ""));
    check(&e, ControllerErrorKind::Invalid, "machines[0].transitions", 14, 13, "one transition per state");
}

#[test]
fn fractional_iterations_are_refused() {
    let e = error(&broken("delay: 2", "delay: 2.5"));
    check(&e, ControllerErrorKind::Invalid, "machines[0].transitions[0].delay", 15, 48, "whole iterations");
}

#[test]
fn protective_machines_blend_with_the_walking_arms() {
    struct Push {
        iteration: u64,
    }
    impl SensorInput for Push {
        // Pushed from behind from iteration 10 to 12 (a short raw pulse), never falling backward.
        fn sensor(&mut self, q: &SensorQuery<'_>) -> f64 {
            f64::from(u8::from(q.kind == "falling_forward" && (10..13).contains(&self.iteration)))
        }
    }
    let procs = Procedures::<Push>::new();
    let c0 = Controller::from_ron(&asset("walk-protected.ron"), &procs).unwrap();
    // The walking stage still selects only the four W-LEGS thresholds; the tolerances are sensor-set
    // parameters.
    let legs = c0.free_params(&Selection::machines(&["W-LEGS"], anima_control::Scope::Transitions));
    assert_eq!(legs.len(), 4);
    assert_eq!(c0.free_params(&Selection::all()).len(), 6);
    let mut c = c0.clone();
    let mut t = c.new_targets();
    let mut shoulder_l = Vec::new();
    for k in 0..20 {
        c.step(&mut Push { iteration: k }, &procs, &mut t);
        shoulder_l.push(t.mean_angle(10).unwrap());
    }
    // W-ARMS E1 sends −0.3 to the left shoulder; while the (held) sensor is active PROTECT-FWD adds
    // +2.4 with weight 3: (−0.3 + 3 · 2.4)/4. The 3-iteration pulse is held for the 5-iteration
    // hold-off (10..=14).
    let blended = (-0.3 + 3.0 * 2.4) / 4.0;
    for (k, a) in shoulder_l.iter().enumerate() {
        let expected = if (10..15).contains(&k) { blended } else { -0.3 };
        assert!((a - expected).abs() < 1e-12, "iteration {k}: {a} vs {expected}");
    }
}

#[test]
fn the_example_in_the_docs_parses() {
    let path = format!("{}/../../docs/control.md", env!("CARGO_MANIFEST_DIR"));
    let doc = std::fs::read_to_string(&path).unwrap();
    let example = doc.split("```ron\n").nth(1).and_then(|s| s.split("```").next()).expect("a ```ron block");
    let c = Controller::from_ron(example, &procedures()).unwrap_or_else(|e| panic!("docs/control.md: {e}"));
    assert_eq!(c.free_params(&Selection::all()).len(), 2, "T1's time and the sensor tolerance");
}

/// A machine `name` of `states` states named `E0…`, each posing actuator `a` and left after 20
/// iterations, one a line after the machine's first two lines.
fn machine(name: &str, states: usize) -> String {
    let mut text = format!("        Machine(name: \"{name}\", kind: Constant,\n            states: [\n");
    for s in 0..states {
        text.push_str(&format!("                State(name: \"E{s}\", pose: [(\"a\", Angle(0.1))]),\n"));
    }
    text.push_str("            ],\n            transitions: [\n");
    for _ in 0..states {
        text.push_str("                Transition(when: Temporal(20)),\n");
    }
    text.push_str("            ],\n        ),\n");
    text
}

/// A controller of these machines over the one actuator `a`; the first machine starts on line 5.
fn controller(machines: &[String]) -> String {
    format!(
        "Controller(\n    name: \"big\",\n    actuators: [\"a\"],\n    machines: [\n{}    ],\n)\n",
        machines.concat()
    )
}

/// More states than anima's limit are refused at the `states` field of the machine that passes it,
/// before anything is built for them; at the limit the checks are linear (issue #40: 100 000 states
/// took 27.7 s).
#[test]
fn states_above_the_limit_are_refused_and_checks_are_linear() {
    use anima_format::limits::MAX_STATES;
    let e = error(&controller(&[machine("M", MAX_STATES + 1)]));
    check(&e, ControllerErrorKind::Invalid, "machines[0].states", 6, 13, "at most 10000 states");
    // The count is the controller's, over its machines.
    let half = MAX_STATES / 2;
    let e = error(&controller(&[machine("M", half), machine("N", 1), machine("O", half)]));
    assert_eq!(e.field, "machines[2].states", "{e}");
    assert!(e.message.contains(&format!("found {}", 2 * half + 1)), "{e}");

    let start = std::time::Instant::now();
    let text = controller(&[machine("M", MAX_STATES)]);
    let c = Controller::from_ron(&text, &procedures()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(c.machines()[0].n_states(), MAX_STATES);
    // A duplicate at the end is still found, at its line.
    let last = MAX_STATES - 1;
    let e = error(&text.replace(&format!("\"E{last}\""), "\"E0\""));
    let field = format!("machines[0].states[{last}].name");
    check(&e, ControllerErrorKind::Invalid, &field, 7 + last, 23, "a second state named `E0`");
    let took = start.elapsed();
    // Quadratic checks took seconds for 10 000 states; linear ones take milliseconds (a generous
    // bound for a debug build on a busy machine).
    assert!(took.as_secs_f64() < 10.0, "{took:?}");
}

#[test]
fn procedure_arguments_are_checked_when_read() {
    let with_call = |call: &str| {
        broken(
            "State(name: \"E1\", pose: [(\"a\"",
            &format!("State(name: \"E1\", procedure: Some({call}), pose: [(\"a\""),
        )
    };
    let field = "machines[0].states[0].procedure.args";
    let e = error(&with_call("Call(name: \"negate_into\")"));
    check(&e, ControllerErrorKind::Invalid, field, 11, 35, "expected 1 argument");
    let e = error(&with_call("Call(name: \"negate_into\", args: [\"nowhere\"])"));
    check(&e, ControllerErrorKind::Invalid, field, 11, 77, "argument 0: expected a parameter");
    let e = error(&with_call(
        "Call(name: \"copy_params\", args: [\"machines[0].transitions[1].when.params[0]\"])",
    ));
    check(&e, ControllerErrorKind::Invalid, field, 11, 77, "pairs of parameters");
    let ok = with_call(
        "Call(name: \"copy_params\", args: [\"machines[0].transitions[1].when.params[0]\", \"machines[0].transitions[1].when.params[0]\"])",
    );
    if let Err(e) = Controller::from_ron(&ok, &procedures()) {
        panic!("a call with two parameters is read: {e}");
    }
}

/// Actuators and sensors have the states' limit, checked before anything is built for them.
#[test]
fn actuators_and_sensors_above_the_limit_are_refused() {
    use anima_format::limits::MAX_STATES;
    let names =
        |prefix: &str| (0..=MAX_STATES).map(|k| format!("\"{prefix}{k}\"")).collect::<Vec<_>>().join(", ");
    let text = controller(&[machine("M", 1)])
        .replace("actuators: [\"a\"]", &format!("actuators: [\"a\", {}]", names("x")));
    let e = error(&text);
    check(&e, ControllerErrorKind::Invalid, "actuators", 3, 5, "at most 10000 actuators");
    let sensors =
        (0..=MAX_STATES).map(|k| format!("Sensor(name: \"s{k}\", kind: \"never\")")).collect::<Vec<_>>();
    let text = controller(&[machine("M", 1)])
        .replace("    machines: [", &format!("    sensors: [{}],\n    machines: [", sensors.join(", ")));
    let e = error(&text);
    check(&e, ControllerErrorKind::Invalid, "sensors", 4, 5, "at most 10000 sensors");
}
