//! The harness's PROFINET suites over the wire: `harness serve pnio` on one end of a veth pair
//! (raw Ethernet, and RPC on UDP 34964 at 192.168.20.200), `harness run --dut
//! pnio://IFACE/nord-device` as IO controller inside a network namespace on the other
//! (192.168.20.1), for the SK TU3-PNT (`tu3-pnt`); what its run and captures must show is
//! [`common::pnio_wire::check`]. The SK 5xxP's (`sk550p`) full run is the first of the load
//! test's five (`network_load`), under the same checks. Then a silent or garbage-sending
//! impostor and a device answering late.
//!
//! Needs root (network namespaces, raw sockets) and tshark (`.ci/interop-setup`); without
//! them the test says so and skips on a developer's machine, and fails in strict mode.

use harness::pnio_serve::{start, ServeOptions};
use serde_json::Value;

#[allow(dead_code)] // what the other network tests share
mod common;
use common::netns::{require_root_or_skip, Netns};
use common::peer::require_tshark;
use common::suite_run::SuiteRun;

/// The name of station the suites address the device by.
const NAME: &str = "nord-device";

#[test]
fn every_profinet_suite_passes_against_a_served_tu3_pnt_over_a_veth_pair() {
    // On a loaded host when `.ci/run` asks (NORD_TEST_HOG): the verdicts must hold there too.
    let _hog = common::hog::Hog::if_asked();
    let why = "the PROFINET suites against harness serve pnio over a veth pair";
    if !require_root_or_skip(why) || !require_tshark(why) {
        return;
    }
    let ns = Netns::new("pniosuites");
    ns.add_ipv4("192.168.20.200/24", "192.168.20.1/24");
    let mut options = ServeOptions::new(ns.root_if());
    options.profile = "tu3-pnt".to_string();
    options.name = NAME.to_string();
    let served = start(&options).expect("serve pnio");
    let run = SuiteRun::new(
        &ns,
        "pnio",
        "tu3-pnt@pnio",
        &format!("pnio://{}/{NAME}", ns.ns_if()),
    );
    let stats = served.stop().expect("the device served to the end");
    common::pnio_wire::check(&run, "tu3-pnt", &stats);
    run.finish();
}

/// What stands behind the interface instead of a device.
#[derive(Clone, Copy, Debug)]
enum Impostor {
    /// Nothing answers.
    Silent,
    /// Every DCP Identify gets a response frame with its Xid whose DCPDataLength runs past the
    /// frame.
    Garbage,
}

/// Answers the Identify requests arriving on `iface` with garbage until `stop`.
fn garbage_responder(iface: &str, stop: std::sync::Arc<std::sync::atomic::AtomicBool>) {
    use pnet_datalink::Channel;
    let interface = pnet_datalink::interfaces()
        .into_iter()
        .find(|i| i.name == iface)
        .expect("the veth end");
    let config = pnet_datalink::Config {
        read_timeout: Some(std::time::Duration::from_millis(20)),
        ..Default::default()
    };
    let Ok(Channel::Ethernet(mut tx, mut rx)) = pnet_datalink::channel(&interface, config) else {
        panic!("a raw socket on {iface}");
    };
    while !stop.load(std::sync::atomic::Ordering::Relaxed) {
        let Ok(frame) = rx.next() else { continue };
        // EtherType 8892h, frame id FEFEh: an Identify request.
        if frame.len() < 22 || frame[12..14] != [0x88, 0x92] || frame[14..16] != [0xFE, 0xFE] {
            continue;
        }
        let mut answer = Vec::new();
        answer.extend_from_slice(&frame[6..12]); // to the requester
        answer.extend_from_slice(&[0x02, 0, 0, 0, 0, 0x66]);
        answer.extend_from_slice(&[0x88, 0x92, 0xFE, 0xFF, 0x05, 0x01]);
        answer.extend_from_slice(&frame[18..22]); // its Xid
        answer.extend_from_slice(&[0x00, 0x00, 0x05, 0xDC]); // DCPDataLength 1500
        answer.resize(60, 0xA5);
        let _ = tx.send_to(&answer, None);
    }
}

#[test]
fn a_silent_or_garbage_sending_device_is_an_error_verdict_within_the_timeout() {
    let why = "the IO controller against a silent and a garbage-sending veth end";
    if !require_root_or_skip(why) {
        return;
    }
    for impostor in [Impostor::Silent, Impostor::Garbage] {
        let ns = Netns::new("pniofake");
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let responder = match impostor {
            Impostor::Silent => None,
            Impostor::Garbage => {
                let (iface, stop) = (ns.root_if().to_string(), stop.clone());
                Some(std::thread::spawn(move || garbage_responder(&iface, stop)))
            }
        };
        let out_dir =
            std::env::temp_dir().join(format!("harness-pnio-{impostor:?}-{}", std::process::id()));
        let start = std::time::Instant::now();
        let out = ns
            .command(env!("CARGO_BIN_EXE_harness"))
            .args(["run", "--profile", "sk550p@pnio", "--timeout", "0.3"])
            .args(["--filter", "pnio/dcp/identify"])
            .arg("--dut")
            .arg(format!("pnio://{}", ns.ns_if()))
            .arg("--out")
            .arg(&out_dir)
            .output()
            .expect("harness runs");
        let took = start.elapsed();
        stop.store(true, std::sync::atomic::Ordering::Relaxed);
        if let Some(r) = responder {
            r.join().expect("the responder ends");
        }
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(out.status.code(), Some(1), "{impostor:?}: {stdout}");
        let run: Value =
            serde_json::from_slice(&std::fs::read(out_dir.join("run.json")).unwrap()).unwrap();
        let cases: Vec<&Value> = run["cases"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| c["verdict"] != "not_applicable")
            .collect();
        assert!(!cases.is_empty(), "{impostor:?}: {stdout}");
        let says = match impostor {
            Impostor::Silent => "no PROFINET IO device answered Identify",
            Impostor::Garbage => "malformed DCP Identify response",
        };
        for c in &cases {
            assert_eq!(c["verdict"], "error", "{impostor:?}: {c}");
            assert!(
                c["message"].as_str().unwrap().contains(says),
                "{impostor:?}: {c}"
            );
        }
        // A bound against a hang, not a speed figure: each case ends at the 0.3 s timeout, and
        // the rest is a debug process starting on a host that CI keeps busy (two busy loops
        // beside the tests made it 4.3 s once), far below any wait a hang would reach.
        assert!(
            took < std::time::Duration::from_secs(10 + cases.len() as u64),
            "{impostor:?}: {} cases took {took:?}",
            cases.len()
        );
        let _ = std::fs::remove_dir_all(&out_dir);
    }
}

/// A device whose DCP responses leave later than the controller's Identify window (400 ms)
/// is late, and the report says so with both times — the limit and how long the harness
/// waited — while the host was on time: never "host late", never a pass, and a fail, not an
/// error: given five times its limits the device comes up, so it is there and late, not
/// absent. Identify comes first, so the run ends at its connection check.
#[test]
fn a_device_whose_answers_leave_past_the_limit_is_late_with_both_times() {
    let why = "a late PROFINET IO device (serve pnio --misbehave late=…) over a veth pair";
    if !require_root_or_skip(why) {
        return;
    }
    let ns = Netns::new("pniolate");
    ns.add_ipv4("192.168.20.200/24", "192.168.20.1/24");
    let options = ServeOptions {
        name: NAME.to_string(),
        misbehave: harness::misbehave::Misbehaviour::late(std::time::Duration::from_millis(600)),
        ..ServeOptions::new(ns.root_if())
    };
    let served = start(&options).expect("serve pnio");
    let cases = common::cases_of_run(
        ns.command(env!("CARGO_BIN_EXE_harness")),
        "sk550p@pnio",
        &format!("pnio://{}/{NAME}", ns.ns_if()),
        "pnio/records/",
    );
    served.stop().expect("the device served to the end");
    assert_eq!(cases.len(), 1, "{cases:?}");
    let (verdict, message) = (&cases[0]["verdict"], cases[0]["message"].as_str().unwrap());
    assert_eq!(verdict, "fail", "{message}");
    assert!(
        message.contains(
            "the DUT answers late: no DCP Identify response from the device within its limit \
             of 400 ms (waited "
        ) && message.contains("given 5 times its limits, it came up"),
        "{message}"
    );
    assert!(!message.contains("host late"), "{message}");
}

/// Both sides of the SK 550P's gateway over PROFINET: `harness serve pnio --system-bus`
/// publishes the CANopen frames it exchanges with FI 2…8 over socketcand, and a run over
/// PROFINET from the namespace with `--tap` asserts them (BU 0620: P102 of FI 3 written over a
/// data record is an SDO download to node 36). Without `--tap` the case is not applicable,
/// saying what it needs.
#[test]
fn a_pnio_run_with_tap_asserts_the_served_devices_system_bus() {
    let why = "harness serve pnio --system-bus against a run with --tap over a veth pair";
    if !require_root_or_skip(why) {
        return;
    }
    // A subnet of its own: the suites' test serves on 192.168.20.200 at the same time (its RPC
    // socket and its routes); the device takes this interface's address.
    let ns = Netns::new("pniotap");
    ns.add_ipv4("192.168.21.200/24", "192.168.21.1/24");
    // The relay listens on the served side's address, which the namespace reaches over the pair.
    let bus = "192.168.21.200:29536";
    let _server =
        common::serve_on_iface_with_relay("pnio", ns.root_if(), "sk550p", &["--name", NAME], bus);
    let id = "bu0620/systembus/gateway-parameter-of-fi3-is-sdo";
    let dut = format!("pnio://{}/{NAME}", ns.ns_if());
    common::check_tap_runs(
        || ns.command(env!("CARGO_BIN_EXE_harness")),
        &["--profile", "sk550p", "--dut", &dut],
        id,
        bus,
        &[id],
    );
}
