//! The process's exit codes, shared by every command (`run`, `serve <bus>`, `diff`, `merge`):
//! 0 every case passed (or did not apply), 1 a case failed or ended in error, 2 usage or
//! configuration error (bad arguments, a suite file that does not load).

use crate::outcome::{RunResult, Verdict};

/// Exit code: every case passed or did not apply.
pub const EXIT_PASS: i32 = 0;
/// Exit code: a case failed or ended in error.
pub const EXIT_FAIL: i32 = 1;
/// Exit code: usage or configuration error.
pub const EXIT_USAGE: i32 = 2;

/// A run's exit code: usage error when a suite file did not load, fail when a case failed or
/// ended in error, else pass (a merge of shards exits as the unsharded run would).
pub(crate) fn verdict_exit(run: &RunResult) -> i32 {
    if !run.load_errors.is_empty() {
        EXIT_USAGE
    } else if run.count(Verdict::Fail) + run.count(Verdict::Error) > 0 {
        EXIT_FAIL
    } else {
        EXIT_PASS
    }
}
