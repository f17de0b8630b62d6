//! PROFINET IO: the IO-controller binding (DCP, Connect/PrmEnd/ApplicationReady, RT cyclic
//! data, records, alarms, Release) and the `pnio:` steps — for the SK 550P (BU 0620 §2.5) and
//! the SK TU3-PNT (BU 0590).

mod binding;
mod controller;
mod gsdml;
mod link;
mod step;

use std::time::Duration;

use binding::PnioBinding;
use controller::Controller;
use link::{EmbeddedLink, Link, EMBEDDED_PEER, SOURCE};
use proto::eth::MacAddr;
use proto::nord::{Product, Protocol};
use sim::device::Device;
use sim::pnio::{IoConfig, IoDevice};

use crate::binding::embedded::device_config;
use crate::binding::{Binding, OpenError};
use crate::bus::{Bus, Description, Embedded, Network};
use crate::net::peer::Tapped;
use crate::profile::Profile;
use crate::runner::DutFactory;

/// The registry entry.
pub(crate) const BUS: Bus = Bus {
    name: "pnio",
    title: "PROFINET IO",
    profiles,
    parse_step: step::parse,
    embedded,
    network,
    serve,
    descriptions: &[Description {
        format: "gsdml",
        write: describe_gsdml,
    }],
};

/// `harness describe gsdml`: the GSDML of a PROFINET product, from `proto::nord::pnio` (the
/// definition the simulated IO device runs on).
fn describe_gsdml(profile: &Profile, inverters: u8) -> Result<String, String> {
    gsdml::gsdml(profile.nord()?, inverters)
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

/// The simulated IO device of the profile's product, named, behind the controller.
fn embedded(profile: &Profile, context: &Embedded) -> Result<Box<dyn Binding>, OpenError> {
    let product = profile.nord().map_err(OpenError::Profile)?;
    let config = IoConfig {
        name: EMBEDDED_NAME.into(),
        ..IoConfig::new()
    };
    let io = IoDevice::new(Device::new(device_config(profile)?), config)
        .map_err(|e| OpenError::Profile(e.to_string()))?;
    let link = EmbeddedLink::new(io, EMBEDDED_PEER);
    let what = "embedded PROFINET IO device".to_string();
    let name = Some(EMBEDDED_NAME.to_string());
    match &context.tap {
        None => open(link, product, profile.inverters, name, what),
        Some(tap) => open(
            Tapped::new(link, tap.clone(), SOURCE),
            product,
            profile.inverters,
            name,
            what,
        ),
    }
}

fn open<L: Link + 'static>(
    link: L,
    product: Product,
    inverters: u8,
    name: Option<String>,
    what: String,
) -> Result<Box<dyn Binding>, OpenError> {
    let ctl = Controller::new(link, EMBEDDED_MAC, EMBEDDED_TIMEOUT);
    Ok(Box::new(PnioBinding::open(
        ctl, product, inverters, name, what, 0,
    )?))
}

fn network(n: &Network) -> Result<Box<dyn DutFactory>, OpenError> {
    Err(OpenError::Profile(format!(
        "`pnio://{}`: the PROFINET controller runs against the embedded device only so far",
        n.target
    )))
}

fn serve(_args: &[String]) -> Result<i32, String> {
    Err("`harness serve pnio` is not there yet: the PROFINET device runs embedded only".into())
}
