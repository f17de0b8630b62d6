//! A tshark capture on an interface of a test's network namespace, for the tests that let
//! Wireshark's dissectors judge the traffic on the wire.

use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};

use super::netns::Netns;

/// A tshark capture, stopped (SIGINT, so it finishes its file) when dropped.
pub(crate) struct Capture(Child);

impl Capture {
    /// Starts tshark on `iface` inside `ns`, writing `file`; returns once it captures.
    pub(crate) fn start(ns: &Netns, iface: &str, file: &Path) -> Capture {
        let mut child = ns
            .command("tshark")
            .args(["-i", iface, "-q", "-w"])
            .arg(file)
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("tshark starts");
        // tshark says "Capturing on 'IFACE'" once its capture runs.
        let stderr = child.stderr.take().expect("tshark's stderr");
        let mut lines = BufReader::new(stderr).lines();
        loop {
            let line = lines
                .next()
                .expect("tshark announces its capture")
                .expect("tshark's stderr reads");
            if line.contains("Capturing on") {
                break;
            }
        }
        // Keep draining stderr so tshark never blocks on it.
        std::thread::spawn(move || lines.for_each(drop));
        Capture(child)
    }

    /// Stops the capture and waits until tshark has written its file.
    pub(crate) fn stop(mut self) {
        interrupt(&self.0);
        let _ = self.0.wait();
    }
}

impl Drop for Capture {
    fn drop(&mut self) {
        if matches!(self.0.try_wait(), Ok(None)) {
            interrupt(&self.0);
            let _ = self.0.wait();
        }
    }
}

/// SIGINT to a child (`ip netns exec` execs its program, so the pid is tshark's).
fn interrupt(child: &Child) {
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
}
