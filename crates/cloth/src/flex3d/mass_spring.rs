//! The one-spring test of Nedel 1993 §4.4 (Table 4.1, Fig. 4.1): a unit mass on a spring of stiffness 1
//! and rest length 2, fixed at the origin, released from x = 4 at rest. Exact solution x(t) = 2 + 2 cos t.

use anima_ode::{Integrator, State, Stepper};

/// The step sizes of Table 4.1, in column order.
pub const TABLE_4_1_STEPS: [f64; 6] = [1.0, 0.5, 0.05, 0.005, 0.0005, 0.00005];

/// Table 4.1 as printed in the thesis (p. 98): rows t = 0..=10, columns [`TABLE_4_1_STEPS`].
pub const TABLE_4_1_THESIS: [[f64; 6]; 11] = [
    [4.0000, 4.0000, 4.0000, 4.0000, 4.0000, 4.0000],
    [4.0000, 3.5000, 3.1093, 3.0833, 3.0808, 3.0806],
    [2.0000, 1.1250, 1.1282, 1.1635, 1.1672, 1.1676],
    [-2.0000, -1.6562, -0.1332, 0.0051, 0.0185, 0.0198],
    [-6.0000, -2.1171, 0.5498, 0.6795, 0.6914, 0.6925],
    [-6.0000, 1.5371, 2.6337, 2.5743, 2.5680, 2.5673],
    [2.0000, 7.7387, 4.2274, 3.9493, 3.9232, 3.9206],
    [18.0000, 11.3314, 3.8048, 3.5345, 3.5104, 3.5080],
    [34.0000, 7.0303, 1.6607, 1.7032, 1.7084, 1.7089],
    [34.0000, -5.0348, -0.2736, 0.1363, 0.1736, 0.1773],
    [2.0000, -16.4121, -0.1656, 0.2792, 0.3176, 0.3214],
];

/// The spring of Table 4.1 (in `anima_ode`, whose integrator tests step it too).
pub use anima_ode::SingleSpring;

/// Positions at t = 0, 1, …, `t_end` for step `h`, taking exactly round(1/h) steps per time unit (steps
/// are counted as integers; t is never accumulated).
pub fn trajectory(integrator: Integrator, h: f64, t_end: usize) -> Vec<f64> {
    let mut sys = SingleSpring::thesis();
    let mut stepper = Stepper::new(integrator, 1);
    let steps_per_unit = (1.0 / h).round() as usize;
    let mut now = State::new(vec![4.0], vec![0.0]);
    let mut next = State::zeros(1);
    let mut out = vec![now.x[0]];
    let mut k = 0usize;
    for _ in 0..t_end {
        for _ in 0..steps_per_unit {
            stepper
                .step(&mut sys, k as f64 * h, h, &now, &mut next)
                .expect("the spring gives its Jacobian, so every method steps it");
            std::mem::swap(&mut now, &mut next);
            k += 1;
        }
        out.push(now.x[0]);
    }
    out
}

/// Truncation toward zero to four decimals, as the thesis printed its table (ordinary rounding differs
/// from the printed values in 21 of the 66 entries).
pub fn truncate_4(x: f64) -> f64 {
    (x * 1e4).trunc() / 1e4
}

/// Table 4.1 recomputed: rows t = 0..=10, columns [`TABLE_4_1_STEPS`], truncated to four decimals.
pub fn table_4_1(integrator: Integrator) -> [[f64; 6]; 11] {
    let mut table = [[0.0; 6]; 11];
    for (c, &h) in TABLE_4_1_STEPS.iter().enumerate() {
        for (t, x) in trajectory(integrator, h, 10).into_iter().enumerate() {
            table[t][c] = truncate_4(x);
        }
    }
    table
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_4_1_matches_every_printed_digit() {
        let ours = table_4_1(Integrator::ForwardEuler);
        let mut mismatches = Vec::new();
        for t in 0..11 {
            for c in 0..6 {
                if ours[t][c] != TABLE_4_1_THESIS[t][c] {
                    mismatches.push(format!(
                        "t={t} h={}: ours {} thesis {}",
                        TABLE_4_1_STEPS[c], ours[t][c], TABLE_4_1_THESIS[t][c]
                    ));
                }
            }
        }
        assert!(mismatches.is_empty(), "{} of 66 differ:\n{}", mismatches.len(), mismatches.join("\n"));
    }

    #[test]
    fn symplectic_euler_does_not_reproduce_table_4_1() {
        let ours = table_4_1(Integrator::SymplecticEuler);
        let same = (0..11)
            .flat_map(|t| (0..6).map(move |c| (t, c)))
            .filter(|&(t, c)| ours[t][c] == TABLE_4_1_THESIS[t][c])
            .count();
        assert!(same < 20, "symplectic Euler matched {same} of 66 entries; the thesis used forward Euler");
    }
}
