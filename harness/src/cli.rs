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
    /// Serve the simulator on the network as a real device, e.g. `harness serve enip`.
    Serve(ServeArgs),
    /// Print a device description file, e.g. `harness describe eds --profile tu3-eip`.
    Describe(DescribeArgs),
}

#[derive(ClapArgs, Debug)]
struct DescribeArgs {
    /// What to describe: `eds` (EtherNet/IP electronic data sheet).
    what: String,
    /// Product profile: sk550p, tu3-eip, tu4-eip, cu4-eip.
    #[arg(long)]
    profile: String,
    /// Inverters behind the interface (default: the product's maximum).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    inverters: Option<u8>,
}

#[derive(ClapArgs, Debug)]
struct ServeArgs {
    /// Protocol to serve: `enip` (EtherNet/IP adapter).
    protocol: String,
    /// Listen address, HOST[:PORT] (UDP 2222 on the same host carries I/O).
    #[arg(long, default_value = "127.0.0.2:44818")]
    listen: String,
    /// Product profile: sk550p, tu3-eip, tu4-eip, cu4-eip.
    #[arg(long, default_value = "tu3-eip")]
    profile: String,
    /// Inverters behind the interface (default: the product's maximum).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    inverters: Option<u8>,
    /// Stop after this many seconds (default: serve until killed).
    #[arg(long)]
    seconds: Option<u64>,
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
    /// The DUT: the embedded simulator (default) or `enip://HOST[:PORT]`, an EtherNet/IP
    /// device or another implementation on the network.
    #[arg(long)]
    dut: Option<String>,
    /// Seconds a network DUT may take to answer one request.
    #[arg(long, default_value_t = 2.0)]
    timeout: f64,
    /// The scanner's own IP address for `--dut enip://`: its TCP connections come from it and
    /// the target sends T→O data to its UDP 2222 (a host with several interfaces, or several
    /// runs at once on one host, each with its own address). By default the address the
    /// routing table picks.
    #[arg(long, requires = "dut")]
    local: Option<std::net::IpAddr>,
    /// Write the run's EtherNet/IP traffic to this file as pcapng (whatever its name; each
    /// packet's comment names the profile, case and step that produced it): the embedded
    /// simulator's on its virtual clock, or what was sent to and received from a
    /// `--dut enip://` target, with the real addresses and times (IPv4 only).
    #[arg(long)]
    pcap: Option<PathBuf>,
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
        Command::Serve(a) => serve(a),
        Command::Describe(a) => describe(a),
    };
    match outcome {
        Ok(code) => code,
        Err(message) => {
            eprintln!("harness: {message}");
            EXIT_USAGE
        }
    }
}

fn describe(a: DescribeArgs) -> Result<i32, String> {
    if a.what != "eds" {
        return Err(format!("cannot describe `{}` (known: eds)", a.what));
    }
    let product = Profile::by_name(&a.profile)?.nord()?;
    let text = crate::eds::eds(product, a.inverters.unwrap_or(product.max_inverters()))?;
    // A closed pipe (`| head`) ends the output, not the program with a panic.
    let _ = std::io::Write::write_all(&mut std::io::stdout().lock(), text.as_bytes());
    Ok(EXIT_PASS)
}

fn serve(a: ServeArgs) -> Result<i32, String> {
    if a.protocol != "enip" {
        return Err(format!("cannot serve `{}` (protocols: enip)", a.protocol));
    }
    let product = Profile::by_name(&a.profile)?.nord()?;
    if proto::nord::eip::identity(product).is_none() {
        return Err(format!("{} has no EtherNet/IP interface", product.name()));
    }
    let config = sim::device::DeviceConfig {
        inverters: a
            .inverters
            .unwrap_or(product.max_inverters())
            .min(product.max_inverters()),
        ..sim::device::DeviceConfig::new(product)
    };
    let listen = crate::serve::parse_addr(&a.listen)?;
    crate::serve::serve_enip(
        listen,
        config,
        a.seconds.map(std::time::Duration::from_secs),
    )?;
    Ok(EXIT_PASS)
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
    let tap = a.pcap.as_ref().map(|_| crate::pcap::SharedTap::default());
    let opts = RunOptions {
        profiles,
        filter: a.filter,
        retries: a.retries,
        tap: tap.clone(),
    };
    let mut run = match &a.dut {
        None => {
            let mut factory = EmbeddedFactory { tap: tap.clone() };
            runner::run(&loaded, &opts, &mut factory)
        }
        Some(url) => {
            let target = url
                .strip_prefix("enip://")
                .ok_or_else(|| format!("`--dut {url}`: only enip://HOST[:PORT] is supported"))
                .and_then(crate::serve::parse_addr)?;
            if tap.is_some() && !target.is_ipv4() {
                return Err(format!(
                    "`--pcap` with `--dut {url}`: a pcap records IPv4 only"
                ));
            }
            if !(0.01..=60.0).contains(&a.timeout) {
                return Err(format!(
                    "`--timeout {}`: give 0.01 to 60 seconds",
                    a.timeout
                ));
            }
            let opts = RunOptions {
                profiles: opts
                    .profiles
                    .iter()
                    .filter_map(|p| match p.product {
                        Some(product) => Profile::enip(product),
                        None => Some(p.clone()),
                    })
                    .collect(),
                ..opts
            };
            if opts.profiles.is_empty() {
                return Err("none of the profiles speaks EtherNet/IP".into());
            }
            let mut factory = crate::binding::enip::NetworkFactory {
                target,
                local: a.local,
                timeout: std::time::Duration::from_secs_f64(a.timeout),
                tap: tap.clone(),
                clock: std::rc::Rc::new(sim::clock::RealClock::new()),
            };
            runner::run(&loaded, &opts, &mut factory)
        }
    };
    // Every link is closed by now, its FIN exchange recorded.
    if let (Some(path), Some(tap)) = (&a.pcap, &tap) {
        let tap = tap.borrow();
        tap.capture
            .write(path)
            .map_err(|e| format!("{}: cannot write pcap: {e}", path.display()))?;
        println!("pcap: {} packets in {}", tap.capture.len(), path.display());
    }
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
            "{:<64} {} {} {} [{}]  {}",
            c.id,
            c.manual.doc,
            c.manual.edition,
            c.manual.place(),
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
