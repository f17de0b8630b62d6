//! EtherNet/IP: the scanner binding (explicit messages to NORD's parameter classes and a
//! class-1 I/O connection), `harness serve enip`, the EDS writer and the `enip:` suite steps.

/// What the EtherNet/IP speed bench needs of the library (`harness::enip_bench`).
pub mod bench_support;
mod cleanup;
mod eds;
mod link;
mod pcap;
mod scanner;
pub(crate) mod serve;
mod serve_tcp;
#[cfg(test)]
mod serve_tests;
mod step;

pub(crate) use scanner::{ForwardOpenSpec, Scanner};

use proto::nord::Product;
use sim::device::Device;
use std::rc::Rc;

use crate::binding::embedded::device_config;
use crate::binding::{Binding, OpenError};
use crate::bus::{Bus, Description, Embedded, Network};
use crate::profile::Profile;
use crate::runner::DutFactory;

/// The registry entry.
pub(crate) const BUS: Bus = Bus {
    name: "enip",
    title: "EtherNet/IP",
    profiles,
    parse_step: step::parse,
    embedded,
    network,
    serve: serve::command,
    descriptions: &[Description {
        format: "eds",
        write: describe_eds,
    }],
};

/// Every NORD product with an EtherNet/IP interface, and `cip`: any maker's adapter, against
/// which the suites' EtherNet/IP cases run (`run --dut` only).
fn profiles() -> Vec<Profile> {
    Product::ALL
        .into_iter()
        .filter(|p| proto::nord::eip::identity(*p).is_some())
        .map(|p| Profile::on_bus(p, "enip"))
        .chain([Profile::generic("cip", "enip")])
        .collect()
}

fn embedded(profile: &Profile, context: &Embedded) -> Result<Box<dyn Binding>, OpenError> {
    let device = Device::new(device_config(profile)?);
    Ok(Box::new(Scanner::embedded(device, context.tap.clone())))
}

fn network(n: &Network) -> Result<Box<dyn DutFactory>, OpenError> {
    let target = serve::parse_addr(&n.target).map_err(OpenError::Unreachable)?;
    if n.tap.is_some() && !target.is_ipv4() {
        return Err(OpenError::Profile(format!(
            "`--pcap` with `--dut enip://{}`: a pcap records IPv4 only",
            n.target
        )));
    }
    Ok(Box::new(scanner::NetworkFactory {
        target,
        local: n.local,
        timeout: n.timeout,
        tap: n.tap.clone(),
        clock: Rc::new(sim::clock::RealClock::new()),
    }))
}

fn describe_eds(profile: &Profile, inverters: u8) -> Result<String, String> {
    eds::eds(profile.nord()?, inverters)
}
