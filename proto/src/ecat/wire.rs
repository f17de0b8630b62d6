//! Length-checked little-endian reading shared by the EtherCAT codecs (EtherCAT is
//! little-endian throughout, ETG.1000.4; only the Ethernet header is big-endian).

use super::Error;

/// Reads fields front to back, checking every length; each read names its field.
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

    pub(crate) fn bytes(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], Error> {
        if self.remaining() < n {
            return Err(Error::Truncated {
                what,
                need: n,
                got: self.remaining(),
            });
        }
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

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

    /// Fails if bytes are left.
    pub(crate) fn finish(&self, what: &'static str) -> Result<(), Error> {
        match self.remaining() {
            0 => Ok(()),
            extra => Err(Error::Trailing { what, extra }),
        }
    }
}

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
    fn short_reads_name_the_field() {
        let mut r = Reader::new(&[1, 2, 3]);
        assert_eq!(r.u16("a").unwrap(), 0x0201);
        assert_eq!(
            r.u32("b"),
            Err(Error::Truncated {
                what: "b",
                need: 4,
                got: 1
            })
        );
        assert_eq!(
            r.finish("c"),
            Err(Error::Trailing {
                what: "c",
                extra: 1
            })
        );
        assert_eq!(r.rest(), [3]);
        assert!(r.finish("c").is_ok());
        assert_eq!(
            fit("x", 3, 2),
            Err(Error::TooLong {
                what: "x",
                len: 3,
                max: 2
            })
        );
    }
}
