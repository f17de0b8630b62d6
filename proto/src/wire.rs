//! What the codecs of every bus share: the one error type they return ([`Error`]) and the
//! length-checked reader that reports it (`Reader`).
//!
//! A malformed frame means the same thing on every bus (a field runs short, bytes are left
//! over, a length field lies, a code is unknown), so the EtherCAT, POWERLINK, PROFINET,
//! EtherNet/IP, CAN/CANopen and Ethernet codecs say it with the same variants, and the
//! simulator and the harness handle one type. What only one bus can get wrong (a CAN toggle
//! bit, a socketcand message, an SII checksum) has its own variant, named after it.

mod error;
mod reader;

pub use error::Error;
pub(crate) use reader::Reader;
