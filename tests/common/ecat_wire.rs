//! What the EtherCAT wire must show of a full `sk550p@ecat` run against `harness serve ecat`
//! ([`check`]): the EtherCAT suites and the manual-level cases passed, and tshark dissects the
//! run's own capture and its capture of the wire as EtherCAT (`ecat`, `ecat_mailbox` with CoE)
//! with no malformed frame but those of steps that send malformed bytes on purpose. The load
//! test makes this run as the first of its five against the served slave.

use std::collections::HashMap;
use std::path::Path;

use harness::ecat_serve::Stats;
use pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketOption;
use pcap_file::pcapng::{Block, PcapNgReader};

use super::suite_run::SuiteRun;

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
    let out = super::tshark::fields(
        path,
        &[
            "frame.number",
            "frame.protocols",
            "_ws.malformed",
            "ecat_mailbox.coe",
        ],
    );
    let mut malformed = Vec::new();
    let mut protocols: HashMap<String, usize> = HashMap::new();
    for line in out.lines() {
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

/// Checks the run and both its captures; `stats` are the served slave's (of this run and any
/// after it). Panics with what is wrong.
pub(crate) fn check(run: &SuiteRun, stats: &Stats) {
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
}
