//! EtherCAT: the master binding (CoE SDO and cyclic PDOs over raw Ethernet or the in-memory
//! link to the simulated slave), `harness serve ecat`, the ESI writer and the `ecat:` steps.

pub mod bench_support;
mod esi;
pub(crate) mod master;
pub mod serve;
mod step;

use crate::binding::{Binding, OpenError};
use crate::bus::{Bus, Description, Embedded, Network};
use crate::profile::Profile;
use crate::runner::DutFactory;

/// The registry entry.
pub(crate) const BUS: Bus = Bus {
    name: "ecat",
    title: "EtherCAT",
    profiles,
    parse_step: step::parse,
    embedded,
    network,
    serve: serve::command,
    descriptions: &[Description {
        format: "esi",
        write: describe_esi,
    }],
};

/// `harness describe esi`: the products speaking EtherCAT have their ESI from
/// `proto::nord::ecat` (the SK 550P's integrated interface, BU 0620 §2.2).
fn describe_esi(profile: &Profile, inverters: u8) -> Result<String, String> {
    let product = profile.nord()?;
    if !product
        .protocols()
        .contains(&proto::nord::Protocol::Ethercat)
    {
        return Err(format!("{} has no EtherCAT interface", product.name()));
    }
    esi::esi(inverters).map_err(|e| e.to_string())
}

fn profiles() -> Vec<Profile> {
    Vec::new()
}

fn embedded(_: &Profile, _: &Embedded) -> Result<Box<dyn Binding>, OpenError> {
    Err(OpenError::Profile("EtherCAT is not there yet".into()))
}

fn network(_: &Network) -> Result<Box<dyn DutFactory>, OpenError> {
    Err(OpenError::Profile("EtherCAT is not there yet".into()))
}
