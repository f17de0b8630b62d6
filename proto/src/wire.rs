//! Length-checked reading shared by the codecs of every bus: little-endian (EtherCAT, CIP,
//! POWERLINK) and big-endian (PROFINET's network order). Each protocol keeps its own error type; it tells the reader how to say
//! "truncated" and "bytes left over" through [`ReadError`]. Every read names the field it was
//! reading, so an error says which field of which structure ran short.

use std::marker::PhantomData;

/// The two errors a [`Reader`] reports, built in the protocol's own error type.
pub(crate) trait ReadError {
    /// The bytes end before the field `what`: `need` bytes wanted, `got` left.
    fn truncated(what: &'static str, need: usize, got: usize) -> Self;
    /// `extra` bytes are left after the structure `what`, which must fill its buffer.
    fn trailing(what: &'static str, extra: usize) -> Self;
}

/// Implements [`ReadError`] for an error enum with the variants `Truncated { what, need, got }`
/// and `Trailing { what, extra }` (the EtherCAT and EtherNet/IP errors both have them).
macro_rules! read_error {
    ($t:ty) => {
        impl $crate::wire::ReadError for $t {
            fn truncated(what: &'static str, need: usize, got: usize) -> Self {
                Self::Truncated { what, need, got }
            }
            fn trailing(what: &'static str, extra: usize) -> Self {
                Self::Trailing { what, extra }
            }
        }
    };
}
pub(crate) use read_error;

/// Reads fields front to back, checking every length; errors are `E`s.
#[derive(Debug, Clone)]
pub(crate) struct Reader<'a, E> {
    buf: &'a [u8],
    pos: usize,
    error: PhantomData<fn() -> E>,
}

impl<'a, E: ReadError> Reader<'a, E> {
    pub(crate) fn new(buf: &'a [u8]) -> Self {
        Reader {
            buf,
            pos: 0,
            error: PhantomData,
        }
    }

    /// Bytes not yet read.
    pub(crate) fn remaining(&self) -> usize {
        self.buf.len() - self.pos
    }

    /// The next `n` bytes of the field `what`.
    pub(crate) fn bytes(&mut self, n: usize, what: &'static str) -> Result<&'a [u8], E> {
        if self.remaining() < n {
            return Err(E::truncated(what, n, self.remaining()));
        }
        let s = &self.buf[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    /// All bytes not yet read.
    pub(crate) fn rest(&mut self) -> &'a [u8] {
        let s = &self.buf[self.pos..];
        self.pos = self.buf.len();
        s
    }

    pub(crate) fn u8(&mut self, what: &'static str) -> Result<u8, E> {
        Ok(self.bytes(1, what)?[0])
    }

    pub(crate) fn u16(&mut self, what: &'static str) -> Result<u16, E> {
        let b = self.bytes(2, what)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    pub(crate) fn u32(&mut self, what: &'static str) -> Result<u32, E> {
        let b = self.bytes(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    pub(crate) fn u16_be(&mut self, what: &'static str) -> Result<u16, E> {
        let b = self.bytes(2, what)?;
        Ok(u16::from_be_bytes([b[0], b[1]]))
    }

    pub(crate) fn u32_be(&mut self, what: &'static str) -> Result<u32, E> {
        let b = self.bytes(4, what)?;
        Ok(u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// Fails if bytes are left.
    pub(crate) fn finish(&self, what: &'static str) -> Result<(), E> {
        match self.remaining() {
            0 => Ok(()),
            extra => Err(E::trailing(what, extra)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An error that records what the reader said.
    #[derive(Debug, Clone, PartialEq, Eq)]
    enum Said {
        Truncated(&'static str, usize, usize),
        Trailing(&'static str, usize),
    }

    impl ReadError for Said {
        fn truncated(what: &'static str, need: usize, got: usize) -> Self {
            Said::Truncated(what, need, got)
        }
        fn trailing(what: &'static str, extra: usize) -> Self {
            Said::Trailing(what, extra)
        }
    }

    #[test]
    fn short_reads_name_the_field() {
        // 01 02: a u16 0201h; 03: one byte left.
        let mut r = Reader::<Said>::new(&[1, 2, 3]);
        assert_eq!(r.clone().u16_be("a"), Ok(0x0102));
        assert_eq!(r.clone().u32_be("a"), Err(Said::Truncated("a", 4, 3)));
        assert_eq!(r.u16("a"), Ok(0x0201));
        assert_eq!(r.u32("b"), Err(Said::Truncated("b", 4, 1)));
        assert_eq!(r.finish("c"), Err(Said::Trailing("c", 1)));
        assert_eq!(r.remaining(), 1);
        assert_eq!(r.u8("d"), Ok(3));
        assert_eq!(r.finish("c"), Ok(()));
        assert_eq!(r.rest(), [] as [u8; 0]);
    }
}
