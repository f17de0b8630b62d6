//! The SK 550P's integrated EtherCAT interface as a slave (sans-IO): an EtherCAT Slave
//! Controller (registers, process RAM, SyncManagers, FMMUs, SII EEPROM, watchdog) and its
//! application (AL state machine, mailbox with CoE SDO server, process data to the inverters).
//!
//! BU 0620 §2.2 (EtherCAT basics), §3.6 (setting up), §4.2.1 (P850 "Second Address"), §4.3
//! (P870, P872–P874), §5.5.2.1 (RUN/ERR LEDs); ETG.1000.4 (data link), ETG.1000.6 (application
//! layer: AL states and status codes, mailbox, CoE), ETG.1020 (explicit device ID), ETG.2010
//! (SII). What the device is — identity, SyncManagers, PDOs, objects — comes from
//! `proto::nord::ecat`, the same definition the SII image and the ESI file are made from.
//!
//! A driver feeds whole Ethernet frames to [`Slave::process`], which processes each EtherCAT
//! frame in place ("on the fly") and says whether to send it back, and calls [`Slave::poll`]
//! with the time between frames. Time is always an argument.

mod al;
mod coe;
mod endpoint;
mod esc;
mod mailbox;
pub(crate) mod od;
pub(crate) mod pdo;
mod sii;
mod slave;
mod sm;
#[cfg(test)]
mod tests;

pub use slave::{DropReason, Processed, Slave, SlaveConfig, SlaveError, POLL_PERIOD};

/// EtherType of EtherCAT (ETG.1000.4 §5.3; BU 0620 §2.2.3 figure 3 prints 88ABh, an erratum).
pub const ETHERTYPE: u16 = proto::eth::ETHERTYPE_ECAT;
