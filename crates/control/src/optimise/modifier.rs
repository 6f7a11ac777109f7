//! The random modifier of Nunes 2006 §4.4.2, §5.4.1 (spec §7.3): which parameters change per
//! evaluation (all, a group, one) and in which interval the new value is drawn (the admissible
//! interval, a window centred on the current value, or a window that shrinks over the stage).

use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::{Space, uniform};

/// Where a local modifier draws a new value.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Interval {
    /// The whole admissible interval for the whole stage.
    Fixed,
    /// A window of `fraction` × the admissible width, centred on the current value and clipped to the
    /// admissible interval. The throw's 50 % window is `fraction: 0.5` (current ± 25 % of the width).
    PartiallyReduced { fraction: f64 },
    /// Like `PartiallyReduced`, but evaluation i = 1…N of the stage uses the width
    /// `fraction · width · (1 − (i − 1)/N)`, shrinking linearly towards the current value
    /// (spec §7.3 \[GAP\]: linear schedule).
    IterativelyReduced { fraction: f64 },
}

/// How a subset modifier picks the group to change.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GroupChoice {
    /// Uniformly at random (the default of spec §8.3.2).
    Random,
    /// Groups in turn: evaluation i changes group (i − 1) mod k.
    Alternate,
}

/// Which parameters change per evaluation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Modifier {
    /// Every parameter of the stage, drawn in its whole admissible interval (current values ignored).
    Global,
    /// One parameter of the stage, chosen uniformly.
    LocalSingle(Interval),
    /// One group of parameters (indices into the space), e.g. all angles of one state.
    LocalSubset { groups: Vec<Vec<usize>>, choice: GroupChoice, interval: Interval },
}

/// A new candidate from the incumbent `x`: evaluation `i` (1-based) of `n` in a stage over the
/// dimensions `dims` of `space`. Draws come from `rng` in a fixed order: the choice of parameter or
/// group first, then one uniform per changed parameter in index order.
pub fn propose(
    modifier: &Modifier,
    space: &Space,
    dims: &[usize],
    x: &[f64],
    i: usize,
    n: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<f64> {
    let mut y = x.to_vec();
    let mut draw = |d: usize, interval: Interval, rng: &mut ChaCha8Rng| {
        let dim = &space.dims[d];
        let (lo, hi) = window(dim.min, dim.max, x[d], interval, i, n);
        y[d] = dim.admit(uniform(rng, lo, hi));
    };
    match modifier {
        Modifier::Global => {
            for &d in dims {
                draw(d, Interval::Fixed, rng);
            }
        }
        Modifier::LocalSingle(interval) => {
            if !dims.is_empty() {
                let d = dims[rng.random_range(0..dims.len())];
                draw(d, *interval, rng);
            }
        }
        Modifier::LocalSubset { groups, choice, interval } => {
            if !groups.is_empty() {
                let g = match choice {
                    GroupChoice::Random => rng.random_range(0..groups.len()),
                    GroupChoice::Alternate => (i.max(1) - 1) % groups.len(),
                };
                for &d in &groups[g] {
                    draw(d, *interval, rng);
                }
            }
        }
    }
    y
}

/// The sampling interval of one parameter.
fn window(min: f64, max: f64, current: f64, interval: Interval, i: usize, n: usize) -> (f64, f64) {
    let width = match interval {
        Interval::Fixed => return (min, max),
        Interval::PartiallyReduced { fraction } => fraction * (max - min),
        Interval::IterativelyReduced { fraction } => {
            let shrink = 1.0 - (i.max(1) - 1) as f64 / n.max(1) as f64;
            fraction * (max - min) * shrink
        }
    };
    ((current - width / 2.0).max(min), (current + width / 2.0).min(max))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optimise::Dim;
    use rand::SeedableRng;

    #[test]
    fn windows_follow_the_thesis_example() {
        // Width 40, current 20, 50 % window: draw in [10, 30] (spec §8.3.2).
        assert_eq!(
            window(0.0, 40.0, 20.0, Interval::PartiallyReduced { fraction: 0.5 }, 1, 400),
            (10.0, 30.0)
        );
        // Clipped at the admissible interval.
        assert_eq!(
            window(0.0, 40.0, 35.0, Interval::PartiallyReduced { fraction: 0.5 }, 1, 400),
            (25.0, 40.0)
        );
        // Iteratively reduced: full window first, a tenth of it at the last of 10.
        assert_eq!(
            window(0.0, 40.0, 20.0, Interval::IterativelyReduced { fraction: 0.5 }, 1, 10),
            (10.0, 30.0)
        );
        assert_eq!(
            window(0.0, 40.0, 20.0, Interval::IterativelyReduced { fraction: 0.5 }, 10, 10),
            (19.0, 21.0)
        );
    }

    #[test]
    fn local_single_changes_exactly_one_admissible_parameter() {
        let mut space = Space::cube(4, -0.25, 0.75);
        space.dims[3] = Dim { integer: true, ..Dim::new("tau", 0.0, 40.0) };
        let x = vec![0.0, 0.1, 0.2, 20.0];
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for i in 1..=200 {
            let y =
                propose(&Modifier::LocalSingle(Interval::Fixed), &space, &[0, 1, 2, 3], &x, i, 200, &mut rng);
            let changed = (0..4).filter(|&d| y[d] != x[d]).count();
            assert!(changed <= 1, "{y:?}");
            assert!(y.iter().zip(&space.dims).all(|(v, d)| (d.min..=d.max).contains(v)));
            assert_eq!(y[3].fract(), 0.0, "whole iterations");
        }
    }
}
