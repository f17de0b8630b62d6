//! Independent EtherNet/IP clients against the served simulator: pycomm3 and cpppo read and
//! write NORD parameters over `harness serve enip` and get the values and CIP status codes the
//! manuals imply (BU 2100 §6.3: class 100 + FI, instance from set/element, attribute = P-number).
//!
//! The clients live in a venv that `.ci/interop-setup` installs (CI always runs it). Without
//! that venv the test says so and skips: the peers are third-party packages from PyPI.

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

fn serve(listen: &str, profile: &str) -> Server {
    let child = Command::new(env!("CARGO_BIN_EXE_harness"))
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
        .spawn()
        .expect("harness serve starts");
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
