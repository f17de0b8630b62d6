//! EtherCAT: the master binding (CoE SDO and cyclic PDOs over raw Ethernet or the in-memory
//! link to the simulated slave), `harness serve ecat`, the ESI writer and the `ecat:` steps.

pub mod serve;
mod step;

use crate::binding::{Binding, OpenError};
use crate::bus::{Bus, Embedded, Network};
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
    serve,
    descriptions: &[],
};

fn profiles() -> Vec<Profile> {
    Vec::new()
}

fn embedded(_: &Profile, _: &Embedded) -> Result<Box<dyn Binding>, OpenError> {
    Err(OpenError::Profile("EtherCAT is not there yet".into()))
}

fn network(_: &Network) -> Result<Box<dyn DutFactory>, OpenError> {
    Err(OpenError::Profile("EtherCAT is not there yet".into()))
}

fn serve(_: &[String]) -> Result<i32, String> {
    Err("EtherCAT is not there yet".into())
}
