//! System-bus speed over loopback: `cargo bench -p harness --bench can` (`-- sdo pdo load`
//! picks figures; all by default).
//!
//! One run serves the simulated SK 550P's system bus with the built `harness serve can
//! --socketcand` (a process of its own, as a socketcand server on a test bench would be) and
//! prints, one line per figure with its target and whether it was met:
//!
//! - SDO reads of the harness's own SDO client: **one operation is one complete SDO read** of
//!   P102 set 1 of FI 3 (node 36, 2066h:01h, expedited), the upload request sent and the
//!   node's answer with the value received, one after the other; and python-canopen's, the
//!   same operation against the same server in the same rounds (`tests/interop/canopen_bench.py`
//!   in the interop venv; said and skipped without it); target: the harness at least 5 times
//!   as fast. Beside them, in the same rounds, the floor both stand on (`floor.rs`: a minimal
//!   client and a trivial server exchanging the same two socketcand messages over TCP
//!   loopback) and what each part costs above it: the served segment (the minimal client
//!   against `harness serve can`) and each SDO client (against the trivial server). Each
//!   figure is the median of [`ROUNDS`] interleaved rounds, in µs a read and reads a second;
//! - the jitter of the harness's process-data cycle at 5 ms (FI 2's RPDOs and a SYNC per
//!   cycle, over socketcand): the SYNC intervals a second client of the bus sees, median,
//!   1st–99th percentile and worst, against a target of 98 % within 0.5 ms of the period;
//! - the bus time one process-data cycle of 8 inverters takes at 250 kBaud at the most
//!   (`proto::nord::can::cycle_bus_time_us`: SYNC, each inverter's RPDOs and TPDOs at their
//!   worst-case stuffed length), against the 8-inverter update cycle of BU 2100's table and
//!   the 5 ms the manuals allow at least: the physical floor the simulator must respect.
//!
//! A bench, not a timed test: bounded in count and time (about 25 s), nothing asserts on
//! time, a missed target is printed, not failed.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Duration;

use harness::can_bench::{self, Reads};
use harness::stats::{median, Rate};
use proto::nord::can::MIN_CYCLE_US;

#[path = "../common/mod.rs"]
mod common;
mod floor;

use common::served::Served;
use common::{interop_python, met, run_script, Script};

/// Rounds of the SDO figures, interleaved (the machine's load moves between them).
const ROUNDS: usize = 7;
/// The harness's reads, and the minimal client's, a round.
const READS: u32 = 5_000;
/// python-canopen's (slower: fewer, for the same bounded time).
const PEER_READS: u32 = 1_000;
/// How much faster the harness must be.
const TARGET_RATIO: f64 = 5.0;
/// Process-data cycles timed (5 s at 5 ms).
const PDO_CYCLES: u32 = 1000;
/// How far from its period 98 % of the SYNC intervals may be, µs (a tenth of 5 ms).
const JITTER_TARGET_US: u64 = 500;

fn main() {
    let only: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let runs = |key: &str| only.is_empty() || only.iter().any(|o| o == key);
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
    if runs("sdo") {
        sdo_reads(addr);
    }
    if runs("pdo") {
        pdo_jitter(addr);
    }
    if runs("load") {
        bus_load();
    }
    drop(server);
}

/// One SDO figure: a client against a server, round after round.
struct Figure {
    what: &'static str,
    /// Each round's rate.
    rounds: Vec<Rate>,
    /// Every read's time of every round, µs.
    each_us: Vec<f64>,
    error: Option<String>,
}

impl Figure {
    fn new(what: &'static str) -> Figure {
        Figure {
            what,
            rounds: Vec::new(),
            each_us: Vec::new(),
            error: None,
        }
    }

    fn add(&mut self, r: Result<Reads, String>) {
        match r {
            Ok(r) if r.rate.count > 0 => {
                self.rounds.push(r.rate);
                self.each_us.extend(r.each_us);
            }
            Ok(_) => {
                self.error.get_or_insert("no reads".into());
            }
            Err(e) => {
                self.error.get_or_insert(e);
            }
        }
    }

    /// The median time of one read over all rounds, µs: what a read costs when the machine's
    /// other work does not get in its way (a read that waits for a core is slower, not more
    /// frequent).
    fn p50(&self) -> Option<f64> {
        median(self.each_us.clone())
    }

    /// The median of the rounds' rates, reads a second.
    fn rate(&self) -> Option<f64> {
        median(self.rounds.iter().map(Rate::per_sec).collect())
    }

    /// `p50 12.3 µs a read, 61,020/s (rounds: 14.1 16.4 19.0 µs a read)`, or why there is no
    /// figure.
    fn show(&self, floor: Option<f64>) -> String {
        let rounds: Vec<String> = self
            .rounds
            .iter()
            .map(|r| format!("{:.1}", 1e6 / r.per_sec()))
            .collect();
        match (self.p50(), self.rate(), &self.error) {
            (Some(p50), Some(rate), _) => {
                let above =
                    floor.map_or(String::new(), |f| format!(" = floor + {:.1} µs", p50 - f));
                format!(
                    "p50 {p50:.1} µs a read{above}; {rate:.0} reads/s (rounds: {} µs a read)",
                    rounds.join(" ")
                )
            }
            (_, _, Some(e)) => format!("ERROR {e}"),
            _ => "no figure".into(),
        }
    }
}

/// python-canopen's reads against `addr`: `None` when it cannot run here (said once).
fn canopen_reads(
    python: Option<&Path>,
    script: &Path,
    addr: SocketAddr,
) -> Option<Result<Reads, String>> {
    let args = [
        addr.ip().to_string(),
        addr.port().to_string(),
        "can0".to_string(),
        PEER_READS.to_string(),
    ];
    match run_script(python, script, &args, "canopen", Duration::from_secs(60)) {
        Script::Ran(v) => Some(Ok(Reads {
            rate: Rate {
                count: v["reads"].as_u64().unwrap_or(0),
                secs: v["secs"].as_f64().unwrap_or(0.0),
            },
            each_us: v["us"]
                .as_array()
                .map(|a| a.iter().filter_map(serde_json::Value::as_f64).collect())
                .unwrap_or_default(),
        })),
        Script::Skipped(why) => {
            println!("python-canopen: skipped ({why})");
            None
        }
        Script::Failed(why) => Some(Err(why)),
    }
}

/// The SDO figures: [`ROUNDS`] rounds of the floor, the served segment above it, each client
/// above it, and each client against the served segment.
fn sdo_reads(served: SocketAddr) {
    let trivial = match floor::trivial_server() {
        Ok(a) => a,
        Err(e) => {
            println!("SDO reads: ERROR cannot start the trivial server: {e}");
            return;
        }
    };
    let script: PathBuf =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/interop/canopen_bench.py");
    let python = interop_python();
    let mut python_runs = true;
    let mut floor = Figure::new("floor: minimal client, trivial server");
    let mut server = Figure::new("minimal client, served segment");
    let mut ours_trivial = Figure::new("harness SDO client, trivial server");
    let mut ours = Figure::new("harness SDO client, served segment");
    let mut peer_trivial = Figure::new("python-canopen, trivial server");
    let mut peer = Figure::new("python-canopen, served segment");
    for _ in 0..ROUNDS {
        floor.add(floor::minimal_client(trivial, READS));
        server.add(floor::minimal_client(served, READS));
        ours_trivial.add(can_bench::sdo_reads(trivial, "can0", READS));
        ours.add(can_bench::sdo_reads(served, "can0", READS));
        if python_runs {
            match canopen_reads(python.as_deref(), &script, trivial) {
                Some(r) => peer_trivial.add(r),
                None => python_runs = false,
            }
        }
        if python_runs {
            if let Some(r) = canopen_reads(python.as_deref(), &script, served) {
                peer.add(r);
            }
        }
    }
    println!(
        "complete SDO reads of P102 at node 36 (2066h:01h) over socketcand on loopback, \
         {ROUNDS} rounds interleaved: the median time of a read over all rounds (p50), and \
         reads a second, median of the rounds"
    );
    let f = floor.p50();
    println!("  {}: {}", floor.what, floor.show(None));
    for fig in [&server, &ours_trivial, &ours, &peer_trivial, &peer] {
        if python_runs || !fig.what.starts_with("python") {
            println!("  {}: {}", fig.what, fig.show(f));
        }
    }
    if let (Some(o), Some(p)) = (ours.rate(), peer.rate()) {
        let ratio = o / p;
        println!(
            "harness / python-canopen, reads a second: {ratio:.1}× (target ≥ {TARGET_RATIO}×: {})",
            met(ratio >= TARGET_RATIO)
        );
    }
    if let (Some(o), Some(p)) = (ours.p50(), peer.p50()) {
        let ratio = p / o;
        println!(
            "harness / python-canopen, p50 of a read: {ratio:.1}× (target ≥ {TARGET_RATIO}×: {})",
            met(ratio >= TARGET_RATIO)
        );
        if let (Some(f), Some(s)) = (f, server.p50()) {
            let parts = |trivial: &Figure| {
                trivial.p50().map_or(String::new(), |t| {
                    format!(": the server {:.1} µs, the client {:.1} µs", s - f, t - f)
                })
            };
            println!(
                "  above the floor of {f:.1} µs: the harness {:.1} µs{}; python-canopen {:.1} µs{}",
                o - f,
                parts(&ours_trivial),
                p - f,
                parts(&peer_trivial)
            );
        }
    }
}

fn pdo_jitter(addr: SocketAddr) {
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
}

fn bus_load() {
    // The SK TU3-EIP's table (BU 2100 §4.3) gives the update cycle per number of inverters;
    // the other products only "≥ 5 ms".
    let table = match proto::nord::can::update_cycle(proto::nord::Product::Tu3Eip, 8) {
        Ok(proto::nord::can::UpdateCycle::Table(us)) => us,
        _ => MIN_CYCLE_US.get(),
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
            met(us <= MIN_CYCLE_US.get())
        );
    }
}

/// A port nobody listens on now.
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .unwrap_or(29536)
}
