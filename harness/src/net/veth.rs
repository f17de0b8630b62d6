//! A veth pair for the unit tests of raw Ethernet code (root only).

use std::process::Command;

use super::RawLink;

// The end-to-end tests' one rule for a test that cannot run here: skip and record it, or fail
// in strict mode.
#[path = "../../../tests/common/skip.rs"]
mod skip;

/// A veth pair in this namespace, deleted when dropped.
pub(crate) struct Veth(pub(crate) String, pub(crate) String);

impl Veth {
    /// Creates and brings up a pair, or says why not: `None` skips the test without root (in
    /// strict mode it fails: a run must not pass by skipping).
    pub(crate) fn new(tag: &str) -> Option<Veth> {
        if let Err(e) = RawLink::open("lo", None) {
            let what = format!("root ({e})");
            skip::require_or_skip(false, &what, "raw Ethernet over a veth pair");
            return None;
        }
        let a = format!("vt{tag}{}a", std::process::id() % 100_000);
        let b = format!("vt{tag}{}b", std::process::id() % 100_000);
        let ip = |args: &[&str]| {
            let ok = Command::new("ip").args(args).status().map(|s| s.success());
            assert!(matches!(ok, Ok(true)), "ip {args:?}: {ok:?}");
        };
        ip(&["link", "add", &a, "type", "veth", "peer", "name", &b]);
        let v = Veth(a, b);
        ip(&["link", "set", &v.0, "up"]);
        ip(&["link", "set", &v.1, "up"]);
        // Frames sent before the kernel's link watch has seen the carrier (a moment after
        // `up`, with the qdisc still `noop`) are dropped: wait for it.
        for name in [&v.0, &v.1] {
            let t = std::time::Instant::now();
            loop {
                let out = Command::new("ip")
                    .args(["-o", "link", "show", "dev", name])
                    .output();
                let text = out.map(|o| String::from_utf8_lossy(&o.stdout).into_owned());
                let text = text.unwrap_or_default();
                if text.contains("state UP") && !text.contains("qdisc noop") {
                    break;
                }
                assert!(t.elapsed().as_secs() < 5, "{name} not up: {text}");
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
        }
        Some(v)
    }
}

impl Drop for Veth {
    fn drop(&mut self) {
        let _ = Command::new("ip").args(["link", "del", &self.0]).status();
    }
}
