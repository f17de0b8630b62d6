//! Hand-built runs for the report tests: one device case of every verdict, a passing
//! reference-model case, two profiles, two manuals, an erratum, and an exchange the DUT never
//! answered.

use serde_json::json;
use std::path::PathBuf;
use std::time::Duration;

use crate::outcome::*;

fn manual(doc: &str, edition: &str, section: &str, page: u32) -> ManualRef {
    ManualRef {
        doc: doc.into(),
        edition: edition.into(),
        section: section.into(),
        page: Some(page),
        quote: None,
    }
}

/// The BU 0620 §2.5.6.4 (p. 59) P102 write: order `24 4E 01 00 00 00 00 FA` to FI 2,
/// answered with response label 1 and PWE 250.
fn p102_write() -> Exchange {
    Exchange {
        sent_hex: "65 02 24 4E 01 00 00 00 00 FA".into(),
        sent: "AK 2, PNU 1102 = P102, IND 0100h, PWE 250".into(),
        received_hex: "65 02 14 4E 01 00 00 00 00 FA".into(),
        received: "AK 1, PNU 1102 = P102, IND 0100h, PWE 250".into(),
    }
}

fn step(line: &str, verdict: Verdict, message: &str, exchanges: Vec<Exchange>) -> StepResult {
    StepResult {
        step: line.into(),
        verdict,
        observed: json!({"ak": 1, "pwe": 250}),
        refusal: None,
        message: message.into(),
        exchanges,
    }
}

fn case(
    id: &str,
    profile: &str,
    manual: ManualRef,
    verdict: Verdict,
    message: &str,
    steps: Vec<StepResult>,
) -> CaseResult {
    CaseResult {
        id: id.into(),
        title: format!("title of {id}"),
        profile: profile.into(),
        manual,
        kind: CaseKind::Device,
        verdict,
        message: message.into(),
        steps,
        duration: Duration::from_millis(3),
        seq: 0,
        discarded: Vec::new(),
        transcript: None,
    }
}

/// A run with one device case of each verdict under `sk550p` and `tu3-eip`, then one passing
/// model case under `sk550p`.
pub(super) fn sample_run() -> RunResult {
    let bu0620 = |section: &str, page| manual("BU 0620", "2020-03 en", section, page);
    let fail = "status: expected 2865 (0B31h), got 2871 (0B37h)";
    let silent = Exchange {
        received_hex: String::new(),
        received: String::new(),
        ..p102_write()
    };
    let mut run = RunResult {
        mutation: Some(crate::outcome::MutationScore {
            mutants: 1000,
            killed: 962,
            measured: "2026-11-27T05:00:00Z".into(),
            sample: false,
        }),
        dut: "embedded simulator".into(),
        meta: RunMeta {
            harness_version: "0.1.0".into(),
            harness_revision: "0123456789abcdef0123456789abcdef01234567".into(),
            suites_revision: "0123456789abcdef0123456789abcdef01234567".into(),
            started: "2026-11-27T06:00:00Z".into(),
            host: "qa-bench-1".into(),
            command_line: vec![
                "harness".into(),
                "run".into(),
                "--filter".into(),
                "a b".into(),
            ],
            identities: [(
                "sk550p".to_string(),
                Identity {
                    source: "P743/P707/P780 over the parameter channel".into(),
                    vendor: Some("NORD".into()),
                    product_code: None,
                    product_name: Some("SK 550P".into()),
                    revision: Some("V1.2 R0".into()),
                    serial: Some("123456".into()),
                },
            )]
            .into(),
            motion_allowed: false,
            shard: None,
            shuffle: None,
            discarded_attempts: 0,
            eeprom_writes: 4,
            eeprom_cap: Some(20),
            interrupted: None,
        },
        profiles: vec!["sk550p".into(), "tu3-eip".into()],
        cases: vec![
            case(
                "bu0620/pkw-telegrams/p102-write",
                "sk550p",
                bu0620("2.5.6.4", 59),
                Verdict::Pass,
                "",
                vec![step(
                    "pkw FI 2: 24 4E 01 00 00 00 00 FA",
                    Verdict::Pass,
                    "",
                    vec![p102_write()],
                )],
            ),
            case(
                "bu0620/addressing/coe-p102",
                "sk550p",
                bu0620("2.2.7", 20),
                Verdict::Fail,
                fail,
                vec![step(
                    "read P102 set 3 FI 5",
                    Verdict::Fail,
                    fail,
                    vec![p102_write()],
                )],
            ),
            case(
                "bu0620/addressing/coe-p102",
                "tu3-eip",
                bu0620("2.2.7", 20),
                Verdict::NotApplicable,
                "the statement is about sk550p, this run is tu3-eip",
                vec![],
            ),
            case(
                "bu0620/pkw-telegrams/silent",
                "tu3-eip",
                bu0620("2.5.6.4", 59),
                Verdict::Error,
                "no answer from the DUT within 250 bus cycles",
                vec![step(
                    "pkw FI 2: 24 4E 01 00 00 00 00 FA",
                    Verdict::Error,
                    "no answer from the DUT within 250 bus cycles",
                    vec![silent],
                )],
            ),
            case(
                "bu2100/cip/identity",
                "tu3-eip",
                manual("BU 2100", "en", "5.1", 92),
                Verdict::Inconclusive,
                "setup step 1 failed: no connection",
                vec![step(
                    "compute cip.path FI 1",
                    Verdict::Inconclusive,
                    "setup step 1 failed: no connection",
                    vec![],
                )],
            ),
            CaseResult {
                kind: CaseKind::Model,
                ..case(
                    "bu0620/drive-scaling/setpoint",
                    "sk550p",
                    bu0620("2.6.1", 64),
                    Verdict::Pass,
                    "",
                    vec![step("compute setpoint 50 %", Verdict::Pass, "", vec![])],
                )
            },
        ],
        errata: vec![Erratum {
            doc: "BU 0620".into(),
            edition: "2020-03 en".into(),
            section: "2.3.5".into(),
            page: Some(27),
            case: "bu0620/addressing-cip/x".into(),
            printed: "class 103".into(),
            correct: "class 102".into(),
            why: "FI 2 is class 102".into(),
            ambiguous: false,
            check: ErratumCheck::OwnText,
            standard: None,
        }],
        statements: vec![
            StatementCoverage {
                doc: "BU 0620".into(),
                edition: "2020-03 en".into(),
                section: "2.2.7".into(),
                statements: 4,
                asserted: 1,
                model_only: 1,
                pending: 1,
                untestable: 0,
            },
            StatementCoverage {
                doc: "BU 0620".into(),
                edition: "2020-03 en".into(),
                section: "2.5.6.4".into(),
                statements: 3,
                asserted: 3,
                model_only: 0,
                pending: 0,
                untestable: 0,
            },
            StatementCoverage {
                doc: "BU 0620".into(),
                edition: "2020-03 en".into(),
                section: "2.6.1".into(),
                statements: 1,
                asserted: 0,
                model_only: 0,
                pending: 0,
                untestable: 1,
            },
        ],
        sections: vec![SectionCount {
            doc: "BU 0620".into(),
            edition: "2020-03 en".into(),
            contents: 5,
            with_statements: 3,
            nothing: 2,
        }],
        load_errors: vec![],
        duration: Duration::from_millis(15),
    };
    for (seq, c) in run.cases.iter_mut().enumerate() {
        c.seq = seq;
    }
    run
}

/// A fresh, empty folder for one test.
pub(super) fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("harness-report-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}
