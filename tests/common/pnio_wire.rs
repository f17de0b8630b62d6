//! What the PROFINET wire must show of a full run against `harness serve pnio` ([`check`]):
//! the manual-level cases over records and RT, the `pnio:` suites and the bad-input cases
//! passed; tshark dissects the run's own capture and its capture of the wire as PROFINET — DCP
//! (`pn_dcp`), cyclic RT (`pn_rt`), the context management's blocks over DCE/RPC (`dcerpc`,
//! `pn_io`) — with no malformed frame but in steps that send bytes as written on purpose. The
//! load test makes this run as the first of its five against the served `sk550p`.

use std::collections::HashMap;
use std::path::Path;

use harness::pnio_serve::Stats;

use super::suite_run::SuiteRun;

/// What tshark makes of a capture.
struct Dissected {
    /// Frames per protocol stack (`eth:ethertype:pn_rt:pn_dcp`, `…:udp:dcerpc:pn_io`…).
    stacks: HashMap<String, usize>,
    /// Frames tshark finds malformed, with their packet comment (the run's label) where the
    /// capture has one.
    malformed: Vec<(usize, Option<String>)>,
    /// DCE/RPC datagrams whose PNIO-CM blocks tshark's `pn_io` decodes (it adds no layer of
    /// its own to `frame.protocols` there).
    cm: usize,
}

fn dissect(path: &Path) -> Dissected {
    let out = super::tshark::fields(
        path,
        &[
            "frame.number",
            "frame.protocols",
            "_ws.malformed",
            "frame.comment",
            "pn_io.block_type",
        ],
    );
    let mut d = Dissected {
        stacks: HashMap::new(),
        malformed: Vec::new(),
        cm: 0,
    };
    for line in out.lines() {
        let f: Vec<&str> = line.split('\t').collect();
        let field = |i: usize| f.get(i).copied().unwrap_or("");
        let number: usize = field(0).parse().expect("a frame number");
        *d.stacks.entry(field(1).to_string()).or_default() += 1;
        if !field(2).is_empty() || field(1).contains("_ws.malformed") {
            let comment = Some(field(3)).filter(|c| !c.is_empty()).map(str::to_string);
            d.malformed.push((number, comment));
        }
        if field(1).contains("udp:dcerpc") && !field(4).is_empty() {
            d.cm += 1;
        }
    }
    d
}

/// Whether a label names a step that sends bytes as a suite writes them: a `pnio: {frame: …}`
/// or `{rpc: …}` step. Every other frame is built by the controller's codecs.
fn on_purpose(label: &str) -> bool {
    label.split_once(": ").is_some_and(|(head, step)| {
        head.contains(" step ")
            && (step.starts_with("pnio frame ") || step.starts_with("pnio RPC "))
    })
}

/// Whether a label names a step on the SK TU3-PNT's data record 47. tshark's `pn_io` reads
/// index 47 as PROFIdrive's base mode parameter access (reference, request id, axis, count,
/// then six-byte parameter addresses) and flags its data malformed; BU 0590 §4.2.2 lays record
/// 47 out as NORD's own eleven bytes (reference, axis and the PKW order), which the device
/// answers as the manual shows. The disagreement is the manual's layout, not a broken frame.
fn record_47(label: &str) -> bool {
    label.contains(" step ") && label.contains("record 47")
}

/// Checks the run of `product`'s profile and both its captures; `stats` are the served
/// device's (of this run and any after it). Panics with what is wrong.
pub(crate) fn check(run: &SuiteRun, product: &str, stats: &Stats) {
    let manual = if product == "sk550p" {
        "bu0620"
    } else {
        "bu0590"
    };
    run.assert_passed(&[
        ("pnio/dcp/".to_string(), 10),
        ("pnio/connect/".to_string(), 5),
        ("pnio/records/".to_string(), 10),
        // Most alarm cases need an inverter fault raised or LEDs seen: the simulator only.
        ("pnio/alarms/".to_string(), 1),
        ("pnio/bad-input/".to_string(), 30),
        (format!("{manual}/drive-words/"), 1),
    ]);
    assert!(stats.frames_in > 5_000, "{product}: {stats:?}");
    assert!(stats.datagrams_in > 100, "{product}: RPC ran: {stats:?}");

    // Both captures dissect as PROFINET: DCP, RT, and the RPC calls of the context
    // management on the wire.
    let run_d = dissect(&run.run_pcap);
    let wire_d = dissect(&run.wire_pcap);
    let count = |d: &Dissected, layers: &str| super::tshark::frames_with(&d.stacks, layers);
    for (d, which) in [(&run_d, "run"), (&wire_d, "wire")] {
        assert!(count(d, "pn_rt") > 1000, "{which}: {:?}", d.stacks);
        assert!(count(d, "pn_dcp") > 20, "{which}: {:?}", d.stacks);
        assert!(d.cm > 100, "{which}: {} PNIO-CM datagrams", d.cm);
    }

    // Malformed frames only in steps that send bytes as written, and in record 47's.
    super::tshark::assert_flagged_on_purpose(
        product,
        &run_d.malformed,
        wire_d.malformed.len(),
        |l| on_purpose(l) || record_47(l),
    );
}
