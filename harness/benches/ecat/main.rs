//! EtherCAT speed over a veth pair: `cargo bench -p harness --bench ecat`.
//!
//! One run makes a network namespace with a veth pair into it, serves the simulated SK 550P
//! there with the built `harness serve ecat` (a process of its own, as a device would be),
//! and prints, one line per figure with its target and whether it was met:
//!
//! - frame round trips per second of the harness master: **one operation is one frame** sent
//!   and back, an FPRD of the AL status register;
//! - CoE SDO uploads per second of the harness master and of pysoem (SOEM, a subprocess in
//!   the interop venv) of the same object (1018h:01h, the vendor id), in interleaved rounds,
//!   and the ratio of the two (target: harness ≥ 5× pysoem): **one operation is one complete
//!   SDO upload**, the request written to the slave's receive mailbox and the response with
//!   the value read from its send mailbox (an abort ends the figure with an error);
//! - the jitter of the harness master's 1 ms process data cycle in Operational over 10 s:
//!   p50, p99 and maximum of |interval − cycle| between the kernel's receive stamps
//!   (SO_TIMESTAMPNS) of consecutive returning frames (target p99 < 100 µs).
//!
//! Both masters run in this (the root) namespace on the root end of the pair; the slave in
//! the namespace on the other. A bench, not a timed test: bounded in count and time (about
//! 40 s), nothing asserts on time, a missed target is printed, not failed. Without root (or
//! without `ip`) it says why and exits 0.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use harness::ecat_bench;
use harness::stats::{jitter, median, percentile, Rate};

#[path = "../common/mod.rs"]
mod common;
#[path = "../../../tests/common/netns.rs"]
mod netns;
#[allow(dead_code)] // the skip-or-fail rule netns.rs uses
#[path = "../../../tests/common/peer.rs"]
mod peer;

use common::served::Served;
use common::{met, run_script, Script};
use netns::Netns;

/// The harness master must make at least this many SDO uploads per pysoem upload.
const TARGET_RATIO: f64 = 5.0;
/// The p99 of |interval − cycle| of the returning process data frames must stay below this.
const TARGET_P99: Duration = Duration::from_micros(100);
/// The object uploaded: 1018h:01h, vendor id 538h (BU 0620 §2.2.7.1).
const INDEX: u16 = 0x1018;
const SUB: u8 = 1;

/// What to measure, and the bounds of each figure.
#[derive(Debug, Clone)]
struct Settings {
    /// Frame round trips, at most.
    round_trips: u32,
    /// Rounds of the SDO figures (harness, pysoem in turn).
    rounds: u32,
    /// SDO uploads per round and master, at most.
    uploads: u32,
    /// Time limit of each round-trip or upload figure.
    limit: Duration,
    /// Process data cycle time.
    cycle: Duration,
    /// How long the cycle runs.
    record: Duration,
    /// The interop venv's Python, when it exists.
    python: Option<PathBuf>,
    /// `tests/interop/pysoem_bench.py`.
    script: PathBuf,
}

impl Settings {
    /// The bounds: 20,000 round trips, 3 rounds of 1,600 uploads per master (under
    /// 5,000 each), 10 s of 1 ms cycles; each round-trip or upload figure within 5 s.
    fn new() -> Settings {
        Settings {
            round_trips: 20_000,
            rounds: 3,
            uploads: 1_600,
            limit: Duration::from_secs(5),
            cycle: Duration::from_millis(1),
            record: Duration::from_secs(10),
            python: common::interop_python(),
            script: Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/interop/pysoem_bench.py"),
        }
    }
}

fn main() {
    if let Some(why) = cannot_run() {
        println!("EtherCAT bench skipped: {why}");
        return;
    }
    if let Err(e) = run(&Settings::new()) {
        eprintln!("EtherCAT bench could not run: {e}");
        std::process::exit(1);
    }
}

/// Why this machine cannot run the bench (network namespaces and raw Ethernet need root and
/// `ip`), if it cannot.
fn cannot_run() -> Option<String> {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let euid = status
        .lines()
        .find(|l| l.starts_with("Uid:"))
        .and_then(|l| l.split_whitespace().nth(2))
        .and_then(|u| u.parse::<u32>().ok());
    if euid != Some(0) {
        return Some("needs root (a network namespace with a veth pair, raw Ethernet)".into());
    }
    let ip = Command::new("ip")
        .arg("-V")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status();
    if !ip.is_ok_and(|s| s.success()) {
        return Some("needs `ip` (iproute2) for the network namespace".into());
    }
    None
}

/// Serves the slave and prints every figure. An error means the bench could not run at all;
/// a figure that fails prints why and the rest go on.
fn run(s: &Settings) -> Result<(), String> {
    let ns = Netns::new("ecat-bench");
    let command = ns.command(env!("CARGO_BIN_EXE_harness"));
    let (slave, line) = Served::start(
        command,
        "ecat",
        &["--iface", ns.ns_if(), "--seconds", "120"],
    )?;
    let iface = ns.root_if().to_string();
    println!(
        "EtherCAT bench: {line}, namespace {}; masters on {iface}",
        ns.name()
    );

    match ecat_bench::round_trips(&iface, s.round_trips, s.limit) {
        Ok(r) => println!(
            "harness master, frame round trips (FPRD of AL status, 1 frame each): {}",
            r.show("round trips")
        ),
        Err(e) => println!("harness master, frame round trips: failed ({e})"),
    }

    // The SDO figures in interleaved rounds, so that a burst of load elsewhere on the machine
    // falls on both masters alike; each figure is the median of its rounds.
    let mut harness = Vec::new();
    let mut pysoem = Vec::new();
    let mut pysoem_client = None;
    for round in 1..=s.rounds {
        let mut line = format!(
            "round {round}/{}: SDO upload {INDEX:04X}h:{SUB:02X}h:",
            s.rounds
        );
        match ecat_bench::sdo_uploads(&iface, INDEX, SUB, s.uploads, s.limit) {
            Ok(r) => {
                line += &format!(" harness master {:.0}/s", r.per_sec());
                harness.push(r.per_sec());
            }
            Err(e) => line += &format!(" harness master failed ({e})"),
        }
        match pysoem_uploads(s, &iface) {
            Pysoem::Skipped(why) => line += &format!(", pysoem skipped ({why})"),
            Pysoem::Failed(why) => line += &format!(", pysoem failed ({why})"),
            Pysoem::Ran { client, rate } => {
                line += &format!(", {client} {:.0}/s", rate.per_sec());
                pysoem.push(rate.per_sec());
                pysoem_client = Some(client);
            }
        }
        println!("{line}");
    }
    let (harness, pysoem) = (median(harness), median(pysoem));
    let show = |what: &str, rate: Option<f64>| match rate {
        Some(r) => println!("{what}, median of the rounds: {r:.0} SDO uploads/s"),
        None => println!("{what}: no round completed"),
    };
    show("harness master", harness);
    if let Some(client) = &pysoem_client {
        show(client, pysoem);
    }
    if let (Some(h), Some(p)) = (harness, pysoem) {
        let ratio = h / p;
        println!(
            "harness master / pysoem: {ratio:.1}x (target >= {TARGET_RATIO}x: {})",
            met(ratio >= TARGET_RATIO)
        );
    }

    let what = format!(
        "process data, LRW every {} µs in OP for {} s",
        s.cycle.as_micros(),
        s.record.as_secs_f64()
    );
    match ecat_bench::pdo_cycles(&iface, s.cycle, s.record) {
        Ok(c) => {
            match jitter(&c.arrivals, s.cycle) {
                Some(j) => println!(
                    "{what}: {} cycles, {} lost, {} without stamp, {} working counter errors; |interval − cycle| of receive stamps p50 {} µs, p99 {} µs, max {} µs (target p99 < {} µs: {})",
                    c.cycles,
                    c.lost,
                    c.unstamped,
                    c.wkc_errors,
                    j.p50.as_micros(),
                    j.p99.as_micros(),
                    j.max.as_micros(),
                    TARGET_P99.as_micros(),
                    met(j.p99 < TARGET_P99)
                ),
                None => println!(
                    "{what}: no two consecutive stamped cycles ({} cycles, {} lost, {} without stamp)",
                    c.cycles, c.lost, c.unstamped
                ),
            }
            // Where the jitter comes from: the master sending late, or the frame's way through
            // the slave.
            println!(
                "  of which: sent after due {}; send to return {}",
                spread(c.late),
                spread(c.round_trips)
            );
        }
        Err(e) => println!("{what}: failed ({e})"),
    }
    drop(slave);
    drop(ns);
    Ok(())
}

/// What pysoem did.
enum Pysoem {
    Skipped(String),
    Failed(String),
    Ran { client: String, rate: Rate },
}

/// pysoem's SDO uploads: `pysoem_bench.py` in the interop venv on `iface`, one JSON line back.
fn pysoem_uploads(s: &Settings, iface: &str) -> Pysoem {
    let args = [
        iface.to_string(),
        "--count".into(),
        s.uploads.to_string(),
        "--seconds".into(),
        s.limit.as_secs_f64().to_string(),
        "--index".into(),
        format!("{INDEX:#x}"),
        "--sub".into(),
        SUB.to_string(),
        "--deadline".into(),
        (s.limit.as_secs() + 30).to_string(),
    ];
    let v = match run_script(s.python.as_deref(), &s.script, &args, "pysoem", s.limit) {
        Script::Skipped(why) => return Pysoem::Skipped(why),
        Script::Failed(why) => return Pysoem::Failed(why),
        Script::Ran(v) => v,
    };
    match (
        v.get("count").and_then(serde_json::Value::as_u64),
        v.get("seconds").and_then(serde_json::Value::as_f64),
    ) {
        (Some(count), Some(secs)) if count > 0 => Pysoem::Ran {
            client: v
                .get("client")
                .and_then(serde_json::Value::as_str)
                .unwrap_or("pysoem")
                .to_string(),
            rate: Rate { count, secs },
        },
        _ => Pysoem::Failed(format!("unexpected reply from pysoem_bench.py: {v}")),
    }
}

/// `p50 3 µs, p99 20 µs, max 3900 µs` of `values`.
fn spread(mut values: Vec<Duration>) -> String {
    values.sort();
    let p = |q: f64| percentile(&values, q).map_or(0, |d| d.as_micros());
    format!(
        "p50 {} µs, p99 {} µs, max {} µs",
        p(50.0),
        p(99.0),
        values.last().map_or(0, |d| d.as_micros())
    )
}
