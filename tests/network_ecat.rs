//! The harness's EtherCAT suites over the wire: `harness serve ecat` on one end of a veth pair,
//! `harness run --dut ecat://IFACE` inside a network namespace on the other, every suite of the
//! `sk550p` profile over EtherCAT (manual-level cases over CoE and PDOs, the `ecat:` suites,
//! the bad-input cases). The run must end with no case failed or in error, and tshark, taking
//! its own capture on the wire meanwhile, must dissect the traffic as EtherCAT (`ecat`,
//! `ecat_mailbox` with CoE) with no malformed frame but those of steps that send malformed
//! bytes on purpose; `--pcap` writes the run's own capture, whose packet comments name each
//! frame's case and step.
//!
//! Needs root (network namespaces, raw sockets) and tshark (`.ci/interop-setup`); without
//! them the test says so and skips on a developer's machine, and fails when `CI` is set.

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

use harness::ecat_serve::{start, ServeOptions};
use pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketOption;
use pcap_file::pcapng::{Block, PcapNgReader};

#[allow(dead_code)] // what the EtherNet/IP tests share
mod common;
use common::netns::{require_root_or_skip, Netns};
use common::peer::require_tshark;
use common::suite_run::SuiteRun;

/// Every packet of a pcapng file: its bytes and its comment (the harness's label).
fn packets(path: &Path) -> Vec<(Vec<u8>, Option<String>)> {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = PcapNgReader::new(file).expect("a pcapng file");
    let mut out = Vec::new();
    while let Some(block) = reader.next_block() {
        if let Block::EnhancedPacket(p) = block.expect("a pcapng block") {
            let comment = p.options.iter().find_map(|o| match o {
                EnhancedPacketOption::Comment(c) => Some(c.to_string()),
                _ => None,
            });
            out.push((p.data.to_vec(), comment));
        }
    }
    out
}

/// The numbers (from 1) of the frames tshark finds malformed in a capture, and the protocols
/// it dissected in it.
fn dissect(path: &Path) -> (Vec<usize>, HashMap<String, usize>) {
    let out = Command::new("tshark")
        .arg("-r")
        .arg(path)
        .args([
            "-T",
            "fields",
            "-e",
            "frame.number",
            "-e",
            "frame.protocols",
        ])
        .args(["-e", "_ws.malformed", "-e", "ecat_mailbox.coe"])
        .output()
        .expect("tshark runs");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut malformed = Vec::new();
    let mut protocols: HashMap<String, usize> = HashMap::new();
    for line in String::from_utf8_lossy(&out.stdout).lines() {
        let f: Vec<&str> = line.split('\t').collect();
        let number: usize = f[0].parse().expect("a frame number");
        for p in f.get(1).unwrap_or(&"").split(':') {
            *protocols.entry(p.to_string()).or_default() += 1;
        }
        if f.get(2).is_some_and(|m| !m.is_empty()) {
            malformed.push(number);
        }
        if f.get(3).is_some_and(|c| !c.is_empty()) {
            *protocols.entry("coe".into()).or_default() += 1;
        }
    }
    (malformed, protocols)
}

/// Whether a label names a step that sends bytes as a suite writes them, malformed on
/// purpose: an `ecat: {frame: …}`, `{datagram: …}` or `{mailbox: …}` step. Every other frame
/// is built by the master's codecs.
fn on_purpose(label: &str) -> bool {
    label.split_once(": ").is_some_and(|(head, step)| {
        head.contains(" step ")
            && ["ecat frame ", "ecat datagram ", "ecat mailbox "]
                .iter()
                .any(|p| step.starts_with(p))
    })
}

#[test]
fn every_ethercat_suite_passes_against_the_served_slave_over_a_veth_pair() {
    // On a loaded host when `.ci/run` asks (NORD_TEST_HOG): the verdicts must hold there too.
    let _hog = common::hog::Hog::if_asked();
    let why = "the EtherCAT suites against harness serve ecat over a veth pair";
    if !require_root_or_skip(why) {
        return;
    }
    if !require_tshark(why) {
        return;
    }
    let ns = Netns::new("ecsuites");
    let served = start(&ServeOptions::new(ns.root_if())).expect("serve ecat");
    let run = SuiteRun::new(
        &ns,
        "ecat",
        "sk550p@ecat",
        &format!("ecat://{}", ns.ns_if()),
    );
    let stats = served.stop().expect("the slave served to the end");
    // The EtherCAT suites and the manual-level cases ran.
    run.assert_passed(&[
        ("bu0620/ecat-al/", 5),
        ("bu0620/ecat-sdo-abort/", 5),
        ("bu0620/ecat-coe/", 5),
        ("bu0620/ecat-pdo/", 4),
        ("bu0620/ecat-watchdog/", 3),
        ("bu0620/ecat-hot-connect/", 2),
        ("bu0620/drive-switching/", 5),
        ("ecat/", 30),
    ]);
    assert!(stats.frames > 10_000, "{stats:?}");

    // tshark dissects both captures as EtherCAT with mailbox and CoE.
    let (run_pcap, wire_pcap) = (&run.run_pcap, &run.wire_pcap);
    let (run_bad, run_protocols) = dissect(run_pcap);
    let (wire_bad, wire_protocols) = dissect(wire_pcap);
    for (path, protocols) in [(run_pcap, run_protocols), (wire_pcap, wire_protocols)] {
        for p in ["ecatf", "ecat", "ecat_mailbox", "coe"] {
            assert!(
                protocols.get(p).is_some_and(|n| *n > 100),
                "{}: {p} in {protocols:?}",
                path.display()
            );
        }
    }

    // The only malformed frames are those of steps sending malformed bytes on purpose. The
    // run's own capture labels each frame; a frame of the wire capture takes the label of the
    // run's frame with the same bytes.
    let run_packets = packets(run_pcap);
    let label_of: HashMap<&[u8], &str> = run_packets
        .iter()
        .filter_map(|(bytes, c)| c.as_deref().map(|c| (bytes.as_slice(), c)))
        .collect();
    let wire_packets = packets(wire_pcap);
    let mut wrong = Vec::new();
    for n in &run_bad {
        let label = run_packets[n - 1].1.as_deref().unwrap_or("(no label)");
        if !on_purpose(label) {
            wrong.push(format!("run.pcapng frame {n}: {label}"));
        }
    }
    for n in &wire_bad {
        // The wire pads short frames to 60 bytes; the run's capture has them as sent.
        let bytes = wire_packets[n - 1].0.as_slice();
        let label = label_of
            .iter()
            .find(|(b, _)| bytes.starts_with(b) && bytes[b.len()..].iter().all(|x| *x == 0))
            .map(|(_, l)| *l)
            .unwrap_or("(no frame of the run has these bytes)");
        if !on_purpose(label) {
            wrong.push(format!("wire.pcapng frame {n}: {label}"));
        }
    }
    assert!(
        wrong.is_empty(),
        "malformed outside the bad-input steps:\n{}",
        wrong.join("\n")
    );
    assert!(
        !run_bad.is_empty(),
        "the bad-input cases send malformed frames, and tshark should see them"
    );
    run.finish();
}

/// `harness run` of the cases whose id contains `filter` for `profile` against `dut` from
/// inside `ns`: the report's cases (the connection check's, when the run stopped there).
fn cases_of_run(ns: &Netns, profile: &str, dut: &str, filter: &str) -> Vec<serde_json::Value> {
    let dir = std::env::temp_dir().join(format!("harness-late-{}-{profile}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let suites = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../suites");
    let run = ns
        .command(env!("CARGO_BIN_EXE_harness"))
        .args(["run", "--profile", profile, "--suites"])
        .arg(&suites)
        .args(["--filter", filter, "--dut", dut, "--allow-motion", "--out"])
        .arg(&dir)
        .output()
        .expect("harness run starts");
    let report: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("run.json")).expect("run.json written"),
    )
    .unwrap_or_else(|e| panic!("{e}: {}", String::from_utf8_lossy(&run.stdout)));
    let _ = std::fs::remove_dir_all(&dir);
    report["cases"].as_array().expect("cases").clone()
}

/// A slave whose frames come back later than the master's limit for a frame (50 ms; ETG.1000
/// prints none) is late, and the report says so with both times — the limit and how long the
/// harness waited — while the host was on time: never "host late", never a pass. The frames
/// are late from the scan on, so the run ends at its connection check (the runner's verdict
/// for a DUT that does not answer in time there).
#[test]
fn a_slave_whose_frames_come_back_past_the_limit_is_late_with_both_times() {
    let why = "a late EtherCAT slave (serve ecat --reply-delay) over a veth pair";
    if !require_root_or_skip(why) {
        return;
    }
    let ns = Netns::new("eclate");
    let options = ServeOptions {
        reply_delay: std::time::Duration::from_millis(80),
        ..ServeOptions::new(ns.root_if())
    };
    let served = start(&options).expect("serve ecat");
    let dut = format!("ecat://{}", ns.ns_if());
    let cases = cases_of_run(&ns, "sk550p@ecat", &dut, "bu0620/ecat-al/");
    served.stop().expect("the slave served to the end");
    assert_eq!(cases.len(), 1, "{cases:?}");
    let (verdict, message) = (&cases[0]["verdict"], cases[0]["message"].as_str().unwrap());
    assert_eq!(verdict, "error", "{message}");
    assert!(
        message.contains("a frame back: no answer within the device's limit of 50 ms (waited "),
        "{message}"
    );
    assert!(!message.contains("host late"), "{message}");
}
