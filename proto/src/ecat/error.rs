//! The one error type of the EtherCAT codecs: every variant names the field or structure that
//! is wrong, so a negative test can assert on it.

/// A malformed EtherCAT structure (frame, datagram, register block, SII image, mailbox, CoE).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
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
    /// A length field claims more bytes than there are (or a value the format forbids).
    #[error("{field}: length {value} but {available} bytes available")]
    BadLength {
        /// The length field.
        field: &'static str,
        /// What the field says.
        value: usize,
        /// What is there (or the largest value allowed).
        available: usize,
    },
    /// A datagram of an EtherCAT frame does not fit what is left of the frame's length
    /// (ETG.1000.4 "EtherCAT datagram": header 10 bytes, data, working counter 2 bytes).
    #[error("datagram {index}: needs {need} bytes, only {got} left in the EtherCAT frame")]
    DatagramTruncated {
        /// Datagram number in the frame, from 0.
        index: usize,
        /// Bytes the datagram claims (header, data length, working counter).
        need: usize,
        /// Bytes left in the frame at its start.
        got: usize,
    },
    /// Bytes left after a structure that must fill its space (e.g. after the datagram whose
    /// "more follows" bit is clear, within the EtherCAT length).
    #[error("{what}: {extra} bytes left over")]
    Trailing {
        /// The structure.
        what: &'static str,
        /// How many bytes are left.
        extra: usize,
    },
    /// A code this crate cannot interpret where it must (e.g. an SDO command specifier).
    #[error("{field}: unknown value {value:#X}")]
    Unknown {
        /// The field.
        field: &'static str,
        /// Its value.
        value: u32,
    },
    /// A field holds a value the format does not allow.
    #[error("{field}: value {value:#X} is invalid: {why}")]
    Invalid {
        /// The field.
        field: &'static str,
        /// Its value.
        value: u32,
        /// Why.
        why: &'static str,
    },
    /// The SII configuration area's checksum (word 7, ETG.2010) is wrong.
    #[error("SII checksum: word 7 holds {stored:02X}h, words 0..6 give {computed:02X}h")]
    Checksum {
        /// The low byte of word 7.
        stored: u8,
        /// The CRC-8 of words 0..6.
        computed: u8,
    },
    /// Something to emit does not fit its length field.
    #[error("{what}: {len} does not fit (at most {max})")]
    TooLong {
        /// The structure or field.
        what: &'static str,
        /// The length asked for.
        len: usize,
        /// The largest the field allows.
        max: usize,
    },
}
