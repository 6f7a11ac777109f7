use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::{Coord, OdeSystem};

/// Positions and velocities of a second-order system.
#[derive(Debug, Clone, PartialEq)]
pub struct State<C> {
    pub x: Vec<C>,
    pub v: Vec<C>,
}

impl<C: Coord> State<C> {
    pub fn new(x: Vec<C>, v: Vec<C>) -> Self {
        assert_eq!(x.len(), v.len(), "as many velocities as positions");
        Self { x, v }
    }

    /// `n` coordinates, all zero.
    pub fn zeros(n: usize) -> Self {
        Self { x: vec![C::default(); n], v: vec![C::default(); n] }
    }
}

/// The integration methods a scene can name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum Integrator {
    /// Forward Euler as FLEX3D ran it (Nedel 1993 §4.4): x_{k+1} = x_k + h·v_k, v_{k+1} = v_k + h·a_k.
    /// The position uses the *old* velocity; this is what reproduces Table 4.1.
    #[default]
    ForwardEuler,
    /// Semi-implicit (symplectic) Euler: v_{k+1} = v_k + h·a_k, x_{k+1} = x_k + h·v_{k+1}.
    SymplecticEuler,
    /// Classical fourth-order Runge–Kutta (Nedel 1993 §4.2.2) on y = (x, v).
    Rk4,
}

impl Integrator {
    pub const ALL: [Integrator; 3] = [Integrator::ForwardEuler, Integrator::SymplecticEuler, Integrator::Rk4];

    /// The name used on the command line and in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::ForwardEuler => "forward-euler",
            Integrator::SymplecticEuler => "symplectic-euler",
            Integrator::Rk4 => "rk4",
        }
    }

    /// Acceleration evaluations per step.
    pub fn evaluations_per_step(self) -> usize {
        match self {
            Integrator::ForwardEuler | Integrator::SymplecticEuler => 1,
            Integrator::Rk4 => 4,
        }
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

    /// Accepts the kebab-case names and the short forms `euler` and `symplectic`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.to_ascii_lowercase().as_str() {
            "forward-euler" | "euler" | "explicit-euler" => Ok(Integrator::ForwardEuler),
            "symplectic-euler" | "symplectic" | "semi-implicit-euler" => Ok(Integrator::SymplecticEuler),
            "rk4" | "runge-kutta" | "runge-kutta-4" => Ok(Integrator::Rk4),
            _ => Err(ParseIntegratorError(s.to_owned())),
        }
    }
}

/// An integrator with the scratch buffers it needs, owned by the caller so that the step loop never
/// allocates.
#[derive(Debug, Clone)]
pub struct Stepper<C: Coord> {
    integrator: Integrator,
    a: Vec<C>,
    /// RK4 stage states and the accumulated increments.
    xs: Vec<C>,
    vs: Vec<C>,
    dx: Vec<C>,
    dv: Vec<C>,
}

impl<C: Coord> Stepper<C> {
    pub fn new(integrator: Integrator, n_coords: usize) -> Self {
        let stage = if integrator == Integrator::Rk4 { n_coords } else { 0 };
        Self {
            integrator,
            a: vec![C::default(); n_coords],
            xs: vec![C::default(); stage],
            vs: vec![C::default(); stage],
            dx: vec![C::default(); stage],
            dv: vec![C::default(); stage],
        }
    }

    pub fn integrator(&self) -> Integrator {
        self.integrator
    }

    /// One step of size `h` from `now` (at time `t`) into `next`.
    pub fn step<S: OdeSystem<Coord = C>>(
        &mut self,
        sys: &mut S,
        t: f64,
        h: f64,
        now: &State<C>,
        next: &mut State<C>,
    ) {
        let (x, v) = (&now.x[..], &now.v[..]);
        let (x_new, v_new) = (&mut next.x[..], &mut next.v[..]);
        let n = sys.n_coords();
        assert!(x.len() == n && v.len() == n && x_new.len() == n && v_new.len() == n && self.a.len() == n);
        match self.integrator {
            Integrator::ForwardEuler => {
                sys.acceleration(t, x, v, &mut self.a);
                for i in 0..n {
                    x_new[i] = x[i] + v[i] * h;
                    v_new[i] = v[i] + self.a[i] * h;
                }
            }
            Integrator::SymplecticEuler => {
                sys.acceleration(t, x, v, &mut self.a);
                for i in 0..n {
                    let vi = v[i] + self.a[i] * h;
                    v_new[i] = vi;
                    x_new[i] = x[i] + vi * h;
                }
            }
            Integrator::Rk4 => self.rk4(sys, t, h, x, v, x_new, v_new),
        }
    }

    /// Classical RK4 on y = (x, v): k_x = v_stage, k_v = a(stage). Increments are accumulated in
    /// (dx, dv) with weights 1, 2, 2, 1 and applied once at the end.
    #[expect(clippy::too_many_arguments, reason = "double-buffered state mirrors `step`")]
    fn rk4<S: OdeSystem<Coord = C>>(
        &mut self,
        sys: &mut S,
        t: f64,
        h: f64,
        x: &[C],
        v: &[C],
        x_new: &mut [C],
        v_new: &mut [C],
    ) {
        let n = x.len();
        let half = 0.5 * h;
        // Stage 1 at (x, v).
        sys.acceleration(t, x, v, &mut self.a);
        for i in 0..n {
            self.dx[i] = v[i];
            self.dv[i] = self.a[i];
            self.xs[i] = x[i] + v[i] * half;
            self.vs[i] = v[i] + self.a[i] * half;
        }
        // Stages 2 and 3 at the midpoint; stage 3's slope then carries the state a full step.
        for step_to in [half, h] {
            sys.acceleration(t + half, &self.xs, &self.vs, &mut self.a);
            for i in 0..n {
                let (kx, kv) = (self.vs[i], self.a[i]);
                self.dx[i] += kx * 2.0;
                self.dv[i] += kv * 2.0;
                self.xs[i] = x[i] + kx * step_to;
                self.vs[i] = v[i] + kv * step_to;
            }
        }
        sys.acceleration(t + h, &self.xs, &self.vs, &mut self.a);
        let w = h / 6.0;
        for i in 0..n {
            x_new[i] = x[i] + (self.dx[i] + self.vs[i]) * w;
            v_new[i] = v[i] + (self.dv[i] + self.a[i]) * w;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// x'' = −(x − 2): the FLEX3D Table 4.1 spring (k = 1, m = 1, rest length 2).
    struct Spring;
    impl OdeSystem for Spring {
        type Coord = f64;
        fn n_coords(&self) -> usize {
            1
        }
        fn acceleration(&mut self, _t: f64, x: &[f64], _v: &[f64], a: &mut [f64]) {
            a[0] = -(x[0] - 2.0);
        }
    }

    fn error_at_one(integrator: Integrator, h: f64) -> f64 {
        let mut st = Stepper::new(integrator, 1);
        let mut now = State::new(vec![4.0], vec![0.0]);
        let mut next = State::zeros(1);
        let steps = (1.0 / h).round() as usize;
        for k in 0..steps {
            st.step(&mut Spring, k as f64 * h, h, &now, &mut next);
            std::mem::swap(&mut now, &mut next);
        }
        (now.x[0] - (2.0 + 2.0 * 1.0f64.cos())).abs()
    }

    #[test]
    fn forward_euler_uses_the_old_velocity() {
        let now = State::new(vec![4.0], vec![0.0]);
        let mut next = State::zeros(1);
        Stepper::new(Integrator::ForwardEuler, 1).step(&mut Spring, 0.0, 1.0, &now, &mut next);
        assert_eq!((next.x[0], next.v[0]), (4.0, -2.0));
        Stepper::new(Integrator::SymplecticEuler, 1).step(&mut Spring, 0.0, 1.0, &now, &mut next);
        assert_eq!((next.x[0], next.v[0]), (2.0, -2.0));
    }

    #[test]
    fn convergence_orders() {
        for (integrator, order) in
            [(Integrator::ForwardEuler, 1.0), (Integrator::SymplecticEuler, 1.0), (Integrator::Rk4, 4.0)]
        {
            let (e1, e2) = (error_at_one(integrator, 0.01), error_at_one(integrator, 0.005));
            let observed = (e1 / e2).log2();
            assert!(
                (observed - order).abs() < 0.15,
                "{integrator}: observed order {observed}, expected {order}"
            );
        }
    }

    #[test]
    fn names_round_trip() {
        for i in Integrator::ALL {
            assert_eq!(i.name().parse::<Integrator>().unwrap(), i);
        }
        assert!("rk5".parse::<Integrator>().unwrap_err().to_string().contains("rk4"));
    }
}
