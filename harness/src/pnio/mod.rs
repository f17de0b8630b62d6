//! PROFINET IO: the IO-controller binding (DCP, Connect/PrmEnd/ApplicationReady, RT cyclic
//! data, records, alarms, Release) and the `pnio:` steps — for the SK 550P (BU 0620 §2.5) and
//! the SK TU3-PNT (BU 0590).

pub mod bench_support;
mod binding;
mod consumer;
mod controller;
mod effect;
mod faults;
mod generic;
mod gsdml;
mod link;
mod restore;
pub mod serve;
mod step;
mod variable;

use std::net::SocketAddr;
use std::time::Duration;

use binding::PnioBinding;
use controller::Controller;
use link::{EmbeddedLink, Link, NetLink, EMBEDDED_PEER, SOURCE};
use proto::eth::MacAddr;
use proto::nord::{Product, Protocol};
use sim::device::Device;
use sim::pnio::{IoConfig, IoDevice};

use crate::binding::simulator::device_config;
use crate::binding::DutFactory;
use crate::binding::{Binding, OpenError};
use crate::bus::{Bus, Description, Embedded, Network};
use crate::dictionary::DescribeError;
use crate::net::peer::Tapped;
use crate::net::LinkError;
use crate::profile::Profile;

/// The registry entry.
pub(crate) const BUS: Bus = Bus {
    name: "pnio",
    title: "PROFINET IO",
    url: "pnio://IFACE[/NAME][?rr=N]",
    schemes: &[],
    profiles,
    parse_step: step::parse,
    embedded,
    network,
    serve: serve::command,
    descriptions: &[Description {
        format: "gsdml",
        write: describe_gsdml,
        per_inverter: false,
    }],
    variable: variable::VARIABLE,
};

/// `harness describe gsdml`: the GSDML of a PROFINET product, from `proto::nord::pnio` (the
/// definition the simulated IO device runs on).
fn describe_gsdml(profile: &Profile, inverters: u8) -> Result<String, DescribeError> {
    gsdml::gsdml(
        profile
            .nord()
            .map_err(|_| DescribeError::AnyMaker(profile.name().to_string()))?,
        inverters,
    )
}

fn profiles() -> Vec<Profile> {
    Product::ALL
        .into_iter()
        .filter(|p| p.protocols().contains(&Protocol::Profinet))
        .map(|p| Profile::on_bus(p, "pnio"))
        .collect()
}

/// The controller's own Ethernet address in-process (locally administered).
const EMBEDDED_MAC: MacAddr = MacAddr([0x02, 0x00, 0x00, 0x00, 0x00, 0xC1]);
/// How long the embedded controller waits for an answer (virtual time).
const EMBEDDED_TIMEOUT: Duration = Duration::from_millis(500);
/// The name the embedded device is given (BU 0620 §2.5.4: the controller addresses the
/// device by its name of station).
const EMBEDDED_NAME: &str = "nord-device";
/// The embedded run's reduction ratio: a 4 ms cycle, as the embedded PPO binding and the
/// EtherNet/IP scanner run (a valid RT_CLASS_1 ratio). The drive model runs on time, not on
/// cycles, so a case sees the same drive at a quarter of the frames.
const EMBEDDED_REDUCTION_RATIO: u16 = 4;

/// The simulated IO device of the profile's product, named, behind the controller.
fn embedded(profile: &Profile, context: &Embedded) -> Result<Box<dyn Binding>, OpenError> {
    let product = profile.nord().map_err(OpenError::Profile)?;
    let config = IoConfig {
        name: EMBEDDED_NAME.into(),
        ..IoConfig::new(product)
    };
    let io = IoDevice::new(Device::new(device_config(profile)?), config)
        .map_err(|e| OpenError::Profile(e.to_string()))?;
    let link = EmbeddedLink::new(io, EMBEDDED_PEER);
    let target = Target {
        device: Kind::Nord(product),
        inverters: profile.inverters,
        name: Some(EMBEDDED_NAME.to_string()),
        what: "embedded PROFINET IO device".to_string(),
        reduction_ratio: EMBEDDED_REDUCTION_RATIO,
        persistent: false,
    };
    match &context.tap {
        None => open(link, EMBEDDED_MAC, EMBEDDED_TIMEOUT, target),
        Some(tap) => open(
            Tapped::new(link, tap.clone(), SOURCE),
            EMBEDDED_MAC,
            EMBEDDED_TIMEOUT,
            target,
        ),
    }
}

/// The controller on `link` with Ethernet address `mac`, the device found and connected.
fn open<L: Link + 'static>(
    link: L,
    mac: MacAddr,
    timeout: Duration,
    target: Target,
) -> Result<Box<dyn Binding>, OpenError> {
    // A device on the network runs on the real clock, the embedded one on a virtual clock.
    let real_time = target.persistent;
    let mut ctl = Controller::new(link, mac, timeout, real_time);
    ctl.set_reduction_ratio(target.reduction_ratio);
    match target.device {
        Kind::Nord(product) => Ok(Box::new(PnioBinding::open(
            ctl,
            product,
            target.inverters,
            target.name,
            target.what,
            target.persistent,
        )?)),
        Kind::Any(layout) => Ok(Box::new(generic::GenericPnio::open(
            ctl,
            layout,
            target.name,
            target.what,
        )?)),
    }
}

/// The device a binding opens.
enum Kind {
    /// A NORD product: its modules, its parameter channel.
    Nord(Product),
    /// Any maker's device, with the layout its GSDML plans.
    Any(generic::Layout),
}

/// What a binding is opened on.
struct Target {
    device: Kind,
    inverters: u8,
    /// The name of station to find (`None`: the only device that answers).
    name: Option<String>,
    what: String,
    reduction_ratio: u16,
    /// A device on the network, which keeps what a case changes.
    persistent: bool,
}

/// `--dut pnio://IFACE[/NAME][?rr=N]`: the device behind that interface, found by DCP by its
/// name of station (or the only one answering), both CRs at reduction ratio N of the 1 ms
/// send clock (1 unless given).
fn network(n: &Network) -> Result<Box<dyn DutFactory>, OpenError> {
    let url = |why: String| OpenError::Profile(format!("`pnio://{}`: {why}", n.target));
    let (path, query) = n.target.split_once('?').unwrap_or((&n.target, ""));
    let (iface, name) = match path.split_once('/') {
        Some((i, name)) => {
            proto::nord::pnio::check_station_name(name)
                .map_err(|e| url(format!("name of station {name:?}: {e}")))?;
            (i.to_string(), Some(name.to_string()))
        }
        None => (path.to_string(), None),
    };
    let mut reduction_ratio = 1;
    for pair in query.split('&').filter(|p| !p.is_empty()) {
        match pair.split_once('=') {
            Some(("rr", v)) => {
                reduction_ratio = v
                    .parse()
                    .ok()
                    .filter(|r| (1..=512).contains(r))
                    .ok_or_else(|| url(format!("rr={v}: give 1…512")))?
            }
            _ => return Err(url(format!("`{pair}`: the option is rr=N"))),
        }
    }
    let layout = match &n.description {
        Some(crate::description::Description::Gsdml(g)) => Some(generic::Layout {
            dap: g.dap.clone(),
            modules: g.modules.clone(),
            device_access: g.device_access,
        }),
        _ => None,
    };
    Ok(Box::new(NetworkFactory {
        layout,
        iface,
        name,
        reduction_ratio,
        timeout: n.timeout,
        tap: n.tap.clone(),
    }))
}

/// Opens the link behind an interface for each case (one device for the whole run).
struct NetworkFactory {
    /// The layout of the device's GSDML (`--description`), for any maker's device.
    layout: Option<generic::Layout>,
    iface: String,
    name: Option<String>,
    reduction_ratio: u16,
    timeout: Duration,
    tap: Option<crate::pcap::SharedTap>,
}

impl DutFactory for NetworkFactory {
    fn describe(&self) -> String {
        match &self.name {
            Some(n) => format!("PROFINET IO device {n:?} on {}", self.iface),
            None => format!("PROFINET IO device on {}", self.iface),
        }
    }

    fn open(&mut self, profile: &Profile, _retries: u32) -> Result<Box<dyn Binding>, OpenError> {
        let device = match (profile.product, &self.layout) {
            (Some(product), _) => Kind::Nord(product),
            (None, Some(layout)) => Kind::Any(layout.clone()),
            (None, None) => {
                return Err(OpenError::Profile(
                    "any maker's PROFINET device is connected as its GSDML says: give it with `--description`".into(),
                ))
            }
        };
        // The device's address comes with DCP Identify; until then the socket points nowhere.
        let nowhere = SocketAddr::from((std::net::Ipv4Addr::LOCALHOST, proto::pnio::RPC_PORT));
        let mut link = NetLink::open(
            &self.iface,
            proto::eth::ETHERTYPE_PROFINET,
            nowhere,
            proto::pnio::RPC_PORT,
        )
        .map_err(|e| match e {
            LinkError::NeedsRoot { .. } => OpenError::NotPermitted(e.to_string()),
            other => OpenError::Unreachable(other.to_string()),
        })?;
        // The device's LLDP frames (BU 0620 §2.5.3), for the `lldp` step.
        link.also_take(proto::eth::ETHERTYPE_LLDP);
        let mac = MacAddr(link.mac());
        let target = Target {
            device,
            inverters: profile.inverters,
            name: self.name.clone(),
            what: format!("PROFINET IO on {}", self.iface),
            reduction_ratio: self.reduction_ratio,
            persistent: true,
        };
        match &self.tap {
            None => open(link, mac, self.timeout, target),
            Some(tap) => open(
                Tapped::new(link, tap.clone(), SOURCE),
                mac,
                self.timeout,
                target,
            ),
        }
    }
}

#[cfg(test)]
mod identity_tests {
    use proto::nord::Product;

    #[test]
    fn the_identity_comes_from_the_bus_service() {
        let id = crate::embedded::identity_over(Product::Tu3Pnt, "pnio");
        assert_eq!(
            id.source,
            "DCP Identify of station \"nord-device\" and I&M0"
        );
        assert_eq!(id.serial.as_deref(), Some("000ECF036000"));
        assert!(id.product_code.is_some() && id.revision.is_some(), "{id:?}");
    }
}
