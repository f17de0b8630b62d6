//! The NORD system bus (CANopen on CAN at 250 kBaud, BU 0620 §2.6, `proto::nord::can`): the
//! inverters as CANopen nodes on a CAN segment (`sim::can`).
//!
//! What runs today: `harness serve can --socketcand ADDR` serves the simulated segment over
//! socketcand's TCP protocol, where python-can, python-canopen or another master joins it.
//! What does not yet: a binding of the harness's own (`--dut can://IFACE`,
//! `--dut socketcand://HOST:PORT/CHANNEL`), the system-bus profiles of the default run and
//! `can:` suite steps; each refuses with that said rather than doing something else.

mod eds;
mod serve;

use serde_json::Value;

use crate::binding::{Binding, OpenError};
use crate::bus::{Bus, BusStep, Description, Embedded, Network};
use crate::profile::Profile;
use crate::runner::DutFactory;

/// The registry entry.
pub(crate) const BUS: Bus = Bus {
    name: "can",
    title: "NORD system bus (CANopen)",
    url: "can://IFACE",
    profiles: Vec::new,
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

/// Why the harness cannot test over the system bus yet.
const NO_BINDING: &str = "the harness has no system-bus binding yet: `harness serve can` serves \
the simulated segment to CANopen masters such as python-canopen, but `--dut` and `can:` \
steps over CAN are not built";

fn parse_step(_: &Value) -> Result<Box<dyn BusStep>, String> {
    Err(NO_BINDING.to_string())
}

fn embedded(_: &Profile, _: &Embedded) -> Result<Box<dyn Binding>, OpenError> {
    Err(OpenError::Profile(NO_BINDING.to_string()))
}

fn network(_: &Network) -> Result<Box<dyn DutFactory>, OpenError> {
    Err(OpenError::Profile(NO_BINDING.to_string()))
}

/// `harness describe eds --bus can --profile P [--inverter N]`: the EDS of inverter N (FI 1 by
/// default) of the product's system bus.
fn describe_eds(profile: &Profile, fi: u8) -> Result<String, String> {
    let product = profile.nord()?;
    let fi = proto::nord::Inverter::new(i64::from(fi)).map_err(|e| e.to_string())?;
    eds::eds(product, fi)
}
