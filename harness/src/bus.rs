//! The buses the harness speaks, one entry per `harness/src/<bus>/` folder.
//!
//! This registry is the only shared place that names a bus. The runner, the suite loader and
//! the reports reach a bus through its entry: its profiles (`sk550p@ecat`), the suite steps
//! written under its key (`ecat:`), the binding that opens the embedded simulator or a DUT
//! given by URL (`--dut ecat://IFACE`), its `serve` command and its device-description writers.
//! Adding a bus adds a folder and a line to [`BUSES`].

use crate::suite::BusStep;
use serde_json::Value;
use std::fmt;
use std::net::IpAddr;
use std::time::Duration;

use crate::binding::DutFactory;
use crate::binding::{Binding, OpenError};
use crate::pcap::SharedTap;
use crate::profile::Profile;

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

/// Every bus, in report order.
pub(crate) const BUSES: &[&Bus] = &[
    &crate::enip::BUS,
    &crate::ecat::BUS,
    &crate::epl::BUS,
    &crate::pnio::BUS,
    &crate::can::BUS,
];

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
    pub(crate) parse_step: fn(&Value) -> Result<Box<dyn BusStep>, String>,
    /// Opens the embedded simulator for one case, behind the bus's binding.
    pub(crate) embedded: fn(&Profile, &Embedded) -> Result<Box<dyn Binding>, OpenError>,
    /// Reaches a DUT given as `<name>://<target>`.
    pub(crate) network: fn(&Network) -> Result<Box<dyn DutFactory>, OpenError>,
    /// `harness serve <name> ARGS…`: serves the simulator as a device on the network; the
    /// arguments are the bus's own. Returns the process exit code.
    pub(crate) serve: fn(&[String]) -> Result<i32, String>,
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
    pub(crate) write: fn(&Profile, u8) -> Result<String, String>,
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

/// The bus of that name.
pub(crate) fn by_name(name: &str) -> Option<&'static Bus> {
    BUSES.iter().copied().find(|b| b.name == name)
}

/// The bus names, for messages.
pub(crate) fn names() -> String {
    let v: Vec<&str> = BUSES.iter().map(|b| b.name).collect();
    v.join(", ")
}

/// Every bus's `--dut` URL with its title (`enip://HOST[:PORT] (EtherNet/IP), …`), for help.
pub(crate) fn urls() -> String {
    let v: Vec<String> = BUSES
        .iter()
        .map(|b| format!("{} ({})", b.url, b.title))
        .collect();
    v.join(", ")
}

/// The bus, scheme and target of a `--dut` URL (`ecat://veth0`).
pub(crate) fn by_url(url: &str) -> Result<(&'static Bus, &str, &str), String> {
    let schemes = || {
        let v: Vec<String> = BUSES
            .iter()
            .flat_map(|b| std::iter::once(b.name).chain(b.schemes.iter().copied()))
            .map(|s| format!("{s}://"))
            .collect();
        v.join(", ")
    };
    let (scheme, target) = url
        .split_once("://")
        .ok_or_else(|| format!("`--dut {url}`: give a URL ({})", schemes()))?;
    let bus = BUSES
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
pub(crate) fn description(
    format: &str,
    bus: Option<&str>,
) -> Result<(&'static Bus, &'static Description), String> {
    BUSES
        .iter()
        .filter(|b| bus.is_none_or(|name| b.name == name))
        .flat_map(|b| b.descriptions.iter().map(move |d| (*b, d)))
        .find(|(_, d)| d.format == format)
        .ok_or_else(|| {
            let known: Vec<String> = BUSES
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_urls_resolve_through_the_registry() {
        assert_eq!(by_name("enip").map(|b| b.title), Some("EtherNet/IP"));
        assert_eq!(by_name("ecat").map(|b| b.title), Some("EtherCAT"));
        let (bus, _, target) = by_url("ecat://veth0").unwrap();
        assert_eq!((bus.name, target), ("ecat", "veth0"));
        assert!(by_url("ecat://").unwrap_err().contains("nothing after"));
        let (bus, scheme, target) = by_url("socketcand://127.0.0.1/can0").unwrap();
        assert_eq!(
            (bus.name, scheme, target),
            ("can", "socketcand", "127.0.0.1/can0")
        );
        let e = by_url("lin://x").unwrap_err();
        assert!(e.contains("unknown scheme `lin://`"), "{e}");
        assert!(e.contains("enip://, ecat://"), "{e}");
        assert!(by_url("veth0").unwrap_err().contains("give a URL"));
    }

    #[test]
    fn every_profile_of_a_bus_names_the_bus() {
        for bus in BUSES {
            for p in (bus.profiles)() {
                assert_eq!(p.bus, Some(bus.name), "{}", p.name());
                if p.product.is_some() {
                    assert!(
                        p.name().ends_with(&format!("@{}", bus.name)),
                        "{}",
                        p.name()
                    );
                }
            }
        }
    }

    #[test]
    fn every_bus_url_starts_with_its_scheme() {
        for bus in BUSES {
            let scheme = bus.url.split("://").next().unwrap_or_default();
            assert!(
                scheme == bus.name || bus.schemes.contains(&scheme),
                "{}",
                bus.url
            );
            assert_eq!(by_url(bus.url).unwrap().0.name, bus.name);
            assert!(urls().contains(bus.url));
        }
    }

    #[test]
    fn description_formats_are_found_by_name() {
        assert_eq!(description("eds", None).unwrap().0.name, "enip");
        assert_eq!(description("eds", Some("can")).unwrap().0.name, "can");
        assert_eq!(description("gsdml", None).unwrap().0.name, "pnio");
        let e = description("xyz", None).unwrap_err();
        assert!(e.contains("known: eds (enip), esi (ecat)"), "{e}");
        assert!(e.contains("eds (can)"), "{e}");
        assert!(description("esi", Some("can")).is_err());
    }
}
