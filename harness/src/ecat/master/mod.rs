//! The EtherCAT master of the harness (BU 0620 §2.2; ETG.1000.4, ETG.1000.6): scan and
//! station addresses, SII, AL states, mailbox with the CoE SDO client, cyclic process data,
//! and raw frames and datagrams for protocol-level test steps.
//!
//! The protocol logic reads no clock and does no I/O of its own: it runs over a [`Segment`],
//! either the embedded simulated slave on a virtual clock ([`EmbeddedSegment`]) or a network
//! interface ([`NetSegment`]); [`Faulty`] injects a silent, looping or garbage-returning
//! segment. Errors come in three kinds ([`ErrorKind`]): the slave's refusal (data), a broken
//! protocol, a failed link.

// The binding (harness/src/ecat) uses part of the API; tests and benches use the rest.
#![allow(dead_code)]

mod al;
mod engine;
mod error;
mod mailbox;
mod pdo;
mod port;
mod record;
mod scan;
mod sdo;
mod segment;
mod sii;
#[cfg(test)]
mod tests;
mod wire;

#[allow(unused_imports)] // the module's API, not all of it used yet
pub(crate) use al::AlReading;
#[allow(unused_imports)]
pub(crate) use engine::{EscInfo, Master, MasterConfig, ProcessSetup, SlaveInfo, SmSetup};
#[allow(unused_imports)]
pub(crate) use error::{
    AlRefused, Awaited, ErrorKind, LinkFailure, MasterError, NoSlave, ProtocolError, Refusal,
    UsageError,
};
#[allow(unused_imports)]
pub(crate) use pdo::CyclicStats;
#[allow(unused_imports)]
pub(crate) use port::PortStats;
#[allow(unused_imports)]
pub(crate) use proto::ecat::al::{AlStatus, AlStatusCode};
#[allow(unused_imports)]
pub(crate) use proto::ecat::coe::{Emergency, SdoAbortCode};
#[allow(unused_imports)]
pub(crate) use proto::ecat::mailbox::{MailboxErrorCode, MailboxRepr, MailboxType};
#[allow(unused_imports)]
pub(crate) use proto::ecat::sii::{SiiRepr, SiiSm, SmType};
#[allow(unused_imports)]
pub(crate) use proto::ecat::{Command, DatagramRepr};
#[allow(unused_imports)]
pub(crate) use segment::{
    Arrival, EmbeddedSegment, Fault, Faulty, NetSegment, Segment, SegmentError,
};
