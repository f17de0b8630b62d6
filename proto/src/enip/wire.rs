//! Little-endian writing shared by the EtherNet/IP codecs.
//!
//! CIP and the encapsulation layer are little-endian; only the socket-address item is
//! big-endian (network order). Reading is `crate::wire`'s length-checked reader.

use crate::wire::Error;

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
pub(crate) fn len16(what: &'static str, n: usize) -> Result<u16, Error> {
    u16::try_from(n).map_err(|_| Error::TooLong {
        what,
        len: n,
        max: usize::from(u16::MAX),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_length_must_fit_16_bits() {
        assert_eq!(len16("x", 65_535), Ok(65_535));
        assert_eq!(
            len16("x", 65_536),
            Err(Error::TooLong {
                what: "x",
                len: 65_536,
                max: 65_535
            })
        );
    }
}
