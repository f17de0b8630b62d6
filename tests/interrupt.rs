//! Ctrl-C in the middle of a run against a device on the network (the simulator served by
//! `harness serve enip` on a loopback address of the test's own): the run ends with exit 130
//! and reports marked interrupted, the case under way cleaned up, and the next run against the
//! same device finds it as a case expects it (no fault left, no connection held, voltage off).
//! Before, an interrupted run wrote nothing and the next one failed
//! `shut-down-from-switched-on-transition-6` with 0B38h (fault).

#[allow(dead_code)] // what the other network tests share
mod common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::addr::free_loopback;
use common::serve;

/// `harness run` of the tu3-eip profile's cases containing `filter` against `dut`, motion
/// allowed, reports into `out`.
fn run_against(dut: &str, filter: &str, out: &Path) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_harness"));
    c.args([
        "run",
        "--dut",
        dut,
        "--profile",
        "tu3-eip",
        "--allow-motion",
    ])
    .args(["--filter", filter, "-q", "--out"])
    .arg(out);
    c
}

fn run_json(out: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(out.join("run.json")).expect("run.json written");
    serde_json::from_str(&text).expect("run.json parses")
}

#[test]
fn ctrl_c_cleans_up_writes_interrupted_reports_and_leaves_the_device_ready() {
    let ip = free_loopback();
    let listen = format!("{ip}:44818");
    let _server = serve(&listen, "tu3-eip", 600);
    let out = std::env::temp_dir().join(format!("harness-interrupt-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let dut = format!("enip://{ip}");

    // The drive cases run their process data for seconds of real time each: three seconds in,
    // one is under way and most have not started.
    let mut child = run_against(&dut, "drive-switching", &out)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("harness run starts");
    std::thread::sleep(Duration::from_secs(3));
    assert!(
        child.try_wait().expect("wait").is_none(),
        "the run ended before the signal: the test needs a longer one"
    );
    let pid = nix::unistd::Pid::from_raw(i32::try_from(child.id()).expect("pid"));
    nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGINT).expect("SIGINT sent");
    let deadline = Instant::now() + Duration::from_secs(60);
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait") {
            break s;
        }
        assert!(Instant::now() < deadline, "no exit within 60 s of SIGINT");
        std::thread::sleep(Duration::from_millis(50));
    };
    let stderr = std::io::read_to_string(child.stderr.take().expect("stderr")).unwrap_or_default();
    assert_eq!(status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("SIGINT: stopping after the step under way"),
        "{stderr}"
    );

    let run = run_json(&out);
    let interrupted = &run["meta"]["interrupted"];
    let not_run = interrupted["not_run"].as_array().expect("not_run listed");
    assert!(!not_run.is_empty(), "{interrupted}");
    let cut = interrupted["cut"].as_array().expect("cut listed");
    for c in run["cases"].as_array().expect("cases") {
        let named = format!(
            "{} {}",
            c["profile"].as_str().unwrap(),
            c["id"].as_str().unwrap()
        );
        assert!(
            !not_run.iter().any(|n| n == named.as_str()),
            "{named} ran and is listed as not run"
        );
        if cut.iter().any(|n| n == named.as_str()) {
            assert_eq!(c["verdict"], "inconclusive", "{c}");
        } else {
            assert_ne!(c["verdict"], "error", "a case before the signal erred: {c}");
        }
    }
    let summary = std::fs::read_to_string(out.join("summary.md")).expect("summary.md");
    assert!(
        summary.starts_with("**INTERRUPTED: stopped by a signal"),
        "{}",
        &summary[..200.min(summary.len())]
    );
    assert!(summary.contains("interrupted"), "the record says so");

    // The next run finds the device as the manuals' cases expect it.
    let next = out.join("next");
    let o = run_against(&dut, "shut-down-from-switched-on-transition-6", &next)
        .output()
        .expect("harness run");
    let run = run_json(&next);
    let case = &run["cases"][0];
    assert_eq!(
        (o.status.code(), case["verdict"].as_str()),
        (Some(0), Some("pass")),
        "{case}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let _ = std::fs::remove_dir_all(&out);
}
