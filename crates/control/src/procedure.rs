//! Procedures (spec §6.8): designer code the controller fires by itself — on states (every active
//! iteration), on transitions (once, when they switch) and on machine sensors (on activation or while
//! active). A controller file names them; a [`Procedures`] registry maps the names to Rust functions.
//!
//! A procedure gets a [`ProcCtx`]: the caller's environment `E` (the same value that answers sensor
//! queries, so a procedure can read the body or release a weld), the controller's parameters, machine
//! switches and method triggers, and the sensor value that fired it.

use std::fmt;

use crate::controller::Controller;
use crate::param::ParamId;

/// A procedure's code.
pub type ProcedureFn<E> = dyn Fn(&mut ProcCtx<'_, E>) + Send + Sync;

/// Named procedures for controllers whose environment is `E`.
pub struct Procedures<E> {
    names: Vec<String>,
    fns: Vec<Box<ProcedureFn<E>>>,
}

impl<E> fmt::Debug for Procedures<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Procedures").field("names", &self.names).finish()
    }
}

impl<E> Default for Procedures<E> {
    fn default() -> Self {
        Self { names: Vec::new(), fns: Vec::new() }
    }
}

impl<E> Procedures<E> {
    /// An empty registry.
    pub fn new() -> Self {
        Self::default()
    }

    /// Registers `f` under `name`, replacing an earlier one of that name.
    pub fn register(
        &mut self,
        name: &str,
        f: impl Fn(&mut ProcCtx<'_, E>) + Send + Sync + 'static,
    ) -> &mut Self {
        match self.index(name) {
            Some(i) => self.fns[i] = Box::new(f),
            None => {
                self.names.push(name.to_string());
                self.fns.push(Box::new(f));
            }
        }
        self
    }

    pub fn index(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    pub fn names(&self) -> &[String] {
        &self.names
    }

    pub(crate) fn call(&self, index: usize, ctx: &mut ProcCtx<'_, E>) {
        (self.fns[index])(ctx);
    }
}

impl<E> Procedures<E> {
    /// The registry with the generic procedures every controller file may name:
    ///
    /// - `copy_params(from₁, to₁, from₂, to₂, …)`: sets each `to` parameter to the value of its
    ///   `from` (paths or labels, see [`Controller::param_id`]) — the thesis's symmetry procedure
    ///   (spec §7.5, §8.1.7, §8.3.1);
    /// - `negate_into(to)`: sets parameter `to` to minus the firing sensor's value — the on-line
    ///   balance example of Fig. 4.6 (θd = −α).
    pub fn with_builtins() -> Self {
        let mut p = Self::new();
        p.register("copy_params", |ctx| {
            for k in (0..ctx.args().len() / 2).map(|k| 2 * k) {
                let (from, to) = (ctx.arg_param(k), ctx.arg_param(k + 1));
                if let (Some(from), Some(to)) = (from, to) {
                    let v = ctx.param(from);
                    ctx.set_param(to, v);
                }
            }
        });
        p.register("negate_into", |ctx| {
            if let Some(to) = ctx.arg_param(0) {
                let v = -ctx.value();
                ctx.set_param(to, v);
            }
        });
        p
    }
}

/// Which attach point fired a procedure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Origin {
    State { machine: usize, state: usize },
    Transition { machine: usize, transition: usize },
    Sensor { sensor: usize },
}

/// What a procedure sees while it runs.
pub struct ProcCtx<'a, E> {
    pub(crate) controller: &'a mut Controller,
    /// The caller's environment: the body, the world, whatever the scene layer passes to
    /// [`Controller::step`].
    pub env: &'a mut E,
    pub(crate) value: f64,
    pub(crate) call: usize,
    pub(crate) origin: Origin,
}

impl<E> fmt::Debug for ProcCtx<'_, E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("ProcCtx").field("origin", &self.origin).field("value", &self.value).finish()
    }
}

impl<E> ProcCtx<'_, E> {
    /// The return value of the sensor that fired this procedure (a machine sensor, or a sensory
    /// transition's sensor); 0 for state procedures and other transitions.
    pub fn value(&self) -> f64 {
        self.value
    }

    pub fn origin(&self) -> Origin {
        self.origin
    }

    /// The fixed arguments the controller file gives this call.
    pub fn args(&self) -> &[String] {
        &self.controller.calls[self.call].args
    }

    /// The parameter named by argument `k` (a path or a label).
    pub fn arg_param(&self, k: usize) -> Option<ParamId> {
        self.args().get(k).and_then(|a| self.controller.param_id(a))
    }

    /// The iteration being computed (0 for the first step after a reset).
    pub fn iteration(&self) -> u64 {
        self.controller.iteration()
    }

    /// Read access to the whole controller.
    pub fn controller(&self) -> &Controller {
        self.controller
    }

    pub fn param_id(&self, path_or_label: &str) -> Option<ParamId> {
        self.controller.param_id(path_or_label)
    }

    pub fn param(&self, id: ParamId) -> f64 {
        self.controller.param(id)
    }

    /// On-line automatic modification (spec §6.12). Whole-iteration kinds are rounded; the interval
    /// is not enforced (a procedure may steer outside it on purpose).
    pub fn set_param(&mut self, id: ParamId, value: f64) {
        self.controller.set_param(id, value);
    }

    pub fn set_enabled(&mut self, machine: usize, enabled: bool) {
        self.controller.set_enabled(machine, enabled);
    }

    /// Invokes a method transition (see [`Controller::trigger`]).
    pub fn trigger(&mut self, machine: usize, transition: usize) -> bool {
        self.controller.trigger(machine, transition)
    }
}
