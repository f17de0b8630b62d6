//! EtherCAT wire formats (IEC 61158 type 12 = ETG.1000: .3 data link services, .4 data link
//! protocol, .6 application layer; ETG.2010 SII; CiA 301 for the SDO protocol CoE carries;
//! BU 0620 §2.2 for the SK 550P's use of them).
//!
//! - [`frame`]: the EtherCAT header and the datagram walk; [`datagram`]: commands, addressing,
//!   working counter, writable in place for a slave.
//! - [`register`]: the ESC registers a master needs, SyncManager and FMMU blocks, SII
//!   interface bits; [`al`]: AL control/status and the AL status codes.
//! - [`sii`]: the SII EEPROM image and its categories.
//! - [`mailbox`]: the mailbox header and mailbox error replies; [`coe`]: CoE, SDO, SDO abort
//!   codes, emergencies.
//!
//! Every checked view (`new_checked`) and every `parse` checks each length and returns
//! [`crate::wire::Error`] naming the field on malformed input; none panics on any byte
//! sequence. Byte order is little-endian throughout.

pub mod al;
pub mod coe;
pub mod datagram;
pub mod frame;
pub mod mailbox;
pub mod register;
pub mod sii;
mod wire;

pub mod no_panic;

pub use datagram::{Command, Datagram, DatagramRepr};
pub use frame::{EcatFrame, EcatFrameRepr, ECAT_UDP_PORT};
