//! The one error type of the CAN and CANopen codecs (`can`, and `canopen` above it): every
//! variant names the field that is wrong, so a negative test can assert on it. A device's
//! refusal (an SDO abort) is not an error: it parses to a message carrying its abort code.

/// A malformed CAN frame, SocketCAN structure, socketcand message or CANopen message, or one
/// that breaks a transfer's sequence.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Error {
    /// The bytes end before the field or structure.
    #[error("{what}: truncated, need {need} bytes, got {got}")]
    Truncated {
        /// The field or structure.
        what: &'static str,
        /// Bytes needed.
        need: usize,
        /// Bytes present.
        got: usize,
    },
    /// Bytes left after a structure of fixed size.
    #[error("{what}: {extra} bytes left over")]
    Trailing {
        /// The structure.
        what: &'static str,
        /// How many bytes are left.
        extra: usize,
    },
    /// An identifier above 7FFh where a base-format (11-bit) identifier is required.
    #[error("CAN identifier {id:#X} does not fit 11 bits (CAN 2.0A: at most 7FFh)")]
    Identifier {
        /// The identifier.
        id: u32,
    },
    /// More than 8 data bytes, or a data length code above 8.
    #[error("CAN data length {len} is above 8")]
    Length {
        /// The length asked for or found.
        len: usize,
    },
    /// An extended-format (29-bit) frame: the system bus is CAN 2.0A.
    #[error("extended CAN frame {id:08X}h: the system bus uses 11-bit identifiers (CAN 2.0A)")]
    Extended {
        /// The 29-bit identifier.
        id: u32,
    },
    /// A socketcand message that does not follow the syntax of `doc/protocol.md`.
    #[error("socketcand {field}: {token:?} {why}")]
    Syntax {
        /// The field or message.
        field: &'static str,
        /// The offending text (shortened to 40 characters).
        token: String,
        /// What is wrong with it.
        why: &'static str,
    },
    /// No `>` within the longest socketcand message this codec accepts.
    #[error("socketcand message: no '>' within {max} bytes")]
    Unterminated {
        /// The limit.
        max: usize,
    },
    /// A remote frame to carry over socketcand, whose `send` and `frame` cannot express one.
    #[error("socketcand cannot carry a remote (RTR) frame")]
    Remote,
    /// A code this crate cannot interpret where it must (a command specifier, an NMT state).
    #[error("{field}: unknown value {value:#X}")]
    Unknown {
        /// The field.
        field: &'static str,
        /// Its value.
        value: u32,
    },
    /// A field holds a value CiA 301 does not allow there.
    #[error("{field}: value {value:#X} is invalid: {why}")]
    Invalid {
        /// The field.
        field: &'static str,
        /// Its value.
        value: u32,
        /// Why.
        why: &'static str,
    },
    /// Something to emit does not fit its field.
    #[error("{what}: {len} does not fit (at most {max})")]
    TooLong {
        /// The field.
        what: &'static str,
        /// The length asked for.
        len: usize,
        /// The largest the field allows.
        max: usize,
    },
    /// A segment's toggle bit is not the one expected (CiA 301 abort code 0503_0000h).
    #[error("SDO segment toggle bit is {got}, expected {expected}")]
    Toggle {
        /// The toggle bit expected.
        expected: bool,
        /// The toggle bit received.
        got: bool,
    },
    /// A block segment's sequence number is not the one expected (abort code 0504_0003h).
    #[error("SDO block segment sequence number {got}, expected {expected}")]
    Sequence {
        /// The sequence number expected.
        expected: u8,
        /// The sequence number received.
        got: u8,
    },
    /// A CAN frame's identifier is not the one the message travels on.
    #[error("{what}: COB-ID {cob_id:03X}h is not {expected}")]
    CobId {
        /// The message expected.
        what: &'static str,
        /// The frame's identifier.
        cob_id: u16,
        /// What the identifier should be.
        expected: &'static str,
    },
}

crate::wire::read_error!(Error);

impl Error {
    /// A [`Error::Syntax`] quoting at most 40 characters of `token`.
    pub(crate) fn syntax(field: &'static str, token: &str, why: &'static str) -> Error {
        Error::Syntax {
            field,
            token: token.chars().take(40).collect(),
            why,
        }
    }
}
