//! Independent EtherNet/IP clients against the served simulator: pycomm3 and cpppo read and
//! write NORD parameters over `harness serve enip` and get the values and CIP status codes the
//! manuals imply (BU 2100 §6.3: class 100 + FI, instance from set/element, attribute = P-number).
//!
//! The clients live in a venv that `.ci/interop-setup` installs (`cargo xtask test` runs it).
//! Without that venv the test says so and skips (fails in strict mode): the peers are
//! third-party packages from PyPI.
//!
//! tshark (installed by the same script) judges `harness run --pcap` of full EtherNet/IP runs
//! (every suite): the pcapng of an embedded run, and that of a run against the served simulator
//! beside one tshark took on the wire, dissect as `enip`/`cip`/`cipio`, and the only frames
//! tshark flags (malformed, or an expert item of warning or above) are bytes that suites/cip
//! breaks on purpose, told apart by each packet's comment naming its case and step. Capturing
//! on `lo` needs root (CI runs as root); without tshark or root those tests skip.
//!
//! The other way round, the harness runs the generic profile `cip` (`suites/cip/`) against
//! cpppo's server: every place cpppo departs from CIP comes out as a failure that names the
//! rule, never as a harness error, and the cases cpppo gets right pass.

use std::collections::{BTreeSet, HashMap, HashSet, VecDeque};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

#[allow(dead_code)] // what the other network tests share
mod common;
use common::addr::free_loopback;
use common::peer::{interop_python, is_root, require_or_skip, require_tshark};
use common::{serve, wait_listening, Server};

fn python(why: &str) -> Option<PathBuf> {
    interop_python(&["pycomm3", "cpppo"], why)
}

/// Runs a client script; one JSON object per operation.
fn client(py: &PathBuf, script: &str, target: &[&str], ops: &[&str]) -> Vec<Value> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/interop");
    let out = Command::new(py)
        .arg(dir.join(script))
        .args(target)
        .args(["--timeout", "3"])
        .args(ops)
        .output()
        .expect("client runs");
    assert!(
        out.status.success(),
        "{script}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter(|l| l.starts_with('{'))
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect()
}

#[test]
fn pycomm3_and_cpppo_read_and_write_parameters_of_the_served_simulator() {
    let Some(py) = python("pycomm3 and cpppo against harness serve enip") else {
        return;
    };
    let listen = format!("{}:44818", free_loopback());
    let _server = serve(&listen, "tu3-eip", 600);
    let (host, port) = listen.split_once(':').unwrap();
    // FI 1 P102 (class 101, instance 0 = set 1, attribute 102): write 1000 (10.00 s), read back.
    // FI 2 P400 [-03] set 3: instance 14 (BU 2100 §6.3 example, class 102).
    let r = client(
        &py,
        "pycomm3_client.py",
        &["--host", host, "--port", port],
        &[
            "set", "101", "0", "102", "1000", "get", "101", "0", "102", "get", "102", "14", "400",
            "get", "101", "0", "998", "get", "109", "0", "102", "set", "101", "0", "102", "40000",
            "identity",
        ],
    );
    assert_eq!(r.len(), 7, "{r:?}");
    assert_eq!(r[0]["ok"], true, "{}", r[0]);
    assert_eq!(r[1]["value"], 1000, "{}", r[1]);
    assert_eq!(r[2]["ok"], true, "{}", r[2]);
    // Unknown parameter: attribute not supported (14h). FI 9 does not exist: path destination
    // unknown (05h). 40000 is beyond P102's range: invalid attribute value (09h).
    assert_eq!(r[3]["status"], 0x14, "{}", r[3]);
    assert_eq!(r[4]["status"], 0x05, "{}", r[4]);
    assert_eq!(r[5]["status"], 0x09, "{}", r[5]);
    assert_eq!(r[6]["identity"]["product_name"], "SK TU3-EIP", "{}", r[6]);
    assert_eq!(r[6]["identity"]["vendor_id"], 834, "{}", r[6]);

    // cpppo sees what pycomm3 wrote.
    let r = client(
        &py,
        "cpppo_client.py",
        &[&listen],
        &[
            "get", "101", "0", "102", "set", "101", "0", "102", "250", "get", "101", "0", "102",
            "set", "101", "0", "172", "1",
        ],
    );
    assert_eq!(r.len(), 4, "{r:?}");
    assert_eq!(r[0]["value"], 1000, "{}", r[0]);
    assert_eq!(r[1]["ok"], true, "{}", r[1]);
    assert_eq!(r[2]["value"], 250, "{}", r[2]);
    // P172 is an information parameter of the interface, not of FI 1: attribute not supported.
    assert_eq!(r[3]["ok"], false, "{}", r[3]);
}

// --- `harness run --pcap`: the run's own capture, and one taken on the wire by tshark --------
//
// The captured run is a full EtherNet/IP run: every suite under one profile, suites/cip's
// malformed requests included. tshark rightly flags those (malformed, or an expert warning),
// so "nothing flagged" cannot hold; what must hold, frame by frame, is that tshark flags only
// bytes a step breaks on purpose. Each packet of the run's pcapng names its profile, case and
// step in its comment (`frame.comment`); a frame of the wire capture takes the comment of the
// run's frame it matches.

/// Fields of a dissected frame that the checks read (`tshark -T json -e …`).
const FIELDS: [&str; 24] = [
    "frame.number",
    "frame.time_relative",
    "frame.protocols",
    "frame.comment",
    "ip.src",
    "ip.dst",
    "tcp.stream",
    "tcp.srcport",
    "tcp.dstport",
    "tcp.len",
    "tcp.flags.syn",
    "tcp.flags.fin",
    "udp.srcport",
    "udp.dstport",
    "icmp.type",
    "icmp.code",
    "enip.command",
    "enip.status",
    "enip.response_to",
    "cip.service",
    "cip.genstat",
    "_ws.malformed",
    "_ws.expert.severity",
    "_ws.expert.message",
];

/// Expert severity `warning` (`_ws.expert.severity`: comment 0x100000, chat 0x200000, note
/// 0x400000, warning 0x600000, error 0x800000). A packet comment is an expert item of the
/// lowest severity.
const WARNING: u64 = 0x0060_0000;

/// The verification of IPv4, TCP and UDP checksums, off by default in tshark. Only for
/// synthesized captures: on `lo` the kernel leaves checksums to an offload that never happens.
const CHECKSUMS: [&str; 6] = [
    "-o",
    "ip.check_checksum:TRUE",
    "-o",
    "tcp.check_checksum:TRUE",
    "-o",
    "udp.check_checksum:TRUE",
];

/// One frame as tshark dissected it: each of [`FIELDS`] with all its occurrences.
#[derive(Debug)]
struct Frame(serde_json::Map<String, Value>);

impl Frame {
    fn all(&self, field: &str) -> Vec<&str> {
        self.0
            .get(field)
            .and_then(Value::as_array)
            .map(|a| a.iter().filter_map(Value::as_str).collect())
            .unwrap_or_default()
    }

    /// The first occurrence of a field, or "".
    fn get(&self, field: &str) -> &str {
        debug_assert!(FIELDS.contains(&field), "{field}");
        self.all(field).first().copied().unwrap_or("")
    }

    fn flag(&self, field: &str) -> bool {
        // tshark 4.0 prints booleans as 1/0, later versions as True/False.
        matches!(self.get(field), "1" | "True" | "true")
    }

    fn number(&self, field: &str) -> u64 {
        let v = self.get(field);
        match v.strip_prefix("0x") {
            Some(hex) => u64::from_str_radix(hex, 16).unwrap_or(u64::MAX),
            None => v.parse().unwrap_or(0),
        }
    }

    fn protocols(&self) -> Vec<&str> {
        self.get("frame.protocols").split(':').collect()
    }

    fn is_tcp(&self) -> bool {
        !self.get("tcp.srcport").is_empty()
    }

    fn is_icmp(&self) -> bool {
        !self.get("icmp.type").is_empty()
    }

    /// A class-1 I/O datagram (not one quoted by ICMP).
    fn is_io(&self) -> bool {
        !self.is_icmp() && (self.get("udp.srcport") == "2222" || self.get("udp.dstport") == "2222")
    }

    fn malformed(&self) -> bool {
        !self.all("_ws.malformed").is_empty()
    }

    /// What tshark flags in the frame: the messages of its expert items of warning severity
    /// or above, and `malformed` if it is; empty for a clean frame.
    fn flags(&self) -> Vec<&str> {
        let severities = self.all("_ws.expert.severity");
        let messages = self.all("_ws.expert.message");
        assert_eq!(severities.len(), messages.len(), "{self:?}");
        let mut flags: Vec<&str> = severities
            .iter()
            .zip(&messages)
            .filter(|(s, _)| s.parse::<u64>().expect("numeric severity") >= WARNING)
            .map(|(_, m)| *m)
            .collect();
        if self.malformed() {
            flags.push("malformed");
        }
        flags
    }
}

/// A frame's label, as the harness writes it into the packet comment (`pcap::Tap::label`):
/// `<profile> <case> step <n>: <the step as the report shows it>`, or `<profile> <case>: open`
/// (opening the case's connections) and `<profile> <case> cleanup` (leaving the DUT as the
/// case found it, closing the connections). The case, step number and step text of a step's
/// label; `None` for the others.
fn parse_label(label: &str) -> Option<(&str, u32, &str)> {
    let (head, step) = label.split_once(": ")?;
    match head.split(' ').collect::<Vec<_>>()[..] {
        [_profile, case, "step", n] => Some((case, n.parse().ok()?, step)),
        _ => None,
    }
}

/// Whether a label names a step that sends malformed bytes on purpose: an `enip: {raw: …}`
/// step (encapsulation bytes as the suite writes them: lying lengths, bad CPF…) or an
/// `enip: {mr: …}` step (message-router bytes: cut EPATHs, reserved segments…) of a case of
/// `suites/cip/`. Every other step's messages are built by the harness's codecs.
fn on_purpose(label: &str) -> bool {
    parse_label(label).is_some_and(|(case, _, step)| {
        case.starts_with("cip/")
            && (step.starts_with("enip raw ") || step.starts_with("enip message-router request "))
    })
}

/// Every frame of a capture, dissected.
fn dissect(path: &Path, checksums: bool) -> Vec<Frame> {
    let mut args = vec!["-T", "json"];
    for f in FIELDS {
        args.extend(["-e", f]);
    }
    let json: Value = serde_json::from_str(&tshark(path, checksums, &args))
        .unwrap_or_else(|e| panic!("tshark -T json on {}: {e}", path.display()));
    let frames: Vec<Frame> = json
        .as_array()
        .expect("an array of packets")
        .iter()
        .map(|p| Frame(p["_source"]["layers"].as_object().expect("layers").clone()))
        .collect();
    assert!(!frames.is_empty(), "{}: no frames", path.display());
    frames
}

/// What [`judge`] found in a capture.
#[derive(Debug, Default)]
struct Judged {
    /// Steps with traffic (their labels).
    steps: BTreeSet<String>,
    /// Steps with a frame tshark flags: every one breaks bytes on purpose.
    flagged: BTreeSet<String>,
    /// Frames tshark flags, of how many.
    flagged_frames: (usize, usize),
    /// Replies of the DUT that tshark flags only by repeating the warning of the request
    /// they answer (see [`judge`]).
    echoes: Vec<String>,
    /// ICMP port-unreachable messages for T→O data (wire captures only).
    unreachable: usize,
}

/// Judges every frame of a capture of a full run; `labels[i]` is frame i's label (its
/// comment, or that of the run's frame it matches). Panics listing every frame that breaks
/// one of these rules:
///
/// - A frame of the scanner that tshark flags belongs to a step that breaks bytes on purpose
///   ([`on_purpose`]).
/// - A frame of the DUT is never flagged, with one exception, narrowly: tshark dissects a
///   CIP reply against the path of the request it answers (the reply tree shows the generated
///   `[Request Path]`) and so repeats that path's warnings (e.g. `Unsupported Segment Type` for
///   the reserved segment type E0h) on a reply that is right (04h path segment error). Such a
///   reply is not malformed, refuses the request (general status ≠ 0), answers
///   (`enip.response_to`) a flagged request of the same on-purpose step, and every flag it
///   carries the request carries too.
/// - Every frame is Ethernet/IPv4; nothing is left as raw `data` or marked malformed in its
///   protocols (bytes broken on purpose excepted); TCP is on 44818, and each segment with
///   data is `enip`, each SendRRData with encapsulation status 0 also `cip`; UDP is class-1
///   I/O on 2222 dissected as `cipio`; ICMP is only a port unreachable for a T→O datagram of
///   the DUT (it reaches the scanner's 2222 after the scanner closed it at the end of a case).
/// - Exempt from the `enip` rule: the scanner's segments, on the same connection, after bytes
///   broken on purpose that tshark holds as the start of a longer message (a header
///   announcing more than it carries): tshark, like the DUT, takes them as that message's
///   rest.
fn judge(path: &Path, frames: &[Frame], labels: &[Option<&str>]) -> Judged {
    assert_eq!(frames.len(), labels.len());
    let dut = frames
        .iter()
        .find(|f| f.get("tcp.srcport") == "44818")
        .map(|f| f.get("ip.src"))
        .expect("a frame from the DUT");
    let by_number: HashMap<&str, usize> = frames
        .iter()
        .enumerate()
        .map(|(i, f)| (f.get("frame.number"), i))
        .collect();
    let mut judged = Judged::default();
    let mut wrong = Vec::new();
    // TCP streams where tshark waits for the rest of a message broken on purpose.
    let mut held: HashSet<&str> = HashSet::new();
    judged.flagged_frames.1 = frames.len();
    for (f, label) in frames.iter().zip(labels) {
        let label = *label;
        let purpose = label.is_some_and(on_purpose);
        let from_dut = f.get("ip.src") == dut;
        let mut bad = |why: String| {
            wrong.push(format!(
                "frame {} ({}): {why}",
                f.get("frame.number"),
                label.unwrap_or("no label")
            ))
        };
        if let Some(l) = label.filter(|l| parse_label(l).is_some()) {
            judged.steps.insert(l.to_string());
        }

        let flags = f.flags();
        if !flags.is_empty() {
            let allowed = if from_dut {
                let request = by_number
                    .get(f.get("enip.response_to"))
                    .map(|&r| (&frames[r], labels[r]));
                let echo = purpose
                    && !f.malformed()
                    && f.number("cip.genstat") != 0
                    && request.is_some_and(|(req, req_label)| {
                        let req_flags = req.flags();
                        req_label == label && flags.iter().all(|m| req_flags.contains(m))
                    });
                if echo {
                    judged
                        .echoes
                        .push(format!("frame {}: {flags:?}", f.get("frame.number")));
                }
                echo
            } else {
                purpose
            };
            if allowed {
                judged.flagged_frames.0 += 1;
                judged.flagged.insert(label.unwrap_or_default().to_string());
            } else {
                bad(format!(
                    "tshark flags {flags:?} in a {} frame",
                    if from_dut { "DUT" } else { "scanner" }
                ));
            }
        }

        let p = f.protocols();
        if p.len() < 3 || p[..3] != ["eth", "ethertype", "ip"] {
            bad(format!("not Ethernet/IPv4: {p:?}"));
        }
        let stream = f.get("tcp.stream");
        let exempt = !from_dut && (purpose || (f.is_tcp() && held.contains(stream)));
        if !exempt && (p.contains(&"data") || p.contains(&"_ws.malformed")) {
            bad(format!("protocols {p:?}"));
        }
        if f.is_tcp() {
            if f.get("tcp.srcport") != "44818" && f.get("tcp.dstport") != "44818" {
                bad("TCP off port 44818".into());
            }
            let data = f.number("tcp.len") > 0;
            let enip = p.contains(&"enip");
            if !from_dut && data {
                if purpose && !enip {
                    held.insert(stream);
                } else if enip {
                    held.remove(stream);
                }
            }
            if !exempt && data != enip {
                bad(format!(
                    "{} bytes of TCP data, protocols {p:?}",
                    f.get("tcp.len")
                ));
            }
            if !exempt
                && f.get("enip.command") == "0x006f"
                && f.number("enip.status") == 0
                && !p.contains(&"cip")
            {
                bad("SendRRData without CIP".into());
            }
        } else if f.is_icmp() {
            if (f.get("icmp.type"), f.get("icmp.code")) == ("3", "3")
                && !from_dut
                && f.get("udp.srcport") == "2222"
                && f.all("ip.src").get(1) == Some(&dut)
            {
                judged.unreachable += 1;
            } else {
                bad(format!("ICMP {:?}", f.0));
            }
        } else if !f.is_io() || !p.contains(&"cipio") {
            bad(format!("UDP that is not class-1 I/O: {p:?}"));
        }
    }
    assert!(
        wrong.is_empty(),
        "{}: {} frames break the rules:\n{}",
        path.display(),
        wrong.len(),
        wrong.join("\n")
    );

    // Parameter access, a Forward_Open and I/O both ways took place.
    let services: Vec<&str> = frames.iter().map(|f| f.get("cip.service")).collect();
    for (service, what) in [
        ("0x10", "Set_Attribute_Single"),
        ("0x0e", "Get_Attribute_Single"),
        ("0x54", "Forward_Open"),
        ("0xd4", "Forward_Open reply"),
    ] {
        assert!(services.contains(&service), "{}: no {what}", path.display());
    }
    assert!(
        frames.iter().any(|f| f.protocols().contains(&"cipcm")),
        "{}: no connection manager request",
        path.display()
    );
    for port in ["udp.srcport", "udp.dstport"] {
        assert!(
            frames.iter().any(|f| f.is_io() && f.get(port) == "2222"),
            "{}: no I/O datagram with {port} 2222",
            path.display()
        );
    }
    judged
}

/// Asserts that the flagging rule is not vacuous: tshark did flag steps (the malformed
/// requests of suites/cip), and the clean steps vastly outnumber them.
fn assert_flagged_few(path: &Path, judged: &Judged) {
    let (steps, flagged) = (judged.steps.len(), judged.flagged.len());
    eprintln!(
        "{}: {steps} steps with traffic, {flagged} flagged by tshark (each breaks bytes on \
         purpose; {} of {} frames), {} DUT replies repeating their request's warning, {} ICMP \
         unreachable:\n  {}",
        path.display(),
        judged.flagged_frames.0,
        judged.flagged_frames.1,
        judged.echoes.len(),
        judged.unreachable,
        judged
            .flagged
            .iter()
            .cloned()
            .collect::<Vec<_>>()
            .join("\n  ")
    );
    assert!(
        flagged > 0,
        "{}: tshark flags nothing, not even the malformed requests of suites/cip",
        path.display()
    );
    assert!(
        steps - flagged >= 10 * flagged,
        "{}: {flagged} of {steps} steps flagged",
        path.display()
    );
}

/// A fresh scratch folder.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("harness-interop-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `harness run ARGS --pcap PCAP`: the run completes and reaches the DUT in every case (its
/// pass/fail verdicts are not judged here, but an `error` means a link that did not open, e.g.
/// UDP 2222 taken by another program, and a capture without its traffic), and reports the
/// packets it wrote; returns their number.
fn run_with_pcap(args: &[&str], pcap: &Path, out: &Path) -> usize {
    let o = Command::new(env!("CARGO_BIN_EXE_harness"))
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .arg("run")
        .args(args)
        .arg("--pcap")
        .arg(pcap)
        .arg("--out")
        .arg(out)
        .output()
        .expect("the harness binary runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        matches!(o.status.code(), Some(0 | 1)),
        "harness run {args:?} did not complete:\n{stdout}\n{stderr}"
    );
    let run: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    let errors: Vec<&Value> = run["cases"]
        .as_array()
        .expect("cases")
        .iter()
        .filter(|c| c["verdict"] == "error")
        .map(|c| &c["message"])
        .collect();
    assert!(errors.is_empty(), "harness run {args:?}: {errors:?}");
    let line = stdout
        .lines()
        .find(|l| l.starts_with("pcap: "))
        .unwrap_or_else(|| panic!("no pcap line in:\n{stdout}\n{stderr}"));
    line["pcap: ".len()..]
        .split(' ')
        .next()
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("pcap line `{line}`"))
}

/// Runs tshark on a capture file; returns its standard output.
fn tshark(path: &Path, checksums: bool, args: &[&str]) -> String {
    let out = Command::new("tshark")
        .arg("-n")
        .arg("-r")
        .arg(path)
        .args(if checksums { &CHECKSUMS[..] } else { &[] })
        .args(args)
        .output()
        .expect("tshark runs");
    assert!(
        out.status.success(),
        "tshark {args:?} on {}: {}",
        path.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The labels of a run's own capture: every packet has one, of a case of one of `profiles`.
fn own_labels<'a>(path: &Path, frames: &'a [Frame], profiles: &[&str]) -> Vec<Option<&'a str>> {
    frames
        .iter()
        .map(|f| {
            let label = f.get("frame.comment");
            assert!(
                profiles.iter().any(|p| label.starts_with(&format!("{p} "))),
                "{}: frame {} is labelled `{label}`",
                path.display(),
                f.get("frame.number")
            );
            Some(label)
        })
        .collect()
}

/// The whole run, not a filtered part: every suite under these profiles.
const EMBEDDED_PROFILES: [&str; 2] = ["tu4-eip@enip", "sk550p@enip"];

#[test]
fn embedded_run_pcap_dissects_cleanly_and_reproducibly() {
    if !require_tshark("tshark on the pcapng of an embedded run") {
        return;
    }
    let dir = scratch("embedded-pcap");
    let args = EMBEDDED_PROFILES.map(|p| ["--profile", p]).concat();
    // The name is the user's: the file is pcapng whatever it is called.
    let first = dir.join("first.pcap");
    let packets = run_with_pcap(&args, &first, &dir.join("reports"));
    let bytes = std::fs::read(&first).unwrap();
    assert_eq!(&bytes[..4], &[0x0A, 0x0D, 0x0D, 0x0A], "a pcapng section");
    let frames = dissect(&first, true);
    assert_eq!(frames.len(), packets);
    let labels = own_labels(&first, &frames, &EMBEDDED_PROFILES);
    let judged = judge(&first, &frames, &labels);
    assert_flagged_few(&first, &judged);
    // Both profiles' malformed requests are there.
    for p in EMBEDDED_PROFILES {
        assert!(
            judged.flagged.iter().any(|l| l.starts_with(p)),
            "{p}: nothing flagged"
        );
    }

    // The virtual clock and derived addresses make the capture of a run byte-for-byte the same,
    // comments included.
    let second = dir.join("second.pcapng");
    run_with_pcap(&args, &second, &dir.join("reports"));
    assert!(
        bytes == std::fs::read(&second).unwrap(),
        "two embedded runs gave different captures"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// tshark capturing on `lo`; stopped like Ctrl-C so the file is complete.
struct WireCapture {
    child: Child,
    stderr: PathBuf,
}

impl WireCapture {
    /// Starts capturing `filter` on `lo` into `file`, and returns once tshark captures.
    fn start(filter: &str, file: &Path) -> WireCapture {
        let stderr = file.with_extension("stderr");
        let child = Command::new("tshark")
            .args(["-i", "lo", "-f", filter, "-w"])
            .arg(file)
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&stderr).unwrap())
            .spawn()
            .expect("tshark starts");
        let mut capture = WireCapture { child, stderr };
        let deadline = Instant::now() + Duration::from_secs(20);
        loop {
            let said = std::fs::read_to_string(&capture.stderr).unwrap_or_default();
            if said.contains("Capturing on") {
                break;
            }
            if let Ok(Some(status)) = capture.child.try_wait() {
                panic!("tshark ended ({status}) before capturing:\n{said}");
            }
            assert!(
                Instant::now() < deadline,
                "tshark is not capturing:\n{said}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
        // "Capturing on" comes as the capture starts; leave it a moment to settle.
        std::thread::sleep(Duration::from_millis(300));
        capture
    }

    /// Interrupts tshark and waits for it to finish the file.
    fn stop(mut self) {
        // Late packets (the last ACKs) reach the capture before it stops.
        std::thread::sleep(Duration::from_millis(300));
        let _ = Command::new("kill")
            .args(["-INT", &self.child.id().to_string()])
            .status();
        let deadline = Instant::now() + Duration::from_secs(20);
        while self.child.try_wait().ok().flatten().is_none() {
            assert!(Instant::now() < deadline, "tshark does not stop");
            std::thread::sleep(Duration::from_millis(50));
        }
    }
}

impl Drop for WireCapture {
    fn drop(&mut self) {
        if self.child.try_wait().ok().flatten().is_none() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}

/// A TCP frame's place in the conversation, comparable between the run's capture and the
/// wire: who sent it, SYN/FIN, how much data, which encapsulation command and CIP service.
fn tcp_signature(f: &Frame) -> Option<String> {
    let pure_ack = f.number("tcp.len") == 0 && !f.flag("tcp.flags.syn") && !f.flag("tcp.flags.fin");
    (f.is_tcp() && !pure_ack).then(|| {
        format!(
            "{}:{} > {}:{} syn={} fin={} len={} enip={} cip={} status={}",
            f.get("ip.src"),
            f.get("tcp.srcport"),
            f.get("ip.dst"),
            f.get("tcp.dstport"),
            f.flag("tcp.flags.syn"),
            f.flag("tcp.flags.fin"),
            f.get("tcp.len"),
            f.get("enip.command"),
            f.get("cip.service"),
            f.get("cip.genstat"),
        )
    })
}

/// The I/O datagrams from `src` of a capture, with their addresses.
fn io_from<'a>(frames: &'a [Frame], src: &str) -> Vec<(&'a str, &'a str, &'a str)> {
    frames
        .iter()
        .filter(|f| f.is_io() && f.get("ip.src") == src)
        .map(|f| (f.get("udp.srcport"), f.get("ip.dst"), f.get("udp.dstport")))
        .collect()
}

/// Time from the first to the last TCP frame of a capture, in seconds.
fn tcp_span(frames: &[Frame]) -> f64 {
    let times: Vec<f64> = frames
        .iter()
        .filter(|f| f.is_tcp())
        .map(|f| f.get("frame.time_relative").parse().unwrap())
        .collect();
    times.last().unwrap() - times.first().unwrap()
}

/// A capture's TCP segments, bare ACKs left out, as [`tcp_signature`]s: those without FIN
/// in capture order, and the FINs sorted.
fn segments(frames: &[Frame]) -> (Vec<String>, Vec<String>) {
    let (fins, others): (Vec<_>, Vec<_>) = frames
        .iter()
        .filter_map(|f| Some((f.flag("tcp.flags.fin"), tcp_signature(f)?)))
        .partition(|(fin, _)| *fin);
    let mut fins: Vec<String> = fins.into_iter().map(|(_, s)| s).collect();
    fins.sort();
    (others.into_iter().map(|(_, s)| s).collect(), fins)
}

/// The labels of a wire capture's frames: each TCP segment that is not a bare ACK takes the
/// label of the run's next segment with the same signature (the same segments, asserted by
/// the caller); bare ACKs, datagrams and ICMP have none.
fn wire_labels<'a>(
    seen: &[Frame],
    recorded: &[Frame],
    recorded_labels: &[Option<&'a str>],
) -> Vec<Option<&'a str>> {
    let mut from_run: HashMap<String, VecDeque<Option<&'a str>>> = HashMap::new();
    for (f, l) in recorded.iter().zip(recorded_labels) {
        if let Some(s) = tcp_signature(f) {
            from_run.entry(s).or_default().push_back(*l);
        }
    }
    seen.iter()
        .map(|f| {
            let s = tcp_signature(f)?;
            from_run
                .get_mut(&s)
                .and_then(VecDeque::pop_front)
                .expect("a segment of the run")
        })
        .collect()
}

#[test]
fn network_run_pcap_matches_a_wire_capture_and_both_dissect_cleanly() {
    let why = "a run's pcapng beside tshark's capture on lo";
    if !require_tshark(why) || !require_or_skip(is_root(), "root to capture on lo", why) {
        return;
    }
    let dir = scratch("network-pcap");
    // The whole run (about 100 s of real time: the drive examples run in real time).
    let profile = "tu4-eip@enip";
    let device = free_loopback().to_string();
    let _server = serve(&format!("{device}:44818"), "tu4-eip", 600);
    let wire_file = dir.join("wire.pcapng");
    let wire = WireCapture::start(&format!("host {device}"), &wire_file);
    let run_file = dir.join("run.pcapng");
    let packets = run_with_pcap(
        &[
            "--dut",
            &format!("enip://{device}"),
            "--local",
            &free_loopback().to_string(),
            "--profile",
            profile,
            // The served simulator has no motor to turn and no EEPROM to wear.
            "--allow-motion",
            "--max-eeprom-writes",
            "10000",
        ],
        &run_file,
        &dir.join("reports"),
    );
    wire.stop();

    let recorded = dissect(&run_file, true);
    assert_eq!(recorded.len(), packets);
    let seen = dissect(&wire_file, false);

    // The run recorded the conversation the wire carried: the same segments (less the bare
    // ACKs the kernel sends) between the same addresses and ports, in the same order, except
    // for FINs: the harness records a connection's closing when it closes it or sees it
    // closed, while the target's FIN may cross the wire later (after the next case's
    // handshake, say).
    let (recorded_tcp, recorded_fins) = segments(&recorded);
    let (seen_tcp, seen_fins) = segments(&seen);
    assert!(recorded_fins == seen_fins, "FINs differ");
    if recorded_tcp != seen_tcp {
        let at = recorded_tcp
            .iter()
            .zip(&seen_tcp)
            .position(|(r, s)| r != s)
            .unwrap_or(recorded_tcp.len().min(seen_tcp.len()));
        panic!(
            "{} segments recorded, {} on the wire; from the {at}th on:\nrun:  {:?}\nwire: {:?}",
            recorded_tcp.len(),
            seen_tcp.len(),
            &recorded_tcp[at..(at + 5).min(recorded_tcp.len())],
            &seen_tcp[at..(at + 5).min(seen_tcp.len())],
        );
    }
    // Every O→T datagram the harness sent; the T→O ones it received (the target may send a
    // last few after the harness stopped listening), from and to the same ports.
    let scanner = recorded[0].get("ip.src");
    assert_eq!(
        io_from(&recorded, scanner),
        io_from(&seen, scanner),
        "O→T datagrams"
    );
    let (recorded_t_o, seen_t_o) = (io_from(&recorded, &device), io_from(&seen, &device));
    assert!(
        !recorded_t_o.is_empty() && recorded_t_o.len() <= seen_t_o.len(),
        "T→O datagrams: {} recorded, {} on the wire",
        recorded_t_o.len(),
        seen_t_o.len()
    );
    assert!(recorded_t_o.iter().all(|a| seen_t_o.contains(a)));
    // Real time: the run's capture spans what the wire's does.
    let (r, s) = (tcp_span(&recorded), tcp_span(&seen));
    assert!(
        r > 10.0 && (r - s).abs() < 0.5,
        "spans: run {r} s, wire {s} s"
    );

    // Both dissect as the run's own capture says: tshark flags only bytes broken on purpose,
    // in the run's capture and on the wire alike.
    let recorded_labels = own_labels(&run_file, &recorded, &[profile]);
    let judged = judge(&run_file, &recorded, &recorded_labels);
    assert_flagged_few(&run_file, &judged);
    let labels = wire_labels(&seen, &recorded, &recorded_labels);
    let judged_wire = judge(&wire_file, &seen, &labels);
    assert_flagged_few(&wire_file, &judged_wire);
    assert_eq!(
        judged.flagged, judged_wire.flagged,
        "the same steps flagged in the run's capture and on the wire"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn generic_suite_against_cpppo_server_reports_deviations_as_failures() {
    let Some(py) = python("the cip suites against cpppo's server") else {
        return;
    };
    let device = free_loopback();
    let listen = format!("{device}:44818");
    let server = Server(
        Command::new(&py)
            .args([
                "-m",
                "cpppo.server.enip",
                "--address",
                &listen,
                "SCADA=INT[10]",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("cpppo server starts"),
    );
    wait_listening(&listen, Duration::from_secs(20));
    let out_dir = scratch("cpppo-server");
    let out = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args([
            "run",
            "--dut",
            &format!("enip://{device}"),
            "--local",
            &free_loopback().to_string(),
            "--profile",
            "cip",
            "--timeout",
            "1",
        ])
        .arg("--out")
        .arg(&out_dir)
        .output()
        .expect("harness runs");
    drop(server);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "failures expected:\n{stdout}");

    let run: Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("run.json")).unwrap()).unwrap();
    let verdict = |id: &str| common::case_verdict(&run, id);
    // A misbehaving peer is judged, never an error of the harness.
    assert_eq!(run["counts"]["error"], 0, "{stdout}");
    // What cpppo does as CIP says.
    for id in [
        "cip/encapsulation/list-identity",
        "cip/encapsulation/list-services",
        "cip/encapsulation/sender-context-is-echoed",
        "cip/encapsulation/send-rr-data-well-formed",
        "cip/message-router/reply-echoes-the-service",
    ] {
        assert_eq!(verdict(id).0, "pass", "{id}: {:?}", verdict(id));
    }
    // Where it departs (cpppo 5.2.5): sessions are not checked, an unknown class ends in
    // encapsulation status 0008h instead of CIP status 05h, protocol version 2 is accepted.
    for (id, says) in [
        (
            "cip/encapsulation/send-rr-data-unknown-session",
            "encap_status",
        ),
        (
            "cip/encapsulation/register-session-unsupported-version",
            "encap_status",
        ),
        ("cip/message-router/unknown-class", "0008h"),
    ] {
        let (v, message) = verdict(id);
        assert_eq!(v, "fail", "{id}: {message}");
        assert!(message.contains(says), "{id}: {message}");
    }
    // The terminal report names the rule each failure broke and where CIP states it.
    assert!(
        stdout.contains("rule: Get_Attribute_Single on class 77h, which the device lacks: 05h path destination unknown (CIP Vol 1 §Appendix B-1)"),
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(&out_dir);
}
