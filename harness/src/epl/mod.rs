//! POWERLINK: the managing-node binding (SDO over ASnd or UDP, the cycle, NMT), `harness
//! serve epl`, the XDD writer and the `epl:` steps — for the SK 550P (BU 0620 §2.4) and the
//! modules SK TU3-POL, SK TU4-POL, SK CU4-POL (BU 2200).

mod address;
pub mod bench_support;
mod binding;
mod effect;
mod faults;
pub(crate) mod mn;
pub mod serve;
mod step;

use std::net::SocketAddr;
use std::time::Duration;

use crate::net::peer::Tapped;
use binding::EplBinding;
use mn::link::{EmbeddedLink, Link, NetLink, EMBEDDED_PEER, SOURCE};
use mn::{Manager, MnConfig};
use proto::eth::MacAddr;
use proto::nord::epl as def;
use proto::nord::{Product, Protocol};
use sim::device::Device;
use sim::epl::{Node, NodeConfig};

use crate::binding::simulator::device_config;
use crate::binding::DutFactory;
use crate::binding::{Binding, OpenError};
use crate::bus::{Bus, Description, Embedded, Network};
use crate::dictionary::DescribeError;
use crate::net::LinkError;
use crate::profile::Profile;

/// The registry entry.
pub(crate) const BUS: Bus = Bus {
    name: "epl",
    title: "POWERLINK",
    url: "epl://IFACE[/NODE][?sdo=udp|asnd&cycle=TIME]",
    schemes: &[],
    profiles,
    parse_step: step::parse,
    embedded,
    network,
    serve: serve::command,
    descriptions: &[Description {
        format: "xdd",
        write: describe_xdd,
        per_inverter: false,
    }],
    variable: crate::bus::Variable::NONE,
};

/// `harness describe xdd`: the XDD of a POWERLINK product, from `proto::nord::epl` (the
/// definition the simulated node runs on).
fn describe_xdd(profile: &Profile, inverters: u8) -> Result<String, DescribeError> {
    crate::dictionary::xdd::xdd(
        profile
            .nord()
            .map_err(|_| DescribeError::AnyMaker(profile.name().to_string()))?,
        inverters,
    )
}

fn profiles() -> Vec<Profile> {
    Product::ALL
        .into_iter()
        .filter(|p| p.protocols().contains(&Protocol::Powerlink))
        .map(|p| Profile::on_bus(p, "epl"))
        .collect()
}

/// The MN's own Ethernet address in-process (locally administered).
const EMBEDDED_MN_MAC: MacAddr = MacAddr([0x02, 0x00, 0x00, 0x00, 0x00, 0xF0]);

/// The simulated node of the profile's product (node 1) behind the MN.
fn embedded(profile: &Profile, context: &Embedded) -> Result<Box<dyn Binding>, OpenError> {
    let product = Some(profile.nord().map_err(OpenError::Profile)?);
    let device = Device::new(device_config(profile)?);
    let node =
        Node::new(device, NodeConfig::new(1)).map_err(|e| OpenError::Profile(e.to_string()))?;
    let link = EmbeddedLink::new(node, EMBEDDED_PEER);
    let what = "embedded POWERLINK node".to_string();
    let config = MnConfig::default();
    match &context.tap {
        None => open(link, config, EMBEDDED_MN_MAC, product, what, false),
        Some(tap) => {
            let link = Tapped::new(link, tap.clone(), SOURCE);
            open(link, config, EMBEDDED_MN_MAC, product, what, false)
        }
    }
}

/// The MN on `link`, its node booted to PRE_OPERATIONAL_2 behind the binding.
fn open<L: Link + 'static>(
    link: L,
    config: MnConfig,
    mac: MacAddr,
    product: Option<Product>,
    what: String,
    persistent: bool,
) -> Result<Box<dyn Binding>, OpenError> {
    let mn = Manager::new(link, config, mac);
    Ok(Box::new(EplBinding::open(mn, product, what, persistent)?))
}

/// `--dut epl://IFACE[/NODE][?sdo=udp|asnd&cycle=TIME]`: the node behind that interface (node 1
/// unless given), SDO over ASnd unless `sdo=udp`, the cycle 1 ms unless given (P858: 400 µs to
/// 2 ms). The bus's own options ride in the URL, so the command line names no bus.
fn network(n: &Network) -> Result<Box<dyn DutFactory>, OpenError> {
    let url = |why: String| OpenError::Profile(format!("`epl://{}`: {why}", n.target));
    let (path, query) = n.target.split_once('?').unwrap_or((&n.target, ""));
    let (iface, node) = match path.split_once('/') {
        Some((i, id)) => (
            i.to_string(),
            id.parse::<u8>()
                .ok()
                .filter(|v| (1..=239).contains(v))
                .ok_or_else(|| url(format!("node id `{id}` is not 1…239 (BU 0620 §2.4.3.1)")))?,
        ),
        None => (path.to_string(), 1),
    };
    let mut config = MnConfig {
        node,
        sdo: n.timeout,
        asked: n.timeout,
        ..MnConfig::default()
    };
    for pair in query.split('&').filter(|p| !p.is_empty()) {
        match pair.split_once('=') {
            Some(("sdo", v)) => config.via = mn::Via::parse(v).map_err(url)?,
            Some(("cycle", v)) => {
                let d = crate::suite::parse_duration(v).map_err(url)?;
                if !(Duration::from_micros(100)..=Duration::from_millis(100)).contains(&d) {
                    return Err(url(format!("cycle {v}: give 100µs…100ms")));
                }
                config.cycle = d;
                config.reply = config.reply.min(d / 2);
            }
            _ => {
                return Err(url(format!(
                    "`{pair}`: options are sdo=udp|asnd and cycle=TIME"
                )))
            }
        }
    }
    // SDO over UDP/IP goes to the node's 192.168.100.N: without an address of the interface on
    // that subnet every UDP case would err ("Connection refused"), so it is refused before
    // any. A node whose XDD declares no SDO over UDP/IP (1F82h bit 1 clear) needs none.
    let udp_declared = match &n.description {
        Some(crate::description::Description::Xdd(x)) => {
            x.feature_flags.is_none_or(|f| f & 0x2 != 0)
        }
        _ => true,
    };
    if udp_declared {
        let have = crate::net::udp::ipv4s_of(&iface)
            .ok_or_else(|| url(format!("no network interface `{iface}` here")))?;
        address::check_mn(&iface, node, &have).map_err(url)?;
    }
    Ok(Box::new(NetworkFactory {
        iface,
        config,
        tap: n.tap.clone(),
    }))
}

/// Opens the link behind an interface for each case (one node for the whole run).
struct NetworkFactory {
    iface: String,
    config: MnConfig,
    tap: Option<crate::pcap::SharedTap>,
}

impl DutFactory for NetworkFactory {
    fn describe(&self) -> String {
        format!("POWERLINK node {} on {}", self.config.node, self.iface)
    }

    fn open(&mut self, profile: &Profile, _retries: u32) -> Result<Box<dyn Binding>, OpenError> {
        let product = profile.product;
        let peer = SocketAddr::from((def::ip_address(self.config.node), proto::epl::SDO_UDP_PORT));
        let link =
            NetLink::open(&self.iface, proto::eth::ETHERTYPE_POWERLINK, peer, 0).map_err(|e| {
                match e {
                    LinkError::NeedsRoot { .. } => OpenError::NotPermitted(e.to_string()),
                    other => OpenError::Unreachable(other.to_string()),
                }
            })?;
        let mac = MacAddr(link.mac());
        let config = self.config;
        let what = format!("POWERLINK on {}", self.iface);
        match &self.tap {
            None => open(link, config, mac, product, what, true),
            Some(tap) => open(
                Tapped::new(link, tap.clone(), SOURCE),
                config,
                mac,
                product,
                what,
                true,
            ),
        }
    }
}
