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

/// A procedure's check of the fixed arguments a controller file gives it, run once when the
/// controller is read: `Err` says what is wrong, and the reader reports it at the call's `args` with
/// line and column. A procedure fires inside a step, where it has no way to report a bad argument, so
/// what it needs is checked here.
pub type ArgCheck = fn(&CallArgs<'_>) -> Result<(), String>;

/// What an [`ArgCheck`] sees: the call's arguments and which names are parameters of the controller.
pub struct CallArgs<'a> {
    pub(crate) args: &'a [String],
    pub(crate) is_param: &'a dyn Fn(&str) -> bool,
}

impl fmt::Debug for CallArgs<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CallArgs").field("args", &self.args).finish()
    }
}

impl CallArgs<'_> {
    pub fn args(&self) -> &[String] {
        self.args
    }

    /// Whether `path_or_label` names a parameter of the controller (see [`Controller::param_id`]).
    pub fn is_param(&self, path_or_label: &str) -> bool {
        (self.is_param)(path_or_label)
    }

    /// `Err` unless there are `n` arguments, described as `what` (e.g. "a parameter to set").
    pub fn expect_count(&self, n: usize, what: &str) -> Result<(), String> {
        if self.args.len() == n {
            Ok(())
        } else {
            Err(format!(
                "expected {n} argument{} ({what}), found {}",
                if n == 1 { "" } else { "s" },
                self.args.len()
            ))
        }
    }

    /// `Err` unless argument `k` names a parameter.
    pub fn expect_param(&self, k: usize) -> Result<(), String> {
        match self.args.get(k) {
            Some(a) if self.is_param(a) => Ok(()),
            Some(a) => Err(format!("argument {k}: expected a parameter's path or label, found `{a}`")),
            None => Err(format!("argument {k}: expected a parameter's path or label, found none")),
        }
    }

    /// `Err` unless argument `k` is a finite number.
    pub fn expect_number(&self, k: usize) -> Result<(), String> {
        match self.args.get(k).map(|a| (a, a.trim().parse::<f64>())) {
            Some((_, Ok(v))) if v.is_finite() => Ok(()),
            Some((a, _)) => Err(format!("argument {k}: expected a finite number, found `{a}`")),
            None => Err(format!("argument {k}: expected a finite number, found none")),
        }
    }
}

/// Named procedures for controllers whose environment is `E`.
pub struct Procedures<E> {
    names: Vec<String>,
    fns: Vec<Box<ProcedureFn<E>>>,
    checks: Vec<Option<ArgCheck>>,
}

impl<E> fmt::Debug for Procedures<E> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("Procedures").field("names", &self.names).finish()
    }
}

impl<E> Default for Procedures<E> {
    fn default() -> Self {
        Self { names: Vec::new(), fns: Vec::new(), checks: Vec::new() }
    }
}

impl<E> Procedures<E> {
    /// An empty registry.
    pub fn new() -> Self {
        Self::default()
    }

    /// Registers `f` under `name`, replacing an earlier one of that name. Any arguments are accepted;
    /// [`Procedures::register_checked`] says which are.
    pub fn register(
        &mut self,
        name: &str,
        f: impl Fn(&mut ProcCtx<'_, E>) + Send + Sync + 'static,
    ) -> &mut Self {
        self.insert(name, Box::new(f), None)
    }

    /// Registers `f` under `name` with the check of its arguments that a controller file's calls must
    /// pass when the file is read.
    pub fn register_checked(
        &mut self,
        name: &str,
        check: ArgCheck,
        f: impl Fn(&mut ProcCtx<'_, E>) + Send + Sync + 'static,
    ) -> &mut Self {
        self.insert(name, Box::new(f), Some(check))
    }

    fn insert(&mut self, name: &str, f: Box<ProcedureFn<E>>, check: Option<ArgCheck>) -> &mut Self {
        match self.index(name) {
            Some(i) => {
                self.fns[i] = f;
                self.checks[i] = check;
            }
            None => {
                self.names.push(name.to_string());
                self.fns.push(f);
                self.checks.push(check);
            }
        }
        self
    }

    /// The argument check of each procedure, in the order of [`Procedures::names`].
    pub(crate) fn checks(&self) -> &[Option<ArgCheck>] {
        &self.checks
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
        p.register_checked("copy_params", check_copy_params, |ctx| {
            for k in (0..ctx.args().len() / 2).map(|k| 2 * k) {
                let (from, to) = (ctx.arg_param(k), ctx.arg_param(k + 1));
                if let (Some(from), Some(to)) = (from, to) {
                    let v = ctx.param(from);
                    ctx.set_param(to, v);
                }
            }
        });
        p.register_checked(
            "negate_into",
            |a| a.expect_count(1, "the parameter to set").and(a.expect_param(0)),
            |ctx| {
                if let Some(to) = ctx.arg_param(0) {
                    let v = -ctx.value();
                    ctx.set_param(to, v);
                }
            },
        );
        p
    }
}

/// `copy_params`: pairs of parameters, at least one.
fn check_copy_params(a: &CallArgs<'_>) -> Result<(), String> {
    if a.args().is_empty() || !a.args().len().is_multiple_of(2) {
        return Err(format!(
            "expected pairs of parameters (from, to, from, to, …), found {} argument{}",
            a.args().len(),
            if a.args().len() == 1 { "" } else { "s" }
        ));
    }
    (0..a.args().len()).try_for_each(|k| a.expect_param(k))
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
