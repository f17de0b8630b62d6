//! System-bus speed over loopback: `cargo bench -p harness --bench can`.
//!
//! One run serves the simulated SK 550P's system bus with the built `harness serve can
//! --socketcand` (a process of its own, as a socketcand server on a test bench would be) and
//! prints, one line per figure with its target and whether it was met:
//!
//! - SDO reads per second of the harness's own SDO client: **one operation is one complete SDO
//!   read** of P102 set 1 of FI 3 (node 36, 2066h:01h, expedited), the upload request sent and
//!   the node's answer with the value received, one after the other;
//! - python-canopen's, the same operation, in the same run against the same server
//!   (`tests/interop/canopen_bench.py` in the interop venv; said and skipped without it);
//!   target: the harness at least 5 times as fast;
//! - the jitter of the harness's process-data cycle at 5 ms (FI 2's RPDOs and a SYNC per
//!   cycle, over socketcand): the SYNC intervals a second client of the bus sees, median,
//!   1st–99th percentile and worst, against a target of 98 % within 0.5 ms of the period;
//! - the bus time one process-data cycle of 8 inverters takes at 250 kBaud at the most
//!   (`proto::nord::can::cycle_bus_time_us`: SYNC, each inverter's RPDOs and TPDOs at their
//!   worst-case stuffed length), against the 8-inverter update cycle of BU 2100's table and
//!   the 5 ms the manuals allow at least: the physical floor the simulator must respect.
//!
//! A bench, not a timed test: bounded in count and time (a few seconds), nothing asserts on
//! time, a missed target is printed, not failed.

use std::net::SocketAddr;
use std::path::Path;
use std::process::Command;
use std::time::Duration;

use harness::can_bench;
use harness::stats::Rate;
use proto::nord::can::MIN_CYCLE_US;

#[path = "../common/mod.rs"]
mod common;

use common::served::Served;
use common::{interop_python, met, run_script, Script};

/// The harness's reads.
const READS: u32 = 20_000;
/// python-canopen's (slower: fewer, for the same bounded time).
const PEER_READS: u32 = 2_000;
/// How much faster the harness must be.
const TARGET_RATIO: f64 = 5.0;
/// Process-data cycles timed (5 s at 5 ms).
const PDO_CYCLES: u32 = 1000;
/// How far from its period 98 % of the SYNC intervals may be, µs (a tenth of 5 ms).
const JITTER_TARGET_US: u64 = 500;

fn main() {
    let addr = SocketAddr::from(([127, 0, 0, 1], free_port()));
    let listen = addr.to_string();
    let args = [
        "--socketcand",
        &listen,
        "--profile",
        "sk550p",
        "--seconds",
        "120",
    ];
    let (server, _) = Served::start(Command::new(env!("CARGO_BIN_EXE_harness")), "can", &args)
        .expect("harness serve can starts");
    let ours = can_bench::sdo_reads(addr, "can0", READS);
    match &ours {
        Ok(r) => println!("harness SDO client: {}", r.show("complete SDO reads")),
        Err(e) => println!("harness SDO client: ERROR {e}"),
    }
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/interop/canopen_bench.py");
    let args = [
        addr.ip().to_string(),
        addr.port().to_string(),
        "can0".to_string(),
        PEER_READS.to_string(),
    ];
    let python = interop_python();
    match run_script(
        python.as_deref(),
        &script,
        &args,
        "canopen",
        Duration::from_secs(60),
    ) {
        Script::Ran(v) => {
            let peer = Rate {
                count: v["reads"].as_u64().unwrap_or(0),
                secs: v["secs"].as_f64().unwrap_or(0.0),
            };
            println!("python-canopen:     {}", peer.show("complete SDO reads"));
            if let (Ok(r), true) = (&ours, peer.per_sec() > 0.0) {
                let ratio = r.per_sec() / peer.per_sec();
                println!(
                    "harness / python-canopen: {ratio:.1}× (target ≥ {TARGET_RATIO}×: {})",
                    met(ratio >= TARGET_RATIO)
                );
            }
        }
        Script::Skipped(why) => println!("python-canopen: skipped ({why})"),
        Script::Failed(why) => println!("python-canopen: ERROR {why}"),
    }
    // Process data in the bus interface's place: FI 2's PDOs and a SYNC per cycle, the SYNCs
    // timed by a second client of the bus.
    match can_bench::pdo_cycles(addr, "can0", PDO_CYCLES) {
        Ok(j) => {
            let period = j.period.as_micros() as u64;
            let p99 = j
                .quantile(0.99)
                .abs_diff(period)
                .max(j.quantile(0.01).abs_diff(period));
            println!(
                "PDO cycle of the harness at {} ms, {} SYNC intervals seen by another client: \
                 median {} µs, 1st–99th percentile {}–{} µs, worst deviation {} µs \
                 (target: 98 % within {} µs of the period: {})",
                period / 1000,
                j.intervals_us.len(),
                j.quantile(0.5),
                j.quantile(0.01),
                j.quantile(0.99),
                j.worst_us(),
                JITTER_TARGET_US,
                met(p99 <= JITTER_TARGET_US)
            );
        }
        Err(e) => println!("PDO cycle: ERROR {e}"),
    }
    // The SK TU3-EIP's table (BU 2100 §4.3) gives the update cycle per number of inverters;
    // the other products only "≥ 5 ms".
    let table = match proto::nord::can::update_cycle(proto::nord::Product::Tu3Eip, 8) {
        Ok(proto::nord::can::UpdateCycle::Table(us)) => us,
        _ => MIN_CYCLE_US,
    };
    for series in [
        proto::nord::can::InverterSeries::Sk2xxe,
        proto::nord::can::InverterSeries::Sk5x0p,
    ] {
        let us = proto::nord::can::cycle_bus_time_us(series, 8);
        println!(
            "bus time of one process-data cycle of 8 {series:?} at 250 kBaud: at most {us} µs; \
             fits the 8-inverter update cycle of BU 2100's table ({} ms): {}; fits 5 ms: {}",
            f64::from(table) / 1000.0,
            met(us <= table),
            met(us <= MIN_CYCLE_US)
        );
    }
    drop(server);
}

/// A port nobody listens on now.
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .unwrap_or(29536)
}
