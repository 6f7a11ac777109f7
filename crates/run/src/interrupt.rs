//! A request, from outside a long computation, that it stop: Python's Ctrl-C.
//!
//! Why a flag and not a callback: the loops that can run long (a run's steps and frames, a walk's or
//! a throw's control iterations, an optimisation's generations) are many and nested, and the one
//! thing that can ask them to stop is process-wide by nature (a signal). A caller that waits on a
//! computation, such as the Python package, calls [`request`] when the user interrupts; every such
//! loop looks at [`requested`] once per step or iteration (an atomic load) and ends early: a run with
//! the error [`Interrupted`], a walk or a throw with the outcome so far, which the caller that asked
//! for the stop discards. [`clear`] before starting the next computation.
//!
//! The flag is the process's: a stop asked while two computations run stops both.

use std::sync::atomic::{AtomicBool, Ordering};

static REQUESTED: AtomicBool = AtomicBool::new(false);

/// Asks every running computation to stop at its next step.
pub fn request() {
    REQUESTED.store(true, Ordering::Relaxed);
}

/// Withdraws the request (before the next computation starts).
pub fn clear() {
    REQUESTED.store(false, Ordering::Relaxed);
}

/// Whether a stop has been asked for.
pub fn requested() -> bool {
    REQUESTED.load(Ordering::Relaxed)
}

/// A computation that stopped because a stop was asked for ([`request`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Interrupted;

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("interrupted")
    }
}

impl std::error::Error for Interrupted {}

/// `Err(Interrupted)` once a stop has been asked for.
pub fn check() -> Result<(), Interrupted> {
    if requested() { Err(Interrupted) } else { Ok(()) }
}
