//! `harness run --dut` against targets on loopback:
//!
//! - a hung, closing or garbage-sending EtherNet/IP target becomes an error verdict within the
//!   scanner's timeout, never a hang of the harness: three fake targets, one run each;
//! - the served simulator, one persistent device for a whole run as a real one is, passes the
//!   full `tu4-eip@enip` and `sk550p@enip` runs: each case leaves it as it found it (the
//!   scanner's cleanup), and what only a freshly powered-on or factory-set device can show is
//!   not applicable there.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::Value;

#[allow(dead_code)] // what the other network tests share
mod common;
use common::addr::free_loopback;
use common::serve;
use common::transcripts::transcript;

#[derive(Clone, Copy)]
enum Target {
    /// Accepts and reads, never answers.
    Silent,
    /// Accepts and closes at once.
    Closing,
    /// Answers every read with a header-sized block that is not EtherNet/IP.
    Garbage,
}

/// A fake target on a free port of a loopback address of its own; where it listens.
fn fake(kind: Target) -> std::net::SocketAddr {
    let listener = TcpListener::bind((free_loopback(), 0)).expect("bind a free port");
    let at = listener.local_addr().unwrap();
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            std::thread::spawn(move || {
                let mut s = stream;
                let mut buf = [0u8; 4096];
                match kind {
                    Target::Closing => {}
                    Target::Silent => while matches!(s.read(&mut buf), Ok(n) if n > 0) {},
                    Target::Garbage => {
                        while matches!(s.read(&mut buf), Ok(n) if n > 0) {
                            // A 24-byte header that frames (length 0) but is no reply.
                            let _ = s.write_all(b"GG\0\0GARBAGE GARBAGE GARBAG");
                        }
                    }
                }
            });
        }
    });
    at
}

#[test]
fn hung_closing_and_garbage_targets_are_error_verdicts() {
    // A target that accepts and never answers, closes at once, or answers garbage fails the
    // run's connection check: one error naming the cause, and the run stops (an answer that
    // breaks the protocol is the device's, whatever the cases would ask).
    for (kind, says) in [
        (
            Target::Silent,
            "no reply to ListIdentity within 1500 ms (5 times the limit of one request)",
        ),
        (Target::Closing, "the device closed the connection"),
        (
            Target::Garbage,
            "asked who it is: the DUT does not speak the protocol: the reply to ListIdentity is command 4747h",
        ),
    ] {
        let at = fake(kind);
        let out_dir =
            std::env::temp_dir().join(format!("harness-fake-{}-{}", std::process::id(), at.port()));
        let start = Instant::now();
        let out = Command::new(env!("CARGO_BIN_EXE_harness"))
            .args(["run", "--profile", "cip", "--timeout", "0.3"])
            .args(["--filter", "cip/message-router/unknown-"])
            .arg("--dut")
            .arg(format!("enip://{at}"))
            // Its own UDP 2222 for T→O data, whatever else runs on this host.
            .args(["--local", &free_loopback().to_string()])
            .arg("--out")
            .arg(&out_dir)
            .output()
            .expect("harness runs");
        let took = start.elapsed();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(out.status.code(), Some(1), "{stdout}");
        let run: Value =
            serde_json::from_slice(&std::fs::read(out_dir.join("run.json")).unwrap()).unwrap();
        let cases: Vec<&Value> = run["cases"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| c["verdict"] != "not_applicable")
            .collect();
        assert_eq!(cases.len(), 1, "{stdout}");
        assert_eq!(cases[0]["id"], "harness/connection-check", "{stdout}");
        assert!(
            cases[0]["message"]
                .as_str()
                .unwrap()
                .ends_with("the run stopped before its cases"),
            "{}",
            cases[0]
        );
        for c in cases {
            assert_eq!(c["verdict"], "error", "{c}");
            assert!(c["message"].as_str().unwrap().contains(says), "{c}");
        }
        // Four cases, each bounded by the 0.3 s timeout (plus process start).
        assert!(took < Duration::from_secs(10), "took {took:?}");
        let _ = std::fs::remove_dir_all(&out_dir);
    }
}

/// A served adapter whose every reply leaves 500 ms late (`--misbehave late=500ms`), against a
/// run whose limit for one request is 200 ms: the connection check finds it (it answers, late,
/// and the identity says so) and every case that reaches it fails, naming the limit and how
/// long the harness waited; none is an error or inconclusive.
#[test]
fn a_device_that_answers_past_the_limit_fails_the_cases_that_reach_it() {
    let late = format!("{}:44818", free_loopback());
    let mut server = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["serve", "enip", "--listen", &late, "--profile", "tu3-eip"])
        .args(["--misbehave", "late=500ms", "--seconds", "120"])
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("harness serve starts");
    common::wait_listening(&late, Duration::from_secs(10));
    let out_dir = std::env::temp_dir().join(format!("harness-late-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["run", "--profile", "tu3-eip", "--timeout", "0.2"])
        .args(["--filter", "bu2100/enip-io/t"])
        .args(["--dut", &format!("enip://{late}")])
        .args(["--allow-motion", "--max-eeprom-writes", "100"])
        // Its own UDP 2222 for T→O data, whatever else runs on this host.
        .args(["--local", &free_loopback().to_string()])
        .arg("--out")
        .arg(&out_dir)
        .output()
        .expect("harness runs");
    let _ = server.kill();
    let _ = server.wait();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}");
    let run: Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("run.json")).unwrap()).unwrap();
    let source = run["meta"]["identities"]["tu3-eip@enip"]["source"]
        .as_str()
        .unwrap_or_else(|| panic!("no identity: {}", run["meta"]));
    assert!(
        source.starts_with("ListIdentity, answered after ")
            && source.ends_with("past the limit of 200 ms"),
        "{source}"
    );
    let reached: Vec<&Value> = run["cases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["verdict"] != "not_applicable")
        .collect();
    assert!(reached.len() >= 2, "{stdout}");
    for c in reached {
        assert_eq!(c["verdict"], "fail", "{c}");
        let message = c["message"].as_str().unwrap();
        let (_, waited) = message
            .split_once("no answer within the device's limit of 200 ms (waited ")
            .unwrap_or_else(|| panic!("{message}"));
        let ms: u64 = waited
            .split(' ')
            .next()
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{message}"));
        assert!((200..500).contains(&ms), "{message}");
    }
    let _ = std::fs::remove_dir_all(&out_dir);
}

/// The served simulators of the full runs: product and profile. Each listens on an address of
/// its own, and the scanner has another (its UDP 2222 for T→O data), whatever else runs on
/// this host.
const SERVED: [(&str, &str); 2] = [("tu4-eip", "tu4-eip@enip"), ("sk550p", "sk550p@enip")];

/// One encapsulation message and its reply (header: command, length, session, status,
/// context, options; CIP Vol 2 §2-3.2).
fn encap(s: &mut TcpStream, command: u16, session: u32, data: &[u8]) -> Vec<u8> {
    let mut msg = Vec::new();
    msg.extend(command.to_le_bytes());
    msg.extend((data.len() as u16).to_le_bytes());
    msg.extend(session.to_le_bytes());
    msg.extend([0u8; 16]); // status, sender context, options
    msg.extend(data);
    s.write_all(&msg).unwrap();
    let mut header = [0u8; 24];
    s.read_exact(&mut header).unwrap();
    let mut reply = vec![0u8; usize::from(u16::from_le_bytes([header[2], header[3]]))];
    s.read_exact(&mut reply).unwrap();
    assert_eq!(header[8..12], [0, 0, 0, 0], "encapsulation status");
    [header.to_vec(), reply].concat()
}

/// P102 of FI 1 (class 101, instance 0 = parameter set 1, attribute 102: BU 2100 §6.3,
/// BU 0620 §2.3.5), read by a client of the test's own, apart from the harness.
fn read_p102(served: &str) -> u16 {
    let mut s = TcpStream::connect(served).expect("connect to the served simulator");
    s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
    // RegisterSession (0065h): protocol version 1, options 0.
    let reply = encap(&mut s, 0x65, 0, &[1, 0, 0, 0]);
    let session = u32::from_le_bytes(reply[4..8].try_into().unwrap());
    // SendRRData (006Fh): interface handle 0, timeout 0, two items: null address (0000h,
    // length 0) and unconnected data (00B2h, length 8): Get_Attribute_Single (0Eh), path of
    // 3 words 20 65 24 00 30 66.
    let mut data = vec![0, 0, 0, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0xB2, 0, 8, 0];
    data.extend([0x0E, 0x03, 0x20, 0x65, 0x24, 0x00, 0x30, 0x66]);
    let reply = encap(&mut s, 0x6F, session, &data);
    // Header 24, interface handle and timeout 6, item count 2, null item 4, data item
    // header 4; then the reply: service 8Eh, reserved, general status, extended size, value.
    let mr = &reply[40..];
    assert_eq!(
        mr[..4],
        [0x8E, 0, 0, 0],
        "Get_Attribute_Single P102: {mr:02X?}"
    );
    u16::from_le_bytes([mr[4], mr[5]])
}

/// Takes about 100 s of real time per profile: the suites run their drive for seconds at a
/// time, and a device on the network runs on its own clock. The two profiles run side by side,
/// each against a device of its own.
#[test]
fn network_runs_leave_the_device_as_each_case_found_it() {
    // On a loaded host when `.ci/run` asks (NORD_TEST_HOG): the verdicts must hold there too.
    let _hog = common::hog::Hog::if_asked();
    let failed: Vec<&str> = std::thread::scope(|s| {
        let runs: Vec<_> = SERVED
            .into_iter()
            .map(|(served, profile)| {
                let listen = format!("{}:44818", free_loopback());
                let local = free_loopback().to_string();
                (
                    profile,
                    s.spawn(move || check_full_run(served, profile, &listen, &local)),
                )
            })
            .collect();
        runs.into_iter()
            .filter_map(|(profile, run)| run.join().err().map(|_| profile))
            .collect()
    });
    assert!(failed.is_empty(), "failed: {}", failed.join(", "));
}

/// Serves `served` on `listen`, runs every suite of `profile` against it from `local` and
/// checks that each case left the device as it found it; panics with what is wrong.
fn check_full_run(served: &str, profile: &str, listen: &str, local: &str) {
    let _server = serve(listen, served, 900);
    let p102 = read_p102(listen);
    let out_dir =
        std::env::temp_dir().join(format!("harness-network-{}-{served}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["run", "--profile", profile])
        .arg("--dut")
        .arg(format!("enip://{listen}"))
        // The served simulator has no motor to turn and no EEPROM to wear.
        .args(["--allow-motion", "--max-eeprom-writes", "10000"])
        .args(["--local", local])
        .arg("--out")
        .arg(&out_dir)
        .output()
        .expect("harness runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    let run: Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("run.json")).unwrap()).unwrap();
    let cases = run["cases"].as_array().unwrap();
    let bad: Vec<String> = cases
        .iter()
        .filter(|c| c["verdict"] == "fail" || c["verdict"] == "error")
        .map(|c| format!("{} {}: {}", c["verdict"], c["id"], c["message"]))
        .collect();
    assert!(bad.is_empty(), "{profile}:\n{}", bad.join("\n"));
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    let verdict = |id: &str| {
        let c = cases.iter().find(|c| c["id"] == id).unwrap();
        (
            c["verdict"].as_str().unwrap(),
            c["message"].as_str().unwrap(),
        )
    };
    let passed = cases.iter().filter(|c| c["verdict"] == "pass").count();
    assert!(passed > 150, "{profile}: only {passed} cases passed");

    // A case that writes P102 (99.99 s) passes and sets it back in its cleanup: the
    // device shows the run-up time it had before the run.
    let case = "bu0620/pkw-dut/resolution-99-99-s";
    assert_eq!(verdict(case), ("pass", ""));
    let text = transcript(&out_dir, profile, case);
    let cleanup = text
        .split("cleanup: leave the DUT as the case found it")
        .nth(1)
        .unwrap_or_else(|| panic!("no cleanup step:\n{text}"));
    assert!(
        cleanup.contains("Set_Attribute_Single class 101 / instance 0 / attribute 102"),
        "{text}"
    );
    assert_eq!(read_p102(listen), p102, "{profile}: P102 after the run");
    assert_ne!(p102, 9999);

    // What needs a freshly powered-on device is not applicable, and says so.
    let (v, why) = verdict("bu0620/drive-switching/actual-position-words");
    assert_eq!(v, "not_applicable");
    assert!(why.contains("needs `power-on`"), "{why}");
    let _ = std::fs::remove_dir_all(&out_dir);
}
