//! The `harness` command line: `run` (the default), `list`, `addr`, `decode`, `serve`,
//! `describe`, and `diff`/`merge` over report folders (`crate::cli_reports`). What is a bus's
//! own (`serve <bus>`, `describe <format>`, `--dut <bus>://…`) is found through the bus
//! registry (`crate::bus`).
//!
//! Exit codes: 0 every case passed (or did not apply), 1 a case failed or ended in error,
//! 2 usage or configuration error (bad arguments, a suite file that does not load).

use clap::{Args as ClapArgs, Parser, Subcommand};
use std::path::PathBuf;

use crate::buses::BUSES;
use crate::embedded::EmbeddedFactory;
use crate::exit::verdict_exit;
use crate::profile::{Catalog, Profile};
use crate::progress::Verbosity;
use crate::report::{self, SnapshotMode};
use crate::runner::{self, RunOptions};
use crate::suite;

pub use crate::exit::{EXIT_FAIL, EXIT_PASS, EXIT_USAGE};

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
    /// Serve the simulator on the network as a real device, e.g. `harness serve enip` or
    /// `harness serve ecat --iface veth0`; `harness serve <bus> --help` lists a bus's options.
    Serve(ServeArgs),
    /// Print a device description file, e.g. `harness describe eds --profile tu3-eip` or
    /// `harness describe esi --profile sk550p`.
    Describe(DescribeArgs),
    /// Compare two runs (report folders or run.json files), e.g. two firmware releases: verdict
    /// and transcript changes, new and vanished cases; exit 1 when a case regressed.
    Diff(crate::cli_reports::DiffArgs),
    /// Join the report folders of `run --shard K/N` runs into one unsharded run's reports.
    Merge(crate::cli_reports::MergeArgs),
    /// The manuals' statements per section and how many the cases assert (the inventories in
    /// `suites/inventory/`), and the check that keeps them honest.
    Coverage(crate::cli_reports::CoverageArgs),
    /// The mutation score of the manuals as code: changes one datum the manuals state at a
    /// time (a default, a range, an error number, an abort code, an LED row, a bit, a
    /// formula's constant) and runs the cases that cite it; lists the changes no case notices.
    Mutants(crate::mutants::MutantsArgs),
}

#[derive(ClapArgs, Debug)]
struct DescribeArgs {
    /// What to describe: `eds` (EtherNet/IP electronic data sheet; with `--bus can` the CiA
    /// 306 EDS of an inverter on the NORD system bus), `esi` (EtherCAT slave information),
    /// `xdd` (POWERLINK XML device description), `gsdml` (PROFINET general station
    /// description).
    what: String,
    /// Product profile, e.g. tu3-eip, sk550p.
    #[arg(long)]
    profile: String,
    /// Inverters behind the interface (default: the product's maximum).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    inverters: Option<u8>,
    /// The bus whose description it is, where two write the same format (`eds`: enip, the
    /// default, or can for the NORD system bus).
    #[arg(long)]
    bus: Option<String>,
    /// The inverter a per-node description is of (`eds --bus can`; default FI 1).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    inverter: Option<u8>,
}

#[derive(ClapArgs, Debug)]
struct ServeArgs {
    /// The bus to serve (enip, ecat, epl, pnio), then its own options (`harness serve <bus>
    /// --help`). One list, so that clap hands everything after the bus, `--help` included, to
    /// the bus's own parser.
    #[arg(
        value_name = "BUS",
        required = true,
        trailing_var_arg = true,
        allow_hyphen_values = true
    )]
    words: Vec<String>,
}

#[derive(ClapArgs, Debug, Default)]
struct RunArgs {
    // Its help lists the profile registry's names (`profiles_help`).
    #[arg(long = "profile", value_name = "PROFILE", help = profiles_help())]
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
    /// Transcripts: `one` file (`transcripts.txt`, one section per case), or also `files`, one
    /// per case under `transcripts/`.
    #[arg(long, value_enum, default_value_t)]
    transcripts: report::Transcripts,
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
    // Its help lists the bus registry's URLs (`dut_help`).
    #[arg(long, value_name = "URL", help = dut_help())]
    dut: Option<String>,
    /// The DUT's own device description: its EDS, ESI, XDD or GSDML (told by content). The
    /// harness plans from it what it cannot know of another maker's device: the connection
    /// to open, the modules to connect, the process-data sizes.
    #[arg(long, value_name = "FILE")]
    description: Option<PathBuf>,
    /// Seconds a network DUT may take to answer one request.
    #[arg(long, default_value_t = 2.0)]
    timeout: f64,
    /// The harness's own IP address on the network, for a bus that sends from one: with
    /// `--dut enip://` the scanner's TCP connections come from it and the target sends T→O data
    /// to its UDP 2222 (a host with several interfaces, or several runs at once on one host,
    /// each with its own address). By default the address the routing table picks.
    #[arg(long, requires = "dut")]
    local: Option<std::net::IpAddr>,
    /// The DUT's node id on its bus, the same as the URL's `/N` (`--dut epl://IFACE --node-id
    /// 5`: POWERLINK node 5; `--dut socketcand://HOST/can0 --node-id 5 --profile any`: CANopen
    /// node 5).
    #[arg(long, requires = "dut")]
    node_id: Option<u8>,
    /// How the DUT's SDO travel, the same as the URL's `?sdo=` (POWERLINK: `asnd`, `udp`).
    #[arg(long, requires = "dut")]
    sdo: Option<String>,
    /// Say nothing while running; at the end, a line per suite file that did not load and per
    /// failed or errored case, then the totals.
    #[arg(short, long, conflicts_with = "verbose")]
    quiet: bool,
    /// A line per case-run with its verdict, on stderr.
    #[arg(short, long)]
    verbose: bool,
    /// Write the run's bus traffic to this file as pcapng (whatever its name; each packet's
    /// comment names the profile, case and step that produced it): the embedded simulator's on
    /// its virtual clock, or what was sent to and received from a `--dut` target, with the real
    /// addresses and times.
    #[arg(long)]
    pcap: Option<PathBuf>,
    /// With `--dut`: also watch the bus module's system bus, `socketcand://HOST[:PORT]/CHANNEL`
    /// (a socketcand server on the CAN bus behind the module, or `harness serve enip
    /// --system-bus`) or `can://IFACE` (a CAN adapter of this host on it), so that `observe: {
    /// what: system-bus }` steps assert what the module's gateway put on it.
    #[arg(long, value_name = "URL", requires = "dut")]
    tap: Option<String>,
    /// Run only share K of N of the case-runs (round robin over the unsharded order), for
    /// parallel CI; `harness merge` joins the N report folders.
    #[arg(long, value_name = "K/N")]
    shard: Option<crate::shard::Shard>,
    /// Run each profile's cases in an order shuffled from SEED (recorded in run.json), to find
    /// cases whose verdict depends on the cases before them. The same seed gives the same
    /// order; shards of one run take the same seed.
    #[arg(long, value_name = "SEED")]
    shuffle: Option<u64>,
    /// Against a `--dut`, also run the cases that can make a motor turn: a control word that
    /// enables operation, a setpoint, a fault acknowledgement, a parameter write that can start
    /// the drive (P420…P425, P470, P480, P506, P509, P510), output data the harness cannot
    /// decode. Without it those cases are not applicable, decided before any of their steps
    /// is sent. The embedded simulator has no motor: it runs them all.
    #[arg(long)]
    allow_motion: bool,
    /// Against a `--dut`, the EEPROM writes a run may make, each parameter write counted with
    /// the cleanup's restore of it; a case that would exceed the cap is not applicable. The
    /// manuals allow 100,000 writing cycles (BU 0620 §2.5.6): at the default, a run every
    /// night for ten years stays below. RAM-only orders (`eeprom: false`) do not count. The
    /// embedded simulator has no EEPROM to wear: it is not capped.
    #[arg(long, default_value_t = 20)]
    max_eeprom_writes: u32,
}

/// A `--dut` target with `--node-id` and `--sdo` written into it as the URL spells them
/// (`IFACE/N?sdo=udp`, `HOST:PORT/can0/N`: the node id is the last path segment, which
/// replaces one the URL gave); the bus reads them, or refuses what it does not take.
fn with_options(target: &str, node_id: Option<u8>, sdo: Option<&str>) -> String {
    let (path, query) = target.split_once('?').unwrap_or((target, ""));
    let mut path = path.to_string();
    if let Some(n) = node_id {
        let base = match path.rsplit_once('/') {
            Some((base, last)) if last.parse::<u8>().is_ok() => base,
            _ => path.as_str(),
        };
        path = format!("{base}/{n}");
    }
    let mut query: Vec<String> = query
        .split('&')
        .filter(|q| !q.is_empty() && !(sdo.is_some() && q.starts_with("sdo=")))
        .map(str::to_string)
        .collect();
    if let Some(v) = sdo {
        query.push(format!("sdo={v}"));
    }
    if query.is_empty() {
        path
    } else {
        format!("{path}?{}", query.join("&"))
    }
}

#[derive(ClapArgs, Debug)]
struct ListArgs {
    /// Suites folder.
    #[arg(long)]
    suites: Option<PathBuf>,
    /// List the reference model's compute functions instead of cases.
    #[arg(long)]
    functions: bool,
    /// Only cases whose id contains this text (as `run --filter`).
    #[arg(long)]
    filter: Option<String>,
    /// Only the cases that would run under these profiles (as `run --profile`), each with the
    /// profiles it would run under; the last line counts the case-runs.
    #[arg(long = "profile")]
    profiles: Vec<String>,
}

/// `run --profile`'s help: every built-in profile, from the registry.
fn profiles_help() -> String {
    format!(
        "Built-in profile to run, repeatable (default: every product over PPO and over each bus it speaks): {}; `{}` (any maker's device) with --dut",
        crate::bus::catalog(BUSES).names().join(", "),
        crate::profile::ANY
    )
}

/// `run --dut`'s help: every bus's URL, from the registry.
fn dut_help() -> String {
    format!(
        "The DUT: the embedded simulator (default), or a device or another implementation on the network: {}",
        crate::bus::urls(BUSES)
    )
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
        max_eeprom_writes: 20,
        ..RunArgs::default()
    })) {
        Command::Run(a) => run(a),
        Command::List(a) => list(a),
        Command::Addr(a) => crate::cli_tools::addr(a),
        Command::Decode(a) => crate::cli_tools::decode(a),
        Command::Serve(a) => serve(a),
        Command::Describe(a) => describe(a),
        Command::Diff(a) => crate::cli_reports::diff(a),
        Command::Merge(a) => crate::cli_reports::merge(a),
        Command::Coverage(a) => crate::cli_reports::coverage(a),
        Command::Mutants(a) => crate::mutants::command(a),
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
    let (bus, description) = crate::bus::description(BUSES, &a.what, a.bus.as_deref())?;
    let catalog = crate::bus::catalog(BUSES);
    let profile = catalog.by_name(&a.profile)?;
    let product = profile.nord()?;
    // The writer says so when the product has no such interface.
    let profile = catalog.over(&profile, bus.name).unwrap_or(profile);
    let units = match description.per_inverter {
        true => a.inverter.unwrap_or(1),
        false => a.inverters.unwrap_or(product.max_inverters()),
    };
    let text = (description.write)(&profile, units).map_err(|e| e.to_string())?;
    // A closed pipe (`| head`) ends the output, not the program with a panic.
    let _ = std::io::Write::write_all(&mut std::io::stdout().lock(), text.as_bytes());
    Ok(EXIT_PASS)
}

fn serve(a: ServeArgs) -> Result<i32, String> {
    let (name, args) = a.words.split_first().ok_or("`harness serve` needs a bus")?;
    let bus = crate::bus::by_name(BUSES, name).ok_or_else(|| {
        format!(
            "cannot serve `{name}` (buses: {})",
            crate::bus::names(BUSES)
        )
    })?;
    (bus.serve)(args).map_err(|e| e.to_string())
}

fn run(a: RunArgs) -> Result<i32, String> {
    let catalog = crate::bus::catalog(BUSES);
    let profiles = if a.profiles.is_empty() {
        catalog.all()
    } else {
        chosen_profiles(&catalog, &a.profiles)?
    };
    let profiles: Vec<Profile> = profiles
        .into_iter()
        .map(|mut p| {
            p.inverters = a.inverters.unwrap_or(p.inverters);
            p
        })
        .collect();
    if a.retries == 0 {
        return Err("`--retries 0`: a parameter order needs at least one bus cycle".into());
    }
    if a.out.is_file() {
        return Err(format!(
            "`--out {}` is a file; give the folder the reports go to",
            a.out.display()
        ));
    }
    if a.dut.is_some() && a.profiles.is_empty() {
        return Err(
            "`--dut` needs `--profile`: the product behind the address (e.g. `--profile tu3-eip`, or `any` for any maker's device); every profile against one device would test it as products it is not"
                .into(),
        );
    }
    if let (None, Some(f)) = (&a.dut, &a.description) {
        return Err(format!(
            "`--description {}` describes a device on the network: give it with `--dut URL`",
            f.display()
        ));
    }
    if let (None, Some(p)) = (&a.dut, profiles.iter().find(|p| p.product.is_none())) {
        return Err(format!(
            "profile `{}` stands for any maker's device: give the device with `--dut URL`",
            p.name()
        ));
    }
    let dir = suite::location::suites_or_usage(a.suites)?;
    let loaded =
        suite::load_dir(&dir, &crate::bus::vocabulary(BUSES)).map_err(|e| e.to_string())?;
    let selected = loaded
        .cases
        .iter()
        .filter(|c| a.filter.as_deref().is_none_or(|f| c.id.contains(f)))
        .count();
    if selected == 0 && loaded.errors.is_empty() {
        return Err(match &a.filter {
            Some(f) => format!(
                "no case id contains `{f}` ({} cases in {}; `harness list` shows them)",
                loaded.cases.len(),
                dir.display()
            ),
            None => format!("no case in {}", dir.display()),
        });
    }
    let meta = crate::record::start(&dir, &loaded.digest);
    let verbosity = if a.quiet {
        Verbosity::Quiet
    } else if a.verbose {
        Verbosity::Verbose
    } else {
        Verbosity::Normal
    };
    let tap = a.pcap.as_ref().map(|_| crate::pcap::SharedTap::default());
    let opts = RunOptions {
        filter: a.filter,
        retries: a.retries,
        tap: tap.clone(),
        progress: std::cell::RefCell::new(crate::progress::on_stderr(verbosity)),
        limits: None,
        shuffle: a.shuffle,
        stop: crate::interrupt::flag(),
        ..RunOptions::new(profiles)
    };
    crate::interrupt::install()?;
    let mut run = match &a.dut {
        None => {
            crate::binding::simulator::sim_firmware()?;
            let mut factory = EmbeddedFactory::new(BUSES);
            factory.context.tap = tap.clone();
            runner::run_shard(&loaded, &opts, a.shard, &mut factory)
        }
        Some(url) => {
            let (bus, scheme, target) = crate::bus::by_url(BUSES, url)?;
            if !(0.01..=60.0).contains(&a.timeout) {
                return Err(format!(
                    "`--timeout {}`: give 0.01 to 60 seconds",
                    a.timeout
                ));
            }
            // Each product once, over the DUT's bus.
            let mut profiles: Vec<Profile> = Vec::new();
            for p in opts
                .profiles
                .iter()
                .filter_map(|p| catalog.over(p, bus.name))
            {
                if !profiles.iter().any(|q| q.name() == p.name()) {
                    profiles.push(p);
                }
            }
            let opts = RunOptions {
                profiles,
                limits: Some(crate::safety::Limits {
                    allow_motion: a.allow_motion,
                    max_eeprom_writes: a.max_eeprom_writes,
                }),
                ..opts
            };
            if opts.profiles.is_empty() {
                return Err(format!("none of the profiles speaks {}", bus.title));
            }
            let description = match &a.description {
                None => None,
                Some(path) => {
                    let file = path.display().to_string();
                    let d = crate::description::Description::read(path)
                        .and_then(|d| d.for_bus(bus.name, &file))
                        .map_err(|e| e.to_string())?;
                    outln!("description: {file}, {} of {}", d.format(), d.identity());
                    Some(d)
                }
            };
            let mut factory = (bus.network)(&crate::bus::Network {
                description,
                scheme: scheme.to_string(),
                target: with_options(target, a.node_id, a.sdo.as_deref()),
                local: a.local,
                timeout: std::time::Duration::from_secs_f64(a.timeout),
                tap: tap.clone(),
            })
            .map_err(|e| e.to_string())?;
            if let Some(url) = &a.tap {
                let tap = crate::can::SystemBusTap::connect(
                    url,
                    std::time::Duration::from_secs_f64(a.timeout),
                )?;
                factory = Box::new(crate::can::TapFactory {
                    inner: factory,
                    tap,
                });
            }
            runner::run_shard(&loaded, &opts, a.shard, factory.as_mut())
        }
    };
    // The record of the start, with what the runner found.
    let found = std::mem::take(&mut run.meta);
    run.meta = crate::outcome::RunMeta {
        identities: found.identities,
        motion_allowed: found.motion_allowed,
        eeprom_writes: found.eeprom_writes,
        eeprom_cap: found.eeprom_cap,
        shard: found.shard,
        shuffle: found.shuffle,
        discarded_attempts: found.discarded_attempts,
        interrupted: found.interrupted,
        ..meta
    };
    // What the manuals state and the suites assert (an inventory that does not load is a
    // load error, as a suite file's is).
    match crate::suite::inventory::load(&dir) {
        Ok(inventories) => {
            run.statements = crate::suite::inventory::coverage(&inventories, &loaded);
            run.sections = crate::suite::inventory::sections(&inventories);
        }
        Err(e) => run.load_errors.push(e.to_string()),
    }
    // The score `harness mutants` measured into this report folder.
    run.mutation = crate::mutants::score_in(&a.out)?;
    // Every link is closed by now, its FIN exchange recorded.
    if let (Some(path), Some(tap)) = (&a.pcap, &tap) {
        let tap = tap.borrow();
        tap.capture
            .write(path)
            .map_err(|e| format!("{}: cannot write pcap: {e}", path.display()))?;
        outln!("pcap: {} packets in {}", tap.capture.len(), path.display());
    }
    let mode = if a.accept {
        SnapshotMode::Accept(a.snapshot_dir)
    } else if a.snapshots {
        SnapshotMode::Compare(a.snapshot_dir)
    } else {
        SnapshotMode::Off
    };
    let snaps = report::apply_snapshots(BUSES, &mut run, &mode).map_err(|e| e.to_string())?;
    crate::interrupt::doing(format!("writing the reports into {}", a.out.display()));
    let written = report::write_all(&run, &a.out, a.transcripts).map_err(|e| e.to_string())?;
    if verbosity == Verbosity::Quiet {
        // A line per load error and per failed or errored case, then the totals.
        out!("{}", report::quiet(&run));
    } else {
        out!("{}", report::terminal(&run));
        if !matches!(mode, SnapshotMode::Off) {
            outln!("{snaps}");
        }
        outln!("{written}");
    }
    if let Some(i) = &run.meta.interrupted {
        eprintln!(
            "harness: interrupted: {} case-runs cut short (not judged, cleaned up), {} not run; the reports say so",
            i.cut.len(),
            i.not_run.len()
        );
        return Ok(crate::interrupt::EXIT_INTERRUPTED);
    }
    Ok(verdict_exit(&run))
}

/// The `--profile` profiles, each once in the order given; a repeated one is dropped with a
/// note on stderr (one testsuite per profile in the reports, not two of the same).
fn chosen_profiles(catalog: &Catalog, names: &[String]) -> Result<Vec<Profile>, String> {
    let (chosen, repeated) = catalog.by_names(names)?;
    if !repeated.is_empty() {
        eprintln!(
            "harness: `--profile {}` given again: each profile runs once",
            repeated.join("`, `--profile ")
        );
    }
    Ok(chosen)
}

fn list(a: ListArgs) -> Result<i32, String> {
    if a.functions {
        for f in crate::model::registry() {
            outln!("{:<28} {}", f.name, f.doc);
        }
        return Ok(EXIT_PASS);
    }
    let dir = suite::location::suites_or_usage(a.suites)?;
    let loaded =
        suite::load_dir(&dir, &crate::bus::vocabulary(BUSES)).map_err(|e| e.to_string())?;
    let catalog = crate::bus::catalog(BUSES);
    let mut chosen: Vec<Profile> = Vec::new();
    for p in chosen_profiles(&catalog, &a.profiles)? {
        // `any` names no bus until `--dut` does: listed, it is every bus's generic profile.
        if p.product.is_none() && p.bus.is_none() {
            chosen.extend(BUSES.iter().filter_map(|b| catalog.over(&p, b.name)));
        } else {
            chosen.push(p);
        }
    }
    let (mut listed, mut case_runs) = (0, 0);
    for c in loaded
        .cases
        .iter()
        .filter(|c| a.filter.as_deref().is_none_or(|f| c.id.contains(f)))
    {
        let profiles = if chosen.is_empty() {
            c.products
                .as_ref()
                .map(|ps| ps.iter().map(|p| p.name()).collect::<Vec<_>>().join(","))
                .unwrap_or_else(|| "all".into())
        } else {
            let under: Vec<&str> = chosen
                .iter()
                .filter(|p| runner::not_applicable_before_opening(c, p).is_none())
                .map(|p| p.name())
                .collect();
            if under.is_empty() {
                continue;
            }
            case_runs += under.len();
            under.join(",")
        };
        listed += 1;
        outln!(
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
    if chosen.is_empty() {
        outln!(
            "{listed} of {} cases in {} files",
            loaded.cases.len(),
            loaded.files
        );
    } else {
        outln!(
            "{listed} of {} cases in {} files; {case_runs} case-runs under {} profiles (a DUT may still find some not applicable)",
            loaded.cases.len(),
            loaded.files,
            chosen.len()
        );
    }
    Ok(if loaded.errors.is_empty() {
        EXIT_PASS
    } else {
        EXIT_USAGE
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    /// `harness run --help` as clap prints it.
    fn run_help() -> String {
        let mut cli = Cli::command();
        let run = cli.find_subcommand_mut("run").expect("a run command");
        run.render_long_help().to_string()
    }

    #[test]
    fn run_help_names_every_profile_and_every_bus_url() {
        let help = run_help();
        // Wrapped lines joined, so a name is found whatever the terminal width.
        let flat = help.split_whitespace().collect::<Vec<_>>().join(" ");
        let names = crate::bus::catalog(BUSES).names();
        assert!(names.len() >= 19, "{names:?}");
        for name in &names {
            assert!(
                flat.contains(&format!(" {name},")) || flat.contains(&format!(" {name};")),
                "{name} missing from run --help:\n{help}"
            );
        }
        for bus in BUSES {
            assert!(flat.contains(bus.url), "{} missing:\n{help}", bus.url);
        }
        assert!(flat.contains("pnio://IFACE"), "{help}");
    }

    #[test]
    fn node_id_and_sdo_go_into_the_target_as_the_url_spells_them() {
        assert_eq!(with_options("veth0", None, None), "veth0");
        assert_eq!(
            with_options("veth0", Some(5), Some("udp")),
            "veth0/5?sdo=udp"
        );
        assert_eq!(
            with_options("veth0/3?cycle=400us", Some(5), None),
            "veth0/5?cycle=400us"
        );
        assert_eq!(
            with_options("veth0?sdo=asnd&cycle=1ms", None, Some("udp")),
            "veth0?cycle=1ms&sdo=udp"
        );
        // The system bus keeps its channel: the node id follows it.
        assert_eq!(
            with_options("127.0.0.1:29536/can0", Some(5), None),
            "127.0.0.1:29536/can0/5"
        );
        assert_eq!(with_options("can0/3", Some(5), None), "can0/5");
    }
}
