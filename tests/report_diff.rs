//! `harness diff` on two real runs of the `harness` binary: a small suite folder against the
//! embedded simulator as released, then a changed suite folder against the simulator's "next"
//! firmware (`NORD_SIM_FIRMWARE=next`: the SK 550P's P856 leaves the factory as 2, DHCP,
//! instead of 1, BOOTP). The diff must name the case that flips pass → fail with both messages,
//! show the changed exchange side by side, list the new and the vanished case, exit 1; and the
//! snapshots (`--accept`/`--snapshots`) must report the same change the same way.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Cases both suite versions have: the factory value (flips with the firmware), the range
/// (passes either way, its exchange changes) and, under the SK TU3-PNT whose software version
/// the run's record reads, a case the firmware does not touch.
const COMMON: &str = r#"
doc: BU 0620
edition: "2020-03 en"
cases:
  - id: p856-factory-bootp
    title: "P856 Addressing mode leaves the factory as 1 (BOOTP)"
    ref: { section: "4.2.2", page: 79 }
    profiles: [sk550p]
    steps:
      - read: { param: 856, target: interface }
        expect: { value: 1 }
  - id: p171-special-version
    title: "P171 [-03] special version: 0 = standard"
    ref: { section: "5.1.3", page: 35 }
    profiles: [tu3-pnt]
    steps:
      - read: { param: 171, element: 3, target: interface }
        expect: { value: 0 }
  - id: p856-a-mode
    title: "P856 holds an addressing mode, 0…2"
    ref: { section: "4.2.2", page: 79 }
    profiles: [sk550p]
    steps:
      - read: { param: 856, target: interface }
        expect: { value: { one_of: [0, 1, 2] } }
"#;

/// A case on an unchanged parameter, by element: the old suite has `[-01]`, the new `[-02]`.
fn mac_case(element: u8, value: &str) -> String {
    format!(
        r#"  - id: p878-manufacturer-{element}
    title: "P878 [-0{element}] = {value}"
    ref: {{ section: "4.4.1", page: 86 }}
    profiles: [sk550p]
    steps:
      - read: {{ param: 878, element: {element}, target: interface }}
        expect: {{ value: "{value}" }}
"#
    )
}

struct Dir(PathBuf);

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A fresh folder for one test (the tests run side by side).
fn scratch(test: &str) -> Dir {
    let dir =
        std::env::temp_dir().join(format!("harness-report-diff-{test}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Dir(dir)
}

fn suite(dir: &Path, name: &str, extra: &str) -> PathBuf {
    let suites = dir.join(name);
    std::fs::create_dir_all(suites.join("bu0620")).unwrap();
    std::fs::write(
        suites.join("bu0620/firmware.yaml"),
        format!("{COMMON}{extra}"),
    )
    .unwrap();
    suites
}

fn harness(args: &[&str], firmware: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_harness"));
    c.args(args).env_remove("NORD_SIM_FIRMWARE");
    if let Some(f) = firmware {
        c.env("NORD_SIM_FIRMWARE", f);
    }
    c.output().expect("the harness binary runs")
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Runs the old suite on the released simulator and the new suite on the next firmware.
fn two_runs(dir: &Path) -> (PathBuf, PathBuf) {
    let old_suites = suite(dir, "suites-old", &mac_case(1, "F0h"));
    let new_suites = suite(dir, "suites-new", &mac_case(2, "5Fh"));
    let (old, new) = (dir.join("old"), dir.join("new"));
    let run = |suites: &Path, out: &Path, fw| {
        harness(
            &[
                "run",
                "--suites",
                s(suites),
                "--profile",
                "sk550p",
                "--profile",
                "tu3-pnt",
                "--out",
                s(out),
            ],
            fw,
        )
    };
    let o = run(&old_suites, &old, None);
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
    let o = run(&new_suites, &new, Some("next"));
    assert_eq!(
        o.status.code(),
        Some(1),
        "the next firmware fails one case: {:?}",
        text(&o)
    );
    (old, new)
}

#[test]
fn a_firmware_change_flips_known_cases_and_the_diff_says_so() {
    let dir = scratch("flip");
    let (old, new) = two_runs(&dir.0);
    let out = dir.0.join("diff");
    let o = harness(&["diff", s(&old), s(&new), "--out", s(&out)], None);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(1), "a regression: {stdout}{stderr}");

    // Header: both runs, the firmware named in the DUT and in the identity the device reports.
    assert!(
        stdout.contains("DUT: embedded simulator  →  embedded simulator (firmware next)\n"),
        "{stdout}"
    );
    assert!(
        stdout.contains("identity tu3-pnt: firmware 1.0 R4 (from P171 software version over the parameter channel)  →  firmware 1.0 R5 (from P171 software version over the parameter channel)\n"),
        "{stdout}"
    );
    // Unchanged: the P171 case under tu3-pnt, each profile's not-applicable cases.
    assert!(
        stdout.contains("verdict changes: 1 (regressions: 1), new fails or errors: 1, transcript changes: 2, new: 2, vanished: 2, unchanged: 4"),
        "{stdout}"
    );
    // The flipped case, old → new, with both messages.
    assert!(
        stdout.contains("Verdict changes:\n  sk550p bu0620/firmware/p856-factory-bootp: pass → fail (regression)\n    old: —\n    new: value: expected 1, got 2\n"),
        "{stdout}"
    );
    // The changed exchange, decoded, old line against new line.
    let answer = |pwe: u8| format!("<- 64 02 17 40 00 00 00 00 00 0{pwe} 00 00 00 00 00 00 00 00");
    let decoded = |pwe: u8| {
        format!("AK 1 \"Transfer parameter value (word)\", PNU 1856 = P856, IND 0000h (set 1 / element 1), PWE {pwe};")
    };
    let range = stdout
        .split("  sk550p bu0620/firmware/p856-a-mode\n")
        .nth(1)
        .expect("the passing case's transcript changed too");
    for want in [
        "    @ step 1: read P856 interface\n".to_string(),
        format!("    -   16   {}\n", answer(1)),
        format!("    +   16   {}\n", answer(2)),
        format!("    -   17      {}", decoded(1)),
        format!("    +   17      {}", decoded(2)),
    ] {
        assert!(range.contains(&want), "{want}\n---\n{stdout}");
    }
    assert!(
        stdout.contains("New cases (only in the new run):\n  sk550p bu0620/firmware/p878-manufacturer-2: pass\n"),
        "{stdout}"
    );
    // What decided the exit code.
    assert!(
        stdout.contains("\ngate (regressions and new fails or errors): 1 case(s)\n  sk550p bu0620/firmware/p856-factory-bootp: pass → fail\n"),
        "{stdout}"
    );
    assert!(
        stdout.contains("Vanished cases (only in the old run):\n  sk550p bu0620/firmware/p878-manufacturer-1: pass\n"),
        "{stdout}"
    );

    // The same in diff.md and diff.html.
    let md = std::fs::read_to_string(out.join("diff.md")).unwrap();
    assert!(
        md.contains("| sk550p | `bu0620/firmware/p856-factory-bootp` | **pass → fail (regression)** |  | value: expected 1, got 2 |"),
        "{md}"
    );
    assert!(
        md.contains(&format!(
            "| 16 | **`   {} `** | 16 | **`   {} `** |",
            answer(1),
            answer(2)
        )),
        "{md}"
    );
    assert!(md.contains("`bu0620/firmware/p878-manufacturer-1`"), "{md}");
    let html = std::fs::read_to_string(out.join("diff.html")).unwrap();
    assert!(
        html.contains("<td class=\"regression\">pass → fail (regression)</td>"),
        "{html}"
    );
    assert!(
        html.contains(&format!(
            "<td class=\"code new\">  &lt;{}</td>",
            &answer(2)[1..]
        )),
        "{html}"
    );
    assert!(
        stdout.ends_with(&format!(
            "diff: {}, {}\n",
            s(&out.join("diff.md")),
            s(&out.join("diff.html"))
        )),
        "{stdout}"
    );
}

#[test]
fn no_change_exits_0_and_an_unreadable_run_is_a_usage_error_naming_the_file() {
    let dir = scratch("same");
    let (old, _) = two_runs(&dir.0);
    let o = harness(&["diff", s(&old), s(&old.join("run.json"))], None);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stdout}{stderr}");
    assert!(
        stdout.contains("verdict changes: 0 (regressions: 0), new fails or errors: 0, transcript changes: 0, new: 0, vanished: 0, unchanged: 8"),
        "{stdout}"
    );

    let missing = dir.0.join("no-such-run");
    let o = harness(&["diff", s(&old), s(&missing)], None);
    let (_, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr.contains(s(&missing)), "{stderr}");
    // A lost transcript is named too.
    let file = old.join("transcripts.txt");
    let kept = std::fs::read_to_string(&file).unwrap();
    let lost = "=== sk550p/bu0620/firmware/p856-a-mode\n";
    assert!(kept.contains(lost), "{kept}");
    std::fs::write(&file, kept.replace(lost, "")).unwrap();
    let o = harness(&["diff", s(&old), s(&old)], None);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o)
            .1
            .contains("transcripts.txt#sk550p/bu0620/firmware/p856-a-mode"),
        "{:?}",
        text(&o)
    );
    let o = harness(&["diff", s(&old)], None);
    assert_eq!(o.status.code(), Some(2), "NEW missing: usage");
}

#[test]
fn snapshots_report_the_same_change_the_same_way() {
    let dir = scratch("snapshots");
    let suites = suite(&dir.0, "suites", "");
    let snaps = dir.0.join("snapshots");
    let run = |extra: &str, fw| {
        harness(
            &[
                "run",
                "--suites",
                s(&suites),
                "--profile",
                "sk550p",
                "--out",
                s(&dir.0.join("out")),
                "--snapshot-dir",
                s(&snaps),
                extra,
            ],
            fw,
        )
    };
    let o = run("--accept", None);
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
    let o = run("--snapshots", Some("next"));
    let (stdout, _) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("snapshots: 0 stored, 1 unchanged, 2 changed, 0 new"),
        "{stdout}"
    );
    // The case that still passes on its own fails on its changed transcript, which names the
    // first changed line the way `harness diff` shows it.
    let run_json = std::fs::read_to_string(dir.0.join("out/run.json")).unwrap();
    let want = format!(
        "transcript differs from snapshot {}: first difference at line 9 (step 1: read P856 interface): expected `  observed: {{\\\"ak\\\":1,\\\"cycles\\\":2,\\\"error\\\":null,\\\"ind\\\":0,\\\"pnu\\\":1856,\\\"value\\\":1}}`, got `  observed: {{\\\"ak\\\":1,\\\"cycles\\\":2,\\\"error\\\":null,\\\"ind\\\":0,\\\"pnu\\\":1856,\\\"value\\\":2}}`",
        s(&snaps.join("sk550p/bu0620__firmware__p856-a-mode.snap"))
    );
    assert!(run_json.contains(&want), "{want}\n---\n{run_json}");
}

/// A quiet run of the checked-in suites, as the README's demo runs them, under the SK 550P
/// over EtherNet/IP, cut to the cases `filter` selects, on `firmware`.
fn run_checked_in(out: &Path, filter: &str, firmware: Option<&str>) -> Output {
    let suites = Path::new(env!("CARGO_MANIFEST_DIR")).join("../suites");
    harness(
        &[
            "run",
            "--suites",
            s(&suites),
            "--profile",
            "sk550p@enip",
            "--filter",
            filter,
            "--out",
            s(out),
            "-q",
        ],
        firmware,
    )
}

/// The README's firmware comparison on the checked-in suites, cut to the P85x cases of the
/// SK 550P over EtherNet/IP: the next firmware's P856 factory value (2, DHCP) fails a device
/// case, and `harness diff` exits 1 on it under either rule.
#[test]
fn the_readme_firmware_demo_fails_a_device_case_and_the_diff_exits_1() {
    let dir = scratch("readme-demo");
    let (old, new) = (dir.0.join("release"), dir.0.join("next"));
    let case = "bu0620/params-catalogue/p856-factory-and-range";
    let o = run_checked_in(&old, "params-catalogue/p85", None);
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
    let o = run_checked_in(&new, "params-catalogue/p85", Some("next"));
    let (stdout, _) = text(&o);
    assert_eq!(
        o.status.code(),
        Some(1),
        "the next firmware fails: {stdout}"
    );
    // -q names the failed case, then the totals.
    assert!(
        stdout.starts_with(&format!(
            "FAIL  [sk550p@enip] {case}: value: expected 1, got 2\n"
        )),
        "{stdout}"
    );
    assert_eq!(stdout.lines().count(), 2, "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(new.join("run.json")).unwrap()).unwrap();
    let failed: Vec<(&str, &str)> = json["cases"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|c| c["verdict"] == "fail")
        .map(|c| (c["id"].as_str().unwrap(), c["kind"].as_str().unwrap()))
        .collect();
    assert_eq!(
        failed,
        [(case, "device")],
        "a device case fails, no model case"
    );

    for rule in [None, Some("--regressions-only")] {
        let mut args = vec!["diff", s(&old), s(&new)];
        args.extend(rule);
        let o = harness(&args, None);
        let (stdout, stderr) = text(&o);
        assert_eq!(o.status.code(), Some(1), "{rule:?}: {stdout}{stderr}");
        assert!(
            stdout.contains(&format!("  sk550p@enip {case}: pass → fail (regression)\n")),
            "{stdout}"
        );
    }
}

/// The two rules of `harness diff`: a case the old run did not select that fails in the new
/// one gates by default, not with `--regressions-only`.
#[test]
fn a_new_case_that_fails_gates_unless_regressions_only() {
    let dir = scratch("new-fail");
    let (old, new) = (dir.0.join("old"), dir.0.join("new"));
    // The old run has P853's case only; the new one P856's too, which fails on the next
    // firmware.
    let o = run_checked_in(&old, "params-catalogue/p853", None);
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
    let o = run_checked_in(&new, "params-catalogue/p85", Some("next"));
    assert_eq!(o.status.code(), Some(1), "{:?}", text(&o));
    let o = harness(&["diff", s(&old), s(&new)], None);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{stdout}{stderr}");
    assert!(
        stdout.contains("New cases (only in the new run):\n  sk550p@enip bu0620/params-catalogue/p856-factory-and-range: fail (new failure) (value: expected 1, got 2)\n"),
        "{stdout}"
    );
    assert!(
        stdout.contains("gate (regressions and new fails or errors): 1 case(s)\n  sk550p@enip bu0620/params-catalogue/p856-factory-and-range: new → fail\n"),
        "{stdout}"
    );
    let o = harness(&["diff", s(&old), s(&new), "--regressions-only"], None);
    let (stdout, stderr) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{stdout}{stderr}");
    assert!(
        stdout.contains("gate (regressions only): 0 case(s)\n"),
        "{stdout}"
    );
}
