//! PROFINET IO speed over a veth pair: `cargo bench -p harness --bench pnio`.
//!
//! One run makes two network namespaces joined by a veth pair: the device's, where the
//! simulated SK 550P (one inverter) is served by `harness::pnio_serve` in threads of this
//! process on 192.168.20.200/24 (the SK 550P's factory address, BU 0620 §4.2.4), and the
//! controller's, 192.168.20.1/24, where the clients run. Both ends bind UDP 34964 (the device
//! its RPC endpoint, the harness controller its own), so they cannot share a namespace; and
//! neither is the root namespace, where a test running meanwhile could have 192.168.20.0/24 on
//! a veth end of its own. The threads enter the namespaces with `setns`; the Python client is
//! started from a thread inside the controller's. It prints, one line per figure with its
//! target and whether it was met:
//!
//! - record read round trips per second of the harness IO controller, in data exchange at the
//!   1 ms send clock (the cyclic exchange running while it awaits each answer), and p50/p99 of
//!   one read: the PKW order "read P102" written to data record 101 (FI 1) once, then IODRead
//!   of record 101 back to back (the first answer carries the order's answer, the rest the
//!   documented "Read Response (−)" DE 80 B5 00: no order pending; BU 0620 §2.5.6.2);
//! - the same for scapy's PROFINET layers (`tests/interop/scapy_pnio_peer.py bench-read`, a
//!   subprocess in the interop venv: Connect with the same submodules, then the same write
//!   and reads in its AR), and the ratio of the two (target: harness ≥ 5× scapy);
//! - the jitter of the device's input CR frames at 1 ms over 10 s of data exchange: count,
//!   mean interval, and p50, p99 and maximum of |interval − 1 ms| between the kernel's receive
//!   stamps (SO_TIMESTAMPNS) on the controller's end of consecutive cycles (target p99
//!   < 100 µs).
//!
//! The device's thread runs at a real-time priority (`chrt -f 10`) where it can, standing in
//! for a device with a processor of its own, as the POWERLINK bench serves its node. A bench,
//! not a timed test: bounded in count and time (about 15 s), nothing asserts on time, a missed
//! target is printed, not failed. Without root (or without `ip`) it says why and exits 0.

use std::fs::File;
use std::net::Ipv4Addr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use harness::pnio_bench::{self, Session};
use harness::pnio_serve::{self, ServeOptions};
use harness::stats::{jitter, percentile};
use nix::sched::{setns, CloneFlags};
use proto::nord::Product;

#[path = "../common/mod.rs"]
mod common;
#[path = "../../../tests/common/netns.rs"]
mod netns;
// What netns.rs takes its root check from.
#[allow(unused_imports)]
#[path = "../../../tests/common/peer.rs"]
mod peer;

use common::{met, run_script, Script};
use netns::Netns;

/// The harness must make at least this many record reads per read of the scapy client.
const TARGET_RATIO: f64 = 5.0;
/// The p99 of |interval − cycle| of the input CR's frames must stay below this.
const TARGET_P99: Duration = Duration::from_micros(100);
/// The send clock the controller connects with (SendClockFactor 32, ReductionRatio 1).
const CYCLE: Duration = Duration::from_millis(1);
/// The device's address (the SK 550P's factory IP, BU 0620 §4.2.4) and the controller's.
const DEVICE_IP: Ipv4Addr = Ipv4Addr::new(192, 168, 20, 200);
const CONTROLLER_IP: Ipv4Addr = Ipv4Addr::new(192, 168, 20, 1);
/// The product served.
const PRODUCT: Product = Product::Sk550p;

/// What to measure, and the bounds of each figure.
#[derive(Debug, Clone)]
struct Settings {
    /// Record reads of the harness, at most.
    reads: u32,
    /// Record reads of the scapy client, at most.
    scapy_reads: u32,
    /// Time limit of each read figure.
    limit: Duration,
    /// How long the input CR's frames are stamped.
    record: Duration,
    /// The interop venv's Python, when it exists.
    python: Option<PathBuf>,
    /// `tests/interop/scapy_pnio_peer.py`.
    script: PathBuf,
}

impl Settings {
    /// The bounds: 2,000 harness reads and 1,000 scapy reads, each within 10 s; 10 s
    /// of input frames at 1 ms.
    fn new() -> Settings {
        Settings {
            reads: 2_000,
            scapy_reads: 1_000,
            limit: Duration::from_secs(10),
            record: Duration::from_secs(10),
            python: common::interop_python(),
            script: Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../tests/interop/scapy_pnio_peer.py"),
        }
    }
}

fn main() {
    if let Some(why) = cannot_run() {
        println!("PROFINET bench skipped: {why}");
        return;
    }
    let start = Instant::now();
    if let Err(e) = run(&Settings::new()) {
        eprintln!("PROFINET bench could not run: {e}");
        std::process::exit(1);
    }
    println!("PROFINET bench ran {:.1} s", start.elapsed().as_secs_f64());
}

/// Why this machine cannot run the bench (network namespaces and raw Ethernet need root and
/// `ip`), if it cannot.
fn cannot_run() -> Option<String> {
    if !peer::is_root() {
        return Some("needs root (network namespaces with a veth pair, raw Ethernet)".into());
    }
    if !peer::runs("ip", "-V") {
        return Some("needs `ip` (iproute2) for the network namespaces".into());
    }
    None
}

/// Runs `ip ARGS…`; its error message when it fails.
fn ip(args: &[&str]) -> Result<(), String> {
    let out = Command::new("ip")
        .args(args)
        .output()
        .map_err(|e| format!("cannot run ip: {e}"))?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "ip {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

/// The controller's namespace: the root-side end of [`Netns`]'s pair moved into a namespace of
/// its own (named as `netns.rs` names them, so a run that was killed is cleaned up by the
/// next), deleted when dropped.
struct ControllerNs {
    name: String,
    iface: String,
}

impl ControllerNs {
    fn new(device: &Netns) -> Result<ControllerNs, String> {
        let name = format!("nord-test-{}-99-pnio-bench-ctl", std::process::id());
        ip(&["netns", "add", &name])?;
        let ns = ControllerNs {
            name,
            iface: device.root_if().to_string(),
        };
        ip(&["link", "set", "dev", &ns.iface, "netns", &ns.name])?;
        ip(&["-n", &ns.name, "link", "set", "lo", "up"])?;
        // Moved, the end has its new namespace's defaults: IPv6 off again (no router
        // solicitations or MLD reports on the wire).
        let _ = Command::new("ip")
            .args(["netns", "exec", &ns.name, "sh", "-c"])
            .arg(format!(
                "echo 1 > /proc/sys/net/ipv6/conf/{}/disable_ipv6",
                ns.iface
            ))
            .stderr(Stdio::null())
            .status();
        ip(&[
            "-n",
            &ns.name,
            "addr",
            "add",
            &format!("{CONTROLLER_IP}/24"),
            "dev",
            &ns.iface,
        ])?;
        ip(&["-n", &ns.name, "link", "set", &ns.iface, "up"])?;
        Ok(ns)
    }
}

impl Drop for ControllerNs {
    fn drop(&mut self) {
        let _ = Command::new("ip")
            .args(["netns", "del", &self.name])
            .stderr(Stdio::null())
            .status();
    }
}

/// Waits (5 s at most) until `ip -n NS link show dev IFACE` says the link is up with its
/// queueing discipline attached.
fn wait_carrier(ns: &str, iface: &str) -> Result<(), String> {
    let start = Instant::now();
    loop {
        let out = Command::new("ip")
            .args(["-n", ns, "-o", "link", "show", "dev", iface])
            .output()
            .map_err(|e| format!("cannot run ip: {e}"))?;
        let text = String::from_utf8_lossy(&out.stdout);
        if text.contains("state UP") && !text.contains("qdisc noop") {
            return Ok(());
        }
        if start.elapsed() > Duration::from_secs(5) {
            return Err(format!("{iface} does not come up in {ns}: {text}"));
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Runs `f` in a thread of its own inside the network namespace `ns` (`/run/netns/NS`): the
/// sockets it opens and the processes it starts are that namespace's.
fn in_netns<T: Send>(ns: &str, f: impl FnOnce() -> T + Send) -> Result<T, String> {
    std::thread::scope(|scope| {
        scope
            .spawn(|| {
                let fd = File::open(format!("/run/netns/{ns}"))
                    .map_err(|e| format!("network namespace {ns}: {e}"))?;
                setns(&fd, CloneFlags::CLONE_NEWNET)
                    .map_err(|e| format!("setns into {ns}: {e}"))?;
                Ok(f())
            })
            .join()
            .unwrap_or_else(|_| Err(format!("the thread in {ns} panicked")))
    })
}

/// Puts this process's device threads (`pnio-device-…`) at SCHED_FIFO 10 with `chrt`; what
/// priority they run at.
fn device_realtime() -> &'static str {
    if !peer::runs("chrt", "--version") {
        return "normal priority (no chrt)";
    }
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return "normal priority";
    };
    let mut done = false;
    for task in tasks.flatten() {
        let comm = std::fs::read_to_string(task.path().join("comm")).unwrap_or_default();
        if !comm.starts_with("pnio-device") {
            continue;
        }
        let tid = task.file_name().to_string_lossy().into_owned();
        let ok = Command::new("chrt")
            .args(["-f", "-p", "10", &tid])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            return "normal priority (chrt failed)";
        }
        done = true;
    }
    if done {
        "SCHED_FIFO 10 (chrt)"
    } else {
        "normal priority (device thread not found)"
    }
}

/// The harness figures: record reads, then the input frames, in one AR.
struct Harness {
    station: String,
    reads: Result<pnio_bench::Reads, String>,
    frames: Result<pnio_bench::InputFrames, String>,
    release: Result<(), String>,
}

fn harness_figures(iface: &str, s: &Settings) -> Result<Harness, String> {
    let mut session = Session::open(iface, PRODUCT, Duration::from_secs(1))?;
    let station = session.station().to_string();
    let reads = session.record_reads(s.reads, s.limit);
    let frames = session.input_frames(s.record);
    let release = session.release();
    Ok(Harness {
        station,
        reads,
        frames,
        release,
    })
}

/// The scapy client's arguments: the device, the same submodules as the harness, Connect,
/// then `bench-read` (the order written once, then the reads). The client sends no PrmEnd:
/// its AR stays in parameterisation, where records are read and written as in data exchange,
/// and no ApplicationReady (which it would not answer) ends it. It is not released: its last
/// line is the figure, and the device stops after it.
fn scapy_args(iface: &str, s: &Settings) -> Result<Vec<String>, String> {
    let mut args: Vec<String> = [
        "--ip",
        &DEVICE_IP.to_string(),
        "--iface",
        iface,
        "--vendor-id",
        &format!("{:#06x}", proto::nord::pnio::VENDOR_ID),
        "--device-id",
        &format!(
            "{:#06x}",
            proto::nord::pnio::device_id(PRODUCT).unwrap_or_default()
        ),
        "--timeout",
        "2",
        "--deadline",
        &(s.limit.as_secs() + 10).to_string(),
    ]
    .iter()
    .map(|a| a.to_string())
    .collect();
    for sub in pnio_bench::layout(PRODUCT)? {
        args.push("--submodule".into());
        args.push(format!(
            "{},{:#x},{:#x},{:#x},{},{}",
            sub.slot, sub.subslot, sub.module_ident, sub.ident, sub.input_len, sub.output_len
        ));
    }
    let order: String = pnio_bench::order()
        .emit_bytes()
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect();
    args.extend([
        "connect".to_string(),
        "bench-read".into(),
        s.scapy_reads.to_string(),
        pnio_bench::RECORD.to_string(),
        pnio_bench::record_slot(PRODUCT)?.to_string(),
        "1".into(),
        order,
    ]);
    Ok(args)
}

/// Serves the device and prints every figure. An error means the bench could not run at all;
/// a figure that fails prints why and the rest go on.
fn run(s: &Settings) -> Result<(), String> {
    let dev_ns = Netns::new("pnio-bench-dev");
    let ctl_ns = ControllerNs::new(&dev_ns)?;
    ip(&[
        "-n",
        dev_ns.name(),
        "addr",
        "add",
        &format!("{DEVICE_IP}/24"),
        "dev",
        dev_ns.ns_if(),
    ])?;
    wait_carrier(dev_ns.name(), dev_ns.ns_if())?;
    wait_carrier(&ctl_ns.name, &ctl_ns.iface)?;

    let opts = ServeOptions {
        inverters: Some(1),
        ..ServeOptions::new(dev_ns.ns_if())
    };
    let served = in_netns(dev_ns.name(), || pnio_serve::start(&opts))?
        .map_err(|e| format!("serving the device on {}: {e}", dev_ns.ns_if()))?;
    let priority = device_realtime();
    println!(
        "PROFINET bench: SK 550P (1 inverter) served on {} ({DEVICE_IP}/24, MAC {}) in {} at {priority}; controllers on {} ({CONTROLLER_IP}/24) in {}",
        dev_ns.ns_if(),
        served.mac(),
        dev_ns.name(),
        ctl_ns.iface,
        ctl_ns.name
    );

    let order = pnio_bench::order();
    let what = format!(
        "record {} (FI 1, slot {}): \"{}\" written once, then IODRead back to back",
        pnio_bench::RECORD,
        pnio_bench::record_slot(PRODUCT)?,
        order.describe_order()
    );
    let h = in_netns(&ctl_ns.name, || harness_figures(&ctl_ns.iface, s))??;
    println!(
        "harness IO controller found the device by DCP: {}",
        h.station
    );

    let head = format!("harness IO controller in data exchange at 1 ms, {what}");
    let harness_rate = match &h.reads {
        Ok(r) => {
            let p = |q| percentile(&r.latencies, q).map_or(0, |d: Duration| d.as_micros());
            println!(
                "{head}: {}, p50 {} µs, p99 {} µs per read; timed answers: {} with data, {} Read Response (−), {} other; the order's answer: {}",
                r.rate.show("reads"),
                p(50.0),
                p(99.0),
                r.data,
                r.busy,
                r.other,
                r.answer.as_deref().unwrap_or("none")
            );
            Some(r.rate.per_sec())
        }
        Err(e) => {
            println!("{head}: failed ({e})");
            None
        }
    };

    // The scapy client after the harness's AR is released (one AR at a time).
    let head = format!("scapy {what} (in its AR, no cyclic data)");
    let scapy = match (&h.release, scapy_args(&ctl_ns.iface, s)) {
        (Err(e), _) => Script::Failed(format!("the harness's AR was not released: {e}")),
        (_, Err(e)) => Script::Failed(e),
        (Ok(()), Ok(args)) => in_netns(&ctl_ns.name, || {
            run_script(
                s.python.as_deref(),
                &s.script,
                &args,
                "scapy",
                s.limit + Duration::from_secs(10),
            )
        })?,
    };
    match scapy {
        Script::Skipped(why) => println!("{head}: skipped ({why})"),
        Script::Failed(why) => println!("{head}: failed ({why})"),
        Script::Ran(v) => {
            let answered = v["answered"].as_u64().unwrap_or(0);
            let secs = v["seconds"].as_f64().unwrap_or(0.0);
            let rate = if secs > 0.0 {
                answered as f64 / secs
            } else {
                0.0
            };
            let write_ok = v["write"]["ok"].as_bool().unwrap_or(false);
            println!(
                "{head}: {answered} reads in {secs:.3} s = {rate:.0}/s, mean {} µs per read; PNIO statuses {}; write {}{}",
                if answered > 0 {
                    (secs * 1e6 / answered as f64).round()
                } else {
                    0.0
                },
                v["statuses"],
                if write_ok { "ok" } else { "NOT ok" },
                v["error"]
                    .as_str()
                    .map_or(String::new(), |e| format!(" ({e})"))
            );
            match harness_rate {
                Some(hr) if rate > 0.0 => {
                    let ratio = hr / rate;
                    println!(
                        "harness/scapy record reads: {ratio:.1}x (target >= {TARGET_RATIO:.0}x: {})",
                        met(ratio >= TARGET_RATIO)
                    );
                }
                _ => println!("harness/scapy record reads: no ratio (a figure is missing)"),
            }
        }
    }

    let head = format!(
        "input CR frames of the device at 1 ms, {} s of data exchange, kernel receive stamps on the controller's end",
        s.record.as_secs()
    );
    match &h.frames {
        Ok(f) => {
            let mean = match (f.arrivals.first(), f.arrivals.last()) {
                (Some(a), Some(b)) if f.arrivals.len() > 1 => {
                    (b.1.saturating_sub(a.1)).as_secs_f64() * 1e6 / (f.arrivals.len() - 1) as f64
                }
                _ => 0.0,
            };
            println!(
                "{head}: {} frames in {:.3} s, mean interval {mean:.1} µs, {} without stamp, device {} at the end",
                f.arrivals.len(),
                f.elapsed.as_secs_f64(),
                f.unstamped,
                if f.running { "running" } else { "NOT running" }
            );
            match jitter(&f.arrivals, CYCLE) {
                Some(j) => println!(
                    "  |interval − 1 ms| of consecutive cycles: p50 {} µs, p99 {} µs, max {} µs; {} cycles missing, {} out of order (target p99 < {} µs: {})",
                    j.p50.as_micros(),
                    j.p99.as_micros(),
                    j.max.as_micros(),
                    j.lost,
                    j.disordered,
                    TARGET_P99.as_micros(),
                    met(j.p99 < TARGET_P99)
                ),
                None => println!("  no two consecutive stamped input frames"),
            }
        }
        Err(e) => println!("{head}: failed ({e})"),
    }
    if let Err(e) = &h.release {
        println!("harness Release: {e}");
    }

    let stats = served
        .stop()
        .map_err(|e| format!("the served device stopped: {e}"))?;
    println!(
        "device served: {} frames in, {} out, {} RPC datagrams in, {} out",
        stats.frames_in, stats.frames_out, stats.datagrams_in, stats.datagrams_out
    );
    drop(ctl_ns);
    drop(dev_ns);
    Ok(())
}
