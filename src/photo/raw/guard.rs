//! Containing decoder panics. rawler panics on some corrupt or unexpected
//! files instead of returning an error; [`contain`] turns such a panic into an
//! `Err(message)` for that file and keeps its message off stderr.
//!
//! The panic hook is process-global, so it is not swapped in and out around
//! each decode (two threads doing that at once can leave the wrong hook
//! installed for good). Instead a hook is installed once that stays silent
//! while the panicking thread is inside [`contain`] — or is a rayon worker
//! while some decode is running, since rawler decompresses in parallel — and
//! otherwise hands the panic to whatever hook was installed before it.

use std::any::Any;
use std::cell::Cell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Once;
use std::sync::atomic::{AtomicUsize, Ordering};

static INSTALL: Once = Once::new();
static ACTIVE: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    static QUIET: Cell<usize> = const { Cell::new(0) };
}

fn install() {
    INSTALL.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let here = QUIET.with(|q| q.get()) > 0;
            let worker =
                ACTIVE.load(Ordering::SeqCst) > 0 && rayon::current_thread_index().is_some();
            if !(here || worker) {
                previous(info);
            }
        }));
    });
}

/// Decrements the counters even if the closure unwinds.
struct Scope;

impl Drop for Scope {
    fn drop(&mut self) {
        QUIET.with(|q| q.set(q.get() - 1));
        ACTIVE.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Runs `f`; a panic inside it becomes `Err(panic message)`, printed nowhere.
pub(crate) fn contain<T>(f: impl FnOnce() -> T) -> Result<T, String> {
    install();
    QUIET.with(|q| q.set(q.get() + 1));
    ACTIVE.fetch_add(1, Ordering::SeqCst);
    let scope = Scope;
    let result = catch_unwind(AssertUnwindSafe(f));
    drop(scope);
    result.map_err(|payload| payload_text(payload.as_ref()))
}

fn payload_text(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "panic without a message".to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_panic_becomes_an_error_and_later_code_runs_normally() {
        let r: Result<(), String> = contain(|| panic!("bad tile {}", 7));
        assert_eq!(r.unwrap_err(), "bad tile 7");
        assert_eq!(contain(|| 3).unwrap(), 3);
        // nested use keeps the counters balanced
        let r = contain(|| contain(|| -> i32 { panic!("inner") }));
        assert_eq!(r.unwrap().unwrap_err(), "inner");
        assert_eq!(QUIET.with(|q| q.get()), 0);
    }

    #[test]
    fn a_panic_in_a_rayon_worker_is_contained() {
        use rayon::prelude::*;
        let r = contain(|| {
            (0..64).into_par_iter().for_each(|i| {
                if i == 33 {
                    panic!("worker {i}");
                }
            })
        });
        assert!(r.unwrap_err().contains("worker 33"));
    }
}
