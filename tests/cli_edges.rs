//! The command line at its edges, through the `harness` binary: nonsensical options are usage
//! errors (exit 2) that say what is wrong, a closed stdout ends the output quietly, one number
//! syntax reads every wire value, suite files load whatever the case of their extension, and a
//! UDP port clash with the DUT is diagnosed once before the run.

#[allow(dead_code)] // what the other network tests share
mod common;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use common::cli::harness;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn scratch(tag: &str) -> PathBuf {
    common::cli::scratch("cli", tag)
}

#[test]
fn nonsensical_options_are_usage_errors_that_say_why() {
    let out = scratch("usage");
    let file = out.join("a-file");
    std::fs::write(&file, "not a folder").unwrap();
    for (args, says) in [
        (vec!["run", "--retries", "0"], "`--retries 0`"),
        (
            vec!["run", "--out", file.to_str().unwrap()],
            "is a file; give the folder",
        ),
        (
            vec!["run", "--filter", "no-such-case-anywhere"],
            "no case id contains `no-such-case-anywhere`",
        ),
        (
            vec!["run", "--dut", "enip://127.0.0.1"],
            "`--dut` needs `--profile`",
        ),
        (
            vec!["addr", "P102", "--index", "2"],
            "P102 \"Acceleration time\" is not an array parameter",
        ),
        (vec!["addr", "P400", "--index", "12"], "has 9 elements"),
        (
            vec!["addr", "P465", "--set", "2"],
            "does not depend on the parameter set",
        ),
    ] {
        let o = harness(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
    }
    // The refused run wrote nothing.
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "not a folder");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn a_closed_stdout_ends_the_listing_quietly() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_harness"))
        .current_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join(".."))
        .arg("list")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Read a little, then close the pipe, as `harness list | head -1` does.
    let mut first = [0u8; 64];
    child.stdout.take().unwrap().read_exact(&mut first).unwrap();
    let mut err = String::new();
    child
        .stderr
        .take()
        .unwrap()
        .read_to_string(&mut err)
        .unwrap();
    let status = child.wait().unwrap();
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.is_empty(), "{err}");
    assert_eq!(status.code(), Some(0));
}

#[test]
fn words_and_pkw_bytes_read_one_number_syntax() {
    let status = |w: &str| {
        let o = harness(&["decode", "status", w, "--json"]);
        assert_eq!(o.status.code(), Some(0), "{w}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v["meaning"].as_str().unwrap().to_string()
    };
    let want = status("0B31h");
    for w in ["0x0B31", "0B31", "0000101100110001b"] {
        assert_eq!(status(w), want, "{w}");
    }
    let pkw = |bytes: &[&str]| {
        let o = harness(&[&["decode", "pkw"], bytes].concat());
        assert_eq!(o.status.code(), Some(0), "{bytes:?}: {}", stderr(&o));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let want = pkw(&["70", "66", "02", "00", "00", "00", "03", "E8"]);
    assert_eq!(
        pkw(&["70h", "0x66", "02", "00", "00", "00", "03h", "0xE8"]),
        want
    );
    // Refused alike, with the same words.
    for args in [
        vec!["decode", "status", "zz"],
        vec!["decode", "pkw", "70", "zz"],
    ] {
        let o = harness(&args);
        assert_eq!(o.status.code(), Some(2));
        assert!(
            stderr(&o).contains("`zz` is not a hex value"),
            "{}",
            stderr(&o)
        );
    }
}

#[test]
fn suite_files_with_upper_case_extensions_load() {
    let dir = scratch("ext");
    let suite = |id: &str| {
        format!(
            "doc: BU 0620\nedition: \"2020-03 en\"\ncases:\n  - id: {id}\n    title: P102 reads\n    ref: {{ section: \"2.5.6\", page: 51 }}\n    profiles: [sk550p]\n    steps:\n      - read: {{ param: 102 }}\n"
        )
    };
    std::fs::write(dir.join("upper.YAML"), suite("upper")).unwrap();
    std::fs::write(dir.join("mixed.Yml"), suite("mixed")).unwrap();
    let out = dir.join("reports");
    let o = harness(&[
        "run",
        "--profile",
        "sk550p",
        "--suites",
        dir.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{stdout}{}", stderr(&o));
    assert!(
        stdout.contains("2 cases under 1 profile: 2 pass"),
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_udp_port_clash_with_the_adapter_is_diagnosed_once_at_start() {
    // The scanner's `--local` is the served adapter's own address: its UDP 2222 is taken.
    let clash = common::addr::free_loopback();
    let _server = common::serve(&format!("{clash}:44818"), "tu3-eip", 60);
    let out = scratch("clash");
    let o = harness(&[
        "run",
        "--dut",
        &format!("enip://{clash}"),
        "--local",
        &clash.to_string(),
        "--profile",
        "tu3-eip",
        "--out",
        out.to_str().unwrap(),
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains(&format!("UDP {clash}:2222 is in use")) && err.contains("--local"),
        "{err}"
    );
    assert!(!out.join("run.json").exists(), "no run took place");
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn coverage_counts_the_inventories_and_names_what_keeps_them_dishonest() {
    // The release gate of issue 13: every section of every manual has at least 90 % of its
    // testable statements asserted.
    let o = harness(&["coverage", "--min", "90"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{stdout}{}", stderr(&o));
    for manual in [
        "BU 0620  2020-03 en",
        "BU 2100  en",
        "BU 0590  2012-03 en",
        "BU 2200  2019 de",
    ] {
        assert!(
            stdout
                .lines()
                .any(|l| l.starts_with(manual) && l.contains(" all ")),
            "{manual}: {stdout}"
        );
        // Every section of its table of contents is accounted for (item 5 of issue 23).
        assert!(
            stdout.lines().any(|l| l.starts_with(manual)
                && l.contains(" sections: ")
                && l.ends_with("with nothing testable (reasons given)")),
            "{manual}: {stdout}"
        );
    }
    // A suite folder whose inventory names a case no suite has, and misses the one there is.
    let dir = scratch("coverage");
    std::fs::create_dir_all(dir.join("inventory")).unwrap();
    std::fs::write(
        dir.join("p102.yaml"),
        "doc: BU 0620\nedition: \"2020-03 en\"\ncases:\n  - id: read\n    title: P102 reads\n    ref: { section: \"2.5.6\", page: 51 }\n    steps:\n      - read: { param: 102 }\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("inventory/bu0620.yaml"),
        "doc: BU 0620\nedition: \"2020-03 en\"\ncontents: [{ section: \"2.5.6\", title: Parameter data transmission }]\nstatements:\n  - section: \"2.5.6\"\n    says: P102 reads\n    cases: [p102/gone]\n    values: [{ case: p102/gone, step: 1, value: 250 }]\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("inventory/floors.yaml"),
        "\"BU 0620 2020-03 en\": 1\n",
    )
    .unwrap();
    let o = harness(&["coverage", "--suites", dir.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("names case `p102/gone`, which no suite has"),
        "{stdout}"
    );
    assert!(
        stdout.contains("case `p102/read` cites BU 0620 §2.5.6 and no statement names it"),
        "{stdout}"
    );
    // A hollow claim: P102 is what the step reads, not what it expects.
    std::fs::write(
        dir.join("inventory/bu0620.yaml"),
        "doc: BU 0620\nedition: \"2020-03 en\"\ncontents: [{ section: \"2.5.6\", title: Parameter data transmission }]\nstatements:\n  - section: \"2.5.6\"\n    says: P102 reads\n    cases: [p102/read]\n    values: [{ case: p102/read, step: 1, value: 102 }]\n",
    )
    .unwrap();
    let o = harness(&["coverage", "--suites", dir.to_str().unwrap()]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("value `102` is not asserted by case `p102/read` step 1: the case step 1 expects nothing"),
        "{stdout}"
    );
    // A section of the table of contents without statements and without a reason: the
    // inventory does not load, and the error names the file and the section.
    std::fs::write(
        dir.join("inventory/bu0620.yaml"),
        "doc: BU 0620\nedition: \"2020-03 en\"\ncontents:\n  - { section: \"2.5.6\", title: Parameter data transmission }\n  - { section: \"2.5.7\", title: Forgotten }\nstatements:\n  - section: \"2.5.6\"\n    says: P102 reads\n    cases: [p102/read]\n    values: [{ case: p102/read, step: 1, value: 250 }]\n",
    )
    .unwrap();
    let o = harness(&["coverage", "--suites", dir.to_str().unwrap()]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("bu0620.yaml")
            && err.contains("§2.5.7 \"Forgotten\": no statement lies in it"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn coverage_gates_on_a_share_per_section_and_counts_errata_by_check() {
    let dir = scratch("coverage-min");
    std::fs::create_dir_all(dir.join("inventory")).unwrap();
    std::fs::write(
        dir.join("p102.yaml"),
        "doc: BU 0620\nedition: \"2020-03 en\"\ncases:\n  - id: read\n    title: P102 reads\n    ref: { section: \"2.5.6\", page: 51 }\n    manual_says: { printed: \"06020002h\", correct: \"06010002h\", why: \"w\", check: standard, standard: \"CiA 301 4.2.0 §7.2.4.3.17\" }\n    steps:\n      - read: { param: 102 }\n        expect: { value: 250 }\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("inventory/bu0620.yaml"),
        "doc: BU 0620\nedition: \"2020-03 en\"\ncontents: [{ section: \"2.5.6\", title: Parameter data transmission }]\nstatements:\n  - section: \"2.5.6\"\n    says: P102 reads\n    cases: [p102/read]\n    values: [{ case: p102/read, step: 1, value: 250 }]\n  - section: \"2.5.6\"\n    says: P102 writes\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("inventory/floors.yaml"),
        "\"BU 0620 2020-03 en\": 1\n",
    )
    .unwrap();
    let suites = dir.to_str().unwrap();
    let o = harness(&["coverage", "--suites", suites, "--min", "50"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(0), "{stdout}{}", stderr(&o));
    let errata: Vec<&str> = stdout
        .lines()
        .find(|l| l.starts_with("BU 0620 2020-03 en"))
        .expect("an errata row")
        .split_whitespace()
        .collect();
    // errata, own-text, standard, other-manual, range-default, ambiguous
    assert_eq!(errata[4..], ["1", "0", "1", "0", "0", "0"], "{stdout}");
    let o = harness(&["coverage", "--suites", suites, "--min", "90"]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains("PROBLEM BU 0620 2020-03 en §2.5.6: 1 of 2 testable statements asserted (50 %; 1 on the device), below 90 %"),
        "{stdout}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn each_bus_served_shows_its_own_options() {
    for (bus, option) in [
        ("enip", "--max-sessions"),
        ("ecat", "--iface"),
        ("epl", "--node-id"),
        ("pnio", "--name"),
        ("can", "--socketcand"),
    ] {
        let o = harness(&["serve", bus, "--help"]);
        let stdout = String::from_utf8_lossy(&o.stdout);
        assert_eq!(o.status.code(), Some(0), "{bus}: {}", stderr(&o));
        assert!(
            stdout.contains(&format!("Usage: harness serve {bus}")) && stdout.contains(option),
            "{bus}: {stdout}"
        );
    }
    let o = harness(&["serve", "lin"]);
    assert!(
        stderr(&o).contains("cannot serve `lin` (buses: enip, ecat, epl, pnio, can)"),
        "{}",
        stderr(&o)
    );
}

/// `field` of every case in the run.json in `out`, in order.
fn cases_in(out: &Path, field: &str) -> Vec<String> {
    let run: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("run.json")).unwrap()).unwrap();
    run["cases"]
        .as_array()
        .expect("cases")
        .iter()
        .filter_map(|c| c[field].as_str().map(String::from))
        .collect()
}

#[test]
fn a_profile_given_twice_runs_once_and_the_note_says_so() {
    let out = scratch("twice");
    let o = harness(&[
        "run",
        "--profile",
        "sk550p",
        "--profile",
        "tu3-eip",
        "--profile",
        "sk550p",
        "--filter",
        "first-control-command-047eh",
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("`--profile sk550p` given again: each profile runs once"),
        "{err}"
    );
    // Each case once per profile: no (profile, case) twice.
    let runs: Vec<(String, String)> = cases_in(&out, "profile")
        .into_iter()
        .zip(cases_in(&out, "id"))
        .collect();
    let mut once = runs.clone();
    once.dedup();
    assert_eq!(once, runs, "a case-run twice");
    let profiles: std::collections::BTreeSet<&str> = runs.iter().map(|r| r.0.as_str()).collect();
    assert_eq!(
        profiles.into_iter().collect::<Vec<_>>(),
        ["sk550p", "tu3-eip"]
    );
    let _ = std::fs::remove_dir_all(&out);
}

#[test]
fn run_help_lists_every_profile_and_every_dut_scheme() {
    let o = harness(&["run", "--help"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let help = String::from_utf8_lossy(&o.stdout);
    let flat = help.split_whitespace().collect::<Vec<_>>().join(" ");
    for name in [
        "sk550p,",
        "cu4-pol,",
        "tu3-pnt@pnio,",
        "sk550p@ecat,",
        "tu4-pol@epl,",
        "any@enip,",
        "any@pnio,",
        "tu3-pol@can,",
        "any@can;",
    ] {
        assert!(flat.contains(name), "{name}: {help}");
    }
    for scheme in ["enip://", "ecat://", "epl://", "pnio://", "socketcand://"] {
        assert!(flat.contains(scheme), "{scheme}: {help}");
    }
}

/// The harness binary run in `dir`.
fn harness_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_harness"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("the harness binary runs")
}

#[test]
fn run_from_another_folder_takes_its_suites_or_says_whose_it_takes() {
    let dir = scratch("elsewhere");
    let out = dir.join("out");
    let args = ["run", "--profile", "sk550p", "--out", "out", "-q"];
    // No suites/ here: the build checkout's, with a note naming them.
    let filter = ["--filter", "first-control-command-047eh"];
    let o = harness_in(&dir, &[&args[..], &filter[..]].concat());
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let built = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../suites")
        .canonicalize()
        .unwrap();
    assert!(
        err.contains(&format!(
            "no `suites/` in {}: using the suites of the checkout this harness was built in, {}",
            dir.canonicalize().unwrap().display(),
            built.display()
        )),
        "{err}"
    );
    assert!(out.join("run.json").is_file());
    // A suites/ here is the one run, without a note.
    std::fs::create_dir_all(dir.join("suites/mine")).unwrap();
    std::fs::write(
        dir.join("suites/mine/one.yaml"),
        r#"doc: BU 0620
edition: "2020-03 en"
cases:
  - id: only-here
    title: "A case of this folder's own"
    ref: { section: "6.1.2.1", page: 106 }
    steps:
      - { compute: drive.control, args: { word: "047Eh" }, expect: { parameter_set: 1 } }
"#,
    )
    .unwrap();
    let o = harness_in(&dir, &args);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(!err.contains("suites"), "{err}");
    assert_eq!(cases_in(&out, "id"), ["mine/one/only-here"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn epl_needs_an_address_on_the_powerlink_subnet_before_any_case() {
    if !common::netns::require_root_or_skip("the POWERLINK address checks on a veth pair") {
        return;
    }
    let ns = common::netns::Netns::new("cli-epl");
    let iface = ns.root_if().to_string();
    let out = scratch("epl-address");
    let run = |iface: &str| {
        harness(&[
            "run",
            "--dut",
            &format!("epl://{iface}"),
            "--profile",
            "tu4-pol",
            "--out",
            out.to_str().unwrap(),
        ])
    };
    // No address: refused before any case (no run.json), naming the interface and the way out.
    let o = run(&iface);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "{iface} has no IPv4 address: no address on the POWERLINK subnet"
        )),
        "{err}"
    );
    assert!(
        err.contains(&format!("ip addr add 192.168.100.240/24 dev {iface}")),
        "{err}"
    );
    assert!(!out.join("run.json").exists(), "no run took place");
    // Another subnet's address: named.
    let pid = std::process::id();
    let other = format!("10.231.{}.{}", (pid >> 8) as u8, (pid as u8).clamp(1, 254));
    let ok = Command::new("ip")
        .args(["addr", "add", &format!("{other}/32"), "dev", &iface])
        .status()
        .unwrap();
    assert!(ok.success());
    let o = run(&iface);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!("{iface} has {other}/32: no address")),
        "{err}"
    );
    // `serve epl` on an interface without the node's 192.168.100.N: refused, naming it.
    let o = harness(&[
        "serve",
        "epl",
        "--iface",
        &iface,
        "--node-id",
        "5",
        "--seconds",
        "1",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!(
            "{iface} has {other}/32 but not 192.168.100.5, node 5's address"
        )),
        "{err}"
    );
    // No such interface: said so.
    let o = run("no-such-if0");
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("no network interface `no-such-if0`"),
        "{}",
        stderr(&o)
    );
    let _ = std::fs::remove_dir_all(&out);
}
