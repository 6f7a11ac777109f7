//! The largest scene, figure and optimisation anima agrees to build, stated in one place.
//!
//! A file declares sizes and counts (a grid's rows and columns, a number of fixed points, a duration
//! and a step, a skeleton's bodies, a controller's states, an optimiser's population and budget); a
//! reader checks each against these limits, with checked arithmetic, before it allocates anything for
//! it, so a hostile or mistyped number is an error that names where it is written, never an abort for
//! want of memory or a run that does not end. The Python package checks the same numbers. They are
//! generous for what the models mean: the largest thesis scene has 800 particles and 145 000 steps,
//! the thesis figure 15 bodies, its largest controller a few dozen states, its searches a few thousand
//! evaluations. (The OBJ reader's bound on a polygon's corners is `anima_geom::MAX_FACE_CORNERS`:
//! `anima-geom` depends on no anima crate.)

/// Particles in one scene (all surfaces, or one sheet or cloth): 4 million, about 1 GB of state,
/// springs and solver scratch.
pub const MAX_PARTICLES: usize = 4_000_000;

/// Integration (or control) steps in one run: 10⁹, days of wall time for the smallest scene.
pub const MAX_STEPS: f64 = 1e9;

/// Frames written by one run.
pub const MAX_FRAMES: f64 = 1e6;

/// Bytes of one scene file or part: 256 MiB (the Stanford Bunny's OBJ is 3 MB).
pub const MAX_FILE_BYTES: u64 = 256 << 20;

/// Lengths and coordinates of a scene's objects (a mesh's placed size and position, a sphere's
/// radius, a floor's point): 10⁶ m. Beyond it a mesh's volume and a cloth's contact tolerances leave
/// f64's useful range (a Bunny scaled to 10²⁰⁰ m has no finite volume), and no cloth scene means it.
pub const MAX_LENGTH_M: f64 = 1e6;

/// Bodies of one skeleton, and joints of one (a joint joins two bodies): 1 000. Rapier holds about
/// 80 kB per multibody link, so this caps a figure near 100 MB; a crowd belongs in several files.
pub const MAX_BODIES: usize = 1_000;

/// States of one controller's graph (and transitions out of one state), and its actuators and its
/// sensors: 10 000 each.
pub const MAX_STATES: usize = 10_000;

/// Candidates in one generation of an optimiser (CMA-ES's λ, a random search's or annealing's batch):
/// 10 000.
pub const MAX_POPULATION: usize = 10_000;

/// Evaluations of one optimisation (its budget, a greedy stage's evaluations): 10⁶. The run's log
/// keeps every one, about 250 bytes each for the thesis's parameter counts.
pub const MAX_EVALUATIONS: usize = 1_000_000;

/// Why a run of `duration_s` at steps of `dt_s` writing `frame_rate_hz` frames per second cannot be
/// run, or `None` when it can. Times are checked positive and finite elsewhere.
pub fn run_length_problem(duration_s: f64, dt_s: f64, frame_rate_hz: Option<f64>) -> Option<String> {
    let steps = duration_s / dt_s;
    // NaN counts as too many: a run of NaN steps cannot be counted.
    if steps.is_nan() || steps >= MAX_STEPS {
        return Some(format!(
            "a run of at most {MAX_STEPS:e} steps (duration {duration_s} s at steps of {dt_s} s makes {steps:.3e})"
        ));
    }
    if dt_s > duration_s * (1.0 + 1e-9) {
        return Some(format!(
            "a step no longer than the run (a step of {dt_s} s for a run of {duration_s} s)"
        ));
    }
    if let Some(fps) = frame_rate_hz {
        if fps * dt_s > 1.0 + 1e-9 {
            return Some(format!(
                "at most one frame per step ({fps} frames per second with steps of {dt_s} s would write each state \
                 {:.3} times)",
                fps * dt_s
            ));
        }
        let frames = duration_s * fps;
        if frames.is_nan() || frames >= MAX_FRAMES {
            return Some(format!("at most {MAX_FRAMES:e} frames ({fps} per second for {duration_s} s)"));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_lengths() {
        assert_eq!(run_length_problem(25.0, 0.001, Some(1.0)), None);
        assert!(run_length_problem(1.0, 1e-300, None).unwrap().contains("at most 1e9 steps"));
        assert!(run_length_problem(1e308, 0.1, None).unwrap().contains("at most 1e9 steps"));
        assert!(run_length_problem(0.1, 0.5, None).unwrap().contains("no longer than the run"));
        assert!(run_length_problem(1.0, 0.01, Some(1000.0)).unwrap().contains("one frame per step"));
        assert_eq!(run_length_problem(1.0, 0.01, Some(100.0)), None, "a frame every step is fine");
        assert!(run_length_problem(1e8, 1.0, Some(1.0)).unwrap().contains("frames"));
    }
}
