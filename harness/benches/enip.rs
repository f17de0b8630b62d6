//! Prints EtherNet/IP speed over loopback: round trips per second of the harness scanner and of
//! pycomm3 against the served simulator, the simulator's throughput with 8 concurrent clients,
//! and the jitter of a 96-byte I/O connection at RPI 1 ms (see `harness::bench`).
//!
//! `cargo bench -p harness --bench enip`. A bench, not a timed test: it prints figures and
//! whether each target was met, and asserts nothing about time. About 20 s.

fn main() {
    let script =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/interop/pycomm3_bench.py");
    let settings = harness::bench::Settings::new(script);
    if let Err(e) = harness::bench::run_enip(&settings) {
        eprintln!("EtherNet/IP bench could not run: {e}");
        std::process::exit(1);
    }
}
