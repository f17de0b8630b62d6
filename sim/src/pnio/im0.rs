//! The device's I&M0 record (index AFF0h at the DAP: slot 0, subslot 1): who it is, for a
//! controller or an engineering tool. The manuals list I&M among the functions of every
//! conformance class (BU 0620 §2.5.3) and print none of its values: the vendor and device ids
//! are the DCP ones (`proto::nord::pnio`), the OrderID the type of station, the serial number
//! the MAC address in hex, the software revision the simulator's own.

use proto::eth::MacAddr;
use proto::nord::pnio as def;
use proto::nord::Product;
use proto::pnio::im0::{Im0Repr, SoftwareRevision};
use proto::pnio::status::pniorw;
use proto::pnio::PnioStatus;

/// The simulator's firmware revision as I&M0 gives it.
const SOFTWARE_REVISION: SoftwareRevision = SoftwareRevision {
    prefix: b'V',
    functional: 1,
    bug_fix: 0,
    internal: 0,
};

/// The DAP's slot and subslot, where I&M0 is read.
const DAP: (u16, u16) = (0, 1);

/// The record data of an I&M0 read at `slot`/`subslot`, or the status that refuses it
/// ("invalid slot/subslot" anywhere but the DAP: no other submodule carries its own I&M0).
pub(super) fn read(
    product: Product,
    mac: MacAddr,
    slot: u16,
    subslot: u16,
) -> Result<Vec<u8>, PnioStatus> {
    if (slot, subslot) != DAP {
        return Err(PnioStatus::record(false, pniorw::INVALID_SLOT));
    }
    let im = Im0Repr {
        vendor_id: def::VENDOR_ID,
        order_id: def::station_type(product).unwrap_or(product.name()).into(),
        serial: mac.0.iter().map(|b| format!("{b:02X}")).collect(),
        hardware_revision: 1,
        software_revision: SOFTWARE_REVISION,
        revision_counter: 0,
        profile_id: 0,
        profile_specific_type: 0,
        version: (1, 1),
        supported: 0,
    };
    im.emit()
        .map_err(|_| PnioStatus::record(false, pniorw::READ_ERROR))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dap_answers_its_identity_and_other_subslots_refuse() {
        let mac = MacAddr([0x00, 0x0E, 0xCF, 0x03, 0x60, 0x00]);
        let im = Im0Repr::parse(&read(Product::Tu3Pnt, mac, 0, 1).unwrap()).unwrap();
        assert_eq!(im.vendor_id, def::VENDOR_ID);
        assert_eq!(im.serial, "000ECF036000");
        assert_eq!(im.software_revision.to_string(), "V1.0.0");
        assert_eq!(
            read(Product::Tu3Pnt, mac, 3, 1),
            Err(PnioStatus::record(false, pniorw::INVALID_SLOT))
        );
    }
}
