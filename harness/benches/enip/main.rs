//! EtherNet/IP speed over loopback: `cargo bench -p harness --bench enip`.
//!
//! One run serves the simulator inside this process (the threads of `harness serve enip`,
//! through `harness::enip_bench::serve`) and prints, one line per figure with its target and
//! whether it was met:
//!
//! - explicit-message round trips per second of the harness scanner (one client, P102 of FI 1
//!   read with Get_Attribute_Single, class 101 instance 0 attribute 102), and of the bench's
//!   own minimal client (encode, send, receive, decode: what the simulator and loopback allow):
//!   **one operation is one complete parameter read**, the request sent and the reply with
//!   the value and CIP status 0 received (EtherNet/IP answers a parameter read in one
//!   exchange; another status ends the figure with an error);
//! - the same for pycomm3 (a subprocess in the interop venv) and the ratio of the two;
//! - the simulator's Get_Attribute_Single throughput with 8 concurrent harness scanners;
//! - the arrival jitter of a class-1 Exclusive Owner connection (SK 550P assemblies 100/101,
//!   96 bytes each way) at RPI 1 ms: p50, p99 and maximum of |interval − RPI|, frames lost;
//! - a good client's request latency (p50, p99) and rate with 8,000 idle TCP connections open
//!   to the adapter, next to the same without them, and the process's thread count both ways
//!   (the adapter serves every TCP client from one event loop: no thread per connection).
//!
//! `cargo bench -p harness --bench enip -- WORD…` runs only the figures named: `round-trips`,
//! `concurrent`, `io`, `idle`.
//!
//! The scanner, the minimal client and the served adapter poll their sockets for a few tens
//! of µs before sleeping (`harness::poll`); pycomm3 gets the same adapter.
//!
//! A bench, not a timed test: everything runs on loopback and is bounded in count and time,
//! and nothing asserts on time; a missed target is printed, not failed. About 20 s. The I/O
//! connection is the bench's own (the minimal client's Forward_Open, O→T from one thread every
//! RPI, T→O received on another), and each T→O datagram's arrival time is the kernel's receive
//! stamp (SO_TIMESTAMPNS), not the moment a thread got round to reading it.

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::PathBuf;
use std::time::Duration;

use harness::enip_bench::{self, ParamReader};
use harness::stats::{median, Rate};
use proto::enip::epath::EPath;
use proto::nord::eip;
use proto::nord::{Inverter, ParamNumber, Product};
use sim::device::DeviceConfig;

#[path = "../common/mod.rs"]
mod common;
mod idle;
mod io;

use common::enip_client::Client;
use common::{concurrent, met, run_script, Script};
use io::io_jitter;

/// The scanner must make at least this many round trips per pycomm3 round trip.
const TARGET_RATIO: f64 = 5.0;
/// Get_Attribute_Single per second the simulator must answer with concurrent clients.
const TARGET_THROUGHPUT: f64 = 20_000.0;
/// The p99 of |interval − RPI| of T→O arrivals must stay below this.
const TARGET_P99: Duration = Duration::from_micros(200);
/// The product served: SK 550P, assemblies 100 (O→T) and 101 (T→O), 96 bytes each.
const PRODUCT: Product = Product::Sk550p;
/// The parameter read: P102 (BU 0620 §2.3.5: class 100 + FI, instance 0 = set 1).
const PARAM: u16 = 102;
/// Requests each client makes before it is timed.
const WARM_UP: u32 = 100;

fn main() {
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/interop/pycomm3_bench.py");
    let settings = Settings::new(script);
    if let Err(e) = run(&settings) {
        eprintln!("EtherNet/IP bench could not run: {e}");
        std::process::exit(1);
    }
}

/// What to measure, and the bounds of each figure.
#[derive(Debug, Clone)]
struct Settings {
    /// Where the simulator is served (TCP and UDP; class-1 I/O on UDP 2222 of the same IP).
    /// Not 127.0.0.1: the clients' end of a loopback connection is 127.0.0.1, and the T→O data
    /// arrives on its UDP 2222.
    listen: SocketAddr,
    /// Rounds of the single-client figures (scanner, minimal client, pycomm3 in turn).
    rounds: u32,
    /// Round trips of a single-client figure, at most.
    requests: u32,
    /// Time limit of each round-trip figure.
    limit: Duration,
    /// Concurrent harness scanners of the throughput figure.
    clients: usize,
    /// Requests per concurrent client, at most.
    per_client: u32,
    /// RPI of the I/O connection.
    rpi: Duration,
    /// How long T→O arrivals are recorded.
    record: Duration,
    /// The interop venv's Python, when it exists.
    python: Option<PathBuf>,
    /// `tests/interop/pycomm3_bench.py`.
    script: PathBuf,
    /// Idle TCP connections of the idle-clients figure.
    idle: usize,
    /// The figures to run (all when empty).
    only: Vec<String>,
}

impl Settings {
    /// The figures: 3 rounds of 20,000 round trips or 2 s per client figure, 8 clients
    /// × 5,000, 10 s of I/O at RPI 1 ms, 8,000 idle connections; Python from
    /// `${INTEROP_VENV:-target/interop-venv}`; the figures named on the command line.
    fn new(script: PathBuf) -> Settings {
        Settings {
            listen: SocketAddr::new(IpAddr::V4(Ipv4Addr::new(127, 0, 0, 5)), 44818),
            rounds: 3,
            requests: 20_000,
            limit: Duration::from_secs(2),
            clients: 8,
            per_client: 5_000,
            rpi: Duration::from_millis(1),
            record: Duration::from_secs(10),
            python: common::interop_python(),
            script,
            idle: 8_000,
            only: std::env::args()
                .skip(1)
                .filter(|a| !a.starts_with('-'))
                .collect(),
        }
    }

    /// Whether figure `key` runs.
    fn runs(&self, key: &str) -> bool {
        self.only.is_empty() || self.only.iter().any(|o| o == key)
    }
}

/// Serves the simulator and prints every figure. An error means the bench could not run at
/// all (the listen address is taken, say); a figure that fails prints why and the rest go on.
fn run(s: &Settings) -> Result<(), String> {
    let served = enip_bench::serve(s.listen, DeviceConfig::new(PRODUCT))?;
    println!(
        "EtherNet/IP bench: simulated {} served on {} (I/O on {}), loopback",
        PRODUCT.name(),
        served.listen,
        served.io
    );

    if s.runs("round-trips") {
        single_client(s);
    }
    if s.runs("concurrent") {
        concurrent_clients(s);
    }
    if s.runs("io") {
        io(s);
    }
    if s.runs("idle") {
        idle_clients(s)?;
    }
    Ok(())
}

/// A good client's latency without and with `s.idle` idle TCP connections open.
fn idle_clients(s: &Settings) -> Result<(), String> {
    let what = format!(
        "good client (bench's minimal client), {} idle TCP connections open",
        s.idle
    );
    match idle::idle_clients(s, &param_path()?) {
        Ok(f) => println!(
            "{what}: {}; without them: {}; threads of the serving process: {} with, {} without (opened in {:.1} s)",
            f.with.show(),
            f.without.show(),
            f.threads_with,
            f.threads_without,
            f.opening.as_secs_f64()
        ),
        Err(e) => println!("{what}: failed ({e})"),
    }
    Ok(())
}

/// The single-client figures in interleaved rounds, so that a burst of load elsewhere on the
/// machine falls on every client alike; each figure is the median of its rounds.
fn single_client(s: &Settings) {
    let mut scanner = Vec::new();
    let mut minimal = Vec::new();
    let mut pycomm3 = Vec::new();
    let mut pycomm3_client = None;
    for round in 1..=s.rounds {
        let mut line = format!("round {round}/{}:", s.rounds);
        match scanner_round_trips(s, 1, s.requests) {
            Ok(r) => {
                line += &format!(" harness scanner {:.0}/s", r.per_sec());
                scanner.push(r.per_sec());
            }
            Err(e) => line += &format!(" harness scanner failed ({e})"),
        }
        // What the simulator and loopback allow one client, for comparison: a client that
        // does nothing but encode and decode.
        match minimal_round_trips(s, 1, s.requests) {
            Ok(r) => {
                line += &format!(", bench's minimal client {:.0}/s", r.per_sec());
                minimal.push(r.per_sec());
            }
            Err(e) => line += &format!(", bench's minimal client failed ({e})"),
        }
        match pycomm3_round_trips(s) {
            Pycomm3::Skipped(why) => line += &format!(", pycomm3 skipped ({why})"),
            Pycomm3::Failed(why) => line += &format!(", pycomm3 failed ({why})"),
            Pycomm3::Ran { client, rate } => {
                line += &format!(", {client} {:.0}/s", rate.per_sec());
                pycomm3.push(rate.per_sec());
                pycomm3_client = Some(client);
            }
        }
        println!("{line}");
    }
    let (scanner, minimal, pycomm3) = (median(scanner), median(minimal), median(pycomm3));
    let show = |what: &str, rate: Option<f64>| match rate {
        Some(r) => println!("{what}, 1 client, median of the rounds: {r:.0} round trips/s"),
        None => println!("{what}, 1 client: no round completed"),
    };
    show("harness scanner", scanner);
    show("bench's minimal client", minimal);
    if let Some(client) = &pycomm3_client {
        show(client, pycomm3);
    }
    if let (Some(sc), Some(py)) = (scanner, pycomm3) {
        let ratio = sc / py;
        print!(
            "harness scanner / pycomm3: {ratio:.1}x (target >= {TARGET_RATIO}x: {})",
            met(ratio >= TARGET_RATIO)
        );
        if let Some(m) = minimal {
            print!("; bench's minimal client / pycomm3: {:.1}x", m / py);
        }
        println!();
    }
}

/// The simulator's throughput with concurrent harness scanners.
fn concurrent_clients(s: &Settings) {
    match scanner_round_trips(s, s.clients, s.per_client) {
        Ok(r) => println!(
            "simulator, {} concurrent harness scanners: {} (target >= {TARGET_THROUGHPUT:.0}/s: {})",
            s.clients,
            r.show("Get_Attribute_Single"),
            met(r.per_sec() >= TARGET_THROUGHPUT)
        ),
        Err(e) => println!(
            "simulator, {} concurrent harness scanners: failed ({e})",
            s.clients
        ),
    }
}

/// The jitter of a class-1 connection's T→O frames.
fn io(s: &Settings) {
    let what = format!(
        "I/O, 96-byte Exclusive Owner at RPI {} µs for {} s",
        s.rpi.as_micros(),
        s.record.as_secs_f64()
    );
    match io_jitter(s) {
        Ok(j) => println!(
            "{what}: {} T→O frames ({} due), {} lost, {} out of order; |interval − RPI| p50 {} µs, p99 {} µs, max {} µs (target p99 < {} µs: {})",
            j.frames,
            s.record.as_micros() / s.rpi.as_micros().max(1),
            j.lost,
            j.disordered,
            j.p50.as_micros(),
            j.p99.as_micros(),
            j.max.as_micros(),
            TARGET_P99.as_micros(),
            met(j.p99 < TARGET_P99)
        ),
        Err(e) => println!("{what}: failed ({e})"),
    }
}

/// Round trips of `clients` harness scanners at once, each reading P102 of FI 1 on its own
/// connection and session as a suite's `read` step does, after a short warm-up.
fn scanner_round_trips(s: &Settings, clients: usize, per_client: u32) -> Result<Rate, String> {
    let fi = Inverter::new(1).map_err(|e| e.to_string())?;
    let number = ParamNumber::new(i64::from(PARAM)).map_err(|e| e.to_string())?;
    let connect = || -> Result<ParamReader, String> {
        let mut reader =
            ParamReader::connect(s.listen, PRODUCT, fi, number, Duration::from_secs(2))?;
        for _ in 0..WARM_UP {
            reader.read()?;
        }
        Ok(reader)
    };
    concurrent(clients, per_client, s.limit, connect, ParamReader::read)
}

/// Round trips of `clients` of the bench's minimal client at once (Get_Attribute_Single of
/// P102 FI 1), after a short warm-up.
fn minimal_round_trips(s: &Settings, clients: usize, per_client: u32) -> Result<Rate, String> {
    let path = param_path()?;
    let connect = || -> Result<Client, String> {
        let mut c = Client::connect(s.listen)?;
        for _ in 0..WARM_UP {
            c.get(&path)?;
        }
        Ok(c)
    };
    concurrent(clients, per_client, s.limit, connect, |c| {
        c.get(&path).map(drop)
    })
}

/// What pycomm3 did.
enum Pycomm3 {
    Skipped(String),
    Failed(String),
    Ran { client: String, rate: Rate },
}

/// pycomm3's round trips: `pycomm3_bench.py` in the interop venv, one JSON line back.
fn pycomm3_round_trips(s: &Settings) -> Pycomm3 {
    let args = [
        "--host".to_string(),
        s.listen.ip().to_string(),
        "--port".into(),
        s.listen.port().to_string(),
        "--count".into(),
        s.requests.to_string(),
        "--seconds".into(),
        s.limit.as_secs_f64().to_string(),
    ];
    let v = match run_script(s.python.as_deref(), &s.script, &args, "pycomm3", s.limit) {
        Script::Skipped(why) => return Pycomm3::Skipped(why),
        Script::Failed(why) => return Pycomm3::Failed(why),
        Script::Ran(v) => v,
    };
    match (
        v.get("count").and_then(serde_json::Value::as_u64),
        v.get("seconds").and_then(serde_json::Value::as_f64),
    ) {
        (Some(count), Some(secs)) if count > 0 => Pycomm3::Ran {
            client: v
                .get("client")
                .and_then(serde_json::Value::as_str)
                .unwrap_or("pycomm3")
                .to_string(),
            rate: Rate { count, secs },
        },
        _ => Pycomm3::Failed(format!("unexpected reply from pycomm3_bench.py: {v}")),
    }
}

/// Class 101, instance 0, attribute 102: P102 of FI 1, set 1.
fn param_path() -> Result<EPath, String> {
    let fi = Inverter::new(1).map_err(|e| e.to_string())?;
    Ok(EPath::attribute(eip::param_class(Some(fi)), 0, PARAM))
}
