//! Little-endian helpers of the EtherCAT codecs (EtherCAT is little-endian throughout,
//! ETG.1000.4; only the Ethernet header is big-endian) for slices already checked, and the
//! check of a length to emit. Reading unchecked bytes is `crate::wire`'s reader.

use crate::wire::Error;

/// Little-endian u16 at `at` of a slice the caller has checked.
pub(crate) fn le16(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes([b[at], b[at + 1]])
}

/// Little-endian u32 at `at` of a slice the caller has checked.
pub(crate) fn le32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes([b[at], b[at + 1], b[at + 2], b[at + 3]])
}

/// A length that must fit `max`.
pub(crate) fn fit(what: &'static str, len: usize, max: usize) -> Result<usize, Error> {
    if len > max {
        Err(Error::TooLong { what, len, max })
    } else {
        Ok(len)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lengths_must_fit() {
        assert_eq!(
            fit("x", 3, 2),
            Err(Error::TooLong {
                what: "x",
                len: 3,
                max: 2
            })
        );
        assert_eq!(fit("x", 2, 2), Ok(2));
    }
}
