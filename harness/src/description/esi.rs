//! An EtherCAT ESI as the harness reads it (ETG.2000): the vendor, the first device's type
//! (product code, revision, name), its SyncManagers and whether it declares CoE.

use super::xml::{number, Element};
use super::{missing, DescriptionError, Identity};

/// One SyncManager as declared: its kind (`MBoxOut`, `MBoxIn`, `Outputs`, `Inputs`), start
/// address and default size.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Sm {
    pub(crate) kind: String,
    pub(crate) start: Option<u16>,
    pub(crate) size: Option<u16>,
}

/// What the harness takes from an ESI.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Esi {
    pub(crate) identity: Identity,
    pub(crate) sms: Vec<Sm>,
    /// The device declares CoE in its mailbox.
    pub(crate) coe: bool,
}

/// Reads an ESI's root element (the first device of its `Devices`).
pub(crate) fn parse(root: &Element, file: &str) -> Result<Esi, DescriptionError> {
    let vendor = root
        .child("Vendor")
        .and_then(|v| v.child("Id"))
        .and_then(|i| number(&i.text))
        .map(|v| v as u32);
    let device = root
        .find("Device")
        .ok_or_else(|| missing(file, "Devices/Device"))?;
    let ty = device
        .child("Type")
        .ok_or_else(|| missing(file, "Device/Type"))?;
    let identity = Identity {
        vendor,
        product: ty.attr("ProductCode").and_then(number).map(|v| v as u32),
        revision: ty.attr("RevisionNo").map(str::to_string),
        name: Some(ty.text.trim().to_string()).filter(|t| !t.is_empty()),
    };
    let sms = device
        .children("Sm")
        .map(|s| Sm {
            kind: s.text.trim().to_string(),
            start: s.attr("StartAddress").and_then(number).map(|v| v as u16),
            size: s.attr("DefaultSize").and_then(number).map(|v| v as u16),
        })
        .collect();
    let coe = device
        .child("Mailbox")
        .is_some_and(|m| m.child("CoE").is_some());
    Ok(Esi { identity, sms, coe })
}
