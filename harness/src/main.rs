//! The `harness` binary: see `harness --help`.

fn main() {
    std::process::exit(harness::cli::main())
}
