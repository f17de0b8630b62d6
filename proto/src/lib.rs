//! The NORD DRIVESYSTEMS bus-interface manuals as code.
//!
//! Pure functions and types, no I/O, no clock: the simulator (`sim`) and the tester (`harness`)
//! share this vocabulary so that both sides speak the manuals' terms.
//!
//! Every parser in this crate returns `Err` on malformed input; none panics on any byte
//! sequence.

pub mod can;
pub mod canopen;
pub mod ecat;
pub mod enip;
pub mod epl;
pub mod eth;
pub mod lldp;
pub mod nord;
pub mod pnio;
pub mod wire;
