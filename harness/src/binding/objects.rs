//! The NORD parameters as SDO objects, for the bindings of the CANopen-style buses (EtherCAT
//! CoE, POWERLINK): what a `read`/`write` order addresses, the object's bytes as a value and
//! back, and the object as the ledger's key. Each bus turns the address into its own index
//! (BU 0620 §2.2.7 for CoE, §2.4.6 and BU 2200 §6.4 for POWERLINK); the sub-index rule is one
//! (`proto::nord::addr::sdo_subindex`).

use std::fmt;

use proto::nord::ecat::{parameter_data_type, DataType};
use proto::nord::params::{self, Owner, ParamDef};
use proto::nord::{ArrayElement, Inverter, ParamSet, Product};

use super::StepError;
use crate::profile::Capability;
use crate::suite::{OrderSpec, Target};

/// What the embedded simulator behind such a bus's binding offers: every general capability
/// but the PKW parameter channel (the parameters are objects), and the bus's own steps.
pub(crate) const fn embedded_capabilities(bus: &'static str) -> [Capability; 9] {
    [
        Capability::ParameterAccess,
        Capability::ProcessData,
        Capability::FaultInjection,
        Capability::Observe,
        Capability::PowerOn,
        Capability::FactoryState,
        Capability::Readdressing,
        Capability::SystemBus,
        Capability::Bus(bus),
    ]
}

/// What a device on the network offers: one persistent device, which the harness can neither
/// power-cycle, reset to factory settings nor look into.
pub(crate) const fn network_capabilities(bus: &'static str) -> [Capability; 3] {
    [
        Capability::ParameterAccess,
        Capability::ProcessData,
        Capability::Bus(bus),
    ]
}

/// An SDO object: the key under which a binding's ledger keeps what a case wrote.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Object {
    /// Index.
    pub(crate) index: u16,
    /// Sub-index.
    pub(crate) sub: u8,
}

impl fmt::Display for Object {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "object {:04X}h:{:02X}h", self.index, self.sub)
    }
}

/// Whose parameter an order addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Unit {
    /// A module's own parameters (the SK 550P has none apart from FI 1's, see [`address`]).
    Interface,
    /// An inverter's.
    Inverter(Inverter),
}

/// What a `read`/`write` order addresses, with the parameter's definition where the
/// catalogue has it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Address {
    /// Whose parameter.
    pub(crate) unit: Unit,
    /// The definition.
    pub(crate) def: Option<&'static ParamDef>,
    /// The set: a set-dependent parameter without one is set 1.
    pub(crate) set: Option<ParamSet>,
    /// The element: an array without one is element 1 (sub-index 0 of such a parameter is its
    /// count, BU 0620 §2.2.7 / §2.4.6).
    pub(crate) element: Option<ArrayElement>,
}

/// The address of an order. On the SK 550P the interface is built into FI 1: its parameters
/// (P85x–P89x) are FI 1's objects, for an interface target and for FI 1 alike.
pub(crate) fn address(product: Product, o: &OrderSpec) -> Result<Address, StepError> {
    let integrated = product.family() == proto::nord::Family::Integrated;
    let iface = || params::lookup(product, Owner::Interface, o.number);
    let (unit, def) = match o.target {
        Target::Interface if integrated => (
            Unit::Inverter(Inverter::new(1).map_err(|e| StepError::Suite(e.into()))?),
            iface(),
        ),
        Target::Interface => (Unit::Interface, iface()),
        Target::Inverter(i) => {
            let inv = params::lookup(product, Owner::Inverter, o.number);
            let own = (integrated && i.get() == 1).then(iface).flatten();
            (Unit::Inverter(i), own.or(inv))
        }
    };
    Ok(Address {
        unit,
        def,
        set: o
            .set
            .or_else(|| def.filter(|d| d.set_dependent).and(ParamSet::new(1).ok())),
        element: o.element.or_else(|| {
            def.filter(|d| d.array.is_some())
                .and(ArrayElement::new(1).ok())
        }),
    })
}

/// A parameter's value from the bytes of its object: 16 bits (unsigned where the catalogue's
/// range needs it, `proto::nord::ecat::parameter_data_type`) or 32.
pub(crate) fn value_of(obj: Object, data: &[u8], def: Option<&ParamDef>) -> Result<i64, StepError> {
    Ok(match (data, def.map(parameter_data_type)) {
        ([a, b], Some(DataType::U16)) => i64::from(u16::from_le_bytes([*a, *b])),
        ([a, b], _) => i64::from(i16::from_le_bytes([*a, *b])),
        ([a, b, c, d], _) => i64::from(i32::from_le_bytes([*a, *b, *c, *d])),
        (other, _) => {
            return Err(StepError::Protocol(
                format!(
                    "{obj}: a parameter value of {} bytes (2 or 4 expected)",
                    other.len()
                )
                .into(),
            ))
        }
    })
}

/// The bytes of a `write` order's value for its object: as wide as the parameter's type
/// (16 bits for a parameter the catalogue does not have).
pub(crate) fn bytes_of(o: &OrderSpec, def: Option<&ParamDef>) -> Result<Vec<u8>, StepError> {
    let value = o.value.unwrap_or(0);
    let v = i32::try_from(value)
        .map_err(|_| StepError::Suite(format!("value {value} does not fit 32 bits").into()))?;
    let width = def.map_or(2, |d| parameter_data_type(d).bytes());
    Ok(v.to_le_bytes()[..width].to_vec())
}
