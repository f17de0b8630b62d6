//! Network namespaces for end-to-end tests on raw Ethernet: a namespace of the test's own with
//! a veth pair, one end in this (the root) namespace and one inside, removed again when the
//! test ends, also when it panics.
//!
//! Uses `ip` (iproute2), and needs root (`CAP_SYS_ADMIN` for the namespace, `CAP_NET_ADMIN`
//! for the links): call [`require_root_or_skip`] first. A namespace left behind by a test that
//! was killed (no unwinding, so no `Drop`) is removed by the next [`Netns::new`], which finds
//! it by its name (the prefix and the id of a process that no longer runs).

#![allow(dead_code)] // each test binary uses a part

use std::process::{Command, Output, Stdio};
use std::sync::atomic::{AtomicU32, Ordering};

/// Every namespace made here is named `PREFIX<pid>-<n>-<tag>`.
const PREFIX: &str = "nord-test-";

pub(crate) use super::peer::require_or_skip;
use super::peer::{is_root, runs};

/// Whether the test can make network namespaces: root, and `ip` (iproute2) on the `PATH`.
/// Without them it skips, saying why, and fails in strict mode (`skip.rs`).
pub(crate) fn require_root_or_skip(why: &str) -> bool {
    require_or_skip(is_root(), "root for network namespaces", why)
        && require_or_skip(
            runs("ip", "-V"),
            "`ip` (iproute2: apt-get install iproute2) for network namespaces",
            why,
        )
}

/// Runs `ip ARGS…`; panics with its message when it fails.
fn ip(args: &[&str]) {
    let out = Command::new("ip").args(args).output().expect("`ip` runs");
    assert!(
        out.status.success(),
        "ip {}: {}",
        args.join(" "),
        String::from_utf8_lossy(&out.stderr).trim()
    );
}

/// A network namespace with a veth pair into it; everything is removed when it is dropped.
#[derive(Debug)]
pub(crate) struct Netns {
    name: String,
    root_if: String,
    ns_if: String,
}

impl Netns {
    /// Makes a namespace named after `tag` and this process, and a veth pair: one end stays
    /// in the root namespace, the other goes inside; both ends and the namespace's `lo` are
    /// brought up, and IPv6 is off on both ends (no router solicitations or MLD reports on
    /// the wire). Panics when `ip` fails: call [`require_root_or_skip`] first.
    pub(crate) fn new(tag: &str) -> Netns {
        static NEXT: AtomicU32 = AtomicU32::new(0);
        remove_stale();
        let pid = std::process::id();
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        // Interface names have at most 15 bytes: "nt" + pid and n in hex + "r"/"n".
        let link = format!("nt{pid:x}x{n:x}");
        let ns = Netns {
            name: format!("{PREFIX}{pid}-{n}-{tag}"),
            root_if: format!("{link}r"),
            ns_if: format!("{link}n"),
        };
        ip(&["netns", "add", &ns.name]);
        // From here on `Drop` removes what exists, should a step below panic.
        ip(&[
            "link",
            "add",
            &ns.root_if,
            "type",
            "veth",
            "peer",
            "name",
            &ns.ns_if,
            "netns",
            &ns.name,
        ]);
        let _ = std::fs::write(
            format!("/proc/sys/net/ipv6/conf/{}/disable_ipv6", ns.root_if),
            "1",
        );
        // Best effort: a kernel without IPv6 has nothing to turn off.
        let _ = ns.exec(&[
            "sh",
            "-c",
            &format!("echo 1 > /proc/sys/net/ipv6/conf/{}/disable_ipv6", ns.ns_if),
        ]);
        ip(&["link", "set", &ns.root_if, "up"]);
        ns.ip_inside(&["link", "set", &ns.ns_if, "up"]);
        ns.ip_inside(&["link", "set", "lo", "up"]);
        // Frames sent before the kernel's link watch has seen the carrier (a moment after
        // `up`, while the qdisc is still `noop`) are dropped: wait until both ends carry.
        wait_carrier(&[], &ns.root_if);
        wait_carrier(&["-n", &ns.name], &ns.ns_if);
        ns
    }

    /// Gives the root-side end the IPv4 address `root` and the inside end `inside`, both in
    /// CIDR notation (`10.200.0.1/24`). Use addresses of a private range that nothing else on
    /// the machine routes.
    pub(crate) fn add_ipv4(&self, root: &str, inside: &str) {
        ip(&["addr", "add", root, "dev", &self.root_if]);
        self.ip_inside(&["addr", "add", inside, "dev", &self.ns_if]);
    }

    /// The namespace's name.
    pub(crate) fn name(&self) -> &str {
        &self.name
    }

    /// The veth end in the root namespace.
    pub(crate) fn root_if(&self) -> &str {
        &self.root_if
    }

    /// The veth end inside the namespace.
    pub(crate) fn ns_if(&self) -> &str {
        &self.ns_if
    }

    /// A command that runs `program` inside the namespace (`ip netns exec NAME program`): add
    /// arguments, pipes and environment, then spawn or run it.
    pub(crate) fn command(&self, program: impl AsRef<std::ffi::OsStr>) -> Command {
        let mut c = Command::new("ip");
        c.args(["netns", "exec", &self.name]).arg(program);
        c
    }

    /// Runs `argv` inside the namespace to its end and returns what it printed.
    pub(crate) fn exec(&self, argv: &[&str]) -> Output {
        let (program, args) = argv.split_first().expect("a program to run");
        self.command(program)
            .args(args)
            .output()
            .expect("`ip netns exec` runs")
    }

    /// `ip ARGS…` inside the namespace.
    fn ip_inside(&self, args: &[&str]) {
        ip(&[&["-n", self.name.as_str()], args].concat());
    }
}

impl Drop for Netns {
    fn drop(&mut self) {
        // Deleting one end deletes the pair; deleting the namespace would too, but only once
        // no process holds it, so the root-side end goes first.
        let quiet = |args: &[&str]| {
            let _ = Command::new("ip")
                .args(args)
                .stdout(Stdio::null())
                .stderr(Stdio::null())
                .status();
        };
        quiet(&["link", "del", &self.root_if]);
        quiet(&["netns", "del", &self.name]);
    }
}

/// Waits (5 s at most, then panics) until `ip [NETNS] link show dev IFACE` says the link is up
/// with its queueing discipline attached.
fn wait_carrier(netns: &[&str], iface: &str) {
    let start = std::time::Instant::now();
    loop {
        let out = Command::new("ip")
            .args(netns)
            .args(["-o", "link", "show", "dev", iface])
            .output()
            .expect("`ip` runs");
        let text = String::from_utf8_lossy(&out.stdout);
        if text.contains("state UP") && !text.contains("qdisc noop") {
            return;
        }
        assert!(
            start.elapsed() < std::time::Duration::from_secs(5),
            "{iface} does not come up: {text}"
        );
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
}

/// Deletes the namespaces that tests of processes no longer running left behind.
fn remove_stale() {
    let Ok(out) = Command::new("ip").args(["netns", "list"]).output() else {
        return;
    };
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let Some(name) = line.split_whitespace().next() else {
            continue;
        };
        let Some(pid) = name
            .strip_prefix(PREFIX)
            .and_then(|rest| rest.split('-').next())
            .and_then(|p| p.parse::<u32>().ok())
        else {
            continue;
        };
        if pid != std::process::id() && !std::path::Path::new(&format!("/proc/{pid}")).exists() {
            let _ = Command::new("ip")
                .args(["netns", "del", name])
                .stderr(Stdio::null())
                .status();
        }
    }
}
