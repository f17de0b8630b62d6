//! PROFINET IO (IEC 61158-5-10 / -6-10, IEC 61784-2 CP 3/4) on the wire: what an IO controller
//! and an IO device exchange.
//!
//! BU 0620 §2.5.3 names the frame: Ethernet II with EtherType 8892h
//! ([`crate::eth::ETHERTYPE_PROFINET`]), a frame id, the data and a status; the layouts are the
//! standard's, which the manuals refer to ("PROFINET IO is specified in the standards IEC 61158
//! and IEC 61784", BU 0620 §2.5.1):
//!
//! - `dcp`: Discovery and basic Configuration (Identify, Get, Set, Hello) with its blocks;
//! - `rt`: RT class 1 frames: the cyclic data with IOxS, cycle counter, data and transfer
//!   status;
//! - `alarm`: the RTA-PDU of the alarm CR and the alarm notification / acknowledge blocks;
//! - `rpc`: the connectionless DCE/RPC header (UDP 34964) and the NDR header of PNIO calls;
//! - `block`: the PNIO-CM blocks (AR, IOCR, Alarm CR, ExpectedSubmodule, ModuleDiff, the
//!   IODRead/IODWrite headers, IODControl) and the PNIO status;
//! - `im0`: the I&M0 identification record;
//! - `plan`: the cyclic layout a controller's Connect gives (frame offsets of the IOCRs).
//!
//! Every parser returns `Err` on malformed input and never panics ([`crate::wire::Error`]
//! names the field). PROFINET fields are big-endian (network order) except the DCE/RPC
//! header, whose byte order its data representation field gives.

pub mod alarm;
pub mod block;
pub mod dcp;
pub mod frame;
pub mod im0;
pub mod no_panic;
pub mod plan;
pub mod rpc;
pub mod rt;
pub mod status;

pub use frame::{FrameId, FrameKind, PnRepr};
pub use status::PnioStatus;

use crate::eth::MacAddr;

/// UDP port of the PNIO-CM RPC endpoint (IANA "profinet-cm", 34964).
pub const RPC_PORT: u16 = 34964;

/// Destination of DCP Identify requests (IEC 61158-6-10 "PN-MC-Identify": 01-0E-CF-00-00-00).
pub const MULTICAST_DCP_IDENTIFY: MacAddr = MacAddr([0x01, 0x0E, 0xCF, 0x00, 0x00, 0x00]);
/// Destination of DCP Hello requests (01-0E-CF-00-00-01).
pub const MULTICAST_DCP_HELLO: MacAddr = MacAddr([0x01, 0x0E, 0xCF, 0x00, 0x00, 0x01]);
