//! Raw Ethernet on a named network interface, for the buses that run on Ethernet frames
//! rather than IP (EtherCAT now, POWERLINK and PROFINET RT next): open an interface with an
//! EtherType filter, send a frame, receive the next one by a deadline, with the kernel's
//! receive stamp.

pub(crate) mod driver;
mod error;
pub(crate) mod held;
mod iface;
pub(crate) mod inject;
mod link;
pub mod misbehave;
pub(crate) mod peer;
pub(crate) mod raw_port;
pub(crate) mod serve_args;
pub(crate) mod serve_error;
pub(crate) mod udp;
#[cfg(test)]
pub(crate) mod veth;
pub(crate) mod wait;
pub(crate) mod workers;

pub(crate) use error::timed_out;
pub use error::LinkError;
#[allow(unused_imports)] // the module's API, not all of it used yet
pub(crate) use iface::{interface, Interface, Mac};
#[allow(unused_imports)]
pub(crate) use link::{RawLink, Ready, Received, MAX_FRAME};
