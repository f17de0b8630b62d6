//! Independent EtherNet/IP clients against the served simulator: pycomm3 and cpppo read and
//! write NORD parameters over `harness serve enip` and get the values and CIP status codes the
//! manuals imply (BU 2100 §6.3: class 100 + FI, instance from set/element, attribute = P-number).
//!
//! The clients live in a venv that `.ci/interop-setup` installs (CI always runs it). Without
//! that venv the test says so and skips: the peers are third-party packages from PyPI.
//!
//! tshark (installed by the same script) judges `harness run --pcap`: the capture of an
//! embedded run, and that of a run against the served simulator beside one tshark took on the
//! wire, dissect as `enip`/`cip`/`cipio` with no malformed frame and no expert warning.
//! Capturing on `lo` needs root (CI runs as root); without tshark or root those tests skip.
//!
//! The other way round, the harness runs the generic profile `cip` (`suites/cip/`) against
//! cpppo's server: every place cpppo departs from CIP comes out as a failure that names the
//! rule, never as a harness error, and the cases cpppo gets right pass.

use std::io::{BufRead, BufReader};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

struct Server(Child);

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn python() -> Option<PathBuf> {
    let venv = std::env::var("INTEROP_VENV").unwrap_or_else(|_| "/tmp/nord-interop-venv".into());
    let p = PathBuf::from(venv).join("bin/python");
    p.exists().then_some(p)
}

fn serve(listen: &str, profile: &str) -> Server {
    let mut child = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args([
            "serve",
            "enip",
            "--listen",
            listen,
            "--profile",
            profile,
            "--seconds",
            "60",
        ])
        .stdout(Stdio::piped())
        .spawn()
        .expect("harness serve starts");
    // It announces itself once its sockets are bound, and exits at once when it cannot bind
    // them: then whatever holds the address would answer in its place.
    let mut out = BufReader::new(child.stdout.take().expect("piped stdout"));
    let mut line = String::new();
    if out.read_line(&mut line).unwrap_or(0) == 0 {
        let status = child.wait();
        panic!("harness serve --listen {listen} did not start ({status:?}): address taken?");
    }
    print!("{line}");
    std::thread::spawn(move || std::io::copy(&mut out, &mut std::io::stdout()));
    let addr: SocketAddr = listen.parse().unwrap();
    let deadline = Instant::now() + Duration::from_secs(10);
    while TcpStream::connect_timeout(&addr, Duration::from_millis(200)).is_err() {
        assert!(
            Instant::now() < deadline,
            "harness serve did not listen on {listen}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    Server(child)
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
    let Some(py) = python() else {
        eprintln!("SKIP: no interop venv (run `bash .ci/interop-setup`; CI does)");
        return;
    };
    let _server = serve("127.0.0.3:44818", "tu3-eip");
    // FI 1 P102 (class 101, instance 0 = set 1, attribute 102): write 1000 (10.00 s), read back.
    // FI 2 P400 [-03] set 3: instance 14 (BU 2100 §6.3 example, class 102).
    let r = client(
        &py,
        "pycomm3_client.py",
        &["--host", "127.0.0.3", "--port", "44818"],
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
        &["127.0.0.3:44818"],
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

/// Fields of a dissected frame, in the order [`dissect`] asks tshark for them.
const FIELDS: [&str; 15] = [
    "frame.number",
    "frame.time_relative",
    "frame.protocols",
    "ip.src",
    "ip.dst",
    "tcp.srcport",
    "tcp.dstport",
    "tcp.len",
    "tcp.flags.syn",
    "tcp.flags.fin",
    "udp.srcport",
    "udp.dstport",
    "enip.command",
    "cip.service",
    "cip.genstat",
];

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

/// One frame as tshark dissected it (first occurrence of each of [`FIELDS`]).
#[derive(Debug)]
struct Frame(Vec<String>);

impl Frame {
    fn get(&self, field: &str) -> &str {
        let i = FIELDS
            .iter()
            .position(|f| *f == field)
            .expect("a known field");
        &self.0[i]
    }

    fn flag(&self, field: &str) -> bool {
        // tshark 4.0 prints booleans as 1/0, later versions as True/False.
        matches!(self.get(field), "1" | "True" | "true")
    }

    fn number(&self, field: &str) -> u64 {
        self.get(field).parse().unwrap_or(0)
    }

    fn protocols(&self) -> Vec<&str> {
        self.get("frame.protocols").split(':').collect()
    }

    fn is_tcp(&self) -> bool {
        !self.get("tcp.srcport").is_empty()
    }

    fn is_io(&self) -> bool {
        self.get("udp.srcport") == "2222" || self.get("udp.dstport") == "2222"
    }
}

fn have_tshark() -> bool {
    Command::new("tshark").arg("--version").output().is_ok()
}

/// Whether this process runs as root (capturing on `lo` needs it).
fn is_root() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find_map(|l| l.strip_prefix("Uid:"))
                .and_then(|ids| ids.split_whitespace().nth(1).map(|euid| euid == "0"))
        })
        .unwrap_or(false)
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

/// Every frame of a capture, dissected.
fn dissect(path: &Path, checksums: bool) -> Vec<Frame> {
    let mut args = vec!["-T", "fields", "-E", "separator=|", "-E", "occurrence=f"];
    for f in FIELDS {
        args.extend(["-e", f]);
    }
    tshark(path, checksums, &args)
        .lines()
        .map(|l| Frame(l.split('|').map(str::to_string).collect()))
        .inspect(|f| assert_eq!(f.0.len(), FIELDS.len(), "{f:?}"))
        .collect()
}

/// Asserts that no frame is malformed or carries an expert item of warning or error severity,
/// and that each frame is dissected as what it carries: every TCP segment with data as `enip`,
/// every SendRRData as `cip`, every datagram on UDP 2222 as `cipio`, nothing left as raw
/// `data`. Returns the frames.
fn assert_clean(path: &Path, checksums: bool) -> Vec<Frame> {
    // _ws.expert.severity is numeric: note 0x400000, warning 0x600000, error 0x800000.
    let bad = tshark(
        path,
        checksums,
        &[
            "-Y",
            "_ws.malformed || _ws.expert.severity >= 6291456",
            "-T",
            "fields",
            "-e",
            "frame.number",
            "-e",
            "_ws.expert.message",
            "-e",
            "_ws.col.Info",
        ],
    );
    assert!(
        bad.trim().is_empty(),
        "{}: malformed frames or expert warnings/errors:\n{bad}",
        path.display()
    );
    // The same filter machinery does see expert items (the TCP handshakes' chats and the
    // closing notes), so the empty answer above is not a filter that matches nothing.
    let expert = tshark(
        path,
        checksums,
        &[
            "-Y",
            "_ws.expert.severity",
            "-T",
            "fields",
            "-e",
            "frame.number",
        ],
    );
    assert!(
        !expert.trim().is_empty(),
        "{}: tshark reports no expert item at all",
        path.display()
    );

    let frames = dissect(path, checksums);
    assert!(!frames.is_empty(), "{}: no frames", path.display());
    for f in &frames {
        let p = f.protocols();
        assert_eq!(&p[..3], ["eth", "ethertype", "ip"], "{f:?}");
        assert!(
            !p.contains(&"data") && !p.contains(&"_ws.malformed"),
            "{f:?}"
        );
        if f.is_tcp() {
            assert!(
                f.get("tcp.srcport") == "44818" || f.get("tcp.dstport") == "44818",
                "{f:?}"
            );
            assert_eq!(p.contains(&"enip"), f.number("tcp.len") > 0, "{f:?}");
            if f.get("enip.command") == "0x006f" {
                assert!(p.contains(&"cip"), "SendRRData without CIP: {f:?}");
            }
        } else {
            assert!(f.is_io(), "only class-1 I/O travels on UDP here: {f:?}");
            assert!(p.contains(&"cipio"), "{f:?}");
        }
    }
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
    frames
}

/// The run whose traffic is captured: parameter writes and reads of inverters behind the
/// module, and the switching example over an I/O connection (BU 2100 §6.3, §6.4).
const CASES: &str = "bu2100/addr-cip";

#[test]
fn embedded_run_pcap_dissects_cleanly_and_reproducibly() {
    if !have_tshark() {
        eprintln!("SKIP: tshark is not on PATH (run `bash .ci/interop-setup`; CI does)");
        return;
    }
    let dir = scratch("embedded-pcap");
    let args = ["--profile", "tu4-eip@enip", "--filter", CASES];
    let first = dir.join("first.pcap");
    let packets = run_with_pcap(&args, &first, &dir.join("reports"));
    let frames = assert_clean(&first, true);
    assert_eq!(frames.len(), packets);

    // The virtual clock and derived addresses make the capture of a run byte-for-byte the same.
    let second = dir.join("second.pcap");
    run_with_pcap(&args, &second, &dir.join("reports"));
    assert!(
        std::fs::read(&first).unwrap() == std::fs::read(&second).unwrap(),
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

#[test]
fn network_run_pcap_matches_a_wire_capture_and_both_dissect_cleanly() {
    if !have_tshark() {
        eprintln!("SKIP: tshark is not on PATH (run `bash .ci/interop-setup`; CI does)");
        return;
    }
    if !is_root() {
        eprintln!("SKIP: capturing on lo needs root (CI runs as root)");
        return;
    }
    let dir = scratch("network-pcap");
    let _server = serve("127.0.0.6:44818", "tu4-eip");
    let wire_file = dir.join("wire.pcapng");
    let wire = WireCapture::start("host 127.0.0.6", &wire_file);
    let run_file = dir.join("run.pcap");
    let packets = run_with_pcap(
        &[
            "--dut",
            "enip://127.0.0.6",
            "--profile",
            "tu4-eip@enip",
            "--filter",
            CASES,
        ],
        &run_file,
        &dir.join("reports"),
    );
    wire.stop();

    let recorded = assert_clean(&run_file, true);
    assert_eq!(recorded.len(), packets);
    let seen = assert_clean(&wire_file, false);

    // The run recorded the conversation the wire carried: the same segments (less the bare
    // ACKs the kernel sends) between the same addresses and ports, in the same order.
    let recorded_tcp: Vec<String> = recorded.iter().filter_map(tcp_signature).collect();
    let seen_tcp: Vec<String> = seen.iter().filter_map(tcp_signature).collect();
    assert_eq!(recorded_tcp, seen_tcp);
    // Every O→T datagram the harness sent; the T→O ones it received (the target may send a
    // last few after the harness stopped listening), from and to the same ports.
    let scanner = recorded[0].get("ip.src");
    assert_eq!(
        io_from(&recorded, scanner),
        io_from(&seen, scanner),
        "O→T datagrams"
    );
    let (recorded_t_o, seen_t_o) = (io_from(&recorded, "127.0.0.6"), io_from(&seen, "127.0.0.6"));
    assert!(
        !recorded_t_o.is_empty() && recorded_t_o.len() <= seen_t_o.len(),
        "T→O datagrams: {} recorded, {} on the wire",
        recorded_t_o.len(),
        seen_t_o.len()
    );
    assert!(recorded_t_o.iter().all(|a| seen_t_o.contains(a)));
    // Real time: the run's capture spans what the wire's does (the switching example alone
    // runs its drive for 2 s).
    let (r, s) = (tcp_span(&recorded), tcp_span(&seen));
    assert!(
        r > 2.0 && (r - s).abs() < 0.5,
        "spans: run {r} s, wire {s} s"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn generic_suite_against_cpppo_server_reports_deviations_as_failures() {
    let Some(py) = python() else {
        eprintln!("SKIP: no interop venv (run `bash .ci/interop-setup`; CI does)");
        return;
    };
    let listen = "127.0.0.8:44818";
    let server = Server(
        Command::new(&py)
            .args([
                "-m",
                "cpppo.server.enip",
                "--address",
                listen,
                "SCADA=INT[10]",
            ])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("cpppo server starts"),
    );
    let addr: SocketAddr = listen.parse().unwrap();
    let deadline = Instant::now() + Duration::from_secs(20);
    while TcpStream::connect_timeout(&addr, Duration::from_millis(200)).is_err() {
        assert!(
            Instant::now() < deadline,
            "cpppo did not listen on {listen}"
        );
        std::thread::sleep(Duration::from_millis(100));
    }
    let out_dir = scratch("cpppo-server");
    let out = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args([
            "run",
            "--dut",
            "enip://127.0.0.8",
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
    let verdict = |id: &str| -> (String, String) {
        let c = run["cases"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["id"] == id)
            .unwrap_or_else(|| panic!("no case {id}"));
        (
            c["verdict"].as_str().unwrap().to_string(),
            c["message"].as_str().unwrap_or_default().to_string(),
        )
    };
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
