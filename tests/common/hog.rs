//! A busy host on cue: one process per core spinning in a shell loop, as other builds and jobs
//! on a shared CI runner load it. The network tests run under it when `NORD_TEST_HOG` is set
//! (`.ci/run` sets it), and the load test always: their verdicts must not move with the host's
//! load.
//!
//! Bounded: each spinner is `timeout 1800 sh -c …`, so even a test killed before its `Drop`
//! leaves nothing spinning for longer than that; dropping the [`Hog`] sends SIGTERM, which
//! `timeout` passes on to its shell.

#![allow(dead_code)] // each test binary uses a part

use std::process::{Child, Command, Stdio};
use std::sync::Mutex;

/// The spinners; stopped when dropped.
pub(crate) struct Hog(Vec<Child>);

impl Hog {
    /// One spinner per core of the machine.
    pub(crate) fn start() -> Hog {
        let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
        let spinners = (0..cores)
            .map(|_| {
                Command::new("timeout")
                    .args(["1800", "sh", "-c", "while :; do :; done"])
                    .stdin(Stdio::null())
                    .spawn()
                    .expect("a spinner starts (timeout, sh)")
            })
            .collect();
        eprintln!("host loaded: {cores} spinning processes, one per core");
        Hog(spinners)
    }

    /// When `NORD_TEST_HOG` is set (not empty), the hog of this test binary until the guard
    /// is dropped: tests that run side by side share one (one spinner per core, not per test),
    /// and the last guard dropped stops it.
    pub(crate) fn if_asked() -> Option<Shared> {
        if !std::env::var_os("NORD_TEST_HOG").is_some_and(|v| !v.is_empty()) {
            return None;
        }
        let mut shared = SHARED.lock().unwrap_or_else(|e| e.into_inner());
        shared.0 += 1;
        if shared.1.is_none() {
            shared.1 = Some(Hog::start());
        }
        Some(Shared)
    }
}

/// The test binary's hog and the guards that hold it.
static SHARED: Mutex<(usize, Option<Hog>)> = Mutex::new((0, None));

/// A hold on the test binary's shared hog ([`Hog::if_asked`]).
pub(crate) struct Shared;

impl Drop for Shared {
    fn drop(&mut self) {
        let mut shared = SHARED.lock().unwrap_or_else(|e| e.into_inner());
        shared.0 -= 1;
        if shared.0 == 0 {
            shared.1 = None;
        }
    }
}

impl Drop for Hog {
    fn drop(&mut self) {
        for c in &mut self.0 {
            // SIGTERM: `timeout` ends its shell with it (SIGKILL would leave the shell spinning).
            let _ = Command::new("kill")
                .args(["-TERM", &c.id().to_string()])
                .status();
            let _ = c.wait();
        }
    }
}
