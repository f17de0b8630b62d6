//! The EtherCAT mailbox: a 6-byte header in front of every acyclic message (CoE, EoE, FoE,
//! SoE, AoE, VoE), written by the master into the mailbox-out SyncManager (SM0) and read from
//! the mailbox-in SyncManager (SM1) (ETG.1000.4 "Mailbox"; ETG.1000.6
//! "Mailbox" and, for the error reply, "Mailbox error reply").
//!
//! | bytes | field |
//! |---|---|
//! | 0–1 | length of the data after the header |
//! | 2–3 | address (station address of the originator; 0 from the master) |
//! | 4 | bits 0–5 channel (0), bits 6–7 priority (0 lowest … 3 highest) |
//! | 5 | bits 0–3 type ([`MailboxType`]), bits 4–6 counter (1..7, 0 = not used), bit 7 reserved |
//!
//! The header's length bounds the message: the bytes after it up to the end of the
//! SyncManager's buffer are padding.

use std::fmt;

use super::wire::{fit, le16};
use crate::wire::{Error, Reader};

/// Mailbox header length.
pub const HEADER_LEN: usize = 6;

/// The type of a mailbox message (ETG.1000.4 / ETG.1000.6 "Mailbox" type field; open).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct MailboxType(pub u8);

impl MailboxType {
    /// Mailbox error reply.
    pub const ERR: MailboxType = MailboxType(0);
    /// ADS over EtherCAT.
    pub const AOE: MailboxType = MailboxType(1);
    /// Ethernet over EtherCAT.
    pub const EOE: MailboxType = MailboxType(2);
    /// CANopen over EtherCAT.
    pub const COE: MailboxType = MailboxType(3);
    /// File access over EtherCAT.
    pub const FOE: MailboxType = MailboxType(4);
    /// Servo profile over EtherCAT.
    pub const SOE: MailboxType = MailboxType(5);
    /// Vendor specific over EtherCAT.
    pub const VOE: MailboxType = MailboxType(15);

    /// The type's name, if defined.
    pub fn name(self) -> Option<&'static str> {
        Some(match self {
            MailboxType::ERR => "ERR",
            MailboxType::AOE => "AoE",
            MailboxType::EOE => "EoE",
            MailboxType::COE => "CoE",
            MailboxType::FOE => "FoE",
            MailboxType::SOE => "SoE",
            MailboxType::VOE => "VoE",
            _ => return None,
        })
    }

    /// The bit of this protocol in SII word 1Ch "mailbox protocol" (ETG.2010 fixed header: AoE
    /// bit 0, EoE 1, CoE 2, FoE 3, SoE 4, VoE 5); `None` for ERR and undefined types.
    pub fn sii_protocol_bit(self) -> Option<u16> {
        Some(match self {
            MailboxType::AOE => 0x01,
            MailboxType::EOE => 0x02,
            MailboxType::COE => 0x04,
            MailboxType::FOE => 0x08,
            MailboxType::SOE => 0x10,
            MailboxType::VOE => 0x20,
            _ => return None,
        })
    }
}

impl fmt::Display for MailboxType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => f.write_str(n),
            None => write!(f, "mailbox type {}", self.0),
        }
    }
}

impl fmt::Debug for MailboxType {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "MailboxType::{}", n.to_ascii_uppercase()),
            None => write!(f, "MailboxType({})", self.0),
        }
    }
}

/// The counter that follows `c` (1..7 cycling, ETG.1000.4 "Mailbox": 0 is "not used", so it is
/// skipped; a repeated counter marks a repeated message).
pub fn next_counter(c: u8) -> u8 {
    if (1..7).contains(&c) {
        c + 1
    } else {
        1
    }
}

/// Checked view over a mailbox message; the buffer may be a whole SyncManager area (padding
/// after the message is allowed).
#[derive(Debug, Clone)]
pub struct Mailbox<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Mailbox<T> {
    /// Wraps a buffer without checking; accessors panic if it is shorter than the header.
    pub fn new_unchecked(buffer: T) -> Self {
        Mailbox { buffer }
    }

    /// Wraps a buffer after checking the header and that the length field fits.
    pub fn new_checked(buffer: T) -> Result<Self, Error> {
        let m = Mailbox { buffer };
        m.check_len()?;
        Ok(m)
    }

    /// Checks the header and the length field against the buffer.
    pub fn check_len(&self) -> Result<(), Error> {
        let got = self.buffer.as_ref().len();
        if got < HEADER_LEN {
            return Err(Error::Truncated {
                what: "mailbox header",
                need: HEADER_LEN,
                got,
            });
        }
        if self.len() > got - HEADER_LEN {
            return Err(Error::Length {
                field: "mailbox length",
                value: self.len(),
                available: got - HEADER_LEN,
            });
        }
        Ok(())
    }

    /// The buffer back.
    pub fn into_inner(self) -> T {
        self.buffer
    }

    fn b(&self) -> &[u8] {
        self.buffer.as_ref()
    }

    /// Data length from the header.
    pub fn len(&self) -> usize {
        usize::from(le16(self.b(), 0))
    }
    /// Whether the length field says 0.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Address field.
    pub fn address(&self) -> u16 {
        le16(self.b(), 2)
    }
    /// Channel (bits 0–5 of byte 4).
    pub fn channel(&self) -> u8 {
        self.b()[4] & 0x3F
    }
    /// Priority (bits 6–7 of byte 4).
    pub fn priority(&self) -> u8 {
        self.b()[4] >> 6
    }
    /// Type (bits 0–3 of byte 5).
    pub fn kind(&self) -> MailboxType {
        MailboxType(self.b()[5] & 0x0F)
    }
    /// Counter (bits 4–6 of byte 5).
    pub fn counter(&self) -> u8 {
        (self.b()[5] >> 4) & 0x07
    }
    /// Reserved bit 7 of byte 5.
    pub fn reserved(&self) -> bool {
        self.b()[5] & 0x80 != 0
    }
    /// The message data (as many bytes as the length says, bounded by the buffer).
    pub fn data(&self) -> &[u8] {
        let end = (HEADER_LEN + self.len()).min(self.b().len());
        &self.b()[HEADER_LEN..end]
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Mailbox<T> {
    /// Sets the length field (negative tests: a lying length).
    pub fn set_len(&mut self, len: u16) {
        self.buffer.as_mut()[0..2].copy_from_slice(&len.to_le_bytes());
    }
    /// Sets the address.
    pub fn set_address(&mut self, a: u16) {
        self.buffer.as_mut()[2..4].copy_from_slice(&a.to_le_bytes());
    }
    /// Sets channel and priority.
    pub fn set_channel_priority(&mut self, channel: u8, priority: u8) {
        self.buffer.as_mut()[4] = channel & 0x3F | (priority & 3) << 6;
    }
    /// Sets the type.
    pub fn set_kind(&mut self, t: MailboxType) {
        let b = &mut self.buffer.as_mut()[5];
        *b = *b & 0xF0 | t.0 & 0x0F;
    }
    /// Sets the counter.
    pub fn set_counter(&mut self, c: u8) {
        let b = &mut self.buffer.as_mut()[5];
        *b = *b & 0x8F | (c & 7) << 4;
    }
    /// The data, writable.
    pub fn data_mut(&mut self) -> &mut [u8] {
        let end = (HEADER_LEN + self.len()).min(self.b().len());
        &mut self.buffer.as_mut()[HEADER_LEN..end]
    }
}

/// A mailbox message.
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct MailboxRepr {
    /// Address (0 from the master; the slave's station address in its replies, or 0).
    pub address: u16,
    /// Channel (0).
    pub channel: u8,
    /// Priority 0..3.
    pub priority: u8,
    /// Type.
    pub kind: MailboxType,
    /// Counter 1..7 (0: not used).
    pub counter: u8,
    /// The data after the header.
    pub data: Vec<u8>,
}

impl MailboxRepr {
    /// A message of `kind` with `counter` and `data`, address/channel/priority 0.
    pub fn new(kind: MailboxType, counter: u8, data: Vec<u8>) -> Self {
        MailboxRepr {
            kind,
            counter,
            data,
            ..MailboxRepr::default()
        }
    }

    /// Reads a checked mailbox view (padding after the message is ignored).
    pub fn parse<T: AsRef<[u8]>>(m: &Mailbox<T>) -> Result<MailboxRepr, Error> {
        m.check_len()?;
        Ok(MailboxRepr {
            address: m.address(),
            channel: m.channel(),
            priority: m.priority(),
            kind: m.kind(),
            counter: m.counter(),
            data: m.data().to_vec(),
        })
    }

    /// Parses a message at the start of `bytes`.
    pub fn parse_bytes(bytes: &[u8]) -> Result<MailboxRepr, Error> {
        MailboxRepr::parse(&Mailbox::new_checked(bytes)?)
    }

    /// Header plus data.
    pub fn buffer_len(&self) -> usize {
        HEADER_LEN + self.data.len()
    }

    /// The message's bytes (no padding).
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let len = fit("mailbox data", self.data.len(), usize::from(u16::MAX))?;
        let mut out = Vec::with_capacity(self.buffer_len());
        out.extend_from_slice(&(len as u16).to_le_bytes());
        out.extend_from_slice(&self.address.to_le_bytes());
        out.push(self.channel & 0x3F | (self.priority & 3) << 6);
        out.push(self.kind.0 & 0x0F | (self.counter & 7) << 4);
        out.extend_from_slice(&self.data);
        Ok(out)
    }

    /// The message padded with zeros to a SyncManager's length `sm_len` (a mailbox is written
    /// whole: the write of its last byte hands it over, ETG.1000.4 "SyncManager" mailbox mode).
    pub fn emit_padded(&self, sm_len: usize) -> Result<Vec<u8>, Error> {
        fit("mailbox message", self.buffer_len(), sm_len)?;
        let mut out = self.emit()?;
        out.resize(sm_len, 0);
        Ok(out)
    }
}

/// A mailbox error detail code (ETG.1000.6 "Mailbox error reply"; open).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct MailboxErrorCode(pub u16);

impl MailboxErrorCode {
    /// Syntax of the 6-byte mailbox header is wrong.
    pub const SYNTAX: MailboxErrorCode = MailboxErrorCode(0x0001);
    /// The mailbox protocol (type) is not supported.
    pub const UNSUPPORTED_PROTOCOL: MailboxErrorCode = MailboxErrorCode(0x0002);
    /// The channel field holds a wrong value.
    pub const INVALID_CHANNEL: MailboxErrorCode = MailboxErrorCode(0x0003);
    /// The service in the mailbox protocol is not supported.
    pub const SERVICE_NOT_SUPPORTED: MailboxErrorCode = MailboxErrorCode(0x0004);
    /// The mailbox protocol's header is wrong (without the 6-byte mailbox header).
    pub const INVALID_HEADER: MailboxErrorCode = MailboxErrorCode(0x0005);
    /// The received data are too short.
    pub const SIZE_TOO_SHORT: MailboxErrorCode = MailboxErrorCode(0x0006);
    /// The slave has no memory left for the message.
    pub const NO_MORE_MEMORY: MailboxErrorCode = MailboxErrorCode(0x0007);
    /// The data length is inconsistent.
    pub const INVALID_SIZE: MailboxErrorCode = MailboxErrorCode(0x0008);
    /// The service is still being processed.
    pub const SERVICE_IN_WORK: MailboxErrorCode = MailboxErrorCode(0x0009);

    /// Every code with its name.
    pub const ALL: [(MailboxErrorCode, &'static str); 9] = [
        (Self::SYNTAX, "Syntax of the mailbox header is wrong"),
        (Self::UNSUPPORTED_PROTOCOL, "Mailbox protocol not supported"),
        (
            Self::INVALID_CHANNEL,
            "Channel field contains a wrong value",
        ),
        (Self::SERVICE_NOT_SUPPORTED, "Service not supported"),
        (Self::INVALID_HEADER, "Invalid protocol header"),
        (Self::SIZE_TOO_SHORT, "Received data too short"),
        (Self::NO_MORE_MEMORY, "No more memory in the slave"),
        (Self::INVALID_SIZE, "Inconsistent data length"),
        (Self::SERVICE_IN_WORK, "Service in work"),
    ];

    /// The code's name, if defined.
    pub fn name(self) -> Option<&'static str> {
        Self::ALL.iter().find(|(c, _)| *c == self).map(|(_, n)| *n)
    }
}

impl fmt::Display for MailboxErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "{:04X}h ({n})", self.0),
            None => write!(f, "{:04X}h", self.0),
        }
    }
}

impl fmt::Debug for MailboxErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "MailboxErrorCode({:04X}h)", self.0)
    }
}

/// The service word of a mailbox error reply (always 1, ETG.1000.6 "Mailbox error reply").
pub const ERROR_SERVICE: u16 = 0x0001;

/// The data of a mailbox error reply (type [`MailboxType::ERR`]): service 1 and the detail.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct MailboxError {
    /// The service word (1).
    pub service: u16,
    /// The detail code.
    pub detail: MailboxErrorCode,
}

impl MailboxError {
    /// An error reply with `detail`.
    pub fn new(detail: MailboxErrorCode) -> Self {
        MailboxError {
            service: ERROR_SERVICE,
            detail,
        }
    }

    /// Parses the 4 data bytes (more are an error).
    pub fn parse(data: &[u8]) -> Result<MailboxError, Error> {
        let mut r = Reader::new(data);
        let service = r.u16("mailbox error service")?;
        let detail = MailboxErrorCode(r.u16("mailbox error detail")?);
        r.finish("mailbox error")?;
        Ok(MailboxError { service, detail })
    }

    /// The 4 data bytes.
    pub fn emit(&self) -> [u8; 4] {
        let s = self.service.to_le_bytes();
        let d = self.detail.0.to_le_bytes();
        [s[0], s[1], d[0], d[1]]
    }

    /// The whole mailbox message (type ERR, the given counter).
    pub fn to_mailbox(&self, counter: u8) -> MailboxRepr {
        MailboxRepr::new(MailboxType::ERR, counter, self.emit().to_vec())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A CoE SDO upload request of 1000h:00 as SOEM writes it into SM0 (128 bytes).
    const COE_UPLOAD: [u8; 16] = [
        0x0A, 0x00, // length 10
        0x00, 0x00, // address 0 (master)
        0x00, // channel 0, priority 0
        0x23, // type 3 CoE, counter 2
        0x00, 0x20, // CoE: number 0, service 2 (SDO request)
        0x40, 0x00, 0x10, 0x00, // SDO: initiate upload, 1000h, sub 0
        0x00, 0x00, 0x00, 0x00, // reserved
    ];

    #[test]
    fn parses_field_by_field() {
        let m = Mailbox::new_checked(&COE_UPLOAD[..]).unwrap();
        assert_eq!(
            (m.len(), m.address(), m.channel(), m.priority()),
            (10, 0, 0, 0)
        );
        assert_eq!(
            (m.kind(), m.counter(), m.reserved()),
            (MailboxType::COE, 2, false)
        );
        assert_eq!(m.data(), &COE_UPLOAD[6..]);
        let r = MailboxRepr::parse(&m).unwrap();
        assert_eq!(
            r,
            MailboxRepr::new(MailboxType::COE, 2, COE_UPLOAD[6..].to_vec())
        );
        assert_eq!(r.emit().unwrap(), COE_UPLOAD);
        let padded = r.emit_padded(128).unwrap();
        assert_eq!((padded.len(), &padded[..16]), (128, &COE_UPLOAD[..]));
        // Padding after the message is ignored.
        assert_eq!(MailboxRepr::parse_bytes(&padded).unwrap(), r);
        assert_eq!(
            r.emit_padded(15),
            Err(Error::TooLong {
                what: "mailbox message",
                len: 16,
                max: 15
            })
        );
    }

    #[test]
    fn truncation_at_every_length_is_an_error() {
        for n in 0..COE_UPLOAD.len() {
            let e = MailboxRepr::parse_bytes(&COE_UPLOAD[..n]).unwrap_err();
            if n < 6 {
                assert_eq!(
                    e,
                    Error::Truncated {
                        what: "mailbox header",
                        need: 6,
                        got: n
                    }
                );
            } else {
                assert_eq!(
                    e,
                    Error::Length {
                        field: "mailbox length",
                        value: 10,
                        available: n - 6
                    }
                );
            }
        }
    }

    #[test]
    fn setters_break_a_valid_message() {
        let mut b = COE_UPLOAD;
        let mut m = Mailbox::new_checked(&mut b[..]).unwrap();
        m.set_kind(MailboxType(7));
        m.set_counter(0);
        m.set_channel_priority(5, 3);
        m.set_address(0x1001);
        m.data_mut()[0] = 0xFF;
        m.set_len(200);
        assert_eq!(&b[..8], [200, 0, 0x01, 0x10, 0xC5, 0x07, 0xFF, 0x20]);
        let m = Mailbox::new_unchecked(&b[..]);
        assert_eq!(
            (m.kind(), m.counter(), m.channel(), m.priority()),
            (MailboxType(7), 0, 5, 3)
        );
        assert_eq!(m.data().len(), 10);
        assert!(m.check_len().is_err());
    }

    #[test]
    fn counters_cycle_1_to_7() {
        let mut c = 0;
        let seq: Vec<u8> = (0..9)
            .map(|_| {
                c = next_counter(c);
                c
            })
            .collect();
        assert_eq!(seq, [1, 2, 3, 4, 5, 6, 7, 1, 2]);
        assert_eq!(next_counter(9), 1);
    }

    #[test]
    fn error_reply() {
        // Mailbox error reply: length 4, type 0, counter 1, service 1, detail 0002h.
        let bytes = [0x04, 0x00, 0x00, 0x00, 0x00, 0x10, 0x01, 0x00, 0x02, 0x00];
        let m = MailboxRepr::parse_bytes(&bytes).unwrap();
        assert_eq!(m.kind, MailboxType::ERR);
        let e = MailboxError::parse(&m.data).unwrap();
        assert_eq!(e, MailboxError::new(MailboxErrorCode::UNSUPPORTED_PROTOCOL));
        assert_eq!(e.to_mailbox(1).emit().unwrap(), bytes);
        assert_eq!(
            e.detail.to_string(),
            "0002h (Mailbox protocol not supported)"
        );
        for n in 0..4 {
            assert!(matches!(
                MailboxError::parse(&bytes[6..6 + n]),
                Err(Error::Truncated { .. })
            ));
        }
        assert!(matches!(
            MailboxError::parse(&[1, 0, 2, 0, 0]),
            Err(Error::Trailing { .. })
        ));
        assert_eq!(MailboxErrorCode(0x42).to_string(), "0042h");
    }

    #[test]
    fn types() {
        assert_eq!(MailboxType::COE.to_string(), "CoE");
        assert_eq!(format!("{:?}", MailboxType::COE), "MailboxType::COE");
        assert_eq!(MailboxType(9).to_string(), "mailbox type 9");
        assert_eq!(MailboxType::COE.sii_protocol_bit(), Some(0x04));
        assert_eq!(MailboxType::ERR.sii_protocol_bit(), None);
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        /// Every header the codec represents: channel 6 bits, priority 2, type 4, counter 3.
        fn mailbox() -> impl Strategy<Value = MailboxRepr> {
            (
                any::<u16>(),
                0u8..=0x3F,
                0u8..=3,
                0u8..=0x0F,
                0u8..=7,
                vec(any::<u8>(), 0..=64),
            )
                .prop_map(|(address, channel, priority, kind, counter, data)| {
                    MailboxRepr {
                        address,
                        channel,
                        priority,
                        kind: MailboxType(kind),
                        counter,
                        data,
                    }
                })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(r in mailbox(), pad in 0usize..16) {
                let bytes = r.emit().unwrap();
                prop_assert_eq!(bytes.len(), r.buffer_len());
                prop_assert_eq!(MailboxRepr::parse_bytes(&bytes), Ok(r.clone()));
                let padded = r.emit_padded(r.buffer_len() + pad).unwrap();
                prop_assert_eq!(MailboxRepr::parse_bytes(&padded), Ok(r));
            }

            #[test]
            fn error_reply_round_trips(service in any::<u16>(), detail in any::<u16>()) {
                let e = MailboxError { service, detail: MailboxErrorCode(detail) };
                prop_assert_eq!(MailboxError::parse(&e.emit()), Ok(e));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..40)) {
                let _ = MailboxRepr::parse_bytes(&bytes);
                let _ = MailboxError::parse(&bytes);
            }
        }
    }
}
