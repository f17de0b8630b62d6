//! No motor turns unless the user says so: a full `harness run --dut enip://…` of every suite
//! against the served simulator, captured with `--pcap`, without `--allow-motion`. Every frame
//! that can carry a control word toward the device is decoded here, apart from the harness's
//! own classification: the class-1 O→T data (UDP 2222) and the explicit messages that write
//! an assembly (class 04h) or a NORD parameter (class 100 + FI, attribute = parameter number:
//! BU 2100 §6.3), also inside Unconnected_Send and Multiple_Service. None may carry an
//! enabling control word (bits 0–3 set: "Enable operation", BU 0620 §6.1.2.1) or write a
//! parameter that can start the drive. The run reports the cases that would have as not
//! applicable; the same run with `--allow-motion` does send enabling words, so the decoding
//! finds them when they are there. And a case whose EEPROM writes exceed `--max-eeprom-writes`
//! does not run.

use std::collections::HashMap;
use std::net::Ipv4Addr;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::LazyLock;

use serde_json::Value;

#[allow(dead_code)] // what the other network tests share
mod common;
use common::addr::free_loopback;
use common::{case_verdict, serve};

/// Where the served simulator listens, and the harness's own address: each an address of its
/// own, whatever else runs on this host.
static DEVICE: LazyLock<Ipv4Addr> = LazyLock::new(free_loopback);
static LOCAL: LazyLock<String> = LazyLock::new(|| free_loopback().to_string());

/// The inverter parameters whose write can start a drive (BU 0620 §4.5, §5.2, §6.1.2.1;
/// BU 0590 §6.3).
const STARTING: [u16; 11] = [420, 421, 422, 423, 424, 425, 470, 480, 506, 509, 510];

/// What was found in the frames toward the device.
#[derive(Default, Debug)]
struct Findings {
    /// Class-1 O→T frames decoded.
    io_frames: usize,
    /// Explicit Set_Attribute requests decoded.
    sets: usize,
    /// Enabling control words and starting parameter writes, one line each.
    violations: Vec<String>,
}

impl Findings {
    /// Every 16-bit word of output data, at every even offset (the assembly layout and the
    /// run/idle header, 4 bytes, keep the words even): any with bits 0–3 set enables.
    fn words(&mut self, what: &str, data: &[u8]) {
        for (k, w) in data.chunks_exact(2).enumerate() {
            let w = u16::from_le_bytes([w[0], w[1]]);
            if w & 0x000F == 0x000F {
                self.violations
                    .push(format!("{what}: word {k} = {w:04X}h enables operation"));
            }
        }
    }

    /// A message-router request (CIP Vol 1 §2-4.1): service, path size in words, path, data.
    fn request(&mut self, what: &str, bytes: &[u8]) {
        let (Some(&service), Some(&words)) = (bytes.first(), bytes.get(1)) else {
            return;
        };
        let path_end = 2 + 2 * usize::from(words);
        let (Some(path), Some(data)) = (bytes.get(2..path_end), bytes.get(path_end..)) else {
            return;
        };
        let (class, attribute) = logical(path);
        match service {
            // Set_Attribute_Single, Set_Attributes_All.
            0x10 | 0x02 => {
                self.sets += 1;
                match (class, attribute) {
                    (Some(4), _) => self.words(&format!("{what}: assembly write"), data),
                    (Some(c @ 101..=108), Some(p)) if STARTING.contains(&p) => self
                        .violations
                        .push(format!("{what}: P{p} of FI {} written", c - 100)),
                    _ => {}
                }
            }
            // Unconnected_Send: priority/tick, timeout ticks, message size, the message.
            0x52 => {
                if let Some(size) = data.get(2..4) {
                    let size = usize::from(u16::from_le_bytes([size[0], size[1]]));
                    let end = (4 + size).min(data.len());
                    self.request(what, &data[4.min(end)..end]);
                }
            }
            // Multiple_Service: count, offsets from the count, the requests.
            0x0A => {
                let word = |at: usize| {
                    data.get(at..at + 2)
                        .map(|b| usize::from(u16::from_le_bytes([b[0], b[1]])))
                };
                let count = word(0).unwrap_or(0);
                let mut offsets: Vec<usize> = (0..count).filter_map(|k| word(2 + 2 * k)).collect();
                offsets.push(data.len());
                for w in offsets.windows(2) {
                    if let Some(r) = data.get(w[0]..w[1].max(w[0])) {
                        self.request(what, r);
                    }
                }
            }
            _ => {}
        }
    }

    /// Encapsulation messages as far as `bytes` holds them (CIP Vol 2 §2-3.2: command,
    /// length, session, status, context, options; then the data): SendRRData's unconnected
    /// and SendUnitData's connected data items carry requests.
    fn encapsulation(&mut self, what: &str, mut bytes: &[u8]) {
        while bytes.len() >= 24 {
            let command = u16::from_le_bytes([bytes[0], bytes[1]]);
            let len = usize::from(u16::from_le_bytes([bytes[2], bytes[3]]));
            let end = (24 + len).min(bytes.len());
            let data = &bytes[24..end];
            if matches!(command, 0x6F | 0x70) {
                // Interface handle 4, timeout 2, then the item list.
                for (kind, item) in items(data.get(6..).unwrap_or_default()) {
                    match kind {
                        0x00B2 => self.request(what, item),
                        0x00B1 => self.request(what, item.get(2..).unwrap_or_default()),
                        _ => {}
                    }
                }
            }
            bytes = &bytes[end..];
        }
    }

    /// A class-1 I/O datagram (CIP Vol 2 §3-2.2): the item list, whose connected data item
    /// holds the sequence count and the output data (after the run/idle header, if any).
    fn io(&mut self, what: &str, datagram: &[u8]) {
        for (kind, item) in items(datagram) {
            if kind == 0x00B1 {
                self.io_frames += 1;
                self.words(what, item.get(2..).unwrap_or_default());
            }
        }
    }
}

/// A common packet format list: item count, then type, length and data of each, walked as far
/// as the bytes go (a list that lies about its lengths is what some cases send on purpose).
fn items(list: &[u8]) -> Vec<(u16, &[u8])> {
    let word = |at: usize| {
        list.get(at..at + 2)
            .map(|b| u16::from_le_bytes([b[0], b[1]]))
    };
    let mut out = Vec::new();
    let mut at = 2;
    while let (Some(kind), Some(len)) = (word(at), word(at + 2)) {
        let end = (at + 4 + usize::from(len)).min(list.len());
        out.push((kind, &list[at + 4..end]));
        at = end;
    }
    out
}

/// The class and attribute of a logical path (8- and 16-bit class, instance and attribute
/// segments, CIP Vol 1 Appendix C).
fn logical(path: &[u8]) -> (Option<u16>, Option<u16>) {
    let (mut class, mut attribute) = (None, None);
    let mut at = 0;
    while let Some(&seg) = path.get(at) {
        let (value, len) = match seg & 0x03 {
            0 => (path.get(at + 1).map(|v| u16::from(*v)), 2),
            1 => (
                path.get(at + 2..at + 4)
                    .map(|v| u16::from_le_bytes([v[0], v[1]])),
                4,
            ),
            _ => return (class, attribute),
        };
        match seg & 0xFC {
            0x20 => class = value,
            0x24 => {}
            0x30 => attribute = value,
            _ => return (class, attribute),
        }
        at += len;
    }
    (class, attribute)
}

/// Every frame of the capture toward the device, decoded. TCP segments are decoded each on its
/// own and, reassembled, each connection's stream as a whole.
fn decode(pcap: &Path) -> Findings {
    let bytes = std::fs::read(pcap).expect("the run's pcapng");
    let mut reader = pcap_file::pcapng::PcapNgReader::new(&bytes[..]).expect("a pcapng file");
    let mut findings = Findings::default();
    let mut streams: HashMap<(u32, u16), Vec<u8>> = HashMap::new();
    let mut n = 0;
    while let Some(block) = reader.next_block() {
        let Some(epb) = block.expect("a pcapng block").into_enhanced_packet() else {
            continue;
        };
        n += 1;
        let what = format!("packet {n}");
        let frame = &epb.data[..];
        // Ethernet II, IPv4.
        let Some(ip) = frame.get(14..) else { continue };
        if frame[12..14] != [0x08, 0x00] || ip.len() < 20 {
            continue;
        }
        let ihl = usize::from(ip[0] & 0x0F) * 4;
        let (src, dst) = (
            u32::from_be_bytes([ip[12], ip[13], ip[14], ip[15]]),
            Ipv4Addr::new(ip[16], ip[17], ip[18], ip[19]),
        );
        let Some(l4) = ip.get(ihl..) else { continue };
        if dst != *DEVICE || l4.len() < 8 {
            continue;
        }
        let dst_port = u16::from_be_bytes([l4[2], l4[3]]);
        let src_port = u16::from_be_bytes([l4[0], l4[1]]);
        match (ip[9], dst_port) {
            (17, 2222) => findings.io(&what, &l4[8..]),
            (6, 44818) => {
                let payload = l4
                    .get(usize::from(l4.get(12).copied().unwrap_or(0) >> 4) * 4..)
                    .unwrap_or_default();
                findings.encapsulation(&what, payload);
                streams
                    .entry((src, src_port))
                    .or_default()
                    .extend_from_slice(payload);
            }
            _ => {}
        }
    }
    let mut stream_findings = Findings::default();
    for ((_, port), stream) in &streams {
        stream_findings.encapsulation(&format!("TCP stream from port {port}"), stream);
    }
    findings.violations.extend(stream_findings.violations);
    findings
}

/// `harness run` of every suite under `tu3-eip` against the served simulator, with `extra`
/// options, captured to `dir/run.pcapng`; returns run.json, the capture's file and the
/// console output. The run must pass unless `may_fail` (the drive examples run on the
/// device's own clock, and a loaded machine can make one late).
fn run(dir: &Path, extra: &[&str], may_fail: bool) -> (Value, PathBuf, String) {
    let pcap = dir.join("run.pcapng");
    let out = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["run", "--profile", "tu3-eip", "--local", &LOCAL])
        .arg("--dut")
        .arg(format!("enip://{}:44818", *DEVICE))
        .args(extra)
        .arg("--pcap")
        .arg(&pcap)
        .arg("--out")
        .arg(dir.join("reports"))
        .output()
        .expect("harness runs");
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let expected: &[i32] = if may_fail { &[0, 1] } else { &[0] };
    assert!(
        out.status.code().is_some_and(|c| expected.contains(&c)),
        "{:?}\n{stdout}",
        out.status
    );
    let run: Value =
        serde_json::from_slice(&std::fs::read(dir.join("reports/run.json")).unwrap()).unwrap();
    (run, pcap, stdout)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("harness-motion-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

const SWITCHING: &str = "bu0620/drive-switching/switching-example";

/// Takes about half a minute of real time: the whole run without `--allow-motion`, where the
/// drive examples do not run, and the switching example with it, on the device's own clock.
#[test]
fn no_enabling_control_word_leaves_the_harness_without_allow_motion() {
    // On a loaded host when `.ci/run` asks (NORD_TEST_HOG): the verdicts must hold there too.
    let _hog = common::hog::Hog::if_asked();
    let _server = serve(&format!("{}:44818", *DEVICE), "tu3-eip", 900);

    // Without the flag.
    let dir = scratch("default");
    let (run, pcap, stdout) = run(&dir, &[], false);
    let found = decode(&pcap);
    assert!(
        found.violations.is_empty(),
        "{}",
        found.violations.join("\n")
    );
    // The decoding saw what carries control words and parameters.
    assert!(found.io_frames > 100, "{found:?}");
    assert!(found.sets > 3, "{found:?}");
    let (v, why) = case_verdict(&run, SWITCHING);
    assert_eq!(v, "not_applicable");
    assert!(
        why.starts_with("motion not allowed (--allow-motion): control word 047Fh"),
        "{why}"
    );
    let refused = run["cases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| {
            c["message"]
                .as_str()
                .is_some_and(|m| m.starts_with("motion not allowed (--allow-motion)"))
        })
        .count();
    assert!(refused >= 10, "{refused} cases refused:\n{stdout}");
    // A refused case sent nothing: not even its opening.
    assert!(!pcap_labels(&pcap).iter().any(|l| l.contains(SWITCHING)));

    // With the flag the switching example sends enabling words, and the decoding finds them
    // (the whole run with the flag is the load test's, `network_load`).
    let dir_motion = scratch("allow-motion");
    let (run, pcap, stdout) = self::run(
        &dir_motion,
        &["--allow-motion", "--filter", SWITCHING],
        true,
    );
    assert_ne!(
        case_verdict(&run, SWITCHING).0,
        "not_applicable",
        "{stdout}"
    );
    let found = decode(&pcap);
    assert!(
        found
            .violations
            .iter()
            .any(|v| v.contains("= 047Fh enables operation")),
        "{found:?}"
    );

    // A case whose EEPROM writes (P102, and its restore) exceed the cap does not run.
    let dir_cap = scratch("eeprom-cap");
    let (run, _, _) = self::run(
        &dir_cap,
        &[
            "--filter",
            "bu0620/pkw-dut/resolution-99-99-s",
            "--max-eeprom-writes",
            "1",
        ],
        false,
    );
    let (v, why) = case_verdict(&run, "bu0620/pkw-dut/resolution-99-99-s");
    assert_eq!(v, "not_applicable");
    assert!(
        why.starts_with("EEPROM write cap reached (--max-eeprom-writes 1)"),
        "{why}"
    );
    for d in [dir, dir_motion, dir_cap] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// The packet comments of a capture: the profile, case and step that produced each packet.
fn pcap_labels(pcap: &Path) -> Vec<String> {
    let bytes = std::fs::read(pcap).unwrap();
    let mut reader = pcap_file::pcapng::PcapNgReader::new(&bytes[..]).unwrap();
    let mut labels = Vec::new();
    while let Some(block) = reader.next_block() {
        if let Some(epb) = block.unwrap().into_enhanced_packet() {
            for o in &epb.options {
                if let pcap_file::pcapng::blocks::enhanced_packet::EnhancedPacketOption::Comment(
                    c,
                ) = o
                {
                    labels.push(c.to_string());
                }
            }
        }
    }
    labels
}
