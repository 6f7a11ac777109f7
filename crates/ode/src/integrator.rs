use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// The integration methods a scene can name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default, Serialize, Deserialize)]
pub enum Integrator {
    /// Forward Euler as FLEX3D ran it (Nedel 1993 §4.4): x_{k+1} = x_k + h·v_k, v_{k+1} = v_k + h·a_k.
    /// The position uses the *old* velocity; this is what reproduces Table 4.1.
    #[default]
    ForwardEuler,
    /// Semi-implicit (symplectic) Euler: v_{k+1} = v_k + h·a_k, x_{k+1} = x_k + h·v_{k+1}.
    SymplecticEuler,
    /// Explicit midpoint, a second-order Runge–Kutta method.
    Midpoint,
    /// Classical fourth-order Runge–Kutta (Nedel 1993 §4.2.2) on y = (x, v).
    Rk4,
    /// Dormand–Prince 5(4): fifth-order steps with a fourth-order embedded error estimate, for step
    /// control by tolerance.
    DormandPrince,
    /// Adams–Bashforth 4 (Nedel 1993 §4.2.3): x_{n+1} = x_n + h/24 (55 f_n − 59 f_{n−1} + 37 f_{n−2} − 9 f_{n−3}),
    /// started by three RK4 steps; restarted whenever the step changes.
    AdamsBashforth4,
    /// Adams–Bashforth–Moulton 4 predictor–corrector (Nedel 1993 §4.2.4), PECE: predict with AB4, evaluate,
    /// correct with x_{n+1} = x_n + h/24 (9 f_{n+1} + 19 f_n − 5 f_{n−1} + f_{n−2}).
    AdamsBashforthMoulton4,
    /// Forward Euler with the thesis's step rule h = √(2·max_err/|f′|) (Nedel 1993 §4.2.1), f′ estimated by
    /// differencing f over the step.
    AdaptiveEuler,
    /// Backward Euler, linearised once per step (Baraff & Witkin 1998):
    /// (M − h D − h² K) Δv = h (f + h K v), x_{n+1} = x_n + h (v_n + Δv).
    ImplicitEuler,
    /// The second-order backward differentiation formula, linearised once per step like implicit Euler:
    /// y_{n+1} − 4/3 y_n + 1/3 y_{n−1} = 2/3 h f(y_{n+1}). A-stable like backward Euler but with far less
    /// numerical damping; started (and restarted after a discontinuity or a change of step) by one
    /// implicit Euler step.
    Bdf2,
    /// Generalised-α (Chung & Hulbert 1993): second order, with the damping of the modes a step cannot
    /// resolve set by its spectral radius ρ∞ (0 damps them in one step, 1 is the undamped implicit midpoint
    /// rule; default [`crate::DEFAULT_RHO_INF`], `Stepper::set_spectral_radius`), and barely any damping of
    /// the ones it resolves. Solved by Newton's method with a line search, by default with conjugate
    /// gradients and the rigid-aggregation preconditioner ([`crate::LinearSolver::RigidAggregation`]); the
    /// one method that
    /// can constrain contacts inside its solve (`Stepper::step_with_contacts`). The accurate choice for
    /// large steps.
    GeneralizedAlpha,
}

impl Integrator {
    pub const ALL: [Integrator; 11] = [
        Integrator::ForwardEuler,
        Integrator::SymplecticEuler,
        Integrator::Midpoint,
        Integrator::Rk4,
        Integrator::DormandPrince,
        Integrator::AdamsBashforth4,
        Integrator::AdamsBashforthMoulton4,
        Integrator::AdaptiveEuler,
        Integrator::ImplicitEuler,
        Integrator::Bdf2,
        Integrator::GeneralizedAlpha,
    ];

    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::ForwardEuler => "forward-euler",
            Integrator::SymplecticEuler => "symplectic-euler",
            Integrator::Midpoint => "midpoint",
            Integrator::Rk4 => "rk4",
            Integrator::DormandPrince => "dopri5",
            Integrator::AdamsBashforth4 => "ab4",
            Integrator::AdamsBashforthMoulton4 => "abm4",
            Integrator::AdaptiveEuler => "adaptive-euler",
            Integrator::ImplicitEuler => "implicit-euler",
            Integrator::Bdf2 => "bdf2",
            Integrator::GeneralizedAlpha => "generalized-alpha",
        }
    }

    /// Acceleration evaluations per (accepted, started) step.
    pub fn evaluations_per_step(self) -> usize {
        match self {
            Integrator::ForwardEuler | Integrator::SymplecticEuler | Integrator::AdamsBashforth4 => 1,
            Integrator::Midpoint | Integrator::AdamsBashforthMoulton4 | Integrator::AdaptiveEuler => 2,
            Integrator::Rk4 => 4,
            Integrator::DormandPrince => 7,
            Integrator::ImplicitEuler | Integrator::Bdf2 | Integrator::GeneralizedAlpha => 1,
        }
    }

    /// Order of the global error for smooth problems.
    pub fn order(self) -> u32 {
        match self {
            Integrator::ForwardEuler
            | Integrator::SymplecticEuler
            | Integrator::AdaptiveEuler
            | Integrator::ImplicitEuler => 1,
            Integrator::Midpoint | Integrator::Bdf2 | Integrator::GeneralizedAlpha => 2,
            Integrator::Rk4 | Integrator::AdamsBashforth4 | Integrator::AdamsBashforthMoulton4 => 4,
            Integrator::DormandPrince => 5,
        }
    }

    /// Whether each step yields an error estimate a controller can use.
    pub fn is_adaptive(self) -> bool {
        matches!(self, Integrator::DormandPrince | Integrator::AdaptiveEuler)
    }

    /// Whether the method needs the system's Jacobians ([`crate::OdeSystem::linearized`]).
    pub fn needs_jacobians(self) -> bool {
        self.is_implicit()
    }

    /// Whether the method is implicit (A-stable: no step-size limit from stiffness).
    pub fn is_implicit(self) -> bool {
        matches!(self, Integrator::ImplicitEuler | Integrator::Bdf2 | Integrator::GeneralizedAlpha)
    }

    /// Whether the method keeps a history of earlier steps that a discontinuity (a collision response, a
    /// constraint that starts moving) invalidates.
    pub fn is_multistep(self) -> bool {
        matches!(self, Integrator::AdamsBashforth4 | Integrator::AdamsBashforthMoulton4)
    }
}

impl fmt::Display for Integrator {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An integrator name that is not one of [`Integrator::ALL`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseIntegratorError(pub String);

impl fmt::Display for ParseIntegratorError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<_> = Integrator::ALL.iter().map(|i| i.name()).collect();
        write!(f, "unknown integrator `{}`; expected one of {}", self.0, names.join(", "))
    }
}

impl std::error::Error for ParseIntegratorError {}

impl FromStr for Integrator {
    type Err = ParseIntegratorError;

    /// Accepts the names of [`Integrator::name`] and a few common aliases (`euler`, `rk2`, …).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(match s.to_ascii_lowercase().replace('_', "-").as_str() {
            "forward-euler" | "euler" | "explicit-euler" => Integrator::ForwardEuler,
            "symplectic-euler" | "symplectic" | "semi-implicit-euler" => Integrator::SymplecticEuler,
            "midpoint" | "rk2" => Integrator::Midpoint,
            "rk4" | "runge-kutta" | "runge-kutta-4" => Integrator::Rk4,
            "dopri5" | "dormand-prince" | "rk45" => Integrator::DormandPrince,
            "ab4" | "adams-bashforth" | "adams-bashforth-4" => Integrator::AdamsBashforth4,
            "abm4" | "predictor-corrector" | "adams-bashforth-moulton" => Integrator::AdamsBashforthMoulton4,
            "adaptive-euler" => Integrator::AdaptiveEuler,
            "implicit-euler" | "backward-euler" | "implicit" => Integrator::ImplicitEuler,
            "bdf2" | "bdf-2" => Integrator::Bdf2,
            "generalized-alpha" | "generalised-alpha" | "gen-alpha" | "alpha" => Integrator::GeneralizedAlpha,
            _ => return Err(ParseIntegratorError(s.to_owned())),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip() {
        for i in Integrator::ALL {
            assert_eq!(i.name().parse::<Integrator>().unwrap(), i);
        }
        assert!("rk5".parse::<Integrator>().unwrap_err().to_string().contains("rk4"));
    }
}
