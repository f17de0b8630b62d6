//! EtherCAT: the master binding (CoE SDO and cyclic PDOs over raw Ethernet or the in-memory
//! link to the simulated slave), `harness serve ecat`, the ESI writer and the `ecat:` steps.

pub mod bench_support;
mod binding;
mod effect;
mod emergency;
mod esi;
mod faults;
pub(crate) mod master;
mod pcap;
pub mod serve;
mod step;

use binding::{DutSegment, EcatBinding};
use master::{EmbeddedSegment, NetSegment, SegmentError};
use pcap::Tapped;
use proto::nord::{Product, Protocol};
use sim::device::Device;
use sim::ecat::Slave;
use std::time::Duration;

use crate::binding::simulator::device_config;
use crate::binding::DutFactory;
use crate::binding::{Binding, OpenError};
use crate::bus::{Bus, Description, Embedded, Network};
use crate::dictionary::DescribeError;
use crate::net::LinkError;
use crate::profile::Profile;

/// The registry entry.
pub(crate) const BUS: Bus = Bus {
    name: "ecat",
    title: "EtherCAT",
    url: "ecat://IFACE",
    schemes: &[],
    profiles,
    parse_step: step::parse,
    embedded,
    network,
    serve: serve::command,
    descriptions: &[Description {
        format: "esi",
        write: describe_esi,
        per_inverter: false,
    }],
    variable: crate::bus::Variable::NONE,
};

/// `harness describe esi`: the products speaking EtherCAT have their ESI from
/// `proto::nord::ecat` (the SK 550P's integrated interface, BU 0620 §2.2).
fn describe_esi(profile: &Profile, inverters: u8) -> Result<String, DescribeError> {
    let product = profile
        .nord()
        .map_err(|_| DescribeError::AnyMaker(profile.name().to_string()))?;
    if !product.protocols().contains(&Protocol::Ethercat) {
        return Err(DescribeError::NoInterface {
            product,
            bus: "EtherCAT",
            format: "ESI",
        });
    }
    DescribeError::check_inverters(product, inverters)?;
    esi::esi(inverters).map_err(|e| DescribeError::Write {
        format: "ESI",
        detail: e.to_string(),
    })
}

fn profiles() -> Vec<Profile> {
    Product::ALL
        .into_iter()
        .filter(|p| p.protocols().contains(&Protocol::Ethercat))
        .map(|p| Profile::on_bus(p, "ecat"))
        .collect()
}

/// The embedded run's process-data cycle: 4 ms, as the embedded PPO binding and the
/// EtherNet/IP scanner run. The drive model runs on time, not on cycles, so a case sees the
/// same drive at a quarter of the frames; a network run keeps the master's 1 ms.
const EMBEDDED_CYCLE: Duration = Duration::from_millis(4);

/// The simulated slave of the profile's product on a segment of its own, behind the master.
fn embedded(profile: &Profile, context: &Embedded) -> Result<Box<dyn Binding>, OpenError> {
    let product = Some(profile.nord().map_err(OpenError::Profile)?);
    let device = Device::new(device_config(profile)?);
    let slave = Slave::new(device).map_err(|e| OpenError::Profile(e.to_string()))?;
    let segment = EmbeddedSegment::new(slave);
    let opening = Opening {
        product,
        what: "embedded EtherCAT slave".to_string(),
        persistent: false,
        cycle: EMBEDDED_CYCLE,
    };
    opening.open(segment, context.tap.as_ref())
}

/// How the master opens a segment: for which product, named how, whether the device lives on
/// between cases, at which cycle.
struct Opening {
    product: Option<Product>,
    what: String,
    persistent: bool,
    cycle: Duration,
}

impl Opening {
    /// The binding on `segment`, its frames also to `tap` (`--pcap`) if given.
    fn open<S: DutSegment + 'static>(
        self,
        segment: S,
        tap: Option<&crate::pcap::SharedTap>,
    ) -> Result<Box<dyn Binding>, OpenError> {
        match tap {
            None => self.bind(segment),
            Some(tap) => self.bind(Tapped::new(segment, tap.clone())),
        }
    }

    fn bind<S: DutSegment + 'static>(self, segment: S) -> Result<Box<dyn Binding>, OpenError> {
        let b = EcatBinding::open(
            segment,
            self.product,
            self.what,
            self.persistent,
            self.cycle,
        )?;
        binding::check_vendor(&b)?;
        Ok(Box::new(b))
    }
}

/// `--dut ecat://IFACE`: the slave on the segment behind that interface.
fn network(n: &Network) -> Result<Box<dyn DutFactory>, OpenError> {
    Ok(Box::new(NetworkFactory {
        iface: n.target.clone(),
        tap: n.tap.clone(),
    }))
}

/// Opens the segment behind an interface for each case (one device for the whole run).
struct NetworkFactory {
    iface: String,
    tap: Option<crate::pcap::SharedTap>,
}

impl DutFactory for NetworkFactory {
    fn describe(&self) -> String {
        format!("EtherCAT segment on {}", self.iface)
    }

    fn open(&mut self, profile: &Profile, _retries: u32) -> Result<Box<dyn Binding>, OpenError> {
        let product = profile.product;
        let segment = NetSegment::open(&self.iface).map_err(|e| match e {
            SegmentError::Link(LinkError::NeedsRoot { .. }) => {
                OpenError::NotPermitted(e.to_string())
            }
            other => OpenError::Unreachable(other.to_string()),
        })?;
        let opening = Opening {
            product,
            what: format!("EtherCAT segment on {}", self.iface),
            persistent: true,
            cycle: master::MasterConfig::default().cycle,
        };
        opening.open(segment, self.tap.as_ref())
    }
}
