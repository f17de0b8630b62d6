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

    /// A hog when `NORD_TEST_HOG` is set (not empty), else none.
    pub(crate) fn if_asked() -> Option<Hog> {
        std::env::var_os("NORD_TEST_HOG")
            .is_some_and(|v| !v.is_empty())
            .then(Hog::start)
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
