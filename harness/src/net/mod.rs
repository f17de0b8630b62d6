//! Raw Ethernet on a named network interface, for the buses that run on Ethernet frames
//! rather than IP (EtherCAT now, POWERLINK and PROFINET RT next): open an interface with an
//! EtherType filter, send a frame, receive the next one by a deadline, with the kernel's
//! receive stamp.

// Used by `harness serve ecat` (next): until then nothing calls it outside its tests.
#![allow(dead_code, unused_imports)]

mod error;
mod iface;
mod link;

pub(crate) use error::LinkError;
pub(crate) use iface::{interface, Interface, Mac};
pub(crate) use link::{RawLink, Received};
