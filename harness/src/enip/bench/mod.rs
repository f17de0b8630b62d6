//! EtherNet/IP speed over loopback, for `cargo bench -p harness --bench enip`.
//!
//! One run serves the simulator inside this process (the threads of `harness serve enip`) and
//! prints, one line per figure with its target and whether it was met:
//!
//! - explicit-message round trips per second of the harness scanner (one client, P102 of FI 1
//!   read with Get_Attribute_Single, class 101 instance 0 attribute 102), and of the bench's
//!   own minimal client (encode, send, receive, decode: what the simulator and loopback allow);
//! - the same for pycomm3 (a subprocess in the interop venv) and the ratio of the two;
//! - the simulator's Get_Attribute_Single throughput with 8 concurrent harness scanners;
//! - the arrival jitter of a class-1 Exclusive Owner connection (SK 550P assemblies 100/101,
//!   96 bytes each way) at RPI 1 ms: p50, p99 and maximum of |interval − RPI|, frames lost.
//!
//! The scanner, the minimal client and the served adapter poll their sockets for a few tens
//! of µs before sleeping (`crate::poll`); pycomm3 gets the same adapter.
//!
//! Everything runs on loopback and is bounded in count and time. Nothing here asserts on time:
//! a missed target is printed, not failed. The I/O connection is the bench's own (the minimal
//! client's Forward_Open, O→T from one thread every RPI, T→O received on another), and each
//! T→O datagram's arrival time is the kernel's receive stamp (SO_TIMESTAMPNS), not the moment
//! a thread got round to reading it.

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::Barrier;
use std::thread;
use std::time::{Duration, Instant};

use proto::enip::epath::EPath;
use proto::nord::eip;
use proto::nord::{Inverter, ParamNumber, Product};
use sim::device::DeviceConfig;

mod client;
mod io;

use client::Client;
use io::io_jitter;

use super::Scanner;
use crate::binding::Binding;
use crate::suite::{Action, OrderSpec, Target};

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
/// Originator vendor id and serial number of the bench's own Forward_Open.
const VENDOR: u16 = 0x4E48;
const ORIGINATOR_SERIAL: u32 = 0x4E48_4245;
/// Requests each client makes before it is timed.
const WARM_UP: u32 = 100;
/// Timeout multiplier of the I/O connection: ×64, so an O→T frame that a busy host sends a
/// few RPIs late does not end the measurement; the jitter measured is the T→O side.
const IO_MULTIPLIER: u8 = 4;

/// What to measure, and the bounds of each figure.
#[derive(Debug, Clone)]
pub struct Settings {
    /// Where the simulator is served (TCP and UDP; class-1 I/O on UDP 2222 of the same IP).
    /// Not 127.0.0.1: the clients' end of a loopback connection is 127.0.0.1, and the T→O data
    /// arrives on its UDP 2222.
    pub listen: SocketAddr,
    /// Rounds of the single-client figures (scanner, minimal client, pycomm3 in turn).
    pub rounds: u32,
    /// Round trips of a single-client figure, at most.
    pub requests: u32,
    /// Time limit of each round-trip figure.
    pub limit: Duration,
    /// Concurrent harness scanners of the throughput figure.
    pub clients: usize,
    /// Requests per concurrent client, at most.
    pub per_client: u32,
    /// RPI of the I/O connection.
    pub rpi: Duration,
    /// How long T→O arrivals are recorded.
    pub record: Duration,
    /// The interop venv's Python, when it exists.
    pub python: Option<PathBuf>,
    /// `tests/interop/pycomm3_bench.py`.
    pub script: PathBuf,
}

impl Settings {
    /// The figures: 3 rounds of 20,000 round trips or 2 s per client figure, 8 clients × 5,000,
    /// 10 s of I/O at RPI 1 ms; Python from `${INTEROP_VENV:-/tmp/nord-interop-venv}`.
    pub fn new(script: PathBuf) -> Settings {
        let venv =
            std::env::var("INTEROP_VENV").unwrap_or_else(|_| "/tmp/nord-interop-venv".into());
        let python = Path::new(&venv).join("bin/python");
        Settings {
            listen: SocketAddr::new(IpAddr::V4(Ipv4Addr::new(127, 0, 0, 5)), 44818),
            rounds: 3,
            requests: 20_000,
            limit: Duration::from_secs(2),
            clients: 8,
            per_client: 5_000,
            rpi: Duration::from_millis(1),
            record: Duration::from_secs(10),
            python: python.exists().then_some(python),
            script,
        }
    }
}

/// Serves the simulator and prints every figure. An error means the bench could not run at
/// all (the listen address is taken, say); a figure that fails prints why and the rest go on.
pub fn run_enip(s: &Settings) -> Result<(), String> {
    let served = super::serve::start_enip(s.listen, DeviceConfig::new(PRODUCT))?;
    println!(
        "EtherNet/IP bench: simulated {} served on {} (I/O on {}), loopback",
        PRODUCT.name(),
        served.listen,
        served.io
    );

    // The single-client figures in interleaved rounds, so that a burst of load elsewhere on
    // the machine falls on every client alike; each figure is the median of its rounds.
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
    Ok(())
}

/// The median of `values` (the mean of the middle two of an even count); `None` when empty.
fn median(mut values: Vec<f64>) -> Option<f64> {
    values.sort_by(f64::total_cmp);
    let n = values.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(values[n / 2]),
        _ => Some((values[n / 2 - 1] + values[n / 2]) / 2.0),
    }
}

fn met(ok: bool) -> &'static str {
    if ok {
        "met"
    } else {
        "NOT met"
    }
}

/// A count over a time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Rate {
    count: u64,
    secs: f64,
}

impl Rate {
    /// `20000 round trips in 0.812 s = 24631/s`.
    fn show(&self, what: &str) -> String {
        format!(
            "{} {what} in {:.3} s = {:.0}/s",
            self.count,
            self.secs,
            self.per_sec()
        )
    }

    fn per_sec(&self) -> f64 {
        if self.secs > 0.0 {
            self.count as f64 / self.secs
        } else {
            0.0
        }
    }
}

/// Round trips of `clients` harness scanners at once, each `perform(Read P102 FI 1)` on its own
/// connection and session, after a short warm-up.
fn scanner_round_trips(s: &Settings, clients: usize, per_client: u32) -> Result<Rate, String> {
    let read = Action::Read(OrderSpec {
        target: Target::Inverter(Inverter::new(1).map_err(|e| e.to_string())?),
        number: ParamNumber::new(i64::from(PARAM)).map_err(|e| e.to_string())?,
        set: None,
        element: None,
        ak: None,
        value: None,
        eeprom: true,
        dword: None,
    });
    let one = |scanner: &mut Scanner| -> Result<(), String> {
        let v = scanner.perform(&read).map_err(|e| format!("{e:?}"))?.fields;
        // The transcript of the step, as the runner takes it after each step.
        scanner.take_exchanges();
        match v.get("cip_status").and_then(serde_json::Value::as_u64) {
            Some(0) => Ok(()),
            _ => Err(format!("P{PARAM} read refused: {v}")),
        }
    };
    let connect = || -> Result<Scanner, String> {
        let mut scanner = Scanner::network(s.listen, None, Some(PRODUCT), Duration::from_secs(2))?;
        for _ in 0..WARM_UP {
            one(&mut scanner)?;
        }
        Ok(scanner)
    };
    concurrent(clients, per_client, s.limit, connect, one)
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

/// Aggregate rate of `clients` threads, each with its own client from `connect` (made in the
/// thread: a scanner stays on the thread that made it), all started together, each doing
/// `one` up to `per_client` times within `limit`. The first error of any thread is returned.
fn concurrent<C>(
    clients: usize,
    per_client: u32,
    limit: Duration,
    connect: impl Fn() -> Result<C, String> + Sync,
    one: impl Fn(&mut C) -> Result<(), String> + Sync,
) -> Result<Rate, String> {
    let go = Barrier::new(clients + 1);
    thread::scope(|scope| {
        let threads: Vec<_> = (0..clients)
            .map(|_| {
                scope.spawn(|| -> Result<(u64, Instant), String> {
                    let client = connect();
                    // Every thread reaches the barrier, even one that could not connect.
                    go.wait();
                    let mut client = client?;
                    let start = Instant::now();
                    let mut n = 0u64;
                    while n < u64::from(per_client) && start.elapsed() < limit {
                        one(&mut client)?;
                        n += 1;
                    }
                    // Ended before the client is dropped (its session closed).
                    Ok((n, Instant::now()))
                })
            })
            .collect();
        go.wait();
        let start = Instant::now();
        let mut count = 0;
        let mut end = start;
        let mut error = None;
        for t in threads {
            match t.join() {
                Ok(Ok((n, at))) => {
                    count += n;
                    end = end.max(at);
                }
                Ok(Err(e)) => {
                    error.get_or_insert(e);
                }
                Err(_) => {
                    error.get_or_insert("a client thread panicked".into());
                }
            }
        }
        match error {
            Some(e) => Err(e),
            None => Ok(Rate {
                count,
                secs: (end - start).as_secs_f64(),
            }),
        }
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
    let Some(python) = &s.python else {
        return Pycomm3::Skipped(
            "no interop venv at ${INTEROP_VENV:-/tmp/nord-interop-venv}; run `bash .ci/interop-setup`"
                .into(),
        );
    };
    let child = Command::new(python)
        .arg(&s.script)
        .args(["--host", &s.listen.ip().to_string()])
        .args(["--port", &s.listen.port().to_string()])
        .args(["--count", &s.requests.to_string()])
        .args(["--seconds", &s.limit.as_secs_f64().to_string()])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn();
    let mut child = match child {
        Ok(c) => c,
        Err(e) => return Pycomm3::Failed(format!("cannot run {}: {e}", python.display())),
    };
    // Python's start and pycomm3's import on top of the measured time.
    let deadline = Instant::now() + s.limit + Duration::from_secs(30);
    loop {
        match child.try_wait() {
            Ok(Some(_)) => break,
            Ok(None) if Instant::now() < deadline => thread::sleep(Duration::from_millis(20)),
            Ok(None) => {
                let _ = child.kill();
                let _ = child.wait();
                return Pycomm3::Failed("pycomm3_bench.py overran its time limit".into());
            }
            Err(e) => return Pycomm3::Failed(e.to_string()),
        }
    }
    let out = match child.wait_with_output() {
        Ok(o) => o,
        Err(e) => return Pycomm3::Failed(e.to_string()),
    };
    let stderr = String::from_utf8_lossy(&out.stderr).trim().to_string();
    match out.status.code() {
        Some(0) => {}
        Some(3) => return Pycomm3::Skipped(format!("pycomm3 not importable: {stderr}")),
        _ => return Pycomm3::Failed(format!("pycomm3_bench.py {}: {stderr}", out.status)),
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let Some(v) = stdout
        .lines()
        .rev()
        .find_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
    else {
        return Pycomm3::Failed(format!("no JSON line from pycomm3_bench.py: {stdout}"));
    };
    if let Some(e) = v.get("error").and_then(serde_json::Value::as_str) {
        return Pycomm3::Failed(e.to_string());
    }
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

#[cfg(test)]
mod tests {
    use super::median;

    #[test]
    fn median_of_odd_even_and_no_rounds() {
        assert_eq!(median(vec![3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(vec![4.0, 1.0, 3.0, 2.0]), Some(2.5));
        assert_eq!(median(Vec::new()), None);
    }
}
