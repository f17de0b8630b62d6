//! The NORD system bus (CANopen on CAN at 250 kBaud, BU 0620 §2.6, `proto::nord::can`): the
//! inverters as CANopen nodes on a CAN segment (`sim::can`).
//!
//! What runs: the `<product>@can` profiles test each product's inverters as system-bus nodes
//! through the harness's SDO client ([`binding`]), against the simulated segment in-process
//! or a segment behind a socketcand server (`--dut socketcand://HOST[:PORT]/CHANNEL`);
//! `harness serve can --socketcand ADDR` serves the simulated segment to CANopen masters such
//! as python-canopen; `can:` steps put frames and NMT commands on the bus and observe what comes
//! back; `process`/`wait` steps run PDOs on SYNC in the bus interface's place ([`process`]).
//! `--profile any` with `--dut socketcand://HOST[:PORT]/CHANNEL/NODE` tests any maker's CANopen
//! node with the cases whose steps are all `can:` (COB-IDs relative to the node: `600+N`).
//! `--dut can://IFACE[/NODE]` reaches a CAN interface of this host (SocketCAN), and `harness
//! serve can --iface IFACE` serves the simulated segment on one.

pub mod bench_support;
mod binding;
mod faults;
mod link;
mod process;
mod sdo;
mod serve;
mod socketcan;
mod step;
mod tap;

use std::net::SocketAddr;
use std::time::Duration;

use serde_json::Value;

use crate::binding::DutFactory;
use crate::binding::{Binding, OpenError};
use crate::bus::{Bus, Description, Embedded, Network};
use crate::dictionary::DescribeError;
use crate::pcap::SharedTap;
use crate::profile::Profile;
use crate::suite::BusStep;
use binding::CanBinding;
pub(crate) use serve::{announce_relay, relay_served, relay_system_bus};
pub(crate) use tap::{SystemBusTap, TapFactory};

/// The registry entry.
pub(crate) const BUS: Bus = Bus {
    name: "can",
    title: "NORD system bus (CANopen)",
    url: "socketcand://HOST[:PORT]/CHANNEL or can://IFACE",
    schemes: &["socketcand", "can"],
    profiles,
    parse_step,
    embedded,
    network,
    serve: serve::command,
    descriptions: &[Description {
        format: "eds",
        write: describe_eds,
        per_inverter: true,
    }],
    variable: crate::bus::Variable::NONE,
};

/// How long an inverter node of the simulated segment may take to answer an SDO request (it
/// answers at once on the virtual clock; the limit only bounds a node that stays silent).
const EMBEDDED_LIMIT: Duration = Duration::from_millis(100);

/// Every product's inverters: each interface reaches its inverters over the system bus.
fn profiles() -> Vec<Profile> {
    proto::nord::Product::ALL
        .into_iter()
        .map(|p| Profile::on_bus(p, "can"))
        .collect()
}

fn parse_step(v: &Value) -> Result<Box<dyn BusStep>, crate::suite::fields::FieldError> {
    step::parse(v)
}

/// The simulated segment of the profile's product, behind the SDO client.
fn embedded(profile: &Profile, context: &Embedded) -> Result<Box<dyn Binding>, OpenError> {
    let config = crate::binding::simulator::device_config(profile)?;
    let (product, inverters) = (config.product, config.inverters);
    let segment = sim::can::Segment::new(config).map_err(|e| OpenError::Profile(e.to_string()))?;
    let link = link::Embedded::new(segment);
    let what = "embedded system-bus segment".to_string();
    open(
        link,
        context.tap.as_ref(),
        EMBEDDED_LIMIT,
        (product, inverters),
        what,
        false,
    )
}

/// The binding on `link`, its frames also going to the run's capture when it has one.
fn open<L: link::CanLink + 'static>(
    link: L,
    tap: Option<&SharedTap>,
    limit: Duration,
    (product, inverters): (proto::nord::Product, u8),
    what: String,
    persistent: bool,
) -> Result<Box<dyn Binding>, OpenError> {
    Ok(match tap {
        None => Box::new(CanBinding::open(
            link, limit, product, inverters, what, persistent,
        )?),
        Some(tap) => Box::new(CanBinding::open(
            link::Tapped::new(link, tap.clone()),
            limit,
            product,
            inverters,
            what,
            persistent,
        )?),
    })
}

/// `--dut socketcand://HOST[:PORT]/CHANNEL[/NODE]`: the inverters on the bus `CHANNEL` of a
/// socketcand server (port 29536 unless given); `--dut can://IFACE[/NODE]`: those on a CAN
/// interface of this host (SocketCAN). With `--profile any`, the CANopen node NODE of any
/// maker.
fn network(n: &Network) -> Result<Box<dyn DutFactory>, OpenError> {
    let url = format!("{}://{}", n.scheme, n.target);
    let bad = |what: String| OpenError::Profile(format!("`{url}`: {what}"));
    let (transport, rest) = match n.scheme.as_str() {
        "socketcand" => {
            let (host, rest) = n.target.split_once('/').ok_or_else(|| {
                bad("give the bus after a slash (`socketcand://HOST[:PORT]/can0`)".into())
            })?;
            let addr = crate::net::serve_args::socket_addr(host, serve::DEFAULT_PORT)
                .map_err(|e| bad(e.to_string()))?;
            (Some(addr), rest)
        }
        _ => (None, n.target.as_str()),
    };
    // Any maker's node: `…/NODE`.
    let (bus, node) = match rest.split_once('/') {
        None => (rest, None),
        Some((bus, node)) => {
            let id = node
                .parse::<u8>()
                .ok()
                .filter(|n| (1..=127).contains(n))
                .ok_or_else(|| bad(format!("`{node}` is not a node id 1…127")))?;
            (bus, Some(id))
        }
    };
    if bus.is_empty() || bus.contains(char::is_whitespace) {
        return Err(bad(format!("`{bus}` is not a bus name")));
    }
    Ok(Box::new(BusFactory {
        transport: match transport {
            Some(addr) => Transport::Socketcand {
                addr,
                channel: bus.to_string(),
            },
            None => Transport::SocketCan {
                iface: bus.to_string(),
            },
        },
        node,
        timeout: n.timeout,
        tap: n.tap.clone(),
    }))
}

/// How the harness reaches a system bus on the network.
enum Transport {
    /// The bus `channel` of a socketcand server.
    Socketcand { addr: SocketAddr, channel: String },
    /// A CAN interface of this host.
    SocketCan { iface: String },
}

/// Opens the bus anew for every case.
struct BusFactory {
    transport: Transport,
    /// Any maker's node, as the URL names it (`…/NODE`).
    node: Option<u8>,
    timeout: Duration,
    /// The run's capture (`--pcap`).
    tap: Option<SharedTap>,
}

impl BusFactory {
    /// The binding of `profile` on `link`: a NORD product's inverters, or any maker's node.
    fn open_on<L: link::CanLink + 'static>(
        &self,
        link: L,
        profile: &Profile,
    ) -> Result<Box<dyn Binding>, OpenError> {
        let Ok(product) = profile.nord() else {
            // Any maker's CANopen node: the URL names it.
            let node = self.node.ok_or_else(|| {
                OpenError::Profile(
                    "any maker's CANopen node: give its node id at the end of the URL \
                     (`socketcand://HOST[:PORT]/CHANNEL/NODE`, `can://IFACE/NODE`)"
                        .into(),
                )
            })?;
            let what = self.describe();
            return Ok(match &self.tap {
                None => Box::new(CanBinding::open_any(link, self.timeout, node, what)?),
                Some(tap) => Box::new(CanBinding::open_any(
                    link::Tapped::new(link, tap.clone()),
                    self.timeout,
                    node,
                    what,
                )?),
            });
        };
        let inverters = profile.inverters.min(product.max_inverters());
        open(
            link,
            self.tap.as_ref(),
            self.timeout,
            (product, inverters),
            self.describe(),
            true,
        )
    }
}

impl DutFactory for BusFactory {
    fn describe(&self) -> String {
        match &self.transport {
            Transport::Socketcand { addr, channel } => {
                format!("system bus `{channel}` of socketcand {addr}")
            }
            Transport::SocketCan { iface } => format!("system bus on CAN interface {iface}"),
        }
    }

    fn open(&mut self, profile: &Profile, _retries: u32) -> Result<Box<dyn Binding>, OpenError> {
        let unreachable = |e: link::CanLinkError| OpenError::Unreachable(e.to_string());
        match &self.transport {
            Transport::Socketcand { addr, channel } => {
                let link =
                    link::Socketcand::connect(*addr, channel, self.timeout).map_err(unreachable)?;
                self.open_on(link, profile)
            }
            Transport::SocketCan { iface } => {
                let link = socketcan::SocketCan::open(iface).map_err(unreachable)?;
                self.open_on(link, profile)
            }
        }
    }
}

/// `harness describe eds --bus can --profile P [--inverter N]`: the EDS of inverter N (FI 1 by
/// default) of the product's system bus.
fn describe_eds(profile: &Profile, fi: u8) -> Result<String, DescribeError> {
    let product = profile
        .nord()
        .map_err(|_| DescribeError::AnyMaker(profile.name().to_string()))?;
    let fi = proto::nord::Inverter::new(i64::from(fi))
        .map_err(|_| DescribeError::Inverters { product, asked: fi })?;
    crate::dictionary::eds::eds(product, fi)
}
