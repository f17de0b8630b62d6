//! The harness against devices that misbehave on purpose (`harness serve <bus> --misbehave`,
//! `docs/misbehave.md`): for each mode on each Ethernet bus where it applies, the harness's own
//! master, managing node, controller or scanner runs a case against the served device, and its
//! verdict names what the device did — never a hang, a panic, a pass or "host late". The modes
//! are chosen so that the verdict does not hang on timing: a field sent wrong in every frame,
//! a device silent from its first exchange on, a connection closed at its second request;
//! the harness's own limits decide, with their margins.
//!
//! The raw buses need root (network namespaces, raw sockets); without it those tests say so
//! and skip on a developer's machine, and fail in strict mode. EtherNet/IP runs on loopback.


use harness::misbehave::Misbehaviour;

#[allow(dead_code)] // what the other network tests share
mod common;
use common::netns::{require_root_or_skip, Netns};

/// The served device's misbehaviour, parsed as `--misbehave` parses it.
fn spec(s: &str) -> Misbehaviour {
    s.parse().unwrap_or_else(|e| panic!("{s}: {e}"))
}

/// The one case of a run (its connection check's, when the run stopped there): verdict and
/// message, after checking it neither passed nor blamed the host.
fn the_case(cases: &[serde_json::Value]) -> (String, String) {
    assert!(!cases.is_empty(), "no case ran");
    let c = &cases[0];
    let verdict = c["verdict"].as_str().unwrap_or_default().to_string();
    let message = c["message"].as_str().unwrap_or_default().to_string();
    assert_ne!(verdict, "pass", "{message}");
    assert!(!message.contains("host late"), "{message}");
    (verdict, message)
}

fn assert_says(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(message.contains(p), "{message:?} does not say {p:?}");
    }
}

/// EtherCAT: `spec` on a slave, one AL case from the namespace; verdict and message.
fn ecat(tag: &str, s: &str) -> (String, String, harness::misbehave::Touched) {
    let ns = Netns::new(tag);
    let options = harness::ecat_serve::ServeOptions {
        misbehave: spec(s),
        ..harness::ecat_serve::ServeOptions::new(ns.root_if())
    };
    let served = harness::ecat_serve::start(&options).expect("serve ecat");
    let cases = common::cases_of_run(
        ns.command(env!("CARGO_BIN_EXE_harness")),
        "sk550p@ecat",
        &format!("ecat://{}", ns.ns_if()),
        "bu0620/ecat-al/start-up-sequence",
    );
    let stats = served.stop().expect("the slave served to the end");
    let (v, m) = the_case(&cases);
    (v, m, stats.misbehaved)
}

#[test]
fn ecat_a_slave_whose_working_counter_is_0_is_named_for_it() {
    if !require_root_or_skip("serve ecat --misbehave corrupt=wkc over a veth pair") {
        return;
    }
    let (verdict, message, touched) = ecat("mbwkc", "corrupt=wkc");
    assert_eq!(verdict, "error", "{message}");
    assert_says(&message, &["working counter 0"]);
    assert!(touched.corrupted > 0, "{touched:?}");
}

#[test]
fn ecat_a_slave_silent_from_its_first_frame_is_unreachable_not_a_hang() {
    if !require_root_or_skip("serve ecat --misbehave silent=… over a veth pair") {
        return;
    }
    let (verdict, message, touched) = ecat("mbesil", "silent=600s");
    assert_eq!(verdict, "error", "{message}");
    assert_says(&message, &["no answer"]);
    assert!(touched.silenced > 0, "{touched:?}");
}

/// POWERLINK: `spec` on node 1, one NMT case from the namespace as MN.
fn epl(tag: &str, s: &str) -> (String, String, harness::misbehave::Touched) {
    let ns = Netns::new(tag);
    ns.add_ipv4("192.168.100.1/24", "192.168.100.240/24");
    let options = harness::epl_serve::ServeOptions {
        misbehave: spec(s),
        ..harness::epl_serve::ServeOptions::new(ns.root_if())
    };
    let served = harness::epl_serve::start(&options).expect("serve epl");
    let cases = common::cases_of_run(
        ns.command(env!("CARGO_BIN_EXE_harness")),
        "sk550p@epl",
        &format!("epl://{}", ns.ns_if()),
        "bu0620/epl-nmt/start-up-sequence",
    );
    let stats = served.stop().expect("the node served to the end");
    let (v, m) = the_case(&cases);
    (v, m, stats.misbehaved)
}

#[test]
fn epl_a_node_whose_pres_says_stopped_is_named_for_its_state() {
    if !require_root_or_skip("serve epl --misbehave corrupt=state over a veth pair") {
        return;
    }
    let (_, message, touched) = epl("mbstate", "corrupt=state");
    assert_says(&message, &["STOPPED"]);
    assert!(touched.corrupted > 0, "{touched:?}");
}

#[test]
fn epl_a_node_silent_from_its_first_frame_is_unreachable_not_a_hang() {
    if !require_root_or_skip("serve epl --misbehave silent=… over a veth pair") {
        return;
    }
    let (verdict, message, touched) = epl("mbplsil", "silent=600s");
    assert_eq!(verdict, "error", "{message}");
    assert_says(&message, &["no "]);
    assert!(touched.silenced > 0, "{touched:?}");
}

/// PROFINET IO: `spec` on the device, one connect case from the namespace as controller.
fn pnio(tag: &str, s: &str) -> (String, String, harness::misbehave::Touched) {
    const NAME: &str = "nord-device";
    let ns = Netns::new(tag);
    ns.add_ipv4("192.168.22.200/24", "192.168.22.1/24");
    let options = harness::pnio_serve::ServeOptions {
        name: NAME.to_string(),
        misbehave: spec(s),
        ..harness::pnio_serve::ServeOptions::new(ns.root_if())
    };
    let served = harness::pnio_serve::start(&options).expect("serve pnio");
    let cases = common::cases_of_run(
        ns.command(env!("CARGO_BIN_EXE_harness")),
        "sk550p@pnio",
        &format!("pnio://{}/{NAME}", ns.ns_if()),
        "pnio/connect/",
    );
    let stats = served.stop().expect("the device served to the end");
    let (v, m) = the_case(&cases);
    (v, m, stats.misbehaved)
}

#[test]
fn pnio_a_device_whose_data_is_not_valid_is_named_for_its_data_status() {
    if !require_root_or_skip("serve pnio --misbehave corrupt=data-status over a veth pair") {
        return;
    }
    let (_, message, touched) = pnio("mbdstat", "corrupt=data-status");
    assert_says(&message, &["data status"]);
    assert!(touched.corrupted > 0, "{touched:?}");
}

#[test]
fn pnio_a_device_silent_from_its_first_frame_is_unreachable_not_a_hang() {
    if !require_root_or_skip("serve pnio --misbehave silent=… over a veth pair") {
        return;
    }
    let (verdict, message, touched) = pnio("mbpnsil", "silent=600s");
    assert_eq!(verdict, "error", "{message}");
    assert_says(&message, &["no DCP"]);
    assert!(touched.silenced > 0, "{touched:?}");
}

/// EtherNet/IP on loopback: `harness serve enip --misbehave SPEC`, one identity case.
fn enip(s: &str) -> (String, String) {
    let listen = format!("{}:44818", common::addr::free_loopback());
    let _server = common::serve_with(&listen, "tu3-eip", 120, &["--misbehave", s]);
    let cases = common::cases_of_run(
        std::process::Command::new(env!("CARGO_BIN_EXE_harness")),
        "tu3-eip",
        &format!("enip://{listen}"),
        "bu2100/identity/",
    );
    the_case(&cases)
}

#[test]
fn enip_an_adapter_whose_replies_say_service_not_supported_is_named_for_it() {
    let (_, message) = enip("corrupt=status");
    assert_says(&message, &["08h"]);
}

#[test]
fn enip_an_adapter_that_closes_mid_exchange_is_named_for_it() {
    let (verdict, message) = enip("close");
    assert_eq!(verdict, "error", "{message}");
    assert_says(&message, &["closed"]);
}

/// A bad spec is a usage error naming the bad part, and what a bus cannot do is refused
/// naming the bus, before anything is served.
#[test]
fn a_bad_spec_is_a_usage_error_naming_the_part() {
    for (args, says) in [
        (
            vec!["serve", "enip", "--misbehave", "late=1s,drop=150%"],
            "`drop=150%`: `150%` is not a percentage 1%…100%",
        ),
        (
            vec!["serve", "ecat", "--iface", "lo", "--misbehave", "close"],
            "`close`: EtherCAT has no session to close",
        ),
        (
            vec!["serve", "epl", "--iface", "lo", "--misbehave", "corrupt=wkc"],
            "`corrupt=wkc`: POWERLINK has no such field (its fields: state)",
        ),
        (
            vec!["serve", "pnio", "--iface", "lo", "--misbehave", "explode"],
            "`explode`: unknown mode",
        ),
    ] {
        let out = common::cli::harness(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(says), "{args:?}: {stderr}");
    }
}
