//! Length-checked reading shared by the codecs of every bus: little-endian (EtherCAT, CIP,
//! POWERLINK, CANopen) and big-endian (PROFINET's network order). Every read names the field it
//! was reading, so an error says which field of which structure ran short.

use super::Error;

/// Reads fields front to back, checking every length.
#[derive(Debug, Clone)]
pub(crate) struct Reader<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(buf: &'a [u8]) -> Self {
        Reader { buf, pos: 0 }
    }

    /// Bytes not yet read.
    pub(crate) fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }

    /// The next `n` bytes of the field `what`.
    pub(crate) fn bytes(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], Error> {
        let got = self.remaining();
        if got < n {
            return Err(Error::Truncated { what, need: n, got });
        }
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    /// `n` bytes announced by the length field `field`; too few is an [`Error::Length`]
    /// naming that field, since the field, not the data, is what lies.
    pub(crate) fn sized(&mut self, n: usize, field: &'static str) -> Result<&'a [u8], Error> {
        let available = self.remaining();
        self.bytes(n, field).map_err(|_| Error::Length {
            field,
            value: n,
            available,
        })
    }

    /// All bytes not yet read.
    pub(crate) fn rest(&mut self) -> &'a [u8] {
        let s = &self.buf[self.pos..];
        self.pos = self.buf.len();
        s
    }

    pub(crate) fn u8(&mut self, what: &'static str) -> Result<u8, Error> {
        Ok(self.bytes(1, what)?[0])
    }

    pub(crate) fn u16(&mut self, what: &'static str) -> Result<u16, Error> {
        let b = self.bytes(2, what)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    pub(crate) fn u32(&mut self, what: &'static str) -> Result<u32, Error> {
        let b = self.bytes(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    pub(crate) fn u16_be(&mut self, what: &'static str) -> Result<u16, Error> {
        let b = self.bytes(2, what)?;
        Ok(u16::from_be_bytes([b[0], b[1]]))
    }

    pub(crate) fn u32_be(&mut self, what: &'static str) -> Result<u32, Error> {
        let b = self.bytes(4, what)?;
        Ok(u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// Fails if bytes are left.
    pub(crate) fn finish(&self, what: &'static str) -> Result<(), Error> {
        match self.remaining() {
            0 => Ok(()),
            extra => Err(Error::Trailing { what, extra }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_reads_name_the_field() {
        // 01 02: a u16 0201h; 03: one byte left.
        let mut r = Reader::new(&[1, 2, 3]);
        let short = |what, need, got| Err(Error::Truncated { what, need, got });
        assert_eq!(r.clone().u16_be("a"), Ok(0x0102));
        assert_eq!(r.clone().u32_be("a"), short("a", 4, 3));
        assert_eq!(r.u16("a"), Ok(0x0201));
        assert_eq!(r.u32("b"), short("b", 4, 1));
        assert_eq!(
            r.finish("c"),
            Err(Error::Trailing {
                what: "c",
                extra: 1
            })
        );
        assert_eq!(r.remaining(), 1);
        assert_eq!(r.u8("d"), Ok(3));
        assert_eq!(r.finish("c"), Ok(()));
        assert_eq!(r.rest(), [] as [u8; 0]);
    }

    #[test]
    fn a_lying_length_field_is_named() {
        // A length field announcing 4 bytes where 3 are left.
        let mut r = Reader::new(&[1, 2, 3]);
        let lie = Error::Length {
            field: "item length",
            value: 4,
            available: 3,
        };
        assert_eq!(r.sized(4, "item length"), Err(lie));
        assert_eq!(r.sized(3, "item length"), Ok(&[1u8, 2, 3][..]));
    }
}
