//! SDO over POWERLINK (EPSG DS 301 §6.3): a sequence layer (connection, numbering,
//! acknowledgement) and a command layer (the transfer) carried in ASnd frames of service 5 or
//! in UDP datagrams to port 3819 (§6.3.2.1: the UDP payload starts with the ASnd message type,
//! two reserved bytes and the SDO service id).
//!
//! Sequence layer, 4 bytes: 0 ReceiveSequenceNumber (bits 2–7) and ReceiveCon (bits 0–1);
//! 1 SendSequenceNumber and SendCon; 2–3 reserved. Con: 0 no connection, 1 initialisation,
//! 2 connection valid, 3 error (ReceiveCon: retransmission request; SendCon: valid with
//! acknowledge request).
//!
//! Command layer, 8 bytes and the payload: 0 reserved; 1 TransactionID; 2 flags — response 80h,
//! abort 40h, segmentation bits 4–5 (0 expedited, 1 initiate, 2 segment, 3 complete); 3
//! CommandID; 4–5 SegmentSize (the bytes after these 8, the data size of an initiate included);
//! 6–7 reserved; then the DataSize (u32) of an initiate, then the data. WriteByIndex requests
//! start their data with index (u16), sub-index and a reserved byte; ReadByIndex requests are
//! just those 4 bytes; an abort carries the 4-byte abort code (BU 0620 §2.4.7, BU 2200 §6.4.1).

use std::fmt;

use crate::wire::{Error, Reader};

/// Length of the sequence layer header.
pub const SEQ_LEN: usize = 4;
/// Length of the command layer header (without the data size of an initiate).
pub const CMD_HEADER_LEN: usize = 8;
/// The UDP prefix before the sequence layer: ASnd message type, two reserved bytes, service
/// id 5.
pub const UDP_PREFIX: [u8; 4] = [0x06, 0x00, 0x00, 0x05];
/// Sequence numbers count modulo 64 (6 bits).
pub const SEQ_MODULO: u8 = 64;

/// The connection field of the sequence layer (2 bits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Con {
    /// No connection.
    #[default]
    None,
    /// Initialisation.
    Init,
    /// Connection valid.
    Valid,
    /// ReceiveCon: error, retransmission request; SendCon: valid, acknowledge requested.
    ErrorOrAckRequest,
}

impl Con {
    fn from_bits(b: u8) -> Con {
        match b & 0x03 {
            0 => Con::None,
            1 => Con::Init,
            2 => Con::Valid,
            _ => Con::ErrorOrAckRequest,
        }
    }

    fn bits(self) -> u8 {
        match self {
            Con::None => 0,
            Con::Init => 1,
            Con::Valid => 2,
            Con::ErrorOrAckRequest => 3,
        }
    }
}

/// The sequence layer header.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Seq {
    /// The last sequence number received from the peer (0..63).
    pub rsnr: u8,
    /// ReceiveCon.
    pub rcon: Con,
    /// This frame's sequence number (0..63).
    pub ssnr: u8,
    /// SendCon.
    pub scon: Con,
}

impl Seq {
    /// Parses the 4 bytes.
    fn parse(r: &mut Reader<'_>) -> Result<Seq, Error> {
        let b = r.bytes(SEQ_LEN, "SDO sequence layer")?;
        Ok(Seq {
            rsnr: b[0] >> 2,
            rcon: Con::from_bits(b[0]),
            ssnr: b[1] >> 2,
            scon: Con::from_bits(b[1]),
        })
    }

    fn emit(&self, b: &mut Vec<u8>) {
        b.push(((self.rsnr % SEQ_MODULO) << 2) | self.rcon.bits());
        b.push(((self.ssnr % SEQ_MODULO) << 2) | self.scon.bits());
        b.extend([0, 0]);
    }
}

/// The segmentation of a command-layer frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub enum Segmentation {
    /// The whole transfer in this frame.
    #[default]
    Expedited,
    /// The first segment; the data size follows the header.
    Initiate,
    /// A middle segment.
    Segment,
    /// The last segment.
    Complete,
}

impl Segmentation {
    fn from_bits(b: u8) -> Segmentation {
        match (b >> 4) & 0x03 {
            0 => Segmentation::Expedited,
            1 => Segmentation::Initiate,
            2 => Segmentation::Segment,
            _ => Segmentation::Complete,
        }
    }

    fn bits(self) -> u8 {
        (match self {
            Segmentation::Expedited => 0,
            Segmentation::Initiate => 1,
            Segmentation::Segment => 2,
            Segmentation::Complete => 3,
        }) << 4
    }
}

/// A command id of the SDO command layer (DS 301 §6.3.2.4.2; open).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct CommandId(pub u8);

impl CommandId {
    /// NIL (no command: an acknowledgement).
    pub const NIL: CommandId = CommandId(0x00);
    /// Write by index.
    pub const WRITE_BY_INDEX: CommandId = CommandId(0x01);
    /// Read by index.
    pub const READ_BY_INDEX: CommandId = CommandId(0x02);
    /// Write all by index.
    pub const WRITE_ALL_BY_INDEX: CommandId = CommandId(0x03);
    /// Read all by index.
    pub const READ_ALL_BY_INDEX: CommandId = CommandId(0x04);
    /// Write by name.
    pub const WRITE_BY_NAME: CommandId = CommandId(0x05);
    /// Read by name.
    pub const READ_BY_NAME: CommandId = CommandId(0x06);
    /// File write.
    pub const FILE_WRITE: CommandId = CommandId(0x20);
    /// File read.
    pub const FILE_READ: CommandId = CommandId(0x21);
    /// Write multiple parameters by index.
    pub const WRITE_MULTIPLE_BY_INDEX: CommandId = CommandId(0x31);
    /// Read multiple parameters by index.
    pub const READ_MULTIPLE_BY_INDEX: CommandId = CommandId(0x32);
    /// Maximum segment size.
    pub const MAX_SEGMENT_SIZE: CommandId = CommandId(0x70);

    /// The command's name, if defined.
    pub fn name(self) -> Option<&'static str> {
        Some(match self {
            CommandId::NIL => "NIL",
            CommandId::WRITE_BY_INDEX => "WriteByIndex",
            CommandId::READ_BY_INDEX => "ReadByIndex",
            CommandId::WRITE_ALL_BY_INDEX => "WriteAllByIndex",
            CommandId::READ_ALL_BY_INDEX => "ReadAllByIndex",
            CommandId::WRITE_BY_NAME => "WriteByName",
            CommandId::READ_BY_NAME => "ReadByName",
            CommandId::FILE_WRITE => "FileWrite",
            CommandId::FILE_READ => "FileRead",
            CommandId::WRITE_MULTIPLE_BY_INDEX => "WriteMultipleParameterByIndex",
            CommandId::READ_MULTIPLE_BY_INDEX => "ReadMultipleParameterByIndex",
            CommandId::MAX_SEGMENT_SIZE => "MaximumSegmentSize",
            _ => return None,
        })
    }
}

impl fmt::Debug for CommandId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "{n}"),
            None => write!(f, "CommandId({:02X}h)", self.0),
        }
    }
}

/// A command-layer frame.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Command {
    /// TransactionID: a response carries its request's.
    pub transaction: u8,
    /// A response (from the server).
    pub response: bool,
    /// An abort: the payload is the abort code.
    pub abort: bool,
    /// Segmentation.
    pub segmentation: Segmentation,
    /// The command.
    pub command: CommandId,
    /// DataSize of an initiate: the whole transfer's size.
    pub data_size: Option<u32>,
    /// The bytes after the header (and the data size).
    pub payload: Vec<u8>,
}

impl Command {
    /// A ReadByIndex request (expedited).
    pub fn read_by_index(transaction: u8, index: u16, sub: u8) -> Command {
        let mut payload = index.to_le_bytes().to_vec();
        payload.extend([sub, 0]);
        Command {
            transaction,
            command: CommandId::READ_BY_INDEX,
            payload,
            ..Command::default()
        }
    }

    /// A WriteByIndex request carrying all of `data` (expedited).
    pub fn write_by_index(transaction: u8, index: u16, sub: u8, data: &[u8]) -> Command {
        let mut payload = index.to_le_bytes().to_vec();
        payload.extend([sub, 0]);
        payload.extend(data);
        Command {
            transaction,
            command: CommandId::WRITE_BY_INDEX,
            payload,
            ..Command::default()
        }
    }

    /// An abort of `transaction` with `code` (from the server when `response`).
    pub fn abort(transaction: u8, command: CommandId, response: bool, code: u32) -> Command {
        Command {
            transaction,
            response,
            abort: true,
            command,
            payload: code.to_le_bytes().to_vec(),
            ..Command::default()
        }
    }

    /// The abort code of an abort frame.
    pub fn abort_code(&self) -> Option<u32> {
        if !self.abort {
            return None;
        }
        let b = self.payload.get(..4)?;
        Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// The index, sub-index and the data after them of a by-index request.
    pub fn by_index(&self) -> Result<(u16, u8, &[u8]), Error> {
        let mut r = Reader::new(&self.payload);
        let index = r.u16("SDO index")?;
        let sub = r.u8("SDO sub-index")?;
        r.u8("SDO reserved")?;
        Ok((index, sub, r.rest()))
    }

    fn parse(r: &mut Reader<'_>) -> Result<Command, Error> {
        r.u8("SDO command reserved")?;
        let transaction = r.u8("SDO TransactionID")?;
        let flags = r.u8("SDO command flags")?;
        let command = CommandId(r.u8("SDO CommandID")?);
        let size = usize::from(r.u16("SDO SegmentSize")?);
        r.u16("SDO command reserved")?;
        if size > r.remaining() {
            return Err(Error::Length {
                field: "SDO SegmentSize",
                value: size,
                available: r.remaining(),
            });
        }
        let segmentation = Segmentation::from_bits(flags);
        let mut body = Reader::new(r.bytes(size, "SDO segment")?);
        let data_size = match segmentation {
            Segmentation::Initiate if flags & 0x40 == 0 => Some(body.u32("SDO DataSize")?),
            _ => None,
        };
        Ok(Command {
            transaction,
            response: flags & 0x80 != 0,
            abort: flags & 0x40 != 0,
            segmentation,
            command,
            data_size,
            payload: body.rest().to_vec(),
        })
    }

    fn emit(&self, b: &mut Vec<u8>) -> Result<(), Error> {
        let size = self.payload.len() + if self.data_size.is_some() { 4 } else { 0 };
        let size = u16::try_from(size).map_err(|_| Error::TooLong {
            what: "SDO segment",
            len: size,
            max: usize::from(u16::MAX),
        })?;
        let flags = if self.response { 0x80 } else { 0 }
            | if self.abort { 0x40 } else { 0 }
            | self.segmentation.bits();
        b.extend([0, self.transaction, flags, self.command.0]);
        b.extend(size.to_le_bytes());
        b.extend([0, 0]);
        if let Some(n) = self.data_size {
            b.extend(n.to_le_bytes());
        }
        b.extend(&self.payload);
        Ok(())
    }
}

/// An SDO frame: the sequence layer and, unless it only manages the connection, a command.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct SdoFrame {
    /// The sequence layer.
    pub seq: Seq,
    /// The command layer, if any.
    pub command: Option<Command>,
}

impl SdoFrame {
    /// Parses the bytes after the ASnd ServiceID (or after [`UDP_PREFIX`]). Bytes after a
    /// command's segment are padding.
    pub fn parse(bytes: &[u8]) -> Result<SdoFrame, Error> {
        let mut r = Reader::new(bytes);
        let seq = Seq::parse(&mut r)?;
        // Nothing, or only zeros (Ethernet padding), after the sequence layer: a connection or
        // acknowledgement frame without a command (a command has at least its size or id).
        let command = if bytes[SEQ_LEN..].iter().all(|&b| b == 0) {
            None
        } else {
            Some(Command::parse(&mut r)?)
        };
        Ok(SdoFrame { seq, command })
    }

    /// The bytes after the ServiceID.
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut b = Vec::with_capacity(SEQ_LEN + CMD_HEADER_LEN + 8);
        self.seq.emit(&mut b);
        if let Some(c) = &self.command {
            c.emit(&mut b)?;
        }
        Ok(b)
    }

    /// A UDP datagram's SDO bytes: checks and strips [`UDP_PREFIX`].
    pub fn strip_udp(datagram: &[u8]) -> Result<&[u8], Error> {
        let head = datagram.get(..UDP_PREFIX.len()).ok_or(Error::Truncated {
            what: "POWERLINK UDP header",
            need: UDP_PREFIX.len(),
            got: datagram.len(),
        })?;
        if head[0] & 0x7F != UDP_PREFIX[0] {
            return Err(Error::Unknown {
                field: "POWERLINK UDP MessageType",
                value: u32::from(head[0]),
            });
        }
        if head[3] != UDP_PREFIX[3] {
            return Err(Error::Unknown {
                field: "POWERLINK UDP ServiceID",
                value: u32::from(head[3]),
            });
        }
        Ok(&datagram[UDP_PREFIX.len()..])
    }

    /// The UDP datagram carrying this frame.
    pub fn emit_udp(&self) -> Result<Vec<u8>, Error> {
        let mut b = UDP_PREFIX.to_vec();
        b.extend(self.emit()?);
        Ok(b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn read_request_bytes() {
        // Sequence: rsnr 3 rcon valid (0E), ssnr 4 scon valid (12), reserved.
        // Command: reserved, tid 7, flags 00 (request, expedited), ReadByIndex, size 4,
        // reserved, index 2066h, sub 1, reserved.
        let f = SdoFrame {
            seq: Seq {
                rsnr: 3,
                rcon: Con::Valid,
                ssnr: 4,
                scon: Con::Valid,
            },
            command: Some(Command::read_by_index(7, 0x2066, 1)),
        };
        let b = f.emit().unwrap();
        assert_eq!(
            b,
            [0x0E, 0x12, 0, 0, 0, 7, 0x00, 0x02, 4, 0, 0, 0, 0x66, 0x20, 0x01, 0x00]
        );
        assert_eq!(SdoFrame::parse(&b).unwrap(), f);
        let mut padded = b.clone();
        padded.extend([0; 20]);
        assert_eq!(SdoFrame::parse(&padded).unwrap(), f);
        assert_eq!(f.command.unwrap().by_index().unwrap(), (0x2066, 1, &[][..]));
    }

    #[test]
    fn abort_and_initiate() {
        let a = Command::abort(7, CommandId::WRITE_BY_INDEX, true, 0x0601_0002);
        let f = SdoFrame {
            seq: Seq::default(),
            command: Some(a),
        };
        let b = f.emit().unwrap();
        assert_eq!(
            &b[4..],
            [0, 7, 0xC0, 0x01, 4, 0, 0, 0, 0x02, 0x00, 0x01, 0x06]
        );
        let back = SdoFrame::parse(&b).unwrap().command.unwrap();
        assert_eq!(back.abort_code(), Some(0x0601_0002));
        let init = Command {
            transaction: 1,
            segmentation: Segmentation::Initiate,
            command: CommandId::WRITE_BY_INDEX,
            data_size: Some(1000),
            payload: vec![1, 2, 3],
            ..Command::default()
        };
        let f = SdoFrame {
            seq: Seq::default(),
            command: Some(init),
        };
        let b = f.emit().unwrap();
        // reserved, tid 1, flags initiate, WriteByIndex, size 7 (data size + 3), reserved.
        assert_eq!(&b[4..12], [0, 1, 0x10, 0x01, 7, 0, 0, 0]);
        assert_eq!(&b[12..16], 1000u32.to_le_bytes());
        assert_eq!(SdoFrame::parse(&b).unwrap(), f);
    }

    #[test]
    fn connection_frames_and_bad_sizes() {
        // Init request: rcon 0, scon 1, no command.
        let f = SdoFrame::parse(&[0x00, 0x01, 0, 0]).unwrap();
        assert_eq!(f.seq.scon, Con::Init);
        assert!(f.command.is_none());
        assert!(SdoFrame::parse(&[0x00, 0x01, 0]).is_err());
        // Segment size 50 with 4 bytes present.
        let b = [0x0A, 0x0A, 0, 0, 0, 1, 0, 2, 50, 0, 0, 0, 1, 2, 3, 4];
        assert!(matches!(
            SdoFrame::parse(&b),
            Err(Error::Length {
                field: "SDO SegmentSize",
                ..
            })
        ));
        // A command header cut short.
        assert!(SdoFrame::parse(&[0x0A, 0x0A, 0, 0, 0, 1, 0]).is_err());
    }

    #[test]
    fn udp_prefix() {
        let f = SdoFrame::default();
        let d = f.emit_udp().unwrap();
        assert_eq!(&d[..4], UDP_PREFIX);
        assert_eq!(SdoFrame::strip_udp(&d).unwrap(), &d[4..]);
        assert!(SdoFrame::strip_udp(&[6, 0, 0]).is_err());
        assert!(matches!(
            SdoFrame::strip_udp(&[6, 0, 0, 1, 0, 0, 0, 0]),
            Err(Error::Unknown { .. })
        ));
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn con() -> impl Strategy<Value = Con> {
            prop_oneof![
                Just(Con::None),
                Just(Con::Init),
                Just(Con::Valid),
                Just(Con::ErrorOrAckRequest),
            ]
        }

        fn seq() -> impl Strategy<Value = Seq> {
            (0..SEQ_MODULO, con(), 0..SEQ_MODULO, con()).prop_map(|(rsnr, rcon, ssnr, scon)| Seq {
                rsnr,
                rcon,
                ssnr,
                scon,
            })
        }

        fn segmentation() -> impl Strategy<Value = Segmentation> {
            prop_oneof![
                Just(Segmentation::Expedited),
                Just(Segmentation::Initiate),
                Just(Segmentation::Segment),
                Just(Segmentation::Complete),
            ]
        }

        /// A command as the codec carries it: a DataSize exactly on an initiate that is not an
        /// abort. An all-zero command without payload (NIL, TransactionID 0, expedited request)
        /// is left out: its bytes are those of Ethernet padding, which `parse` reads as "no
        /// command" by design.
        fn command() -> impl Strategy<Value = Command> {
            (
                any::<u8>(),
                any::<bool>(),
                any::<bool>(),
                segmentation(),
                any::<u8>(),
                any::<u32>(),
                vec(any::<u8>(), 0..=48),
            )
                .prop_map(
                    |(transaction, response, abort, segmentation, command, size, payload)| {
                        Command {
                            transaction,
                            response,
                            abort,
                            segmentation,
                            command: CommandId(command),
                            data_size: (segmentation == Segmentation::Initiate && !abort)
                                .then_some(size),
                            payload,
                        }
                    },
                )
                .prop_filter("all-zero command reads as padding", |c| {
                    c.transaction != 0
                        || c.response
                        || c.abort
                        || c.segmentation != Segmentation::Expedited
                        || c.command != CommandId::NIL
                        || !c.payload.is_empty()
                })
        }

        fn frame() -> impl Strategy<Value = SdoFrame> {
            (seq(), proptest::option::of(command()))
                .prop_map(|(seq, command)| SdoFrame { seq, command })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn emit_then_parse_round_trips(f in frame(), padding in 0usize..8) {
                let mut b = f.emit().unwrap();
                prop_assert_eq!(SdoFrame::parse(&b), Ok(f.clone()));
                // Ethernet padding after the frame is ignored.
                b.resize(b.len() + padding, 0);
                prop_assert_eq!(SdoFrame::parse(&b), Ok(f.clone()));
                let udp = f.emit_udp().unwrap();
                prop_assert_eq!(SdoFrame::parse(SdoFrame::strip_udp(&udp).unwrap()), Ok(f));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..32)) {
                let _ = SdoFrame::parse(&bytes);
                if let Ok(rest) = SdoFrame::strip_udp(&bytes) {
                    let _ = SdoFrame::parse(rest);
                }
            }
        }
    }
}
