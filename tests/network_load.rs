//! Verdicts that hold on a busy host: with a spinning process on every core ([`common::hog`]),
//! three consecutive `harness run --dut` runs against one served device per bus —
//! EtherNet/IP `tu3-eip`, EtherCAT `sk550p`, POWERLINK `tu4-pol`, PROFINET IO `sk550p` — each
//! in an order shuffled from its own seed (`--shuffle`), must give every case the same verdict,
//! with no case failed or in error. A verdict that moves between runs depends on the host's
//! load (a wait that is the host's, not the device's) or on the cases before it (a case that
//! inherits what an earlier one left). The four buses run side by side: their runs mostly wait
//! on the drive's real-time steps, and the load is the point.
//!
//! The first EtherCAT and PROFINET runs are also those buses' full runs over the wire, with
//! tshark capturing: what their captures must show is checked as `network_ecat` and
//! `network_pnio` would ([`common::ecat_wire`], [`common::pnio_wire`]), so CI makes each
//! run once.
//!
//! Needs root (network namespaces, raw sockets) and tshark (`.ci/interop-setup`); without them
//! the test says so and skips on a developer's machine, and fails in strict mode.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::LazyLock;
use std::time::{SystemTime, UNIX_EPOCH};

use serde_json::Value;

#[allow(dead_code)] // what the other network tests share
mod common;
use common::addr::free_loopback;
use common::hog::Hog;
use common::netns::{require_root_or_skip, Netns};
use common::peer::require_tshark;
use common::suite_run::SuiteRun;

/// Runs per bus: three shuffled orders per CI run (the seeds change with every run, so
/// successive CI runs try new orders); five took CI past its thirty minutes.
const RUNS: u64 = 3;
/// The PROFINET device's name of station, as the suites address it.
const PNIO_NAME: &str = "nord-device";
/// Where the served EtherNet/IP adapter listens, and the scanner's own address: each an address
/// of its own, whatever else runs on this host.
static ENIP_SERVED: LazyLock<String> = LazyLock::new(|| format!("{}:44818", free_loopback()));
static ENIP_LOCAL: LazyLock<String> = LazyLock::new(|| free_loopback().to_string());

/// One run's verdict per case: id → (verdict, message).
type Verdicts = BTreeMap<String, (String, String)>;

/// Runs the suites for `profile` against `dut` with `--shuffle seed`, from inside `ns` when
/// given; the verdicts from its run.json.
fn run(ns: Option<&Netns>, profile: &str, dut: &str, seed: u64, out: &Path) -> Verdicts {
    let suites = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../suites");
    let mut cmd = match ns {
        Some(ns) => ns.command(env!("CARGO_BIN_EXE_harness")),
        None => Command::new(env!("CARGO_BIN_EXE_harness")),
    };
    cmd.args(["run", "-q", "--profile", profile, "--suites"])
        .arg(&suites)
        .args(["--dut", dut, "--shuffle", &seed.to_string()])
        // The served simulator has no motor to turn and no EEPROM to wear.
        .args(["--allow-motion", "--max-eeprom-writes", "100000"])
        .arg("--out")
        .arg(out);
    if ns.is_none() {
        cmd.args(["--local", &ENIP_LOCAL]);
    }
    let done = cmd.output().expect("harness run starts");
    let report: Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap_or_else(|e| {
            panic!(
                "{profile} seed {seed}: no run.json ({e}): {}",
                String::from_utf8_lossy(&done.stderr)
            )
        }))
        .expect("run.json parses");
    assert_eq!(
        report["meta"]["shuffle"], seed,
        "{profile}: the seed is recorded"
    );
    eprintln!(
        "{profile} seed {seed}: {} (attempts discarded for a late host: {})",
        String::from_utf8_lossy(&done.stdout).trim(),
        report["meta"]["discarded_attempts"]
    );
    report["cases"]
        .as_array()
        .expect("cases")
        .iter()
        .map(|c| {
            let s = |k: &str| c[k].as_str().unwrap_or_default().to_string();
            (s("id"), (s("verdict"), s("message")))
        })
        .collect()
}

/// [`RUNS`] shuffled runs of `profile` against one served device, from seed `base` on;
/// `first`, when given, holds the verdicts of the first run, already made. What went wrong,
/// if anything.
fn shuffled_runs(
    ns: Option<&Netns>,
    profile: &str,
    dut: &str,
    base: u64,
    mut first: Option<Verdicts>,
) -> Vec<String> {
    let dir = std::env::temp_dir().join(format!(
        "harness-load-{}-{}",
        std::process::id(),
        profile.replace('@', "-")
    ));
    let runs: Vec<(u64, Verdicts)> = (0..RUNS)
        .map(|i| {
            let seed = base + i;
            let verdicts = match first.take() {
                Some(made) => made,
                None => run(ns, profile, dut, seed, &dir.join(seed.to_string())),
            };
            (seed, verdicts)
        })
        .collect();
    let mut wrong = Vec::new();
    for (seed, verdicts) in &runs {
        for (id, (v, m)) in verdicts {
            if v == "fail" || v == "error" {
                wrong.push(format!("{profile} seed {seed}: {id} {v}: {m}"));
            }
        }
    }
    let (first_seed, first) = &runs[0];
    for (seed, verdicts) in &runs[1..] {
        for (id, (v, m)) in verdicts {
            match first.get(id) {
                Some((v0, m0)) if v0 != v => wrong.push(format!(
                    "{profile} {id}: {v0} with seed {first_seed} ({m0}), {v} with seed {seed} ({m})"
                )),
                None => wrong.push(format!("{profile} {id}: only in the run of seed {seed}")),
                _ => {}
            }
        }
    }
    if wrong.is_empty() {
        let _ = std::fs::remove_dir_all(&dir);
    }
    wrong
}

#[test]
fn shuffled_runs_per_bus_under_load_give_the_same_verdicts() {
    let why = "shuffled --dut runs per bus on a loaded host";
    if !require_root_or_skip(why) || !require_tshark(why) {
        return;
    }
    // Seeds from the clock, printed with every run: a failure names the seed to run again.
    let base = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(1, |d| d.as_secs() % 1_000_000 * 10);
    let _hog = Hog::start();
    let wrong: Vec<String> = std::thread::scope(|s| {
        let enip = s.spawn(|| {
            let _served = common::serve(&ENIP_SERVED, "tu3-eip", 1800);
            shuffled_runs(
                None,
                "tu3-eip@enip",
                &format!("enip://{}", *ENIP_SERVED),
                base,
                None,
            )
        });
        let ecat = s.spawn(|| {
            let ns = Netns::new("loadecat");
            let served =
                harness::ecat_serve::start(&harness::ecat_serve::ServeOptions::new(ns.root_if()))
                    .expect("serve ecat");
            let (profile, dut) = ("sk550p@ecat", format!("ecat://{}", ns.ns_if()));
            let wire = SuiteRun::shuffled(&ns, "load-ecat", profile, &dut, base);
            let wrong = shuffled_runs(Some(&ns), profile, &dut, base, Some(wire.verdicts()));
            let stats = served.stop().expect("the slave served to the end");
            common::ecat_wire::check(&wire, &stats);
            wire.finish();
            wrong
        });
        let epl = s.spawn(|| {
            let ns = Netns::new("loadepl");
            ns.add_ipv4("192.168.100.1/24", "192.168.100.240/24");
            let mut options = harness::epl_serve::ServeOptions::new(ns.root_if());
            options.profile = "tu4-pol".into();
            let served = harness::epl_serve::start(&options).expect("serve epl");
            let wrong = shuffled_runs(
                Some(&ns),
                "tu4-pol@epl",
                &format!("epl://{}", ns.ns_if()),
                base,
                None,
            );
            served.stop().expect("the node served to the end");
            wrong
        });
        let pnio = s.spawn(|| {
            let ns = Netns::new("loadpnio");
            ns.add_ipv4("192.168.20.200/24", "192.168.20.1/24");
            let mut options = harness::pnio_serve::ServeOptions::new(ns.root_if());
            options.name = PNIO_NAME.into();
            let served = harness::pnio_serve::start(&options).expect("serve pnio");
            let (profile, dut) = ("sk550p@pnio", format!("pnio://{}/{PNIO_NAME}", ns.ns_if()));
            let wire = SuiteRun::shuffled(&ns, "load-pnio", profile, &dut, base);
            let wrong = shuffled_runs(Some(&ns), profile, &dut, base, Some(wire.verdicts()));
            let stats = served.stop().expect("the device served to the end");
            common::pnio_wire::check(&wire, "sk550p", &stats);
            wire.finish();
            wrong
        });
        [enip, ecat, epl, pnio]
            .into_iter()
            .flat_map(|h| h.join().expect("a bus's runs end"))
            .collect()
    });
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}
