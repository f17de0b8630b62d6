//! POWERLINK speed over a veth pair: `cargo bench -p harness --bench epl`.
//!
//! One run makes a network namespace with a veth pair into it, serves the simulated SK 550P
//! there with the built `harness serve epl` (a process of its own, as a device would be: raw
//! Ethernet, and SDO over UDP 3819 on the inner end's IPv4 address), and prints, one line per
//! figure with its target and whether it was met:
//!
//! - SDO reads per second of the harness managing node with the node in PRE_OPERATIONAL_2:
//!   **one operation is one complete SDO read** of 1018h:01h (the vendor id, expedited): the
//!   upload request sent, the node's answer with the value received (an SDO abort would end
//!   the figure with an error). Over ASnd at the 1 ms cycle and at 400 µs (an ASnd read takes
//!   at least two cycles: the MN's slot for the request, an invite for the answer), and over
//!   UDP beside the running 1 ms cycle;
//! - the isochronous cycle the MN sustains with the node OPERATIONAL at 1 ms (P858's factory
//!   setting) and at 400 µs (P858's minimum, BU 0620 §4.2.3), 10 s each: **one operation is
//!   one cycle** (SoC, PReq, the node's PRes, SoA); PRes missed (not within the MN's reply
//!   time) and p50, p99 and maximum of |interval − cycle| between the kernel's receive stamps
//!   (SO_TIMESTAMPNS) of consecutive PRes (targets: p99 < 100 µs at 1 ms; no PRes missed in
//!   10 s at 400 µs).
//!
//! The node runs in one network namespace on one end of the pair, at 192.168.100.1 (node 1's
//! address, BU 0620 §3.7.3: `harness serve epl` serves SDO over UDP on the node's address), at
//! a real-time priority (`chrt -f 10`) where it can, standing in for a device with a processor
//! of its own; the MN runs in threads of this process inside a second namespace on the other
//! end, at 192.168.100.240, as `harness run` runs it. Neither end is in the root namespace,
//! where a test running meanwhile may have the POWERLINK subnet on a veth end of its own.
//!
//! `cargo bench -p harness --bench epl -- WORD…` runs only the figures whose key
//! (`sdo-asnd-1ms`, `sdo-asnd-400us`, `sdo-udp`, `cycle-1ms`, `cycle-400us`) contains one of
//! the words. A bench, not a timed test: bounded in count and time (about 50 s), nothing
//! asserts on time, a missed target is printed, not failed. Without root (or without `ip`) it
//! says why and exits 0.

use std::net::SocketAddr;
use std::time::Duration;

use harness::epl_bench::{self, Transport};
use harness::stats::{jitter, Rate};

#[path = "../common/mod.rs"]
mod common;
#[path = "../../../tests/common/netns.rs"]
mod netns;
// What netns.rs takes its root check from.
#[allow(unused_imports)]
#[path = "../../../tests/common/peer.rs"]
mod peer;

use common::served::Served;
use common::{ip, met, wait_carrier, ClientNs};
use netns::Netns;

/// The p99 of |interval − cycle| of the PRes arrivals must stay below this at 1 ms.
const TARGET_P99: Duration = Duration::from_micros(100);
/// P858's factory cycle and its minimum (BU 0620 §4.2.3).
const CYCLE: Duration = Duration::from_millis(1);
const MIN_CYCLE: Duration = Duration::from_micros(400);

/// What to measure, and the bounds of each figure.
#[derive(Debug, Clone)]
struct Settings {
    /// SDO reads over ASnd, at most, per cycle time.
    asnd_reads: u32,
    /// SDO reads over UDP, at most.
    udp_reads: u32,
    /// Time limit of each SDO figure.
    limit: Duration,
    /// How long each cycle figure runs.
    record: Duration,
    /// Words from the command line (`cargo bench -p harness --bench epl -- udp cycle-400`):
    /// only the figures whose key contains one of them run; all when there are none.
    only: Vec<String>,
}

impl Settings {
    /// The bounds: 5,000 reads over ASnd (at most 2,500 fit in 5 s at 400 µs), 20,000
    /// over UDP, each within 5 s; 10 s of cycles at 1 ms and at 400 µs.
    fn new() -> Settings {
        Settings {
            asnd_reads: 5_000,
            udp_reads: 20_000,
            limit: Duration::from_secs(5),
            record: Duration::from_secs(10),
            only: std::env::args()
                .skip(1)
                .filter(|a| !a.starts_with('-'))
                .collect(),
        }
    }

    /// Whether the figure of `key` (`sdo-asnd-1ms`, `sdo-asnd-400us`, `sdo-udp`,
    /// `cycle-1ms`, `cycle-400us`) runs.
    fn wants(&self, key: &str) -> bool {
        self.only.is_empty() || self.only.iter().any(|w| key.contains(w.as_str()))
    }
}

fn main() {
    if let Some(why) = cannot_run() {
        println!("POWERLINK bench skipped: {why}");
        return;
    }
    if let Err(e) = run(&Settings::new()) {
        eprintln!("POWERLINK bench could not run: {e}");
        std::process::exit(1);
    }
}

/// Why this machine cannot run the bench (network namespaces and raw Ethernet need root and
/// `ip`), if it cannot: the EtherCAT bench's rule.
fn cannot_run() -> Option<String> {
    if !peer::is_root() {
        return Some("needs root (a network namespace with a veth pair, raw Ethernet)".into());
    }
    if !peer::runs("ip", "-V") {
        return Some("needs `ip` (iproute2) for the network namespace".into());
    }
    None
}

/// `harness serve epl --iface IFACE` inside `ns` for `seconds` at most (under `chrt -f 10`
/// when `realtime`), once it says it serves.
fn serve_node(ns: &Netns, seconds: u64, realtime: bool) -> Result<(Served, String), String> {
    let command = if realtime {
        let mut c = ns.command("chrt");
        c.args(["-f", "10", env!("CARGO_BIN_EXE_harness")]);
        c
    } else {
        ns.command(env!("CARGO_BIN_EXE_harness"))
    };
    let seconds = seconds.to_string();
    Served::start(
        command,
        "epl",
        &["--iface", ns.ns_if(), "--seconds", &seconds],
    )
}

/// Serves the node and prints every figure. An error means the bench could not run at all;
/// a figure that fails prints why and the rest go on.
fn run(s: &Settings) -> Result<(), String> {
    let ns = Netns::new("epl-bench");
    let node_ip = proto::nord::epl::ip_address(epl_bench::NODE);
    let mn_ip = proto::nord::epl::ip_address(proto::epl::MN_NODE_ID);
    ip(&[
        "-n",
        ns.name(),
        "addr",
        "add",
        &format!("{node_ip}/24"),
        "dev",
        ns.ns_if(),
    ])?;
    let mn = ClientNs::new(ns.root_if(), "epl-bench-mn", &format!("{mn_ip}/24"))?;
    wait_carrier(ns.name(), ns.ns_if())?;
    wait_carrier(&mn.name, &mn.iface)?;
    // The node stands in for a device, which has a processor of its own: served at a
    // real-time priority, a busy machine does not delay its PRes by a time slice (at 400 µs a
    // served node at normal priority missed 59 of 25,000 PRes on a loaded 2-core machine, at
    // SCHED_FIFO 0 or 1). The managing node, the thing measured, runs as `harness run` runs it.
    let (node, line, priority) = match serve_node(&ns, 180, peer::runs("chrt", "--version")) {
        Ok((node, line)) => (node, line, "SCHED_FIFO 10 (chrt)"),
        Err(e) => {
            let (node, line) = serve_node(&ns, 180, false)?;
            eprintln!("serving the node at a real-time priority failed ({e}): normal priority");
            (node, line, "normal priority")
        }
    };
    let iface = mn.iface.clone();
    let udp = SocketAddr::from((node_ip, proto::epl::SDO_UDP_PORT));
    println!(
        "POWERLINK bench: {line}, at {priority}, namespace {}; managing node on {iface} ({mn_ip}/24) in {}",
        ns.name(),
        mn.name
    );

    for (key, via, cycle, count, what) in [
        (
            "sdo-asnd-1ms",
            Transport::Asnd,
            CYCLE,
            s.asnd_reads,
            "over ASnd, 1 ms cycle",
        ),
        (
            "sdo-asnd-400us",
            Transport::Asnd,
            MIN_CYCLE,
            s.asnd_reads,
            "over ASnd, 400 µs cycle",
        ),
        (
            "sdo-udp",
            Transport::Udp,
            CYCLE,
            s.udp_reads,
            "over UDP, beside the 1 ms cycle",
        ),
    ] {
        if !s.wants(key) {
            continue;
        }
        let head = format!(
            "harness MN, SDO reads of {:04X}h:{:02X}h in PRE_OPERATIONAL_2 {what}",
            epl_bench::INDEX,
            epl_bench::SUB
        );
        match mn.run(|| epl_bench::sdo_reads(&iface, udp, via, cycle, count, s.limit))? {
            Ok(r) => {
                let per_cycle = if via == Transport::Asnd {
                    format!(
                        " ({:.2} cycles per read)",
                        r.secs / cycle.as_secs_f64() / r.count.max(1) as f64
                    )
                } else {
                    String::new()
                };
                println!("{head}: {}{per_cycle}", r.show("reads"));
            }
            Err(e) => println!("{head}: failed ({e})"),
        }
    }

    for (key, cycle) in [("cycle-1ms", CYCLE), ("cycle-400us", MIN_CYCLE)] {
        if !s.wants(key) {
            continue;
        }
        let what = format!(
            "cycle SoC/PReq/PRes/SoA every {} µs in OPERATIONAL for {} s",
            cycle.as_micros(),
            s.record.as_secs_f64()
        );
        match mn.run(|| epl_bench::cycles(&iface, udp, cycle, s.record))? {
            Ok(c) => {
                let sustained = c.elapsed / c.cycles.max(1);
                let target = if cycle == MIN_CYCLE {
                    format!("target no PRes missed: {}", met(c.missed == 0))
                } else {
                    format!("PRes missed: {}", c.missed)
                };
                let rate = Rate {
                    count: u64::from(c.cycles),
                    secs: c.elapsed.as_secs_f64(),
                };
                println!(
                    "{what}: {} ({} µs sustained), {} PRes missed, {} without stamp, node {} at the end ({target})",
                    rate.show("cycles"),
                    sustained.as_micros(),
                    c.missed,
                    c.unstamped,
                    c.state.as_deref().unwrap_or("silent")
                );
                match jitter(&c.arrivals, cycle) {
                    Some(j) => println!(
                        "  |interval − cycle| of PRes receive stamps: p50 {} µs, p99 {} µs, max {} µs{}",
                        j.p50.as_micros(),
                        j.p99.as_micros(),
                        j.max.as_micros(),
                        if cycle == CYCLE {
                            format!(
                                " (target p99 < {} µs: {})",
                                TARGET_P99.as_micros(),
                                met(j.p99 < TARGET_P99)
                            )
                        } else {
                            String::new()
                        }
                    ),
                    None => println!("  no two consecutive stamped PRes"),
                }
            }
            Err(e) => println!("{what}: failed ({e})"),
        }
    }
    drop(node);
    drop(mn);
    drop(ns);
    Ok(())
}
