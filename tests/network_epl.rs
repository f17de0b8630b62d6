//! The harness's POWERLINK suites over the wire: `harness serve epl` on one end of a veth pair
//! (raw Ethernet and UDP 3819 on 192.168.100.1), `harness run --dut epl://IFACE` as managing
//! node inside a network namespace on the other (192.168.100.240), for every POWERLINK profile
//! (`sk550p`, `tu3-pol`, `tu4-pol`, `cu4-pol`): the manual-level cases over SDO and PReq/PRes,
//! the `epl:` suites and the bad-input cases. Each run must end with no case failed or in
//! error. tshark, capturing on the wire meanwhile, must dissect the traffic as POWERLINK
//! (`epl`, SDO over UDP too) with no malformed frame and no expert warning but in steps that
//! send bytes as written on purpose, and the NMT states it decodes from the node's frames must
//! only ever move as the CN state machine allows (BU 0620 §2.4.4, DS 301 §7.1.4), through
//! PRE_OPERATIONAL_1, PRE_OPERATIONAL_2, READY_TO_OPERATE and OPERATIONAL. `--pcap` writes the
//! run's own capture, whose packet comments name each frame's case and step.
//!
//! Needs root (network namespaces, raw sockets) and tshark (`.ci/interop-setup`); without
//! them the test says so and skips on a developer's machine, and fails in strict mode.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use harness::epl_serve::{start, ServeOptions};

#[allow(dead_code)] // what the other network tests share
mod common;
use common::netns::{require_root_or_skip, Netns};
use common::peer::require_tshark;
use common::suite_run::SuiteRun;

/// What tshark makes of a capture.
struct Dissected {
    /// Frames per protocol stack (`eth:ethertype:epl`, `eth:ethertype:ip:udp:epl`…).
    stacks: HashMap<String, usize>,
    /// Frames tshark finds malformed or warns about (expert severity warning or error), with
    /// their packet comment (the run's label) where the capture has one.
    flagged: Vec<(usize, Option<String>)>,
    /// The NMT states the node's frames carry, in order.
    states: Vec<u8>,
}

fn dissect(path: &Path) -> Dissected {
    let out = common::tshark::fields(
        path,
        &[
            "frame.number",
            "frame.protocols",
            "_ws.malformed",
            "_ws.expert.severity",
            "epl.src",
            "epl.pres.stat",
            "epl.asnd.ires.state",
            "epl.asnd.sres.stat",
            "frame.comment",
        ],
    );
    let mut d = Dissected {
        stacks: HashMap::new(),
        flagged: Vec::new(),
        states: Vec::new(),
    };
    // Expert severities: 0x00400000 note, 0x00600000 warning, 0x00800000 error.
    const WARNING: u64 = 0x0060_0000;
    for line in out.lines() {
        let f: Vec<&str> = line.split('\t').collect();
        let field = |i: usize| f.get(i).copied().unwrap_or("");
        let number: usize = field(0).parse().expect("a frame number");
        *d.stacks.entry(field(1).to_string()).or_default() += 1;
        let warned = field(3)
            .split(',')
            .filter_map(|s| s.parse::<u64>().ok())
            .any(|s| s >= WARNING);
        if !field(2).is_empty() || warned {
            let comment = Some(field(8)).filter(|c| !c.is_empty()).map(str::to_string);
            d.flagged.push((number, comment));
        }
        if !field(4).is_empty() && field(4) != "240" {
            for i in 5..=7 {
                let s = field(i).split(',').next().unwrap_or("");
                if let Some(v) = s
                    .strip_prefix("0x")
                    .and_then(|h| u8::from_str_radix(h, 16).ok())
                {
                    d.states.push(v);
                }
            }
        }
    }
    d
}

/// Whether a label names a step that sends bytes as a suite writes them: an `epl: {frame: …}`
/// or `{sdo: …}` step. Every other frame is built by the managing node's codecs.
fn on_purpose(label: &str) -> bool {
    label.split_once(": ").is_some_and(|(head, step)| {
        head.contains(" step ")
            && (step.starts_with("epl frame ") || step.starts_with("epl SDO bytes "))
    })
}

/// The moves between NMT states a CN's frames may show (DS 301 §7.1.4; a reset passes
/// through NOT_ACTIVE, where the node sends nothing, so it shows as a move to PRE_OP_1).
fn allowed(from: u8, to: u8) -> bool {
    const PRE1: u8 = 0x1D;
    const PRE2: u8 = 0x5D;
    const RTO: u8 = 0x6D;
    const OP: u8 = 0xFD;
    const STOPPED: u8 = 0x4D;
    const BASIC: u8 = 0x1E;
    matches!(
        (from, to),
        (PRE1, PRE2)
            | (PRE2, RTO)
            | (RTO, OP)
            | (OP | STOPPED, PRE2)
            | (PRE1 | PRE2 | RTO | OP, STOPPED)
            | (BASIC, PRE1)
            | (_, PRE1)
            | (_, BASIC)
    )
}

#[test]
fn every_powerlink_suite_passes_against_the_served_node_over_a_veth_pair() {
    // On a loaded host when `.ci/run` asks (NORD_TEST_HOG): the verdicts must hold there too.
    let _hog = common::hog::Hog::if_asked();
    let why = "the POWERLINK suites against harness serve epl over a veth pair";
    if !require_root_or_skip(why) || !require_tshark(why) {
        return;
    }
    // The four products side by side, each on a pair of its own (the served nodes all have
    // 192.168.100.1, each tied to its interface): their runs mostly wait on the drives'
    // real-time steps, and one after another they took seven minutes of CI.
    let failed: Vec<&str> = std::thread::scope(|s| {
        let runs: Vec<_> = ["sk550p", "tu3-pol", "tu4-pol", "cu4-pol"]
            .into_iter()
            .map(|product| (product, s.spawn(move || check_product(product))))
            .collect();
        runs.into_iter()
            .filter_map(|(product, run)| run.join().err().map(|_| product))
            .collect()
    });
    assert!(failed.is_empty(), "failed: {}", failed.join(", "));
}

/// Serves `product`'s node on a pair of its own, runs every suite against it and checks the run
/// and both captures; panics with what is wrong.
fn check_product(product: &str) {
    let ns = Netns::new(&format!("epl-{product}"));
    ns.add_ipv4("192.168.100.1/24", "192.168.100.240/24");
    let mut options = ServeOptions::new(ns.root_if());
    options.profile = product.to_string();
    let served = start(&options).expect("serve epl");
    let run = SuiteRun::new(
        &ns,
        "epl",
        &format!("{product}@epl"),
        &format!("epl://{}", ns.ns_if()),
    );
    let stats = served.stop().expect("the node served to the end");
    let manual = if product == "sk550p" {
        "bu0620"
    } else {
        "bu2200"
    };
    run.assert_passed(&[
        (format!("{manual}/epl-nmt/"), 3),
        (format!("{manual}/epl-sdo-abort/"), 5),
        (format!("{manual}/epl-pdo-mapping/"), 3),
        (format!("{manual}/drive-words/"), 1),
        ("epl/bad-input/".to_string(), 30),
    ]);
    assert!(stats.frames_in > 5_000, "{product}: {stats:?}");
    assert!(
        stats.datagrams_in > 0,
        "{product}: SDO over UDP ran: {stats:?}"
    );

    // Both captures dissect as POWERLINK; the wire's has SDO over UDP too.
    let run_d = dissect(&run.run_pcap);
    let wire_d = dissect(&run.wire_pcap);
    let count = |d: &Dissected, layers: &str| common::tshark::frames_with(&d.stacks, layers);
    assert!(
        count(&run_d, "eth:ethertype:epl") > 1000,
        "{:?}",
        run_d.stacks
    );
    assert!(
        count(&wire_d, "eth:ethertype:epl") > 1000,
        "{:?}",
        wire_d.stacks
    );
    assert!(count(&wire_d, "udp:epl") > 10, "{:?}", wire_d.stacks);

    // Malformed frames and expert warnings only in steps that send bytes as written.
    assert!(
        !run_d.flagged.is_empty(),
        "{product}: the bad-input steps flag frames"
    );
    common::tshark::assert_flagged_on_purpose(
        product,
        &run_d.flagged,
        wire_d.flagged.len(),
        on_purpose,
    );

    // The node's NMT states, as tshark decodes them from its frames, move only as the CN
    // state machine allows, and the boot sequence is there.
    let mut moves = HashSet::new();
    for w in wire_d.states.windows(2) {
        if w[0] != w[1] {
            moves.insert((w[0], w[1]));
        }
    }
    let illegal: Vec<String> = moves
        .iter()
        .filter(|(a, b)| !allowed(*a, *b))
        .map(|(a, b)| format!("{a:02X}h → {b:02X}h"))
        .collect();
    assert!(illegal.is_empty(), "{product}: {}", illegal.join(", "));
    for m in [(0x1D, 0x5D), (0x5D, 0x6D), (0x6D, 0xFD)] {
        assert!(
            moves.contains(&m),
            "{product}: no {:02X}h → {:02X}h in {moves:?}",
            m.0,
            m.1
        );
    }
    run.finish();
}

/// Both sides of a served POWERLINK module's gateway: `harness serve epl --system-bus`
/// publishes the CANopen frames its gateway exchanges with its inverters over socketcand, and
/// a run over POWERLINK from the namespace with `--tap` asserts them (BU 2200 §5.1: P102 of FI 3
/// written over SDO is an SDO download to node 36; FI 2's process data are PDOs of node 34).
/// Without `--tap` the same cases are not applicable, saying what they need.
#[test]
fn an_epl_run_with_tap_asserts_the_served_modules_system_bus() {
    let why = "harness serve epl --system-bus against a run with --tap over a veth pair";
    if !require_root_or_skip(why) {
        return;
    }
    let ns = Netns::new("epl-tap");
    ns.add_ipv4("192.168.100.1/24", "192.168.100.240/24");
    // The relay listens on an address of this pair alone: the other tests' pairs have
    // 192.168.100.1 on their root side too, and the namespace's answer must come back here.
    ns.add_ipv4("10.222.0.1/30", "10.222.0.2/30");
    let bus = "10.222.0.1:29536";
    let _server = common::serve_on_iface_with_relay("epl", ns.root_if(), "tu3-pol", &[], bus);
    let dut = format!("epl://{}", ns.ns_if());
    common::check_tap_runs(
        || ns.command(env!("CARGO_BIN_EXE_harness")),
        &["--profile", "tu3-pol", "--dut", &dut],
        "bu2200/systembus/gateway",
        bus,
        &[
            "bu2200/systembus/gateway-parameterzugriff-ist-sdo",
            "bu2200/systembus/gateway-prozessdaten-sind-pdos",
        ],
    );
}
