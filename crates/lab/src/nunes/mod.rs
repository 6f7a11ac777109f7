//! The experiments of Nunes 2006 Chapter 6 on anima's bodies and controllers: worlds, evaluators and
//! fitness functions (spec §7.4, §7.6) in this module; the thesis's optimisation runs beside its numbers
//! ([`report`], `cargo xtask reproduce nunes`), the optimiser comparisons and the robust and SIMBICON
//! searches beyond the thesis ([`optimisers`]), SIMBICON as it was published ([`faithful`]), the
//! search for a thesis-faithful walker ([`faithful_walk`]), SIMBICON's push, slopes and steps on every
//! committed walker ([`robustness`]), and the strobe figures ([`figures`]).

pub mod faithful;
pub mod faithful_walk;
pub mod figures;
pub mod optimisers;
pub mod protocol;
pub mod report;
pub mod robustness;
pub mod speeds;

use anima_body::Actuation;
use anima_control::Controller;
use anyhow::Context as _;

use anima_character::{Character, CharacterError};

/// The text of a controller shipped in `assets/controllers/` (`"walk"` for `walk.ron`): the thesis's
/// walker (`walk`), its optimised (`walk-optimised`), push-robust (`walk-robust`), SIMBICON
/// (`walk-simbicon`), symmetric (`walk-symmetric`, variant A) and temporal (`walk-temporal`, variant B)
/// forms, SIMBICON as published (`walk-simbicon-faithful`), the thrower (`throw`, `throw-optimised`) and
/// the backflip pair (`backflip`).
pub fn controller_text(name: &str) -> anyhow::Result<String> {
    let path = crate::repo::Repo::here().assets(format!("controllers/{name}.ron"));
    std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))
}

/// A shipped controller (see [`controller_text`]), parsed with the character procedures.
pub fn controller(name: &str) -> anyhow::Result<Controller> {
    let text = controller_text(name)?;
    parse(&text).with_context(|| format!("assets/controllers/{name}.ron"))
}

pub use anima_run::objectives::*;

/// The gain multiplier G of the configuration closest to the thesis in which its before-and-after
/// holds (the walker of `walk.ron` falls at p = 0.25 and the thesis's staged search makes it walk):
/// implicit springs, 4 sub-steps, the re-authored poses. Found by the scan of [`faithful_walk`]
/// (`cargo xtask reproduce nunes-walk-faithful`, `docs/reproduction/nunes-walk-faithful.md`: the
/// spec's poses walk under no reading tried; with the re-authored ones G = 26 and 27 fall before and
/// walk after, G ≥ 28 walk before any search). That the falling-then-walking holds is a property of the scan's choice, not of
/// any number of the thesis's.
pub const FAITHFUL_GAIN: f64 = 27.0;

/// The actuation of [`FAITHFUL_GAIN`]: the experiments' implicit springs with every gain, cap and brake
/// × 27 instead of × 100.
pub fn faithful_actuation() -> Actuation {
    Actuation { gain_scale: FAITHFUL_GAIN, ..actuation() }
}

/// A humanoid with the actuation of [`FAITHFUL_GAIN`], standing on the ground, driven by `controller`.
pub fn faithful_character(controller: Controller) -> Result<Character, CharacterError> {
    humanoid_with(controller, faithful_actuation())
}

/// The spacings of the pair at which the backflip must land standing (issue #18): 0.86 to 0.94 m.
pub const FLIP_SPACINGS: [f64; 5] = [0.86, 0.88, 0.9, 0.92, 0.94];

/// The spacings of [`FLIP_SPACINGS`]' range in steps of 5 mm (0.86, 0.865, …, 0.94 m): the flip at
/// spacings it was not tuned at.
pub fn flip_fine_spacings() -> Vec<f64> {
    let (near, far) = (FLIP_SPACINGS[0], FLIP_SPACINGS[FLIP_SPACINGS.len() - 1]);
    let steps = ((far - near) / 0.005).round() as usize;
    (0..=steps).map(|k| near + 0.005 * k as f64).collect()
}

/// The backflip controller's label of the margin of its recovery step's trigger (the acrobat's T8,
/// `capture_outside`).
pub const FLIP_STEP_MARGIN: &str = "B-ACRO-BODY/T8/p0";

/// `c` (the backflip controller) with its recovery step disabled: T8's margin so wide (100 m) that
/// the capture point never leaves it, so the acrobat keeps its landing stance E8 whatever happens.
///
/// # Panics
/// If `c` has no parameter [`FLIP_STEP_MARGIN`] (it is not the backflip controller).
pub fn without_recovery_step(mut c: Controller) -> Controller {
    let id = c.param_id(FLIP_STEP_MARGIN).expect("the backflip's T8 margin");
    c.set_param(id, 100.0);
    c
}

/// A symmetric description of the walker's leg poses: W-LEGS's E1 and E3 by swing and stance leg (E4
/// and E6 are their mirrors), with the inter-thigh target kept at hip_l − hip_r. The space the walking
/// poses were re-authored in (`examples/tune_walk.rs`) and the one the optimiser comparison searches.
pub mod walk_poses {
    use anima_control::Controller;
    use anima_control::optimise::{Dim, Space};

    pub const NAMES: [&str; 12] = [
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
    /// Interval of each number, rad.
    pub const LO: [f64; 12] = [-0.4, 0.0, -1.6, -0.4, -0.6, -0.6, -0.4, -0.2, -1.0, -0.4, -0.6, -0.4];
    pub const HI: [f64; 12] = [0.2, 1.2, 0.0, 0.6, 0.4, 0.0, 0.6, 1.0, 0.0, 0.4, 0.4, 0.6];
    /// The spec's §8.1.2 proposal, with which our humanoid falls within seconds: the thesis's
    /// "before optimisation" walker (`assets/controllers/walk-spec.ron`).
    pub const SPEC: [f64; 12] = [-0.05, 0.6, -1.1, 0.2, -0.1, -0.05, 0.0, 0.4, -0.05, 0.0, -0.2, 0.1];

    pub fn space() -> Space {
        Space { dims: NAMES.iter().zip(LO.iter().zip(HI)).map(|(n, (&a, b))| Dim::new(n, a, b)).collect() }
    }

    /// Reads the pose vector back from a walking controller (E1 and E3; the inverse of [`set`] for a
    /// symmetric walker).
    ///
    /// # Panics
    /// If the controller is not the walker (a W-LEGS pose entry is missing).
    pub fn get(c: &Controller) -> [f64; 12] {
        let get = |label: &str| c.param(c.param_id(label).unwrap_or_else(|| panic!("no parameter {label}")));
        [
            get("W-LEGS/E1/waist"),
            get("W-LEGS/E1/hip_l"),
            get("W-LEGS/E1/knee_l"),
            get("W-LEGS/E1/ankle_l"),
            get("W-LEGS/E1/hip_r"),
            get("W-LEGS/E1/knee_r"),
            get("W-LEGS/E1/ankle_r"),
            get("W-LEGS/E3/hip_l"),
            get("W-LEGS/E3/knee_l"),
            get("W-LEGS/E3/ankle_l"),
            get("W-LEGS/E3/hip_r"),
            get("W-LEGS/E3/ankle_r"),
        ]
    }

    /// Where each W-LEGS pose entry of the walking states takes its value from.
    #[derive(Debug, Clone, Copy, PartialEq)]
    pub enum Source {
        /// Pose number i.
        Number(usize),
        /// A fixed angle, rad (E3/E6's stance knee).
        Fixed(f64),
        /// sign × (number a − number b): the inter-thigh target, hip_l − hip_r.
        Difference(f64, usize, usize),
    }

    /// The pose entries the twelve numbers set, as (`W-LEGS/<state>/<joint>`, source): E1 and E3 with
    /// the left leg swinging, and their mirrors E4 and E6.
    pub fn layout() -> Vec<(String, Source)> {
        use Source::{Fixed, Number};
        // Per pair of mirrored states: the swing leg's hip, knee and ankle numbers, and the stance
        // leg's hip, knee and ankle sources.
        let groups = [
            (["E1", "E4"], [1, 2, 3], [Number(4), Number(5), Number(6)]),
            (["E3", "E6"], [7, 8, 9], [Number(10), Fixed(-0.05), Number(11)]),
        ];
        let mut out = Vec::new();
        for (states, swing, stance) in groups {
            let Number(stance_hip) = stance[0] else { unreachable!("the stance hip is a pose number") };
            for (state, sw, st) in [(states[0], "l", "r"), (states[1], "r", "l")] {
                let s = if sw == "l" { 1.0 } else { -1.0 };
                out.extend([
                    (format!("W-LEGS/{state}/waist"), Number(0)),
                    (format!("W-LEGS/{state}/hip_{sw}"), Number(swing[0])),
                    (format!("W-LEGS/{state}/knee_{sw}"), Number(swing[1])),
                    (format!("W-LEGS/{state}/ankle_{sw}"), Number(swing[2])),
                    (format!("W-LEGS/{state}/hip_{st}"), stance[0]),
                    (format!("W-LEGS/{state}/knee_{st}"), stance[1]),
                    (format!("W-LEGS/{state}/ankle_{st}"), stance[2]),
                    (format!("W-LEGS/{state}/inter_thigh"), Source::Difference(s, swing[0], stance_hip)),
                ]);
            }
        }
        out
    }

    /// Writes pose vector `x` into a walking controller (E1/E3 and mirrored E4/E6; see [`layout`]).
    ///
    /// # Panics
    /// If the controller is not the walker (a W-LEGS pose entry is missing).
    pub fn set(c: &mut Controller, x: &[f64]) {
        for (label, source) in layout() {
            let v = match source {
                Source::Number(i) => x[i],
                Source::Fixed(v) => v,
                Source::Difference(s, a, b) => s * (x[a] - x[b]),
            };
            let id = c.param_id(&label).unwrap_or_else(|| panic!("no parameter {label}"));
            c.set_param(id, v);
        }
    }
}

/// A SIMBICON-style walker (Yin et al. 2007) in the thesis's representation: the walking machines
/// of `walk.ron` with the swing hip's target in the world frame and balance feedback
/// θ = θ₀ + c_d·d + c_v·v (d: the centre of mass ahead of the stance foot, m; v: its forward speed,
/// m/s), and the trunk (waist) held at a world angle. Everything else — states, sensory
/// transitions, the arms — is the thesis's walker, so the two can be compared on equal terms.
pub mod simbicon {
    use anima_control::optimise::{Dim, Space};
    use anima_control::{Controller, FeedbackDesc, FeedbackTerm, Param, SensorDesc, TargetDesc};

    use super::walk_poses;
    use anima_character::{CharacterError, procedures};

    /// The two feedback gains, after the twelve [`walk_poses`] numbers (whose swing-hip entries
    /// become the world-frame θ₀, and whose waist entry the trunk's world angle).
    pub const GAINS: [&str; 2] = ["c_d", "c_v"];
    /// Intervals of the gains: SIMBICON's published walks use c_d ∈ [0, 2.2] and c_v ∈ [0, 0.55];
    /// slightly negative values are allowed so that the search can find they do not help.
    pub const GAINS_LO: [f64; 2] = [-0.5, -0.5];
    pub const GAINS_HI: [f64; 2] = [2.5, 1.0];

    /// The swing phases of W-LEGS: state, swing side, stance side (the sensor's argument).
    const SWING: [(&str, &str, &str); 4] =
        [("E1", "l", "right"), ("E3", "l", "right"), ("E4", "r", "left"), ("E6", "r", "left")];

    /// Turns a walker (`walk.ron` or one of its variants) into its SIMBICON form, gains 0.
    ///
    /// # Panics
    /// If the controller has no W-LEGS machine.
    pub fn controller(walker: &Controller) -> Result<Controller, CharacterError> {
        let mut desc = walker.to_desc();
        let legs =
            desc.machines.iter_mut().find(|m| m.name == "W-LEGS").expect("a walker has a W-LEGS machine");
        for state in &mut legs.states {
            let Some(&(_, sw, stance)) = SWING.iter().find(|(n, _, _)| *n == state.name) else { continue };
            let terms = vec![
                FeedbackTerm {
                    gain: Param::fixed(0.0),
                    sensor: SensorDesc {
                        kind: "com_offset".into(),
                        args: vec![stance.into()],
                        params: vec![],
                    },
                },
                FeedbackTerm {
                    gain: Param::fixed(0.0),
                    sensor: SensorDesc { kind: "com_speed".into(), args: vec![], params: vec![] },
                },
            ];
            for entry in &mut state.pose {
                let Some(name) = entry.0.name(walker.actuators()) else { continue };
                let TargetDesc::Angle(p) = entry.1 else { continue };
                entry.1 = if name == format!("hip_{sw}") {
                    TargetDesc::Feedback(FeedbackDesc { base: p, world: true, terms: terms.clone() })
                } else if name == "inter_thigh" {
                    TargetDesc::Feedback(FeedbackDesc { base: p, world: false, terms: terms.clone() })
                } else if name == "waist" {
                    TargetDesc::WorldAngle(p)
                } else {
                    continue;
                };
            }
        }
        Ok(Controller::from_desc(desc, &procedures())?)
    }

    /// The search space: the twelve pose numbers, then c_d and c_v.
    pub fn space() -> Space {
        let mut s = walk_poses::space();
        s.dims.extend(GAINS.iter().zip(GAINS_LO.iter().zip(GAINS_HI)).map(|(n, (&a, b))| Dim::new(n, a, b)));
        s
    }

    /// Writes `x` (twelve pose numbers, c_d, c_v) into a controller made by [`controller`]. The
    /// inter-thigh target (hip_l − hip_r) gets the swing hip's feedback with the swing side's sign.
    ///
    /// # Panics
    /// If the controller was not made by [`controller`].
    pub fn set(c: &mut Controller, x: &[f64]) {
        walk_poses::set(c, &x[..12]);
        let (cd, cv) = (x[12], x[13]);
        let mut set = |label: String, v: f64| {
            let id = c.param_id(&label).unwrap_or_else(|| panic!("no parameter {label}"));
            c.set_param(id, v);
        };
        for (state, sw, _) in SWING {
            let s = if sw == "l" { 1.0 } else { -1.0 };
            set(format!("W-LEGS/{state}/hip_{sw}/k0"), cd);
            set(format!("W-LEGS/{state}/hip_{sw}/k1"), cv);
            set(format!("W-LEGS/{state}/inter_thigh/k0"), s * cd);
            set(format!("W-LEGS/{state}/inter_thigh/k1"), s * cv);
        }
    }
}

/// A walker that leans into slopes: each leg-pose entry of W-LEGS that [`walk_poses::set`] writes
/// becomes θ₀ + k·s, s the inclination of the ground under the centre of mass (rad, positive
/// uphill; the `ground_slope` sensor). On level ground, the flat and the treads of stairs alike,
/// s = 0 and the walker is the one it was made from to the bit; only its gait on slopes changes. The
/// twelve gains follow the twelve pose numbers (mirrored into E4 and E6 as the poses are).
pub mod slope_form {
    use anima_control::optimise::{Dim, Space};
    use anima_control::{Controller, FeedbackDesc, FeedbackTerm, Param, SensorDesc, TargetDesc};

    use super::walk_poses;
    use anima_character::{CharacterError, procedures};

    /// The interval of every gain, rad of target per rad of slope: ±3 moves a target by up to
    /// 0.52 rad on a 10° slope.
    pub const GAIN_LIMIT: f64 = 3.0;

    /// The joints whose targets get the slope term, in every walking state.
    const JOINTS: [&str; 8] =
        ["waist", "hip_l", "knee_l", "ankle_l", "hip_r", "knee_r", "ankle_r", "inter_thigh"];

    /// Turns a thesis-form walker (`walk.ron` or one searched from it) into its slope form, gains 0.
    ///
    /// # Panics
    /// If the controller has no W-LEGS machine.
    pub fn controller(walker: &Controller) -> Result<Controller, CharacterError> {
        let mut desc = walker.to_desc();
        let legs =
            desc.machines.iter_mut().find(|m| m.name == "W-LEGS").expect("a walker has a W-LEGS machine");
        for state in &mut legs.states {
            if !["E1", "E3", "E4", "E6"].contains(&state.name.as_str()) {
                continue;
            }
            for entry in &mut state.pose {
                let Some(name) = entry.0.name(walker.actuators()) else { continue };
                let TargetDesc::Angle(p) = entry.1 else { continue };
                if JOINTS.contains(&name) {
                    entry.1 = TargetDesc::Feedback(FeedbackDesc {
                        base: p,
                        world: false,
                        terms: vec![FeedbackTerm {
                            gain: Param::fixed(0.0),
                            sensor: SensorDesc { kind: "ground_slope".into(), args: vec![], params: vec![] },
                        }],
                    });
                }
            }
        }
        Ok(Controller::from_desc(desc, &procedures())?)
    }

    /// The search space of the twelve gains, named after the pose numbers.
    pub fn space() -> Space {
        Space {
            dims: walk_poses::NAMES
                .iter()
                .map(|n| Dim::new(&format!("k_{n}"), -GAIN_LIMIT, GAIN_LIMIT))
                .collect(),
        }
    }

    /// Writes the twelve gains `k` into a controller made by [`controller`], entry by entry as
    /// [`walk_poses::set`] writes the poses (the E3/E6 stance knee, fixed there, keeps gain 0; the
    /// inter-thigh target gets the difference of the hips' gains with the swing side's sign).
    ///
    /// # Panics
    /// If the controller was not made by [`controller`].
    pub fn set(c: &mut Controller, k: &[f64]) {
        for (label, source) in walk_poses::layout() {
            let v = match source {
                walk_poses::Source::Number(i) => k[i],
                walk_poses::Source::Fixed(_) => 0.0,
                walk_poses::Source::Difference(s, a, b) => s * (k[a] - k[b]),
            };
            let label = format!("{label}/k0");
            let id = c.param_id(&label).unwrap_or_else(|| panic!("no parameter {label}"));
            c.set_param(id, v);
        }
    }
}
