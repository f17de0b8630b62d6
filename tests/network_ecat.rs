//! The harness against an EtherCAT slave over the wire: `harness serve ecat` on one end of a
//! veth pair, `harness run --dut ecat://IFACE` inside a network namespace on the other. The
//! full `sk550p@ecat` run over the wire is the first of the load test's five
//! (`network_load`), with what its captures must show ([`common::ecat_wire::check`]); here, a
//! slave answering late.
//!
//! Needs root (network namespaces, raw sockets); without it the test says so and skips on a
//! developer's machine, and fails in strict mode.

use harness::ecat_serve::{start, ServeOptions};

#[allow(dead_code)] // what the other network tests share
mod common;
use common::netns::{require_root_or_skip, Netns};

/// A slave whose frames come back later than the master's limit for a frame (50 ms; ETG.1000
/// prints none) is late, and the report says so with both times — the limit and how long the
/// harness waited — while the host was on time: never "host late", never a pass, and a fail,
/// not an error: given five times its limits the slave comes up, so it is there and late, not
/// absent. The frames are late from the scan on, so the run ends at its connection check.
#[test]
fn a_slave_whose_frames_come_back_past_the_limit_is_late_with_both_times() {
    let why = "a late EtherCAT slave (serve ecat --misbehave late=…) over a veth pair";
    if !require_root_or_skip(why) {
        return;
    }
    let ns = Netns::new("eclate");
    let options = ServeOptions {
        misbehave: harness::misbehave::Misbehaviour::late(std::time::Duration::from_millis(80)),
        ..ServeOptions::new(ns.root_if())
    };
    let served = start(&options).expect("serve ecat");
    let dut = format!("ecat://{}", ns.ns_if());
    let harness = ns.command(env!("CARGO_BIN_EXE_harness"));
    let cases = common::cases_of_run(harness, "sk550p@ecat", &dut, "bu0620/ecat-al/");
    served.stop().expect("the slave served to the end");
    assert_eq!(cases.len(), 1, "{cases:?}");
    let (verdict, message) = (&cases[0]["verdict"], cases[0]["message"].as_str().unwrap());
    assert_eq!(verdict, "fail", "{message}");
    assert!(
        message.contains(
            "the DUT answers late: a frame back: no answer within the device's limit of 50 ms \
             (waited "
        ) && message.contains("given 5 times its limits, it came up"),
        "{message}"
    );
    assert!(!message.contains("host late"), "{message}");
}

/// Both sides of the SK 550P's gateway over EtherCAT: `harness serve ecat --system-bus`
/// publishes the CANopen frames it exchanges with FI 2…8 over socketcand, and a run over
/// EtherCAT from the namespace with `--tap` asserts them (BU 0620: P102 of FI 3 written over CoE
/// is an SDO download to node 36). Without `--tap` the case is not applicable, saying what it
/// needs.
#[test]
fn an_ecat_run_with_tap_asserts_the_served_slaves_system_bus() {
    let why = "harness serve ecat --system-bus against a run with --tap over a veth pair";
    if !require_root_or_skip(why) {
        return;
    }
    let ns = Netns::new("ecattap");
    // EtherCAT needs no address; the relay listens on one of this pair alone, which the
    // namespace reaches over it.
    ns.add_ipv4("10.223.0.1/30", "10.223.0.2/30");
    let bus = "10.223.0.1:29536";
    let _server = common::serve_on_iface_with_relay("ecat", ns.root_if(), "sk550p", &[], bus);
    let id = "bu0620/systembus/gateway-parameter-of-fi3-is-sdo";
    let dut = format!("ecat://{}", ns.ns_if());
    common::check_tap_runs(
        || ns.command(env!("CARGO_BIN_EXE_harness")),
        &["--profile", "sk550p", "--dut", &dut],
        id,
        bus,
        &[id],
    );
}
