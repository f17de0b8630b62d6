//! The `harness` command line: `run` (the default), `list`, `addr`, `decode`.
//!
//! Exit codes: 0 every case passed (or did not apply), 1 a case failed or ended in error,
//! 2 usage or configuration error (bad arguments, a suite file that does not load).

use clap::{Args as ClapArgs, Parser, Subcommand};
use std::path::{Path, PathBuf};

use crate::binding::embedded::EmbeddedFactory;
use crate::outcome::Verdict;
use crate::profile::Profile;
use crate::report::{self, SnapshotMode};
use crate::runner::{self, RunOptions};
use crate::suite;

/// Exit code: every case passed or did not apply.
pub const EXIT_PASS: i32 = 0;
/// Exit code: a case failed or ended in error.
pub const EXIT_FAIL: i32 = 1;
/// Exit code: usage or configuration error.
pub const EXIT_USAGE: i32 = 2;

#[derive(Parser, Debug)]
#[command(
    name = "harness",
    version,
    about = "Conformance and HIL test harness for NORD bus interfaces"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run suites against a DUT (default: every suite against the embedded simulator, once per
    /// built-in profile).
    Run(RunArgs),
    /// List cases with their manual references, or the reference model's functions.
    List(ListArgs),
    /// Every protocol address of a parameter, e.g. `harness addr P102 --inverter 5 --set 3`.
    Addr(crate::cli_tools::AddrArgs),
    /// Decode a telegram or word in the manuals' terms, e.g. `harness decode status 0B31h`.
    Decode(crate::cli_tools::DecodeArgs),
}

#[derive(ClapArgs, Debug, Default)]
struct RunArgs {
    /// Built-in profile(s) to run (default: all): sk550p, tu3-eip, tu4-eip, cu4-eip, tu3-pnt,
    /// tu3-pol, tu4-pol, cu4-pol.
    #[arg(long = "profile")]
    profiles: Vec<String>,
    /// Suites folder.
    #[arg(long)]
    suites: Option<PathBuf>,
    /// Only cases whose id contains this text.
    #[arg(long)]
    filter: Option<String>,
    /// Report folder.
    #[arg(long, default_value = "reports")]
    out: PathBuf,
    /// Inverters behind the simulated interface (default: the product's maximum, 8).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    inverters: Option<u8>,
    /// Bus cycles a parameter order is repeated before the step times out.
    #[arg(long, default_value_t = 250)]
    retries: u32,
    /// Compare every transcript with the stored snapshot; a difference fails the case.
    #[arg(long, conflicts_with = "accept")]
    snapshots: bool,
    /// Store every transcript as the new snapshot.
    #[arg(long)]
    accept: bool,
    /// Snapshot folder.
    #[arg(long, default_value = "vectors/snapshots")]
    snapshot_dir: PathBuf,
}

#[derive(ClapArgs, Debug)]
struct ListArgs {
    /// Suites folder.
    #[arg(long)]
    suites: Option<PathBuf>,
    /// List the reference model's compute functions instead of cases.
    #[arg(long)]
    functions: bool,
}

/// The suites folder: as given, else `suites/` here, else the one beside the sources.
fn suites_dir(given: Option<PathBuf>) -> PathBuf {
    given.unwrap_or_else(|| {
        let here = PathBuf::from("suites");
        if here.is_dir() {
            here
        } else {
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../suites")
        }
    })
}

/// Entry point; returns the process exit code.
pub fn main() -> i32 {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() {
                EXIT_USAGE
            } else {
                EXIT_PASS
            };
            let _ = e.print();
            return code;
        }
    };
    let outcome = match cli.command.unwrap_or(Command::Run(RunArgs {
        out: "reports".into(),
        retries: 250,
        snapshot_dir: "vectors/snapshots".into(),
        ..RunArgs::default()
    })) {
        Command::Run(a) => run(a),
        Command::List(a) => list(a),
        Command::Addr(a) => crate::cli_tools::addr(a),
        Command::Decode(a) => crate::cli_tools::decode(a),
    };
    match outcome {
        Ok(code) => code,
        Err(message) => {
            eprintln!("harness: {message}");
            EXIT_USAGE
        }
    }
}

fn run(a: RunArgs) -> Result<i32, String> {
    let profiles = if a.profiles.is_empty() {
        Profile::all()
    } else {
        a.profiles
            .iter()
            .map(|n| Profile::by_name(n))
            .collect::<Result<_, _>>()?
    };
    let profiles: Vec<Profile> = profiles
        .into_iter()
        .map(|p| Profile {
            inverters: a.inverters.unwrap_or(p.inverters),
            ..p
        })
        .collect();
    let dir = suites_dir(a.suites);
    let loaded = suite::load_dir(&dir).map_err(|e| e.to_string())?;
    let opts = RunOptions {
        profiles,
        filter: a.filter,
        retries: a.retries,
    };
    let mut run = runner::run(&loaded, &opts, &mut EmbeddedFactory);
    let mode = if a.accept {
        SnapshotMode::Accept(a.snapshot_dir)
    } else if a.snapshots {
        SnapshotMode::Compare(a.snapshot_dir)
    } else {
        SnapshotMode::Off
    };
    let snaps = report::apply_snapshots(&mut run, &mode).map_err(|e| e.to_string())?;
    let written = report::write_all(&run, &a.out).map_err(|e| e.to_string())?;
    print!("{}", report::terminal(&run));
    if !matches!(mode, SnapshotMode::Off) {
        println!("{snaps}");
    }
    println!("{written}");
    Ok(if !run.load_errors.is_empty() {
        EXIT_USAGE
    } else if run.count(Verdict::Fail) + run.count(Verdict::Error) > 0 {
        EXIT_FAIL
    } else {
        EXIT_PASS
    })
}

fn list(a: ListArgs) -> Result<i32, String> {
    if a.functions {
        for f in crate::model::registry() {
            println!("{:<28} {}", f.name, f.doc);
        }
        return Ok(EXIT_PASS);
    }
    let loaded = suite::load_dir(&suites_dir(a.suites)).map_err(|e| e.to_string())?;
    for c in &loaded.cases {
        let profiles = c
            .products
            .as_ref()
            .map(|ps| ps.iter().map(|p| p.name()).collect::<Vec<_>>().join(","))
            .unwrap_or_else(|| "all".into());
        println!(
            "{:<64} {} {} §{} p.{} [{}]  {}",
            c.id,
            c.manual.doc,
            c.manual.edition,
            c.manual.section,
            c.manual.page,
            profiles,
            c.title
        );
    }
    for e in &loaded.errors {
        eprintln!("{e}");
    }
    println!("{} cases in {} files", loaded.cases.len(), loaded.files);
    Ok(if loaded.errors.is_empty() {
        EXIT_PASS
    } else {
        EXIT_USAGE
    })
}
