//! The NORD PROFINET IO devices as the manuals define them: the SK 550P's integrated interface
//! (BU 0620 §2.5, §3.4, §3.8, §4.2.4, §4.4.3, §5.4.2, §5.5.2.4) and the SK TU3-PNT bus module
//! (BU 0590). Identity, slot layout, the modules of the PPO types, the data records and their
//! targets, device-name and IP rules, alarm numbers, what a lost controller raises and the LEDs
//! per state. Pure data and functions: the simulator's IO device, the harness's IO controller
//! and the GSDML writer are made from this one definition. No I/O; nothing here panics.
//!
//! What the manuals leave out, and what is used instead (said once, here):
//! - **Vendor id and device ids.** Neither manual prints them (BU 0620 §3.4 sends the reader to
//!   www.nord.com for the device description; BU 0590 §3.3 names only the GSDML file). No
//!   public list searched (PI member lists are not public; p-net, Wireshark and the
//!   OpenCommissioning device-id list hold no NORD entry) gives them. [`VENDOR_ID`] is NORD's
//!   manufacturer code of BU 0620 §2.2.7/§3.6.1 (00000538h, CANopen/EtherCAT), which fits the
//!   16 bits of a PROFINET vendor id; device ids are 0550h (SK 550P) and 0590h (SK TU3-PNT,
//!   after its manual as `epl::product_code` does for POWERLINK). Placeholders, not PI's.
//! - **DAP ident numbers.** Module 00000001h, submodule 00000001h in subslot 1, interface
//!   00008000h in subslot 8000h, ports 00008001h/00008002h in 8001h/8002h (the convention of
//!   IEC 61158-6-10 subslot numbering, as p-net's DAP uses). Both products have two ports
//!   (BU 0620 §2.5.3 "integrated switch with two ports"; BU 0590 §3.2.1 "both RJ45 sockets …
//!   connected via a switch").
//! - **I/O module ident numbers** are the values the PPO-type parameters display: BU 0590
//!   §5.1.4 says P180 shows "the module ID (see gsdml file)" (3 = PPO3 … 7 = PPO2, 2 = DIG-IO);
//!   the SK 550P's P879 (BU 0620 §4.4.3) uses the same order shifted by 3 (6 = PPO3 … 10 =
//!   PPO2, 3 = empty slot), taken as its module ids too. Each module has one submodule in
//!   subslot 1 with the module's ident number.
//! - **The DIG-IO module** of the SK TU3-PNT (slot 2, "process data for the TU") is one word
//!   each way (P176 [-01] / P177 [-01] are one word each); the manual gives no size.
//! - **"Read Response (−)"** (BU 0620 §2.5.6.1, BU 0590 §4.2.1): the PNIO status of a read while
//!   the parameter order is still processed is DE 80 B5 00 (IODReadRes, PNIORW, "state
//!   conflict"), as PROFIdrive devices answer a read before their response is ready.
//!
//! Errata this module follows the correct value of (see /work/brief/pnio-facts.md):
//! - BU 0620 §3.8.1 prints a device name of at most 127 characters; P854 (§4.2.4), BU 0590
//!   P162 and IEC 61158-6-10 give 240 ([`STATION_NAME_MAX`]).
//! - BU 0590 §5.1.2 P163 example "Trigger alarm with error 5.0 on Slot 2: P163[-04] = 50": by
//!   the same entry's element list [-04] is slot 3 (the FI) ([`test_alarm_slot`]).
//! - BU 0590 §4.2.2 "The data records are written to Slot 0" against §4.2.1 and Fig. 11 (TU
//!   parameters in slot 2, FI parameters in slot 3): all three slots take the records.
//! - BU 0590 §4.2.2.2 calls record 47 "compliant with the ProfiDrive profile"; its 11-byte
//!   layout is NORD's own (no number of parameters, attribute, format), and PROFIdrive over
//!   PROFINET uses indices B02Eh/B02Fh. [`Record47Repr`] follows the manual's table 20.

mod alarms;
mod naming;
mod records;
mod slots;

pub use alarms::*;
pub use naming::*;
pub use records::*;
pub use slots::*;

use super::product::{Product, Protocol};
use crate::pnio::PnioStatus;

/// PROFINET vendor id used for both products (placeholder: see the module documentation).
pub const VENDOR_ID: u16 = 0x0538;

/// The value of P899 / P870 for PROFINET IO (BU 0620 §3.3, §4.1, §4.3: 1 = PROFINET IO).
pub const BUS_PROTOCOL_CODE: u16 = 1;

/// DCP DeviceRole of both products: IO device (BU 0620 §2.5.1 table "IO Device").
pub const DEVICE_ROLE_IO_DEVICE: u8 = 0x01;

/// What cannot be formed for a product.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PnioError {
    /// The product is no PROFINET IO device.
    #[error("{0} does not speak PROFINET IO")]
    NotProfinet(&'static str),
    /// An inverter the product does not reach.
    #[error("{product} reaches FI 1..{max}, not FI {inverter}")]
    NoSuchInverter {
        /// Product name.
        product: &'static str,
        /// The inverter asked for.
        inverter: u8,
        /// The product's last inverter.
        max: u8,
    },
    /// A record index the device does not have (PNIORW B0h "invalid index").
    #[error("data record {0} is not one of the device's")]
    UnknownRecord(u16),
    /// A slot/subslot that takes no data records (PNIORW B2h "invalid slot/subslot").
    #[error("slot {slot} subslot {subslot:#06X} takes no parameter data records")]
    WrongSlot {
        /// Slot addressed.
        slot: u16,
        /// Subslot addressed.
        subslot: u16,
    },
    /// A record of the wrong length (PNIORW B1h "write length error").
    #[error("data record {index} is {need} bytes, got {got}")]
    BadLength {
        /// The record index.
        index: u16,
        /// Its length.
        need: usize,
        /// Bytes given.
        got: usize,
    },
    /// A record 47 axis other than 0 (SK TU3-PNT) and 1 (FI) (PNIORW B8h "invalid parameter").
    #[error("axis {0} is neither 0 (SK TU3-PNT) nor 1 (frequency inverter)")]
    UnknownAxis(u8),
}

impl PnioError {
    /// The PNIO status a record service answers this refusal with (IEC 61158-6-10 PNIORW).
    pub fn record_status(&self, write: bool) -> PnioStatus {
        use crate::pnio::status::pniorw;
        let code1 = match self {
            PnioError::WrongSlot { .. } => pniorw::INVALID_SLOT,
            PnioError::BadLength { .. } => pniorw::WRITE_LENGTH,
            PnioError::UnknownAxis(_) => pniorw::INVALID_PARAMETER,
            _ => pniorw::INVALID_INDEX,
        };
        PnioStatus::record(write, code1)
    }
}

fn profinet(product: Product) -> Result<(), PnioError> {
    if product.protocols().contains(&Protocol::Profinet) {
        Ok(())
    } else {
        Err(PnioError::NotProfinet(product.name()))
    }
}

/// Device id (placeholder: see the module documentation); `None` for non-PROFINET products.
pub fn device_id(product: Product) -> Option<u16> {
    match product {
        Product::Sk550p => Some(0x0550),
        Product::Tu3Pnt => Some(0x0590),
        _ => None,
    }
}

/// The product as DCP's DeviceVendorValue ("type of station") and the GSDML name it.
pub fn station_type(product: Product) -> Option<&'static str> {
    match product {
        Product::Sk550p => Some("NORDAC PRO SK 550P"),
        Product::Tu3Pnt => Some("SK TU3-PNT"),
        _ => None,
    }
}

/// The GSDML file the manual names: BU 0590 §3.3 (p. 15); BU 0620 §3.4 (p. 64) names none.
pub fn gsdml_file_name(product: Product) -> Option<&'static str> {
    match product {
        Product::Tu3Pnt => Some("GSDML-V2.2-NORD DRIVESYSTEMS-TU3PNT-20110606.xml"),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identity_of_both_products() {
        assert_eq!(device_id(Product::Sk550p), Some(0x0550));
        assert_eq!(device_id(Product::Tu3Pnt), Some(0x0590));
        assert_eq!(device_id(Product::Tu3Eip), None);
        // BU 0590 §3.3 p. 15: the GSDML file name.
        assert!(gsdml_file_name(Product::Tu3Pnt)
            .unwrap()
            .contains("TU3PNT-20110606"));
        assert_eq!(gsdml_file_name(Product::Sk550p), None);
        assert_eq!(station_type(Product::Tu3Pnt), Some("SK TU3-PNT"));
    }
}
