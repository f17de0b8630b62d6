//! Ctrl-C and SIGTERM during a run. The first asks the runner to stop: the step under way ends,
//! the case's cleanup runs (voltage disabled, the faults the harness caused acknowledged,
//! parameters restored, connections closed), no further case starts, and the reports are written
//! marked "interrupted" with the case-runs left. The second aborts at once, saying what that
//! left undone. Without the first, a CI job cancelled mid-run left no reports and a device on the
//! network faulted for the next run.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

use signal_hook::consts::{SIGINT, SIGTERM};

/// Whether a stop was asked for.
static REQUESTED: AtomicBool = AtomicBool::new(false);

/// What the run is doing, for the message of an abort.
static DOING: Mutex<String> = Mutex::new(String::new());

/// The exit code of an interrupted run: 128 + SIGINT, as shells report one.
pub(crate) const EXIT_INTERRUPTED: i32 = 130;

/// The flag the first signal sets, for the runner to read at each step boundary
/// ([`crate::runner::RunOptions::stop`]).
pub(crate) fn flag() -> &'static AtomicBool {
    &REQUESTED
}

/// Notes what the run is doing now (a case-run, the reports), for an abort's message.
pub(crate) fn doing(what: impl Into<String>) {
    *DOING.lock().unwrap_or_else(|e| e.into_inner()) = what.into();
}

/// Watches for SIGINT and SIGTERM on a thread of its own for the rest of the process.
pub(crate) fn install() -> Result<(), String> {
    let mut signals = signal_hook::iterator::Signals::new([SIGINT, SIGTERM])
        .map_err(|e| format!("cannot watch for Ctrl-C: {e}"))?;
    std::thread::Builder::new()
        .name("signals".into())
        .spawn(move || {
            for signal in signals.forever() {
                let name = if signal == SIGTERM { "SIGTERM" } else { "SIGINT" };
                if !REQUESTED.swap(true, Ordering::Relaxed) {
                    eprintln!(
                        "\nharness: {name}: stopping after the step under way and its case's cleanup, then writing the reports marked \"interrupted\" (again to abort at once)"
                    );
                } else {
                    let doing = DOING.lock().map(|d| d.clone()).unwrap_or_default();
                    eprintln!("\nharness: {name} again: aborted. {}", left_undone(&doing));
                    std::process::exit(EXIT_INTERRUPTED);
                }
            }
        })
        .map(drop)
        .map_err(|e| format!("cannot watch for Ctrl-C: {e}"))
}

/// What an abort leaves undone while the run is `doing` something.
fn left_undone(doing: &str) -> String {
    if doing.is_empty() {
        "No report was written.".into()
    } else {
        format!(
            "Left undone: {doing} (its cleanup did not run: the DUT may still have voltage enabled, a fault set, parameters changed or a connection open), and no report was written."
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_abort_names_what_it_left_undone() {
        let text = left_undone("tu3-eip@enip bu0620/drive-switching/rotation-left");
        assert!(text.starts_with("Left undone: tu3-eip@enip bu0620/drive-switching/rotation-left (its cleanup did not run"), "{text}");
        assert!(text.ends_with("no report was written."), "{text}");
        assert_eq!(left_undone(""), "No report was written.");
    }
}
