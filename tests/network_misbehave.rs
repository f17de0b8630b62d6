//! The harness against devices that misbehave on purpose (`harness serve <bus> --misbehave`,
//! `docs/misbehave.md`): the harness's own master, managing node, controller or scanner runs a
//! case against the served device, and its verdict names what the device did — never a hang,
//! a panic, a pass or "host late". Covered: EtherCAT `corrupt=wkc`, `corrupt=length`,
//! `drop=every:2`, `silent`, `corrupt=sequence`, `alarm=every:2ms`; POWERLINK `corrupt=state`,
//! `silent`, `drop=every:3`, `alarm=`; PROFINET IO `corrupt=data-status`, `corrupt=cycle`,
//! `corrupt=status`, `alarm=every:20ms`, that with `corrupt=sequence`, `silent`; EtherNet/IP
//! `corrupt=status`, `corrupt=length`, `corrupt=sequence`, `close`, `dup`, `drop=every:2`;
//! `late=` has its own tests (`network_ecat`, `network_pnio`, `network_dut`,
//! the POWERLINK binding's). The modes are those whose verdict does not hang on timing: a
//! field wrong in every frame, a device silent from its first exchange on, the n-th answer of
//! a master that asks one thing at a time; the harness's own limits decide, with their margins.
//!
//! The raw buses need root (network namespaces, raw sockets); without it those tests say so
//! and skip on a developer's machine, and fail in strict mode. EtherNet/IP runs on loopback.

use harness::misbehave::{Misbehaviour, Touched};

#[allow(dead_code)] // what the other network tests share
mod common;
use common::netns::{require_root_or_skip, Netns};

/// The served device's misbehaviour, parsed as `--misbehave` parses it.
fn spec(s: &str) -> Misbehaviour {
    s.parse().unwrap_or_else(|e| panic!("{s}: {e}"))
}

/// The first case of a run (its connection check's, when the run stopped there) must have
/// `verdict` and a message that says each of `says`. A host too loaded for the device's limit
/// (the two busy loops of `.ci/run` beside a debug build) may make a time-out inconclusive
/// instead: the harness then says the host was late, and its last attempt must still name what
/// the device did. Never a pass.
fn check(cases: &[serde_json::Value], verdict: &str, says: &[&str]) {
    let c = cases.first().expect("a case ran");
    let message = c["message"].as_str().unwrap_or_default();
    println!("{}: {}: {message}", c["id"], c["verdict"]);
    if c["verdict"] == "inconclusive" && message.starts_with("host late by ") {
        assert!(message.contains("(last attempt: "), "{message}");
    } else {
        assert_eq!(c["verdict"], verdict, "{message}");
        assert!(!message.contains("host late"), "{message}");
    }
    for p in says {
        assert!(message.contains(p), "{message:?} does not say {p:?}");
    }
}

/// Runs the cases whose id contains `filter` for `profile` against `dut` from inside `ns`,
/// then stops the served device (`stop`: what it touched), and checks the first case.
fn judged(
    ns: &Netns,
    (profile, dut, filter): (&str, String, &str),
    stop: impl FnOnce() -> Touched,
    verdict: &str,
    says: &[&str],
) -> Touched {
    let harness = ns.command(env!("CARGO_BIN_EXE_harness"));
    let cases = common::cases_of_run(harness, profile, &dut, filter);
    let touched = stop();
    check(&cases, verdict, says);
    touched
}

/// EtherCAT: `s` on a slave, the AL start-up case from the namespace; what the slave touched.
fn ecat(tag: &str, s: &str, verdict: &str, says: &[&str]) -> Touched {
    ecat_case(tag, s, "bu0620/ecat-al/start-up-sequence", verdict, says)
}

/// EtherCAT: `s` on a slave, the cases whose id contains `case` from the namespace.
fn ecat_case(tag: &str, s: &str, case: &str, verdict: &str, says: &[&str]) -> Touched {
    let ns = Netns::new(tag);
    let options = harness::ecat_serve::ServeOptions {
        misbehave: spec(s),
        ..harness::ecat_serve::ServeOptions::new(ns.root_if())
    };
    let served = harness::ecat_serve::start(&options).expect("serve ecat");
    let run = ("sk550p@ecat", format!("ecat://{}", ns.ns_if()), case);
    let stop = || {
        served
            .stop()
            .expect("the slave served to the end")
            .misbehaved
    };
    judged(&ns, run, stop, verdict, says)
}

#[test]
fn ecat_a_slave_misbehaving_is_named_for_what_it_did() {
    if !require_root_or_skip("serve ecat --misbehave over veth pairs") {
        return;
    }
    // A working counter of 0 in every datagram: no slave processed the scan's read.
    let t = ecat(
        "mbwkc",
        "corrupt=wkc",
        "error",
        &["the broadcast read counted no slave"],
    );
    assert!(t.corrupted > 0, "{t:?}");
    let t = ecat(
        "mblen",
        "corrupt=length",
        "error",
        &["malformed EtherCAT frame came back: EtherCAT length: length 2047 but "],
    );
    assert!(t.corrupted > 0, "{t:?}");
    // The master sends one frame at a time: the second is the one lost.
    let no_answer = "a frame back: no answer within the device's limit of 50 ms";
    let t = ecat("mbedrop", "drop=every:2", "error", &[no_answer]);
    assert!(t.dropped > 0, "{t:?}");
    let t = ecat("mbesil", "silent=600s", "error", &[no_answer]);
    assert!(t.silenced > 0, "{t:?}");
    // Every answer from the send mailbox #1: from the second on, a repeat of the one before.
    // The connection check's identity read (1018h over CoE) meets it first and stops the run:
    // an answer that breaks the protocol is the device's, whatever the cases would ask.
    let t = ecat_case(
        "mbeseq",
        "corrupt=sequence",
        "bu0620/ecat-coe/identity-object",
        "error",
        &[
            "asked who it is: malformed answer from the DUT: mailbox counter 1 repeated: 1 \
           answer(s) with the counter of the message before discarded as a repeat, and no new \
           one within ",
        ],
    );
    assert!(t.corrupted > 0, "{t:?}");
}

#[test]
fn ecat_a_slave_raising_an_emergency_for_no_error_is_named_for_it() {
    if !require_root_or_skip("serve ecat --misbehave over veth pairs") {
        return;
    }
    // E10.2 on FI 1 in the send mailbox every 2 ms from Pre-Operational on (the queue keeps
    // the last 16): the master sets each aside while it waits for its answer, then asks
    // P700/P701. A release build runs one case's uploads in about the 2 ms between two, so
    // the run takes every CoE and PDO case of BU 0620: those the emergencies meet must fail
    // naming it, none may pass otherwise unnoticed in all of them.
    let ns = Netns::new("mbealarm");
    let options = harness::ecat_serve::ServeOptions {
        misbehave: spec("alarm=every:2ms"),
        ..harness::ecat_serve::ServeOptions::new(ns.root_if())
    };
    let served = harness::ecat_serve::start(&options).expect("serve ecat");
    let cases = common::cases_of_run(
        ns.command(env!("CARGO_BIN_EXE_harness")),
        "sk550p@ecat",
        &format!("ecat://{}", ns.ns_if()),
        "bu0620/ecat-",
    );
    let t = served
        .stop()
        .expect("the slave served to the end")
        .misbehaved;
    let says = "the DUT departed from the protocol: CoE emergency 7591h (error register 11h) \
                reports error 102 (P700) on FI 1, but P700 [-01] reads 0";
    let named: Vec<&serde_json::Value> = cases
        .iter()
        .filter(|c| c["message"].as_str().unwrap_or_default().contains(says))
        .collect();
    assert!(!named.is_empty(), "no case named the emergency: {cases:#?}");
    assert!(named.iter().all(|c| c["verdict"] == "fail"), "{named:#?}");
    assert!(t.alarms > 0, "{t:?}");
}

/// POWERLINK: `s` on node 1, the NMT case `case` from the namespace as MN.
fn epl(tag: &str, s: &str, case: &str, verdict: &str, says: &[&str]) -> Touched {
    let ns = Netns::new(tag);
    ns.add_ipv4("192.168.100.1/24", "192.168.100.240/24");
    let options = harness::epl_serve::ServeOptions {
        misbehave: spec(s),
        ..harness::epl_serve::ServeOptions::new(ns.root_if())
    };
    let served = harness::epl_serve::start(&options).expect("serve epl");
    let filter = format!("bu0620/epl-nmt/{case}");
    let run = (
        "sk550p@epl",
        format!("epl://{}", ns.ns_if()),
        filter.as_str(),
    );
    let stop = || {
        served
            .stop()
            .expect("the node served to the end")
            .misbehaved
    };
    judged(&ns, run, stop, verdict, says)
}

#[test]
fn epl_a_node_misbehaving_is_named_for_what_it_did() {
    if !require_root_or_skip("serve epl --misbehave over veth pairs") {
        return;
    }
    // Every PRes says STOPPED (4Dh): the MN's cycle checks each PRes's NMT status against
    // the state the node reported (its StatusResponse) as it boots the node, before any case:
    // PRE_OPERATIONAL_1 or 2, as the first PRes checked comes before or after the SoC that
    // moves it on.
    let t = epl(
        "mbstate",
        "corrupt=state",
        "start-up-sequence",
        "error",
        &[
            "the DUT did not come up: node 1's PRes says NMT_CS_STOPPED (4Dh), expected \
           NMT_CS_PRE_OPERATIONAL_",
        ],
    );
    assert!(t.corrupted > 0, "{t:?}");
    let t = epl(
        "mbplsil",
        "silent=600s",
        "start-up-sequence",
        "error",
        &["no reply from node 1 to SoA IdentRequest within its limit of 2000 ms"],
    );
    assert!(t.silenced > 0, "{t:?}");
}

#[test]
fn epl_a_node_that_loses_pres_is_named_for_the_loss_of_pres_threshold() {
    if !require_root_or_skip("serve epl --misbehave over veth pairs") {
        return;
    }
    // Every third output of the node lost: in the case's SDO read and its 50 idle cycles
    // mostly PRes, which DS 301's threshold counter (+8 per loss, −1 per good cycle) takes
    // past the threshold 15 within a few losses (8, 7, 6, 14, 13, 12, 20).
    let t = epl(
        "mbpldrop",
        "drop=every:3",
        "pre-operational-2-parameters-only",
        "fail",
        &[
            "no PRes from node 1 in ",
            "loss of PRes",
            "E_DLL_LOSS_PRES_TH",
        ],
    );
    assert!(t.dropped > 0, "{t:?}");
}

#[test]
fn epl_a_node_that_signals_errors_unasked_is_named_for_the_entry() {
    if !require_root_or_skip("serve epl --misbehave over veth pairs") {
        return;
    }
    // An error entry and EN toggled every 50 ms: the MN fetches the StatusResponse (DS 301
    // §6.5) and the case, which provoked no error, fails naming the entry; its first step
    // that does not read the StatusResponse itself (the SDO read) sees one.
    let t = epl(
        "mbplalarm",
        "alarm=every:50ms",
        "pre-operational-2-parameters-only",
        "fail",
        &[
            "node 1 signalled an error no step provoked (EN toggled; its StatusResponse lists \
           entry 9000h External watchdog, \"1   12.0\"",
        ],
    );
    assert!(t.alarms > 0, "{t:?}");
}

/// PROFINET IO: `s` on the device, the connect cases from the namespace as controller.
fn pnio(tag: &str, s: &str, verdict: &str, says: &[&str]) -> Touched {
    const NAME: &str = "nord-device";
    let ns = Netns::new(tag);
    ns.add_ipv4("192.168.22.200/24", "192.168.22.1/24");
    let options = harness::pnio_serve::ServeOptions {
        name: NAME.to_string(),
        misbehave: spec(s),
        ..harness::pnio_serve::ServeOptions::new(ns.root_if())
    };
    let served = harness::pnio_serve::start(&options).expect("serve pnio");
    let run = (
        "sk550p@pnio",
        format!("pnio://{}/{NAME}", ns.ns_if()),
        "pnio/connect/",
    );
    let stop = || {
        served
            .stop()
            .expect("the device served to the end")
            .misbehaved
    };
    judged(&ns, run, stop, verdict, says)
}

#[test]
fn pnio_a_device_misbehaving_is_named_for_what_it_did() {
    if !require_root_or_skip("serve pnio --misbehave over veth pairs") {
        return;
    }
    // DataValid cleared in every input frame: 35h became 31h.
    let t = pnio(
        "mbdstat",
        "corrupt=data-status",
        "fail",
        &["data_status: expected 53 (0035h), got 49 (0031h)"],
    );
    assert!(t.corrupted > 0, "{t:?}");
    // The input CR's cycle counter stands at 0: the first frame is new, none after it, and
    // the data hold time (100 cycles of 1 ms) runs out on frames that keep coming.
    let t = pnio(
        "mbcycle",
        "corrupt=cycle",
        "fail",
        &[
            "cycle counter stood at 0 for ",
            "(data hold time 100 ms expired)",
        ],
    );
    assert!(t.corrupted > 0, "{t:?}");
    // Every RPC response refused "state conflict": the Connect of the opening first.
    let t = pnio(
        "mbpstat",
        "corrupt=status",
        "error",
        &["Connect response PNIO status DB 81 40 06: IODConnectRes, PNIO: CMRPC: state conflict"],
    );
    assert!(t.corrupted > 0, "{t:?}");
    // A process alarm every 20 ms while an AR runs (each case opens its own, and runs it
    // longer than that): acknowledged, and the step it came by fails (one that came while
    // the case opened fails its first step).
    let t = pnio(
        "mbpalarm",
        "alarm=every:20ms",
        "fail",
        &[
            "the device raised a Process alarm (AlarmType 0002h) from slot 3 subslot 1",
            "its manual names diagnosis alarms only",
        ],
    );
    assert!(t.alarms > 0, "{t:?}");
    // The same alarms, each DATA PDU's SendSeqNum one ahead: the first comes as 1, not 0.
    let t = pnio(
        "mbpseq",
        "alarm=every:20ms,corrupt=sequence",
        "fail",
        &["alarm DATA-RTA-PDU came with SendSeqNum 1 where 0 was due"],
    );
    assert!(t.alarms > 0 && t.corrupted > 0, "{t:?}");
    let t = pnio(
        "mbpnsil",
        "silent=600s",
        "error",
        &["no DCP Identify response from the device within its limit of 400 ms"],
    );
    assert!(t.silenced > 0, "{t:?}");
}

/// EtherNet/IP on loopback: `harness serve enip --misbehave SPEC`, the identity cases.
fn enip(s: &str, verdict: &str, says: &[&str]) {
    enip_case(s, "bu2100/identity/", verdict, says);
}

/// EtherNet/IP on loopback: `harness serve enip --misbehave SPEC`, the cases whose id
/// contains `case`.
fn enip_case(s: &str, case: &str, verdict: &str, says: &[&str]) {
    let listen = format!("{}:44818", common::addr::free_loopback());
    let _server = common::serve_with(&listen, "tu3-eip", 120, &["--misbehave", s]);
    let cases = common::cases_of_run(
        std::process::Command::new(env!("CARGO_BIN_EXE_harness")),
        "tu3-eip",
        &format!("enip://{listen}"),
        case,
    );
    check(&cases, verdict, says);
}

#[test]
fn enip_an_adapter_whose_replies_say_service_not_supported_is_named_for_it() {
    enip("corrupt=status", "fail", &["cip_status: expected 0, got 8"]);
}

#[test]
fn enip_an_adapter_whose_reply_lengths_run_past_the_bytes_is_named_for_it() {
    // Get_Attribute_Single's reply (SendRRData, 22 data bytes) says 534: the scanner waits its
    // limit for the rest, then closes the connection, the stream's framing lost.
    enip(
        "corrupt=length",
        "fail",
        &["the reply's encapsulation header says length 534 but 22 bytes followed within 2000 ms: \
           the scanner closed the connection"],
    );
}

#[test]
fn enip_an_adapter_whose_t_o_sequence_stands_still_times_out_its_connection() {
    // Every T→O frame numbered 1: the first is taken, the others discarded as not new, and
    // after the connection's timeout of nothing new the scanner names them.
    enip_case(
        "corrupt=sequence",
        "bu2100/drive-bits/enable-pulses-bit-4",
        "fail",
        &[
            "frames discarded: their sequence number 1 did not advance past 1, CIP Vol 2): \
             no answer within the device's limit of ",
        ],
    );
}

#[test]
fn enip_an_adapter_that_closes_mid_exchange_is_named_for_it() {
    enip(
        "close",
        "fail",
        &["the device closed the connection: the target closed the TCP connection"],
    );
}

#[test]
fn enip_an_adapter_that_sends_a_reply_twice_does_not_speak_the_protocol() {
    // RegisterSession's reply, twice: the second stands where SendRRData's belongs.
    enip(
        "dup",
        "error",
        &["the reply to SendRRData is command 0065h"],
    );
}

#[test]
fn enip_an_adapter_that_drops_a_reply_is_named_for_the_request_unanswered() {
    // Per connection the first reply (RegisterSession's) leaves, the second is lost.
    enip(
        "drop=every:2",
        "fail",
        &["Get_Attribute_Single: no answer within the device's limit of 2000 ms"],
    );
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
            vec![
                "serve",
                "epl",
                "--iface",
                "lo",
                "--misbehave",
                "corrupt=wkc",
            ],
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

/// What the served device touched is on stderr, one line each, and counted in the summary
/// on stdout when serving ends: an adapter that sends every reply twice, asked once.
#[test]
fn each_touched_reply_is_logged_and_counted_in_the_summary() {
    use proto::enip::encap::{Command, EncapRepr};
    use std::process::Stdio;
    let ip = common::addr::free_loopback();
    let listen = format!("{ip}:44818");
    let server = std::process::Command::new(env!("CARGO_BIN_EXE_harness"))
        .args(["serve", "enip", "--listen", &listen, "--misbehave", "dup"])
        .args(["--seed", "7", "--seconds", "3"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("harness serve starts");
    common::wait_listening(&listen, std::time::Duration::from_secs(10));
    let udp = std::net::UdpSocket::bind((ip, 0)).unwrap();
    udp.set_read_timeout(Some(std::time::Duration::from_secs(2)))
        .unwrap();
    let ask = EncapRepr {
        command: Command::LIST_IDENTITY.0,
        ..EncapRepr::default()
    };
    udp.send_to(&ask.emit().unwrap(), &listen).unwrap();
    let mut buf = [0u8; 600];
    let first = udp.recv(&mut buf).expect("the reply");
    let second = udp.recv(&mut buf).expect("the reply again");
    assert_eq!(first, second);
    let out = server.wait_with_output().unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(
        stdout.contains("misbehaving on purpose: dup (seed 7)"),
        "{stdout}"
    );
    assert!(stdout.contains("misbehaved: 1 duplicated"), "{stdout}");
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("misbehave "))
        .collect();
    assert_eq!(lines.len(), 1, "{stderr}");
    assert!(
        lines[0].contains(" dup     datagram ") && lines[0].contains(&format!(" B to {ip}:")),
        "{}",
        lines[0]
    );
}
