//! SDO messages on CAN (CiA 301 "SDO protocol"): the client's requests on 600h + node, the
//! server's responses on 580h + node, 8 bytes each ([`super::command`] for the command byte).
//!
//! | frame | bytes |
//! |---|---|
//! | initiate download / initiate upload response | cmd; index (u16); sub-index; d: 1..4 expedited bytes, or the size (u32) of a segmented transfer |
//! | initiate upload / initiate download response | cmd; index; sub-index; 4 reserved |
//! | download segment / upload segment response | cmd (t, n, c); 7 bytes of segment data, 7 − n of them data |
//! | upload segment / download segment response | cmd (t); 7 reserved |
//! | abort | 80h; index; sub-index; abort code (u32) |
//!
//! Block transfers are [`SdoRequest::Block`] / [`SdoResponse::Block`] ([`super::block`]);
//! the segments of a sub-block carry no command byte and are parsed as
//! [`super::BlockSegment`] by whoever knows a sub-block is under way.

use std::fmt;

use super::block::{BlockRequest, BlockResponse};
use super::command::{
    expedited_bits, expedited_len, head, segment_bits, segment_unused, tg, ClientCommand, SdoFrame,
    ServerCommand, ABORT, EXPEDITED, FRAME_LEN, LAST, SEGMENT_DATA, SIZE, TOGGLE,
};
use super::SdoAbortCode;
use crate::wire::Error;

/// Expedited data: 1..4 bytes with the size indicated (s = 1), or 4 bytes without (s = 0).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Expedited {
    len: u8,
    sized: bool,
    bytes: [u8; 4],
}

impl Expedited {
    /// 1..4 bytes, size indicated.
    pub fn new(data: &[u8]) -> Result<Expedited, Error> {
        if data.is_empty() || data.len() > 4 {
            return Err(Error::Invalid {
                field: "expedited SDO data",
                value: data.len() as u32,
                why: "an expedited transfer carries 1 to 4 bytes",
            });
        }
        let mut bytes = [0; 4];
        bytes[..data.len()].copy_from_slice(data);
        Ok(Expedited {
            len: data.len() as u8,
            sized: true,
            bytes,
        })
    }

    /// 4 bytes, size not indicated (s = 0).
    pub fn without_size(bytes: [u8; 4]) -> Expedited {
        Expedited {
            len: 4,
            sized: false,
            bytes,
        }
    }

    /// The data bytes.
    pub fn data(&self) -> &[u8] {
        &self.bytes[..usize::from(self.len)]
    }

    /// Whether the size is indicated (s bit).
    pub fn is_sized(&self) -> bool {
        self.sized
    }
}

impl fmt::Debug for Expedited {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let s = if self.sized { "" } else { "unsized " };
        write!(f, "Expedited({s}{:02X?})", self.data())
    }
}

/// What an initiate download request or initiate upload response announces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum InitiateData {
    /// e = 1: the data, in this frame.
    Expedited(Expedited),
    /// e = 0: segments follow; s = 1 gives the data set size in bytes 4–7, s = 0 does not.
    Segmented {
        /// The size, if indicated.
        size: Option<u32>,
    },
}

impl InitiateData {
    fn parse<T: AsRef<[u8]>>(f: &SdoFrame<T>) -> InitiateData {
        let cmd = f.command();
        if cmd & EXPEDITED != 0 {
            let mut bytes = f.data();
            let len = expedited_len(cmd);
            bytes[len..].fill(0);
            InitiateData::Expedited(Expedited {
                len: len as u8,
                sized: cmd & SIZE != 0,
                bytes,
            })
        } else {
            InitiateData::Segmented {
                size: (cmd & SIZE != 0).then(|| f.data_u32()),
            }
        }
    }

    /// The frame of `command` (the specifier bits), `index`, `sub` with this data.
    fn emit(&self, command: u8, index: u16, sub: u8) -> [u8; FRAME_LEN] {
        let (bits, d) = match self {
            InitiateData::Expedited(e) if e.sized => (expedited_bits(e.data().len()), e.bytes),
            InitiateData::Expedited(e) => (EXPEDITED, e.bytes),
            InitiateData::Segmented { size: Some(s) } => (SIZE, s.to_le_bytes()),
            InitiateData::Segmented { size: None } => (0, [0; 4]),
        };
        let mut b = head(command | bits, index, sub);
        b[4..].copy_from_slice(&d);
        b
    }
}

/// The data of a segment: 0..7 bytes.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SegmentData {
    len: u8,
    bytes: [u8; SEGMENT_DATA],
}

impl SegmentData {
    /// 0..7 bytes.
    pub fn new(data: &[u8]) -> Result<SegmentData, Error> {
        if data.len() > SEGMENT_DATA {
            return Err(Error::TooLong {
                what: "SDO segment data",
                len: data.len(),
                max: SEGMENT_DATA,
            });
        }
        let mut bytes = [0; SEGMENT_DATA];
        bytes[..data.len()].copy_from_slice(data);
        Ok(SegmentData {
            len: data.len() as u8,
            bytes,
        })
    }

    /// The data bytes.
    pub fn data(&self) -> &[u8] {
        &self.bytes[..usize::from(self.len)]
    }

    fn parse<T: AsRef<[u8]>>(f: &SdoFrame<T>) -> SegmentData {
        let len = SEGMENT_DATA - segment_unused(f.command());
        let mut bytes = [0; SEGMENT_DATA];
        bytes[..len].copy_from_slice(&f.segment()[..len]);
        SegmentData {
            len: len as u8,
            bytes,
        }
    }

    fn emit(&self, command: u8, toggle: bool, last: bool) -> [u8; FRAME_LEN] {
        let mut b = [0; FRAME_LEN];
        b[0] = command | segment_bits(toggle, self.data().len(), last);
        b[1..].copy_from_slice(&self.bytes);
        b
    }
}

impl fmt::Debug for SegmentData {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SegmentData({:02X?})", self.data())
    }
}

/// An SDO transfer aborted by either side, for the object `index`:`sub`, with `code`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct Abort {
    /// Object index.
    pub index: u16,
    /// Sub-index.
    pub sub: u8,
    /// Why.
    pub code: SdoAbortCode,
}

impl Abort {
    fn parse<T: AsRef<[u8]>>(f: &SdoFrame<T>) -> Abort {
        Abort {
            index: f.index(),
            sub: f.sub(),
            code: SdoAbortCode(f.data_u32()),
        }
    }

    fn emit(&self) -> [u8; FRAME_LEN] {
        let mut b = head(ABORT, self.index, self.sub);
        b[4..].copy_from_slice(&self.code.0.to_le_bytes());
        b
    }
}

/// A frame from the SDO client (on 600h + node).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SdoRequest {
    /// Initiate SDO download (ccs 1): write `index`:`sub`.
    InitiateDownload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Expedited data, or the announcement of segments.
        data: InitiateData,
    },
    /// Download SDO segment (ccs 0).
    DownloadSegment {
        /// t.
        toggle: bool,
        /// c: no more segments.
        last: bool,
        /// The segment's data.
        data: SegmentData,
    },
    /// Initiate SDO upload (ccs 2): read `index`:`sub`.
    InitiateUpload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
    },
    /// Upload SDO segment (ccs 3): ask for the next segment.
    UploadSegment {
        /// t.
        toggle: bool,
    },
    /// Abort SDO transfer (cs 4).
    Abort(Abort),
    /// An SDO block download or upload command (ccs 5, 6).
    Block(BlockRequest),
}

impl SdoRequest {
    /// Parses an SDO frame from the client: 8 bytes. A command specifier of 7, or a block
    /// command with an unknown subcommand, is [`Error::Unknown`].
    pub fn parse(bytes: &[u8]) -> Result<SdoRequest, Error> {
        let f = SdoFrame::new_checked(bytes)?;
        let cmd = f.command();
        let (index, sub) = (f.index(), f.sub());
        Ok(match ClientCommand::of(cmd) {
            ClientCommand::INITIATE_DOWNLOAD => SdoRequest::InitiateDownload {
                index,
                sub,
                data: InitiateData::parse(&f),
            },
            ClientCommand::DOWNLOAD_SEGMENT => SdoRequest::DownloadSegment {
                toggle: cmd & TOGGLE != 0,
                last: cmd & LAST != 0,
                data: SegmentData::parse(&f),
            },
            ClientCommand::INITIATE_UPLOAD => SdoRequest::InitiateUpload { index, sub },
            ClientCommand::UPLOAD_SEGMENT => SdoRequest::UploadSegment {
                toggle: cmd & TOGGLE != 0,
            },
            ClientCommand::ABORT => SdoRequest::Abort(Abort::parse(&f)),
            ClientCommand::BLOCK_UPLOAD | ClientCommand::BLOCK_DOWNLOAD => {
                SdoRequest::Block(BlockRequest::parse(&f)?)
            }
            ccs => {
                return Err(Error::Unknown {
                    field: "SDO client command specifier",
                    value: u32::from(ccs.0),
                })
            }
        })
    }

    /// The 8 bytes of the frame.
    pub fn emit(&self) -> [u8; FRAME_LEN] {
        match self {
            SdoRequest::InitiateDownload { index, sub, data } => {
                data.emit(ClientCommand::INITIATE_DOWNLOAD.bits(), *index, *sub)
            }
            SdoRequest::DownloadSegment { toggle, last, data } => {
                data.emit(ClientCommand::DOWNLOAD_SEGMENT.bits(), *toggle, *last)
            }
            SdoRequest::InitiateUpload { index, sub } => {
                head(ClientCommand::INITIATE_UPLOAD.bits(), *index, *sub)
            }
            SdoRequest::UploadSegment { toggle } => {
                head(ClientCommand::UPLOAD_SEGMENT.bits() | tg(*toggle), 0, 0)
            }
            SdoRequest::Abort(a) => a.emit(),
            SdoRequest::Block(b) => b.emit(),
        }
    }
}

/// A frame from the SDO server (on 580h + node).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum SdoResponse {
    /// Initiate SDO download response (scs 3).
    InitiateDownload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
    },
    /// Download SDO segment response (scs 1).
    DownloadSegment {
        /// t of the segment confirmed.
        toggle: bool,
    },
    /// Initiate SDO upload response (scs 2).
    InitiateUpload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Expedited data, or the announcement of segments.
        data: InitiateData,
    },
    /// Upload SDO segment response (scs 0).
    UploadSegment {
        /// t of the request answered.
        toggle: bool,
        /// c: no more segments.
        last: bool,
        /// The segment's data.
        data: SegmentData,
    },
    /// Abort SDO transfer (cs 4): the server's refusal.
    Abort(Abort),
    /// An SDO block download or upload command (scs 5, 6).
    Block(BlockResponse),
}

impl SdoResponse {
    /// Parses an SDO frame from the server: 8 bytes. A command specifier of 7, or a block
    /// command with an unknown subcommand, is [`Error::Unknown`].
    pub fn parse(bytes: &[u8]) -> Result<SdoResponse, Error> {
        let f = SdoFrame::new_checked(bytes)?;
        let cmd = f.command();
        let (index, sub) = (f.index(), f.sub());
        Ok(match ServerCommand::of(cmd) {
            ServerCommand::INITIATE_DOWNLOAD => SdoResponse::InitiateDownload { index, sub },
            ServerCommand::DOWNLOAD_SEGMENT => SdoResponse::DownloadSegment {
                toggle: cmd & TOGGLE != 0,
            },
            ServerCommand::INITIATE_UPLOAD => SdoResponse::InitiateUpload {
                index,
                sub,
                data: InitiateData::parse(&f),
            },
            ServerCommand::UPLOAD_SEGMENT => SdoResponse::UploadSegment {
                toggle: cmd & TOGGLE != 0,
                last: cmd & LAST != 0,
                data: SegmentData::parse(&f),
            },
            ServerCommand::ABORT => SdoResponse::Abort(Abort::parse(&f)),
            ServerCommand::BLOCK_DOWNLOAD | ServerCommand::BLOCK_UPLOAD => {
                SdoResponse::Block(BlockResponse::parse(&f)?)
            }
            scs => {
                return Err(Error::Unknown {
                    field: "SDO server command specifier",
                    value: u32::from(scs.0),
                })
            }
        })
    }

    /// The 8 bytes of the frame.
    pub fn emit(&self) -> [u8; FRAME_LEN] {
        match self {
            SdoResponse::InitiateDownload { index, sub } => {
                head(ServerCommand::INITIATE_DOWNLOAD.bits(), *index, *sub)
            }
            SdoResponse::DownloadSegment { toggle } => {
                head(ServerCommand::DOWNLOAD_SEGMENT.bits() | tg(*toggle), 0, 0)
            }
            SdoResponse::InitiateUpload { index, sub, data } => {
                data.emit(ServerCommand::INITIATE_UPLOAD.bits(), *index, *sub)
            }
            SdoResponse::UploadSegment { toggle, last, data } => {
                data.emit(ServerCommand::UPLOAD_SEGMENT.bits(), *toggle, *last)
            }
            SdoResponse::Abort(a) => a.emit(),
            SdoResponse::Block(b) => b.emit(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn req(r: SdoRequest, bytes: [u8; 8]) {
        assert_eq!(r.emit(), bytes, "{r:?}");
        assert_eq!(SdoRequest::parse(&bytes), Ok(r));
    }

    fn resp(r: SdoResponse, bytes: [u8; 8]) {
        assert_eq!(r.emit(), bytes, "{r:?}");
        assert_eq!(SdoResponse::parse(&bytes), Ok(r));
    }

    #[test]
    fn expedited_download_and_upload() {
        // 2Bh: ccs 1, n = 2, e = 1, s = 1: 2 bytes; 6040h:00 = 000Fh (controlword).
        let data = InitiateData::Expedited(Expedited::new(&[0x0F, 0x00]).unwrap());
        req(
            SdoRequest::InitiateDownload {
                index: 0x6040,
                sub: 0,
                data,
            },
            [0x2B, 0x40, 0x60, 0x00, 0x0F, 0x00, 0x00, 0x00],
        );
        // 60h: scs 3, the download confirmed.
        resp(
            SdoResponse::InitiateDownload {
                index: 0x6040,
                sub: 0,
            },
            [0x60, 0x40, 0x60, 0x00, 0, 0, 0, 0],
        );
        // 40h: ccs 2, read 1000h:00.
        req(
            SdoRequest::InitiateUpload {
                index: 0x1000,
                sub: 0,
            },
            [0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0],
        );
        // 43h: scs 2, e = 1, s = 1, n = 0: 4 bytes, device type 00020192h.
        resp(
            SdoResponse::InitiateUpload {
                index: 0x1000,
                sub: 0,
                data: InitiateData::Expedited(Expedited::new(&[0x92, 0x01, 0x02, 0x00]).unwrap()),
            },
            [0x43, 0x00, 0x10, 0x00, 0x92, 0x01, 0x02, 0x00],
        );
        // 4Fh: 1 byte, the padding after it not part of the data.
        let r = SdoResponse::parse(&[0x4F, 0x01, 0x10, 0x00, 0x05, 0xAA, 0xBB, 0xCC]).unwrap();
        let SdoResponse::InitiateUpload {
            data: InitiateData::Expedited(e),
            ..
        } = r
        else {
            panic!("{r:?}")
        };
        assert_eq!((e.data(), e.is_sized()), (&[0x05][..], true));
        // 42h: e = 1, s = 0: 4 bytes, size not indicated.
        resp(
            SdoResponse::InitiateUpload {
                index: 0x1001,
                sub: 0,
                data: InitiateData::Expedited(Expedited::without_size([1, 2, 3, 4])),
            },
            [0x42, 0x01, 0x10, 0x00, 1, 2, 3, 4],
        );
        assert!(Expedited::new(&[]).is_err());
        assert!(Expedited::new(&[0; 5]).is_err());
    }

    #[test]
    fn segmented_transfers() {
        // 21h: ccs 1, e = 0, s = 1: 10 bytes follow in segments.
        req(
            SdoRequest::InitiateDownload {
                index: 0x1008,
                sub: 0,
                data: InitiateData::Segmented { size: Some(10) },
            },
            [0x21, 0x08, 0x10, 0x00, 10, 0, 0, 0],
        );
        // 20h: e = 0, s = 0: size not indicated, d reserved.
        req(
            SdoRequest::InitiateDownload {
                index: 0x1008,
                sub: 0,
                data: InitiateData::Segmented { size: None },
            },
            [0x20, 0x08, 0x10, 0x00, 0, 0, 0, 0],
        );
        // 00h: t = 0, n = 0, c = 0: 7 bytes.
        req(
            SdoRequest::DownloadSegment {
                toggle: false,
                last: false,
                data: SegmentData::new(b"SK 500E").unwrap(),
            },
            [0x00, b'S', b'K', b' ', b'5', b'0', b'0', b'E'],
        );
        // 17h: t = 1, n = 3, c = 1: 4 bytes, the last.
        req(
            SdoRequest::DownloadSegment {
                toggle: true,
                last: true,
                data: SegmentData::new(&[1, 2, 3, 4]).unwrap(),
            },
            [0x17, 1, 2, 3, 4, 0, 0, 0],
        );
        // 20h / 30h: download segment responses t = 0 / 1.
        resp(
            SdoResponse::DownloadSegment { toggle: false },
            [0x20, 0, 0, 0, 0, 0, 0, 0],
        );
        resp(
            SdoResponse::DownloadSegment { toggle: true },
            [0x30, 0, 0, 0, 0, 0, 0, 0],
        );
        // 60h / 70h: upload segment requests t = 0 / 1.
        req(
            SdoRequest::UploadSegment { toggle: false },
            [0x60, 0, 0, 0, 0, 0, 0, 0],
        );
        req(
            SdoRequest::UploadSegment { toggle: true },
            [0x70, 0, 0, 0, 0, 0, 0, 0],
        );
        // 41h: upload response, segmented, 12 bytes; 0Bh: t = 0, n = 5, c = 1: 2 bytes.
        resp(
            SdoResponse::InitiateUpload {
                index: 0x1008,
                sub: 0,
                data: InitiateData::Segmented { size: Some(12) },
            },
            [0x41, 0x08, 0x10, 0x00, 12, 0, 0, 0],
        );
        resp(
            SdoResponse::UploadSegment {
                toggle: false,
                last: true,
                data: SegmentData::new(&[0xAB, 0xCD]).unwrap(),
            },
            [0x0B, 0xAB, 0xCD, 0, 0, 0, 0, 0],
        );
        // 0Fh: n = 7, a segment without data.
        assert_eq!(
            SdoResponse::parse(&[0x0F, 9, 9, 9, 9, 9, 9, 9]),
            Ok(SdoResponse::UploadSegment {
                toggle: false,
                last: true,
                data: SegmentData::default()
            })
        );
        assert!(SegmentData::new(&[0; 8]).is_err());
    }

    #[test]
    fn aborts_either_way() {
        // 80h; 2000h:01; 06090011h (sub-index does not exist).
        let a = Abort {
            index: 0x2000,
            sub: 1,
            code: SdoAbortCode::NO_SUBINDEX,
        };
        let b = [0x80, 0x00, 0x20, 0x01, 0x11, 0x00, 0x09, 0x06];
        req(SdoRequest::Abort(a), b);
        resp(SdoResponse::Abort(a), b);
        // Bits 0–4 are "not used": ignored.
        let mut x = b;
        x[0] = 0x9F;
        assert_eq!(SdoResponse::parse(&x), Ok(SdoResponse::Abort(a)));
    }

    #[test]
    fn unknown_specifiers_and_lengths() {
        // ccs/scs 7 is undefined.
        assert_eq!(
            SdoRequest::parse(&[0xE0, 0, 0, 0, 0, 0, 0, 0]),
            Err(Error::Unknown {
                field: "SDO client command specifier",
                value: 7
            })
        );
        assert_eq!(
            SdoResponse::parse(&[0xE0, 0, 0, 0, 0, 0, 0, 0]),
            Err(Error::Unknown {
                field: "SDO server command specifier",
                value: 7
            })
        );
        // Every length but 8, from a valid frame.
        let b = SdoRequest::InitiateUpload {
            index: 0x1018,
            sub: 1,
        }
        .emit();
        for n in 0..8 {
            assert_eq!(
                SdoRequest::parse(&b[..n]),
                Err(Error::Truncated {
                    what: "SDO frame",
                    need: 8,
                    got: n
                })
            );
            assert!(matches!(
                SdoResponse::parse(&b[..n]),
                Err(Error::Truncated { got, .. }) if got == n
            ));
        }
        let mut long = b.to_vec();
        long.push(0);
        assert_eq!(
            SdoRequest::parse(&long),
            Err(Error::Trailing {
                what: "SDO frame",
                extra: 1
            })
        );
    }

    #[test]
    fn a_transfer_checks_its_toggle_bits() {
        // The server's view of a segmented download of 10 bytes: segments t = 0, 1, then a
        // repeated t = 1 is a toggle error (abort 05030000h).
        let mut t = super::super::Toggle::new();
        let segs = [
            SdoRequest::DownloadSegment {
                toggle: false,
                last: false,
                data: SegmentData::new(&[0; 7]).unwrap(),
            },
            SdoRequest::DownloadSegment {
                toggle: true,
                last: false,
                data: SegmentData::new(&[0; 3]).unwrap(),
            },
        ];
        for s in segs {
            let SdoRequest::DownloadSegment { toggle, .. } = SdoRequest::parse(&s.emit()).unwrap()
            else {
                panic!()
            };
            t.check(toggle).unwrap();
        }
        let mut bad = SdoFrame::new_checked(segs[1].emit()).unwrap();
        bad.set_command(bad.command() | 0x01);
        let Ok(SdoRequest::DownloadSegment { toggle, .. }) = SdoRequest::parse(&bad.into_inner())
        else {
            panic!()
        };
        assert_eq!(
            t.check(toggle),
            Err(Error::SdoToggle {
                expected: false,
                got: true
            })
        );
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn expedited() -> impl Strategy<Value = Expedited> {
            prop_oneof![
                vec(any::<u8>(), 1..=4).prop_map(|d| Expedited::new(&d).unwrap()),
                any::<[u8; 4]>().prop_map(Expedited::without_size),
            ]
        }

        fn initiate_data() -> impl Strategy<Value = InitiateData> {
            prop_oneof![
                expedited().prop_map(InitiateData::Expedited),
                proptest::option::of(any::<u32>())
                    .prop_map(|size| InitiateData::Segmented { size }),
            ]
        }

        fn segment_data() -> impl Strategy<Value = SegmentData> {
            vec(any::<u8>(), 0..=SEGMENT_DATA).prop_map(|d| SegmentData::new(&d).unwrap())
        }

        fn abort() -> impl Strategy<Value = Abort> {
            (any::<u16>(), any::<u8>(), any::<u32>()).prop_map(|(index, sub, code)| Abort {
                index,
                sub,
                code: SdoAbortCode(code),
            })
        }

        /// Every request but block transfers (those are `block`'s).
        fn request() -> impl Strategy<Value = SdoRequest> {
            prop_oneof![
                (any::<u16>(), any::<u8>(), initiate_data()).prop_map(|(index, sub, data)| {
                    SdoRequest::InitiateDownload { index, sub, data }
                }),
                (any::<bool>(), any::<bool>(), segment_data()).prop_map(|(toggle, last, data)| {
                    SdoRequest::DownloadSegment { toggle, last, data }
                }),
                (any::<u16>(), any::<u8>())
                    .prop_map(|(index, sub)| SdoRequest::InitiateUpload { index, sub }),
                any::<bool>().prop_map(|toggle| SdoRequest::UploadSegment { toggle }),
                abort().prop_map(SdoRequest::Abort),
            ]
        }

        /// Every response but block transfers.
        fn response() -> impl Strategy<Value = SdoResponse> {
            prop_oneof![
                (any::<u16>(), any::<u8>())
                    .prop_map(|(index, sub)| SdoResponse::InitiateDownload { index, sub }),
                any::<bool>().prop_map(|toggle| SdoResponse::DownloadSegment { toggle }),
                (any::<u16>(), any::<u8>(), initiate_data()).prop_map(|(index, sub, data)| {
                    SdoResponse::InitiateUpload { index, sub, data }
                }),
                (any::<bool>(), any::<bool>(), segment_data()).prop_map(|(toggle, last, data)| {
                    SdoResponse::UploadSegment { toggle, last, data }
                }),
                abort().prop_map(SdoResponse::Abort),
            ]
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn request_round_trips(r in request()) {
                let bytes = r.emit();
                prop_assert_eq!(bytes.len(), FRAME_LEN);
                prop_assert_eq!(SdoRequest::parse(&bytes), Ok(r));
            }

            #[test]
            fn response_round_trips(r in response()) {
                let bytes = r.emit();
                prop_assert_eq!(bytes.len(), FRAME_LEN);
                prop_assert_eq!(SdoResponse::parse(&bytes), Ok(r));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..12)) {
                let _ = SdoRequest::parse(&bytes);
                let _ = SdoResponse::parse(&bytes);
            }
        }
    }
}
