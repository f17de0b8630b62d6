//! `harness run --shard K/N` and `harness merge`, end to end through the binary: a real suite
//! subset run whole and as three shards; the merged reports equal the whole run's file by file,
//! byte for byte, once what differs between any two runs is masked. And snapshots accepted from
//! the whole run hold for a filtered, a sharded and a shuffled run: a case's transcript is a
//! function of the case alone, whatever ran before it.

use regex::Regex;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The selection: one profile per way the harness reaches a device — the PPO link and each
/// bus's own binding (EtherNet/IP, EtherCAT, POWERLINK, PROFINET) — over BU 0620 and the
/// buses' own suites ([`SUITES`]), a few thousand case-runs, most of them not applicable, so
/// every shard gets both kinds.
///
/// The PPO link alone (this test's selection once) picks no identifier of its own, so it could
/// not see what the buses' bindings carry from case to case: EtherNet/IP connection serial
/// numbers and T→O connection ids, and PROFINET RPC activities, came from process-wide
/// counters, and a merge of shards differed from the whole run in hundreds of transcripts.
const SELECTION: [&str; 10] = [
    "--profile",
    "sk550p",
    "--profile",
    "tu3-eip@enip",
    "--profile",
    "sk550p@ecat",
    "--profile",
    "tu4-pol@epl",
    "--profile",
    "sk550p@pnio",
];

/// The suite folders copied, `bu0620` with [`FAILING`] added.
const SUITES: [&str; 5] = ["bu0620", "cip", "ecat", "epl", "pnio"];

/// Cases the simulator fails, so that the reports' failure details (the deciding step, what
/// was observed, the device's refusal) must survive the merge too.
const FAILING: &str = r#"
doc: BU 0620
edition: "2020-03 en"
cases:
  - id: p856-wrong-factory-value
    title: "P856 leaves the factory as 2 (it is 1: this case fails on purpose)"
    ref: { section: "4.2.2", page: 79 }
    profiles: [sk550p]
    steps:
      - read: { param: 856, target: interface }
        expect: { value: 2 }
  - id: p856-out-of-range-accepted
    title: "P856 takes 5 (it is refused: this case fails on purpose)"
    ref: { section: "4.2.2", page: 79 }
    profiles: [sk550p]
    steps:
      - write: { param: 856, target: interface, value: 5 }
"#;

/// [`SUITES`] in `dir/suites`, with the failing cases.
fn suites(dir: &Path) -> PathBuf {
    for name in SUITES {
        let from = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../suites")
            .join(name);
        let to = dir.join("suites").join(name);
        std::fs::create_dir_all(&to).unwrap();
        for e in std::fs::read_dir(&from).unwrap() {
            let p = e.unwrap().path();
            std::fs::copy(&p, to.join(p.file_name().unwrap())).unwrap();
        }
    }
    std::fs::write(dir.join("suites/bu0620/zz-failing.yaml"), FAILING).unwrap();
    dir.join("suites")
}

struct Dir(PathBuf);

impl Drop for Dir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// A fresh folder for one test (the tests run side by side).
fn scratch(test: &str) -> Dir {
    let dir = std::env::temp_dir().join(format!(
        "harness-report-shard-{test}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    Dir(dir)
}

fn harness(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_harness"))
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .args(args)
        .env_remove("NORD_SIM_FIRMWARE")
        .output()
        .expect("the harness binary runs")
}

fn show(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// `harness run` of the selection in `suites` into `out`, with `extra` arguments.
fn run_output(suites: &Path, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["run", "--suites", s(suites), "--out", s(out)];
    args.extend(SELECTION);
    args.extend(extra);
    harness(&args)
}

/// [`run_output`]'s exit code.
fn run(suites: &Path, out: &Path, extra: &[&str]) -> i32 {
    let o = run_output(suites, out, extra);
    o.status.code().unwrap_or_else(|| panic!("{}", show(&o)))
}

/// `run.json` of the report folder `out`, parsed.
fn run_json(out: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap()
}

/// Every case-run of a report's `run.json`: (profile, case id) → verdict.
fn verdicts(json: &Value) -> BTreeMap<(String, String), String> {
    json["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let text = |k: &str| c[k].as_str().unwrap().to_string();
            ((text("profile"), text("id")), text("verdict"))
        })
        .collect()
}

/// The profiles of [`SELECTION`].
fn selected_profiles() -> Vec<&'static str> {
    SELECTION.iter().skip(1).step_by(2).copied().collect()
}

/// Every selected profile passes cases that reach the device, so that the comparisons cover
/// the exchanges of every binding.
fn assert_every_binding_exchanged(json: &Value) {
    for profile in selected_profiles() {
        let passed = json["cases"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|c| c["profile"] == profile && c["kind"] == "device" && c["verdict"] == "pass")
            .count();
        assert!(passed > 20, "{profile}: {passed} device cases passed");
    }
}

/// Every file below `dir`, by relative path.
fn files(dir: &Path) -> BTreeMap<String, String> {
    fn walk(base: &Path, dir: &Path, into: &mut BTreeMap<String, String>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(base, &p, into);
            } else {
                let rel = p.strip_prefix(base).unwrap().to_string_lossy().into_owned();
                into.insert(rel, std::fs::read_to_string(&p).unwrap());
            }
        }
    }
    let mut all = BTreeMap::new();
    walk(dir, dir, &mut all);
    all
}

/// What legitimately differs between two runs of the same selection, masked:
/// - the report folders' paths (`--out` on the command line: the merge's command line is the
///   first shard's);
/// - the command line in `run.json` (the merge's is the first shard's without `--shard`);
/// - start times: every RFC 3339 timestamp (`started`, JUnit's `timestamp`);
/// - durations: `run.json`'s `"duration"` fields, JUnit's `time` attributes and `duration`
///   property, the summary's `0.223 s`.
fn masked(text: &str, folders: &[&Path]) -> String {
    let masks = [
        (
            r#""command_line": \[[^\]]*\]"#,
            r#""command_line": <command line>"#,
        ),
        (
            r"\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}(\.\d+)?(Z|[+-]\d{2}:\d{2})?",
            "<time>",
        ),
        (r#""duration": [-+.\deE]+"#, r#""duration": <duration>"#),
        (r#" time="[^"]*""#, r#" time="<duration>""#),
        (
            r#"name="duration" value="[^"]*""#,
            r#"name="duration" value="<duration>""#,
        ),
        (r"\b\d+\.\d+ s\b", "<duration> s"),
    ];
    let mut text = text.to_string();
    for folder in folders {
        text = text.replace(s(folder), "<out>");
    }
    for (pattern, by) in masks {
        text = Regex::new(pattern)
            .unwrap()
            .replace_all(&text, by)
            .into_owned();
    }
    text
}

/// The first line where two texts differ, for a readable failure.
fn first_difference(a: &str, b: &str) -> Option<(usize, String, String)> {
    let (mut x, mut y) = (a.lines(), b.lines());
    for n in 1.. {
        match (x.next(), y.next()) {
            (None, None) => return None,
            (l, r) if l != r => {
                let show = |l: Option<&str>| l.unwrap_or("(end)").to_string();
                return Some((n, show(l), show(r)));
            }
            _ => {}
        }
    }
    None
}

#[test]
fn three_shards_merge_into_the_unsharded_reports() {
    let dir = scratch("merge");
    let suites = suites(&dir.0);
    let whole = dir.0.join("whole");
    let code = run(&suites, &whole, &[]);
    assert_eq!(code, 1, "the failing cases fail");
    assert_every_binding_exchanged(&run_json(&whole));
    let shards: Vec<PathBuf> = (1..=3).map(|k| dir.0.join(format!("shard{k}"))).collect();
    let mut counts = Vec::new();
    for (k, shard) in (1..).zip(&shards) {
        let spec = format!("{k}/3");
        assert!(
            [0, 1].contains(&run(&suites, shard, &["--shard", &spec])),
            "shard {spec}"
        );
        let seqs: Vec<usize> = run_json(shard)["cases"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c["seq"].as_u64().unwrap() as usize)
            .collect();
        assert!(
            seqs.iter().all(|q| q % 3 == k - 1),
            "shard {spec} runs case-runs i with i mod 3 = {}: {seqs:?}",
            k - 1
        );
        counts.push(seqs.len());
    }
    let merged = dir.0.join("merged");
    let mut args = vec!["merge", "--out", s(&merged)];
    args.extend(shards.iter().map(|p| s(p)));
    let o = harness(&args);
    assert_eq!(
        o.status.code(),
        Some(code),
        "merge exits as the whole run: {}",
        show(&o)
    );

    let (want, got) = (files(&whole), files(&merged));
    assert_eq!(
        want.keys().collect::<Vec<_>>(),
        got.keys().collect::<Vec<_>>(),
        "the same files"
    );
    assert!(want.contains_key("run.json") && want.contains_key("junit.xml"));
    // What the comparison must cover: the failures' deciding steps and the device's refusal.
    let html = &want["index.html"];
    assert!(html.contains("<dt>step observed</dt>"), "{html}");
    assert!(html.contains("<dt>refusal</dt>"), "{html}");
    assert!(want["transcripts.txt"].matches("\n=== ").count() > 50);
    let total: usize = counts.iter().sum();
    assert!(counts.iter().all(|&n| n >= total / 3), "{counts:?}");
    for (name, text) in &want {
        let folders: Vec<&Path> = [&whole, &merged]
            .into_iter()
            .chain(&shards)
            .map(PathBuf::as_path)
            .collect();
        let (w, g) = (masked(text, &folders), masked(&got[name], &folders));
        assert_eq!(
            first_difference(&w, &g),
            None,
            "{name} differs after masking"
        );
        assert_eq!(w, g, "{name}: byte for byte");
    }
}

#[test]
fn merge_refuses_an_incomplete_or_doubled_set_and_shard_values_are_checked() {
    let dir = scratch("refuse");
    let suites = suites(&dir.0);
    let shards: Vec<PathBuf> = (1..=3).map(|k| dir.0.join(format!("shard{k}"))).collect();
    // A few case-runs are shards enough for the refusals.
    for (k, shard) in (1..).zip(&shards) {
        run(
            &suites,
            shard,
            &["--filter", "p856", "--shard", &format!("{k}/3")],
        );
    }
    let out = dir.0.join("merged");
    let o = harness(&["merge", "--out", s(&out), s(&shards[0]), s(&shards[1])]);
    assert_eq!(o.status.code(), Some(2), "{}", show(&o));
    assert!(show(&o).contains("incomplete"), "{}", show(&o));
    assert!(!out.join("run.json").exists(), "nothing written");

    let o = harness(&[
        "merge",
        "--out",
        s(&out),
        s(&shards[0]),
        s(&shards[1]),
        s(&shards[2]),
        s(&shards[2]),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(show(&o).contains("given twice"), "{}", show(&o));
    assert!(
        show(&o).contains(s(&shards[2])),
        "names the folder: {}",
        show(&o)
    );

    let o = harness(&[
        "merge",
        "--out",
        s(&shards[0]),
        s(&shards[0]),
        s(&shards[1]),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        show(&o).contains("is one of the shards' folders"),
        "{}",
        show(&o)
    );

    for bad in ["0/3", "4/3", "1/0", "3"] {
        let o = harness(&["run", "--out", s(&out), "--shard", bad]);
        assert_eq!(o.status.code(), Some(2), "--shard {bad}: {}", show(&o));
        assert!(show(&o).contains("1 ≤ K ≤ N"), "{}", show(&o));
    }
}

/// Snapshots accepted from the whole run, then runs of part of it in another order: the cases a
/// `--filter` selects (each run after fewer cases than in the whole run), one shard, and every
/// case shuffled. No transcript changed, so every case has the whole run's verdict (a changed
/// transcript turns a passing case into a failure).
#[test]
fn snapshots_of_the_whole_run_hold_for_a_filtered_sharded_or_shuffled_run() {
    let dir = scratch("snapshots");
    let suites = suites(&dir.0);
    let snapshots = dir.0.join("snapshots");
    let whole = dir.0.join("whole");
    let accept = ["--accept", "--snapshot-dir", s(&snapshots)];
    assert_eq!(run(&suites, &whole, &accept), 1, "the failing cases fail");
    let want = verdicts(&run_json(&whole));
    assert_every_binding_exchanged(&run_json(&whole));

    let compare = ["--snapshots", "--snapshot-dir", s(&snapshots)];
    // drive-switching: process data, after other process-data cases in the whole run (an
    // EtherNet/IP I/O connection, a PROFINET AR, EtherCAT and POWERLINK PDOs).
    let parts: [&[&str]; 3] = [
        &["--filter", "drive-switching"],
        &["--shard", "2/3"],
        &["--shuffle", "7"],
    ];
    for (n, part) in parts.into_iter().enumerate() {
        let out = dir.0.join(format!("part{n}"));
        let mut args = compare.to_vec();
        args.extend(part);
        let o = run_output(&suites, &out, &args);
        let text = show(&o);
        assert!(
            text.contains(" 0 changed,"),
            "{part:?}: no transcript changed:\n{text}"
        );
        let got = verdicts(&run_json(&out));
        assert!(got.len() > 20, "{part:?}: {} case-runs", got.len());
        for ((profile, id), verdict) in &got {
            assert_eq!(
                Some(verdict),
                want.get(&(profile.clone(), id.clone())),
                "{part:?}: {profile} {id}"
            );
        }
        if part[0] == "--filter" {
            for profile in selected_profiles() {
                assert!(
                    got.iter().any(|((p, _), v)| p == profile && v == "pass"),
                    "{part:?} passes cases under {profile}: {got:?}"
                );
            }
        }
    }
}
