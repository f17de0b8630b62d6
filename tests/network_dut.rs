//! A hung, closing or garbage-sending EtherNet/IP target becomes an error verdict within the
//! scanner's timeout, never a hang of the harness: three fake targets on loopback, one
//! `harness run --dut` each.

use std::io::{Read, Write};
use std::net::TcpListener;
use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::Value;

#[derive(Clone, Copy)]
enum Target {
    /// Accepts and reads, never answers.
    Silent,
    /// Accepts and closes at once.
    Closing,
    /// Answers every read with a header-sized block that is not EtherNet/IP.
    Garbage,
}

fn fake(kind: Target) -> u16 {
    let listener = TcpListener::bind("127.0.0.9:0").expect("bind 127.0.0.9");
    let port = listener.local_addr().unwrap().port();
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
    port
}

#[test]
fn hung_closing_and_garbage_targets_are_error_verdicts() {
    for (kind, says) in [
        (Target::Silent, "no reply to RegisterSession"),
        (Target::Closing, "link error"),
        (Target::Garbage, "does not speak the protocol"),
    ] {
        let port = fake(kind);
        let out_dir =
            std::env::temp_dir().join(format!("harness-fake-{}-{port}", std::process::id()));
        let start = Instant::now();
        let out = Command::new(env!("CARGO_BIN_EXE_harness"))
            .args(["run", "--profile", "cip", "--timeout", "0.3"])
            .args(["--filter", "cip/message-router/unknown-"])
            .arg("--dut")
            .arg(format!("enip://127.0.0.9:{port}"))
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
        assert_eq!(cases.len(), 4, "{stdout}");
        for c in cases {
            assert_eq!(c["verdict"], "error", "{c}");
            assert!(c["message"].as_str().unwrap().contains(says), "{c}");
        }
        // Four cases, each bounded by the 0.3 s timeout (plus process start).
        assert!(took < Duration::from_secs(10), "took {took:?}");
        let _ = std::fs::remove_dir_all(&out_dir);
    }
}
