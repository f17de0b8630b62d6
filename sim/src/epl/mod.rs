//! The POWERLINK controlled node of the NORD interfaces (sans-IO): the SK 550P's integrated
//! interface (BU 0620 §2.4) and the modules SK TU3-POL, SK TU4-POL, SK CU4-POL (BU 2200).
//!
//! What the node is — identity, object dictionary, process map — comes from
//! `proto::nord::epl`, which the XDD writer also reads. A driver feeds whole Ethernet frames
//! to [`Node::receive`] and UDP datagrams of port 3819 to [`Node::udp`], sends what they
//! return, and calls [`Node::poll`] between frames. Time is always an argument.
//!
//! - NMT (BU 0620 §2.4.4, BU 2200 §6.2; DS 301 §7.1.4): NOT_ACTIVE → PRE_OPERATIONAL_1 on a
//!   SoC or SoA of the MN, → BASIC_ETHERNET after the Basic Ethernet timeout without one
//!   (and back to PRE_OPERATIONAL_1 on any POWERLINK frame); PRE_OPERATIONAL_1 →
//!   PRE_OPERATIONAL_2 on a SoC; then the MN's NMT commands; resets back to NOT_ACTIVE; the
//!   loss of the SoC in a cycling state → PRE_OPERATIONAL_1 with the "BE" LED red.
//! - PReq → PRes within the same call (the response time is the driver's); SoA IdentRequest,
//!   StatusRequest and UnspecifiedInvite (queued SDO answers go out on an invitation, as DS
//!   301's asynchronous scheduling wants).
//! - Malformed frames are dropped and counted: the node's state does not change.

mod endpoint;
mod mapping;
mod node;
mod od;
mod sdo;
#[cfg(test)]
mod tests;

pub use node::{Node, NodeConfig, NodeError, POLL_PERIOD};
