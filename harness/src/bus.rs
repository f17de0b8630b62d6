//! What a bus provides the shared code: one [`Bus`] entry per `harness/src/<bus>/` folder.
//!
//! The runner, the suite loader and the reports reach a bus through its entry: its profiles
//! (`sk550p@ecat`), the suite steps written under its key (`ecat:`), the binding that opens the
//! embedded simulator or a DUT given by URL (`--dut ecat://IFACE`), its `serve` command and its
//! device-description writers. The list of the entries is `crate::buses`, read by the CLI
//! alone and handed down as `&[&Bus]`; the functions here look a bus up in such a list.
//! Adding a bus adds a folder and a line to that list.

use std::fmt;
use std::net::IpAddr;
use std::time::Duration;

use crate::binding::{Binding, DutFactory, OpenError};
use crate::dictionary::DescribeError;
use crate::pcap::SharedTap;
use crate::profile::{Catalog, Profile};
use crate::suite::{ParseStep, Vocabulary};

impl fmt::Debug for Bus {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Bus({})", self.name)
    }
}

impl fmt::Debug for Description {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Description({})", self.format)
    }
}

/// A bus: what the shared code may ask of it.
pub(crate) struct Bus {
    /// Its name in profile names (`sk550p@enip`), suite step keys (`enip:`), URL schemes
    /// (`enip://`) and the `serve` command.
    pub(crate) name: &'static str,
    /// As people write it (`EtherNet/IP`).
    pub(crate) title: &'static str,
    /// How `--dut` names a device of the bus (`ecat://IFACE`), for help and messages.
    pub(crate) url: &'static str,
    /// URL schemes besides its name that reach it (`socketcand://` the system bus through a
    /// socketcand server).
    pub(crate) schemes: &'static [&'static str],
    /// Its NORD profiles: the products speaking it. Its generic profile (`any@<bus>`, any
    /// maker's device, `--dut` only) is added by [`Profile`].
    pub(crate) profiles: fn() -> Vec<Profile>,
    /// Parses a suite step written under the bus's key; the error says what is wrong.
    pub(crate) parse_step: ParseStep,
    /// Opens the embedded simulator for one case, behind the bus's binding.
    pub(crate) embedded: fn(&Profile, &Embedded) -> Result<Box<dyn Binding>, OpenError>,
    /// Reaches a DUT given as `<name>://<target>`.
    pub(crate) network: fn(&Network) -> Result<Box<dyn DutFactory>, OpenError>,
    /// `harness serve <name> ARGS…`: serves the simulator as a device on the network; the
    /// arguments are the bus's own. Returns the process exit code.
    pub(crate) serve: fn(&[String]) -> Result<i32, crate::net::serve_error::ServeError>,
    /// Device descriptions it writes: `harness describe <format>`.
    pub(crate) descriptions: &'static [Description],
    /// What in its frames a device picks anew each run, masked when transcripts are compared.
    pub(crate) variable: Variable,
}

/// The parts of a bus's frames whose values a device picks for each session, connection or
/// start (a session handle, a connection id, a sequence number): two runs against the same
/// device differ there, so `--snapshots` and `harness diff` compare them masked.
#[derive(Clone, Copy)]
pub(crate) struct Variable {
    /// The byte ranges of one frame (as a transcript shows it) that vary.
    pub(crate) bytes: fn(&[u8]) -> Vec<std::ops::Range<usize>>,
    /// One decoded line of a frame, what varies in it masked.
    pub(crate) decoded: fn(&str) -> String,
}

impl Variable {
    /// A bus whose frames hold nothing a device picks per run: the EtherCAT master and the
    /// POWERLINK MN choose every index and address of a case themselves.
    pub(crate) const NONE: Variable = Variable {
        bytes: |_| Vec::new(),
        decoded: str::to_string,
    };
}

/// A device-description file a bus writes.
pub(crate) struct Description {
    /// Format name on the command line (`eds`, `esi`).
    pub(crate) format: &'static str,
    /// Writes it for a product profile of the bus with `inverters` inverters, or, for a
    /// description of one node per inverter ([`Description::per_inverter`]), of that inverter.
    pub(crate) write: fn(&Profile, u8) -> Result<String, DescribeError>,
    /// Describes one inverter (a node of the system bus), not the interface with all of them.
    pub(crate) per_inverter: bool,
}

/// What opening the embedded simulator may use.
#[derive(Default)]
pub(crate) struct Embedded {
    /// Where `--pcap` collects the run's frames.
    pub(crate) tap: Option<SharedTap>,
}

/// A DUT on the network, as the command line gives it.
pub(crate) struct Network {
    /// The URL's scheme: the bus's name or one of its [`Bus::schemes`].
    pub(crate) scheme: String,
    /// What follows `<scheme>://`: a host, an interface name…
    pub(crate) target: String,
    /// The harness's own address, where a bus sends from (`--local`).
    pub(crate) local: Option<IpAddr>,
    /// How long one request may take.
    pub(crate) timeout: Duration,
    /// Where `--pcap` collects the run's frames.
    pub(crate) tap: Option<SharedTap>,
    /// The device's own description (`--description`), one of this bus's.
    pub(crate) description: Option<crate::description::Description>,
}

/// The profiles and capabilities of `buses`.
pub(crate) fn catalog(buses: &[&Bus]) -> Catalog {
    Catalog::new(buses.iter().map(|b| (b.name, (b.profiles)())))
}

/// What the suite loader must know of `buses`: their profiles, capabilities and step parsers.
pub(crate) fn vocabulary(buses: &[&Bus]) -> Vocabulary {
    Vocabulary {
        catalog: catalog(buses),
        steps: buses.iter().map(|b| (b.name, b.parse_step)).collect(),
    }
}

/// The bus of that name.
pub(crate) fn by_name<'a>(buses: &[&'a Bus], name: &str) -> Option<&'a Bus> {
    buses.iter().copied().find(|b| b.name == name)
}

/// The bus names, for messages.
pub(crate) fn names(buses: &[&Bus]) -> String {
    let v: Vec<&str> = buses.iter().map(|b| b.name).collect();
    v.join(", ")
}

/// Every bus's `--dut` URL with its title (`enip://HOST[:PORT] (EtherNet/IP), …`), for help.
pub(crate) fn urls(buses: &[&Bus]) -> String {
    let v: Vec<String> = buses
        .iter()
        .map(|b| format!("{} ({})", b.url, b.title))
        .collect();
    v.join(", ")
}

/// The bus, scheme and target of a `--dut` URL (`ecat://veth0`).
pub(crate) fn by_url<'a, 'u>(
    buses: &[&'a Bus],
    url: &'u str,
) -> Result<(&'a Bus, &'u str, &'u str), String> {
    let schemes = || {
        let v: Vec<String> = buses
            .iter()
            .flat_map(|b| std::iter::once(b.name).chain(b.schemes.iter().copied()))
            .map(|s| format!("{s}://"))
            .collect();
        v.join(", ")
    };
    let (scheme, target) = url
        .split_once("://")
        .ok_or_else(|| format!("`--dut {url}`: give a URL ({})", schemes()))?;
    let bus = buses
        .iter()
        .copied()
        .find(|b| b.name == scheme || b.schemes.contains(&scheme));
    let bus = bus.ok_or_else(|| {
        format!(
            "`--dut {url}`: unknown scheme `{scheme}://` ({})",
            schemes()
        )
    })?;
    if target.is_empty() {
        return Err(format!("`--dut {url}`: nothing after `{scheme}://`"));
    }
    Ok((bus, scheme, target))
}

/// The description writer for `format`, with its bus: of the bus `bus` names, else of the
/// first bus that writes one (`eds`: EtherNet/IP's; `--bus can` the system bus's).
pub(crate) fn description<'a>(
    buses: &[&'a Bus],
    format: &str,
    bus: Option<&str>,
) -> Result<(&'a Bus, &'a Description), String> {
    buses
        .iter()
        .filter(|b| bus.is_none_or(|name| b.name == name))
        .flat_map(|b| b.descriptions.iter().map(move |d| (*b, d)))
        .find(|(_, d)| d.format == format)
        .ok_or_else(|| {
            let known: Vec<String> = buses
                .iter()
                .flat_map(|b| {
                    b.descriptions
                        .iter()
                        .map(move |d| format!("{} ({})", d.format, b.name))
                })
                .collect();
            format!("cannot describe `{format}` (known: {})", known.join(", "))
        })
}
