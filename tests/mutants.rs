//! `harness mutants` through the binary. A mutant changes the manuals' data for a whole process,
//! so the command runs each in a child process of its own, and these tests run the command, never
//! a mutant in their own process (it would change the data under every test beside them).

#[allow(dead_code)] // what the other tests share
mod common;

use common::cli::harness;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Output;

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn scratch(tag: &str) -> PathBuf {
    common::cli::scratch("mutants", tag)
}

fn mutants_json(dir: &Path) -> Value {
    let text = std::fs::read_to_string(dir.join("mutants.json")).expect("mutants.json written");
    serde_json::from_str(&text).unwrap()
}

#[test]
fn the_list_names_each_change_and_the_manual_section_that_states_the_datum() {
    let o = harness(&["mutants", "--list"]);
    assert!(o.status.success(), "{o:?}");
    let list = stdout(&o);
    assert!(list.lines().count() > 700, "{}", list.lines().count());
    for line in [
        "led-dev/1/pattern\t\"FI is enabled\": Green → Off\tBU 0620 §5.5.1.1 DEV LED",
        "ethercat-aborts/7/code\tObject does not exist in the object dictionary (access to a non-existent parameter) 06020000h → 06020001h\tBU 0620 §2.2.7.2 EtherCAT SDO error codes",
        "coe-index/0/plus-one\tCoE index of P0 8192 → 8193\tBU 0620 §2.2.7 CoE object index",
    ] {
        assert!(list.lines().any(|l| l == line), "{line}\n{list}");
    }
    // A field no manual states is not mutated: P102's range and default are assumed.
    assert!(list.contains("P102 (inverter) decimals 2 → 3"), "{list}");
    assert!(!list.contains("P102 (inverter) default"), "{list}");
}

#[test]
fn a_changed_datum_is_killed_by_a_case_that_cites_it() {
    let out = scratch("killed");
    let o = harness(&[
        "mutants",
        "--only",
        "led-dev/1/",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{o:?}");
    assert!(
        stdout(&o)
            .contains("mutation score: 1 of 1 mutants of the manuals as code killed (100.0 %)"),
        "{}",
        stdout(&o)
    );
    let doc = mutants_json(&out);
    let r = &doc["results"][0];
    assert_eq!(r["id"], "led-dev/1/pattern");
    assert_eq!(r["outcome"], "killed");
    assert_eq!(
        (&r["manual"], &r["section"]),
        (&"BU 0620".into(), &"5.5.1.1".into())
    );
    let by = r["by"][0].as_str().unwrap();
    assert!(by.contains("leds"), "{by}");
    assert!(r["cases"].as_u64().unwrap() > 0);
}

#[test]
fn a_datum_no_case_can_see_survives_is_listed_and_fails_the_gate() {
    // Control bit 13 is reserved: no manual lets a case see it inverted.
    let out = scratch("survivor");
    let o = harness(&[
        "mutants",
        "--only",
        "control-bits/13/",
        "--min",
        "95",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{o:?}");
    let text = stdout(&o);
    assert!(
        text.contains("1 survivors (no case noticed the change):"),
        "{text}"
    );
    assert!(
        text.contains("  control-bits/13/inverted  control word bit 13 inverted"),
        "{text}"
    );
    assert_eq!(mutants_json(&out)["results"][0]["outcome"], "survived");
}

#[test]
fn the_run_reports_and_coverage_show_the_score_measured_into_their_folder() {
    let out = scratch("reports");
    let dir = out.to_str().unwrap();
    assert!(harness(&["mutants", "--only", "led-bus/5/", "--out", dir])
        .status
        .success());
    let o = harness(&["run", "-q", "--filter", "bu0620/leds/", "--out", dir]);
    assert!(o.status.success(), "{o:?}");
    let run: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(
        (&run["mutation"]["mutants"], &run["mutation"]["killed"]),
        (&1.into(), &1.into())
    );
    assert_eq!(run["mutation"]["sample"], true);
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(
        html.contains("<h2>Mutation score</h2>"),
        "no score in the HTML report"
    );
    let o = harness(&["coverage", "--reports", dir]);
    assert!(
        stdout(&o)
            .contains("mutation score: 1 of 1 mutants of the manuals as code killed (100.0 %)"),
        "{}",
        stdout(&o)
    );
}

#[test]
fn an_unknown_mutant_is_a_usage_error() {
    let o = harness(&["mutants", "--only", "no-such-site/"]);
    assert_eq!(o.status.code(), Some(2), "{o:?}");
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("no mutant id contains"),
        "{o:?}"
    );
}

/// The gate: the suites kill at least 95 % of the catalogue's mutants, here of every
/// other one, a sample across every site (half a minute on two cores, where CI's half hour is
/// tight; `harness mutants` runs them all, README gives the figure); the survivors are listed.
#[test]
fn the_suites_kill_at_least_95_percent_of_the_manuals_as_code_mutants() {
    let out = scratch("gate");
    let dir = out.to_str().unwrap();
    let o = harness(&["mutants", "--every", "2", "--min", "95", "--out", dir]);
    let doc = mutants_json(&out);
    let (n, killed) = (
        doc["mutants"].as_u64().unwrap(),
        doc["killed"].as_u64().unwrap(),
    );
    assert!(n > 350, "{n} mutants");
    assert_eq!(
        o.status.code(),
        Some(0),
        "{killed} of {n} killed:\n{}",
        stdout(&o)
    );
    for r in doc["results"].as_array().unwrap() {
        if r["outcome"] != "killed" {
            assert!(
                stdout(&o).contains(r["id"].as_str().unwrap()),
                "{r} not listed"
            );
        }
    }
}
