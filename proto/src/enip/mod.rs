//! EtherNet/IP and CIP wire formats (BU 0620 §2.3, BU 2100 §3, §6).
//!
//! Each structure has a `parse` that checks every length and returns [`crate::wire::Error`]
//! on malformed input, and an `emit`; the encapsulation header also has a checked view
//! ([`encap::EncapFrame`]). Byte order is CIP's little-endian throughout, except the socket
//! address item (network order).

pub mod cip;
pub mod cm;
pub mod cpf;
pub mod encap;
pub mod epath;
pub mod identity;
pub mod io;
pub mod no_panic;
mod wire;
