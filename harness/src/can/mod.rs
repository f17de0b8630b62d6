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
//! What does not yet: SocketCAN (`can://IFACE`); it refuses with that said.

pub mod bench_support;
mod binding;
mod eds;
mod link;
mod process;
mod sdo;
mod serve;
mod step;
mod tap;

use std::net::SocketAddr;
use std::time::Duration;

use serde_json::Value;

use crate::binding::{Binding, OpenError};
use crate::bus::{Bus, BusStep, Description, Embedded, Network};
use crate::pcap::SharedTap;
use crate::profile::Profile;
use crate::runner::DutFactory;
use binding::CanBinding;
pub(crate) use sdo::frame_hex;
pub(crate) use serve::relay_system_bus;
pub(crate) use tap::{SystemBusTap, TapFactory};

/// The registry entry.
pub(crate) const BUS: Bus = Bus {
    name: "can",
    title: "NORD system bus (CANopen)",
    url: "socketcand://HOST[:PORT]/CHANNEL",
    schemes: &["socketcand"],
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

fn parse_step(v: &Value) -> Result<Box<dyn BusStep>, String> {
    step::parse(v)
}

/// The simulated segment of the profile's product, behind the SDO client.
fn embedded(profile: &Profile, context: &Embedded) -> Result<Box<dyn Binding>, OpenError> {
    let config = crate::binding::embedded::device_config(profile)?;
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
/// socketcand server (port 29536 unless given), or with `--profile any` the CANopen node NODE
/// of any maker.
fn network(n: &Network) -> Result<Box<dyn DutFactory>, OpenError> {
    if n.scheme != "socketcand" {
        return Err(OpenError::Profile(format!(
            "`{}://{}`: SocketCAN is not built yet; reach the bus through a socketcand server \
             (`--dut socketcand://HOST[:PORT]/CHANNEL`)",
            n.scheme, n.target
        )));
    }
    let (host, channel) = n.target.split_once('/').ok_or_else(|| {
        OpenError::Profile(format!(
            "`socketcand://{}`: give the bus after a slash (`socketcand://HOST[:PORT]/can0`)",
            n.target
        ))
    })?;
    // Any maker's node: `…/CHANNEL/NODE`.
    let (channel, node) = match channel.split_once('/') {
        None => (channel, None),
        Some((channel, node)) => {
            let id = node
                .parse::<u8>()
                .ok()
                .filter(|n| (1..=127).contains(n))
                .ok_or_else(|| {
                    OpenError::Profile(format!(
                        "`socketcand://{}`: `{node}` is not a node id 1…127",
                        n.target
                    ))
                })?;
            (channel, Some(id))
        }
    };
    if channel.is_empty() || channel.contains(char::is_whitespace) {
        return Err(OpenError::Profile(format!(
            "`socketcand://{}`: `{channel}` is not a bus name",
            n.target
        )));
    }
    let addr = crate::net::serve_args::socket_addr(host, serve::DEFAULT_PORT)
        .map_err(|e| OpenError::Profile(format!("`socketcand://{}`: {e}", n.target)))?;
    Ok(Box::new(SocketcandFactory {
        addr,
        node,
        channel: channel.to_string(),
        timeout: n.timeout,
        tap: n.tap.clone(),
    }))
}

/// Opens the socketcand server's bus anew for every case.
struct SocketcandFactory {
    addr: SocketAddr,
    /// Any maker's node, as the URL names it (`…/CHANNEL/NODE`).
    node: Option<u8>,
    channel: String,
    timeout: Duration,
    /// The run's capture (`--pcap`).
    tap: Option<SharedTap>,
}

impl DutFactory for SocketcandFactory {
    fn describe(&self) -> String {
        format!("system bus `{}` of socketcand {}", self.channel, self.addr)
    }

    fn open(&mut self, profile: &Profile, _retries: u32) -> Result<Box<dyn Binding>, OpenError> {
        let link = link::Socketcand::connect(self.addr, &self.channel, self.timeout)
            .map_err(|e| OpenError::Unreachable(e.to_string()))?;
        let Ok(product) = profile.nord() else {
            // Any maker's CANopen node: the URL names it.
            let node = self.node.ok_or_else(|| {
                OpenError::Profile(
                    "any maker's CANopen node: give its node id in the URL \
                     (`socketcand://HOST[:PORT]/CHANNEL/NODE`)"
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

/// `harness describe eds --bus can --profile P [--inverter N]`: the EDS of inverter N (FI 1 by
/// default) of the product's system bus.
fn describe_eds(profile: &Profile, fi: u8) -> Result<String, String> {
    let product = profile.nord()?;
    let fi = proto::nord::Inverter::new(i64::from(fi)).map_err(|e| e.to_string())?;
    eds::eds(product, fi)
}
