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

/// `tshark -r PATH -T fields -E occurrence=a -e FIELD…`: one line per frame, its fields in
/// `fields`' order separated by tabs (a field's occurrences by commas).
pub(crate) fn fields(path: &Path, fields: &[&str]) -> String {
    let mut cmd = Command::new("tshark");
    cmd.arg("-r")
        .arg(path)
        .args(["-T", "fields", "-E", "occurrence=a"]);
    for f in fields {
        cmd.args(["-e", f]);
    }
    let out = cmd.output().expect("tshark runs");
    assert!(
        out.status.success(),
        "tshark on {}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Asserts that every frame tshark flagged in a run's own capture (its number and label) is of
/// a step `on_purpose` accepts, one that sends bytes as a suite wrote them; and that the wire's
/// capture, which has no labels, flags no more frames (`wire_flagged`) than the run's, which
/// has every frame and datagram the wire has.
pub(crate) fn assert_flagged_on_purpose(
    what: &str,
    run: &[(usize, Option<String>)],
    wire_flagged: usize,
    on_purpose: impl Fn(&str) -> bool,
) {
    let wrong: Vec<String> = run
        .iter()
        .filter(|(_, label)| !label.as_deref().is_some_and(&on_purpose))
        .map(|(n, label)| format!("run.pcapng frame {n}: {label:?}"))
        .collect();
    assert!(
        wrong.is_empty(),
        "{what}: flagged outside the steps that send bytes as written:\n{}",
        wrong.join("\n")
    );
    assert!(
        wire_flagged <= run.len(),
        "{what}: the wire shows {wire_flagged} flagged frames, the run's capture {}",
        run.len()
    );
}

/// How many frames of a capture, counted per protocol stack (`frame.protocols`), have a stack
/// that contains `layers` (`pn_rt`, `eth:ethertype:epl`…).
pub(crate) fn frames_with(
    stacks: &std::collections::HashMap<String, usize>,
    layers: &str,
) -> usize {
    stacks
        .iter()
        .filter(|(s, _)| s.contains(layers))
        .map(|(_, n)| *n)
        .sum()
}
