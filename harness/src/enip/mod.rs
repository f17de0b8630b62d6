//! EtherNet/IP: the scanner binding (explicit messages to NORD's parameter classes and a
//! class-1 I/O connection), `harness serve enip`, the EDS writer and the `enip:` suite steps.

/// What the EtherNet/IP speed bench needs of the library (`harness::enip_bench`).
pub mod bench_support;
mod cleanup;
mod consumer;
mod eds;
mod effect;
mod faults;
mod link;
mod pcap;
mod scanner;
mod serials;
pub(crate) mod serve;
mod serve_tcp;
#[cfg(test)]
mod serve_tests;
mod step;
mod variable;

pub(crate) use scanner::{ForwardOpenSpec, Scanner};

use proto::nord::Product;
use sim::device::Device;
use std::rc::Rc;

use crate::binding::simulator::device_config;
use crate::binding::DutFactory;
use crate::binding::{Binding, OpenError};
use crate::bus::{Bus, Description, Embedded, Network};
use crate::dictionary::DescribeError;
use crate::profile::Profile;

/// The registry entry.
pub(crate) const BUS: Bus = Bus {
    name: "enip",
    title: "EtherNet/IP",
    url: "enip://HOST[:PORT]",
    schemes: &[],
    profiles,
    parse_step: step::parse,
    embedded,
    network,
    serve: serve::command,
    descriptions: &[Description {
        format: "eds",
        write: describe_eds,
        per_inverter: false,
    }],
    variable: variable::VARIABLE,
};

/// Every NORD product with an EtherNet/IP interface.
fn profiles() -> Vec<Profile> {
    Product::ALL
        .into_iter()
        .filter(|p| proto::nord::eip::identity(*p).is_some())
        .map(|p| Profile::on_bus(p, "enip"))
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
    io_port_free(target, n.local).map_err(OpenError::Profile)?;
    Ok(Box::new(scanner::NetworkFactory {
        target,
        local: n.local,
        timeout: n.timeout,
        tap: n.tap.clone(),
        clock: Rc::new(sim::clock::RealClock::new()),
        declared: match &n.description {
            Some(crate::description::Description::Eds(e)) => e.owner().cloned(),
            _ => None,
        },
    }))
}

/// Checks once, before the run, that the scanner can bind UDP 2222 on the address it will
/// send from (`--local`, else the one the routing table picks toward the target): the target
/// sends T→O data there. When an adapter on this host already holds it (the scanner and
/// `harness serve enip` on one address), every I/O case would fail alike; this says why at
/// once.
fn io_port_free(
    target: std::net::SocketAddr,
    local: Option<std::net::IpAddr>,
) -> Result<(), String> {
    use std::net::{SocketAddr, UdpSocket};
    let local = match local {
        Some(ip) => ip,
        None => {
            let any: SocketAddr = if target.is_ipv4() {
                ([0, 0, 0, 0], 0).into()
            } else {
                (std::net::Ipv6Addr::UNSPECIFIED, 0).into()
            };
            let probe =
                UdpSocket::bind(any).map_err(|e| format!("cannot open a UDP socket: {e}"))?;
            match probe.connect(target).and_then(|()| probe.local_addr()) {
                Ok(a) => a.ip(),
                // No route: the connection check will say the target cannot be reached.
                Err(_) => return Ok(()),
            }
        }
    };
    let at = SocketAddr::new(local, proto::enip::io::IO_PORT);
    match UdpSocket::bind(at) {
        Ok(_) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::AddrInUse => Err(format!(
            "UDP {at} is in use (an adapter on the same address, or another run?): the target sends T→O data there; give the scanner an address of its own with `--local`"
        )),
        Err(e) => Err(format!("cannot bind UDP {at} for T→O data: {e}")),
    }
}

fn describe_eds(profile: &Profile, inverters: u8) -> Result<String, DescribeError> {
    eds::eds(
        profile
            .nord()
            .map_err(|_| DescribeError::AnyMaker(profile.name().to_string()))?,
        inverters,
    )
}

#[cfg(test)]
mod identity_tests {
    use proto::nord::Product;

    #[test]
    fn the_identity_comes_from_the_bus_service() {
        let id = crate::embedded::identity_over(Product::Tu3Eip, "enip");
        assert_eq!(id.source, "ListIdentity");
        assert_eq!(id.product_name.as_deref(), Some("SK TU3-EIP"));
        assert!(id.product_code.is_some() && id.revision.is_some() && id.serial.is_some());
    }
}
