//! The tester side: suites, bindings, runner, reports and the `harness` CLI.

/// `print!`/`println!` for what the CLI writes to stdout, ignoring a closed stdout: a reader
/// that stopped reading (`harness list | head`) has what it wanted, and the harness goes on
/// quietly instead of panicking on the broken pipe.
macro_rules! out {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = write!(std::io::stdout().lock(), $($t)*);
    }};
}
macro_rules! outln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        let _ = writeln!(std::io::stdout().lock(), $($t)*);
    }};
}

mod args;
mod binding;
mod bus;
mod buses;
mod can;
pub mod cli;
mod cli_reports;
mod cli_tools;

mod description;
mod dictionary;
mod ecat;
mod effect;
mod embedded;
/// What the system-bus speed bench (`harness/benches/can/`) needs of the library.
pub use can::bench_support as can_bench;
/// What the EtherCAT speed bench (`harness/benches/ecat/`) needs of the library.
pub use ecat::bench_support as ecat_bench;
/// `harness serve ecat` in a thread of the caller (EtherCAT end-to-end tests and benches).
pub use ecat::serve as ecat_serve;
pub use epl::bench_support as epl_bench;
pub use epl::serve as epl_serve;
/// What the PROFINET speed bench (`harness/benches/pnio/`) needs of the library: the harness
/// IO controller in data exchange, reading a data record and stamping the input CR's frames.
pub use pnio::bench_support as pnio_bench;
/// `harness serve pnio` in a thread of the caller (PROFINET end-to-end tests and benches).
pub use pnio::serve as pnio_serve;
mod enip;
mod epl;
mod exit;
/// The suite loader and description readers for the fuzz targets (`fuzz/`).
pub mod fuzz_support;
/// What the EtherNet/IP speed bench (`harness/benches/enip/`) needs of the library: the
/// simulator served as an adapter, the harness scanner reading a parameter.
pub use enip::bench_support as enip_bench;
mod hex;
mod identity;
mod interrupt;
mod model;
mod mutants;
mod net;
pub use net::misbehave;
mod notation;
pub mod outcome;
mod pcap;
mod pnio;
pub mod poll;
mod profile;
mod progress;
mod record;
mod report;
mod runner;
mod safety;
pub mod shard;
pub mod stats;
mod suite;
mod timing;

/// Runs every suite below `suites` against the embedded simulator under every built-in profile
/// (the default job, without writing reports). Used by the bench.
pub fn run_embedded(suites: &std::path::Path) -> Result<outcome::RunResult, String> {
    let loaded =
        suite::load_dir(suites, &bus::vocabulary(buses::BUSES)).map_err(|e| e.to_string())?;
    let opts = runner::RunOptions::new(bus::catalog(buses::BUSES).all());
    Ok(runner::run(
        &loaded,
        &opts,
        &mut crate::embedded::EmbeddedFactory::new(crate::buses::BUSES),
    ))
}
