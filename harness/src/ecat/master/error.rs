//! What can go wrong for the master, in three kinds kept apart (STYLE.md "A device's refusal is
//! data"):
//!
//! - [`Refusal`]: a slave understood the request and said no — an AL status code refusing a
//!   state, an SDO abort code, a mailbox error reply. Data the suites match.
//! - [`ProtocolError`]: a slave answered, and the answer breaks EtherCAT (a malformed frame, a
//!   working counter that cannot be, an SDO response that does not fit the request, a wrong
//!   toggle bit). A failing verdict.
//! - [`LinkFailure`]: nothing usable came back — the link failed, no frame within the timeout,
//!   frames come back unprocessed (a loop, no slave), no reply within its time. An error
//!   verdict.

use std::time::Duration;

use proto::ecat::al::AlStatusCode;
use proto::ecat::coe::SdoAbortCode;
use proto::ecat::mailbox::MailboxErrorCode;

use super::segment::SegmentError;
use crate::outcome;

/// Which of the three kinds an error is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ErrorKind {
    /// The device refused ([`Refusal`]).
    Refused,
    /// The device broke the protocol ([`ProtocolError`]).
    Protocol,
    /// The link or the segment failed ([`LinkFailure`]), or the harness asked for something
    /// impossible ([`UsageError`]): an error verdict either way.
    Link,
}

/// A failed master operation.
#[derive(Debug, thiserror::Error)]
pub(crate) enum MasterError {
    /// A slave refused the request.
    #[error(transparent)]
    Refused(#[from] Refusal),
    /// A slave broke the protocol.
    #[error(transparent)]
    Protocol(#[from] ProtocolError),
    /// The link failed or nothing answered.
    #[error(transparent)]
    Link(#[from] LinkFailure),
    /// The master was asked for something it cannot do (a harness or suite error).
    #[error(transparent)]
    Usage(#[from] UsageError),
}

impl MasterError {
    /// Its kind.
    pub(crate) fn kind(&self) -> ErrorKind {
        match self {
            MasterError::Refused(_) => ErrorKind::Refused,
            MasterError::Protocol(_) => ErrorKind::Protocol,
            MasterError::Link(_) | MasterError::Usage(_) => ErrorKind::Link,
        }
    }

    /// The refusal, if the device refused.
    pub(crate) fn refusal(&self) -> Option<&Refusal> {
        match self {
            MasterError::Refused(r) => Some(r),
            _ => None,
        }
    }
}

impl From<SegmentError> for MasterError {
    fn from(e: SegmentError) -> Self {
        MasterError::Link(LinkFailure::Segment(e))
    }
}

/// A slave's refusal, in EtherCAT's own terms.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum Refusal {
    /// The slave did not enter the requested AL state: it set the error indication (AL status
    /// bit 4) with an AL status code (ETG.1000.6 §6.4.1, table 11).
    #[error("{0}")]
    Al(AlRefused),
    /// The slave aborted an SDO transfer (ETG.1000.6 §5.6.2.7; BU 0620 §2.2.7.2).
    #[error("SDO {index:04X}h:{sub:02X}h aborted: {code}")]
    SdoAbort {
        /// Object index of the transfer.
        index: u16,
        /// Sub-index of the transfer.
        sub: u8,
        /// The abort code.
        code: SdoAbortCode,
    },
    /// The slave answered a mailbox message with a mailbox error (ETG.1000.6 §5.5, table 30).
    #[error("mailbox error {0}")]
    Mailbox(MailboxErrorCode),
}

/// The AL status after a refused state request.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct AlRefused {
    /// The state requested (AL control bits 0–3, as sent: may be no valid state).
    pub(crate) requested: u8,
    /// The state the slave is in (AL status bits 0–3).
    pub(crate) state: u8,
    /// The AL status code (register 0134h).
    pub(crate) code: AlStatusCode,
}

impl std::fmt::Display for AlRefused {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "AL state {:02X}h refused in state {:02X}h: AL status code {}",
            self.requested, self.state, self.code
        )
    }
}

impl Refusal {
    /// The refusal as the runner reports it.
    pub(crate) fn to_outcome(&self) -> outcome::Refusal {
        match self {
            Refusal::Al(a) => outcome::Refusal {
                kind: "AL status code".into(),
                code: u32::from(a.code.0),
                text: a.code.to_string(),
            },
            Refusal::SdoAbort { code, .. } => outcome::Refusal {
                kind: "SDO abort code".into(),
                code: code.0,
                text: code.to_string(),
            },
            Refusal::Mailbox(code) => outcome::Refusal {
                kind: "mailbox error".into(),
                code: u32::from(code.0),
                text: code.to_string(),
            },
        }
    }
}

/// What a slave sent that breaks EtherCAT.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum ProtocolError {
    /// An EtherCAT frame came back that cannot be parsed (the last such frame; no good frame
    /// came within the timeout).
    #[error("malformed EtherCAT frame came back: {0}")]
    Malformed(proto::wire::Error),
    /// A frame came back with the index of the frame sent but other datagrams (other commands
    /// or lengths).
    #[error("the frame with index {index:02X}h came back with other datagrams than were sent")]
    Mismatch {
        /// The frame's index.
        index: u8,
    },
    /// A datagram's working counter is not what the access must give.
    #[error("{access}: working counter {got}, expected {expected}")]
    WorkingCounter {
        /// The access, e.g. `FPWR 1001h:0120h`.
        access: String,
        /// What it must be.
        expected: u16,
        /// What came back.
        got: u16,
    },
    /// The SII EEPROM interface reported an error (register 0502h bits 11–14).
    #[error("SII EEPROM interface error: status {status:04X}h")]
    Eeprom {
        /// The EEPROM control/status register.
        status: u16,
    },
    /// The SII contents cannot be parsed (a wrong checksum of the configuration area too).
    #[error("SII contents: {0}")]
    Sii(proto::wire::Error),
    /// The SII's categories have no end marker within the words the master reads at most.
    #[error("SII: no end marker within {words} words")]
    SiiEnd {
        /// Words read.
        words: usize,
    },
    /// The slave's answers came with the counter of the message it sent before, each
    /// discarded as a repeat (ETG.1000.6 §5.6, mailbox header "Cnt"), and no new one came.
    #[error(
        "mailbox counter {counter} repeated: {discarded} answer(s) with the counter of the \
         message before discarded as a repeat, and no new one within {}",
        crate::timing::ms(*limit)
    )]
    RepeatedCounter {
        /// The counter that came again.
        counter: u8,
        /// Messages discarded.
        discarded: u32,
        /// How long the master waited for a new one.
        limit: Duration,
    },
    /// A mailbox message from the slave cannot be parsed.
    #[error("mailbox reply: {0}")]
    Mailbox(proto::wire::Error),
    /// A CoE message from the slave cannot be parsed.
    #[error("CoE reply: {0}")]
    Coe(proto::wire::Error),
    /// A reply that does not answer the request (an SDO response of another service, index or
    /// sub-index; a mailbox type not asked for).
    #[error("unexpected reply: expected {expected}, got {got}")]
    Unexpected {
        /// What the request needs.
        expected: &'static str,
        /// What came, decoded.
        got: String,
    },
    /// A segmented SDO response with the toggle bit of the previous segment.
    #[error("SDO segment toggle bit {got}, expected {expected}")]
    Toggle {
        /// The toggle bit expected.
        expected: bool,
        /// The one received.
        got: bool,
    },
    /// An SDO upload whose data does not add up to the size announced.
    #[error("SDO upload of {announced} bytes delivered {got}")]
    SdoSize {
        /// The size the initiate response announced.
        announced: u32,
        /// Bytes delivered.
        got: usize,
    },
}

/// A request the master cannot carry out as asked (a harness or suite error, not the slave's).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub(crate) enum UsageError {
    /// No slave with that station address was found by the scan.
    #[error("no slave with station address {station:04X}h")]
    NoSuchSlave {
        /// The station address.
        station: u16,
    },
    /// The slave has no mailbox (none in its SII, or not configured yet).
    #[error("slave {station:04X}h has no mailbox configured")]
    NoMailbox {
        /// Its station address.
        station: u16,
    },
    /// The slave has no process data configured.
    #[error("slave {station:04X}h has no process data configured")]
    NoProcessData {
        /// Its station address.
        station: u16,
    },
    /// A process data word outside the slave's image.
    #[error("FI {inverter} word {word} is not in the process image")]
    NoSuchWord {
        /// FI 1..=8.
        inverter: u8,
        /// Word 0..=5.
        word: u8,
    },
    /// The datagrams cannot be put into one frame.
    #[error("cannot build the frame: {0}")]
    Frame(super::wire::BuildError),
    /// The mailbox message cannot be built (too long for its length field).
    #[error("cannot build the mailbox message: {0}")]
    Mailbox(proto::wire::Error),
    /// Data too large for a mailbox.
    #[error("{what}: {len} bytes do not fit ({max} at most)")]
    TooLong {
        /// What was to be sent.
        what: &'static str,
        /// Its length.
        len: usize,
        /// The room.
        max: usize,
    },
}

/// What the master waited for when the time ran out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Awaited {
    /// A frame back.
    Frame,
    /// Room in the slave's receive mailbox (SM0 full).
    MailboxRoom,
    /// A reply in the slave's send mailbox (SM1).
    MailboxReply,
    /// The AL status to show the requested state or an error.
    AlState,
    /// The SII EEPROM interface to finish (busy bit).
    Eeprom,
}

impl std::fmt::Display for Awaited {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Awaited::Frame => "a frame back",
            Awaited::MailboxRoom => "room in the receive mailbox (SM0)",
            Awaited::MailboxReply => "a reply in the send mailbox (SM1)",
            Awaited::AlState => "the AL state change",
            Awaited::Eeprom => "the SII EEPROM interface",
        })
    }
}

/// The link failed or nothing answered.
#[derive(Debug, thiserror::Error)]
pub(crate) enum LinkFailure {
    /// The segment (network link) failed.
    #[error("link: {0}")]
    Segment(#[from] SegmentError),
    /// Nothing came within the slave's limit.
    #[error(
        "{awaited}: no answer within the device's limit of {} (waited {})",
        crate::timing::ms(*limit),
        crate::timing::ms(*waited)
    )]
    Timeout {
        /// What was awaited.
        awaited: Awaited,
        /// The slave's limit.
        limit: Duration,
        /// How long the master waited (on the real clock, the host's lost time included).
        waited: Duration,
    },
    /// Frames come back, but no slave processed them: the frame returned unchanged (a looped
    /// cable or a segment without slaves) or with every working counter 0.
    #[error("no slave answered: {0}")]
    NoSlave(NoSlave),
}

impl LinkFailure {
    /// `wait` for `awaited` passed at `now`.
    pub(crate) fn timeout(awaited: Awaited, wait: &crate::net::wait::Wait, now: Duration) -> Self {
        LinkFailure::Timeout {
            awaited,
            limit: wait.limit(),
            waited: wait.waited(now),
        }
    }
}

/// How a frame showed that no slave answered.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum NoSlave {
    /// It came back byte for byte as sent (no ESC set the source address's locally
    /// administered bit or touched a datagram).
    Unprocessed,
    /// Every datagram's working counter is 0.
    WorkingCounters,
    /// The broadcast read of the scan counted no slave.
    NoneCounted,
}

impl std::fmt::Display for NoSlave {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            NoSlave::Unprocessed => "the frame came back unprocessed (looped segment, no slave)",
            NoSlave::WorkingCounters => "every working counter came back 0",
            NoSlave::NoneCounted => "the broadcast read counted no slave",
        })
    }
}

/// `Err` of a master operation.
pub(crate) type Result<T, E = MasterError> = std::result::Result<T, E>;
