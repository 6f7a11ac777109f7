//! Machines with roles (SIMBICON's stance and swing legs) and torso targets (its stance hip): the roles
//! swap at a foot strike, sensors follow them, one parameter serves both sides, and the file's errors
//! name line, column and field.

use anima_control::{
    Controller, ControllerError, ControllerErrorKind, ParamKind, Procedures, SensorQuery, TargetKind, Targets,
};

/// A two-state SIMBICON machine over two legs: LIFT (2 iterations), STRIDE until the swing foot is down.
const SIMBICON: &str = r#"Controller(
    name: "simbicon",
    actuators: ["hip_l", "knee_l", "hip_r", "knee_r"],
    machines: [
        Machine(
            name: "S",
            kind: Constant,
            roles: Some(Roles(
                actuators: [
                    ("stance_hip", "hip_r", "hip_l"),
                    ("swing_hip", "hip_l", "hip_r"),
                    ("swing_knee", "knee_l", "knee_r"),
                    ("stance_knee", "knee_r", "knee_l"),
                ],
                args: [("stance", "right", "left"), ("swing", "left", "right")],
            )),
            states: [
                State(name: "LIFT", pose: [
                    ("stance_hip", Torso((angle: 0.05, swing: "swing_hip"))),
                    ("swing_hip", Feedback((base: 0.4, world: true, terms: [
                        (gain: 0.5, sensor: (kind: "com_ahead_of_ankle", args: ["stance"])),
                        (gain: 0.2, sensor: (kind: "com_speed")),
                    ]))),
                    ("swing_knee", Angle(-1.1)),
                    ("stance_knee", Angle(-0.05)),
                ]),
                State(name: "STRIDE", pose: [
                    ("stance_hip", Torso((angle: 0.0, swing: "swing_hip"))),
                    ("swing_hip", WorldAngle(-0.3)),
                    ("swing_knee", Angle(-0.05)),
                    ("stance_knee", Angle(-0.1)),
                ]),
            ],
            transitions: [
                Transition(name: "LIFTED", when: Temporal(2)),
                Transition(name: "STRIKE", when: Sensory((kind: "foot_down", args: ["swing"])), swap_roles: true),
            ],
        ),
    ],
)"#;

fn build(text: &str) -> Result<Controller, ControllerError> {
    Controller::from_ron(text, &Procedures::<()>::new())
}

/// The body as the controller sees it: d ahead of the left ankle is 0.1 m, of the right one 0.3 m;
/// v = 1 m/s; the left foot is down from iteration 3 on, the right one never.
struct Body {
    iteration: u64,
    asked: Vec<(String, Vec<String>)>,
}

impl anima_control::SensorInput for Body {
    fn sensor(&mut self, q: &SensorQuery<'_>) -> f64 {
        self.asked.push((q.kind.to_string(), q.args.to_vec()));
        let side = q.args.first().map(String::as_str);
        match (q.kind, side) {
            ("com_ahead_of_ankle", Some("left")) => 0.1,
            ("com_ahead_of_ankle", Some("right")) => 0.3,
            ("com_speed", _) => 1.0,
            ("foot_down", Some("left")) => f64::from(u8::from(self.iteration >= 3)),
            _ => 0.0,
        }
    }
}

/// Steps once and returns what each actuator was sent (by actuator name).
fn step(c: &mut Controller, body: &mut Body, out: &mut Targets) -> Vec<(String, TargetKind)> {
    c.step(body, &Procedures::new(), out);
    body.iteration += 1;
    out.signals().iter().map(|s| (c.actuators()[s.actuator].clone(), s.target)).collect()
}

fn sent<'a>(signals: &'a [(String, TargetKind)], actuator: &str) -> &'a TargetKind {
    &signals.iter().find(|(a, _)| a == actuator).unwrap_or_else(|| panic!("nothing sent to {actuator}")).1
}

#[test]
fn the_roles_swap_at_the_foot_strike_and_the_sensors_follow_them() {
    let mut c = build(SIMBICON).unwrap();
    let (hip_l, hip_r) = (0, 2);
    assert!(c.warnings().is_empty(), "{:?}", c.warnings());
    let mut out = c.new_targets();
    let mut body = Body { iteration: 0, asked: Vec::new() };
    // LIFT, right leg standing: the right hip holds the torso with the left hip as its swing; the left
    // hip's feedback reads the right (stance) ankle: 0.4 + 0.5·0.3 + 0.2·1.
    let s = step(&mut c, &mut body, &mut out);
    assert_eq!(sent(&s, "hip_r"), &TargetKind::Torso { angle: 0.05, swing: hip_l });
    let TargetKind::Angle(a) = *sent(&s, "hip_l") else { panic!("the swing hip tracks an angle") };
    assert!((a - 0.75).abs() < 1e-12, "{a}");
    assert!(matches!(sent(&s, "knee_l"), TargetKind::Angle(k) if *k == -1.1));
    assert!(matches!(sent(&s, "knee_r"), TargetKind::Angle(k) if *k == -0.05));
    assert!(body.asked.contains(&("com_ahead_of_ankle".into(), vec!["right".into()])), "{:?}", body.asked);
    assert_eq!(c.machines()[0].phase(), Some(0));
    // Iteration 1 ends LIFT; STRIDE waits for the left foot, down from iteration 3.
    step(&mut c, &mut body, &mut out);
    let s = step(&mut c, &mut body, &mut out);
    assert_eq!(sent(&s, "hip_r"), &TargetKind::Torso { angle: 0.0, swing: hip_l });
    assert_eq!((c.machines()[0].current_state(), c.machines()[0].phase()), (Some(1), Some(0)));
    // Iteration 3 still sends STRIDE with the right leg standing, then the strike swaps the roles.
    let s = step(&mut c, &mut body, &mut out);
    assert_eq!(sent(&s, "hip_r"), &TargetKind::Torso { angle: 0.0, swing: hip_l });
    assert_eq!((c.machines()[0].current_state(), c.machines()[0].phase()), (Some(0), Some(1)));
    // LIFT again, the left leg standing.
    body.asked.clear();
    let s = step(&mut c, &mut body, &mut out);
    assert_eq!(c.machines()[0].current_state(), Some(0));
    assert_eq!(sent(&s, "hip_l"), &TargetKind::Torso { angle: 0.05, swing: hip_r });
    let TargetKind::Angle(a) = *sent(&s, "hip_r") else { panic!("the swing hip tracks an angle") };
    assert!((a - (0.4 + 0.5 * 0.1 + 0.2)).abs() < 1e-12, "the left ankle's d now: {a}");
    assert!(matches!(sent(&s, "knee_r"), TargetKind::Angle(k) if *k == -1.1));
    assert!(body.asked.contains(&("com_ahead_of_ankle".into(), vec!["left".into()])), "{:?}", body.asked);
    // The strike sensor of the new phase watches the right foot, which never lands: no second swap.
    for _ in 0..5 {
        step(&mut c, &mut body, &mut out);
    }
    assert_eq!(c.machines()[0].phase(), Some(1));
    assert!(body.asked.contains(&("foot_down".into(), vec!["right".into()])), "{:?}", body.asked);
    // A reset starts over in the first phase.
    c.reset();
    let s = step(&mut c, &mut body, &mut out);
    assert_eq!(sent(&s, "hip_r"), &TargetKind::Torso { angle: 0.05, swing: hip_l });
}

#[test]
fn one_parameter_serves_both_sides_and_the_labels_name_the_roles() {
    let mut c = build(SIMBICON).unwrap();
    let label = |k: usize| c.params()[k].label.clone();
    let labels: Vec<String> = (0..c.params().len()).map(label).collect();
    for l in [
        "S/LIFT/stance_hip",
        "S/LIFT/swing_hip",
        "S/LIFT/swing_hip/k0",
        "S/LIFT/swing_hip/k1",
        "S/STRIDE/swing_knee",
    ] {
        assert!(labels.iter().any(|x| x == l), "no parameter {l}: {labels:?}");
    }
    let gain = c.param_id("S/LIFT/swing_hip/k0").unwrap();
    assert_eq!(c.params()[gain.0].kind, ParamKind::FeedbackGain);
    let torso = c.param_id("S/LIFT/stance_hip").unwrap();
    assert_eq!(c.params()[torso.0].path, "machines[0].states[0].pose[0].angle");
    // Changing c_d once changes both sides' feedback.
    c.set_param(gain, 1.0);
    let mut out = c.new_targets();
    let mut body = Body { iteration: 0, asked: Vec::new() };
    let s = step(&mut c, &mut body, &mut out);
    assert!(matches!(sent(&s, "hip_l"), TargetKind::Angle(a) if (*a - (0.4 + 0.3 + 0.2)).abs() < 1e-12));
    for _ in 0..4 {
        step(&mut c, &mut body, &mut out);
    }
    let s = step(&mut c, &mut body, &mut out);
    assert_eq!(c.machines()[0].phase(), Some(1));
    assert!(
        matches!(sent(&s, "hip_r"), TargetKind::Angle(a) if (*a - (0.4 + 0.1 + 0.2)).abs() < 1e-12),
        "{s:?}"
    );
    // The roles survive a round trip through RON, with the values as they are now.
    let back = build(&c.to_ron()).unwrap_or_else(|e| panic!("{e}\n{}", c.to_ron()));
    assert_eq!(back.param_values(), c.param_values());
    assert_eq!(back.params(), c.params());
    assert_eq!(back.torso_pairs(), vec![(2, 0), (0, 2)]);
}

/// `SIMBICON` with `from` replaced by `to` (which must occur exactly once).
fn broken(from: &str, to: &str) -> String {
    assert_eq!(SIMBICON.matches(from).count(), 1, "`{from}` must occur once");
    SIMBICON.replace(from, to)
}

#[track_caller]
fn refused(text: &str, field: &str, line: usize, says: &str) {
    let e = build(text).expect_err("the controller should be refused");
    assert_eq!(e.kind, ControllerErrorKind::Invalid, "{e}");
    assert_eq!(e.field, field, "{e}");
    assert_eq!(e.line, Some(line), "{e}");
    assert!(e.message.contains(says), "`{}` should mention `{says}`", e.message);
    assert!(e.to_string().contains(&format!("line {line}")), "{e}");
}

#[test]
fn role_errors_name_line_and_field() {
    // A pose names a role the machine does not have.
    refused(
        &broken(r#"("swing_knee", Angle(-1.1))"#, r#"("swing_kne", Angle(-1.1))"#),
        "machines[0].states[0].pose[2]",
        24,
        "unknown actuator `swing_kne`; the controller's actuators are: hip_l, knee_l, hip_r, knee_r; the \
         machine's roles: stance_hip, swing_hip, swing_knee, stance_knee",
    );
    // A role names an actuator the controller does not have.
    refused(
        &broken(r#"("swing_knee", "knee_l", "knee_r")"#, r#"("swing_knee", "knee_l", "ankle_r")"#),
        "machines[0].roles.actuators[2]",
        12,
        "unknown actuator `ankle_r`",
    );
    // A role may not be named like an actuator.
    refused(
        &broken(r#"("swing_knee", "knee_l", "knee_r")"#, r#"("knee_l", "knee_l", "knee_r")"#),
        "machines[0].roles.actuators[2]",
        12,
        "a name of its own",
    );
    // The stance hip's swing must be another actuator, in both phases.
    refused(
        &broken(r#"Torso((angle: 0.0, swing: "swing_hip"))"#, r#"Torso((angle: 0.0, swing: "stance_hip"))"#),
        "machines[0].states[1].pose[0].swing",
        28,
        "another one than `stance_hip`",
    );
    refused(
        &broken(r#"Torso((angle: 0.0, swing: "swing_hip"))"#, r#"Torso((angle: 0.0, swing: "hip_l"))"#),
        "machines[0].states[1].pose[0].swing",
        28,
        "another one",
    );
    // A role and a plain actuator that coincide once the roles swap.
    refused(
        &broken(r#"("stance_knee", Angle(-0.05))"#, r#"("knee_r", Angle(-0.05))"#),
        "machines[0].states[0].pose[3]",
        25,
        "appears twice in this pose (with the roles swapped)",
    );
    // Swapping roles needs roles.
    let no_roles = r#"Controller(name: "m", actuators: ["a"], machines: [Machine(name: "M", kind: Constant,
        states: [State(name: "E1", pose: [("a", Angle(0.1))])],
        transitions: [Transition(when: Temporal(5), swap_roles: true)])])"#;
    let e = build(no_roles).expect_err("swap_roles without roles");
    assert_eq!(e.field, "machines[0].transitions[0].swap_roles", "{e}");
    assert_eq!(e.line, Some(3), "{e}");
    assert!(e.message.contains("has no roles"), "{e}");
    // A misspelt role table entry is ron's error, placed as well.
    let e = build(&broken("args: [(\"stance\"", "argz: [(\"stance\"")).expect_err("an unknown field");
    assert_eq!(e.kind, ControllerErrorKind::Syntax, "{e}");
    assert_eq!((e.field.as_str(), e.line), ("machines[0].roles.argz", Some(15)), "{e}");
}

#[test]
fn a_machine_with_roles_that_never_swap_is_warned_about() {
    let c = build(&broken(", swap_roles: true", "")).unwrap();
    assert!(c.warnings().iter().any(|w| w.contains("no transition swaps them")), "{:?}", c.warnings());
}
