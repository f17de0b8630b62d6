//! The `harness` binary: see `harness --help`.

/// mimalloc rather than the system allocator: a run makes and drops millions of small
/// frames and strings on two or more threads at once, where glibc's malloc spends a fifth
/// of the run (measured with perf; see the README's speed paragraph).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() {
    // No transparent huge pages: a run's memory is touched once, and a fresh 2 MB page costs
    // its zeroing in full however little of it is used. On a VM whose host has taken back the
    // guest's free memory that was a third of a default run's time (0.5 s of system time
    // after a pause, against 0.1 s without). Nothing is lost where the call is refused.
    #[cfg(target_os = "linux")]
    let _ = nix::sys::prctl::set_thp_disable(true);
    std::process::exit(harness::cli::main())
}
