//! Parsing a subcommand's own arguments with clap, for commands whose options belong to one
//! bus (`harness serve <bus> ARGS…`), so a bus's folder need not reach into the CLI.

use crate::exit::{EXIT_PASS, EXIT_USAGE};

/// Parses `args` as the options of the command `name`; `Err` is the exit code when clap
/// printed help, a version or a usage error instead.
pub(crate) fn parse_args<T: clap::Parser>(name: &str, args: &[String]) -> Result<T, i32> {
    T::try_parse_from(std::iter::once(name).chain(args.iter().map(String::as_str))).map_err(|e| {
        let _ = e.print();
        if e.use_stderr() {
            EXIT_USAGE
        } else {
            EXIT_PASS
        }
    })
}
