//! The end of a case on a PROFINET device on the network ([`crate::binding::ledger`]): the parameters
//! the case wrote are written back, the drives it ran are brought back to "Switch-on block",
//! a name of station or IP suite it set by DCP is set back, and the AR is released, so that
//! the next case connects to the device as this one found it.
//!
//! The way back runs in a fresh AR with the default module in every inverter's slot (the case
//! may have connected with other modules, or lost its AR on purpose): the drives settle over
//! its cyclic data, the parameters go back through the records.

use std::fmt;

use proto::nord::{ArrayElement, Inverter, ParamNumber, ParamSet, Product};
use proto::pnio::dcp::{BlockError, BlockQualifier, BlockValue, DcpBlock, IpParameter};

use super::binding::{module_bytes, module_ppo, module_pzd};
use super::controller::{Controller, PnioError, Station};
use super::link::Link;
use crate::binding::settle::Cycling;
use crate::outcome::Exchange;
use crate::suite::{OrderSpec, Target};

/// A parameter a case wrote: the ledger's key.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Param {
    pub(super) target: Target,
    pub(super) number: ParamNumber,
    pub(super) set: Option<ParamSet>,
    pub(super) element: Option<ArrayElement>,
    /// Written to EEPROM (labels 2/3/7/8) or RAM only (11–14): written back the same way.
    pub(super) eeprom: bool,
}

impl Param {
    pub(super) fn of(o: &OrderSpec) -> Param {
        Param {
            target: o.target,
            number: o.number,
            set: o.set,
            element: o.element,
            eeprom: o.eeprom,
        }
    }

    /// The read of its value.
    pub(super) fn read(&self) -> OrderSpec {
        OrderSpec {
            set: self.set,
            element: self.element,
            eeprom: self.eeprom,
            ..OrderSpec::read(self.target, self.number)
        }
    }

    /// The write of `value`.
    pub(super) fn write(&self, value: i64) -> OrderSpec {
        OrderSpec {
            value: Some(value),
            ..self.read()
        }
    }
}

impl fmt::Display for Param {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "P{}", self.number.get())?;
        if let Some(e) = self.element {
            write!(f, " [-{:02}]", e.get())?;
        }
        if let Some(s) = self.set {
            write!(f, " set {}", s.get())?;
        }
        match self.target {
            Target::Interface => write!(f, " of the interface"),
            Target::Inverter(i) => write!(f, " of FI {}", i.get()),
        }
    }
}

/// A value as the ledger keeps it.
pub(super) fn value_bytes(v: i64) -> Vec<u8> {
    v.to_le_bytes().to_vec()
}

/// The value the ledger kept.
pub(super) fn value_of(bytes: &[u8]) -> i64 {
    let mut b = [0u8; 8];
    let n = bytes.len().min(8);
    b[..n].copy_from_slice(&bytes[..n]);
    i64::from_le_bytes(b)
}

/// DCP Sets back the name of station and IP suite the device had when the run found it, where
/// they differ now (the AR released: a device in operation refuses them).
pub(super) fn station<L: Link>(ctl: &mut Controller<L>, was: &Station) -> Result<(), String> {
    // After a DCP Set the controller did not follow the device is asked as it is now (DCP
    // Identify): its view may be stale, as when a device takes an IP suite it answered with a
    // refusal (p-net, docs/interop.md) or was reset to factory.
    let seen = match ctl.take_unsure() {
        true => ctl
            .identify(None)
            .ok()
            .and_then(|all| all.into_iter().find(|s| s.mac == was.mac)),
        false => None,
    };
    let Some(now) = seen.or_else(|| ctl.station().cloned()) else {
        return Ok(());
    };
    let mut problems = Vec::new();
    let mut set = |ctl: &mut Controller<L>, what: &str, value: BlockValue| match ctl
        .dcp_set(DcpBlock::set(BlockQualifier::PERMANENT, value))
    {
        Ok(BlockError::OK) => {}
        Ok(e) => problems.push(format!("setting the {what} back: DCP error {:02X}h", e.0)),
        Err(e) => problems.push(format!("setting the {what} back: {e}")),
    };
    if now.name != was.name {
        set(
            ctl,
            "name of station",
            BlockValue::NameOfStation(was.name.clone()),
        );
    }
    if let (Some(ip), true) = (was.ip, now.ip != was.ip) {
        let value = BlockValue::IpParameter(IpParameter {
            ip: ip.ip,
            mask: ip.mask,
            gateway: ip.gateway,
        });
        set(ctl, "IP suite", value);
    }
    match problems.is_empty() {
        true => Ok(()),
        false => Err(problems.join("; ")),
    }
}

/// The cyclic data of the way back: every inverter's module, each with its words.
pub(super) struct Settling<'a, L> {
    pub(super) ctl: &'a mut Controller<L>,
    pub(super) product: Product,
    pub(super) words: Vec<(Inverter, [u16; 6])>,
}

impl<L: Link> Settling<'_, L> {
    fn slot(&self, fi: Inverter) -> Result<u16, PnioError> {
        proto::nord::pnio::inverter_slot(self.product, fi).map_err(|e| PnioError::Malformed {
            what: "inverter slot",
            error: e.to_string(),
        })
    }
}

impl<L: Link> Cycling for Settling<'_, L> {
    type Error = PnioError;

    fn run_cycles(&mut self, n: u64) -> Result<(), PnioError> {
        let mut data = Vec::new();
        for (fi, words) in &self.words {
            let slot = self.slot(*fi)?;
            if let Some(t) = module_ppo(self.ctl, self.product, slot) {
                data.push((slot, module_bytes(t, words)));
            }
        }
        let modules: Vec<(u16, &[u8])> = data.iter().map(|(s, b)| (*s, &b[..])).collect();
        self.ctl.provide(&modules)?;
        for _ in 0..n {
            self.ctl.exchange_cycle()?;
        }
        Ok(())
    }

    fn take_exchanges(&mut self) -> Vec<Exchange> {
        self.ctl.take_exchanges()
    }

    fn set_recording(&mut self, on: bool) {
        self.ctl.set_recording(on);
    }

    fn set_words(&mut self, fi: Inverter, words: [u16; 6]) -> Result<(), PnioError> {
        match self.words.iter_mut().find(|(f, _)| *f == fi) {
            Some((_, w)) => *w = words,
            None => self.words.push((fi, words)),
        }
        Ok(())
    }

    fn status_word(&mut self, fi: Inverter) -> Result<u16, PnioError> {
        let slot = self.slot(fi)?;
        let no_input = || PnioError::NoInput;
        let t = module_ppo(self.ctl, self.product, slot).ok_or_else(no_input)?;
        let (data, _) = self.ctl.input(slot).ok_or_else(no_input)?;
        let pzd = module_pzd(t, &data).ok_or_else(no_input)?;
        Ok(pzd.first().copied().unwrap_or(0))
    }
}
