//! The NORD system bus — CANopen on CAN between a bus interface and its inverters — as the
//! manuals state it: bit rate, addresses, participants, update cycle, monitoring, error codes
//! and the commissioning examples. Pure data and functions, no I/O.
//!
//! Sources (pages from each manual's table of contents, BU 2200's from its page footers):
//! - BU 0620 §2.1 (p. 14–15), §2.5.1 (p. 39), §2.5.3 (p. 44–45), §3.1 (p. 61–62), §3.9
//!   (p. 73–75), §4.3 (p. 84), §4.5 (p. 90–91), §5.1 (p. 92), §5.3 (p. 94), §5.5.1.2 (p. 100):
//!   the SK 550P as FI 1 and up to seven SK 5x0P behind it.
//! - BU 2100 §4 (p. 18–22), §5.3 (p. 28–29), §6.2.5 (p. 39), §7.1.1 (p. 46), §7.1.3 (p. 50–51),
//!   §7.2 (p. 54–55), §8.1 (p. 56–57), §8.3 (p. 59); BU 2200 (German) the same sections at
//!   §4 (p. 19–20), §5.3 (p. 27–28), §6.3.4 (p. 38), §7.1.1 (p. 49), §7.1.3 (p. 54), §7.2
//!   (p. 59–60), §8.1 (p. 61), §8.4 (p. 67); BU 0590 §5.2.1 (p. 38), §6.3 table 29 (p. 44).
//!
//! Not stated by the manuals — CANopen needs it, so a choice is made here and named as one
//! (none of it is a NORD fact; a real device may differ):
//! - COB-IDs: the CiA 301 pre-defined connection set ([`crate::canopen::cob_id`]).
//! - PDO layout: each inverter is its own node; its six process-data words (control word and
//!   setpoints 1…5 to the FI, status word and actual values 1…5 from it) are entries 1…6 of
//!   the objects the project's EtherCAT layout gives FI 1 (7000h outputs, 6000h inputs,
//!   `nord::ecat::outputs_index`), four words in PDO 1 and two in PDO 2 ([`pdo_words`]).
//! - SDO access to a parameter: index 2000h + P in the inverter's own dictionary, sub-index as
//!   under EtherCAT (`nord::ecat::PARAMETER_BASE`, `nord::addr::sdo_subindex`); the node-ID
//!   chooses the inverter, so the EtherCAT device offset 800h·(FI−1) drops out
//!   ([`parameter_sdo`]).
//! - Node monitoring: BU 0620 §5.3 names both "NodeGuard" (7582h) and "HeartBeat" (7583h)
//!   time-outs; which one the interface uses is not said. Choice: CiA 301 heartbeat.
//! - The interface's own node-ID: fixed and not settable, its value not printed
//!   ([`INTERFACE_NODE_ID_CHOICE`]); the addresses of I/O extensions (SK xU4-IOE).
//! - The bits of P748 "CANopen status" ([`P748`]: here the NMT state); P514's values other
//!   than 5; which telegram P120 watches, for how long, and what P120 = 1 "Auto" waits for
//!   ([`InterfaceWatch`]: the interface's heartbeat, 600 ms, from the first one seen). The
//!   manuals refer to the inverter manuals (BU 0600, BU 0200, BU 0500).
//!
//! Errata of the manuals kept here (the code holds the right value):
//! - BU 0620 §3.1 (p. 61) prints the further inverters' CAN IDs "34, 36, 37, 38, 40, 42, 44,
//!   and 46": 37 is the encoder of the FI at 36; the matrix and §4.5 ("34, 36, 38 … 46") step
//!   by 2 ([`SystemBusAddress::inverter`]).
//! - BU 2100 §7.2 (p. 54) gives the SK TU3 columns P515 "32, 34, 36 oder 38"; the SK TU3-EIP
//!   serves 8 inverters at 32…46 (its own §4.3 table, p. 22; BU 2200 §7.2: "32, 34, …46")
//!   ([`p515_addresses`]).
//! - BU 2100 §8.1 (p. 56) loses the last inverter column ("SK 54xE") of the SK TU3 "via
//!   CANopen" group from its header, so its six values stand under five columns; BU 2200 §8.1
//!   (p. 61) prints all six: the "—⁴⁾ automatic" belongs to an SK TU3 and the FI it is mounted
//!   on, not to SK 54xE ([`system_bus_watch`]).
//! - BU 0620 §5.1 (p. 92) calls P513 "Off" the setting that ignores all communication errors;
//!   BU 2200 §8.1 (p. 61) and BU 0590 §5.2.1 (p. 38) give −0.1 "no error" for that and 0.0
//!   "Off" for monitoring switched off (BU 2100 §8.1 prints "0,1", its minus sign lost)
//!   ([`P513_NO_ERROR`]).
//! - BU 2100 §7.1.1 (p. 45), P151's footnote "Error E10.8 = No Ethernet connection": no row of
//!   its table gives E10.8 (a cut Ethernet cable gives E10.5), and §8.3 (p. 59) makes 10.8 the
//!   SK TU3-EIP's system-bus connection timeout (10.6 the bus cable fault) ([`FI_ERRORS`]).
//! - BU 0620 names E10.9 for the system-bus monitoring (§5.5.1.2 p. 100, §5.4.1.2 8111h) but its
//!   error table (§5.3 p. 94) ends at 10.8; its meaning is BU 2100's and BU 2200's.
//! - BU 2100 §4.3 (p. 22) footnote: "the shortest possible cycle … is 5 ms for each frequency
//!   inverter" against its table (8 FIs 10 ms); its 6.5 ms and 5.25 ms rows break the table's
//!   1.25 ms step ([`update_cycle`], `nord::eip::tu3_update_cycle_us`).

mod address;
mod cia301;
mod monitoring;
mod settings;
mod timing;

pub use address::*;
pub use cia301::*;
pub use monitoring::*;
pub use settings::*;
pub use timing::*;

use super::product::Product;
use super::types::{Inverter, RangeError};

/// Why a system-bus value cannot be formed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CanError {
    /// A number outside its range.
    #[error(transparent)]
    Range(#[from] RangeError),
    /// The product does not reach that many inverters.
    #[error("{product} reaches FI 1..{max}, not FI {inverter}")]
    NoSuchInverter {
        /// Product name.
        product: &'static str,
        /// The inverter asked for.
        inverter: u8,
        /// The product's maximum.
        max: u8,
    },
    /// P515 holds another address than the one the manuals assign the inverter.
    #[error("P515 [-01] of FI {inverter} must be {expected}, not {got}")]
    WrongAddress {
        /// The inverter.
        inverter: u8,
        /// 32 + 2·(FI−1).
        expected: u8,
        /// The value found.
        got: i64,
    },
    /// The product is not mounted on or connected to that inverter series.
    #[error("{product} does not serve {series:?}")]
    NotServed {
        /// Product name.
        product: &'static str,
        /// The series asked for.
        series: InverterSeries,
    },
}

fn check_inverter(product: Product, fi: Inverter) -> Result<(), CanError> {
    let max = product.max_inverters();
    if fi.get() > max {
        return Err(CanError::NoSuchInverter {
            product: product.name(),
            inverter: fi.get(),
            max,
        });
    }
    Ok(())
}

fn serves(product: Product, series: InverterSeries) -> Result<(), CanError> {
    if inverter_series(product).contains(&series) {
        Ok(())
    } else {
        Err(CanError::NotServed {
            product: product.name(),
            series,
        })
    }
}
