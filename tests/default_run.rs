//! The full default run, end to end through the `harness` binary: every suite against the
//! embedded simulator under every built-in profile, reports into a fresh folder.

#[path = "common/transcripts.rs"]
mod transcripts;

use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

fn harness(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_harness"))
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .args(args)
        .output()
        .expect("the harness binary runs")
}

#[test]
fn default_run_passes_every_applicable_case_and_writes_reports() {
    let out = std::env::temp_dir().join(format!("harness-default-run-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = harness(&["run", "--out", out.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "default run failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );

    let run: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert!(out.join("junit.xml").is_file());
    assert!(out.join("summary.md").is_file());
    assert_eq!(
        run["load_errors"].as_array().map(Vec::len),
        Some(0),
        "{}",
        run["load_errors"]
    );

    let cases = run["cases"].as_array().expect("cases");
    let mut counts: BTreeMap<String, BTreeMap<String, usize>> = BTreeMap::new();
    for c in cases {
        assert!(
            c["id"].is_string()
                && c["manual"]["doc"].is_string()
                && c["manual"]["section"].is_string()
        );
        let profile = c["profile"].as_str().unwrap().to_string();
        *counts
            .entry(profile)
            .or_default()
            .entry(c["verdict"].as_str().unwrap().to_string())
            .or_default() += 1;
        assert_ne!(
            c["verdict"], "error",
            "case {} ended in error: {}",
            c["id"], c["message"]
        );
        assert_ne!(
            c["verdict"], "fail",
            "case {} failed: {}",
            c["id"], c["message"]
        );
    }
    // Every built-in profile ran (8 products over PPO, the 4 EtherNet/IP products over
    // EtherNet/IP, the SK 550P over EtherCAT, the 4 POWERLINK products over POWERLINK, the SK
    // 550P and SK TU3-PNT over PROFINET IO, the 8 products' inverters over the system bus), and
    // every case ran (passed) under at least one of them.
    assert_eq!(counts.len(), 27, "{counts:?}");
    assert!(
        counts["sk550p@can"]["pass"] >= 40,
        "the system-bus cases ran over CAN: {counts:?}"
    );
    let mut passed_somewhere = std::collections::HashSet::new();
    for c in cases.iter().filter(|c| c["verdict"] == "pass") {
        passed_somewhere.insert(c["id"].as_str().unwrap());
    }
    let all_ids: std::collections::HashSet<&str> =
        cases.iter().map(|c| c["id"].as_str().unwrap()).collect();
    let never: Vec<_> = all_ids.difference(&passed_somewhere).collect();
    assert!(
        never.is_empty(),
        "cases that ran under no profile: {never:?}"
    );
    assert!(
        !run["errata"].as_array().unwrap().is_empty(),
        "the suites record the manuals' errata"
    );
    insta::assert_json_snapshot!("verdict_counts", counts);
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_broken_suite_file_is_reported_with_file_and_line_and_exits_2() {
    let dir = std::env::temp_dir().join(format!("harness-broken-suite-{}", std::process::id()));
    let out = dir.join("out");
    std::fs::create_dir_all(dir.join("bu0620")).unwrap();
    std::fs::write(
        dir.join("bu0620/broken.yaml"),
        "doc: BU 0620\nedition: \"2020-03 en\"\ncases:\n  - id: x\n    title: t\n    ref: { section: \"2.2.7\", page: 20 }\n    steps:\n      - wait: soon\n",
    )
    .unwrap();
    let o = harness(&[
        "run",
        "--suites",
        dir.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--profile",
        "sk550p",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let run: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    let err = run["load_errors"][0].as_str().unwrap();
    assert!(
        err.contains("broken.yaml:8:") && err.contains("soon"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_bad_input_is_one_line_naming_the_problem() {
    for (args, needle) in [
        (
            vec!["addr", "P102", "--inverter", "9"],
            "inverter 9 is out of range",
        ),
        (
            vec!["addr", "P1000"],
            "parameter number 1000 is out of range",
        ),
        (
            vec!["decode", "pkw", "70", "66", "zz"],
            "`zz` is not a hex value",
        ),
        (vec!["decode", "status", "12345h"], "does not fit 16 bits"),
        (vec!["run", "--profile", "sk999"], "unknown profile `sk999`"),
    ] {
        let o = harness(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

#[test]
fn decode_and_addr_speak_the_manuals_terms() {
    let o = harness(&["decode", "status", "0B31h", "--json"]);
    assert_eq!(o.status.code(), Some(0));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v.is_object());
    let o = harness(&["addr", "P102", "--inverter", "3", "--json"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let text = String::from_utf8_lossy(&o.stdout);
    // BU 0620 §2.2.7: P102 on FI 3 is CoE index 2000h + 1000h + 66h = 3066h (12390).
    assert!(text.contains("12390"), "{text}");
}

#[test]
fn transcript_of_the_p102_write_example_is_stable() {
    // BU 0620 §2.5.6.4: the P102 write order over the link, byte for byte; the snapshot pins the
    // exchange (order repeated until answered, response label 1, PWE 250).
    let out = std::env::temp_dir().join(format!("harness-transcript-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let o = harness(&[
        "run",
        "--profile",
        "sk550p",
        "--filter",
        "pkw-telegrams/p102-write-on-the-dut",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    let transcript =
        transcripts::transcript(&out, "sk550p", "bu0620/pkw-telegrams/p102-write-on-the-dut");
    insta::assert_snapshot!("p102_write_transcript", transcript);
    let _ = std::fs::remove_dir_all(&out);
}
