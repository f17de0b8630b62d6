//! The one error type of the PROFINET IO codecs: every variant names the field or structure
//! that is wrong, so a negative test can assert on it.

/// A malformed PROFINET structure (DCP telegram, RT frame, RPC header, PNIO-CM block, alarm).
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
    /// Bytes left after a structure that must fill its space.
    #[error("{what}: {extra} bytes left over")]
    Trailing {
        /// The structure.
        what: &'static str,
        /// How many bytes are left.
        extra: usize,
    },
    /// A length field claims other than the bytes there are.
    #[error("{field}: length {value} but {available} bytes available")]
    BadLength {
        /// The length field.
        field: &'static str,
        /// What the field says.
        value: usize,
        /// What is there.
        available: usize,
    },
    /// A code this crate cannot interpret where it must (a frame id, a block type, a DCP
    /// option).
    #[error("{field}: unknown value {value:#X}")]
    Unknown {
        /// The field.
        field: &'static str,
        /// Its value.
        value: u32,
    },
    /// A field whose value the standard forbids there (a block version, a reserved bit).
    #[error("{field}: invalid value {value:#X}")]
    Invalid {
        /// The field.
        field: &'static str,
        /// Its value.
        value: u32,
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

crate::wire::read_error!(Error);
