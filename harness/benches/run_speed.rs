//! Prints how fast the default run goes, two ways. **One operation is one case-run**: one case
//! under one profile against the embedded simulator, opened, its steps run and judged (a model
//! case's compute steps alone), as `harness run` counts them.
//!
//! - without reports: the run in this process, no report written;
//! - with reports: the README's command, `harness run` as a user starts it (the built binary,
//!   its suites loaded, every profile run, the reports written into a folder an earlier run
//!   wrote), wall clock from start to exit.
//!
//! `cargo bench -p harness --bench run_speed`. A bench, not a timed test: it prints figures and
//! asserts nothing about time.

use std::process::Command;
use std::time::Instant;

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
    let start = Instant::now();
    for _ in 0..rounds {
        run();
    }
    let secs = start.elapsed().as_secs_f64();
    let _ = std::fs::remove_dir_all(&out);
    println!(
        "default run with reports (`harness run`, wall clock): {per_run} cases x {rounds} rounds in {secs:.3} s = {:.0} cases/s, {:.1} ms per run",
        (per_run * rounds) as f64 / secs,
        secs * 1000.0 / rounds as f64
    );
}
