//! Length-checked little-endian reading shared by the EtherNet/IP codecs.
//!
//! CIP and the encapsulation layer are little-endian; only the socket-address item is
//! big-endian (network order). Every read names what it was reading, so an error says which
//! field of which structure ran short.

/// A malformed EtherNet/IP or CIP structure.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum WireError {
    /// The bytes end before the field.
    #[error("{what}: truncated, need {need} bytes, got {got}")]
    Truncated {
        /// The field or structure.
        what: &'static str,
        /// Bytes needed.
        need: usize,
        /// Bytes present.
        got: usize,
    },
    /// A length field disagrees with the bytes present.
    #[error("{what}: length field says {declared} bytes, {actual} present")]
    Length {
        /// The length field.
        what: &'static str,
        /// What the field says.
        declared: usize,
        /// What is there.
        actual: usize,
    },
    /// Bytes left over after a structure that must fill its buffer.
    #[error("{what}: {extra} unexpected trailing bytes")]
    Trailing {
        /// The structure.
        what: &'static str,
        /// How many bytes are left.
        extra: usize,
    },
    /// A field holds a value the format does not allow.
    #[error("{what}: {detail}")]
    Invalid {
        /// The field.
        what: &'static str,
        /// What is wrong.
        detail: String,
    },
}

/// The shared length-checked reader, reporting [`WireError`]s.
pub(crate) type Reader<'a> = crate::wire::Reader<'a, WireError>;

crate::wire::read_error!(WireError);

impl<'a> Reader<'a> {
    /// `n` bytes announced by the length field `what`; too few is a [`WireError::Length`]
    /// naming that field, since the field, not the data, is what lies.
    pub(crate) fn sized(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], WireError> {
        let actual = self.remaining();
        self.bytes(n, what).map_err(|_| WireError::Length {
            what,
            declared: n,
            actual,
        })
    }
}

/// Writes little-endian fields.
pub(crate) trait Put {
    fn put_u8(&mut self, v: u8);
    fn put_u16(&mut self, v: u16);
    fn put_u32(&mut self, v: u32);
}

impl Put for Vec<u8> {
    fn put_u8(&mut self, v: u8) {
        self.push(v);
    }
    fn put_u16(&mut self, v: u16) {
        self.extend_from_slice(&v.to_le_bytes());
    }
    fn put_u32(&mut self, v: u32) {
        self.extend_from_slice(&v.to_le_bytes());
    }
}

/// A length that must fit a 16-bit field.
pub(crate) fn len16(what: &'static str, n: usize) -> Result<u16, WireError> {
    u16::try_from(n).map_err(|_| WireError::Invalid {
        what,
        detail: format!("{n} bytes do not fit a 16-bit length"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lying_length_field_is_named() {
        // A length field announcing 4 bytes where 3 are left.
        let mut r = Reader::new(&[1, 2, 3]);
        let lie = WireError::Length {
            what: "item length",
            declared: 4,
            actual: 3,
        };
        assert_eq!(r.sized(4, "item length"), Err(lie));
        assert_eq!(r.sized(3, "item length"), Ok(&[1u8, 2, 3][..]));
        assert!(len16("x", 65_536).is_err());
    }
}
