//! The EtherCAT master of the harness (BU 0620 §2.2; ETG.1000.4, ETG.1000.6): scan and
//! station addresses, SII, AL states, mailbox with the CoE SDO client, cyclic process data,
//! and raw frames and datagrams for protocol-level test steps.
//!
//! The protocol logic reads no clock and does no I/O of its own: it runs over a [`Segment`],
//! either the embedded simulated slave on a virtual clock ([`EmbeddedSegment`]) or a network
//! interface ([`NetSegment`]); [`Faulty`] injects a silent, looping or garbage-returning
//! segment. Errors come in three kinds ([`ErrorKind`]): the slave's refusal (data), a broken
//! protocol, a failed link.

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

#[cfg(test)]
pub(crate) use al::al_limit;
pub(crate) use engine::{Master, MasterConfig};
pub(crate) use error::{AlRefused, ErrorKind, LinkFailure, MasterError, ProtocolError, Refusal};
pub(crate) use segment::{Arrival, EmbeddedSegment, NetSegment, Segment, SegmentError};
#[cfg(test)]
pub(crate) use segment::{Fault, Faulty};
