//! The `harness` binary: see `harness --help`.

/// mimalloc rather than the system allocator: a run makes and drops millions of small
/// frames and strings on two or more threads at once, where glibc's malloc spends a fifth
/// of the run (measured with perf; see the README's speed paragraph).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    std::process::exit(harness::cli::main())
}
