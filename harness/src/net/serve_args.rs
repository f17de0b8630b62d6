//! What every raw-Ethernet `harness serve <bus>` (EtherCAT, POWERLINK, PROFINET IO) takes —
//! the interface, the product, the inverters behind it, how long — and the simulated device
//! those name, so the three commands read and refuse them alike.

use std::net::{IpAddr, SocketAddr};

use proto::nord::{Product, Protocol};
use sim::device::DeviceConfig;

use super::misbehave::{BusFaults, Misbehaviour, DEFAULT_SEED};

/// `--iface --profile --inverters --seconds --misbehave --seed`, flattened into each bus's own
/// arguments.
#[derive(clap::Args, Debug)]
pub(crate) struct RawServeArgs {
    /// The network interface, e.g. one end of a veth pair.
    #[arg(long)]
    pub(crate) iface: String,
    /// Product profile: a product with this bus's interface.
    #[arg(long, default_value = "sk550p")]
    pub(crate) profile: String,
    /// Inverters behind the interface (default: the product's maximum).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=8))]
    pub(crate) inverters: Option<u8>,
    /// Stop after this many seconds (default: serve until killed).
    #[arg(long)]
    pub(crate) seconds: Option<u64>,
    #[command(flatten)]
    pub(crate) misbehave: MisbehaveArgs,
}

/// `--misbehave SPEC --seed N`: every bus's device misbehaving on purpose (`docs/misbehave.md`).
#[derive(clap::Args, Debug)]
pub(crate) struct MisbehaveArgs {
    /// Misbehave on purpose, to test that the harness names what the device did: modes
    /// separated by commas, e.g. `late=500ms`, `late=100ms..900ms`, `drop=20%`,
    /// `drop=every:3`, `dup`, `reorder`, `silent=2s` (from the first exchange) or
    /// `silent=2s@5s`, `corrupt=FIELD`, `close`, `alarm=2s` or `alarm=every:2s` (see
    /// docs/misbehave.md).
    #[arg(long, value_name = "SPEC")]
    pub(crate) misbehave: Option<Misbehaviour>,
    /// Where `--misbehave`'s random choices come from (a jittered delay, `drop=20%`): the
    /// same spec and seed misbehave the same way.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_SEED)]
    pub(crate) seed: u64,
}

impl MisbehaveArgs {
    /// The misbehaviour asked for, if `bus` can do it; else the usage error's exit code, after
    /// a line on stderr naming the mode at fault.
    pub(crate) fn for_bus(&self, bus: &BusFaults) -> Result<Misbehaviour, i32> {
        let m = self.misbehave.unwrap_or_default().with_seed(self.seed);
        m.check(bus).map(|()| m).map_err(|e| {
            eprintln!("error: --misbehave {e}");
            crate::exit::EXIT_USAGE
        })
    }
}

/// `--system-bus ADDR`, for the raw-Ethernet buses whose bus modules are gateways onto the
/// system bus (POWERLINK, PROFINET IO).
#[derive(clap::Args, Debug)]
pub(crate) struct SystemBusArg {
    /// Also publish the device's system bus as its gateway sees it (the CANopen frames it
    /// exchanges with its inverters) on a socketcand server at ADDR, HOST[:PORT], channel
    /// `can0`: a run over the fieldbus watches it with `--tap socketcand://ADDR/can0`.
    #[arg(long, value_name = "ADDR")]
    pub(crate) system_bus: Option<String>,
}

/// The simulated device of `profile` with `inverters` (default and ceiling: the product's
/// maximum), if the product has a `protocol` interface; else why not, naming the products
/// that have one.
pub(crate) fn device_config(
    profile: &str,
    inverters: Option<u8>,
    protocol: Protocol,
    bus_name: &str,
) -> Result<DeviceConfig, String> {
    let product = crate::profile::product_named(profile)?;
    if !product.protocols().contains(&protocol) {
        let with: Vec<&str> = Product::ALL
            .into_iter()
            .filter(|p| p.protocols().contains(&protocol))
            .map(Product::name)
            .collect();
        return Err(format!(
            "{} has no {bus_name} interface ({bus_name} profiles: {})",
            product.name(),
            with.join(", ")
        ));
    }
    let max = product.max_inverters();
    Ok(DeviceConfig {
        inverters: inverters.unwrap_or(max).clamp(1, max),
        ..DeviceConfig::new(product)
    })
}

/// A listen or target address `HOST[:PORT]`, `default_port` where none is given (EtherNet/IP's
/// 44818, socketcand's 29536).
pub(crate) fn socket_addr(text: &str, default_port: u16) -> Result<SocketAddr, String> {
    if let Ok(a) = text.parse::<SocketAddr>() {
        return Ok(a);
    }
    text.parse::<IpAddr>()
        .map(|ip| SocketAddr::new(ip, default_port))
        .map_err(|_| {
            format!("`{text}` is not an address like 127.0.0.2 or 127.0.0.2:{default_port}")
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_product_without_the_bus_is_refused_naming_those_with_it() {
        let e = device_config("tu3-eip", None, Protocol::Powerlink, "POWERLINK").unwrap_err();
        assert_eq!(
            e,
            "tu3-eip has no POWERLINK interface (POWERLINK profiles: sk550p, tu3-pol, tu4-pol, cu4-pol)"
        );
        assert!(device_config("nope", None, Protocol::Ethercat, "EtherCAT")
            .unwrap_err()
            .contains("unknown profile `nope`"));
    }

    #[test]
    fn inverters_default_to_and_stop_at_the_products_maximum() {
        let max = Product::Sk550p.max_inverters();
        let at = |n| {
            device_config("sk550p", n, Protocol::Ethercat, "EtherCAT")
                .unwrap()
                .inverters
        };
        assert_eq!(at(None), max);
        assert_eq!(at(Some(1)), 1);
        assert_eq!(at(Some(8)), max.min(8));
    }
}
