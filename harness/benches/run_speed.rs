//! Prints how fast the default run goes, two ways. **One operation is one case-run**: one case
//! under one profile against the embedded simulator, opened, its steps run and judged (a model
//! case's compute steps alone), as `harness run` counts them.
//!
//! - without reports: the run in this process, no report written;
//! - with reports: the README's command, `harness run` as a user starts it (the built binary,
//!   its suites loaded, every profile run, the reports written into a folder an earlier run
//!   wrote), wall clock from start to exit of each run: back to back, and after a pause of
//!   five seconds, as a user meets it (on a VM whose host takes back free memory, a process's
//!   fresh pages then cost more).
//!
//! `cargo bench -p harness --bench run_speed`. A bench, not a timed test: it prints figures and
//! asserts nothing about time.

use std::process::Command;
use std::time::{Duration, Instant};

/// The binary's allocator, so the run in this process goes as `harness run` does.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    let suites = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../suites");
    let rounds = 5;
    let mut cases = 0usize;
    let start = Instant::now();
    for _ in 0..rounds {
        let run = harness::run_embedded(&suites).expect("suites load");
        cases += run.cases.len();
    }
    let secs = start.elapsed().as_secs_f64();
    let per_run = cases / rounds;
    println!(
        "default run without reports: {per_run} cases x {rounds} rounds in {secs:.3} s = {:.0} cases/s, {:.1} ms per full run",
        cases as f64 / secs,
        secs * 1000.0 / rounds as f64
    );

    let out = std::env::temp_dir().join(format!("nord-run-speed-{}", std::process::id()));
    let run = || {
        let status = Command::new(env!("CARGO_BIN_EXE_harness"))
            .args(["run", "-q", "--suites"])
            .arg(&suites)
            .arg("--out")
            .arg(&out)
            .stdout(std::process::Stdio::null())
            .status()
            .expect("harness starts");
        assert!(status.success(), "the default run fails: {status}");
    };
    // The folder an earlier run wrote, as the README's run meets it the second time.
    run();
    let timed = |pause: Duration| {
        let mut secs: Vec<f64> = (0..rounds)
            .map(|_| {
                std::thread::sleep(pause);
                let start = Instant::now();
                run();
                start.elapsed().as_secs_f64()
            })
            .collect();
        secs.sort_by(f64::total_cmp);
        secs
    };
    for (how, pause) in [
        ("back to back", Duration::ZERO),
        ("each after a 5 s pause", Duration::from_secs(5)),
    ] {
        let secs = timed(pause);
        let median = secs[secs.len() / 2];
        println!(
            "default run with reports (`harness run`, wall clock, {how}): {per_run} cases, {rounds} runs: median {:.0} ms ({:.0} cases/s), fastest {:.0} ms, slowest {:.0} ms",
            median * 1000.0,
            per_run as f64 / median,
            secs[0] * 1000.0,
            secs[secs.len() - 1] * 1000.0
        );
    }
    let _ = std::fs::remove_dir_all(&out);
}
