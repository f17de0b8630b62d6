//! Ethernet POWERLINK V2 (EPSG DS 301, IEC 61158-4/-6-13) on the wire: the frames a Managing
//! Node (MN) and a Controlled Node (CN) exchange, carried in Ethernet II frames of EtherType
//! 88ABh ([`crate::eth::ETHERTYPE_POWERLINK`]) and, for SDO over UDP/IP, in UDP datagrams to
//! port 3819 ([`SDO_UDP_PORT`]).
//!
//! BU 0620 §2.4.3 and BU 2200 §3.3 (German) name the frame: "DA, SA, Type (0x88AB), MT, DN, SN,
//! application data (min. 3, max. 1475 bytes), pad" and the five message types (SoC 01h, PReq
//! 03h, PRes 04h, SoA 05h, ASnd 06h); the layouts of each type's body, the NMT states and
//! commands, the ASnd services and the SDO sequence and command layers are DS 301's (§4.6 data
//! link layer frames, §7 network management, §6.3 SDO), which the manuals refer to ("The error
//! codes correspond to the POWERLINK standard EPSG DS-301", BU 0620 §2.4.7).
//!
//! - [`frame`]: the common header and the bodies of SoC, PReq, PRes, SoA and ASnd;
//! - [`nmt`]: NMT state codes, NMT commands, SoA requested services, ASnd service ids;
//! - [`asnd`]: IdentResponse, StatusResponse (with the error history entries), NMT command and
//!   NMT request;
//! - [`sdo`]: the SDO sequence layer and command layer, over ASnd and over UDP.
//!
//! Every parser returns `Err` on malformed input and never panics ([`crate::wire::Error`]
//! names the field). All multi-byte fields are little-endian except the IP addresses of the
//! IdentResponse, which are in network order as DS 301 prints them.

pub mod asnd;
pub mod frame;
pub mod nmt;
pub mod no_panic;
pub mod sdo;

pub use frame::{EplFrame, EplRepr, MessageType};
pub use nmt::{NmtCommand, NmtState, RequestedService, ServiceId};

use crate::eth::MacAddr;

/// UDP port of POWERLINK frames over UDP/IP (DS 301 C_SDO_EPL_PORT = 3819).
pub const SDO_UDP_PORT: u16 = 3819;

/// Node id of the Managing Node (C_ADR_MN_DEF_NODE_ID, BU 0620 §2.4.3.1: 240).
pub const MN_NODE_ID: u8 = 240;
/// The broadcast node id (C_ADR_BROADCAST, 255).
pub const BROADCAST_NODE_ID: u8 = 255;

/// Multicast destination of SoC frames (DS 301 C_DLL_MULTICAST_SOC).
pub const MULTICAST_SOC: MacAddr = MacAddr([0x01, 0x11, 0x1E, 0x00, 0x00, 0x01]);
/// Multicast destination of PRes frames (C_DLL_MULTICAST_PRES).
pub const MULTICAST_PRES: MacAddr = MacAddr([0x01, 0x11, 0x1E, 0x00, 0x00, 0x02]);
/// Multicast destination of SoA frames (C_DLL_MULTICAST_SOA).
pub const MULTICAST_SOA: MacAddr = MacAddr([0x01, 0x11, 0x1E, 0x00, 0x00, 0x03]);
/// Multicast destination of ASnd frames (C_DLL_MULTICAST_ASND).
pub const MULTICAST_ASND: MacAddr = MacAddr([0x01, 0x11, 0x1E, 0x00, 0x00, 0x04]);

/// The shortest POWERLINK body after the Ethernet header: message type, destination, source
/// (BU 0620 §2.4.3: "application data min. 3 byte").
pub const HEADER_LEN: usize = 3;
/// The longest POWERLINK body (BU 0620 §2.4.3 figure 8: application data max. 1475 bytes
/// after MT, DN, SN... which with the 3 header bytes is 1478 — DS 301 C_DLL_MAX_PAYL_OFFSET
/// 1499 bytes; the Ethernet MTU bounds it).
pub const MAX_LEN: usize = 1500;
