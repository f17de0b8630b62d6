//! python-canopen, the CANopen master most test benches script with, against the simulated
//! NORD system bus served over socketcand (`harness serve can --socketcand`, reached through
//! python-can's `socketcand` interface): it reads and writes P102 of inverter 3 at its NORD
//! object (node 36 = P515 address of FI 3, object 2000h + 102, sub-index 1 = set 1) and gets
//! CiA 301 abort codes for bad requests, after which the node still serves. It also imports
//! the node's EDS as `harness describe eds --bus can` writes it (CiA 306) and reads P102 there
//! by name.
//!
//! The peers live in the venv `.ci/interop-setup` installs (python-can and canopen from
//! PyPI); without it the test says so and skips (fails in strict mode).

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Duration;

use serde_json::Value;

#[allow(dead_code)] // what the other network tests share
mod common;
use common::addr::free_loopback;
use common::peer::interop_python;
use common::{wait_listening, Server};

#[test]
fn python_canopen_reads_and_writes_p102_of_fi_3_gets_cia_301_aborts_and_imports_the_eds() {
    let Some(py) = interop_python(
        &["can", "canopen"],
        "python-canopen as master of the served system bus",
    ) else {
        return;
    };
    let listen = format!("{}:29536", free_loopback());
    let child = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args([
            "serve",
            "can",
            "--socketcand",
            &listen,
            "--profile",
            "sk550p",
        ])
        .args(["--seconds", "120"])
        .stdout(Stdio::null())
        .spawn()
        .expect("harness serve can starts");
    let _server = Server(child);
    wait_listening(&listen, Duration::from_secs(10));
    let eds = std::env::temp_dir().join(format!("nord-fi3-{}.eds", std::process::id()));
    let described = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["describe", "eds", "--bus", "can", "--profile", "sk550p"])
        .args(["--inverter", "3"])
        .output()
        .expect("harness describe runs");
    assert!(described.status.success(), "{described:?}");
    std::fs::write(&eds, &described.stdout).expect("EDS written");
    let (host, port) = listen.split_once(':').expect("HOST:PORT");
    let script =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/interop/canopen_master.py");
    let out = Command::new(&py)
        .arg(script)
        .args([host, port, "can0"])
        .arg(&eds)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "canopen_master.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let seen: Value = serde_json::from_slice(&out.stdout).expect("one JSON object");
    // Factory P102 (BU 0620's P102 write example writes 250 = 2.50 s).
    assert_eq!(seen["p102_before"], 200, "{seen}");
    assert_eq!(seen["p102_after"], 250, "{seen}");
    assert_eq!(seen["device_name"], "sk550p", "1008h in segments: {seen}");
    let aborts = &seen["aborts"];
    assert_eq!(aborts["absent_object"], 0x0602_0000, "{seen}");
    assert_eq!(aborts["absent_subindex"], 0x0609_0011, "{seen}");
    assert_eq!(aborts["read_only"], 0x0601_0002, "{seen}");
    assert_eq!(aborts["too_high"], 0x0609_0031, "{seen}");
    assert_eq!(seen["p102_last"], 250, "still serving: {seen}");
    // The EDS: python-canopen imports it and reads P102 set 1 by name, typed INTEGER16.
    assert_eq!(seen["eds_p102_by_name"], 250, "{seen}");
    assert_eq!(seen["eds_p102_type"], 0x0003, "{seen}");
    assert!(seen["eds_objects"].as_u64().unwrap_or(0) > 20, "{seen}");
    let _ = std::fs::remove_file(&eds);
}
