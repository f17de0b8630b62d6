//! CANopen application layer (CiA 301 "CANopen application layer and communication profile")
//! on CAN 2.0A, as the NORD system bus uses it: COB-IDs of the pre-defined connection set,
//! NMT, heartbeat and node guarding, SYNC, EMCY, and SDO (expedited, segmented, block) with
//! its abort codes. The SDO command byte, the abort codes and the emergency message are
//! CiA 301's wherever they travel, so CANopen over EtherCAT (`ecat::coe`) uses these
//! definitions too.
//!
//! - [`cob_id`]: [`Function`], [`Cob::classify`], the table [`cob_id::PREDEFINED`];
//! - [`nmt`]: [`NmtFrame`], [`NmtState`] with its transition table, [`ErrorControl`];
//! - [`sync`], [`emcy`]: [`SyncFrame`], [`Emergency`];
//! - [`command`]: the SDO command byte, [`SdoFrame`], [`Toggle`]; [`sdo`]: [`SdoRequest`],
//!   [`SdoResponse`]; [`block`]: block transfer commands, [`BlockSegment`], [`SubBlock`];
//!   [`crc`]: the block transfer CRC; [`abort`]: [`SdoAbortCode`];
//! - [`message`]: a CAN frame read as one of these objects.
//!
//! Every parser checks each length and returns [`crate::wire::Error`] naming the field on
//! malformed input (wrong length, unknown command specifier, value out of range); none panics
//! on any byte sequence. Multi-byte fields are little-endian. A device's refusal, an SDO abort,
//! parses to a message, not an error.

pub mod abort;
pub mod block;
pub mod cob_id;
pub mod command;
pub mod crc;
pub mod emcy;
pub mod message;
pub mod nmt;
pub mod no_panic;
pub mod sdo;
pub mod sync;

pub(crate) use abort::abort_codes;
pub use abort::SdoAbortCode;
pub use block::{BlockRequest, BlockResponse, BlockSegment, SubBlock};
pub use cob_id::{Cob, Function};
pub use command::{ClientCommand, SdoFrame, ServerCommand, Toggle};
pub use crc::{crc16, Crc16};
pub use emcy::Emergency;
pub use message::Message;
pub use nmt::{ErrorControl, NmtCommand, NmtFrame, NmtState, StateCode};
pub use sdo::{Abort, Expedited, InitiateData, SdoRequest, SdoResponse, SegmentData};
pub use sync::SyncFrame;
