//! How a cloth's contacts with static objects are answered: after the step, as the theses do, or inside
//! the implicit solve. One switch for every model (FLEX3D surfaces, sheets and networks, Oliveira's
//! cloth), named in their scene files.

use serde::{Deserialize, Serialize};

/// Where contact with static objects is answered.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum ContactMode {
    /// After the integrator's step, by each model's own response (a split): FLEX3D's elastic impact,
    /// Oliveira's repulsion and friction (Eqs. 4.16–4.18), the sheets' projection with Coulomb friction.
    /// The theses' method, and the default.
    #[default]
    AfterStep,
    /// Inside the implicit step (generalised-α only): a particle in contact has its normal velocity
    /// constrained in the Newton solve, Coulomb friction acts at the velocity level (sticking while
    /// the tangential force stays within μ times the normal force, sliding against μ times it
    /// otherwise), and a contact is released when its force would pull
    /// (`anima_ode::contact`). Contacts between surfaces (FLEX3D) stay after the step.
    InSolve,
}

impl ContactMode {
    /// Whether this is the default, after the step: scene structs skip the field when writing it, so
    /// that every scene file written before the switch existed is written the same.
    pub fn is_after_step(&self) -> bool {
        *self == ContactMode::AfterStep
    }

    /// The name on the command line: `after-step` or `in-solve`.
    pub fn name(self) -> &'static str {
        match self {
            ContactMode::AfterStep => "after-step",
            ContactMode::InSolve => "in-solve",
        }
    }
}

impl std::fmt::Display for ContactMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ContactMode {
    type Err = String;

    /// `after-step` (also `split`, `thesis`) or `in-solve` (also `implicit`).
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().replace('_', "-").as_str() {
            "after-step" | "split" | "thesis" => Ok(ContactMode::AfterStep),
            "in-solve" | "implicit" => Ok(ContactMode::InSolve),
            _ => Err(format!("unknown contact mode `{s}`; expected `after-step` or `in-solve`")),
        }
    }
}
