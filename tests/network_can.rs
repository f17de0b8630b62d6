//! The harness against a system bus it reaches over the network: `harness serve can
//! --socketcand` serves the simulated segment of an SK 550P on loopback, and `harness run --dut
//! socketcand://HOST:PORT/can0` tests its inverters as a persistent device, with the same
//! system-bus cases as the embedded run; what a case wrote is written back afterwards, and
//! process data run in real time and end with the drives and nodes as the case found them; a
//! served EtherNet/IP module's system bus is tapped during a run over EtherNet/IP. A
//! missing bus name and a refused channel are clear errors; a segment served misbehaving on
//! purpose is named for what it did (a toggle bit, a size, silence, an EMCY of an error the
//! inverter does not have). Loopback only: no peer to skip for.

use std::process::Command;

use serde_json::Value;

#[allow(dead_code)] // what the other network tests share
mod common;
use common::addr::free_loopback;
use common::{case_verdict, serve_can, serve_with, wait_listening};

#[test]
fn the_system_bus_cases_pass_over_socketcand_and_leave_the_parameters_as_found() {
    let listen = format!("{}:29536", free_loopback());
    let _server = serve_can(&listen, &[]);
    let out_dir = std::env::temp_dir().join(format!("nord-can-dut-{}", std::process::id()));
    let run_with = |filter: &str, extra: &[&str]| {
        Command::new(env!("CARGO_BIN_EXE_harness"))
            .args(["run", "--profile", "sk550p", "--timeout", "2"])
            .args(extra)
            .args(["--filter", filter])
            .args(["--dut", &format!("socketcand://{listen}/can0")])
            .arg("--out")
            .arg(&out_dir)
            .output()
            .expect("harness runs")
    };
    let run = |filter: &str| run_with(filter, &[]);
    let out = run("can/sdo/");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    let report: Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("run.json")).unwrap()).unwrap();
    let cases = report["cases"].as_array().unwrap();
    let passed: Vec<&str> = cases
        .iter()
        .filter(|c| c["verdict"] == "pass")
        .filter_map(|c| c["id"].as_str())
        .collect();
    // Every case of the file applies to a device on the network (parameters over SDO).
    for id in [
        "can/sdo/expedited-read-and-write",
        "can/sdo/sets-are-sub-indices",
        "can/sdo/absent-object",
        "can/sdo/write-to-read-only",
        "can/sdo/value-too-high",
    ] {
        assert!(passed.contains(&id), "{id} did not pass: {stdout}");
    }
    assert_eq!(
        report["meta"]["identities"]["sk550p@can"]["vendor"], "00000538h",
        "{report}"
    );
    // The run wrote P102 of FI 3 and set 2 of FI 1, and put both back: a second run finds the
    // factory values again.
    let again = run("can/sdo/expedited-read-and-write");
    assert_eq!(
        again.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&again.stdout)
    );
    // Process data in the bus interface's place, in real time: the drive is enabled and
    // stopped through PDOs on SYNC and brought back to "Switch-on block" after the case. The
    // nodes are then back in pre-operational, where the PDO cases expect to find them.
    let moved = run_with("bu0620/drive-bits/enable-pulses-bit-4", &["--allow-motion"]);
    let stdout = String::from_utf8_lossy(&moved.stdout);
    assert_eq!(moved.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("1 pass, 0 fail"), "{stdout}");
    let pdo = run_with("can/pdo/pdos-only-in-operational", &["--allow-motion"]);
    let stdout = String::from_utf8_lossy(&pdo.stdout);
    assert_eq!(pdo.status.code(), Some(0), "{stdout}");
    assert!(stdout.contains("1 pass, 0 fail"), "{stdout}");
    let _ = std::fs::remove_dir_all(&out_dir);
}

#[test]
fn a_socketcand_url_without_a_bus_or_with_an_unknown_one_is_a_clear_error() {
    let listen = format!("{}:29536", free_loopback());
    let _server = serve_can(&listen, &[]);
    let no_bus = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args([
            "run",
            "--profile",
            "sk550p",
            "--dut",
            &format!("socketcand://{listen}"),
        ])
        .output()
        .expect("harness runs");
    assert_eq!(no_bus.status.code(), Some(2));
    let said = String::from_utf8_lossy(&no_bus.stderr);
    assert!(said.contains("give the bus after a slash"), "{said}");
    let out_dir = std::env::temp_dir().join(format!("nord-can-refused-{}", std::process::id()));
    let refused = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args([
            "run",
            "--profile",
            "sk550p",
            "--filter",
            "can/sdo/absent-object",
        ])
        .args(["--dut", &format!("socketcand://{listen}/can7")])
        .arg("--out")
        .arg(&out_dir)
        .output()
        .expect("harness runs");
    let said = String::from_utf8_lossy(&refused.stdout);
    assert_ne!(refused.status.code(), Some(0), "{said}");
    assert!(said.contains("could not open bus"), "{said}");
    // A tap that is not socketcand's is refused before anything runs.
    let tap = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["run", "--profile", "sk550p", "--tap", "http://x/can0"])
        .args(["--dut", &format!("socketcand://{listen}/can0")])
        .output()
        .expect("harness runs");
    assert_eq!(tap.status.code(), Some(2));
    let said = String::from_utf8_lossy(&tap.stderr);
    assert!(
        said.contains("`--tap http://x/can0`: give socketcand://"),
        "{said}"
    );
    let _ = std::fs::remove_dir_all(&out_dir);
}

/// `harness serve can --misbehave SPEC` (`docs/misbehave.md`): the harness's SDO client names
/// what the segment did wrong when the connection check asks FI 1's node who it is (1008h,
/// a segmented upload): a toggle bit not alternated (the transfer aborted with 05030000h, as
/// CiA 301 §7.2.4.3.5 has the client do), a size announced that the segments do not carry, a
/// bus gone silent; an error that stops the run, never a hang or a pass.
#[test]
fn a_misbehaving_segment_is_named_for_what_it_did() {
    for (spec, says) in [
        (
            "corrupt=sequence",
            "upload segment of 1008h:00h with toggle bit 1, expected 0: aborted with 05030000h (Toggle bit not alternated)",
        ),
        (
            "corrupt=length",
            "6 bytes of 1008h:00h uploaded, 106 announced",
        ),
        ("silent=600s", "no SDO answer from node 32"),
    ] {
        let listen = format!("{}:29536", free_loopback());
        let _server = serve_can(&listen, &["--misbehave", spec]);
        let cases = common::cases_of_run(
            Command::new(env!("CARGO_BIN_EXE_harness")),
            "sk550p",
            &format!("socketcand://{listen}/can0"),
            "can/sdo/expedited-read-and-write",
        );
        let first = &cases[0];
        let message = first["message"].as_str().unwrap_or_default();
        assert_eq!(first["id"], "harness/connection-check", "{spec}: {message}");
        assert_eq!(first["verdict"], "error", "{spec}: {message}");
        assert!(message.contains(says), "{spec}: {message:?} does not say {says:?}");
    }
}

/// `harness serve can --misbehave alarm=`: FI 1's node sends EMCY 7580h (P700 100) though its
/// inverter has no error; the process step that hears it reads P700 and P701 and fails naming
/// it (`crate::binding::emergency`), a case that would pass otherwise.
#[test]
fn a_spurious_emcy_fails_the_step_that_hears_it() {
    let listen = format!("{}:29536", free_loopback());
    let _server = serve_can(&listen, &["--misbehave", "alarm=every:200ms"]);
    let cases = common::cases_of_run(
        Command::new(env!("CARGO_BIN_EXE_harness")),
        "sk550p",
        &format!("socketcand://{listen}/can0"),
        "bu0620/drive-bits/enable-pulses-bit-4",
    );
    let case = &cases[0];
    let message = case["message"].as_str().unwrap_or_default();
    assert_eq!(case["verdict"], "fail", "{message}");
    assert!(
        message.contains(
            "node 32's EMCY 7580h (error register 11h) reports error 100 (P700) on FI 1, but P700 [-01] reads 0 and P701 (the last 5 errors) does not hold it"
        ),
        "{message}"
    );
}

/// Both sides of a served bus module's gateway: `harness serve enip --system-bus` publishes the
/// CANopen frames its gateway exchanges with the inverters over socketcand, and a run over
/// EtherNet/IP with `--tap` asserts them (P102 of FI 3 written over CIP is an SDO download to
/// node 36; FI 2's process data are PDOs of node 34). Without `--tap` the same cases are not
/// applicable, saying what they need.
#[test]
fn an_enip_run_with_tap_asserts_the_served_modules_system_bus() {
    let ip = free_loopback();
    let (listen, bus) = (format!("{ip}:44818"), format!("{ip}:29536"));
    let _server = serve_with(&listen, "tu4-eip", 120, &["--system-bus", &bus]);
    wait_listening(&bus, std::time::Duration::from_secs(10));
    let dut = format!("enip://{ip}");
    common::check_tap_runs(
        || Command::new(env!("CARGO_BIN_EXE_harness")),
        &["--profile", "tu4-eip", "--dut", &dut],
        "bu2100/systembus/gateway",
        &bus,
        &[
            "bu2100/systembus/gateway-parameter-access-is-sdo",
            "bu2100/systembus/gateway-process-data-are-pdos",
        ],
    );
}

/// SocketCAN, where the kernel has it: `harness serve can --iface` serves the segment on a vcan
/// interface and `harness run --dut can://IFACE` runs the SDO cases against it, as against a
/// real adapter. Without root or a kernel with AF_CAN and vcan the test says so and returns,
/// under CI too: the one skip this project allows (README).
#[test]
fn socketcan_serves_and_runs_the_system_bus_where_vcan_exists() {
    let iface = format!("vcannord{}", std::process::id() % 1000);
    let ip = |args: &[&str]| {
        Command::new("ip")
            .args(args)
            .output()
            .is_ok_and(|o| o.status.success())
    };
    let made =
        ip(&["link", "add", "dev", &iface, "type", "vcan"]) && ip(&["link", "set", "up", &iface]);
    if !common::peer::allowed_skip(
        made,
        "a vcan interface (root, and a kernel with AF_CAN and the vcan module)",
        "SocketCAN: harness serve can --iface and run --dut can://IFACE",
    ) {
        return;
    }
    struct Gone<'a>(&'a str);
    impl Drop for Gone<'_> {
        fn drop(&mut self) {
            let _ = Command::new("ip").args(["link", "del", self.0]).output();
        }
    }
    let _gone = Gone(&iface);
    let server = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["serve", "can", "--iface", &iface, "--seconds", "60"])
        .stdout(std::process::Stdio::null())
        .spawn()
        .expect("harness serve can starts");
    let _server = common::Server(server);
    std::thread::sleep(std::time::Duration::from_millis(500));
    let out_dir = std::env::temp_dir().join(format!("nord-socketcan-{}", std::process::id()));
    let out = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["run", "--profile", "sk550p", "--filter", "can/sdo/"])
        .args(["--dut", &format!("can://{iface}")])
        .arg("--out")
        .arg(&out_dir)
        .output()
        .expect("harness runs");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}");
    let report: Value =
        serde_json::from_slice(&std::fs::read(out_dir.join("run.json")).unwrap()).unwrap();
    assert_eq!(
        case_verdict(&report, "can/sdo/expedited-read-and-write").0,
        "pass",
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(&out_dir);
}
