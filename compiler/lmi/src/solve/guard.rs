//! Containment of a solver's internal failures.
//!
//! Clarabel unwraps the result of its dense factorizations (the SVD and
//! eigendecomposition of each PSD cone's scaling), so an iterate that has
//! lost finiteness makes it panic instead of returning a status. [`run`]
//! turns that panic into an error the caller reports as a numerical-error
//! status, and keeps the default panic message off stderr while it runs, so
//! the user sees tsfc's diagnosis and never a solver backtrace.

use std::cell::Cell;
use std::panic::{self, AssertUnwindSafe};
use std::sync::Once;

thread_local! {
    /// Whether this thread is inside [`run`] (its panics are reported by the caller).
    static INSIDE: Cell<bool> = const { Cell::new(false) };
}

/// Installs, once per process, a panic hook that stays silent for panics
/// raised inside [`run`] and defers to the previous hook otherwise.
fn install_hook() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let previous = panic::take_hook();
        panic::set_hook(Box::new(move |info| {
            if !INSIDE.with(Cell::get) {
                previous(info);
            }
        }));
    });
}

/// Runs `body`, returning `Err` with the panic message if it panicked.
pub(crate) fn run<R>(body: impl FnOnce() -> R) -> Result<R, String> {
    install_hook();
    let was = INSIDE.with(|c| c.replace(true));
    let outcome = panic::catch_unwind(AssertUnwindSafe(body));
    INSIDE.with(|c| c.set(was));
    outcome.map_err(|payload| {
        payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "solver panicked".to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::run;

    #[test]
    fn a_panic_inside_becomes_an_error_and_the_flag_is_restored() {
        assert_eq!(run(|| 3), Ok(3));
        let err = run(|| -> u8 { panic!("SVD error: SVD(1)") }).unwrap_err();
        assert_eq!(err, "SVD error: SVD(1)");
        // Outside `run` again: a panic is not contained (and would print).
        assert!(!super::INSIDE.with(std::cell::Cell::get));
    }
}
