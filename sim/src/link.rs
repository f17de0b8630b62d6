//! The link between the harness and the device: frames of real bytes.
//!
//! # Frame
//!
//! The manuals define the PPO telegram (BU 0620 §2.5.5, BU 0590 PPO types) and address an
//! inverter by PROFINET slot or data record (BU 0620 §2.5.6.2: record 100 = bus interface,
//! 101..108 = FI 1..8). A link frame carries exactly that, so the in-memory link holds the bytes
//! a bus would:
//!
//! | byte | field |
//! |---|---|
//! | 0 | data record: 100 = bus interface, 101..=108 = FI 1..8 |
//! | 1 | PPO type (1, 2, 3, 4, 6) |
//! | 2.. | the PPO telegram, big-endian words as in the manuals' examples |
//!
//! [`LinkFrame`] is a checked view over such bytes; [`LinkRepr`] the parsed form. Parsing never
//! panics: short frames and unknown records are typed errors.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::rc::Rc;

/// Data record of the bus interface's own parameters (BU 0620 §2.5.6.2).
pub const RECORD_INTERFACE: u8 = 100;
/// Data record of FI 1; FI n is `RECORD_FI1 + n - 1` (BU 0620 §2.5.6.2).
pub const RECORD_FI1: u8 = 101;

mod field {
    pub(super) const RECORD: usize = 0;
    pub(super) const PPO_TYPE: usize = 1;
    pub(super) const PAYLOAD: usize = 2;
}

/// A malformed link frame.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum LinkFrameError {
    /// Fewer bytes than the header.
    #[error("link frame truncated: need {need} bytes, got {got}")]
    Truncated {
        /// Bytes needed.
        need: usize,
        /// Bytes present.
        got: usize,
    },
    /// A data record that addresses nothing.
    #[error("data record {0} addresses neither the bus interface (100) nor FI 1..8 (101..108)")]
    UnknownRecord(u8),
}

/// Checked view over a link frame.
#[derive(Debug, Clone)]
pub struct LinkFrame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> LinkFrame<T> {
    /// Wraps bytes after checking the header is there and the record is known.
    pub fn new_checked(buffer: T) -> Result<Self, LinkFrameError> {
        let b = buffer.as_ref();
        if b.len() < field::PAYLOAD {
            return Err(LinkFrameError::Truncated {
                need: field::PAYLOAD,
                got: b.len(),
            });
        }
        let record = b[field::RECORD];
        if record != RECORD_INTERFACE && !(RECORD_FI1..RECORD_FI1 + 8).contains(&record) {
            return Err(LinkFrameError::UnknownRecord(record));
        }
        Ok(LinkFrame { buffer })
    }

    /// Data record byte.
    pub fn record(&self) -> u8 {
        self.buffer.as_ref()[field::RECORD]
    }

    /// PPO type byte.
    pub fn ppo_type(&self) -> u8 {
        self.buffer.as_ref()[field::PPO_TYPE]
    }

    /// The PPO telegram.
    pub fn payload(&self) -> &[u8] {
        &self.buffer.as_ref()[field::PAYLOAD..]
    }
}

/// Who a frame is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// The bus interface (record 100).
    Interface,
    /// FI 1..8 (records 101..108).
    Inverter(proto::nord::Inverter),
}

impl Unit {
    /// The data record of the unit.
    pub fn record(self) -> u8 {
        match self {
            Unit::Interface => RECORD_INTERFACE,
            Unit::Inverter(i) => RECORD_FI1 + i.get() - 1,
        }
    }

    fn from_record(record: u8) -> Result<Unit, LinkFrameError> {
        if record == RECORD_INTERFACE {
            return Ok(Unit::Interface);
        }
        proto::nord::Inverter::new(i64::from(record) - i64::from(RECORD_FI1) + 1)
            .map(Unit::Inverter)
            .map_err(|_| LinkFrameError::UnknownRecord(record))
    }
}

/// A parsed link frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinkRepr {
    /// Addressee.
    pub unit: Unit,
    /// PPO type byte as sent (validated by the PPO codec).
    pub ppo_type: u8,
    /// The PPO telegram.
    pub payload: Vec<u8>,
}

impl LinkRepr {
    /// Parses a frame.
    pub fn parse(bytes: &[u8]) -> Result<LinkRepr, LinkFrameError> {
        let f = LinkFrame::new_checked(bytes)?;
        Ok(LinkRepr {
            unit: Unit::from_record(f.record())?,
            ppo_type: f.ppo_type(),
            payload: f.payload().to_vec(),
        })
    }

    /// Length of the emitted frame.
    pub fn buffer_len(&self) -> usize {
        field::PAYLOAD + self.payload.len()
    }

    /// The frame's bytes.
    pub fn emit(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.buffer_len());
        out.push(self.unit.record());
        out.push(self.ppo_type);
        out.extend_from_slice(&self.payload);
        out
    }
}

/// One end of an in-memory link: what one side sends, the other receives, byte for byte.
#[derive(Debug, Clone)]
pub struct MemEnd {
    tx: Rc<RefCell<VecDeque<Vec<u8>>>>,
    rx: Rc<RefCell<VecDeque<Vec<u8>>>>,
}

impl MemEnd {
    /// Queues a frame for the other end.
    pub fn send(&self, frame: Vec<u8>) {
        self.tx.borrow_mut().push_back(frame);
    }

    /// Takes the next frame the other end sent.
    pub fn recv(&self) -> Option<Vec<u8>> {
        self.rx.borrow_mut().pop_front()
    }
}

/// Two connected ends.
pub fn mem_pair() -> (MemEnd, MemEnd) {
    let a = Rc::new(RefCell::new(VecDeque::new()));
    let b = Rc::new(RefCell::new(VecDeque::new()));
    (
        MemEnd {
            tx: a.clone(),
            rx: b.clone(),
        },
        MemEnd { tx: b, rx: a },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proto::nord::Inverter;

    #[test]
    fn round_trip() {
        // FI 5 = record 105; PPO 1 with the P102 order of BU 0620 §2.5.6.4 (24 4E 01 00 00 00 00 FA).
        let r = LinkRepr {
            unit: Unit::Inverter(Inverter::new(5).unwrap()),
            ppo_type: 1,
            payload: vec![0x24, 0x4E, 0x01, 0x00, 0x00, 0x00, 0x00, 0xFA, 0, 0, 0, 0],
        };
        let bytes = r.emit();
        assert_eq!(&bytes[..3], &[105, 1, 0x24]);
        assert_eq!(LinkRepr::parse(&bytes), Ok(r));
    }

    #[test]
    fn truncation_at_every_length() {
        for n in 0..2 {
            assert_eq!(
                LinkRepr::parse(&[100, 1][..n]),
                Err(LinkFrameError::Truncated { need: 2, got: n })
            );
        }
        assert!(LinkRepr::parse(&[100, 1]).is_ok());
    }

    #[test]
    fn unknown_records_are_refused() {
        for rec in [0, 99, 109, 255] {
            assert_eq!(
                LinkRepr::parse(&[rec, 1]),
                Err(LinkFrameError::UnknownRecord(rec))
            );
        }
    }

    #[test]
    fn mem_pair_carries_bytes_in_order() {
        let (a, b) = mem_pair();
        a.send(vec![1]);
        a.send(vec![2]);
        assert_eq!(b.recv(), Some(vec![1]));
        assert_eq!(b.recv(), Some(vec![2]));
        assert_eq!(b.recv(), None);
        b.send(vec![3]);
        assert_eq!(a.recv(), Some(vec![3]));
    }
}
