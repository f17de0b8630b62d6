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
//! Everything runs on loopback and is bounded in count and time. Nothing here asserts on time:
//! a missed target is printed, not failed. The I/O connection is the bench's own (the minimal
//! client's Forward_Open, O→T from one thread every RPI, T→O timed on another), so arrival
//! times are taken as the datagrams come, not once per scanner cycle.

use std::io::{Read, Write};
use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpStream, UdpSocket};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Barrier};
use std::thread;
use std::time::{Duration, Instant};

use proto::enip::cip::{class, MrRequest, MrResponse, Service};
use proto::enip::cm::{kind, ForwardClose, ForwardOpen, ForwardOpenReply, NetParams, Transport};
use proto::enip::cpf::{Cpf, Item};
use proto::enip::encap::{
    frame_len, Command as EncapCommand, EncapRepr, RegisterSession, SendData,
};
use proto::enip::epath::{EPath, Segment};
use proto::enip::io::{IoFrame, IO_PORT};
use proto::nord::eip::{self, Direction};
use proto::nord::{Inverter, ParamNumber, Product};
use sim::device::DeviceConfig;

use crate::binding::enip::Scanner;
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
    /// The figures: 20,000 round trips or 2 s per client figure, 8 clients × 5,000,
    /// 10 s of I/O at RPI 1 ms; Python from `${INTEROP_VENV:-/tmp/nord-interop-venv}`.
    pub fn new(script: PathBuf) -> Settings {
        let venv =
            std::env::var("INTEROP_VENV").unwrap_or_else(|_| "/tmp/nord-interop-venv".into());
        let python = Path::new(&venv).join("bin/python");
        Settings {
            listen: SocketAddr::new(IpAddr::V4(Ipv4Addr::new(127, 0, 0, 5)), 44818),
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
    let served = crate::serve::start_enip(s.listen, DeviceConfig::new(PRODUCT))?;
    println!(
        "EtherNet/IP bench: simulated {} served on {} (I/O on {}), loopback",
        PRODUCT.name(),
        served.listen,
        served.io
    );

    let scanner = scanner_round_trips(s, 1, s.requests);
    match &scanner {
        Ok(r) => println!("harness scanner, 1 client: {}", r.show("round trips")),
        Err(e) => println!("harness scanner, 1 client: failed ({e})"),
    }
    // What the simulator and loopback allow one client, for comparison: a client that does
    // nothing but encode and decode.
    let minimal = minimal_round_trips(s, 1, s.requests);
    match &minimal {
        Ok(r) => println!(
            "bench's minimal client, 1 client: {}",
            r.show("round trips")
        ),
        Err(e) => println!("bench's minimal client, 1 client: failed ({e})"),
    }

    match pycomm3_round_trips(s) {
        Pycomm3::Skipped(why) => println!("pycomm3: skipped ({why})"),
        Pycomm3::Failed(why) => println!("pycomm3: failed ({why})"),
        Pycomm3::Ran { client, rate } => {
            println!("{client}, 1 client: {}", rate.show("round trips"));
            if let Ok(sc) = &scanner {
                let ratio = sc.per_sec() / rate.per_sec();
                print!(
                    "harness scanner / pycomm3: {ratio:.1}x (target >= {TARGET_RATIO}x: {})",
                    met(ratio >= TARGET_RATIO)
                );
                if let Ok(m) = &minimal {
                    print!(
                        "; bench's minimal client / pycomm3: {:.1}x",
                        m.per_sec() / rate.per_sec()
                    );
                }
                println!();
            }
        }
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
        let v = scanner.perform(&read).map_err(|e| format!("{e:?}"))?;
        // The transcript of the step, as the runner takes it after each step.
        scanner.take_exchanges();
        match v.get("cip_status").and_then(serde_json::Value::as_u64) {
            Some(0) => Ok(()),
            _ => Err(format!("P{PARAM} read refused: {v}")),
        }
    };
    let connect = || -> Result<Scanner, String> {
        let mut scanner = Scanner::network(s.listen, Some(PRODUCT), Duration::from_secs(2))?;
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

/// T→O arrival jitter of an Exclusive Owner connection: O→T every RPI from one thread, T→O
/// arrival times recorded on this one.
fn io_jitter(s: &Settings) -> Result<Jitter, String> {
    let mut client = Client::connect(s.listen)?;
    let local = client.tcp.local_addr().map_err(|e| e.to_string())?.ip();
    // Bound before Forward_Open: the first T→O frame follows its reply at once.
    let udp = UdpSocket::bind(SocketAddr::new(local, IO_PORT))
        .map_err(|e| format!("cannot bind UDP {local}:{IO_PORT} for T→O data: {e}"))?;
    let out = eip::assemblies(PRODUCT)
        .iter()
        .filter(|a| a.direction == Direction::Output)
        .max_by_key(|a| a.len)
        .ok_or("no output assembly")?;
    let inp = eip::assembly(PRODUCT, out.instance + 1).ok_or("no input assembly")?;
    let run_idle = eip::o_t_run_idle(PRODUCT, out.instance, 0);
    let rpi_us = u32::try_from(s.rpi.as_micros()).map_err(|e| e.to_string())?;
    let conn = client.forward_open(
        out.instance,
        inp.instance,
        2 + if run_idle { 4 } else { 0 } + out.len,
        2 + inp.len,
        rpi_us,
    )?;

    let stop = Arc::new(AtomicBool::new(false));
    let sender = {
        let udp = udp.try_clone().map_err(|e| e.to_string())?;
        let stop = stop.clone();
        let to = SocketAddr::new(s.listen.ip(), IO_PORT);
        let (rpi, len, id) = (s.rpi, usize::from(out.len), conn.o_t_id);
        thread::spawn(move || -> Result<(), String> {
            let mut frame = IoFrame {
                connection: id,
                sequence: 0,
                count: 0,
                run_idle: run_idle.then_some(1),
                data: vec![0; len],
            };
            let mut due = Instant::now();
            while !stop.load(Ordering::Relaxed) {
                frame.sequence = frame.sequence.wrapping_add(1);
                frame.count = frame.count.wrapping_add(1);
                let bytes = frame.emit().map_err(|e| e.to_string())?;
                udp.send_to(&bytes, to)
                    .map_err(|e| format!("O→T send failed: {e}"))?;
                due += rpi;
                thread::sleep(due.saturating_duration_since(Instant::now()));
            }
            Ok(())
        })
    };

    let recorded = record_t_o(&udp, conn.t_o_id, s.record);
    stop.store(true, Ordering::Relaxed);
    let sent = sender
        .join()
        .map_err(|_| "the O→T thread panicked".to_string())?;
    client.forward_close(conn.serial)?;
    sent?;
    let arrivals = recorded?;
    jitter(&arrivals, s.rpi).ok_or_else(|| format!("only {} T→O frames", arrivals.len()))
}

/// (sequence, arrival time) of every T→O frame of connection `t_o_id` for `span` from the
/// first.
fn record_t_o(
    udp: &UdpSocket,
    t_o_id: u32,
    span: Duration,
) -> Result<Vec<(u32, Duration)>, String> {
    udp.set_read_timeout(Some(Duration::from_millis(100)))
        .map_err(|e| e.to_string())?;
    let mut buf = [0u8; 1500];
    let mut arrivals = Vec::with_capacity(span.as_millis() as usize + 64);
    let begin = Instant::now();
    let mut first: Option<Instant> = None;
    loop {
        let now = Instant::now();
        match first {
            Some(f) if now >= f + span => break,
            None if now >= begin + Duration::from_secs(1) => {
                return Err("no T→O frame within 1 s of Forward_Open".into())
            }
            _ => {}
        }
        match udp.recv_from(&mut buf) {
            Ok((n, _)) => {
                let at = Instant::now();
                let Ok(frame) = IoFrame::parse(&buf[..n], false) else {
                    continue;
                };
                if frame.connection != t_o_id {
                    continue;
                }
                let f = *first.get_or_insert(at);
                arrivals.push((frame.sequence, at - f));
            }
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                if first.is_some() {
                    return Err(format!(
                        "T→O stopped after {} frames (connection timed out?)",
                        arrivals.len()
                    ));
                }
            }
            Err(e) => return Err(format!("T→O receive failed: {e}")),
        }
    }
    Ok(arrivals)
}

/// How far the arrivals of a periodic stream stray from its period.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Jitter {
    /// Frames received.
    frames: usize,
    /// Frames missing by their sequence numbers.
    lost: u64,
    /// Frames whose sequence number did not advance (duplicates, reordering).
    disordered: u64,
    /// Median of |interval − period| over consecutive sequence numbers.
    p50: Duration,
    /// 99th percentile of the same.
    p99: Duration,
    /// The largest.
    max: Duration,
}

/// Jitter of `arrivals` ((sequence number, arrival time), in arrival order) against `period`.
/// Only intervals between consecutive sequence numbers count; a gap counts its missing frames
/// as lost. `None` without a single such interval.
pub(crate) fn jitter(arrivals: &[(u32, Duration)], period: Duration) -> Option<Jitter> {
    let (mut lost, mut disordered) = (0u64, 0u64);
    let mut deviations = Vec::with_capacity(arrivals.len());
    for pair in arrivals.windows(2) {
        let ((s0, t0), (s1, t1)) = (pair[0], pair[1]);
        match s1.wrapping_sub(s0) {
            1 => deviations.push(t1.saturating_sub(t0).abs_diff(period)),
            gap if gap > 1 && gap < 1 << 31 => lost += u64::from(gap - 1),
            _ => disordered += 1,
        }
    }
    deviations.sort_unstable();
    Some(Jitter {
        frames: arrivals.len(),
        lost,
        disordered,
        p50: percentile(&deviations, 50.0)?,
        p99: percentile(&deviations, 99.0)?,
        max: *deviations.last()?,
    })
}

/// The `p`th percentile (nearest rank) of ascending `sorted`; `None` when empty.
pub(crate) fn percentile(sorted: &[Duration], p: f64) -> Option<Duration> {
    if sorted.is_empty() {
        return None;
    }
    let rank = (p / 100.0 * sorted.len() as f64).ceil() as usize;
    sorted.get(rank.clamp(1, sorted.len()) - 1).copied()
}

/// The bench's minimal explicit client: one session, unconnected requests.
struct Client {
    tcp: TcpStream,
    session: u32,
    buf: Vec<u8>,
}

/// An open I/O connection, as the Forward_Open reply gave it.
struct IoConnection {
    o_t_id: u32,
    t_o_id: u32,
    serial: u16,
}

impl Client {
    fn connect(target: SocketAddr) -> Result<Client, String> {
        let tcp = TcpStream::connect_timeout(&target, Duration::from_secs(2))
            .map_err(|e| format!("cannot connect to {target}: {e}"))?;
        tcp.set_nodelay(true).map_err(|e| e.to_string())?;
        tcp.set_read_timeout(Some(Duration::from_secs(2)))
            .map_err(|e| e.to_string())?;
        let mut c = Client {
            tcp,
            session: 0,
            buf: Vec::new(),
        };
        let reply = c.exchange(&EncapRepr {
            command: EncapCommand::REGISTER_SESSION.0,
            data: RegisterSession::V1.emit(),
            ..EncapRepr::default()
        })?;
        if reply.status != 0 || reply.session == 0 {
            return Err(format!(
                "RegisterSession refused: status {:#x}",
                reply.status
            ));
        }
        c.session = reply.session;
        Ok(c)
    }

    /// One encapsulation message and its reply.
    fn exchange(&mut self, msg: &EncapRepr) -> Result<EncapRepr, String> {
        let bytes = msg.emit().map_err(|e| e.to_string())?;
        self.tcp
            .write_all(&bytes)
            .map_err(|e| format!("TCP send failed: {e}"))?;
        let mut chunk = [0u8; 4096];
        loop {
            if let Some(n) = frame_len(&self.buf).filter(|n| self.buf.len() >= *n) {
                let reply = EncapRepr::parse(&self.buf[..n]).map_err(|e| e.to_string());
                self.buf.drain(..n);
                return reply;
            }
            match self.tcp.read(&mut chunk) {
                Ok(0) => return Err("the simulator closed the TCP connection".into()),
                Ok(n) => self.buf.extend_from_slice(&chunk[..n]),
                Err(e) => return Err(format!("TCP receive failed: {e}")),
            }
        }
    }

    /// An unconnected request (SendRRData) and its message-router reply.
    fn request(&mut self, req: &MrRequest) -> Result<MrResponse, String> {
        let data = SendData {
            interface: 0,
            timeout: 0,
            cpf: Cpf::new(vec![Item::Null, Item::UnconnectedData(req.emit())]),
        }
        .emit()
        .map_err(|e| e.to_string())?;
        let reply = self.exchange(&EncapRepr {
            command: EncapCommand::SEND_RR_DATA.0,
            session: self.session,
            data,
            ..EncapRepr::default()
        })?;
        if reply.status != 0 {
            return Err(format!("SendRRData status {:#x}", reply.status));
        }
        let sd = SendData::parse(&reply.data).map_err(|e| e.to_string())?;
        let Some(Item::UnconnectedData(payload)) = sd.cpf.items.get(1) else {
            return Err("SendRRData reply without unconnected data item".into());
        };
        let resp = MrResponse::parse(payload).map_err(|e| e.to_string())?;
        if resp.general != 0 {
            return Err(format!(
                "{} {} refused: general status {:#04x}",
                Service(req.service),
                req.path,
                resp.general
            ));
        }
        Ok(resp)
    }

    /// Get_Attribute_Single of `path`.
    fn get(&mut self, path: &EPath) -> Result<Vec<u8>, String> {
        self.request(&MrRequest {
            service: Service::GET_ATTRIBUTE_SINGLE.0,
            path: path.clone(),
            data: Vec::new(),
        })
        .map(|r| r.data)
    }

    /// Forward_Open of a class-1 cyclic point-to-point connection to assembly points `o_t`
    /// and `t_o` with connection sizes `o_t_size` and `t_o_size`, RPI `rpi_us` both ways.
    fn forward_open(
        &mut self,
        o_t: u16,
        t_o: u16,
        o_t_size: u16,
        t_o_size: u16,
        rpi_us: u32,
    ) -> Result<IoConnection, String> {
        let np = |size: u16| NetParams {
            size,
            variable: false,
            priority: 0,
            kind: kind::POINT_TO_POINT,
            redundant_owner: false,
        };
        let serial = 0x4245;
        let fo = ForwardOpen {
            large: false,
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            o_t_id: 0,
            t_o_id: 0x4245_0001,
            serial,
            vendor: VENDOR,
            originator_serial: ORIGINATOR_SERIAL,
            timeout_multiplier: IO_MULTIPLIER,
            o_t_rpi: rpi_us,
            o_t: np(o_t_size),
            t_o_rpi: rpi_us,
            t_o: np(t_o_size),
            transport: Transport::CLASS1_CYCLIC,
            path: EPath {
                segments: vec![
                    Segment::Class(class::ASSEMBLY),
                    Segment::Instance(1),
                    Segment::ConnectionPoint(o_t),
                    Segment::ConnectionPoint(t_o),
                ],
            },
        };
        let resp = self.request(&MrRequest {
            service: Service::FORWARD_OPEN.0,
            path: EPath::object(class::CONNECTION_MANAGER, 1),
            data: fo.emit(),
        })?;
        let r = ForwardOpenReply::parse(&resp.data).map_err(|e| format!("Forward_Open: {e}"))?;
        Ok(IoConnection {
            o_t_id: r.o_t_id,
            t_o_id: r.t_o_id,
            serial,
        })
    }

    fn forward_close(&mut self, serial: u16) -> Result<(), String> {
        let fc = ForwardClose {
            priority_tick: 0x0A,
            timeout_ticks: 0x0E,
            serial,
            vendor: VENDOR,
            originator_serial: ORIGINATOR_SERIAL,
            path: EPath::object(class::ASSEMBLY, 1),
        };
        self.request(&MrRequest {
            service: Service::FORWARD_CLOSE.0,
            path: EPath::object(class::CONNECTION_MANAGER, 1),
            data: fc.emit(),
        })
        .map(|_| ())
    }
}

impl Drop for Client {
    /// Leaves the simulator as found: the session unregistered.
    fn drop(&mut self) {
        let bye = EncapRepr {
            command: EncapCommand::UNREGISTER_SESSION.0,
            session: self.session,
            ..EncapRepr::default()
        };
        if let Ok(b) = bye.emit() {
            let _ = self.tcp.write_all(&b);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn us(n: u64) -> Duration {
        Duration::from_micros(n)
    }

    #[test]
    fn percentile_is_nearest_rank() {
        let v: Vec<Duration> = (1..=100).map(us).collect();
        assert_eq!(percentile(&v, 50.0), Some(us(50)));
        assert_eq!(percentile(&v, 99.0), Some(us(99)));
        assert_eq!(percentile(&v, 100.0), Some(us(100)));
        assert_eq!(percentile(&v, 0.0), Some(us(1)));
        // 10 values: rank ceil(9.9) = 10, the largest.
        let ten: Vec<Duration> = (1..=10).map(us).collect();
        assert_eq!(percentile(&ten, 99.0), Some(us(10)));
        assert_eq!(percentile(&ten, 50.0), Some(us(5)));
        assert_eq!(percentile(&[us(7)], 99.0), Some(us(7)));
        assert_eq!(percentile(&[], 50.0), None);
    }

    #[test]
    fn jitter_of_a_perfect_stream_is_zero() {
        let a: Vec<(u32, Duration)> = (0..10).map(|i| (i + 1, us(1000 * u64::from(i)))).collect();
        let j = jitter(&a, us(1000)).unwrap();
        assert_eq!(
            j,
            Jitter {
                frames: 10,
                lost: 0,
                disordered: 0,
                p50: Duration::ZERO,
                p99: Duration::ZERO,
                max: Duration::ZERO,
            }
        );
    }

    #[test]
    fn jitter_is_the_absolute_deviation_from_the_period() {
        // Intervals 1100, 900, 1000, 1300 µs: deviations 100, 100, 0, 300.
        let a = [
            (1, us(0)),
            (2, us(1100)),
            (3, us(2000)),
            (4, us(3000)),
            (5, us(4300)),
        ];
        let j = jitter(&a, us(1000)).unwrap();
        assert_eq!((j.p50, j.p99, j.max), (us(100), us(300), us(300)));
    }

    #[test]
    fn gaps_count_as_lost_and_are_not_intervals() {
        // 3 and 4 missing: the 3000 µs interval 2→5 is not a jitter sample.
        let a = [(1, us(0)), (2, us(1000)), (5, us(4000)), (6, us(5050))];
        let j = jitter(&a, us(1000)).unwrap();
        assert_eq!((j.frames, j.lost, j.disordered), (4, 2, 0));
        assert_eq!((j.p50, j.max), (us(0), us(50)));
    }

    #[test]
    fn sequence_numbers_wrap_and_repeats_are_disordered() {
        let a = [
            (u32::MAX, us(0)),
            (0, us(1000)),
            (0, us(1500)),
            (1, us(2000)),
        ];
        let j = jitter(&a, us(1000)).unwrap();
        assert_eq!((j.lost, j.disordered), (0, 1));
        // 0 → 1 counts from the repeat's arrival: 500 µs, deviation 500.
        assert_eq!((j.p50, j.max), (us(0), us(500)));
    }

    #[test]
    fn no_interval_no_jitter() {
        assert_eq!(jitter(&[], us(1000)), None);
        assert_eq!(jitter(&[(1, us(0))], us(1000)), None);
        assert_eq!(jitter(&[(1, us(0)), (3, us(2000))], us(1000)), None);
    }
}
