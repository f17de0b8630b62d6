//! The bench driver's served device: `harness serve BUS …` as a process of its own, as a
//! device on the network is, which any bench starts the same way — the harness binary (or a
//! wrapper such as `chrt` around it, inside a network namespace or not), its line saying it
//! serves awaited, its stderr passed on, the process killed when the bench is done with it.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

/// How long a served device has to say it serves.
const START: Duration = Duration::from_secs(10);

/// A served device; dropping it kills the process.
pub(crate) struct Served(Child);

impl Served {
    /// Runs `command` (which runs the harness binary) with `serve BUS ARGS…` and waits for its
    /// first line on stdout, which must say it serves (it prints it once its sockets are
    /// bound): that line. Its stderr lines are passed on, named.
    pub(crate) fn start(
        mut command: Command,
        bus: &str,
        args: &[&str],
    ) -> Result<(Served, String), String> {
        let name = format!("harness serve {bus}");
        let mut child = command
            .args(["serve", bus])
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| format!("cannot start {name}: {e}"))?;
        let (Some(stdout), Some(stderr)) = (child.stdout.take(), child.stderr.take()) else {
            return Err(format!("no stdout or stderr of {name}"));
        };
        let served = Served(child);
        let prefix = name.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(stderr).lines().map_while(Result::ok) {
                eprintln!("{prefix}: {line}");
            }
        });
        let (tx, rx) = mpsc::channel();
        std::thread::spawn(move || {
            let mut lines = BufReader::new(stdout).lines();
            let _ = tx.send(lines.next());
            // Keep reading, so the device never blocks on a full pipe.
            for _ in lines {}
        });
        match rx.recv_timeout(START) {
            Ok(Some(Ok(line))) if line.starts_with("serving") => Ok((served, line)),
            Ok(other) => Err(format!("{name} said: {other:?}")),
            Err(_) => Err(format!("{name} did not start within {} s", START.as_secs())),
        }
    }
}

impl Served {
    /// The process id, to sample its memory from `/proc/PID/status` (the soak).
    pub(crate) fn pid(&self) -> u32 {
        self.0.id()
    }
}

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}
