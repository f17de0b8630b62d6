//! A small run with something of every kind for the report tests: a suites folder written by
//! the test — a case the embedded simulator passes, one whose expectation it contradicts (a
//! fail), a reference-model check, and a file that does not load —, run through the `harness`
//! binary under two profiles, its reports in a fresh folder.

#![allow(dead_code)] // each test binary uses a part

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A suite file of three cases: P172 read right (pass under tu3-pnt), P172 read with a wrong
/// expectation (fail under tu3-pnt), and P170's definition from the reference model (a model
/// case under every profile: it passes under tu3-pnt and fails under sk550p, whose model has
/// no bus-interface P170). Under sk550p the first two do not apply.
const SUITE: &str = r#"doc: BU 0590
edition: "2012-03 en"
cases:
  - id: p172-right
    title: "P172 Configuration: 2 = module SK TU3-PNT"
    ref: { section: "5.1.3", page: 36 }
    profiles: [tu3-pnt]
    steps:
      - read: { param: 172, target: interface }
        expect: { value: 2 }
  - id: p172-wrong
    title: "P172 Configuration: 3 (an expectation the simulator contradicts)"
    ref: { section: "5.1.3", page: 36 }
    profiles: [tu3-pnt]
    steps:
      - read: { param: 172, target: interface }
        expect: { value: 3 }
  - id: p170-definition
    title: "P170 Present error: 0…5420, two elements, display only"
    ref: { section: "5.1.3", page: 35 }
    steps:
      - { compute: params.def, args: { param: 170, owner: interface }, expect: { max: 5420, array: 2, access: read-only } }
"#;

/// A file the loader refuses at line 4 (an unknown key).
const BROKEN: &str = "doc: BU 0590\nedition: \"2012-03 en\"\ncases:\n  - id: x\n    bogus: 1\n";

/// The reports of a finished run.
pub(crate) struct ReportRun {
    /// The output folder.
    pub(crate) out: PathBuf,
    /// `run.json`, parsed.
    pub(crate) json: Value,
}

/// Writes the suites into a fresh folder named for `name`, runs them, and returns the reports.
/// The run exits 2: a suite file did not load.
pub(crate) fn report_run(name: &str) -> ReportRun {
    let base = std::env::temp_dir().join(format!("harness-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&base);
    let suites = base.join("suites");
    std::fs::create_dir_all(suites.join("bu0590")).unwrap();
    std::fs::write(suites.join("bu0590/report-test.yaml"), SUITE).unwrap();
    std::fs::write(suites.join("bu0590/broken.yaml"), BROKEN).unwrap();
    let out = base.join("reports");
    let o = Command::new(env!("CARGO_BIN_EXE_harness"))
        .args([
            "run",
            "--profile",
            "tu3-pnt",
            "--profile",
            "sk550p",
            "--suites",
        ])
        .arg(&suites)
        .arg("--out")
        .arg(&out)
        .output()
        .expect("the harness binary runs");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(2),
        "a load error exits 2:\n{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let json: Value = serde_json::from_str(&read(&out.join("run.json"))).unwrap();
    ReportRun { out, json }
}

/// A report file's text.
pub(crate) fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}
