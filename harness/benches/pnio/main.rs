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
//! - parameter accesses per second of the harness IO controller, in data exchange at the 1 ms
//!   send clock (the cyclic exchange running while it awaits each answer), and p50/p99 of one
//!   access. **One operation is one complete parameter access**, what "read P102" is for a
//!   user (BU 0620 §2.5.6.2): the PKW order "request parameter value P102" written to data
//!   record 101 (FI 1) with IODWrite, then IODRead of record 101 until the answer carries the
//!   value (reads before the inverter has processed the order get the documented "Read
//!   Response (−)", DE 80 B5 00, and are read again; the reads an access took are counted);
//! - the same accesses by scapy's PROFINET layers (`tests/interop/scapy_pnio_peer.py
//!   bench-access`, a subprocess in the interop venv: Connect with the same submodules, then
//!   the same write and reads until the value, in its AR), and the ratio of the two (target:
//!   harness ≥ 5× scapy);
//! - the jitter of the device's input CR frames at 1 ms over 10 s of data exchange: count,
//!   mean interval, and p50, p99 and maximum of |interval − 1 ms| between the kernel's receive
//!   stamps (SO_TIMESTAMPNS) on the controller's end of consecutive cycles (target p99
//!   < 100 µs).
//!
//! The device's thread runs at a real-time priority (`chrt -f 10`) where it can, standing in
//! for a device with a processor of its own, as the POWERLINK bench serves its node. A bench,
//! not a timed test: bounded in count and time (about 15 s), nothing asserts on time, a missed
//! target is printed, not failed. Without root (or without `ip`) it says why and exits 0.

use std::net::Ipv4Addr;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use harness::pnio_bench::{self, Session};
use harness::pnio_serve::{self, ServeOptions};
use harness::stats::{jitter, percentile};
use proto::nord::Product;

#[path = "../common/mod.rs"]
mod common;
#[path = "../../../tests/common/netns.rs"]
mod netns;
// What netns.rs takes its root check from.
#[allow(unused_imports)]
#[path = "../../../tests/common/peer.rs"]
mod peer;

use common::{in_netns, ip, met, run_script, wait_carrier, ClientNs, Script};
use netns::Netns;

/// The harness must make at least this many parameter accesses per access of the scapy
/// client.
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
    /// Parameter accesses of the harness, at most.
    accesses: u32,
    /// Parameter accesses of the scapy client, at most.
    scapy_accesses: u32,
    /// Time limit of each access figure.
    limit: Duration,
    /// How long the input CR's frames are stamped.
    record: Duration,
    /// The interop venv's Python, when it exists.
    python: Option<PathBuf>,
    /// `tests/interop/scapy_pnio_peer.py`.
    script: PathBuf,
}

impl Settings {
    /// 2,000 harness accesses and 500 scapy accesses, each within 10 s; 10 s of input frames
    /// at 1 ms.
    fn new() -> Settings {
        Settings {
            accesses: 2_000,
            scapy_accesses: 500,
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

/// The harness figures: parameter accesses, then the input frames, in one AR.
struct Harness {
    station: String,
    accesses: Result<pnio_bench::Accesses, String>,
    frames: Result<pnio_bench::InputFrames, String>,
    release: Result<(), String>,
}

fn harness_figures(iface: &str, s: &Settings) -> Result<Harness, String> {
    let mut session = Session::open(iface, PRODUCT, Duration::from_secs(1))?;
    let station = session.station().to_string();
    let accesses = session.parameter_accesses(s.accesses, s.limit);
    let frames = session.input_frames(s.record);
    let release = session.release();
    Ok(Harness {
        station,
        accesses,
        frames,
        release,
    })
}

/// The scapy client's arguments: the device, the same submodules as the harness, Connect,
/// then `bench-access` (each access: the order written, then the reads until the value). The client sends no PrmEnd:
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
        "bench-access".into(),
        s.scapy_accesses.to_string(),
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
    let ctl_ns = ClientNs::new(
        dev_ns.root_if(),
        "pnio-bench-ctl",
        &format!("{CONTROLLER_IP}/24"),
    )?;
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
        "parameter accesses over record {} (FI 1, slot {}), one access = IODWrite of the order \"{}\", then IODRead until the answer with the value",
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
    let harness_rate = match &h.accesses {
        Ok(a) => {
            let p = |q| percentile(&a.latencies, q).map_or(0, |d: Duration| d.as_micros());
            println!(
                "{head}: {}, p50 {} µs, p99 {} µs per access; {:.2} IODReads per access ({} Read Response (−) in all); the answer: {}",
                a.rate.show("accesses"),
                p(50.0),
                p(99.0),
                a.reads as f64 / a.rate.count.max(1) as f64,
                a.busy,
                a.answer.as_deref().unwrap_or("none")
            );
            Some(a.rate.per_sec())
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
        (Ok(()), Ok(args)) => ctl_ns.run(|| {
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
            let done = v["done"].as_u64().unwrap_or(0);
            let secs = v["seconds"].as_f64().unwrap_or(0.0);
            let rate = if secs > 0.0 { done as f64 / secs } else { 0.0 };
            println!(
                "{head}: {done} accesses in {secs:.3} s = {rate:.0}/s, p50 {} µs, p99 {} µs per access; {:.2} IODReads per access ({} Read Response (−) in all); the answer: {}",
                v["p50_us"],
                v["p99_us"],
                v["reads"].as_u64().unwrap_or(0) as f64 / done.max(1) as f64,
                v["busy"],
                v["answer"].as_str().unwrap_or("none")
            );
            match harness_rate {
                Some(hr) if rate > 0.0 => {
                    let ratio = hr / rate;
                    println!(
                        "harness/scapy parameter accesses: {ratio:.1}x (target >= {TARGET_RATIO:.0}x: {})",
                        met(ratio >= TARGET_RATIO)
                    );
                }
                _ => println!("harness/scapy parameter accesses: no ratio (a figure is missing)"),
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
