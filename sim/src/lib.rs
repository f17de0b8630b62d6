//! The device side: NORD inverters behind a bus interface, speaking real telegrams.
//!
//! Sans-IO: the [`device::Device`] is fed link frames and the current time and returns the
//! frames to send; drivers (the in-memory link of the embedded run, sockets when served) own the
//! I/O. Time comes from a [`clock::Clock`]: virtual in tests (deterministic, instant), real when
//! served.

mod bus_status;
pub mod can;
pub mod clock;
pub mod device;
pub mod drive;
pub mod ecat;
pub mod endpoint;
pub mod enip;
pub mod epl;
pub mod link;
mod objects;
mod pdo_image;
pub mod pkw_server;
pub mod pnio;
mod sdo_server;
pub mod store;
mod system_bus;
