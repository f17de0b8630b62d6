//! CANopen over EtherCAT: the CoE header, the SDO protocol it carries, SDO abort codes, the
//! emergency message and the SDO information header (ETG.1000.6 "CANopen over EtherCAT";
//! CiA 301 "SDO protocol" for the command specifiers and "SDO abort codes";
//! BU 0620 §2.2.7 for the SK 550P's objects and §2.2.7.2 for the abort codes it prints).
//! What is CiA 301's — the command byte ([`crate::canopen::command`]), [`SdoAbortCode`] and
//! [`Emergency`] — is defined in [`crate::canopen`] and re-exported here; the abort codes
//! ETG.1000.6 adds and the BU 0620 errata stay in this module.
//!
//! | CoE header (u16) | |
//! |---|---|
//! | bits 0–8 | number (PDO number; 0 for SDO) |
//! | bits 9–11 | reserved |
//! | bits 12–15 | service ([`CoeService`]) |
//!
//! The 8-byte SDO header after it: command byte, index (u16), sub-index (u8), 4 data bytes.
//! The command byte's top 3 bits are the client command specifier (ccs, in requests) or the
//! server command specifier (scs, in responses); the CoE service (2 request, 3 response) says
//! which. An SDO abort travels with service 2 in both directions (ETG.1000.6 "Abort SDO transfer").
//!
//! | transfer | how |
//! |---|---|
//! | expedited | e = 1: 1..4 bytes in the header; s = 1: n (bits 2–3) = 4 − size |
//! | normal | e = 0, s = 1: the 4 header bytes hold the complete size, the data follow the 8-byte header — CoE may carry more than 4 bytes in one mailbox (ETG.1000.6 "SDO download normal" / "SDO upload normal") |
//! | segmented | after a normal transfer whose data did not fit: command byte with toggle (bit 4), n (bits 1–3: unused of 7 bytes when a segment is shorter than 7), c (bit 0: last segment), then the data; a segment longer than 7 bytes has n = 0 and the mailbox length gives its size |
//! | complete access | bit 4 of the initiate command: the whole object from sub-index 0 or 1 |
//!
//! Fixed-size messages (initiate upload, upload segment request, responses without data,
//! abort, emergency) must be at least their size; bytes after them are ignored, as CoE slaves
//! and masters do with mailbox padding.

use std::fmt;

use super::mailbox::{MailboxRepr, MailboxType};
use super::wire::{fit, le16, le32};
use crate::canopen::command::{
    expedited_bits, expedited_len, segment_bits, segment_unused, tg, ClientCommand, ServerCommand,
    ABORT, EXPEDITED, LAST, SIZE, TOGGLE,
};
use crate::wire::{Error, Reader};

/// CoE header length.
pub const COE_HEADER_LEN: usize = 2;
/// SDO header length (command, index, sub-index, 4 data bytes).
pub const SDO_HEADER_LEN: usize = 8;
/// Data bytes of a segment of minimal size (CiA 301: 7).
pub const SEGMENT_MIN_DATA: usize = 7;

/// A CoE service (ETG.1000.6 "CoE header"; open).
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
pub struct CoeService(pub u8);

impl CoeService {
    /// Emergency.
    pub const EMERGENCY: CoeService = CoeService(1);
    /// SDO request.
    pub const SDO_REQUEST: CoeService = CoeService(2);
    /// SDO response.
    pub const SDO_RESPONSE: CoeService = CoeService(3);
    /// TxPDO.
    pub const TXPDO: CoeService = CoeService(4);
    /// RxPDO.
    pub const RXPDO: CoeService = CoeService(5);
    /// TxPDO remote request.
    pub const TXPDO_REMOTE_REQUEST: CoeService = CoeService(6);
    /// RxPDO remote request.
    pub const RXPDO_REMOTE_REQUEST: CoeService = CoeService(7);
    /// SDO information.
    pub const SDO_INFO: CoeService = CoeService(8);

    /// The service's name, if defined.
    pub fn name(self) -> Option<&'static str> {
        Some(match self.0 {
            1 => "Emergency",
            2 => "SDO request",
            3 => "SDO response",
            4 => "TxPDO",
            5 => "RxPDO",
            6 => "TxPDO remote request",
            7 => "RxPDO remote request",
            8 => "SDO information",
            _ => return None,
        })
    }
}

impl fmt::Display for CoeService {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => f.write_str(n),
            None => write!(f, "CoE service {}", self.0),
        }
    }
}

impl fmt::Debug for CoeService {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.name() {
            Some(n) => write!(f, "CoeService({} {n})", self.0),
            None => write!(f, "CoeService({})", self.0),
        }
    }
}

/// The CoE header.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct CoeHeader {
    /// Number (9 bits).
    pub number: u16,
    /// Reserved bits 9–11.
    pub reserved: u8,
    /// Service (4 bits).
    pub service: CoeService,
}

impl CoeHeader {
    /// A header of `service`, number 0.
    pub fn new(service: CoeService) -> Self {
        CoeHeader {
            service,
            ..CoeHeader::default()
        }
    }

    /// From the header word.
    pub fn from_word(w: u16) -> Self {
        CoeHeader {
            number: w & 0x01FF,
            reserved: ((w >> 9) & 0x7) as u8,
            service: CoeService((w >> 12) as u8),
        }
    }

    /// The header word.
    pub fn to_word(self) -> u16 {
        self.number & 0x01FF
            | u16::from(self.reserved & 0x7) << 9
            | u16::from(self.service.0 & 0xF) << 12
    }

    /// Splits mailbox data into the CoE header and what follows it.
    pub fn split(data: &[u8]) -> Result<(CoeHeader, &[u8]), Error> {
        let mut r = Reader::new(data);
        let h = CoeHeader::from_word(r.u16("CoE header")?);
        Ok((h, r.rest()))
    }

    /// The 2 header bytes.
    pub fn emit(self) -> [u8; 2] {
        self.to_word().to_le_bytes()
    }
}

pub use crate::canopen::SdoAbortCode;

crate::canopen::abort_codes! {
    /// The codes ETG.1000.6 "SDO abort codes" adds to CiA 301's
    /// ([`SdoAbortCode::CIA_301`]) for CoE, with their meanings: sub-index 0 and complete
    /// access, the mailbox size, objects mapped to an RxPDO.
    ETG_1000_6 {
        SUBINDEX_0_NOT_ZERO = 0x0601_0003, "Sub-index cannot be written, sub-index 0 must be 0 for write access";
        COMPLETE_ACCESS_VARIABLE = 0x0601_0004, "SDO complete access not supported for objects of variable length";
        OBJECT_TOO_LONG = 0x0601_0005, "Object length exceeds mailbox size";
        MAPPED_TO_RXPDO = 0x0601_0006, "Object mapped to RxPDO, SDO download blocked";
    }
}

/// Where BU 0620 §2.2.7.2 (p. 21) prints a code CiA 301 does not define for the meaning it
/// gives: (printed, standard). The device answers the standard's code; suites record the
/// printed one as the manual's erratum.
pub const BU0620_ABORT_ERRATA: &[(SdoAbortCode, SdoAbortCode)] = &[
    // "Writing access to read-only object": CiA 301 "attempt to write a read only object".
    (SdoAbortCode(0x0602_0002), SdoAbortCode::READ_ONLY),
    // "Internal incompatibility in the bus interface": CiA 301 "general internal
    // incompatibility in the device".
    (
        SdoAbortCode(0x0606_0047),
        SdoAbortCode::INTERNAL_INCOMPATIBLE,
    ),
];

/// One row of BU 0620 §2.2.7.2 (p. 21): the code printed, the code the standard defines for
/// that meaning (equal unless the row is an erratum), the manual's text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ManualAbort {
    /// As printed.
    pub printed: SdoAbortCode,
    /// As CiA 301 defines it (what the device sends).
    pub standard: SdoAbortCode,
    /// The manual's description.
    pub text: &'static str,
}

impl ManualAbort {
    /// Whether the manual prints a code other than the standard's.
    pub fn is_erratum(&self) -> bool {
        self.printed != self.standard
    }
}

/// The standard code for a code printed in BU 0620 §2.2.7.2 (the code itself where the row is
/// right).
pub fn bu0620_standard_code(printed: SdoAbortCode) -> SdoAbortCode {
    BU0620_ABORT_ERRATA
        .iter()
        .find(|(p, _)| *p == printed)
        .map_or(printed, |(_, s)| *s)
}

/// The rows of BU 0620 §2.2.7.2 ([`crate::nord::errors::ETHERCAT_ABORTS`]) with the standard
/// code beside each.
pub fn bu0620_aborts() -> impl Iterator<Item = ManualAbort> {
    crate::nord::errors::ETHERCAT_ABORTS
        .iter()
        .map(|&(code, text)| ManualAbort {
            printed: SdoAbortCode(code),
            standard: bu0620_standard_code(SdoAbortCode(code)),
            text,
        })
}

/// The data of an initiate download request or an initiate upload response.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum SdoData {
    /// e = 1: the data in the SDO header. `sized` = s bit: with s = 1 the data are 1..4 bytes
    /// (n = 4 − length); with s = 0 the size is not indicated and all 4 bytes are carried.
    Expedited {
        /// s bit.
        sized: bool,
        /// 1..4 bytes (4 when `sized` is false).
        data: Vec<u8>,
    },
    /// e = 0, s = 1: the complete size, then the first (or all) data bytes; the rest, if any,
    /// follows in segments.
    Normal {
        /// Complete size of the object's data.
        size: u32,
        /// The data carried in this message.
        data: Vec<u8>,
    },
}

impl SdoData {
    /// Expedited if `data` has 1..4 bytes, else normal with `size` = its length.
    pub fn auto(data: Vec<u8>) -> SdoData {
        if (1..=4).contains(&data.len()) {
            SdoData::Expedited { sized: true, data }
        } else {
            SdoData::Normal {
                size: data.len() as u32,
                data,
            }
        }
    }

    /// The data bytes carried.
    pub fn data(&self) -> &[u8] {
        match self {
            SdoData::Expedited { data, .. } | SdoData::Normal { data, .. } => data,
        }
    }

    /// Reads the e/s/n bits of `cmd` and the bytes from offset 4 of an SDO header `b` (at
    /// least 8 bytes). `lenient`: as a tolerant server reads a download (see
    /// [`SdoRequest::parse_lenient`]).
    fn parse(cmd: u8, b: &[u8], lenient: bool) -> Result<SdoData, Error> {
        let expedited = cmd & EXPEDITED != 0;
        let sized = cmd & SIZE != 0;
        if expedited {
            let len = expedited_len(cmd);
            Ok(SdoData::Expedited {
                sized,
                data: b[4..4 + len].to_vec(),
            })
        } else if !sized && lenient {
            let data = &b[SDO_HEADER_LEN..];
            Ok(SdoData::Normal {
                size: data.len() as u32,
                data: data.to_vec(),
            })
        } else if !sized {
            Err(Error::Invalid {
                field: "SDO command",
                value: u32::from(cmd),
                why: "e = 0 and s = 0 is reserved (a normal transfer indicates its size)",
            })
        } else {
            let size = le32(b, 4);
            let mut data = &b[SDO_HEADER_LEN..];
            if lenient && data.len() as u64 > u64::from(size) {
                data = &data[..size as usize];
            }
            if data.len() as u64 > u64::from(size) {
                return Err(Error::Length {
                    field: "SDO complete size",
                    value: size as usize,
                    available: data.len(),
                });
            }
            Ok(SdoData::Normal {
                size,
                data: data.to_vec(),
            })
        }
    }

    /// The e/s/n bits and the bytes from offset 4 on.
    fn emit(&self) -> Result<(u8, Vec<u8>), Error> {
        match self {
            SdoData::Expedited { sized: true, data } => {
                if data.is_empty() || data.len() > 4 {
                    return Err(Error::Invalid {
                        field: "expedited SDO data",
                        value: data.len() as u32,
                        why: "an expedited transfer carries 1 to 4 bytes",
                    });
                }
                let mut d = data.clone();
                d.resize(4, 0);
                Ok((expedited_bits(data.len()), d))
            }
            SdoData::Expedited { sized: false, data } => {
                if data.len() != 4 {
                    return Err(Error::Invalid {
                        field: "expedited SDO data",
                        value: data.len() as u32,
                        why: "without size indication an expedited transfer carries 4 bytes",
                    });
                }
                Ok((EXPEDITED, data.clone()))
            }
            SdoData::Normal { size, data } => {
                if data.len() as u64 > u64::from(*size) {
                    return Err(Error::TooLong {
                        what: "normal SDO data",
                        len: data.len(),
                        max: *size as usize,
                    });
                }
                let mut d = size.to_le_bytes().to_vec();
                d.extend_from_slice(data);
                Ok((SIZE, d))
            }
        }
    }
}

/// Reads a segment's data: a minimal segment (7 data bytes) has n unused ones, a longer one
/// must have n = 0.
fn segment_data(cmd: u8, b: &[u8], lenient: bool) -> Result<Vec<u8>, Error> {
    let n = segment_unused(cmd);
    let carried = &b[1..];
    if carried.len() == SEGMENT_MIN_DATA {
        Ok(carried[..SEGMENT_MIN_DATA - n].to_vec())
    } else if n == 0 || lenient {
        Ok(carried.to_vec())
    } else {
        Err(Error::Invalid {
            field: "SDO segment n",
            value: n as u32,
            why: "a segment longer than 7 bytes must have n = 0",
        })
    }
}

/// The data of a segment, padded to 7 bytes (its command byte: [`segment_bits`]).
fn emit_segment(data: &[u8]) -> Vec<u8> {
    let mut d = data.to_vec();
    if d.len() < SEGMENT_MIN_DATA {
        d.resize(SEGMENT_MIN_DATA, 0);
    }
    d
}

fn check_sdo_len(b: &[u8]) -> Result<(), Error> {
    Reader::new(b)
        .bytes(SDO_HEADER_LEN, "SDO header")
        .map(|_| ())
}

fn head(out: &mut Vec<u8>, cmd: u8, index: u16, sub: u8) {
    out.push(cmd);
    out.extend_from_slice(&index.to_le_bytes());
    out.push(sub);
}

/// Complete access bit of initiate commands.
const CA: u8 = 0x10;

/// An SDO request: client → server, CoE service 2 (CiA 301 "SDO protocol").
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum SdoRequest {
    /// Initiate download (ccs 1).
    Download {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Complete access.
        complete_access: bool,
        /// Expedited or normal data.
        data: SdoData,
    },
    /// Download segment (ccs 0).
    DownloadSegment {
        /// Toggle bit.
        toggle: bool,
        /// c bit: no more segments.
        last: bool,
        /// Segment data.
        data: Vec<u8>,
    },
    /// Initiate upload (ccs 2).
    Upload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Complete access.
        complete_access: bool,
    },
    /// Upload segment (ccs 3).
    UploadSegment {
        /// Toggle bit.
        toggle: bool,
    },
    /// Abort transfer (cs 4).
    Abort {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Abort code.
        code: SdoAbortCode,
    },
}

impl SdoRequest {
    /// Parses the bytes after the CoE header.
    pub fn parse(b: &[u8]) -> Result<SdoRequest, Error> {
        SdoRequest::parse_with(b, false)
    }

    /// Parses the bytes after the CoE header as a tolerant SDO server does (the simulated
    /// slave): an initiate download with e = 0 and s = 0 (reserved) is a normal download of
    /// the bytes carried; normal data beyond the indicated size are ignored; a segment longer
    /// than 7 bytes is taken whole whatever its n bits say. An unknown command specifier, or
    /// fewer than 8 bytes, is still an error.
    pub fn parse_lenient(b: &[u8]) -> Result<SdoRequest, Error> {
        SdoRequest::parse_with(b, true)
    }

    fn parse_with(b: &[u8], lenient: bool) -> Result<SdoRequest, Error> {
        check_sdo_len(b)?;
        let cmd = b[0];
        let (index, sub) = (le16(b, 1), b[3]);
        Ok(match ClientCommand::of(cmd) {
            ClientCommand::INITIATE_DOWNLOAD => SdoRequest::Download {
                index,
                sub,
                complete_access: cmd & CA != 0,
                data: SdoData::parse(cmd, b, lenient)?,
            },
            ClientCommand::DOWNLOAD_SEGMENT => SdoRequest::DownloadSegment {
                toggle: cmd & TOGGLE != 0,
                last: cmd & LAST != 0,
                data: segment_data(cmd, b, lenient)?,
            },
            ClientCommand::INITIATE_UPLOAD => SdoRequest::Upload {
                index,
                sub,
                complete_access: cmd & CA != 0,
            },
            ClientCommand::UPLOAD_SEGMENT => SdoRequest::UploadSegment {
                toggle: cmd & TOGGLE != 0,
            },
            ClientCommand::ABORT => SdoRequest::Abort {
                index,
                sub,
                code: SdoAbortCode(le32(b, 4)),
            },
            ccs => {
                return Err(Error::Unknown {
                    field: "SDO client command specifier",
                    value: u32::from(ccs.0),
                })
            }
        })
    }

    /// Parses mailbox data: CoE header (service 2) and the request.
    pub fn parse_coe(data: &[u8]) -> Result<SdoRequest, Error> {
        let (h, rest) = CoeHeader::split(data)?;
        if h.service != CoeService::SDO_REQUEST {
            return Err(Error::Unknown {
                field: "CoE service (SDO request expected)",
                value: u32::from(h.service.0),
            });
        }
        SdoRequest::parse(rest)
    }

    /// The bytes after the CoE header.
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut out = Vec::with_capacity(SDO_HEADER_LEN);
        match self {
            SdoRequest::Download {
                index,
                sub,
                complete_access,
                data,
            } => {
                let (bits, d) = data.emit()?;
                let cs = ClientCommand::INITIATE_DOWNLOAD.bits();
                head(&mut out, cs | bits | ca(*complete_access), *index, *sub);
                out.extend(d);
            }
            SdoRequest::DownloadSegment { toggle, last, data } => {
                let cs = ClientCommand::DOWNLOAD_SEGMENT.bits();
                out.push(cs | segment_bits(*toggle, data.len(), *last));
                out.extend(emit_segment(data));
            }
            SdoRequest::Upload {
                index,
                sub,
                complete_access,
            } => {
                let cs = ClientCommand::INITIATE_UPLOAD.bits();
                head(&mut out, cs | ca(*complete_access), *index, *sub);
                out.extend([0; 4]);
            }
            SdoRequest::UploadSegment { toggle } => {
                out.push(ClientCommand::UPLOAD_SEGMENT.bits() | tg(*toggle));
                out.extend([0; 7]);
            }
            SdoRequest::Abort { index, sub, code } => {
                head(&mut out, ABORT, *index, *sub);
                out.extend(code.0.to_le_bytes());
            }
        }
        Ok(out)
    }

    /// Mailbox data: CoE header (service 2) and the request.
    pub fn emit_coe(&self) -> Result<Vec<u8>, Error> {
        let mut out = CoeHeader::new(CoeService::SDO_REQUEST).emit().to_vec();
        out.extend(self.emit()?);
        Ok(out)
    }

    /// The whole mailbox message (type CoE, `counter`).
    pub fn to_mailbox(&self, counter: u8) -> Result<MailboxRepr, Error> {
        Ok(MailboxRepr::new(
            MailboxType::COE,
            counter,
            self.emit_coe()?,
        ))
    }
}

fn ca(on: bool) -> u8 {
    if on {
        CA
    } else {
        0
    }
}

/// An SDO response: server → client, CoE service 3 (an abort with service 2).
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum SdoResponse {
    /// Initiate download response (scs 3).
    Download {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Complete access bit echoed.
        complete_access: bool,
    },
    /// Download segment response (scs 1).
    DownloadSegment {
        /// Toggle bit of the acknowledged segment.
        toggle: bool,
    },
    /// Initiate upload response (scs 2).
    Upload {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Complete access bit echoed.
        complete_access: bool,
        /// Expedited or normal data.
        data: SdoData,
    },
    /// Upload segment response (scs 0).
    UploadSegment {
        /// Toggle bit.
        toggle: bool,
        /// c bit: last segment.
        last: bool,
        /// Segment data.
        data: Vec<u8>,
    },
    /// Abort transfer (cs 4).
    Abort {
        /// Object index.
        index: u16,
        /// Sub-index.
        sub: u8,
        /// Abort code.
        code: SdoAbortCode,
    },
}

impl SdoResponse {
    /// Parses the bytes after the CoE header.
    pub fn parse(b: &[u8]) -> Result<SdoResponse, Error> {
        check_sdo_len(b)?;
        let cmd = b[0];
        let (index, sub) = (le16(b, 1), b[3]);
        Ok(match ServerCommand::of(cmd) {
            ServerCommand::INITIATE_DOWNLOAD => SdoResponse::Download {
                index,
                sub,
                complete_access: cmd & CA != 0,
            },
            ServerCommand::DOWNLOAD_SEGMENT => SdoResponse::DownloadSegment {
                toggle: cmd & TOGGLE != 0,
            },
            ServerCommand::INITIATE_UPLOAD => SdoResponse::Upload {
                index,
                sub,
                complete_access: cmd & CA != 0,
                data: SdoData::parse(cmd, b, false)?,
            },
            ServerCommand::UPLOAD_SEGMENT => SdoResponse::UploadSegment {
                toggle: cmd & TOGGLE != 0,
                last: cmd & LAST != 0,
                data: segment_data(cmd, b, false)?,
            },
            ServerCommand::ABORT => SdoResponse::Abort {
                index,
                sub,
                code: SdoAbortCode(le32(b, 4)),
            },
            scs => {
                return Err(Error::Unknown {
                    field: "SDO server command specifier",
                    value: u32::from(scs.0),
                })
            }
        })
    }

    /// Parses mailbox data: a CoE header of service 3 and the response, or of service 2 with
    /// an abort (how slaves send aborts, ETG.1000.6 "Abort SDO transfer").
    pub fn parse_coe(data: &[u8]) -> Result<SdoResponse, Error> {
        let (h, rest) = CoeHeader::split(data)?;
        match h.service {
            CoeService::SDO_RESPONSE => SdoResponse::parse(rest),
            CoeService::SDO_REQUEST if rest.first() == Some(&ABORT) => SdoResponse::parse(rest),
            // An abort whose bits 0–4 are set: CiA 301 §7.2.4.3.17 has them "not used, always
            // 0"; named as such, not as a service that does not exist.
            CoeService::SDO_REQUEST if rest.first().is_some_and(|c| c & 0xE0 == ABORT) => {
                Err(Error::Unknown {
                    field: "SDO abort command byte, bits 0–4 set (CiA 301 §7.2.4.3.17: always 0)",
                    value: u32::from(rest[0]),
                })
            }
            s => Err(Error::Unknown {
                field: "CoE service (SDO response expected)",
                value: u32::from(s.0),
            }),
        }
    }

    /// The bytes after the CoE header.
    pub fn emit(&self) -> Result<Vec<u8>, Error> {
        let mut out = Vec::with_capacity(SDO_HEADER_LEN);
        match self {
            SdoResponse::Download {
                index,
                sub,
                complete_access,
            } => {
                let cs = ServerCommand::INITIATE_DOWNLOAD.bits();
                head(&mut out, cs | ca(*complete_access), *index, *sub);
                out.extend([0; 4]);
            }
            SdoResponse::DownloadSegment { toggle } => {
                out.push(ServerCommand::DOWNLOAD_SEGMENT.bits() | tg(*toggle));
                out.extend([0; 7]);
            }
            SdoResponse::Upload {
                index,
                sub,
                complete_access,
                data,
            } => {
                let (bits, d) = data.emit()?;
                let cs = ServerCommand::INITIATE_UPLOAD.bits();
                head(&mut out, cs | bits | ca(*complete_access), *index, *sub);
                out.extend(d);
            }
            SdoResponse::UploadSegment { toggle, last, data } => {
                let cs = ServerCommand::UPLOAD_SEGMENT.bits();
                out.push(cs | segment_bits(*toggle, data.len(), *last));
                out.extend(emit_segment(data));
            }
            SdoResponse::Abort { index, sub, code } => {
                head(&mut out, ABORT, *index, *sub);
                out.extend(code.0.to_le_bytes());
            }
        }
        Ok(out)
    }

    /// The CoE service this response travels with: 3, or 2 for an abort.
    pub fn service(&self) -> CoeService {
        match self {
            SdoResponse::Abort { .. } => CoeService::SDO_REQUEST,
            _ => CoeService::SDO_RESPONSE,
        }
    }

    /// Mailbox data: CoE header and the response.
    pub fn emit_coe(&self) -> Result<Vec<u8>, Error> {
        let mut out = CoeHeader::new(self.service()).emit().to_vec();
        out.extend(self.emit()?);
        Ok(out)
    }

    /// The whole mailbox message (type CoE, `counter`).
    pub fn to_mailbox(&self, counter: u8) -> Result<MailboxRepr, Error> {
        Ok(MailboxRepr::new(
            MailboxType::COE,
            counter,
            self.emit_coe()?,
        ))
    }
}

/// The emergency message (CiA 301 "Emergency object"), which CoE carries after a header of
/// service 1 (ETG.1000.6 "Emergency").
pub use crate::canopen::Emergency;

impl Emergency {
    /// Parses mailbox data: CoE header (service 1) and the emergency (at least 8 bytes; bytes
    /// after them are mailbox padding).
    pub fn parse_coe(data: &[u8]) -> Result<Emergency, Error> {
        let (h, rest) = CoeHeader::split(data)?;
        if h.service != CoeService::EMERGENCY {
            return Err(Error::Unknown {
                field: "CoE service (emergency expected)",
                value: u32::from(h.service.0),
            });
        }
        emergency(rest)
    }

    /// Mailbox data: CoE header (service 1) and the emergency.
    pub fn emit_coe(&self) -> Vec<u8> {
        let mut out = CoeHeader::new(CoeService::EMERGENCY).emit().to_vec();
        out.extend(self.emit());
        out
    }
}

/// The emergency in the bytes after the CoE header.
fn emergency(rest: &[u8]) -> Result<Emergency, Error> {
    let b = Reader::new(rest).bytes(Emergency::LEN, "emergency")?;
    let mut bytes = [0; Emergency::LEN];
    bytes.copy_from_slice(b);
    Ok(Emergency::from_bytes(bytes))
}

/// An SDO information opcode (ETG.1000.6 "SDO information"; open).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Default)]
pub struct SdoInfoOpcode(pub u8);

impl SdoInfoOpcode {
    /// Get OD list request.
    pub const GET_OD_LIST_REQ: SdoInfoOpcode = SdoInfoOpcode(1);
    /// Get OD list response.
    pub const GET_OD_LIST_RESP: SdoInfoOpcode = SdoInfoOpcode(2);
    /// Get object description request.
    pub const GET_OBJECT_DESC_REQ: SdoInfoOpcode = SdoInfoOpcode(3);
    /// Get object description response.
    pub const GET_OBJECT_DESC_RESP: SdoInfoOpcode = SdoInfoOpcode(4);
    /// Get entry description request.
    pub const GET_ENTRY_DESC_REQ: SdoInfoOpcode = SdoInfoOpcode(5);
    /// Get entry description response.
    pub const GET_ENTRY_DESC_RESP: SdoInfoOpcode = SdoInfoOpcode(6);
    /// SDO information error request (carries an abort code).
    pub const ERROR: SdoInfoOpcode = SdoInfoOpcode(7);
}

impl fmt::Debug for SdoInfoOpcode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SdoInfoOpcode({})", self.0)
    }
}

/// An SDO information message (CoE service 8; ETG.1000.6 "SDO information"): opcode (bits 0–6)
/// with the incomplete bit (7), a reserved byte, the fragments left (u16), then the
/// opcode's data (not interpreted here; for [`SdoInfoOpcode::ERROR`] see
/// [`SdoInfo::abort_code`]).
#[derive(Debug, Clone, PartialEq, Eq, Hash, Default)]
pub struct SdoInfo {
    /// Opcode.
    pub opcode: SdoInfoOpcode,
    /// More fragments follow.
    pub incomplete: bool,
    /// Fragments left.
    pub fragments_left: u16,
    /// The data after the 4-byte header.
    pub data: Vec<u8>,
}

impl SdoInfo {
    /// Parses the bytes after the CoE header.
    pub fn parse(b: &[u8]) -> Result<SdoInfo, Error> {
        let mut r = Reader::new(b);
        let op = r.u8("SDO information opcode")?;
        r.u8("SDO information reserved")?;
        let fragments_left = r.u16("SDO information fragments left")?;
        Ok(SdoInfo {
            opcode: SdoInfoOpcode(op & 0x7F),
            incomplete: op & 0x80 != 0,
            fragments_left,
            data: r.rest().to_vec(),
        })
    }

    /// The bytes after the CoE header.
    pub fn emit(&self) -> Vec<u8> {
        let mut out = vec![
            self.opcode.0 & 0x7F | if self.incomplete { 0x80 } else { 0 },
            0,
        ];
        out.extend(self.fragments_left.to_le_bytes());
        out.extend(&self.data);
        out
    }

    /// Mailbox data: CoE header (service 8) and the message.
    pub fn emit_coe(&self) -> Vec<u8> {
        let mut out = CoeHeader::new(CoeService::SDO_INFO).emit().to_vec();
        out.extend(self.emit());
        out
    }

    /// An SDO information error carrying `code`.
    pub fn error(code: SdoAbortCode) -> SdoInfo {
        SdoInfo {
            opcode: SdoInfoOpcode::ERROR,
            data: code.0.to_le_bytes().to_vec(),
            ..SdoInfo::default()
        }
    }

    /// The abort code of an error message.
    pub fn abort_code(&self) -> Result<SdoAbortCode, Error> {
        if self.opcode != SdoInfoOpcode::ERROR {
            return Err(Error::Unknown {
                field: "SDO information opcode (error expected)",
                value: u32::from(self.opcode.0),
            });
        }
        let mut r = Reader::new(&self.data);
        Ok(SdoAbortCode(r.u32("SDO information abort code")?))
    }
}

/// A CoE message as it arrives in a mailbox, sorted by service.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum CoeMessage {
    /// Service 1.
    Emergency(Emergency),
    /// Service 2 (an abort from a slave is parsed here too).
    SdoRequest(SdoRequest),
    /// Service 3.
    SdoResponse(SdoResponse),
    /// Service 8.
    SdoInfo(SdoInfo),
    /// Any other service (PDOs over the mailbox, undefined services), kept as bytes.
    Other {
        /// The header.
        header: CoeHeader,
        /// The bytes after it.
        data: Vec<u8>,
    },
}

impl CoeMessage {
    /// Parses mailbox data of type CoE.
    pub fn parse(data: &[u8]) -> Result<CoeMessage, Error> {
        let (h, rest) = CoeHeader::split(data)?;
        Ok(match h.service {
            CoeService::EMERGENCY => CoeMessage::Emergency(emergency(rest)?),
            CoeService::SDO_REQUEST => CoeMessage::SdoRequest(SdoRequest::parse(rest)?),
            CoeService::SDO_RESPONSE => CoeMessage::SdoResponse(SdoResponse::parse(rest)?),
            CoeService::SDO_INFO => CoeMessage::SdoInfo(SdoInfo::parse(rest)?),
            _ => CoeMessage::Other {
                header: h,
                data: rest.to_vec(),
            },
        })
    }
}

/// The largest data a normal transfer can carry in one mailbox of `mailbox_len` bytes
/// (SyncManager length): minus the mailbox header (6), the CoE header (2), the SDO header (8).
pub fn normal_capacity(mailbox_len: usize) -> usize {
    mailbox_len.saturating_sub(super::mailbox::HEADER_LEN + COE_HEADER_LEN + SDO_HEADER_LEN)
}

/// The largest segment data in one mailbox of `mailbox_len` bytes: minus the mailbox header,
/// the CoE header and the command byte.
pub fn segment_capacity(mailbox_len: usize) -> usize {
    mailbox_len.saturating_sub(super::mailbox::HEADER_LEN + COE_HEADER_LEN + 1)
}

/// Checks that an SDO message fits a mailbox of `mailbox_len` bytes.
pub fn check_fits(coe_data_len: usize, mailbox_len: usize) -> Result<(), Error> {
    fit(
        "CoE message",
        coe_data_len,
        mailbox_len.saturating_sub(super::mailbox::HEADER_LEN),
    )
    .map(|_| ())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip_req(r: &SdoRequest, bytes: &[u8]) {
        assert_eq!(r.emit().unwrap(), bytes, "{r:?}");
        assert_eq!(&SdoRequest::parse(bytes).unwrap(), r);
        let coe = r.emit_coe().unwrap();
        assert_eq!(&coe[..2], [0x00, 0x20]);
        assert_eq!(&SdoRequest::parse_coe(&coe).unwrap(), r);
        assert_eq!(
            CoeMessage::parse(&coe).unwrap(),
            CoeMessage::SdoRequest(r.clone())
        );
    }

    fn round_trip_resp(r: &SdoResponse, bytes: &[u8]) {
        assert_eq!(r.emit().unwrap(), bytes, "{r:?}");
        assert_eq!(&SdoResponse::parse(bytes).unwrap(), r);
        let coe = r.emit_coe().unwrap();
        assert_eq!(&SdoResponse::parse_coe(&coe).unwrap(), r);
    }

    #[test]
    fn coe_header() {
        // 0x3000: service 3 (SDO response), number 0.
        let (h, rest) = CoeHeader::split(&[0x00, 0x30, 0xAA]).unwrap();
        assert_eq!(h, CoeHeader::new(CoeService::SDO_RESPONSE));
        assert_eq!(rest, [0xAA]);
        let h = CoeHeader::from_word(0x51FF);
        assert_eq!(
            (h.number, h.reserved, h.service),
            (0x1FF, 0, CoeService::RXPDO)
        );
        assert_eq!(h.to_word(), 0x51FF);
        assert_eq!(CoeHeader::from_word(0x0E00).reserved, 7);
        assert!(matches!(
            CoeHeader::split(&[0]),
            Err(Error::Truncated { .. })
        ));
        assert_eq!(CoeService(3).to_string(), "SDO response");
        assert_eq!(CoeService(12).to_string(), "CoE service 12");
    }

    #[test]
    fn expedited_download_of_p102_fi3() {
        // BU 0620 §2.2.7: P102 of FI 3 is object 3066h, sub-index 1 (array element 1); 1000.
        let r = SdoRequest::Download {
            index: 0x3066,
            sub: 1,
            complete_access: false,
            data: SdoData::auto(vec![0xE8, 0x03]),
        };
        round_trip_req(
            &r,
            &[
                0x2B, // ccs 1, n = 2, e = 1, s = 1
                0x66, 0x30, // index 3066h
                0x01, // sub-index 1
                0xE8, 0x03, 0x00, 0x00, // 1000, 2 bytes used
            ],
        );
        let resp = SdoResponse::Download {
            index: 0x3066,
            sub: 1,
            complete_access: false,
        };
        round_trip_resp(&resp, &[0x60, 0x66, 0x30, 0x01, 0, 0, 0, 0]);
    }

    #[test]
    fn expedited_sizes_and_unsized() {
        for (len, cmd) in [(1, 0x2F), (2, 0x2B), (3, 0x27), (4, 0x23)] {
            let r = SdoRequest::Download {
                index: 0x1000,
                sub: 0,
                complete_access: false,
                data: SdoData::auto(vec![0x11; len]),
            };
            let b = r.emit().unwrap();
            assert_eq!((b[0], b.len()), (cmd, 8));
            assert_eq!(SdoRequest::parse(&b).unwrap(), r);
        }
        // e = 1, s = 0: size not indicated, all 4 bytes.
        let b = [0x22, 0x00, 0x10, 0x00, 1, 2, 3, 4];
        let r = SdoRequest::parse(&b).unwrap();
        assert_eq!(
            r,
            SdoRequest::Download {
                index: 0x1000,
                sub: 0,
                complete_access: false,
                data: SdoData::Expedited {
                    sized: false,
                    data: vec![1, 2, 3, 4]
                }
            }
        );
        assert_eq!(r.emit().unwrap(), b);
        // Emitting impossible expedited data is an error, not a panic.
        for bad in [
            SdoData::Expedited {
                sized: true,
                data: vec![],
            },
            SdoData::Expedited {
                sized: true,
                data: vec![0; 5],
            },
            SdoData::Expedited {
                sized: false,
                data: vec![0; 3],
            },
        ] {
            let r = SdoRequest::Download {
                index: 0,
                sub: 0,
                complete_access: false,
                data: bad,
            };
            assert!(matches!(r.emit(), Err(Error::Invalid { .. })));
        }
    }

    #[test]
    fn upload_expedited_and_normal() {
        round_trip_req(
            &SdoRequest::Upload {
                index: 0x1018,
                sub: 1,
                complete_access: false,
            },
            &[0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0],
        );
        // 1018h:01 vendor id 538h, 4 bytes expedited.
        round_trip_resp(
            &SdoResponse::Upload {
                index: 0x1018,
                sub: 1,
                complete_access: false,
                data: SdoData::auto(vec![0x38, 0x05, 0, 0]),
            },
            &[0x43, 0x18, 0x10, 0x01, 0x38, 0x05, 0x00, 0x00],
        );
        // Normal: 1008h device name "SK 550P" (7 bytes) in one mailbox.
        round_trip_resp(
            &SdoResponse::Upload {
                index: 0x1008,
                sub: 0,
                complete_access: false,
                data: SdoData::auto(b"SK 550P".to_vec()),
            },
            &[
                0x41, // scs 2, e = 0, s = 1
                0x08, 0x10, 0x00, // 1008h:00
                0x07, 0x00, 0x00, 0x00, // complete size 7
                b'S', b'K', b' ', b'5', b'5', b'0', b'P',
            ],
        );
        // Complete access on 1C12h with 2 sub-indices' worth of data (normal, 5 bytes).
        round_trip_req(
            &SdoRequest::Upload {
                index: 0x1C12,
                sub: 0,
                complete_access: true,
            },
            &[0x50, 0x12, 0x1C, 0x00, 0, 0, 0, 0],
        );
        // A first chunk shorter than the complete size (segments follow).
        let r = SdoResponse::Upload {
            index: 0x2000,
            sub: 0,
            complete_access: false,
            data: SdoData::Normal {
                size: 300,
                data: vec![7; 100],
            },
        };
        assert_eq!(SdoResponse::parse(&r.emit().unwrap()).unwrap(), r);
    }

    #[test]
    fn normal_transfer_lies_are_errors() {
        // Complete size 2 but 3 data bytes.
        let b = [0x21, 0x00, 0x20, 0x00, 0x02, 0, 0, 0, 1, 2, 3];
        assert_eq!(
            SdoRequest::parse(&b),
            Err(Error::Length {
                field: "SDO complete size",
                value: 2,
                available: 3
            })
        );
        // e = 0, s = 0 is reserved.
        let b = [0x20, 0x00, 0x20, 0x00, 0, 0, 0, 0];
        assert!(matches!(
            SdoRequest::parse(&b),
            Err(Error::Invalid {
                field: "SDO command",
                ..
            })
        ));
        let r = SdoRequest::Download {
            index: 0,
            sub: 0,
            complete_access: false,
            data: SdoData::Normal {
                size: 1,
                data: vec![1, 2],
            },
        };
        assert!(matches!(r.emit(), Err(Error::TooLong { .. })));
    }

    #[test]
    fn segments() {
        // Download segment, toggle 1, 3 bytes, last: n = 4.
        round_trip_req(
            &SdoRequest::DownloadSegment {
                toggle: true,
                last: true,
                data: vec![1, 2, 3],
            },
            &[0x19, 1, 2, 3, 0, 0, 0, 0],
        );
        // A 10-byte segment: n = 0, no padding.
        round_trip_req(
            &SdoRequest::DownloadSegment {
                toggle: false,
                last: false,
                data: (0..10).collect(),
            },
            &[0x00, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9],
        );
        round_trip_resp(
            &SdoResponse::DownloadSegment { toggle: true },
            &[0x30, 0, 0, 0, 0, 0, 0, 0],
        );
        round_trip_req(
            &SdoRequest::UploadSegment { toggle: true },
            &[0x70, 0, 0, 0, 0, 0, 0, 0],
        );
        // Upload segment response, toggle 0, 7 bytes exactly, last.
        round_trip_resp(
            &SdoResponse::UploadSegment {
                toggle: false,
                last: true,
                data: vec![9; 7],
            },
            &[0x01, 9, 9, 9, 9, 9, 9, 9],
        );
        // n ≠ 0 in a segment longer than 7 bytes.
        assert!(matches!(
            SdoResponse::parse(&[0x02, 0, 0, 0, 0, 0, 0, 0, 0]),
            Err(Error::Invalid {
                field: "SDO segment n",
                ..
            })
        ));
    }

    #[test]
    fn aborts_travel_as_requests() {
        let a = SdoResponse::Abort {
            index: 0x3066,
            sub: 9,
            code: SdoAbortCode::NO_SUBINDEX,
        };
        let coe = a.emit_coe().unwrap();
        assert_eq!(
            coe,
            [
                0x00, 0x20, // CoE: service 2
                0x80, // abort
                0x66, 0x30, 0x09, // 3066h:09
                0x11, 0x00, 0x09, 0x06, // 06090011h
            ]
        );
        assert_eq!(SdoResponse::parse_coe(&coe).unwrap(), a);
        assert_eq!(
            SdoRequest::parse_coe(&coe).unwrap(),
            SdoRequest::Abort {
                index: 0x3066,
                sub: 9,
                code: SdoAbortCode::NO_SUBINDEX
            }
        );
        // A request that is not an abort is not a response.
        let up = SdoRequest::Upload {
            index: 1,
            sub: 0,
            complete_access: false,
        }
        .emit_coe()
        .unwrap();
        assert!(matches!(
            SdoResponse::parse_coe(&up),
            Err(Error::Unknown { .. })
        ));
        assert!(matches!(
            SdoRequest::parse_coe(&[0, 0x30, 0x80]),
            Err(Error::Unknown { .. })
        ));
    }

    #[test]
    fn truncation_at_every_length_is_an_error() {
        let msgs: Vec<Vec<u8>> = vec![
            SdoRequest::Upload {
                index: 0x1000,
                sub: 0,
                complete_access: false,
            }
            .emit()
            .unwrap(),
            SdoRequest::Download {
                index: 0x1000,
                sub: 0,
                complete_access: false,
                data: SdoData::auto(vec![1, 2]),
            }
            .emit()
            .unwrap(),
            SdoResponse::UploadSegment {
                toggle: true,
                last: false,
                data: vec![1; 3],
            }
            .emit()
            .unwrap(),
        ];
        for m in &msgs {
            for n in 0..SDO_HEADER_LEN {
                assert_eq!(
                    SdoRequest::parse(&m[..n]),
                    Err(Error::Truncated {
                        what: "SDO header",
                        need: 8,
                        got: n
                    })
                );
                assert!(SdoResponse::parse(&m[..n]).is_err());
            }
        }
        // A normal transfer cut inside its data is still well-formed: the size says more
        // follows (in segments), so only the header length matters.
        let normal = SdoResponse::Upload {
            index: 0x1008,
            sub: 0,
            complete_access: false,
            data: SdoData::auto(vec![1; 9]),
        }
        .emit()
        .unwrap();
        for n in 8..normal.len() {
            assert!(SdoResponse::parse(&normal[..n]).is_ok());
        }
    }

    #[test]
    fn unknown_command_specifiers() {
        for cs in [5u8, 6, 7] {
            let b = [cs << 5, 0, 0, 0, 0, 0, 0, 0];
            assert_eq!(
                SdoRequest::parse(&b),
                Err(Error::Unknown {
                    field: "SDO client command specifier",
                    value: u32::from(cs)
                })
            );
            assert_eq!(
                SdoResponse::parse(&b),
                Err(Error::Unknown {
                    field: "SDO server command specifier",
                    value: u32::from(cs)
                })
            );
        }
    }

    #[test]
    fn emergency() {
        // Emergency 1000h (generic error), register 81h, manufacturer bytes 0A 00 00 00 00.
        let e = Emergency {
            code: 0x1000,
            register: 0x81,
            data: [0x0A, 0, 0, 0, 0],
        };
        let coe = e.emit_coe();
        assert_eq!(coe, [0x00, 0x10, 0x00, 0x10, 0x81, 0x0A, 0, 0, 0, 0]);
        assert_eq!(Emergency::parse_coe(&coe).unwrap(), e);
        assert_eq!(CoeMessage::parse(&coe).unwrap(), CoeMessage::Emergency(e));
        for n in 2..coe.len() {
            assert!(matches!(
                Emergency::parse_coe(&coe[..n]),
                Err(Error::Truncated { .. })
            ));
        }
        assert!(matches!(
            Emergency::parse_coe(&[0, 0x20, 0, 0, 0, 0, 0, 0, 0, 0]),
            Err(Error::Unknown { .. })
        ));
    }

    #[test]
    fn sdo_info() {
        let e = SdoInfo::error(SdoAbortCode::NO_OBJECT);
        let coe = e.emit_coe();
        assert_eq!(
            coe,
            [0x00, 0x80, 0x07, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x06]
        );
        match CoeMessage::parse(&coe).unwrap() {
            CoeMessage::SdoInfo(i) => {
                assert_eq!(i, e);
                assert_eq!(i.abort_code().unwrap(), SdoAbortCode::NO_OBJECT);
            }
            other => panic!("{other:?}"),
        }
        let list = SdoInfo {
            opcode: SdoInfoOpcode::GET_OD_LIST_RESP,
            incomplete: true,
            fragments_left: 2,
            data: vec![1, 0],
        };
        assert_eq!(list.emit(), [0x82, 0, 2, 0, 1, 0]);
        assert_eq!(SdoInfo::parse(&list.emit()).unwrap(), list);
        assert!(list.abort_code().is_err());
        for n in 0..4 {
            assert!(SdoInfo::parse(&list.emit()[..n]).is_err());
        }
        // Other services are kept as bytes.
        assert_eq!(
            CoeMessage::parse(&[0x01, 0x50, 9]).unwrap(),
            CoeMessage::Other {
                header: CoeHeader {
                    number: 1,
                    reserved: 0,
                    service: CoeService::RXPDO
                },
                data: vec![9]
            }
        );
    }

    #[test]
    fn abort_codes_and_the_manual() {
        assert_eq!(
            SdoAbortCode::READ_ONLY.to_string(),
            "06010002h (Attempt to write a read only object)"
        );
        assert_eq!(SdoAbortCode(0x0602_0002).to_string(), "06020002h");
        assert_eq!(
            format!("{:?}", SdoAbortCode::GENERAL),
            "SdoAbortCode(08000000h)"
        );
        // The four codes ETG.1000.6 adds are named, and CiA 301 defines none of them.
        assert_eq!(SdoAbortCode::ETG_1000_6.len(), 4);
        for (c, text) in SdoAbortCode::ETG_1000_6 {
            assert_eq!(c.name(), Some(*text));
            assert!(SdoAbortCode::CIA_301.iter().all(|(d, _)| d != c));
        }
        assert_eq!(
            SdoAbortCode::OBJECT_TOO_LONG.to_string(),
            "06010005h (Object length exceeds mailbox size)"
        );
        // Every row of BU 0620 §2.2.7.2 maps onto a code CiA 301 / ETG.1000.6 defines; exactly
        // the two errata print codes that no standard defines.
        let rows: Vec<ManualAbort> = bu0620_aborts().collect();
        assert_eq!(rows.len(), 20);
        for r in &rows {
            assert!(r.standard.name().is_some(), "{r:?}");
            assert_eq!(r.is_erratum(), r.printed.name().is_none(), "{r:?}");
        }
        let errata: Vec<_> = rows.iter().filter(|r| r.is_erratum()).collect();
        assert_eq!(errata.len(), 2);
        assert_eq!(
            bu0620_standard_code(SdoAbortCode(0x0602_0002)),
            SdoAbortCode(0x0601_0002)
        );
        assert_eq!(
            bu0620_standard_code(SdoAbortCode(0x0606_0047)),
            SdoAbortCode(0x0604_0047)
        );
        assert_eq!(
            bu0620_standard_code(SdoAbortCode::TOGGLE_BIT),
            SdoAbortCode::TOGGLE_BIT
        );
    }

    #[test]
    fn capacities() {
        assert_eq!(normal_capacity(128), 112);
        assert_eq!(segment_capacity(128), 119);
        assert_eq!(normal_capacity(10), 0);
        assert!(check_fits(122, 128).is_ok());
        assert!(check_fits(123, 128).is_err());
    }

    #[test]
    fn an_abort_with_reserved_bits_is_named_as_such() {
        // CoE header service 2, then 8Bh: abort (cs 4) with bits 0–4 of a request copied in.
        let mut data = CoeHeader::new(CoeService::SDO_REQUEST).emit().to_vec();
        data.extend([0x8B, 0x18, 0x10, 0x05, 0x11, 0x00, 0x09, 0x06]);
        let e = SdoResponse::parse_coe(&data).unwrap_err().to_string();
        assert!(e.contains("bits 0–4 set") && e.contains("0x8B"), "{e}");
        data[2] = 0x80;
        assert!(matches!(
            SdoResponse::parse_coe(&data),
            Ok(SdoResponse::Abort {
                code: SdoAbortCode(0x0609_0011),
                ..
            })
        ));
    }

    #[test]
    fn lenient_parse_takes_what_a_tolerant_server_takes() {
        // cmd 20h: initiate download, e = 0, s = 0 (reserved); index 2000h, sub 1; bytes 4..8
        // (size field, unused), then 2 data bytes.
        let no_size = [0x20, 0x00, 0x20, 0x01, 0, 0, 0, 0, 0xAA, 0xBB];
        assert!(SdoRequest::parse(&no_size).is_err());
        assert_eq!(
            SdoRequest::parse_lenient(&no_size).unwrap(),
            SdoRequest::Download {
                index: 0x2000,
                sub: 1,
                complete_access: false,
                data: SdoData::Normal {
                    size: 2,
                    data: vec![0xAA, 0xBB]
                }
            }
        );
        // cmd 21h: normal download, size 1, but 2 data bytes: the second is ignored.
        let long = [0x21, 0x00, 0x20, 0x01, 1, 0, 0, 0, 0xAA, 0xBB];
        assert!(SdoRequest::parse(&long).is_err());
        assert_eq!(
            SdoRequest::parse_lenient(&long).unwrap(),
            SdoRequest::Download {
                index: 0x2000,
                sub: 1,
                complete_access: false,
                data: SdoData::Normal {
                    size: 1,
                    data: vec![0xAA]
                }
            }
        );
        // cmd 02h: download segment, n = 1, but 8 data bytes: taken whole.
        let seg = [0x02, 1, 2, 3, 4, 5, 6, 7, 8];
        assert!(SdoRequest::parse(&seg).is_err());
        assert_eq!(
            SdoRequest::parse_lenient(&seg).unwrap(),
            SdoRequest::DownloadSegment {
                toggle: false,
                last: false,
                data: vec![1, 2, 3, 4, 5, 6, 7, 8]
            }
        );
        // ccs 5: still an error; 7 bytes: still truncated.
        assert!(SdoRequest::parse_lenient(&[0xA0, 0, 0x20, 1, 0, 0, 0, 0]).is_err());
        assert!(SdoRequest::parse_lenient(&[0x40, 0, 0x20, 1, 0, 0, 0]).is_err());
    }

    mod properties {
        use super::*;
        use proptest::collection::vec;
        use proptest::prelude::*;

        fn sdo_data() -> impl Strategy<Value = SdoData> {
            prop_oneof![
                vec(any::<u8>(), 1..=4).prop_map(|data| SdoData::Expedited { sized: true, data }),
                vec(any::<u8>(), 4).prop_map(|data| SdoData::Expedited { sized: false, data }),
                // Normal: the complete size is at least the bytes carried.
                (vec(any::<u8>(), 0..=32), any::<u32>()).prop_map(|(data, extra)| {
                    SdoData::Normal {
                        size: (data.len() as u32).saturating_add(extra % 1024),
                        data,
                    }
                }),
            ]
        }

        fn abort_code() -> impl Strategy<Value = SdoAbortCode> {
            any::<u32>().prop_map(SdoAbortCode)
        }

        fn request() -> impl Strategy<Value = SdoRequest> {
            prop_oneof![
                (any::<u16>(), any::<u8>(), any::<bool>(), sdo_data()).prop_map(
                    |(index, sub, complete_access, data)| SdoRequest::Download {
                        index,
                        sub,
                        complete_access,
                        data
                    }
                ),
                (any::<bool>(), any::<bool>(), vec(any::<u8>(), 0..=32)).prop_map(
                    |(toggle, last, data)| SdoRequest::DownloadSegment { toggle, last, data }
                ),
                (any::<u16>(), any::<u8>(), any::<bool>()).prop_map(
                    |(index, sub, complete_access)| SdoRequest::Upload {
                        index,
                        sub,
                        complete_access
                    }
                ),
                any::<bool>().prop_map(|toggle| SdoRequest::UploadSegment { toggle }),
                (any::<u16>(), any::<u8>(), abort_code())
                    .prop_map(|(index, sub, code)| SdoRequest::Abort { index, sub, code }),
            ]
        }

        fn response() -> impl Strategy<Value = SdoResponse> {
            prop_oneof![
                (any::<u16>(), any::<u8>(), any::<bool>()).prop_map(
                    |(index, sub, complete_access)| SdoResponse::Download {
                        index,
                        sub,
                        complete_access
                    }
                ),
                any::<bool>().prop_map(|toggle| SdoResponse::DownloadSegment { toggle }),
                (any::<u16>(), any::<u8>(), any::<bool>(), sdo_data()).prop_map(
                    |(index, sub, complete_access, data)| SdoResponse::Upload {
                        index,
                        sub,
                        complete_access,
                        data
                    }
                ),
                (any::<bool>(), any::<bool>(), vec(any::<u8>(), 0..=32)).prop_map(
                    |(toggle, last, data)| SdoResponse::UploadSegment { toggle, last, data }
                ),
                (any::<u16>(), any::<u8>(), abort_code())
                    .prop_map(|(index, sub, code)| SdoResponse::Abort { index, sub, code }),
            ]
        }

        fn sdo_info() -> impl Strategy<Value = SdoInfo> {
            (
                0u8..=0x7F,
                any::<bool>(),
                any::<u16>(),
                vec(any::<u8>(), 0..=32),
            )
                .prop_map(|(op, incomplete, fragments_left, data)| SdoInfo {
                    opcode: SdoInfoOpcode(op),
                    incomplete,
                    fragments_left,
                    data,
                })
        }

        fn coe_header() -> impl Strategy<Value = CoeHeader> {
            (0u16..=0x01FF, 0u8..=7, 0u8..=0x0F).prop_map(|(number, reserved, service)| CoeHeader {
                number,
                reserved,
                service: CoeService(service),
            })
        }

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(256))]

            #[test]
            fn request_round_trips(r in request()) {
                let b = r.emit().unwrap();
                prop_assert_eq!(SdoRequest::parse(&b), Ok(r.clone()));
                prop_assert_eq!(SdoRequest::parse_lenient(&b), Ok(r.clone()));
                let coe = r.emit_coe().unwrap();
                prop_assert_eq!(SdoRequest::parse_coe(&coe), Ok(r.clone()));
                prop_assert_eq!(CoeMessage::parse(&coe), Ok(CoeMessage::SdoRequest(r)));
            }

            #[test]
            fn response_round_trips(r in response()) {
                let b = r.emit().unwrap();
                prop_assert_eq!(SdoResponse::parse(&b), Ok(r.clone()));
                let coe = r.emit_coe().unwrap();
                prop_assert_eq!(SdoResponse::parse_coe(&coe), Ok(r));
            }

            #[test]
            fn sdo_info_round_trips(i in sdo_info()) {
                prop_assert_eq!(SdoInfo::parse(&i.emit()), Ok(i.clone()));
                prop_assert_eq!(CoeMessage::parse(&i.emit_coe()), Ok(CoeMessage::SdoInfo(i)));
            }

            #[test]
            fn header_round_trips(h in coe_header()) {
                prop_assert_eq!(CoeHeader::from_word(h.to_word()), h);
                let bytes = h.emit();
                let (back, rest) = CoeHeader::split(&bytes).unwrap();
                prop_assert_eq!(back, h);
                prop_assert!(rest.is_empty());
            }

            #[test]
            fn emergency_round_trips(code in any::<u16>(), register in any::<u8>(), data in any::<[u8; 5]>()) {
                let e = Emergency { code, register, data };
                prop_assert_eq!(Emergency::parse_coe(&e.emit_coe()), Ok(e));
                prop_assert_eq!(CoeMessage::parse(&e.emit_coe()), Ok(CoeMessage::Emergency(e)));
            }

            #[test]
            fn parsing_arbitrary_bytes_never_panics(bytes in vec(any::<u8>(), 0..24)) {
                let _ = CoeMessage::parse(&bytes);
                let _ = SdoRequest::parse(&bytes);
                let _ = SdoRequest::parse_lenient(&bytes);
                let _ = SdoRequest::parse_coe(&bytes);
                let _ = SdoResponse::parse(&bytes);
                let _ = SdoResponse::parse_coe(&bytes);
                let _ = SdoInfo::parse(&bytes);
                let _ = Emergency::parse_coe(&bytes);
            }
        }
    }
}
