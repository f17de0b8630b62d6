//! Prints how fast the default run goes: cases per second of the full embedded run. **One
//! operation is one case-run**: one case under one profile against the embedded simulator,
//! opened, its steps run and judged (a model case's compute steps alone), as `harness run`
//! counts them; no reports are written.
//!
//! `cargo bench -p harness --bench run_speed`. A bench, not a timed test: it prints figures and
//! asserts nothing about time.

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
    println!(
        "default run: {} cases x {rounds} rounds in {secs:.3} s = {:.0} cases/s, {:.1} ms per full run",
        cases / rounds,
        cases as f64 / secs,
        secs * 1000.0 / rounds as f64
    );
}
