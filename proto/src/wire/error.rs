//! The one error type of every codec in this crate: every variant names the field or structure
//! that is wrong, so a negative test can assert on it. A device's refusal (an SDO abort, a CIP
//! general status, a PNIO status) is not an error: it parses to a message carrying its code.

/// A malformed frame or structure of any bus, or one that breaks a transfer's sequence.
///
/// Not `Copy`: [`Error::SocketcandSyntax`] quotes the offending text.
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
    /// Bytes left after a structure that must fill its space (a structure of fixed size, the
    /// last EtherCAT datagram within the frame's length).
    #[error("{what}: {extra} bytes left over")]
    Trailing {
        /// The structure.
        what: &'static str,
        /// How many bytes are left.
        extra: usize,
    },
    /// A length field claims other than the bytes there are (or a value the format forbids):
    /// the field, not the data, is what lies.
    #[error("{field}: length {value} but {available} bytes available")]
    Length {
        /// The length field.
        field: &'static str,
        /// What the field says.
        value: usize,
        /// What is there (or the largest value allowed).
        available: usize,
    },
    /// A code this crate cannot interpret where it must (a command specifier, a frame id, a
    /// block type, a message type).
    #[error("{field}: unknown value {value:#X}")]
    Unknown {
        /// The field.
        field: &'static str,
        /// Its value.
        value: u32,
    },
    /// A field holds a value the standard does not allow there.
    #[error("{field}: value {value:#X} is invalid: {why}")]
    Invalid {
        /// The field.
        field: &'static str,
        /// Its value.
        value: u32,
        /// Why.
        why: &'static str,
    },
    /// A structure lacks a part it must have (an I/O frame without its connected data item).
    #[error("{what}: no {part}")]
    Missing {
        /// The structure.
        what: &'static str,
        /// The part it lacks.
        part: &'static str,
    },
    /// Something to emit does not fit its field or buffer.
    #[error("{what}: {len} does not fit (at most {max})")]
    TooLong {
        /// The structure or field.
        what: &'static str,
        /// The length asked for.
        len: usize,
        /// The largest the field allows.
        max: usize,
    },
    /// An EtherCAT datagram does not fit what is left of the frame's length (ETG.1000.4
    /// "EtherCAT datagram": header 10 bytes, data, working counter 2 bytes).
    #[error("datagram {index}: needs {need} bytes, only {got} left in the EtherCAT frame")]
    DatagramTruncated {
        /// Datagram number in the frame, from 0.
        index: usize,
        /// Bytes the datagram claims (header, data length, working counter).
        need: usize,
        /// Bytes left in the frame at its start.
        got: usize,
    },
    /// The EtherCAT SII configuration area's checksum (word 7, ETG.2010) is wrong.
    #[error("SII checksum: word 7 holds {stored:02X}h, words 0..6 give {computed:02X}h")]
    SiiChecksum {
        /// The low byte of word 7.
        stored: u8,
        /// The CRC-8 of words 0..6.
        computed: u8,
    },
    /// An identifier above 7FFh where a base-format (11-bit) CAN identifier is required.
    #[error("CAN identifier {id:#X} does not fit 11 bits (CAN 2.0A: at most 7FFh)")]
    CanIdentifier {
        /// The identifier.
        id: u32,
    },
    /// More than 8 CAN data bytes, or a data length code above 8.
    #[error("CAN data length {len} is above 8")]
    CanDataLength {
        /// The length asked for or found.
        len: usize,
    },
    /// An extended-format (29-bit) CAN frame: the system bus is CAN 2.0A.
    #[error("extended CAN frame {id:08X}h: the system bus uses 11-bit identifiers (CAN 2.0A)")]
    CanExtended {
        /// The 29-bit identifier.
        id: u32,
    },
    /// A socketcand message that does not follow the syntax of `doc/protocol.md`.
    #[error("socketcand {field}: {token:?} {why}")]
    SocketcandSyntax {
        /// The field or message.
        field: &'static str,
        /// The offending text (shortened to 40 characters).
        token: String,
        /// What is wrong with it.
        why: &'static str,
    },
    /// No `>` within the longest socketcand message this codec accepts.
    #[error("socketcand message: no '>' within {max} bytes")]
    SocketcandUnterminated {
        /// The limit.
        max: usize,
    },
    /// A remote frame to carry over socketcand, whose `send` and `frame` cannot express one.
    #[error("socketcand cannot carry a remote (RTR) frame")]
    SocketcandRemote,
    /// A CANopen SDO segment's toggle bit is not the one expected (CiA 301 abort code
    /// 0503_0000h).
    #[error("SDO segment toggle bit is {got}, expected {expected}")]
    SdoToggle {
        /// The toggle bit expected.
        expected: bool,
        /// The toggle bit received.
        got: bool,
    },
    /// A CANopen SDO block segment's sequence number is not the one expected (abort code
    /// 0504_0003h).
    #[error("SDO block segment sequence number {got}, expected {expected}")]
    SdoBlockSequence {
        /// The sequence number expected.
        expected: u8,
        /// The sequence number received.
        got: u8,
    },
    /// A CAN frame's identifier is not the one the CANopen message travels on.
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

impl Error {
    /// A [`Error::SocketcandSyntax`] quoting at most 40 characters of `token`.
    pub(crate) fn syntax(field: &'static str, token: &str, why: &'static str) -> Error {
        Error::SocketcandSyntax {
            field,
            token: token.chars().take(40).collect(),
            why,
        }
    }
}
