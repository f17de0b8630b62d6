//! TCP framing of encapsulation messages: bytes in, whole messages out.
//!
//! The header's length field is the only framing EtherNet/IP has. A peer that announces more
//! than it sends leaves a partial message buffered; the driver's read timeout decides when
//! that becomes an error, not the framer.

use proto::enip::encap::{frame_len, HEADER_LEN, MAX_DATA_LEN};

/// Accumulates stream bytes.
#[derive(Debug, Default)]
pub struct Framer {
    buf: Vec<u8>,
}

/// The stream cannot be framed any more.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[error("encapsulation length {0} exceeds the {MAX_DATA_LEN}-byte limit")]
pub struct Oversize(pub usize);

impl Framer {
    /// A framer with nothing buffered.
    pub fn new() -> Framer {
        Framer::default()
    }

    /// Adds bytes and returns every whole message now available.
    pub fn push(&mut self, bytes: &[u8]) -> Result<Vec<Vec<u8>>, Oversize> {
        self.buf.extend_from_slice(bytes);
        let mut out = Vec::new();
        while let Some(n) = frame_len(&self.buf) {
            if n - HEADER_LEN > MAX_DATA_LEN {
                return Err(Oversize(n - HEADER_LEN));
            }
            if self.buf.len() < n {
                break;
            }
            out.push(self.buf.drain(..n).collect());
        }
        Ok(out)
    }

    /// Bytes of an incomplete message still buffered.
    pub fn pending(&self) -> usize {
        self.buf.len()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn splits_and_joins_messages() {
        let mut msg = vec![0x65, 0, 4, 0];
        msg.extend([0; 20]);
        msg.extend([1, 0, 0, 0]);
        let mut two = msg.clone();
        two.extend(&msg);
        let mut f = Framer::new();
        assert_eq!(f.push(&two[..30]).unwrap().len(), 1);
        assert_eq!(f.pending(), 2);
        assert_eq!(f.push(&two[30..]).unwrap(), vec![msg.clone()]);
        assert_eq!(f.pending(), 0);
        let mut big = vec![0x6F, 0, 0xFF, 0xFF];
        big.extend([0; 20]);
        assert_eq!(f.push(&big), Err(Oversize(65_535)));
    }
}
