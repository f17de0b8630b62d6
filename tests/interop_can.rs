//! python-canopen, the CANopen master most test benches script with, against the simulated
//! NORD system bus served over socketcand (`harness serve can --socketcand`, reached through
//! python-can's `socketcand` interface): it reads and writes P102 of inverter 3 at its NORD
//! object (node 36 = P515 address of FI 3, object 2000h + 102, sub-index 1 = set 1) and gets
//! CiA 301 abort codes for bad requests, after which the node still serves; then it starts the
//! node and gets its TPDO1 (the status word) for each RPDO1 and SYNC it sends. It also imports
//! the node's EDS as `harness describe eds --bus can` writes it (CiA 306) and reads P102 there
//! by name.
//!
//! The other way round, python-canopen's LocalNode (its own SDO server) joins the served bus as
//! a node of any maker, and the harness tests it with the generic CiA 301 cases
//! (`--profile any`, `suites/can/any-node.yaml`).
//!
//! tshark reads the capture of a system-bus run (`harness run --pcap`, link type
//! `LINKTYPE_CAN_SOCKETCAN`) with Wireshark's CANopen dissector.
//!
//! The peers live in the venv `.ci/interop-setup` installs (python-can and canopen from
//! PyPI), and tshark comes from its apt package there; without them the tests say so and skip
//! (fail in strict mode).

use std::path::PathBuf;
use std::process::Command;

use serde_json::Value;

#[allow(dead_code)] // what the other network tests share
mod common;
use common::addr::free_loopback;
use common::peer::{interop_python, require_tshark};
use common::{serve_can, Server};

#[test]
fn python_canopen_reads_and_writes_p102_of_fi_3_gets_cia_301_aborts_runs_pdos_and_imports_the_eds()
{
    let Some(py) = interop_python(
        &["can", "canopen"],
        "python-canopen as master of the served system bus",
    ) else {
        return;
    };
    let listen = format!("{}:29536", free_loopback());
    let _server = serve_can(&listen, &[]);
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
    // Process data on SYNC: a TPDO1 per SYNC, 8 bytes, the status "Ready to switch on".
    assert!(seen["tpdo_count"].as_u64().unwrap_or(0) >= 4, "{seen}");
    assert_eq!(seen["tpdo_len"], 8, "{seen}");
    assert_eq!(
        seen["tpdo_status"].as_u64().map(|s| s & 0xFF),
        Some(0x31),
        "{seen}"
    );
    // The EDS: python-canopen imports it and reads P102 set 1 by name, typed INTEGER16.
    assert_eq!(seen["eds_p102_by_name"], 250, "{seen}");
    assert_eq!(seen["eds_p102_type"], 0x0003, "{seen}");
    assert!(seen["eds_objects"].as_u64().unwrap_or(0) > 20, "{seen}");
    // 1016h:01, read from the node and the EDS's default: node 32's heartbeat, 600 ms.
    assert_eq!(seen["consumer_read"], 0x0020_0258, "{seen}");
    assert_eq!(seen["consumer_eds"], 0x0020_0258, "{seen}");
    let _ = std::fs::remove_file(&eds);
}

/// Every frame of a system-bus run's capture decodes as CANopen (a remote frame as CAN), none
/// malformed, and tshark finds in it what the cases say they did: the SDO read of P102 of FI 3
/// (node 36, 2066h sub-index 1), the nodes' abort codes for the bad requests and the error
/// frames of a faulty controller, each in the frame its case and step label.
#[test]
fn tshark_decodes_the_capture_of_a_system_bus_run_as_canopen() {
    if !require_tshark("tshark as the independent reader of the system bus's capture") {
        return;
    }
    let dir = std::env::temp_dir().join(format!("nord-can-pcap-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a folder for the run");
    let pcap = dir.join("can.pcapng");
    let run = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["run", "-q", "--profile", "sk550p@can", "--filter", "can/"])
        .arg("--out")
        .arg(&dir)
        .arg("--pcap")
        .arg(&pcap)
        .output()
        .expect("harness runs");
    assert!(run.status.success(), "{run:?}");
    let out = Command::new("tshark")
        .arg("-r")
        .arg(&pcap)
        .args(["-d", "can.subdissector,canopen", "-T", "fields"])
        .args(["-E", "occurrence=f", "-E", "separator=|"])
        .args(["-e", "_ws.col.Protocol", "-e", "canopen.cob_id"])
        .args(["-e", "canopen.sdo.main_idx", "-e", "canopen.sdo.sub_idx"])
        .args(["-e", "canopen.sdo.abort_code", "-e", "_ws.expert.severity"])
        .args([
            "-e",
            "frame.comment",
            "-e",
            "can.flags.rtr",
            "-e",
            "can.flags.err",
        ])
        .args(["-e", "_ws.col.Info"])
        .output()
        .expect("tshark runs");
    assert!(out.status.success(), "{out:?}");
    let text = String::from_utf8_lossy(&out.stdout);
    let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split('|').collect()).collect();
    assert!(rows.len() > 300, "{} frames", rows.len());
    for r in &rows {
        // CANopen's dissector leaves remote frames (a bad-input case's) and the controllers'
        // error frames (a bus-errors case's) to CAN's.
        let protocol = if r[7] == "1" || r[8] == "1" {
            "CAN"
        } else {
            "CANopen"
        };
        assert_eq!(r[0], protocol, "{r:?}");
        // Expert severity, in decimal: a comment (the frame's label) is 0x00100000; warnings
        // start at 0x00600000 (malformed frames are errors).
        let severity: u32 = r[5].parse().unwrap_or(0);
        assert!(severity < 0x0060_0000, "tshark flags {r:?}");
    }
    // The error frames of a node's faulty controller, as SocketCAN reports them (CAN_ERR_FLAG,
    // class 088h), each in its step.
    assert!(
        rows.iter().any(|r| r[8] == "1"
            && r[9].contains("Protocol violation")
            && r[6].contains("can/bus-errors/error-frames-are-seen-as-such")),
        "no error frame of the bus-errors case"
    );
    let has = |cob: &str, index: &str, sub: &str, abort: &str, case: &str| {
        rows.iter().any(|r| {
            r[1] == cob && r[2] == index && r[3] == sub && r[4] == abort && r[6].contains(case)
        })
    };
    assert!(
        has(
            "0x00000624",
            "0x2066",
            "0x01",
            "",
            "can/sdo/expedited-read-and-write"
        ),
        "no SDO to node 36 at 2066h:01"
    );
    for (cob, index, sub, abort, case) in [
        (
            "0x000005a0",
            "0x23e7",
            "0x00",
            "0x06020000",
            "can/sdo/absent-object step 1",
        ),
        (
            "0x000005a0",
            "0x2066",
            "0x01",
            "0x06090031",
            "can/sdo/value-too-high step 1",
        ),
        (
            "0x000005a4",
            "0x2066",
            "0x01",
            "0x06090032",
            "can/bad-input/p102-below-its-range",
        ),
        (
            "0x000005a4",
            "0x0000",
            "0x00",
            "0x05040001",
            "can/bad-input/command-specifier-7",
        ),
    ] {
        assert!(
            has(cob, index, sub, abort, case),
            "{case}: no abort {abort} from {cob}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The harness against any maker's CANopen node: python-canopen's LocalNode, with the object
/// dictionary of FI 1's EDS and python-canopen's own SDO server, joins the served bus as node 5;
/// `harness run --profile any --dut socketcand://…/can0/5` runs the CiA 301 cases written
/// relative to the node, and every one passes (expedited uploads, and the abort codes for an
/// absent object, an absent sub-index, a read-only object and an unknown command specifier).
#[test]
fn the_harness_tests_a_python_canopen_local_node_as_any_makers_node() {
    let Some(py) = interop_python(
        &["can", "canopen"],
        "a python-canopen LocalNode as the DUT of `--profile any`",
    ) else {
        return;
    };
    let listen = format!("{}:29536", free_loopback());
    let _server = serve_can(&listen, &[]);
    let eds = std::env::temp_dir().join(format!("nord-any-{}.eds", std::process::id()));
    let described = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["describe", "eds", "--bus", "can", "--profile", "sk550p"])
        .output()
        .expect("harness describe runs");
    assert!(described.status.success(), "{described:?}");
    std::fs::write(&eds, &described.stdout).expect("EDS written");
    let (host, port) = listen.split_once(':').expect("HOST:PORT");
    let script = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/interop/canopen_node.py");
    let mut child = Command::new(&py)
        .arg(script)
        .args([host, port, "can0", "5"])
        .arg(&eds)
        .arg("60")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("python runs");
    let mut ready = String::new();
    let stdout = child.stdout.take().expect("piped");
    let node = Server(child);
    std::io::BufRead::read_line(&mut std::io::BufReader::new(stdout), &mut ready)
        .expect("the node says it is ready");
    assert_eq!(ready.trim(), "ready");
    let out_dir = std::env::temp_dir().join(format!("nord-any-run-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["run", "--profile", "any", "--filter", "can/any-node/"])
        .args(["--dut", &format!("socketcand://{listen}/can0/5")])
        .arg("--out")
        .arg(&out_dir)
        .output()
        .expect("harness runs");
    drop(node);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    let report: Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("run.json")).unwrap()).unwrap();
    let passed = report["cases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["verdict"] == "pass")
        .count();
    assert_eq!(passed, 6, "{stdout}");
    assert!(
        report["meta"]["identities"]["any@can"].is_object(),
        "the node's identity is on record: {report}"
    );
    let _ = std::fs::remove_dir_all(&out_dir);
    let _ = std::fs::remove_file(&eds);
}
