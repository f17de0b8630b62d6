//! SDO block transfer (CiA 301 "SDO block download" and "SDO block upload"): an initiate
//! exchange, sub-blocks of up to 127 segments each acknowledged at once, and an end exchange
//! carrying the CRC of the whole data set ([`super::crc16`]) when both sides support it.
//!
//! | frame | command byte | bytes 1–7 |
//! |---|---|---|
//! | initiate block download (client) | ccs 6; cc (bit 2); s (bit 1); cs 0 | index; sub; size (u32) if s |
//! | initiate block download response | scs 5; sc (bit 2); ss 0 | index; sub; blksize |
//! | sub-block segment (client) | c (bit 7); seqno 1..127 | 7 bytes of data |
//! | block download response | scs 5; ss 2 | ackseq; blksize |
//! | end block download (client) | ccs 6; n (bits 4–2); cs 1 | CRC (u16) |
//! | end block download response | scs 5; ss 1 | reserved |
//! | initiate block upload (client) | ccs 5; cc (bit 2); cs 0 | index; sub; blksize; pst |
//! | initiate block upload response | scs 6; sc (bit 2); s (bit 1); ss 0 | index; sub; size (u32) if s |
//! | start upload (client) | ccs 5; cs 3 | reserved |
//! | sub-block segment (server) | c; seqno | 7 bytes of data |
//! | block upload response (client) | ccs 5; cs 2 | ackseq; blksize |
//! | end block upload (server) | scs 6; n (bits 4–2); ss 1 | CRC (u16) |
//! | end block upload response (client) | ccs 5; cs 1 | reserved |
//!
//! blksize (segments per sub-block) is 1..127; ackseq is the sequence number of the last
//! segment received in order (0: none); n counts the bytes of the last segment that carry no
//! data (0..6). pst > 0 lets the server answer an initiate block upload with a normal upload
//! when the data set has at most pst bytes.

use super::command::{head, ClientCommand, SdoFrame, ServerCommand, FRAME_LEN, SEGMENT_DATA};
use crate::wire::Error;

/// The largest number of segments in a sub-block (blksize, seqno).
pub const MAX_BLOCK_SIZE: u8 = 127;
/// cc / sc: CRC supported (bit 2 of the initiate commands).
pub const CRC_SUPPORTED: u8 = 0x04;
/// s: size indicated (bit 1 of the initiate block commands).
pub const SIZE: u8 = 0x02;
/// c: the last segment of the transfer (bit 7 of a sub-block segment).
pub const LAST_SEGMENT: u8 = 0x80;

/// A command of the client in a block transfer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BlockRequest {
    /// Initiate block download (ccs 6, cs 0).
    InitiateDownload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// cc: the client can generate the CRC.
        crc: bool,
        /// The data set size, if indicated (s).
        size: Option<u32>,
    },
    /// End block download (ccs 6, cs 1).
    EndDownload {
        /// n: bytes of the last segment without data (0..6).
        unused: u8,
        /// The CRC of the data set (0 when either side lacks CRC support).
        crc: u16,
    },
    /// Initiate block upload (ccs 5, cs 0).
    InitiateUpload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// cc: the client can check the CRC.
        crc: bool,
        /// Segments per sub-block (1..127).
        blksize: u8,
        /// Protocol switch threshold (0: no switch).
        pst: u8,
    },
    /// End block upload response (ccs 5, cs 1).
    EndUpload,
    /// Block upload response (ccs 5, cs 2): the sub-block is acknowledged.
    UploadAck {
        /// The last segment received in order (0..127).
        ackseq: u8,
        /// Segments in the next sub-block (1..127).
        blksize: u8,
    },
    /// Start upload (ccs 5, cs 3).
    StartUpload,
}

/// A command of the server in a block transfer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BlockResponse {
    /// Initiate block download response (scs 5, ss 0).
    InitiateDownload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// sc: the server can check the CRC.
        crc: bool,
        /// Segments per sub-block (1..127).
        blksize: u8,
    },
    /// End block download response (scs 5, ss 1).
    EndDownload,
    /// Block download response (scs 5, ss 2): the sub-block is acknowledged.
    DownloadAck {
        /// The last segment received in order (0..127).
        ackseq: u8,
        /// Segments in the next sub-block (1..127).
        blksize: u8,
    },
    /// Initiate block upload response (scs 6, ss 0).
    InitiateUpload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// sc: the server can generate the CRC.
        crc: bool,
        /// The data set size, if indicated (s).
        size: Option<u32>,
    },
    /// End block upload (scs 6, ss 1).
    EndUpload {
        /// n: bytes of the last segment without data (0..6).
        unused: u8,
        /// The CRC of the data set.
        crc: u16,
    },
}

fn blksize(value: u8) -> Result<u8, Error> {
    if (1..=MAX_BLOCK_SIZE).contains(&value) {
        Ok(value)
    } else {
        Err(Error::Invalid {
            field: "SDO blksize",
            value: u32::from(value),
            why: "a sub-block has 1 to 127 segments",
        })
    }
}

fn ackseq(value: u8) -> Result<u8, Error> {
    if value <= MAX_BLOCK_SIZE {
        Ok(value)
    } else {
        Err(Error::Invalid {
            field: "SDO ackseq",
            value: u32::from(value),
            why: "a sequence number is 0 to 127",
        })
    }
}

fn unused(command: u8) -> Result<u8, Error> {
    let n = (command >> 2) & 0x07;
    if usize::from(n) < SEGMENT_DATA {
        Ok(n)
    } else {
        Err(Error::Invalid {
            field: "SDO block end n",
            value: u32::from(n),
            why: "the last segment carries at least 1 byte, so n is 0 to 6",
        })
    }
}

fn size<T: AsRef<[u8]>>(f: &SdoFrame<T>) -> Option<u32> {
    (f.command() & SIZE != 0).then(|| f.data_u32())
}

fn crc<T: AsRef<[u8]>>(f: &SdoFrame<T>) -> u16 {
    u16::from_le_bytes([f.byte(1), f.byte(2)])
}

fn flag(on: bool, bit: u8) -> u8 {
    if on {
        bit
    } else {
        0
    }
}

/// An initiate frame with the size (s) in bytes 4–7.
fn with_size(command: u8, index: u16, sub: u8, crc: bool, size: Option<u32>) -> [u8; 8] {
    let mut b = head(
        command | flag(crc, CRC_SUPPORTED) | flag(size.is_some(), SIZE),
        index,
        sub,
    );
    b[4..].copy_from_slice(&size.unwrap_or(0).to_le_bytes());
    b
}

/// A frame of `command`, then `bytes` from byte 1.
fn short(command: u8, bytes: &[u8]) -> [u8; FRAME_LEN] {
    let mut b = [0; FRAME_LEN];
    b[0] = command;
    b[1..1 + bytes.len().min(7)].copy_from_slice(&bytes[..bytes.len().min(7)]);
    b
}

impl BlockRequest {
    /// Reads a frame whose ccs is 5 or 6.
    pub(crate) fn parse<T: AsRef<[u8]>>(f: &SdoFrame<T>) -> Result<BlockRequest, Error> {
        let cmd = f.command();
        let (index, sub) = (f.index(), f.sub());
        let crc_bit = cmd & CRC_SUPPORTED != 0;
        Ok(match (ClientCommand::of(cmd), cmd & 0x03) {
            (ClientCommand::BLOCK_DOWNLOAD, 0 | 2) => BlockRequest::InitiateDownload {
                index,
                sub,
                crc: crc_bit,
                size: size(f),
            },
            (ClientCommand::BLOCK_DOWNLOAD, _) => BlockRequest::EndDownload {
                unused: unused(cmd)?,
                crc: crc(f),
            },
            (_, 0) => BlockRequest::InitiateUpload {
                index,
                sub,
                crc: crc_bit,
                blksize: blksize(f.byte(4))?,
                pst: f.byte(5),
            },
            (_, 1) => BlockRequest::EndUpload,
            (_, 2) => BlockRequest::UploadAck {
                ackseq: ackseq(f.byte(1))?,
                blksize: blksize(f.byte(2))?,
            },
            _ => BlockRequest::StartUpload,
        })
    }

    /// The 8 bytes of the frame (fields out of range are written masked, not refused, so a
    /// test can send them).
    pub fn emit(&self) -> [u8; FRAME_LEN] {
        let up = ClientCommand::BLOCK_UPLOAD.bits();
        let down = ClientCommand::BLOCK_DOWNLOAD.bits();
        match *self {
            BlockRequest::InitiateDownload {
                index,
                sub,
                crc,
                size,
            } => with_size(down, index, sub, crc, size),
            BlockRequest::EndDownload { unused, crc } => {
                short(down | (unused & 0x07) << 2 | 1, &crc.to_le_bytes())
            }
            BlockRequest::InitiateUpload {
                index,
                sub,
                crc,
                blksize,
                pst,
            } => {
                let mut b = head(up | flag(crc, CRC_SUPPORTED), index, sub);
                b[4] = blksize;
                b[5] = pst;
                b
            }
            BlockRequest::EndUpload => short(up | 1, &[]),
            BlockRequest::UploadAck { ackseq, blksize } => short(up | 2, &[ackseq, blksize]),
            BlockRequest::StartUpload => short(up | 3, &[]),
        }
    }
}

impl BlockResponse {
    /// Reads a frame whose scs is 5 or 6.
    pub(crate) fn parse<T: AsRef<[u8]>>(f: &SdoFrame<T>) -> Result<BlockResponse, Error> {
        let cmd = f.command();
        let (index, sub) = (f.index(), f.sub());
        let crc_bit = cmd & CRC_SUPPORTED != 0;
        Ok(match (ServerCommand::of(cmd), cmd & 0x03) {
            (ServerCommand::BLOCK_DOWNLOAD, 0) => BlockResponse::InitiateDownload {
                index,
                sub,
                crc: crc_bit,
                blksize: blksize(f.byte(4))?,
            },
            (ServerCommand::BLOCK_DOWNLOAD, 1) => BlockResponse::EndDownload,
            (ServerCommand::BLOCK_DOWNLOAD, 2) => BlockResponse::DownloadAck {
                ackseq: ackseq(f.byte(1))?,
                blksize: blksize(f.byte(2))?,
            },
            (ServerCommand::BLOCK_DOWNLOAD, ss) => {
                return Err(Error::Unknown {
                    field: "SDO block download server subcommand",
                    value: u32::from(ss),
                })
            }
            (_, 0 | 2) => BlockResponse::InitiateUpload {
                index,
                sub,
                crc: crc_bit,
                size: size(f),
            },
            _ => BlockResponse::EndUpload {
                unused: unused(cmd)?,
                crc: crc(f),
            },
        })
    }

    /// The 8 bytes of the frame (fields out of range are written masked, not refused).
    pub fn emit(&self) -> [u8; FRAME_LEN] {
        let down = ServerCommand::BLOCK_DOWNLOAD.bits();
        let up = ServerCommand::BLOCK_UPLOAD.bits();
        match *self {
            BlockResponse::InitiateDownload {
                index,
                sub,
                crc,
                blksize,
            } => {
                let mut b = head(down | flag(crc, CRC_SUPPORTED), index, sub);
                b[4] = blksize;
                b
            }
            BlockResponse::EndDownload => short(down | 1, &[]),
            BlockResponse::DownloadAck { ackseq, blksize } => short(down | 2, &[ackseq, blksize]),
            BlockResponse::InitiateUpload {
                index,
                sub,
                crc,
                size,
            } => with_size(up, index, sub, crc, size),
            BlockResponse::EndUpload { unused, crc } => {
                short(up | (unused & 0x07) << 2 | 1, &crc.to_le_bytes())
            }
        }
    }
}

/// A segment of a sub-block: no command byte, but c (bit 7) and the sequence number
/// 1..127 (bits 6–0), then 7 bytes of data (the last segment's final n bytes are padding,
/// n from the end frame).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct BlockSegment {
    /// seqno, 1..127.
    pub seqno: u8,
    /// c: the last segment of the data set.
    pub last: bool,
    /// The 7 data bytes.
    pub data: [u8; SEGMENT_DATA],
}

impl BlockSegment {
    /// Parses 8 bytes; a sequence number of 0 is [`Error::Invalid`].
    pub fn parse(bytes: &[u8]) -> Result<BlockSegment, Error> {
        let f = SdoFrame::new_checked(bytes)?;
        let seqno = f.command() & 0x7F;
        if seqno == 0 {
            return Err(Error::Invalid {
                field: "SDO block segment seqno",
                value: 0,
                why: "sequence numbers start at 1",
            });
        }
        let mut data = [0; SEGMENT_DATA];
        data.copy_from_slice(f.segment());
        Ok(BlockSegment {
            seqno,
            last: f.command() & LAST_SEGMENT != 0,
            data,
        })
    }

    /// The 8 bytes (seqno masked to 7 bits).
    pub fn emit(&self) -> [u8; FRAME_LEN] {
        let mut b = [0; FRAME_LEN];
        b[0] = self.seqno & 0x7F | flag(self.last, LAST_SEGMENT);
        b[1..].copy_from_slice(&self.data);
        b
    }

    /// n of the end frame for a data set of `len` bytes: the padding in its last segment.
    pub fn unused_in_last(len: usize) -> u8 {
        ((SEGMENT_DATA - len % SEGMENT_DATA) % SEGMENT_DATA) as u8
    }
}

/// The receiving side of one sub-block: segments must come with sequence numbers 1, 2, … up
/// to blksize, or the last one of the data set earlier; the acknowledgement's ackseq is the
/// last one received in order.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SubBlock {
    blksize: u8,
    ackseq: u8,
    done: bool,
}

impl SubBlock {
    /// A sub-block of `blksize` segments (1..127).
    pub fn new(blksize: u8) -> Result<SubBlock, Error> {
        Ok(SubBlock {
            blksize: self::blksize(blksize)?,
            ackseq: 0,
            done: false,
        })
    }

    /// Takes the next segment: [`Error::SdoBlockSequence`] if it is not the one expected (CiA 301
    /// abort code 0504_0003h); `Ok(true)` when the sub-block is complete (blksize segments,
    /// or the last one of the data set).
    pub fn accept(&mut self, seg: &BlockSegment) -> Result<bool, Error> {
        let expected = self.ackseq + 1;
        if self.done || seg.seqno != expected {
            return Err(Error::SdoBlockSequence {
                expected,
                got: seg.seqno,
            });
        }
        self.ackseq = expected;
        self.done = seg.last || expected == self.blksize;
        Ok(self.done)
    }

    /// The ackseq to answer with: the last segment received in order.
    pub fn ackseq(&self) -> u8 {
        self.ackseq
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canopen::{crc16, SdoRequest, SdoResponse};

    fn req(r: BlockRequest, bytes: [u8; 8]) {
        assert_eq!(r.emit(), bytes, "{r:?}");
        assert_eq!(SdoRequest::parse(&bytes), Ok(SdoRequest::Block(r)));
    }

    fn resp(r: BlockResponse, bytes: [u8; 8]) {
        assert_eq!(r.emit(), bytes, "{r:?}");
        assert_eq!(SdoResponse::parse(&bytes), Ok(SdoResponse::Block(r)));
    }

    #[test]
    fn block_download() {
        // A download of 9 bytes "123456789" to 1F50h:01 in one sub-block of 2 segments.
        // C6h: ccs 6, cc = 1, s = 1, cs = 0; size 9.
        req(
            BlockRequest::InitiateDownload {
                index: 0x1F50,
                sub: 1,
                crc: true,
                size: Some(9),
            },
            [0xC6, 0x50, 0x1F, 0x01, 9, 0, 0, 0],
        );
        // A4h: scs 5, sc = 1, ss = 0; blksize 127.
        resp(
            BlockResponse::InitiateDownload {
                index: 0x1F50,
                sub: 1,
                crc: true,
                blksize: 127,
            },
            [0xA4, 0x50, 0x1F, 0x01, 127, 0, 0, 0],
        );
        // Segments: 01h "1234567", then 82h (c = 1, seqno 2) "89" and 5 bytes padding.
        let s1 = BlockSegment {
            seqno: 1,
            last: false,
            data: *b"1234567",
        };
        let s2 = BlockSegment {
            seqno: 2,
            last: true,
            data: [b'8', b'9', 0, 0, 0, 0, 0],
        };
        assert_eq!(s1.emit()[0], 0x01);
        assert_eq!(s2.emit(), [0x82, b'8', b'9', 0, 0, 0, 0, 0]);
        assert_eq!(BlockSegment::parse(&s2.emit()), Ok(s2));
        let mut sb = SubBlock::new(127).unwrap();
        assert_eq!(sb.accept(&s1), Ok(false));
        assert_eq!(sb.accept(&s2), Ok(true));
        // A2h: scs 5, ss = 2; ackseq 2, blksize 127.
        resp(
            BlockResponse::DownloadAck {
                ackseq: sb.ackseq(),
                blksize: 127,
            },
            [0xA2, 2, 127, 0, 0, 0, 0, 0],
        );
        // D5h: ccs 6, n = 5, cs = 1; CRC 31C3h little-endian.
        assert_eq!(BlockSegment::unused_in_last(9), 5);
        req(
            BlockRequest::EndDownload {
                unused: 5,
                crc: crc16(b"123456789"),
            },
            [0xD5, 0xC3, 0x31, 0, 0, 0, 0, 0],
        );
        // A1h: scs 5, ss = 1.
        resp(BlockResponse::EndDownload, [0xA1, 0, 0, 0, 0, 0, 0, 0]);
        // Without size and without CRC: C0h.
        req(
            BlockRequest::InitiateDownload {
                index: 0x2000,
                sub: 0,
                crc: false,
                size: None,
            },
            [0xC0, 0x00, 0x20, 0x00, 0, 0, 0, 0],
        );
    }

    #[test]
    fn block_upload() {
        // A4h: ccs 5, cc = 1, cs = 0; blksize 16, pst 0.
        req(
            BlockRequest::InitiateUpload {
                index: 0x1008,
                sub: 0,
                crc: true,
                blksize: 16,
                pst: 0,
            },
            [0xA4, 0x08, 0x10, 0x00, 16, 0, 0, 0],
        );
        // C6h: scs 6, sc = 1, s = 1, ss = 0; size 7.
        resp(
            BlockResponse::InitiateUpload {
                index: 0x1008,
                sub: 0,
                crc: true,
                size: Some(7),
            },
            [0xC6, 0x08, 0x10, 0x00, 7, 0, 0, 0],
        );
        // A3h: start upload.
        req(BlockRequest::StartUpload, [0xA3, 0, 0, 0, 0, 0, 0, 0]);
        // A2h: block upload response, ackseq 1, blksize 16.
        req(
            BlockRequest::UploadAck {
                ackseq: 1,
                blksize: 16,
            },
            [0xA2, 1, 16, 0, 0, 0, 0, 0],
        );
        // C1h: scs 6, n = 0, ss = 1; the CRC of 7 bytes.
        let crc = crc16(b"SK 500E");
        resp(
            BlockResponse::EndUpload { unused: 0, crc },
            [0xC1, crc as u8, (crc >> 8) as u8, 0, 0, 0, 0, 0],
        );
        // A1h: end block upload response.
        req(BlockRequest::EndUpload, [0xA1, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(BlockSegment::unused_in_last(7), 0);
        assert_eq!(BlockSegment::unused_in_last(8), 6);
    }

    #[test]
    fn out_of_range_fields_are_errors() {
        // blksize 0 and 128, ackseq 128, n = 7, ss = 3 of a download, seqno 0.
        let cases: [([u8; 8], &str); 6] = [
            ([0xA4, 0x08, 0x10, 0x00, 0, 0, 0, 0], "SDO blksize"),
            ([0xA2, 1, 128, 0, 0, 0, 0, 0], "SDO blksize"),
            ([0xA2, 128, 1, 0, 0, 0, 0, 0], "SDO ackseq"),
            ([0xDD, 0, 0, 0, 0, 0, 0, 0], "SDO block end n"),
            ([0xA4, 0x08, 0x10, 0x00, 128, 0, 0, 0], "SDO blksize"),
            ([0xC1 | 7 << 2, 0, 0, 0, 0, 0, 0, 0], "SDO block end n"),
        ];
        for (i, (b, field)) in cases.into_iter().enumerate() {
            // The first three and the fifth are requests, the others a request (DDh) and a
            // response (DDh as scs 6).
            let r = if i == 5 {
                SdoResponse::parse(&b).map(|_| ())
            } else {
                SdoRequest::parse(&b).map(|_| ())
            };
            assert!(
                matches!(r, Err(Error::Invalid { field: f, .. }) if f == field),
                "{b:02X?}: {r:?}"
            );
        }
        // A block download response with ss = 3.
        assert_eq!(
            SdoResponse::parse(&[0xA3, 0, 0, 0, 0, 0, 0, 0]),
            Err(Error::Unknown {
                field: "SDO block download server subcommand",
                value: 3
            })
        );
        assert!(matches!(
            BlockSegment::parse(&[0x80, 0, 0, 0, 0, 0, 0, 0]),
            Err(Error::Invalid {
                field: "SDO block segment seqno",
                ..
            })
        ));
        assert!(matches!(
            BlockSegment::parse(&[1; 7]),
            Err(Error::Truncated { .. })
        ));
    }

    #[test]
    fn sub_block_sequence() {
        let seg = |seqno, last| BlockSegment {
            seqno,
            last,
            data: [0; 7],
        };
        let mut sb = SubBlock::new(3).unwrap();
        assert_eq!(sb.accept(&seg(1, false)), Ok(false));
        // Segment 3 before 2: invalid sequence (abort 05040003h); ackseq stays 1.
        assert_eq!(
            sb.accept(&seg(3, false)),
            Err(Error::SdoBlockSequence {
                expected: 2,
                got: 3
            })
        );
        assert_eq!(sb.ackseq(), 1);
        assert_eq!(sb.accept(&seg(2, false)), Ok(false));
        assert_eq!(sb.accept(&seg(3, false)), Ok(true));
        // The sub-block is full: a fourth segment is out of sequence.
        assert!(sb.accept(&seg(4, false)).is_err());
        assert!(SubBlock::new(0).is_err());
        assert!(SubBlock::new(128).is_err());
    }

    mod properties {
        use super::*;
        use crate::canopen::{SdoRequest, SdoResponse};
        use proptest::prelude::*;

        fn request() -> impl Strategy<Value = BlockRequest> {
            prop_oneof![
                (
                    any::<u16>(),
                    any::<u8>(),
                    any::<bool>(),
                    proptest::option::of(any::<u32>())
                )
                    .prop_map(|(index, sub, crc, size)| {
                        BlockRequest::InitiateDownload {
                            index,
                            sub,
                            crc,
                            size,
                        }
                    }),
                (0u8..=6, any::<u16>())
                    .prop_map(|(unused, crc)| BlockRequest::EndDownload { unused, crc }),
                (
                    any::<u16>(),
                    any::<u8>(),
                    any::<bool>(),
                    1..=MAX_BLOCK_SIZE,
                    any::<u8>()
                )
                    .prop_map(|(index, sub, crc, blksize, pst)| {
                        BlockRequest::InitiateUpload {
                            index,
                            sub,
                            crc,
                            blksize,
                            pst,
                        }
                    }),
                Just(BlockRequest::EndUpload),
                (0..=MAX_BLOCK_SIZE, 1..=MAX_BLOCK_SIZE)
                    .prop_map(|(ackseq, blksize)| BlockRequest::UploadAck { ackseq, blksize }),
                Just(BlockRequest::StartUpload),
            ]
        }

        fn response() -> impl Strategy<Value = BlockResponse> {
            prop_oneof![
                (any::<u16>(), any::<u8>(), any::<bool>(), 1..=MAX_BLOCK_SIZE).prop_map(
                    |(index, sub, crc, blksize)| BlockResponse::InitiateDownload {
                        index,
                        sub,
                        crc,
                        blksize
                    }
                ),
                Just(BlockResponse::EndDownload),
                (0..=MAX_BLOCK_SIZE, 1..=MAX_BLOCK_SIZE)
                    .prop_map(|(ackseq, blksize)| BlockResponse::DownloadAck { ackseq, blksize }),
                (
                    any::<u16>(),
                    any::<u8>(),
                    any::<bool>(),
                    proptest::option::of(any::<u32>())
                )
                    .prop_map(|(index, sub, crc, size)| {
                        BlockResponse::InitiateUpload {
                            index,
                            sub,
                            crc,
                            size,
                        }
                    }),
                (0u8..=6, any::<u16>())
                    .prop_map(|(unused, crc)| BlockResponse::EndUpload { unused, crc }),
            ]
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn request_round_trips(r in request()) {
                prop_assert_eq!(SdoRequest::parse(&r.emit()), Ok(SdoRequest::Block(r)));
            }

            #[test]
            fn response_round_trips(r in response()) {
                prop_assert_eq!(SdoResponse::parse(&r.emit()), Ok(SdoResponse::Block(r)));
            }

            #[test]
            fn segment_round_trips(seqno in 1..=MAX_BLOCK_SIZE, last in any::<bool>(), data in any::<[u8; SEGMENT_DATA]>()) {
                let s = BlockSegment { seqno, last, data };
                prop_assert_eq!(BlockSegment::parse(&s.emit()), Ok(s));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..10)) {
                let _ = BlockSegment::parse(&bytes);
            }
        }
    }
}
