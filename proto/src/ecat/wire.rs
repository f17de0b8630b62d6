//! Length-checked little-endian reading shared by the EtherCAT codecs (EtherCAT is
//! little-endian throughout, ETG.1000.4; only the Ethernet header is big-endian): the reader
//! of `crate::wire` reporting [`Error`]s, and the helpers for slices already checked.

use super::Error;

/// The shared length-checked reader, reporting [`Error`]s.
pub(crate) type Reader<'a> = crate::wire::Reader<'a, Error>;

crate::wire::read_error!(Error);

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
    fn short_reads_are_ecat_errors_and_lengths_must_fit() {
        // 01 02 03: a u16, then one byte where a u32 was wanted.
        let mut r = Reader::new(&[1, 2, 3]);
        assert_eq!(r.u16("a"), Ok(0x0201));
        let short = Error::Truncated {
            what: "b",
            need: 4,
            got: 1,
        };
        assert_eq!(r.u32("b"), Err(short));
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
