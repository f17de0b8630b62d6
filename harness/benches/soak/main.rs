//! The soak (issue 24, item 5): `cargo bench -p harness --bench soak -- [--seconds N]
//! [--seed S] [--fuzz-rate R] [enip] [ecat] [pnio] [epl]` (the buses named, all when none is).
//!
//! A served device, `harness serve BUS` as a process of its own, under good clients and fuzzed
//! clients for a bounded time: first the good clients alone (the idle phase, a quarter of
//! the time), then beside the fuzzed clients (the mixed phase, the rest). Each good client
//! makes one request every 2 ms with a known answer and checks every answer; each fuzzed
//! client sends broken frames (good ones built with `proto`'s emitters, then mutated by a
//! seeded generator) at a bounded rate. The served process's resident memory is sampled from
//! `/proc/PID/status` every 250 ms. Printed per bus: the memory (start, max, end, the mixed
//! phase's slope), the good clients' p50/p99 idle and mixed and the ratio of the p99s, the
//! good requests, lost and wrong, the broken frames sent, and the criteria met or
//! not:
//!
//! - memory flat: over the mixed phase after its first quarter (allocators and buffers
//!   settle in as the fuzzed clients start), RSS grows by at most [`RSS_GROWTH_KIB`] and its
//!   least-squares slope stays below [`RSS_SLOPE_KIB_S`];
//! - the good clients' p99 in the mixed phase at most [`P99_RATIO`]× the idle phase's;
//! - nothing lost: every good request got its known answer, and a good client made after
//!   the soak gets it too (a device that leaked sessions or connections to the fuzzed
//!   clients would refuse it).
//!
//! The buses: EtherNet/IP over loopback (TCP and UDP); EtherCAT, PROFINET IO and POWERLINK
//! over a veth pair into a network namespace (made and removed here; needs root, else
//! skipped). A bench, not a test: bounded in time (`--seconds`, 60 by
//! default, per bus) and in rate, nothing asserts; the host's load average is printed beside
//! the figures, since latency on a shared machine depends on it.

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::process::Command;
use std::time::Duration;

#[path = "../common/mod.rs"]
mod common;
mod ecat;
mod enip;
mod epl;
mod mutate;
#[path = "../../../tests/common/netns.rs"]
mod netns;
#[path = "../../../tests/common/peer.rs"]
mod peer;
mod pnio;
mod raw;
mod rss;
mod run;

use common::met;
use common::served::Served;
use netns::Netns;
use run::{Answer, Bus, Plan, Soaked};

/// Memory may grow this much over the mixed phase after its first quarter.
const RSS_GROWTH_KIB: f64 = 1024.0;
/// And its slope must stay below this.
const RSS_SLOPE_KIB_S: f64 = 8.0;
/// The good clients' mixed p99 at most this many times the idle p99.
const P99_RATIO: f64 = 2.0;
/// Where the EtherNet/IP adapter is served: an address of its own on loopback.
const ENIP_LISTEN: SocketAddr = SocketAddr::new(IpAddr::V4(Ipv4Addr::new(127, 0, 0, 24)), 44818);

fn main() {
    let (plan, only) = match plan(std::env::args().skip(1)) {
        Ok(p) => p,
        Err(e) => {
            eprintln!("soak: {e}");
            std::process::exit(2);
        }
    };
    let total = (plan.idle + plan.mixed).as_secs();
    println!(
        "soak: {total} s per bus (idle {} s, mixed {} s); {} good clients, 1 request each per {} ms; {} fuzzed clients, {} broken frames/s at most; seed {}",
        plan.idle.as_secs(),
        plan.mixed.as_secs(),
        plan.good_clients,
        plan.period.as_millis(),
        plan.fuzz_clients,
        plan.fuzz_rate,
        plan.seed
    );
    let runs = |bus: &str| only.is_empty() || only.iter().any(|o| o == bus);
    // The device outlives the soak by a margin, and is killed when it is over.
    let seconds = total + 30;
    if runs("enip") {
        match enip::serve(ENIP_LISTEN, seconds, |bus, args| {
            serve(|p| Command::new(p), bus, args)
        }) {
            Ok((served, line, bus)) => report("EtherNet/IP", &line, &bus, served.pid(), &plan),
            Err(e) => println!("EtherNet/IP: could not serve ({e})"),
        }
    }
    let raw = runs("ecat") || runs("pnio") || runs("epl");
    if raw && !(peer::is_root() && peer::runs("ip", "-V")) {
        println!(
            "EtherCAT, PROFINET IO, POWERLINK: skipped (a veth pair into a namespace needs root and `ip`)"
        );
        return;
    }
    if runs("ecat") {
        let r = soak_raw(&plan, seconds, ("EtherCAT", "ecat", &[]), None, |iface| {
            let bus = ecat::Ecat::new(iface)?;
            let said = format!("known answer {:02x?}", bus.expected());
            Ok((bus, said))
        });
        if let Err(e) = r {
            println!("EtherCAT: could not run ({e})");
        }
    }
    if runs("pnio") {
        let r = soak_raw(
            &plan,
            seconds,
            ("PROFINET IO", "pnio", &["--name", "soak"]),
            None,
            |iface| {
                let bus = pnio::Pnio::new(iface)?;
                let said = bus.said();
                Ok((bus, said))
            },
        );
        if let Err(e) = r {
            println!("PROFINET IO: could not run ({e})");
        }
    }
    if runs("epl") {
        let node = format!("{}/24", proto::nord::epl::ip_address(1));
        let r = soak_raw(
            &plan,
            seconds,
            ("POWERLINK", "epl", &[]),
            Some(&node),
            |iface| {
                let bus = epl::Epl::new(iface)?;
                let said = bus.said();
                Ok((bus, said))
            },
        );
        if let Err(e) = r {
            println!("POWERLINK: could not run ({e})");
        }
    }
}

/// A raw-Ethernet bus's soak: the device served (`harness serve BUS ARGS…`) in a namespace of
/// its own, its end given the IPv4 address `address` (CIDR) first when it serves UDP too, the
/// clients on the root end of the veth pair; `bus` makes the bus's clients on that interface
/// and says what it found.
fn soak_raw<B: Bus>(
    plan: &Plan,
    seconds: u64,
    (name, command, args): (&str, &str, &[&str]),
    address: Option<&str>,
    bus: impl FnOnce(&str) -> Result<(B, String), String>,
) -> Result<(), String> {
    let ns = Netns::new(&format!("soak-{command}"));
    if let Some(a) = address {
        let out = ns.exec(&["ip", "addr", "add", a, "dev", ns.ns_if()]);
        if !out.status.success() {
            return Err(format!(
                "ip addr add {a}: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            ));
        }
    }
    let seconds = seconds.to_string();
    let mut all = vec!["--iface", ns.ns_if(), "--seconds", &seconds];
    all.extend(args);
    let (served, line) = serve(|p| ns.command(p), command, &all)?;
    let (bus, said) = bus(ns.root_if())?;
    let line = format!("{line}; clients on {}; {said}", ns.root_if());
    report(name, &line, &bus, served.pid(), plan);
    Ok(())
}

/// Starts `harness serve BUS ARGS…` through `wrap` (which makes the command that runs a
/// program: here, or inside a namespace) at a real-time priority (`chrt -f 10`) where the
/// machine allows, standing in for a device with a processor of its own, as the POWERLINK and
/// PROFINET benches serve theirs (at normal priority a loaded host holds the device back long
/// enough for its socket to overflow); else at normal priority. Its line says which.
fn serve(
    wrap: impl Fn(&str) -> Command,
    bus: &str,
    args: &[&str],
) -> Result<(Served, String), String> {
    let harness = env!("CARGO_BIN_EXE_harness");
    if peer::runs("chrt", "--version") {
        let mut command = wrap("chrt");
        command.args(["-f", "10", harness]);
        match Served::start(command, bus, args) {
            Ok((served, line)) => return Ok((served, format!("{line}; at SCHED_FIFO 10"))),
            Err(e) => eprintln!("serving at a real-time priority failed ({e}): normal priority"),
        }
    }
    let (served, line) = Served::start(wrap(harness), bus, args)?;
    Ok((served, format!("{line}; at normal priority")))
}

/// The plan and the buses named on the command line (`cargo bench` adds `--bench`, which is
/// ignored).
fn plan(mut args: impl Iterator<Item = String>) -> Result<(Plan, Vec<String>), String> {
    let mut only = Vec::new();
    let mut seconds = 60u64;
    let mut seed = 24u64;
    let mut fuzz_rate = 2_000u64;
    while let Some(a) = args.next() {
        let mut value = |name: &str| -> Result<u64, String> {
            args.next()
                .and_then(|v| v.parse().ok())
                .ok_or(format!("{name} takes a whole number"))
        };
        match a.as_str() {
            "--seconds" => seconds = value("--seconds")?.max(8),
            "--seed" => seed = value("--seed")?,
            "--fuzz-rate" => fuzz_rate = value("--fuzz-rate")?.max(1),
            "--bench" => {}
            bus @ ("enip" | "ecat" | "pnio" | "epl") => only.push(bus.to_string()),
            other => return Err(format!("unknown argument {other}")),
        }
    }
    let idle = Duration::from_secs(seconds / 4);
    let plan = Plan {
        idle,
        mixed: Duration::from_secs(seconds) - idle,
        good_clients: 2,
        period: Duration::from_millis(2),
        fuzz_clients: 2,
        fuzz_rate,
        seed,
        rss_every: Duration::from_millis(250),
    };
    Ok((plan, only))
}

/// Soaks `bus` and prints its figures and criteria.
fn report<B: Bus>(name: &str, line: &str, bus: &B, pid: u32, plan: &Plan) {
    let comm = std::fs::read_to_string(format!("/proc/{pid}/comm")).unwrap_or_default();
    println!("{name}: {line} (process {}, pid {pid})", comm.trim());
    let load_before = load();
    let s = match run::soak(bus, pid, plan) {
        Ok(s) => s,
        Err(e) => {
            println!("{name}: the soak could not run ({e})");
            return;
        }
    };
    println!(
        "{name}: host load average (1 min) {} before, {} after",
        load_before,
        load()
    );
    let memory = memory(name, &s);
    let latency = latency(name, &s);
    let lost = s.idle.lost + s.idle.wrong + s.mixed.lost + s.mixed.wrong;
    println!(
        "{name}: good requests {} idle + {} mixed; lost {}, wrong {} (0: {})",
        s.idle.requests(),
        s.mixed.requests(),
        s.idle.lost + s.mixed.lost,
        s.idle.wrong + s.mixed.wrong,
        met(lost == 0)
    );
    for (phase, said) in [("idle", &s.idle.said), ("mixed", &s.mixed.said)] {
        for said in said {
            println!("{name}:   {phase}: {said}");
        }
    }
    let share = |cpu: Duration, over: Duration| 100.0 * cpu.as_secs_f64() / over.as_secs_f64();
    println!(
        "{name}: broken frames sent {}; served process {}, its processor time {:.1} % idle, {:.1} % mixed",
        s.fuzzed,
        if s.alive { "alive at the end" } else { "GONE" },
        share(s.cpu.0, s.mixed_from),
        share(s.cpu.1, s.mixed_for)
    );
    let fresh = match &s.fresh {
        Ok(Answer::Right) => Ok(()),
        Ok(Answer::Wrong(e) | Answer::Lost(e)) => Err(e.clone()),
        Err(e) => Err(format!("could not connect: {e}")),
    };
    println!(
        "{name}: a new good client after the soak: {}",
        match &fresh {
            Ok(()) => "answered right".to_string(),
            Err(e) => format!("NOT answered right ({e})"),
        }
    );
    let pass = memory && latency && lost == 0 && s.alive && fresh.is_ok();
    println!("{name}: soak {}", if pass { "PASSED" } else { "FAILED" });
}

/// Prints the memory figures; whether they stayed flat.
fn memory(name: &str, s: &Soaked) -> bool {
    let settled = s.mixed_from + s.mixed_for / 4;
    let judged = s.rss.after(settled);
    let kib = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.0}"));
    let growth = judged.last().zip(judged.first()).map(|(l, f)| l - f);
    let slope = judged.slope();
    let flat =
        growth.is_some_and(|g| g <= RSS_GROWTH_KIB) && slope.is_some_and(|v| v < RSS_SLOPE_KIB_S);
    println!(
        "{name}: RSS (KiB, {} samples): start {}, max {}, end {}; from {:.0} s on: {} → {}, growth {}, slope {} KiB/s (flat: growth ≤ {RSS_GROWTH_KIB:.0} KiB and slope < {RSS_SLOPE_KIB_S} KiB/s: {})",
        s.rss.0.len(),
        kib(s.rss.first()),
        kib(s.rss.max()),
        kib(s.rss.last()),
        settled.as_secs_f64(),
        kib(judged.first()),
        kib(judged.last()),
        kib(growth),
        slope.map_or("-".into(), |v| format!("{v:.2}")),
        met(flat)
    );
    flat
}

/// Prints the good clients' latency; whether the mixed p99 stayed within the ratio.
fn latency(name: &str, s: &Soaked) -> bool {
    let us = |d: Option<Duration>| d.map_or("-".into(), |d| format!("{} µs", d.as_micros()));
    let ratio = s
        .mixed
        .p(99.0)
        .zip(s.idle.p(99.0))
        .map(|(m, i)| m.as_secs_f64() / i.as_secs_f64().max(1e-9));
    println!(
        "{name}: good clients' latency: idle p50 {}, p99 {}; mixed p50 {}, p99 {}; p99 mixed/idle {} (≤ {P99_RATIO}: {})",
        us(s.idle.p(50.0)),
        us(s.idle.p(99.0)),
        us(s.mixed.p(50.0)),
        us(s.mixed.p(99.0)),
        ratio.map_or("-".into(), |r| format!("{r:.2}")),
        met(ratio.is_some_and(|r| r <= P99_RATIO))
    );
    ratio.is_some_and(|r| r <= P99_RATIO)
}

/// The 1-minute load average.
fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|l| l.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "-".into())
}
