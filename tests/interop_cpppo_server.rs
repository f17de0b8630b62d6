//! The harness against an independent EtherNet/IP adapter: cpppo's server (PyPI, pinned by
//! `.ci/interop-setup`). The generic profile `cip` runs the protocol's own cases
//! (`suites/cip/`); every place cpppo departs from CIP must come out as a failure that names
//! the rule, never as a harness error, and the cases cpppo gets right must pass.
//!
//! Without the venv the test says so and skips: the peer is a third-party package.

use std::net::{SocketAddr, TcpStream};
use std::path::PathBuf;
use std::process::{Child, Command};
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
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
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
    let out_dir = std::env::temp_dir().join(format!("harness-cpppo-{}", std::process::id()));
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
